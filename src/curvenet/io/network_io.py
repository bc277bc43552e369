"""Writers of curve networks (pure functions: network -> bytes or text) and the JSON reader."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..errors import FormatError
from ..network import CurveNetwork, _jsonable
from .points import check_readable

__all__ = ["network_to_json", "network_to_obj", "network_to_ply", "read_network", "polyline_vertices"]


def network_to_json(net: CurveNetwork, *, indent: int | None = None) -> str:
    """The network in the curvenet JSON format (version 1).

    Without ``indent``, written by ``orjson`` when it is installed (``curvenet[fast]``; about
    ten times faster on large networks): the same document, every number reading back to
    the same value, only without spaces after the separators.
    """
    if indent is None:
        text = _json_orjson(net)
        if text is not None:
            return text
    return json.dumps(net.to_dict(), indent=indent, allow_nan=False) + "\n"


def _json_orjson(net: CurveNetwork) -> str | None:
    """:func:`network_to_json` by orjson (the arrays serialised without Python floats), or
    None when orjson is missing or a coordinate is not finite (``json`` raises then)."""
    try:
        import orjson
    except ImportError:
        return None
    arrays = [net.nodes] + [a for c in net.curves for a in (c.points, c.indices)]
    floats = [a.ravel() for a in arrays if a.dtype.kind == "f"]
    if floats and not np.isfinite(np.concatenate(floats)).all():
        return None  # orjson would write null
    doc = {  # the layout of CurveNetwork.to_dict
        "format": "curvenet",
        "version": 1,
        "dimension": net.dimension,
        "nodes": np.ascontiguousarray(net.nodes, dtype=np.float64),
        "curves": [
            {
                "points": np.ascontiguousarray(c.points, dtype=np.float64),
                "start": None if c.start is None else int(c.start),
                "end": None if c.end is None else int(c.end),
                "closed": bool(c.closed),
                "indices": np.ascontiguousarray(c.indices, dtype=np.int64),
            }
            for c in net.curves
        ],
        "parameters": _jsonable(net.parameters),
        "stats": _jsonable(net.stats),
    }
    return orjson.dumps(doc, option=orjson.OPT_SERIALIZE_NUMPY).decode("utf-8") + "\n"


def polyline_vertices(net: CurveNetwork):
    """One vertex list shared by all curves, with node vertices shared by the curves meeting there.

    Returns
    -------
    vertices : (V, 3) ndarray of float
        Node positions first (vertex ``i`` is node ``i``), then the inner points of each curve;
        2D networks get z = 0.
    polylines : list of (m,) ndarray of int
        Vertex indices of each curve in order; a closed curve repeats its first vertex at the end.
    """
    d = net.dimension
    blocks = [net.nodes.reshape(-1, d)]
    polylines = []
    nv = len(net.nodes)
    for c in net.curves:
        pts = c.points
        if c.start is not None:
            inner = pts[1:-1] if len(pts) >= 2 else pts[:0]
            ids = np.concatenate([[c.start], nv + np.arange(len(inner)), [c.end]])
        else:
            inner = pts
            ids = nv + np.arange(len(inner))
            if c.closed and len(ids):
                ids = np.append(ids, ids[0])
        blocks.append(inner)
        nv += len(inner)
        polylines.append(ids.astype(np.int64))
    v = np.vstack(blocks) if blocks else np.zeros((0, d))
    if d == 2:
        v = np.column_stack([v, np.zeros(len(v))])
    return v, polylines


def network_to_obj(net: CurveNetwork) -> str:
    """Wavefront OBJ: ``v`` lines, then one ``l`` polyline per curve (``o curve_<i>``).

    Node vertices come first and are shared by every curve that ends there.
    """
    v, lines = polyline_vertices(net)
    out = [f"# curvenet network: {net.n_nodes} nodes, {net.n_curves} curves", f"# nodes are vertices 1..{net.n_nodes}"]
    out.append("\n".join(f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in v))
    for i, ids in enumerate(lines):
        out.append(f"o curve_{i}")
        out.append("l " + " ".join(str(j + 1) for j in ids))
    return "\n".join(s for s in out if s) + "\n"


def network_to_ply(net: CurveNetwork) -> bytes:
    """Binary little-endian PLY with ``vertex`` (x, y, z, node flag) and ``edge`` (vertex1, vertex2,
    curve id) elements."""
    v, lines = polyline_vertices(net)
    e = [np.column_stack([ids[:-1], ids[1:], np.full(len(ids) - 1, i)]) for i, ids in enumerate(lines) if len(ids) > 1]
    e = np.vstack(e) if e else np.zeros((0, 3), dtype=np.int64)
    vert = np.zeros(len(v), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("node", "u1")])
    vert["x"], vert["y"], vert["z"] = v.T
    vert["node"][: net.n_nodes] = 1
    edge = np.zeros(len(e), dtype=[("vertex1", "<i4"), ("vertex2", "<i4"), ("curve", "<i4")])
    edge["vertex1"], edge["vertex2"], edge["curve"] = e.T
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment curvenet network\n"
        f"element vertex {len(v)}\nproperty double x\nproperty double y\nproperty double z\n"
        "property uchar node\n"
        f"element edge {len(e)}\nproperty int vertex1\nproperty int vertex2\nproperty int curve\n"
        "end_header\n"
    )
    return header.encode("ascii") + vert.tobytes() + edge.tobytes()


def read_network(path) -> CurveNetwork:
    """Read a curve network written in the curvenet JSON format.

    The whole document is checked first against the format (see
    :mod:`curvenet.io.network_schema`, published in ``docs/network-format.md``).

    Raises
    ------
    FormatError
        When the file is not valid JSON or not a curvenet network: a one-line message with the
        file and the JSON path of the first problem.
    """
    from .network_schema import check_network_document

    p = check_readable(path)
    try:
        data = json.loads(Path(p).read_bytes().decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise FormatError(f"{p}: not a valid JSON file (undecodable bytes at offset {exc.start})") from None
    except RecursionError:
        raise FormatError(f"{p}: not a curvenet network (JSON nested too deeply)") from None
    except ValueError as exc:  # JSONDecodeError, and integers longer than Python converts
        msg = re.sub(r";\s*use sys\.set_int_max_str_digits.*$", "", str(exc).splitlines()[0])
        raise FormatError(f"{p}: not a valid JSON file ({msg})") from None
    try:
        check_network_document(data)
        return CurveNetwork.from_dict(data)
    except FormatError as exc:
        raise FormatError(f"{p}: invalid curvenet network {exc}") from None
