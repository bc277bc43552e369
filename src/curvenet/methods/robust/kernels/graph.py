"""Graph kernels: the linked kNN edges, short links, CSR adjacency, connected components, and
the strand test that cuts links between two close parallel strands.

The strand test's fixed constants come in a
:class:`~curvenet.methods.robust.thresholds.Strand` (``sd``), its PCA's in a ``Linalg`` (``la``).
"""

from __future__ import annotations

import numpy as np

from .linalg import _pca01

prange = range  # numba.prange in the compiled copies (parallel loops over independent rows)


def _dist(P, p, q):  # pragma: no cover - compiled
    """``|P_q - P_p|`` summed as scipy's k-d tree query sums it (squares of the coordinate
    differences, first to last, then the root): the same bits as its distances."""
    s = 0.0
    for c in range(P.shape[1]):
        v = P[q, c] - P[p, c]
        s += v * v
    return np.sqrt(s)


def _in_lens(P, idx, p, j, q, dd, width):  # pragma: no cover - compiled
    """Whether a nearer neighbour of ``p`` (``idx[p, :j]``, rows sorted by distance) lies nearer
    to ``q`` than ``p`` does (``dd``: inside the lens of the edge ``(p, q)``, the relative
    neighbourhood graph's test) and farther than ``width`` from the edge's line: a sample of
    the corner the edge cuts (samples near its line, a junction's on a straight curve, do not
    count)."""
    for i in range(j):
        s = idx[p, i]
        if s == p or s == q or not (_dist(P, q, s) < dd):
            continue
        a = 0.0
        for c in range(P.shape[1]):
            a += (P[s, c] - P[p, c]) * (P[q, c] - P[p, c])
        a /= dd
        pw = _dist(P, p, s)
        x = pw * pw - a * a
        if x > width * width:
            return True
    return False


