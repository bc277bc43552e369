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
from .numbers import group_texts
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
    lengths = curve_lengths(net.curves)
    if not np.isfinite(lengths).all():
        return _geojson_slow(net, lines)  # json refuses them (as before)
    # the text json.dumps writes for the document, with the coordinates written apart in bulk
    out = ['{"type": "FeatureCollection", "features": [']
    sep = ""
    for i, (c, coords, length) in enumerate(zip(net.curves, _positions(lines), lengths.tolist())):
        start = "null" if c.start is None else int(c.start)
        end = "null" if c.end is None else int(c.end)
        out.append(
            f'{sep}{{"type": "Feature", "id": "curve-{i}", "geometry": {{"type": "LineString", "coordinates": '
            f'{coords}}}, "properties": {{"kind": "curve", "curve": {i}, "start": {start}, "end": {end}, '
            f'"closed": {"true" if c.closed else "false"}, "length": {length!r}}}}}'
        )
        sep = ", "
    for j, (coords, v) in enumerate(zip(_positions([net.nodes], single=True), net.valence.tolist())):
        kind = "junction" if v >= 3 else ("end" if v == 1 else "other")
        out.append(
            f'{sep}{{"type": "Feature", "id": "node-{j}", "geometry": {{"type": "Point", "coordinates": {coords}}}, '
            f'"properties": {{"kind": "node", "node": {j}, "valence": {int(v)}, "node_kind": "{kind}"}}}}'
        )
        sep = ", "
    out.append("]}\n")
    return "".join(out)


def _positions(arrays: list, single: bool = False) -> list[str]:
    """JSON text of the positions of each (m, d) array as ``json`` writes them
    (``[[x, y], [x, y]]``), or with ``single`` of each row of the one array (``[x, y]``)."""
    blocks = [np.asarray(a, dtype=float) for a in arrays]
    full = [b for b in blocks if len(b)]
    if not full:
        return [] if single else ["[]" for _ in blocks]
    P = np.concatenate(full)
    glue = [", "] * (P.shape[1] - 1)
    if single:
        return ["[" + t + "]" for t in group_texts(P, glue + [""], groups=np.arange(len(P) + 1))]
    sizes = np.array([len(b) for b in blocks], dtype=np.int64)
    texts = group_texts(P, glue + ["], ["], groups=np.concatenate([[0], np.cumsum(sizes)]))
    return ["[[" + t + "]]" if k else "[]" for t, k in zip(texts, sizes.tolist())]


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
