"""The .dxf, .svg, .vtp and .graphml writers and CurveNetwork.to_networkx, read back with the
libraries that read those formats (ezdxf, xml.etree, VTK, networkx)."""

import base64
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import sys
from pathlib import Path

from curvenet import Curve, CurveNetwork
from curvenet.errors import InputError
from curvenet.io import WRITERS, write_network

sys.path.insert(0, str(Path(__file__).parent))


def sample_network(d: int = 3) -> CurveNetwork:
    """Two junctions joined by three arcs, a branch to a free end, a loop through one node, and a
    closed loop without nodes (every kind of curve)."""
    t = np.linspace(0, np.pi, 23)
    curves = []
    for h in (1.0, 0.2, -1.0):
        p = np.column_stack([-np.cos(t), h * np.sin(t), 0.3 * h * np.sin(t)])
        p[[0, -1]] = [[-1, 0, 0], [1, 0, 0]]  # curves end exactly at their nodes
        curves.append(Curve(p[:, :d], 0, 1, indices=np.arange(len(p)) + 100 * len(curves)))
    s = np.linspace(0, 1, 9)[:, None]
    b, e = np.array([1.0, 0, 0]), np.array([2.0, 0.5, 1.5])
    curves.append(Curve((b + s * (e - b))[:, :d], 1, 2))
    u = np.linspace(0, 2 * np.pi, 17)
    one = np.column_stack([-1 - 0.4 * (1 - np.cos(u)), 0.4 * np.sin(u), 0.1 * np.sin(u)])
    one[[0, -1]] = [-1, 0, 0]
    curves.append(Curve(one[:, :d], 0, 0, closed=True))
    v = np.linspace(0, 2 * np.pi, 31, endpoint=False)
    loop = np.column_stack([4 + 0.5 * np.cos(v), 0.7 * np.sin(v), 0.2 * np.cos(v)])
    curves.append(Curve(loop[:, :d], None, None, closed=True))
    nodes = np.array([[-1.0, 0, 0], [1.0, 0, 0], e])[:, :d]
    return CurveNetwork(nodes, curves, parameters={"method": "test"})


@pytest.fixture(params=[3, 2], ids=["3d", "2d"])
def net(request):
    return sample_network(request.param)


def xyz(p):
    p = np.asarray(p, float)
    return np.column_stack([p, np.zeros(len(p))]) if p.shape[1] == 2 else p


def test_registered():
    for ext in (".dxf", ".svg", ".vtp", ".graphml"):
        assert ext in WRITERS


