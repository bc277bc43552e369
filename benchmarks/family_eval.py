"""Score the default method on families of real-like networks drawn at random (issue 25).

Usage::

    python benchmarks/family_eval.py [--families facade,grid] [--members 16]
                                     [--conditions clean,"density x3","noise 0.2h"] [--jobs 2]

For each family of :mod:`curvenet.synth.families` and condition (names of
``curvenet.bench.CONDITIONS`` and ``EXTRA_CONDITIONS``), members 0 .. n-1 are drawn and sampled
(:func:`curvenet.synth.families.sampling_seed`) and reconstructed by ``robust``; prints every
member below curve F1 1 and, per family and condition, the mean and worst curve F1 and the
number with exact topology.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np


def _score(args):
    family, k, condition = args
    from curvenet import bench, metrics, reconstruct, synth
    from curvenet.synth import families

    truth = families.member(family, k)
    kw = {**bench.CONDITIONS, **bench.EXTRA_CONDITIONS}[condition]
    pts, _ = synth.sample(truth, rng=families.sampling_seed(k), **kw)
    m = metrics.compare(reconstruct(pts, method="robust"), truth, h=synth.h_of(truth))
    return (family, k, condition, float(m["curve_f1"]), bool(m["exact_topology"]),
            int(m["n_nodes_found"]), int(m["n_nodes_true"]))


def main(argv=None) -> int:
    from curvenet.synth import families

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--families", default=",".join(families.FAMILIES))
    ap.add_argument("--members", type=int, default=16)
    ap.add_argument("--conditions", default="clean,density x3,noise 0.1h,noise 0.2h")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    jobs = [(f, k, c) for f in a.families.split(",") for c in a.conditions.split(",") for k in range(a.members)]
    with ProcessPoolExecutor(a.jobs) as ex:
        res = list(ex.map(_score, jobs))
    for f in a.families.split(","):
        for c in a.conditions.split(","):
            rs = [r for r in res if r[0] == f and r[2] == c]
            for r in rs:
                if r[3] < 1.0:
                    print(f"  {f}#{r[1]} {c}: curve F1 {r[3]:.3f}, nodes {r[5]} of {r[6]}")
            f1 = np.array([r[3] for r in rs])
            print(f"{f:8s} {c:12s} members {len(rs)}  curve F1 mean {f1.mean():.4f} worst {f1.min():.3f}  "
                  f"exact {sum(r[4] for r in rs)} of {len(rs)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
