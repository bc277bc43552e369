"""`reconstruct`: the one entry point that runs a reconstruction method on points."""

from __future__ import annotations

import contextlib
import importlib
import inspect
import time
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike

from .errors import InputError
from .network import CurveNetwork
from .validate import reconstructable, unit_frame

__all__ = ["reconstruct", "compile_pending", "METHODS", "DEFAULT_METHOD", "LENGTH_PARAMETERS", "LENGTH_RESULTS"]

#: Method name -> (module, function). Each function takes ``(points, **params)`` with points a
#: checked (N, d) float array and returns a :class:`CurveNetwork`.
METHODS: dict[str, tuple[str, str]] = {
    "paper": ("curvenet.methods.paper", "reconstruct_paper"),
    "emst": ("curvenet.methods.emst", "reconstruct_emst"),
    "robust": ("curvenet.methods.robust", "reconstruct_robust"),
}

#: The method used when none is named.
DEFAULT_METHOD = "robust"

#: Method name -> its parameters that are lengths in the units of the points: a given value is
#: brought into the internal frame of the points (see :func:`curvenet.validate.unit_frame`).
LENGTH_PARAMETERS: dict[str, tuple[str, ...]] = {
    "paper": ("tau_s",),
    "emst": (),
    "robust": ("spacing",),
}

#: Method name -> the entries of ``network.parameters`` and ``network.stats`` that are lengths
#: (numbers or lists of numbers): brought back from the internal frame to the units of the points.
LENGTH_RESULTS: dict[str, tuple[str, ...]] = {
    "paper": ("tau_s", "h"),
    "emst": (),
    "robust": ("spacing", "spacing_range", "noise"),
}


def reconstruct(
    points: ArrayLike,
    *,
    method: str = "auto",
    on_stage: Callable[[str, float], None] | None = None,
    **params: Any,
) -> CurveNetwork:
    """Reconstruct a curve network from unorganized points.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
        Points sampled along curves, in any order.
    method : str
        ``"auto"`` (the default method), or a name from :data:`METHODS`: ``"paper"`` is the
        method of the founding paper (Algorithms 1 and 2).
    on_stage : callable, optional
        ``on_stage(name, share)``, called as each stage of the method begins, with the stage's
        name and its share (0 to 1) of the method's work (the shares of
        :mod:`curvenet.methods.stages`, measured); for a progress display. The ``robust`` and
        ``paper`` methods report their stages; ``emst`` does not call it.
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
        For invalid points (among them points whose extent float64 cannot resolve, see
        :func:`curvenet.validate.unit_frame`), an unknown method or an unknown parameter.

    Notes
    -----
    The result does not depend on the units of the points: points whose extent lies outside
    :data:`curvenet.validate.UNSCALED_EXTENTS` (about 5e-20 to 2e19) are scaled by a power of
    two that brings it into [0.5, 1) (exact in float64), and points far from the origin for
    their extent (:data:`curvenet.validate.TRANSLATE_RATIO`) are translated to the centre of
    their bounding box. Given lengths (:data:`LENGTH_PARAMETERS`) are scaled in, the network
    and the reported lengths (:data:`LENGTH_RESULTS`) scaled back; without a translation both
    ways are exact. So the points at 1e-200 or 1e200 give the network of the points at 1, up
    to the last bits of coordinates (and exactly that of the points at ``2**-k``).
    """
    name = DEFAULT_METHOD if method == "auto" else method
    if name not in METHODS:
        raise InputError(f"unknown method {method!r}; expected one of: auto, {', '.join(sorted(METHODS))}")
    pts = reconstructable(points)
    module, func = METHODS[name]
    fn = getattr(importlib.import_module(module), func)
    _check_params(name, fn, params)
    shift, k = unit_frame(pts)
    inner = pts if shift is None and k == 0 else np.ldexp(pts if shift is None else pts - shift, k)
    for key in LENGTH_PARAMETERS.get(name, ()):
        if key in params:
            params[key] = _scaled(params[key], k)
    if on_stage is not None and "on_stage" in inspect.signature(fn).parameters:
        params = {**params, "on_stage": on_stage}
    hook = contextlib.nullcontext()
    if name == "robust":  # a first run: its kernels compiled on all cores at once (warmup)
        from .methods.robust.kernels.registry import first_use_hook
        from .methods.robust.warmup import COMMON, on_first_use, precompile

        if compile_pending(len(pts), method=name):
            precompile(names=COMMON)
        hook = first_use_hook(on_first_use)  # (the kernels of noisy input: when first needed)
    t0 = time.perf_counter()
    with hook:
        net = fn(inner, **params)
    _back_to_units(net, name, shift, k)
    net.parameters.setdefault("method", name)
    net.parameters["method"] = name
    stats = net.stats
    stats["N_n"] = net.n_nodes
    stats["N_c"] = net.n_curves
    stats["N_d"] = int(len(pts))
    stats.setdefault("time", {})
    stats["time"]["total"] = time.perf_counter() - t0
    return net


