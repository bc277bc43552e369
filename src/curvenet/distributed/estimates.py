"""The whole cloud's estimates, exactly, from its tiles.

The default method takes a few decisions from two medians over the whole cloud (the local
spacing and the noise estimate of every point, see
:class:`~curvenet.methods.robust.PointEstimates`), once more after the duplicate rule when it
drops points. Each per-point value depends on the point's k nearest neighbours alone, so a tile
with a halo computes it exactly for the points it owns; the medians over all tiles are then
found without gathering the values, in bounded memory whatever N: the values are counted in
coarse bins of their bit pattern (a non-negative double's bits sort as the double does), then,
inside the one or two bins that hold the middle ranks, in finer bins, and last the distinct
values inside the finest middle bins are fetched with their counts. The result is the median
``numpy.median`` gives on the whole array, bit for bit.

The tasks (:func:`tile_values`, :func:`tile_fix_values`, :func:`tile_count_below`,
:func:`tile_counts_in`, :func:`tile_values_in`) run on the workers;
:func:`whole_cloud_estimates` drives them from the client.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from ..methods.robust import Estimates, dedup_applies, dedup_radius, point_estimates, prepare
from ..methods.robust.params import RobustParams
from ..methods.robust.thresholds import DEFAULTS
from .grid import TileGrid
from .scratch import read_tile, read_values, write_prepared, write_values
from .tasks import method_slot, tile_points

__all__ = ["MEDIAN_SHIFTS", "REACH_FACTOR", "FIX_MAX_SIDES", "TileValues", "bin_keys", "sparse_counts", "merge_counts",
           "rank_bins", "median_from_counts", "merge_values", "exact_median", "tile_values", "tile_fix_values", "tile_count_below", "tile_values_in",
           "whole_cloud_estimates"]

#: The levels of bins: a value's 64 bits shifted right by these many. The first (16 bits kept:
#: sign, exponent and 4 bits of mantissa, 16 bins an octave) bounds what a tile reports by the
#: octaves its values span, whatever its size; each next level splits the one or two middle
#: bins of the level before into 2^8, so that a tile reports at most 512 counts a level
#: (one level of 2^16 had each tile report up to 131,072 counts: 13 million on the client at
#: 10^8 points); inside the last level's middle bins (2^-20 of a value) the distinct values
#: are fetched.
MEDIAN_SHIFTS: tuple[int, ...] = (48, 40, 32)
#: A tile's value for a point is exact when the point's k nearest neighbours lie inside the
#: tile's widened box: its k-th neighbour distance times this is at most the distance to the
#: box's edge (2: after the duplicate rule, the neighbours' own neighbourhoods count too).
REACH_FACTOR: float = 2.0
#: A point whose values a tile could not compute exactly (its reach past the tile's widened
#: box) is computed again from the points within its reach, when that reach is at most this
#: many tile sides (of the tiles that far, only the points within the reach of such a point
#: are held; a point alone farther from every other is left, and counted inexact).
FIX_MAX_SIDES: float = 8.0

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


def bin_keys(values: np.ndarray, shift: int = MEDIAN_SHIFTS[0]) -> np.ndarray:
    """(n,) uint64: the bin of each non-negative finite value (n,) (order-preserving)."""
    v = np.ascontiguousarray(values, dtype=np.float64) + 0.0  # -0.0 -> 0.0
    return v.view(np.uint64) >> np.uint64(shift)


def _within(values: np.ndarray, sel) -> np.ndarray:
    """The finite values, and of them those in bins ``[lo, hi]`` at ``shift`` when ``sel`` is
    ``(shift, lo, hi)`` (None: all)."""
    v = values[np.isfinite(values)]
    if sel is None:
        return v
    shift, lo, hi = sel
    b = bin_keys(v, shift)
    return v[(b >= np.uint64(lo)) & (b <= np.uint64(hi))]


def sparse_counts(values: np.ndarray, shift: int = MEDIAN_SHIFTS[0], sel=None) -> tuple[np.ndarray, np.ndarray]:
    """The bins at ``shift`` (m,) uint64, ascending, and how many of the finite ``values`` (n,)
    (those in ``sel``, see :func:`_within`) fall in each."""
    return np.unique(bin_keys(_within(values, sel), shift), return_counts=True)


def merge_counts(parts) -> tuple[np.ndarray, np.ndarray]:
    """Sum sparse counts ``[(keys, counts), ...]`` into one ``(keys, counts)`` (keys ascending;
    keys may be bins or values)."""
    parts = [p for p in parts if len(p[0])]
    if not parts:
        return np.zeros(0, np.uint64), np.zeros(0, np.int64)
    keys = np.concatenate([p[0] for p in parts])
    counts = np.concatenate([p[1] for p in parts]).astype(np.int64)
    uk, inv = np.unique(keys, return_inverse=True)
    return uk, np.bincount(inv.ravel(), weights=counts, minlength=len(uk)).astype(np.int64)


def merge_values(parts) -> tuple[np.ndarray, np.ndarray]:
    """:func:`merge_counts` of ``[(values, counts), ...]`` (float values)."""
    parts = [p for p in parts if len(p[0])]
    if not parts:
        return np.zeros(0), np.zeros(0, np.int64)
    return merge_counts(parts)


def rank_bins(keys: np.ndarray, counts: np.ndarray, ranks) -> tuple[list, int]:
    """The bin (key) holding each of the 0-based ``ranks`` (ascending) of the counted values,
    and how many values lie before the first of those bins."""
    cum = np.cumsum(counts)
    at = [int(np.searchsorted(cum, r, side="right")) for r in ranks]
    below = int(cum[at[0] - 1]) if at[0] else 0
    return [keys[i] for i in at], below


def median_from_counts(values: np.ndarray, counts: np.ndarray, below: int, n: int) -> float:
    """The median of all ``n`` values from the distinct values (ascending) of the middle bins
    with their counts, and the count ``below`` of values before them: what ``numpy.median``
    gives on the whole array."""
    v0, v1 = rank_bins(values, counts, [(n - 1) // 2 - below, n // 2 - below])[0]
    return float(np.median(np.array([v0, v1], dtype=np.float64)))


def exact_median(first, count_in: Callable, values_in: Callable) -> float:
    """The median of values spread over tiles, from bounded counts.

    Parameters
    ----------
    first : (keys, counts)
        The merged counts at ``MEDIAN_SHIFTS[0]`` of all values.
    count_in : callable
        ``count_in(sel, shift)``: the merged counts at ``shift`` of the values in ``sel``
        (``(shift, lo, hi)``: the bins ``[lo, hi]`` at a coarser shift).
    values_in : callable
        ``values_in(sel)``: the merged distinct values in ``sel`` and their counts.

    Returns
    -------
    float
        0.0 when there is no value.
    """
    keys, counts = first
    n = int(counts.sum())
    if not n:
        return 0.0
    ranks = [(n - 1) // 2, n // 2]
    (lo, hi), below = rank_bins(keys, counts, ranks)
    sel = (MEDIAN_SHIFTS[0], int(lo), int(hi))
    for shift in MEDIAN_SHIFTS[1:]:
        keys, counts = count_in(sel, shift)
        (lo, hi), b = rank_bins(keys, counts, [r - below for r in ranks])
        below += b
        sel = (shift, int(lo), int(hi))
    vals, cnts = values_in(sel)
    return median_from_counts(vals, cnts, below, n)


def _margins(P: np.ndarray, grid: TileGrid, key, halo: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,) distance of each point (n, d) to the edge of tile ``key``'s widened box, counting
    only the sides past which the cloud (bounds ``lo``, ``hi``) has points."""
    blo, bhi = grid.box(key)
    wlo, whi = blo - halo, bhi + halo
    d_lo = np.where(wlo > lo, P - wlo, np.inf)
    d_hi = np.where(whi <= hi, whi - P, np.inf)
    return np.minimum(d_lo, d_hi).min(axis=1)


