"""Stage 9, under noise: branches that the finished network leaves unexplained.

A twig a few spacings long that leaves a curve near a junction can escape every earlier stage.
Its tip's shell holds the parent curve on both sides, so the tip looks like a point on a curve.
The widened shell under noise takes its junction into the neighbouring junction's region. The
chain tracer then runs past it. Its samples are still there: a run of points, each about one
spacing from the next, leading away from the network to points the network does not explain.

This stage reads that evidence from the finished network (its fitted curves), not from a shell.
It runs on noisy input only (:func:`.pipeline.reconstruct_robust`): on noise-free input the
shell test sees such twigs, and what the stage added there on real sketches (the ends of
strokes past a junction) scored worse. A point is *unexplained* when it lies more than ``UNEXPLAINED.explain`` spacings
(plus ``UNEXPLAINED.explain_noise`` times the noise) from every curve. The unexplained points
form groups (points within ``UNEXPLAINED.group`` spacings of each other). From the point of each
group farthest from the network, the shortest path through the samples (steps of at most the
link length ``link`` spacings) runs back to a point the network explains closely (within
``UNEXPLAINED.near`` spacings plus ``UNEXPLAINED.near_noise`` times the noise). That path is a
new branch, from the curve point its line meets when extended towards the network to a new
free end at its tip, when:

* it holds at least ``UNEXPLAINED.min_samples`` samples (on the path through every sample
  between its ends): a sampled curve, not one stray point;
* its tip lies at least ``min_spur`` less ``UNEXPLAINED.tip_short`` spacings (its last sample
  lies up to a spacing short of its true end) plus ``UNEXPLAINED.length_noise`` times the noise
  from where it joins the network (the spurs the repairs drop are shorter; noise scatters the
  samples around a junction that far), and ``min_spur`` spacings plus as much from every other
  node;
* its tip lies at least ``UNEXPLAINED.rise`` times the path's length from the network. A branch
  leaves the network. A path that runs alongside a curve is a stretch of that curve the network
  passes a little off, and it is left alone;
* its tip is a free end: the samples within ``min_spur`` spacings of it lie to one side
  (``UNEXPLAINED.end``, ``UNEXPLAINED.end_points``). Where they lie on both sides the samples go
  on past it: a curve the network missed or merged with another, not a branch;
* no sample the network leaves unexplained (beyond the near band) lies within ``min_spur``
  spacings of its tip off its own samples. Where some do, the samples run out to the tip and
  come back: a corner of a zigzagging curve (a traced neurite) that the network cuts across,
  whose two legs both lie on the network's side of the tip, so the free-end test above passes.

A branch joining a curve within ``min_spur`` spacings of the curve's free end extends the
curve: the curve stopped short, and its free end moves to the tip. A branch joining a curve
within ``UNEXPLAINED.snap`` spacings of one of its other nodes joins that node. Otherwise the
curve is cut at the joining point, which becomes a junction node. The stage adds branches,
extends and splits curves, and changes nothing else. Under noise the new branches (and an
extended curve) are fitted like every other curve.
"""

from __future__ import annotations

import itertools
from typing import Callable, NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

from ...network import Curve
from ...neighbors import build_tree, query_threads
from .chains import segment_distance
from .curves import renumbered
from .thresholds import NUMERIC, UNEXPLAINED

__all__ = ["add_unexplained_branches", "network_distance", "pairs_within", "walk_back", "explain_band", "noise_band", "leaves"]


def twig_reach(min_spur: float, h, noise: float):
    """The least reach of a twig from where it joins: ``min_spur`` less ``UNEXPLAINED.tip_short``
    spacings ``h`` (its tip's sample may lie up to a spacing short of its end), plus
    ``UNEXPLAINED.length_noise`` times the noise (the stage's branches, and
    :func:`.branched.orphan_twigs`, :func:`.branched._free_branch` on noisy input)."""
    return (min_spur - UNEXPLAINED.tip_short) * h + UNEXPLAINED.length_noise * noise


