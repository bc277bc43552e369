"""Issue 21, reading and the command line: text columns, .tsv, standard input and output, .pcd
(written by Open3D), other libraries' point clouds, the help, completion, and the new
output options (--view, --units, --labels)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from curvenet import reconstruct
from curvenet.cli import main
from curvenet.errors import FormatError
from curvenet.io import read_points

SRC = str(Path(__file__).resolve().parents[1] / "src")


def run_cli(*args, stdin=None, env=None):
    e = dict(os.environ)
    e["PYTHONPATH"] = SRC + os.pathsep + e.get("PYTHONPATH", "")
    e.pop("CURVENET_PROGRESS", None)
    e.update(env or {})
    return subprocess.run([sys.executable, "-m", "curvenet", *map(str, args)], input=stdin, capture_output=True,
                          env=e, timeout=120)


def tee_points(n=60):
    """A T: a bar and a stem meeting at its middle, in 3D."""
    t = np.linspace(-1, 1, 2 * n + 1)[:, None]
    bar = t * [1.0, 0, 0]
    s = np.linspace(0, 1, n + 1)[1:, None]
    stem = s * [0, 1.0, 0.3]
    return np.vstack([bar, stem])


# ----------------------------------------------------------------------------- text columns, .tsv
def test_text_columns_are_skipped(tmp_path):
    pts = tee_points(10)
    f = tmp_path / "scan.csv"
    rows = [f"p{i},{i % 7},{x!r},{y!r},{z!r},label {i % 3}" for i, (x, y, z) in enumerate(pts.tolist())]
    f.write_text("id,intensity,x,y,z,label\n" + "\n".join(rows) + "\n")
    assert np.array_equal(read_points(f, columns=["x", "y", "z"]), pts)
    assert np.array_equal(read_points(f), pts)  # the header names x, y, z
    assert np.array_equal(read_points(f, columns=[2, 3]), pts[:, :2])
    with pytest.raises(FormatError, match=r"column 'label' is not numeric") as e:
        read_points(f, columns=["x", "y", "label"])
    assert "\n" not in str(e.value)


def test_tsv_with_text_fields(tmp_path):
    pts = tee_points(10)
    f = tmp_path / "scan.tsv"
    f.write_text("name\tx\ty\tz\n" + "".join(f"a b {i}\t{x!r}\t{y!r}\t{z!r}\n" for i, (x, y, z) in enumerate(pts.tolist())))
    assert np.array_equal(read_points(f), pts)


# ----------------------------------------------------------------------------- stdin / stdout
def test_stdin_to_stdout_through_a_pipe():
    pts = tee_points()
    text = "\n".join(f"{x!r} {y!r} {z!r}" for x, y, z in pts.tolist()).encode()
    r = run_cli("reconstruct", "-", "--format", "xyz", "-o", "-", stdin=text)
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)  # standard output holds the network alone
    assert doc["format"] == "curvenet" and len(doc["nodes"]) == 4 and len(doc["curves"]) == 3
    assert b"N_n" in r.stderr  # the summary went to standard error


def _stdin(monkeypatch, data: bytes):
    import io

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))


def test_stdin_stdout_formats_and_errors(tmp_path, monkeypatch, capsysbinary):
    text = "\n".join(f"{x!r} {y!r} {z!r}" for x, y, z in tee_points().tolist()).encode()
    _stdin(monkeypatch, text)
    assert main(["reconstruct", "-", "--format", "xyz", "-o", "-", "--output-format", "geojson", "-q"]) == 0
    out, err = capsysbinary.readouterr()
    assert json.loads(out)["type"] == "FeatureCollection" and err == b""
    _stdin(monkeypatch, text)
    assert main(["reconstruct", "-", "-o", str(tmp_path / "a.json")]) == 2
    out, err = capsysbinary.readouterr()
    assert b"needs --format" in err and len(err.strip().splitlines()) == 1 and not (tmp_path / "a.json").exists()
    _stdin(monkeypatch, b"1 2 3\n4 5\n")
    assert main(["reconstruct", "-", "--format", "xyz", "-o", "-"]) == 2
    out, err = capsysbinary.readouterr()
    assert err.startswith(b"curvenet: error: <stdin>:") and b"/tmp" not in err and out == b""
    _stdin(monkeypatch, text)
    assert main(["reconstruct", "-", "--format", "npy", "-o", "-"]) == 2
    assert b"not a valid .npy" in capsysbinary.readouterr().err


# ----------------------------------------------------------------------------- .pcd
@pytest.mark.parametrize("how", ["ascii", "binary", "binary_compressed"])
def test_pcd_written_by_open3d(tmp_path, how):
    o3d = pytest.importorskip("open3d", exc_type=ImportError)
    pts = np.random.default_rng(2).normal(size=(500, 3))
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    pc.colors = o3d.utility.Vector3dVector(np.random.default_rng(3).random((500, 3)))
    f = tmp_path / "c.pcd"
    o3d.io.write_point_cloud(str(f), pc, write_ascii=how == "ascii", compressed=how == "binary_compressed")
    assert f"DATA {how}".encode() in f.read_bytes()[:400]
    want = np.asarray(o3d.io.read_point_cloud(str(f)).points)
    assert np.array_equal(read_points(f), want)


def test_pcd_by_hand_and_broken(tmp_path):
    head = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z label\nSIZE 8 8 8 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
            "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary\n")
    rec = np.zeros(3, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("label", "<u4")])
    rec["x"], rec["y"], rec["z"], rec["label"] = [0.1, 1, 2], [3, 4, 5], [6, 7, 8.5], [1, 2, 3]
    f = tmp_path / "h.pcd"
    f.write_bytes(head.encode() + rec.tobytes())
    assert np.array_equal(read_points(f), np.column_stack([rec["x"], rec["y"], rec["z"]]))
    f.write_bytes(head.encode() + rec.tobytes()[:-10])
    with pytest.raises(FormatError, match="truncated"):
        read_points(f)
    f.write_bytes(b"VERSION 0.7\nFIELDS x y z\n")
    with pytest.raises(FormatError, match="not a PCD file"):
        read_points(f)


# ----------------------------------------------------------------------------- Python objects
def test_other_libraries_point_clouds():
    pts = tee_points()
    want = reconstruct(pts)
    o3d = pytest.importorskip("open3d", exc_type=ImportError)
    assert reconstruct(o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))) == want
    trimesh = pytest.importorskip("trimesh")
    assert reconstruct(trimesh.PointCloud(pts)) == want
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = [1e-9] * 3, [0.0] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    scaled = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])  # on the 1e-9 grid
    assert np.abs(scaled - pts).max() < 1e-8
    assert reconstruct(las) == reconstruct(scaled)


def test_point_clouds_recognised_without_importing_their_packages():
    code = ("import sys, numpy as np, curvenet\n"
            "t = np.linspace(0, 1, 50)\n"
            "curvenet.reconstruct(np.column_stack([t, t * t, 0 * t]))\n"
            "print(sorted(m for m in ('open3d', 'trimesh', 'laspy', 'pandas') if m in sys.modules))\n")
    e = dict(os.environ, PYTHONPATH=SRC)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=e, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "[]", r.stderr


# ----------------------------------------------------------------------------- help, method name, completion
def test_help_lists_robust_parameters_and_ends_with_examples(capsys):
    from curvenet.cli import COMMANDS

    with pytest.raises(SystemExit):
        main(["reconstruct", "--help"])
    out = capsys.readouterr().out
    for opt in ("--spacing", "--shell-inner", "--shell-outer", "--link ", "--link-width", "--min-spur", "--fit",
                "--smoothing", "--k", "--epsilon", "--tau-s", "--theta"):
        assert opt in out, opt
    assert "robust (the default" in out and "auto (default)" not in out
    assert "parameters of the default method, robust" in out
    for cmd in COMMANDS:
        with pytest.raises(SystemExit):
            main([cmd, "--help"])
        out = capsys.readouterr().out
        tail = out.split("examples:\n")[-1].splitlines()
        assert "examples:\n" in out and 1 <= len(tail) <= 4 and all(t.startswith("  curvenet ") or "curvenet" in t
                                                                   for t in tail), cmd
    with pytest.raises(SystemExit):
        main(["info", "--help"])
    assert "Betti numbers" in capsys.readouterr().out  # info has a description


def test_default_method_has_one_name(tmp_path, capsys):
    f = tmp_path / "t.xyz"
    np.savetxt(f, tee_points(20))
    assert main(["reconstruct", str(f), "-o", str(tmp_path / "a.json"), "--verbose"]) == 0
    err = capsys.readouterr().err
    assert "reconstructing (robust)" in err and "(auto)" not in err
    assert json.loads((tmp_path / "a.json").read_text())["parameters"]["method"] == "robust"


def test_shell_completion(tmp_path, capsys):
    pytest.importorskip("argcomplete")
    assert main(["completion", "bash"]) == 0
    code = capsys.readouterr().out
    assert "complete" in code and "curvenet" in code
    for line, want in (("curvenet rec", {"reconstruct"}),
                       ("curvenet reconstruct x.xyz --sh", {"--shell-inner", "--shell-outer"})):
        out = tmp_path / "completions"
        r = run_cli(env={"_ARGCOMPLETE": "1", "COMP_LINE": line, "COMP_POINT": str(len(line)),
                         "_ARGCOMPLETE_STDOUT_FILENAME": str(out)})
        assert r.returncode == 0, r.stderr
        assert {w.strip() for w in out.read_text().split("\x0b")} == want


def test_python_dash_m_curvenet():
    r = run_cli("--version")
    assert r.returncode == 0 and r.stdout.startswith(b"curvenet ")


# ----------------------------------------------------------------------------- output options
def test_cli_view_units_labels(tmp_path, capsys):
    ezdxf = pytest.importorskip("ezdxf")
    f = tmp_path / "t.xyz"
    pts = tee_points(20)
    np.savetxt(f, pts)
    out = [str(tmp_path / n) for n in ("top.svg", "front.svg", "a.dxf", "l.csv", "l.npy")]
    assert main(["reconstruct", str(f), "-o", out[0], "-q"]) == 0
    assert main(["reconstruct", str(f), "-o", out[1], "-o", out[2], "--view", "front", "--units", "mm",
                 "--labels", out[3], "-q"]) == 0
    assert 'data-projection="xy"' in Path(out[0]).read_text() and 'data-projection="xz"' in Path(out[1]).read_text()
    assert ezdxf.readfile(out[2]).header["$INSUNITS"] == 4
    lab = np.loadtxt(out[3], delimiter=",", skiprows=1, dtype=np.int64)
    assert lab.shape == (len(pts), 3) and np.array_equal(lab[:, 0], np.arange(len(pts)))
    assert ((lab[:, 1:] >= 0).sum(axis=1) == 1).all()  # clean input: every point on a curve or a node
    assert main(["reconstruct", str(f), "--labels", out[4], "-q"]) == 0
    assert np.array_equal(np.load(out[4]), lab[:, 1:])
    assert main(["reconstruct", str(f), "--labels", str(tmp_path / "l.txt"), "-q"]) == 2
    assert "--labels file must end in .csv or .npy" in capsys.readouterr().err


def test_formats_lists_the_new_readers_and_writers(capsys):
    import re

    assert main(["formats"]) == 0
    out = capsys.readouterr().out
    readable, writable = out.split("Writable network files")[0], out.split("Writable network files")[1]
    for ext in (".tsv", ".pcd"):
        assert re.search(rf"^  {re.escape(ext)} ", readable, re.M), ext
    for ext in (".vtu", ".geojson", ".swc"):
        assert re.search(rf"^  {re.escape(ext)} ", writable, re.M), ext


def test_progress_log_lines_name_and_number_the_stages(tmp_path, monkeypatch, capsys):
    f = tmp_path / "t.xyz"
    np.savetxt(f, tee_points(20))
    monkeypatch.setenv("CURVENET_PROGRESS", "log")
    assert main(["reconstruct", str(f), "-o", str(tmp_path / "a.json"), "-o", str(tmp_path / "a.ply")]) == 0
    lines = capsys.readouterr().err.splitlines()
    import re

    assert len(lines) == 8, lines
    assert re.fullmatch(r"curvenet: \[1/3\] reading t\.xyz: \d+\.\d\d s", lines[0])
    parts = ("neighbors", "graph", "nodes", "tracing", "assemble")  # the method's own stages
    for line, part in zip(lines[1:6], parts):
        assert re.fullmatch(rf"curvenet: \[2/3\] reconstructing \(robust\) \u00b7 61 points \u00b7 {part} "
                            rf"\(\d+% of the work\): \d+\.\d\d s(, .+ left)?", line), line
    assert re.fullmatch(r"curvenet: \[2/3\] reconstructing \(robust\) \u00b7 61 points: \d+\.\d\d s", lines[6])
    assert re.fullmatch(r"curvenet: \[3/3\] writing \u00b7 2 file\(s\): \d+\.\d\d s", lines[7])
    assert main(["reconstruct", str(f), "-o", str(tmp_path / "b.json"), "-q"]) == 0
    assert capsys.readouterr().err == ""  # --quiet wins
