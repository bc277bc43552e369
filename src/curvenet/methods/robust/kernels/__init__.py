"""Sequential per-point loops of the robust method, compiled with numba when it is installed.

Each kernel is plain Python written in the subset numba compiles. When numba is missing (or
``CURVENET_NO_NUMBA=1`` is set) the very same Python function runs, so both paths give identical
results; the Python path is only slow.
"""

from __future__ import annotations

import contextvars
import os
from contextlib import contextmanager

import numpy as np

from ...._sigint import held

prange = range  # numba.prange when compiled (parallel loops over independent blocks)

__all__ = ["spacing", "shell_groups", "csr_union", "components", "chain_order", "end_count", "end_counts", "tangents", "linked_edges", "short_links", "chain_ends", "junction_nodes", "trim_ends", "untangle", "noisy_tangents", "strand_cuts", "vote_agreement", "vote_eig", "HAVE_NUMBA"]


def _heap_pop(heap_k, heap_v, hs):  # pragma: no cover - compiled
    """Pop the smallest entry of the binary heap ``heap_k[:hs]`` / ``heap_v[:hs]`` (key, then
    id: equal keys come out by id, so the order never depends on the insertion order).

    Returns the key, the id and the new size."""
    key = heap_k[0]
    a = heap_v[0]
    hs -= 1
    if hs > 0:
        lk = heap_k[hs]
        lv = heap_v[hs]
        i = 0
        while True:
            c1 = 2 * i + 1
            if c1 >= hs:
                break
            c2 = c1 + 1
            if c2 < hs and (heap_k[c2] < heap_k[c1] or (heap_k[c2] == heap_k[c1] and heap_v[c2] < heap_v[c1])):
                c1 = c2
            if heap_k[c1] < lk or (heap_k[c1] == lk and heap_v[c1] < lv):
                heap_k[i] = heap_k[c1]
                heap_v[i] = heap_v[c1]
                i = c1
            else:
                break
        heap_k[i] = lk
        heap_v[i] = lv
    return key, a, hs


def _heap_push(heap_k, heap_v, hs, key, v):  # pragma: no cover - compiled
    """Push ``(key, v)`` on the binary heap of :func:`_heap_pop`; returns the new size."""
    i = hs
    hs += 1
    while i > 0:
        par = (i - 1) // 2
        if heap_k[par] > key or (heap_k[par] == key and heap_v[par] > v):
            heap_k[i] = heap_k[par]
            heap_v[i] = heap_v[par]
            i = par
        else:
            break
    heap_k[i] = key
    heap_v[i] = v
    return hs


#: the shell test's Dijkstra keeps up to this many frontier points in a list scanned for the
#: nearest (cheaper than a heap for the few on a curve), more in a heap
FRONT_MAX = 32


def _shell_groups(P, h, indptr, indices, r_in, r_out, order, nblocks):  # pragma: no cover - compiled
    """Groups of the geodesic shell around every point (see robust.shell_group_counts).

    The points ``order`` (any permutation: the result does not depend on it; a spatial one is
    cache-friendly; or a subset: the others get 0) are cut into ``nblocks`` runs done in
    parallel, each with its own scratch.
    """
    n = P.shape[0]
    no = order.shape[0]
    groups = np.zeros(n, dtype=np.int32)
    bs = (no + nblocks - 1) // nblocks if nblocks > 0 else no
    nb = (no + bs - 1) // bs if bs > 0 else 0
    for b in prange(nb):
        p1 = (b + 1) * bs
        _shell_groups_block(P, h, indptr, indices, r_in, r_out, order, b * bs, p1 if p1 < no else no, groups)
    return groups


def _shell_groups_block(P, h, indptr, indices, r_in, r_out, order, i0, i1, groups):  # pragma: no cover - compiled
    """Points ``order[i0:i1]`` of :func:`_shell_groups` (own scratch: ids as int32)."""
    n = P.shape[0]
    d = P.shape[1]
    mark = np.full(n, -1, dtype=np.int32)  # == p when reached from p
    done = np.full(n, -1, dtype=np.int32)  # == p when settled
    gd = np.zeros(n, dtype=np.float64)  # tentative geodesic distance from p
    pos = np.zeros(n, dtype=np.int32)  # place in the short frontier list
    comp = np.full(n, -1, dtype=np.int32)
    shell = np.full(n, -1, dtype=np.int32)
    reached = np.empty(n, dtype=np.int32)
    fk = np.empty(FRONT_MAX + 1, dtype=np.float64)
    fv = np.empty(FRONT_MAX + 1, dtype=np.int32)
    heap_k = np.empty(n + 1, dtype=np.float64)
    heap_v = np.empty(n + 1, dtype=np.int32)
    cap = n + 1
    stack = np.empty(n, dtype=np.int32)
    for ii in range(i0, i1):
        p = order[ii]
        ro = r_out * h[p]
        ri = r_in * h[p]
        nreach = 0
        # Dijkstra from p, bounded by ro. The frontier is a short list scanned for its nearest
        # point (on curves it holds a few); past FRONT_MAX points (a dense clump) it moves to a
        # binary heap with lazy deletion. Either way the distances are the same bits: each is
        # the least of (settled distance + edge length) over the settled neighbours.
        nf = 1
        fk[0] = 0.0
        fv[0] = p
        pos[p] = 0
        mark[p] = p
        gd[p] = 0.0
        hs = 0
        heap = False
        while True:
            if not heap:
                if nf == 0:
                    break
                j = 0
                key = fk[0]
                for q in range(1, nf):
                    if fk[q] < key:
                        key = fk[q]
                        j = q
                a = fv[j]
                nf -= 1
                if j != nf:
                    fk[j] = fk[nf]
                    fv[j] = fv[nf]
                    pos[fv[j]] = j
            else:
                if hs == 0:
                    break
                key, a, hs = _heap_pop(heap_k, heap_v, hs)
                if done[a] == p or key > gd[a]:
                    continue
            done[a] = p
            reached[nreach] = a
            nreach += 1
            for e in range(indptr[a], indptr[a + 1]):
                b = indices[e]
                if done[b] == p:
                    continue
                d2 = 0.0
                for c in range(d):
                    t = P[b, c] - P[a, c]
                    d2 += t * t
                nk = key + np.sqrt(d2)
                if nk > ro:
                    continue
                new = mark[b] != p
                if not new and gd[b] <= nk:
                    continue
                mark[b] = p
                gd[b] = nk
                if heap:
                    if hs < cap:
                        hs = _heap_push(heap_k, heap_v, hs, nk, b)
                elif not new:
                    fk[pos[b]] = nk
                else:
                    fk[nf] = nk
                    fv[nf] = b
                    pos[b] = nf
                    nf += 1
                    if nf > FRONT_MAX:
                        heap = True
                        for q in range(nf):
                            hs = _heap_push(heap_k, heap_v, hs, fk[q], fv[q])
        # the shell: reached points at least ri away, both along the graph and in space
        for q in range(nreach):
            a = reached[q]
            if gd[a] < ri:
                continue
            d2 = 0.0
            for c in range(d):
                t = P[a, c] - P[p, c]
                d2 += t * t
            if d2 >= ri * ri:
                shell[a] = p
        # connected groups of shell points, linked among themselves; a group counts only
        # when it reaches the middle of the shell along the graph (a branch leaving p), not
        # when it is a small cluster near the inner radius (the tip of an acute corner)
        rmid = 0.5 * (ri + ro)
        ng = 0
        for q in range(nreach):
            a = reached[q]
            if shell[a] != p or comp[a] == p:
                continue
            comp[a] = p
            gmax = gd[a]
            top = 1
            stack[0] = a
            while top > 0:
                top -= 1
                x = stack[top]
                if gd[x] > gmax:
                    gmax = gd[x]
                for e in range(indptr[x], indptr[x + 1]):
                    y = indices[e]
                    if shell[y] == p and comp[y] != p:
                        comp[y] = p
                        stack[top] = y
                        top += 1
            if gmax >= rmid:
                ng += 1
        groups[p] = ng
    return groups


def _csr_union(n, src, dst):  # pragma: no cover - compiled
    """CSR adjacency of the undirected graph with edges (src[i], dst[i]) (both directions).

    Within a row, the out-edges come first in edge order, then the in-edges in edge order
    (a counting sort, stable).
    """
    m = src.shape[0]
    deg = np.zeros(n + 1, dtype=np.int64)
    for i in range(m):
        deg[src[i] + 1] += 1
        deg[dst[i] + 1] += 1
    for i in range(n):
        deg[i + 1] += deg[i]
    fill = deg[:-1].copy()
    out = np.empty(2 * m, dtype=np.int64)
    for i in range(m):
        a = src[i]
        out[fill[a]] = dst[i]
        fill[a] += 1
    for i in range(m):
        b = dst[i]
        out[fill[b]] = src[i]
        fill[b] += 1
    return deg, out


def _end_count(P, ids, lim):  # pragma: no cover - compiled
    """How many points, from the last id of ``ids`` backwards, lie within arc length ``lim``.

    The count of prefix sums ``0, |x1 - x0|, ...`` of the reversed polyline that are ``<= lim``
    (what ``searchsorted(seg, lim, side="right")`` gives), with the sums formed exactly as numpy's
    ``cumsum(norm(diff(X), axis=1))`` forms them, so the result is the same bit for bit.
    """
    n = ids.shape[0]
    d = P.shape[1]
    if n == 0 or not lim >= 0.0:
        return 0
    s = 0.0
    m = 1
    for q in range(n - 1, 0, -1):
        a = ids[q]
        b = ids[q - 1]
        sq = 0.0
        for c in range(d):
            t = P[b, c] - P[a, c]
            sq = sq + t * t if c > 0 else t * t
        s += np.sqrt(sq)
        if not s <= lim:
            break
        m += 1
    return m


def _end_counts(P, h, flat, off, span):  # pragma: no cover - compiled
    """How many points of each id list make its end portion (see robust._end_portion).

    For list ``b``, ``ids = flat[off[b]:off[b + 1]]`` (running towards its end): the count of
    :func:`_end_count` within ``span * h[ids[-1]]``, at least ``min(3, len(ids))``.

    Returns
    -------
    (n_lists,) ndarray of int64
    """
    nb = off.shape[0] - 1
    out = np.zeros(nb, dtype=np.int64)
    for b in range(nb):
        n = off[b + 1] - off[b]
        if n == 0:
            continue
        ids = flat[off[b]:off[b + 1]]
        m = _end_count(P, ids, span * h[ids[n - 1]])
        out[b] = m if m > min(3, n) else min(3, n)
    return out


