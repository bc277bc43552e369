"""Node kernels: end portions of chains, junction node positions, and the trimming of chain
points that lie behind their nodes.

The fixed constants come in the groups :class:`~curvenet.methods.robust.thresholds.Ends`
(``en``), ``Nodes`` (``nd``) and ``Linalg`` (``la``); the method's settings of the junction
placement in a :class:`JunctionParams` (``jp``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .linalg import _eig_sym, _eig_top, _solve_small

#: coefficients of the algebraic form of a circle (or line) in a branch end's frame,
#: ``y = a (s^2 + y^2) + b s + c`` (:func:`_arc_fit`): also the fewest points that fit it
ARC_COEFS = 3


class JunctionParams(NamedTuple):
    """The method's settings of the junction placement (:func:`_junction_nodes`); lengths in
    local spacings ``h`` unless said otherwise."""

    #: the lines are fitted on each branch's end over this arc length (spacings; robust.JSPAN)
    jspan: float
    #: plus this many noise levels over the end's spacing (unitless; robust.JN)
    jn: float
    #: a walk into the region stops where it strays more than this many link widths from the
    #: branch's line (unitless; robust.WALK_DEV)
    walk_dev: float
    #: the link width is at least this many noise levels (unitless; robust.NW)
    nw: float
    #: the node falls back to the anchor beyond this distance from it (spacings)
    far: float
    #: a hidden branch has region points beyond this distance from the node (spacings of the
    #: widened junction spacing)
    swallow_r: float
    #: ... in a direction whose cosine to every branch is below this (cosine; robust.SWALLOW_COS)
    swallow_cos: float
    #: the junction spacing is widened by this many noise levels there (unitless; robust.WIDEN)
    widen: float
    #: whether the branches are walked into the region along the linked graph
    use_graph: bool


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


def _end_counts(P, h, flat, off, span, en):  # pragma: no cover - compiled
    """How many points of each id list make its end portion (see chains.end_portion).

    For list ``b``, ``ids = flat[off[b]:off[b + 1]]`` (running towards its end): the count of
    :func:`_end_count` within ``span * h[ids[-1]]``, at least ``min(en.min_points, len(ids))``.

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
        least = en.min_points if en.min_points < n else n
        out[b] = m if m > least else least
    return out


def _point_back(flat, off, bi, n0, claim_pt, claim_prev, tail, k):  # pragma: no cover - compiled
    """The point ``k`` steps back from the end of branch ``bi`` walked into its region: its
    claimed points (a list linked backwards from ``tail[bi]``), then its own ``flat[off[bi]:]``."""
    e = tail[bi]
    q = n0 - 1
    for _ in range(k):
        if e >= 0:
            e = claim_prev[e]
        else:
            q -= 1
    return claim_pt[e] if e >= 0 else flat[off[bi] + q]


def _extend_into_region(P, h, indptr, indices, flat, off, rs, width, wnoise, en, nd):  # pragma: no cover - compiled
    """Walk every branch end into its junction region, in turns (see nodes.junction_positions).

    Branch ``b`` is ``flat[off[b]:off[b + 1]]`` (running towards the junction); ``rs`` the sorted
    unique region points. Each round, every active branch (at least 2 points) proposes the
    nearest unclaimed region point linked to its end ``cur`` (CSR ``indptr``, ``indices``) that
    lies ahead, ``al > nd.ahead * h_cur`` along the unit direction from the point ``en.walk_span * h_cur`` back
    along the branch (as ``chains.end_portion``) to ``cur``, and within
    ``max(width * h_cur, wnoise)`` of that line; distance ``hypot(al, perp)``, ties: lowest id.
    A branch with no such point stops. Proposals are taken by increasing (distance, id), a
    point claimed once only. Rounds stop when nothing is proposed.

    Memory: the claims of all branches together are at most the region's points (each is
    claimed once), kept as lists linked backwards per branch; no (branches, longest) array.

    Returns
    -------
    ext : (n_claimed,) ndarray of int64
    eoff : (n_branches + 1,) ndarray of int64
        Branch ``b`` extended is ``flat[off[b]:off[b + 1]]`` followed by ``ext[eoff[b]:eoff[b + 1]]``.
    """
    nbr = off.shape[0] - 1
    nr = rs.shape[0]
    d = P.shape[1]
    cnt = np.empty(nbr, dtype=np.int64)
    for b in range(nbr):
        cnt[b] = off[b + 1] - off[b]
    claim_pt = np.empty(nr, dtype=np.int64)
    claim_prev = np.empty(nr, dtype=np.int64)
    tail = np.full(nbr, -1, dtype=np.int64)
    nc = 0
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
            n0 = off[bi + 1] - off[bi]
            cur = _point_back(flat, off, bi, n0, claim_pt, claim_prev, tail, 0)
            hl = h[cur]
            # the end portion over en.walk_span h: arc length summed backwards from the end
            # (a cursor: claim e while e >= 0, then the branch's own point q)
            lim = en.walk_span * hl
            s = 0.0
            m = 1
            far = cur
            a = cur
            e = tail[bi]
            q = n0 - 1
            for _ in range(n - 1):
                if e >= 0:
                    e = claim_prev[e]
                else:
                    q -= 1
                c2 = claim_pt[e] if e >= 0 else flat[off[bi] + q]
                sq = 0.0
                for c in range(d):
                    t = P[c2, c] - P[a, c]
                    sq = sq + t * t if c > 0 else t * t
                s += np.sqrt(sq)
                if not s <= lim:
                    break
                m += 1
                far = c2
                a = c2
            if m < en.min_points and n >= en.min_points:
                m = en.min_points
                far = _point_back(flat, off, bi, n0, claim_pt, claim_prev, tail, m - 1)
            elif m < n and n < en.min_points:
                m = n
                far = flat[off[bi]]
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
                if al > nd.ahead * hl and perp <= w:
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
            claim_pt[nc] = pj[i]
            claim_prev[nc] = tail[bi]
            tail[bi] = nc
            nc += 1
            cnt[bi] += 1
            claimed[pos] = True
    # each branch's claims in order, one after the other
    eoff = np.zeros(nbr + 1, dtype=np.int64)
    for b in range(nbr):
        eoff[b + 1] = eoff[b] + cnt[b] - (off[b + 1] - off[b])
    ext = np.empty(nc, dtype=np.int64)
    for b in range(nbr):
        e = tail[b]
        k = eoff[b + 1] - 1
        while e >= 0:
            ext[k] = claim_pt[e]
            k -= 1
            e = claim_prev[e]
    return ext, eoff


