"""Fairing of a height-field patch: the Laplacian of the heights, read off the boundary curves.

A patch laid out over its best-fit plane is a height field ``h`` over the 2D domain. Along a
boundary run (the part of one curve between two corners), the heights give the second derivative
along the boundary; at each corner the two runs that meet give the gradient (two directional
slopes) and, through the second derivative of the other run, the curvature across the boundary.
The Laplacian on the boundary is then

.. math:: \\Delta h = (h_{ss} - \\kappa_g \\, h_{n}) + h_{nn}

with ``s`` the arc length of the run in the domain, ``kappa_g`` its curvature toward the interior,
``h_n`` the inward slope and ``h_nn`` the curvature across. At a corner, the Laplacian is taken as
the sum of the two runs' second derivatives (exact for perpendicular runs, and at any angle for
an isotropic Hessian), so the curvature across one run is the other's; along a run it is
interpolated linearly between its corners. The term ``kappa_g h_n`` is left out (see
:func:`boundary_laplacian`). Inside, the Laplacian is interpolated from these values
(transfinite Coons interpolation on a four-sided patch, harmonic otherwise), and the heights
solve the Poisson equation with it (:func:`curvenet.surfacing.patches.triangulate_patch`). A cylinder's quarter
bounded by two arcs and two lines gets the arcs' curvature across its whole height (a membrane of
constant mean curvature sags between the arcs), a sphere's quad twice its arcs' curvature.
"""

from __future__ import annotations

import numpy as np

__all__ = ["boundary_laplacian", "quadratic_derivatives", "MIN_CORNER_ANGLE", "SMOOTH_FRACTION", "MIN_WINDOW"]

#: Degrees: at a corner whose two runs meet closer to straight (or folded) than this, the gradient
#: is not determined by the two slopes; the runs take their across-data from their other end.
MIN_CORNER_ANGLE = 30.0

#: Fraction of a run's points in the window of the quadratic (Savitzky-Golay) fits that give its
#: slopes and second derivatives (smooths the noise of reconstructed curves).
SMOOTH_FRACTION = 0.25

#: Smallest window (points, odd) of those fits.
MIN_WINDOW = 5


