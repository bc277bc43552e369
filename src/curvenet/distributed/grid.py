"""The explicit tile grid: an origin and a side; tile ``key`` owns the half-open box [lo, hi)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["TileGrid", "OWNER_DECIMALS"]

#: Positions in tile units are rounded to this many decimals before the floor that gives their
#: tile: a node that two tiles compute a rounding error apart, on a face or a corner, is then
#: owned by one tile in both.
OWNER_DECIMALS: int = 9


@dataclass(frozen=True)
class TileGrid:
    """A regular grid of cubic (square in 2D) tiles.

    Tile ``key`` (a tuple of ``d`` ints) owns the half-open box ``[origin + key * side,
    origin + (key + 1) * side)``, so a point on a face belongs to exactly one tile.

    Parameters
    ----------
    origin : (d,) tuple of float
        A corner of tile ``(0, ..., 0)``.
    side : float
        The side of every tile, in input units (> 0).
    """

    origin: tuple[float, ...]
    side: float

    def __post_init__(self):
        if not (np.isfinite(self.side) and self.side > 0):
            raise InputError(f"the tile side must be a positive number, got {self.side!r}")
        if not np.isfinite(self.origin).all():
            raise InputError(f"the tile origin must be finite, got {self.origin!r}")

    @property
    def dim(self) -> int:
        return len(self.origin)

    def keys_of(self, points: np.ndarray) -> np.ndarray:
        """(N, d) int64 array: the key of the tile that owns each point of ``points`` (N, d)."""
        t = (np.asarray(points, float) - np.asarray(self.origin)) / self.side
        return np.floor(np.round(t, OWNER_DECIMALS)).astype(np.int64)

    def owners(self, points: np.ndarray, occupied) -> np.ndarray:
        """(N, d) int64: the tile that keeps each of ``points`` (N, d), among ``occupied``.

        A point's own tile (:meth:`keys_of`) when it holds input points (is in ``occupied``,
        a set of key tuples); otherwise the occupied tile whose box is nearest (ties: the
        smallest key). A node computed off the input points can lie in a tile without input
        points, which runs no task: the nearest occupied tile keeps it. A function of the
        position and the set alone, so every tile decides alike.
        """
        keys = self.keys_of(points)
        if not len(keys):
            return keys
        uk, inv = np.unique(keys, axis=0, return_inverse=True)
        inv = inv.ravel()
        lost = [u for u, k in enumerate(map(tuple, uk.tolist())) if k not in occupied]
        for i in np.flatnonzero(np.isin(inv, lost)):
            keys[i] = self._nearest_occupied(points[i], tuple(keys[i].tolist()), occupied)
        return keys

    def _nearest_occupied(self, p: np.ndarray, key: tuple, occupied) -> tuple:
        """The occupied tile whose box is nearest to ``p`` (ties: the smallest key)."""
        occ = np.array(sorted(occupied), dtype=np.int64).reshape(-1, self.dim)
        if not len(occ):
            raise ValueError("no tile holds input points")
        lo = np.asarray(self.origin) + occ * self.side
        dist = np.linalg.norm(np.maximum(0.0, np.maximum(lo - p, p - (lo + self.side))), axis=1)
        return tuple(occ[int(np.argmin(dist))].tolist())  # (argmin: the first, in sorted key order)

    def box(self, key) -> tuple[np.ndarray, np.ndarray]:
        """The (lo, hi) corners of tile ``key``, each a (d,) array."""
        lo = np.asarray(self.origin) + np.asarray(key, dtype=float) * self.side
        return lo, lo + self.side

    def owns(self, key, points: np.ndarray) -> np.ndarray:
        """(N,) bool: which of ``points`` (N, d) tile ``key`` owns (the same rule as :meth:`keys_of`)."""
        return (self.keys_of(points) == np.asarray(key, dtype=np.int64)).all(axis=1)

    def within(self, key, points: np.ndarray, halo: float) -> np.ndarray:
        """(N,) bool: which of ``points`` (N, d) lie in tile ``key``'s box widened by ``halo``."""
        lo, hi = self.box(key)
        p = np.asarray(points, float)
        return ((p >= lo - halo) & (p < hi + halo)).all(axis=1)

    def neighbours(self, key, halo: float) -> list[tuple[int, ...]]:
        """The keys of every tile whose box meets tile ``key``'s box widened by ``halo``
        (``key`` itself included), in sorted order."""
        reach = int(np.ceil(halo / self.side))
        steps = range(-reach, reach + 1)
        return sorted(tuple(int(k + s) for k, s in zip(key, off)) for off in itertools.product(steps, repeat=len(key)))
