"""Surfacing: turn a curve network into a triangle mesh (the paper's third step, Figure 3(e)).

:func:`surface` finds the patch boundaries (cycles of curves, chosen globally), fills each with a
refined and faired triangle mesh whose boundary is exactly the curve samples, and joins the
patches into one :class:`SurfaceMesh` with shared, consistently oriented boundary vertices.
"""

from .assemble import SurfaceMesh, surface
from .checks import MeshChecks, SurfaceCheckWarning, check_mesh
from .cycles import CycleSet, find_cycles
from .patches import min_area_triangulation, triangulate_patch

__all__ = [
    "surface",
    "SurfaceMesh",
    "MeshChecks",
    "check_mesh",
    "SurfaceCheckWarning",
    "find_cycles",
    "CycleSet",
    "triangulate_patch",
    "min_area_triangulation",
]
