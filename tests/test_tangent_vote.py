"""The tangent vote of stage 2 (`frames.vote_tangents`): a tangent its own nearest samples
confirm stays against a vote of farther neighbours."""

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.metrics import compare
from curvenet.methods.robust import branched
from curvenet.methods.robust import frames as RF
from curvenet.methods.robust import thresholds as TH
from curvenet.neighbors import knn
from curvenet.reconstruct import reconstruct


def _short_edge_between_faces():
    """A short edge (5 samples along z) between two dense parallel lines (along x, 2.5 apart
    above and below its ends): the edge's 16 nearest neighbours are mostly the lines'."""
    x = np.arange(-10.0, 10.5, 1.0)
    low = np.column_stack([x, np.zeros_like(x), np.full_like(x, -2.5)])
    high = np.column_stack([x, np.zeros_like(x), np.full_like(x, 2.5)])
    z = np.arange(-1.5, 1.6, 1.0)
    edge = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
    P = np.vstack([low, high, edge])
    _, idx = knn(P, 16)
    t = np.tile([1.0, 0.0, 0.0], (len(P), 1))
    t[-len(z):] = [0.0, 0.0, 1.0]  # each point's own tangent: the lines along x, the edge along z
    return P, idx, t, len(z)


def test_a_tangent_its_nearest_samples_confirm_stays():
    P, idx, t, m = _short_edge_between_faces()
    lin = np.ones(len(P))
    voted, _ = RF.vote_tangents(t, lin, idx, m=16)
    kept, _ = RF.vote_tangents(t, lin, idx, m=16, P=P)
    # without the points the lines' neighbours outvote the edge: its tangents turn along x
    assert np.abs(voted[-m:, 0]).min() > 0.9
    # with them the edge keeps its own direction, the lines theirs
    assert np.allclose(kept[-m:], t[-m:]) and np.allclose(kept[:-m], t[:-m])


def test_a_tangent_across_its_samples_is_still_voted():
    # a point whose tangent points across its curve (its two nearest samples lie along x, not
    # along its tangent) is outvoted as before
    P, idx, t, m = _short_edge_between_faces()
    t = t.copy()
    t[5] = [0.0, 0.0, 1.0]  # a point of the lower line, thrown across
    kept, _ = RF.vote_tangents(t, np.ones(len(P)), idx, m=16, P=P)
    assert abs(kept[5, 0]) > 0.99


def test_the_plate_s_short_edges_keep_their_links(monkeypatch):
    # the plate kind under noise 0.2 h, benchmark sampling 5: its edges 6 h long between the two
    # faces were voted onto the faces' direction, lost their links, and four tangent T junctions
    # with them (curve F1 0.72); with the rule the network is exact
    truth = synth.model("plate")
    kw = bench.CONDITIONS["noise 0.2h"]
    pts, _ = synth.sample(truth, rng=bench.run_seed("plate", "noise 0.2h") + 5, **kw)
    h = synth.h_of(truth)
    with_rule = compare(reconstruct(pts), truth, h=h)
    assert with_rule["exact_topology"] and with_rule["curve_f1"] == pytest.approx(1.0)
    off = TH.TANGENTS._replace(vote_keep_cos=1.0 + TH.NUMERIC.rel)  # no neighbour lies within it
    monkeypatch.setattr(RF, "TANGENTS", off)
    # (measured alone: branched.orphan_twigs mends one of the lost junctions, 0.72 -> 0.87)
    monkeypatch.setattr(branched, "orphan_twigs", lambda *a: set())
    without = compare(reconstruct(pts), truth, h=h)
    assert without["curve_f1"] < with_rule["curve_f1"] - 0.2
