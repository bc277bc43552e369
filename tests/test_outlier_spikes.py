"""Outliers taken into a curve are dropped from it (issue 25: 2% outliers with noise 0.1h)."""

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.methods.robust import pipeline, thresholds
from curvenet.methods.robust.curves import drop_spikes
from curvenet.metrics import compare
from curvenet.network import Curve
from curvenet.reconstruct import reconstruct


def test_drop_spikes_keeps_corners_and_ends():
    # a polyline with a 30-degree corner and one sample 3 spacings off the line
    P = np.array([[0, 0], [1, 0], [2, 0], [2.5, 3.0], [3, 0], [4, 0],
                  [4 + np.cos(np.radians(150)), np.sin(np.radians(150))]], dtype=float)
    ids = np.arange(len(P))
    h = np.ones(len(P))
    c = Curve(P[[0, 1, 2, 3, 4, 5]], 0, 1, False, ids[:6])
    out = drop_spikes([c], P, h, 0.0)[0]
    assert out.indices.tolist() == [0, 1, 2, 4, 5]
    corner = Curve(P[[3, 4, 5, 6]][1:], 0, 1, False, ids[[4, 5, 6]])  # 30-degree turn at sample 5
    assert drop_spikes([corner], P, h, 0.0)[0] is corner


@pytest.mark.parametrize("name", ["fan", "crossing"])
def test_outliers_with_noise_leave_every_curve(name, monkeypatch):
    # benchmark sampling: an outlier 2.6-2.7h off a curve was a sample of that curve (F1 0.86-0.88)
    cond = "outliers 2% + noise 0.1h"
    truth = synth.model(name)
    pts, _ = synth.sample(truth, rng=bench.run_seed(name, cond), **bench.EXTRA_CONDITIONS[cond])
    h = synth.h_of(truth)
    assert compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"] == 1.0
    # the spikes' effect, without the fit (which would pull a spike towards its curve too)
    assert compare(reconstruct(pts, method="robust", fit=False), truth, h=h)["curve_f1"] == 1.0
    monkeypatch.setattr(pipeline, "drop_spikes", lambda curves, *a: curves)
    assert compare(reconstruct(pts, method="robust", fit=False), truth, h=h)["curve_f1"] < 0.9
    assert thresholds.CURVES.spike > 1.0
