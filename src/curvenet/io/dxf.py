"""DXF writer (extra ``io``, ezdxf): curves as 3D polylines or splines (fitted curves), nodes as points.

ezdxf writes the document (header, units, tables, layers, objects) without entities; the
entities are written here as the text ezdxf writes for them, the numbers of all vertices and
points in bulk (:mod:`curvenet.io.numbers`): ezdxf's Python object per vertex cost 81 s for a
network of a million points. ``tests/test_writers_extra.py`` reads the file back with ezdxf,
audits it and compares its entities with those ezdxf builds from the same network.
"""

from __future__ import annotations

import io
from typing import Callable

import numpy as np

from ..errors import InputError, require
from ..lengths import step_lengths
from ..network import CurveNetwork
from ..style import curve_colors
from .numbers import table_groups, table_pieces

__all__ = ["network_to_dxf", "CURVE_LAYER", "NODE_LAYER", "DXF_UNITS"]

CURVE_LAYER = "CURVES"
NODE_LAYER = "NODES"

#: ``units`` names -> the DXF ``$INSUNITS`` code (AutoCAD's drawing-units table); 0 is unitless.
DXF_UNITS = {
    "unitless": 0, "in": 1, "ft": 2, "mi": 3, "mm": 4, "cm": 5, "m": 6, "km": 7,
    "um": 13, "dm": 14, "yd": 10, "nm": 12,
}

#: Unit names that are metric (``$MEASUREMENT`` 1); the others are imperial (0).
_METRIC = {"mm", "cm", "m", "km", "um", "dm", "nm"}


def network_to_dxf(net: CurveNetwork, *, splines: bool | None = None, units: str | None = None) -> bytes:
    """The network as an ASCII DXF drawing (AutoCAD R2010).

    Each curve is one entity on layer ``CURVES``: a 3D ``POLYLINE`` through its points (closed
    for a loop), or with ``splines`` a cubic ``SPLINE`` through them: the interpolating B-spline
    in the chord-length parameter (periodic on a loop), written with its control points and
    knots (what a CAD program draws) and the curve's points as its fit points. Each node is a
    ``POINT`` on layer ``NODES``. Curves get the colours of the PNG pictures (true colour); 2D
    networks are written with z = 0.

    Parameters
    ----------
    net : CurveNetwork
    splines : bool, optional
        Write splines instead of polylines. By default, splines when the network's curves were
        fitted (``net.parameters["fit"]``, see the ``fit`` keyword of the default method).
    units : str, optional
        The unit of the coordinates, a key of :data:`DXF_UNITS` (``"mm"``, ``"m"``, ``"in"``...),
        written as ``$INSUNITS``. By default the drawing is unitless (``$INSUNITS`` 0): the
        points carry no unit, so a CAD program neither scales them nor claims metres.

    Returns
    -------
    bytes
        The DXF text (ASCII; bytes, as a file holds it: a million points make 160 MB). Curves with fewer than 2 points are left out; a curve with fewer than 3
        distinct points (4 on a loop) stays a polyline when ``splines`` is on.
    """
    ezdxf = require("ezdxf", "writing DXF files", "io")

    unit = "unitless" if units is None else str(units).strip().lower()
    if unit not in DXF_UNITS:
        raise InputError(f"unknown DXF units {units!r}; expected one of: {', '.join(DXF_UNITS)}")
    if splines is None:
        splines = bool(net.parameters.get("fit", False))
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = DXF_UNITS[unit]
    if unit != "unitless":
        doc.header["$MEASUREMENT"] = int(unit in _METRIC)
    doc.layers.add(CURVE_LAYER, color=5)
    doc.layers.add(NODE_LAYER, color=1)
    owner = doc.modelspace().block_record_handle
    entities, seed = _entities(net, bool(splines), owner, int(str(doc.entitydb.handles), 16))
    doc.entitydb.handles.reset(f"{seed:X}")  # ezdxf writes it as $HANDSEED, the next free handle
    buf = io.StringIO()
    doc.write(buf)
    head, empty, tail = buf.getvalue().partition(_EMPTY_ENTITIES)
    if not empty:
        raise RuntimeError("ezdxf wrote no ENTITIES section")  # (every version does)
    return b"".join([head.encode(), _ENTITIES_START, *entities, b"  0\nENDSEC\n", tail.encode()])


#: The empty ENTITIES section of the document ezdxf writes, which :func:`network_to_dxf` fills.
_EMPTY_ENTITIES = "  0\nSECTION\n  2\nENTITIES\n  0\nENDSEC\n"
_ENTITIES_START = b"  0\nSECTION\n  2\nENTITIES\n"


