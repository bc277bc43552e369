"""Issue 21, the Python object: equality, allclose, len and iteration, a clearly mutable network
whose derived values never go stale, save/load at the top level, and typed public API."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import curvenet
from curvenet import Curve, CurveNetwork

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from test_writers_extra import sample_network  # noqa: E402


def test_equality_exact_and_on_canonical_forms():
    a, b = sample_network(3), sample_network(3)
    assert a == b and not (a != b)
    assert a.canonical() == b.canonical()  # the docstring's advice works (it raised ValueError)
    shuffled = CurveNetwork(a.nodes, a.curves[::-1], dict(a.parameters))
    assert shuffled != a and shuffled.canonical() == a.canonical()
    b.curves[2].points[3, 1] += 1e-12
    assert a != b and a.allclose(b) and not a.allclose(b, rtol=0, atol=1e-13)
    c = sample_network(3)
    c.curves[0] = Curve(c.curves[0].points, 1, 0)  # other end nodes: not close at any tolerance
    assert not a.allclose(c, atol=10)
    assert a != sample_network(2) and not a.allclose(sample_network(2))
    assert (a == "network") is False
    with pytest.raises(TypeError):
        hash(a)  # mutable, so not hashable


def test_len_iter_and_derived_values_follow_changes():
    net = sample_network(3)
    assert len(net) == net.n_curves == 6 and list(net) == net.curves
    assert [len(c) for c in net] == [len(c.points) for c in net.curves]
    val, betti = net.valence.copy(), net.betti
    net.curves.append(Curve(np.array([[2.0, 0.5, 1.5], [3, 3, 3]]), 2, 2))  # a loop at the free end
    assert net.valence[2] == val[2] + 2 and net.betti == (betti[0], betti[1] + 1)  # no stale cache
    net.curves.pop()
    assert np.array_equal(net.valence, val)


def test_save_and_load_at_the_top_level(tmp_path):
    net = sample_network(3)
    path = curvenet.save(net, tmp_path / "n.json")
    assert curvenet.load(path) == net
    assert curvenet.save(net, tmp_path / "n.svg", projection="iso").read_text().startswith("<?xml")
    with pytest.raises(curvenet.FormatError):
        curvenet.save(net, tmp_path / "n.xyz")
    with pytest.raises(curvenet.InputError):
        curvenet.load(tmp_path / "missing.json")


@pytest.mark.parametrize("options", [{}, {"indent": 2}], ids=["compact (orjson when installed)", "indented (json)"])
@pytest.mark.parametrize("dim", [2, 3])
def test_net_save_round_trips_through_load(tmp_path, options, dim):
    """``net.save`` then ``curvenet.load``: exactly equal, for each JSON writer path (the only
    format read back); a nudged coordinate breaks ``==`` but not ``allclose``."""
    net = sample_network(3)
    if dim == 2:
        net = CurveNetwork(net.nodes[:, :2].copy(), [Curve(c.points[:, :2].copy(), c.start, c.end, c.closed,
                                                           c.indices) for c in net.curves])
    net.curves[0].points[1] += np.array([0.1, 1 / 3, 2 / 7][:dim])  # digits that need all 17 places
    path = net.save(tmp_path / "n.json", **options)
    assert path == tmp_path / "n.json"
    back = curvenet.load(path)
    assert back == net and back.allclose(net, rtol=0, atol=0)
    assert back.canonical() == net.canonical()
    assert back.dimension == dim and [c.start for c in back] == [c.start for c in net]
    back.curves[0].points[1, 0] = np.nextafter(back.curves[0].points[1, 0], np.inf)
    assert back != net and back.allclose(net) and not back.allclose(net, rtol=0, atol=0)


def test_net_save_writes_every_format_and_load_refuses_the_ones_it_cannot_read(tmp_path):
    from curvenet.io import WRITERS

    net = sample_network(3)
    for ext in sorted(WRITERS):
        path = net.save(tmp_path / f"n{ext}")
        a, b = path.read_bytes(), curvenet.save(net, tmp_path / f"m{ext}").read_bytes()
        if ext == ".dxf":  # ezdxf stamps each file with random GUIDs and its times of writing
            a, b = (_without_stamps(x) for x in (a, b))
        assert a == b, ext
        if ext != ".json":
            with pytest.raises(curvenet.FormatError, match="written, not read back"):
                curvenet.load(path)
    with pytest.raises(curvenet.FormatError):
        net.save(tmp_path / "n.xyz")


def _without_stamps(dxf: bytes) -> list[str]:
    """The DXF's lines with the values of its GUID and time header variables blanked."""
    lines = dxf.decode().split("\n")
    for i, line in enumerate(lines):
        if re.fullmatch(r"\$(TD\w+|FINGERPRINTGUID|VERSIONGUID)", line.strip()):
            lines[i + 2] = ""
        lines[i] = re.sub(r"@ \d{4}-\d\d-\d\dT[0-9:.+]+", "", lines[i])
    return lines


