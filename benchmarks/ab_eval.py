"""A/B harness of the default method: score a source tree on the development runs, compare two.

Usage::

    python benchmarks/ab_eval.py run OUT.json [--sets main,extra,cassie] [--jobs 2] [--quick]
    python benchmarks/ab_eval.py compare A.json B.json [--per-kind]

    # a variant: a copy of the source, run with PYTHONPATH
    cp -r src /tmp/variant/ && (edit /tmp/variant/src/...)
    PYTHONPATH=/tmp/variant/src python benchmarks/ab_eval.py run variant.json

``run`` scores ``robust`` (whatever ``curvenet`` the interpreter imports) on

* ``main`` (928 runs): the kinds (:data:`curvenet.synth.kinds.KIND_MODELS`) and the synthetic
  models (:data:`curvenet.synth.MODELS`) under every condition of
  :data:`curvenet.bench.CONDITIONS`, samplings 0-7 (the benchmark's seed spread), and the
  real-dev networks under :data:`curvenet.bench.REALDEV_CONDITIONS`, samplings 0-3;
* ``extra`` (352 runs): the same three sets under ``noise 0.1h`` and the outlier condition
  (:data:`curvenet.bench.OUTLIER_CONDITION`), samplings 0-3;
* ``cassie`` (320 runs): the 64 CASSIE sketches (free creations and study sketches, at 2 mm as
  :func:`curvenet.bench.run_cassie`; over 50,000 samples skipped) under the four conditions
  and the outlier condition, one sampling each;

in ``--jobs`` worker processes, and writes one row per run (set, model, condition, sampling,
curve and node F1, exact topology, node and curve counts, node offset, time) as JSON. The sets
need the datasets of ``../shared`` for real-dev and CASSIE (left out when absent).
``--quick``: two kinds at noise 0.2 h, sampling 0 (what the test runs).

``compare`` prints every run whose curve F1 moved (better or worse, with its node and curve
counts) and, per set and condition, the mean curve F1 of A and B, the exact count and how many
runs went up and down; ``--per-kind`` adds the mean and worst per kind and condition. Every
rule of the default method is measured this way before it lands (the notes of issue 25 quote
these counts); the family figures come from ``benchmarks/family_eval.py``.
"""

from __future__ import annotations

import argparse
import json
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor

import numpy as np

#: Samplings (seed offsets) of each set: the main kinds and synthetic runs, the real-dev runs,
#: and the extra conditions.
MAIN_SAMPLINGS = 8
REALDEV_SAMPLINGS = 4
EXTRA_SAMPLINGS = 4
#: The extra conditions (names of ``curvenet.bench.EXTRA_CONDITIONS``).
EXTRA = ("noise 0.1h", "outliers 2% + noise 0.1h")
#: CASSIE: spacing (metres) and the largest sketch scored, as :func:`curvenet.bench.run_cassie`.
CASSIE_H = 0.002
CASSIE_MAX_POINTS = 50_000


def tasks(sets: list[str], quick: bool = False) -> list[tuple[str, str, str, int]]:
    """The runs ``(set, model, condition, sampling)`` of the named sets."""
    from curvenet import bench, synth
    from curvenet.synth import cassie, kinds, realdev

    if quick:
        return [("kinds", m, "noise 0.2h", 0) for m in ("ladder", "tangent")]
    km, sm = list(kinds.KIND_MODELS), list(synth.MODELS)
    rm = list(realdev.names()) if realdev.available() else []
    out = []
    if "main" in sets:
        for c in bench.CONDITIONS:
            for k in range(MAIN_SAMPLINGS):
                out += [("kinds", m, c, k) for m in km] + [("synthetic", m, c, k) for m in sm]
        for c in bench.REALDEV_CONDITIONS:
            out += [("realdev", m, c, k) for k in range(REALDEV_SAMPLINGS) for m in rm]
    if "extra" in sets:
        for c in EXTRA:
            for k in range(EXTRA_SAMPLINGS):
                out += [("kinds", m, c, k) for m in km] + [("synthetic", m, c, k) for m in sm]
                out += [("realdev", m, c, k) for m in rm]
    if "cassie" in sets and cassie.available():
        names = list(cassie.FREE_CREATIONS) + list(cassie.study_sketches())
        for c in list(bench.CONDITIONS) + [bench.OUTLIER_CONDITION]:
            out += [("cassie", m, c, 0) for m in names]
    return out


