"""Score ``robust`` on the analogues of real failure kinds and on the real-dev networks (issue 25).

Usage::

    python benchmarks/quality_eval.py kinds [--models ladder,comb] [--conditions clean,"noise 0.2h"]
    python benchmarks/quality_eval.py realdev [--models nrn_c11471_s1066,...]
    python benchmarks/quality_eval.py synthetic --conditions clean

Prints one line per model and condition (nodes and curves found / true, node and curve F1,
exact topology, node offset and Chamfer distance in h, time) and the means per condition
(per kind for real-dev: mean and worst curve F1, exact count). ``--json FILE`` also writes the
rows (:func:`curvenet.bench.write_json`).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from curvenet import bench


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("which", choices=("kinds", "realdev", "synthetic"))
    ap.add_argument("--models", default="")
    ap.add_argument("--conditions", default="")
    ap.add_argument("--method", default="robust")
    ap.add_argument("--json", default="")
    args = ap.parse_args(argv)
    models = args.models.split(",") if args.models else None
    conds = args.conditions.split(",") if args.conditions else None
    t0 = time.time()
    if args.which == "kinds":
        rows = bench.run_kinds([args.method], models, conds)
    elif args.which == "realdev":
        rows = bench.run_realdev([args.method], models, conds)
    else:
        rows = bench.run_bench([args.method], models, conds)
    for r in rows:
        print(f"{r['model']:28s} {r['condition']:26s} nodes {r.get('n_nodes_found')}/{r.get('true_N_n')} "
              f"curves {r.get('n_curves_found')}/{r.get('true_N_c')} nodeF1 {r.get('node_f1', 0):.3f} "
              f"curveF1 {r.get('curve_f1', 0):.3f} exact {int(bool(r.get('exact_topology')))} "
              f"off {r.get('node_offset_h', float('nan')):.2f} chamfer {r.get('chamfer_h', float('nan')):.2f} "
              f"t {r.get('time', 0):.1f} {r.get('error') or ''}", flush=True)
    groups: dict[tuple, list] = {}
    for r in rows:
        groups.setdefault((r.get("kind", r["dataset"]), r["condition"]), []).append(r)
    for (g, c), rs in groups.items():
        f = [r["curve_f1"] for r in rs]
        ch = [r["chamfer_h"] for r in rs if np.isfinite(r["chamfer_h"])]
        print(f"== {g} {c}: curve F1 mean {np.mean(f):.3f} worst {min(f):.3f}, exact "
              f"{sum(bool(r['exact_topology']) for r in rs)}/{len(rs)}, Chamfer {np.mean(ch):.2f}h")
    if args.json:
        bench.write_json(rows, args.json)
    print(f"elapsed {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
