"""Two junctions seen as one region (methods/robust/paired.py): the line test, the topology
change, and the method on networks whose junctions lie a few spacings apart under noise."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import reconstruct, synth
from curvenet.methods.robust import paired, repairs
from curvenet.methods.robust.chains import Chain
from curvenet.methods.robust.paired import Lines, best_pair, meeting_point
from curvenet.methods.robust.topology import Topology
from curvenet.metrics import compare
from curvenet.synth.models import _Builder, _poly

H = 1.0


def _lines(junction_dirs, lim=1.0, noise=0.0, seed=0):
    """Lines of branches leaving junction points: ``(x, u)`` pairs, the branch's end portion
    from 3 h to 7 h out (its tip at 3 h, its centroid at 5 h), offset by ``noise`` at random."""
    rng = np.random.default_rng(seed)
    c, u, tip = [], [], []
    for x, d in junction_dirs:
        x, d = np.asarray(x, float), np.asarray(d, float) / np.linalg.norm(d)
        off = rng.normal(scale=noise, size=3)
        off -= (off @ d) * d
        c.append(x + 5 * H * d + off)
        u.append(d)
        tip.append(x + 3 * H * d + off)
    return Lines(np.array(c), np.array(u), np.array(tip), np.full(len(c), lim))


A, B = np.zeros(3), np.array([4.0, 0, 0])


def _assert_split_at_a_and_b(L, tol):
    """``best_pair`` of the lines ``L`` (two leaving A, then two leaving B) splits them so, its
    points within ``tol`` h of A and B."""
    pair = best_pair(L, (A + B) / 2, H)
    assert pair is not None
    mask, xa, xb = pair
    assert mask[0] == mask[1] and mask[2] == mask[3] and mask[0] != mask[2]
    pa, pb = (xa, xb) if not mask[0] else (xb, xa)
    assert np.linalg.norm(pa - A) < tol and np.linalg.norm(pb - B) < tol


def test_a_building_step_reads_as_two_junctions():
    # the junctions A and B 4 h apart, joined along x: each has a wall and an edge up
    L = _lines([(A, [0, 1, 0]), (A, [0, 0, 1]), (B, [0, -1, 0]), (B, [0, 0, 1])], noise=0.1)
    _assert_split_at_a_and_b(L, 0.3)


def test_a_ladder_rail_collinear_with_the_segment_reads_as_two_junctions():
    # a T at each end: the rail runs on through A and B (collinear with A-B), the rungs leave up
    L = _lines([(A, [-1, 0, 0]), (A, [0, 1, 0]), (B, [1, 0, 0]), (B, [0, 1, 0])], noise=0.1)
    _assert_split_at_a_and_b(L, 0.5)


@pytest.mark.parametrize("angle", [40.0, 90.0])
def test_a_crossing_is_one_junction(angle):
    # two curves crossing at one point: the four lines meet there within the noise
    a = np.radians(angle)
    d = [1, 0, 0], [np.cos(a), np.sin(a), 0]
    L = _lines([(A, d[0]), (A, -np.asarray(d[0])), (A, d[1]), (A, -np.asarray(d[1]))], noise=0.2, seed=3)
    assert best_pair(L, A, H) is None


def test_branches_ending_nearer_the_other_point_do_not_split():
    # the same step, but every branch's end lies beyond the other junction (ends swapped): the
    # branches cannot end at the junction they are said to meet
    L = _lines([(A, [0, 1, 0]), (A, [0, 0, 1]), (B, [0, -1, 0]), (B, [0, 0, 1])], noise=0.1)
    tip = L.tip.copy()
    tip[:2] += B - A
    tip[2:] -= B - A
    assert best_pair(L._replace(tip=tip), (A + B) / 2, H) is None


def _overrun_rail(partner=True):
    """The ladder's T pair (A and B 4 h apart, rail along x, rungs up), the rail's half at A run
    on past A: its tip 0.7 of the way to B, its end portion's centroid 1 h behind A. Without
    ``partner`` the rail's other half (at B) is a second rung instead."""
    far = [1, 0, 0] if partner else [0, 1, 0.3]
    L = _lines([(A, [-1, 0, 0]), (A, [0, 1, 0]), (B, far), (B, [0, 1, 0])], noise=0.1)
    c, tip = L.c.copy(), L.tip.copy()
    c[0] = A - np.array([1.0, 0, 0])
    tip[0] = A + 0.7 * (B - A)
    return L._replace(c=c, tip=tip)


