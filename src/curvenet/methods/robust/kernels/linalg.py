"""Small dense linear algebra of the kernels: eigenpairs of (d, d) symmetric matrices, weighted
PCA, small linear solves.

Only ``+ - * /`` and ``sqrt``: the compiled and the plain-Python runs agree bit for bit. The
fixed constants come in a :class:`~curvenet.methods.robust.thresholds.Linalg` (``la``).
"""

from __future__ import annotations

import numpy as np


def _eig_sym(C, V, ev, la):  # pragma: no cover - compiled
    """Eigen-decomposition of a small symmetric matrix ``C`` (d, d) by cyclic Jacobi rotations.

    ``C`` is overwritten; on return ``ev`` (d,) holds the eigenvalues in ascending order (ties:
    lower index first) and the columns of ``V`` (d, d) the unit eigenvectors, in that order.
    Only ``+ - * /`` and ``sqrt``: the compiled and the Python runs agree bit for bit.
    """
    d = C.shape[0]
    for i in range(d):
        for j in range(d):
            V[i, j] = 1.0 if i == j else 0.0
    for sweep in range(la.jacobi_sweeps):
        off = 0.0
        scale = 0.0
        for p in range(d):
            scale += abs(C[p, p])
            for q in range(p + 1, d):
                off += abs(C[p, q])
        if off <= la.jacobi_tol * scale or off == 0.0:
            break
        for p in range(d - 1):
            for q in range(p + 1, d):
                apq = C[p, q]
                if apq == 0.0:
                    continue
                theta = (C[q, q] - C[p, p]) / (2.0 * apq)
                if abs(theta) > la.theta_max:
                    t = 0.5 / theta
                else:
                    t = 1.0 / (abs(theta) + np.sqrt(theta * theta + 1.0))
                    if theta < 0.0:
                        t = -t
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for r in range(d):  # C <- C J (columns p, q)
                    crp = C[r, p]
                    crq = C[r, q]
                    C[r, p] = c * crp - s * crq
                    C[r, q] = s * crp + c * crq
                for r in range(d):  # C <- J^T C (rows p, q)
                    cpr = C[p, r]
                    cqr = C[q, r]
                    C[p, r] = c * cpr - s * cqr
                    C[q, r] = s * cpr + c * cqr
                C[p, q] = 0.0
                C[q, p] = 0.0
                for r in range(d):
                    vrp = V[r, p]
                    vrq = V[r, q]
                    V[r, p] = c * vrp - s * vrq
                    V[r, q] = s * vrp + c * vrq
    # sort ascending (insertion sort, stable), columns of V along
    for i in range(d):
        ev[i] = C[i, i]
    for i in range(1, d):
        j = i
        while j > 0 and ev[j - 1] > ev[j]:
            tmp = ev[j - 1]
            ev[j - 1] = ev[j]
            ev[j] = tmp
            for r in range(d):
                tmp = V[r, j - 1]
                V[r, j - 1] = V[r, j]
                V[r, j] = tmp
            j -= 1


def _sym2(m00, m11, m01):  # pragma: no cover - compiled
    """The symmetric 2 x 2 matrix ``[[m00, m01], [m01, m11]]``: its eigenvalues are
    ``q -+ r``, with ``q`` the mean of the diagonal, ``b`` half its difference and
    ``r = sqrt(b^2 + m01^2)``; returns ``(q, b, r)``."""
    q = 0.5 * (m00 + m11)
    b = 0.5 * (m00 - m11)
    return q, b, np.sqrt(b * b + m01 * m01)


