"""Checks of a LAS/LAZ file's header against the file's size, before any decoder sees it.

A corrupt count in a LAS header (VLRs, points, the offset to the points, a LAZ chunk table) can
make a decoder allocate many gigabytes, loop for minutes or abort the process. :func:`check_las`
reads the fixed header, walks the variable-length records and the LAZ chunk table header, and
checks every count and offset against the file's size, so that only a file whose layout holds
reaches the decoder. Field positions follow the ASPRS LAS specification 1.4 R15 (section 2.4,
the public header block) and the LASzip specification (the ``laszip encoded`` VLR, the chunk
table).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

from ..errors import FormatError

__all__ = ["LasLayout", "check_las", "POINT_RECORD_MIN"]

#: Smallest point record length in bytes of each point data record format (LAS 1.4, table 7 on).
POINT_RECORD_MIN = {0: 20, 1: 28, 2: 26, 3: 34, 4: 57, 5: 63, 6: 30, 7: 36, 8: 38, 9: 59, 10: 67}

#: Smallest public header block of each minor version of LAS 1.x.
HEADER_MIN = {0: 227, 1: 227, 2: 227, 3: 235, 4: 375}

#: Bytes of a VLR header and of an extended VLR header.
VLR_HEADER = 54
EVLR_HEADER = 60

#: The LASzip VLR: user id and record id.
LASZIP_USER = b"laszip encoded"
LASZIP_RECORD = 22204

#: Bytes of the LASzip VLR's fixed part (compressor to the number of items), before the items.
LASZIP_VLR_FIXED = 34

#: The chunk size of a LAZ file whose chunks vary in size (LASzip).
LAZ_VARIABLE_CHUNKS = 0xFFFFFFFF

#: Largest buffer in bytes that a LAZ chunk may need (points of the chunk x point record length):
#: the decoder (lazrs) reserves it before decoding, and aborts the process when it cannot. LASzip
#: writes chunks of 50,000 points (1.7 MB of 34-byte records); 512 MiB is 300 times that.
LAZ_CHUNK_BYTES_MAX = 2**29


@dataclass(frozen=True)
class LasLayout:
    """What the header of a checked LAS/LAZ file says.

    Attributes
    ----------
    n_points : int
        Number of point records.
    compressed : bool
        True for LAZ.
    point_format : int
        The point data record format (0 to 10).
    """

    n_points: int
    compressed: bool
    point_format: int


def _bad(path, what: str):
    return FormatError(f"{path}: not a valid LAS/LAZ file ({what})")


def check_las(path) -> LasLayout:
    """Check the layout of a LAS or LAZ file against its size.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    LasLayout

    Raises
    ------
    FormatError
        When the signature, the version, the header size, the VLRs, the offset to the points,
        the point record length, the number of points (against the bytes there are, for LAS),
        the LAZ chunk table or the extended VLRs do not fit the file, or a LAZ chunk would need a
        decoding buffer over :data:`LAZ_CHUNK_BYTES_MAX`.
    """
    p = Path(path)
    size = p.stat().st_size
    with open(p, "rb") as f:
        head = f.read(max(HEADER_MIN.values()))
        if len(head) < min(HEADER_MIN.values()) or head[:4] != b"LASF":
            raise _bad(p, "no LAS header")
        major, minor = head[24], head[25]
        if major != 1 or minor not in HEADER_MIN:
            raise _bad(p, f"unknown version {major}.{minor}")
        header_size, offset, n_vlr = struct.unpack_from("<HII", head, 94)
        fmt_byte = head[104]
        rec_len = struct.unpack_from("<H", head, 105)[0]
        n_points = struct.unpack_from("<I", head, 107)[0]
        if not HEADER_MIN[minor] <= header_size <= min(size, offset):
            raise _bad(p, f"header size {header_size} does not fit (offset to points {offset}, file {size} bytes)")
        if offset > size:
            raise _bad(p, f"the points start at byte {offset}, after the end of the file ({size} bytes)")
        fmt = fmt_byte & 0x3F
        compressed = bool(fmt_byte & 0xC0)
        if fmt not in POINT_RECORD_MIN:
            raise _bad(p, f"unknown point format {fmt}")
        if rec_len < POINT_RECORD_MIN[fmt]:
            raise _bad(p, f"point records of {rec_len} bytes, format {fmt} needs {POINT_RECORD_MIN[fmt]}")
        end = size  # where the point data must end (the extended VLRs of LAS 1.4 follow them)
        if minor >= 4:
            evlr_start, n_evlr, n64 = struct.unpack_from("<QIQ", head, 235)
            if n64:
                n_points = n64
            if n_evlr:
                if not offset <= evlr_start <= size:
                    raise _bad(p, f"extended VLRs at byte {evlr_start}, outside the file ({size} bytes)")
                end = evlr_start
                _walk_evlrs(p, f, evlr_start, n_evlr, size)
        if n_vlr > (offset - header_size) // VLR_HEADER:
            raise _bad(p, f"{n_vlr} VLRs announced, at most {(offset - header_size) // VLR_HEADER} fit before the points")
        laszip = _walk_vlrs(p, f, header_size, n_vlr, offset)
        if not compressed:
            if n_points * rec_len > end - offset:
                raise _bad(p, f"{n_points} points of {rec_len} bytes announced, {end - offset} bytes of point data")
        else:
            _check_chunks(p, f, offset, end, size, n_points, rec_len, laszip)
    return LasLayout(int(n_points), compressed, fmt)


def _walk_vlrs(p, f, start: int, n: int, stop: int):
    """Walk the ``n`` VLRs from byte ``start``; each must end by ``stop``. Returns the data of
    the LASzip VLR (or None)."""
    pos = start
    laszip = None
    for i in range(n):
        if pos + VLR_HEADER > stop:
            raise _bad(p, f"VLR {i + 1} of {n} runs into the point data")
        f.seek(pos)
        h = f.read(VLR_HEADER)
        user = h[2:18].rstrip(b"\0")
        record_id, length = struct.unpack_from("<HH", h, 18)
        if pos + VLR_HEADER + length > stop:
            raise _bad(p, f"VLR {i + 1} of {n} runs into the point data")
        if user == LASZIP_USER and record_id == LASZIP_RECORD:
            laszip = f.read(length)
        pos += VLR_HEADER + length
    return laszip


def _walk_evlrs(p, f, start: int, n: int, size: int) -> None:
    pos = start
    for i in range(n):
        if pos + EVLR_HEADER > size:
            raise _bad(p, f"extended VLR {i + 1} of {n} runs past the end of the file")
        f.seek(pos + 20)
        length = struct.unpack("<Q", f.read(8))[0]
        pos += EVLR_HEADER + length
        if pos > size:
            raise _bad(p, f"extended VLR {i + 1} of {n} runs past the end of the file")


def _check_chunk_buffer(p, n: int, rec_len: int) -> None:
    """A chunk of ``n`` points must fit the decoder's buffer bound :data:`LAZ_CHUNK_BYTES_MAX`."""
    if n * rec_len > LAZ_CHUNK_BYTES_MAX:
        raise _bad(p, f"LAZ chunks of {n} points of {rec_len} bytes, over the {LAZ_CHUNK_BYTES_MAX >> 20} MiB "
                      "a chunk may take")


