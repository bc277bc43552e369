"""VTK XML PolyData writer (``.vtp``): curves as polylines and nodes as vertices, for ParaView.

No VTK installation is needed to write; the file follows the VTK XML format (version 1.0,
little-endian, ``UInt64`` headers), with data inline as ASCII or base64.
"""

from __future__ import annotations

import base64
from typing import Literal

import numpy as np

from ..errors import InputError
from ..network import CurveNetwork
from .network_io import polyline_vertices
from .numbers import ints_text, shortest

__all__ = ["network_to_vtp"]

_VTK_TYPES = {
    np.dtype("<f8"): "Float64",
    np.dtype("<i8"): "Int64",
    np.dtype("<i4"): "Int32",
    np.dtype("u1"): "UInt8",
}


def network_to_vtp(net: CurveNetwork, *, encoding: Literal["ascii", "base64"] = "ascii") -> str:
    """The network as VTK XML PolyData.

    Points are the node positions (point ``j`` is node ``j``) followed by the inner points of
    the curves (as in :func:`curvenet.io.network_io.polyline_vertices`; 2D networks get z = 0).
    Cells are one vertex per node (``Verts``), then one polyline per curve (``Lines``; a closed
    loop repeats its first point).

    Data arrays: point data ``node_id`` (node index, -1 elsewhere) and ``valence`` (0 off
    nodes); cell data ``curve_id`` (-1 for node vertices), ``node_id`` (-1 for curves) and
    ``closed`` (1 for closed loops).

    Parameters
    ----------
    net : CurveNetwork
    encoding : {"ascii", "base64"}
        Inline data as text or as base64 binary (smaller, exact).

    Returns
    -------
    str
    """
    if encoding not in ("ascii", "base64"):
        raise InputError(f"unknown VTP encoding {encoding!r}; expected 'ascii' or 'base64'")
    v, all_lines = polyline_vertices(net)
    keep = [i for i, ids in enumerate(all_lines) if len(ids) >= 2]  # a cell needs 2 points
    lines = [all_lines[i] for i in keep]
    n = net.n_nodes
    nv = len(v)
    point_node = np.full(nv, -1, dtype="<i8")
    point_node[:n] = np.arange(n)
    point_val = np.zeros(nv, dtype="<i4")
    point_val[:n] = net.valence
    vert_conn = np.arange(n, dtype="<i8")
    vert_off = np.arange(1, n + 1, dtype="<i8")
    line_conn = np.concatenate(lines).astype("<i8") if lines else np.zeros(0, "<i8")
    line_off = np.cumsum([len(ids) for ids in lines]).astype("<i8") if lines else np.zeros(0, "<i8")
    cell_curve = np.concatenate([np.full(n, -1), np.asarray(keep, dtype=np.int64)]).astype("<i8")
    cell_node = np.concatenate([np.arange(n), np.full(len(lines), -1)]).astype("<i8")
    closed = np.array([net.curves[i].closed for i in keep], dtype=bool)
    cell_closed = np.concatenate([np.zeros(n), closed]).astype("u1")

    def arr(name, a, ncomp=1):
        a = np.ascontiguousarray(a)
        t = _VTK_TYPES[a.dtype]
        head = f'<DataArray type="{t}"' + (f' Name="{name}"' if name else "")
        head += f' NumberOfComponents="{ncomp}"' if ncomp > 1 else ""
        if encoding == "ascii":
            if a.dtype.kind == "f":
                body = shortest(a)
            else:
                body = ints_text(a)
            return f'{head} format="ascii">{body}</DataArray>'
        raw = a.tobytes()
        body = base64.b64encode(np.uint64(len(raw)).astype("<u8").tobytes() + raw).decode("ascii")
        return f'{head} format="binary">{body}</DataArray>'

    out = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        "<PolyData>",
        f'<Piece NumberOfPoints="{nv}" NumberOfVerts="{n}" NumberOfLines="{len(lines)}" '
        'NumberOfStrips="0" NumberOfPolys="0">',
        '<PointData Scalars="node_id">',
        arr("node_id", point_node),
        arr("valence", point_val),
        "</PointData>",
        '<CellData Scalars="curve_id">',
        arr("curve_id", cell_curve),
        arr("node_id", cell_node),
        arr("closed", cell_closed),
        "</CellData>",
        "<Points>",
        arr("Points", np.asarray(v, dtype="<f8"), 3),
        "</Points>",
        "<Verts>",
        arr("connectivity", vert_conn),
        arr("offsets", vert_off),
        "</Verts>",
        "<Lines>",
        arr("connectivity", line_conn),
        arr("offsets", line_off),
        "</Lines>",
        "</Piece>",
        "</PolyData>",
        "</VTKFile>",
    ]
    return "\n".join(out) + "\n"