def _portion_mean(P, ids, m, mu):  # pragma: no cover - compiled
    """Mean of the last ``m`` points ``P[ids[-m:]]`` into ``mu`` (d,) (zeros when ``m`` is 0)."""
    n = ids.shape[0]
    for c in range(P.shape[1]):
        acc = 0.0
        for q in range(n - m, n):
            acc += P[ids[q], c]
        mu[c] = acc / m if m > 0 else 0.0


def _portion_scatter(P, ids, m, mu, C):  # pragma: no cover - compiled
    """Scatter matrix of the last ``m`` points ``P[ids[-m:]]`` about ``mu`` into ``C`` (d, d)."""
    n = ids.shape[0]
    d = P.shape[1]
    for i in range(d):
        for j in range(i, d):
            acc = 0.0
            for q in range(n - m, n):
                acc += (P[ids[q], i] - mu[i]) * (P[ids[q], j] - mu[j])
            C[i, j] = acc
            C[j, i] = acc


def _fit_end(P, h, ids, span, mu, u, C, V, ev, with_dir, en, la):  # pragma: no cover - compiled
    """Line through the end portion of ``ids`` (running towards the end) over ``span`` h.

    The end portion is that of ``chains.end_portion``: the points from the last id backwards
    within arc length ``span * h[ids[-1]]``, at least ``min(en.min_points, n)``. Its mean goes into ``mu``
    and, when ``with_dir``, its principal direction into ``u``. Returns the number of points in
    the portion (the direction is meaningful only when it is at least 2).
    """
    n = ids.shape[0]
    d = P.shape[1]
    if n < 2:
        m = n
    else:
        m = _end_count(P, ids, span * h[ids[n - 1]])
        if m < en.min_points and n >= en.min_points:
            m = en.min_points
        elif m < n and n < en.min_points:
            m = n
    _portion_mean(P, ids, m, mu)
    if not with_dir:
        return m
    _portion_scatter(P, ids, m, mu, C)
    if m >= 2:
        _eig_top(C, V, ev, la)
        for c in range(d):
            u[c] = V[c, d - 1]
    return m


def _arc_fit(P, ids, lim, mu, U, cf, C, ev, M3, r3, la):  # pragma: no cover - compiled
    """Circle (or line) through the end portion of ``ids`` (running towards the end): the
    points from the last id backwards within arc length ``lim`` (:func:`_end_count`).

    The portion's mean goes into ``mu`` and its principal axes into the columns of ``U``
    (ascending: ``U[:, d - 1]`` the direction ``s``, ``U[:, d - 2]`` the second ``y``). In that
    frame the circle is ``y = cf[0] (s^2 + y^2) + cf[1] s + cf[2]`` (an algebraic fit, linear
    least squares regressing ``y``; a line when ``cf[0]`` is 0, curvature ``2 cf[0]``), out of the
    plane the offset is 0. Returns the number of points in the portion, or 0 when the fit is
    singular.
    """
    n = ids.shape[0]
    d = P.shape[1]
    m = _end_count(P, ids, lim)
    if m < ARC_COEFS:
        return 0
    _portion_mean(P, ids, m, mu)
    _portion_scatter(P, ids, m, mu, C)
    _eig_sym(C, U, ev, la)
    for a in range(ARC_COEFS):
        r3[a] = 0.0
        for c in range(ARC_COEFS):
            M3[a, c] = 0.0
    for q in range(n - m, n):
        s = 0.0
        y = 0.0
        for c in range(d):
            t = P[ids[q], c] - mu[c]
            s += t * U[c, d - 1]
            y += t * U[c, d - 2]
        f0 = s * s + y * y
        M3[0, 0] += f0 * f0
        M3[0, 1] += f0 * s
        M3[0, 2] += f0
        M3[1, 1] += s * s
        M3[1, 2] += s
        M3[2, 2] += 1.0
        r3[0] += f0 * y
        r3[1] += s * y
        r3[2] += y
    M3[1, 0] = M3[0, 1]
    M3[2, 0] = M3[0, 2]
    M3[2, 1] = M3[1, 2]
    if not _solve_small(M3, r3, cf):
        return 0
    return m


def _arc_resid(x, mu, U, cf, e, J):  # pragma: no cover - compiled
    """Offset of ``x`` from a circle of :func:`_arc_fit` (``e``, d - 1: the in-plane distance
    ``g / |grad g|`` of the algebraic form ``g``, then the out-of-plane coordinates) and its
    Jacobian ``J`` (d - 1, d; the gradient's norm held fixed). Returns ``|e|^2``."""
    d = x.shape[0]
    s = 0.0
    y = 0.0
    for c in range(d):
        t = x[c] - mu[c]
        s += t * U[c, d - 1]
        y += t * U[c, d - 2]
    g = cf[0] * (s * s + y * y) + cf[1] * s + cf[2] - y
    gs = 2.0 * cf[0] * s + cf[1]
    gy = 2.0 * cf[0] * y - 1.0
    nn = np.sqrt(gs * gs + gy * gy)
    e[0] = g / nn
    f = e[0] * e[0]
    for c in range(d):
        J[0, c] = (gs * U[c, d - 1] + gy * U[c, d - 2]) / nn
    for k in range(d - 2):
        acc = 0.0
        for c in range(d):
            acc += (x[c] - mu[c]) * U[c, k]
            J[k + 1, c] = U[c, k]
        e[k + 1] = acc
        f += acc * acc
    return f


