"""Euclidean lengths of steps between points, at any scale float64 holds.

``np.linalg.norm`` squares the coordinates: steps longer than about 1e154 overflow to infinity,
steps shorter than about 1e-154 lose their digits or vanish (with a RuntimeWarning). Coordinates
of that size are valid input (:func:`curvenet.reconstruct` works in an internal frame), so the
lengths of a network's curves are computed here instead.
"""

from __future__ import annotations

import numpy as np

__all__ = ["step_lengths", "SQUARE_SAFE"]

#: Lengths computed with plain squares when they lie in [1 / SQUARE_SAFE, SQUARE_SAFE]; outside
#: that range (or where the squares overflowed) each step is first divided by its largest
#: coordinate. 2**500 leaves the squares of a 3-vector far from float64's under- and overflow.
SQUARE_SAFE = 2.0**500


def step_lengths(steps) -> np.ndarray:
    """Euclidean norms along the last axis, without overflow or underflow.

    Parameters
    ----------
    steps : (..., d) array_like
        Differences between points.

    Returns
    -------
    (...) float ndarray
        The norms; bit for bit those of ``np.linalg.norm(steps, axis=-1)`` where these lie in
        [1 / :data:`SQUARE_SAFE`, :data:`SQUARE_SAFE`] (or are 0 for a zero step).
    """
    d = np.asarray(steps, dtype=float)
    with np.errstate(over="ignore", under="ignore"):
        n = np.linalg.norm(d, axis=-1)
    redo = ~((n >= 1.0 / SQUARE_SAFE) & (n <= SQUARE_SAFE)) & np.isfinite(d).all(axis=-1)
    redo &= (d != 0).any(axis=-1)
    if redo.any():
        r = d[redo]
        s = np.abs(r).max(axis=-1, keepdims=True)
        n = np.array(n, dtype=float, copy=True)
        n[redo] = s[..., 0] * np.linalg.norm(r / s, axis=-1)
    return n
