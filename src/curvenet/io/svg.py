"""SVG writer: a 2D network, or a projection of a 3D network, as a vector drawing."""

from __future__ import annotations

from typing import Literal
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import InputError
from ..network import CurveNetwork
from ..style import NODE_COLORS, curve_colors
from .numbers import g_table_bytes

__all__ = ["network_to_svg", "PROJECTIONS", "VIEWS", "project"]

#: Projections of 3D networks onto the drawing plane: (u, v) coordinates from (x, y, z).
PROJECTIONS = ("xy", "xz", "yz", "iso")

#: View names of the command line (``--view``) and the projection each one is.
VIEWS = {"top": "xy", "front": "xz", "side": "yz", "iso": "iso"}

#: Significant digits of the coordinates (``%.9g``: a hundredth of a micrometre on a 10 m drawing).
SVG_DIGITS = 9

#: Unit vectors of the isometric drawing plane: u along (1, -1, 0), v along (-1, -1, 2); the
#: view looks down the diagonal (1, 1, 1), so the three axes are drawn equally foreshortened
#: (by sqrt(2/3)) at 120 degrees from each other.
_ISO_U = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
_ISO_V = np.array([-1.0, -1.0, 2.0]) / np.sqrt(6.0)


def project(points, projection: str = "xy") -> np.ndarray:
    """Project (m, 2|3) points to (m, 2) drawing coordinates.

    ``"xy"`` (``"top"``), ``"xz"`` (``"front"``), ``"yz"`` (``"side"``) keep two coordinates;
    ``"iso"`` is the true isometric projection, orthographic along the diagonal (1, 1, 1):
    ``u = (x - y) / sqrt 2``, ``v = (2 z - x - y) / sqrt 6`` (x to the lower right, y to the
    lower left, z up), which keeps the lengths of segments parallel to the drawing plane.
    A 2D network accepts only ``"xy"`` (``"top"``).
    """
    p = np.asarray(points, dtype=float)
    projection = VIEWS.get(projection, projection)
    if projection not in PROJECTIONS:
        raise InputError(
            f"unknown SVG view (projection) {projection!r}; expected one of: {', '.join(VIEWS)} (or {', '.join(PROJECTIONS[:3])})"
        )
    if p.shape[-1] == 2:
        if projection != "xy":
            raise InputError(f"a 2D network can only be drawn with projection 'xy', got {projection!r}")
        return p.reshape(-1, 2)
    p = p.reshape(-1, 3)
    x, y, z = p.T
    if projection == "xy":
        return np.column_stack([x, y])
    if projection == "xz":
        return np.column_stack([x, z])
    if projection == "yz":
        return np.column_stack([y, z])
    return np.column_stack([p @ _ISO_U, p @ _ISO_V])


def network_to_svg(
    net: CurveNetwork,
    *,
    projection: Literal["xy", "xz", "yz", "iso", "top", "front", "side"] = "xy",
    width: int = 800,
    nodes: bool = True,
) -> str:
    """The network as an SVG drawing.

    Coordinates stay in input units (the ``viewBox`` frames the network; ``v`` is negated
    because SVG's y axis points down), so a drawing program imports the true scale. Each curve
    is a ``<polyline>`` (``<polygon>`` for a closed loop) with ``id="curve-<i>"``,
    ``data-start``/``data-end`` node ids and a ``<title>`` tooltip; each node a ``<circle>``
    with ``id="node-<j>"`` and ``class`` ``junction``, ``end`` or ``other``.

    Parameters
    ----------
    net : CurveNetwork
    projection : {"xy", "xz", "yz", "iso", "top", "front", "side"}
        How to draw a 3D network (see :func:`project`; ``top``, ``front`` and ``side`` are
        ``xy``, ``xz`` and ``yz``); 2D networks use ``"xy"``.
    width : int
        Width in pixels of the drawing; the height follows the aspect ratio.
    nodes : bool
        Draw the nodes.

    Returns
    -------
    str
    """
    if not isinstance(width, (int, np.integer)) or width <= 0:
        raise InputError(f"SVG width must be a positive integer, got {width!r}")
    d = net.dimension
    projection = VIEWS.get(projection, projection)
    curves_uv, sizes = _project_curves(net, projection)
    nodes_uv = project(net.nodes, projection) if len(net.nodes) else np.zeros((0, 2))
    allp = np.vstack([nodes_uv, curves_uv])
    if len(allp) == 0:
        allp = np.zeros((1, 2))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = hi - lo
    big = float(span.max()) or 1.0
    pad = 0.03 * big
    span = np.maximum(span, 1e-3 * big)
    vb = (lo[0] - pad, -(lo[1] + span[1]) - pad, span[0] + 2 * pad, span[1] + 2 * pad)
    height = max(1, int(round(width * (vb[3] / vb[2]))))  # (the ratio first: no overflow near 1e308)
    sw = 0.004 * big
    r = 0.008 * big

    def num(v: float) -> str:
        return f"{v:.{SVG_DIGITS}g}"

    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="{" ".join(num(v) for v in vb)}" data-projection="{projection}" data-dimension="{d}">',
        f"<title>curvenet network: {net.n_nodes} nodes, {net.n_curves} curves</title>",
        f'<g id="curves" fill="none" stroke-width="{num(sw)}" stroke-linecap="round" stroke-linejoin="round">',
    ]
    if net.n_curves:
        out.append(_curve_elements(net, curve_colors(net), _point_lists(curves_uv, sizes)))
    out.append("</g>")
    if nodes and len(nodes_uv):
        out.append(f'<g id="nodes" stroke="black" stroke-width="{num(sw / 2)}">')
        out.append(_node_elements(net, nodes_uv, num(r)))
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


