"""Per-point frames of the kernels: local spacing, tangents (clean and noisy), tangent votes.

The fixed constants come in the groups of :mod:`curvenet.methods.robust.thresholds`, passed as
the last arguments (``sp``: Spacing, ``st``: Strip, ``nz``: Noisy, ``vo``: Vote, ``la``: Linalg).
"""

from __future__ import annotations

import numpy as np

from ..thresholds import NOISY
from .linalg import _eig_top, _pca01

prange = range  # numba.prange in the compiled copies (parallel loops over independent blocks)


def _spacing(dist, idx, dup, dup_k, sp):  # pragma: no cover - compiled
    """Local spacing of every point before its floor, in one pass (see frames.local_spacing,
    whose numpy formula it reproduces bit for bit for ``k <= 128`` neighbours: the sums run in
    numpy's order, the 4-term mean left to right and the k-term row sum pairwise).

    Parameters
    ----------
    dist : (N, k) ndarray of float
        Neighbour distances, ascending in each row (C order).
    idx : (N, k) ndarray of int64
    dup, dup_k : float
        The duplicate thresholds (robust.DUP, robust.DUP_K).
    sp : Spacing

    Returns
    -------
    (N,) ndarray of float
    """
    n = dist.shape[0]
    k = dist.shape[1]
    m = sp.n_mean if k >= sp.n_mean else k
    div = sp.mean_div if m >= sp.n_mean else 1.0
    nl = sp.numpy_lanes
    raw = np.empty(n)
    buf = np.empty(k)
    r = np.empty(nl)
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
        # numpy's pairwise sum of a row (k <= 128: nl accumulators, summed as a tree, then the rest)
        if k < nl:
            s = 0.0
            for j in range(k):
                s += buf[j]
        else:
            for j in range(nl):
                r[j] = buf[j]
            top = k - k % nl
            for i in range(nl, top, nl):
                for j in range(nl):
                    r[j] += buf[i + j]
            wdt = nl
            while wdt > 1:  # ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7)) for 8
                wdt //= 2
                for j in range(wdt):
                    r[j] = r[2 * j] + r[2 * j + 1]
            s = r[0]
            for i in range(top, k):
                s += buf[i]
        raw[p] = s / cnt / div
    # the median over the point and its (up to) 8 nearest neighbours
    jn = sp.n_median if k >= sp.n_median else k
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


def _strip_score(Q, m, u, hp, st):  # pragma: no cover - compiled
    """Score of the line through ``Q[0]`` along the unit vector ``u``: the sum over ``Q[1:m+1]``
    within ``st.a * hp`` along it of ``exp(-(r / (st.w * hp))^2)``, ``r`` the distance from
    the line."""
    d = Q.shape[1]
    s = 0.0
    a_max = st.a * hp
    w2 = (st.w * hp) ** 2
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


def _tangents_block(P, idx, h, m, order, p0, p1, margin, T, lin, chord, gain, st, la):  # pragma: no cover - compiled
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
    nf = st.n_first + 1  # the point and its first neighbours
    for ii in range(p0, p1):
        p = order[ii]
        for c in range(d):
            Q[0, c] = P[p, c]
        for k in range(m):
            q = idx[p, k]
            for c in range(d):
                Q[k + 1, c] = P[q, c]
        for k in range(nf):
            w[k] = 1.0
        _pca01(Q, nf, w, C, V, ev, mu, t, la)
        hp2 = h[p] * h[p]
        # a close parallel curve can pull the 4-neighbour direction across: the direction
        # towards one of the 4 nearest neighbours replaces it when its narrow strip holds
        # clearly more points nearby (see _strip_score)
        kb = -1
        lam = ev[d - 1]
        if lam < la.tiny:
            lam = la.tiny
        best = np.inf
        s4 = np.inf
        top = -np.inf  # the best score of the neighbours' directions
        if 1.0 - ev[d - 2] / lam < st.cand_lin:  # (4 nearly collinear neighbours: t is theirs)
            s4 = _strip_score(Q, m, t, h[p], st)
            best = s4 + margin
        for k in range(1, nf if best < np.inf else 1):
            r2 = 0.0
            for c in range(d):
                x = Q[k, c] - Q[0, c]
                r2 += x * x
            if r2 < la.tiny:
                continue
            r = np.sqrt(r2)
            for c in range(d):
                u[c] = (Q[k, c] - Q[0, c]) / r
            sc = _strip_score(Q, m, u, h[p], st)
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
        for it in range(st.refine):
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
            _pca01(Q, m + 1, w, C, V, ev, mu, t, la)
        lam = ev[d - 1]
        if lam < la.tiny:
            lam = la.tiny
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
        if lab < la.tiny:
            lab = la.tiny
        x = apab / lab
        q2 = ap2 - x * x
        chord[p] = np.sqrt(q2) if q2 > 0.0 else 0.0


