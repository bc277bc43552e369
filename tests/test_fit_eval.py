"""benchmarks/fit_eval.py runs on its CI size (two models, noise 0.3 h) and says what it measures."""

from __future__ import annotations

from pathlib import Path

import pytest
from bench_scripts import load

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "fit_eval.py"

pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="benchmarks/fit_eval.py not in this checkout")


def _load():
    return load("fit_eval")


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


def test_samplings_are_averaged_per_model_and_the_worst_is_kept():
    fe = _load()

    def row(model, k, after):
        return dict(model=model, condition="noise 0.2h", sampling=k, noise=0.2, mean_before=0.2,
                    max_before=0.7, mean_after=after, max_after=0.4)

    rows = [row("a", 0, 0.08), row("a", 1, 0.12), row("b", 0, 0.06), row("b", 1, 0.06)]
    pm = fe.per_model(rows)
    assert [(r["model"], r["samplings"]) for r in pm] == [("a", 2), ("b", 2)]
    assert pm[0]["mean_after"] == pytest.approx(0.10) and pm[0]["worst_after"] == pytest.approx(0.12)
    # model a's mean (0.10 h) is at the target (half of 0.2 h), not over it; the worst model is a
    table = fe.summary(rows)
    assert "| noise 0.2h | 2 | 0.200 | 0.080 | 0.10 | 0 | 0.100 (a) |" in table[2]
    # in noise standard deviations: a 0.50 / 0.60, b 0.30 / 0.30
    spread = fe.spread(rows)
    assert spread[2] == "| a | 0.50 / 0.60 |" and spread[3] == "| b | 0.30 / 0.30 |"
