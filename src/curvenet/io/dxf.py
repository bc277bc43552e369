"""DXF writer (extra ``io``, ezdxf): curves as 3D polylines or splines, nodes as points."""

from __future__ import annotations

import io

from ..errors import InputError, require
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


def network_to_dxf(net: CurveNetwork, *, smooth: bool | None = None, units: str | None = None) -> str:
    """The network as an ASCII DXF drawing (AutoCAD R2010).

    Each curve is one entity on layer ``CURVES``: a 3D ``POLYLINE`` through its points (closed
    for a loop), or with ``smooth`` a ``SPLINE`` whose fit points are the curve's points. Each
    node is a ``POINT`` on layer ``NODES``. Curves get the colours of the PNG pictures (true
    colour); 2D networks are written with z = 0.

    Parameters
    ----------
    net : CurveNetwork
    smooth : bool, optional
        Write splines instead of polylines. By default, splines when the network was made with
        the ``smooth`` parameter set (``net.parameters["smooth"]``).
    units : str, optional
        The unit of the coordinates, a key of :data:`DXF_UNITS` (``"mm"``, ``"m"``, ``"in"``...),
        written as ``$INSUNITS``. By default the drawing is unitless (``$INSUNITS`` 0): the
        points carry no unit, so a CAD program neither scales them nor claims metres.

    Returns
    -------
    str
        The DXF text. Curves with fewer than 2 points are left out; a curve with fewer than 3
        distinct points stays a polyline when ``smooth`` is on.
    """
    ezdxf = require("ezdxf", "writing DXF files", "io")

    unit = "unitless" if units is None else str(units).strip().lower()
    if unit not in DXF_UNITS:
        raise InputError(f"unknown DXF units {units!r}; expected one of: {', '.join(DXF_UNITS)}")
    if smooth is None:
        smooth = bool(net.parameters.get("smooth", False))
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = DXF_UNITS[unit]
    if unit != "unitless":
        doc.header["$MEASUREMENT"] = int(unit in _METRIC)
    doc.layers.add(CURVE_LAYER, color=5)
    doc.layers.add(NODE_LAYER, color=1)
    msp = doc.modelspace()
    colors = curve_colors(net)
    for i, c in enumerate(net.curves):
        pts = [_xyz(p) for p in c.points]
        if len(pts) < 2:
            continue
        attribs = {"layer": CURVE_LAYER}
        fit = _fit_points(pts, c.closed) if smooth else []
        if len(fit) >= 3:
            e = msp.add_spline(fit_points=fit, dxfattribs=attribs)
            if c.closed:
                e.closed = True
        else:
            e = msp.add_polyline3d(pts, close=bool(c.closed), dxfattribs=attribs)
        e.rgb = _rgb(colors[i])
    for p in net.nodes:
        msp.add_point(_xyz(p), dxfattribs={"layer": NODE_LAYER})
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue()


def _fit_points(pts, closed: bool) -> list:
    """Spline fit points: no (nearly) repeated consecutive points, which break the interpolation;
    a closed curve ends where it starts."""
    import numpy as np

    a = np.asarray(pts, dtype=float)
    tol = 1e-9 * max(float(np.ptp(a, axis=0).max()), 1e-300)
    fit = [pts[0]]
    for q in pts[1:]:
        if np.linalg.norm(np.asarray(q) - np.asarray(fit[-1])) > tol:
            fit.append(q)
    if closed and len(fit) > 2:
        if np.linalg.norm(np.asarray(fit[-1]) - np.asarray(fit[0])) <= tol:
            fit[-1] = fit[0]
        else:
            fit.append(fit[0])
    return fit


def _xyz(p) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]) if len(p) > 2 else 0.0)


def _rgb(hexcolor: str) -> tuple[int, int, int]:
    h = hexcolor.lstrip("#")
    return (int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16))