#: The element of a curve between nodes and of a free loop (``%`` formats: tag, id, colour,
#: [start, end,] points, id, [start, end,] tag). The titles hold no character to escape
#: (digits and fixed words).
_CURVE = ('<%s id="curve-%d" class="curve" stroke="%s" data-start="%d" data-end="%d" points="%s">'
          "<title>curve %d: nodes %s-%s</title></%s>")
_FREE_CURVE = '<%s id="curve-%d" class="curve" stroke="%s" points="%s"><title>curve %d: free loop</title></%s>'

#: The element of a node (``%`` format: id, class, cx, cy, radius, fill, id, valence).
_NODE = ('<circle id="node-%d" class=%s cx="%s" cy="%s" r="%s" fill="%s"><title>node %d, valence %d</title>'
         "</circle>")


def _curve_elements(net: CurveNetwork, colors: list[str], points: list[str]) -> str:
    """The elements of all curves, one a line (:data:`_CURVE`, :data:`_FREE_CURVE`), written by
    one ``%`` (the text made once, without a string per curve joined after)."""
    fmts, args = [], []
    for i, (c, color, pts) in enumerate(zip(net.curves, colors, points)):
        tag = "polygon" if c.closed else "polyline"
        if c.start is None:
            fmts.append(_FREE_CURVE)
            args += (tag, i, color, pts, i, tag)
        else:
            fmts.append(_CURVE)
            args += (tag, i, color, int(c.start), int(c.end), pts, i, c.start, c.end, tag)
    return "\n".join(fmts) % tuple(args)


def _node_elements(net: CurveNetwork, nodes_uv: np.ndarray, radius: str) -> str:
    """The elements of all nodes at drawing coordinates ``nodes_uv`` (n, 2), one a line
    (:data:`_NODE`), their coordinates as ``%.9g`` in bulk (:func:`g_table_bytes`)."""
    kinds = net.node_kinds.tolist()
    val = net.valence.tolist()
    attr = {k: quoteattr(k) for k in set(kinds)}
    uv = g_table_bytes(np.column_stack([nodes_uv[:, 0], 0.0 - nodes_uv[:, 1]]), SVG_DIGITS, [" ", " "])
    coords = uv.decode("ascii").split(" ")  # u, v of each node (no number's text holds a space)
    args: list = []
    for j, k in enumerate(kinds):
        args += (j, attr[k], coords[2 * j], coords[2 * j + 1], radius, NODE_COLORS[k], j, val[j])
    return "\n".join([_NODE] * len(kinds)) % tuple(args)


def _point_lists(uv: np.ndarray, sizes: np.ndarray) -> list[str]:
    """The ``points`` attribute of each curve (``sizes`` points each, their (u, v) the rows of
    ``uv`` curve after curve): ``u,-v`` pairs with :data:`SVG_DIGITS` significant digits (as
    ``f"{u:.9g},{0.0 - v:.9g}"``), joined by spaces; all pairs formatted in one bulk call
    (:func:`curvenet.io.numbers.g_table_bytes`, the text of ``%`` to the byte), with a line end
    after each curve's last pair, which splits the text into the curves'."""
    if not len(uv):
        return ["" for _ in sizes]
    buf = bytearray(g_table_bytes(np.column_stack([uv[:, 0], 0.0 - uv[:, 1]]), SVG_DIGITS, [",", " "]))
    chars = np.frombuffer(buf, dtype=np.uint8)
    spaces = np.flatnonzero(chars == ord(" "))  # one after each pair (no number's text holds one)
    chars[spaces[np.cumsum(sizes[sizes > 0]) - 1]] = ord("\n")  # after each curve's last pair
    texts = iter(buf.decode("ascii").split("\n"))
    return [next(texts) if k else "" for k in sizes.tolist()]


def _project_curves(net: CurveNetwork, projection: str) -> tuple[np.ndarray, np.ndarray]:
    """:func:`project` of the points of all curves, (N, 2) curve after curve, and the number of
    points of each curve; the projections that keep coordinates (all but ``iso``) of all curves
    at once."""
    sizes = np.fromiter((len(c.points) for c in net.curves), dtype=np.int64, count=net.n_curves)
    full = [c.points for c in net.curves if len(c.points)]
    if not full:
        return np.zeros((0, 2)), sizes
    if projection == "iso" or any(p.shape[1] != full[0].shape[1] for p in full):
        return np.concatenate([project(p, projection) for p in full]), sizes
    return project(np.concatenate(full), projection), sizes