def _arc_rms(P, ids, m, mu, U, cf, e, J):  # pragma: no cover - compiled
    """Root mean square offset (:func:`_arc_resid`) of the last ``m`` points of ``ids`` from the
    circle ``mu, U, cf`` of :func:`_arc_fit` (``e``, ``J``: scratch)."""
    n = ids.shape[0]
    acc = 0.0
    for q in range(n - m, n):
        acc += _arc_resid(P[ids[q]], mu, U, cf, e, J)
    return np.sqrt(acc / m)


def _arc_fit_grown(P, ids, hend, tol, mu, U, cf, C, ev, M3, r3, e, J, nd, la):  # pragma: no cover - compiled
    """:func:`_arc_fit` over the longest span (``nd.tangent_span`` spacings ``hend``, then
    ``nd.tangent_grow`` more at a time, at most ``nd.tangent_span_max``) whose points lie within
    ``tol`` of the circle (root mean square); a line (``cf = 0``: the portion's principal axis)
    where the circle does not fit its points better by ``nd.tangent_sel`` (the F statistic of
    the one more coefficient). Returns the points of the span kept (0: none fits)."""
    n = ids.shape[0]
    d = P.shape[1]
    mb = 0
    mu2 = np.zeros(d)
    U2 = np.zeros((d, d))
    cf2 = np.zeros(ARC_COEFS)
    sp = nd.tangent_span
    while sp <= nd.tangent_span_max:
        m = _arc_fit(P, ids, sp * hend, mu2, U2, cf2, C, ev, M3, r3, la)
        if m < ARC_COEFS:
            break
        rss = 0.0
        for q in range(n - m, n):
            rss += _arc_resid(P[ids[q]], mu2, U2, cf2, e, J)
        if mb > 0 and rss > m * tol * tol:
            break
        lin = 0.0
        for c in range(d - 1):
            lin += ev[c]
        mb = m
        for c in range(d):
            mu[c] = mu2[c]
            for a in range(d):
                U[c, a] = U2[c, a]
        for a in range(ARC_COEFS):
            cf[a] = cf2[a]
        if m > ARC_COEFS and not (lin - rss) > nd.tangent_sel * rss / (m - ARC_COEFS):
            for a in range(ARC_COEFS):
                cf[a] = 0.0
        if m >= n:
            break
        sp += nd.tangent_grow
    return mb


def _arc_profile(x0, w, Q, t, MU, UU, CF, nm, x, e, J, H, g, z, iters):  # pragma: no cover - compiled
    """The least sum of squared offsets of the point ``x0 + t w + Q y`` from the ``nm`` circles
    ``MU[k], UU[k], CF[k]`` (:func:`_arc_resid`) over ``y`` (Gauss-Newton, ``iters`` steps from
    ``y = 0``; ``Q`` (d, d - 1): an orthonormal basis of the directions normal to ``w``). The
    point goes into ``x``; returns the sum."""
    d = x0.shape[0]
    k1 = d - 1
    for c in range(d):
        x[c] = x0[c] + t * w[c]
    for _ in range(iters):
        for a in range(k1):
            g[a] = 0.0
            for b in range(k1):
                H[a, b] = 0.0
        for k in range(nm):
            _arc_resid(x, MU[k], UU[k], CF[k], e, J)
            for r in range(k1):
                # row r of J Q, into z
                for a in range(k1):
                    acc = 0.0
                    for c in range(d):
                        acc += J[r, c] * Q[c, a]
                    z[a] = acc
                for a in range(k1):
                    g[a] -= z[a] * e[r]
                    for b in range(k1):
                        H[a, b] += z[a] * z[b]
        if not _solve_small(H, g, z):
            break
        for c in range(d):
            acc = 0.0
            for a in range(k1):
                acc += Q[c, a] * z[a]
            x[c] += acc
    f = 0.0
    for k in range(nm):
        f += _arc_resid(x, MU[k], UU[k], CF[k], e, J)
    return f


