"""Issue 21, writing: every network and mesh file opens in the tools people use, read back with
those tools' own readers (trimesh, Open3D, meshio, PyVista/VTK, ezdxf, GDAL via pyogrio,
shapely, navis, MorphIO)."""

import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from curvenet import Curve, CurveNetwork
from curvenet.errors import InputError
from curvenet.io import write_network
from curvenet.io.numbers import shortest

sys.path.insert(0, str(Path(__file__).parent))
from test_writers_extra import sample_network  # noqa: E402


@pytest.fixture(params=[3, 2], ids=["3d", "2d"])
def net(request):
    return sample_network(request.param)


def _edge_set(pairs) -> set:
    return {tuple(sorted(map(int, p))) for p in pairs}


# ----------------------------------------------------------------------------- numbers
def test_shortest_round_trip_decimals():
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.normal(size=500) * 10.0 ** rng.integers(-12, 12, 500), [0.499559, 0.2, 1.0, -0.0]])
    text = shortest(x)
    back = np.array([float(t) for t in text.split()])
    assert np.array_equal(back.view(np.int64), x.view(np.int64))  # bit for bit, -0.0 included
    assert text.split()[-4:] == ["0.499559", "0.2", "1.0", "-0.0"]  # not 0.49955899999999998


def test_obj_coordinates_are_shortest_and_exact(tmp_path, net):
    net.nodes[0, 0] = 0.499559
    net.curves[0].points[0, 0] = 0.499559
    text = write_network(net, tmp_path / "n.obj").read_text()
    assert "v 0.499559 " in text and "99999999" not in text
    v = np.array([[float(t) for t in line.split()[1:]] for line in text.splitlines() if line.startswith("v ")])
    assert np.array_equal(v[: net.n_nodes, : net.dimension], net.nodes)


# ----------------------------------------------------------------------------- PLY / OBJ / VTU
def test_ply_network_is_a_line_set_in_trimesh(tmp_path, net):
    trimesh = pytest.importorskip("trimesh")
    path = write_network(net, tmp_path / "n.ply")
    v, seg, _ = net.segments()
    got = trimesh.load(path)
    assert isinstance(got, trimesh.path.Path3D)
    assert np.array_equal(got.vertices, v)
    edges = np.vstack([e.nodes for e in got.entities])
    assert _edge_set(edges) == _edge_set(seg)


def test_ply_network_is_a_line_set_in_open3d(tmp_path, net):
    o3d = pytest.importorskip("open3d", exc_type=ImportError)
    path = write_network(net, tmp_path / "n.ply")
    v, seg, _ = net.segments()
    ls = o3d.io.read_line_set(str(path))
    assert np.array_equal(np.asarray(ls.points), v)
    assert np.array_equal(np.asarray(ls.lines), seg)


def test_ply_curve_ids_behind_an_option(tmp_path, net):
    plyfile = pytest.importorskip("plyfile")
    from curvenet.io.network_io import network_to_ply

    _, _, cid = net.segments()
    plain = plyfile.PlyData.read(_write(tmp_path / "a.ply", network_to_ply(net)))
    assert [p.name for p in plain["edge"].properties] == ["vertex1", "vertex2"]
    rich = plyfile.PlyData.read(_write(tmp_path / "b.ply", network_to_ply(net, curve_ids=True)))
    assert np.array_equal(rich["edge"]["curve"], cid)


def _write(path, data):
    path.write_bytes(data)
    return str(path)


def test_vtu_network_is_line_cells_in_meshio(tmp_path, net):
    meshio = pytest.importorskip("meshio")
    path = write_network(net, tmp_path / "n.vtu")
    v, seg, cid = net.segments()
    m = meshio.read(path)
    assert np.array_equal(m.points, v)
    assert np.array_equal(m.cells_dict["line"], seg)
    assert np.array_equal(m.cell_data["curve_id"][0], cid)
    node_id = m.point_data["node_id"]
    assert np.array_equal(node_id[: net.n_nodes], np.arange(net.n_nodes)) and (node_id[net.n_nodes:] == -1).all()


