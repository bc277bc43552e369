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

Where a value came from is said per field ("origin"); "benchmark" means chosen on the
project's synthetic models and CASSIE sketches (docs/benchmarks.md), never per input, and the
figures quoted are those the commit named in parentheses measured (``git show <commit>``).
"No measurement recorded" says that the history holds no measurement of that value: it is
the commit's choice, kept since because the benchmark did not ask for another. "Derived" values
follow from the geometry or the code, "definition" ones from what a junction is; a rounding
guard or an implementation setting is not a tuning (results never depend on the latter).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Defaults", "DEFAULTS", "Layout", "LAYOUT", "Spacing", "SPACING", "Tangents", "TANGENTS", "Strip", "STRIP", "Noisy", "NOISY", "Vote", "VOTE", "Noise", "NOISE", "Links", "LINKS", "Strand", "STRAND", "Shell", "SHELL", "Split", "SPLIT", "Chains", "CHAINS", "Ends", "ENDS", "Repairs", "REPAIRS", "Paired", "PAIRED", "Spanning", "SPANNING", "EndTrees", "ENDTREES", "Branched", "BRANCHED", "Nodes", "NODES", "Curves", "CURVES", "Fit", "FIT", "Untangle", "UNTANGLE", "Skipped", "SKIPPED", "Excursion", "EXCURSION", "WalkIn", "WALKIN", "Unexplained", "UNEXPLAINED", "Numeric", "NUMERIC", "Linalg", "LINALG"]

class Defaults(NamedTuple):
    """The defaults of the user's keywords (:class:`~.params.RobustParams`)."""

    #: neighbours per point for the linked graph
    #: origin: first version (3e727c1); no measurement recorded
    k: int = 16
    #: inner radius of the junction-test shell, in h (a junction's branches are apart there)
    #: origin: an early tuning hook (RB_RI), made a constant in c5f96bf; the tuning runs were not
    #: recorded
    shell_inner: float = 2.5
    #: outer radius of the shell, in h
    #: origin: an early tuning hook (RB_RO; 4.5 in the first version), made a constant in c5f96bf;
    #: the tuning runs were not recorded
    shell_outer: float = 5.5
    #: longest link between two points, in h
    #: origin: first version (3e727c1); no measurement recorded
    link: float = 2.5
    #: a link's far end lies within this many h of the tangent line through one of its ends
    #: origin: an early tuning hook (RB_W), made a constant in c5f96bf; the tuning runs were not
    #: recorded
    link_width: float = 1.0
    #: spurs and isolated pieces shorter than this many h are dropped
    #: origin: first version (3e727c1); no measurement recorded
    min_spur: float = 3.0
    #: the fewest neighbours that give a spacing and a tangent
    #: origin: derived: the spacing averages the ``SPACING.n_mean`` = 4 nearest neighbours (first
    #: version)
    k_min: int = 4
    #: under this many points there is no network to find (empty result)
    #: origin: derived: a point and its ``k_min`` neighbours (first version)
    min_points: int = 5


DEFAULTS = Defaults()


class Layout(NamedTuple):
    """The internal numbering of the points (cache locality only; results never depend on it)."""

    #: clouds of more points are numbered cell by cell (6% faster at 34,000 points, 15% at 1e6)
    #: origin: measured speed, 6884b44 (the 272-run sweep unchanged)
    local_min: int = 20_000
    #: curve samples per block of the vectorized per-curve tests (their temporaries stay small)
    #: origin: memory only: a block holds whole curves, the same arithmetic; results never depend on
    #: it
    curve_block: int = 1 << 18
    #: candidate links per block of the test of links stepping over a region (its temporaries,
    #: about 5 region points per link, stay small)
    #: origin: memory only: the links are independent, results never depend on it (1e6 noisy
    #: points: 263 MB at once, 1.8 million (link, point) pairs)
    link_block: int = 1 << 16


LAYOUT = Layout()


class Spacing(NamedTuple):
    """Stage 1: the local sampling spacing ``h`` and duplicate samples (:mod:`.frames`; the
    compiled ``kernels/frames.py`` reproduces the numpy formula of :func:`.frames.local_spacing`)."""

    #: nearest neighbours whose mean distance is the raw spacing (points)
    #: origin: first version (3e727c1); no measurement recorded
    n_mean: int = 4
    #: divisor of that mean: the mean distance to the 4 nearest samples of a curve sampled
    #: every ``h`` is ``1.5 h`` (unitless)
    #: origin: derived (above; first version)
    mean_div: float = 1.5
    #: neighbours whose raw spacings, with the point's own, give the median (points)
    #: origin: first version (3e727c1); no measurement recorded
    n_median: int = 8
    #: accumulators of numpy's pairwise summation of a row, summed as a binary tree (a power
    #: of two: numpy's unrolling, reproduced so the sums are the same bits; a property of numpy,
    #: not a tuning)
    #: origin: a property of numpy (above), not a tuning
    numpy_lanes: int = 8
    #: a neighbour closer than ``dup`` times the first estimate is the same place sampled twice
    #: origin: benchmark: CASSIE mean curve F1 0.857 -> 0.862 (4aabe83)
    dup: float = 0.1
    #: ... or closer than ``dup_k`` times the k-th neighbour's distance over k / 2 (several
    #: curves ending on one sample make the first estimate tiny)
    #: origin: benchmark: CASSIE mean 0.870 -> 0.874, guitar 0.588 -> 0.637 (bdebc5b)
    dup_k: float = 0.3
    #: the compiled spacing kernel takes rows of at most this many neighbours
    #: origin: implementation: for more neighbours the numpy formula runs, the same bits (c90f454)
    kernel_k_max: int = 128
    #: rows at a time of the numpy spacing (the (rows, k) temporaries stay small)
    #: origin: memory only: the rows are independent, results never depend on it (ae0b350)
    block: int = 1 << 16
    #: spacings are raised to this fraction of the smallest positive one (coincident clouds)
    #: origin: first version's guard against a zero spacing (3e727c1), not a tuning
    floor: float = 1e-3
    #: noise-free samples (estimated noise under ``dedup_noise`` median spacings) closer than
    #: ``dedup`` median spacings to an earlier one are dropped: overlapping strokes (benchmark)
    #: origin: benchmark: CASSIE free creations 0.891 -> 0.904 (d822590)
    dedup: float = 0.3
    #: the noise level, in median spacings, under which the input counts as noise-free
    #: origin: benchmark, set with the duplicate rule (d822590: CASSIE free creations 0.891 ->
    #: 0.904)
    dedup_noise: float = 0.05
    #: a point whose ``n_mean``-th nearest neighbour lies farther than this many median
    #: spacings is alone in space (an outlier, not a sample of a curve): dropped
    #: (:func:`.frames.isolated`). Its own spacing would be that far, and every radius of it
    #: with it, beyond any bounded neighbourhood (a tile's halo)
    #: origin: issue 23 (tiled == one process under outliers): corridor outliers have spacings
    #: of 40-80 median spacings; a sparse free end (density ratio 3) has its 4th neighbour about
    #: 8. No network of the 576 digest runs nor of the 256 'outliers 2%' bench runs changed
    isolated: float = 16.0
    #: the spacing range reported: these percentiles of h
    #: origin: reporting only: no result depends on it
    report_lo: float = 5.0
    #: ... and the upper one (percentile)
    #: origin: reporting only: no result depends on it
    report_hi: float = 95.0


SPACING = Spacing()


class Tangents(NamedTuple):
    """Stage 2: tangents, their vote and the noise estimate (:mod:`.frames`)."""

    #: neighbours of the strip PCA that refines a tangent
    #: origin: set with the strip-refined tangents (400599a); no measurement recorded
    strip_m: int = 12
    #: on noise-free input a neighbour's direction replaces the 4-neighbour direction when it
    #: scores this much more (under noise the kernels' larger margin): a sparse curve between
    #: two close parallel curves has its 4 nearest neighbours half across (benchmark)
    #: origin: benchmark: the eye at density x3 exact in 8 of 8 samplings, were 6 (2cbe27f)
    cand_margin_clean: float = 1.5
    #: a tangent more than 10 degrees (cosine) off a coherent vote of its neighbours is replaced
    #: origin: set with the tangent vote (2bace58); no measurement recorded
    vote_cos: float = float(np.cos(np.radians(10.0)))
    #: neighbours in the vote on noise-free input
    #: origin: set with the tangent vote (2bace58); no measurement recorded
    vote_m: int = 8
    #: ... and under noise (a tangent thrown across close curves has more neighbours to outvote it)
    #: origin: benchmark: sweep under noise 0.2h 0.984 -> 0.996 (70ade3d)
    vote_m_noisy: int = 16
    #: the vote's coherence ``1 - l2 / l1`` needed to replace a tangent
    #: origin: set with the tangent vote (2bace58); no measurement recorded
    vote_coh: float = 0.6
    #: a tangent stays against the vote when this many of its nearest neighbours (one on either
    #: side) lie along it (:func:`.frames.vote_tangents`)
    #: origin: derived: the samples just before and after the point on its own curve
    vote_keep_nearest: int = 2
    #: ... each within this cosine of it (53 degrees), and none within it of the vote's direction
    #: origin: benchmark (issue 25, 6 December 2026): cosines 0.5 / 0.6 / 0.7 / 0.75 / 0.8 on the
    #: 928-run harness 24 / 28 / 28 / 28 / 30 runs better and 14 / 18 / 20 / 21 / 29 worse
    #: (+1.75 / +2.01 / +1.91 / +1.91 / +1.24 in curve F1; 0.8 costs the kinds' clean twigs); at 0.6
    #: also 352 runs at noise 0.1 h and with outliers 13 better / 4 worse, CASSIE 320 runs 27 / 12
    vote_keep_cos: float = 0.6
    #: picking the nearest strip neighbour on each side favours points pulled towards the
    #: point: the chord distance is scaled by this (measured on Gaussian noise)
    #: origin: measured on Gaussian noise, with the noise estimate (20a7b2f)
    rms_bias: float = 1.28
    #: the chord distance of Gaussian noise of std s per coordinate is s * sqrt(rms_dim (d - 1))
    #: origin: derived: the point's own noise plus a quarter of each chord end's (s^2 (1 + 1/4 +
    #: 1/4)) per direction across
    rms_dim: float = 1.5
    #: neighbours of the noisy tangents of the strand test
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    noisy_k: int = 32
    #: points per block of the noisy tangents' own neighbour query
    #: origin: memory only: results never depend on it (efa6188)
    noisy_block: int = 1 << 16


TANGENTS = Tangents()


class Strip(NamedTuple):
    """Tangents of clean input (``kernels/frames.py``, :func:`_tangents`)."""

    #: half-width scale of the strip that scores a direction: the Gaussian weight is
    #: ``exp(-(r / (w h))^2)`` (spacings; former ``STRIP_W``)
    #: origin: benchmark: set with the neighbour-direction test (652e120: density x3 0.969 -> 1.000)
    w: float = 0.5
    #: reach along the line of that strip (spacings; former ``STRIP_A``)
    #: origin: benchmark: set with the neighbour-direction test (652e120: density x3 0.969 -> 1.000)
    a: float = 3.0
    #: score a neighbour's direction needs above the 4-neighbour direction's to replace it
    #: (points of strip score; former ``CAND_MARGIN``)
    #: origin: benchmark: set with the neighbour-direction test (652e120: density x3 0.969 -> 1.000)
    cand_margin: float = 2.0
    #: the neighbours' directions are tried only where the first PCA's linearity is below this
    #: (unitless; former ``CAND_LIN``)
    #: origin: measured: the same networks on 16 models x 2 seeds, tangents at 1e6 3.9 s -> 1.5 s
    #: (f669b37)
    cand_lin: float = 0.8
    #: nearest neighbours of the first PCA, whose directions are the candidates (points)
    #: origin: benchmark: set with the neighbour-direction test (652e120: density x3 0.969 -> 1.000)
    n_first: int = 4
    #: weighted PCA refinements of the direction (each reweights the points within ``h`` of
    #: the current line)
    #: origin: set with the strip-refined tangents (400599a); no measurement recorded
    refine: int = 2
    #: points per parallel block (one set of scratch arrays each; results never depend on it)
    #: origin: implementation: results never depend on it
    rows: int = 2048


STRIP = Strip()


class Noisy(NamedTuple):
    """Tangents of noisy input (``kernels/frames.py``, :func:`_noisy_tangents`)."""

    #: directions to this many nearest neighbours are scored (points; former ``NOISY_CAND``)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    cand: int = 16
    #: reach of the strip along the line, plus ``reach_sig`` sigma (spacings; former
    #: ``NOISY_A``)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    a: float = 5.0
    #: noise part of that reach (sigmas)
    #: origin: measured: the sweep moved by one sampling of the eye (efa6188: under noise 0.3h + x3
    #: 0.496 -> 0.502)
    reach_sig: float = 2.0
    #: strip width: ``max(wh h, wf sigma)`` (sigmas; former ``NOISY_WF``)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    wf: float = 2.0
    #: (spacings; former ``NOISY_WH``)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    wh: float = 0.5
    #: Gaussian weights are cut at this many strip widths (unitless; former ``NOISY_CUT``)
    #: origin: measured: the sweep unchanged (efa6188); a reach, not a tuning
    cut: float = 3.0
    #: the refining PCA takes the points within ``max(h, rw sigma)`` of the line (sigmas;
    #: former ``NOISY_RW``)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    rw: float = 2.5
    #: a candidate direction within this cosine (10 degrees) of one already scored is not
    #: scored again: the refinement, whose strip is at least a spacing wide over 5 spacings,
    #: starts from the same points (cosine; former ``NOISY_SAME``)
    #: origin: benchmark: the eye under noise 0.3h + x3 0.502 -> 0.550, twice as fast (3d841b0)
    same: float = float(np.cos(np.radians(10.0)))
    #: weighted PCA refinements of the best direction
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    refine: int = 2
    #: rows per parallel block (one set of scratch arrays each; results never depend on it;
    #: former ``NOISY_ROWS``)
    #: origin: implementation: results never depend on it
    rows: int = 256


NOISY = Noisy()


class Vote(NamedTuple):
    """Tangent vote (``kernels/frames.py``, :func:`_vote_eig`)."""

    #: candidate points per parallel block (results never depend on it)
    #: origin: implementation: results never depend on it
    rows: int = 1024


VOTE = Vote()


class Noise(NamedTuple):
    """The noise scale of every radius below."""

    #: the noise scale is this many times the estimated noise std
    #: origin: set with the noise estimate (20a7b2f); no measurement recorded
    scale: float = 1.2
    #: noise under this many median spacings is low: the links and the junction stages read the
    #: input as noise-free (no strand test between parallel strands; the region splits, the
    #: spanning-tree reading of pairs and the free-end rules of noise-free input),
    #: while the tangents, the multi-scale separation of close junctions, the duplicate rule
    #: and the fit keep the noise-free test (``SPACING.dedup_noise``); the separation of close
    #: junctions also runs above this level, with guards (low noise has the spanning tree's pairs)
    #: origin: benchmark (issue 25, 4 December 2026), A/B against 0.05 (the noise-free test,
    #: which these stages read before): see docs/method.md, "Noise-free, low noise, noisy"
    low: float = 0.15


NOISE = Noise()


class Links(NamedTuple):
    """Stage 3: the linked graph (:mod:`.graph`)."""

    #: links may stray from a tangent line by this many times the noise
    #: origin: an early tuning hook (RB_NW), made a constant in c5f96bf; the tuning runs were not
    #: recorded
    strip_noise: float = 4.5
    #: links may be longer than ``link * h`` by this many times the noise
    #: origin: set with the noise-aware long links (a811460); no measurement recorded
    gap_noise: float = 3.0
    #: directional links (nearest along the tangent) reach this many times the link length
    #: origin: set in 20a7b2f; no measurement recorded
    directional: float = 2.0
    #: below this linearity a point has no reliable tangent and its links are kept
    #: origin: an early tuning hook (RB_LIN; 0.6 in the first version), made a constant in c5f96bf;
    #: the tuning runs were not recorded
    lin_min: float = 0.3


LINKS = Links()


class Strand(NamedTuple):
    """The test that cuts links between two close parallel strands of a noisy cloud
    (``kernels/graph.py``, :func:`_strand_cuts`; former ``STRAND_*``)."""

    #: only links between tangents within 20 degrees are tested (cosine)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    cos: float = float(np.cos(np.radians(20.0)))
    #: the far end must lie more than ``max(t0 sigma, dmin h / 2)`` from the tangent line
    #: (sigmas)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    t0: float = 2.0
    #: window: neighbours within ``a h`` along the tangent (spacings)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    a: float = 4.0
    #: mean-shift kernel width ``max(b sigma, bh h)`` (sigmas)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    b: float = 1.5
    #: (spacings)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    bh: float = 0.35
    #: the two modes must lie more than ``max(thr sigma, dmin h)`` apart (sigmas)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    thr: float = 3.0
    #: (spacings)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    dmin: float = 1.5
    #: points each mode needs (points)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    nmin: int = 3
    #: on both sides of the link, beyond ``side h`` along it (spacings)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    side: float = 0.5
    #: the points of a mode must run within 15 degrees of the tangent (cosine)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    lcos: float = float(np.cos(np.radians(15.0)))
    #: most mean-shift steps
    #: origin: a cap on the iterations, set with the strand test, its values measured together
    #: (0b70e44: sweep under noise 0.3h + x3 0.929 -> 0.961)
    steps: int = 30
    #: mean shift stops when a step moves less than this fraction of the kernel width, squared
    #: (unitless)
    #: origin: a convergence test, set with the strand test, its values measured together (0b70e44:
    #: sweep under noise 0.3h + x3 0.929 -> 0.961)
    shift_tol: float = 1e-12
    #: a point belongs to a mode within this many kernel widths (unitless)
    #: origin: set with the strand test, its values measured together (0b70e44: sweep under noise
    #: 0.3h + x3 0.929 -> 0.961)
    member: float = 1.5
    #: links per parallel block (one set of scratch arrays each; results never depend on it;
    #: former ``STRAND_ROWS``)
    #: origin: implementation: results never depend on it
    rows: int = 1024
    #: A link whose two modes cannot lie the needed separation apart (both are weighted means
    #: of the window's offsets or their starts, so they lie within the diameter of those points,
    #: and the mode from q within the furthest of them from the mode from p) skips the mean
    #: shifts. The bound must clear that separation by this relative margin, far more than the
    #: rounding of a mean (about 1e-14 relative; results never depend on it) (unitless).
    #: origin: a rounding guard (above): results never depend on it
    bound_margin: float = 1e-9
    #: The bound is used only when the needed separation is within this many kernel widths
    #: (squared): then every weight of a mean within the bound is a normal number (above
    #: exp(-2 bound_reach)), so its rounding stays relative. The defaults need at most
    #: (1.5 / 0.35)^2 = 18.4 (unitless).
    #: origin: derived (above): any value over the defaults' 18.4 gives the same results
    bound_reach: float = 100.0


STRAND = Strand()


class Shell(NamedTuple):
    """Stage 4: the shell test (:mod:`.junctions`, ``kernels/shell.py``)."""

    #: the shell radii grow by this many times the noise (in units of ``shell_*``)
    #: origin: set with the shell widened for noise (a811460), not measured then; measured on
    #: 6 December 2026 (928-run harness, the repairs as they stand): 1.0 63 better / 70 worse
    #: (kinds at noise 0.2 h 0.915 -> 0.877: comb, ladder, plate; real-dev at noise 0.2 h
    #: 0.959 -> 0.964), 0.5 56 / 107
    widen: float = 1.5
    #: a point in this many shell groups or more is a junction point (1: a free end, 2: a curve)
    #: origin: definition: three branches meet at a junction (first version)
    junction_groups: int = 3
    #: the Dijkstra keeps up to this many frontier points in a list scanned for the nearest
    #: (cheaper than a heap for the few on a curve), more in a heap (points; results never
    #: depend on it; former ``FRONT_MAX``)
    #: origin: measured speed, the shell kernel at 1e6 1.93-2.11 s -> 1.25-1.44 s (61a0b66); results
    #: never depend on it
    front_max: int = 32


SHELL = Shell()


class Split(NamedTuple):
    """Stage 4: regions too large for one junction (:func:`.junctions.split_large_regions`)."""

    #: a region whose radius exceeds this many outer shell radii may hold two junctions (one
    #: junction's region measures 0.35 to 0.45 on the benchmark)
    #: origin: benchmark: one junction's region measures 0.35 to 0.45 there (5ab855e)
    radius: float = 0.65
    #: it is re-tested on a shell this many times the size; a region still too large for one
    #: junction at one scale (radius over ``radius`` times that scale's outer radius) is
    #: re-tested at the next, finer one
    #: origin: benchmark: 0.6 (5ab855e), then 0.7 (c438275: CASSIE free creations 0.877 -> 0.891),
    #: then the finer 0.5 (6165e16: kinds clean 0.482 -> 0.498)
    scales: tuple = (0.7, 0.5)
    #: and split into sub-regions of at least this many points
    #: origin: set with the region split (5ab855e); no measurement recorded
    min_points: int = 2
    #: ... at the finer scales (after the first) at least this many: a pair of points there is
    #: too few to tell two junctions under 2h apart (a sketch's double junction) from one
    #: origin: benchmark, with the finer scale (6165e16)
    fine_min_points: int = 3
    #: ... and only where their inner shell radius is over this many times the noise scale (a
    #: finer shell inside the noise's blur splits one junction: noise 0.3h with density x3
    #: lost junctions; noise 0.2h keeps the finer scale) (benchmark); the same guard for the
    #: close-junction scales under noise (``junctions.separate_close_junctions``)
    #: origin: benchmark: the sweep under noise 0.3h + x3 back to 0.961 (67077db); for the close
    #: scales under noise the same value, not tuned (issue 25, 5 December 2026: with it, of 256
    #: kind runs 15 better / 3 worse, without 24 / 25)
    fine_noise: float = 6.0
    #: more than this many fine outer radii apart
    #: origin: benchmark: 1.5 -> 1.2, fork stress test under noise 53 -> 57 of 90 (17e065f)
    sep: float = 1.2
    #: junctions a few spacings apart (a facade's ladder, a comb, short street links): a region
    #: still wider than one junction after the splits, its radius over this many outer shell
    #: radii (2.4 h by default: one junction's region measures at most 2.3 h on the speed
    #: benchmark's clean clouds, two junctions 3-5 h apart 2.4 h and more on the kinds) ...;
    #: under noise also the widest a candidate junction of the re-test may be (in outer radii
    #: of its scale) for the scale to resolve its region
    #: origin: measured: region radii on the speed clouds (1e5 clean) and the kinds (issue 25, junc25);
    #: the candidates' bound under noise the same value, not tuned (5 December 2026: 0.4, 0.44,
    #: 0.45 and 0.5 give the same kind runs but one or two of 256)
    close_radius: float = 0.44
    #: ... is re-tested on shells these many times the size (about 1.4 to 3.3 h: a junction's
    #: flagged points stay within about 1.5 h of it); the scale separating the most junctions
    #: is kept (benchmark: kinds ladder, comb, streets)
    #: origin: benchmark: kinds clean curve F1 0.498 -> 0.632 with the three scales (one scale: 0.5 alone or 0.55 alone lost ladder or comb) (junc25)
    close_scales: tuple = (0.6, 0.55, 0.5)
    #: ... its points flagged at that scale, joined by links of at most this many h (the
    #: next sample along a curve, not the one after), form one junction each; the region is
    #: replaced by them when two or more hold a junction point (noise-free input, and noise
    #: above ``NOISE.low`` with the guards of ``fine_noise`` and ``close_radius``)
    #: origin: benchmark: kinds ladder, comb (1.2 kept fewer, junc25)
    close_link: float = 1.5
    #: ... and two of them joined by a segment lie more than this many h apart (centroids): the
    #: parts of one crossing or hub seen by such a shell lie 2-2.7 h apart (benchmark: window
    #: at density x3, CASSIE flower)
    #: origin: benchmark: 3.0 -> 3.5, CASSIE flower and window density x3 back to main's; 4.0 lost kinds (junc25)
    close_sep: float = 3.5


SPLIT = Split()


class Chains(NamedTuple):
    """Stage 5: chains between regions (:mod:`.chains`, ``kernels/chains.py``)."""

    #: a chain whose points, ordered by distance from one end, form a polyline this many times
    #: longer than that distance is a cycle of the linked graph (it would zigzag)
    #: origin: benchmark: speaker under noise 0.3h + x3 exact on seeds 0-9 (efc248b)
    zigzag: float = 4.0
    #: ... tested on chains of at least this many points
    #: origin: set with the zigzag test (efc248b); no measurement of this value recorded
    zigzag_min_points: int = 6
    #: a loop is cut where its links to both sides lie within this many h of the cut point
    #: origin: first version (3e727c1), the cut rule of 7395488; no measurement recorded
    loop_cut: float = 3.0
    #: ... or within this factor of its longest link there (unitless)
    #: origin: set in 7395488 (loops cut across long links); no measurement recorded
    loop_cut_link: float = 1.01
    #: a loop is closed when it is longer than this many h
    #: origin: first version (3e727c1); no measurement recorded
    loop_min: float = 6.0
    #: a loop of fewer points is an open piece
    #: origin: first version (3e727c1); no measurement recorded
    loop_min_points: int = 3
    #: floor of an edge length in the chains' Dijkstra (length; coincident points still get an
    #: order)
    #: origin: a rounding guard, not a tuning
    min_edge: float = 1e-12
    #: an end of a chain reads its contacts within ``min(L / 2, end_reach h)`` of it
    #: (spacings): the default link length (``RobustParams.link``), the farthest a curve's next
    #: sample is linked; a contact farther along is the chain running past a region, not its end
    #: origin: benchmark (issue 25, 7 December 2026; ``benchmarks/ab_eval.py``, 1,599 runs, and
    #: ``benchmarks/family_eval.py``), against 4.0 (first version, 3e727c1, never measured): kinds,
    #: synthetic and real-dev 16 runs better, 9 worse (kinds at noise 0.2 h mean 0.9465 -> 0.9502,
    #: ladder s0 0.714 -> 0.828, outline s7 0.940 -> 1.000: an end given to a region the chain
    #: passes 3-4 h before it, whose contacts outnumbered those of the region at its last
    #: samples; worse: the eye at noise 0.3 h + x3 s1 0.800 -> 0.182, its valence-4 junction now
    #: read whole, then split in two by ``split_paired_junctions``), families 7 members better,
    #: 3 worse, CASSIE 17 better, 16 worse (means within 0.001); 2.0: 23 better, 12 worse; 3.0:
    #: 9 better, 7 worse
    end_reach: float = 2.5
    #: a chain of at most this many points with one end only, between two junctions separated
    #: a few spacings apart (``junctions.separate_close_junctions``), takes the other one as its
    #: second end: a segment of a single sample (points)
    #: origin: benchmark: kinds comb clean 0.375 -> 0.647 with it; 2 points changed no kind (junc25)
    pair_points: int = 1
    #: a chain that runs past a region it does not end at is cut there (it took a long link
    #: over the region's few points) when its contacts with the region lie in its middle
    #: (beyond ``end_reach`` of both ends), within this many h of one another along it ...
    #: origin: benchmark: kinds outline, 8 clean copies jittered by 1e-6 h (the contacts of a
    #: building notch's corner regions span 5 h: 3 cut none)
    pass_span: float = 6.0
    #: ... and a link of the chain among them is longer than this many h (a sample skipped:
    #: 1.8 cut a CASSIE guitar chain beside a junction, free creation 0.743 -> 0.730) ...
    #: origin: benchmark: kinds outline jittered copies 0.812 -> 0.852 with 1.8 and 2.0
    pass_jump: float = 2.0
    #: ... and the region holds this many points or more (a lone flagged point beside a gap of a
    #: sparse curve is no junction: the guitar again)
    #: origin: benchmark: CASSIE guitar (a one-point region 10 h from any node)
    pass_min_points: int = 2
    #: a link between two points outside the regions steps over (or cuts the corner of) a
    #: region point linked to both its ends when that point projects inside the link and lies
    #: within this fraction of the link's length from it (0.75: the link's ends seen from the
    #: point at least 67 degrees apart); such a link does not join the chains
    #: (:func:`.chains.part_bypassed`)
    #: origin: benchmark (issue 25, 5 December 2026; 928 + 352 kind/real-dev/synthetic runs):
    #: the ladder's rails at noise 0.2 h linked over their junctions' regions; 0.25, 0.5, 0.75
    #: and 1.0 tried: kinds at noise 0.2 h 0.790 -> 0.815 (0.25, without the two-pieces rule),
    #: 0.823, 0.820, 0.820 (8 samplings); 0.75 keeps the
    #: streets' two crossings 4.7 h apart (sampling 0) that 0.5 merges (links around the corner)
    bypass_off: float = 0.75


CHAINS = Chains()


class Ends(NamedTuple):
    """End portions of chains and branches (``kernels/nodes.py``; as ``chains.end_portion``)."""

    #: an end portion holds at least ``min(min_points, n)`` points (points)
    #: origin: first version (3e727c1); no measurement recorded
    min_points: int = 3
    #: the walk into a junction region aims along the end portion over this arc length
    #: (spacings)
    #: origin: the first version's end portion of 3 h (3e727c1), kept for the junction walk
    #: (a811460); no measurement recorded
    walk_span: float = 3.0
    #: chains with fewer points are not trimmed behind their nodes (points)
    #: origin: set with the overshoot trim (e4922ab); no measurement recorded
    trim_min: int = 4


ENDS = Ends()


class Repairs(NamedTuple):
    """Stage 6: the repairs of :mod:`.repairs` (what noise and sparse sampling break)."""

    #: two tips (or a tip and a region) within this many link lengths are joined
    #: origin: set with the join of facing free ends (8b94cf1); no measurement recorded
    tip_gap: float = 1.2
    #: ... under noise only when they face each other: each end's line, pointing out of its
    #: chain, within this cosine of the way to the other tip (0: the other tip lies ahead)
    #: origin: benchmark (issue 25, 6 December 2026): cosines -0.5 / 0 / 0.5 on the 928-run harness
    #: 5 / 8 / 8 runs better and 1 / 1 / 2 worse (twigs under noise; the worse one plate 0.3 h + x3);
    #: at 0 also 352 runs at noise 0.1 h and with outliers 7 better / 2 worse, CASSIE 320 runs
    #: 12 / 5 (worst -0.006)
    tip_face_cos: float = 0.0
    #: ... a gap of at most this many median spacings has no direction to read: joined
    #: origin: derived: one sample step
    tip_touch: float = 1.0
    #: under noise, a region passed through by one curve (valence 2) merges into a junction next
    #: to it (valence 3 or more) only when the curve passes it straight: the lines of its two
    #: chain ends within 30 degrees of each other (cosine; either way along them). Half of a
    #: crossing cut in two by noise is passed straight by one of the crossing curves; a region
    #: whose two curves meet at an angle there is a junction of its own, whose short curve to
    #: the next junction the widened shell took into the regions (two junctions 4-9 h apart)
    #: origin: benchmark (issue 25, 4 December 2026; 784 kind/real-dev/synthetic runs): 21
    #: better, 2 worse (-0.03, -0.01); on noise-free input too, 16 worse (the outline kind's
    #: jittered clean samplings, 4 CASSIE sketches: a crossing cut into two corner halves)
    pass_cos: float = float(np.cos(np.radians(30.0)))
    #: ... and when that junction's centre lies within this many shell spacings (``h`` plus
    #: ``SHELL.widen`` times the noise) of the curve's line through the region: half of a
    #: crossing lies on the curve that passes straight through the other half; a T junction
    #: whose stem (a short link to the next crossing, 4-6 h) the widened shell took into the
    #: regions is passed straight by its through road, the next crossing lying off that road
    #: origin: benchmark (issue 25, 6 December 2026): 1.5 / 2.5 / 3.5 on the 928-run harness 5
    #: better and 2 / 2 / 1 worse (streets noise 0.2 h s2 0.70 -> 0.85, s5 0.67 -> 0.77; under
    #: 3.5 a real neuron's junction 3.9 h off the line stayed apart); at 3.5 352 runs at noise
    #: 0.1 h and with outliers all equal, CASSIE 320 runs 3 better / 2 worse (-0.006 at most)
    pass_line: float = 3.5
    #: a free end attaches to a chain at most this many link lengths (plus gap_noise times the
    #: noise) ahead of it: a link lost to noise; a longer gap on clean samples is in the data
    #: origin: benchmark: 1.5 -> 1.0, CASSIE 0.8752 -> 0.8774, 2.5h gaps under noise still joined
    #: (5171ee8)
    attach: float = 1.0
    #: ... within 45 degrees of its end's direction (cosine); also the least angle between the
    #: four ways out of a crossing (:func:`.repairs.cross_pass_regions`)
    #: origin: benchmark: held-out seeds 5-9 density x3 0.964 -> 0.969 (8c10e3f); reused for the
    #: crossings, not tuned (issue 25, 6 December 2026)
    attach_cos: float = float(np.cos(np.radians(45.0)))
    #: the end portion (in h) that gives a free end's direction for the attach test (and each
    #: way out of a crossing, :func:`.repairs.cross_pass_regions`)
    #: origin: set with the dangling-end attach (b34cd7a); no measurement recorded
    attach_span: float = 3.0
    #: a chain point within this many points of the other chain's end joins that end's region
    #: (and is no crossing's point, :func:`.repairs.cross_pass_regions`)
    #: origin: set with the dangling-end attach (b34cd7a); no measurement recorded
    attach_end_points: int = 2
    #: the end portion (in h) that gives a tip's node for the tip-to-junction test
    #: origin: set with the tip-to-junction repair (45a8121); no measurement recorded
    tip_span: float = 4.0
    #: junctions joined by a chain at most this many h long may be one junction
    #: origin: benchmark: CASSIE 0.849 -> 0.855 (49430c8)
    merge_len: float = 8.0
    #: ... when the other branches of one aim at the other within 10 degrees (tangent)
    #: origin: benchmark: CASSIE hat 0.954 -> 0.969 (3e0684a)
    merge_tan: float = float(np.tan(np.radians(10.0)))
    #: a chain sampled this many times as densely as the median is two strokes run together:
    #: its length is measured in median spacings
    #: origin: benchmark: CASSIE hat exact, 48 study sketches 0.8632 -> 0.8646 (fa86815)
    dense: float = 1.5
    #: a doubled chain into a hub of this many curves or more may aim within ``merge_tan_hub``
    #: origin: benchmark: CASSIE hat exact, 48 study sketches 0.8632 -> 0.8646 (fa86815)
    hub_valence: int = 5
    #: 20 degrees (tangent): strokes drawn into a pole part from each other bent
    #: origin: benchmark: CASSIE hat exact, 48 study sketches 0.8632 -> 0.8646 (fa86815)
    merge_tan_hub: float = float(np.tan(np.radians(20.0)))
    #: passes of the spur pruning (a pruned spur can make another)
    #: origin: first version (3e727c1); no measurement recorded
    prune_passes: int = 3
    #: two chains between the same two regions are one curve traced twice when every point of
    #: each lies within this many spacings (plus the noise) of the other's points: samples of
    #: one curve shared out between two chains lie about one spacing from the other's
    #: origin: set with the repair (issue 25), not tuned: the shell test's finest re-tests on a
    #: real-dev building split a 4 h edge's samples into chains of 4 and 3 points
    twin: float = 1.5


REPAIRS = Repairs()


class Paired(NamedTuple):
    """Stage 6: two junctions seen as one region (:mod:`.paired`)."""

    #: a region with this many branch ends or more may be two junctions (two of valence 3 or more
    #: joined by a segment show 3 + 3 - 2 = 4)
    #: origin: definition
    min_valence: int = 4
    #: each of the two junctions keeps at least this many of the region's branches (with the
    #: segment between them, a junction of valence 3 or more)
    #: origin: definition
    min_group: int = 2
    #: a region with more branch ends is not read as two junctions: its splits (about 2^(m - 1)
    #: of m ends) would be too many to try (two junctions of valence 5 show 5 + 5 - 2 = 8)
    #: origin: measured (5 December 2026): over CASSIE 64 sketches x 4 conditions and 464 harness
    #: runs no split was ever taken above 7 ends (regions of 8 to 20 ends: 491 tried, 0 split);
    #: the CASSIE flower at noise 0.3 h had a region of 22 ends, 2 million splits: out of memory
    max_lines: int = 8
    #: the two meeting points lie more than this many spacings apart
    #: origin: set with the split (issue 25), not tuned: the real-dev buildings' jogs under noise
    #: 0.2h measure 3.7 to 5.5 h (24 splits, two samplings)
    sep: float = 2.0
    #: weight of the hold of a meeting point at the region's centroid, per line (a line's own
    #: weight is 1): it fixes only what the lines leave free (parallel lines)
    #: origin: set with the split (issue 25); small against a line's weight 1
    hold: float = 1e-3
    #: rounds that add the segment between the two points as a line of both groups
    #: origin: set with the split (issue 25)
    rounds: int = 2
    #: the two points must bring the lines' summed squared distances down to this share of the
    #: one point's: two junctions' straight branches meet their points within the noise (0.001 to
    #: 0.09 on the real-dev buildings' jogs under noise 0.2h, 24 splits), the curved branches of
    #: one junction miss two points almost as much as one (0.27 to 0.67: torus, eye and tree
    #: crossings under noise, where every such split lost curves)
    #: origin: measured with the split (issue 25) on those runs
    gain: float = 0.15
    #: a line meets a point up to this many strip half-widths behind its branch's end portion
    #: (its centroid, along the line; 0: only ahead of it): a chain that ran on past its node
    #: round the corner onto the short segment to the next junction (a building outline's notch
    #: under noise) bends its end portion back over the node; :func:`.paired.split_paired_junctions`
    #: then trims such a chain's points on the segment into the region (``Topology.trim_end``)
    #: origin: benchmark (issue 25, 5 December 2026; with the trim): kinds, real-dev and synthetic,
    #: 928 + 352 runs: 7 better, none worse (outline with outliers + noise 0.1 h samplings 0 and
    #: 2 0.81 -> 0.91, 0.85 -> 0.91; ladder at density x3 0.62 -> 0.71); CASSIE 64 x 5
    #: conditions (clean to noise 0.3 h) 0 better, 3 worse (06-1-2 at noise 0.1 h 0.49 -> 0.45,
    #: two by 0.01); sweep digests equal; other values not measured. The trim applied also
    #: where the segment stays broken moved plate junctions (density x3, 0.91 -> 0.84)
    behind: float = 2.0
    #: lines within this cosine of parallel are one direction (about 18 degrees): a line along the
    #: segment between the two points, rungs parallel to each other
    #: origin: set with the through-curve rule of the split (issue 25), not tuned
    parallel_cos: float = 0.95
    #: the branches' end portions are measured on their last this many points at once (a longer
    #: portion, rare, is measured alone): memory and speed only, not a result
    #: origin: a padding width (end portions under noise 0.3h hold about 10 points)
    tail_points: int = 32


PAIRED = Paired()


class Spanning(NamedTuple):
    """Stage 6: a row of junctions seen as one region under noise (:mod:`.spanning`)."""

    #: neighbours per point of the k-nearest-neighbour graph whose minimum spanning tree is read
    #: (the exact tree whenever each tree edge joins two points among each other's nearest)
    #: origin: set with the split (issue 25), not tuned; a setting of the tree, not of a result
    k: int = 10
    #: the tree is read over the points within this many spacings of the region (beyond the
    #: outer shell radius, 5.5 h, so that every branch leaves the region in the tree)
    #: origin: set with the split (issue 25), not tuned
    margin: float = 6.0
    #: leaf branches of the tree shorter than this many spacings ...
    #: origin: set with the split (issue 25), not tuned: noise hangs single samples off the
    #: curve (under 1 h at noise 0.3h + x3); the shortest true branch of the benchmark (a twig)
    #: is 3 h
    prune: float = 2.0
    #: ... plus this many times the noise are cut
    #: origin: set with the split (issue 25), not tuned
    prune_noise: float = 2.0
    #: passes of the cut (a cut branch can leave a short one behind)
    #: origin: set with the split (issue 25), not tuned
    prune_passes: int = 3
    #: tree vertices of three or more branches within this many spacings (plus the noise) of one
    #: another are one junction (an X crossing under noise shows two such vertices close together)
    #: origin: set with the split (issue 25), not tuned
    cluster: float = 1.5
    #: a lone such vertex is a junction only if its branches, followed this many spacings ...
    #: origin: set with the split (issue 25), not tuned
    arm: float = 2.0
    #: ... leave at least 30 degrees apart (cosine): else the tree hops between close curves
    #: origin: set with the split (issue 25), not tuned
    arm_cos: float = float(np.cos(np.radians(30.0)))
    #: a region splits into this many junctions or more; a pair is left to
    #: :func:`.paired.split_paired_junctions`, whose through-curve rule keeps an X crossing whole
    #: origin: measured with the split (issue 25): with pairs split too, the synthetic crossing
    #: under noise 0.3h + x3 fell 1.00 -> 0.71 (an X read as two V's) and the eye under noise
    #: 0.2h 1.00 -> 0.18-0.55 on 4 of 8 samplings (its two close curves), for 7 runs better
    #: elsewhere (kinds, real-dev, CASSIE under noise) by 0.01-0.04 each
    min_cores: int = 3
    #: each junction of the row has at most this valence (rows of real networks: a comb's, a
    #: street's, a facade's junctions of valence 3 and 4); a core of more is a hub of many
    #: strokes spread by the noise (a real sketch's pole), left whole with its region, unless
    #: ``min_cores`` plain junctions (valence 3 or 4: a crossing of a block of cells; valence 3
    #: only before the loop closures) lie beside it: then the region is a row, and the
    #: core holds the chain ends of a junction of the row the pruned tree did not show (a ladder's
    #: rail under noise); it is split, that core kept as one junction. So too when the core lies
    #: inside a row (the cores a path, it between two of them) beside ``min_cores`` - 1 plain
    #: junctions: two junctions of the row the tree did not part (a ladder's rungs 3 h apart);
    #: a hub is the centre of a star of cores or a leaf of the path
    #: origin: measured: CASSIE hat under noise 0.1h and 2% outliers, a hub of 14 strokes read
    #: as 3 cores of valence 6, 3 and 3 (curve F1 0.966 -> 0.929). The row exception (issue 25,
    #: 6 December 2026): the CASSIE regions with a core over 4 held at most 2 plain cores
    #: ([5, 5, 3, 4], [3, 5, 4], [3, 3, 5], the flower's [4, 4, 9, 3, 3]); the kinds' rails
    #: held 5 to 7 ([3, 3, 3, 3, 3, 3, 5, 3]): ladder noise 0.2h s4 0.353 -> 0.915, 0.3h + x3 s0 0.423
    #: -> 0.746, comb 0.3h + x3 s5 0.000 -> 0.486, CASSIE 5 of 128 runs at noise 0.2h and 0.3h
    #: better by 0.016-0.086, none worse of 928 + 352 harness runs and 320 CASSIE runs. Inside a
    #: row (6 December 2026): 928 + 352 runs 5 better, 0 worse (ladder noise 0.2h s3 0.561 ->
    #: 0.800, streets 0.3h + x3 s1 0.700 -> 0.806), CASSIE 256 noisy runs 3 better, 1 worse
    #: (10-2-1 at 0.2h by 0.004); any core beside 2 plain ones instead: the flower's hub (a star
    #: of cores, valence 10) split, 0.788 -> 0.713. Plain junctions of valence 4 too (with the
    #: loop closures, 7 December 2026): the families' storeys at noise 0.2h 0.852 -> 0.909, grid
    #: 0.710 -> 0.732, grid density x3 0.847 -> 0.881; the centre of a star of more than
    #: ``min_cores`` cores is still a hub (the flower's [4, 4, 9, 3, 3], 0.788 kept)
    max_valence: int = 4
    #: the fewest chain ends of such a region: three junctions of valence 3 in a row show
    #: 3 + 3 + 3 - 2 x 2
    #: origin: derived from ``min_cores`` and a junction's valence 3
    region_valence: int = 5
    #: the fewest points of such a region (three junctions 3 h apart: 7 samples along the row
    #: and a branch's first)
    #: origin: set with the split (issue 25) at 12; 12 -> 8: the benchmark's ladder at noise
    #: 0.2h held rows of three junctions in regions of 9-10 points (curve F1 0.25 -> 0.39); of
    #: the 832-run harness, 240 more kinds runs (5 kinds x 3 noisy conditions x 16 samplings)
    #: and CASSIE 64 x 3 one other run moved (outline, noise 0.3h + x3, +0.086), none worse
    min_points: int = 8
    #: on noise-free input a region splits into this many junctions or more: a pair too, when
    #: each junction's branches leave it over ``arm_cos`` apart (two curves converging at a
    #: small angle part where the tree branches: an eye's arcs, a thin X crossing) and no
    #: straight curve crosses the segment between them (an X whose curves pass apart)
    #: origin: measured (issue 25) on the kinds clean and density x3 (8 samplings; 54 runs) and
    #: the 48 CASSIE study sketches, clean: no split on clean input 0.584 / 0.8731, rows of
    #: three 0.610 / 0.8722, pairs too 0.624 / 0.8727 (the synthetic models, real-dev and the
    #: CASSIE free creations unchanged by either)
    clean_min_cores: int = 2
    #: the fewest chain ends of such a region on noise-free input: two junctions of valence 3
    #: joined by a segment show 3 + 3 - 2
    #: origin: derived from ``clean_min_cores`` and a junction's valence 3
    clean_region_valence: int = 4
    #: the fewest points of such a region on noise-free input (no shell widened for noise: a
    #: clean row of three valence-3 junctions 3-5 h apart flags 11 points)
    #: origin: measured (issue 25), as ``clean_min_cores``: 3 or 4 points 0.624 / 0.8727, 6
    #: 0.623, 8 0.615, 12 (the noisy value) 0.608 / 0.8715
    clean_min_points: int = 4
    #: the junctions lie at least this many spacings apart (the benchmark's rows: 3 to 5 h):
    #: two neighbouring cores nearer than this are one junction (merged while more than
    #: ``min_cores`` are left; a row read whole was dropped before: a ladder's rail under noise
    #: 0.2h, ten cores found and one pair 1.9 h apart, became a single node of valence 12)
    #: origin: set with the split (issue 25), not tuned; the merge: 832-run harness 7 better, 0
    #: worse (ladder, comb, outline under noise), CASSIE equal
    sep: float = 2.5
    #: the new chain between two junctions holds the region's points of the tree path between
    #: them farther than this many spacings (plus the noise) from both junctions' tree vertices
    #: (the region's other points go to the junction nearest along the tree) ...
    #: origin: set with the split (issue 25), not tuned
    core: float = 1.0
    #: ... or than this share of the distance between the two vertices, if less; when no point
    #: of the path lies that far, the chain is the path's region point farthest from both
    #: (junctions 3 h apart under noise: the samples between lie 1 h from one or the other)
    #: origin: set with the split (issue 25): 2.8 h apart on the comb under noise 0.2h, a core
    #: of 1.24 h left no point between two junctions; the farthest point: the ladder kind's rails
    #: under noise 0.2h (10 junctions found, the row left whole: two nodes of valence 12);
    #: 832-run harness 21 better, 1 worse (+7.05)
    core_share: float = 0.35
    #: the spanning tree has no cycle, so a cell of the network inside the region (a street
    #: block or a window 4-5 h wide, its four sides within the widened shell) loses a side:
    #: the tree drops the cell's longest edge, the side's two halves hang as leaf branches of
    #: about half its length and are pruned, and its corners lose a branch. A leaf of the tree
    #: and a point at most this many spacings from it (plus ``prune_noise`` times the noise),
    #: the gap going on along the tree at the leaf (and at the point when that is a leaf too,
    #: ``close_cos``), are joined again when the graph's path between them is ``loop`` spacings
    #: or longer (the closest pair first; :func:`.spanning.loop_closures`)
    #: origin: set with the loop closure (issue 25), not tuned; the 90 gaps it closed on the
    #: grid and storeys families at noise 0.1h and 0.2h were 1.3-2.4 spacings long, each on a
    #: true curve (midpoint within 0.7 h of one)
    close: float = 2.0
    #: the shortest cycle closed: a cell 2.5 h square (the families' cells are 4 h or more; the
    #: gap between two branches of a junction at a small angle closes a shorter cycle)
    #: origin: set with the loop closure (issue 25), not tuned
    loop: float = 10.0
    #: a gap is closed only when it goes on along the tree's direction at its leaf ends
    #: (measured ``arm`` spacings back along the tree): within 45 degrees
    #: origin: set with the loop closure (issue 25), not tuned
    close_cos: float = float(np.cos(np.radians(45.0)))


SPANNING = Spanning()

class EndTrees(NamedTuple):
    """Stage 6: a junction inside a free-end or pass region (:mod:`.endtrees`)."""

    #: regions with at least this many chain ends are read (a region no chain reaches is a
    #: clump of stroke ends or outliers: its tree joins stroke ends that pass near each other) ...
    #: origin: set with the reading (issue 25): with clumps read, CASSIE sewing-machine with
    #: outliers made four stroke ends 7 h apart one junction
    min_valence: int = 1
    #: ... and at most this many (a free end: 1; a pass: 2); a region of three or more is a
    #: junction already
    #: origin: set with the reading (issue 25), not tuned: the valences of a junction the shell
    #: test read whole with its twigs
    max_valence: int = 2
    #: a region of fewer points is not read (a junction and one free arm hold at least this many)
    #: origin: set with the reading (issue 25), not tuned
    min_points: int = 3
    #: a free arm holding more than this many times the samples per length of the densest other
    #: branch of its junction is a fold (a curve that runs out and back along itself: a spike
    #: of a neuron tracing), not a twig ...
    #: origin: set with the reading (issue 25): the spike of real-dev nrn_ri05_s591 at noise
    #: 0.1 h held 1.96 times, the kinds' twigs at noise 0.2 h up to 1.4 times
    fold: float = 1.75
    #: ... the samples counted within this many spacings (plus the noise) of the branch
    #: origin: set with the reading (issue 25), not tuned: half a spacing, the samples of one
    #: strand and not of a curve beside it
    fold_band: float = 0.5


ENDTREES = EndTrees()



class Branched(NamedTuple):
    """Stage 6: a junction the shell test missed, where a chain branches (:mod:`.branched`)."""

    #: a chain whose consecutive points (in chain order) lie over this many spacings apart ...
    #: origin: set with the repair (issue 25), not tuned: along a path the next point is about
    #: 1 h away; where a run of points branches the order jumps back 2-3 h (the kinds' comb and
    #: twigs, clean)
    jump: float = 1.8
    #: ... plus this many times the noise is read from its spanning tree
    #: origin: set with the repair (issue 25), not tuned
    jump_noise: float = 2.0
    #: the fewest points of such a chain
    #: origin: set with the repair (issue 25), not tuned
    min_points: int = 6
    #: the tree of the points within this many spacings (plus the noise) of a jump is read first;
    #: the whole chain's only where it shows a junction (a missed junction lies within its
    #: shortest branch's length of the jump)
    #: origin: set with the repair (issue 25): the shell's outer radius (5.5 h) and the spanning
    #: tree's margin (``SPANNING.margin``)
    window: float = 6.0
    #: a branch's region: the one most linked to its last this many points
    #: origin: set with the repair (issue 25), not tuned
    tip_points: int = 2
    #: ... when the branch's last point lies within this many spacings (plus the noise) of it
    #: (the next sample along the curve); a branch shorter than the tree's cut that reaches no
    #: region this way is no branch
    #: origin: set with the repair (issue 25): the branches of the kinds' missed junctions end
    #: 0.97-1.06 h from their region (clean); a neuron under noise 0.2h showed a one-point
    #: branch 3.2 h from the region it was linked to (a spurious junction)
    reach: float = 1.5
    #: ... plus this many times the noise
    #: origin: set with the repair (issue 25), not tuned
    reach_noise: float = 2.0
    #: a branch that reaches no region this way is a free branch (its tip a free end no shell
    #: saw: a twig of 3-6 h a few spacings from a junction, whose tip's shell holds the parent
    #: curve) when it is at least ``min_spur`` spacings long and holds at least this many samples
    #: per spacing of its length; else it is no branch and the chain is left as it is (two
    #: samples 3.5 h apart hanging off a region: a hop across a gap, as density x3 makes)
    #: origin: benchmark (issue 25, 4 December 2026): without the fill test (any branch of
    #: ``min_spur`` h) kinds 336 runs 8 better, 1 worse (a ladder under noise 0.3h + x3, 0.458 ->
    #: 0.356: a branch of 2 samples over 3.5 h); with 0.75: 7 better, 0 worse
    free_fill: float = 0.75
    #: ... and only at a junction whose every branch holds at least this many samples (a branch
    #: of one sample into a region is the chain's end stepping into it; past such a step a sharp
    #: corner under noise hangs a few samples that read as a free branch)
    #: origin: benchmark: synthetic corners under noise 0.2h, sampling 5: 1.000 -> 0.667 without
    #: it (branches of 70, 4 and 1 samples); kinds with it: the same 7 better, 0 worse
    free_arm_points: int = 2
    #: two pieces of a chain split at several junctions that join one junction to one region are
    #: two curves (a double edge: a ladder's end rung and the rail's rounded end) when a point of
    #: one lies over this many spacings from the other; closer, they are one chain end widened by
    #: noise (the split is not made)
    #: origin: set with the rule (issue 25): the shell's inner radius (2.5 h), where a junction's
    #: branches are apart
    twin_apart: float = 2.5
    #: ... plus this many times the noise
    #: origin: set with the rule (issue 25), as ``reach_noise``
    twin_apart_noise: float = 2.0


BRANCHED = Branched()


class Nodes(NamedTuple):
    """Stage 7: node placement (:mod:`.nodes`, ``kernels/nodes.py``; the kernel's settings from
    here arrive in a :class:`~curvenet.methods.robust.kernels.JunctionParams`)."""

    #: a region where this many curve ends meet or more is a junction (1: a free end, 2: no node)
    #: origin: definition: three curve ends make a junction (first version)
    junction_valence: int = 3
    #: length (h) of the chain end that gives a chain's direction where it is trimmed at a node
    #: (the trim reaches twice this)
    #: origin: an early tuning hook (RB_SPAN), made a constant in c5f96bf; the tuning runs were not
    #: recorded
    span: float = 6.0
    #: length (h) of the walked branch end fitted for the junction node
    #: origin: set with the walked-branch fit (2bace58); no measurement recorded
    fit_span: float = 4.0
    #: ... plus this many times the noise (a longer fit averages the noise out)
    #: origin: set with the walked-branch fit (2bace58); no measurement recorded
    fit_noise: float = 6.0
    #: a walk into a junction stops where it strays this many link widths from its line
    #: origin: benchmark: 1.5 -> 1.25, 5 seeds under noise + x3 0.889 -> 0.898 (3cc87ed)
    walk_dev: float = 1.25
    #: a walk reaches at most this many default outer shell radii (3 x 5.5 h)
    #: origin: a bound of the node fit from the early versions (before c5f96bf); no measurement
    #: recorded
    walk_far: float = 16.5
    #: the end portion (h) that gives a free end's node
    #: origin: first version (3e727c1); no measurement recorded
    free_span: float = 4.0
    #: a free end's region that bends: the point farthest along it is the node when it lies
    #: over this many spacings from the point farthest ahead (:func:`.nodes.bent_tips`) ...
    #: origin: set with the bent tip (issue 25): the neurites kind under noise, tips 4 h after a
    #: turn placed at the turn; 832-run harness 13 better, 2 worse (+0.83)
    bend: float = 2.0
    #: ... and the region holds a sample farther along than that point per this many spacings
    #: of the distance between them (one outlier 2.8 h beyond a street's dead end is no tail)
    #: origin: set with the bent tip (issue 25): a regular step (``EXCURSION.gap``); the streets
    #: kind with outliers, one run 0.969 -> 0.938 without it
    bend_step: float = 1.5
    #: only regions with such a point this many spacings off the straight approach (the
    #: segment from the chain's end to the point farthest ahead) are read: a tail after a turn
    #: leaves it, the points before the tip lie along it
    #: origin: set with the bent tip (issue 25), half of ``bend``: a pre-test, the 832-run
    #: harness the same with it as without; at 10^6 noisy points 4,011 free ends of 6 points or
    #: more, read in 0.18 s without it
    bend_off: float = 1.0
    #: a junction's node over this many spacings (plus ``off_noise`` noise scales) from every
    #: point of its region and of its branches' chains is off the samples: it moves to the
    #: region's median point (:func:`.nodes.median_points`); on noise-free input only when a
    #: chain end lies beyond the shell radius of that point (the region holds more than the
    #: junction)
    #: origin: set with the median point (issue 25): the least-squares node lay 1.0 h or less
    #: from the samples on the synthetic models at noise 0.2 h and with outliers, up to 1.54 h
    #: at noise 0.3 h + x3 (3 samplings each); 880-run harness with ``off_noise``: 1.5 h with
    #: the shell condition everywhere 20 better, 0 worse (2 h: 19 better), then without it under
    #: noise 25 better, 3 worse by 0.004-0.011 (+2.30); without it on noise-free input too, a
    #: CASSIE study sketch whose strokes stop short of their junction lost its node; 1 h (no
    #: noise term) broke the synthetic eye's crossings under noise
    off_region: float = 1.5
    #: ... plus this many noise scales
    #: origin: set with ``off_region``: 0, 1 and 2 gave 53 / 4, 43 / 3 and 39 / 2 better / worse
    #: without the shell condition; 1 keeps the synthetic models' 1.54 h under the bound
    off_noise: float = 1.0
    #: a region point beyond this fraction of the shell radius from its junction node, in a
    #: direction no incident branch takes, is a swallowed branch's tip
    #: origin: benchmark: held-out seeds 5-9 under noise + x3 0.919 -> 0.923 (bce5eca)
    swallow: float = 0.8
    #: ... no branch within 25 degrees (cosine)
    #: origin: benchmark: held-out seeds 5-9 under noise + x3 0.919 -> 0.923 (bce5eca)
    swallow_cos: float = float(np.cos(np.radians(25.0)))
    #: a free end's region holds a fork when a point lies this many shell radii from the path
    #: to its farthest point (2.2 h by default: a twig of 3 h leaving a branch end at 45-50
    #: degrees has its tip 2.4 h from the branch)
    #: origin: benchmark: held-out seeds 5-9 under noise + x3 0.923 -> 0.927 with 0.6 (892bc11);
    #: 0.6 -> 0.4: kinds twigs clean 0.725 -> 0.780 (0.35 and 0.3 the same), no other run moved
    #: (kinds noisy 96 runs: one sampling better, one worse; synthetic 112, real-dev 60, CASSIE
    #: free creations and study sketches clean: equal)
    fork: float = 0.4
    #: ... in a region of at least this many points
    #: origin: set with the hidden-fork test (892bc11); no measurement of this value recorded
    fork_min_points: int = 6
    #: the walk into a region takes a point only ahead of the branch end by more than this
    #: (spacings)
    #: origin: set with the junction walk (a811460); no measurement recorded
    ahead: float = 0.25
    #: weight of the pull of the node towards the mean of the branch ends in the least
    #: squares (unitless; small: it only makes near-parallel lines well-posed)
    #: origin: first version (3e727c1): a regularisation, not a tuning
    anchor_pull: float = 1e-2
    #: a junction's branch whose line lies over this many junction spacings (widened for
    #: noise) from the node of the other branches' lines strays (its curve turns a few
    #: spacings before the junction: a roof's corner beside a facade's post) and is left out
    #: of the node's fit (``kernels/nodes._without_stray_line``) ...
    #: origin: issue 25 (7 December 2026): facades drawn at random at noise 0.2 h, the turned
    #: branch's line 3.3 spacings of the widened shell (4.6 h) off the true node, the node
    #: 1.6-2.8 h off; set to 2, not tuned. With the rule: families (synth.families, 16 members)
    #: at noise 0.2 h facade 0.947 -> 0.987, storeys 0.807 -> 0.832, grid 0.574 -> 0.608, comb
    #: 0.831 -> 0.846, no family and condition lower; 928-run harness 11 better, 1 worse (kinds
    #: at noise 0.2 h 0.9258 -> 0.9338), 352 runs equal, CASSIE 320 runs 20 better, 8 worse
    stray_off: float = 2.0
    #: ... when every other line lies within this many junction spacings of their node
    #: origin: issue 25 (7 December 2026): the facade corner's two other lines 0.2-0.4 h off
    #: the true node at noise 0.2 h; set to a quarter of ``stray_off``
    stray_agree: float = 0.5
    #: ... and their normal matrix has its smallest eigenvalue at least this (unitless: two
    #: lines at an angle a give 1 - cos a; 0.5 is 60 degrees), so that they place the node
    #: in every direction
    #: origin: issue 25 (7 December 2026): the geometry of two lines, not tuned
    stray_cond: float = 0.5
    #: relative slack of the hidden-branch tests' comparisons (rounding guard; the exact test
    #: is ``junctions.swallowed_branches``)
    #: origin: a rounding guard, not a tuning
    swallow_tol: float = 1e-9
    #: a branch can hide in a region of at least this many points (points)
    #: origin: set with the hidden-branch test (bce5eca); no measurement recorded
    swallow_min: int = 3
    #: near-tangent branches: a junction whose lines' normal matrix (the sum of ``I - u u^T``
    #: over its branches, without the anchor's pull) has its smallest eigenvalue under this many
    #: times the number of branches (unitless; 2 collinear branches and a third at 28 degrees
    #: give 0.05) is placed where the branches' circles meet along that eigenvector, with
    #: circles on 2 branches or more (``kernels/nodes._tangent_node``; any other junction only
    #: when every branch gets its circle)
    #: origin: benchmark: kinds model tangent (lines leaving a circle at 0-20 degrees, 0.005-0.03)
    #: against all junctions of the other kinds and synthetic models, clean (0.25 and more)
    tangent_weak: float = 0.05
    #: ... each circle fitted on the branch's last this many spacings, outside the region (h)
    #: origin: benchmark: kinds tangent clean and density x3, 6 / 8 / 10 / 14 h: 8 h the only one
    #: placing all 5 tangent junctions within 0.5 h in both
    tangent_span: float = 8.0
    #: ... of at least this many points (points)
    #: origin: set with the tangent placement; no measurement of this value
    tangent_points: int = 5
    #: ... and fitting it within this many spacings (root mean square offset of its points; h):
    #: a circle fitted across a corner, or on a stroke that wiggles, is no model of the branch
    #: (a branch is curved when its points lie over this far from its line, see
    #: ``kernels/nodes._tangent_node``)
    #: origin: benchmark (curved-branch placement, issue 25): without the fit test CASSIE 01-1-1
    #: clean 0.671 -> 0.631; the 880-run harness the same either way; the tangent family
    #: (benchmarks/tangent_family.py) 1 sampling better, 1 worse. The curved test: noisy
    #: straight branches read as noise-free (tests/test_robust_kernels.py's junctions, noise
    #: 0.03) moved 0.06 -> 0.07 off on average without it; every figure above the same with it
    tangent_fit: float = 0.1
    #: ... as here where the noise is at most this many local spacings (unitless); above it
    #: near-tangent junctions, and curved ones in the band of ``tangent_weak_noisy``, with the
    #: circles fitted as the noise allows (``tangent_rc`` and after): the curvature over 8 h is
    #: not measurable under noise; the noise estimate of clean
    #: samplings is 0.01-0.03 h, of noise 0.1h 0.12-0.19 h, of 0.2h and of 0.3h + x3 both about
    #: 0.37 h
    #: origin: benchmark: kinds tangent, curve F1 without / with the placement: span 8 h, noise
    #: 0.1h 0.55 / 0.27, 0.2h 0.09 / 0.09 (nodes farther off); span 8 h + 60 noise levels: 0.1h
    #: 0.55 / 0.55, 0.2h 0.09 / 0.45, but 0.3h + x3 0.09 / 0.00 (not told apart from 0.2h).
    #: The same noise-free reading puts each junction line through its branch's last sample
    #: (kernels/nodes.py ``_junction_nodes``; issue 25, 6 December 2026): real-dev clean
    #: nrn_Image001 0.857 -> 1.000 on 4 of 4 samplings (its lines, fitted over 4 h of a
    #: traced polyline kinking every few spacings, met 0.4-2.1 h off the junctions), the
    #: 928-run harness 5 better, 1 worse (plate density x3 s3, two junctions read as one either
    #: way, the node moved from 1.25 h off one to 3.25 h off both); CASSIE clean mean node
    #: offset 0.134 -> 0.127 h (53 sketches closer, 11 farther), hmd_sutherland 0.905 -> 0.896
    tangent_noise: float = 0.05
    #: ... the node walks along the weak direction by steps of this many spacings (h)
    #: origin: a sampling of the profile, not a tuning
    tangent_step: float = 0.1
    #: ... at most this many spacings from the lines' node (h)
    #: origin: set with the tangent placement (the anchor lies up to 5 h from a 0-degree junction
    #: on the tangent model); no measurement of this value
    tangent_reach: float = 8.0
    #: ... Gauss-Newton steps of the offsets normal to the weak direction, per step (count)
    #: origin: set with the tangent placement; no measurement of this value
    tangent_iters: int = 3
    #: ... kept only where the circles meet within this many spacings (root mean square; h):
    #: they meet within 0.04 h at the tangent model's junctions, a merged pair of junctions
    #: (ladder) misses by 1.4 h
    #: origin: benchmark: kinds ladder clean (curve F1 0.519 -> 0.481 without this test)
    tangent_meet: float = 0.1
    #: ... plus, under noise, this many noise scales
    #: origin: benchmark (noisy tangent placement, issue 25; 880-run harness against the
    #: placement off under noise): 1.0 22 better, 9 worse (neurons at noise 0.2 h); 0.5 23 / 3;
    #: 0.25 (with tangent_mid 0.5) 23 / 2; then on the final settings 0.5: 2 better, 1 worse
    tangent_meet_noise: float = 0.25
    #: under noise each circle is fitted over the longest span whose points lie within this
    #: many noise scales of it (root mean square; the noise scale of a sampling at noise 0.1 h is
    #: about 0.13 h) (``kernels/nodes._arc_fit_grown``)
    #: origin: benchmark (880-run harness): 1.5 -> 2.0 4 better, 1 worse; 1.2: 3 better, 6 worse;
    #: 2.5: 0 better, 2 worse (all on the tangent kind)
    tangent_rc: float = 2.0
    #: ... the span grown from ``tangent_span`` by this many spacings at a time (h)
    #: origin: benchmark (880-run harness): 2 h 1 better, 1 worse (-0.03), twice the fits
    tangent_grow: float = 4.0
    #: ... to at most this many spacings (h): over 8 h a curvature of 1 / 30 h has a sagitta of
    #: 0.27 h, within the noise; over 30-60 h it is measured
    #: origin: benchmark (880-run harness): 30 h 1 better, 16 worse; 90 h 1 better, 2 worse
    tangent_span_max: float = 60.0
    #: ... a line where the circle's one more coefficient does not reduce the squared offsets by
    #: this F statistic (a line's curvature fitted on noise bends its extrapolation to the node
    #: by 0.1-0.2 h over 10 h)
    #: origin: benchmark (880-run harness): 2: 0 better, 1 worse; 8: 1 better, 1 worse (an F
    #: quantile of about 5% for 10-40 points is 4)
    tangent_sel: float = 4.0
    #: ... and the node is the middle of the stretch along the weak direction where the circles
    #: meet within this many squared noise scales (per circle) of the best
    #: origin: benchmark (880-run harness): 0 (the lowest point): 3 better, 2 worse; 1: 0
    #: better, 6 worse
    tangent_mid: float = 0.5
    #: under noise the curved-branch placement (case (b)) only where the lines' normal matrix
    #: has its smallest eigenvalue under this many times the number of branches (unitless; two
    #: collinear branches and a third at 49 degrees give 0.15): a fillet's arc leaving its
    #: straight edge, a line leaving a circle at 5-20 degrees whose chord reads wider; a branch
    #: is curved where its grown fit kept the circle (``tangent_sel``); the node is the circles'
    #: lowest meeting point (no valley middle: they cross). 0: noise-free input only
    #: origin: benchmark (issue 25, 5 December 2026): without the band (every junction) the
    #: tangent kind gained (noise 0.2 h, 8 samplings, 6 better) but the mug's handle junction
    #: moved 7.4 h along its side under noise 0.2 h (2 worse; its eigenvalue 0.2 per branch);
    #: with it (and the lines kept where they already lie in the circles' meeting) 928 + 352 runs: 9
    #: better, none worse; CASSIE 64 sketches at noise 0.1, 0.2, 0.3 h: every run equal
    tangent_weak_noisy: float = 0.15
    #: under noise, a junction of near-collinear branches moves to where the samples per length
    #: along the branches' common direction step up (one curve on one side of the junction, two
    #: on the other: ``kernels/nodes._strand_change``), the step searched within
    #: ``tangent_reach`` spacings of the node and counted over this many spacings more on each
    #: side (h)
    #: origin: benchmark (issue 25, 5 December 2026; 928-run harness, with tangent_keep 1): 6 h
    #: 24 better / 10 worse, 8 h 22 / 8 (kinds at noise 0.2 h equal); 2 and 4 h left a
    #: 0-degree junction 6.8 h from the node without samples beyond it (tangent kind, sampling 5)
    tangent_window: float = 6.0
    #: ... on junctions whose lines' smallest eigenvalue is under this many times the number of
    #: branches (unitless; two collinear branches and a third at about 65 degrees give 0.25: a
    #: quick test, the turn rule of ``tangent_turn`` (60 degrees) decides)
    #: origin: benchmark (928-run harness against the band of ``tangent_weak_noisy``, 0.15): 0.25,
    #: 0.35 and 10 (every junction) the same 2 better, none worse (the tangent kind's fillet,
    #: eigenvalue 0.22 per branch in sampling 3, 5.5 -> 0.8 h); CASSIE 64 at noise 0.1-0.3 h and
    #: with outliers (320 runs) 4 better / 6 worse, +0.16 in all (06-2-1 at 0.3 h 0.84 -> 0.78)
    tangent_weak_step: float = 0.25
    #: ... where the lone branch's side holds at most 1 / this many times the samples per length
    #: of the other (unitless: one curve against two gives 2)
    #: origin: below the ratios at the tangent kind's junctions under noise 0.2 h (1.7-2.5);
    #: no other value measured
    tangent_ratio: float = 1.5
    #: ... and only where the step lies over this many spacings from the node (h): nearer, the
    #: node is as sure as the step (whose error on the tangent kind at noise 0.2 h is at most
    #: 1.7 h over 8 samplings)
    #: origin: benchmark (928-run harness): 1 h 24 better / 10 worse (neuron forks at noise 0.2 h
    #: moved 2-2.5 h off: nrn_c12877), 2 h 23 / 8, 2.5 h 20 / 6 (kinds at noise 0.2 h equal)
    tangent_keep: float = 2.0
    #: ... counting a branch's samples from its end out while it runs within this cosine of that
    #: direction (unitless; 0.5: 60 degrees, beyond the band's 49), measured on the chord to the
    #: sample ``tangent_lag`` samples back
    #: origin: the fillet of the tangent kind (radius 10 h, its edge square to the line after
    #: the arc): counting every branch sample within the window left its junction 4-13 h off in
    #: 5 of 8 samplings at noise 0.2 h, the turn rule 1 of 8 (that one outside the band); no
    #: other value measured
    tangent_turn: float = 0.5
    #: ... that chord spanning this many samples (count; two spacings: under noise 0.2 h its
    #: direction wanders by about 8 degrees, one spacing's by about 16)
    #: origin: set with the turn rule from that wander; no measurement of this value
    tangent_lag: int = 2


NODES = Nodes()


class Curves(NamedTuple):
    """Stage 8: curves (:mod:`.curves`)."""

    #: two successive steps of a curve more than 120 degrees apart (cosine below) turn back
    #: origin: benchmark: corners under noise 0.3h + x3 F1 0.67 -> 1.00 (444e1bc)
    turn_back_cos: float = -0.5
    #: the reach (in points along the curve) of one reordering move of the untangle kernel
    #: origin: benchmark: 32 -> 64, corners 8 of 8 samplings exact (9f5c6f3)
    untangle_w: int = 64
    #: node and curve order: coordinates rounded to this many decimals
    #: origin: first version (3e727c1): an ordering convention, only the order depends on it
    round_decimals: int = 9
    #: an interior sample farther than this many (spacing + noise scale) from the chord of its
    #: two neighbours is a spike (an outlier taken into the curve) and is dropped; a 30-degree
    #: corner sits 0.97 spacing from that chord
    #: origin: benchmark: outliers 2% + noise 0.1h, curve F1 0.983 -> 1.000 (55a389d)
    spike: float = 1.5


CURVES = Curves()


class Fit(NamedTuple):
    """Stage 8, under noise: each curve fitted by a penalised smoothing spline through its
    samples (:func:`.curves.fit_curves`)."""

    #: the derivative whose square the fit penalises: 3 leaves quadratics unpenalised (a bend
    #: of steady curvature is fitted with the bias of a sixth-order kernel: on a circle of
    #: radius R sampled every h, a fit of width b spacings pulls it in by about
    #: R (b h / R)^(2 order)); 2, the cubic smoothing spline (Reinsch 1967) used before, pulls
    #: bends in as (b h / R)^4 and so had to narrow on every bend (benchmark)
    #: origin: benchmark (issue 25, 6 December 2026): benchmarks/fit_eval.py --samplings 4, with
    #: the candidate widths below: mean distance to the true curves 0.045, 0.085, 0.125, 0.136
    #: -> 0.042, 0.082, 0.126, 0.135 h at noise 0.1, 0.2, 0.3 h and 0.3 h + x3, models over half
    #: a noise deviation 4, 4, 4, 5 -> 3, 2, 3, 5; the 8 kinds and the 20 real-dev networks
    #: closer too (order 2 with the same width choice: synthetic worse); see docs/method.md,
    #: stage 8
    order: int = 3
    #: widest kernel of the fit, in local spacings (the equivalent kernel of the smoothing
    #: spline, Silverman 1984: it averages about this many samples on either side), the width
    #: on straight and gently bent stretches (benchmark)
    #: origin: benchmark: benchmarks/fit_eval.py, the distance to the true curves (71dc5cf: 4 for
    #: ``order`` 2; 6 December 2026: 5, 6 and 8 for ``order`` 3 with the width extrapolated
    #: from the widest fit, 5 taken: the knot 0.45, 0.51, 0.58 deviations at noise 0.1 h)
    band: float = 5.0
    #: narrowest kernel, in local spacings: the width at sharp bends and corners (benchmark)
    #: origin: benchmark: benchmarks/fit_eval.py, the distance to the true curves (71dc5cf; 1,
    #: 1.5 and 2 again with ``order`` 3, 6 December 2026: 1.5)
    band_min: float = 1.5
    #: the number of candidate widths, geometric from ``band_min`` to ``band`` (each one a
    #: solve of the whole system: the fit's time grows with it): each sample takes the one of
    #: least estimated squared error (``curves._widths``)
    #: origin: benchmark (issue 25, 6 December 2026): 4, 5 and 7 candidates over the 16
    #: synthetic models, the 8 kinds and the 20 real-dev networks at noise 0.1 h, 0.2 h and 0.3 h
    #: + x3: the same to 0.007 noise deviations; 4 the cheapest
    widths: int = 4
    #: within a few samples of a held end (a node) the kernel is at most this many spacings wide
    #: per sample from the end (benchmark)
    #: origin: benchmark: benchmarks/fit_eval.py, the distance to the true curves (71dc5cf;
    #: 0.5, 0.7 and 1 again with ``order`` 3, 6 December 2026: 1, see docs/method.md)
    end_taper: float = 1.0
    #: a candidate width's squared bias at a sample is the larger of the mean squared parting
    #: of its fit from the narrowest over this many of its reaches on either side (short: a
    #: corner's bias stays local) ...
    #: origin: the reach of the widest kernel (71dc5cf): a window of one kernel width
    bias_reach: float = 1.0
    #: ... and over this many (long: the parting of the two fits is correlated over about one
    #: kernel width, so the short window holds about two independent values of it and its mean
    #: follows the noise; three reaches hold about six). On smooth curves the width then follows
    #: the bend, not the noise: over the 16 synthetic models at noise 0.1 h the mean distance
    #: to the true curves 0.0525 -> 0.0465 h (knot 0.075 -> 0.048, fig8 0.060 -> 0.039)
    #: origin: benchmark: benchmarks/fit_eval.py (issue 25, 4 December 2026): 2, 3 and 4 reaches
    #: alone and 3 with the short window (taken): see docs/method.md, stage 8
    bias_reach_long: float = 3.0
    #: a corner (``curves._corners``) is read over this many samples on either side of a
    #: sample
    #: origin: benchmark (issue 25, 4 December 2026): the corner test's gain on the synthetic
    #: models at noise 0.1 h, 0.3 h and 0.3 h + x3, over 4 and 6 samples: see docs/method.md,
    #: stage 8
    corner_reach: int = 6
    #: ... where two lines meeting at the sample fit its window better than a parabola by this
    #: many noise variances (both models have three parameters a coordinate: on noise alone the
    #: gain is about a chi-square of 3 degrees of freedom; with the turn below and the best
    #: within a reach, few windows of a smooth curve pass)
    #: origin: benchmark (issue 25, 4 December 2026): the 16 synthetic models, 6 samplings at
    #: noise 0.1, 0.2, 0.3 h and 0.3 h + x3 (384 runs): corners found within 2 h of a true one
    #: 281 at 9, 265 at 12, 238 at 16; elsewhere 57, 49, 47 (mostly kinks of the unfitted
    #: curves near nodes); fit_eval at 9: corners 0.139 -> 0.126 h at noise 0.3 h
    corner_gain: float = 9.0
    #: ... and turn by at least this many degrees (a bend of a smooth curve over the window
    #: turns less and fits the parabola)
    #: origin: benchmark (as corner_reach)
    corner_turn: float = 30.0
    #: only the samples whose chords to the samples a reach away turn by this fraction of
    #: ``corner_turn`` are tested (speed: on the noisy tree a quarter of the samples instead of
    #: half; the chords' directions are off the hinge's lines by a few degrees of noise)
    #: origin: speed, checked: the corners found on the 16 synthetic models at four noise
    #: levels the same as with 0.5
    corner_chord: float = 0.75
    #: curves of fewer samples are left as they are (points: an open curve's two ends are held)
    #: origin: derived: a fit needs a sample between the two held ends
    min_points: int = 3
    #: a step between two samples counts as at least this fraction of the curve's median step
    #: (repeated samples: the divided differences stay finite)
    #: origin: a rounding guard, not a tuning (71dc5cf)
    step_floor: float = 1e-3


FIT = Fit()


class Untangle(NamedTuple):
    """Windowed 2-opt of a curve's points (``kernels/chains.py``, :func:`_untangle`)."""

    #: most sweeps per curve
    #: origin: a cap on the iterations, set with the untangle kernel (444e1bc); no measurement
    #: recorded
    sweeps: int = 50
    #: a reversal is made when it shortens the polyline by more than this fraction of the
    #: step it replaces (unitless; rounding guard)
    #: origin: a rounding guard, not a tuning
    min_gain: float = 1e-9
    #: curves with fewer points are left as they are (points: a reversal needs two inner ones)
    #: origin: derived: a reversal needs two inner points
    min_points: int = 4


UNTANGLE = Untangle()


class Skipped(NamedTuple):
    """Stage 8c: a free spur that is the skipped first stretch of a neighbouring curve
    (:mod:`.skipped`)."""

    #: a spur (a curve from a junction to a free end) is read as a skipped stretch only when it
    #: is at most this many spacings long
    #: origin: benchmark (issue 25, 5 December 2026): the spurs seen on real neurons (zigzags of
    #: 50-110 degree turns every 2 h) were 2.9-5.5 h long (8 h first); on the neurites kind at
    #: noise 0.1 h spurs of 8.5 h that jump over a zigzag's lost samples: 12 h, with ``search``,
    #: 6 more networks better and none worse on the 832-run harness, one CASSIE sketch better
    spur: float = 12.0
    #: the samples bridging the spur's tip to the curve's first sample lie no nearer the node
    #: than the nearer of the two, less this many spacings (the bridge runs outside the
    #: junction's own samples)
    #: origin: set with the stage, not tuned: half a sample step
    clearance: float = 0.5
    #: the samples of a bridging path are searched within this many spacings of the spur's tip
    #: (at least: farther when the curve's first sample lies farther)
    #: origin: set with the stage, not tuned: a skipped stretch about as long as a spur
    search: float = 12.0
    #: where the curve's first sample lies nearer the node than the spur's tip, the bridging
    #: path must be longer than the way through the node by this many spacings (it runs around
    #: the junction; a path straight through it is no skipped stretch)
    #: origin: set with the stage (issue 25): on the twigs model (clean) a path straight
    #: through a junction was 0.5 h longer than the way through the node; around a real
    #: zigzag's junction 3 h
    around: float = 2.0


SKIPPED = Skipped()


class Excursion(NamedTuple):
    """Stage 8d: a curve that runs out along a twig and back (:mod:`.excursions`)."""

    #: the twig's tip: the curve turns there by more than about 107 degrees (cosine under this)
    #: origin: benchmark (issue 25, 5 December 2026): the tips seen on the twigs kind turn by
    #: 110-160 degrees (cosine -0.34 to -0.94)
    turn_cos: float = -0.3
    #: the step the excursion interrupts: its two samples at most this many spacings apart ...
    #: origin: benchmark (issue 25): the steps seen on the twigs kind were 1.0-1.4 h (one 1.8 h);
    #: 2.5 h (the link length) also cut real neurons' narrow hairpins and the neurites' zigzags
    #: (832-run harness 55 better, 50 worse), 1.5 h: 52 better, 8 worse
    gap: float = 1.5
    #: ... plus this many times the noise
    #: origin: benchmark (issue 25): 2 cut a real neuron's hairpin at noise 0.2h (a step of
    #: 1.86 h); 1: 52 better, 8 worse with ``gap``
    gap_noise: float = 1.0
    #: the curve's direction into and out of the step, over this many samples (samples)
    #: origin: set with the stage, not tuned
    dir_samples: int = 2
    #: a curve of fewer samples holds no excursion: the directions' samples on both sides, the
    #: step's two samples and a tip between them (samples)
    #: origin: derived: ``2 dir_samples + 3``
    min_samples: int = 7
    #: ... agree within about 45 degrees (cosine): the curve runs on straight across the step
    #: origin: set with the stage, not tuned (0.9: the twigs kind at noise 0.2h 0.62 -> 0.60)
    through_cos: float = 0.7
    #: the excursion reaches this many spacings off the step (a twig of 3 h leaving at 50
    #: degrees reaches 2.3 h)
    #: origin: set with the stage, not tuned
    height: float = 2.0
    #: ... within this many spacings of arc on either side of the tip (the skipped-stretch
    #: stage's longest spur)
    #: origin: set with the stage, not tuned
    reach: float = 12.0
    #: one side of the tip, from the step's sample to the tip, holds at most this many samples
    #: (the way back from a twig's tip: the jump, or a few samples) (samples)
    #: origin: set with the stage, not tuned: the ways back seen on the twigs kind held 1-2
    back_samples: int = 4
    #: ... the other at most this many (the twig's samples; implementation bound of the
    #: vectorised test, above the samples of ``reach`` spacings at the benchmark's densities)
    #: origin: set with the stage, not tuned
    long_samples: int = 40
    #: the twig's tip is a free end: no sample (but the twig's) lies a step (``gap``) from it
    #: within about 60 degrees (cosine) of the twig's direction; else the curve goes on there
    #: origin: set with the stage (issue 25): the plate kind at noise 0.2h ran 3 h along a curve
    #: between two junctions and back (curve F1 0.238 -> 0.227 without the test)
    ahead_cos: float = 0.5
    #: its samples lie within this many spacings of their principal line ...
    #: origin: set with the stage, not tuned
    line: float = 0.5
    #: ... plus this many times the noise
    #: origin: set with the stage, not tuned
    line_noise: float = 2.0
    #: the twig's line and the curve's are parallel when the squared sine of their angle is under
    #: this (the junction then sits at the first twig sample's foot on the curve's line)
    #: origin: a rounding guard, not a tuning
    parallel: float = 1e-6


EXCURSION = Excursion()


class WalkIn(NamedTuple):
    """Stage 8e: a curve that jumps from its junction's node over samples of no curve
    (:mod:`.walkins`)."""

    #: the path through the samples of no curve ends this many spacings from the node or nearer
    #: (it arrives at the junction)
    #: origin: set with the stage (issue 25), the metric's curve tolerance (2 h): nearer than
    #: that the last straight step is within it. 832-run harness with this and ``off``: 9
    #: networks better (neurites kind under noise, e.g. noise 0.1 h 0.65 -> 0.75), none worse
    arrive: float = 2.0
    #: the path is taken when one of its samples lies over this many spacings off the straight
    #: line from the first sample to the node (nearer, the line is within the curve tolerance)
    #: origin: set with the stage (issue 25), the metric's curve tolerance; with 1 h, and the
    #: first sample read from 2-3 h out instead of beyond the shell, clean neurites and tangent
    #: junctions lost curves (a node placed 1.7 h off, the walk then hooked to it; the other
    #: branch's samples beside a tangent one): 11 better, 10 worse
    off: float = 2.0


WALKIN = WalkIn()


class Unexplained(NamedTuple):
    """Stage 9: branches the finished network leaves unexplained (:mod:`.unexplained`). The
    band of unexplained points (``explain``, ``explain_noise``), the fewest samples of a branch
    (``min_samples``) and its rise (``rise``) are read in stage 6 too, where a short twig is told
    from samples that noise hangs off a curve (:func:`.repairs._twig`,
    :func:`.branched.split_tails`)."""

    #: a point farther than this many spacings from every curve ...
    #: origin: benchmark (issue 25, 5 December 2026, with the fields below): the tip of a 3 h
    #: twig leaving at 50 degrees lies 2.3 h from its parent; a noise-free sample lies on its
    #: curve, a noisy one within about 3 standard deviations
    explain: float = 1.2
    #: ... plus this many times the noise (2.5 noise scales: 3 standard deviations) is unexplained
    #: origin: as ``explain``
    explain_noise: float = 2.5
    #: unexplained points within this many spacings of each other form one group (one branch
    #: at most per group, from its point farthest from the network)
    #: origin: set with the stage, not tuned: about two sample steps
    group: float = 2.0
    #: a branch's path ends at a sample within this many spacings of a curve ...
    #: origin: set with the stage, not tuned
    near: float = 0.5
    #: ... plus this many times the noise
    #: origin: as ``explain_noise``
    near_noise: float = 2.5
    #: a branch's path is at most this many spacings long (the samples searched lie within this
    #: distance of its tip)
    #: origin: set with the stage, not tuned: the twigs of the kinds and neurons are 3-6 h
    search: float = 14.0
    #: the fewest samples of a branch's path (its explained end included; the path through
    #: every sample, since 5 December 2026, see ``tip_short``): fewer are stray points (2%
    #: outliers land near curves too)
    #: origin: benchmark (issue 25, 5 December 2026; a first version of the stage, run after the
    #: method, on 832 runs of the kinds, real-dev and synthetic models under noise, outliers and
    #: density x3): 3 samples 46 networks better, 27 worse (curve F1 summed +6.1); 4 samples 19
    #: better, 20 worse (+1.5)
    min_samples: int = 3
    #: a branch's tip lies at least this many times its path's length from the network: a
    #: branch leaves the network; a path alongside a curve (a stretch the network passes a
    #: little off, a bend it cuts) is no branch
    #: origin: benchmark (issue 25, 5 December 2026; the first version, as ``min_samples``):
    #: without the test 43 better, 47 worse (+4.9: branches along real neurons' wiggles under
    #: noise 0.1 h); with 0.5 46 better, 27 worse (+6.1)
    rise: float = 0.5
    #: a branch reaches at least ``min_spur`` spacings plus this many times the noise from where
    #: it joins, and its tip lies as far from every other node: noise scatters the samples around
    #: a junction by this much (where the points are sampled densely, ``min_spur`` local spacings
    #: are less than the scatter)
    #: origin: benchmark (issue 25, 5 December 2026): without it three of the sweep's 576 networks
    #: lost their exact topology (eye, fan, tree at noise 0.3 h + x3: a branch of 2-4 samples 2.3 h
    #: from a junction placed 2 h off the true one)
    length_noise: float = 2.5
    #: ... less this many spacings for the branch's own reach from its foot: its last sample lies
    #: up to one spacing short of the curve's true end, so a twig ``min_spur`` spacings long
    #: reaches ``min_spur - 1`` to ``min_spur`` (its tip's distance from other nodes keeps the full
    #: bound). Taken with the detour test (``unexplained._other_leg``: unexplained samples near
    #: the tip off the branch's own, the curve going out and back) and the sample count on the
    #: path through every sample
    #: origin: benchmark (issue 25, 5 December 2026; 928 + 352 runs of the harness): with the
    #: three changes 27 better, 7 worse (twigs at noise 0.2 h: 7 of 8 samplings better, e.g. 0.709
    #: -> 0.819; ladder at noise 0.2 h s1, s6 and plate at 0.3 h + x3 worse); without the detour
    #: test real neurons gained false twigs (nrn_CTh5080328L_s4 at noise 0.1 h 0.714 -> 0.500:
    #: 2-3 h corners of a tortuous neurite); without this allowance (0) 12 better, 10 worse
    tip_short: float = 1.0
    #: a branch joining a curve within this many spacings (along it) of one of its nodes joins
    #: that node instead of cutting the curve
    #: origin: set with the stage, not tuned: a node placed within 2 h of a junction matches it
    snap: float = 2.0
    #: a branch's direction at its foot: from its sample this many steps along its path to its
    #: first sample off the network
    #: origin: set with the stage, not tuned
    foot_samples: int = 3
    #: a branch's tip is a free end: the mean of the unit vectors from it to the samples within
    #: ``min_spur`` spacings is at least this long (samples on one side); where samples lie on both
    #: sides the unexplained points are a stretch of a curve the network missed or merged
    #: with another, and no branch
    #: origin: benchmark (issue 25, 5 December 2026; 832 runs as ``min_samples``): without the
    #: test 46 better, 53 worse (+6.3; real neurons under noise got branches along curves the
    #: network had merged); with 0.5 over the link length 39 better, 27 worse (+6.7); over
    #: ``min_spur`` with ``end_points`` (the stage as landed) 39 better, 19 worse (+6.75)
    end: float = 0.5
    #: ... read on at least this many samples (fewer: no end, nothing to read it on)
    #: origin: set with the stage, not tuned: a neuron's branch whose tip had one sample within
    #: the link length of it (a junction the earlier stages merged with another, 1.8 h away)
    end_points: int = 2
    #: implementation setting (results never depend on it): the pairs of points within their
    #: radii are searched with the largest radius at once when it is at most this many times
    #: the median radius, else point by point within each point's own radius
    #: origin: speed, checked: 576 runs of the kinds and real-dev the same either way
    pair_spread: float = 4.0


UNEXPLAINED = Unexplained()


class Numeric(NamedTuple):
    """Rounding tolerances (not thresholds of the method: they make equal values compare equal)."""

    #: relative tolerance of a comparison against a computed bound (unitless)
    #: origin: a rounding guard, not a tuning
    rel: float = 1e-9
    #: a looser one, for bounds of prefilters (the exact test follows; unitless)
    #: origin: a rounding guard, not a tuning
    rel_loose: float = 1e-6
    #: a projection above minus this is ahead (input length units)
    #: origin: a rounding guard, not a tuning
    ahead: float = 1e-12
    #: the smallest positive length (divisions and zero-length edges)
    #: origin: a rounding guard, not a tuning
    tiny: float = 1e-300


NUMERIC = Numeric()


class Linalg(NamedTuple):
    """Small dense solvers of the kernels (``kernels/linalg.py``): eigenpairs of (d, d)
    scatter matrices by Jacobi sweeps or in closed form, weighted PCA."""

    #: most cyclic Jacobi sweeps (a 3 x 3 matrix converges in about 5; a safety bound)
    #: origin: a cap, set with the compiled PCA (9b95206); converged runs never reach it
    jacobi_sweeps: int = 60
    #: Jacobi stops when the off-diagonal sum is below this fraction of the diagonal sum
    #: (unitless; about 1e-14 of double precision's range squared: fully converged)
    #: origin: a rounding guard, not a tuning: fully converged in double precision
    jacobi_tol: float = 1e-30
    #: a rotation angle ratio ``theta`` above this is treated as infinite, ``t = 1 / (2 theta)``
    #: (unitless; Numerical Recipes' guard against overflow of ``theta^2``)
    #: origin: Numerical Recipes (above), not a tuning
    theta_max: float = 1e150
    #: the closed-form top eigenpair leaves a top eigenvalue closer than this (relative to the
    #: size of the eigenvalues) to the next one to the Jacobi sweeps: its direction is
    #: ill-defined there (unitless; former ``TOP_GAP``)
    #: origin: set with the closed-form eigenpair (e9fe7c8); no measurement recorded
    top_gap: float = 1e-3
    #: most Newton steps for the largest root of the 3 x 3 characteristic polynomial (it
    #: decreases monotonically from an upper bound; a handful suffice, a safety bound)
    #: origin: a cap, set with the closed form (e9fe7c8); converged runs never reach it
    newton_steps: int = 100
    #: the largest size ``d`` of a matrix whose top eigenpair ``_eig_top`` finds in closed form
    #: (its characteristic polynomial a cubic; the points are 2D or 3D); larger ones take the
    #: Jacobi sweeps (a property of the code, not a tuning)
    #: origin: a property of the code (above)
    closed_dim: int = 3
    #: floor of a divisor that may vanish (a sum of weights, a top eigenvalue, a length): any
    #: positive double far below the data's scale (unitless)
    #: origin: a rounding guard, not a tuning
    tiny: float = 1e-300


LINALG = Linalg()
