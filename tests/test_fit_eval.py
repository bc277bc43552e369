"""benchmarks/fit_eval.py runs on its CI size (two models, noise 0.3 h) and says what it measures."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "fit_eval.py"

pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="benchmarks/fit_eval.py not in this checkout")


def _load():
    spec = importlib.util.spec_from_file_location("curvenet_fit_eval", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["curvenet_fit_eval"] = mod
    spec.loader.exec_module(mod)
    return mod


def test_quick_run_fits_and_keeps_the_topology(capsys):
    fe = _load()
    rows = fe.measure(["crossing", "knot"], ["noise 0.3h"])
    assert [r["model"] for r in rows] == ["crossing", "knot"]
    for r in rows:
        assert r["fitted"] and r["same_topology"]
        # the fit takes 40% or more off the mean distance to the true curves on these two models
        assert r["mean_after"] < 0.6 * r["mean_before"]
        assert r["mean_after"] <= 0.5 * r["noise"]  # the target: half the noise's std
    table = fe.summary(rows)
    assert table[0].startswith("| Condition |") and "| noise 0.3h | 2 |" in table[2]
    assert fe.main(["--quick"]) == 0
    assert "topology same" in capsys.readouterr().out