# ----------------------------------------------------------------------------- DXF
def test_dxf_polylines_and_points(net, tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    path = write_network(net, tmp_path / "n.dxf")
    doc = ezdxf.readfile(path)
    msp = doc.modelspace()
    polys = msp.query("POLYLINE")
    assert len(polys) == net.n_curves
    assert all(p.dxf.layer == "CURVES" and p.is_3d_polyline for p in polys)
    for p, c in zip(polys, net.curves):
        got = np.array([v.dxf.location for v in p.vertices])
        np.testing.assert_allclose(got, xyz(c.points), atol=1e-12)
        assert p.is_closed == c.closed
    pts = msp.query("POINT")
    assert len(pts) == net.n_nodes and all(p.dxf.layer == "NODES" for p in pts)
    np.testing.assert_allclose([p.dxf.location for p in pts], xyz(net.nodes), atol=1e-12)
    assert not msp.query("SPLINE")
    assert doc.layers.has_entry("CURVES") and doc.layers.has_entry("NODES")


def test_dxf_splines_are_b_splines_through_the_points(net, tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    path = write_network(net, tmp_path / "s.dxf", splines=True)
    msp = ezdxf.readfile(path).modelspace()
    splines = msp.query("SPLINE")
    assert len(splines) == net.n_curves and not msp.query("POLYLINE")
    for sp, c in zip(splines, net.curves):
        want = xyz(c.points)
        if c.closed and np.linalg.norm(want[0] - want[-1]) > 1e-9:
            want = np.vstack([want, want[:1]])
        np.testing.assert_allclose(np.array(sp.fit_points), want, atol=1e-12)
        assert sp.dxf.layer == "CURVES" and sp.dxf.degree == 3 and bool(sp.closed) == c.closed
        # a true B-spline: control points and clamped knots (what a CAD program draws)
        knots = np.array(sp.knots)
        assert len(knots) == len(sp.control_points) + 4
        assert np.all(np.diff(knots) >= 0) and np.all(knots[:4] == knots[0]) and np.all(knots[-4:] == knots[-1])
        # evaluated from them (not from the fit points), the spline passes through every point
        # of the curve and stays near its polyline
        ctrl_only = ezdxf.math.BSpline(np.array(sp.control_points), order=4, knots=knots)
        samples = np.array(list(ctrl_only.flattening(1e-6)))
        from scipy.spatial import cKDTree

        u = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(want, axis=0), axis=1))]  # chord length
        np.testing.assert_allclose(knots[[0, -1]], u[[0, -1]], rtol=1e-12)
        np.testing.assert_allclose([ctrl_only.point(x) for x in u], want, atol=1e-9)
        from curvenet.metrics import densify

        poly = densify(want, 1e-3)
        assert cKDTree(poly).query(samples)[0].max() < 0.2 * np.linalg.norm(np.diff(want, axis=0), axis=1).max()
        if c.closed:  # periodic: the same tangent on both sides of the seam
            d0 = np.array(ctrl_only.derivative(knots[0], 1)[1])
            d1 = np.array(ctrl_only.derivative(knots[-1], 1)[1])
            np.testing.assert_allclose(d0, d1, rtol=1e-6, atol=1e-9)


def _ezdxf_built(net, splines):
    """The drawing the DXF writer made through ezdxf's objects before it wrote the text itself
    (issue 22): the reference its entities must equal."""
    import ezdxf

    from curvenet.io.dxf import _fit_points, _interpolating_bspline, _MIN_LOOP
    from curvenet.style import curve_colors

    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    colors = curve_colors(net)
    for i, c in enumerate(net.curves):
        pts = xyz(c.points) if len(c.points) else np.zeros((0, 3))
        if len(pts) < 2:
            continue
        fit = _fit_points(pts, c.closed) if splines else pts[:0]
        if len(fit) >= (_MIN_LOOP if c.closed else 3):
            degree, control, knots = _interpolating_bspline(fit, c.closed)
            e = msp.add_spline(dxfattribs={"layer": "CURVES"})
            e.dxf.degree = degree
            e.control_points, e.knots, e.fit_points = control.tolist(), knots.tolist(), fit.tolist()
            e.closed = bool(c.closed)
        else:
            e = msp.add_polyline3d(pts.tolist(), close=bool(c.closed), dxfattribs={"layer": "CURVES"})
        e.rgb = tuple(int(colors[i][k:k + 2], 16) for k in (1, 3, 5))
    for p in xyz(net.nodes) if len(net.nodes) else []:
        msp.add_point(p.tolist(), dxfattribs={"layer": "NODES"})
    return doc


def _dxf_networks():
    from sample_networks import writer_networks

    nets = {f"sample{d}": sample_network(d) for d in (2, 3)}
    nets.update({k: v for k, v in writer_networks().items() if k != "theta2"})
    short = [Curve(np.array([[0.0, 0, 0], [1, 2, 0.5], [2, 0, 1]]), 0, 1),  # a degree-2 spline
             Curve(np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 1]]), 0, 1),  # a repeated point
             Curve(np.array([[5.0, 5, 5]]), None, None), Curve(np.zeros((0, 3)), None, None),
             Curve(np.array([[0.0, 0, 0], [1, 1, 0], [0, 0, 0]]), 0, 0, closed=True)]
    nets["short"] = CurveNetwork(np.array([[0.0, 0, 0], [2, 0, 1]]), short)
    return nets


