"""PNG pictures of a surfaced network, like the bottom row of the paper's Figure 6 (extra ``viz``).

Each patch gets a pale colour, shaded by the angle between its triangle normals and a light near
the viewer; triangles are projected with the camera of matplotlib's ``view_init(elev, azim)`` and
painted far to near (correct for meshes without intersections); the curves of the network are
drawn on top in dark lines. matplotlib is imported inside the
functions and used without pyplot (Agg canvas, no global state).
"""

from __future__ import annotations

from io import BytesIO

import numpy as np

from ..errors import InputError, require

__all__ = ["render_surface_png", "PATCH_PALETTE"]

#: Pale patch colours (Pastel1 / Set3 of ColorBrewer).
PATCH_PALETTE: tuple[str, ...] = (
    "#8dd3c7", "#ffffb3", "#bebada", "#fb8072", "#80b1d3", "#fdb462", "#b3de69", "#fccde5",
    "#bc80bd", "#ccebc5", "#ffed6f", "#d9d9d9",
)  # fmt: skip


def render_surface_png(
    mesh,
    *,
    network=None,
    width: float = 8.0,
    height: float = 6.5,
    dpi: int = 120,
    elev: float = 25.0,
    azim: float = -60.0,
    title: str | None = None,
) -> bytes:
    """Draw a :class:`~curvenet.surfacing.SurfaceMesh` and return the PNG bytes.

    Parameters
    ----------
    mesh : SurfaceMesh
    network : CurveNetwork, optional
        Its curves are drawn over the surface.
    width, height : float
        Figure size in inches.
    dpi : int
        Pixels per inch.
    elev, azim : float
        View angles in degrees (as in matplotlib).
    title : str, optional

    Returns
    -------
    bytes
        The PNG file.

    Raises
    ------
    InputError
        For a mesh without triangles or a non-positive size.
    MissingDependencyError
        If matplotlib is missing.
    """
    require("matplotlib", "drawing PNG pictures", "viz")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.colors import to_rgb
    from matplotlib.figure import Figure

    V = np.asarray(mesh.vertices, dtype=float)
    T = np.asarray(mesh.triangles, dtype=np.int64)
    if not len(T):
        raise InputError("the surface mesh has no triangles to draw")
    if not (width > 0 and height > 0 and dpi > 0):
        raise InputError(f"picture size must be positive, got {width} x {height} in at {dpi} dpi")
    P = np.asarray(mesh.patch, dtype=np.int64)
    # camera of matplotlib's view_init(elev, azim); painter's algorithm on the projected mesh
    el, az = np.radians(elev), np.radians(azim)
    right = np.array([-np.sin(az), np.cos(az), 0.0])
    up = np.array([-np.sin(el) * np.cos(az), -np.sin(el) * np.sin(az), np.cos(el)])
    toward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    tri = V[T]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = 0.6 * toward + 0.4 * up
    light /= np.linalg.norm(light)
    shade = 0.45 + 0.55 * np.abs(n @ light)
    base = np.array([to_rgb(c) for c in PATCH_PALETTE])[P % len(PATCH_PALETTE)]
    colors = np.clip(base * shade[:, None], 0, 1)
    order = np.argsort(tri.mean(axis=1) @ toward, kind="stable")  # far first
    xy = np.stack([tri @ right, tri @ up], axis=-1)[order]

    fig = Figure(figsize=(width, height), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.add_collection(PolyCollection(xy, facecolors=colors[order], edgecolors=colors[order], linewidths=0.2))
    if network is not None:
        segs = []
        for c in network.curves:
            p = np.asarray(c.points, dtype=float)
            if p.shape[1] == 2:
                p = np.column_stack([p, np.zeros(len(p))])
            if c.closed and len(p) > 2 and c.start is None:
                p = np.vstack([p, p[:1]])
            segs.append(np.column_stack([p @ right, p @ up]))
        ax.add_collection(LineCollection(segs, colors="#222222", linewidths=1.0, alpha=0.85))
    allxy = xy.reshape(-1, 2)
    lo, hi = allxy.min(axis=0), allxy.max(axis=0)
    pad = 0.03 * max(float((hi - lo).max()), 1e-12)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_axis_off()
    if title:
        ax.set_title(title)
    buf = BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
