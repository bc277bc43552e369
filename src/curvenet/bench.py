"""The benchmark: methods x ground-truth models x sampling conditions, scored by the metrics.

Reproduces the paper's Table 1 (N_n, N_c, N_d, parameters, time per model) with quality
columns from :func:`curvenet.metrics.compare`, for every method of
:data:`curvenet.reconstruct.METHODS`, plus ``paper-tuned``: the paper's method with its
parameters (ε, τ_S, θ) chosen per model by a grid search against the ground truth on the clean
sampling (an *oracle* tuning: an upper bound of what trial and error could reach, then used for
every condition of that model).

``curvenet bench --out docs`` regenerates ``docs/benchmarks.md``, ``docs/benchmarks.json`` and
the figures in ``docs/img``. This module computes; the figures of :mod:`curvenet.plots.bench_figures`
only draw the data it hands them (:func:`eps_sweep`, :func:`method_vs_emst`).
"""

from __future__ import annotations

import importlib
import json
import os
import platform
import sys
import time
import zlib
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from . import synth
from .errors import InputError
from .metrics import compare
from .reconstruct import METHODS, reconstruct

__all__ = [
    "CONDITIONS",
    "run_seed",
    "EXTRA_CONDITIONS",
    "REALDEV_CONDITIONS",
    "QUICK_MODELS",
    "PAPER_GRID",
    "available_methods",
    "tune_paper",
    "run_bench",
    "run_cassie",
    "run_kinds",
    "run_realdev",
    "run_outliers",
    "OUTLIER_CONDITION",
    "OUTLIER_TARGET",
    "eps_sweep",
    "method_vs_emst",
    "summarize",
    "head_to_head",
    "write_markdown",
    "write_json",
    "machine",
    "run_all",
]

#: Sampling conditions: keyword arguments of :func:`curvenet.synth.sample`.
CONDITIONS: dict[str, dict[str, float]] = {
    "clean": {},
    "noise 0.2h": {"noise": 0.2},
    "density x3": {"density_ratio": 3.0},
    "noise 0.3h + density x3": {"noise": 0.3, "density_ratio": 3.0},
}

#: Further conditions that can be named (``--conditions``) but are not run by default.
EXTRA_CONDITIONS: dict[str, dict[str, float]] = {
    "outliers 2%": {"outliers": 0.02},
    "noise 0.1h": {"noise": 0.1},
    "outliers 2% + noise 0.1h": {"outliers": 0.02, "noise": 0.1},
}

#: Condition of the outlier table (:func:`run_outliers`): outliers, 2% of the curve samples,
#: uniform in the curves' bounding box, on samples with noise 0.1 h (issue 25's target condition).
OUTLIER_CONDITION = "outliers 2% + noise 0.1h"

#: Curve F1 every model should reach under :data:`OUTLIER_CONDITION` (issue 25's target; the
#: outlier table counts the models at or above it).
OUTLIER_TARGET = 0.98

#: Conditions of the real-dev table (:func:`run_realdev`).
REALDEV_CONDITIONS = ("clean", "noise 0.2h")

#: Models of ``--quick``: two small ones.
QUICK_MODELS = ("crossing", "cube")

#: The oracle grid of ``paper-tuned``: ε values, τ_S in units of h, θ in degrees.
PAPER_GRID = {
    "epsilon": (1e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 1e-1),
    "tau_s": (3.0, 5.0, 8.0, 12.0),
    "theta": (120.0, 150.0),
}
_QUICK_GRID = {"epsilon": (1e-3, 1e-2, 3e-2), "tau_s": (5.0, 8.0), "theta": (120.0,)}

#: Order in which methods are shown.
_ORDER = ("robust", "paper-tuned", "paper", "emst")

_QUALITY = ("node_f1", "curve_f1", "exact_topology", "node_offset_h", "coverage", "chamfer_h")


def run_seed(*parts: str) -> int:
    """The sampling seed of a benchmark run named by ``parts`` (e.g. model and condition): the
    CRC-32 of the parts joined by ``/``, so every script that repeats a run samples the same
    points (``benchmarks/robust_digests.py`` does)."""
    return zlib.crc32("/".join(parts).encode())


def available_methods() -> list[str]:
    """Methods whose module imports, in display order, plus ``paper-tuned`` when ``paper`` is."""
    names = []
    for m in METHODS:
        try:
            importlib.import_module(METHODS[m][0])
        except ImportError:
            continue
        names.append(m)
    if "paper" in names:
        names.append("paper-tuned")
    return sorted(names, key=lambda m: (_ORDER.index(m) if m in _ORDER else len(_ORDER), m))


def _score_key(m: dict[str, Any]):
    off = m["node_offset_h"]
    return (m["curve_f1"], m["node_f1"], m["exact_topology"], -(off if np.isfinite(off) else 1e9))


def tune_paper(points: np.ndarray, truth, *, h: float, grid: dict | None = None) -> tuple[dict, dict]:
    """Oracle grid search of the paper's parameters against the ground truth.

    Parameters
    ----------
    points : (N, d) ndarray
        Samples of ``truth``.
    truth : CurveNetwork
        The ground truth.
    h : float
        The sampling spacing (``tau_s`` of the grid is in units of h).
    grid : dict, optional
        ``{"epsilon": [...], "tau_s": [...], "theta": [...]}``; default :data:`PAPER_GRID`.

    Returns
    -------
    params : dict
        The best parameters (``epsilon``, ``tau_s`` absolute, ``theta``) among the method's
        defaults and the grid: highest curve F1, then node F1, then exact topology, then least
        node offset; the first tried on ties (the defaults first).
    metrics : dict
        Their scores.
    """
    grid = grid or PAPER_GRID
    best, best_m = None, None
    settings = [{}]  # the method's own defaults first: tuned is never worse than fixed
    for eps in grid["epsilon"]:
        for tau in grid["tau_s"]:
            for th in grid["theta"]:
                settings.append({"epsilon": eps, "tau_s": tau * h, "theta": th})
    for p in settings:
        try:
            net = reconstruct(points, method="paper", **p)
        except Exception:  # a failing setting is just a bad one
            continue
        m = compare(net, truth, h=h)
        if best is None or _score_key(m) > _score_key(best_m):
            best, best_m = {k: net.parameters[k] for k in ("epsilon", "tau_s", "theta")}, m
    if best is None:
        best, best_m = {}, {}
    return best, best_m


def _fmt_params(params: dict) -> str:
    items = []
    for k, v in params.items():
        if k in ("method", "use_numba"):
            continue
        if isinstance(v, float):
            v = f"{v:.3g}"
        elif isinstance(v, (list, tuple, dict)):
            continue
        items.append(f"{k}={v}")
    return ", ".join(items[:6])


def _run_one(method: str, points, truth, h, params: dict) -> dict[str, Any]:
    name = "paper" if method == "paper-tuned" else method
    row: dict[str, Any] = {"method": method, "N_d": int(len(points))}
    t0 = time.perf_counter()
    try:
        net = reconstruct(points, method=name, **params)
    except Exception as exc:  # report, do not stop the benchmark
        row.update(error=f"{type(exc).__name__}: {exc}", time=time.perf_counter() - t0, N_n=0, N_c=0)
        row.update(compare(_empty_like(truth), truth, h=h))
        row["parameters"] = dict(params)
        return row
    row["time"] = float(net.stats.get("time", {}).get("total", time.perf_counter() - t0))
    row["N_n"], row["N_c"] = net.n_nodes, net.n_curves
    row["parameters"] = {k: v for k, v in net.parameters.items() if k != "method"}
    row["error"] = None
    row.update(compare(net, truth, h=h))
    return row


