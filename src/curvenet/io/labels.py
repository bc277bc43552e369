"""Per-point labels: which curve or node each input point went to, or -1 for noise.

:func:`point_labels` computes them from a network and its input points; :func:`labels_to_csv`
and :func:`labels_to_npy` are the file formats of ``curvenet reconstruct --labels``.
"""

from __future__ import annotations

import io

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from ..lengths import step_lengths
from ..network import CurveNetwork
from .numbers import int_rows_text

__all__ = ["point_labels", "labels_to_csv", "labels_to_npy", "LABEL_REACH"]

#: An input point that no curve passes through is given to the nearest node or curve point
#: within this many sampling spacings (points cut out of a junction region, repeated samples,
#: noise close to a curve); farther points are noise (-1).
LABEL_REACH = 3.0


def point_labels(net: CurveNetwork, points: ArrayLike, *, reach: float | None = None) -> np.ndarray:
    """For each input point, the id of its curve or of its node, or -1.

    A point that a curve passes through (its index is in ``curve.indices``) gets that curve's
    id (the lowest id when several curves share it). Any other point is given to the nearest
    node position or curve point, when it lies within ``reach``: to that node, or to that
    point's curve. The rest is noise. The labels depend on the network and the points only,
    not on the order of the points.

    Parameters
    ----------
    net : CurveNetwork
        The network reconstructed from ``points``.
    points : (N, d) array_like of float
        The input points, in the order the network's ``indices`` refer to.
    reach : float, optional
        Distance in input units; by default :data:`LABEL_REACH` times the network's
        ``parameters["spacing"]`` (or, without one, the median distance between consecutive
        curve points).

    Returns
    -------
    (N, 2) ndarray of int64
        Column 0 the curve id (-1 when none), column 1 the node id (-1 when none); at most one
        of them is not -1; both -1 for noise.

    Raises
    ------
    InputError
        When the points do not fit the network (dimension, or indices beyond them).
    """
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != net.dimension:
        raise InputError(f"labels need the (N, {net.dimension}) input points, got shape {pts.shape}")
    n = len(pts)
    out = np.full((n, 2), -1, dtype=np.int64)
    for i in range(len(net.curves) - 1, -1, -1):  # the lowest curve id wins
        idx = net.curves[i].indices
        idx = idx[idx >= 0]
        if len(idx) and idx.max() >= n:
            raise InputError(f"curve {i} refers to input point {int(idx.max())}, but only {n} points were given")
        out[idx, 0] = i
    free = np.flatnonzero(out[:, 0] < 0)
    feats = [net.nodes] + [c.points for c in net.curves]
    owner_node = np.concatenate([np.arange(net.n_nodes)] + [np.full(len(c.points), -1) for c in net.curves])
    owner_curve = np.concatenate([np.full(net.n_nodes, -1)] + [np.full(len(c.points), i) for i, c in enumerate(net.curves)])
    allf = np.vstack(feats) if sum(len(f) for f in feats) else np.zeros((0, net.dimension))
    if len(free) == 0 or len(allf) == 0:
        return out
    if reach is None:
        reach = LABEL_REACH * _spacing(net)
    dist, k = cKDTree(allf).query(pts[free])
    near = dist <= reach
    out[free[near], 0] = owner_curve[k[near]]
    out[free[near], 1] = owner_node[k[near]]
    return out


def _spacing(net: CurveNetwork) -> float:
    """The network's sampling spacing: its ``spacing`` parameter, or the median curve step."""
    h = net.parameters.get("spacing")
    if isinstance(h, (int, float)) and not isinstance(h, bool) and np.isfinite(h) and h > 0:
        return float(h)
    parts = [step_lengths(np.diff(c.points, axis=0)) for c in net.curves if len(c.points) > 1]
    steps = np.concatenate(parts) if parts else np.zeros(0)
    steps = steps[steps > 0]
    return float(np.median(steps)) if len(steps) else 0.0


def labels_to_csv(labels: np.ndarray) -> str:
    """CSV text with header ``point,curve,node``: one row per input point, in input order."""
    lab = np.asarray(labels, dtype=np.int64).reshape(-1, 2)
    return "point,curve,node\n" + int_rows_text(np.column_stack([np.arange(len(lab)), lab]), ",")


def labels_to_npy(labels: np.ndarray) -> bytes:
    """The (N, 2) int64 array (curve id, node id) as the bytes of a ``.npy`` file."""
    buf = io.BytesIO()
    np.save(buf, np.asarray(labels, dtype=np.int64).reshape(-1, 2), allow_pickle=False)
    return buf.getvalue()
