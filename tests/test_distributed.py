"""Tiled reconstruction on Dask (curvenet.distributed): the tiled network equals the network of
one process, on a LocalCluster of worker processes, on adversarial tile layouts."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from curvenet.distributed import TileGrid, halo_width, network_difference, reconstruct_tiled  # noqa: E402
from curvenet.methods.robust import Estimates, estimate  # noqa: E402
from curvenet.reconstruct import reconstruct  # noqa: E402

SIDE = 20.0  # the adversarial scene: spacing 1, tiles of 20 spacings, origin (0, 0)


def _segment(a, b, h=1.0, with_ends=True):
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = max(int(round(np.linalg.norm(b - a) / h)), 1)
    t = np.linspace(0, 1, n + 1)
    if not with_ends:
        t = t[1:]
    return a + t[:, None] * (b - a)


def _circle(c, r, h=1.0):
    n = int(round(2 * np.pi * r / h))
    t = np.linspace(0, 2 * np.pi, n, endpoint=False) + 0.1
    return np.asarray(c, float) + r * np.c_[np.cos(t), np.sin(t)]


def adversarial_scene(noise: float = 0.0, rng=0) -> np.ndarray:
    """2D points (spacing 1) placed against the tiles of side 20 at origin (0, 0).

    - a junction exactly on a tile corner (0, 0), three arms;
    - a junction exactly on a face (x = 60) of a curve running along that face;
    - a loop tangent to the four faces of its tile, a loop inside one tile, a loop around the
      corner (240, 0) (four tiles);
    - a long curve over some twenty tiles;
    - a free end just inside the halo of the tiles left of it;
    - between them, empty tiles and tiles with halo points only.
    """
    P = [np.zeros((1, 2))]
    for ang in (20.0, 140.0, 260.0):
        u = np.array([np.cos(np.radians(ang)), np.sin(np.radians(ang))])
        P.append(_segment(u, 26 * u))
    P.append(_segment((60, -15), (60, 35)))  # along the face x = 60
    P.append(_segment((61, 10), (85, 10)))  # the branch: junction on the face at (60, 10)
    P.append(_circle((130, 10), 10))  # tangent to x = 120, 140 and y = 0, 20
    P.append(_circle((190, 10), 5))  # inside tile (9, 0)
    P.append(_circle((240, 0), 8))  # around the corner (240, 0)
    x = np.arange(-40.0, 300.0, 1.0)
    P.append(np.c_[x, 80 + 8 * np.sin(x / 15)])  # long curve
    H = halo_width(Estimates(1.0, 0.0))
    P.append(_segment((340 + 0.95 * H, -40), (430, -40)))  # free end just inside tile 16's halo
    P = np.vstack(P)
    if noise:
        P = P + np.random.default_rng(rng).normal(scale=noise, size=P.shape)
    return P


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def _save(tmp_path, P, name="p.npy"):
    f = tmp_path / name
    np.save(f, P)
    return f


def _assert_same(one, tiled, spacing):
    diff = network_difference(one, tiled, 0.5 * spacing)
    assert diff is None, diff


@pytest.fixture(scope="module")
def scene_clean():
    P = adversarial_scene()
    return P, reconstruct(P)


@pytest.mark.slow
def test_adversarial_scene_equals_one_process(client, scene_clean, tmp_path):
    P, one = scene_clean
    f = _save(tmp_path, P)
    net = reconstruct_tiled(f, tiles=SIDE, origin=(0.0, 0.0), client=client)
    _assert_same(one, net, one.parameters["spacing"])
    assert net.stats["unmatched_ports"] == 0 and net.stats["ports"] > 40
    # the features are there: junction on the corner, junction on the face, 3 loops without node
    for at in ((0.0, 0.0), (60.0, 10.0)):
        near = np.linalg.norm(net.nodes - at, axis=1) < 0.1
        assert near.sum() == 1 and net.valence[near][0] == 3
    assert sum(c.start is None for c in net.curves) == 3
    # the long curve is one curve, across its tiles
    long = [c for c in net.curves if c.points[:, 1].min() > 60]
    assert len(long) == 1 and np.ptp(long[0].points[:, 0]) > 330
    # empty tiles and halo-only tiles ran no task
    grid = TileGrid((0.0, 0.0), SIDE)
    keys = {tuple(k) for k in grid.keys_of(P).tolist()}
    assert net.parameters["tiles"] == len(keys)
    assert (16, -2) not in keys and 0.95 * halo_width(Estimates(1.0, 0.0)) < net.parameters["halo"]
    # global ids: every curve point that is an input point is that input point
    for c in net.curves:
        m = c.indices >= 0
        assert np.array_equal(P[c.indices[m]], c.points[m])


@pytest.mark.slow
def test_negative_control_without_stitching_the_equality_fails(client, scene_clean, tmp_path):
    P, one = scene_clean
    net = reconstruct_tiled(_save(tmp_path, P), tiles=SIDE, origin=(0.0, 0.0), client=client, stitching=False)
    assert network_difference(one, net, 0.5 * one.parameters["spacing"]) is not None
    assert net.stats["unmatched_ports"] == net.stats["ports"] > 0


def test_noisy_scene_equals_one_process(client, tmp_path):
    P = adversarial_scene(noise=0.15, rng=3)
    one = reconstruct(P)
    net = reconstruct_tiled(_save(tmp_path, P), tiles=SIDE, origin=(0.0, 0.0), client=client)
    _assert_same(one, net, one.parameters["spacing"])
    assert net.parameters["clean"] is False and net.parameters["noise"] == one.parameters["noise"]


def test_corridor_with_outliers_equals_one_process(client, tmp_path):
    """Noise and 1.5% outliers (the corridor of the scale benchmark, 5 spans): an outlier's
    spacing, and every radius of it, reached tens of median spacings, beyond the halo, so tiles
    found junctions and ends the whole cloud did not (64 nodes against 60 before the method
    dropped the points alone in space)."""
    from curvenet.synth.corridor import corridor_layout, corridor_span

    lay = corridor_layout(5, wires=4, rng=1)
    P = np.vstack([corridor_span(lay, i, noise=0.03, outliers=0.015, rng=1) for i in range(lay.n_spans + 1)])
    one = reconstruct(P)
    net = reconstruct_tiled(_save(tmp_path, P), tiles=60.0, client=client)
    assert net.parameters["tiles"] > 30
    _assert_same(one, net, one.parameters["spacing"])
    assert one.parameters["isolated_dropped"] > 0.5 * 0.015 * len(P)


def test_the_halo_holds_the_isolation_test_of_every_point_within_the_reach():
    from curvenet.distributed.halo import HALO_MARGIN, interaction_reach
    from curvenet.methods.robust.thresholds import SPACING

    in_h, _ = interaction_reach()
    assert HALO_MARGIN * in_h >= in_h + SPACING.isolated


@pytest.fixture(scope="module")
def tree3d():
    from curvenet import synth

    P, _ = synth.sample(synth.model("tree"), noise=0.1, rng=2)
    return P, reconstruct(P)


@pytest.mark.parametrize("side,shift", [(20, (0.31, 0.77, 0.05)), (45, (0.9, 0.1, 0.5)), (None, (0.5, 0.5, 0.5))])
def test_3d_equal_for_tile_sides_origin_shifts_and_input_order(client, tree3d, tmp_path, side, shift):
    P, one = tree3d
    h = one.parameters["spacing"]
    perm = np.random.default_rng(side or 7).permutation(len(P))
    side_u = 1e3 * np.ptp(P).max() if side is None else side * h
    origin = P.min(axis=0) - np.asarray(shift) * side_u
    net = reconstruct_tiled(_save(tmp_path, P[perm]), tiles=side_u, origin=origin, client=client)
    _assert_same(one, net, h)
    # indices are rows of the (permuted) input: the cloud is noisy, so the stitched curves are
    # fitted and each point is its input point moved onto the fit (by about the noise; a
    # neighbouring sample lies ten noise deviations away)
    assert net.parameters["fit"] is True
    moved = np.concatenate([np.linalg.norm(P[perm][c.indices[c.indices >= 0]] - c.points[c.indices >= 0], axis=1)
                            for c in net.curves])
    assert np.median(moved) < 2.0 * net.parameters["noise"]


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 4])
def test_threads_scheduler_with_1_and_4_workers(tree3d, tmp_path, workers):
    P, one = tree3d
    h = one.parameters["spacing"]
    net = reconstruct_tiled(_save(tmp_path, P), tiles=45 * h, scheduler="threads", workers=workers)
    _assert_same(one, net, h)


@pytest.mark.slow
def test_halo_doubled_changes_nothing(client, tree3d, tmp_path):
    P, one = tree3d
    h = one.parameters["spacing"]
    f = _save(tmp_path, P)
    a = reconstruct_tiled(f, tiles=45 * h, client=client)
    b = reconstruct_tiled(f, tiles=45 * h, client=client, halo=2 * a.parameters["halo"])
    assert a.parameters["halo"] == pytest.approx(halo_width(estimate(P)))
    assert np.array_equal(a.nodes, b.nodes) and len(a.curves) == len(b.curves)
    for ca, cb in zip(a.curves, b.curves):
        assert np.array_equal(ca.points, cb.points) and np.array_equal(ca.indices, cb.indices)
    # and a halo far too small does change it (the test can fail)
    c = reconstruct_tiled(f, tiles=45 * h, client=client, halo=2 * h)
    assert network_difference(one, c, 0.5 * h) is not None


def test_estimates_are_the_whole_clouds_with_or_without_a_sample(client, tree3d, tmp_path, monkeypatch):
    from curvenet.distributed import run

    P, one = tree3d
    est = estimate(P)
    f = _save(tmp_path, P)
    h = one.parameters["spacing"]
    net = reconstruct_tiled(f, tiles=45 * h, client=client)
    assert net.parameters["estimates_exact"] is True
    assert (net.parameters["spacing"], net.parameters["noise"]) == (est.hmed, est.sigma)
    # a cloud larger than the sample: the sample sets the scale, the medians over every tile
    # the values (tests/test_distributed_estimates.py shows the sample alone would differ)
    monkeypatch.setattr(run, "ESTIMATE_POINTS", len(P) // 3)
    sub = reconstruct_tiled(f, tiles=45 * h, client=client)
    assert sub.parameters["estimates_exact"] is True and sub.parameters["estimates_points"] == len(P)
    assert (sub.parameters["spacing"], sub.parameters["noise"]) == (est.hmed, est.sigma)
    assert sub == net


def test_chunked_inputs_several_files_laz_and_npy(client, tmp_path, monkeypatch):
    """Row ranges of a .npy (memmap) and of LAZ files (laspy's chunked reader), several files:
    one cloud, the ids its rows in order."""
    laspy = pytest.importorskip("laspy")
    from curvenet.distributed import inputs

    monkeypatch.setattr(inputs, "CHUNK_ROWS", 150)
    P = np.c_[adversarial_scene()[:600], np.zeros(600)] * 0.01 + [1000.0, 2000.0, 5.0]
    parts = np.array_split(np.arange(len(P)), 3)
    folder = tmp_path / "tiles"
    folder.mkdir()
    np.save(folder / "a.npy", P[parts[0]])
    for name, idx in (("b.laz", parts[1]), ("c.laz", parts[2])):
        hdr = laspy.LasHeader(point_format=3, version="1.2")
        hdr.scales, hdr.offsets = np.array([1e-4] * 3), np.array([1000.0, 2000.0, 0.0])
        las = laspy.LasData(hdr)
        las.x, las.y, las.z = P[idx].T
        las.write(folder / name)
    back = np.vstack([P[parts[0]]] + [np.c_[laspy.read(folder / n).x, laspy.read(folder / n).y, laspy.read(folder / n).z]
                                      for n in ("b.laz", "c.laz")])
    one = reconstruct(back)
    net = reconstruct_tiled(folder, tiles=0.2, client=client)
    _assert_same(one, net, one.parameters["spacing"])
    assert net.stats["N_d"] == len(back)
    for c in net.curves:
        m = c.indices >= 0
        assert np.array_equal(back[c.indices[m]], c.points[m])


@pytest.mark.slow
def test_a_killed_worker_is_survived_with_the_same_output(tree3d, tmp_path):
    """SIGKILL one worker process while it runs a tile: Dask reruns its tasks elsewhere and the
    output is the same network, exactly (the futures of the finished reference run were
    released, so nothing of it is recomputed from its removed scratch store)."""
    import threading

    P, one = tree3d
    h = one.parameters["spacing"]
    f = _save(tmp_path, P)
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    try:
        ref = reconstruct_tiled(f, tiles=20 * h, client=c)
        out = {}
        th = threading.Thread(target=lambda: out.setdefault("net", reconstruct_tiled(f, tiles=20 * h, client=c)))
        th.start()
        victim = None
        for _ in range(1200):  # wait until a tile runs, then kill the process that runs it
            busy = {w: ts for w, ts in c.processing().items() if any(str(t).startswith("tile-") for t in ts)}
            if busy:
                victim = sorted(busy)[0]
                break
            time.sleep(0.05)
        assert victim is not None
        pid = c.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)
        th.join(300)
        assert "net" in out, "the run did not survive the killed worker"
        assert out["net"] == ref
        _assert_same(one, out["net"], 0.5 * h)
    finally:
        c.close()
        cluster.close()


# ------------------------------------------------------------------------------------ the CLI
def _cli(*args, cwd=None):
    env = dict(os.environ)
    return subprocess.run([sys.executable, "-m", "curvenet.cli", "reconstruct", *map(str, args)],
                          capture_output=True, text=True, env=env, cwd=cwd, timeout=300)


@pytest.mark.slow
def test_cli_tiles_a_folder_of_files_and_writes_the_network(tmp_path):
    P = adversarial_scene()[:600]
    folder = tmp_path / "in"
    folder.mkdir()
    for i, part in enumerate(np.array_split(P, 3)):
        np.save(folder / f"t{i}.npy", part)
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    (scratch / "keep.txt").write_text("the user's")
    out = tmp_path / "net.json"
    ply, vtu = tmp_path / "net.ply", tmp_path / "net.vtu"  # (streamed as .json; .vtu built in memory)
    r = _cli(str(folder / "t*.npy"), "-o", out, "-o", ply, "-o", vtu, "--tiles", "20", "--workers", "2",
             "--scratch", scratch, "-q")
    assert r.returncode == 0, r.stderr
    from curvenet.io import read_network
    from curvenet.io.network_io import network_to_ply

    net = read_network(out)
    _assert_same(reconstruct(P), net, 1.0)
    assert net.parameters["halo"] > 0 and net.parameters["tile_side"] == 20
    assert sorted(p.name for p in scratch.iterdir()) == ["keep.txt"]
    assert ply.read_bytes() == network_to_ply(net)
    meshio = pytest.importorskip("meshio")
    m = meshio.read(vtu)
    assert sum(len(c.data) for c in m.cells) == sum(len(c.points) - 1 + c.closed for c in net.curves)


def test_the_stored_network_written_piece_by_piece_is_the_network_in_memory(client, tmp_path):
    """A tiled run's network, its points left in the scratch store, written one curve at a time
    (.json, .ply): the bytes of the network built in memory; the client holds no curve point
    (the stored network's curves are plans over the tiles' files)."""
    from curvenet.distributed import tiled_network
    from curvenet.io.network_io import network_to_json, network_to_ply
    from curvenet.io.streamed import write_network_streamed

    P = adversarial_scene(noise=0.1)
    f = _save(tmp_path, P)
    with tiled_network(f, tiles=SIDE, client=client) as stored:
        assert not any(hasattr(p, "points") for p in stored.plans)
        net = stored.network()
        assert stored.stats["fitted_here"] > 0  # (curves fitted once joined: spilled by the client)
        a = write_network_streamed(stored, tmp_path / "a.json")
        b = write_network_streamed(stored, tmp_path / "b.ply")
    assert a.read_bytes() == network_to_json(net).encode() and b.read_bytes() == network_to_ply(net)
    _assert_same(reconstruct(P), net, 1.0)


@pytest.mark.parametrize("args,msg", [
    (["--tiles=-3"], "positive"),
    (["--tiles", "20", "--spacing", "1"], "method parameters"),
    (["--tiles", "20", "--png", "x.png"], "--png"),
    (["--halo", "3"], "need --tiles"),
])
def test_cli_bad_tile_options_one_line_exit_2(tmp_path, args, msg):
    f = _save(tmp_path, adversarial_scene()[:100])
    r = _cli(f, "-o", tmp_path / "o.json", *args)
    last = r.stderr.strip().splitlines()[-1]  # (argparse's own errors come after its usage lines)
    assert r.returncode == 2 and msg in last and "error" in last, r.stderr
    assert "Traceback" not in r.stderr and not (tmp_path / "o.json").exists()


def test_cli_mixed_2d_and_3d_inputs_exit_2(tmp_path):
    a = _save(tmp_path, adversarial_scene()[:100], "a.npy")
    b = _save(tmp_path, np.c_[adversarial_scene()[:100], np.zeros(100)], "b.npy")
    r = _cli(a, b, "-o", tmp_path / "o.json", "--tiles", "20", "--scheduler", "threads", "--workers", "1")
    assert r.returncode == 2 and "mix 2D and 3D" in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "o.json").exists()


def _fails_on_tile_5_1(root, grid, key, halo, est, occ, prepared):
    """A tile task that fails for good on tile (5, 1) (module level: Dask pickles it)."""
    from curvenet.distributed.tasks import METHOD_LOCK  # noqa: F401  (the real module is loaded)

    if tuple(key) == (5, 1):
        raise RuntimeError("disk on fire")
    return _REAL_RUN_TILE(root, grid, key, halo, est, occ, prepared)


def test_a_failing_tile_one_line_exit_1_no_output_scratch_removed(tmp_path, monkeypatch, capsys):
    global _REAL_RUN_TILE
    from curvenet.cli import main
    from curvenet.distributed import tasks

    _REAL_RUN_TILE = tasks.run_tile
    monkeypatch.setattr(tasks, "run_tile", _fails_on_tile_5_1)
    f = _save(tmp_path, adversarial_scene()[:300])
    scratch = tmp_path / "scratch"
    out = tmp_path / "o.json"
    code = main(["reconstruct", str(f), "-o", str(out), "--tiles", "20", "--scheduler", "threads",
                 "--workers", "2", "--scratch", str(scratch), "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1, err
    assert "tile (5, 1)" in err[0] and "disk on fire" in err[0] and str(f) in err[0]
    assert not out.exists() and list(scratch.iterdir()) == []


def test_scratch_in_the_temporary_folder_is_removed(tmp_path, monkeypatch, tree3d):
    import tempfile

    P, one = tree3d
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    from curvenet.distributed.scratch import SCRATCH_PREFIX

    reconstruct_tiled(_save(tmp_path, P), tiles=30 * one.parameters["spacing"], scheduler="threads", workers=2)
    assert not [p for p in tmp.iterdir() if p.name.startswith(SCRATCH_PREFIX)]  # (Dask keeps its own folder)


def test_core_never_imports_the_distributed_package_nor_dask():
    """Dask is imported only in curvenet.distributed; the core never imports curvenet.distributed."""
    import ast

    import curvenet

    src = Path(curvenet.__file__).parent
    bad = []
    for f in sorted(src.rglob("*.py")):
        rel = f.relative_to(src).as_posix()
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            for n in names:
                if n.split(".")[0] in ("dask", "distributed") and not rel.startswith("distributed/"):
                    bad.append(f"{rel}: {n}")
                if "distributed" in n and not n.startswith(("dask", "distributed")) and not rel.startswith(("distributed/", "cli/")):
                    bad.append(f"{rel}: {n}")
    assert not bad, bad


@pytest.mark.slow
def test_ctrl_c_removes_the_scratch_store(tmp_path, tree3d):
    P, one = tree3d
    f = _save(tmp_path, np.vstack([P + [i * 10.0, 0, 0] for i in range(4)]))
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    out = tmp_path / "o.json"
    proc = subprocess.Popen([sys.executable, "-m", "curvenet.cli", "reconstruct", str(f), "-o", str(out), "--tiles",
                             str(20 * one.parameters["spacing"]), "--scheduler", "threads", "--workers", "1",
                             "--scratch", str(scratch), "-q"], stderr=subprocess.PIPE, text=True)
    for _ in range(1200):  # wait until the run has tiles in its store
        if any(d.is_dir() and any(d.iterdir()) for d in scratch.iterdir()) or proc.poll() is not None:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 130 and "interrupted" in err, err
    assert list(scratch.iterdir()) == [] and not out.exists()


def test_curves_fitted_by_their_tiles_equal_curves_fitted_once_stitched(tree3d, tmp_path, monkeypatch):
    # under noise each tile fits the curves it holds whole and the stitching only those that
    # cross a face: the network equals the one whose every curve is fitted once stitched
    from curvenet.distributed import tasks

    P, one = tree3d
    h = one.parameters["spacing"]
    f = _save(tmp_path, P)
    net = reconstruct_tiled(f, tiles=20 * h, scheduler="threads", workers=1)
    assert 0 < net.stats["fitted_here"] < net.n_curves
    monkeypatch.setattr(tasks, "fit_whole_pieces", lambda tile, sigma: tile)
    ref = reconstruct_tiled(f, tiles=20 * h, scheduler="threads", workers=1)
    assert ref.stats["fitted_here"] == ref.n_curves
    assert np.array_equal(net.nodes, ref.nodes) and len(net.curves) == len(ref.curves)
    for a, b in zip(net.curves, ref.curves):
        assert (a.start, a.end, a.closed) == (b.start, b.end, b.closed)
        assert np.array_equal(a.indices, b.indices)
        assert np.allclose(a.points, b.points, rtol=0, atol=1e-9 * h)
    _assert_same(one, net, h)


def _query_workers(monkeypatch) -> list:
    """The ``workers`` of every neighbour query from now on, in order (a spy on
    :func:`curvenet.neighbors.query`)."""
    from curvenet import neighbors

    seen = []
    real = neighbors.query

    def spy(tree, x, **kw):
        seen.append(kw.get("workers"))
        return real(tree, x, **kw)

    monkeypatch.setattr(neighbors, "query", spy)
    return seen


def test_a_task_runs_the_method_on_its_own_thread(monkeypatch):
    # a worker has one thread: within a task the neighbour queries and numba's parallel loops
    # take one thread (and every core again after it)
    from curvenet import neighbors
    from curvenet.distributed.tasks import method_slot

    seen = _query_workers(monkeypatch)
    P = np.random.default_rng(0).random((neighbors.SERIAL_ROWS + 500, 3))  # (fewer: one thread anyway)
    neighbors.knn(P, 4)
    with method_slot():
        neighbors.knn(P, 4)
        numba = pytest.importorskip("numba")
        assert numba.get_num_threads() == 1
    neighbors.knn(P, 4)
    assert seen == [-1, 1, -1]
    assert numba.get_num_threads() == numba.config.NUMBA_NUM_THREADS


def _fast(x):
    return np.full(1000, x)


def _slow_then_look(keys):
    # a task that outlives the others, then says which of their results its worker still holds
    from distributed import get_worker

    time.sleep(3.0)
    data = get_worker().data
    return [k for k in keys if k in data]


def test_a_pass_releases_each_result_on_the_workers_once_fetched():
    # the tiles' pieces of a large cloud must not pile up on the workers until a pass ends
    from curvenet.distributed.run import _gather

    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None)
    c = distributed.Client(cluster)
    try:
        fast = {i: c.submit(_fast, i, key=f"fast-{i}") for i in range(3)}
        distributed.wait(list(fast.values()))
        futs = dict(fast)
        futs["slow"] = c.submit(_slow_then_look, [f"fast-{i}" for i in range(3)], key="slow")
        del fast
        out = _gather(c, futs, lambda label, exc: exc)
        assert [int(out[i][0]) for i in range(3)] == [0, 1, 2]
        assert out["slow"] == []  # released while the slow task still ran
    finally:
        c.close()
        cluster.close()


def test_a_small_query_runs_on_the_calling_thread(monkeypatch):
    # under SERIAL_ROWS rows the query takes one thread (scipy's thread start costs more than
    # it saves there); the result is the same
    from curvenet import neighbors

    seen = _query_workers(monkeypatch)
    P = np.random.default_rng(1).random((neighbors.SERIAL_ROWS + 10, 3))
    d_all, i_all = neighbors.knn(P, 5)
    d_few, i_few = neighbors.knn(P, 5, rows=np.arange(neighbors.SERIAL_ROWS - 1))
    assert seen == [-1, 1]
    assert np.array_equal(i_few, i_all[:neighbors.SERIAL_ROWS - 1]) and np.array_equal(d_few, d_all[:len(d_few)])


def test_a_first_tiled_run_compiles_the_kernels_once_on_this_machine(client, scene_clean, tmp_path, monkeypatch):
    # on a LocalCluster whose tiles will compile numba kernels, the client compiles them first
    # (warmup.precompile, shared out over the cores; its note before), not every worker at once
    from curvenet.distributed import run

    P, one = scene_clean
    f = _save(tmp_path, P)
    from curvenet.methods.robust import warmup

    calls = []
    monkeypatch.setattr(run, "precompile", lambda names=None: calls.append(names))
    monkeypatch.setattr(run, "compile_pending", lambda n: calls.append(n) or True)
    net = reconstruct_tiled(f, tiles=SIDE, origin=(0.0, 0.0), client=client, on_compile=lambda: calls.append("note"))
    # (a noise-free scene: the kernels of noisy input are left out)
    assert calls[1:] == ["note", warmup.COMMON] and 0 < calls[0] < len(P)  # (the largest tile's count)
    assert "compile" in net.stats["time"]
    calls.clear()
    monkeypatch.setattr(run.Estimates, "clean", property(lambda self: False))  # as the estimates of a noisy cloud
    reconstruct_tiled(f, tiles=SIDE, origin=(0.0, 0.0), client=client, on_compile=lambda: calls.append("note"))
    assert calls[1:] == ["note", warmup.COMMON, warmup.NOISY_ONLY]
    calls.clear()
    monkeypatch.setattr(run, "compile_pending", lambda n: False)  # the kernels in the cache: nothing
    net = reconstruct_tiled(f, tiles=SIDE, origin=(0.0, 0.0), client=client, on_compile=lambda: calls.append("note"))
    assert calls == [] and "compile" not in net.stats["time"]
    # workers that are not this machine's (a client of a running scheduler) compile for themselves
    assert run._workers_here(client) and not run._workers_here(type("Remote", (), {"cluster": None})())
