"""Stage 8: the curves, each ending exactly at its nodes; fitted under noise.

Chain points lying behind their junction node (an overshoot into another branch) are trimmed
(:func:`build_curves`); every open curve runs from its node through the free-end extension,
the chain and the other extension to its other node (:func:`open_curves`); a curve or loop
that turns back on itself is reordered into a shorter path (:func:`untangle_loops`); curves
are sorted canonically (:func:`sort_curves`); samples far off the chord of their neighbours
(outliers a chain took in) are dropped (:func:`drop_spikes`); under noise, each curve's samples
are moved onto a smoothing spline fitted through them (:func:`fit_curves`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ...network import Curve
from . import kernels as _k
from .chains import segment_distance
from .nodes import Placement
from .thresholds import CURVES, FIT, LAYOUT, NODES, NUMERIC

__all__ = ["build_curves", "open_curves", "untangle_loops", "sort_curves", "renumbered", "end_nodes", "fit_curves",
           "drop_spikes"]


def build_curves(P: np.ndarray, h: np.ndarray, pl: Placement) -> list[Curve]:
    """Stage 8: the curves of the live chains, their nodes' extensions and the extra branches.

    Parameters
    ----------
    P : (N, d) ndarray
    h : (N,) ndarray
    pl : Placement

    Returns
    -------
    list of Curve
        Sorted (:func:`sort_curves`); ``indices`` are internal point ids (-1 at computed nodes).
    """
    live, v, nodes, new_id, node_of, end_ext = pl.live, pl.v, pl.nodes, pl.new_id, pl.node_of, pl.end_ext
    # at a junction, chain points lying behind the node (the chain overshot it into another
    # branch) are dropped (all open chains in one compiled call)
    opn = [ci for ci, c in enumerate(live) if not c.closed]
    trim = {}
    if opn:
        vl = v.tolist()
        node_arr = np.full(len(v), -1, dtype=np.int64)
        node_arr[list(node_of)] = list(node_of.values())
        ends = np.fromiter(itertools.chain.from_iterable(live[ci].ends for ci in opn), dtype=np.int64,
                           count=2 * len(opn))
        ends = new_id[node_arr[ends]].reshape(-1, 2)
        do0 = np.array([(ci, 0) not in end_ext and vl[live[ci].ends[0]] >= 2 for ci in opn])
        do1 = np.array([(ci, 1) not in end_ext and vl[live[ci].ends[1]] >= 2 for ci in opn])
        flat = np.concatenate([live[ci].ids for ci in opn]).astype(np.int64, copy=False)
        off = np.r_[0, np.cumsum([len(live[ci].ids) for ci in opn])].astype(np.int64)
        lo, hi = _k.trim_ends(P, np.ascontiguousarray(h, dtype=np.float64), flat, off, do0, do1,
                              nodes[ends[:, 0]], nodes[ends[:, 1]], 2.0 * NODES.span)
        trim = {ci: flat[lo[i]:hi[i]] for i, ci in enumerate(opn)}
    curves: list = [None] * len(live)
    loops = [ci for ci, c in enumerate(live) if c.closed]
    for ci, ids in zip(loops, untangle_loops(P, [live[ci].ids for ci in loops])):
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
        curves_open = open_curves(P, nodes, np.concatenate(pieces).astype(np.int64, copy=False),
                                  n0 + (hi - lo) + n1, ends[:, 0], ends[:, 1], last0, last1)
        for ci, cv in zip(opn, curves_open):
            curves[ci] = cv
    for j, t, br in pl.extra:
        a, b = int(new_id[j]), int(new_id[t])
        cv = Curve(np.vstack([nodes[a], P[br]]), a, b, False, np.r_[-1, br].astype(np.int64))
        if a > b:
            cv = cv.reversed()
        curves.append(cv)
    return sort_curves(curves)


def open_curves(P, nodes, ids, nids, a, b, last0, last1):
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
    del local, src  # (memory: the (M,) temporaries go before the next ones come)
    at_a = np.flatnonzero(~inner & (k < 0))
    at_b = np.flatnonzero(~inner & (k >= 0))
    del k, inner
    pts = P[np.maximum(ind, 0)]
    pts[at_a] = nodes[a[cid[at_a]]]
    pts[at_b] = nodes[b[cid[at_b]]]
    del cid
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


def untangle_loops(P, loops):
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
    (:func:`curvenet.methods.robust.kernels.untangle`)."""
    which = _turning_back(X, off)
    if not len(which):
        return None, which
    order = _k.untangle(X, np.asarray(off, dtype=np.int64), which.astype(np.int64), CURVES.untangle_w, CURVES.turn_back_cos)
    return order, which