@pytest.mark.parametrize("splines", [False, True], ids=["polylines", "splines"])
@pytest.mark.parametrize("units", [None, "mm"])
def test_dxf_text_equals_ezdxf_objects_and_audits(splines, units, tmp_path):
    """The DXF written as text (issue 22) loads in ezdxf, passes its audit untouched, and holds
    the entities ezdxf builds from the same network: types, layers, colours, flags, and every
    coordinate, knot and control point bit for bit; handles distinct and below $HANDSEED."""
    ezdxf = pytest.importorskip("ezdxf")
    from curvenet.io.dxf import network_to_dxf

    for name, net in _dxf_networks().items():
        path = tmp_path / f"{name}.dxf"
        path.write_bytes(network_to_dxf(net, splines=splines, units=units))
        doc = ezdxf.readfile(path)
        audit = doc.audit()
        assert not audit.errors and not audit.fixes, (name, [str(f.message) for f in audit.fixes])
        assert doc.header["$INSUNITS"] == (4 if units else 0)
        got, want = list(doc.modelspace()), list(_ezdxf_built(net, splines).modelspace())
        assert [e.dxftype() for e in got] == [e.dxftype() for e in want], name
        for a, b in zip(got, want):
            assert a.dxf.layer == b.dxf.layer and a.rgb == b.rgb, name
            if a.dxftype() == "POINT":
                assert tuple(a.dxf.location) == tuple(b.dxf.location)
            elif a.dxftype() == "POLYLINE":
                assert a.is_3d_polyline and a.is_closed == b.is_closed
                assert [tuple(v.dxf.location) for v in a.vertices] == [tuple(v.dxf.location) for v in b.vertices]
            else:
                assert (a.dxf.degree, a.closed) == (b.dxf.degree, b.closed)
                for attr in ("control_points", "knots", "fit_points"):
                    assert np.array_equal(np.array(getattr(a, attr)), np.array(getattr(b, attr))), (name, attr)
        handles = [e.dxf.handle for e in doc.entitydb.values()]
        assert len(set(handles)) == len(handles)
        assert max(int(h, 16) for h in handles) < int(doc.header["$HANDSEED"], 16)


def test_dxf_splines_default_follows_the_fit(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    n = sample_network(3)
    n.parameters["fit"] = True
    msp = ezdxf.readfile(write_network(n, tmp_path / "a.dxf")).modelspace()
    assert len(msp.query("SPLINE")) == n.n_curves
    msp = ezdxf.readfile(write_network(n, tmp_path / "b.dxf", splines=False)).modelspace()
    assert len(msp.query("POLYLINE")) == n.n_curves


def test_dxf_of_a_fitted_noisy_network_round_trips(tmp_path):
    """A noisy reconstruction is fitted by default; its DXF holds one spline per curve, each
    within a small fraction of a spacing of the fitted samples and ending at its nodes."""
    ezdxf = pytest.importorskip("ezdxf")
    from scipy.spatial import cKDTree

    from curvenet import reconstruct, synth

    truth = synth.model("crossing")
    h = synth.h_of(truth)
    pts, _ = synth.sample(truth, noise=0.3, rng=5)
    net = reconstruct(pts)
    assert net.parameters["fit"] is True
    msp = ezdxf.readfile(write_network(net, tmp_path / "f.dxf")).modelspace()
    splines = msp.query("SPLINE")
    assert len(splines) == net.n_curves
    for sp, c in zip(splines, net.curves):
        tool = sp.construction_tool()
        samples = np.array(list(tool.flattening(1e-4 * h)))
        P = xyz(c.points)
        u = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(np.array(sp.fit_points), axis=0), axis=1))]
        on = np.array([tool.point(x) for x in u])
        assert cKDTree(on).query(P)[0].max() < 1e-6 * h  # through every fitted sample
        from curvenet.metrics import densify

        assert cKDTree(densify(P, 0.01 * h)).query(samples)[0].max() < 0.5 * h  # near the polyline
        if c.start is not None:
            np.testing.assert_allclose(samples[0], xyz(net.nodes[[c.start]])[0], atol=1e-9 * h)
            np.testing.assert_allclose(samples[-1], xyz(net.nodes[[c.end]])[0], atol=1e-9 * h)