def _scored_row(method: str, points, truth, params: dict, **fields) -> dict[str, Any]:
    """:func:`_run_one`'s row (scored at the spacing ``fields["h"]``) with ``fields``
    (``dataset``, ``model``, ``condition``, ``h``, ..., in that order) and the truth's counts
    after contraction (``true_N_n``, ``true_N_c``)."""
    row = _run_one(method, points, truth, fields["h"], params)
    row.update(fields)
    row["true_N_n"], row["true_N_c"] = row["n_nodes_true"], row["n_curves_true"]
    return row


def _checked_conditions(conditions: Iterable[str] | None, default: Iterable[str]) -> tuple[list[str], dict]:
    """``conditions`` (default ``default``) as a list, each a key of :data:`CONDITIONS` or
    :data:`EXTRA_CONDITIONS` (InputError otherwise), and those two tables in one."""
    allc = {**CONDITIONS, **EXTRA_CONDITIONS}
    conditions = list(conditions) if conditions is not None else list(default)
    for c in conditions:
        if c not in allc:
            raise InputError(f"unknown condition {c!r}; expected one of: {', '.join(allc)}")
    return conditions, allc


def _empty_like(truth):
    """An empty network of the dimension of ``truth`` (what a failed run is scored as)."""
    from .network import CurveNetwork

    return CurveNetwork(np.zeros((0, truth.dimension)), [])


def run_bench(
    methods: Iterable[str] | None = None,
    models: Iterable[str] | None = None,
    conditions: Iterable[str] | None = None,
    *,
    quick: bool = False,
    tune_on: str = "clean",
    seed: int = 0,
    progress=None,
) -> list[dict[str, Any]]:
    """Run methods on sampled synthetic models and score them.

    Parameters
    ----------
    methods : iterable of str, optional
        Names from :data:`curvenet.reconstruct.METHODS` and ``"paper-tuned"``; default
        :func:`available_methods`. Unknown names raise InputError; a method whose module
        cannot be imported is skipped.
    models : iterable of str, optional
        Names from :data:`curvenet.synth.MODELS` or :data:`curvenet.synth.KIND_MODELS` (rows of
        the latter have ``dataset = "kinds"``); default all of :data:`curvenet.synth.MODELS`
        (``QUICK_MODELS`` if quick).
    conditions : iterable of str, optional
        Keys of :data:`CONDITIONS` or :data:`EXTRA_CONDITIONS`; default all of
        :data:`CONDITIONS`.
    quick : bool
        Small run for CI: two small models and a 6-point tuning grid.
    tune_on : {"clean", "each"}
        Where ``paper-tuned`` is tuned: once per model on the clean sampling (then used for
        every condition), or on every (model, condition) sample (a stronger oracle, four
        times the cost).
    seed : int
        Added to the per-(model, condition) seed of the sampler.
    progress : callable, optional
        Called with a one-line message after every run.

    Returns
    -------
    list of dict
        One row per (model, condition, method): ``dataset``, ``model``, ``condition``,
        ``method``, ``h``, truth counts ``true_N_n`` and ``true_N_c`` (after contraction),
        ``N_n``, ``N_c``, ``N_d``, ``parameters``, ``time`` (s), ``error`` (None or message)
        and every value of :func:`curvenet.metrics.compare`; ``paper-tuned`` rows also have
        ``tuned_on`` (the condition the parameters were tuned on).
    """
    methods = _check_methods(methods)
    models = list(models) if models is not None else list(QUICK_MODELS if quick else synth.MODELS)
    for m in models:
        if m not in synth.MODELS and m not in synth.KIND_MODELS:
            raise InputError(f"unknown model {m!r}; expected one of: {', '.join([*synth.MODELS, *synth.KIND_MODELS])}")
    conditions, allc = _checked_conditions(conditions, CONDITIONS)
    if tune_on not in ("clean", "each"):
        raise InputError(f"tune_on must be 'clean' or 'each', got {tune_on!r}")
    grid = _QUICK_GRID if quick else PAPER_GRID
    rows = []
    for name in models:
        truth = synth.model(name)
        h = synth.h_of(truth)
        tuned = None
        for cond in conditions:
            pts, _ = synth.sample(truth, rng=run_seed(name, cond) + seed, **allc[cond])
            if tune_on == "each":
                tuned = None
            for method in methods:
                params: dict[str, Any] = {}
                if method == "paper-tuned":
                    if tuned is None:
                        if tune_on == "each":
                            tuned, _ = tune_paper(pts, truth, h=h, grid=grid)
                        else:
                            clean, _ = synth.sample(truth, rng=run_seed(name, "clean") + seed)
                            tuned, _ = tune_paper(clean, truth, h=h, grid=grid)
                    params = dict(tuned)
                row = _scored_row(method, pts, truth, params,
                                  dataset="synthetic" if name in synth.MODELS else "kinds", model=name,
                                  condition=cond, h=h)
                if method == "paper-tuned":
                    row["tuned_on"] = "clean" if tune_on == "clean" else cond
                rows.append(row)
                if progress:
                    progress(_line(row))
    return rows


def run_cassie(
    methods: Iterable[str] | None = None,
    names: Iterable[str] | None = None,
    *,
    h: float = 0.002,
    tune: bool = True,
    max_points: int | None = 50000,
    progress=None,
    dataset: str = "cassie",
) -> list[dict[str, Any]]:
    """Run methods on the CASSIE free creations sampled cleanly at spacing ``h`` (metres).

    Parameters
    ----------
    methods, progress
        As for :func:`run_bench`.
    names : iterable of str, optional
        Sketch names; default :data:`curvenet.synth.cassie.FREE_CREATIONS`.
    h : float
        Sampling spacing, 2 mm by default.
    tune : bool
        Run ``paper-tuned`` (a 6-point oracle grid per sketch: ε in {1e-3, 1e-2, 3e-2},
        τ_S in {5, 8} h, θ = 120).
    max_points : int or None
        Skip sketches with more samples (reported as skipped rows) to bound the run time.
    dataset : str
        The rows' ``dataset`` (``"cassie-study"`` for :func:`curvenet.synth.cassie.study_sketches`).

    Returns
    -------
    list of dict
        Rows as :func:`run_bench` (``dataset``, ``condition = "clean"``), plus
        ``gap_h``: the smallest distance between two true curves that share no node, in h
        (``inf`` when over 10 h). An empty list when the dataset is missing.
    """
    from .synth import cassie

    if not cassie.available():
        return []
    methods = [m for m in _check_methods(methods) if tune or m != "paper-tuned"]
    names = list(names) if names is not None else list(cassie.FREE_CREATIONS)
    rows = []
    for name in names:
        truth = cassie.load(name)
        gap = cassie.min_separation(truth, within=10 * h) / h
        pts, _ = synth.sample(truth, h=h, rng=run_seed("cassie", name))
        tuned = None
        for method in methods:
            if max_points is not None and len(pts) > max_points:
                row = {"method": method, "N_d": int(len(pts)), "error": f"skipped: {len(pts)} points > {max_points}"}
                row.update(dataset=dataset, model=name, condition="clean", h=h, gap_h=gap)
                row["true_N_n"], row["true_N_c"] = truth.n_nodes, truth.n_curves
                rows.append(row)
                continue
            params: dict[str, Any] = {}
            if method == "paper-tuned":
                if tuned is None:
                    tuned, _ = tune_paper(pts, truth, h=h, grid=_QUICK_GRID)
                params = dict(tuned)
            row = _scored_row(method, pts, truth, params, dataset=dataset, model=name, condition="clean",
                              h=h, gap_h=gap)
            rows.append(row)
            if progress:
                progress(_line(row))
    return rows


#: CASSIE sampling spacing of the surfacing section (metres), as :func:`run_cassie`'s default.
SURFACING_CASSIE_H = 0.002


