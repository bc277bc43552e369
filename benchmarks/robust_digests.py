"""Digests of the default method's networks: the guard of a redesign that must change no result.

Usage::

    python benchmarks/robust_digests.py --write [--out FILE]     # store today's digests
    python benchmarks/robust_digests.py --check [--subset] [--only synthetic|cassie]

The runs are those of the benchmark's robustness sweep (:func:`curvenet.bench.seed_spread`):
every synthetic model under every condition of :data:`curvenet.bench.CONDITIONS`, samplings
0 to 7, plus every CASSIE sketch (free creations and study sketches, sampled at 2 mm as in
:func:`curvenet.bench.run_cassie`; skipped when the dataset is absent or a sketch has over
50,000 samples). A digest is the SHA-256 of the network's node coordinates (float64 bits),
and of every curve's points, start and end nodes, closed flag and input indices, in order: two
networks have the same digest only when they are identical to the bit.

``--check`` prints one line per differing run and exits 1 when any differs (runs missing from
the stored file are listed and count as differing). The stored digests were written where
OpenBLAS runs its AVX-512 (``SkylakeX``) kernels. Under its other kernels (AMD EPYC processors
get ``Zen``/``Haswell`` kernels even with AVX-512) one run differs, ``cassie/06-1-2``: two node
coordinates in their last bits (1e-15; the topology is the same), from the LAPACK and BLAS calls
of ``junctions.hidden_fork`` (``chains.fit_line``'s SVD, ``np.linalg.solve``), whose sums the
kernels round differently. Check there with ``OPENBLAS_CORETYPE=SkylakeX`` in the environment
(measured 4 December 2026: the stored digest under ``SkylakeX``, another under ``Haswell`` and
``Zen``). ``--subset`` checks the 20 runs of
:data:`SUBSET` only (the CI test does the same).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

from curvenet import synth
from curvenet.bench import CONDITIONS, run_seed
from curvenet.reconstruct import reconstruct

STORE = Path(__file__).resolve().parents[1] / "tests" / "data" / "robust_digests.json"
SEEDS = 8
CASSIE_H = 0.002
CASSIE_MAX_POINTS = 50_000
#: Short names of the sweep's conditions (keys of :data:`curvenet.bench.CONDITIONS`).
CONDITION_NAMES = {"clean": "clean", "noise": "noise 0.2h", "ratio": "density x3",
                   "both": "noise 0.3h + density x3"}

#: Runs checked in CI: every condition, many models and samplings, two real sketches.
SUBSET = (
    "synthetic/cube/clean/0", "synthetic/wheel/noise/1", "synthetic/fan/ratio/2",
    "synthetic/tree/both/3", "synthetic/eye/both/0", "synthetic/eye/both/4",
    "synthetic/crossing/noise/7", "synthetic/crossing/both/5", "synthetic/torus/clean/6",
    "synthetic/corners/both/2", "synthetic/corners/ratio/1", "synthetic/star8/noise/3",
    "synthetic/knot/both/0", "synthetic/window/clean/5", "synthetic/sphere/ratio/4",
    "synthetic/mug/both/6", "synthetic/speaker/noise/7", "synthetic/fig8/both/1",
    "cassie/shield", "cassie/vintage_car",
)


def network_digest(net) -> str:
    """SHA-256 of a network's nodes and curves (every bit of every coordinate and index)."""
    d = hashlib.sha256()
    nodes = np.ascontiguousarray(np.asarray(net.nodes, dtype=np.float64))
    d.update(repr(nodes.shape).encode())
    d.update(nodes.tobytes())
    d.update(str(len(net.curves)).encode())
    for c in net.curves:
        pts = np.ascontiguousarray(np.asarray(c.points, dtype=np.float64))
        d.update(repr(pts.shape).encode())
        d.update(pts.tobytes())
        d.update(repr((c.start, c.end, bool(c.closed))).encode())
        d.update(np.ascontiguousarray(np.asarray(c.indices, dtype=np.int64)).tobytes())
    return d.hexdigest()


def run_ids(include_cassie: bool = True) -> list[str]:
    """Every run of the sweep, as ``synthetic/MODEL/CONDITION/SEED`` or ``cassie/NAME``."""
    ids = [f"synthetic/{m}/{c}/{k}" for k in range(SEEDS) for m in synth.MODELS for c in CONDITION_NAMES]
    if include_cassie:
        from curvenet.synth import cassie

        if cassie.available():
            ids += [f"cassie/{n}" for n in (*cassie.FREE_CREATIONS, *cassie.study_sketches())]
    return ids


def points_of(run_id: str) -> np.ndarray | None:
    """The sampled points of one run (None: a CASSIE sketch over the size limit or absent)."""
    parts = run_id.split("/")
    if parts[0] == "synthetic":
        _, m, c, k = parts
        truth = synth.model(m)
        cond = CONDITION_NAMES[c]
        return synth.sample(truth, rng=run_seed(m, cond) + int(k), **CONDITIONS[cond])[0]
    from curvenet.synth import cassie

    if not cassie.available():
        return None
    pts = synth.sample(cassie.load(parts[1]), h=CASSIE_H, rng=run_seed("cassie", parts[1]))[0]
    return pts if len(pts) <= CASSIE_MAX_POINTS else None


def digest_of(run_id: str) -> str | None:
    """The digest of the default method's network on one run (None: the run is skipped)."""
    pts = points_of(run_id)
    if pts is None:
        return None
    return network_digest(reconstruct(pts, method="robust"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true", help="compute every digest and store them")
    g.add_argument("--check", action="store_true", help="compare with the stored digests")
    ap.add_argument("--subset", action="store_true", help="only the runs of SUBSET")
    ap.add_argument("--only", choices=("synthetic", "cassie"), help="only the runs of one dataset")
    ap.add_argument("--out", type=Path, default=STORE)
    a = ap.parse_args(argv)
    ids = list(SUBSET) if a.subset else run_ids()
    if a.only:
        ids = [i for i in ids if i.startswith(a.only + "/")]
    stored = json.loads(a.out.read_text())["digests"] if a.check else {}
    got, bad, t0 = {}, [], time.perf_counter()
    for i, rid in enumerate(ids):
        dg = digest_of(rid)
        if dg is None:
            continue
        got[rid] = dg
        if a.check and stored.get(rid) != dg:
            bad.append(rid)
            print(f"DIFFERS {rid}" if rid in stored else f"MISSING {rid}", flush=True)
        if (i + 1) % 64 == 0:
            print(f"{i + 1}/{len(ids)} runs, {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    if a.write:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(json.dumps({"runs": len(got), "digests": got}, indent=0, sort_keys=True) + "\n")
        print(f"{len(got)} digests written to {a.out} in {time.perf_counter() - t0:.0f} s")
        return 0
    print(f"{len(got)} runs checked, {len(bad)} differ ({time.perf_counter() - t0:.0f} s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
