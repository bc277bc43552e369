"""Curve networks drawn on known surfaces: ground truth for surfacing (issue 24).

Each model is a :class:`SurfaceModel`: the true network (curves lying exactly on the surface,
sampled like the models of :mod:`curvenet.synth.models`, ``parameters["h"]`` its reference
spacing), the exact distance of points to the true surface, a sampler of the true surface
(for the distance from the surface to a mesh), and what a faithful surfacing of the network
must give: its count of patches and of boundary loops.

>>> from curvenet.synth import surfaces
>>> m = surfaces.surface_model("saddle")
>>> m.patches, m.boundary_loops
(9, 1)
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from ..errors import InputError
from ..network import CurveNetwork
from .models import _Builder, _poly, _sphere, _torus

__all__ = ["SurfaceModel", "SURFACE_MODELS", "surface_model", "surface_model_names"]

#: Reference sampling spacing of the new models (the sphere's and torus's is theirs, 0.03).
H = 0.02
#: Samples per unit length along each parameter when sampling a true surface.
SAMPLES_PER_UNIT = 200


class SurfaceModel(NamedTuple):
    """A curve network on a known surface.

    Attributes
    ----------
    network : CurveNetwork
        The true network (``parameters["h"]``: the reference spacing h).
    distance : callable
        ``distance(points)``: (n, 3) ndarray -> (n,) ndarray, the distance of each point to the
        true surface (exact, or to within 1e-6 of the model's size).
    sample : callable
        ``sample(density)`` -> (m, 3) ndarray: points on the true surface, about ``density``
        per unit length along each parameter (uniform in the parameters, not in area).
    patches : int
        The patches a designer would draw: the faces of the network on the surface.
    boundary_loops : int
        Boundary loops of the true surface (0 where it is closed).
    open_curves : tuple of int
        The curves of ``network`` on the true surface's boundary (each borders one patch): what
        a designer would name as openings (``surface(..., open_curves=...)``).
    """

    network: CurveNetwork
    distance: Callable[[np.ndarray], np.ndarray]
    sample: Callable[[int], np.ndarray]
    patches: int
    boundary_loops: int
    open_curves: tuple = ()


def _grid(u0, u1, v0, v1, density, f):
    """Evaluate ``f(u, v)`` -> (n, 3) on a parameter grid of about ``density`` steps per unit."""
    nu = max(int(np.ceil((u1 - u0) * density)), 2)
    nv = max(int(np.ceil((v1 - v0) * density)), 2)
    u, v = np.meshgrid(np.linspace(u0, u1, nu + 1), np.linspace(v0, v1, nv + 1), indexing="ij")
    return f(u.ravel(), v.ravel())


def _polyline_distance(q: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance of points ``q`` (n, 2) to a dense open polyline ``line`` (m, 2).

    The nearest polyline point is on one of the two segments at the nearest vertex (the
    polyline is dense and smooth against the distances measured).
    """
    from scipy.spatial import cKDTree

    i = cKDTree(line).query(q)[1]
    best = np.full(len(q), np.inf)
    for a, b in ((np.maximum(i - 1, 0), i), (i, np.minimum(i + 1, len(line) - 1))):
        A, B = line[a], line[b]
        e = B - A
        ee = np.einsum("ij,ij->i", e, e)
        t = np.clip(np.einsum("ij,ij->i", q - A, e) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(q - (A + t[:, None] * e), axis=1))
    return best


# --- sphere and torus: the models of curvenet.synth.models ---------------------------------------
def _sphere_model() -> SurfaceModel:
    def sample(density):
        return _grid(-np.pi / 2, np.pi / 2, 0, 2 * np.pi, density, lambda la, lo: np.column_stack(
            [np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)]))

    return SurfaceModel(_sphere(), lambda p: np.abs(np.linalg.norm(p, axis=1) - 1.0), sample, 14, 0)


#: Radii of the torus of :func:`curvenet.synth.models._torus`.
TORUS_R, TORUS_r = 1.0, 0.4


