"""File formats: one registry of readers (points) and writers (networks), keyed by extension.

``READERS`` maps an extension to a function ``f(path, *, columns=None, drop_nonfinite=False)``
returning an (N, d) float array. ``WRITERS`` maps an extension to a pure function
``f(network, **options)`` returning ``str`` or ``bytes``; :func:`write_network` writes its result
atomically.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from ..errors import FormatError
from ..network import CurveNetwork
from .atomic import all_or_nothing, atomic_write, check_output_path, check_outputs
from .dxf import network_to_dxf
from .geojson import network_to_geojson
from .graphml import network_to_graphml
from .svg import network_to_svg
from .swc import network_to_swc
from .vtp import network_to_vtp
from .vtu import network_to_vtu
from .network_io import network_to_json, network_to_obj, network_to_ply, read_network
from .pcd import read_pcd
from .points import check_readable, read_las, read_npy, read_obj, read_ply, read_text

__all__ = [
    "READERS",
    "WRITERS",
    "read_points",
    "write_network",
    "read_network",
    "atomic_write",
    "all_or_nothing",
    "check_output_path",
    "check_outputs",
    "extension",
]

#: extension -> (reader, description)
READERS: dict[str, tuple[Callable[..., np.ndarray], str]] = {
    ".xyz": (read_text, "text, x y [z] per line"),
    ".txt": (read_text, "text, x y [z] per line"),
    ".pts": (read_text, "text, x y [z] per line"),
    ".csv": (read_text, "comma-separated values, optional header; text columns skipped"),
    ".tsv": (read_text, "tab-separated values, optional header; text columns skipped"),
    ".pcd": (read_pcd, "PCL/Open3D point cloud, ascii, binary or binary_compressed"),
    ".npy": (read_npy, "NumPy array (N, 2|3)"),
    ".ply": (read_ply, "PLY vertices, ASCII or binary (extra io)"),
    ".obj": (read_obj, "Wavefront OBJ vertices"),
    ".las": (read_las, "LAS point cloud (extra io)"),
    ".laz": (read_las, "LAZ point cloud (extra io)"),
}

#: extension -> (writer, description)
WRITERS: dict[str, tuple[Callable[..., Any], str]] = {
    ".json": (network_to_json, "curvenet JSON network"),
    ".obj": (network_to_obj, "Wavefront OBJ polylines (l lines: Blender, MeshLab, ParaView)"),
    ".ply": (network_to_ply, "PLY vertices and edges (a line set in trimesh, Open3D, MeshLab, Blender)"),
    ".dxf": (network_to_dxf, "DXF: 3D polylines or splines (layer CURVES), node points (NODES); --units (extra io)"),
    ".svg": (network_to_svg, "SVG drawing of a 2D network or a view of a 3D one (--view top|front|side|iso)"),
    ".vtp": (network_to_vtp, "VTK XML PolyData polylines and node vertices (ParaView)"),
    ".vtu": (network_to_vtu, "VTK XML UnstructuredGrid line cells with curve ids (meshio, ParaView)"),
    ".graphml": (network_to_graphml, "GraphML graph: nodes with x y z, one edge per curve with its polyline"),
    ".geojson": (network_to_geojson, "GeoJSON: curves as LineStrings, nodes as Points (QGIS, GDAL, shapely)"),
    ".swc": (network_to_swc, "SWC tree samples with parent links, fork and end types (navis, NEURON)"),
}


def extension(path: str | Path) -> str:
    """Lower-case extension of ``path`` (e.g. ``".xyz"``)."""
    return Path(path).suffix.lower()


def read_points(
    path: str | Path, *, columns: Sequence[int | str] | None = None, drop_nonfinite: bool = False
) -> np.ndarray:
    """Read points from a file, choosing the reader by extension.

    Parameters
    ----------
    path : str or Path
        A point file with an extension listed in :data:`READERS`.
    columns : sequence of int or str, optional
        Coordinate columns to use (text and array formats).
    drop_nonfinite : bool
        Drop points with NaN or infinite coordinates instead of raising.

    Returns
    -------
    (N, d) ndarray of float64

    Raises
    ------
    InputError, FormatError
        With a one-line message naming the file and the problem.
    """
    check_readable(path)
    ext = extension(path)
    if ext not in READERS:
        known = ", ".join(sorted(READERS))
        raise FormatError(f"{path}: unknown point file extension {ext or '(none)'!r}; readable: {known}")
    return READERS[ext][0](path, columns=columns, drop_nonfinite=drop_nonfinite)


def write_network(net: CurveNetwork, path: str | Path, *, inputs: Iterable[str | Path] = (), **options: Any) -> Path:
    """Write a network to ``path`` in the format given by its extension, atomically.

    Parameters
    ----------
    net : CurveNetwork
    path : str or Path
    inputs : iterable of paths
        Input files of the run, which must not be overwritten.
    **options
        Passed to the writer.
    """
    ext = extension(path)
    if ext not in WRITERS:
        known = ", ".join(sorted(WRITERS))
        raise FormatError(f"{path}: unknown output extension {ext or '(none)'!r}; writable: {known}")
    check_output_path(path, inputs=inputs)
    data = WRITERS[ext][0](net, **options)
    return atomic_write(path, data, inputs=inputs)
