"""The robust, parameter-free default method ("robust").

Outline (every radius is in units of the *local* sampling spacing ``h_i``; "noise" below is
``NOISE`` times the estimated noise standard deviation, 0 on clean data):

1. **Spacing.** ``h_i`` is the mean distance to the 4 nearest neighbours divided by 1.5 (on a
   uniformly sampled curve the 4 nearest lie at h, h, 2h, 2h), smoothed by the median over the
   point and its 8 nearest neighbours; neighbours under ``DUP`` times that spacing (the same
   place sampled twice, e.g. overlapping strokes), or under ``DUP_K`` times the 16th neighbour's
   distance over 8 (several curves ending on one sample), are skipped. Density may vary along
   the curves.
2. **Tangents and noise.** A first direction from the 4 nearest neighbours (where their PCA is
   not clearly linear, the direction towards one of them when a narrow strip along it holds
   clearly more points: a close parallel curve under two spacings away can pull the PCA across)
   is refined twice by
   the PCA of the 12 nearest lying within one spacing of its line (a strip that leaves out a
   close parallel curve); the linearity ``1 - l2 / l1`` is that of the strip. A tangent at odds
   (over 10 degrees) with a coherent vote of its 8 neighbours' tangents is replaced by the vote
   (noise can throw a tangent across close parallel curves). The noise standard deviation is the
   median distance of a point from the chord of its nearest strip neighbours on either side,
   scaled for Gaussian noise (curvature adds only h^2 / 2R there; reported as ``noise``).
3. **Linked graph.** A link up to ``link * h`` long is kept when its far end lies within
   ``max(link_width * h, NW * noise)`` of the tangent line through one of its ends (or an end has
   no reliable tangent); links up to ``link * h + GAP * noise`` long must lie along both tangents;
   each point is also linked to its nearest strip neighbour on either side along its tangent
   (this bridges the random gaps of sparse, noisy sampling). Two close parallel curves and the
   two sides of an acute angle stay apart.
4. **Shell test.** Around each point, the points reached through the linked graph within a
   geodesic distance of ``shell_outer * (h + WIDEN * noise)`` are collected; those at least
   ``shell_inner * (h + WIDEN * noise)`` away, both along the graph and in space, form the shell;
   its connected groups that reach the middle of the shell along the graph are counted: 1 at a
   free end, 2 on a curve (a sharp or acute corner included), 3 or more near a junction.
5. **Regions and chains.** Points whose count is not 2 are grouped (links shorter than
   ``link * h``) into regions. A region too large for one junction (two junctions closer than
   about two shell radii) is re-tested on a shell 0.7 times the size and split when that shows
   two junctions and one chain between them. The remaining points fall apart into chains, one
   per curve segment. Each chain is ordered by geodesic distance from one end (Dijkstra on the linked
   graph) and attached to the regions its two ends touch (a short chain given the same region
   at both ends takes the other region it touches at that side); a chain with no region at
   either end is a closed loop (cut open at its straightest point) or an open piece, and a chain
   still cyclic in the linked graph (its order would zigzag) is a loop cut open at the region it
   touches.
6. **Repairs** (what noise and sparse sampling break): a region passed through by one curve
   right next to a junction region joins it (a crossing split in two); a short chain leaving a
   region and coming back is absorbed; a flagged clump touching no chain joins the free end beside
   it; a free end whose node would sit within a gap of a junction region joins that junction;
   two facing free ends are one curve; a free end stopping within a link reach ahead of another
   chain splits it into a junction (a T whose stem lost its link); two junctions joined by a
   chain under ``MERGE_LEN`` spacings merge when the other branches of one aim at the other's node
   within a strip or 10 degrees (two branches of one junction that ran together for a while; short loops this leaves are
   absorbed as above). Short spurs (a chain from a junction to a free end shorter than
   ``min_spur * h``) and small isolated clumps are dropped.
7. **Network.** A region touched by one chain end is a free end: its points extend the chain and
   the node is the extreme point. A region touched by 2 ends is no node (the chains are joined
   through it; a chain joined to itself is a closed loop). A region touched by 3 or more is a
   junction: every incident branch is walked into the region (each round, the nearest proposals
   first, so the order of the branches does not matter; a walk stops where it strays
   ``WALK_DEV`` link widths from its branch's line), its line is fitted on its last
   ``JSPAN h + JN noise``, and the node is the least-squares intersection of those lines. Chain
   points lying behind their junction node (an overshoot into another branch) are trimmed, and
   every curve ends exactly at its nodes.
8. **Smoothing** (``smooth=True``): each curve is replaced by a smoothing spline (scipy
   ``splprep``) pinned at its end nodes and evaluated densely.

The result does not depend on the order of the input points: they are sorted by coordinates
first and every tie is broken by that order. The module constants below are fixed (not tuned
per input); every user-facing radius is a keyword of :func:`reconstruct_robust`.
"""

from __future__ import annotations

import functools
import itertools
import time

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from . import kernels as _k
from ... import _sigint
from ...errors import InputError
from ...network import Curve, CurveNetwork
from ...neighbors import build_tree, knn, locality_order
from ...validate import as_points

__all__ = ["reconstruct_robust", "local_spacing", "shell_group_counts"]

#: Length (in spacings) of the chain end that gives a chain's direction (trim, old fits).
SPAN = 6.0
#: Length (in spacings) of the walked branch end fitted for the junction node.
JSPAN = 4.0
#: ... plus this many times the noise scale (a longer fit averages the noise out).
JN = 6.0
#: A walk into a junction stops where it strays this many link widths from its line.
WALK_DEV = 1.25
#: The noise scale of the radii below: this many times the estimated noise std.
NOISE = 1.2
#: Links may stray from a tangent line by this many times the estimated noise.
NW = 4.5
#: The shell radii grow by this many times the estimated noise (in units of ``shell_*``).
WIDEN = 1.5
#: Links may be longer than ``link * h`` by this many times the estimated noise.
GAP = 3.0
#: Junctions joined by a chain at most this many spacings long may be one junction.
MERGE_LEN = 8.0
MERGE_TAN = float(np.tan(np.radians(10.0)))
#: Such a chain sampled DENSE times as densely as the median or more is two strokes run
#: together: its length is measured in median spacings, and when the other junction is a hub
#: of HUB_VAL curves or more, the branches may aim at it within MERGE_TAN_HUB (20 degrees:
#: strokes drawn into a pole part from each other bent).
DENSE = 1.5
HUB_VAL = 5
MERGE_TAN_HUB = float(np.tan(np.radians(20.0)))
#: Directional links (nearest along the tangent) reach this many times the link length.
EXTRA = 2.0
#: A region point beyond this fraction of the shell radius from its junction node, in a
#: direction no incident branch takes (cosine under SWALLOW_COS), is a swallowed branch's tip.
SWALLOW = 0.8
SWALLOW_COS = float(np.cos(np.radians(25.0)))
#: A free end's region holds a fork when a point lies this many shell radii from the path
#: to its farthest point.
FORK = 0.6
#: Below this linearity a point has no reliable tangent and its links are kept.
LIN = 0.3
#: A chain whose points, ordered by distance from one end, form a polyline this many times
#: longer than that distance is a cycle of the linked graph (ordered, it would zigzag).
ZIGZAG = 4.0
#: A chain end is the region most in contact with the chain within this many spacings of it
#: (or half the chain, if shorter; robust._chain_ends).
SHORT_REACH = 4.0
#: A neighbour closer than DUP times the first spacing estimate, or DUP_K times the k-th
#: neighbour distance over k / 2, is a duplicate sample.
DUP = 0.1
DUP_K = 0.3
#: Noise-free samples (estimated noise under DEDUP_NOISE median spacings) closer than DEDUP
#: median spacings to an earlier sample (internal order) are dropped: overlapping strokes.
DEDUP = 0.3
DEDUP_NOISE = 0.05
#: Clouds of more points than this are numbered cell by cell inside (cache locality only: 6% at
#: 34,000 points, 15% at 1e6).
LOCAL_MIN = 20_000
_DEFAULTS = {
    "k": 16,
    "shell_inner": 2.5,
    "shell_outer": 5.5,
    "link": 2.5,
    "link_width": 1.0,
    "min_spur": 3.0,
}


