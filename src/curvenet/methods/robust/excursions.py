"""Stage 8d: a curve that runs out along a twig and back, read as a junction and a twig.

Where a short branch (a twig of 3-6 spacings) leaves a curve and the shell test misses its
junction (the twig's tip lies inside the shell of the curve it leaves), the chain tracer can
take the twig's samples into the curve: the curve runs along the twig to its tip, turns back
sharply and jumps back to the curve it left, which then goes on as before. The finished curve
shows it as an excursion: samples ``a`` and ``b`` of the curve lie a regular sample step apart
(at most ``EXCURSION.gap`` local spacings plus ``EXCURSION.gap_noise`` times the noise), and
the samples between them leave that step, reach a tip and come back. This stage reads that
pattern from the finished curves (before the fit) and splits each such curve into the two
curves the excursion interrupted and a twig from a new junction to a new free end, when:

* the curve turns back at a sample ``t`` between them (a turn whose cosine is under
  ``EXCURSION.turn_cos``: the twig's tip), which lies ``EXCURSION.height`` spacings or more
  off the step, and ``a`` and ``b`` lie within ``EXCURSION.reach`` spacings of arc of it;
* one side of the tip is the way back: at most ``EXCURSION.back_samples`` samples, among whose
  steps is a jump (over ``BRANCHED.jump`` local spacings plus ``BRANCHED.jump_noise`` times the
  noise: the jump by which :mod:`.branched` finds a chain that branches); a curve's own narrow
  hairpin or zigzag, sampled all along, has none;
* the curve runs on straight across the step: its direction into ``a`` and out of ``b`` (over
  ``EXCURSION.dir_samples`` samples) agree within ``EXCURSION.through_cos``;
* the excursion's samples lie along one line (within ``EXCURSION.line`` spacings plus
  ``EXCURSION.line_noise`` times the noise of their principal line), the twig is at least
  ``min_spur`` spacings long, and its tip is a free end: no sample of a curve but the twig's
  lies a step (``gap``) from it ahead, within ``EXCURSION.ahead_cos`` of the twig's direction
  (else the excursion ran part of the way along a curve between two junctions).

The junction is placed on the curve's line through the step (the principal line of its samples
``dir_samples`` before ``a`` to ``a`` and ``b`` to ``dir_samples`` after ``b``), at its point
nearest the twig's line; a sample of the step that lies off that line (the curve left it a
sample late or came back a sample early) goes to the twig. The twig runs from the junction
through the excursion's samples in order of their distance from it, and its tip (the farthest)
is the new free end. Of several excursions of one curve the tightest (fewest samples, then
shortest step) is split first, and the pieces are read again. A test of all curves at once
(:func:`_candidates`, necessary for the rule) picks the curves read one by one.
"""

from __future__ import annotations

import numpy as np

from ...neighbors import build_tree
from ...network import Curve
from .chains import group_medians, segment_distance
from .curves import renumbered
from .thresholds import BRANCHED, EXCURSION

__all__ = ["split_excursions"]


