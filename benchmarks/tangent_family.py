"""Tangent junctions on clean CAD-like networks, a family of them (issue 25).

A circle of radius R spacings with four straight lines leaving it almost tangentially
(``curvenet.synth.kinds.tangent_circle``), for R from a small fillet to a large hole and two sets
of angles, each sampled three times: noise-free with a jitter of 1e-6 h (as a CAD export's
rounding; an exact grid of samples would decide ties by luck), with a density ratio of 3, and
with noise of 0.2 h per coordinate (issue 25's noisy condition; ``--conditions``).
Prints, per model and condition, the curve F1 of each sampling, whether the topology is exact and
the largest distance (in spacings) from a true junction to the nearest node found.

    python benchmarks/tangent_family.py [--radii 5,8,10,15,30,60] [--samplings 3]
                                        [--conditions clean,x3,noise]
"""

from __future__ import annotations

import argparse

import numpy as np

from curvenet import reconstruct
from curvenet.metrics import compare
from curvenet.synth import sample
from curvenet.synth.kinds import tangent_circle

#: The angle sets (degrees from the circle's tangent), one line per junction.
ANGLE_SETS = ((0.0, 1.0, 2.0, 3.0), (5.0, 7.0, 10.0, 15.0))
#: The jitter of the noise-free samplings, in spacings (a CAD export's rounding).
JITTER = 1e-6
#: The density ratio of the uneven samplings.
DENSITY = 3.0
#: The noise of the noisy samplings, in spacings per coordinate.
NOISE = 0.2
#: The conditions, by name.
CONDITIONS = ("clean", "x3", "noise")


def run(radii, samplings: int, conditions=CONDITIONS) -> None:
    print(f"{'R (h)':>6} {'angles':>14} {'condition':>10}  curve F1 per sampling  exact  "
          "worst junction offset (h)")
    tot = {}
    for R in radii:
        for angles in ANGLE_SETS:
            truth = tangent_circle(R, angles)
            h = truth.parameters["h"]
            junctions = truth.nodes[: len(angles)]  # (the circle's nodes come first)
            for cond in conditions:
                f1s, exact, worst = [], 0, 0.0
                for s in range(samplings):
                    if cond == "clean":
                        P, _ = sample(truth, rng=s)
                        P = P + np.random.default_rng(s).normal(scale=JITTER * h, size=P.shape)
                    elif cond == "x3":
                        P, _ = sample(truth, rng=s, density_ratio=DENSITY)
                    else:
                        P, _ = sample(truth, rng=s, noise=NOISE)
                    net = reconstruct(P)
                    m = compare(net, truth, h=h)
                    f1s.append(m["curve_f1"])
                    exact += bool(m["exact_topology"])
                    if len(net.nodes):
                        off = np.linalg.norm(junctions[:, None] - net.nodes[None], axis=2).min(axis=1) / h
                        worst = max(worst, float(off.max()))
                    else:
                        worst = float("inf")
                tot.setdefault(cond, []).extend(f1s)
                print(f"{R:>6g} {','.join('%g' % a for a in angles):>14} {cond:>10}  "
                      f"{' '.join('%.2f' % f for f in f1s):<21}  {exact}/{samplings}  {worst:.2f}")
    for cond, f in tot.items():
        print(f"mean curve F1, {cond}: {np.mean(f):.3f} over {len(f)} runs; "
              f"{sum(x == 1.0 for x in f)} at 1.00")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radii", default="5,8,10,15,30,60")
    ap.add_argument("--samplings", type=int, default=3)
    ap.add_argument("--conditions", default=",".join(CONDITIONS))
    a = ap.parse_args(argv)
    conds = a.conditions.split(",")
    bad = [c for c in conds if c not in CONDITIONS]
    if bad:
        ap.error(f"unknown condition {bad[0]!r} (one of {', '.join(CONDITIONS)})")
    run([float(r) for r in a.radii.split(",")], a.samplings, conds)


if __name__ == "__main__":
    main()
