"""Tiny hand-made networks shared by the picture and viewer tests."""

import numpy as np

from curvenet import Curve, CurveNetwork


def theta_network(d: int = 3) -> CurveNetwork:
    """Two junctions joined by three arcs, a free end, and a free loop."""
    t = np.linspace(0, np.pi, 40)
    curves = []
    for h in (1.0, 0.0, -1.0):
        p = np.column_stack([-np.cos(t), h * np.sin(t), 0.4 * h * np.sin(t)])
        curves.append(Curve(p[:, :d], 0, 1))
    s = np.linspace(0, 1, 20)[:, None]
    b, e = np.array([1.0, 0, 0]), np.array([1.8, -0.9, 0.8])
    curves.append(Curve((b + s * (e - b))[:, :d], 1, 2))
    v = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    curves.append(Curve(np.column_stack([3 + 0.6 * np.cos(v), 0.6 * np.sin(v), 0 * v])[:, :d], None, None, closed=True))
    return CurveNetwork(np.array([[-1.0, 0, 0], b, e])[:, :d], curves)
