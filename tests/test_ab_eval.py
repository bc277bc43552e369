"""The A/B harness of the default method runs (its quick form) and compares, so it cannot rot."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from bench_scripts import BENCH, has, load

pytestmark = pytest.mark.skipif(not has("ab_eval"), reason="benchmarks/ not in this checkout")


@pytest.fixture(scope="module")
def ab_eval():
    return load("ab_eval")


def test_quick_run_and_compare(tmp_path, ab_eval):
    out = tmp_path / "a.json"
    subprocess.run([sys.executable, str(BENCH / "ab_eval.py"), "run", str(out), "--quick", "--jobs", "1"],
                   check=True, capture_output=True, text=True, cwd=BENCH)
    rows = json.loads(out.read_text())
    assert [(r["set"], r["model"], r["condition"], r["seed"]) for r in rows] == [
        ("kinds", "ladder", "noise 0.2h", 0), ("kinds", "tangent", "noise 0.2h", 0)]
    assert all(0.0 <= r["curve_f1"] <= 1.0 and r["true_nodes"] > 0 for r in rows)
    same = ab_eval.compare(rows, rows)
    assert not any(line.lstrip().startswith(("better", "worse")) for line in same)
    assert "better 0 worse 0" in same[-1]
    lower = [dict(r, curve_f1=r["curve_f1"] - 0.25) if r["model"] == "tangent" else r for r in rows]
    moved = ab_eval.compare(rows, lower, per_kind=True)
    assert sum(line.lstrip().startswith("worse") for line in moved) == 1
    assert any("better 0 worse 1" in line for line in moved)
    assert any(line.startswith("kind tangent") for line in moved)


def test_tasks_count(ab_eval):
    from curvenet import bench, synth
    from curvenet.synth import kinds

    main = [t for t in ab_eval.tasks(["main"]) if t[0] != "realdev"]
    assert len(main) == len(bench.CONDITIONS) * ab_eval.MAIN_SAMPLINGS * (len(kinds.KIND_MODELS) + len(synth.MODELS))