def compile_pending(n_points: int, *, method: str = "auto") -> bool:
    """Whether a run of ``method`` on ``n_points`` points will first compile numba kernels.

    numba compiles a method's kernels on their first use and keeps them in its disk cache
    (beside the package, or in ``NUMBA_CACHE_DIR``): that happens once, then runs load them.
    Only the ``robust`` method decides this ahead (see
    :func:`curvenet.methods.robust.kernels.registry.compile_pending`); the others answer False.

    Parameters
    ----------
    n_points : int
        Points of the run (small inputs run plain-Python kernels, compiling nothing).
    method : str
        ``"auto"`` or a name from :data:`METHODS`.

    Returns
    -------
    bool
    """
    name = DEFAULT_METHOD if method == "auto" else method
    if name != "robust":
        return False
    from .methods.robust.kernels.registry import compile_pending as _pending

    return _pending(n_points)


def _check_params(name: str, fn: Callable[..., CurveNetwork], params: dict[str, Any]) -> None:
    """Raise InputError for a parameter the method does not take, or a value of another type
    than its annotation says (a number for ``int`` and ``float``, true or false for ``bool``)."""
    sig = inspect.signature(fn)
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        return
    known = [p for p in list(sig.parameters)[1:] if p != "on_stage"]  # (reconstruct's own keyword)
    for key, value in params.items():
        if key not in known:
            raise InputError(
                f"method {name!r} has no parameter {key!r}; its parameters: {', '.join(known) or 'none'}"
            )
        expected = _expected_type(sig.parameters[key])
        if expected and not _has_type(value, expected):
            raise InputError(f"parameter {key!r} of method {name!r} must be {expected}, got {value!r}")


#: Annotation word -> what a value must be, in words (the first word found decides).
_TYPE_WORDS = (("float", "a number"), ("int", "an integer"), ("bool", "true or false"))


def _expected_type(param: inspect.Parameter) -> str | None:
    """What a value of ``param`` must be, from its annotation, or None (anything)."""
    ann = param.annotation
    text = ann if isinstance(ann, str) else getattr(ann, "__name__", str(ann))
    words = set(text.replace("|", " ").replace(",", " ").replace("[", " ").replace("]", " ").split())
    for word, what in _TYPE_WORDS:
        if word in words:
            return what + (" or none" if "None" in words or param.default is None else "")
    return None


def _has_type(value: Any, expected: str) -> bool:
    if value is None:
        return expected.endswith(" or none")
    if expected.startswith("true or false"):
        return isinstance(value, (bool, np.bool_))
    if isinstance(value, (bool, np.bool_)):
        return False
    if expected.startswith("an integer"):
        return isinstance(value, (int, np.integer)) or (isinstance(value, (float, np.floating)) and float(value).is_integer())
    return isinstance(value, (int, float, np.integer, np.floating))


def _scaled(value: Any, k: int) -> Any:
    """``value * 2**k`` for a number or a list of numbers (exact); anything else unchanged."""
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, (int, float, np.floating, np.integer)):
        v = float(value)
        return float(np.ldexp(v, k)) if np.isfinite(v) else v
    if isinstance(value, (list, tuple)):
        return type(value)(_scaled(v, k) for v in value)
    return value


def _back_to_units(net: CurveNetwork, name: str, shift: np.ndarray | None, k: int) -> None:
    """Bring the network ``net`` computed in the internal frame ``(shift, k)`` back to the units
    of the points, in place: coordinates times ``2**-k`` plus ``shift``, and the length entries
    of :data:`LENGTH_RESULTS`."""
    if shift is None and k == 0:
        return

    def back(a: Any) -> np.ndarray:
        a = np.ldexp(np.asarray(a, dtype=np.float64), -k)
        return a if shift is None else a + shift

    net.nodes = back(net.nodes).reshape(np.shape(net.nodes))
    for c in net.curves:
        c.points = back(c.points).reshape(np.shape(c.points))
    for key in LENGTH_RESULTS.get(name, ()):
        for table in (net.parameters, net.stats):
            if key in table:
                table[key] = _scaled(table[key], -k)
