"""The result type: :class:`CurveNetwork`, nodes joined by curves.

A curve network is a graph whose vertices are *nodes* (junctions where curves meet, and free
ends) and whose edges are *curves* (polylines through the input points). A closed loop that
meets no other curve has no node at all.

Networks and curves are plain, **mutable** containers (like a networkx graph): their arrays and
lists can be changed in place, and every derived value (valence, Betti numbers, lengths) is
recomputed from them on each access, so it never goes stale. ``==`` compares two networks
exactly, :meth:`CurveNetwork.allclose` within a tolerance; both compare nodes and curves in
the order they are stored (compare :meth:`CurveNetwork.canonical` forms to ignore the order).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .lengths import step_lengths

if TYPE_CHECKING:  # optional packages, imported by the converters only when called
    import networkx
    import open3d
    import pyvista
    import trimesh

__all__ = ["Curve", "CurveNetwork", "NODE_KINDS"]

#: The kinds of node, by valence (see :attr:`CurveNetwork.node_kinds`): ``"junction"`` (3 or
#: more curve ends), ``"end"`` (a free end, 1) and ``"other"`` (2, or 0 for a node no curve
#: reaches).
NODE_KINDS = ("junction", "end", "other")

#: The function behind :meth:`CurveNetwork.save`, ``f(network, path, **options) -> Path``:
#: :func:`curvenet.save`, handed in by the package when it is imported (which Python always
#: does before any of its modules). The file formats (:mod:`curvenet.io`) are an outer layer
#: this core module never imports, not even inside a function; the package facade, allowed to
#: import them when called, passes its writer in instead (see :func:`_set_file_writer`).
_file_writer: Callable[..., Path] | None = None


def _set_file_writer(writer: Callable[..., Path]) -> None:
    """Set the function behind :meth:`CurveNetwork.save` (called once, by ``curvenet``)."""
    global _file_writer
    _file_writer = writer


@dataclass(eq=False)
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
        input point (a node position computed by the method). A curve fitted under noise
        keeps its samples' indices, its points moved onto the fit.
    """

    points: np.ndarray
    start: int | None
    end: int | None
    closed: bool = False
    indices: np.ndarray = None  # type: ignore[assignment]  # None: all -1, set in __post_init__

    def __post_init__(self) -> None:
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
        return float(step_lengths(np.diff(p, axis=0)).sum())

    def reversed(self) -> "Curve":
        """The same curve traversed the other way."""
        return Curve(self.points[::-1].copy(), self.end, self.start, self.closed, self.indices[::-1].copy())

    def __len__(self) -> int:
        """Number of polyline points."""
        return int(len(self.points))

    def __eq__(self, other: object) -> bool:
        """Exact equality: same end nodes, closedness, points and input indices."""
        if not isinstance(other, Curve):
            return NotImplemented
        return (
            _same_end(self.start, other.start)
            and _same_end(self.end, other.end)
            and bool(self.closed) == bool(other.closed)
            and self.points.shape == other.points.shape
            and bool(np.array_equal(self.points, other.points))
            and bool(np.array_equal(self.indices, other.indices))
        )

    __hash__ = None  # type: ignore[assignment]  # mutable: not hashable

    def allclose(self, other: "Curve", *, rtol: float = 1e-5, atol: float = 1e-8) -> bool:
        """True when ``other`` has the same ends and closedness and points within tolerance.

        Parameters
        ----------
        other : Curve
        rtol, atol : float
            Relative and absolute tolerance of :func:`numpy.allclose` on the (m, d) points.
            Input indices are not compared.

        Returns
        -------
        bool
        """
        return (
            _same_end(self.start, other.start)
            and _same_end(self.end, other.end)
            and bool(self.closed) == bool(other.closed)
            and self.points.shape == other.points.shape
            and bool(np.allclose(self.points, other.points, rtol=rtol, atol=atol))
        )


