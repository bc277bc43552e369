"""Tests of the founding paper's method (curvenet.methods.paper): Algorithms 1 and 2."""

import itertools

import numpy as np
import pytest

from curvenet import reconstruct
from curvenet.errors import InputError
from curvenet.methods.paper import detect_nodes, point_variation, reconstruct_paper


# ------------------------------------------------------------------------------ tiny fixtures
def cube(n=50, corners=False):
    """Unit-cube wireframe, ``n`` points per edge at t = (i + 0.5) / n; labels = edge number."""
    v = np.array(list(itertools.product([0, 1], repeat=3)), float)
    edges = [(i, j) for i in range(8) for j in range(i + 1, 8) if np.abs(v[i] - v[j]).sum() == 1]
    t = (np.arange(n) + 0.5) / n
    pts = [v[i] + t[:, None] * (v[j] - v[i]) for i, j in edges]
    lab = np.repeat(np.arange(12), n)
    if corners:
        pts.append(v)
        lab = np.r_[lab, np.full(8, -1)]
    return np.vstack(pts), lab, v, edges


def star(dirs, n=40):
    """Straight arms from the origin (the origin is a sample), ``n`` points per arm."""
    t = (np.arange(n) + 0.5) / n
    d = np.asarray(dirs, float)
    pts = [t[:, None] * u[None] for u in d] + [np.zeros((1, d.shape[1]))]
    return np.vstack(pts)


def lens(n1=50, n2=70, half=20.0):
    """Two circular arcs from (0, 0) to (1, 0), on either side, meeting at 2 * half degrees.

    The shape of the paper's Figure 8 / Figure 5: two curves between the same two nodes, close
    together near the nodes. Labels: +1 upper arc, -1 lower arc, 0 the two tips.
    """
    h = np.radians(half)
    r = 0.5 / np.sin(h)
    pts, lab = [], []
    for sgn, n in ((1, n1), (-1, n2)):
        c = np.array([0.5, -sgn * r * np.cos(h)])
        a0, a1 = np.arctan2(-c[1], -c[0]), np.arctan2(-c[1], 1 - c[0])
        ang = a0 + (a1 - a0) * np.arange(1, n) / n
        pts.append(c + r * np.c_[np.cos(ang), np.sin(ang)])
        lab += [sgn] * (n - 1)
    pts.append([[0.0, 0.0], [1.0, 0.0]])
    return np.vstack(pts), np.array(lab + [0, 0])


def same_network(a, b):
    a, b = a.canonical(), b.canonical()
    if not np.array_equal(a.nodes, b.nodes) or len(a.curves) != len(b.curves):
        return False
    return all(
        x.start == y.start and x.end == y.end and np.array_equal(x.points, y.points)
        for x, y in zip(a.curves, b.curves)
    )


def check_consistent(net, points):
    """Curves start/end exactly at their nodes; every curve point is the input point it names."""
    for c in net.curves:
        assert c.start is not None and c.end is not None and not c.closed
        np.testing.assert_array_equal(c.points[0], net.nodes[c.start])
        np.testing.assert_array_equal(c.points[-1], net.nodes[c.end])
        assert (c.indices >= 0).all()
        np.testing.assert_array_equal(c.points, points[c.indices])


# ------------------------------------------------------------------------------ the cube
@pytest.mark.parametrize("theta", [120.0, 150.0])
def test_cube_8_nodes_12_curves_between_the_right_corners(theta):
    pts, lab, corners, edges = cube(50)
    net = reconstruct_paper(pts, theta=theta)
    assert net.n_nodes == 8 and net.n_curves == 12
    check_consistent(net, pts)
    h = 1 / 50
    d = np.linalg.norm(net.nodes[:, None] - corners[None], axis=2)
    corner_of = d.argmin(axis=1)
    assert sorted(corner_of.tolist()) == list(range(8))  # one node per corner
    assert d.min(axis=1).max() < 2 * h
    found = sorted(tuple(sorted((int(corner_of[c.start]), int(corner_of[c.end])))) for c in net.curves)
    assert found == sorted(edges)
    for c in net.curves:  # inner points all on the cube edge joining the curve's corners
        e = edges.index(tuple(sorted((int(corner_of[c.start]), int(corner_of[c.end])))))
        assert (lab[c.indices[1:-1]] == e).all()
        assert len(c.indices) - 2 >= 50 - 2 * 5  # only the removed candidates are missing
    assert (net.valence == 3).all()
    assert net.betti == (1, 5)
    assert set(net.parameters) == {"k", "epsilon", "tau_s", "theta"}
    assert net.parameters["theta"] == theta
    assert net.stats["unmatched"] == 0 and net.stats["free_ends"] == 0
    assert {"neighbors", "nodes", "tracing", "merging"} <= set(net.stats["time"])