def free_reach(min_spur: float, h, noise: float):
    """The least length of a free branch read where no shell saw its end (a chain's branch,
    :func:`.branched._free_branch`; a branch wholly inside a region, :func:`.spanning._free_arms`):
    ``min_spur`` spacings ``h``; on noisy input (``noise`` > 0) as long as stage 9's twig
    (:func:`twig_reach`) where that is shorter: the same curve under the same noise is a twig there."""
    need = min_spur * h
    return min(need, twig_reach(min_spur, h, noise)) if noise > 0 else need


def noise_band(noise: float) -> float:
    """The band in which noise scatters a curve's samples about it: ``UNEXPLAINED.explain_noise``
    times the noise scale ``noise``."""
    return UNEXPLAINED.explain_noise * noise


def explain_band(h, noise: float):
    """How far from every curve a sample is unexplained: ``UNEXPLAINED.explain`` spacings ``h``
    (a float or an array) plus the noise band (:func:`noise_band`)."""
    return UNEXPLAINED.explain * h + noise_band(noise)


def leaves(off: float, length: float, h: float, noise: float) -> bool:
    """Whether a branch whose tip lies ``off`` from the curves it joins, ``length`` from where it
    joins them, leaves them: beyond the noise band (:func:`explain_band`) and at least
    ``UNEXPLAINED.rise`` times that length off (the twig tests of stage 6,
    :func:`.repairs._twig` and :func:`.branched.split_tails`)."""
    return off > max(explain_band(h, noise), UNEXPLAINED.rise * length)


class _Join(NamedTuple):
    """Where a branch joins the network: ``kind`` "node" (at node ``at``), "cut" (curve ``at``
    cut at its point ``sample``) or "extend" (curve ``at`` runs on from its point ``sample``
    in place of its free end at ``side``: 0 its start, 1 its end)."""

    kind: str
    at: int
    sample: int = -1
    side: int = -1


class _Vertices(NamedTuple):
    """The curves' points stacked: ``V`` (M, d), each curve's first row ``off`` (n + 1,), the
    curve of each row ``owner`` (M,) and a k-d tree of ``V``."""

    V: np.ndarray
    off: np.ndarray
    owner: np.ndarray
    tree: object


def _vertices(curves: list[Curve]) -> _Vertices:
    V = np.concatenate([c.points for c in curves])
    lens = np.fromiter((len(c.points) for c in curves), dtype=np.int64, count=len(curves))
    return _Vertices(V, np.r_[0, np.cumsum(lens)], np.repeat(np.arange(len(curves)), lens), build_tree(V))


def _near_band(h: np.ndarray, noise: float) -> np.ndarray:
    """The distance within which the network explains a sample of spacing ``h`` closely:
    ``UNEXPLAINED.near`` spacings plus ``UNEXPLAINED.near_noise`` times the noise."""
    return UNEXPLAINED.near * h + UNEXPLAINED.near_noise * noise


def _distances(P: np.ndarray, h: np.ndarray, curves: list[Curve], vx: _Vertices, noise: float) -> np.ndarray:
    """Each point's distance to the network as the stage reads it (N,): a curve's sample lying
    within the near band (``UNEXPLAINED.near`` spacings plus ``near_noise`` times the noise) of
    its own place on the curve gets that distance (at most the true one's band: it is explained
    and near either way, which is all the stage asks of it); every other point its distance to
    the network (:func:`network_distance`), so only those are searched for."""
    d = np.full(len(P), np.inf)
    ids = np.concatenate([c.indices for c in curves])
    on = ids >= 0
    ids, X = ids[on], vx.V[on]
    own = np.linalg.norm(P[ids] - X, axis=1)
    near = own <= _near_band(h[ids], noise)
    d[ids[near]] = own[near]
    rest = np.flatnonzero(np.isinf(d))
    if len(rest):
        d[rest] = _network_distance(P[rest], curves, vx)
    return d


