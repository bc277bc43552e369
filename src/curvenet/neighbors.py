"""Nearest-neighbour queries shared by the methods (k nearest, fixed radius)."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from contextvars import ContextVar

import numpy as np
from scipy.spatial import cKDTree

from ._sigint import held

__all__ = ["knn", "build_tree", "locality_order", "query", "one_thread", "query_threads"]

#: Queries of fewer rows than this run on the calling thread: starting scipy's worker threads
#: costs more than they save there (the repairs query hundreds of small point sets, 0.1-0.3 ms
#: of thread start each; measured in issue 25: at 10^6 noisy points the branched-chain repair's
#: 982 small trees took 0.66 s in their queries, most of it thread start and lock waits).
SERIAL_ROWS = 2048

#: Threads of the neighbour queries in this context (-1: every core; see :func:`one_thread`).
_THREADS: ContextVar[int] = ContextVar("curvenet_query_threads", default=-1)


def query_threads() -> int:
    """The threads a neighbour query takes here: -1 (every core) unless within :func:`one_thread`."""
    return _THREADS.get()


@contextmanager
def one_thread():
    """Run the enclosed work on the calling thread alone: the neighbour queries, and numba's
    parallel loops when numba is loaded (its thread count is the calling thread's own).

    For a task of a Dask worker that has one thread: the workers of a machine share its cores,
    and a task that spread over every core would contend with the others.
    """
    token = _THREADS.set(1)
    numba = sys.modules.get("numba")
    old = numba.get_num_threads() if numba is not None else None
    if numba is not None:
        numba.set_num_threads(1)
    try:
        yield
    finally:
        _THREADS.reset(token)
        if numba is not None:
            numba.set_num_threads(old)


def build_tree(points: np.ndarray) -> cKDTree:
    """A k-d tree over ``points`` ((N, d) float array)."""
    return cKDTree(points, balanced_tree=False, compact_nodes=False)


def query(tree: cKDTree, x: np.ndarray, **kwargs):
    """``tree.query(x, **kwargs)`` that Ctrl-C cannot cut short (see :mod:`curvenet._sigint`:
    scipy's worker threads write into the result arrays while the main thread waits)."""
    with held():
        return tree.query(x, **kwargs)


def knn(points: np.ndarray, k: int, *, tree: cKDTree | None = None, workers: int | None = None,
        ordered: bool = False, rows: np.ndarray | None = None, index_dtype=np.int64):
    """The ``k`` nearest neighbours of every point, the point itself excluded.

    Parameters
    ----------
    points : (N, d) ndarray
        The points.
    k : int
        Number of neighbours; clipped to ``N - 1``.
    tree : cKDTree, optional
        A tree over ``points`` to reuse.
    workers : int, optional
        Threads for the query (-1: all cores); default :func:`query_threads`.
    ordered : bool
        The points are already in a cache-friendly order (e.g. numbered by
        :func:`locality_order`): they are queried as numbered. Otherwise, above 100,000 points,
        they are queried in :func:`locality_order` (the result does not depend on it).
    rows : (R,) ndarray of int, optional
        Only these points (ids into ``points``, queried in the order given): the result has
        their ``R`` rows.
    index_dtype : numpy integer dtype
        Of ``idx`` (``np.int32`` halves the largest array of a large cloud; N < 2**31).

    Returns
    -------
    dist : (N, k) or (R, k) ndarray of float
        Distances, ascending in each row.
    idx : (N, k) or (R, k) ndarray of ``index_dtype``
        Neighbour indices. Ties are broken by index, so the result does not depend on the
        order of the input points up to that relabelling.
    """
    n = len(points)
    workers = query_threads() if workers is None else workers
    sel = None if rows is None else np.asarray(rows, dtype=np.int64)
    n_out = n if sel is None else len(sel)
    if n_out < SERIAL_ROWS:
        workers = 1
    k = int(min(k, max(n - 1, 0)))
    if k == 0:
        return np.zeros((n_out, 0)), np.zeros((n_out, 0), dtype=index_dtype)
    tree = tree if tree is not None else build_tree(points)
    dist = np.empty((n_out, k))
    idx = np.empty((n_out, k), dtype=index_dtype)
    # in blocks of rows, so the (rows, k + 1) query results stay small for large clouds; the
    # rows are visited in spatial order (each query is independent: the result is the same, but
    # consecutive queries touch the same parts of the tree, which is much faster for large N)
    order = None if sel is not None or n <= 100_000 or ordered else locality_order(points)
    step = max(1, (1 << 20) // (k + 1))
    visit = sel if sel is not None else order  # the point ids queried, None: all in turn
    for s in range(0, n_out, step):
        e = min(n_out, s + step)
        ids = np.arange(s, e) if visit is None else visit[s:e]
        out = ids if order is not None else slice(s, e)  # (a slice: no scatter)
        d, i = query(tree, points[s:e] if visit is None else points[ids], k=k + 1, workers=workers)
        d = np.atleast_2d(d)
        i = np.atleast_2d(i)
        if np.array_equal(i[:, 0], ids):  # the usual case: each point first in its own list
            dist[out] = d[:, 1:]
            idx[out] = i[:, 1:]
            continue
        # drop the point itself (it may not be in column 0 when duplicates exist)
        self_mask = i == ids[:, None]
        has_self = self_mask.any(axis=1)
        drop = np.where(has_self[:, None], self_mask, np.arange(k + 1)[None, :] == k)
        keep = ~drop
        dist[out] = d[keep].reshape(e - s, k)
        idx[out] = i[keep].reshape(e - s, k)
    return dist, idx


def locality_order(points: np.ndarray, per_cell: int = 512) -> np.ndarray:
    """A permutation that visits the points cell by cell of a regular grid.

    The grid has about ``per_cell`` points per cell on average; cells are taken in row-major
    order, points within a cell in index order. Used only to order independent per-point work
    for cache locality: results never depend on it.

    Parameters
    ----------
    points : (N, d) ndarray

    Returns
    -------
    (N,) ndarray of int64
    """
    n, d = points.shape
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    lo = points.min(axis=0)
    span = float((points.max(axis=0) - lo).max())
    if not span > 0:
        return np.arange(n, dtype=np.int64)
    g = max(1, int(round((n / per_cell) ** (1.0 / d))))
    code = np.zeros(n, dtype=np.int64)
    for c in range(d):
        q = np.minimum(((points[:, c] - lo[c]) * (g / span)).astype(np.int64), g - 1)
        code = code * g + q
    if g**d <= 1 << 16:  # (numpy sorts 16-bit keys by radix: the same permutation, faster)
        code = code.astype(np.uint16)
    return np.argsort(code, kind="stable").astype(np.int64)