def _eig_top(C, V, ev, la):  # pragma: no cover - compiled
    """Eigenvalues (ascending, into ``ev``) and top eigenvector (into ``V[:, d - 1]``; the other
    columns are not set) of a small symmetric matrix ``C`` (d, d).

    For d = 2 and 3 (``la.closed_dim``) in closed form: the largest root of the characteristic polynomial of the
    traceless ``C - tr(C) / d`` by Newton's method from an upper bound (monotone there), the
    vector as the longest cross product of two rows of ``C - l_top I``, the other two
    eigenvalues from ``C`` restricted to the plane normal to it; a few times cheaper than the
    Jacobi sweeps. Other sizes, and a top eigenvalue within ``la.top_gap`` of the next:
    :func:`_eig_sym` (``C`` overwritten).
    Only ``+ - * /`` and ``sqrt``: the compiled and the Python runs agree bit for bit.
    """
    d = C.shape[0]
    if d == 2:
        q, b, r = _sym2(C[0, 0], C[1, 1], C[0, 1])
        if not r > la.top_gap * (abs(q) + r):
            _eig_sym(C, V, ev, la)
            return
        ev[0] = q - r
        ev[1] = q + r
        if b >= 0.0:
            x = r + b
            y = C[0, 1]
        else:
            x = C[0, 1]
            y = r - b
        s = 1.0 / np.sqrt(x * x + y * y)
        V[0, 1] = x * s
        V[1, 1] = y * s
        return
    if d != la.closed_dim:
        _eig_sym(C, V, ev, la)
        return
    # d = 3 from here on
    a01 = C[0, 1]
    a02 = C[0, 2]
    a12 = C[1, 2]
    q = (C[0, 0] + C[1, 1] + C[2, 2]) / d
    b00 = C[0, 0] - q
    b11 = C[1, 1] - q
    b22 = C[2, 2] - q
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * (a01 * a01 + a02 * a02 + a12 * a12)
    if not p2 > 0.0:
        _eig_sym(C, V, ev, la)
        return
    # f(x) = x^3 - (p2 / 2) x - det(B): its largest root lies in [sqrt(p2 / 6), sqrt(2 p2 / 3)],
    # where f is convex and increasing: Newton from the upper end decreases to it
    det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02)
    hp = 0.5 * p2
    x = np.sqrt(2.0 * p2 / d)
    for it in range(la.newton_steps):
        f = (x * x - hp) * x - det
        df = d * x * x - hp
        if not f > 0.0 or not df > 0.0:
            break
        xn = x - f / df
        if not xn < x:
            break
        x = xn
    # the other two: sum -x, product x^2 - p2 / 2
    disc = 2.0 * p2 - d * x * x
    sq = np.sqrt(disc) if disc > 0.0 else 0.0
    x1 = 0.5 * (sq - x)
    if not x - x1 > la.top_gap * (np.sqrt(p2) + abs(q)):
        _eig_sym(C, V, ev, la)
        return
    # the top eigenvector: the longest cross product of two rows of B - x I
    r00 = b00 - x
    r11 = b11 - x
    r22 = b22 - x
    c0x = a01 * a12 - a02 * r11
    c0y = a02 * a01 - r00 * a12
    c0z = r00 * r11 - a01 * a01
    c1x = a01 * r22 - a02 * a12
    c1y = a02 * a02 - r00 * r22
    c1z = r00 * a12 - a01 * a02
    c2x = r11 * r22 - a12 * a12
    c2y = a12 * a02 - a01 * r22
    c2z = a01 * a12 - r11 * a02
    n0 = c0x * c0x + c0y * c0y + c0z * c0z
    n1 = c1x * c1x + c1y * c1y + c1z * c1z
    n2 = c2x * c2x + c2y * c2y + c2z * c2z
    if n0 >= n1 and n0 >= n2:
        vx, vy, vz, nn = c0x, c0y, c0z, n0
    elif n1 >= n2:
        vx, vy, vz, nn = c1x, c1y, c1z, n1
    else:
        vx, vy, vz, nn = c2x, c2y, c2z, n2
    if not nn > 0.0:
        _eig_sym(C, V, ev, la)
        return
    s = 1.0 / np.sqrt(nn)
    vx *= s
    vy *= s
    vz *= s
    V[0, 2] = vx
    V[1, 2] = vy
    V[2, 2] = vz
    ev[2] = q + x
    # the other two (x1 above is only good to sqrt(eps) relative): from C restricted to the
    # plane normal to v, an orthonormal pair (u, w) there, in closed form (2 x 2)
    ax = abs(vx)
    ay = abs(vy)
    az = abs(vz)
    if ax <= ay and ax <= az:  # u = v x (the axis where v is smallest)
        ux, uy, uz = 0.0, vz, -vy
    elif ay <= az:
        ux, uy, uz = -vz, 0.0, vx
    else:
        ux, uy, uz = vy, -vx, 0.0
    s = 1.0 / np.sqrt(ux * ux + uy * uy + uz * uz)
    ux *= s
    uy *= s
    uz *= s
    wx = vy * uz - vz * uy
    wy = vz * ux - vx * uz
    wz = vx * uy - vy * ux
    cux = C[0, 0] * ux + a01 * uy + a02 * uz
    cuy = a01 * ux + C[1, 1] * uy + a12 * uz
    cuz = a02 * ux + a12 * uy + C[2, 2] * uz
    cwx = C[0, 0] * wx + a01 * wy + a02 * wz
    cwy = a01 * wx + C[1, 1] * wy + a12 * wz
    cwz = a02 * wx + a12 * wy + C[2, 2] * wz
    m00 = ux * cux + uy * cuy + uz * cuz
    m11 = wx * cwx + wy * cwy + wz * cwz
    m01 = ux * cwx + uy * cwy + uz * cwz
    q2, b2, r2 = _sym2(m00, m11, m01)
    ev[0] = q2 - r2
    ev[1] = q2 + r2
    if ev[1] > ev[2]:  # (rounding, within the gap test's margin)
        ev[1] = ev[2]


