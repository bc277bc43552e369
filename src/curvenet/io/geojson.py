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
    features = []
    for i, c in enumerate(net.curves):
        pts = np.asarray(c.points, dtype=float)
        if c.closed and len(pts) and c.start is None:
            pts = np.vstack([pts, pts[:1]])
        if len(pts) == 1:  # a LineString needs two positions
            pts = np.vstack([pts, pts])
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
    val = net.valence
    for j, p in enumerate(net.nodes):
        v = int(val[j])
        features.append({
            "type": "Feature",
            "id": f"node-{j}",
            "geometry": {"type": "Point", "coordinates": np.asarray(p, dtype=float).tolist()},
            "properties": {
                "kind": "node",
                "node": j,
                "valence": v,
                "node_kind": "junction" if v >= 3 else ("end" if v == 1 else "other"),
            },
        })
    doc = {"type": "FeatureCollection", "features": features}
    return json.dumps(doc, allow_nan=False) + "\n"
