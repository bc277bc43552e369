"""The robust, parameter-free default method: the stages in order.

Every radius is in units of the *local* sampling spacing ``h`` of a point, and grows with the
estimated noise. The stages, each a module of this package (docs/method.md shows each on a
small example):

1-2. :mod:`.frames` -- neighbours, local spacing, duplicate samples, points alone in space
   (outliers); tangents, noise level;
3. :mod:`.graph` -- links along the tangents (strand links cut under noise);
4. :mod:`.junctions` -- the shell test: which points are junction points, and their regions;
5. :mod:`.chains` -- the chains between regions, ordered;
6. :mod:`.topology` and :mod:`.repairs` -- regions and chains as one topology object, repaired
   where noise and sparse sampling broke it;
7. :mod:`.nodes` -- node positions;
8. :mod:`.curves` -- curves ending exactly at their nodes, without spikes (outliers), fitted
   by smoothing splines under noise (8b); before the fit, :mod:`.skipped` makes a short free
   spur that a neighbouring curve jumped over (a zigzag read as a junction) part of that curve
   (8c), :mod:`.excursions` splits a curve that runs out along a twig and back into a
   junction and that twig (8d), and :mod:`.walkins` runs a curve that jumped from its
   junction's node over samples of no curve through them (8e);
9. :mod:`.unexplained` -- under noise, branches the network leaves unexplained (a twig whose
   junction the earlier stages missed), added.

(The numbers are those of docs/method.md's sections and of the comments below.)

The result does not depend on the order of the input points: they are sorted by coordinates
first and every tie is broken by that order. The fixed constants are in :mod:`.thresholds`,
the user's keywords in :class:`.params.RobustParams`.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from typing import NamedTuple

import numpy as np

from ...errors import InputError
from ...network import CurveNetwork
from ...neighbors import build_tree, locality_order
from ...validate import as_points
from ..stages import ROBUST_SHARES, OnStage, report_stage
from . import kernels as _k
from .chains import trace_chains
from .curves import build_curves, drop_spikes, fit_curves
from .frames import (Neighbours, Tangents, coincident, dedup_applies, dedup_radius, duplicates, frames, isolated,
                     lex_order, local_spacing, median_noise, median_spacing, neighbours, neighbours_and_distances,
                     point_tangents)
from .graph import linked_graph
from .junctions import junction_regions, shell_group_counts
from .nodes import place_nodes
from .params import Estimates, RobustParams, Scales
from .repairs import run_repairs
from .excursions import split_excursions
from .skipped import rejoin_skipped_stretches
from .walkins import walk_into_junctions
from .thresholds import DEFAULTS, LAYOUT, NOISE, SPACING
from .topology import Topology
from .unexplained import add_unexplained_branches

__all__ = ["reconstruct_robust", "estimate", "local_spacing", "shell_group_counts", "Prepared", "prepare",
           "PointEstimates", "point_estimates"]


def reconstruct_robust(
    points,
    *,
    spacing: float | None = None,
    k: int | None = None,
    shell_inner: float | None = None,
    shell_outer: float | None = None,
    link: float | None = None,
    link_width: float | None = None,
    min_spur: float | None = None,
    fit: bool | None = None,
    smoothing: float | None = None,
    estimates: Estimates | None = None,
    on_stage: OnStage | None = None,
) -> CurveNetwork:
    """Reconstruct a curve network without tuning: the robust default method.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like, or Prepared
        Points sampled along curves, in any order; or those points with the first stages done
        (:func:`prepare`, with the same ``spacing`` and ``k``): the same network.
    spacing : float, optional
        Sampling spacing h. Default: estimated per point (see :func:`local_spacing`); the
        median is reported. A given value is used everywhere.
    k : int, optional
        Neighbours per point for the linked graph (default 16).
    shell_inner, shell_outer : float, optional
        Radii of the junction-test shell in spacings (default 2.5 and 5.5).
    link : float, optional
        Longest link between two points, in spacings (default 2.5).
    link_width : float, optional
        A link is kept when its far end lies within this many spacings of the tangent line
        through one of its ends (default 1.0).
    min_spur : float, optional
        Spurs (junction to free end) and isolated pieces shorter than this many spacings are
        dropped (default 3).
    fit : bool, optional
        Fit each curve by a smoothing spline whose ends are held at the curve's nodes
        (:func:`.curves.fit_curves`): each sample keeps its input index and is moved onto the
        fit, so the curves no longer zigzag with the noise. Default (None): on where noise is
        detected (the estimated noise is at least ``SPACING.dedup_noise`` median spacings), off
        on noise-free input, whose curves stay the input points.
    smoothing : float, optional
        Width of the fit's smoothing kernel, in spacings (default ``FIT.band``); 0 fits
        nothing.
    estimates : Estimates, optional
        The median spacing and noise level of a larger cloud this one is a part of (a tile):
        the decisions taken from them (noise gates, duplicate rule, radii) are then the whole
        cloud's. Default: estimated on ``points`` (see :func:`estimate`).
    on_stage : callable, optional
        ``on_stage(name, share)``, called as each stage begins with its name (a key of
        ``stats["time"]``) and its share of the work (:data:`curvenet.methods.stages.ROBUST_SHARES`),
        e.g. for a progress display. Not called for inputs too small to run the stages.

    Returns
    -------
    CurveNetwork
        Nodes (junctions and free ends), curves ending exactly at their nodes (closed loops
        without node have ``start = end = None``), parameters used and stage timings.
    """
    t0 = time.perf_counter()
    prm = RobustParams.from_keywords(spacing=spacing, k=k, shell_inner=shell_inner, shell_outer=shell_outer,
                                     link=link, link_width=link_width, min_spur=min_spur, fit=fit,
                                     smoothing=smoothing)
    prep = points if isinstance(points, Prepared) else None
    if prep is not None and (prep.k != prm.k or prep.spacing != prm.spacing):
        raise ValueError(f"the points were prepared with k={prep.k}, spacing={prep.spacing}, not k={prm.k}, "
                         f"spacing={prm.spacing}")
    P0 = prep.points if prep is not None else as_points(points)
    # small inputs run the plain-Python kernels: no numba compile or cache load (same results)
    with _k.compiled_for(len(P0)):
        return _stages(P0, prep, prm, estimates, on_stage, t0)


def _stages(P0: np.ndarray, prep: Prepared | None, prm: RobustParams, estimates: Estimates | None,
            on_stage: OnStage | None, t0: float) -> CurveNetwork:
    """The stages in order on the points ``P0`` (N, d) (see :func:`reconstruct_robust`); from
    stage 2's whole-cloud decisions on when ``prep`` (those points, prepared) is given."""
    tm: dict[str, float] = {}
    N, dim = P0.shape
    params_out = prm.report()
    if N < DEFAULTS.min_points:
        params_out["spacing"] = float(prm.spacing) if prm.spacing is not None else None
        return CurveNetwork(np.zeros((0, dim)), [], params_out, {"time": tm})

    report_stage(on_stage, ROBUST_SHARES, "neighbors")
    if prep is None:
        order = _internal_order(P0)
        P = P0[order]
        del P0  # (a copy when the input was not float64)
        nb = neighbours(P, prm)  # 1. neighbours and spacing
        tg = None  # (computed by stage 2)
    else:  # (the same tree, over the same points, as stage 1 builds)
        P, order, tg = prep.points, prep.order, prep.tangents
        nb = Neighbours(build_tree(P), prep.idx, prep.h)
        del P0, prep
    tm["neighbors"] = time.perf_counter() - t0
    report_stage(on_stage, ROBUST_SHARES, "graph")
    t1 = time.perf_counter()
    fr = frames(P, nb, estimates, tg)  # 2. tangents and noise
    del tg
    P, order, nb, fr = _without_duplicates(P, order, nb, fr, prm, estimates)
    params_out["duplicates_dropped"] = int(N - len(P))
    n_kept, h_all = len(P), nb.h
    P, order, nb, fr = _without_isolated(P, order, nb, fr, prm)
    params_out["isolated_dropped"] = int(n_kept - len(P))
    params_out.update(_spacing_report(prm, h_all if nb is None else nb.h, fr))
    del h_all
    if estimates is not None:
        params_out["estimates_given"] = True
    if nb is None:  # too few points left that are not alone in space: no curve
        return CurveNetwork(np.zeros((0, dim)), [], params_out, {"time": tm})
    graph = linked_graph(P, nb, fr, prm)  # 3. links
    tm["graph"] = time.perf_counter() - t1
    # memory: every intermediate is dropped as soon as no later stage reads it (at 1e7 points
    # the peak is in the last stages); from here on the tangents are not read
    sigma, hmed, clean, lin = fr.sigma, fr.hmed, fr.clean, fr.lin
    fr = fr._replace(t=None)  # (stage 4 reads sigma, clean and low only)
    # the k-d tree is read again by the repairs alone: it is built again there, over the same
    # points (the same tree, the same answers), instead of being held through the two stages
    # that hold the most memory (about 20 bytes a point: its ids and nodes)
    nb = nb._replace(tree=None)

    report_stage(on_stage, ROBUST_SHARES, "nodes")
    t1 = time.perf_counter()
    reg = junction_regions(P, nb, fr, graph, prm)  # 4. the shell test and its regions
    del fr
    tm["nodes"] = time.perf_counter() - t1
    # (counts of the small non-negative group numbers: a bincount, not a sort of all points)
    groups_histogram = {str(g): c for g, c in enumerate(np.bincount(reg.groups).tolist()) if c}
    flagged, reg_of, n_reg, close = reg.flagged, reg.reg, reg.n_reg, reg.close
    del reg
    report_stage(on_stage, ROBUST_SHARES, "tracing")
    t1 = time.perf_counter()
    h = nb.h
    del nb  # the kNN lists are not needed below
    chains, regions = trace_chains(P, h, graph, flagged, reg_of, n_reg, lin, close=close)  # 5. chains
    indptr, indices = graph.indptr, graph.indices
    del graph, flagged, reg_of, lin, close  # the directed links, region labels and linearity
    tm["tracing"] = time.perf_counter() - t1

    report_stage(on_stage, ROBUST_SHARES, "assemble")
    t1 = time.perf_counter()
    sc = Scales(h=h, hmed=hmed, sigma=sigma, noise=NOISE.scale * sigma, clean=clean,
                width=max(prm.link_width, 0.0), indptr=indptr, indices=indices, tree=build_tree(P))
    del indptr, indices  # (held by sc alone, dropped with it)
    topo = run_repairs(Topology(P, chains, regions), sc, prm)  # 6. repairs
    del chains, regions
    sc = dataclasses.replace(sc, tree=None)  # the k-d tree: read by the repairs alone
    placement = place_nodes(topo, sc, prm)  # 7. nodes
    noise = sc.noise
    del topo, sc  # the linked graph: read by the repairs and node placement alone
    nodes, curves = placement.nodes, drop_spikes(build_curves(P, h, placement), P, h, noise)  # 8. curves
    del placement
    nodes, curves, rejoined = rejoin_skipped_stretches(P, h, nodes, curves, prm.link)  # 8c. skipped stretches
    params_out["stretches_rejoined"] = rejoined
    nodes, curves, twigs = split_excursions(P, h, nodes, curves, noise, prm.min_spur)  # 8d. excursions
    params_out["excursions_split"] = twigs
    curves, walked = walk_into_junctions(P, h, nodes, curves, prm.link, prm.shell_outer, noise)  # 8e. walk-ins
    params_out["ends_walked"] = walked
    tm["assemble"] = time.perf_counter() - t1

    fitted = (not clean) if prm.fit is None else prm.fit
    params_out["fit"] = fitted
    fit = None
    if fitted:  # 8b. under noise: the curves fitted (same samples, same input indices)
        report_stage(on_stage, ROBUST_SHARES, "fit")
        t1 = time.perf_counter()
        params_out["smoothing"] = prm.smoothing
        fit = functools.partial(fit_curves, sigma=sigma, band=prm.smoothing)
        curves = fit(curves)
        tm["fit"] = time.perf_counter() - t1
    added = 0
    if not clean:  # 9. under noise: branches the network leaves unexplained (fitted like the others)
        report_stage(on_stage, ROBUST_SHARES, "branches")
        t1 = time.perf_counter()
        nodes, curves, added = add_unexplained_branches(P, h, nodes, curves, noise, prm.link, prm.min_spur, fit)
        tm["branches"] = time.perf_counter() - t1
    params_out["branches_added"] = added
    del P, h
    _to_input_ids(curves, order)
    del order
    params_out["groups_histogram"] = groups_histogram
    return CurveNetwork(nodes, curves, params_out, {"time": tm})


