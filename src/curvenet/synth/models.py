"""Parametric ground-truth curve networks.

Each model is a :class:`~curvenet.network.CurveNetwork` whose curves are the true curves,
densely sampled (spacing ``h / 10`` of the model's reference spacing) and whose nodes are the
junctions and free ends; it has no node of valence 2 (corners inside a curve are not nodes).
``net.parameters`` holds ``model`` (the name), ``h`` (the reference sampling spacing, chosen so
that the model's hard features sit at the spacings the benchmark asks for) and ``features``
(what the model tests).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import InputError
from ..network import Curve, CurveNetwork
from .arith import matmul, matvec, norm

__all__ = ["MODELS", "h_of", "model_names"]


# ---------------------------------------------------------------------------------------------
# builders
# ---------------------------------------------------------------------------------------------
def _param(f: Callable[[np.ndarray], np.ndarray], t0: float, t1: float, step: float) -> np.ndarray:
    """Evaluate a smooth parametric curve at an even arc-length spacing <= step, ends exact."""
    t = np.linspace(t0, t1, 4001)
    p = f(t)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    n_fine = int(np.ceil(s[-1] / step * 20))
    if n_fine > 4000:  # long curve: evaluate finer
        t = np.linspace(t0, t1, n_fine + 1)
        p = f(t)
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    n = max(int(np.ceil(s[-1] / step)), 1)
    u = np.linspace(0.0, s[-1], n + 1)
    out = np.column_stack([np.interp(u, s, p[:, k]) for k in range(p.shape[1])])
    out[0], out[-1] = p[0], p[-1]
    return out


def _poly(vertices, step: float, *, closed: bool = False) -> np.ndarray:
    """A polyline through ``vertices`` (kept: they are the sharp corners) at spacing <= step."""
    v = np.asarray(vertices, dtype=float)
    if closed:
        v = np.vstack([v, v[:1]])
    parts = []
    for a, b in zip(v[:-1], v[1:]):
        n = max(int(np.ceil(norm(b - a) / step)), 1)
        t = np.linspace(0.0, 1.0, n + 1)[:-1]
        parts.append(a + (b - a) * t[:, None])
    if not closed:
        parts.append(v[-1:])
    return np.vstack(parts)


class _Builder:
    """Collect nodes and pieces, then contract valence-2 nodes into one network."""

    def __init__(self, h: float):
        self.h = h
        self.step = h / 10.0
        self.nodes: list[np.ndarray] = []
        self.curves: list[Curve] = []

    def node(self, p) -> int:
        self.nodes.append(np.asarray(p, dtype=float))
        return len(self.nodes) - 1

    def curve(self, pts: np.ndarray, a: int, b: int) -> None:
        pts = np.array(pts, dtype=float)
        if norm(pts[0] - self.nodes[a]) > 1e-9 or norm(pts[-1] - self.nodes[b]) > 1e-9:
            raise AssertionError("model piece does not end at its nodes")  # a bug in a model
        pts[0], pts[-1] = self.nodes[a], self.nodes[b]
        self.curves.append(Curve(pts, a, b, a == b))

    def param(self, f, t0, t1, a: int, b: int) -> None:
        self.curve(_param(f, t0, t1, self.step), a, b)

    def loop(self, pts: np.ndarray) -> None:
        self.curves.append(Curve(np.asarray(pts, dtype=float), None, None, True))

    def build(self, name: str, features: str) -> CurveNetwork:
        from ..metrics import contract

        d = self.curves[0].points.shape[1]
        net = CurveNetwork(np.array(self.nodes, dtype=float).reshape(len(self.nodes), d), self.curves)
        net = contract(net)
        net.parameters = {"model": name, "h": self.h, "features": features}
        return net


def _rot(ax: float, ay: float, az: float) -> np.ndarray:
    """Rotation matrix from angles (radians) about x, then y, then z."""
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return matmul(matmul(rz, ry), rx)


def _circle(c, r, e1, e2):
    c, e1, e2 = (np.asarray(x, dtype=float) for x in (c, e1, e2))
    return lambda t: c + r * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2)


# ---------------------------------------------------------------------------------------------
# the models
# ---------------------------------------------------------------------------------------------
def _cube() -> CurveNetwork:
    b = _Builder(0.025)
    corners = [b.node([x, y, z]) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    for i in range(8):
        for j in range(i + 1, 8):
            if bin(i ^ j).count("1") == 1:
                b.curve(_poly([b.nodes[corners[i]], b.nodes[corners[j]]], b.step), i, j)
    return b.build("cube", "cube wireframe: straight edges, valence 3, right angles")


def _wheel() -> CurveNetwork:
    b = _Builder(0.02)
    hub = b.node([0.0, 0.0])
    ang = np.deg2rad(15 + 60 * np.arange(6))
    rim = [b.node([np.cos(a), np.sin(a)]) for a in ang]
    for k, a in enumerate(ang):
        b.curve(_poly([[0, 0], [np.cos(a), np.sin(a)]], b.step), hub, rim[k])
        a1 = a + np.pi / 3
        b.param(lambda t: np.column_stack([np.cos(t), np.sin(t)]), a, a1, rim[k], rim[(k + 1) % 6])
    return b.build("wheel", "2D; hub of valence 6, rim nodes of valence 3")


def _fan() -> CurveNetwork:
    b = _Builder(0.02)
    o = b.node([0.0, 0.0])

    def spoke(theta, length, bend):
        d = np.array([np.cos(theta), np.sin(theta)])
        n = np.array([-d[1], d[0]])
        return lambda t: t[:, None] * d + bend * (t**2)[:, None] * n

    for deg in (0.0, 30.0, 180.0, 260.0):
        f = spoke(np.deg2rad(deg), 1.0, 0.08)
        e = b.node(f(np.array([1.0]))[0])
        b.param(f, 0.0, 1.0, o, e)
    top = b.node([0.0, 1.0])
    b.curve(_poly([[0, 0], [0, 1]], b.step), o, top)
    for deg in (70.0, 110.0):
        f0 = spoke(np.deg2rad(deg), 0.8, 0.0)
        f = lambda t, f0=f0: f0(t) + np.array([0.0, 1.0])
        e = b.node(f(np.array([0.8]))[0])
        b.param(f, 0.0, 0.8, top, e)
    return b.build("fan", "2D; valence 5 with curves 30 degrees apart, valence 3 at 40 degrees, free ends")


def _crossing() -> CurveNetwork:
    b = _Builder(0.02)
    xs = (-1.0, 0.0, 1.0)
    cross = [b.node([x, 0.0]) for x in xs]
    ends_b = [b.node([-1.5, 0.0]), b.node([1.5, 0.0])]
    f = lambda t: np.column_stack([t, 0.25 * np.sin(np.pi * t)])
    ends_a = [b.node(f(np.array([-1.25]))[0]), b.node(f(np.array([1.25]))[0])]
    line = [ends_b[0], *cross, ends_b[1]]
    pos = [-1.5, *xs, 1.5]
    for k in range(4):
        b.curve(_poly([[pos[k], 0], [pos[k + 1], 0]], b.step), line[k], line[k + 1])
    wave = [ends_a[0], *cross, ends_a[1]]
    tw = [-1.25, *xs, 1.25]
    for k in range(4):
        b.param(f, tw[k], tw[k + 1], wave[k], wave[k + 1])
    return b.build("crossing", "2D; a wave crossing a line three times (valence 4, 38 degrees), free ends")


def _tree() -> CurveNetwork:
    b = _Builder(0.02)
    rng = np.random.default_rng(7)

    def branch(p0, d, length, depth, parent):
        d = d / norm(d)
        w = np.cross(d, [0.3, 0.5, 0.8])
        w = 0.12 * length * w / norm(w)
        f = lambda t: p0 + t[:, None] * (length * d) + np.sin(np.pi * t)[:, None] * w
        p1 = f(np.array([1.0]))[0]
        child = b.node(p1)
        b.param(f, 0.0, 1.0, parent, child)
        if depth == 0:
            return
        k = 3 if depth == 2 else 2
        base = np.cross(d, [1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.cross(d, [0.0, 1.0, 0.0])
        base /= norm(base)
        other = np.cross(d, base)
        phase = rng.uniform(0, 2 * np.pi)
        for i in range(k):
            a = phase + 2 * np.pi * i / k
            nd = d + 0.9 * (np.cos(a) * base + np.sin(a) * other)
            branch(p1, nd, length * 0.7, depth - 1, child)

    root = b.node([0.0, 0.0, 0.0])
    branch(np.zeros(3), np.array([0.0, 0.0, 1.0]), 1.0, 3, root)
    return b.build("tree", "3D branching tree: free ends, valence 3 and 4")


def _knot() -> CurveNetwork:
    b = _Builder(0.03)
    f = lambda t: 0.3 * np.column_stack(
        [np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]
    )
    p = _param(f, 0.0, 2 * np.pi, b.step)[:-1]
    b.loop(p)
    g = _circle([0.0, 0.0, 1.2], 0.5, [1, 0, 0], [0, 1, 0])
    b.loop(_param(g, 0.0, 2 * np.pi, b.step)[:-1])
    return b.build("knot", "3D; a trefoil knot and a circle: closed loops without nodes")


def _eye() -> CurveNetwork:
    h = 0.02
    b = _Builder(h)
    R = _rot(0.4, -0.3, 0.2)
    L, s = 1.0, 2.5 * h
    k = np.tan(np.deg2rad(30.0)) / s

    def prof(t):  # rises from 0 with slope tan(30 deg), plateaus at s, back down to 0
        return s * (1 - np.exp(-k * t)) * (1 - np.exp(-k * (L - t)))

    A = b.node(matvec(R, [0.0, 0.0, 0.0]))
    B = b.node(matvec(R, [L, 0.0, 0.0]))
    for sign in (1.0, 0.0, -1.0):
        f = lambda t, sg=sign: matmul(R, np.vstack([t, sg * prof(t), 0 * t])).T
        b.param(f, 0.0, L, A, B)
    tA = b.node(matvec(R, [-0.4, 0.0, 0.0]))
    tB = b.node(matvec(R, [L + 0.4, 0.0, 0.0]))
    b.curve(_poly([b.nodes[A], b.nodes[tA]], b.step), A, tA)
    b.curve(_poly([b.nodes[B], b.nodes[tB]], b.step), B, tB)
    return b.build("eye", "3D (tilted plane); three curves between two nodes, 2.5h apart, meeting at 30 degrees")


def _window() -> CurveNetwork:
    b = _Builder(0.015)
    R = _rot(0.7, 0.4, -0.3)
    g = [0.0, 1 / 3, 2 / 3, 1.0]
    ids = {}
    for i, x in enumerate(g):
        for j, y in enumerate(g):
            ids[i, j] = b.node(matvec(R, [x, y, 0.0]))
    for i in range(4):
        for j in range(3):
            b.curve(_poly([b.nodes[ids[i, j]], b.nodes[ids[i, j + 1]]], b.step), ids[i, j], ids[i, j + 1])
            b.curve(_poly([b.nodes[ids[j, i]], b.nodes[ids[j + 1, i]]], b.step), ids[j, i], ids[j + 1, i])
    return b.build("window", "planar network in 3D: 3x3 grid, valence 4 and 3, right-angle corners")


def _sphere() -> CurveNetwork:
    b = _Builder(0.03)

    def sph(lat, lon):
        return np.column_stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])

    lats = np.deg2rad([-60.0, 0.0, 60.0])
    lons = np.deg2rad(60.0 * np.arange(6) + 10.0)
    ids = {(i, j): b.node(sph(np.array([la]), np.array([lo]))[0]) for i, la in enumerate(lats) for j, lo in enumerate(lons)}
    for i, la in enumerate(lats):
        for j, lo in enumerate(lons):
            lo1 = lo + np.pi / 3
            b.param(lambda t, la=la: sph(np.full_like(t, la), t), lo, lo1, ids[i, j], ids[i, (j + 1) % 6])
            if i < 2:
                b.param(lambda t, lo=lo: sph(t, np.full_like(t, lo)), la, lats[i + 1], ids[i, j], ids[i + 1, j])
    return b.build("sphere", "lat-long grid on a sphere with polar loops: curved surface, valence 3 and 4")


def _torus() -> CurveNetwork:
    b = _Builder(0.03)
    Rr, r = 1.0, 0.4

    def tor(th, ph):
        return np.column_stack([(Rr + r * np.cos(th)) * np.cos(ph), (Rr + r * np.cos(th)) * np.sin(ph), r * np.sin(th)])

    ths = np.deg2rad(90.0 * np.arange(4))
    phs = np.deg2rad(60.0 * np.arange(6))
    ids = {(i, j): b.node(tor(np.array([th]), np.array([ph]))[0]) for i, th in enumerate(ths) for j, ph in enumerate(phs)}
    for i, th in enumerate(ths):
        for j, ph in enumerate(phs):
            b.param(lambda t, th=th: tor(np.full_like(t, th), t), ph, ph + np.pi / 3, ids[i, j], ids[i, (j + 1) % 6])
            b.param(lambda t, ph=ph: tor(t, np.full_like(t, ph)), th, th + np.pi / 2, ids[i, j], ids[(i + 1) % 4, j])
    return b.build("torus", "grid on a torus: curved surface of both signs of curvature, valence 4")


def _star8() -> CurveNetwork:
    b = _Builder(0.02)
    o = b.node([0.0, 0.0, 0.0])
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                d = np.array([sx, sy, sz], dtype=float) / np.sqrt(3)
                w = np.cross(d, [0.0, 0.0, 1.0]) if abs(d[2]) < 0.99 else np.array([1.0, 0, 0])
                w = 0.1 * w / norm(w)
                f = lambda t, d=d, w=w: t[:, None] * d + (t**2)[:, None] * w
                e = b.node(f(np.array([1.0]))[0])
                b.param(f, 0.0, 1.0, o, e)
    return b.build("star8", "3D; one node of valence 8 (curves 70 degrees apart), free ends")


def _pyramid() -> CurveNetwork:
    b = _Builder(0.02)
    apex = b.node([0.0, 0.0, 0.8])
    ang = 2 * np.pi * np.arange(5) / 5
    base = [b.node([np.cos(a), np.sin(a), 0.0]) for a in ang]
    for k in range(5):
        b.curve(_poly([b.nodes[apex], b.nodes[base[k]]], b.step), apex, base[k])
        b.curve(_poly([b.nodes[base[k]], b.nodes[base[(k + 1) % 5]]], b.step), base[k], base[(k + 1) % 5])
    return b.build("pyramid", "3D pentagonal pyramid: apex of valence 5, base of valence 3")


def _corners() -> CurveNetwork:
    b = _Builder(0.02)
    zig = np.array([[0, 0, 0], [0.5, 0, 0], [0.5, 0.5, 0], [0.75, 0.07, 0.0], [1.0, 0.5, 0.3], [1.4, 0.5, 0.6]])
    a, e = b.node(zig[0]), b.node(zig[-1])
    b.curve(_poly(zig, b.step), a, e)
    b.loop(_poly([[0, 1, 0], [0.6, 1, 0], [0.6, 1, 0.6], [0, 1, 0.6]], b.step, closed=True))
    b.loop(_poly([[1.0, 1.0, 0], [1.6, 1.0, 0], [1.3, 1.5, 0.4]], b.step, closed=True))
    return b.build("corners", "3D; sharp corners (90, 60, 30 degrees) inside an open curve and in closed loops")


def _mug() -> CurveNetwork:
    b = _Builder(0.02)
    r, H = 0.5, 1.0
    ang = np.deg2rad([0.0, 90.0, 180.0, 270.0])
    bot = [b.node([r * np.cos(a), r * np.sin(a), 0.0]) for a in ang]
    top = [b.node([r * np.cos(a), r * np.sin(a), H]) for a in ang]
    for k in range(4):
        for z, ring in ((0.0, bot), (H, top)):
            f = lambda t, z=z: np.column_stack([r * np.cos(t), r * np.sin(t), np.full_like(t, z)])
            b.param(f, ang[k], ang[k] + np.pi / 2, ring[k], ring[(k + 1) % 4])
    h1, h2 = b.node([r, 0.0, 0.25]), b.node([r, 0.0, 0.75])
    chain = [bot[0], h1, h2, top[0]]
    zs = [0.0, 0.25, 0.75, H]
    for k in range(3):
        b.curve(_poly([[r, 0, zs[k]], [r, 0, zs[k + 1]]], b.step), chain[k], chain[k + 1])
    for k in (1, 2, 3):
        b.curve(_poly([b.nodes[bot[k]], b.nodes[top[k]]], b.step), bot[k], top[k])
    f = lambda t: np.column_stack([r + 0.3 * np.sin(np.pi * t), 0 * t, 0.25 + 0.5 * t])
    b.param(f, 0.0, 1.0, h1, h2)
    return b.build("mug", "3D mug: rings, four lines and a handle, valence 3")


def _speaker() -> CurveNetwork:
    b = _Builder(0.015)
    W, D, H = 0.6, 0.4, 1.0
    ids = {}
    for i, x in enumerate((0, W)):
        for j, y in enumerate((0, D)):
            for k, z in enumerate((0, H)):
                ids[i, j, k] = b.node([x, y, z])
    keys = list(ids)
    for p in keys:
        for q in keys:
            if p < q and sum(a != c for a, c in zip(p, q)) == 1:
                b.curve(_poly([b.nodes[ids[p]], b.nodes[ids[q]]], b.step), ids[p], ids[q])
    for cz, rad in ((0.3, 0.18), (0.75, 0.08)):
        f = _circle([W / 2, 0.0, cz], rad, [1, 0, 0], [0, 0, 1])
        b.loop(_param(f, 0.0, 2 * np.pi, b.step)[:-1])
    return b.build("speaker", "3D box with two circles on its front face (loops without nodes)")


def _fig8() -> CurveNetwork:
    b = _Builder(0.02)
    f = _circle([0.0, 0.0], 0.5, [1, 0], [0, 1])
    b.loop(_param(f, 0.0, 2 * np.pi, b.step)[:-1])
    g = lambda t: np.column_stack([t, -0.5 - 3 * 0.02 - 0.15 * t**2 + 0.05 * np.sin(3 * t) * t])
    a, e = b.node(g(np.array([-1.0]))[0]), b.node(g(np.array([1.0]))[0])
    b.param(g, -1.0, 1.0, a, e)
    return b.build("fig8", "2D (the paper's Figure 8): a circle and an open curve passing 3h from it")


def fork(stem: float, half_angle: float, length: float = 30.0) -> CurveNetwork:
    """Two close junctions (2D, spacing h = 1): a T whose stem forks ``stem`` away from the line.

    A line from (-length, 0) to (length, 0); a stem from (0, 0) to (0, stem); two branches of
    ``length`` from (0, stem) at +- ``half_angle`` from the stem's direction. The parametric case
    of ``benchmarks/fork_stress.py`` (not one of :data:`MODELS`).

    Parameters
    ----------
    stem : float
        Length of the stem between the two junctions, in h.
    half_angle : float
        Angle of each branch from the stem's direction, degrees.
    length : float
        Length of the line's halves and of the branches, in h.

    Returns
    -------
    CurveNetwork
        6 nodes (2 junctions, 4 free ends) and 5 straight curves sampled every 0.1 h;
        ``parameters["h"] = 1``.

    Raises
    ------
    InputError
        For a non-positive ``stem`` or ``length``, or a half-angle outside (0, 90) degrees.
    """
    if not (stem > 0 and length > 0):
        raise InputError(f"stem and length must be positive, got {stem!r} and {length!r}")
    if not 0 < half_angle < 90:
        raise InputError(f"half_angle must be between 0 and 90 degrees, got {half_angle!r}")
    a = np.radians(half_angle)
    b = _Builder(1.0)
    V = [b.node([x, y]) for x, y in [(-length, 0.0), (length, 0.0), (0.0, 0.0), (0.0, stem),
                                      (length * np.sin(a), stem + length * np.cos(a)),
                                      (-length * np.sin(a), stem + length * np.cos(a))]]
    for i, j in [(0, 2), (2, 1), (2, 3), (3, 4), (3, 5)]:
        b.curve(_poly([b.nodes[V[i]], b.nodes[V[j]]], b.step), V[i], V[j])
    return b.build("fork", f"2D; a T whose stem forks {stem:g}h away, branches {half_angle:g} degrees from it")


#: Model name -> builder (no argument, returns a CurveNetwork).
MODELS: dict[str, Callable[[], CurveNetwork]] = {
    "cube": _cube,
    "wheel": _wheel,
    "fan": _fan,
    "crossing": _crossing,
    "tree": _tree,
    "knot": _knot,
    "eye": _eye,
    "window": _window,
    "sphere": _sphere,
    "torus": _torus,
    "star8": _star8,
    "pyramid": _pyramid,
    "corners": _corners,
    "mug": _mug,
    "speaker": _speaker,
    "fig8": _fig8,
}


def model_names() -> list[str]:
    """Names of the synthetic models, in benchmark order."""
    return list(MODELS)


def h_of(net: CurveNetwork) -> float:
    """The reference sampling spacing of a ground-truth network (``parameters["h"]``).

    Raises
    ------
    InputError
        When the network has no ``h`` parameter.
    """
    try:
        return float(net.parameters["h"])
    except (KeyError, TypeError, ValueError):
        raise InputError("network has no reference spacing parameters['h']") from None
