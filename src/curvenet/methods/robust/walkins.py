"""Stage 8e: a curve that jumps from its junction's node over samples of no curve runs through them.

A chain stops where its junction region starts, and the curve joins the chain's first sample to
the node in a straight line. Where the region is long (a traced neurite's zigzag a few spacings
from its junction, flagged with it by the shell test) that line cuts across samples that belong
to no curve, and the curve misses the true one by the zigzag's width. This stage reads that
pattern from the finished curves (after the skipped stretches and excursions of stages 8c and
8d, which read the jump themselves, and before the fit). At a node that is no free end, a
curve end whose first sample lies beyond the shell test's outer radius from the node (widened
for noise as the test widens it: the chain started outside the shell, so its region holds more
than the junction) runs instead through the samples of no curve from that sample to the one
nearest the node, by the shortest path with steps of at most the link length (in the smaller
spacing of their two ends; each step weighs its length squared, so that the path takes the
samples in turn instead of leaping over every other one), when:

* that path's last sample lies within ``WALKIN.arrive`` spacings of the node (the path
  arrives: samples of another branch beside the chain's end lead nowhere near it), and
* a sample of the path lies over ``WALKIN.off`` spacings off the straight line from the first
  sample to the node (where none does, the line follows the samples as well; on noise-free
  tangent junctions the samples beside it are the other branch's).

The samples searched lie within the first sample's distance to the node, plus a link, of the
node; every end's path is searched in one graph. The curve ends are then taken in order of
node and curve, and a path that shares a sample with one taken before is left (each sample on
one curve). The nodes and the topology are unchanged.
"""

from __future__ import annotations

import itertools

import numpy as np

from ...network import Curve
from ...neighbors import build_tree, query_threads
from .chains import segment_distance
from .curves import end_nodes
from .thresholds import NUMERIC, SHELL, WALKIN
from .unexplained import walk_back

__all__ = ["walk_into_junctions"]


def walk_into_junctions(P: np.ndarray, h: np.ndarray, nodes: np.ndarray, curves: list[Curve],
                        link: float, shell_outer: float, noise: float) -> tuple[list[Curve], int]:
    """The curves, each end that jumps from its node over samples of no curve run through them
    (see the module docstring for the rule).

    Parameters
    ----------
    P : (N, d) ndarray
        The points, in the internal order the curves' ``indices`` refer to.
    h : (N,) ndarray
        Local spacing of each point.
    nodes : (n, d) ndarray
        Node positions.
    curves : list of Curve
        The network's curves, not fitted (``indices``: internal point ids, -1 at computed
        nodes).
    link : float
        Longest step of a path, in spacings (the method's link length).
    shell_outer : float
        The shell test's outer radius, in spacings.
    noise : float
        The noise scale (the shell's widening).

    Returns
    -------
    curves : list of Curve
        New list, in the same order (the inputs' objects where nothing changed).
    walked : int
        The number of curve ends that now run through samples.
    """
    n, m = len(nodes), len(curves)
    if not m or n == 0:
        return curves, 0
    ends, valence = end_nodes(curves, n)
    # the curve ends at nodes that are no free end, with their first sample
    ci = np.repeat(np.arange(m, dtype=np.int64), 2)
    side = np.tile(np.array([0, 1], dtype=np.int64), m)
    j = ends.ravel()
    first = np.fromiter(((c.indices[1] if s == 0 else c.indices[-2]) if len(c.indices) >= 2 else -1
                         for c, s in zip((curves[k] for k in ci.tolist()), side.tolist())), dtype=np.int64, count=2 * m)
    ok = (j >= 0) & (first >= 0)
    ok[ok] = valence[j[ok]] >= 2
    ci, side, j, first = ci[ok], side[ok], j[ok], first[ok]
    gap = np.linalg.norm(P[first] - nodes[j], axis=1)
    far = gap > shell_outer * (h[first] + SHELL.widen * noise)
    ci, side, j, first, gap = ci[far], side[far], j[far], first[far], gap[far]
    if not len(ci):
        return curves, 0
    ids = np.concatenate([c.indices for c in curves])
    used = np.zeros(len(P), dtype=bool)
    used[ids[ids >= 0]] = True
    spare = np.flatnonzero(~used)  # the samples of no curve
    if len(spare) == 0:
        return curves, 0
    # the samples of no curve near each node, all ends at once; the ends where none lies off
    # the straight line, or none near the node, are left as they are
    near = build_tree(P[spare]).query_ball_point(nodes[j], r=gap + link * h[first], workers=query_threads())
    cnt = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(near))
    keep = cnt > 0
    if not keep.any():
        return curves, 0
    g = np.repeat(np.arange(len(cnt), dtype=np.int64), cnt)
    s = spare[np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=int(cnt.sum()))]
    starts = np.r_[0, np.cumsum(cnt)[:-1]]
    dn = np.linalg.norm(P[s] - nodes[j][g], axis=1)
    off = segment_distance(P[s], P[first][g], nodes[j][g])
    nz = np.flatnonzero(keep)
    nearest = np.full(len(cnt), np.inf)
    nearest[nz] = np.minimum.reduceat(dn, starts[nz])
    widest = np.zeros(len(cnt))
    widest[nz] = np.maximum.reduceat(off, starts[nz])
    target = np.full(len(cnt), -1, dtype=np.int64)
    o = np.lexsort((s, dn, g))  # per end, its samples nearest the node first
    target[nz] = s[o[starts[nz]]]
    read = np.flatnonzero(keep & (widest > WALKIN.off * h[first]) & (nearest <= WALKIN.arrive * h[np.maximum(target, 0)]))
    if not len(read):
        return curves, 0
    sets = np.split(s, starts[1:])  # (each end's samples)
    paths = _paths(P, h, link, first[read], [sets[k] for k in read.tolist()], target[read])
    out = list(curves)
    walked = 0
    for k in np.lexsort((side[read], ci[read], j[read])).tolist():
        path = paths[k]
        e = read[k]
        if path is None or used[path].any():
            continue
        if segment_distance(P[path], P[first[e]], nodes[j[e]]).max() <= WALKIN.off * h[first[e]]:
            continue
        used[path] = True
        out[ci[e]] = _walked(P, out[ci[e]], int(side[e]), path)
        walked += 1
    return out, walked


