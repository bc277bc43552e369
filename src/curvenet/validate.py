"""Checks of arrays at the public boundary."""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["as_points"]


def as_points(points, *, min_points: int = 1, name: str = "points") -> np.ndarray:
    """Check and convert input points.

    Parameters
    ----------
    points : (N, d) array_like, or a point cloud object
        Point coordinates, ``d`` = 2 or 3: an array, a pandas DataFrame, or the point clouds of
        other libraries: ``open3d.geometry.PointCloud``, ``trimesh.PointCloud`` and laspy's
        ``LasData`` (recognised by their type, without importing those packages).
    min_points : int
        The least number of points accepted.
    name : str
        What to call the array in messages.

    Returns
    -------
    (N, d) ndarray of float64
        A C-contiguous float64 array (the input itself when it already is one).

    Raises
    ------
    InputError
        If the array is not numeric, not (N, 2) or (N, 3), has NaN or infinite values, or fewer
        than ``min_points`` rows.
    """
    points = _coordinates_of(points)
    try:
        p = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a numeric (N, 2) or (N, 3) array") from None
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise InputError(f"{name} must be an (N, 2) or (N, 3) array, got shape {p.shape}")
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        rows = np.flatnonzero(bad)
        where = ", ".join(str(r) for r in rows[:5]) + (", ..." if len(rows) > 5 else "")
        raise InputError(f"{name} has {len(rows)} row(s) with NaN or infinite values (rows {where})")
    if len(p) < min_points:
        raise InputError(f"{name}: {len(p)} point(s) given, at least {min_points} needed")
    return np.ascontiguousarray(p)


def _coordinates_of(obj):
    """The coordinate array of another library's point cloud, or ``obj`` itself."""
    module = type(obj).__module__.split(".")[0]
    if module == "open3d" and hasattr(obj, "points"):  # open3d.geometry.PointCloud
        return np.asarray(obj.points)
    if module == "trimesh" and hasattr(obj, "vertices"):  # trimesh.PointCloud (or a mesh's vertices)
        return np.asarray(obj.vertices)
    if module == "laspy" and all(hasattr(obj, a) for a in "xyz"):  # laspy.LasData: scaled x, y, z
        return np.column_stack([np.asarray(obj.x), np.asarray(obj.y), np.asarray(obj.z)])
    return obj
