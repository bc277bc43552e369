"""Real ground truth: the curve networks of the CASSIE VR sketches (sketch_graph files).

The dataset (Yu et al., "CASSIE: Curve and Surface Sketching in Immersive Environments",
CHI 2021, MIT licence) is not shipped with curvenet. It is looked up in the folder named by the
environment variable ``CURVENET_CASSIE``, else in ``../shared/datasets/cassie`` next to the
repository. Each ``sketch_graph/*.json`` file lists segments (poly-Bézier curves or lines, each
between two nodes) and nodes; coordinates are in metres.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..errors import FormatError, InputError
from ..network import Curve, CurveNetwork

__all__ = ["FREE_CREATIONS", "root", "available", "study_sketches", "load", "min_separation"]

#: The 16 sketches made freely with the full CASSIE system (not the user-study files).
FREE_CREATIONS = (
    "architecture",
    "architecture-2",
    "chair",
    "computer-mouse",
    "dress",
    "flower",
    "guitar",
    "hat",
    "hmd_modern",
    "hmd_sutherland",
    "monster_head",
    "sewing-machine",
    "shield",
    "teapot",
    "vacuum",
    "vintage_car",
)


def root() -> Path:
    """The dataset folder.

    ``$CURVENET_CASSIE`` when set; else ``../shared/datasets/cassie`` relative to the source
    checkout this module lives in, then relative to the current folder (a clean clone with
    ``shared/`` beside it, the package installed non-editable); the first that exists.
    """
    env = os.environ.get("CURVENET_CASSIE")
    if env:
        return Path(env)
    rel = Path("..") / "shared" / "datasets" / "cassie"
    candidates = [Path(__file__).resolve().parents[3] / rel, Path.cwd() / rel]
    for c in candidates:
        if (c / "sketch_graph").is_dir():
            return c.resolve()
    return candidates[0]


def available() -> bool:
    """True when the sketch_graph folder of the dataset can be found."""
    return (root() / "sketch_graph").is_dir()


def study_sketches() -> list[str]:
    """Names of the user-study sketches (``NN-M-K``: participant, model, system), sorted.

    Their networks were recovered after the study from stroke intersections (the dataset's
    README: "may have some errors"); the benchmark uses them as a check of changes chosen on
    :data:`FREE_CREATIONS`. Empty when the dataset is missing.
    """
    if not available():
        return []
    return sorted(p.stem for p in (root() / "sketch_graph").glob("[0-9][0-9]-*.json"))


def _bezier(ctrl: np.ndarray, step: float) -> np.ndarray:
    """Evaluate one cubic Bézier piece (4, 3) or line (2, 3) at parameter steps giving <= step."""
    poly_len = float(np.linalg.norm(np.diff(ctrl, axis=0), axis=1).sum())
    n = max(int(np.ceil(poly_len / step)), 1)
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    if len(ctrl) == 2:
        return ctrl[0] * (1 - t) + ctrl[1] * t
    if len(ctrl) != 4:
        raise FormatError(f"expected a cubic Bézier piece (4 control points) or a line (2), got {len(ctrl)}")
    u = 1 - t
    return u**3 * ctrl[0] + 3 * u**2 * t * ctrl[1] + 3 * u * t**2 * ctrl[2] + t**3 * ctrl[3]


def load(name_or_path, *, step: float = 0.0005, contract: bool = True, merge_tol: float = 1e-6) -> CurveNetwork:
    """Load a CASSIE sketch graph as a ground-truth network.

    Parameters
    ----------
    name_or_path : str or path
        A sketch name (``"hat"``, see :data:`FREE_CREATIONS`) looked up in
        ``root()/sketch_graph``, or the path of a sketch_graph JSON file.
    step : float
        Largest spacing (metres) of the dense polylines the Bézier segments are evaluated into.
    contract : bool
        Join segments through nodes of valence 2 (strokes split where nothing meets them), as
        :func:`curvenet.metrics.contract` does.
    merge_tol : float
        Nodes closer than this (metres) are merged, and segments shorter than it that join a
        node to itself are dropped (a few sketches have such zero-length segments).

    Returns
    -------
    CurveNetwork
        3D network; curves start and end exactly at their nodes. ``parameters`` holds
        ``model`` (the name), ``h`` = 0.002 (the 2 mm spacing of the benchmark) and
        ``source`` (the file).

    Raises
    ------
    InputError
        When the file cannot be found.
    FormatError
        When it is not a sketch_graph file.
    """
    p = Path(name_or_path)
    if not p.is_file():
        name = str(name_or_path)
        name = name[:-5] if name.endswith(".json") else name
        p = root() / "sketch_graph" / f"{name}.json"
        if not p.is_file():
            raise InputError(
                f"CASSIE sketch {name_or_path!r} not found (looked in {p.parent}; set CURVENET_CASSIE "
                "to the dataset folder)"
            )
    try:
        data = json.loads(p.read_text())
        nodes_in = {int(n["id"]): np.asarray(n["position"], dtype=float) for n in data["nodes"]}
        segs = [(np.asarray(s["ctrl_pts"], dtype=float), [int(v) for v in s["nodes"]]) for s in data["segments"]]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise FormatError(f"{p}: not a CASSIE sketch_graph file ({exc})") from None

    # merge coincident nodes (first id wins), renumber densely in id order
    ids = sorted(nodes_in)
    pos = np.array([nodes_in[i] for i in ids]).reshape(-1, 3)
    from scipy.spatial import cKDTree

    rep = np.arange(len(ids))
    for a, b in sorted(cKDTree(pos).query_pairs(merge_tol)) if len(pos) else []:
        ra, rb = rep[a], rep[b]
        while rep[ra] != ra:
            ra = rep[ra]
        while rep[rb] != rb:
            rb = rep[rb]
        rep[max(ra, rb)] = min(ra, rb)
    for i in range(len(rep)):
        r = i
        while rep[r] != r:
            r = rep[r]
        rep[i] = r
    keep = np.unique(rep)
    new = np.full(len(ids), -1, dtype=np.int64)
    new[keep] = np.arange(len(keep))
    index_of = {nid: int(new[rep[k]]) for k, nid in enumerate(ids)}
    nodes = pos[keep]

    curves = []
    for ctrl, (a, b) in segs:
        if ctrl.ndim != 3 or ctrl.shape[-1] != 3:
            raise FormatError(f"{p}: segment control points must be a list of pieces of 3D points")
        pts = np.vstack([_bezier(c, step)[(0 if k == 0 else 1):] for k, c in enumerate(ctrl)])
        na, nb = index_of[a], index_of[b]
        # orient the polyline to its nodes
        if np.linalg.norm(pts[0] - nodes[na]) + np.linalg.norm(pts[-1] - nodes[nb]) > np.linalg.norm(
            pts[0] - nodes[nb]
        ) + np.linalg.norm(pts[-1] - nodes[na]):
            pts = pts[::-1]
        length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
        if na == nb and length < merge_tol:
            continue
        pts[0], pts[-1] = nodes[na], nodes[nb]
        curves.append(Curve(pts, na, nb, na == nb))
    net = CurveNetwork(nodes, curves)
    # drop nodes no segment uses
    used = np.flatnonzero(net.valence > 0)
    if len(used) < len(nodes):
        remap = np.full(len(nodes), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        net = CurveNetwork(
            nodes[used], [Curve(c.points, int(remap[c.start]), int(remap[c.end]), c.closed) for c in curves]
        )
    if contract:
        from ..metrics import contract as _contract

        net = _contract(net)
    net.parameters = {"model": p.stem, "h": 0.002, "source": str(p)}
    return net


def min_separation(net: CurveNetwork, *, within: float) -> float:
    """The smallest distance between two curves of a network that share no node.

    Parameters
    ----------
    net : CurveNetwork
        A network with densely sampled curves.
    within : float
        Only distances below this are searched (larger ones are reported as ``inf``).

    Returns
    -------
    float
        The distance, or ``inf`` when no two such curves come closer than ``within``. Curves
        that touch without a junction give 0.
    """
    from scipy.spatial import cKDTree

    pts, lab = [], []
    for i, c in enumerate(net.curves):
        pts.append(c.points)
        lab.append(np.full(len(c.points), i))
    if len(pts) < 2:
        return float("inf")
    P, L = np.vstack(pts), np.concatenate(lab)
    ends = [set() if c.start is None else {c.start, c.end} for c in net.curves]
    pairs = cKDTree(P).query_pairs(within, output_type="ndarray")
    if not len(pairs):
        return float("inf")
    la, lb = L[pairs[:, 0]], L[pairs[:, 1]]
    cand = la != lb
    pairs, la, lb = pairs[cand], la[cand], lb[cand]
    ok = np.array([not (ends[a] & ends[b]) for a, b in zip(la, lb)], dtype=bool)
    if not ok.any():
        return float("inf")
    d = np.linalg.norm(P[pairs[ok, 0]] - P[pairs[ok, 1]], axis=1)
    return float(d.min())
