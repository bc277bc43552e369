"""Networks too large to hold, written one curve at a time.

A network whose curves are read on demand (:class:`curvenet.distributed.StoredNetwork`: the
result of a tiled run, its points in the scratch store) is written to ``.json`` or ``.ply``
without ever holding all its points: the same bytes as :func:`~curvenet.io.network_io.network_to_json`
and :func:`~curvenet.io.network_io.network_to_ply` give for the network in memory (tested), the
document built and written piece by piece (:func:`~curvenet.io.atomic.atomic_write`: all or
nothing). Other formats need the network in memory.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Iterable, Iterator, Protocol

import numpy as np

from ..errors import FormatError
from ..network import Curve, _jsonable
from . import extension
from .atomic import atomic_write
from .polylines import inner_counts, polyline_ids, polyline_segments

__all__ = ["STREAMED", "CurveSource", "write_network_streamed", "json_pieces", "ply_pieces"]

#: The formats written one curve at a time.
STREAMED = (".json", ".ply")
#: Curves are gathered into blocks of about this many points before they are encoded (a JSON
#: block's text is about 75 bytes a point in 3D: 20 MB; 2^20 points held 0.25 GB while writing).
BLOCK_POINTS: int = 1 << 18


class CurveSource(Protocol):
    """What the streamed writers read: nodes and parameters in memory, curves on demand."""

    nodes: np.ndarray
    parameters: dict
    stats: dict

    @property
    def dimension(self) -> int: ...

    def curve_shapes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Sizes (c,), start and end nodes (c,) (-1: none) and closedness (c,) of the curves."""
        ...

    def curves(self) -> Iterator[Curve]:
        """The curves in order."""
        ...


def write_network_streamed(net: CurveSource, path, *, inputs: Iterable = ()) -> Path:
    """Write ``net`` to ``path`` (``.json`` or ``.ply``) one block of curves at a time, atomically.

    Parameters
    ----------
    net : CurveSource
    path : str or Path
    inputs : iterable of paths
        Input files of the run, which must not be overwritten.

    Raises
    ------
    FormatError
        Another extension (see :data:`STREAMED`).
    """
    ext = extension(path)
    if ext not in STREAMED:
        raise FormatError(f"{path}: a network is written piece by piece to {' or '.join(STREAMED)} only, not {ext!r}")
    pieces = json_pieces(net) if ext == ".json" else ply_pieces(net)  # (atomic_write checks the path first)
    return atomic_write(path, pieces, inputs=inputs)


def _blocks(net: CurveSource) -> Iterator[list[Curve]]:
    """The curves in order, in lists of about :data:`BLOCK_POINTS` points."""
    block: list[Curve] = []
    n = 0
    for c in net.curves():
        block.append(c)
        n += len(c.points)
        if n >= BLOCK_POINTS:
            yield block
            block, n = [], 0
    if block:
        yield block


def json_pieces(net: CurveSource) -> Iterator[bytes]:
    """The curvenet JSON document of ``net`` (:func:`~curvenet.io.network_io.network_to_json`,
    the same bytes), piece by piece."""
    try:
        import orjson
    except ImportError:
        orjson = None
    head: dict[str, Any] = {"format": "curvenet", "version": 1, "dimension": net.dimension}
    if orjson is not None and np.isfinite(net.nodes).all():
        opt = orjson.OPT_SERIALIZE_NUMPY
        head["nodes"] = np.ascontiguousarray(net.nodes, dtype=np.float64)
        yield orjson.dumps(head, option=opt)[:-1] + b',"curves":['
        first = True
        for block in _blocks(net):
            docs = []
            for c in block:
                if not np.isfinite(c.points).all():  # (network_to_json hands these to json, which refuses them)
                    raise ValueError("Out of range float values are not JSON compliant")
                docs.append(orjson.dumps({
                    "points": np.ascontiguousarray(c.points, dtype=np.float64),
                    "start": None if c.start is None else int(c.start),
                    "end": None if c.end is None else int(c.end),
                    "closed": bool(c.closed),
                    "indices": np.ascontiguousarray(c.indices, dtype=np.int64),
                }, option=opt))
            if not first:
                yield b","
            yield b",".join(docs)
            first = False
        tail = orjson.dumps({"parameters": _jsonable(net.parameters), "stats": _jsonable(net.stats)})
        yield b"]," + tail[1:] + b"\n"
        return
    head["nodes"] = net.nodes.tolist()
    yield json.dumps(head, allow_nan=False)[:-1] + ', "curves": ['
    first = True
    for block in _blocks(net):
        text = ", ".join(json.dumps({
            "points": c.points.tolist(),
            "start": None if c.start is None else int(c.start),
            "end": None if c.end is None else int(c.end),
            "closed": bool(c.closed),
            "indices": c.indices.tolist(),
        }, allow_nan=False) for c in block)
        yield ("" if first else ", ") + text
        first = False
    tail = json.dumps({"parameters": _jsonable(net.parameters), "stats": _jsonable(net.stats)}, allow_nan=False)
    yield "], " + tail[1:] + "\n"


def ply_pieces(net: CurveSource) -> Iterator[bytes]:
    """The binary PLY of ``net`` (:func:`~curvenet.io.network_io.network_to_ply`, the same
    bytes), piece by piece: the vertex counts come from the curves' shapes, the vertices from
    the curves block by block, the edges from the shapes again."""
    sizes, starts, ends, closed = net.curve_shapes()
    n, d = len(net.nodes), net.dimension
    n_inner = inner_counts(sizes, starts)
    plen = np.where(starts >= 0, n_inner + 2, sizes + (closed & (sizes > 0)))
    n_vert = n + int(n_inner.sum())
    n_edge = int(np.maximum(plen - 1, 0).sum())
    yield (
        "ply\nformat binary_little_endian 1.0\ncomment curvenet network\n"
        f"element vertex {n_vert}\nproperty double x\nproperty double y\nproperty double z\n"
        "property uchar node\n"
        f"element edge {n_edge}\nproperty int vertex1\nproperty int vertex2\n"
        "end_header\n"
    ).encode("ascii")
    yield _vertices(net.nodes, d, node=True)
    for block in _blocks(net):  # each curve's inner points, as polyline_arrays takes them
        inner = [(c.points[1:-1] if c.start is not None else c.points).reshape(-1, d) for c in block]
        yield _vertices(np.vstack(inner), d, node=False)
    base = n  # edges: from the shapes alone, a block of curves at a time
    step = max(1, BLOCK_POINTS // 64)
    for a in range(0, len(sizes), step):
        b = min(a + step, len(sizes))
        ids, off = polyline_ids(sizes[a:b], starts[a:b], ends[a:b], closed[a:b], base)
        seg = polyline_segments(ids, off)[0]
        base += int(n_inner[a:b].sum())
        e = np.zeros(len(seg), dtype=[("vertex1", "<i4"), ("vertex2", "<i4")])
        e["vertex1"], e["vertex2"] = seg.T
        yield e.tobytes()


def _vertices(P: np.ndarray, d: int, *, node: bool) -> bytes:
    """The PLY vertex records of points (m, d) (z = 0 in 2D)."""
    v = np.zeros(len(P), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("node", "u1")])
    v["x"], v["y"] = P[:, 0], P[:, 1]
    if d == 3:
        v["z"] = P[:, 2]
    v["node"] = 1 if node else 0
    return v.tobytes()
