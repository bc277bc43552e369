"""Junction nodes off the samples moved to the region's median point
(curvenet.methods.robust.nodes.median_points)."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.methods.robust import nodes
from curvenet.methods.robust.params import RobustParams
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct

PRM = RobustParams()


def _y_region(zigzag):
    """A Y of samples (h = 1) meeting at the origin: arms along -x, and at +-60 degrees, each
    5 samples; the third arm runs on through ``zigzag`` (m, 2) samples. Chain ends: each arm's
    last sample. Returns the points, the chain ends and the region's points."""
    arms = [np.array([-1.0, 0.0]), np.array([0.5, np.sqrt(3) / 2]), np.array([0.5, -np.sqrt(3) / 2])]
    pts = [np.zeros((1, 2))] + [np.outer(np.arange(1, 6), u) for u in arms]
    pts.append(np.asarray(zigzag, dtype=float).reshape(-1, 2))
    P = np.concatenate(pts)
    ends = [5, 10, len(P) - 1 if len(zigzag) else 15]
    rid = np.array([i for i in range(len(P)) if i not in ends], dtype=np.int64)
    return P, ends, rid


def test_the_median_of_a_y_is_where_its_arms_meet():
    P, ends, rid = _y_region(np.zeros((0, 2)))
    (q,) = nodes.median_points(P, np.ones(len(P)), PRM.link, [(ends, rid)])
    assert q == 0


def test_a_zigzag_on_one_arm_does_not_move_the_median():
    # the third arm turns back and forth for 8 more samples (the region runs 10 h out)
    tip = np.array([0.5, -np.sqrt(3) / 2]) * 5
    zig = tip + np.c_[np.arange(1.0, 9.0), 0.8 * (np.arange(1, 9) % 2)]
    P, ends, rid = _y_region(zig)
    (q,) = nodes.median_points(P, np.ones(len(P)), PRM.link, [(ends, rid)])
    assert q == 0
    # its centroid, and the meeting point of lines fitted to the arms' far ends, lie elsewhere
    assert np.linalg.norm(P[rid].mean(axis=0)) > 2.0


def test_a_region_in_two_pieces_gives_none():
    # two Ys 50 h apart, read as one region: no point is reached from every chain end
    P, ends, rid = _y_region(np.zeros((0, 2)))
    n = len(P)
    P = np.r_[P, P + 50.0]
    (q,) = nodes.median_points(P, np.ones(len(P)), PRM.link, [(ends + [e + n for e in ends], np.r_[rid, rid + n])])
    assert q is None


@pytest.mark.parametrize("offset", [2, 4])
def test_the_neurites_kind_under_noise_gains(monkeypatch, offset):
    """At noise 0.1 h the neurites' zigzags next to junctions are flagged with them, and the
    branches' lines met 4 h off the samples (curve F1 0.60 / 0.56 at these samplings, 0.93 /
    0.80 with the median point)."""
    truth = synth.model("neurites")
    pts, _ = synth.sample(truth, rng=bench.run_seed("kinds", "neurites", "n0.1") + offset, noise=0.1)
    h = synth.h_of(truth)
    got = compare(reconstruct(pts, method="robust"), truth, h=h)
    monkeypatch.setattr(nodes, "median_points", lambda P, h, link, items: [None] * len(items))
    without = compare(reconstruct(pts, method="robust"), truth, h=h)
    assert got["curve_f1"] >= without["curve_f1"] + 0.1, (got["curve_f1"], without["curve_f1"])
    assert got["node_f1"] > without["node_f1"]  # nodes 4 h off are found


def test_under_noise_a_small_region_moves_too(monkeypatch):
    """The ladder kind at noise 0.1 h, sampling 2: a region of 4 points whose branches' lines
    met 3.9 h from the junction, off the samples (its median point 0.1 h from it); no chain end
    lies beyond the shell radius, so the move is the noisy input's alone (curve F1 0.90 with
    the shell condition, 1.00 without)."""
    truth = synth.model("ladder")
    pts, _ = synth.sample(truth, rng=bench.run_seed("kinds", "ladder", "n0.1") + 2, noise=0.1)
    h = synth.h_of(truth)
    got = compare(reconstruct(pts, method="robust"), truth, h=h)
    monkeypatch.setattr(nodes, "median_points", lambda P, h, link, items: [None] * len(items))
    without = compare(reconstruct(pts, method="robust"), truth, h=h)
    assert got["curve_f1"] >= without["curve_f1"] + 0.05, (got["curve_f1"], without["curve_f1"])
