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


def test_meet_at_one_point_each_equals_the_test_one_region_at_a_time():
    from curvenet.methods.robust.paired import Lines, meet_at_one_point, meet_at_one_point_each

    rng = np.random.default_rng(3)
    parts, anchors, off = [], [], [0]
    for j in range(40):  # regions of 3 to 6 branches: half aimed at one point, half scattered
        m = int(rng.integers(3, 7))
        ang = rng.uniform(0, 2 * np.pi, m)
        u = np.c_[np.cos(ang), np.sin(ang)]
        c = 6 * u + (0 if j % 2 else rng.normal(0, 2.0, (m, 2)))
        parts.append(Lines(c, u, c - 3 * u, np.full(m, 0.5)))
        anchors.append(rng.normal(0, 0.5, 2))
        off.append(off[-1] + m)
    L = Lines(*(np.concatenate([getattr(p, f) for p in parts]) for f in Lines._fields))
    got = meet_at_one_point_each(L, np.array(off), np.array(anchors))
    want = [meet_at_one_point(p, a) for p, a in zip(parts, anchors)]
    assert got.tolist() == want and 0 < sum(want) < len(want)


def test_straight_across_tells_an_x_from_a_comb_s_pair():
    from curvenet.methods.robust.paired import Lines
    from curvenet.methods.robust.spanning import Plan, _straight_across

    def case(angles, owner, through=None):  # branches leaving junctions at (0, 0) and (3, 0)
        ang = np.radians(angles)
        u = np.c_[np.cos(ang), np.sin(ang)]
        at = np.array([[0.0, 0.0], [3.0, 0.0]])[owner] if through is None else np.asarray(through)
        tip = at + 2.5 * u
        ends = [(i, 1) for i in range(len(angles))]
        plan = Plan({k: [e for e, o in zip(ends, owner) if o == k] for k in (0, 1)}, [],
                    {0: np.zeros(2), 1: np.array([3.0, 0.0])})
        return _straight_across(Lines(tip + 4 * u, u, tip, np.full(len(angles), 0.5)), ends, plan)

    # a comb's pair: the spine through both junctions, two parallel teeth: two junctions
    assert not case([180.0, 90.0, 90.0, 0.0], [0, 0, 1, 1])
    # the same with the teeth 45 degrees apart: strokes crossing one curve loosely
    assert case([180.0, 90.0, 45.0, 0.0], [0, 0, 1, 1])
    # an X crossing at (1.5, 0) read as two V's (the tree branches on either side of it): each
    # curve has a half at each junction and crosses the segment at 30 degrees
    assert case([150.0, 210.0, 30.0, 330.0], [0, 0, 1, 1], through=[1.5, 0.0])


def test_straight_across_reads_skew_teeth_as_two_junctions():
    # a spine along x through junctions at (0, 0, 0) and (3, 0, 0), a tooth at each, 30 degrees
    # apart: in the spine's plane, both teeth's lines meet (strokes drawn loosely into one point
    # of the curve: one junction); one tooth tilted out of that plane instead, the lines pass
    # 3 h apart (a 3D comb's teeth, the kinds' comb at noise 0.1 h sampling 3): two junctions
    from curvenet.methods.robust.paired import Lines
    from curvenet.methods.robust.spanning import Plan, _straight_across

    def case(u_second):
        u = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], u_second, [1.0, 0.0, 0.0]])
        u /= np.linalg.norm(u, axis=1)[:, None]
        at = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
        tip = at + 2.5 * u
        ends = [(i, 1) for i in range(4)]
        plan = Plan({0: ends[:2], 1: ends[2:]}, [], {0: np.zeros(3), 1: np.array([3.0, 0.0, 0.0])})
        return _straight_across(Lines(tip + 4 * u, u, tip, np.full(4, 0.5)), ends, plan)

    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    assert case([-s, c, 0.0])  # in the plane, leaning back to the first tooth: their lines meet
    assert not case([0.0, c, s])  # tilted out of the plane: skew lines, two junctions


def test_branches_apart_tells_converging_curves_from_a_junction_s_branches():
    from curvenet.methods.robust.paired import Lines
    from curvenet.methods.robust.spanning import Plan, _branches_apart

    def case(a0, a1):  # core 0: branches at angles a0, a1 (degrees); core 1: up and right
        ang = np.radians([a0, a1, 90.0, 0.0])
        u = np.c_[np.cos(ang), np.sin(ang)]
        tip = np.array([[0, 0], [0, 0], [4, 0], [4, 0]], dtype=float) + 2 * u
        ends = [(i, 1) for i in range(4)]
        plan = Plan({0: ends[:2], 1: ends[2:]}, [], {0: np.zeros(2), 1: np.array([4.0, 0.0])})
        return _branches_apart(Lines(tip + 4 * u, -u, tip, np.ones(4)), ends, plan)  # u unoriented

    assert case(180.0, 90.0)  # a junction's branches: left and up
    assert not case(180.0, 172.0)  # two curves converging 8 degrees apart (an eye's arcs)
    assert case(180.0, 180.0 - np.degrees(np.arccos(SPANNING.arm_cos)) - 1)


