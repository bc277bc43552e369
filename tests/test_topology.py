"""The Topology of the robust method on tiny hand-built cases: every method, and its invariants.

Points are in units of the sampling spacing (h = 1). The main case is a T: a junction region
``J`` (one point at the origin) with three chains of four points (left, right, up), whose far
ends get empty free-end regions from the constructor.
"""

from __future__ import annotations

import numpy as np
import pytest

from curvenet.methods.robust.chains import Chain
from curvenet.methods.robust.topology import Topology, TopologyError

J = 0  # the junction region of the T
LEFT, RIGHT, UP = 0, 1, 2  # its chains


def _ids(a, b):
    return np.arange(a, b, dtype=np.int64)


def _t_shape():
    """The T: point 0 the junction, 1-4 left, 5-8 right, 9-12 up (chain ids run as listed)."""
    P = np.array([[0, 0]] + [[-x, 0] for x in (4, 3, 2, 1)] + [[x, 0] for x in (1, 2, 3, 4)]
                 + [[0, y] for y in (1, 2, 3, 4)], dtype=float)
    chains = [Chain(_ids(1, 5), [-1, J]),  # left: from its free end towards J
              Chain(_ids(5, 9), [J, -1]),  # right: from J out
              Chain(_ids(9, 13), [J, -1])]  # up: from J out
    return Topology(P, chains, [np.array([0], dtype=np.int64)])


@pytest.fixture
def t_shape():
    return _t_shape()


def _regions_of_ends(topo):
    return [list(c.ends) for c in topo.chains]


# ------------------------------------------------------------------------------ construction
def test_constructor_gives_free_ends_empty_regions(t_shape):
    topo = t_shape
    # the three open far ends get regions 1, 2, 3 in chain order
    assert _regions_of_ends(topo) == [[1, J], [J, 2], [J, 3]]
    assert len(topo.regions) == 4
    assert [len(r) for r in topo.regions] == [1, 0, 0, 0]
    assert topo.v.tolist() == [3, 1, 1, 1]
    assert topo.incident(J) == [(LEFT, 1), (RIGHT, 0), (UP, 0)]
    assert topo.incident(1) == [(LEFT, 0)]
    assert all(topo.listed(r) for r in range(4))
    assert topo.live() == topo.chains
    topo.check()


def test_constructor_leaves_closed_chains_without_regions():
    P = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 8, endpoint=False)]) * 2
    topo = Topology(P, [Chain(_ids(0, 8), [-1, -1], closed=True)], [])
    assert topo.regions == [] and topo.v.tolist() == []
    assert topo.chains[0].ends == [-1, -1]
    topo.check()


def test_end_ids_run_towards_the_end(t_shape):
    topo = t_shape
    assert topo.end_ids(LEFT, 1).tolist() == [1, 2, 3, 4]  # towards J
    assert topo.end_ids(LEFT, 0).tolist() == [4, 3, 2, 1]  # towards the free end
    assert topo.end_ids(UP, 0).tolist() == [12, 11, 10, 9]


def test_valence_counts_live_open_ends_only(t_shape):
    topo = t_shape
    topo.alive[UP] = False  # by hand: the kept valence is now stale, the counted one is not
    assert topo.valence().tolist() == [2, 1, 1, 0]
    with pytest.raises(TopologyError, match="valence"):
        topo.check()


# ------------------------------------------------------------------------------ changes
def test_absorb_moves_points_ends_and_valence(t_shape):
    topo = t_shape
    topo.regions[3] = np.array([12], dtype=np.int64)  # (a point for the up chain's free end)
    topo.chains[UP].ids = _ids(9, 12)
    topo.absorb(3, J)
    assert topo.regions[J].tolist() == [0, 12] and len(topo.regions[3]) == 0
    assert topo.chains[UP].ends == [J, J]  # the up chain is now a loop at J
    assert topo.v.tolist() == [4, 1, 1, 0]
    assert topo.incident(J) == [(LEFT, 1), (RIGHT, 0), (UP, 0), (UP, 1)]  # arrival order kept
    assert topo.incident(3) == [] and not topo.listed(3)
    topo.check()


