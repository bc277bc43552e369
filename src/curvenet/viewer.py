"""An interactive viewer of a curve network: one self-contained HTML file (extra ``viz``).

The page embeds plotly's JavaScript (no CDN, no network access), so it works offline and can be
mailed or archived as one file. Curves are coloured as in the PNG pictures; nodes (junctions,
free ends) and the input points can be shown or hidden with the legend or the buttons; hovering
a curve shows its id, end nodes and length, hovering a node its id and valence.
"""

from __future__ import annotations

import html as _html

import numpy as np

from .errors import InputError, require
from .network import CurveNetwork
from .style import END_COLOR, JUNCTION_COLOR, OTHER_NODE_COLOR, POINT_COLOR, curve_colors

__all__ = ["network_figure", "network_to_html", "save_html", "subsample_points"]

#: Input points beyond this number are thinned for the viewer (see :func:`subsample_points`).
MAX_VIEWER_POINTS = 200_000

#: Networks with more curves than this draw one trace per colour instead of one per curve.
MAX_CURVE_TRACES = 300


def subsample_points(points: np.ndarray, max_points: int) -> np.ndarray:
    """At most ``max_points`` of ``points``, chosen independently of their order.

    The points are sorted by coordinates and taken at a regular stride, so the same set in any
    order gives the same subset.

    Parameters
    ----------
    points : (N, d) ndarray
    max_points : int

    Returns
    -------
    (M, d) ndarray, M <= max_points
    """
    if max_points <= 0:
        return points[:0]
    if len(points) <= max_points:
        return points
    order = np.lexsort(points.T[::-1])
    take = np.linspace(0, len(points) - 1, max_points).round().astype(np.int64)
    return points[order[take]]