def test_cube_with_corner_samples_has_nodes_at_the_corners():
    pts, _, corners, _ = cube(50, corners=True)
    net = reconstruct_paper(pts)
    assert net.n_nodes == 8 and net.n_curves == 12
    d = np.linalg.norm(net.nodes[:, None] - corners[None], axis=2)
    assert d.min(axis=1).max() == 0.0


def test_explicit_parameters_are_recorded_and_used():
    pts, *_ = cube(50)
    net = reconstruct_paper(pts, k=8, epsilon=1e-2, tau_s=0.2, theta=130)
    assert net.parameters == {"k": 8, "epsilon": 1e-2, "tau_s": 0.2, "theta": 130.0}
    assert net.n_nodes == 8 and net.n_curves == 12
    # tau_s below the candidate gap around the corners: no starting point, no curve
    net = reconstruct_paper(pts, tau_s=0.05)
    assert net.n_curves == 0


def test_default_tau_s_follows_the_spacing():
    pts, *_ = cube(50)
    a = reconstruct_paper(pts)
    b = reconstruct_paper(pts * 7.0 + 3.0)
    assert b.parameters["tau_s"] == pytest.approx(7.0 * a.parameters["tau_s"])
    assert a.stats["h"] == pytest.approx(1 / 50)
    assert b.n_nodes == 8 and b.n_curves == 12


# ------------------------------------------------------------------------------ Figure 8
def test_figure8_two_close_curves_emst_fails_algorithm2_succeeds():
    from scipy.sparse.csgraph import minimum_spanning_tree
    from scipy.spatial.distance import pdist, squareform

    pts, lab = lens()
    # EMST links interior points of the two different curves: it does not give the two curves
    mst = minimum_spanning_tree(squareform(pdist(pts))).tocoo()
    cross = sum(1 for i, j in zip(mst.row, mst.col) if lab[i] * lab[j] == -1)
    assert cross > 0
    net = reconstruct_paper(pts)
    check_consistent(net, pts)
    assert net.n_nodes == 2 and net.n_curves == 2
    tips = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert np.linalg.norm(net.nodes - tips, axis=1).max() < 0.05
    arcs = []
    for c in net.curves:
        assert {c.start, c.end} == {0, 1}
        inner = lab[c.indices[1:-1]]
        assert len(set(inner.tolist())) == 1  # one curve, one arc
        arcs.append(int(inner[0]))
        assert len(inner) >= 0.6 * (lab == inner[0]).sum()
    assert sorted(arcs) == [-1, 1]


# ------------------------------------------------------------------------------ junctions
@pytest.mark.parametrize(
    "dirs",
    [
        [(1, 0), (-1, 0), (0, 1)],  # valence 3, 2D (T)
        [(1, 0), (np.cos(2.1), np.sin(2.1)), (np.cos(4.2), np.sin(4.2))],  # valence 3, 2D (Y)
        [(1, 0), (-1, 0), (0, 1), (0, -1)],  # valence 4, 2D
        [(1, 0, 0), (0, 1, 0), (0, 0, 1)],  # valence 3, 3D, not coplanar
        [(1, 0, 0), (0, 1, 0), (0, 0, 1), (-1, -1, -1)],  # valence 4, 3D
    ],
)
def test_star_junction_and_free_ends(dirs):
    pts = star(dirs)
    net = reconstruct_paper(pts)
    check_consistent(net, pts)
    v = len(dirs)
    assert net.n_nodes == v + 1 and net.n_curves == v
    assert sorted(net.valence.tolist()) == [1] * v + [v]
    hub = int(np.argmax(net.valence))
    assert np.linalg.norm(net.nodes[hub]) < 3 / 40
    tips = np.asarray(dirs, float) * (39.5 / 40)  # the last sample of each arm
    ends = np.delete(net.nodes, hub, axis=0)
    assert np.linalg.norm(ends[:, None] - tips[None], axis=2).min(axis=1).max() < 1e-12
    assert net.stats["free_ends"] == v