def quadratic_derivatives(X: np.ndarray, window: int, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives of evenly spaced samples by local quadratic least squares.

    The Savitzky-Golay filter of order 2 (the values of ``scipy.signal.savgol_filter(X, window,
    2, deriv=k, delta=delta, axis=0, mode="interp")`` for k = 1, 2): each point's derivatives are
    those of the least-squares parabola through the ``window`` samples centred on it; the first
    and last ``window // 2`` points take the parabola of the first and last full window. Written
    here because importing ``scipy.signal`` costs more than a second, more than surfacing a
    small network.

    Parameters
    ----------
    X : (N, k) ndarray
        Samples, one row per point, evenly spaced by ``delta``.
    window : int
        Odd number of samples per fit, ``3 <= window <= N``.
    delta : float
        The spacing.

    Returns
    -------
    d1, d2 : (N, k) ndarray
        First and second derivatives.
    """
    from numpy.lib.stride_tricks import sliding_window_view

    N, half = len(X), window // 2
    x = (np.arange(window) - half) * delta
    P = np.linalg.pinv(np.vander(x, 3, increasing=True))  # (3, window): rows give a0, a1, a2
    coef = sliding_window_view(X, window, axis=0) @ P.T  # (N - window + 1, k, 3)
    d1, d2 = np.empty_like(X, dtype=float), np.empty_like(X, dtype=float)
    d1[half:N - half], d2[half:N - half] = coef[..., 1], 2.0 * coef[..., 2]
    for c, rows, at in ((coef[0], slice(0, half), x[:half]), (coef[-1], slice(N - half, N), x[half + 1:])):
        d1[rows] = c[:, 1] + 2.0 * c[:, 2] * at[:, None]
        d2[rows] = 2.0 * c[:, 2]
    return d1, d2


def _run_derivatives(q: np.ndarray, h: np.ndarray, sign: float):
    """First and second derivatives along one run, by arc length of its 2D path.

    Returns ``(t, n_in, kappa, h_s, h_ss)``: unit tangents (m, 2), inward normals (m, 2), curvature
    toward the interior (m,), slope (m,) and second derivative (m,) of the heights.
    """
    m = len(q)
    seg = np.linalg.norm(np.diff(q, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    L = s[-1]
    N = max(m, MIN_WINDOW + 2)
    g = np.linspace(0.0, L, N)
    X = np.column_stack([np.interp(g, s, q[:, 0]), np.interp(g, s, q[:, 1]), np.interp(g, s, h)])
    w = max(MIN_WINDOW, int(SMOOTH_FRACTION * N) | 1)
    w = min(w, N if N % 2 else N - 1)
    ds = L / (N - 1)
    d1, d2 = quadratic_derivatives(X, w, ds)
    d1 = np.column_stack([np.interp(s, g, d1[:, j]) for j in range(3)])
    d2 = np.column_stack([np.interp(s, g, d2[:, j]) for j in range(3)])
    t = d1[:, :2] / np.maximum(np.linalg.norm(d1[:, :2], axis=1), 1e-300)[:, None]
    n_in = sign * np.column_stack([-t[:, 1], t[:, 0]])
    kappa = np.einsum("ij,ij->i", d2[:, :2], n_in)
    return t, n_in, kappa, d1[:, 2], d2[:, 2]


def _runs(q, h, ci, sign):
    n = len(q)
    runs = []
    for k in range(len(ci)):
        a, b = ci[k], ci[(k + 1) % len(ci)]
        if b > a:
            idx = np.arange(a, b + 1)
        else:
            idx = np.concatenate([np.arange(a, n), np.arange(0, b + 1)])
        runs.append((idx, *_run_derivatives(q[idx], h[idx], sign)))
    return runs


def _turn(A, B) -> float:
    """|sin| of the angle between the run ``A`` arriving at a corner and ``B`` leaving it."""
    eA, eB = -A[1][-1], B[1][0]
    return abs(eA[0] * eB[1] - eA[1] * eB[0])


def boundary_laplacian(q: np.ndarray, h: np.ndarray, corners: np.ndarray):
    """The Laplacian of a height field on its boundary, from the boundary curves.

    Parameters
    ----------
    q : (n, 2) ndarray
        The boundary polygon in the domain (not repeating its first point).
    h : (n,) ndarray
        Heights of its points.
    corners : (n,) ndarray of bool
        Points where one curve ends and the next begins (nodes).

    Returns
    -------
    values : (n,) ndarray
        The Laplacian at each boundary point (meaningful where ``known``).
    known : (n,) ndarray of bool
        Points of the sides that have at least one corner.
    sides : list of (m_i,) ndarray of int
        The boundary split at its corners (nodes where the curves meet at an angle of at least
        :data:`MIN_CORNER_ANGLE`), each from corner to corner, in order.
    Or ``None`` when the polygon has fewer than two such corners.
    """
    n = len(q)
    ci = np.flatnonzero(np.asarray(corners, dtype=bool)[:n])
    if len(ci) < 2:
        return None
    area2 = np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])
    sign = 1.0 if area2 > 0 else -1.0
    sin_min = np.sin(np.radians(MIN_CORNER_ANGLE))
    runs = _runs(q, h, ci, sign)
    # nodes where the curves go on about straight are not corners: merge their runs
    real = [ci[k] for k in range(len(runs)) if _turn(runs[k - 1], runs[k]) >= sin_min]
    if len(real) < 2:
        return None
    if len(real) < len(ci):
        runs = _runs(q, h, np.array(real), sign)
    ends = {}  # (run, 0 or 1) -> (inward slope, curvature across)
    for k in range(len(runs)):
        A, B = runs[k - 1], runs[k]
        eA, sA = -A[1][-1], -A[4][-1]
        eB, sB = B[1][0], B[4][0]
        sin = _turn(A, B)
        if sin < sin_min:
            continue
        g = np.linalg.solve(np.array([eA, eB]), np.array([sA, sB]))
        hinA, hinB = g @ A[2][-1], g @ B[2][0]
        HA = A[5][-1] - A[3][-1] * hinA  # second derivative along A's direction
        HB = B[5][0] - B[3][0] * hinB
        # the Laplacian at the corner is HA + HB (exact for perpendicular runs, and at any
        # angle for an isotropic Hessian): the curvature across one run is the other's
        ends[(k - 1) % len(runs), 1] = (hinA, HB)
        ends[k, 0] = (hinB, HA)
    if not ends:
        return None
    values = np.zeros(n)
    weight = np.zeros(n)
    for k, (idx, t, n_in, kappa, h_s, h_ss) in enumerate(runs):
        e0, e1 = ends.get((k, 0)), ends.get((k, 1))
        if e0 is None and e1 is None:
            continue
        e0, e1 = e0 or e1, e1 or e0
        seg = np.linalg.norm(np.diff(q[idx], axis=0), axis=1)
        u = np.concatenate([[0.0], np.cumsum(seg)])
        u = u / u[-1] if u[-1] > 0 else np.zeros_like(u)
        hin = (1 - u) * e0[0] + u * e1[0]
        hnn = (1 - u) * e0[1] + u * e1[1]
        # the term -kappa * h_n of the boundary's own turning is left out: with h_n interpolated
        # linearly between the corners it added error (measured on the sphere and torus models:
        # largest deviation 1.03 and 0.75 spacings with it, 0.66 and 0.36 without)
        np.add.at(values, idx, h_ss + hnn)
        np.add.at(weight, idx, 1.0)
    known = weight > 0
    values[known] /= weight[known]
    return values, known, [r[0] for r in runs]
