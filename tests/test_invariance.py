"""Issue 7, property tests: the network does not depend on the order, position, orientation or
scale of the input points; every curve ends at its nodes; no input point is used twice."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import curvenet
from curvenet.reconstruct import METHODS

PROPS = settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _frame_points():
    """A small network with junctions of valence 3 and 4, a free end and a loop through a node."""
    rng = np.random.default_rng(5)
    h = 0.05
    segs = []
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]], float)
    for a, b in zip(square[:-1], square[1:]):
        segs.append((a, b))
    segs.append((np.array([0.0, 0, 0]), np.array([0.0, 0, 1])))  # vertical post with a free end
    segs.append((np.array([1.0, 1, 0]), np.array([1.6, 1.5, 0.4])))  # spur
    pts = []
    for a, b in segs:
        n = int(np.ceil(np.linalg.norm(b - a) / h))
        t = (np.arange(n) + 0.5) / n
        pts.append(a + t[:, None] * (b - a))
    th = np.linspace(0, 2 * np.pi, int(2 * np.pi * 0.35 / h), endpoint=False)  # loop through (1,0,0)
    pts.append(np.column_stack([1.35 + 0.35 * np.cos(th + np.pi), 0.35 * np.sin(th + np.pi), np.zeros_like(th)])[1:])
    pts = np.vstack(pts)
    pts += rng.normal(scale=0.03 * h, size=pts.shape)
    return pts


POINTS = _frame_points()
METHOD_NAMES = [m for m in ("robust", "paper") if m in METHODS]


def _signature(net, point_map=None):
    """Order-free description: per curve its sorted input indices (mapped), with node positions."""
    curves = []
    for c in net.curves:
        idx = c.indices[c.indices >= 0]
        if point_map is not None:
            idx = point_map[idx]
        curves.append(tuple(sorted(idx.tolist())))
    return sorted(curves)


def _check_structure(net, pts):
    for c in net.curves:
        if c.start is not None:
            np.testing.assert_allclose(c.points[0], net.nodes[c.start], atol=1e-9)
            np.testing.assert_allclose(c.points[-1], net.nodes[c.end], atol=1e-9)
        else:
            assert c.closed
        ok = c.indices >= 0
        np.testing.assert_allclose(c.points[ok], pts[c.indices[ok]], atol=1e-9)
    used = np.concatenate([c.indices[c.indices >= 0] for c in net.curves] or [np.zeros(0, int)])
    # a point may stand at both ends of a closed curve or be a node shared by curves; inner points are not shared
    inner = np.concatenate([c.indices[1:-1][c.indices[1:-1] >= 0] for c in net.curves] or [np.zeros(0, int)])
    assert len(np.unique(inner)) == len(inner), "an input point is inside two curves"
    return used


def _match_nodes(a, b, tol):
    from scipy.optimize import linear_sum_assignment

    assert len(a) == len(b)
    if not len(a):
        return
    d = np.linalg.norm(a[:, None] - b[None], axis=2)
    r, c = linear_sum_assignment(d)
    assert d[r, c].max() <= tol, d[r, c].max()


@pytest.fixture(scope="module", params=METHOD_NAMES)
def base(request):
    net = curvenet.reconstruct(POINTS, method=request.param)
    _check_structure(net, POINTS)
    return request.param, net


@PROPS
@given(seed=st.integers(0, 2**32 - 1))
def test_permutation(base, seed):
    method, net = base
    perm = np.random.default_rng(seed).permutation(len(POINTS))
    net2 = curvenet.reconstruct(POINTS[perm], method=method)
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))
    # net2's index j is original point perm[j]
    assert _signature(net2, perm) == _signature(net)
    _match_nodes(net.nodes, net2.nodes, 1e-9)


@PROPS
@given(
    quat=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
    shift=st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3),
    scale=st.floats(1e-3, 1e3),
)
def test_rigid_motion_and_scale(base, quat, shift, scale):
    method, net = base
    R = Rotation.from_quat(quat).as_matrix()
    moved = scale * POINTS @ R.T + np.asarray(shift)
    net2 = curvenet.reconstruct(moved, method=method)
    _check_structure(net2, moved)
    assert _signature(net2) == _signature(net)
    _match_nodes(scale * net.nodes @ R.T + np.asarray(shift), net2.nodes, 1e-6 * scale + 1e-9 * np.abs(shift).max())