def _eig_sym_py(C, V, ev):  # pragma: no cover - compiled
    """Eigen-decomposition of a small symmetric matrix ``C`` (d, d) by cyclic Jacobi rotations.

    ``C`` is overwritten; on return ``ev`` (d,) holds the eigenvalues in ascending order (ties:
    lower index first) and the columns of ``V`` (d, d) the unit eigenvectors, in that order.
    Only ``+ - * /`` and ``sqrt``: the compiled and the Python runs agree bit for bit.
    """
    d = C.shape[0]
    for i in range(d):
        for j in range(d):
            V[i, j] = 1.0 if i == j else 0.0
    for sweep in range(60):
        off = 0.0
        scale = 0.0
        for p in range(d):
            scale += abs(C[p, p])
            for q in range(p + 1, d):
                off += abs(C[p, q])
        if off <= 1e-30 * scale or off == 0.0:
            break
        for p in range(d - 1):
            for q in range(p + 1, d):
                apq = C[p, q]
                if apq == 0.0:
                    continue
                theta = (C[q, q] - C[p, p]) / (2.0 * apq)
                if abs(theta) > 1e150:
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


_eig_sym = _eig_sym_py

#: _eig_top leaves a top eigenvalue closer than this (relative to the size of the
#: eigenvalues) to the next one to the Jacobi sweeps: its direction is ill-defined there
TOP_GAP = 1e-3


def _sym2(m00, m11, m01):  # pragma: no cover - compiled
    """The symmetric 2 x 2 matrix ``[[m00, m01], [m01, m11]]``: its eigenvalues are
    ``q -+ r``, with ``q`` the mean of the diagonal, ``b`` half its difference and
    ``r = sqrt(b^2 + m01^2)``; returns ``(q, b, r)``."""
    q = 0.5 * (m00 + m11)
    b = 0.5 * (m00 - m11)
    return q, b, np.sqrt(b * b + m01 * m01)


def _eig_top_py(C, V, ev):  # pragma: no cover - compiled
    """Eigenvalues (ascending, into ``ev``) and top eigenvector (into ``V[:, d - 1]``; the other
    columns are not set) of a small symmetric matrix ``C`` (d, d).

    For d = 2 and 3 in closed form: the largest root of the characteristic polynomial of the
    traceless ``C - tr(C) / d`` by Newton's method from an upper bound (monotone there), the
    vector as the longest cross product of two rows of ``C - l_top I``, the other two
    eigenvalues from ``C`` restricted to the plane normal to it; a few times cheaper than the
    Jacobi sweeps. Other sizes, and a top eigenvalue within ``TOP_GAP`` of the next:
    :func:`_eig_sym_py` (``C`` overwritten).
    Only ``+ - * /`` and ``sqrt``: the compiled and the Python runs agree bit for bit.
    """
    d = C.shape[0]
    if d == 2:
        q, b, r = _sym2(C[0, 0], C[1, 1], C[0, 1])
        if not r > TOP_GAP * (abs(q) + r):
            _eig_sym(C, V, ev)
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
    if d != 3:
        _eig_sym(C, V, ev)
        return
    a01 = C[0, 1]
    a02 = C[0, 2]
    a12 = C[1, 2]
    q = (C[0, 0] + C[1, 1] + C[2, 2]) / 3.0
    b00 = C[0, 0] - q
    b11 = C[1, 1] - q
    b22 = C[2, 2] - q
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * (a01 * a01 + a02 * a02 + a12 * a12)
    if not p2 > 0.0:
        _eig_sym(C, V, ev)
        return
    # f(x) = x^3 - (p2 / 2) x - det(B): its largest root lies in [sqrt(p2 / 6), sqrt(2 p2 / 3)],
    # where f is convex and increasing: Newton from the upper end decreases to it
    det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02)
    hp = 0.5 * p2
    x = np.sqrt(2.0 * p2 / 3.0)
    for it in range(100):
        f = (x * x - hp) * x - det
        df = 3.0 * x * x - hp
        if not f > 0.0 or not df > 0.0:
            break
        xn = x - f / df
        if not xn < x:
            break
        x = xn
    # the other two: sum -x, product x^2 - p2 / 2
    disc = 2.0 * p2 - 3.0 * x * x
    sq = np.sqrt(disc) if disc > 0.0 else 0.0
    x1 = 0.5 * (sq - x)
    if not x - x1 > TOP_GAP * (np.sqrt(p2) + abs(q)):
        _eig_sym(C, V, ev)
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
        _eig_sym(C, V, ev)
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


_eig_top = _eig_top_py


def _pca01(Q, cnt, w, C, V, ev, mu, t):  # pragma: no cover - compiled
    """PCA of the rows ``Q[:cnt]`` with weights ``w[:cnt]`` of 0 or 1 (the numpy reference is in
    tests/test_robust_kernels.py):
    principal direction into ``t``, ascending eigenvalues into ``ev``."""
    d = Q.shape[1]
    sw = 0.0
    for k in range(cnt):
        sw += w[k]
    if sw < 1e-300:
        sw = 1e-300
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
    _eig_top(C, V, ev)
    for c in range(d):
        t[c] = V[c, d - 1]


#: width (in local spacings) and reach along the line of the strip that scores a direction
STRIP_W = 0.5
STRIP_A = 3.0
#: score a neighbour's direction needs above the 4-neighbour direction's to replace it
CAND_MARGIN = 2.0
#: the neighbours' directions are tried only where the 4-neighbour PCA's linearity is below this
CAND_LIN = 0.8


def _strip_score(Q, m, u, hp):  # pragma: no cover - compiled
    """Score of the line through ``Q[0]`` along the unit vector ``u``: the sum over ``Q[1:m+1]``
    within ``STRIP_A * hp`` along it of ``exp(-(r / (STRIP_W * hp))^2)``, ``r`` the distance from
    the line."""
    d = Q.shape[1]
    s = 0.0
    a_max = STRIP_A * hp
    w2 = (STRIP_W * hp) ** 2
    for k in range(1, m + 1):
        al = 0.0
        r2 = 0.0
        for c in range(d):
            x = Q[k, c] - Q[0, c]
            al += x * u[c]
            r2 += x * x
        if al > a_max or al < -a_max:
            continue
        q = r2 - al * al
        if q < 0.0:
            q = 0.0
        s += np.exp(-q / w2)
    return s


def _tangents_block(P, idx, h, m, order, p0, p1, margin, T, lin, chord, gain):  # pragma: no cover - compiled
    """Points ``order[p0:p1]`` of :func:`_tangents` (own scratch arrays)."""
    d = P.shape[1]
    Q = np.empty((m + 1, d))
    w = np.ones(m + 1)
    C = np.zeros((d, d))
    V = np.zeros((d, d))
    ev = np.zeros(d)
    mu = np.zeros(d)
    t = np.zeros(d)
    u = np.zeros(d)
    ub = np.zeros(d)  # the best of the neighbour directions
    for ii in range(p0, p1):
        p = order[ii]
        for c in range(d):
            Q[0, c] = P[p, c]
        for k in range(m):
            q = idx[p, k]
            for c in range(d):
                Q[k + 1, c] = P[q, c]
        for k in range(5):
            w[k] = 1.0
        _pca01(Q, 5, w, C, V, ev, mu, t)
        hp2 = h[p] * h[p]
        # a close parallel curve can pull the 4-neighbour direction across: the direction
        # towards one of the 4 nearest neighbours replaces it when its narrow strip holds
        # clearly more points nearby (see _strip_score)
        kb = -1
        lam = ev[d - 1]
        if lam < 1e-300:
            lam = 1e-300
        best = np.inf
        s4 = np.inf
        top = -np.inf  # the best score of the neighbours' directions
        if 1.0 - ev[d - 2] / lam < CAND_LIN:  # (4 nearly collinear neighbours: t is theirs)
            s4 = _strip_score(Q, m, t, h[p])
            best = s4 + margin
        for k in range(1, 5 if best < np.inf else 1):
            r2 = 0.0
            for c in range(d):
                x = Q[k, c] - Q[0, c]
                r2 += x * x
            if r2 < 1e-300:
                continue
            r = np.sqrt(r2)
            for c in range(d):
                u[c] = (Q[k, c] - Q[0, c]) / r
            sc = _strip_score(Q, m, u, h[p])
            if sc > top:
                top = sc
            if sc > best:
                best = sc
                kb = k
                for c in range(d):
                    ub[c] = u[c]
        gain[p] = top - s4 if s4 < np.inf and top > -np.inf else -np.inf
        if kb > 0:
            for c in range(d):
                t[c] = ub[c]
        for it in range(2):
            same = it > 0
            for k in range(m + 1):
                al = 0.0
                r2 = 0.0
                for c in range(d):
                    x = Q[k, c] - Q[0, c]
                    al += x * t[c]
                    r2 += x * x
                wk = 1.0 if r2 - al * al <= hp2 else 0.0
                if wk != w[k]:
                    same = False
                w[k] = wk
            if same:  # the same weights as the last PCA: the same result
                break
            _pca01(Q, m + 1, w, C, V, ev, mu, t)
        lam = ev[d - 1]
        if lam < 1e-300:
            lam = 1e-300
        lin[p] = 1.0 - ev[d - 2] / lam
        for c in range(d):
            T[p, c] = t[c]
        # chord between the nearest strip neighbours ahead and behind along the tangent
        ia = -1
        ib = -1
        besta = np.inf
        bestb = np.inf
        for k in range(1, m + 1):
            al = 0.0
            r2 = 0.0
            for c in range(d):
                x = Q[k, c] - Q[0, c]
                al += x * t[c]
                r2 += x * x
            if r2 - al * al <= hp2:
                if al > 0.0 and al < besta:
                    besta = al
                    ia = k
                elif al < 0.0 and -al < bestb:
                    bestb = -al
                    ib = k
        if ia < 0 or ib < 0:
            chord[p] = np.nan
            continue
        ab2 = 0.0
        ap2 = 0.0
        apab = 0.0
        for c in range(d):
            ab = Q[ib, c] - Q[ia, c]
            ap = Q[0, c] - Q[ia, c]
            ab2 += ab * ab
            ap2 += ap * ap
            apab += ap * ab
        lab = np.sqrt(ab2)
        if lab < 1e-300:
            lab = 1e-300
        x = apab / lab
        q2 = ap2 - x * x
        chord[p] = np.sqrt(q2) if q2 > 0.0 else 0.0