def surfacing_available() -> bool:
    """Whether the surfacing section can run: the ``surface`` extra (triangle, pymeshlab,
    libigl) is installed."""
    import importlib.util

    return all(importlib.util.find_spec(m) is not None for m in ("triangle", "pymeshlab", "igl"))


def run_surfacing(names: Iterable[str] | None = None, cassie_names: Iterable[str] | None = None, *,
                  progress=None) -> list[dict[str, Any]]:
    """Surface the default method's networks and check the meshes (issue 24).

    The networks drawn on known surfaces (:mod:`curvenet.synth.surfaces`), each sampled once at
    its spacing h and reconstructed by ``robust``, are surfaced and measured against the true
    surface (:func:`curvenet.surfacing.evaluation.surface_row`); a model with an opening is
    surfaced a second time with it named, as a designer would (``"(opening given)"``). Then the
    CASSIE free creations (when the dataset is found), sampled at 2 mm as :func:`run_cassie`
    samples them, reconstructed and surfaced: they have no true surface, so their rows hold the
    checks and times only.

    Parameters
    ----------
    names : iterable of str, optional
        Surface models (default: all of :func:`curvenet.synth.surfaces.surface_model_names`).
    cassie_names : iterable of str, optional
        CASSIE sketches (default: :data:`curvenet.synth.cassie.FREE_CREATIONS`; empty: none).
    progress : callable, optional
        Called with one line per row.

    Returns
    -------
    list of dict
        The rows of :func:`curvenet.surfacing.evaluation.surface_row`; an empty list without the
        ``surface`` extra (:func:`surfacing_available`).
    """
    from .reconstruct import reconstruct
    from .surfacing.evaluation import open_curve_ids, surface_row
    from .synth import cassie, surfaces

    if not surfacing_available():
        return []
    rows = []

    def done(row):
        rows.append(row)
        if progress:
            progress(f"surfacing {row['set']:8s} {row['model']:24s} patches {row['patches']:4d}  "
                     f"self-intersecting {row['self_x']}  genus {row['genus']}  {row['time']:.1f}s")

    for name in (list(names) if names is not None else surfaces.surface_model_names()):
        model = surfaces.surface_model(name)
        h = synth.h_of(model.network)
        pts, _ = synth.sample(model.network, rng=run_seed(name, "clean"))
        net = reconstruct(pts)
        done(surface_row("surfaces", name, net, model, h)[0])
        ids = open_curve_ids(model, net, h)
        if ids:
            done(surface_row("surfaces", f"{name} (opening given)", net, model, h, open_curves=ids)[0])
    if cassie.available():
        for name in (list(cassie_names) if cassie_names is not None else list(cassie.FREE_CREATIONS)):
            pts, _ = synth.sample(cassie.load(name), h=SURFACING_CASSIE_H, rng=run_seed("cassie", name))
            done(surface_row("cassie", name, reconstruct(pts))[0])
    return rows


