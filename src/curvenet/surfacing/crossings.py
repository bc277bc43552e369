"""Which patches of a triangle mesh cross or cover each other: the selection's conflict tests.

Two triangles that share no vertex cross when an edge of one pierces the other (the segment of
their intersection ends on such edges). The cycle selection of :func:`curvenet.surfacing.surface`
uses this test, and :func:`overlapping_patches` (sheets lying on each other), to forbid pairs of patches that cross; the check reported to the user is MeshLab's
(:func:`curvenet.surfacing.checks.self_intersecting_faces`), independent of this one.
"""

from __future__ import annotations

import numpy as np

__all__ = ["crossing_patches", "overlapping_patches", "curve_samples", "PIERCE_EPS", "SIZE_STEP", "REACH_SLACK", "LEVEL_TAIL"]

#: Barycentric and segment-parameter margin of the piercing test: contacts closer than this to
#: an edge or an end (in relative units) are not crossings (shared curve points touch exactly).
PIERCE_EPS = 1e-9

#: Size ratio between the groups of elements searched together in the broad phase.
SIZE_STEP = 2.0

#: Relative margin added to the bounds of the broad phases (the reach of the overlap test, the
#: grown boxes of the cells of :func:`_pairs_touching`): a bound must not drop, by rounding, a
#: pair that the exact test would keep.
REACH_SLACK = 1e-9

#: Fraction of the balls, at each end of the sizes, put together in one size level of the broad
#: phase of :func:`_pairs_touching` (the smallest with the next level up, the largest in one
#: level of their own): without it, slivers and a few large triangles make many small cells.
LEVEL_TAIL = 0.02

#: Pairs tested per vectorised block (bounds the memory of the test).
_CHUNK = 200_000


def _cross(u, v):
    """Cross product of paired rows, ``(k, 3)``: the same arithmetic as ``np.cross``, faster."""
    return np.column_stack([u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1], u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
                            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]])


def _pierce(p0, p1, a, b, c):
    """Whether segments ``p0 p1`` cross triangles ``a b c`` (rows paired), Moeller-Trumbore.

    Segments parallel to their triangle are tested in its plane (:func:`_coplanar_cross`).
    """
    e1, e2, d = b - a, c - a, p1 - p0
    pv = _cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pv)
    scale = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(d, axis=1)
    ok = np.abs(det) > 1e-12 * np.maximum(scale, 1e-300)
    det = np.where(ok, det, 1.0)
    s = p0 - a
    u = np.einsum("ij,ij->i", s, pv) / det
    q = _cross(s, e1)
    v = np.einsum("ij,ij->i", d, q) / det
    t = np.einsum("ij,ij->i", e2, q) / det
    e = PIERCE_EPS
    hit = ok & (u > e) & (v > e) & (u + v < 1 - e) & (t > e) & (t < 1 - e)
    flat = ~ok
    if flat.any():
        hit[flat] = _coplanar_cross(p0[flat], p1[flat], a[flat], b[flat], c[flat])
    return hit


