"""Baseline: the Euclidean minimum spanning tree split into curves (the paper's Figure 8).

The EMST of the points is a tree through every point; its vertices of degree other than 2
(free ends of degree 1, branchings of degree >= 3) become nodes and the paths between them
become curves. It cannot produce a closed loop, and every small zigzag caused by noise leaves a
spur: that is what the comparison is meant to show [Figueiredo and Miranda Gomes 1994].
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from ..network import Curve, CurveNetwork
from ..neighbors import knn
from ..validate import as_points

__all__ = ["reconstruct_emst", "emst_edges", "emst_edges_each"]


def emst_edges(points: np.ndarray, *, k: int = 12) -> np.ndarray:
    """Edges of the minimum spanning forest of the symmetrised k-nearest-neighbour graph.

    Parameters
    ----------
    points : (N, d) ndarray
        Points, ideally sorted lexicographically (ties between equal lengths are broken by the
        order of the points).
    k : int
        Neighbours per point. The result is the exact EMST whenever every EMST edge joins two
        points among each other's ``k`` nearest neighbours (almost always for points along
        curves); a disconnected kNN graph gives a forest.

    Returns
    -------
    (E, 2) ndarray of int64
        Edges ``(i, j)`` with ``i < j``, sorted.
    """
    return emst_edges_each([points], [k])[0]


def emst_edges_each(blocks, ks) -> list[np.ndarray]:
    """:func:`emst_edges` of several point sets at once: one spanning-tree computation over
    the block-diagonal graph of all of them instead of one per set.

    Parameters
    ----------
    blocks : sequence of (n_b, d) ndarray
        The point sets.
    ks : sequence of int
        Neighbours per point of each set's graph (clipped to ``n_b - 1``).

    Returns
    -------
    list of (E_b, 2) ndarray of int64
        Per set, its edges as :func:`emst_edges` returns them (ids into that set). The same
        edges as one call per set: no edge joins two sets, every set's weights are its own, and
        Kruskal's algorithm (scipy's, with a stable sort of the weights) meets each set's edges
        in the order it meets them alone.

    Notes
    -----
    Many small sets (the regions and chains the robust method reads with their trees) cost
    mostly the fixed cost of each sparse-graph call; here that cost is paid once.
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import minimum_spanning_tree

    sizes = np.array([len(b) for b in blocks], dtype=np.int64)
    base = np.r_[0, np.cumsum(sizes)]
    total = int(base[-1])
    keys, weights = [np.zeros(0, dtype=np.int64)], [np.zeros(0)]
    for b, (X, k) in enumerate(zip(blocks, ks)):
        n = int(sizes[b])
        if n < 2:
            continue
        dist, idx = knn(X, int(k))
        rows = np.repeat(np.arange(n), idx.shape[1])
        cols = idx.ravel()
        i, j = np.minimum(rows, cols), np.maximum(rows, cols)
        # explicit zeros count as "no edge" in csgraph: shift every weight of the set by the
        # same tiny amount
        scale = float(np.median(dist[:, 0])) if dist.size else 1.0
        w = dist.ravel() + max(scale, 1e-300) * 1e-9
        # one weight per undirected pair (the same from both sides: coo would sum duplicates)
        key = i * n + j
        uk, first = np.unique(key, return_index=True)
        keys.append((uk // n + base[b]) * total + (uk % n + base[b]))
        weights.append(w[first])
    key, w = np.concatenate(keys), np.concatenate(weights)
    out = [np.zeros((0, 2), dtype=np.int64) for _ in blocks]
    if not len(key):
        return out
    ui, uj = key // total, key % total
    # the keys are sorted and unique (sets in turn, each row by row, columns ascending): the
    # canonical CSR layout itself, without a COO conversion
    g = csr_matrix((w, uj, np.searchsorted(ui, np.arange(total + 1))), shape=(total, total))
    t = minimum_spanning_tree(g)
    row = np.repeat(np.arange(total), np.diff(t.indptr))
    col = t.indices.astype(np.int64)
    e = np.column_stack([np.minimum(row, col), np.maximum(row, col)])
    e = e[np.lexsort(e.T[::-1])]
    cut = np.searchsorted(e[:, 0], base)
    for b in range(len(blocks)):
        out[b] = e[cut[b]:cut[b + 1]] - base[b]
    return out


def reconstruct_emst(points, *, k: int = 12) -> CurveNetwork:
    """Reconstruct a curve network as the EMST split at vertices of degree other than 2.

    Parameters
    ----------
    points : (N, 2) or (N, 3) array_like
        Points along curves, in any order.
    k : int
        Neighbours per point of the graph the spanning tree is taken from (see
        :func:`emst_edges`).

    Returns
    -------
    CurveNetwork
        Nodes at the points of degree 1 or >= 3 of the tree (at those input points), curves
        along the tree paths between them (``indices`` are input point indices). Never a closed
        loop. ``parameters = {"k": k}``; ``stats["time"]`` has ``neighbors`` (kNN and tree) and
        ``tracing``.

    Raises
    ------
    InputError
        For invalid points or ``k < 1``.

    Notes
    -----
    The points are sorted by coordinates first, so the output does not depend on their order.
    O(N k log N).
    """
    if int(k) != k or k < 1:
        raise InputError(f"k must be a positive integer, got {k!r}")
    k = int(k)
    pts = as_points(points)
    n = len(pts)
    order = np.lexsort(pts.T[::-1])
    P = pts[order]
    t0 = time.perf_counter()
    e = emst_edges(P, k=k)
    t1 = time.perf_counter()

    deg = np.bincount(e.ravel(), minlength=n)
    adj_ptr = np.r_[0, np.cumsum(deg)]
    adj = np.empty(2 * len(e), dtype=np.int64)
    fill = adj_ptr[:-1].copy()
    for a, b in e:  # edges are sorted, so adjacency lists are in a canonical order
        adj[fill[a]] = b
        fill[a] += 1
        adj[fill[b]] = a
        fill[b] += 1
    is_node = deg != 2
    node_id = np.full(n, -1, dtype=np.int64)
    nodes_v = np.flatnonzero(is_node)
    node_id[nodes_v] = np.arange(len(nodes_v))
    used = np.zeros(len(adj), dtype=bool)  # directed half-edges already traversed

    def half(a, b):
        lo = adj_ptr[a]
        return lo + int(np.flatnonzero(adj[lo : adj_ptr[a + 1]] == b)[0])

    curves = []
    for v in nodes_v:
        for s in range(adj_ptr[v], adj_ptr[v + 1]):
            if used[s]:
                continue
            path = [v]
            prev, cur = v, adj[s]
            used[s] = True
            while not is_node[cur]:
                path.append(cur)
                a, b = adj[adj_ptr[cur]], adj[adj_ptr[cur] + 1]
                nxt = b if a == prev else a
                prev, cur = cur, nxt
            path.append(cur)
            used[half(cur, prev)] = True
            path = np.asarray(path)
            curves.append(Curve(P[path], int(node_id[v]), int(node_id[cur]), False, order[path]))
    t2 = time.perf_counter()
    net = CurveNetwork(P[nodes_v], curves)
    net.parameters = {"k": k}
    net.stats = {"time": {"neighbors": t1 - t0, "tracing": t2 - t1}}
    return net
