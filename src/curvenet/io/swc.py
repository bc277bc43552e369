"""SWC writer: the network as a forest of samples with parent links (neurons, vessels, roots).

SWC (Cannon et al. 1998, the format of NeuroMorpho.Org) lists one sample a line:
``n T x y z R P`` (sample id from 1, type, position, radius, parent id or -1 for a root).
NEURON, navis, MorphIO, Vaa3D and neuTube read it.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..errors import InputError
from ..lengths import step_lengths
from ..network import CurveNetwork
from .numbers import int_rows_text, join_columns, rows_text, shortest, table_text

__all__ = ["network_to_swc", "SWC_UNDEFINED", "SWC_FORK", "SWC_END", "SWC_RADIUS_FRACTION"]

#: SWC sample type "undefined" (the type of curve samples unless ``sample_type`` is given).
SWC_UNDEFINED = 0
#: SWC sample type "fork point" (a junction: valence 3 or more).
SWC_FORK = 5
#: SWC sample type "end point" (a free end: valence 1).
SWC_END = 6
#: Default radius of every sample, as a fraction of the median distance between consecutive
#: curve points (the data hold no radius; a positive one keeps viewers from drawing nothing).
SWC_RADIUS_FRACTION = 0.5
#: Radius of every sample when the curves have no step to measure (points only).
SWC_FALLBACK_RADIUS = 1.0


def network_to_swc(
    net: CurveNetwork,
    *,
    radius: float | None = None,
    sample_type: int = SWC_UNDEFINED,
    fork_type: int = SWC_FORK,
    end_type: int = SWC_END,
) -> str:
    """The network as SWC text: one sample per node and per inner curve point.

    Each connected part becomes one tree, rooted at its lowest-numbered free end (or its
    lowest-numbered node when it has none; a free loop at its first point) and walked breadth
    first: every curve is written from the node it is reached by, one sample per point, each
    sample's parent the one before it. A network with cycles is not a tree: where a curve
    reaches a node already written, its last sample keeps no link to it (the cycle is cut
    there; a comment line gives the count of cut links), so no sample has two parents.

    Parameters
    ----------
    net : CurveNetwork
        2D networks are written with z = 0.
    radius : float, optional
        Radius of every sample; by default :data:`SWC_RADIUS_FRACTION` times the median
        distance between consecutive curve points.
    sample_type, fork_type, end_type : int
        SWC types of the curve samples (and nodes of valence 2), of junctions (valence 3 or
        more) and of free ends (valence 1). Defaults: 0 undefined, 5 fork point, 6 end point
        of the SWC specification; readers that want one neurite type (MorphIO) take e.g. 3
        (dendrite) for all three.

    Returns
    -------
    str
    """
    for name, t in (("sample_type", sample_type), ("fork_type", fork_type), ("end_type", end_type)):
        if not isinstance(t, (int, np.integer)) or t < 0:
            raise InputError(f"SWC {name} must be a non-negative integer, got {t!r}")
    if radius is not None and not (np.isfinite(radius) and radius > 0):
        raise InputError(f"SWC radius must be a positive number, got {radius!r}")
    d = net.dimension
    val = net.valence
    n = net.n_nodes
    if radius is None:
        step = _median_step(net.curves)
        radius = SWC_RADIUS_FRACTION * step if step > 0 else SWC_FALLBACK_RADIUS
    node_type = np.where(val >= 3, fork_type, np.where(val == 1, end_type, sample_type)).tolist()
    at_node: list[list[int]] = [[] for _ in range(n)]
    for i, c in enumerate(net.curves):
        if c.start is not None and c.end is not None:
            at_node[int(c.start)].append(i)
            if int(c.end) != int(c.start):
                at_node[int(c.end)].append(i)
    blocks: list[tuple[np.ndarray, int, int]] = []  # runs of samples: (positions, type, parent of the first)
    count = 0  # samples so far
    sample_of_node = [0] * n  # 0: not written yet (Python lists: the walk reads them one by one)
    used = [False] * len(net.curves)
    cut = 0

    def add(pts: np.ndarray, t: int, parent: int) -> int:
        """Samples at ``pts`` in a chain (each the parent of the next); returns the last id."""
        nonlocal count
        if not len(pts):
            return parent
        blocks.append((pts, int(t), parent))
        count += len(pts)
        return count

    roots = sorted(range(n), key=(val != 1).tolist().__getitem__)  # free ends first (stable)
    for root in roots:
        if sample_of_node[root]:
            continue
        sample_of_node[root] = add(net.nodes[root:root + 1], node_type[root], -1)
        queue = deque([root])
        while queue:
            j = queue.popleft()
            for i in at_node[j]:
                if used[i]:
                    continue
                used[i] = True
                c = net.curves[i]
                a, b = int(c.start or 0), int(c.end or 0)  # curves listed at a node have both
                pts = c.points if a == j else c.points[::-1]
                other = b if a == j else a
                parent = add(pts[1:-1], sample_type, sample_of_node[j])
                if sample_of_node[other]:
                    cut += 1
                else:
                    sample_of_node[other] = add(net.nodes[other:other + 1], node_type[other], parent)
                    queue.append(other)
    for i, c in enumerate(net.curves):  # loops that meet no node
        if c.start is None and len(c.points):
            add(c.points, sample_type, -1)
            cut += bool(c.closed)
    out = [
        f"# curvenet network: {n} nodes, {net.n_curves} curves; {count} samples",
        f"# types: {sample_type} curve sample, {fork_type} junction, {end_type} free end",
        f"# cycles cut: {cut} (links to an already written sample left out)",
        "# n T x y z R P",
    ]
    return "\n".join(out) + "\n" + _sample_lines(blocks, count, d, shortest([radius]))


def _sample_lines(blocks: list, count: int, d: int, radius: str) -> str:
    """The sample lines ``n T x y z R P`` of the runs of samples ``blocks`` (see
    :func:`network_to_swc`), ``count`` samples in all."""
    if not count:
        return ""
    sizes = np.array([len(pts) for pts, _, _ in blocks], dtype=np.int64)
    types = np.repeat(np.array([t for _, t, _ in blocks], dtype=np.int64), sizes)
    parents = np.arange(count, dtype=np.int64)  # within a run, the sample before
    parents[np.concatenate([[0], np.cumsum(sizes)[:-1]])] = [parent for _, _, parent in blocks]
    ids = np.arange(1, count + 1)
    if types.max() < _EXACT_INT:  # one table: integers as floats, written as integers
        table = np.zeros((count, 6))
        table[:, 0], table[:, 1], table[:, 5] = ids, types, parents
        table[:, 2:2 + d] = np.concatenate([pts for pts, _, _ in blocks])
        return table_text(table, [" ", " ", " ", " ", f" {radius} ", "\n"], int_cols=(0, 1, 5))
    xyz = np.zeros((count, 3))
    xyz[:, :d] = np.concatenate([pts for pts, _, _ in blocks])
    return join_columns([
        int_rows_text(np.column_stack([ids, types])),
        rows_text(xyz, "", " ", f" {radius}\n"),
        int_rows_text(parents.reshape(-1, 1)),
    ])


#: Integers below this are exact as float64 (a sample type above it is written apart).
_EXACT_INT = 2**53


def _median_step(curves: list) -> float:
    """Median distance between consecutive points of the same curve (0 without any)."""
    long = [c.points for c in curves if len(c.points) > 1]
    if not long:
        return 0.0
    P = np.concatenate(long)
    steps = step_lengths(np.diff(P, axis=0))
    last = np.cumsum([len(p) for p in long])[:-1] - 1  # the step from one curve to the next
    return float(np.median(np.delete(steps, last)))