def _check_chunks(p, f, offset: int, end: int, size: int, n_points: int, rec_len: int, laszip) -> None:
    """The LAZ chunk table: its offset inside the point data, a number of chunks that matches
    the number of points (fixed chunk size) or the bytes there are (variable), and chunks whose
    decoding buffer stays within :data:`LAZ_CHUNK_BYTES_MAX`."""
    if laszip is None or len(laszip) < LASZIP_VLR_FIXED:
        raise _bad(p, "compressed points without a valid LASzip VLR")
    chunk_size = struct.unpack_from("<I", laszip, 12)[0]
    if chunk_size == 0:
        raise _bad(p, "LAZ chunk size 0")
    if chunk_size != LAZ_VARIABLE_CHUNKS:
        _check_chunk_buffer(p, chunk_size, rec_len)
    if end - offset < 8:
        raise _bad(p, "no compressed point data")
    f.seek(offset)
    table = struct.unpack("<q", f.read(8))[0]
    if table == -1:  # written as a stream: the offset is in the last 8 bytes of the file
        f.seek(size - 8)
        table = struct.unpack("<q", f.read(8))[0]
    if not offset + 8 <= table <= end - 8:
        raise _bad(p, f"LAZ chunk table at byte {table}, outside the point data ({offset + 8} to {end - 8})")
    f.seek(table)
    version, n_chunks = struct.unpack("<II", f.read(8))
    if version != 0:
        raise _bad(p, f"unknown LAZ chunk table version {version}")
    if n_chunks > table - offset - 8:
        raise _bad(p, f"{n_chunks} LAZ chunks announced in {table - offset - 8} bytes of point data")
    if chunk_size != LAZ_VARIABLE_CHUNKS and n_chunks != -(-n_points // chunk_size):
        raise _bad(p, f"{n_points} points announced, {n_chunks} LAZ chunks of {chunk_size} points")
    _check_chunk_entries(p, f, offset, table, n_points, chunk_size, rec_len, laszip)


def _check_chunk_entries(p, f, offset: int, table: int, n_points: int, chunk_size: int, rec_len: int,
                         laszip) -> None:
    """The entries of the LAZ chunk table (read by lazrs, when installed): the chunks' bytes
    within the compressed data, their points (variable chunks) adding up to ``n_points``. A
    garbage entry makes the decoder reserve an impossible buffer and panic."""
    try:
        import lazrs
    except ImportError:  # laspy will say that LAZ needs it
        return
    f.seek(offset)
    try:
        entries = lazrs.read_chunk_table(f, lazrs.LazVlr(laszip))
    except (KeyboardInterrupt, SystemExit, MemoryError):
        raise
    except BaseException as exc:  # lazrs errors, and Rust panics (BaseException)
        raise _bad(p, f"unreadable LAZ chunk table ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    room = table - offset - 8
    used = points = 0
    for i, (n, nbytes) in enumerate(entries):
        used += nbytes
        points += n
        if chunk_size == LAZ_VARIABLE_CHUNKS:
            _check_chunk_buffer(p, n, rec_len)
        if used > room:
            raise _bad(p, f"LAZ chunk {i + 1} of {len(entries)} ends after the compressed data ({room} bytes)")
    if chunk_size == LAZ_VARIABLE_CHUNKS and points != n_points:
        raise _bad(p, f"{n_points} points announced, the LAZ chunks hold {points}")