def _internal_order(P0: np.ndarray) -> np.ndarray:
    """The internal numbering: sorted by coordinates (so that nothing depends on the input
    order); large clouds then cell by cell of a grid, so that near points get near ids and every
    per-point stage reads memory nearly in sequence (still a function of the point set alone)."""
    order = lex_order(P0)
    if len(P0) > LAYOUT.local_min:
        order = order[locality_order(P0[order])]
    return order


def _without_duplicates(P, order, nb, fr, prm: RobustParams, est: Estimates | None):
    """Points, internal order, neighbours and frames without the noise-free samples repeated in
    one place (see :func:`.frames.duplicates`): those are dropped and stages 1-2 redone on the
    rest; the inputs themselves when nothing is dropped."""
    keep = duplicates(nb, fr)
    if keep is None:
        return P, order, nb, fr
    P, order = P[keep], order[keep]
    nb = neighbours(P, prm)
    return P, order, nb, frames(P, nb, est)


def _without_isolated(P, order, nb, fr, prm: RobustParams):
    """Points, internal order, neighbours and frames without the points alone in space (see
    :func:`.frames.isolated`): those are dropped and stages 1-2 redone on the rest, with the
    median spacing and noise level found on all of them (those of :func:`estimate`); the inputs
    themselves when nothing is dropped. When fewer than ``DEFAULTS.min_points`` are left, the
    neighbours and frames are None (no network)."""
    keep = isolated(nb, fr.hmed)
    if keep is None:
        return P, order, nb, fr
    P, order = P[keep], order[keep]
    if len(P) < DEFAULTS.min_points:
        return P, order, None, fr
    nb = neighbours(P, prm)
    return P, order, nb, frames(P, nb, Estimates(fr.hmed, fr.sigma))