def tile_values(root: str, grid: TileGrid, key, halo: float, lo, hi, radius: float | None, tag: str,
                keep: bool = False) -> TileValues:
    """Compute the per-point values of the points tile ``key`` owns (from its box widened by
    ``halo``; the duplicate rule at ``radius`` first, if given), store them in the scratch
    store under ``tag`` and report their bin counts (see :class:`TileValues`). ``keep`` (without
    ``radius``): also store the prepared box (:func:`.scratch.write_prepared`), from which the
    tile's reconstruction goes on when its halo is ``halo``."""
    P, ids = tile_points(root, grid, key, halo)
    own = grid.owns(key, P)
    if len(P) < DEFAULTS.min_points:  # too few to estimate anything: every owned point is
        # computed again from the points around (its reach unknown: inf), see tile_fix_values
        n = int(own.sum())
        for name in _NAMES:
            write_values(root, key, f"{tag}-{name}", np.full(n, np.nan))
        write_values(root, key, f"{tag}-far", np.arange(n))
        write_values(root, key, f"{tag}-far-ids", ids[own])
        write_values(root, key, f"{tag}-far-points", P[own])
        write_values(root, key, f"{tag}-far-reach", np.full(n, np.inf))
        return TileValues(n, n, {"h": merge_counts([]), "rms": merge_counts([])})
    with method_slot():
        if radius is None:
            prep, v = prepare(P)
        else:
            prep, v = None, point_estimates(P, dedup_radius=radius)
    if keep and prep is not None:
        write_prepared(root, key, prep, ids)
    del prep
    mine = own[v.order]
    rows = v.order[mine]
    reach = REACH_FACTOR * v.reach[mine]
    far = np.flatnonzero(reach > _margins(P[rows], grid, key, halo, np.asarray(lo, float), np.asarray(hi, float)))
    vals = {"h": v.h[mine], "rms": v.rms[mine], "earlier": v.earlier[mine]}
    for name in _NAMES:
        write_values(root, key, f"{tag}-{name}", vals[name])
    # the points to compute again (tile_fix_values): where they are among the values, their
    # global ids, positions and reach
    write_values(root, key, f"{tag}-far", far)
    write_values(root, key, f"{tag}-far-ids", ids[rows[far]])
    write_values(root, key, f"{tag}-far-points", P[rows[far]])
    write_values(root, key, f"{tag}-far-reach", reach[far])
    return TileValues(int(mine.sum()), len(far), {"h": sparse_counts(vals["h"]), "rms": sparse_counts(vals["rms"])})