def _coplanar_cross(p0, p1, a, b, c):
    """Segments lying in their triangle's plane that enter the triangle's interior.

    A segment enters when it properly crosses one of the triangle's edges or has an end strictly
    inside; segments off the plane (parallel, not coplanar) do not.
    """
    n = np.cross(b - a, c - a)
    nn = np.linalg.norm(n, axis=1)
    size = np.maximum(np.linalg.norm(b - a, axis=1) + np.linalg.norm(c - a, axis=1), 1e-300)
    good = nn > PIERCE_EPS * size * size
    nu = n / np.maximum(nn, 1e-300)[:, None]
    off = np.maximum(np.abs(np.einsum("ij,ij->i", p0 - a, nu)), np.abs(np.einsum("ij,ij->i", p1 - a, nu)))
    good &= off <= PIERCE_EPS * size
    # 2D frame of each triangle's plane
    e1 = (b - a) / np.maximum(np.linalg.norm(b - a, axis=1), 1e-300)[:, None]
    e2 = np.cross(nu, e1)

    def flat2(x):
        return np.column_stack([np.einsum("ij,ij->i", x - a, e1), np.einsum("ij,ij->i", x - a, e2)])

    P0, P1, A, B, C = flat2(p0), flat2(p1), flat2(a), flat2(b), flat2(c)
    tol = PIERCE_EPS * size * size

    def orient(p, q, r):
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    hit = np.zeros(len(p0), dtype=bool)
    for X, Y in ((A, B), (B, C), (C, A)):
        d1, d2 = orient(X, Y, P0), orient(X, Y, P1)
        d3, d4 = orient(P0, P1, X), orient(P0, P1, Y)
        hit |= (((d1 > tol) & (d2 < -tol)) | ((d1 < -tol) & (d2 > tol))) & (
            ((d3 > tol) & (d4 < -tol)) | ((d3 < -tol) & (d4 > tol)))
    sgn = np.sign(orient(A, B, C))
    for Q in (P0, P1):
        inside = (orient(A, B, Q) * sgn > tol) & (orient(B, C, Q) * sgn > tol) & (orient(C, A, Q) * sgn > tol)
        hit |= inside
    return hit & good


def _near_pairs(pa, ra, pb, rb):
    """Index pairs ``(i, j)`` of balls ``(pa[i], ra[i])`` and ``(pb[j], rb[j])`` that meet.

    Balls are grouped by radius (factors of :data:`SIZE_STEP`) and each pair of groups is
    searched with a k-d tree at the radius of its largest balls, so that a few large triangles
    do not widen the search of the many small ones.
    """
    from scipy.spatial import cKDTree

    if not len(pa) or not len(pb):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    rmin = max(float(min(ra.min(), rb.min())), 1e-12 * float(max(ra.max(), rb.max())), 1e-300)

    def groups(r):
        lv = np.floor(np.log(np.maximum(r, rmin) / rmin) / np.log(SIZE_STEP)).astype(np.int64)
        return {k: np.flatnonzero(lv == k) for k in np.unique(lv)}

    ga, gb = groups(ra), groups(rb)
    ta = {k: cKDTree(pa[v]) for k, v in ga.items()}
    tb = {k: cKDTree(pb[v]) for k, v in gb.items()}
    out_i, out_j = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
    for ka, ia in ga.items():
        for kb, ib in gb.items():
            r = float(ra[ia].max() + rb[ib].max())
            m = ta[ka].sparse_distance_matrix(tb[kb], r, output_type="ndarray")
            i, j = ia[m["i"]], ib[m["j"]]
            keep = m["v"] <= ra[i] + rb[j]
            out_i.append(i[keep])
            out_j.append(j[keep])
    return np.concatenate(out_i), np.concatenate(out_j)


def _levels(r, rmin):
    """Size level of each ball: ``floor(log_SIZE_STEP(r / rmin))`` (radii below ``rmin`` count as it)."""
    return np.floor(np.log(np.maximum(r, rmin) / rmin) / np.log(SIZE_STEP)).astype(np.int64)


def _boxes(p, r, key):
    """Sorted unique keys, the members of each and their bounding box grown by the largest radius.

    Returns ``keys (g,)``, ``members`` (list of index arrays), ``lo (g, 3)``, ``hi (g, 3)`` and
    ``rmax (g,)``.
    """
    order = np.argsort(key, kind="stable")
    keys, start = np.unique(key[order], return_index=True)
    members = np.split(order, start[1:])
    rmax = np.maximum.reduceat(r[order], start)
    lo = np.minimum.reduceat(p[order], start, axis=0) - rmax[:, None]
    hi = np.maximum.reduceat(p[order], start, axis=0) + rmax[:, None]
    return keys, members, lo, hi, rmax


