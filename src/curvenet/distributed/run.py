"""The tiled run on Dask: scan, bin, estimate, reconstruct tile by tile, stitch."""

from __future__ import annotations

import dataclasses
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, Literal

import numpy as np

from .._sigint import checkpoint
from ..errors import CurvenetError, InputError, MethodError, require
from ..methods.robust import Estimates
from ..methods.robust.kernels.registry import compile_pending
from ..methods.robust.warmup import COMMON, NOISY_ONLY, precompile
from ..network import CurveNetwork
from . import tasks
from .grid import TileGrid
from .estimates import whole_cloud_estimates
from .halo import halo_width
from .inputs import expand_inputs, plan_chunks
from .plan import StoredNetwork
from .scratch import new_root, remove_root
from .stitch import stitch

__all__ = ["reconstruct_tiled", "tiled_network", "TILE_AUTO_POINTS", "ESTIMATE_POINTS", "TASK_RETRIES", "make_client"]

#: ``tiles="auto"``: the side that gives about this many points a tile, counted as if the
#: points lay along the longest side of the bounding box (curves: denser tiles are rarer).
TILE_AUTO_POINTS: int = 400_000
#: The whole-cloud estimates are first computed on whole tiles of at most about this many points
#: in all (every tile when the cloud is smaller: then they are exactly the one-process values);
#: for a larger cloud this sample only sets the scale (the halo) of the exact pass over every
#: tile (:mod:`.estimates`), which runs on every worker at once: the sample is one task, so it
#: is kept small (the scale needs no more than a tile; the exact pass certifies it, see
#: ``estimates_exact``).
ESTIMATE_POINTS: int = 250_000
#: A task that raises is retried this many times before the run fails (a lost worker's tasks
#: are rescheduled by Dask itself).
TASK_RETRIES: int = 2
#: Seconds between two looks at Ctrl-C while waiting for tasks.
_POLL = 0.2


def make_client(scheduler: str = "processes", workers: int | None = None, *, dashboard: bool = False):
    """A Dask client: a LocalCluster of worker processes or threads, or a running scheduler.

    Parameters
    ----------
    scheduler : str
        ``"processes"`` (a LocalCluster of ``workers`` single-threaded processes),
        ``"threads"`` (one process, ``workers`` threads) or a scheduler address
        (``tcp://host:8786``).
    workers : int, optional
        Local workers (default: the CPU count).
    dashboard : bool
        Serve the dashboard on a free port (its address is ``client.dashboard_link``).

    Returns
    -------
    distributed.Client
        Close it (and its cluster) when done: ``client.close(); client.cluster.close()``.
    """
    distributed = require("distributed", "tiled reconstruction", "dask", package="dask[distributed]")
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    dash = ":0" if dashboard else None
    if scheduler == "processes":
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           dashboard_address=dash)
    elif scheduler == "threads":
        cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=workers, processes=False,
                                           dashboard_address=dash)
    else:
        if workers is not None:
            raise InputError("--workers applies to a local cluster, not to a scheduler address")
        try:
            return distributed.Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"cannot reach the Dask scheduler at {scheduler!r} ({exc})") from None
    return distributed.Client(cluster)


def _gather(client, futures: dict, what):
    """Wait for every future (Ctrl-C checked meanwhile); the first failure raises.

    ``futures`` maps a label to a future; ``what(label, exc)`` gives the error to raise. Each
    result is fetched as soon as its task finishes and then released on the cluster, so a
    worker holds the results of its finished tasks only until the client has them (not until
    the whole pass ends: the tiles' pieces of a large cloud would pile up on the workers).
    Whatever the outcome, the futures are released on the way out (cancelled if still pending):
    nothing of a phase stays alive on the cluster, so a worker lost later makes Dask recompute
    only the tasks still needed, never the tasks of a finished phase or run (whose scratch store
    may be gone by then).
    """
    from distributed import wait

    results: dict = {}
    try:
        pending = list(futures.values())
        while pending:
            checkpoint()
            try:
                wait(pending, timeout=_POLL, return_when="FIRST_COMPLETED")
            except TimeoutError:
                pass
            for label, f in futures.items():
                if f.status == "error":
                    raise what(label, f.exception())
                if f.status == "finished" and label not in results:
                    results[label] = f.result()
                    f.release()
            pending = [f for label, f in futures.items() if label not in results]
        return {label: results[label] for label in futures}
    finally:
        client.cancel([f for label, f in futures.items() if label not in results])


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def _input_error(label, exc):
    if isinstance(exc, CurvenetError):
        return exc
    return InputError(f"{label}: cannot read ({_one_line(exc)})")


