"""Surfacing (issue 4): cycles, patches, assembly, writers, CLI and picture."""

from __future__ import annotations

import importlib.util
import itertools
import json
import warnings
import subprocess
import sys

import numpy as np
import pytest

from curvenet import Curve, CurveNetwork, InputError
from curvenet.surfacing import SurfaceMesh, min_area_triangulation, surface
from curvenet.io.mesh import mesh_to_obj, mesh_to_ply
from curvenet.surfacing.assemble import _split_shared_chords
from curvenet.surfacing.cycles import _orient
from curvenet.surfacing.patches import is_simple_polygon

synth = pytest.importorskip("curvenet.synth")
pytest.importorskip("triangle")


# ---------------------------------------------------------------------------------------------
# networks
# ---------------------------------------------------------------------------------------------
def coarsen(net: CurveNetwork, k: int = 25) -> CurveNetwork:
    """Keep every k-th point of each curve (ends kept): the synthetic models are very dense."""
    curves = []
    for c in net.curves:
        m = len(c.points)
        if c.start is None:
            idx = np.arange(0, m, k)
        else:
            idx = np.unique(np.r_[np.arange(0, m - 1, k), m - 1])
            if len(idx) > 2 and idx[-1] - idx[-2] < k // 2:
                idx = np.delete(idx, -2)
        curves.append(Curve(c.points[idx], c.start, c.end, c.closed, c.indices[idx]))
    return CurveNetwork(net.nodes, curves, dict(net.parameters))


def grid_network(f, nu, nv, periodic_u, periodic_v, m=7):
    """Grid lines of a parametric surface f(u, v) on [0, 1]^2 (periodic directions wrap)."""
    us = np.arange(nu) / nu if periodic_u else np.linspace(0, 1, nu)
    vs = np.arange(nv) / nv if periodic_v else np.linspace(0, 1, nv)
    du = 1 / nu if periodic_u else 1 / (nu - 1)
    dv = 1 / nv if periodic_v else 1 / (nv - 1)
    nodes = np.array([f(u, v) for u in us for v in vs])
    t = np.linspace(0, 1, m)
    curves = []
    for i, j in itertools.product(range(nu), range(nv)):
        if i + 1 < nu or periodic_u:
            curves.append(Curve(np.array([f(us[i] + s * du, vs[j]) for s in t]), i * nv + j, ((i + 1) % nu) * nv + j))
        if j + 1 < nv or periodic_v:
            curves.append(Curve(np.array([f(us[i], vs[j] + s * dv) for s in t]), i * nv + j, i * nv + (j + 1) % nv))
    return CurveNetwork(nodes, curves)


def sheet_fn(u, v):
    x, y = 2 * u - 1, 2 * v - 1
    return np.array([x, y, 0.4 * (x * x - y * y) + 0.3 * x])


def curved_sheet(n=5):
    return grid_network(sheet_fn, n, n, False, False)


def prism(outline, height=1.0, m=6):
    """Wireframe of an extruded polygon (concave outlines give concave nodes)."""
    outline = np.asarray(outline, dtype=float)
    k = len(outline)
    nodes = np.vstack([np.c_[outline, np.zeros(k)], np.c_[outline, np.full(k, height)]])
    t = np.linspace(0, 1, m)[:, None]
    curves = []
    for i in range(k):
        for a, b in ((i, (i + 1) % k), (k + i, k + (i + 1) % k), (i, k + i)):
            curves.append(Curve(nodes[a] * (1 - t) + nodes[b] * t, a, b))
    return CurveNetwork(nodes, curves)


L_OUTLINE = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]


def ring(n=40, r=1.0, z=0.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([r * np.cos(t), r * np.sin(t), np.full(n, z)])


@pytest.fixture(scope="module")
def meshes():
    """Each test network with its mesh (computed once)."""
    nets = {
        "cube": coarsen(synth.model("cube")),
        "torus": coarsen(synth.model("torus")),
        "sphere": coarsen(synth.model("sphere")),
        "sheet": curved_sheet(),
        "lprism": prism(L_OUTLINE),
        "pyramid": coarsen(synth.model("pyramid")),
        "wheel": coarsen(synth.model("wheel")),
    }
    return {name: (net, surface(net)) for name, net in nets.items()}


# ---------------------------------------------------------------------------------------------
# mesh checks
# ---------------------------------------------------------------------------------------------
def edge_slots(T):
    return np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), np.tile(np.arange(len(T)), 3)


