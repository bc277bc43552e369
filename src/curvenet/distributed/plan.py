"""The stitched network with its curve points left on disk.

Each tile stores its pieces of curves in the scratch store (:func:`.cut.store_pieces`); the
stitching (:mod:`.stitch`) joins them into curves that are only *plans*: which rows of which
tile's stored pieces, in order, each run forwards or backwards. The client then holds the nodes
and the plans (a few numbers a curve), never the points: :class:`StoredNetwork` reads a curve's
points when it is asked for them, one curve at a time, to write the network out without
holding it (:mod:`curvenet.io.streamed`) or to build it in memory (:meth:`StoredNetwork.network`).
Curves the client makes itself (fitted once joined, turned to their canonical start) are
appended to a spill file of its own in the scratch store.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np

from ..network import (Curve, CurveNetwork, _canonical_curve, betti_numbers, canonical_node_order, needs_points,
                       order_by_ends)
from .scratch import read_piece_rows

__all__ = ["Span", "CurvePlan", "PieceStore", "StoredNetwork", "SPILL", "CANONICAL_DECIMALS"]

#: The tile index of a span in the client's spill file.
SPILL: int = -1
#: Coordinates are compared rounded to this many decimals in the canonical order (as
#: :meth:`CurveNetwork.canonical`).
CANONICAL_DECIMALS: int = 6


@dataclass(frozen=True)
class Span:
    """Rows ``[lo, hi)`` of one tile's stored pieces (``tile``: its index in the store's keys,
    or :data:`SPILL`), read backwards when ``rev``."""

    tile: int
    lo: int
    hi: int
    rev: bool = False

    def reversed(self) -> "Span":
        return Span(self.tile, self.lo, self.hi, not self.rev)


@dataclass
class CurvePlan:
    """A curve as spans of stored rows, in order, and its end nodes (as :class:`~curvenet.network.Curve`)."""

    spans: list[Span]
    start: int | None
    end: int | None
    closed: bool = False
    size: int = field(init=False)

    def __post_init__(self) -> None:
        self.size = int(sum(s.hi - s.lo for s in self.spans))

    def reversed(self) -> "CurvePlan":
        """The same curve traversed the other way (:meth:`Curve.reversed`)."""
        return CurvePlan([s.reversed() for s in self.spans[::-1]], self.end, self.start, self.closed)


class PieceStore:
    """Reads the rows of the tiles' stored pieces; appends the client's own curves to a spill
    file (``ROOT/client.pts`` and ``.ids``).

    Parameters
    ----------
    root : path
        The scratch store.
    keys : list of tuple
        The tiles, by index.
    dim : int
    """

    def __init__(self, root, keys: list, dim: int):
        self.root, self.keys, self.dim = Path(root), list(keys), int(dim)
        self._spilled = 0

    def read(self, span: Span) -> tuple[np.ndarray, np.ndarray]:
        """Points (m, d) and ids (m,) of one span, in its direction."""
        if span.tile == SPILL:
            n = span.hi - span.lo
            P = np.fromfile(self.root / "client.pts", dtype="<f8", count=n * self.dim, offset=span.lo * self.dim * 8)
            I = np.fromfile(self.root / "client.ids", dtype="<i8", count=n, offset=span.lo * 8)
            P = P.reshape(n, self.dim)
        else:
            P, I = read_piece_rows(self.root, self.keys[span.tile], span.lo, span.hi, self.dim)
        return (P[::-1].copy(), I[::-1].copy()) if span.rev else (P, I)

    def spill(self, points: np.ndarray, ids: np.ndarray) -> Span:
        """Append a curve's points (m, d) and ids (m,) to the spill file; its span."""
        with open(self.root / "client.pts", "ab") as f:
            np.ascontiguousarray(points, dtype="<f8").tofile(f)
        with open(self.root / "client.ids", "ab") as f:
            np.ascontiguousarray(ids, dtype="<i8").tofile(f)
        lo = self._spilled
        self._spilled += len(points)
        return Span(SPILL, lo, self._spilled)

    def curve(self, plan: CurvePlan) -> Curve:
        """The curve a plan stands for, read from the store."""
        parts = [self.read(s) for s in plan.spans]
        if len(parts) == 1:  # (its own arrays, no copy)
            P, I = parts[0]
        elif parts:
            P, I = np.vstack([p for p, _ in parts]), np.concatenate([i for _, i in parts])
        else:
            P, I = np.zeros((0, self.dim)), np.zeros(0, np.int64)
        return Curve(P, plan.start, plan.end, plan.closed, I)

    def keep(self, curve: Curve) -> CurvePlan:
        """A curve made on the client, spilled: its plan."""
        return CurvePlan([self.spill(curve.points, curve.indices)], curve.start, curve.end, curve.closed)


