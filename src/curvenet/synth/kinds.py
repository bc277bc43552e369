"""Synthetic analogues of the failure kinds seen on real networks (issue 25).

Each model reproduces one structure that real networks have and the original synthetic models
lack: junctions a few spacings apart (a facade's ladder, a comb of free ends, street grids
with short links), short twigs near junctions (neuron trees), tortuous branches (traced
neurites zigzag), short coplanar edges at right
angles (building outlines) and lines leaving arcs almost tangentially (CAD feature curves).
They are built as :mod:`.models` builds its models (curves sampled every h/10, valence-2 nodes
contracted, ``parameters`` with ``model``, ``h`` and ``features``) and can be named wherever a
model of :data:`curvenet.synth.MODELS` can.

Every model is well posed at its spacing h unless its ``features`` say otherwise: curves at
least 3h long, curves sharing no node at least 3h apart.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..network import CurveNetwork
from .arith import matmul, matvec, norm
from .models import _Builder, _param, _poly, _rot

__all__ = ["KIND_MODELS", "TANGENT_ANGLES", "tangent_circle"]

#: Angles (degrees) between the arc's tangent and the line leaving it at the junctions of the
#: ``tangent`` model (0: exactly tangent, as where a fillet meets a straight edge).
TANGENT_ANGLES = (0.0, 5.0, 10.0, 20.0)


def _lines(b: _Builder, ids, edges) -> None:
    """Straight curves between node pairs ``edges`` (indices into ``ids``)."""
    for i, j in edges:
        b.curve(_poly([b.nodes[ids[i]], b.nodes[ids[j]]], b.step), ids[i], ids[j])


def _ladder() -> CurveNetwork:
    h = 0.01
    b = _Builder(h)
    R = _rot(0.3, -0.5, 0.2)
    gaps = np.array([4.0, 5.0, 4.0, 3.0, 4.0, 5.0, 4.0, 4.0, 3.0, 5.0, 4.0]) * h
    x = np.r_[0.0, np.cumsum(gaps)]
    height = 20 * h
    bot = [b.node(matvec(R, [xi, 0.0, 0.0])) for xi in x]
    top = [b.node(matvec(R, [xi, height, 0.0])) for xi in x]
    ids = bot + top
    n = len(x)
    _lines(b, ids, [(k, k + 1) for k in range(n - 1)] + [(n + k, n + k + 1) for k in range(n - 1)]
           + [(k, n + k) for k in range(n)])
    return b.build("ladder", "facade ladder in a tilted plane: rungs 3-5h apart, valence-3 junctions 3-5h "
                   "apart along both rails, right angles")


def _comb() -> CurveNetwork:
    h = 0.01
    b = _Builder(h)
    gaps = np.array([5.0, 4.0, 3.0, 4.0, 5.0, 4.0, 3.0, 5.0]) * h
    x = np.r_[0.0, np.cumsum(gaps)]
    spine = [b.node([xi, 0.0, 0.0]) for xi in x]
    end_l, end_r = b.node([x[0] - 8 * h, 0.0, 0.0]), b.node([x[-1] + 8 * h, 0.0, 0.0])
    chain = [end_l, *spine, end_r]
    for a, c in zip(chain[:-1], chain[1:]):
        b.curve(_poly([b.nodes[a], b.nodes[c]], b.step), a, c)
    for k, xi in enumerate(x):
        length = (10.0 + 3.0 * (k % 3)) * h
        tip = b.node([xi, length, 0.5 * length * (k % 2)])
        b.curve(_poly([b.nodes[spine[k]], b.nodes[tip]], b.step), spine[k], tip)
    return b.build("comb", "teeth (free ends) leaving a spine 3-5h apart: valence-3 junctions 3-5h apart, "
                   "parallel teeth 3h apart")


def _streets() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    rng = np.random.default_rng(25)
    xs = np.array([0.0, 22.0, 26.0, 50.0, 75.0]) * h  # a short block (4h) between two avenues
    ys = np.array([0.0, 24.0, 48.0, 53.0, 76.0]) * h  # and another one (5h)
    jit = rng.uniform(-1.0, 1.0, size=(len(xs), len(ys), 2)) * h
    ids = {(i, j): b.node([xs[i] + jit[i, j, 0], ys[j] + jit[i, j, 1]]) for i in range(len(xs))
           for j in range(len(ys))}
    edges = []
    for i in range(len(xs)):
        for j in range(len(ys)):
            if i + 1 < len(xs):
                edges.append(((i, j), (i + 1, j)))
            if j + 1 < len(ys):
                edges.append(((i, j), (i, j + 1)))
    # a few streets missing (T junctions), as in real grids
    for e in (((1, 0), (2, 0)), ((3, 3), (3, 4)), ((0, 2), (1, 2))):
        edges.remove(e)
    for p, q in edges:
        b.curve(_poly([b.nodes[ids[p]], b.nodes[ids[q]]], b.step), ids[p], ids[q])
    # dead ends leaving the grid
    for p, d in (((0, 1), (-12.0, 1.0)), ((4, 2), (14.0, -1.0)), ((2, 4), (1.0, 12.0))):
        e = b.node(b.nodes[ids[p]] + np.array(d) * h)
        b.curve(_poly([b.nodes[ids[p]], b.nodes[e]], b.step), ids[p], e)
    return b.build("streets", "2D street grid: jittered blocks, short links 4-5h between close "
                   "intersections, T junctions where streets are missing, dead ends")


def _twigs() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    rng = np.random.default_rng(5)

    def seg(p0, d, length, a, bend):
        d = d / norm(d)
        w = np.cross(d, [0.2, 0.6, 0.77])
        w = bend * length * w / norm(w)
        f = lambda t: p0 + t[:, None] * (length * d) + np.sin(np.pi * t)[:, None] * w
        e = b.node(f(np.array([1.0]))[0])
        b.param(f, 0.0, 1.0, a, e)
        return e, f(np.array([1.0]))[0], d

    def perp(d):
        u = np.cross(d, [1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.cross(d, [0.0, 1.0, 0.0])
        return u / norm(u)

    def branch(a, p0, d, length, depth):
        # a branch: a stem, then a twig 3-6h long a few spacings before its end, then two children
        split = rng.uniform(0.55, 0.7)
        m, pm, dm = seg(p0, d, split * length, a, 0.05)
        u = perp(dm)
        twig_len = rng.uniform(3.0, 6.0) * h
        seg(pm, dm + 1.2 * u, twig_len, m, 0.0)
        e, pe, de = seg(pm, dm, (1 - split) * length, m, 0.03)
        if depth == 0:
            return
        phase = rng.uniform(0, 2 * np.pi)
        v = np.cross(de, u)
        for i in range(2):
            ang = phase + np.pi * i
            branch(e, pe, de + 0.8 * (np.cos(ang) * u + np.sin(ang) * v), 0.75 * length, depth - 1)

    root = b.node([0.0, 0.0, 0.0])
    branch(root, np.zeros(3), np.array([0.0, 0.0, 1.0]), 40 * h, 3)
    return b.build("twigs", "3D tree whose branches carry twigs 3-6h long (free ends) a few spacings "
                   "from a junction, valence 3")


def _turned(d: np.ndarray, axis: np.ndarray, deg: float) -> np.ndarray:
    """The unit vector ``d`` turned by ``deg`` degrees about ``axis`` (Rodrigues)."""
    k = axis / norm(axis)
    a = np.radians(deg)
    return d * np.cos(a) + np.cross(k, d) * np.sin(a) + k * float((k * d).sum()) * (1.0 - np.cos(a))


def _neurites() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    rng = np.random.default_rng(11)
    placed: list[np.ndarray] = []  # the dense points of the branches so far, with their start node

    def zigzag_path(p0, d, length):
        # straight runs of 4-10h, each followed by a zigzag of 2-4 turns of 40-120 degrees about
        # random axes every 1.6-3.7h (a traced neurite's tortuosity), until about ``length``;
        # the branch starts and ends with a straight run (its junctions and tip stay clear)
        v, run, heading = [p0], 0.0, d / norm(d)
        while True:
            step = rng.uniform(4.0, 10.0) * h
            v.append(v[-1] + heading * step)
            run += step
            if run >= length:
                return np.array(v)
            for _ in range(int(rng.integers(2, 5))):
                heading = _turned(heading, np.cross(heading, rng.normal(size=3)), rng.uniform(40.0, 120.0))
                step = rng.uniform(1.6, 3.7) * h
                v.append(v[-1] + heading * step)
                run += step
            # back towards the branch's direction, so the tree spreads out
            heading = heading + 1.5 * d / norm(d)
            heading = heading / norm(heading)

    def well_posed(pts, p0):
        # at least 3h from the other branches (away from the shared start) and from itself
        # (parts more than 6h apart along it)
        far = np.linalg.norm(pts - p0, axis=1) > 4.0 * h
        q = pts[far]
        for other in placed:
            if len(q) and np.min(np.linalg.norm(q[:, None] - other[None, ::4], axis=2)) < 3.0 * h:
                return False
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
        sub = slice(None, None, 4)
        D = np.linalg.norm(pts[sub][:, None] - pts[sub][None], axis=2)
        apart = np.abs(s[sub][:, None] - s[sub][None]) > 6.0 * h
        return not np.any(D[apart] < 3.0 * h)

    def branch(a, p0, d, length, depth):
        for _ in range(200):
            v = zigzag_path(p0, d, length)
            pts = _poly(v, b.step)
            if well_posed(pts, p0):
                break
        else:  # (a bug in the model's parameters)
            raise AssertionError("no well-posed branch found")
        placed.append(pts)
        e = b.node(v[-1])
        b.curve(pts, a, e)
        if depth == 0:
            return
        de = v[-1] - v[-2]
        de = de / norm(de)
        u = np.cross(de, rng.normal(size=3))
        u = u / norm(u)
        for sgn in (1.0, -1.0):
            branch(e, v[-1], de + sgn * 1.0 * u, 0.8 * length, depth - 1)

    root = b.node([0.0, 0.0, 0.0])
    branch(root, np.zeros(3), np.array([0.0, 0.0, 1.0]), 45 * h, 3)
    return b.build("neurites", "3D tree (valence 3) whose branches zigzag as traced neurites do: straight "
                   "runs of 4-10h between bursts of 2-4 turns of 40-120 degrees every 1.6-3.7h; no part "
                   "within 3h of another")


def _outline() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    # footprint with notches of 4-5h (bay windows, a recessed entrance), counter-clockwise
    foot = np.array([[0, 0], [30, 0], [30, 12], [34, 12], [34, 17], [30, 17], [30, 30],
                     [17, 30], [17, 26], [13, 26], [13, 30], [0, 30]], dtype=float) * h
    H = 16 * h
    bot = [b.node([x, y, 0.0]) for x, y in foot]
    top = [b.node([x, y, H]) for x, y in foot]
    n = len(foot)
    ridge = [b.node([4 * h, 15 * h, H + 6 * h]), b.node([26 * h, 15 * h, H + 6 * h])]
    ids = bot + top + ridge
    edges = [(k, (k + 1) % n) for k in range(n)] + [(n + k, n + (k + 1) % n) for k in range(n)]
    edges += [(k, n + k) for k in range(n)]
    edges += [(2 * n, 2 * n + 1), (2 * n, n + 0), (2 * n, n + n - 1), (2 * n + 1, n + 1), (2 * n + 1, n + 6)]
    _lines(b, ids, edges)
    # a window outline on the front wall: a loop with 5h edges, 4h from the wall's edges
    b.loop(_poly([[8 * h, 0.0, 4 * h], [13 * h, 0.0, 4 * h], [13 * h, 0.0, 9 * h], [8 * h, 0.0, 9 * h]],
                 b.step, closed=True))
    return b.build("outline", "building wireframe: footprint and eaves with notches of 4-5h (coplanar "
                   "right-angle corners 4-5h apart), hipped roof, a window loop 4h from the wall's edges")


def _circle_with_lines(b: _Builder, R: float, L: float, angles) -> None:
    """A circle of radius ``R`` about the origin (in the xy plane) and one straight line of
    length ``L`` per angle of ``angles`` (degrees from the circle's tangent, leaving it
    outwards), at junctions spread evenly round it, the first at 20 degrees."""
    circ = lambda t: np.column_stack([R * np.cos(t), R * np.sin(t), 0.0 * t])
    k = len(angles)
    base = np.deg2rad(360.0 / k * np.arange(k) + 20.0)
    ids = [b.node(circ(np.array([t]))[0]) for t in base]
    for i in range(k):
        t0, t1 = base[i], base[(i + 1) % k] + (2 * np.pi if i == k - 1 else 0.0)
        b.param(circ, t0, t1, ids[i], ids[(i + 1) % k])
    for i, ang in enumerate(angles):
        p = b.nodes[ids[i]]
        tan = np.array([-np.sin(base[i]), np.cos(base[i]), 0.0])  # direction of increasing t
        out = np.array([np.cos(base[i]), np.sin(base[i]), 0.0])
        a = np.deg2rad(ang)
        d = np.cos(a) * tan + np.sin(a) * out  # leaves outwards, `ang` from the arc's tangent
        e = b.node(p + L * d)
        b.curve(_poly([p, b.nodes[e]], b.step), ids[i], e)


def _tangent() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    R = 30 * h
    _circle_with_lines(b, R, 30 * h, TANGENT_ANGLES)
    # a fillet: two lines joined by an arc, tangent at both ends; one of the lines continues
    # straight past the arc (a T junction whose arc leaves the line tangentially)
    r = 10 * h
    c0 = np.array([2 * R + 20 * h, 0.0, 0.0])
    arc = lambda t: c0 + np.column_stack([r * np.cos(t), r * np.sin(t), 0.0 * t])
    p_a, p_b = arc(np.array([0.0]))[0], arc(np.array([np.pi / 2]))[0]
    na, nb = b.node(p_a), b.node(p_b)
    b.param(arc, 0.0, np.pi / 2, na, nb)
    fa, fb = b.node(p_a - [0.0, 25 * h, 0.0]), b.node(p_b - [25 * h, 0.0, 0.0])
    b.curve(_poly([b.nodes[fa], p_a], b.step), fa, na)
    b.curve(_poly([p_b, b.nodes[fb]], b.step), nb, fb)
    ga = b.node(p_a + [0.0, 25 * h, 0.0])  # continues the straight edge past the arc: tangent T
    b.curve(_poly([p_a, b.nodes[ga]], b.step), na, ga)
    return b.build("tangent", "CAD-like: lines leaving a circle at 0, 5, 10 and 20 degrees from its "
                   "tangent, a fillet whose straight edge continues past it (a tangent T junction)")


def tangent_circle(radius: float, angles, length: float = 20.0, h: float = 0.02) -> CurveNetwork:
    """A circle with straight lines leaving it almost tangentially: one family of CAD feature
    curves (a hole or boss outline and the edges that leave it).

    Parameters
    ----------
    radius : float
        The circle's radius, in spacings ``h`` (a fillet or a small hole: 5-15; the ``tangent``
        kind's circle: 30).
    angles : sequence of float
        One line per angle (degrees between the circle's tangent and the line, leaving it
        outwards), at junctions spread evenly round the circle (the first at 20 degrees).
    length : float
        Each line's length, in spacings.
    h : float
        The spacing.

    Returns
    -------
    CurveNetwork
        ``len(angles)`` junctions of valence 3 and as many free ends; ``parameters["h"]`` is
        ``h``.
    """
    b = _Builder(h)
    _circle_with_lines(b, radius * h, length * h, angles)
    names = ", ".join("%g" % a for a in angles)
    return b.build(f"tangent_circle_r{radius:g}", f"CAD-like: a circle of radius {radius:g}h with lines "
                   f"leaving it at {names} degrees from its tangent")


def _plate() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    R = _rot(0.4, 0.25, -0.3)
    place = lambda X: matmul(np.atleast_2d(X), R.T)  # each row rotated by R
    W, D, T, r, hole = 40 * h, 25 * h, 6 * h, 5 * h, 4 * h
    # a plate with rounded corners (vertical edges filleted, radius r) and two through holes:
    # on each face the outline is four lines and four quarter arcs meeting tangentially, and at
    # each of the 8 tangent points an edge of the fillet (length T) leaves at a right angle,
    # to the tangent point of the other face: 16 tangent T junctions in pairs T apart
    corners = [(r, r, np.pi), (W - r, r, 1.5 * np.pi), (W - r, D - r, 0.0), (r, D - r, 0.5 * np.pi)]
    face = []
    for z in (0.0, T):
        ends = []
        for cx, cy, a0 in corners:
            arc = lambda u, cx=cx, cy=cy, z=z: place(np.column_stack([cx + r * np.cos(u), cy + r * np.sin(u),
                                                                      np.full(len(u), z)]))
            i, j = b.node(arc(np.array([a0]))[0]), b.node(arc(np.array([a0 + np.pi / 2]))[0])
            b.param(arc, a0, a0 + np.pi / 2, i, j)
            ends.append((i, j))
        for k in range(4):
            j, i = ends[k][1], ends[(k + 1) % 4][0]
            b.curve(_poly([b.nodes[j], b.nodes[i]], b.step), j, i)
        face.append(ends)
    for k in range(4):
        for e in range(2):
            lo, hi = face[0][k][e], face[1][k][e]
            b.curve(_poly([b.nodes[lo], b.nodes[hi]], b.step), lo, hi)
    for z in (0.0, T):
        for cx in (W / 3, 2 * W / 3):
            circle = lambda u, cx=cx, z=z: place(np.column_stack([cx + hole * np.cos(u), D / 2 + hole * np.sin(u),
                                                                  np.full(len(u), z)]))
            b.loop(_param(circle, 0.0, 2 * np.pi, b.step)[:-1])
    return b.build("plate", "CAD-like part: a plate 6h thick with rounded corners (radius 5h) and two "
                   "holes; tangent T junctions (a line continuing into an arc, an edge leaving at a "
                   "right angle) in pairs 6h apart")


#: Model name -> builder (no argument, returns a CurveNetwork).
KIND_MODELS: dict[str, Callable[[], CurveNetwork]] = {
    "ladder": _ladder,
    "comb": _comb,
    "streets": _streets,
    "twigs": _twigs,
    "neurites": _neurites,
    "outline": _outline,
    "tangent": _tangent,
    "plate": _plate,
}