def network_distance(P: np.ndarray, curves: list[Curve]) -> np.ndarray:
    """The distance of every point to the nearest curve of the network.

    The distance is taken to the two polyline segments at each point's nearest curve vertex.
    With vertices about a spacing apart, this equals the distance to the polylines within a
    fraction of the vertex step.

    Parameters
    ----------
    P : (N, d) ndarray
        The points.
    curves : list of Curve
        At least one curve with at least one point.

    Returns
    -------
    (N,) ndarray
        The distances, in the units of ``P``.
    """
    return _network_distance(P, curves, _vertices(curves))


def _network_distance(P: np.ndarray, curves: list[Curve], vx: _Vertices) -> np.ndarray:
    """:func:`network_distance` with the curves' vertices ``vx`` given."""
    V, off = vx.V, vx.off
    lens = np.diff(off)
    first = np.repeat(off[:-1], lens)
    last = np.repeat(off[1:] - 1, lens)
    closed = np.repeat(np.fromiter((bool(c.closed) for c in curves), dtype=bool, count=len(curves)), lens)
    d, v = vx.tree.query(P, workers=query_threads())
    best = d
    for step in (-1, 1):  # the segment before and the one after the nearest vertex
        w = v + step
        wrap_lo, wrap_hi = w < first[v], w > last[v]
        w = np.where(wrap_lo, np.where(closed[v], last[v], v), w)
        w = np.where(wrap_hi, np.where(closed[v], first[v], v), w)
        best = np.minimum(best, segment_distance(P, V[v], V[w]))
    return best


def add_unexplained_branches(P: np.ndarray, h: np.ndarray, nodes: np.ndarray, curves: list[Curve],
                             noise: float, link: float, min_spur: float,
                             fit: Callable[[list[Curve]], list[Curve]] | None = None,
                             ) -> tuple[np.ndarray, list[Curve], int]:
    """The network with a branch added for every run of samples it leaves unexplained.

    See the module docstring for the rule.

    Parameters
    ----------
    P : (N, d) ndarray
        The points, in the internal order the curves' ``indices`` refer to.
    h : (N,) ndarray
        Local spacing of each point.
    nodes : (n, d) ndarray
        Node positions, sorted by coordinates.
    curves : list of Curve
        The network's curves (``indices``: internal point ids, -1 at computed nodes).
    noise : float
        Noise scale (absolute units; 0 on clean input).
    link : float
        Longest step of a branch's path, in spacings (the method's link length).
    min_spur : float
        Shortest branch, in spacings (from where it joins the network to its tip).
    fit : callable, optional
        Applied to the list of new branches before they join the network (the fit of a noisy
        network's curves); default: they stay their samples.

    Returns
    -------
    nodes : (n', d) ndarray
        Node positions, sorted by coordinates: the input's, the new junctions and the new
        free ends.
    curves : list of Curve
        New list. The curves split where a branch joins them or run on to a branch's tip (a
        free end), then the new branches (each from its junction to its tip, its samples'
        internal ids, -1 at the junction). The list is sorted as :func:`.curves.sort_curves`
        sorts it.
    added : int
        The number of branches added and curves run on. When it is 0, ``nodes`` and
        ``curves`` are the inputs.
    """
    if not curves or len(P) == 0:
        return nodes, curves, 0
    vx = _vertices(curves)
    d = _distances(P, h, curves, vx, noise)
    un = np.flatnonzero(d > explain_band(h, noise))
    if len(un) == 0:
        return nodes, curves, 0
    ptree = build_tree(P)
    branches = _branches(P, h, d, un, noise, link, min_spur, ptree)
    if not branches:
        return nodes, curves, 0
    joins, kept = _joins(P, h, d, nodes, curves, vx, branches, min_spur, link, noise, ptree)
    if not kept:
        return nodes, curves, 0
    return _with_branches(P, nodes, curves, joins, kept, fit)


