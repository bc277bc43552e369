"""Whether two networks are the same up to small geometric differences (the tiled run's test)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..metrics import densify, hausdorff
from ..network import CurveNetwork

__all__ = ["network_difference"]


def network_difference(a: CurveNetwork, b: CurveNetwork, tol: float) -> str | None:
    """The first difference between two networks, or None when they are the same.

    The same means: a one-to-one matching of the nodes within ``tol``, and under it a
    one-to-one matching of the curves with the same end nodes (free loops with free loops),
    every matched pair within ``tol`` Hausdorff distance (polylines densified to ``tol / 2``).

    Parameters
    ----------
    a, b : CurveNetwork
    tol : float
        In input units (the tiled run's test uses half the median spacing). The densified
        polylines hold curve length / (tol / 2) points each: for exact equality use ``a == b``
        (:meth:`CurveNetwork.__eq__`), not a tiny ``tol``.

    Returns
    -------
    str or None
    """
    if a.n_nodes != b.n_nodes:
        return f"{a.n_nodes} nodes against {b.n_nodes}"
    if a.n_curves != b.n_curves:
        return f"{a.n_curves} curves against {b.n_curves}"
    node_map = np.full(a.n_nodes, -1, dtype=np.int64)
    if a.n_nodes:
        dist, j = cKDTree(b.nodes).query(a.nodes)
        if dist.max() > tol or len(set(j.tolist())) != len(j):
            k = int(np.argmax(dist))
            return f"node {a.nodes[k].round(6).tolist()} has no own partner within {tol:g} (nearest {dist[k]:.3g})"
        node_map = j
    groups: dict = {}
    for i, c in enumerate(b.curves):
        groups.setdefault(_ends(c.start, c.end), []).append(i)
    taken = np.zeros(b.n_curves, dtype=bool)
    for c in a.curves:
        key = _ends(None if c.start is None else int(node_map[c.start]), None if c.end is None else int(node_map[c.end]))
        pa = densify(c.points, tol / 2, closed=c.closed)
        best, where = np.inf, -1
        for i in groups.get(key, []):
            if taken[i]:
                continue
            hd = hausdorff(pa, densify(b.curves[i].points, tol / 2, closed=b.curves[i].closed))
            if hd < best:
                best, where = hd, i
        if where < 0 or best > tol:
            return (f"curve of {len(c.points)} points from {c.points[0].round(6).tolist()} has no partner "
                    f"(closest {best:.3g})")
        taken[where] = True
    return None


def _ends(s, e):
    return (-1, -1) if s is None else tuple(sorted((int(s), int(e))))