def _spacing_report(prm: RobustParams, h: np.ndarray, fr) -> dict:
    """The estimated spacing (median, range) and noise level, as reported in ``parameters``."""
    out: dict = {}
    if prm.spacing is None:
        out["spacing"] = fr.hmed
        out["spacing_range"] = [float(x) for x in np.percentile(h, [SPACING.report_lo, SPACING.report_hi])]
        out["spacing_estimated"] = True
    else:
        out["spacing"] = float(prm.spacing)
        out["spacing_estimated"] = False
    out["noise"] = fr.sigma  # estimated std of the noise per coordinate
    return out


def _to_input_ids(curves, order: np.ndarray) -> None:
    """Map the curves' internal point ids back to input ids (all curves at once)."""
    if not curves:
        return
    ind = np.concatenate([c.indices for c in curves])
    ind = np.where(ind >= 0, order[np.maximum(ind, 0)], -1)
    off = np.r_[0, np.cumsum([len(c.indices) for c in curves])].tolist()
    for i, c in enumerate(curves):
        c.indices = ind[off[i]:off[i + 1]]


class PointEstimates(NamedTuple):
    """The per-point values whose medians are the whole-cloud :class:`Estimates`.

    Each is a function of the point's k nearest neighbours alone, so a part of the cloud (a tile
    with a halo) computes them exactly for its points whose neighbourhood it holds
    (``reach``): the medians over the parts are then the whole cloud's estimates exactly.

    Attributes
    ----------
    order : (M,) ndarray of int64
        The input ids of the points the values are for (the points kept: all of them, or those
        left after the duplicate rule), in the internal order.
    h : (M,) ndarray
        Local spacing; ``Estimates.hmed`` is its median.
    rms : (M,) ndarray
        Noise estimate (NaN where there is none); ``Estimates.sigma`` is its median over the
        finite values (0 when none is).
    earlier : (M,) ndarray
        Distance to the nearest of the k neighbours that comes earlier in the internal order
        (inf when none does): the point is a duplicate at radius ``r`` iff ``earlier < r``.
    reach : (M,) ndarray
        Distance to the k-th neighbour: every value above looks no farther.
    """

    order: np.ndarray
    h: np.ndarray
    rms: np.ndarray
    earlier: np.ndarray
    reach: np.ndarray


