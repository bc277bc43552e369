"""Issue 7: degenerate but valid input gets a sensible result, not an error (default method)."""

import numpy as np
import pytest

import curvenet


def _line(n=60, h=0.01, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * h
    p = np.column_stack([t, 0.5 * t, -0.25 * t])
    return p + rng.normal(scale=noise * h, size=p.shape)


def _circle(n=120, r=1.0, seed=0, noise=0.05):
    rng = np.random.default_rng(seed)
    th = np.sort(rng.uniform(0, 2 * np.pi, n))
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    p = np.column_stack([r * np.cos(th), r * np.sin(th), np.zeros(n)])
    return p + rng.normal(scale=noise * 2 * np.pi * r / n, size=p.shape)


def _assert_one_open_curve(net, pts):
    assert net.n_curves == 1 and net.n_nodes == 2, net
    c = net.curves[0]
    assert not c.closed and c.start != c.end
    ends = net.nodes[[c.start, c.end]]
    # the end nodes are at the ends of the line (not shrunk inward by more than one spacing)
    a, b = pts[np.argmin(pts[:, 0])], pts[np.argmax(pts[:, 0])]
    h = np.median(np.linalg.norm(np.diff(pts[np.argsort(pts[:, 0])], axis=0), axis=1))
    d = min(np.linalg.norm(ends[0] - a) + np.linalg.norm(ends[1] - b), np.linalg.norm(ends[0] - b) + np.linalg.norm(ends[1] - a))
    assert d <= 2 * h, (d, h)


def test_straight_line():
    pts = _line()
    _assert_one_open_curve(curvenet.reconstruct(pts), pts)


def test_single_circle_is_one_closed_loop():
    net = curvenet.reconstruct(_circle())
    assert net.n_curves == 1 and net.n_nodes == 0
    c = net.curves[0]
    assert c.closed and c.start is None and c.end is None
    assert net.betti == (1, 1)


def test_duplicated_points():
    pts = _line()
    dup = np.vstack([pts, pts[::3]])  # a third of the points twice
    net = curvenet.reconstruct(dup)
    _assert_one_open_curve(net, pts)
    inner = np.concatenate([c.indices[1:-1] for c in net.curves])
    inner = inner[inner >= 0]
    assert len(np.unique(inner)) == len(inner)


@pytest.mark.parametrize("offset,scale", [(1e8, 1.0), (0.0, 1e-6), (-3e7, 1e3)])
def test_huge_offset_or_tiny_scale(offset, scale):
    pts = np.vstack([_circle(seed=1), _circle(seed=2) + [3.0, 0, 0]])
    base = curvenet.reconstruct(pts)
    moved = curvenet.reconstruct(pts * scale + offset)
    assert (moved.n_nodes, moved.n_curves, moved.betti) == (base.n_nodes, base.n_curves, base.betti) == (0, 2, (2, 2))
    for c in moved.curves:
        assert c.closed


def test_2d_points_with_zero_z_match_2d_input():
    rng = np.random.default_rng(3)
    h = 0.02
    arms = []
    for ang in (0, 2.1, 4.2):  # a Y: one junction, three free ends
        t = np.arange(1, 40) * h
        arms.append(np.column_stack([t * np.cos(ang), t * np.sin(ang)]))
    p2 = np.vstack(arms + [np.zeros((1, 2))]) + rng.normal(scale=0.05 * h, size=(118, 2))
    p3 = np.column_stack([p2, np.zeros(len(p2))])
    n2, n3 = curvenet.reconstruct(p2), curvenet.reconstruct(p3)
    assert n2.dimension == 2 and n3.dimension == 3
    assert (n2.n_nodes, n2.n_curves) == (n3.n_nodes, n3.n_curves) == (4, 3)
    assert sorted(n2.valence.tolist()) == sorted(n3.valence.tolist()) == [1, 1, 1, 3]
    # same nodes up to a small part of the spacing (the 3D noise estimate has one more normal direction)
    np.testing.assert_allclose(np.sort(n3.nodes[:, :2], axis=0), np.sort(n2.nodes, axis=0), atol=0.1 * h)
    assert np.abs(n3.nodes[:, 2]).max() < 1e-12
