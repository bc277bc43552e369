"""The HTML viewer: a self-contained page, checked in a real headless browser (Debian's chromium
driven by playwright). The browser tests skip only when chromium is not installed."""

import io
import os
import re
import shutil

import numpy as np
import pytest

from curvenet import Curve, CurveNetwork
from sample_networks import theta_network

pytest.importorskip("plotly")

from curvenet import viewer  # noqa: E402
from curvenet.style import JUNCTION_COLOR, curve_colors  # noqa: E402

CHROMIUM = "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else shutil.which("chromium")
GD = "document.getElementById('curvenet-viewer')"
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
]


def sample_points(net, seed=0):
    p = np.vstack([c.points for c in net.curves])
    return p + np.random.default_rng(seed).normal(scale=0.02, size=p.shape)


# ----------------------------------------------------------------------------- without a browser
def test_page_is_self_contained(tmp_path):
    net = theta_network(3)
    html = viewer.network_to_html(net, points=sample_points(net))
    assert html.lstrip().lower().startswith("<html") or html.lstrip().lower().startswith("<!doctype")
    # plotly's JavaScript is inline: no external script, stylesheet or font
    assert not re.search(r"<script[^>]+src=", html, re.I)
    assert not re.search(r"<link[^>]+href=", html, re.I)
    assert len(html) > 1_000_000 and "Plotly.newPlot" in html


def test_figure_traces_and_hover_texts():
    net = theta_network(3)
    fig = viewer.network_figure(net, points=sample_points(net))
    names = [t.name for t in fig.data]
    assert names[0].startswith("input points") and fig.data[0].legendgroup == "points"
    curves = [t for t in fig.data if t.legendgroup == "curves"]
    assert len(curves) == net.n_curves
    assert [t.line.color for t in curves] == curve_colors(net)
    for i, (t, c) in enumerate(zip(curves, net.curves)):
        assert t.hovertext.startswith(f"curve {i}<br>")
        assert ("free loop" in t.hovertext) == (c.start is None)
        n = len(c.points) + (1 if c.closed else 0)
        np.testing.assert_array_equal(t.x, np.append(c.points[:, 0], c.points[0, 0])[:n])
    nodes = [t for t in fig.data if t.legendgroup == "nodes"]
    texts = [s for t in nodes for s in t.hovertext]
    assert sorted(texts) == sorted(f"node {j}<br>valence {v}" for j, v in enumerate(net.valence))
    assert fig.layout.scene.aspectmode == "manual" and max(fig.layout.scene.aspectratio.to_plotly_json().values()) == 1
    assert [b.label for b in fig.layout.updatemenus[0].buttons] == ["all", "curves + nodes", "curves only", "points only"]


def test_many_curves_share_one_trace_per_colour():
    rng = np.random.default_rng(5)
    nodes = rng.random((41, 3))
    net = CurveNetwork(nodes, [Curve(np.linspace(nodes[i], nodes[i + 1], 7), i, i + 1) for i in range(40)])
    fig = viewer.network_figure(net, max_curve_traces=10)
    curves = [t for t in fig.data if t.legendgroup == "curves"]
    colors = curve_colors(net)
    assert len(curves) == len(set(colors)) < net.n_curves
    assert sum(t.showlegend for t in curves) == 1 and curves[0].name == "curves (40)"
    seen = set()
    for t in curves:
        x = np.asarray(t.x, dtype=float)
        gaps = np.flatnonzero(np.isnan(x))
        starts = np.concatenate([[0], gaps[:-1] + 1])
        for a, b in zip(starts, gaps):
            i = int(t.hovertext[a].split("<br>")[0].split()[1])
            assert all(h == t.hovertext[a] for h in t.hovertext[a:b])
            np.testing.assert_array_equal(x[a:b], net.curves[i].points[:, 0])
            assert colors[i] == t.line.color
            seen.add(i)
    assert seen == set(range(40))
    # the same figure with one trace per curve
    assert len([t for t in viewer.network_figure(net).data if t.legendgroup == "curves"]) == 40


def test_subsample_points_is_order_independent():
    rng = np.random.default_rng(3)
    p = rng.random((1000, 3))
    a = viewer.subsample_points(p, 100)
    b = viewer.subsample_points(p[rng.permutation(1000)], 100)
    assert len(a) == 100
    np.testing.assert_array_equal(a, b)
    assert viewer.subsample_points(p, 5000) is p
    fig = viewer.network_figure(theta_network(3), points=p, max_points=100)
    assert len(fig.data[0].x) == 100 and "1000" in fig.data[0].name and "100 shown" in fig.data[0].name