@dataclass(eq=False)
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
    Mutable: ``nodes``, ``curves`` and the dictionaries may be changed in place; derived values
    (valence, Betti numbers, lengths) are computed on each access. ``len(net)`` is the number
    of curves and iterating over a network yields its curves. ``net_a == net_b`` is exact
    equality of nodes and curves (parameters and stats are not compared); see
    :meth:`allclose` for a tolerance and :meth:`canonical` to ignore the storage order.

    Examples
    --------
    >>> import numpy as np
    >>> net = CurveNetwork(np.array([[0.0, 0], [1, 0]]), [Curve(np.array([[0.0, 0], [1, 0]]), 0, 1)])
    >>> len(net), net.valence.tolist(), net == net.canonical()
    (1, [1, 1], True)
    """

    nodes: np.ndarray
    curves: list[Curve]
    parameters: dict[str, Any] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
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
        """Number of nodes."""
        return int(len(self.nodes))

    @property
    def n_curves(self) -> int:
        """Number of curves."""
        return len(self.curves)

    def __len__(self) -> int:
        """Number of curves."""
        return len(self.curves)

    def __iter__(self) -> Iterator[Curve]:
        """The curves, in order."""
        return iter(self.curves)

    def __eq__(self, other: object) -> bool:
        """Exact equality of the nodes and curves, in order (parameters and stats aside)."""
        if not isinstance(other, CurveNetwork):
            return NotImplemented
        return (
            self.dimension == other.dimension
            and self.nodes.shape == other.nodes.shape
            and bool(np.array_equal(self.nodes, other.nodes))
            and len(self.curves) == len(other.curves)
            and all(a == b for a, b in zip(self.curves, other.curves))
        )

    __hash__ = None  # type: ignore[assignment]  # mutable: not hashable

    def allclose(self, other: "CurveNetwork", *, rtol: float = 1e-5, atol: float = 1e-8) -> bool:
        """True when ``other`` has the same topology and coordinates within tolerance.

        The same node count and curve count, each curve with the same end nodes, closedness and
        number of points, and every coordinate within :func:`numpy.allclose`'s tolerance. Nodes
        and curves are compared in storage order: compare ``a.canonical()`` with
        ``b.canonical()`` to ignore it.

        Parameters
        ----------
        other : CurveNetwork
        rtol, atol : float
            Relative and absolute tolerance, as in :func:`numpy.allclose`.

        Returns
        -------
        bool
        """
        return (
            self.dimension == other.dimension
            and self.nodes.shape == other.nodes.shape
            and bool(np.allclose(self.nodes, other.nodes, rtol=rtol, atol=atol))
            and len(self.curves) == len(other.curves)
            and all(a.allclose(b, rtol=rtol, atol=atol) for a, b in zip(self.curves, other.curves))
        )

    @property
    def edges(self) -> np.ndarray:
        """(c, 2) int array of the end nodes of each curve, ``-1`` for loops without nodes."""
        e = np.full((len(self.curves), 2), -1, dtype=np.int64)
        for i, c in enumerate(self.curves):
            if c.start is not None and c.end is not None:
                e[i] = (int(c.start), int(c.end))
        return e

    @property
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

    @property
    def betti(self) -> tuple[int, int]:
        """Betti numbers (β0, β1) of the network as a 1-dimensional complex."""
        return betti_numbers(len(self.nodes), self.edges)

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

    def canonical(self, decimals: int = 6, *, copy: bool = True) -> "CurveNetwork":
        """The same network with nodes and curves in a canonical order.

        Nodes are sorted by their rounded coordinates; each open curve runs from its lower to
        its higher node id (ties broken by the polyline); a free closed loop starts at its
        lexicographically smallest point. Two networks that differ only in the order of nodes
        and curves have equal canonical forms.

        Parameters
        ----------
        decimals : int
            Coordinates are compared rounded to this many decimals.
        copy : bool
            False: a curve kept as it runs shares its ``points`` and ``indices`` arrays with
            this network's (a curve turned round or a loop rolled gets new ones), so that a
            large network built only to be put in order is not held twice.
        """
        order, new_id = canonical_node_order(self.nodes, decimals)
        curves = []
        for c in self.curves:
            s = None if c.start is None else int(new_id[c.start])
            e = None if c.end is None else int(new_id[c.end])
            cc = Curve(c.points.copy(), s, e, c.closed, c.indices.copy()) if copy else Curve(c.points, s, e, c.closed, c.indices)
            curves.append(_canonical_curve(cc, decimals))
        curves = [curves[i] for i in _key_order(curves, decimals)]
        return CurveNetwork(self.nodes[order], curves, dict(self.parameters), dict(self.stats))

    def to_networkx(self) -> "networkx.MultiGraph":
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
            if c.start is None or c.end is None:
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


    def polyline_vertices(self) -> tuple[np.ndarray, list[np.ndarray]]:
        """One vertex list shared by all curves, node vertices shared by the curves meeting there.

        Returns
        -------
        vertices : (V, 3) ndarray of float
            Node positions first (vertex ``i`` is node ``i``), then the inner points of each
            curve in order; 2D networks get z = 0.
        polylines : list of (m,) ndarray of int
            Vertex indices of each curve in order; a closed curve repeats its first vertex at
            the end.
        """
        d = self.dimension
        blocks = [self.nodes.reshape(-1, d)]
        polylines = []
        nv = len(self.nodes)
        for c in self.curves:
            pts = c.points.reshape(-1, d)
            if c.start is not None:
                inner = pts[1:-1] if len(pts) >= 2 else pts[:0]
                ids = np.concatenate([[c.start], nv + np.arange(len(inner)), [c.end]])
            else:
                inner = pts
                ids = nv + np.arange(len(inner))
                if c.closed and len(ids):
                    ids = np.append(ids, ids[0])
            blocks.append(inner)
            nv += len(inner)
            polylines.append(ids.astype(np.int64))
        v = np.vstack(blocks)
        if d == 2:
            v = np.column_stack([v, np.zeros(len(v))])
        return v, polylines

    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The network as straight segments between shared vertices.

        Returns
        -------
        vertices : (V, 3) ndarray of float
            As in :meth:`polyline_vertices` (nodes first).
        segments : (S, 2) ndarray of int
            Vertex indices of each segment, curve after curve, in polyline order.
        curve_ids : (S,) ndarray of int
            The curve each segment belongs to.
        """
        v, lines = self.polyline_vertices()
        seg = [np.column_stack([ids[:-1], ids[1:]]) for ids in lines]
        cid = [np.full(len(ids) - 1, i, dtype=np.int64) for i, ids in enumerate(lines) if len(ids) > 1]
        seg = [s for s in seg if len(s)]
        if not seg:
            return v, np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64)
        return v, np.vstack(seg).astype(np.int64), np.concatenate(cid)

    def to_open3d(self) -> "open3d.geometry.LineSet":
        """The network as an Open3D ``LineSet`` (package ``open3d``, extra ``convert``).

        Returns
        -------
        open3d.geometry.LineSet
            Points (V, 3) as in :meth:`polyline_vertices` (nodes first, 2D networks at z = 0),
            one line per segment (see :meth:`segments`); the segments of curve ``i`` share
            colour ``i`` of a fixed ten-colour palette.

        Raises
        ------
        MissingDependencyError
            When open3d is not installed.
        """
        from .errors import require

        o3d = require("open3d", "CurveNetwork.to_open3d", "convert")
        v, seg, cid = self.segments()
        ls = o3d.geometry.LineSet()
        ls.points = o3d.utility.Vector3dVector(np.ascontiguousarray(v, dtype=np.float64))
        ls.lines = o3d.utility.Vector2iVector(np.ascontiguousarray(seg, dtype=np.int32))
        if len(seg):
            ls.colors = o3d.utility.Vector3dVector(_curve_rgb(cid))
        return ls

    def to_pyvista(self) -> "pyvista.PolyData":
        """The network as a PyVista ``PolyData`` of polylines (package ``pyvista``, extra ``convert``).

        Returns
        -------
        pyvista.PolyData
            Points (V, 3) as in :meth:`polyline_vertices`, one polyline cell per curve (a closed
            loop repeats its first point), cell data ``curve_id`` and point data ``node_id``
            (node index, -1 elsewhere).

        Raises
        ------
        MissingDependencyError
            When pyvista is not installed.
        """
        from .errors import require

        pv = require("pyvista", "CurveNetwork.to_pyvista", "convert")
        v, lines = self.polyline_vertices()
        keep = [i for i, ids in enumerate(lines) if len(ids) >= 2]
        cells = np.concatenate([np.concatenate([[len(lines[i])], lines[i]]) for i in keep]) if keep else None
        poly = pv.PolyData(np.ascontiguousarray(v, dtype=np.float64), lines=cells)
        poly.cell_data["curve_id"] = np.asarray(keep, dtype=np.int64)
        node_id = np.full(len(v), -1, dtype=np.int64)
        node_id[: self.n_nodes] = np.arange(self.n_nodes)
        poly.point_data["node_id"] = node_id
        return poly

    def to_trimesh(self) -> "trimesh.path.Path3D":
        """The network as a trimesh ``Path3D``: one ``Line`` entity per curve (extra ``surface``).

        Returns
        -------
        trimesh.path.Path3D
            Vertices (V, 3) as in :meth:`polyline_vertices` (nodes first, 2D networks at
            z = 0); entity ``i`` is curve ``i`` (a closed loop repeats its first vertex).

        Raises
        ------
        MissingDependencyError
            When trimesh is not installed.
        """
        from .errors import require

        trimesh = require("trimesh", "CurveNetwork.to_trimesh", "surface")
        from trimesh.path.entities import Line

        v, lines = self.polyline_vertices()
        entities = [Line(points=ids) for ids in lines if len(ids) >= 2]
        return trimesh.path.Path3D(entities=entities, vertices=v, process=False)

    def save(self, path: str | Path, **options: Any) -> Path:
        """Write the network to ``path``, the format chosen by the extension, atomically.

        ``net.save(p, **options)`` is :func:`curvenet.save` ``(net, p, **options)``: its
        documentation lists the formats, the writers' options and the errors;
        :func:`curvenet.load` reads a ``.json`` back (``load(p) == net``).

        Parameters
        ----------
        path : str or Path
        **options
            As :func:`curvenet.save`.

        Returns
        -------
        Path
            The written file.
        """
        if _file_writer is None:  # only when this module was loaded without its package
            from .errors import OutputError

            raise OutputError("CurveNetwork.save needs the curvenet package imported (import curvenet)")
        return _file_writer(self, path, **options)

    def __repr__(self) -> str:
        return (
            f"CurveNetwork(dimension={self.dimension}, nodes={self.n_nodes}, "
            f"curves={self.n_curves}, betti={self.betti})"
        )


