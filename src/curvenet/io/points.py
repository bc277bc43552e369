"""Readers of point files. Each reader returns an (N, d) float64 array, d = 2 or 3.

Readers raise :class:`~curvenet.errors.FormatError` (or :class:`~curvenet.errors.InputError`)
with a one-line message that names the file and the problem.
"""

from __future__ import annotations

import io as _io
import re
import warnings
from pathlib import Path
from typing import Sequence

import numpy as np

from .._sigint import checkpoint
from ..errors import FormatError, InputError, require

__all__ = ["read_text", "read_npy", "read_ply", "read_obj", "read_las", "check_readable", "select_columns"]

Columns = Sequence["int | str"] | None

_AXES = ("x", "y", "z")


def check_readable(path) -> Path:
    """Check that ``path`` is an existing, readable, non-empty regular file.

    Raises
    ------
    InputError
        Naming the file and the problem.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file")
    if p.is_dir():
        raise InputError(f"{p}: is a folder, not a file")
    try:
        with open(p, "rb") as f:
            head = f.read(1)
    except OSError as exc:
        raise InputError(f"{p}: cannot read file ({exc.strerror or exc})") from None
    if not head:
        raise FormatError(f"{p}: empty file")
    return p


def select_columns(path, names: list[str] | None, ncols: int, columns: Columns) -> list[int]:
    """Column indices of the coordinates, from an explicit choice, a header or the count."""
    if columns is not None:
        cols = []
        for c in columns:
            if isinstance(c, str) and not c.lstrip("-").isdigit():
                if names is None or c.lower() not in names:
                    raise InputError(f"{path}: no column named {c!r} (the file has no such header name)")
                cols.append(names.index(c.lower()))
            else:
                i = int(c)
                if not -ncols <= i < ncols:
                    raise InputError(f"{path}: column {i} does not exist (the file has {ncols} columns)")
                cols.append(i % ncols)
        if len(cols) not in (2, 3):
            raise InputError(f"{path}: choose 2 or 3 coordinate columns, got {len(cols)}")
        return cols
    if names is not None and "x" in names and "y" in names:
        cols = [names.index("x"), names.index("y")]
        if "z" in names:
            cols.append(names.index("z"))
        return cols
    if ncols in (2, 3):
        return list(range(ncols))
    if ncols == 1:
        raise InputError(f"{path}: only one column per row; points need 2 or 3 coordinates")
    raise InputError(
        f"{path}: {ncols} columns per row; choose the coordinate columns (e.g. --columns 0,1,2)"
    )


def _first_data_row(lines: list[str], skip: int, delim: str | None) -> list[str] | None:
    """The tokens of the first data line after ``skip`` lines (comments and blanks skipped)."""
    for line in lines[skip:]:
        t = line.strip()
        if t and not t.startswith("#"):
            return [x.strip() for x in (line.split(delim) if delim else t.split())]
    return None


def _is_number(tok: str) -> bool:
    try:
        float(tok)
        return True
    except ValueError:
        return False


def read_text(path, *, columns: Columns = None, drop_nonfinite: bool = False) -> np.ndarray:
    """Read points from a delimited text file (``.xyz``, ``.txt``, ``.pts``, ``.csv``, ``.tsv``).

    Values are separated by commas, semicolons, tabs (always in ``.tsv``) or spaces; lines
    starting with ``#`` are comments; an optional header line names the columns. Without a
    column choice, a file with 2 or 3 columns is read whole, a header naming ``x``, ``y`` (and
    ``z``) picks those columns, and any other column count is an error. Only the chosen columns
    are read, so other columns may hold text (ids, labels).

    Parameters
    ----------
    path : str or Path
        The file.
    columns : sequence of int or str, optional
        The 2 or 3 coordinate columns, by 0-based index or header name.
    drop_nonfinite : bool
        Drop rows with NaN or infinite values instead of raising.

    Returns
    -------
    (N, d) ndarray of float64
    """
    p = check_readable(path)
    with open(p, "rb") as f:
        head = f.read(1 << 16)
    if b"\x00" in head:
        raise FormatError(f"{p}: binary data in a text point file")
    data_part = b"\n".join(line.split(b"#", 1)[0] for line in head.splitlines())  # comments may hold any bytes
    try:
        data_part.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(data_part) - 4:  # not just a character cut at the end of the block
            raise FormatError(f"{p}: not a text file (undecodable bytes outside comments)") from None
    # the first non-comment line decides header and delimiter
    skip = 0
    first = None
    # lines split as the reader below splits them (universal newlines: \n, \r\n, \r)
    lines = head.decode("utf-8", errors="replace").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    for line in lines[:-1] if len(head) == 1 << 16 else lines:
        s = line.strip()
        if not s or s.startswith("#"):
            skip += 1
            continue
        first = s
        break
    if first is None:
        raise FormatError(f"{p}: no data (only blank or comment lines)")
    if p.suffix.lower() == ".tsv":
        delim = "\t"
    else:
        delim = "," if "," in first else (";" if ";" in first else None)
    toks = [t.strip() for t in (first.split(delim) if delim else first.split())]
    names = None
    if not all(_is_number(t) for t in toks):
        names = [t.strip().strip('"').strip("'").lower() for t in toks]
        skip += 1
    ncols = len(toks)
    cols = select_columns(p, names, ncols, columns)
    data_row = _first_data_row(lines, skip, delim)
    text_cols = [i for i, t in enumerate(data_row or []) if not _is_number(t)]
    usecols = None
    if text_cols:  # a text column (an id, a label): read the chosen columns only
        chosen_text = [i for i in cols if i in text_cols]
        if chosen_text:
            i = chosen_text[0]
            what = repr(names[i]) if names and i < len(names) else str(i)
            raise FormatError(f"{p}: column {what} is not numeric (first data row has {data_row[i]!r}); "
                              "choose the coordinate columns with --columns")
        usecols = list(cols)
    arr = _read_rows(p, skip, delim, ncols, usecols=usecols)
    if arr.size == 0:
        raise FormatError(f"{p}: a header but no data rows" if names else f"{p}: no data rows")
    if usecols is not None:
        return _finite(p, arr, drop_nonfinite)
    return _finite(p, arr[:, cols], drop_nonfinite)


#: Bytes of a text point file parsed at a time, cut at a line end (Ctrl-C acted on between).
TEXT_CHUNK_BYTES = 1 << 23


def _read_rows(p: Path, skip: int, delim, ncols: int, usecols: list[int] | None = None) -> np.ndarray:
    """The numbers of a text point file after its first ``skip`` lines, about
    :data:`TEXT_CHUNK_BYTES` at a time; errors name the data row (counted from 1, blank and
    comment lines not counted, as in the NaN errors). ``usecols``: only these columns (the
    others may hold text)."""
    blocks = []
    done = 0  # data rows parsed so far
    # Latin-1 decodes every byte: a stray byte in a comment is ignored, one in the data fails as
    # a number that does not convert
    with open(p, encoding="latin-1", newline=None) as f:
        for _ in range(skip):
            f.readline()
        while True:
            raw = f.read(TEXT_CHUNK_BYTES)
            if not raw:
                break
            if not raw.endswith("\n"):
                raw += f.readline()  # the rest of the last line
            text = _io.StringIO(raw)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
                    arr = np.loadtxt(text, delimiter=delim, comments="#", ndmin=2, dtype=np.float64,
                                     usecols=usecols)
            except ValueError as exc:
                raise FormatError(f"{p}: {_row_message(str(exc), done)}") from None
            if arr.size:
                if usecols is None and arr.shape[1] != ncols:
                    raise FormatError(f"{p}: data row {done + 1} has {arr.shape[1]} values, the first row {ncols}")
                blocks.append(arr)
                done += len(arr)
            checkpoint()  # Ctrl-C during a long read: acted on here (see curvenet._sigint)
    return np.vstack(blocks) if blocks else np.zeros((0, ncols if usecols is None else len(usecols)))


def _row_message(msg: str, done: int) -> str:
    """numpy's loadtxt message with its row number made a data row of the file (from 1)."""
    msg = msg.split("\n")[0]
    msg = re.sub(r"; use `usecols`.*$", "", msg).rstrip(".")
    m = re.search(r"at row (\d+)", msg)
    if m:  # numpy counts the rows of its input from 0 in conversion errors, from 1 in others
        row = int(m.group(1)) + (1 if msg.startswith("could not convert") else 0)
        msg = msg[: m.start()] + f"in data row {done + row}" + msg[m.end():]
    return msg