def _turning_back(X, off):
    """The curves (points ``X[off[i]:off[i + 1]]``, concatenated) with two successive steps
    whose directions are more than 120 degrees apart (``CURVES.turn_back_cos``), ascending;
    in blocks of about ``LAYOUT.curve_block`` points (the temporaries stay small)."""
    off = np.asarray(off, dtype=np.int64)
    out, i, nc = [], 0, len(off) - 1
    while i < nc:
        j = max(i + 1, min(nc, int(np.searchsorted(off, off[i] + LAYOUT.curve_block, side="right")) - 1))
        out.append(i + _turning_back_block(X[off[i]:off[j]], off[i:j + 1] - off[i]))
        i = j
    return np.concatenate(out) if out else np.zeros(0, dtype=np.int64)


def _turning_back_block(X, off):
    """:func:`_turning_back` of one block of curves."""
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
    return np.unique(cid[idx[1:]][pair & (cosang < CURVES.turn_back_cos)])


def sort_curves(curves):
    """The curves by start node, end node (-1 for none), then second point rounded to 9
    decimals (the first for a curve of one point); ties keep their order."""
    if not curves:
        return curves
    n = len(curves)
    st = np.fromiter((-1 if c.start is None else c.start for c in curves), dtype=np.int64, count=n)
    en = np.fromiter((-1 if c.end is None else c.end for c in curves), dtype=np.int64, count=n)
    X = np.round(np.stack([c.points[min(1, len(c.points) - 1)] for c in curves]), CURVES.round_decimals)
    o = np.lexsort(tuple(X[:, j] for j in range(X.shape[1] - 1, -1, -1)) + (en, st))
    return [curves[i] for i in o.tolist()]


def end_nodes(curves: list[Curve], n: int) -> tuple[np.ndarray, np.ndarray]:
    """The node ids at both ends of every curve and the valence of every node.

    Parameters
    ----------
    curves : list of Curve
    n : int
        The number of nodes.

    Returns
    -------
    ends : (len(curves), 2) ndarray of int64
        Start and end node of each curve (-1: none, a loop without node).
    valence : (n,) ndarray of int64
        The number of curve ends at each node.
    """
    m = len(curves)
    ends = np.fromiter(itertools.chain.from_iterable((-1 if c.start is None else c.start, -1 if c.end is None else c.end)
                                                     for c in curves), dtype=np.int64, count=2 * m).reshape(m, 2)
    return ends, np.bincount(ends[ends >= 0], minlength=n)


def renumbered(X: np.ndarray, curves: list[Curve], drop=()) -> tuple[np.ndarray, list[Curve]]:
    """The nodes ``X`` (n, d) without the rows ``drop`` (no curve ends there), sorted by
    coordinates (rounded to ``CURVES.round_decimals``), and the curves with their node ids
    renumbered, each oriented from its lower node id, sorted as :func:`sort_curves` sorts them.

    Returns
    -------
    nodes : (n - len(drop), d) ndarray
    curves : list of Curve
        New list (curves without nodes are the inputs' objects).
    """
    keep = np.ones(len(X), dtype=bool)
    keep[np.asarray(list(drop), dtype=np.int64)] = False
    kept = np.flatnonzero(keep)
    order = kept[np.lexsort(np.round(X[kept], CURVES.round_decimals).T[::-1])]
    new_id = np.full(len(X), -1, dtype=np.int64)
    new_id[order] = np.arange(len(order))
    final: list[Curve] = []
    for c in curves:
        if c.start is None:
            final.append(c)
            continue
        cv = Curve(c.points, int(new_id[c.start]), int(new_id[c.end]), c.closed, c.indices)
        if cv.start > cv.end:
            cv = cv.reversed()
        final.append(cv)
    return X[order], sort_curves(final)