# ---------------------------------------------------------------------------------- stages
def local_spacing(dist: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Local sampling spacing of every point.

    Parameters
    ----------
    dist, idx : (N, k) ndarray
        Distances and indices of the k nearest neighbours (self excluded), k >= 4.

    Returns
    -------
    (N,) ndarray of float
        Mean distance to the 4 nearest neighbours divided by 1.5, median-smoothed over the point
        and its 8 nearest neighbours. Neighbours closer than ``DUP`` times that first mean are
        the same place sampled twice (overlapping strokes, a curve given twice): they are
        skipped and the mean is taken over the next ones, so that coincident samples do not
        shrink the spacing (and every radius) below the gaps along the curve. So are those
        closer than ``DUP_K`` times the k-th neighbour's distance over k / 2 (about one
        spacing on a curve): several curves ending on one sample make the first mean tiny.
    """
    if _k.compiled_active() and dist.shape[1] <= 128:
        # compiled, one pass over the rows, the same numbers as the numpy formula below
        h = _k.spacing(np.ascontiguousarray(dist, dtype=np.float64), np.ascontiguousarray(idx, dtype=np.int64),
                       float(DUP), float(DUP_K))
        return _spacing_floor(h)
    m = min(4, dist.shape[1])
    div = 1.5 if m >= 4 else 1.0
    raw = np.empty(len(dist))
    step = 1 << 16  # rows at a time: the (rows, k) temporaries stay small at any N
    for a in range(0, len(dist), step):
        D = dist[a:a + step]
        raw0 = D[:, :m].mean(axis=1) / div
        # several samples at one place (curves ending at one node) make raw0 tiny: the k-th
        # neighbour, about k / 2 spacings away on a curve, sets a floor to the duplicate test
        thr = np.maximum(DUP * raw0, DUP_K * D[:, -1] / (0.5 * D.shape[1]))
        keep = D >= thr[:, None]
        sel = keep & (np.cumsum(keep, axis=1) <= m)
        cnt = sel.sum(axis=1)
        raw[a:a + step] = np.where(cnt >= m, np.where(sel, D, 0.0).sum(axis=1) / np.maximum(cnt, 1) / div, raw0)
    j = min(8, idx.shape[1])
    h = np.empty(len(dist))
    for a in range(0, len(dist), step):
        R = np.concatenate([raw[a:a + step, None], raw[idx[a:a + step, :j]]], axis=1)
        if R.shape[1] % 2:  # an odd count: the median is the middle value (partition is faster)
            h[a:a + step] = np.partition(R, R.shape[1] // 2, axis=1)[:, R.shape[1] // 2]
        else:
            h[a:a + step] = np.median(R, axis=1)
    return _spacing_floor(h)


def _spacing_floor(h):
    """``h`` raised to a thousandth of its smallest positive value (coincident clouds)."""
    pos = h[h > 0]
    floor = (pos.min() if len(pos) else 1.0) * 1e-3
    return np.maximum(h, floor)


def _tangents(P: np.ndarray, idx: np.ndarray, h: np.ndarray, m: int = 12, order=None, margin=None):
    """Local tangent and linearity of each point.

    A first direction from the 4 nearest neighbours (or towards one of them, when its narrow
    strip holds clearly more points: a close parallel curve can pull the PCA across) is refined
    by a PCA of the ``m`` nearest that lie within one spacing of its line (a strip that leaves
    out a close parallel curve). The linearity ``1 - l2 / l1`` is that of the last strip PCA.
    ``order``: the points to do (all, in this order; or a subset, the others get zeros);
    ``margin``: the score a neighbour's direction needs above the 4-neighbour direction's
    (default: the kernels' ``CAND_MARGIN``).

    Returns
    -------
    t : (N, d) ndarray
        Unit tangents.
    lin : (N,) ndarray
        Linearity.
    rms : (N,) ndarray
        Noise estimate of each point (NaN where there is none).
    gain : (N,) ndarray
        How much more a neighbour's direction scores than the 4-neighbour direction (``-inf``
        where none was tried); see :func:`_retry_tangents`.
    """
    m = min(m, idx.shape[1])
    # compiled, one point at a time: the 4-neighbour PCA, then twice the PCA of the point and
    # its m nearest within h of the current line (weights 0/1: a weighted PCA, whose numpy
    # formula on stacked arrays is the reference of tests/test_robust_kernels.py);
    # and the noise: distance of each point from the chord between its nearest strip neighbours
    # on either side (NaN without both; curvature adds only h^2 / 2R there); for Gaussian
    # noise of std sigma per coordinate its RMS is sigma * sqrt(1.5 (d - 1))
    t, lin, cr, gain = _k.tangents(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(idx, dtype=np.int64),
                                   np.ascontiguousarray(h, dtype=np.float64), m, order, margin=margin)
    dim = P.shape[1]
    # (x 1.28: picking the nearest neighbour on each side favours points pulled towards p)
    rms = 1.28 * cr / np.sqrt(1.5 * max(dim - 1, 1))
    return t, lin, rms, gain


#: on noise-free input a neighbour's direction replaces the 4-neighbour direction when it scores
#: this much more (under noise, the kernels' CAND_MARGIN): a sparse curve between two close
#: parallel curves has its 4 nearest neighbours half across, and its true direction scores only a
#: little more; under noise the smaller margin turns tangents at sharp corners onto one leg
CAND_MARGIN_CLEAN = 1.5


def _retry_tangents(P, idx, h, t, lin, gain, m: int = 12):
    """Tangents of noise-free input: the points whose best neighbour direction scores between
    :data:`CAND_MARGIN_CLEAN` and the kernels' margin more than the 4-neighbour direction are
    done again with the smaller margin (few points: near close curves, junctions, corners)."""
    redo = np.flatnonzero((gain > CAND_MARGIN_CLEAN) & (gain <= _k.CAND_MARGIN))
    if len(redo) == 0:
        return t, lin
    t2, lin2, _, _ = _tangents(P, idx, h, m, order=redo, margin=CAND_MARGIN_CLEAN)
    t = t.copy()
    lin = lin.copy()
    t[redo] = t2[redo]
    lin[redo] = lin2[redo]
    return t, lin


VOTE_COS = np.cos(np.radians(10.0))
#: neighbours in the tangent vote; under noise (estimated noise at least DEDUP_NOISE median
#: spacings) VOTE_M_NOISY
VOTE_M = 8
VOTE_M_NOISY = 16
VOTE_COH = 0.6


def _vote_tangents(t, lin, idx, m=8):
    """Tangents by a vote of the point and its ``m`` nearest neighbours (tensor sum of t t^T).

    A tangent thrown across close parallel curves by noise is outvoted by its neighbours'.
    The linearity becomes the smaller of the point's own and the vote's coherence
    ``1 - l2 / l1`` (low at junctions, where neighbours vote for different branches).
    """
    m = min(m, idx.shape[1])
    # only a tangent clearly at odds with a coherent vote is replaced. With C = sum T_k T_k^T,
    # eigenvalues l1 >= l2 and l1 <= m + 1: a swap needs |u.t| < c (u the top eigenvector) and
    # l2 <= (1 - VOTE_COH) l1, hence t^T C t <= (m + 1) (c^2 + (1 - VOTE_COH) (1 - c^2)); the
    # eigen-decomposition is computed only for the points below that bound (few on clean data);
    # t^T C t = sum_k (T_k . t)^2 is computed in a compiled loop (no (N, m + 1, d) array)
    agree = _k.vote_agreement(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(idx, dtype=np.int64), m)
    bound = (m + 1) * (VOTE_COS**2 + (1.0 - VOTE_COH) * (1.0 - VOTE_COS**2))
    cand = np.flatnonzero(agree <= bound * (1 + 1e-9))
    if len(cand) == 0:
        return t, lin
    # the top eigenpair of C for the candidates (compiled, closed form: _robust_kernels._eig_top)
    u, coh = _k.vote_eig(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(idx, dtype=np.int64), m,
                         cand.astype(np.int64))
    swap = (np.abs(np.einsum("nd,nd->n", u, t[cand])) < VOTE_COS) & (coh >= VOTE_COH)
    sw = cand[swap]
    t = t.copy()
    lin = lin.copy()
    t[sw] = u[swap]
    lin[sw] = np.minimum(lin[sw], coh[swap])
    return t, lin


#: neighbours of the noisy tangents (see _noisy_tangents)
NOISY_K = 32
#: points per block of the noisy tangents' own neighbour query (its rows are not kept)
NOISY_BLOCK = 1 << 16


def _noisy_tangents(P, h, sig, tree, dist, idx):
    """Tangents and linearity of a noisy cloud found over a longer reach
    (:func:`_robust_kernels._noisy_tangents`, over the ``NOISY_K`` nearest neighbours): the
    frames of the strand test (:func:`_cut_strand_links`).

    Where sparse, noisy curves run a few spacings apart, a point's nearest neighbours lie as
    often on the next curve as on its own, and the 4-neighbour start of :func:`_tangents` often
    points across (on the "eye" under noise 0.3h and density x3, after the vote: 8.6% of the
    points more than 30 degrees off; 0.1% with these). Used as the tangents of the whole method
    they cost the mug's junctions (bench samplings 0 and 1), so they serve this test only.

    The method's own neighbours (``dist``, ``idx``: (N, k), sorted by distance) serve the
    points whose last one (or ``NOISY_K``-th) lies beyond the kernel's reach
    (:func:`_robust_kernels.noisy_reach`): the farther ones would change nothing (on a lone
    curve, most points). The others get their ``NOISY_K`` nearest from ``tree``, in blocks.

    Returns
    -------
    T : (N, d) ndarray
    lin : (N,) ndarray
    """
    P = np.ascontiguousarray(P, dtype=np.float64)
    h = np.ascontiguousarray(h, dtype=np.float64)
    sig = float(sig)
    N = len(P)
    k = min(NOISY_K, N - 1)
    T = np.empty_like(P)
    lin = np.empty(N)
    kk = min(idx.shape[1], k)  # the method's neighbours the kernel may take
    if kk >= k:
        short = np.ones(N, dtype=bool)  # (as many as the kernel's)
    elif kk >= min(_k.NOISY_CAND, k) and kk > 0:
        short = dist[:, kk - 1] > _k.noisy_reach(h, sig)
    else:
        short = np.zeros(N, dtype=bool)
    rows = np.flatnonzero(short)
    if len(rows):
        T[rows], lin[rows] = _k.noisy_tangents(P, rows, np.ascontiguousarray(idx[rows, :kk], dtype=np.int64), h, sig)
    rows = np.flatnonzero(~short)
    for s in range(0, len(rows), NOISY_BLOCK):  # blocks: the (rows, 32) neighbour ids stay small
        r = rows[s:s + NOISY_BLOCK]
        _, nb = knn(P, k, tree=tree, rows=r)
        T[r], lin[r] = _k.noisy_tangents(P, r, nb, h, sig)
    return T, lin


def _cut_strand_links(P, h, idx, tn, src, dst, dd, sig):
    """The links without those that join two close parallel strands (noisy input).

    :func:`_robust_kernels._strand_cuts` finds them; a pair is cut in both directions.
    """
    if len(src) == 0:
        return src, dst, dd
    cut = _k.strand_cuts(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(h, dtype=np.float64),
                         np.ascontiguousarray(idx, dtype=np.int64), np.ascontiguousarray(tn, dtype=np.float64),
                         np.asarray(src, dtype=np.int64), np.asarray(dst, dtype=np.int64), float(sig))
    if not cut.any():
        return src, dst, dd
    n = np.int64(len(P))
    a, b = np.minimum(src, dst).astype(np.int64), np.maximum(src, dst).astype(np.int64)
    key = a * n + b
    keep = ~np.isin(key, key[cut])
    return src[keep], dst[keep], dd[keep]


def _linked_edges(P, h, dist, idx, t, lin, link, width, wmin=0.0, gap=0.0):
    """Directed kNN edges kept by the distance and tangent tests: (src, dst, length).

    A link is at most ``link * h + gap`` long (``gap`` widens it for noise, which opens random
    gaps along a curve). Besides, a point with a reliable tangent is linked to its nearest
    neighbour on each side along the tangent, within the strip, up to twice that length:
    this bridges the widest gaps of sparse, noisy sampling.
    """
    # compiled, one kNN row at a time (the tests are spelled out in _robust_kernels.linked_edges):
    # links at most EXTRA * (link * h + gap) long; the far end's distance from the tangent
    # line through either end within max(width * h, wmin) (or an end not linear, LIN); short
    # links need one tangent test, longer ones (up to link * h + gap) both; plus the nearest
    # strip neighbour on each side along the tangent (rows are sorted by distance)
    return _k.linked_edges(P, np.ascontiguousarray(h, dtype=np.float64), dist, idx, t, lin, float(link),
                           float(width), float(wmin), float(gap), float(EXTRA), float(LIN))


def shell_group_counts(P, h, indptr, indices, shell_inner, shell_outer, order=None):
    """Number of connected groups of linked points in the shell around each point.

    Parameters
    ----------
    P : (N, d) ndarray
        Points.
    h : (N,) ndarray
        Local spacing.
    indptr, indices : ndarray
        CSR adjacency of the linked graph.
    shell_inner, shell_outer : float
        Shell radii in units of ``h``.
    order : (N,) ndarray of int, optional
        Visiting order of the points (cache locality only), when already computed.

    Returns
    -------
    (N,) ndarray of int32
    """
    return _k.shell_groups(
        np.ascontiguousarray(P), np.ascontiguousarray(h, dtype=np.float64),
        indptr, indices, float(shell_inner), float(shell_outer), order=order,
    )


def _coincident(dist, idx, r):
    """Points with a neighbour earlier in the (internal) order closer than ``r``.

    Parameters
    ----------
    dist, idx : (N, k) ndarray
        Distances and indices of the k nearest neighbours, ascending.
    r : float

    Returns
    -------
    (N,) bool ndarray
    """
    dup = np.zeros(len(dist), dtype=bool)
    rows = np.flatnonzero(dist[:, 0] < r)
    if len(rows):
        dup[rows] = ((dist[rows] < r) & (idx[rows] < rows[:, None])).any(axis=1)
    return dup


def _components(n, a, b, mask):
    """Connected components of the points in ``mask`` joined by edges (a, b) inside ``mask``.

    Returns labels (-1 outside mask), ordered so that component ids follow the lowest point id,
    and their number (compiled union-find).
    """
    lab, count = _k.components(int(n), np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64),
                               np.ascontiguousarray(mask, dtype=np.bool_))
    return lab, int(count)


def _lex_order(P):
    """``np.lexsort(P.T[::-1])``: the rows sorted by the first coordinate, then the next, ...,
    ties by index (the same permutation, faster: one sort on the first coordinate, then the few
    rows tied there sorted by the others).

    Parameters
    ----------
    P : (N, d) ndarray of float
        Finite coordinates.

    Returns
    -------
    (N,) ndarray of int64
    """
    o = np.argsort(P[:, 0])  # not stable: the tied rows are put in index order below
    x = P[o, 0]
    tie = x[1:] == x[:-1]
    if not tie.any():
        return o
    pos = np.flatnonzero(np.r_[False, tie] | np.r_[tie, False])  # rows in a run of equal x
    run = np.cumsum(np.r_[True, ~tie])[pos]
    sub = o[pos]
    keys = (sub,) + tuple(P[sub, c] for c in range(P.shape[1] - 1, 0, -1)) + (run,)
    o[pos] = sub[np.lexsort(keys)]
    return o


# ---------------------------------------------------------------------------------- helpers
def _fit_line(X):
    c = X.mean(axis=0)
    if len(X) < 2:
        return c, None
    _, _, vt = np.linalg.svd(X - c, full_matrices=False)
    return c, vt[0]


def _step_lengths(P, ids):
    """Distance from every point ``P[ids[i]]`` to the next one ``P[ids[i + 1]]``, 0 after the last.

    Parameters
    ----------
    P : (N, d) ndarray
    ids : (n,) ndarray of int

    Returns
    -------
    (n,) ndarray of float
        The same values as ``np.linalg.norm(np.diff(P[ids], axis=0), axis=1)`` (one gather).
    """
    out = np.zeros(len(ids))
    if len(ids) > 1:
        X = P[ids]
        D = X[1:] - X[:-1]
        D *= D
        out[:-1] = np.sqrt(D.sum(axis=1))
    return out


def _polylen(X):
    if len(X) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(X, axis=0), axis=1).sum())


class _Chain:
    __slots__ = ("ids", "ends", "closed")

    def __init__(self, ids, ends, closed=False):
        self.ids = ids  # ordered point ids (sorted-order ids)
        self.ends = ends  # [start region, end region]; -1 none
        self.closed = closed


# ---------------------------------------------------------------------------------- method
def _reconstruct_robust(
    points,
    *,
    spacing: float | None = None,
    k: int | None = None,
    shell_inner: float | None = None,
    shell_outer: float | None = None,
    link: float | None = None,
    link_width: float | None = None,
    min_spur: float | None = None,
    smooth: bool = False,
    smoothing: float | None = None,
) -> CurveNetwork:
    """Reconstruct a curve network without tuning: the robust default method.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
        Points sampled along curves, in any order.
    spacing : float, optional
        Sampling spacing h. Default: estimated per point (see :func:`local_spacing`); the
        median is reported. A given value is used everywhere.
    k : int, optional
        Neighbours per point for the linked graph (default 16).
    shell_inner, shell_outer : float, optional
        Radii of the junction-test shell in spacings (default 2.5 and 5.5).
    link : float, optional
        Longest link between two points, in spacings (default 2.5).
    link_width : float, optional
        A link is kept when its far end lies within this many spacings of the tangent line
        through one of its ends (default 1.0).
    min_spur : float, optional
        Spurs (junction to free end) and isolated pieces shorter than this many spacings are
        dropped (default 3).
    smooth : bool
        Replace each curve by a smoothing spline through its end nodes, densely evaluated.
    smoothing : float, optional
        Smoothing factor per point in squared spacings (default: the mean squared distance
        of a sample from its curve, estimated from the spread around the local tangents);
        used only with ``smooth=True``.

    Returns
    -------
    CurveNetwork
        Nodes (junctions and free ends), curves ending exactly at their nodes (closed loops
        without node have ``start = end = None``), parameters used and stage timings.
    """
    tm: dict[str, float] = {}
    t0 = time.perf_counter()
    P0 = as_points(points)
    prm = dict(_DEFAULTS)
    given = dict(k=k, shell_inner=shell_inner, shell_outer=shell_outer, link=link,
                 link_width=link_width, min_spur=min_spur)
    for name, val in given.items():
        if val is not None:
            if not np.isfinite(val) or val <= 0:
                raise InputError(f"{name} must be a positive number, got {val!r}")
            prm[name] = val
    prm["k"] = int(prm["k"])
    if prm["k"] < 4:
        raise InputError(f"k must be at least 4, got {prm['k']}")
    if prm["shell_outer"] <= prm["shell_inner"]:
        raise InputError(
            f"shell_outer ({prm['shell_outer']}) must be larger than shell_inner ({prm['shell_inner']})"
        )
    if spacing is not None and (not np.isfinite(spacing) or spacing <= 0):
        raise InputError(f"spacing must be a positive number, got {spacing!r}")
    if smoothing is not None and (not np.isfinite(smoothing) or smoothing < 0):
        raise InputError(f"smoothing must be a non-negative number, got {smoothing!r}")

    N, dim = P0.shape
    # the internal order: sorted (so that nothing depends on the input order); large clouds
    # then cell by cell of a grid, so that near points get near ids and every per-point stage
    # reads memory nearly in sequence (still a function of the point set alone)
    order = _lex_order(P0)
    if N > LOCAL_MIN:
        order = order[locality_order(P0[order])]
    P = P0[order]
    params_out = dict(prm)
    params_out["smooth"] = bool(smooth)
    if N < 5:
        net = CurveNetwork(np.zeros((0, dim)), [], params_out, {"time": tm})
        params_out["spacing"] = float(spacing) if spacing is not None else None
        return net

    # 1. neighbours and spacing (and 2a. the tangents, redone with them when samples are dropped)
    # (the points are visited as numbered by the per-point kernels: see above, already
    # cache-friendly)
    def front(P):
        tree = build_tree(P)  # kept for the repairs (robust._attach_dangling)
        dist, idx = knn(P, prm["k"], ordered=True, tree=tree)
        h = local_spacing(dist, idx) if spacing is None else np.full(len(P), float(spacing))
        return tree, dist, idx, h

    def tangents(P, idx, h):
        t, lin, rms, gain = _tangents(P, idx, h, order=np.arange(len(P), dtype=np.int64))
        sig = float(np.nanmedian(rms)) if np.isfinite(rms).any() else 0.0
        hmed = float(np.median(h))
        # noise-free input: estimated noise under DEDUP_NOISE median spacings; under noise the
        # vote takes in more neighbours (a tangent thrown across close curves by noise has more
        # of its neighbours' to outvote it)
        clean = sig < DEDUP_NOISE * hmed
        if clean:
            t, lin = _retry_tangents(P, idx, h, t, lin, gain)
        t, lin = _vote_tangents(t, lin, idx, m=min(VOTE_M if clean else VOTE_M_NOISY, idx.shape[1]))
        return t, lin, sig, hmed, clean

    tree, dist, idx, h = front(P)
    tm["neighbors"] = time.perf_counter() - t0
    t1 = time.perf_counter()

    # 2. linked graph
    t, lin, sigma, hmed, clean = tangents(P, idx, h)
    # noise-free samples closer than DEDUP median spacings are one place sampled twice
    # (overlapping strokes, a curve given twice): the later ones (internal order) are dropped and
    # the steps above redone on the rest (under noise, close samples are noise: kept)
    params_out["duplicates_dropped"] = 0
    dup = _coincident(dist, idx, DEDUP * hmed) if clean else None
    if dup is not None and dup.any() and N - dup.sum() >= 5:
        params_out["duplicates_dropped"] = int(dup.sum())
        keep = np.flatnonzero(~dup)
        P, order, N = P[keep], order[keep], len(keep)
        tree, dist, idx, h = front(P)
        t, lin, sigma, hmed, clean = tangents(P, idx, h)
    if spacing is None:
        params_out["spacing"] = hmed
        params_out["spacing_range"] = [float(x) for x in np.percentile(h, [5, 95])]
        params_out["spacing_estimated"] = True
    else:
        params_out["spacing"] = float(spacing)
        params_out["spacing_estimated"] = False
    params_out["noise"] = sigma  # estimated std of the noise per coordinate
    noise = NOISE * sigma
    src, dst, dd = _linked_edges(P, h, dist, idx, t, lin, prm["link"], prm["link_width"], NW * noise,
                                 GAP * noise)
    if not clean:  # links between two close parallel strands are cut
        with _k.compiled_for(N, _k.NUMBA_MIN_POINTS_NOISY, _k.STRAND_KERNELS):  # (slow in plain Python)
            tn, ln = _noisy_tangents(P, h, sigma, tree, dist, idx)
            tn, _ = _vote_tangents(tn, ln, idx, m=min(VOTE_M_NOISY, idx.shape[1]))
            src, dst, dd = _cut_strand_links(P, h, idx, tn, src, dst, dd, sigma)
    indptr, indices = _k.csr_union(N, np.asarray(src, dtype=np.int64), np.asarray(dst, dtype=np.int64))
    tm["graph"] = time.perf_counter() - t1

    # 3. shell test
    t1 = time.perf_counter()
    # noise blurs the junction over a few sigma: the shell grows with it
    hs = h + WIDEN * noise
    groups = shell_group_counts(P, hs, indptr, indices, prm["shell_inner"], prm["shell_outer"],
                                order=np.arange(N, dtype=np.int64))
    tm["nodes"] = time.perf_counter() - t1

    # 4. regions and chains
    t1 = time.perf_counter()
    flagged = groups != 2
    # regions: flagged points joined by plain short links (any direction)
    ka, kb = _k.short_links(h, dist, idx, float(prm["link"]))  # kNN pairs within link * h
    # two junctions closer than about two shell radii flag one region: re-test large ones
    flagged, reg, n_reg = _split_large_regions(P, hs, indptr, indices, flagged, ka, kb, dict(prm, _noisy=not clean))
    del ka, kb, dist, idx  # memory: the kNN lists are not needed below
    chn, n_chn = _components(N, src, dst, ~flagged)

    chains = _order_chains(P, h, src, dst, dd, chn, n_chn, reg, lin)
    # the points of each region, ascending (one stable sort, not one pass over N per region)
    o = np.argsort(reg, kind="stable")
    cut = np.searchsorted(reg[o], np.arange(n_reg + 1))
    regions = [o[cut[r]:cut[r + 1]] for r in range(n_reg)]
    tm["tracing"] = time.perf_counter() - t1

    # 5. network
    t1 = time.perf_counter()
    prm_int = dict(prm, _graph=(indptr, indices), _width=max(prm["link_width"], 0.0), _noise=noise, _tree=tree,
                   _hmed=hmed)
    nodes, curves = _assemble(P, h, chains, regions, prm_int)
    tm["assemble"] = time.perf_counter() - t1

    # map back to input indices (all curves at once)
    if curves:
        ind = np.concatenate([c.indices for c in curves])
        ind = np.where(ind >= 0, order[np.maximum(ind, 0)], -1)
        off = np.r_[0, np.cumsum([len(c.indices) for c in curves])].tolist()
        for i, c in enumerate(curves):
            c.indices = ind[off[i]:off[i + 1]]

    if smooth:
        t1 = time.perf_counter()
        hm = hmed
        if smoothing is None:
            # mean squared distance of a sample from the true curve, from the noise estimate
            s = max(sigma**2 * max(dim - 1, 1), 1e-4 * hm**2) / hm**2
        else:
            s = float(smoothing)
        params_out["smoothing"] = s
        curves = [_smooth_curve(c, nodes, s * hm**2) for c in curves]
        tm["smooth"] = time.perf_counter() - t1
    # (counts of the small non-negative group numbers: a bincount, not a sort of all points)
    params_out["groups_histogram"] = {str(g): c for g, c in enumerate(np.bincount(groups).tolist()) if c}
    net = CurveNetwork(nodes, curves, params_out, {"time": tm})
    return net


#: a region whose radius (from its centroid) exceeds SPLIT_R outer shell radii may hold two
#: junctions (one junction's region measures 0.35 to 0.45 on the benchmark); it is re-tested
#: on a shell SPLIT_F times the size, and split when that gives two or more sub-regions of
#: SPLIT_MIN points or more with a junction point each, over SPLIT_SEP fine outer radii apart
SPLIT_R = 0.65
SPLIT_F = 0.7
SPLIT_MIN = 2
SPLIT_SEP = 1.2


def _split_large_regions(P, hs, indptr, indices, flagged, ka, kb, prm):
    """The junction flags, with regions too large for one junction split in two or more.

    A region of radius over ``SPLIT_R`` outer shell radii is re-tested on a shell ``SPLIT_F``
    times the size. The split is kept when it gives two or more sub-regions (``SPLIT_MIN``
    points or more, one of them in 3 or more groups), each pair joined by at most one chain of
    the freed points (linked graph), no freed chain touching three, at least one joining two,
    and the joined sub-regions over ``SPLIT_SEP`` fine outer radii apart: two junctions and the
    short segment between them. Two chains between the same two (a crossing seen in two halves
    by the smaller shell) keep the region whole. Under noise (``prm["_noisy"]``) a sub-region
    with a free-end point (1 group) counts too when another has a junction point: a junction
    and the tip of a branch shorter than the widened shell, joined by the branch.

    Parameters
    ----------
    P : (N, d) ndarray
    hs : (N,) ndarray
        Spacing of the shell test (widened for noise).
    indptr, indices : ndarray
        CSR adjacency of the linked graph.
    flagged : (N,) bool ndarray
        Points not in 2 shell groups.
    ka, kb : (E,) int ndarray
        Short kNN links (the region graph).
    prm : dict
        Parameters (``shell_inner``, ``shell_outer``; ``_noisy``: the input is noisy).

    Returns
    -------
    flagged : (N,) bool ndarray
        The flags with the split regions' freed points cleared.
    reg : (N,) int ndarray
        Region of each flagged point (-1 elsewhere), see :func:`_components`.
    n_reg : int
    """
    N, dim = P.shape
    reg, n_reg = _components(N, ka, kb, flagged)
    if n_reg == 0:
        return flagged, reg, n_reg
    ids = np.flatnonzero(flagged)
    r = reg[ids]
    cnt = np.bincount(r, minlength=n_reg).astype(float)
    cen = np.stack([np.bincount(r, weights=P[ids, c], minlength=n_reg) for c in range(dim)], axis=1) / cnt[:, None]
    rad = np.zeros(n_reg)
    np.maximum.at(rad, r, np.linalg.norm(P[ids] - cen[r], axis=1))
    hmean = np.bincount(r, weights=hs[ids], minlength=n_reg) / cnt
    big = rad > SPLIT_R * prm["shell_outer"] * hmean
    if not big.any():
        return flagged, reg, n_reg
    sub = ids[big[r]]
    fine = _k.shell_groups(P, hs, indptr, indices, SPLIT_F * prm["shell_inner"], SPLIT_F * prm["shell_outer"],
                           subset=sub)
    nf = flagged.copy()
    nf[sub] = fine[sub] != 2
    reg2, _ = _components(N, ka, kb, nf)
    freed = np.zeros(N, dtype=bool)
    freed[sub] = ~nf[sub]
    # the freed points' chains (linked graph) and the sub-regions each touches (short links)
    fs = np.flatnonzero(freed)
    lens = indptr[fs + 1] - indptr[fs]
    ea = np.repeat(fs, lens)
    eb = indices[np.repeat(indptr[fs] - np.cumsum(np.r_[0, lens[:-1]]), lens) + np.arange(lens.sum())]
    lab, _ = _components(N, ea, eb, freed)
    t = freed[ka] & nf[kb]
    touch = np.unique(np.stack([lab[ka[t]], reg2[kb[t]]], axis=1), axis=0)  # sorted by chain
    tcut = np.searchsorted(touch[:, 0], np.arange(lab.max() + 2))
    is_j = np.zeros(N, dtype=bool)  # points of the fine test in 3 or more groups
    is_j[sub] = fine[sub] >= 3
    is_e = np.zeros(N, dtype=bool)  # and in 1 group (a free end)
    is_e[sub] = fine[sub] == 1
    # the points of each big region, grouped (one sort, not one pass per region)
    bsel = big[r]
    bi, br = ids[bsel], r[bsel]
    o = np.argsort(br, kind="stable")
    bi, br = bi[o], br[o]
    bcut = np.flatnonzero(np.r_[True, br[1:] != br[:-1], True])
    out = flagged.copy()
    for g0, g1 in zip(bcut[:-1], bcut[1:]):
        b = br[g0]
        pts = bi[g0:g1]
        kept = pts[nf[pts]]
        labs, c2 = np.unique(reg2[kept], return_counts=True)
        # sub-regions of 2 or more points with a junction point (3 or more groups)
        jun = np.isin(labs, reg2[kept[is_j[kept]]])
        if prm.get("_noisy", False):
            # under noise also with a free end point, when another is a junction: the shell,
            # widened for noise, can be longer than a short branch, whose points then all
            # look like its free end and join the junction's region (the finer shell sees
            # the branch)
            tip = np.isin(labs, reg2[kept[is_e[kept]]]) & ~jun
            good = labs[(c2 >= SPLIT_MIN) & (jun | tip)]
            ok = len(good) >= 2 and bool(np.isin(good, labs[jun]).any())
        else:
            good = labs[(c2 >= SPLIT_MIN) & jun]
            ok = len(good) >= 2
        if ok:
            links = []
            for c in np.unique(lab[pts[freed[pts]]]):
                tb = touch[tcut[c]:tcut[c + 1], 1]
                tb = tb[np.isin(tb, good)]
                if len(tb) > 2:
                    ok = False
                elif len(tb) == 2:
                    links.append(tuple(tb))
            # one chain between two sub-regions and no chain among three: two junctions and
            # the segment between them (two chains between the same two: a crossing split)
            ok = ok and bool(links) and len(set(links)) == len(links)
            if ok:  # and the two junctions clearly apart
                far = SPLIT_SEP * SPLIT_F * prm["shell_outer"] * hmean[b]
                for a_, b_ in links:
                    ca = P[kept[reg2[kept] == a_]].mean(axis=0)
                    cb = P[kept[reg2[kept] == b_]].mean(axis=0)
                    ok = ok and np.linalg.norm(ca - cb) > far
        if ok:
            out[pts] = False
            out[kept[np.isin(reg2[kept], good)]] = True
    if np.array_equal(out, flagged):
        return flagged, reg, n_reg
    return (out, *_components(N, ka, kb, out))


def _order_chains(P, h, src, dst, dd, chn, n_chn, reg, lin):
    """Order every chain by geodesic distance from one end; find the regions its ends touch."""
    N = len(P)
    if n_chn == 0:
        return []
    # compiled: each chain ordered by its distance along the linked graph (edges inside the
    # chain) from its far end, the point farthest from its lowest id (a double sweep)
    ids_o, par_o, bounds = _k.chain_order(N, np.asarray(src, dtype=np.int64), np.asarray(dst, dtype=np.int64),
                                          np.ascontiguousarray(dd, dtype=np.float64), chn, int(n_chn))

    # contacts: linked edges between a chain point and a region point
    in_chn, in_reg = chn >= 0, reg >= 0  # (gathers of bytes below, not of int64)
    cmask = in_chn[src] & in_reg[dst]
    c_pt = src[cmask]
    c_reg = reg[dst[cmask]]
    cmask2 = in_chn[dst] & in_reg[src]
    c_pt = np.r_[c_pt, dst[cmask2]]
    c_reg = np.r_[c_reg, reg[src[cmask2]]]
    c_chain = chn[c_pt]
    pos_in_chain = np.empty(N)
    pos_in_chain[ids_o] = par_o
    c_par = pos_in_chain[c_pt]
    corder = np.lexsort((c_reg, c_chain))
    c_chain, c_reg, c_par, c_pt = c_chain[corder], c_reg[corder], c_par[corder], c_pt[corder]
    cb = np.searchsorted(c_chain, np.arange(n_chn + 1))

    # compiled: for each chain with contacts, the most frequent region among the contacts
    # within reach = min(L / 2, 4 h) of each end (h: the chain's median spacing; a chain
    # shorter than 2 reach is split at L / 2); ties: the lowest region id
    ends, touch = _k.chain_ends(np.ascontiguousarray(h, dtype=np.float64), ids_o, par_o, bounds,
                                c_reg, c_par, cb)
    # polyline length of every ordered chain (steps inside a chain; a zigzag test below)
    step = _step_lengths(P, ids_o)
    step[bounds[1:] - 1] = 0.0  # the step from a chain's last point to the next chain's first
    plen = np.add.reduceat(step, bounds[:-1]) if n_chn else np.zeros(0)
    length = par_o[bounds[1:] - 1]  # the distance of each chain's far end
    # a short chain given the same region at both ends may take another one at one side
    for ci in np.flatnonzero(touch & (ends[:, 0] >= 0) & (ends[:, 0] == ends[:, 1])).tolist():
        _other_end(ci, ends, c_reg[cb[ci]:cb[ci + 1]], c_par[cb[ci]:cb[ci + 1]],
                   float(length[ci]), float(np.median(h[ids_o[bounds[ci]:bounds[ci + 1]]])))
    # no region at either end (a contact in the middle only: a clump beside a loop)
    free = ~touch | ((ends[:, 0] < 0) & (ends[:, 1] < 0))
    # may zigzag (checked below)
    zig = ~free & (np.diff(bounds) >= 6) & (plen > ZIGZAG * length * (1 - 1e-6))
    special = np.flatnonzero(free | zig)
    b = bounds.tolist()
    e0, e1 = ends[:, 0].tolist(), ends[:, 1].tolist()
    chains = [_Chain(ids_o[b[ci]:b[ci + 1]], [e0[ci], e1[ci]]) for ci in range(n_chn)]
    if not len(special):
        return chains
    # the linked graph inside the chains below (their loops are cut open on it)
    inside = (chn[src] >= 0) & (chn[src] == chn[dst])
    inside[inside] = np.isin(chn[src[inside]], special)
    g = coo_matrix((np.maximum(dd[inside], 1e-12), (src[inside], dst[inside])), shape=(N, N)).tocsr()
    for ci in special.tolist():
        seg = ids_o[b[ci]:b[ci + 1]]
        if free[ci]:
            chains[ci] = _loop_or_piece(P, h, g, seg, lin)
            continue
        if _polylen(P[seg]) > ZIGZAG * float(length[ci]):
            # the points ordered by distance from one end zigzag: the chain is still a cycle
            # in the linked graph (a loop whose links bypass the few points flagged on it):
            # it is cut open at its contact with the region it touches most, both ends there
            regs_c, pts_c = c_reg[cb[ci]:cb[ci + 1]], c_pt[cb[ci]:cb[ci + 1]]
            ru, rc = np.unique(regs_c, return_counts=True)
            r = int(ru[np.argmax(rc)])
            lp = _loop_or_piece(P, h, g, seg, lin, start=int(pts_c[regs_c == r].min()))
            if lp.closed:
                chains[ci] = _Chain(lp.ids, [r, r])
    return chains


def _other_end(ci, ends, regs, par, length, hl):
    """A short chain given the same region at both ends that also touches another region.

    Under ``2 * SHORT_REACH`` spacings long, both halves of a chain may be linked mostly to
    the larger region at one end (a sparse free branch, whose long links reach the chain's far
    end): the other region touched (most contacts; ties: lowest id) takes the side its
    contacts lie on (mean position along the chain against that of the first region's).
    """
    if length > 2 * SHORT_REACH * hl:
        return
    r = ends[ci, 0]
    other = regs != r
    if not other.any():
        return
    ru, rc = np.unique(regs[other], return_counts=True)
    r2 = int(ru[np.argmax(rc)])
    side = 1 if par[regs == r2].mean() > par[regs == r].mean() else 0
    ends[ci, side] = r2


def _loop_or_piece(P, h, g, seg, lin, start=None):
    """A chain that touches no region: a closed loop (cut open and ordered), or an open piece.

    The loop is cut at ``start`` when given, else at its straightest point (largest
    linearity; ties: lowest id), never at a sharp corner where the tangent is undefined.
    """
    if len(seg) < 3:
        return _Chain(seg, [-1, -1])
    seg = np.sort(seg)
    s0 = int(np.argmax(lin[seg])) if start is None else int(np.searchsorted(seg, start))
    seg = np.r_[seg[s0:], seg[:s0]]
    sub = g[seg][:, seg].tocoo()
    X = P[seg]
    hl = float(np.median(h[seg]))
    # tangent at the start point; every link crossing the cut has both ends this near
    rnear = max(3.0 * hl, 1.01 * float(sub.data.max()) if sub.nnz else 0.0)
    near = np.linalg.norm(X - X[0], axis=1) <= rnear
    _, u = _fit_line(X[np.linalg.norm(X - X[0], axis=1) <= 3.0 * hl])
    if u is None:
        return _Chain(seg, [-1, -1])
    side = (X - X[0]) @ u
    a, b = sub.row, sub.col
    cut = near[a] & near[b] & ((side[a] < 0) != (side[b] < 0)) & (a != 0) & (b != 0)
    # keep the start's links to the positive side only
    cut |= ((a == 0) & (side[b] < 0)) | ((b == 0) & (side[a] < 0))
    keep = ~cut
    n = len(seg)
    gg = coo_matrix((sub.data[keep], (a[keep], b[keep])), shape=(n, n)).tocsr()
    dd = dijkstra(gg, directed=False, indices=0)
    finite = np.isfinite(dd)
    o = np.lexsort((np.arange(n), dd))
    o = o[finite[o]]
    rest = np.flatnonzero(~finite)
    ordered = seg[o]
    last = X[o[-1]]
    closed = np.linalg.norm(last - X[0]) <= rnear and _polylen(X[o]) > 6.0 * hl
    if not closed:
        # an open piece: ordered from one end to the other (double sweep on the uncut graph)
        g0 = coo_matrix((sub.data, (a, b)), shape=(n, n)).tocsr()
        d0 = dijkstra(g0, directed=False, indices=0)
        f0 = np.isfinite(d0)
        e1 = int(np.lexsort((np.arange(n), -np.where(f0, d0, -1.0)))[0])
        d1 = dijkstra(g0, directed=False, indices=e1)
        f1 = np.isfinite(d1)
        o = np.lexsort((np.arange(n), d1))
        o = o[f1[o]]
        return _Chain(np.r_[seg[o], seg[np.flatnonzero(~f1)]], [-1, -1], closed=False)
    if len(rest):
        # unreachable points: append by their position along the tangent (rare)
        ordered = np.r_[ordered, seg[rest[np.argsort(side[rest], kind="stable")]]]
    return _Chain(ordered, [-1, -1], closed=bool(closed))


def _assemble(P, h, chains, regions, prm):
    """Turn chains and regions into nodes and curves (spur pruning, joins, node positions)."""
    regions = list(regions)
    dim = P.shape[1]
    # dangling open ends -> empty free-end regions
    for c in chains:
        if c.closed:
            continue
        for s in (0, 1):
            if c.ends[s] < 0:
                regions.append(np.zeros(0, dtype=np.int64))
                c.ends[s] = len(regions) - 1
    alive = [True] * len(chains)
    # the chain ends at each region (chain, side), kept up to date below
    ends_at: list[list[tuple[int, int]]] = [[] for _ in regions]
    for i, c in enumerate(chains):
        if not c.closed:
            for s in (0, 1):
                ends_at[c.ends[s]].append((i, s))

    def valence():
        e = [c.ends for c, a in zip(chains, alive) if a and not c.closed]
        e = np.fromiter(itertools.chain.from_iterable(e), dtype=np.int64, count=2 * len(e))
        return np.bincount(e, minlength=len(regions)).astype(np.int64)

    hmed = prm["_hmed"]  # the median spacing (of the tangent step)
    # a region passed through by one curve (valence 2) right next to a junction region is a
    # piece of that junction cut off by noise (a crossing split in two): merge it
    _merge_near_pass_through(P, h, chains, regions, alive, ends_at, valence(), prm)
    # a short chain leaving a region and coming back to it lies inside the junction: absorb it
    _absorb_short_loops(P, h, chains, regions, alive, prm)
    # a flagged clump touching no chain, just beyond a free end, is the rest of that end (the
    # link between them was lost to noise): it joins the free end's region
    _absorb_orphans(P, h, chains, regions, alive, ends_at, valence(), prm)
    # a free end right next to a junction region belongs to it (its link was lost to noise)
    _tips_to_junctions(P, h, chains, regions, alive, ends_at, valence(), prm)
    # two free ends facing each other across a small gap are one curve broken by noise: join
    v = valence()
    tips = []
    for i, c in enumerate(chains):
        if alive[i] and not c.closed:
            for s in (0, 1):
                r = c.ends[s]
                if v[r] == 1:
                    end_pt = c.ids[-1] if s == 1 else c.ids[0]
                    tips.append((r, np.r_[regions[r], end_pt].astype(np.int64)))
    if len(tips) >= 2:
        # only pairs of tips closer than the threshold can merge: found with a k-d tree, then
        # visited in the same (a, b) order as a double loop over all pairs
        for a, b in _close_tip_pairs(P, [ia for _, ia in tips], prm["link"] * 1.2 * hmed):
            ra, ia = tips[a]
            rb, ib = tips[b]
            if ra == rb:
                continue
            gap = np.min(np.linalg.norm(P[ia][:, None, :] - P[ib][None, :, :], axis=2))
            if gap <= prm["link"] * 1.2 * hmed:
                # merge region rb into ra
                regions[ra] = np.r_[regions[ra], regions[rb]]
                regions[rb] = np.zeros(0, dtype=np.int64)
                for ci, s in ends_at[rb]:
                    chains[ci].ends[s] = ra
                ends_at[ra].extend(ends_at[rb])
                ends_at[rb] = []
                tips[b] = (ra, ib)
    # a free end that stops short of another curve is a junction whose link was lost to
    # noise or sparse sampling (a T whose stem does not reach the bar): split that curve there
    _attach_dangling(P, h, chains, regions, alive, ends_at, valence(), prm)
    # prune short spurs and small isolated pieces
    # a chain is short only if its polyline is under min_spur (a loop: twice) times its largest
    # spacing: the exact tests below run only for those (the sums here are within rounding)
    length, hmax = _chain_lengths(P, h, chains)
    short_loop = (length <= 2 * prm["min_spur"] * hmax * (1 + 1e-9)).tolist()
    short = (length <= prm["min_spur"] * hmax * (1 + 1e-9)).tolist()
    for _ in range(3):
        v = valence()
        changed = False
        for i, c in enumerate(chains):
            if not alive[i] or not short_loop[i]:
                continue
            if c.closed:
                hl = float(np.median(h[c.ids])) if len(c.ids) else hmed
                if _polylen(P[c.ids]) < 2 * prm["min_spur"] * hl:
                    alive[i] = False
                    changed = True
                continue
            a, b = c.ends
            free_a, free_b = v[a] == 1, v[b] == 1
            if not (free_a or free_b) or not short[i]:
                continue
            hl = float(np.median(h[c.ids])) if len(c.ids) else hmed
            length = _polylen(P[c.ids])
            ext = sum(_extent(P, regions[r]) for r in (a, b) if v[r] == 1)
            if length + ext < prm["min_spur"] * hl:
                if free_a and free_b or v[a] >= 3 or v[b] >= 3:
                    alive[i] = False
                    changed = True
                    v[a] -= 1  # the valence without chain i
                    v[b] -= 1
        if not changed:
            break

    # join chains through regions of valence 2 (in region order; a join leaves the valence of
    # every other region unchanged)
    v = valence()
    for r in np.flatnonzero(v == 2).tolist():
        inc = sorted({(i, s) for i, s in ends_at[r]
                      if alive[i] and not chains[i].closed and chains[i].ends[s] == r})
        (i, si), (j, sj) = inc
        if i != j and len(regions[r]) >= 3:
            # a short free branch hidden in the region (a fork passed through by one curve in
            # a sparse place): the region stays a junction
            X, maybe = _junction_positions(P, h, [(chains, inc, regions[r])], prm)
            if maybe[0] and _swallowed_branches(P, h, chains, inc, regions[r], X[0], prm):
                continue
        ci = chains[i]
        a_ids = ci.ids if si == 1 else ci.ids[::-1]
        a_other = ci.ends[1 - si]
        if i == j:
            mid = _order_between(P, regions[r], P[a_ids[-1]], P[a_ids[0]])
            chains[i] = _Chain(np.r_[a_ids, mid], [-1, -1], closed=True)
            regions[r] = np.zeros(0, dtype=np.int64)
            continue
        cj = chains[j]
        b_ids = cj.ids if sj == 0 else cj.ids[::-1]
        b_other = cj.ends[1 - sj]
        mid = _order_between(P, regions[r], P[a_ids[-1]], P[b_ids[0]])
        chains[i] = _Chain(np.r_[a_ids, mid, b_ids], [a_other, b_other])
        alive[j] = False
        regions[r] = np.zeros(0, dtype=np.int64)
        ends_at[r] = []
        ends_at[a_other] = [e for e in ends_at[a_other] if e != (i, 1 - si)] + [(i, 0)]
        ends_at[b_other] = [e for e in ends_at[b_other] if e != (j, 1 - sj)] + [(i, 1)]

    # two junctions joined by a short chain, the other branches of one pointing at the other,
    # are one junction (two of its branches ran together for a while): merge them
    _merge_close_junctions(P, h, chains, regions, alive, ends_at, valence(), prm)
    # a short chain between two merged junctions is now a short loop at the merged one
    _absorb_short_loops(P, h, chains, regions, alive, prm)
    v = valence()
    live = [c for i, c in enumerate(chains) if alive[i]]
    # node positions
    node_of = {}
    node_pos = []
    end_ext: dict[tuple[int, int], np.ndarray] = {}
    inc_at: dict[int, list[tuple[int, int]]] = {}
    extra: list[tuple[int, np.ndarray]] = []
    for ci, c in enumerate(live):
        if not c.closed:
            for s in (0, 1):
                inc_at.setdefault(c.ends[s], []).append((ci, s))
    # all junction nodes in one compiled call
    jr = [r for r in range(len(regions)) if v[r] >= 2]
    JX, JMAYBE = _junction_positions(P, h, [(live, inc_at[r], regions[r]) for r in jr], prm)
    jpos = {r: i for i, r in enumerate(jr)}
    # the region paths of all free ends that may hide a fork, in one call
    fr = [r for r in range(len(regions)) if v[r] == 1]
    fids = {}
    for r in fr:
        ci, s = inc_at[r][0]
        fids[r] = live[ci].ids if s == 1 else live[ci].ids[::-1]  # ids run towards the region
    fr = [r for r in fr if _fork_possible(P, h, fids[r], regions[r], prm)]
    fpaths = dict(zip(fr, _region_paths(P, [(regions[r], int(fids[r][-1])) for r in fr], prm)))
    fm = dict(zip(fids, _end_counts(P, h, list(fids.values()), 4.0).tolist()))  # _free_end's
    for r in range(len(regions)):
        if v[r] == 0:
            continue
        inc = inc_at[r]
        if v[r] == 1:
            ci, s = inc[0]
            ids = fids[r]
            fork = _hidden_fork(P, h, ids, regions[r], prm, fpaths[r]) if r in fpaths else None
            if fork is not None:
                # a whole fork (junction and two short free branches) inside one free end's
                # region (sparse sampling): a junction node and two free branches
                ext, pos, leaves = fork
                end_ext[(ci, s)] = ext
                node_pos.append(pos)
                extra.extend((len(node_pos) - 1, lf) for lf in leaves)
                node_of[r] = len(node_pos) - 1
                continue
            ext, pos = _free_end(P, h, ids, regions[r], m=fm[r])
            end_ext[(ci, s)] = ext
            node_pos.append(pos)
        else:
            node_pos.append(JX[jpos[r]])
            if JMAYBE[jpos[r]]:
                for br in _swallowed_branches(P, h, live, inc, regions[r], node_pos[-1], prm):
                    extra.append((len(node_pos) - 1, br))
        node_of[r] = len(node_pos) - 1
    # a short free branch lying wholly inside its junction's region (sparse sampling: its
    # length is under the shell radius) gets its own curve to a free end at its tip
    extra_ids = []
    for j, br in extra:
        node_pos.append(P[br[-1]])
        extra_ids.append((j, len(node_pos) - 1, br))
    nodes = np.asarray(node_pos, dtype=float).reshape(-1, dim)
    # canonical node order (by coordinates)
    if len(nodes):
        norder = np.lexsort(np.round(nodes, 9).T[::-1])
        new_id = np.empty(len(norder), dtype=np.int64)
        new_id[norder] = np.arange(len(norder))
        nodes = nodes[norder]
    # at a junction, chain points lying behind the node (the chain overshot it into another
    # branch) are dropped (all open chains in one compiled call)
    opn = [ci for ci, c in enumerate(live) if not c.closed]
    trim = {}
    if opn:
        vl = v.tolist()
        node_arr = np.full(len(regions), -1, dtype=np.int64)
        node_arr[list(node_of)] = list(node_of.values())
        ends = np.fromiter(itertools.chain.from_iterable(live[ci].ends for ci in opn), dtype=np.int64,
                           count=2 * len(opn))
        ends = new_id[node_arr[ends]].reshape(-1, 2)
        do0 = np.array([(ci, 0) not in end_ext and vl[live[ci].ends[0]] >= 2 for ci in opn])
        do1 = np.array([(ci, 1) not in end_ext and vl[live[ci].ends[1]] >= 2 for ci in opn])
        flat = np.concatenate([live[ci].ids for ci in opn]).astype(np.int64, copy=False)
        off = np.r_[0, np.cumsum([len(live[ci].ids) for ci in opn])].astype(np.int64)
        lo, hi = _k.trim_ends(P, np.ascontiguousarray(h, dtype=np.float64), flat, off, do0, do1,
                              nodes[ends[:, 0]], nodes[ends[:, 1]], 2.0 * SPAN)
        trim = {ci: flat[lo[i]:hi[i]] for i, ci in enumerate(opn)}
    curves: list = [None] * len(live)
    loops = [ci for ci, c in enumerate(live) if c.closed]
    for ci, ids in zip(loops, _untangle_loops(P, [live[ci].ids for ci in loops])):
        curves[ci] = Curve(P[ids], None, None, True, ids)
    if opn:
        # the open curves all at once: each runs from node a through its free-end extension
        # (reversed), trimmed chain points and the other extension to node b
        pieces, n0, n1, last0, last1 = [], np.zeros(len(opn), np.int64), np.zeros(len(opn), np.int64), [], []
        for i, ci in enumerate(opn):
            ext0, ext1 = end_ext.get((ci, 0)), end_ext.get((ci, 1))
            if ext0 is not None and len(ext0):
                pieces.append(ext0[::-1])
                n0[i] = len(ext0)
                last0.append((i, ext0[-1]))
            pieces.append(trim[ci])
            if ext1 is not None and len(ext1):
                pieces.append(ext1)
                n1[i] = len(ext1)
                last1.append((i, ext1[-1]))
        curves_open = _open_curves(P, nodes, np.concatenate(pieces).astype(np.int64, copy=False),
                                   n0 + (hi - lo) + n1, ends[:, 0], ends[:, 1], last0, last1)
        for ci, cv in zip(opn, curves_open):
            curves[ci] = cv
    for j, t, br in extra_ids:
        a, b = int(new_id[j]), int(new_id[t])
        cv = Curve(np.vstack([nodes[a], P[br]]), a, b, False, np.r_[-1, br].astype(np.int64))
        if a > b:
            cv = cv.reversed()
        curves.append(cv)
    curves = _sort_curves(curves)
    return nodes, curves


def _chain_lengths(P, h, chains):
    """Polyline length (summed per chain, within rounding of :func:`_polylen`) and largest
    spacing of every chain; a chain without points gets length 0 and spacing inf."""
    lens = np.array([len(c.ids) for c in chains], dtype=np.int64)
    length = np.zeros(len(chains))
    hmax = np.full(len(chains), np.inf)
    nz = np.flatnonzero(lens > 0)
    if len(nz):
        flat = np.concatenate([chains[i].ids for i in nz.tolist()]).astype(np.int64, copy=False)
        off = np.r_[0, np.cumsum(lens[nz])]
        step = _step_lengths(P, flat)
        step[off[1:] - 1] = 0.0  # from a chain's last point to the next chain's first
        length[nz] = np.add.reduceat(step, off[:-1])
        hmax[nz] = np.maximum.reduceat(h[flat], off[:-1])
    return length, hmax


def _open_curves(P, nodes, ids, nids, a, b, last0, last1):
    """Open curves from their point ids, each ending exactly at its two nodes.

    Parameters
    ----------
    P : (N, d) ndarray
        Points.
    nodes : (n_nodes, d) ndarray
        Node positions.
    ids : (M,) ndarray of int64
        The point ids of all curves, concatenated, each curve's running from node ``a`` to ``b``.
    nids : (n_curves,) ndarray of int64
        The number of ids of each curve.
    a, b : (n_curves,) ndarray of int64
        The nodes at the start and the end of each curve's ids.
    last0, last1 : list of (int, int)
        ``(curve, point id)``: a curve whose first (resp. last) id is the extreme point of a free
        end; where that point lies exactly at the node, the node is not added again.

    Returns
    -------
    list of Curve
        Node position, points, node position (``indices`` -1 at the nodes), stored from the
        lower node id to the higher (reversed where ``a > b``). The curves' arrays are views of
        two shared arrays.
    """
    nc = len(nids)
    head = np.ones(nc, dtype=np.int64)
    tail = np.ones(nc, dtype=np.int64)
    for flag, last, node in ((head, last0, a), (tail, last1, b)):
        if last:
            c, q = np.asarray(last, dtype=np.int64).T
            flag[c] = ~(P[q] == nodes[node[c]]).all(axis=1)
    n = nids + head + tail
    off = np.r_[0, np.cumsum(n)]
    cid = np.repeat(np.arange(nc), n)
    local = np.arange(off[-1]) - off[cid]
    rev = a > b
    # the position of each output entry in the curve as built from a to b
    src = np.where(rev[cid], n[cid] - 1 - local, local)
    k = src - head[cid]
    inner = (k >= 0) & (k < nids[cid])
    ind = np.full(off[-1], -1, dtype=np.int64)
    ind[inner] = ids[(np.r_[0, np.cumsum(nids)][cid] + k)[inner]]
    pts = P[np.maximum(ind, 0)]
    at_a = ~inner & (k < 0)
    at_b = ~inner & (k >= 0)
    pts[at_a] = nodes[a[cid[at_a]]]
    pts[at_b] = nodes[b[cid[at_b]]]
    # a curve whose points turn back (two steps in a row more than 120 degrees apart) zigzags
    # (a sharp spike whose legs were linked across, a region's points ordered along a chord
    # that crosses the spike): its inner points are reordered into a shorter path
    order, _ = _untangled(pts, off)
    if order is not None:
        pts = pts[order]
        ind = ind[order]
    o = off.tolist()
    lo_, hi_ = np.where(rev, b, a).tolist(), np.where(rev, a, b).tolist()
    return [Curve(pts[o[i]:o[i + 1]], lo_[i], hi_[i], False, ind[o[i]:o[i + 1]]) for i in range(nc)]


#: two successive steps of a curve more than this apart (cosine below) turn back
TURN_BACK_COS = -0.5
#: the reach (in points along the curve) of one reordering move (see
#: :func:`curvenet._robust_kernels._untangle`)
UNTANGLE_W = 64


def _untangle_loops(P, loops):
    """The closed loops' point ids (each a list from its cut point around), those that turn
    back reordered into a shorter cycle from the same cut point (see :func:`_turning_back`)."""
    if not loops:
        return []
    # each loop as a path from its first point around and back to it (both ends kept)
    ids = np.concatenate([np.r_[c, c[:1]] for c in loops]).astype(np.int64, copy=False)
    off = np.r_[0, np.cumsum([len(c) + 1 for c in loops])].astype(np.int64)
    order, which = _untangled(P[ids], off)
    out = [np.array(c, dtype=np.int64, copy=True) for c in loops]
    if order is not None:
        ids = ids[order]
        for i in which.tolist():
            out[i] = ids[off[i]:off[i + 1] - 1].copy()
    return out


def _untangled(X, off):
    """The curves ``X[off[i]:off[i + 1]]`` (concatenated) that turn back, and the order of the
    rows of ``X`` that reorders their inner points into shorter paths (their ends kept; the
    other curves as they are), or ``None`` when none turns back
    (:func:`curvenet._robust_kernels._untangle`)."""
    which = _turning_back(X, off)
    if not len(which):
        return None, which
    order = _k.untangle(X, np.asarray(off, dtype=np.int64), which.astype(np.int64), UNTANGLE_W, TURN_BACK_COS)
    return order, which


def _turning_back(X, off):
    """The curves (points ``X[off[i]:off[i + 1]]``, concatenated) with two successive steps
    whose directions are more than 120 degrees apart (``TURN_BACK_COS``)."""
    d = np.diff(X, axis=0)
    L = np.linalg.norm(d, axis=1)
    # steps inside a curve of nonzero length, and pairs of them inside one curve
    cid = np.repeat(np.arange(len(off) - 1), np.diff(off))
    inside = (cid[1:] == cid[:-1]) & (L > 0)
    u = d / np.where(L > 0, L, 1.0)[:, None]
    idx = np.flatnonzero(inside)
    # consecutive nonzero steps of the same curve (zero steps skipped)
    pair = (cid[idx[1:]] == cid[idx[:-1]])
    cosang = np.einsum("nd,nd->n", u[idx[1:]], u[idx[:-1]])
    return np.unique(cid[idx[1:]][pair & (cosang < TURN_BACK_COS)])


def _sort_curves(curves):
    """The curves by start node, end node (-1 for none), then second point rounded to 9
    decimals (the first for a curve of one point); ties keep their order."""
    if not curves:
        return curves
    n = len(curves)
    st = np.fromiter((-1 if c.start is None else c.start for c in curves), dtype=np.int64, count=n)
    en = np.fromiter((-1 if c.end is None else c.end for c in curves), dtype=np.int64, count=n)
    X = np.round(np.stack([c.points[min(1, len(c.points) - 1)] for c in curves]), 9)
    o = np.lexsort(tuple(X[:, j] for j in range(X.shape[1] - 1, -1, -1)) + (en, st))
    return [curves[i] for i in o.tolist()]


def _absorb_short_loops(P, h, chains, regions, alive, prm):
    """Absorb into its region every chain that leaves a region and comes back to it while
    staying within ``shell_outer`` spacings of the region's centre (it lies inside the junction)."""
    for i, c in enumerate(chains):
        if alive[i] and not c.closed and c.ends[0] == c.ends[1] and len(regions[c.ends[0]]):
            hl = float(np.median(h[c.ids]))
            cen = P[regions[c.ends[0]]].mean(axis=0)
            if np.linalg.norm(P[c.ids] - cen, axis=1).max() < prm["shell_outer"] * hl:
                alive[i] = False
                regions[c.ends[0]] = np.r_[regions[c.ends[0]], c.ids]


def _close_tip_pairs(P, tips, r):
    """Pairs ``(a, b)``, ``a < b``, of point sets ``tips[a]``, ``tips[b]`` that may come within
    ``r`` of each other (a superset: the caller checks the exact distance), sorted."""
    from scipy.spatial import cKDTree

    own = np.repeat(np.arange(len(tips)), [len(t) for t in tips])
    pts = P[np.concatenate(tips)] if len(own) else np.zeros((0, P.shape[1]))
    pairs = cKDTree(pts).query_pairs(r * (1 + 1e-6) + 1e-300, output_type="ndarray")
    a, b = own[pairs[:, 0]], own[pairs[:, 1]]
    a, b = np.minimum(a, b), np.maximum(a, b)
    ab = np.unique(np.stack([a[a != b], b[a != b]], axis=1), axis=0)
    return [(int(x), int(y)) for x, y in ab]


#: A free end attaches to a chain at most ATT link lengths (plus GAP times the noise) ahead of it:
#: a link lost to noise. A longer gap on clean samples is in the data: the end stays free.
ATT = 1.0
#: (and within 45 degrees of the direction of its end: cosine ATT_COS)
ATT_COS = float(np.cos(np.radians(45.0)))


def _merge_near_pass_through(P, h, chains, regions, alive, ends_at, v, prm):
    """Merge every valence-2 region into the nearest region of valence >= 2 within a gap."""
    from scipy.spatial import cKDTree

    cand = [r for r in range(len(regions)) if v[r] >= 2 and len(regions[r])]
    two = [r for r in cand if v[r] == 2]
    if not two or len(cand) < 2:
        return
    noise = prm.get("_noise", 0.0)
    lab = np.repeat(np.asarray(cand, dtype=np.int64), [len(regions[r]) for r in cand])
    ids = np.concatenate([regions[r] for r in cand])
    tree = cKDTree(P[ids])
    for r in two:
        pts = regions[r]
        if len(pts) == 0 or v[r] != 2:
            continue
        gap = prm["link"] * 1.2 * float(np.median(h[pts])) + GAP * noise
        best = None
        for k_list, p_ in zip(tree.query_ball_point(P[pts], gap), pts):
            for k in k_list:
                t = int(lab[k])
                if t == r or len(regions[t]) == 0:
                    continue
                d = float(np.linalg.norm(P[ids[k]] - P[p_]))
                if best is None or (d, t) < best:
                    best = (d, t)
        if best is None:
            continue
        t = best[1]
        lab[lab == r] = t
        _absorb_region(r, t, chains, regions, alive, ends_at, v)


def _absorb_region(r, t, chains, regions, alive, ends_at, v):
    """Merge region ``r`` into region ``t``: its points, the chain ends at it and its valence."""
    regions[t] = np.r_[regions[t], regions[r]]
    regions[r] = np.zeros(0, dtype=np.int64)
    for i, s in ends_at[r]:
        if alive[i] and chains[i].ends[s] == r:
            chains[i].ends[s] = t
            ends_at[t].append((i, s))
    ends_at[r] = []
    v[t] += v[r]
    v[r] = 0


def _tips_to_junctions(P, h, chains, regions, alive, ends_at, v, prm):
    """Merge every free-end region into the nearest region of valence >= 2 within a gap."""
    from scipy.spatial import cKDTree

    big = [r for r in range(len(regions)) if v[r] >= 2 and len(regions[r])]
    tips = [r for r in range(len(regions)) if v[r] == 1]
    if not big or not tips:
        return
    lab = np.repeat(np.asarray(big, dtype=np.int64), [len(regions[r]) for r in big])
    ids = np.concatenate([regions[r] for r in big])
    tree = cKDTree(P[ids])
    noise = prm.get("_noise", 0.0)
    # a tip's chain end and region do not change below before its turn (a merge only moves
    # the ends at the tip merged): the end portions of all in one call
    one = []
    for r in tips:
        inc = [(i, s) for i, s in ends_at[r] if alive[i] and chains[i].ends[s] == r]
        if len(inc) == 1:
            i, s = inc[0]
            one.append((r, i, s, chains[i].ids if s == 1 else chains[i].ids[::-1]))  # towards the tip
    ms = _end_counts(P, h, [x[3] for x in one], 4.0).tolist()
    if not one:
        return
    # where each free end's node would be, then the nearest junction point of each (one query:
    # the tree does not change below)
    tip = np.array([_free_end(P, h, cids, regions[r], m=m)[1] for (r, _, _, cids), m in zip(one, ms)])
    gap = prm["link"] * 1.2 * h[[int(x[3][-1]) for x in one]] + GAP * noise
    dk, kk = tree.query(tip, distance_upper_bound=float(gap.max()))
    # the bound is per tip: beyond it, none (as a query bounded by it; at the bound itself,
    # within rounding, that query is run)
    dk[dk > gap * (1 + 1e-9)] = np.inf
    for j in np.flatnonzero(np.isfinite(dk) & (dk >= gap * (1 - 1e-9))).tolist():
        dk[j], kk[j] = tree.query(tip[j], distance_upper_bound=float(gap[j]))
    for (r, i, s, cids), d, k in zip(one, dk.tolist(), kk.tolist()):
        if not np.isfinite(d):
            continue
        t = int(lab[k])
        if chains[i].ends[1 - s] == t:
            continue  # a short spur of that very junction: left to the pruning
        _absorb_region(r, t, chains, regions, alive, ends_at, v)


def _merge_close_junctions(P, h, chains, regions, alive, ends_at, v, prm):
    """Merge junction b into junction a when a chain a-b is short and b's other branches aim at a.

    "Short": at most ``MERGE_LEN`` spacings (median spacings for a chain sampled ``DENSE`` times
    as densely: two strokes run together). "Aim at a": a's node (least-squares intersection)
    lies within ``max(link_width * h, NW * noise)`` of the line fitted on each of b's other
    branches, or within ``MERGE_TAN`` times its distance from the branch end (10 degrees: a fan
    of curved strokes converging on one node parts a few degrees apart; ``MERGE_TAN_HUB``, 20
    degrees, for a doubled chain into a junction of ``HUB_VAL`` curves or more).
    """
    noise = prm.get("_noise", 0.0)
    # lengths of all chains at once (the ids do not change below); a chain longer than
    # MERGE_LEN times its largest spacing is longer than MERGE_LEN times its median one
    lens = [len(c.ids) for c in chains]
    flat = np.concatenate([c.ids for c in chains]).astype(np.int64) if chains else np.zeros(0, np.int64)
    step = _step_lengths(P, flat)[:-1]
    cum = np.r_[0.0, np.cumsum(step)]
    off = np.r_[0, np.cumsum(lens)].astype(np.int64)
    hmax = np.zeros(len(chains))
    nz = np.flatnonzero(np.asarray(lens) > 0)
    if len(nz):
        hmax[nz] = np.maximum.reduceat(h[flat], off[nz])
    # (two strokes running together are sampled twice as densely: "short" is measured in the
    # median spacing where the chain is sampled DENSE times as densely or more, else in its own;
    # such a doubled chain into a hub gets the wider aim MERGE_TAN_HUB below)
    hglob = prm["_hmed"]
    # the short chains between two junctions (a merge only maps one junction onto another and
    # raises its valence, so no other chain can become one below)
    cand = []
    doubled = {}
    for ci in range(len(chains)):
        c = chains[ci]
        if not alive[ci] or c.closed:
            continue
        a, b = c.ends
        if a == b or v[a] < 3 or v[b] < 3:
            continue
        # polyline length: the steps inside the chain (not the one joining it to the next)
        length = cum[off[ci + 1] - 1] - cum[off[ci]] if lens[ci] > 1 else 0.0
        if length > MERGE_LEN * max(hmax[ci], hglob) * (1 + 1e-9):
            continue
        hl = float(np.median(h[c.ids])) if len(c.ids) else hglob
        dbl = hl * DENSE < hglob
        if _polylen(P[c.ids]) > MERGE_LEN * (hglob if dbl else hl):
            continue
        cand.append(ci)
        doubled[ci] = dbl

    def incident(r):
        return [(i, s) for i, s in ends_at[r] if alive[i] and chains[i].ends[s] == r]

    # the nodes of their junctions in one batch; a merge changes only its two junctions
    need = sorted({r for ci in cand for r in chains[ci].ends})
    pos = {}
    if need:
        X, _ = _junction_positions(P, h, [(chains, incident(r), regions[r]) for r in need], prm)
        pos = dict(zip(need, X))
    for ci in cand:
        c = chains[ci]
        a, b = c.ends
        if not alive[ci] or a == b or v[a] < 3 or v[b] < 3:
            continue
        for x_r, y_r in ((a, b), (b, a)):
            inc_x = incident(x_r)
            inc_y = [(i, s) for i, s in ends_at[y_r] if alive[i] and chains[i].ends[s] == y_r and i != ci]
            if len(inc_y) < 2:
                continue
            if x_r not in pos:
                pos[x_r] = _junction(P, h, chains, inc_x, regions[x_r], prm)
            xpos = pos[x_r]
            ok = True
            for i, s in inc_y:
                ids = chains[i].ids if s == 1 else chains[i].ids[::-1]
                E = _end_portion(P, h, np.asarray(ids), span=JSPAN + JN * noise / float(h[ids[-1]]))
                cc, u = _fit_line(E)
                if u is None:
                    ok = False
                    break
                r = xpos - cc
                d = np.sqrt(max(float(r @ r) - float(r @ u) ** 2, 0.0))
                # within the strip, or within MERGE_ANG as seen from the branch end (a fan of
                # curves converging on one node parts a few degrees apart)
                tan = MERGE_TAN_HUB if v[x_r] >= HUB_VAL and doubled[ci] else MERGE_TAN
                lim = max(prm["_width"] * float(h[ids[-1]]), NW * noise, tan * float(np.linalg.norm(xpos - E[0])))
                if d > lim or float((E[0] - cc) @ u) * float((xpos - cc) @ u) < 0:
                    ok = False
                    break
            if not ok:
                continue
            # merge y into x, the short chain included
            pos.pop(x_r, None)
            pos.pop(y_r, None)
            alive[ci] = False
            v[x_r] -= 1
            v[y_r] -= 1
            regions[x_r] = np.r_[regions[x_r], regions[y_r], c.ids].astype(np.int64)
            regions[y_r] = np.zeros(0, dtype=np.int64)
            for i, s in inc_y:
                chains[i].ends[s] = x_r
                ends_at[x_r].append((i, s))
            ends_at[y_r] = []
            v[x_r] += v[y_r]
            v[y_r] = 0
            break


def _absorb_orphans(P, h, chains, regions, alive, ends_at, v, prm):
    """Merge regions without chain ends into the nearest free-end region within a gap (in place)."""
    from scipy.spatial import cKDTree

    tips = [r for r in range(len(regions)) if v[r] == 1]
    orphans = [r for r in range(len(regions)) if v[r] == 0 and len(regions[r]) and not ends_at[r]]
    if not tips or not orphans:
        return
    tip_pts, tip_of = [], []
    for r in tips:
        ids = list(regions[r])
        for i, s in ends_at[r]:
            if alive[i] and chains[i].ends[s] == r:
                ids.append(int(chains[i].ids[-1] if s == 1 else chains[i].ids[0]))
        tip_pts += ids
        tip_of += [r] * len(ids)
    tip_pts = np.asarray(tip_pts, dtype=np.int64)
    tip_of = np.asarray(tip_of, dtype=np.int64)
    tree = cKDTree(P[tip_pts])
    noise = prm.get("_noise", 0.0)
    for r in orphans:
        ids = regions[r]
        gap = prm["link"] * 1.2 * float(np.median(h[ids])) + GAP * noise
        d, k = tree.query(P[ids], distance_upper_bound=gap)
        ok = np.isfinite(d)
        if not ok.any():
            continue
        o = np.lexsort((tip_pts[k[ok]], d[ok]))[0]
        t = int(tip_of[k[ok][o]])
        regions[t] = np.r_[regions[t], ids]
        regions[r] = np.zeros(0, dtype=np.int64)


def _attach_dangling(P, h, chains, regions, alive, ends_at, v, prm):
    """Join free ends lying within a link reach ahead of another chain to it (in place).

    The other chain is split at its nearest point, which becomes a new junction region
    holding the free end's region too; near an end of the other chain, the free end joins
    the region there instead. Tips are handled in chain order; each moves at most once.
    """
    N = len(P)
    owner = np.full(N, -1, dtype=np.int64)
    for i, c in enumerate(chains):
        if alive[i]:
            owner[c.ids] = i
    if not (owner >= 0).any():
        return
    # the tree over all points (built for the k-NN query): the points of no chain it returns
    # as well are left out below (owner -1), as are those of split-off cores
    tree = prm["_tree"]
    noise = prm.get("_noise", 0.0)
    tips = [(i, s) for i, c in enumerate(chains) if alive[i] and not c.closed
            for s in (0, 1) if v[c.ends[s]] == 1]
    if not tips:
        return
    # what each tip needs, for all at once: a tip still to be handled has the chain end and
    # region it had here (a move or a split changes only the valence-1 ends it involves), and
    # its chain's points unless that chain was split meanwhile (then its end is redone below)
    tchain = [chains[i] for i, _ in tips]
    tids = [c.ids if s == 1 else c.ids[::-1] for c, (_, s) in zip(tchain, tips)]  # towards the tip
    tms = _end_counts(P, h, tids, 3.0).tolist()
    tpts = [np.r_[regions[c.ends[s]], ids[-1]].astype(np.int64) for c, (_, s), ids in zip(tchain, tips, tids)]
    reach_of = ATT * prm["link"] * h[[int(ids[-1]) for ids in tids]] + GAP * noise
    # chain points within reach of each tip point (one threaded query)
    allp = np.concatenate(tpts)
    with _sigint.held():
        near = tree.query_ball_point(P[allp], np.repeat(reach_of, [len(x) for x in tpts]), workers=-1)
    cnt = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(near))
    qall = np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=int(cnt.sum()))
    qoff = np.r_[0, np.cumsum(cnt)]
    toff = np.r_[0, np.cumsum([len(x) for x in tpts])].tolist()
    # most tips have no point of another chain ahead within reach: found for all at once (a
    # test a little looser than the one below, with the owners as they are now: a tip whose
    # chain is unchanged when its turn comes has no more candidates then)
    tip_of = np.repeat(np.repeat(np.arange(len(tips)), np.diff(toff)), cnt)  # the tip of each pair
    e_t = np.array([int(ids[-1]) for ids in tids], dtype=np.int64)
    # (the tip direction as below: from the first point of _end_portion's end piece, ids[-m], to
    # the tip; a prefilter only: the exact test below still runs on every tip kept)
    b_t = np.array([int(ids[-m]) if m <= len(ids) else int(ids[0]) for ids, m in zip(tids, tms)], dtype=np.int64)
    u_t = P[e_t] - P[b_t]
    u_t /= np.maximum(np.sqrt((u_t * u_t).sum(axis=1)), 1e-300)[:, None]
    jq = owner[qall]
    vq_all = P[qall] - P[e_t[tip_of]]
    cand = ((jq >= 0) & (jq != np.array([i for i, _ in tips], dtype=np.int64)[tip_of])
            & ((vq_all * u_t[tip_of]).sum(axis=1)
               >= (ATT_COS - 1e-6) * np.sqrt((vq_all * vq_all).sum(axis=1))))
    has_cand = np.bincount(tip_of[cand], minlength=len(tips)) > 0
    for t_, (i, s) in enumerate(tips):
        c = chains[i]
        if not alive[i] or c.closed or v[c.ends[s]] != 1:
            continue
        if not has_cand[t_] and c is tchain[t_]:
            continue
        r = c.ends[s]
        ids = c.ids if s == 1 else c.ids[::-1]  # running towards the tip
        e = int(ids[-1])
        same = c is tchain[t_]
        E = _end_portion(P, h, ids, span=3.0, m=tms[t_] if same else None)
        u = E[0] - E[-1]
        nu = np.linalg.norm(u)
        if nu == 0:
            continue
        u = u / nu
        # chain points of other chains within reach of the tip, ahead of it (within 45 degrees
        # of its direction): the nearest (then lowest id) is where it attaches
        if same:
            tip_pts = tpts[t_]
            a0, a1 = toff[t_], toff[t_ + 1]
            if qoff[a1] == qoff[a0]:
                continue
            q = qall[qoff[a0]:qoff[a1]]
            tp = np.repeat(tip_pts, cnt[a0:a1])
        else:  # its chain was split meanwhile: queried again
            tip_pts = np.r_[regions[r], e].astype(np.int64)
            near_t = tree.query_ball_point(P[tip_pts], ATT * prm["link"] * float(h[e]) + GAP * noise)
            cnt_t = np.fromiter((len(x) for x in near_t), dtype=np.int64, count=len(near_t))
            if not cnt_t.sum():
                continue
            q = np.concatenate([np.asarray(x, dtype=np.int64) for x in near_t])
            tp = np.repeat(tip_pts, cnt_t)
        j = owner[q]
        vq = P[q] - P[e]
        ok = (j >= 0) & (j != i) & ((vq @ u) >= ATT_COS * np.sqrt((vq * vq).sum(axis=1)))
        ok[ok] = [alive[x] for x in j[ok].tolist()]
        if not ok.any():
            continue
        q, j, tp = q[ok], j[ok], tp[ok]
        d = np.sqrt(((P[q] - P[tp]) ** 2).sum(axis=1))
        b = np.lexsort((q, d))[0]
        q, j = int(q[b]), int(j[b])
        cj = chains[j]
        k = int(np.flatnonzero(cj.ids == q)[0])
        m = len(cj.ids)
        if not cj.closed and (k < 2 or k > m - 3):
            # near an end of the other chain: join its region there
            sj = 0 if k < 2 else 1
            rr = cj.ends[sj]
            if rr == r:
                continue
            regions[rr] = np.r_[regions[rr], regions[r]]
            regions[r] = np.zeros(0, dtype=np.int64)
            c.ends[s] = rr
            ends_at[rr].append((i, s))
            ends_at[r] = []
            v[rr] += 1
            v[r] = 0
            continue
        # split chain j at q: q and its two chain neighbours form the new junction region
        lo, hi = max(k - 1, 0), min(k + 2, m)
        core = cj.ids[lo:hi]
        regions.append(np.r_[core, regions[r]].astype(np.int64))
        nr = len(regions) - 1
        ends_at.append([(i, s)])
        regions[r] = np.zeros(0, dtype=np.int64)
        ends_at[r] = []
        c.ends[s] = nr
        v[r] = 0
        v = np.r_[v, 1]
        owner[core] = -1
        if cj.closed:
            chains[j] = _Chain(np.r_[cj.ids[hi:], cj.ids[:lo]], [nr, nr])
            ends_at[nr] += [(j, 0), (j, 1)]
            v[nr] += 2
        else:
            a, b = cj.ends
            chains[j] = _Chain(cj.ids[:lo], [a, nr])
            chains.append(_Chain(cj.ids[hi:], [nr, b]))
            alive.append(True)
            jn = len(chains) - 1
            owner[chains[jn].ids] = jn
            ends_at[nr] += [(j, 1), (jn, 0)]
            ends_at[b] = [(jn, 1) if e_ == (j, 1) else e_ for e_ in ends_at[b]]
            v[nr] += 2


