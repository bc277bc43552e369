"""PNG pictures of a curve network, in the style of the paper's Figure 6 (extra ``viz``).

Input points are drawn faint, every curve in its own colour (curves that share a node get
different colours), junctions and free ends with different markers, with equal axis scales. The
colours are those of :mod:`curvenet.style`, shared with the viewer and the SVG and DXF writers.
3D networks are drawn from a fixed view (``elev``, ``azim`` in degrees, as in matplotlib).

matplotlib is imported inside the functions and used without pyplot (no global state, no
display needed).
"""

from __future__ import annotations

from io import BytesIO
import numpy as np

from ..errors import InputError, require
from ..network import CurveNetwork
from ..style import (
    END_COLOR,
    JUNCTION_COLOR,
    OTHER_NODE_COLOR,
    PALETTE,
    POINT_COLOR,
    curve_colors,
    curve_sort_key,
)

__all__ = [
    "DEFAULT_ELEV",
    "DEFAULT_AZIM",
    "MAX_PICTURE_SIDE",
    "MAX_PICTURE_AREA",
    "check_picture",
    "plot_network",
    "render_png",
    "save_png",
]

#: Default 3D view (degrees), looking slightly from above and from the front left.
DEFAULT_ELEV = 25.0
DEFAULT_AZIM = -60.0

#: Longest side of a picture in pixels: matplotlib's Agg renderer refuses 2**16 and more.
MAX_PICTURE_SIDE = 2**16 - 1
#: Most pixels in a picture: 2**28 pixels of 4 bytes are the 1 GiB canvas Agg allocates.
MAX_PICTURE_AREA = 2**28


def check_picture(*, width: float, height: float, dpi: float, elev: float = DEFAULT_ELEV,
                  azim: float = DEFAULT_AZIM) -> None:
    """Check the size and the view of a picture before any drawing.

    Parameters
    ----------
    width, height : float
        Figure size in inches.
    dpi : float
        Pixels per inch.
    elev, azim : float
        3D view angles in degrees.

    Raises
    ------
    InputError
        When a size is not positive, the picture has a side over :data:`MAX_PICTURE_SIDE` or
        more than :data:`MAX_PICTURE_AREA` pixels, or an angle is not finite.
    """
    if not (width > 0 and height > 0 and dpi > 0):
        raise InputError(f"picture size must be positive, got {width} x {height} in at {dpi} dpi")
    w, h = width * dpi, height * dpi
    if max(w, h) > MAX_PICTURE_SIDE or w * h > MAX_PICTURE_AREA:
        raise InputError(f"a picture of {w:.0f} x {h:.0f} pixels ({width:g} x {height:g} in at {dpi} dpi) is too "
                         f"large: at most {MAX_PICTURE_SIDE} pixels a side and {MAX_PICTURE_AREA} pixels; "
                         "lower --dpi")
    for name, v in (("elev", elev), ("azim", azim)):
        if not np.isfinite(v):
            raise InputError(f"{name} must be a finite angle in degrees, got {v}")


#: Pictures are drawn for coordinates whose magnitude and extent lie within these bounds
#: (matplotlib's transforms square coordinates: beyond about 1e150 they overflow, below about
#: 1e-150 they vanish); outside, :func:`render_png` refuses with an :class:`InputError`
#: instead of failing inside matplotlib.
DRAWABLE_RANGE = (1e-100, 1e100)


def _check_drawable(net: CurveNetwork, points) -> None:
    """Refuse coordinates too large or too small for matplotlib (see :data:`DRAWABLE_RANGE`)."""
    parts = [np.asarray(net.nodes, dtype=float).reshape(-1, net.dimension)]
    parts += [np.asarray(c.points, dtype=float).reshape(-1, net.dimension) for c in net.curves]
    if points is not None:
        parts.append(points)
    X = np.concatenate(parts) if parts else np.zeros((0, net.dimension))
    if not len(X):
        return
    lo, hi = DRAWABLE_RANGE
    with np.errstate(over="ignore", invalid="ignore"):
        size = float(np.abs(X).max())
        extent = float(np.ptp(X, axis=0).max())
    if size > hi or (extent > 0 and extent < lo):
        raise InputError(
            f"cannot draw coordinates of magnitude {size:.3g} spanning {extent:.3g}: pictures need "
            f"extents between {lo:g} and {hi:g} (scale the points or the network)"
        )