def _surfacing_lines(rows: list[dict]) -> list[str]:
    """The surfacing section of the report (issue 24)."""
    from .surfacing.evaluation import HAUSDORFF_TARGET, MEAN_TARGET

    if not rows:
        return []
    L = ["", "## Surfacing (`curvenet surface` on the default method's networks)", "",
         "Networks drawn on known surfaces (`curvenet.synth.surfaces`), sampled at their spacing h and "
         "reconstructed by `robust`, then surfaced; distances in units of h both ways (mesh vertices to the "
         "true surface; samples of the true surface to the mesh, libigl); the Hausdorff distance is the "
         f"larger of the two largest. Issue 24's targets: mean (mesh to truth) at most {MEAN_TARGET:g} h and "
         f"Hausdorff at most {HAUSDORFF_TARGET:g} h on each, 0 self-intersecting faces and 0 non-manifold edges. "
         "Self-intersections: MeshLab's test confirmed by libigl's. A model with an opening is surfaced a "
         "second time with it named (`--open`, \"opening given\"): the network alone does not say which rings "
         "are openings (docs/surfacing.md). Time: `curvenet.surface` alone, and over a k=16 cKDTree query of "
         "the network's curve points in the same run. The table of every CASSIE sketch (free creations and "
         "study) is docs/surfacing-table.md.", "",
         "| set | model | nodes | curves | patches (true) | boundary loops (true) | self-intersecting faces | "
         "non-manifold edges | overlapping patch pairs | genus | mesh to truth, mean / max (h) | truth to mesh, "
         "mean / max (h) | Hausdorff (h) | targets | time (s) | time / ref |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        d = r.get("distances")
        tp = f" ({r['true_patches']})" if "true_patches" in r else ""
        tb = f" ({r['true_boundary_loops']})" if "true_boundary_loops" in r else ""
        L.append(f"| {r['set']} | {r['model']} | {r['nodes']} | {r['curves']} | {r['patches']}{tp} | "
                 f"{r['boundary_loops']}{tb} | {'-' if r['self_x'] is None else r['self_x']} | {r['non_manifold']} | "
                 f"{r['overlaps']} | {'-' if r['genus'] is None else r['genus']} | "
                 + (f"{d[0]:.3f} / {d[1]:.2f} | {d[2]:.3f} / {d[3]:.2f} | {r['hausdorff']:.2f} | "
                    f"{'met' if r['target'] else '**missed**'} | " if d else "- | - | - | - | ")
                 + f"{r['time']:.1f} | {r['time'] / max(r['ref'], 1e-9):.0f} |")
    clean = sum(1 for r in rows if not r["self_x"] and not r["non_manifold"] and not r["overlaps"])
    known = [r for r in rows if r.get("distances")]
    L += ["", f"Meshes without a self-intersecting face, a non-manifold edge or overlapping patches: {clean} of "
          f"{len(rows)}. Known surfaces at both targets: {sum(r['target'] for r in known)} of {len(known)}"
          + (f" (missed: {', '.join(r['model'] for r in known if not r['target'])})"
             if any(not r["target"] for r in known) else "") + "."]
    return L


def run_kinds(methods: Iterable[str] | None = None, models: Iterable[str] | None = None,
              conditions: Iterable[str] | None = None, *, seed: int = 0, progress=None) -> list[dict[str, Any]]:
    """Run methods on the synthetic analogues of real failure kinds (:mod:`curvenet.synth.kinds`).

    As :func:`run_bench` (same conditions, seeds and rows, ``dataset = "kinds"``) on the models
    of :data:`curvenet.synth.KIND_MODELS` (default all of them); ``paper-tuned`` is not run.
    """
    methods = [m for m in _check_methods(methods) if m != "paper-tuned"]
    models = list(models) if models is not None else list(synth.KIND_MODELS)
    for m in models:
        if m not in synth.KIND_MODELS:
            raise InputError(f"unknown kind model {m!r}; expected one of: {', '.join(synth.KIND_MODELS)}")
    return run_bench(methods, models, conditions, seed=seed, progress=progress)


#: Members of each family (:mod:`curvenet.synth.families`) the benchmark draws, and the
#: conditions it samples them at (those of the held-out real networks of issue 25).
FAMILY_MEMBERS = 16
FAMILY_CONDITIONS = ("clean", "noise 0.2h")


def run_families(families: Iterable[str] | None = None, members: int = FAMILY_MEMBERS,
                 conditions: Iterable[str] | None = None, *, progress=None) -> list[dict[str, Any]]:
    """Run ``robust`` on families of real-like networks drawn at random
    (:mod:`curvenet.synth.families`): members ``0 .. members - 1`` of each, sampled with
    :func:`curvenet.synth.families.sampling_seed` at each condition (default
    :data:`FAMILY_CONDITIONS`).

    Returns
    -------
    list of dict
        Rows as :func:`run_bench`'s, ``dataset = "families"``, ``model`` the member's name
        (``"facade#3"``) and ``family`` its family.
    """
    from .synth import families as fam

    names = list(families) if families is not None else list(fam.FAMILIES)
    for f in names:
        if f not in fam.FAMILIES:
            raise InputError(f"unknown family {f!r}; expected one of: {', '.join(fam.FAMILIES)}")
    conditions, allc = _checked_conditions(conditions, FAMILY_CONDITIONS)
    rows = []
    for f in names:
        for k in range(members):
            truth = fam.member(f, k)
            h = synth.h_of(truth)
            for cond in conditions:
                pts, _ = synth.sample(truth, rng=fam.sampling_seed(k), **allc[cond])
                row = _scored_row("robust", pts, truth, {}, dataset="families", family=f,
                                  model=truth.parameters["model"], condition=cond, h=h)
                rows.append(row)
                if progress:
                    progress(_line(row))
    return rows


def _family_lines(rows: list[dict]) -> list[str]:
    """The Markdown section of :func:`run_families`' rows (none: no lines)."""
    fr = [r for r in rows if r["dataset"] == "families"]
    if not fr:
        return []
    L = ["", "## Families drawn at random (`robust`)", "",
         "The models above are one network each, and a rule tuned until they pass may pass them alone. "
         "`curvenet.synth.families` draws a structure's sizes, spacings and orientation at random (facade "
         "ladders with verticals 4-5h apart, facades of storeys, street grids with blocks 4-25h, combs with "
         "teeth 4-5h apart; every member well posed: curves at least 4h long, curves sharing no node at least "
         "4h apart); each member is sampled once per condition. Mean and worst curve F1 over the members, "
         "the number with exact topology, and the members below F1 1.", "",
         "| Family | Condition | members | curve F1 | worst | exact | members below F1 1 |",
         "|---|---|---|---|---|---|---|"]
    for f in dict.fromkeys(r["family"] for r in fr):
        for c in dict.fromkeys(r["condition"] for r in fr):
            rs = [r for r in fr if r["family"] == f and r["condition"] == c]
            if not rs:
                continue
            f1 = [float(r.get("curve_f1", 0.0)) for r in rs]
            below = sorted((v, r["model"]) for v, r in zip(f1, rs) if v < 1.0)
            L.append(f"| {f} | {c} | {len(rs)} | {np.mean(f1):.3f} | {min(f1):.3f} | "
                     f"{sum(bool(r.get('exact_topology')) for r in rs)} | "
                     f"{', '.join(f'{m} {v:.2f}' for v, m in below) or 'none'} |")
    return L


def run_realdev(methods: Iterable[str] | None = None, names: Iterable[str] | None = None,
                conditions: Iterable[str] | None = None, *, seed: int = 0, progress=None) -> list[dict[str, Any]]:
    """Run methods on the real-dev networks (:mod:`curvenet.synth.realdev`) sampled at their spacing.

    Parameters
    ----------
    methods, progress
        As for :func:`run_bench` (``paper-tuned`` is not run).
    names : iterable of str, optional
        Model names; default :func:`curvenet.synth.realdev.names` (all 20).
    conditions : iterable of str, optional
        Keys of :data:`CONDITIONS` or :data:`EXTRA_CONDITIONS`; default
        :data:`REALDEV_CONDITIONS`.
    seed : int
        Added to the per-(model, condition) seed of the sampler.

    Returns
    -------
    list of dict
        Rows as :func:`run_bench` with ``dataset = "realdev"`` and ``kind`` (``"neuron"`` or
        ``"building"``). An empty list when the dataset is missing.
    """
    from .synth import realdev

    if not realdev.available():
        return []
    methods = [m for m in _check_methods(methods) if m != "paper-tuned"]
    names = list(names) if names is not None else realdev.names()
    conditions, allc = _checked_conditions(conditions, REALDEV_CONDITIONS)
    rows = []
    for name in names:
        truth = realdev.load(name)
        h = synth.h_of(truth)
        for cond in conditions:
            pts, _ = synth.sample(truth, rng=run_seed("realdev", name, cond) + seed, **allc[cond])
            for method in methods:
                row = _scored_row(method, pts, truth, {}, dataset="realdev", model=name,
                                  kind=truth.parameters["kind"], condition=cond, h=h)
                rows.append(row)
                if progress:
                    progress(_line(row))
    return rows


def run_outliers(models: Iterable[str] | None = None, kind_models: Iterable[str] | None = None,
                 realdev_names: Iterable[str] | None = None, *, seed: int = 0, progress=None) -> list[dict[str, Any]]:
    """``robust`` under :data:`OUTLIER_CONDITION` on every benchmark set: the synthetic models, the
    kind analogues and the real-dev networks (one sampling each, the seeds of their own tables).

    Parameters
    ----------
    models, kind_models, realdev_names : iterable of str, optional
        The models of each set; default all of :data:`curvenet.synth.MODELS`,
        :data:`curvenet.synth.KIND_MODELS` and :func:`curvenet.synth.realdev.names` (an empty
        list: none of that set).
    seed : int
        Added to the per-(model, condition) seed of the sampler.
    progress : callable, optional
        As for :func:`run_bench`.

    Returns
    -------
    list of dict
        Rows as :func:`run_bench` with ``dataset = "outliers"`` and ``group``, the set they come
        from (``"synthetic"``, ``"kinds"`` or ``"realdev"``).
    """
    cond = [OUTLIER_CONDITION]
    models = list(models) if models is not None else list(synth.MODELS)
    kind_models = list(kind_models) if kind_models is not None else list(synth.KIND_MODELS)
    rows = run_bench(["robust"], models, cond, seed=seed, progress=progress) if models else []
    if kind_models:
        rows += run_kinds(["robust"], kind_models, cond, seed=seed, progress=progress)
    if realdev_names is None or list(realdev_names):
        rows += run_realdev(["robust"], realdev_names, cond, seed=seed, progress=progress)
    for r in rows:
        r["group"], r["dataset"] = r["dataset"], "outliers"
    return rows


def _outlier_lines(rows: list[dict]) -> list[str]:
    """The outlier section of the report (rows of :func:`run_outliers`), empty without them."""
    out = [r for r in rows if r["dataset"] == "outliers"]
    if not out:
        return []
    L = ["", f"## Outliers ({OUTLIER_CONDITION}, `robust`)", "",
         f"Every benchmark set sampled once with noise 0.1h and outliers (2% of the samples, uniform in the curves' "
         f"bounding box; "
         f"the seeds of the sets' own tables). Issue 25's target: curve F1 at least {OUTLIER_TARGET:g} on "
         f"every model.", "",
         "| Set | models | curve F1 | worst curve F1 | at target | exact | models below target (curve F1) |",
         "|---|---|---|---|---|---|---|"]
    for g in dict.fromkeys(r["group"] for r in out):
        rs = [r for r in out if r["group"] == g]
        f1 = [float(r.get("curve_f1", 0.0)) for r in rs]
        w = int(np.argmin(f1))
        below = sorted((f, r["model"]) for f, r in zip(f1, rs) if f < OUTLIER_TARGET)
        L.append(f"| {g} | {len(rs)} | {_f(float(np.mean(f1)))} | {f1[w]:.2f} ({rs[w]['model']}) | "
                 f"{sum(f >= OUTLIER_TARGET for f in f1)} of {len(rs)} | "
                 f"{sum(bool(r.get('exact_topology')) for r in rs)} of {len(rs)} | "
                 f"{', '.join(f'{m} {f:.2f}' for f, m in below) or 'none'} |")
    return L


def eps_sweep(model: str = "tree", epsilons: Iterable[float] | None = None, *, condition: str = "clean", **params):
    """The paper's Figure 7: run its method over a range of ε on one model.

    Parameters
    ----------
    model : str
        A synthetic model name.
    epsilons : iterable of float, optional
        Values of ε; default 12 values from 1e-6 to 1e-1 (log-spaced).
    condition : str
        Sampling condition (a key of :data:`CONDITIONS`).
    **params
        Other parameters of the paper's method (``tau_s`` in absolute units, ``theta``).

    Returns
    -------
    dict
        ``model``, ``h``, ``true_N_n``, ``true_N_c`` and lists ``epsilon``, ``N_n``, ``N_c``
        (raw counts of the method's output), ``contracted_N_n``, ``contracted_N_c``,
        ``node_f1``, ``curve_f1``, ``exact_topology``.
    """
    truth = synth.model(model)
    h = synth.h_of(truth)
    pts, _ = synth.sample(truth, rng=run_seed(model, condition), **{**CONDITIONS, **EXTRA_CONDITIONS}[condition])
    eps = list(epsilons) if epsilons is not None else list(np.logspace(-6, -1, 12))
    out: dict[str, Any] = {"model": model, "h": h, "condition": condition, "params": dict(params),
                           "true_N_n": truth.n_nodes, "true_N_c": truth.n_curves}
    keys = ("epsilon", "N_n", "N_c", "contracted_N_n", "contracted_N_c", "node_f1", "curve_f1", "exact_topology")
    for k in keys:
        out[k] = []
    for e in eps:
        net = reconstruct(pts, method="paper", epsilon=float(e), **params)
        m = compare(net, truth, h=h)
        vals = (float(e), net.n_nodes, net.n_curves, m["n_nodes_found"], m["n_curves_found"], m["node_f1"],
                m["curve_f1"], m["exact_topology"])
        for k, v in zip(keys, vals):
            out[k].append(v)
    return out


def method_vs_emst(model: str = "fig8", method: str = "robust", *, condition: str = "clean") -> dict[str, Any]:
    """The paper's Figure 8: ``method`` and the EMST on the same sampling of a 2D model.

    Parameters
    ----------
    model : str
        A 2D synthetic model name (e.g. ``"fig8"``).
    method : str
        The method shown against the EMST.
    condition : str
        Sampling condition (a key of :data:`CONDITIONS`).

    Returns
    -------
    dict
        ``model``, ``condition``, ``points`` ((N, 2) ndarray, the sampling), ``true_N_n``,
        ``true_N_c`` and ``panels``: for ``method`` then ``"emst"``, a dict with ``method``,
        ``network`` (:class:`CurveNetwork`), ``curve_f1`` and ``exact_topology``.
    """
    truth = synth.model(model)
    h = synth.h_of(truth)
    pts, _ = synth.sample(truth, rng=run_seed(model, condition), **CONDITIONS[condition])
    panels = []
    for m in (method, "emst"):
        net = reconstruct(pts, method=m)
        s = compare(net, truth, h=h)
        panels.append({"method": m, "network": net, "curve_f1": s["curve_f1"],
                       "exact_topology": s["exact_topology"]})
    return {"model": model, "condition": condition, "points": pts, "true_N_n": truth.n_nodes,
            "true_N_c": truth.n_curves, "panels": panels}


def _check_methods(methods) -> list[str]:
    avail = available_methods()
    if methods is None:
        return avail
    out = []
    for m in methods:
        if m not in METHODS and m != "paper-tuned":
            raise InputError(f"unknown method {m!r}; expected some of: {', '.join(list(METHODS) + ['paper-tuned'])}")
        if m in avail:
            out.append(m)
    return out


def _line(r: dict) -> str:
    if r.get("error"):
        return f"{r['dataset']:9s} {r['model']:15s} {r['condition']:24s} {r['method']:12s} ERROR {r['error']}"
    return (
        f"{r['dataset']:9s} {r['model']:15s} {r['condition']:24s} {r['method']:12s} "
        f"nodeF1 {r['node_f1']:.2f} curveF1 {r['curve_f1']:.2f} exact {int(r['exact_topology'])} "
        f"t {r['time']:.2f}s"
    )


# ---------------------------------------------------------------------------------------------
# summaries and output
# ---------------------------------------------------------------------------------------------
def seed_spread(method: str = "robust", seeds: int = 8, models=None, conditions=None,
                progress=None) -> list[dict[str, Any]]:
    """The same benchmark on more samplings: ``seeds`` seed offsets (0 is the main tables').

    One method only (the tables above use seed offset 0 alone): how much the means depend on
    the draw of the points.

    Returns
    -------
    list of dict
        One per condition: ``condition``, ``seeds``, ``mean`` (curve F1 over every model and
        seed), ``seed0`` (the mean at offset 0), ``worst_seed`` (the lowest mean over the models
        of one seed), ``exact`` (share of exact topology) and ``misses`` (``"model sK F1"`` for
        every run below curve F1 1, worst first).
    """
    conditions = list(conditions) if conditions is not None else list(CONDITIONS)
    if method == "robust":
        # the synthetic clouds are under robust's numba threshold (2,000 points): one larger
        # cloud first makes every run below use the compiled kernels (same results, 10x faster)
        t = synth.model("torus")
        reconstruct(synth.sample(t, h=synth.h_of(t) / 4, rng=0)[0], method="robust")
    per: dict[str, list[tuple[int, dict]]] = {c: [] for c in conditions}
    for k in range(seeds):
        for r in run_bench([method], models, conditions, seed=k):
            per[r["condition"]].append((k, r))
        if progress:
            progress(f"seed spread: offset {k} done")
    out = []
    for c, rs in per.items():
        ks = np.array([k for k, _ in rs], dtype=np.int64)
        f1 = np.array([float(r.get("curve_f1", 0.0)) for _, r in rs])
        by_seed = [float(f1[ks == s].mean()) for s in range(seeds) if (ks == s).any()]
        miss = sorted((float(v), r["model"], int(k)) for k, (_, r), v in zip(ks, rs, f1) if v < 1.0)
        out.append({"condition": c, "seeds": seeds, "mean": float(f1.mean()) if len(f1) else float("nan"),
                    "seed0": by_seed[0] if by_seed else float("nan"),
                    "worst_seed": min(by_seed) if by_seed else float("nan"),
                    "exact": float(np.mean([bool(r.get("exact_topology")) for _, r in rs])) if rs else float("nan"),
                    "misses": [f"{m} s{k} {v:.2f}" for v, m, k in miss]})
    return out


def summarize(rows: list[dict]) -> list[dict[str, Any]]:
    """Means per (dataset, condition, method): node F1, curve F1, share of exact topology,
    mean node offset (h), coverage, Chamfer (h), total time; ``n`` rows, ``errors``."""
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["dataset"], r["condition"], r["method"]), []).append(r)
    out = []
    for (ds, cond, meth), rs in groups.items():
        ok = [r for r in rs if "node_f1" in r]
        s: dict[str, Any] = {"dataset": ds, "condition": cond, "method": meth, "n": len(ok),
                             "errors": sum(1 for r in rs if r.get("error"))}
        for k in _QUALITY:
            vals = [float(r[k]) for r in ok if r.get(k) is not None and np.isfinite(float(r[k]))]
            s[k] = float(np.mean(vals)) if vals else float("nan")
        s["time"] = float(sum(r.get("time", 0.0) for r in ok))
        out.append(s)
    return out


