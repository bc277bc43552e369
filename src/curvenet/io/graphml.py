"""GraphML writer: nodes with positions, one edge per curve with its polyline (for graph tools).

Written with the standard library; networkx, yEd, Gephi and Cytoscape read it.
"""

from __future__ import annotations

import numpy as np

from ..network import CurveNetwork
from .numbers import group_texts, shortest_rows
from .polylines import curve_lengths

__all__ = ["network_to_graphml", "format_polyline", "parse_polyline"]

_NS = "http://graphml.graphdrawing.org/xmlns"

#: (id, for, attr.name, attr.type)
_KEYS = [
    ("dimension", "graph", "dimension", "int"),
    ("x", "node", "x", "double"),
    ("y", "node", "y", "double"),
    ("z", "node", "z", "double"),
    ("valence", "node", "valence", "int"),
    ("kind", "node", "kind", "string"),
    ("anchor", "node", "anchor", "boolean"),
    ("curve", "edge", "curve", "int"),
    ("length", "edge", "length", "double"),
    ("closed", "edge", "closed", "boolean"),
    ("n_points", "edge", "n_points", "int"),
    ("points", "edge", "points", "string"),
]


def format_polyline(points) -> str:
    """``"x y [z];x y [z];..."``: the points of a polyline as one string (shortest round-trip
    decimals)."""
    return ";".join(shortest_rows(np.asarray(points, dtype=float)))


def parse_polyline(text: str, dimension: int) -> np.ndarray:
    """Inverse of :func:`format_polyline`: an (m, dimension) array."""
    if not text.strip():
        return np.zeros((0, dimension))
    return np.array([[float(x) for x in p.split()] for p in text.split(";")], dtype=float).reshape(-1, dimension)


def network_to_graphml(net: CurveNetwork) -> str:
    """The network as a GraphML document (an undirected multigraph).

    Nodes have ids ``"0" .. "n-1"`` and data ``x``, ``y``, ``z`` (z = 0 in 2D), ``valence``,
    ``kind`` (``junction``, ``end``, ``other``) and ``anchor`` (false). Curve ``i`` is the edge
    ``id="c<i>"`` from its start node to its end node, with data ``curve`` (= i), ``length``,
    ``closed``, ``n_points`` and ``points``: its polyline as ``"x y z;x y z;..."`` (d numbers per
    point, d = the graph's ``dimension``) running from the source to the target node.

    A closed loop without nodes is kept the way :meth:`CurveNetwork.to_networkx` keeps it: on an
    anchor node ``n + j`` at its first point (``kind="loop"``, ``anchor=true``), as a self-loop.

    Returns
    -------
    str
        The text that ``xml.etree.ElementTree`` writes for this document (indented by
        ``ET.indent``), built here directly: tens of thousands of elements cost seconds there.
    """
    d = net.dimension
    val = net.valence
    nodes = []  # (position, valence, kind, anchor)
    for j, p in enumerate(net.nodes):
        v = int(val[j])
        nodes.append((p, v, "junction" if v >= 3 else ("end" if v == 1 else "other"), "false"))
    ends = []
    for c in net.curves:
        if c.start is None:
            first = c.points[0] if len(c.points) else np.zeros(d)
            ends.append((len(nodes), len(nodes)))
            nodes.append((first, 2, "loop", "true"))
        else:
            ends.append((int(c.start), int(c.end)))
    pos = np.zeros((len(nodes), 3))
    if nodes:
        pos[:, :d] = np.array([p for p, _, _, _ in nodes], dtype=float).reshape(len(nodes), d)
    xyz = shortest_rows(pos) if len(pos) else []
    out = ['<?xml version="1.0" encoding="UTF-8"?>\n', f'<graphml xmlns="{_NS}">\n']
    for kid, kfor, name, typ in _KEYS:
        out.append(f'  <key id="{kid}" for="{kfor}" attr.name="{name}" attr.type="{typ}" />\n')
    out.append('  <graph id="curvenet" edgedefault="undirected">\n')
    out.append(f'    <data key="dimension">{d}</data>\n')
    for j, ((_, v, kind, anchor), coords) in enumerate(zip(nodes, xyz)):
        x, y, z = coords.split(" ")
        out.append(
            f'    <node id="{j}">\n      <data key="x">{x}</data>\n      <data key="y">{y}</data>\n'
            f'      <data key="z">{z}</data>\n      <data key="valence">{v}</data>\n'
            f'      <data key="kind">{kind}</data>\n      <data key="anchor">{anchor}</data>\n    </node>\n'
        )
    lengths = curve_lengths(net.curves).tolist()
    for i, (c, (s, e), text) in enumerate(zip(net.curves, ends, _polylines([c.points for c in net.curves]))):
        points = f'<data key="points">{text}</data>' if text else '<data key="points" />'
        out.append(
            f'    <edge id="c{i}" source="{s}" target="{e}">\n      <data key="curve">{i}</data>\n'
            f'      <data key="length">{lengths[i]!r}</data>\n'
            f'      <data key="closed">{"true" if c.closed else "false"}</data>\n'
            f'      <data key="n_points">{len(c.points)}</data>\n      {points}\n    </edge>\n'
        )
    out.append("  </graph>\n</graphml>\n")
    return "".join(out)


def _polylines(arrays) -> list[str]:
    """:func:`format_polyline` of each (m, d) array (all formatted at once)."""
    arrays = [np.asarray(a, dtype=float) for a in arrays]
    full = [a for a in arrays if len(a)]
    if not full:
        return ["" for _ in arrays]
    d = full[0].shape[1]
    sizes = np.array([len(a) for a in arrays], dtype=np.int64)
    return group_texts(np.concatenate(full), [" "] * (d - 1) + [";"], groups=np.concatenate([[0], np.cumsum(sizes)]))
