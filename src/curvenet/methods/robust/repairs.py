"""Stage 6: the repairs, in order: what noise and sparse sampling break, fixed on the topology.

Each repair is ``repair(topo, sc, prm) -> None``: it reads the :class:`~.topology.Topology`,
the :class:`~.params.Scales` and the user's :class:`~.params.RobustParams`, and changes the
topology only through its methods. :data:`ORDER` lists them in the order
:func:`run_repairs` applies them (the order matters: each docstring says what it expects).
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from ... import _sigint
from ...neighbors import query_threads
from .chains import Chain, chain_lengths, end_counts, end_portion, extent, fit_line, polylen, segment_distance, step_lengths
from .graph import csr_edges
from .junctions import swallowed_branches
from .nodes import free_end, junction, junction_positions
from .paired import split_paired_junctions
from .spanning import split_multiple_junctions, split_rows_again
from .endtrees import read_end_junctions
from .branched import split_branched_chains, split_tails
from .params import RobustParams, Scales
from .thresholds import LINKS, NODES, NUMERIC, REPAIRS, SHELL, UNEXPLAINED
from .topology import Topology
from .unexplained import leaves, noise_band

__all__ = ["ORDER", "run_repairs", "merge_twin_chains", "merge_near_pass_through", "absorb_short_loops", "absorb_orphans",
           "tips_to_junctions", "join_facing_tips", "attach_dangling", "prune_spurs", "cross_pass_regions", "join_through_pass_regions",
           "merge_close_junctions", "close_tip_pairs", "split_multiple_junctions", "split_rows_again", "split_branched_chains"]


def merge_near_pass_through(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """A region passed through by one curve (valence 2) right next to a junction region joins it.

    The failure: noise cuts a crossing's region in two, one half seen as a plain pass-through.
    Each valence-2 region merges into the nearest region of valence 2 or more within
    ``link * REPAIRS.tip_gap`` spacings (plus ``LINKS.gap_noise`` times the noise). Under noise,
    into a junction (valence 3 or more) only when the curve passes it straight
    (:func:`_passed_straight`) and the junction lies on that curve (:func:`_on_the_way`): else it
    is a junction whose short curve to that one the widened shell took into the regions (a T
    whose through road passes straight, its stem the short link to the next crossing), and it
    stays (see ``REPAIRS.pass_cos``, ``REPAIRS.pass_line``). Never where a chain joining the two
    would become a loop that stays (:func:`_would_loop`).
    """
    from scipy.spatial import cKDTree

    P, h, regions, v = topo.P, sc.h, topo.regions, topo.v
    cand = [r for r in range(len(regions)) if v[r] >= 2 and len(regions[r])]
    two = [r for r in cand if v[r] == 2]
    if not two or len(cand) < 2:
        return
    noise = sc.noise
    lab = np.repeat(np.asarray(cand, dtype=np.int64), [len(regions[r]) for r in cand])
    ids = np.concatenate([regions[r] for r in cand])
    tree = cKDTree(P[ids])
    for r in two:
        pts = regions[r]
        if len(pts) == 0 or v[r] != 2:
            continue
        gap = prm.link * REPAIRS.tip_gap * float(np.median(h[pts])) + LINKS.gap_noise * noise
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
        if not sc.clean and v[t] >= NODES.junction_valence:
            us = _pass_dirs(topo, sc, r)
            if not (_passed_straight(topo, sc, r, us) and _on_the_way(topo, sc, r, t, us)):
                continue
        if _would_loop(topo, prm, r, t, h):
            continue
        lab[lab == r] = t
        topo.absorb(r, t)


def _would_loop(topo: Topology, prm: RobustParams, r: int, t: int, h: np.ndarray) -> bool:
    """Whether merging region ``r`` into ``t`` makes a loop that stays: a chain joins the two
    and reaches farther than ``shell_outer`` spacings from their merged centre (what
    :func:`absorb_short_loops` would not take into the junction): the tip of a sharp corner
    whose two legs, close together, were each flagged, not the two halves of one crossing."""
    P = topo.P
    cen = None
    for i, s in topo.incident(r):
        c = topo.chains[i]
        if c.closed or c.ends[1 - s] != t:
            continue
        if cen is None:
            cen = P[np.r_[topo.regions[r], topo.regions[t]]].mean(axis=0)
        if not _within_shell(P, h, c.ids, cen, prm):
            return True
    return False


def _within_shell(P: np.ndarray, h: np.ndarray, ids: np.ndarray, cen: np.ndarray, prm: RobustParams) -> bool:
    """Whether the points ``ids`` of a chain lie within ``shell_outer`` of their median spacing
    from ``cen`` (d,): a chain from a junction back to it that short lies inside the junction
    (:func:`absorb_short_loops`)."""
    return bool(np.linalg.norm(P[ids] - cen, axis=1).max() < prm.shell_outer * float(np.median(h[ids])))


def _pass_dirs(topo: Topology, sc: Scales, r: int) -> list:
    """The directions of the lines of region ``r``'s chain ends (:func:`_end_line`, as node
    placement fits them; None for an end too short for a line), in incidence order."""
    return [_end_line(topo.P, sc.h, topo.chains, i, s, sc.noise)[2] for i, s in topo.incident(r)]


def _passed_straight(topo: Topology, sc: Scales, r: int, us: list | None = None) -> bool:
    """Whether the curve through region ``r`` (valence 2) passes it straight: the lines of its
    two chain ends (:func:`_pass_dirs`, or ``us`` when already read) within
    ``REPAIRS.pass_cos`` of each other; True when an end has too few points for a line."""
    us = _pass_dirs(topo, sc, r) if us is None else us
    if any(u is None for u in us):
        return True
    return len(us) != 2 or abs(float(us[0] @ us[1])) >= REPAIRS.pass_cos


def _on_the_way(topo: Topology, sc: Scales, r: int, t: int, us: list | None = None) -> bool:
    """Whether region ``t``'s centre lies within ``REPAIRS.pass_line`` shell spacings (the median
    spacing of region ``r`` plus ``SHELL.widen`` times the noise) of the line of the curve through
    region ``r`` (valence 2: its two chain ends' lines, :func:`_pass_dirs` or ``us`` when already
    read, averaged, through ``r``'s centre): the other half of a crossing lies on the curve that
    passes straight through this half; the next junction of a T's stem lies off its through road.
    True when an end has too few points for a line."""
    P = topo.P
    us = _pass_dirs(topo, sc, r) if us is None else us
    if len(us) != 2 or any(u is None for u in us):
        return True
    u = us[0] + (us[1] if float(us[0] @ us[1]) >= 0 else -us[1])
    u = u / np.linalg.norm(u)
    d = P[topo.regions[t]].mean(axis=0) - P[topo.regions[r]].mean(axis=0)
    off = float(np.sqrt(max(float(d @ d) - float(d @ u) ** 2, 0.0)))
    return off <= REPAIRS.pass_line * (float(np.median(sc.h[topo.regions[r]])) + SHELL.widen * sc.noise)


def absorb_short_loops(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """A short chain leaving a region and coming back to it lies inside the junction: absorbed.

    The failure: a few points of a junction region escape the flagging and form a chain from
    the region back to itself. Such a chain staying within ``shell_outer`` spacings of the
    region's centre joins the region.
    """
    P, h = topo.P, sc.h
    for i, c in enumerate(topo.chains):
        r = c.ends[0]
        if topo.alive[i] and not c.closed and r == c.ends[1] and len(topo.regions[r]):
            if _within_shell(P, h, c.ids, P[topo.regions[r]].mean(axis=0), prm):
                topo.absorb_chain(i, r)


def merge_twin_chains(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Two chains between the same two regions that are one curve traced twice become one.

    The failure: the samples of a short curve between two junctions are shared out between two
    chains (every other sample in each), giving the two junctions a double edge. Two live open
    chains with the same two end regions (distinct) are twins when every point of each lies
    within ``REPAIRS.twin`` spacings (plus the noise) of a point of the other; the second (in
    chain order) dies and its points join the first, ordered along it. Two curves between the
    same two junctions that lie apart (an eye's two arcs) are left as they are. A region the
    merges leave with one chain end is a free end that :func:`attach_dangling` (which ran
    before) never saw: it is tried now (7 December 2026: a T's stem traced twice, its two chains
    joined at their tips by :func:`join_facing_tips`, while the bar passed by the junction;
    the plate kind at noise 0.2 h, sampling 7, 0.889 -> 1.000).
    """
    from scipy.spatial import cKDTree

    P, h = topo.P, sc.h
    pairs: dict[tuple[int, int], list[int]] = {}
    for i, c in enumerate(topo.chains):
        if topo.alive[i] and not c.closed and c.ends[0] != c.ends[1]:
            pairs.setdefault((min(c.ends), max(c.ends)), []).append(i)
    merged: set = set()
    for key in sorted(pairs):
        group = pairs[key]
        while len(group) >= 2:
            i = group[0]
            for j in group[1:]:
                a, b = topo.chains[i].ids, topo.chains[j].ids
                lim = REPAIRS.twin * float(np.median(h[np.r_[a, b]])) + sc.noise
                if (cKDTree(P[a]).query(P[b])[0].max() <= lim * (1 + NUMERIC.rel)
                        and cKDTree(P[b]).query(P[a])[0].max() <= lim * (1 + NUMERIC.rel)):
                    topo.merge_twin(i, j)
                    merged.update(key)
                    group.remove(j)
                    break
            else:
                group.pop(0)
    # a region the merges left with one chain end is a free end now, after attach_dangling ran:
    # it is tried again (a T's stem traced twice, its junction passed by the bar)
    freed = {r for r in merged if topo.v[r] == 1}
    if freed:
        attach_dangling(topo, sc, prm, only=freed)


def absorb_orphans(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """A flagged clump touching no chain, just beyond a free end, joins that free end's region.

    The failure: noise cuts the link between a free end and the last points of its curve,
    which are left as a region of their own. Such a region (no chain end ever listed there)
    joins the nearest free end within ``link * REPAIRS.tip_gap`` spacings (plus the noise gap).
    Under noise, a region that a chain passes over (:func:`_passed_over`: each of its points
    within the noise band of the segment between two consecutive samples of a chain) is a
    flagged sample of that chain's curve, not a lost tip: it is left (a twig's free end 1-2 h
    from another curve took such a sample of that curve as its tip, and the twig's tip was then
    read on the other curve and pruned; kinds twigs at noise 0.2 h sampling 7).
    """
    from scipy.spatial import cKDTree

    P, h, regions, v = topo.P, sc.h, topo.regions, topo.v
    tips = [r for r in range(len(regions)) if v[r] == 1]
    orphans = [r for r in range(len(regions)) if v[r] == 0 and len(regions[r]) and not topo.listed(r)]
    if not tips or not orphans:
        return
    tip_pts, tip_of = [], []
    for r in tips:
        ids = list(regions[r])
        for i, s in topo.incident(r):
            ids.append(int(topo.chains[i].ids[-1] if s == 1 else topo.chains[i].ids[0]))
        tip_pts += ids
        tip_of += [r] * len(ids)
    tip_pts = np.asarray(tip_pts, dtype=np.int64)
    tip_of = np.asarray(tip_of, dtype=np.int64)
    if not sc.clean:
        passed = _passed_over(topo, sc, prm, [regions[r] for r in orphans])
        orphans = [r for r, p in zip(orphans, passed) if not p]
    tree = cKDTree(P[tip_pts])
    noise = sc.noise
    for r in orphans:
        ids = regions[r]
        gap = prm.link * REPAIRS.tip_gap * float(np.median(h[ids])) + LINKS.gap_noise * noise
        d, k = tree.query(P[ids], distance_upper_bound=gap)
        ok = np.isfinite(d)
        if not ok.any():
            continue
        o = np.lexsort((tip_pts[k[ok]], d[ok]))[0]
        topo.absorb(r, int(tip_of[k[ok][o]]))


def _passed_over(topo: Topology, sc: Scales, prm: RobustParams, groups: list[np.ndarray]) -> list[bool]:
    """Whether a live chain passes over every point of each group (an (m,) array of point ids):
    the point lies within the noise band (:func:`.unexplained.noise_band`) of the segment between
    two consecutive samples of a chain, its foot strictly inside the segment (a point beyond a
    chain's end is not passed), one of the two within a link (``link`` spacings plus
    ``LINKS.gap_noise`` times the noise) of the point."""
    P = topo.P
    nxt = np.full(len(P), -1, dtype=np.int64)
    for i, c in enumerate(topo.chains):
        if topo.alive[i] and len(c.ids) > 1:
            nxt[c.ids[:-1]] = c.ids[1:]
            if c.closed:
                nxt[c.ids[-1]] = c.ids[0]
    q = np.concatenate(groups).astype(np.int64)
    near = sc.tree.query_ball_point(P[q], prm.link * sc.h[q] + LINKS.gap_noise * sc.noise)
    count = np.array([len(n) for n in near], dtype=np.int64)
    row = np.repeat(np.arange(len(q)), count)
    a = np.concatenate([np.asarray(n, dtype=np.int64) for n in near]) if len(row) else np.zeros(0, np.int64)
    prv = np.full(len(P), -1, dtype=np.int64)
    prv[nxt[nxt >= 0]] = np.flatnonzero(nxt >= 0)
    # the segments to the next and from the previous sample of each chain sample near the point
    row, a, b = np.r_[row, row], np.r_[a, prv[a]], np.r_[nxt[a], a]
    keep = (a >= 0) & (b >= 0)
    row, a, b = row[keep], a[keep], b[keep]
    x, A, B = P[q[row]], P[a], P[b]
    ab = B - A
    t = ((x - A) * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), NUMERIC.tiny)
    # (the foot inside the segment: the distance to it is the segment's, segment_distance's)
    off = np.linalg.norm(x - (A + t[:, None] * ab), axis=1)
    hit = (t > 0) & (t < 1) & (off < noise_band(sc.noise))
    on = np.zeros(len(q), dtype=bool)
    on[row[hit]] = True
    cut = np.cumsum([len(g) for g in groups])[:-1]
    return [bool(o.all()) for o in np.split(on, cut)]


def tips_to_junctions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """A free end right next to a junction region belongs to it (its link was lost to noise).

    Where the free end's node would be (:func:`~.nodes.free_end`), the nearest point of a region
    of valence 2 or more within ``link * REPAIRS.tip_gap`` spacings (plus the noise gap) takes
    the free end's region, unless the chain's other end is that very junction (a short spur:
    left to :func:`prune_spurs`). A free end without tip points there goes to the nearest
    other junction within that gap when the chain runs straight between the two
    (:func:`_linked_junction`): a short link between two close junctions (a street grid's, a
    ladder's, a building's edge of 7 h between two corners under noise), traced out of one of
    them, the other's region holding its last samples.
    """
    from scipy.spatial import cKDTree

    P, h, regions, v = topo.P, sc.h, topo.regions, topo.v
    big = [r for r in range(len(regions)) if v[r] >= 2 and len(regions[r])]
    tips = [r for r in range(len(regions)) if v[r] == 1]
    if not big or not tips:
        return
    lab = np.repeat(np.asarray(big, dtype=np.int64), [len(regions[r]) for r in big])
    ids = np.concatenate([regions[r] for r in big])
    tree = cKDTree(P[ids])
    noise = sc.noise
    # a tip's chain end and region do not change below before its turn (a merge only moves
    # the ends at the tip merged): the end portions of all in one call
    one = []
    for r in tips:
        inc = topo.incident(r)
        if len(inc) == 1:
            i, s = inc[0]
            one.append((r, i, s, topo.end_ids(i, s)))  # towards the tip
    ms = end_counts(P, h, [cids for _, _, _, cids in one], REPAIRS.tip_span).tolist()
    if not one:
        return
    # where each free end's node would be, then the nearest junction point of each (one query:
    # the tree does not change below)
    tip = np.array([free_end(P, h, cids, regions[r], m=m)[1] for (r, _, _, cids), m in zip(one, ms)])
    gap = prm.link * REPAIRS.tip_gap * h[[int(cids[-1]) for _, _, _, cids in one]] + LINKS.gap_noise * noise
    dk, kk = tree.query(tip, distance_upper_bound=float(gap.max()))
    # the bound is per tip: beyond it, none (as a query bounded by it; at the bound itself,
    # within rounding, that query is run)
    dk[dk > gap * (1 + NUMERIC.rel)] = np.inf
    for j in np.flatnonzero(np.isfinite(dk) & (dk >= gap * (1 - NUMERIC.rel))).tolist():
        dk[j], kk[j] = tree.query(tip[j], distance_upper_bound=float(gap[j]))
    for j, ((r, i, s, cids), d, k) in enumerate(zip(one, dk.tolist(), kk.tolist())):
        if not np.isfinite(d):
            continue
        t = int(lab[k])
        if topo.chains[i].ends[1 - s] == t:
            # a short spur of that very junction, left to the pruning; or, without tip points,
            # a short link between two close junctions traced from one of them: taken by the
            # other one
            t = _linked_junction(topo, sc, i, r, t, tip[j], float(gap[j]), tree, ids, lab)
            if t < 0:
                continue
        topo.absorb(r, t)


def _bare_end(topo: Topology, r: int) -> bool:
    """Whether region ``r`` is a free end without tip points (valence 1, no points: the chain
    touching it ends on no flagged sample)."""
    return topo.v[r] == 1 and not len(topo.regions[r])


def _no_curve_end(topo: Topology, sc: Scales, r: int) -> bool:
    """Whether the free end ``r`` is no curve's end: on noise-free input (and under low noise,
    ``NOISE.low``) the last points of a curve always see one side in their shells, so a curve's
    end is always flagged; a free end without tip points is a stub's, a piece of a region's own
    curve traced out of it. (Under noise a real tip can lose its flags: False there.)"""
    return bool(sc.low) and _bare_end(topo, r)


def _stub_beside(topo: Topology, i: int, s: int) -> bool:
    """Whether chain ``i``, from the region of valence 2 at its side ``s`` to a free end without
    tip points, is a stub at any noise: it leaves that region beside the region's other branch
    (its end there nearer that branch's end than half the region's reach beyond it), so the
    region holds a curve's end beyond them both, and a curve passing through would leave it
    on the far side. Under noise a spur of a sample or two off a tip's region (a traced
    neurite's end) made the region a pass: joined through it, the curve ran out to its tip and
    back to the spur, and the tip was lost."""
    r, far = topo.chains[i].ends[s], topo.chains[i].ends[1 - s]
    if not _bare_end(topo, far) or not len(topo.regions[r]):
        return False
    other = [(k, t) for k, t in topo.incident(r) if k != i]
    if len(other) != 1:
        return False
    P = topo.P
    a = P[int(topo.end_ids(*other[0])[-1])]
    b = P[int(topo.end_ids(i, s)[-1])]
    reach = float(np.max(np.linalg.norm(P[topo.regions[r]] - a, axis=1)))
    return float(np.linalg.norm(b - a)) < 0.5 * reach


def _linked_junction(topo: Topology, sc: Scales, i: int, r: int, own: int, tip: np.ndarray, gap: float,
                     tree, ids: np.ndarray, lab: np.ndarray) -> int:
    """The junction a stub (chain ``i`` from junction ``own`` to the free end ``r`` without tip
    points) is a link to: the nearest region point of another junction within ``gap`` of its
    tip (``tree`` over the junction points ``ids``, labelled ``lab``), when every point of the
    stub lies within ``sc.width`` spacings (under noise, at least ``LINKS.strip_noise`` times
    the noise: the strip a link keeps to its line) of the segment between the two junctions'
    centres (a link runs straight between them) and no other chain links the two already (the
    stub would be a second trace of that link); -1 where there is none.

    Under noise a free end without tip points may be a true tip whose flags the noise took
    (:func:`_no_curve_end`); one whose chain runs straight from its junction to within the gap
    of another junction's region is read as the link between them all the same (since 6
    December 2026: a building's 7 h edge between two corners under noise 0.2 h, whose samples
    but one the two regions took, was pruned and both corners lost)."""
    if not _bare_end(topo, r):
        return -1
    near = np.asarray(tree.query_ball_point(tip, gap), dtype=np.int64)
    near = near[lab[near] != own]
    if not len(near):
        return -1
    P = topo.P
    dn = np.linalg.norm(P[ids[near]] - tip, axis=1)
    t = int(lab[near[np.lexsort((near, dn))[0]]])
    if any(topo.chains[j].ends[1 - q] == t for j, q in topo.incident(own) if j != i):
        return -1  # the two are linked already: the stub is a second trace of that link
    a, b = P[topo.regions[own]].mean(axis=0), P[topo.regions[t]].mean(axis=0)
    u = b - a
    L = float(np.linalg.norm(u))
    if not L > 0:
        return -1
    X = P[topo.chains[i].ids] - a
    along = np.clip(X @ (u / L), 0.0, L)
    off = np.linalg.norm(X - along[:, None] * (u / L), axis=1)
    lim = max(sc.width * float(np.median(sc.h[topo.chains[i].ids])), LINKS.strip_noise * sc.noise)
    return t if bool(np.all(off <= lim)) else -1


def join_facing_tips(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Two free ends facing each other across a small gap are one curve broken by noise: joined.

    Two free-end regions (with their chains' last points) within ``link * REPAIRS.tip_gap``
    median spacings of each other merge (the later into the earlier, pairs in order). Under
    noise they must face each other (:func:`_facing`): the two tips of a fork at a branch's end
    (a twig's tip a few spacings from its sibling's) lie that close too, beside each other
    rather than ahead. On noise-free input the test is not made: two tip regions that close
    there are the two sides of a short twig whose junction the shell test missed, which the
    merge reads right (the twigs kind lost a twig in each of 8 samplings with the test).
    """
    P, regions, v = topo.P, topo.regions, topo.v
    tips, ends = [], []
    for i, c in enumerate(topo.chains):
        if topo.alive[i] and not c.closed:
            for s in (0, 1):
                r = c.ends[s]
                if v[r] == 1:
                    end_pt = c.ids[-1] if s == 1 else c.ids[0]
                    tips.append((r, np.r_[regions[r], end_pt].astype(np.int64)))
                    ends.append((i, s))
    if len(tips) < 2:
        return
    gap_max = prm.link * REPAIRS.tip_gap * sc.hmed
    lines: dict = {}  # the chain ends' lines read by _facing (no chain's points move here)
    # only pairs of tips closer than the threshold can merge: found with a k-d tree, then
    # visited in the same (a, b) order as a double loop over all pairs
    for a, b in close_tip_pairs(P, [ia for _, ia in tips], gap_max):
        ra, ia = tips[a]
        rb, ib = tips[b]
        if ra == rb:
            continue
        D = np.linalg.norm(P[ia][:, None, :] - P[ib][None, :, :], axis=2)
        k = np.unravel_index(np.argmin(D), D.shape)
        if D[k] > gap_max:
            continue
        if not sc.clean and not _facing(topo, sc, ends[a], ends[b], P[ia[k[0]]], P[ib[k[1]]], lines):
            continue
        topo.absorb(rb, ra)
        tips[b] = (ra, ib)


def _facing(topo: Topology, sc: Scales, end_a, end_b, xa, xb, lines: dict) -> bool:
    """Whether the chain ends ``end_a`` and ``end_b`` ((chain, side)) face each other across
    the gap from ``xa`` to ``xb`` (the closest points of their tips): each end's line, pointing
    out of its chain (:func:`_end_line`; ``lines``: those already read, by end, filled here),
    runs within ``REPAIRS.tip_face_cos`` of the way to the other tip. A gap of at most
    ``REPAIRS.tip_touch`` median spacings has no way to read: facing; so is an end too short
    for a line."""
    g = xb - xa
    n = float(np.linalg.norm(g))
    if n <= REPAIRS.tip_touch * sc.hmed:
        return True
    for (i, s), w in ((end_a, g / n), (end_b, -g / n)):
        if (i, s) not in lines:
            lines[i, s] = _end_line(topo.P, sc.h, topo.chains, i, s, sc.noise)
        e0, cc, u, _ = lines[i, s]
        if u is None:
            continue
        out = u if float((e0 - cc) @ u) >= 0 else -u
        if float(out @ w) < REPAIRS.tip_face_cos:
            return False
    return True


def close_tip_pairs(P, tips, r):
    """Pairs ``(a, b)``, ``a < b``, of point sets ``tips[a]``, ``tips[b]`` that may come within
    ``r`` of each other (a superset: the caller checks the exact distance), sorted."""
    from scipy.spatial import cKDTree

    own = np.repeat(np.arange(len(tips)), [len(t) for t in tips])
    pts = P[np.concatenate(tips)] if len(own) else np.zeros((0, P.shape[1]))
    pairs = cKDTree(pts).query_pairs(r * (1 + NUMERIC.rel_loose) + NUMERIC.tiny, output_type="ndarray")
    a, b = own[pairs[:, 0]], own[pairs[:, 1]]
    a, b = np.minimum(a, b), np.maximum(a, b)
    ab = np.unique(np.stack([a[a != b], b[a != b]], axis=1), axis=0)
    return [(int(x), int(y)) for x, y in ab]


def attach_dangling(topo: Topology, sc: Scales, prm: RobustParams, only: set | None = None) -> None:
    """A free end stopping short of another curve is a junction whose link was lost: attached.

    The failure: a T whose stem does not reach the bar (noise or sparse sampling). A free end
    with a point of another chain within ``REPAIRS.attach * link`` spacings (plus the noise gap)
    ahead of it (within 45 degrees of its direction) attaches there: the other chain is split
    at its nearest point, which becomes a new junction region holding the free end's region
    too; near an end of the other chain, the free end joins the region there instead. Tips
    are handled in chain order; each moves at most once.
    """
    chains = topo.chains
    tips = _free_tips(topo, only)
    if not tips:
        return
    owner, _ = topo.owners()
    if not (owner >= 0).any():
        return
    pre = _attach_prefilter(topo, sc, prm, tips, owner)
    for t_, (i, s) in enumerate(tips):
        c = chains[i]
        if not topo.alive[i] or c.closed or topo.v[c.ends[s]] != 1:
            continue
        if not pre.has_cand[t_] and c is pre.tchain[t_]:
            continue
        found = _attach_target(topo, sc, prm, pre, t_, i, s, owner)
        if found is None:
            continue
        q, j = found
        cj = chains[j]
        k = int(np.flatnonzero(cj.ids == q)[0])
        m = len(cj.ids)
        near_end = REPAIRS.attach_end_points
        if not cj.closed and (k < near_end or k > m - 1 - near_end):
            # near an end of the other chain: join its region there
            rr = cj.ends[0 if k < near_end else 1]
            if rr != c.ends[s]:
                topo.absorb(c.ends[s], rr)
            continue
        # split chain j at q: q and its two chain neighbours form the new junction region
        core = topo.split_chain(j, max(k - 1, 0), min(k + 2, m), i, s)
        owner[core] = -1
        if not cj.closed:  # the part after the split is a new chain
            jn = len(chains) - 1
            owner[chains[jn].ids] = jn


def _free_tips(topo: Topology, only: set | None = None) -> list[tuple[int, int]]:
    """The free ends ``(chain, side)`` of the live open chains (their region of valence 1), in
    chain order; with ``only``, those at these regions alone."""
    return [(i, s) for i, c in enumerate(topo.chains) if topo.alive[i] and not c.closed
            for s in (0, 1) if topo.v[c.ends[s]] == 1 and (only is None or c.ends[s] in only)]


def _attach_reach(sc: Scales, prm: RobustParams, h_tip):
    """How far from a tip point :func:`attach_dangling` looks for chain points:
    ``REPAIRS.attach`` links of the spacing ``h_tip`` at the tip (a float or an array) plus
    ``LINKS.gap_noise`` times the noise."""
    return REPAIRS.attach * prm.link * h_tip + LINKS.gap_noise * sc.noise


class _Prefilter(NamedTuple):
    """What :func:`attach_dangling` finds for all tips at once, before any moves."""

    tchain: list  # the chain of each tip then
    tms: list  # the point count of its end portion
    tpts: list  # its region's points and its last chain point
    toff: list  # offsets of tpts, concatenated
    qall: np.ndarray  # chain points near each tip point, concatenated
    qoff: np.ndarray  # their offsets per tip point
    cnt: np.ndarray  # their count per tip point
    has_cand: np.ndarray  # (n_tips,) bool: a point of another chain within reach, ahead


def _attach_prefilter(topo, sc, prm, tips, owner) -> _Prefilter:
    """The candidates of every tip in one threaded query (a test a little looser than the exact
    one of :func:`_attach_target`, with the owners as they are now: a tip whose chain is
    unchanged when its turn comes has no more candidates then).

    A tip still to be handled has the chain end and region it had here (a move or a split
    changes only the valence-1 ends it involves), and its chain's points unless that chain was
    split meanwhile (then its end is redone in :func:`_attach_target`).
    """
    P, h = topo.P, sc.h
    tchain = [topo.chains[i] for i, _ in tips]
    tids, tpts = (list(x) for x in zip(*(_tip(topo, sc, prm, i, s) for i, s in tips)))
    tms = end_counts(P, h, tids, REPAIRS.attach_span).tolist()
    reach_of = _attach_reach(sc, prm, h[[int(ids[-1]) for ids in tids]])
    # chain points within reach of each tip point (one threaded query of the tree over all
    # points, built for the k-NN query: points of no chain are left out by their owner -1)
    allp = np.concatenate(tpts)
    with _sigint.held():
        near = sc.tree.query_ball_point(P[allp], np.repeat(reach_of, [len(x) for x in tpts]), workers=query_threads())
    cnt = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(near))
    qall = np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=int(cnt.sum()))
    qoff = np.r_[0, np.cumsum(cnt)]
    toff = np.r_[0, np.cumsum([len(x) for x in tpts])].tolist()
    tip_of = np.repeat(np.repeat(np.arange(len(tips)), np.diff(toff)), cnt)  # the tip of each pair
    e_t = np.array([int(ids[-1]) for ids in tids], dtype=np.int64)
    # (the tip direction as in _attach_target: from the first point of end_portion's end
    # piece, ids[-m], to the tip)
    b_t = np.array([int(ids[-m]) if m <= len(ids) else int(ids[0]) for ids, m in zip(tids, tms)], dtype=np.int64)
    u_t = P[e_t] - P[b_t]
    u_t /= np.maximum(np.sqrt((u_t * u_t).sum(axis=1)), NUMERIC.tiny)[:, None]
    jq = owner[qall]
    vq_all = P[qall] - P[e_t[tip_of]]
    cand = ((jq >= 0) & (jq != np.array([i for i, _ in tips], dtype=np.int64)[tip_of])
            & ((vq_all * u_t[tip_of]).sum(axis=1)
               >= (REPAIRS.attach_cos - NUMERIC.rel_loose) * np.sqrt((vq_all * vq_all).sum(axis=1))))
    has_cand = np.bincount(tip_of[cand], minlength=len(tips)) > 0
    return _Prefilter(tchain, tms, tpts, toff, qall, qoff, cnt, has_cand)


def _tip(topo: Topology, sc: Scales, prm: RobustParams, i: int, s: int) -> tuple[np.ndarray, np.ndarray]:
    """Free end ``s`` of chain ``i`` as the attach test reads it: the ids running to its tip
    (:func:`_tip_path`) and the points whose neighbours are its candidates (its region's and
    the chain's last point), both (n,) int64."""
    ids, region = topo.end_ids(i, s), topo.regions[topo.chains[i].ends[s]]
    return _tip_path(topo.P, sc.h, _tip_reach(sc, prm), ids, region), np.r_[region, ids[-1]].astype(np.int64)


def _tip_reach(sc: Scales, prm: RobustParams) -> float | None:
    """How far past its chain's last point a free end's region must reach for its far end to be
    the tip (:func:`_tip_path`): a link, on noise-free input; under noise never (an end region
    there is the noise's scatter as often as the curve)."""
    return prm.link if sc.clean else None


def _tip_path(P: np.ndarray, h: np.ndarray, past: float | None, ids: np.ndarray, region: np.ndarray) -> np.ndarray:
    """The way to a free end's tip, as the attach test reads it: the chain's ids ``ids`` (n,)
    (running towards its end) and, where its end region ``region`` (r,) reaches more than
    ``past`` spacings (``h`` at the chain's last point) beyond that last point, then the
    region's points by distance from it (ties: lowest id): its farthest is the tip. On
    noise-free input the samples of a curve that stops short of another can be flagged as
    its end region over several spacings (a neurite's stem, a sketched stroke): read from the
    chain's last point, the curve it stops at may lie over 45 degrees off its direction.

    Returns
    -------
    (n,) or (n + r,) ndarray of int64
    """
    if past is None or not len(region):
        return ids
    d = ((P[region] - P[ids[-1]]) ** 2).sum(axis=1)
    if d.max() <= (past * h[ids[-1]]) ** 2:
        return ids
    return np.r_[ids, region[np.lexsort((region, d))]].astype(np.int64)


def _attach_target(topo, sc, prm, pre: _Prefilter, t_, i, s, owner):
    """Where tip ``t_`` (end ``s`` of chain ``i``) attaches: ``(point, chain)``, or None.

    The chain points of other live chains within reach of the tip, ahead of it (within 45
    degrees of its direction): the nearest (then lowest id).
    """
    P, h = topo.P, sc.h
    c = topo.chains[i]
    ids, tip_pts = _tip(topo, sc, prm, i, s)
    e = int(ids[-1])
    same = c is pre.tchain[t_]
    E = end_portion(P, h, ids, span=REPAIRS.attach_span, m=pre.tms[t_] if same else None)
    u = E[0] - E[-1]
    nu = np.linalg.norm(u)
    if nu == 0:
        return None
    u = u / nu
    if same:
        a0, a1 = pre.toff[t_], pre.toff[t_ + 1]
        if pre.qoff[a1] == pre.qoff[a0]:
            return None
        q = pre.qall[pre.qoff[a0]:pre.qoff[a1]]
        tp = np.repeat(pre.tpts[t_], pre.cnt[a0:a1])
    else:  # its chain was split meanwhile: queried again
        near_t = sc.tree.query_ball_point(P[tip_pts], _attach_reach(sc, prm, float(h[e])))
        cnt_t = np.fromiter((len(x) for x in near_t), dtype=np.int64, count=len(near_t))
        if not cnt_t.sum():
            return None
        q = np.concatenate([np.asarray(x, dtype=np.int64) for x in near_t])
        tp = np.repeat(tip_pts, cnt_t)
    j = owner[q]
    vq = P[q] - P[e]
    ok = (j >= 0) & (j != i) & ((vq @ u) >= REPAIRS.attach_cos * np.sqrt((vq * vq).sum(axis=1)))
    ok[ok] = [topo.alive[x] for x in j[ok].tolist()]
    if not ok.any():
        return None
    q, j, tp = q[ok], j[ok], tp[ok]
    d = np.sqrt(((P[q] - P[tp]) ** 2).sum(axis=1))
    b = np.lexsort((q, d))[0]
    return int(q[b]), int(j[b])


def prune_spurs(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Short spurs (junction to free end) and small isolated pieces are dropped.

    A chain from a junction to a free end, or between two free ends, whose polyline plus the
    extent of its free-end regions is under ``min_spur`` spacings goes; so does a closed loop
    under twice that. On noise-free input also such a chain from a region of valence 2 to a free
    end without tip points (a stub: a noise-free curve's end is always flagged) joins that
    region, which is a free end again (a whole fork with two short branches in one region: the
    hidden fork of :func:`~.junctions.hidden_fork`); at any noise so too when the stub leaves
    that region beside its other branch (:func:`_stub_beside`: the region holds the curve's end
    beyond both). Under noise a short chain from a junction to
    a free end stays when it is a twig all the same (:func:`_twig`): measured from the junction's
    node it reaches ``min_spur``, it holds ``UNEXPLAINED.min_samples`` samples or more with its
    foot in the junction (as stage 9 counts a branch's path, its explained end included; since
    7 December 2026: a twig of two samples past its junction's region was pruned), and its
    tip lies off the junction's other branches. Up to ``REPAIRS.prune_passes`` passes (a dropped
    spur can leave another).
    """
    P, h, chains, regions = topo.P, sc.h, topo.chains, topo.regions
    # a chain is short only if its polyline is under min_spur (a loop: twice) times its largest
    # spacing: the exact tests below run only for those (the sums here are within rounding)
    length, hmax = chain_lengths(P, h, chains)
    short_loop = (length <= 2 * prm.min_spur * hmax * (1 + NUMERIC.rel)).tolist()
    short = (length <= prm.min_spur * hmax * (1 + NUMERIC.rel)).tolist()
    for _ in range(REPAIRS.prune_passes):
        v = topo.v
        changed = False
        for i, c in enumerate(chains):
            if not topo.alive[i] or not short_loop[i]:
                continue
            if c.closed:
                hl = float(np.median(h[c.ids])) if len(c.ids) else sc.hmed
                if polylen(P[c.ids]) < 2 * prm.min_spur * hl:
                    topo.drop(i)
                    changed = True
                continue
            a, b = c.ends
            free_a, free_b = v[a] == 1, v[b] == 1
            if not (free_a or free_b) or not short[i]:
                continue
            hl = float(np.median(h[c.ids])) if len(c.ids) else sc.hmed
            length = polylen(P[c.ids])
            ext = sum(extent(P, regions[r]) for r in (a, b) if v[r] == 1)
            if length + ext < prm.min_spur * hl and not _twig(topo, sc, prm, i, hl, length + ext):
                if free_a and free_b or v[a] >= NODES.junction_valence or v[b] >= NODES.junction_valence:
                    topo.drop(i)
                    changed = True
                elif ((v[a] == 2 and (_no_curve_end(topo, sc, b) or _stub_beside(topo, i, 0)))
                      or (v[b] == 2 and (_no_curve_end(topo, sc, a) or _stub_beside(topo, i, 1)))):
                    # a stub (see _no_curve_end): its points join the region, which is a free
                    # end again (and may show a hidden fork)
                    topo.absorb_chain(i, a if v[a] == 2 else b)
                    changed = True
        if not changed:
            break


def _twig(topo: Topology, sc: Scales, prm: RobustParams, i: int, hl: float, length: float) -> bool:
    """Whether the chain ``i`` from a junction to a free end, ``length`` long from its first
    point to its tip (polyline and free-end region), is a twig all the same: measured from the
    junction's node (:func:`.nodes.junction_positions`) it reaches ``min_spur`` spacings ``hl``,
    and its tip lies off the junction's other branches (more than ``UNEXPLAINED.explain``
    spacings plus ``UNEXPLAINED.explain_noise`` times the noise from each, and at least
    ``UNEXPLAINED.rise`` times that length: a branch leaves the curves it joins). Under noise the
    junction's region takes in a twig's first samples, so its chain alone is shorter than the twig
    (the kinds' twigs of 3-6 h); samples that noise hangs off a curve near a junction lie within
    the noise band of a branch."""
    P, c, v = topo.P, topo.chains[i], topo.v
    if sc.clean or not len(c.ids):
        return False
    s = 0 if v[c.ends[0]] >= NODES.junction_valence else 1
    if v[c.ends[s]] < NODES.junction_valence or v[c.ends[1 - s]] != 1:
        return False
    j, first = c.ends[s], c.ids[0] if s == 0 else c.ids[-1]
    tip_ids = np.r_[topo.regions[c.ends[1 - s]], c.ids[-1] if s == 0 else c.ids[0]].astype(np.int64)
    # the twig's samples with its foot, the junction's sample it leaves from (as stage 9 counts a
    # branch's path, its explained end included)
    if len(c.ids) + len(topo.regions[c.ends[1 - s]]) + 1 < UNEXPLAINED.min_samples:
        return False  # a stray sample, not a sampled curve
    X, _ = junction_positions(P, sc, prm, [(topo.chains, topo.incident(j), topo.regions[j])])
    reach = length + float(np.linalg.norm(X[0] - P[first]))
    if reach < prm.min_spur * hl:
        return False
    tip = P[tip_ids[np.argmax(np.linalg.norm(P[tip_ids] - X[0], axis=1))]]
    off = np.inf
    for k, side in topo.incident(j):
        ids = topo.end_ids(k, side)[::-1]  # the branch from the node outwards
        if k == i or not len(ids):
            continue
        Y = np.vstack([X[0][None], P[ids]])
        off = min(off, float(segment_distance(tip, Y[:-1], Y[1:]).min()))
    return leaves(off, reach, hl, sc.noise)


def cross_pass_regions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """A region of valence 2 or more that another chain passes through is a crossing: that chain joins it.

    The failure: where two curves cross, the chains ran through the crossing along one curve,
    or turned there from one curve onto the other (a street grid's crossings 4 h apart under
    noise), so the crossing's region holds only two chain ends (valence 2) and would be joined
    through as a bend of one curve. Likewise a junction's region (valence 3 or more) that a
    chain runs through without ending there: a building's roof apex of five edges whose two
    collinear ones were traced as one chain past the region of the other three (real-dev
    bld_zurich_1c91dd3a at noise 0.2 h, 8 December 2026), unless the chain's parts would run
    beside a chain of the junction to the same region (the passing chain ends where one of
    the junction's chains ends: it ran along that chain). A point of another chain linked to a
    point of the region, at least ``REPAIRS.attach_end_points`` points from that chain's ends, is
    a crossing when the ways out are as many branches: the region's chains (to the mean of each chain's
    last ``REPAIRS.attach_span`` spacings) and the other chain's two sides (to the mean of its
    points within ``REPAIRS.attach_span`` spacings on that side, at least one), each from the
    point halfway between the region's centroid and the chain point, lie more than 45 degrees
    apart, every pair (cosine under ``REPAIRS.attach_cos``). Closed chains are left as they are.
    The nearest such point to the centroid and its two chain neighbours then join the region,
    the chain split there (:meth:`.topology.Topology.cross`). A curve passing beside a bend
    runs along one of its chains: two ways out lie together.
    """
    P, h, chains = topo.P, sc.h, topo.chains
    rs = np.flatnonzero(topo.v >= 2).tolist()
    if not rs:
        return
    owner, place = topo.owners()
    near_end = REPAIRS.attach_end_points
    span = REPAIRS.attach_span

    def unit(v):
        n = float(np.linalg.norm(v))
        return v / n if n > 0 else None

    for r in rs:
        R = topo.regions[r]
        inc = sorted(set(topo.incident(r)))
        own = sorted({i for i, _ in inc})
        if not len(R) or len(inc) != topo.v[r] or len(own) != len(inc):
            continue  # (a chain with both ends here, a loop: left as it is)
        nb = np.unique(csr_edges(sc.indptr, sc.indices, R)[1])
        k_of = owner[nb]
        cand = nb[(k_of >= 0) & ~np.isin(k_of, own)]
        far = {topo.chains[i].ends[1 - s] for i, s in inc}  # where the junction's chains lead
        if not len(cand):
            continue
        cen = P[R].mean(axis=0)
        ends = [end_portion(P, h, topo.end_ids(i, s), span=span).mean(axis=0) for i, s in inc]
        dist = np.sqrt(((P[cand] - cen) ** 2).sum(axis=1))
        for q in cand[np.lexsort((cand, dist))].tolist():
            k = int(owner[q])
            c = chains[k]
            m, a = len(c.ids), int(place[q])
            if c.closed or not near_end <= a <= m - 1 - near_end:
                continue
            if not _may_cross(topo, r, c, far):
                continue
            arc = np.r_[0.0, np.cumsum(step_lengths(P, c.ids)[:-1])]
            reach = span * h[q]
            b0 = min(int(np.searchsorted(arc, arc[a] - reach, side="left")), a - 1)  # (a sample at least)
            b1 = max(int(np.searchsorted(arc, arc[a] + reach, side="right")), a + 2)
            at = (cen + P[q]) / 2  # (the crossing: between the region and the chain)
            U = [unit(x - at) for x in ends + [P[c.ids[b0:a]].mean(axis=0), P[c.ids[a + 1:b1]].mean(axis=0)]]
            if any(u is None for u in U):
                continue
            U = np.array(U)
            cos = U @ U.T
            if (cos[np.triu_indices(len(U), 1)] < REPAIRS.attach_cos).all():
                lo, hi = a - 1, a + 2
                owner[c.ids[lo:hi]] = -1
                topo.cross(r, k, lo, hi)
                kn = len(chains) - 1  # the part after the split is a new chain
                owner[chains[kn].ids] = kn
                place[chains[kn].ids] = np.arange(len(chains[kn].ids))
                break


def _may_cross(topo: Topology, r: int, c: Chain, far: set) -> bool:
    """Whether chain ``c`` may cross region ``r`` (:func:`cross_pass_regions`): a region of
    valence 2 always; a junction's only when ``c`` ends at none of the regions ``far`` its chains
    lead to (else split, one part would run beside the junction's chain to that region)."""
    return topo.v[r] == 2 or not far.intersection(c.ends)


def join_through_pass_regions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Chains are joined through every region of valence 2 (no node there), in region order.

    A region passed through by one curve is no node: its two chain ends become one curve (a
    chain joined to itself, a closed loop). Except where a short free branch hides in the
    region (a fork passed through by one curve in a sparse place,
    :func:`~.junctions.swallowed_branches`): the region stays a junction. The free ends with
    one of the joined regions' points within their attach reach (:func:`_tips_near`) are then
    tried again by :func:`attach_dangling`, which takes chain points only: a T's stem that
    stopped short of its bar where the bar's samples were a pass region's (real-dev
    nrn_Image001-005-01 at noise 0.2 h, 7 December 2026: 0.732 -> 0.857). It runs again last
    (:data:`ORDER`): the last :func:`absorb_short_loops` can leave a region of valence 2 (a spike
    of a traced curve, its tip merged into the junction at its foot by :func:`tips_to_junctions`,
    a loop that only then is short), which would otherwise be placed as a node of valence 2.
    """
    P = topo.P
    joined = []
    for r in np.flatnonzero(topo.v == 2).tolist():
        inc = sorted(set(topo.incident(r)))
        (i, _), (j, _) = inc
        if i != j and len(topo.regions[r]) >= NODES.swallow_min:
            X, maybe = junction_positions(P, sc, prm, [(topo.chains, inc, topo.regions[r])])
            if maybe[0] and swallowed_branches(P, sc, prm, topo.chains, inc, topo.regions[r], X[0]):
                continue
        joined.append(topo.regions[r])
        topo.join_through(r, inc)
    # a free end that stopped short of a pass region found no chain point ahead there when
    # attach_dangling ran (region points are no chain's): tried again, now that they are
    near = _tips_near(topo, sc, prm, np.concatenate(joined)) if joined else set()
    if near:
        attach_dangling(topo, sc, prm, only=near)


def _tips_near(topo: Topology, sc: Scales, prm: RobustParams, pts: np.ndarray) -> set:
    """The free-end regions with a point of ``pts`` (m,) within the attach reach of one of
    their tip points (:func:`_tip`: the region's points and the chain's last point; the reach
    :func:`_attach_reach` at that last point)."""
    from scipy.spatial import cKDTree

    ends = [(topo.chains[i].ends[s], int(topo.end_ids(i, s)[-1])) for i, s in _free_tips(topo)]
    if not ends or not len(pts):
        return set()
    tp = [np.r_[topo.regions[r], e].astype(np.int64) for r, e in ends]
    reach = _attach_reach(sc, prm, sc.h[[e for _, e in ends]])
    found = cKDTree(topo.P[pts]).query_ball_point(topo.P[np.concatenate(tp)], np.repeat(reach, [len(x) for x in tp]))
    hit = np.fromiter((len(x) > 0 for x in found), dtype=bool, count=len(found))
    per = np.add.reduceat(hit, np.r_[0, np.cumsum([len(x) for x in tp])[:-1]])
    return {r for (r, _), k in zip(ends, per.tolist()) if k}


def merge_close_junctions(topo: Topology, sc: Scales, prm: RobustParams) -> None:
    """Junction b merges into junction a when a chain a-b is short and b's other branches aim at a.

    The failure: two branches of one junction ran together for a while (strokes drawn into a
    hub), so the junction was seen twice. "Short": at most ``REPAIRS.merge_len`` spacings
    (median spacings for a chain sampled ``REPAIRS.dense`` times as densely: two strokes run
    together). "Aim at a": a's node (least-squares intersection) lies within
    ``max(width * h, LINKS.strip_noise * noise)`` of the line fitted on each of b's other
    branches, or within ``REPAIRS.merge_tan`` times its distance from the branch end (10
    degrees: a fan of curved strokes converging on one node parts a few degrees apart;
    ``REPAIRS.merge_tan_hub``, 20 degrees, for a doubled chain into a junction of
    ``REPAIRS.hub_valence`` curves or more). The chain between them joins the merged region.
    """
    P, h, chains, regions = topo.P, sc.h, topo.chains, topo.regions
    v = topo.v
    noise = sc.noise
    # lengths of all chains at once (the ids do not change below); a chain longer than
    # merge_len times its largest spacing is longer than merge_len times its median one
    lens = [len(c.ids) for c in chains]
    flat = np.concatenate([c.ids for c in chains]).astype(np.int64) if chains else np.zeros(0, np.int64)
    step = step_lengths(P, flat)[:-1]
    cum = np.r_[0.0, np.cumsum(step)]
    off = np.r_[0, np.cumsum(lens)].astype(np.int64)
    hmax = np.zeros(len(chains))
    nz = np.flatnonzero(np.asarray(lens) > 0)
    if len(nz):
        hmax[nz] = np.maximum.reduceat(h[flat], off[nz])
    # (two strokes running together are sampled twice as densely: "short" is measured in the
    # median spacing where the chain is sampled REPAIRS.dense times as densely or more, else
    # in its own; such a doubled chain into a hub gets the wider aim REPAIRS.merge_tan_hub)
    hglob = sc.hmed
    jv = NODES.junction_valence
    # the short chains between two junctions (a merge only maps one junction onto another and
    # raises its valence, so no other chain can become one below)
    cand = []
    doubled = {}
    for ci in range(len(chains)):
        c = chains[ci]
        if not topo.alive[ci] or c.closed:
            continue
        a, b = c.ends
        if a == b or v[a] < jv or v[b] < jv:
            continue
        # polyline length: the steps inside the chain (not the one joining it to the next)
        length = cum[off[ci + 1] - 1] - cum[off[ci]] if lens[ci] > 1 else 0.0
        if length > REPAIRS.merge_len * max(hmax[ci], hglob) * (1 + NUMERIC.rel):
            continue
        hl = float(np.median(h[c.ids])) if len(c.ids) else hglob
        dbl = hl * REPAIRS.dense < hglob
        if polylen(P[c.ids]) > REPAIRS.merge_len * (hglob if dbl else hl):
            continue
        cand.append(ci)
        doubled[ci] = dbl

    # the nodes of their junctions in one batch; a merge changes only its two junctions
    need = sorted({r for ci in cand for r in chains[ci].ends})
    pos = {}
    if need:
        X, _ = junction_positions(P, sc, prm, [(chains, topo.incident(r), regions[r]) for r in need])
        pos = dict(zip(need, X))
    lines: dict = {}  # the branch ends' lines, read once each
    for ci in cand:
        c = chains[ci]
        a, b = c.ends
        if not topo.alive[ci] or a == b or v[a] < jv or v[b] < jv:
            continue
        for x_r, y_r in ((a, b), (b, a)):
            inc_x = topo.incident(x_r)
            inc_y = [(i, s) for i, s in topo.incident(y_r) if i != ci]
            if len(inc_y) < 2:
                continue
            if x_r not in pos:
                pos[x_r] = junction(P, sc, prm, chains, inc_x, regions[x_r])
            xpos = pos[x_r]
            if not _aims_at(P, h, sc, chains, inc_y, xpos, v[x_r] >= REPAIRS.hub_valence and doubled[ci], noise,
                            lines):
                continue
            # merge y into x, the short chain included
            pos.pop(x_r, None)
            pos.pop(y_r, None)
            topo.drop(ci)
            topo.absorb(y_r, x_r)
            topo.regions[x_r] = np.r_[topo.regions[x_r], c.ids].astype(np.int64)
            break


def _end_line(P, h, chains, i, s, noise):
    """The line of the branch end ``(i, s)`` as :func:`_aims_at` reads it: the end's point, the
    line's centre and direction (None: under two points) and the spacing at the end."""
    ids = chains[i].ids if s == 1 else chains[i].ids[::-1]
    hl = float(h[ids[-1]])
    E = end_portion(P, h, np.asarray(ids), span=NODES.fit_span + NODES.fit_noise * noise / hl)
    cc, u = fit_line(E)
    return E[0], cc, u, hl


def _aims_at(P, h, sc, chains, inc, xpos, hub, noise, lines=None) -> bool:
    """True when every branch ``inc`` (chain, side) aims at ``xpos`` (see merge_close_junctions).

    ``lines``: a dict of the branch ends' lines (:func:`_end_line`) already read, filled here
    (a chain's points do not change while the junctions merge)."""
    lines = {} if lines is None else lines
    for i, s in inc:
        if (i, s) not in lines:
            lines[i, s] = _end_line(P, h, chains, i, s, noise)
        e0, cc, u, hl = lines[i, s]
        if u is None:
            return False
        r = xpos - cc
        d = np.sqrt(max(float(r @ r) - float(r @ u) ** 2, 0.0))
        # within the strip, or within the aim angle as seen from the branch end (a fan of
        # curves converging on one node parts a few degrees apart)
        tan = REPAIRS.merge_tan_hub if hub else REPAIRS.merge_tan
        lim = max(sc.width * hl, LINKS.strip_noise * noise, tan * float(np.linalg.norm(xpos - e0)))
        if d > lim or float((e0 - cc) @ u) * float((xpos - cc) @ u) < 0:
            return False
    return True


#: The repairs in the order :func:`run_repairs` applies them.
ORDER = (
    split_multiple_junctions,  # (first: the row's region as the shell test left it)
    split_branched_chains,  # (then the rows its split chains reached, read again)
    merge_near_pass_through,
    absorb_short_loops,
    absorb_orphans,
    read_end_junctions,  # (after the orphans: a twig's tip can be one)
    tips_to_junctions,
    join_facing_tips,
    attach_dangling,
    prune_spurs,
    split_tails,  # (a free end the pruning left: a chain may run on past it)
    merge_twin_chains,  # (after the tips joined junctions: a tip's chain can become a twin)
    cross_pass_regions,  # (before the valence-2 regions are joined through)
    join_through_pass_regions,
    split_rows_again,  # (the rows again, their ends cleaned: a spur pruned, a tip joined)
    split_paired_junctions,
    merge_close_junctions,  # (after the split: it merges back what it takes for one junction)
    absorb_short_loops,  # a short chain between two merged junctions is now a short loop
    join_through_pass_regions,  # (a region whose loop it absorbed may be a pass now)
)


def run_repairs(topo: Topology, sc: Scales, prm: RobustParams) -> Topology:
    """Apply every repair of :data:`ORDER` to ``topo`` (changed in place) and return it."""
    for repair in ORDER:
        repair(topo, sc, prm)
    return topo
