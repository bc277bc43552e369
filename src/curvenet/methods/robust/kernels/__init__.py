"""The sequential per-point loops of the robust method, compiled with numba when it is installed.

Each kernel is plain Python written in the subset numba compiles, in a module per topic:
:mod:`.linalg` (eigenpairs, PCA, small solves), :mod:`.heap`, :mod:`.frames` (spacing, tangents,
votes, noisy tangents), :mod:`.graph` (linked edges, short links, CSR union, components, strand
cuts), :mod:`.shell` (the shell test), :mod:`.chains` (chain order and ends, untangling) and
:mod:`.nodes` (end portions, junction nodes, trimmed ends). :mod:`.registry` holds the plain and
the compiled version of each side by side and runs one or the other (same results); the
functions below are its dispatch. The kernels' fixed constants are the groups of
:mod:`curvenet.methods.robust.thresholds`.
"""

from __future__ import annotations

import numpy as np

from ..thresholds import NOISY, STRIP
from .frames import noisy_reach
from .nodes import JunctionParams
from .registry import (
    HAVE_NUMBA, NUMBA_MIN_POINTS_NOISY, STRAND_KERNELS, chain_ends, chain_order,
    compiled_active, compiled_for, components, csr_union, end_count, end_counts, envelope_solve, junction_nodes,
    linked_edges, noisy_tangents, shell_groups, short_links, spacing, strand_cuts, tangents, trim_ends,
    untangle, vote_agreement, vote_eig,
)

#: dtype of the neighbour ids handed to the kernels (the (N, k) kNN ids are the method's largest
#: array: int32 halves them; a cloud holds fewer than 2**31 points, see ``MAX_SHELL_POINTS``)
INDEX = np.int32

#: score a neighbour's direction needs above the 4-neighbour direction's to replace it (the
#: tangents' default margin; ``STRIP.cand_margin``)
CAND_MARGIN = STRIP.cand_margin
#: directions to this many nearest neighbours are scored by the noisy tangents (``NOISY.cand``)
NOISY_CAND = NOISY.cand

__all__ = [
    "CAND_MARGIN", "INDEX", "NOISY_CAND", "NUMBA_MIN_POINTS_NOISY", "STRAND_KERNELS",
    "HAVE_NUMBA", "JunctionParams", "chain_ends", "chain_order", "compiled_active", "compiled_for",
    "components", "csr_union", "end_count", "end_counts", "envelope_solve", "junction_nodes", "linked_edges",
    "noisy_reach", "noisy_tangents", "shell_groups", "short_links", "spacing", "strand_cuts",
    "tangents", "trim_ends", "untangle", "vote_agreement", "vote_eig",
]