def _tangent_node(P, h, flat, off, x, hl, noise, V, ev, nd, la):  # pragma: no cover - compiled
    """Where the branches' circles meet: the node ``x`` of :func:`_junction_nodes` moved along
    the weak direction of the lines' normal matrix ``A`` (without the anchor's pull), given by
    its eigenvalues ``ev`` (d,, ascending) and unit eigenvectors, the columns of ``V`` (d, d).

    Two cases. (a) Near-tangent branches: the smallest eigenvalue of ``A`` under
    ``nd.tangent_weak`` times the number of branches; the lines cannot place the node along its
    eigenvector ``w`` (their straight lines, fitted on chords of curved branches, even cross at
    the wrong place). (b) Curved branches: any other junction, when every branch gets a circle
    (below) and one at least is curved (its points lie over ``nd.tangent_fit hl`` from their
    line, root mean square: noisy straight branches read as noise-free keep their lines); a
    line fitted on the chord of a branch curving with a radius of a few spacings
    lies a spacing or more off the branch at the junction, and the lines meet off the node
    (circles of radius 8 h with lines leaving at 0-3 degrees: 2.0-2.3 h off). Each branch
    (``flat[off[b]:off[b + 1]]``, not walked into the region) of at least ``nd.tangent_points``
    points is fitted by a circle over its last ``nd.tangent_span`` spacings (:func:`_arc_fit`),
    kept when its points lie within ``nd.tangent_fit hl`` of it (root mean square: a circle
    across a corner or a stroke's wiggle is no model of the branch). Then the node is where
    those circles meet: the point ``x + t w + (normal to w)`` whose summed squared offsets from
    them is least over the normal part, walked downhill in ``t`` from 0 by steps of
    ``nd.tangent_step hl`` (at most ``nd.tangent_reach hl`` away) to the nearest local minimum.
    Kept only when the circles meet there within ``nd.tangent_meet hl`` (root mean square) and
    at least 2 circles were fitted in case (a), every branch's in case (b) (two circles of four
    branches always meet somewhere: a crossing whose short branches got none moved 1.4 h off);
    else ``x`` is left as it is. Returns whether ``x`` moved.

    Under noise (``noise`` over ``nd.tangent_noise hl``: the noise scale, absolute) every
    branch needs its circle, and the circles are measured as the noise allows: each fitted
    over the longest span whose points lie within ``nd.tangent_rc`` noise scales of it
    (:func:`_arc_fit_grown`: a curvature over 8 h is not measurable under noise 0.1 h, over
    20-40 h it is), a line where the circle does not fit significantly better, and the circles'
    meeting widened by ``nd.tangent_meet_noise`` noise scales. In case (a) the node is the middle
    of the stretch where the circles meet within ``nd.tangent_mid`` squared noise scales (per
    circle) of the best: near-tangent circles meet along a valley as flat as the noise of their
    fits, whose lowest point falls anywhere in it. Case (b) runs only on junctions whose smallest
    eigenvalue is under ``nd.tangent_weak_noisy`` times the number of branches (a branch within
    about 50 degrees of two collinear ones: a fillet's arc and its straight edge), a branch being
    curved where its fit kept the circle: a circle fitted over a long span of a strongly curved
    branch (a mug's handle, a semicircle leaving its side at a right angle) misses the junction
    by a few spacings, where the lines already meet well.
    """
    nbr = off.shape[0] - 1  # (2 or more, in 2D or 3D: the caller's test)
    d = P.shape[1]
    weak = ev[0] < nd.tangent_weak * nbr
    noisy = noise > nd.tangent_noise * hl
    if noisy and not weak and not ev[0] < nd.tangent_weak_noisy * nbr:  # (b) under noise: a band
        return False
    # under noise: each circle fitted over the longest span its points still fit, a line where
    # the circle is no better, and the fits' tolerance widened for the noise
    tol = nd.tangent_fit * hl
    if noisy and nd.tangent_rc * noise > tol:
        tol = nd.tangent_rc * noise
    e = np.zeros(d - 1)
    J = np.zeros((d - 1, d))
    MU = np.zeros((nbr, d))
    UU = np.zeros((nbr, d, d))
    CF = np.zeros((nbr, ARC_COEFS))
    C = np.zeros((d, d))
    ev2 = np.zeros(d)
    M3 = np.zeros((ARC_COEFS, ARC_COEFS))
    r3 = np.zeros(ARC_COEFS)
    nm = 0
    curved = False
    for bi in range(nbr):
        ids = flat[off[bi]:off[bi + 1]]
        n = ids.shape[0]
        if n < nd.tangent_points:
            if noisy or not weak:
                return False
            continue
        if noisy:
            m = _arc_fit_grown(P, ids, h[ids[n - 1]], tol, MU[nm], UU[nm], CF[nm], C, ev2, M3, r3, e, J, nd, la)
        else:
            m = _arc_fit(P, ids, nd.tangent_span * h[ids[n - 1]], MU[nm], UU[nm], CF[nm], C, ev2, M3, r3, la)
        if m >= nd.tangent_points and _arc_rms(P, ids, m, MU[nm], UU[nm], CF[nm], e, J) <= tol:
            if noisy:  # (case (b): a branch is curved where its fit kept the circle)
                for a in range(ARC_COEFS):
                    if CF[nm, a] != 0.0:
                        curved = True
            else:  # (case (b) only, read noise-free: ev2 is then this span's scatter)
                # the portion's offsets from its line: the scatter's eigenvalues but the largest
                off2 = 0.0
                for c in range(d - 1):
                    off2 += ev2[c]
                if off2 > m * (nd.tangent_fit * hl) ** 2:
                    curved = True
            nm += 1
        elif noisy or not weak:  # (b), and (a) under noise, need every branch's circle
            return False
    if nm < 2 or ((noisy or not weak) and nm < nbr) or (not weak and not curved):
        return False
    w = np.zeros(d)
    Q = np.zeros((d, d - 1))
    for c in range(d):
        w[c] = V[c, 0]
        for a in range(d - 1):
            Q[c, a] = V[c, a + 1]
    x0 = x.copy()
    xb = np.zeros(d)
    xt = np.zeros(d)
    H = np.zeros((d - 1, d - 1))
    g = np.zeros(d - 1)
    z = np.zeros(d - 1)
    it = nd.tangent_iters
    step = nd.tangent_step * hl
    kmax = int(nd.tangent_reach / nd.tangent_step)
    fb = _arc_profile(x0, w, Q, 0.0, MU, UU, CF, nm, xb, e, J, H, g, z, it)
    f0 = fb
    fm = _arc_profile(x0, w, Q, -step, MU, UU, CF, nm, xt, e, J, H, g, z, it)
    fp = _arc_profile(x0, w, Q, step, MU, UU, CF, nm, xt, e, J, H, g, z, it)
    sgn = 0
    if fm < fb and fm <= fp:
        sgn = -1
    elif fp < fb:
        sgn = 1
    k = 0
    while sgn != 0 and k < kmax:
        ft = _arc_profile(x0, w, Q, (k + 1) * sgn * step, MU, UU, CF, nm, xt, e, J, H, g, z, it)
        if not ft < fb:
            break
        fb = ft
        k += 1
        for c in range(d):
            xb[c] = xt[c]
    meet = nd.tangent_meet * hl + (nd.tangent_meet_noise * noise if noisy else 0.0)
    if not fb <= meet * meet * nm:
        return False
    if noisy and not weak and f0 <= fb + nd.tangent_mid * nm * noise * noise:
        return False  # (b) under noise: the lines' node lies in the circles' meeting already
    if noisy and weak and nd.tangent_mid > 0.0:
        # the valley of near-tangent circles is flat within the fits' noise: its middle (case
        # (b)'s circles cross, at its lowest point)
        lim = fb + nd.tangent_mid * nm * noise * noise
        tb = k * sgn * step
        lo = tb
        while lo - step >= -kmax * step and _arc_profile(x0, w, Q, lo - step, MU, UU, CF, nm, xt, e, J, H, g, z, it) <= lim:
            lo -= step
        hi = tb
        while hi + step <= kmax * step and _arc_profile(x0, w, Q, hi + step, MU, UU, CF, nm, xt, e, J, H, g, z, it) <= lim:
            hi += step
        _arc_profile(x0, w, Q, 0.5 * (lo + hi), MU, UU, CF, nm, xb, e, J, H, g, z, it)
    for c in range(d):
        x[c] = xb[c]
    return True