def fit_curves(curves: list[Curve], sigma: float, band: float | None = None) -> list[Curve]:
    """The curves fitted by penalised smoothing splines: the noise of their samples averaged out.

    Each curve keeps its samples (and their input ``indices``); their positions become the
    values, at the same samples, of the sequence ``y`` that minimises

    ``sum_i |y_i - x_i|^2 + sum_j (b_j s_j)^(2 k) |Dk y_j|^2``

    over the curve's samples ``x``, where ``Dk y_j`` is ``k!`` times the ``k``-th divided
    difference of ``y`` over the window of ``k + 1`` samples at sample ``j`` in the
    chord-length parameter (``k = FIT.order``, 3: about the third derivative) and ``s_j`` the
    window's mean step: a discrete smoothing spline (Reinsch 1967 for ``k`` 2; ``k`` 3 leaves
    quadratics unpenalised, so a bend of steady curvature is pulled in as ``b^6``, not ``b^4``)
    whose equivalent kernel is about ``b_j`` local spacings wide (Silverman 1984), so a
    sample's noise is averaged with that of its neighbours along the curve. An open curve's
    two ends are held where they are (at its nodes); a closed loop is periodic (no seam).

    The width ``b_j`` is chosen per sample from the noise ``sigma`` (Lepski's idea): the curves
    are fitted with ``FIT.widths`` candidate widths from ``FIT.band_min`` to ``FIT.band``; a
    candidate whose fit parts (across the curve) from the narrowest one by more than the noise
    explains (the parting averaged along the curve over ``FIT.bias_reach`` and over
    ``FIT.bias_reach_long`` of its reaches: the larger) rounds a bend or a corner, and each
    sample takes the candidate of least expected squared error: that bias squared, plus the
    noise variance its kernel keeps (falling as ``1 / b``), see :func:`_widths`. On a straight
    or gently bent stretch the width stays ``FIT.band``; within a few samples of a held end it
    is at most ``FIT.end_taper`` times their number (a node placed a little off the samples
    pulls only the last few).

    Parameters
    ----------
    curves : list of Curve
        Each open curve's first and last points are its nodes' positions.
    sigma : float
        Standard deviation of the noise per coordinate (the method's estimate), in the units
        of the points.
    band : float, optional
        One width for every sample, in local spacings, instead of the choice above; 0 leaves
        the curves as they are.

    Returns
    -------
    list of Curve
        New curves, in the same order, with the same ends, closedness and ``indices`` and
        (m, d) fitted points; curves of fewer than ``FIT.min_points`` samples are the same
        objects.

    Notes
    -----
    Every curve is solved at once, in one sparse symmetric system of as many unknowns as
    samples (banded but for the wrap-around of the loops): ``FIT.widths`` + 1 solves in all
    (one per candidate width, then the chosen ones), linear in the number of samples.
    """
    sel = [i for i, c in enumerate(curves) if len(c.points) >= FIT.min_points]
    if (band is not None and band <= 0) or not sel:
        return list(curves)
    out = list(curves)
    # the curves are independent of each other: solved in blocks of about LAYOUT.curve_block
    # samples (whole curves), so the system and its temporaries (about 30 arrays of one value
    # a sample) stay small at any size
    sizes = np.array([len(curves[i].points) for i in sel], dtype=np.int64)
    start = 0
    while start < len(sel):
        stop = start + max(1, int(np.searchsorted(np.cumsum(sizes[start:]), LAYOUT.curve_block, side="right")))
        block = sel[start:stop]
        X = np.concatenate([curves[i].points for i in block])
        m = sizes[start:stop]
        closed = np.array([bool(curves[i].closed) for i in block])
        ch = _Chains(X, m, closed)
        corner, at = _corners(ch, float(sigma))
        if corner.any():  # held where found, the two sides fitted apart
            X = X.copy()
            X[corner] = at
            ch = _Chains(X, m, closed, corner)
        if band is not None:
            Y = ch.solve(np.full(len(X), float(band)))
        else:
            Y = ch.solve(_widths(ch, float(sigma)))
        off = np.r_[0, np.cumsum(m)].tolist()
        for k, i in enumerate(block):
            c = curves[i]
            out[i] = Curve(Y[off[k]:off[k + 1]], c.start, c.end, c.closed, c.indices.copy())
        start = stop
    return out


