"""Every fixed constant of the robust method, one documented field each, grouped by stage.

Nothing here is tuned per input: these are the method's design constants. The user's keywords
(shell radii, link length, ...) are :class:`~curvenet.methods.robust.params.RobustParams`.
Units: ``h`` is the local sampling spacing of a point, ``noise`` the noise scale
(:data:`NOISE` ``.scale`` times the estimated noise standard deviation, 0 on clean input).
Each group is a :class:`typing.NamedTuple` with one module-level instance (``SPACING``,
``TANGENTS``, ...); a test may swap one with ``GROUP._replace(field=value)``. The compiled
kernels receive their groups as arguments (numba types a named tuple like any tuple), so a
changed value reaches the compiled and the plain-Python kernels alike, and numba's disk cache
never serves a kernel built with an older value.

Where a value came from is said per field; "benchmark" means chosen on the project's
synthetic models and CASSIE sketches (docs/benchmarks.md), never per input.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Defaults", "DEFAULTS", "Layout", "LAYOUT", "Spacing", "SPACING", "Tangents", "TANGENTS", "Strip", "STRIP", "Noisy", "NOISY", "Vote", "VOTE", "Noise", "NOISE", "Links", "LINKS", "Strand", "STRAND", "Shell", "SHELL", "Split", "SPLIT", "Chains", "CHAINS", "Ends", "ENDS", "Repairs", "REPAIRS", "Nodes", "NODES", "Curves", "CURVES", "Fit", "FIT", "Untangle", "UNTANGLE", "Numeric", "NUMERIC", "Linalg", "LINALG"]

class Defaults(NamedTuple):
    """The defaults of the user's keywords (:class:`~.params.RobustParams`)."""

    #: neighbours per point for the linked graph
    k: int = 16
    #: inner radius of the junction-test shell, in h (a junction's branches are apart there)
    shell_inner: float = 2.5
    #: outer radius of the shell, in h
    shell_outer: float = 5.5
    #: longest link between two points, in h
    link: float = 2.5
    #: a link's far end lies within this many h of the tangent line through one of its ends
    link_width: float = 1.0
    #: spurs and isolated pieces shorter than this many h are dropped
    min_spur: float = 3.0
    #: the fewest neighbours that give a spacing and a tangent
    k_min: int = 4
    #: under this many points there is no network to find (empty result)
    min_points: int = 5


DEFAULTS = Defaults()


class Layout(NamedTuple):
    """The internal numbering of the points (cache locality only; results never depend on it)."""

    #: clouds of more points are numbered cell by cell (6% faster at 34,000 points, 15% at 1e6)
    local_min: int = 20_000
    #: curve samples per block of the vectorized per-curve tests (their temporaries stay small)
    curve_block: int = 1 << 18


LAYOUT = Layout()


class Spacing(NamedTuple):
    """Stage 1: the local sampling spacing ``h`` and duplicate samples (:mod:`.frames`; the
    compiled ``kernels/frames.py`` reproduces the numpy formula of :func:`.frames.local_spacing`)."""

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
    #: a neighbour closer than ``dup`` times the first estimate is the same place sampled twice
    dup: float = 0.1
    #: ... or closer than ``dup_k`` times the k-th neighbour's distance over k / 2 (several
    #: curves ending on one sample make the first estimate tiny)
    dup_k: float = 0.3
    #: the compiled spacing kernel takes rows of at most this many neighbours
    kernel_k_max: int = 128
    #: rows at a time of the numpy spacing (the (rows, k) temporaries stay small)
    block: int = 1 << 16
    #: spacings are raised to this fraction of the smallest positive one (coincident clouds)
    floor: float = 1e-3
    #: noise-free samples (estimated noise under ``dedup_noise`` median spacings) closer than
    #: ``dedup`` median spacings to an earlier one are dropped: overlapping strokes (benchmark)
    dedup: float = 0.3
    #: the noise level, in median spacings, under which the input counts as noise-free
    dedup_noise: float = 0.05
    #: the spacing range reported: these percentiles of h
    report_lo: float = 5.0
    report_hi: float = 95.0


SPACING = Spacing()