def _pairs_touching(pa, ra, ga, pb, rb, gb, only, within=None):
    """Index pairs ``(i, j)`` of balls that meet, ``ga[i] != gb[j]`` or in the same group.

    Parameters
    ----------
    pa : (n, 3) ndarray
    ra : (n,) ndarray
    ga : (n,) ndarray of int
        Centres, radii and group (patch) of the first balls.
    pb, rb, gb
        The same for the second balls.
    only : set of int or None
        Keep only the pairs with a side in these groups (all if ``None``).
    within : set of int or None
        Groups whose balls are also paired with balls of their own group (all if ``None``).

    Returns
    -------
    i, j : (k,) ndarray of int
        The pairs: ``|pa[i] - pb[j]| <= ra[i] + rb[j]`` (the k-d tree's distance, as in
        :func:`_near_pairs`), in no particular order.

    Notes
    -----
    With ``only`` (a few new patches), the balls of those groups are searched against all
    others by size level (:func:`_near_pairs`) and the pairs inside one group dropped after.
    Without, the balls are split by group and by size level (factors of :data:`SIZE_STEP`);
    two such cells are searched against each other only when their bounding boxes, grown by
    their largest radius, meet, so that the pairs inside one group (most of the near pairs of
    a mesh: neighbouring triangles of one patch) are never formed unless the group is in
    ``within``.
    """
    from scipy.spatial import cKDTree

    empty = np.zeros(0, dtype=np.int64)
    if not len(pa) or not len(pb):
        return empty, empty
    if only is not None:
        oa, ob = np.isin(ga, list(only)), np.isin(gb, list(only))
        ia, ib, rest = np.flatnonzero(oa), np.flatnonzero(ob), np.flatnonzero(~oa)
        i1, j1 = _near_pairs(pa[ia], ra[ia], pb, rb)
        i2, j2 = _near_pairs(pa[rest], ra[rest], pb[ib], rb[ib])
        i, j = np.concatenate([ia[i1], rest[i2]]), np.concatenate([j1, ib[j2]])
        if within is not None:
            keep = (ga[i] != gb[j]) | np.isin(ga[i], list(within))
            i, j = i[keep], j[keep]
        return i, j
    rmin = max(float(min(ra.min(), rb.min())), 1e-12 * float(max(ra.max(), rb.max())), 1e-300)
    la, lb = _levels(ra, rmin), _levels(rb, rmin)
    # the few smallest and largest balls join the nearest well-filled level (fewer, fuller cells)
    lo, hi = np.quantile(np.concatenate([la, lb]), [LEVEL_TAIL, 1.0 - LEVEL_TAIL], method="nearest")
    la, lb = np.clip(la, lo, hi + 1), np.clip(lb, lo, hi + 1)
    nl = int(max(la.max(), lb.max())) + 1
    ka, ma, loa, hia, rxa = _boxes(pa, ra, ga.astype(np.int64) * nl + la)
    kb, mb, lob, hib, rxb = _boxes(pb, rb, gb.astype(np.int64) * nl + lb)
    tol = REACH_SLACK * float(max(np.abs(hia).max(), np.abs(hib).max(), 1e-300))
    meet = ((loa[:, None, :] <= hib[None, :, :] + tol) & (lob[None, :, :] <= hia[:, None, :] + tol)).all(axis=2)
    xa, xb = ka // nl, kb // nl
    if within is not None:
        meet &= (xa[:, None] != xb[None, :]) | np.isin(xa, list(within))[:, None]
    ta, tb = {}, {}
    out_i, out_j = [empty], [empty]
    for u, v in zip(*np.nonzero(meet)):
        if u not in ta:
            ta[u] = cKDTree(pa[ma[u]])
        if v not in tb:
            tb[v] = cKDTree(pb[mb[v]])
        m = ta[u].sparse_distance_matrix(tb[v], float(rxa[u] + rxb[v]), output_type="ndarray")
        i, j = ma[u][m["i"]], mb[v][m["j"]]
        keep = m["v"] <= ra[i] + rb[j]
        out_i.append(i[keep])
        out_j.append(j[keep])
    return np.concatenate(out_i), np.concatenate(out_j)