def reconstruct_tiled(inputs, *, tiles: float | Literal["auto"] = "auto", halo: float | None = None,
                      origin=None, client=None, scheduler: str = "processes", workers: int | None = None,
                      scratch=None, columns=None, drop_nonfinite: bool = False, stitching: bool = True,
                      progress: bool = False, on_compile=None) -> CurveNetwork:
    """Reconstruct a curve network tile by tile on Dask (the default method).

    The client reads no point: a first pass bins every input chunk into the tiles of an
    explicit grid (a scratch store), the whole-cloud estimates are computed once and handed
    to every tile, each tile is reconstructed with a halo around its box and cut at the box
    into pieces and ports, and the pieces are stitched across the faces. The network is then
    built in memory (all its curve points: 32 bytes a point); :func:`tiled_network` gives it
    with its points left on disk, to write it out without holding it.

    Parameters
    ----------
    inputs : path, glob or folder, or a list of them
        Point files (LAS/LAZ, .npy, text...); several files are one cloud, in the order given.
    tiles : float or "auto"
        The tile side in input units, or ``"auto"`` (about :data:`TILE_AUTO_POINTS` points a tile).
    halo : float, optional
        The halo in input units; default :func:`.halo.halo_width` of the estimates.
    origin : (d,) array_like, optional
        A corner of tile 0 (default: the lowest corner of the bounding box).
    client : distributed.Client, optional
        Run on this client; default: one made by :func:`make_client` for this run.
    scheduler, workers
        For the client made here (see :func:`make_client`).
    scratch : path, optional
        Folder for the scratch store (a fresh sub-folder, removed at the end); default: the
        system's temporary folder.
    columns, drop_nonfinite
        As for :func:`curvenet.io.read_points`.
    stitching : bool
        Join the pieces across tile faces (False only for tests: every port stays a free end).
    progress : bool
        Show Dask's progress bar of each pass (on a terminal).
    on_compile : callable, optional
        Called (no argument) before the kernels' first compile, when this run makes it: on a
        LocalCluster whose tiles will compile numba kernels (none in numba's cache yet), they are
        compiled once here, shared out over the cores (:func:`curvenet.methods.robust.warmup.precompile`),
        before any worker needs them; for a progress note. (Workers elsewhere compile for
        themselves on their first tile.)

    Returns
    -------
    CurveNetwork
        ``indices`` are global input ids (rows of the inputs, in order); ``parameters`` holds
        the method's estimates (``spacing``, ``noise``, ``clean``), ``tile_side``, ``halo``,
        ``tile_origin`` and the estimate's sample; ``stats`` the counts, ports and pass times.

    Raises
    ------
    InputError, FormatError
        Bad inputs or options (before any tile is reconstructed).
    MethodError
        A tile failed for good: the message names the tile and its input files.
    """
    with tiled_network(inputs, tiles=tiles, halo=halo, origin=origin, client=client, scheduler=scheduler,
                       workers=workers, scratch=scratch, columns=columns, drop_nonfinite=drop_nonfinite,
                       stitching=stitching, progress=progress, on_compile=on_compile) as stored:
        return stored.network()


@contextmanager
def tiled_network(inputs, *, tiles: float | Literal["auto"] = "auto", halo: float | None = None,
                  origin=None, client=None, scheduler: str = "processes", workers: int | None = None,
                  scratch=None, columns=None, drop_nonfinite: bool = False, stitching: bool = True,
                  progress: bool = False, on_compile=None) -> Iterator[StoredNetwork]:
    """:func:`reconstruct_tiled`, the network's curve points left in the scratch store.

    A context manager: inside it the :class:`~.plan.StoredNetwork` reads each curve from the
    store when asked (:func:`curvenet.io.streamed.write_network_streamed` writes it out one
    curve at a time: the client holds the nodes and a few numbers a curve, whatever N); the
    store is removed on the way out. The parameters are those of :func:`reconstruct_tiled`.

    Examples
    --------
    >>> with tiled_network("scans/", tiles="auto") as net:          # doctest: +SKIP
    ...     write_network_streamed(net, "network.ply")
    """
    if tiles != "auto" and not (isinstance(tiles, (int, float)) and np.isfinite(tiles) and tiles > 0):
        raise InputError(f"the tile side must be a positive number or 'auto', got {tiles!r}")
    if halo is not None and not (np.isfinite(halo) and halo > 0):
        raise InputError(f"the halo must be a positive number, got {halo!r}")
    files = expand_inputs(inputs)
    chunks = plan_chunks(files)
    own_client = client is None
    if own_client:
        client = make_client(scheduler, workers)
    root = None
    try:
        root = new_root(scratch)
        stored = _run(client, files, chunks, root, tiles, halo, origin, columns, drop_nonfinite, stitching, progress,
                      on_compile)
        if own_client:  # (the cluster is not needed to read the store)
            own_client = False
            _close(client)
        yield stored
    finally:
        if root is not None:
            remove_root(root)
        if own_client:
            _close(client)


