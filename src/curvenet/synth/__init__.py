"""Ground truth for benchmarks: parametric curve networks (the original models and analogues of
real failure kinds), a sampler, the CASSIE sketches and the real-dev networks.

>>> from curvenet import synth
>>> truth = synth.model("cube")
>>> points, labels = synth.sample(truth, noise=0.2, rng=1)
"""

from . import cassie, realdev
from .catalog import model
from .kinds import KIND_MODELS
from .models import MODELS, fork, h_of, model_names
from .sampler import sample

__all__ = ["cassie", "realdev", "MODELS", "KIND_MODELS", "model", "model_names", "h_of", "fork", "sample"]