def _extent(P, ids):
    if len(ids) < 2:
        return 0.0
    X = P[ids]
    return float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))


def _order_between(P, ids, pa, pb):
    """Region points ordered from ``pa`` towards ``pb``."""
    if len(ids) == 0:
        return ids
    u = pb - pa
    nu = np.linalg.norm(u)
    if nu == 0:
        return ids
    proj = (P[ids] - pa) @ (u / nu)
    return ids[np.lexsort((ids, proj))]


def _end_portion(P, h, ids, span=3.0, m=None):
    """The last points of an ordered id list ``ids`` (running towards the end), over ``span`` h.

    ``m``: their number when already known (:func:`_end_counts`).
    """
    n = len(ids)
    if n < 2:
        return P[ids[::-1]]
    if m is None:
        hl = float(h[ids[-1]])
        # arc length summed backwards from the end, only as far as needed (compiled kernel)
        m = max(int(_k.end_count(P, np.asarray(ids, dtype=np.int64), span * hl)), min(3, n))
    return P[ids[: -m - 1: -1]]


def _end_counts(P, h, lists, span):
    """The number of points of :func:`_end_portion` of every id list, in one compiled call.

    Parameters
    ----------
    P : (N, d) ndarray
    h : (N,) ndarray
    lists : list of (n_i,) ndarray of int
        Id lists, each running towards its end.
    span : float

    Returns
    -------
    (len(lists),) ndarray of int64
    """
    if not lists:
        return np.zeros(0, dtype=np.int64)
    flat = np.concatenate(lists).astype(np.int64, copy=False)
    off = np.r_[0, np.cumsum([len(x) for x in lists])].astype(np.int64)
    return _k.end_counts(P, np.ascontiguousarray(h, dtype=np.float64), flat, off, float(span))