def _branches(P, h, d, un, noise, link, min_spur, ptree) -> list[tuple[np.ndarray, np.ndarray]]:
    """Candidate branches: per group of unexplained points ``un`` with a path to the network,
    the shortest path from a closely explained sample to the group's tip (its point farthest
    from the network) through samples at most ``link`` spacings apart (the smaller spacing of
    the two), and the path between the same two samples through every sample between them
    (the least sum of squared steps); each an array of point ids from the explained sample to
    the tip."""
    pairs, _ = pairs_within(P[un], UNEXPLAINED.group * h[un])
    n = len(un)
    A = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, group = connected_components(A, directed=False)
    # the tip of each group: its point farthest from the network (ties: the lowest id)
    order = np.lexsort((un, -d[un], group))
    starts = np.r_[0, np.flatnonzero(np.diff(group[order])) + 1]
    tips = un[order[starts]]
    # a tip must be a free end (the samples near it on one side): tested first, on the tip alone
    tips = tips[np.fromiter((_is_end(P, ptree, int(t), min_spur * float(h[t])) for t in tips.tolist()),
                            dtype=bool, count=len(tips))]
    if len(tips) == 0:
        return []
    # the samples a path can use: those within its longest length of a tip
    reach = UNEXPLAINED.search * h[tips]
    local = np.unique(np.concatenate([np.asarray(x, dtype=np.int64) for x in ptree.query_ball_point(
        P[tips], reach, workers=query_threads())] + [tips]).astype(np.int64))
    hl = h[local]
    # (steps in the smaller of the two spacings: a point alone in sparse surroundings, an
    # outlier the isolated-point rule kept, does not step far)
    lp, w = pairs_within(P[local], link * hl)
    if len(lp) == 0:
        return []
    w = np.maximum(w, NUMERIC.tiny)
    m = len(local)
    G = coo_matrix((w, (lp[:, 0], lp[:, 1])), shape=(m, m)).tocsr()
    # the same ends joined through every sample between them: the path whose squared steps sum
    # least (the shortest path above skips samples that lie nearly in line)
    G2 = coo_matrix((w * w, (lp[:, 0], lp[:, 1])), shape=(m, m)).tocsr()
    near = d[local] <= _near_band(hl, noise)
    src = np.searchsorted(local, tips)
    # the paths of each connected piece of the graph searched on its own (a path cannot leave
    # its piece; one search over all tips at once would hold tips x samples distances)
    _, piece = connected_components(G, directed=False)
    perm = np.lexsort((np.arange(m), piece))  # by piece, in order within each
    inv = np.empty(m, dtype=np.int64)
    inv[perm] = np.arange(m)
    Gp, G2p, nearp = G[perm][:, perm], G2[perm][:, perm], near[perm]
    bounds = np.r_[0, np.cumsum(np.bincount(piece, minlength=int(piece.max()) + 1))]
    found: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    tip_piece = piece[src]
    for c in np.unique(tip_piece).tolist():
        a, b = int(bounds[c]), int(bounds[c + 1])
        ks = np.flatnonzero(tip_piece == c)
        srcs = inv[src[ks]] - a
        sub, sub2 = Gp[a:b, a:b], G2p[a:b, a:b]
        dist, pred = dijkstra(sub, directed=False, indices=srcs, return_predecessors=True)
        _, pred2 = dijkstra(sub2, directed=False, indices=srcs, return_predecessors=True)
        for r, k in enumerate(ks.tolist()):
            cand = np.flatnonzero(nearp[a:b] & np.isfinite(dist[r]))
            if len(cand) == 0:
                continue
            # the nearest closely explained sample (ties: the lowest)
            j = int(cand[np.lexsort((perm[a + cand], dist[r][cand]))[0]])
            found[k] = (local[perm[a + walk_back(pred[r], j, int(srcs[r]))]],
                        local[perm[a + walk_back(pred2[r], j, int(srcs[r]))]])
    return [found[k] for k in sorted(found)]


