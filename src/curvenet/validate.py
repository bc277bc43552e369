"""Checks of arrays at the public boundary."""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["as_points"]


def as_points(points, *, min_points: int = 1, name: str = "points") -> np.ndarray:
    """Check and convert input points.

    Parameters
    ----------
    points : (N, d) array_like
        Point coordinates, ``d`` = 2 or 3.
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
