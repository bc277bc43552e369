"""Patch boundaries of a curve network: candidate cycles chosen globally by an integer program.

The surfacing step of the paper (Section 3.1, Figure 3(e)) used the cycle discovery of Zhuang et
al. (2013). Local rules (turning to the next curve by angle around a node) fail at concave nodes,
so the cycles here are chosen globally:

1. *Candidates*: the faces of the rotation system given by ordering the curves around each node in
   its estimated tangent plane, the shortest cycle through every corner (pair of curves at a
   node, the rest of the cycle being a shortest path that avoids the node), and every loop.
2. *Scores*: each candidate is spanned by a minimal-area triangulation of a coarse copy of its
   polygon (Barequet and Sharir 1995; Liepa 2003); the area is its cost and the triangulation gives
   the side from which the patch meets each of its curves.
3. *Selection*: a 0-1 integer program (``scipy.optimize.milp``) maximises the number of
   (curve, patch) incidences with every curve bordering at most two patches (one for the curves
   the caller names as the rims of openings: ``open_curves``), then minimises the
   total area. Two candidates that meet a common curve from the same side (folded onto each other,
   e.g. the outer boundary of an open sheet against the sheet's own cells) may not both be chosen;
   this is what keeps an open network open while a closed network gets every curve used twice.
   :func:`curvenet.surfacing.surface` adds geometric conflicts: pairs of chosen patches whose
   meshes cross or lie on each other are forbidden and the program is solved again
   (:func:`select_cycles` with ``conflicts`` and ``banned``).
4. *Orientation*: the chosen cycles are oriented so that two patches run through a shared curve in
   opposite directions. Should the choice be non-orientable (an odd ring of patches), the patch
   whose removal leaves the fewest conflicts is dropped, until none is left.

References
----------
.. [1] T. Zhuang, M. Zou, N. Carr, T. Ju, "A general and efficient method for finding cycles in 3D
   curve networks", ACM Trans. Graph. 32(6), 2013.
.. [2] G. Barequet, M. Sharir, "Filling gaps in the boundary of a polyhedron", CAGD 12(2), 1995.
.. [3] P. Liepa, "Filling holes in meshes", Eurographics Symposium on Geometry Processing, 2003.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from .patches import min_area_triangulations

__all__ = ["CycleSet", "Candidates", "candidate_cycles", "select_cycles", "find_cycles", "prune_dangling", "MAT_BATCH",
           "curve_caps"]

#: Candidate polygons of one size whose minimal-area triangulations are solved together (bounds
#: the memory: a batch of 64-point polygons holds about ``MAT_BATCH`` x 42,000 triangle areas).
MAT_BATCH = 64


@dataclass
class CycleSet:
    """The chosen patch boundaries.

    Attributes
    ----------
    cycles : list of list of int
        Curve ids of each cycle in traversal order.
    directions : list of list of int
        ``+1`` where the cycle runs along a curve from its start to its end, ``-1`` against it.
    n_candidates : int
        Number of distinct candidate cycles scored.
    costs : list of float
        Area of the coarse minimal triangulation of each chosen cycle.
    index : list of int
        The candidate (index into :attr:`Candidates.cycles`) of each chosen cycle.
    """

    cycles: list
    directions: list
    n_candidates: int = 0
    costs: list | None = None
    index: list | None = None


@dataclass
class Candidates:
    """Candidate patch boundaries of a network, scored (see :func:`candidate_cycles`).

    Attributes
    ----------
    cycles : list of list of int
        Each candidate as darts: ``2 c`` runs along curve ``c`` from its start to its end,
        ``2 c + 1`` against it.
    costs : (K,) ndarray
        Area of the coarse minimal triangulation of each candidate.
    inward : list of dict
        Per candidate: curve id -> mean unit vector from the curve into the candidate's
        coarse triangulation.
    n_curves : int
        Number of curves of the network.
    """

    cycles: list
    costs: np.ndarray
    inward: list
    n_curves: int


def prune_dangling(edges: np.ndarray, n_nodes: int) -> np.ndarray:
    """Curves left after removing, repeatedly, the curves that end at a node of valence 1.

    Parameters
    ----------
    edges : (c, 2) ndarray of int
        End nodes of each curve, ``-1`` for a loop without node.
    n_nodes : int

    Returns
    -------
    (c,) ndarray of bool
        True for the curves that can border a patch (loops without nodes included).
    """
    keep = np.ones(len(edges), dtype=bool)
    with_node = edges[:, 0] >= 0
    while True:
        deg = np.zeros(n_nodes + 1, dtype=np.int64)  # slot n_nodes: loops without node
        e = edges[keep & with_node]
        np.add.at(deg, e.ravel(), 1)
        e0 = np.where(with_node, edges[:, 0], n_nodes)
        e1 = np.where(with_node, edges[:, 1], n_nodes)
        bad = keep & with_node & ((deg[e0] == 1) | (deg[e1] == 1))
        if not bad.any():
            return keep
        keep &= ~bad


def _resample(chain: np.ndarray, k: int) -> np.ndarray:
    """``k`` points (ends included) of a polyline, evenly spaced in arc length."""
    if len(chain) <= k:
        return chain
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(chain, axis=0), axis=1))])
    if s[-1] <= 0:
        return chain[[0, -1]]
    t = np.linspace(0.0, s[-1], k)
    out = np.empty((k, chain.shape[1]))
    for j in range(chain.shape[1]):
        out[:, j] = np.interp(t, s, chain[:, j])
    return out


def _point_at(chain: np.ndarray, dist: float) -> np.ndarray:
    """The point at arc length ``dist`` from the start of a polyline."""
    seg = np.linalg.norm(np.diff(chain, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    dist = min(dist, s[-1])
    return np.array([np.interp(dist, s, chain[:, j]) for j in range(chain.shape[1])])


class _Graph:
    """Darts of the core network: dart ``2c`` runs along curve ``c``, dart ``2c + 1`` against it."""

    def __init__(self, chains, edges, keep, nodes):
        self.chains = chains
        self.edges = edges
        self.nodes = nodes
        self.core = [c for c in range(len(edges)) if keep[c] and edges[c, 0] >= 0 and edges[c, 0] != edges[c, 1]]
        self.loops = [c for c in range(len(edges)) if keep[c] and (edges[c, 0] < 0 or edges[c, 0] == edges[c, 1])]
        self.lengths = np.array([np.linalg.norm(np.diff(ch, axis=0), axis=1).sum() for ch in chains])
        self.out = {}  # node -> list of darts leaving it
        for c in self.core:
            self.out.setdefault(int(edges[c, 0]), []).append(2 * c)
            self.out.setdefault(int(edges[c, 1]), []).append(2 * c + 1)

    def tail(self, d):
        return int(self.edges[d // 2, d % 2])

    def head(self, d):
        return int(self.edges[d // 2, 1 - d % 2])

    def chain(self, d):
        ch = self.chains[d // 2]
        return ch if d % 2 == 0 else ch[::-1]


def _node_frames(g: _Graph):
    """Unit normal at each node of the core, consistently signed along the graph."""
    normals = {}
    for v, darts in g.out.items():
        if len(darts) < 3:
            continue
        r = min(g.lengths[d // 2] for d in darts) * 0.25
        t = []
        for d in darts:
            u = _point_at(g.chain(d), r) - g.nodes[v]
            nrm = np.linalg.norm(u)
            if nrm > 0:
                t.append(u / nrm)
        t = np.array(t)
        if len(t) < 2:
            continue
        # normal of the plane through the tips of the unit tangents (for a cone of curves, its
        # axis; for curves in a tangent plane, the plane's normal)
        tc = t - t.mean(axis=0) if len(t) >= 3 else t
        w, vec = np.linalg.eigh(tc.T @ tc)
        normals[v] = vec[:, 0]
    # sign propagation: breadth-first over the graph, from the lowest node (by coordinates)
    order = sorted(normals, key=lambda v: tuple(np.round(g.nodes[v], 9)))
    seen = set()
    for root in order:
        if root in seen:
            continue
        seen.add(root)
        queue = deque([(root, normals[root])])
        while queue:
            v, ref = queue.popleft()
            for d in g.out.get(v, []):
                w = g.head(d)
                if w in seen:
                    continue
                seen.add(w)
                if w in normals:
                    if normals[w] @ ref < 0:
                        normals[w] = -normals[w]
                    queue.append((w, normals[w]))
                else:
                    queue.append((w, ref))
    return normals


def _rotation_faces(g: _Graph, normals) -> list[list[int]]:
    """Faces of the rotation system given by the angular order of the curves around each node."""
    nxt = {}
    for v, darts in g.out.items():
        if len(darts) == 1:
            nxt[darts[0]] = darts[0]
            continue
        n = normals.get(v)
        if n is None or len(darts) == 2:
            order = sorted(darts)
        else:
            a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
            e1 = np.cross(n, a)
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(n, e1)
            r = min(g.lengths[d // 2] for d in darts) * 0.25
            ang = []
            for d in darts:
                u = _point_at(g.chain(d), r) - g.nodes[v]
                ang.append(np.arctan2(u @ e2, u @ e1))
            order = [darts[i] for i in np.argsort(ang, kind="stable")]
        for i, d in enumerate(order):
            nxt[d] = order[(i + 1) % len(order)]
    faces = []
    used = set()
    for start in sorted(nxt):
        if start in used:
            continue
        face = []
        d = start
        while d not in used:
            used.add(d)
            face.append(d)
            d = nxt[d ^ 1]  # arrive at head(d), leave by the dart after the reverse of d
        faces.append(face)
    return faces


def _corner_cycles(g: _Graph) -> list[list[int]]:
    """For every pair of curves at a node, the shortest cycle through both avoiding the node."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    nodes = sorted(g.out)
    if not nodes:
        return []
    idx = {v: i for i, v in enumerate(nodes)}
    m = len(nodes)
    best = {}  # (i, j) -> dart from i to j of the shortest curve
    for c in g.core:
        a, b = idx[int(g.edges[c, 0])], idx[int(g.edges[c, 1])]
        for (i, j, d) in ((a, b, 2 * c), (b, a, 2 * c + 1)):
            if (i, j) not in best or g.lengths[best[(i, j)] // 2] > g.lengths[c]:
                best[(i, j)] = d
    rows = np.array([k[0] for k in best], dtype=np.int64)
    cols = np.array([k[1] for k in best], dtype=np.int64)
    wts = np.array([max(g.lengths[d // 2], 1e-300) for d in best.values()])
    full = csr_matrix((wts, (rows, cols)), shape=(m, m))
    full.sort_indices()
    row_of_entry = np.repeat(np.arange(m), np.diff(full.indptr))
    cycles = []
    for v in nodes:
        darts = g.out[v]
        if len(darts) < 2:
            continue
        iv = idx[v]
        graph = _without_node(full, row_of_entry, iv)
        heads = sorted({idx[g.head(d)] for d in darts})
        dist, pred = dijkstra(graph, directed=True, indices=heads, return_predecessors=True)
        row_of = {h: r for r, h in enumerate(heads)}
        for x in range(len(darts)):
            for y in range(x + 1, len(darts)):
                d1, d2 = darts[x], darts[y]
                a, b = idx[g.head(d1)], idx[g.head(d2)]
                if a == b:
                    cycles.append([d1, d2 ^ 1])
                    continue
                r = row_of[a]
                if not np.isfinite(dist[r, b]):
                    continue
                path = []
                w = b
                while w != a:
                    p = pred[r, w]
                    path.append(best[(p, w)])
                    w = p
                cycles.append([d1] + path[::-1] + [d2 ^ 1])
    return cycles


def _without_node(full, row_of_entry: np.ndarray, iv: int):
    """The graph ``full`` (CSR, sorted indices) less the arcs into and out of node ``iv``.

    The same matrix as building the CSR again from the remaining arcs (same ``indptr``,
    ``indices`` and ``data``), without the conversion from coordinates.

    Parameters
    ----------
    full : (m, m) scipy.sparse.csr_matrix
    row_of_entry : (nnz,) ndarray of int
        Row of each stored entry of ``full``.
    iv : int
    """
    from scipy.sparse import csr_matrix

    keep = (row_of_entry != iv) & (full.indices != iv)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(row_of_entry[keep], minlength=full.shape[0]))])
    return csr_matrix((full.data[keep], full.indices[keep], indptr), shape=full.shape)


def _canonical(cycle: list[int]) -> tuple:
    """An orientation- and rotation-free key of a dart cycle."""
    return tuple(sorted(d // 2 for d in cycle))


def candidate_cycles(
    chains: list[np.ndarray],
    edges: np.ndarray,
    nodes: np.ndarray,
    *,
    coarse_points: int = 64,
) -> Candidates:
    """Candidate patch boundaries of a curve network, each scored by a coarse spanning surface.

    Parameters
    ----------
    chains : list of (m_c, 3) ndarray
        Each curve as a polyline from its start node to its end node (node positions included;
        a loop without node does not repeat its first point).
    edges : (c, 2) ndarray of int
        Start and end node of each curve, ``-1`` for a loop without node.
    nodes : (n, 3) ndarray
        Node positions.
    coarse_points : int
        Size of the coarse polygon on which a candidate's minimal-area triangulation is computed.

    Returns
    -------
    Candidates
        In a deterministic order (sorted by their sets of curves; loops last).

    Notes
    -----
    :math:`O(\\sum_v \\deg(v)^2)` shortest-path cycles plus the rotation faces; each is scored in
    :math:`O(k^3)` for a coarse polygon of ``k <= coarse_points`` points.
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    keep = prune_dangling(edges, len(nodes))
    g = _Graph(chains, edges, keep, nodes)
    raw = []
    if g.core:
        normals = _node_frames(g)
        raw += _rotation_faces(g, normals)
        raw += _corner_cycles(g)
    seen = {}
    for cyc in raw:
        curves = [d // 2 for d in cyc]
        if len(set(curves)) != len(curves):
            continue  # runs twice through a curve: not a disk boundary
        key = _canonical(cyc)
        if key not in seen:
            seen[key] = cyc
    cands = [seen[k] for k in sorted(seen)]
    cands += [[2 * c] for c in g.loops]
    per_curve = {}
    polys, owners = [], []
    for cyc in cands:
        kc = max(2, min(8, coarse_points // len(cyc) + 1))
        poly, owner = [], []
        for d in cyc:
            key = (d // 2, kc)
            if key not in per_curve:
                ch = g.chains[d // 2]
                if g.edges[d // 2, 0] < 0 or g.edges[d // 2, 0] == g.edges[d // 2, 1]:
                    ch = np.vstack([ch, ch[:1]]) if g.edges[d // 2, 0] < 0 else ch
                per_curve[key] = _resample(ch, kc if len(cyc) > 1 else max(kc, coarse_points // 2))
            pts = per_curve[key] if d % 2 == 0 else per_curve[key][::-1]
            poly.append(pts[:-1])
            owner += [d // 2] * (len(pts) - 1)
        polys.append(np.vstack(poly))
        owners.append(np.array(owner))
    # minimal-area triangulations, solved together for the polygons of each size
    costs = np.zeros(len(cands))
    tris = [None] * len(cands)
    by_size = {}
    for k, poly in enumerate(polys):
        if len(poly) >= 3:
            by_size.setdefault(len(poly), []).append(k)
    for ks in by_size.values():
        for lo in range(0, len(ks), MAT_BATCH):
            part = ks[lo:lo + MAT_BATCH]
            areas, ts = min_area_triangulations(np.stack([polys[k] for k in part]))
            for k, a, t in zip(part, areas, ts):
                costs[k], tris[k] = a, t
    inward = [{} if tris[k] is None else _inward_directions(polys[k], tris[k], owners[k]) for k in range(len(cands))]
    return Candidates(cands, costs, inward, len(edges))


def select_cycles(
    cand: Candidates,
    *,
    fold_angle: float = 30.0,
    time_limit: float = 60.0,
    conflicts=(),
    banned=(),
    open_curves=(),
) -> CycleSet:
    """Choose patch boundaries among candidates by a 0-1 program, and orient them.

    Parameters
    ----------
    cand : Candidates
    fold_angle : float
        Two candidates that meet a common curve from sides closer than this angle (degrees) are
        exclusive.
    time_limit : float
        Seconds allowed to the integer program.
    conflicts : iterable of (int, int)
        More pairs of candidates that may not both be chosen (patches found to cross or cover
        each other, see :func:`curvenet.surfacing.assemble.surface`).
    banned : iterable of int
        Candidates that may not be chosen (a patch that crosses itself).
    open_curves : iterable of int
        Curves that border at most one patch (the rim of an opening the designer left open);
        every other curve borders at most two.

    Returns
    -------
    CycleSet
    """
    if not cand.cycles:
        return CycleSet([], [], 0, [], [])
    cands, costs = cand.cycles, cand.costs
    cap = curve_caps(cand.n_curves, open_curves)
    chosen = _select(cands, costs, cand.inward, cap, fold_angle, time_limit, conflicts, banned)
    # a non-orientable choice (a Moebius-like ring of patches) cannot be oriented: drop, one at
    # a time, the patch whose removal leaves the fewest conflicts (ties: the costliest by area
    # per curve) among those that run the same way through a curve as a neighbour
    cycles, bad = _orient([cands[k] for k in chosen])
    while bad:
        best = None
        for i in bad:
            rest = [k for j, k in enumerate(chosen) if j != i]
            left = len(_orient([cands[k] for k in rest])[1])
            key = (left, -costs[chosen[i]] / len(cands[chosen[i]]), chosen[i])
            if best is None or key < best[0]:
                best = (key, i)
        chosen = [k for j, k in enumerate(chosen) if j != best[1]]
        cycles, bad = _orient([cands[k] for k in chosen])
    return CycleSet(
        [[d // 2 for d in c] for c in cycles],
        [[1 if d % 2 == 0 else -1 for d in c] for c in cycles],
        len(cands),
        [float(costs[k]) for k in chosen],
        [int(k) for k in chosen],
    )


def find_cycles(
    chains: list[np.ndarray],
    edges: np.ndarray,
    nodes: np.ndarray,
    *,
    fold_angle: float = 30.0,
    coarse_points: int = 64,
    time_limit: float = 60.0,
    open_curves=(),
) -> CycleSet:
    """Choose the patch boundaries of a curve network (:func:`candidate_cycles`, then
    :func:`select_cycles` without geometric conflicts).

    Parameters
    ----------
    chains, edges, nodes, coarse_points
        As for :func:`candidate_cycles`.
    fold_angle, time_limit, open_curves
        As for :func:`select_cycles`.

    Returns
    -------
    CycleSet
    """
    cand = candidate_cycles(chains, edges, nodes, coarse_points=coarse_points)
    return select_cycles(cand, fold_angle=fold_angle, time_limit=time_limit, open_curves=open_curves)


def _inward_directions(poly, tris, owner):
    """Mean unit vector, per curve, from the polygon edges into the spanning triangulation.

    At each polygon edge ``e`` the inward direction is ``n x e`` with ``n`` the normal of the
    triangle on that edge, or, where that triangle is a sliver (collinear samples of a straight
    curve give zero-area triangles of equal cost), the normal of the polygon's vector area.
    """
    n = len(poly)
    third = {}
    for t in tris:
        for a, b, c in ((t[0], t[1], t[2]), (t[1], t[2], t[0]), (t[2], t[0], t[1])):
            if (b - a) % n == 1:
                third[a] = c
    nxt = np.roll(poly, -1, axis=0)
    N = 0.5 * np.cross(poly, nxt).sum(axis=0)
    lN = np.linalg.norm(N)
    e = nxt - poly
    le = np.linalg.norm(e, axis=1)
    thr = np.array([third.get(i, -1) for i in range(n)])
    has = thr >= 0
    cr = np.zeros_like(poly)
    cr[has] = np.cross(e[has], poly[thr[has]] - poly[has])
    lc = np.linalg.norm(cr, axis=1)
    good = has & (lc > 0.1 * le * le) & (le > 0)
    nrm = np.zeros_like(poly)
    nrm[good] = cr[good] / lc[good, None]
    if lN > 0:
        nrm[~good] = N / lN
    u = np.cross(nrm, e)
    nu = np.linalg.norm(u, axis=1)
    ok = (nu > 0) & (le > 0)
    w = np.zeros_like(poly)
    w[ok] = le[ok, None] * u[ok] / nu[ok, None]
    out = {}
    for c in np.unique(owner[ok]):
        s = w[ok & (owner == c)].sum(axis=0)
        ns = np.linalg.norm(s)
        if ns > 0:
            out[int(c)] = s / ns
    return out


def curve_caps(n_curves: int, open_curves=()) -> np.ndarray:
    """The most patches each curve may border: 2, and 1 for the curves of ``open_curves``.

    Parameters
    ----------
    n_curves : int
    open_curves : iterable of int
        Curve indices, each in ``range(n_curves)``.

    Returns
    -------
    (n_curves,) ndarray of float
    """
    cap = np.full(n_curves, 2.0)
    cap[np.asarray(list(open_curves), dtype=np.int64)] = 1.0
    return cap


def _select(cands, costs, inward, cap, fold_angle, time_limit, extra=(), banned=()):
    """Solve the 0-1 program (each curve ``c`` bordering at most ``cap[c]`` chosen candidates);
    returns the indices of the chosen candidates."""
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import coo_matrix

    K = len(cands)
    rows, cols = [], []
    by_curve = {}
    for k, cyc in enumerate(cands):
        for d in cyc:
            rows.append(d // 2)
            cols.append(k)
            by_curve.setdefault(d // 2, []).append(k)
    n_curves = len(cap)
    A = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_curves, K)).tocsr()
    cos_max = np.cos(np.radians(fold_angle))
    conflicts = set()
    for c, ks in by_curve.items():
        for i in range(len(ks)):
            for j in range(i + 1, len(ks)):
                a, b = inward[ks[i]].get(c), inward[ks[j]].get(c)
                if a is not None and b is not None and a @ b > cos_max:
                    conflicts.add((ks[i], ks[j]))
    conflicts.update((min(a, b), max(a, b)) for a, b in extra if a != b)
    ub = np.ones(K)
    ub[list(banned)] = 0.0
    constraints = [LinearConstraint(A, -np.inf, cap)]
    if conflicts:
        cr = np.repeat(np.arange(len(conflicts)), 2)
        cc = np.array(sorted(conflicts)).ravel()
        C = coo_matrix((np.ones(len(cc)), (cr, cc)), shape=(len(conflicts), K)).tocsr()
        constraints.append(LinearConstraint(C, -np.inf, 1.0))
    size = np.array([len(c) for c in cands], dtype=float)
    total = float(costs.sum()) or 1.0
    obj = -size + 0.999 * costs / total
    res = milp(
        obj,
        constraints=constraints,
        integrality=np.ones(K),
        bounds=Bounds(0, ub),
        options={"time_limit": time_limit, "disp": False},
    )
    if res.x is None:
        return _greedy(cands, costs, conflicts, cap, banned)
    return [k for k in range(K) if res.x[k] > 0.5]


def _greedy(cands, costs, conflicts, cap, banned=()):
    """Fallback selection: cheapest area per curve first, respecting the same constraints."""
    use = np.zeros(len(cap), dtype=np.int64)
    bad = {}
    for a, b in conflicts:
        bad.setdefault(a, set()).add(b)
        bad.setdefault(b, set()).add(a)
    chosen = []
    for k in np.argsort(costs / np.maximum([len(c) for c in cands], 1), kind="stable"):
        cur = [d // 2 for d in cands[k]]
        if k in banned:
            continue
        if (use[cur] < cap[cur]).all() and not (bad.get(k, set()) & set(chosen)):
            use[cur] += 1
            chosen.append(int(k))
    return sorted(chosen)


def _orient(cycles: list[list[int]]):
    """Reverse cycles so that two cycles sharing a curve run through it in opposite directions.

    Returns the oriented cycles and the indices of the cycles left running the same way as a
    neighbour through a shared curve (empty when the arrangement is orientable).
    """
    by_curve = {}
    for k, cyc in enumerate(cycles):
        for d in cyc:
            by_curve.setdefault(d // 2, []).append(k)
    flip = [None] * len(cycles)
    for root in range(len(cycles)):
        if flip[root] is not None:
            continue
        flip[root] = False
        queue = deque([root])
        while queue:
            k = queue.popleft()
            for d in cycles[k]:
                dk = d ^ int(flip[k])  # dart as traversed after flipping
                for m in by_curve[d // 2]:
                    if m == k or flip[m] is not None:
                        continue
                    dm = next(e for e in cycles[m] if e // 2 == d // 2)
                    flip[m] = dm == dk  # same direction: reverse m
                    queue.append(m)
    out = []
    for cyc, f in zip(cycles, flip):
        out.append([d ^ 1 for d in reversed(cyc)] if f else list(cyc))
    bad = set()
    for c, ks in by_curve.items():
        if len(ks) == 2:
            d0 = next(e for e in out[ks[0]] if e // 2 == c)
            d1 = next(e for e in out[ks[1]] if e // 2 == c)
            if d0 == d1:
                bad.update(ks)
    return out, sorted(bad)
