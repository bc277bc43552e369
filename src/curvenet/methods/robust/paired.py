"""Two junctions seen as one: a region whose branches meet at two points a few spacings apart.

Two junctions joined by a segment a few spacings long (a building's notch, a facade's rung, a
short street link, a twig near a fork) lie inside one another's shell; under noise the shell
is widened and their flagged points form one region, found as one junction of valence 4 or
more. The branches tell them apart: the lines fitted on their ends do not meet at one point,
but split into two groups whose lines meet at two points, with region points along the
segment between them. :func:`split_paired_junctions` finds such regions after the repairs that
mend chains and replaces each by two junctions joined by a new chain
(:meth:`.topology.Topology.split_region`); :func:`.repairs.merge_close_junctions` runs after it
and merges back a pair whose branches aim at one node (two strokes drawn into a hub that part).
One reading is left as one junction: a straight curve passing through both points with two
branches crossing it at different angles, a few spacings apart, is strokes meeting loosely
where one junction was meant (real sketches); branches crossing it in parallel (a ladder's
rungs, a comb's teeth) are two junctions; a branch whose whole chain is shorter than the end
portion its line is fitted on (:func:`short_branches`: a street grid's 4 h link into the next
crossing, its line bent by the turn there) tells no crossing angle and counts as parallel
(7 December 2026). And a straight curve with a half in each group
(:func:`straight_pairs`) must run along the segment (its direction, from one half's centroid
to the other's, within ``PAIRED.parallel_cos``): it passes through both points (under heavy
noise an X crossing otherwise splits into two V's). The direction is read over the span between
the two halves' end portions, 10-16 h on a street, not as the mean of the halves' own
directions, which the noise tilts by several degrees each (7 December 2026: a street grid's
junctions 4.6 h apart under noise 0.2 h were refused, the segment 19 degrees off that mean and
13 degrees off the centroid line). Every branch must end nearer its own point than the other;
a rail's half (a line along the segment whose one parallel line is in the other group) that
ran on past its junction towards the next under noise is judged by its end portion's centroid
instead of its tip (7 December 2026, late: the ladder kind at noise 0.2 h, its rails' chains
running up to two thirds of the way into the next 3.5-4 h segment, two junctions merged per rung
pair).

The test is the converse of :func:`.repairs.merge_close_junctions` (branches aiming at one
node make one junction): a line "meets" a point when the point lies within the strip of the
line, ``max(width * h, LINKS.strip_noise * noise)``, or within ``REPAIRS.merge_tan`` times its
distance from the branch end, and ahead of the branch.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from .chains import end_portion, group_medians, polylen
from .params import RobustParams, Scales
from .thresholds import ENDS, LINKS, NODES, PAIRED, REPAIRS
from .topology import Topology

__all__ = ["split_paired_junctions", "Lines", "branch_lines", "meeting_point", "meet_at_one_point", "meet_loosely",
           "best_pair", "best_pairs", "short_branches", "straight_pairs", "towards_tips", "curve_directions",
           "meet_at_one_point_each", "region_stats"]


class Lines(NamedTuple):
    """The fitted lines of branches: m lines (arrays (m, d) and (m,)), or m lines of each of n
    regions (arrays (n, m, d) and (n, m)).

    Attributes
    ----------
    c : (..., m, d) ndarray
        A point of each line (the centroid of the branch's end portion).
    u : (..., m, d) ndarray
        Unit directions (0 for a branch of a single point).
    tip : (..., m, d) ndarray
        The branch's last point (nearest the junction).
    lim : (..., m) ndarray
        Strip half-width of each line (absolute units).
    """

    c: np.ndarray
    u: np.ndarray
    tip: np.ndarray
    lim: np.ndarray


def branch_lines(topo: Topology, sc: Scales, incs: list[list[tuple[int, int]]]) -> tuple[Lines, np.ndarray]:
    """The lines of the branches at many regions, fitted as the node placement fits them.

    Each branch ``(chain, side)`` of ``incs[j]`` (the ends at region ``j``) gets the line of
    its end portion (:func:`.chains.end_portion` over ``NODES.fit_span`` spacings, plus
    ``NODES.fit_noise`` times the noise): the centroid and the principal direction of those
    points, all branches at once.

    Parameters
    ----------
    topo : Topology
    sc : Scales
    incs : list of list of (int, int)

    Returns
    -------
    lines : Lines
        Every branch's line, region after region (a branch of a single point has direction 0).
    off : (len(incs) + 1,) ndarray of int64
        Region ``j``'s lines are ``off[j]:off[j + 1]``.
    """
    P, h, noise = topo.P, sc.h, float(sc.noise)
    tails = [np.asarray(topo.end_ids(i, s))[::-1] for inc in incs for i, s in inc]  # from the end
    n_br = len(tails)
    off = np.r_[0, np.cumsum([len(inc) for inc in incs])].astype(np.int64)
    hl = np.array([h[t[0]] for t in tails], dtype=np.float64)
    lim_arc = NODES.fit_span * hl + NODES.fit_noise * noise
    # the end portions: arc length summed from each end (padded rows, sequential sums: the
    # counts of chains.end_portion); a portion longer than the padding is found one by one
    width = min(max((len(t) for t in tails), default=1), PAIRED.tail_points)
    idx = np.zeros((n_br, width), dtype=np.int64)
    valid = np.zeros((n_br, width), dtype=bool)
    for b, t in enumerate(tails):
        k = min(len(t), width)
        idx[b, :k] = t[:k]
        valid[b, :k] = True
    X = P[idx]  # (n_br, width, d)
    D = X[:, 1:] - X[:, :-1]
    D *= D
    step = np.sqrt(D.sum(axis=2))
    step[~valid[:, 1:]] = np.inf
    arc = np.cumsum(step, axis=1)
    m = 1 + np.sum(arc <= lim_arc[:, None], axis=1)
    m = np.maximum(m, np.minimum(ENDS.min_points, np.array([len(t) for t in tails])))
    for b in np.flatnonzero(m >= width).tolist():  # (rare: a portion past the padding)
        E = end_portion(P, h, tails[b][::-1], span=NODES.fit_span + NODES.fit_noise * noise / hl[b])
        m[b] = len(E)
    m = np.minimum(m, np.array([len(t) for t in tails]))
    big = max(int(m.max()) if n_br else 1, 1)
    if big > width:
        idx = np.zeros((n_br, big), dtype=np.int64)
        for b, t in enumerate(tails):
            idx[b, :m[b]] = t[:m[b]]
        X = P[idx]
    W = (np.arange(X.shape[1])[None, :] < m[:, None]).astype(np.float64)  # (n_br, width)
    c = (X * W[:, :, None]).sum(axis=1) / m[:, None]
    Y = (X - c[:, None, :]) * W[:, :, None]
    C = np.einsum("bki,bkj->bij", Y, Y)
    _, V = np.linalg.eigh(C)
    u = V[:, :, -1] * (m > 1)[:, None]
    lims = np.maximum(sc.width * hl, LINKS.strip_noise * noise)
    return Lines(c, u, X[:, 0, :].copy(), lims), off


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
    L = Lines(c[None], u[None], c[None], np.zeros((1, len(c))))
    return _group_points(L, np.ones((1, len(c))), np.asarray(anchor, dtype=np.float64)[None])[0]


def meet_at_one_point(L: Lines, anchor: np.ndarray) -> bool:
    """Whether every line of ``L`` (m lines) meets their least-squares meeting point
    (:func:`meeting_point`, held near ``anchor``): the branches of one junction."""
    x = meeting_point(L.c, L.u, anchor)
    return bool(_meets_all(L, np.broadcast_to(x, L.c.shape)).all())


def meet_at_one_point_each(L: Lines, off: np.ndarray, anchors: np.ndarray) -> np.ndarray:
    """:func:`meet_at_one_point` of many regions at once (the regions of ``m`` lines together).

    Parameters
    ----------
    L : Lines
        Every region's lines, region after region (as :func:`branch_lines` returns them).
    off : (R + 1,) ndarray of int64
        Region ``j``'s lines are ``off[j]:off[j + 1]``.
    anchors : (R, d) ndarray

    Returns
    -------
    (R,) ndarray of bool
    """
    nl = np.diff(off)
    out = np.zeros(len(nl), dtype=bool)
    for m in np.unique(nl).tolist():
        js = np.flatnonzero(nl == m)
        rows = off[js][:, None] + np.arange(m)
        x = _group_points(Lines(L.c[rows], L.u[rows], L.c[rows], L.lim[rows]), np.ones((len(js), m)), anchors[js])
        flat = Lines(L.c[rows].reshape(-1, L.c.shape[1]), L.u[rows].reshape(-1, L.c.shape[1]),
                     L.tip[rows].reshape(-1, L.c.shape[1]), L.lim[rows].reshape(-1))
        out[js] = _meets_all(flat, np.repeat(x, m, axis=0)).reshape(len(js), m).all(axis=1)
    return out


def meet_loosely(L: Lines, anchor: np.ndarray) -> bool:
    """Whether branches crossing a straight curve that runs through two junction points, not
    all parallel, are strokes drawn loosely into one point of it (one junction, real sketches).

    True unless they are two branches with a direction (a branch of a single point has none)
    whose lines pass apart (:func:`meet_at_one_point`, held at ``anchor``: the middle of the
    segment between the two points): skew lines in 3D are a comb's teeth leaving its spine at
    two tilts, one junction each.

    Parameters
    ----------
    L : Lines
        The crossing branches' lines, m of them.
    anchor : (d,) ndarray

    Returns
    -------
    bool
    """
    known = np.linalg.norm(L.u, axis=1) > 0
    if known.sum() != 2:
        return True
    ids = np.flatnonzero(known)
    return meet_at_one_point(Lines(L.c[ids], L.u[ids], L.tip[ids], L.lim[ids]), anchor)


def _meets_all(L: Lines, x: np.ndarray) -> np.ndarray:
    """Per line of ``L``: whether it meets point ``x[k]`` (one point per line; see the module's
    note)."""
    r = x - L.c
    along = np.einsum("ij,ij->i", r, L.u)
    dist = np.sqrt(np.maximum(np.einsum("ij,ij->i", r, r) - along * along, 0.0))
    lim = np.maximum(L.lim, REPAIRS.merge_tan * np.linalg.norm(x - L.tip, axis=1))
    ahead = np.sign(np.einsum("ij,ij->i", L.tip - L.c, L.u)) * along >= -PAIRED.behind * lim
    return (dist <= lim) & ahead


def _one_point_links(topo: Topology, L: Lines, off: np.ndarray, incs: list, regions: list) -> Lines:
    """The lines ``L`` (of :func:`branch_lines`, ``off`` per region of ``regions``, the ends
    ``incs`` at each) with a direction for every branch of a single point that links two
    regions: from this region's point nearest to it to the other region's point nearest to it
    (the short link between two junctions, a street's between two close crossings, whose one
    sample gives no line of its own); other one-point branches keep direction 0."""
    P = topo.P
    u = L.u
    zero = np.flatnonzero(~(np.linalg.norm(u, axis=1) > 0))  # (few: read one by one)
    for b, j in zip(zero.tolist(), (np.searchsorted(off, zero, side="right") - 1).tolist()):
        r = regions[j]
        i, s = incs[j][b - int(off[j])]
        c = topo.chains[i]
        other = c.ends[1 - s]
        if len(c.ids) != 1 or other == r or other < 0 or not len(topo.regions[other]) or not len(topo.regions[r]):
            continue
        p = P[int(c.ids[0])]
        a = P[topo.regions[r]][np.argmin(np.linalg.norm(P[topo.regions[r]] - p, axis=1))]
        z = P[topo.regions[other]][np.argmin(np.linalg.norm(P[topo.regions[other]] - p, axis=1))]
        e = z - a
        ne = float(np.linalg.norm(e))
        if ne > 0:
            if u is L.u:
                u = u.copy()
            u[b] = e / ne
    return L if u is L.u else Lines(L.c, u, L.tip, L.lim)


def best_pair(L: Lines, anchor: np.ndarray, h: float):
    """The split of the lines ``L`` into two groups meeting at two points, if one reads so.

    None when all lines meet one point (:func:`meeting_point` of all), or when no split into two
    groups of two or more lines has every group's lines meet its point with the points over
    ``PAIRED.sep * h`` apart, every branch's end nearer its own group's point (a half of a
    straight curve through both points, :func:`_through_halves`, by its end portion's centroid:
    a rail that ran on past its junction towards the other under noise) and the summed
    squared distances of the lines to their points at most ``PAIRED.gain`` times those to the
    one point (curved branches of one junction miss it, but miss two points almost as much),
    and, when a line of each group runs along the segment (one straight curve through both
    points), the other lines parallel (within ``PAIRED.parallel_cos``). Each group's point is found with the segment between the two
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
    found = best_pairs(Lines(L.c[None], L.u[None], L.tip[None], L.lim[None]), anchor[None], np.array([h]))
    k, xa, xb = found[0][0], found[1][0], found[2][0]
    if k < 0:
        return None
    return _splits(len(L.c))[k].copy(), xa, xb


def best_pairs(L: Lines, anchor: np.ndarray, h: np.ndarray, short: np.ndarray | None = None):
    """:func:`best_pair` of many regions of ``m`` lines each, at once.

    Parameters
    ----------
    L : Lines
        Arrays of shape (R, m, d) (``lim``: (R, m)): the lines of R regions.
    anchor : (R, d) ndarray
    h : (R,) ndarray
    short : (R, m) ndarray of bool, optional
        Lines of branches whose whole chain is shorter than the end portion a line is fitted
        on (:func:`short_branches`): their direction is no crossing angle, so they count as
        parallel to the others in the test of one straight curve through both points.

    Returns
    -------
    split : (R,) ndarray of int64
        The row of :func:`_splits` chosen per region, -1 where none (every region when ``m`` is
        over ``PAIRED.max_lines``: its splits are not tried).
    xa, xb : (R, d) ndarray
        Its two points (the second group's is ``xb``).
    """
    R, m, d = L.c.shape
    if m > PAIRED.max_lines:  # (too many splits to try; never two junctions)
        return np.full(R, -1, dtype=np.int64), np.zeros((R, d)), np.zeros((R, d))
    flat = Lines(L.c.reshape(-1, d), L.u.reshape(-1, d), L.tip.reshape(-1, d), L.lim.reshape(-1))
    one = np.ones((R, m))
    x1 = _group_points(L, one, anchor)
    meets1 = _meets_all(flat, np.repeat(x1, m, axis=0)).reshape(R, m).all(axis=1)
    cost1 = _costs(L, np.broadcast_to(x1[:, None, :], L.c.shape))
    B = _splits(m)  # (S, m): the second group of every split
    S = len(B)
    if S == 0:
        return np.full(R, -1, dtype=np.int64), np.zeros((R, d)), np.zeros((R, d))
    # every (region, split) pair: arrays of shape (R * S, ...)
    Lr = Lines(np.repeat(L.c, S, axis=0), np.repeat(L.u, S, axis=0), np.repeat(L.tip, S, axis=0),
               np.repeat(L.lim, S, axis=0))
    Wb = np.tile(B.astype(np.float64), (R, 1))
    Wa = 1.0 - Wb
    an = np.repeat(anchor, S, axis=0)
    xa = _group_points(Lr, Wa, an)
    xb = _group_points(Lr, Wb, an)
    for _ in range(PAIRED.rounds):
        e = xb - xa
        ne = np.linalg.norm(e, axis=1)
        go = ne > 0
        e = np.where(go[:, None], e / np.where(go, ne, 1.0)[:, None], 0.0)
        xa = np.where(go[:, None], _group_points(Lr, Wa, an, xb, e), xa)
        xb = np.where(go[:, None], _group_points(Lr, Wb, an, xa, e), xb)
    good = np.linalg.norm(xb - xa, axis=1) > PAIRED.sep * np.repeat(h, S)
    Bb = Wb > 0.5
    own = np.where(Bb[:, :, None], xb[:, None, :], xa[:, None, :])  # (R * S, m, d)
    other = np.where(Bb[:, :, None], xa[:, None, :], xb[:, None, :])
    fl = Lines(Lr.c.reshape(-1, d), Lr.u.reshape(-1, d), Lr.tip.reshape(-1, d), Lr.lim.reshape(-1))
    good &= _meets_all(fl, own.reshape(-1, d)).reshape(R * S, m).all(axis=1)
    # every branch ends nearer its own junction than the other one (a rail's half that ran on
    # past its junction towards the other: by its end portion's centroid)
    e = xb - xa
    e = e / np.maximum(np.linalg.norm(e, axis=1), np.finfo(float).tiny)[:, None]
    along = np.abs(np.einsum("nmi,ni->nm", Lr.u, e)) > PAIRED.parallel_cos
    end = np.where(_through_halves(Lr.u, along, Bb)[:, :, None], Lr.c, Lr.tip)
    good &= (np.linalg.norm(end - own, axis=2) < np.linalg.norm(end - other, axis=2)).all(axis=1)
    cost = _costs(Lr, own)
    good &= cost <= PAIRED.gain * np.repeat(cost1, S)
    good &= ~np.repeat(meets1, S)
    # one straight curve through both points (a line of each group along the segment) with the
    # other branches crossing it at two places: junctions only when those are parallel (a
    # ladder's rungs, a comb's teeth); strokes crossing a curve at two angles a few spacings
    # apart are one junction drawn loosely (real sketches)
    through = (along.sum(axis=1) == 2) & ((along & Bb).sum(axis=1) == 1)
    first = np.argmax(~along, axis=1)
    v0 = Lr.u[np.arange(len(first)), first]
    par = (np.abs(np.einsum("nmi,ni->nm", Lr.u, v0)) > PAIRED.parallel_cos) | along
    if short is not None:
        par |= np.repeat(short, S, axis=0)
    loose = through & ~par.all(axis=1) & good
    for q in np.flatnonzero(loose).tolist():  # (few)
        rest = ~along[q]
        loose[q] = meet_loosely(Lines(Lr.c[q, rest], Lr.u[q, rest], Lr.tip[q, rest], Lr.lim[q, rest]),
                                0.5 * (xa[q] + xb[q]))
    good &= ~loose
    # a straight curve with a half in each group (two lines facing each other, each through the
    # other's centroid) passes through both points: it must run along the segment (an X
    # crossing seen under noise splits into two V's whose points lie off that curve)
    cross = Bb[:, :, None] != Bb[:, None, :]
    span = curve_directions(L)
    on_seg = np.abs(np.einsum("rmni,rsi->rsmn", span, e.reshape(R, S, d))).reshape(R * S, m, m) > PAIRED.parallel_cos
    good &= ~np.any(np.repeat(straight_pairs(L, towards_tips(L)), S, axis=0) & cross & ~on_seg, axis=(1, 2))
    cost = np.where(good, cost, np.inf).reshape(R, S)
    k = np.argmin(cost, axis=1)  # the least cost (ties: the first split)
    ok = np.isfinite(cost[np.arange(R), k])
    pick = np.arange(R) * S + k
    return np.where(ok, k, -1), xa[pick], xb[pick]


def _through_halves(u: np.ndarray, along: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Which lines are a half of one straight curve through both points of a split: along the
    segment (``along``: within ``PAIRED.parallel_cos`` of its direction) and parallel to exactly
    one other line, which is in the other group (a ladder's rail through two junctions). Such a
    half may run on past its junction towards the other under noise (its tip then nearer the
    other point), so :func:`best_pairs` judges its side by its end portion's centroid instead; a third
    line parallel to them (strokes drawn over one another) leaves every line judged by its tip.

    Parameters
    ----------
    u : (n, m, d) ndarray
        Unit directions of m lines, per split.
    along : (n, m) ndarray of bool
        The lines along each split's segment.
    second : (n, m) ndarray of bool
        The lines of each split's second group.

    Returns
    -------
    (n, m) ndarray of bool
    """
    par = np.abs(np.einsum("nmi,nki->nmk", u, u)) > PAIRED.parallel_cos
    par &= ~np.eye(u.shape[1], dtype=bool)[None]
    across = second[:, :, None] != second[:, None, :]
    return along & (par.sum(axis=2) == 1) & (par & across).any(axis=2)


def towards_tips(L: Lines) -> np.ndarray:
    """The directions of lines ``L`` (R, m, d), each turned towards its branch's end (the
    fitted directions have either sign): (R, m, d)."""
    return L.u * np.where(np.einsum("rmi,rmi->rm", L.tip - L.c, L.u) < 0, -1.0, 1.0)[:, :, None]


def curve_directions(L: Lines) -> np.ndarray:
    """The direction of the curve through each pair of branches of lines ``L`` ((R, m, d)
    arrays): from one line's centroid to the other's, normalised, (R, m, m, d) (0 for a line
    with itself). Read over the span between the two end portions (10-16 h apart on a street),
    not as the mean of the lines' own directions, which the noise tilts by several degrees each
    (7 December 2026, see the module's text)."""
    span = L.c[:, None, :, :] - L.c[:, :, None, :]
    return span / np.maximum(np.linalg.norm(span, axis=-1), np.finfo(float).tiny)[..., None]


def straight_pairs(L: Lines, ud: np.ndarray) -> np.ndarray:
    """Per region, the pairs of lines that are one straight curve through it: (R, m, m) bool for
    lines ``L`` of shape (R, m, d) (``ud``: their :func:`towards_tips`), True where the two
    branches face each other (their directions towards their ends within ``PAIRED.parallel_cos``
    of opposite) and each line passes the other's centroid, on average, within the strip or the aim angle ``REPAIRS.merge_tan`` seen over half
    the distance between the centroids (as a line meets a point)."""
    facing = np.einsum("rmi,rni->rmn", ud, ud) < -PAIRED.parallel_cos
    r = L.c[:, None, :, :] - L.c[:, :, None, :]  # (R, m, n, d): from line m's point to line n's
    along = np.einsum("rmni,rmi->rmn", r, L.u)
    rr = np.einsum("rmni,rmni->rmn", r, r)
    dist = np.sqrt(np.maximum(rr - along * along, 0.0))
    lim = np.maximum(L.lim[:, :, None], L.lim[:, None, :]) + REPAIRS.merge_tan * 0.5 * np.sqrt(rr)
    return facing & (0.5 * (dist + np.swapaxes(dist, 1, 2)) <= lim)


def _costs(L: Lines, x: np.ndarray) -> np.ndarray:
    """Summed squared distances of the points ``x`` (n, m, d) to the lines ``L`` (n, m, d), per
    row: (n,)."""
    r = x - L.c
    along = np.einsum("nmi,nmi->nm", r, L.u)
    return (np.einsum("nmi,nmi->nm", r, r) - along * along).sum(axis=1)


def _splits(m: int) -> np.ndarray:
    """Every split of ``m`` lines into two groups of ``PAIRED.min_group`` or more, each once:
    (n_split, m) bool, True for the second group (the smaller one; with line 0 when the two are
    of one size), in the order of :func:`itertools.combinations` by growing size."""
    out = []
    for k in range(PAIRED.min_group, m // 2 + 1):
        for grp in itertools.combinations(range(m), k):
            if 2 * k == m and 0 not in grp:
                continue
            row = np.zeros(m, dtype=bool)
            row[list(grp)] = True
            out.append(row)
    return np.array(out, dtype=bool).reshape(-1, m)


def _group_points(L: Lines, W: np.ndarray, anchor: np.ndarray, xo: np.ndarray | None = None,
                  e: np.ndarray | None = None) -> np.ndarray:
    """:func:`meeting_point` of a group of lines per row, many rows at once.

    Parameters
    ----------
    L : Lines
        Arrays of shape (n, m, d): m lines per row.
    W : (n, m) ndarray of float
        1 for the lines of each row's group, 0 for the others.
    anchor : (n, d) ndarray
    xo, e : (n, d) ndarray, optional
        One more line per row: through ``xo`` along ``e`` (the segment to the other point).

    Returns
    -------
    (n, d) ndarray
    """
    d = L.c.shape[2]
    k = W.sum(axis=1)
    uc = np.einsum("nki,nki->nk", L.u, L.c)
    UU = np.einsum("nk,nki,nkj->nij", W, L.u, L.u)
    b = np.einsum("nk,nki->ni", W, L.c) - np.einsum("nk,nki->ni", W * uc, L.u)
    if xo is not None:
        k = k + 1
        UU = UU + np.einsum("ni,nj->nij", e, e)
        b = b + xo - e * np.einsum("ni,ni->n", e, xo)[:, None]
    w = PAIRED.hold * k
    A = (k + w)[:, None, None] * np.eye(d) - UU
    b = b + w[:, None] * anchor
    return np.linalg.solve(A, b[:, :, None])[:, :, 0]


def _segment(P: np.ndarray, rid: np.ndarray, xa: np.ndarray, xb: np.ndarray, lim: float, gap: float):
    """The region points along the segment ``xa``-``xb``, ordered from ``xa``: those strictly
    between the two points (projection) within ``lim`` of the line; None when there are none or
    when two consecutive ones (or the ends and their nearest) lie over ``gap`` apart."""
    on, t = _on_segment(P, rid, xa, xb, lim)
    L = float(np.linalg.norm(xb - xa))
    if not on.any():
        return None, t
    ids = rid[on][np.lexsort((rid[on], t[on]))]
    ts = np.r_[0.0, np.sort(t[on]), L]
    if np.diff(ts).max() > gap:
        return None, t
    return ids, t


def _on_segment(P: np.ndarray, ids: np.ndarray, xa: np.ndarray, xb: np.ndarray, lim: float):
    """Which points ``ids`` lie on the segment ``xa``-``xb`` (strictly between the two points by
    their projection, within ``lim`` of the line), and their projections ``t`` from ``xa``."""
    e = xb - xa
    L = float(np.linalg.norm(e))
    R = P[ids] - xa
    t = R @ (e / L)
    d = np.sqrt(np.maximum(np.einsum("ij,ij->i", R, R) - t * t, 0.0))
    return (t > 0) & (t < L) & (d <= lim), t


def _overruns(P: np.ndarray, topo: Topology, inc: list[tuple[int, int]], xa: np.ndarray, xb: np.ndarray,
              lim: float) -> list[np.ndarray]:
    """Per chain end ``inc`` at a region: its last points that lie on the segment ``xa``-``xb``
    (:func:`_on_segment`; all but its first at most), from the end: a chain that ran on past
    its node, round the corner onto the short segment to the next junction."""
    out = []
    for i, s in inc:
        ids = topo.end_ids(i, s)[::-1]  # (from the end)
        on, _ = _on_segment(P, ids, xa, xb, lim)
        k = int(np.argmin(on)) if not on.all() else len(on)
        out.append(ids[:min(k, len(ids) - 1)])  # (a chain keeps a point: Topology.trim_end)
    return out


def split_paired_junctions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Every region of valence ``PAIRED.min_valence`` or more whose branches meet at two points
    (:func:`best_pair`), joined by region points along the segment between them, becomes two
    junctions joined by a chain of those points.

    Where the segment's points are a chain's that ran on past its node round the corner onto
    it (:func:`_overruns`; its line may then meet its point up to ``PAIRED.behind`` strip
    half-widths behind its end portion), they join the region first (``Topology.trim_end``),
    when the segment is then whole (else nothing changes).

    A branch of a single sample has no line of its own; one that links the region to another
    (two crossings a few spacings apart, their short link one sample long under noise) gets
    the direction between the two regions' points nearest to it (:func:`_one_point_links`);
    a region with any other one-sample branch is not tried. Since 6 December 2026 (the streets'
    crossings 3.9 h apart: 928-run harness 7 better, 0 worse, outliers 1 better; CASSIE 2
    worse by 0.012 and 0.002, a study sketch's cluster of three junctions read as two).

    The region's other points go to the nearer junction (by their projection on the segment).
    A chain with both ends at the region (it leaves and comes back: a street block's side)
    is read as any other, each end going to its junction (such regions were left whole: a
    building under noise 0.2h 0.70 -> 0.91, the rest of the 832-run harness and CASSIE
    equal). Under noise the
    shell is widened and merges such junctions more often; on noise-free input it runs after
    :func:`.junctions.separate_close_junctions`, for the pairs that test left as one.
    """
    P, h = topo.P, sc.h
    cand, incs = [], []
    for r in np.flatnonzero(topo.v >= PAIRED.min_valence).tolist():
        inc = topo.incident(r)
        if len(topo.regions[r]):
            cand.append(r)
            incs.append(inc)
    if not cand:
        return
    L, off = branch_lines(topo, sc, incs)
    L = _one_point_links(topo, L, off, incs, cand)
    nl = np.diff(off)
    single = np.logical_or.reduceat(~(np.linalg.norm(L.u, axis=1) > 0), off[:-1])  # a one-point branch
    anchors, hr = region_stats(P, h, [topo.regions[r] for r in cand])
    short = short_branches(topo, sc, incs)
    found: dict[int, tuple] = {}
    for m in np.unique(nl).tolist():  # the regions of m lines at once
        js = np.flatnonzero((nl == m) & ~single)
        if not len(js):
            continue
        rows = off[js][:, None] + np.arange(m)
        Lm = Lines(L.c[rows], L.u[rows], L.tip[rows], L.lim[rows])
        k, xa, xb = best_pairs(Lm, anchors[js], hr[js], short[rows])
        hit = np.flatnonzero(k >= 0).tolist()
        B = _splits(m) if hit else None  # (none over PAIRED.max_lines: never enumerated)
        for q in hit:
            found[int(js[q])] = (B[k[q]], xa[q], xb[q], float(np.max(L.lim[rows[q]])))
    for j in sorted(found):
        r, inc = cand[j], incs[j]
        mask, xa, xb, lim = found[j]
        rid = topo.regions[r]
        seg, t = _segment(P, rid, xa, xb, lim, prm.link * hr[j])
        if seg is None:  # the segment's samples may end a chain that ran on past its node
            tails = _overruns(P, topo, inc, xa, xb, lim)
            if any(len(x) for x in tails):
                seg, t = _segment(P, np.concatenate([rid, *tails]), xa, xb, lim, prm.link * hr[j])
                if seg is not None:  # (trimmed only when the segment is then whole)
                    for (i, s), x in zip(inc, tails):
                        topo.trim_end(i, s, len(x))
                    rid = topo.regions[r]  # (the same points in the trims' order: t again)
                    seg, t = _segment(P, rid, xa, xb, lim, prm.link * hr[j])
        if seg is None:
            continue
        rest = ~np.isin(rid, seg)
        near_b = t > 0.5 * float(np.linalg.norm(xb - xa))
        topo.split_region(r, [e for e, mk in zip(inc, mask.tolist()) if mk], rid[rest & ~near_b],
                          rid[rest & near_b], seg)


def short_branches(topo: Topology, sc: Scales, incs: list[list[tuple[int, int]]]) -> np.ndarray:
    """Per branch of ``incs`` (as :func:`branch_lines` orders them): whether its whole chain
    is shorter than the end portion its line is fitted on (``NODES.fit_span`` spacings at its
    end plus ``NODES.fit_noise`` times the noise). Such a line runs from this junction into the
    next one (a street grid's short link, 4 h between two crossings): its direction is bent by
    the turn there and tells no crossing angle.

    Returns
    -------
    (n_branches,) ndarray of bool
    """
    P, h = topo.P, sc.h
    ends = [topo.end_ids(i, s) for inc in incs for i, s in inc]
    span = np.array([NODES.fit_span * h[e[-1]] for e in ends]) + NODES.fit_noise * float(sc.noise)
    return np.array([polylen(P[e]) for e in ends]) < span


def region_stats(P: np.ndarray, h: np.ndarray, rids: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Centroid and median spacing (as ``np.median``) of every region's points, all at once.

    Parameters
    ----------
    P : (N, d) ndarray
    h : (N,) ndarray
    rids : list of (n_j,) ndarray of int64
        Non-empty point lists.

    Returns
    -------
    centroid : (len(rids), d) ndarray
    hmed : (len(rids),) ndarray
    """
    n = np.array([len(r) for r in rids], dtype=np.int64)
    flat = np.concatenate(rids)
    start = np.r_[0, np.cumsum(n)[:-1]]
    cen = np.add.reduceat(P[flat], start, axis=0) / n[:, None]
    return cen, group_medians(h[flat], n)