def test_absorb_refuses_a_region_into_itself(t_shape):
    # (it looped for ever, appending to the list it walked)
    with pytest.raises(TopologyError, match="into itself"):
        t_shape.absorb(J, J)


def test_absorb_leaves_dead_chain_ends_behind(t_shape):
    topo = t_shape
    topo.drop(RIGHT)
    topo.absorb(2, 1)  # the dead right chain's free end merges into the left one's
    assert topo.chains[RIGHT].ends == [J, 2]  # a dead chain's ends do not move
    assert topo.v.tolist() == [2, 1, 0, 1]
    assert topo.incident(1) == [(LEFT, 0)]
    topo.check()


def test_absorb_chain_puts_its_points_into_the_region(t_shape):
    topo = t_shape
    topo.absorb_chain(UP, J)
    assert not topo.alive[UP]
    assert topo.regions[J].tolist() == [0, 9, 10, 11, 12]
    assert topo.v.tolist() == [2, 1, 1, 0]
    assert topo.incident(J) == [(LEFT, 1), (RIGHT, 0)]
    assert topo.incident(3) == [] and topo.listed(3)  # the dead end stays listed there
    assert len(topo.live()) == 2
    topo.check()


def test_drop_lowers_the_valence_at_both_ends(t_shape):
    topo = t_shape
    topo.drop(RIGHT)
    assert topo.alive == [True, False, True]
    assert topo.v.tolist() == [2, 1, 0, 1]
    assert topo.incident(J) == [(LEFT, 1), (UP, 0)]
    assert topo.live() == [topo.chains[LEFT], topo.chains[UP]]
    topo.check()


def test_join_through_makes_two_chains_one(t_shape):
    topo = t_shape
    topo.drop(UP)
    topo.join_through(J, topo.incident(J))
    c = topo.chains[LEFT]
    # left (towards J), J's point, right (from J): one curve along x, ascending
    assert c.ids.tolist() == [1, 2, 3, 4, 0, 5, 6, 7, 8]
    assert np.all(np.diff(topo.P[c.ids, 0]) > 0)
    assert c.ends == [1, 2] and not c.closed
    assert topo.alive == [True, False, False]
    assert len(topo.regions[J]) == 0
    assert topo.v.tolist() == [0, 1, 1, 0]
    assert topo.incident(1) == [(LEFT, 0)] and topo.incident(2) == [(LEFT, 1)]
    topo.check()


def test_join_through_orders_the_region_points_between_the_ends(t_shape):
    topo = t_shape
    topo.drop(UP)
    topo.regions[J] = np.array([10, 0, 9], dtype=np.int64)  # (points off the line: order by projection)
    topo.P[[9, 10]] = [[0.5, 0.2], [-0.5, -0.2]]
    topo.join_through(J, topo.incident(J))
    assert topo.chains[LEFT].ids.tolist() == [1, 2, 3, 4, 10, 0, 9, 5, 6, 7, 8]
    topo.check()


def test_join_through_one_chain_closes_a_loop():
    # a U from region 0 back to it: region 0 holds the point that closes it
    P = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2], [0, 1]], dtype=float)
    topo = Topology(P, [Chain(_ids(0, 7), [0, 0])], [np.array([7], dtype=np.int64)])
    assert topo.v.tolist() == [2]
    topo.join_through(0, topo.incident(0))
    c = topo.chains[0]
    # the first end listed (the chain's start) runs in: the chain reversed, then the region
    assert c.closed and c.ids.tolist() == [6, 5, 4, 3, 2, 1, 0, 7]
    assert topo.v.tolist() == [0] and len(topo.regions[0]) == 0
    topo.check()


def _bar_and_stem():
    """A bar (9 points along x, free ends) and a stem below its middle, tip at (0, -2)."""
    P = np.array([[x, 0] for x in range(-4, 5)] + [[0, -y] for y in (5, 4, 3, 2)], dtype=float)
    chains = [Chain(_ids(0, 9), [-1, -1]), Chain(_ids(9, 13), [-1, -1])]
    return Topology(P, chains, [])


