"""DXF writer (extra ``io``, ezdxf): curves as 3D polylines or splines (fitted curves), nodes as points.

ezdxf writes the document (header, units, tables, layers, objects) without entities; the
entities are written here as the text ezdxf writes for them, the numbers of all vertices and
points in bulk (:mod:`curvenet.io.numbers`): ezdxf's Python object per vertex cost 81 s for a
network of a million points. ``tests/test_writers_extra.py`` reads the file back with ezdxf,
audits it and compares its entities with those ezdxf builds from the same network.
"""

from __future__ import annotations

import io
from itertools import chain
from typing import NamedTuple

import numpy as np

from ..errors import InputError, require
from ..lengths import step_lengths
from ..network import CurveNetwork
from ..style import curve_colors
from .gc_pause import collector_paused
from .numbers import table_groups
from .splines import DEGREE, cubic_splines, open_fit_points

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
    with collector_paused():  # (100k pieces of text: see curvenet.io.gc_pause)
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
    text : list of bytes or memoryview
        The entities, each starting with its ``  0`` tag, in pieces to be joined (the numbers'
        text as views into the texts of chunks of numbers: the join copies each byte once).
    seed : int
        A handle above every handle used.
    """
    curves = net.curves
    sizes = np.fromiter((len(c.points) for c in curves), dtype=np.int64, count=len(curves))
    off = np.concatenate([[0], np.cumsum(sizes)])
    P = _xyz_rows(np.concatenate([c.points for c in curves if len(c.points)])) if off[-1] else np.zeros((0, 3))
    closed = np.fromiter((bool(c.closed) for c in curves), dtype=bool, count=len(curves))
    names = curve_colors(net)
    true_color = {h: _true_color(h) for h in set(names)}
    sp = _splines(P, off, closed) if splines else None
    is_spline = sp.is_spline if sp else np.zeros(len(curves), dtype=bool)
    written = np.flatnonzero(sizes >= 2)
    poly = written[~is_spline[written]]
    step = np.where(is_spline[written], 1, 2)  # handles of each written curve
    handles = first + np.concatenate([[0], np.cumsum(step)])[:-1]
    last = first + int(step.sum()) - 1
    base = 10 ** len(f"{max(last, first):X}")  # decimal-looking handles above the curves'
    keep = np.repeat(~is_spline & (sizes >= 2), sizes)  # the points of the polylines
    vertex_text = _vertex_texts(P[keep], sizes[poly], base, owner)
    rgb = np.array([true_color[names[i]] for i in written.tolist()], dtype=np.int64)
    pieces: list[tuple] = [()] * len(written)  # the pieces of each written curve's entity
    p_idx = np.flatnonzero(~is_spline[written])
    tags = _polyline_tags(handles[p_idx], rgb[p_idx], closed[poly], owner)
    for k, (a, b) in enumerate(zip(p_idx.tolist(), vertex_text)):
        pieces[a] = (tags[2 * k], b, tags[2 * k + 1])
    if sp is not None:
        s_idx = np.flatnonzero(is_spline[written])
        heads = _spline_heads(handles[s_idx], rgb[s_idx], closed[written[s_idx]], sp, owner)
        for k, a, b in zip(s_idx.tolist(), heads, _spline_texts(sp)):
            pieces[k] = (a, *b)
    n_vert = int(keep.sum())
    seed = int(str(base + n_vert + len(net.nodes)), 16)  # above the last decimal-looking handle
    out = list(chain.from_iterable(pieces))
    out.append(_point_text(net.nodes, base + n_vert, owner))
    return out, seed


def _polyline_tags(handles: np.ndarray, rgb: np.ndarray, closed: np.ndarray, owner: str) -> list[bytes]:
    """The tags of each polyline before its vertices and after them (two pieces a polyline,
    all written by one ``%``), for polylines of handles (p,), true colours (p,) and flags (p,)."""
    head = (f"  0\nPOLYLINE\n  5\n%X\n330\n{owner}\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n420\n%d\n"
            "100\nAcDb3dPolyline\n 66\n1\n 10\n0.0\n 20\n0.0\n 30\n0.0\n 70\n%d\n  0\nVERTEX\n  5\n\x00"
            f"\n 70\n32\n  0\nSEQEND\n  5\n%X\n330\n%X\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n\x00")
    values = np.column_stack([handles, rgb, 8 + closed, handles + 1, handles])
    return ((head * len(handles)) % tuple(values.ravel().tolist())).encode().split(b"\x00")


def _spline_heads(handles: np.ndarray, rgb: np.ndarray, closed: np.ndarray, sp: "_SplineTables",
                  owner: str) -> list[bytes]:
    """The tags of each spline before its knots (one ``%`` for all), for splines of handles
    (s,), true colours (s,) and flags (s,)."""
    head = (f"  0\nSPLINE\n  5\n%X\n330\n{owner}\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n420\n%d\n"
            "100\nAcDbSpline\n 70\n%d\n 71\n%d\n 72\n%d\n 73\n%d\n 74\n%d\n 40\n\x00")
    values = np.column_stack([handles, rgb, closed, sp.degree, np.diff(sp.knot_off), np.diff(sp.ctrl_off),
                              np.diff(sp.fit_off)])
    return ((head * len(handles)) % tuple(values.ravel().tolist())).encode().split(b"\x00")[:-1]


def _xyz_rows(points) -> np.ndarray:
    """(m, 3) float coordinates of (m, 2|3) points (z = 0 in 2D)."""
    p = np.asarray(points, dtype=float)
    p = p.reshape(len(p), -1) if len(p) else p.reshape(0, p.shape[-1] if p.ndim > 1 else 3)
    if p.shape[1] >= 3:
        return p[:, :3]
    return np.column_stack([p, np.zeros((len(p), 3 - p.shape[1]))])


def _vertex_texts(P: np.ndarray, sizes: np.ndarray, base: int, owner: str) -> list[bytes | memoryview]:
    """The VERTEX entities at the points ``P`` (V, 3) of polylines of ``sizes`` points, each
    from the handle of its first vertex to its last vertex's z (the tags before and after are
    the caller's), as views into the texts of chunks of polylines
    (:func:`curvenet.io.numbers.table_groups`)."""
    if not len(sizes):
        return []
    table = np.column_stack([base + np.arange(len(P)), P]).astype(np.float64)
    mid = f"\n330\n{owner}\n100\nAcDbEntity\n  8\n{CURVE_LAYER}\n100\nAcDbVertex\n100\nAcDb3dPolylineVertex\n 10\n"
    glue = [mid, "\n 20\n", "\n 30\n", "\n 70\n32\n  0\nVERTEX\n  5\n"]
    return table_groups(table, glue, int_cols=(0,), groups=np.concatenate([[0], np.cumsum(sizes)]), views=True)


def _point_text(nodes: np.ndarray, base: int, owner: str) -> bytes:
    """The POINT entities of the nodes (handles from ``base`` on)."""
    P = _xyz_rows(nodes)
    if not len(P):
        return b""
    table = np.column_stack([base + np.arange(len(P)), P]).astype(np.float64)
    mid = f"\n330\n{owner}\n100\nAcDbEntity\n  8\n{NODE_LAYER}\n100\nAcDbPoint\n 10\n"
    glue = [mid, "\n 20\n", "\n 30\n", "\n  0\nPOINT\n  5\n"]
    return b"  0\nPOINT\n  5\n" + table_groups(table, glue, int_cols=(0,), groups=[0, len(P)])[0] + b"\n"


class _SplineTables(NamedTuple):
    """The splines of a drawing, in the order of their curves: ``s`` splines."""

    is_spline: np.ndarray  #: (C,) bool: which curves are splines
    degree: np.ndarray  #: (s,) int
    fit: np.ndarray  #: (F, 3) fit points; spline ``j``: rows ``fit_off[j]:fit_off[j + 1]``
    fit_off: np.ndarray  #: (s + 1,) int
    control: np.ndarray  #: (K, 3) control points, by ``ctrl_off`` (s + 1,)
    ctrl_off: np.ndarray
    knots: np.ndarray  #: (T,) knots, by ``knot_off`` (s + 1,)
    knot_off: np.ndarray


def _splines(P: np.ndarray, off: np.ndarray, closed: np.ndarray) -> _SplineTables:
    """The splines through the curves (see :func:`network_to_dxf`): fit points, control points
    and knots of each curve that gets one.

    The open curves with at least 4 fit points, nearly all, are made together
    (:func:`curvenet.io.splines.cubic_splines`, SciPy's splines to the bit); loops and curves of
    3 fit points one by one (:func:`_interpolating_bspline`).

    Parameters
    ----------
    P : (N, 3) float ndarray
        The points of all curves, curve ``c`` being rows ``off[c]:off[c + 1]``.
    off : (C + 1,) int ndarray
    closed : (C,) bool ndarray

    Returns
    -------
    _SplineTables
    """
    two = np.flatnonzero(np.diff(off) >= 2)
    rows, r_off = _open_fit_rows(P, off, two)
    counts = np.diff(r_off)
    one = {}  # curve -> (degree, control, knots, fit) made alone
    for j in np.flatnonzero(closed[two] | (counts == 3)).tolist():
        i = int(two[j])
        fit = _fit_points(P[off[i]:off[i + 1]], True) if closed[i] else P[rows[r_off[j]:r_off[j + 1]]]
        if len(fit) >= (_MIN_LOOP if closed[i] else 3):
            one[i] = (*_interpolating_bspline(fit, bool(closed[i])), fit)
    batch = ~closed[two] & (counts >= 4)
    F = P[rows[np.repeat(batch, counts)]]
    f_off = np.concatenate([[0], np.cumsum(counts[batch])])
    made = cubic_splines(F, f_off)
    if made is None:  # SciPy would raise (or find a singular system): one by one, for its error
        for i, fit in zip(two[batch].tolist(), np.split(F, f_off[1:-1])):
            one[i] = (*_interpolating_bspline(fit, False), fit)
        batch[:], F, f_off = False, F[:0], f_off[:1]
        made = cubic_splines(F, f_off)
    return _gather(len(closed), two[batch], F, f_off, made, one)


def _open_fit_rows(P: np.ndarray, off: np.ndarray, two: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows of ``P`` kept as fit points of the curves ``two`` (w,), of 2 or more points,
    were they open (:func:`_fit_points`): all rows (R,) and the offsets of each curve's (w + 1,)."""
    sizes = np.diff(off)[two]
    sub = np.concatenate([[0], np.cumsum(sizes)])
    idx = np.arange(sub[-1]) + np.repeat(off[two] - sub[:-1], sizes)
    keep = open_fit_points(P[idx], sub, _FIT_TOL) if len(two) else np.zeros(0, dtype=bool)
    counts = np.add.reduceat(keep, sub[:-1]) if len(two) else np.zeros(0, dtype=np.int64)
    return idx[keep], np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)