def _free_end(P, h, ids, rid, m=None):
    """Extension ids (ordered outward) and node position of a free end (``m``: the count of
    its end portion, when known)."""
    E = _end_portion(P, h, ids, span=4.0, m=m)
    tip = E[0]
    if len(E) >= 2:
        u = E[0] - E[-1]
        nu = np.linalg.norm(u)
        u = u / nu if nu > 0 else None
    else:
        u = None
    if len(rid) == 0:
        return np.zeros(0, dtype=np.int64), tip
    R = P[rid]
    if u is None:
        u = R.mean(axis=0) - tip
        nu = np.linalg.norm(u)
        u = u / nu if nu > 0 else np.eye(P.shape[1])[0]
    proj = (R - tip) @ u
    o = np.lexsort((rid, proj))
    ext = rid[o]
    ext = ext[proj[o] > -1e-12] if (proj > -1e-12).any() else ext
    # drop points behind the tip (they belong to the chain's thickness), keep the rest in order
    if len(ext) == 0:
        return ext, tip
    return ext, P[ext[-1]].copy()


def _junction(P, h, live, inc, rid, prm):
    """Node position of one junction: see :func:`_junction_positions`."""
    return _junction_positions(P, h, [(live, inc, rid)], prm)[0][0]


def _junction_positions(P, h, items, prm):
    """Least-squares intersection of the tangent lines of the incident branches, per junction.

    ``items``: ``(chains, inc, rid)`` per junction, ``inc`` the (chain, side) ends at it and
    ``rid`` its region points. The branches are first walked into the junction region
    (:func:`_robust_kernels._extend_into_region`), a walk that strays from the branch's own line
    (onto another branch, led by noise) cut where it leaves a strip of ``WALK_DEV`` link widths
    around that line; the lines are then fitted close to the junction (over ``JSPAN`` spacings, longer under
    noise: the fitted direction's error shrinks with the span) and extrapolated only a little.
    All junctions run in one compiled call (:func:`_robust_kernels._junction_nodes`).

    Returns
    -------
    X : (n_items, d) ndarray
        Node positions.
    maybe : (n_items,) ndarray of bool
        False where :func:`_swallowed_branches` surely finds nothing.
    """
    dim = P.shape[1]
    if not items:
        return np.zeros((0, dim)), np.zeros(0, dtype=bool)
    branches, nb, rids, hfall = [], [], [], []
    for chains, inc, rid in items:
        for ci, s in inc:
            c = chains[ci]
            branches.append(c.ids if s == 1 else c.ids[::-1])
        nb.append(len(inc))
        rids.append(np.asarray(rid, dtype=np.int64))
        hfall.append(0.0 if len(rid) else float(np.median([h[chains[ci].ids[0]] for ci, _ in inc])))
    bflat = np.concatenate(branches).astype(np.int64, copy=False)
    boff = np.r_[0, np.cumsum([len(b) for b in branches])].astype(np.int64)
    jb = np.r_[0, np.cumsum(nb)].astype(np.int64)
    rflat = np.concatenate(rids).astype(np.int64, copy=False)
    rlen = np.array([len(r) for r in rids], dtype=np.int64)
    grp = np.repeat(np.arange(len(rids)), rlen)
    # each junction's spacing: the median of h over its region points (as np.median: the
    # middle value, or the mean of the two middle ones), all junctions at once
    hv = h[rflat]
    o = np.lexsort((hv, grp))
    hv = hv[o]
    start = np.r_[0, np.cumsum(rlen)[:-1]]
    lo = start + np.maximum(rlen - 1, 0) // 2
    hi = start + rlen // 2
    hj = np.asarray(hfall, dtype=np.float64)
    has = rlen > 0
    hj[has] = (hv[lo[has]] + hv[np.minimum(hi, len(hv) - 1)[has]]) / 2
    # region points sorted and unique per junction
    o = np.lexsort((rflat, grp))
    rs, gs = rflat[o], grp[o]
    first = np.ones(len(rs), dtype=bool)
    first[1:] = (rs[1:] != rs[:-1]) | (gs[1:] != gs[:-1])
    rflat = rs[first]
    roff = np.r_[0, np.cumsum(np.bincount(gs[first], minlength=len(rids)))].astype(np.int64)
    graph = prm.get("_graph")
    if graph is None:
        graph = (np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64))
    noise = float(prm.get("_noise", 0.0))
    consts = _k.JunctionParams(JSPAN, JN, WALK_DEV, NW, 3.0 * _DEFAULTS["shell_outer"],
                               SWALLOW * prm["shell_outer"], SWALLOW_COS, WIDEN, "_graph" in prm)
    X, maybe = _k.junction_nodes(P, np.ascontiguousarray(h, dtype=np.float64), graph[0], graph[1],
                                 bflat, boff, jb, rflat, roff, hj,
                                 float(prm.get("_width", max(prm["link_width"], 0.0))), noise, consts)
    return X, maybe