class Prepared(NamedTuple):
    """A cloud with the method's first stages done: what depends on each point's neighbours
    alone and on no whole-cloud value (:func:`prepare`). :func:`reconstruct_robust` continues
    from it; a tile of a tiled run prepares itself once, for the whole-cloud estimates and for
    its reconstruction.

    Attributes
    ----------
    points : (N, d) ndarray of float64
        The points, in the internal order.
    order : (N,) ndarray of int64
        Their input rows.
    idx : (N, k) ndarray of int32
        Ids of the k nearest neighbours (self excluded), by ascending distance.
    h : (N,) ndarray
        Local spacing (or the given spacing everywhere).
    tangents : Tangents
        Stage 2's per-point values before its whole-cloud decisions.
    k : int
        Neighbours per point.
    spacing : float or None
        The spacing given (None: estimated per point).
    """

    points: np.ndarray
    order: np.ndarray
    idx: np.ndarray
    h: np.ndarray
    tangents: Tangents
    k: int
    spacing: float | None


def _prepare(P0: np.ndarray, prm: RobustParams) -> tuple[Prepared, np.ndarray]:
    """The :class:`Prepared` cloud of the points ``P0`` (N, d), and its (N, k) neighbour distances."""
    order = _internal_order(P0)
    return _prepare_ordered(P0[order], order, prm)