def test_obj_network_polylines_in_vtk(tmp_path, net):
    pv = pytest.importorskip("pyvista")
    path = write_network(net, tmp_path / "n.obj")
    got = pv.read(path)
    assert got.n_lines == net.n_curves
    v, lines = net.polyline_vertices()
    assert np.allclose(got.points, v)
    flat, sizes = got.lines, []
    while len(flat):
        sizes.append(int(flat[0]))
        flat = flat[flat[0] + 1:]
    assert sizes == [len(ids) for ids in lines]  # one polyline per curve, loops closed


# ----------------------------------------------------------------------------- surface PLY
def test_surface_ply_opens_in_meshio_trimesh_open3d(tmp_path):
    meshio = pytest.importorskip("meshio")
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("triangle")
    from curvenet import surface
    from curvenet.io.mesh import mesh_to_ply

    mesh = surface(_cube_network())
    path = tmp_path / "m.ply"
    path.write_bytes(mesh_to_ply(mesh))
    m = meshio.read(path)
    assert np.array_equal(m.points, mesh.vertices) and np.array_equal(m.cells_dict["triangle"], mesh.triangles)
    tm = trimesh.load(path, process=False)
    assert tm.is_watertight and np.array_equal(tm.faces, mesh.triangles)
    o3d = pytest.importorskip("open3d", exc_type=ImportError)
    om = o3d.io.read_triangle_mesh(str(path))
    assert np.array_equal(np.asarray(om.triangles), mesh.triangles)


def _cube_network() -> CurveNetwork:
    c = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    curves = []
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(c[i] != c[j]) == 1:
                t = np.linspace(0, 1, 9)[:, None]
                curves.append(Curve(c[i] + t * (c[j] - c[i]), i, j))
    return CurveNetwork(c, curves)


# ----------------------------------------------------------------------------- SVG views
def _svg_polylines(text: str) -> list[np.ndarray]:
    root = ET.fromstring(text)
    ns = "{http://www.w3.org/2000/svg}"
    out = []
    for el in root.iter():
        if el.tag in (ns + "polyline", ns + "polygon"):
            out.append(np.array([[float(a) for a in p.split(",")] for p in el.get("points").split()]))
    return out


@pytest.mark.parametrize("view, collapsed", [("top", 4), ("front", 4), ("side", 4), ("iso", 0)])
def test_svg_views_of_a_cube(view, collapsed):
    from curvenet.io.svg import network_to_svg

    lines = _svg_polylines(network_to_svg(_cube_network(), projection=view))
    lengths = np.array([np.linalg.norm(p[-1] - p[0]) for p in lines])
    assert (lengths < 1e-12).sum() == collapsed  # the 4 edges along the view direction are dots


def test_svg_iso_is_an_orthographic_projection():
    from curvenet.io.svg import project

    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 50, 3))
    diag = np.ones(3) / np.sqrt(3)
    flat = lambda p: p - np.outer(p @ diag, diag)  # noqa: E731
    da = np.linalg.norm(project(a, "iso") - project(b, "iso"), axis=1)
    np.testing.assert_allclose(da, np.linalg.norm(flat(a - b), axis=1), rtol=1e-12)
    np.testing.assert_allclose(project(np.ones((1, 3)), "iso"), [[0, 0]], atol=1e-15)
    axes = project(np.eye(3), "iso")
    np.testing.assert_allclose(np.linalg.norm(axes, axis=1), np.sqrt(2 / 3))
    cosines = [axes[i] @ axes[j] / (2 / 3) for i, j in ((0, 1), (1, 2), (0, 2))]
    np.testing.assert_allclose(cosines, -0.5)  # 120 degrees apart


