"""Small shared fixtures: tiny named point sets."""

import os

import numpy as np
import pytest

# the robust method's Topology checks its invariants after every change (subprocesses inherit it)
os.environ.setdefault("CURVENET_CHECK_TOPOLOGY", "1")


def cube_edges_points(n_per_edge: int = 50, side: float = 1.0) -> np.ndarray:
    """Points along the 12 edges of a cube, corners excluded, ``n_per_edge`` per edge."""
    c = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) * side
    pts = []
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(np.abs(c[i] - c[j]) > 0) == 1:
                t = np.linspace(0, 1, n_per_edge + 2)[1:-1, None]
                pts.append(c[i] + t * (c[j] - c[i]))
    return np.vstack(pts + [c])


@pytest.fixture
def cube_points():
    return cube_edges_points()


@pytest.fixture
def line_points():
    t = np.linspace(0, 1, 40)
    return np.column_stack([t, 2 * t, np.zeros_like(t)])