def test_split_chain_makes_a_junction_in_the_middle():
    topo = _bar_and_stem()
    assert _regions_of_ends(topo) == [[0, 1], [2, 3]]
    core = topo.split_chain(0, 3, 6, 1, 1)  # the bar's points 3..5 (x = -1, 0, 1), the stem's tip
    assert core.tolist() == [3, 4, 5]
    nr = 4
    assert topo.regions[nr].tolist() == [3, 4, 5] and len(topo.regions[3]) == 0
    assert [c.ids.tolist() for c in topo.chains] == [[0, 1, 2], [9, 10, 11, 12], [6, 7, 8]]
    assert _regions_of_ends(topo) == [[0, nr], [2, nr], [nr, 1]]
    assert topo.alive == [True, True, True]
    assert topo.v.tolist() == [1, 1, 1, 0, 3]
    assert topo.incident(nr) == [(1, 1), (0, 1), (2, 0)]
    assert topo.incident(1) == [(2, 1)] and not topo.listed(3)
    topo.check()


def test_join_regions_adds_a_chain_between_two_regions(t_shape):
    # the free ends of the right and up chains joined by a new chain (a cell's side found again)
    topo = t_shape
    right_end, up_end = topo.chains[RIGHT].ends[1], topo.chains[UP].ends[1]
    P = np.r_[topo.P, [[3.0, 3.0]]]  # (one point between the two tips)
    topo.P = P
    j = topo.join_regions(right_end, up_end, np.array([13], dtype=np.int64))
    assert j == 3 and topo.chains[j].ends == [right_end, up_end] and topo.alive[j]
    assert topo.v[right_end] == 2 and topo.v[up_end] == 2 and topo.v[J] == 3
    assert topo.incident(right_end) == [(RIGHT, 1), (j, 0)] and topo.incident(up_end) == [(UP, 1), (j, 1)]
    assert topo.v.tolist() == topo.valence().tolist()
    topo.check()


def test_free_branch_adds_a_chain_to_a_new_free_end(t_shape):
    # a free branch that lay inside the junction's region (a comb's tooth under noise): one
    # point beside the junction, split out as a chain to a new empty free-end region
    topo = t_shape
    topo.P = np.r_[topo.P, [[-1.0, -1.0]]]
    n = len(topo.regions)
    j = topo.free_branch(J, np.array([13], dtype=np.int64))
    assert j == 3 and topo.chains[j].ends == [J, n] and topo.alive[j]
    assert len(topo.regions) == n + 1 and len(topo.regions[n]) == 0
    assert topo.v[J] == 4 and topo.v[n] == 1
    assert topo.v.tolist() == topo.valence().tolist()
    topo.check()


def test_extend_end_takes_region_points_onto_the_chain(t_shape):
    # the up chain read short of its junction: two region points between it and the junction
    # join it at its start (ordered from its end into the region), the region keeps the rest
    topo = t_shape
    topo.P = np.r_[topo.P, [[0.0, 0.7], [0.0, 0.4]]]
    topo.regions[J] = np.array([0, 14, 13], dtype=np.int64)
    topo.extend_end(UP, 0, np.array([13, 14], dtype=np.int64))
    assert topo.chains[UP].ids.tolist() == [14, 13, 9, 10, 11, 12]
    assert topo.regions[J].tolist() == [0]
    assert topo.v[J] == 3 and topo.chains[UP].ends == [J, topo.chains[UP].ends[1]]
    topo.extend_end(RIGHT, 1, np.zeros(0, dtype=np.int64))  # (nothing to take: unchanged)
    assert topo.chains[RIGHT].ids.tolist() == [5, 6, 7, 8]
    topo.check()


def test_split_chain_takes_the_free_ends_region_points_along():
    topo = _bar_and_stem()
    topo.chains[1].ids = _ids(9, 12)  # the tip point (0, -2) is the stem's free-end region
    topo.regions[3] = np.array([12], dtype=np.int64)
    topo.split_chain(0, 3, 6, 1, 1)
    assert topo.regions[4].tolist() == [3, 4, 5, 12]
    topo.check()