def test_clusters_number_as_connected_components():
    """The branch vertices' clusters: pairs at most r apart joined, numbered in the order of
    each cluster's first point, as scipy's connected components of the k-d tree's pairs (the
    code this replaced); pairs exactly r apart (integer grids) included."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from curvenet.methods.robust.spanning import _clusters

    rng = np.random.default_rng(3)
    for t in range(400):
        m, d = int(rng.integers(1, 25)), int(rng.integers(2, 4))
        Y = rng.uniform(0, 6, size=(m, d)) if t % 2 else np.round(rng.uniform(0, 6, size=(m, d)))
        r = float(rng.choice([1.0, 1.5, 2.0])) + (0.0 if t % 3 else float(rng.uniform(0, 1)))
        pairs = cKDTree(Y).query_pairs(r, output_type="ndarray")
        g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
        _, lab = connected_components(g, directed=False)
        np.testing.assert_array_equal(_clusters(Y, r), lab)


def test_pruned_trees_of_many_sets_equal_each_alone():
    from curvenet.methods.robust.spanning import pruned_trees

    rng = np.random.default_rng(2)
    sets, cuts, keeps = [], [], []
    for n in (12, 40, 90):
        X = _line((0, 0), (n / 2, 0))
        X = np.r_[X, X[::3] + [0.3, 0.9] + rng.normal(0, 0.05, (len(X[::3]), 2)), _line((4, -1), (4, -6))]
        sets.append(X)
        cuts.append(SPANNING.prune + SPANNING.prune_noise * NOISE)
        keeps.append(None if n == 40 else rng.random(len(X)) < 0.1)
    for X, cut, keep, adj in zip(sets, cuts, keeps, pruned_trees(sets, cuts, keeps)):
        assert adj == pruned_tree(X, cut, keep)
        assert any(len(a) > 2 for a in adj)  # the twig at x = 4 (5 spacings, over the cut) stays


def test_split_plan_merges_two_cores_closer_than_sep_and_keeps_the_row():
    # a comb whose last two teeth stand 2 h apart (under SPANNING.sep): that pair is read as one
    # junction of valence 4, the rest of the row still splits (the whole row was left as one
    # node of valence 6 when any two cores came that close)
    rng = np.random.default_rng(2)
    teeth = (0, 4, 8, 10)
    assert 10 - 8 < SPANNING.sep
    X = np.r_[_line((-12, 0), (22, 0)), *[_line((x, 1), (x, 12)) for x in teeth]]
    X = X + rng.normal(0, 0.05, X.shape)
    region = (np.abs(X[:, 1]) < 3.5) & (X[:, 0] > -3.5) & (X[:, 0] < 13.5)
    outside = np.flatnonzero(~region)
    d, _ = cKDTree(X[region]).query(X[outside])
    plan = _plan(X, region, outside[d < 1.5])
    assert plan is not None and len(plan.steps) == 2
    assert sorted(len(v) for v in plan.ends.values()) == [1, 2, 3]  # middle tooth; left end; the pair and the spine's end
    centres = np.array(list(plan.centres.values()))
    gaps = np.linalg.norm(centres[:, None] - centres[None], axis=2)[np.triu_indices(3, 1)]
    assert gaps.min() >= SPANNING.sep


def test_split_plan_parts_junctions_closer_than_two_core_radii():
    """Teeth 3 h apart: the spine's two samples between two junctions each lie within the
    core radius (``SPANNING.core_share`` of 3 h) of one of them; the new chain between them
    is then the path's sample farthest from both (the row was left whole: the ladder kind's rails under noise
    0.2h, two nodes of valence 12)."""
    rng = np.random.default_rng(2)
    X = np.r_[_line((-12, 0), (18, 0)), *[_line((x, 1), (x, 12)) for x in (0, 3, 6)]]
    X = X + rng.normal(0, 0.05, X.shape)
    region = (np.abs(X[:, 1]) < 3.5) & (X[:, 0] > -3.5) & (X[:, 0] < 9.5)
    outside = np.flatnonzero(~region)
    d, _ = cKDTree(X[region]).query(X[outside])
    plan = _plan(X, region, outside[d < 1.5])
    assert plan is not None and len(plan.steps) == 2
    for _, _, _, seg in plan.steps:  # spine samples between the junctions, 1-2 h from both
        assert len(seg) and np.all(np.abs(X[seg, 1]) < 0.5)
        assert all(min(abs(x - t) for t in (0, 3, 6)) > 0.5 for x in X[seg, 0])
    assert sorted(len(v) for v in plan.ends.values()) == [1, 2, 2]


def _cells(xs, ys, reach, rng, noise=0.05):
    """A lattice of straight curves along x = xs and y = ys, each running ``reach`` spacings
    past the outer ones, sampled every spacing, with Gaussian noise."""
    X = np.r_[*[_line((x, ys[0] - reach), (x, ys[-1] + reach)) for x in xs],
              *[_line((xs[0] - reach, y), (xs[-1] + reach, y)) for y in ys]]
    X = np.unique(np.round(X, 9), axis=0)
    return X + rng.normal(0, noise, X.shape)


def test_loop_closures_give_a_cell_its_lost_side_back():
    """A block of 2 x 2 cells 4 h wide: the spanning tree drops one edge of every cell, the
    pruning then cuts the two halves of that side and its corners lose a branch; with the gaps
    closed every one of the 9 junctions shows a vertex of three or more branches."""
    from curvenet.methods.robust.spanning import loop_closures, pruned_trees

    rng = np.random.default_rng(3)
    X = _cells((0, 4, 8), (0, 4, 8), 6, rng)
    cut = SPANNING.prune + SPANNING.prune_noise * NOISE
    junctions = np.array([(x, y) for x in (0, 4, 8) for y in (0, 4, 8)], dtype=float)

    def seen(adj):
        v = _branching(adj)
        return int(np.sum(cKDTree(X[v]).query(junctions)[0] <= 1.0)) if v else 0

    assert seen(pruned_tree(X, cut)) < 9
    (adj,) = pruned_trees([X], [cut], [None], closes=[(1.0, NOISE)])
    assert seen(adj) == 9
    edges = np.array([(a, b) for a in range(len(adj)) for b in adj[a] if a < b])
    from curvenet.methods.emst import emst_edges

    closed = loop_closures(X, emst_edges(X), 1.0, NOISE)
    assert len(closed) == 4  # one per cell
    assert len(edges) == len(X) - 1 + 4 - sum(1 for a in adj if not a)  # the tree, pruned, and the 4


def test_loop_closures_leave_branches_at_a_small_angle_and_noise_alone():
    """Two branches leaving a junction 20 degrees apart come within the closing reach of each
    other some spacings out, but their points are not the tree's leaves; the samples noise
    hangs beside a curve are leaves whose path back is short: nothing is closed."""
    from curvenet.methods.emst import emst_edges
    from curvenet.methods.robust.spanning import loop_closures

    rng = np.random.default_rng(4)
    a = np.radians(10.0)
    X = np.r_[_line((-15, 0), (0, 0)), _line((1, 0), (15 * np.cos(a), 15 * np.sin(a)))[0:],
              _line((np.cos(a), -np.sin(a)), (15 * np.cos(a), -15 * np.sin(a)))]
    X = np.r_[X, X[::4] + [0.2, 0.8]]
    X = X + rng.normal(0, 0.05, X.shape)
    assert len(loop_closures(X, emst_edges(X), 1.0, NOISE)) == 0


def test_split_plan_reads_a_block_of_cells_with_its_cycles():
    """The 9 junctions of a block of 2 x 2 cells 4 h wide in one region (the shell widened for
    noise covers it): 9 junctions, the 4 cells' sides that the tree lost made chains between
    split junctions (Plan.joins); the tree alone showed too few for a split."""
    rng = np.random.default_rng(3)
    X = _cells((0, 4, 8), (0, 4, 8), 8, rng)
    region = (X[:, 0] > -3.5) & (X[:, 0] < 11.5) & (X[:, 1] > -3.5) & (X[:, 1] < 11.5)
    outside = np.flatnonzero(~region)
    d, _ = cKDTree(X[region]).query(X[outside])
    plan = _plan(X, region, outside[d < 1.5])
    assert plan is not None and len(plan.ends) == 9
    assert len(plan.steps) == 8 and len(plan.joins) == 4
    centres = np.array(list(plan.centres.values()))
    junctions = np.array([(x, y) for x in (0, 4, 8) for y in (0, 4, 8)], dtype=float)
    assert np.all(cKDTree(centres).query(junctions)[0] <= 1.0)
    segs = [seg for *_, seg in plan.steps] + [seg for *_, seg in plan.joins]
    ids = np.concatenate(segs)
    assert len(ids) == len(np.unique(ids))  # no sample on two chains
    for (u, w, seg) in plan.joins:  # a cell's side: its samples between its two junctions
        cu, cw = plan.centres[u], plan.centres[w]
        assert np.linalg.norm(cu - cw) < 6
        t = (X[seg] - cu) @ (cw - cu) / np.dot(cw - cu, cw - cu)
        assert np.all((t > 0) & (t < 1))