def _gather(n_curves: int, batched: np.ndarray, F: np.ndarray, f_off: np.ndarray, made: tuple,
            one: dict) -> _SplineTables:
    """The splines made together (curves ``batched``, their fit points ``F`` by ``f_off``, and
    ``made``, the control points and knots of :func:`cubic_splines`) and those made alone
    (``one``: curve -> (degree, control, knots, fit)) in curve order."""
    control, knots = made
    order = np.union1d(batched, np.fromiter(one, dtype=np.int64, count=len(one))).astype(np.int64)
    is_spline = np.zeros(n_curves, dtype=bool)
    is_spline[order] = True
    pos = np.searchsorted(order, batched)  # where the batched splines go
    nb = np.diff(f_off)
    degree = np.full(len(order), DEGREE, dtype=np.int64)
    nf = np.zeros(len(order), dtype=np.int64)
    nf[pos] = nb
    nc, nk = nf.copy(), nf + DEGREE + 1
    for i, (deg, c, k, fit) in one.items():
        j = int(np.searchsorted(order, i))
        degree[j], nf[j], nc[j], nk[j] = deg, len(fit), len(c), len(k)
    fit_off, ctrl_off, knot_off = (np.concatenate([[0], np.cumsum(x)]) for x in (nf, nc, nk))
    fit_all, ctrl_all = np.empty((fit_off[-1], 3)), np.empty((ctrl_off[-1], 3))
    knot_all = np.empty(knot_off[-1])
    src = np.arange(f_off[-1])
    fit_all[src + np.repeat(fit_off[pos] - f_off[:-1], nb)] = F
    ctrl_all[src + np.repeat(ctrl_off[pos] - f_off[:-1], nb)] = control
    k_src = np.arange(len(knots))
    knot_all[k_src + np.repeat(knot_off[pos] - f_off[:-1] - (DEGREE + 1) * np.arange(len(nb)), nb + DEGREE + 1)] = knots
    for i, (_, c, k, fit) in one.items():
        j = int(np.searchsorted(order, i))
        fit_all[fit_off[j]:fit_off[j + 1]] = fit
        ctrl_all[ctrl_off[j]:ctrl_off[j + 1]] = np.asarray(c, dtype=float).reshape(len(c), -1)
        knot_all[knot_off[j]:knot_off[j + 1]] = k
    return _SplineTables(is_spline, degree, fit_all, fit_off, ctrl_all, ctrl_off, knot_all, knot_off)


