"""Surfacing a curve network: cycles, patches, one shared-vertex mesh (the paper's third step)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError
from ..network import CurveNetwork
from .checks import MeshChecks, SurfaceCheckWarning, check_mesh
from .cycles import candidate_cycles, select_cycles
from .patches import triangulate_patch

__all__ = ["SurfaceMesh", "surface", "MAX_SELECTION_ROUNDS"]

#: Times the cycle selection is solved again with the pairs of patches found crossing or lying
#: on each other forbidden; patches still in conflict after the last round are dropped.
MAX_SELECTION_ROUNDS = 30


@dataclass
class SurfaceMesh:
    """A triangle mesh made of patches bounded by cycles of curves.

    Parameters
    ----------
    vertices : (V, 3) ndarray of float
        One vertex per node, per curve sample point and per interior patch vertex.
    triangles : (T, 3) ndarray of int
        Vertex indices, consistently oriented (outward on closed components).
    patch : (T,) ndarray of int
        The patch (index into ``cycles``) of each triangle.
    cycles : list of list of int
        Curve ids around each patch, in order; for a patch with holes (loops without node lying
        on it), the loops follow the outer cycle.
    directions : list of list of int
        ``+1`` where the patch boundary runs along a curve from its start to its end (the
        boundary of each patch runs counter-clockwise seen from the side its normals point to),
        ``-1`` against it.
    curve_vertices : list of (m_c,) ndarray of int
        Mesh vertex of each point of each curve, from its start node to its end node (``None``
        for a dangling curve no patch uses, whose points are not in the mesh).
    stats : dict
        ``time`` (seconds per stage), ``candidates`` (cycles scored), ``domains`` (count of
        patches laid out on their best-fit plane or on a circle), ``target_edge``,
        ``chord_splits`` (interior edges split because two patches shared them),
        ``selection_rounds`` (times the cycle selection was solved), ``conflicts`` (pairs of
        candidate patches found crossing or lying on each other, forbidden), ``folded``
        (candidates found crossing themselves, banned).
    checks : MeshChecks or None
        Self-intersections, non-manifold edges, boundary loops, genus and overlapping patches
        of the mesh (see :func:`curvenet.surfacing.check_mesh`); ``None`` when not checked.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    patch: np.ndarray
    cycles: list
    directions: list
    curve_vertices: list = field(default_factory=list)
    stats: dict[str, Any] = field(default_factory=dict)
    checks: MeshChecks | None = None

    @property
    def n_patches(self) -> int:
        return len(self.cycles)

    @property
    def edges(self) -> np.ndarray:
        """(E, 2) int array of the unique undirected edges, each sorted."""
        e = np.sort(np.concatenate([self.triangles[:, [0, 1]], self.triangles[:, [1, 2]], self.triangles[:, [2, 0]]]), axis=1)
        return np.unique(e, axis=0) if len(e) else np.zeros((0, 2), dtype=np.int64)

    @property
    def euler_characteristic(self) -> int:
        """``V - E + F`` over the vertices used by triangles."""
        used = len(np.unique(self.triangles)) if len(self.triangles) else 0
        return int(used - len(self.edges) + len(self.triangles))

    def boundary_edges(self) -> np.ndarray:
        """(B, 2) int array of the edges used by exactly one triangle, sorted."""
        e = np.sort(np.concatenate([self.triangles[:, [0, 1]], self.triangles[:, [1, 2]], self.triangles[:, [2, 0]]]), axis=1)
        if not len(e):
            return e
        u, cnt = np.unique(e, axis=0, return_counts=True)
        return u[cnt == 1]

    def to_trimesh(self):
        """The mesh as a ``trimesh.Trimesh`` (extra ``surface``), patch ids as face attribute."""
        from ..errors import require

        trimesh = require("trimesh", "converting to trimesh", "surface")
        return trimesh.Trimesh(self.vertices, self.triangles, process=False, face_attributes={"patch": self.patch})

    def __repr__(self) -> str:
        return (
            f"SurfaceMesh(vertices={len(self.vertices)}, triangles={len(self.triangles)}, "
            f"patches={self.n_patches}, euler={self.euler_characteristic})"
        )