def _close(client) -> None:
    cluster = client.cluster
    client.close()
    if cluster is not None:
        cluster.close()


def _progress(futures, show: bool):
    if show:
        from distributed import progress

        progress(list(futures), notebook=False)


def _workers_here(client) -> bool:
    """Whether the workers of ``client`` run on this machine and read its numba cache: a
    LocalCluster's (its processes inherit this environment). Workers elsewhere compile for
    themselves, each on its first tile, as before."""
    from distributed import LocalCluster

    return isinstance(getattr(client, "cluster", None), LocalCluster)


def _run(client, files, chunks, root: Path, tiles, halo, origin, columns, drop_nonfinite, stitching, show,
         on_compile=None):
    tm = {}
    t0 = time.perf_counter()
    # 1. scan: counts, dimension, bounds (offsets of whole-read files follow)
    fut = {c: client.submit(tasks.scan, c, columns, drop_nonfinite, pure=False, retries=TASK_RETRIES)
           for c in chunks}
    _progress(fut.values(), show)
    scans = _gather(client, fut, lambda c, exc: _input_error(c.path, exc))
    scans = list(scans.values())
    dims = {s[1] for s in scans}
    if len(dims) > 1:
        raise InputError(f"the inputs mix 2D and 3D points ({', '.join(str(f) for f in files)})")
    dim = dims.pop()
    counts = [s[0] for s in scans]
    offsets = np.r_[0, np.cumsum(counts)[:-1]].astype(np.int64)
    chunks = [dataclasses.replace(c, offset=int(o)) for c, o in zip(chunks, offsets)]
    lo = np.min([s[2] for s in scans], axis=0)
    hi = np.max([s[3] for s in scans], axis=0)
    n_total = int(sum(counts))
    if tiles == "auto":
        extent = float(np.max(hi - lo)) or 1.0
        side = extent / max(1, int(np.ceil(n_total / TILE_AUTO_POINTS))) * (1 + 1e-9)
    else:
        side = float(tiles)
    if origin is None:
        origin = lo
    origin = np.asarray(origin, dtype=float).ravel()
    if origin.shape != (dim,):
        raise InputError(f"the tile origin needs {dim} coordinates, got {origin.size}")
    grid = TileGrid(tuple(float(x) for x in origin), side)
    tm["scan"] = time.perf_counter() - t0

    # 2. bin every chunk into the tiles it touches
    t1 = time.perf_counter()
    fut = {i: client.submit(tasks.bin_chunk, c, i, grid, str(root), columns, drop_nonfinite, pure=False,
                            retries=TASK_RETRIES) for i, c in enumerate(chunks)}
    _progress(fut.values(), show)
    binned = _gather(client, fut, lambda i, exc: _input_error(chunks[i].path, exc))
    tile_count: dict = {}
    tile_files: dict = {}
    for i, per in binned.items():
        for key, n in per.items():
            tile_count[key] = tile_count.get(key, 0) + n
            tile_files.setdefault(key, set()).add(chunks[i].path)
    keys = sorted(tile_count)
    tm["bin"] = time.perf_counter() - t1

    # the kernels' first compile: once, shared out over this machine's cores, before any
    # worker needs them (else every worker of a LocalCluster compiles all of them at once)
    # (those every run calls here; those of noisy input only once the estimates say noisy)
    t1 = time.perf_counter()
    compiling = _workers_here(client) and compile_pending(max(tile_count.values(), default=0))
    if compiling:
        if on_compile is not None:
            on_compile()
        precompile(names=COMMON)
        tm["compile"] = time.perf_counter() - t1

    # 3. the whole-cloud estimates: from whole tiles spread over the cloud (all of it when it
    #    is small), then, for a larger cloud, exactly from every tile (see .estimates)
    t1 = time.perf_counter()
    sample = _sample_tiles(keys, tile_count)

    def submit(fn, *args):
        return client.submit(fn, *args, pure=False, retries=TASK_RETRIES)

    def gather(futures):
        return _gather(client, futures, lambda _, exc: exc if isinstance(exc, CurvenetError)
                       else MethodError(f"the whole-cloud estimates failed ({_one_line(exc)})"))

    est, n_est = gather({"estimates": submit(tasks.estimate_sample, str(root), sample)})["estimates"]
    inexact = 0
    prepared = False
    if len(sample) < len(keys):
        # the sample gave the scale (and the halo); the medians over every tile give the values
        # themselves. Each tile computes them on its box with the halo of its reconstruction,
        # prepared once for both (when a halo given is smaller than the estimates need, on the
        # estimates' box, and the tiles prepare their own again)
        h0 = halo_width(est)
        H = h0 if halo is None else float(halo)
        prepared = H >= h0
        est, n_est, inexact = whole_cloud_estimates(submit, gather, str(root), grid, keys, H if prepared else h0,
                                                    lo, hi, keep=prepared)
    est = Estimates(float(est.hmed), float(est.sigma))
    if len(sample) == len(keys):  # (the estimates of one task on every point: the halo from them)
        H = halo_width(est) if halo is None else float(halo)
    tm["estimate"] = time.perf_counter() - t1
    if compiling and not est.clean:  # (a noisy cloud: its own kernels too)
        t1 = time.perf_counter()
        precompile(names=NOISY_ONLY)
        tm["compile"] += time.perf_counter() - t1

    # 4. one task per tile that owns points
    t1 = time.perf_counter()
    occ = frozenset(keys)
    fut = {key: client.submit(tasks.run_tile, str(root), grid, key, H, est, occ, prepared, pure=False,
                              retries=TASK_RETRIES, key=f"tile-{'_'.join(map(str, key))}-{root.name}") for key in keys}
    _progress(fut.values(), show)

    def tile_failed(key, exc):
        files_ = sorted({f for nb in grid.neighbours(key, H) for f in tile_files.get(nb, ())})
        return MethodError(f"tile {key} (box {_box(grid, key)}) failed: {_one_line(exc)}; "
                           f"its input files: {', '.join(files_)}")

    parts = list(_gather(client, fut, tile_failed).values())
    tm["tiles"] = time.perf_counter() - t1
    n_max = max((p.n_points for p in parts), default=0)
    n_prepared = sum(p.prepared for p in parts)

    # 5. stitch (and, under noise, the fit of the method's stage 8 for the curves that cross a
    #    face: each tile fitted the curves it holds whole)
    t1 = time.perf_counter()
    net = stitch(parts, est.hmed, root, join=stitching, sigma=None if est.clean else est.sigma)
    del parts
    tm["stitch"] = time.perf_counter() - t1
    tm["total"] = time.perf_counter() - t0
    net.parameters.update({
        "method": "robust",
        "spacing": est.hmed,
        "noise": est.sigma,
        "clean": est.clean,
        "fit": not est.clean,
        "estimates_points": n_est,
        "estimates_tiles": len(sample),
        "estimates_exact": inexact == 0,
        "estimates_inexact_points": inexact,
        "halo": H,
        "tile_side": side,
        "tile_origin": [float(x) for x in grid.origin],
        "tiles": len(keys),
    })
    net.stats.update({"N_n": net.n_nodes, "N_c": net.n_curves, "N_d": n_total,
                      "tile_points_max": n_max,
                      "tiles_prepared": n_prepared,
                      "time": tm})
    return net


def _box(grid: TileGrid, key) -> str:
    lo, hi = grid.box(key)
    return "[" + ", ".join(f"{a:g}..{b:g}" for a, b in zip(lo, hi)) + ")"


def _sample_tiles(keys: list, count: dict) -> list:
    """Whole tiles spread evenly over the sorted keys, about :data:`ESTIMATE_POINTS` points in
    all (every tile when the cloud is no larger)."""
    total = sum(count.values())
    if total <= ESTIMATE_POINTS:
        return list(keys)
    n = len(keys)
    take, got = [], 0
    # a stride through the keys, then fill in: tiles from every part of the cloud
    stride = max(1, int(round(total / ESTIMATE_POINTS)))
    for start in range(stride):
        for j in range(start, n, stride):
            if got >= ESTIMATE_POINTS:
                return sorted(take)
            take.append(keys[j])
            got += count[keys[j]]
    return sorted(take)
