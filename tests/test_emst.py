"""The EMST baseline."""

import numpy as np
import pytest

from curvenet.methods.emst import emst_edges, reconstruct_emst
from curvenet.errors import InputError
from curvenet.reconstruct import reconstruct


def line(a, b, n):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a + (b - a) * np.linspace(0, 1, n)[:, None]


def test_line_is_one_curve_through_every_point():
    p = line((0, 0, 0), (1, 0.5, 0.2), 40)
    rng = np.random.default_rng(0)
    q = p[rng.permutation(40)]
    net = reconstruct_emst(q)
    assert net.n_nodes == 2 and net.n_curves == 1
    c = net.curves[0]
    assert len(c.points) == 40 and sorted(c.indices.tolist()) == list(range(40))
    assert np.array_equal(q[c.indices], c.points)
    assert c.length == pytest.approx(np.linalg.norm([1, 0.5, 0.2]))


@pytest.mark.parametrize("d", [2, 3])
def test_y_junction(d):
    arms = [line(np.zeros(d), np.r_[np.cos(a), np.sin(a), np.zeros(d - 2)], 30)[1:] for a in (0.3, 2.4, 4.3)]
    p = np.vstack([np.zeros((1, d))] + arms)
    net = reconstruct_emst(p)
    assert net.n_nodes == 4 and net.n_curves == 3
    assert sorted(net.valence.tolist()) == [1, 1, 1, 3]
    centre = net.nodes[net.valence == 3][0]
    assert np.allclose(centre, 0.0)


def test_circle_is_opened_never_a_loop():
    t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    net = reconstruct_emst(np.column_stack([np.cos(t), np.sin(t)]))
    assert net.n_curves == 1 and net.n_nodes == 2 and not net.curves[0].closed
    assert net.betti == (1, 0)


def test_disconnected_knn_graph_gives_a_forest():
    p = np.vstack([line((0, 0), (1, 0), 30), line((0, 5), (1, 5), 30)])
    net = reconstruct_emst(p, k=5)
    assert net.n_curves == 2 and net.n_nodes == 4 and net.betti == (2, 0)
    assert len(emst_edges(p, k=5)) == 58


def test_independent_of_point_order():
    rng = np.random.default_rng(1)
    p = np.vstack([line((0, 0), (1, 0), 50), line((0.5, 0), (0.5, 1), 50)[1:]]) + rng.normal(0, 0.003, (99, 2))
    a = reconstruct_emst(p).canonical()
    b = reconstruct_emst(p[rng.permutation(len(p))]).canonical()
    assert np.array_equal(a.nodes, b.nodes)
    assert len(a.curves) == len(b.curves)
    for x, y in zip(a.curves, b.curves):
        assert np.array_equal(x.points, y.points)


def test_equal_edge_lengths_and_duplicates():
    # a regular grid row has only tied lengths; duplicates have length zero
    p = np.vstack([line((0, 0), (1, 0), 11), [[0.5, 0.0]]])
    net = reconstruct_emst(p)
    assert sum(len(c.points) for c in net.curves) - (net.n_curves - 1) >= 12 - 2
    assert net.betti[0] == 1


def test_registered_and_parameters():
    p = line((0, 0), (1, 1), 20)
    net = reconstruct(p, method="emst", k=8)
    assert net.parameters["k"] == 8 and net.parameters["method"] == "emst"
    assert "tracing" in net.stats["time"]
    with pytest.raises(InputError):
        reconstruct_emst(p, k=0)


def test_single_point():
    net = reconstruct_emst(np.zeros((1, 3)))
    assert net.n_nodes == 1 and net.n_curves == 0