def test_a_rail_half_run_on_past_its_junction_is_judged_by_its_centroid(monkeypatch):
    # its tip lies nearer B, but the rail's two halves are one straight curve through A and B:
    # the half is judged by its end portion's centroid, behind A
    L = _overrun_rail()
    assert np.linalg.norm(L.tip[0] - B) < np.linalg.norm(L.tip[0] - A)
    _assert_split_at_a_and_b(L, 0.5)
    # judged by its tip (as before): no split reads so
    monkeypatch.setattr(paired, "_through_halves", lambda u, along, second: np.zeros(along.shape, dtype=bool))
    assert best_pair(L, (A + B) / 2, H) is None


def test_a_line_along_the_segment_without_its_other_half_is_judged_by_its_tip():
    # the same run-on line, but nothing continues it at B: it may be a curve ending past its
    # junction, so its tip (nearer B) decides, and the pair is not read
    L = _overrun_rail(partner=False)
    assert best_pair(L, (A + B) / 2, H) is None


def test_through_halves_need_exactly_one_parallel_line_in_the_other_group():
    u = np.array([[[1.0, 0, 0], [0, 1, 0], [-1, 0, 0], [0, 1, 0]]])
    along = np.array([[True, False, True, False]])
    # halves in the two groups: both judged by their centroids
    assert paired._through_halves(u, along, np.array([[False, False, True, True]])).tolist() == \
        [[True, False, True, False]]
    # both halves in one group: no curve through both points
    assert not paired._through_halves(u, along, np.array([[True, False, True, False]])).any()
    # a third parallel line (strokes drawn over one another): judged by their tips
    u3 = u.copy()
    u3[0, 3] = [1.0, 0.05, 0]
    assert not paired._through_halves(u3, along, np.array([[False, False, True, True]])).any()


def test_meeting_point_of_parallel_lines_is_held_at_the_anchor():
    c = np.array([[0.0, 1, 0], [0, -1, 0]])
    u = np.array([[1.0, 0, 0], [1, 0, 0]])
    x = meeting_point(c, u, np.array([7.0, 0.5, 0]))
    assert np.allclose(x, [7.0, 0.0, 0.0], atol=1e-2)


def test_split_region_keeps_the_topology_consistent(monkeypatch):
    monkeypatch.setenv("CURVENET_CHECK_TOPOLOGY", "1")
    P = np.arange(60, dtype=float).reshape(20, 3)
    # four chains into region 0 (points 0-5), each from its own free end
    chains = [Chain(np.array([6 + 3 * k, 7 + 3 * k, 8 + 3 * k]), [-1, 0]) for k in range(4)]
    topo = Topology(P, chains, [np.arange(6, dtype=np.int64)])
    assert topo.v[0] == 4
    nr = topo.split_region(0, [(2, 1), (3, 1)], np.array([0, 1]), np.array([4, 5]), np.array([2, 3]))
    topo.check()
    assert topo.v[0] == 3 and topo.v[nr] == 3
    assert [e for e in topo.incident(nr)] == [(2, 1), (3, 1), (4, 1)]
    assert topo.chains[4].ids.tolist() == [2, 3] and topo.chains[4].ends == [0, nr]
    assert topo.regions[0].tolist() == [0, 1] and topo.regions[nr].tolist() == [4, 5]


def _stepped_box(h: float = 0.02):
    """A box whose footprint and eaves have a jog of 4 h (two valence-3 corners 4 h apart on
    each), as buildings have: 12 nodes, 18 curves."""
    b = _Builder(h)
    foot = np.array([[0, 0], [40, 0], [40, 20], [24, 20], [24, 24], [0, 24]], dtype=float) * h
    bot = [b.node([x, y, 0.0]) for x, y in foot]
    top = [b.node([x, y, 16 * h]) for x, y in foot]
    n = len(foot)
    ids = bot + top
    edges = [(k, (k + 1) % n) for k in range(n)] + [(n + k, n + (k + 1) % n) for k in range(n)]
    edges += [(k, n + k) for k in range(n)]
    for i, j in edges:
        b.curve(_poly([b.nodes[ids[i]], b.nodes[ids[j]]], b.step), ids[i], ids[j])
    return b.build("stepped", "a box with a 4h jog")


def _scores(monkeypatch, split: bool, seeds=range(6)):
    if not split:
        monkeypatch.setattr(repairs, "ORDER", tuple(r for r in repairs.ORDER
                                                    if r.__name__ != "split_paired_junctions"))
    truth = _stepped_box()
    h = synth.h_of(truth)
    out = []
    for s in seeds:
        pts, _ = synth.sample(truth, noise=0.2, rng=100 + s)
        out.append(compare(reconstruct(pts), truth, h=h))
    return out


