"""The geodesic shell test: how many branches leave every point (groups of its shell).

The fixed constants come in a :class:`~curvenet.methods.robust.thresholds.Shell` (``sh``) and
the rounding tolerance in a :class:`~curvenet.methods.robust.thresholds.Numeric` (``num``).
Every radius is compared with that relative tolerance, ties counting in: on regularly sampled
input a point often lies exactly at a radius (the middle of the shell is 4 spacings out, 2 at
the finest scale of the re-tests), where the last bit of a sum of steps would otherwise decide
whether a branch leaves.
"""

from __future__ import annotations

import numpy as np

from .heap import _heap_pop, _heap_push

prange = range  # numba.prange in the compiled copies (parallel loops over blocks of points)


def _shell_groups(P, h, indptr, indices, r_in, r_out, goes_on, order, nblocks, sh, num):  # pragma: no cover - compiled
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
        _shell_groups_block(P, h, indptr, indices, r_in, r_out, goes_on, order, b * bs, p1 if p1 < no else no, groups, sh, num)
    return groups


def _shell_groups_block(P, h, indptr, indices, r_in, r_out, goes_on, order, i0, i1, groups, sh, num):  # pragma: no cover - compiled
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
    front_max = sh.front_max
    fk = np.empty(front_max + 1, dtype=np.float64)
    fv = np.empty(front_max + 1, dtype=np.int32)
    heap_k = np.empty(n + 1, dtype=np.float64)
    heap_v = np.empty(n + 1, dtype=np.int32)
    cap = n + 1
    stack = np.empty(n, dtype=np.int32)
    for ii in range(i0, i1):
        p = order[ii]
        # the radii with the rounding tolerance, ties in: the reach bound a little out, the
        # inner radius and the middle a little in
        ro = r_out * h[p] * (1.0 + num.rel)
        ri = r_in * h[p] * (1.0 - num.rel)
        nreach = 0
        # Dijkstra from p, bounded by ro. The frontier is a short list scanned for its nearest
        # point (on curves it holds a few); past front_max points (a dense clump) it moves to a
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
                    if nf > front_max:
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
        # when it is a branch leaving p: it reaches the middle of the shell along the graph,
        # or (``goes_on``) it goes on past the shell (a point of it linked to one beyond the
        # outer radius); not a small cluster near the inner radius (the tip of an acute
        # corner). (On a thin shell, at the finest re-tests, a branch sampled every spacing has
        # one sample in it, on either side of the middle by the sampling's phase.)
        rmid = 0.5 * (r_in + r_out) * h[p] * (1.0 - num.rel)
        ng = 0
        for q in range(nreach):
            a = reached[q]
            if shell[a] != p or comp[a] == p:
                continue
            comp[a] = p
            gmax = gd[a]
            beyond = False
            top = 1
            stack[0] = a
            while top > 0:
                top -= 1
                x = stack[top]
                if gd[x] > gmax:
                    gmax = gd[x]
                for e in range(indptr[x], indptr[x + 1]):
                    y = indices[e]
                    if mark[y] != p:  # (not reached within the outer radius)
                        beyond = True
                    elif shell[y] == p and comp[y] != p:
                        comp[y] = p
                        stack[top] = y
                        top += 1
            if gmax >= rmid or (goes_on and beyond):
                ng += 1
        groups[p] = ng
    return groups