class StoredNetwork:
    """A network whose nodes are in memory and whose curves are plans read from a
    :class:`PieceStore` (the store must outlive it).

    Attributes
    ----------
    nodes : (n, d) ndarray of float
    plans : list of CurvePlan
    store : PieceStore
    parameters, stats : dict
    """

    def __init__(self, nodes: np.ndarray, plans: list[CurvePlan], store: PieceStore, parameters=None, stats=None):
        self.nodes = np.asarray(nodes, dtype=float)
        self.plans = plans
        self.store = store
        self.parameters = dict(parameters or {})
        self.stats = dict(stats or {})

    @property
    def dimension(self) -> int:
        return int(self.nodes.shape[1])

    @property
    def n_nodes(self) -> int:
        return int(len(self.nodes))

    @property
    def n_curves(self) -> int:
        return len(self.plans)

    @property
    def edges(self) -> np.ndarray:
        """(c, 2) end nodes of each curve, -1 for loops without node (:attr:`CurveNetwork.edges`)."""
        return np.array([[-1, -1] if p.start is None else [p.start, p.end] for p in self.plans],
                        dtype=np.int64).reshape(-1, 2)

    @property
    def betti(self) -> tuple[int, int]:
        """:attr:`CurveNetwork.betti`."""
        return betti_numbers(self.n_nodes, self.edges)

    def curve_shapes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Sizes (c,), start and end nodes (c,) (-1: none) and closedness (c,) of the curves,
        from the plans (nothing read)."""
        e = self.edges
        sizes = np.array([p.size for p in self.plans], dtype=np.int64)
        closed = np.array([bool(p.closed) for p in self.plans], dtype=bool)
        return sizes, e[:, 0].copy(), e[:, 1].copy(), closed

    def curves(self) -> Iterator[Curve]:
        """Every curve, in order, read from the store one at a time."""
        for plan in self.plans:
            yield self.store.curve(plan)

    def network(self) -> CurveNetwork:
        """The whole network in memory."""
        return CurveNetwork(self.nodes, list(self.curves()), dict(self.parameters), dict(self.stats))

    def canonical(self) -> "StoredNetwork":
        """The same network in the order of :meth:`CurveNetwork.canonical` (the same nodes,
        curves and points: the curves whose turn depends on their points, loops, are read and
        spilled turned; the others are turned by their plan)."""
        decimals = CANONICAL_DECIMALS
        order, new_id = canonical_node_order(self.nodes, decimals)
        plans = []
        for p in self.plans:
            s = None if p.start is None else int(new_id[p.start])
            e = None if p.end is None else int(new_id[p.end])
            q = CurvePlan(p.spans, s, e, p.closed)
            if needs_points(s, e, p.closed) and q.size:  # (rare: read, turned, spilled)
                q = self.store.keep(_canonical_curve(self.store.curve(q), decimals))
            elif s is not None and e is not None and e < s:
                q = q.reversed()
            plans.append(q)
        ends = np.array([[-1 if p.start is None else p.start, -1 if p.end is None else p.end] for p in plans],
                        dtype=np.int64).reshape(-1, 2)
        ordered = order_by_ends(ends, lambda i: self.store.curve(plans[i]).points, decimals)
        return StoredNetwork(self.nodes[order], [plans[i] for i in ordered], self.store, self.parameters, self.stats)