def _check_points(net: CurveNetwork, points) -> np.ndarray | None:
    if points is None:
        return None
    from ..validate import as_points

    pts = as_points(points, min_points=0)
    if pts.shape[1] != net.dimension:
        raise InputError(
            f"points have dimension {pts.shape[1]} but the network has dimension {net.dimension}"
        )
    return pts


def _polylines(net: CurveNetwork) -> list[np.ndarray]:
    out = []
    for c in net.curves:
        p = c.points
        if c.closed and len(p) > 1:
            p = np.vstack([p, p[:1]])
        out.append(p)
    return out


def plot_network(
    net: CurveNetwork,
    *,
    points=None,
    ax=None,
    elev: float = DEFAULT_ELEV,
    azim: float = DEFAULT_AZIM,
    legend: bool = True,
    title: str | None = None,
    show_nodes: bool = True,
):
    """Draw a network on a matplotlib Axes (2D) or Axes3D (3D).

    Parameters
    ----------
    net : CurveNetwork
    points : (N, d) array_like, optional
        The input points, drawn small and faint; ``d`` must be the network's dimension.
    ax : matplotlib Axes, optional
        Where to draw (an ``Axes3D`` for a 3D network). A new figure is made when omitted.
    elev, azim : float
        3D view angles in degrees (ignored in 2D).
    legend : bool
        Add a legend (points, curves, junctions, free ends).
    title : str, optional
        Axes title; the default names the counts of nodes and curves; ``""`` for none.
    show_nodes : bool
        Mark the nodes.

    Returns
    -------
    matplotlib Axes
    """
    require("matplotlib", "drawing networks", "viz")
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    pts = _check_points(net, points)
    d = net.dimension
    if d not in (2, 3):
        raise InputError(f"can only draw 2D or 3D networks, got dimension {d}")
    if ax is None:
        fig = Figure(figsize=(8, 6.5))
        ax = fig.add_subplot(**_subplot_kw(d))
    is3d = getattr(ax, "name", "") == "3d"
    if d == 3 and not is3d:
        raise InputError("a 3D network needs a 3D axes (projection='3d')")

    handles = []
    if pts is not None and len(pts):
        s = float(np.clip(3000.0 / len(pts), 0.2, 6.0))
        ax.scatter(*pts.T, s=s, c=POINT_COLOR, alpha=0.35, linewidths=0, rasterized=True, zorder=1,
                   **({"depthshade": False} if is3d else {}))
        handles.append(Line2D([], [], ls="", marker="o", ms=4, color=POINT_COLOR, alpha=0.6,
                              label=f"input points ({len(pts)})"))

    lines = _polylines(net)
    colors = curve_colors(net)
    # drawn in an order fixed by geometry, so the picture does not depend on the curve order
    keep = sorted((i for i, p in enumerate(lines) if len(p) >= 2), key=lambda i: curve_sort_key(net.curves[i]))
    if keep:
        segs = [lines[i] for i in keep]
        cols = [colors[i] for i in keep]
        if is3d:
            from mpl_toolkits.mplot3d.art3d import Line3DCollection

            coll = Line3DCollection(segs, colors=cols, linewidths=1.8, zorder=2)
            ax.add_collection3d(coll)
        else:
            coll = LineCollection(segs, colors=cols, linewidths=1.8, zorder=2, capstyle="round")
            ax.add_collection(coll)
    if net.n_curves:
        handles.append(Line2D([], [], color=PALETTE[0], lw=2, label=f"curves ({net.n_curves}), one colour each"))

    if show_nodes and net.n_nodes:
        kinds = net.node_kinds
        style = {
            "junction": dict(marker="o", s=38, c=JUNCTION_COLOR, label="junctions"),
            "end": dict(marker="s", s=30, c=END_COLOR, label="free ends"),
            "other": dict(marker="D", s=26, c=OTHER_NODE_COLOR, label="other nodes"),
        }
        for kind in ("other", "end", "junction"):
            m = kinds == kind
            if not m.any():
                continue
            st = dict(style[kind])
            label = st.pop("label")
            ax.scatter(*net.nodes[m].T, edgecolors="k", linewidths=0.8, zorder=4,
                       **({"depthshade": False} if is3d else {}), **st)
            handles.append(Line2D([], [], ls="", marker=st["marker"], ms=6, mfc=st["c"], mec="k",
                                  label=f"{label} ({int(m.sum())})"))

    _set_limits(ax, net, pts, is3d, elev, azim)
    if title is None:
        title = f"{net.n_nodes} nodes, {net.n_curves} curves"
    if title:
        ax.set_title(title)
    if legend and handles:
        ax.legend(handles=handles, loc="upper right", fontsize="small", framealpha=0.85)
    return ax


