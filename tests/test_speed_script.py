"""benchmarks/speed.py (issue 22's targets) runs on a tiny size, so it cannot rot; its clouds
are what it says. No timing assertions."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "speed.py"
pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="benchmarks/speed.py not in this checkout")


def test_noisy_cloud_is_noisier_and_uneven():
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import speed
    finally:
        sys.path.pop(0)
    from curvenet.methods.robust import estimate

    clean = speed.make_points(3000, **speed.CONDITIONS["clean"])
    noisy = speed.make_points(3000, **speed.CONDITIONS["noisy"])
    assert len(clean) >= 3000 and len(noisy) >= 3000
    assert np.array_equal(clean, speed.make_points(3000, **speed.CONDITIONS["clean"]))  # deterministic
    assert estimate(noisy).sigma > 5 * estimate(clean).sigma


def test_quick_run_prints_every_condition_and_the_verdicts():
    r = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--stages"], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    out = r.stdout
    for cond in ("clean", "noisy"):
        assert f"{cond}:" in out and "x the query" in out
    assert "failed" not in out
    assert "neighbors" in out and "assemble" in out  # the per-stage lines
