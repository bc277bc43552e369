"""Checks of a surfaced mesh: self-intersections, non-manifold edges, boundary loops, genus, overlap.

:func:`check_mesh` measures a :class:`~curvenet.surfacing.SurfaceMesh` and names the patches
involved in each failed check. The self-intersection test is MeshLab's
(``compute_selection_by_self_intersections_per_face`` of ``pymeshlab``, extra ``surface``), each
face it selects confirmed by libigl's exact triangle-triangle test; the
other checks are counted here with numpy/scipy from the triangle list.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "MeshChecks",
    "SurfaceCheckWarning",
    "check_mesh",
    "self_intersecting_faces",
    "OVERLAP_DISTANCE",
    "OVERLAP_CURVE_MARGIN",
    "OVERLAP_MIN_TRIANGLES",
]

#: Two patches overlap where the centroid of a triangle of one projects inside a triangle of the
#: other at less than this distance (in units of the mesh's target edge length) from its plane:
#: sheets this close cover the same region twice.
OVERLAP_DISTANCE = 0.5

#: Triangles whose centroid lies within this distance (in target edge lengths) of a curve point
#: are left out of the overlap test: two patches meet along their common curves.
OVERLAP_CURVE_MARGIN = 2.0

#: A pair of patches counts as overlapping from this many overlapping triangles on.
OVERLAP_MIN_TRIANGLES = 3


class SurfaceCheckWarning(UserWarning):
    """A surfaced mesh failed a check (crossing faces, non-manifold edges, overlapping patches)."""


@dataclass(frozen=True)
class MeshChecks:
    """What :func:`check_mesh` measured.

    Attributes
    ----------
    self_intersecting_faces : int or None
        Triangles that cross another triangle (MeshLab's test confirmed by libigl's, see
        :func:`self_intersecting_faces`); ``None`` when those packages are not installed.
    non_manifold_edges : int
        Edges used by more than two triangles.
    boundary_loops : int
        Closed loops of edges used by one triangle (0 for a closed mesh).
    components : int
        Connected pieces (triangles joined by edges).
    genus : int or None
        ``(2 C - B - chi) / 2`` for ``C`` components, ``B`` boundary loops and Euler
        characteristic ``chi``; ``None`` when the mesh is not edge-manifold (undefined).
    overlaps : list of tuple of int
        Pairs of patches that cover the same region (see :data:`OVERLAP_DISTANCE`).
    overlap_triangles : int
        Triangles that lie on another patch's sheet.
    patches : dict
        Check name (``"self_intersections"``, ``"non_manifold_edges"``, ``"overlaps"``) -> sorted
        list of the patch ids involved, for the checks that failed.
    """

    self_intersecting_faces: int | None
    non_manifold_edges: int
    boundary_loops: int
    components: int
    genus: int | None
    overlaps: list = field(default_factory=list)
    overlap_triangles: int = 0
    patches: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when no triangle crosses another, every edge is manifold and no patches overlap."""
        return not self.patches

    def summary(self) -> str:
        """One line of the figures, e.g. ``0 self-intersecting faces, 0 non-manifold edges, ...``."""
        si = "self-intersections not tested" if self.self_intersecting_faces is None else (
            f"{self.self_intersecting_faces} self-intersecting faces")
        genus = "genus undefined" if self.genus is None else f"genus {self.genus}"
        return (f"{si}, {self.non_manifold_edges} non-manifold edges, {self.boundary_loops} boundary "
                f"loops, {genus}, {len(self.overlaps)} overlapping patch pairs")

    def warning(self) -> str | None:
        """A one-line warning naming the patches of each failed check, or ``None``."""
        if self.ok:
            return None
        what = {"self_intersections": "self-intersecting faces", "non_manifold_edges": "non-manifold edges",
                "overlaps": "overlapping patches"}
        parts = [f"{what[k]} in patches {', '.join(map(str, v))}" for k, v in self.patches.items()]
        return "surface check failed: " + "; ".join(parts)


def self_intersecting_faces(vertices: np.ndarray, triangles: np.ndarray, *, confirm: bool = True) -> np.ndarray:
    """Mask of the triangles that intersect another triangle.

    MeshLab's test (``compute_selection_by_self_intersections_per_face`` of ``pymeshlab``)
    selects the faces; with ``confirm``, each selected face is kept only if libigl's exact test
    (``igl.tri_tri_intersection_test_3d``) finds it crossing another selected face (MeshLab also
    selects exactly coplanar triangles whose bounding boxes meet but that do not touch).

    Parameters
    ----------
    vertices : (V, 3) ndarray
    triangles : (T, 3) ndarray of int
    confirm : bool

    Returns
    -------
    (T,) ndarray of bool

    Raises
    ------
    MissingDependencyError
        If ``pymeshlab`` or (with ``confirm``) ``libigl`` (extra ``surface``) is missing.
    """
    from ..errors import require

    ml = require("pymeshlab", "the self-intersection test of surfaces", "surface")
    V = np.asarray(vertices, dtype=np.float64)
    T = np.asarray(triangles, dtype=np.int32).reshape(-1, 3)
    if not len(T):
        return np.zeros(0, dtype=bool)
    ms = ml.MeshSet()
    ms.add_mesh(ml.Mesh(vertex_matrix=V, face_matrix=T))
    ms.compute_selection_by_self_intersections_per_face()
    mask = np.asarray(ms.current_mesh().face_selection_array(), dtype=bool)
    if confirm and mask.any():
        mask = _confirm(V, T, mask, require("igl", "the self-intersection test of surfaces", "surface", "libigl"))
    return mask


