"""curvenet: reconstruct curve networks from unorganized 2D/3D points.

The main entry point is :func:`reconstruct`, which returns a :class:`CurveNetwork`.
"""

from ._version import __version__
from .errors import (
    CurvenetError,
    FormatError,
    InputError,
    MethodError,
    MissingDependencyError,
    OutputError,
)
from .network import Curve, CurveNetwork
from .reconstruct import METHODS, reconstruct


def surface(network, **options):
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
