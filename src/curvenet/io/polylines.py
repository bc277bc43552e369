"""Per-curve values of many curves at once, for the writers (the same floats as one curve at a
time)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..network import Curve

__all__ = ["curve_lengths"]


def curve_lengths(curves: Sequence[Curve]) -> np.ndarray:
    """:attr:`Curve.length` of every curve, computed for all curves of one size together.

    Parameters
    ----------
    curves : sequence of Curve

    Returns
    -------
    (c,) ndarray of float
        Bit for bit the value of each curve's ``length`` (the same operations in the same
        order on each curve's points: numpy sums each row of a stack as it sums one array).
    """
    out = np.zeros(len(curves))
    groups: dict[tuple[int, bool, int], list[int]] = {}
    for i, c in enumerate(curves):
        if len(c.points) >= 2:
            groups.setdefault((len(c.points), bool(c.closed), c.points.shape[1]), []).append(i)
    for (m, closed, _), ids in groups.items():
        P = np.stack([curves[i].points for i in ids])
        if closed:
            P = np.concatenate([P, P[:, :1]], axis=1)
        out[ids] = np.linalg.norm(np.diff(P, axis=1), axis=2).sum(axis=1)
    return out
