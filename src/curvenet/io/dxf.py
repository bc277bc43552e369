"""DXF writer (extra ``io``, ezdxf): curves as 3D polylines or splines (fitted curves), nodes as points."""

from __future__ import annotations

import io

import numpy as np

from ..errors import InputError, require
from ..lengths import step_lengths
from ..network import CurveNetwork
from ..style import curve_colors

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


def network_to_dxf(net: CurveNetwork, *, splines: bool | None = None, units: str | None = None) -> str:
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
    str
        The DXF text. Curves with fewer than 2 points are left out; a curve with fewer than 3
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
    msp = doc.modelspace()
    colors = curve_colors(net)
    for i, c in enumerate(net.curves):
        pts = np.array([_xyz(p) for p in c.points]).reshape(-1, 3)
        if len(pts) < 2:
            continue
        attribs = {"layer": CURVE_LAYER}
        fit = _fit_points(pts, c.closed) if splines else pts[:0]
        if len(fit) >= (_MIN_LOOP if c.closed else 3):
            degree, control, knots = _interpolating_bspline(fit, c.closed)
            e = msp.add_spline(dxfattribs={**attribs, "degree": degree})
            e.control_points = control.tolist()
            e.knots = knots.tolist()
            e.fit_points = fit.tolist()
            if c.closed:
                e.closed = True
        else:
            e = msp.add_polyline3d(pts.tolist(), close=bool(c.closed), dxfattribs=attribs)
        e.rgb = _rgb(colors[i])
    for p in net.nodes:
        msp.add_point(_xyz(p), dxfattribs={"layer": NODE_LAYER})
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue()


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


def _xyz(p) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]) if len(p) > 2 else 0.0)


def _rgb(hexcolor: str) -> tuple[int, int, int]:
    h = hexcolor.lstrip("#")
    return (int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16))
