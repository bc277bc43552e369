"""Two junctions seen as one: a region whose branches meet at two points a few spacings apart.

Two junctions joined by a segment a few spacings long (a building's notch, a facade's rung, a
short street link, a twig near a fork) lie inside one another's shell; under noise the shell
is widened and their flagged points form one region, found as one junction of valence 4 or
more. The branches tell them apart: the lines fitted on their ends do not meet at one point,
but split into two groups whose lines meet at two points, with region points along the
segment between them. :func:`split_paired_junctions` finds such regions after the repairs
and replaces each by two junctions joined by a new chain (:meth:`.topology.Topology.split_region`).

The test is the converse of :func:`.repairs.merge_close_junctions` (branches aiming at one
node make one junction): a line "meets" a point when the point lies within the strip of the
line, ``max(width * h, LINKS.strip_noise * noise)``, or within ``REPAIRS.merge_tan`` times its
distance from the branch end, and ahead of the branch.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from .chains import end_portion, fit_line
from .params import RobustParams, Scales
from .thresholds import LINKS, NODES, PAIRED, REPAIRS
from .topology import Topology

__all__ = ["split_paired_junctions", "Lines", "branch_lines", "meeting_point", "best_pair"]


class Lines(NamedTuple):
    """The fitted lines of a junction's branches.

    Attributes
    ----------
    c : (m, d) ndarray
        A point of each line (the centroid of the branch's end portion).
    u : (m, d) ndarray
        Unit directions.
    tip : (m, d) ndarray
        The branch's last point (nearest the junction).
    lim : (m,) ndarray
        Strip half-width of each line (absolute units).
    """

    c: np.ndarray
    u: np.ndarray
    tip: np.ndarray
    lim: np.ndarray


def branch_lines(topo: Topology, sc: Scales, inc: list[tuple[int, int]]) -> Lines | None:
    """The lines of the branches ``inc`` (chain, side) at a region, fitted as the node placement
    fits them (``NODES.fit_span`` spacings, longer under noise); None when a branch has a single
    point (no direction)."""
    P, h, noise = topo.P, sc.h, float(sc.noise)
    cs, us, tips, lims = [], [], [], []
    for i, s in inc:
        ids = np.asarray(topo.end_ids(i, s))
        hl = float(h[ids[-1]])
        E = end_portion(P, h, ids, span=NODES.fit_span + NODES.fit_noise * noise / hl)
        cc, u = fit_line(E)
        if u is None:
            return None
        cs.append(cc)
        us.append(u)
        tips.append(E[0])
        lims.append(max(sc.width * hl, LINKS.strip_noise * noise))
    return Lines(np.array(cs), np.array(us), np.array(tips), np.array(lims))


def meeting_point(c: np.ndarray, u: np.ndarray, anchor: np.ndarray) -> np.ndarray:
    """Least-squares meeting point of lines, held near ``anchor`` where they do not fix it.

    Parameters
    ----------
    c, u : (m, d) ndarray
        A point and a unit direction of each line.
    anchor : (d,) ndarray
        Where a direction the lines leave free (parallel lines) is held (weight
        ``PAIRED.hold`` per line).

    Returns
    -------
    (d,) ndarray
        The point minimising the summed squared distances to the lines plus the hold.
    """
    d = c.shape[1]
    A = np.zeros((d, d))
    b = np.zeros(d)
    for ci, ui in zip(c, u):
        M = np.eye(d) - np.outer(ui, ui)
        A += M
        b += M @ ci
    w = PAIRED.hold * len(c)
    A += w * np.eye(d)
    b += w * anchor
    return np.linalg.solve(A, b)


def _meets(L: Lines, sel: np.ndarray, x: np.ndarray) -> bool:
    """True when every line ``sel`` of ``L`` meets point ``x`` (see the module's note)."""
    for k in sel.tolist():
        r = x - L.c[k]
        along = float(r @ L.u[k])
        d = float(np.sqrt(max(float(r @ r) - along * along, 0.0)))
        lim = max(L.lim[k], REPAIRS.merge_tan * float(np.linalg.norm(x - L.tip[k])))
        if d > lim or float((L.tip[k] - L.c[k]) @ L.u[k]) * along < 0:
            return False
    return True


def best_pair(L: Lines, anchor: np.ndarray, h: float):
    """The split of the lines ``L`` into two groups meeting at two points, if one reads so.

    None when all lines meet one point (:func:`meeting_point` of all), or when no split into two
    groups of two or more lines has every group's lines meet its point with the points over
    ``PAIRED.sep * h`` apart, every branch's end nearer its own group's point and the summed
    squared distances of the lines to their points at most ``PAIRED.gain`` times those to the
    one point (curved branches of one junction miss it, but miss two points almost as much).
    Each group's point is found with the segment between the two
    points counted as one more line of both (``PAIRED.rounds`` rounds): a junction whose other
    two branches are collinear (a T) is fixed along them by the segment.

    Parameters
    ----------
    L : Lines
        m >= 4 lines.
    anchor : (d,) ndarray
        The region's centroid (holds what the lines leave free).
    h : float
        The region's spacing.

    Returns
    -------
    (mask, xa, xb) or None
        ``mask`` (m,) bool, True for the lines of the second group; the two points.
    """
    m = len(L.c)
    every = np.arange(m)
    x1 = meeting_point(L.c, L.u, anchor)
    if _meets(L, every, x1):
        return None
    cost1 = _cost(L, every, x1)
    best, best_cost = None, np.inf
    for k in range(PAIRED.min_group, m // 2 + 1):
        for grp in itertools.combinations(range(m), k):
            if 2 * k == m and 0 not in grp:  # each even split once
                continue
            mask = np.zeros(m, dtype=bool)
            mask[list(grp)] = True
            a, b = every[~mask], every[mask]
            xa = meeting_point(L.c[a], L.u[a], anchor)
            xb = meeting_point(L.c[b], L.u[b], anchor)
            for _ in range(PAIRED.rounds):
                e = xb - xa
                ne = float(np.linalg.norm(e))
                if ne == 0:
                    break
                e = e / ne
                xa = meeting_point(np.r_[L.c[a], xb[None]], np.r_[L.u[a], e[None]], anchor)
                xb = meeting_point(np.r_[L.c[b], xa[None]], np.r_[L.u[b], e[None]], anchor)
            if not float(np.linalg.norm(xb - xa)) > PAIRED.sep * h:
                continue
            if not (_meets(L, a, xa) and _meets(L, b, xb)):
                continue
            # every branch ends nearer its own junction than the other one
            da = np.linalg.norm(L.tip - xa, axis=1)
            db = np.linalg.norm(L.tip - xb, axis=1)
            if not (np.all(da[a] < db[a]) and np.all(db[b] < da[b])):
                continue
            cost = _cost(L, a, xa) + _cost(L, b, xb)
            if cost < best_cost and cost <= PAIRED.gain * cost1:
                best, best_cost = (mask, xa, xb), cost
    return best


def _cost(L: Lines, sel: np.ndarray, x: np.ndarray) -> float:
    """Summed squared distances of point ``x`` to the lines ``sel``."""
    r = x - L.c[sel]
    along = np.einsum("ij,ij->i", r, L.u[sel])
    return float(np.sum(np.einsum("ij,ij->i", r, r) - along * along))


def _segment(P: np.ndarray, rid: np.ndarray, xa: np.ndarray, xb: np.ndarray, lim: float, gap: float):
    """The region points along the segment ``xa``-``xb``, ordered from ``xa``: those strictly
    between the two points (projection) within ``lim`` of the line; None when there are none or
    when two consecutive ones (or the ends and their nearest) lie over ``gap`` apart."""
    e = xb - xa
    L = float(np.linalg.norm(e))
    e = e / L
    R = P[rid] - xa
    t = R @ e
    d = np.sqrt(np.maximum(np.einsum("ij,ij->i", R, R) - t * t, 0.0))
    on = (t > 0) & (t < L) & (d <= lim)
    if not on.any():
        return None, t
    ids = rid[on][np.lexsort((rid[on], t[on]))]
    ts = np.r_[0.0, np.sort(t[on]), L]
    if np.diff(ts).max() > gap:
        return None, t
    return ids, t


def split_paired_junctions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Every region of valence ``PAIRED.min_valence`` or more whose branches meet at two points
    (:func:`best_pair`), joined by region points along the segment between them, becomes two
    junctions joined by a chain of those points.

    The region's other points go to the nearer junction (by their projection on the segment).
    A region with a chain that has both ends there (a loop) is left as it is. Noise-free input is
    left as it is: there the shell is not widened and the close junctions it merges are
    separated, or kept as one, by :func:`.junctions.separate_close_junctions` (on real
    sketches, strokes meeting a few spacings apart make one junction of the ground truth).
    """
    if sc.clean:
        return
    P, h = topo.P, sc.h
    for r in np.flatnonzero(topo.v >= PAIRED.min_valence).tolist():
        inc = topo.incident(r)
        rid = topo.regions[r]
        if len(rid) == 0 or len({i for i, _ in inc}) < len(inc):
            continue
        L = branch_lines(topo, sc, inc)
        if L is None:
            continue
        hr = float(np.median(h[rid]))
        pair = best_pair(L, P[rid].mean(axis=0), hr)
        if pair is None:
            continue
        mask, xa, xb = pair
        seg, t = _segment(P, rid, xa, xb, float(np.max(L.lim)), prm.link * hr)
        if seg is None:
            continue
        rest = ~np.isin(rid, seg)
        near_b = t > 0.5 * float(np.linalg.norm(xb - xa))
        topo.split_region(r, [e for e, m in zip(inc, mask.tolist()) if m], rid[rest & ~near_b],
                          rid[rest & near_b], seg)