def test_criterion3_stops_a_free_end_jumping_onto_a_nearby_curve():
    # a T whose right arm ends next to an unrelated segment, parallel and 0.3 away (< tau_s):
    # the nearest point past the arm's end is on the segment, sideways; criterion 3 (theta=150)
    # rejects it, so the arm ends at its last sample, a free end, and the segment (touching no
    # node) is not used
    arms = star([(1, 0), (-1, 0), (0, 1)])
    seg = np.c_[np.linspace(0.95, 1.6, 27), np.full(27, 0.3)]
    pts = np.vstack([arms, seg])
    net = reconstruct_paper(pts, theta=150.0, k=10)  # tau_s = 15 h: the segment is within reach
    assert net.parameters["tau_s"] > 0.3
    check_consistent(net, pts)
    assert net.n_nodes == 4 and net.n_curves == 3
    assert np.min(np.linalg.norm(net.nodes - [39.5 / 40, 0.0], axis=1)) < 1e-12
    assert all((c.indices < len(arms)).all() for c in net.curves)


def test_2d_input_gives_2d_network():
    pts = star([(1, 0), (-1, 0), (0, 1)])
    net = reconstruct(pts, method="paper")
    assert net.dimension == 2 and net.nodes.shape == (4, 2)
    assert net.stats["N_n"] == 4 and net.stats["N_c"] == 3 and net.stats["N_d"] == len(pts)


# ------------------------------------------------------------------------------ determinism
@pytest.mark.parametrize("shape", ["cube", "lens", "star"])
@pytest.mark.parametrize("seed", [0, 1])
def test_input_order_does_not_matter(shape, seed):
    pts = {"cube": lambda: cube(50)[0], "lens": lambda: lens()[0],
           "star": lambda: star([(1, 0, 0), (0, 1, 0), (0, 0, 1), (-1, -1, -1)])}[shape]()
    perm = np.random.default_rng(seed).permutation(len(pts))
    a = reconstruct_paper(pts)
    b = reconstruct_paper(pts[perm])
    assert same_network(a, b)
    check_consistent(b, pts[perm])


def test_rigid_motion_and_scale_keep_the_cube():
    pts, _, corners, _ = cube(50)
    rot = np.linalg.qr(np.random.default_rng(2).normal(size=(3, 3)))[0]
    moved = 3.5 * pts @ rot.T + [10.0, -4.0, 2.0]
    net = reconstruct_paper(moved)
    assert net.n_nodes == 8 and net.n_curves == 12 and net.betti == (1, 5)
    back = (net.nodes - [10.0, -4.0, 2.0]) @ rot / 3.5
    assert np.linalg.norm(back[:, None] - corners[None], axis=2).min(axis=1).max() < 2 / 50


def test_numba_and_python_kernels_agree():
    pytest.importorskip("numba")
    for pts in (cube(30)[0], lens()[0], star([(1, 0), (-1, 0), (0, 1), (0, -1)])):
        assert same_network(reconstruct_paper(pts, use_numba=True), reconstruct_paper(pts, use_numba=False))


# ------------------------------------------------------------------------------ criterion 4
def test_reverse_search_replaces_the_end_of_a_curve_by_the_start_of_its_twin():
    from curvenet.methods.paper import _merge_twins

    a, b = 100, 200
    seq = lambda *v: np.array(v, dtype=np.int64)  # noqa: E731
    curves = [
        (a, b, seq(a, 1, 2, 3, 4, 5, 6, 99, b)),  # near its end it strayed onto point 99 (Fig. 5b)
        (a, b, seq(a, 11, 12, 13, 14, b)),  # a second curve between the same nodes
        (b, a, seq(b, 14, 13, 12, 11, a)),
        (b, a, seq(b, 7, 6, 5, 4, 3, 2, 1, a)),  # traced from b: right next to b
        (a, 300, seq(a, 50, 51, 300)),  # no twin: not found from both directions
        (a, a, seq(a, 60, 61, 62, a)),  # a loop through one node is its own twin
    ]
    merged, unmatched = _merge_twins(curves)
    assert unmatched == 1
    got = sorted(tuple(c[2].tolist()) for c in merged)
    assert got == sorted([(a, 1, 2, 3, 4, 5, 6, 7, b), (a, 11, 12, 13, 14, b), (a, 60, 61, 62, a)])
    assert all(c[0] == c[2][0] and c[1] == c[2][-1] for c in merged)