def test_2d_axes_have_equal_scale():
    fig = viewer.network_figure(theta_network(2))
    assert fig.layout.yaxis.scaleanchor == "x" and fig.layout.yaxis.scaleratio == 1


# ----------------------------------------------------------------------------- in chromium
@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM:
        pytest.skip("chromium is not installed (apt-get install chromium)")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


def open_page(browser, path):
    """Load the page; return (page, problems) where problems collects console errors, page
    errors and every request that is not the local file itself."""
    page = browser.new_page(viewport={"width": 1000, "height": 760})
    problems = []
    page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(f"page error: {e}"))

    def request(r):
        if not r.url.startswith(("file:", "data:", "blob:")):
            problems.append(f"network request: {r.url}")

    page.on("request", request)
    page.goto(path.as_uri())
    page.wait_for_selector("#curvenet-viewer .main-svg", timeout=30_000)
    page.wait_for_function(f"{GD}._fullLayout !== undefined", timeout=10_000)
    page.wait_for_timeout(300)
    return page, problems


def shot(page) -> np.ndarray:
    from PIL import Image

    png = page.locator("#curvenet-viewer").screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def count_color(img, hexcolor, tol=10) -> int:
    rgb = np.array([int(hexcolor[i : i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img - rgb).max(axis=-1) <= tol).sum())


@pytest.mark.browser
@pytest.mark.parametrize("d", [3, 2])
def test_viewer_draws_in_chromium(browser, tmp_path, d):
    net = theta_network(d)
    path = viewer.save_html(net, tmp_path / f"view{d}.html", points=sample_points(net))
    page, problems = open_page(browser, path)
    try:
        if d == 3:
            assert page.locator("#curvenet-viewer canvas").count() >= 1  # WebGL scene
        img = shot(page)
        assert img.std() > 5  # not blank
        for c in set(curve_colors(net)):
            assert count_color(img, c) > 0, f"curve colour {c} not drawn"
        assert count_color(img, JUNCTION_COLOR) > 0

        # the buttons toggle nodes and points
        page.get_by_text("curves only", exact=True).click(timeout=5000)
        page.wait_for_function(f"{GD}.data.every(t => t.visible === (t.legendgroup === 'curves'))", timeout=5000)
        page.wait_for_timeout(150)  # let WebGL draw the frame
        vis = page.evaluate("document.getElementById('curvenet-viewer').data.map(t => [t.legendgroup, t.visible])")
        assert {g for g, v in vis if v is True} == {"curves"}
        assert all(v is False for g, v in vis if g != "curves")
        img2 = shot(page)
        assert count_color(img2, JUNCTION_COLOR) < count_color(img, JUNCTION_COLOR)
        page.get_by_text("all", exact=True).click(timeout=5000)
        page.wait_for_function(f"{GD}.data.every(t => t.visible === true)", timeout=5000)
        vis = page.evaluate("document.getElementById('curvenet-viewer').data.map(t => t.visible)")
        assert all(v is True for v in vis)

        # the legend hides the points
        item = page.locator("g.traces", has=page.locator(".legendtext", has_text="input points"))
        item.locator(".legendtoggle").click(timeout=5000)
        # plotly waits for a possible double click before it acts
        page.wait_for_function("document.getElementById('curvenet-viewer').data[0].visible === 'legendonly'",
                               timeout=5000)
        vis = page.evaluate("document.getElementById('curvenet-viewer').data.map(t => t.visible)")
        assert vis[0] == "legendonly" and all(v is True for v in vis[1:])

        if d == 2:  # hovering a node shows its id and valence
            k = page.evaluate("document.getElementById('curvenet-viewer').data.findIndex(t => t.name.startsWith('junctions'))")
            page.evaluate(f"Plotly.Fx.hover('curvenet-viewer', [{{curveNumber: {k}, pointNumber: 0}}])")
            page.wait_for_timeout(200)
            text = page.locator(".hoverlayer").text_content()
            assert "node 0" in text and f"valence {net.valence[0]}" in text
        assert problems == []
    finally:
        page.close()


# ----------------------------------------------------------------------------- scaling (issue 21)
def wide_network(n_curves=40, per_curve=400):
    """A long chain of curves along x (100 wide, 3 deep, 1 high) with a node every curve."""
    nodes = np.column_stack([np.linspace(0, 100, n_curves + 1), np.zeros(n_curves + 1), np.zeros(n_curves + 1)])
    curves = []
    for i in range(n_curves):
        t = np.linspace(0, 1, per_curve)[:, None]
        p = nodes[i] + t * (nodes[i + 1] - nodes[i])
        p[:, 1] = 3 * np.sin(np.pi * t[:, 0]) * (1 if i % 2 else -1)
        p[:, 2] = np.sin(np.pi * t[:, 0])
        curves.append(Curve(p, i, i + 1))
    return CurveNetwork(nodes, curves)


def test_page_stays_under_its_budget_and_says_so(tmp_path):
    net = wide_network(60, 2000)  # 120,000 curve samples
    pts = np.random.default_rng(0).random((300_000, 3)) * [100, 3, 1]
    budget = 8_000_000
    plan = viewer.plan_display(net, pts, max_bytes=budget)
    assert plan.points_shown < 200_000 and plan.curve_stride > 1 and "curve ends kept" in plan.message()
    html = viewer.network_to_html(net, points=pts, max_bytes=budget)
    assert len(html) <= budget
    fig = viewer.network_figure(net, points=pts, max_bytes=budget)
    curves = [t for t in fig.data if t.legendgroup == "curves"]
    assert f"1 in {plan.curve_stride} samples shown" in curves[0].name and "shown" in fig.data[0].name
    for t, c in zip(curves, net.curves):  # topology kept: each curve still runs node to node
        assert (t.x[0], t.x[-1]) == (c.points[0, 0], c.points[-1, 0]) and len(t.x) < len(c.points)
    small = viewer.network_to_html(theta_network(3))  # nothing to thin: nothing said
    assert viewer.plan_display(theta_network(3)).message() == "" and len(small) < 5_100_000
    assert len(viewer.network_to_html(net, points=pts)) <= viewer.MAX_VIEWER_BYTES


def test_points_only_button_only_with_points_and_markers_by_scene():
    fig = viewer.network_figure(theta_network(3))
    assert [b.label for b in fig.layout.updatemenus[0].buttons] == ["all", "curves + nodes", "curves only"]
    small = [t.marker.size for t in fig.data if t.legendgroup == "nodes"]
    many = [t.marker.size for t in viewer.network_figure(wide_network(400, 5)).data if t.legendgroup == "nodes"]
    assert max(many) < min(small)


@pytest.mark.browser
def test_wide_network_framed_whole_in_chromium(browser, tmp_path):
    net = wide_network()
    path = viewer.save_html(net, tmp_path / "wide.html", title="a wide network")
    page, problems = open_page(browser, path)
    try:
        img = shot(page)
        assert page.locator(".gtitle").text_content() == "a wide network"
        legend = " ".join(page.locator(".legendtext").all_text_contents())
        assert "curves (40)" in legend and "junctions" not in legend and "free ends (2)" in legend
        assert "points only" not in page.locator(".updatemenu-container").text_content()
        drawn = np.zeros(img.shape[:2], dtype=bool)
        for c in set(curve_colors(net)):
            rgb = np.array([int(c[i: i + 2], 16) for i in (1, 3, 5)])
            drawn |= np.abs(img - rgb).max(axis=-1) <= 10
        box = page.locator("#curvenet-viewer").bounding_box()
        leg = page.locator("#curvenet-viewer .legend").bounding_box()
        drawn[:, int(leg["x"] - box["x"]):] = False  # the legend's line swatch is not the scene
        cols = np.flatnonzero(drawn.any(axis=0))
        rows = np.flatnonzero(drawn.any(axis=1))
        w, h = img.shape[1], img.shape[0]
        assert drawn.sum() > 1000  # a non-empty canvas
        # the whole chain is in view: it spans a good part of the width and touches no edge (the
        # former camera, aspectmode "data", showed a third of it, cut at the left edge)
        assert cols.max() - cols.min() > 0.35 * w and cols.min() > 0.03 * w
        assert rows.min() > 0.03 * h and rows.max() < 0.97 * h
        assert problems == []
    finally:
        page.close()


def test_view_command_says_when_it_thins(tmp_path, capsys):
    from curvenet.cli import main
    from curvenet.io import write_network

    net = wide_network(20, 200)
    write_network(net, tmp_path / "n.json")
    np.save(tmp_path / "p.npy", np.random.default_rng(1).random((250_000, 3)) * [100, 3, 1])
    out = tmp_path / "v.html"
    assert main(["view", str(tmp_path / "n.json"), "-o", str(out), "--points", str(tmp_path / "p.npy"),
                 "--max-mb", "6"]) == 0
    err = capsys.readouterr().err
    assert "of 250000 input points" in err and "under 6 MB" in err and out.stat().st_size <= 6_000_000
    assert main(["view", str(tmp_path / "n.json"), "-o", str(out), "--max-mb", "3"]) == 2
    assert "--max-mb must be at least 5" in capsys.readouterr().err
