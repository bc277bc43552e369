"""A junction inside a free-end or pass region, read from the spanning tree of its points.

Under noise the shell test flags whole short curves: a twig of 3-6 spacings leaving a curve a
few spacings from where another twig leaves it (a neuron's short side branches, a comb's short
teeth) can lie inside one region together with the junction it leaves. Only the chain it
leaves from reaches the region, so the region is read as that chain's free end (valence 1) or
as a pass (valence 2): the junction and its twigs vanish, the chain runs on along one twig.

The pruned spanning tree of the region's points (:func:`.spanning.pruned_trees`, as
:func:`.spanning.split_plan` builds it for a row of junctions) shows such a junction: one core
(:func:`.spanning.tree_cores`) with three or more branches, on the region's points or on a
chain ending there (a chain traced through the junction and on along a twig).
:func:`read_end_junctions` reads every region of valence ``ENDTREES.min_valence`` to
``ENDTREES.max_valence`` that way, under noise only. A branch that holds a chain's end is that
chain's; a chain that enters by one branch and ends in another ran past the core along a twig
(under noise, in and out of two twigs), and its points after the last of its own branch go back
to the region; in a pass that is a sharp corner traced round its apex (:func:`_corner`), left. A branch no chain holds is a free arm when its path from the core out to its
farthest vertex runs through region points only, at least :func:`.unexplained.free_reach` long,
filled as :func:`.spanning._free_arms` asks (``BRANCHED.free_fill`` samples per spacing, the core's counted), its tip off the other
branches (:func:`.unexplained.leaves`: not a bend of one curve) and not a fold: holding at most
``ENDTREES.fold`` times the samples per length of the densest other branch (a curve that runs
out and straight back along itself, a spike of a neuron tracing, holds about twice). When the
chains' branches and the free arms are three or more, each free arm becomes a chain from the
region (now a junction) to a new free end (:meth:`.topology.Topology.free_branch`).
"""

from __future__ import annotations

import numpy as np

from .chains import group_medians, polylen, segment_distance
from .params import RobustParams, Scales
from .spanning import prune_cut, pruned_trees, region_points_each, tree_cores
from .thresholds import BRANCHED, ENDTREES, NODES, NUMERIC
from .topology import Topology
from .unexplained import free_reach, leaves

__all__ = ["read_end_junctions", "core_branches"]


def core_branches(adj: list[set], core: list[int]) -> np.ndarray:
    """The branch of every vertex of a tree around its core.

    Parameters
    ----------
    adj : list of set
        The tree's adjacency sets over n vertices.
    core : list of int
        The core's vertices.

    Returns
    -------
    (n,) ndarray of int64
        -1 for a core vertex, -2 for a vertex the branches do not reach (pruned, or in another
        component), else the branch's index (branches numbered as they leave the core).
    """
    lab = np.full(len(adj), -2, dtype=np.int64)
    lab[core] = -1
    b = 0
    for v in core:
        for w in sorted(adj[v]):
            if lab[w] != -2:
                continue
            lab[w] = b
            stack = [w]
            while stack:
                x = stack.pop()
                for y in adj[x]:
                    if lab[y] == -2:
                        lab[y] = b
                        stack.append(y)
            b += 1
    return lab


def _arm_path(X: np.ndarray, adj: list[set], lab: np.ndarray, b: int) -> list[int]:
    """The path of branch ``b`` from its vertex next to the core out to its vertex farthest
    along the tree (vertex ids into ``X``, (n, d))."""
    start = [v for v in np.flatnonzero(lab == b).tolist() if any(lab[w] == -1 for w in adj[v])]
    if len(start) != 1:
        return []
    dist, parent, stack = {start[0]: 0.0}, {start[0]: -1}, [start[0]]
    while stack:
        x = stack.pop()
        for y in adj[x]:
            if lab[y] == b and y not in dist:
                dist[y] = dist[x] + float(np.linalg.norm(X[y] - X[x]))
                parent[y] = x
                stack.append(y)
    far = max(dist, key=lambda v: (dist[v], -v))
    path = [far]
    while parent[path[-1]] >= 0:
        path.append(parent[path[-1]])
    return path[::-1]


def _core_points(topo: Topology, r: int, inc: list) -> np.ndarray:
    """The points the junction of region ``r`` may lie on: the region's and those of the chains
    ending there (``inc``; a chain traced through the junction and on along a twig holds it)."""
    return np.concatenate([topo.regions[r]] + [topo.chains[i].ids for i, _ in inc])


def _corner(trims: list, inc: list) -> bool:
    """Whether a pass (two chain ends ``inc``) has a chain that ran past the core (``trims``):
    a sharp corner under noise, traced round its apex, whose apex samples hang past the tree's
    core like a twig (synthetic corners at noise 0.2 h, sampling 5, read without the fit: curve
    F1 1.000 -> 0.500); a free end's chain may run on along a twig."""
    return bool(trims) and len(inc) > 1


def _fill(X: np.ndarray, Y: np.ndarray, band: float) -> float:
    """The points of ``X`` (n, d) within ``band`` of the polyline ``Y`` (m, d), m >= 2, per
    unit of its length."""
    d = np.min(segment_distance(X[:, None], Y[None, :-1], Y[None, 1:]), axis=1)
    return float(np.sum(d < band)) / max(polylen(Y), NUMERIC.tiny)


