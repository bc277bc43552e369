"""Reader of PCL/Open3D point clouds (``.pcd``): ASCII, binary and binary_compressed data.

The format (PCL's "Point Cloud Data", version 0.7): a text header of ``FIELDS``, ``SIZE``,
``TYPE``, ``COUNT``, ``WIDTH``, ``HEIGHT``, ``VIEWPOINT``, ``POINTS`` and ``DATA`` lines, then
the points: text rows, packed binary records, or LZF-compressed field-by-field arrays.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import FormatError
from .points import Columns, _from_array, check_readable

__all__ = ["read_pcd"]

#: The header lines of a PCD file, in the order PCL writes them (``VERSION`` optional).
_KEYS = ("FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "POINTS", "DATA")

#: (TYPE, SIZE) -> numpy type
_TYPES = {
    ("F", 4): "f4", ("F", 8): "f8",
    ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4", ("I", 8): "i8",
    ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8",
}

#: The longest header accepted, in bytes (a header is a dozen short lines).
_MAX_HEADER = 1 << 16


def read_pcd(path: str | Path, *, columns: Columns = None, drop_nonfinite: bool = False) -> np.ndarray:
    """Read the ``x``, ``y`` (``z``) fields of a PCD point cloud.

    Parameters
    ----------
    path : str or Path
    columns : sequence of int or str, optional
        Fields to use as coordinates (by name, or index among the fields).
    drop_nonfinite : bool
        Drop points with NaN coordinates (PCL marks invalid points of organized clouds so).

    Returns
    -------
    (N, d) ndarray of float64
    """
    p = check_readable(path)
    raw = p.read_bytes()
    header, body = _split_header(p, raw)
    fields = header["FIELDS"]
    n = len(fields)
    sizes = _ints(p, header, "SIZE", n)
    counts = _ints(p, header, "COUNT", n) if "COUNT" in header else [1] * n
    types = header["TYPE"]
    if len(types) != n:
        raise FormatError(f"{p}: PCD header has {n} FIELDS but {len(types)} TYPE values")
    try:
        dtype = np.dtype([(f, "<" + _TYPES[(t.upper(), s)], (c,) if c > 1 else ())
                          for f, t, s, c in zip(fields, types, sizes, counts)])
    except (KeyError, ValueError, TypeError):
        raise FormatError(f"{p}: PCD header has an unsupported field type or size") from None
    npts = _ints(p, header, "POINTS", 1)[0] if "POINTS" in header else (
        _ints(p, header, "WIDTH", 1)[0] * _ints(p, header, "HEIGHT", 1)[0])
    kind = header["DATA"][0].lower() if header.get("DATA") else ""
    if kind == "ascii":
        arr = _ascii(p, body, dtype, npts)
    elif kind == "binary":
        need = npts * dtype.itemsize
        if len(body) < need:
            raise FormatError(f"{p}: PCD binary data truncated ({len(body)} of {need} bytes)")
        arr = np.frombuffer(body[:need], dtype=dtype)
    elif kind == "binary_compressed":
        arr = _compressed(p, body, dtype, npts)
    else:
        raise FormatError(f"{p}: PCD DATA must be ascii, binary or binary_compressed, got {kind or 'nothing'!r}")
    if npts == 0:
        raise FormatError(f"{p}: PCD file has no points")
    if arr.dtype.names is None or "x" not in arr.dtype.names or "y" not in arr.dtype.names:
        raise FormatError(f"{p}: PCD file has no x and y fields (fields: {', '.join(fields)})")
    flat = [f for f in arr.dtype.names if arr.dtype[f].shape == ()]
    return _from_array(p, np.asarray(arr[flat]), columns, drop_nonfinite)


def _split_header(p: Path, raw: bytes) -> tuple[dict[str, list[str]], bytes]:
    header: dict[str, list[str]] = {}
    pos = 0
    while pos < min(len(raw), _MAX_HEADER):
        end = raw.find(b"\n", pos)
        if end < 0:
            end = len(raw)
        line = raw[pos:end].decode("ascii", errors="replace").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        header[key.upper()] = vals
        if key.upper() == "DATA":
            break
    else:
        raise FormatError(f"{p}: not a PCD file (no DATA line in the header)")
    if "DATA" not in header:
        raise FormatError(f"{p}: not a PCD file (no DATA line in the header)")
    if "FIELDS" not in header or "SIZE" not in header or "TYPE" not in header:
        raise FormatError(f"{p}: not a PCD file (header needs FIELDS, SIZE and TYPE)")
    return header, raw[pos:]


def _ints(p: Path, header: dict[str, list[str]], key: str, n: int) -> list[int]:
    try:
        vals = [int(v) for v in header[key]]
    except (KeyError, ValueError):
        raise FormatError(f"{p}: PCD header line {key} is missing or not integers") from None
    if len(vals) != n or any(v < 0 for v in vals):
        raise FormatError(f"{p}: PCD header line {key} needs {n} non-negative integer(s), got {header[key]}")
    return vals


def _ascii(p: Path, body: bytes, dtype: np.dtype, npts: int) -> np.ndarray:
    names = dtype.names or ()
    rows = body.decode("ascii", errors="replace").split()
    width = sum(int(np.prod(dtype[f].shape)) for f in names)
    if len(rows) < npts * width:
        raise FormatError(f"{p}: PCD ascii data truncated ({len(rows)} of {npts * width} values)")
    try:
        flat = np.array(rows[: npts * width], dtype=np.float64).reshape(npts, width)
    except ValueError:
        raise FormatError(f"{p}: PCD ascii data holds a value that is not a number") from None
    # text keeps its digits: float fields are read as float64 whatever SIZE says (Open3D writes
    # ten significant digits under "F 4", and reads them back as doubles)
    wide = np.dtype([(f, "<f8" if dtype[f].base.kind == "f" else dtype[f].base, dtype[f].shape) for f in names])
    out = np.zeros(npts, dtype=wide)
    col = 0
    for f in names:
        w = int(np.prod(dtype[f].shape))
        out[f] = flat[:, col: col + w].reshape(out[f].shape)
        col += w
    return out


def _compressed(p: Path, body: bytes, dtype: np.dtype, npts: int) -> np.ndarray:
    """PCL's binary_compressed: two uint32 sizes, then LZF data holding each field's array in
    turn (structure of arrays)."""
    if len(body) < 8:
        raise FormatError(f"{p}: PCD compressed data truncated")
    csize, usize = np.frombuffer(body[:8], dtype="<u4")
    if len(body) < 8 + int(csize):
        raise FormatError(f"{p}: PCD compressed data truncated ({len(body) - 8} of {int(csize)} bytes)")
    data = _lzf_decompress(p, body[8: 8 + int(csize)], int(usize))
    if len(data) != npts * dtype.itemsize:
        raise FormatError(f"{p}: PCD compressed data holds {len(data)} bytes, {npts} points need {npts * dtype.itemsize}")
    out = np.zeros(npts, dtype=dtype)
    pos = 0
    for f in dtype.names or ():
        sub = np.dtype((dtype[f].base, dtype[f].shape)) if dtype[f].shape else dtype[f]
        nbytes = npts * sub.itemsize
        out[f] = np.frombuffer(data[pos: pos + nbytes], dtype=sub)
        pos += nbytes
    return out


def _lzf_decompress(p: Path, src: bytes, size: int) -> bytes:
    """LZF decompression (liblzf's format, as PCL writes it), in plain Python."""
    out = bytearray()
    i = 0
    n = len(src)
    try:
        while i < n:
            ctrl = src[i]
            i += 1
            if ctrl < 32:  # a literal run of ctrl + 1 bytes
                out += src[i: i + ctrl + 1]
                i += ctrl + 1
            else:  # a back reference
                length = ctrl >> 5
                if length == 7:
                    length += src[i]
                    i += 1
                ref = len(out) - ((ctrl & 0x1F) << 8) - src[i] - 1
                i += 1
                if ref < 0:
                    raise IndexError
                for _ in range(length + 2):
                    out.append(out[ref])
                    ref += 1
    except IndexError:
        raise FormatError(f"{p}: PCD compressed data are corrupt") from None
    if len(out) != size:
        raise FormatError(f"{p}: PCD compressed data are corrupt ({len(out)} bytes, header says {size})")
    return bytes(out)