def _paths(P, h, link, sources, sets, targets):
    """Per item, the samples of the shortest path from ``sources[k]`` to ``targets[k]`` through
    ``sets[k]`` (which holds the target; steps of at most ``link`` times the smaller spacing of
    their ends, a step's length its square), without its source; None when there is none. All
    items in one graph."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    U = np.concatenate([np.r_[a, b] for a, b in zip(sources.tolist(), sets)]).astype(np.int64)
    sizes = np.array([1 + len(b) for b in sets], dtype=np.int64)
    start = np.r_[0, np.cumsum(sizes)[:-1]]
    r = link * h[U]
    # the items' samples overlap (the ends at one node share them): each item set apart along
    # an extra axis, so that no pair of two items is ever listed (listed and dropped, they grew
    # as the square of the ends at a node: over 12 GB on 3,000 points of a hub)
    apart = np.repeat(np.arange(len(sets), dtype=np.float64) * (2.0 * float(r.max()) + 1.0), sizes)
    pa, pb = build_tree(np.column_stack([P[U], apart])).query_pairs(float(r.max()), output_type="ndarray").T
    d = np.linalg.norm(P[U[pa]] - P[U[pb]], axis=1)
    keep = d <= np.minimum(r[pa], r[pb])  # (every pair within one item: the items lie apart)
    # squared lengths: of two ways the one by shorter steps, through every sample on it
    G = coo_matrix((d[keep] ** 2 + NUMERIC.tiny, (pa[keep], pb[keep])), shape=(len(U), len(U))).tocsr()
    _, pred, _ = dijkstra(G, directed=False, indices=start, min_only=True, return_predecessors=True)
    out = []
    for s0, b, t in zip(start.tolist(), sets, targets.tolist()):
        at = s0 + 1 + int(np.flatnonzero(b == t)[0])
        if pred[at] < 0:
            out.append(None)
            continue
        out.append(U[walk_back(pred, at, s0)[::-1][1:]])
    return out


def _walked(P, c: Curve, side: int, path: np.ndarray) -> Curve:
    """Curve ``c`` with the samples ``path`` (from its first sample at end ``side`` towards the
    node) between that sample and the node."""
    if side == 0:
        pts = np.vstack([c.points[:1], P[path[::-1]], c.points[1:]])
        ind = np.r_[c.indices[:1], path[::-1], c.indices[1:]]
    else:
        pts = np.vstack([c.points[:-1], P[path], c.points[-1:]])
        ind = np.r_[c.indices[:-1], path, c.indices[-1:]]
    return Curve(pts, c.start, c.end, False, ind.astype(np.int64))
