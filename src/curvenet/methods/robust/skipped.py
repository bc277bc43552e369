"""Stage 8c: a short free spur that is the skipped first stretch of a neighbouring curve.

A real curve can turn sharply several times within a few spacings (neuron tracings zigzag with
turns of 50-110 degrees every 2 spacings). Around such a zigzag the shell test sees three
branches and places a junction. The chain tracer then reads part of the zigzag as a short spur
to a free end, and the curve that carries on past it starts with a jump: from the junction
over the spur's samples to its first sample beyond the spur's tip. The samples between the
spur's tip and that first sample are in no curve.

This stage reads that pattern from the finished curves (before the fit). At a junction (valence
3 or more, no loop) with a spur (a curve to a free end, at most ``SKIPPED.spur`` spacings long),
the spur is the skipped stretch of one of the other curves when:

* that curve's first sample lies farther from the node than the spur's tip (it jumped past the
  spur; on a twig at a junction the curves' first samples lie nearer the node than the twig's
  tip),
  or, where that first sample lies nearer, the path below is longer than the way from the tip
  through the node to that sample by ``SKIPPED.around`` spacings (the curve came back past the
  junction: it runs around it, where a path between a twig's tip and its neighbour runs
  through it);
* a path leads from the spur's tip to that first sample through samples that belong to no
  curve (searched within ``SKIPPED.search`` spacings of the tip), with steps of at most the
  link length ``link`` spacings (in the smaller spacing of their two ends), each sample no
  nearer the node than the nearer of the tip and the first sample less ``SKIPPED.clearance``
  spacings (the path runs outside the junction).

Of the curves that qualify, the one with the shortest path takes the spur: the curve now runs
from the node through the spur's samples and the path's samples to its own, and the spur's free
end is dropped. A node of valence 3 is then of valence 2 and is dropped too: that curve and the
third are one curve (a loop through one node when their far ends are the same node). A node of
higher valence stays a junction.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from ...network import Curve
from ...neighbors import build_tree
from .curves import end_nodes, renumbered
from .thresholds import NODES, SKIPPED
from .unexplained import pairs_within, walk_back

__all__ = ["rejoin_skipped_stretches"]


def rejoin_skipped_stretches(P: np.ndarray, h: np.ndarray, nodes: np.ndarray, curves: list[Curve],
                             link: float) -> tuple[np.ndarray, list[Curve], int]:
    """The network with every short free spur that a neighbouring curve skipped made part of
    that curve (see the module docstring for the rule).

    Parameters
    ----------
    P : (N, d) ndarray
        The points, in the internal order the curves' ``indices`` refer to.
    h : (N,) ndarray
        Local spacing of each point.
    nodes : (n, d) ndarray
        Node positions, sorted by coordinates.
    curves : list of Curve
        The network's curves, not fitted (``indices``: internal point ids, -1 at computed
        nodes).
    link : float
        Longest step of a bridging path, in spacings (the method's link length).

    Returns
    -------
    nodes : (n', d) ndarray
        Node positions, sorted by coordinates: the input's without the dropped junctions and
        free ends.
    curves : list of Curve
        New list, sorted as :func:`.curves.sort_curves` sorts it. When ``rejoined`` is 0,
        ``nodes`` and ``curves`` are the inputs.
    rejoined : int
        The number of spurs made part of a neighbouring curve.
    """
    n = len(nodes)
    if not curves or n == 0:
        return nodes, curves, 0
    ends, valence = end_nodes(curves, n)
    # candidates: a node of the smallest junction valence (a spur and two curves) at one end of
    # a curve whose other end is free and which is short
    free = (ends >= 0) & (valence[np.maximum(ends, 0)] == 1)
    one = np.flatnonzero(free.any(axis=1) & ~free.all(axis=1))
    at_j = np.where(free[one, 0], ends[one, 1], ends[one, 0])
    keep = valence[at_j] >= NODES.junction_valence
    cand = []
    for j, ci in zip(at_j[keep].tolist(), one[keep].tolist()):
        own = curves[ci].indices[curves[ci].indices >= 0]
        if len(own) and curves[ci].length <= SKIPPED.spur * float(np.median(h[own])):
            cand.append((j, ci))
    if not cand:
        return nodes, curves, 0
    ids = np.concatenate([c.indices for c in curves])
    used = np.zeros(len(P), dtype=bool)
    used[ids[ids >= 0]] = True
    spare = np.flatnonzero(~used)  # the samples of no curve: a bridge's only samples
    if len(spare) == 0:
        return nodes, curves, 0
    tree = build_tree(P[spare])
    out: list[Curve | None] = list(curves)
    at: dict[int, list[int]] = {}
    for ci, (a, b) in enumerate(ends.tolist()):
        for v in {a, b}:
            if v >= 0:
                at.setdefault(v, []).append(ci)
    dropped: list[int] = []
    rejoined = 0
    for j, s in sorted(cand):
        inc = at.get(j, [])
        if s not in inc or len(inc) < NODES.junction_valence or any(out[ci].start == out[ci].end for ci in inc):
            continue  # (a curve here changed in an earlier rejoin, or a loop at the node)
        sp = out[s]
        best = _best_bridge(P, h, nodes[j], j, sp, [(ci, out[ci]) for ci in inc if ci != s], used, spare, tree, link)
        if best is None:
            continue
        a, bridge = best
        tip_node = sp.end if sp.start == j else sp.start
        used[bridge] = True
        if len(inc) == NODES.junction_valence:  # the node is left with two curves: they are one
            b = next(ci for ci in inc if ci not in (s, a))
            new = _merged(P, j, sp, bridge, out[a], out[b])
            gone = (s, a, b)
            dropped.append(j)
            at.pop(j, None)
        else:  # a junction still: the curve runs from it through the spur
            new = _rerouted(P, j, sp, bridge, out[a])
            gone = (s, a)
        for ci in gone:
            out[ci] = None
        out.append(new)
        k = len(out) - 1
        for v in (new.start, new.end):
            lst = at.get(v)
            if lst is None:
                continue
            for ci in gone:
                if ci in lst:
                    lst.remove(ci)
            if k not in lst:
                lst.append(k)
        at.pop(tip_node, None)
        dropped.append(tip_node)
        rejoined += 1
    if not dropped:
        return nodes, curves, 0
    X, final = renumbered(nodes, [c for c in out if c is not None], drop=dropped)
    return X, final, rejoined


def _from(c: Curve, j: int) -> tuple[np.ndarray, np.ndarray]:
    """The points and indices of curve ``c`` oriented to start at node ``j``."""
    return (c.points, c.indices) if c.start == j else (c.points[::-1], c.indices[::-1])


def _best_bridge(P, h, x0, j, sp, others, used, spare, tree, link):
    """(curve id, bridge sample ids) of the curve of ``others`` (pairs of curve id and curve
    at node ``j``, at ``x0``) whose skipped stretch the spur ``sp`` is, with the shortest
    bridging path; None when no curve qualifies."""
    _, sid = _from(sp, j)
    sid = sid[sid >= 0]
    if len(sid) == 0:
        return None
    tip = int(sid[-1])
    dtip = float(np.linalg.norm(P[tip] - x0))
    best = None
    for ci, c in others:
        _, aid = _from(c, j)
        aid = aid[aid >= 0]
        if len(aid) == 0:
            continue
        a0 = int(aid[0])
        da0 = float(np.linalg.norm(P[a0] - x0))
        reach = max(float(np.linalg.norm(P[a0] - P[tip])) + link * max(h[tip], h[a0]), SKIPPED.search * h[tip])
        near = spare[np.asarray(tree.query_ball_point(P[tip], r=reach), dtype=np.int64)]
        near = near[~used[near]]
        near = near[np.linalg.norm(P[near] - x0, axis=1) >= min(dtip, da0) - SKIPPED.clearance * h[near]]
        ids = np.r_[tip, near, a0].astype(np.int64)
        path = _shortest_path(P, h, ids, link)
        # the curve jumped past the spur's tip, or the path runs around the junction (longer
        # than the way through the node): on a twig neither holds
        if path is not None and da0 <= dtip and path[0] <= dtip + da0 + SKIPPED.around * h[tip]:
            continue
        if path is not None and (best is None or path[0] < best[0]):
            best = (path[0], ci, path[1])
    return None if best is None else (best[1], best[2])


def _shortest_path(P, h, ids, link):
    """(length, inner sample ids) of the shortest path from ``ids[0]`` to ``ids[-1]`` through
    ``ids`` with steps of at most ``link`` times the smaller spacing of their ends; None when
    there is none."""
    pr, w = pairs_within(P[ids], link * h[ids])
    if len(pr) == 0:
        return None
    m = len(ids)
    G = coo_matrix((w, (pr[:, 0], pr[:, 1])), shape=(m, m)).tocsr()
    dist, pred = dijkstra(G, directed=False, indices=0, return_predecessors=True)
    if not np.isfinite(dist[m - 1]):
        return None
    return float(dist[m - 1]), ids[walk_back(pred, m - 1, 0)[::-1][1:-1]]


def _rerouted(P, j, sp, bridge, ca) -> Curve:
    """Curve ``ca`` from node ``j`` through the spur's samples and the bridge to its first
    sample and on to its far end."""
    _, sid = _from(sp, j)
    sid = sid[sid >= 0]
    pa, ia = _from(ca, j)
    first = int(np.flatnonzero(ia >= 0)[0])
    pts = np.vstack([pa[:1], P[sid], P[bridge], pa[first:]])
    ind = np.r_[ia[:1], sid, bridge, ia[first:]].astype(np.int64)
    return Curve(pts, j, ca.end if ca.start == j else ca.start, False, ind)


def _merged(P, j, sp, bridge, ca, cb) -> Curve:
    """One curve: ``cb`` from its far end to node ``j`` (the node's point left out), then
    :func:`_rerouted` ``ca`` without the node's point."""
    pb, ib = _from(cb, j)
    ra = _rerouted(P, j, sp, bridge, ca)
    return Curve(np.vstack([pb[::-1][:-1], ra.points[1:]]), cb.end if cb.start == j else cb.start, ra.end, False,
                 np.r_[ib[::-1][:-1], ra.indices[1:]].astype(np.int64))
