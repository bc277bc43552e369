"""The paper method's default k comes from the study of benchmarks/paper_defaults.py."""

import json
import subprocess
import sys
from pathlib import Path

from curvenet.methods.paper import DEFAULT_K

ROOT = Path(__file__).resolve().parents[1]


def test_default_k_is_the_best_of_the_stored_study():
    study = json.loads((ROOT / "docs" / "paper-defaults.json").read_text())
    for kind in ("tuned", "defaults"):
        rows = [s for s in study["summary"] if s["kind"] == kind]
        best = max(rows, key=lambda s: (s["curve_f1"], s["node_f1"]))
        assert best["k"] == DEFAULT_K, (kind, best)
    assert len({r["model"] for r in study["rows"]}) == 8 and min(r["n_points"] for r in study["rows"]) > 14_000


def test_study_script_runs(tmp_path):
    out = tmp_path / "study.json"
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "paper_defaults.py"), "--quick", "--out", str(out)],
                       capture_output=True, text=True, timeout=600, cwd=ROOT,
                       env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr
    data = json.loads(out.read_text())
    assert {s["k"] for s in data["summary"]} == {6, 8, 10} and "curve F1" in r.stdout
