"""An interactive viewer of a curve network: one self-contained HTML file (extra ``viz``).

The page embeds plotly's JavaScript (no CDN, no network access), so it works offline and can be
mailed or archived as one file. Curves are coloured as in the PNG pictures; nodes (junctions,
free ends) and the input points can be shown or hidden with the legend or the buttons; hovering
a curve shows its id, end nodes and length, hovering a node its id and valence.
"""

from __future__ import annotations

import html as _html
import math
from dataclasses import dataclass

import numpy as np

from .errors import InputError, require
from .network import CurveNetwork
from .style import END_COLOR, JUNCTION_COLOR, OTHER_NODE_COLOR, POINT_COLOR, curve_colors

__all__ = ["network_figure", "network_to_html", "save_html", "subsample_points", "plan_display", "DisplayPlan",
           "thin_polyline"]

#: Input points beyond this number are thinned for the viewer (see :func:`subsample_points`).
MAX_VIEWER_POINTS = 200_000

#: Networks with more curves than this draw one trace per colour instead of one per curve.
MAX_CURVE_TRACES = 300

#: Largest page by default, in bytes: points, then curve samples are thinned to stay under it.
#: plotly's JavaScript alone is about 4.8 MB of it (the least a page can weigh).
MAX_VIEWER_BYTES = 20_000_000

#: The smallest page budget accepted by ``curvenet view --max-mb``, in bytes (plotly's
#: JavaScript and a small network).
MIN_VIEWER_BYTES = 5_000_000

#: Bytes a coordinate takes in the page (plotly 6+ writes arrays as base64 float64: measured
#: 40.4 bytes per 3D point on 100,000 points, including the array framing).
_BYTES_PER_COORD = 14

#: Bytes of a per-sample hover text when curves share a trace (measured: 73 per sample).
_BYTES_PER_SHARED_HOVER = 75

#: Bytes of a node's marker and hover text ("node 12<br>valence 3").
_BYTES_PER_NODE_HOVER = 30

#: Bytes of the page around the data (HTML, layout, legend, buttons) and of each trace.
_PAGE_BYTES = 60_000
_TRACE_BYTES = 600

#: When both must be thinned, the curves keep this share of the data budget, the points the rest.
CURVE_SHARE = 0.75

#: Node markers keep their full size up to this many nodes, and shrink as 1/sqrt(count) beyond
#: (down to :data:`MIN_MARKER_SCALE`), so that thousands of nodes do not cover the curves.
MARKER_FULL_SIZE_NODES = 50
MIN_MARKER_SCALE = 0.3

#: Thinnest axis of the 3D box, relative to the widest (a flat network keeps some depth).
MIN_ASPECT = 0.05

#: The first camera of a 3D network whose box is a cube: from the front left and slightly above,
#: like the PNG pictures; for other boxes it moves along this line with the box's diagonal.
EYE_DIRECTION = (-1.1, -1.9, 1.0)


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


def thin_polyline(points: np.ndarray, stride: int) -> np.ndarray:
    """Every ``stride``-th row of an (m, d) polyline, its first and last rows always kept.

    The ends are the positions of the curve's nodes, so a thinned network keeps its topology.
    """
    if stride <= 1 or len(points) <= 2:
        return points
    keep = np.arange(0, len(points), stride)
    if keep[-1] != len(points) - 1:
        keep = np.append(keep, len(points) - 1)
    return points[keep]


@dataclass(frozen=True)
class DisplayPlan:
    """What the viewer shows of a network and its points (see :func:`plan_display`).

    Attributes
    ----------
    points_total, points_shown : int
        Input points given and drawn.
    samples_total, curve_stride : int
        Curve samples in the network; every ``curve_stride``-th one is drawn (ends kept).
    max_bytes : int or None
        The page budget the plan keeps to.
    """

    points_total: int
    points_shown: int
    samples_total: int
    curve_stride: int
    max_bytes: int | None

    @property
    def thinned(self) -> bool:
        """True when points or curve samples are left out."""
        return self.points_shown < self.points_total or self.curve_stride > 1

    def message(self) -> str:
        """One line saying what was thinned and why ("" when nothing was)."""
        if not self.thinned:
            return ""
        parts = []
        if self.points_shown < self.points_total:
            parts.append(f"{self.points_shown} of {self.points_total} input points")
        if self.curve_stride > 1:
            parts.append(f"1 in {self.curve_stride} curve samples (curve ends kept)")
        why = f" to keep the page under {self.max_bytes / 1e6:.0f} MB" if self.max_bytes else ""
        return "viewer shows " + " and ".join(parts) + why