def is_manifold_and_oriented(T):
    e, _ = edge_slots(T)
    _, cnt = np.unique(np.sort(e, axis=1), axis=0, return_counts=True)
    _, dcnt = np.unique(e, axis=0, return_counts=True)
    return bool(cnt.max() <= 2), bool(dcnt.max() == 1)


def edges_between_patches(mesh):
    e, f = edge_slots(mesh.triangles)
    key = np.sort(e, axis=1)
    order = np.lexsort(key.T[::-1])
    key, f = key[order], f[order]
    same = (key[1:] == key[:-1]).all(axis=1) & (mesh.patch[f[1:]] != mesh.patch[f[:-1]])
    return {tuple(map(int, k)) for k in key[:-1][same]}


def curve_edges(mesh, curves):
    out = set()
    for c in curves:
        ids = list(mesh.curve_vertices[c])
        for a, b in zip(ids[:-1], ids[1:]):
            out.add((min(a, b), max(a, b)))
    return out


def self_intersections(V, T):
    """Number of (edge, triangle) crossings between triangles that share no vertex."""
    from scipy.spatial import cKDTree

    cen = V[T].mean(axis=1)
    rad = np.linalg.norm(V[T] - cen[:, None], axis=2).max(axis=1)
    lists = cKDTree(cen).query_ball_point(cen, 2 * rad * (1 + 1e-9))
    a = np.repeat(np.arange(len(T)), [len(x) for x in lists])
    b = np.concatenate([np.asarray(x, dtype=np.int64) for x in lists])
    keep = (rad[b] < rad[a]) | ((rad[b] == rad[a]) & (b > a))
    a, b = a[keep], b[keep]
    share = (T[a][:, :, None] == T[b][:, None, :]).any(axis=(1, 2))
    a, b = a[~share], b[~share]
    hits = 0
    for x, y in ((a, b), (b, a)):
        for i, j in ((0, 1), (1, 2), (2, 0)):
            p, q = V[T[x, i]], V[T[x, j]]
            v0, v1, v2 = V[T[y, 0]], V[T[y, 1]], V[T[y, 2]]
            d, e1, e2 = q - p, v1 - v0, v2 - v0
            h = np.cross(d, e2)
            det = np.einsum("ij,ij->i", e1, h)
            ok = np.abs(det) > 1e-12 * np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            s = p - v0
            u = inv * np.einsum("ij,ij->i", s, h)
            qq = np.cross(s, e1)
            v = inv * np.einsum("ij,ij->i", d, qq)
            t = inv * np.einsum("ij,ij->i", e2, qq)
            hits += int((ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)).sum())
    return hits


def triangle_areas(mesh):
    V, T = mesh.vertices, mesh.triangles
    return 0.5 * np.linalg.norm(np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]), axis=1)


def signed_volume(mesh):
    V, T = mesh.vertices, mesh.triangles
    return float(np.einsum("ij,ij->i", V[T[:, 0]], np.cross(V[T[:, 1]], V[T[:, 2]])).sum() / 6)


# ---------------------------------------------------------------------------------------------
# the acceptance tests
# ---------------------------------------------------------------------------------------------
def test_cube_six_patches_watertight_chi2(meshes):
    net, mesh = meshes["cube"]
    assert isinstance(mesh, SurfaceMesh)
    assert mesh.n_patches == 6
    assert all(len(c) == 4 for c in mesh.cycles)
    assert len(mesh.boundary_edges()) == 0
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    assert mesh.euler_characteristic == 2
    assert signed_volume(mesh) == pytest.approx(1.0, rel=1e-6)  # outward, and the faces are flat
    trimesh = pytest.importorskip("trimesh")
    tm = trimesh.Trimesh(mesh.vertices, mesh.triangles, process=False)
    assert tm.is_watertight and tm.is_winding_consistent


