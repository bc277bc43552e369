"""Every fixed constant of the robust method, as documented fields grouped by stage.

Each group is a :class:`typing.NamedTuple` with a default per field and one module-level
instance (``STRIP = Strip()``). The compiled kernels receive their groups as arguments (numba
types a named tuple like any tuple), so a changed value reaches the compiled and the plain-Python
kernels alike, and numba's disk cache never serves a kernel built with an older value. Lengths
are in local spacings ``h`` (see :func:`~curvenet.methods.robust.kernels.spacing`) unless a field
says otherwise; ``sigma`` is the estimated noise (a length).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "Linalg", "LINALG", "Spacing", "SPACING", "Strip", "STRIP", "Noisy", "NOISY", "Vote", "VOTE",
    "Strand", "STRAND", "Shell", "SHELL", "Chains", "CHAINS", "Untangle", "UNTANGLE", "Ends", "ENDS",
    "Nodes", "NODES",
]


# kernels


class Linalg(NamedTuple):
    """Small dense solvers of the kernels (``kernels/linalg.py``): eigenpairs of (d, d)
    scatter matrices by Jacobi sweeps or in closed form, weighted PCA."""

    #: most cyclic Jacobi sweeps (a 3 x 3 matrix converges in about 5; a safety bound)
    jacobi_sweeps: int = 60
    #: Jacobi stops when the off-diagonal sum is below this fraction of the diagonal sum
    #: (unitless; about 1e-14 of double precision's range squared: fully converged)
    jacobi_tol: float = 1e-30
    #: a rotation angle ratio ``theta`` above this is treated as infinite, ``t = 1 / (2 theta)``
    #: (unitless; Numerical Recipes' guard against overflow of ``theta^2``)
    theta_max: float = 1e150
    #: the closed-form top eigenpair leaves a top eigenvalue closer than this (relative to the
    #: size of the eigenvalues) to the next one to the Jacobi sweeps: its direction is
    #: ill-defined there (unitless; former ``TOP_GAP``)
    top_gap: float = 1e-3
    #: most Newton steps for the largest root of the 3 x 3 characteristic polynomial (it
    #: decreases monotonically from an upper bound; a handful suffice, a safety bound)
    newton_steps: int = 100
    #: floor of a divisor that may vanish (a sum of weights, a top eigenvalue, a length): any
    #: positive double far below the data's scale (unitless)
    tiny: float = 1e-300


LINALG = Linalg()


class Spacing(NamedTuple):
    """Local spacing of every point (``kernels/frames.py``; the numpy formula it reproduces is
    ``robust.local_spacing``)."""

    #: nearest neighbours whose mean distance is the raw spacing (points)
    n_mean: int = 4
    #: divisor of that mean: the mean distance to the 4 nearest samples of a curve sampled
    #: every ``h`` is ``1.5 h`` (unitless)
    mean_div: float = 1.5
    #: neighbours whose raw spacings, with the point's own, give the median (points)
    n_median: int = 8
    #: accumulators of numpy's pairwise summation of a row, summed as a binary tree (a power
    #: of two: numpy's unrolling, reproduced so the sums are the same bits; a property of numpy,
    #: not a tuning)
    numpy_lanes: int = 8


SPACING = Spacing()


class Strip(NamedTuple):
    """Tangents of clean input (``kernels/frames.py``, :func:`_tangents`)."""

    #: half-width scale of the strip that scores a direction: the Gaussian weight is
    #: ``exp(-(r / (w h))^2)`` (spacings; former ``STRIP_W``)
    w: float = 0.5
    #: reach along the line of that strip (spacings; former ``STRIP_A``)
    a: float = 3.0
    #: score a neighbour's direction needs above the 4-neighbour direction's to replace it
    #: (points of strip score; former ``CAND_MARGIN``)
    cand_margin: float = 2.0
    #: the neighbours' directions are tried only where the first PCA's linearity is below this
    #: (unitless; former ``CAND_LIN``)
    cand_lin: float = 0.8
    #: nearest neighbours of the first PCA, whose directions are the candidates (points)
    n_first: int = 4
    #: weighted PCA refinements of the direction (each reweights the points within ``h`` of
    #: the current line)
    refine: int = 2
    #: points per parallel block (one set of scratch arrays each; results never depend on it)
    rows: int = 2048


STRIP = Strip()


class Noisy(NamedTuple):
    """Tangents of noisy input (``kernels/frames.py``, :func:`_noisy_tangents`)."""

    #: directions to this many nearest neighbours are scored (points; former ``NOISY_CAND``)
    cand: int = 16
    #: reach of the strip along the line, plus ``reach_sig`` sigma (spacings; former
    #: ``NOISY_A``)
    a: float = 5.0
    #: noise part of that reach (sigmas)
    reach_sig: float = 2.0
    #: strip width: ``max(wh h, wf sigma)`` (sigmas; former ``NOISY_WF``)
    wf: float = 2.0
    #: (spacings; former ``NOISY_WH``)
    wh: float = 0.5
    #: Gaussian weights are cut at this many strip widths (unitless; former ``NOISY_CUT``)
    cut: float = 3.0
    #: the refining PCA takes the points within ``max(h, rw sigma)`` of the line (sigmas;
    #: former ``NOISY_RW``)
    rw: float = 2.5
    #: a candidate direction within this cosine (10 degrees) of one already scored is not
    #: scored again: the refinement, whose strip is at least a spacing wide over 5 spacings,
    #: starts from the same points (cosine; former ``NOISY_SAME``)
    same: float = float(np.cos(np.radians(10.0)))
    #: weighted PCA refinements of the best direction
    refine: int = 2
    #: rows per parallel block (one set of scratch arrays each; results never depend on it;
    #: former ``NOISY_ROWS``)
    rows: int = 256


NOISY = Noisy()


class Vote(NamedTuple):
    """Tangent vote (``kernels/frames.py``, :func:`_vote_eig`)."""

    #: candidate points per parallel block (results never depend on it)
    rows: int = 1024


VOTE = Vote()


class Strand(NamedTuple):
    """The test that cuts links between two close parallel strands of a noisy cloud
    (``kernels/graph.py``, :func:`_strand_cuts`; former ``STRAND_*``)."""

    #: only links between tangents within 20 degrees are tested (cosine)
    cos: float = float(np.cos(np.radians(20.0)))
    #: the far end must lie more than ``max(t0 sigma, dmin h / 2)`` from the tangent line
    #: (sigmas)
    t0: float = 2.0
    #: window: neighbours within ``a h`` along the tangent (spacings)
    a: float = 4.0
    #: mean-shift kernel width ``max(b sigma, bh h)`` (sigmas)
    b: float = 1.5
    #: (spacings)
    bh: float = 0.35
    #: the two modes must lie more than ``max(thr sigma, dmin h)`` apart (sigmas)
    thr: float = 3.0
    #: (spacings)
    dmin: float = 1.5
    #: points each mode needs (points)
    nmin: int = 3
    #: on both sides of the link, beyond ``side h`` along it (spacings)
    side: float = 0.5
    #: the points of a mode must run within 15 degrees of the tangent (cosine)
    lcos: float = float(np.cos(np.radians(15.0)))
    #: most mean-shift steps
    steps: int = 30
    #: mean shift stops when a step moves less than this fraction of the kernel width, squared
    #: (unitless)
    shift_tol: float = 1e-12
    #: a point belongs to a mode within this many kernel widths (unitless)
    member: float = 1.5
    #: links per parallel block (one set of scratch arrays each; results never depend on it;
    #: former ``STRAND_ROWS``)
    rows: int = 1024


STRAND = Strand()


class Shell(NamedTuple):
    """The geodesic shell test (``kernels/shell.py``, :func:`_shell_groups`)."""

    #: the Dijkstra keeps up to this many frontier points in a list scanned for the nearest
    #: (cheaper than a heap for the few on a curve), more in a heap (points; results never
    #: depend on it; former ``FRONT_MAX``)
    front_max: int = 32


SHELL = Shell()


class Chains(NamedTuple):
    """Chain order and chain ends (``kernels/chains.py``)."""

    #: floor of an edge length in the chains' Dijkstra (length; coincident points still get an
    #: order)
    min_edge: float = 1e-12
    #: an end of a chain reads its contacts within ``min(L / 2, end_reach h)`` of it
    #: (spacings)
    end_reach: float = 4.0


CHAINS = Chains()


class Untangle(NamedTuple):
    """Windowed 2-opt of a curve's points (``kernels/chains.py``, :func:`_untangle`)."""

    #: most sweeps per curve
    sweeps: int = 50
    #: a reversal is made when it shortens the polyline by more than this fraction of the
    #: step it replaces (unitless; rounding guard)
    min_gain: float = 1e-9
    #: curves with fewer points are left as they are (points: a reversal needs two inner ones)
    min_points: int = 4