def split_excursions(P: np.ndarray, h: np.ndarray, nodes: np.ndarray, curves: list[Curve], noise: float,
                     min_spur: float) -> tuple[np.ndarray, list[Curve], int]:
    """The network with every excursion along a twig split off as that twig (see the module
    docstring for the rule).

    Parameters
    ----------
    P : (N, d) ndarray
        The points, in the internal order the curves' ``indices`` refer to.
    h : (N,) ndarray
        Local spacing of each point.
    nodes : (n, d) ndarray
        Node positions, sorted by coordinates.
    curves : list of Curve
        The network's curves, not fitted (``indices``: internal point ids, -1 at computed nodes).
    noise : float
        The noise scale.
    min_spur : float
        The shortest twig, in spacings (the method's ``min_spur``).

    Returns
    -------
    nodes : (n', d) ndarray
        Node positions, sorted by coordinates: the input's and two new ones per twig.
    curves : list of Curve
        New list, sorted as :func:`.curves.sort_curves` sorts it. When ``split`` is 0, ``nodes``
        and ``curves`` are the inputs.
    split : int
        The number of twigs split off.
    """
    if not curves or len(nodes) == 0:
        return nodes, curves, 0
    maybe = _candidates(curves, h, noise)
    if not maybe.any():
        return nodes, curves, 0
    node_list = list(nodes)
    out: list[Curve] = [c for c, m in zip(curves, maybe) if not m]
    work = [c for c, m in zip(curves, maybe) if m]
    split = 0
    ptree = used = None
    while work:
        c = work.pop()
        cut = _excursion(c, h, noise, min_spur)
        if cut is not None:  # the twig's tip is a free end: no sample a step ahead of it
            if ptree is None:  # (the samples of the curves do not change below: a split keeps them)
                ptree = build_tree(P)
                used = np.zeros(len(P), dtype=bool)
                ids = np.concatenate([q.indices for q in curves])
                used[ids[ids >= 0]] = True
            _, _, x, twig = cut
            tip = int(c.indices[twig[-1]])
            if _continued(P, ptree, tip, _unit(P[tip] - x), _step(float(h[tip]), noise), c.indices[twig], used):
                cut = None
        if cut is None:
            out.append(c)
            continue
        a, b, x, twig = cut
        node_list.append(x)
        j = len(node_list) - 1
        node_list.append(c.points[twig[-1]].copy())
        k = len(node_list) - 1
        Q, idx = c.points, c.indices
        work.append(Curve(np.r_[Q[:a + 1], x[None]], c.start, j, False, np.r_[idx[:a + 1], -1]))
        work.append(Curve(np.r_[x[None], Q[b:]], j, c.end, False, np.r_[-1, idx[b:]]))
        out.append(Curve(np.r_[x[None], Q[twig]], j, k, False, np.r_[-1, idx[twig]]))
        split += 1
    if not split:
        return nodes, curves, 0
    X, final = renumbered(np.asarray(node_list, dtype=float), out)
    return X, final, split


def _continued(P: np.ndarray, ptree, tip: int, u: np.ndarray, r: float, own: np.ndarray,
               used: np.ndarray) -> bool:
    """Whether a sample of a curve (``used``: per point), not of the twig (``own``: its point
    ids), lies within ``r`` of the twig's tip ``tip`` ahead of it, within ``EXCURSION.ahead_cos``
    of the twig's direction ``u`` (unit): a curve goes on past the "tip" (the excursion ran part
    of the way along a curve between two junctions), which is then no free end. (Samples of no
    curve there are the twig's own, left out by the tracer.)"""
    near = np.asarray(ptree.query_ball_point(P[tip], r), dtype=np.int64)
    near = near[used[near] & ~np.isin(near, own)]
    if not len(near):
        return False
    v = _unit(P[near] - P[tip])
    return bool(np.any(v @ u >= EXCURSION.ahead_cos))