def _region_paths(P, items, prm):
    """Dijkstra on the linked graph restricted to each region and its entry point.

    ``items``: ``(rid, entry)`` pairs. All regions run in one multi-source call on the union
    of their (disjoint) subgraphs. Returns, per item, the point ids ``S`` (``S[0] = entry``,
    then the other region points ascending), the geodesic distances from the entry and the
    predecessor of each (local positions in ``S``; -9999 for none).
    """
    from scipy.sparse import csr_matrix
    indptr, indices = prm["_graph"]
    if not items:
        return []
    # per item: the entry, then the other region points sorted and unique (as
    # np.setdiff1d(rid, [entry])), all items in one sort
    G = len(items)
    ent = np.array([entry for _, entry in items], dtype=np.int64)
    rl = np.array([len(rid) for rid, _ in items], dtype=np.int64)
    flat = np.concatenate([np.asarray(rid, dtype=np.int64) for rid, _ in items])
    fg = np.repeat(np.arange(G, dtype=np.int64), rl)
    o = np.lexsort((flat, fg))
    flat, fg = flat[o], fg[o]
    keep = np.ones(len(flat), dtype=bool)
    keep[1:] = (flat[1:] != flat[:-1]) | (fg[1:] != fg[:-1])
    keep &= flat != ent[fg]
    flat, fg = flat[keep], fg[keep]
    sizes = 1 + np.bincount(fg, minlength=G).astype(np.int64)
    start = np.r_[0, np.cumsum(sizes)[:-1]]
    grp = np.repeat(np.arange(G, dtype=np.int64), sizes)
    U = np.empty(int(sizes.sum()), dtype=np.int64)
    U[start] = ent
    rest = np.ones(len(U), dtype=bool)
    rest[start] = False
    U[rest] = flat
    Ss = [U[a:a + n] for a, n in zip(start.tolist(), sizes.tolist())]
    # position in U of (point, group): key point * G + group (a point may be in two groups)
    key = U * G + grp
    srt = np.argsort(key, kind="stable")
    ks = key[srt]
    cnt = indptr[U + 1] - indptr[U]
    rows = np.repeat(np.arange(len(U)), cnt)
    starts = np.repeat(indptr[U] - np.r_[0, np.cumsum(cnt)[:-1]], cnt)
    nb = indices[np.arange(len(rows)) + starts]
    want = nb * G + grp[rows]
    pos = np.minimum(np.searchsorted(ks, want), len(ks) - 1)
    ok = ks[pos] == want
    ea, eb = rows[ok], srt[pos[ok]]
    w = np.sqrt(((P[U[ea]] - P[U[eb]]) ** 2).sum(axis=1)) + 1e-300
    M = csr_matrix((w, (ea, eb)), shape=(len(U), len(U)))
    g, pred, _ = dijkstra(M, directed=False, indices=start, min_only=True, return_predecessors=True)
    pred = np.where(pred >= 0, pred - start[grp], pred)
    return [(S, g[o:o + n], pred[o:o + n]) for S, o, n in zip(Ss, start, sizes)]


