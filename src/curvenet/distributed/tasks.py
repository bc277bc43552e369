"""The tasks of a tiled run, each a plain function that runs on a Dask worker.

1. :func:`scan` -- count and bound one input chunk;
2. :func:`bin_chunk` -- read one chunk and store its points tile by tile (each point in the one
   tile that owns it);
3. :func:`estimate_sample` -- the whole-cloud estimates from whole tiles;
4. :func:`run_tile` -- reconstruct one tile with its halo and cut the result at its box.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager

import numpy as np

from ..methods.robust import Estimates, estimate, reconstruct_robust
from ..neighbors import one_thread
from .cut import TilePieces, cut_network, fit_whole_pieces, store_pieces
from .grid import TileGrid
from .inputs import Chunk, read_chunk, scan_chunk
from .scratch import read_prepared, read_tile, write_part

__all__ = ["scan", "bin_chunk", "estimate_sample", "run_tile", "tile_points", "METHOD_LOCK", "method_slot"]

#: One run of the method at a time per process: the method switches its kernels (compiled or
#: plain Python) through module globals, which is not safe from two threads at once (the
#: ``threads`` scheduler runs several tasks in one process; worker processes run one each).
METHOD_LOCK = threading.Lock()


@contextmanager
def method_slot():
    """The method's run within a task: one at a time per process (:data:`METHOD_LOCK`), on the
    task's own thread (:func:`curvenet.neighbors.one_thread`: a worker has one thread, and the
    workers of a machine share its cores; a task spread over all of them contends with the
    others' tasks)."""
    with METHOD_LOCK, one_thread():
        yield


def scan(chunk: Chunk, columns=None, drop_nonfinite: bool = False):
    """Row count, dimension and bounds of one chunk (see :func:`.inputs.scan_chunk`)."""
    return scan_chunk(chunk, columns=columns, drop_nonfinite=drop_nonfinite)


def bin_chunk(chunk: Chunk, index: int, grid: TileGrid, root: str, columns=None,
              drop_nonfinite: bool = False) -> dict:
    """Store the points of one chunk in the scratch store, tile by tile.

    Returns
    -------
    dict
        Tile key -> number of points of this chunk it owns.
    """
    pts = read_chunk(chunk, columns=columns, drop_nonfinite=drop_nonfinite)
    ids = chunk.offset + np.arange(len(pts), dtype=np.int64)
    fin = np.isfinite(pts).all(axis=1)
    if not fin.all():  # (only with drop_nonfinite: read_chunk raises otherwise)
        pts, ids = pts[fin], ids[fin]
    keys = grid.keys_of(pts)
    uk, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    bounds = np.r_[0, np.cumsum(np.bincount(inv, minlength=len(uk)))]
    out = {}
    for t, key in enumerate(map(tuple, uk.tolist())):
        sel = order[bounds[t]:bounds[t + 1]]
        write_part(root, key, index, pts[sel], ids[sel])
        out[key] = int(len(sel))
    return out


def tile_points(root: str, grid: TileGrid, key, halo: float):
    """The points (n, d) and global ids (n,) of tile ``key``'s box widened by ``halo``."""
    pts, ids = [], []
    for nb in grid.neighbours(key, halo):
        for p, i in read_tile(root, nb):
            m = grid.within(key, p, halo)
            pts.append(p[m])
            ids.append(i[m])
    d = grid.dim
    if not pts:
        return np.zeros((0, d)), np.zeros(0, np.int64)
    return np.vstack(pts), np.concatenate(ids)


def estimate_sample(root: str, keys: list) -> tuple[Estimates, int]:
    """The estimates of the method on the points of whole tiles ``keys`` (their boxes only).

    Returns
    -------
    Estimates
    int
        The number of points they were computed on.
    """
    parts = [p for key in keys for p, _ in read_tile(root, key)]
    P = np.vstack(parts)
    with method_slot():
        return estimate(P), int(len(P))


def run_tile(root: str, grid: TileGrid, key, halo: float, estimates: Estimates, occupied,
             prepared: bool = False) -> TilePieces:
    """Reconstruct tile ``key`` with its halo (the default method, the whole cloud's
    estimates) and cut the network at the tile's box (``occupied``: the keys of every tile
    that holds input points, see :func:`.cut.cut_network`). Under noise the pieces that are
    whole curves are fitted here (:func:`.cut.fit_whole_pieces`); the stitching fits the
    curves that cross a face, once whole. ``prepared``: the estimates' pass stored this box
    (the same ``halo``) prepared (:func:`.scratch.write_prepared`): the method goes on from
    it (the same network; when it is not there, the box is read and prepared again)."""
    got = read_prepared(root, key) if prepared else None
    if got is None:
        P, ids = tile_points(root, grid, key, halo)
        cloud, n = P, len(P)
    else:
        cloud, ids = got
        n = len(cloud.points)
    with method_slot():
        net = reconstruct_robust(cloud, estimates=estimates, fit=False)  # fitted below, or once stitched
        del cloud
        out = cut_network(net, grid, key, ids, occupied)
        out.n_points = int(n)
        out.prepared = got is not None
        if not estimates.clean:  # the method's fit under noise, of the curves this tile holds whole
            out = fit_whole_pieces(out, estimates.sigma)
    return store_pieces(root, out)  # (the client gets where the pieces are, not their points)
