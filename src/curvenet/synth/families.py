"""Families of real-like networks drawn at random (issue 25): many members of one structure.

The models of :mod:`.kinds` are one network each, and a rule tuned until they pass may pass
them alone. A family draws its structure's sizes, spacings and orientation at random, so that
a figure over its members says how the structure itself fares:

- ``facade``: a facade ladder, the held-out building wireframes' failure: 15-41 verticals
  4-5 h apart, 10-40 h tall, joined by two rails, in a random plane;
- ``storeys``: a facade of 2-3 storeys: 8-24 verticals 4-5 h apart, 3-4 rails 8-25 h apart
  (valence-4 junctions inside);
- ``grid``: a street grid of 4-8 by 3-5 streets, blocks 4-20 h long by 4-25 h wide;
- ``comb``: a spine with 8-29 teeth 4-5 h apart, 6-25 h long, ending 8 h past the last teeth.

Every member is well posed at its spacing h (curves at least 4 h long, curves sharing no node
at least 4 h apart). Member ``k`` of a family is drawn with ``numpy.random.default_rng(1000 +
k)`` and sampled by the benchmark with seed ``77 + k`` (:func:`sampling_seed`).

>>> from curvenet.synth import families
>>> truth = families.member("facade", 6)
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..network import CurveNetwork
from .arith import matvec
from .models import _Builder, _poly, _rot

__all__ = ["FAMILIES", "member", "sampling_seed"]

#: The spacing h of every family (the members' lengths are drawn in units of it).
H = 0.01


def _straight(b: _Builder, a: int, c: int) -> None:
    """A straight curve between nodes ``a`` and ``c``."""
    b.curve(_poly([b.nodes[a], b.nodes[c]], b.step), a, c)


def _lattice(b: _Builder, R: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> None:
    """Straight curves along every row and column of the lattice ``xs`` x ``ys`` (in the plane
    z = 0, rotated by ``R``)."""
    ids = {(i, j): b.node(matvec(R, [x, y, 0.0])) for i, x in enumerate(xs) for j, y in enumerate(ys)}
    for i in range(len(xs)):
        for j in range(len(ys)):
            if i + 1 < len(xs):
                _straight(b, ids[(i, j)], ids[(i + 1, j)])
            if j + 1 < len(ys):
                _straight(b, ids[(i, j)], ids[(i, j + 1)])


def _plane(rng: np.random.Generator) -> np.ndarray:
    """A random rotation (angles uniform in [-1, 1] radian about each axis)."""
    return _rot(*rng.uniform(-1.0, 1.0, 3))


def facade(rng: np.random.Generator) -> CurveNetwork:
    """A facade ladder: verticals 4-5 h apart between two rails."""
    b = _Builder(H)
    n = int(rng.integers(15, 42))
    xs = np.r_[0.0, np.cumsum(rng.uniform(4.0, 5.0, n - 1))] * H
    height = rng.uniform(10.0, 40.0) * H
    _lattice(b, _plane(rng), xs, np.array([0.0, height]))
    return b.build("facade", "a facade ladder drawn at random: verticals 4-5h apart")


def storeys(rng: np.random.Generator) -> CurveNetwork:
    """A facade of several storeys: verticals 4-5 h apart, rails 8-25 h apart."""
    b = _Builder(H)
    n = int(rng.integers(8, 25))
    xs = np.r_[0.0, np.cumsum(rng.uniform(4.0, 5.0, n - 1))] * H
    ys = np.r_[0.0, np.cumsum(rng.uniform(8.0, 25.0, int(rng.integers(2, 4))))] * H
    _lattice(b, _plane(rng), xs, ys)
    return b.build("storeys", "a facade of storeys drawn at random: valence-3 and -4 junctions 4-5h apart")


def grid(rng: np.random.Generator) -> CurveNetwork:
    """A street grid with short and long blocks."""
    b = _Builder(H)
    nx, ny = int(rng.integers(4, 9)), int(rng.integers(3, 6))
    xs = np.r_[0.0, np.cumsum(rng.choice([4.0, 4.5, 5.0, 12.0, 20.0], nx - 1))] * H
    ys = np.r_[0.0, np.cumsum(rng.choice([4.0, 5.0, 15.0, 25.0], ny - 1))] * H
    _lattice(b, _plane(rng), xs, ys)
    return b.build("grid", "a street grid drawn at random: blocks 4-20h by 4-25h")


def comb(rng: np.random.Generator) -> CurveNetwork:
    """A spine with teeth (free ends) 4-5 h apart."""
    b = _Builder(H)
    n = int(rng.integers(8, 30))
    xs = np.r_[0.0, np.cumsum(rng.uniform(4.0, 5.0, n - 1))] * H
    R = _plane(rng)
    spine = [b.node(matvec(R, [x, 0.0, 0.0])) for x in xs]
    ends = b.node(matvec(R, [xs[0] - 8 * H, 0.0, 0.0])), b.node(matvec(R, [xs[-1] + 8 * H, 0.0, 0.0]))
    chain = [ends[0], *spine, ends[1]]
    for a, c in zip(chain[:-1], chain[1:]):
        _straight(b, a, c)
    for k, x in enumerate(xs):
        tip = b.node(matvec(R, [x, rng.uniform(6.0, 25.0) * H, 0.0]))
        _straight(b, spine[k], tip)
    return b.build("comb", "a comb drawn at random: teeth 4-5h apart")


#: Every family: its name and the function that draws one member from a generator.
FAMILIES: dict[str, Callable[[np.random.Generator], CurveNetwork]] = {
    "facade": facade, "storeys": storeys, "grid": grid, "comb": comb,
}


def member(family: str, k: int) -> CurveNetwork:
    """Member ``k`` (0, 1, ...) of ``family`` (a name of :data:`FAMILIES`).

    Returns
    -------
    CurveNetwork
        The member's true network; ``parameters["model"]`` is ``"<family>#<k>"``.
    """
    if family not in FAMILIES:
        raise KeyError(f"unknown family {family!r}; expected one of: {', '.join(FAMILIES)}")
    net = FAMILIES[family](np.random.default_rng(1000 + int(k)))
    net.parameters["model"] = f"{family}#{int(k)}"
    return net


def sampling_seed(k: int) -> int:
    """The seed the benchmark samples member ``k`` of a family with."""
    return 77 + int(k)