def _pca01(Q, cnt, w, C, V, ev, mu, t, la):  # pragma: no cover - compiled
    """PCA of the rows ``Q[:cnt]`` with weights ``w[:cnt]`` of 0 or 1 (the numpy reference is in
    tests/test_robust_kernels.py):
    principal direction into ``t``, ascending eigenvalues into ``ev``."""
    d = Q.shape[1]
    sw = 0.0
    for k in range(cnt):
        sw += w[k]
    if sw < la.tiny:
        sw = la.tiny
    for c in range(d):
        acc = 0.0
        for k in range(cnt):
            if w[k] != 0.0:
                acc += Q[k, c]
        mu[c] = acc / sw
    for i in range(d):
        for j in range(i, d):
            acc = 0.0
            for k in range(cnt):
                if w[k] != 0.0:
                    acc += (Q[k, i] - mu[i]) * (Q[k, j] - mu[j])
            C[i, j] = acc
            C[j, i] = acc
    _eig_top(C, V, ev, la)
    for c in range(d):
        t[c] = V[c, d - 1]


def _solve_small(A, b, x):  # pragma: no cover - compiled
    """``x = A^-1 b`` for a small square ``A`` by Gaussian elimination with partial pivoting
    (``A`` and ``b`` are overwritten). Returns False when ``A`` is singular."""
    d = A.shape[0]
    for k in range(d):
        p = k
        for i in range(k + 1, d):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if A[p, k] == 0.0:
            return False
        if p != k:
            for j in range(d):
                t = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = t
            t = b[k]
            b[k] = b[p]
            b[p] = t
        for i in range(k + 1, d):
            f = A[i, k] / A[k, k]
            for j in range(k, d):
                A[i, j] -= f * A[k, j]
            b[i] -= f * b[k]
    for k in range(d - 1, -1, -1):
        acc = b[k]
        for j in range(k + 1, d):
            acc -= A[k, j] * x[j]
        x[k] = acc / A[k, k]
    return True


def _envelope_solve(indptr, indices, data, rhs):  # pragma: no cover - compiled
    """``x = A^-1 rhs`` for a sparse symmetric positive definite ``A`` (n, n) by the Cholesky
    factor of its envelope, in one fixed order of operations (the same bits on every machine,
    unlike LAPACK's, whose BLAS kernels depend on the processor).

    Parameters
    ----------
    indptr, indices, data : ndarray
        The lower triangle of ``A`` (diagonal included) in CSR form, columns sorted in each row.
    rhs : ndarray of float64, shape (n, d)
        The right-hand sides.

    Returns
    -------
    ndarray of float64, shape (n, d)

    Notes
    -----
    Row ``i`` of the factor ``L`` is stored from the first column of row ``i`` of ``A`` to the
    diagonal (its envelope: no fill outside it): a banded matrix of half-width w costs
    O(n w^2); a cyclic band (a closed curve, ordered along it) adds its last rows, dense back to
    the curve's first sample, still O(n w) in all. Only ``+ - * /`` and ``sqrt``.
    """
    n = rhs.shape[0]
    d = rhs.shape[1]
    first = np.empty(n, dtype=np.int64)
    start = np.empty(n + 1, dtype=np.int64)
    start[0] = 0
    for i in range(n):
        first[i] = indices[indptr[i]] if indptr[i + 1] > indptr[i] else i
        start[i + 1] = start[i] + i - first[i] + 1
    L = np.zeros(start[n])
    for i in range(n):  # A's row i into L's envelope
        for q in range(indptr[i], indptr[i + 1]):
            L[start[i] + indices[q] - first[i]] = data[q]
    for i in range(n):
        fi = first[i]
        for j in range(fi, i + 1):
            k0 = max(fi, first[j])
            acc = L[start[i] + j - fi]
            for k in range(k0, j):
                acc -= L[start[i] + k - fi] * L[start[j] + k - first[j]]
            if j < i:
                L[start[i] + j - fi] = acc / L[start[j + 1] - 1]
            else:
                L[start[i + 1] - 1] = np.sqrt(acc)
    x = np.empty((n, d))
    for i in range(n):  # L y = rhs
        fi = first[i]
        for c in range(d):
            acc = rhs[i, c]
            for k in range(fi, i):
                acc -= L[start[i] + k - fi] * x[k, c]
            x[i, c] = acc / L[start[i + 1] - 1]
    for i in range(n - 1, -1, -1):  # L^T x = y, column i of L^T is row i of L
        fi = first[i]
        for c in range(d):
            x[i, c] = x[i, c] / L[start[i + 1] - 1]
            for k in range(fi, i):
                x[k, c] -= L[start[i] + k - fi] * x[i, c]
    return x
