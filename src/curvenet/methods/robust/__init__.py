"""The robust, parameter-free default method: see :mod:`.pipeline` for the stages in order."""

from .params import Estimates
from .frames import dedup_applies, dedup_radius, median_noise, median_spacing
from .pipeline import (PointEstimates, Prepared, estimate, local_spacing, point_estimates, prepare, reconstruct_robust,
                       shell_group_counts)

__all__ = ["reconstruct_robust", "estimate", "Estimates", "local_spacing", "shell_group_counts", "PointEstimates",
           "Prepared", "prepare", "point_estimates", "median_spacing", "median_noise", "dedup_radius", "dedup_applies"]
