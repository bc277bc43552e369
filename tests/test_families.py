"""The families of real-like networks drawn at random (curvenet.synth.families)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from curvenet import synth
from curvenet.metrics import densify
from curvenet.synth import families


def test_a_member_is_the_same_every_time_and_named():
    a, b = families.member("grid", 4), families.member("grid", 4)
    assert np.array_equal(a.nodes, b.nodes) and a.n_curves == b.n_curves
    assert a.parameters["model"] == "grid#4"
    assert not np.array_equal(a.nodes, families.member("grid", 5).nodes) or a.n_curves != families.member("grid", 5).n_curves


def test_an_unknown_family_is_refused():
    with pytest.raises(KeyError, match="unknown family"):
        families.member("castle", 0)


@pytest.mark.parametrize("family", list(families.FAMILIES))
def test_members_are_well_posed(family):
    # as the docstring says: curves at least 4h long, curves sharing no node at least 4h apart
    for k in range(3):
        net = families.member(family, k)
        h = synth.h_of(net)
        pts, owner = [], []
        for i, c in enumerate(net.curves):
            assert np.linalg.norm(np.diff(c.points, axis=0), axis=1).sum() >= 4 * h * (1 - 1e-9)
            q = densify(c.points, h / 2)
            pts.append(q)
            owner.append(np.full(len(q), i))
        P, own = np.concatenate(pts), np.concatenate(owner)
        ends = [{c.start, c.end} for c in net.curves]
        pairs = cKDTree(P).query_pairs(4 * h * (1 - 1e-6), output_type="ndarray")
        a, b = own[pairs[:, 0]], own[pairs[:, 1]]
        apart = [(i, j) for i, j in set(zip(a.tolist(), b.tolist())) if i != j and not ends[i] & ends[j]]
        assert not apart, (family, k, apart[:3])