def _linked_edges(P, h, idx, t, lin, link, width, wmin, gap, extra_len, lin_min, lens):  # pragma: no cover - compiled
    """Directed kNN edges kept by the distance and tangent tests (see graph.linked_edges).

    For the edge from ``p`` to its neighbour ``q`` at distance ``d`` (rows sorted by distance;
    ``d`` recomputed from ``P`` as the k-d tree query computes it, the same bits, so that the
    (N, k) distances need not be kept: :func:`_dist`):
    ``reach = link * (h_p + h_q) / 2 + gap``; edges longer than ``extra_len * reach`` (and
    self-pairs) are out. ``ps``, ``pd`` are the distances of the far end from the tangent lines
    at ``p`` and ``q``; ``w = max(width * (h_p + h_q) / 2, wmin)``. An edge is kept if it is
    short (``d <= link * (h_p + h_q) / 2``) and passes one tangent test (or an end has
    linearity below ``lin_min``, or ``d == 0``), or if it passes both tangent tests at two
    linear ends and ``d <= reach``, or if it is the first such two-sided strip edge of its row
    on either side of ``p`` along its tangent (with ``lens``, an edge kept by this last rule
    alone only where no nearer neighbour of ``p`` lies in its lens off its line:
    :func:`_in_lens`, with the strip half-width ``w``).

    Returns
    -------
    src, dst : (E,) ndarray of the dtype of ``idx``
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
            dd = _dist(P, p, q)
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
                strip = False
                if al > 0 and not got_pos:
                    got_pos = True
                    strip = True
                elif -al > 0 and not got_neg:
                    got_neg = True
                    strip = True
                if strip and not keep:  # a strip edge only: it bridges a gap, where no sample lies beside
                    keep = not (lens and _in_lens(P, idx, p, j, q, dd, w))
            if keep:
                sel[p, j] = True
                row += 1
        cnt[p + 1] = row
    for p in range(n):
        cnt[p + 1] += cnt[p]
    total = cnt[n]
    src = np.empty(total, dtype=idx.dtype)
    dst = np.empty(total, dtype=idx.dtype)
    out_d = np.empty(total)
    for p in prange(n):
        e = cnt[p]
        for j in range(k):
            if sel[p, j]:
                src[e] = p
                dst[e] = idx[p, j]
                out_d[e] = _dist(P, p, idx[p, j])
                e += 1
    return src, dst, out_d


def _short_links(P, h, idx, link):  # pragma: no cover - compiled
    """The kNN pairs ``(p, q)`` with ``|P_p - P_q| <= link * 0.5 * (h_p + h_q)``, in row order (ids
    of the dtype of ``idx``; distances by :func:`_dist`)."""
    n = idx.shape[0]
    k = idx.shape[1]
    cnt = np.zeros(n + 1, dtype=np.int64)  # pairs of row p at cnt[p + 1]
    for p in prange(n):  # rows are independent (parallel when compiled so)
        row = 0
        for j in range(k):
            if _dist(P, p, idx[p, j]) <= link * 0.5 * (h[p] + h[idx[p, j]]):
                row += 1
        cnt[p + 1] = row
    for p in range(n):
        cnt[p + 1] += cnt[p]
    total = cnt[n]
    a = np.empty(total, dtype=idx.dtype)
    b = np.empty(total, dtype=idx.dtype)
    for p in prange(n):
        e = cnt[p]
        for j in range(k):
            if _dist(P, p, idx[p, j]) <= link * 0.5 * (h[p] + h[idx[p, j]]):
                a[e] = p
                b[e] = idx[p, j]
                e += 1
    return a, b


def _csr_union(n, src, dst):  # pragma: no cover - compiled
    """CSR adjacency of the undirected graph with edges (src[i], dst[i]) (both directions).

    Within a row, the out-edges come first in edge order, then the in-edges in edge order
    (a counting sort, stable), each neighbour once: a pair linked both ways (most are: each
    end keeps the other) is listed at its first place only. ``indptr`` is int64, ``indices``
    of the dtype of ``src``.
    """
    m = src.shape[0]
    deg = np.zeros(n + 1, dtype=np.int64)
    for i in range(m):
        deg[src[i] + 1] += 1
        deg[dst[i] + 1] += 1
    for i in range(n):
        deg[i + 1] += deg[i]
    fill = deg[:-1].copy()
    out = np.empty(2 * m, dtype=src.dtype)
    for i in range(m):
        a = src[i]
        out[fill[a]] = dst[i]
        fill[a] += 1
    for i in range(m):
        b = dst[i]
        out[fill[b]] = src[i]
        fill[b] += 1
    # a link kept in both directions is one edge: each row keeps the first of its repeats
    seen = np.full(n, -1, dtype=np.int64)
    indptr = np.zeros(n + 1, dtype=np.int64)
    k = 0
    for i in range(n):
        for e in range(deg[i], deg[i + 1]):
            j = out[e]
            if seen[j] != i:
                seen[j] = i
                out[k] = j
                k += 1
        indptr[i + 1] = k
    return indptr, out[:k].copy()


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


def _shift_mode(L, cnt, x0, b, out, sd):  # pragma: no cover - compiled
    """Mean shift (Gaussian kernel of width ``b``) over the rows ``L[:cnt]`` from ``x0``: the
    mode into ``out``."""
    d = L.shape[1]
    for c in range(d):
        out[c] = x0[c]
    x2 = np.zeros(d)
    for it in range(sd.steps):
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
        if mv < sd.shift_tol * b * b:
            break


def _dist2_to(x, y):  # pragma: no cover - compiled
    """``|x - y|^2`` of two (d,) vectors."""
    s = 0.0
    for c in range(x.shape[0]):
        z = x[c] - y[c]
        s += z * z
    return s


def _upper(x, y):  # pragma: no cover - compiled
    """The larger of ``x`` and ``y``, inf when ``y`` is NaN (a bound that NaN cannot lower)."""
    if y <= x:
        return x
    return y if y == y else np.inf


def _spread2(L, cnt, x):  # pragma: no cover - compiled
    """The largest ``|L_i - x|^2`` over the rows ``L[:cnt]`` (0 for none; inf if one is NaN)."""
    f = 0.0
    for i in range(cnt):
        f = _upper(f, _dist2_to(L[i], x))
    return f


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


def _strand_cuts(P, h, idx, t, src, dst, sig, sd, la):  # pragma: no cover - compiled
    """The links of a noisy cloud that join two parallel strands (close parallel curves).

    For the link ``p -> q`` between nearly parallel tangents (``sd.cos``) whose far end lies
    more than ``max(sd.t0 sig, sd.dmin h_p / 2)`` from the tangent line at ``p``: the
    offsets across the strand of ``p`` and of its neighbours within ``sd.a h_p`` along it
    (each from the line through ``p`` along the mean of the two tangents, which follows a bend)
    are searched for modes by mean shift (width ``max(sd.b sig, sd.bh h_p)``), once from
    ``p`` and once from ``q``. The link is cut when the two modes lie more than
    ``max(sd.thr sig, sd.dmin h_p)`` apart with a density valley between them, and each
    mode holds at least ``sd.nmin`` points that run parallel to ``t_p`` (``sd.lcos``) on
    both sides of the link (beyond ``sd.side h_p`` along): two strands, not one strand's
    noise, bend or crossing.

    Returns
    -------
    (E,) ndarray of bool
    """
    d = P.shape[1]
    k = idx.shape[1]
    ne = src.shape[0]
    cut = np.zeros(ne, dtype=np.bool_)
    nblk = (ne + sd.rows - 1) // sd.rows
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
        wp = -1  # the point whose window L, X, A (cnt rows), b, sl2, dw hold
        cnt = 0
        b = 1.0
        sl2 = 0.0
        dw = 0.0
        have_ms = False  # ms (the mode from p) and rs computed for wp
        rs = 0.0
        have_fs = False  # fs (the density at ms) computed for wp
        fs = 0.0
        for e in range(bi * sd.rows, min(ne, (bi + 1) * sd.rows)):
            p = src[e]
            q = dst[e]
            dot = 0.0
            for c in range(d):
                dot += t[p, c] * t[q, c]
            if abs(dot) < sd.cos:
                continue
            al = 0.0
            r2 = 0.0
            for c in range(d):
                v[c] = P[q, c] - P[p, c]
                al += v[c] * t[p, c]
                r2 += v[c] * v[c]
            lat2 = r2 - al * al
            lim = sd.t0 * sig
            if 0.5 * sd.dmin * h[p] > lim:
                lim = 0.5 * sd.dmin * h[p]
            if not (lat2 > lim * lim):
                continue
            al_pq = al
            _mean_line_offset(P, t, p, q, tb, lq)  # q's offset
            if p != wp:  # the window of p (and all that depends on p alone), once per p
                wp = p
                have_ms = False
                # the window: p and its neighbours within sd.a h_p along t_p
                cnt = 0
                for j in range(-1, k):
                    i = p if j < 0 else idx[p, j]
                    aj = 0.0
                    for c in range(d):
                        aj += (P[i, c] - P[p, c]) * t[p, c]
                    if aj > sd.a * h[p] or aj < -sd.a * h[p]:
                        continue
                    _mean_line_offset(P, t, p, i, tb, L[cnt])
                    for c in range(d):
                        X[cnt, c] = P[i, c]
                    A[cnt] = aj
                    cnt += 1
                b = sd.b * sig
                if sd.bh * h[p] > b:
                    b = sd.bh * h[p]
                sl = sd.thr * sig
                if sd.dmin * h[p] > sl:
                    sl = sd.dmin * h[p]
                sl2 = sl * sl * (1.0 - sd.bound_margin)
                if not (sl * sl < sd.bound_reach * b * b):
                    sl2 = -1.0  # no bound: a mean's weights could underflow (not with the defaults)
                dw = _spread2(L, cnt, zero)  # squared diameter of the window's offsets and the origin
                for i in range(cnt):
                    dw = _upper(dw, _spread2(L, i, L[i]))
            # Both modes are weighted means of the window's offsets (or their starts, the origin
            # and q's offset): they cannot lie further apart than the diameter of those points,
            # nor further from the mode from p than its furthest point. When that bound is short
            # of the separation the test needs, the link cannot be cut (exact: the bound is kept
            # a relative sd.bound_margin clear of the rounding of the means).
            r2 = _upper(dw, _upper(_spread2(L, cnt, lq), _dist2_to(lq, zero)))
            if r2 < sl2:
                continue
            if not have_ms:
                _shift_mode(L, cnt, zero, b, ms, sd)
                have_ms = True
                have_fs = False
                rs = _upper(_spread2(L, cnt, ms), _dist2_to(ms, zero))
            r2 = _upper(rs, _dist2_to(lq, ms))
            if r2 < sl2:
                continue
            _shift_mode(L, cnt, lq, b, mq, sd)
            sep = 0.0
            for c in range(d):
                z = ms[c] - mq[c]
                sep += z * z
                mid[c] = 0.5 * (ms[c] + mq[c])
            lim = sd.thr * sig
            if sd.dmin * h[p] > lim:
                lim = sd.dmin * h[p]
            if not (sep > lim * lim):
                continue
            if not have_fs:
                fs = _density(L, cnt, ms, b)
                have_fs = True
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
                    if r2 <= (sd.member * b) * (sd.member * b):
                        w[i] = 1.0
                        nm += 1
                        am = A[i] - 0.5 * al_pq
                        if am < lo:
                            lo = am
                        if am > hi:
                            hi = am
                    else:
                        w[i] = 0.0
                if nm < sd.nmin or not (lo < -sd.side * h[p] and hi > sd.side * h[p]):
                    ok = False
                    break
                _pca01(X, cnt, w, C, V, ev, mu, u, la)
                dj = 0.0
                for c in range(d):
                    dj += u[c] * t[p, c]
                if abs(dj) < sd.lcos:
                    ok = False
                    break
            if ok:
                cut[e] = True
    return cut