def test_jogs_of_four_spacings_are_two_junctions_under_noise(monkeypatch):
    with_split = _scores(monkeypatch, True)
    assert all(s["n_nodes_found"] == 12 for s in with_split)
    assert np.mean([s["curve_f1"] for s in with_split]) >= 0.95
    assert sum(s["exact_topology"] for s in with_split) >= 5


def test_without_the_split_the_jogs_merge(monkeypatch):
    # the control: the same samplings without the split lose the jogs' junctions
    without = _scores(monkeypatch, False)
    assert np.mean([s["n_nodes_found"] for s in without]) < 11


def test_strokes_crossing_a_curve_loosely_are_one_junction():
    # a straight curve through A and B, crossed at A at 90 degrees and at B at 45 degrees: one
    # junction drawn loosely (the rule of best_pair); crossed in parallel: a ladder (split)
    d45 = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    loose = _lines([(A, [-1, 0, 0]), (A, [0, 1, 0]), (B, [1, 0, 0]), (B, d45)], noise=0.05)
    assert best_pair(loose, (A + B) / 2, H) is None
    rungs = _lines([(A, [-1, 0, 0]), (A, [0, 1, 0]), (B, [1, 0, 0]), (B, [0, 1, 0])], noise=0.05)
    assert best_pair(rungs, (A + B) / 2, H) is not None


def test_best_pair_reads_skew_teeth_as_two_junctions():
    # a spine along x through A and B, a tooth at each, 45 degrees apart: in the spine's plane,
    # the tooth at B leaning back to A's, their lines meet a spacing past A's tooth's tip
    # (strokes drawn loosely into one point of the curve: one junction); that tooth tilted out
    # of the plane instead, the lines pass apart (a 3D comb's teeth, the kinds' comb at noise
    # 0.2 h sampling 6): two junctions, as spanning._straight_across reads them
    r = 1.0 / np.sqrt(2.0)

    def lines(tooth_b):
        return _lines([(A, [-1, 0, 0]), (A, [0, 1, 0]), (B, tooth_b), (B, [1, 0, 0])], noise=0.05)

    assert best_pair(lines([-r, r, 0.0]), (A + B) / 2, H) is None
    _assert_split_at_a_and_b(lines([0.0, r, r]), 0.5)


def test_meet_loosely_needs_two_lines_with_a_direction():
    from curvenet.methods.robust.paired import meet_loosely

    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    skew = _lines([(A, [0, 1, 0]), (B, [0.0, c, s])])
    assert not meet_loosely(skew, (A + B) / 2)
    # a branch of a single point (direction 0) beside them has no line: the two decide
    three = Lines(*(np.concatenate([f, f[:1]]) for f in skew))
    three = three._replace(u=np.concatenate([skew.u, np.zeros((1, 3))]))
    assert not meet_loosely(three, (A + B) / 2)
    # one line with a direction (and one without) tells nothing: loose, as before
    one = three._replace(u=np.concatenate([skew.u[:1], np.zeros((2, 3))]))
    assert meet_loosely(one, (A + B) / 2)


def _street_lines():
    """The lines of a street grid's two junctions 4.6 h apart under noise 0.2 h (the kinds'
    streets, sampling 0, in h about the region's centroid): a street along x through both (lines
    0 and 4, tilted 7 and 3 degrees by the noise), a street ending at the left junction from
    below (1), and one crossing at the right junction (2 from below, 3 from above)."""
    c = np.array([[-8.3, 0.7], [-2.6, -6.9], [2.0, -6.8], [2.4, 5.7], [8.2, 0.7]])
    u = np.array([[0.99, 0.13], [0.06, 1.0], [0.04, 1.0], [0.02, -1.0], [-1.0, -0.06]])
    u = u / np.linalg.norm(u, axis=1)[:, None]
    pad = np.zeros((5, 1))
    return Lines(np.hstack([c, pad]), np.hstack([u, pad]), np.hstack([c + 2 * u, pad]), np.full(5, 1.16))


def test_a_street_through_two_junctions_passes_through_both_points():
    # the segment between the two points runs 19 degrees off the mean of the street's halves'
    # directions (the noise tilts them 7 and 3 degrees), but 13 degrees off the street's line
    # drawn through its halves' centroids 16 h apart: two junctions (measured on the mean of
    # the directions, before 7 December 2026, one of valence 5)
    pair = best_pair(_street_lines(), np.zeros(3), H)
    assert pair is not None
    mask, xa, xb = pair
    assert mask.tolist() in ([True, True, False, False, False], [False, False, True, True, True])


