"""Issue 7: readers fed random bytes or random text raise only curvenet's documented errors."""

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from curvenet import CurvenetError
from curvenet.io import READERS, read_points

EXTS = sorted(READERS)
FUZZ = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _read_or_documented_error(path):
    try:
        pts = read_points(path)
    except CurvenetError as exc:
        msg = str(exc)
        assert "\n" not in msg and msg
        return None
    assert pts.ndim == 2 and pts.shape[1] in (2, 3) and len(pts) > 0
    assert np.isfinite(pts).all()
    return pts


@FUZZ
@given(data=st.binary(max_size=600), ext=st.sampled_from(EXTS))
def test_random_bytes(tmp_path, data, ext):
    f = tmp_path / f"fuzz{ext}"
    f.write_bytes(data)
    _read_or_documented_error(f)


_token = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**6, 10**6).map(str),
    st.sampled_from(["x", "y", "z", "nan", "-", "1e", "0x10", "#", "v", "1,2", ""]),
)
_line = st.lists(_token, max_size=5).map(lambda t: " ".join(t))


@FUZZ
@given(lines=st.lists(_line, max_size=12), ext=st.sampled_from([".xyz", ".csv", ".txt", ".pts", ".obj"]))
@example(lines=["v "], ext=".obj")  # a vertex line without coordinates read as no points (found by this test)
def test_random_text(tmp_path, lines, ext):
    f = tmp_path / f"fuzz{ext}"
    f.write_text("\n".join(lines))
    _read_or_documented_error(f)


@FUZZ
@given(data=st.binary(min_size=1, max_size=64), cut=st.integers(0, 400))
def test_corrupted_valid_files(tmp_path, data, cut):
    """Valid PLY/NPY files with their tail cut or overwritten by random bytes."""
    import io

    plyfile = pytest.importorskip("plyfile")
    pts = np.arange(60.0).reshape(20, 3)
    v = np.zeros(20, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    v["x"], v["y"], v["z"] = pts.T
    buf = io.BytesIO()
    plyfile.PlyData([plyfile.PlyElement.describe(v, "vertex")]).write(buf)
    ply = buf.getvalue()
    buf = io.BytesIO()
    np.save(buf, pts)
    npy = buf.getvalue()
    for name, raw in (("a.ply", ply), ("a.npy", npy)):
        k = min(cut, len(raw) - 1)
        for blob in (raw[:k], raw[:k] + data + raw[k + len(data):]):
            f = tmp_path / name
            f.write_bytes(blob)
            _read_or_documented_error(f)