def _candidates(curves: list[Curve], h: np.ndarray, noise: float) -> np.ndarray:
    """Per curve: whether it may hold an excursion (a necessary test of :func:`_excursion`, all
    curves at once): a curve between nodes with a turn back, a jump within ``2 EXCURSION.reach``
    spacings of arc of it, and two samples around it, one of them at most
    ``EXCURSION.back_samples`` samples from it, within a step's ``gap`` of each other."""
    m = len(curves)
    out = np.zeros(m, dtype=bool)
    k = EXCURSION.dir_samples
    use = np.array([i for i, c in enumerate(curves) if c.start is not None and len(c.points) >= EXCURSION.min_samples
                    and c.indices.max() >= 0], dtype=np.int64)
    if not len(use):
        return out
    n = np.array([len(curves[i].points) for i in use], dtype=np.int64)
    first = np.r_[0, np.cumsum(n)[:-1]]
    Q = np.concatenate([curves[i].points for i in use])
    idx = np.concatenate([curves[i].indices for i in use])
    cid = np.repeat(np.arange(len(use)), n)
    hs = _flat_spacing(idx, cid, h)
    D = np.diff(Q, axis=0)
    L = np.linalg.norm(D, axis=1)
    inner = cid[1:] == cid[:-1]  # steps within one curve
    L = np.where(inner, L, 0.0)
    tip = np.zeros(len(Q), dtype=bool)
    tip[1:-1] = _turns_back(_unit(D), L) & inner[:-1] & inner[1:]
    jump = np.zeros(len(Q), dtype=bool)
    jump[:-1] = inner & _jumps(L, hs, noise)
    # (the arc runs on over the curve boundaries: only differences within one curve are read)
    arc = np.r_[0.0, np.cumsum(L)]
    if not tip.any() or not jump.any():
        return out
    # per tip: a jump on its short side (the way back), before or after it
    cj = np.r_[0, np.cumsum(jump)]  # jumps among steps 0 .. s - 1: cj[s]
    tp = np.flatnonzero(tip)
    w = EXCURSION.back_samples
    before = cj[tp] - cj[np.maximum(tp - w, 0)] > 0  # steps t - w .. t - 1 (jump[s]: step s to s + 1)
    after = cj[np.minimum(tp + w, len(Q) - 1)] - cj[tp] > 0  # steps t .. t + w - 1
    keep = before | after
    tp, before, after = tp[keep], before[keep], after[keep]
    if not len(tp):
        return out
    # the spacing of the curves of those tips (the median over their samples, as _excursion's)
    hl = np.zeros(len(use))
    cs = np.unique(cid[tp])
    own = [curves[i].indices[curves[i].indices >= 0] for i in use[cs].tolist()]
    hl[cs] = group_medians(h[np.concatenate(own)], np.array([len(o) for o in own], dtype=np.int64))
    # per remaining tip: the pairs (t - i, t + j) and (t - j, t + i), j on the short side (its
    # sample at least height spacings from the tip: the tip lies that far off the step), i on
    # the long side, within the curve (room for the directions) and the reach, a step's gap
    # apart, the tip height spacings off the step
    hl_t = hl[cid[tp]]
    H = EXCURSION.height * hl_t
    combos = []  # (tip, short-side sample, direction of the long side: -1 before, +1 after)
    for jj in range(1, w + 1):
        for side, sgn in ((after, 1), (before, -1)):
            b = tp + sgn * jj
            okb = side & (b >= first[cid[tp]]) & (b < first[cid[tp]] + n[cid[tp]])
            bc = np.clip(b, 0, len(Q) - 1)
            okb &= np.linalg.norm(Q[bc] - Q[tp], axis=1) >= H
            sel = np.flatnonzero(okb)
            combos.append((sel, bc[sel], np.full(len(sel), -sgn)))
    ti = np.concatenate([c[0] for c in combos])
    sb = np.concatenate([c[1] for c in combos])
    dl = np.concatenate([c[2] for c in combos])
    lo = first[cid[tp[ti]]] + k
    hi = first[cid[tp[ti]]] + n[cid[tp[ti]]] - 1 - k
    hit = np.zeros(len(tp), dtype=bool)
    for i in range(1, EXCURSION.long_samples + 1):
        if not len(ti):
            break
        t = tp[ti]
        a = t + dl * i
        inside = (a >= first[cid[t]]) & (a < first[cid[t]] + n[cid[t]])
        ac = np.clip(a, 0, len(Q) - 1)
        inside &= np.abs(arc[ac] - arc[t]) <= EXCURSION.reach * hl_t[ti]
        ti, sb, dl, lo, hi, t, ac = ti[inside], sb[inside], dl[inside], lo[inside], hi[inside], t[inside], ac[inside]
        room = (np.minimum(ac, sb) >= lo) & (np.maximum(ac, sb) <= hi)
        G = np.linalg.norm(Q[ac] - Q[sb], axis=1)
        ok = room & (G <= _step(np.maximum(hs[ac], hs[sb]), noise))
        ok &= segment_distance(Q[t], Q[ac], Q[sb]) >= H[ti]
        hit[ti[ok]] = True
    out[use[np.unique(cid[tp[hit]])]] = True
    return out