def _along(P, p, x, w):  # pragma: no cover - compiled
    """Position of sample ``p`` along the unit direction ``w`` from the point ``x``."""
    t = 0.0
    for c in range(P.shape[1]):
        t += (P[p, c] - x[c]) * w[c]
    return t


def _strand_change(P, h, indptr, indices, use_graph, flat, off, rid, x, V, ev, hl, noise, nd):  # pragma: no cover - compiled
    """Under noise, a near-tangent junction's node moved to where the number of strands changes.

    Where branches leave each other at a few degrees (a line leaving a circle tangentially, a
    fillet's arc leaving its straight edge), noise hides for several spacings which samples are
    whose: the circles and lines fitted to the branches meet along a stretch as long as that,
    and a line fitted slightly askew crosses its circle twice, a few spacings either side of
    the junction. The samples still tell it: on one side of a valence-3 junction run one curve's
    samples, on the other two curves' (the branches that have not parted yet), so the samples
    per unit length along the branches' common direction step up by about two there.

    ``A``: the lines' normal matrix, given by its eigenvalues ``ev`` (d,, ascending) and unit
    eigenvectors, the columns of ``V`` (d, d); its eigenvector of the smallest eigenvalue ``w``
    is that direction. The test runs (under noise: the caller's test) only
    where that eigenvalue is under ``nd.tangent_weak_step`` times the number of branches (the
    lines place the node poorly along ``w``), with region points (without them the samples
    near the node are missing), on 3 branches or more, each running along ``w``
    for ``nd.tangent_points`` samples at least (a stub, or a branch turning away at once, is no
    strand), one alone on its side of ``x`` (where along ``w`` its sample the window's length
    from its end lies; a crossing, two and two, has no step). Spacing ``hb``: the median of
    ``h`` over the branches' last ``nd.tangent_window`` region spacings ``hl``. The samples:
    the region points ``rid``, each branch's points (``flat[off[b]:off[b + 1]]``, from its end
    out) while the chord to the sample ``nd.tangent_lag`` back keeps within the cosine
    ``nd.tangent_turn`` of ``w`` (a fillet's arc turning square to its edge would pile samples
    up at one position along ``w``), and their neighbours in the linked graph (``indptr``,
    ``indices``, when ``use_graph``: the junction's samples held by a chain running past the
    node), all within
    ``(nd.tangent_reach + nd.tangent_window) hb`` of ``x`` along ``w``; the window ends where
    the lone branch's samples counted end on its side, and where the first of the others' end
    on the other. The step is the maximum likelihood split of their positions along ``w`` into
    two stretches of constant density (Poisson), at most ``nd.tangent_reach hb`` from ``x``,
    with ``nd.tangent_points`` samples or more on each side, and the lone branch's side at most
    1 / ``nd.tangent_ratio`` as dense as the other. The node moves (to the mean of the samples
    within ``hb`` of the step along ``w``) when the step lies over ``nd.tangent_keep hb`` from
    ``x`` (nearer, the node is as sure as the step). Returns whether ``x`` moved.
    """
    nbr = off.shape[0] - 1
    d = P.shape[1]
    if nbr < nd.junction_valence or rid.shape[0] == 0:  # (without its region: a hole; d >= 2: the caller's test)
        return False
    if not ev[0] < nd.tangent_weak_step * nbr:
        return False
    w = np.zeros(d)
    for c in range(d):
        w[c] = V[c, 0]
    # the strands' spacing: the branches' ends (outside the region, where the doubled side's
    # samples are denser than one curve's; the median holds the single side's too)
    hv = np.empty(flat.shape[0])
    k = 0
    for bi in range(nbr):
        ids = flat[off[bi]:off[bi + 1]]
        n = ids.shape[0]
        for q in range(n - _end_count(P, ids, nd.tangent_window * hl), n):
            hv[k] = h[ids[q]]
            k += 1
    if k == 0:
        return False
    hb = np.median(hv[:k])
    R = nd.tangent_reach * hb
    W = R + nd.tangent_window * hb
    # the side the one branch comes from (where along w its sample the window's length from
    # its end lies: a branch may end past the node): the step is from one curve there to two
    # on the other side (a crossing, two and two, has none)
    below = 0
    above = 0
    b_lo = -1
    b_hi = -1
    for bi in range(nbr):
        ids = flat[off[bi]:off[bi + 1]]
        n = ids.shape[0]
        m = _end_count(P, ids, W)
        if m < nd.tangent_points:  # (a stub is no strand: its side is unknown)
            return False
        if _along(P, ids[n - m], x, w) < 0.0:
            below += 1
            b_lo = bi
        else:
            above += 1
            b_hi = bi
    if below == 1 and above >= 2:
        sgn = 1.0
        stem = b_lo
    elif above == 1 and below >= 2:
        sgn = -1.0
        stem = b_hi
    else:
        return False
    # the samples within the window: the region's, and each branch's from its end out while it
    # runs along w (a branch turning away, e.g. a fillet's arc turning square to its edge,
    # would pile its samples up at one position along w) ...
    nr = rid.shape[0]
    cid = np.empty(nr + flat.shape[0], dtype=np.int64)
    ct = np.empty(nr + flat.shape[0])  # (their positions along w)
    n = 0
    for q in range(nr):
        t = _along(P, rid[q], x, w)
        if -W <= t <= W:
            cid[n] = rid[q]
            ct[n] = t
            n += 1
    # the window ends where the branches' samples counted end (a branch ending or turning away
    # within it would read as fewer curves there): on the one branch's side where its samples
    # end, on the other where the first of the others' ends
    lag = nd.tangent_lag
    a = -W
    b = W
    for bi in range(nbr):
        ids = flat[off[bi]:off[bi + 1]]
        nb = ids.shape[0]
        reach = 0.0
        run = 0
        for q in range(nb - 1, -1, -1):
            if q + lag < nb:
                a2 = 0.0
                al = 0.0
                for c in range(d):
                    dc = P[ids[q], c] - P[ids[q + lag], c]
                    a2 += dc * dc
                    al += dc * w[c]
                if al * al < nd.tangent_turn * nd.tangent_turn * a2:
                    break
            t = _along(P, ids[q], x, w)
            if not -W <= t <= W:
                break
            cid[n] = ids[q]
            ct[n] = t
            if bi == stem and sgn * t < reach or bi != stem and sgn * t > reach:
                reach = sgn * t
            n += 1
            run += 1
        if run < nd.tangent_points:  # (a branch turning away at once: no strand along w)
            return False
        if bi == stem and reach > a:
            a = reach
        elif bi != stem and reach < b:
            b = reach
    # ... and their linked neighbours within it (samples of the junction's curves that a chain
    # running past the node, or a spur dropped there, holds: without them the count has a hole)
    m = 0
    if use_graph:
        for q in range(n):
            m += indptr[cid[q] + 1] - indptr[cid[q]]
    ids = np.empty(n + m, dtype=np.int64)
    tv = np.empty(n + m)
    ids[:n] = cid[:n]
    tv[:n] = ct[:n]
    k = n
    for q in range(n if use_graph else 0):
        p = cid[q]
        for e in range(indptr[p], indptr[p + 1]):
            j = indices[e]
            t = _along(P, j, x, w)
            if not -W <= t <= W:
                continue
            seen = False
            for r in range(k):
                if ids[r] == j:
                    seen = True
                    break
            if not seen:
                ids[k] = j
                tv[k] = t
                k += 1
    n = k
    for q in range(n):
        tv[q] = sgn * tv[q]
    if n < 2 * nd.tangent_points:
        return False
    ts = np.sort(tv[:n])
    i0 = 0
    while i0 < n and ts[i0] < a:
        i0 += 1
    i1 = n
    while i1 > i0 and ts[i1 - 1] > b:
        i1 -= 1
    best = -np.inf
    split = 0.0
    for i in range(i0 + nd.tangent_points, i1 - nd.tangent_points + 1):
        s = 0.5 * (ts[i - 1] + ts[i])
        if not (-R <= s <= R) or ts[i] == ts[i - 1]:
            continue
        r1 = (i - i0) / (s - a)
        r2 = (i1 - i) / (b - s)
        if not r2 >= nd.tangent_ratio * r1:
            continue
        ll = (i - i0) * np.log(r1) + (i1 - i) * np.log(r2)
        if ll > best:
            best = ll
            split = s
    if best == -np.inf or not abs(split) > nd.tangent_keep * hb:
        return False
    xm = np.zeros(d)
    cnt = 0
    for q in range(n):
        if abs(tv[q] - split) <= hb:
            for c in range(d):
                xm[c] += P[ids[q], c]
            cnt += 1
    if cnt == 0:
        return False
    for c in range(d):
        x[c] = xm[c] / cnt
    return True


