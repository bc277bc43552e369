"""Issue 20 item 5: the same network at any scale where float64 holds the points."""

from pathlib import Path

import numpy as np
import pytest

from curvenet import InputError
from curvenet.io import read_points
from curvenet.reconstruct import reconstruct

MUG = Path(__file__).resolve().parents[2] / "examples" / "mug.xyz"


@pytest.fixture(scope="module")
def mug():
    return read_points(MUG)


@pytest.fixture(scope="module")
def mug_net(mug):
    return reconstruct(mug)


def _same_up_to_scale(a, b, s, rtol=1e-9):
    """Networks ``a`` and ``b`` with ``b`` = ``a`` scaled by ``s``: same nodes, curves, indices."""
    ca, cb = a.canonical(), b.canonical()
    assert (a.n_nodes, a.n_curves) == (b.n_nodes, b.n_curves)
    np.testing.assert_allclose(cb.nodes / s, ca.nodes, rtol=rtol, atol=rtol)
    for x, y in zip(ca.curves, cb.curves):
        assert (x.start, x.end, x.closed) == (y.start, y.end, y.closed)
        assert np.array_equal(x.indices, y.indices)
        np.testing.assert_allclose(y.points / s, x.points, rtol=rtol, atol=rtol)


@pytest.mark.parametrize("s", [1e-200, 1e-155, 1e155, 1e200])
def test_mug_at_extreme_scales(mug, mug_net, s):
    """On main: 1e+-200 gave an empty network or an IndexError, 1e+-155 overflow warnings."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        net = reconstruct(mug * s)
    assert mug_net.n_curves > 0
    _same_up_to_scale(mug_net, net, s)
    assert net.parameters["spacing"] == pytest.approx(mug_net.parameters["spacing"] * s, rel=1e-9)


@pytest.mark.parametrize("k", [-900, 600])
def test_power_of_two_scales_are_exact(mug, k):
    """Scaling by 2**k is exact: outside the unscaled range, the network at 2**(k + 300) is the
    one at 2**k times 2**300 to the bit; inside it, points run as given (the default method's
    networks unchanged: the digest check)."""
    a = reconstruct(np.ldexp(mug, k))
    b = reconstruct(np.ldexp(mug, k + 300))
    assert a.n_curves > 0
    assert np.array_equal(b.nodes, np.ldexp(a.nodes, 300))
    for x, y in zip(a.curves, b.curves):
        assert np.array_equal(y.points, np.ldexp(x.points, 300))
        assert np.array_equal(x.indices, y.indices)
    assert b.parameters["spacing"] == np.ldexp(a.parameters["spacing"], 300)
    assert b.parameters["spacing_range"] == [np.ldexp(v, 300) for v in a.parameters["spacing_range"]]


def test_ordinary_scales_run_unscaled(mug, mug_net):
    from curvenet.validate import UNSCALED_EXTENTS, unit_frame

    assert unit_frame(mug) == (None, 0)
    assert unit_frame(mug * 1e-15) == (None, 0) and unit_frame(mug * 1e15) == (None, 0)
    assert unit_frame(np.ldexp(mug, 64))[1] < 0 and UNSCALED_EXTENTS[0] <= 2.0**-64


def test_a_given_length_is_in_the_units_of_the_points(mug):
    ref = reconstruct(mug, spacing=0.01)
    net = reconstruct(mug * 1e200, spacing=0.01 * 1e200)
    _same_up_to_scale(ref, net, 1e200)
    assert net.parameters["spacing"] == 0.01 * 1e200


def test_paper_method_at_extreme_scales(cube_points):
    ref = reconstruct(cube_points, method="paper")
    assert ref.n_curves > 0
    for s in (1e-200, 1e200):
        net = reconstruct(cube_points * s, method="paper", tau_s=0.1 * s)
        _same_up_to_scale(reconstruct(cube_points, method="paper", tau_s=0.1), net, s)
        assert net.parameters["tau_s"] == pytest.approx(0.1 * s)


def test_far_from_the_origin(mug, mug_net):
    """Points 1e9 extents away are translated internally: the same network, shifted."""
    off = np.array([1e9, -2e9, 3e9])
    net = reconstruct(mug + off)
    ca, cb = mug_net.canonical(), net.canonical()
    assert (ca.n_nodes, ca.n_curves) == (cb.n_nodes, cb.n_curves)
    np.testing.assert_allclose(cb.nodes - off, ca.nodes, atol=1e-5)


@pytest.mark.parametrize("pts, what", [
    (np.array([[0.0, 0, 0], [1e-300, 0, 0], [0, 1e-300, 0], [0, 0, 2e-300]]), "cannot resolve"),
    (np.array([[-1e308, 0, 0], [1e308, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]), "span more than float64"),
    (np.array([[1e15, 0, 0], [1e15 + 0.25, 0, 0], [1e15, 0.25, 0], [1e15, 0, 0.5]]), "from the origin"),
])
def test_points_float64_cannot_resolve_are_refused(pts, what):
    with pytest.raises(InputError, match=what):
        reconstruct(pts)


def _scaled(net, s):
    from curvenet.network import Curve, CurveNetwork

    return CurveNetwork(net.nodes * s, [Curve(c.points * s, c.start, c.end, c.closed, c.indices) for c in net.curves],
                        parameters=dict(net.parameters))


@pytest.mark.parametrize("s", [1e-200, 1e200, 1e307])
def test_the_network_writes_and_reads_at_extreme_scales(mug, mug_net, tmp_path, s):
    """The network of the mug at 1e-200, 1e200, 1e307 through every writer, the labels, the
    viewer and the lengths (info), with warnings as errors. On main: .dxf and .geojson ended in
    internal errors at 1e200 (the lengths overflowed in np.linalg.norm), .svg, .dxf and the viewer
    at 1e307 (rounding overflowed in the colour keys, the SVG height), info and .swc printed
    RuntimeWarnings; at 1e-200 every length was 0."""
    import warnings

    from curvenet.io import WRITERS, write_network
    from curvenet.io.labels import point_labels
    from curvenet.viewer import network_to_html

    net = _scaled(mug_net, s)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_allclose(net.lengths / s, mug_net.lengths, rtol=1e-12)
        for ext in sorted(WRITERS):
            write_network(net, tmp_path / f"n{ext}")
        assert point_labels(net, mug * s).shape == (len(mug), 2)
        network_to_html(net, points=mug * s)


def test_step_lengths_match_numpy_where_numpy_holds():
    from curvenet.lengths import step_lengths

    rng = np.random.default_rng(0)
    d = rng.normal(size=(1000, 3)) * 10.0 ** rng.integers(-100, 100, size=(1000, 1))
    assert np.array_equal(step_lengths(d), np.linalg.norm(d, axis=1))  # bit for bit
    for s in (1e-300, 1e-200, 1e200, 1e300):  # numpy gives 0 or inf here
        np.testing.assert_allclose(step_lengths(np.array([[3.0, 4.0, 12.0], [-3.0, 0.0, 4.0]]) * s) / s, [13, 5],
                                   rtol=1e-15)
    assert step_lengths(np.zeros((2, 3))).tolist() == [0.0, 0.0]


@pytest.mark.parametrize("s", [1e-200, 1e200])
def test_the_mug_surfaces_at_extreme_scales(mug_net, s):
    """On main the surfacing failed at 1e200 (ValueError in the cycle selection) and at 1e-200
    (Triangle: invalid geometry): a network far outside ordinary units is surfaced scaled by an
    exact power of two and the mesh scaled back."""
    pytest.importorskip("triangle")
    from curvenet.surfacing import surface

    ref = surface(mug_net, check=False)
    mesh = surface(_scaled(mug_net, s), check=False)
    assert mesh.n_patches == ref.n_patches and mesh.euler_characteristic == ref.euler_characteristic
    assert np.isfinite(mesh.vertices).all()
    lo, hi = mesh.vertices.min(axis=0) / s, mesh.vertices.max(axis=0) / s
    np.testing.assert_allclose(lo, ref.vertices.min(axis=0), rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(hi, ref.vertices.max(axis=0), rtol=1e-6, atol=1e-6)
    assert mesh.stats["target_edge"] / s == pytest.approx(ref.stats["target_edge"], rel=1e-6)


@pytest.mark.parametrize("s", [1e-200, 1e200])
def test_a_picture_at_extreme_scales_is_a_clear_error(mug_net, tmp_path, s, capsys):
    """On main matplotlib failed inside (LinAlgError, exit 1) at 1e200 and warned at 1e-200."""
    pytest.importorskip("matplotlib")
    from curvenet.cli import main
    from curvenet.plots.network_png import render_png

    net = _scaled(mug_net, s)
    with pytest.raises(InputError, match="cannot draw"):
        render_png(net)
    path = tmp_path / "n.json"
    net.save(path)
    assert main(["render", str(path), "-o", str(tmp_path / "n.png")]) == 2
    assert "cannot draw" in capsys.readouterr().err
    assert not (tmp_path / "n.png").exists()


def test_an_unresolvable_extent_names_the_file_before_the_work(mug, tmp_path, capsys):
    """On main the 1e-300 error came from the method, after reading, without the file's name."""
    from curvenet.cli import main

    path = tmp_path / "tiny.xyz"
    np.savetxt(path, mug * 1e-300, fmt="%.17g")
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "n.json")]) == 2
    err = capsys.readouterr().err
    assert "tiny.xyz: points span only" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "n.json").exists()