def test_torus_chi0_and_close_to_torus(meshes):
    net, mesh = meshes["torus"]
    assert mesh.n_patches == 24
    assert len(mesh.boundary_edges()) == 0
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    assert mesh.euler_characteristic == 0
    V = mesh.vertices

    def dist(p):
        return np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1.0, p[:, 2]) - 0.4)

    for cyc in mesh.cycles:  # the cycles are the curves: exactly on the torus
        ids = np.concatenate([mesh.curve_vertices[c] for c in cyc])
        assert dist(V[ids]).max() < 1e-6  # the model samples are interpolated: ~1e-8 off
    # patches span 90 x 60 degrees of the tube (radius 0.4): measured deviation 0.052 with
    # fairing by the curves' curvature, 0.133 for flat (harmonic) membranes
    assert dist(V).max() < 0.07
    flat = surface(net, fair=False)
    assert dist(flat.vertices).max() > 2 * dist(V).max()
    assert signed_volume(mesh) > 0


def test_sphere_with_polar_loops_closed_chi2(meshes):
    net, mesh = meshes["sphere"]
    assert mesh.n_patches == 14  # 12 quads and the two polar caps
    assert sorted(len(c) for c in mesh.cycles)[-2:] == [6, 6]
    assert len(mesh.boundary_edges()) == 0
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    assert mesh.euler_characteristic == 2
    r = np.linalg.norm(mesh.vertices, axis=1)
    for cyc in mesh.cycles:
        ids = np.concatenate([mesh.curve_vertices[c] for c in cyc])
        assert np.abs(r[ids] - 1).max() < 1e-6
    # measured: within 0.015 of the sphere, caps included (flat caps would sag by
    # 1 - cos(30 deg) = 0.134, flat membranes on the quads by 0.11)
    assert np.abs(r - 1).max() < 0.02
    flat = surface(net, fair=False)
    assert np.abs(np.linalg.norm(flat.vertices, axis=1) - 1).max() > 0.1
    assert signed_volume(mesh) > 0


def test_open_sheet_boundary_is_outer_curves(meshes):
    net, mesh = meshes["sheet"]
    assert mesh.n_patches == 16
    assert mesh.euler_characteristic == 1
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    e = net.edges
    pos = net.nodes
    outer = [c for c in range(net.n_curves) if np.all(np.isclose(np.abs(pos[e[c]][:, 0]), 1)) or np.all(np.isclose(np.abs(pos[e[c]][:, 1]), 1))]
    assert len(outer) == 16
    bnd = {tuple(map(int, b)) for b in mesh.boundary_edges()}
    assert bnd == curve_edges(mesh, outer)
    # the surface follows the sheet (interior vertices within a small distance of z = f(x, y))
    V = mesh.vertices
    z = 0.4 * (V[:, 0] ** 2 - V[:, 1] ** 2) + 0.3 * V[:, 0]
    assert np.abs(V[:, 2] - z).max() < 0.006  # measured 0.0044


@pytest.mark.parametrize("name", ["cube", "torus", "sphere", "sheet", "lprism", "pyramid", "wheel"])
def test_patch_seams_are_curves_no_degenerate_no_intersection(meshes, name):
    net, mesh = meshes[name]
    used = {}
    for cyc in mesh.cycles:
        for c in cyc:
            used[c] = used.get(c, 0) + 1
    assert max(used.values()) <= 2
    twice = [c for c, n in used.items() if n == 2]
    once = [c for c, n in used.items() if n == 1]
    assert edges_between_patches(mesh) == curve_edges(mesh, twice)
    assert {tuple(map(int, b)) for b in mesh.boundary_edges()} == curve_edges(mesh, once)
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    # boundary vertices are exactly the curve samples, each once
    for c in used:
        ids = mesh.curve_vertices[c]
        chain = net.curves[c].points
        if chain.shape[1] == 2:
            chain = np.column_stack([chain, np.zeros(len(chain))])
        assert np.array_equal(mesh.vertices[ids], chain)
    assert len(np.unique(np.round(mesh.vertices, 12), axis=0)) == len(mesh.vertices)
    spacing = np.median(np.concatenate([np.linalg.norm(np.diff(c.points, axis=0), axis=1) for c in net.curves]))
    assert triangle_areas(mesh).min() > 1e-3 * spacing**2
    assert self_intersections(mesh.vertices, mesh.triangles) == 0


def test_concave_nodes_lprism(meshes):
    net, mesh = meshes["lprism"]
    assert mesh.n_patches == 8  # two L-shaped caps and six walls
    assert sorted(len(c) for c in mesh.cycles) == [4] * 6 + [6, 6]
    assert mesh.euler_characteristic == 2 and len(mesh.boundary_edges()) == 0
    assert signed_volume(mesh) == pytest.approx(3.0, rel=1e-6)


