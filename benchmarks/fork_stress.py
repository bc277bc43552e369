"""Stress test of two close junctions: a fork (Y) on a short stem leaving a straight line (a T).

Usage::

    python benchmarks/fork_stress.py [--method robust] [--quick]

The true network: a line from (-30, 0) to (30, 0), a stem from (0, 0) to (0, s), and two
branches of length 30 from (0, s) at +- a half-angle from the stem's direction (spacing h = 1).
Stems s in 5, 7, 9, 11, 14 h; half-angles 10, 15, 20, 30, 45, 60 degrees; seeds 0, 1, 2; the
four conditions of ``robust_eval.py`` (clean, noise 0.2h, density ratio 3, both with noise
0.3h). Prints, per condition, how many of the 90 networks come out with exact topology (two
junctions, four free ends, five curves) and the failing (stem, half-angle, seed) cases.
``--quick``: stems 5 and 9, half-angles 20 and 45, seed 0 (what the test runs).
The commit messages of issue 8 quote its figures.
"""

from __future__ import annotations

import argparse

from curvenet import synth
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct

try:
    from robust_eval import CONDITIONS
except ImportError:  # imported as benchmarks.fork_stress
    from benchmarks.robust_eval import CONDITIONS


fork = synth.fork  # the true network (curvenet.synth.fork)


def run(method: str = "robust", quick: bool = False) -> dict[str, tuple[int, int, list]]:
    """Exact-topology counts per condition: ``{condition: (exact, total, failures)}``."""
    stems = [5, 9] if quick else [5, 7, 9, 11, 14]
    angles = [20, 45] if quick else [10, 15, 20, 30, 45, 60]
    seeds = [0] if quick else [0, 1, 2]
    out = {}
    for cname, cond in CONDITIONS.items():
        ok, fails = 0, []
        for s in stems:
            for al in angles:
                truth = fork(s, al)
                for seed in seeds:
                    pts, _ = synth.sample(truth, h=1.0, rng=seed, **cond)
                    m = compare(reconstruct(pts, method=method), truth, h=1.0)
                    ok += bool(m["exact_topology"])
                    if not m["exact_topology"]:
                        fails.append((s, al, seed))
        out[cname] = (ok, len(stems) * len(angles) * len(seeds), fails)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--method", default="robust")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    res = run(args.method, args.quick)
    for cname, (ok, n, fails) in res.items():
        print(f"{cname:6s} exact {ok:3d} of {n}  failing (stem, half-angle, seed): {fails}")
    print("total", sum(r[0] for r in res.values()), "of", sum(r[1] for r in res.values()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