def _flat_spacing(idx: np.ndarray, cid: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The local spacing at each sample of curves laid end to end, or of one curve (``cid`` all
    0) (``idx``: point ids, -1 at computed nodes, which take the spacing of the nearest sample
    of their curve before them, else after; ``cid``: each sample's curve, ascending; every
    curve holds a sample)."""
    has = idx >= 0
    ar = np.arange(len(idx))
    prev = np.maximum.accumulate(np.where(has, ar, -1))
    nxt = np.minimum.accumulate(np.where(has, ar, len(idx))[::-1])[::-1]
    okp = (prev >= 0) & (cid[np.maximum(prev, 0)] == cid)
    src = np.where(okp, prev, nxt)
    return h[idx[src]]


def _turns_back(U: np.ndarray, L: np.ndarray) -> np.ndarray:
    """Per inner sample of a polyline (its unit steps ``U`` (m, d) and their lengths ``L``
    (m,)): whether the curve turns back there (a turn whose cosine is under
    ``EXCURSION.turn_cos``, between two steps of non-zero length)."""
    return (np.einsum("ij,ij->i", U[:-1], U[1:]) < EXCURSION.turn_cos) & (L[:-1] > 0) & (L[1:] > 0)


def _jumps(L: np.ndarray, hs: np.ndarray, noise: float) -> np.ndarray:
    """Per step (lengths ``L`` (m,), spacings at its samples ``hs`` (m + 1,)): whether it is a
    jump, over ``BRANCHED.jump`` local spacings plus ``BRANCHED.jump_noise`` times the noise."""
    return L >= BRANCHED.jump * np.maximum(hs[:-1], hs[1:]) + BRANCHED.jump_noise * noise


def _step(hs, noise: float):
    """The longest regular step at local spacing ``hs``: ``EXCURSION.gap`` spacings plus
    ``EXCURSION.gap_noise`` times the noise."""
    return EXCURSION.gap * hs + EXCURSION.gap_noise * noise


def _unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (..., d) scaled to unit length (zero rows left zero)."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def _excursion(c: Curve, h: np.ndarray, noise: float, min_spur: float):
    """The tightest excursion of curve ``c`` that is a twig: ``(a, b, x, twig)`` (the samples
    of the step, the junction's position (d,), the twig's samples from the junction out to its
    tip), or None."""
    Q = c.points
    n = len(Q)
    k = EXCURSION.dir_samples
    if n < EXCURSION.min_samples:
        return None
    own = c.indices[c.indices >= 0]
    if not len(own):
        return None
    hl = float(np.median(h[own]))
    D = np.diff(Q, axis=0)
    L = np.linalg.norm(D, axis=1)
    tips = np.flatnonzero(_turns_back(_unit(D), L)) + 1
    if not len(tips):
        return None
    arc = np.r_[0.0, np.cumsum(L)]
    hs = _flat_spacing(c.indices, np.zeros(n, dtype=np.int64), h)
    big = _jumps(L, hs, noise)
    uin = np.zeros_like(Q)
    uin[k:] = _unit(Q[k:] - Q[:-k])  # direction into each sample
    uout = np.zeros_like(Q)
    uout[:-k] = _unit(Q[k:] - Q[:-k])  # direction out of each sample
    cands = []
    for t in tips.tolist():
        lo = max(int(np.searchsorted(arc, arc[t] - EXCURSION.reach * hl)), k)
        hi = min(int(np.searchsorted(arc, arc[t] + EXCURSION.reach * hl, side="right")), n - k)
        A = np.arange(lo, t)
        B = np.arange(t + 1, hi)
        if not len(A) or not len(B):
            continue
        G = np.linalg.norm(Q[A][:, None] - Q[B][None], axis=2)
        ok = G <= _step(np.maximum(hs[A][:, None], hs[B][None, :]), noise)
        ok &= uin[A] @ uout[B].T >= EXCURSION.through_cos
        # one side of the tip is the way back: at most back_samples samples, a jump among them
        back = np.logical_or.accumulate(big[A[::-1]])[::-1]  # any of big[a .. t - 1]
        fwd = np.logical_or.accumulate(big[t:B[-1]])  # any of big[t .. b - 1]
        w = EXCURSION.back_samples
        ok &= ((t - A <= w) & back)[:, None] | ((B - t <= w) & fwd)[None, :]
        # the tip reaches height spacings off the step
        ok &= segment_distance(Q[t], Q[A][:, None, :], Q[B][None, :, :]) >= EXCURSION.height * hl
        for ia, ib in zip(*np.nonzero(ok)):
            a, b = int(A[ia]), int(B[ib])
            cands.append((b - a, float(G[ia, ib]), a, b))
    for _, _, a, b in sorted(cands):
        cut = _twig(Q, a, b, hl, noise, min_spur)
        if cut is not None:
            return cut
    return None


def _twig(Q: np.ndarray, a: int, b: int, hl: float, noise: float, min_spur: float):
    """The twig of the excursion between samples ``a`` and ``b`` of the polyline ``Q``:
    ``(a, b, x, twig)`` as :func:`_excursion` returns it, or None when the excursion is no twig
    (bent, or short)."""
    E = np.arange(a + 1, b)
    k = EXCURSION.dir_samples
    ct = Q[E].mean(axis=0)
    if len(E) >= 2:
        ut = np.linalg.svd(Q[E] - ct, full_matrices=False)[2][0]
    else:
        ut = _unit(Q[E[0]] - Q[a])
    off = np.linalg.norm((Q[E] - ct) - np.outer((Q[E] - ct) @ ut, ut), axis=1)
    if off.max() > EXCURSION.line * hl + EXCURSION.line_noise * noise:
        return None
    # the junction: the point of the curve's line through the step (the principal line of its
    # samples a - k .. a and b .. b + k) nearest the twig's line
    M = np.r_[Q[a - k:a + 1], Q[b:b + k + 1]]
    cm = M.mean(axis=0)
    um = np.linalg.svd(M - cm, full_matrices=False)[2][0]
    um = um if float(um @ (Q[b + k] - Q[a - k])) >= 0 else -um
    w0 = cm - ct
    cb = float(um @ ut)
    den = 1.0 - cb * cb
    s = (cb * float(ut @ w0) - float(um @ w0)) / den if den > EXCURSION.parallel else float((Q[E[0]] - cm) @ um)
    # (kept within the step's reach: from a's foot on the line to b's, widened by a step)
    fa, fb = float((Q[a] - cm) @ um), float((Q[b] - cm) @ um)
    gap = _step(hl, noise)  # (the clamp's margin)
    x = cm + min(max(s, min(fa, fb) - gap), max(fa, fb) + gap) * um
    # a step's sample that lies off the curve's line (the twig's first sample, where the curve
    # left the line a sample late or came back a sample early) belongs to the twig
    tol = EXCURSION.line * hl + EXCURSION.line_noise * noise
    dline = lambda i: float(np.linalg.norm((Q[i] - cm) - ((Q[i] - cm) @ um) * um))
    while a > k and dline(a) > tol:
        a -= 1
    while b < len(Q) - 1 - k and dline(b) > tol:
        b += 1
    E = np.arange(a + 1, b)
    o = E[np.argsort(np.linalg.norm(Q[E] - x, axis=1), kind="stable")]
    length = float(np.linalg.norm(np.diff(np.r_[x[None], Q[o]], axis=0), axis=1).sum())
    if length < min_spur * hl:
        return None
    return a, b, x, o
