"""The command line through a subprocess: help, version, formats, info, bad input."""

import subprocess
import sys

import numpy as np

import curvenet


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "curvenet.cli", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_help_lists_every_command():
    from curvenet.cli import COMMANDS

    r = cli("--help")
    assert r.returncode == 0
    for name in COMMANDS:
        assert name in r.stdout


def test_version():
    r = cli("--version")
    assert r.returncode == 0 and curvenet.__version__ in r.stdout


def test_formats_lists_registry():
    r = cli("formats")
    assert r.returncode == 0
    for ext in (".xyz", ".csv", ".ply", ".npy", ".json", ".obj"):
        assert ext in r.stdout


def test_info_points(tmp_path):
    f = tmp_path / "a.xyz"
    np.savetxt(f, np.column_stack([np.arange(10.0), np.zeros(10), np.zeros(10)]))
    r = cli("info", f)
    assert r.returncode == 0, r.stderr
    assert "10 points, dimension 3" in r.stdout and "median 1" in r.stdout


def test_no_command_is_usage_error():
    assert cli().returncode == 2
    assert cli("reconstruct").returncode == 2  # missing INPUT


def test_param_option_reaches_the_method(tmp_path):
    import json

    out = tmp_path / "a.json"
    r = cli("reconstruct", "examples/mug.xyz", "-p", "min_spur=4", "--param", "k=20", "-q", "-o", out,
            cwd=__import__("pathlib").Path(__file__).resolve().parents[1])
    assert r.returncode == 0, r.stderr
    params = json.loads(out.read_text())["parameters"]
    assert params["k"] == 20 and params["min_spur"] == 4


def test_unknown_param_is_usage_error(tmp_path):
    f = tmp_path / "p.xyz"
    np.savetxt(f, np.column_stack([np.arange(30.0), np.zeros(30), np.zeros(30)]))
    r = cli("reconstruct", f, "-p", "nosuch=1", "-o", tmp_path / "o.json")
    assert r.returncode == 2 and "has no parameter 'nosuch'" in r.stderr
    assert not (tmp_path / "o.json").exists()
    r = cli("reconstruct", f, "-p", "novalue")
    assert r.returncode == 2 and "NAME=VALUE" in r.stderr


def test_broken_pipe_is_quiet():
    p = subprocess.run(f"{sys.executable} -m curvenet.cli formats | head -1", shell=True, capture_output=True, text=True)
    assert "Traceback" not in p.stderr and "internal error" not in p.stderr


def test_info_network(tmp_path):
    root = __import__("pathlib").Path(__file__).resolve().parents[1]
    out = tmp_path / "mug.json"
    assert cli("reconstruct", root / "examples" / "mug.xyz", "-q", "-o", out).returncode == 0
    r = cli("info", out)
    assert r.returncode == 0, r.stderr
    assert "nodes 10 (free ends 0, junctions 10)" in r.stdout and "curves 15" in r.stdout
    assert "b0=1 b1=6" in r.stdout and "method=robust" in r.stdout
