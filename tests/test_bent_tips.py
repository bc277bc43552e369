"""Free ends whose region bends (curvenet.methods.robust.nodes.bent_tips)."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.methods.robust import nodes
from curvenet.methods.robust.params import RobustParams
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct

PRM = RobustParams()


def _free_end(region, noise=0.0):
    """A chain along x ending at (-1, 0), h = 1, and a free end's region ``region`` (m, 2)
    after it: the straight-ahead node (``free_end``) and what ``bent_tips`` makes of it."""
    chain = np.c_[np.arange(-10.0, 0.0), np.zeros(10)]
    P = np.r_[chain, np.asarray(region, dtype=float)]
    h = np.ones(len(P))
    ids = np.arange(len(chain))
    rid = np.arange(len(chain), len(P))
    ext, pos = nodes.free_end(P, h, ids, rid)
    (tip,) = nodes.bent_tips(P, h, PRM.link, noise, PRM.shell_outer, [(ids[-1], rid, pos, ext)])
    return P, pos, tip


def _turn(angle, n=4):
    """Three samples on along x, then ``n`` more turning by ``angle`` degrees at (2, 0)."""
    u = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    return np.r_[[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], [2.0, 0.0] + np.outer(np.arange(1, n + 1), u)]


def test_a_tail_after_a_turn_gets_the_node():
    P, pos, tip = _free_end(_turn(120.0))
    assert np.allclose(pos, [2.0, 0.0])  # straight ahead: the turn
    assert tip is not None
    ext, node = tip
    assert np.allclose(node, _turn(120.0)[-1])  # the tail's end, 4 h from the turn
    assert np.allclose(P[ext], _turn(120.0))  # every region point, in order along the region


def test_a_straight_or_gently_bending_end_stays():
    assert _free_end(_turn(0.0))[2] is None
    assert _free_end(_turn(20.0))[2] is None  # the tip moves under NODES.bend


def test_a_lone_sample_beyond_the_turn_is_no_tail():
    # samples along x to (2, 0), then one 2.2 h off the line (an outlier, 2.4 h from the tip
    # ahead, within a step of the line): under one sample per NODES.bend_step h of the move
    region = np.r_[[[-0.5, 0.0], [0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.5, 0.0], [2.0, 0.0]], [[1.0, 2.2]]]
    assert _free_end(region)[2] is None


def test_a_fork_in_the_region_is_left_to_the_fork_test():
    # two tails from the turn, up and down: a point of one lies far off the path to the other
    region = np.r_[_turn(120.0), _turn(-120.0)[3:]]
    assert _free_end(region)[2] is None


@pytest.mark.parametrize("offset", [2, 7])
def test_the_neurites_kind_under_noise_gains(monkeypatch, offset):
    """Traced neurites zigzag up to their tips: under noise 0.2h a tip 4 h past a turn was
    placed at the turn (curve F1 0.60 / 0.53 at these samplings, 0.80 / 0.60 with the bent
    tip)."""
    truth = synth.model("neurites")
    pts, _ = synth.sample(truth, rng=bench.run_seed("kinds", "neurites", "n0.2") + offset, noise=0.2)
    h = synth.h_of(truth)
    got = compare(reconstruct(pts, method="robust"), truth, h=h)
    monkeypatch.setattr(nodes, "bent_tips", lambda *a: [None] * len(a[-1]))
    without = compare(reconstruct(pts, method="robust"), truth, h=h)
    assert got["curve_f1"] >= without["curve_f1"] + 0.05, (got["curve_f1"], without["curve_f1"])
    assert got["n_nodes_found"] == without["n_nodes_found"]  # the same nodes, placed better
