"""Sequential per-point loops of the robust method, compiled with numba when it is installed.

Each kernel is plain Python written in the subset numba compiles. When numba is missing (or
``CURVENET_NO_NUMBA=1`` is set) the very same Python function runs, so both paths give identical
results; the Python path is only slow.
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["shell_groups", "csr_union", "end_count", "HAVE_NUMBA"]


def _shell_groups(P, h, indptr, indices, r_in, r_out):  # pragma: no cover - compiled
    """Groups of the geodesic shell around every point (see robust.shell_group_counts)."""
    n = P.shape[0]
    d = P.shape[1]
    groups = np.zeros(n, dtype=np.int32)
    mark = np.full(n, -1, dtype=np.int64)  # == p when reached from p
    done = np.full(n, -1, dtype=np.int64)  # == p when settled
    gd = np.zeros(n, dtype=np.float64)  # tentative geodesic distance from p
    comp = np.full(n, -1, dtype=np.int64)
    shell = np.full(n, -1, dtype=np.int64)
    reached = np.empty(n, dtype=np.int64)
    heap_k = np.empty(n + 1, dtype=np.float64)
    heap_v = np.empty(n + 1, dtype=np.int64)
    cap = n + 1
    stack = np.empty(n, dtype=np.int64)
    for p in range(n):
        ro = r_out * h[p]
        ri = r_in * h[p]
        nreach = 0
        # Dijkstra from p, bounded by ro (lazy deletion binary heap)
        hs = 1
        heap_k[0] = 0.0
        heap_v[0] = p
        mark[p] = p
        gd[p] = 0.0
        while hs > 0:
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
                if mark[b] == p and gd[b] <= nk:
                    continue
                mark[b] = p
                gd[b] = nk
                if hs >= cap:
                    continue
                i = hs
                hs += 1
                while i > 0:
                    par = (i - 1) // 2
                    if heap_k[par] > nk or (heap_k[par] == nk and heap_v[par] > b):
                        heap_k[i] = heap_k[par]
                        heap_v[i] = heap_v[par]
                        i = par
                    else:
                        break
                heap_k[i] = nk
                heap_v[i] = b
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


HAVE_NUMBA = False
shell_groups = _shell_groups
csr_union = _csr_union
end_count = _end_count
if os.environ.get("CURVENET_NO_NUMBA", "") not in ("1", "true", "yes"):
    try:  # pragma: no cover - depends on the environment
        import numba

        shell_groups = numba.njit(cache=True, nogil=True)(_shell_groups)
        csr_union = numba.njit(cache=True, nogil=True)(_csr_union)
        end_count = numba.njit(cache=True, nogil=True)(_end_count)
        HAVE_NUMBA = True
    except ImportError:  # pragma: no cover
        pass
