"""Per-curve values of many curves at once, for the writers (the same floats as one curve at a
time)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..lengths import step_lengths
from ..network import Curve, CurveNetwork

__all__ = ["curve_lengths", "polyline_arrays", "polyline_ids", "inner_counts", "polyline_vertices", "segments",
           "polyline_segments"]


def curve_lengths(curves: Sequence[Curve]) -> np.ndarray:
    """:attr:`Curve.length` of every curve, computed for all curves of one size together.

    Parameters
    ----------
    curves : sequence of Curve

    Returns
    -------
    (c,) ndarray of float
        Bit for bit the value of each curve's ``length`` (the same operations in the same
        order on each curve's points: numpy sums each row of a stack as it sums one array).
    """
    out = np.zeros(len(curves))
    groups: dict[tuple[int, bool, int], list[int]] = {}
    for i, c in enumerate(curves):
        if len(c.points) >= 2:
            groups.setdefault((len(c.points), bool(c.closed), c.points.shape[1]), []).append(i)
    for (m, closed, _), ids in groups.items():
        P = np.stack([curves[i].points for i in ids])
        if closed:
            P = np.concatenate([P, P[:, :1]], axis=1)
        out[ids] = step_lengths(np.diff(P, axis=1)).sum(axis=1)
    return out


def polyline_arrays(net: CurveNetwork) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`CurveNetwork.polyline_vertices` as flat arrays, built without a loop over curves.

    Returns
    -------
    vertices : (V, 3) ndarray of float
        Node positions first, then the inner points of each curve (2D networks get z = 0).
    ids : (L,) ndarray of int64
        The vertex indices of all polylines, one after the other.
    offsets : (c + 1,) ndarray of int64
        Polyline ``i`` is ``ids[offsets[i]:offsets[i + 1]]``: the same as polyline ``i`` of
        :meth:`CurveNetwork.polyline_vertices` (a closed loop without node repeats its first
        vertex at the end).
    """
    d = net.dimension
    curves = net.curves
    n = net.n_nodes
    nc = len(curves)
    sizes = np.fromiter((len(c.points) for c in curves), dtype=np.int64, count=nc)
    closed = np.fromiter((bool(c.closed) for c in curves), dtype=bool, count=nc)
    starts = np.fromiter((-1 if c.start is None else int(c.start) for c in curves), dtype=np.int64, count=nc)
    ends = np.fromiter((-1 if c.end is None else int(c.end) for c in curves), dtype=np.int64, count=nc)
    full = [c.points.reshape(-1, d) for c in curves if len(c.points)]
    P = np.concatenate(full) if full else np.zeros((0, d))
    off = np.concatenate([[0], np.cumsum(sizes)])
    keep = np.ones(len(P), dtype=bool)
    has = starts >= 0
    ends_cut = has & (sizes > 0)  # a curve between nodes gives its inner points only
    keep[off[:-1][ends_cut]] = False
    keep[off[1:][ends_cut] - 1] = False
    ids, poff = polyline_ids(sizes, starts, ends, closed, n)
    v = np.vstack([net.nodes.reshape(-1, d), P[keep]])
    if d == 2:
        v = np.column_stack([v, np.zeros(len(v))])
    return v, ids, poff


def inner_counts(sizes: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(c,) how many vertices of its own each curve adds after the nodes (its inner points;
    every point of a loop without node), from its size (c,) and start node (c,) (-1: none)."""
    return np.where(starts >= 0, np.maximum(sizes - 2, 0), sizes)


def polyline_ids(sizes: np.ndarray, starts: np.ndarray, ends: np.ndarray, closed: np.ndarray,
                 n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``ids`` and ``offsets`` of :func:`polyline_arrays` from the curves' shapes alone:
    sizes (c,), start and end nodes (c,) (-1: a loop without node), closedness (c,), and the
    node count ``n`` (vertex ids of the inner points start at ``n``)."""
    nc = len(sizes)
    has = starts >= 0
    n_inner = inner_counts(sizes, starts)
    base = n + np.concatenate([[0], np.cumsum(n_inner)])[:-1]
    plen = np.where(has, n_inner + 2, sizes + (closed & (sizes > 0)))
    poff = np.concatenate([[0], np.cumsum(plen)]).astype(np.int64)
    cur = np.repeat(np.arange(nc), plen)
    k = np.arange(int(poff[-1]), dtype=np.int64) - np.repeat(poff[:-1], plen)
    h = has[cur]
    ids = np.where(h, base[cur] + k - 1, base[cur] + np.where(k < sizes[cur], k, 0))
    ids = np.where(h & (k == 0), starts[cur], ids)
    ids = np.where(h & (k == plen[cur] - 1), ends[cur], ids)
    return ids.astype(np.int64), poff


def polyline_vertices(net: CurveNetwork) -> tuple[np.ndarray, list[np.ndarray]]:
    """:meth:`CurveNetwork.polyline_vertices` (the same arrays), from :func:`polyline_arrays`."""
    v, ids, off = polyline_arrays(net)
    return v, np.split(ids, off[1:-1]) if len(off) > 1 else []


def segments(net: CurveNetwork) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`CurveNetwork.segments` (the same arrays), from :func:`polyline_arrays`."""
    v, ids, off = polyline_arrays(net)
    seg, cid = polyline_segments(ids, off)
    return v, seg, cid


def polyline_segments(ids: np.ndarray, off: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The segments (s, 2) of polylines ``ids`` with ``offsets`` (see :func:`polyline_arrays`),
    and the polyline (s,) of each, in order."""
    plen = np.diff(off)
    cur = np.repeat(np.arange(len(plen)), plen)
    last = np.zeros(len(ids), dtype=bool)
    last[off[1:][plen > 0] - 1] = True
    first = ~last[:-1] if len(ids) else np.zeros(0, dtype=bool)
    if not first.any():
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64)
    seg = np.column_stack([ids[:-1][first], ids[1:][first]]).astype(np.int64)
    return seg, cur[:-1][first].astype(np.int64)