# ----------------------------------------------------------------------------- DXF units
def test_dxf_unitless_by_default_units_on_request(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    from curvenet.io.dxf import network_to_dxf

    net = sample_network(3)
    (tmp_path / "a.dxf").write_bytes(network_to_dxf(net))
    assert ezdxf.readfile(tmp_path / "a.dxf").header["$INSUNITS"] == 0
    (tmp_path / "b.dxf").write_bytes(network_to_dxf(net, units="mm"))
    doc = ezdxf.readfile(tmp_path / "b.dxf")
    assert doc.header["$INSUNITS"] == ezdxf.units.MM and doc.header["$MEASUREMENT"] == 1
    (tmp_path / "c.dxf").write_bytes(network_to_dxf(net, units="in"))
    assert ezdxf.readfile(tmp_path / "c.dxf").header["$INSUNITS"] == ezdxf.units.IN
    with pytest.raises(InputError, match="DXF units"):
        network_to_dxf(net, units="parsec")


# ----------------------------------------------------------------------------- GeoJSON
def test_geojson_in_gdal_and_shapely(tmp_path):
    shapely_geometry = pytest.importorskip("shapely.geometry")
    net = sample_network(2)
    path = write_network(net, tmp_path / "n.geojson")
    doc = json.loads(path.read_text())
    feats = doc["features"]
    lines = [f for f in feats if f["properties"]["kind"] == "curve"]
    nodes = [f for f in feats if f["properties"]["kind"] == "node"]
    assert len(lines) == net.n_curves and len(nodes) == net.n_nodes
    for f, c in zip(lines, net.curves):
        g = shapely_geometry.shape(f["geometry"])
        assert g.geom_type == "LineString" and g.is_valid
        want = np.vstack([c.points, c.points[:1]]) if c.start is None else c.points
        assert np.array_equal(np.asarray(g.coords), want)
        assert (f["properties"]["start"], f["properties"]["end"]) == (c.start, c.end)
        assert g.length == pytest.approx(c.length)
    for f, p, v in zip(nodes, net.nodes, net.valence):
        assert np.array_equal(shapely_geometry.shape(f["geometry"]).coords[0], p) and f["properties"]["valence"] == v
    pyogrio = pytest.importorskip("pyogrio")
    meta, _, geom, fields = pyogrio.raw.read(path)
    assert meta["geometry_type"] in ("Unknown", "Geometry") and len(geom) == net.n_curves + net.n_nodes
    kinds = list(fields[list(meta["fields"]).index("kind")])
    assert kinds.count("curve") == net.n_curves and kinds.count("node") == net.n_nodes


# ----------------------------------------------------------------------------- SWC
def _tree_network() -> CurveNetwork:
    """A root free end, a junction, two tips, and a cycle hanging off a tip branch."""
    t = np.linspace(0, 1, 6)[:, None]
    nodes = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 2], [-1, 0, 2], [0, 1, 3]], float)

    def seg(a, b):
        return Curve(nodes[a] + t * (nodes[b] - nodes[a]), a, b)

    bow = Curve(np.array([nodes[2], [1.5, 0.5, 2.5], [0.5, 1.0, 3.0], nodes[4]]), 2, 4)
    return CurveNetwork(nodes, [seg(0, 1), seg(1, 2), seg(1, 3), seg(2, 4), bow])


def test_swc_tree_in_navis(tmp_path):
    navis = pytest.importorskip("navis")
    net = _tree_network()
    path = write_network(net, tmp_path / "n.swc")
    n_samples = net.n_nodes + sum(len(c.points) - 2 for c in net.curves)
    neuron = navis.read_swc(str(path))
    nodes = neuron.nodes.sort_values("node_id")
    assert len(nodes) == n_samples and neuron.n_trees == 1
    assert (nodes["parent_id"] < 0).sum() == 1
    types = dict(zip(nodes["node_id"], nodes["label"]))
    root = nodes[nodes["parent_id"] < 0].iloc[0]
    assert types[root["node_id"]] == 6 and np.allclose(root[["x", "y", "z"]].to_numpy(float), net.nodes[0])
    labels = [int(x) for x in nodes["label"]]
    assert labels.count(5) == 2 and labels.count(6) == 2  # junctions 1 and 2, free ends 0 and 3
    assert int((neuron.nodes["type"] == "end").sum()) == 3  # for navis the cut cycle adds a tip
    assert "cycles cut: 1" in path.read_text()  # the bow closes a cycle 2-4-2


