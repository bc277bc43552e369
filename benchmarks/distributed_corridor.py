"""Scale benchmark of the tiled run: a synthetic power-line corridor written as LAZ tiles.

Usage::

    python benchmarks/distributed_corridor.py --points 1e6 [--workers 2] [--tiles auto]
        [--single] [--one-worker] [--keep DIR]

Writes the corridor (:mod:`curvenet.synth.corridor`: towers every 200-400 m, 4 catenary wires
a span joined at insulators, spacing 0.25 m, noise 3 cm, 1.5% outliers) as LAZ files of about
``--file-points`` points, then runs :func:`curvenet.distributed.reconstruct_tiled` on a
LocalCluster of ``--workers`` worker processes and prints: wall time, throughput, the peak
memory (RSS, sampled every 0.2 s) of each worker and of the client, the tile count and size,
the halo, the estimates (the tiled run's, exact over every tile, against one process's when ``--single``).
``--single`` also runs the one-process method on the whole cloud (the reference: time, peak
memory, and the equality of the two networks within half a spacing; its time is given without
and with its reading of the files, which the tiled run's time includes); ``--one-worker`` reruns
the tiled run on one worker (the speed-up of two). Figures, not assertions: nothing here
fails on a slow machine. A small size runs in CI (tests/test_distributed.py).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np


class PeakRSS:
    """Sample the resident memory of some processes every ``every`` seconds; keep the peaks."""

    def __init__(self, pids, every: float = 0.2):
        import psutil

        self.procs = {pid: psutil.Process(pid) for pid in pids}
        self.peak = {pid: 0 for pid in pids}
        self.every = every
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.is_set():
            for pid, p in self.procs.items():
                try:
                    rss = p.memory_info().rss  # the process alone (the client's children are the workers)
                except Exception:  # a process that ended (a restarted worker)
                    continue
                self.peak[pid] = max(self.peak[pid], rss)
            self._stop.wait(self.every)

    def __enter__(self):
        self._t.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()


def write_corridor(folder: Path, n_points: float, file_points: float, seed: int = 1, noise: float = 0.03,
                   outliers: float = 0.015) -> tuple[int, int, list]:
    """Write the corridor as LAZ files; returns (points, spans, files)."""
    import laspy

    from curvenet.synth.corridor import corridor_layout, corridor_span, spans_for_points

    n_spans = spans_for_points(n_points, wires=4)
    lay = corridor_layout(n_spans, wires=4, rng=seed)
    files, buf, total, k = [], [], 0, 0

    def flush():
        nonlocal buf, k
        if not buf:
            return
        P = np.vstack(buf)
        hdr = laspy.LasHeader(point_format=3, version="1.2")
        hdr.offsets = np.floor(P.min(axis=0))
        hdr.scales = np.array([1e-3, 1e-3, 1e-3])
        las = laspy.LasData(hdr)
        las.x, las.y, las.z = P.T
        f = folder / f"corridor_{k:05d}.laz"
        las.write(f)
        files.append(f)
        k += 1
        buf = []

    for i in range(lay.n_spans + 1):
        P = corridor_span(lay, i, spacing=0.25, noise=noise, outliers=outliers, rng=seed)
        buf.append(P)
        total += len(P)
        if sum(len(b) for b in buf) >= file_points:
            flush()
    flush()
    return total, n_spans, files


def run_tiled(folder, workers, tiles, output=None):
    """The tiled run on a LocalCluster of ``workers`` processes: the network in memory
    (``reconstruct_tiled``), or, with ``output``, written to that file one curve at a time from
    the scratch store (``tiled_network``, as ``curvenet reconstruct --tiles`` writes .json and
    .ply; the time includes the writing). Returns the network (without ``output``; with it, an
    object with its counts, parameters and stats), the wall time, the workers' and the client's
    peak memory."""
    import types

    import distributed

    from curvenet.distributed import reconstruct_tiled, tiled_network
    from curvenet.io.streamed import write_network_streamed

    cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    client = distributed.Client(cluster)
    try:
        pids = list(client.run(os.getpid).values())
        with PeakRSS(pids + [os.getpid()]) as mem:
            t0 = time.perf_counter()
            if output is None:
                net = reconstruct_tiled(str(folder), tiles=tiles, client=client)
            else:
                with tiled_network(str(folder), tiles=tiles, client=client) as stored:
                    write_network_streamed(stored, output)
                    net = types.SimpleNamespace(parameters=stored.parameters, stats=stored.stats,
                                                n_nodes=stored.n_nodes, n_curves=stored.n_curves)
            wall = time.perf_counter() - t0
        peaks = [mem.peak[p] / 2**30 for p in pids]
        client_peak = mem.peak[os.getpid()] / 2**30
    finally:
        client.close()
        cluster.close()
    return net, wall, peaks, client_peak


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=float, default=1e6)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--tiles", default="auto")
    ap.add_argument("--file-points", type=float, default=250_000)
    ap.add_argument("--noise", type=float, default=0.03, help="noise std per coordinate (m)")
    ap.add_argument("--outliers", type=float, default=0.015, help="outliers, fraction of the curve samples")
    ap.add_argument("--single", action="store_true", help="also run one process on the whole cloud")
    ap.add_argument("--one-worker", action="store_true", help="also run the tiled run on one worker")
    ap.add_argument("--keep", default=None, help="write the LAZ files here and keep them")
    ap.add_argument("--json", default=None, help="also write the figures as JSON")
    ap.add_argument("--output", default=None,
                    help="write the network to this .json or .ply one curve at a time from the scratch store "
                         "(the client holds no curve point; the time includes the writing)")
    args = ap.parse_args(argv)
    tiles = args.tiles if args.tiles == "auto" else float(args.tiles)
    # a SIGTERM (a batch system's time limit, kill) unwinds as an exception does, so that the
    # finally blocks close the cluster and remove the LAZ files (the default handler skips them)
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    folder = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="corridor-"))
    folder.mkdir(parents=True, exist_ok=True)
    fig: dict = {"target_points": args.points, "workers": args.workers}
    try:
        t0 = time.perf_counter()
        n, spans, files = write_corridor(folder, args.points, args.file_points, noise=args.noise,
                                         outliers=args.outliers)
        fig.update(points=n, spans=spans, files=len(files), write_s=time.perf_counter() - t0)
        print(f"corridor: {n} points, {spans} spans, {len(files)} LAZ files, written in {fig['write_s']:.1f} s",
              flush=True)
        net, wall, peaks, cpeak = run_tiled(folder, args.workers, tiles, args.output)
        if args.output:
            fig.update(output=args.output, output_bytes=os.path.getsize(args.output))
        p = net.parameters
        fig.update(tiled_s=wall, tiled_pts_per_s=n / wall, worker_peak_gb=peaks, client_peak_gb=cpeak,
                   tiles=p["tiles"], tile_side=p["tile_side"], halo=p["halo"], spacing=p["spacing"],
                   noise=p["noise"], clean=p["clean"], estimates_points=p["estimates_points"],
                   estimates_inexact_points=p.get("estimates_inexact_points"),
                   tiles_prepared=net.stats.get("tiles_prepared"),
                   tile_points_max=net.stats["tile_points_max"], unmatched_ports=net.stats["unmatched_ports"],
                   fitted_on_client=net.stats.get("fitted_here", 0),
                   nodes=net.n_nodes, curves=net.n_curves, passes_s=net.stats["time"])
        print(f"tiled, {args.workers} workers: {wall:.1f} s ({n / wall:,.0f} points/s); {p['tiles']} tiles of "
              f"side {p['tile_side']:.1f} m (at most {net.stats['tile_points_max']:,} points with the halo), "
              f"halo {p['halo']:.2f} m; worker peaks {', '.join(f'{x:.2f}' for x in peaks)} GB, client peak "
              f"{cpeak:.2f} GB; {net.n_nodes} nodes, {net.n_curves} curves, {net.stats['unmatched_ports']} "
              f"unmatched ports, {net.stats.get('fitted_here', 0)} curves fitted on the client", flush=True)
        print("  passes: " + ", ".join(f"{k} {v:.1f} s" for k, v in net.stats["time"].items()), flush=True)
        print(f"  estimates over {p['estimates_points']:,} points (exact: {p.get('estimates_exact')}, "
              f"{p.get('estimates_inexact_points')} points inexact; {net.stats.get('tiles_prepared')} tiles "
              f"went on from the box the estimates prepared): "
              f"spacing {p['spacing']:.4f}, "
              f"noise {p['noise']:.4f}, clean {p['clean']}", flush=True)
        if args.single:
            from curvenet.distributed import network_difference
            from curvenet.io import read_points
            from curvenet.methods.robust import estimate
            from curvenet.reconstruct import reconstruct

            t0 = time.perf_counter()
            P = np.vstack([read_points(f) for f in files])
            wread = time.perf_counter() - t0  # (the tiled run's time includes its reading)
            with PeakRSS([os.getpid()]) as mem:
                t0 = time.perf_counter()
                one = reconstruct(P)
                ws = time.perf_counter() - t0
            est = estimate(P)
            tiled = net
            if args.output:  # (the network written, read back: a .json)
                from curvenet.io import read_network

                tiled = read_network(args.output)
            diff = network_difference(one, tiled, 0.5 * one.parameters["spacing"])
            fig.update(single_s=ws, single_peak_gb=mem.peak[os.getpid()] / 2**30, single_pts_per_s=n / ws,
                       throughput_ratio=ws / wall, single_read_s=wread,
                       throughput_ratio_with_read=(ws + wread) / wall, whole_spacing=est.hmed, whole_noise=est.sigma,
                       whole_clean=est.clean, equal=diff is None, difference=diff,
                       single_nodes=one.n_nodes, single_curves=one.n_curves)
            print(f"one process: {ws:.1f} s ({n / ws:,.0f} points/s), peak {fig['single_peak_gb']:.2f} GB "
                  f"(process total); tiled/one-process throughput {ws / wall:.2f}; with its reading of the "
                  f"files ({wread:.1f} s, as the tiled run's time includes): {(ws + wread) / wall:.2f}", flush=True)
            print(f"  whole-cloud estimates: spacing {est.hmed:.4f}, noise {est.sigma:.4f}, clean {est.clean} "
                  f"(tiled: {p['spacing']:.4f}, {p['noise']:.4f}, {p['clean']})", flush=True)
            print(f"  tiled == one process (nodes and curves within half a spacing): {diff is None}"
                  + (f" ({diff})" if diff else ""), flush=True)
        if args.one_worker:
            _, wall1, peaks1, _ = run_tiled(folder, 1, tiles)
            fig.update(one_worker_s=wall1, speedup=wall1 / wall, one_worker_peak_gb=peaks1)
            print(f"tiled, 1 worker: {wall1:.1f} s; {args.workers} workers are {wall1 / wall:.2f}x faster", flush=True)
        if args.json:
            Path(args.json).write_text(json.dumps(fig, indent=1, default=str))
    finally:
        if not args.keep:
            shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
