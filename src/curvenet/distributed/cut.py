"""A tile's network cut at its box: the pieces it owns and their ports.

Every polyline vertex belongs to the tile whose half-open box holds it (input points and node
positions alike). A tile keeps the maximal runs of consecutive vertices it owns; where a run
stops because the next vertex lies in another tile, the piece ends at a *port*: the midpoint of
that crossing segment, with the segment's direction out of the tile. The tile on the other
side has the same segment, so the same port (same midpoint, opposite direction):
:mod:`.stitch` joins the two.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..methods.robust.curves import fit_curves
from ..network import Curve, CurveNetwork
from .grid import TileGrid
from .scratch import write_pieces

__all__ = ["Piece", "TilePieces", "cut_network", "fit_whole_pieces", "store_pieces"]


@dataclass
class Piece:
    """A run of owned vertices of one curve.

    Attributes
    ----------
    points : (m, d) ndarray of float
        The run, with the port midpoint first and/or last where an end is a port.
    indices : (m,) ndarray of int64
        Global input id of each point, -1 for node positions and port midpoints.
    ends : tuple of two (str, int), or None
        Each end is ``("node", i)`` (the tile's owned node i) or ``("port", j)`` (the tile's
        port j); None for a closed loop without node, kept whole.
    fitted : bool
        The piece is a whole curve already fitted by its tile (:func:`fit_whole_pieces`).
    rows : tuple of two int, or None
        Once stored (:func:`store_pieces`): the rows ``[lo, hi)`` of the tile's stored pieces
        that hold it (``points`` and ``indices`` are then None).
    """

    points: np.ndarray | None
    indices: np.ndarray | None
    ends: tuple | None
    fitted: bool = False
    rows: tuple | None = None


@dataclass
class TilePieces:
    """What one tile hands to the stitching: its owned nodes, pieces and ports.

    Attributes
    ----------
    key : tuple of int
    nodes : (n, d) ndarray of float
        The nodes inside the tile's box.
    pieces : list of Piece
    ports : (p, d) ndarray of float
        Port positions (crossing-segment midpoints).
    tangents : (p, d) ndarray of float
        Unit direction of each crossing segment, out of the tile.
    n_points : int
        Points the tile reconstructed (box and halo).
    prepared : bool
        The reconstruction went on from the box the estimates' pass prepared.
    """

    key: tuple
    nodes: np.ndarray
    pieces: list = field(default_factory=list)
    ports: np.ndarray | None = None
    tangents: np.ndarray | None = None
    n_points: int = 0
    prepared: bool = False


def cut_network(net: CurveNetwork, grid: TileGrid, key, ids: np.ndarray, occupied) -> TilePieces:
    """Cut the network of one tile (box and halo) at the tile's box.

    Parameters
    ----------
    net : CurveNetwork
        The tile's network; its curves' ``indices`` index ``ids``.
    grid : TileGrid
    key : tuple of int
        The tile.
    ids : (N,) ndarray of int64
        Global input id of each of the tile's points.
    occupied : set of tuple
        The keys of every tile that holds input points (each runs a task): a vertex in
        another tile goes to the nearest of them (:meth:`TileGrid.owners`).

    Returns
    -------
    TilePieces
    """
    key = tuple(int(k) for k in key)
    d = net.dimension
    kk = np.asarray(key, dtype=np.int64)

    def owns(V):
        return (grid.owners(V, occupied) == kk).all(axis=1) if len(V) else np.zeros(0, bool)

    own_node = owns(net.nodes)
    new_node = np.cumsum(own_node) - 1
    ports: list[np.ndarray] = []
    tans: list[np.ndarray] = []
    pieces: list[Piece] = []

    def port(p, q):
        """The port of the crossing segment from owned ``p`` to foreign ``q``."""
        ports.append((p + q) * 0.5)
        t = q - p
        tans.append(t / max(float(np.linalg.norm(t)), np.finfo(float).tiny))
        return ("port", len(ports) - 1)

    for c in net.curves:
        V = c.points
        ind = np.where(c.indices >= 0, ids[np.maximum(c.indices, 0)], -1)
        own = owns(V)
        if not own.any():
            continue
        if own.all():
            ends = None if c.start is None else (("node", int(new_node[c.start])), ("node", int(new_node[c.end])))
            pieces.append(Piece(V.copy(), ind.copy(), ends))
            continue
        if c.closed:  # a loop: start at a foreign vertex and close it, so every run ends at ports
            r = int(np.flatnonzero(~own)[0])
            V, ind, own = (np.concatenate([np.roll(a, -r, axis=0), np.roll(a, -r, axis=0)[:1]]) for a in (V, ind, own))
        k = len(V)
        edges = np.flatnonzero(np.diff(np.r_[0, own.astype(np.int8), 0]))
        for a, b in zip(edges[::2], edges[1::2] - 1):
            pts, pid = [V[a:b + 1]], [ind[a:b + 1]]
            if a == 0:
                e0 = ("node", int(new_node[c.start]))
            else:
                e0 = port(V[a], V[a - 1])
                pts.insert(0, ports[-1][None])
                pid.insert(0, np.full(1, -1, np.int64))
            if b == k - 1:
                e1 = ("node", int(new_node[c.end]))
            else:
                e1 = port(V[b], V[b + 1])
                pts.append(ports[-1][None])
                pid.append(np.full(1, -1, np.int64))
            pieces.append(Piece(np.vstack(pts), np.concatenate(pid), (e0, e1)))
    return TilePieces(key, net.nodes[own_node], pieces,
                      np.array(ports, float).reshape(-1, d), np.array(tans, float).reshape(-1, d))


def _whole_curve(pc: Piece) -> Curve:
    """The curve a whole piece stands for, as the stitching makes it (a loop kept whole is
    closed; a piece between two nodes is open); node ids 0 (the fit reads only the points and
    the closedness)."""
    if pc.ends is None:
        return Curve(pc.points, None, None, True, pc.indices)
    return Curve(pc.points, 0, 0, False, pc.indices)


def fit_whole_pieces(tile: TilePieces, sigma: float) -> TilePieces:
    """The tile's pieces that are whole curves (both ends at nodes, or a loop kept whole) fitted
    as the default method fits its curves under noise (:func:`~curvenet.methods.robust.curves.fit_curves`),
    so that the client fits only the curves that cross a tile face, once stitched.

    Parameters
    ----------
    tile : TilePieces
    sigma : float
        The whole cloud's noise estimate.

    Returns
    -------
    TilePieces
        The same tile with those pieces replaced by fitted ones (``fitted`` set).
    """
    whole = [i for i, pc in enumerate(tile.pieces) if pc.ends is None or all(e[0] == "node" for e in pc.ends)]
    fitted = fit_curves([_whole_curve(tile.pieces[i]) for i in whole], sigma)
    pieces = list(tile.pieces)
    for i, c in zip(whole, fitted):
        pieces[i] = Piece(c.points, tile.pieces[i].indices, tile.pieces[i].ends, True)
    return replace(tile, pieces=pieces)


def store_pieces(root, tile: TilePieces) -> TilePieces:
    """Write the tile's pieces to the scratch store (:func:`.scratch.write_pieces`: their points
    and ids one after the other) and return the tile with pieces that only say where they are
    (``rows``): the client then holds no point of the network (see :mod:`.plan`)."""
    d = tile.nodes.shape[1]
    sizes = [len(pc.points) for pc in tile.pieces]
    off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    P = np.vstack([pc.points for pc in tile.pieces]) if tile.pieces else np.zeros((0, d))
    ids = np.concatenate([pc.indices for pc in tile.pieces]) if tile.pieces else np.zeros(0, np.int64)
    write_pieces(root, tile.key, P, ids)
    pieces = [Piece(None, None, pc.ends, pc.fitted, (int(off[i]), int(off[i + 1]))) for i, pc in enumerate(tile.pieces)]
    return replace(tile, pieces=pieces)