def _subplot_kw(d: int) -> dict:
    # computed_zorder=False: nodes stay on top of curves, curves on top of points, in 3D too
    return {"projection": "3d", "computed_zorder": False} if d == 3 else {}


def _set_limits(ax, net: CurveNetwork, pts, is3d: bool, elev: float, azim: float) -> None:
    d = net.dimension
    blocks = [net.nodes.reshape(-1, d)] + [c.points for c in net.curves]
    if pts is not None:
        blocks.append(pts)
    allp = np.vstack(blocks) if blocks else np.zeros((0, d))
    if len(allp) == 0:
        allp = np.zeros((1, d))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = hi - lo
    big = float(span.max()) or 1.0
    pad = 0.04 * big
    span = np.maximum(span, 1e-3 * big)
    mid = (lo + hi) / 2
    lo, hi = mid - span / 2 - pad, mid + span / 2 + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    if is3d:
        ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(tuple(hi - lo), zoom=0.95)
        ax.view_init(elev=elev, azim=azim)
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_zlabel("z")
    else:
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x")
        ax.set_ylabel("y")


def _default_height(net: CurveNetwork, points, width: float) -> float:
    if net.dimension != 2:
        return 6.5
    blocks = [net.nodes] + [c.points for c in net.curves]
    if points is not None:
        blocks.append(np.asarray(points, dtype=float).reshape(-1, 2))
    allp = np.vstack(blocks)
    if len(allp) == 0:
        return 6.5
    span = np.ptp(allp, axis=0)
    ratio = span[1] / span[0] if span[0] > 0 else 1.6
    return float(np.clip(ratio, 0.45, 1.6) * (width - 1.0) + 1.2)


def render_png(
    net: CurveNetwork,
    *,
    points=None,
    width: float = 8.0,
    height: float | None = None,
    dpi: int = 120,
    elev: float = DEFAULT_ELEV,
    azim: float = DEFAULT_AZIM,
    legend: bool = True,
    title: str | None = None,
) -> bytes:
    """The PNG picture of a network, as bytes.

    Parameters
    ----------
    net : CurveNetwork
    points : (N, d) array_like, optional
        Input points, drawn faint.
    width, height : float
        Figure size in inches; by default the height follows the shape of a 2D network (6.5 in
        for 3D).
    dpi : int
        Pixels per inch (the PNG is ``width * dpi`` by ``height * dpi`` pixels).
    elev, azim, legend, title
        As in :func:`plot_network`.

    Returns
    -------
    bytes
        PNG data (without a time stamp, so the same input gives the same bytes).
    """
    require("matplotlib", "drawing networks", "viz")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    points = _check_points(net, points)
    _check_drawable(net, points)
    if height is None:
        height = _default_height(net, points, width)
    check_picture(width=width, height=height, dpi=dpi, elev=elev, azim=azim)
    fig = Figure(figsize=(width, height), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(**_subplot_kw(net.dimension))
    plot_network(net, points=points, ax=ax, elev=elev, azim=azim, legend=legend, title=title)
    if net.dimension == 2:
        fig.tight_layout()
    buf = BytesIO()
    extra = {"bbox_inches": "tight", "pad_inches": 0.2} if net.dimension == 3 else {}
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None}, facecolor="white", **extra)
    return buf.getvalue()


def save_png(net: CurveNetwork, path, *, inputs=(), **options):
    """Write :func:`render_png` to ``path`` atomically; ``options`` go to :func:`render_png`.

    Returns
    -------
    Path
    """
    from ..io.atomic import atomic_write, check_output_path

    check_output_path(path, inputs=inputs)
    return atomic_write(path, render_png(net, **options), inputs=inputs)