def head_to_head(rows: list[dict], method: str = "robust", others=("paper-tuned", "emst")) -> list[dict[str, Any]]:
    """``method`` against each of ``others`` on the same inputs, model by model, by curve F1.

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`run_bench` or :func:`run_cassie`.
    method : str
        The method compared.
    others : sequence of str
        The methods it is compared with (those absent from ``rows`` are skipped).

    Returns
    -------
    list of dict
        One entry per (dataset, condition, other method) with ``better``, ``same`` and ``worse``:
        lists of ``(model, F1 of method, F1 of other)``, in the order of the rows. A model where
        either run failed counts as worse for the method that failed (as same when both did).
    """
    f1: dict[tuple, float] = {}
    for r in rows:
        v = r.get("curve_f1")
        f1[(r["dataset"], r["condition"], r["model"], r["method"])] = (
            float(v) if v is not None and not r.get("error") else float("nan"))
    # (dataset, condition) -> models, in the order of the rows
    cells: dict[tuple, list[str]] = {}
    for ds, cond, model, _ in f1:
        ms = cells.setdefault((ds, cond), [])
        if model not in ms:
            ms.append(model)
    out = []
    for (ds, cond), models in cells.items():
        for o in others:
            res: dict[str, Any] = {"dataset": ds, "condition": cond, "method": method, "other": o,
                                   "better": [], "same": [], "worse": []}
            for model in models:
                if (ds, cond, model, method) not in f1 or (ds, cond, model, o) not in f1:
                    continue
                a, b = f1[(ds, cond, model, method)], f1[(ds, cond, model, o)]
                a_ok, b_ok = np.isfinite(a), np.isfinite(b)
                if a_ok and b_ok:
                    # the table's two decimals: a difference under 0.005 is shown (and counted) as same
                    kind = "same" if abs(a - b) < 0.005 else ("better" if a > b else "worse")
                else:
                    kind = "same" if a_ok == b_ok else ("better" if a_ok else "worse")
                res[kind].append((model, a, b))
            if res["better"] or res["same"] or res["worse"]:
                out.append(res)
    return out


