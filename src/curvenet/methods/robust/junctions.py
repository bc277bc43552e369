"""Stage 4: which points are junction points (the shell test), and junction regions.

Around each point the points reached through the linked graph within a geodesic radius
``shell_outer * (h + SHELL.widen * noise)`` form, beyond ``shell_inner``, a shell; its connected
groups are counted (:func:`shell_group_counts`): 1 at a free end, 2 on a curve, 3 or more near
a junction. Points not in 2 groups, joined by short links, form regions (:func:`junction_regions`);
a region too large for one junction is re-tested on smaller shells, scale by scale, and split
(:func:`split_large_regions`); junctions a few spacings apart, still one region at the finest
scale, are separated on a smaller shell (:func:`separate_close_junctions`). After the chains are known, a junction region may still hide a
whole short branch (:func:`swallowed_branches`) and a free end's region a fork
(:func:`fork_possible`, :func:`hidden_fork`): the other places that decide junctions.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.sparse.csgraph import dijkstra

from . import kernels as _k
from .chains import end_portion, fit_line, points_apart, polylen
from .frames import Frames, Neighbours
from .graph import Graph, components, csr_edges, edge_lengths
from .params import RobustParams, Scales
from .thresholds import BRANCHED, LINKS, NODES, NOISE, NUMERIC, SHELL, SPLIT

__all__ = ["Regions", "junction_regions", "shell_group_counts", "split_large_regions", "separate_close_junctions",
           "fork_possible",
           "hidden_fork", "branches_meeting", "swallowed_branches", "region_paths"]


class Regions(NamedTuple):
    """The junction test's result.

    Attributes
    ----------
    groups : (N,) ndarray of int32
        Shell group count of every point.
    flagged : (N,) ndarray of bool
        Points in a region (not in 2 groups, after splitting large regions).
    reg : (N,) ndarray of int64
        Region of each flagged point (-1 elsewhere), ids following the lowest point id.
    n_reg : int
    close : (n_reg,) ndarray of bool
        The regions separated as junctions a few spacings apart
        (:func:`separate_close_junctions`): a single point between two of them is a segment.
    """

    groups: np.ndarray
    flagged: np.ndarray
    reg: np.ndarray
    n_reg: int
    close: np.ndarray


def junction_regions(P: np.ndarray, nb: Neighbours, fr: Frames, graph: Graph, prm: RobustParams) -> Regions:
    """Stage 4: the shell test on every point, and the regions of the points not on one curve.

    Noise blurs a junction over a few sigma: the shell grows with the noise scale. Regions are
    the flagged points joined by plain short links (kNN pairs within ``link * h``, any
    direction); two junctions closer than about two shell radii flag one region, so large
    ones are re-tested (:func:`split_large_regions`).
    """
    N = len(P)
    hs = nb.h + SHELL.widen * (NOISE.scale * fr.sigma)
    groups = shell_group_counts(P, hs, graph.indptr, graph.indices, prm.shell_inner, prm.shell_outer,
                                order=np.arange(N, dtype=np.int64))
    flagged = groups != 2
    ka, kb = _k.short_links(P, nb.h, nb.idx, float(prm.link))
    # (the splits read low noise as none; the finer multi-scale separation only noise-free
    # input: see NOISE.low)
    flagged, reg, n_reg = split_large_regions(P, hs, graph.indptr, graph.indices, flagged, ka, kb, prm,
                                              noisy=not fr.low, noise=NOISE.scale * fr.sigma)
    flagged, reg, n_reg, close = separate_close_junctions(P, hs, graph.indptr, graph.indices, flagged, reg, n_reg,
                                                          ka, kb, prm, noisy=not fr.clean, low=fr.low,
                                                          noise=NOISE.scale * fr.sigma)
    return Regions(groups, flagged, reg, n_reg, close)


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


def split_large_regions(P, hs, indptr, indices, flagged, ka, kb, prm: RobustParams, noisy: bool,
                        noise: float = 0.0):
    """The junction flags, with regions too large for one junction split in two or more.

    A region of radius over ``SPLIT.radius`` outer shell radii is re-tested on a shell
    ``SPLIT.scales[0]`` times the size, and a region still too large at that scale at the next
    scale, and so on (junctions 4-5h apart: a facade, a building's notches). The split is kept
    when it gives two or more sub-regions (``SPLIT.min_points`` points or more,
    ``SPLIT.fine_min_points`` after the first scale; one of them in 3 or more groups), each
    pair joined by at most one chain of the freed points (linked graph), no freed chain
    touching three, at least one joining two, and the joined sub-regions over ``SPLIT.sep``
    fine outer radii apart: two junctions and the
    short segment between them. Two chains between the same two (a crossing seen in two halves
    by the smaller shell) keep the region whole unless the two are apart (some point of one over
    ``BRANCHED.twin_apart`` spacings of the re-test from the other: two sides of a cell of the
    network, a window or a street block 4-5 h wide, whose corners a fine shell sees as two
    junctions joined twice; street grids drawn at random, clean, 0.930 -> 1.000). Under noise (``noisy``), at the first scale
    only, a sub-region with a free-end point (1 group) counts too when another has a junction
    point: a junction and the tip of a branch shorter than the widened shell, joined by the
    branch. On noise-free and low-noise input (not ``noisy``) a split, once made, keeps every
    sub-region with a junction point, the smaller ones too: a facade's rail with verticals 4-5 h
    apart is one region at the first scales, and at the finest the junctions along it read as
    sub-regions of 1-3 points; those under ``SPLIT.fine_min_points`` were freed, the rail's
    chain ran through them and they were lost (:mod:`curvenet.synth.families`, 16 facade
    ladders, clean: curve F1 0.857 -> 0.992, exact 7 -> 13). Under noise a sub-region of a point or two may be
    the noise's: they are freed as before.

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
    prm : RobustParams
        ``shell_inner``, ``shell_outer``.
    noisy : bool
        The input is noisy.
    noise : float
        The noise scale (absolute units): a scale after the first re-tests only the regions
        whose fine inner shell radius is over ``SPLIT.fine_noise`` times it (a finer shell
        inside the noise's blur would split one junction).

    Returns
    -------
    flagged : (N,) bool ndarray
        The flags with the split regions' freed points cleared.
    reg : (N,) int ndarray
        Region of each flagged point (-1 elsewhere), see :func:`components`.
    n_reg : int
    """
    reg, n_reg = components(len(P), ka, kb, flagged)
    coarse = 1.0
    for k, fine in enumerate(SPLIT.scales):
        # the tip rule (noisy) at the first re-test only: it is there for branches shorter than
        # the widened shell, which that re-test already sees; at finer scales a noise blob
        # would pass for a tip
        flagged, reg, n_reg = _split_pass(P, hs, indptr, indices, flagged, reg, n_reg, ka, kb, prm,
                                          noisy and k == 0, coarse, fine,
                                          SPLIT.min_points if k == 0 else SPLIT.fine_min_points,
                                          0.0 if k == 0 else SPLIT.fine_noise * noise, goes_on=not noisy)
        coarse = fine
    return flagged, reg, n_reg


def _split_pass(P, hs, indptr, indices, flagged, reg, n_reg, ka, kb, prm: RobustParams, noisy: bool,
                coarse: float, fine: float, min_points: int, clear: float, goes_on: bool = False):
    """One scale of :func:`split_large_regions`: the regions too large for one junction at shell
    scale ``coarse`` re-tested at scale ``fine`` (both in shell radii), split when that shows
    separate junctions (sub-regions of ``min_points`` points or more); only regions whose
    fine inner shell radius exceeds ``clear`` are re-tested; ``goes_on`` (noise-free or
    low-noise input): the fine test's groups go on past the shell, and a split keeps every
    sub-region with a junction point. Returns ``flagged, reg, n_reg`` (the inputs when nothing
    splits)."""
    N = len(P)
    if n_reg == 0:
        return flagged, reg, n_reg
    ids = np.flatnonzero(flagged)
    r = reg[ids]
    rad, hmean = _region_sizes(P, hs, ids, r, n_reg)
    big = (rad > SPLIT.radius * coarse * prm.shell_outer * hmean) & (fine * prm.shell_inner * hmean > clear)
    if not big.any():
        return flagged, reg, n_reg
    ft = _fine_test(P, hs, indptr, indices, flagged, ka, kb, ids[big[r]], prm, fine, goes_on=goes_on)
    # the points of each big region, grouped (one sort, not one pass per region)
    bsel = big[r]
    bi, br = ids[bsel], r[bsel]
    o = np.argsort(br, kind="stable")
    bi, br = bi[o], br[o]
    bcut = np.flatnonzero(np.r_[True, br[1:] != br[:-1], True])
    out = flagged.copy()
    for g0, g1 in zip(bcut[:-1], bcut[1:]):
        pts = bi[g0:g1]
        kept = pts[ft.nf[pts]]
        good = _split_of(P, ft, pts, kept, SPLIT.sep * fine * prm.shell_outer * hmean[br[g0]], noisy, min_points,
                         keep_every=goes_on, apart=BRANCHED.twin_apart * hmean[br[g0]])
        if good is not None:
            out[pts] = False
            out[kept[np.isin(ft.reg2[kept], good)]] = True
    if np.array_equal(out, flagged):
        return flagged, reg, n_reg
    return (out, *components(N, ka, kb, out))


def separate_close_junctions(P, hs, indptr, indices, flagged, reg, n_reg, ka, kb, prm: RobustParams,
                             noisy: bool = False, low: bool = True, noise: float = 0.0):
    """The junction flags, with regions holding several junctions a few spacings apart separated.

    Junctions 3-5 h apart (a facade's ladder, a comb, short links of a street grid) lie
    within one another's shells even at the finest scale of :func:`split_large_regions`, and
    the short links (``link`` h) join their flagged points into one region. A region still
    wider than one junction (radius over ``SPLIT.close_radius`` outer shell radii) is re-tested
    at the scales ``SPLIT.close_scales`` on each of their shells (a multi-scale
    test: one scale alone is not enough, on samples ``h`` apart a shell a few spacings wide
    misses a junction's own point at one scale and joins two junctions at the next). Its
    points flagged at a scale, joined only by links of at most ``SPLIT.close_link`` spacings
    (the next sample along a curve: a freed point between two junctions parts them), form
    candidate junctions, kept when of ``SPLIT.fine_min_points`` points or more with a junction
    point (3 or more groups). They must read as separate junctions joined by segments
    (:func:`_candidates_per_region`): the region's freed points, in chains, join at most two
    candidates each and never the same two twice; two joined candidates lie over
    ``SPLIT.close_sep`` spacings apart; and the branch count is stable: the sum of the
    candidates' group counts, less two per candidate after the first (the ends of the segments
    joining them), is at most the number of chains leaving the region (a junction seen in parts counts its branches twice). The scale giving
    the most candidates, two or more (ties: the first listed), resolves the region: its
    candidates replace it, its other points are freed (the short chains between the
    junctions). (Until 6 December 2026 a chain of those freed points touching four or more of
    the candidates kept and the branches leaving stayed a region, holding junctions the scale
    missed; since a split of :func:`split_large_regions` keeps every junction its scale sees,
    that rule changed no network for the better: 928-run harness without it 4 better, 0 worse,
    CASSIE 320 runs 1 worse, a family of 8 jittered ladders 0.971 -> 1.000.)

    Under noise above ``NOISE.low`` (where the spanning tree no longer reads pairs of junctions,
    so a region this test leaves whole stays one node) the same test runs with two guards, as
    the region splits have them: a scale re-tests only the regions whose inner shell radius
    there is over ``SPLIT.fine_noise`` noise scales (a finer shell inside the noise's blur splits
    one junction: the benchmark's crossings and fans under noise 0.2 h and 0.3 h lost their
    exact topology without it), and a scale resolves a region only when each of its candidates
    has the size of one junction (radius at most ``SPLIT.close_radius`` outer radii of that
    scale): a candidate holding two junctions would replace them by one node, where leaving the
    region whole lets the later repairs part it. Low noise is left as it is (the spanning tree
    reads its pairs as on noise-free input).

    Parameters
    ----------
    P : (N, d) ndarray
    hs : (N,) ndarray
        Spacing of the shell test (widened for noise).
    indptr, indices : ndarray
        CSR adjacency of the linked graph.
    flagged : (N,) bool ndarray
        Region points (after :func:`split_large_regions`).
    reg : (N,) int ndarray
        Their regions (-1 elsewhere).
    n_reg : int
    ka, kb : (E,) int ndarray
        Short kNN links (the region graph).
    prm : RobustParams
        ``shell_inner``, ``shell_outer``.
    noisy : bool
        The input is not noise-free.
    low : bool
        Its noise is low (``NOISE.low``): with ``noisy``, nothing is separated.
    noise : float
        The noise scale (absolute units), for the guards under noise.

    Returns
    -------
    flagged, reg, n_reg
        As given when nothing is separated.
    close : (n_reg,) bool ndarray
        The regions that are such separated junctions.
    """
    N = len(P)
    none = (flagged, reg, n_reg, np.zeros(n_reg, dtype=bool))
    if n_reg == 0 or (noisy and low) or not SPLIT.close_scales:
        return none
    ids = np.flatnonzero(flagged)
    r = reg[ids]
    rad, hmean = _region_sizes(P, hs, ids, r, n_reg)
    big = rad > SPLIT.close_radius * prm.shell_outer * hmean
    if noisy:  # (no region whose shell is clear of the noise's blur at any scale: nothing to do)
        big &= max(SPLIT.close_scales) * prm.shell_inner * hmean > SPLIT.fine_noise * noise
    if not big.any():
        return none
    sel = big[r]
    sub, rsub = ids[sel], r[sel]  # the big regions' points and their regions
    # the fine links: short links among the big regions' points, at most close_link h long
    inbig = np.zeros(N, dtype=bool)
    inbig[sub] = True
    m = inbig[ka] & inbig[kb]
    fa, fb = ka[m], kb[m]
    near = edge_lengths(P, fa, fb) <= SPLIT.close_link * 0.5 * (hs[fa] + hs[fb])
    fa, fb = fa[near], fb[near]
    del inbig, m, near
    # every scale's candidates; each big region takes the scale with the most (two or more)
    best = np.ones(n_reg, dtype=np.int64)
    pick = np.full(n_reg, -1, dtype=np.int64)
    found = []
    exits = _exits(indptr, indices, flagged, sub, rsub, ka, kb, n_reg)
    for k, sc in enumerate(SPLIT.close_scales):
        # under noise a scale re-tests only the regions whose shell there is clear of the
        # noise's blur: a scale with none is not computed (the same result, sooner)
        clear = big & (sc * prm.shell_inner * hmean > SPLIT.fine_noise * noise) if noisy else big
        if not clear.any():
            found.append((None, None))
            continue
        cand, good, fine = _close_candidates(P, hs, indptr, indices, sub, fa, fb, prm, sc)
        found.append((cand, good))
        n_cand = _candidates_per_region(P, hs, indptr, indices, sub, rsub, cand, good, n_reg)
        # branch count: the candidates' branches, less the two ends of each segment joining
        # them, are at most the region's own
        cs = cand[sub]
        ing = np.isin(cs, good)
        if ing.any():
            # the candidates (region, label), each candidate point's among them
            u, inv = np.unique(np.stack([rsub[ing], cs[ing]], axis=1), axis=0, return_inverse=True)
            inv = inv.ravel()
            vmax = np.zeros(len(u), dtype=np.int64)
            np.maximum.at(vmax, inv, fine[sub][ing])
            tot = np.bincount(u[:, 0], weights=vmax, minlength=n_reg)
            n_cand[(n_cand >= 2) & (tot - 2 * (n_cand - 1) > exits)] = 0
            if noisy:  # (the guards under noise: every candidate one junction's size)
                n_cand[_holding_several(P, hs, sub[ing], inv, u[:, 0], sc, prm)] = 0
        better = clear & (n_cand > best)  # (... and, under noise, a shell clear of its blur)
        best[better] = n_cand[better]
        pick[better] = k
    if not (pick >= 0).any():
        return none
    out = flagged.copy()
    sep = np.zeros(N, dtype=bool)  # points of the separated regions
    for k, (cand, good) in enumerate(found):
        at = ids[pick[r] == k]  # the points of the regions resolved at this scale
        if not len(at):  # (always so for a scale not computed)
            continue
        out[at] = False
        keep = at[np.isin(cand[at], good)]
        out[keep] = True
        sep[keep] = True
    # the separated regions are joined by the fine links only, the others stay as they were;
    # region ids renumbered to follow the lowest point id again
    j = sep[fa] & sep[fb]
    sl, _ = components(N, fa[j], fb[j], sep)
    fl = np.flatnonzero(out)
    key = np.where(sep[fl], n_reg + sl[fl], reg[fl])
    u, first, inv = np.unique(key, return_index=True, return_inverse=True)
    rank = np.empty(len(u), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(u))
    reg2 = np.full(N, -1, dtype=reg.dtype)
    reg2[fl] = rank[inv.ravel()]
    close = np.zeros(len(u), dtype=bool)
    close[reg2[sep]] = True
    return out, reg2, len(u), close


def _candidates_per_region(P, hs, indptr, indices, sub, rs, cand, good, n_reg):
    """How many candidates (labels ``good`` of ``cand``) each region holds, 0 where they do not
    read as separate junctions joined by segments: the region's other points (freed), in
    chains of the linked graph, must join at most two candidates each, no two chains the same
    two, and two candidates joined by a chain must lie over ``SPLIT.close_sep`` spacings
    apart (a crossing or a hub seen in parts by the smaller shell: its parts lie closer, or
    are joined twice)."""
    N = len(cand)
    n_cand = np.zeros(n_reg, dtype=np.int64)
    if not len(good):
        return n_cand
    ing = np.zeros(N, dtype=bool)
    ing[sub] = np.isin(cand[sub], good)
    kept = sub[ing[sub]]
    rk = rs[ing[sub]]
    u = np.unique(np.stack([rk, cand[kept]], axis=1), axis=0)
    np.add.at(n_cand, u[:, 0], 1)
    # the freed points' chains (linked graph) and the candidates each touches
    freed = np.zeros(N, dtype=bool)
    freed[sub] = ~ing[sub]
    fs = np.flatnonzero(freed)
    ea, eb = csr_edges(indptr, indices, fs)
    lab, _ = components(N, ea, eb, freed)
    t = ing[eb]
    touch = np.unique(np.stack([lab[ea[t]], cand[eb[t]]], axis=1), axis=0)
    if not len(touch):
        return n_cand
    region_of = np.full(N, -1, dtype=np.int64)
    region_of[sub] = rs
    creg = region_of[ea[t]]
    creg = np.unique(np.stack([lab[ea[t]], creg], axis=1), axis=0)
    chain_reg = dict(zip(creg[:, 0].tolist(), creg[:, 1].tolist()))
    cut = np.flatnonzero(np.r_[True, touch[1:, 0] != touch[:-1, 0], True])
    pairs: dict[int, list] = {}
    for c0, c1 in zip(cut[:-1], cut[1:]):
        g = chain_reg[int(touch[c0, 0])]
        if c1 - c0 > 2:
            n_cand[g] = 0
        elif c1 - c0 == 2:
            pairs.setdefault(g, []).append((int(touch[c0, 1]), int(touch[c0 + 1, 1])))
    # two candidates joined by a segment: clearly apart (parts of one junction lie closer)
    labs, inv = np.unique(cand[kept], return_inverse=True)
    inv = inv.ravel()
    cnt = np.bincount(inv).astype(float)
    cen = np.stack([np.bincount(inv, weights=P[kept, c]) for c in range(P.shape[1])], axis=1) / cnt[:, None]
    hc = np.bincount(inv, weights=hs[kept]) / cnt
    for g in np.flatnonzero(n_cand).tolist():
        pr = pairs.get(g, [])
        if len(set(pr)) != len(pr):
            n_cand[g] = 0
            continue
        for x, y in pr:
            i, j = np.searchsorted(labs, x), np.searchsorted(labs, y)
            if not np.linalg.norm(cen[i] - cen[j]) > SPLIT.close_sep * 0.5 * (hc[i] + hc[j]):
                n_cand[g] = 0
                break
    return n_cand


def _holding_several(P, hs, pts, inv, regions, sc, prm) -> np.ndarray:
    """The regions (ids, unique) that have a candidate wider than one junction at shell scale
    ``sc``: radius over ``SPLIT.close_radius`` outer radii of that scale. ``pts``: the
    candidates' points, ``inv`` the candidate of each (0 to ``len(regions) - 1``), ``regions``
    the region of each candidate."""
    rad, hmean = _region_sizes(P, hs, pts, inv, len(regions))
    wide = rad > SPLIT.close_radius * sc * prm.shell_outer * hmean
    return np.unique(regions[wide])


def _exits(indptr, indices, flagged, sub, rs, ka, kb, n_reg):
    """How many branches leave each region: its points' linked neighbours outside every region,
    in groups joined by short links (one group per chain leaving it)."""
    N = len(flagged)
    ea, eb = csr_edges(indptr, indices, sub)
    out = ~flagged[eb]
    region_of = np.full(N, -1, dtype=np.int64)
    region_of[sub] = rs
    pts = np.zeros(N, dtype=bool)
    pts[eb[out]] = True
    m = pts[ka] & pts[kb]
    lab, _ = components(N, ka[m], kb[m], pts)
    pairs = np.unique(np.stack([region_of[ea[out]], lab[eb[out]]], axis=1), axis=0)
    return np.bincount(pairs[:, 0], minlength=n_reg)


def _close_candidates(P, hs, indptr, indices, sub, na, nb_, prm, sc):
    """The candidate junctions of :func:`separate_close_junctions` at shell scale ``sc``.

    ``sub``: the points tested; ``na, nb_``: the fine links.
    Returns the label of every point (-1: not flagged at that scale) and the labels of the
    candidates kept: ``SPLIT.fine_min_points`` points or more, one of them in 3 or more groups.
    """
    N = len(P)
    fine = _k.shell_groups(P, hs, indptr, indices, sc * prm.shell_inner, sc * prm.shell_outer, subset=sub,
                           goes_on=True)  # (noise-free input only)
    nf = np.zeros(N, dtype=bool)
    nf[sub] = fine[sub] != 2
    cand, _ = components(N, na, nb_, nf)
    kept = sub[nf[sub]]
    labs, cnt = np.unique(cand[kept], return_counts=True)
    jl = np.unique(cand[kept[fine[kept] >= SHELL.junction_groups]])
    return cand, labs[(cnt >= SPLIT.fine_min_points) & np.isin(labs, jl)], fine


class _Fine(NamedTuple):
    """The fine shell test on the points of the big regions (:func:`split_large_regions`)."""

    nf: np.ndarray  # (N,) bool: flagged after it
    reg2: np.ndarray  # (N,) int: sub-region of each such point
    freed: np.ndarray  # (N,) bool: flagged before, not after
    lab: np.ndarray  # (N,) int: chain of the freed points (linked graph)
    touch: np.ndarray  # (T, 2) int: (chain, sub-region) pairs in contact, sorted by chain
    tcut: np.ndarray  # the rows of each chain in touch
    is_j: np.ndarray  # (N,) bool: in 3 or more fine groups
    is_e: np.ndarray  # (N,) bool: in 1 fine group (a free end)


def _region_sizes(P, hs, ids, r, n_reg):
    """Radius (largest distance from the centroid) and mean shell spacing of every region."""
    dim = P.shape[1]
    cnt = np.bincount(r, minlength=n_reg).astype(float)
    cen = np.stack([np.bincount(r, weights=P[ids, c], minlength=n_reg) for c in range(dim)], axis=1) / cnt[:, None]
    rad = np.zeros(n_reg)
    np.maximum.at(rad, r, np.linalg.norm(P[ids] - cen[r], axis=1))
    return rad, np.bincount(r, weights=hs[ids], minlength=n_reg) / cnt


def _fine_test(P, hs, indptr, indices, flagged, ka, kb, sub, prm, scale, goes_on: bool = False) -> _Fine:
    """The shell test again on the points ``sub``, ``scale`` times the size, and what it frees.

    ``goes_on``: a group that goes on past the shell (a point of it linked to one beyond the
    outer radius) counts as a branch even when it falls short of the shell's middle, so that
    the sampling's phase does not decide on the thin shells of the re-tests; on noise-free and
    low-noise input only (``NOISE.low``), where the links follow the curves (see
    ``kernels/shell.py``)."""
    N = len(P)
    fine = _k.shell_groups(P, hs, indptr, indices, scale * prm.shell_inner, scale * prm.shell_outer,
                           subset=sub, goes_on=goes_on)
    nf = flagged.copy()
    nf[sub] = fine[sub] != 2
    reg2, _ = components(N, ka, kb, nf)
    freed = np.zeros(N, dtype=bool)
    freed[sub] = ~nf[sub]
    # the freed points' chains (linked graph) and the sub-regions each touches (short links)
    fs = np.flatnonzero(freed)
    ea, eb = csr_edges(indptr, indices, fs)
    lab, _ = components(N, ea, eb, freed)
    t = freed[ka] & nf[kb]
    touch = np.unique(np.stack([lab[ka[t]], reg2[kb[t]]], axis=1), axis=0)  # sorted by chain
    tcut = np.searchsorted(touch[:, 0], np.arange(lab.max() + 2))
    is_j = np.zeros(N, dtype=bool)
    is_j[sub] = fine[sub] >= SHELL.junction_groups
    is_e = np.zeros(N, dtype=bool)
    is_e[sub] = fine[sub] == 1
    return _Fine(nf, reg2, freed, lab, touch, tcut, is_j, is_e)


def _split_of(P, ft: _Fine, pts, kept, far, noisy, min_points, keep_every: bool = False, apart: float = 0.0):
    """The sub-regions one big region splits into (their labels in ``ft.reg2``), or None.

    ``pts``: the region's points; ``kept``: those still flagged by the fine test; ``far``: how
    far apart two joined sub-regions' centroids must be; ``apart``: how far apart two chains
    joining the same two must be (:func:`.chains.points_apart`). The split is decided on the
    sub-regions of ``min_points`` points or more; with ``keep_every`` (noise-free or low-noise
    input) the smaller sub-regions with a junction point are kept as well once it is made.
    """
    reg2 = ft.reg2
    labs, c2 = np.unique(reg2[kept], return_counts=True)
    # sub-regions of 2 or more points with a junction point (3 or more groups)
    jun = np.isin(labs, reg2[kept[ft.is_j[kept]]])
    if noisy:
        # under noise also with a free end point, when another is a junction: the shell,
        # widened for noise, can be longer than a short branch, whose points then all
        # look like its free end and join the junction's region (the finer shell sees
        # the branch)
        tip = np.isin(labs, reg2[kept[ft.is_e[kept]]]) & ~jun
        good = labs[(c2 >= min_points) & (jun | tip)]
        ok = len(good) >= 2 and bool(np.isin(good, labs[jun]).any())
    else:
        good = labs[(c2 >= min_points) & jun]
        ok = len(good) >= 2
    if not ok:
        return None
    chains = {}  # the freed points of each chain joining two sub-regions, per pair
    fr = pts[ft.freed[pts]]
    fr = fr[np.argsort(ft.lab[fr], kind="stable")]
    labs_fr, first = np.unique(ft.lab[fr], return_index=True)
    for c, f0, f1 in zip(labs_fr, first, np.r_[first[1:], len(fr)]):
        tb = ft.touch[ft.tcut[c]:ft.tcut[c + 1], 1]
        tb = tb[np.isin(tb, good)]
        if len(tb) > 2:
            return None
        if len(tb) == 2:
            chains.setdefault(tuple(tb), []).append(fr[f0:f1])
    # one chain between two sub-regions and no chain among three: two junctions and
    # the segment between them; two chains between the same two are a crossing split in
    # halves unless they are apart (two sides of a cell: a window, a street block)
    if not chains:
        return None
    for two in chains.values():
        if len(two) > 1 and not all(points_apart(P[a], P[b], apart) for i, a in enumerate(two) for b in two[i + 1:]):
            return None
    for a_, b_ in chains:  # and the two junctions clearly apart
        ca = P[kept[reg2[kept] == a_]].mean(axis=0)
        cb = P[kept[reg2[kept] == b_]].mean(axis=0)
        if not np.linalg.norm(ca - cb) > far:
            return None
    if keep_every:  # (the split made, every junction the scale sees is kept: none is freed)
        return np.union1d(good, labs[jun])
    return good


def fork_possible(P, sc: Scales, prm: RobustParams, ids, rid):
    """False when :func:`hidden_fork` surely finds no fork (no paths needed): a region of
    under 6 points, or all within ``NODES.fork`` shell radii of the entry point (the second tip lies
    that far from the first path, which starts at the entry)."""
    h = sc.h
    if len(rid) < NODES.fork_min_points:
        return False
    hs = float(np.median(h[rid])) + SHELL.widen * sc.noise
    far = np.sqrt(((P[rid] - P[int(ids[-1])]) ** 2).sum(axis=1).max())
    return bool(far > NODES.fork * prm.shell_outer * hs * (1 - NUMERIC.rel))


def hidden_fork(P, sc: Scales, prm: RobustParams, ids, rid, paths):
    """A fork (junction and two free branches) hidden in a free end's region, or None.

    The region is searched from the chain's last point ``ids[-1]``: the geodesically farthest
    point is one tip; a second tip lies over ``NODES.fork`` shell radii away from that path, both
    branches from the point where the paths part are over ``min_spur`` spacings long. Returns
    the chain's extension (ids, outward, up to the fork), the node (least-squares intersection
    of the three branches' lines) and the two branches (ids ordered from the node out).
    ``paths``: the region's :func:`region_paths` from ``ids[-1]``; the caller runs it only for
    the regions that pass :func:`fork_possible`.
    """
    h = sc.h
    hl = float(np.median(h[rid]))
    noise = sc.noise
    hs = hl + SHELL.widen * noise
    S, g, pred = paths
    fin = np.isfinite(g)
    if fin.sum() < NODES.fork_min_points:
        return None
    gg = np.where(fin, g, -1.0)
    t1 = int(np.argmax(gg))
    p1 = _path_to(pred, t1)
    X = P[S]
    d1 = np.min(np.linalg.norm(X[:, None, :] - X[p1][None, :, :], axis=2), axis=1)
    d1[~fin] = -1.0
    t2 = int(np.argmax(d1))
    if d1[t2] <= NODES.fork * prm.shell_outer * hs:
        return None
    p2 = _path_to(pred, t2)
    m = min(len(p1), len(p2))
    k = int(np.flatnonzero(np.r_[p1[:m] != p2[:m], True])[0])  # first index where they differ
    if k == 0:
        return None
    f = k - 1  # the fork point: last common one
    l1, l2 = S[p1[f:]], S[p2[f:]]
    if min(polylen(P[l1]), polylen(P[l2])) < prm.min_spur * hl:
        return None
    stem = np.r_[np.asarray(ids), S[p1[1:f + 1]]]
    anchor = P[S[p1[f]]]
    x = branches_meeting(P, sc, prm, (stem, l1[::-1], l2[::-1]), hl, anchor)
    return S[p1[1:f]], anchor if x is None else x, [l1[1:], l2[1:]]


def branches_meeting(P, sc: Scales, prm: RobustParams, branches, hl: float, anchor):
    """The least-squares meeting point of the lines of ``branches`` (id lists, each running
    towards the junction), each fitted on its end portion over ``NODES.fit_span`` spacings
    plus ``NODES.fit_noise`` noise (:func:`.chains.end_portion`; ``hl`` the local spacing),
    pulled towards ``anchor`` (d,) by ``NODES.anchor_pull`` (which only makes near-parallel
    lines well-posed); a branch of one point gives no line. Returns the (d,) point, or None
    where the system is singular or the point lies over one outer shell radius (widened for
    noise) from ``anchor``. :func:`hidden_fork` places a fork's node so, and
    :func:`.nodes._tail_fork_node` one found on a chain's tail."""
    h, noise = sc.h, sc.noise
    span = NODES.fit_span + NODES.fit_noise * noise / hl
    dim = P.shape[1]
    A = np.zeros((dim, dim))
    bb = np.zeros(dim)
    for br in branches:
        cc, u = fit_line(end_portion(P, h, br, span=span))
        if u is None:
            continue
        M = np.eye(dim) - np.outer(u, u)
        A += M
        bb += M @ cc
    A += NODES.anchor_pull * np.eye(dim)
    bb += NODES.anchor_pull * anchor
    x = np.linalg.solve(A, bb)
    if not np.all(np.isfinite(x)) or np.linalg.norm(x - anchor) > prm.shell_outer * (hl + SHELL.widen * noise):
        return None
    return x


def swallowed_branches(P, sc: Scales, prm: RobustParams, live, inc, rid, x):
    """Free branches wholly inside a junction region, as id lists ordered from node ``x`` out.

    A region point far from the node (over ``NODES.swallow`` shell radii) in a direction no incident
    branch takes is the tip of a branch shorter than the shell radius (a free end in a sparse
    place): the region points along the segment from the node to it, without a gap, form it.
    A branch is also at least ``min_spur`` long in the spacing of the incident branches' end
    portions (as :func:`~.repairs.prune_spurs` measures a spur), not only in the region's: where
    a curve folds back on itself (a traced neurite's spike, out and back) the region's samples
    lie twice over and its spacing is about half the curve's (0.53-0.56 h measured), so a spike
    2.8 h deep passed the shell fraction of the halved spacing as a branch (real-dev
    nrn_ri05_s591, clean: spikes of 2.4 and 2.8 h, 30 nodes for 28; now exact).
    """
    h = sc.h
    if len(rid) < NODES.swallow_min:
        return []
    hl = float(np.median(h[rid]))
    noise = sc.noise
    hs = hl + SHELL.widen * noise
    dirs, ends = [], []
    for ci, s in inc:
        c = live[ci]
        ids = c.ids if s == 1 else c.ids[::-1]
        E = end_portion(P, h, np.asarray(ids), span=NODES.fit_span)
        ends.append(np.asarray(ids)[-len(E):])
        u = E.mean(axis=0) - x
        nu = np.linalg.norm(u)
        if nu > 0:
            dirs.append(u / nu)
    if not dirs:
        return []
    X = P[rid] - x
    d = np.linalg.norm(X, axis=1)
    cosb = (X @ np.asarray(dirs).T).max(axis=1) / np.maximum(d, NUMERIC.tiny)
    h_ends = float(np.median(h[np.concatenate(ends)]))  # the curves' spacing, not the region's
    reach = max(NODES.swallow * prm.shell_outer * hs, prm.min_spur * h_ends)
    cand = np.flatnonzero((d > reach) & (cosb < NODES.swallow_cos))
    if not len(cand):
        return []
    tip = cand[np.lexsort((np.arange(len(cand)), -d[cand]))[0]]
    u = X[tip] / d[tip]
    proj = X @ u
    perp = np.sqrt(np.maximum(d * d - proj * proj, 0.0))
    lim = max(sc.width * hl, LINKS.strip_noise * noise) * NODES.walk_dev
    on = np.flatnonzero((proj > 0) & (proj <= d[tip] * (1 + NUMERIC.rel)) & (perp <= lim))
    on = on[np.argsort(proj[on], kind="stable")]
    steps = np.diff(np.r_[0.0, proj[on]])
    if not len(on) or steps.max() > prm.link * hl + LINKS.gap_noise * noise:
        return []
    return [rid[on]]


def region_paths(P, sc: Scales, items):
    """Dijkstra on the linked graph restricted to each region and its entry point.

    ``items``: ``(rid, entry)`` pairs. All regions run in one multi-source call on the union
    of their (disjoint) subgraphs. Returns, per item, the point ids ``S`` (``S[0] = entry``,
    then the other region points ascending), the geodesic distances from the entry and the
    predecessor of each (local positions in ``S``; -9999 for none).
    """
    from scipy.sparse import csr_matrix
    indptr, indices = (sc.indptr, sc.indices)
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
    w = np.sqrt(((P[U[ea]] - P[U[eb]]) ** 2).sum(axis=1)) + NUMERIC.tiny
    M = csr_matrix((w, (ea, eb)), shape=(len(U), len(U)))
    g, pred, _ = dijkstra(M, directed=False, indices=start, min_only=True, return_predecessors=True)
    pred = np.where(pred >= 0, pred - start[grp], pred)
    return [(S, g[o:o + n], pred[o:o + n]) for S, o, n in zip(Ss, start, sizes)]


def _path_to(pred, j):
    out = [j]
    while pred[out[-1]] >= 0:
        out.append(int(pred[out[-1]]))
    return np.asarray(out[::-1], dtype=np.int64)
