"""Start-up, first run and writers of curvenet (issue 22): the figures that a benchmark prints.

Three parts, each printed with a reference measured in the same run on the same machine (the
k=16 ``cKDTree`` query on the same points, as every speed figure of the project):

``writers``
    Every writer of :data:`curvenet.io.WRITERS` (and the ``--labels`` CSV) on a network of
    about a million points, and the surface mesh OBJ writer on a torus of as many vertices
    (:func:`torus_mesh`), best of ``--repeat`` calls, wall-clock and processor time, against
    the target of 1 s. The network
    is reconstructed once from the synthetic (noisy) cloud of ``benchmarks/perf.py`` and cached
    in ``--cache`` (``/tmp`` by default) as ``.npz``; its curves are fitted, so its ``.dxf``
    holds splines. The writers of :data:`UNFITTED_FORMATS` (``.dxf``: polylines) are timed on
    the unfitted network of the same cloud too (``fit=False``, cached beside it). With
    ``--hashes``, the SHA-256 of every file (a DXF's times and GUIDs masked), to show that two
    versions of the writers write the same bytes.
``cli``
    A fresh ``curvenet reconstruct f.xyz -o o.json`` process on a 34k-point file, best and
    median of ``--repeat`` runs (our own loop, as hyperfine would), against the target of
    0.3 s, with its breakdown: the interpreter alone, ``import numpy``, ``import numba``,
    ``import curvenet.cli`` (``python -X importtime``: the slowest modules), and the steps of
    the command as the process itself times them.
``compile``
    The first run after a fresh install (numba's cache emptied by pointing ``NUMBA_CACHE_DIR``
    at an empty folder) against a warm run on the same points, and the compile time of every
    kernel.

Usage::

    python benchmarks/startup.py                    # all parts, full sizes
    python benchmarks/startup.py --part writers --n 1e6
    python benchmarks/startup.py --part writers --hashes --repeat 1   # the digests of the files
    python benchmarks/startup.py --quick            # tiny sizes, for CI (cannot rot)

Runs above 1e6 points take the shared lock of the machine (``flock /work/notes/bigrun.lock``)
when run by hand.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

#: the writing target of issue 22 (seconds for any format of a 1M-point network)
WRITE_TARGET_S = 1.0
#: the fresh-process target of issue 22 (seconds end to end on a 34k-point file)
CLI_TARGET_S = 0.3
#: the first-run target of issue 22 (first run with an empty numba cache / warm run, at 1e6)
FIRST_RUN_TARGET = 2.0


# ------------------------------------------------------------------------------ helpers
def machine() -> str:
    """The machine in one line (from :func:`perf.machine`), with the load average now."""
    import perf

    m = perf.machine()
    return f"{m['cpu']}, {m['cores']} cores, load average {m['load']}; Python {m['python']}, numpy {m['numpy']}"


def knn_floor(P: np.ndarray) -> float:
    """One k=16 neighbour query with its tree build on ``P`` (seconds): the reference."""
    from scipy.spatial import cKDTree

    t = time.perf_counter()
    cKDTree(P).query(P, k=16, workers=-1)
    return time.perf_counter() - t


def cloud(n: int, seed: int = 0) -> np.ndarray:
    """The synthetic cloud of ``benchmarks/perf.py`` (rotated copies of the 3D models)."""
    import perf

    return perf.make_points(n, seed=seed)[0]


def save_network(net, path: Path) -> None:
    """The network as one ``.npz`` (curve arrays concatenated), for the cache between runs."""
    curves = net.curves
    sizes = np.array([len(c.points) for c in curves], dtype=np.int64)
    d = net.dimension
    np.savez(
        path,
        nodes=net.nodes,
        points=np.concatenate([c.points for c in curves]) if curves else np.zeros((0, d)),
        indices=np.concatenate([c.indices for c in curves]) if curves else np.zeros(0, np.int64),
        offsets=np.concatenate([[0], np.cumsum(sizes)]),
        start=np.array([-1 if c.start is None else c.start for c in curves], dtype=np.int64),
        end=np.array([-1 if c.end is None else c.end for c in curves], dtype=np.int64),
        closed=np.array([c.closed for c in curves], dtype=bool),
        meta=np.array(json.dumps({"parameters": _plain(net.parameters), "stats": _plain(net.stats)})),
    )


def _plain(obj):
    from curvenet.network import _jsonable

    return _jsonable(obj)


def load_network(path: Path):
    """Inverse of :func:`save_network`."""
    from curvenet import Curve, CurveNetwork

    with np.load(path) as f:
        z = {k: f[k] for k in f.files}  # (each f[k] reads the whole array again)
    off = z["offsets"]
    pts, ind = z["points"], z["indices"]
    curves = [
        Curve(pts[a:b].copy(), None if s < 0 else int(s), None if e < 0 else int(e), bool(c), ind[a:b].copy())
        for a, b, s, e, c in zip(off[:-1], off[1:], z["start"], z["end"], z["closed"])
    ]
    meta = json.loads(str(z["meta"]))
    return CurveNetwork(z["nodes"], curves, meta["parameters"], meta["stats"])


def network(n: int, cache: Path, fit: bool | None = None):
    """The network of the ``n``-point cloud and the cloud, reconstructed once and cached.

    ``fit`` is the default method's keyword: None (its default: the noisy cloud's curves are
    fitted, ``parameters["fit"]`` True) or False (the curves through the input points)."""
    P = cloud(n)
    tag = "" if fit is None else f"_fit{int(fit)}"
    path = cache / f"curvenet_startup_net_{n}{tag}.npz"
    if path.exists():
        return load_network(path), P
    import curvenet

    net = curvenet.reconstruct(P) if fit is None else curvenet.reconstruct(P, fit=fit)
    cache.mkdir(parents=True, exist_ok=True)  # (a --cache folder that is not there yet)
    save_network(net, path)
    return net, P


# ------------------------------------------------------------------------------ writers
#: Triangles per patch of the benchmark's surface mesh (a surfaced network has a patch per
#: cycle of curves; 1000 triangles a patch gives 2000 patches at a million vertices).
MESH_PATCH_TRIANGLES = 1000


def torus_mesh(n: int):
    """A triangulated torus of about ``n`` vertices and ``2 n`` triangles, the triangles cut into
    patches of :data:`MESH_PATCH_TRIANGLES` in order, as the surface mesh of a network of ``n``
    points (the mesh OBJ writer's input, the size the surfacing gives such a network)."""
    from curvenet.surfacing import SurfaceMesh

    m = max(int(np.sqrt(n)), 3)
    i, j = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
    a, b = 2 * np.pi * i.ravel() / m, 2 * np.pi * j.ravel() / m
    V = np.column_stack([np.cos(a) * (2 + np.cos(b)), np.sin(a) * (2 + np.cos(b)), np.sin(b)])
    q = (i * m + j).ravel()
    right, up = (((i + 1) % m) * m + j).ravel(), (i * m + (j + 1) % m).ravel()
    diag = (((i + 1) % m) * m + (j + 1) % m).ravel()
    T = np.concatenate([np.column_stack([q, right, up]), np.column_stack([up, right, diag])])
    patch = np.arange(len(T)) // MESH_PATCH_TRIANGLES
    cycles = [[] for _ in range(int(patch[-1]) + 1)]
    return SurfaceMesh(V, T, patch, cycles, [[] for _ in cycles])


#: The writers timed on the unfitted network too (the default one is fitted: its ``.dxf`` holds
#: splines, the unfitted one's polylines; the others write other numbers).
UNFITTED_FORMATS = (".dxf", ".swc", ".svg")

#: Lines of ezdxf's header that change from one call to the next (creation and update times,
#: GUIDs), and the stamp of its objects: masked before a DXF is hashed (``--hashes``).
_DXF_VARYING = re.compile(rb"(\$(?:TDCREATE|TDUPDATE|FINGERPRINTGUID|VERSIONGUID)\n *\d+\n)[^\n]*\n|"
                          rb"\n  1\n\d+\.\d+\.\d+ @ [^\n]*\n")


#: The CLASSES section of a DXF, whose entries ezdxf writes in the order of a set of strings
#: (Python's string hashing: another order in each process).
_DXF_CLASSES = re.compile(rb"(  2\nCLASSES\n)(.*?)(  0\nENDSEC\n)", re.S)


def output_digest(path: Path) -> str:
    """SHA-256 of a written file; in a DXF the varying header values masked
    (:data:`_DXF_VARYING`) and the classes sorted (:data:`_DXF_CLASSES`)."""
    data = path.read_bytes()
    if path.suffix == ".dxf":
        data = _DXF_VARYING.sub(lambda m: (m.group(1) or b"\n  1\n") + b"*\n", data)
        data = _DXF_CLASSES.sub(lambda m: m.group(1) + b"".join(sorted(m.group(2).split(b"  0\nCLASS\n"))) + m.group(3),
                                data, count=1)
    return hashlib.sha256(data).hexdigest()


def writers(n: int, repeat: int, cache: Path, out: Path, exts=(), hashes: bool = False) -> list[tuple]:
    """Best time of every writer (the pure function and :func:`write_network`'s file), on the
    default (fitted) network, then of :data:`UNFITTED_FORMATS` on the unfitted network."""
    from curvenet.io import WRITERS, atomic_write, write_network
    from curvenet.io.labels import labels_to_csv, point_labels

    net, P = network(n, cache)
    n_pts = sum(len(c.points) for c in net.curves)
    print(f"network: {len(P):,} input points, {net.n_nodes:,} nodes, {net.n_curves:,} curves, "
          f"{n_pts:,} curve points, fitted: {bool(net.parameters.get('fit'))}")
    floor = min(knn_floor(P) for _ in range(2))
    print(f"reference: k=16 cKDTree query on the {len(P):,} points {floor:.3f} s; the writers' times are"
          " wall-clock (cpu: this process's processor time, which the other processes of the machine"
          " do not inflate)")
    only = [e for e in (exts or WRITERS) if e in WRITERS]
    jobs = [(ext, lambda p, e=ext: write_network(net, p)) for ext in only]
    lab = point_labels(net, P)
    if not exts or ".csv" in exts:
        jobs.append((".csv (--labels)", lambda p: atomic_write(p, labels_to_csv(lab))))
    if not exts or "mesh.obj" in exts:
        from curvenet.io.mesh import mesh_to_obj

        mesh = torus_mesh(n)
        print(f"surface mesh: {len(mesh.vertices):,} vertices, {len(mesh.triangles):,} triangles, "
              f"{mesh.n_patches:,} patches")
        jobs.append((".obj (surface mesh)", lambda p: atomic_write(p, mesh_to_obj(mesh))))
    rows = _time_jobs(jobs, repeat, out, floor, hashes)
    unfitted = [e for e in only if e in UNFITTED_FORMATS]
    if unfitted:
        net_u, _ = network(n, cache, fit=False)
        print(f"unfitted network (fit=False): {net_u.n_nodes:,} nodes, {net_u.n_curves:,} curves, "
              f"{sum(len(c.points) for c in net_u.curves):,} curve points")
        jobs = [(f"{ext} (unfitted)", lambda p, e=ext: write_network(net_u, p)) for ext in unfitted]
        rows += _time_jobs(jobs, repeat, out, floor, hashes, json_best=next((r[1] for r in rows if r[0] == ".json"), None))
    return rows


def _time_jobs(jobs: list, repeat: int, out: Path, floor: float, hashes: bool, json_best: float | None = None) -> list[tuple]:
    """Best wall-clock and processor time of each ``(label, job)`` (``job(path)`` writes the file),
    printed against the query ``floor`` and the target; with ``hashes`` the file's digest too.

    Each call writes a new file: the previous call's is removed before the clock starts.
    Replacing an existing file makes the rename free the old one's pages and blocks, which cost
    this machine's disk (ext4, online discard) 0.3-0.5 s of system time for the 150 MB of a
    million-point DXF: the file system's time, not the writer's, and the same for any writer
    of as many bytes."""
    rows = []
    for ext, job in jobs:
        if ext.startswith(".dxf"):
            try:
                import ezdxf  # noqa: F401
            except ImportError:
                print(f"  {ext}: skipped (ezdxf missing)")
                continue
        best = cpu = None
        path = out / ("net" + ext.split()[0])
        for _ in range(repeat):
            path.unlink(missing_ok=True)  # a new file each time (see _time_jobs)
            t, c = time.perf_counter(), time.process_time()
            job(path)
            s, c = time.perf_counter() - t, time.process_time() - c
            best = s if best is None else min(best, s)
            cpu = c if cpu is None else min(cpu, c)
        size = path.stat().st_size / 1e6
        digest = f"  sha256 {output_digest(path)}" if hashes else ""
        path.unlink()
        flag = "ok" if best <= WRITE_TARGET_S else "OVER"
        cpu_flag = "ok" if cpu <= WRITE_TARGET_S else "OVER"
        rows.append((ext, best, best / floor, size, flag))
        json_best = json_best or next((r[1] for r in rows if r[0] == ".json"), None)
        vs_json = f"  {best / json_best:5.2f} x json" if json_best else ""
        print(f"  {ext:20s} {best:7.3f} s (cpu {cpu:6.3f} s)  {best / floor:6.2f} x query{vs_json}  {size:8.1f} MB  "
              f"load {os.getloadavg()[0]:4.1f}  target {WRITE_TARGET_S} s: {flag} (cpu: {cpu_flag}){digest}", flush=True)
    return rows


# ------------------------------------------------------------------------------ fresh CLI
def _env(**extra) -> dict:
    env = dict(os.environ)
    env.update(extra)
    return env


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(cmd: list[str], env: dict) -> tuple[float, float]:
    """Wall-clock and processor time (user + system) of one process running ``cmd``."""
    t, c = time.perf_counter(), _children_cpu()
    r = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    s, c = time.perf_counter() - t, _children_cpu() - c
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed: {r.stderr.strip()}")
    return s, c


def _timed(cmd: list[str], env: dict, repeat: int) -> tuple[float, float, float]:
    """Best and median wall-clock time and best processor time of ``repeat`` runs."""
    _run(cmd, env)  # a first run fills the file cache (and numba's, when empty)
    runs = [_run(cmd, env) for _ in range(repeat)]
    return min(w for w, _ in runs), statistics.median(w for w, _ in runs), min(c for _, c in runs)


def fresh_cli(n: int, repeat: int, tmp: Path, plain: bool = True) -> dict:
    """A fresh ``curvenet reconstruct`` process on an ``n``-point file, and its breakdown."""
    import perf

    P = cloud(n)
    xyz = tmp / f"p{n}.xyz"
    perf.write_xyz(xyz, P)
    out = tmp / "o.json"
    py = sys.executable
    env = _env()
    floor = min(knn_floor(P) for _ in range(3))
    print(f"reference: k=16 cKDTree query on the {len(P):,} points {floor * 1e3:.1f} ms")
    cli = [py, "-m", "curvenet", "reconstruct", str(xyz), "-o", str(out), "-q"]
    res = {}
    for label, cmd, e in (
        ("python -c pass", [py, "-c", "pass"], env),
        ("python -c 'import numpy'", [py, "-c", "import numpy"], env),
        ("python -c 'import scipy.spatial'", [py, "-c", "import scipy.spatial"], env),
        ("python -c 'import numba'", [py, "-c", "import numba"], env),
        ("python -c 'import curvenet'", [py, "-c", "import curvenet"], env),
        ("python -c 'import curvenet.cli'", [py, "-c", "import curvenet.cli"], env),
        ("curvenet reconstruct (numba)", cli, env),
        ("curvenet reconstruct (CURVENET_NO_NUMBA=1)", cli, _env(CURVENET_NO_NUMBA="1")),
    ):
        if "NO_NUMBA" in label and not plain:
            continue
        if "NO_NUMBA" in label and n > 5000:  # minutes in plain Python: once
            best, cpu = _run(cmd, e)
            med = best
        else:
            best, med, cpu = _timed(cmd, e, repeat)
        res[label] = (best, cpu)
        extra = ""
        if label.startswith("curvenet reconstruct"):
            flag = "ok" if best <= CLI_TARGET_S else "OVER"
            extra = f"  {best / floor:5.1f} x query  target {CLI_TARGET_S} s: {flag}"
        print(f"  {label:45s} best {best:6.3f} s  median {med:6.3f} s  cpu {cpu:6.3f} s{extra}", flush=True)
    _importtime(py, env)
    _steps(xyz, out, env)
    return res


def _importtime(py: str, env: dict, top: int = 12) -> None:
    """The slowest imports of ``curvenet.cli`` plus the method (``-X importtime``, cumulative)."""
    code = "import curvenet.cli, curvenet.io, curvenet.methods.robust.pipeline"
    r = subprocess.run([py, "-X", "importtime", "-c", code], env=env, capture_output=True, text=True)
    rows = []
    for line in r.stderr.splitlines():
        parts = line.split("|")
        if not line.startswith("import time:") or len(parts) != 3 or "cumulative" in line:
            continue
        depth = (len(parts[2]) - len(parts[2].lstrip()) - 1) // 2
        if depth <= 1:
            rows.append((int(parts[1]), parts[2].strip()))
    print(f"  -X importtime of {code!r}, the {top} slowest of the top two levels (cumulative, wall):")
    for cum, name in sorted(rows, reverse=True)[:top]:
        print(f"    {cum / 1e3:7.1f} ms  {name}")


#: a fresh process that times the steps of ``curvenet reconstruct`` from the inside
_STEPS = r"""
import sys, time
t0 = time.perf_counter()
import curvenet.cli
t1 = time.perf_counter()
from curvenet.io import read_points, write_network
from curvenet.reconstruct import reconstruct
t2 = time.perf_counter()
P = read_points(sys.argv[1])
t3 = time.perf_counter()
net = reconstruct(P)
t4 = time.perf_counter()
write_network(net, sys.argv[2])
t5 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4)
"""


def _steps(xyz: Path, out: Path, env: dict) -> None:
    best = None
    for _ in range(3):
        r = subprocess.run([sys.executable, "-c", _STEPS, str(xyz), str(out)], env=env, capture_output=True,
                           text=True, check=True)
        v = [float(x) for x in r.stdout.split()]
        best = v if best is None or sum(v) < sum(best) else best
    names = ("import curvenet.cli", "import io + reconstruct", "read .xyz", "reconstruct (first call)", "write .json")
    print("  inside the process (best of 3): " + ", ".join(f"{a} {b:.3f} s" for a, b in zip(names, best)))


# ------------------------------------------------------------------------------ first run
_FIRST = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import perf
P, _ = perf.make_points(int(sys.argv[2]), seed=0)
t = time.perf_counter()
import curvenet
from curvenet.methods.robust.kernels import registry as R
from curvenet.methods.robust import warmup as W
imported = time.perf_counter() - t
first_call = {}
shared = {"seconds": 0.0}
if sys.argv[3] == "serial":  # the compile as before warmup: each kernel on its first use, one core
    W.precompile = lambda processes=None, names=None: None
else:
    _precompile = W.precompile

    def precompile(processes=None, names=None):
        t = time.perf_counter()
        _precompile(processes, names)
        shared["seconds"] += time.perf_counter() - t

    W.precompile = precompile
_kernel = R._kernel


def timed(name):  # the time of each kernel's call that compiled it (or loaded it from the cache)
    f = _kernel(name)
    if not hasattr(f, "signatures") or f.signatures:  # plain Python, or compiled already
        return f

    def run(*args):
        t = time.perf_counter()
        out = f(*args)
        first_call[name] = first_call.get(name, 0.0) + time.perf_counter() - t
        return out

    return run


R._kernel = timed
t = time.perf_counter()
net = curvenet.reconstruct(P)
first = time.perf_counter() - t
R._kernel = _kernel
t = time.perf_counter()
net2 = curvenet.reconstruct(P)
warm = time.perf_counter() - t
print(json.dumps({"first": first, "warm": warm, "import": imported, "same": net == net2, "n": len(P),
                  "kernels": first_call, "numba": R.HAVE_NUMBA, "precompile": shared["seconds"],
                  "nodes": len(net.nodes)}))
"""


def first_run(n: int, tmp: Path) -> dict:
    """First run with an empty numba cache against the warm second run in the same process:
    as a user's first run does it (the compile shared out over the cores by
    ``curvenet.methods.robust.warmup.precompile``), then with that switched off (each kernel
    compiled on its first use, one after the other: the first call of each kernel is its
    compile), then with the cache that the first run filled (every kernel, those of noisy input
    included: its warm-up compiles them all; the serial run's noise-free cloud never calls the
    noisy-only kernels, so a cache it filled lacks them and a run there compiles them again)."""
    from curvenet.methods.robust.warmup import cores

    P = cloud(n)
    floor = knn_floor(P)
    print(f"reference: k=16 cKDTree query on the {len(P):,} points {floor:.3f} s")
    out = {}
    # (label, mode, the run whose cache it uses: None for a new, empty one)
    runs = (("empty numba cache, shared compile", "shared", None), ("empty numba cache, one kernel after the other",
            "serial", None), ("numba cache filled (by the shared compile)", "shared", "empty numba cache, shared compile"))
    caches = {}
    for label, mode, reuse in runs:
        caches[label] = caches[reuse] if reuse else Path(tempfile.mkdtemp(prefix="numba-cache-", dir=tmp))
        env = _env(NUMBA_CACHE_DIR=str(caches[label]))
        r = subprocess.run([sys.executable, "-c", _FIRST, str(HERE), str(n), mode], env=env, capture_output=True,
                           text=True)
        if r.returncode != 0:
            raise RuntimeError(r.stderr)
        res = json.loads(r.stdout.splitlines()[-1])
        ratio = res["first"] / res["warm"]
        flag = "ok" if ratio <= FIRST_RUN_TARGET else "OVER"
        print(f"  {label}: first run {res['first']:.2f} s, warm run {res['warm']:.2f} s "
              f"({res['warm'] / floor:.2f} x query): {ratio:.2f} x warm, target {FIRST_RUN_TARGET}: {flag}; "
              f"same network: {res['same']}, {res['nodes']:,} nodes")
        if res["precompile"]:
            print(f"    of which the shared compile (warmup.precompile, {cores()} cores): {res['precompile']:.2f} s; "
                  "the kernels of this process's share are timed on the warm-up clouds, the others loaded")
        ks = sorted(res["kernels"].items(), key=lambda kv: -kv[1])
        print(f"    first call of each kernel ({sum(res['kernels'].values()):.2f} s in all): "
              + ", ".join(f"{k} {v:.2f}" for k, v in ks))
        out[label] = res
    return out


# ------------------------------------------------------------------------------ main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("writers", "cli", "compile", "all"), default="all")
    ap.add_argument("--n", type=float, default=1e6, help="points of the writers' and the first run's cloud")
    ap.add_argument("--cli-n", type=float, default=3.4e4, help="points of the fresh-CLI file")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--formats", default="",
                    help="writers to time, e.g. .obj,.vtu,mesh.obj (the surface mesh's OBJ; default: all)")
    ap.add_argument("--hashes", action="store_true",
                    help="print the SHA-256 of each writer's file (a DXF's times and GUIDs masked): same bytes?")
    ap.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()))
    ap.add_argument("--quick", action="store_true", help="tiny sizes (CI)")
    ap.add_argument("--skip-plain", action="store_true",
                    help="leave out the CLI run without numba (about 40 s of processor time at 34k points)")
    args = ap.parse_args(argv)
    if args.quick:
        args.n, args.cli_n, args.repeat = 3e3, 3e3, 2
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if args.part in ("writers", "all"):
            print(f"\n== writers: every output format, best of {args.repeat} ==")
            writers(int(args.n), args.repeat, args.cache, tmp, [e for e in args.formats.split(",") if e],
                    hashes=args.hashes)
        if args.part in ("cli", "all"):
            print(f"\n== a fresh curvenet reconstruct process, best and median of {args.repeat} ==")
            fresh_cli(int(args.cli_n), args.repeat, tmp, plain=not args.skip_plain)
        if args.part in ("compile", "all"):
            print("\n== the first run after a fresh install (empty numba cache) ==")
            first_run(int(args.n), tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