def pairs_within(X: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(i, j)``, ``i < j``, of the points ``X`` (m, d) at most the smaller of their
    radii ``r`` (m,) apart, as an (p, 2) array, and their distances (p,). All pairs within the
    largest radius are searched at once when it is at most ``UNEXPLAINED.pair_spread`` times
    the median; else each point's neighbours within its own radius (one far-reaching radius, of
    an outlier in sparse surroundings, does not widen every search). The pairs are the same
    either way."""
    tree = build_tree(X)
    if len(r) == 0 or float(r.max()) <= UNEXPLAINED.pair_spread * float(np.median(r)):
        ij = tree.query_pairs(float(r.max()) if len(r) else 0.0, output_type="ndarray")
        i, j = ij[:, 0].astype(np.int64), ij[:, 1].astype(np.int64)
    else:  # a few far-reaching radii: each point searched within its own
        near = tree.query_ball_point(X, r, workers=query_threads())
        cnt = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(near))
        i = np.repeat(np.arange(len(X), dtype=np.int64), cnt)
        j = np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=int(cnt.sum()))
        keep = j > i
        i, j = i[keep], j[keep]
    w = np.linalg.norm(X[i] - X[j], axis=1)
    ok = w <= np.minimum(r[i], r[j])
    return np.column_stack([i[ok], j[ok]]), w[ok]


def walk_back(pred: np.ndarray, j: int, s: int) -> np.ndarray:
    """The vertices from ``j`` back to the source ``s`` of the predecessor row ``pred``."""
    path = [j]
    while path[-1] != s:
        path.append(int(pred[path[-1]]))
    return np.asarray(path, dtype=np.int64)


def _joins(P, h, d, nodes, curves, vx, branches, min_spur, link, noise, ptree):
    """Where each kept branch joins the network, and the kept branches.

    Returns
    -------
    joins : list of _Join
        Per kept branch, where it joins (an "extend" join: the curve's free end moves to the
        tip, the curve runs from its point ``sample`` through the branch).
    kept : list of (m,) ndarray of int64
        The kept branches' point ids, from the first sample off the network to the tip.
    """
    V, off, owner, tree = vx
    arcs: dict[int, np.ndarray] = {}

    def arc_of(ci: int) -> np.ndarray:  # arc length along curve ci at each of its points
        if ci not in arcs:
            arcs[ci] = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(curves[ci].points, axis=0), axis=1))]
        return arcs[ci]

    ends = [e for c in curves if c.start is not None for e in (c.start, c.end)]
    valence = np.bincount(np.asarray(ends, dtype=np.int64), minlength=len(nodes))
    used = np.zeros(len(P), dtype=bool)
    ids = np.concatenate([c.indices for c in curves])
    used[ids[ids >= 0]] = True
    joins, kept = [], []
    for path, samples in branches:
        j, tip = int(path[0]), int(path[-1])
        # (counted on the path through every sample: the shortest path may step from the
        # explained sample straight to the tip past the branch's other samples)
        if len(samples) < UNEXPLAINED.min_samples or used[tip]:
            continue  # (a tip that is a curve's sample: that curve runs through it)
        hj = float(h[j])
        # (the foot's direction needs two samples off the network: a shortest path of one step
        # from its explained sample to the tip has none, the path through every sample has)
        q = _foot(P, V, tree, path if len(path) > 2 else samples, link * hj + UNEXPLAINED.near_noise * noise)
        x = V[q]
        if np.linalg.norm(P[tip] - x) < twig_reach(min_spur, hj, noise):  # (a branch's shortest reach)
            continue
        plen = float(np.linalg.norm(np.diff(P[path], axis=0), axis=1).sum() + np.linalg.norm(P[j] - x))
        if d[tip] < UNEXPLAINED.rise * plen:
            continue
        if _other_leg(P, h, d, ptree, samples, min_spur, noise):
            continue  # (a zigzag's corner the network cuts across: out and back)
        ci = int(owner[q])
        s = q - int(off[ci])
        c = curves[ci]
        arc = arc_of(ci)
        at = arc[s]
        # by a free end: the curve stopped short of its end, and runs on to the tip
        if c.start is not None and c.start != c.end and valence[c.start] == 1 and at <= min_spur * hj:
            jn = _Join("extend", ci, s, 0)
        elif c.end is not None and c.start != c.end and valence[c.end] == 1 and arc[-1] - at <= min_spur * hj:
            jn = _Join("extend", ci, s, 1)
        elif c.start is not None and at <= UNEXPLAINED.snap * hj:
            jn = _Join("node", int(c.start))
        elif c.end is not None and arc[-1] - at <= UNEXPLAINED.snap * hj:
            jn = _Join("node", int(c.end))
        else:
            jn = _Join("cut", ci, s)
        own = -1 if jn.kind != "extend" else (c.start if jn.side == 0 else c.end)
        dn = np.linalg.norm(nodes - P[tip], axis=1) if len(nodes) else np.zeros(0)
        if own >= 0:
            dn[own] = np.inf
        if len(dn) and np.min(dn) < min_spur * float(h[tip]) + UNEXPLAINED.length_noise * noise:
            continue  # a tip by a node: a piece of the junction there, not a free end
        joins.append(jn)
        # its samples: those past the last one the network explains closely, none a sample of
        # a curve already (a point stays in one curve)
        close = d[samples] <= _near_band(h[samples], noise)
        samples = samples[len(samples) - int(np.argmax(close[::-1])):] if close.any() else samples
        kept.append(samples[~used[samples]])
    return joins, kept


def _other_leg(P, h, d, ptree, samples, min_spur, noise) -> bool:
    """Whether samples the network does not explain closely (over the near band of
    :func:`_distances`) lie within ``min_spur`` spacings of the branch's tip and off the branch
    (over that band from the polyline of its samples ``samples``, from its explained sample to
    the tip: densely sampled noisy branches are bands of samples beside that path): the samples
    run out to the tip and come back, a detour of the curve, not a branch."""
    tip = int(samples[-1])
    near = np.asarray(ptree.query_ball_point(P[tip], min_spur * float(h[tip])), dtype=np.int64)
    band = _near_band(h[near], noise)
    out = d[near] > band
    if not out.any():
        return False
    B = P[samples]
    off = segment_distance(P[near[out]][:, None], B[:-1][None], B[1:][None]).min(axis=1)
    return bool(np.any(off > band[out]))


def _is_end(P, ptree, tip, r) -> bool:
    """Whether the samples within ``r`` of the point ``tip`` (at least ``UNEXPLAINED.end_points``
    of them) lie to one side of it, as at a curve's free end: the mean of the unit vectors to
    them is at least ``UNEXPLAINED.end`` long (about 0 where samples lie on both sides, 1 at an
    end)."""
    near = np.asarray(ptree.query_ball_point(P[tip], r), dtype=np.int64)
    near = near[near != tip]
    if len(near) < UNEXPLAINED.end_points:
        return False
    u = P[near] - P[tip]
    u = u / np.maximum(np.linalg.norm(u, axis=1), NUMERIC.tiny)[:, None]
    return bool(np.linalg.norm(u.mean(axis=0)) >= UNEXPLAINED.end)


def _foot(P, V, tree, path, r) -> int:
    """The curve vertex (a row of ``V``) where the branch ``path`` (from its explained sample to
    its tip) joins the network: of the vertices within ``r`` of its first sample off the network,
    the one nearest the branch's line extended towards the network (the path itself may step
    across to the network a little beyond the branch's foot)."""
    a = P[path[1]]
    b = P[path[min(UNEXPLAINED.foot_samples, len(path) - 1)]]
    u = a - b
    n = float(np.linalg.norm(u))
    near = np.asarray(tree.query_ball_point(a, r), dtype=np.int64)
    if n == 0.0 or len(near) == 0:
        return int(tree.query(a)[1])
    u = u / n
    w = V[near] - a
    t = np.maximum(w @ u, 0.0)
    off = np.linalg.norm(w - t[:, None] * u, axis=1)
    return int(near[np.lexsort((near, t, off))[0]])


