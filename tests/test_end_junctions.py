"""Stage 6, ``read_end_junctions``: a junction with its twigs inside one free-end or pass region
under noise, read from the region's pruned spanning tree (:mod:`curvenet.methods.robust.endtrees`)."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.methods.robust import endtrees
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct
from curvenet.synth import realdev

from test_quality_kinds import _sampled


def test_the_branches_of_a_star_around_its_core():
    # a star: core 0, arms 1-2-3 and 4-5, a vertex 6 the tree does not reach
    adj = [{1, 4}, {0, 2}, {1, 3}, {2}, {0, 5}, {4}, set()]
    lab = endtrees.core_branches(adj, [0])
    assert lab.tolist() == [-1, 0, 0, 0, 1, 1, -2]
    X = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [0, 1], [0, 2], [9, 9]], dtype=float)
    assert endtrees._arm_path(X, adj, lab, 0) == [1, 2, 3]
    assert endtrees._arm_path(X, adj, lab, 1) == [4, 5]


def _off(topo, r, inc, near, adj, hl, noise, free_len):
    return None


def test_twigs_inside_a_free_end_region_are_read(monkeypatch):
    # the twigs kind at noise 0.2h, sampling 7: twigs of 3-6 h whose junction the shell test
    # read whole with them, as a free end or a pass of the curve they leave; 0.907 with the
    # reading, 0.805 without (0.837 and 0.732 before absorb_orphans left the samples a chain
    # passes over, 7 December 2026)
    pts, truth = _sampled("twigs", "noise 0.2h", 7)
    h = synth.h_of(truth)
    assert compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"] >= 0.90
    monkeypatch.setattr(endtrees, "_read", _off)
    assert compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"] < 0.85


def test_a_junction_on_a_chain_traced_through_it(monkeypatch):
    # sampling 3: a chain traced through the junction and on in and out of two twigs (its end
    # region the longer twig's outer samples): the junction lies on the chain; 0.884 (41 of 46
    # nodes) read there, 0.833 (39) with the junction looked for among the region's points only
    pts, truth = _sampled("twigs", "noise 0.2h", 3)
    h = synth.h_of(truth)
    assert compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"] >= 0.88
    monkeypatch.setattr(endtrees, "_core_points", lambda topo, r, inc: topo.regions[r])
    assert compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"] < 0.85


def test_a_sharp_corner_traced_round_its_apex_is_left(monkeypatch):
    # synthetic corners at noise 0.2h, sampling 5, unfitted (the fit hides a wrong branch from
    # the curve match): a pass whose chain ran round the apex, whose samples hang past the
    # tree's core like a twig; read as a junction: curve F1 1.000 -> 0.500
    pts, truth = _sampled("corners", "noise 0.2h", 5)
    h = synth.h_of(truth)
    assert compare(reconstruct(pts, method="robust", fit=False), truth, h=h)["curve_f1"] == 1.0
    monkeypatch.setattr(endtrees, "_corner", lambda trims, inc: False)
    assert compare(reconstruct(pts, method="robust", fit=False), truth, h=h)["curve_f1"] < 1.0


def test_noise_free_input_is_not_read(monkeypatch):
    # on clean input the twigs kind is exact with or without the reading (it read the ends of
    # clean twigs as junctions: 8 of 8 samplings 46 -> 44 nodes when it ran there)
    pts, truth = _sampled("twigs", "clean", 0)
    calls = []
    monkeypatch.setattr(endtrees, "_read", lambda *a: calls.append(a))
    net = reconstruct(pts, method="robust")
    assert calls == []
    assert compare(net, truth, h=synth.h_of(truth))["exact_topology"]


@pytest.mark.skipif(not realdev.available(), reason="real-dev dataset not found")
def test_a_fold_is_not_a_twig(monkeypatch):
    # real-dev neuron nrn_ri05_s591 at noise 0.1 h: its tracing runs 3 h out and straight back
    # (a spike); the spike's branch holds 1.96 times the samples per length of the curve's, a
    # fold (ENDTREES.fold): exact; read as a twig 30 nodes for 28
    name, cond = "nrn_ri05_s591", "noise 0.1h"
    truth = realdev.load(name)
    kw = {**bench.CONDITIONS, **bench.EXTRA_CONDITIONS}[cond]
    pts, _ = synth.sample(truth, rng=bench.run_seed("realdev", name, cond), **kw)
    h = synth.h_of(truth)
    assert compare(reconstruct(pts, method="robust"), truth, h=h)["exact_topology"]
    monkeypatch.setattr(endtrees, "ENDTREES", endtrees.ENDTREES._replace(fold=np.inf))
    net = reconstruct(pts, method="robust")
    assert len(net.nodes) > len(truth.nodes)
