"""`reconstruct`: the one entry point that runs a reconstruction method on points."""

from __future__ import annotations

import importlib
import inspect
import time
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike

from .errors import InputError
from .network import CurveNetwork
from .validate import as_points

__all__ = ["reconstruct", "METHODS", "DEFAULT_METHOD"]

#: Method name -> (module, function). Each function takes ``(points, **params)`` with points a
#: checked (N, d) float array and returns a :class:`CurveNetwork`.
METHODS: dict[str, tuple[str, str]] = {
    "paper": ("curvenet.methods.paper", "reconstruct_paper"),
    "emst": ("curvenet.methods.emst", "reconstruct_emst"),
    "robust": ("curvenet.methods.robust", "reconstruct_robust"),
}

#: The method used when none is named.
DEFAULT_METHOD = "robust"


def reconstruct(points: ArrayLike, *, method: str = "auto", **params: Any) -> CurveNetwork:
    """Reconstruct a curve network from unorganized points.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
        Points sampled along curves, in any order.
    method : str
        ``"auto"`` (the default method), or a name from :data:`METHODS`: ``"paper"`` is the
        method of the founding paper (Algorithms 1 and 2).
    **params
        Parameters of the method (see its documentation); unknown names raise InputError.

    Returns
    -------
    CurveNetwork
        The network; ``network.parameters`` holds every parameter used and
        ``network.stats["time"]`` the seconds spent per stage.

    Raises
    ------
    InputError
        For invalid points, an unknown method or an unknown parameter.
    """
    name = DEFAULT_METHOD if method == "auto" else method
    if name not in METHODS:
        raise InputError(f"unknown method {method!r}; expected one of: auto, {', '.join(sorted(METHODS))}")
    pts = as_points(points, min_points=3)
    if not np.ptp(pts, axis=0).any():
        raise InputError(f"all {len(pts)} points are identical; nothing to reconstruct")
    module, func = METHODS[name]
    fn = getattr(importlib.import_module(module), func)
    _check_params(name, fn, params)
    t0 = time.perf_counter()
    net = fn(pts, **params)
    net.parameters.setdefault("method", name)
    net.parameters["method"] = name
    stats = net.stats
    stats["N_n"] = net.n_nodes
    stats["N_c"] = net.n_curves
    stats["N_d"] = int(len(pts))
    stats.setdefault("time", {})
    stats["time"]["total"] = time.perf_counter() - t0
    return net


def _check_params(name: str, fn: Callable[..., CurveNetwork], params: dict[str, Any]) -> None:
    """Raise InputError for a parameter the method does not take."""
    sig = inspect.signature(fn)
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        return
    known = [p for p in list(sig.parameters)[1:]]
    for key in params:
        if key not in known:
            raise InputError(
                f"method {name!r} has no parameter {key!r}; its parameters: {', '.join(known) or 'none'}"
            )
