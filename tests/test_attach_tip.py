"""Stage 6, ``attach_dangling``: on noise-free input a free end's tip is the far end of an end
region that reaches over a link past its chain (:func:`curvenet.methods.robust.repairs._tip_path`)."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.methods.robust import repairs
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct
from curvenet.synth import cassie


def test_the_path_goes_on_through_a_long_end_region():
    P = np.array([[float(x), 0.0] for x in range(10)])  # a chain 0-5, its end region 6-9
    h = np.ones(len(P))
    ids = np.arange(6)
    region = np.array([9, 7, 8, 6])
    assert repairs._tip_path(P, h, 2.5, ids, region).tolist() == list(range(10))
    assert repairs._tip_path(P, h, 5.0, ids, region).tolist() == list(range(6))  # within reach
    assert repairs._tip_path(P, h, None, ids, region).tolist() == list(range(6))  # under noise


@pytest.mark.skipif(not cassie.available(), reason="the CASSIE dataset is not here")
def test_a_sketched_stroke_stopping_short_attaches(monkeypatch):
    # CASSIE study sketch 09-2-1 sampled at 2 mm: strokes whose last samples, over several
    # spacings, were flagged as their end region, the curve they stop at over 45 degrees off
    # the direction of the chain's last samples: curve F1 0.879 (0.836 read from the chain end)
    name = "09-2-1"
    truth = cassie.load(name)
    pts, _ = synth.sample(truth, h=0.002, rng=bench.run_seed("cassie", name, "clean"))
    assert compare(reconstruct(pts, method="robust"), truth, h=0.002)["curve_f1"] >= 0.87
    monkeypatch.setattr(repairs, "_tip_reach", lambda sc, prm: None)
    assert compare(reconstruct(pts, method="robust"), truth, h=0.002)["curve_f1"] < 0.85