# ------------------------------------------------------------------------------ Algorithm 1
@pytest.mark.parametrize("d", [2, 3])
def test_point_variation_is_equation_2_centred_at_the_point(d):
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(60, d))
    k = 7
    got = point_variation(pts, k)
    for i in range(len(pts)):
        nb = np.argsort(np.linalg.norm(pts - pts[i], axis=1))[1 : k + 1]
        a = pts[nb] - pts[i]  # centred at P_i, not at the mean of A
        lam = np.linalg.eigvalsh(a.T @ a / k)
        assert got[i] == pytest.approx(lam[0] / lam.sum(), rel=1e-9, abs=1e-15)


def test_point_variation_is_zero_on_a_line_and_high_at_a_corner():
    pts, *_ = cube(50, corners=True)
    delta = point_variation(pts, 10)
    corners = np.flatnonzero((np.abs(pts - np.round(pts)) < 1e-12).all(axis=1))
    mid = np.flatnonzero(np.abs(pts - 0.5).min(axis=1) < 0.02)
    assert delta[corners].min() > 0.1
    assert delta[mid].max() < 1e-12


def test_groups_and_node_rule():
    pts, *_ = cube(50)
    det = detect_nodes(pts, k=10, epsilon=1e-3, tau_s=0.1)
    assert len(det["groups"]) == 8
    assert sum(len(g) for g in det["groups"]) == len(det["candidates"])
    # a group of <= 4 candidates keeps them all: its node is the one nearest their centroid
    few = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.0, 0.3, 0]])
    from curvenet.methods.paper import _select_nodes

    assert _select_nodes(few, [np.arange(3)])[0] == 0


def test_large_group_selection_matches_the_plain_iteration():
    from curvenet.methods.paper import _select_node_large, _select_nodes

    def plain(gp):  # the paper's loop, centroid kept as a running sum
        alive = list(range(len(gp)))
        total = gp.sum(axis=0)
        while len(alive) > 4:
            c = total / len(alive)
            j = alive[int(np.argmax(((gp[alive] - c) ** 2).sum(axis=1)))]
            alive.remove(j)
            total = total - gp[j]
        c = total / len(alive)
        return alive[int(np.argmin(((gp[alive] - c) ** 2).sum(axis=1)))]

    rng = np.random.default_rng(5)
    for gp in (rng.normal(size=(700, 3)), np.round(rng.normal(size=(500, 2)) * 4), rng.uniform(size=(300, 3))):
        assert _select_node_large(gp) == plain(gp)
        assert _select_nodes(gp, [np.arange(len(gp))])[0] == plain(gp)  # routed to the large path


def test_coplanar_junction_in_3d_is_not_a_candidate():
    # the paper's δ = λ0 / Σλ is zero for a neighbourhood in a plane (documented limitation)
    pts = star([(1, 0, 0), (-1, 0, 0), (0, 1, 0)])
    assert point_variation(pts, 10).max() < 1e-12
    assert reconstruct_paper(pts).n_nodes == 0


# ------------------------------------------------------------------------------ edge cases
def test_loop_without_node_is_lost_and_tiny_inputs_work():
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    net = reconstruct_paper(np.c_[np.cos(t), np.sin(t), 0 * t])
    assert net.n_nodes == 0 and net.n_curves == 0
    for pts in ([[0.0, 0.0, 0.0]], [[0.0, 0.0], [1.0, 0.0]], np.zeros((5, 3))):
        net = reconstruct_paper(pts)
        assert net.n_curves == 0


@pytest.mark.parametrize(
    "params",
    [{"k": 1}, {"k": 2.5}, {"epsilon": -0.1}, {"epsilon": 1.0}, {"tau_s": 0.0}, {"tau_s": "a"},
     {"theta": 200}, {"theta": float("nan")}, {"tau": 1.0}],
)
def test_bad_parameters_raise_input_error(params):
    pts = star([(1, 0), (-1, 0), (0, 1)])
    with pytest.raises(InputError):
        reconstruct_paper(pts, **params)
    with pytest.raises(InputError):
        reconstruct(pts, method="paper", **params)
