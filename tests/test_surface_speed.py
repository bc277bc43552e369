"""The surfacing's fast paths give what the plain computations give (issue 24, speed)."""

import numpy as np
import pytest

from curvenet.surfacing.assemble import _edge_keys
from curvenet.surfacing.crossings import _pairs_touching
from curvenet.surfacing.patches import _gap_table, min_area_triangulation, min_area_triangulations


def _brute_pairs(pa, ra, ga, pb, rb, gb, only, within):
    d = np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=2)
    ok = d <= ra[:, None] + rb[None, :]
    same = ga[:, None] == gb[None, :]
    if within is not None:
        ok &= ~same | np.isin(ga, list(within))[:, None]
    if only is not None:
        ok &= np.isin(ga, list(only))[:, None] | np.isin(gb, list(only))[None, :]
    return set(zip(*(x.tolist() for x in np.nonzero(ok))))


@pytest.mark.parametrize("only, within", [(None, None), (None, set()), ({1}, set()), ({0, 2}, {1}), (None, {3})])
def test_pairs_touching_is_brute_force(only, within):
    rng = np.random.default_rng(3)
    pa, pb = rng.random((300, 3)), rng.random((250, 3))
    # radii spread over several size levels, groups as patches
    ra, rb = 0.01 * 2.0 ** rng.integers(0, 5, 300), 0.01 * 2.0 ** rng.integers(0, 5, 250)
    ga, gb = rng.integers(0, 4, 300), rng.integers(0, 4, 250)
    i, j = _pairs_touching(pa, ra, ga, pb, rb, gb, only, within=within)
    got = list(zip(i.tolist(), j.tolist()))
    assert len(got) == len(set(got))  # each pair once
    want = _brute_pairs(pa, ra, ga, pb, rb, gb, only, within)
    assert want and set(got) == want


def test_pairs_touching_far_groups_and_empty():
    pa = np.array([[0.0, 0, 0], [10.0, 0, 0]])
    r = np.full(2, 0.1)
    i, j = _pairs_touching(pa, r, np.array([0, 1]), pa, r, np.array([0, 1]), None, within=set())
    assert len(i) == 0  # each ball meets only its own group's
    i, j = _pairs_touching(pa, r, np.array([0, 1]), pa, r, np.array([0, 1]), None, within=None)
    assert sorted(zip(i.tolist(), j.tolist())) == [(0, 0), (1, 1)]
    i, j = _pairs_touching(pa[:0], r[:0], np.zeros(0, int), pa, r, np.array([0, 1]), None)
    assert len(i) == 0


def test_edge_keys_match_unique_rows():
    rng = np.random.default_rng(0)
    T = rng.integers(0, 40, (200, 3))
    u, inv, cnt = _edge_keys(T, 40)
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    u0, inv0, cnt0 = np.unique(e, axis=0, return_inverse=True, return_counts=True)
    assert np.array_equal(u, u0) and np.array_equal(inv, inv0.ravel()) and np.array_equal(cnt, cnt0)


@pytest.mark.parametrize("n", [3, 4, 5, 9, 17])
def test_gap_table_lists_every_triple_once(n):
    I, K, J, start, IK, KJ = _gap_table(n)
    triples = set(zip(I.tolist(), K.tolist(), J.tolist()))
    assert len(triples) == len(I) == n * (n - 1) * (n - 2) // 6
    assert all(i < k < j for i, k, j in triples)
    for gap in range(2, n):
        lo, hi = start[gap], start[gap] + (n - gap) * (gap - 1)
        assert (J[lo:hi] - I[lo:hi] == gap).all()
    assert np.array_equal(IK, I * n + K) and np.array_equal(KJ, K * n + J)


def _reference_mat(p):
    """The dynamic program written out with loops (ties: the smallest k)."""
    n = len(p)

    def area(i, k, j):
        return 0.5 * np.linalg.norm(np.cross(p[k] - p[i], p[j] - p[i]))

    W = np.zeros((n, n))
    for gap in range(2, n):
        for i in range(n - gap):
            j = i + gap
            W[i, j] = min(W[i, k] + W[k, j] + area(i, k, j) for k in range(i + 1, j))
    return W[0, n - 1]


