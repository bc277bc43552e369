"""Ground truth for benchmarks: parametric curve networks, a sampler and the CASSIE sketches.

>>> from curvenet import synth
>>> truth = synth.model("cube")
>>> points, labels = synth.sample(truth, noise=0.2, rng=1)
"""

from . import cassie
from .models import MODELS, fork, h_of, model, model_names
from .sampler import sample

__all__ = ["cassie", "MODELS", "model", "model_names", "h_of", "fork", "sample"]