def _entities(net: CurveNetwork, splines: bool, owner: str, first: int) -> tuple[list[bytes], int]:
    """The ENTITIES of the drawing as DXF text, and the next free handle.

    The tags of every entity are those ezdxf writes (R2010): a ``POLYLINE`` (3D) with one
    ``VERTEX`` per point and its ``SEQEND``, or a ``SPLINE``, for each curve; a ``POINT`` for
    each node. The numbers of all vertices and points are written in bulk
    (:mod:`curvenet.io.numbers`), where ezdxf's object per entity cost a minute at a million
    points.

    Handles: curves get ``first``, ``first + 1``... (a polyline two, for it and its ``SEQEND``);
    vertices and points get handles whose hexadecimal digits are all decimal digits, from
    ``10**k`` on (``k`` the number of digits of the last curve handle, so they are larger),
    written with the coordinates in the same bulk call. DXF asks only that handles be distinct
    and below ``$HANDSEED``.

    Parameters
    ----------
    net : CurveNetwork
    splines : bool
        Splines through the points of curves (see :func:`network_to_dxf`).
    owner : str
        Handle of the model space's block record.
    first : int
        The first free handle.

    Returns
    -------
    text : list of bytes
        The entities, each starting with its ``  0`` tag, in pieces to be joined.
    seed : int
        A handle above every handle used.
    """
    curves = net.curves
    sizes = np.fromiter((len(c.points) for c in curves), dtype=np.int64, count=len(curves))
    off = np.concatenate([[0], np.cumsum(sizes)])
    P = _xyz_rows(np.concatenate([c.points for c in curves if len(c.points)])) if off[-1] else np.zeros((0, 3))
    closed = [bool(c.closed) for c in curves]
    names = curve_colors(net)
    true_color = {h: _true_color(h) for h in set(names)}
    is_spline = np.zeros(len(curves), dtype=bool)
    spline_data = {}  # curve -> (degree, control (n, 3), knots (n + degree + 1,), fit points (k, 3))
    if splines:
        for i in np.flatnonzero(sizes >= 2).tolist():
            fit = _fit_points(P[off[i]:off[i + 1]], closed[i])
            if len(fit) >= (_MIN_LOOP if closed[i] else 3):
                degree, control, knots = _interpolating_bspline(fit, closed[i])
                spline_data[i] = (degree, np.asarray(control, dtype=float), np.asarray(knots, dtype=float), fit)
                is_spline[i] = True
    written = np.flatnonzero(sizes >= 2)
    poly = written[~is_spline[written]]
    step = np.where(is_spline[written], 1, 2)  # handles of each written curve
    handles = (first + np.concatenate([[0], np.cumsum(step)])[:-1]).tolist()
    last = first + int(step.sum()) - 1
    base = 10 ** len(f"{max(last, first):X}")  # decimal-looking handles above the curves'
    keep = np.repeat(~is_spline & (sizes >= 2), sizes)  # the points of the polylines
    vertex_text, fill = _vertex_texts(P[keep], sizes[poly], base, owner)
    spline_texts = dict(zip(spline_data, _spline_texts(list(spline_data.values()))))
    rgb = [true_color[names[i]] for i in written.tolist()]
    # the tags of each curve before and after its vertices, all in one % call
    head = (f"  0\nPOLYLINE\n  5\n%X\n330\n{owner}\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n420\n%d\n"
            "100\nAcDb3dPolyline\n 66\n1\n 10\n0.0\n 20\n0.0\n 30\n0.0\n 70\n%d\n  0\nVERTEX\n  5\n\x00"
            f"\n 70\n32\n  0\nSEQEND\n  5\n%X\n330\n%X\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n\x00")
    p_idx = np.flatnonzero(~is_spline[written])
    h = np.asarray(handles, dtype=np.int64)[p_idx]
    values = np.column_stack([h, np.asarray(rgb, dtype=np.int64)[p_idx], 8 + np.asarray(closed)[poly], h + 1, h])
    tags = ((head * len(p_idx)) % tuple(values.ravel().tolist())).encode().split(b"\x00")
    out: list = [b""] * (3 * len(written))
    for k, (a, b) in enumerate(zip(p_idx.tolist(), vertex_text)):
        out[3 * a:3 * a + 3] = tags[2 * k], b, tags[2 * k + 1]
    for k, (i, hh) in enumerate(zip(written.tolist(), handles)):
        if is_spline[i]:
            degree, control, knots, fit = spline_data[i]
            out[3 * k] = (
                f"  0\nSPLINE\n  5\n{hh:X}\n330\n{owner}\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n420\n{rgb[k]}\n"
                f"100\nAcDbSpline\n 70\n{int(closed[i])}\n 71\n{degree}\n"
                f" 72\n{len(knots)}\n 73\n{len(control)}\n 74\n{len(fit)}\n".encode()
            )
            out[3 * k + 1] = spline_texts[i]
    n_vert = int(keep.sum())
    seed = int(str(base + n_vert + len(net.nodes)), 16)  # above the last decimal-looking handle
    return [*fill(b"".join(out)), _point_text(net.nodes, base + n_vert, owner)], seed


def _xyz_rows(points) -> np.ndarray:
    """(m, 3) float coordinates of (m, 2|3) points (z = 0 in 2D)."""
    p = np.asarray(points, dtype=float)
    p = p.reshape(len(p), -1) if len(p) else p.reshape(0, p.shape[-1] if p.ndim > 1 else 3)
    if p.shape[1] >= 3:
        return p[:, :3]
    return np.column_stack([p, np.zeros((len(p), 3 - p.shape[1]))])


