"""Ground truth for benchmarks: parametric curve networks (the original models and analogues of
real failure kinds), a sampler, the CASSIE sketches, the real-dev networks and networks drawn on known
surfaces (:mod:`curvenet.synth.surfaces`, ground truth for surfacing); families of real-like
networks drawn at random (:mod:`curvenet.synth.families`).

>>> from curvenet import synth
>>> truth = synth.model("cube")
>>> points, labels = synth.sample(truth, noise=0.2, rng=1)
"""

from . import cassie, families, realdev, surfaces
from .catalog import model
from .kinds import KIND_MODELS
from .models import MODELS, fork, h_of, model_names
from .sampler import sample

__all__ = ["cassie", "families", "realdev", "surfaces", "MODELS", "KIND_MODELS", "model", "model_names", "h_of", "fork", "sample"]