UNTANGLE = Untangle()


class Ends(NamedTuple):
    """End portions of chains and branches (``kernels/nodes.py``; as ``robust._end_portion``)."""

    #: an end portion holds at least ``min(min_points, n)`` points (points)
    min_points: int = 3
    #: the walk into a junction region aims along the end portion over this arc length
    #: (spacings)
    walk_span: float = 3.0
    #: chains with fewer points are not trimmed behind their nodes (points)
    trim_min: int = 4


ENDS = Ends()


class Nodes(NamedTuple):
    """Junction node placement (``kernels/nodes.py``, :func:`_junction_nodes`); the method's
    settings of it arrive in a :class:`~curvenet.methods.robust.kernels.JunctionParams`."""

    #: the walk into a region takes a point only ahead of the branch end by more than this
    #: (spacings)
    ahead: float = 0.25
    #: weight of the pull of the node towards the mean of the branch ends in the least
    #: squares (unitless; small: it only makes near-parallel lines well-posed)
    anchor_pull: float = 1e-2
    #: relative slack of the hidden-branch tests' comparisons (rounding guard; the exact test
    #: is ``robust._swallowed_branches``)
    swallow_tol: float = 1e-9
    #: a branch can hide in a region of at least this many points (points)
    swallow_min: int = 3


NODES = Nodes()
