"""The result type: :class:`CurveNetwork`, nodes joined by curves.

A curve network is a graph whose vertices are *nodes* (junctions where curves meet, and free
ends) and whose edges are *curves* (polylines through the input points). A closed loop that
meets no other curve has no node at all.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

__all__ = ["Curve", "CurveNetwork", "NODE_KINDS"]

#: The kinds of node, by valence (see :attr:`CurveNetwork.node_kinds`): ``"junction"`` (3 or
#: more curve ends), ``"end"`` (a free end, 1) and ``"other"`` (2, or 0 for a node no curve
#: reaches).
NODE_KINDS = ("junction", "end", "other")


@dataclass
class Curve:
    """One curve segment of a network.

    Parameters
    ----------
    points : (m, d) ndarray of float
        The polyline, in order. An open curve starts at the position of node ``start`` and ends
        at the position of node ``end``.
    start, end : int or None
        Indices of the end nodes; both ``None`` for a closed loop that meets no other curve.
        ``start == end`` for a loop through one node.
    closed : bool
        True for a loop (the last point joins the first).
    indices : (m,) ndarray of int
        Index of the input point behind each polyline point, ``-1`` where the point is not an
        input point (a node position computed by the method, or a smoothed sample).
    """

    points: np.ndarray
    start: int | None
    end: int | None
    closed: bool = False
    indices: np.ndarray | None = None

    def __post_init__(self):
        self.points = np.asarray(self.points, dtype=float)
        if self.indices is None:
            self.indices = np.full(len(self.points), -1, dtype=np.int64)
        else:
            self.indices = np.asarray(self.indices, dtype=np.int64)

    @property
    def length(self) -> float:
        """Arc length of the polyline (closing segment included for a loop)."""
        p = self.points
        if len(p) < 2:
            return 0.0
        if self.closed:
            p = np.vstack([p, p[:1]])
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())

    def reversed(self) -> "Curve":
        """The same curve traversed the other way."""
        return Curve(self.points[::-1].copy(), self.end, self.start, self.closed, self.indices[::-1].copy())


@dataclass
class CurveNetwork:
    """A reconstructed curve network.

    Parameters
    ----------
    nodes : (n, d) ndarray of float
        Node coordinates, ``d`` = 2 or 3.
    curves : list of Curve
        The curve segments.
    parameters : dict
        The parameters the method used (given or estimated), by name.
    stats : dict
        Counts and timings: ``N_n``, ``N_c``, ``N_d`` and ``time`` (seconds per stage).

    Notes
    -----
    Derived values (valence, Betti numbers) are computed on demand and cached; do not change
    ``nodes`` or ``curves`` in place after reading them.
    """

    nodes: np.ndarray
    curves: list[Curve]
    parameters: dict[str, Any] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        self.nodes = np.asarray(self.nodes, dtype=float)
        if self.nodes.ndim != 2:
            self.nodes = self.nodes.reshape(0, self.nodes.shape[-1] if self.nodes.ndim else 3)

    # ------------------------------------------------------------------ derived values
    @property
    def dimension(self) -> int:
        """Number of coordinates, 2 or 3."""
        if self.nodes.shape[1]:
            return int(self.nodes.shape[1])
        for c in self.curves:
            return int(c.points.shape[1])
        return 3

    @property
    def n_nodes(self) -> int:
        return int(len(self.nodes))

    @property
    def n_curves(self) -> int:
        return len(self.curves)

    @property
    def edges(self) -> np.ndarray:
        """(c, 2) int array of the end nodes of each curve, ``-1`` for loops without nodes."""
        e = np.full((len(self.curves), 2), -1, dtype=np.int64)
        for i, c in enumerate(self.curves):
            if c.start is not None:
                e[i] = (c.start, c.end)
        return e

    @cached_property
    def valence(self) -> np.ndarray:
        """(n,) int array: number of curve ends at each node (a loop through a node counts 2)."""
        v = np.zeros(len(self.nodes), dtype=np.int64)
        e = self.edges
        e = e[e[:, 0] >= 0]
        np.add.at(v, e.ravel(), 1)
        return v

    @property
    def node_kinds(self) -> np.ndarray:
        """(n,) object array of str, the kind of each node (:data:`NODE_KINDS`): ``"end"``
        (valence 1), ``"junction"`` (valence 3 or more) or ``"other"``."""
        v = self.valence
        kinds = np.full(len(v), "other", dtype=object)
        kinds[v == 1] = "end"
        kinds[v >= 3] = "junction"
        return kinds

    @cached_property
    def betti(self) -> tuple[int, int]:
        """Betti numbers (β0, β1) of the network as a 1-dimensional complex."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = len(self.nodes)
        e = self.edges
        free_loops = int((e[:, 0] < 0).sum())
        e = e[e[:, 0] >= 0]
        if n:
            g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
            comps = connected_components(g, directed=False)[0]
        else:
            comps = 0
        b0 = comps + free_loops
        b1 = len(e) - n + comps + free_loops
        return int(b0), int(b1)

    @property
    def lengths(self) -> np.ndarray:
        """(c,) float array of curve lengths."""
        return np.array([c.length for c in self.curves], dtype=float)

    # ------------------------------------------------------------------ conversions
    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready dictionary of the curvenet format, version 1."""
        return {
            "format": "curvenet",
            "version": 1,
            "dimension": self.dimension,
            "nodes": self.nodes.tolist(),
            "curves": [
                {
                    "points": c.points.tolist(),
                    "start": None if c.start is None else int(c.start),
                    "end": None if c.end is None else int(c.end),
                    "closed": bool(c.closed),
                    "indices": c.indices.tolist(),
                }
                for c in self.curves
            ],
            "parameters": _jsonable(self.parameters),
            "stats": _jsonable(self.stats),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "CurveNetwork":
        """Build a network from the dictionary of :meth:`to_dict` (as read from JSON).

        Raises
        ------
        FormatError
            When the dictionary is not a curvenet network.
        """
        from .errors import FormatError

        if not isinstance(data, dict) or data.get("format") != "curvenet":
            raise FormatError("not a curvenet network (missing \"format\": \"curvenet\")")
        try:
            d = int(data.get("dimension", 3))
            nodes = np.asarray(data["nodes"], dtype=float).reshape(-1, d)
            curves = []
            for c in data["curves"]:
                pts = np.asarray(c["points"], dtype=float).reshape(-1, d)
                curves.append(
                    Curve(pts, c.get("start"), c.get("end"), bool(c.get("closed", False)), c.get("indices"))
                )
        except (KeyError, TypeError, ValueError) as exc:
            raise FormatError(f"malformed curvenet network: {exc}") from None
        n = len(nodes)
        for c in curves:
            for v in (c.start, c.end):
                if v is not None and not (0 <= v < n):
                    raise FormatError(f"malformed curvenet network: node index {v} out of range")
        return cls(nodes, curves, dict(data.get("parameters", {})), dict(data.get("stats", {})))

    def canonical(self, decimals: int = 6) -> "CurveNetwork":
        """The same network with nodes and curves in a canonical order.

        Nodes are sorted by their rounded coordinates; each open curve runs from its lower to
        its higher node id (ties broken by the polyline); a free closed loop starts at its
        lexicographically smallest point. Two networks that differ only in the order of nodes
        and curves have equal canonical forms.
        """
        r = np.round(self.nodes, decimals)
        order = np.lexsort(r.T[::-1]) if len(r) else np.zeros(0, dtype=np.int64)
        new_id = np.empty(len(order), dtype=np.int64)
        new_id[order] = np.arange(len(order))
        curves = []
        for c in self.curves:
            s = None if c.start is None else int(new_id[c.start])
            e = None if c.end is None else int(new_id[c.end])
            cc = Curve(c.points.copy(), s, e, c.closed, c.indices.copy())
            if s is None and c.closed and len(cc.points):
                k = _lexmin(np.round(cc.points, decimals))
                cc.points = np.roll(cc.points, -k, axis=0)
                cc.indices = np.roll(cc.indices, -k)
                rev = cc.reversed()
                rev.points = np.roll(rev.points, 1, axis=0)
                rev.indices = np.roll(rev.indices, 1)
                if _key(rev, decimals) < _key(cc, decimals):
                    cc = rev
            elif s is not None and (e < s or (e == s and _key(cc.reversed(), decimals) < _key(cc, decimals))):
                cc = cc.reversed()
            curves.append(cc)
        curves.sort(key=lambda c: _key(c, decimals))
        return CurveNetwork(self.nodes[order], curves, dict(self.parameters), dict(self.stats))

    def to_networkx(self):
        """The network as a ``networkx.MultiGraph``: one node per network node, one edge per curve.

        Returns
        -------
        networkx.MultiGraph
            Nodes ``0 .. n-1`` are the network's nodes, with attributes ``pos`` (tuple of d
            floats), ``valence``, ``kind`` (``"junction"`` for valence >= 3, ``"end"`` for
            valence 1, ``"other"``) and ``anchor=False``. Curve ``i`` is the edge with key ``i``
            between its end nodes, with attributes ``curve`` (= i), ``points`` ((m, d) array,
            from node ``start`` to node ``end``), ``indices`` ((m,) input point indices),
            ``closed``, ``length``, ``start`` and ``end``. The graph attributes hold
            ``dimension`` and ``parameters``.

        Notes
        -----
        A closed loop that meets no other curve has no node. So that it is not lost and the
        graph keeps the network's Betti numbers, such a loop gets an *anchor* node: node
        ``n + j`` for the ``j``-th free loop, at the loop's first point, with ``kind="loop"``,
        ``anchor=True`` and valence 2; the loop is a self-loop edge on it (``start`` and
        ``end`` of the edge data stay ``None``). Remove nodes with ``anchor=True`` to drop the
        free loops.

        Raises
        ------
        MissingDependencyError
            When networkx is not installed (extra ``io``).
        """
        from .errors import require

        nx = require("networkx", "CurveNetwork.to_networkx", "io")
        g = nx.MultiGraph(dimension=self.dimension, parameters=dict(self.parameters))
        val = self.valence
        for j, p in enumerate(self.nodes):
            v = int(val[j])
            kind = "junction" if v >= 3 else ("end" if v == 1 else "other")
            g.add_node(j, pos=tuple(float(x) for x in p), valence=v, kind=kind, anchor=False)
        n_anchor = len(self.nodes)
        for i, c in enumerate(self.curves):
            if c.start is None:
                a = n_anchor
                n_anchor += 1
                first = c.points[0] if len(c.points) else np.zeros(self.dimension)
                g.add_node(a, pos=tuple(float(x) for x in first), valence=2, kind="loop", anchor=True)
                s = e = a
            else:
                s, e = int(c.start), int(c.end)
            g.add_edge(s, e, key=i, curve=i, points=c.points, indices=c.indices, closed=bool(c.closed),
                       length=c.length, start=c.start, end=c.end)
        return g

    def __repr__(self) -> str:
        return (
            f"CurveNetwork(dimension={self.dimension}, nodes={self.n_nodes}, "
            f"curves={self.n_curves}, betti={self.betti})"
        )


def _lexmin(p: np.ndarray) -> int:
    return int(np.lexsort(p.T[::-1])[0])


def _key(c: Curve, decimals: int):
    s = -1 if c.start is None else c.start
    e = -1 if c.end is None else c.end
    return (s, e, tuple(np.round(c.points, decimals).ravel().tolist()))


def _jsonable(obj):
    """Convert numpy scalars and arrays inside dicts/lists to plain Python values."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj
