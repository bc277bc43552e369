"""The robust, parameter-free default method: see :mod:`.pipeline` for the stages in order."""

from .pipeline import local_spacing, reconstruct_robust, shell_group_counts

__all__ = ["reconstruct_robust", "local_spacing", "shell_group_counts"]
