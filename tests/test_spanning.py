"""The spanning tree reading of a row of junctions (curvenet.methods.robust.spanning)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from curvenet.methods.robust.spanning import pruned_tree, split_plan
from curvenet.methods.robust.thresholds import SPANNING

#: the noise of the cases below, in spacings (the noise scale of the radii)
NOISE = 0.2


def _branching(adj) -> list[int]:
    return [v for v, a in enumerate(adj) if len(a) > 2]


def _line(a, b, step=1.0):
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = int(round(np.linalg.norm(b - a) / step)) + 1
    return np.linspace(a, b, n)


def test_pruned_tree_cuts_what_noise_hangs_off_a_curve():
    rng = np.random.default_rng(0)
    X = _line((0, 0), (30, 0))
    # a sample beside every third one, as noise puts it: leaf branches of about one spacing
    X = np.r_[X, X[::3] + [0.3, 0.9] + rng.normal(0, 0.05, (len(X[::3]), 2))]
    raw = pruned_tree(X, 0.0)
    assert len(_branching(raw)) > 5  # the tree itself branches at every such sample
    assert _branching(pruned_tree(X, SPANNING.prune + SPANNING.prune_noise * NOISE)) == []


def test_pruned_tree_keeps_a_twig_longer_than_the_cut():
    twig = SPANNING.prune + SPANNING.prune_noise * NOISE + 0.5
    X = np.r_[_line((-10, 0), (10, 0)), _line((0, 1), (0, np.ceil(twig)))]
    adj = pruned_tree(X, SPANNING.prune + SPANNING.prune_noise * NOISE)
    (v,) = _branching(adj)
    assert np.allclose(X[v], [0, 0])
    short = np.r_[_line((-10, 0), (10, 0)), _line((0, 1), (0, 2))]  # 2 h: under the cut
    assert _branching(pruned_tree(short, SPANNING.prune + SPANNING.prune_noise * NOISE)) == []


def _plan(X, region, end_points):
    ids = np.flatnonzero(region)
    ends = [(i, 1) for i in range(len(end_points))]
    return split_plan(X, cKDTree(X), np.ones(len(X)), NOISE, ids, ends, np.asarray(end_points, dtype=np.int64))


def test_split_plan_reads_a_row_of_teeth_but_not_a_crossing():
    rng = np.random.default_rng(1)
    # a comb: spine along x, teeth up at 0, 4, 8, noisy
    X = np.r_[_line((-12, 0), (20, 0)), *[_line((x, 1), (x, 12)) for x in (0, 4, 8)]]
    X = X + rng.normal(0, 0.05, X.shape)
    region = (np.abs(X[:, 1]) < 3.5) & (X[:, 0] > -3.5) & (X[:, 0] < 11.5)
    outside = np.flatnonzero(~region)
    tree = cKDTree(X[region])
    d, _ = tree.query(X[outside])
    ends = outside[d < 1.5]  # the first point of each branch outside the region
    plan = _plan(X, region, ends)
    assert plan is not None and len(plan.steps) == 2
    assert sorted(len(v) for v in plan.ends.values()) == [1, 2, 2]  # the middle tooth; the ends
    # an X crossing (and a third line through it): branch vertices close together, one junction
    Y = np.r_[_line((-12, 0), (12, 0)), _line((0, -12), (0, 12)), _line((-8, -8), (8, 8), np.sqrt(2))]
    Y = Y + rng.normal(0, 0.05, Y.shape)
    region = np.linalg.norm(Y, axis=1) < 3.5
    outside = np.flatnonzero(~region)
    d, _ = cKDTree(Y[region]).query(Y[outside])
    assert _plan(Y, region, outside[d < 1.5]) is None


def test_meet_at_one_point_tells_a_hub_from_parallel_teeth():
    from curvenet.methods.robust.paired import Lines, meet_at_one_point

    def lines(c, u, lim=0.5):
        c, u = np.asarray(c, float), np.asarray(u, float)
        u = u / np.linalg.norm(u, axis=1)[:, None]
        return Lines(c, u, c - 3 * u, np.full(len(c), lim))  # tips 3 h nearer the middle

    ang = np.radians([8, -8, 172, 188, 90])
    u = np.c_[np.cos(ang), np.sin(ang)]
    assert meet_at_one_point(lines(6 * u, u), np.zeros(2))  # five strokes aimed at the origin
    teeth = lines([[0, 6], [4, 6], [8, 6]], [[0, 1]] * 3)  # parallel, 4 h apart
    assert not meet_at_one_point(teeth, np.array([4.0, 0.0]))
