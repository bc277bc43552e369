"""Speed and memory of the default method against the neighbour query, per stage (issue 22).

For each size and condition a fresh worker process builds the cloud (the copies of eight 3D
synthetic models of ``benchmarks/perf.py``; ``clean``: noise-free, ``noisy``: noise 0.3 spacing
and density ratio 3, as the ``both`` condition of ``benchmarks/robust_eval.py``), warms the
kernels up on a small cloud, then alternates the reference (one ``cKDTree(P).query(P, k=16,
workers=-1)``, build + query) with :func:`curvenet.reconstruct` (``--repeat`` times, best of each).
A thread samples the process's resident memory every 5 ms, so each stage's peak is known
(the kernels' arrays included, which ``tracemalloc`` does not see).

Printed per run: points, method time, query time, their ratio, the method's peak RSS above the
resident memory before it (the input points, the interpreter and the loaded kernels: ``start``)
and per point; with ``--stages`` each stage's time and peak above the start. The query's own
result arrays ((N, 16) distances and ids, 256 bytes a point) are freed before the method runs. The targets of issue 22 are checked at the
end: at most 2x the query at every size and condition, at most 11x the time from 1e6 to 1e7,
at most 350 bytes a point peak at 1e7.

Usage::

    python benchmarks/speed.py                         # 1e4, 1e5, 1e6; clean and noisy
    python benchmarks/speed.py --sizes 1e7 --repeat 1  # the large run (serialize it: flock)
    python benchmarks/speed.py --quick                 # tiny (CI)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

CONDITIONS = {"clean": dict(noise=0.0, density_ratio=1.0), "noisy": dict(noise=0.3, density_ratio=3.0)}
MAX_RATIO = 2.0  # method / query, every size and condition
MAX_GROWTH = 11.0  # time from 1e6 to 1e7
MAX_BYTES = 350.0  # peak bytes a point at 1e7


def make_points(n: int, *, seed: int = 0, noise: float = 0.0, density_ratio: float = 1.0) -> np.ndarray:
    """About ``n`` points: rotated copies of the 3D synthetic models on a grid (see perf.py),
    sampled with ``noise`` (in spacings) and ``density_ratio``."""
    from perf import MODELS_3D, _rotation

    from curvenet import synth

    rng = np.random.default_rng(seed)
    base = []
    for i, name in enumerate(MODELS_3D):
        P, _ = synth.sample(synth.model(name), noise=noise, density_ratio=density_ratio, rng=seed + i)
        base.append(P - P.mean(axis=0))
    sizes = np.array([len(b) for b in base])
    m = int(np.ceil(n / sizes.mean()))
    counts = np.arange(m) % len(base)
    side = int(np.ceil(m ** (1.0 / 3.0)))
    out = np.empty((int(sizes[counts].sum()), 3))
    pos = 0
    for c, j in enumerate(counts):
        g = 4.0 * np.array([c % side, (c // side) % side, c // (side * side)], dtype=float)
        out[pos:pos + sizes[j]] = base[j] @ _rotation(rng).T + g
        pos += sizes[j]
    return out[rng.permutation(len(out))]


class _RSS:
    """Samples the resident memory (bytes) in a thread: ``(time, rss)`` pairs."""

    def __init__(self, every: float = 0.005):
        self.every, self.samples, self._stop = every, [], threading.Event()
        self._page = os.sysconf("SC_PAGE_SIZE")
        self._t = threading.Thread(target=self._run, daemon=True)

    def now(self) -> int:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * self._page

    def _run(self):
        while not self._stop.is_set():
            self.samples.append((time.perf_counter(), self.now()))
            time.sleep(self.every)

    def __enter__(self):
        self._t.start()
        return self

    def __exit__(self, *a):
        self._stop.set()
        self._t.join()

    def peak(self, t0: float, t1: float) -> int:
        return max((r for t, r in self.samples if t0 <= t <= t1), default=0)


def _worker(n: int, cond: str, repeat: int, warm: bool = True) -> dict:
    import curvenet
    from scipy.spatial import cKDTree

    P = make_points(n, **CONDITIONS[cond])
    if warm:  # the kernels loaded (or compiled) before the timed runs
        curvenet.reconstruct(make_points(3000, seed=9, **CONDITIONS[cond]))
    rss = _RSS()
    base = rss.now()
    best, query = None, []
    with rss:
        for _ in range(repeat):
            t = time.perf_counter()
            cKDTree(P).query(P, k=16, workers=-1)
            query.append(time.perf_counter() - t)
            t0 = time.perf_counter()
            net = curvenet.reconstruct(P)
            t1 = time.perf_counter()
            if best is None or t1 - t0 < best[0]:
                stages, t = {}, t0
                for name, dt in net.stats["time"].items():
                    if name == "total":
                        continue
                    stages[name] = (dt, rss.peak(t, t + dt) - base)
                    t += dt
                best = (t1 - t0, stages, rss.peak(t0, t1) - base, net.n_nodes, net.n_curves)
            del net
    return {"n": len(P), "cond": cond, "method": best[0], "query": min(query), "stages": best[1],
            "peak": best[2], "base": base, "nodes": best[3], "curves": best[4]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e4,1e5,1e6")
    ap.add_argument("--conditions", default="clean,noisy")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stages", action="store_true", help="print each stage's time and peak")
    ap.add_argument("--quick", action="store_true", help="2,000 points, once, not warmed up (CI)")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        n, cond = a.worker.split(":")
        print(json.dumps(_worker(int(float(n)), cond, a.repeat, warm=not a.quick)))
        return 0
    sizes = [2000] if a.quick else [int(float(x)) for x in a.sizes.split(",")]
    repeat = 1 if a.quick else a.repeat
    print(f"{'points':>10} {'cond':>6} {'method s':>9} {'query s':>8} {'ratio':>6} {'peak MB':>8} {'B/point':>8}"
          f" {'start MB':>8}")
    rows = []
    for n in sizes:
        for cond in a.conditions.split(","):
            r = subprocess.run([sys.executable, __file__, "--worker", f"{n}:{cond}", "--repeat", str(repeat)]
                               + ["--quick"] * a.quick, capture_output=True, text=True)
            if r.returncode:
                print(f"{n:>10} {cond:>6} failed (exit {r.returncode}): {r.stderr.strip().splitlines()[-1:]}")
                continue
            d = json.loads(r.stdout.strip().splitlines()[-1])
            rows.append(d)
            print(f"{d['n']:>10} {cond:>6} {d['method']:>9.3f} {d['query']:>8.3f} {d['method'] / d['query']:>6.2f}"
                  f" {d['peak'] / 2**20:>8.0f} {d['peak'] / d['n']:>8.0f} {d['base'] / 2**20:>8.0f}", flush=True)
            if a.stages:
                for name, (dt, pk) in d["stages"].items():
                    print(f"{'':>10} {'':>6} {name:>12} {dt:>7.3f} s {pk / 2**20:>8.0f} MB {pk / d['n']:>6.0f} B/pt")
    print()
    ok = True
    for d in rows:
        good = d["method"] / d["query"] <= MAX_RATIO
        ok &= good
        print(f"{d['n']:>10} {d['cond']:>6}: {d['method'] / d['query']:.2f}x the query (target <= {MAX_RATIO})"
              f" {'met' if good else 'MISSED'}")
    for cond in CONDITIONS:
        by = {round(np.log10(d["n"])): d for d in rows if d["cond"] == cond}
        if 6 in by and 7 in by:
            g = by[7]["method"] / by[6]["method"]
            ok &= g <= MAX_GROWTH
            print(f"{cond}: 1e6 -> 1e7 time x{g:.1f} (target <= {MAX_GROWTH}) {'met' if g <= MAX_GROWTH else 'MISSED'}")
        if 7 in by:
            d = by[7]
            b = (d["base"] + d["peak"]) / d["n"]
            ok &= b <= MAX_BYTES
            print(f"{cond}: 1e7 peak RSS {b:.0f} B/point, the start included ({d['peak'] / d['n']:.0f} above it;"
                  f" target <= {MAX_BYTES:.0f}) {'met' if b <= MAX_BYTES else 'MISSED'}")
    print("all targets met" if ok else "some targets missed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
