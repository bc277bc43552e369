"""The user's keywords (:class:`RobustParams`) and the scales estimated once per input (:class:`Scales`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from ...errors import InputError
from .thresholds import DEFAULTS, NOISE, SPACING

__all__ = ["RobustParams", "Scales", "Estimates"]

_POSITIVE = ("k", "shell_inner", "shell_outer", "link", "link_width", "min_spur")


@dataclass(frozen=True)
class RobustParams:
    """The robust method's keywords, validated once (every radius in local spacings h).

    Parameters
    ----------
    spacing : float or None
        Sampling spacing h used everywhere; None: estimated per point.
    k : int
        Neighbours per point for the linked graph.
    shell_inner, shell_outer : float
        Radii of the junction-test shell.
    link : float
        Longest link between two points.
    link_width : float
        A link's far end lies within this many spacings of the tangent line through one end.
    min_spur : float
        Spurs and isolated pieces shorter than this are dropped.
    fit : bool or None
        Fit each curve by a smoothing spline, ends held at its nodes (each sample moved onto
        it); None: where noise is detected.
    smoothing : float or None
        Width of the fit's smoothing kernel, in spacings (None: the default of the method).
    """

    spacing: float | None = None
    k: int = DEFAULTS.k
    shell_inner: float = DEFAULTS.shell_inner
    shell_outer: float = DEFAULTS.shell_outer
    link: float = DEFAULTS.link
    link_width: float = DEFAULTS.link_width
    min_spur: float = DEFAULTS.min_spur
    fit: bool | None = None
    smoothing: float | None = None

    @classmethod
    def from_keywords(cls, *, spacing: float | None = None, k: int | None = None, shell_inner: float | None = None,
                      shell_outer: float | None = None, link: float | None = None, link_width: float | None = None,
                      min_spur: float | None = None, fit: bool | None = None,
                      smoothing: float | None = None) -> "RobustParams":
        """Validate the keywords of :func:`~.pipeline.reconstruct_robust` (None: the default).

        Raises
        ------
        InputError
            A radius or count that is not a positive finite number, ``k`` under 4, the outer
            shell not larger than the inner one, a bad spacing or smoothing width, a ``fit``
            that is not a bool or None.
        """
        given = {"k": k, "shell_inner": shell_inner, "shell_outer": shell_outer, "link": link,
                 "link_width": link_width, "min_spur": min_spur}
        vals: dict[str, Any] = {}
        for name in _POSITIVE:
            val = given[name]
            if val is None:
                continue
            if not np.isfinite(val) or val <= 0:
                raise InputError(f"{name} must be a positive number, got {val!r}")
            vals[name] = val
        vals["k"] = int(vals.get("k", DEFAULTS.k))
        if vals["k"] < DEFAULTS.k_min:
            raise InputError(f"k must be at least {DEFAULTS.k_min}, got {vals['k']}")
        inner = vals.get("shell_inner", DEFAULTS.shell_inner)
        outer = vals.get("shell_outer", DEFAULTS.shell_outer)
        if outer <= inner:
            raise InputError(f"shell_outer ({outer}) must be larger than shell_inner ({inner})")
        if spacing is not None and (not np.isfinite(spacing) or spacing <= 0):
            raise InputError(f"spacing must be a positive number, got {spacing!r}")
        if smoothing is not None and (not np.isfinite(smoothing) or smoothing < 0):
            raise InputError(f"smoothing must be a non-negative number of spacings, got {smoothing!r}")
        if fit is not None and not isinstance(fit, (bool, np.bool_)):
            raise InputError(f"fit must be true, false or none (none: where noise is detected), got {fit!r}")
        return cls(spacing=spacing, smoothing=smoothing, fit=None if fit is None else bool(fit), **vals)

    def report(self) -> dict[str, Any]:
        """The keywords as reported in the network's ``parameters`` (before the estimates)."""
        out = {name: getattr(self, name) for name in _POSITIVE}
        out["fit"] = self.fit
        return out


class Estimates(NamedTuple):
    """Whole-cloud estimates that a part of the cloud (a tile) must share with the whole.

    The method takes a few decisions from them: the noise gates (noise-free input or not: the
    tangent retry, the vote's size, the strand test, the duplicate rule), the radii's growth
    with the noise, and the joins measured in median spacings. A tile of a larger cloud run
    with the whole cloud's :class:`Estimates` decides as the whole would
    (:func:`~.pipeline.estimate` computes them; ``reconstruct_robust(points, estimates=...)``
    takes them). The local spacing of every point stays its own.

    Attributes
    ----------
    hmed : float
        Median local spacing.
    sigma : float
        Noise standard deviation per coordinate.
    """

    hmed: float
    sigma: float

    @property
    def clean(self) -> bool:
        """The cloud counts as noise-free (``sigma`` under ``SPACING.dedup_noise`` median spacings)."""
        return bool(self.sigma < SPACING.dedup_noise * self.hmed)

    @property
    def low(self) -> bool:
        """The cloud's noise is low (``sigma`` under ``NOISE.low`` median spacings): the links
        and the junction stages read it as noise-free (:data:`~.thresholds.NOISE`)."""
        return bool(self.sigma < NOISE.low * self.hmed)


@dataclass(frozen=True)
class Scales:
    """What the method estimates once per input and every later stage reads.

    Attributes
    ----------
    h : (N,) ndarray of float
        Local sampling spacing of every point.
    hmed : float
        The median spacing.
    sigma : float
        Estimated noise standard deviation per coordinate (0 on clean input).
    noise : float
        The noise scale of the radii (``NOISE.scale * sigma``).
    clean : bool
        The input is noise-free (``sigma`` under ``SPACING.dedup_noise`` median spacings).
    width : float
        The link width in spacings (``max(link_width, 0)``).
    indptr, indices : ndarray of int64, ndarray of int32
        CSR adjacency of the linked graph.
    tree : scipy.spatial.cKDTree
        The k-d tree over the points (of the k-nearest-neighbour query).
    """

    h: np.ndarray
    hmed: float
    sigma: float
    noise: float
    clean: bool
    width: float
    indptr: np.ndarray = field(repr=False)
    indices: np.ndarray = field(repr=False)
    tree: Any = field(repr=False)

    @property
    def low(self) -> bool:
        """The noise is low (``sigma`` under ``NOISE.low`` median spacings; :attr:`Estimates.low`)."""
        return Estimates(self.hmed, self.sigma).low
