"""Sample points from a ground-truth curve network: spacing, noise, density variation, outliers."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..network import CurveNetwork
from .arith import matvec, norm

__all__ = ["sample"]


def sample(
    network: CurveNetwork,
    *,
    h: float | None = None,
    noise: float = 0.0,
    density_ratio: float = 1.0,
    outliers: float = 0.0,
    rng=0,
) -> tuple[np.ndarray, np.ndarray]:
    """Sample unorganized points along the curves of a network.

    Parameters
    ----------
    network : CurveNetwork
        The true network (e.g. from :func:`curvenet.synth.model`).
    h : float, optional
        The reference spacing: the *mean* distance between consecutive samples along a curve
        (more exactly, the linear density of samples averaged along the curves is ``1 / h``).
        Defaults to ``network.parameters["h"]``. Every distance "in units of h" of the
        benchmark and of :func:`curvenet.metrics.compare` uses this value.
    noise : float
        Standard deviation of the Gaussian noise added to every coordinate of every sample,
        as a fraction of ``h`` (``0.2`` means sigma = 0.2 h per coordinate).
    density_ratio : float
        Ratio (>= 1) between the largest and the smallest local spacing. The linear density of
        samples is ``(1 + a sin(2 pi <x, w> / lambda + phi)) / h`` with
        ``a = (ratio - 1) / (ratio + 1)``, a random unit direction ``w``, a random phase
        ``phi`` and a wavelength ``lambda`` of half the diagonal of the bounding box: a smooth
        field in space, so curves meeting at a node share the same local density there. The
        local spacing then varies between ``h / (1 + a)`` and ``h / (1 - a)`` (for a ratio
        of 3: from 0.67 h to 2 h).
    outliers : float
        Number of outliers as a fraction of the number of curve samples, drawn uniformly in
        the bounding box of the curves.
    rng : int, numpy.random.Generator or None
        Seed or generator; the default (0) makes the result reproducible. ``None`` means 0.

    Returns
    -------
    points : (N, d) ndarray of float
        The samples, in a random (seeded) order.
    labels : (N,) ndarray of int
        Index of the true curve each sample was drawn from; ``-1`` for outliers. Every node is
        sampled once, exactly at its position (before noise), and labelled with the smallest
        index of its incident curves.

    Raises
    ------
    InputError
        For a non-positive ``h``, a negative noise or outlier fraction, or a ratio below 1.
    """
    if h is None:
        h = float(network.parameters.get("h", 0.0))
    if not (h > 0 and np.isfinite(h)):
        raise InputError(f"h must be a positive number, got {h!r}")
    if not noise >= 0:
        raise InputError(f"noise must be >= 0, got {noise!r}")
    if not density_ratio >= 1:
        raise InputError(f"density_ratio must be >= 1, got {density_ratio!r}")
    if not outliers >= 0:
        raise InputError(f"outliers must be >= 0, got {outliers!r}")
    gen = np.random.default_rng(0 if rng is None else rng)
    d = network.dimension
    allp = np.vstack([network.nodes.reshape(-1, d)] + [c.points for c in network.curves])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    a = (density_ratio - 1.0) / (density_ratio + 1.0)
    w = gen.normal(size=d)
    w /= norm(w)
    lam = max(0.5 * norm(hi - lo), 10 * h)
    phi = gen.uniform(0.0, 2 * np.pi)

    pts, labels = [], []
    node_label = np.full(network.n_nodes, -1, dtype=np.int64)
    for cid, c in enumerate(network.curves):
        p = c.points
        if c.closed and c.start is None:
            p = np.vstack([p, p[:1]])
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        s = np.r_[0.0, np.cumsum(seg)]
        if c.start is not None:
            for v in (c.start, c.end):
                if node_label[v] < 0:
                    node_label[v] = cid
        if len(p) < 2 or s[-1] <= 0:
            continue
        # a fine grid along the curve (at most h/10 apart) to integrate the density
        fine = max(int(np.ceil(s[-1] / (h / 10.0))), len(p) - 1)
        u = np.linspace(0.0, s[-1], fine + 1)
        xu = np.column_stack([np.interp(u, s, p[:, k]) for k in range(d)])
        rho = (1.0 + a * np.sin(2 * np.pi * matvec(xu, w) / lam + phi)) / h
        F = np.r_[0.0, np.cumsum(0.5 * (rho[1:] + rho[:-1]) * np.diff(u))]
        total = F[-1]
        if c.start is None:  # free loop: evenly in F, random start
            n = max(int(round(total)), 3)
            targets = (np.arange(n) + gen.uniform()) * total / n
        else:  # open curve or loop through a node: end points are node samples
            n = max(int(round(total)), 1)
            targets = np.arange(1, n) * total / n
        su = np.interp(targets, F, u)
        q = np.column_stack([np.interp(su, s, p[:, k]) for k in range(d)])
        pts.append(q)
        labels.append(np.full(len(q), cid, dtype=np.int64))
    used = node_label >= 0
    pts.append(network.nodes[used])
    labels.append(node_label[used])
    P = np.vstack(pts) if pts else np.zeros((0, d))
    L = np.concatenate(labels) if labels else np.zeros(0, dtype=np.int64)
    if noise > 0:
        P = P + gen.normal(scale=noise * h, size=P.shape)
    n_out = int(round(outliers * len(P)))
    if n_out:
        O = lo + (hi - lo) * gen.uniform(size=(n_out, d))
        P = np.vstack([P, O])
        L = np.concatenate([L, np.full(n_out, -1, dtype=np.int64)])
    order = gen.permutation(len(P))
    return np.ascontiguousarray(P[order]), L[order]
