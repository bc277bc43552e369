"""Real ground truth: the real-dev networks (neuron tracings and building wireframes).

Twenty real curve networks with known topology, for developing on data made by people and
instruments: 10 neuron trees (SWC tracings) and 10 LoD2 building wireframes (CityJSON). The
dataset is not shipped with curvenet. It is looked up in the folder named by the environment
variable ``CURVENET_REALDEV``, else in ``../shared/datasets/real-dev`` next to the repository.
Each ``<name>.json`` file holds ``kind``, ``spacing`` (the sampling spacing h at which the
network is well posed), ``nodes`` and ``curves`` (polylines between two nodes); see the
dataset's README.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..errors import FormatError, InputError
from ..network import Curve, CurveNetwork

__all__ = ["KINDS", "root", "available", "names", "load"]

#: The kinds of network in the dataset (the ``kind`` field of a file).
KINDS = ("neuron", "building")

#: Largest distance, as a fraction of the model's spacing, between a curve's end point and its
#: node before the file is rejected (the files store them equal; this only absorbs rounding).
END_TOLERANCE_H = 1e-3


def root() -> Path:
    """The dataset folder.

    ``$CURVENET_REALDEV`` when set; else ``../shared/datasets/real-dev`` relative to the
    source checkout this module lives in, then relative to the current folder; the first
    that exists.
    """
    env = os.environ.get("CURVENET_REALDEV")
    if env:
        return Path(env)
    rel = Path("..") / "shared" / "datasets" / "real-dev"
    candidates = [Path(__file__).resolve().parents[3] / rel, Path.cwd() / rel]
    for c in candidates:
        if c.is_dir() and any(c.glob("*.json")):
            return c.resolve()
    return candidates[0]


def available() -> bool:
    """True when the dataset folder holds at least one model file."""
    r = root()
    return r.is_dir() and any(r.glob("*.json"))


def names(kind: str | None = None) -> list[str]:
    """Names of the models (file stems), sorted; only those of ``kind`` when given.

    Parameters
    ----------
    kind : {"neuron", "building"}, optional
        Keep the models of this kind (by the name's prefix ``nrn_`` / ``bld_``).

    Returns
    -------
    list of str
        Empty when the dataset is missing.

    Raises
    ------
    InputError
        For an unknown kind.
    """
    if kind is not None and kind not in KINDS:
        raise InputError(f"unknown kind {kind!r}; expected one of: {', '.join(KINDS)}")
    if not available():
        return []
    out = sorted(p.stem for p in root().glob("*.json"))
    if kind is not None:
        prefix = {"neuron": "nrn_", "building": "bld_"}[kind]
        out = [n for n in out if n.startswith(prefix)]
    return out


def load(name_or_path, *, contract: bool = True) -> CurveNetwork:
    """Load a real-dev model as a ground-truth network.

    Parameters
    ----------
    name_or_path : str or path
        A model name (``"nrn_c11471_s1066"``, see :func:`names`) looked up in :func:`root`,
        or the path of a model file.
    contract : bool
        Join curves through nodes of valence 2 (a closed curve through its seam node becomes
        a loop without nodes), as :func:`curvenet.metrics.contract` does.

    Returns
    -------
    CurveNetwork
        3D network; curves start and end exactly at their nodes. ``parameters`` holds
        ``model`` (the name), ``kind``, ``h`` (the file's spacing) and ``source`` (the file).

    Raises
    ------
    InputError
        When the file cannot be found.
    FormatError
        When it is not a real-dev model file (missing fields, curves not ending at their
        nodes, node indices out of range).
    """
    p = Path(name_or_path)
    if not p.is_file():
        name = str(name_or_path)
        name = name[:-5] if name.endswith(".json") else name
        p = root() / f"{name}.json"
        if not p.is_file():
            raise InputError(
                f"real-dev model {name_or_path!r} not found (looked in {p.parent}; set CURVENET_REALDEV "
                "to the dataset folder)"
            )
    try:
        data = json.loads(p.read_text())
        h = float(data["spacing"])
        kind = str(data["kind"])
        nodes = np.asarray(data["nodes"], dtype=float).reshape(-1, 3)
        raw = [(np.asarray(c["points"], dtype=float), int(c["start"]), int(c["end"]), bool(c.get("closed", False)))
               for c in data["curves"]]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise FormatError(f"{p}: not a real-dev model file ({exc})") from None
    if not (h > 0 and np.isfinite(h)):
        raise FormatError(f"{p}: spacing must be a positive number, got {h!r}")
    curves = []
    for k, (pts, a, b, closed) in enumerate(raw):
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 2:
            raise FormatError(f"{p}: curve {k} must be a list of at least two 3D points")
        if not (0 <= a < len(nodes) and 0 <= b < len(nodes)):
            raise FormatError(f"{p}: curve {k} has a node index out of range ({a}, {b} for {len(nodes)} nodes)")
        tol = END_TOLERANCE_H * h
        if np.linalg.norm(pts[0] - nodes[a]) > tol or np.linalg.norm(pts[-1] - nodes[b]) > tol:
            raise FormatError(f"{p}: curve {k} does not start and end at its nodes")
        pts = pts.copy()
        pts[0], pts[-1] = nodes[a], nodes[b]
        curves.append(Curve(pts, a, b, closed or a == b))
    net = CurveNetwork(nodes, curves)
    if contract:
        from ..metrics import contract as _contract

        net = _contract(net)
    net.parameters = {"model": p.stem, "kind": kind, "h": h, "source": str(p)}
    return net
