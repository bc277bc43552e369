"""The look shared by every drawing of a network: colours of curves, nodes and points.

The PNG pictures (:mod:`curvenet.plots.network_png`), the HTML viewer (:mod:`curvenet.viewer`)
and the SVG and DXF writers (:mod:`curvenet.io`) all take their colours from here, so a network
looks the same in each. The kind of a node (junction, free end, other) is a property of the
network: :attr:`curvenet.network.CurveNetwork.node_kinds`.

This module needs numpy alone and imports nothing of curvenet's I/O, pictures or CLI.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

if TYPE_CHECKING:
    from .network import Curve, CurveNetwork

__all__ = [
    "PALETTE",
    "POINT_COLOR",
    "JUNCTION_COLOR",
    "END_COLOR",
    "OTHER_NODE_COLOR",
    "NODE_COLORS",
    "curve_colors",
    "curve_sort_key",
    "curve_order",
]

#: Curve colours (colour-blind-friendly tab10 without its grey, then darker companions).
PALETTE: tuple[str, ...] = (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#bcbd22",
    "#17becf", "#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173", "#3182bd", "#e6550d",
    "#31a354", "#756bb1",
)  # fmt: skip

#: Input points (drawn faint).
POINT_COLOR = "#9a9a9a"
#: Junctions (nodes of valence 3 or more).
JUNCTION_COLOR = "#e41a1c"
#: Free ends (nodes of valence 1), drawn with a black outline.
END_COLOR = "#ffffff"
#: Other nodes (valence 2 or 0).
OTHER_NODE_COLOR = "#ffd92f"

#: Node kind (:data:`curvenet.network.NODE_KINDS`) -> colour.
NODE_COLORS: dict[str, str] = {"junction": JUNCTION_COLOR, "end": END_COLOR, "other": OTHER_NODE_COLOR}

#: Coordinates are rounded to this many decimals in the keys that order curves and nodes, so
#: the order does not hinge on the last bits of a coordinate.
KEY_DECIMALS = 9


def curve_colors(net: CurveNetwork, *, palette: Sequence[str] = PALETTE) -> list[str]:
    """One colour per curve; curves that share a node get different colours when possible.

    A greedy colouring: curves are visited in an order fixed by their geometry
    (:func:`curve_sort_key`, not their position in ``net.curves``), and each takes the least-used
    palette colour that no already coloured curve at its end nodes has (ties broken by palette
    order). So the same network gets the same colours whatever the order of its curves.

    Parameters
    ----------
    net : CurveNetwork
    palette : sequence of str
        Matplotlib/CSS colours.

    Returns
    -------
    list of str, one per curve
    """
    k = len(palette)
    starts = [-1 if c.start is None else int(c.start) for c in net.curves]
    ends = [s if c.end is None else int(c.end) for c, s in zip(net.curves, starts)]
    taken_at = [0] * (max(starts + ends + [-1]) + 1)  # bit j set: a curve of colour j ends at the node
    counts = [0] * k
    out = [0] * net.n_curves
    least = _LeastUsed(k, counts)
    for i in curve_order(net.curves):
        s, e = starts[i], ends[i]
        taken = taken_at[s] | taken_at[e] if s >= 0 else 0
        j = least(taken) if taken else counts.index(min(counts))
        out[i] = j
        counts[j] += 1
        if s >= 0:
            taken_at[s] |= 1 << j
            taken_at[e] |= 1 << j
    return [palette[j] for j in out]


class _LeastUsed:
    """The colour :func:`curve_colors` gives a curve whose end nodes hold the colours of a bit
    mask: the least used (``counts``, shared with the caller) of the colours not in the mask, the
    first in the palette on a tie; of all colours when the mask holds every one.

    The colours left free by each mask are found once (a network's nodes hold few masks).
    """

    def __init__(self, k: int, counts: list[int]):
        self._every = tuple(range(k))
        self._free: dict[int, tuple[int, ...]] = {}
        self._count = counts.__getitem__

    def __call__(self, taken: int) -> int:
        free = self._free.get(taken)
        if free is None:
            free = tuple(j for j in self._every if not taken >> j & 1) or self._every
            self._free[taken] = free
        return min(free, key=self._count)


def curve_order(curves: Sequence[Curve]) -> list[int]:
    """The indices of ``curves`` sorted by :func:`curve_sort_key` (stable: ties keep their order).

    The keys' leading parts (whether a curve has points, its smallest and largest points in
    lexicographic order, its number of points) are found and compared for all curves at once
    (``ufunc.reduceat``, ``np.lexsort``); only runs of curves equal in all of them are sorted by
    the whole key.

    Parameters
    ----------
    curves : sequence of Curve

    Returns
    -------
    list of int
    """
    n = len(curves)
    pts = [c.points for c in curves]
    sizes = np.fromiter(map(len, pts), dtype=np.int64, count=n)
    full = [p for p in pts if len(p)]
    try:  # (raises on points of different shapes: no check of each curve's shape)
        P = np.concatenate(full) if full else None
    except ValueError:
        P = None
    if P is None or P.ndim != 2:
        return sorted(range(n), key=lambda i: curve_sort_key(curves[i]))
    P = _rounded(P.astype(float, copy=False)) + 0.0
    if not np.isfinite(P).all():  # (tuples holding nan compare as Python does, not as numpy)
        return sorted(range(n), key=lambda i: curve_sort_key(curves[i]))
    has = sizes > 0
    starts = np.concatenate([[0], np.cumsum(sizes[has])])[:-1]
    lo = np.zeros((n, P.shape[1]))
    hi = np.zeros((n, P.shape[1]))
    lo[has] = _lexicographic_extreme(P, np.repeat(np.arange(len(starts)), sizes[has]), starts, np.minimum)
    hi[has] = _lexicographic_extreme(P, np.repeat(np.arange(len(starts)), sizes[has]), starts, np.maximum)
    keys = [has] + list(lo.T) + list(hi.T) + [sizes]
    order = np.lexsort(tuple(keys[::-1]))
    K = np.column_stack(keys)[order]
    same = (K[1:] == K[:-1]).all(axis=1)  # equal leading parts: the whole key decides
    out = order.tolist()
    starts = np.flatnonzero(np.diff(np.concatenate([[0], same.astype(np.int8), [0]])) == 1)
    stops = np.flatnonzero(np.diff(np.concatenate([[0], same.astype(np.int8), [0]])) == -1) + 1
    for a, b in zip(starts.tolist(), stops.tolist()):
        run = sorted(out[a:b])  # their order in ``curves``, then the stable sort by the whole key
        out[a:b] = sorted(run, key=lambda i: curve_sort_key(curves[i]))
    return out


def _lexicographic_extreme(P: np.ndarray, cid: np.ndarray, starts: np.ndarray, ufunc) -> np.ndarray:
    """The lexicographically smallest (``np.minimum``) or largest (``np.maximum``) row of each
    run of rows ``P[starts[i]:starts[i + 1]]`` (``cid``: the run of each row), (runs, d):
    column by column among the rows that tie on the columns before."""
    out = np.empty((len(starts), P.shape[1]))
    alive = np.ones(len(P), dtype=bool)
    blank = np.inf if ufunc is np.minimum else -np.inf
    for j in range(P.shape[1]):
        col = np.where(alive, P[:, j], blank)
        out[:, j] = ufunc.reduceat(col, starts)
        alive &= col == out[cid, j]
    return out


def _rounded(a: np.ndarray) -> np.ndarray:
    """``a`` rounded to :data:`KEY_DECIMALS`; values so large that the rounding overflows (over
    about 1e299) are whole numbers already and stay as they are."""
    with np.errstate(over="ignore", invalid="ignore"):
        r = np.round(a, KEY_DECIMALS)
    return np.where(np.isfinite(r), r, a)


def curve_sort_key(c: Curve) -> tuple:
    """A key of a curve that depends neither on its direction nor on its place in the network.

    Parameters
    ----------
    c : Curve
        A curve whose ``points`` are (m, d).

    Returns
    -------
    tuple
        Its lexicographically smallest and largest points, its number of points, then all its
        points sorted (coordinates rounded to :data:`KEY_DECIMALS`).
    """
    p = _rounded(np.asarray(c.points, dtype=float))
    if not len(p):
        return ((), (), 0)
    rows = p[np.lexsort(p.T[::-1])] + 0.0  # sorted points (+ 0.0 turns -0.0 into 0.0)
    return (tuple(rows[0].tolist()), tuple(rows[-1].tolist()), len(p), rows.ravel().tolist())