def _widths(ch: "_Chains", sigma: float) -> np.ndarray:
    """(M,) kernel width per sample, in local spacings (see :func:`fit_curves`).

    The curves are fitted with each of ``FIT.widths`` candidate widths, geometric from
    ``FIT.band_min`` to ``FIT.band``. A candidate's squared bias at a sample is read as the
    squared parting (across the curve) of its fit from the narrowest one, averaged along the
    curve (over ``FIT.bias_reach`` and ``FIT.bias_reach_long`` of its reaches: the larger),
    less what the noise alone puts between the two fits; its variance is what its kernel keeps
    of the noise. Each sample takes the candidate of least sum. Read so, the bias of every
    candidate is measured, not extrapolated from the widest one by a power of the width (which
    holds on smooth bends but not on a traced neurite's zigzag, whose bias grows about as the
    width itself)."""
    cand = np.geomspace(FIT.band_min, FIT.band, FIT.widths)
    fits = [ch.solve(np.full(ch.M, b)) for b in cand]
    d = ch.X.shape[1]
    t = fits[-1][ch.nxt_open] - fits[-1][ch.prv_open]
    t /= np.maximum(np.linalg.norm(t, axis=1), NUMERIC.tiny)[:, None]
    var = (d - 1) * kernel_l2(FIT.order) * sigma**2  # the noise a kernel of width 1 keeps (across)
    mse = np.empty((len(cand), ch.M))
    mse[0] = var / cand[0]
    for i in range(1, len(cand)):
        D = fits[0] - fits[i]
        D -= (D * t).sum(axis=1)[:, None] * t  # across the curve only
        part = (D * D).sum(axis=1)
        part2 = np.maximum(_window_mean(part, ch, int(np.ceil(FIT.bias_reach * cand[i]))),
                           _window_mean(part, ch, int(np.ceil(FIT.bias_reach_long * cand[i]))))
        mse[i] = np.maximum(part2 - var * (1.0 / cand[0] - 1.0 / cand[i]), 0.0) + var / cand[i]
    best = cand[np.argmin(mse, axis=0)]
    # near a held end no wider than its distance from it in samples: a node placed off the
    # samples then pulls only the last few of them
    return np.clip(np.minimum(best, FIT.end_taper * ch.to_held), cand[0], cand[-1])


def kernel_l2(order: int) -> float:
    """Squared L2 norm of the fit's equivalent kernel of width 1 spacing: a fit of width ``b``
    spacings keeps ``kernel_l2 / b`` of the noise's variance.

    The penalty of the ``order``-th derivative gives the kernel whose transfer function is
    ``1 / (1 + w^(2 order))`` (Silverman 1984 for ``order`` 2); the squared norm is
    ``(1 / 2 pi) int 1 / (1 + w^(2 m))^2 dw = (2 m - 1) / (2 m) / (2 m sin(pi / (2 m)))``:
    ``3 / (8 sqrt 2)`` for 2, ``5 / 18`` for 3.
    """
    m = float(order)
    return (2.0 * m - 1.0) / (2.0 * m) / (2.0 * m * np.sin(np.pi / (2.0 * m)))


def _to_held(held: np.ndarray, idx: np.ndarray, first: np.ndarray, last: np.ndarray,
             loop: np.ndarray) -> np.ndarray:
    """(M,) samples from each sample to the nearest held one of its curve (along a loop either
    way round; ``inf`` on a curve without one)."""
    M = len(held)
    far = M  # (farther than any two samples of one curve)
    # the nearest held sample at or before / at or after each sample, in the concatenation
    before = np.maximum.accumulate(np.where(held, idx, -far))
    after = np.minimum.accumulate(np.where(held, idx, M + far)[::-1])[::-1]
    d = np.minimum(np.where(before >= first, idx - before, far), np.where(after <= last, after - idx, far))
    # a loop wraps: from a sample back past its first sample to its last held one, or on past
    # its last sample to its first held one
    lo_h, hi_h = after[first], before[last]  # each curve's first and last held sample
    has = (lo_h <= last) & (hi_h >= first)
    wrap = np.minimum(idx - first + last - hi_h + 1, last - idx + lo_h - first + 1)
    d = np.where(loop & has, np.minimum(d, wrap), d)
    return np.where(d < far, d, np.inf).astype(float)


def _corners(ch: "_Chains", sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """The samples at sharp corners of the curves, and where each corner lies.

    Over the ``FIT.corner_reach`` samples on either side of a sample (chord-length parameter
    ``s``, 0 at the sample), two models of as many parameters are fitted by least squares to
    each coordinate: a parabola ``a + b s + c s^2`` (a smooth bend) and a hinge
    ``a + b s + c max(s, 0)`` (two lines meeting at the sample). A corner is where the hinge
    fits better by at least ``FIT.corner_gain`` noise variances (sum of squares over the
    window and the coordinates), its two lines turn by at least ``FIT.corner_turn`` degrees,
    and no sample within the reach fits the hinge better by more; the corner lies at the
    hinge's knot (``a``). Noise-free curves, curves shorter than two reaches and the samples
    within a reach of an open curve's ends have none.

    Returns
    -------
    corner : (M,) bool ndarray
    at : (n_corners, d) float ndarray
        The corners' positions, in the order of the samples.
    """
    M, d = ch.X.shape
    L = int(FIT.corner_reach)
    none = np.zeros(M, dtype=bool), np.zeros((0, d))
    if not sigma > 0 or M < 2 * L + 1:
        return none
    idx, first, last = ch.idx, ch.first, ch.last
    n = last - first + 1
    ok = np.where(ch.loop, n >= 2 * L + 1, (idx - first >= L) & (last - idx >= L))
    # a cheap bound first: the chords to the samples a reach away turn by FIT.corner_chord of
    # the angle at least
    ok_ids = np.flatnonzero(ok)
    back = first[ok_ids] + (ok_ids - first[ok_ids] - L) % n[ok_ids]
    ahead = first[ok_ids] + (ok_ids - first[ok_ids] + L) % n[ok_ids]
    u, v = ch.X[ok_ids] - ch.X[back], ch.X[ahead] - ch.X[ok_ids]
    cos = (u * v).sum(axis=1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), NUMERIC.tiny)
    cand = ok_ids[cos <= np.cos(np.radians(FIT.corner_chord * FIT.corner_turn))]
    if not len(cand):
        return none
    # the two fits, window by window, in chunks of about LAYOUT.curve_block window samples
    # (memory: a few arrays of one value per window sample and coordinate)
    step = max(1, LAYOUT.curve_block // (2 * L + 1))
    kept = []  # (samples, windows, gains, knots) of the windows that pass
    for i in range(0, len(cand), step):
        c = cand[i:i + step]
        J, gain, turn, knot = _hinge_gain(ch, c, L, sigma)
        keep = (gain >= FIT.corner_gain) & (turn <= np.cos(np.radians(FIT.corner_turn)))
        kept.append((c[keep], J[keep], gain[keep], knot[keep]))
    ck, Jk, gain, knot = (np.concatenate(x) for x in zip(*kept))
    # the best within a reach (ties: the first sample)
    g = np.full(M, -np.inf)
    g[ck] = gain
    gk = g[Jk]
    pos = np.arange(2 * L + 1)[None, :]
    best = ((gk < gain[:, None]) | ((gk == gain[:, None]) & (Jk >= ck[:, None])) | (pos == L)).all(axis=1)
    corner = np.zeros(M, dtype=bool)
    corner[ck[best]] = True
    return corner, knot[best]


def _hinge_gain(ch: "_Chains", cand: np.ndarray, L: int, sigma: float):
    """The parabola's and the hinge's fits over the windows of the samples ``cand`` (C,) (see
    :func:`_corners`).

    Returns
    -------
    J : (C, 2 L + 1) int ndarray
        Each window's samples.
    gain : (C,) float ndarray
        How much better the hinge fits, in noise variances.
    turn : (C,) float ndarray
        Cosine of the angle between the hinge's two lines.
    knot : (C, d) float ndarray
        Where they meet.
    """
    first, n = ch.first[cand], (ch.last - ch.first + 1)[cand]
    k = np.arange(-L, L + 1)
    J = first[:, None] + (cand[:, None] - first[:, None] + k[None, :]) % n[:, None]
    st = ch.step[J[:, :-1]]  # the step from each window sample to the next
    s = np.concatenate([-np.cumsum(st[:, :L][:, ::-1], axis=1)[:, ::-1], np.zeros((len(cand), 1)),
                        np.cumsum(st[:, L:], axis=1)], axis=1)
    s /= np.maximum(s[:, -1] - s[:, 0], NUMERIC.tiny)[:, None]  # (conditioning: unit length)
    Y = ch.X[J]  # (C, 2L + 1, d)
    one = np.ones_like(s)
    rss, coef = [], []
    for A in (np.stack([one, s, s * s], axis=2), np.stack([one, s, np.maximum(s, 0.0)], axis=2)):
        # (einsum's own loops and Cramer's rule, not BLAS and LAPACK: the same bits under every
        # processor's kernels of OpenBLAS, whose sums round differently)
        cf = _solve3(np.einsum("cki,ckj->cij", A, A), np.einsum("cki,ckd->cid", A, Y))  # (C, 3, d)
        r = Y - np.einsum("cki,cid->ckd", A, cf)
        rss.append((r * r).sum(axis=(1, 2)))
        coef.append(cf)
    a, b = coef[1][:, 1], coef[1][:, 1] + coef[1][:, 2]  # the slopes before and after the knot
    turn = (a * b).sum(axis=1) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), NUMERIC.tiny)
    return J, (rss[0] - rss[1]) / sigma**2, turn, coef[1][:, 0]


