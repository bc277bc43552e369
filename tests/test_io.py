"""Readers and writers: round trips, registry, errors."""

import json

import numpy as np
import pytest

from curvenet import Curve, CurveNetwork, FormatError, InputError, OutputError
from curvenet.io import READERS, WRITERS, atomic_write, read_network, read_points, write_network


@pytest.fixture
def pts3():
    rng = np.random.default_rng(0)
    return rng.normal(size=(57, 3)) * 10


@pytest.fixture
def net():
    nodes = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], float)
    curves = [
        Curve(np.array([[0, 0, 0], [0.5, 0.1, 0], [1, 0, 0]]), 0, 1, indices=[-1, 7, -1]),
        Curve(np.array([[1, 0, 0], [1.1, 0.5, 0], [1, 1, 0]]), 1, 2),
        Curve(np.array([[1, 1, 0], [1.5, 1.5, 0], [1, 2, 0], [1, 1, 0]]), 2, 2),
        Curve(np.array([[5, 5, 5], [6, 5, 5], [6, 6, 5]]), None, None, closed=True),
    ]
    return CurveNetwork(nodes, curves, {"method": "test", "k": 3}, {"N_d": 10})


@pytest.mark.parametrize("ext,sep", [(".xyz", " "), (".txt", "\t"), (".pts", " "), (".csv", ",")])
def test_text_roundtrip(tmp_path, pts3, ext, sep):
    f = tmp_path / f"p{ext}"
    np.savetxt(f, pts3, delimiter=sep, fmt="%.17g")
    np.testing.assert_array_equal(read_points(f), pts3)


def test_text_2d_and_header_and_comments(tmp_path):
    f = tmp_path / "p.csv"
    f.write_text("# a comment\nx,y\n1,2\n3,4\n\n5,6\n")
    np.testing.assert_array_equal(read_points(f), [[1, 2], [3, 4], [5, 6]])


def test_text_header_picks_named_columns(tmp_path):
    f = tmp_path / "p.csv"
    f.write_text("id,X,Y,Z,intensity\n0,1,2,3,9\n1,4,5,6,9\n")
    np.testing.assert_array_equal(read_points(f), [[1, 2, 3], [4, 5, 6]])


