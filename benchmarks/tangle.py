"""A dense 2D tangle: many crossing segments, most points near a junction. Time and peak memory.

Usage::

    python benchmarks/tangle.py [--sizes 1e5,6e5,1e6] [--seed 0]

Each size runs in a fresh process: the points are random segments of 40 spacings in a square
sized so that about 60% of the points lie within a shell radius (5.5 spacings) of a crossing,
sampled every spacing (noise-free). Printed per size: the points, the share near a crossing,
the time of the default method, the time of one k=16 neighbour query on the same points (the
reference, in the same process) and their ratio, and the process's peak resident memory (the
kernels' arrays included, which Python's own tracing does not see).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

SEG = 40.0  # segment length in spacings (default; --seg)
SHELL = 5.5  # the junction shell's outer radius in spacings (thresholds.DEFAULTS.shell_outer)
NEAR_SHARE = 1.0  # sizes the square: about 60% of the points end within SHELL of a crossing (measured: 0.62)


def tangle(n: int, seed: int = 0, seg: float = SEG) -> tuple[np.ndarray, float]:
    """About ``n`` points on random segments, and the share of them near a crossing.

    Segments of ``seg`` spacings with uniform centres and directions in a square of side ``L``:
    a segment crosses about ``2 SEG^2 m / (pi L^2)`` others (``m`` segments), each crossing
    putting ``4 SHELL`` of its points near it; ``L`` is chosen for ``NEAR_SHARE`` of them.
    """
    rng = np.random.default_rng(seed)
    m = max(int(n / (seg + 1)), 2)
    crossings_per_seg = NEAR_SHARE * seg / (2 * SHELL)
    side = float(np.sqrt(2 * seg**2 * m / (np.pi * crossings_per_seg)))
    c = rng.uniform(0, side, (m, 2))
    a = rng.uniform(0, np.pi, m)
    u = np.column_stack([np.cos(a), np.sin(a)])
    t = np.arange(-seg / 2, seg / 2 + 1e-9, 1.0)
    P = (c[:, None, :] + t[None, :, None] * u[:, None, :]).reshape(-1, 2)
    return P, _near_share(P, c, u, seg)


def _near_share(P, c, u, seg) -> float:
    """Share of the points within SHELL of a crossing of two segments (on a sample of segments)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(c)
    # crossings: pairs of segments whose centres are within SEG, intersecting within both
    pairs = np.array(sorted(tree.query_pairs(seg)), dtype=np.int64).reshape(-1, 2)
    i, j = pairs[:, 0], pairs[:, 1]
    d = c[j] - c[i]
    den = u[i, 0] * u[j, 1] - u[i, 1] * u[j, 0]
    ok = np.abs(den) > 1e-9
    s = np.where(ok, (d[:, 0] * u[j, 1] - d[:, 1] * u[j, 0]) / np.where(ok, den, 1), np.inf)
    r = np.where(ok, (d[:, 0] * u[i, 1] - d[:, 1] * u[i, 0]) / np.where(ok, den, 1), np.inf)
    hit = ok & (np.abs(s) <= seg / 2) & (np.abs(r) <= seg / 2)
    X = c[i[hit]] + s[hit, None] * u[i[hit]]
    if not len(X):
        return 0.0
    near = cKDTree(X).query(P, distance_upper_bound=SHELL)[0]
    return float(np.isfinite(near).mean())


def _worker(n: int, seed: int, seg: float) -> None:
    import curvenet
    from curvenet.neighbors import knn

    P, share = tangle(n, seed, seg)
    t0 = time.perf_counter()
    knn(P, 16)
    tq = time.perf_counter() - t0
    t0 = time.perf_counter()
    net = curvenet.reconstruct(P)
    tr = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({"n": len(P), "near": share, "query": tq, "robust": tr, "peak": peak,
                      "nodes": net.n_nodes, "curves": net.n_curves}))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e5,6e5,1e6")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seg", type=float, default=SEG, help="segment length in spacings")
    ap.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        _worker(a.worker, a.seed, a.seg)
        return 0
    print(f"{'points':>9} {'near':>5} {'robust s':>9} {'query s':>8} {'ratio':>6} {'peak MB':>8} {'B/point':>8}")
    for n in (int(float(x)) for x in a.sizes.split(",")):
        r = subprocess.run([sys.executable, __file__, "--worker", str(n), "--seed", str(a.seed), "--seg", str(a.seg)],
                           capture_output=True, text=True)
        if r.returncode:
            print(f"{n:>9} failed (exit {r.returncode}): {r.stderr.strip().splitlines()[-1:]}")
            continue
        d = json.loads(r.stdout.strip().splitlines()[-1])
        print(f"{d['n']:>9} {d['near']:>5.2f} {d['robust']:>9.2f} {d['query']:>8.2f} {d['robust'] / d['query']:>6.1f}"
              f" {d['peak'] / 2**20:>8.0f} {d['peak'] / d['n']:>8.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
