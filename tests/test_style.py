"""The curve colours (curvenet.style.curve_colors) against the greedy colouring written out
plainly: the fast loop (bit masks of the colours at each node, the free colours of a mask found
once) gives the same colour to every curve."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import Curve, CurveNetwork
from curvenet.style import PALETTE, curve_colors, curve_order


def _plain_colors(net: CurveNetwork, palette=PALETTE) -> list[str]:
    """The greedy colouring of :func:`curve_colors` as first written: lists of the colours at
    each node, the least-used colour not among them (the first on a tie)."""
    k = len(palette)
    starts = [-1 if c.start is None else int(c.start) for c in net.curves]
    ends = [-1 if c.end is None else int(c.end) for c in net.curves]
    at_node = [[] for _ in range(max(starts + ends + [-1]) + 1)]
    counts = [0] * k
    out = [0] * net.n_curves
    for i in curve_order(net.curves):
        s, e = starts[i], (ends[i] if ends[i] >= 0 else starts[i])
        taken = set(at_node[s] + at_node[e]) if s >= 0 else ()
        if taken:
            free = [j for j in range(k) if j not in taken] or range(k)
            j = min(free, key=counts.__getitem__)
        else:
            j = counts.index(min(counts))
        out[i] = j
        counts[j] += 1
        if s >= 0:
            at_node[s].append(j)
            if e != s:
                at_node[e].append(j)
    return [palette[j] for j in out]


def _random_network(rng: np.random.Generator, n_nodes: int, n_curves: int) -> CurveNetwork:
    """Curves between few nodes (more curves at a node than colours), self-loops, free loops
    and curves of equal geometry (ties of the order)."""
    nodes = rng.integers(0, 4, size=(n_nodes, 2)).astype(float)
    curves = []
    for _ in range(n_curves):
        m = int(rng.integers(2, 5))
        pts = rng.integers(0, 3, size=(m, 2)).astype(float)
        r = rng.random()
        if r < 0.1:
            curves.append(Curve(pts, None, None, True))
        else:
            s = int(rng.integers(0, n_nodes))
            e = s if r < 0.2 else int(rng.integers(0, n_nodes))
            curves.append(Curve(pts, s, e, s == e))
    return CurveNetwork(nodes, curves)


@pytest.mark.parametrize("seed", range(40))
def test_colors_equal_the_plain_greedy_colouring(seed):
    rng = np.random.default_rng(seed)
    net = _random_network(rng, int(rng.integers(1, 6)), int(rng.integers(0, 60)))
    assert curve_colors(net) == _plain_colors(net)
    small = PALETTE[:3]  # every colour taken at a node: the least used of all
    assert curve_colors(net, palette=small) == _plain_colors(net, small)


def test_a_star_of_more_curves_than_colours():
    k = len(PALETTE)
    nodes = np.vstack([[0.0, 0.0], np.column_stack([np.arange(2 * k + 3), np.ones(2 * k + 3)])])
    net = CurveNetwork(nodes, [Curve(np.array([nodes[0], nodes[i + 1]]), 0, i + 1) for i in range(2 * k + 3)])
    cols = curve_colors(net)
    assert cols == _plain_colors(net)
    assert len(set(cols)) == k
