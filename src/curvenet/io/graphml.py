"""GraphML writer: nodes with positions, one edge per curve with its polyline (for graph tools).

Written with the standard library; networkx, yEd, Gephi and Cytoscape read it.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from ..network import CurveNetwork
from .numbers import shortest_rows

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
    """
    ET.register_namespace("", _NS)
    root = ET.Element(f"{{{_NS}}}graphml")
    for kid, kfor, name, typ in _KEYS:
        ET.SubElement(root, f"{{{_NS}}}key", {"id": kid, "for": kfor, "attr.name": name, "attr.type": typ})
    g = ET.SubElement(root, f"{{{_NS}}}graph", {"id": "curvenet", "edgedefault": "undirected"})
    _data(g, "dimension", str(net.dimension))

    def add_node(j, pos, valence, kind, anchor):
        el = ET.SubElement(g, f"{{{_NS}}}node", {"id": str(j)})
        xyz = list(pos) + [0.0] * (3 - len(pos))
        for key, val in zip("xyz", xyz):
            _data(el, key, repr(float(val)))
        _data(el, "valence", str(int(valence)))
        _data(el, "kind", kind)
        _data(el, "anchor", "true" if anchor else "false")

    val = net.valence
    for j, p in enumerate(net.nodes):
        v = int(val[j])
        add_node(j, p, v, "junction" if v >= 3 else ("end" if v == 1 else "other"), False)
    anchor = net.n_nodes
    edges = []
    for i, c in enumerate(net.curves):
        if c.start is None:
            first = c.points[0] if len(c.points) else np.zeros(net.dimension)
            add_node(anchor, first, 2, "loop", True)
            s = e = anchor
            anchor += 1
        else:
            s, e = int(c.start), int(c.end)
        edges.append((i, s, e, c))
    for i, s, e, c in edges:  # GraphML lists nodes before edges
        el = ET.SubElement(g, f"{{{_NS}}}edge", {"id": f"c{i}", "source": str(s), "target": str(e)})
        _data(el, "curve", str(i))
        _data(el, "length", repr(float(c.length)))
        _data(el, "closed", "true" if c.closed else "false")
        _data(el, "n_points", str(len(c.points)))
        _data(el, "points", format_polyline(c.points))
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _data(parent, key: str, text: str) -> None:
    ET.SubElement(parent, f"{{{_NS}}}data", {"key": key}).text = text
