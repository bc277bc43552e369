"""Geometry under noise: how far the curves of ``robust`` lie from the true curves, without and
with the fit of stage 8 (issue 25).

Usage::

    python benchmarks/fit_eval.py [--models cube,knot] [--conditions "noise 0.2h"]
    python benchmarks/fit_eval.py --quick        # two models, one condition (CI-sized)
    python benchmarks/fit_eval.py --timing 100000 # the fit's time against the whole run's
    python benchmarks/fit_eval.py --samplings 4   # each model sampled 4 times (seed offsets 0-3)

For every synthetic model (:data:`curvenet.synth.MODELS`) and noisy condition, the points are
sampled as the benchmark does (same seeds) and reconstructed twice: ``fit=False`` (the curves
are the input samples: *before*) and the default (fitted under noise: *after*). Each network's
curves are sampled every h / 10 and the exact distance of every sample to the nearest true
curve is measured (:func:`curvenet.metrics.deviation`): its mean along arc length and its
largest value, in units of h. The target: a mean at most half the noise's standard deviation.
The two runs must have the same topology (nodes, curves, end nodes and input indices): the
script says so, or exits 1. With ``--samplings N`` each model is sampled N times (the
benchmark's seed plus 0 to N - 1): the table then reads each model's mean over its samplings
(one sampling moves a model's mean by several hundredths of h), and a second table gives each
model's mean and worst sampling in units of the noise's standard deviation.

The summary is the markdown table of docs/method.md (stage 8). ``--timing N`` reconstructs a noisy
sampling of about N points (the tree model tiled) and prints the fit's seconds against the
whole run's and against the k=16 cKDTree query of the same points, measured in the same run.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from curvenet import synth
from curvenet.bench import run_seed
from curvenet.metrics import deviation
from curvenet.reconstruct import reconstruct

#: The noisy conditions measured: keyword arguments of :func:`curvenet.synth.sample`.
CONDITIONS = {
    "noise 0.1h": {"noise": 0.1},
    "noise 0.2h": {"noise": 0.2},
    "noise 0.3h": {"noise": 0.3},
    "noise 0.3h + density x3": {"noise": 0.3, "density_ratio": 3.0},
}


def same_topology(a, b) -> bool:
    """Same nodes, and curves with the same ends, closedness and input indices, in order."""
    return (np.array_equal(a.nodes, b.nodes) and a.n_curves == b.n_curves
            and all(x.start == y.start and x.end == y.end and x.closed == y.closed
                    and np.array_equal(x.indices, y.indices) for x, y in zip(a.curves, b.curves)))


def measure(models, conditions, samplings: int = 1) -> list[dict]:
    """One row per (model, condition, sampling): mean and max distance (h) before and after,
    topology."""
    rows = []
    for name in models:
        truth = synth.model(name)
        h = synth.h_of(truth)
        for cond, k in ((c, k) for c in conditions for k in range(samplings)):
            kw = CONDITIONS[cond]
            pts, _ = synth.sample(truth, rng=run_seed(name, cond) + k, **kw)
            before = reconstruct(pts, fit=False)
            t0 = time.perf_counter()
            after = reconstruct(pts)
            t_all = time.perf_counter() - t0
            mb, xb = deviation(before, truth, h=h)
            ma, xa = deviation(after, truth, h=h)
            rows.append(dict(model=name, condition=cond, sampling=k, noise=kw["noise"], mean_before=mb, max_before=xb,
                             mean_after=ma, max_after=xa, fitted=bool(after.parameters.get("fit")),
                             same_topology=same_topology(before, after),
                             fit_share=after.stats["time"].get("fit", 0.0) / max(t_all, 1e-12)))
            r = rows[-1]
            print(f"{name:9s} {cond:24s} s{k} mean {mb:.3f} -> {ma:.3f} h  max {xb:.2f} -> {xa:.2f} h  "
                  f"fitted {int(r['fitted'])} topology {'same' if r['same_topology'] else 'DIFFERS'}", flush=True)
    return rows


def per_model(rows) -> list[dict]:
    """The rows of each (model, condition) averaged over their samplings (one row each), with
    the worst sampling's mean after the fit (``worst_after``)."""
    keys = dict.fromkeys((r["model"], r["condition"]) for r in rows)
    out = []
    for m, c in keys:
        rs = [r for r in rows if r["model"] == m and r["condition"] == c]
        avg = {f: float(np.mean([r[f] for r in rs])) for f in ("mean_before", "max_before", "mean_after", "max_after")}
        out.append(dict(model=m, condition=c, noise=rs[0]["noise"], samplings=len(rs),
                        worst_after=max(r["mean_after"] for r in rs), **avg))
    return out