def test_pyramid_closed(meshes):
    net, mesh = meshes["pyramid"]
    assert mesh.n_patches == 6 and mesh.euler_characteristic == 2
    assert len(mesh.boundary_edges()) == 0


def test_loops_on_a_face_become_holes():
    """The speaker: two circles (loops without node) on the front face of a box."""
    net = coarsen(synth.model("speaker"))
    mesh = surface(net)
    assert mesh.n_patches == 8 and mesh.euler_characteristic == 2
    assert len(mesh.boundary_edges()) == 0
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    loops = [c for c in range(net.n_curves) if net.curves[c].start is None]
    assert len(loops) == 2
    host = [cyc for cyc in mesh.cycles if len(cyc) > 1 and set(loops) & set(cyc)]
    assert len(host) == 1 and set(loops) <= set(host[0])  # the front face has both holes
    assert self_intersections(mesh.vertices, mesh.triangles) == 0
    assert signed_volume(mesh) == pytest.approx(0.6 * 0.4 * 1.0, rel=1e-6)


def test_planar_network_has_no_outer_face(meshes):
    net, mesh = meshes["wheel"]
    assert net.dimension == 2
    assert mesh.n_patches == 6 and mesh.euler_characteristic == 1
    assert np.abs(mesh.vertices[:, 2]).max() == 0.0
    # the disk: total area of a hexagonal fan of circular sectors, i.e. about pi
    assert triangle_areas(mesh).sum() == pytest.approx(np.pi, rel=0.01)


# ---------------------------------------------------------------------------------------------
# small cases
# ---------------------------------------------------------------------------------------------
def test_free_loop_bounds_a_disk():
    mesh = surface(CurveNetwork(np.zeros((0, 3)), [Curve(ring(), None, None, closed=True)]))
    assert mesh.n_patches == 1 and mesh.euler_characteristic == 1
    assert len(mesh.boundary_edges()) == 40
    assert triangle_areas(mesh).sum() == pytest.approx(40 / 2 * np.sin(2 * np.pi / 40), rel=1e-9)


def test_loop_at_node_and_dangling_curves_ignored():
    p = ring(30)
    loop = Curve(np.vstack([p, p[:1]]), 0, 0)
    tail = Curve(np.linspace(p[0], p[0] + [1.0, 0, 0], 8), 0, 1)
    net = CurveNetwork(np.array([p[0], p[0] + [1.0, 0, 0]]), [loop, tail])
    mesh = surface(net)
    assert mesh.cycles == [[0]]
    assert mesh.curve_vertices[1] is None
    assert mesh.euler_characteristic == 1 and len(mesh.boundary_edges()) == 30


def test_empty_and_tree_give_empty_mesh():
    tree = synth.model("tree")
    mesh = surface(coarsen(tree))
    assert mesh.n_patches == 0 and len(mesh.triangles) == 0 and len(mesh.vertices) == 0


def test_cycles_do_not_depend_on_curve_order_or_direction_or_pose():
    net = prism(L_OUTLINE)
    base = {frozenset(c) for c in surface(net).cycles}
    rng = np.random.default_rng(3)
    perm = rng.permutation(net.n_curves)
    curves = [net.curves[i].reversed() if i % 3 == 0 else net.curves[i] for i in perm]
    shuffled = CurveNetwork(net.nodes, curves)
    got = {frozenset(int(perm[c]) for c in cyc) for cyc in surface(shuffled).cycles}
    assert got == base
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moved = CurveNetwork(net.nodes @ q.T * 3.0 + 1.0, [Curve(c.points @ q.T * 3.0 + 1.0, c.start, c.end) for c in net.curves])
    assert {frozenset(c) for c in surface(moved).cycles} == base


def test_target_edge_refines():
    net = prism(L_OUTLINE)
    coarse, fine = surface(net, target_edge=0.3), surface(net, target_edge=0.08)
    assert len(fine.triangles) > 2 * len(coarse.triangles)
    assert fine.euler_characteristic == coarse.euler_characteristic == 2


