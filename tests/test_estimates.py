"""Whole-cloud estimates handed to the default method (the hook of tiled reconstruction)."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import synth
from curvenet.methods.robust import Estimates, estimate, reconstruct_robust
from curvenet.methods.robust.thresholds import SPACING


def _same(a, b):
    assert np.array_equal(a.nodes, b.nodes)
    assert len(a.curves) == len(b.curves)
    for x, y in zip(a.curves, b.curves):
        assert np.array_equal(x.points, y.points) and (x.start, x.end) == (y.start, y.end)
        assert np.array_equal(x.indices, y.indices)


@pytest.mark.parametrize("noise", [0.0, 0.2])
def test_the_cloud_own_estimates_change_nothing(noise):
    pts, _ = synth.sample(synth.model("crossing"), noise=noise, rng=2)
    est = estimate(pts)
    net = reconstruct_robust(pts)
    assert est.hmed == net.parameters["spacing"] and est.sigma == net.parameters["noise"]
    assert est.clean == (noise == 0.0)
    _same(reconstruct_robust(pts, estimates=est), net)


def test_a_tile_takes_the_whole_cloud_decisions():
    # a clean cloud told it is part of a noisy whole decides as the noisy whole: the noise
    # reported and the gates (no duplicate rule, strand test) are the given ones
    pts, _ = synth.sample(synth.model("crossing"), rng=2)
    own = reconstruct_robust(pts)
    hmed = own.parameters["spacing"]
    noisy = Estimates(hmed=hmed, sigma=0.5 * hmed)
    assert not noisy.clean and Estimates(hmed=hmed, sigma=0.0).clean
    net = reconstruct_robust(pts, estimates=noisy)
    assert net.parameters["noise"] == noisy.sigma and net.parameters["estimates_given"]
    assert net.parameters["spacing"] == hmed
    # a wider noise scale widens the shell: the shell groups differ from the clean run's
    assert net.parameters["groups_histogram"] != own.parameters["groups_histogram"]


def test_the_duplicate_rule_follows_the_estimates():
    # a curve given twice (noise-free): dropped with the cloud's own (clean) estimates, kept
    # when the whole is noisy (close samples are noise there)
    t = np.linspace(0, 10, 101)[:, None]
    P = np.hstack([t, np.zeros_like(t)])
    P2 = np.vstack([P, P + [0.0, 1e-4]])
    est = estimate(P2)
    assert est.clean
    assert reconstruct_robust(P2, estimates=est).parameters["duplicates_dropped"] == 101
    noisy = Estimates(hmed=est.hmed, sigma=SPACING.dedup_noise * est.hmed * 4)
    assert reconstruct_robust(P2, estimates=noisy).parameters["duplicates_dropped"] == 0


@pytest.mark.parametrize("noise", [0.0, 0.2])
def test_point_estimates_take_the_query_distances_bit_for_bit(noise):
    # point_estimates keeps the k-d tree query's distances instead of recomputing them from
    # the neighbour ids (Neighbours.distances): the same bits, so the same medians and reaches
    from curvenet.methods.robust import point_estimates
    from curvenet.methods.robust.frames import neighbours, neighbours_and_distances
    from curvenet.methods.robust.params import RobustParams

    pts, _ = synth.sample(synth.model("torus"), noise=noise, rng=3)
    prm = RobustParams.from_keywords()
    nb, dist = neighbours_and_distances(pts, prm)
    again = neighbours(pts, prm)
    assert np.array_equal(dist, again.distances())
    assert np.array_equal(nb.idx, again.idx) and np.array_equal(nb.h, again.h)
    v = point_estimates(pts)
    P = pts[v.order]
    nb2 = neighbours(P, prm)
    d2 = nb2.distances()
    assert np.array_equal(v.reach, d2[:, -1])
    rows = np.arange(len(P))[:, None]
    assert np.array_equal(v.earlier, np.where(nb2.idx < rows, d2, np.inf).min(axis=1))
