"""The founding paper's method: Algorithm 1 (node detection) and Algorithm 2 (curve reconstruction).

Reference: *Reconstruction of Curve Networks from Unorganized Spatial Points*
(``shared/paper/reconstruction-of-curve-networks.txt``), section 3. This module implements it
as published; where the paper is silent or ambiguous the reading chosen is stated below, so
that results can be reproduced and compared.

Algorithm 1, node detection
---------------------------
1. For every point :math:`P_i`, its ``k`` nearest neighbours :math:`A` (the point itself
   excluded) give the covariance of equation (1), centred at :math:`P_i` itself (not at the
   mean of :math:`A`) and divided by ``k``. The point variation of equation (2) is
   :math:`\\delta = \\lambda_0 / \\sum \\lambda` with :math:`\\lambda_0` the smallest eigenvalue.
   2D input uses the 2x2 covariance (:math:`\\delta = \\lambda_0 / (\\lambda_0 + \\lambda_1)`).
   All points are done at once (batched ``eigvalsh``). Note that this is Pauly's *surface*
   variation: in 3D, neighbourhoods that lie in a plane have :math:`\\lambda_0 = 0`, so a
   junction whose curves are coplanar (a flat star, a T in a plane) is not a candidate. That is
   the paper's equation (2), kept as is.
2. Points with :math:`\\delta > \\varepsilon` are candidate nodes.
3. Grouping (the paper: "if the Euclidean distances between a random candidate and the rest of
   the candidates are less than τ_S, these candidates are divided into a same group"). Read
   deterministically: groups are the connected components of the graph joining candidates at
   distance ``<= tau_s``.
4. In each group of ``n > 4`` candidates, the candidate farthest from the group's centroid is
   removed and the centroid recomputed, until four remain; the candidate nearest the last
   centroid is the node. A group of four or fewer candidates has no removal step: its node is
   simply the candidate nearest its centroid (the same final step). Nodes are input points.

Algorithm 2, curve reconstruction
---------------------------------
Our reading of the pseudo-code, line by line:

* Line 2 ("remove all candidate nodes from P"): the candidates that did not become nodes are
  removed from the point set for the whole of Algorithm 2; the nodes stay in it (they are what
  a curve ends on). The removal sits inside the loop over nodes and line 6 tests ``P_j`` only
  against the curves of the *current* node (``F^i``): so criterion 2 (point removal) acts
  **per node pass**. Each node starts with all points available again, which is what lets every
  curve be traced from both of its ends (criterion 4).
* Lines 4-10: the starting points of node ``C_i`` are the available points at distance
  ``< tau_s`` from it, in ascending order of distance (ties by coordinates). Nodes are never
  starting points (the literal pseudo-code would start a curve at ``C_i`` itself). A starting
  point already used by an earlier curve of this pass is skipped (line 6).
* Lines 11-19, criteria 1-3: from the last point ``F_{k-1}`` (predecessor ``F_{k-2}``) take the
  nearest available point; reject it if the angle at ``F_{k-1}`` between ``F_{k-2}F_{k-1}`` and
  ``F_{k-1}P_n`` is below ``theta`` (the *interior* angle at the middle point, so a straight
  continuation is 180 degrees and the paper's "greater than an obtuse angle", 100-150 degrees,
  bounds the turn at each point) and try the next nearest. The angle is measured at every inner
  point, the first one included (its predecessor is the start node); never at a node ("three
  continuous points excluding the node"). We apply the angle test to nodes as targets too (the
  literal lines 17-18 accept any node): otherwise the first inner point would often return to
  its own start node, a two-point loop.
* A curve ends when the chosen point is a node (line 11). Points are never used twice in one
  pass; nodes are never "used", so several curves of a pass may end on the same node and a curve
  may return to its start node (a loop through one node, ``start == end``).
* **Step bound and free ends** (not in the paper): a point at ``tau_s`` or more from the
  current point is not admissible. When no admissible point remains, the curve has reached a
  *dead end*: it ends there and its last point becomes a new free-end node (valence 1). Free-end
  nodes are then traced from like the detected nodes, so that their curves also have twins;
  dead ends met on those traces do not make further nodes (their curves find no twin and are
  dropped), so traces cannot wander from free end to free end onto curves that touch no node.
  Without the bound, a curve reaching a free end would jump across to any far point and free
  ends could never be nodes. ``tau_s`` is the paper's own neighbourhood scale and must already
  exceed the gap left by the removed candidates around a node (or no starting point exists), so
  the bound never cuts a proper step into a node.
* Criterion 4, reverse search (lines 24-28): every curve ``a -> b`` (``a != b``) is matched with a
  *twin* traced from ``b`` ending at ``a``, the twin sharing the most inner points (greedy over
  all pairs of a node pair, most shared points first; pairs sharing no point are not twins).
  The merged curve keeps the part of ``a -> b`` next to its start node and replaces the part next
  to its ending node by the twin's part next to the twin's start node (the paper's "replace the
  points next to the ending node of F with the points next to the starting node of F_s"). The
  paper's figure replaces one point; we splice at the shared point that balances the two parts
  (it minimises the larger of the two relative positions), which is the paper's rule when the
  traces disagree at one point and also repairs longer disagreements near an end. The twin is
  removed. A curve without a twin is discarded (it was not found from both directions; counted
  in ``stats["unmatched"]``). A loop ``a -> a`` is its own twin and is kept once.
* Free-end nodes left without a curve are dropped; detected nodes are all kept.

Consequences, faithful to the paper: a closed loop with no candidate on it (a circle) has no
node and is lost; an open curve with no junction at all is lost too (nothing starts it); curves
passing within a neighbourhood of each other create candidates (and so nodes) there.

Also faithful: δ of a junction whose curves lie on a smooth surface shrinks like
``(h * curvature)**2`` as the sampling gets denser (two curves through a point span a plane),
so ε must shrink with the spacing; this is why the paper's ε go down to 1e-9. Only junctions
whose curves are not coplanar (a cube corner) keep a δ independent of the density.

Performance
-----------
The 8 nearest available neighbours closer than ``tau_s`` of every point are found with one
threaded k-d tree query and kept sorted by (distance, index); tracing scans these short lists.
When a trace exhausts a list that may be incomplete, that row is replaced by its full
``tau_s``-ball and the node pass is run again, so the result is exactly that of full lists.
The tracing loop is a small kernel compiled with numba when it is installed (extra ``fast``)
and the input is large (:data:`NUMBA_MIN_POINTS`), and run as plain Python otherwise; both give
the same result. Measured on a loaded 2-core machine: a 3D lattice wireframe of 1.14 million
points in about 20 s (about as long as one threaded k = 16 neighbour query in the same run).
Input points are first sorted by coordinates, so that every tie broken by index is broken by
coordinates and the result does not depend on the order of the input points.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..errors import InputError
from ..network import Curve, CurveNetwork
from .._sigint import held
from ..neighbors import build_tree, knn, query
from ..validate import as_points
from .stages import PAPER_SHARES, OnStage, report_stage

__all__ = [
    "reconstruct_paper",
    "point_variation",
    "detect_nodes",
    "DEFAULT_K",
    "DEFAULT_EPSILON",
    "DEFAULT_TAU_FACTOR",
]

#: Neighbours per point in Algorithm 1. The paper gives no value; 6 is chosen by a study
#: (``benchmarks/paper_defaults.py``, docs/paper-defaults.md): on 8 clean 3D wireframe
#: sketches of about 15,000 points each (the size of the paper's Table 1 models), k = 6 gave
#: the best mean curve F1 both with ε, τ_S, θ tuned per sketch (0.64, against 0.54 for
#: k = 10, 0.61 for k = 4, 0.54 for k = 8) and with the defaults (0.63 against 0.51 for
#: k = 10), and the most sketches with the exact topology (3 of 8 tuned, as k = 4; 2 for k = 10).
#: Fewer neighbours keep the PCA of eq. (1) local, so candidates stay close to the junctions
#: and junction regions of nearby nodes do not run into each other; k = 4 is too few for a
#: stable covariance. The default τ_S scales with k (``DEFAULT_TAU_FACTOR * k * h``, 9 h).
DEFAULT_K = 6

#: Threshold on the point variation, by dimension. δ is scale-free. On clean, uniformly sampled
#: curves (k = 10) δ is ~1e-16 on straight parts, ~1e-6 on a helix sampled at 20 points per
#: radius (1e-5 at 10), and above ~1e-2 next to a non-coplanar junction. In 2D, curvature
#: enters δ directly: a circle at 20 points per radius has δ ~ 0.01 (0.045 at 10), so the 2D
#: threshold is higher and tight 2D bends below ~15 points per radius become candidates.
#: The paper's values (1e-9 .. 1e-4) are for its own models.
DEFAULT_EPSILON = {2: 2e-2, 3: 1e-3}

#: Default ``tau_s`` is ``DEFAULT_TAU_FACTOR * k * h``, ``h`` the median nearest-neighbour
#: spacing. τ_S plays three parts: it groups candidates (so it must exceed the spacing between
#: candidates, ~h), it picks the starting points of the curves around a node (so it must exceed
#: the gap left by the removed candidates, which reach about ``k / 2`` spacings along each
#: curve at a right-angled junction and up to ``k / (2 sin a)`` at a junction of angle ``a``),
#: and it bounds a step. ``1.5 k h`` (9 h for the default k = 6) clears the gap for junction
#: angles down to about 20 degrees; nodes must then be more than about ``2.5 k h`` apart to stay
#: separate.
DEFAULT_TAU_FACTOR = 1.5

_CHUNK = 65536


# ---------------------------------------------------------------------------------------------
# Algorithm 1
# ---------------------------------------------------------------------------------------------
def point_variation(points: np.ndarray, k: int = DEFAULT_K, *, neighbors: np.ndarray | None = None) -> np.ndarray:
    """Point variation δ of every point (the paper's equations (1) and (2)).

    Parameters
    ----------
    points : (N, d) ndarray of float
        The points, ``d`` = 2 or 3.
    k : int
        Number of nearest neighbours (the point itself excluded).
    neighbors : (N, k) ndarray of int, optional
        Precomputed neighbour indices (as from :func:`curvenet.neighbors.knn`).

    Returns
    -------
    (N,) ndarray of float
        ``λ0 / (λ0 + ... + λ_{d-1})`` of the covariance ``(1/k) Σ (a - p)(a - p)^T`` over the
        neighbours ``a`` of each point ``p``, centred at ``p`` itself; 0 where all neighbours
        coincide with the point.
    """
    p = np.asarray(points, dtype=float)
    if neighbors is None:
        _, neighbors = knn(p, k)
    n, kk = neighbors.shape
    out = np.zeros(n)
    if kk == 0:
        return out
    for s in range(0, n, _CHUNK):
        e = min(n, s + _CHUNK)
        diff = p[neighbors[s:e]] - p[s:e, None, :]  # (m, k, d)
        cov = np.matmul(diff.transpose(0, 2, 1), diff) / kk  # eq. (1)
        lam = np.linalg.eigvalsh(cov)  # ascending
        lam = np.clip(lam, 0.0, None)
        tot = lam.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[s:e] = np.where(tot > 0, lam[:, 0] / np.where(tot > 0, tot, 1.0), 0.0)  # eq. (2)
    return out


def _group_candidates(points: np.ndarray, cand: np.ndarray, tau_s: float) -> list[np.ndarray]:
    """Connected components of the ``tau_s`` graph among candidates (indices into ``points``)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if len(cand) == 0:
        return []
    tree = build_tree(points[cand])
    pairs = tree.query_pairs(r=tau_s, output_type="ndarray")
    m = len(cand)
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
    _, lab = connected_components(g, directed=False)
    order = np.argsort(lab, kind="stable")  # members ascending by index within each label
    splits = np.flatnonzero(np.diff(lab[order])) + 1
    groups = [cand[g_] for g_ in np.split(order, splits)]
    groups.sort(key=lambda g_: int(g_[0]))
    return groups


def _select_nodes(points: np.ndarray, groups: list[np.ndarray]) -> np.ndarray:
    """The node of each group (an index into ``points``), Algorithm 1 lines 12-16.

    In each group (members ascending by index, i.e. by coordinates) the candidate farthest from
    the centroid of the remaining ones is removed (ties: the first) until four remain; the
    candidate nearest the last centroid (ties: the first) is the node. Groups are processed
    together, padded to a power-of-two size.
    """
    out = np.empty(len(groups), dtype=np.int64)
    if not groups:
        return out
    sizes = np.array([len(g) for g in groups])
    pad = 1 << np.ceil(np.log2(np.maximum(sizes, 1))).astype(int)
    for gi in np.flatnonzero(sizes > _LARGE_GROUP):
        out[gi] = groups[gi][_select_node_large(points[groups[gi]])]
    for m in np.unique(pad[sizes <= _LARGE_GROUP]):
        sel = np.flatnonzero((pad == m) & (sizes <= _LARGE_GROUP))
        G, d = len(sel), points.shape[1]
        X = np.zeros((G, m, d))
        alive = np.zeros((G, m), dtype=bool)
        for r, gi in enumerate(sel):
            X[r, : sizes[gi]] = points[groups[gi]]
            alive[r, : sizes[gi]] = True
        cnt = sizes[sel].astype(float)
        rows = np.arange(G)
        while True:
            c = (X * alive[:, :, None]).sum(axis=1) / cnt[:, None]
            dd = ((X - c[:, None, :]) ** 2).sum(axis=2)
            act = cnt > 4
            if not act.any():
                break
            j = np.argmax(np.where(alive, dd, -np.inf), axis=1)
            alive[rows[act], j[act]] = False
            cnt[act] -= 1
        j = np.argmin(np.where(alive, dd, np.inf), axis=1)
        for r, gi in enumerate(sel):
            out[gi] = groups[gi][j[r]]
    return out


_LARGE_GROUP = 256


def _select_node_large(gp: np.ndarray) -> int:
    """:func:`_select_nodes` for one large group ((n, d) points), without the O(n^2) rescans.

    Distances ``d0`` to a reference centroid ``c0`` bound the distances to the current centroid
    ``c`` within ``|c - c0|``, so the farthest point from ``c`` is among the points with
    ``d0 >= max(d0) - 2 |c - c0|``; only those are measured. The reference is renewed when that
    set grows. The result is exact (the centroid is kept as a running sum).
    """
    n = len(gp)
    alive = np.ones(n, dtype=bool)
    total = gp.sum(axis=0)
    cnt = n

    def reference(c):
        pos = np.flatnonzero(alive)
        d0 = np.sqrt(((gp[pos] - c) ** 2).sum(axis=1))
        o = np.argsort(-d0, kind="stable")
        return c.copy(), pos[o], -d0[o]  # -d0 ascending

    c = total / cnt
    c0, order, nd0 = reference(c)
    top = 0
    while cnt > 4:
        while not alive[order[top]]:
            top += 1
        lim = -nd0[top] - 2.0 * np.sqrt(((c - c0) ** 2).sum())
        stop = int(np.searchsorted(nd0, -lim, side="right"))
        cand = order[top:stop]
        cand = np.sort(cand[alive[cand]])
        if len(cand) > max(64, 4 * int(np.sqrt(cnt))):
            c0, order, nd0 = reference(c)
            top = 0
            continue
        dd = ((gp[cand] - c) ** 2).sum(axis=1)
        j = int(cand[int(np.argmax(dd))])
        alive[j] = False
        total = total - gp[j]
        cnt -= 1
        c = total / cnt
    pos = np.flatnonzero(alive)
    dd = ((gp[pos] - c) ** 2).sum(axis=1)
    return int(pos[int(np.argmin(dd))])


def detect_nodes(points: np.ndarray, *, k: int = DEFAULT_K, epsilon: float, tau_s: float,
                 neighbors: np.ndarray | None = None) -> dict[str, Any]:
    """Algorithm 1: candidate nodes, their groups and the node of each group.

    Parameters
    ----------
    points : (N, d) ndarray of float
        The points. Ties are broken by index, so sort the points by coordinates first for a
        result independent of their order (:func:`reconstruct_paper` does).
    k : int
        Neighbours per point for the covariance (eq. 1).
    epsilon : float
        Threshold on the point variation δ (eq. 2): candidates have ``δ > epsilon``.
    tau_s : float
        Grouping distance.
    neighbors : (N, k) ndarray of int, optional
        Precomputed k nearest neighbours.

    Returns
    -------
    dict
        ``"delta"`` (N,) point variation; ``"candidates"`` (c,) indices of the candidates;
        ``"groups"`` list of index arrays; ``"nodes"`` (n,) index of each group's node,
        ascending.
    """
    delta = point_variation(points, k, neighbors=neighbors)
    cand = np.flatnonzero(delta > epsilon)
    groups = _group_candidates(points, cand, tau_s)
    nodes = np.sort(_select_nodes(points, groups))
    return {"delta": delta, "candidates": cand, "groups": groups, "nodes": nodes}


# ---------------------------------------------------------------------------------------------
# Algorithm 2
# ---------------------------------------------------------------------------------------------
class _Lists:
    """Neighbour lists of the available points, at distance ``< tau_s``, sorted by (distance, index).

    Every row starts as a prefix of at most ``K`` nearest neighbours (``base``, padded with -1;
    ``complete`` tells whether the prefix is the whole list). Rows found too short while tracing
    are replaced by their full list (``ov_ptr``/``ov_idx``, row ``ov_row[i]``), so tracing sees
    exactly the full lists while storing only ``K`` neighbours for most points.
    """

    def __init__(self, p: np.ndarray, tau_s: float, K: int = 8):
        self.p = p
        self.tau = tau_s
        n = len(p)
        self.tree = build_tree(p)
        self.ub = float(np.nextafter(tau_s, np.inf))
        kq = int(min(K + 1, n))
        dist, idx = query(self.tree, p, k=kq, distance_upper_bound=self.ub, workers=-1)
        dist = dist.reshape(n, kq)
        idx = idx.reshape(n, kq).astype(np.int64)
        # a row is complete when the query returned fewer than kq points within the bound
        complete = ~np.isfinite(dist[:, -1]) | (kq >= n)
        last = np.where(complete, np.inf, dist[:, -1])
        is_self = idx == np.arange(n)[:, None]
        if is_self[:, 0].all():  # no duplicate points: the point itself comes first
            dist, idx, is_self = dist[:, 1:], idx[:, 1:], is_self[:, 1:]
        bad = is_self | ~(dist < tau_s)
        dist = np.where(bad, np.inf, dist)
        # ties at the end of an incomplete row may have left out an equal point: trim them
        dist = np.where(~complete[:, None] & (dist >= last[:, None]), np.inf, dist)
        # order by (distance, index): the tree orders by distance only, so re-sort the rows
        # that hold equal distances (the removed entries, now inf, also need moving to the end)
        fin = np.isfinite(dist)
        fix = ((dist[:, 1:] == dist[:, :-1]) & fin[:, 1:]).any(axis=1) | (fin[:, 1:] & ~fin[:, :-1]).any(axis=1)
        if fix.any():
            dr, ir = dist[fix], idx[fix]
            order = np.lexsort((ir, dr), axis=-1)
            dist[fix] = np.take_along_axis(dr, order, axis=1)
            idx[fix] = np.take_along_axis(ir, order, axis=1)
        idx[~np.isfinite(dist)] = -1
        self.base = np.ascontiguousarray(idx)
        self.complete = complete
        self.ov_row = np.full(n, -1, dtype=np.int64)
        self._ov_lists: list[np.ndarray] = []
        self.ov_ptr = np.zeros(1, dtype=np.int64)
        self.ov_idx = np.zeros(0, dtype=np.int64)

    def complete_rows(self, rows) -> None:
        """Replace the given rows by their full lists (no-op for rows already full)."""
        rows = np.asarray(rows, dtype=np.int64)
        rows = rows[(self.ov_row[rows] < 0) & ~self.complete[rows]]
        if len(rows) == 0:
            return
        balls = self.tree.query_ball_point(self.p[rows], r=self.ub)
        for r, ball in zip(rows, balls):
            j = np.asarray(ball, dtype=np.int64)
            d = np.sqrt(((self.p[j] - self.p[r]) ** 2).sum(axis=1))
            ok = (d < self.tau) & (j != r)
            j, d = j[ok], d[ok]
            self.ov_row[r] = len(self._ov_lists)
            self._ov_lists.append(j[np.lexsort((j, d))])
        self.ov_ptr = np.zeros(len(self._ov_lists) + 1, dtype=np.int64)
        np.cumsum([len(x) for x in self._ov_lists], out=self.ov_ptr[1:])
        self.ov_idx = np.concatenate(self._ov_lists).astype(np.int64)


def _trace_kernel(p, base, complete, ov_row, ov_ptr, ov_idx, is_node, starts, cos_theta,
                  stamp, stamp0, need, bad):
    """Trace all curves from the nodes ``starts`` (Algorithm 2, lines 1-23).

    ``stamp`` (n,) marks points used in the current pass (``stamp[q] == pass id``), so nothing
    is reset between passes. A pass that runs out of neighbours on a row that is not complete
    sets ``need[row]`` and ``bad[t]`` and goes on speculatively; the caller completes those rows
    and runs the pass again. Returns flat arrays: per curve its pass, start, end, whether it
    ended at a dead end, offsets into the concatenated point sequences, and the sequences.
    """
    n = p.shape[0]
    d = p.shape[1]
    kb = base.shape[1]
    cap = 4 * n + 16
    seq = np.empty(cap, dtype=np.int64)
    ccap = 64
    cpass = np.empty(ccap, dtype=np.int64)
    cstart = np.empty(ccap, dtype=np.int64)
    cend = np.empty(ccap, dtype=np.int64)
    cdead = np.empty(ccap, dtype=np.bool_)
    coff = np.empty(ccap + 1, dtype=np.int64)
    coff[0] = 0
    nc = 0
    ns = 0
    for t in range(starts.shape[0]):
        a = starts[t]
        pid = stamp0 + t
        ra = ov_row[a]
        if ra >= 0:
            na = ov_ptr[ra + 1] - ov_ptr[ra]
        else:
            na = kb
        for jj in range(na):
            if ra >= 0:
                s = ov_idx[ov_ptr[ra] + jj]
            else:
                s = base[a, jj]
                if s < 0:
                    break
            if is_node[s] or stamp[s] == pid:
                continue
            # a new curve: a, s, ...
            if ns + 2 >= cap:
                new = np.empty(2 * cap, dtype=np.int64)
                new[:ns] = seq[:ns]
                seq = new
                cap = 2 * cap
            seq[ns] = a
            seq[ns + 1] = s
            ns += 2
            stamp[s] = pid
            prev = a
            cur = s
            end = -1
            while True:
                nxt = -1
                r = ov_row[cur]
                if r >= 0:
                    m = ov_ptr[r + 1] - ov_ptr[r]
                else:
                    m = kb
                for ii in range(m):
                    if r >= 0:
                        q = ov_idx[ov_ptr[r] + ii]
                    else:
                        q = base[cur, ii]
                        if q < 0:
                            break
                    if stamp[q] == pid or q == prev:
                        continue
                    # interior angle at cur between cur->prev and cur->q (criterion 3)
                    dot = 0.0
                    nb = 0.0
                    nq = 0.0
                    for c in range(d):
                        u = p[prev, c] - p[cur, c]
                        v = p[q, c] - p[cur, c]
                        dot += u * v
                        nb += u * u
                        nq += v * v
                    if nb > 0.0 and nq > 0.0:
                        if dot > cos_theta * np.sqrt(nb * nq):
                            continue
                    nxt = q
                    break
                if nxt < 0:
                    if r < 0 and not complete[cur]:
                        need[cur] = True
                        bad[t] = True
                    end = cur  # dead end: free-end node at cur
                    break
                if ns + 1 >= cap:
                    new = np.empty(2 * cap, dtype=np.int64)
                    new[:ns] = seq[:ns]
                    seq = new
                    cap = 2 * cap
                seq[ns] = nxt
                ns += 1
                if is_node[nxt]:
                    end = nxt
                    break
                stamp[nxt] = pid
                prev = cur
                cur = nxt
            if nc + 1 >= ccap:
                ccap2 = 2 * ccap
                x0 = np.empty(ccap2, dtype=np.int64)
                x0[:nc] = cpass[:nc]
                cpass = x0
                x1 = np.empty(ccap2, dtype=np.int64)
                x1[:nc] = cstart[:nc]
                cstart = x1
                x2 = np.empty(ccap2, dtype=np.int64)
                x2[:nc] = cend[:nc]
                cend = x2
                x3 = np.empty(ccap2, dtype=np.bool_)
                x3[:nc] = cdead[:nc]
                cdead = x3
                x4 = np.empty(ccap2 + 1, dtype=np.int64)
                x4[: nc + 1] = coff[: nc + 1]
                coff = x4
                ccap = ccap2
            cpass[nc] = t
            cstart[nc] = a
            cend[nc] = end
            cdead[nc] = not is_node[end]
            nc += 1
            coff[nc] = ns
    return (cpass[:nc].copy(), cstart[:nc].copy(), cend[:nc].copy(), cdead[:nc].copy(),
            coff[: nc + 1].copy(), seq[:ns].copy())


_COMPILED: dict[str, Any] = {}


#: With ``use_numba=None``, the compiled kernel is used from this many points on (below it,
#: importing numba and loading the compiled kernel costs more than it saves).
NUMBA_MIN_POINTS = 50_000


def _kernel(use_numba: bool | None, n: int = 0):
    """The tracing kernel: numba-compiled when available (and not disabled), else plain Python."""
    if use_numba is False or (use_numba is None and n < NUMBA_MIN_POINTS):
        return _trace_kernel
    if "numba" not in _COMPILED:
        try:
            import numba
        except ImportError:
            _COMPILED["numba"] = None
        else:
            _COMPILED["numba"] = numba.njit(cache=True, nogil=True)(_trace_kernel)
    k = _COMPILED["numba"]
    if k is None:
        if use_numba:
            from ..errors import require

            require("numba", "the compiled tracing kernel", "fast")
        return _trace_kernel
    return k


def _trace(lists: _Lists, is_node: np.ndarray, nodes: np.ndarray, theta: float, use_numba):
    """Algorithm 2, lines 1-23, from every node, then from the free ends found on the way.

    Only dead ends of curves traced from the detected nodes become free-end nodes; a curve
    traced from a free end that reaches a dead end ends at a point that is no node, has no
    twin, and is discarded by the reverse search. Returns the raw curves ``(start, end, seq)``
    in node order (then in order of their starting point) and the list of free-end nodes.
    """
    n = len(lists.p)
    raw_kern = _kernel(use_numba, n)

    def kern(*args):
        with held():  # Ctrl-C waits for the kernel (see curvenet._sigint)
            return raw_kern(*args)

    cos_t = float(np.cos(np.radians(theta)))
    stamp = np.full(n, -1, dtype=np.int64)
    need = np.zeros(n, dtype=np.bool_)
    pid = 0
    raw: list[tuple[int, int, np.ndarray]] = []
    free: list[int] = []
    todo = np.sort(np.asarray(nodes, dtype=np.int64))
    first = True
    while len(todo):
        lists.complete_rows(todo)  # starting points: everything within tau_s of the node
        done: dict[int, list[tuple[int, int, np.ndarray, bool]]] = {}
        pending = todo
        while len(pending):
            bad = np.zeros(len(pending), dtype=np.bool_)
            cp, cs, ce, cd, co, seq = kern(lists.p, lists.base, lists.complete, lists.ov_row,
                                           lists.ov_ptr, lists.ov_idx, is_node, pending, cos_t,
                                           stamp, pid, need, bad)
            pid += len(pending)
            for c in range(len(cs)):
                if not bad[cp[c]]:
                    done.setdefault(int(cs[c]), []).append(
                        (int(cs[c]), int(ce[c]), seq[co[c]:co[c + 1]], bool(cd[c])))
            rows = np.flatnonzero(need)
            need[:] = False
            lists.complete_rows(rows)
            pending = pending[bad]
        new = set()
        for a in todo:
            for s, e, sq, dead in done.get(int(a), []):
                raw.append((s, e, sq))
                if dead and first and not is_node[e]:
                    new.add(e)
        todo = np.array(sorted(new), dtype=np.int64)
        is_node[todo] = True
        free.extend(todo.tolist())
        first = False
    return raw, free


def _merge_twins(curves: list[tuple[int, int, np.ndarray]]):
    """Criterion 4: match each curve ``a -> b`` with its twin ``b -> a`` and merge them.

    ``curves`` holds ``(start, end, seq)`` with ``seq`` the point sequence, node ends included,
    in a deterministic order. Returns the merged list and the number of unmatched curves.
    """
    out: list[tuple[int, int, np.ndarray]] = []
    by_pair: dict[tuple[int, int], tuple[list[int], list[int]]] = {}
    for i, (a, b, _) in enumerate(curves):
        if a == b:
            out.append(curves[i])
            continue
        key = (min(a, b), max(a, b))
        fw, bw = by_pair.setdefault(key, ([], []))
        (fw if a < b else bw).append(i)
    unmatched = 0
    for key in sorted(by_pair):
        fw, bw = by_pair[key]
        cand = []
        for x, i in enumerate(fw):
            si = curves[i][2][1:-1]
            for y, j in enumerate(bw):
                sj = curves[j][2][1:-1]
                ov = int(np.intersect1d(si, sj, assume_unique=True).size)
                if ov > 0:
                    cand.append((-ov, x, y))
        cand.sort()
        used_f, used_b = set(), set()
        for _, x, y in cand:
            if x in used_f or y in used_b:
                continue
            used_f.add(x)
            used_b.add(y)
            out.append(_splice(curves[fw[x]], curves[bw[y]]))
        unmatched += len(fw) - len(used_f) + len(bw) - len(used_b)
    return out, unmatched


def _splice(f: tuple[int, int, np.ndarray], t: tuple[int, int, np.ndarray]):
    """Merge curve ``f`` (a -> b) with its twin ``t`` (b -> a): ``f`` next to ``a``, ``t`` next to ``b``.

    The splice point is the shared inner point minimising the larger of its relative positions
    in ``f`` (from ``a``) and in ``t`` (from ``b``); ties go to the smallest point index.
    """
    a, b, fs = f
    ts = t[2]
    m, n = len(fs) - 1, len(ts) - 1
    v, i, j = np.intersect1d(fs[1:-1], ts[1:-1], assume_unique=True, return_indices=True)
    i += 1
    j += 1
    best = np.lexsort((v, np.maximum(i / m, j / n)))[0]
    seq = np.concatenate([fs[: i[best]], ts[j[best]::-1]])
    return (a, b, seq)


def _default_tau_s(h: float, k: int) -> float:
    return float(DEFAULT_TAU_FACTOR * k * h)


def _check_params(k, epsilon, tau_s, theta):
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 2:
        raise InputError(f"k must be an integer >= 2, got {k!r}")
    for name, v in (("epsilon", epsilon), ("tau_s", tau_s), ("theta", theta)):
        if v is None and name in ("epsilon", "tau_s"):
            continue
        try:
            fv = float(v)
        except (TypeError, ValueError):
            raise InputError(f"{name} must be a number, got {v!r}") from None
        if not np.isfinite(fv):
            raise InputError(f"{name} must be finite, got {v!r}")
    if epsilon is not None and not (0.0 <= float(epsilon) < 1.0):
        raise InputError(f"epsilon must be in [0, 1), got {epsilon!r}")
    if tau_s is not None and not float(tau_s) > 0:
        raise InputError(f"tau_s must be > 0, got {tau_s!r}")
    if not 0.0 <= float(theta) <= 180.0:
        raise InputError(f"theta must be an angle in degrees in [0, 180], got {theta!r}")


def reconstruct_paper(
    points,
    *,
    k: int = DEFAULT_K,
    epsilon: float | None = None,
    tau_s: float | None = None,
    theta: float = 120.0,
    use_numba: bool | None = None,
    on_stage: OnStage | None = None,
    **unknown: Any,
) -> CurveNetwork:
    """Reconstruct a curve network with the founding paper's Algorithms 1 and 2.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
        Points sampled along the curves, in any order.
    k : int
        Nearest neighbours for the covariance of equation (1). The paper gives no value;
        default :data:`DEFAULT_K` (6, chosen by the study in docs/paper-defaults.md).
    epsilon : float, optional
        Threshold ε on the point variation δ of equation (2); candidates have ``δ > ε``.
        Default :data:`DEFAULT_EPSILON` for the dimension (1e-3 in 3D, 2e-2 in 2D).
    tau_s : float, optional
        The paper's τ_S, in the units of the points: candidates closer than it are grouped,
        curves start from the points closer than it to a node, and (our addition) no step of a
        curve is longer. Default ``k * h`` with ``h`` the median nearest-neighbour spacing.
    theta : float
        The paper's θ in degrees: the interior angle at each inner point of a curve (180 for a
        straight continuation) must be at least ``theta``. The paper uses 100 to 150.
    use_numba : bool, optional
        Run the tracing kernel compiled with numba (True; needs the ``fast`` extra), as plain
        Python (False), or (None, the default) compiled when numba is installed and there are
        at least :data:`NUMBA_MIN_POINTS` points. Both give the same result.
    on_stage : callable, optional
        ``on_stage(name, share)``, called as each stage begins with its name (a key of
        ``stats["time"]``) and its share of the work (:data:`curvenet.methods.stages.PAPER_SHARES`),
        e.g. for a progress display.

    Returns
    -------
    CurveNetwork
        Nodes (input points: detected nodes, then free ends) and curves whose first and last
        points are their nodes' positions, with the input index of every point.
        ``parameters`` holds ``k``, ``epsilon``, ``tau_s`` and ``theta`` as used; ``stats`` holds
        ``time`` (seconds for ``neighbors``, ``nodes``, ``tracing``, ``merging``), the spacing
        ``h``, and the counts ``candidates``, ``groups``, ``free_ends`` and ``unmatched``.

    Raises
    ------
    InputError
        For invalid points or parameters, or an unknown parameter name.

    Notes
    -----
    See the module documentation for how each ambiguous step of the paper is read. Cost:
    one k-nearest-neighbour query, batched 2x2/3x3 eigenvalues, one radius-list construction
    over the non-candidate points, and tracing that visits every point about twice (once from
    each end of its curve), i.e. O(N log N) for curve-like data.

    Examples
    --------
    >>> import numpy as np
    >>> t = (np.arange(40) + 0.5) / 40
    >>> arms = [np.c_[t, 0 * t], np.c_[-t, 0 * t], np.c_[0 * t, t]]
    >>> net = reconstruct_paper(np.vstack(arms + [[[0.0, 0.0]]]))
    >>> net.n_nodes, net.n_curves
    (4, 3)
    """
    if unknown:
        raise InputError(
            f"unknown parameter(s) for method 'paper': {', '.join(sorted(unknown))}; "
            "expected k, epsilon, tau_s, theta"
        )
    _check_params(k, epsilon, tau_s, theta)
    pts_in = as_points(points)
    n, dim = pts_in.shape
    k = int(k)
    times: dict[str, float] = {}

    # canonical order: every tie broken by index below is then broken by coordinates
    report_stage(on_stage, PAPER_SHARES, "neighbors")
    t0 = time.perf_counter()
    order = np.lexsort(pts_in.T[::-1])
    p = np.ascontiguousarray(pts_in[order])
    dist, nbr = knn(p, k)
    nn = dist[:, 0] if dist.shape[1] else np.zeros(0)
    pos = nn[nn > 0]
    h = float(np.median(pos)) if len(pos) else 0.0
    eps = float(DEFAULT_EPSILON[dim] if epsilon is None else epsilon)
    tau = float(_default_tau_s(h, k) if tau_s is None else tau_s)
    times["neighbors"] = time.perf_counter() - t0

    params = {"k": k, "epsilon": eps, "tau_s": tau, "theta": float(theta)}
    stats: dict[str, Any] = {"h": h, "time": times}
    if tau <= 0 or n < 2:
        stats.update(candidates=0, groups=0, free_ends=0, unmatched=0)
        return CurveNetwork(np.zeros((0, dim)), [], params, stats)

    # Algorithm 1
    report_stage(on_stage, PAPER_SHARES, "nodes")
    t0 = time.perf_counter()
    det = detect_nodes(p, k=k, epsilon=eps, tau_s=tau, neighbors=nbr)
    nodes = det["nodes"]
    times["nodes"] = time.perf_counter() - t0

    # Algorithm 2, lines 1-23: trace from every node on the points minus the other candidates
    report_stage(on_stage, PAPER_SHARES, "tracing")
    t0 = time.perf_counter()
    keep = np.ones(n, dtype=bool)
    keep[det["candidates"]] = False
    keep[nodes] = True
    sub = np.flatnonzero(keep)  # ascending: still in coordinate order
    ps = np.ascontiguousarray(p[sub])
    lists = _Lists(ps, tau)
    loc = np.full(n, -1, dtype=np.int64)
    loc[sub] = np.arange(len(sub))
    is_node = np.zeros(len(sub), dtype=np.bool_)
    is_node[loc[nodes]] = True
    raw, free = _trace(lists, is_node, loc[nodes], float(theta), use_numba)
    times["tracing"] = time.perf_counter() - t0

    # Algorithm 2, lines 24-28: reverse search
    report_stage(on_stage, PAPER_SHARES, "merging")
    t0 = time.perf_counter()
    merged, unmatched = _merge_twins(raw)
    node_loc = np.flatnonzero(is_node)  # ascending = coordinate order
    used_nodes = set()
    for a, b, _ in merged:
        used_nodes.add(a)
        used_nodes.add(b)
    free_set = set(free)
    node_loc = np.array([v for v in node_loc if v in used_nodes or v not in free_set], dtype=np.int64)
    node_id = {int(v): i for i, v in enumerate(node_loc)}
    curves = []
    for a, b, seq in sorted(merged, key=lambda c: (node_id[c[0]], node_id[c[1]], c[2].tolist())):
        gi = sub[seq]  # indices in sorted points
        curves.append(Curve(p[gi], node_id[a], node_id[b], False, order[gi]))
    net = CurveNetwork(ps[node_loc].reshape(-1, dim), curves, params, stats)
    times["merging"] = time.perf_counter() - t0
    stats.update(
        candidates=int(len(det["candidates"])),
        groups=int(len(det["groups"])),
        free_ends=int(sum(1 for v in node_loc if int(v) in free_set)),
        unmatched=int(unmatched),
    )
    return net
