"""The whole cloud's estimates, exactly, from its tiles.

The default method takes a few decisions from two medians over the whole cloud (the local
spacing and the noise estimate of every point, see
:class:`~curvenet.methods.robust.PointEstimates`), once more after the duplicate rule when it
drops points. Each per-point value depends on the point's k nearest neighbours alone, so a tile
with a halo computes it exactly for the points it owns; the medians over all tiles are then
found without gathering the values: a first pass counts them in fine bins of their bit pattern
(a non-negative double's bits sort as the double does), a second fetches only the values in the
one or two bins that hold the middle ranks. The result is the median ``numpy.median`` gives on
the whole array, bit for bit.

The tasks (:func:`tile_values`, :func:`tile_count_below`, :func:`tile_values_in`) run on the
workers; :func:`whole_cloud_estimates` drives them from the client.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from ..methods.robust import Estimates, dedup_applies, dedup_radius, point_estimates
from ..methods.robust.thresholds import DEFAULTS
from .grid import TileGrid
from .scratch import read_values, write_values
from .tasks import method_slot, tile_points

__all__ = ["MEDIAN_BIN_SHIFT", "REACH_FACTOR", "TileValues", "bin_keys", "sparse_counts", "merge_counts",
           "middle_bins", "median_of", "tile_values", "tile_count_below", "tile_values_in",
           "whole_cloud_estimates"]

#: The bins of the first pass: a value's 64 bits shifted right by this many (28 bits kept: sign,
#: exponent and 16 bits of mantissa, so a bin spans a relative width of 2^-16 and the second
#: pass fetches about N / 65,536 values per octave the values spread over).
MEDIAN_BIN_SHIFT: int = 36
#: A tile's value for a point is exact when the point's k nearest neighbours lie inside the
#: tile's widened box: its k-th neighbour distance times this is at most the distance to the
#: box's edge (2: after the duplicate rule, the neighbours' own neighbourhoods count too).
REACH_FACTOR: float = 2.0

_NAMES = ("h", "rms", "earlier")


class TileValues(NamedTuple):
    """What one tile reports of its owned points' values (see :func:`tile_values`).

    Attributes
    ----------
    n : int
        Points owned (after the duplicate rule of the pass, if any).
    inexact : int
        Of those, the points whose neighbourhood reaches past the tile's widened box (their
        values are the tile's, maybe not the whole cloud's).
    counts : dict
        ``"h"`` and ``"rms"`` -> ``(keys, counts)``: the sparse bin counts of the finite values.
    """

    n: int
    inexact: int
    counts: dict


def bin_keys(values: np.ndarray) -> np.ndarray:
    """(n,) uint64: the bin of each non-negative finite value (n,) (order-preserving)."""
    v = np.ascontiguousarray(values, dtype=np.float64) + 0.0  # -0.0 -> 0.0
    return v.view(np.uint64) >> np.uint64(MEDIAN_BIN_SHIFT)


def sparse_counts(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bins (m,) uint64, ascending, and how many of the finite ``values`` (n,) fall in each."""
    v = values[np.isfinite(values)]
    return np.unique(bin_keys(v), return_counts=True)


def merge_counts(parts) -> tuple[np.ndarray, np.ndarray]:
    """Sum sparse bin counts ``[(keys, counts), ...]`` into one ``(keys, counts)``."""
    parts = [p for p in parts if len(p[0])]
    if not parts:
        return np.zeros(0, np.uint64), np.zeros(0, np.int64)
    keys = np.concatenate([p[0] for p in parts])
    counts = np.concatenate([p[1] for p in parts]).astype(np.int64)
    uk, inv = np.unique(keys, return_inverse=True)
    return uk, np.bincount(inv.ravel(), weights=counts, minlength=len(uk)).astype(np.int64)