def spread(rows) -> list[str]:
    """Markdown table: each model's mean distance after the fit over its samplings and its worst
    sampling, in units of the noise's standard deviation (the target: at most 0.5), per condition."""
    pm = per_model(rows)
    conds = list(dict.fromkeys(r["condition"] for r in pm))
    out = ["| model | " + " | ".join(f"{c}: mean / worst (sd)" for c in conds) + " |",
           "|---|" + "---|" * len(conds)]
    for m in dict.fromkeys(r["model"] for r in pm):
        cells = []
        for c in conds:
            r = next(x for x in pm if x["model"] == m and x["condition"] == c)
            cells.append(f"{r['mean_after'] / r['noise']:.2f} / {r['worst_after'] / r['noise']:.2f}")
        out.append(f"| {m} | " + " | ".join(cells) + " |")
    return out


def summary(rows) -> list[str]:
    """Markdown table: per condition, the means over the models (each model's mean over its
    samplings) and the worst model."""
    rows = per_model(rows)
    out = ["| Condition | models | mean distance before (h) | after (h) | target (h) | models over target "
           "after | worst mean after (h) | max distance before (h) | after (h) |",
           "|---|---|---|---|---|---|---|---|---|"]
    for cond in dict.fromkeys(r["condition"] for r in rows):
        rs = [r for r in rows if r["condition"] == cond]
        tgt = 0.5 * rs[0]["noise"]
        worst = max(rs, key=lambda r: r["mean_after"])
        over = sum(r["mean_after"] > tgt for r in rs)
        out.append(f"| {cond} | {len(rs)} | {np.mean([r['mean_before'] for r in rs]):.3f} | "
                   f"{np.mean([r['mean_after'] for r in rs]):.3f} | {tgt:.2f} | {over} | "
                   f"{worst['mean_after']:.3f} ({worst['model']}) | {np.mean([r['max_before'] for r in rs]):.2f} | "
                   f"{np.mean([r['max_after'] for r in rs]):.2f} |")
    return out


def timing(n: int) -> None:
    """The fit's time against the whole run and the k=16 cKDTree query, on about ``n`` points."""
    from scipy.spatial import cKDTree

    truth = synth.model("tree")
    h = synth.h_of(truth)
    base, _ = synth.sample(truth, rng=1, noise=0.2)
    span = np.ptp(base, axis=0).max() * 1.5
    reps = max(int(np.ceil(n / len(base))), 1)
    side = int(np.ceil(reps ** (1 / 3)))
    shifts = np.array([(i, j, k) for i in range(side) for j in range(side) for k in range(side)][:reps]) * span
    rng = np.random.default_rng(2)
    P = np.vstack([synth.sample(truth, rng=int(rng.integers(1 << 30)), noise=0.2)[0] + s for s in shifts])
    t0 = time.perf_counter()
    cKDTree(P).query(P, k=16)
    t_ref = time.perf_counter() - t0
    t0 = time.perf_counter()
    net = reconstruct(P)
    t_all = time.perf_counter() - t0
    t_fit = net.stats["time"].get("fit", 0.0)
    print(f"{len(P):,} points (h {h:g}), {net.n_curves:,} curves: whole run {t_all:.2f} s, fit {t_fit:.3f} s "
          f"({100 * t_fit / t_all:.1f}% of the run), k=16 cKDTree query {t_ref:.2f} s (fit / query "
          f"{t_fit / t_ref:.2f})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="")
    ap.add_argument("--conditions", default="")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--timing", type=int, default=0, metavar="N")
    ap.add_argument("--samplings", type=int, default=1, metavar="N", help="samplings per model (seed offsets 0 to N - 1)")
    args = ap.parse_args(argv)
    if args.timing:
        timing(args.timing)
        return 0
    models = args.models.split(",") if args.models else (["crossing", "knot"] if args.quick else list(synth.MODELS))
    conds = args.conditions.split(",") if args.conditions else (["noise 0.3h"] if args.quick else list(CONDITIONS))
    if args.samplings < 1:
        ap.error("--samplings must be at least 1")
    rows = measure(models, conds, args.samplings)
    print("\n".join(summary(rows)))
    if args.samplings > 1:
        print("\n".join(spread(rows)))
    if not all(r["same_topology"] for r in rows):
        print("the fit changed the topology of: " + ", ".join(f"{r['model']} / {r['condition']}"
                                                                for r in rows if not r["same_topology"]))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