def _region_mean(P, rid, out):  # pragma: no cover - compiled
    """The mean of the points ``rid`` (at least one) into ``out`` (d,); returns ``out``."""
    for c in range(out.shape[0]):
        acc = 0.0
        for q in range(rid.shape[0]):
            acc += P[rid[q], c]
        out[c] = acc / rid.shape[0]
    return out


def _add_line(A, b, mu, u):  # pragma: no cover - compiled
    """Add the line through ``mu`` along the unit ``u`` (both (d,)) to the least-squares normal
    equations of the point nearest to lines: ``A += I - u u^T``, ``b += (I - u u^T) mu``."""
    d = mu.shape[0]
    um = 0.0
    for c in range(d):
        um += u[c] * mu[c]
    for a in range(d):
        for c in range(d):
            A[a, c] += (1.0 if a == c else 0.0) - u[a] * u[c]
        b[a] += mu[a] - u[a] * um


def _line_dist(x, mu, u):  # pragma: no cover - compiled
    """Distance from the point ``x`` (d,) to the line through ``mu`` along the unit ``u``."""
    r2 = 0.0
    al = 0.0
    for c in range(x.shape[0]):
        t = x[c] - mu[c]
        r2 += t * t
        al += t * u[c]
    dv = r2 - al * al
    return np.sqrt(dv if dv > 0.0 else 0.0)