def _solve3(M: np.ndarray, B: np.ndarray) -> np.ndarray:
    """The solutions ``X`` (C, 3, d) of the 3 x 3 systems ``M X = B`` (``M`` (C, 3, 3), ``B``
    (C, 3, d)) by Cramer's rule: the cofactors of ``M`` over its determinant."""
    a, b, c = M[:, 0, 0], M[:, 0, 1], M[:, 0, 2]
    d, e, f = M[:, 1, 0], M[:, 1, 1], M[:, 1, 2]
    g, h, i = M[:, 2, 0], M[:, 2, 1], M[:, 2, 2]
    inv = np.empty_like(M)
    inv[:, 0, 0], inv[:, 0, 1], inv[:, 0, 2] = e * i - f * h, c * h - b * i, b * f - c * e
    inv[:, 1, 0], inv[:, 1, 1], inv[:, 1, 2] = f * g - d * i, a * i - c * g, c * d - a * f
    inv[:, 2, 0], inv[:, 2, 1], inv[:, 2, 2] = d * h - e * g, b * g - a * h, a * e - b * d
    det = a * inv[:, 0, 0] + b * inv[:, 1, 0] + c * inv[:, 2, 0]
    with np.errstate(divide="ignore", invalid="ignore"):  # (a singular system: inf or nan, no corner)
        return np.einsum("cij,cjd->cid", inv, B) / det[:, None, None]


def _window_mean(value: np.ndarray, ch: "_Chains", w: int) -> np.ndarray:
    """(M,) mean of a per-sample ``value`` (M,) over the ``w`` samples on either side of each
    sample, within its curve.

    Summed offset by offset (``-w`` to ``w``), not from a running sum over the concatenation:
    each sample's mean then has the same bits whichever curves share its block (a running
    sum carries the rounding of every curve before it; the fit of order 3 turns a difference
    in the last bit of a width into 1e-9 spacings, and a tiled run fits a curve in another
    block than a whole run does)."""
    total, count = value.astype(float, copy=True), np.ones(ch.M)
    for k in range(1, w + 1):  # the samples k after and k before each one, on its curve
        same = ch.first[k:] == ch.first[:-k]
        total[:-k] += np.where(same, value[k:], 0.0)
        total[k:] += np.where(same, value[:-k], 0.0)
        count[:-k] += same
        count[k:] += same
    return total / count


