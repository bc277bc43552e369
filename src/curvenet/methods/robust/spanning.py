"""Several junctions seen as one region, read from the spanning tree of its points.

A row of junctions a few spacings apart (a comb's teeth leaving its spine, a ladder's rungs on
a rail, a street with short links, a roof outline with notches) lies within one shell once the
shell is widened for noise: the shell test flags one region, found as one node of high valence.
:func:`.paired.split_paired_junctions` parts a region into two junctions by the lines of its
branches (later, for the pairs); a row of three or more needs another reading. The minimum
spanning tree of the points around the region shows it: noise makes only short leaf branches (a sample off the curve hangs
on its neighbour), so once leaf branches shorter than ``SPANNING.prune`` spacings (plus twice
the noise) are cut, the tree is the skeleton of the curves, and its vertices with three or more
branches gather at the junctions. Those within ``SPANNING.cluster`` spacings of one another are
one junction (an X crossing shows two vertices of three branches close together); a single
vertex whose branches leave within ``SPANNING.arm_cos`` of one another is the tree hopping
between two close curves, not a junction.

:func:`split_plan` returns the junctions (cores) of one region when there are at least
``SPANNING.min_cores`` of them, each ``SPANNING.sep`` spacings from the others, and each of
valence 3 to ``SPANNING.max_valence``: its share of the region's chain ends (the tree vertex of
each end point goes to the nearest core along the tree) plus the tree paths to its neighbouring
cores. A core of valence under 3 (a bend of the spine, or the region's end where the next
junction is another region) is merged into its nearest neighbour first; then two neighbouring
cores under ``SPANNING.sep`` apart are one junction (the closest pair merged first, while more
than ``SPANNING.min_cores`` are left: under noise one pair of a ladder's rail came 1.9 h apart
and the whole row stayed one node); a core of higher
valence is a hub of many strokes spread by the noise, and a region whose branches' lines all
meet one point (:func:`.paired.meet_at_one_point`) is one junction: both are left whole. The
exception is a core of higher valence beside ``SPANNING.min_cores`` plain junctions (valence
3): that is a row, and the core holds the chain ends of a junction of the row that the pruned
tree did not show (a ladder's rail under noise); it is split, the core of higher valence kept as
one junction. A hub's satellites are fewer (two or fewer plain cores on every CASSIE sketch
under noise).
:func:`split_multiple_junctions` (a repair of :data:`.repairs.ORDER`, the first: before any
other repair reads the region) then splits the cores off the region one leaf of the core tree at
a time (:meth:`.topology.Topology.split_region`), each joined to its neighbour by a new chain of
the region's points along the tree path between them (those over a core radius from both, or,
for junctions 3 h apart under noise, the one farthest from both).

On noise-free input the shell is not widened (under low noise, ``NOISE.low``, little), but
junctions 3-5 h apart still share one
(:func:`.junctions.separate_close_junctions` parts some rows; a facade's ladder and a comb kept
pairs and rows of three whole): there a pair is split too (``SPANNING.clean_min_cores``) and a
region of a few points is read (``SPANNING.clean_min_points``). A pair is split only when each
junction's branches leave it over ``SPANNING.arm_cos`` apart (:func:`_branches_apart`: two curves
converging at a small angle part where the tree branches, a few spacings before their node) and
no straight curve runs through both junctions off the segment between them
(:func:`_straight_across`: an X crossing whose curves pass a spacing or two apart reads as two
V's; a straight curve along the segment with the other branches not parallel is strokes
crossing one curve loosely, one junction in a real sketch, as :func:`.paired.best_pairs` reads
it). Under noise pairs are left to :func:`.paired.split_paired_junctions`: read here too they
cost 35% of the run at 10^6 points (every valence-4 region read) for a gain of about 0.01.

The regions whose branches' lines meet one point are dropped first, all at once
(:func:`.paired.meet_at_one_point_each`): on noise-free input every X crossing (7,333 regions of
the 10^6-point benchmark cloud, 8.5 s of 15 s when each was read with its tree).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..emst import emst_edges_each
from .chains import group_medians, points_apart, polylen
from .graph import components
from .paired import (Lines, branch_lines, curve_directions, meet_at_one_point_each, meet_loosely, region_stats,
                     straight_pairs, towards_tips)
from .params import RobustParams, Scales
from .thresholds import BRANCHED, NODES, PAIRED, SPANNING
from .topology import Topology
from .unexplained import free_reach

__all__ = ["split_multiple_junctions", "split_rows_again", "split_plan", "region_points", "Plan", "pruned_tree", "pruned_trees", "prune_cut",
           "loop_closures", "tree_cores", "core_order"]


class Plan(NamedTuple):
    """How one region splits into a row of junctions (the result of :func:`split_plan`).

    Attributes
    ----------
    ends : dict of int to list of (int, int)
        Per core, the region's chain ends ``(chain, side)`` that belong to it.
    steps : list of (int, int, ndarray, ndarray)
        In order: the core split off (a leaf of the cores' tree among those left), its
        neighbour, the new region's points and the new chain's points (ordered from the
        neighbour, still in the region, to the new region).
    centres : dict of int to (d,) ndarray
        Per core, its position (the tree vertex nearest the mean of its vertices).
    joins : list of (int, int, ndarray), optional
        The chains that close cycles of the cores (a cell of the network inside the region):
        its two cores and its points, ordered from the first; made after the steps (none by default).
    free : list of (int, ndarray), optional
        The free branches wholly inside the region (:func:`_free_arms`): its core and its
        points, ordered from the core outwards; each becomes a chain to a new free end.
    """

    ends: dict
    steps: list
    centres: dict
    joins: list | tuple = ()
    free: list | tuple = ()


def pruned_tree(X: np.ndarray, cut: float, keep: np.ndarray | None = None) -> list[set]:
    """The minimum spanning tree of the points ``X`` (n, d), as adjacency sets, without its
    leaf branches shorter than ``cut`` (a leaf in ``keep``, (n,) bool, stays).

    A leaf branch runs from a vertex of one tree edge to the first vertex of three or more; it
    is cut (its vertices lose their edges) when its length is under ``cut``. Up to
    ``SPANNING.prune_passes`` passes (cutting a branch can leave a short one behind).
    """
    return pruned_trees([X], [cut], [keep])[0]


def pruned_trees(blocks, cuts, keeps, closes=None) -> list[list[set]]:
    """:func:`pruned_tree` of several point sets, their spanning trees computed at once
    (:func:`..emst.emst_edges_each`): per set ``blocks[b]`` (n_b, d), its cut ``cuts[b]`` and
    its ``keeps[b]`` ((n_b,) bool or None), the pruned tree as adjacency sets. ``closes``: per
    set, None or its spacing and noise ``(hl, noise)``: the tree's gaps that close a cycle of
    the network (:func:`loop_closures`) are joined before the pruning (the result is then a
    graph with those cycles, not a tree)."""
    edges = emst_edges_each(blocks, [min(SPANNING.k, len(X) - 1) for X in blocks])
    if closes is not None:
        edges = [e if c is None else np.concatenate([e, loop_closures(X, e, *c)])
                 for X, e, c in zip(blocks, edges, closes)]
    return [_pruned(X, e, cut, keep) for X, e, cut, keep in zip(blocks, edges, cuts, keeps)]


def loop_closures(X: np.ndarray, edges: np.ndarray, hl: float, noise: float) -> np.ndarray:
    """The gaps of the spanning tree of ``X`` (n, d) that close a cycle of the network.

    A spanning tree has no cycle: a cell of the network among the points (a street block, a
    window) loses its longest edge, and the two halves of that side hang as leaf branches.
    A leaf of the tree (``edges``, (E, 2) ids into ``X``) and a point at most
    ``SPANNING.close`` spacings ``hl`` from it (plus ``SPANNING.prune_noise`` times ``noise``),
    the gap between them going on along the tree at the leaf (the tree's direction over
    ``SPANNING.arm`` spacings back within ``SPANNING.close_cos`` of the gap's) and at the point
    too when it is a leaf (a side's two halves; a point inside a curve: the side of a cell
    ending at a T, most often at its corner, where the curve's own direction is not defined),
    whose path in the graph is ``SPANNING.loop`` spacings or longer, are
    joined; the closest pair first, the path measured in the graph with the edges joined so far
    (a leaf joined is no longer one). Two branches of a junction at a small angle close
    no cycle: their points are not leaves, and their path through the junction is short.

    Returns
    -------
    (M, 2) ndarray of int64
        The edges joined, ``(i, j)`` with ``i < j``.
    """
    none = np.zeros((0, 2), dtype=np.int64)
    n = len(X)
    if not len(edges):
        return none
    adj: list[list[int]] = [[] for _ in range(n)]
    for a, b in edges.tolist():
        adj[a].append(b)
        adj[b].append(a)
    leaf = np.array([len(s) == 1 for s in adj])
    if not leaf.any():
        return none
    from scipy.spatial import cKDTree

    lv = np.flatnonzero(leaf)
    reach = SPANNING.close * hl + SPANNING.prune_noise * noise
    found = cKDTree(X).query_ball_point(X[lv], reach)
    pa = np.repeat(lv, [len(f) for f in found])
    pb = np.fromiter((v for f in found for v in f), dtype=np.int64, count=len(pa))
    keep = (pa != pb) & ~(leaf[pb] & (pb < pa))  # (two leaves: once)
    pa, pb = pa[keep], pb[keep]
    if not len(pa):
        return none
    d = np.linalg.norm(X[pa] - X[pb], axis=1)
    order = np.lexsort((pb, pa, d))
    out = []
    for a, b in zip(pa[order].tolist(), pb[order].tolist()):
        if len(adj[a]) != 1 or b in adj[a]:
            continue
        e = X[b] - X[a]
        e = e / max(float(np.linalg.norm(e)), np.finfo(float).tiny)
        if not _leaf_direction(X, adj, a, SPANNING.arm * hl) @ e >= SPANNING.close_cos:
            continue
        if len(adj[b]) == 1 and not _leaf_direction(X, adj, b, SPANNING.arm * hl) @ -e >= SPANNING.close_cos:
            continue
        if _path_within(X, adj, a, b, SPANNING.loop * hl):
            continue
        adj[a].append(b)
        adj[b].append(a)
        out.append((min(a, b), max(a, b)))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def _leaf_direction(X: np.ndarray, adj: list, v: int, reach: float) -> np.ndarray:
    """The unit direction at the leaf ``v`` out of the tree ``adj``: from the vertex ``reach``
    back along it (or its last before a fork) to ``v`` (:func:`_walk_out`)."""
    d = X[v] - X[_walk_out(X, adj, v, adj[v][0], reach)]
    return d / max(float(np.linalg.norm(d)), np.finfo(float).tiny)


def _path_within(X: np.ndarray, adj: list, a: int, b: int, limit: float) -> bool:
    """Whether the graph ``adj`` joins ``a`` to ``b`` by a path shorter than ``limit``
    (Dijkstra from ``a``, stopped at ``limit``)."""
    import heapq

    dist = {a: 0.0}
    heap = [(0.0, a)]
    while heap:
        du, u = heapq.heappop(heap)
        if u == b:
            return True
        if du > dist.get(u, np.inf):
            continue
        for w in adj[u]:
            dw = du + float(np.linalg.norm(X[w] - X[u]))
            if dw < limit and dw < dist.get(w, np.inf):
                dist[w] = dw
                heapq.heappush(heap, (dw, w))
    return False


def _pruned(X: np.ndarray, edges: np.ndarray, cut: float, keep: np.ndarray | None) -> list[set]:
    """The tree of ``edges`` ((E, 2) ids into ``X``) as adjacency sets, pruned as
    :func:`pruned_tree` says."""
    n = len(X)
    adj: list[set] = [set() for _ in range(n)]
    for a, b in edges.tolist():
        adj[a].add(b)
        adj[b].add(a)
    for _ in range(SPANNING.prune_passes):
        changed = False
        for leaf in range(n):
            if len(adj[leaf]) != 1 or (keep is not None and keep[leaf]):
                continue
            path, length, prev, cur = [leaf], 0.0, -1, leaf
            while True:
                nxt = [v for v in adj[cur] if v != prev]
                if not nxt or len(adj[cur]) > 2:
                    break
                v = nxt[0]
                length += float(np.linalg.norm(X[v] - X[cur]))
                prev, cur = cur, v
                if len(adj[cur]) > 2 or length >= cut:
                    break
                path.append(cur)
            if len(adj[cur]) > 2 and length < cut:
                for p in path:
                    for v in adj[p]:
                        adj[v].discard(p)
                    adj[p] = set()
                changed = True
        if not changed:
            break
    return adj


def prune_cut(hl: float, noise: float) -> float:
    """The length under which :func:`pruned_tree` cuts a leaf branch: ``SPANNING.prune``
    spacings ``hl`` plus ``SPANNING.prune_noise`` times the noise."""
    return SPANNING.prune * hl + SPANNING.prune_noise * noise


def _arms_apart(X: np.ndarray, adj: list[set], v: int, reach: float) -> bool:
    """The branches of vertex ``v`` leave in directions (to their point ``reach`` along the
    tree, or their last before a fork) pairwise over ``SPANNING.arm_cos`` apart."""
    dirs = []
    for s in sorted(adj[v]):
        d = X[_walk_out(X, adj, v, s, reach)] - X[v]
        dirs.append(d / max(float(np.linalg.norm(d)), np.finfo(float).tiny))
    D = np.array(dirs)
    cos = D @ D.T
    return bool(np.all(cos[np.triu_indices(len(D), 1)] <= SPANNING.arm_cos))


def _walk_out(X: np.ndarray, adj: list, v: int, s: int, reach: float) -> int:
    """The vertex reached from ``v`` through its neighbour ``s`` along the graph ``adj``: the
    first ``reach`` or farther along it, or the last before a fork or an end."""
    prev, cur = v, s
    length = float(np.linalg.norm(X[s] - X[v]))
    while length < reach:
        nxt = [u for u in adj[cur] if u != prev]
        if len(nxt) != 1:
            break
        prev, cur = cur, nxt[0]
        length += float(np.linalg.norm(X[cur] - X[prev]))
    return cur


def _tree_edges(adj: list[set]) -> tuple[np.ndarray, np.ndarray]:
    """The edges of the tree ``adj``, each in both directions: vertex arrays ``(a, b)``."""
    a = np.array([u for u in range(len(adj)) for _ in adj[u]], dtype=np.int64)
    b = np.array([w for u in range(len(adj)) for w in adj[u]], dtype=np.int64)
    return a, b


def _labels(X: np.ndarray, a: np.ndarray, b: np.ndarray, sources: dict) -> np.ndarray:
    """The core of every vertex of the tree of edges ``(a, b)`` (:func:`_tree_edges`): that of
    the nearest source vertex along the tree (``sources``: vertex -> core), -1 where none is
    reachable."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    n = len(X)
    w = np.linalg.norm(X[a] - X[b], axis=1) if len(a) else np.zeros(0)
    G = coo_matrix((w + np.finfo(float).tiny, (a, b)), shape=(n, n)).tocsr()
    src = np.array(sorted(sources), dtype=np.int64)
    _, _, nearest = dijkstra(G, directed=False, indices=src, min_only=True, return_predecessors=True)
    lab = np.full(n, -1, dtype=np.int64)
    ok = nearest >= 0
    lab[ok] = [sources[int(s)] for s in nearest[ok].tolist()]
    return lab


def _clusters(Y: np.ndarray, r: float) -> np.ndarray:
    """The clusters of the few points ``Y`` (m, d) joined by pairs at most ``r`` apart: a label
    per point, numbered in the order of each cluster's first point (:func:`.graph.components`,
    as ``scipy.sparse.csgraph.connected_components`` numbers them). The branch vertices of one
    region are a handful: all pairs at once, without a k-d tree or a sparse graph."""
    D = Y[:, None, :] - Y[None, :, :]
    pa, pb = np.nonzero(np.triu(np.einsum("ijk,ijk->ij", D, D) <= r * r, 1))
    lab, _ = components(len(Y), pa, pb, np.ones(len(Y), dtype=bool))
    return lab


def tree_cores(X: np.ndarray, adj: list[set], inside: np.ndarray, hl: float, noise: float,
               min_cores: int) -> list[list[int]]:
    """The junctions the pruned tree shows inside the region: its vertices of three or more
    branches, those within ``SPANNING.cluster`` spacings (plus the noise) of one another taken
    together; a lone vertex whose branches do not leave apart (:func:`_arms_apart`) is none.
    Each as its vertices, the one nearest their mean first."""
    bv = np.array([v for v in range(len(X)) if len(adj[v]) > 2 and inside[v]], dtype=np.int64)
    if len(bv) < min_cores:
        return []
    lab = _clusters(X[bv], SPANNING.cluster * hl + noise)
    out = []
    for c in range(int(lab.max()) + 1):
        mem = bv[lab == c]
        if len(mem) == 1 and not _arms_apart(X, adj, int(mem[0]), SPANNING.arm * hl):
            continue
        out.append(core_order(X, mem))
    return out


def core_order(X: np.ndarray, mem: np.ndarray) -> list[int]:
    """The vertices ``mem`` (m,) of a junction of a tree over the points ``X``, the one nearest
    their mean first (ties: in the order of ``mem``)."""
    order = np.argsort(np.linalg.norm(X[mem] - X[mem].mean(axis=0), axis=1), kind="stable")
    return mem[order].tolist()


def region_points(P: np.ndarray, tree, h: np.ndarray, ids: np.ndarray, end_points: np.ndarray) -> np.ndarray:
    """The points whose spanning tree :func:`split_plan` reads for the region ``ids``: those
    within ``SPANNING.margin`` spacings (the region's median) of a region point, and the points
    ``end_points`` of its chain ends; sorted ids into ``P`` (its arguments are that function's)."""
    return region_points_each(P, tree, np.array([np.median(h[ids])]), [ids], [end_points])[0]


def region_points_each(P: np.ndarray, tree, hls: np.ndarray, regions: list, end_points: list) -> list[np.ndarray]:
    """:func:`region_points` of several regions (``regions``, their median spacings ``hls``
    and ``end_points``), the ball queries of all of them in one call."""
    sizes = np.array([len(ids) for ids in regions], dtype=np.int64)
    if not len(sizes) or not sizes.sum():
        return [np.union1d(np.zeros(0, dtype=np.int64), e) for e in end_points]
    flat = np.concatenate(regions).astype(np.int64)
    balls = tree.query_ball_point(P[flat], np.repeat(SPANNING.margin * np.asarray(hls, dtype=float), sizes))
    lens = np.fromiter((len(b) for b in balls), dtype=np.int64, count=len(balls))
    found = np.fromiter((v for b in balls for v in b), dtype=np.int64, count=int(lens.sum()))
    per = np.add.reduceat(lens, np.r_[0, np.cumsum(sizes)[:-1]])
    cut = np.r_[0, np.cumsum(per)]
    return [np.union1d(np.unique(found[cut[r]:cut[r + 1]]), e) for r, e in enumerate(end_points)]


def split_plan(P: np.ndarray, tree, h: np.ndarray, noise: float, ids: np.ndarray, ends: list,
               end_points: np.ndarray, min_cores: int = SPANNING.min_cores,
               near_tree: tuple[np.ndarray, list[set]] | None = None, chain_ids: dict | None = None,
               free_len: float = np.inf) -> Plan | None:
    """How the region of points ``ids`` splits into a row of junctions (None: it does not).

    Parameters
    ----------
    P : (N, d) ndarray
        All points.
    tree : scipy.spatial.cKDTree
        Over ``P``.
    h : (N,) ndarray
        Local spacing.
    noise : float
        The noise scale.
    ids : (m,) ndarray of int64
        The region's points.
    ends : list of (int, int)
        The chain ends ``(chain, side)`` at the region.
    end_points : (len(ends),) ndarray of int64
        The point of each chain end next to the region.
    min_cores : int
        The fewest junctions of a split (``SPANNING.min_cores``, or ``SPANNING.clean_min_cores``
        on noise-free input).
    near_tree : (ndarray, list of set), optional
        The region's points (:func:`region_points`) and their pruned tree with its cycles
        closed (:func:`pruned_trees` with the cut :func:`prune_cut` and :func:`loop_closures`),
        when already built (:func:`split_multiple_junctions` builds every region's at once).
    chain_ids : dict of int to ndarray, optional
        The samples of each chain of ``ends`` (:func:`_twin_of_chain`: a cycle of junctions
        closed by a chain already gets no new chain beside it).
    free_len : float
        The least length (absolute) of a free branch wholly inside the region
        (:func:`_free_arms`; infinite: none is read).

    Returns
    -------
    Plan or None
    """
    hl = float(np.median(h[ids]))
    if near_tree is None:
        near = region_points(P, tree, h, ids, end_points)
        adj = pruned_trees([P[near]], [prune_cut(hl, noise)], [None], closes=[(hl, noise)])[0]
    else:
        near, adj = near_tree
    X = P[near]
    inside = np.isin(near, ids)
    cores = tree_cores(X, adj, inside, hl, noise, min_cores)
    if len(cores) < min_cores:
        return None
    centre = np.array([X[mem[0]] for mem in cores])
    # the cores kept below are some of these, at these positions, and no two of them may lie
    # under SPANNING.sep apart: when no two of these do, nothing below can (the same None, sooner)
    if np.linalg.norm(centre[:, None] - centre[None], axis=2).max() < SPANNING.sep * hl:
        return None
    ea, eb = _tree_edges(adj)
    lab = _labels(X, ea, eb, {v: k for k, mem in enumerate(cores) for v in mem})
    at = np.searchsorted(near, end_points)
    arms = _free_arms(X, adj, inside, free_len, hl)
    live = list(range(len(cores)))
    while True:  # cores of valence under 3 merged into their nearest neighbour
        nbr = {k: set() for k in live}
        la, lb = lab[ea], lab[eb]
        cross = (la >= 0) & (lb >= 0) & (la != lb)
        for u, w in zip(la[cross].tolist(), lb[cross].tolist()):
            nbr[u].add(w)
        own = np.array([lab[j] if lab[j] >= 0 else
                        live[int(np.argmin(np.linalg.norm(centre[live] - P[e], axis=1)))]
                        for j, e in zip(at.tolist(), end_points.tolist())], dtype=np.int64)
        arm_of = np.array([lab[arm[0]] for arm in arms], dtype=np.int64)
        val = {k: int(np.sum(own == k)) + len(nbr[k]) + int(np.sum(arm_of == k)) for k in live}
        if len(live) < min_cores:
            break
        weak = [k for k in live if val[k] < NODES.junction_valence and nbr[k]]
        if weak:
            k = min(weak, key=lambda q: (val[q], q))
            into = min(sorted(nbr[k]), key=lambda q: float(np.linalg.norm(centre[q] - centre[k])))
        else:  # neighbouring cores under SPANNING.sep apart are one junction: the closest pair
            pairs = [(float(np.linalg.norm(centre[a] - centre[b])), a, b) for a in live for b in sorted(nbr[a])
                     if a < b] if len(live) > SPANNING.min_cores else []
            close = [q for q in pairs if q[0] < SPANNING.sep * hl]
            if not close:
                break
            _, a, b = min(close)
            k, into = (a, b) if (val[a], a) <= (val[b], b) else (b, a)
        lab[lab == k] = into
        live.remove(k)
    if len(live) < min_cores or min(val.values()) < NODES.junction_valence:
        return None
    tree_nbr, joins = _core_tree(nbr, centre, live)
    if tree_nbr is None:  # (the cores not all joined)
        return None
    # a core over SPANNING.max_valence is a hub of many strokes spread by the noise, unless a row
    # of SPANNING.min_cores plain junctions lies beside it (then it holds a missed junction's
    # ends), or it lies inside a row: the cores a path, it between two of them, and one plain
    # junction fewer (two junctions of the row the tree did not part). Plain: of valence 3 or
    # 4 (a crossing: a rail crossing a row of verticals, a street grid)
    regular = sum(1 for k in live if NODES.junction_valence <= val[k] <= SPANNING.max_valence)
    over = [k for k in live if val[k] > SPANNING.max_valence]
    inside_row = (all(len(nbr[k]) <= 2 for k in live) and all(len(nbr[k]) == 2 for k in over)
                  and regular >= SPANNING.min_cores - 1)
    if over and regular < SPANNING.min_cores and not inside_row:
        return None
    # the centre of a star of SPANNING.min_cores cores or more (every other core's one
    # neighbour) is a hub all the same: strokes drawn into a pole, their ends read as junctions
    # around it (a path of three is a row: two junctions of it the tree did not part)
    if len(live) > SPANNING.min_cores and any(all(nbr[j] == {k} for j in live if j != k) for k in over):
        return None
    C = centre[live]
    gap = np.linalg.norm(C[:, None] - C[None], axis=2)
    if np.min(gap + np.diag(np.full(len(live), np.inf))) < SPANNING.sep * hl:
        return None
    # the core of every region point: that of its tree vertex, else the nearest core
    owner = lab[np.searchsorted(near, ids)]
    lost = np.flatnonzero(owner < 0)
    if len(lost):
        owner[lost] = np.array(live)[np.argmin(np.linalg.norm(P[ids[lost]][:, None] - C[None], axis=2), axis=1)]
    region = ids
    free = [(int(lab[arm[0]]), near[np.asarray(arm[1:])]) for arm in arms]
    if free:
        region = region[~np.isin(region, np.concatenate([a for _, a in free]))]
    # the chains that close cycles of the cores (a cell of the network inside the region, its
    # sides found again by loop_closures) first: their points are no core's
    ring = []
    for u, w in joins:
        path = _core_path(adj, lab, cores[u][0], cores[w][0], (u, w))
        if _joined_outside(near, path, region):
            continue
        seg = _core_segment(P, X, near, path, region, hl, noise)
        if seg is None:
            return None
        if _twin_of_chain(P, ends, own, u, w, seg, chain_ids, hl, noise):
            continue
        ring.append((u, w, seg))
        region = region[~np.isin(region, seg)]
    steps = []
    left = set(live)
    while len(left) > 1:
        leaf = min(k for k in left if len(tree_nbr[k] & left) == 1)
        to = min(tree_nbr[leaf] & left)
        seg = _core_segment(P, X, near, _core_path(adj, lab, cores[to][0], cores[leaf][0], (to, leaf)), region, hl,
                            noise)
        if seg is None:
            return None
        mine = np.isin(region, ids[owner == leaf]) & ~np.isin(region, seg)
        if not mine.any():  # (the core's points all on the chains: no region left for it)
            return None
        new_ids = region[mine]
        steps.append((leaf, to, new_ids, seg))
        region = region[~np.isin(region, np.r_[new_ids, seg])]
        left.discard(leaf)
    return Plan({k: [e for e, o in zip(ends, own.tolist()) if o == k] for k in live}, steps,
                {k: X[cores[k][0]] for k in live}, ring, free)


def _free_arms(X: np.ndarray, adj: list, inside: np.ndarray, free_len: float, hl: float) -> list[list[int]]:
    """The free branches of the pruned tree ``adj`` (adjacency sets over the points ``X``,
    (n, d); ``inside``: (n,) bool, the region's points) that run wholly inside the region: leaf
    branches (from a leaf to the first vertex of three or more edges) whose vertices are all
    region points (``inside``), no chain beyond them, at least ``free_len`` long (absolute) and
    holding at least ``BRANCHED.free_fill`` samples per spacing ``hl`` of that length (as
    :func:`.branched._free_branch` reads a chain's branch): a comb's tooth shorter than the
    widened shell, its tip a free end no chain reaches. Each as vertex positions, the branch
    vertex first, then the branch ordered outwards."""
    out = []
    for v in range(len(X)):
        if len(adj[v]) != 1 or not inside[v]:
            continue
        path, prev, u = [v], v, next(iter(adj[v]))
        while len(adj[u]) == 2 and inside[u]:
            path.append(u)
            prev, u = u, next(w for w in adj[u] if w != prev)
        if len(adj[u]) < NODES.junction_valence or not inside[u]:
            continue
        arm = [u] + path[::-1]
        length = polylen(X[arm])
        if length >= free_len and len(path) >= BRANCHED.free_fill * length / hl:
            out.append(arm)
    return out


def _core_tree(nbr: dict, centre: np.ndarray, live: list) -> tuple:
    """A spanning tree of the cores' graph (``nbr``: core -> neighbouring cores), the edges
    between nearer cores (``centre``) first, and the graph's other edges (each closes a cycle:
    a cell of the network inside the region). Returns ``(tree_nbr, joins)``: per core its
    neighbours in the tree, and the other edges ``(u, w)``, ``u < w``, in the order met; or
    ``(None, [])`` when the cores are not all joined."""
    edges = sorted({(min(u, w), max(u, w)) for u in live for w in nbr[u]},
                   key=lambda e: (float(np.linalg.norm(centre[e[0]] - centre[e[1]])), e))
    root = {k: k for k in live}

    def find(k):
        while root[k] != k:
            k = root[k]
        return k

    tree_nbr = {k: set() for k in live}
    joins = []
    for u, w in edges:
        ru, rw = find(u), find(w)
        if ru == rw:
            joins.append((u, w))
            continue
        root[max(ru, rw)] = min(ru, rw)
        tree_nbr[u].add(w)
        tree_nbr[w].add(u)
    if sum(len(t) for t in tree_nbr.values()) != 2 * (len(live) - 1):
        return None, []
    return tree_nbr, joins


def _twin_of_chain(P, ends: list, own: np.ndarray, u: int, w: int, seg: np.ndarray, chain_ids: dict | None,
                   hl: float, noise: float) -> bool:
    """Whether a chain of the topology from core ``u`` to core ``w`` (both its ends at the
    region, ``ends``, one owned by each, ``own``) runs where the new chain ``seg`` would: no
    sample of either over ``BRANCHED.twin_apart`` spacings ``hl`` (plus
    ``BRANCHED.twin_apart_noise`` times ``noise``) from the other (:func:`.chains.points_apart`,
    as stage 4 tells a cell's two sides from one side). The cycle of cores is that chain's: a
    new one would be its twin (grid#11 of the families at noise 0.1 h: two sides made twice).
    ``chain_ids``: the samples of each chain of ``ends`` (None: no chain is known)."""
    if chain_ids is None:
        return False
    at = {}
    for (i, side), o in zip(ends, own.tolist()):
        at.setdefault(i, {})[side] = o
    lim = BRANCHED.twin_apart * hl + BRANCHED.twin_apart_noise * noise
    return any(len(sides) == 2 and {sides[0], sides[1]} == {u, w} and i in chain_ids
               and not points_apart(P[seg], P[chain_ids[i]], lim) for i, sides in at.items())


def _joined_outside(near: np.ndarray, path: list | None, region: np.ndarray) -> bool:
    """Whether the path (vertices into ``near``, from one core's vertex to another's) runs
    through samples outside the ``region`` only: the two junctions are joined by a chain of
    the topology already (a cell's side long enough to leave the region; grid#15 of the
    families at noise 0.2 h: such a cycle had no chain to make, and the region was left whole)."""
    return path is not None and not np.isin(near[path[1:-1]], region).any()


def _core_segment(P, X, near, path: list | None, region, hl: float, noise: float):
    """The points of the new chain between the junctions at the two ends ``a``, ``b`` of
    ``path`` (:func:`_core_path`, vertices into ``near``; :func:`split_plan`'s arrays), ordered
    from ``a``: the ``region`` points of the path that lie over a core radius from both
    (``SPANNING.core``, ``SPANNING.core_share``), or, when none does, the path's region point
    farthest from both; None when there is no path or no such point."""
    if path is None:
        return None
    a, b = path[0], path[-1]
    ra = min(SPANNING.core * hl + noise, SPANNING.core_share * float(np.linalg.norm(X[a] - X[b])))
    pts = near[path]
    off = np.minimum(np.linalg.norm(P[pts] - X[a], axis=1), np.linalg.norm(P[pts] - X[b], axis=1))
    held = np.isin(pts, region)
    seg = pts[(off > ra) & held]
    if not len(seg):  # junctions closer than two core radii: the path's point farthest from both
        mid = np.flatnonzero(held[1:-1]) + 1
        if not len(mid):
            return None
        seg = pts[mid[[np.argmax(off[mid])]]]
    return seg


def _core_path(adj: list, lab: np.ndarray, a: int, b: int, two: tuple) -> list | None:
    """The vertices of a path with fewest edges from ``a`` to ``b`` in the graph ``adj``
    through vertices of the cores ``two`` only (``lab``: each vertex's core); on a tree the
    one path between two neighbouring cores. None: there is none."""
    prev = {a: -1}
    front = [a]
    while front and b not in prev:
        nxt = []
        for u in front:
            for w in sorted(adj[u]):
                if w not in prev and lab[w] in two:
                    prev[w] = u
                    nxt.append(w)
        front = nxt
    if b not in prev:
        return None
    out = [b]
    while out[-1] != a:
        out.append(prev[out[-1]])
    return out[::-1]


def _branches_apart(L, ends: list, plan: Plan) -> bool:
    """Whether the branches each core of ``plan`` takes leave it pairwise over
    ``SPANNING.arm_cos`` apart: their lines ``L`` (one per chain end of ``ends``, as
    :func:`.paired.branch_lines` fits them), directed away from the region. Two curves that
    converge at a small angle (an eye's arcs meeting their node, the arms of a thin X crossing)
    part where the tree branches, a few spacings before their node: those branches run nearly
    parallel. Asked of pairs only (a row's cores were never two converging curves in the runs
    measured)."""
    out = np.sign(np.einsum("ij,ij->i", L.c - L.tip, L.u))[:, None] * L.u
    for own in plan.ends.values():
        k = [ends.index(e) for e in own]
        cos = out[k] @ out[k].T
        if np.any(cos[np.triu_indices(len(k), 1)] > SPANNING.arm_cos):
            return False
    return True


def _straight_across(L, ends: list, plan: Plan) -> bool:
    """Whether a straight curve passes through both junctions of the pair ``plan`` off the
    segment between them: two lines of ``L`` (one per chain end of ``ends``), one owned by
    each junction, that are one straight curve (:func:`.paired.straight_pairs`) whose direction
    is not within ``PAIRED.parallel_cos`` of the segment's. An X crossing, its curves passing a
    spacing or two apart (a real sketch's strokes), reads as two V's on the tree: each curve
    has a half at each junction and crosses the segment; a comb's spine or a ladder's rail runs
    along it. Also True when such a curve runs along the segment and the other branches are not
    all parallel (within ``PAIRED.parallel_cos``): strokes crossing one curve at two angles a
    few spacings apart, one junction drawn loosely (:func:`.paired.best_pairs` reads them so);
    but where those are two branches with a direction (a branch of a single point has none),
    only when their lines meet (:func:`.paired.meet_loosely`, held near the segment's
    middle): two lines that pass apart, skew in 3D, are the teeth of a comb whose spine runs
    along the segment, one junction each."""
    ca, cb = (plan.centres[k] for k in sorted(plan.ends))
    e = cb - ca
    e = e / max(float(np.linalg.norm(e)), np.finfo(float).tiny)
    core = {end: k for k, own in plan.ends.items() for end in own}
    of = np.array([core[end] for end in ends])
    R = Lines(L.c[None], L.u[None], L.tip[None], L.lim[None])
    ud = towards_tips(R)
    straight = straight_pairs(R, ud)[0] & (of[:, None] != of[None, :])
    along = np.abs(curve_directions(R)[0] @ e) > PAIRED.parallel_cos
    if np.any(straight & ~along):
        return True
    # a straight curve along the segment: the other branches cross it at two places, junctions
    # only when parallel (as :func:`.paired.best_pairs` reads it)
    through = straight & along
    if through.any():
        rest = ~through.any(axis=1)
        u = L.u[rest]
        if len(u) >= 2 and np.any(np.abs(u @ u.T) <= PAIRED.parallel_cos):
            return meet_loosely(Lines(L.c[rest], u, L.tip[rest], L.lim[rest]), (ca + cb) / 2)
    return False


def split_rows_again(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Every row of junctions :func:`split_multiple_junctions` reads, read again once the
    repairs since have cleaned the chain ends at it.

    The repairs between prune spurs, join tips to their junctions and chains through passes.
    Read first, a row's region may hold an end too many (a spur of a few samples that noise or
    an uneven sampling hangs off a junction): the junction it is given reads over
    ``SPANNING.max_valence``, as a hub of strokes, and the row is left whole (a storey's row of
    three crossings under noise read [3, 5, 5]); it is split now, as
    :func:`split_multiple_junctions` splits it, rows only (``SPANNING.min_cores`` junctions or
    more at every noise level: a pair, on noise-free input too, is left to
    :func:`.paired.split_paired_junctions`, whose through-curve rule keeps a loose crossing
    whole; read here, two crossings of CASSIE study sketches drawn loosely became two
    junctions each). A region the repairs left as it was reads as before.
    """
    split_multiple_junctions(topo, sc, prm, rows_only=True)


def split_multiple_junctions(topo: Topology, sc: Scales, prm: RobustParams, only: set | None = None,
                             rows_only: bool = False) -> None:
    """Every region of valence ``SPANNING.region_valence`` or more that holds a row of
    junctions (:func:`split_plan`) becomes those junctions, joined by new chains.

    On noise-free or low-noise input (``NOISE.low``) a pair is split too (``SPANNING.clean_min_cores``, regions of
    ``SPANNING.clean_min_points`` points or more), when each junction's branches leave it apart
    (:func:`_branches_apart`). A chain with both ends at the region (a rung between the two
    rails of a ladder read as one region, a street block's side) is read as any other: each of
    its ends goes to its core, so the junctions joined by it and by the tree form a cycle (such
    regions were left whole: ladder, outline and street kinds under noise, 11 runs better, 4
    worse by 0.01-0.02 of the 832-run harness, +2.98; CASSIE 2 better). The regions are planned
    first, then split in region order (a split leaves the other regions as they are). A free
    branch wholly inside the region (:func:`_free_arms`: a comb's tooth shorter than the widened
    shell) counts as a branch of its junction and becomes a chain to a new free end. ``only``:
    the regions to read (default: all); :func:`.branched.split_branched_chains` reads again
    those its split chains reached (a rail's region, joined to the rungs that a chain ran past
    only then). ``rows_only``: rows of ``SPANNING.min_cores`` junctions or more on noise-free
    input too (:func:`split_rows_again`).
    """
    if sc.low and rows_only:
        min_cores, min_points, valence = SPANNING.min_cores, SPANNING.clean_min_points, SPANNING.region_valence
    elif sc.low:
        min_cores, min_points, valence = SPANNING.clean_min_cores, SPANNING.clean_min_points, SPANNING.clean_region_valence
    else:
        min_cores, min_points, valence = SPANNING.min_cores, SPANNING.min_points, SPANNING.region_valence
    cand, incs = [], []
    for r in np.flatnonzero(topo.v >= valence).tolist():
        if only is not None and r not in only:
            continue
        inc = topo.incident(r)
        if len(topo.regions[r]) >= min_points:
            cand.append(r)
            incs.append(inc)
    if not cand:
        return
    # the cheap test first, all regions at once: branches whose lines meet one point are one
    # junction (strokes drawn into one hub; on noise-free input every X crossing)
    L_all, off = branch_lines(topo, sc, incs)
    anchors, _ = region_stats(topo.P, sc.h, [topo.regions[r] for r in cand])
    hub = meet_at_one_point_each(L_all, off, anchors)
    # every region's spanning tree at once (one sparse-graph call instead of one per region)
    read = np.flatnonzero(~hub).tolist()
    end_points = [np.array([int(topo.end_ids(i, s)[-1]) for i, s in incs[j]], dtype=np.int64) for j in read]
    regions = [topo.regions[cand[j]] for j in read]
    hls = group_medians(sc.h[np.concatenate(regions)], [len(ids) for ids in regions]) if read else np.zeros(0)
    nears = region_points_each(topo.P, sc.tree, hls, regions, end_points)
    cuts = [prune_cut(float(hl), sc.noise) for hl in hls]
    trees = pruned_trees([topo.P[near] for near in nears], cuts, [None] * len(read),
                         closes=[(float(hl), sc.noise) for hl in hls])
    plans = []
    for j, ep, near, adj, hl in zip(read, end_points, nears, trees, hls):
        r, inc = cand[j], incs[j]
        ids = topo.regions[r]
        L = Lines(*(a[off[j]:off[j + 1]] for a in L_all))
        free_len = free_reach(prm.min_spur, float(hl), 0.0 if sc.clean else sc.noise)
        plan = split_plan(topo.P, sc.tree, sc.h, sc.noise, ids, list(inc), ep, min_cores, (near, adj),
                          {i: topo.chains[i].ids for i, _ in inc}, free_len)
        if plan is None:
            continue
        if len(plan.ends) == 2 and not _branches_apart(L, list(inc), plan):  # converging curves
            continue
        if len(plan.ends) == 2 and _straight_across(L, list(inc), plan):  # an X, its curves apart
            continue
        plans.append((r, plan))
    for r, plan in plans:
        ends = {k: list(v) for k, v in plan.ends.items()}
        ring = np.concatenate([seg for _, _, seg in plan.joins]) if plan.joins else np.zeros(0, dtype=np.int64)
        if plan.free:
            ring = np.r_[ring, np.concatenate([a for _, a in plan.free])]
        if len(ring):
            topo.regions[r] = topo.regions[r][~np.isin(topo.regions[r], ring)]
        where = {}
        for leaf, to, new_ids, seg in plan.steps:
            rest = topo.regions[r]
            rest = rest[~np.isin(rest, np.r_[new_ids, seg])]
            where[leaf] = topo.split_region(r, ends[leaf], rest, new_ids, seg)
            ends[to].append((len(topo.chains) - 1, 0))  # the new chain's end at the rest
        for u, w, seg in plan.joins:
            topo.join_regions(where.get(u, r), where.get(w, r), seg)
        for k, arm in plan.free:
            topo.free_branch(where.get(k, r), arm)
