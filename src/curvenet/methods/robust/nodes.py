"""Stage 7: node placement: where each junction and free end sits.

A region touched by one chain end is a free end: its points extend the chain and the node is
the extreme point (:func:`free_end`), unless the region hides a whole fork
(:func:`~.junctions.hidden_fork`). A region touched by 3 or more ends is a junction: every
incident branch is walked into the region, its line is fitted on its last
``NODES.fit_span h + NODES.fit_noise noise``, and the node is the least-squares intersection of
those lines (:func:`junction_positions`, one compiled call for all junctions).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import kernels as _k
from .chains import Chain, end_counts, end_portion, group_medians
from .junctions import fork_possible, hidden_fork, region_paths, swallowed_branches
from .params import RobustParams, Scales
from .thresholds import CURVES, LINKS, NODES, NUMERIC, SHELL
from .topology import Topology

__all__ = ["Placement", "place_nodes", "free_end", "junction", "junction_positions"]


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
    # the region paths of all free ends that may hide a fork, in one call
    fr = [r for r in range(len(regions)) if v[r] == 1]
    fids = {}
    for r in fr:
        ci, s = inc_at[r][0]
        fids[r] = live[ci].ids if s == 1 else live[ci].ids[::-1]  # ids run towards the region
    fr = [r for r in fr if fork_possible(P, sc, prm, fids[r], regions[r])]
    fpaths = dict(zip(fr, region_paths(P, sc, [(regions[r], int(fids[r][-1])) for r in fr])))
    fm = dict(zip(fids, end_counts(P, h, list(fids.values()), NODES.free_span).tolist()))  # free_end's
    for r in range(len(regions)):
        if v[r] == 0:
            continue
        inc = inc_at[r]
        if v[r] == 1:
            ci, s = inc[0]
            ids = fids[r]
            fork = hidden_fork(P, sc, prm, ids, regions[r], fpaths[r]) if r in fpaths else None
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
            end_ext[(ci, s)] = ext
            node_pos.append(pos)
        else:
            node_pos.append(JX[jpos[r]])
            if JMAYBE[jpos[r]]:
                for br in swallowed_branches(P, sc, prm, live, inc, regions[r], node_pos[-1]):
                    extra.append((len(node_pos) - 1, br))
        node_of[r] = len(node_pos) - 1
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