def tile_fix_values(root: str, grid: TileGrid, key, radius: float | None, tag: str) -> TileValues:
    """Compute again, exactly, the values of tile ``key``'s points whose neighbourhood reached
    past its widened box (in :func:`tile_values`), from every point of the cloud within their
    reach (read from the tiles around, as far as it takes, up to :data:`FIX_MAX_SIDES` tile
    sides), rewrite them in the store and report the tile's counts again (``inexact``: the
    points left, whose reach is farther than that).

    A point's values depend on the points within ``REACH_FACTOR`` times its k-th neighbour
    distance, and that distance is never larger in the whole cloud than in a part of it: the
    points within the part's reach hold all of them.
    """
    far = read_values(root, key, f"{tag}-far").astype(np.int64)
    X = read_values(root, key, f"{tag}-far-points").reshape(len(far), grid.dim)
    xid = read_values(root, key, f"{tag}-far-ids").astype(np.int64)
    reach = read_values(root, key, f"{tag}-far-reach")
    unknown = ~np.isfinite(reach)  # (a tile of too few points) bounded by the points around
    if unknown.any():
        reach[unknown] = _reach_bound(root, grid, key, X[unknown], FIX_MAX_SIDES * grid.side)
    fix = reach <= FIX_MAX_SIDES * grid.side
    vals = {name: read_values(root, key, f"{tag}-{name}") for name in _NAMES}
    if fix.any():
        P, ids = _points_near(root, grid, key, X[fix], reach[fix])
        if len(P) >= DEFAULTS.min_points:
            with method_slot():
                v = point_estimates(P, dedup_radius=radius)
            at = dict(zip(ids[v.order].tolist(), range(len(v.order))))
            done = np.zeros(len(far), bool)
            for j in np.flatnonzero(fix):
                i = at.get(int(xid[j]))
                if i is None:  # dropped by the duplicate rule here, not in the tile: left as it was
                    continue
                for name in _NAMES:
                    vals[name][far[j]] = getattr(v, name)[i]
                done[j] = True
            fix &= done
            for name in _NAMES:
                write_values(root, key, f"{tag}-{name}", vals[name])
        else:
            fix[:] = False
    return TileValues(len(vals["h"]), int(np.count_nonzero(~fix)),
                      {"h": sparse_counts(vals["h"]), "rms": sparse_counts(vals["rms"])})