def network_figure(net: CurveNetwork, *, points=None, title: str | None = None,
                   max_points: int = MAX_VIEWER_POINTS, max_curve_traces: int = MAX_CURVE_TRACES):
    """A plotly Figure of the network.

    Parameters
    ----------
    net : CurveNetwork
    points : (N, d) array_like, optional
        Input points, drawn faint (hidden and shown with the legend or buttons).
    title : str, optional
        Page title; by default the counts of nodes and curves.
    max_points : int
        Thin the input points to at most this many (order-independent).
    max_curve_traces : int
        Up to this many curves, each curve is its own plotly trace; beyond, curves of the same
        colour share a trace (separated by gaps), which keeps large networks fast. Hovering
        names the curve either way.

    Returns
    -------
    plotly.graph_objects.Figure
    """
    require("plotly", "the HTML viewer", "viz")
    import plotly.graph_objects as go

    from .plots.network_png import _check_points

    d = net.dimension
    if d not in (2, 3):
        raise InputError(f"can only show 2D or 3D networks, got dimension {d}")
    pts = _check_points(net, points)
    is3d = d == 3
    Scatter = go.Scatter3d if is3d else go.Scatter

    def xyz(a):
        a = np.asarray(a, dtype=float).reshape(-1, d)
        out = {"x": a[:, 0], "y": a[:, 1]}
        if is3d:
            out["z"] = a[:, 2]
        return out

    traces = []
    groups = []  # legend group of each trace, for the buttons
    if pts is not None and len(pts):
        shown = subsample_points(pts, max_points)
        label = f"input points ({len(pts)})" + (f", {len(shown)} shown" if len(shown) < len(pts) else "")
        traces.append(Scatter(
            **xyz(shown), mode="markers", name=label, legendgroup="points",
            marker=dict(size=2 if is3d else 3, color=POINT_COLOR, opacity=0.45),
            hoverinfo="skip",
        ))
        groups.append("points")

    colors = curve_colors(net)
    lengths = net.lengths
    texts, lines = [], []
    for i, c in enumerate(net.curves):
        p = c.points
        if c.closed and len(p) > 1:
            p = np.vstack([p, p[:1]])
        lines.append(p)
        ends = "free loop" if c.start is None else f"nodes {c.start} \u2013 {c.end}"
        texts.append(f"curve {i}<br>{ends}<br>{len(c.points)} points, length {lengths[i]:.4g}")
    if net.n_curves <= max_curve_traces:  # one trace per curve
        groups_of_curves = [[i] for i in range(net.n_curves)]
    else:  # one trace per colour, curves separated by gaps: fast with thousands of curves
        order = {}
        for i, col in enumerate(colors):
            order.setdefault(col, []).append(i)
        groups_of_curves = list(order.values())
    for k, ids in enumerate(groups_of_curves):
        if len(ids) == 1:
            xy = lines[ids[0]]
            hover = texts[ids[0]]
        else:
            gap = np.full((1, d), np.nan)
            xy = np.vstack([b for i in ids for b in (lines[i], gap)])
            hover = [t for i in ids for t in [texts[i]] * len(lines[i]) + [None]]
        col = colors[ids[0]]
        traces.append(Scatter(
            **xyz(xy), mode="lines", name="curves", legendgroup="curves", showlegend=(k == 0),
            line=dict(color=col, width=5 if is3d else 2.5), connectgaps=False,
            hovertext=hover, hoverinfo="text", hoverlabel=dict(bgcolor=col),
        ))
        groups.append("curves")
    if "curves" in groups:
        traces[groups.index("curves")].name = f"curves ({net.n_curves})"

    if net.n_nodes:
        kinds = net.node_kinds
        val = net.valence
        style = {
            "junction": ("junctions", "circle", JUNCTION_COLOR, 6 if is3d else 10),
            "end": ("free ends", "square", END_COLOR, 5 if is3d else 9),
            "other": ("other nodes", "diamond", OTHER_NODE_COLOR, 5 if is3d else 9),
        }
        for kind in ("junction", "end", "other"):
            ids = np.flatnonzero(kinds == kind)
            if not len(ids):
                continue
            name, symbol, color, size = style[kind]
            traces.append(Scatter(
                **xyz(net.nodes[ids]), mode="markers", name=f"{name} ({len(ids)})", legendgroup="nodes",
                marker=dict(size=size, color=color, symbol=symbol, line=dict(color="black", width=1)),
                hovertext=[f"node {j}<br>valence {val[j]}" for j in ids], hoverinfo="text",
            ))
            groups.append("nodes")

    fig = go.Figure(data=traces)
    if title is None:
        title = f"curvenet: {net.n_nodes} nodes, {net.n_curves} curves"

    def vis(show):
        return [g in show for g in groups]

    buttons = [
        dict(label="all", method="restyle", args=[{"visible": vis({"points", "curves", "nodes"})}]),
        dict(label="curves + nodes", method="restyle", args=[{"visible": vis({"curves", "nodes"})}]),
        dict(label="curves only", method="restyle", args=[{"visible": vis({"curves"})}]),
        dict(label="points only", method="restyle", args=[{"visible": vis({"points"})}]),
    ]
    layout = dict(
        title=dict(text=_html.escape(title), y=0.985, yanchor="top"),
        legend=dict(itemsizing="constant", groupclick="togglegroup"),
        hovermode="closest",
        margin=dict(l=10, r=10, t=95, b=10),
        updatemenus=[dict(type="buttons", direction="right", x=0.0, xanchor="left", y=1.0,
                          yanchor="bottom", buttons=buttons, showactive=True)],
        paper_bgcolor="white",
    )
    if is3d:
        # a view from the front left and slightly above, like the PNG pictures
        layout["scene"] = dict(aspectmode="data", xaxis_title="x", yaxis_title="y", zaxis_title="z",
                               camera=dict(eye=dict(x=-1.1, y=-1.9, z=1.0)))
    else:
        layout["xaxis"] = dict(title="x")
        layout["yaxis"] = dict(title="y", scaleanchor="x", scaleratio=1)
        layout["plot_bgcolor"] = "white"
    fig.update_layout(**layout)
    return fig


def network_to_html(net: CurveNetwork, *, points=None, title: str | None = None,
                    max_points: int = MAX_VIEWER_POINTS, max_curve_traces: int = MAX_CURVE_TRACES) -> str:
    """The viewer page: one HTML document with plotly's JavaScript embedded (works offline).

    Parameters are those of :func:`network_figure`.

    Returns
    -------
    str
        A complete HTML document.
    """
    fig = network_figure(net, points=points, title=title, max_points=max_points,
                         max_curve_traces=max_curve_traces)
    return fig.to_html(
        full_html=True,
        include_plotlyjs=True,
        include_mathjax=False,
        config={"displaylogo": False, "responsive": True, "scrollZoom": True},
        default_width="100%",
        default_height="95vh",
        div_id="curvenet-viewer",
    )


def save_html(net: CurveNetwork, path, *, inputs=(), **options):
    """Write :func:`network_to_html` to ``path`` atomically.

    Returns
    -------
    Path
    """
    from .io.atomic import atomic_write, check_output_path

    check_output_path(path, inputs=inputs)
    return atomic_write(path, network_to_html(net, **options), inputs=inputs)