# ----------------------------------------------------------------------------- SVG
def _svg(text):
    root = ET.fromstring(text)
    ns = {"s": "http://www.w3.org/2000/svg"}
    curves = root.findall("s:g[@id='curves']/*", ns)
    nodes = root.findall("s:g[@id='nodes']/s:circle", ns)
    return root, curves, nodes


def _poly_points(el):
    return np.array([[float(v) for v in p.split(",")] for p in el.get("points").split()])


def test_svg_xy_readback(net):
    from curvenet.io.svg import network_to_svg

    root, curves, nodes = _svg(network_to_svg(net))
    assert root.tag.endswith("svg")
    assert len(curves) == net.n_curves and len(nodes) == net.n_nodes
    for el, c in zip(curves, net.curves):
        assert el.tag.endswith("polygon" if c.closed else "polyline")
        got = _poly_points(el)
        np.testing.assert_allclose(got[:, 0], c.points[:, 0], rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(-got[:, 1], c.points[:, 1], rtol=1e-8, atol=1e-8)
        if c.start is not None:
            assert (int(el.get("data-start")), int(el.get("data-end"))) == (c.start, c.end)
    kinds = {"junction": net.valence >= 3, "end": net.valence == 1}
    for j, el in enumerate(nodes):
        assert el.get("id") == f"node-{j}"
        np.testing.assert_allclose([float(el.get("cx")), -float(el.get("cy"))], net.nodes[j, :2], atol=1e-8)
        for k, m in kinds.items():
            assert (el.get("class") == k) == bool(m[j])
    # the viewBox holds every point
    x0, y0, w, h = map(float, root.get("viewBox").split())
    allp = np.vstack([_poly_points(el) for el in curves])
    assert (allp[:, 0] >= x0).all() and (allp[:, 0] <= x0 + w).all()
    assert (allp[:, 1] >= y0).all() and (allp[:, 1] <= y0 + h).all()
    assert int(root.get("width")) == 800 and int(root.get("height")) == round(800 * h / w)


@pytest.mark.parametrize("projection", ["xz", "yz", "iso"])
def test_svg_projections_of_3d(projection):
    from curvenet.io.svg import network_to_svg, project

    n = sample_network(3)
    _, curves, _ = _svg(network_to_svg(n, projection=projection))
    cols = {"xz": (0, 2), "yz": (1, 2)}
    for el, c in zip(curves, n.curves):
        got = _poly_points(el) * [1, -1]
        if projection == "iso":
            x, y, z = c.points.T
            want = np.column_stack([(x - y) / np.sqrt(2), (2 * z - x - y) / np.sqrt(6)])
        else:
            want = c.points[:, cols[projection]]
        np.testing.assert_allclose(got, want, atol=1e-8)
        np.testing.assert_allclose(project(c.points, projection), want, atol=1e-12)


def test_svg_bad_options():
    from curvenet.io.svg import network_to_svg

    with pytest.raises(InputError, match="projection"):
        network_to_svg(sample_network(3), projection="zx")
    with pytest.raises(InputError, match="2D network"):
        network_to_svg(sample_network(2), projection="xz")
    with pytest.raises(InputError, match="width"):
        network_to_svg(sample_network(2), width=0)


def test_svg_and_dxf_colours_are_the_shared_style(tmp_path):
    """The writers colour curves and nodes as the pictures and the viewer do (curvenet.style)."""
    from curvenet.io.svg import network_to_svg
    from curvenet.style import NODE_COLORS, curve_colors

    n = sample_network(3)
    want = curve_colors(n)
    assert len(set(want)) > 1
    _, curves, nodes = _svg(network_to_svg(n))
    assert [el.get("stroke") for el in curves] == want
    kinds = list(n.node_kinds)
    assert sorted(set(kinds)) == ["end", "junction"]
    assert [(el.get("class"), el.get("fill")) for el in nodes] == [(k, NODE_COLORS[k]) for k in kinds]
    ezdxf = pytest.importorskip("ezdxf")
    polys = ezdxf.readfile(write_network(n, tmp_path / "n.dxf")).modelspace().query("POLYLINE")
    assert ["#%02x%02x%02x" % p.rgb for p in polys] == want


def test_node_kinds_follow_the_valence():
    n = sample_network(2)  # node 0: three arcs and a loop (5 ends), node 1: three arcs and a branch
    assert list(n.valence) == [5, 4, 1]
    assert list(n.node_kinds) == ["junction", "junction", "end"]
    two = CurveNetwork(np.array([[0.0, 0], [1, 0], [2, 0], [5, 5]]),
                       [Curve(np.array([[0.0, 0], [1, 0]]), 0, 1), Curve(np.array([[1.0, 0], [2, 0]]), 1, 2)])
    assert list(two.node_kinds) == ["end", "other", "end", "other"]  # valence 1, 2, 1, 0


# ----------------------------------------------------------------------------- VTP
def _read_vtp_vtk(path):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(str(path))
    r.Update()
    assert r.GetErrorCode() == 0
    pd = r.GetOutput()
    pts = vtk_to_numpy(pd.GetPoints().GetData())
    lines = []
    ca = pd.GetLines()
    ids = vtk.vtkIdList()
    ca.InitTraversal()
    while ca.GetNextCell(ids):
        lines.append([ids.GetId(i) for i in range(ids.GetNumberOfIds())])
    cd = {pd.GetCellData().GetArrayName(i): vtk_to_numpy(pd.GetCellData().GetArray(i))
          for i in range(pd.GetCellData().GetNumberOfArrays())}
    pdd = {pd.GetPointData().GetArrayName(i): vtk_to_numpy(pd.GetPointData().GetArray(i))
           for i in range(pd.GetPointData().GetNumberOfArrays())}
    return pd.GetNumberOfVerts(), pts, lines, cd, pdd


@pytest.mark.parametrize("encoding", ["ascii", "base64"])
def test_vtp_read_by_vtk(net, tmp_path, encoding):
    path = write_network(net, tmp_path / "n.vtp", encoding=encoding)
    nverts, pts, lines, cd, pdd = _read_vtp_vtk(path)
    assert nverts == net.n_nodes and len(lines) == net.n_curves
    np.testing.assert_array_equal(pts[: net.n_nodes], xyz(net.nodes))
    for ids, c in zip(lines, net.curves):
        want = xyz(c.points)
        if c.start is None and c.closed:
            want = np.vstack([want, want[:1]])
        np.testing.assert_array_equal(pts[ids], want)
        if c.start is not None:
            assert (ids[0], ids[-1]) == (c.start, c.end)
    assert cd["curve_id"].tolist() == [-1] * net.n_nodes + list(range(net.n_curves))
    assert cd["node_id"].tolist() == list(range(net.n_nodes)) + [-1] * net.n_curves
    assert cd["closed"][net.n_nodes:].tolist() == [int(c.closed) for c in net.curves]
    np.testing.assert_array_equal(pdd["valence"][: net.n_nodes], net.valence)
    assert (pdd["node_id"][net.n_nodes:] == -1).all()


def test_vtp_structure_without_vtk():
    """Parsed with the XML parser alone: the arrays decode to the expected sizes in both encodings."""
    from curvenet.io.vtp import network_to_vtp

    n = sample_network(3)
    got = {}
    for enc in ("ascii", "base64"):
        root = ET.fromstring(network_to_vtp(n, encoding=enc))
        assert root.get("type") == "PolyData"
        piece = root.find("PolyData/Piece")
        pts_el = piece.find("Points/DataArray")
        if enc == "ascii":
            pts = np.array(pts_el.text.split(), float).reshape(-1, 3)
        else:
            raw = base64.b64decode(pts_el.text)
            size = int(np.frombuffer(raw[:8], "<u8")[0])
            assert size == len(raw) - 8
            pts = np.frombuffer(raw[8:], "<f8").reshape(-1, 3)
        assert len(pts) == int(piece.get("NumberOfPoints"))
        got[enc] = pts
    np.testing.assert_array_equal(got["ascii"], got["base64"])
    with pytest.raises(InputError):
        network_to_vtp(n, encoding="zlib")


# ----------------------------------------------------------------------------- GraphML, networkx
def test_graphml_read_by_networkx(net, tmp_path):
    nx = pytest.importorskip("networkx")
    from curvenet.io.graphml import parse_polyline

    g = nx.read_graphml(write_network(net, tmp_path / "n.graphml"), node_type=int)
    assert g.is_multigraph() and not g.is_directed()
    n_free = sum(c.start is None for c in net.curves)
    assert g.number_of_nodes() == net.n_nodes + n_free
    assert g.number_of_edges() == net.n_curves
    for j in range(net.n_nodes):
        a = g.nodes[j]
        np.testing.assert_array_equal([a["x"], a["y"], a["z"]], xyz(net.nodes[j : j + 1])[0])
        assert a["valence"] == net.valence[j] and a["anchor"] is False
        assert a["valence"] == g.degree(j)
    by_curve = {d["curve"]: (u, v, d) for u, v, d in g.edges(data=True)}
    assert sorted(by_curve) == list(range(net.n_curves))
    for i, c in enumerate(net.curves):
        u, v, d = by_curve[i]
        pts = parse_polyline(d["points"], int(g.graph["dimension"]))
        np.testing.assert_array_equal(pts, c.points)
        assert d["closed"] == c.closed and d["n_points"] == len(c.points)
        assert d["length"] == pytest.approx(c.length, rel=1e-15)
        if c.start is None:
            assert u == v and g.nodes[u]["anchor"] is True and g.nodes[u]["kind"] == "loop"
        else:
            assert {u, v} == {c.start, c.end}
    b0 = nx.number_connected_components(g)
    assert (b0, g.number_of_edges() - g.number_of_nodes() + b0) == net.betti


def test_to_networkx(net):
    nx = pytest.importorskip("networkx")
    g = net.to_networkx()
    assert isinstance(g, nx.MultiGraph)
    assert g.graph["dimension"] == net.dimension
    assert g.number_of_edges() == net.n_curves
    b0 = nx.number_connected_components(g)
    assert (b0, g.number_of_edges() - g.number_of_nodes() + b0) == net.betti
    for j in range(net.n_nodes):
        assert g.nodes[j]["pos"] == tuple(net.nodes[j]) and g.degree(j) == net.valence[j]
        assert g.nodes[j]["kind"] == ("junction" if net.valence[j] >= 3 else "end" if net.valence[j] == 1 else "other")
    for u, v, k, d in g.edges(keys=True, data=True):
        c = net.curves[k]
        assert d["curve"] == k and d["points"] is c.points and d["length"] == c.length
        if c.start is not None:
            assert {u, v} == {c.start, c.end}
        else:
            assert u == v >= net.n_nodes and g.nodes[u]["anchor"]
            assert g.nodes[u]["pos"] == tuple(c.points[0])
    anchors = [a for a, d in g.nodes(data=True) if d["anchor"]]
    g.remove_nodes_from(anchors)
    assert g.number_of_edges() == sum(c.start is not None for c in net.curves)


def test_empty_network_all_writers(tmp_path):
    empty = CurveNetwork(np.zeros((0, 3)), [])
    for ext in (".dxf", ".svg", ".vtp", ".graphml"):
        out = write_network(empty, tmp_path / f"e{ext}")
        assert out.stat().st_size > 0
    nx = pytest.importorskip("networkx")
    g = nx.read_graphml(tmp_path / "e.graphml")
    assert g.number_of_nodes() == 0
