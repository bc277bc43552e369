"""Stage 5: chains, the runs of points between junction regions, ordered along their curve.

The points outside every region fall apart (linked graph) into chains, one per curve segment.
Each is ordered by geodesic distance from one end and given the regions its two ends touch
(:func:`order_chains`); a chain touching no region is a closed loop cut open at its
straightest point or an open piece; links that step over a region between two pieces are left
out before (:func:`part_bypassed`), and a chain that still runs past a region over a long link
is cut there (:func:`_passed_regions`). The geometric helpers of chains (end portions, lengths,
line fits) live here too.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from . import kernels as _k
from .graph import Graph, components, csr_edges, edge_lengths
from .thresholds import CHAINS, ENDS, LAYOUT, NUMERIC

__all__ = ["Chain", "trace_chains", "order_chains", "fit_line", "step_lengths", "polylen", "chain_lengths",
           "extent", "order_between", "end_portion", "end_counts"]


class Chain:
    """A run of points along one curve segment.

    Attributes
    ----------
    ids : (n,) ndarray of int64
        Ordered point ids (internal numbering).
    ends : list of two int
        The regions at its start and end (-1: none). Changed only by :class:`~.topology.Topology`.
    closed : bool
        A closed loop (its ends are then -1 or one region twice).
    """

    __slots__ = ("ids", "ends", "closed")

    def __init__(self, ids, ends, closed=False):
        self.ids = ids
        self.ends = ends
        self.closed = closed


def trace_chains(P: np.ndarray, h: np.ndarray, graph: Graph, flagged: np.ndarray, reg: np.ndarray, n_reg: int,
                 lin: np.ndarray, close: np.ndarray | None = None) -> tuple[list[Chain], list[np.ndarray]]:
    """Stage 5: the chains (points outside every region, split by them) and the regions' points.

    Parameters
    ----------
    P : (N, d) ndarray
    h : (N,) ndarray
    graph : Graph
    flagged : (N,) ndarray of bool
        Region points.
    reg : (N,) ndarray of int64
        Region of each flagged point (-1 elsewhere).
    n_reg : int
    lin : (N,) ndarray
        Linearity (a loop is cut open at its straightest point).
    close : (n_reg,) ndarray of bool, optional
        Regions separated as junctions a few spacings apart (see
        :func:`.junctions.separate_close_junctions`): a chain of a single point between two of
        them is a segment (:func:`_missing_end`).

    Returns
    -------
    chains : list of Chain
        Ordered, with the regions their ends touch.
    regions : list of (m,) ndarray of int64
        The points of each region, ascending.
    """
    chn, n_chn = components(len(P), graph.src, graph.dst, ~flagged)
    chn, n_chn, _ = part_bypassed(P, graph, flagged, reg, chn, n_chn)
    dd = edge_lengths(P, graph.src, graph.dst)
    chains = order_chains(P, h, graph.src, graph.dst, dd, chn, n_chn, reg, lin, close)
    # the points of each region, ascending (one stable sort, not one pass over N per region)
    o = np.argsort(reg, kind="stable")
    cut = np.searchsorted(reg[o], np.arange(n_reg + 1))
    regions = [o[cut[r]:cut[r + 1]] for r in range(n_reg)]
    return chains, regions


class Parted(NamedTuple):
    """The pieces of :func:`part_bypassed`.

    Attributes
    ----------
    chn : (N,) ndarray of int
        Piece of every point (-1 for region points), numbered in the order of the lowest point.
    n_chn : int
    dropped : (D,) ndarray of int64
        Indices (into ``graph.src`` / ``graph.dst``) of the links left out, ascending.
    """

    chn: np.ndarray
    n_chn: int
    dropped: np.ndarray


def part_bypassed(P: np.ndarray, graph: Graph, flagged: np.ndarray, reg: np.ndarray, chn: np.ndarray,
                  n_chn: int) -> Parted:
    """The links that step over a region between two pieces of curve: left out of the chains.

    Under noise the links reach up to a few spacings, and a region of a few points on a curve
    (a junction of the ladder's rail with a rung) can be stepped over by a link from the curve's
    samples on one side to those on the other: the points outside the regions then stay one
    piece past the junction, which gets too few chain ends to be one. A link ``(u, v)`` between
    two points outside the regions steps over (or cuts the corner of) the region of a point
    ``w`` linked to both when ``w`` projects inside the link and lies within
    ``CHAINS.bypass_off`` of its length from it (a crossing's corner: its two streets' links
    around it),
    and the region holds ``CHAINS.pass_min_points`` points or more (the rule of
    :func:`_passed_regions`: a lone flagged point is no junction). Such a link is left out
    where that parts two pieces that each touch a region other than the one stepped over (the
    rail's pieces reach the next junctions); it is kept where a piece would touch no other
    region: the tip of a sharp corner whose legs, close together, were flagged on both, or a
    sample inside one region spanning several junctions (a building's notch).

    Only the pieces holding such links are formed again (a union-find over their links), so
    that no copy of the links is made: the links left out stay in the graph, joining two
    chains, which every later reading ignores (a chain's own links have both ends in it).

    Parameters
    ----------
    P : (N, d) ndarray
    graph : Graph
    flagged : (N,) ndarray of bool
        Region points.
    reg : (N,) ndarray of int
        Region of each flagged point (-1 elsewhere).
    chn : (N,) ndarray of int
        The pieces over every link (:func:`.graph.components` of the points outside the regions;
        -1 for region points).
    n_chn : int

    Returns
    -------
    Parted
        The pieces without the links left out (numbered, as ``chn``, in the order of their
        lowest point), their number and the links left out.
    """
    src, dst, ip, ix = graph.src, graph.dst, graph.indptr, graph.indices
    same = Parted(chn, n_chn, np.zeros(0, dtype=np.int64))
    if not flagged.any() or not n_chn:
        return same
    N = len(P)
    sizes = np.bincount(reg[flagged])
    big = np.zeros(N, dtype=bool)
    big[flagged] = sizes[reg[flagged]] >= CHAINS.pass_min_points
    # the region points' links (the adjacency is symmetric: read from the region side, the
    # fewer rows); those of points outside the regions to such regions' points, as sorted keys
    # (point, region point): each pair once, as a CSR row holds a neighbour once
    fa, fb = csr_edges(ip, ix, np.flatnonzero(flagged))
    sel = big[fa] & ~flagged[fb]
    ea, eb = fb[sel], fa[sel].astype(np.int64)
    if not len(ea):
        return same
    keys = np.sort(ea.astype(np.int64) * N + eb)
    has = np.zeros(N, dtype=bool)
    has[ea] = True
    del ea, eb, sel
    cand = np.flatnonzero(has[src] & has[dst])
    del has
    if not len(cand):
        return same
    # (link, w): w a region point linked to both ends of the link, inside it and near it; the
    # links in blocks (their temporaries stay small)
    rows = np.unique(np.concatenate([_stepped_over(P, src, dst, keys, reg, cand[b:b + LAYOUT.link_block])
                                     for b in range(0, len(cand), LAYOUT.link_block)]), axis=0)
    if not len(rows):
        return same
    # the pieces holding those links, formed again without them
    inA = np.zeros(n_chn, dtype=bool)
    inA[chn[src[rows[:, 0]]]] = True
    ptsA = chn >= 0
    ptsA[ptsA] = inA[chn[ptsA]]
    e_sub = np.flatnonzero(ptsA[src])  # (a piece's links have both ends in it)

    def pieces(drop):
        k = e_sub[~np.isin(e_sub, drop)]
        return components(N, src[k], dst[k], ptsA)[0]

    sub = pieces(rows[:, 0])
    # the regions each new piece touches (one sorted key each)
    n_reg = int(reg.max()) + 1
    m = sub[fb] >= 0
    tk = np.unique(sub[fb[m]].astype(np.int64) * n_reg + reg[fa[m]])
    n_touch = np.bincount(tk // n_reg, minlength=int(sub.max()) + 1)

    def elsewhere(c, r):  # piece c touches a region other than r
        key = c * n_reg + r
        j = np.minimum(np.searchsorted(tk, key), len(tk) - 1)
        return n_touch[c] - (tk[j] == key) > 0

    e, r = rows[:, 0], rows[:, 1]
    cu, cv = sub[src[e]].astype(np.int64), sub[dst[e]].astype(np.int64)
    dropped = np.unique(e[(cu != cv) & elsewhere(cu, r) & elsewhere(cv, r)])
    if not len(dropped):
        return same
    if len(dropped) < len(np.unique(e)):
        sub = pieces(dropped)
    # the pieces outside A as they were, those of A new; numbered by their lowest point
    lab = chn.astype(np.int64)
    lab[ptsA] = n_chn + sub[ptsA]
    m = lab >= 0
    first = np.full(n_chn + int(sub.max()) + 1, N, dtype=np.int64)
    np.minimum.at(first, lab[m], np.flatnonzero(m))
    used = np.flatnonzero(first < N)
    rank = np.full(len(first), -1, dtype=np.int64)
    rank[used[np.argsort(first[used], kind="stable")]] = np.arange(len(used))
    out = np.full(N, -1, dtype=chn.dtype)
    out[m] = rank[lab[m]]
    return Parted(out, len(used), dropped)


def _stepped_over(P, src, dst, keys, reg, cand):
    """(k, 2) rows (link, region) of :func:`part_bypassed` for the links ``cand``: a point of
    the region is linked to both ends of the link (``keys``: sorted ``point * N + region
    point``), projects inside it and lies within ``CHAINS.bypass_off`` of its length from it."""
    N = len(P)
    lu = src[cand].astype(np.int64)
    lo = np.searchsorted(keys, lu * N)
    n = np.searchsorted(keys, (lu + 1) * N) - lo
    pe = np.repeat(cand, n)
    pw = keys[np.repeat(lo - np.cumsum(np.r_[0, n[:-1]]), n) + np.arange(n.sum())] % N
    k2 = dst[pe].astype(np.int64) * N + pw
    j = np.minimum(np.searchsorted(keys, k2), len(keys) - 1)
    both = keys[j] == k2
    pe, pw = pe[both], pw[both]
    a, d = P[src[pe]], P[dst[pe]] - P[src[pe]]
    L2 = np.einsum("ij,ij->i", d, d)
    w = P[pw] - a
    t = np.einsum("ij,ij->i", w, d) / np.maximum(L2, NUMERIC.tiny)
    w -= t[:, None] * d
    over = (t > 0) & (t < 1) & (np.einsum("ij,ij->i", w, w) < CHAINS.bypass_off ** 2 * L2)
    return np.c_[pe[over], reg[pw[over]]].astype(np.int64)


def order_chains(P, h, src, dst, dd, chn, n_chn, reg, lin, close=None):
    """Order every chain by geodesic distance from one end; find the regions its ends touch."""
    N = len(P)
    if n_chn == 0:
        return []
    # compiled: each chain ordered by its distance along the linked graph (edges inside the
    # chain) from its far end, the point farthest from its lowest id (a double sweep)
    ids_o, par_o, bounds = _k.chain_order(N, np.asarray(src, dtype=_k.INDEX), np.asarray(dst, dtype=_k.INDEX),
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
    # within reach = min(L / 2, CHAINS.end_reach h) of each end (h: the chain's median spacing; a chain
    # shorter than 2 reach is split at L / 2); ties: the lowest region id
    ends, touch = _k.chain_ends(np.ascontiguousarray(h, dtype=np.float64), ids_o, par_o, bounds,
                                c_reg, c_par, cb)
    # polyline length of every ordered chain (steps inside a chain; a zigzag test below)
    step = step_lengths(P, ids_o)
    step[bounds[1:] - 1] = 0.0  # the step from a chain's last point to the next chain's first
    plen = np.add.reduceat(step, bounds[:-1]) if n_chn else np.zeros(0)
    length = par_o[bounds[1:] - 1]  # the distance of each chain's far end
    # a short chain given the same region at both ends may take another one at one side
    for ci in np.flatnonzero(touch & (ends[:, 0] >= 0) & (ends[:, 0] == ends[:, 1])).tolist():
        _other_end(ci, ends, c_reg[cb[ci]:cb[ci + 1]], c_par[cb[ci]:cb[ci + 1]],
                   float(length[ci]), float(np.median(h[ids_o[bounds[ci]:bounds[ci + 1]]])))
    # a chain of a single point between two close junctions has one end only
    one = (ends[:, 0] >= 0) != (ends[:, 1] >= 0)
    tiny = np.flatnonzero(touch & one & (np.diff(bounds) <= CHAINS.pair_points)) if close is not None and close.any() else []
    if len(tiny):
        cen = _region_centroids(P, reg)
        for ci in tiny.tolist():
            _missing_end(ci, ends, c_reg[cb[ci]:cb[ci + 1]], P[ids_o[bounds[ci]:bounds[ci + 1]]].mean(axis=0), cen, close)
    # no region at either end (a contact in the middle only: a clump beside a loop)
    free = ~touch | ((ends[:, 0] < 0) & (ends[:, 1] < 0))
    # may zigzag (checked below)
    zig = ~free & (np.diff(bounds) >= CHAINS.zigzag_min_points) & (plen > CHAINS.zigzag * length * (1 - NUMERIC.rel_loose))
    special = np.flatnonzero(free | zig)
    b = bounds.tolist()
    e0, e1 = ends[:, 0].tolist(), ends[:, 1].tolist()
    chains = [Chain(ids_o[b[ci]:b[ci + 1]], [e0[ci], e1[ci]]) for ci in range(n_chn)]
    # where a chain runs past a region over a long link, the cut: (chain, position, region)
    # (read only on the chains with a contact of a region at neither end: few)
    other = (c_reg != ends[c_chain, 0]) & (c_reg != ends[c_chain, 1])
    some = np.zeros(n_chn, dtype=bool)
    some[c_chain[other]] = True
    passed = _passed_regions(P, h, reg, ids_o, par_o, bounds, c_reg, c_par, cb, some & touch & ~free & ~zig, ends)
    if not len(special):
        return _cut_at(chains, par_o, bounds, passed)
    # the linked graph inside the chains below (their loops are cut open on it)
    inside = (chn[src] >= 0) & (chn[src] == chn[dst])
    inside[inside] = np.isin(chn[src[inside]], special)
    g = coo_matrix((np.maximum(dd[inside], CHAINS.min_edge), (src[inside], dst[inside])), shape=(N, N)).tocsr()
    for ci in special.tolist():
        seg = ids_o[b[ci]:b[ci + 1]]
        if free[ci]:
            chains[ci] = _loop_or_piece(P, h, g, seg, lin)
            continue
        if polylen(P[seg]) > CHAINS.zigzag * float(length[ci]):
            # the points ordered by distance from one end zigzag: the chain is still a cycle
            # in the linked graph (a loop whose links bypass the few points flagged on it):
            # it is cut open at its contact with the region it touches most, both ends there
            regs_c, pts_c = c_reg[cb[ci]:cb[ci + 1]], c_pt[cb[ci]:cb[ci + 1]]
            ru, rc = np.unique(regs_c, return_counts=True)
            r = int(ru[np.argmax(rc)])
            lp = _loop_or_piece(P, h, g, seg, lin, start=int(pts_c[regs_c == r].min()))
            if lp.closed:
                chains[ci] = Chain(lp.ids, [r, r])
    return _cut_at(chains, par_o, bounds, passed)


def _passed_regions(P, h, reg, ids_o, par_o, bounds, c_reg, c_par, cb, open_, ends):
    """Where a chain runs past a region it does not end at: ``(chain, position, region)`` rows,
    sorted by chain and position (the position: a distance along the chain, as ``par_o``).

    The linked graph can join the two samples on either side of a region of a few points (a
    right-angle corner's sample with the first samples of a branch leaving it), so the run of
    points outside the regions goes on past the region instead of ending at it, and the region
    has too few chain ends to be a junction (a building's notch lost all four corners so). Such
    a chain is cut there (:func:`_cut_at`): every contact of the region with the chain lies in
    the chain's middle (beyond ``min(L / 2, CHAINS.end_reach h)`` of both ends), all within
    ``CHAINS.pass_span`` spacings of one another along it, the region holds at least
    ``CHAINS.pass_min_points`` points, and among the chain's points there one link (consecutive
    points whose distance along the chain is their distance in space) is longer than
    ``CHAINS.pass_jump`` spacings: the chain stepped over the region's points. Only the open
    chains ``open_`` (with their ends known) are read.
    """
    rows = []
    sizes = np.bincount(reg[reg >= 0]) if (reg >= 0).any() else np.zeros(0, dtype=np.int64)
    for ci in np.flatnonzero(open_).tolist():
        lo, hi = bounds[ci], bounds[ci + 1]
        regs, pars = c_reg[cb[ci]:cb[ci + 1]], c_par[cb[ci]:cb[ci + 1]]
        par = par_o[lo:hi]
        L = float(par[-1])
        hl = float(np.median(h[ids_o[lo:hi]]))
        reach = min(0.5 * L, CHAINS.end_reach * hl)
        inner = (pars > reach) & (pars < L - reach)
        if not inner.any():
            continue
        for r in np.unique(regs[inner]).tolist():
            q = pars[regs == r]
            if r in (ends[ci, 0], ends[ci, 1]) or sizes[r] < CHAINS.pass_min_points:
                continue
            if not inner[regs == r].all() or q.max() - q.min() > CHAINS.pass_span * hl:
                continue
            at = np.flatnonzero((par >= q.min()) & (par <= q.max()))
            if len(at) < 2:
                continue
            along = np.diff(par[at])
            k = int(np.argmax(along))
            step = float(np.linalg.norm(P[ids_o[lo + at[k + 1]]] - P[ids_o[lo + at[k]]]))
            if along[k] > CHAINS.pass_jump * hl and abs(step - along[k]) <= NUMERIC.rel_loose * along[k]:
                rows.append((ci, 0.5 * float(q.min() + q.max()), r))
    rows.sort()
    return rows


def _cut_at(chains, par_o, bounds, passed):
    """The chains with each chain of ``passed`` (:func:`_passed_regions`) cut at its positions
    into pieces ending at the regions passed; its pieces take its place in the list, in order.
    A cut that would leave a piece without points leaves the chain whole."""
    if not passed:
        return chains
    by = {}
    for ci, x, r in passed:
        by.setdefault(ci, []).append((x, r))
    out = []
    for ci, ch in enumerate(chains):
        cuts = by.get(ci)
        if cuts is None:
            out.append(ch)
            continue
        par = par_o[bounds[ci]:bounds[ci + 1]]
        ks = [int(np.searchsorted(par, x, side="right")) for x, _ in cuts]
        if ks[0] < 1 or ks[-1] >= len(ch.ids) or any(b_ <= a_ for a_, b_ in zip(ks, ks[1:])):
            out.append(ch)
            continue
        left, start = ch.ends[0], 0
        for k, (_, r) in zip(ks, cuts):
            out.append(Chain(ch.ids[start:k], [left, r]))
            left, start = r, k
        out.append(Chain(ch.ids[start:], [left, ch.ends[1]]))
    return out


def _other_end(ci, ends, regs, par, length, hl):
    """A short chain given the same region at both ends that also touches another region.

    Under ``2 * CHAINS.end_reach`` spacings long, both halves of a chain may be linked mostly to
    the larger region at one end (a sparse free branch, whose long links reach the chain's far
    end): the other region touched (most contacts; ties: lowest id) takes the side its
    contacts lie on (mean position along the chain against that of the first region's).
    """
    if length > 2 * CHAINS.end_reach * hl:
        return
    r = ends[ci, 0]
    other = regs != r
    if not other.any():
        return
    ru, rc = np.unique(regs[other], return_counts=True)
    r2 = int(ru[np.argmax(rc)])
    side = 1 if par[regs == r2].mean() > par[regs == r].mean() else 0
    ends[ci, side] = r2


def _missing_end(ci, ends, regs, x, cen, close):
    """A chain of ``CHAINS.pair_points`` points or fewer with one end only.

    The chain's ends are read from the contacts near either end; on a chain of a single point
    both ends see the same contacts, and the region at the second end is lost. Between two
    junctions a few spacings apart a single point can be the whole segment: the other region
    it touches (most contacts; ties: lowest id) takes the missing end, when both are such
    separated junctions (``close``) and the chain (at ``x``) lies between the two (``cen``:
    region centroids; the two seen from ``x`` in opposite directions: a point beside two
    regions joins neither). Elsewhere (hand-drawn strokes) such a point is left a spur.
    """
    known = 0 if ends[ci, 0] >= 0 else 1
    r = ends[ci, known]
    if not close[r]:
        return
    other = regs != r
    if not other.any():
        return
    ru, rc = np.unique(regs[other], return_counts=True)
    r2 = int(ru[np.argmax(rc)])
    if close[r2] and float((cen[r] - x) @ (cen[r2] - x)) < 0:
        ends[ci, 1 - known] = r2


def _region_centroids(P, reg):
    """(n_reg, d) centroid of every region (``reg``: region of each point, -1 for none)."""
    fl = reg >= 0
    n = int(reg.max()) + 1 if fl.any() else 0
    cnt = np.maximum(np.bincount(reg[fl], minlength=n), 1).astype(float)
    return np.stack([np.bincount(reg[fl], weights=P[fl, c], minlength=n) for c in range(P.shape[1])], axis=1) / cnt[:, None]


def _loop_or_piece(P, h, g, seg, lin, start=None):
    """A chain that touches no region: a closed loop (cut open and ordered), or an open piece.

    The loop is cut at ``start`` when given, else at its straightest point (largest
    linearity; ties: lowest id), never at a sharp corner where the tangent is undefined.
    """
    if len(seg) < CHAINS.loop_min_points:
        return Chain(seg, [-1, -1])
    seg = np.sort(seg)
    s0 = int(np.argmax(lin[seg])) if start is None else int(np.searchsorted(seg, start))
    seg = np.r_[seg[s0:], seg[:s0]]
    sub = g[seg][:, seg].tocoo()
    X = P[seg]
    hl = float(np.median(h[seg]))
    # tangent at the start point; every link crossing the cut has both ends this near
    rnear = max(CHAINS.loop_cut * hl, CHAINS.loop_cut_link * float(sub.data.max()) if sub.nnz else 0.0)
    near = np.linalg.norm(X - X[0], axis=1) <= rnear
    _, u = fit_line(X[np.linalg.norm(X - X[0], axis=1) <= CHAINS.loop_cut * hl])
    if u is None:
        return Chain(seg, [-1, -1])
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
    closed = np.linalg.norm(last - X[0]) <= rnear and polylen(X[o]) > CHAINS.loop_min * hl
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
        return Chain(np.r_[seg[o], seg[np.flatnonzero(~f1)]], [-1, -1], closed=False)
    if len(rest):
        # unreachable points: append by their position along the tangent (rare)
        ordered = np.r_[ordered, seg[rest[np.argsort(side[rest], kind="stable")]]]
    return Chain(ordered, [-1, -1], closed=bool(closed))


def fit_line(X):
    c = X.mean(axis=0)
    if len(X) < 2:
        return c, None
    _, _, vt = np.linalg.svd(X - c, full_matrices=False)
    return c, vt[0]


def step_lengths(P, ids):
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
    n = len(ids)
    out = np.zeros(n)
    # in blocks of LAYOUT.curve_block steps (the same arithmetic per step): the (block, d)
    # gathers stay small, where one gather of all the points was 2 x 24 bytes a point at the
    # peak of the method's memory
    for i in range(0, n - 1, LAYOUT.curve_block):
        X = P[ids[i:min(i + LAYOUT.curve_block + 1, n)]]
        D = X[1:] - X[:-1]
        D *= D
        out[i:i + len(D)] = np.sqrt(D.sum(axis=1))
    return out


def group_medians(values: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The median of each group of consecutive values (as ``np.median``: the middle value, or the
    mean of the two middle ones), all groups at once.

    Parameters
    ----------
    values : (n,) ndarray
        The groups' values, group after group.
    counts : (g,) ndarray of int
        The size of each group (sum n).

    Returns
    -------
    (g,) ndarray
        NaN for an empty group.
    """
    counts = np.asarray(counts, dtype=np.int64)
    grp = np.repeat(np.arange(len(counts)), counts)
    v = values[np.lexsort((values, grp))]
    start = np.r_[0, np.cumsum(counts)[:-1]].astype(np.int64)
    out = np.full(len(counts), np.nan)
    has = counts > 0
    out[has] = (v[start[has] + (counts[has] - 1) // 2] + v[start[has] + counts[has] // 2]) / 2
    return out


def polylen(X):
    if len(X) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(X, axis=0), axis=1).sum())


def flat_steps(P, id_lists):
    """The points of many non-empty chains end to end, and the steps along each.

    Parameters
    ----------
    P : (N, d) ndarray
    id_lists : list of (n_j,) ndarray of int, each n_j >= 1

    Returns
    -------
    flat : (sum n_j,) ndarray of int64
        The ids, chain after chain.
    off : (len(id_lists) + 1,) ndarray of int64
        Chain ``j``'s ids are ``flat[off[j]:off[j + 1]]``.
    step : (sum n_j,) ndarray
        From each point to the next of its chain (0 after a chain's last point).
    """
    flat = np.concatenate(id_lists).astype(np.int64, copy=False)
    off = np.r_[0, np.cumsum([len(ids) for ids in id_lists])].astype(np.int64)
    step = step_lengths(P, flat)
    step[off[1:] - 1] = 0.0  # from a chain's last point to the next chain's first
    return flat, off, step


def chain_lengths(P, h, chains):
    """Polyline length (summed per chain, within rounding of :func:`polylen`) and largest
    spacing of every chain; a chain without points gets length 0 and spacing inf."""
    lens = np.array([len(c.ids) for c in chains], dtype=np.int64)
    length = np.zeros(len(chains))
    hmax = np.full(len(chains), np.inf)
    nz = np.flatnonzero(lens > 0)
    if len(nz):
        flat, off, step = flat_steps(P, [chains[i].ids for i in nz.tolist()])
        length[nz] = np.add.reduceat(step, off[:-1])
        hmax[nz] = np.maximum.reduceat(h[flat], off[:-1])
    return length, hmax


def extent(P, ids):
    if len(ids) < 2:
        return 0.0
    X = P[ids]
    return float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))


def order_between(P, ids, pa, pb):
    """Region points ordered from ``pa`` towards ``pb``."""
    if len(ids) == 0:
        return ids
    u = pb - pa
    nu = np.linalg.norm(u)
    if nu == 0:
        return ids
    proj = (P[ids] - pa) @ (u / nu)
    return ids[np.lexsort((ids, proj))]


def end_portion(P, h, ids, span, m=None):
    """The last points of an ordered id list ``ids`` (running towards the end), over ``span`` h.

    ``m``: their number when already known (:func:`end_counts`).
    """
    n = len(ids)
    if n < 2:
        return P[ids[::-1]]
    if m is None:
        hl = float(h[ids[-1]])
        # arc length summed backwards from the end, only as far as needed (compiled kernel)
        m = max(int(_k.end_count(P, np.ascontiguousarray(ids, dtype=np.int64), span * hl)), min(ENDS.min_points, n))
    return P[ids[: -m - 1: -1]]


def end_counts(P, h, lists, span):
    """The number of points of :func:`end_portion` of every id list, in one compiled call.

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


def segment_distance(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(...) distance of each point ``x`` (..., d) to the segment from ``a`` (..., d) to ``b``
    (..., d), the three broadcast together, e.g. (n, d) each (a segment of length 0: the
    distance to its point)."""
    ab = b - a
    L2 = np.maximum((ab * ab).sum(axis=-1), NUMERIC.tiny)
    t = np.clip(((x - a) * ab).sum(axis=-1) / L2, 0.0, 1.0)
    return np.linalg.norm(x - (a + t[..., None] * ab), axis=-1)


def points_apart(A: np.ndarray, B: np.ndarray, lim: float) -> bool:
    """Whether some point of ``A`` (a, d) lies over ``lim`` from every point of ``B`` (b, d),
    or some point of ``B`` from every point of ``A``: two pieces that are two curves, not one
    curve's samples shared out between them."""
    d = np.linalg.norm(A[:, None, :] - B[None, :, :], axis=2)
    return bool(max(d.min(axis=1).max(), d.min(axis=0).max()) > lim)