def _extended(P, c: Curve, s: int, side: int, br: np.ndarray, fit) -> Curve:
    """The curve ``c`` run on from its sample ``s`` through the branch samples ``br`` to a free
    end at the last of them (in place of its free end at ``side``); under noise fitted again
    from its samples (the input points; the computed node kept at its other end)."""
    pts, ind = (c.points, c.indices) if side == 1 else (c.points[::-1], c.indices[::-1])
    k = s if side == 1 else len(c.points) - 1 - s
    raw = np.where((ind >= 0)[:, None], P[np.maximum(ind, 0)], pts) if fit is not None else pts
    cv = Curve(np.vstack([raw[:k + 1], P[br]]), c.start if side == 1 else c.end, c.end if side == 1 else c.start,
               False, np.r_[ind[:k + 1], br].astype(np.int64))
    if fit is not None:
        cv = fit([cv])[0]
    return cv if side == 1 else cv.reversed()


def _with_branches(P, nodes, curves, joins, kept, fit):
    """The network with the branches ``kept`` joined at ``joins`` (see :func:`_joins`): curves
    cut at their joining samples, a node at each cut and at each tip, nodes sorted and curves
    renumbered, oriented from the lower node id and sorted."""
    node_list = [np.asarray(x, dtype=float) for x in nodes]
    cuts: dict[int, list[int]] = {}
    for jn in joins:
        if jn.kind == "cut":
            cuts.setdefault(jn.at, []).append(jn.sample)
    # a free end runs on to one branch's tip (the first of its branches; none where the curve
    # is cut as well)
    extend: dict[int, tuple[int, int, np.ndarray]] = {}
    for jn, br in zip(joins, kept):
        if jn.kind == "extend" and jn.at not in cuts and jn.at not in extend:
            extend[jn.at] = (jn.sample, jn.side, br)
    node_at: dict[tuple[int, int], int] = {}
    out: list[Curve] = []
    for ci, c in enumerate(curves):
        if ci in extend:
            out.append(_extended(P, c, *extend[ci], fit))
            end = c.start if extend[ci][1] == 0 else c.end
            node_list[end] = P[extend[ci][2][-1]].copy()
            continue
        if ci not in cuts:
            out.append(c)
            continue
        cs = sorted(set(cuts[ci]))
        for s in cs:
            node_list.append(c.points[s].copy())
            node_at[(ci, s)] = len(node_list) - 1
        pts, ind = c.points, c.indices
        if c.closed and c.start is None:  # a loop without node: it starts at its first cut
            s0 = cs[0]
            pts = np.vstack([pts[s0:], pts[:s0 + 1]])
            ind = np.r_[ind[s0:], ind[:s0 + 1]]
            bnd = [s - s0 for s in cs] + [len(c.points)]
            ids = [node_at[(ci, s)] for s in cs] + [node_at[(ci, s0)]]
        else:
            bnd = [0] + cs + [len(pts) - 1]
            ids = [c.start] + [node_at[(ci, s)] for s in cs] + [c.end]
        for x, y, u, v in zip(bnd[:-1], bnd[1:], ids[:-1], ids[1:]):
            out.append(Curve(pts[x:y + 1].copy(), u, v, False, ind[x:y + 1].copy()))
    new = []
    for jn, br in zip(joins, kept):
        if jn.kind == "extend":
            continue
        a = jn.at if jn.kind == "node" else node_at[(jn.at, jn.sample)]
        node_list.append(P[br[-1]].copy())
        b = len(node_list) - 1
        new.append(Curve(np.vstack([node_list[a], P[br]]), a, b, False, np.r_[-1, br].astype(np.int64)))
    out.extend(fit(new) if fit is not None else new)
    X, final = renumbered(np.stack(node_list), out)
    return X, final, len(new) + len(extend)