def crossing_patches(V: np.ndarray, T: np.ndarray, P: np.ndarray, *, only=None, folds=None) -> tuple[set, set]:
    """Pairs of patches whose triangles cross, and patches that cross themselves.

    Parameters
    ----------
    V : (n, 3) ndarray
        Vertices (shared between patches along their common curves).
    T : (t, 3) ndarray of int
        Triangles.
    P : (t,) ndarray of int
        Patch of each triangle.
    only : set of int, optional
        Test only the pairs that involve one of these patches (the others were tested before).
    folds : set of int, optional
        Test only these patches against themselves (default: all; a height field over a simple
        planar domain cannot cross itself).

    Returns
    -------
    pairs : set of (int, int)
        ``(a, b)`` with ``a < b``: a triangle of one is pierced by an edge of the other.
    folded : set of int
        Patches with two of their own triangles (sharing no vertex) crossing.

    Notes
    -----
    Triangles that share a vertex are not tested against each other's edges through that vertex
    (they touch there). Broad phase by a k-d tree on edge midpoints and triangle centroids;
    about :math:`O(t \\log t)` for evenly sized triangles.
    """
    V = np.asarray(V, dtype=float)
    T = np.asarray(T, dtype=np.int64).reshape(-1, 3)
    P = np.asarray(P, dtype=np.int64)
    if not len(T):
        return set(), set()
    # edges with the patch they belong to (an edge on a shared curve once per patch)
    E = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    EP = np.tile(P, 3)
    E = np.sort(E, axis=1)
    nv, npatch = int(T.max()) + 1, int(P.max()) + 1
    _, first = np.unique((E[:, 0] * nv + E[:, 1]) * npatch + EP, return_index=True)
    E, EP = E[first], EP[first]
    ep = V[E].mean(axis=1)
    er = 0.5 * np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)
    tp = V[T].mean(axis=1)
    tr = np.linalg.norm(V[T] - tp[:, None, :], axis=2).max(axis=1)
    i, j = _pairs_touching(ep, er, EP, tp, tr, P, only, within=folds)
    pairs, folded = set(), set()
    for lo in range(0, len(i), _CHUNK):
        a, b = i[lo:lo + _CHUNK], j[lo:lo + _CHUNK]
        share = (E[a, 0:1] == T[b]).any(axis=1) | (E[a, 1:2] == T[b]).any(axis=1)
        a, b = a[~share], b[~share]
        hit = _pierce(V[E[a, 0]], V[E[a, 1]], V[T[b, 0]], V[T[b, 1]], V[T[b, 2]])
        for pa, pb in set(zip(EP[a[hit]].tolist(), P[b[hit]].tolist())):
            if pa == pb:
                folded.add(pa)
            else:
                pairs.add((min(pa, pb), max(pa, pb)))
    return pairs, folded