def _tangents(P, idx, h, m, order, margin):  # pragma: no cover - compiled
    """Tangent, linearity and strip chord distance of every point (see robust._tangents).

    A first direction from the point and its 4 nearest neighbours, replaced by the direction
    towards one of those neighbours when that scores ``margin`` more (:func:`_strip_score`:
    a close parallel curve, within two spacings, can pull the PCA across); twice, the point and its
    ``m`` nearest neighbours within ``h`` of the current line are weighted 1 (others 0) and the
    weighted PCA gives the next direction. The linearity is ``1 - l2 / l1`` of the last PCA.
    The chord distance is that of the point from the segment joining its nearest neighbours
    (among the ``m``) inside the strip ahead and behind along the tangent (NaN without both).
    No (N, m, d) temporaries: one point at a time, in the given ``order`` (any permutation:
    the result does not depend on it; or a subset: the other points get zeros), blocks of
    points on all cores.

    Returns
    -------
    T : (N, d) ndarray
        Unit tangents (sign arbitrary).
    lin : (N,) ndarray
    chord : (N,) ndarray
    gain : (N,) ndarray
        Best score of the 4 neighbours' directions minus the 4-neighbour direction's (``-inf``
        where they were not tried: a linear 4-neighbour PCA). The direction changes where
        ``gain > margin``.
    """
    n = P.shape[0]
    d = P.shape[1]
    no = order.shape[0]
    T = np.zeros((n, d))
    lin = np.zeros(n)
    chord = np.zeros(n)
    gain = np.full(n, -np.inf)
    bs = 2048
    nb = (no + bs - 1) // bs
    for b in prange(nb):
        p1 = (b + 1) * bs
        _tangents_block(P, idx, h, m, order, b * bs, p1 if p1 < no else no, margin, T, lin, chord, gain)
    return T, lin, chord, gain


def _linked_edges(P, h, dist, idx, t, lin, link, width, wmin, gap, extra_len, lin_min):  # pragma: no cover - compiled
    """Directed kNN edges kept by the distance and tangent tests (see robust._linked_edges).

    For the edge from ``p`` to its neighbour ``q`` at distance ``d`` (rows sorted by distance):
    ``reach = link * (h_p + h_q) / 2 + gap``; edges longer than ``extra_len * reach`` (and
    self-pairs) are out. ``ps``, ``pd`` are the distances of the far end from the tangent lines
    at ``p`` and ``q``; ``w = max(width * (h_p + h_q) / 2, wmin)``. An edge is kept if it is
    short (``d <= link * (h_p + h_q) / 2``) and passes one tangent test (or an end has
    linearity below ``lin_min``, or ``d == 0``), or if it passes both tangent tests at two
    linear ends and ``d <= reach``, or if it is the first such two-sided strip edge of its row
    on either side of ``p`` along its tangent.

    Returns
    -------
    src, dst : (E,) ndarray of int64
    dd : (E,) ndarray of float
    """
    n = idx.shape[0]
    k = idx.shape[1]
    d = P.shape[1]
    sel = np.zeros((n, k), dtype=np.bool_)
    cnt = np.zeros(n + 1, dtype=np.int64)  # kept edges of row p at cnt[p + 1]
    for p in prange(n):  # rows are independent (parallel when compiled so)
        got_pos = False
        got_neg = False
        row = 0
        for j in range(k):
            q = idx[p, j]
            dd = dist[p, j]
            hh = 0.5 * (h[p] + h[q])
            reach = link * hh + gap
            if not (dd <= extra_len * reach) or p == q:
                continue
            al = 0.0
            aq = 0.0
            for c in range(d):
                v = P[q, c] - P[p, c]
                al += v * t[p, c]
                aq += v * t[q, c]
            x = dd * dd - al * al
            ps = np.sqrt(x if x > 0.0 else 0.0)
            x = dd * dd - aq * aq
            pd = np.sqrt(x if x > 0.0 else 0.0)
            w = width * 0.5 * (h[p] + h[q])
            if w < wmin:
                w = wmin
            ok = (ps <= w) or (pd <= w) or (lin[p] < lin_min) or (lin[q] < lin_min) or (dd == 0)
            short = dd <= link * 0.5 * (h[p] + h[q])
            both = (ps <= w) and (pd <= w) and (lin[p] >= lin_min) and (lin[q] >= lin_min)
            keep = (ok and short) or (both and (dd <= reach))
            if both and dd > 0:
                if al > 0 and not got_pos:
                    got_pos = True
                    keep = True
                elif -al > 0 and not got_neg:
                    got_neg = True
                    keep = True
            if keep:
                sel[p, j] = True
                row += 1
        cnt[p + 1] = row
    for p in range(n):
        cnt[p + 1] += cnt[p]
    total = cnt[n]
    src = np.empty(total, dtype=np.int64)
    dst = np.empty(total, dtype=np.int64)
    out_d = np.empty(total)
    for p in prange(n):
        e = cnt[p]
        for j in range(k):
            if sel[p, j]:
                src[e] = p
                dst[e] = idx[p, j]
                out_d[e] = dist[p, j]
                e += 1
    return src, dst, out_d


def _short_links(h, dist, idx, link):  # pragma: no cover - compiled
    """The kNN pairs ``(p, q)`` with ``dist <= link * 0.5 * (h_p + h_q)``, in row order."""
    n = idx.shape[0]
    k = idx.shape[1]
    cnt = np.zeros(n + 1, dtype=np.int64)  # pairs of row p at cnt[p + 1]
    for p in prange(n):  # rows are independent (parallel when compiled so)
        row = 0
        for j in range(k):
            if dist[p, j] <= link * 0.5 * (h[p] + h[idx[p, j]]):
                row += 1
        cnt[p + 1] = row
    for p in range(n):
        cnt[p + 1] += cnt[p]
    total = cnt[n]
    a = np.empty(total, dtype=np.int64)
    b = np.empty(total, dtype=np.int64)
    for p in prange(n):
        e = cnt[p]
        for j in range(k):
            if dist[p, j] <= link * 0.5 * (h[p] + h[idx[p, j]]):
                a[e] = p
                b[e] = idx[p, j]
                e += 1
    return a, b


def _components(n, a, b, mask):  # pragma: no cover - compiled
    """Connected components of the points in ``mask`` joined by the edges ``(a[i], b[i])``
    with both ends in ``mask`` (union-find), numbered in the order of their lowest point.

    Returns
    -------
    lab : (n,) ndarray of int64
        Component of every point, -1 outside ``mask``.
    count : int
    """
    parent = np.arange(n)
    for i in range(a.shape[0]):
        x = a[i]
        y = b[i]
        if not (mask[x] and mask[y]):
            continue
        while parent[x] != x:  # the roots, halving the paths on the way
            parent[x] = parent[parent[x]]
            x = parent[x]
        while parent[y] != y:
            parent[y] = parent[parent[y]]
            y = parent[y]
        if x < y:
            parent[y] = x
        elif y < x:
            parent[x] = y
    lab = np.full(n, -1, dtype=np.int64)
    count = 0
    for p in range(n):
        if not mask[p]:
            continue
        x = p
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        if x == p:  # the lowest point of its component is its root: the first one met
            lab[p] = count
            count += 1
        else:
            lab[p] = lab[x]
    return lab, count


def _chain_order(n, src, dst, dd, chn, n_chn):  # pragma: no cover - compiled
    """Every chain ordered by geodesic distance from one end (see robust._order_chains).

    Chain ``c`` is the set of points with ``chn == c`` (-1: none), joined by the edges
    ``(src[i], dst[i])`` with both ends in it, undirected, of length ``max(dd[i], 1e-12)``.
    Its far end is the point geodesically farthest from its lowest id (ties: the lowest id);
    its points are ordered by their geodesic distance from the far end (ties: by id). Both
    are Dijkstra runs inside the chain: a distance is the smallest sum of edge lengths, added
    up along a path from its source (what scipy's ``dijkstra`` gives, bit for bit).

    Parameters
    ----------
    n : int
        Number of points.
    src, dst : (E,) ndarray of int64
        Edges.
    dd : (E,) ndarray of float
        Their lengths.
    chn : (n,) ndarray of int64
        Chain of every point (-1: none); every chain is connected by its edges.
    n_chn : int
        Number of chains.

    Returns
    -------
    ids_o : (M,) ndarray of int64
        The points of all chains (M of them), chain by chain, each chain in order.
    par_o : (M,) ndarray of float
        Their distance from their chain's far end.
    bounds : (n_chn + 1,) ndarray of int64
        Chain ``c`` is ``ids_o[bounds[c]:bounds[c + 1]]``.
    """
    m = src.shape[0]
    # the undirected adjacency of the chain edges (counting sort)
    deg = np.zeros(n + 1, dtype=np.int64)
    for i in range(m):
        a = src[i]
        b = dst[i]
        if chn[a] >= 0 and chn[a] == chn[b]:
            deg[a + 1] += 1
            deg[b + 1] += 1
    for i in range(n):
        deg[i + 1] += deg[i]
    nbr = np.empty(deg[n], dtype=np.int64)
    wt = np.empty(deg[n], dtype=np.float64)
    fill = deg[:-1].copy()
    for i in range(m):
        a = src[i]
        b = dst[i]
        if chn[a] >= 0 and chn[a] == chn[b]:
            w = dd[i] if dd[i] > 1e-12 else 1e-12
            nbr[fill[a]] = b
            wt[fill[a]] = w
            fill[a] += 1
            nbr[fill[b]] = a
            wt[fill[b]] = w
            fill[b] += 1
    # the members of each chain, ascending
    bounds = np.zeros(n_chn + 1, dtype=np.int64)
    for p in range(n):
        if chn[p] >= 0:
            bounds[chn[p] + 1] += 1
    for c in range(n_chn):
        bounds[c + 1] += bounds[c]
    mem = np.empty(bounds[n_chn], dtype=np.int64)
    fc = bounds[:-1].copy()
    for p in range(n):
        c = chn[p]
        if c >= 0:
            mem[fc[c]] = p
            fc[c] += 1
    # heap room: one entry per push, at most 1 + the adjacency size of the chain
    cap = 1
    for c in range(n_chn):
        x = 1
        for j in range(bounds[c], bounds[c + 1]):
            x += deg[mem[j] + 1] - deg[mem[j]]
        if x > cap:
            cap = x
    heap_k = np.empty(cap, dtype=np.float64)
    heap_v = np.empty(cap, dtype=np.int64)
    gd = np.zeros(n, dtype=np.float64)
    mark = np.full(n, -1, dtype=np.int64)  # == run when gd is set in that run
    done = np.full(n, -1, dtype=np.int64)  # == run when settled in that run
    ids_o = np.empty(bounds[n_chn], dtype=np.int64)
    par_o = np.empty(bounds[n_chn], dtype=np.float64)
    for c in range(n_chn):
        b0 = bounds[c]
        b1 = bounds[c + 1]
        s = mem[b0]
        for rep in range(2):
            run = 2 * c + rep
            # Dijkstra from s (lazy deletion binary heap, ties by id); settled order into ids_o
            hs = 1
            heap_k[0] = 0.0
            heap_v[0] = s
            mark[s] = run
            gd[s] = 0.0
            k = b0
            while hs > 0:
                key, a, hs = _heap_pop(heap_k, heap_v, hs)
                if done[a] == run or key > gd[a]:
                    continue
                done[a] = run
                ids_o[k] = a
                par_o[k] = key
                k += 1
                for e in range(deg[a], deg[a + 1]):
                    b = nbr[e]
                    if done[b] == run:
                        continue
                    nk = key + wt[e]
                    if mark[b] == run and gd[b] <= nk:
                        continue
                    mark[b] = run
                    gd[b] = nk
                    hs = _heap_push(heap_k, heap_v, hs, nk, b)
            if rep == 0:
                # the far end: the largest distance, ties the lowest id
                best = -1.0
                for j in range(b0, b1):
                    p = mem[j]
                    if gd[p] > best:
                        best = gd[p]
                        s = p
        # settled by distance (non-decreasing); equal distances by id
        i = b0
        while i < b1:
            j = i + 1
            while j < b1 and par_o[j] == par_o[i]:
                j += 1
            for x in range(i + 1, j):  # insertion sort (ties are few and short)
                v = ids_o[x]
                y = x - 1
                while y >= i and ids_o[y] > v:
                    ids_o[y + 1] = ids_o[y]
                    y -= 1
                ids_o[y + 1] = v
            i = j
    return ids_o, par_o, bounds


