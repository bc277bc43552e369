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


def writer_networks() -> dict:
    """Networks whose writer outputs are pinned (tests/data/writer_digests.json): coordinates
    from exact arithmetic only (the same floats on every platform), among them values that
    ``repr`` writes with an exponent, negative zero and a subnormal."""

    def coords(m: int, d: int, seed: int) -> np.ndarray:
        i = np.arange(m * d, dtype=np.int64)
        return (((i * 7919 + seed * 104729) % 10007) - 5003).reshape(m, d) / 997.0

    nets = {"theta2": theta_network(2), "theta3": theta_network(3)}
    for d in (2, 3):
        nodes = coords(6, d, d)
        curves = []
        for k in range(12):
            a, b = k % 6, (k * 5 + 1) % 6
            mid = coords(3 + 7 * k % 40, d, 10 * k + d)
            curves.append(Curve(np.vstack([nodes[a], mid, nodes[b]]), a, b,
                                indices=np.arange(len(mid) + 2) * (k + 1) - 1))
        curves.append(Curve(coords(9, d, 99), None, None, closed=True))
        odd = coords(5, d, 7)
        odd[0, 0], odd[1, 0], odd[2, 0] = 1e-7, -0.0, 5e-324
        odd[3, 0], odd[4, 0] = 1.5e20, -2.5e-5
        curves.append(Curve(np.vstack([nodes[2], odd, nodes[3]]), 2, 3))
        nets[f"exact{d}"] = CurveNetwork(nodes, curves, {"spacing": 0.125}, {})
    nets["empty"] = CurveNetwork(np.zeros((0, 3)), [])
    return nets
