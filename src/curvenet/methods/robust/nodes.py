"""Stage 7: node placement: where each junction and free end sits.

A region touched by one chain end is a free end: its points extend the chain and the node is
the extreme point ahead (:func:`free_end`), or, where the region bends (a traced neurite turning
a few spacings before its tip), the point farthest along it (:func:`bent_tips`), unless the
region hides a whole fork (:func:`~.junctions.hidden_fork`; also searched on the region and
its chain's last samples, :func:`_fork_tail`: a twig and its sibling whose tips the region
holds, their junction a few samples back on the chain, placed by :func:`_tail_fork_node`). A region touched by 3 or more ends is a junction: every
incident branch is walked into the region, its line is fitted on its last
``NODES.fit_span h + NODES.fit_noise noise``, and the node is the least-squares intersection of
those lines (:func:`junction_positions`, one compiled call for all junctions; a line that strays
from the others' node, fitted before its curve turns, left out), or the region's
median point where that intersection lies off the samples (:func:`median_points`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import kernels as _k
from .chains import Chain, end_counts, end_portion, group_medians, segment_distance
from .junctions import branches_meeting, fork_possible, hidden_fork, region_paths, swallowed_branches
from .params import RobustParams, Scales
from .thresholds import CURVES, LINKS, NODES, NUMERIC, SHELL
from .topology import Topology

__all__ = ["Placement", "place_nodes", "free_end", "bent_tips", "junction", "junction_positions"]


class Placement(NamedTuple):
    """The nodes of a repaired topology and what the curves need of them.

    Attributes
    ----------
    nodes : (n_nodes, d) ndarray
        Node positions, sorted by coordinates (rounded to ``CURVES.round_decimals``).
    new_id : (n_nodes,) ndarray of int64
        The sorted id of each node in placement order.
    node_of : dict of int to int
        The node (placement order) of each region that has one.
    end_ext : dict of (int, int) to ndarray
        Per free chain end ``(live chain, side)``: the region points that extend it, outward.
    extra : list of (int, int, ndarray)
        Short free branches found inside a region: (node, tip node, point ids from the node out),
        nodes in placement order.
    live : list of Chain
        The live chains.
    v : (n_regions,) ndarray of int64
        The valence of every region.
    """

    nodes: np.ndarray
    new_id: np.ndarray
    node_of: dict
    end_ext: dict
    extra: list
    live: list
    v: np.ndarray


def place_nodes(topo: Topology, sc: Scales, prm: RobustParams) -> Placement:
    """Stage 7: a node for every region of valence 1 (free end) or 3 and more (junction).

    Parameters
    ----------
    topo : Topology
        After the repairs (no region of valence 2 is left but those kept as junctions).
    sc : Scales
    prm : RobustParams

    Returns
    -------
    Placement
    """
    P, h, regions = topo.P, sc.h, topo.regions
    dim = P.shape[1]
    v = topo.v
    live: list[Chain] = topo.live()
    node_of: dict[int, int] = {}
    node_pos: list = []
    end_ext: dict[tuple[int, int], np.ndarray] = {}
    inc_at: dict[int, list[tuple[int, int]]] = {}
    extra: list[tuple[int, np.ndarray]] = []
    for ci, c in enumerate(live):
        if not c.closed:
            for s in (0, 1):
                inc_at.setdefault(c.ends[s], []).append((ci, s))
    # all junction nodes in one compiled call
    jr = [r for r in range(len(regions)) if v[r] >= 2]
    JX, JMAYBE = junction_positions(P, sc, prm, [(live, inc_at[r], regions[r]) for r in jr])
    jpos = {r: i for i, r in enumerate(jr)}
    # a node off the samples (its region's and its branches') moves to the region's median
    # point; on noise-free input only where the region holds more than the junction (a chain
    # end lies beyond the shell radius of that point): there the lines are sure, and a node
    # off the samples of a small region is where sketched strokes stop short of each other
    hr = [r for r in jr if v[r] >= NODES.junction_valence and len(regions[r])]
    off, hl_of = [], {}
    if hr:  # (all junctions at once: each one's samples, their distances to its node)
        pieces = [[regions[r], *(live[ci].ids for ci, _ in inc_at[r])] for r in hr]
        sizes = np.array([sum(len(x) for x in pc) for pc in pieces], dtype=np.int64)
        near = np.concatenate([x for pc in pieces for x in pc]).astype(np.int64)
        at = np.repeat(np.array([jpos[r] for r in hr], dtype=np.int64), sizes)
        gap = np.minimum.reduceat(np.linalg.norm(P[near] - JX[at], axis=1), np.r_[0, np.cumsum(sizes)[:-1]])
        hl = group_medians(h[np.concatenate([regions[r] for r in hr])], [len(regions[r]) for r in hr])
        for r, g, hk in zip(hr, gap.tolist(), hl.tolist()):
            if g > NODES.off_region * hk + NODES.off_noise * sc.noise:
                off.append(r)
                hl_of[r] = hk
    ends = {r: [int(live[ci].ids[-1 if s == 1 else 0]) for ci, s in inc_at[r]] for r in off}
    for r, q in zip(off, median_points(P, h, prm.link, [(ends[r], regions[r]) for r in off])):
        if q is not None and (not sc.clean or np.max(np.linalg.norm(P[ends[r]] - P[q], axis=1))
                              > prm.shell_outer * (hl_of[r] + SHELL.widen * sc.noise)):
            JX[jpos[r]] = P[q]
    # the region paths of all free ends that may hide a fork, in one call
    fr = [r for r in range(len(regions)) if v[r] == 1]
    fids = {}
    for r in fr:
        ci, s = inc_at[r][0]
        fids[r] = live[ci].ids if s == 1 else live[ci].ids[::-1]  # ids run towards the region
    fr = [r for r in fr if fork_possible(P, sc, prm, fids[r], regions[r])]
    fpaths = dict(zip(fr, region_paths(P, sc, [(regions[r], int(fids[r][-1])) for r in fr])))
    # where the region alone shows no fork, its chain's last samples may hold the fork's
    # junction (a twig the shell test saw too short, its tip and its sibling's in the region):
    # the region and that tail, searched from the sample before the tail (read on demand);
    # the node placed by _tail_fork_node
    tails = {r: _fork_tail(P, sc, prm, fids[r], regions[r]) for r in fr}
    fm = dict(zip(fids, end_counts(P, h, list(fids.values()), NODES.free_span).tolist()))  # free_end's
    bent: list = []  # the free ends whose region may bend: (node, chain end, entry, region, ext)
    for r in range(len(regions)):
        if v[r] == 0:
            continue
        inc = inc_at[r]
        if v[r] == 1:
            ci, s = inc[0]
            ids = fids[r]
            fork = hidden_fork(P, sc, prm, ids, regions[r], fpaths[r]) if r in fpaths else None
            if fork is None and tails.get(r, 0):
                n = tails[r]
                rid = np.r_[ids[-n:], regions[r]]
                fork = hidden_fork(P, sc, prm, ids[:-n], rid, region_paths(P, sc, [(rid, int(ids[-n - 1]))])[0])
                if fork is not None:  # the chain ends before its tail (the tail's samples: the fork's)
                    fork = (fork[0], _tail_fork_node(P, sc, prm, ids[:-n], ids[-n:], *fork), fork[2])
                    c = live[ci]
                    live[ci] = Chain(c.ids[:-n] if s == 1 else c.ids[n:], c.ends, c.closed)
            if fork is not None:
                # a whole fork (junction and two short free branches) inside one free end's
                # region (sparse sampling): a junction node and two free branches
                ext, pos, leaves = fork
                end_ext[(ci, s)] = ext
                node_pos.append(pos)
                extra.extend((len(node_pos) - 1, lf) for lf in leaves)
                node_of[r] = len(node_pos) - 1
                continue
            ext, pos = free_end(P, h, ids, regions[r], m=fm[r])
            if len(regions[r]) >= NODES.fork_min_points:
                bent.append((len(node_pos), (ci, s), ids[-1], regions[r], ext))
            end_ext[(ci, s)] = ext
            node_pos.append(pos)
        else:
            node_pos.append(JX[jpos[r]])
            if JMAYBE[jpos[r]]:
                for br in swallowed_branches(P, sc, prm, live, inc, regions[r], node_pos[-1]):
                    extra.append((len(node_pos) - 1, br))
        node_of[r] = len(node_pos) - 1
    for (j, end, _, _, _), tip in zip(bent, bent_tips(P, h, prm.link, sc.noise, prm.shell_outer,
                                                    [(e, rid, node_pos[j], ext) for j, _, e, rid, ext in bent])):
        if tip is not None:
            end_ext[end], node_pos[j] = tip
    # a short free branch lying wholly inside its junction's region (sparse sampling: its
    # length is under the shell radius) gets its own curve to a free end at its tip
    extra_ids = []
    for j, br in extra:
        node_pos.append(P[br[-1]])
        extra_ids.append((j, len(node_pos) - 1, br))
    nodes = np.asarray(node_pos, dtype=float).reshape(-1, dim)
    # canonical node order (by coordinates)
    new_id = np.zeros(0, dtype=np.int64)
    if len(nodes):
        norder = np.lexsort(np.round(nodes, CURVES.round_decimals).T[::-1])
        new_id = np.empty(len(norder), dtype=np.int64)
        new_id[norder] = np.arange(len(norder))
        nodes = nodes[norder]
    return Placement(nodes, new_id, node_of, end_ext, extra_ids, live, v)


def _fork_tail(P, sc: Scales, prm: RobustParams, ids, rid) -> int:
    """How many of the last samples of the chain ``ids`` (running towards the free end's region
    ``rid``) lie within one outer shell radius of its last sample: where a fork's junction may
    hide when its region shows none (:func:`.junctions.hidden_fork` on the region and those
    samples). 0 when the chain holds no sample beyond them."""
    hs = float(np.median(sc.h[rid])) + SHELL.widen * sc.noise
    d = np.linalg.norm(P[ids] - P[int(ids[-1])], axis=1)
    far = np.flatnonzero(d > prm.shell_outer * hs)
    if not len(far):
        return 0
    return int(len(ids) - 1 - far[-1])


def _tail_fork_node(P, sc: Scales, prm: RobustParams, stem, tail, ext, x, leaves) -> np.ndarray:
    """The node of a fork found on a chain's tail (:func:`_fork_tail`): the least-squares meeting
    point of the lines of its three branches, each fitted on its end portion at the fork as
    :func:`.junctions.hidden_fork` fits them, the stem's on the chain ``stem`` with ``ext`` and the
    tail's samples on neither leaf (the parent curve's last samples, which the paths from the
    entry skip), held near where the two leaves start (their first samples' mean) instead of
    the paths' parting point, which under noise lies back at the entry. ``x``: the node
    hidden_fork placed (kept where the lines meet off the shell)."""
    h = sc.h
    on_leaf = np.isin(tail, np.concatenate([np.asarray(lf) for lf in leaves] + [np.asarray(ext, dtype=np.int64)]))
    anchor = np.mean([P[int(lf[0])] for lf in leaves], axis=0)
    rest = tail[~on_leaf]
    rest = rest[np.argsort(-np.linalg.norm(P[rest] - anchor, axis=1), kind="stable")]  # farthest first
    branches = (np.r_[np.asarray(stem), np.asarray(ext, dtype=np.int64), rest], *(np.asarray(lf)[::-1] for lf in leaves))
    y = branches_meeting(P, sc, prm, branches, float(np.median(h[tail])), anchor)
    return x if y is None else y


def free_end(P, h, ids, rid, m=None):
    """Extension ids (ordered outward) and node position of a free end (``m``: the count of
    its end portion, when known)."""
    E = end_portion(P, h, ids, span=NODES.free_span, m=m)
    tip = E[0]
    if len(E) >= 2:
        u = E[0] - E[-1]
        nu = np.linalg.norm(u)
        u = u / nu if nu > 0 else None
    else:
        u = None
    if len(rid) == 0:
        return np.zeros(0, dtype=np.int64), tip
    R = P[rid]
    if u is None:
        u = R.mean(axis=0) - tip
        nu = np.linalg.norm(u)
        u = u / nu if nu > 0 else np.eye(P.shape[1])[0]
    proj = (R - tip) @ u
    o = np.lexsort((rid, proj))
    ext = rid[o]
    ext = ext[proj[o] > -NUMERIC.ahead] if (proj > -NUMERIC.ahead).any() else ext
    # drop points behind the tip (they belong to the chain's thickness), keep the rest in order
    if len(ext) == 0:
        return ext, tip
    return ext, P[ext[-1]].copy()


def bent_tips(P: np.ndarray, h: np.ndarray, link: float, noise: float, shell_outer: float,
              items: list) -> list:
    """Free ends whose region bends: the node at the point farthest along the region.

    :func:`free_end` places the node at the region point farthest ahead of the chain's end
    direction; where the region turns (a traced neurite's zigzag a few spacings before its
    tip) that point is the turn, and the tail beyond it is lost. Here the region's points are
    joined by steps of at most ``link`` spacings (the region's median; the chain's end joined
    to its nearest region point), and the point with the longest shortest path from the
    chain's end is the tip when: every region point reached lies within ``NODES.fork`` shell
    radii of that path (the region is one path: a second tip there is a fork, read by
    :func:`~.junctions.hidden_fork`, or left to it); the tip lies over ``NODES.bend`` spacings
    from the straight-ahead one; and the region holds a sample farther along than the
    straight-ahead tip per ``NODES.bend_step`` spacings of that distance (a lone outlier
    beyond the tip is no tail). All regions' shortest paths in one call. (Not the linked graph
    of :func:`~.junctions.region_paths`: at a sharp turn under noise the links break, and the
    tail is unreachable there.)

    Parameters
    ----------
    P : (N, d) ndarray
    h : (N,) ndarray
        Local spacing.
    link : float
        The longest step (spacings).
    noise : float
        The noise scale (the shell's widening).
    shell_outer : float
        The outer shell radius (spacings).
    items : list of (int, ndarray, (d,) ndarray, ndarray)
        Per free end: the chain's end point, the region's points, the straight-ahead node and
        its extension (:func:`free_end`).

    Returns
    -------
    list of (ndarray, (d,) ndarray) or None
        Per item, the extension (region points reached, ordered along the path lengths) and
        the node; None where the straight-ahead placement stands.
    """
    out: list = [None] * len(items)
    if not items:
        return out
    # the tip moves only to a region point over NODES.bend spacings from the straight-ahead
    # one and NODES.bend_off off the straight approach (the segment from the chain's end to
    # it, which the path would only run back along): the regions with none are left out first, at once
    flat = np.concatenate([rid for _, rid, _, _ in items]).astype(np.int64)
    lens = np.array([len(rid) for _, rid, _, _ in items], dtype=np.int64)
    gi = np.repeat(np.arange(len(items)), lens)
    hl = group_medians(h[flat], lens.tolist())
    a = P[np.array([e for e, _, _, _ in items], dtype=np.int64)][gi]
    b = np.array([pos for _, _, pos, _ in items])[gi]
    X = P[flat]
    off = segment_distance(X, a, b)
    far = (np.linalg.norm(X - b, axis=1) > NODES.bend * hl[gi]) & (off > NODES.bend_off * hl[gi])
    wide = np.flatnonzero(np.logical_or.reduceat(far, np.r_[0, np.cumsum(lens)[:-1]]))
    for k, tip in zip(wide.tolist(), _bent_tips(P, hl[wide], link, noise, shell_outer, [items[k] for k in wide])):
        out[k] = tip
    return out


def _bent_tips(P, hl, link, noise, shell_outer, items) -> list:
    """:func:`bent_tips` on the items that may move (its arguments and result, with ``hl`` the
    median spacing of each item's region instead of every point's)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    if not items:
        return []
    U = np.concatenate([np.r_[e, rid] for e, rid, _, _ in items]).astype(np.int64)
    sizes = np.array([1 + len(rid) for _, rid, _, _ in items], dtype=np.int64)
    start = np.r_[0, np.cumsum(sizes)[:-1]]
    grp = np.repeat(np.arange(len(items)), sizes)
    step = link * hl
    pa, pb = cKDTree(P[U]).query_pairs(float(step.max()), output_type="ndarray").T
    d = np.linalg.norm(P[U[pa]] - P[U[pb]], axis=1)
    keep = (grp[pa] == grp[pb]) & (d <= step[grp[pa]])
    pa, pb, d = pa[keep], pb[keep], d[keep]
    # each chain end joined to its region's nearest point, however far
    de = np.linalg.norm(P[U] - P[U[start[grp]]], axis=1)
    de[start] = np.inf
    near = np.array([s0 + 1 + int(np.argmin(de[s0 + 1:s0 + n])) for s0, n in zip(start.tolist(), sizes.tolist())])
    pa, pb, d = np.r_[pa, start], np.r_[pb, near], np.r_[d, de[near]]
    tiny = np.finfo(float).tiny  # (a zero length would be no edge)
    G = coo_matrix((d + tiny, (pa, pb)), shape=(len(U), len(U))).tocsr()
    g, pred, _ = dijkstra(G, directed=False, indices=start, min_only=True, return_predecessors=True)
    out = []
    for k, ((_, rid, pos, ext), s0, n) in enumerate(zip(items, start.tolist(), sizes.tolist())):
        gl = g[s0 + 1:s0 + n]
        reach = np.flatnonzero(np.isfinite(gl))
        if not len(reach):
            out.append(None)
            continue
        order = reach[np.argsort(gl[reach], kind="stable")]
        far = s0 + 1 + int(order[-1])
        path = [far]
        while path[-1] != s0:
            path.append(int(pred[path[-1]]))
        X = P[rid[reach]]
        off = np.min(np.linalg.norm(X[:, None] - P[U[path]][None], axis=2), axis=1)
        hs = hl[k] + SHELL.widen * noise
        moved = float(np.linalg.norm(P[U[far]] - pos))
        at = gl[np.flatnonzero(rid == ext[-1])[0]] if len(ext) else 0.0
        beyond = int(np.sum(gl[reach] > at))
        if (off.max() <= NODES.fork * shell_outer * hs and moved > NODES.bend * hl[k]
                and beyond >= moved / (NODES.bend_step * hl[k])):
            out.append((rid[order], P[U[far]].copy()))
        else:
            out.append(None)
    return out


def median_points(P: np.ndarray, h: np.ndarray, link: float, items: list) -> list:
    """Per junction, its region's point with the least sum of path lengths from its branches.

    The least-squares meeting point of the branches' lines (:func:`junction_positions`) can
    lie off the samples where a branch's line is read far from the junction (a region that
    runs 10 h out along a zigzag): there the node moves to the region point that the chain
    ends reach with the least summed length of shortest paths through the region's points
    (steps of at most ``link`` spacings, the region's median; each chain end joined to its
    region's nearest point). Along a tree of samples that point is where the branches meet.

    Parameters
    ----------
    P : (N, d) ndarray
    h : (N,) ndarray
        Local spacing.
    link : float
        The longest step (spacings).
    items : list of (list of int, ndarray)
        Per junction: its chain ends' points and its region's points.

    Returns
    -------
    list of int or None
        Per junction, the median point (None where no region point is reached from every
        chain end: a region in pieces farther apart than a step).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    out: list = []
    for ends, rid in items:
        ends = np.asarray(ends, dtype=np.int64)
        U = np.r_[ends, rid].astype(np.int64)
        k = len(ends)
        step = link * float(np.median(h[rid]))
        pa, pb = cKDTree(P[U]).query_pairs(step, output_type="ndarray").T
        d = np.linalg.norm(P[U[pa]] - P[U[pb]], axis=1)
        de = np.linalg.norm(P[rid][None] - P[ends][:, None], axis=2)
        near = k + np.argmin(de, axis=1)
        pa, pb = np.r_[pa, np.arange(k)], np.r_[pb, near]
        d = np.r_[d, de[np.arange(k), near - k]]
        G = coo_matrix((d + NUMERIC.tiny, (pa, pb)), shape=(len(U), len(U))).tocsr()
        D = dijkstra(G, directed=False, indices=np.arange(k))[:, k:]
        total = D.sum(axis=0)
        out.append(int(rid[np.argmin(total)]) if np.isfinite(total).any() else None)
    return out


def junction(P, sc: Scales, prm: RobustParams, live, inc, rid):
    """Node position of one junction: see :func:`junction_positions`."""
    return junction_positions(P, sc, prm, [(live, inc, rid)])[0][0]


def junction_positions(P, sc: Scales, prm: RobustParams, items):
    """Least-squares intersection of the tangent lines of the incident branches, per junction.

    ``items``: ``(chains, inc, rid)`` per junction, ``inc`` the (chain, side) ends at it and
    ``rid`` its region points. The branches are first walked into the junction region
    (:func:`kernels.nodes._extend_into_region`), a walk that strays from the branch's own line
    (onto another branch, led by noise) cut where it leaves a strip of ``NODES.walk_dev`` link widths
    around that line; the lines are then fitted close to the junction (over ``NODES.fit_span`` spacings, longer under
    noise: the fitted direction's error shrinks with the span) and extrapolated only a little.
    All junctions run in one compiled call (:func:`kernels.nodes._junction_nodes`).

    Returns
    -------
    X : (n_items, d) ndarray
        Node positions.
    maybe : (n_items,) ndarray of bool
        False where :func:`swallowed_branches` surely finds nothing.
    """
    h = sc.h
    dim = P.shape[1]
    if not items:
        return np.zeros((0, dim)), np.zeros(0, dtype=bool)
    branches, nb, rids, hfall = [], [], [], []
    for chains, inc, rid in items:
        for ci, s in inc:
            c = chains[ci]
            branches.append(c.ids if s == 1 else c.ids[::-1])
        nb.append(len(inc))
        rids.append(np.asarray(rid, dtype=np.int64))
        hfall.append(0.0 if len(rid) else float(np.median([h[chains[ci].ids[0]] for ci, _ in inc])))
    bflat = np.concatenate(branches).astype(np.int64, copy=False)
    boff = np.r_[0, np.cumsum([len(b) for b in branches])].astype(np.int64)
    jb = np.r_[0, np.cumsum(nb)].astype(np.int64)
    rflat = np.concatenate(rids).astype(np.int64, copy=False)
    rlen = np.array([len(r) for r in rids], dtype=np.int64)
    grp = np.repeat(np.arange(len(rids)), rlen)
    # each junction's spacing: the median of h over its region points, all junctions at once
    hj = np.asarray(hfall, dtype=np.float64)
    has = rlen > 0
    hj[has] = group_medians(h[rflat], rlen)[has]
    # region points sorted and unique per junction
    o = np.lexsort((rflat, grp))
    rs, gs = rflat[o], grp[o]
    first = np.ones(len(rs), dtype=bool)
    first[1:] = (rs[1:] != rs[:-1]) | (gs[1:] != gs[:-1])
    rflat = rs[first]
    roff = np.r_[0, np.cumsum(np.bincount(gs[first], minlength=len(rids)))].astype(np.int64)
    noise = float(sc.noise)
    consts = _k.JunctionParams(NODES.fit_span, NODES.fit_noise, NODES.walk_dev, LINKS.strip_noise, NODES.walk_far,
                               NODES.swallow * prm.shell_outer, NODES.swallow_cos, SHELL.widen, True)
    X, maybe = _k.junction_nodes(P, np.ascontiguousarray(h, dtype=np.float64), sc.indptr, sc.indices,
                                 bflat, boff, jb, rflat, roff, hj, float(sc.width), noise, consts)
    return X, maybe