def score(task: tuple[str, str, str, int]) -> list[dict]:
    """The rows of one run (none for a CASSIE sketch over :data:`CASSIE_MAX_POINTS` samples)."""
    from curvenet import bench, synth

    s, m, c, k = task
    if s == "kinds":
        rows = bench.run_kinds(["robust"], [m], [c], seed=k)
    elif s == "synthetic":
        rows = bench.run_bench(["robust"], [m], [c], seed=k)
    elif s == "realdev":
        rows = bench.run_realdev(["robust"], [m], [c], seed=k)
    else:
        from curvenet.synth import cassie

        truth = cassie.load(m)
        allc = {**bench.CONDITIONS, **bench.EXTRA_CONDITIONS}
        pts, _ = synth.sample(truth, h=CASSIE_H, rng=bench.run_seed("cassie", m, c), **allc[c])
        if len(pts) > CASSIE_MAX_POINTS:
            return []
        rows = [bench._scored_row("robust", pts, truth, {}, dataset="cassie", model=m, condition=c, h=CASSIE_H)]
    return [{"set": s, "model": m, "condition": c, "seed": k, "curve_f1": float(r.get("curve_f1") or 0.0),
             "node_f1": float(r.get("node_f1") or 0.0), "exact": bool(r.get("exact_topology")),
             "nodes": r.get("n_nodes_found"), "true_nodes": r.get("true_N_n"), "curves": r.get("n_curves_found"),
             "true_curves": r.get("true_N_c"), "offset_h": r.get("node_offset_h"), "time": r.get("time"),
             "error": r.get("error")} for r in rows]


def run(out: str, sets: list[str], jobs: int, quick: bool = False) -> list[dict]:
    """Score every run of :func:`tasks` and write the rows to ``out`` (JSON)."""
    todo = tasks(sets, quick)
    t0 = time.perf_counter()
    rows: list[dict] = []
    with ProcessPoolExecutor(jobs) as ex:
        for r in ex.map(score, todo, chunksize=1):
            rows += r
    with open(out, "w") as f:
        json.dump(rows, f)
    print(f"{len(rows)} rows in {time.perf_counter() - t0:.0f} s -> {out}")
    return rows


def _key(r: dict) -> tuple:
    return r["set"], r["model"], r["condition"], r["seed"]


def compare(a_rows: list[dict], b_rows: list[dict], per_kind: bool = False) -> list[str]:
    """The lines of ``compare``: moved runs, then per set and condition A -> B."""
    A = {_key(r): r for r in a_rows}
    B = {_key(r): r for r in b_rows}
    keys = sorted(set(A) & set(B))
    lines = [f"{len(A)} rows in A, {len(B)} in B, {len(keys)} in both"]
    groups: dict[tuple, list] = defaultdict(list)
    for k in keys:
        a, b = A[k], B[k]
        groups[(k[0], k[2])].append((a["curve_f1"], b["curve_f1"], a["exact"], b["exact"]))
        if a["curve_f1"] != b["curve_f1"]:
            lines.append(f"  {'better' if b['curve_f1'] > a['curve_f1'] else 'worse '} {k[0]:9s} {k[1]:26s} "
                         f"{k[2]:26s} s{k[3]}  {a['curve_f1']:.3f} -> {b['curve_f1']:.3f}  nodes {a['nodes']} -> "
                         f"{b['nodes']} of {b['true_nodes']}, curves {a['curves']} -> {b['curves']} of {b['true_curves']}")
    for (s, c), v in sorted(groups.items()):
        x = np.array(v, dtype=float)
        lines.append(f"{s:9s} {c:26s} runs {len(x):3d}  mean {x[:, 0].mean():.4f} -> {x[:, 1].mean():.4f}  exact "
                     f"{int(x[:, 2].sum())} -> {int(x[:, 3].sum())}  better {int((x[:, 1] > x[:, 0]).sum())} "
                     f"worse {int((x[:, 1] < x[:, 0]).sum())}")
    if per_kind:
        kind = defaultdict(list)
        for k in keys:
            if k[0] == "kinds":
                kind[(k[1], k[2])].append((A[k]["curve_f1"], B[k]["curve_f1"]))
        for (m, c), v in sorted(kind.items()):
            x = np.array(v)
            lines.append(f"kind {m:10s} {c:26s} {x[:, 0].mean():.3f} -> {x[:, 1].mean():.3f}  worst {x[:, 1].min():.3f}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out")
    r.add_argument("--sets", default="main,extra,cassie")
    r.add_argument("--jobs", type=int, default=2)
    r.add_argument("--quick", action="store_true")
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--per-kind", action="store_true")
    a = ap.parse_args(argv)
    if a.cmd == "run":
        run(a.out, a.sets.split(","), a.jobs, a.quick)
    else:
        with open(a.a) as fa, open(a.b) as fb:
            print("\n".join(compare(json.load(fa), json.load(fb), a.per_kind)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
