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

__all__ = [
    "__version__",
    "reconstruct",
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