def test_a_street_whose_points_lie_off_its_line_is_no_pair(monkeypatch):
    # the street's halves turned 8 degrees the same way: the two points they give lie on a
    # segment 21 degrees off the street's line (centroid to centroid, still horizontal): no
    # curve through both, no pair; without the straight-curve rule the split is taken
    L = _street_lines()
    t = np.radians(8.0)
    u = L.u.copy()
    u[0], u[4] = [np.cos(t), np.sin(t), 0.0], [-np.cos(t), -np.sin(t), 0.0]
    L = L._replace(u=u, tip=L.c + 2 * u)
    assert best_pair(L, np.zeros(3), H) is None
    monkeypatch.setattr(paired, "straight_pairs", lambda L, ud: np.zeros(L.c.shape[:2] + L.c.shape[1:2], dtype=bool))
    assert best_pair(L, np.zeros(3), H) is not None


def test_jogs_are_two_junctions_on_noise_free_samples_too():
    truth = _stepped_box()
    h = synth.h_of(truth)
    for s in range(3):
        pts, _ = synth.sample(truth, rng=200 + s)
        assert compare(reconstruct(pts), truth, h=h)["n_nodes_found"] == 12


def test_many_regions_at_once_give_each_region_s_own_answer():
    # best_pairs on a stack of regions = best_pair region by region (a step, a T pair, a crossing)
    from curvenet.methods.robust.paired import best_pairs

    a = np.radians(40.0)
    regions = [
        _lines([(A, [0, 1, 0]), (A, [0, 0, 1]), (B, [0, -1, 0]), (B, [0, 0, 1])], noise=0.1),
        _lines([(A, [-1, 0, 0]), (A, [0, 1, 0]), (B, [1, 0, 0]), (B, [0, 1, 0])], noise=0.1),
        _lines([(A, [1, 0, 0]), (A, [-1, 0, 0]), (A, [np.cos(a), np.sin(a), 0]), (A, [-np.cos(a), -np.sin(a), 0])],
               noise=0.2, seed=3),
    ]
    anchors = np.array([(A + B) / 2, (A + B) / 2, A])
    stack = Lines(*(np.stack([getattr(L, f) for L in regions]) for f in Lines._fields))
    k, xa, xb = best_pairs(stack, anchors, np.ones(3))
    for j, L in enumerate(regions):
        one = best_pair(L, anchors[j], H)
        assert (one is None) == (k[j] < 0)
        if one is not None:
            assert np.allclose(one[1], xa[j]) and np.allclose(one[2], xb[j])
    assert k.tolist()[2] == -1 and (k[:2] >= 0).all()


def test_branch_lines_are_the_end_portions_lines(monkeypatch):
    # the padded, all-at-once end portions count what chains.end_portion counts, per branch
    from curvenet.methods.robust.chains import end_portion, fit_line
    from curvenet.methods.robust.paired import branch_lines
    from curvenet.methods.robust.params import Scales
    from curvenet.methods.robust.thresholds import NODES

    rng = np.random.default_rng(1)
    pts, chains = [], []
    for k in range(5):  # five branches of different lengths into region 0, the last one dense
        n = [3, 6, 12, 40, 400][k]  # (its end portion, over 100 points, is past the padding)
        d = np.array([np.cos(k), np.sin(k), 0.3 * k])
        X = np.linspace(20, 1, n)[:, None] * d / np.linalg.norm(d) + rng.normal(scale=0.2 * (k < 4), size=(n, 3))
        chains.append(Chain(np.arange(len(pts), len(pts) + n), [-1, 0]))
        pts.extend(X.tolist())
    P = np.array(pts + [[0.0, 0, 0]])
    topo = Topology(P, chains, [np.array([len(P) - 1])])
    noise = 0.3
    h = rng.uniform(0.5, 1.5, len(P))
    sc = Scales(h=h, hmed=1.0, sigma=noise, noise=noise, clean=False, width=1.0,
                indptr=np.zeros(len(P) + 1, dtype=np.int64), indices=np.zeros(0, dtype=np.int64), tree=None)
    inc = topo.incident(0)
    L, off = branch_lines(topo, sc, [inc])
    assert off.tolist() == [0, 5]
    for b, (i, s) in enumerate(inc):
        ids = topo.end_ids(i, s)
        E = end_portion(P, h, ids, span=NODES.fit_span + NODES.fit_noise * noise / h[ids[-1]])
        c, u = fit_line(E)
        assert np.allclose(L.c[b], c) and np.allclose(L.tip[b], E[0])
        assert np.isclose(abs(L.u[b] @ u), 1.0)