def overlapping_patches(V, T, P, curve_points, *, distance: float, margin: float, min_triangles: int = 1,
                        only=None, folds=()):
    """Pairs of patches whose sheets lie on each other (closer than ``distance``).

    Parameters
    ----------
    V : (n, 3) ndarray
    T : (t, 3) ndarray of int
    P : (t,) ndarray of int
        Patch of each triangle.
    curve_points : (m, 3) ndarray
        Points of the curves: triangles whose centroid is within ``margin`` of one are left out
        (patches meet along their curves).
    distance : float
        A triangle's centroid that projects inside a triangle of another patch at less than this
        distance from its plane lies on that patch.
    margin : float
    min_triangles : int
        A pair counts from this many such triangles on.
    only : set of int, optional
        Test only the pairs that involve one of these patches.
    folds : set of int
        Patches also tested against themselves: a triangle whose centroid lies on another
        triangle of its own patch (sharing no vertex) is a fold, reported as the pair ``(k, k)``.

    Returns
    -------
    pairs : list of (int, int)
        Sorted ``(a, b)``, ``a < b``.
    count : int
        Triangles lying on another patch.
    """
    from scipy.spatial import cKDTree

    V = np.asarray(V, dtype=float)
    T = np.asarray(T, dtype=np.int64).reshape(-1, 3)
    P = np.asarray(P, dtype=np.int64)
    if not len(T):
        return [], 0
    cen = V[T].mean(axis=1)
    far = np.ones(len(T), dtype=bool)
    if len(curve_points):
        d, _ = cKDTree(curve_points).query(cen, distance_upper_bound=margin)
        far = ~np.isfinite(d)
    idx = np.flatnonzero(far)
    if not len(idx):
        return [], 0
    tr = np.linalg.norm(V[T] - cen[:, None, :], axis=2).max(axis=1)
    # a centroid lying on triangle j is within `distance` of its plane and projects inside it,
    # within tr[j] of its centroid: no farther than sqrt(distance^2 + tr^2) from that centroid
    reach = np.sqrt(float(distance) ** 2 + tr**2) * (1.0 + REACH_SLACK)
    i, j = _pairs_touching(cen[idx], np.zeros(len(idx)), P[idx], cen, reach, P, only, within=set(folds))
    i = idx[i]
    # the tests below are per pair: each filters the pairs left by the one before (cheapest
    # first), which gives the pairs all of them pass at once
    other = P[i] != P[j]  # else a fold candidate: same patch, another triangle, no shared vertex
    keep = other | (np.isin(P[i], list(folds)) & (i != j))
    i, j, other = i[keep], j[keep], other[keep]
    a, b, c = V[T[j, 0]], V[T[j, 1]], V[T[j, 2]]
    n = _cross(b - a, c - a)
    nn = np.linalg.norm(n, axis=1)
    ok = nn > 0
    i, j, other, a, b, c, n, nn = i[ok], j[ok], other[ok], a[ok], b[ok], c[ok], n[ok], nn[ok]
    x = cen[i]
    near = np.abs(np.einsum("ij,ij->i", x - a, n)) / nn < distance
    i, j, other, a, b, c, n, x = i[near], j[near], other[near], a[near], b[near], c[near], n[near], x[near]
    # barycentric signs of the projection: inside when the three sub-areas agree with n
    inside = ((np.einsum("ij,ij->i", _cross(b - a, x - a), n) >= 0) & (np.einsum("ij,ij->i", _cross(c - b, x - b), n) >= 0)
              & (np.einsum("ij,ij->i", _cross(a - c, x - c), n) >= 0))
    i, j, other = i[inside], j[inside], other[inside]
    hit = other | ~(T[i][:, :, None] == T[j][:, None, :]).any(axis=(1, 2))
    count = {}
    seen = set()
    for t, q in zip(i[hit].tolist(), P[j[hit]].tolist()):
        if (t, q) in seen:
            continue
        seen.add((t, q))
        key = (min(int(P[t]), q), max(int(P[t]), q))
        count[key] = count.get(key, 0) + 1
    pairs = sorted(k for k, v in count.items() if v >= min_triangles)
    return pairs, len({t for t, _ in seen})


def curve_samples(V, curve_vertices, step: float) -> np.ndarray:
    """Points along the curves' polylines, no farther apart than ``step``.

    Parameters
    ----------
    V : (n, 3) ndarray
    curve_vertices : list of (m_c,) ndarray of int or None
        Vertex ids of each curve, in order (``None``: skipped).
    step : float

    Returns
    -------
    (k, 3) ndarray
    """
    out = [np.zeros((0, 3))]
    for ids in curve_vertices:
        if ids is None or not len(ids):
            continue
        p = V[np.asarray(ids)]
        out.append(p)
        if len(p) < 2:
            continue
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        k = np.ceil(seg / step).astype(np.int64)
        long = np.flatnonzero(k > 1)
        if not len(long):
            continue
        # the points i + t (i + 1) of every long segment i, t = 1/k .. (k-1)/k, in order
        i = np.repeat(long, k[long] - 1)
        first = np.cumsum(k[long] - 1) - (k[long] - 1)
        num = np.arange(len(i)) - np.repeat(first, k[long] - 1) + 1
        t = (num / k[i])[:, None]
        out.append(p[i] + t * (p[i + 1] - p[i]))
    return np.vstack(out)
