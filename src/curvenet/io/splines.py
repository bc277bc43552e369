"""Interpolating cubic B-splines of many curves at once, bit for bit as SciPy makes each.

The DXF writer (:mod:`curvenet.io.dxf`) writes a fitted network's curves as B-splines through
their points: for each open curve, ``scipy.interpolate.make_interp_spline(u, points, k=3)`` in
the chord-length parameter ``u`` (not-a-knot end conditions). One call a curve costs about
0.3 ms of Python around a solve of a few dozen unknowns: 10 s for the 30,000 curves of a
million-point network. Here every curve is set up at once (numpy, the curves grouped by their
number of points) and all the systems are solved by one LAPACK ``gbsv`` call, the same routine
SciPy calls for each curve:

* the collocation matrix of each curve is SciPy's (``_coloc``): the same de Boor recursion
  (:func:`_de_boor`), operation for operation, at the same knots (``_not_a_knot``);
* the matrices are placed one after the other on the diagonal of one banded matrix (the
  curves grouped by their number of points, so that each group's blocks are one slab of the
  band storage, written by a few slices), each followed by :data:`_PAD` rows and columns of
  the identity (right-hand side zero). LU with
  partial pivoting of a block-diagonal banded matrix works on each block alone: the entries
  between blocks are zeros, never chosen as pivots, and the padding keeps every product of a
  zero entry with a value of another block (which could turn a ``-0.0`` into ``0.0``) out of
  the band. Each curve's control points are then those SciPy computes for it, to the bit:
  ``tests/test_splines.py`` compares them on curves of every length from 4 to 80 points and on
  degenerate ones (flat, a coordinate all zero, points near each other).

Curves that need anything else (loops, which are periodic splines; three points, a quadratic)
stay with the caller's one-curve function.
"""

from __future__ import annotations

import numpy as np

from ..lengths import step_lengths

__all__ = ["chord_parameters", "cubic_splines", "open_fit_points", "DEGREE"]

#: Degree of the splines made here (cubic).
DEGREE = 3

#: Identity rows and columns after each curve's block in the joint banded system: as many as the
#: band of its LU factors is wide above the diagonal (``kl + ku`` = 2 * DEGREE), so that no entry
#: of a curve's factors reaches the next curve's unknowns.
_PAD = 2 * DEGREE


def open_fit_points(P: np.ndarray, off: np.ndarray, rel_tol: float) -> np.ndarray:
    """Mask of the points of open curves kept as spline fit points: a point is dropped where it
    lies within ``rel_tol`` times its curve's extent of the point before it.

    Parameters
    ----------
    P : (N, 3) float ndarray
        The points of all curves, curve ``c`` being rows ``off[c]:off[c + 1]``.
    off : (C + 1,) int ndarray
        Row offsets of the curves (each of at least one point).
    rel_tol : float
        Tolerance as a fraction of the largest side of the curve's bounding box.

    Returns
    -------
    keep : (N,) bool ndarray
        For each curve the mask of ``_fit_points`` in :mod:`curvenet.io.dxf` (its first point
        always kept), computed with the same operations.
    """
    starts = off[:-1]
    ext = np.maximum.reduceat(P, starts, axis=0) - np.minimum.reduceat(P, starts, axis=0)
    tol = rel_tol * np.maximum(ext.max(axis=1), 1e-300)  # (C,)
    steps = step_lengths(np.diff(P, axis=0))  # the steps between curves are not used
    keep = np.ones(len(P), dtype=bool)
    keep[1:] = steps > np.repeat(tol, np.diff(off))[1:]
    keep[starts] = True
    return keep


def chord_parameters(G: np.ndarray) -> np.ndarray:
    """The chord-length parameter of curves of the same number of points.

    Parameters
    ----------
    G : (m, n, d) float ndarray
        ``m`` curves of ``n`` points.

    Returns
    -------
    (m, n) float ndarray
        ``u[c] = r_[0, cumsum(|G[c, i + 1] - G[c, i]|)]``, each curve summed from its start in
        order (as ``np.cumsum`` of the curve alone).
    """
    u = np.zeros(G.shape[:2])
    u[:, 1:] = np.cumsum(step_lengths(np.diff(G, axis=1)), axis=1)
    return u


def _not_a_knot(u: np.ndarray) -> np.ndarray:
    """(m, n + 4) knots of the cubic not-a-knot interpolants at parameters ``u`` (m, n): the ends
    four times, the inner parameters but the second and the second to last."""
    m, n = u.shape
    return np.concatenate([np.repeat(u[:, :1], DEGREE + 1, axis=1), u[:, 2:n - 2],
                           np.repeat(u[:, -1:], DEGREE + 1, axis=1)], axis=1)


