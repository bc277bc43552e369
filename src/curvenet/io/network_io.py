"""Writers of curve networks (pure functions: network -> bytes or text) and the JSON reader."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..errors import FormatError
from ..network import CurveNetwork, _jsonable
from .numbers import group_texts, rows_text
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


def polyline_vertices(net: CurveNetwork) -> tuple[np.ndarray, list[np.ndarray]]:
    """One vertex list shared by all curves: :meth:`CurveNetwork.polyline_vertices`.

    Returns
    -------
    vertices : (V, 3) ndarray of float
        Node positions first (vertex ``i`` is node ``i``), then the inner points of each curve;
        2D networks get z = 0.
    polylines : list of (m,) ndarray of int
        Vertex indices of each curve in order; a closed curve repeats its first vertex at the end.
    """
    from .polylines import polyline_vertices as _fast

    return _fast(net)


def network_to_obj(net: CurveNetwork) -> str:
    """Wavefront OBJ: ``v`` lines, then one ``l`` polyline per curve (``g curve_<i>``).

    Node vertices come first and are shared by every curve that ends there (one object whose
    curves meet at their nodes: Blender imports it as one mesh of loose edges, and its "split by
    group" option gives one object per curve); coordinates are
    the shortest decimals that read back to the same floats. Blender, MeshLab and VTK
    (ParaView, PyVista) read the ``l`` lines as edges; trimesh and meshio read OBJ faces only
    and see the vertices alone: give them the ``.ply`` (trimesh, Open3D) or ``.vtu`` (meshio).
    """
    from .polylines import polyline_arrays

    v, ids, off = polyline_arrays(net)
    out = [f"# curvenet network: {net.n_nodes} nodes, {net.n_curves} curves\n# nodes are vertices 1..{net.n_nodes}\n"]
    out.append(rows_text(v, "v "))
    lines = group_texts((ids + 1).reshape(-1, 1), [" "], groups=off) if net.n_curves else []
    out += [f"g curve_{i}\nl {text}\n" for i, text in enumerate(lines)]
    return "".join(out)


def network_to_ply(net: CurveNetwork, *, curve_ids: bool = False) -> bytes:
    """Binary little-endian PLY: ``vertex`` (x, y, z, node flag) and ``edge`` (vertex1, vertex2).

    Vertices are those of :func:`polyline_vertices` (nodes first, flagged ``node = 1``); each
    curve is a run of edges in polyline order, curve after curve. trimesh (as a ``Path3D``),
    Open3D (``read_line_set``), MeshLab and Blender read it as a line set. meshio's PLY reader
    accepts no ``edge`` element: write ``.vtu`` for meshio.

    Parameters
    ----------
    net : CurveNetwork
    curve_ids : bool
        Also give each edge an ``int curve`` property (its curve id). Off by default: trimesh
        refuses edges with a third property ("edges are not (n, 2)").

    Returns
    -------
    bytes
    """
    from .polylines import segments

    v, seg, cid = segments(net)
    vert = np.zeros(len(v), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("node", "u1")])
    vert["x"], vert["y"], vert["z"] = v.T
    vert["node"][: net.n_nodes] = 1
    fields = [("vertex1", "<i4"), ("vertex2", "<i4")] + ([("curve", "<i4")] if curve_ids else [])
    edge = np.zeros(len(seg), dtype=fields)
    edge["vertex1"], edge["vertex2"] = seg.T
    if curve_ids:
        edge["curve"] = cid
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment curvenet network\n"
        f"element vertex {len(v)}\nproperty double x\nproperty double y\nproperty double z\n"
        "property uchar node\n"
        f"element edge {len(seg)}\nproperty int vertex1\nproperty int vertex2\n"
        + ("property int curve\n" if curve_ids else "")
        + "end_header\n"
    )
    return header.encode("ascii") + vert.tobytes() + edge.tobytes()


def read_network(path: str | Path) -> CurveNetwork:
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
