"""curvenet: reconstruct curve networks from unorganized 2D/3D points.

The main entry point is :func:`reconstruct`, which returns a :class:`CurveNetwork`;
:func:`save` (or ``network.save(path)``) writes one in any format (by extension) and
:func:`load` reads a saved ``.json``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._version import __version__
from .errors import (
    CurvenetError,
    FormatError,
    InputError,
    MethodError,
    MissingDependencyError,
    OutputError,
)
from . import network as _network
from .network import Curve, CurveNetwork
from .reconstruct import METHODS, reconstruct


def save(network: CurveNetwork, path: str | Path, **options: Any) -> Path:
    """Write a network to ``path``, the format chosen by the extension, atomically.

    Parameters
    ----------
    network : CurveNetwork
    path : str or Path
        ``.json`` (readable by :func:`load`), ``.ply``, ``.obj``, ``.vtu``, ``.svg``,
        ``.dxf``, ``.geojson``, ``.swc``... (``curvenet formats`` lists them).
    **options
        Options of the format's writer (e.g. ``projection="iso"`` for ``.svg``,
        ``units="mm"`` for ``.dxf``).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    FormatError
        For an unknown extension.
    OutputError
        When the file cannot be written.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> net = CurveNetwork(np.array([[0.0, 0], [1, 0]]), [Curve(np.array([[0.0, 0], [1, 0]]), 0, 1)])
    >>> path = save(net, os.path.join(tempfile.mkdtemp(), "net.json"))
    >>> load(path) == net
    True
    """
    from .io import write_network

    return write_network(network, path, **options)


_network._set_file_writer(save)  # CurveNetwork.save writes through save (network never imports io)


def load(path: str | Path) -> CurveNetwork:
    """Read a network saved in the curvenet JSON format (``.json``).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    CurveNetwork

    Raises
    ------
    InputError, FormatError
        When the file is missing or is not a curvenet network.
    """
    from .io import extension, read_network

    if extension(path) != ".json":
        raise FormatError(f"{path}: curvenet.load reads the curvenet JSON format (.json); "
                          f"{extension(path) or 'a file without extension'} is written, not read back")
    return read_network(path)


def surface(network: CurveNetwork, **options: Any) -> Any:
    """Turn a curve network into a surface mesh (the paper's third step).

    A thin front of :func:`curvenet.surfacing.surface` (extra ``surface``); see it for the
    options.

    Parameters
    ----------
    network : CurveNetwork
        The network to surface.
    **options
        Options of :func:`curvenet.surfacing.surface` (``target_edge``, ``fair``...).

    Returns
    -------
    curvenet.surfacing.SurfaceMesh
        Vertices (V, 3), triangles (T, 3), a patch id per triangle and the cycles of curve ids.
    """
    from .surfacing import surface as _surface

    return _surface(network, **options)

__all__ = [
    "__version__",
    "reconstruct",
    "surface",
    "save",
    "load",
    "METHODS",
    "Curve",
    "CurveNetwork",
    "CurvenetError",
    "InputError",
    "FormatError",
    "OutputError",
    "MethodError",
    "MissingDependencyError",
]