def test_network_module_never_imports_the_file_formats():
    """CurveNetwork.save reaches curvenet.io only through the writer the package hands in."""
    import ast

    import curvenet.network as network

    tree = ast.parse(Path(network.__file__).read_text())
    imported = [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    imported += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    assert not [m for m in imported if m.lstrip(".").startswith("io") or "curvenet.io" in m]
    assert network._file_writer is curvenet.save


def test_meshlab_reads_the_network_and_surface_ply(tmp_path):
    """MeshLab's own reader (pymeshlab, of the surface extra) opens both PLY files."""
    pymeshlab = pytest.importorskip("pymeshlab")
    from curvenet import synth

    net = synth.model("cube")
    curvenet.save(net, tmp_path / "net.ply")
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(tmp_path / "net.ply"))
    m = ms.current_mesh()
    assert m.vertex_number() > 0
    assert m.edge_number() == sum(len(c.points) - 1 for c in net.curves)  # every segment a line
    mesh = curvenet.surface(net)
    from curvenet.io.mesh import mesh_to_ply

    (tmp_path / "mesh.ply").write_bytes(mesh_to_ply(mesh))
    ms.load_new_mesh(str(tmp_path / "mesh.ply"))
    assert ms.current_mesh().face_number() == len(mesh.triangles)


def test_py_typed_is_shipped():
    assert (ROOT / "src" / "curvenet" / "py.typed").exists()
    text = (ROOT / "pyproject.toml").read_text()
    assert 'curvenet = ["py.typed"]' in text


#: numpy's and scipy's stubs are skipped (their types become Any): checking them takes a minute
#: and is their business; every function of ours must still be fully annotated and consistent.
MYPY_INI = """[mypy]
ignore_missing_imports = True
follow_imports = skip
disallow_untyped_defs = True
disallow_incomplete_defs = True

[mypy-numpy.*,scipy.*]
follow_imports_for_stubs = True
"""


def test_public_api_type_hints_pass_mypy(tmp_path):
    pytest.importorskip("mypy")
    (tmp_path / "mypy.ini").write_text(MYPY_INI)
    files = ["__init__.py", "network.py", "reconstruct.py", "io/__init__.py", "io/network_io.py", "io/labels.py",
             "io/numbers.py", "io/stdio.py", "io/geojson.py", "io/swc.py", "io/vtu.py", "io/pcd.py"]
    args = [sys.executable, "-m", "mypy", "--config-file", str(tmp_path / "mypy.ini"), "--cache-dir",
            str(tmp_path / "cache"), "--no-error-summary"]
    r = subprocess.run([*args, *[str(ROOT / "src" / "curvenet" / f) for f in files]],
                       capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
    (tmp_path / "untyped.py").write_text("def f(x):\n    return x\n")  # the check can fail
    r = subprocess.run([*args, str(tmp_path / "untyped.py")], capture_output=True, text=True, timeout=600)
    assert r.returncode == 1 and "missing a type annotation" in r.stdout


def test_canonical_without_copy_is_the_same_form_and_shares_the_kept_curves():
    from curvenet import synth

    net = synth.model("wheel")
    shuffled = CurveNetwork(net.nodes[::-1], [Curve(c.points, len(net.nodes) - 1 - c.start, len(net.nodes) - 1 - c.end)
                                              if c.start is not None else c for c in net.curves[::-1]])
    before = [c.points.copy() for c in shuffled.curves]
    a, b = shuffled.canonical(), shuffled.canonical(copy=False)
    assert a == b
    shared = [any(np.shares_memory(cb.points, c.points) for c in shuffled.curves) for cb in b.curves]
    assert any(shared) and not any(any(np.shares_memory(ca.points, c.points) for c in shuffled.curves)
                                   for ca in a.curves)
    assert all(np.array_equal(x, c.points) for x, c in zip(before, shuffled.curves))  # left as it was


def test_canonical_curve_order_is_the_order_by_the_whole_key():
    # the canonical order sorts by end nodes, and by the rounded polyline only among curves
    # with the same ends: the same order as sorting every curve by the whole key
    from curvenet.network import _key, _key_order

    rng = np.random.default_rng(5)
    curves = []
    for _ in range(300):
        s, e = (None, None) if rng.random() < 0.1 else tuple(int(x) for x in rng.integers(0, 6, 2))
        m = int(rng.integers(1, 5))
        pts = np.round(rng.random((m, 3)) * 3) / 3  # many ties in the leading coordinates
        if rng.random() < 0.2 and curves:  # exact duplicates of an earlier curve
            other = curves[int(rng.integers(len(curves)))]
            s, e, pts = other.start, other.end, other.points.copy()
        curves.append(Curve(pts, s, e, s is None))
    assert _key_order(curves, 6) == sorted(range(len(curves)), key=lambda i: _key(curves[i], 6))
