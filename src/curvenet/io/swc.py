"""SWC writer: the network as a forest of samples with parent links (neurons, vessels, roots).

SWC (Cannon et al. 1998, the format of NeuroMorpho.Org) lists one sample a line:
``n T x y z R P`` (sample id from 1, type, position, radius, parent id or -1 for a root).
NEURON, navis, MorphIO, Vaa3D and neuTube read it.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..errors import InputError
from ..network import CurveNetwork
from .numbers import shortest

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
        steps = [np.linalg.norm(np.diff(c.points, axis=0), axis=1) for c in net.curves if len(c.points) > 1]
        step = float(np.median(np.concatenate(steps))) if steps else 0.0
        radius = SWC_RADIUS_FRACTION * step if step > 0 else SWC_FALLBACK_RADIUS
    node_type = np.where(val >= 3, fork_type, np.where(val == 1, end_type, sample_type))
    at_node: list[list[int]] = [[] for _ in range(n)]
    for i, c in enumerate(net.curves):
        if c.start is not None and c.end is not None:
            at_node[int(c.start)].append(i)
            if int(c.end) != int(c.start):
                at_node[int(c.end)].append(i)
    rows: list[tuple[int, int, np.ndarray, int]] = []  # (id, type, position, parent)
    sample_of_node = np.zeros(n, dtype=np.int64)  # 0: not written yet
    used = np.zeros(len(net.curves), dtype=bool)
    cut = 0

    def add(t: int, p: np.ndarray, parent: int) -> int:
        rows.append((len(rows) + 1, int(t), p, parent))
        return len(rows)

    roots = sorted(range(n), key=lambda j: (val[j] != 1, j))
    for root in roots:
        if sample_of_node[root]:
            continue
        sample_of_node[root] = add(node_type[root], net.nodes[root], -1)
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
                parent = int(sample_of_node[j])
                for p in pts[1:-1]:
                    parent = add(sample_type, p, parent)
                if sample_of_node[other]:
                    cut += 1
                else:
                    sample_of_node[other] = add(node_type[other], net.nodes[other], parent)
                    queue.append(other)
    for i, c in enumerate(net.curves):  # loops that meet no node
        if c.start is None and len(c.points):
            parent = -1
            for p in c.points:
                parent = add(sample_type, p, parent)
            cut += bool(c.closed)
    out = [
        f"# curvenet network: {n} nodes, {net.n_curves} curves; {len(rows)} samples",
        f"# types: {sample_type} curve sample, {fork_type} junction, {end_type} free end",
        f"# cycles cut: {cut} (links to an already written sample left out)",
        "# n T x y z R P",
    ]
    r = shortest([radius])
    for sid, t, p, parent in rows:
        xyz = np.zeros(3)
        xyz[:d] = p
        out.append(f"{sid} {t} {shortest(xyz)} {r} {parent}")
    return "\n".join(out) + "\n"
