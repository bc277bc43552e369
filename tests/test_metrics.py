"""Metrics on hand-made networks with exact expected values."""

import numpy as np
import pytest

from curvenet.errors import InputError
from curvenet.metrics import compare, contract, densify, hausdorff
from curvenet.network import Curve, CurveNetwork

H = 0.02


def seg(a, b, step=0.01):
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = int(np.ceil(np.linalg.norm(b - a) / step))
    return a + (b - a) * np.linspace(0, 1, n + 1)[:, None]


def circle():
    t = np.linspace(0, 2 * np.pi, 300, endpoint=False)
    return np.column_stack([3 + 0.5 * np.cos(t), 3 + 0.5 * np.sin(t)])


A, B, C, D = (0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (1.0, 1.0)


def net(nodes, edges, loop=True):
    curves = [Curve(seg(nodes[i], nodes[j]), i, j) for i, j in edges]
    if loop:
        curves.append(Curve(circle(), None, None, True))
    return CurveNetwork(np.array(nodes, float), curves)


@pytest.fixture
def truth():
    # a "T" (A-B, B-C, B-D; B of valence 3) and a free loop
    return net([A, B, C, D], [(0, 1), (1, 2), (1, 3)])


def test_identical(truth):
    m = compare(truth, truth, h=H)
    for k in ("node_precision", "node_recall", "node_f1", "curve_precision", "curve_recall", "curve_f1",
              "coverage", "coverage_length"):
        assert m[k] == 1.0, k
    assert m["exact_topology"] is True
    assert m["node_offset"] == 0.0 and m["chamfer"] == 0.0
    assert m["betti_true"] == m["betti_found"] == (2, 1)
    assert (m["n_nodes_true"], m["n_curves_true"]) == (4, 4)


def test_node_order_does_not_matter(truth):
    perm = [2, 0, 3, 1]
    inv = {old: new for new, old in enumerate(perm)}
    nodes = truth.nodes[perm]
    curves = [Curve(c.points, None if c.start is None else inv[c.start], None if c.end is None else inv[c.end],
                    c.closed) for c in truth.curves[::-1]]
    m = compare(CurveNetwork(nodes, curves), truth, h=H)
    assert m["curve_f1"] == 1.0 and m["node_f1"] == 1.0 and m["exact_topology"]


def test_missing_loop(truth):
    res = net([A, B, C, D], [(0, 1), (1, 2), (1, 3)], loop=False)
    m = compare(res, truth, h=H)
    assert m["node_f1"] == 1.0
    assert m["curve_precision"] == 1.0 and m["curve_recall"] == 0.75
    assert m["curve_f1"] == pytest.approx(6 / 7)
    assert m["coverage"] == 0.75
    assert m["exact_topology"] is False
    assert m["betti_found"] == (1, 0)


def test_missing_curve(truth):
    # without B-D, B has valence 2 and is contracted: A-C is one curve
    res = net([A, B, C], [(0, 1), (1, 2)])
    m = compare(res, truth, h=H)
    assert (m["n_nodes_found"], m["n_curves_found"]) == (2, 2)
    assert m["node_precision"] == 1.0 and m["node_recall"] == 0.5
    assert m["node_f1"] == pytest.approx(2 / 3)
    assert m["curve_precision"] == 0.5 and m["curve_recall"] == 0.25
    assert m["curve_f1"] == pytest.approx(1 / 3)
    assert m["coverage"] == 0.75
    assert m["exact_topology"] is False


def test_split_at_valence2_node_is_not_an_error(truth):
    res = net([A, B, C, D, (1.5, 0.0)], [(0, 1), (1, 4), (4, 2), (1, 3)])
    m = compare(res, truth, h=H)
    assert m["node_f1"] == 1.0 and m["curve_f1"] == 1.0 and m["exact_topology"] is True


def test_split_with_gap_is_an_error(truth):
    res = net([A, B, C, D, (1.4, 0.0), (1.6, 0.0)], [(0, 1), (1, 4), (5, 2), (1, 3)])
    m = compare(res, truth, h=H)
    assert m["node_precision"] == pytest.approx(4 / 6) and m["node_recall"] == 1.0
    assert m["node_f1"] == pytest.approx(0.8)
    assert m["curve_matched"] == 3
    assert m["curve_precision"] == pytest.approx(3 / 5) and m["curve_recall"] == 0.75
    assert m["curve_f1"] == pytest.approx(2 / 3)
    assert m["coverage"] == 0.75
    assert m["exact_topology"] is False
    assert m["betti_found"] == (3, 1)


def test_displaced_node_beyond_radius(truth):
    res = net([A, B, C, (1.0, 1.2)], [(0, 1), (1, 2), (1, 3)])
    m = compare(res, truth, h=H)
    assert m["node_precision"] == 0.75 and m["node_recall"] == 0.75 and m["node_f1"] == 0.75
    assert m["curve_precision"] == 0.75 and m["curve_recall"] == 0.75
    assert m["node_offset"] == 0.0
    assert m["exact_topology"] is False


def test_displaced_node_within_radius(truth):
    res = net([A, B, C, (1.0, 1.03)], [(0, 1), (1, 2), (1, 3)])
    m = compare(res, truth, h=H)
    assert m["node_f1"] == 1.0 and m["curve_f1"] == 1.0 and m["exact_topology"] is True
    assert m["node_offset"] == pytest.approx(0.03 / 4)
    assert m["node_offset_h"] == pytest.approx(0.03 / 4 / H)
    # a tighter curve tolerance rejects the displaced curve
    m = compare(res, truth, h=H, curve_tol=1.0)
    assert m["curve_matched"] == 3 and m["exact_topology"] is True


def test_extra_spur(truth):
    res = net([A, B, C, D, (0.5, 0.0), (0.5, 0.3)], [(0, 4), (4, 1), (4, 5), (1, 2), (1, 3)])
    m = compare(res, truth, h=H)
    assert m["node_precision"] == pytest.approx(4 / 6) and m["node_recall"] == 1.0
    assert m["node_f1"] == pytest.approx(0.8)
    assert m["curve_precision"] == 0.5 and m["curve_recall"] == 0.75
    assert m["curve_f1"] == pytest.approx(0.6)
    assert m["coverage"] == 1.0
    assert m["exact_topology"] is False


def test_wrong_shape_between_right_nodes(truth):
    # B-D drawn as a detour far from the true curve: nodes right, that curve wrong
    detour = np.vstack([seg(B, (1.3, 0.5)), seg((1.3, 0.5), D)[1:]])
    curves = [Curve(seg(A, B), 0, 1), Curve(seg(B, C), 1, 2), Curve(detour, 1, 3), Curve(circle(), None, None, True)]
    m = compare(CurveNetwork(np.array([A, B, C, D]), curves), truth, h=H)
    assert m["node_f1"] == 1.0 and m["curve_matched"] == 3
    assert m["exact_topology"] is True  # graphs only


def test_empty_result(truth):
    m = compare(CurveNetwork(np.zeros((0, 2)), []), truth, h=H)
    assert m["node_f1"] == 0.0 and m["curve_f1"] == 0.0 and m["coverage"] == 0.0
    assert m["chamfer"] == float("inf") and m["exact_topology"] is False


def test_contract_loop_of_valence2_nodes():
    sq = [(0, 0), (1, 0), (1, 1), (0, 1)]
    n = net(sq, [(0, 1), (1, 2), (2, 3), (3, 0)], loop=False)
    c = contract(n)
    assert c.n_nodes == 0 and c.n_curves == 1
    cur = c.curves[0]
    assert cur.closed and cur.start is None
    assert cur.length == pytest.approx(4.0)
    assert c.betti == n.betti == (1, 1)
    # the contracted loop matches a plain closed loop
    t = CurveNetwork(np.zeros((0, 2)), [Curve(np.array(sq, float), None, None, True)])
    assert compare(n, t, h=H)["curve_f1"] == 1.0


def test_contract_keeps_betti_on_theta_graph():
    n = net([A, B, (0.5, 0.5), (0.5, -0.5)], [(0, 2), (2, 1), (0, 3), (3, 1), (0, 1)], loop=False)
    c = contract(n)
    assert (c.n_nodes, c.n_curves) == (2, 3)
    assert c.betti == n.betti == (1, 2)
    assert sorted(c.valence.tolist()) == [3, 3]


def test_hausdorff_and_densify():
    a = seg((0, 0), (1, 0))
    b = seg((0, 0.1), (1, 0.1))
    assert hausdorff(a, b) == pytest.approx(0.1)
    d = densify(np.array([[0.0, 0.0], [1.0, 0.0]]), 0.1)
    assert len(d) == 11 and np.allclose(np.diff(d[:, 0]), 0.1)
    d = densify(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), 0.5, closed=True)
    assert np.linalg.norm(np.diff(np.vstack([d, d[:1]]), axis=0), axis=1).max() <= 0.5 + 1e-12


def test_bad_h(truth):
    with pytest.raises(InputError):
        compare(truth, truth, h=0.0)


def test_invariant_under_rigid_motion_and_scaling(truth):
    # a faulty result (extra spur), moved and scaled together with the truth and h
    res = net([A, B, C, D, (0.5, 0.0), (0.5, 0.3)], [(0, 4), (4, 1), (4, 5), (1, 2), (1, 3)])
    base = compare(res, truth, h=H)
    a = 0.7
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])

    def move(n, s):
        return CurveNetwork(
            (n.nodes @ R.T) * s + [5.0, -2.0],
            [Curve((c.points @ R.T) * s + [5.0, -2.0], c.start, c.end, c.closed) for c in n.curves],
        )

    for s in (1.0, 3.0):
        m = compare(move(res, s), move(truth, s), h=H * s)
        for k in ("node_f1", "curve_f1", "coverage", "exact_topology", "betti_found"):
            assert m[k] == base[k], k
        # distances are measured on polylines densified to h/4: accurate to about h/8
        assert m["chamfer_h"] == pytest.approx(base["chamfer_h"], abs=0.125)