def _chain_ends(h, ids_o, par_o, bounds, c_reg, c_par, cb):  # pragma: no cover - compiled
    """The region each end of every chain touches (see robust._order_chains).

    Chain ``ci`` is ``ids_o[bounds[ci]:bounds[ci + 1]]`` with positions ``par_o`` (ascending,
    its length ``L`` the last one); its contacts ``cb[ci]:cb[ci + 1]`` give a region
    ``c_reg`` (ascending within the chain) and a position ``c_par``. With ``hl`` the median
    spacing of the chain and ``reach = min(L / 2, 4 hl)``, the start end takes the most frequent
    region among contacts at ``c_par <= reach`` and the far end among ``c_par >= L - reach``
    (for a chain shorter than ``2 reach``: ``<= L / 2`` and ``> L / 2``); ties: the lowest
    region; none: -1.

    Returns
    -------
    ends : (n_chains, 2) ndarray of int64
    touch : (n_chains,) ndarray of bool
        Whether the chain has any contact.
    """
    nc = bounds.shape[0] - 1
    ends = np.full((nc, 2), -1, dtype=np.int64)
    touch = np.zeros(nc, dtype=np.bool_)
    for ci in range(nc):
        a0 = bounds[ci]
        a1 = bounds[ci + 1]
        b0 = cb[ci]
        b1 = cb[ci + 1]
        if b1 <= b0:
            continue
        touch[ci] = True
        L = par_o[a1 - 1] if a1 > a0 else 0.0
        hs = np.sort(h[ids_o[a0:a1]])
        m = hs.shape[0]
        if m % 2 == 1:
            hl = hs[m // 2]
        else:
            hl = (hs[m // 2 - 1] + hs[m // 2]) / 2.0
        reach = 0.5 * L
        if 4.0 * hl < reach:
            reach = 4.0 * hl
        short = L <= 2 * reach
        for side in range(2):
            best = -1
            best_cnt = 0
            cur = -1
            cnt = 0
            for e in range(b0, b1):
                cp = c_par[e]
                if side == 0:
                    ok = (cp <= 0.5 * L) if short else (cp <= reach)
                else:
                    ok = (cp > 0.5 * L) if short else (cp >= L - reach)
                if not ok:
                    continue
                r = c_reg[e]
                if r != cur:
                    if cnt > best_cnt:
                        best = cur
                        best_cnt = cnt
                    cur = r
                    cnt = 0
                cnt += 1
            if cnt > best_cnt:
                best = cur
                best_cnt = cnt
            ends[ci, side] = best
    return ends, touch


def _branch_buffer(flat, off, extra):  # pragma: no cover - compiled
    """Branches ``flat[off[b]:off[b + 1]]`` as the rows of an array with room for ``extra``
    more ids each: ``buf`` (n_branches, longest + extra) and the lengths ``cnt``."""
    nbr = off.shape[0] - 1
    cap = 1
    for b in range(nbr):
        if off[b + 1] - off[b] > cap:
            cap = off[b + 1] - off[b]
    buf = np.zeros((nbr, cap + extra), dtype=np.int64)
    cnt = np.zeros(nbr, dtype=np.int64)
    for b in range(nbr):
        n = off[b + 1] - off[b]
        for i in range(n):
            buf[b, i] = flat[off[b] + i]
        cnt[b] = n
    return buf, cnt


def _extend_into_region(P, h, indptr, indices, flat, off, rs, width, wnoise):  # pragma: no cover - compiled
    """Walk every branch end into its junction region, in turns (see robust._junction_positions).

    Branch ``b`` is ``flat[off[b]:off[b + 1]]`` (running towards the junction); ``rs`` the sorted
    unique region points. Each round, every active branch (at least 2 points) proposes the
    nearest unclaimed region point linked to its end ``cur`` (CSR ``indptr``, ``indices``) that
    lies ahead, ``al > h_cur / 4`` along the unit direction from the point ``3 h_cur`` back
    along the branch (as ``robust._end_portion``) to ``cur``, and within
    ``max(width * h_cur, wnoise)`` of that line; distance ``hypot(al, perp)``, ties: lowest id.
    A branch with no such point stops. Proposals are taken by increasing (distance, id), a
    point claimed once only. Rounds stop when nothing is proposed.

    Returns
    -------
    buf : (n_branches, cap) ndarray of int64
    cnt : (n_branches,) ndarray of int64
        Branch ``b`` extended is ``buf[b, :cnt[b]]``.
    """
    nbr = off.shape[0] - 1
    nr = rs.shape[0]
    d = P.shape[1]
    buf, cnt = _branch_buffer(flat, off, nr + 1)
    active = np.zeros(nbr, dtype=np.bool_)
    for b in range(nbr):
        active[b] = cnt[b] >= 2
    claimed = np.zeros(nr, dtype=np.bool_)
    pd_ = np.empty(nbr)
    pj = np.empty(nbr, dtype=np.int64)
    pb = np.empty(nbr, dtype=np.int64)
    u = np.empty(d)
    for it in range(nr + 1):
        npr = 0
        for bi in range(nbr):
            if not active[bi]:
                continue
            n = cnt[bi]
            cur = buf[bi, n - 1]
            hl = h[cur]
            # the end portion over 3 h: prefix sums of the reversed branch
            lim = 3.0 * hl
            s = 0.0
            m = 1
            for q in range(n - 1, 0, -1):
                a = buf[bi, q]
                c2 = buf[bi, q - 1]
                sq = 0.0
                for c in range(d):
                    t = P[c2, c] - P[a, c]
                    sq = sq + t * t if c > 0 else t * t
                s += np.sqrt(sq)
                if not s <= lim:
                    break
                m += 1
            if m < 3 and n >= 3:
                m = 3
            elif m < n and n < 3:
                m = n
            far = buf[bi, n - m]
            nu2 = 0.0
            for c in range(d):
                u[c] = P[cur, c] - P[far, c]
                nu2 += u[c] * u[c]
            nu = np.sqrt(nu2)
            if nu == 0:
                active[bi] = False
                continue
            for c in range(d):
                u[c] = u[c] / nu
            w = width * hl
            if wnoise > w:
                w = wnoise
            any_nb = False
            best_d = np.inf
            best_j = -1
            for e in range(indptr[cur], indptr[cur + 1]):
                j = indices[e]
                pos = np.searchsorted(rs, j)
                if pos >= nr or rs[pos] != j or claimed[pos]:
                    continue
                any_nb = True
                al = 0.0
                vv = 0.0
                for c in range(d):
                    v = P[j, c] - P[cur, c]
                    al += v * u[c]
                    vv = vv + v * v if c > 0 else v * v
                x = vv - al * al
                perp = np.sqrt(x if x > 0.0 else 0.0)
                if al > 0.25 * hl and perp <= w:
                    dj = np.hypot(al, perp)
                    if dj < best_d or (dj == best_d and j < best_j):
                        best_d = dj
                        best_j = j
            if not any_nb or best_j < 0:
                active[bi] = False
                continue
            # insert the proposal, sorted by (distance, id), stable
            i = npr
            while i > 0 and (pd_[i - 1] > best_d or (pd_[i - 1] == best_d and pj[i - 1] > best_j)):
                pd_[i] = pd_[i - 1]
                pj[i] = pj[i - 1]
                pb[i] = pb[i - 1]
                i -= 1
            pd_[i] = best_d
            pj[i] = best_j
            pb[i] = bi
            npr += 1
        if npr == 0:
            break
        for i in range(npr):
            pos = np.searchsorted(rs, pj[i])
            if claimed[pos]:
                continue
            bi = pb[i]
            buf[bi, cnt[bi]] = pj[i]
            cnt[bi] += 1
            claimed[pos] = True
    return buf, cnt


def _fit_end(P, h, ids, span, mu, u, C, V, ev, with_dir):  # pragma: no cover - compiled
    """Line through the end portion of ``ids`` (running towards the end) over ``span`` h.

    The end portion is that of ``robust._end_portion``: the points from the last id backwards
    within arc length ``span * h[ids[-1]]``, at least ``min(3, n)``. Its mean goes into ``mu``
    and, when ``with_dir``, its principal direction into ``u``. Returns the number of points in
    the portion (the direction is meaningful only when it is at least 2).
    """
    n = ids.shape[0]
    d = P.shape[1]
    if n < 2:
        m = n
    else:
        m = _end_count(P, ids, span * h[ids[n - 1]])
        if m < 3 and n >= 3:
            m = 3
        elif m < n and n < 3:
            m = n
    for c in range(d):
        acc = 0.0
        for q in range(n - m, n):
            acc += P[ids[q], c]
        mu[c] = acc / m if m > 0 else 0.0
    if not with_dir:
        return m
    for i in range(d):
        for j in range(i, d):
            acc = 0.0
            for q in range(n - m, n):
                acc += (P[ids[q], i] - mu[i]) * (P[ids[q], j] - mu[j])
            C[i, j] = acc
            C[j, i] = acc
    if m >= 2:
        _eig_top(C, V, ev)
        for c in range(d):
            u[c] = V[c, d - 1]
    return m


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


def _junction_nodes(P, h, indptr, indices, bflat, boff, jb, rflat, roff, hj, width, noise, consts):  # pragma: no cover - compiled
    """Node position of many junctions at once (see ``robust._junction_positions``).

    Junction ``j`` has the branches ``jb[j] .. jb[j + 1] - 1``; branch ``b`` is
    ``bflat[boff[b]:boff[b + 1]]`` (point ids running towards the junction); its region points
    are ``rflat[roff[j]:roff[j + 1]]`` (sorted, unique). ``hj[j]``: the junction's spacing (the
    median over its region points; without region points, over its branches' first points).
    ``consts``: JSPAN, JN, WALK_DEV, NW, the node's largest distance from the
    anchor in spacings, SWALLOW * shell_outer, SWALLOW_COS, WIDEN, use the graph (1 or 0).

    Each branch is walked into the region (:func:`_extend_into_region`), the walk cut where it
    leaves a strip of ``WALK_DEV`` link widths around the line fitted on the branch's end; the
    node is the least-squares intersection of the lines fitted on the walked ends, pulled a
    little (weight 1e-2) towards the mean of the branch ends (the anchor), and the anchor when
    it lands over the largest distance away.

    Returns
    -------
    X : (n_junctions, d) ndarray
        Node positions.
    maybe : (n_junctions,) ndarray of bool
        Whether a free branch may hide in the region (a superset of what
        ``robust._swallowed_branches`` finds: False means it finds none).
    """
    nj = jb.shape[0] - 1
    d = P.shape[1]
    jspan = consts[0]
    jn = consts[1]
    walk_dev = consts[2]
    nw = consts[3]
    far = consts[4]
    swallow_r = consts[5]
    swallow_cos = consts[6]
    widen = consts[7]
    use_graph = consts[8] > 0.5
    X = np.zeros((nj, d))
    maybe = np.zeros(nj, dtype=np.bool_)
    mu = np.zeros(d)
    u = np.zeros(d)
    C = np.zeros((d, d))
    V = np.zeros((d, d))
    ev = np.zeros(d)
    A = np.zeros((d, d))
    bb = np.zeros(d)
    x = np.zeros(d)
    anchor = np.zeros(d)
    for j in range(nj):
        b0 = jb[j]
        b1 = jb[j + 1]
        nbr = b1 - b0
        rid = rflat[roff[j]:roff[j + 1]]
        nr = rid.shape[0]
        base = boff[b0]
        flat = bflat[base:boff[b1]]
        off = boff[b0:b1 + 1] - base
        # walked branches: buf[bi, :L[bi]]
        if nr > 0 and use_graph:
            buf, cnt = _extend_into_region(P, h, indptr, indices, flat, off, rid, width, nw * noise)
            L = cnt.copy()
            for bi in range(nbr):
                n0 = off[bi + 1] - off[bi]
                if cnt[bi] <= n0 or n0 < 2:
                    continue
                orig = flat[off[bi]:off[bi + 1]]
                hl0 = h[orig[n0 - 1]]
                m = _fit_end(P, h, orig, jspan + jn * noise / hl0, mu, u, C, V, ev, True)
                if m < 2:
                    continue
                lim = width * hl0
                if nw * noise > lim:
                    lim = nw * noise
                lim = walk_dev * lim
                for q in range(n0, cnt[bi]):
                    p = buf[bi, q]
                    al = 0.0
                    r2 = 0.0
                    for c in range(d):
                        t = P[p, c] - mu[c]
                        al += t * u[c]
                        r2 += t * t
                    dv = r2 - al * al
                    dev = np.sqrt(dv if dv > 0.0 else 0.0)
                    if dev > lim:
                        L[bi] = q
                        break
        else:
            buf, L = _branch_buffer(flat, off, 0)
        for a in range(d):
            bb[a] = 0.0
            anchor[a] = 0.0
            for c in range(d):
                A[a, c] = 0.0
        ncs = 0
        for bi in range(nbr):
            ids = buf[bi, :L[bi]]
            n = ids.shape[0]
            if n == 0:
                continue
            m = _fit_end(P, h, ids, jspan + jn * noise / h[ids[n - 1]], mu, u, C, V, ev, True)
            for c in range(d):
                anchor[c] += P[ids[n - 1], c]
            ncs += 1
            if m < 2:
                continue
            # M = I - u u^T; A += M; b += M mu
            um = 0.0
            for c in range(d):
                um += u[c] * mu[c]
            for a in range(d):
                for c in range(d):
                    A[a, c] += (1.0 if a == c else 0.0) - u[a] * u[c]
                bb[a] += mu[a] - u[a] * um
        if ncs > 0:
            for c in range(d):
                anchor[c] = anchor[c] / ncs
        else:
            for c in range(d):
                acc = 0.0
                for q in range(nr):
                    acc += P[rid[q], c]
                anchor[c] = acc / nr if nr > 0 else 0.0
        hl = hj[j]
        for a in range(d):
            A[a, a] += 1e-2
            bb[a] += 1e-2 * anchor[a]
        ok = _solve_small(A, bb, x)
        dist2 = 0.0
        for c in range(d):
            if not np.isfinite(x[c]):
                ok = False
            dist2 += (x[c] - anchor[c]) ** 2
        if not ok or not np.sqrt(dist2) <= far * hl:
            for c in range(d):
                x[c] = anchor[c]
        for c in range(d):
            X[j, c] = x[c]
        # a free branch hidden in the region: some region point far from the node, in a
        # direction no branch takes (tested again exactly by robust._swallowed_branches)
        if nr < 3:
            continue
        hs = hl + widen * noise
        ndir = 0
        D = np.zeros((nbr, d))
        for bi in range(nbr):
            orig = flat[off[bi]:off[bi + 1]]
            _fit_end(P, h, orig, jspan, mu, u, C, V, ev, False)  # the mean of the end only
            nu2 = 0.0
            for c in range(d):
                D[ndir, c] = mu[c] - x[c]
                nu2 += D[ndir, c] ** 2
            if nu2 > 0.0:
                nu = np.sqrt(nu2)
                for c in range(d):
                    D[ndir, c] /= nu
                ndir += 1
        if ndir == 0:
            continue
        for q in range(nr):
            p = rid[q]
            r2 = 0.0
            for c in range(d):
                r2 += (P[p, c] - x[c]) ** 2
            dq = np.sqrt(r2)
            if not dq > swallow_r * hs * (1.0 - 1e-9):
                continue
            best = -np.inf
            for k in range(ndir):
                al = 0.0
                for c in range(d):
                    al += (P[p, c] - x[c]) * D[k, c]
                if al > best:
                    best = al
            if best / dq < swallow_cos + 1e-9:
                maybe[j] = True
                break
    return X, maybe


def _behind_count(P, h, ids, lo, hi, step, x, span2):  # pragma: no cover - compiled
    """How many leading ids of ``ids[lo:hi]`` (read from ``lo`` up when ``step`` is 1, from
    ``hi - 1`` down when it is -1) lie behind the node ``x``.

    The chain's direction is that from ``x`` to its point ``k``, the first at arc length
    ``span2 * h`` from the start (at most the last); leading points whose offset from ``x`` has
    no positive component along it are behind. At least 2 points are kept. (The numpy formula
    is the reference of tests/test_robust_kernels.py.)"""
    n = hi - lo
    if n < 4:
        return 0
    d = P.shape[1]
    first = ids[lo] if step == 1 else ids[hi - 1]
    lim = span2 * h[first]
    # k: the first index whose arc length from the start is >= lim (at most n - 1)
    s = 0.0
    k = 0
    if not s >= lim:
        k = n - 1
        for i in range(1, n):
            a = ids[lo + i - 1] if step == 1 else ids[hi - i]
            b = ids[lo + i] if step == 1 else ids[hi - 1 - i]
            sq = 0.0
            for c in range(d):
                t = P[b, c] - P[a, c]
                sq += t * t
            s += np.sqrt(sq)
            if s >= lim:
                k = i
                break
    pk = ids[lo + k] if step == 1 else ids[hi - 1 - k]
    nu2 = 0.0
    for c in range(d):
        nu2 += (P[pk, c] - x[c]) ** 2
    nu = np.sqrt(nu2)
    if nu == 0:
        return 0
    j = 0
    while j < k:
        p = ids[lo + j] if step == 1 else ids[hi - 1 - j]
        al = 0.0
        for c in range(d):
            al += (P[p, c] - x[c]) * ((P[pk, c] - x[c]) / nu)
        if not al <= 0:
            break
        j += 1
    return j if j < n - 2 else n - 2


def _dist2(X, a, b):  # pragma: no cover - compiled
    """Squared distance between the rows ``a`` and ``b`` of ``X``."""
    s = 0.0
    for q in range(X.shape[1]):
        t = X[b, q] - X[a, q]
        s += t * t
    return s


#: noisy tangents (see _noisy_tangents): directions to the NOISY_CAND nearest are scored; the
#: strip reaches NOISY_A spacings (+ 2 sigma) along, is max(NOISY_WH h, NOISY_WF sigma) wide
#: (Gaussian weights, cut at NOISY_CUT widths); the refining PCA takes the points within
#: max(h, NOISY_RW sigma) of the line
NOISY_CAND = 16
NOISY_A = 5.0
NOISY_WF = 2.0
NOISY_WH = 0.5
NOISY_CUT = 3.0
NOISY_RW = 2.5
#: a candidate direction within this cosine (10 degrees) of one already scored is not scored
#: again: the refinement, whose strip is at least a spacing wide over 5 spacings, starts from the
#: same points
NOISY_SAME = float(np.cos(np.radians(10.0)))
#: rows per block of the noisy-tangent kernel (one set of scratch arrays per block)
NOISY_ROWS = 256


def _noisy_scales(hp, sig):  # pragma: no cover - compiled
    """Strip width, reach along and refining width of the noisy tangent at spacing ``hp``
    (see :func:`_noisy_tangents`; scalars, or arrays of ``hp`` in numpy)."""
    return np.maximum(NOISY_WH * hp, NOISY_WF * sig), NOISY_A * hp + 2.0 * sig, np.maximum(hp, NOISY_RW * sig)


def noisy_reach(h, sig):
    """How far from a point the noisy tangent reads its neighbours (see :func:`_noisy_tangents`):
    a neighbour farther away changes nothing. Works on arrays of ``h``."""
    W, amax, rw = _PY_HELPERS["_noisy_scales"](h, sig)  # (the numpy one, also when compiled)
    lat = np.maximum(NOISY_CUT * W, rw)
    return np.sqrt(amax * amax + lat * lat)


def _noisy_tangents(P, rows, idx, h, sig):  # pragma: no cover - compiled
    """Tangent and linearity of the points ``rows`` ((R,) ids) of a noisy cloud, whose ``k``
    nearest neighbours are the rows of ``idx`` ((R, k)).

    Where sparse, noisy curves run 2 to 3 spacings apart, the nearest neighbours of a point lie
    as often across as along: the best line is found over a longer reach. The direction towards
    each of the ``NOISY_CAND`` nearest neighbours (within ``amax``, below; not within 10 degrees
    of one scored before) is scored by the sum, over all ``k`` neighbours
    within ``amax = NOISY_A * h + 2 sig`` along it and ``NOISY_CUT * w`` across, of
    ``exp(-(r / w)^2)``, ``r`` the distance from the line through the point and
    ``w = max(NOISY_WH * h, NOISY_WF * sig)``; the best (the first of equal scores) is refined
    twice by the PCA of the point and its neighbours within ``max(h, NOISY_RW * sig)`` of the
    current line and ``amax`` along it. The linearity is ``1 - l2 / l1`` of the last PCA.
    Neighbours beyond :func:`noisy_reach` take no part.

    Returns
    -------
    T : (R, d) ndarray
        Unit tangents (sign arbitrary).
    lin : (R,) ndarray
    """
    n = rows.shape[0]
    d = P.shape[1]
    k = idx.shape[1]
    T = np.zeros((n, d))
    lin = np.zeros(n)
    nblk = (n + NOISY_ROWS - 1) // NOISY_ROWS
    for bi in prange(nblk):  # blocks of rows, each with one set of scratch arrays
        Q = np.empty((k + 1, d))
        R2 = np.empty(k + 1)
        w = np.zeros(k + 1)
        C = np.zeros((d, d))
        V = np.zeros((d, d))
        ev = np.zeros(d)
        mu = np.zeros(d)
        t = np.zeros(d)
        u = np.zeros(d)
        U = np.zeros((k, d))
        for ri in range(bi * NOISY_ROWS, min(n, (bi + 1) * NOISY_ROWS)):
            lin[ri] = _noisy_tangent_at(P, rows[ri], idx[ri], h[rows[ri]], sig, Q, R2, w, C, V, ev, mu, t, u, U)
            for c in range(d):
                T[ri, c] = t[c]
    return T, lin


def _noisy_tangent_at(P, p, nb, hp, sig, Q, R2, w, C, V, ev, mu, t, u, U):  # pragma: no cover - compiled
    """The noisy tangent of the point ``p`` (neighbour ids ``nb``, (k,); local spacing ``hp``)
    into ``t``; returns its linearity. The other arrays are scratch (see
    :func:`_noisy_tangents`)."""
    d = P.shape[1]
    k = nb.shape[0]
    nc = NOISY_CAND if NOISY_CAND < k else k
    for c in range(d):
        Q[0, c] = 0.0
    R2[0] = 0.0
    for j in range(k):
        r2 = 0.0
        for c in range(d):
            Q[j + 1, c] = P[nb[j], c] - P[p, c]
            r2 += Q[j + 1, c] * Q[j + 1, c]
        R2[j + 1] = r2
    W, amax, rw = _noisy_scales(hp, sig)
    w2 = W * W
    qmax = NOISY_CUT * NOISY_CUT * w2
    best = -np.inf
    ns = 0
    for j in range(nc):
        if R2[j + 1] > amax * amax and j > 0:  # (a direction the nearer ones give)
            continue
        r = np.sqrt(R2[j + 1])
        if r < 1e-300:
            r = 1e-300
        for c in range(d):
            u[c] = Q[j + 1, c] / r
        dup = False
        for i in range(ns):  # (a direction within NOISY_SAME of one scored)
            x = 0.0
            for c in range(d):
                x += U[i, c] * u[c]
            if abs(x) > NOISY_SAME:
                dup = True
                break
        if dup:
            continue
        for c in range(d):
            U[ns, c] = u[c]
        ns += 1
        sc = 0.0
        for i in range(1, k + 1):
            al = 0.0
            for c in range(d):
                al += Q[i, c] * u[c]
            if al > amax or al < -amax:
                continue
            q2 = R2[i] - al * al
            if q2 < 0.0:
                q2 = 0.0
            if q2 > qmax:
                continue
            sc += np.exp(-q2 / w2)
        if sc > best:
            best = sc
            for c in range(d):
                t[c] = u[c]
    rw2 = rw * rw
    lp = 0.0
    for it in range(2):
        w[0] = 1.0
        for i in range(1, k + 1):
            al = 0.0
            for c in range(d):
                al += Q[i, c] * t[c]
            w[i] = 1.0 if (R2[i] - al * al <= rw2 and abs(al) <= amax) else 0.0
        for c in range(d):
            u[c] = t[c]
        _pca01(Q, k + 1, w, C, V, ev, mu, t)
        sg = 0.0
        for c in range(d):
            sg += t[c] * u[c]
        if sg < 0.0:
            for c in range(d):
                t[c] = -t[c]
        lam = ev[d - 1]
        if lam < 1e-300:
            lam = 1e-300
        lp = 1.0 - ev[d - 2] / lam
    return lp


#: the strand test (see _strand_cuts)
STRAND_COS = float(np.cos(np.radians(20.0)))
STRAND_T0 = 2.0
STRAND_A = 4.0
STRAND_B = 1.5
STRAND_BH = 0.35
STRAND_THR = 3.0
STRAND_DMIN = 1.5
STRAND_NMIN = 3
STRAND_SIDE = 0.5
STRAND_LCOS = float(np.cos(np.radians(15.0)))
STRAND_IT = 30
#: links per block of the strand-cut kernel (one set of scratch arrays per block)
STRAND_ROWS = 1024


def _shift_mode(L, cnt, x0, b, out):  # pragma: no cover - compiled
    """Mean shift (Gaussian kernel of width ``b``) over the rows ``L[:cnt]`` from ``x0``: the
    mode into ``out``."""
    d = L.shape[1]
    for c in range(d):
        out[c] = x0[c]
    x2 = np.zeros(d)
    for it in range(STRAND_IT):
        sw = 0.0
        for c in range(d):
            x2[c] = 0.0
        for i in range(cnt):
            r2 = 0.0
            for c in range(d):
                z = L[i, c] - out[c]
                r2 += z * z
            wi = np.exp(-0.5 * r2 / (b * b))
            sw += wi
            for c in range(d):
                x2[c] += wi * L[i, c]
        if not sw > 0.0:  # every weight underflowed (x0 far from all rows): x0 stays the mode
            break
        mv = 0.0
        for c in range(d):
            x2[c] /= sw
            z = x2[c] - out[c]
            mv += z * z
            out[c] = x2[c]
        if mv < 1e-12 * b * b:
            break


def _density(L, cnt, x, b):  # pragma: no cover - compiled
    """Kernel density (unnormalized) of the rows ``L[:cnt]`` at ``x``."""
    d = L.shape[1]
    f = 0.0
    for i in range(cnt):
        r2 = 0.0
        for c in range(d):
            z = L[i, c] - x[c]
            r2 += z * z
        f += np.exp(-0.5 * r2 / (b * b))
    return f


def _mean_line_offset(P, t, p, i, tb, out):  # pragma: no cover - compiled
    """Offset of ``P[i]`` from the line through ``P[p]`` along the mean of the tangents ``t[p]``
    and ``t[i]`` (``t[i]`` turned to agree with ``t[p]``), into ``out`` (d,); ``tb`` (d,) is
    scratch (left holding the mean direction)."""
    d = P.shape[1]
    dj = 0.0
    for c in range(d):
        dj += t[p, c] * t[i, c]
    sg = 1.0 if dj >= 0.0 else -1.0
    nn = 0.0
    for c in range(d):
        tb[c] = sg * t[i, c] + t[p, c]
        nn += tb[c] * tb[c]
    nn = np.sqrt(nn)
    a2 = 0.0
    for c in range(d):
        tb[c] /= nn
        a2 += (P[i, c] - P[p, c]) * tb[c]
    for c in range(d):
        out[c] = P[i, c] - P[p, c] - a2 * tb[c]


def _strand_cuts(P, h, idx, t, src, dst, sig):  # pragma: no cover - compiled
    """The links of a noisy cloud that join two parallel strands (close parallel curves).

    For the link ``p -> q`` between nearly parallel tangents (``STRAND_COS``) whose far end lies
    more than ``max(STRAND_T0 sig, STRAND_DMIN h_p / 2)`` from the tangent line at ``p``: the
    offsets across the strand of ``p`` and of its neighbours within ``STRAND_A h_p`` along it
    (each from the line through ``p`` along the mean of the two tangents, which follows a bend)
    are searched for modes by mean shift (width ``max(STRAND_B sig, STRAND_BH h_p)``), once from
    ``p`` and once from ``q``. The link is cut when the two modes lie more than
    ``max(STRAND_THR sig, STRAND_DMIN h_p)`` apart with a density valley between them, and each
    mode holds at least ``STRAND_NMIN`` points that run parallel to ``t_p`` (``STRAND_LCOS``) on
    both sides of the link (beyond ``STRAND_SIDE h_p`` along): two strands, not one strand's
    noise, bend or crossing.

    Returns
    -------
    (E,) ndarray of bool
    """
    d = P.shape[1]
    k = idx.shape[1]
    ne = src.shape[0]
    cut = np.zeros(ne, dtype=np.bool_)
    nblk = (ne + STRAND_ROWS - 1) // STRAND_ROWS
    for bi in prange(nblk):  # blocks of links, each with one set of scratch arrays
        L = np.empty((k + 1, d))
        X = np.empty((k + 1, d))
        A = np.empty(k + 1)
        w = np.zeros(k + 1)
        C = np.zeros((d, d))
        V = np.zeros((d, d))
        ev = np.zeros(d)
        mu = np.zeros(d)
        u = np.zeros(d)
        tb = np.zeros(d)
        v = np.zeros(d)
        lq = np.zeros(d)
        zero = np.zeros(d)
        ms = np.zeros(d)
        mq = np.zeros(d)
        mid = np.zeros(d)
        for e in range(bi * STRAND_ROWS, min(ne, (bi + 1) * STRAND_ROWS)):
            p = src[e]
            q = dst[e]
            dot = 0.0
            for c in range(d):
                dot += t[p, c] * t[q, c]
            if abs(dot) < STRAND_COS:
                continue
            al = 0.0
            r2 = 0.0
            for c in range(d):
                v[c] = P[q, c] - P[p, c]
                al += v[c] * t[p, c]
                r2 += v[c] * v[c]
            lat2 = r2 - al * al
            lim = STRAND_T0 * sig
            if 0.5 * STRAND_DMIN * h[p] > lim:
                lim = 0.5 * STRAND_DMIN * h[p]
            if not (lat2 > lim * lim):
                continue
            al_pq = al
            _mean_line_offset(P, t, p, q, tb, lq)  # q's offset
            # the window: p and its neighbours within STRAND_A h_p along t_p
            cnt = 0
            for j in range(-1, k):
                i = p if j < 0 else idx[p, j]
                aj = 0.0
                for c in range(d):
                    aj += (P[i, c] - P[p, c]) * t[p, c]
                if aj > STRAND_A * h[p] or aj < -STRAND_A * h[p]:
                    continue
                _mean_line_offset(P, t, p, i, tb, L[cnt])
                for c in range(d):
                    X[cnt, c] = P[i, c]
                A[cnt] = aj
                cnt += 1
            b = STRAND_B * sig
            if STRAND_BH * h[p] > b:
                b = STRAND_BH * h[p]
            _shift_mode(L, cnt, zero, b, ms)
            _shift_mode(L, cnt, lq, b, mq)
            sep = 0.0
            for c in range(d):
                z = ms[c] - mq[c]
                sep += z * z
                mid[c] = 0.5 * (ms[c] + mq[c])
            lim = STRAND_THR * sig
            if STRAND_DMIN * h[p] > lim:
                lim = STRAND_DMIN * h[p]
            if not (sep > lim * lim):
                continue
            fs = _density(L, cnt, ms, b)
            fq = _density(L, cnt, mq, b)
            if not (_density(L, cnt, mid, b) < min(fs, fq)):
                continue
            ok = True
            for which in range(2):
                nm = 0
                lo = np.inf
                hi = -np.inf
                for i in range(cnt):
                    r2 = 0.0
                    for c in range(d):
                        z = L[i, c] - (ms[c] if which == 0 else mq[c])
                        r2 += z * z
                    if r2 <= (1.5 * b) * (1.5 * b):
                        w[i] = 1.0
                        nm += 1
                        am = A[i] - 0.5 * al_pq
                        if am < lo:
                            lo = am
                        if am > hi:
                            hi = am
                    else:
                        w[i] = 0.0
                if nm < STRAND_NMIN or not (lo < -STRAND_SIDE * h[p] and hi > STRAND_SIDE * h[p]):
                    ok = False
                    break
                _pca01(X, cnt, w, C, V, ev, mu, u)
                dj = 0.0
                for c in range(d):
                    dj += u[c] * t[p, c]
                if abs(dj) < STRAND_LCOS:
                    ok = False
                    break
            if ok:
                cut[e] = True
    return cut


def _untangle(X, off, which, w, cos_back):  # pragma: no cover - compiled
    """A shorter order of the inner points of the curves ``which`` (windowed 2-opt).

    The curves are ``X[off[c]:off[c + 1]]``, concatenated; each keeps its first and last
    point. In sweeps (at most 50) over the positions ``i`` up to ``w`` points before a turn
    back (two successive nonzero steps with direction cosine under ``cos_back``), the
    reversal of ``[i + 1, j]``, ``j`` within ``w`` points after ``i``, that shortens the
    polyline most is made, until a sweep makes none: the path loses its crossings and its
    back-and-forth steps. Only ``+ - * /`` and ``sqrt``: compiled and Python runs agree.

    Returns
    -------
    order : (M,) ndarray of int64
        A permutation of the rows of ``X`` (the identity outside the curves ``which``).
    """
    M = X.shape[0]
    d = X.shape[1]
    order = np.arange(M)
    near = np.zeros(M, dtype=np.bool_)
    for wi in range(which.shape[0]):
        c = which[wi]
        s0 = off[c]
        n = off[c + 1] - s0
        if n < 4:
            continue
        for sweep in range(50):
            # the turn backs of the current order
            for k in range(n):
                near[s0 + k] = False
            found = False
            pk = -1
            px = 0.0
            py = 0.0
            pz = 0.0
            for k in range(n - 1):
                a = order[s0 + k]
                b = order[s0 + k + 1]
                L2 = _dist2(X, a, b)
                if not L2 > 0.0:
                    continue
                L = np.sqrt(L2)
                ux = (X[b, 0] - X[a, 0]) / L
                uy = (X[b, 1] - X[a, 1]) / L
                uz = (X[b, 2] - X[a, 2]) / L if d > 2 else 0.0
                if pk >= 0 and ux * px + uy * py + uz * pz < cos_back:
                    found = True
                    lo = pk - w if pk - w > 0 else 0
                    for q in range(lo, pk + 2):
                        near[s0 + q] = True
                pk = k
                px = ux
                py = uy
                pz = uz
            if not found:
                break
            improved = False
            for i in range(n - 3):
                if not near[s0 + i]:
                    continue
                j1 = i + w + 1
                if j1 > n - 1:
                    j1 = n - 1
                a = order[s0 + i]
                b = order[s0 + i + 1]
                dab = np.sqrt(_dist2(X, a, b))
                best = 0.0
                bj = -1
                for j in range(i + 2, j1):
                    cc = order[s0 + j]
                    dd = order[s0 + j + 1]
                    delta = (np.sqrt(_dist2(X, cc, a)) + np.sqrt(_dist2(X, dd, b)) - dab
                             - np.sqrt(_dist2(X, cc, dd)))
                    if bj < 0 or delta < best:
                        best = delta
                        bj = j
                if bj >= 0 and best < -1e-9 * dab:
                    lo = s0 + i + 1
                    hi = s0 + bj
                    while lo < hi:
                        t2 = order[lo]
                        order[lo] = order[hi]
                        order[hi] = t2
                        lo += 1
                        hi -= 1
                    improved = True
            if not improved:
                break
    return order


def _trim_ends(P, h, flat, off, do0, do1, XA, XB, span2):  # pragma: no cover - compiled
    """Chain points lying behind their nodes, for many chains (see :func:`_behind_count`).

    Chain ``c`` is ``flat[off[c]:off[c + 1]]``, from its node ``XA[c]`` to its node ``XB[c]``;
    its start is trimmed when ``do0[c]``, then (what is left) its end when ``do1[c]``.

    Returns
    -------
    lo, hi : (n_chains,) ndarray of int64
        The kept points are ``flat[lo[c]:hi[c]]``.
    """
    nc = off.shape[0] - 1
    lo = off[:-1].copy()
    hi = off[1:].copy()
    for c in range(nc):
        if do0[c]:
            lo[c] += _behind_count(P, h, flat, lo[c], hi[c], 1, XA[c], span2)
        if do1[c]:
            hi[c] -= _behind_count(P, h, flat, lo[c], hi[c], -1, XB[c], span2)
    return lo, hi


def _vote_agreement(t, idx, m):  # pragma: no cover - compiled
    """``sum_k (t[q_k] . t[p])^2`` over the point ``p`` itself and its ``m`` nearest neighbours
    ``q_k = idx[p, k]``, for every point (see robust._vote_tangents)."""
    n = t.shape[0]
    d = t.shape[1]
    out = np.zeros(n)
    for p in prange(n):
        x = 0.0
        for c in range(d):
            x += t[p, c] * t[p, c]
        acc = x * x
        for k in range(m):
            q = idx[p, k]
            x = 0.0
            for c in range(d):
                x += t[q, c] * t[p, c]
            acc += x * x
        out[p] = acc
    return out


def _vote_eig(t, idx, m, cand):  # pragma: no cover - compiled
    """Top eigenvector and coherence ``1 - l2 / l1`` of ``C = sum_k t_k t_k^T`` over each
    candidate point and its ``m`` nearest neighbours (see robust._vote_tangents).

    Returns
    -------
    U : (n_cand, d) ndarray
    coh : (n_cand,) ndarray
    """
    nc = cand.shape[0]
    d = t.shape[1]
    U = np.zeros((nc, d))
    coh = np.zeros(nc)
    bs = 1024
    nb = (nc + bs - 1) // bs
    for b in prange(nb):
        C = np.zeros((d, d))
        V = np.zeros((d, d))
        ev = np.zeros(d)
        i1 = (b + 1) * bs
        for i in range(b * bs, i1 if i1 < nc else nc):
            p = cand[i]
            for a in range(d):
                for c in range(a, d):
                    acc = t[p, a] * t[p, c]
                    for k in range(m):
                        q = idx[p, k]
                        acc += t[q, a] * t[q, c]
                    C[a, c] = acc
                    C[c, a] = acc
            _eig_top(C, V, ev)
            top = ev[d - 1]
            if top < 1e-300:
                top = 1e-300
            coh[i] = 1.0 - ev[d - 2] / top
            for c in range(d):
                U[i, c] = V[c, d - 1]
    return U, coh


def _spacing(dist, idx, dup, dup_k):  # pragma: no cover - compiled
    """Local spacing of every point before its floor, in one pass (see robust.local_spacing,
    whose numpy formula it reproduces bit for bit for ``k <= 128`` neighbours: the sums run in
    numpy's order, the 4-term mean left to right and the k-term row sum pairwise).

    Parameters
    ----------
    dist : (N, k) ndarray of float
        Neighbour distances, ascending in each row (C order).
    idx : (N, k) ndarray of int64
    dup, dup_k : float
        The duplicate thresholds (robust.DUP, robust.DUP_K).

    Returns
    -------
    (N,) ndarray of float
    """
    n = dist.shape[0]
    k = dist.shape[1]
    m = 4 if k >= 4 else k
    div = 1.5 if m >= 4 else 1.0
    raw = np.empty(n)
    buf = np.empty(k)
    r = np.empty(8)
    for p in range(n):
        s = 0.0
        for j in range(m):
            s += dist[p, j]
        raw0 = s / m / div
        # neighbours under the duplicate threshold are skipped, the next m are averaged
        t1 = dup * raw0
        t2 = dup_k * dist[p, k - 1] / (0.5 * k)
        thr = t1 if t1 >= t2 else t2
        cnt = 0
        for j in range(k):
            x = dist[p, j]
            if x >= thr and cnt < m:
                buf[j] = x
                cnt += 1
            else:
                buf[j] = 0.0
        if cnt < m:
            raw[p] = raw0
            continue
        # numpy's pairwise sum of a row (k <= 128: eight accumulators, then the rest)
        if k < 8:
            s = 0.0
            for j in range(k):
                s += buf[j]
        else:
            for j in range(8):
                r[j] = buf[j]
            top = k - k % 8
            for i in range(8, top, 8):
                for j in range(8):
                    r[j] += buf[i + j]
            s = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
            for i in range(top, k):
                s += buf[i]
        raw[p] = s / cnt / div
    # the median over the point and its (up to) 8 nearest neighbours
    jn = 8 if k >= 8 else k
    h = np.empty(n)
    v = np.empty(jn + 1)
    for p in range(n):
        v[0] = raw[p]
        for j in range(jn):
            v[j + 1] = raw[idx[p, j]]
        for a in range(1, jn + 1):  # insertion sort
            x = v[a]
            b = a - 1
            while b >= 0 and v[b] > x:
                v[b + 1] = v[b]
                b -= 1
            v[b + 1] = x
        c = (jn + 1) // 2
        h[p] = v[c] if (jn + 1) % 2 else (v[c - 1] + v[c]) / 2.0
    return h


def _order(P):
    """A cache-friendly visiting order of the points (results never depend on it)."""
    if P.shape[0] <= 100_000:
        return np.arange(P.shape[0], dtype=np.int64)
    from ....neighbors import locality_order

    return locality_order(P)


#: Inputs with fewer points than this run the plain-Python kernels even when numba is there,
#: unless the compiled ones are already loaded in this process: the Python kernels take about
#: a millisecond per point, less than loading compiled kernels from numba's cache (about 1 s)
#: and far less than compiling them on a first run (15 to 20 s).
NUMBA_MIN_POINTS = 2000

#: The same threshold for the kernels of the strand test, which run on noisy input only
#: (:func:`_noisy_tangents`, :func:`_strand_cuts`, and the vote of the noisy tangents), when
#: numba's disk cache already holds them (see :func:`compiled_for`): in plain Python they take
#: 2 to 10 ms a point (the 515-point tree under noise 0.3h + x3: 2.5 s in all, 0.9 s with them
#: compiled), loading them about 0.4 s; compiling them (about 30 s) is left to a first run on
#: :data:`NUMBA_MIN_POINTS` points or more.
NUMBA_MIN_POINTS_NOISY = 200

#: the kernels of the strand test (see NUMBA_MIN_POINTS_NOISY)
STRAND_KERNELS = ("noisy_tangents", "strand_cuts", "vote_agreement", "vote_eig")

_COMPILED = contextvars.ContextVar("curvenet_robust_compiled", default=True)

# the plain-Python functions, kept under their own names (the compiled ones replace some globals)
_PY = {
    "spacing": _spacing,
    "components": _components,
    "chain_order": _chain_order,
    "chain_ends": _chain_ends,
    "linked_edges": _linked_edges,
    "short_links": _short_links,
    "shell_groups": _shell_groups,
    "csr_union": _csr_union,
    "end_count": _end_count,
    "end_counts": _end_counts,
    "tangents": _tangents,
    "junction_nodes": _junction_nodes,
    "trim_ends": _trim_ends,
    "untangle": _untangle,
    "noisy_tangents": _noisy_tangents,
    "strand_cuts": _strand_cuts,
    "vote_agreement": _vote_agreement,
    "vote_eig": _vote_eig,
}
_PY_HELPERS = {"_heap_pop": _heap_pop, "_heap_push": _heap_push,
               "_eig_sym": _eig_sym_py, "_eig_top": _eig_top_py, "_sym2": _sym2, "_dist2": _dist2, "_pca01": _pca01, "_strip_score": _strip_score,
               "_tangents_block": _tangents_block, "prange": range,
               "_shell_groups_block": _shell_groups_block,
               "_end_count": _end_count, "_fit_end": _fit_end, "_solve_small": _solve_small,
               "_extend_into_region": _extend_into_region, "_behind_count": _behind_count,
               "_branch_buffer": _branch_buffer,
               "_shift_mode": _shift_mode, "_density": _density, "_mean_line_offset": _mean_line_offset,
               "_noisy_tangent_at": _noisy_tangent_at, "_noisy_scales": _noisy_scales}
_JIT: dict = {}
_JIT_HELPERS: dict = {}


@contextmanager
def compiled_for(n: int, min_points: int | None = None, cached: tuple = ()):
    """Run the kernels of the enclosed block compiled when numba is there and ``n`` (the number
    of points) is at least ``min_points`` (default :data:`NUMBA_MIN_POINTS`) and numba's disk
    cache holds the kernels ``cached`` (so that they load, not compile), as plain Python
    otherwise (same results). Blocks nest: the inner one decides for its kernels."""
    lim = NUMBA_MIN_POINTS if min_points is None else min_points
    use = HAVE_NUMBA and ((n >= lim and _in_cache(cached)) or _compiled_already())
    token = _COMPILED.set(use)
    helpers = _JIT_HELPERS if use else _PY_HELPERS
    saved = {k: globals()[k] for k in helpers}
    globals().update(helpers)  # the Python kernels call these helpers by their global names
    try:
        yield use
    finally:
        globals().update(saved)
        _COMPILED.reset(token)


def _in_cache(names) -> bool:
    """True when numba's disk cache holds a valid compiled version of every kernel ``names``
    (none: True)."""
    try:  # (numba's cache index: empty when missing or stale)
        return all(bool(_JIT[n]._cache._cache_file._load_index()) for n in names)
    except Exception:  # pragma: no cover - another numba's internals: assume not
        return False


def _compiled_already() -> bool:
    """True once the compiled tangent kernel (which every robust run calls) ran in this process:
    numba's cache is then warm, and small inputs gain from the compiled kernels too. (The
    strand test's kernels run compiled on their own, see :data:`NUMBA_MIN_POINTS_NOISY`.)"""
    return bool(getattr(_JIT.get("tangents"), "signatures", None))


def compiled_active() -> bool:
    """True when the kernels run compiled here (numba there, see :func:`compiled_for`)."""
    return HAVE_NUMBA and _COMPILED.get()


def _kernel(name):
    if HAVE_NUMBA and _COMPILED.get():
        return _JIT[name]
    return _PY[name]


#: Below this many points (the first argument's length) a parallel kernel runs on one thread:
#: starting a parallel loop costs microseconds on an idle machine, but when another process
#: keeps the other cores busy it waits for a time slice (10 to 20 ms measured on 2 cores), more
#: than the whole work of a light kernel on a small input. Results never depend on it.
PAR_MIN = {"tangents": 20_000, "noisy_tangents": 20_000, "strand_cuts": 20_000, "shell_groups": 20_000, "linked_edges": 200_000, "vote_eig": 200_000}


@contextmanager
def _threads_for(name: str, n: int):
    """Run the enclosed parallel kernel ``name`` on ``n`` points on one thread when ``n`` is
    under :data:`PAR_MIN` (and numba runs it)."""
    if name not in PAR_MIN or n >= PAR_MIN[name] or not (HAVE_NUMBA and _COMPILED.get()):
        yield
        return
    old = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(old)


def _dispatch(name: str):
    """A function that runs the kernel ``name`` compiled or in plain Python (see compiled_for)."""

    def run(*args):
        # Ctrl-C waits for the kernel (see curvenet._sigint)
        with held(), _threads_for(name, len(args[0]) if name in PAR_MIN else 0):
            return _kernel(name)(*args)

    run.__name__ = run.__qualname__ = name
    run.__doc__ = f"Run the kernel :func:`_{name}`, compiled or in plain Python."
    return run


spacing = _dispatch("spacing")
components = _dispatch("components")
chain_order = _dispatch("chain_order")
chain_ends = _dispatch("chain_ends")
linked_edges = _dispatch("linked_edges")
short_links = _dispatch("short_links")
csr_union = _dispatch("csr_union")
end_count = _dispatch("end_count")
end_counts = _dispatch("end_counts")
junction_nodes = _dispatch("junction_nodes")
trim_ends = _dispatch("trim_ends")
untangle = _dispatch("untangle")
strand_cuts = _dispatch("strand_cuts")
vote_agreement = _dispatch("vote_agreement")
vote_eig = _dispatch("vote_eig")


def tangents(P, idx, h, m, order=None, margin=None):
    """Tangent, linearity, strip chord distance and candidate gain of every point: see
    :func:`_tangents` (``order``: the visiting order when already computed, see :func:`_order`,
    or a subset of the points; ``margin``: default :data:`CAND_MARGIN`)."""
    margin = CAND_MARGIN if margin is None else float(margin)
    order = _order(P) if order is None else np.ascontiguousarray(order, dtype=np.int64)
    with held(), _threads_for("tangents", len(order)):
        return _kernel("tangents")(P, idx, h, m, order, margin)


def noisy_tangents(P, rows, idx, h, sig):
    """Noisy tangents and linearity of the points ``rows``: see :func:`_noisy_tangents`."""
    with held(), _threads_for("noisy_tangents", len(rows)):
        return _kernel("noisy_tangents")(P, rows, idx, h, sig)


def shell_groups(P, h, indptr, indices, r_in, r_out, subset=None, order=None):
    """Shell group count of every point (or of the points ``subset``, the others 0): see
    :func:`_shell_groups` (``order``: the visiting order of all points when already computed,
    see :func:`_order`)."""
    if P.shape[0] >= 2**31 - 1:
        raise ValueError("too many points for the shell test (int32 ids)")
    compiled = HAVE_NUMBA and _COMPILED.get()
    if subset is not None:
        order = np.sort(np.asarray(subset, dtype=np.int64))
    elif order is None:
        order = _order(P)
    # blocks: a few per thread (balance); one scratch set (about 44 bytes a point) per thread
    par = compiled and len(order) >= PAR_MIN["shell_groups"]
    nblocks = 4 * numba.get_num_threads() if par else 1
    with held(), _threads_for("shell_groups", len(order)):
        return _kernel("shell_groups")(P, h, indptr, indices, r_in, r_out, order, nblocks)


HAVE_NUMBA = False
if os.environ.get("CURVENET_NO_NUMBA", "") not in ("1", "true", "yes"):
    try:  # pragma: no cover - depends on the environment
        import numba

        _jit = numba.njit(cache=True, nogil=True)
        # helpers first: the kernels resolve them by their global names when compiled
        _JIT_HELPERS = {
            # inlined into the Dijkstra loops (as calls they cost the shell kernel 25%)
            "_heap_pop": numba.njit(cache=True, nogil=True, inline="always")(_heap_pop),
            "_heap_push": numba.njit(cache=True, nogil=True, inline="always")(_heap_push),
            "_eig_sym": _jit(_eig_sym_py),
            "_sym2": numba.njit(cache=True, nogil=True, inline="always")(_sym2),
            "_dist2": numba.njit(cache=True, nogil=True, inline="always")(_dist2),
            "_eig_top": _jit(_eig_top_py),
            "_pca01": _jit(_pca01),
            "_strip_score": _jit(_strip_score),
            "_tangents_block": _jit(_tangents_block),
            "_shell_groups_block": _jit(_shell_groups_block),
            "_end_count": _jit(_end_count),
            "_fit_end": _jit(_fit_end),
            "_solve_small": _jit(_solve_small),
            "_extend_into_region": _jit(_extend_into_region),
            "_behind_count": _jit(_behind_count),
            "_branch_buffer": _jit(_branch_buffer),
            "_shift_mode": _jit(_shift_mode),
            "_density": _jit(_density),
            "_noisy_tangent_at": _jit(_noisy_tangent_at),
            "_noisy_scales": numba.njit(cache=True, nogil=True, inline="always")(_noisy_scales),
            "_mean_line_offset": numba.njit(cache=True, nogil=True, inline="always")(_mean_line_offset),
            "prange": numba.prange,
        }
        globals().update(_JIT_HELPERS)
        # prange over independent points or blocks of points
        # (the light vote_agreement and short_links stay serial: their parallel versions cost
        # about 2 s of compile each, more than they save)
        _PAR = ("tangents", "shell_groups", "linked_edges", "vote_eig", "noisy_tangents", "strand_cuts")
        _JIT = {name: _jit(f) for name, f in _PY.items() if name not in _PAR}
        _JIT.update({name: numba.njit(cache=True, nogil=True, parallel=True)(_PY[name]) for name in _PAR})
        HAVE_NUMBA = True
    except ImportError:  # pragma: no cover
        pass
