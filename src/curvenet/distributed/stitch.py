"""Stitching: the tiles' pieces joined at their ports into one network.

Two ports of different tiles join when they lie within ``PORT_MATCH`` median spacings and
their directions are opposite within ``PORT_ANGLE`` (each points out of its own tile). The
joined ports are cut nodes of valence 2: they are contracted, so that a curve crossing ten
tiles comes out as one curve, and a loop cut into pieces as one closed loop. A port left
without partner (the tiles disagree there) becomes a free end, counted in the result.
Under noise the curves that cross a face are fitted here, once whole (each tile fitted the
curves it holds whole).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..methods.robust.curves import fit_curves
from .cut import TilePieces
from .plan import CurvePlan, PieceStore, Span, StoredNetwork

__all__ = ["PORT_MATCH", "PORT_ANGLE_COS", "FIT_BATCH", "stitch"]

#: Ports at most this many median spacings apart may join (the two tiles compute the same
#: crossing segment, so the same midpoint up to rounding; a node placed a little differently
#: moves it by a fraction of a spacing).
PORT_MATCH: float = 0.5
#: ... when their directions are opposite within 30 degrees (cosine).
PORT_ANGLE_COS: float = float(np.cos(np.radians(30.0)))
#: The curves fitted here are read, fitted and spilled a batch of at most this many points
#: at a time (the fit holds several arrays a point).
FIT_BATCH: int = 1 << 17


def _match_ports(pos: np.ndarray, tan: np.ndarray, tile: np.ndarray, reach: float) -> np.ndarray:
    """Partner of every port (-1: none): nearest first, each port once."""
    partner = np.full(len(pos), -1, dtype=np.int64)
    if len(pos) < 2:
        return partner
    pairs = cKDTree(pos).query_pairs(reach, output_type="ndarray")
    if not len(pairs):
        return partner
    i, j = pairs[:, 0], pairs[:, 1]
    ok = (tile[i] != tile[j]) & ((tan[i] * tan[j]).sum(axis=1) <= -PORT_ANGLE_COS)
    i, j = i[ok], j[ok]
    dist = np.linalg.norm(pos[i] - pos[j], axis=1)
    for a, b in zip(*(x[np.lexsort((j, i, dist))] for x in (i, j))):
        if partner[a] < 0 and partner[b] < 0:
            partner[a], partner[b] = b, a
    return partner


def stitch(tiles: list[TilePieces], spacing: float, root, *, join: bool = True,
           sigma: float | None = None) -> StoredNetwork:
    """Join the pieces of every tile into one network (in canonical order).

    Parameters
    ----------
    tiles : list of TilePieces
        In any order (they are sorted by key), their pieces stored in the scratch store
        (:func:`.cut.store_pieces`).
    spacing : float
        The whole cloud's median spacing (the port match distance is in these units).
    root : path
        The scratch store.
    join : bool
        Join ports across tiles (False: every port is a free end; the negative control).
    sigma : float, optional
        The whole cloud's noise estimate when the curves are to be fitted (a noisy cloud):
        every curve not fitted whole by its tile (``Piece.fitted``: one that crosses a face)
        is fitted here, once joined.

    Returns
    -------
    StoredNetwork
        Its curves are plans over the stored pieces (:mod:`.plan`); ``stats["unmatched_ports"]``
        counts the ports without partner, ``stats["fitted_here"]`` the curves fitted here.
    """
    tiles = sorted(tiles, key=lambda t: t.key)
    d = next((t.nodes.shape[1] for t in tiles), 3)
    store = PieceStore(root, [t.key for t in tiles], d)
    node_base = np.cumsum([0] + [len(t.nodes) for t in tiles])
    port_base = np.cumsum([0] + [len(t.ports) for t in tiles])
    nodes = [t.nodes for t in tiles]
    pos = np.vstack([t.ports for t in tiles]) if tiles else np.zeros((0, d))
    tan = np.vstack([t.tangents for t in tiles]) if tiles else np.zeros((0, d))
    tile_of = np.repeat(np.arange(len(tiles)), np.diff(port_base))
    partner = _match_ports(pos, tan, tile_of, PORT_MATCH * spacing) if join else np.full(len(pos), -1, np.int64)
    n_nodes = int(node_base[-1])
    # a port without partner: a free end at the port
    loose = np.flatnonzero(partner < 0)
    loose_node = np.full(len(pos), -1, dtype=np.int64)
    loose_node[loose] = n_nodes + np.arange(len(loose))
    nodes.append(pos[loose])

    pieces, ends, owner = [], [], {}
    for ti, t in enumerate(tiles):
        for pc in t.pieces:
            if pc.ends is None:
                e = None
            else:
                e = []
                for side, (kind, i) in enumerate(pc.ends):
                    if kind == "node":
                        e.append(("node", int(node_base[ti] + i)))
                    else:
                        g = int(port_base[ti] + i)
                        owner[g] = (len(pieces), side)
                        e.append(("node", int(loose_node[g])) if partner[g] < 0 else ("port", g))
            pieces.append((ti, pc))
            ends.append(e)

    plans: list[CurvePlan] = []
    done: list[bool] = []  # fitted by its tile (a fitted piece is a whole curve: its walk is itself)
    used = np.zeros(len(pieces), dtype=bool)
    for i, e in enumerate(ends):
        if e is None:
            used[i] = True
            ti, pc = pieces[i]
            plans.append(CurvePlan([Span(ti, *pc.rows)], None, None, True))
            done.append(pc.fitted)
    for i, e in enumerate(ends):  # chains that start at a node
        if used[i]:
            continue
        for side in (0, 1):
            if e[side][0] == "node":
                plans.append(_walk(i, side, pieces, ends, owner, partner, used, closed=False))
                done.append(pieces[i][1].fitted)
                break
    for i in range(len(pieces)):  # what is left are loops of cut nodes only
        if not used[i]:
            plans.append(_walk(i, 0, pieces, ends, owner, partner, used, closed=True))
            done.append(False)
    todo = [] if sigma is None else [i for i, f in enumerate(done) if not f]
    for batch in _batches(todo, [plans[i].size for i in todo], FIT_BATCH):  # (a batch at a time in memory)
        for i, c in zip(batch, fit_curves([store.curve(plans[i]) for i in batch], sigma)):
            plans[i] = store.keep(c)
    net = StoredNetwork(np.vstack(nodes).reshape(-1, d), plans, store).canonical()
    net.stats["unmatched_ports"] = int(len(loose))
    net.stats["ports"] = int(len(pos))
    net.stats["fitted_here"] = len(todo)
    return net


def _batches(items: list, sizes: list, limit: int):
    """``items`` in consecutive batches of at most ``limit`` in total size (one item a batch
    when it is larger alone)."""
    batch, n = [], 0
    for it, m in zip(items, sizes):
        if batch and n + m > limit:
            yield batch
            batch, n = [], 0
        batch.append(it)
        n += m
    if batch:
        yield batch


def _walk(i, side, pieces, ends, owner, partner, used, *, closed) -> CurvePlan:
    """Follow pieces from piece ``i`` entering at ``side`` through joined ports; drop the port
    midpoints on the way."""
    start = ends[i][side]
    spans = []
    cur, s_in = i, side
    while True:
        used[cur] = True
        ti, pc = pieces[cur]
        a, b = pc.rows
        lo = 1 if ends[cur][s_in][0] == "port" else 0
        out = ends[cur][1 - s_in]
        hi = (b - a) - (1 if out[0] == "port" else 0)
        # rows lo..hi of the piece run from its side s_in: backwards from the stored end when 1
        spans.append(Span(ti, a + lo, a + hi) if s_in == 0 else Span(ti, b - hi, b - lo, True))
        if out[0] == "node":
            end = out
            break
        nxt, s_next = owner[int(partner[out[1]])]
        if used[nxt]:  # back at the start of a loop (or the tiles disagree: stop here)
            end = None
            break
        cur, s_in = nxt, s_next
    if closed or start[0] != "node" or end is None:
        return CurvePlan(spans, None, None, True)
    return CurvePlan(spans, start[1], end[1], False)