def _tangents(P, idx, h, m, order, margin, st, la):  # pragma: no cover - compiled
    """Tangent, linearity and strip chord distance of every point (see frames.tangents).

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
    bs = st.rows
    nb = (no + bs - 1) // bs
    for b in prange(nb):
        p1 = (b + 1) * bs
        _tangents_block(P, idx, h, m, order, b * bs, p1 if p1 < no else no, margin, T, lin, chord, gain, st, la)
    return T, lin, chord, gain


def _vote_agreement(t, idx, m):  # pragma: no cover - compiled
    """``sum_k (t[q_k] . t[p])^2`` over the point ``p`` itself and its ``m`` nearest neighbours
    ``q_k = idx[p, k]``, for every point (see frames.vote_tangents)."""
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


def _vote_eig(t, idx, m, cand, vo, la):  # pragma: no cover - compiled
    """Top eigenvector and coherence ``1 - l2 / l1`` of ``C = sum_k t_k t_k^T`` over each
    candidate point and its ``m`` nearest neighbours (see frames.vote_tangents).

    Returns
    -------
    U : (n_cand, d) ndarray
    coh : (n_cand,) ndarray
    """
    nc = cand.shape[0]
    d = t.shape[1]
    U = np.zeros((nc, d))
    coh = np.zeros(nc)
    bs = vo.rows
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
            _eig_top(C, V, ev, la)
            top = ev[d - 1]
            if top < la.tiny:
                top = la.tiny
            coh[i] = 1.0 - ev[d - 2] / top
            for c in range(d):
                U[i, c] = V[c, d - 1]
    return U, coh


def _noisy_scales(hp, sig, nz):  # pragma: no cover - compiled
    """Strip width, reach along and refining width of the noisy tangent at spacing ``hp``
    (see :func:`_noisy_tangents`; scalars, or arrays of ``hp`` in numpy)."""
    return np.maximum(nz.wh * hp, nz.wf * sig), nz.a * hp + nz.reach_sig * sig, np.maximum(hp, nz.rw * sig)


def noisy_reach(h, sig):
    """How far from a point the noisy tangent reads its neighbours (see :func:`_noisy_tangents`):
    a neighbour farther away changes nothing. Works on arrays of ``h``."""
    W, amax, rw = _noisy_scales(h, sig, NOISY)  # (plain numpy on arrays)
    lat = np.maximum(NOISY.cut * W, rw)
    return np.sqrt(amax * amax + lat * lat)


def _noisy_tangents(P, rows, idx, h, sig, nz, la):  # pragma: no cover - compiled
    """Tangent and linearity of the points ``rows`` ((R,) ids) of a noisy cloud, whose ``k``
    nearest neighbours are the rows of ``idx`` ((R, k)).

    Where sparse, noisy curves run 2 to 3 spacings apart, the nearest neighbours of a point lie
    as often across as along: the best line is found over a longer reach. The direction towards
    each of the ``nz.cand`` nearest neighbours (within ``amax``, below; not within 10 degrees
    of one scored before) is scored by the sum, over all ``k`` neighbours
    within ``amax = nz.a * h + nz.reach_sig * sig`` along it and ``nz.cut * w`` across, of
    ``exp(-(r / w)^2)``, ``r`` the distance from the line through the point and
    ``w = max(nz.wh * h, nz.wf * sig)``; the best (the first of equal scores) is refined
    twice by the PCA of the point and its neighbours within ``max(h, nz.rw * sig)`` of the
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
    nblk = (n + nz.rows - 1) // nz.rows
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
        for ri in range(bi * nz.rows, min(n, (bi + 1) * nz.rows)):
            lin[ri] = _noisy_tangent_at(P, rows[ri], idx[ri], h[rows[ri]], sig, Q, R2, w, C, V, ev, mu, t, u, U, nz, la)
            for c in range(d):
                T[ri, c] = t[c]
    return T, lin


def _noisy_tangent_at(P, p, nb, hp, sig, Q, R2, w, C, V, ev, mu, t, u, U, nz, la):  # pragma: no cover - compiled
    """The noisy tangent of the point ``p`` (neighbour ids ``nb``, (k,); local spacing ``hp``)
    into ``t``; returns its linearity. The other arrays are scratch (see
    :func:`_noisy_tangents`)."""
    d = P.shape[1]
    k = nb.shape[0]
    nc = nz.cand if nz.cand < k else k
    for c in range(d):
        Q[0, c] = 0.0
    R2[0] = 0.0
    for j in range(k):
        r2 = 0.0
        for c in range(d):
            Q[j + 1, c] = P[nb[j], c] - P[p, c]
            r2 += Q[j + 1, c] * Q[j + 1, c]
        R2[j + 1] = r2
    W, amax, rw = _noisy_scales(hp, sig, nz)
    w2 = W * W
    qmax = nz.cut * nz.cut * w2
    best = -np.inf
    ns = 0
    for j in range(nc):
        if R2[j + 1] > amax * amax and j > 0:  # (a direction the nearer ones give)
            continue
        r = np.sqrt(R2[j + 1])
        if r < la.tiny:
            r = la.tiny
        for c in range(d):
            u[c] = Q[j + 1, c] / r
        dup = False
        for i in range(ns):  # (a direction within nz.same of one scored)
            x = 0.0
            for c in range(d):
                x += U[i, c] * u[c]
            if abs(x) > nz.same:
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
    for it in range(nz.refine):
        w[0] = 1.0
        for i in range(1, k + 1):
            al = 0.0
            for c in range(d):
                al += Q[i, c] * t[c]
            w[i] = 1.0 if (R2[i] - al * al <= rw2 and abs(al) <= amax) else 0.0
        for c in range(d):
            u[c] = t[c]
        _pca01(Q, k + 1, w, C, V, ev, mu, t, la)
        sg = 0.0
        for c in range(d):
            sg += t[c] * u[c]
        if sg < 0.0:
            for c in range(d):
                t[c] = -t[c]
        lam = ev[d - 1]
        if lam < la.tiny:
            lam = la.tiny
        lp = 1.0 - ev[d - 2] / lam
    return lp