def middle_bins(keys: np.ndarray, counts: np.ndarray) -> tuple[int, int, int, int]:
    """Where the middle ranks of the counted values lie.

    Returns
    -------
    lo_key, hi_key : int
        The bins of ranks ``(n - 1) // 2`` and ``n // 2`` (0-based, ascending values).
    below : int
        How many values lie in bins before ``lo_key``.
    n : int
        How many values there are in all.
    """
    n = int(counts.sum())
    cum = np.cumsum(counts)
    i_lo = int(np.searchsorted(cum, (n - 1) // 2, side="right"))
    i_hi = int(np.searchsorted(cum, n // 2, side="right"))
    below = int(cum[i_lo - 1]) if i_lo else 0
    return int(keys[i_lo]), int(keys[i_hi]), below, n


def median_of(values_in_bins: np.ndarray, below: int, n: int) -> float:
    """The median of all ``n`` values, from those in the middle bins (any order) and the count
    ``below`` of values before them: what ``numpy.median`` gives on the whole array."""
    v = np.sort(values_in_bins)
    pair = np.array([v[(n - 1) // 2 - below], v[n // 2 - below]])
    return float(np.median(pair))


def _margins(P: np.ndarray, grid: TileGrid, key, halo: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,) distance of each point (n, d) to the edge of tile ``key``'s widened box, counting
    only the sides past which the cloud (bounds ``lo``, ``hi``) has points."""
    blo, bhi = grid.box(key)
    wlo, whi = blo - halo, bhi + halo
    d_lo = np.where(wlo > lo, P - wlo, np.inf)
    d_hi = np.where(whi <= hi, whi - P, np.inf)
    return np.minimum(d_lo, d_hi).min(axis=1)


def tile_values(root: str, grid: TileGrid, key, halo: float, lo, hi, radius: float | None, tag: str) -> TileValues:
    """Compute the per-point values of the points tile ``key`` owns (from its box widened by
    ``halo``; the duplicate rule at ``radius`` first, if given), store them in the scratch
    store under ``tag`` and report their bin counts (see :class:`TileValues`)."""
    P, _ = tile_points(root, grid, key, halo)
    own = grid.owns(key, P)
    if len(P) < DEFAULTS.min_points:  # too few to estimate anything: values of no point
        for name in _NAMES:
            write_values(root, key, f"{tag}-{name}", np.zeros(0))
        return TileValues(0, int(own.sum()), {"h": merge_counts([]), "rms": merge_counts([])})
    with method_slot():
        v = point_estimates(P, dedup_radius=radius)
    mine = own[v.order]
    margin = _margins(P[v.order[mine]], grid, key, halo, np.asarray(lo, float), np.asarray(hi, float))
    inexact = int(np.count_nonzero(REACH_FACTOR * v.reach[mine] > margin))
    vals = {"h": v.h[mine], "rms": v.rms[mine], "earlier": v.earlier[mine]}
    for name in _NAMES:
        write_values(root, key, f"{tag}-{name}", vals[name])
    return TileValues(int(mine.sum()), inexact, {"h": sparse_counts(vals["h"]), "rms": sparse_counts(vals["rms"])})


def tile_count_below(root: str, key, name: str, r: float) -> int:
    """How many stored values ``name`` of tile ``key`` are below ``r``."""
    return int(np.count_nonzero(read_values(root, key, name) < r))


def tile_values_in(root: str, key, name: str, lo_key: int, hi_key: int) -> np.ndarray:
    """The stored finite values ``name`` of tile ``key`` whose bin is in ``[lo_key, hi_key]``."""
    v = read_values(root, key, name)
    v = v[np.isfinite(v)]
    b = bin_keys(v)
    return v[(b >= np.uint64(lo_key)) & (b <= np.uint64(hi_key))]


def whole_cloud_estimates(submit: Callable, gather: Callable, root: str, grid: TileGrid, keys: list, halo: float,
                          lo, hi) -> tuple[Estimates, int, int]:
    """The whole cloud's :class:`Estimates`, as :func:`~curvenet.methods.robust.estimate` would
    give on all points, from tasks on its tiles.

    Parameters
    ----------
    submit : callable
        ``submit(fn, *args)`` -> a future (the client's, with the run's retries).
    gather : callable
        ``gather({label: future})`` -> ``{label: result}`` (the run's wait, Ctrl-C and errors).
    root : str
        The scratch store.
    grid : TileGrid
    keys : list of tuple
        The tiles that own points.
    halo : float
        How far around its box a tile looks (at least the points' neighbourhood reach).
    lo, hi : (d,) array_like
        The cloud's bounds.

    Returns
    -------
    Estimates
    n : int
        The points the medians were taken over.
    inexact : int
        Points whose values a tile could not compute exactly (0: the estimates are exact).
    """

    def run_pass(radius, tag):
        res = gather({k: submit(tile_values, root, grid, k, halo, lo, hi, radius, tag) for k in keys})
        n = sum(r.n for r in res.values())
        inexact = sum(r.inexact for r in res.values())
        med = {}
        for name in ("h", "rms"):
            bk, cn = merge_counts([r.counts[name] for r in res.values()])
            if not len(bk):
                med[name] = 0.0
                continue
            a, b, below, m = middle_bins(bk, cn)
            got = gather({k: submit(tile_values_in, root, k, f"{tag}-{name}", a, b) for k in keys})
            med[name] = median_of(np.concatenate(list(got.values())), below, m)
        return Estimates(med["h"], med["rms"]), n, inexact

    first, n, inexact = run_pass(None, "a")
    r = dedup_radius(first)
    if r is None:
        return first, n, inexact
    dup = sum(gather({k: submit(tile_count_below, root, k, "a-earlier", r) for k in keys}).values())
    if not dedup_applies(n, dup):
        return first, n, inexact
    return run_pass(r, "b")