def plan_display(net: CurveNetwork, points=None, *, max_points: int = MAX_VIEWER_POINTS,
                 max_bytes: int | None = MAX_VIEWER_BYTES, max_curve_traces: int = MAX_CURVE_TRACES) -> DisplayPlan:
    """Decide how much of the points and curve samples the viewer draws.

    Points are first cut to ``max_points``. If the page would then exceed ``max_bytes``
    (estimated from the bytes each coordinate and hover text takes), the points are thinned
    first; if that is not enough, the curves keep :data:`CURVE_SHARE` of the data budget and
    draw every k-th sample (their ends, the nodes, always).

    Parameters
    ----------
    net : CurveNetwork
    points : (N, d) array_like, optional
    max_points : int
    max_bytes : int, optional
        None: no size limit.
    max_curve_traces : int
        As in :func:`network_figure` (shared traces carry a hover text per sample).

    Returns
    -------
    DisplayPlan
    """
    n_pts = 0 if points is None else int(len(points))
    shown = min(n_pts, max(0, int(max_points)))
    samples = int(sum(len(c.points) + bool(c.closed) for c in net.curves))
    if max_bytes is None:
        return DisplayPlan(n_pts, shown, samples, 1, None)
    from plotly.offline import get_plotlyjs

    d = net.dimension
    per = _BYTES_PER_COORD * d
    per_sample = per + (_BYTES_PER_SHARED_HOVER if net.n_curves > max_curve_traces else 0)
    fixed = len(get_plotlyjs()) + _PAGE_BYTES + _TRACE_BYTES * min(net.n_curves, max_curve_traces)
    fixed += net.n_nodes * (per + _BYTES_PER_NODE_HOVER)
    avail = max(0, max_bytes - fixed)
    curves = samples * per_sample
    stride = 1
    if curves + shown * per > avail:
        room = max(avail - curves, (1 - CURVE_SHARE) * avail)
        shown = min(shown, int(room // per))
        if curves > avail - shown * per:
            ends = 2 * net.n_curves * per_sample
            stride = max(2, math.ceil((curves - ends) / max(1.0, avail - shown * per - ends)))
    return DisplayPlan(n_pts, shown, samples, stride, int(max_bytes))


def network_figure(net: CurveNetwork, *, points=None, title: str | None = None,
                   max_points: int = MAX_VIEWER_POINTS, max_curve_traces: int = MAX_CURVE_TRACES,
                   max_bytes: int | None = MAX_VIEWER_BYTES):
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
    max_bytes : int, optional
        Keep the page under this size (default :data:`MAX_VIEWER_BYTES`) by thinning the points
        and then the curve samples (see :func:`plan_display`); the legend says what is shown.

    Returns
    -------
    plotly.graph_objects.Figure
        3D networks are framed whole: the box's axes keep the network's proportions with the
        widest scaled to 1 (no axis so long that the first camera crops it); node markers
        shrink with the node count.
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

    plan = plan_display(net, pts, max_points=max_points, max_bytes=max_bytes, max_curve_traces=max_curve_traces)
    traces = []
    groups = []  # legend group of each trace, for the buttons
    if pts is not None and len(pts):
        shown = subsample_points(pts, plan.points_shown)
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
        lines.append(thin_polyline(p, plan.curve_stride))
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
        thin = f", 1 in {plan.curve_stride} samples shown" if plan.curve_stride > 1 else ""
        traces[groups.index("curves")].name = f"curves ({net.n_curves}{thin})"

    if net.n_nodes:
        kinds = net.node_kinds
        val = net.valence
        scale = max(MIN_MARKER_SCALE, min(1.0, math.sqrt(MARKER_FULL_SIZE_NODES / net.n_nodes)))
        style = {
            "junction": ("junctions", "circle", JUNCTION_COLOR, (6 if is3d else 10) * scale),
            "end": ("free ends", "square", END_COLOR, (5 if is3d else 9) * scale),
            "other": ("other nodes", "diamond", OTHER_NODE_COLOR, (5 if is3d else 9) * scale),
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
    ]
    if "points" in groups:  # offered only when there are points to show
        buttons.append(dict(label="points only", method="restyle", args=[{"visible": vis({"points"})}]))
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
        # the whole network in view: the box keeps the data's proportions with its widest axis 1
        # (plotly's "data" mode scales the box to a unit volume, so a long network overflows)
        allp = [net.nodes] + [c.points for c in net.curves]
        if pts is not None and len(pts):
            allp.append(pts)
        allp = np.vstack([a.reshape(-1, 3) for a in allp])
        span = np.ptp(allp, axis=0) if len(allp) else np.ones(3)
        ratio = np.maximum(span / (span.max() or 1.0), MIN_ASPECT)
        # the camera's distance follows the box's diagonal (a cube's keeps plotly's framing)
        eye = np.array(EYE_DIRECTION) * float(np.linalg.norm(ratio) / np.sqrt(3.0))
        layout["scene"] = dict(aspectmode="manual", aspectratio=dict(x=ratio[0], y=ratio[1], z=ratio[2]),
                               xaxis_title="x", yaxis_title="y", zaxis_title="z",
                               camera=dict(eye=dict(x=eye[0], y=eye[1], z=eye[2])))
    else:
        layout["xaxis"] = dict(title="x")
        layout["yaxis"] = dict(title="y", scaleanchor="x", scaleratio=1)
        layout["plot_bgcolor"] = "white"
    fig.update_layout(**layout)
    return fig


def network_to_html(net: CurveNetwork, *, points=None, title: str | None = None,
                    max_points: int = MAX_VIEWER_POINTS, max_curve_traces: int = MAX_CURVE_TRACES,
                    max_bytes: int | None = MAX_VIEWER_BYTES) -> str:
    """The viewer page: one HTML document with plotly's JavaScript embedded (works offline).

    Parameters are those of :func:`network_figure`.

    Returns
    -------
    str
        A complete HTML document.
    """
    fig = network_figure(net, points=points, title=title, max_points=max_points,
                         max_curve_traces=max_curve_traces, max_bytes=max_bytes)
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