def _prepare_ordered(P: np.ndarray, order: np.ndarray, prm: RobustParams) -> tuple[Prepared, np.ndarray]:
    """:func:`_prepare` of points ``P`` (N, d) already in their internal order (input rows ``order``)."""
    nb, dist = neighbours_and_distances(P, prm)
    tg = point_tangents(P, nb)
    return Prepared(P, order, nb.idx, nb.h, tg, prm.k, prm.spacing), dist


def _values(prep: Prepared, dist: np.ndarray) -> PointEstimates:
    """The :class:`PointEstimates` of a prepared cloud with its neighbour distances (N, k)."""
    rows = np.arange(len(prep.points))[:, None]
    earlier = np.where(prep.idx < rows, dist, np.inf).min(axis=1)
    return PointEstimates(prep.order, prep.h, prep.tangents.rms, earlier, dist[:, -1].copy())


def prepare(points, *, spacing: float | None = None, k: int | None = None) -> tuple[Prepared, PointEstimates]:
    """The points with the method's first stages done, and their per-point values.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
    spacing, k : optional
        As for :func:`reconstruct_robust` (which must then be given the same).

    Returns
    -------
    Prepared
        ``reconstruct_robust(prepared, ...)`` gives the network ``reconstruct_robust(points,
        ...)`` gives.
    PointEstimates
        What :func:`point_estimates` gives on ``points`` (without the duplicate rule).
    """
    P0 = as_points(points)
    prm = RobustParams.from_keywords(spacing=spacing, k=k)
    if len(P0) < DEFAULTS.min_points:
        raise InputError(f"need at least {DEFAULTS.min_points} points to estimate a spacing, got {len(P0)}")
    with _k.compiled_for(len(P0)):
        prep, dist = _prepare(P0, prm)
    return prep, _values(prep, dist)


def point_estimates(points, *, dedup_radius: float | None = None, spacing: float | None = None,
                    k: int | None = None) -> PointEstimates:
    """The per-point values of :class:`PointEstimates` on ``points``.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
    dedup_radius : float, optional
        First drop the duplicates at this radius (the points with an earlier neighbour closer
        than it, see :func:`.frames.coincident`), then compute the values on the rest.
    spacing, k : optional
        As for :func:`reconstruct_robust` (the user's spacing is every point's ``h``).

    Returns
    -------
    PointEstimates
    """
    if dedup_radius is None:
        return prepare(points, spacing=spacing, k=k)[1]
    P0 = as_points(points)
    prm = RobustParams.from_keywords(spacing=spacing, k=k)
    if len(P0) < DEFAULTS.min_points:
        raise InputError(f"need at least {DEFAULTS.min_points} points to estimate a spacing, got {len(P0)}")
    with _k.compiled_for(len(P0)):
        order = _internal_order(P0)
        P = P0[order]
        nb, _ = neighbours_and_distances(P, prm)
        keep = ~coincident(nb, dedup_radius)
        del nb
        # (the kept points keep their order, as the method's duplicate rule keeps it)
        prep, dist = _prepare_ordered(P[keep], order[keep], prm)
    return _values(prep, dist)


def estimate(points, *, spacing: float | None = None, k: int | None = None) -> Estimates:
    """The whole-cloud estimates the method takes its decisions from (see :class:`Estimates`).

    The very values :func:`reconstruct_robust` computes on ``points``: running it on any part
    of them with ``estimates=estimate(points)`` takes those decisions as the whole would. They
    are the medians of :func:`point_estimates`, taken twice when the duplicate rule drops
    points (:func:`dedup_radius`, :func:`dedup_applies`); a tiled run takes the same medians
    over its tiles.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
    spacing, k : optional
        As for :func:`reconstruct_robust`.

    Returns
    -------
    Estimates
    """
    v = point_estimates(points, spacing=spacing, k=k)
    first = Estimates(median_spacing(v.h), median_noise(v.rms))
    r = dedup_radius(first)
    if r is None or not dedup_applies(len(v.h), int(np.count_nonzero(v.earlier < r))):
        return first
    v = point_estimates(points, dedup_radius=r, spacing=spacing, k=k)
    return Estimates(median_spacing(v.h), median_noise(v.rms))