class Tangents(NamedTuple):
    """Stage 2: tangents, their vote and the noise estimate (:mod:`.frames`)."""

    #: neighbours of the strip PCA that refines a tangent
    strip_m: int = 12
    #: on noise-free input a neighbour's direction replaces the 4-neighbour direction when it
    #: scores this much more (under noise the kernels' larger margin): a sparse curve between
    #: two close parallel curves has its 4 nearest neighbours half across (benchmark)
    cand_margin_clean: float = 1.5
    #: a tangent more than 10 degrees (cosine) off a coherent vote of its neighbours is replaced
    vote_cos: float = float(np.cos(np.radians(10.0)))
    #: neighbours in the vote on noise-free input
    vote_m: int = 8
    #: ... and under noise (a tangent thrown across close curves has more neighbours to outvote it)
    vote_m_noisy: int = 16
    #: the vote's coherence ``1 - l2 / l1`` needed to replace a tangent
    vote_coh: float = 0.6
    #: picking the nearest strip neighbour on each side favours points pulled towards the
    #: point: the chord distance is scaled by this (measured on Gaussian noise)
    rms_bias: float = 1.28
    #: the chord distance of Gaussian noise of std s per coordinate is s * sqrt(rms_dim (d - 1))
    rms_dim: float = 1.5
    #: neighbours of the noisy tangents of the strand test
    noisy_k: int = 32
    #: points per block of the noisy tangents' own neighbour query
    noisy_block: int = 1 << 16


TANGENTS = Tangents()


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


class Noise(NamedTuple):
    """The noise scale of every radius below."""

    #: the noise scale is this many times the estimated noise std
    scale: float = 1.2


NOISE = Noise()


class Links(NamedTuple):
    """Stage 3: the linked graph (:mod:`.graph`)."""

    #: links may stray from a tangent line by this many times the noise
    strip_noise: float = 4.5
    #: links may be longer than ``link * h`` by this many times the noise
    gap_noise: float = 3.0
    #: directional links (nearest along the tangent) reach this many times the link length
    directional: float = 2.0
    #: below this linearity a point has no reliable tangent and its links are kept
    lin_min: float = 0.3


LINKS = Links()


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
    #: A link whose two modes cannot lie the needed separation apart (both are weighted means
    #: of the window's offsets or their starts, so they lie within the diameter of those points,
    #: and the mode from q within the furthest of them from the mode from p) skips the mean
    #: shifts. The bound must clear that separation by this relative margin, far more than the
    #: rounding of a mean (about 1e-14 relative; results never depend on it) (unitless).
    bound_margin: float = 1e-9
    #: The bound is used only when the needed separation is within this many kernel widths
    #: (squared): then every weight of a mean within the bound is a normal number (above
    #: exp(-2 bound_reach)), so its rounding stays relative. The defaults need at most
    #: (1.5 / 0.35)^2 = 18.4 (unitless).
    bound_reach: float = 100.0


STRAND = Strand()


class Shell(NamedTuple):
    """Stage 4: the shell test (:mod:`.junctions`, ``kernels/shell.py``)."""

    #: the shell radii grow by this many times the noise (in units of ``shell_*``)
    widen: float = 1.5
    #: a point in this many shell groups or more is a junction point (1: a free end, 2: a curve)
    junction_groups: int = 3
    #: the Dijkstra keeps up to this many frontier points in a list scanned for the nearest
    #: (cheaper than a heap for the few on a curve), more in a heap (points; results never
    #: depend on it; former ``FRONT_MAX``)
    front_max: int = 32


SHELL = Shell()


class Split(NamedTuple):
    """Stage 4: regions too large for one junction (:func:`.junctions.split_large_regions`)."""

    #: a region whose radius exceeds this many outer shell radii may hold two junctions (one
    #: junction's region measures 0.35 to 0.45 on the benchmark)
    radius: float = 0.65
    #: it is re-tested on a shell this many times the size; a region still too large for one
    #: junction at one scale (radius over ``radius`` times that scale's outer radius) is
    #: re-tested at the next, finer one
    scales: tuple = (0.7, 0.5)
    #: and split into sub-regions of at least this many points
    min_points: int = 2
    #: ... at the finer scales (after the first) at least this many: a pair of points there is
    #: too few to tell two junctions under 2h apart (a sketch's double junction) from one
    fine_min_points: int = 3
    #: ... and only where their inner shell radius is over this many times the noise scale (a
    #: finer shell inside the noise's blur splits one junction: noise 0.3h with density x3
    #: lost junctions; noise 0.2h keeps the finer scale) (benchmark)
    fine_noise: float = 6.0
    #: more than this many fine outer radii apart
    sep: float = 1.2


SPLIT = Split()


class Chains(NamedTuple):
    """Stage 5: chains between regions (:mod:`.chains`, ``kernels/chains.py``)."""

    #: a chain whose points, ordered by distance from one end, form a polyline this many times
    #: longer than that distance is a cycle of the linked graph (it would zigzag)
    zigzag: float = 4.0
    #: ... tested on chains of at least this many points
    zigzag_min_points: int = 6
    #: a loop is cut where its links to both sides lie within this many h of the cut point
    loop_cut: float = 3.0
    #: ... or within this factor of its longest link there
    loop_cut_link: float = 1.01
    #: a loop is closed when it is longer than this many h
    loop_min: float = 6.0
    #: a loop of fewer points is an open piece
    loop_min_points: int = 3
    #: floor of an edge length in the chains' Dijkstra (length; coincident points still get an
    #: order)
    min_edge: float = 1e-12
    #: an end of a chain reads its contacts within ``min(L / 2, end_reach h)`` of it
    #: (spacings)
    end_reach: float = 4.0


CHAINS = Chains()


class Ends(NamedTuple):
    """End portions of chains and branches (``kernels/nodes.py``; as ``chains.end_portion``)."""

    #: an end portion holds at least ``min(min_points, n)`` points (points)
    min_points: int = 3
    #: the walk into a junction region aims along the end portion over this arc length
    #: (spacings)
    walk_span: float = 3.0
    #: chains with fewer points are not trimmed behind their nodes (points)
    trim_min: int = 4


ENDS = Ends()


class Repairs(NamedTuple):
    """Stage 6: the repairs of :mod:`.repairs` (what noise and sparse sampling break)."""

    #: two tips (or a tip and a region) within this many link lengths are joined
    tip_gap: float = 1.2
    #: a free end attaches to a chain at most this many link lengths (plus gap_noise times the
    #: noise) ahead of it: a link lost to noise; a longer gap on clean samples is in the data
    attach: float = 1.0
    #: ... within 45 degrees of its end's direction (cosine)
    attach_cos: float = float(np.cos(np.radians(45.0)))
    #: the end portion (in h) that gives a free end's direction for the attach test
    attach_span: float = 3.0
    #: a chain point within this many points of the other chain's end joins that end's region
    attach_end_points: int = 2
    #: the end portion (in h) that gives a tip's node for the tip-to-junction test
    tip_span: float = 4.0
    #: junctions joined by a chain at most this many h long may be one junction
    merge_len: float = 8.0
    #: ... when the other branches of one aim at the other within 10 degrees (tangent)
    merge_tan: float = float(np.tan(np.radians(10.0)))
    #: a chain sampled this many times as densely as the median is two strokes run together:
    #: its length is measured in median spacings
    dense: float = 1.5
    #: a doubled chain into a hub of this many curves or more may aim within ``merge_tan_hub``
    hub_valence: int = 5
    #: 20 degrees (tangent): strokes drawn into a pole part from each other bent
    merge_tan_hub: float = float(np.tan(np.radians(20.0)))
    #: passes of the spur pruning (a pruned spur can make another)
    prune_passes: int = 3


REPAIRS = Repairs()


class Nodes(NamedTuple):
    """Stage 7: node placement (:mod:`.nodes`, ``kernels/nodes.py``; the kernel's settings from
    here arrive in a :class:`~curvenet.methods.robust.kernels.JunctionParams`)."""

    #: a region where this many curve ends meet or more is a junction (1: a free end, 2: no node)
    junction_valence: int = 3
    #: length (h) of the chain end that gives a chain's direction where it is trimmed at a node
    #: (the trim reaches twice this)
    span: float = 6.0
    #: length (h) of the walked branch end fitted for the junction node
    fit_span: float = 4.0
    #: ... plus this many times the noise (a longer fit averages the noise out)
    fit_noise: float = 6.0
    #: a walk into a junction stops where it strays this many link widths from its line
    walk_dev: float = 1.25
    #: a walk reaches at most this many default outer shell radii (3 x 5.5 h)
    walk_far: float = 16.5
    #: the end portion (h) that gives a free end's node
    free_span: float = 4.0
    #: a region point beyond this fraction of the shell radius from its junction node, in a
    #: direction no incident branch takes, is a swallowed branch's tip
    swallow: float = 0.8
    #: ... no branch within 25 degrees (cosine)
    swallow_cos: float = float(np.cos(np.radians(25.0)))
    #: a free end's region holds a fork when a point lies this many shell radii from the path
    #: to its farthest point
    fork: float = 0.6
    #: ... in a region of at least this many points
    fork_min_points: int = 6
    #: the walk into a region takes a point only ahead of the branch end by more than this
    #: (spacings)
    ahead: float = 0.25
    #: weight of the pull of the node towards the mean of the branch ends in the least
    #: squares (unitless; small: it only makes near-parallel lines well-posed)
    anchor_pull: float = 1e-2
    #: relative slack of the hidden-branch tests' comparisons (rounding guard; the exact test
    #: is ``junctions.swallowed_branches``)
    swallow_tol: float = 1e-9
    #: a branch can hide in a region of at least this many points (points)
    swallow_min: int = 3


NODES = Nodes()


class Curves(NamedTuple):
    """Stage 8: curves (:mod:`.curves`)."""

    #: two successive steps of a curve more than 120 degrees apart (cosine below) turn back
    turn_back_cos: float = -0.5
    #: the reach (in points along the curve) of one reordering move of the untangle kernel
    untangle_w: int = 64
    #: node and curve order: coordinates rounded to this many decimals
    round_decimals: int = 9
    #: an interior sample farther than this many (spacing + noise scale) from the chord of its
    #: two neighbours is a spike (an outlier taken into the curve) and is dropped; a 30-degree
    #: corner sits 0.97 spacing from that chord
    spike: float = 1.5


CURVES = Curves()


class Fit(NamedTuple):
    """Stage 8, under noise: each curve fitted by a penalised smoothing spline through its
    samples (:func:`.curves.fit_curves`)."""

    #: widest kernel of the fit, in local spacings (the equivalent kernel of a cubic smoothing
    #: spline, Silverman 1984: it averages about this many samples on either side), the width
    #: on straight and gently bent stretches (benchmark)
    band: float = 4.0
    #: narrowest kernel, in local spacings: the width at sharp bends and corners (benchmark)
    band_min: float = 1.5
    #: within a few samples of a held end (a node) the kernel is at most this many spacings wide
    #: per sample from the end (benchmark)
    end_taper: float = 1.0
    #: squared L2 norm of the spline's equivalent kernel of width 1 (Silverman's kernel,
    #: ``3 / (8 sqrt(2))``): a fit of width ``b`` spacings keeps ``kernel_l2 / b`` of the
    #: noise variance
    kernel_l2: float = 0.265
    #: order of the spline's equivalent kernel (Silverman's kernel is of fourth order): the bias
    #: of a fit of width ``b`` grows as ``b^q``, so the width of least expected squared error
    #: minimises ``(b / wide)^(2q) bias2 + kernel_l2 sigma^2 / b`` (``bias2``: the squared bias
    #: of the widest fit, of width ``wide``; a property of the kernel, not a tuning; unitless)
    bias_order: float = 4.0
    #: curves of fewer samples are left as they are (points: an open curve's two ends are held)
    min_points: int = 3
    #: a step between two samples counts as at least this fraction of the curve's median step
    #: (repeated samples: the divided differences stay finite)
    step_floor: float = 1e-3


FIT = Fit()


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


class Numeric(NamedTuple):
    """Rounding tolerances (not thresholds of the method: they make equal values compare equal)."""

    #: relative tolerance of a comparison against a computed bound
    rel: float = 1e-9
    #: a looser one, for bounds of prefilters (the exact test follows)
    rel_loose: float = 1e-6
    #: a projection above minus this is ahead
    ahead: float = 1e-12
    #: the smallest positive length (divisions and zero-length edges)
    tiny: float = 1e-300


NUMERIC = Numeric()


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
    #: the largest size ``d`` of a matrix whose top eigenpair ``_eig_top`` finds in closed form
    #: (its characteristic polynomial a cubic; the points are 2D or 3D); larger ones take the
    #: Jacobi sweeps (a property of the code, not a tuning)
    closed_dim: int = 3
    #: floor of a divisor that may vanish (a sum of weights, a top eigenvalue, a length): any
    #: positive double far below the data's scale (unitless)
    tiny: float = 1e-300


LINALG = Linalg()