def test_text_extra_columns_need_a_choice(tmp_path):
    f = tmp_path / "p.xyz"
    f.write_text("1 2 3 255 0 0\n4 5 6 0 255 0\n")
    with pytest.raises(InputError, match="6 columns"):
        read_points(f)
    np.testing.assert_array_equal(read_points(f, columns=[0, 1, 2]), [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(read_points(f, columns=["3", "4"]), [[255, 0], [0, 255]])


def test_npy_roundtrip_and_structured(tmp_path, pts3):
    f = tmp_path / "p.npy"
    np.save(f, pts3)
    np.testing.assert_array_equal(read_points(f), pts3)
    s = np.zeros(3, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("w", "f4")])
    s["x"] = [1, 2, 3]
    np.save(f, s)
    assert read_points(f).shape == (3, 3)


@pytest.mark.parametrize("text", [True, False])
def test_ply_roundtrip(tmp_path, pts3, text):
    plyfile = pytest.importorskip("plyfile")
    v = np.zeros(len(pts3), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    v["x"], v["y"], v["z"] = pts3.T
    f = tmp_path / "p.ply"
    plyfile.PlyData([plyfile.PlyElement.describe(v, "vertex")], text=text).write(str(f))
    np.testing.assert_allclose(read_points(f), pts3, rtol=1e-15)


def test_obj_vertices(tmp_path):
    f = tmp_path / "p.obj"
    f.write_text("# c\nv 1 2 3\nvn 0 0 1\nv 4 5 6 1.0\nf 1 2 1\n  v 7 8 9\n")
    np.testing.assert_array_equal(read_points(f), [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


def test_las_roundtrip(tmp_path, pts3):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = np.array([1e-6, 1e-6, 1e-6])
    header.offsets = pts3.min(axis=0)
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts3.T
    f = tmp_path / "p.las"
    las.write(str(f))
    np.testing.assert_allclose(read_points(f), pts3, atol=2e-6)


def test_registry_has_every_documented_extension():
    assert {".xyz", ".txt", ".pts", ".csv", ".npy", ".ply", ".obj", ".las", ".laz"} <= set(READERS)
    assert {".json", ".obj", ".ply"} <= set(WRITERS)


def test_json_roundtrip(tmp_path, net):
    f = tmp_path / "n.json"
    write_network(net, f)
    back = read_network(f)
    assert back.n_nodes == 3 and back.n_curves == 4
    for a, b in zip(net.curves, back.curves):
        np.testing.assert_array_equal(a.points, b.points)
        assert (a.start, a.end, a.closed) == (b.start, b.end, b.closed)
        np.testing.assert_array_equal(a.indices, b.indices)
    assert back.parameters["k"] == 3
    d = json.loads(f.read_text())
    assert d["format"] == "curvenet" and d["version"] == 1 and d["dimension"] == 3
    assert d["curves"][3]["start"] is None and d["curves"][3]["closed"] is True


def test_obj_writer_shares_node_vertices(tmp_path, net):
    f = tmp_path / "n.obj"
    write_network(net, f)
    lines = f.read_text().splitlines()
    v = np.array([list(map(float, l.split()[1:])) for l in lines if l.startswith("v ")])
    polys = [list(map(int, l.split()[1:])) for l in lines if l.startswith("l ")]
    assert len(polys) == 4
    np.testing.assert_array_equal(v[:3], net.nodes)
    assert polys[0][0] == 1 and polys[0][-1] == 2 and polys[1][0] == 2  # shared node vertex
    for c, poly in zip(net.curves, polys):
        got = v[np.array(poly) - 1]
        want = np.vstack([c.points, c.points[:1]]) if c.start is None else c.points
        np.testing.assert_array_equal(got, want)
    # read back through our own OBJ point reader: every vertex is there
    assert len(read_points(f)) == len(v)


def test_ply_writer_reads_back(tmp_path, net):
    plyfile = pytest.importorskip("plyfile")
    f = tmp_path / "n.ply"
    from curvenet.io.network_io import network_to_ply

    f.write_bytes(network_to_ply(net, curve_ids=True))
    ply = plyfile.PlyData.read(str(f))
    v = np.column_stack([ply["vertex"][a] for a in "xyz"])
    e = ply["edge"]
    assert ply["vertex"]["node"].sum() == 3
    assert len(e) == sum(len(c.points) - 1 for c in net.curves) + 1  # free loop closes
    for ci, c in enumerate(net.curves):
        sel = e["curve"] == ci
        np.testing.assert_array_equal(v[e["vertex1"][sel]][: len(c.points) - 1], c.points[:-1])


def test_2d_network_writers(tmp_path):
    n = CurveNetwork(np.array([[0, 0], [1, 0]], float), [Curve(np.array([[0, 0], [0.5, 0.2], [1, 0]]), 0, 1)])
    write_network(n, tmp_path / "a.obj")
    assert "v 0.5 0.2 0.0" in (tmp_path / "a.obj").read_text()  # shortest round-trip decimals
    back = read_network(write_network(n, tmp_path / "a.json"))
    assert back.dimension == 2


def test_atomic_write_keeps_old_file_on_failure(tmp_path, monkeypatch):
    f = tmp_path / "out.json"
    f.write_text("old")

    def boom(*a, **k):
        raise KeyboardInterrupt

    import curvenet.io.atomic as atomic

    monkeypatch.setattr(atomic.os, "fsync", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(f, "new content")
    assert f.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]


def test_output_errors(tmp_path, net):
    with pytest.raises(OutputError, match="does not exist"):
        write_network(net, tmp_path / "missing" / "n.json")
    inp = tmp_path / "in.json"
    inp.write_text("keep")
    with pytest.raises(OutputError, match="same as the input"):
        write_network(net, inp, inputs=[inp])
    assert inp.read_text() == "keep"
    with pytest.raises(FormatError, match="unknown output extension"):
        write_network(net, tmp_path / "n.xyz")


def test_json_fast_and_plain_writers_agree(monkeypatch, net):
    """With orjson (curvenet[fast]) and without, the JSON reads back to the same values, bit
    for bit (the shortest round-trip text of every float), and NaN is refused by both."""
    import sys

    from curvenet import reconstruct, synth
    from curvenet.io.network_io import network_to_json

    pytest.importorskip("orjson")
    pts, _ = synth.sample(synth.model("tree"), noise=0.2, rng=1)
    big = reconstruct(pts)
    odd = CurveNetwork(np.array([[1e-5, -0.0, 1e16], [0.1, 0.2, 0.30000000000000004]]),
                       [Curve(np.array([[1e-5, -0.0, 1e16], [1 / 3, 2e-308, 5e-324],
                                        [0.1, 0.2, 0.30000000000000004]]), 0, 1),
                        Curve(np.zeros((0, 3)), None, None, closed=True)],
                       {"k": np.int64(3), "x": np.float64(0.1), "none": None}, {})
    for n in (net, big, odd):
        fast = network_to_json(n)
        with monkeypatch.context() as m:
            m.setitem(sys.modules, "orjson", None)  # import orjson fails: the json module writes
            plain = network_to_json(n)
        assert fast != plain and json.loads(fast) == json.loads(plain)
        assert fast.endswith("}\n")
    odd.curves[0].points[1, 1] = np.nan
    with pytest.raises(ValueError):
        network_to_json(odd)


def test_atomic_write_encodes_text_in_pieces(tmp_path, monkeypatch):
    """A ``str`` is written encoded a few characters at a time: the file holds its UTF-8 bytes,
    multi-byte characters across piece boundaries too; inside all_or_nothing a second write of
    the same path is compared with the first by its bytes (no temporary file left after)."""
    from curvenet.io import atomic
    from curvenet.io.atomic import all_or_nothing

    text = "n T x y z\n" + "é✓ 1.5 𝜋\n" * 50
    for piece in (1, 3, 7, 1 << 20):
        monkeypatch.setattr(atomic, "ENCODE_PIECE", piece)
        atomic_write(tmp_path / "a.txt", text)
        assert (tmp_path / "a.txt").read_bytes() == text.encode("utf-8")
        with all_or_nothing():
            atomic_write(tmp_path / "b.txt", text)
            atomic_write(tmp_path / "b.txt", text.encode("utf-8"))  # the same bytes: allowed
            with pytest.raises(OutputError):
                atomic_write(tmp_path / "b.txt", text + "!")
        assert (tmp_path / "b.txt").read_bytes() == text.encode("utf-8")
        assert sorted(q.name for q in tmp_path.iterdir()) == ["a.txt", "b.txt"]