def test_split_chain_opens_a_closed_chain():
    a = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    P = np.r_[np.c_[4 * np.cos(a), 4 * np.sin(a)], [[6.5, 0], [7.5, 0], [8.5, 0]]]
    topo = Topology(P, [Chain(_ids(0, 12), [-1, -1], closed=True), Chain(np.array([14, 13, 12]), [-1, -1])], [])
    assert topo.v.tolist() == [1, 1]
    topo.split_chain(0, 11, 12, 1, 1)  # at point 11, just below the stem's tip direction
    c = topo.chains[0]
    assert c.ids.tolist() == list(range(11)) and c.ends == [2, 2] and not c.closed
    assert len(topo.chains) == 2
    assert topo.v.tolist() == [1, 0, 3]
    assert topo.incident(2) == [(1, 1), (0, 0), (0, 1)]
    topo.check()


def test_cross_splits_a_chain_through_a_region():
    # the bar's points 3..5 join the T's junction region J of valence 2 (chains up and down)
    P = np.array([[x, 0] for x in range(-4, 5)] + [[0, 1], [0, -1]] + [[0, y] for y in (2, 3)]
                 + [[0, -y] for y in (2, 3)], dtype=float)
    chains = [Chain(_ids(0, 9), [-1, -1]), Chain(_ids(11, 13), [0, -1]), Chain(_ids(13, 15), [0, -1])]
    topo = Topology(P, chains, [np.array([9, 10], dtype=np.int64)])
    assert topo.v.tolist() == [2, 1, 1, 1, 1]
    topo.cross(0, 0, 3, 6)
    assert topo.regions[0].tolist() == [9, 10, 3, 4, 5]
    assert [c.ids.tolist() for c in topo.chains] == [[0, 1, 2], [11, 12], [13, 14], [6, 7, 8]]
    assert _regions_of_ends(topo) == [[1, 0], [0, 3], [0, 4], [0, 2]]  # (the bar's free ends: 1 and 2)
    assert topo.v.tolist() == [4, 1, 1, 1, 1]
    assert topo.incident(0) == [(1, 0), (2, 0), (0, 1), (3, 0)] and topo.incident(2) == [(3, 1)]
    topo.check()


# ------------------------------------------------------------------------------ broken states
def test_check_rejects_an_end_not_listed_at_its_region(t_shape):
    t_shape._ends_at[J].remove((UP, 0))
    with pytest.raises(TopologyError, match="chain 2 end 0 is not listed at its region 0"):
        t_shape.check()


def test_check_rejects_an_end_at_no_region(t_shape):
    t_shape.chains[RIGHT].ends[1] = 99
    with pytest.raises(TopologyError, match="chain 1 end 1 at region 99"):
        t_shape.check()


def test_check_rejects_a_valence_that_disagrees(t_shape):
    t_shape.v[J] += 1
    with pytest.raises(TopologyError, match="valence"):
        t_shape.check()


def test_check_rejects_a_point_on_two_live_chains(t_shape):
    t_shape.chains[UP].ids = np.r_[t_shape.chains[UP].ids, 5]  # the right chain's first point
    with pytest.raises(TopologyError, match="two live chains"):
        t_shape.check()
    t_shape.drop(RIGHT)  # once one of them is dead, it is no longer shared
    t_shape.check()


def test_check_rejects_lists_of_different_lengths(t_shape):
    t_shape.regions.append(np.zeros(0, dtype=np.int64))
    with pytest.raises(TopologyError, match="differ in length"):
        t_shape.check()


def test_check_ignores_dead_chains(t_shape):
    t_shape.drop(UP)
    t_shape._ends_at[J].remove((UP, 0))  # a dead chain's end need not be listed
    t_shape.chains[UP].ids = t_shape.chains[LEFT].ids  # nor own its points
    t_shape.check()


@pytest.mark.parametrize("flag, raises", [("1", True), ("", False)])
def test_every_change_checks_when_asked(monkeypatch, t_shape, flag, raises):
    """With CURVENET_CHECK_TOPOLOGY=1 each method checks the invariants after its change."""
    monkeypatch.setenv("CURVENET_CHECK_TOPOLOGY", flag)
    t_shape.v[1] += 5  # broken by hand; the drop below does not touch region 1
    if raises:
        with pytest.raises(TopologyError, match="valence"):
            t_shape.drop(UP)
    else:
        t_shape.drop(UP)
        assert t_shape.v.tolist() == [2, 6, 1, 0]