def test_a_one_point_link_between_two_regions_gets_its_direction(monkeypatch):
    # two close crossings' regions A (around x = 0) and B (around x = 4) joined by a chain of
    # one sample at x = 2 (a street's short link under noise): its line runs from A's point
    # nearest to it to B's (along x); a one-point branch to a free end keeps direction 0, and
    # the regions are then tried as a pair (they were left whole: a branch without a line)
    from curvenet.methods.robust.paired import _one_point_links, branch_lines
    from curvenet.methods.robust.params import Scales

    P = np.array([[0, 0, 0], [0.5, 0.3, 0], [4, 0, 0], [3.5, -0.3, 0], [2, 0.1, 0], [0, 5, 0], [9, 9, 9]], float)
    chains = [Chain(np.array([4]), [0, 1]), Chain(np.array([5]), [0, 2])]
    topo = Topology(P, chains, [np.array([0, 1]), np.array([2, 3]), np.zeros(0, dtype=np.int64)])
    sc = Scales(h=np.ones(len(P)), hmed=1.0, sigma=0.1, noise=0.1, clean=False, width=1.0,
                indptr=np.zeros(len(P) + 1, dtype=np.int64), indices=np.zeros(0, dtype=np.int64), tree=None)
    incs = [topo.incident(0), topo.incident(1)]
    L, off = branch_lines(topo, sc, incs)
    assert not np.any(np.linalg.norm(L.u, axis=1) > 0)  # (one sample: no line of its own)
    out = _one_point_links(topo, L, off, incs, [0, 1])
    link0 = incs[0].index((0, 0))
    assert np.allclose(out.u[off[0] + link0], (P[3] - P[1]) / np.linalg.norm(P[3] - P[1]))
    assert np.allclose(out.u[off[1]], (P[1] - P[3]) / np.linalg.norm(P[1] - P[3]))
    assert not np.linalg.norm(out.u[off[0] + incs[0].index((1, 0))]) > 0  # (to a free end: no region points)
    assert np.array_equal(L.u, np.zeros_like(L.u))  # (the given lines untouched)


def test_group_medians_are_numpy_s_medians():
    from curvenet.methods.robust.chains import group_medians

    rng = np.random.default_rng(4)
    counts = np.array([1, 2, 0, 5, 6, 3])
    v = rng.normal(size=counts.sum())
    got = group_medians(v, counts)
    off = np.r_[0, np.cumsum(counts)]
    for g, c in enumerate(counts):
        if c:
            assert got[g] == np.median(v[off[g]:off[g + 1]])
        else:
            assert np.isnan(got[g])


def test_a_region_of_many_branches_is_not_tried_as_a_pair(monkeypatch):
    # a flower's centre: 22 petals' ends at one region (the CASSIE flower at noise 0.3 h) would
    # need 2 million splits (memory exhausted); over PAIRED.max_lines ends no split is tried
    import time

    from curvenet.methods.robust import paired

    ang = np.linspace(0, 2 * np.pi, 22, endpoint=False)
    L = _lines([(np.zeros(3), [np.cos(a), np.sin(a), 0.1 * np.sin(3 * a)]) for a in ang], noise=0.1)
    t = time.perf_counter()
    assert best_pair(L, np.zeros(3), H) is None
    assert time.perf_counter() - t < 5.0  # (a guard against the enumeration, not a speed test)
    # a building step's four ends are two junctions; with the cap under four they are not tried:
    # the cap, not the geometry, is what leaves a large region alone
    step = _lines([(A, [0, 1, 0]), (A, [0, 0, 1]), (B, [0, -1, 0]), (B, [0, 0, 1])], noise=0.1)
    assert best_pair(step, (A + B) / 2, H) is not None
    monkeypatch.setattr(paired, "PAIRED", paired.PAIRED._replace(max_lines=3))
    assert best_pair(step, (A + B) / 2, H) is None


def test_the_cassie_flower_under_heavy_noise_is_reconstructed():
    # end to end: the CASSIE flower (1,924 samples at 2 mm, noise 0.3 h) has a region of 22
    # branch ends at its centre; trying it as a pair exhausted 24 GB of memory
    from curvenet import bench
    from curvenet.synth import cassie

    if not cassie.available():
        pytest.skip("the CASSIE dataset is not on this machine")
    truth = cassie.load("flower")
    pts, _ = synth.sample(truth, h=0.002, rng=bench.run_seed("cassie", "flower", "noise 0.3h"), noise=0.3)
    net = reconstruct(pts, method="robust")
    assert compare(net, truth, h=0.002)["curve_f1"] > 0.5
