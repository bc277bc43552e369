"""The inputs of a tiled run: files, globs or folders of tiles, read in row ranges (chunks).

A chunk is read on a worker, never on the client: ``.npy`` through a memory map, LAS/LAZ with
laspy's chunked reader (seek and read), other formats whole (one chunk a file). Global point
ids are the rows of the inputs in the order listed (files of a folder or glob sorted by name).
"""

from __future__ import annotations

import glob as _glob
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FormatError, InputError, require
from ..io import READERS, extension, read_points
from ..io.points import check_readable, select_columns

__all__ = ["CHUNK_ROWS", "Chunk", "expand_inputs", "plan_chunks", "read_chunk", "scan_chunk"]

#: Rows of a large ``.npy`` or LAS/LAZ file read by one task (about 48 MB of 3D coordinates).
CHUNK_ROWS: int = 2_000_000


@dataclass(frozen=True)
class Chunk:
    """Rows ``[start, stop)`` of one input file; its first point has the global id ``offset``.

    ``stop`` is None for a file read whole (its row count is known once read).
    """

    path: str
    start: int
    stop: int | None
    offset: int = 0


def expand_inputs(inputs) -> list[Path]:
    """The point files named by ``inputs``: files, folders (their readable files, sorted) or
    glob patterns (sorted matches).

    Raises
    ------
    InputError
        No input, a pattern or folder with no point file, or a missing file.
    """
    if isinstance(inputs, (str, Path)):
        inputs = [inputs]
    out: list[Path] = []
    for item in inputs:
        s = str(item)
        p = Path(s)
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.is_file() and extension(f) in READERS)
            if not found:
                raise InputError(f"{p}: folder holds no point file ({', '.join(sorted(READERS))})")
            out.extend(found)
        elif not p.exists() and _glob.has_magic(s):
            found = sorted(Path(f) for f in _glob.glob(s) if Path(f).is_file())
            if not found:
                raise InputError(f"{s}: no file matches")
            out.extend(found)
        else:
            out.append(check_readable(p))
    if not out:
        raise InputError("no input file given")
    for f in out:
        if extension(f) not in READERS:
            raise FormatError(f"{f}: unknown point file extension {extension(f) or '(none)'!r}; "
                              f"readable: {', '.join(sorted(READERS))}")
    return out


def _rows(path: Path) -> int | None:
    """The row count from the header (.npy, LAS/LAZ), None for formats read whole."""
    ext = extension(path)
    if ext == ".npy":
        try:
            arr = np.load(path, mmap_mode="r", allow_pickle=False)
        except Exception as exc:  # numpy raises many types on a bad header
            raise FormatError(f"{path}: not a valid .npy file ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
        if arr.ndim != 2 or arr.dtype.names:
            return None  # structured or odd arrays: the ordinary reader, whole
        return int(arr.shape[0])
    if ext in (".las", ".laz"):
        laspy = require("laspy", "reading LAS/LAZ files", "io")
        try:
            with laspy.open(str(path)) as f:
                return int(f.header.point_count)
        except Exception as exc:  # laspy raises many types on malformed files
            raise FormatError(f"{path}: not a valid LAS/LAZ file ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    return None


def plan_chunks(files: list[Path], rows: int | None = None) -> list[Chunk]:
    """The chunks of ``files`` (row ranges of at most ``rows``, default :data:`CHUNK_ROWS`),
    offsets not yet set (:func:`scan_chunk` counts the rows of whole-read files; the caller
    then sets them)."""
    rows = CHUNK_ROWS if rows is None else int(rows)
    out = []
    for f in files:
        n = _rows(f)
        if n is None:
            out.append(Chunk(str(f), 0, None))
        else:
            if n == 0:
                raise FormatError(f"{f}: no points")
            out.extend(Chunk(str(f), a, min(a + rows, n)) for a in range(0, n, rows))
    return out


def read_chunk(chunk: Chunk, *, columns=None, drop_nonfinite: bool = False) -> np.ndarray:
    """The points of one chunk, (n, d) float64 (runs on a worker).

    Raises
    ------
    InputError, FormatError
        One line naming the file (and the rows) and the problem.
    """
    path = Path(chunk.path)
    ext = extension(path)
    if chunk.stop is None:
        return read_points(path, columns=columns, drop_nonfinite=drop_nonfinite)
    where = f"{path} (rows {chunk.start}-{chunk.stop - 1})"
    if ext == ".npy":
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
        if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
            raise FormatError(f"{path}: expected a real numeric array, got dtype {arr.dtype}")
        cols = select_columns(path, None, arr.shape[1], columns)
        pts = np.array(arr[chunk.start:chunk.stop][:, cols], dtype=np.float64)
    else:
        laspy = require("laspy", "reading LAS/LAZ files", "io")
        try:
            with laspy.open(str(path)) as f:
                f.seek(chunk.start)
                rec = f.read_points(chunk.stop - chunk.start)
                pts = np.column_stack([np.asarray(rec.x), np.asarray(rec.y), np.asarray(rec.z)])
        except Exception as exc:  # laspy raises many types on malformed files
            raise FormatError(f"{where}: not a valid LAS/LAZ file ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
        pts = pts[:, select_columns(path, ["x", "y", "z"], 3, columns)]
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any() and not drop_nonfinite:
        raise InputError(f"{where}: {int(bad.sum())} point(s) with NaN or infinite values; "
                         "use --drop-nonfinite to drop them")
    return pts


def scan_chunk(chunk: Chunk, *, columns=None, drop_nonfinite: bool = False):
    """Row count, dimension and bounding box of one chunk (runs on a worker; reads it whole).

    Returns
    -------
    n : int
    dim : int
    lo, hi : (d,) ndarray
        The finite points' bounds.
    """
    pts = read_chunk(chunk, columns=columns, drop_nonfinite=drop_nonfinite)
    fin = pts[np.isfinite(pts).all(axis=1)]
    if len(fin) == 0:
        raise InputError(f"{chunk.path}: no finite points")
    return len(pts), pts.shape[1], fin.min(axis=0), fin.max(axis=0)