#: The tags between a spline's numbers (:func:`_spline_texts`): after each knot, within and
#: between the rows of its control points and of its fit points.
_KNOT_GLUE = ["\n 40\n"]
_CONTROL_GLUE = ["\n 20\n", "\n 30\n", "\n 10\n"]
_FIT_GLUE = ["\n 21\n", "\n 31\n", "\n 11\n"]

#: The tags after a spline's last knot, after its last control point and after its last fit point.
_AFTER_KNOTS, _AFTER_CONTROL, _AFTER_FIT = b"\n 10\n", b"\n 11\n", b"\n"


def _spline_texts(sp: _SplineTables) -> list[tuple]:
    """The tags of each spline from its first knot's value to the line end after its last fit
    point's z: knots, control points, fit points, each table in one bulk call
    (:func:`curvenet.io.numbers.table_groups`, views into the texts of chunks of splines) and
    the tags between them, in pieces to be joined."""
    if not len(sp.degree):
        return []
    knots = table_groups(sp.knots.reshape(-1, 1), _KNOT_GLUE, groups=sp.knot_off, views=True)
    control = table_groups(sp.control, _CONTROL_GLUE, groups=sp.ctrl_off, views=True)
    fit = table_groups(sp.fit, _FIT_GLUE, groups=sp.fit_off, views=True)
    return [(k, _AFTER_KNOTS, c, _AFTER_CONTROL, f, _AFTER_FIT) for k, c, f in zip(knots, control, fit)]


#: Fit points closer than this fraction of their curve's extent to the one before are dropped.
_FIT_TOL = 1e-9

#: A loop needs this many fit points (its first repeated last) for a periodic cubic spline.
_MIN_LOOP = 5


def _fit_points(pts: np.ndarray, closed: bool) -> np.ndarray:
    """(k, 3) spline fit points: no (nearly) repeated consecutive points, which break the
    interpolation; a closed curve ends where it starts."""
    tol = _FIT_TOL * max(float(np.ptp(pts, axis=0).max()), 1e-300)
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
