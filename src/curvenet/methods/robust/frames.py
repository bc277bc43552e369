"""Stages 1-2: neighbours, the local spacing h, duplicate samples, tangents and the noise level.

Every point gets its k nearest neighbours, a local spacing ``h`` (:func:`local_spacing`), a unit
tangent and a linearity (:func:`tangents`, voted by its neighbours: :func:`vote_tangents`),
and the cloud a noise estimate (the median distance of a point from the chord of its nearest
strip neighbours). Noise-free samples repeated within ``SPACING.dedup`` median spacings are
dropped (:func:`coincident`). :func:`noisy_tangents` are the longer-reach frames of the strand
test (:mod:`.graph`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ...neighbors import build_tree, knn
from . import kernels as _k
from .params import Estimates, RobustParams
from .thresholds import DEFAULTS, NUMERIC, SPACING, TANGENTS

__all__ = ["Neighbours", "Tangents", "Frames", "neighbours", "neighbours_and_distances", "frames", "duplicates", "local_spacing", "tangents",
           "point_tangents", "retry_tangents", "vote_tangents", "noisy_tangents", "coincident", "isolated", "lex_order", "pair_distances"]


class Neighbours(NamedTuple):
    """The k nearest neighbours of every point and its local spacing.

    Their distances are not kept (at 16 neighbours, 128 bytes a point: the largest array of the
    method): :meth:`distances` recomputes them, the same bits as the query's.

    Attributes
    ----------
    tree : scipy.spatial.cKDTree
        Over the points (``tree.data``).
    idx : (N, k) ndarray of int32
        Ids of the k nearest neighbours (self excluded), by ascending distance (int32: half the
        size of int64).
    h : (N,) ndarray of float
        Local spacing (or the user's spacing everywhere).
    """

    tree: object
    idx: np.ndarray
    h: np.ndarray

    def distances(self, rows=None, col=None) -> np.ndarray:
        """Distances of the neighbours (of the points ``rows``; of column ``col`` only), as the
        query gave them.

        Returns
        -------
        (N, k), (R, k), (N,) or (R,) ndarray of float
        """
        I = self.idx if rows is None else self.idx[rows]
        return pair_distances(self.tree.data, rows, I if col is None else I[:, col])


class Tangents(NamedTuple):
    """Stage 2's per-point values before any whole-cloud decision (see :func:`tangents`): a
    function of each point's neighbours alone, so a tile computes them once, for its estimate
    and its reconstruction (:class:`.pipeline.Prepared`).

    Attributes
    ----------
    t : (N, d) ndarray
        Unit tangents, before the retry and the vote.
    lin : (N,) ndarray
        Linearity.
    rms : (N,) ndarray
        Noise estimate of each point (NaN where there is none).
    gain : (N,) ndarray
        See :func:`tangents`.
    """

    t: np.ndarray
    lin: np.ndarray
    rms: np.ndarray
    gain: np.ndarray


def point_tangents(P: np.ndarray, nb: Neighbours) -> Tangents:
    """The :class:`Tangents` of every point of ``P`` (N, d) from its neighbours ``nb``."""
    return Tangents(*tangents(P, nb.idx, nb.h, order=np.arange(len(P), dtype=np.int64)))


class Frames(NamedTuple):
    """Tangents and the noise level.

    Attributes
    ----------
    t : (N, d) ndarray
        Unit tangents.
    lin : (N,) ndarray
        Linearity ``1 - l2 / l1`` (low where the tangent is not reliable).
    sigma : float
        Estimated noise standard deviation per coordinate.
    hmed : float
        Median spacing.
    clean : bool
        ``sigma`` under ``SPACING.dedup_noise`` median spacings (:attr:`.params.Estimates.clean`).
    """

    t: np.ndarray
    lin: np.ndarray
    sigma: float
    hmed: float
    clean: bool

    @property
    def low(self) -> bool:
        """``sigma`` under ``NOISE.low`` median spacings (:attr:`.params.Estimates.low`)."""
        return Estimates(self.hmed, self.sigma).low


def neighbours(P: np.ndarray, prm: RobustParams) -> Neighbours:
    """Stage 1: the k-d tree, the k nearest neighbours and the local spacing of the points ``P``."""
    return neighbours_and_distances(P, prm)[0]  # (the distances go: Neighbours.distances recomputes them)


def neighbours_and_distances(P: np.ndarray, prm: RobustParams) -> tuple[Neighbours, np.ndarray]:
    """:func:`neighbours`, and the (N, k) distances of the query, for a caller that needs them
    all (:meth:`Neighbours.distances` would recompute the same bits, at the cost of a gather of
    every neighbour's coordinates: a third of the whole-cloud estimates' time)."""
    tree = build_tree(P)  # kept for the repairs (repairs.attach_dangling)
    dist, idx = knn(P, prm.k, ordered=True, tree=tree, index_dtype=_k.INDEX)
    h = local_spacing(dist, idx) if prm.spacing is None else np.full(len(P), float(prm.spacing))
    return Neighbours(tree, idx, h), dist


def pair_distances(P: np.ndarray, rows, I: np.ndarray) -> np.ndarray:
    """``|P[I] - P[rows]|`` summed as scipy's k-d tree query sums it (the squared coordinate
    differences, first to last, then the root): the same bits as the distances it returns.

    Parameters
    ----------
    P : (N, d) ndarray
    rows : (R,) ndarray of int or None
        The points (None: all, R = N).
    I : (R,) or (R, m) ndarray of int
        Ids of other points, a row (or one id) for each.

    Returns
    -------
    ndarray of float, the shape of ``I``
    """
    Q = P if rows is None else P[rows]
    s = np.zeros(I.shape)
    for c in range(P.shape[1]):
        q = Q[:, c] if I.ndim == 1 else Q[:, c, None]
        v = P[I, c] - q
        s += v * v
    return np.sqrt(s)


def frames(P: np.ndarray, nb: Neighbours, est: Estimates | None = None, tg: Tangents | None = None) -> Frames:
    """Stage 2: tangents, linearity and the noise level (see :func:`tangents`).

    Noise-free input (estimated noise under ``SPACING.dedup_noise`` median spacings) retries the
    tangents near close curves with the smaller margin (:func:`retry_tangents`); under noise
    the vote takes in more neighbours (a tangent thrown across close curves by noise has more
    of its neighbours' to outvote it). ``est``: the whole cloud's median spacing and noise,
    used instead of those of ``P`` (a tile of a larger cloud decides as the whole). ``tg``: the
    points' :func:`point_tangents`, when already computed.
    """
    idx, h = nb.idx, nb.h
    t, lin, rms, gain = point_tangents(P, nb) if tg is None else tg
    if est is None:
        sig = median_noise(rms)
        hmed = median_spacing(h)
    else:
        sig, hmed = float(est.sigma), float(est.hmed)
    clean = Estimates(hmed, sig).clean
    if clean:
        t, lin = retry_tangents(P, idx, h, t, lin, gain)
    t, lin = vote_tangents(t, lin, idx, m=min(TANGENTS.vote_m if clean else TANGENTS.vote_m_noisy, idx.shape[1]), P=P)
    return Frames(t, lin, sig, hmed, bool(clean))


def duplicates(nb: Neighbours, fr: Frames) -> np.ndarray | None:
    """The points to keep when noise-free samples repeat one place, else None.

    Noise-free samples closer than ``SPACING.dedup`` median spacings are one place sampled twice
    (overlapping strokes, a curve given twice): the later ones (internal order) go, unless
    fewer than ``DEFAULTS.min_points`` would remain. Under noise, close samples are noise: kept.

    Returns
    -------
    (M,) ndarray of int64 or None
        Ids of the points kept, ascending.
    """
    r = dedup_radius(Estimates(fr.hmed, fr.sigma))
    if r is None:
        return None
    dup = coincident(nb, r)
    if not dedup_applies(len(dup), int(np.count_nonzero(dup))):
        return None
    return np.flatnonzero(~dup)


def isolated(nb: Neighbours, hmed: float) -> np.ndarray | None:
    """The points to keep when some are alone in space, else None.

    A point whose ``SPACING.n_mean``-th nearest neighbour lies farther than ``SPACING.isolated``
    median spacings ``hmed`` (the whole cloud's: :class:`Estimates`) is an outlier, not a sample
    of a curve: every radius of the method is in local spacings, and its own would reach that
    far. The test of a point looks no farther than that radius and depends on nothing else
    (no count over the cloud), so a part of the cloud holding the point's surroundings to that
    radius (a tile with its halo) decides it as the whole cloud.

    Returns
    -------
    (M,) ndarray of int64 or None
        Ids of the points kept, ascending (possibly none); None when every point is kept.
    """
    m = min(SPACING.n_mean, nb.idx.shape[1])
    if m == 0:
        return None
    alone = nb.distances(col=m - 1) > SPACING.isolated * hmed
    if not alone.any():
        return None
    return np.flatnonzero(~alone)


def median_spacing(h: np.ndarray) -> float:
    """``Estimates.hmed`` from the local spacings (N,) of the points."""
    return float(np.median(h))


def median_noise(rms: np.ndarray) -> float:
    """``Estimates.sigma`` from the per-point noise estimates (N,) (NaN: none)."""
    return float(np.nanmedian(rms)) if np.isfinite(rms).any() else 0.0


def dedup_radius(first: Estimates) -> float | None:
    """The duplicate rule's radius for a cloud of estimates ``first`` (taken on all of its
    points), or None when the rule does not apply (noisy input: close samples are noise)."""
    return SPACING.dedup * first.hmed if first.clean else None


def dedup_applies(n_points: int, n_duplicates: int) -> bool:
    """Whether duplicates are dropped: some were found and at least ``DEFAULTS.min_points``
    points would remain (else the cloud is kept whole)."""
    return n_duplicates > 0 and n_points - n_duplicates >= DEFAULTS.min_points


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
        and its 8 nearest neighbours. Neighbours closer than ``SPACING.dup`` times that first mean are
        the same place sampled twice (overlapping strokes, a curve given twice): they are
        skipped and the mean is taken over the next ones, so that coincident samples do not
        shrink the spacing (and every radius) below the gaps along the curve. So are those
        closer than ``SPACING.dup_k`` times the k-th neighbour's distance over k / 2 (about one
        spacing on a curve): several curves ending on one sample make the first mean tiny.
    """
    if _k.compiled_active() and dist.shape[1] <= SPACING.kernel_k_max:
        # compiled, one pass over the rows, the same numbers as the numpy formula below
        h = _k.spacing(np.ascontiguousarray(dist, dtype=np.float64), np.ascontiguousarray(idx, dtype=_k.INDEX),
                       float(SPACING.dup), float(SPACING.dup_k))
        return _spacing_floor(h)
    m = min(SPACING.n_mean, dist.shape[1])
    div = SPACING.mean_div if m >= SPACING.n_mean else 1.0
    raw = np.empty(len(dist))
    step = SPACING.block  # rows at a time: the (rows, k) temporaries stay small at any N
    for a in range(0, len(dist), step):
        D = dist[a:a + step]
        raw0 = D[:, :m].mean(axis=1) / div
        # several samples at one place (curves ending at one node) make raw0 tiny: the k-th
        # neighbour, about k / 2 spacings away on a curve, sets a floor to the duplicate test
        thr = np.maximum(SPACING.dup * raw0, SPACING.dup_k * D[:, -1] / (0.5 * D.shape[1]))
        keep = D >= thr[:, None]
        sel = keep & (np.cumsum(keep, axis=1) <= m)
        cnt = sel.sum(axis=1)
        raw[a:a + step] = np.where(cnt >= m, np.where(sel, D, 0.0).sum(axis=1) / np.maximum(cnt, 1) / div, raw0)
    j = min(SPACING.n_median, idx.shape[1])
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
    floor = (pos.min() if len(pos) else 1.0) * SPACING.floor
    return np.maximum(h, floor)


def tangents(P: np.ndarray, idx: np.ndarray, h: np.ndarray, m: int = TANGENTS.strip_m, order=None, margin=None):
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
        where none was tried); see :func:`retry_tangents`.
    """
    m = min(m, idx.shape[1])
    # compiled, one point at a time: the 4-neighbour PCA, then twice the PCA of the point and
    # its m nearest within h of the current line (weights 0/1: a weighted PCA, whose numpy
    # formula on stacked arrays is the reference of tests/test_robust_kernels.py);
    # and the noise: distance of each point from the chord between its nearest strip neighbours
    # on either side (NaN without both; curvature adds only h^2 / 2R there); for Gaussian
    # noise of std sigma per coordinate its RMS is sigma * sqrt(1.5 (d - 1))
    t, lin, cr, gain = _k.tangents(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(idx, dtype=_k.INDEX),
                                   np.ascontiguousarray(h, dtype=np.float64), m, order, margin=margin)
    dim = P.shape[1]
    # (x 1.28: picking the nearest neighbour on each side favours points pulled towards p)
    rms = TANGENTS.rms_bias * cr / np.sqrt(TANGENTS.rms_dim * max(dim - 1, 1))
    return t, lin, rms, gain


def retry_tangents(P, idx, h, t, lin, gain, m: int = TANGENTS.strip_m):
    """Tangents of noise-free input: the points whose best neighbour direction scores between
    :data:`TANGENTS.cand_margin_clean` and the kernels' margin more than the 4-neighbour direction are
    done again with the smaller margin (few points: near close curves, junctions, corners)."""
    redo = np.flatnonzero((gain > TANGENTS.cand_margin_clean) & (gain <= _k.CAND_MARGIN))
    if len(redo) == 0:
        return t, lin
    t2, lin2, _, _ = tangents(P, idx, h, m, order=redo, margin=TANGENTS.cand_margin_clean)
    t = t.copy()
    lin = lin.copy()
    t[redo] = t2[redo]
    lin[redo] = lin2[redo]
    return t, lin


def vote_tangents(t, lin, idx, m=TANGENTS.vote_m, P=None):
    """Tangents by a vote of the point and its ``m`` nearest neighbours (tensor sum of t t^T).

    A tangent thrown across close parallel curves by noise is outvoted by its neighbours'.
    The linearity becomes the smaller of the point's own and the vote's coherence
    ``1 - l2 / l1`` (low at junctions, where neighbours vote for different branches).

    With the points ``P`` ((N, d); ``idx`` sorted by distance), a tangent stays when its own
    samples say it: its ``TANGENTS.vote_keep_nearest`` nearest neighbours lie on either side of
    the point, each within ``TANGENTS.vote_keep_cos`` of its tangent and none within it of the
    vote's direction (a short curve between two other curves, whose 16 nearest neighbours are
    mostly theirs: a plate's edges 6 h long between its faces were voted onto the faces'
    direction and lost their links). Without ``P`` (the strand test's noisy tangents) every
    tangent at odds with a coherent vote is replaced.
    """
    m = min(m, idx.shape[1])
    # only a tangent clearly at odds with a coherent vote is replaced. With C = sum T_k T_k^T,
    # eigenvalues l1 >= l2 and l1 <= m + 1: a swap needs |u.t| < c (u the top eigenvector) and
    # l2 <= (1 - TANGENTS.vote_coh) l1, hence t^T C t <= (m + 1) (c^2 + (1 - TANGENTS.vote_coh) (1 - c^2)); the
    # eigen-decomposition is computed only for the points below that bound (few on clean data);
    # t^T C t = sum_k (T_k . t)^2 is computed in a compiled loop (no (N, m + 1, d) array)
    agree = _k.vote_agreement(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(idx, dtype=_k.INDEX), m)
    bound = (m + 1) * (TANGENTS.vote_cos**2 + (1.0 - TANGENTS.vote_coh) * (1.0 - TANGENTS.vote_cos**2))
    cand = np.flatnonzero(agree <= bound * (1 + NUMERIC.rel))
    if len(cand) == 0:
        return t, lin
    # the top eigenpair of C for the candidates (compiled, closed form: kernels.linalg._eig_top)
    u, coh = _k.vote_eig(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(idx, dtype=_k.INDEX), m,
                         cand.astype(np.int64))
    swap = (np.abs(np.einsum("nd,nd->n", u, t[cand])) < TANGENTS.vote_cos) & (coh >= TANGENTS.vote_coh)
    if P is not None and swap.any():
        swap[np.flatnonzero(swap)[_own_line(P, idx, t, cand[swap], u[swap])]] = False
    sw = cand[swap]
    t = t.copy()
    lin = lin.copy()
    t[sw] = u[swap]
    lin[sw] = np.minimum(lin[sw], coh[swap])
    return t, lin


def _own_line(P, idx, t, pts, u):
    """Which of the points ``pts`` keep their tangent against the vote's direction ``u``
    ((len(pts), d)): their ``TANGENTS.vote_keep_nearest`` nearest neighbours (``idx``, sorted by
    distance) lie on both sides of the point along its tangent ``t``, each within
    ``TANGENTS.vote_keep_cos`` of it and none within that of ``u`` (see :func:`vote_tangents`).

    Returns
    -------
    (len(pts),) ndarray of bool
    """
    k = min(TANGENTS.vote_keep_nearest, idx.shape[1])
    E = P[idx[pts, :k]] - P[pts][:, None, :]
    E /= np.maximum(np.linalg.norm(E, axis=2, keepdims=True), NUMERIC.tiny)
    along = np.einsum("nkd,nd->nk", E, t[pts])
    across = np.abs(np.einsum("nkd,nd->nk", E, u))
    sides = (along.max(axis=1) > 0) & (along.min(axis=1) < 0)
    return sides & (np.abs(along) > TANGENTS.vote_keep_cos).all(axis=1) & (across < TANGENTS.vote_keep_cos).all(axis=1)


def noisy_tangents(P, h, sig, tree, dist, idx):
    """Tangents and linearity of a noisy cloud found over a longer reach
    (:func:`kernels.frames._noisy_tangents`, over the ``TANGENTS.noisy_k`` nearest neighbours): the
    frames of the strand test (:func:`cut_strand_links`).

    Where sparse, noisy curves run a few spacings apart, a point's nearest neighbours lie as
    often on the next curve as on its own, and the 4-neighbour start of :func:`tangents` often
    points across (on the "eye" under noise 0.3h and density x3, after the vote: 8.6% of the
    points more than 30 degrees off; 0.1% with these). Used as the tangents of the whole method
    they cost the mug's junctions (bench samplings 0 and 1), so they serve this test only.

    The method's own neighbours (``idx``: (N, k), sorted by distance; ``dist`` their distances,
    or None: recomputed where needed, :func:`pair_distances`) serve the
    points whose last one (or ``TANGENTS.noisy_k``-th) lies beyond the kernel's reach
    (:func:`kernels.noisy_reach`): the farther ones would change nothing (on a lone
    curve, most points). The others get their ``TANGENTS.noisy_k`` nearest from ``tree``, in blocks.

    Returns
    -------
    T : (N, d) ndarray
    lin : (N,) ndarray
    """
    P = np.ascontiguousarray(P, dtype=np.float64)
    h = np.ascontiguousarray(h, dtype=np.float64)
    sig = float(sig)
    N = len(P)
    k = min(TANGENTS.noisy_k, N - 1)
    T = np.empty_like(P)
    lin = np.empty(N)
    kk = min(idx.shape[1], k)  # the method's neighbours the kernel may take
    if kk >= k:
        short = np.ones(N, dtype=bool)  # (as many as the kernel's)
    elif kk >= min(_k.NOISY_CAND, k) and kk > 0:
        far = pair_distances(P, None, idx[:, kk - 1]) if dist is None else dist[:, kk - 1]
        short = far > _k.noisy_reach(h, sig)
    else:
        short = np.zeros(N, dtype=bool)
    rows = np.flatnonzero(short)
    if len(rows):
        T[rows], lin[rows] = _k.noisy_tangents(P, rows, np.ascontiguousarray(idx[rows, :kk], dtype=_k.INDEX), h, sig)
    rows = np.flatnonzero(~short)
    for s in range(0, len(rows), TANGENTS.noisy_block):  # blocks: the (rows, 32) neighbour ids stay small
        r = rows[s:s + TANGENTS.noisy_block]
        _, nb = knn(P, k, tree=tree, rows=r, index_dtype=_k.INDEX)
        T[r], lin[r] = _k.noisy_tangents(P, r, nb, h, sig)
    return T, lin


def coincident(nb: Neighbours, r):
    """Points with a neighbour earlier in the (internal) order closer than ``r``.

    Parameters
    ----------
    nb : Neighbours
    r : float

    Returns
    -------
    (N,) bool ndarray
    """
    dup = np.zeros(len(nb.idx), dtype=bool)
    if nb.idx.shape[1] == 0:
        return dup
    rows = np.flatnonzero(nb.distances(col=0) < r)
    if len(rows):
        dup[rows] = ((nb.distances(rows) < r) & (nb.idx[rows] < rows[:, None])).any(axis=1)
    return dup


def lex_order(P):
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