def _chains(net: CurveNetwork, tol: float):
    """Each curve as a 3D polyline from its start node to its end node (loops without node: open)."""
    nodes = net.nodes
    if nodes.shape[1] == 2:
        nodes = np.column_stack([nodes, np.zeros(len(nodes))])
    chains = []
    for c in net.curves:
        p = np.asarray(c.points, dtype=float)
        if p.ndim != 2 or (len(p) and p.shape[1] not in (2, 3)):
            raise InputError(f"curve points must be (m, 2) or (m, 3), got shape {p.shape}")
        if p.shape[1] == 2:
            p = np.column_stack([p, np.zeros(len(p))])
        if c.start is None:
            if len(p) > 1 and np.linalg.norm(p[0] - p[-1]) <= tol:
                p = p[:-1]
            chains.append(p)
            continue
        a, b = nodes[c.start], nodes[c.end]
        inner = p
        while len(inner) and np.linalg.norm(inner[0] - a) <= tol:
            inner = inner[1:]
        while len(inner) and np.linalg.norm(inner[-1] - b) <= tol:
            inner = inner[:-1]
        chains.append(np.vstack([a[None], inner, b[None]]))
    return nodes, chains


#: Networks whose extent lies within ``2**-UNIT_EXPONENT_LIMIT`` to ``2**UNIT_EXPONENT_LIMIT``
#: (about 1e-18 to 1e18) are surfaced as they are; others are first scaled by a power of two
#: (exact) to an extent near 1 (:func:`surface`).
UNIT_EXPONENT_LIMIT = 60


def _unit_exponent(extent: float) -> int:
    """0 for an extent within the ordinary range, else the power of two that brings it near 1."""
    e = int(np.frexp(extent)[1])
    return e if abs(e) > UNIT_EXPONENT_LIMIT else 0


def _scaled(network: CurveNetwork, k: int) -> CurveNetwork:
    """The network with every coordinate multiplied by ``2**k`` (exact)."""
    from ..network import Curve

    curves = [Curve(np.ldexp(np.asarray(c.points, dtype=float), k), c.start, c.end, c.closed, c.indices)
              for c in network.curves]
    return CurveNetwork(np.ldexp(np.asarray(network.nodes, dtype=float), k), curves, dict(network.parameters))


def _curve_ids(ids, n: int) -> tuple[int, ...]:
    """``ids`` (None: none) as sorted, distinct curve indices in ``range(n)``; InputError
    otherwise."""
    out = set()
    for i in () if ids is None else ids:
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)):
            raise InputError(f"curves to leave open are given by their ids (integers), got {i!r}")
        if not 0 <= int(i) < n:
            has = f"{n} curves, numbered 0 to {n - 1}" if n else "no curves"
            raise InputError(f"no curve {int(i)} to leave open (the network has {has})")
        out.add(int(i))
    return tuple(sorted(out))