def _path_to(pred, j):
    out = [j]
    while pred[out[-1]] >= 0:
        out.append(int(pred[out[-1]]))
    return np.asarray(out[::-1], dtype=np.int64)


def _fork_possible(P, h, ids, rid, prm):
    """False when :func:`_hidden_fork` surely finds no fork (no paths needed): a region of
    under 6 points, or all within ``FORK`` shell radii of the entry point (the second tip lies
    that far from the first path, which starts at the entry)."""
    if len(rid) < 6 or "_graph" not in prm:
        return False
    hs = float(np.median(h[rid])) + WIDEN * prm.get("_noise", 0.0)
    far = np.sqrt(((P[rid] - P[int(ids[-1])]) ** 2).sum(axis=1).max())
    return bool(far > FORK * prm["shell_outer"] * hs * (1 - 1e-9))


def _hidden_fork(P, h, ids, rid, prm, paths):
    """A fork (junction and two free branches) hidden in a free end's region, or None.

    The region is searched from the chain's last point ``ids[-1]``: the geodesically farthest
    point is one tip; a second tip lies over ``FORK`` shell radii away from that path, both
    branches from the point where the paths part are over ``min_spur`` spacings long. Returns
    the chain's extension (ids, outward, up to the fork), the node (least-squares intersection
    of the three branches' lines) and the two branches (ids ordered from the node out).
    ``paths``: the region's :func:`_region_paths` from ``ids[-1]``; the caller runs it only for
    the regions that pass :func:`_fork_possible`.
    """
    hl = float(np.median(h[rid]))
    noise = prm.get("_noise", 0.0)
    hs = hl + WIDEN * noise
    S, g, pred = paths
    fin = np.isfinite(g)
    if fin.sum() < 6:
        return None
    gg = np.where(fin, g, -1.0)
    t1 = int(np.argmax(gg))
    p1 = _path_to(pred, t1)
    X = P[S]
    d1 = np.min(np.linalg.norm(X[:, None, :] - X[p1][None, :, :], axis=2), axis=1)
    d1[~fin] = -1.0
    t2 = int(np.argmax(d1))
    if d1[t2] <= FORK * prm["shell_outer"] * hs:
        return None
    p2 = _path_to(pred, t2)
    m = min(len(p1), len(p2))
    k = int(np.flatnonzero(np.r_[p1[:m] != p2[:m], True])[0])  # first index where they differ
    if k == 0:
        return None
    f = k - 1  # the fork point: last common one
    l1, l2 = S[p1[f:]], S[p2[f:]]
    if min(_polylen(P[l1]), _polylen(P[l2])) < prm["min_spur"] * hl:
        return None
    stem = np.r_[np.asarray(ids), S[p1[1:f + 1]]]
    dim = P.shape[1]
    A = np.zeros((dim, dim))
    bb = np.zeros(dim)
    span = JSPAN + JN * noise / hl
    for br in (stem, l1[::-1], l2[::-1]):
        cc, u = _fit_line(_end_portion(P, h, br, span=span))
        if u is None:
            continue
        M = np.eye(dim) - np.outer(u, u)
        A += M
        bb += M @ cc
    anchor = P[S[p1[f]]]
    A += 1e-2 * np.eye(dim)
    bb += 1e-2 * anchor
    x = np.linalg.solve(A, bb)
    if not np.all(np.isfinite(x)) or np.linalg.norm(x - anchor) > prm["shell_outer"] * hs:
        x = anchor
    return S[p1[1:f]], x, [l1[1:], l2[1:]]