def _finite(path, arr: np.ndarray, drop: bool) -> np.ndarray:
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        if drop:
            arr = arr[~bad]
            if len(arr) == 0:
                raise InputError(f"{path}: every row has NaN or infinite values")
        else:
            rows = np.flatnonzero(bad)
            where = ", ".join(str(r + 1) for r in rows[:5]) + (", ..." if len(rows) > 5 else "")
            raise InputError(
                f"{path}: {len(rows)} point(s) with NaN or infinite values (data rows {where}); "
                "use --drop-nonfinite to drop them"
            )
    return np.ascontiguousarray(arr, dtype=np.float64)


def _from_array(path, arr: np.ndarray, columns: Columns, drop_nonfinite: bool) -> np.ndarray:
    if arr.dtype.names:
        names = [n.lower() for n in arr.dtype.names]
        cols = select_columns(path, names, len(names), columns)
        for c in cols:
            field = arr.dtype[arr.dtype.names[c]]
            if field.kind not in "iuf" or field.shape:
                raise FormatError(f"{path}: field {arr.dtype.names[c]!r} holds {field}, not numbers")
        arr = np.stack([arr[arr.dtype.names[c]].astype(np.float64) for c in cols], axis=1)
        return _finite(path, arr.reshape(-1, len(cols)), drop_nonfinite)
    if arr.ndim != 2:
        raise FormatError(f"{path}: expected an (N, 2) or (N, 3) array, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise FormatError(f"{path}: expected a real numeric array, got dtype {arr.dtype}")
    if arr.shape[0] == 0:
        raise FormatError(f"{path}: no points (array of shape {arr.shape})")
    cols = select_columns(path, None, arr.shape[1], columns)
    return _finite(path, arr[:, cols].astype(np.float64), drop_nonfinite)


def read_npy(path, *, columns: Columns = None, drop_nonfinite: bool = False) -> np.ndarray:
    """Read points from a NumPy ``.npy`` file: an (N, 2) or (N, 3) array, or a structured array
    with fields ``x``, ``y`` (``z``). Pickled objects are refused.
    """
    p = check_readable(path)
    try:
        arr = np.load(p, allow_pickle=False, mmap_mode=None)
    except Exception as exc:  # numpy raises ValueError, EOFError, SyntaxError, TokenError... on bad headers
        msg = str(exc).split("\n")[0] or type(exc).__name__
        raise FormatError(f"{p}: not a valid .npy file ({msg})") from None
    if not isinstance(arr, np.ndarray):
        raise FormatError(f"{p}: not a .npy array file")
    return _from_array(p, arr, columns, drop_nonfinite)


def read_ply(path, *, columns: Columns = None, drop_nonfinite: bool = False) -> np.ndarray:
    """Read the ``vertex`` element (``x``, ``y``, optional ``z``) of an ASCII or binary PLY file."""
    p = check_readable(path)
    plyfile = require("plyfile", "reading PLY files", "io")
    try:
        ply = plyfile.PlyData.read(str(p))
        vert = ply["vertex"].data
    except KeyError:
        raise FormatError(f"{p}: PLY file has no 'vertex' element") from None
    except Exception as exc:  # plyfile raises many types on malformed files
        msg = str(exc).split("\n")[0] or type(exc).__name__
        raise FormatError(f"{p}: not a valid PLY file ({msg})") from None
    if vert.dtype.names is None or "x" not in vert.dtype.names or "y" not in vert.dtype.names:
        raise FormatError(f"{p}: PLY vertex element has no x and y properties")
    if len(vert) == 0:
        raise FormatError(f"{p}: PLY file has no vertices")
    return _from_array(p, np.asarray(vert), columns, drop_nonfinite)


def read_obj(path, *, columns: Columns = None, drop_nonfinite: bool = False) -> np.ndarray:
    """Read the vertices (``v x y z`` lines) of a Wavefront OBJ file; other lines are ignored."""
    p = check_readable(path)
    with open(p, "rb") as f:
        data = f.read()
    if b"\x00" in data[:65536]:
        raise FormatError(f"{p}: binary data in an OBJ file")
    text = data.decode("utf-8", errors="replace")
    rows = re.findall(r"^[ \t]*v[ \t]+([^\n\r#]*)", text, flags=re.MULTILINE)
    if not rows:
        raise FormatError(f"{p}: no vertex ('v') lines in OBJ file")
    empty = next((i for i, r in enumerate(rows) if not r.strip()), None)
    if empty is not None:  # (np.loadtxt would skip it: a silent empty or short result)
        raise FormatError(f"{p}: malformed OBJ vertex line (vertex {empty + 1} has no coordinates)")
    try:
        arr = np.loadtxt(_io.StringIO("\n".join(r.strip() for r in rows)), ndmin=2, usecols=(0, 1, 2))
    except ValueError as exc:
        raise FormatError(f"{p}: malformed OBJ vertex line ({str(exc).splitlines()[0]})") from None
    cols = select_columns(p, None, 3, columns)
    return _finite(p, arr[:, cols], drop_nonfinite)


#: Points decoded at a time from a LAS/LAZ file (bounded memory; Ctrl-C acted on between).
LAS_CHUNK_POINTS = 1_000_000


def read_las(path, *, columns: Columns = None, drop_nonfinite: bool = False) -> np.ndarray:
    """Read the x, y, z coordinates of a LAS or LAZ point cloud (needs laspy, extra ``io``).

    The header is checked against the file's size first (:func:`curvenet.io.las_header.check_las`),
    then the points are decoded :data:`LAS_CHUNK_POINTS` at a time (a LAS file's straight into
    the (N, 3) result, no other copy of it), with a Ctrl-C checkpoint after each block.
    """
    from .las_header import check_las

    p = check_readable(path)
    laspy = require("laspy", "reading LAS/LAZ files", "io")
    layout = check_las(p)
    if layout.n_points == 0:
        raise FormatError(f"{p}: LAS file has no points")
    # an uncompressed file's points go straight into one array: their number was checked
    # against the file's size (a LAZ file's number of points is not bounded by its size)
    arr = np.empty((layout.n_points, 3)) if not layout.compressed else None
    blocks, done = [], 0
    try:
        # a corrupt scale or offset overflows in laspy's scaling: the non-finite points are
        # reported below, without numpy's RuntimeWarning on standard error
        with laspy.open(str(p)) as reader, np.errstate(over="ignore", invalid="ignore"):
            for chunk in reader.chunk_iterator(LAS_CHUNK_POINTS):
                if arr is None:
                    block = np.empty((len(chunk), 3))
                    blocks.append(block)
                else:
                    block = arr[done:done + len(chunk)]
                block[:, 0], block[:, 1], block[:, 2] = chunk.x, chunk.y, chunk.z
                done += len(block)
                checkpoint()
    except (KeyboardInterrupt, SystemExit, MemoryError):
        raise
    except BaseException as exc:  # laspy and lazrs raise many types (a Rust panic is a BaseException)
        msg = str(exc).split("\n")[0] or type(exc).__name__
        raise FormatError(f"{p}: not a valid LAS/LAZ file ({msg})") from None
    arr = arr[:done] if arr is not None else np.vstack(blocks) if blocks else np.zeros((0, 3))
    if len(arr) == 0:
        raise FormatError(f"{p}: LAS file has no points")
    cols = select_columns(p, ["x", "y", "z"], 3, columns)
    if cols != [0, 1, 2]:
        arr = arr[:, cols]
    checkpoint()
    return _finite(p, arr, drop_nonfinite)
