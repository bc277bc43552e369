"""Chain kernels: the order of the points of every chain, the regions its ends touch, and the
untangling of a curve's point order.

The fixed constants come in a :class:`~curvenet.methods.robust.thresholds.Chains` (``ch``) and
an ``Untangle`` (``ut``).
"""

from __future__ import annotations

import numpy as np

from .heap import _heap_pop, _heap_push


def _chain_order(n, src, dst, dd, chn, n_chn, ch):  # pragma: no cover - compiled
    """Every chain ordered by geodesic distance from one end (see chains.order_chains).

    Chain ``c`` is the set of points with ``chn == c`` (-1: none), joined by the edges
    ``(src[i], dst[i])`` with both ends in it, undirected, of length ``max(dd[i], ch.min_edge)``.
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
    ch : Chains

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
    nbr = np.empty(deg[n], dtype=src.dtype)  # point ids in the ids' own width (int32)
    wt = np.empty(deg[n], dtype=np.float64)
    fill = deg[:-1].copy()
    for i in range(m):
        a = src[i]
        b = dst[i]
        if chn[a] >= 0 and chn[a] == chn[b]:
            w = dd[i] if dd[i] > ch.min_edge else ch.min_edge
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
    # == run when gd is set in that run. No 'settled' mark is needed: a point's heap entries
    # have strictly decreasing keys (a push needs a shorter distance), so only its last one
    # equals gd when popped; and a settled neighbour b has gd[b] <= key < key + wt (every
    # edge is at least ch.min_edge > 0 long), so the test below skips it
    mark = np.full(n, -1, dtype=np.int64)
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
                if key > gd[a]:
                    continue
                ids_o[k] = a
                par_o[k] = key
                k += 1
                for e in range(deg[a], deg[a + 1]):
                    b = nbr[e]
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


def _chain_ends(h, ids_o, par_o, bounds, c_reg, c_par, cb, ch):  # pragma: no cover - compiled
    """The region each end of every chain touches (see chains.order_chains).

    Chain ``ci`` is ``ids_o[bounds[ci]:bounds[ci + 1]]`` with positions ``par_o`` (ascending,
    its length ``L`` the last one); its contacts ``cb[ci]:cb[ci + 1]`` give a region
    ``c_reg`` (ascending within the chain) and a position ``c_par``. With ``hl`` the median
    spacing of the chain and ``reach = min(L / 2, ch.end_reach hl)``, the start end takes the most frequent
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
        if ch.end_reach * hl < reach:
            reach = ch.end_reach * hl
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


def _dist2(X, a, b):  # pragma: no cover - compiled
    """Squared distance between the rows ``a`` and ``b`` of ``X``."""
    s = 0.0
    for q in range(X.shape[1]):
        t = X[b, q] - X[a, q]
        s += t * t
    return s


def _untangle(X, off, which, w, cos_back, ut):  # pragma: no cover - compiled
    """A shorter order of the inner points of the curves ``which`` (windowed 2-opt).

    The curves are ``X[off[c]:off[c + 1]]``, concatenated; each keeps its first and last
    point. In sweeps (at most ``ut.sweeps``) over the positions ``i`` up to ``w`` points before a turn
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
        if n < ut.min_points:
            continue
        for sweep in range(ut.sweeps):
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
            # (a reversal of [i + 1, j] needs i + 2 <= j <= n - 2: the j loop is empty from i = n - 3 on)
            for i in range(n - 2):
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
                if bj >= 0 and best < -ut.min_gain * dab:
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
