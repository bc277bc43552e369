"""GeoJSON writer (RFC 7946): curves as LineStrings, nodes as Points, for GIS tools.

For networks in a plane: roads, cracks, rivers, vessels in a slice. QGIS, GDAL/OGR
(``ogr2ogr``), geopandas and shapely read it. Coordinates are written as given (no
reprojection): in GIS terms, the file's coordinates are the input's ``x, y`` (and ``z`` for a
3D network, GeoJSON's optional third position value).
"""

from __future__ import annotations

import json

import numpy as np

from ..network import CurveNetwork
from .numbers import shortest_rows
from .polylines import curve_lengths

__all__ = ["network_to_geojson"]


def network_to_geojson(net: CurveNetwork) -> str:
    """The network as a GeoJSON ``FeatureCollection``.

    One ``LineString`` feature per curve (in curve order; a closed loop ends where it starts),
    with properties ``kind="curve"``, ``curve`` (its id), ``start`` and ``end`` (node ids,
    null for a loop without node), ``closed`` and ``length``; then one ``Point`` feature per
    node with ``kind="node"``, ``node`` (its id), ``valence`` and ``node_kind`` (``junction``,
    ``end`` or ``other``). Every feature has an ``id`` (``curve-<i>`` or ``node-<j>``).

    Parameters
    ----------
    net : CurveNetwork
        A 2D network (the usual case) or a 3D one (positions get a third value).

    Returns
    -------
    str
        The JSON text; numbers are the shortest decimals that read back to the same floats.
    """
    lines = []
    for c in net.curves:
        pts = np.asarray(c.points, dtype=float)
        if c.closed and len(pts) and c.start is None:
            pts = np.vstack([pts, pts[:1]])
        if len(pts) == 1:  # a LineString needs two positions
            pts = np.vstack([pts, pts])
        lines.append(pts)
    flat = [p.ravel() for p in lines if len(p)] + [np.asarray(net.nodes, dtype=float).ravel()]
    if not np.isfinite(np.concatenate(flat)).all():
        return _geojson_slow(net, lines)  # json refuses them (as before)
    lengths = curve_lengths(net.curves).tolist()
    features = []
    for i, c in enumerate(net.curves):
        features.append({
            "type": "Feature",
            "id": f"curve-{i}",
            "geometry": {"type": "LineString", "coordinates": _HOLE},
            "properties": {
                "kind": "curve",
                "curve": i,
                "start": None if c.start is None else int(c.start),
                "end": None if c.end is None else int(c.end),
                "closed": bool(c.closed),
                "length": lengths[i],
            },
        })
    features += _node_features(net, [_HOLE] * net.n_nodes)
    doc = {"type": "FeatureCollection", "features": features}
    parts = json.dumps(doc, allow_nan=False).split(json.dumps(_HOLE))
    coords = _positions(lines) + _positions([net.nodes], single=True)
    out = [parts[0]]
    for text, part in zip(coords, parts[1:]):
        out += [text, part]
    return "".join(out) + "\n"


#: Stands in for the coordinates in the document given to ``json`` (they are written apart).
_HOLE = "@coordinates@"


def _positions(arrays: list, single: bool = False) -> list[str]:
    """JSON text of the positions of each (m, d) array as ``json`` writes them
    (``[[x, y], [x, y]]``), or with ``single`` of each row of the one array (``[x, y]``)."""
    blocks = [np.asarray(a, dtype=float) for a in arrays]
    full = [b for b in blocks if len(b)]
    rows = shortest_rows(np.concatenate(full), "[", ", ") if full else []
    if single:
        return [r + "]" for r in rows]
    out = []
    pos = 0
    for b in blocks:
        k = len(b)
        out.append("[" + "], ".join(rows[pos:pos + k]) + "]]" if k else "[]")
        pos += k
    return out


def _node_features(net: CurveNetwork, coordinates: list) -> list[dict]:
    val = net.valence
    out = []
    for j in range(net.n_nodes):
        v = int(val[j])
        out.append({
            "type": "Feature",
            "id": f"node-{j}",
            "geometry": {"type": "Point", "coordinates": coordinates[j]},
            "properties": {
                "kind": "node",
                "node": j,
                "valence": v,
                "node_kind": "junction" if v >= 3 else ("end" if v == 1 else "other"),
            },
        })
    return out


def _geojson_slow(net: CurveNetwork, lines: list[np.ndarray]) -> str:
    """The document through ``json`` alone (raises on a value that is not finite)."""
    features = []
    for i, (c, pts) in enumerate(zip(net.curves, lines)):
        features.append({
            "type": "Feature",
            "id": f"curve-{i}",
            "geometry": {"type": "LineString", "coordinates": pts.tolist()},
            "properties": {
                "kind": "curve",
                "curve": i,
                "start": None if c.start is None else int(c.start),
                "end": None if c.end is None else int(c.end),
                "closed": bool(c.closed),
                "length": float(c.length),
            },
        })
    features += _node_features(net, [np.asarray(p, dtype=float).tolist() for p in net.nodes])
    doc = {"type": "FeatureCollection", "features": features}
    return json.dumps(doc, allow_nan=False) + "\n"