def test_min_area_triangulation():
    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0.0]])[[0, 1, 2, 3]]
    area, tris = min_area_triangulation(sq)
    assert area == pytest.approx(1.0) and len(tris) == 2
    # a skew quadrilateral: the cheaper diagonal is chosen
    skew = np.array([[0, 0, 0], [1, 0, 0.0], [1, 1, 1.0], [0, 1, 0.0]])
    area, tris = min_area_triangulation(skew)
    a1 = 0.5 * np.linalg.norm(np.cross(skew[1] - skew[0], skew[2] - skew[0])) + 0.5 * np.linalg.norm(np.cross(skew[2] - skew[0], skew[3] - skew[0]))
    a2 = 0.5 * np.linalg.norm(np.cross(skew[1] - skew[0], skew[3] - skew[0])) + 0.5 * np.linalg.norm(np.cross(skew[2] - skew[1], skew[3] - skew[1]))
    assert area == pytest.approx(min(a1, a2))


def test_is_simple_polygon():
    t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    assert is_simple_polygon(np.c_[np.cos(t), np.sin(t)])
    assert not is_simple_polygon(np.c_[np.cos(t), np.sin(2 * t)])  # figure eight
    assert not is_simple_polygon(np.array([[0, 0], [1, 0], [0, 1], [1, 1.0]]))  # bow tie


def test_split_shared_chords():
    """Two patches covering the same square by the same diagonal: split it in the second."""
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0.0]])
    T = np.array([[0, 1, 2], [0, 2, 3], [2, 1, 0], [3, 2, 0]])
    P = np.array([0, 0, 1, 1])
    V2, T2, P2, n = _split_shared_chords(V, T, P)
    assert n == 1 and len(V2) == 5 and len(T2) == 6
    assert is_manifold_and_oriented(T2) == (True, True)
    assert sorted(P2.tolist()) == [0, 0, 1, 1, 1, 1]
    assert (T2[P2 == 0] < 4).all()  # the first patch is untouched


def test_orient_reports_non_orientable_rings():
    # darts 2c (along curve c) and 2c + 1 (against it); three cycles pairwise sharing a curve
    ring = [[0, 2], [3, 4], [5, 1]]  # each curve is run once each way: orientable
    out, bad = _orient(ring)
    assert bad == []
    twisted = [[0, 2], [2, 4], [4, 0]]  # every shared curve run the same way: odd ring
    out, bad = _orient(twisted)
    assert bad  # no orientation makes all three pairs opposite


@pytest.mark.skipif(not synth.cassie.available(), reason="CASSIE dataset not found")
def test_cassie_sketch_is_manifold_and_oriented():
    net = synth.cassie.load("computer-mouse")
    mesh = surface(net, max_triangles=20000)
    assert mesh.n_patches >= 20
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    assert triangle_areas(mesh).min() > 0


@pytest.mark.parametrize("bad", ["net", None, np.zeros((3, 3))])
def test_bad_network(bad):
    with pytest.raises(InputError, match="CurveNetwork"):
        surface(bad)


@pytest.mark.parametrize("h", [0.0, -1.0, np.nan, 1e-5])
def test_bad_target_edge(h):
    with pytest.raises(InputError, match="target_edge"):
        surface(prism(L_OUTLINE), target_edge=h)


def test_non_finite_curve_points():
    net = prism(L_OUTLINE)
    net.curves[3].points[2, 1] = np.nan
    with pytest.raises(InputError, match="curve 3 has non-finite"):
        surface(net)


# ---------------------------------------------------------------------------------------------
# writers, CLI, picture
# ---------------------------------------------------------------------------------------------
def test_writers_roundtrip(tmp_path, meshes):
    trimesh = pytest.importorskip("trimesh")
    net, mesh = meshes["lprism"]
    for ext, data in ((".obj", mesh_to_obj(mesh)), (".ply", mesh_to_ply(mesh)), (".ply", mesh_to_ply(mesh, binary=False))):
        path = tmp_path / f"m{ext}"
        path.write_bytes(data)
        tm = trimesh.load(path, process=False, force="mesh")
        assert np.allclose(tm.vertices, mesh.vertices, atol=1e-8)
        assert np.array_equal(tm.faces, mesh.triangles)
    # a second reader; meshio 5 cannot read binary PLY faces with an extra property (its bug),
    # so the patch property is an option (tests/test_third_party_readers.py reads the default)
    meshio = pytest.importorskip("meshio")
    path = tmp_path / "ascii.ply"
    path.write_bytes(mesh_to_ply(mesh, binary=False, patch=True))
    m = meshio.read(path)
    assert np.allclose(m.points, mesh.vertices)
    assert np.array_equal(m.cells_dict["triangle"], mesh.triangles)
    assert np.array_equal(np.asarray(m.cell_data["patch"][0]), mesh.patch)


