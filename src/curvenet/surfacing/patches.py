"""Triangulating one patch: a closed 3D polygon filled with a refined, faired triangle mesh.

The polygon's points are the exact boundary: none is added, removed or moved. The polygon is laid
out in a 2D domain (its projection on the best-fit plane when that projection is a simple polygon,
otherwise a circle parametrised by arc length), triangulated there by a constrained, quality
Delaunay triangulation without boundary Steiner points (Shewchuk's Triangle, flags ``pYq``), and the
interior vertices are placed in 3D as a height field over the domain: harmonic, or (fairing) the
solution of a Poisson equation whose right-hand side, the Laplacian of the heights, is read off
the boundary curves (:mod:`curvenet.surfacing.fairing`; where the boundary has no corners, twice
the mean normal curvature of the curves, i.e. a patch of about constant mean curvature), with
the cotangent weights of the domain mesh (Pinkall and Polthier 1993). A biharmonic extension with positional boundary
conditions only was tried and stays much flatter (sphere quads off the sphere by 0.11 radius
against 0.013 here).

A minimal-area triangulation of the polygon (dynamic program of Barequet and Sharir 1995 and Liepa
2003) scores candidate cycles in :mod:`curvenet.surfacing.cycles`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..errors import MethodError, require
from .fairing import boundary_laplacian

__all__ = ["min_area_triangulation", "min_area_triangulations", "triangulate_patch", "is_simple_polygon", "cotan_laplacian",
           "FLAT_CURVATURE", "FLAT_HEIGHT", "MAT_TABLES"]

#: A patch's boundary curves count as about planar (no curvature of their own to fair by, so the
#: slopes of the curves continuing into the patch give its curvature) when their mean normal
#: curvature times the patch size is below this ...
FLAT_CURVATURE = 0.02

#: ... or when their heights over the best-fit plane span less than this fraction of the patch
#: size. The discrete curvature of a reconstructed curve is noisy (a polar cap of the
#: reconstructed sphere model: curvature x size 0.024, height span 0.002 of the size), its
#: heights are not.
FLAT_HEIGHT = 0.01

#: Polygon sizes whose index tables the minimal-area triangulation keeps (:func:`_gap_table`;
#: the candidate cycles are scored on coarse polygons of at most a few sizes each).
MAT_TABLES = 128


def _cross(u, v):
    """Cross product over the last axis (faster than np.cross on small arrays)."""
    return np.stack(
        [
            u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1],
            u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2],
            u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0],
        ],
        axis=-1,
    )


def _tri_area(a, b, c):
    return 0.5 * np.sqrt((_cross(b - a, c - a) ** 2).sum(axis=-1))


@lru_cache(maxsize=MAT_TABLES)
def _gap_table(n: int):
    """Index triples ``(i, k, j)``, ``i < k < j = i + gap``, of a polygon of ``n`` points, by gap.

    Returns ``I, K, J`` (each ``(n (n - 1) (n - 2) / 6,)`` int arrays, ordered by gap, then ``i``,
    then ``k``), the start of each gap's block (``(n + 1,)``, indexed by gap from 2 on) and, per gap, the
    flat indices of ``W[i, k]`` and ``W[k, j]`` in an ``(n, n)`` table.
    """
    Is, Ks, Js, start = [], [], [], np.zeros(n + 1, dtype=np.int64)
    for gap in range(2, n):
        i = np.repeat(np.arange(n - gap), gap - 1)
        k = i + np.tile(np.arange(1, gap), n - gap)
        Is.append(i)
        Ks.append(k)
        Js.append(i + gap)
        start[gap + 1] = start[gap] + len(i)
    I, K, J = (np.concatenate(x) if x else np.zeros(0, dtype=np.int64) for x in (Is, Ks, Js))
    return I, K, J, start, I * n + K, K * n + J


def min_area_triangulation(poly: np.ndarray) -> tuple[float, np.ndarray]:
    """Triangulation of a closed polygon with the least total area, using only its vertices.

    Parameters
    ----------
    poly : (n, 3) ndarray
        The polygon, not repeating its first point, ``n >= 3``.

    Returns
    -------
    area : float
        Total area of the triangulation.
    triangles : (n - 2, 3) ndarray of int
        Vertex indices, oriented like the polygon.

    Notes
    -----
    :func:`min_area_triangulations` on one polygon.
    """
    p = np.asarray(poly, dtype=float)
    if len(p) < 3:
        return 0.0, np.zeros((0, 3), dtype=np.int64)
    areas, tris = min_area_triangulations(p[None])
    return float(areas[0]), tris[0]


def min_area_triangulations(polys: np.ndarray) -> tuple[np.ndarray, list]:
    """Minimal-area triangulations of polygons of the same size, solved together.

    Parameters
    ----------
    polys : (B, n, 3) ndarray
        ``B`` closed polygons of ``n >= 3`` points each, not repeating their first point.

    Returns
    -------
    areas : (B,) ndarray
        Total area of each triangulation.
    triangles : list of (n - 2, 3) ndarray of int
        Vertex indices of each, oriented like its polygon.

    Notes
    -----
    The dynamic program ``W[i, j] = min_k W[i, k] + W[k, j] + area(i, k, j)`` of Barequet and
    Sharir (1995) / Liepa (2003), vectorised over the polygons and ``(i, k)`` for each gap
    ``j - i``, with the areas of all triangles computed at once beforehand (index tables cached
    per ``n``, :func:`_gap_table`): :math:`O(B n^3)` time and memory. Each polygon's result is
    the one it gets alone (the same floating-point operations; ties go to the smallest ``k``).
    """
    p = np.asarray(polys, dtype=float)
    B, n = p.shape[:2]
    I, K, J, start, IK, KJ = _gap_table(n)
    area = _tri_area(p[:, I], p[:, K], p[:, J])
    W = np.zeros((B, n * n))
    arg = np.zeros((B, n * n), dtype=np.int64)
    for gap in range(2, n):
        m = n - gap
        lo, hi = start[gap], start[gap] + m * (gap - 1)
        vals = (W[:, IK[lo:hi]] + W[:, KJ[lo:hi]] + area[:, lo:hi]).reshape(B, m, gap - 1)
        best = np.argmin(vals, axis=2)[..., None]
        cell = np.arange(m) * (n + 1) + gap  # flat index of (i, i + gap)
        W[:, cell] = np.take_along_axis(vals, best, axis=2)[..., 0]
        arg[:, cell] = np.take_along_axis(K[lo:hi].reshape(1, m, gap - 1), best, axis=2)[..., 0]
    arg = arg.reshape(B, n, n)
    return W[:, n - 1].copy(), [_mat_triangles(a) for a in arg]


def _mat_triangles(arg: np.ndarray) -> np.ndarray:
    """Triangles ``(i, k, j)`` of a minimal-area triangulation from its table of best ``k``."""
    n = len(arg)
    tris = []
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        k = arg[i, j]
        tris.append((i, k, j))
        stack.append((i, k))
        stack.append((k, j))
    return np.array(tris, dtype=np.int64)


def is_simple_polygon(q: np.ndarray) -> bool:
    """Whether a closed 2D polygon has no self-intersection (touching counts as one).

    Parameters
    ----------
    q : (n, 2) ndarray

    Notes
    -----
    Only pairs of non-adjacent edges whose midpoints are within the longest edge length can
    meet; they are found with a k-d tree and tested exactly (orientation signs plus a box test
    for collinear pairs), about :math:`O(n \\log n)` for evenly sampled polygons.
    """
    from scipy.spatial import cKDTree

    q = np.asarray(q, dtype=float)
    n = len(q)
    if n < 3:
        return False
    a, b = q, np.roll(q, -1, axis=0)
    scale = float(np.ptp(q, axis=0).max()) or 1.0
    lengths = np.linalg.norm(b - a, axis=1)
    if (lengths <= 1e-12 * scale).any():
        return False
    pairs = cKDTree((a + b) / 2).query_pairs(float(lengths.max()) * (1 + 1e-9), output_type="ndarray")
    if not len(pairs):
        return True
    I, J = pairs.min(axis=1), pairs.max(axis=1)
    valid = (J != I + 1) & ~((I == 0) & (J == n - 1))
    I, J = I[valid], J[valid]
    if not len(I):
        return True
    eps = 1e-12 * scale * scale

    def orient(p, r, s):
        return (r[:, 0] - p[:, 0]) * (s[:, 1] - p[:, 1]) - (r[:, 1] - p[:, 1]) * (s[:, 0] - p[:, 0])

    A, B, C, D = a[I], b[I], a[J], b[J]
    d1, d2 = orient(C, D, A), orient(C, D, B)
    d3, d4 = orient(A, B, C), orient(A, B, D)
    cross = (d1 * d2 <= eps) & (d3 * d4 <= eps)
    tol = 1e-12 * scale
    box = (
        (np.minimum(A[:, 0], B[:, 0]) <= np.maximum(C[:, 0], D[:, 0]) + tol)
        & (np.minimum(C[:, 0], D[:, 0]) <= np.maximum(A[:, 0], B[:, 0]) + tol)
        & (np.minimum(A[:, 1], B[:, 1]) <= np.maximum(C[:, 1], D[:, 1]) + tol)
        & (np.minimum(C[:, 1], D[:, 1]) <= np.maximum(A[:, 1], B[:, 1]) + tol)
    )
    return not bool((cross & box).any())


def _domain(poly: np.ndarray, *, min_stretch: float = 0.2):
    """2D layout of a 3D polygon: best-fit-plane projection if simple, else a circle.

    Returns the 2D points, the kind (``"plane"`` or ``"circle"``) and, for a plane, its centre
    and the (3, 3) orthonormal frame whose last row is the normal.
    """
    c = poly.mean(axis=0)
    _, _, vt = np.linalg.svd(poly - c, full_matrices=False)
    q = (poly - c) @ vt[:2].T
    e3 = np.linalg.norm(np.diff(np.vstack([poly, poly[:1]]), axis=0), axis=1)
    e2 = np.linalg.norm(np.diff(np.vstack([q, q[:1]]), axis=0), axis=1)
    ok = (e3 > 0).all() and (e2 >= min_stretch * e3).all() and is_simple_polygon(q)
    if ok:
        return q, "plane", (c, vt)
    s = np.concatenate([[0.0], np.cumsum(e3)])
    L = s[-1]
    t = 2 * np.pi * s[:-1] / L
    r = L / (2 * np.pi)
    return np.column_stack([r * np.cos(t), r * np.sin(t)]), "circle", None


def cotan_laplacian(V: np.ndarray, T: np.ndarray, *, clip: bool = True):
    """Cotangent Laplacian and lumped (barycentric) mass of a triangle mesh.

    Parameters
    ----------
    V : (n, 2) or (n, 3) ndarray
    T : (t, 3) ndarray of int
    clip : bool
        Clip negative edge weights to zero (keeps the maximum principle of the harmonic map).

    Returns
    -------
    L : (n, n) scipy.sparse.csr_matrix
        Positive semi-definite: ``(L x)_i = sum_j w_ij (x_i - x_j)``.
    M : (n,) ndarray
        Vertex areas.
    """
    Wm, M = _cotan_weights(V, T)
    return _laplacian(Wm, clip), M


def _cotan_weights(V: np.ndarray, T: np.ndarray):
    """Summed cotangent edge weights ``(n, n)`` (CSR, symmetric) and the vertex areas ``(n,)``."""
    from scipy.sparse import coo_matrix

    if V.shape[1] == 2:
        V = np.column_stack([V, np.zeros(len(V))])
    n = len(V)
    I, J = [], []
    ws = []
    for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        # weight of edge (b, c) from the angle at a
        u = V[T[:, b]] - V[T[:, a]]
        v = V[T[:, c]] - V[T[:, a]]
        cr = np.linalg.norm(_cross(u, v), axis=1)
        cot = np.einsum("ij,ij->i", u, v) / np.maximum(cr, 1e-300)
        I.append(T[:, b])
        J.append(T[:, c])
        ws.append(0.5 * cot)
    I = np.concatenate(I)
    J = np.concatenate(J)
    W = np.concatenate(ws)
    Wm = coo_matrix((np.concatenate([W, W]), (np.concatenate([I, J]), np.concatenate([J, I]))), shape=(n, n)).tocsr()
    Wm.sum_duplicates()
    area = _tri_area(V[T[:, 0]], V[T[:, 1]], V[T[:, 2]])
    # the same sums, in the same order, as np.add.at(M, T.ravel(), np.repeat(area / 3, 3))
    M = np.bincount(T.ravel(), weights=np.repeat(area / 3.0, 3), minlength=n)
    return Wm, M


def _laplacian(Wm, clip: bool):
    """``diag(row sums) - W`` of summed edge weights (negative weights set to 0 with ``clip``)."""
    from scipy.sparse import diags

    Wm = Wm.copy()
    if clip:
        Wm.data = np.maximum(Wm.data, 0.0)
    Wm.eliminate_zeros()
    d = np.asarray(Wm.sum(axis=1)).ravel()
    return (diags(d) - Wm).tocsr()


def _extend(L, M, xb: np.ndarray, nb: int, laplacian: float = 0.0) -> np.ndarray:
    """Interior values of the harmonic extension of boundary values ``xb`` (first ``nb`` rows).

    With ``laplacian``, the interior solves the Poisson equation ``Laplacian(x) = laplacian``
    instead (``L x = -laplacian * M`` on the interior rows).
    """
    from scipy.sparse.linalg import spsolve

    Qii = L[nb:, nb:].tocsc()
    Qib = L[nb:, :nb]
    rhs = -(Qib @ xb)
    if np.any(laplacian):
        rhs = rhs - laplacian * M[nb:, None]
    x = spsolve(Qii, rhs)
    return np.asarray(x).reshape(-1, xb.shape[1])


def _harmonic_field(Vd, T, values, known, L=None):
    """Harmonic interpolation over the domain mesh of values given at some boundary points.

    The first ``len(values)`` vertices carry ``values`` where ``known``; every other vertex is
    free (natural boundary condition on the free boundary points). ``L``: the clipped cotangent
    Laplacian of ``(Vd, T)`` if already computed. Returns (N,) values.
    """
    from scipy.sparse.linalg import spsolve

    if L is None:
        L, _ = cotan_laplacian(Vd, T)
    N = len(Vd)
    fixed = np.zeros(N, dtype=bool)
    fixed[: len(values)] = known
    out = np.zeros(N)
    out[: len(values)][known] = values[known]
    free = np.flatnonzero(~fixed)
    if len(free):
        Lf = L[free]
        Lff = Lf[:, free].tocsc()
        rhs = -(Lf[:, np.flatnonzero(fixed)] @ out[fixed])
        out[free] = spsolve(Lff, rhs)
    return out


def _coons_field(Vd, T, values, sides, L=None):
    """Transfinite (Coons) interpolation over a four-sided domain of values given on its sides.

    ``u`` and ``v`` are harmonic coordinates (``u`` 0 on side 0 and 1 on side 2, ``v`` 0 on side 3
    and 1 on side 1, free elsewhere); each side's values are interpolated along its coordinate and
    blended bilinearly: a value that varies along two opposite sides alone (a cylinder's arcs)
    is carried straight across. ``L``: the clipped cotangent Laplacian of ``(Vd, T)`` if already
    computed. Returns (N,) values, or ``None`` if the coordinates degenerate.
    """
    s0, s1, s2, s3 = sides
    nb = len(values)
    if L is None:
        L, _ = cotan_laplacian(Vd, T)

    def coord(zero, one):
        vals = np.zeros(nb)
        known = np.zeros(nb, dtype=bool)
        vals[one], known[one] = 1.0, True
        vals[zero], known[zero] = 0.0, True
        return _harmonic_field(Vd, T, vals, known, L)

    u, v = coord(s0, s2), coord(s3, s1)
    if not (np.isfinite(u).all() and np.isfinite(v).all()):
        return None

    def along(side, t, at):
        o = np.argsort(t[side], kind="stable")
        return np.interp(at, t[side][o], values[side][o])

    F0, F2 = along(s0, v, v), along(s2, v, v)
    F3, F1 = along(s3, u, u), along(s1, u, u)
    c30, c01, c12, c23 = values[s0[0]], values[s0[-1]], values[s2[0]], values[s2[-1]]
    return ((1 - u) * F0 + u * F2 + (1 - v) * F3 + v * F1
            - ((1 - u) * (1 - v) * c30 + (1 - u) * v * c01 + u * v * c12 + u * (1 - v) * c23))


def _mean_normal_curvature(poly, normal, corners, n_outer) -> float:
    """Length-weighted mean of the boundary curves' curvature along ``normal``.

    The discrete curvature vector ``2 / (a + b) * ((p+ - p) / b - (p - p-) / a)`` is taken at
    the points that are not corners (nodes, where curves meet at an angle), on the outer polygon
    (its first ``n_outer`` points) and on each hole.
    """
    pts = np.asarray(poly, dtype=float)
    segs = [(0, n_outer)]
    if len(pts) > n_outer:
        segs.append((n_outer, len(pts)))  # holes are treated as one closed run each (approx.)
    num = den = 0.0
    for lo, hi in segs:
        p = pts[lo:hi]
        if len(p) < 3:
            continue
        pm, pp = np.roll(p, 1, axis=0), np.roll(p, -1, axis=0)
        a = np.linalg.norm(p - pm, axis=1)
        b = np.linalg.norm(pp - p, axis=1)
        ok = (a > 0) & (b > 0)
        if lo == 0 and corners is not None:
            ok &= ~np.asarray(corners, dtype=bool)
        if not ok.any():
            continue
        k = 2.0 / (a[ok] + b[ok])[:, None] * ((pp[ok] - p[ok]) / b[ok][:, None] - (p[ok] - pm[ok]) / a[ok][:, None])
        w = 0.5 * (a[ok] + b[ok])
        num += float((k @ normal) @ w)
        den += float(w.sum())
    return num / den if den > 0 else 0.0


def _slope_curvature(q, poly, c, vt, cross, max_angle: float = 45.0):
    """Mean curvature of a height field from the slopes of curves continuing across its boundary."""
    n = len(q)
    area = abs(0.5 * np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1]))
    perim = float(np.linalg.norm(np.roll(q, -1, axis=0) - q, axis=1).sum())
    if area <= 0:
        return None
    slopes = []
    for i, d in cross:
        d = np.asarray(d, dtype=float)
        dt = d @ vt[:2].T
        ldt = np.linalg.norm(dt)
        if ldt == 0 or np.degrees(np.arctan2(abs(d @ vt[2]), ldt)) > max_angle:
            continue
        u = dt / ldt
        off_edges = True
        for j in (i - 1, (i + 1) % n):
            e = q[j] - q[i]
            le = np.linalg.norm(e)
            if le == 0 or u @ e / le > np.cos(np.radians(20.0)):
                off_edges = False  # runs along the boundary, not into the patch
        if not off_edges:
            continue
        probe = q[i] + 1e-3 * perim * u
        x, y = probe
        a, b = q, np.roll(q, -1, axis=0)
        cond = (a[:, 1] > y) != (b[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
        if (cond & (x < xc)).sum() % 2 == 1:  # enters the patch
            slopes.append((d @ vt[2]) / ldt)  # rise per unit length inward
    if len(slopes) < 3:
        return None
    # outward derivative = -inward slope; Laplacian(h) * area = flux = mean(outward) * perimeter
    return float(-np.mean(slopes) * perim / area / 2.0)


def _ear_points(q, n_outer, idx, sign) -> np.ndarray:
    """Centroids of the ears ``(i - 1, i, i + 1)`` of the outer polygon at the given corners.

    Only convex ears (turning like the polygon) that contain no other polygon point are kept.
    """
    out = []
    for i in idx:
        a, b, c = q[(i - 1) % n_outer], q[i], q[(i + 1) % n_outer]
        cr = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        if cr * sign <= 1e-12 * max(np.ptp(q, axis=0).max(), 1e-300) ** 2:
            continue

        def side(p, r, s):
            return (r[0] - p[0]) * (s[:, 1] - p[1]) - (r[1] - p[1]) * (s[:, 0] - p[0])

        others = np.delete(q, [(i - 1) % n_outer, i, (i + 1) % n_outer], axis=0)
        sg = np.sign(cr)
        inside = (side(a, b, others) * sg > 0) & (side(b, c, others) * sg > 0) & (side(c, a, others) * sg > 0)
        if inside.any():
            continue
        out.append((a + b + c) / 3.0)
    return np.array(out).reshape(-1, 2)


def triangulate_patch(
    poly: np.ndarray,
    *,
    target_edge: float,
    fair: bool = True,
    min_angle: float = 25.0,
    holes: list | None = None,
    corners: np.ndarray | None = None,
    cross: list | None = None,
) -> tuple[np.ndarray, np.ndarray, str]:
    """Fill a closed 3D polygon with a triangle mesh whose boundary is exactly the polygon.

    Parameters
    ----------
    poly : (n, 3) ndarray
        The boundary, in order, not repeating its first point; ``n >= 3`` distinct points.
    target_edge : float
        Target edge length of the interior (Triangle's maximum area is that of an equilateral
        triangle with this side).
    fair : bool
        When the polygon projects simply on its best-fit plane, the patch is a height field over
        the domain mesh. With ``fair``, the heights solve ``Laplacian(h) = f`` with ``f`` read
        off the boundary curves between their corners (see
        :func:`curvenet.surfacing.fairing.boundary_laplacian`; a quarter cylinder keeps its
        arcs' curvature across), interpolated inside (Coons on four sides, harmonic otherwise);
        without corners, ``f = 2 H`` with ``H`` the mean normal curvature of the boundary curves.
        Without ``fair``, the heights are harmonic (a membrane). Otherwise
        (no simple projection) the interior is the harmonic extension of the 3D boundary over a
        disk.
    corners : (n,) ndarray of bool, optional
        Outer polygon points where curves meet at an angle (nodes), left out of the curvature.
    cross : list of (int, (3,) ndarray), optional
        Boundary points with the direction in which a curve leaving the patch there would
        continue into it (the reverse of the curve's tangent). When the boundary curves are
        about planar (no curvature to go by, e.g. a polar cap bounded by a latitude circle),
        the slopes of the continuations that enter the patch at less than 45 degrees from its
        plane give the curvature by the divergence theorem: ``2 H * area = flux of grad h``.
    min_angle : float
        Minimum angle (degrees) asked of Triangle's quality refinement.
    holes : list of (m_i, 3) ndarray, optional
        Closed polygons inside the patch, cut out as holes (used only when the patch is laid out
        on its best-fit plane). Their points follow the outer polygon's in the vertex numbering.

    Returns
    -------
    interior : (k, 3) ndarray
        New interior vertices.
    triangles : (t, 3) ndarray of int
        Indices ``< n`` refer to the polygon (then the holes' points, in order), the next ones to
        ``interior``. Oriented so that each
        triangle's edges on the boundary run in the polygon's direction.
    domain : str
        ``"plane"`` or ``"circle"``: the 2D layout used.

    Raises
    ------
    MissingDependencyError
        If the ``triangle`` package is missing.
    """
    tr = require("triangle", "surfacing (constrained Delaunay triangulation)", "surface")
    poly = np.asarray(poly, dtype=float)
    n = len(poly)
    if n == 3:
        return np.zeros((0, 3)), np.array([[0, 1, 2]], dtype=np.int64), "plane"
    q, kind, frame = _domain(poly)
    n0 = n
    segs = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    amax = np.sqrt(3.0) / 4.0 * target_edge**2
    signed = 0.5 * np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])
    data = {"vertices": q, "segments": segs}
    if holes and kind == "plane":
        c, vt = frame
        qs, ss, hp = [q], [segs], []
        m = n
        for h in holes:
            h = np.asarray(h, dtype=float)
            qh = (h - c) @ vt[:2].T
            k = len(qh)
            qs.append(qh)
            ss.append(m + np.column_stack([np.arange(k), (np.arange(k) + 1) % k]))
            inner = tr.triangulate({"vertices": qh, "segments": ss[-1] - m}, "pQ")
            hp.append(inner["vertices"][inner["triangles"][0]].mean(axis=0))
            poly = np.vstack([poly, h])
            m += k
        q = np.vstack(qs)
        data = {"vertices": q, "segments": np.vstack(ss), "holes": np.array(hp)}
        n = m
    if corners is not None and np.any(corners):
        # an interior point in the ear at each node keeps the ear (two curve samples and the
        # node) out of the triangulation: two patches that run through a node by the same two
        # curves would otherwise both cut the corner by the same chord (a non-manifold edge)
        st = _ear_points(q, n0, np.flatnonzero(np.asarray(corners, dtype=bool)[:n0]), np.sign(signed))
        if len(st):
            data = dict(data)
            data["vertices"] = np.vstack([data["vertices"], st])
    # the domain of a circle has the polygon's arc length, a projection is no larger: same scale
    out = tr.triangulate(data, f"pYQq{min_angle:g}a{amax:.17g}")
    Vd = out["vertices"]
    T = np.asarray(out["triangles"], dtype=np.int64)
    if len(Vd) < n or not np.allclose(Vd[:n], q):
        raise MethodError("the triangulation moved boundary points of a patch")  # not expected: flag Y
    # orientation: make the boundary run in the polygon's direction
    if signed < 0:
        T = T[:, ::-1]
    if len(Vd) == n:
        return np.zeros((0, 3)), T, kind
    if kind == "plane":
        # a height field over the best-fit plane: the tangential layout is the domain mesh
        # itself (its quality is kept); only the heights are extended from the boundary
        c, vt = frame
        Wm, M = _cotan_weights(Vd, T)  # one pass for the plain and the clipped Laplacian
        L, Lc = _laplacian(Wm, clip=False), None
        hb = (poly - c) @ vt[2]
        H = _mean_normal_curvature(poly, vt[2], corners, n0) if fair else 0.0
        size = float(np.ptp(q[:n0], axis=0).max())
        flat = abs(H) * size < FLAT_CURVATURE or float(np.ptp(hb[:n0])) < FLAT_HEIGHT * size
        if fair and cross and flat:
            Hs = _slope_curvature(q[:n0], poly[:n0], c, vt, cross)
            if Hs is not None:
                H = Hs
        lap = 2.0 * H
        bl = boundary_laplacian(q[:n0], hb[:n0], corners) if fair and corners is not None else None
        if bl is not None:
            values, known, sides = bl
            f = None
            Lc = _laplacian(Wm, clip=True)
            if len(sides) == 4 and all(known[sd].all() for sd in sides):
                f = _coons_field(Vd, T, values, sides, Lc)
            if f is None:
                f = _harmonic_field(Vd, T, values, known, Lc)
            lap = f[n:, None]
        hi = _extend(L, M, hb[:, None], n, lap)[:, 0]
        if not np.isfinite(hi).all():
            hi = _extend(_laplacian(Wm, clip=True) if Lc is None else Lc, M, hb[:, None], n)[:, 0]
        X = c + Vd[n:] @ vt[:2] + hi[:, None] * vt[2]
        return X, T, kind
    # circle domain: harmonic extension of the 3D boundary (clipped weights: maximum principle)
    L, M = cotan_laplacian(Vd, T)
    X = _extend(L, M, poly, n)
    return X, T, kind