def _without_stray_line(MU, U, nl, x, hs, anchor, centre, A, C, V, ev, b, xk, best, nd, la):  # pragma: no cover - compiled
    """A junction's node from the lines of all its branches but one that strays from the others.

    ``MU``, ``U`` (nl, d): each branch's line (a point on it, its unit direction). A branch whose
    curve turns a few spacings before the junction (the corner of a roof or a window outline
    next to a facade's post, a traced neurite's kink) has its line fitted before the turn: it
    misses the junction by about the turn's distance and pulls the least-squares node along the
    others by a spacing or two. For each line ``k`` the node of the others (their normal matrix
    well posed: smallest eigenvalue at least ``nd.stray_cond``, lines about 60 degrees apart or
    more) is computed; where ``k`` lies over ``nd.stray_off`` junction spacings ``hs`` (widened
    for noise) from it and every other line within ``nd.stray_agree hs``, ``k`` strays. Of such
    lines, the one whose others' node lies nearest ``centre`` (d,), the mean of the junction's
    region points, is left out, and ``x`` (d,), the node of all the lines, becomes the others'
    node (pulled by ``nd.anchor_pull`` towards ``anchor`` as the full fit is) when that lies
    nearer ``centre`` than ``x`` (two lines of a kinked traced neurite, 60 degrees apart, can
    meet a few spacings down one of them). The lines alone cannot tell
    which branch turned: in a plane any two lines meet, and the turned branch's line meets the
    straight branch beside it at the turn, so leaving out the third branch's line reads the
    turn as the junction; the region can (the shell test flags the points around the junction,
    where three branches leave, not the turn, where two do). Returns whether ``x`` moved. Needs
    ``nd.junction_valence`` lines or more. ``A``, ``C``, ``V`` (d, d) and ``ev``, ``b``, ``xk``,
    ``best`` (d,): scratch space, overwritten.
    """
    d = x.shape[0]
    if nl < nd.junction_valence:
        return False
    best_r2 = np.inf
    for k in range(nl):
        for a in range(d):
            b[a] = 0.0
            for c in range(d):
                A[a, c] = 0.0
        for q in range(nl):
            if q != k:
                _add_line(A, b, MU[q], U[q])
        for a in range(d):
            for c in range(d):
                C[a, c] = A[a, c]
        _eig_sym(C, V, ev, la)
        if not ev[0] >= nd.stray_cond:
            continue
        for a in range(d):
            A[a, a] += nd.anchor_pull
            b[a] += nd.anchor_pull * anchor[a]
        if not _solve_small(A, b, xk):
            continue
        if not _line_dist(xk, MU[k], U[k]) > nd.stray_off * hs:
            continue
        s = 0.0
        for q in range(nl):
            if q != k:
                dq = _line_dist(xk, MU[q], U[q])
                if dq > s:
                    s = dq
        if s <= nd.stray_agree * hs:
            r2 = 0.0
            for c in range(d):
                r2 += (xk[c] - centre[c]) ** 2
            if r2 < best_r2:
                best_r2 = r2
                for c in range(d):
                    best[c] = xk[c]
    if best_r2 == np.inf:
        return False
    r2 = 0.0
    for c in range(d):
        r2 += (x[c] - centre[c]) ** 2
    if not best_r2 < r2:
        return False
    for c in range(d):
        x[c] = best[c]
    return True


