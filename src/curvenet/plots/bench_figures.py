"""Figures of the benchmark (extra ``viz``): analogues of the paper's Figures 7 and 8.

The functions here only draw: :mod:`curvenet.bench` computes the data (:func:`~curvenet.bench.eps_sweep`,
:func:`~curvenet.bench.method_vs_emst`) and hands it over. matplotlib is imported inside the
functions, with the Agg backend (no display needed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["figure7", "figure8"]


def _plt():
    from ..errors import require

    mpl = require("matplotlib", "benchmark figures", "viz")
    mpl.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def figure7(sweep: dict, path) -> Path:
    """Nodes and curves found by the paper's method against ε (the paper's Figure 7).

    Parameters
    ----------
    sweep : dict
        The result of :func:`curvenet.bench.eps_sweep`.
    path : str or Path
        PNG file to write.

    Returns
    -------
    Path
        ``path``.
    """
    plt = _plt()
    eps = np.asarray(sweep["epsilon"])
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    a.semilogx(eps, sweep["contracted_N_n"], "o-", color="C3", label="nodes found")
    a.semilogx(eps, sweep["contracted_N_c"], "s-", color="C0", label="curves found")
    a.axhline(sweep["true_N_n"], color="C3", ls="--", lw=1, label=f"true nodes ({sweep['true_N_n']})")
    a.axhline(sweep["true_N_c"], color="C0", ls="--", lw=1, label=f"true curves ({sweep['true_N_c']})")
    a.set_xlabel("ε (threshold on the point variation δ)")
    a.set_ylabel("count (valence-2 nodes contracted)")
    a.set_title(f"{sweep['model']}: what the paper's method finds")
    a.legend(fontsize=8)
    b.semilogx(eps, sweep["node_f1"], "o-", color="C3", label="node F1")
    b.semilogx(eps, sweep["curve_f1"], "s-", color="C0", label="curve F1")
    ex = np.asarray(sweep["exact_topology"], dtype=bool)
    if ex.any():
        b.semilogx(eps[ex], np.full(ex.sum(), 1.03), "k*", label="exact topology")
    b.set_ylim(-0.02, 1.08)
    b.set_xlabel("ε")
    b.set_title("scores against the ground truth")
    b.legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _draw(ax, net, title):
    cmap = __import__("matplotlib").colormaps["tab20"]
    for i, c in enumerate(net.curves):
        p = c.points
        if c.closed and len(p):
            p = np.vstack([p, p[:1]])
        ax.plot(p[:, 0], p[:, 1], "-", lw=1.6, color=cmap(i % 20))
    if net.n_nodes:
        ax.plot(net.nodes[:, 0], net.nodes[:, 1], "o", ms=5, color="red", mec="k", mew=0.5)
    ax.set_title(title, fontsize=10)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def figure8(data: dict, path) -> Path:
    """The points of a 2D model, a method's network and the EMST's (the paper's Figure 8).

    Parameters
    ----------
    data : dict
        The result of :func:`curvenet.bench.method_vs_emst`: ``points`` ((N, 2) ndarray),
        ``model``, ``condition``, ``true_N_n``, ``true_N_c`` and two ``panels`` (``method``,
        ``network``, ``curve_f1``, ``exact_topology``).
    path : str or Path
        PNG file to write.

    Returns
    -------
    Path
        ``path``.
    """
    plt = _plt()
    pts = np.asarray(data["points"])
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2))
    axes[0].plot(pts[:, 0], pts[:, 1], ".", ms=2.5, color="0.3")
    axes[0].set_title(f"(a) {len(pts)} points ({data['model']}, {data['condition']})", fontsize=10)
    axes[0].set_aspect("equal")
    axes[0].set_xticks([])
    axes[0].set_yticks([])
    for ax, panel, tag in zip(axes[1:], data["panels"], ("(b)", "(c)")):
        net = panel["network"]
        _draw(ax, net, f"{tag} {panel['method']}: {net.n_nodes} nodes, {net.n_curves} curves\n"
                       f"curve F1 {panel['curve_f1']:.2f}, exact topology {'yes' if panel['exact_topology'] else 'no'}")
    fig.suptitle(f"true network: {data['true_N_n']} nodes, {data['true_N_c']} curves", fontsize=10)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