def surface(
    network: CurveNetwork,
    *,
    target_edge: float | None = None,
    fair: bool = True,
    fold_angle: float = 30.0,
    min_angle: float = 25.0,
    time_limit: float = 60.0,
    max_triangles: int = 200_000,
    check: bool = True,
    open_curves=(),
) -> SurfaceMesh:
    """Surface a curve network: find its patch boundaries and fill each with a triangle mesh.

    Parameters
    ----------
    network : CurveNetwork
        2D or 3D network (2D is surfaced in the plane ``z = 0``). Curves hanging off the rest
        (trees ending at free ends) are ignored; a loop, with or without a node, bounds a patch.
    target_edge : float, optional
        Edge length wanted inside the patches. Default: the median spacing of the curve points,
        raised if needed so that the patches hold about ``max_triangles`` triangles at most (the
        quality triangulation then grades from the boundary spacing to this length).
    fair : bool
        Shape the patch interiors after the curvature of their boundary curves (a Poisson
        equation with the boundary's mean normal curvature, see
        :func:`curvenet.surfacing.patches.triangulate_patch`); ``False``: harmonic membranes.
    fold_angle : float
        Degrees: two cycles meeting a curve from the same side within this angle cannot both be
        patches (see :func:`curvenet.surfacing.cycles.find_cycles`).
    min_angle : float
        Minimum triangle angle asked of the 2D quality triangulation.
    time_limit : float
        Seconds allowed to the integer program choosing the cycles.
    max_triangles : int
        Budget used for the default ``target_edge`` (ignored when ``target_edge`` is given).
    check : bool
        Check the mesh (:func:`curvenet.surfacing.check_mesh`: self-intersections with
        MeshLab's and libigl's tests when ``pymeshlab`` and ``libigl`` are installed,
        non-manifold edges, boundary loops, genus, overlapping patches), store the result in
        ``checks`` and warn (:class:`~curvenet.surfacing.checks.SurfaceCheckWarning`, naming the
        patches) when a check fails.
    open_curves : iterable of int
        Curves (indices into ``network.curves``, as the viewer and the network file number
        them) that border one patch at most: the rims of openings the designer left open. The
        network alone does not say which rings of curves are openings (a vase's mouth and a
        can's lid are the same network), so every ring that can be capped is, unless named here.

    Returns
    -------
    SurfaceMesh
        Vertices shared between patches along the curves (one per curve point and per node),
        consistently oriented triangles, patch id per triangle, and the cycles.

    Raises
    ------
    InputError
        If the network is not a CurveNetwork or ``target_edge`` is not positive.

    Warns
    -----
    SurfaceCheckWarning
        When ``check`` finds crossing faces, non-manifold edges or overlapping patches.

    Notes
    -----
    A network whose extent lies outside ``2**-UNIT_EXPONENT_LIMIT`` to ``2**UNIT_EXPONENT_LIMIT``
    is surfaced scaled by a power of two (exact) and the mesh scaled back, so that coordinates
    of any magnitude float64 holds can be surfaced.

    The paper (Section 3.1, Figure 3(e)) surfaced its networks with the cycle discovery of Zhuang
    et al. (2013) and the triangulation of Zou et al. (2013); this is an independent
    implementation of the same two steps (global cycle selection by a 0-1 program, then
    constrained Delaunay triangulation and fairing per patch).

    Examples
    --------
    >>> import numpy as np
    >>> from curvenet import Curve, CurveNetwork
    >>> t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    >>> ring = Curve(np.column_stack([np.cos(t), np.sin(t), 0 * t]), None, None, closed=True)
    >>> mesh = surface(CurveNetwork(np.zeros((0, 3)), [ring]))
    >>> mesh.n_patches, mesh.euler_characteristic
    (1, 1)
    """
    if not isinstance(network, CurveNetwork):
        raise InputError(f"surface() needs a CurveNetwork, got {type(network).__name__}")
    if target_edge is not None and not (np.isfinite(target_edge) and target_edge > 0):
        raise InputError(f"target_edge must be a positive number, got {target_edge!r}")
    open_curves = _curve_ids(open_curves, len(network.curves))
    t0 = time.perf_counter()
    allpts = [np.asarray(c.points, dtype=float) for c in network.curves if len(c.points)]
    for i, p in enumerate(allpts):
        if not np.isfinite(p).all():
            raise InputError(f"curve {i} has non-finite coordinates (NaN or infinity)")
    if not np.isfinite(network.nodes).all():
        raise InputError("the network has nodes with non-finite coordinates (NaN or infinity)")
    scale = max((float(np.ptp(p, axis=0).max()) for p in allpts), default=1.0) or 1.0
    k = _unit_exponent(scale)
    if k:
        # far outside ordinary units the triangulation and the solvers under- or overflow: the
        # network is surfaced scaled by 2**-k (exact in floating point) and the mesh scaled back
        unit = _scaled(network, -k)
        mesh = surface(unit, target_edge=None if target_edge is None else float(np.ldexp(target_edge, -k)),
                       fair=fair, fold_angle=fold_angle, min_angle=min_angle, time_limit=time_limit,
                       max_triangles=max_triangles, check=check, open_curves=open_curves)
        mesh.vertices = np.ldexp(mesh.vertices, k)
        mesh.stats["target_edge"] = float(np.ldexp(mesh.stats["target_edge"], k))
        return mesh
    tol = 1e-9 * scale
    nodes, chains = _chains(network, tol)
    edges = network.edges
    seg = np.concatenate([np.linalg.norm(np.diff(ch, axis=0), axis=1) for ch in chains] or [np.zeros(0)])
    seg = seg[seg > 0]
    cand = candidate_cycles(chains, edges, nodes)
    cs = select_cycles(cand, fold_angle=fold_angle, time_limit=time_limit, open_curves=open_curves)
    area = float(sum(cs.costs or []))
    if target_edge is not None:
        h = float(target_edge)
        estimate = area / (np.sqrt(3.0) / 4.0 * h * h)
        if estimate > 50 * max(int(max_triangles), 1) and estimate > 1e7:
            raise InputError(
                f"target_edge={target_edge:g} would make about {estimate:.3g} triangles "
                f"(patch area {area:.3g}); give a larger target_edge"
            )
    else:
        h = float(np.median(seg)) if len(seg) else scale / 10
        # equilateral triangles of side h cover sqrt(3)/4 h^2 each
        h = max(h, np.sqrt(area / (np.sqrt(3.0) / 4.0 * max(int(max_triangles), 1))))
    t1 = time.perf_counter()

    # ------------------------------------------------------------------ shared boundary vertices
    verts = [nodes]
    nv = len(nodes)
    curve_vertices = [None] * len(chains)
    cand_curves = sorted({d // 2 for cyc in cand.cycles for d in cyc})
    for c in cand_curves:
        ch = chains[c]
        if edges[c, 0] < 0:
            ids = nv + np.arange(len(ch))
            verts.append(ch)
            nv += len(ch)
        else:
            inner = ch[1:-1]
            ids = np.concatenate([[edges[c, 0]], nv + np.arange(len(inner)), [edges[c, 1]]])
            verts.append(inner)
            nv += len(inner)
        curve_vertices[c] = ids.astype(np.int64)
    Vb = np.vstack(verts)
    # at each node, the direction of every curve leaving it (for cross-boundary slopes)
    leaving = {}
    for c in cand_curves:
        if edges[c, 0] >= 0:
            ch = chains[c]
            for v, d in ((edges[c, 0], _tangent(ch)), (edges[c, 1], _tangent(ch[::-1]))):
                leaving.setdefault(int(v), []).append((c, d))

    # ------------------------------------------------------------------ patches, conflicts
    # each candidate is meshed once, in its own orientation; a selection whose patches cross or
    # lie on each other gets those pairs forbidden and is solved again
    patches = _PatchCache(cand, curve_vertices, edges, Vb, len(nodes), leaving, nv,
                          dict(target_edge=h, fair=fair, min_angle=min_angle))
    conflicts, banned = set(), set()
    rounds = 0
    while True:
        rounds += 1
        rings = [patches.ring(k) for k in cs.index]
        holes = _find_holes(cs.cycles, rings, Vb, edges)
        skip = {(min(cs.index[j], cs.index[k]), max(cs.index[j], cs.index[k])) for j, ks in holes.items() for k in ks}
        new_pairs, new_banned = patches.conflicts(cs.index, skip, h)
        new_pairs -= conflicts
        new_banned -= banned
        if not new_pairs and not new_banned:
            break
        conflicts |= new_pairs
        banned |= new_banned
        if rounds >= MAX_SELECTION_ROUNDS:
            cs = _drop_conflicting(cs, cand, conflicts, banned)
            break
        cs = select_cycles(cand, fold_angle=fold_angle, time_limit=time_limit, conflicts=conflicts, banned=banned,
                           open_curves=open_curves)

    # ------------------------------------------------------------------ final patches
    rings = [patches.ring(k) for k in cs.index]
    holes = _find_holes(cs.cycles, rings, Vb, edges)
    rings = [r if patches.same_direction(k, c, d) else r[::-1]
             for r, k, c, d in zip(rings, cs.index, cs.cycles, cs.directions)]
    tris, pids, domains = [], [], {"plane": 0, "circle": 0}
    for pos, (k, dirs) in enumerate(zip(cs.index, cs.directions)):
        hole_ks = [cs.index[j] for j in holes.get(pos, [])]
        gT, kind = patches.mesh(k, hole_ks)
        if kind is None:
            continue
        if kind != "plane":
            holes.pop(pos, None)
        if not patches.same_direction(k, cs.cycles[pos], dirs):
            gT = gT[:, ::-1]
        domains[kind] += 1
        tris.append(gT)
        pids.append(np.full(len(gT), pos, dtype=np.int64))
    V = patches.vertices()
    T = np.vstack(tris) if tris else np.zeros((0, 3), dtype=np.int64)
    P = np.concatenate(pids) if pids else np.zeros(0, dtype=np.int64)
    t2 = time.perf_counter()

    # ------------------------------------------------------------------ loops cut as holes
    cycles, directions = [list(map(int, c)) for c in cs.cycles], [list(map(int, d)) for d in cs.directions]
    if holes:
        for k, js in holes.items():
            for j in js:
                a, b = int(rings[j][0]), int(rings[j][1])  # rings[j] runs along directions[j][0]
                host_ab = _has_edge(T[P == k], a, b)
                disk_ab = _has_edge(T[P == j], a, b)
                host_dir = directions[j][0] if host_ab else -directions[j][0]
                if disk_ab == host_ab:  # both run the same way: turn the disk over
                    T[P == j] = T[P == j][:, ::-1]
                directions[j] = [-host_dir]
                cycles[k].append(cycles[j][0])
                directions[k].append(host_dir)

    # ------------------------------------------------------------------ shared chords
    V, T, P, n_split = _split_shared_chords(V, T, P)

    # ------------------------------------------------------------------ outward on closed parts
    _orient_outward(V, T, P, cycles, directions)

    # ------------------------------------------------------------------ drop unused vertices
    final_curves = {c for cyc in cycles for c in cyc}
    curve_vertices = [ids if c in final_curves else None for c, ids in enumerate(curve_vertices)]
    used = np.zeros(len(V), dtype=bool)
    used[T.ravel()] = True
    new = np.cumsum(used) - 1
    V, T = V[used], new[T]
    curve_vertices = [None if ids is None else new[ids] for ids in curve_vertices]
    t3 = time.perf_counter()
    mesh = SurfaceMesh(
        V,
        T,
        P,
        cycles,
        directions,
        curve_vertices,
        {
            "time": {"cycles": t1 - t0, "patches": t2 - t1, "assembly": t3 - t2},
            "candidates": cs.n_candidates,
            "domains": domains,
            "target_edge": h,
            "chord_splits": n_split,
            "selection_rounds": rounds,
            "conflicts": len(conflicts),
            "folded": len(banned),
            "open_curves": list(open_curves),
        },
    )
    if check:
        mesh.checks = check_mesh(mesh)
        mesh.stats["time"]["checks"] = time.perf_counter() - t3
        msg = mesh.checks.warning()
        if msg:
            import warnings

            warnings.warn(msg, SurfaceCheckWarning, stacklevel=2)
    return mesh


class _PatchCache:
    """Each candidate cycle meshed at most once (in its own orientation), in global vertex ids.

    Boundary vertices (nodes and curve points) are shared by all candidates; the interior
    vertices of each meshed candidate are appended to one growing list.
    """

    def __init__(self, cand, curve_vertices, edges, Vb, n_nodes, leaving, nv, options):
        self.cand = cand
        self.curve_vertices = curve_vertices
        self.edges = edges
        self.Vb = Vb
        self.n_nodes = n_nodes
        self.leaving = leaving
        self.nv = nv
        self.options = options
        self.extra = []
        self.meshes = {}  # (k, holes) -> (global triangles, kind)
        self.tested = []  # selections tested (sets of candidates): their pairs are known
        self.curve_keys = None
        self.curve_pts = None

    def ring(self, k):
        """Boundary vertex ids of candidate ``k``, along its darts."""
        ring = []
        for d in self.cand.cycles[k]:
            c, s = d // 2, d % 2 == 0
            ids = self.curve_vertices[c]
            if self.edges[c, 0] < 0:
                ring.append(ids if s else ids[::-1])
            else:
                ring.append(ids[:-1] if s else ids[::-1][:-1])
        return np.concatenate(ring)

    def same_direction(self, k, cycle, directions) -> bool:
        """Whether an oriented cycle runs like candidate ``k``'s darts."""
        d = 2 * cycle[0] + (0 if directions[0] > 0 else 1)
        return d in self.cand.cycles[k]

    def mesh(self, k, holes=()):
        """(global triangles, domain kind) of candidate ``k`` (``kind`` None: too short)."""
        key = (k, tuple(holes))
        if key in self.meshes:
            return self.meshes[key]
        ring = self.ring(k)
        if len(ring) < 3:
            self.meshes[key] = (np.zeros((0, 3), dtype=np.int64), None)
            return self.meshes[key]
        curves = {d // 2 for d in self.cand.cycles[k]}
        hole_rings = [self.ring(j) for j in holes]
        interior, T, kind = triangulate_patch(
            self.Vb[ring], holes=[self.Vb[r] for r in hole_rings], corners=ring < self.n_nodes,
            cross=[(i, -d) for i, v in enumerate(ring) if v < self.n_nodes
                   for c, d in self.leaving.get(int(v), []) if c not in curves],
            **self.options,
        )
        if kind != "plane":
            hole_rings = []
        full = np.concatenate([ring, *hole_rings]) if hole_rings else ring
        gid = np.concatenate([full, self.nv + np.arange(len(interior))])
        self.extra.append(interior)
        self.nv += len(interior)
        self.meshes[key] = (gid[T], kind)
        return self.meshes[key]

    def vertices(self):
        return np.vstack([self.Vb, *self.extra]) if self.extra else self.Vb

    def conflicts(self, chosen, skip, h):
        """Pairs of chosen candidates that cross or lie on each other, and those that fold.

        ``skip``: candidate pairs not to report (a loop cut out of the patch it lies on). Pairs
        of candidates both tested in an earlier call are not tested again.
        """
        from .checks import OVERLAP_CURVE_MARGIN, OVERLAP_DISTANCE, OVERLAP_MIN_TRIANGLES
        from .crossings import crossing_patches, curve_samples, overlapping_patches

        parts = [(pos, self.mesh(k)) for pos, k in enumerate(chosen)]
        parts = [(pos, t, kind) for pos, (t, kind) in parts if len(t)]
        if not parts:
            return set(), set()
        T = np.vstack([t for _, t, _ in parts])
        P = np.concatenate([np.full(len(t), pos, dtype=np.int64) for pos, t, _ in parts])
        # pairs inside the largest earlier tested selection (restricted to this one) are known
        ids = {chosen[pos] for pos, _, _ in parts}
        known = max((ids & s for s in self.tested), key=len, default=set())
        only = {pos for pos, _, _ in parts if chosen[pos] not in known} if known else None
        folds = {pos for pos, _, kind in parts if kind != "plane" and chosen[pos] not in known}
        V = self.vertices()
        pairs, folded = crossing_patches(V, T, P, only=only, folds=folds)
        if self.curve_pts is None:
            self.curve_pts = curve_samples(self.Vb, self.curve_vertices, h / 2)
        over, _ = overlapping_patches(V, T, P, self.curve_pts, distance=OVERLAP_DISTANCE * h,
                                      margin=OVERLAP_CURVE_MARGIN * h, min_triangles=OVERLAP_MIN_TRIANGLES,
                                      only=only, folds=folds)
        self.tested.append(ids)
        folded |= {a for a, b in over if a == b}
        pairs = set(pairs) | self._shared_chords(T, P)
        out = set()
        for a, b in (set(pairs) | set(over)) - {(a, a) for a in folded}:
            key = (min(chosen[a], chosen[b]), max(chosen[a], chosen[b]))
            if key not in skip:
                out.add(key)
        return out, {chosen[a] for a in folded}


    def _shared_chords(self, T, P):
        """Pairs of patches that both hold an edge not on a curve (folded onto each other there)."""
        nv = 1 << 31  # fixed, so that the curve keys of the first call stay valid
        if self.curve_keys is None:
            keys = []
            for c, ids in enumerate(self.curve_vertices):
                if ids is None or len(ids) < 2:
                    continue
                ring = np.append(ids, ids[0]) if self.edges[c, 0] < 0 else ids
                e = np.sort(np.column_stack([ring[:-1], ring[1:]]), axis=1)
                keys.append(e[:, 0] * nv + e[:, 1])
            self.curve_keys = np.unique(np.concatenate(keys)) if keys else np.zeros(0, np.int64)
        e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
        key = e[:, 0] * nv + e[:, 1]
        keys, kid = np.unique(key, return_inverse=True)
        inner = ~np.isin(keys, self.curve_keys)
        npatch = int(P.max()) + 1
        kp = np.unique(kid.ravel() * npatch + np.tile(P, 3))  # (edge, patch), each once, sorted
        kp = kp[inner[kp // npatch]]
        edge, patch = kp // npatch, kp % npatch
        dup = np.flatnonzero(edge[1:] == edge[:-1])
        return {(int(min(patch[i], patch[i + 1])), int(max(patch[i], patch[i + 1]))) for i in dup}


def _drop_conflicting(cs, cand, conflicts, banned):
    """The selection less its banned patches and, per conflicting pair, the costlier per curve."""
    keep = [k for k in cs.index if k not in banned]
    per = {k: cand.costs[k] / max(len(cand.cycles[k]), 1) for k in keep}
    for a, b in sorted(conflicts):
        if a in per and b in per and a in keep and b in keep:
            keep.remove(max((a, b), key=lambda k: (per[k], k)))
    pos = [i for i, k in enumerate(cs.index) if k in keep]
    return type(cs)([cs.cycles[i] for i in pos], [cs.directions[i] for i in pos], cs.n_candidates,
                    [cs.costs[i] for i in pos], [cs.index[i] for i in pos])


def _edge_keys(T: np.ndarray, nv: int):
    """Unique undirected edges of a triangle list, as ``np.unique(e, axis=0)`` gives them.

    Parameters
    ----------
    T : (t, 3) ndarray of int
    nv : int
        More than the largest vertex id.

    Returns
    -------
    u : (E, 2) ndarray of int
        Unique edges (each sorted), in lexicographic order.
    inv : (3 t,) ndarray of int
        Edge of each (side, triangle) slot, sides ``(0, 1)``, ``(1, 2)``, ``(2, 0)`` of all
        triangles in turn.
    cnt : (E,) ndarray of int
        Slots per edge.

    Notes
    -----
    One sort of the integer keys ``a * nv + b`` (the same order as the rows ``(a, b)``), in
    place of ``np.unique(..., axis=0)``, which sorts rows as structured records.
    """
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    _, first, inv, cnt = np.unique(e[:, 0] * np.int64(nv) + e[:, 1], return_index=True, return_inverse=True,
                                   return_counts=True)
    return e[first], inv.ravel(), cnt


def _orient_outward(V, T, P, cycles, directions):
    """Flip each closed connected component with negative signed volume (in place)."""
    if not len(T):
        return
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nt = len(T)
    f = np.tile(np.arange(nt), 3)
    _, inv, cnt = _edge_keys(T, len(V))
    order = np.argsort(inv, kind="stable")
    si, sf = inv[order], f[order]
    same = si[1:] == si[:-1]
    g = coo_matrix((np.ones(same.sum()), (sf[:-1][same], sf[1:][same])), shape=(nt, nt))
    ncomp, lab = connected_components(g, directed=False)
    edge_closed = cnt[inv] == 2  # per (triangle, edge) slot
    for comp in range(ncomp):
        sel = lab == comp
        if not edge_closed[np.tile(sel, 3)].all():
            continue
        a, b, c = V[T[sel, 0]], V[T[sel, 1]], V[T[sel, 2]]
        vol = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
        if vol < 0:
            T[sel] = T[sel][:, ::-1]
            for k in np.unique(P[sel]):
                cycles[k] = cycles[k][::-1]
                directions[k] = [-d for d in directions[k][::-1]]


def _has_edge(T, a, b) -> bool:
    """Whether one of the triangles has the directed edge ``a -> b``."""
    return bool((((T[:, 0] == a) & (T[:, 1] == b)) | ((T[:, 1] == a) & (T[:, 2] == b)) | ((T[:, 2] == a) & (T[:, 0] == b))).any())


def _inside(pts2, poly2) -> np.ndarray:
    """Even-odd point-in-polygon test, vectorised over points."""
    x, y = pts2[:, 0][:, None], pts2[:, 1][:, None]
    a, b = poly2, np.roll(poly2, -1, axis=0)
    cond = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return ((cond & (x < xc)).sum(axis=1) % 2) == 1


def _find_holes(cycles, rings, Vb, edges, *, flat: float = 0.01) -> dict:
    """Loops without node lying flat inside another (flat) patch: patch -> list of loop patches.

    Such a loop (a speaker cone on a box face) is cut out of the patch as a hole, and its own
    disk fills the hole, instead of a disk lying on top of the patch.
    """
    loops = [k for k, cyc in enumerate(cycles) if len(cyc) == 1 and edges[cyc[0], 0] < 0 and len(rings[k]) >= 3]
    if not loops:
        return {}
    out = {}
    for j, ring in enumerate(rings):
        if j in loops or len(ring) < 3:
            continue
        P = Vb[ring]
        c = P.mean(axis=0)
        _, s, vt = np.linalg.svd(P - c, full_matrices=False)
        size = float(np.ptp(P, axis=0).max())
        if np.abs((P - c) @ vt[2]).max() > flat * size:
            continue
        P2 = (P - c) @ vt[:2].T
        for k in loops:
            if any(k in v for v in out.values()):
                continue
            Q = Vb[rings[k]]
            if np.abs((Q - c) @ vt[2]).max() > flat * size:
                continue
            Q2 = (Q - c) @ vt[:2].T
            if _inside(Q2, P2).all() and not any(_inside(Q2[:1], (Vb[rings[m]] - c) @ vt[:2].T)[0] for m in out.get(j, [])):
                out.setdefault(j, []).append(k)
    return out


def _tangent(chain: np.ndarray, frac: float = 0.1) -> np.ndarray:
    """Unit tangent at the start of a polyline.

    Richardson extrapolation of the secants to the points at ``frac`` and ``2 frac`` of its
    length: ``2 s(f) - s(2f)`` with ``s(f) = (p(f) - p(0)) / f``, exact for parabolas.
    """
    seg = np.linalg.norm(np.diff(chain, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return np.zeros(chain.shape[1])

    def at(t):
        return np.array([np.interp(t, s, chain[:, j]) for j in range(chain.shape[1])])

    t = frac * s[-1]
    d = 2 * (at(t) - chain[0]) / t - (at(2 * t) - chain[0]) / (2 * t)
    return d / (np.linalg.norm(d) or 1.0)


def _split_shared_chords(V, T, P, max_rounds: int = 5):
    """Split chords that two patches share, so that no edge has more than two triangles.

    Where two patches fold onto each other near a node (both run through it by the same two
    curves), their triangulations can join the same boundary points by the same interior edge.
    Such an edge is split in every patch but the first that has it inside, at a point moved a
    quarter of the way toward the opposite vertices (it stays inside the patch's two triangles).

    Returns the new vertices, triangles, patch ids and the number of splits.
    """
    count = 0
    for _ in range(max_rounds):
        u, inv, cnt = _edge_keys(T, len(V))
        bad = np.flatnonzero(cnt > 2)
        if not len(bad):
            break
        f_of = np.tile(np.arange(len(T)), 3)
        new_v, new_t, new_p, drop = [], [], [], set()
        nv = len(V)
        for b in bad:
            a, c = (int(x) for x in u[b])
            faces = [int(f) for f in f_of[inv == b] if int(f) not in drop]
            by_patch = {}
            for f in faces:
                by_patch.setdefault(int(P[f]), []).append(f)
            inside = sorted(k for k, fs in by_patch.items() if len(fs) == 2)
            for k in inside[1:] if len(inside) == len(by_patch) else inside:
                f1, f2 = by_patch[k]
                opp = [int(next(x for x in T[f] if x != a and x != c)) for f in (f1, f2)]
                mid = (V[a] + V[c]) / 2
                m = mid + 0.25 * ((V[opp[0]] + V[opp[1]]) / 2 - mid)
                new_v.append(m)
                mid_id = nv
                nv += 1
                for f in (f1, f2):
                    t = [int(x) for x in T[f]]
                    # the edge (t[i], t[i+1]) or (t[i-1], t[i]) is (a, c) in some direction
                    for j in range(3):
                        p_, q_ = t[j], t[(j + 1) % 3]
                        if {p_, q_} == {a, c}:
                            r_ = t[(j + 2) % 3]
                            new_t += [[p_, mid_id, r_], [mid_id, q_, r_]]
                            new_p += [k, k]
                            break
                    drop.update((f1, f2))
                count += 1
        if not new_v:
            break
        keep = np.ones(len(T), dtype=bool)
        keep[list(drop)] = False
        V = np.vstack([V, np.array(new_v)])
        T = np.vstack([T[keep], np.array(new_t, dtype=np.int64)])
        P = np.concatenate([P[keep], np.array(new_p, dtype=np.int64)])
    return V, T, P, count