def _junction_nodes(P, h, indptr, indices, bflat, boff, jb, rflat, roff, hj, width, noise,  # pragma: no cover - compiled
                    jp, en, nd, la):
    """Node position of many junctions at once (see ``nodes.junction_positions``).

    Junction ``j`` has the branches ``jb[j] .. jb[j + 1] - 1``; branch ``b`` is
    ``bflat[boff[b]:boff[b + 1]]`` (point ids running towards the junction); its region points
    are ``rflat[roff[j]:roff[j + 1]]`` (sorted, unique). ``hj[j]``: the junction's spacing (the
    median over its region points; without region points, over its branches' first points).
    ``jp``: the method's settings (:class:`JunctionParams`).

    Each branch is walked into the region (:func:`_extend_into_region`), the walk cut where it
    leaves a strip of ``jp.walk_dev`` link widths around the line fitted on the branch's end; the
    node is the least-squares intersection of the lines fitted on the walked ends, pulled a
    little (weight ``nd.anchor_pull``) towards the mean of the branch ends (the anchor), and the anchor when
    it lands over the largest distance away; where the junction has region points, a line that
    strays from the node of the others (its curve turns before the junction) is left out
    (:func:`_without_stray_line`). A line has the direction of its end portion and
    passes through the portion's mean, or, on noise-free input (noise at most
    ``nd.tangent_noise`` spacings) at a junction of ``nd.junction_valence`` branches or more,
    through the walked branch's last sample.

    Returns
    -------
    X : (n_junctions, d) ndarray
        Node positions.
    maybe : (n_junctions,) ndarray of bool
        Whether a free branch may hide in the region (a superset of what
        ``junctions.swallowed_branches`` finds: False means it finds none).
    """
    nj = jb.shape[0] - 1
    d = P.shape[1]
    jspan = jp.jspan
    jn = jp.jn
    walk_dev = jp.walk_dev
    nw = jp.nw
    far = jp.far
    swallow_r = jp.swallow_r
    swallow_cos = jp.swallow_cos
    widen = jp.widen
    use_graph = jp.use_graph
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
    xs = np.zeros(d)
    A0 = np.zeros((d, d))
    Vl = np.zeros((d, d))
    evl = np.zeros(d)
    anchor = np.zeros(d)
    xc = np.zeros(d)
    # the lines of one junction (the most branches of any) and _without_stray_line's scratch
    most = 0
    for j in range(nj):
        if jb[j + 1] - jb[j] > most:
            most = jb[j + 1] - jb[j]
    MU = np.zeros((most, d))
    U = np.zeros((most, d))
    sA = np.zeros((d, d))
    sC = np.zeros((d, d))
    sV = np.zeros((d, d))
    sev = np.zeros(d)
    sb = np.zeros(d)
    sxk = np.zeros(d)
    sbest = np.zeros(d)
    for j in range(nj):
        b0 = jb[j]
        b1 = jb[j + 1]
        nbr = b1 - b0
        rid = rflat[roff[j]:roff[j + 1]]
        nr = rid.shape[0]
        base = boff[b0]
        flat = bflat[base:boff[b1]]
        off = boff[b0:b1 + 1] - base
        # walked branches: flat[off[bi]:off[bi + 1]] then ext[eoff[bi]:], L[bi] points in all
        L = np.empty(nbr, dtype=np.int64)
        for bi in range(nbr):
            L[bi] = off[bi + 1] - off[bi]
        if nr > 0 and use_graph:
            ext, eoff = _extend_into_region(P, h, indptr, indices, flat, off, rid, width, nw * noise, en, nd)
            for bi in range(nbr):
                L[bi] += eoff[bi + 1] - eoff[bi]
            for bi in range(nbr):
                n0 = off[bi + 1] - off[bi]
                if eoff[bi + 1] == eoff[bi] or n0 < 2:
                    continue
                orig = flat[off[bi]:off[bi + 1]]
                hl0 = h[orig[n0 - 1]]
                m = _fit_end(P, h, orig, jspan + jn * noise / hl0, mu, u, C, V, ev, True, en, la)
                if m < 2:
                    continue
                lim = width * hl0
                if nw * noise > lim:
                    lim = nw * noise
                lim = walk_dev * lim
                for q in range(n0, L[bi]):
                    if _line_dist(P[ext[eoff[bi] + q - n0]], mu, u) > lim:
                        L[bi] = q
                        break
        else:
            ext = np.zeros(0, dtype=np.int64)
            eoff = np.zeros(nbr + 1, dtype=np.int64)
        for a in range(d):
            bb[a] = 0.0
            anchor[a] = 0.0
            for c in range(d):
                A[a, c] = 0.0
        ncs = 0
        nl = 0  # the lines, each kept in MU, U
        # noise-free: each line through its branch's last sample, which lies on the curve (the
        # end portion's mean lies off a bent or kinked curve: a traced neurite's lines met 1-2 h
        # off its junctions); two branches keep the mean (their lines are near-parallel, and
        # moving one moves their meeting along the curve)
        through_end = nbr >= nd.junction_valence and noise <= nd.tangent_noise * hj[j]
        for bi in range(nbr):
            n0 = off[bi + 1] - off[bi]
            ids = np.empty(L[bi], dtype=np.int64)
            for q in range(L[bi]):
                ids[q] = flat[off[bi] + q] if q < n0 else ext[eoff[bi] + q - n0]
            n = ids.shape[0]
            if n == 0:
                continue
            m = _fit_end(P, h, ids, jspan + jn * noise / h[ids[n - 1]], mu, u, C, V, ev, True, en, la)
            for c in range(d):
                anchor[c] += P[ids[n - 1], c]
            ncs += 1
            if m < 2:
                continue
            if through_end:
                for c in range(d):
                    mu[c] = P[ids[n - 1], c]
            for c in range(d):
                MU[nl, c] = mu[c]
                U[nl, c] = u[c]
            nl += 1
            _add_line(A, bb, mu, u)
        if ncs > 0:
            for c in range(d):
                anchor[c] = anchor[c] / ncs
        elif nr > 0:
            _region_mean(P, rid, anchor)
        hl = hj[j]
        for a in range(d):
            for c in range(d):
                A0[a, c] = A[a, c]
        for a in range(d):
            A[a, a] += nd.anchor_pull
            bb[a] += nd.anchor_pull * anchor[a]
        ok = _solve_small(A, bb, x)
        dist2 = 0.0
        for c in range(d):
            if not np.isfinite(x[c]):
                ok = False
            dist2 += (x[c] - anchor[c]) ** 2
        if not ok or not np.sqrt(dist2) <= far * hl:
            for c in range(d):
                x[c] = anchor[c]
        elif nr > 0:
            # a branch turning before the junction: the node of the others' lines, when no
            # farther from the anchor than the lines' node may be
            for c in range(d):
                xs[c] = x[c]
            if _without_stray_line(MU, U, nl, xs, hl + widen * noise, anchor, _region_mean(P, rid, xc), sA, sC, sV, sev,
                                   sb, sxk, sbest, nd, la):
                dist2 = 0.0
                for c in range(d):
                    dist2 += (xs[c] - anchor[c]) ** 2
                if np.sqrt(dist2) <= far * hl:
                    for c in range(d):
                        x[c] = xs[c]
        # near-tangent or curved branches: where their circles meet, and under noise where the
        # strands step from one to two (_strand_change), when no farther from the anchor than
        # the lines' node may be
        for c in range(d):
            xs[c] = x[c]
        moved = False
        if d >= 2 and nbr >= 2:  # (the lines' eigenpairs, read by both)
            _eig_sym(A0, Vl, evl, la)
            moved = _tangent_node(P, h, flat, off, x, hl, noise, Vl, evl, nd, la)
            if noise > nd.tangent_noise * hl and _strand_change(P, h, indptr, indices, use_graph, flat, off, rid, x,
                                                                Vl, evl, hl, noise, nd):
                moved = True
        if moved:
            dist2 = 0.0
            for c in range(d):
                if not np.isfinite(x[c]):
                    dist2 = np.inf
                else:
                    dist2 += (x[c] - anchor[c]) ** 2
            if not np.sqrt(dist2) <= far * hl:
                for c in range(d):
                    x[c] = xs[c]
        for c in range(d):
            X[j, c] = x[c]
        # a free branch hidden in the region: some region point far from the node, in a
        # direction no branch takes (tested again exactly by junctions.swallowed_branches)
        if nr < nd.swallow_min:
            continue
        hs = hl + widen * noise
        ndir = 0
        D = np.zeros((nbr, d))
        for bi in range(nbr):
            orig = flat[off[bi]:off[bi + 1]]
            _fit_end(P, h, orig, jspan, mu, u, C, V, ev, False, en, la)  # the mean of the end only
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
            if not dq > swallow_r * hs * (1.0 - nd.swallow_tol):
                continue
            best = -np.inf
            for k in range(ndir):
                al = 0.0
                for c in range(d):
                    al += (P[p, c] - x[c]) * D[k, c]
                if al > best:
                    best = al
            if best / dq < swallow_cos + nd.swallow_tol:
                maybe[j] = True
                break
    return X, maybe


def _behind_count(P, h, ids, lo, hi, step, x, span2, en):  # pragma: no cover - compiled
    """How many leading ids of ``ids[lo:hi]`` (read from ``lo`` up when ``step`` is 1, from
    ``hi - 1`` down when it is -1) lie behind the node ``x``.

    The chain's direction is that from ``x`` to its point ``k``, the first at arc length
    ``span2 * h`` from the start (at most the last); leading points whose offset from ``x`` has
    no positive component along it are behind. At least 2 points are kept. (The numpy formula
    is the reference of tests/test_robust_kernels.py.)"""
    n = hi - lo
    if n < en.trim_min:
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


def _trim_ends(P, h, flat, off, do0, do1, XA, XB, span2, en):  # pragma: no cover - compiled
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
            lo[c] += _behind_count(P, h, flat, lo[c], hi[c], 1, XA[c], span2, en)
        if do1[c]:
            hi[c] -= _behind_count(P, h, flat, lo[c], hi[c], -1, XB[c], span2, en)
    return lo, hi