def _same_end(a: int | None, b: int | None) -> bool:
    return (a is None and b is None) or (a is not None and b is not None and int(a) == int(b))


def _curve_rgb(curve_ids: np.ndarray) -> np.ndarray:
    """(S, 3) float colours in [0, 1] cycling through a fixed qualitative palette by curve id."""
    palette = np.array(_PALETTE, dtype=np.float64) / 255.0
    return palette[np.asarray(curve_ids) % len(palette)]


#: Curve colours of :meth:`CurveNetwork.to_open3d` (matplotlib's tab10), as 8-bit RGB.
_PALETTE = (
    (31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
    (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207),
)


def _lexmin(p: np.ndarray) -> int:
    return int(np.lexsort(p.T[::-1])[0])


def betti_numbers(n: int, edges: np.ndarray) -> tuple[int, int]:
    """Betti numbers (β0, β1) of a network of ``n`` nodes and curves with end nodes ``edges``
    ((c, 2), -1 for a loop without node) as a 1-dimensional complex."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
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


def canonical_node_order(nodes: np.ndarray, decimals: int) -> tuple[np.ndarray, np.ndarray]:
    """The canonical order of nodes (n, d), by their coordinates rounded to ``decimals``: the
    (n,) order and the (n,) new id of each node."""
    r = np.round(nodes, decimals)
    order = np.lexsort(r.T[::-1]) if len(r) else np.zeros(0, dtype=np.int64)
    new_id = np.empty(len(order), dtype=np.int64)
    new_id[order] = np.arange(len(order))
    return order, new_id


def needs_points(start: int | None, end: int | None, closed: bool) -> bool:
    """Whether :func:`_canonical_curve` reads a curve's points to turn it (a free loop, or a
    loop through one node); otherwise its end node ids alone decide."""
    return (start is None and closed) or (start is not None and start == end)


def _canonical_curve(cc: Curve, decimals: int) -> Curve:
    """A curve (its node ids already canonical) turned as :meth:`CurveNetwork.canonical` runs
    it: an open curve from its lower to its higher node id (ties broken by the polyline), a
    free closed loop from its lexicographically smallest point, in the direction of the smaller
    key. ``cc`` is changed (a free loop is rolled) or returned when it runs so already."""
    s, e = cc.start, cc.end
    if s is None and cc.closed and len(cc.points):
        k = _lexmin(np.round(cc.points, decimals))
        cc.points = np.roll(cc.points, -k, axis=0)
        cc.indices = np.roll(cc.indices, -k)
        rev = cc.reversed()
        rev.points = np.roll(rev.points, 1, axis=0)
        rev.indices = np.roll(rev.indices, 1)
        if _key(rev, decimals) < _key(cc, decimals):
            cc = rev
    elif s is not None and e is not None and (
        e < s or (e == s and _key(cc.reversed(), decimals) < _key(cc, decimals))
    ):
        cc = cc.reversed()
    return cc


def _key_order(curves: list[Curve], decimals: int) -> list[int]:
    """``sorted(range(len(curves)), key=lambda i: _key(curves[i], decimals))``, with the
    polyline part of the key (a tuple of every rounded coordinate: about 100 bytes a point)
    built only for the curves that share both end nodes with another (see :func:`order_by_ends`)."""
    ends = np.array([[-1 if c.start is None else c.start, -1 if c.end is None else c.end] for c in curves],
                    dtype=np.int64).reshape(-1, 2)
    return order_by_ends(ends, lambda i: curves[i].points, decimals)


def order_by_ends(ends: np.ndarray, points_of: Callable[[int], np.ndarray], decimals: int) -> list[int]:
    """The canonical order of curves: by end node ids ``ends`` ((c, 2), -1 for none), then by
    the rounded polyline among curves with the same ends (``points_of(i)``: curve ``i``'s
    points, asked for those curves only). The order by end nodes is a stable sort of two
    integer columns, and only its runs of equal ends need the rest."""
    order = np.lexsort((ends[:, 1], ends[:, 0]))  # (stable: ties keep the given order)
    out = order.tolist()
    E = ends[order]
    same = np.concatenate([[0], (E[1:] == E[:-1]).all(axis=1).astype(np.int8), [0]])
    runs = np.diff(same)
    for a, b in zip(np.flatnonzero(runs == 1).tolist(), (np.flatnonzero(runs == -1) + 1).tolist()):
        out[a:b] = _by_polyline(out[a:b], points_of, decimals)
    return out


#: The polyline order compares the first this many rounded coordinates first; only curves
#: whose first ones tie are compared whole (a key of every coordinate is about 100 bytes a point).
KEY_PREFIX: int = 12


def _by_polyline(ids: list[int], points_of: Callable[[int], np.ndarray], decimals: int) -> list[int]:
    """``sorted(ids, key=<the tuple of every rounded coordinate of curve i>)``, the same order:
    sorted by the first :data:`KEY_PREFIX` coordinates (a tuple that differs there differs so
    in the whole, and a shorter one is a prefix of itself), then the runs that tie there by the
    whole tuple (both sorts stable)."""
    head = {i: tuple(np.round(points_of(i).ravel()[:KEY_PREFIX], decimals).tolist()) for i in ids}
    out = sorted(ids, key=head.__getitem__)
    j = 0
    while j < len(out):
        k = j + 1
        while k < len(out) and head[out[k]] == head[out[j]]:
            k += 1
        if k - j > 1 and len(head[out[j]]) == KEY_PREFIX:  # (shorter: the whole tuples, equal)
            out[j:k] = sorted(out[j:k], key=lambda i: tuple(np.round(points_of(i), decimals).ravel().tolist()))
        j = k
    return out


def _key(c: Curve, decimals: int) -> tuple[int, int, tuple[float, ...]]:
    s = -1 if c.start is None else c.start
    e = -1 if c.end is None else c.end
    return (s, e, tuple(np.round(c.points, decimals).ravel().tolist()))


def _jsonable(obj: Any) -> Any:
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
