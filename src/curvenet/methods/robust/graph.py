"""Stage 3: the linked graph (neighbour links along the tangents, strand cuts under noise).

A link joins two neighbours when it runs along the tangent of one of its ends
(:func:`linked_edges`); under noise the links that join two close parallel strands are cut
(:func:`cut_strand_links`). Close parallel curves and the two sides of an acute angle stay
apart. :func:`components` labels connected parts of a point set joined by given edges.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import kernels as _k
from .frames import Frames, Neighbours, noisy_tangents, pair_distances, vote_tangents
from .params import RobustParams
from .thresholds import LAYOUT, LINKS, NOISE, TANGENTS

__all__ = ["Graph", "linked_graph", "linked_edges", "edge_lengths", "cut_strand_links", "components", "csr_edges"]


class Graph(NamedTuple):
    """The linked graph.

    Attributes
    ----------
    src, dst : (E,) ndarray of int32
        Directed links (kept by the tests; both directions of a pair may be there). Their
        lengths are not kept (8 bytes a link, up to 55 bytes a point under noise, held through
        the shell test): :func:`edge_lengths` gives them again, the same bits.
    indptr : (N + 1,) ndarray of int64
    indices : ndarray of int32
        CSR adjacency of the undirected union of the links.
    """

    src: np.ndarray
    dst: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray


def linked_graph(P: np.ndarray, nb: Neighbours, fr: Frames, prm: RobustParams) -> Graph:
    """Stage 3: the links of every point (see :func:`linked_edges`), strand links cut under noise.

    Parameters
    ----------
    P : (N, d) ndarray
    nb : Neighbours
    fr : Frames
    prm : RobustParams
        ``link`` and ``link_width``.

    Returns
    -------
    Graph
    """
    N = len(P)
    noise = NOISE.scale * fr.sigma
    src, dst, dd = linked_edges(P, nb.h, nb.idx, fr.t, fr.lin, prm.link, prm.link_width,
                                LINKS.strip_noise * noise, LINKS.gap_noise * noise, lens=not fr.low)
    if not fr.low:  # links between two close parallel strands are cut
        with _k.compiled_for(N, _k.NUMBA_MIN_POINTS_NOISY, _k.STRAND_KERNELS):  # (slow in plain Python)
            tn, ln = noisy_tangents(P, nb.h, fr.sigma, nb.tree, None, nb.idx)
            tn, _ = vote_tangents(tn, ln, nb.idx, m=min(TANGENTS.vote_m_noisy, nb.idx.shape[1]))
            src, dst, dd = cut_strand_links(P, nb.h, nb.idx, tn, src, dst, dd, fr.sigma)
    indptr, indices = _k.csr_union(N, np.asarray(src, dtype=_k.INDEX), np.asarray(dst, dtype=_k.INDEX))
    return Graph(src, dst, indptr, indices)


def edge_lengths(P: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Lengths of the links ``(src, dst)``: the same bits as :func:`linked_edges` gave them
    (both sum the squared coordinate differences as scipy's k-d tree query does), computed in
    blocks of ``LAYOUT.curve_block`` links so that no (E, d) gather is made.

    Parameters
    ----------
    P : (N, d) ndarray
    src, dst : (E,) ndarray of int

    Returns
    -------
    (E,) ndarray of float
    """
    out = np.empty(len(src))
    for i in range(0, len(src), LAYOUT.curve_block):
        j = i + LAYOUT.curve_block
        out[i:j] = pair_distances(P, src[i:j], dst[i:j])
    return out


def linked_edges(P, h, idx, t, lin, link, width, wmin=0.0, gap=0.0, lens=False):
    """Directed kNN edges kept by the distance and tangent tests: (src, dst, length).

    A link is at most ``link * h + gap`` long (``gap`` widens it for noise, which opens random
    gaps along a curve). Besides, a point with a reliable tangent is linked to its nearest
    neighbour on each side along the tangent, within the strip, up to twice that length:
    this bridges the widest gaps of sparse, noisy sampling. With ``lens`` (noisy input), such
    a link kept by that rule alone is left out where a nearer neighbour of its first end lies
    in its lens (nearer to its far end too) and off its line by more than the strip's
    half-width: it cuts across a corner whose samples are there, not over a gap.
    """
    # compiled, one kNN row at a time (the tests are spelled out in kernels.graph._linked_edges):
    # links at most LINKS.directional * (link * h + gap) long; the far end's distance from the tangent
    # line through either end within max(width * h, wmin) (or an end not linear, LINKS.lin_min); short
    # links need one tangent test, longer ones (up to link * h + gap) both; plus the nearest
    # strip neighbour on each side along the tangent (rows are sorted by distance)
    return _k.linked_edges(P, np.ascontiguousarray(h, dtype=np.float64), idx, t, lin, float(link),
                           float(width), float(wmin), float(gap), float(LINKS.directional), float(LINKS.lin_min), bool(lens))


def cut_strand_links(P, h, idx, tn, src, dst, dd, sig):
    """The links without those that join two close parallel strands (noisy input).

    :func:`kernels.graph._strand_cuts` finds them; a pair is cut in both directions.
    """
    if len(src) == 0:
        return src, dst, dd
    cut = _k.strand_cuts(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(h, dtype=np.float64),
                         np.ascontiguousarray(idx, dtype=_k.INDEX), np.ascontiguousarray(tn, dtype=np.float64),
                         np.asarray(src, dtype=_k.INDEX), np.asarray(dst, dtype=_k.INDEX), float(sig))
    if not cut.any():
        return src, dst, dd
    n = np.int64(len(P))
    a, b = np.minimum(src, dst).astype(np.int64), np.maximum(src, dst).astype(np.int64)
    key = a * n + b
    keep = ~np.isin(key, key[cut])
    return src[keep], dst[keep], dd[keep]


def components(n, a, b, mask):
    """Connected components of the points in ``mask`` joined by edges (a, b) inside ``mask``.

    Returns labels (-1 outside mask), ordered so that component ids follow the lowest point id,
    and their number (compiled union-find).
    """
    lab, count = _k.components(int(n), np.asarray(a, dtype=_k.INDEX), np.asarray(b, dtype=_k.INDEX),
                               np.ascontiguousarray(mask, dtype=np.bool_))
    return lab, int(count)


def csr_edges(indptr: np.ndarray, indices: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges of the CSR adjacency ``(indptr, indices)`` that leave the points ``rows``.

    Parameters
    ----------
    indptr : (N + 1,) ndarray of int
    indices : ndarray of int
    rows : (R,) ndarray of int

    Returns
    -------
    ea, eb : (E,) ndarray
        Every edge ``(ea[i], eb[i])`` of the rows, row by row, each row's in its CSR order.
    """
    lens = indptr[rows + 1] - indptr[rows]
    ea = np.repeat(rows, lens)
    eb = indices[np.repeat(indptr[rows] - np.cumsum(np.r_[0, lens[:-1]]), lens) + np.arange(lens.sum())]
    return ea, eb
