"""The scratch store of a tiled run: one pair of ``.npy`` files per tile and input chunk.

Layout: ``ROOT/t<key>/c<chunk>.pts.npy`` ((n, d) float64 coordinates) and ``.ids.npy`` ((n,)
int64 global ids), each written under a temporary name and renamed (a task that reruns after
a lost worker rewrites its files whole); ``ROOT/t<key>/v-<name>.npy``, per-point values of the
whole-cloud estimates; ``ROOT/t<key>/prepared/``, the tile's box with its halo prepared by the
method (:class:`curvenet.methods.robust.Prepared`, one ``.npy`` a field, written in a temporary
folder and renamed whole); ``ROOT/t<key>/pieces.pts`` and ``.ids``, the tile's pieces of curves,
one after the other (raw float64 and int64, read back a range of rows at a time). ``ROOT`` is a
fresh folder of its own, removed whole at the end of
the run, whatever the outcome.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from ..methods.robust import Prepared
from ..methods.robust.frames import Tangents

__all__ = ["SCRATCH_PREFIX", "new_root", "remove_root", "tile_dir", "write_part", "read_tile", "write_values",
           "read_values", "write_prepared", "read_prepared", "write_pieces", "read_piece_rows"]

#: Name prefix of a run's scratch folder (under ``--scratch`` or the system's temporary folder).
SCRATCH_PREFIX = "curvenet-tiles-"

#: How long (seconds) ``remove_root`` keeps removing files that tasks still running in worker
#: threads finish writing after the run was interrupted (a write in flight takes milliseconds).
REMOVE_PATIENCE = 10.0

#: Pause (seconds) between two removal attempts of ``remove_root``.
REMOVE_PAUSE = 0.05


def new_root(parent=None) -> Path:
    """A new, empty scratch folder for one run (under ``parent``, default the system's temp)."""
    if parent is not None:
        Path(parent).mkdir(parents=True, exist_ok=True)
    return Path(tempfile.mkdtemp(prefix=SCRATCH_PREFIX, dir=parent))


def remove_root(root: Path) -> None:
    """Remove a run's scratch folder and everything in it (only that folder).

    After Ctrl-C, tasks may still be running in worker threads and writing into the store. The
    folder is first renamed, so that no new write can start under its name (a write resolves
    the folder by name and fails once it is gone); then it is removed until nothing is left,
    which catches a write that was already in flight.
    """
    root = Path(root)
    doomed = root.with_name(root.name + ".removing")
    try:
        os.rename(root, doomed)
    except OSError:
        doomed = root
    deadline = time.monotonic() + REMOVE_PATIENCE
    while True:
        shutil.rmtree(doomed, ignore_errors=True)
        if not doomed.exists() or time.monotonic() > deadline:
            return
        time.sleep(REMOVE_PAUSE)


def tile_dir(root, key) -> Path:
    """The folder of tile ``key`` (``t3_-1_0`` for key (3, -1, 0))."""
    return Path(root) / ("t" + "_".join(str(int(k)) for k in key))


def _save(path: Path, arr: np.ndarray) -> None:
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        np.save(f, arr)
    os.replace(tmp, path)


def write_part(root, key, chunk: int, points: np.ndarray, ids: np.ndarray) -> None:
    """Store the points (n, d) and global ids (n,) of input chunk ``chunk`` in tile ``key``."""
    d = tile_dir(root, key)
    d.mkdir(exist_ok=True)
    _save(d / f"c{chunk:06d}.ids.npy", np.ascontiguousarray(ids, dtype=np.int64))
    _save(d / f"c{chunk:06d}.pts.npy", np.ascontiguousarray(points, dtype=np.float64))


def read_tile(root, key):
    """Every stored part of tile ``key``, as ``(points (n, d), ids (n,))`` pairs in chunk order."""
    d = tile_dir(root, key)
    if not d.is_dir():
        return []
    out = []
    for f in sorted(d.glob("c*.pts.npy")):
        out.append((np.load(f), np.load(f.with_name(f.name.replace(".pts.", ".ids.")))))
    return out


def write_values(root, key, name: str, values: np.ndarray) -> None:
    """Store per-point values (n,) of tile ``key`` under ``name`` (``ROOT/t<key>/v-<name>.npy``)."""
    d = tile_dir(root, key)
    d.mkdir(exist_ok=True)
    _save(d / f"v-{name}.npy", np.ascontiguousarray(values))


def read_values(root, key, name: str) -> np.ndarray:
    """The values stored by :func:`write_values` (an empty array when there are none)."""
    f = tile_dir(root, key) / f"v-{name}.npy"
    return np.load(f) if f.exists() else np.zeros(0)


_PREPARED = "prepared"
_ARRAYS = ("points", "order", "idx", "h")


def write_prepared(root, key, prep: Prepared, ids: np.ndarray) -> None:
    """Store tile ``key``'s prepared cloud (its box with the halo) and the global ids (n,) of
    the points in their input order (``prep.order`` indexes them)."""
    d = tile_dir(root, key)
    d.mkdir(exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f"{_PREPARED}.", suffix=".tmp", dir=d))
    arrays = {name: getattr(prep, name) for name in _ARRAYS}
    arrays.update({f"tangents.{name}": a for name, a in prep.tangents._asdict().items()})
    arrays["ids"] = ids
    arrays["meta"] = np.array([prep.k, np.nan if prep.spacing is None else prep.spacing])
    for name, a in arrays.items():
        np.save(tmp / f"{name}.npy", np.ascontiguousarray(a))
    try:
        os.rename(tmp, d / _PREPARED)
    except OSError:  # written already (a task rerun after a lost worker): the same arrays
        shutil.rmtree(tmp, ignore_errors=True)


