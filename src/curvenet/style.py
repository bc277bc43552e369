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
    node_key = [tuple(_rounded(p).tolist()) for p in net.nodes]
    at_node: dict[int, list[int]] = {}
    counts = np.zeros(k, dtype=np.int64)
    out = [0] * net.n_curves
    for i in sorted(range(net.n_curves), key=lambda i: curve_sort_key(net.curves[i])):
        c = net.curves[i]
        ends = [] if c.start is None else sorted({int(c.start), int(c.end)}, key=lambda n: node_key[n])
        taken = {j for n in ends for j in at_node.get(n, ())}
        j = min(range(k), key=lambda i: (i in taken, counts[i], i))
        out[i] = j
        counts[j] += 1
        for n in ends:
            at_node.setdefault(n, []).append(j)
    return [palette[j] for j in out]


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