def _swallowed_branches(P, h, live, inc, rid, x, prm):
    """Free branches wholly inside a junction region, as id lists ordered from node ``x`` out.

    A region point far from the node (over ``SWALLOW`` shell radii) in a direction no incident
    branch takes is the tip of a branch shorter than the shell radius (a free end in a sparse
    place): the region points along the segment from the node to it, without a gap, form it.
    """
    if len(rid) < 3:
        return []
    hl = float(np.median(h[rid]))
    noise = prm.get("_noise", 0.0)
    hs = hl + WIDEN * noise
    dirs = []
    for ci, s in inc:
        c = live[ci]
        ids = c.ids if s == 1 else c.ids[::-1]
        E = _end_portion(P, h, np.asarray(ids), span=JSPAN)
        u = E.mean(axis=0) - x
        nu = np.linalg.norm(u)
        if nu > 0:
            dirs.append(u / nu)
    if not dirs:
        return []
    X = P[rid] - x
    d = np.linalg.norm(X, axis=1)
    cosb = (X @ np.asarray(dirs).T).max(axis=1) / np.maximum(d, 1e-300)
    cand = np.flatnonzero((d > SWALLOW * prm["shell_outer"] * hs) & (cosb < SWALLOW_COS))
    if not len(cand):
        return []
    tip = cand[np.lexsort((np.arange(len(cand)), -d[cand]))[0]]
    u = X[tip] / d[tip]
    proj = X @ u
    perp = np.sqrt(np.maximum(d * d - proj * proj, 0.0))
    lim = max(prm["_width"] * hl, NW * noise) * WALK_DEV
    on = np.flatnonzero((proj > 0) & (proj <= d[tip] * (1 + 1e-9)) & (perp <= lim))
    on = on[np.argsort(proj[on], kind="stable")]
    steps = np.diff(np.r_[0.0, proj[on]])
    if not len(on) or steps.max() > prm["link"] * hl + GAP * noise:
        return []
    return [rid[on]]