def machine() -> dict[str, Any]:
    """The machine and software the benchmark ran on."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import scipy

    info = {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "platform": platform.platform(),
    }
    try:
        import numba

        info["numba"] = numba.__version__
    except ImportError:
        pass
    return info


def _f(x, nd=2) -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    x = float(x)
    if not np.isfinite(x):
        return "-" if np.isnan(x) else "inf"
    return f"{x:.{nd}f}"


def _table(rows: list[dict], *, gap: bool = False) -> list[str]:
    head = ["Model", "true N_n / N_c"] + (["gap (h)"] if gap else []) + [
        "Method", "N_n", "N_c", "N_d", "Parameters", "Time (s)", "node F1", "curve F1", "exact", "offset (h)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    last = None
    for r in rows:
        first = r["model"] != last
        last = r["model"]
        cells = [f"**{r['model']}**" if first else "", f"{r['true_N_n']} / {r['true_N_c']}" if first else ""]
        if gap:
            cells.append(_f(r.get("gap_h"), 1) if first else "")
        if r.get("error"):
            cells += [r["method"], "-", "-", str(r.get("N_d", "-")), r["error"][:60], "-", "-", "-", "-", "-"]
        else:
            cells += [
                r["method"], str(r["N_n"]), str(r["N_c"]), str(r["N_d"]), _fmt_params(r["parameters"]),
                _f(r["time"], 3), _f(r["node_f1"]), _f(r["curve_f1"]), _f(r["exact_topology"]),
                _f(r["node_offset_h"]),
            ]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _worst_table(rows: list[dict], group=lambda r: "") -> list[str]:
    """Per (group, condition, method): models, mean node and curve F1, the worst curve F1 (and its
    model), the number with exact topology and the mean Chamfer distance (h)."""
    cells: dict[tuple, list[dict]] = {}
    for r in rows:
        cells.setdefault((group(r), r["condition"], r["method"]), []).append(r)
    head = ["Group", "Condition", "Method", "models", "node F1", "curve F1", "worst curve F1", "exact",
            "Chamfer (h)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    for (g, c, m), rs in cells.items():
        f1 = [float(r.get("curve_f1", 0.0)) for r in rs]
        w = int(np.argmin(f1))
        ch = [float(r["chamfer_h"]) for r in rs if r.get("chamfer_h") is not None and np.isfinite(r["chamfer_h"])]
        lines.append("| " + " | ".join([
            g or "all", c, m, str(len(rs)), _f(float(np.mean([r.get("node_f1", 0.0) for r in rs]))),
            _f(float(np.mean(f1))), f"{f1[w]:.2f} ({rs[w]['model']})",
            f"{sum(bool(r.get('exact_topology')) for r in rs)} of {len(rs)}",
            _f(float(np.mean(ch))) if ch else "-"]) + " |")
    return lines


def _summary_table(summary: list[dict], dataset: str) -> list[str]:
    conds = []
    for s in summary:
        if s["dataset"] == dataset and s["condition"] not in conds:
            conds.append(s["condition"])
    head = ["Condition", "Method", "models", "node F1", "curve F1", "exact topology", "node offset (h)",
            "coverage", "Chamfer (h)", "total time (s)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    for c in conds:
        ss = [s for s in summary if s["dataset"] == dataset and s["condition"] == c]
        ss.sort(key=lambda s: (_ORDER.index(s["method"]) if s["method"] in _ORDER else 99, s["method"]))
        for i, s in enumerate(ss):
            lines.append("| " + " | ".join([
                c if i == 0 else "", s["method"], str(s["n"]), _f(s["node_f1"]), _f(s["curve_f1"]),
                f"{s['exact_topology'] * 100:.0f}%" if np.isfinite(s["exact_topology"]) else "-",
                _f(s["node_offset_h"]), _f(s["coverage"]), _f(s["chamfer_h"]), _f(s["time"], 1),
            ]) + " |")
    return lines


def _head_to_head_lines(rows: list[dict]) -> list[str]:
    """The head-to-head section of the report (:func:`head_to_head`), empty without rivals."""
    h2h = head_to_head(rows)
    if not h2h:
        return []
    names = {"synthetic": "synthetic", "cassie": "CASSIE free creations", "cassie-study": "CASSIE study"}
    L = ["", "## Head to head (curve F1, model by model)", "",
         "`robust` against `paper-tuned` and `emst` on the same points: the number of models where its "
         "curve F1 is higher, the same (to the tables' two decimals) and lower, and every model where "
         "it is not higher (F1 of `robust` / of the other).", "",
         "| Data | Condition | against | better | same | worse | not better (robust / other) |",
         "|---|---|---|---|---|---|---|"]
    for e in h2h:
        rest = [f"{m} {a:.2f} / {b:.2f}" for m, a, b in e["worse"] + e["same"]]
        L.append(f"| {names.get(e['dataset'], e['dataset'])} | {e['condition']} | {e['other']} | "
                 f"{len(e['better'])} | {len(e['same'])} | {len(e['worse'])} | {', '.join(rest) or 'none'} |")
    return L


def _spread_lines(title: str, lead: str, spread: list[dict]) -> list[str]:
    """The Markdown section of a :func:`seed_spread` result: ``title``, ``lead`` (the text before
    "with seed offsets 0 to ..."), one row per condition."""
    L = ["", title, "",
         f"{lead} with seed offsets 0 to {spread[0]['seeds'] - 1}: mean curve F1 over every model and sampling, "
         "the mean of the worst sampling, the share with exact topology, and every run below F1 1.",
         "", "| Condition | curve F1, offset 0 | curve F1, all | worst sampling | exact | runs below F1 1 |",
         "|---|---|---|---|---|---|"]
    for sp in spread:
        L.append(f"| {sp['condition']} | {sp['seed0']:.3f} | {sp['mean']:.3f} | {sp['worst_seed']:.3f} | "
                 f"{100 * sp['exact']:.0f}% | {', '.join(sp['misses']) or 'none'} |")
    return L


def write_markdown(rows: list[dict], path=None, *, figures: dict | None = None, info: dict | None = None,
                   elapsed: float | None = None, command: str | None = None, tune_on: str = "clean",
                   spread: list[dict] | None = None, kind_spread: list[dict] | None = None,
                   surfacing: list[dict] | None = None) -> str:
    """The benchmark report in Markdown (tables in the form of the paper's Table 1).

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`run_bench` and :func:`run_cassie`.
    path : str or Path, optional
        File to write (atomically); the text is returned either way.
    figures : dict, optional
        Figure name -> path relative to the Markdown file.
    info : dict, optional
        :func:`machine` (measured now when not given).
    elapsed : float, optional
        Wall time of the whole run, seconds.
    command : str, optional
        The command that produced the report.
    tune_on : {"clean", "each"}
        How ``paper-tuned`` was tuned (see :func:`run_bench`), for the text.
    spread : list of dict, optional
        :func:`seed_spread`, written as its own section.
    kind_spread : list of dict, optional
        :func:`seed_spread` on the analogues of real failure kinds, its own section too.
    surfacing : list of dict, optional
        :func:`run_surfacing`, its own section.

    Returns
    -------
    str
        The Markdown text.
    """
    info = info or machine()
    summary = summarize(rows)
    L = ["# Benchmarks", ""]
    L += [
        "Generated by `" + (command or "curvenet bench --out docs") + "`; do not edit by hand.",
        "",
        "Machine: " + f"{info['cpu']}, {info['cores']} cores; Python {info['python']}, numpy {info['numpy']}, "
        f"scipy {info['scipy']}" + (f", numba {info['numba']}" if "numba" in info else "")
        + (f". Whole run: {elapsed / 60:.1f} min (shared machine: times are indicative)." if elapsed else "."),
        "",
        "## How it is measured",
        "",
        "- **Ground truth**: `curvenet.synth` builds parametric curve networks (junctions of valence 3 to 8, free "
        "ends, closed loops without nodes including a trefoil knot, three curves between two nodes 2.5h apart, "
        "curves meeting at 30 degrees, planar networks in 3D, grids on a sphere and a torus, sharp corners, 2D "
        "networks, a crossing). Each model has a reference spacing h.",
        "- **Sampling** (`curvenet.synth.sample`): h is the mean spacing along the curves; every node is "
        "sampled once; *noise 0.2h* adds Gaussian noise of standard deviation 0.2h to every coordinate; "
        "*density x3* varies the local spacing smoothly in space between 0.67h and 2h (ratio 3); the order of "
        "the points is shuffled. Seeds are fixed: every run gives the same points.",
        "- **Scores** (`curvenet.metrics.compare`), after contracting nodes of valence 2 on both sides: node "
        "F1 with one-to-one matching within 3h; curve F1 where a found curve matches a true one when their end "
        "nodes match and their Hausdorff distance is at most 2h; *exact* when the graphs are the same under "
        "the node matching (same number of curves between every pair of matched nodes, same number of free "
        "loops); *offset* is the mean distance of matched nodes, in h.",
        "- **Methods**: `robust` is the parameter-free default; `paper` is the founding paper's method with "
        "one fixed setting (its defaults); `paper-tuned` is the same method with ε, τ_S and θ chosen per model "
        "by a grid search **against the ground truth** on the "
        + ("clean sampling" if tune_on == "clean" else "sampling of each condition") + " (ε in "
        + ", ".join(f"{e:g}" for e in PAPER_GRID["epsilon"]) + "; τ_S in "
        + ", ".join(f"{t:g}" for t in PAPER_GRID["tau_s"]) + " h; θ in "
        + ", ".join(f"{t:g}" for t in PAPER_GRID["theta"])
        + "; best curve F1, then node F1; the method's own defaults are candidates too), "
        + ("then kept for the other conditions" if tune_on == "clean" else "separately for every condition")
        + ". That is an oracle: an upper "
        "bound of what the paper's trial and error can reach, not something a user can do. `emst` is the "
        "Euclidean minimum spanning tree split at vertices of degree other than 2 (the paper's Figure 8).",
        "- Columns as the paper's Table 1: N_n nodes, N_c curves (as output, before contraction), N_d points, "
        "the parameters used (given or estimated), time in seconds; then the quality columns.",
        "- Reproduce: `curvenet bench --out docs` (the whole run, a few minutes on 2 cores); "
        "`curvenet bench --quick --out DIR` is the small version CI runs; `--methods`, `--models`, "
        "`--conditions` select parts.",
        "",
    ]
    models = []
    for r in rows:
        if r["dataset"] == "synthetic" and r["model"] not in models:
            models.append(r["model"])
    if models:
        L += ["## Synthetic models", "", "| Model | dim | nodes | curves | valences | h | what it tests |",
              "|---|---|---|---|---|---|---|"]
        for name in models:
            t = synth.model(name)
            vals = ", ".join(str(v) for v in sorted(set(t.valence.tolist()))) or "-"
            L.append(f"| {name} | {t.dimension}D | {t.n_nodes} | {t.n_curves} | {vals} | {synth.h_of(t):g} | "
                     f"{t.parameters.get('features', '')} |")
        L.append("")
    L += ["## Summary (means over the synthetic models)", ""]
    L += _summary_table(summary, "synthetic")
    if any(s["dataset"] == "cassie" for s in summary):
        L += ["", "## Summary (CASSIE free creations, 2 mm spacing)", ""]
        L += _summary_table(summary, "cassie")
    if any(s["dataset"] == "cassie-study" for s in summary):
        n = sum(1 for r in rows if r["dataset"] == "cassie-study" and r["method"] == "robust")
        L += ["", f"## Check (CASSIE user-study sketches, {n}, 2 mm spacing)", "",
              "The participants' sketches of the CASSIE user study (`sketch_graph/NN-M-K.json`). Their "
              "networks were recovered after the study from stroke intersections and, by the dataset's own "
              "account, may have errors; no target is set on them. The constants of `robust` are chosen on "
              "the synthetic models and the free creations above; these sketches check that a choice holds "
              "on drawings it was not chosen on.", ""]
        L += _summary_table(summary, "cassie-study")
    kinds = [r for r in rows if r["dataset"] == "kinds"]
    if kinds:
        names_k = list(dict.fromkeys(r["model"] for r in kinds))
        L += ["", "## Analogues of real failure kinds (synthetic)", "",
              "Models of `curvenet.synth.kinds`: the structures that real networks have and the models above "
              "lack (junctions a few spacings apart, twigs near junctions, branches that zigzag, short coplanar "
              "edges, lines leaving arcs tangentially), sampled as the models above. Not part of the means "
              "above.", "",
              "| Model | dim | nodes | curves | valences | h | what it tests |", "|---|---|---|---|---|---|---|"]
        for name in names_k:
            t = synth.model(name)
            vals = ", ".join(str(v) for v in sorted(set(t.valence.tolist()))) or "-"
            L.append(f"| {name} | {t.dimension}D | {t.n_nodes} | {t.n_curves} | {vals} | {synth.h_of(t):g} | "
                     f"{t.parameters.get('features', '')} |")
        L += [""] + _worst_table(kinds)
    real = [r for r in rows if r["dataset"] == "realdev"]
    if real:
        L += ["", "## Real networks (real-dev: neuron tracings and building wireframes)", "",
              "The 20 networks of `../shared/datasets/real-dev` (`curvenet.synth.realdev`): 10 neuron trees "
              "(SWC) and 10 LoD2 building wireframes (CityJSON), each sampled at the spacing h its file gives "
              "(every curve at least 4h long, curves sharing no node at least 4h apart), one sampling per "
              "model and condition, scored as the synthetic models.", ""]
        L += _worst_table(real, lambda r: r.get("kind", ""))
    L += _outlier_lines(rows)
    L += _family_lines(rows)
    L += _surfacing_lines(surfacing or [])
    L += _head_to_head_lines(rows)
    if spread:
        L += _spread_lines(f"## Seed spread ({spread[0]['seeds']} samplings, `robust`)", "The tables use one "
                           "sampling per model and condition (seed offset 0). The same models sampled", spread)
    if kind_spread:
        L += _spread_lines(f"## Seed spread, analogues of real failure kinds ({kind_spread[0]['seeds']} samplings, "
                           "`robust`)", "The kinds' tables above use one sampling per model and condition (seed "
                           "offset 0), which moves their means by several hundredths. The same eight models "
                           "sampled", kind_spread)
    if figures:
        L += ["", "## Figures", ""]
        for title, rel in figures.items():
            L += [f"**{title}**", "", f"![{title}]({rel})", ""]
    conds = []
    for r in rows:
        if r["dataset"] == "synthetic" and r["condition"] not in conds:
            conds.append(r["condition"])
    for c in conds:
        L += ["", f"## Synthetic models, {c}", ""]
        L += _table([r for r in rows if r["dataset"] == "synthetic" and r["condition"] == c])
    cas = [r for r in rows if r["dataset"] == "cassie"]
    if cas:
        L += [
            "",
            "## CASSIE free creations (real sketches), clean sampling at 2 mm",
            "",
            "Curve networks drawn in VR (Yu et al., CHI 2021), from `sketch_graph/*.json`: Bézier segments "
            "evaluated densely, nodes from the files, valence-2 nodes contracted. *gap (h)* is the smallest "
            "distance between two true curves that share no node: below about 3h, curves touch or nearly touch "
            "without a junction in the file, and no method can be expected to get the topology exact there. "
            "`paper-tuned` here uses a 6-point oracle grid (ε in 1e-3, 1e-2, 3e-2; τ_S in 5, 8 h; θ = 120).",
            "",
        ]
        close = sorted({r["model"] for r in cas if r.get("gap_h") is not None and r["gap_h"] < 3})
        far = sorted({r["model"] for r in cas if r.get("gap_h") is not None and r["gap_h"] >= 3})
        L += [
            f"Sketches whose true curves touch or come within 3h of each other without a junction "
            f"({len(close)}): {', '.join(close) or 'none'}. Sketches without such places: {', '.join(far) or 'none'}.",
            "",
        ]
        L += _table(cas, gap=True)
    for title, sel in (("Analogues of real failure kinds", kinds), ("Real-dev networks", real)):
        for c in dict.fromkeys(r["condition"] for r in sel):
            L += ["", f"## {title}, {c}", ""]
            L += _table([r for r in sel if r["condition"] == c])
    text = "\n".join(L) + "\n"
    if path is not None:
        _atomic_write(Path(path), text)
    return text


def write_json(rows: list[dict], path, *, extra: dict | None = None) -> None:
    """Write rows (and ``extra`` top-level entries) as JSON, atomically."""
    from .network import _jsonable

    def clean(v):
        if isinstance(v, float) and not np.isfinite(v):
            return None if np.isnan(v) else ("inf" if v > 0 else "-inf")
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        return v

    data = {"rows": clean(_jsonable(rows))}
    if extra:
        data.update(clean(_jsonable(extra)))
    _atomic_write(Path(path), json.dumps(data, indent=1))


def _atomic_write(path: Path, text: str) -> None:
    from .errors import OutputError

    if not path.parent.is_dir():
        raise OutputError(f"folder {path.parent} does not exist")
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc}") from None


def run_all(
    out,
    *,
    quick: bool = False,
    methods=None,
    models=None,
    conditions=None,
    cassie: bool = True,
    figures: bool = True,
    tune_on: str = "clean",
    progress=None,
    command: str | None = None,
    spread_seeds: int = 8,
    surfacing: bool = True,
) -> dict[str, Any]:
    """Run the benchmark and write ``benchmarks.md``, ``benchmarks.json`` and figures into ``out``.

    ``spread_seeds`` samplings of every synthetic model and condition are also scored with
    ``robust`` alone (:func:`seed_spread`; 0 or a quick run: none), and, with ``cassie`` (the
    real data and the kinds), of every model of :data:`curvenet.synth.KIND_MODELS`. With
    ``surfacing`` (and the ``surface`` extra installed) the default method's networks are
    surfaced and checked (:func:`run_surfacing`; a quick run: the saddle alone).

    Returns
    -------
    dict
        ``rows``, ``summary``, ``files`` (paths written), ``elapsed`` (s), ``surfacing`` (the rows
        of :func:`run_surfacing`).
    """
    from .errors import OutputError

    out = Path(out)
    if not out.is_dir():
        raise OutputError(f"output folder {out} does not exist")
    t0 = time.perf_counter()
    rows = run_bench(methods, models, conditions, quick=quick, tune_on=tune_on, progress=progress)
    if cassie and not quick:
        rows += run_cassie(methods, progress=progress)
        from .synth import cassie as _cassie

        study = [m for m in _check_methods(methods) if m in ("robust", "emst")]
        if study:
            rows += run_cassie(study, _cassie.study_sketches(), tune=False, progress=progress,
                               dataset="cassie-study")
    if cassie and not quick:  # the other real data and the kind analogues go with the real sketches
        rows += run_kinds(methods, conditions=conditions, progress=progress)
        rows += run_realdev(methods, progress=progress)
        if "robust" in _check_methods(methods):
            rows += run_outliers(progress=progress)
            rows += run_families(progress=progress)
    spread = kind_spread = None
    if spread_seeds and not quick and "robust" in _check_methods(methods):
        spread = seed_spread("robust", spread_seeds, models, conditions, progress=progress)
        if cassie:  # (the kinds go with the real data, above)
            kind_spread = seed_spread("robust", spread_seeds, list(synth.KIND_MODELS), conditions, progress=progress)
    surf = []
    if surfacing:
        surf = (run_surfacing(["saddle"], [], progress=progress) if quick
                else run_surfacing(cassie_names=None if cassie else [], progress=progress))
    figs: dict[str, str] = {}
    files = []
    if figures:
        from .plots import bench_figures

        img = out / "img"
        img.mkdir(exist_ok=True)
        have = available_methods()
        if "paper" in have:
            model = "tree"
            tuned = [r for r in rows if r["model"] == model and r["method"] == "paper-tuned" and not r.get("error")]
            params = {k: tuned[0]["parameters"][k] for k in ("tau_s", "theta")} if tuned else {}
            sweep = eps_sweep(model, np.logspace(-6, -1, 8 if quick else 16), **params)
            p = bench_figures.figure7(sweep, img / "bench_eps_sweep.png")
            figs[
                f"Figure 7 analogue: the paper's method on the {model} model for a range of ε"
                + (f" (τ_S = {params['tau_s'] / sweep['h']:.3g}h, θ = {params['theta']:g} as tuned)" if params else "")
            ] = f"img/{p.name}"
            files.append(p)
        default = "robust" if "robust" in have else ("paper" if "paper" in have else None)
        if default and "emst" in have:
            p = bench_figures.figure8(method_vs_emst("fig8", default), img / "bench_2d_vs_emst.png")
            figs[f"Figure 8 analogue: `{default}` against the EMST on the same 2D points"] = f"img/{p.name}"
            files.append(p)
    elapsed = time.perf_counter() - t0
    info = machine()
    md = out / "benchmarks.md"
    write_markdown(rows, md, figures=figs, info=info, elapsed=elapsed, command=command, tune_on=tune_on,
                   spread=spread, kind_spread=kind_spread, surfacing=surf)
    js = out / "benchmarks.json"
    write_json(rows, js, extra={"machine": info, "summary": summarize(rows), "elapsed": elapsed,
                                "conditions": CONDITIONS, "paper_grid": PAPER_GRID, "seed_spread": spread,
                                "seed_spread_kinds": kind_spread, "surfacing": surf})
    files = [md, js] + files
    return {"rows": rows, "summary": summarize(rows), "files": files, "elapsed": elapsed, "surfacing": surf}


if __name__ == "__main__":  # the command line lives above this module: point to it
    print("curvenet: error: run the benchmark with `curvenet bench` (or `python -m curvenet.cli bench`)",
          file=sys.stderr)
    sys.exit(2)
