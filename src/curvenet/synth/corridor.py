"""A synthetic power-line corridor: towers, crossarms, insulators and catenary wires, as LiDAR
would sample them (for the tiled run's scale benchmark, :mod:`curvenet.distributed`).

Towers stand every 200 to 400 m along a gently turning route; each carries a crossarm with
3 to 6 insulators, and each wire of a span hangs as a catenary between the insulators of two
consecutive towers, so that the wires of two spans and the insulator meet at a junction.
Points are produced span by span (:func:`corridor_span`), so that a corridor of 10^8 points
can be written file by file without holding it.

>>> from curvenet.synth.corridor import corridor_layout, corridor_span
>>> lay = corridor_layout(10, rng=1)
>>> pts = corridor_span(lay, 0, rng=1)          # tower 0 and the wires to tower 1
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..network import Curve, CurveNetwork
from .arith import norm

__all__ = ["CorridorLayout", "corridor_layout", "corridor_span", "corridor_truth", "spans_for_points",
           "SPAN_RANGE", "TOWER_HEIGHT", "ARM_HALF", "INSULATOR", "SAG", "TURN", "OUTLIER_BOX"]

#: Span length range between two towers (m).
SPAN_RANGE = (200.0, 400.0)
#: Height of the crossarm above the ground (m).
TOWER_HEIGHT = 30.0
#: Half the crossarm's length (m); the insulators hang from points strictly inside it.
ARM_HALF = 7.0
#: Length of an insulator string (m).
INSULATOR = 2.0
#: Sag of a wire at mid-span, as a fraction of the span length.
SAG = 0.03
#: Largest turn of the route at one tower (degrees); the heading stays within 3 times this.
TURN = 8.0
#: Outliers are drawn in the span's box widened by this many metres sideways and up.
OUTLIER_BOX = 15.0


@dataclass(frozen=True)
class CorridorLayout:
    """Where the towers stand.

    Attributes
    ----------
    base : (T, 3) ndarray
        Foot of each tower.
    across : (T, 3) ndarray
        Unit horizontal direction of each crossarm (across the route).
    wires : int
        Wires per span (3 to 6).
    """

    base: np.ndarray
    across: np.ndarray
    wires: int

    @property
    def n_spans(self) -> int:
        return len(self.base) - 1

    def attachments(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """(wires, 3) arrays: the insulator tops (on the crossarm) and bottoms of tower ``i``."""
        off = np.linspace(-1, 1, self.wires + 2)[1:-1] * ARM_HALF
        top = self.base[i] + [0, 0, TOWER_HEIGHT] + off[:, None] * self.across[i]
        return top, top - [0, 0, INSULATOR]


def corridor_layout(n_spans: int, *, wires: int | None = None, rng=0) -> CorridorLayout:
    """The towers of a corridor of ``n_spans`` spans (``n_spans + 1`` towers).

    Parameters
    ----------
    n_spans : int
        At least 1.
    wires : int, optional
        Wires per span, 3 to 6 (default: drawn).
    rng : int or numpy.random.Generator

    Returns
    -------
    CorridorLayout
    """
    if n_spans < 1:
        raise InputError(f"a corridor needs at least one span, got {n_spans}")
    gen = np.random.default_rng(rng)
    if wires is None:
        wires = int(gen.integers(3, 7))
    if not 3 <= wires <= 6:
        raise InputError(f"wires must be 3 to 6, got {wires}")
    length = gen.uniform(*SPAN_RANGE, size=n_spans)
    turn = np.radians(gen.uniform(-TURN, TURN, size=n_spans))
    heading = np.clip(np.cumsum(turn), -np.radians(3 * TURN), np.radians(3 * TURN))
    step = np.c_[np.cos(heading), np.sin(heading)] * length[:, None]
    xy = np.vstack([np.zeros(2), np.cumsum(step, axis=0)])
    ground = 5.0 * np.sin(np.arange(len(xy)) * 0.37)
    base = np.c_[xy, ground]
    d = np.vstack([step[:1], step[:-1] + step[1:], step[-1:]])  # bisector of the route at each tower
    across = np.c_[-d[:, 1], d[:, 0], np.zeros(len(d))]
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    return CorridorLayout(base, across, wires)


def _line(a, b, spacing):
    n = max(int(np.ceil(norm(np.subtract(b, a)) / spacing)), 1)
    t = np.arange(n + 1) / n
    return np.asarray(a) + t[:, None] * np.subtract(b, a)


def _catenary(a, b, spacing, *, with_ends=True):
    """Points every ``spacing`` (about) along a wire hanging from ``a`` to ``b`` (3D)."""
    L = norm((b - a)[:2])
    n = max(int(np.ceil(L * (1 + 8 / 3 * SAG**2) / spacing)), 2)
    t = np.arange(n + 1) / n
    c = L / (8 * SAG)  # the catenary parameter of a sag SAG * L
    s = (t - 0.5) * L
    dip = c * (np.cosh(s / c) - np.cosh(L / (2 * c)))
    P = a + t[:, None] * (b - a)
    P[:, 2] += dip
    return P if with_ends else P[1:-1]


def _tower(lay: CorridorLayout, i: int, spacing: float) -> list[np.ndarray]:
    """The pole, crossarm and insulators of tower ``i`` (junction points sampled once)."""
    top, bottom = lay.attachments(i)
    mid = lay.base[i] + [0, 0, TOWER_HEIGHT]
    ends = (mid - ARM_HALF * lay.across[i], mid + ARM_HALF * lay.across[i])
    out = [_line(lay.base[i], mid, spacing)[:-1]]  # the pole, up to (not with) the arm's middle
    stops = np.vstack([ends[0], top[: lay.wires // 2], mid, top[lay.wires // 2:], ends[1]])
    for a, b in zip(stops[:-1], stops[1:]):  # the crossarm through its junctions
        out.append(_line(a, b, spacing)[:-1] if norm(b - a) > 0 else np.zeros((0, 3)))
    out.append(ends[1][None])
    for a, b in zip(top, bottom):
        out.append(_line(a, b, spacing)[1:])  # insulators, from below the arm to the wire junction
    return out


def corridor_span(lay: CorridorLayout, i: int, *, spacing: float = 0.25, noise: float = 0.03,
                  outliers: float = 0.015, rng=0) -> np.ndarray:
    """The points of tower ``i`` and of the wires from tower ``i`` to ``i + 1`` (the last
    tower with ``i = n_spans``, no wire).

    Parameters
    ----------
    lay : CorridorLayout
    i : int
        0 to ``lay.n_spans``.
    spacing : float
        Sampling step along every curve (m; LiDAR on wires: 0.1 to 0.5).
    noise : float
        Gaussian noise std per coordinate (m; 0.02 to 0.05).
    outliers : float
        Outliers as a fraction of the span's curve samples (0.01 to 0.02), uniform in the
        span's box.
    rng : int
        Seed; the span's generator is seeded with ``(rng, i)`` so spans are independent.

    Returns
    -------
    (n, 3) ndarray of float
    """
    if not (spacing > 0 and noise >= 0 and outliers >= 0):
        raise InputError(f"spacing must be > 0, noise and outliers >= 0; got {spacing}, {noise}, {outliers}")
    gen = np.random.default_rng([int(rng), int(i)])
    parts = _tower(lay, i, spacing)
    if i < lay.n_spans:
        _, b0 = lay.attachments(i)
        _, b1 = lay.attachments(i + 1)
        parts += [_catenary(a, b, spacing, with_ends=False) for a, b in zip(b0, b1)]
    P = np.vstack(parts)
    P = P + gen.normal(scale=noise, size=P.shape) if noise else P
    n_out = int(round(outliers * len(P)))
    if n_out:
        lo = P.min(axis=0) - [OUTLIER_BOX, OUTLIER_BOX, 0]
        hi = P.max(axis=0) + [OUTLIER_BOX, OUTLIER_BOX, OUTLIER_BOX]
        P = np.vstack([P, gen.uniform(lo, hi, size=(n_out, 3))])
    return P


def spans_for_points(n_points: float, *, wires: int = 4, spacing: float = 0.25) -> int:
    """About how many spans give ``n_points`` points (mean span, the wires and a tower)."""
    per_span = (wires * np.mean(SPAN_RANGE) + TOWER_HEIGHT + 2 * ARM_HALF + wires * INSULATOR) / spacing
    return max(1, int(round(n_points / per_span)))


def corridor_truth(lay: CorridorLayout) -> CurveNetwork:
    """The corridor's true curve network (poles, crossarm pieces, insulators, wires)."""
    nodes, curves = [], []

    def node(p):
        nodes.append(np.asarray(p, float))
        return len(nodes) - 1

    bottoms = []
    for i in range(len(lay.base)):
        top, bottom = lay.attachments(i)
        mid = lay.base[i] + [0, 0, TOWER_HEIGHT]
        ends = (mid - ARM_HALF * lay.across[i], mid + ARM_HALF * lay.across[i])
        foot, m = node(lay.base[i]), node(mid)
        curves.append(Curve(np.vstack([lay.base[i], mid]), foot, m))
        tops = [node(t) for t in top]
        bots = [node(b) for b in bottom]
        bottoms.append(bots)
        arm = [node(ends[0])] + tops[: lay.wires // 2] + [m] + tops[lay.wires // 2:] + [node(ends[1])]
        for a, b in zip(arm[:-1], arm[1:]):
            curves.append(Curve(np.vstack([nodes[a], nodes[b]]), a, b))
        for t, b in zip(tops, bots):
            curves.append(Curve(np.vstack([nodes[t], nodes[b]]), t, b))
    for i in range(lay.n_spans):
        for w in range(lay.wires):
            a, b = bottoms[i][w], bottoms[i + 1][w]
            curves.append(Curve(_catenary(nodes[a], nodes[b], 1.0), a, b))
    return CurveNetwork(np.array(nodes), curves, {"h": None}, {})