def _smooth_curve(c: Curve, nodes: np.ndarray, s_per_point: float) -> Curve:
    """A smoothing spline of one curve, pinned at its end nodes, evaluated densely.

    An open curve is fitted with heavy weights on its two end points (the nodes) and its
    first and last samples are set exactly to them. A closed loop is padded on both sides by
    a quarter of itself, fitted as an open curve, and the middle turn is kept.
    """
    from scipy.interpolate import splev, splprep

    X = c.points
    keep = np.r_[True, np.linalg.norm(np.diff(X, axis=0), axis=1) > 0]
    X = X[keep]
    m = len(X)
    if m < 6:
        return c
    q = 0
    if c.closed:
        q = max(m // 4, 3)
        X = np.vstack([X[-q:], X, X[:q + 1]])
    w = np.ones(len(X))
    if not c.closed:
        w[0] = w[-1] = 1e3  # pin the ends at the nodes
    try:
        tck, u = splprep(list(X.T), w=w, s=s_per_point * len(X), k=3, quiet=2)
    except Exception:  # pragma: no cover - degenerate input
        return c
    n_out = max(int(3 * m), 8)
    if c.closed:
        uu = np.linspace(u[q], u[q + m], n_out + 1)[:-1]
    else:
        uu = np.linspace(u[0], u[-1], n_out)
    Y = np.asarray(splev(uu, tck)).T
    if not c.closed:
        Y[0] = c.points[0]
        Y[-1] = c.points[-1]
    return Curve(Y, c.start, c.end, c.closed, np.full(len(Y), -1, dtype=np.int64))


@functools.wraps(_reconstruct_robust)
def reconstruct_robust(points, **params) -> CurveNetwork:
    # small inputs run the plain-Python kernels: no numba compile or cache load (same results)
    with _k.compiled_for(len(points)):
        return _reconstruct_robust(points, **params)