def test_order_invariance_random_points():
    hyp = pytest.importorskip("hypothesis")
    st = pytest.importorskip("hypothesis.strategies")
    from hypothesis.extra.numpy import arrays

    @hyp.settings(max_examples=25, deadline=None)
    @hyp.given(
        arrays(np.float64, st.tuples(st.integers(2, 40), st.sampled_from([2, 3])),
               elements=st.integers(-20, 20).map(lambda v: v / 4.0)),
        st.randoms(use_true_random=False),
    )
    def check(p, rnd):
        perm = list(range(len(p)))
        rnd.shuffle(perm)
        a = reconstruct_emst(p).canonical()
        b = reconstruct_emst(p[perm]).canonical()
        assert np.array_equal(a.nodes, b.nodes)
        assert [c.points.tolist() for c in a.curves] == [c.points.tolist() for c in b.curves]
        # a spanning forest: every point lies on a curve or is a node
        n_pts = len(np.unique(p, axis=0))
        covered = {tuple(x) for c in a.curves for x in c.points} | {tuple(x) for x in a.nodes}
        assert len(covered) == n_pts

    check()


def test_edges_as_from_a_coo_graph():
    """The graph handed to the spanning tree is built as CSR directly: the same tree as through
    scipy's COO conversion (the code this replaced), ties and duplicates included."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import minimum_spanning_tree

    from curvenet.neighbors import knn

    rng = np.random.default_rng(1)
    for t in range(120):
        n, d, k = int(rng.integers(2, 120)), int(rng.integers(2, 4)), int(rng.integers(1, 14))
        X = np.cumsum(rng.normal(size=(n, d)), 0) if t % 3 else np.round(rng.uniform(0, 5, size=(n, d)))
        dist, idx = knn(X, k)
        rows = np.repeat(np.arange(n), idx.shape[1])
        i, j = np.minimum(rows, idx.ravel()), np.maximum(rows, idx.ravel())
        w = dist.ravel() + max(float(np.median(dist[:, 0])), 1e-300) * 1e-9
        uk, first = np.unique(i * n + j, return_index=True)
        tree = minimum_spanning_tree(coo_matrix((w[first], (uk // n, uk % n)), shape=(n, n)).tocsr()).tocoo()
        e = np.column_stack([np.minimum(tree.row, tree.col), np.maximum(tree.row, tree.col)]).astype(np.int64)
        np.testing.assert_array_equal(emst_edges(X, k=k), e[np.lexsort(e.T[::-1])])


def _sets(seed=3):
    """Point sets of every awkward kind: random, on a grid (many equal lengths), on a line,
    with duplicated points, and of 0, 1 and 2 points; 2D and 3D mixed."""
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(np.arange(6.0), np.arange(5.0), np.arange(3.0)), -1).reshape(-1, 3)
    out = [np.zeros((0, 3)), np.zeros((1, 2)), rng.normal(size=(2, 3)), grid, grid[::-1].copy()]
    for n in (5, 17, 60, 150):
        out.append(rng.normal(size=(n, 3)))
        out.append(np.c_[np.arange(n) * 1.0, np.zeros(n)])
        x = rng.uniform(0, 10, (n, 2))
        out.append(np.r_[x, x[: n // 4]])  # duplicates
    return out


def test_emst_of_many_sets_at_once_equals_one_set_at_a_time():
    from curvenet.methods.emst import emst_edges_each

    sets = _sets()
    ks = [1 + i % 11 for i in range(len(sets))]
    together = emst_edges_each(sets, ks)
    assert len(together) == len(sets)
    for X, k, e in zip(sets, ks, together):
        alone = emst_edges_each([X], [k])[0]
        np.testing.assert_array_equal(e, alone)
        assert e.dtype == np.int64 and e.shape == (max(len(X) - 1, 0), 2) or k < len(X) - 1


def test_emst_of_many_sets_is_each_sets_exact_spanning_tree():
    from scipy.sparse.csgraph import minimum_spanning_tree
    from scipy.spatial.distance import cdist

    from curvenet.methods.emst import emst_edges_each

    rng = np.random.default_rng(7)
    sets = [rng.normal(size=(n, 3)) for n in (3, 9, 40, 90)]  # distinct lengths: one EMST each
    for X, e in zip(sets, emst_edges_each(sets, [len(X) - 1 for X in sets])):
        t = minimum_spanning_tree(np.triu(cdist(X, X))).tocoo()
        ref = np.sort(np.column_stack([t.row, t.col]), axis=1)
        np.testing.assert_array_equal(e, ref[np.lexsort(ref.T[::-1])])
