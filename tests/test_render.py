"""PNG pictures of networks (curvenet.plots.network_png)."""

from io import BytesIO

import numpy as np
import pytest

from curvenet import Curve, CurveNetwork
from curvenet.errors import InputError, OutputError
from curvenet.style import JUNCTION_COLOR, curve_colors
from sample_networks import theta_network

pytest.importorskip("matplotlib")

from curvenet.plots import network_png as npng  # noqa: E402


def points_of(net, noise=0.01, seed=0):
    p = np.vstack([c.points for c in net.curves])
    return p + np.random.default_rng(seed).normal(scale=noise, size=p.shape)


def decode(png: bytes) -> np.ndarray:
    from matplotlib.image import imread

    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    return (imread(BytesIO(png), format="png")[..., :3] * 255).round().astype(int)


def has_color(img, hexcolor, tol=2, min_pixels=5) -> bool:
    rgb = np.array([int(hexcolor[i : i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img - rgb).max(axis=-1) <= tol).sum()) >= min_pixels


@pytest.mark.parametrize("d", [2, 3])
def test_every_curve_colour_and_the_junctions_are_drawn(d):
    net = theta_network(d)
    img = decode(npng.render_png(net, points=points_of(net), dpi=100))
    assert img.shape[1] == 800 or d == 3  # 8 in at 100 dpi; 3D is cropped to its content
    for c in set(curve_colors(net)):
        assert has_color(img, c), c
    assert has_color(img, JUNCTION_COLOR)
    # the background is white and most of the picture is background
    assert (img == 255).all(axis=-1).mean() > 0.5


def test_points_are_drawn_faint():
    net = theta_network(2)
    allp = np.vstack([c.points for c in net.curves])
    pts = np.clip(points_of(net, noise=0.05), allp.min(axis=0), allp.max(axis=0))  # same axes limits
    with_pts = decode(npng.render_png(net, points=pts, dpi=80, legend=False))
    without = decode(npng.render_png(net, dpi=80, legend=False))
    assert with_pts.shape == without.shape
    changed = (np.abs(with_pts - without).max(axis=-1) > 0) & (without == 255).all(axis=-1)
    assert changed.mean() > 0.002
    # faint: on the white background the points are light grey, never darker than their colour
    new = with_pts[changed]
    assert np.ptp(new, axis=-1).max() <= 3
    assert new.min() >= 0x9a - 2


def test_junctions_and_free_ends_differ():
    kinds = theta_network(3).node_kinds
    assert list(kinds) == ["junction", "junction", "end"]
    net = theta_network(2)
    net_nodes = decode(npng.render_png(net, dpi=80))
    no_nodes = CurveNetwork(net.nodes, net.curves)
    ax = npng.plot_network(no_nodes, show_nodes=False, legend=False)
    assert len(ax.collections) == 1  # the curves only
    ax = npng.plot_network(net)
    # points (none), curves, one scatter per node kind present (end, junction)
    assert len(ax.collections) == 3
    assert has_color(net_nodes, JUNCTION_COLOR)


def test_deterministic_and_independent_of_point_order():
    net = theta_network(3)
    pts = points_of(net)
    a = npng.render_png(net, points=pts, dpi=40)
    b = npng.render_png(net, points=pts[::-1].copy(), dpi=40)
    assert a == b


def test_independent_of_curve_order_and_direction():
    net = theta_network(3)
    perm = [3, 0, 4, 2, 1]
    shuffled = CurveNetwork(net.nodes, [net.curves[i].reversed() if i % 2 else net.curves[i] for i in perm])
    cols, cols2 = curve_colors(net), curve_colors(shuffled)
    assert [cols[i] for i in perm] == cols2
    assert npng.render_png(net, dpi=40) == npng.render_png(shuffled, dpi=40)


def test_view_angles_change_3d_only():
    net3 = theta_network(3)
    a = npng.render_png(net3, dpi=30)
    assert npng.render_png(net3, dpi=30, elev=60, azim=10) != a
    assert npng.render_png(net3, dpi=30, elev=npng.DEFAULT_ELEV, azim=npng.DEFAULT_AZIM) == a
    net2 = theta_network(2)
    assert npng.render_png(net2, dpi=30, elev=60, azim=10) == npng.render_png(net2, dpi=30)


def test_equal_aspect():
    from matplotlib.figure import Figure

    net = theta_network(2)
    ax = npng.plot_network(net, ax=Figure().add_subplot())
    assert ax.get_aspect() == 1.0
    ax3 = npng.plot_network(theta_network(3))
    x, y, z = ax3.get_xlim(), ax3.get_ylim(), ax3.get_zlim()
    spans = np.array([np.ptp(x), np.ptp(y), np.ptp(z)])
    np.testing.assert_allclose(ax3.get_box_aspect() / ax3.get_box_aspect()[0], spans / spans[0], rtol=1e-6)


def test_curve_colors_differ_at_a_node():
    star = CurveNetwork(
        np.vstack([[0.0, 0.0], [[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 12, endpoint=False)]]),
        [Curve(np.array([[0.0, 0.0], [np.cos(a), np.sin(a)]]), 0, i + 1)
         for i, a in enumerate(np.linspace(0, 2 * np.pi, 12, endpoint=False))],
    )
    cols = curve_colors(star)
    assert len(set(cols)) == 12
    net = theta_network(3)
    cols = curve_colors(net)
    for i, ci in enumerate(net.curves):
        for j, cj in enumerate(net.curves[:i]):
            if ci.start is not None and cj.start is not None and {ci.start, ci.end} & {cj.start, cj.end}:
                assert cols[i] != cols[j]


def test_bad_inputs():
    net = theta_network(3)
    with pytest.raises(InputError, match="dimension 2 but the network has dimension 3"):
        npng.render_png(net, points=np.zeros((5, 2)))
    with pytest.raises(InputError, match="3D axes"):
        from matplotlib.figure import Figure

        npng.plot_network(net, ax=Figure().add_subplot())
    with pytest.raises(InputError, match="size"):
        npng.render_png(net, dpi=0)


def test_empty_network_and_only_points():
    empty = CurveNetwork(np.zeros((0, 3)), [])
    img = decode(npng.render_png(empty, dpi=40))
    assert img.size
    img = decode(npng.render_png(empty, points=np.random.default_rng(1).random((50, 3)), dpi=40))
    assert img.size


def test_save_png_atomic(tmp_path):
    net = theta_network(2)
    out = npng.save_png(net, tmp_path / "a.png", dpi=40)
    assert out.read_bytes() == npng.render_png(net, dpi=40)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]
    with pytest.raises(OutputError):
        npng.save_png(net, tmp_path / "missing" / "a.png")
    before = out.read_bytes()
    with pytest.raises(InputError):
        npng.save_png(net, out, points=np.zeros((3, 3)))
    assert out.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]


def test_importing_plots_does_not_import_matplotlib():
    import subprocess
    import sys

    code = "import sys, curvenet.plots, curvenet.plots.network_png, curvenet.viewer, curvenet.io; " \
           "print('matplotlib' in sys.modules, 'plotly' in sys.modules)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.split() == ["False", "False"], r.stderr