def test_batched_triangulations_equal_single_ones():
    rng = np.random.default_rng(7)
    polys = rng.normal(size=(5, 12, 3))
    areas, tris = min_area_triangulations(polys)
    for p, a, t in zip(polys, areas, tris):
        a1, t1 = min_area_triangulation(p)
        assert a == a1 and np.array_equal(t, t1)  # bit for bit, alone or in a batch
        assert a == pytest.approx(_reference_mat(p), rel=1e-12)
        assert len(t) == 10 and len({tuple(sorted(x)) for x in t.tolist()}) == 10


def _brute_overlaps(V, T, P, distance, folds):
    """Every (triangle centroid, other triangle) pair tested, no broad phase."""
    cen = V[T].mean(axis=1)
    t, j = (x.ravel() for x in np.meshgrid(np.arange(len(T)), np.arange(len(T)), indexing="ij"))
    shared = (T[t][:, :, None] == T[j][:, None, :]).any(axis=(1, 2))
    ok = (P[t] != P[j]) | (np.isin(P[t], list(folds)) & ~shared)
    a, b, c = V[T[j, 0]], V[T[j, 1]], V[T[j, 2]]
    n = np.cross(b - a, c - a)
    nn = np.linalg.norm(n, axis=1)
    x = cen[t]
    with np.errstate(invalid="ignore", divide="ignore"):
        ok &= (nn > 0) & (np.abs(np.einsum("ij,ij->i", x - a, n)) / nn < distance)
    for p, q in ((a, b), (b, c), (c, a)):
        ok &= np.einsum("ij,ij->i", np.cross(q - p, x - p), n) >= 0
    seen = set(zip(t[ok].tolist(), P[j[ok]].tolist()))
    count = {}
    for tt, q in seen:
        key = (min(int(P[tt]), q), max(int(P[tt]), q))
        count[key] = count.get(key, 0) + 1
    return sorted(count), len({tt for tt, _ in seen})


@pytest.mark.parametrize("folds", [(), (0,), (0, 1, 2)])
def test_overlapping_patches_is_brute_force(folds):
    from curvenet.surfacing.crossings import overlapping_patches

    rng = np.random.default_rng(11)
    # three patches of small triangles (about 0.02 across) scattered in a slab 0.05 thick: many
    # lie over each other within the distance 0.03, off their planes by more than their size
    base = rng.random((300, 3)) * [0.2, 0.2, 0.05]
    V = np.repeat(base, 3, axis=0) + rng.normal(scale=0.02, size=(900, 3)) * [1.0, 1.0, 0.05]
    T = np.arange(900).reshape(300, 3)
    P = rng.integers(0, 3, 300)
    got = overlapping_patches(V, T, P, np.zeros((0, 3)), distance=0.03, margin=0.0, folds=set(folds))
    want = _brute_overlaps(V, T, P, 0.03, set(folds))
    assert want[1] > 0 and got == want


@pytest.mark.parametrize("clip", [True, False])
def test_laplacian_from_shared_weights_is_cotan_laplacian(clip):
    from scipy.sparse import coo_matrix

    from curvenet.surfacing.patches import _cotan_weights, _laplacian, cotan_laplacian

    triangle = pytest.importorskip("triangle")
    rng = np.random.default_rng(5)
    V = rng.random((60, 2))
    T = np.asarray(triangle.triangulate({"vertices": V}, "Q")["triangles"], dtype=np.int64)
    L, M = cotan_laplacian(V, T, clip=clip)
    Wm, M2 = _cotan_weights(V, T)
    L2 = _laplacian(Wm, clip)
    assert np.array_equal(M, M2) and (L != L2).nnz == 0
    assert (_laplacian(Wm, not clip) != L).nnz > 0  # hull edges opposite obtuse angles: clipping matters
    # the lumped mass is a third of the incident triangle areas, summed
    u, w = V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]
    area = 0.5 * np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])
    assert M == pytest.approx(coo_matrix((np.repeat(area / 3, 3), (T.ravel(), np.zeros(3 * len(T), int))), shape=(60, 1)).toarray().ravel())
    assert np.allclose(L @ np.ones(60), 0.0)
