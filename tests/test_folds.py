"""Curves that fold back on themselves: the spikes of traced neurites (a tracing runs out a few
spacings and back along itself, then on), read as one curve by ``robust``."""

import numpy as np
import pytest

from curvenet import reconstruct, synth
from curvenet.network import Curve, CurveNetwork

#: the legs of the fold before and after the spike (spacings)
IN_LEG, OUT_LEG = 21.0, 42.0


def _turn(u: np.ndarray, degrees: float) -> np.ndarray:
    """``u`` (3,) turned by ``degrees`` about z."""
    a = np.radians(degrees)
    return np.array([np.cos(a) * u[0] - np.sin(a) * u[1], np.sin(a) * u[0] + np.cos(a) * u[1], 0.0])


def _spike(depth: float, first: float, back: float) -> CurveNetwork:
    """One curve at spacing 1: a leg along x, a turn of ``first`` degrees into a spike
    ``depth`` spacings long, a turn of ``back`` degrees (near 180: back along the spike) and a
    leg out (the shape of real-dev nrn_ri05_s591's spikes, 2.4 and 2.8 spacings deep)."""
    a = np.zeros(3)
    b = a + IN_LEG * np.array([1.0, 0.0, 0.0])
    u = _turn(np.array([1.0, 0.0, 0.0]), first)
    c = b + depth * u
    d = c + OUT_LEG * _turn(u, back)
    corners = np.array([a, b, c, d])
    pieces = [np.linspace(p, q, int(np.ceil(np.linalg.norm(q - p) / 0.05)), endpoint=False)
              for p, q in zip(corners[:-1], corners[1:])]
    line = np.r_[np.concatenate(pieces), d[None]]
    return CurveNetwork(nodes=np.array([a, d]), curves=[Curve(points=line, start=0, end=1)], parameters={"h": 1.0})


def _reconstructed(truth: CurveNetwork, seed: int) -> tuple[int, int]:
    pts, _ = synth.sample(truth, rng=seed)
    net = reconstruct(pts)
    return len(net.nodes), net.n_curves


@pytest.mark.parametrize("seed", [0, 1])
def test_a_spike_whose_samples_lie_twice_is_no_branch(seed):
    # 2.7 h deep: beyond the shell fraction of the region's halved spacing, under min_spur in
    # the curve's own (junctions.swallowed_branches); before, a junction and a tip (4 nodes)
    assert _reconstructed(_spike(2.7, 120.0, 177.0), seed) == (2, 1)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_spike_whose_tip_joins_its_foot_leaves_no_node_of_valence_two(seed, monkeypatch):
    # 2.6 h deep: its tip merged into the junction at its foot (tips_to_junctions), the loop
    # absorbed by the last absorb_short_loops; join_through_pass_regions runs once more after it
    assert _reconstructed(_spike(2.6, 132.0, 177.0), seed) == (2, 1)
    from curvenet.methods.robust import repairs

    assert repairs.ORDER[-1] is repairs.join_through_pass_regions
    monkeypatch.setattr(repairs, "ORDER", repairs.ORDER[:-1])
    assert _reconstructed(_spike(2.6, 132.0, 177.0), seed) == (3, 2)  # a node of valence 2
