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
from .gc_pause import collector_paused
from .numbers import int_rows_text, join_columns, rows_text, shortest, table_chunks

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
    sizes = np.fromiter((len(c.points) for c in net.curves), dtype=np.int64, count=net.n_curves)
    first = np.concatenate([[0], np.cumsum(sizes)])  # each curve's first row in the stack below
    stack = np.concatenate([c.points if c.points.ndim == 2 else c.points.reshape(-1, d) for c in net.curves]
                           + [np.reshape(net.nodes, (-1, d))])
    if radius is None:
        step = _median_step(stack[:first[-1]], sizes)
        radius = SWC_RADIUS_FRACTION * step if step > 0 else SWC_FALLBACK_RADIUS
    node_type = np.where(val >= 3, fork_type, np.where(val == 1, end_type, sample_type)).tolist()
    with collector_paused():  # (a tuple per run of samples: see curvenet.io.gc_pause)
        runs, cut = _walk(net, val, sizes.tolist(), first.tolist(), node_type, sample_type)
    count = int(runs[:, 1].sum()) if len(runs) else 0
    out = [
        f"# curvenet network: {n} nodes, {net.n_curves} curves; {count} samples",
        f"# types: {sample_type} curve sample, {fork_type} junction, {end_type} free end",
        f"# cycles cut: {cut} (links to an already written sample left out)",
        "# n T x y z R P",
    ]
    lines = _sample_lines(stack, runs, d, shortest([radius]))
    return "".join(["\n".join(out) + "\n"] + [t.decode("utf-8") for t in lines])


def _walk(net: CurveNetwork, val: np.ndarray, sizes: list, first: list, node_type: list,
          sample_type: int) -> tuple[np.ndarray, int]:
    """The runs of samples of :func:`network_to_swc`'s breadth-first walk, in writing order.

    Parameters
    ----------
    net : CurveNetwork
    val : (n,) int ndarray
        Valence of each node.
    sizes, first : list of int
        Points of each curve and its first row in the stack of all curves' points then the nodes.
    node_type : list of int
        SWC type of each node.
    sample_type : int

    Returns
    -------
    runs : (r, 5) int ndarray
        Per run: first row in the stack, number of samples, 1 if written backwards, SWC type,
        parent id of its first sample (each other sample's parent is the sample before).
    cut : int
        Links left out (cycles).
    """
    n = net.n_nodes
    node_row = first[-1]  # the nodes follow the curves in the stack
    starts = [-1 if c.start is None else int(c.start) for c in net.curves]
    ends = [-1 if c.end is None else int(c.end) for c in net.curves]
    at_node: list[list[int]] = [[] for _ in range(n)]
    for i, (a, b) in enumerate(zip(starts, ends)):
        if a >= 0 and b >= 0:
            at_node[a].append(i)
            if b != a:
                at_node[b].append(i)
    runs: list[tuple[int, int, int, int, int]] = []
    count = 0  # samples so far
    sample_of_node = [0] * n  # 0: not written yet
    used = [False] * len(sizes)
    cut = 0
    for root in sorted(range(n), key=(val != 1).tolist().__getitem__):  # free ends first (stable)
        if sample_of_node[root]:
            continue
        runs.append((node_row + root, 1, 0, node_type[root], -1))
        count += 1
        sample_of_node[root] = count
        queue = deque([root])
        while queue:
            j = queue.popleft()
            for i in at_node[j]:
                if used[i]:
                    continue
                used[i] = True
                a, b = starts[i], ends[i]
                other = b if a == j else a
                parent = sample_of_node[j]
                if sizes[i] > 2:  # inner points, from the end at j
                    runs.append((first[i] + 1, sizes[i] - 2, int(a != j), sample_type, parent))
                    count += sizes[i] - 2
                    parent = count
                if sample_of_node[other]:
                    cut += 1
                else:
                    runs.append((node_row + other, 1, 0, node_type[other], parent))
                    count += 1
                    sample_of_node[other] = count
                    queue.append(other)
    for i, c in enumerate(net.curves):  # loops that meet no node
        if c.start is None and sizes[i]:
            runs.append((first[i], sizes[i], 0, sample_type, -1))
            count += sizes[i]
            cut += bool(c.closed)
    return np.array(runs, dtype=np.int64).reshape(-1, 5), cut


def _sample_lines(stack: np.ndarray, runs: np.ndarray, d: int, radius: str) -> list[bytes | bytearray]:
    """The sample lines ``n T x y z R P`` of the runs of samples (see :func:`_walk`), whose
    positions are rows of ``stack`` (m, d), in pieces to be joined."""
    if not len(runs):
        return []
    row, size, back, kind, parent0 = runs.T
    count = int(size.sum())
    run_start = np.concatenate([[0], np.cumsum(size)[:-1]])
    k = np.arange(count) - np.repeat(run_start, size)  # position within the run
    rows = np.repeat(row, size) + np.where(np.repeat(back, size) == 1, np.repeat(size - 1, size) - k, k)
    types = np.repeat(kind, size)
    parents = np.arange(count, dtype=np.int64)  # within a run, the sample before
    parents[run_start] = parent0
    ids = np.arange(1, count + 1)
    if types.max() < _EXACT_INT:  # one table: integers as floats, written as integers
        table = np.zeros((count, 6))
        table[:, 0], table[:, 1], table[:, 5] = ids, types, parents
        table[:, 2:2 + d] = stack[rows]
        return table_chunks(table, [" ", " ", " ", " ", f" {radius} ", "\n"], int_cols=(0, 1, 5))
    xyz = np.zeros((count, 3))
    xyz[:, :d] = stack[rows]
    return [join_columns([
        int_rows_text(np.column_stack([ids, types])),
        rows_text(xyz, "", " ", f" {radius}\n"),
        int_rows_text(parents.reshape(-1, 1)),
    ]).encode()]


#: Integers below this are exact as float64 (a sample type above it is written apart).
_EXACT_INT = 2**53


def _median_step(P: np.ndarray, sizes: np.ndarray) -> float:
    """Median distance between consecutive points of the same curve (0 without any).

    Parameters
    ----------
    P : (N, d) float ndarray
        The points of all curves, one after the other.
    sizes : (C,) int ndarray
        Points of each curve.
    """
    curve = np.repeat(np.arange(len(sizes)), sizes)
    within = curve[1:] == curve[:-1]  # steps from one curve to the next left out
    if not within.any():
        return 0.0
    return float(np.median(step_lengths(np.diff(P, axis=0))[within]))