def test_swc_in_morphio_with_one_type(tmp_path):
    morphio = pytest.importorskip("morphio")
    from curvenet.io.swc import network_to_swc

    net = _tree_network()
    path = tmp_path / "n.swc"
    path.write_text(network_to_swc(net, sample_type=3, fork_type=3, end_type=3))
    morphio.set_maximum_warnings(0)
    m = morphio.Morphology(str(path))
    n_samples = net.n_nodes + sum(len(c.points) - 2 for c in net.curves)
    assert len(np.unique(m.points, axis=0)) == n_samples - 1 or len(np.unique(m.points, axis=0)) == n_samples
    assert all(s.type == morphio.SectionType.basal_dendrite for s in m.iter())


def test_swc_2d_and_free_loop():
    from curvenet.io.swc import network_to_swc

    rows = [line.split() for line in network_to_swc(sample_network(2)).splitlines() if not line.startswith("#")]
    ids = [int(r[0]) for r in rows]
    parents = [int(r[6]) for r in rows]
    assert ids == list(range(1, len(rows) + 1))
    assert all(p == -1 or 1 <= p < i for i, p in zip(ids, parents))  # parents come first: a forest
    assert {r[4] for r in rows} == {"0.0"}  # z = 0
    assert parents.count(-1) == 2  # the connected part and the free loop


# ----------------------------------------------------------------------------- labels
def test_point_labels_curves_nodes_noise_any_order():
    from curvenet import reconstruct
    from curvenet.io.labels import point_labels
    from curvenet.synth import model, sample

    pts, _ = sample(model("tree"), noise=0.1, rng=3)
    far = pts.max(axis=0) + 10 * np.ptp(pts, axis=0)
    pts = np.vstack([pts, far])
    net = reconstruct(pts)
    lab = point_labels(net, pts)
    assert lab.shape == (len(pts), 2) and ((lab >= 0).sum(axis=1) <= 1).all()
    for i, c in enumerate(net.curves):
        idx = c.indices[c.indices >= 0]
        assert (lab[idx, 0] >= 0).all() and (lab[idx, 0] <= i).all()
    assert (lab[-1] == -1).all()  # the far outlier is noise
    assert (net.valence >= 3).any() and (lab[:, 1] >= 0).any()  # junction-region points go to nodes
    assert ((lab >= 0).any(axis=1)).mean() > 0.99
    perm = np.random.default_rng(1).permutation(len(pts))
    net2 = reconstruct(pts[perm])
    assert net2.allclose(net, rtol=0, atol=0)  # the same network, its indices refer to the new order
    assert np.array_equal(point_labels(net2, pts[perm]), lab[perm])


# ----------------------------------------------------------------------------- converters
def test_to_open3d(net):
    o3d = pytest.importorskip("open3d", exc_type=ImportError)
    ls = net.to_open3d()
    v, seg, _ = net.segments()
    assert isinstance(ls, o3d.geometry.LineSet)
    assert np.array_equal(np.asarray(ls.points), v) and np.array_equal(np.asarray(ls.lines), seg)
    assert len(ls.colors) == len(seg)


def test_to_pyvista(net):
    pv = pytest.importorskip("pyvista")
    poly = net.to_pyvista()
    v, lines = net.polyline_vertices()
    assert isinstance(poly, pv.PolyData) and poly.n_lines == net.n_curves
    assert np.array_equal(poly.points, v)
    assert np.array_equal(poly.cell_data["curve_id"], np.arange(net.n_curves))
    sizes = poly.compute_cell_sizes(length=True, area=False, volume=False)
    np.testing.assert_allclose(sizes.cell_data["Length"], net.lengths)  # VTK's arc length of each curve


def test_to_trimesh(net):
    trimesh = pytest.importorskip("trimesh")
    path = net.to_trimesh()
    assert isinstance(path, trimesh.path.Path3D) and len(path.entities) == net.n_curves
    assert path.length == pytest.approx(net.lengths.sum())
    v, _ = net.polyline_vertices()
    assert np.array_equal(path.vertices, v)
