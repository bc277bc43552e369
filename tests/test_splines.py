"""curvenet.io.splines: the splines of many curves at once are SciPy's, curve by curve, to the bit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

from curvenet.io.splines import chord_parameters, cubic_splines, open_fit_points


def _curves(seed: int = 1) -> list[np.ndarray]:
    """Curves of 4 to 80 points: random, flat (z = 0 or -0.0), on a line, on a coarse grid,
    with points very close together, and far from the origin."""
    rng = np.random.default_rng(seed)
    out = []
    for n in range(4, 81):
        for kind in range(6):
            c = rng.normal(size=(n, 3))
            if kind == 1:
                c[:, 2] = 0.0
            elif kind == 2:
                c[:, 1:] = -0.0
                c[:, 0] = np.cumsum(rng.random(n) + 0.1)
            elif kind == 3:
                c = np.round(c, 1) + np.arange(n)[:, None]
            elif kind == 4:
                c[::3] *= 1e-6
            elif kind == 5:
                c = 1e7 + c
            out.append(c)
    return out


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.int64)


@pytest.mark.parametrize("shuffled", [False, True], ids=["by-size", "shuffled"])
def test_cubic_splines_equal_scipy_s_bit_for_bit(shuffled):
    """Each curve's control points and knots are SciPy's, whatever the order of the curves'
    sizes (the joint system groups the blocks by size)."""
    curves = _curves()
    if shuffled:
        curves = [curves[i] for i in np.random.default_rng(4).permutation(len(curves))]
    off = np.concatenate([[0], np.cumsum([len(c) for c in curves])])
    control, knots = cubic_splines(np.concatenate(curves), off)
    for j, c in enumerate(curves):
        u = chord_parameters(c[None])[0]
        b = make_interp_spline(u, c, k=3)
        assert np.array_equal(_bits(b.c), _bits(control[off[j]:off[j + 1]])), j
        assert np.array_equal(_bits(b.t), _bits(knots[off[j] + 4 * j:off[j + 1] + 4 * (j + 1)])), j


def test_chord_parameters_are_each_curve_s_cumsum():
    c = np.random.default_rng(2).normal(size=(7, 30, 3))
    u = chord_parameters(c)
    for k in range(7):
        want = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(c[k], axis=0), axis=1))]
        assert np.array_equal(u[k], want)


@pytest.mark.parametrize("bad", ["repeated", "nan"])
def test_cubic_splines_declines_what_scipy_rejects(bad):
    c = np.random.default_rng(3).normal(size=(6, 3))
    if bad == "repeated":
        c[3] = c[2]  # a zero step: parameters not strictly increasing
    else:
        c[1, 0] = np.nan
    ok = np.random.default_rng(4).normal(size=(5, 3))
    assert cubic_splines(np.concatenate([ok, c]), np.array([0, 5, 11])) is None


def test_cubic_splines_empty():
    control, knots = cubic_splines(np.zeros((0, 3)), np.array([0]))
    assert control.shape == (0, 3) and knots.shape == (0,)


def test_open_fit_points_drop_near_repeats_per_curve():
    a = np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 1e-12], [2, 0, 0]])  # third within 1e-9 of its extent
    b = np.array([[5.0, 5, 5], [5, 5, 5 + 1e-12], [6, 5, 5]])  # extent 1: 1e-12 dropped
    keep = open_fit_points(np.concatenate([a, b]), np.array([0, 4, 7]), 1e-9)
    assert keep.tolist() == [True, True, False, True, True, False, True]
