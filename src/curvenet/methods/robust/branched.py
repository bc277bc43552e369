"""A junction the shell test missed, found where a chain branches.

A chain is a connected run of points outside every region, ordered by its distance along the
linked graph from one end (:func:`.chains.order_chains`): it is one curve segment only when the
run is a path. Where the shell test misses a junction (a comb's tooth 3 h from the next, a twig
of 3 h leaving a fork whose shell barely reaches its tip) the run is a tree: its points ordered
by distance jump from one branch to another (consecutive points over ``BRANCHED.jump`` spacings
apart, plus the noise), and the curve traced through it zigzags back and forth.

:func:`split_branched_chains` reads such a chain from the minimum spanning tree of its points,
pruned as :func:`.spanning.pruned_tree` prunes it (leaf branches under ``SPANNING.prune``
spacings plus twice the noise cut: what noise hangs off a curve; a point linked to a region is
never cut: a branch of one sample may be all that joins the next junction). The tree of the
points near the jumps (``BRANCHED.window``) is read first, the whole chain's only where it
shows a junction. Two junctions of the tree joined by a tree edge, no sample between them, are
one (:func:`_joined_cores`: a junction of many branches spread over two tree vertices, as a
roof's apex under noise; read as two, the chain was left whole). When the whole tree shows exactly one junction
(:func:`.spanning.tree_cores`: its vertices of three or more branches, clustered, whose branches
leave apart) and its branches are paths, the chain becomes that junction (a new region of its
vertices) and one chain per branch, ordered from the junction outwards
(:meth:`.topology.Topology.branch_chain`). Each branch ends at the region its last
``BRANCHED.tip_points`` points are most linked to, when its last point lies within
``BRANCHED.reach`` spacings of it (the next sample); the branches holding the chain's two ends
may keep the chain's regions there. A tree of two or more junctions is read too
(:func:`cores_plan`): each piece of the tree between two of them (a path) becomes a chain joining
them, the branches leaving end as above (a chain that ran past a building notch's ground corner
and on up its vertical past the eave corner; rungs of a ladder, teeth of a comb 3-5 h apart
that a chain runs past under noise). The whole chain's tree has its cycles closed
(:func:`.spanning.loop_closures`, as a region's tree has them; 7 December 2026): a chain that
ran round a cell of the network (a ladder's two rails and two rungs under noise, a facade's
window) lost a side of each cell in its spanning tree, the side's halves were pruned as leaf
branches, and the cell's corners showed no junction. It was read on noise-free input only until 4 December
2026; at every noise (A/B, issue 25): 7 of 992 networks changed, 6 better (kinds at noise
0.2 h and 0.3 h + x3: ladder 0.28 -> 0.51, 0.13 -> 0.31, 0.46 -> 0.69; comb 0.61 -> 0.87,
0.20 -> 0.47; twigs 0.13 -> 0.22), 1 worse (twigs 0.30 -> 0.29); the synthetic models, CASSIE
and real-dev the same. A branch of the one-junction reading that
reaches no region is a free branch, its tip a new free end, when it is a sampled curve of
``min_spur`` spacings or more (on noisy input, or as long as stage 9's twig:
:func:`_free_branch`; a twig a few spacings from a junction under noise, whose tip no shell saw
as an end). Left as it is: a chain with a shorter or sparser
branch that reaches no region (noise at a sharp corner hangs such a branch of a few samples: the
synthetic corners under noise 0.3h + x3 lost an exact network to it), or with two branches into
one region (a chain's end widened by noise where it enters a junction), unless the two are
curves apart (:func:`_pieces_apart`: each ``min_spur`` spacings long or more, over
``BRANCHED.twin_apart`` spacings apart somewhere) and the junction's other branches curves too
(:func:`_ragged_end`): a double edge, as a ladder's end rung beside its rail's rounded end. Read so since 6 December 2026 (the ladder kind under noise 0.2 h: its
ends' chains, each through a missed junction, were left whole; with the second pass of
:func:`.spanning.split_multiple_junctions` after this repair, 928-run harness 10 better, 0 worse).
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
from scipy.spatial import cKDTree

from .chains import flat_steps, group_medians, points_apart, polylen
from .graph import components, csr_edges
from .params import RobustParams, Scales
from .spanning import core_order, prune_cut, pruned_tree, pruned_trees, split_multiple_junctions, tree_cores
from .thresholds import BRANCHED, LINKS, NODES, UNEXPLAINED
from .topology import Topology
from .unexplained import free_reach, leaves, twig_reach

__all__ = ["split_branched_chains", "branch_plan", "orphan_twigs"]


def _jump(hl: float, noise: float) -> float:
    """The step between consecutive chain points over which a chain is read: ``BRANCHED.jump``
    spacings ``hl`` plus ``BRANCHED.jump_noise`` times the noise."""
    return BRANCHED.jump * hl + BRANCHED.jump_noise * noise


def _reach(hl: float, noise: float) -> float:
    """How near a region a branch's last point lies when it ends there: ``BRANCHED.reach``
    spacings ``hl`` plus ``BRANCHED.reach_noise`` times the noise."""
    return BRANCHED.reach * hl + BRANCHED.reach_noise * noise


def _arms(adj: list[set], core: set) -> list[list[int]]:
    """The branches of the tree ``adj`` at the vertex set ``core``: per branch its vertices in
    order from the core outwards (breadth first; a branch that forks again is returned as it is
    reached, so the caller checks it is a path)."""
    out = []
    seen = set(core)
    for c in sorted(core):
        for s in sorted(adj[c]):
            if s in seen:
                continue
            arm, frontier = [], [s]
            seen.add(s)
            while frontier:
                u = frontier.pop(0)
                arm.append(u)
                for w in sorted(adj[u]):
                    if w not in seen:
                        seen.add(w)
                        frontier.append(w)
            out.append(arm)
    return out


def branch_plan(X: np.ndarray, hl: float, noise: float, keep: np.ndarray, adj: list[set] | None = None):
    """How the points ``X`` (n, d) of one chain split at one junction.

    Parameters
    ----------
    X : (n, d) ndarray
    hl : float
        The chain's spacing.
    noise : float
    keep : (n,) ndarray of bool
        Points linked to a region: a leaf there is a branch reaching that region, never cut.
    adj : list of set, optional
        The pruned tree of ``X`` (:func:`.spanning.pruned_tree` with these arguments), when
        already built.

    Returns
    -------
    (core, arms) or None
        ``core``: the junction's vertices (indices into ``X``); ``arms``: per branch its
        vertices ordered from the junction outwards (paths of the pruned tree, three or more).
        None unless the pruned tree shows exactly one junction and its branches are paths.
    """
    adj = pruned_tree(X, prune_cut(hl, noise), keep) if adj is None else adj
    cores = _joined_cores(X, adj, hl, noise, 1)
    if len(cores) != 1:
        return None
    core = set(cores[0])
    arms = _arms(adj, core)
    if len(arms) < NODES.junction_valence:
        return None
    for arm in arms:  # each a path: every vertex has at most two tree neighbours in its arm
        inarm = set(arm)
        if any(len(adj[u] & inarm) > 2 for u in arm):
            return None
    return sorted(core), arms


def _joined_cores(X: np.ndarray, adj: list[set], hl: float, noise: float, min_cores: int) -> list[list[int]]:
    """The junctions of the pruned tree ``adj`` of the points ``X`` (:func:`.spanning.tree_cores`
    over every point, at least ``min_cores`` of them), two joined by a tree edge taken as one: no
    piece of curve lies between them (a junction of many branches spread over two tree vertices
    a cluster radius or more apart, as a roof's apex under noise). Each as its vertices, the one
    nearest their mean first."""
    cores = tree_cores(X, adj, np.ones(len(X), dtype=bool), hl, noise, min_cores)
    if len(cores) < 2:
        return cores
    core_of = {v: k for k, mem in enumerate(cores) for v in mem}
    pairs = [(k, core_of[w]) for k, mem in enumerate(cores) for v in mem for w in adj[v]
             if w in core_of and core_of[w] != k]
    if not pairs:
        return cores
    pa, pb = np.array(pairs, dtype=np.int64).T
    lab, n = components(len(cores), pa, pb, np.ones(len(cores), dtype=bool))
    out = []
    for g in range(n):
        mem = np.asarray(sorted(v for k in np.flatnonzero(lab == g).tolist() for v in cores[k]), dtype=np.int64)
        out.append(core_order(X, mem))
    return out


def cores_plan(X: np.ndarray, hl: float, noise: float, keep: np.ndarray, adj: list[set] | None = None):
    """How the points ``X`` (n, d) of one chain split at two or more junctions (the same tree
    as :func:`branch_plan`, which reads one; its arguments are that function's).

    Returns
    -------
    (cores, pieces) or None
        ``cores``: per junction its vertices (indices into ``X``); ``pieces``: per piece of the
        tree between them ``(vertices, a, b)``, the vertices a path ordered from core ``a``,
        ``b`` the core at its other end or -1 (a branch leaving). None unless the tree shows two
        or more junctions, every piece is a path touching one or two of them (at its ends), and
        every junction has three or more pieces.
    """
    adj = pruned_tree(X, prune_cut(hl, noise), keep) if adj is None else adj
    cores = _joined_cores(X, adj, hl, noise, 2)
    if len(cores) < 2:
        return None
    core_of = {v: k for k, mem in enumerate(cores) for v in mem}
    seen = set(core_of)
    pieces = []
    for k, mem in enumerate(cores):
        for c in sorted(mem):
            for s in sorted(adj[c]):
                if s in seen:
                    if s in core_of and core_of[s] != k:
                        return None  # two cores joined by a tree edge: no piece between them
                    continue
                path, prev, u = [], c, s
                while True:  # walk the path away from the core
                    path.append(u)
                    seen.add(u)
                    nxt = [w for w in sorted(adj[u]) if w != prev]
                    if len(nxt) > 1:
                        return None  # a branching piece: a junction not read as a core
                    if not nxt:
                        pieces.append((path, k, -1))
                        break
                    w = nxt[0]
                    if w in core_of:
                        if core_of[w] == k:
                            return None  # a piece that comes back to its own core: a loop
                        pieces.append((path, k, core_of[w]))
                        break
                    prev, u = u, w
    val = np.zeros(len(cores), dtype=np.int64)
    for _, a, b in pieces:
        val[a] += 1
        if b >= 0:
            val[b] += 1
    if val.min() < NODES.junction_valence:
        return None
    return [sorted(mem) for mem in cores], pieces


def _jump_window(X: np.ndarray, hl: float, noise: float, keep: np.ndarray):
    """The chain's points near its jumps (within ``BRANCHED.window`` spacings plus the noise of
    a jump's two points), whose pruned tree :func:`_near_jump_branches` reads: their mask and
    the points kept from the cut (``keep`` and those near the window's edge, where the chain
    goes on). None when every point of the chain is near a jump."""
    step = np.linalg.norm(np.diff(X, axis=0), axis=1)
    at = np.flatnonzero(step > _jump(hl, noise))
    ends = X[np.unique(np.r_[at, at + 1])]
    d = np.min(np.linalg.norm(X[:, None, :] - ends[None, :, :], axis=2), axis=1)
    w = BRANCHED.window * hl + noise
    inw = d <= w
    if inw.all():
        return None
    return inw, keep[inw] | (d[inw] > w - _reach(hl, noise))


def _near_jump_branches(Y: np.ndarray, adj: list[set], hl: float, noise: float) -> bool:
    """Whether the pruned tree ``adj`` of the chain's points ``Y`` near its jumps
    (:func:`_jump_window`) shows a junction: the cheap test before the whole chain's tree (a
    long chain under noise jumps where the noise widens it, most often without a branch)."""
    return len(tree_cores(Y, adj, np.ones(len(Y), dtype=bool), hl, noise, 1)) > 0


def _region_of(topo: Topology) -> np.ndarray:
    """The region of every point (N,) of the topology, -1 where none."""
    region_of = np.full(len(topo.P), -1, dtype=np.int64)
    for r, ids in enumerate(topo.regions):
        region_of[ids] = r
    return region_of


def _links(sc: Scales, region_of: np.ndarray, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every link of the points ``ids``: the position in ``ids`` of its point and the region
    (``region_of``, :func:`_region_of`) of its other point (-1: none)."""
    _, nb = csr_edges(sc.indptr, sc.indices, ids)
    return np.repeat(np.arange(len(ids)), sc.indptr[ids + 1] - sc.indptr[ids]), region_of[nb]


def _ordered_from(P: np.ndarray, ids: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The point ids ``ids`` ordered by their distance from ``x`` (ties: the lowest id first)."""
    return ids[np.lexsort((ids, np.linalg.norm(P[ids] - x, axis=1)))]


def _orphans(topo: Topology) -> list[int]:
    """The regions with points where no chain end was ever listed (*orphans*: flagged points the
    tracer left without a chain)."""
    return [r for r in range(len(topo.regions)) if topo.v[r] == 0 and len(topo.regions[r]) and not topo.listed(r)]


def _orphan_points(topo: Topology, orphans: list[int]) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The points of the regions ``orphans``, region by region, the orphan of each point and
    each orphan's number of points."""
    sizes = [len(topo.regions[r]) for r in orphans]
    ids = np.concatenate([topo.regions[r] for r in orphans]) if orphans else np.zeros(0, dtype=np.int64)
    return ids, np.repeat(np.asarray(orphans, dtype=np.int64), sizes), sizes


def _orphan_reach(prm: RobustParams, hl: float, noise: float) -> float:
    """How near a point an orphan lies to continue a curve there: the link length in spacings
    ``hl``, plus ``LINKS.gap_noise`` times the noise."""
    return prm.link * hl + LINKS.gap_noise * noise


def _tail_twig(topo: Topology, sc: Scales, prm: RobustParams, i: int, side: int, region_of: np.ndarray,
               nearest_orphan) -> tuple[int, int]:
    """Where the chain ``i`` forks at its end ``side`` (0: its first point, 1: its last): the
    position in its ids of the last point (counted from that end) linked to the free end's
    region there, when the points past it (the *tail*) and the region's points are two twigs:
    each, with that point, at least ``UNEXPLAINED.min_samples`` samples, and the tip of each
    (the tail's point farthest from the fork; the region's) more than
    ``UNEXPLAINED.explain`` spacings plus ``UNEXPLAINED.explain_noise`` times the noise from
    the chain's points before the fork and from the other twig, and at least ``UNEXPLAINED.rise``
    times its distance from the fork; and the orphan the tail runs on into, -1 when none. Where
    the tail alone is no twig, it runs on into the orphan nearest its last point within
    :func:`_orphan_reach` (``nearest_orphan(point, reach)``: the twig's last samples, whose links
    noise cut), when the two together are one. ``(-1, -1)`` otherwise."""
    P, r = topo.P, topo.chains[i].ends[side]
    rid = topo.regions[r]
    if len(rid) + 1 < UNEXPLAINED.min_samples:
        return -1, -1
    ids = topo.end_ids(i, side)  # the end at the region last
    own, rr = _links(sc, region_of, ids)
    at = own[rr == r]  # positions linked to the region
    if not len(at):
        return -1, -1
    k = int(at.max())
    head, tail = ids[:k], ids[k:]  # (the tail with the fork's point)
    if not len(head):
        return -1, -1
    fork = P[ids[k]]
    hl = float(np.median(sc.h[tail]))

    def twigs(tail: np.ndarray) -> bool:
        if len(tail) < UNEXPLAINED.min_samples:
            return False
        for twig, other in ((tail, rid), (rid, tail)):
            tip = P[twig[np.argmax(np.linalg.norm(P[twig] - fork, axis=1))]]
            off = float(np.min(np.linalg.norm(P[np.r_[head, other]] - tip, axis=1)))
            if not leaves(off, float(np.linalg.norm(tip - fork)), hl, sc.noise):
                return False
        return True

    at_end = k if side == 1 else len(ids) - 1 - k
    if twigs(tail):
        return at_end, -1
    o = nearest_orphan(P[ids[-1]], _orphan_reach(prm, hl, sc.noise))
    if o >= 0 and twigs(np.r_[tail, topo.regions[o]]):
        return at_end, o
    return -1, -1


def split_tails(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Under noise, every open chain that runs on past the region at one of its ends into a
    twig (:func:`_tail_twig`) branches there: the last point linked to that region (a free
    end) becomes a junction, joined to the chain's other end by the chain's points before it, to
    a new free end by the tail, and to that free end by the region's points (the other twig's
    samples, ordered from the junction; the region keeps its chain end, without points). Where
    the tail runs on into an orphan (the twig's last samples, whose links noise cut), the tail's
    chain takes the orphan's points (ordered from the tail's last point) and ends at the orphan
    instead of a new free end. Read first by :func:`split_branched_chains`, again after
    :func:`.repairs.prune_spurs` (a region that a dropped spur leaves a free end).

    The failure: a terminal fork of two twigs (3-7 h, 40-60 degrees apart) under noise. The
    shell test misses the fork; one twig's samples form the region of a free end, and the chain
    traced up the parent runs on up the other twig to its tip. Its end region is read from its
    links within a few spacings of its end (:func:`.chains.order_chains`), so the chain ends at
    the first twig's region while its last points run up the second twig: the curve built from
    it zigzags up one twig and back to the other, and a node is lost.
    """
    if sc.clean:
        return
    region_of = _region_of(topo)
    opts, of, _ = _orphan_points(topo, _orphans(topo))
    otree = cKDTree(topo.P[opts]) if len(opts) else None

    def nearest_orphan(x: np.ndarray, reach: float) -> int:
        """The orphan with a point nearest ``x`` within ``reach`` (ties: the lowest), among those
        that still hold their points; -1 when none."""
        if otree is None:
            return -1
        hits = np.asarray(otree.query_ball_point(x, reach), dtype=np.int64)
        live = [(float(np.linalg.norm(topo.P[opts[k]] - x)), int(of[k])) for k in hits.tolist()
                if len(topo.regions[of[k]])]
        return min(live)[1] if live else -1

    for i in range(len(topo.chains)):
        c = topo.chains[i]
        if not topo.alive[i] or c.closed or len(c.ids) < BRANCHED.min_points:
            continue
        for side in (1, 0):
            b = c.ends[side]
            if b < 0 or topo.v[b] != 1 or c.ends[1 - side] == b:
                continue
            k, o = _tail_twig(topo, sc, prm, i, side, region_of, nearest_orphan)
            if k < 0:
                continue
            if side == 1:
                head, tail = c.ids[:k][::-1], c.ids[k + 1:]
            else:
                head, tail = c.ids[k + 1:], c.ids[:k][::-1]
            a, core = c.ends[1 - side], c.ids[k:k + 1]
            if o >= 0:  # the tail runs on into the orphan: its points, ordered from the tail's last
                oid = topo.release(o)
                region_of[oid] = -1
                last = tail[-1] if len(tail) else core[0]
                tail = np.r_[tail, _ordered_from(topo.P, oid, topo.P[last])]
            other = topo.release(b)  # the other twig's samples, ordered from the fork
            region_of[other] = -1
            other = _ordered_from(topo.P, other, topo.P[core])
            region_of[core] = topo.branch_chain(i, core, [head, tail, other], [a, o, b])
            break


def split_branched_chains(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Under noise, an open chain that runs on past the free end at one of its ends into a twig
    first branches where that free end's samples link to it (:func:`split_tails`). Every open
    chain whose points, in order, jump by over ``BRANCHED.jump`` spacings (plus
    the noise) and whose spanning tree shows one junction (:func:`branch_plan`) becomes that
    junction and one chain per branch (:meth:`.topology.Topology.branch_chain`); a tree of
    two or more junctions is split at each (:func:`_split_at_cores`), the whole chain's tree
    with the cycles of the cells it runs round closed (:func:`.spanning.loop_closures`). A chain that neither
    split touched and that runs past a region no chain ends at branches into it when the two
    make one junction (:func:`orphan_twigs`). The regions the split chains' branches reached
    are then read again by :func:`.spanning.split_multiple_junctions` (a rail's region, joined
    to the rungs only now)."""
    first = len(topo.chains)  # (the chains before any split here)
    split_tails(topo, sc, prm)
    reached = _split_jumping(topo, sc, prm)
    reached |= orphan_twigs(topo, sc, prm, first)
    if reached:  # a row's region now joined to the branches a chain ran past: read it again
        split_multiple_junctions(topo, sc, prm, only=reached)


def _linked_region(sc: Scales, region_of: np.ndarray, ids: np.ndarray) -> int:
    """The region most linked to the points ``ids`` (``region_of``: :func:`_region_of`; ties:
    the lowest; -1: none)."""
    rr = _links(sc, region_of, ids)[1]
    rr = rr[rr >= 0]
    return int(np.bincount(rr).argmax()) if len(rr) else -1


def _linked_to_a_region(sc: Scales, region_of: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """Per point of ``ids``: whether it is linked to a region point."""
    own, rr = _links(sc, region_of, ids)
    out = np.zeros(len(ids), dtype=bool)
    out[own[rr >= 0]] = True
    return out


def _split_jumping(topo: Topology, sc: Scales, prm: RobustParams) -> set:
    """The chains that jump split where their trees show junctions (see
    :func:`split_branched_chains`); returns the regions their branches reached."""
    P, h = topo.P, sc.h
    # the chains' largest steps and spacings, all at once
    idx = [i for i, c in enumerate(topo.chains)
           if topo.alive[i] and not c.closed and len(c.ids) >= BRANCHED.min_points]
    if not idx:
        return set()
    flat, off, step = flat_steps(P, [topo.chains[i].ids for i in idx])
    hl = group_medians(h[flat], np.diff(off))
    jumps = np.maximum.reduceat(step, off[:-1]) > _jump(hl, sc.noise)
    cand = [(idx[j], float(hl[j])) for j in np.flatnonzero(jumps).tolist()]
    if not cand:
        return set()
    region_of = _region_of(topo)
    linked_region = functools.partial(_linked_region, sc, region_of)

    # the trees of every candidate at once (one sparse-graph call for all the windows, one for
    # the whole chains whose window shows a junction): the candidates are distinct chains, and
    # splitting one leaves the others' points as they are
    Xs = [P[topo.chains[i].ids] for i, _ in cand]
    keeps = [_linked_to_a_region(sc, region_of, topo.chains[i].ids) for i, _ in cand]
    wins = [_jump_window(X, hl, sc.noise, keep) for X, keep, (_, hl) in zip(Xs, keeps, cand)]
    looked = [j for j, w in enumerate(wins) if w is not None]
    wtrees = pruned_trees([Xs[j][wins[j][0]] for j in looked], [prune_cut(cand[j][1], sc.noise) for j in looked],
                          [wins[j][1] for j in looked])
    near = {j: _near_jump_branches(Xs[j][wins[j][0]], adj, cand[j][1], sc.noise) for j, adj in zip(looked, wtrees)}
    whole = [j for j in range(len(cand)) if near.get(j, True)]
    trees = dict(zip(whole, pruned_trees([Xs[j] for j in whole], [prune_cut(cand[j][1], sc.noise) for j in whole],
                                         [keeps[j] for j in whole],
                                         closes=[(cand[j][1], sc.noise) for j in whole])))
    reached: set = set()  # the regions the split chains' branches end at
    for j, (i, hl) in enumerate(cand):
        if j not in trees:
            continue
        c, X, keep, adj = topo.chains[i], Xs[j], keeps[j], trees[j]
        plan = branch_plan(X, hl, sc.noise, keep, adj)
        if plan is None:  # (two or more junctions: read at any noise, see the module's notes)
            reached |= _split_at_cores(topo, sc, prm, i, c, X, hl, keep, adj, linked_region)
            continue
        core, arms = plan
        far = []
        for arm in arms:
            f = _branch_end(topo, sc, c, arm, hl, linked_region)
            if f < 0 and not _free_branch(X, core, arm, arms, hl, prm, 0.0 if sc.clean else sc.noise):
                break  # a branch that reaches no region, too short or too sparse to be a curve
            far.append(f)  # (-1: a free branch, its tip a new free end)
        else:
            branches = [(c.ids[np.asarray(arm)], f) for arm, f in zip(arms, far)]
            if not _ragged_end(topo, branches, hl, sc.noise, prm.min_spur):
                reached |= {f for f in far if f >= 0}
                topo.branch_chain(i, c.ids[core], [c.ids[np.asarray(arm)] for arm in arms], far)
    return reached


def _orphans_beside(topo: Topology, sc: Scales, prm: RobustParams, first: int) -> dict:
    """Per open chain among the first ``first`` chains, still live, with
    ``BRANCHED.min_points`` points or more: the regions no chain end was ever listed at (an
    *orphan*: flagged points the tracer left without a chain) with a point within the link
    length (in the orphan's spacing, plus ``LINKS.gap_noise`` times the noise) of one of its
    points. Only chains beside exactly one orphan are returned: ``{chain: orphan}``."""
    orphans = _orphans(topo)
    if not orphans:
        return {}
    owner, _ = topo.owners()
    for i in range(first, len(topo.chains)):  # (chains made by the splits: not read here)
        owner[topo.chains[i].ids] = -1
    ids, of, sizes = _orphan_points(topo, orphans)
    reach = _orphan_reach(prm, group_medians(sc.h[ids], sizes), sc.noise)
    near = sc.tree.query_ball_point(topo.P[ids], np.repeat(reach, sizes))
    beside: dict = {}
    for r, hits in zip(of.tolist(), near):
        for i in set(owner[np.asarray(hits, dtype=np.int64)].tolist()) - {-1}:
            c = topo.chains[i]
            if not c.closed and len(c.ids) >= BRANCHED.min_points:
                beside.setdefault(i, set()).add(r)
    return {i: next(iter(rs)) for i, rs in sorted(beside.items()) if len(rs) == 1}


def orphan_twigs(topo: Topology, sc: Scales, prm: RobustParams, first: int) -> set:
    """A chain that runs past a twig whose tip is an orphan region branches into it.

    The failure: a twig of 3-5 h leaving a branch under noise (noise 0.1-0.2 h). Noise cut
    the links of its last samples, so the shell test flagged them as a region of their own (a
    free end's points) but no chain ends there (an *orphan*, :func:`_orphans_beside`); the
    chain traced along the branch runs past the twig's junction and takes its first samples
    (its points in order zigzag onto the twig and back, or the twig's first sample hangs off
    it). Its own tree shows no junction: the twig's branch in it, one or two samples, is
    shorter than the cut of noise spurs (:func:`.spanning.prune_cut`). With the orphan's
    points in the tree (a leaf there never cut, as a point linked to a region), it does.

    Each open chain of the first ``first`` (those before the splits of
    :func:`split_branched_chains`; the ones the splits left whole) beside exactly one orphan is
    read as :func:`branch_plan` reads a chain, over its points and the orphan's: where the tree
    shows one junction of the chain's points whose branches are paths, one of them running
    into the orphan (the chain's samples first, then the orphan's only), the others ending as
    :func:`split_branched_chains` ends them, and the orphan's branch is a twig as stage 9 tells
    one (:mod:`.unexplained`): at least ``UNEXPLAINED.min_samples`` samples with the orphan's
    points, its farthest point from the junction ``min_spur - UNEXPLAINED.tip_short`` spacings
    plus ``UNEXPLAINED.length_noise`` times the noise away or more, the chain branches there
    (:meth:`.topology.Topology.branch_chain`): the twig's chain takes the orphan's points
    (ordered from the junction) and ends at the orphan, now a free end without points.

    Returns
    -------
    set
        The regions the other branches end at.
    """
    beside = _orphans_beside(topo, sc, prm, first)
    if not beside:
        return set()
    P = topo.P
    region_of = _region_of(topo)
    linked_region = functools.partial(_linked_region, sc, region_of)
    reached: set = set()
    for i, r in beside.items():
        c, oid = topo.chains[i], topo.regions[r]
        if not topo.alive[i] or not len(oid):  # (split, or taken by another chain, here)
            continue
        n = len(c.ids)
        hl = float(np.median(sc.h[c.ids]))
        X = np.r_[P[c.ids], P[oid]]
        keep = np.r_[_linked_to_a_region(sc, region_of, c.ids), np.ones(len(oid), dtype=bool)]
        plan = branch_plan(X, hl, sc.noise, keep)
        if plan is None or max(plan[0]) >= n:
            continue
        core, arms = plan
        twig = [k for k, arm in enumerate(arms) if arm[-1] >= n]
        if len(twig) != 1:
            continue
        t = twig[0]
        own = [q for q in arms[t] if q < n]
        if any(q >= n for q in arms[t][:len(own)]):
            continue  # (the twig's branch: the chain's samples, then the orphan's)
        tip = float(np.max(np.linalg.norm(P[oid] - X[np.asarray(core)].mean(axis=0), axis=1)))
        if len(arms[t]) < UNEXPLAINED.min_samples or tip < twig_reach(prm.min_spur, hl, sc.noise):
            continue
        far, ids = [], []
        for k, arm in enumerate(arms):
            if k == t:
                far.append(r)
                ids.append(c.ids[np.asarray(own, dtype=np.int64)])
                continue
            if any(q >= n for q in arm):
                break
            f = _branch_end(topo, sc, c, arm, hl, linked_region)
            if f < 0 and not _free_branch(X, core, arm, arms, hl, prm, 0.0 if sc.clean else sc.noise):
                break  # (as in split_branched_chains)
            far.append(f)
            ids.append(c.ids[np.asarray(arm)])
        else:
            if _ragged_end(topo, list(zip(ids, far)), hl, sc.noise, prm.min_spur):
                continue
            other = topo.release(r)  # the twig's last samples, ordered from the junction
            region_of[other] = -1
            x0 = X[np.asarray(core)].mean(axis=0)
            ids[t] = np.r_[ids[t], _ordered_from(P, other, x0)]
            region_of[c.ids[core]] = topo.branch_chain(i, c.ids[core], ids, far)
            reached |= {f for k, f in enumerate(far) if f >= 0 and k != t}
    return reached


def _free_branch(X: np.ndarray, core: list[int], arm: list[int], arms: list[list[int]], hl: float,
                 prm: RobustParams, noise: float = 0.0) -> bool:
    """Whether the branch ``arm`` (positions in ``X``, ordered outwards from the junction
    ``core``; one of its branches ``arms``) that reaches no region is a free branch all the
    same: its polyline from the core's centroid is at least :func:`.unexplained.free_reach`
    long (``min_spur`` spacings ``hl``; on noisy input, ``noise`` > 0, as stage 9's twig where
    that is shorter), it holds at least ``BRANCHED.free_fill`` samples per spacing of that
    length, and every branch of the junction holds ``BRANCHED.free_arm_points`` samples or more
    (see :class:`.thresholds.Branched`)."""
    if min(len(a) for a in arms) < BRANCHED.free_arm_points:
        return False
    pts = np.r_[X[np.asarray(core)].mean(axis=0)[None], X[np.asarray(arm)]]
    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    return length >= free_reach(prm.min_spur, hl, noise) and len(arm) >= BRANCHED.free_fill * length / hl


def _branch_end(topo: Topology, sc: Scales, c, arm: list[int], hl: float, linked_region) -> int:
    """The region the branch ``arm`` (positions in chain ``c``, ordered outwards) of a split
    chain ends at: the region its last ``BRANCHED.tip_points`` points are most linked to, when
    its last point lies within ``BRANCHED.reach`` spacings of it; else the chain's own region at
    the end the branch holds; -1 when neither."""
    P = topo.P
    tip = c.ids[arm[-1]]
    f = linked_region(c.ids[arm[-BRANCHED.tip_points:]])
    if f >= 0 and np.min(np.linalg.norm(P[topo.regions[f]] - P[tip], axis=1)) > _reach(hl, sc.noise):
        f = -1  # (linked, but the region is no next sample of the branch)
    if f < 0 and 0 in arm:
        f = c.ends[0]
    elif f < 0 and len(c.ids) - 1 in arm:
        f = c.ends[1]
    return f


def _split_at_cores(topo: Topology, sc: Scales, prm: RobustParams, i: int, c, X: np.ndarray, hl: float, keep: np.ndarray,
                    adj: list[set], linked_region) -> set:
    """Chain ``i`` (points ``X``, pruned tree ``adj``) split at the two or more junctions its
    tree shows (:func:`cores_plan`; noise-free input): each branch leaving ends as in
    :func:`split_branched_chains` (:func:`_branch_end`), each piece between two junctions joins
    them; a branch that reaches no region is a free branch when :func:`_free_branch` says so
    (a comb's spine past its last tooth); left as it is when such a branch is not, or two
    branches of one junction end in one region as a ragged end (:func:`_ragged_end`). Returns the regions the
    branches leaving end at (empty when the chain is left as it is)."""
    plan = cores_plan(X, hl, sc.noise, keep, adj)
    if plan is None:
        return set()
    cores, pieces = plan
    out = []
    for path, a, b in pieces:
        f = -b - 2 if b >= 0 else _branch_end(topo, sc, c, path, hl, linked_region)
        if f == -1 and not _free_branch(X, cores[a], path, [q for q, x, y in pieces if a in (x, y)], hl, prm):
            return set()  # (a branch that reaches no region, too short or too sparse to be a curve)
        out.append((c.ids[np.asarray(path)], a, f))
    for k in range(len(cores)):
        # (a piece to another core is a curve between two junctions: given as core -2)
        mine = [(ids, f) for ids, a, f in out if a == k] + [(ids, -2) for ids, _, f in out if f == -k - 2]
        if _ragged_end(topo, mine, hl, sc.noise, prm.min_spur):
            return set()
    topo.branch_chain_cores(i, [c.ids[np.asarray(m)] for m in cores], out)
    return {f for _, _, f in out if f >= 0}


def _ragged_end(topo: Topology, branches: list, hl: float, noise: float, min_spur: float) -> bool:
    """Whether the branches of one junction of a split chain, ``(ids, f)`` each (ids ordered
    outwards, ``f`` the region it ends at as :func:`_branch_end` gives it, -1 a free branch, under
    -1 another junction of the split), show a chain's ragged end rather than a junction: two of
    them end in one region, unless those two are curves apart (:func:`_pieces_apart`) and every
    other branch ends where a curve does (a free branch, another junction, a region that
    chains end at). A loop's chain whose spanning tree branches towards a blob the shell test
    flagged beside it (a region no chain ends at: a real sketch's loop under noise 0.1-0.3 h,
    its branch 2.6-6.3 h long) is one curve, with no junction there."""
    P = topo.P
    twins = [(a, b) for a, b in itertools.combinations(range(len(branches)), 2)
             if branches[a][1] >= 0 and branches[a][1] == branches[b][1]]
    if not twins:
        return False
    if not all(_pieces_apart(P[branches[a][0]], P[branches[b][0]], hl, noise, min_spur) for a, b in twins):
        return True
    paired = {k for pair in twins for k in pair}
    return any(k not in paired and f >= 0 and topo.v[f] == 0 for k, (_, f) in enumerate(branches))


def _pieces_apart(A: np.ndarray, B: np.ndarray, hl: float, noise: float, min_spur: float) -> bool:
    """Whether two pieces of a split chain that leave one junction for one region, their points
    ``A`` (a, d) and ``B`` (b, d), are two curves: each at least ``min_spur`` spacings long and
    some point of one over ``BRANCHED.twin_apart`` spacings (plus the noise) from every point of
    the other (a ladder's end rung beside the rail's rounded end, both between the same two
    junctions). Else they are the chain's end widened by noise where it enters the region (a
    few samples each): one curve, and the chain is left as it is."""
    if min(polylen(A), polylen(B)) < min_spur * hl:
        return False
    return points_apart(A, B, BRANCHED.twin_apart * hl + BRANCHED.twin_apart_noise * noise)