def _torus_model() -> SurfaceModel:
    def dist(p):
        return np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - TORUS_R, p[:, 2]) - TORUS_r)

    def sample(density):
        return _grid(0, 2 * np.pi * TORUS_r, 0, 2 * np.pi * TORUS_R, density, lambda a, b: np.column_stack(
            [(TORUS_R + TORUS_r * np.cos(a / TORUS_r)) * np.cos(b / TORUS_R),
             (TORUS_R + TORUS_r * np.cos(a / TORUS_r)) * np.sin(b / TORUS_R), TORUS_r * np.sin(a / TORUS_r)]))

    return SurfaceModel(_torus(), dist, sample, 24, 0)


# --- surfaces of revolution: a capped cylinder and an open vase ---------------------------------
def _revolution(name, features, profile, zs, *, bottom_cap: bool, top_cap: bool, n_meridians: int = 4):
    """A network of parallels at heights ``zs`` and meridians on the surface rho = profile(z).

    The true surface is the surface of revolution, plus flat disks at the lowest and highest
    parallel where ``bottom_cap`` / ``top_cap``.
    """
    b = _Builder(H)
    ang = 2 * np.pi * np.arange(n_meridians) / n_meridians
    ids = [[b.node([profile(z) * np.cos(a), profile(z) * np.sin(a), z]) for a in ang] for z in zs]
    for i, z in enumerate(zs):
        for k, a in enumerate(ang):
            f = lambda t, z=z: np.column_stack([profile(z) * np.cos(t), profile(z) * np.sin(t), np.full_like(t, z)])
            b.param(f, a, a + 2 * np.pi / n_meridians, ids[i][k], ids[i][(k + 1) % n_meridians])
            if i + 1 < len(zs):
                g = lambda t, a=a: np.column_stack([profile(t) * np.cos(a), profile(t) * np.sin(a), t])
                b.param(g, z, zs[i + 1], ids[i][k], ids[i + 1][k])
    net = b.build(name, features)

    # the profile (and the caps' radii), finely sampled, for distances in the (rho, z) half-plane
    tz = np.linspace(zs[0], zs[-1], 20001)
    pieces = [np.column_stack([profile(tz), tz])]
    for on, z in ((bottom_cap, zs[0]), (top_cap, zs[-1])):
        if on:
            pieces.append(np.column_stack([np.linspace(0, profile(z), 2001), np.full(2001, z)]))

    def dist(p):
        q = np.column_stack([np.hypot(p[:, 0], p[:, 1]), p[:, 2]])
        return np.min([_polyline_distance(q, line) for line in pieces], axis=0)

    def sample(density):
        out = [_grid(zs[0], zs[-1], 0, 2 * np.pi, density, lambda z, a: np.column_stack(
            [profile(z) * np.cos(a), profile(z) * np.sin(a), z]))]
        for on, z in ((bottom_cap, zs[0]), (top_cap, zs[-1])):
            if on:
                out.append(_grid(0, profile(z), 0, 2 * np.pi, density, lambda r, a, z=z: np.column_stack(
                    [r * np.cos(a), r * np.sin(a), np.full_like(r, z)])))
        return np.vstack(out)

    n_side = (len(zs) - 1) * n_meridians
    patches = n_side + bottom_cap + top_cap
    rims = [z for on, z in ((bottom_cap, zs[0]), (top_cap, zs[-1])) if not on]
    open_curves = tuple(i for i, c in enumerate(net.curves) if any(np.allclose(c.points[:, 2], z) for z in rims))
    return SurfaceModel(net, dist, sample, patches, 2 - bottom_cap - top_cap, open_curves)


def _capped_cylinder() -> SurfaceModel:
    return _revolution("capped_cylinder", "cylinder (radius 0.5, height 1) with two flat caps: closed, genus 0",
                       lambda z: np.full_like(np.asarray(z, dtype=float), 0.5), [0.0, 0.5, 1.0],
                       bottom_cap=True, top_cap=True)


