"""Issue 20 items 1 and 8: every reader, fed 300 corrupt versions of a valid file, returns points
or raises a documented one-line error naming the file; never another exception, an abort or a
runaway allocation."""

import io
import struct
import subprocess
import sys

import numpy as np
import pytest

from curvenet import CurvenetError
from curvenet.io import read_points

#: Mutated files per format.
N_MUTATIONS = 300

#: Integers written over header fields: the counts and offsets of a hostile header.
EXTREMES = [0, 1, 2**31 - 1, 2**32 - 1, 2**63 - 1, 2**16 - 1, 255, 2**31]


def _points(n=120):
    t = np.linspace(0, 4 * np.pi, n)
    return np.column_stack([np.cos(t), np.sin(t), 0.1 * t])


def _text(ext):
    pts = _points()
    sep = "," if ext == ".csv" else " "
    head = "x,y,z\n" if ext == ".csv" else "# a comment\n"
    return (head + "\n".join(sep.join(f"{v:.6f}" for v in row) for row in pts) + "\n").encode()


def _obj():
    return ("# obj\n" + "\n".join(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in _points()) + "\nl 1 2 3\n").encode()


def _npy():
    buf = io.BytesIO()
    np.save(buf, _points())
    return buf.getvalue()


def _ply(text):
    plyfile = pytest.importorskip("plyfile")
    pts = _points()
    v = np.zeros(len(pts), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    v["x"], v["y"], v["z"] = pts.T
    buf = io.BytesIO()
    plyfile.PlyData([plyfile.PlyElement.describe(v, "vertex")], text=text).write(buf)
    return buf.getvalue()


def _las(compressed, version="1.2"):
    laspy = pytest.importorskip("laspy")
    if compressed:
        pytest.importorskip("lazrs")
    las = laspy.LasData(laspy.LasHeader(point_format=3 if version == "1.2" else 6, version=version))
    pts = _points(500)
    las.x, las.y, las.z = pts.T
    buf = io.BytesIO()
    las.write(buf, do_compress=compressed)
    return buf.getvalue()


FORMATS = {
    ".xyz": lambda: _text(".xyz"),
    ".csv": lambda: _text(".csv"),
    ".obj": _obj,
    ".npy": _npy,
    ".ply": lambda: _ply(False),
    ".ply-ascii": lambda: _ply(True),
    ".las": lambda: _las(False),
    ".las-1.4": lambda: _las(False, "1.4"),
    ".laz": lambda: _las(True),
}


def _mutate(raw: bytes, rng) -> bytes:
    """One random corruption: bytes flipped or set, a header field set to an extreme count, a
    cut, an insertion or a repeated block."""
    b = bytearray(raw)
    kind = rng.integers(6)
    head = min(len(b), 400)  # most structure sits in the first bytes
    if kind == 0:
        for _ in range(rng.integers(1, 4)):
            i = rng.integers(head if rng.random() < 0.7 else len(b))
            b[i] ^= 1 << int(rng.integers(8))
    elif kind == 1:
        i = rng.integers(head)
        b[i] = int(rng.integers(256))
    elif kind == 2:
        i = int(rng.integers(max(head - 8, 1)))
        v = EXTREMES[rng.integers(len(EXTREMES))]
        w = 8 if v >= 2**32 else 4
        b[i:i + w] = struct.pack("<Q" if w == 8 else "<I", v)[: len(b[i:i + w])]
    elif kind == 3:
        b = b[: rng.integers(len(b))]
    elif kind == 4:
        i = rng.integers(len(b))
        b[i:i] = rng.bytes(int(rng.integers(1, 16)))
    else:
        i, j = sorted(rng.integers(len(b), size=2))
        b[j:j] = b[i:j]
    return bytes(b)


@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_hostile_files(tmp_path, capfd, fmt):
    raw = FORMATS[fmt]()
    ext = fmt.split("-")[0]
    f = tmp_path / f"p{ext}"
    f.write_bytes(raw)
    assert len(read_points(f)) > 100  # the valid file reads
    rng = np.random.default_rng(sum(map(ord, fmt)))
    outcomes = {"points": 0, "error": 0}
    for _ in range(N_MUTATIONS):
        f.write_bytes(_mutate(raw, rng))
        try:
            pts = read_points(f)
        except CurvenetError as exc:
            msg = str(exc)
            assert msg.startswith(f"{f}") and "\n" not in msg, msg
            outcomes["error"] += 1
            continue
        assert pts.ndim == 2 and pts.shape[1] in (2, 3) and len(pts) and np.isfinite(pts).all()
        outcomes["points"] += 1
    assert outcomes["error"] > 0  # the corruptions were seen
    assert "panicked" not in capfd.readouterr().err  # no decoder panic, even a caught one


def test_las_header_counts_checked_against_the_file_size(tmp_path):
    """On main: a LAS file claiming 2**31 - 1 VLRs ran 148 s and took 7.7 GB; a LAZ file whose
    offset to the points had one byte flipped aborted the process (exit 134)."""
    raw = _las(False)
    b = bytearray(raw)
    b[100:104] = struct.pack("<I", 2**31 - 1)
    f = tmp_path / "vlrs.las"
    f.write_bytes(bytes(b))
    with pytest.raises(CurvenetError, match="2147483647 VLRs announced"):
        read_points(f)
    raw = _las(True)
    for byte in range(96, 100):
        for v in (0x01, 0x80, 0xFF):
            b = bytearray(raw)
            b[byte] ^= v
            f = tmp_path / "bad.laz"
            f.write_bytes(bytes(b))
            with pytest.raises(CurvenetError, match="not a valid LAS/LAZ file"):
                read_points(f)
    # a block repeated inside the compressed points: lazrs panics ("capacity overflow"), a
    # BaseException that an ``except Exception`` let through (exit 1 with a traceback)
    f.write_bytes(raw[:865] + raw[188:865] + raw[865:])
    with pytest.raises(CurvenetError, match="not a valid LAS/LAZ file"):
        read_points(f)
    b = bytearray(raw)
    b[107:111] = struct.pack("<I", 2**32 - 1)  # the number of points
    f.write_bytes(bytes(b))
    with pytest.raises(CurvenetError, match="4294967295 points announced"):
        read_points(f)


def test_laz_chunk_size_checked_before_the_decoder_reserves_it(tmp_path):
    """The LASzip VLR's chunk size sets the buffer lazrs reserves (chunk size x record length):
    one flipped bit (byte 296, bit 3: 134 million points) took 4.5 GB and 40 s, 2**30 points
    aborted the process (exit 134, 'memory allocation of 36507205016 bytes failed'). Run in
    a child process, so that an abort fails this test instead of killing the test run."""
    raw = _las(True)
    at = raw.index(b"laszip encoded") - 2 + 54 + 12  # the chunk size in the LASzip VLR's data
    assert struct.unpack_from("<I", raw, at)[0] == 50_000
    files = []
    for size in (50_000 + 2**27, 2**30, 0xF0000000):
        b = bytearray(raw)
        b[at:at + 4] = struct.pack("<I", size)
        files.append(tmp_path / f"c{size}.laz")
        files[-1].write_bytes(bytes(b))
    for f in files:
        r = subprocess.run([sys.executable, "-m", "curvenet", "info", str(f)], capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 2, r.stderr[-300:]
        assert r.stderr.strip().splitlines() == [r.stderr.strip()] and "LAZ chunks of" in r.stderr


def test_every_bit_of_a_laz_header_flipped(tmp_path):
    """Each of the 8 bits of each byte before the compressed points (public header, LASzip VLR,
    chunk table offset: 2,728 files), read in one child process: points or the one-line error,
    never an abort, another exception or a panic message."""
    raw = _las(True)
    offset = struct.unpack_from("<I", raw, 96)[0]
    f = tmp_path / "flip.laz"
    script = f"""
import sys
from curvenet import CurvenetError
from curvenet.io import read_points
raw = open({str(tmp_path / 'good.laz')!r}, "rb").read()
outcomes = [0, 0]
for i in range({offset + 8}):
    for bit in range(8):
        b = bytearray(raw)
        b[i] ^= 1 << bit
        open({str(f)!r}, "wb").write(b)
        try:
            read_points({str(f)!r})
            outcomes[0] += 1
        except CurvenetError as exc:
            assert "\\n" not in str(exc), str(exc)
            outcomes[1] += 1
print(*outcomes)
"""
    (tmp_path / "good.laz").write_bytes(raw)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-500:]
    points, errors = map(int, r.stdout.split())
    assert points + errors == 8 * (offset + 8) and errors > 0
    assert "panicked" not in r.stderr and "Warning" not in r.stderr, r.stderr[-500:]


def test_a_corrupt_las_scale_is_one_line(tmp_path):
    """A scale factor of 1e308 overflowed in laspy's scaling: numpy's RuntimeWarning (two more
    lines on standard error) before the error."""
    raw = bytearray(_las(False))
    raw[131:139] = struct.pack("<d", 1e308)  # the x scale factor
    f = tmp_path / "scale.las"
    f.write_bytes(bytes(raw))
    r = subprocess.run([sys.executable, "-m", "curvenet", "info", str(f)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [r.stderr.strip()] and "NaN or infinite" in r.stderr


def test_a_las_file_is_read_without_copies(tmp_path, monkeypatch):
    """The points of a LAS file decoded straight into the result: on main the blocks, their
    vstack and the column selection made three copies (peak 3 times the result under
    tracemalloc), and the last two ran after the last Ctrl-C checkpoint."""
    import tracemalloc

    import curvenet.io.points as points_module

    laspy = pytest.importorskip("laspy")
    monkeypatch.setattr(points_module, "LAS_CHUNK_POINTS", 50_000)
    n = 400_000
    las = laspy.LasData(laspy.LasHeader(point_format=0, version="1.2"))
    t = np.linspace(0, 40, n)
    las.x, las.y, las.z = np.cos(t), np.sin(t), t
    f = tmp_path / "big.las"
    las.write(str(f))
    read_points(f)  # imports and caches outside the measure
    tracemalloc.start()
    try:
        pts = read_points(f)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_allclose(pts[:, 2], t, atol=0.01)
    assert peak < 1.5 * pts.nbytes, peak / pts.nbytes