class _Chains:
    """The curves' samples concatenated, with the sparse system of :func:`fit_curves`'s
    energy for a given kernel width per sample."""

    def __init__(self, X: np.ndarray, m: np.ndarray, closed: np.ndarray, corner: np.ndarray | None = None):
        self.X, self.M = X, len(X)
        corner = np.zeros(len(X), dtype=bool) if corner is None else corner
        cid = np.repeat(np.arange(len(m)), m)
        self.idx = idx = np.arange(self.M)
        self.first = first = np.repeat(np.r_[0, np.cumsum(m)[:-1]], m)
        self.last = last = first + m[cid] - 1
        self.loop = loop = closed[cid]
        self.prv = np.where(idx == first, last, idx - 1)  # neighbours along the curve (cyclic on loops)
        self.nxt = np.where(idx == last, first, idx + 1)
        self.prv_open = np.where((idx == first) & ~loop, idx, self.prv)
        self.nxt_open = np.where((idx == last) & ~loop, idx, self.nxt)
        step = np.linalg.norm(X[self.nxt] - X, axis=1)  # from each sample to the next
        real = loop | (idx != last)  # steps of the curve (an open curve has no wrap-around)
        mean = np.bincount(cid, step * real, len(m)) / np.maximum(np.bincount(cid, real, len(m)), 1)
        self.step = np.maximum(step, FIT.step_floor * mean[cid] + NUMERIC.tiny)
        # one penalty row per window of FIT.order + 1 consecutive samples (from FIT.order // 2
        # before a sample): every window of a loop, those of an open curve within it, none with
        # a corner inside it (the two sides are fitted apart)
        k = FIT.order
        start = idx
        for _ in range(k // 2):
            start = self.prv[start]
        win = [start]
        for _ in range(k):
            win.append(self.nxt[win[-1]])
        win = np.array(win)  # (k + 1, M)
        ok = loop | (np.diff(win, axis=0) == 1).all(axis=0)
        ok &= ~corner[win[1:-1]].any(axis=0)
        self.rows = np.flatnonzero(ok)
        self.win = win[:, self.rows]
        # open curves' ends (at their nodes) and corners stay where they are
        self.held = (~loop & ((idx == first) | (idx == last))) | corner
        self.to_held = _to_held(self.held, idx, first, last, loop)
        self.free = np.flatnonzero(~self.held)
        # the open curves' free samples (a banded system: no wrap-around) and the loops'
        self.free_open = np.flatnonzero(~self.held & ~loop)
        self.free_loop = np.flatnonzero(loop & ~self.held)
        self._system = None

    def _structure(self):
        """The system's layout, built once (it does not depend on the widths): each window's
        unit stencil (``k!`` times its divided-difference weights times its mean step to the
        ``k``); every entry of ``R^T R`` a slot ``(sample, offset along its curve)`` of a band
        ``2 k + 1`` wide (cyclic on a loop), with the products of two stencil weights that
        :meth:`solve` sums into their slots by one ``bincount`` in a fixed order (the same bits
        whichever curves share the block) before adding the identity on the diagonal slots; per
        part (open curves, loops) the slots of its free block's lower triangle in CSR order and
        those that couple it to the held samples."""
        if self._system is not None:
            return self._system
        win, k, M, idx = self.win, FIT.order, self.M, self.idx
        width = 2 * k + 1
        steps = self.step[win[:-1]]  # (k, rows): the window's steps
        t = np.vstack([np.zeros(win.shape[1]), np.cumsum(steps, axis=0)])
        unit = np.full((k + 1, win.shape[1]), float(math.factorial(k)) * steps.mean(axis=0) ** k)
        for i in range(k + 1):
            for j in range(k + 1):
                if i != j:
                    unit[i] /= t[i] - t[j]
        length = self.last - self.first + 1

        def canonical(o, n):  # an offset along a loop of n samples, within half of it
            o = np.mod(o, n)
            return np.where(2 * o > n, o - n, o)

        a, b = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        a, b = a.ravel(), b.ravel()
        at = win[a]  # (pairs, rows): the sample of each entry's row
        off = np.broadcast_to((b - a)[:, None], at.shape)
        short = self.loop & (length <= 2 * k)  # a loop whose band wraps onto itself
        if short.any():
            off = np.where(short[at], canonical(off, length[at]), off)
        slots = (at * width + off + k).ravel()
        prod = unit[a] * unit[b]  # (pairs, rows)
        # the sample at each (sample, offset): -1 off an open curve's ends or (on a short loop)
        # where another offset names the same sample
        nb = np.full((M, width), -1, dtype=np.int64)
        nb[:, k] = idx
        fwd, back = idx, idx
        for o in range(1, k + 1):
            fwd, back = self.nxt[fwd], self.prv[back]
            ahead = self.loop | (idx + o <= self.last)
            behind = self.loop | (idx - o >= self.first)
            if short.any():
                ahead &= ~short | (canonical(o, length) == o)
                behind &= ~short | (canonical(-o, length) == -o)
            nb[:, k + o] = np.where(ahead, fwd, -1)
            nb[:, k - o] = np.where(behind, back, -1)
        parts = []
        for part in (self.free_open, self.free_loop):
            if not len(part):
                continue
            pos = np.full(M, -1, dtype=np.int64)
            pos[part] = np.arange(len(part))
            cols = nb[part]  # (n, width)
            free = (cols >= 0) & (pos[np.maximum(cols, 0)] >= 0)
            lower = free & (cols <= part[:, None])
            order = np.argsort(np.where(lower, cols, M), axis=1, kind="stable")  # columns ascending
            r = np.arange(len(part))[:, None]
            keep = lower[r, order]
            low_slots = (part[:, None] * width + order)[keep]
            indptr = np.r_[0, np.cumsum(keep.sum(axis=1))].astype(np.int64)
            indices = pos[cols[r, order][keep]].astype(np.int64)
            held = (cols >= 0) & self.held[np.maximum(cols, 0)]
            hr, ho = np.nonzero(held)
            parts.append((part, low_slots, indptr, indices, part[hr] * width + ho, hr, cols[hr, ho]))
        self._system = (slots, prod, idx * width + k, M * width, parts)
        return self._system

    def solve(self, band: np.ndarray) -> np.ndarray:
        """(M, d) fitted samples for the kernel width ``band`` (M,) of each sample (spacings);
        the held ends stay where they are.

        Each part's free block is solved by the envelope Cholesky kernel
        (:func:`~.kernels.linalg._envelope_solve`): banded for the open curves, banded but for
        their wrap-around for the loops (whose fill stays in their last rows). Its fixed order
        of operations gives the same bits on every machine (LAPACK's banded Cholesky and
        SuperLU, used before, did not: their BLAS kernels depend on the processor)."""
        X = self.X
        Y = X.copy()
        if not len(self.free):
            return Y
        # the penalty row of window j weighs (band_j s_j)^k k! times the k-th divided difference
        # (k = FIT.order, s_j its mean step: about (band_j s_j)^k times the k-th derivative):
        # unitless weights, any scale; its entries of R^T R scale as band_j^(2 k)
        slots, prod, diagonal, size, parts = self._structure()
        vals = np.bincount(slots, weights=(prod * band[self.rows] ** (2 * FIT.order)).ravel(),
                           minlength=size).astype(np.float64, copy=False)  # (no window: an empty int count)
        vals[diagonal] += 1.0  # the identity (the data term)
        for part, low, indptr, cols, held, hrow, hcol in parts:
            rhs = X[part].copy()
            for c in range(X.shape[1]):
                rhs[:, c] -= np.bincount(hrow, weights=vals[held] * X[hcol, c], minlength=len(part))
            Y[part] = _k.envelope_solve(indptr, cols, np.ascontiguousarray(vals[low]), np.ascontiguousarray(rhs))
        return Y


def drop_spikes(curves, P: np.ndarray, h: np.ndarray, noise: float):
    """The curves without their spikes: interior samples far off the chord of their neighbours.

    A sample whose distance to the segment between the samples before and after it exceeds
    ``CURVES.spike`` times its spacing plus the noise scale is an outlier the chain took in
    (a corner of 30 degrees sits under one spacing from that chord). Computed nodes (index
    -1) and the two ends stay; a curve keeps at least its two ends.

    Parameters
    ----------
    curves : list of Curve
        ``indices`` are internal point ids (-1 at computed nodes).
    P : (N, d) ndarray
    h : (N,) ndarray
        Local spacing.
    noise : float
        Noise scale (absolute units; 0 on clean input).

    Returns
    -------
    list of Curve
        The same list, curves with spikes replaced by copies without them.
    """
    out = list(curves)
    lens = np.fromiter((len(c.points) for c in curves), dtype=np.int64, count=len(curves))
    # all curves at once, in blocks of about LAYOUT.curve_block samples (the same arithmetic,
    # sample by sample, as curve by curve)
    i = 0
    while i < len(curves):
        j = i + max(1, int(np.searchsorted(np.cumsum(lens[i:]), LAYOUT.curve_block, side="right")))
        for ci, keep in _spike_free(curves[i:j], lens[i:j], h, noise):
            c = curves[i + ci]
            out[i + ci] = Curve(c.points[keep], c.start, c.end, c.closed, c.indices[keep])
        i = j
    return out


def _spike_free(curves, lens, h, noise):
    """``(curve, keep)`` for each of ``curves`` (``lens`` samples each) with a spike: the mask
    of its samples kept (see :func:`drop_spikes`)."""
    off = np.r_[0, np.cumsum(lens)]
    if off[-1] <= 2:  # no sample between a first and a last one
        return []
    X = np.concatenate([c.points for c in curves])
    ids = np.concatenate([c.indices for c in curves])
    # x: every sample but the first and last of the block, against the chord of its neighbours
    dist = segment_distance(X[1:-1], X[:-2], X[2:])
    mid = ids[1:-1]
    hh = np.where(mid >= 0, h[np.maximum(mid, 0)], np.inf)
    spike = (mid >= 0) & (dist > CURVES.spike * (hh + noise))
    # the first and last sample of every curve are not tested (x runs from sample 1)
    ends = np.r_[off[:-1], off[1:] - 1] - 1
    spike[ends[(ends >= 0) & (ends < len(spike))]] = False
    full = np.r_[False, spike, False]  # (by sample)
    cs = np.r_[0, np.cumsum(full)]
    hit = np.flatnonzero(cs[off[1:]] > cs[off[:-1]])
    return [(ci, ~full[off[ci]:off[ci + 1]]) for ci in hit.tolist()]
