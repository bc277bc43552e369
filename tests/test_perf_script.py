"""The speed benchmark script runs (tiny sizes), so it cannot rot. No timing assertions."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bench_scripts import load

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "perf.py"
pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="benchmarks/perf.py not in this checkout")


def _load():
    return load("perf")


def test_make_points_reaches_the_size_with_whole_models():
    perf = _load()
    P, truth = perf.make_points(1500, seed=3)
    assert P.shape[1] == 3 and len(P) >= 1500
    assert truth["copies"] >= 2 and truth["nodes"] > 0 and truth["curves"] > 0
    # deterministic, and copies do not overlap (grid cells of 4 units)
    Q, _ = perf.make_points(1500, seed=3)
    assert np.array_equal(P, Q)


def test_written_files_read_back(tmp_path):
    from curvenet.io import read_points

    perf = _load()
    P, _ = perf.make_points(500, seed=1)
    perf.write_xyz(tmp_path / "a.xyz", P)
    perf.write_ply(tmp_path / "a.ply", P)
    A = read_points(tmp_path / "a.xyz")
    B = read_points(tmp_path / "a.ply")
    assert np.array_equal(B, P)
    assert np.allclose(A, P, rtol=1e-8, atol=1e-8)


def test_quick_run_writes_table_and_plot(tmp_path):
    out = tmp_path / "perf.md"
    (tmp_path / "perf.md").write_text("# Notes kept\n\nhand-written text\n")
    r = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--no-compile", "--methods", "robust,paper",
         "--out", str(out), "--tmp", str(tmp_path)],
        capture_output=True, text=True, timeout=240,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    text = out.read_text()
    # no markers yet: the generated block goes below the existing notes
    assert text.startswith("# Notes kept\n\nhand-written text\n")
    assert "| N | method |" in text
    rows = [ln for ln in text.splitlines() if ln.startswith("| 1,") or ln.startswith("| 2,")]
    assert {ln.split("|")[2].strip() for ln in rows} == {"robust", "paper"}
    assert len(rows) == 4
    assert (tmp_path / "img" / "performance.png").stat().st_size > 1000
    # a second report replaces only the generated block and keeps the text around it
    perf = _load()
    out.write_text("# Title\n\nbefore\n\n" + text[text.index(perf.BEGIN):text.index(perf.END) + len(perf.END)] + "\n\nafter\n")
    perf.write_doc(out, perf.BEGIN + "\nnew table\n" + perf.END)
    text2 = out.read_text()
    assert text2 == "# Title\n\nbefore\n\n" + perf.BEGIN + "\nnew table\n" + perf.END + "\n\nafter\n"