def read_prepared(root, key) -> tuple[Prepared, np.ndarray] | None:
    """What :func:`write_prepared` stored for tile ``key`` (the prepared cloud and the global
    ids), or None when nothing is stored."""
    d = tile_dir(root, key) / _PREPARED
    if not d.is_dir():
        return None
    arrays = {f.name[:-len(".npy")]: np.load(f) for f in d.glob("*.npy")}
    k, spacing = arrays["meta"]
    tg = Tangents(*(arrays[f"tangents.{name}"] for name in Tangents._fields))
    prep = Prepared(*(arrays[name] for name in _ARRAYS), tg, int(k), None if np.isnan(spacing) else float(spacing))
    return prep, arrays["ids"]


def _pieces_path(root, key, what: str) -> Path:
    return tile_dir(root, key) / f"pieces.{what}"


def write_pieces(root, key, points: np.ndarray, ids: np.ndarray) -> None:
    """Store tile ``key``'s pieces: their points (n, d) float64 and global ids (n,) int64, one
    piece after the other (raw, so that :func:`read_piece_rows` reads a range of rows alone)."""
    d = tile_dir(root, key)
    d.mkdir(exist_ok=True)
    for what, a, dtype in (("ids", ids, "<i8"), ("pts", points, "<f8")):
        path = _pieces_path(root, key, what)
        tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
        np.ascontiguousarray(a, dtype=dtype).tofile(tmp)
        os.replace(tmp, path)


def read_piece_rows(root, key, lo: int, hi: int, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``[lo, hi)`` of tile ``key``'s stored pieces: points (hi - lo, dim) and ids (hi - lo,)
    (read from the files, not mapped: nothing stays in the process once they are dropped)."""
    n = hi - lo
    P = np.fromfile(_pieces_path(root, key, "pts"), dtype="<f8", count=n * dim, offset=lo * dim * 8)
    I = np.fromfile(_pieces_path(root, key, "ids"), dtype="<i8", count=n, offset=lo * 8)
    return P.reshape(n, dim).astype(np.float64, copy=False), I.astype(np.int64, copy=False)
