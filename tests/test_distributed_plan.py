"""Plans of curves over the tiles' stored pieces (curvenet.distributed.plan): read back as the
arrays they stand for, turned and ordered as CurveNetwork.canonical turns and orders."""

from __future__ import annotations

import numpy as np

from curvenet.distributed.plan import CurvePlan, PieceStore, Span, StoredNetwork
from curvenet.distributed.scratch import write_pieces
from curvenet.network import Curve, CurveNetwork


def _store(tmp_path, rng):
    A = rng.random((30, 3))
    B = rng.random((20, 3))
    write_pieces(tmp_path, (0, 0, 0), A, np.arange(30))
    write_pieces(tmp_path, (1, 0, 0), B, 100 + np.arange(20))
    return PieceStore(tmp_path, [(0, 0, 0), (1, 0, 0)], 3), A, B


def test_spans_read_rows_forwards_and_backwards(tmp_path):
    store, A, B = _store(tmp_path, np.random.default_rng(0))
    plan = CurvePlan([Span(0, 3, 9), Span(1, 5, 12, rev=True), Span(0, 20, 21)], 4, 7)
    c = store.curve(plan)
    want = np.vstack([A[3:9], B[5:12][::-1], A[20:21]])
    assert np.array_equal(c.points, want) and plan.size == len(want)
    assert np.array_equal(c.indices, np.r_[np.arange(3, 9), 100 + np.arange(5, 12)[::-1], 20])
    r = store.curve(plan.reversed())
    assert np.array_equal(r.points, want[::-1]) and (r.start, r.end) == (7, 4)
    s = store.keep(Curve(want, 1, 2, False, c.indices))  # the client's own file
    assert np.array_equal(store.curve(s).points, want) and np.array_equal(store.curve(s).indices, c.indices)


def test_canonical_is_the_network_canonical(tmp_path):
    rng = np.random.default_rng(1)
    store, A, B = _store(tmp_path, rng)
    nodes = rng.random((4, 3))
    plans = [
        CurvePlan([Span(0, 0, 6)], 3, 1),                         # turned by its node ids
        CurvePlan([Span(1, 0, 8, rev=True)], 1, 3),               # same ends: ordered by points
        CurvePlan([Span(0, 6, 15), Span(1, 8, 12)], 2, 2),        # a loop through one node
        CurvePlan([Span(0, 15, 30)], None, None, True),           # a free loop: rolled
        CurvePlan([Span(1, 12, 20, rev=True)], 0, 2),
    ]
    stored = StoredNetwork(nodes, plans, store, {"p": 1}, {"s": 2})
    mem = stored.network()
    a = stored.canonical().network()
    b = mem.canonical()
    assert a == b and a.n_curves == 5
    assert stored.betti == mem.betti and np.array_equal(stored.edges, mem.edges)
    sizes, s, e, closed = stored.curve_shapes()
    assert sizes.tolist() == [len(c.points) for c in mem.curves] and closed.tolist() == [c.closed for c in mem.curves]


def test_order_by_ends_is_the_sort_by_the_whole_key():
    """The polyline order compares a prefix first: the order of the sort by every coordinate,
    with curves that tie on the prefix, short curves and equal curves among them."""
    from curvenet import network

    rng = np.random.default_rng(2)
    pts = []
    for i in range(300):
        m = int(rng.integers(1, 8))
        p = rng.integers(0, 2, size=(m, 3)).astype(float)  # many ties
        if i % 7 == 0 and pts:
            p = np.vstack([pts[-1][:4], p])  # the same first points as another
        pts.append(p)
    ends = rng.integers(-1, 2, size=(300, 1)).repeat(2, axis=1)
    got = network.order_by_ends(ends, lambda i: pts[i], 6)
    want = sorted(range(300), key=lambda i: (int(ends[i, 0]), int(ends[i, 1]), tuple(np.round(pts[i], 6).ravel().tolist())))
    assert got == want
