"""Every ground-truth model by name: the original models and the analogues of real failure kinds."""

from __future__ import annotations

from ..errors import InputError
from ..network import CurveNetwork
from .kinds import KIND_MODELS
from .models import MODELS

__all__ = ["model"]


def model(name: str) -> CurveNetwork:
    """Build a ground-truth model by name.

    Parameters
    ----------
    name : str
        A key of :data:`curvenet.synth.MODELS` or of :data:`curvenet.synth.KIND_MODELS` (the
        analogues of real failure kinds).

    Returns
    -------
    CurveNetwork
        The true network: nodes (junctions and free ends) and densely sampled true curves;
        ``parameters["h"]`` is the model's reference sampling spacing.

    Raises
    ------
    InputError
        For an unknown name.
    """
    if name in MODELS:
        return MODELS[name]()
    if name in KIND_MODELS:
        return KIND_MODELS[name]()
    raise InputError(f"unknown model {name!r}; expected one of: {', '.join([*MODELS, *KIND_MODELS])}")