def _reach_bound(root: str, grid: TileGrid, key, X: np.ndarray, r: float) -> np.ndarray:
    """(m,) ``REACH_FACTOR`` times the k-th neighbour distance of each point of ``X`` (m, d)
    among the cloud's points within ``r`` of them (never less than in the whole cloud; inf
    when there are not k)."""
    P, _ = _points_near(root, grid, key, X, np.full(len(X), r))
    k = RobustParams().k
    if len(P) <= k:
        return np.full(len(X), np.inf)
    d = cKDTree(P).query(X, k + 1)[0][:, -1]  # (the points themselves are among P)
    return np.where(d <= r, REACH_FACTOR * d, np.inf)


def _points_near(root: str, grid: TileGrid, key, X: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points (n, d) of the cloud, and their global ids (n,), within ``r[i]`` of some
    ``X[i]`` ((m, d) points of tile ``key``), read tile by tile (only those kept are held)."""
    r_max = float(r.max())
    tx = cKDTree(X)
    pts, out_ids = [], []
    for nb in grid.neighbours(key, r_max):
        for p, i in read_tile(root, nb):
            # within r_max of one of the points (a query against their few), then within each one's own r
            m = np.flatnonzero(np.isfinite(tx.query(p, distance_upper_bound=r_max * (1 + 1e-9))[0]))
            if not len(m):
                continue
            near = cKDTree(p[m]).query_ball_point(X, r, return_sorted=False)
            keep = m[np.unique(np.concatenate([np.asarray(q, dtype=np.int64) for q in near]))]
            pts.append(p[keep])
            out_ids.append(i[keep])
    if not pts:
        return np.zeros((0, grid.dim)), np.zeros(0, np.int64)
    return np.vstack(pts), np.concatenate(out_ids)


def tile_count_below(root: str, key, name: str, r: float) -> int:
    """How many stored values ``name`` of tile ``key`` are below ``r``."""
    return int(np.count_nonzero(read_values(root, key, name) < r))


def tile_counts_in(root: str, key, name: str, sel, shift: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sparse_counts` at ``shift`` of tile ``key``'s stored values ``name`` in ``sel``."""
    return sparse_counts(read_values(root, key, name), shift, sel)


def tile_values_in(root: str, key, name: str, sel) -> tuple[np.ndarray, np.ndarray]:
    """The distinct stored finite values ``name`` of tile ``key`` in ``sel``, ascending, and how
    many times each occurs."""
    return np.unique(_within(read_values(root, key, name), sel), return_counts=True)


def whole_cloud_estimates(submit: Callable, gather: Callable, root: str, grid: TileGrid, keys: list, halo: float,
                          lo, hi, keep: bool = False) -> tuple[Estimates, int, int]:
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
    keep : bool
        Store each tile's prepared box (see :func:`tile_values`): ``halo`` is then the halo
        of the tiles' reconstruction, which goes on from it.

    Returns
    -------
    Estimates
    n : int
        The points the medians were taken over.
    inexact : int
        Points whose values a tile could not compute exactly (0: the estimates are exact).
    """

    def run_pass(radius, tag):
        res = gather({k: submit(tile_values, root, grid, k, halo, lo, hi, radius, tag, keep and radius is None)
                      for k in keys})
        res.update(gather({k: submit(tile_fix_values, root, grid, k, radius, tag)
                           for k in keys if res[k].inexact and res[k].n}))  # (n = 0: too few points)
        n = sum(r.n for r in res.values())
        inexact = sum(r.inexact for r in res.values())
        med = {}
        for name in ("h", "rms"):
            stored = f"{tag}-{name}"

            def count_in(sel, shift):
                return merge_counts(gather({k: submit(tile_counts_in, root, k, stored, sel, shift)
                                            for k in keys}).values())

            def values_in(sel):
                return merge_values(gather({k: submit(tile_values_in, root, k, stored, sel) for k in keys}).values())

            med[name] = exact_median(merge_counts([r.counts[name] for r in res.values()]), count_in, values_in)
        return Estimates(med["h"], med["rms"]), n, inexact

    first, n, inexact = run_pass(None, "a")
    r = dedup_radius(first)
    if r is None:
        return first, n, inexact
    dup = sum(gather({k: submit(tile_count_below, root, k, "a-earlier", r) for k in keys}).values())
    if not dedup_applies(n, dup):
        return first, n, inexact
    return run_pass(r, "b")