def _de_boor(t: np.ndarray, x: np.ndarray, ell: np.ndarray) -> np.ndarray:
    """The four cubic B-splines that are nonzero at ``x``, by the recursion of SciPy's
    ``_deBoor_D`` (``m = 0``), the same operations in the same order.

    Parameters
    ----------
    t : (m, L) float ndarray
        Knots of each curve.
    x : (m, n) float ndarray
        Where to evaluate.
    ell : (n,) int ndarray
        The knot interval of each column of ``x``: ``t[ell] <= x < t[ell + 1]`` (or the last).

    Returns
    -------
    (m, n, 4) float ndarray
        ``B[ell - 3 + a](x)`` for ``a = 0..3``.
    """
    h = np.zeros(x.shape + (DEGREE + 1,))
    h[..., 0] = 1.0
    for j in range(1, DEGREE + 1):
        hh = h[..., :j].copy()
        h[..., 0] = 0.0
        for n in range(1, j + 1):
            xb, xa = t[:, ell + n], t[:, ell + n - j]
            same = xb == xa
            with np.errstate(divide="ignore", invalid="ignore"):
                w = hh[..., n - 1] / (xb - xa)
                h[..., n - 1] = np.where(same, h[..., n - 1], h[..., n - 1] + w * (xb - x))
                h[..., n] = np.where(same, 0.0, w * (x - xa))
    return h


def _collocation(u: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The collocation matrices of curves of ``n`` points in LAPACK's banded storage.

    Returns the values (m, n, 4), their rows in the band storage (n, 4) and their columns
    within a curve's block (n, 4): ``ab[row, base + col] = value`` with ``kl = ku = 3``.
    """
    n = u.shape[1]
    i = np.arange(n)
    ell = np.clip(i + 2, DEGREE, n - 1)  # the knot interval of u[i] (strictly increasing u)
    col = ell[:, None] - DEGREE + np.arange(DEGREE + 1)
    return _de_boor(t, u, ell), 2 * DEGREE + i[:, None] - col, col


def cubic_splines(F: np.ndarray, off: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The cubic not-a-knot B-splines through the fit points of many open curves.

    Parameters
    ----------
    F : (N, d) float ndarray
        Fit points, curve ``c`` being rows ``off[c]:off[c + 1]``.
    off : (C + 1,) int ndarray
        Row offsets; every curve has at least 4 points.

    Returns
    -------
    control : (N, d) float ndarray
        Control points (curve ``c``: rows ``off[c]:off[c + 1]``).
    knots : (N + 4 C,) float ndarray
        Knots (curve ``c``: ``off[c] + 4 c`` to ``off[c + 1] + 4 (c + 1)``).

    or None when a curve's parameters are not strictly increasing or the points are not all
    finite (where SciPy raises), or a system is singular: the caller then makes the curves one
    by one, and gets SciPy's error.

    Notes
    -----
    Each curve's control points and knots equal those of
    ``make_interp_spline(u, F[off[c]:off[c + 1]], k=3)`` with ``u`` its chord-length parameter
    (see the module's notes). O(N) memory and time.
    """
    from scipy.linalg import lapack

    sizes = np.diff(off)
    C = len(sizes)
    if not C:
        return np.zeros((0,) + F.shape[1:]), np.zeros(0)
    if not np.isfinite(F).all():
        return None
    d = F.shape[1]
    order = np.argsort(sizes, kind="stable")  # the blocks of curves of one size side by side
    width = sizes[order] + _PAD  # a block's unknowns, then its padding
    first = np.concatenate([[0], np.cumsum(width)])  # each block's first unknown, in that order
    ab = np.zeros((3 * DEGREE + 1, int(first[-1])), order="F")
    rhs = np.zeros((int(first[-1]), d))
    control = np.empty_like(F, dtype=np.float64)
    knots = np.empty(int(off[-1]) + (DEGREE + 1) * C)
    k_off = off[:-1] + (DEGREE + 1) * np.arange(C)
    runs = np.flatnonzero(np.diff(sizes[order])) + 1
    spans = list(zip(np.r_[0, runs].tolist(), np.r_[runs, C].tolist()))
    for a, b in spans:  # the curves order[a:b], of n points each
        idx, n = order[a:b], int(sizes[order[a]])
        G = F[off[idx][:, None] + np.arange(n)]  # (m, n, d)
        u = chord_parameters(G)
        if not (np.diff(u, axis=1) > 0).all():
            return None
        t = _not_a_knot(u)
        h, row, col = _collocation(u, t)
        band = ab.T[first[a]:first[b]].reshape(b - a, n + _PAD, 3 * DEGREE + 1)  # (views of the
        band[:, col, row] = h  # group's columns of ab and rows of rhs, block by block)
        band[:, n:, 2 * DEGREE] = 1.0  # the padding: identity
        rhs[first[a]:first[b]].reshape(b - a, n + _PAD, d)[:, :n] = G
        knots[k_off[idx][:, None] + np.arange(n + DEGREE + 1)] = t
    _, _, x, info = lapack.dgbsv(DEGREE, DEGREE, ab, rhs, overwrite_ab=1, overwrite_b=1)
    if info != 0:
        return None
    for a, b in spans:
        idx, n = order[a:b], int(sizes[order[a]])
        control[off[idx][:, None] + np.arange(n)] = x[first[a]:first[b]].reshape(b - a, n + _PAD, d)[:, :n]
    return control, knots
