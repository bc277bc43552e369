"""Checks of arrays at the public boundary."""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["as_points", "reconstructable", "unit_frame", "MIN_EXTENT", "UNSCALED_EXTENTS", "TRANSLATE_RATIO", "MAX_OFFSET_RATIO"]

#: The least extent (largest coordinate range) of points that float64 resolves: below it the
#: differences between points fall among the subnormal numbers (under 2**-1022), where float64
#: keeps fewer than its 53 significant bits.
MIN_EXTENT = 2.0**-970

#: Points whose extent lies in this range run in their own units; others are scaled by a power of
#: two to an extent in [0.5, 1). Inside it, squares and higher powers of every length a method
#: forms stay far from overflow and underflow; and the methods are not exactly scale-equivariant
#: (a few absolute tolerances), so scaling ordinary inputs would change some networks' last bits.
UNSCALED_EXTENTS = (2.0**-64, 2.0**64)

#: Points whose largest coordinate (in absolute value) exceeds this many times their extent are
#: translated to the centre of their bounding box before a method runs (far from the origin,
#: the rounding of the coordinates matters at the scale of the spacing). Closer points are not
#: translated: a translation changes the rounding of every coordinate.
TRANSLATE_RATIO = 1e6

#: Points whose largest coordinate exceeds this many times their extent are refused: float64
#: keeps fewer than 12 significant digits of their differences (2**40 is about 1.1e12).
MAX_OFFSET_RATIO = 2.0**40


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


#: The least number of points a reconstruction takes.
MIN_RECONSTRUCT_POINTS = 3


def reconstructable(points, *, name: str = "points") -> np.ndarray:
    """Check points for a reconstruction: :func:`as_points`, at least
    :data:`MIN_RECONSTRUCT_POINTS` of them, not all identical, an extent float64 resolves
    (:func:`unit_frame`).

    Parameters
    ----------
    points : (N, d) array_like
    name : str
        What to call them in messages (the command line gives the file name).

    Returns
    -------
    (N, d) ndarray of float64

    Raises
    ------
    InputError
        ``"<name>: ..."``.
    """
    pts = as_points(points, min_points=MIN_RECONSTRUCT_POINTS, name=name)
    if not (pts.max(axis=0) > pts.min(axis=0)).any():
        raise InputError(f"{name}: all {len(pts)} points are identical; nothing to reconstruct")
    try:  # extents float64 cannot resolve, refused here with the name (the method checks them too)
        unit_frame(pts)
    except InputError as e:
        raise InputError(f"{name}: {e}") from None
    return pts


def unit_frame(points: np.ndarray) -> tuple[np.ndarray | None, int]:
    """The internal frame of points: a translation (only when needed) and a power-of-two scale.

    Parameters
    ----------
    points : (N, d) ndarray of float64
        Finite points, not all identical.

    Returns
    -------
    shift : (d,) ndarray of float64 or None
        The centre of the bounding box when the points lie farther than
        :data:`TRANSLATE_RATIO` times their extent from the origin, else None.
    k : int
        0 when the extent lies in :data:`UNSCALED_EXTENTS`, else the exponent that brings it
        into [0.5, 1): the internal points are ``(points - shift) * 2**k``, exact in float64
        when ``shift`` is None.

    Raises
    ------
    InputError
        When float64 cannot resolve the points: an extent that overflows, an extent under
        :data:`MIN_EXTENT`, or points farther than :data:`MAX_OFFSET_RATIO` times their extent
        from the origin.
    """
    lo = points.min(axis=0)
    hi = points.max(axis=0)
    with np.errstate(over="ignore"):
        extent = float(np.max(hi - lo))
    far = float(np.max(np.maximum(np.abs(lo), np.abs(hi))))
    if not np.isfinite(extent):
        raise InputError(
            f"points span more than float64 holds (coordinates from {lo.min():.3g} to {hi.max():.3g}); "
            "rescale them"
        )
    if extent < MIN_EXTENT:
        raise InputError(
            f"points span only {extent:.3g}, below {MIN_EXTENT:.3g}: float64 cannot resolve their "
            "differences; rescale them"
        )
    if far > MAX_OFFSET_RATIO * extent:
        raise InputError(
            f"points span {extent:.3g} at {far:.3g} from the origin: float64 keeps too few digits of "
            "their differences; subtract a nearby origin first"
        )
    shift = None
    if far > TRANSLATE_RATIO * extent:
        shift = 0.5 * lo + 0.5 * hi
    lo_ok, hi_ok = UNSCALED_EXTENTS
    k = 0 if lo_ok <= extent <= hi_ok else -int(np.frexp(extent)[1])
    return shift, k


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