def read_end_junctions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Under noise, every free-end or pass region (valence ``ENDTREES.min_valence`` to
    ``ENDTREES.max_valence``) whose pruned spanning tree shows one junction with free arms (twigs
    the shell test flagged whole) becomes that junction, each free arm a chain to a new free end.

    The chains' branches and the free arms together are three or more; a chain that ran on past
    the junction along a twig gives its points past it back to the region, and a chain's branch
    holds the region points between the chain's end and the junction (the chain takes them).
    Not on noise-free input, where a twig's end is always flagged apart from its junction (there
    it read clean twigs' ends as junctions). See the module's text; ``topo`` is changed in place.
    """
    if sc.clean:
        return
    cand = [r for r in np.flatnonzero((topo.v >= ENDTREES.min_valence) & (topo.v <= ENDTREES.max_valence)).tolist()
            if len(topo.regions[r]) >= ENDTREES.min_points]
    if not cand:
        return
    incs = [topo.incident(r) for r in cand]
    end_points = [np.array([int(topo.end_ids(i, s)[-1]) for i, s in inc], dtype=np.int64) for inc in incs]
    regions = [topo.regions[r] for r in cand]
    hls = group_medians(sc.h[np.concatenate(regions)], [len(ids) for ids in regions])
    nears = region_points_each(topo.P, sc.tree, hls, regions, end_points)
    # (trees: no cycle closed, as split_plan closes a row's cells; one junction's branches are
    # told apart by the tree)
    trees = pruned_trees([topo.P[near] for near in nears], [prune_cut(float(hl), sc.noise) for hl in hls],
                         [None] * len(cand))
    for r, inc, near, adj, hl in zip(cand, incs, nears, trees, hls):
        _read(topo, r, inc, near, adj, float(hl), sc.noise, free_reach(prm.min_spur, float(hl), sc.noise))


def _read(topo: Topology, r: int, inc: list, near: np.ndarray, adj: list[set], hl: float, noise: float,
          free_len: float) -> None:
    """:func:`read_end_junctions` on region ``r`` (its chain ends ``inc``, the points ``near``
    its tree ``adj`` spans, their spacing ``hl``)."""
    X = topo.P[near]
    ids = topo.regions[r]
    inside = np.isin(near, ids)
    cores = tree_cores(X, adj, np.isin(near, _core_points(topo, r, inc)), hl, noise, 1)
    if len(cores) != 1:
        return
    lab = core_branches(adj, cores[0])
    n_branch = int(lab.max()) + 1
    if n_branch < NODES.junction_valence:
        return
    pos = {int(p): j for j, p in enumerate(near.tolist())}
    owned, trims, reach = set(), [], []
    for i, s in inc:
        run = topo.end_ids(i, s)[::-1]  # from the end back into the chain
        bl = [int(lab[pos[p]]) if p in pos else -2 for p in run.tolist()]
        seen = [(k, b) for k, b in enumerate(bl) if b >= 0]
        if not seen:
            return
        own = seen[-1][1]  # the branch the chain enters by
        owned.add(own)
        past = next(k for k, b in enumerate(bl) if b == own)  # its points beyond its own branch
        if any(b >= 0 for b in bl[:past]):  # (in another branch: it ran on along that one)
            trims.append((i, s, past))
        else:
            reach.append((i, s, own))
    if _corner(trims, inc):
        return
    for i, s, k in trims:
        inside[[pos[p] for p in topo.end_ids(i, s)[-k:].tolist() if p in pos]] = True
    paths = [_arm_path(X, adj, lab, b) for b in range(n_branch)]
    centre = X[cores[0][0]]
    arms = []
    for b in range(n_branch):
        path = paths[b]
        if b in owned or len(path) < 2 or not inside[path].all():
            continue
        arm = [cores[0][0]] + path
        length = polylen(X[arm])
        if length < free_len or len(arm) < BRANCHED.free_fill * length / hl:
            continue
        off = min((float(segment_distance(X[path[-1]], Y[:-1], Y[1:]).min())
                   for Y in (np.vstack([centre[None], X[q]]) for j, q in enumerate(paths) if j != b and q)),
                  default=np.inf)
        if not leaves(off, length, hl, noise):  # (its tip near the other branches: a bend of one)
            continue
        band = ENDTREES.fold_band * hl + noise
        others = [_fill(X, X[q], band) for j, q in enumerate(paths) if j != b and len(q) > 1]
        if others and _fill(X, X[path], band) > ENDTREES.fold * max(others):  # a fold, not a twig
            continue
        arms.append(near[path])
    if not arms or len(owned) + len(arms) < NODES.junction_valence:
        return
    for i, s, k in trims:
        topo.trim_end(i, s, k)
    for i, s, b in reach:  # a chain whose branch holds region points between it and the core
        lead = []
        for v in paths[b]:
            if not inside[v]:
                break
            lead.append(v)
        if lead and len(lead) < len(paths[b]) and near[paths[b][len(lead)]] == topo.end_ids(i, s)[-1]:
            topo.extend_end(i, s, near[lead[::-1]])
    taken = np.concatenate(arms)
    topo.regions[r] = topo.regions[r][~np.isin(topo.regions[r], taken)]
    for arm in arms:
        topo.free_branch(r, arm)