def _vase() -> SurfaceModel:
    return _revolution("vase", "surface of revolution with a bulge and a neck, flat bottom, open top",
                       lambda z: 0.45 + 0.15 * np.sin(np.pi * (1.5 * np.asarray(z, dtype=float) - 0.25)),
                       [0.0, 0.4, 0.8, 1.2], bottom_cap=True, top_cap=False)


# --- a saddle: an open height field ------------------------------------------------------------
def _saddle_z(x, y):
    return 0.5 * (x**2 - y**2)


def _saddle() -> SurfaceModel:
    b = _Builder(H)
    ts = np.linspace(-1.0, 1.0, 4)
    ids = {(i, j): b.node([x, y, _saddle_z(x, y)]) for i, x in enumerate(ts) for j, y in enumerate(ts)}
    for i, x in enumerate(ts):
        for j in range(3):
            f = lambda t, x=x: np.column_stack([np.full_like(t, x), t, _saddle_z(x, t)])
            b.param(f, ts[j], ts[j + 1], ids[i, j], ids[i, j + 1])
            g = lambda t, x=x: np.column_stack([t, np.full_like(t, x), _saddle_z(t, x)])
            b.param(g, ts[j], ts[j + 1], ids[j, i], ids[j + 1, i])
    net = b.build("saddle", "hyperbolic paraboloid z = (x^2 - y^2) / 2 over [-1, 1]^2: open, negative curvature")

    def dist(p):
        # Newton steps to the foot point on the graph, then the distance to it
        q = p[:, :2].copy()
        for _ in range(30):
            x, y = q[:, 0], q[:, 1]
            r = _saddle_z(x, y) - p[:, 2]
            # gradient and Hessian of |(x, y, z(x, y)) - p|^2 / 2 in (x, y)
            gx = (x - p[:, 0]) + r * x
            gy = (y - p[:, 1]) - r * y
            hxx = 1 + x * x + r
            hyy = 1 + y * y - r
            hxy = -x * y
            det = hxx * hyy - hxy * hxy
            q = q - np.column_stack([(hyy * gx - hxy * gy) / det, (hxx * gy - hxy * gx) / det])
            q = np.clip(q, -1.0, 1.0)
        foot = np.column_stack([q, _saddle_z(q[:, 0], q[:, 1])])
        return np.linalg.norm(p - foot, axis=1)

    def sample(density):
        return _grid(-1, 1, -1, 1, density, lambda x, y: np.column_stack([x, y, _saddle_z(x, y)]))

    # (the curves through a corner of the square turn there: every point on one side or the other)
    border = tuple(i for i, c in enumerate(net.curves)
                   if np.all(np.isclose(np.abs(c.points[:, :2]), 1.0).any(axis=1)))
    return SurfaceModel(net, dist, sample, 9, 1, border)


# --- a box with one filleted edge --------------------------------------------------------------
#: Fillet radius of the box's rounded edge (the edge x = 1, z = 1 of the unit box).
FILLET_R = 0.3


