"""The robust, parameter-free default method: see :mod:`.pipeline` for the stages in order."""

from .params import Estimates
from .pipeline import estimate, local_spacing, reconstruct_robust, shell_group_counts

__all__ = ["reconstruct_robust", "estimate", "Estimates", "local_spacing", "shell_group_counts"]