def test_cli_surface_obj_ply_png(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("matplotlib")
    net = prism(L_OUTLINE)
    src = tmp_path / "net.json"
    src.write_text(json.dumps(net.to_dict()))
    obj, ply, png = tmp_path / "m.obj", tmp_path / "m.ply", tmp_path / "m.png"
    r = subprocess.run(
        [sys.executable, "-m", "curvenet.cli", "surface", str(src), "-o", str(obj), "-o", str(ply), "--png", str(png)],
        capture_output=True, text=True, timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert "8 patches" in r.stdout and "Euler characteristic 2" in r.stdout
    if importlib.util.find_spec("pymeshlab") and importlib.util.find_spec("igl"):
        assert ("checks: 0 self-intersecting faces, 0 non-manifold edges, 0 boundary loops, genus 0, "
                "0 overlapping patch pairs") in r.stdout
    assert "warning" not in r.stderr
    for path in (obj, ply):
        tm = trimesh.load(path, process=False, force="mesh")
        assert tm.is_watertight and tm.euler_number == 2
        assert tm.volume == pytest.approx(3.0, rel=1e-6)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = subprocess.run([sys.executable, "-m", "curvenet.cli", "surface", str(src), "-o", str(tmp_path / "m.stl")],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "unknown mesh extension" in bad.stderr and "\n" == bad.stderr[-1]


def test_cli_surface_open_leaves_the_named_rim_open(tmp_path):
    """``--open`` names the curves of an opening: the prism's top outline bounds its side walls
    only (no lid), and trimesh reads an open mesh whose one boundary loop is that outline; an id
    the network does not have is one line on stderr, exit 2, no file."""
    trimesh = pytest.importorskip("trimesh")
    net = prism(L_OUTLINE)
    top = [3 * i + 1 for i in range(len(L_OUTLINE))]  # (k + i, k + i + 1): the outline at height 1
    src = tmp_path / "net.json"
    src.write_text(json.dumps(net.to_dict()))
    obj = tmp_path / "m.obj"
    ids = ",".join(map(str, top[:2])) + f",{top[2]}-{top[2]}," + ",".join(map(str, top[3:]))
    r = subprocess.run([sys.executable, "-m", "curvenet.cli", "surface", str(src), "-o", str(obj), "--open", ids],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "7 patches" in r.stdout and "closed" not in r.stdout
    tm = trimesh.load(obj, process=False, force="mesh")
    assert not tm.is_watertight
    edges = tm.edges_sorted
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    rim = uniq[count == 1]
    assert len(rim) > 0 and np.allclose(tm.vertices[np.unique(rim)][:, 2], 1.0)
    bad = subprocess.run([sys.executable, "-m", "curvenet.cli", "surface", str(src), "-o", str(tmp_path / "b.obj"),
                          "--open", "1,99"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "no curve 99 to leave open" in bad.stderr
    assert bad.stderr.count("\n") == 1 and not (tmp_path / "b.obj").exists()
    bad = subprocess.run([sys.executable, "-m", "curvenet.cli", "surface", str(src), "-o", str(tmp_path / "b.obj"),
                          "--open", "4-1"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "not a list of curve ids" in bad.stderr and not (tmp_path / "b.obj").exists()


def test_png_not_blank(meshes):
    pytest.importorskip("matplotlib")
    from io import BytesIO

    from matplotlib.image import imread

    from curvenet.plots.surface_png import render_surface_png

    net, mesh = meshes["sphere"]
    data = render_surface_png(mesh, network=net, width=4, height=4, dpi=60)
    img = imread(BytesIO(data))
    assert img.shape[:2] == (240, 240)
    rgb = img[..., :3]
    coloured = (np.abs(rgb - 1.0).max(axis=2) > 0.05).mean()
    assert 0.2 < coloured < 0.95  # a sphere fills part of the picture
    assert len(np.unique(np.round(rgb.reshape(-1, 3), 2), axis=0)) > 20  # shaded, several patches


def test_reconstructed_network_surfaces():
    """Points -> network -> mesh: a sampled cube wireframe gives a closed surface of 6 patches."""
    from curvenet import reconstruct

    truth = synth.model("cube")
    points, _ = synth.sample(truth, rng=1)
    net = reconstruct(points)
    mesh = surface(net, target_edge=0.1)
    assert mesh.n_patches == 6 and mesh.euler_characteristic == 2
    assert len(mesh.boundary_edges()) == 0
    assert is_manifold_and_oriented(mesh.triangles) == (True, True)
    assert signed_volume(mesh) == pytest.approx(1.0, rel=0.05)


def test_reconstruct_surface_option_and_top_level_function(tmp_path):
    """`curvenet reconstruct ... --surface MESH` and `curvenet.surface(network)` (issue 4, item 1)."""
    import subprocess
    import sys
    from pathlib import Path

    import curvenet

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "mug.obj"
    r = subprocess.run([sys.executable, "-m", "curvenet.cli", "reconstruct", str(root / "examples" / "mug.xyz"),
                        "-o", str(tmp_path / "mug.json"), "--surface", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "surface:" in r.stdout and "Euler characteristic" in r.stdout
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.load(str(out), process=False)
    assert len(m.faces) > 0
    from curvenet.io import read_network

    net = read_network(tmp_path / "mug.json")
    mesh = curvenet.surface(net)
    assert len(mesh.triangles) == len(m.faces)
    bad = subprocess.run([sys.executable, "-m", "curvenet.cli", "reconstruct", str(root / "examples" / "mug.xyz"),
                          "-o", str(tmp_path / "b.json"), "--surface", str(tmp_path / "m.stl")], capture_output=True, text=True)
    assert bad.returncode == 2 and "unknown mesh extension" in bad.stderr and not (tmp_path / "b.json").exists()


# ---------------------------------------------------------------------------------------------
# issue 24: checks, conflict-free selection, fairing without sag
# ---------------------------------------------------------------------------------------------
def two_squares(crossing: bool):
    """Two unit squares (two triangles each, patches 0 and 1): crossing at right angles, or apart."""
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                  [0.5, 0.6, -0.45], [0.5, 0.6, 0.55], [0.5, -0.4, 0.55], [0.5, -0.4, -0.45]], float)
    if not crossing:
        V[4:, 0] += 3.0
    T = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    P = np.array([0, 0, 1, 1])
    return SurfaceMesh(V, T, P, [[0], [1]], [[1], [1]], [None, None], {"target_edge": 0.5})


@pytest.mark.parametrize("crossing", [True, False])
def test_check_mesh_finds_crossings_and_names_the_patches(crossing):
    pytest.importorskip("pymeshlab")
    pytest.importorskip("igl")
    from curvenet.surfacing import check_mesh
    from curvenet.surfacing.crossings import crossing_patches

    mesh = two_squares(crossing)
    ck = check_mesh(mesh)
    assert ck.non_manifold_edges == 0 and ck.boundary_loops == 2 and ck.components == 2
    assert ck.genus == 0
    pairs, folded = crossing_patches(mesh.vertices, mesh.triangles, mesh.patch)
    if crossing:
        assert ck.self_intersecting_faces >= 2 and not ck.ok
        assert ck.warning() == "surface check failed: self-intersecting faces in patches 0, 1"
        assert pairs == {(0, 1)} and folded == set()
    else:
        assert ck.self_intersecting_faces == 0 and ck.ok and ck.warning() is None
        assert pairs == set()


def test_check_mesh_non_manifold_edge_and_touching_triangles():
    pytest.importorskip("pymeshlab")
    pytest.importorskip("igl")
    from curvenet.surfacing import check_mesh

    # three triangles on one edge (a fin), one per patch; and two coplanar triangles that only
    # share a vertex (MeshLab selects such pairs; libigl finds they do not cross)
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1]], float)
    T = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    mesh = SurfaceMesh(V, T, np.array([0, 1, 2]), [[0], [1], [2]], [[1]] * 3, [], {"target_edge": 0.3})
    ck = check_mesh(mesh)
    assert ck.non_manifold_edges == 1 and ck.genus is None
    assert ck.patches == {"non_manifold_edges": [0, 1, 2]}
    assert "non-manifold edges in patches 0, 1, 2" in ck.warning()
    fan = SurfaceMesh(np.array([[0, 0, 0], [1, 0, 0], [1, 0.2, 0], [-1, 0, 0], [-1, -0.2, 0]], float),
                      np.array([[0, 1, 2], [0, 3, 4]]), np.array([0, 0]), [[0]], [[1]], [], {"target_edge": 0.3})
    assert check_mesh(fan).self_intersecting_faces == 0


def test_overlapping_patches_found():
    from curvenet.surfacing.crossings import overlapping_patches

    mesh = two_squares(False)
    V = mesh.vertices.copy()
    V[4:] = V[:4] + [0, 0, 0.01]  # the second square lies on the first, 0.01 above
    pairs, n = overlapping_patches(V, mesh.triangles, mesh.patch, np.zeros((0, 3)), distance=0.05, margin=0.0)
    assert pairs == [(0, 1)] and n == 4
    V[4:, 2] += 0.2
    assert overlapping_patches(V, mesh.triangles, mesh.patch, np.zeros((0, 3)), distance=0.05, margin=0.0)[0] == []


def test_surface_warns_naming_patches_when_a_check_fails(monkeypatch):
    from curvenet.surfacing import SurfaceCheckWarning, assemble
    from curvenet.surfacing.checks import MeshChecks

    failing = MeshChecks(3, 0, 0, 1, 0, [], 0, {"self_intersections": [1, 4]})
    monkeypatch.setattr(assemble, "check_mesh", lambda mesh: failing)
    with pytest.warns(SurfaceCheckWarning, match="self-intersecting faces in patches 1, 4"):
        mesh = surface(prism(SQUARE))
    assert mesh.checks is failing
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert surface(prism(SQUARE), check=False).checks is None


@pytest.mark.skipif(not synth.cassie.available(), reason="CASSIE dataset not found")
def test_cassie_sketch_patches_do_not_cross():
    # main's selection (most curves used twice, no geometric test) surfaced the hat drawn at
    # 5 mm with 696 crossing faces (MeshLab, confirmed by libigl); measured now: 0
    pytest.importorskip("pymeshlab")
    pytest.importorskip("igl")
    net = synth.cassie.load("hat", step=0.005)
    mesh = surface(net, target_edge=0.01)
    assert mesh.checks.self_intersecting_faces == 0
    assert mesh.checks.non_manifold_edges == 0 and mesh.checks.overlaps == []
    assert mesh.stats["conflicts"] > 0  # conflicts were found and forbidden
    assert is_manifold_and_oriented(mesh.triangles)[0]


def test_cylinder_does_not_sag():
    # the mug's four quarter cylinders (two arcs, two lines each): a patch of constant mean
    # curvature sagged to radius 0.459 at mid-height (true 0.5); measured now 0.499 .. 0.508
    mesh = surface(synth.model("mug"), target_edge=0.04, check=False)
    V = mesh.vertices
    on_curve = np.zeros(len(V), dtype=bool)
    for ids in mesh.curve_vertices:
        if ids is not None:
            on_curve[ids] = True
    band = (np.abs(V[:, 2] - 0.5) < 0.05) & ~on_curve & ~((np.abs(V[:, 1]) < 1e-9) & (V[:, 0] > 0.5))
    r = np.hypot(V[band, 0], V[band, 1])
    assert len(r) > 20
    assert 0.49 < r.min() and r.max() < 0.515


def test_find_cycles_open_curves_bound_one_cycle_at_most():
    """On a cube's wireframe every curve borders two of the six faces; naming the top square's
    four curves open leaves five faces, each of those curves in one of them."""
    from curvenet.surfacing.cycles import curve_caps, find_cycles

    net = prism(SQUARE)
    chains = [np.asarray(c.points, dtype=float) for c in net.curves]
    top = [3 * i + 1 for i in range(len(SQUARE))]
    closed = find_cycles(chains, net.edges, net.nodes)
    assert len(closed.cycles) == 6
    assert all(sum(c in cyc for cyc in closed.cycles) == 2 for c in range(len(chains)))
    opened = find_cycles(chains, net.edges, net.nodes, open_curves=top)
    assert len(opened.cycles) == 5
    assert all(sum(c in cyc for cyc in opened.cycles) == 1 for c in top)
    assert curve_caps(4, [1, 3]).tolist() == [2.0, 1.0, 2.0, 1.0]