def _fillet_box() -> SurfaceModel:
    b = _Builder(H)
    r = FILLET_R
    c = 1.0 - r  # the fillet's axis is x = z = c
    ids = {}
    for y in (0.0, 1.0):
        for key, p in (("o", [0, y, 0]), ("x", [1, y, 0]), ("xz", [1, y, c]), ("zx", [c, y, 1]), ("z", [0, y, 1])):
            ids[key, y] = b.node(p)
    ring = ["o", "x", "xz", "zx", "z"]
    for y in (0.0, 1.0):
        for a_, b_ in zip(ring, ring[1:] + ring[:1]):
            if (a_, b_) == ("xz", "zx"):
                f = lambda t, y=y: np.column_stack([c + r * np.cos(t), np.full_like(t, y), c + r * np.sin(t)])
                b.param(f, 0.0, np.pi / 2, ids[a_, y], ids[b_, y])
            else:
                b.curve(_poly([b.nodes[ids[a_, y]], b.nodes[ids[b_, y]]], b.step), ids[a_, y], ids[b_, y])
    for key in ring:
        b.curve(_poly([b.nodes[ids[key, 0.0]], b.nodes[ids[key, 1.0]]], b.step), ids[key, 0.0], ids[key, 1.0])
    net = b.build("fillet_box", "unit box whose edge x = z = 1 is rounded (radius 0.3): planes and a quarter cylinder")

    def dist(p):
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        cy = np.clip(y, 0, 1)

        def rect(u, v, w, ulo, uhi, vlo, vhi):  # distance to a rectangle in a coordinate plane
            return np.sqrt((u - np.clip(u, ulo, uhi)) ** 2 + (v - np.clip(v, vlo, vhi)) ** 2 + w**2)

        d = [rect(x, y, z, 0, 1, 0, 1), rect(x, y, z - 1, 0, c, 0, 1),        # bottom, top
             rect(y, z, x, 0, 1, 0, 1), rect(y, z, x - 1, 0, 1, 0, c),        # x = 0, x = 1
             ]
        # the two side faces y = 0, 1: the rectangle [0, 1]^2 less the corner beyond the fillet
        for y0 in (0.0, 1.0):
            cx, cz = np.clip(x, 0, 1), np.clip(z, 0, 1)
            beyond = (cx > c) & (cz > c) & (np.hypot(cx - c, cz - c) > r)
            ang = np.arctan2(cz - c, cx - c)
            fx, fz = c + r * np.cos(ang), c + r * np.sin(ang)
            cx, cz = np.where(beyond, fx, cx), np.where(beyond, fz, cz)
            d.append(np.sqrt((x - cx) ** 2 + (z - cz) ** 2 + (y - y0) ** 2))
        ang = np.clip(np.arctan2(z - c, x - c), 0, np.pi / 2)
        fx, fz = c + r * np.cos(ang), c + r * np.sin(ang)
        d.append(np.sqrt((x - fx) ** 2 + (z - fz) ** 2 + (y - cy) ** 2))
        return np.min(d, axis=0)

    def sample(density):
        one = lambda f: _grid(0, 1, 0, 1, density, f)
        pts = [one(lambda u, v: np.column_stack([u, v, 0 * u])), one(lambda u, v: np.column_stack([c * u, v, 1 + 0 * u])),
               one(lambda u, v: np.column_stack([0 * u, u, v])), one(lambda u, v: np.column_stack([1 + 0 * u, u, c * v])),
               one(lambda u, v: np.column_stack([c + r * np.cos(u * np.pi / 2), v, c + r * np.sin(u * np.pi / 2)]))]
        for y0 in (0.0, 1.0):
            s = one(lambda u, v: np.column_stack([u, np.full_like(u, y0), v]))
            keep = ~((s[:, 0] > c) & (s[:, 2] > c) & (np.hypot(s[:, 0] - c, s[:, 2] - c) > r))
            pts.append(s[keep])
        return np.vstack(pts)

    return SurfaceModel(net, dist, sample, 7, 0)


#: Every surface model by name.
SURFACE_MODELS: dict[str, Callable[[], SurfaceModel]] = {
    "sphere": _sphere_model,
    "torus": _torus_model,
    "capped_cylinder": _capped_cylinder,
    "saddle": _saddle,
    "fillet_box": _fillet_box,
    "vase": _vase,
}


def surface_model_names() -> list[str]:
    """Names of the surface models, in benchmark order."""
    return list(SURFACE_MODELS)


def surface_model(name: str) -> SurfaceModel:
    """Build a curve network on a known surface by name.

    Parameters
    ----------
    name : str
        A key of :data:`SURFACE_MODELS`.

    Returns
    -------
    SurfaceModel

    Raises
    ------
    InputError
        For an unknown name.
    """
    if name not in SURFACE_MODELS:
        raise InputError(f"unknown surface model {name!r}; expected one of: {', '.join(SURFACE_MODELS)}")
    return SURFACE_MODELS[name]()
