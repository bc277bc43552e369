"""VTK XML UnstructuredGrid writer (``.vtu``): each curve as a run of line cells, for meshio.

meshio reads neither PLY edges nor OBJ ``l`` lines nor ``.vtp``; it reads ``.vtu`` line cells.
ParaView and PyVista read the file too. Written without VTK, data inline as ASCII.
"""

from __future__ import annotations

import numpy as np

from ..network import CurveNetwork
from .numbers import ints_text, shortest
from .polylines import segments

__all__ = ["network_to_vtu", "VTK_LINE"]

#: VTK's cell type code of a two-point line segment.
VTK_LINE = 3


def network_to_vtu(net: CurveNetwork) -> str:
    """The network as a VTK XML UnstructuredGrid of line segments.

    Points are the node positions (point ``j`` is node ``j``) followed by the inner points of
    the curves, as in :meth:`CurveNetwork.polyline_vertices` (2D networks get z = 0). Cells are
    the segments of :meth:`CurveNetwork.segments`, curve after curve, each of VTK type
    :data:`VTK_LINE`. Data: point data ``node_id`` (node index, -1 elsewhere), cell data
    ``curve_id``. In meshio: ``mesh.cells_dict["line"]`` and
    ``mesh.cell_data["curve_id"][0]``.

    Parameters
    ----------
    net : CurveNetwork

    Returns
    -------
    str
    """
    v, seg, cid = segments(net)
    node_id = np.full(len(v), -1, dtype=np.int64)
    node_id[: net.n_nodes] = np.arange(net.n_nodes)

    ints = ints_text

    out = [
        '<?xml version="1.0"?>',
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        "<UnstructuredGrid>",
        f'<Piece NumberOfPoints="{len(v)}" NumberOfCells="{len(seg)}">',
        '<PointData Scalars="node_id">',
        f'<DataArray type="Int64" Name="node_id" format="ascii">{ints(node_id)}</DataArray>',
        "</PointData>",
        '<CellData Scalars="curve_id">',
        f'<DataArray type="Int64" Name="curve_id" format="ascii">{ints(cid)}</DataArray>',
        "</CellData>",
        "<Points>",
        f'<DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">{shortest(v)}</DataArray>',
        "</Points>",
        "<Cells>",
        f'<DataArray type="Int64" Name="connectivity" format="ascii">{ints(seg)}</DataArray>',
        f'<DataArray type="Int64" Name="offsets" format="ascii">{ints(2 * np.arange(1, len(seg) + 1))}</DataArray>',
        f'<DataArray type="UInt8" Name="types" format="ascii">{ints(np.full(len(seg), VTK_LINE))}</DataArray>',
        "</Cells>",
        "</Piece>",
        "</UnstructuredGrid>",
        "</VTKFile>",
    ]
    return "\n".join(out) + "\n"