def _confirm(V, T, mask, igl):
    """The selected faces that libigl finds crossing another selected face (touching excluded)."""
    from scipy.spatial import cKDTree

    F = np.flatnonzero(mask)
    cen = V[T[F]].mean(axis=1)
    rad = np.linalg.norm(V[T[F]] - cen[:, None, :], axis=2).max(axis=1)
    pairs = cKDTree(cen).query_pairs(2 * float(rad.max()) * (1 + 1e-9), output_type="ndarray")
    out = np.zeros(len(T), dtype=bool)
    scale = float(np.ptp(V, axis=0).max()) or 1.0
    for i, j in pairs:
        a, b = T[F[i]], T[F[j]]
        shared = set(a.tolist()) & set(b.tolist())
        if len(shared) >= 2 or np.linalg.norm(cen[i] - cen[j]) > rad[i] + rad[j]:
            continue
        A, B = V[a], V[b]
        hit, coplanar, p, q = igl.tri_tri_intersection_test_3d(A[0:1], A[1:2], A[2:3], B[0:1], B[1:2], B[2:3])
        if not hit:
            continue
        if shared:  # touching at the shared vertex only is not a crossing
            if coplanar:  # no segment is returned then: a fan around the vertex, taken as touching
                continue
            v = V[next(iter(shared))]
            p, q = np.asarray(p).ravel(), np.asarray(q).ravel()
            if len(p) == 3 and len(q) == 3 and max(np.linalg.norm(p - v), np.linalg.norm(q - v)) <= 1e-9 * scale:
                continue
        out[F[i]] = out[F[j]] = True
    return out


def _edges(T: np.ndarray):
    """Unique sorted edges, the edge of each (triangle, side) slot and the use counts."""
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    nv = int(T.max()) + 1
    k, first, inv, cnt = np.unique(e[:, 0] * nv + e[:, 1], return_index=True, return_inverse=True,
                                   return_counts=True)
    return e[first], inv.ravel(), cnt


def _components(n: int, a: np.ndarray, b: np.ndarray) -> tuple[int, np.ndarray]:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    g = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    return connected_components(g, directed=False)


def check_mesh(mesh, *, self_intersections: bool = True) -> MeshChecks:
    """Measure a surfaced mesh.

    Parameters
    ----------
    mesh : SurfaceMesh
    self_intersections : bool
        Run MeshLab's self-intersection test (needs ``pymeshlab``); when ``False`` or when
        ``pymeshlab`` is missing, ``self_intersecting_faces`` is ``None``.

    Returns
    -------
    MeshChecks

    Notes
    -----
    Overlap: see :func:`curvenet.surfacing.crossings.overlapping_patches`, with the constants
    of this module; about :math:`O(T \\log T)`.
    """
    from ..errors import MissingDependencyError
    from .crossings import curve_samples, overlapping_patches

    V = np.asarray(mesh.vertices, dtype=float)
    T = np.asarray(mesh.triangles, dtype=np.int64).reshape(-1, 3)
    P = np.asarray(mesh.patch, dtype=np.int64)
    if not len(T):
        return MeshChecks(0 if self_intersections else None, 0, 0, 0, 0)
    u, inv, cnt = _edges(T)
    face_of = np.tile(np.arange(len(T)), 3)
    patches = {}

    si = None
    if self_intersections:
        try:
            mask = self_intersecting_faces(V, T)
        except MissingDependencyError:
            mask = None
        if mask is not None:
            si = int(mask.sum())
            if si:
                patches["self_intersections"] = sorted({int(p) for p in P[mask]})

    nm = cnt > 2
    if nm.any():
        patches["non_manifold_edges"] = sorted({int(P[f]) for f in face_of[nm[inv]]})

    be = u[cnt == 1]
    if len(be):
        ids, lab = np.unique(be, return_inverse=True)
        lab = lab.reshape(-1, 2)
        loops, _ = _components(len(ids), lab[:, 0], lab[:, 1])
    else:
        loops = 0

    # triangles joined by a shared edge
    order = np.argsort(inv, kind="stable")
    si_, sf = inv[order], face_of[order]
    same = si_[1:] == si_[:-1]
    ncomp, _ = _components(len(T), sf[:-1][same], sf[1:][same])

    used = len(np.unique(T))
    chi = used - len(u) + len(T)
    genus = None if nm.any() else (2 * ncomp - loops - chi) // 2

    h = float(mesh.stats.get("target_edge", 0.0)) if mesh.stats else 0.0
    if h <= 0:
        h = float(np.median(np.linalg.norm(V[u[:, 0]] - V[u[:, 1]], axis=1)))
    curve_points = curve_samples(V, mesh.curve_vertices or [], h / 2)
    pairs, n_over = overlapping_patches(V, T, P, curve_points, distance=OVERLAP_DISTANCE * h,
                                        margin=OVERLAP_CURVE_MARGIN * h, min_triangles=OVERLAP_MIN_TRIANGLES)
    if pairs:
        patches["overlaps"] = sorted({k for pr in pairs for k in pr})
    return MeshChecks(si, int(nm.sum()), int(loops), int(ncomp), genus, pairs, n_over, patches)