def _vertex_texts(P: np.ndarray, sizes: np.ndarray, base: int, owner: str) -> tuple[list[bytes], Callable]:
    """The VERTEX entities at the points ``P`` (V, 3) of polylines of ``sizes`` points, each
    from the handle of its first vertex to its last vertex's z (the tags before and after are
    the caller's), and the function that puts in their tags once the caller has joined them with
    its text (:func:`curvenet.io.numbers.table_pieces`)."""
    if not len(sizes):
        return [], lambda text: [text]
    table = np.column_stack([base + np.arange(len(P)), P]).astype(np.float64)
    mid = f"\n330\n{owner}\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n100\nAcDbVertex\n100\nAcDb3dPolylineVertex\n 10\n"
    glue = [mid, "\n 20\n", "\n 30\n", "\n 70\n32\n  0\nVERTEX\n  5\n"]
    return table_pieces(table, glue, int_cols=(0,), groups=np.concatenate([[0], np.cumsum(sizes)]))


def _point_text(nodes: np.ndarray, base: int, owner: str) -> bytes:
    """The POINT entities of the nodes (handles from ``base`` on)."""
    P = _xyz_rows(nodes)
    if not len(P):
        return b""
    table = np.column_stack([base + np.arange(len(P)), P]).astype(np.float64)
    mid = f"\n330\n{owner}\n100\nAcDbEntity\n  8\n{NODE_LAYER}\n100\nAcDbPoint\n 10\n"
    glue = [mid, "\n 20\n", "\n 30\n", "\n  0\nPOINT\n  5\n"]
    return b"  0\nPOINT\n  5\n" + table_groups(table, glue, int_cols=(0,), groups=[0, len(P)])[0] + b"\n"


def _spline_texts(splines: list[tuple]) -> list[bytes]:
    """The tags of each spline (degree, control points, knots, fit points) from its knots on:
    knots, control points, fit points."""
    if not splines:
        return []
    parts = []
    for col, glue in ((2, ["\n 40\n"]), (1, ["\n 20\n", "\n 30\n", "\n 10\n"]), (3, ["\n 21\n", "\n 31\n", "\n 11\n"])):
        arrays = [np.asarray(k[col], dtype=float).reshape(len(k[col]), -1) for k in splines]
        sizes = np.array([len(a) for a in arrays], dtype=np.int64)
        parts.append(table_groups(np.concatenate(arrays), glue, groups=np.concatenate([[0], np.cumsum(sizes)])))
    return [b" 40\n" + k + b"\n 10\n" + c + b"\n 11\n" + f + b"\n" for k, c, f in zip(*parts)]


#: A loop needs this many fit points (its first repeated last) for a periodic cubic spline.
_MIN_LOOP = 5


def _fit_points(pts: np.ndarray, closed: bool) -> np.ndarray:
    """(k, 3) spline fit points: no (nearly) repeated consecutive points, which break the
    interpolation; a closed curve ends where it starts."""
    tol = 1e-9 * max(float(np.ptp(pts, axis=0).max()), 1e-300)
    keep = np.r_[True, step_lengths(np.diff(pts, axis=0)) > tol]
    fit = pts[keep]
    if closed and len(fit) > 2:
        if step_lengths(fit[-1] - fit[0]) <= tol:
            fit = fit[:-1]
        fit = np.vstack([fit, fit[:1]])
    return fit


def _interpolating_bspline(fit: np.ndarray, closed: bool) -> tuple[int, np.ndarray, np.ndarray]:
    """The B-spline through the fit points (k, 3) in the chord-length parameter: its degree
    (3, or 2 for three points), control points (n, 3) and clamped knots (n + degree + 1,);
    periodic (C2 at the seam) for a loop, whose knots are clamped at the seam by knot insertion."""
    from scipy.interpolate import make_interp_spline

    u = np.r_[0.0, np.cumsum(step_lengths(np.diff(fit, axis=0)))]
    k = min(3, len(fit) - 1)
    if not closed:
        b = make_interp_spline(u, fit, k=k)
        return k, b.c, b.t
    b = make_interp_spline(u, fit, k=k, bc_type="periodic")
    tol = 1e-12 * u[-1]
    for x in (u[0], u[-1]):  # clamp at the seam: the knot repeated degree + 1 times
        for _ in range(k + 1 - int(np.sum(np.abs(b.t - x) <= tol))):
            b = b.insert_knot(x)
    i0 = int(np.flatnonzero(np.abs(b.t - u[0]) <= tol)[0])
    i1 = int(np.flatnonzero(np.abs(b.t - u[-1]) <= tol)[-1])
    return k, b.c[i0:i1 - k], b.t[i0:i1 + 1]


def _true_color(hexcolor: str) -> int:
    """DXF true colour (group 420) of ``"#rrggbb"``: ``0xrrggbb``."""
    h = hexcolor.lstrip("#")
    return (int(h[0:2], 16) << 16) | (int(h[2:4], 16) << 8) | int(h[4:6], 16)
