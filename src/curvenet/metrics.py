"""Quality metrics: compare a reconstructed curve network with the ground truth.

Both networks are first *contracted*: every node of valence 2 is removed and its two curves are
joined into one (a loop of valence-2 nodes becomes a closed curve without nodes). So a curve
split at a corner is not an error, while a curve broken by a gap is (the gap leaves two free
ends). Then:

- nodes are matched one-to-one (Hungarian assignment, minimum total distance among the
  matchings of largest size) within ``node_radius * h``;
- a found curve matches a true curve when its end nodes are matched to the true curve's end
  nodes and their symmetric Hausdorff distance is at most ``curve_tol * h``; curves without
  nodes (free loops) match by the Hausdorff distance alone; matching is one-to-one;
- coverage, Chamfer distance and Betti numbers complete the picture.

Every distance given "in units of h" is relative to the sampling spacing ``h`` passed in (see
:func:`curvenet.synth.sample` for what h means for the synthetic data).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from .errors import InputError
from .network import Curve, CurveNetwork

__all__ = ["compare", "contract", "hausdorff", "densify", "distance_to_curves", "deviation"]


# ---------------------------------------------------------------------------------------------
# contraction of valence-2 nodes
# ---------------------------------------------------------------------------------------------
def contract(net: CurveNetwork) -> CurveNetwork:
    """Remove every node of valence 2 by joining its two curves.

    Parameters
    ----------
    net : CurveNetwork
        Any network.

    Returns
    -------
    CurveNetwork
        A new network without valence-2 nodes. Two curves meeting at a valence-2 node become one
        curve (the shared point appears once); a curve that starts and ends at the same
        valence-2 node becomes a closed curve without nodes (``start = end = None``,
        ``closed=True``). Other nodes keep their relative order; ``parameters`` and ``stats``
        are copied. The Betti numbers are unchanged.

    Notes
    -----
    One pass over the nodes: removing a node never changes the valence of another one.
    O(n + c) plus the cost of concatenating polylines.
    """
    n = net.n_nodes
    curves: dict[int, Curve] = {}
    inc: list[list[int]] = [[] for _ in range(n)]
    for cid, c in enumerate(net.curves):
        curves[cid] = Curve(c.points.copy(), c.start, c.end, c.closed, c.indices.copy())
        if c.start is not None:
            inc[c.start].append(cid)
            inc[c.end].append(cid)
    removed = np.zeros(n, dtype=bool)
    for v in range(n):
        if len(inc[v]) != 2:
            continue
        a, b = inc[v]
        if a == b:  # a loop through v and nothing else: a free closed curve
            c = curves[a]
            pts, idx = c.points, c.indices
            if len(pts) > 1 and np.array_equal(pts[0], pts[-1]):
                pts, idx = pts[:-1], idx[:-1]
            curves[a] = Curve(pts, None, None, True, idx)
        else:
            ca, cb = curves[a], curves[b]
            if ca.end != v:
                ca = ca.reversed()
            if cb.start != v:
                cb = cb.reversed()
            if len(ca.points) and len(cb.points) and np.array_equal(ca.points[-1], cb.points[0]):
                pts = np.vstack([ca.points, cb.points[1:]])
                idx = np.concatenate([ca.indices, cb.indices[1:]])
            else:
                pts = np.vstack([ca.points, cb.points])
                idx = np.concatenate([ca.indices, cb.indices])
            curves[a] = Curve(pts, ca.start, cb.end, ca.start == cb.end, idx)
            del curves[b]
            w = cb.end
            inc[w][inc[w].index(b)] = a
        inc[v] = []
        removed[v] = True
    keep = np.flatnonzero(~removed)
    new_id = np.full(n, -1, dtype=np.int64)
    new_id[keep] = np.arange(len(keep))
    out = []
    for cid in sorted(curves):
        c = curves[cid]
        if c.start is not None:
            c = Curve(c.points, int(new_id[c.start]), int(new_id[c.end]), c.closed, c.indices)
        out.append(c)
    return CurveNetwork(net.nodes[keep], out, dict(net.parameters), dict(net.stats))


# ---------------------------------------------------------------------------------------------
# geometry helpers
# ---------------------------------------------------------------------------------------------
def densify(points: np.ndarray, step: float, *, closed: bool = False) -> np.ndarray:
    """Points along a polyline no farther apart than ``step``.

    Parameters
    ----------
    points : (m, d) ndarray
        Polyline vertices.
    step : float
        Largest spacing wanted (> 0).
    closed : bool
        Include the segment from the last vertex back to the first.

    Returns
    -------
    (k, d) ndarray
        The vertices and evenly spaced points inserted in every longer segment.
    """
    p = np.asarray(points, dtype=float)
    if closed and len(p) > 1:
        p = np.vstack([p, p[:1]])
    if len(p) < 2:
        return p.copy()
    seg = np.diff(p, axis=0)
    ln = np.linalg.norm(seg, axis=1)
    k = np.maximum(np.ceil(ln / step).astype(np.int64), 1)
    start = np.repeat(np.arange(len(seg)), k)
    frac = np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)
    t = frac / np.repeat(k, k)
    out = p[start] + seg[start] * t[:, None]
    if closed:
        return out
    return np.vstack([out, p[-1:]])


def distance_to_curves(points: np.ndarray, net: CurveNetwork, *, neighbours: int = 8) -> np.ndarray:
    """Exact distance of each point to the nearest curve of a network (its polyline segments).

    Parameters
    ----------
    points : (k, d) ndarray
    net : CurveNetwork
        Polylines whose segments are short next to the distances measured (the true networks
        of :mod:`curvenet.synth` are sampled every h / 10).
    neighbours : int
        Segments tried per point: those of the nearest segment midpoints (the nearest segment
        is among them when the segments are short next to their distance apart).

    Returns
    -------
    (k,) ndarray of float
        Infinite when the network has no segment.
    """
    from scipy.spatial import cKDTree

    P = np.asarray(points, dtype=float)
    segs = []
    for c in net.curves:
        p = c.points
        if c.closed and len(p) > 1:
            p = np.vstack([p, p[:1]])
        if len(p) >= 2:
            segs.append(np.stack([p[:-1], p[1:]], axis=1))
    if not segs or not len(P):
        return np.full(len(P), np.inf)
    S = np.concatenate(segs)  # (s, 2, d)
    k = min(neighbours, len(S))
    _, j = cKDTree(S.mean(axis=1)).query(P, k=k)
    j = j.reshape(len(P), k)
    a, ab = S[j, 0], S[j, 1] - S[j, 0]  # (k_points, k, d)
    t = np.clip(((P[:, None] - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
    return np.linalg.norm(P[:, None] - (a + t[..., None] * ab), axis=-1).min(axis=1)


def deviation(result: CurveNetwork, truth: CurveNetwork, *, h: float, step: float = 0.1) -> tuple[float, float]:
    """Mean (along arc length) and largest distance of the found curves from the true curves.

    Parameters
    ----------
    result, truth : CurveNetwork
    h : float
        The sampling spacing: the unit of the distances returned.
    step : float
        The found polylines are sampled every ``step * h`` (vertices included).

    Returns
    -------
    mean, max : float
        In units of h; NaN when ``result`` has no curve.
    """
    if not (h > 0 and np.isfinite(h)):
        raise InputError(f"h must be a positive number, got {h!r}")
    pts = [densify(c.points, step * h, closed=c.closed) for c in result.curves if len(c.points)]
    if not pts:
        return float("nan"), float("nan")
    d = distance_to_curves(np.vstack(pts), truth) / h
    return float(d.mean()), float(d.max())


def hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    """Symmetric Hausdorff distance between two point sets ((m, d) and (k, d) arrays)."""
    from scipy.spatial import cKDTree

    if len(a) == 0 or len(b) == 0:
        return float("inf") if len(a) or len(b) else 0.0
    d1 = cKDTree(b).query(a)[0].max()
    d2 = cKDTree(a).query(b)[0].max()
    return float(max(d1, d2))


def _match(cost: np.ndarray, feasible: np.ndarray) -> list[tuple[int, int]]:
    """One-to-one matching of largest size, then least total cost, among feasible pairs."""
    from scipy.optimize import linear_sum_assignment

    if cost.size == 0 or not feasible.any():
        return []
    fc = cost[feasible]
    big = (float(np.abs(fc).sum()) + 1.0) * 4.0
    c = np.where(feasible, cost, big)
    r, k = linear_sum_assignment(c)
    return [(int(i), int(j)) for i, j in zip(r, k) if feasible[i, j]]


def _prf(matched: int, n_found: int, n_true: int) -> tuple[float, float, float]:
    p = matched / n_found if n_found else (1.0 if n_true == 0 else 0.0)
    r = matched / n_true if n_true else (1.0 if n_found == 0 else 0.0)
    f = 2 * p * r / (p + r) if p + r > 0 else 0.0
    return p, r, f


# ---------------------------------------------------------------------------------------------
# comparison
# ---------------------------------------------------------------------------------------------
def compare(
    result: CurveNetwork,
    truth: CurveNetwork,
    *,
    h: float,
    node_radius: float = 3.0,
    curve_tol: float = 2.0,
) -> dict[str, Any]:
    """Score a reconstructed network against the true one.

    Parameters
    ----------
    result : CurveNetwork
        The reconstruction.
    truth : CurveNetwork
        The ground truth (densely sampled true curves).
    h : float
        The sampling spacing; the unit of ``node_radius`` and ``curve_tol``.
    node_radius : float
        Largest distance, in units of h, between a found node and the true node it matches.
    curve_tol : float
        Largest symmetric Hausdorff distance, in units of h, between matching curves; also the
        tolerance of ``coverage``.

    Returns
    -------
    dict
        After contracting valence-2 nodes on both sides (:func:`contract`):

        ``n_nodes_true``, ``n_nodes_found``, ``n_curves_true``, ``n_curves_found``
            Sizes of the contracted graphs.
        ``node_matched``, ``node_precision``, ``node_recall``, ``node_f1``
            One-to-one matching of nodes within ``node_radius * h``: the largest matching,
            and among those the least total distance (Hungarian algorithm).
        ``node_offset``, ``node_offset_h``
            Mean distance between matched nodes (absolute and in h); NaN if none matched.
        ``curve_matched``, ``curve_precision``, ``curve_recall``, ``curve_f1``
            A found curve may match a true curve when (a) both have end nodes and the found
            end nodes are matched to the true end nodes (either orientation), or both have no
            node (free loops); and (b) their symmetric Hausdorff distance is at most
            ``curve_tol * h``. Matching is one-to-one (largest, then least total distance).
        ``coverage``
            Share of the true curves lying entirely within ``curve_tol * h`` of the found
            curves (any of them).
        ``coverage_length``
            Share of the true curves' length within ``curve_tol * h`` of the found curves.
        ``chamfer``, ``chamfer_h``
            Symmetric Chamfer distance: the mean of (mean distance from the true curves to
            the found ones) and (mean distance from the found curves to the true ones), both
            averaged along arc length; absolute and in h. Infinite if one side is empty.
        ``betti_true``, ``betti_found``
            (β0, β1) of both networks.
        ``exact_topology``
            True when every node on both sides is matched, when for every pair of matched
            nodes (a node with itself included) the number of found curves between them equals
            the number of true curves between their partners, and when both have the same
            number of curves without nodes. It compares the graphs only, not the shapes.

    Raises
    ------
    InputError
        If ``h`` is not positive or the two networks have different dimensions.

    Notes
    -----
    Polylines are densified to a spacing of ``h / 4`` before distances are measured, so
    distances are accurate to about ``h / 8``.
    """
    if not (h > 0 and np.isfinite(h)):
        raise InputError(f"h must be a positive number, got {h!r}")
    if result.n_nodes + result.n_curves and truth.n_nodes + truth.n_curves:
        if result.dimension != truth.dimension:
            raise InputError(
                f"networks differ in dimension: result is {result.dimension}D, truth {truth.dimension}D"
            )
    R = contract(result)
    T = contract(truth)
    rad = node_radius * h
    tol = curve_tol * h
    step = h / 4.0
    out: dict[str, Any] = {
        "n_nodes_true": T.n_nodes,
        "n_nodes_found": R.n_nodes,
        "n_curves_true": T.n_curves,
        "n_curves_found": R.n_curves,
    }

    # ---- nodes
    if R.n_nodes and T.n_nodes:
        D = np.linalg.norm(R.nodes[:, None, :] - T.nodes[None, :, :], axis=2)
        pairs = _match(D, D <= rad)
    else:
        D, pairs = np.zeros((R.n_nodes, T.n_nodes)), []
    node_map = {i: j for i, j in pairs}
    p, r, f = _prf(len(pairs), R.n_nodes, T.n_nodes)
    off = float(np.mean([D[i, j] for i, j in pairs])) if pairs else float("nan")
    out.update(
        node_matched=len(pairs),
        node_precision=p,
        node_recall=r,
        node_f1=f,
        node_offset=off,
        node_offset_h=off / h,
    )

    # ---- curves
    dr = [densify(c.points, step, closed=c.closed) for c in R.curves]
    dt = [densify(c.points, step, closed=c.closed) for c in T.curves]

    def key_found(c: Curve):
        if c.start is None:
            return ()
        a, b = node_map.get(c.start), node_map.get(c.end)
        if a is None or b is None:
            return None
        return tuple(sorted((a, b)))

    def key_true(c: Curve):
        return () if c.start is None else tuple(sorted((c.start, c.end)))

    kr = [key_found(c) for c in R.curves]
    kt = [key_true(c) for c in T.curves]
    nr, nt = len(R.curves), len(T.curves)
    cost = np.full((nr, nt), np.inf)
    for i in range(nr):
        if kr[i] is None:
            continue
        for j in range(nt):
            if kr[i] == kt[j]:
                cost[i, j] = hausdorff(dr[i], dt[j])
    cpairs = _match(np.where(np.isfinite(cost), cost, 0.0), cost <= tol)
    p, r, f = _prf(len(cpairs), nr, nt)
    out.update(curve_matched=len(cpairs), curve_precision=p, curve_recall=r, curve_f1=f)

    # ---- coverage and Chamfer
    from scipy.spatial import cKDTree

    all_r = np.vstack(dr) if dr else np.zeros((0, T.dimension))
    all_t = np.vstack(dt) if dt else np.zeros((0, T.dimension))
    if len(all_r) and len(all_t):
        tree_r = cKDTree(all_r)
        covered = [bool(tree_r.query(x)[0].max() <= tol) for x in dt]
        d_t = tree_r.query(all_t)[0]
        d_r = cKDTree(all_t).query(all_r)[0]
        cov_len = float((d_t <= tol).mean())
        cham = 0.5 * (float(d_t.mean()) + float(d_r.mean()))
    else:
        covered = [False] * nt
        cov_len = 0.0 if nt else 1.0
        cham = float("inf") if (len(all_r) or len(all_t)) else 0.0
    out.update(
        coverage=float(np.mean(covered)) if nt else 1.0,
        coverage_length=cov_len,
        chamfer=cham,
        chamfer_h=cham / h,
    )

    # ---- topology
    out["betti_true"] = tuple(T.betti)
    out["betti_found"] = tuple(R.betti)
    exact = len(pairs) == R.n_nodes == T.n_nodes and None not in kr
    if exact:
        exact = Counter(kr) == Counter(kt)
    out["exact_topology"] = bool(exact)
    return out
