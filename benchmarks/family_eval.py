"""Score the default method on families of real-like networks drawn at random (issue 25).

Usage::

    python benchmarks/family_eval.py [--families facade,grid] [--members 16]
                                     [--conditions clean,"density x3","noise 0.2h"] [--jobs 2]

For each family of :mod:`curvenet.synth.families` and condition (names of
``curvenet.bench.CONDITIONS`` and ``EXTRA_CONDITIONS``), members 0 .. n-1 are scored as the
benchmark scores them (:func:`curvenet.bench.run_families`); prints every
member below curve F1 1 and, per family and condition, the mean and worst curve F1 and the
number with exact topology.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np


def _rows(args):
    family, members, condition = args
    from curvenet import bench

    return bench.run_families([family], members, [condition])


def main(argv=None) -> int:
    from curvenet import bench
    from curvenet.synth import families

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--families", default=",".join(families.FAMILIES))
    ap.add_argument("--members", type=int, default=bench.FAMILY_MEMBERS)
    ap.add_argument("--conditions", default="clean,density x3,noise 0.1h,noise 0.2h")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    jobs = [(f, a.members, c) for f in a.families.split(",") for c in a.conditions.split(",")]
    with ProcessPoolExecutor(a.jobs) as ex:
        for (f, _, c), rs in zip(jobs, ex.map(_rows, jobs)):
            for r in rs:
                if r["curve_f1"] < 1.0:
                    print(f"  {r['model']} {c}: curve F1 {r['curve_f1']:.3f}, nodes {r['n_nodes_found']} of "
                          f"{r['n_nodes_true']}")
            f1 = np.array([r["curve_f1"] for r in rs])
            print(f"{f:8s} {c:12s} members {len(rs)}  curve F1 mean {f1.mean():.4f} worst {f1.min():.3f}  "
                  f"exact {sum(bool(r['exact_topology']) for r in rs)} of {len(rs)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
