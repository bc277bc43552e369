"""The pictures and tables of docs/method.md: the default method's stages on small examples.

Usage::

    python benchmarks/method_figures.py            # docs/img/method/*.png and the tables of docs/method.md
    python benchmarks/method_figures.py --check    # exit 1 when the tables in docs/method.md are stale
    python benchmarks/method_figures.py --out DIR --doc FILE [--tiny]

:func:`run_stages` runs the stages of :mod:`curvenet.methods.robust.pipeline` one by one, in the
same order and with the same calls, and keeps what each hands on (:class:`StageRun`); its final
network is checked equal to :func:`~curvenet.methods.robust.pipeline.reconstruct_robust`'s. The
``draw_*`` functions only draw a :class:`StageRun` (no reconstruction), with the colours of
:mod:`curvenet.style`. The tables are generated from
:mod:`curvenet.methods.robust.thresholds` (each field's value and its ``#:`` comment) and
:class:`~curvenet.methods.robust.params.RobustParams`, and written between the markers
``<!-- BEGIN name -->`` and ``<!-- END name -->`` of docs/method.md; the prose around them is
written by hand. ``--tiny`` draws one small clean example only (the test's run).
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import functools
import re
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np

from curvenet import synth
from curvenet.methods.robust import kernels as _k
from curvenet.methods.robust import pipeline, thresholds
from curvenet.methods.robust.chains import trace_chains
from curvenet.methods.robust.curves import build_curves, drop_spikes, fit_curves
from curvenet.methods.robust.frames import duplicates, frames, neighbours
from curvenet.methods.robust.graph import components, linked_edges, linked_graph
from curvenet.methods.robust.junctions import junction_regions
from curvenet.methods.robust.nodes import place_nodes
from curvenet.methods.robust.params import RobustParams, Scales
from curvenet.methods.robust.repairs import ORDER
from curvenet.methods.robust.skipped import rejoin_skipped_stretches
from curvenet.methods.robust.thresholds import SHELL
from curvenet.methods.robust.topology import Topology
from curvenet.methods.robust.unexplained import add_unexplained_branches
from curvenet.network import CurveNetwork
from curvenet.style import END_COLOR, JUNCTION_COLOR, OTHER_NODE_COLOR, PALETTE, POINT_COLOR

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img" / "method"
DOC = ROOT / "docs" / "method.md"

#: Figure width (inches) and resolution: the PNGs stay under about 150 KB.
FIG_WIDTH = 9.0
DPI = 100
#: Tangents are drawn as segments this many local spacings long.
TANGENT_LEN = 1.6
#: A change marker of the repair figure is a circle this many median spacings wider than the
#: points it marks; changed points closer than ``MARK_JOIN`` median spacings share one circle.
MARK_PAD = 3.0
MARK_JOIN = 8.0
#: Rows of panels (one per example) are at most this tall, plus this for their titles (inches).
ROW_MAX = 4.2
ROW_TITLE = 0.6

#: The figures, in stage order: file name -> drawing function name.
FIGURES = {
    "0-order.png": "draw_order",
    "1-spacing.png": "draw_spacing",
    "2-tangents.png": "draw_tangents",
    "3-graph.png": "draw_graph",
    "4-junctions.png": "draw_junctions",
    "5-chains.png": "draw_chains",
    "6-repairs.png": "draw_repairs",
    "7-nodes.png": "draw_nodes",
    "8-curves.png": "draw_curves",
}

#: The sections of docs/method.md that hold threshold tables (marker name) and the groups of
#: thresholds.py (module-level instance names) tabled there, in order. A group named here but
#: not defined in thresholds.py is skipped; a group of thresholds.py named in no section stops
#: the script (:func:`fill`): every constant has its place in the doc.
SECTIONS = {
    "KEYWORD_DEFAULTS": ("DEFAULTS",),
    "INPUT_ORDER": ("LAYOUT",),
    "SPACING": ("SPACING",),
    "TANGENTS": ("TANGENTS", "STRIP", "VOTE", "NOISE"),
    "LINKS": ("LINKS", "NOISY", "STRAND"),
    "JUNCTIONS": ("SHELL", "SPLIT"),
    "CHAINS": ("CHAINS", "ENDS"),
    "REPAIRS": ("REPAIRS", "PAIRED", "SPANNING", "ENDTREES", "BRANCHED"),
    "NODES": ("NODES",),
    "CURVES": ("CURVES", "FIT", "UNTANGLE"),
    "SKIPPED": ("SKIPPED",),
    "EXCURSION": ("EXCURSION",),
    "WALKIN": ("WALKIN",),
    "UNEXPLAINED": ("UNEXPLAINED",),
    "NUMERIC": ("NUMERIC", "LINALG"),
}


def threshold_groups() -> tuple[str, ...]:
    """Every threshold group of thresholds.py: the names of its module-level NamedTuple instances."""
    return tuple(n for n in thresholds.__all__ if n.isupper() and hasattr(getattr(thresholds, n), "_fields"))


# ------------------------------------------------------------------------------------ examples
class Example(NamedTuple):
    """A small input and the window (x0, x1, y0, y1) the close-up panels show."""

    name: str
    title: str
    points: np.ndarray
    zoom: tuple[float, float, float, float]


def examples(tiny: bool = False) -> list[Example]:
    """The examples of the figures: a noisy fan and a clean fork of uneven density (both 2D).

    Chosen so that every stage visibly acts, and both come out exact. The fan under noise 0.2 h
    (sampling 7): a strand link is cut at its valence-5 junction, and the stem stops short of
    the upper junction until the repair ``attach_dangling`` joins it. The fork (a T whose stem
    forks 5 h above the bar, sampled with a density ratio of 3): the spacing varies from about
    0.8 to 1.8 times its median, the two junctions first flag one region that the finer shell
    test splits, and a branch stops short of the bar until ``attach_dangling`` joins it.
    ``tiny``: the fork alone (the test's quick run).
    """
    fork = synth.fork(5.0, 45.0, length=20.0)
    P_fork, _ = synth.sample(fork, density_ratio=3.0, rng=0)
    out = [Example("fork", "clean fork, density ratio 3", P_fork, (-9.0, 9.0, -4.0, 11.0))]
    if tiny:
        return out
    fan = synth.model("fan")
    P_fan, _ = synth.sample(fan, noise=0.2, rng=7)
    return [Example("fan", "fan, noise 0.2 h", P_fan, (-0.14, 0.24, -0.12, 0.15))] + out


# ------------------------------------------------------------------------------------ stages
@dataclasses.dataclass
class TopoState:
    """A copy of a :class:`~curvenet.methods.robust.topology.Topology` at one moment.

    Attributes
    ----------
    chains : list of (n_i,) ndarray of int64
        The live chains' point ids, ordered.
    ends : list of (int, int)
        The regions at their two ends (-1 for a closed loop's).
    closed : list of bool
    regions : list of (m_j,) ndarray of int64
        The points of every region (empty ones included: ids stay those of the topology).
    valence : (n_regions,) ndarray of int64
    """

    chains: list
    ends: list
    closed: list
    regions: list
    valence: np.ndarray

    @classmethod
    def of(cls, topo: Topology) -> "TopoState":
        live = [c for c, a in zip(topo.chains, topo.alive) if a]
        return cls([c.ids.copy() for c in live], [tuple(c.ends) for c in live], [bool(c.closed) for c in live],
                   [r.copy() for r in topo.regions], topo.v.copy())

    def changed_points(self, after: "TopoState") -> np.ndarray:
        """Ids of the points a repair changed between this state and ``after``.

        The points whose region changed (another region, or its point set did), those on a
        chain in one state and on none in the other (a chain dropped or absorbed), and the end
        point of a chain end that moved to another region. A chain merely split or joined
        through a region is marked by that region's points.
        """
        ra, rb = self._region_of(), after._region_of()
        ca, cb = self._on_chain(), after._on_chain()
        changed = {p for p in set(ra) | set(rb) if ra.get(p) != rb.get(p)}
        changed |= {p for p in ca ^ cb if p not in ra and p not in rb}
        mine = {frozenset(c.tolist()): (c, e) for c, e in zip(self.chains, self.ends)}
        for c, e in zip(after.chains, after.ends):
            old = mine.get(frozenset(c.tolist()))
            if old is None or not len(c):
                continue
            same_dir = int(old[0][0]) == int(c[0])
            for s, end_pt in ((0, int(c[0])), (1, int(c[-1]))):
                if old[1][s if same_dir else 1 - s] != e[s]:
                    changed.add(end_pt)
        return np.array(sorted(changed), dtype=np.int64)

    def _region_of(self) -> dict:
        """Point id -> (region id, its point set)."""
        out: dict = {}
        for j, r in enumerate(self.regions):
            out.update(dict.fromkeys(r.tolist(), (j, frozenset(r.tolist()))))
        return out

    def _on_chain(self) -> set:
        return set(np.concatenate(self.chains).tolist()) if self.chains else set()


@dataclasses.dataclass
class StageRun:
    """What every stage of the robust method hands on, for one input (internal point order).

    Attributes
    ----------
    example : Example
    P_in : (N0, d) ndarray
        The input points in the internal order (sorted by coordinates).
    dropped : (N0 - N,) ndarray of int64
        Ids (in ``P_in``) of the noise-free duplicate samples dropped.
    P : (N, d) ndarray
        The points every later stage works on.
    h : (N,) ndarray
        Local spacing.
    t : (N, d) ndarray
        Unit tangents.
    lin : (N,) ndarray
        Linearity of the tangents.
    sigma, hmed : float
        Estimated noise (std per coordinate) and median spacing.
    clean : bool
    links : (E, 2) ndarray of int64
        The linked graph's undirected links ``a < b``.
    cut : (C, 2) ndarray of int64
        The strand links cut under noise (``a < b``).
    groups : (N,) ndarray of int32
        Shell group count of every point.
    reg0 : (N,) ndarray of int64
        Region of every point not in 2 groups, before the large regions are split (-1 elsewhere).
    reg : (N,) ndarray of int64
        The regions handed on (-1 elsewhere).
    traced : TopoState
        Chains and regions as traced (stage 5).
    repairs : list of (str, TopoState)
        The state after each repair of :data:`~curvenet.methods.robust.repairs.ORDER`.
    nodes : (n, d) ndarray
        Node positions (stage 7).
    net : CurveNetwork
        The final network (stage 8), input point ids.
    """

    example: Example
    P_in: np.ndarray
    dropped: np.ndarray
    P: np.ndarray
    h: np.ndarray
    t: np.ndarray
    lin: np.ndarray
    sigma: float
    hmed: float
    clean: bool
    links: np.ndarray
    cut: np.ndarray
    groups: np.ndarray
    reg0: np.ndarray
    reg: np.ndarray
    traced: TopoState
    repairs: list
    nodes: np.ndarray
    net: CurveNetwork


def _pairs(src, dst) -> np.ndarray:
    """Unique undirected pairs ``a < b`` of directed links, sorted."""
    a = np.minimum(src, dst).astype(np.int64)
    b = np.maximum(src, dst).astype(np.int64)
    if not len(a):
        return np.zeros((0, 2), dtype=np.int64)
    return np.unique(np.stack([a, b], axis=1), axis=0)


def run_stages(ex: Example, prm: RobustParams | None = None) -> StageRun:
    """Run the stages of :func:`~curvenet.methods.robust.pipeline.reconstruct_robust` one by one.

    The same calls in the same order as the pipeline (default keywords), keeping
    every stage's output; besides, the links before the strand cut and the regions before the
    split, for the pictures.

    Parameters
    ----------
    ex : Example
        ``ex.points`` : (N, d) ndarray, at least ``DEFAULTS.min_points`` points.
    prm : RobustParams, optional

    Returns
    -------
    StageRun
    """
    prm = prm or RobustParams.from_keywords()
    P0 = np.asarray(ex.points, dtype=float)
    with _k.compiled_for(len(P0)):
        order = pipeline._internal_order(P0)
        P_in = P = P0[order]
        nb = neighbours(P, prm)
        fr = frames(P, nb)
        keep = duplicates(nb, fr)
        dropped = np.zeros(0, dtype=np.int64)
        if keep is not None:
            dropped = np.setdiff1d(np.arange(len(P)), keep)
            P, order = P[keep], order[keep]
            nb = neighbours(P, prm)
            fr = frames(P, nb)
        graph = linked_graph(P, nb, fr, prm)
        noise = thresholds.NOISE.scale * fr.sigma
        src0, dst0, _ = linked_edges(P, nb.h, nb.idx, fr.t, fr.lin, prm.link, prm.link_width,
                                     thresholds.LINKS.strip_noise * noise, thresholds.LINKS.gap_noise * noise,
                                     lens=not fr.low)
        links, before = _pairs(graph.src, graph.dst), _pairs(src0, dst0)
        kept = {tuple(x) for x in links.tolist()}
        cut = np.array([x for x in before.tolist() if tuple(x) not in kept], dtype=np.int64).reshape(-1, 2)
        reg = junction_regions(P, nb, fr, graph, prm)
        ka, kb = _k.short_links(P, nb.h, nb.idx, float(prm.link))
        reg0, _ = components(len(P), ka, kb, reg.groups != 2)
        chains, regions = trace_chains(P, nb.h, graph, reg.flagged, reg.reg, reg.n_reg, fr.lin)
        sc = Scales(h=nb.h, hmed=fr.hmed, sigma=fr.sigma, noise=noise, clean=fr.clean,
                    width=max(prm.link_width, 0.0), indptr=graph.indptr, indices=graph.indices, tree=nb.tree)
        topo = Topology(P, chains, regions)
        traced = TopoState.of(topo)
        states = []
        for repair in ORDER:  # as repairs.run_repairs, one state kept after each
            repair(topo, sc, prm)
            states.append((repair.__name__, TopoState.of(topo)))
        placement = place_nodes(topo, sc, prm)
        curves = drop_spikes(build_curves(P, nb.h, placement), P, nb.h, noise)
        nodes, curves, _ = rejoin_skipped_stretches(P, nb.h, placement.nodes, curves, prm.link)  # stage 8c
        fit = None
        if not fr.clean:  # under noise, fitted (stage 8's last step)
            fit = functools.partial(fit_curves, sigma=fr.sigma, band=prm.smoothing)
            curves = fit(curves)
            nodes, curves, _ = add_unexplained_branches(P, nb.h, nodes, curves, noise, prm.link,
                                                        prm.min_spur, fit)  # stage 9, under noise
        pipeline._to_input_ids(curves, order)
    net = CurveNetwork(nodes, curves, {}, {})
    return StageRun(ex, P_in, dropped, P, nb.h, fr.t, fr.lin, fr.sigma, fr.hmed, fr.clean, links, cut,
                    reg.groups, reg0, reg.reg, traced, states, placement.nodes, net)


def same_network(a: CurveNetwork, b: CurveNetwork) -> bool:
    """True when two networks have the same nodes and curves, to the bit."""
    if not np.array_equal(a.nodes, b.nodes) or a.n_curves != b.n_curves:
        return False
    return all(np.array_equal(x.points, y.points) and x.start == y.start and x.end == y.end
               and x.closed == y.closed and np.array_equal(x.indices, y.indices) for x, y in zip(a.curves, b.curves))


# ------------------------------------------------------------------------------------ drawing
def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _figure(n_panels: int, height: float):
    plt = _plt()
    fig, axes = plt.subplots(1, n_panels, figsize=(FIG_WIDTH, height), squeeze=False)
    return fig, list(axes[0])


def _window(run: StageRun, zoom: bool = False) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1): the close-up window, or the whole input with a margin."""
    if zoom:
        return run.example.zoom
    lo, hi = run.P_in.min(axis=0), run.P_in.max(axis=0)
    pad = 0.07 * float((hi - lo).max())
    return lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad


def _frame(ax, run: StageRun, zoom: bool = False) -> None:
    """Equal scales, no ticks, the close-up window or the whole input."""
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    x0, x1, y0, y1 = _window(run, zoom)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)


def _grid(runs: list[StageRun], n_cols: int):
    """A figure with one row of ``n_cols`` panels per run, each row as tall as its input needs."""
    plt = _plt()
    w = FIG_WIDTH / n_cols
    heights = []
    for run in runs:
        x0, x1, y0, y1 = _window(run)
        heights.append(min(w * (y1 - y0) / (x1 - x0), ROW_MAX) + ROW_TITLE)
    fig = plt.figure(figsize=(FIG_WIDTH, sum(heights)))
    gs = fig.add_gridspec(len(runs), n_cols, height_ratios=heights)
    return fig, [[fig.add_subplot(gs[r, c]) for c in range(n_cols)] for r in range(len(runs))]


def _marker_size(run: StageRun, zoom: bool) -> float:
    return 9.0 if zoom else float(np.clip(2500.0 / len(run.P), 2.0, 12.0))


def _faint(ax, run: StageRun, zoom: bool = False) -> None:
    ax.scatter(*run.P.T[:2], s=_marker_size(run, zoom), c=POINT_COLOR, alpha=0.45, linewidths=0, zorder=1)


def _region_colors(n: int) -> list[str]:
    return [PALETTE[i % len(PALETTE)] for i in range(n)]


def draw_order(runs: list[StageRun], path: Path) -> Path:
    """Stage 0: the points as they arrive and as they are handed on (sorted by coordinates),
    each coloured by its number; in the internal order consecutive numbers are joined."""
    fig, grid = _grid(runs, 2)
    for row, run in zip(grid, runs):
        for ax, X, what in ((row[0], run.example.points, "input order"),
                            (row[1], run.P_in, "internal order (sorted by coordinates)")):
            n = len(X)
            if X is run.P_in:
                ax.plot(*X.T[:2], color=POINT_COLOR, lw=0.5, alpha=0.5, zorder=1)
            sc = ax.scatter(*X.T[:2], s=_marker_size(run, False), c=np.arange(n), cmap="viridis",
                            linewidths=0, zorder=2)
            _frame(ax, run)
            ax.set_title(f"{run.example.title}\n{what}", fontsize="medium")
        fig.colorbar(sc, ax=row[1], shrink=0.7, label="point number")
    return _save(fig, path)


def draw_spacing(runs: list[StageRun], path: Path) -> Path:
    """Stage 1: the input points coloured by their local spacing h (duplicates dropped marked)."""
    fig, axes = _figure(len(runs), ROW_MAX)
    for ax, run in zip(axes, runs):
        sc = ax.scatter(*run.P.T[:2], s=_marker_size(run, False), c=run.h / run.hmed, cmap="viridis",
                        linewidths=0, zorder=2)
        if len(run.dropped):
            ax.scatter(*run.P_in[run.dropped].T[:2], s=20, marker="x", c="k", zorder=3,
                       label=f"duplicates dropped ({len(run.dropped)})")
            ax.legend(loc="lower right", fontsize="small")
        fig.colorbar(sc, ax=ax, shrink=0.7, label="h / median h")
        lo, hi = np.percentile(run.h, [5, 95]) / run.hmed
        _frame(ax, run)
        ax.set_title(f"{run.example.title}\n{len(run.P_in)} points; h from {lo:.2f} to {hi:.2f} median",
                     fontsize="medium")
    return _save(fig, path)


def draw_tangents(runs: list[StageRun], path: Path) -> Path:
    """Stage 2: tangents as short segments (close-up), coloured by linearity; the noise estimate."""
    from matplotlib.collections import LineCollection

    fig, axes = _figure(len(runs), ROW_MAX)
    for ax, run in zip(axes, runs):
        _faint(ax, run, zoom=True)
        half = 0.5 * TANGENT_LEN * run.h[:, None] * run.t
        segs = np.stack([run.P - half, run.P + half], axis=1)[:, :, :2]
        coll = LineCollection(segs, array=run.lin, cmap="plasma", clim=(0.0, 1.0), linewidths=1.6, zorder=2)
        ax.add_collection(coll)
        fig.colorbar(coll, ax=ax, shrink=0.7, label="linearity")
        _frame(ax, run, zoom=True)
        noise = "noise-free" if run.clean else "noisy"
        ax.set_title(f"{run.example.title} (close-up)\nnoise estimate {run.sigma / run.hmed:.2f} h: {noise}",
                     fontsize="medium")
    return _save(fig, path)


def draw_graph(runs: list[StageRun], path: Path) -> Path:
    """Stage 3: the linked graph's links (close-up); strand links cut under noise in red."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    fig, axes = _figure(len(runs), ROW_MAX)
    for ax, run in zip(axes, runs):
        _faint(ax, run, zoom=True)
        ax.add_collection(LineCollection(run.P[run.links][:, :, :2], colors=PALETTE[0], linewidths=1.0, zorder=2))
        handles = [Line2D([], [], color=PALETTE[0], label=f"links ({len(run.links)} in all)")]
        if len(run.cut):
            ax.add_collection(LineCollection(run.P[run.cut][:, :, :2], colors=JUNCTION_COLOR, linewidths=2.2,
                                             linestyles="--", zorder=3))
            handles.append(Line2D([], [], color=JUNCTION_COLOR, ls="--", lw=2,
                                  label=f"strand links cut ({len(run.cut)} in all)"))
        _frame(ax, run, zoom=True)
        ax.legend(handles=handles, loc="best", fontsize="small", framealpha=0.9)
        ax.set_title(f"{run.example.title} (close-up)", fontsize="medium")
    return _save(fig, path)


def _group_style():
    return [(1, "1 group: free end", "s", END_COLOR), (2, "2 groups: on a curve", "o", POINT_COLOR),
            (3, "3+ groups: junction", "o", JUNCTION_COLOR)]


def shell_point(run: StageRun) -> int:
    """The junction point (3 or more groups) nearest the middle of the largest junction region."""
    j = np.flatnonzero((run.groups >= SHELL.junction_groups) & (run.reg >= 0))
    if not len(j):
        return -1
    big = np.bincount(run.reg[j]).argmax()
    j = j[run.reg[j] == big]
    d = np.linalg.norm(run.P[j] - run.P[j].mean(axis=0), axis=1)
    return int(j[np.lexsort((j, d))[0]])


def draw_junctions(runs: list[StageRun], path: Path) -> Path:
    """Stage 4: shell group counts per point (1, 2, 3+) with one shell drawn, and the regions
    (one colour each; ringed: the points not in 2 groups, whose regions are split when too large)."""
    from matplotlib.patches import Circle

    fig, grid = _grid(runs, 2)
    prm = RobustParams.from_keywords()
    for run, (ax, bx) in zip(runs, grid):
        g = np.minimum(run.groups, SHELL.junction_groups)
        ms = _marker_size(run, False)
        for val, label, marker, color in _group_style():
            m = g == val
            if m.any():
                ax.scatter(*run.P[m].T[:2], s=ms * (2.5 if val != 2 else 1), marker=marker, c=color,
                           edgecolors="k" if val != 2 else "none", linewidths=0.5, zorder=3 if val != 2 else 1,
                           label=f"{label} ({int(m.sum())})")
        p = shell_point(run)
        if p >= 0:
            hs = run.h[p] + SHELL.widen * thresholds.NOISE.scale * run.sigma
            for r in (prm.shell_inner, prm.shell_outer):
                ax.add_patch(Circle(run.P[p, :2], r * hs, fill=False, ec="k", lw=1.0, ls=":", zorder=4))
        _frame(ax, run)
        ax.legend(loc="best", fontsize="x-small", framealpha=0.9)
        ax.set_title(f"{run.example.title}: shell groups per point\n(dotted: the shell around one junction point)",
                     fontsize="small")
        _faint(bx, run)
        n0, n1 = int(run.reg0.max()) + 1, int(run.reg.max()) + 1
        cols = _region_colors(n1)
        m0 = run.reg0 >= 0
        bx.scatter(*run.P[m0].T[:2], s=ms * 9, facecolors="none", edgecolors="k", linewidths=0.5, zorder=2)
        for r in range(n1):
            m = run.reg == r
            bx.scatter(*run.P[m].T[:2], s=ms * 2.5, c=cols[r], linewidths=0, zorder=3)
        _frame(bx, run)
        split = f"{n0} before the split, {n1} after" if n0 != n1 else f"{n1} (no region split)"
        bx.set_title(f"regions, one colour each: {split}\n(ringed: points not in 2 groups)", fontsize="small")
    return _save(fig, path)


def chain_colors(run: StageRun, st: TopoState) -> list[str]:
    """A colour per chain of ``st``: traced chain ``i`` has ``PALETTE[i]``; a later chain takes
    the colour of the traced chain it shares most points with, or else (a part split off, a
    colour already taken) the first colour no chain of ``st`` has yet."""
    first = np.full(len(run.P), -1, dtype=np.int64)
    for i, c in enumerate(run.traced.chains):
        first[c] = i
    out: list = [None] * len(st.chains)
    taken = set()
    by_size = sorted(range(len(st.chains)), key=lambda i: (-len(st.chains[i]), int(st.chains[i].min(initial=0))))
    for i in by_size:
        f = first[st.chains[i]]
        f = f[f >= 0]
        if len(f):
            j = int(np.bincount(f).argmax())
            if j not in taken:
                out[i] = j
                taken.add(j)
    for i in by_size:
        if out[i] is None:
            out[i] = next(j for j in range(len(run.traced.chains) + len(st.chains)) if j not in taken)
            taken.add(out[i])
    return [PALETTE[j % len(PALETTE)] for j in out]


def _draw_state(ax, run: StageRun, st: TopoState, zoom: bool = False) -> None:
    """Chains one colour each (closed loops dashed), region points black, on the faint points."""
    from matplotlib.collections import LineCollection

    _faint(ax, run, zoom)
    cols = chain_colors(run, st)
    for c, col, closed in zip(st.chains, cols, st.closed):
        X = run.P[np.r_[c, c[:1]] if closed else c][:, :2]
        ax.add_collection(LineCollection([X], colors=col, linewidths=1.8, linestyles="--" if closed else "-",
                                         zorder=2))
    rp = [r for r in st.regions if len(r)]
    if rp:
        ax.scatter(*run.P[np.concatenate(rp)].T[:2], s=_marker_size(run, zoom) * 1.5, c="k", linewidths=0, zorder=3)
    _frame(ax, run, zoom)


def draw_chains(runs: list[StageRun], path: Path) -> Path:
    """Stage 5: the chains between regions, one colour each, and the region points (black)."""
    fig, axes = _figure(len(runs), ROW_MAX)
    for ax, run in zip(axes, runs):
        _draw_state(ax, run, run.traced)
        n_reg = sum(1 for r in run.traced.regions if len(r))
        ax.set_title(f"{run.example.title}\n{len(run.traced.chains)} chains, {n_reg} regions (black)",
                     fontsize="medium")
    return _save(fig, path)


def _acted(run: StageRun) -> list[tuple[str, np.ndarray]]:
    """The repairs that changed the topology and the points they changed."""
    out, prev = [], run.traced
    for name, st in run.repairs:
        ch = prev.changed_points(st)
        if len(ch):
            out.append((name, ch))
        prev = st
    return out


def _clusters(X: np.ndarray, r: float) -> list[np.ndarray]:
    """The points ``X`` (n, 2) in groups joined by steps of at most ``r``."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(X).query_pairs(r, output_type="ndarray")
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(X), len(X)))
    n, lab = connected_components(g, directed=False)
    return [X[lab == i] for i in range(n)]


def draw_repairs(runs: list[StageRun], path: Path) -> Path:
    """Stage 6: the topology before and after the repairs, what each repair changed circled."""
    from matplotlib.patches import Circle

    shown = [r for r in runs if _acted(r)] or runs[:1]
    fig, grid = _grid(shown, 2)
    for run, (ax, bx) in zip(shown, grid):
        _draw_state(ax, run, run.traced)
        final = run.repairs[-1][1]
        _draw_state(bx, run, final)
        acted = _acted(run)
        for j, (_, ids) in enumerate(acted):
            for X in _clusters(run.P[ids][:, :2], MARK_JOIN * run.hmed):
                c = X.mean(axis=0)
                rad = float(np.linalg.norm(X - c, axis=1).max()) + MARK_PAD * run.hmed
                for a in (ax, bx):
                    a.add_patch(Circle(c, rad, fill=False, ec=JUNCTION_COLOR, lw=1.6, zorder=4))
                    a.annotate(str(j + 1), c + rad * np.array([0.75, 0.75]), color=JUNCTION_COLOR, fontsize=11,
                               fontweight="bold", zorder=5)
        ax.set_title(f"{run.example.title}\nas traced: {len(run.traced.chains)} chains", fontsize="medium")
        text = ", ".join(f"{j + 1}: {name}" for j, (name, _) in enumerate(acted)) or "no repair changed anything"
        bx.set_title(f"after the repairs: {len(final.chains)} chains\n{text}", fontsize="medium")
    return _save(fig, path)


def _node_scatter(ax, net: CurveNetwork) -> list:
    from matplotlib.lines import Line2D

    handles = []
    style = {"junction": ("o", 42, JUNCTION_COLOR, "junctions"), "end": ("s", 32, END_COLOR, "free ends"),
             "other": ("D", 28, OTHER_NODE_COLOR, "other nodes")}
    kinds = net.node_kinds
    for kind in ("other", "end", "junction"):
        m = kinds == kind
        if not m.any():
            continue
        marker, s, c, label = style[kind]
        ax.scatter(*net.nodes[m].T[:2], marker=marker, s=s, c=c, edgecolors="k", linewidths=0.8, zorder=5)
        handles.append(Line2D([], [], ls="", marker=marker, ms=6, mfc=c, mec="k", label=f"{label} ({int(m.sum())})"))
    return handles


def draw_nodes(runs: list[StageRun], path: Path) -> Path:
    """Stage 7: node positions over the repaired regions (black) and chains (one colour each)."""
    fig, axes = _figure(len(runs), ROW_MAX)
    for ax, run in zip(axes, runs):
        _draw_state(ax, run, run.repairs[-1][1])
        handles = _node_scatter(ax, run.net)
        ax.legend(handles=handles, loc="best", fontsize="small", framealpha=0.9)
        ax.set_title(f"{run.example.title}\n{len(run.nodes)} nodes", fontsize="medium")
    return _save(fig, path)


def draw_curves(runs: list[StageRun], path: Path) -> Path:
    """Stage 8: the final network, each curve in its own colour (as every picture of curvenet)."""
    from curvenet.plots.network_png import plot_network
    from matplotlib.lines import Line2D

    fig, axes = _figure(len(runs), ROW_MAX)
    for ax, run in zip(axes, runs):
        plot_network(run.net, points=run.P_in, ax=ax, legend=False, show_nodes=False,
                     title=f"{run.example.title}\n{run.net.n_nodes} nodes, {run.net.n_curves} curves")
        handles = [Line2D([], [], color=PALETTE[0], lw=2, label=f"curves ({run.net.n_curves})")]
        handles += _node_scatter(ax, run.net)
        ax.legend(handles=handles, loc="best", fontsize="small", framealpha=0.9)
        ax.title.set_fontsize("medium")
        _frame(ax, run)
        ax.set_xlabel("")
        ax.set_ylabel("")
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    from io import BytesIO

    from curvenet.io import atomic_write

    fig.tight_layout()
    buf = BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    _plt().close(fig)
    return atomic_write(path, buf.getvalue())


def draw_all(runs: list[StageRun], out: Path) -> list[Path]:
    """Every figure of :data:`FIGURES` into the folder ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    this = sys.modules[__name__]
    return [getattr(this, fn)(runs, out / name) for name, fn in FIGURES.items()]


# ------------------------------------------------------------------------------------ tables
def field_comments(source: str) -> dict[str, dict[str, str]]:
    """The ``#:`` comment of every field of every NamedTuple class in ``source``.

    A field without a comment of its own shares the previous field's (``report_lo`` and
    ``report_hi``); continuation lines are joined.

    Returns
    -------
    dict
        Class name -> field name -> comment text (markdown: ``x`` becomes `x`).
    """
    lines = source.splitlines()
    out: dict[str, dict[str, str]] = {}
    for node in ast.parse(source).body:
        if not isinstance(node, ast.ClassDef):
            continue
        fields: dict[str, str] = {}
        prev_name, prev_text = "", ""
        for item in node.body:
            if not isinstance(item, ast.AnnAssign):
                continue
            comment = []
            i = item.lineno - 2  # the line above the field (0-based)
            while i >= 0 and lines[i].strip().startswith("#"):
                comment.insert(0, lines[i].strip().lstrip("#").lstrip(":").strip())
                i -= 1
            name = item.target.id
            if comment:
                prev_name, prev_text = name, " ".join(comment)
                fields[name] = prev_text
            else:  # shares the comment above it
                fields[name] = f"(with `{prev_name}`) {prev_text}"
        out[node.name] = fields
    return out


#: What starts the part of a field's comment that says where its value came from (the origin
#: column of the tables).
ORIGIN = " origin: "

_ROLE = re.compile(r":\w+:`~?\.*([\w.]+)`")


def _md(text: str) -> str:
    """reST to markdown: roles and double backquotes to code spans, table bars escaped."""
    return _ROLE.sub(r"`\1`", text).replace("``", "`").replace("|", "\\|")


def _value(v) -> str:
    if isinstance(v, tuple):
        return "(" + ", ".join(_value(x) for x in v) + ")"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, (int, np.integer)):
        return f"{int(v):,}" if abs(int(v)) >= 10_000 else str(int(v))
    v = float(v)
    return f"{v:.1f}" if v.is_integer() and abs(v) < 1e6 else f"{v:.6g}"


def group_table(name: str) -> str:
    """The markdown table of one threshold group (``name``: e.g. ``"SPACING"``)."""
    group = getattr(thresholds, name)
    comments = field_comments(Path(thresholds.__file__).read_text())[type(group).__name__]
    doc = " ".join((type(group).__doc__ or "").split())
    rows = [f"*`thresholds.{name}`: {_md(doc)}*", "", "| name | value | meaning | origin |", "|---|---|---|---|"]
    for field, value in zip(group._fields, group):
        meaning, _, origin = comments[field].partition(ORIGIN)
        rows.append(f"| `{field}` | {_value(value)} | {_md(meaning)} | {_md(origin)} |")
    return "\n".join(rows)


def params_table() -> str:
    """The markdown table of the user's keywords (:class:`RobustParams`): name, default, meaning."""
    doc = RobustParams.__doc__ or ""
    meaning: dict[str, str] = {}
    cur: list[str] = []
    for line in doc.split("Parameters")[1].splitlines()[2:]:
        if line.strip() and not line.startswith("        "):
            cur = [n.strip() for n in line.split(":")[0].split(",")]
            continue
        for n in cur:
            meaning[n] = (meaning.get(n, "") + " " + line.strip()).strip()
    rows = ["| keyword | default | meaning |", "|---|---|---|"]
    for f in dataclasses.fields(RobustParams):
        default = "estimated" if f.default is None else _value(f.default)
        rows.append(f"| `{f.name}` | {default} | {_md(meaning[f.name])} |")
    return "\n".join(rows)


def repairs_table() -> str:
    """The markdown table of the repairs in the order they run: name and the first sentence of
    its docstring (the failure it fixes)."""
    rows = ["| # | repair | what it does |", "|---|---|---|"]
    for i, fn in enumerate(ORDER, 1):
        first = " ".join((fn.__doc__ or "").strip().split("\n\n")[0].split())
        rows.append(f"| {i} | `{fn.__name__}` | {_md(first)} |")
    return "\n".join(rows)


def tables() -> dict[str, str]:
    """Every generated block of docs/method.md: marker name -> markdown.

    Raises
    ------
    ValueError
        When a threshold group has no section in :data:`SECTIONS`.
    """
    groups = threshold_groups()
    placed = {g for names in SECTIONS.values() for g in names}
    if set(groups) - placed:
        raise ValueError(f"threshold groups without a section of the doc: {sorted(set(groups) - placed)} "
                         "(add them to SECTIONS in benchmarks/method_figures.py)")
    out = {sec: "\n\n".join(group_table(g) for g in names if g in groups) for sec, names in SECTIONS.items()}
    out["PARAMS"] = params_table()
    out["ORDER"] = repairs_table()
    return out


_BLOCK = re.compile(r"(<!-- BEGIN (\w+) -->\n)(.*?)(<!-- END \2 -->)", re.S)


def blocks_in(doc: str) -> dict[str, str]:
    """The generated blocks found in a docs/method.md text: marker name -> content."""
    return {m.group(2): m.group(3).removesuffix("\n") for m in _BLOCK.finditer(doc)}


def fill(doc: str) -> str:
    """``doc`` with every marked block replaced by its generated table.

    Raises
    ------
    ValueError
        When a table has no markers in ``doc`` or a marker names no table.
    """
    want = tables()
    have = blocks_in(doc)
    missing, unknown = sorted(set(want) - set(have)), sorted(set(have) - set(want))
    if missing or unknown:
        raise ValueError(f"markers missing for {missing}, unknown markers {unknown}")
    return _BLOCK.sub(lambda m: m.group(1) + want[m.group(2)] + "\n" + m.group(4), doc)


# ------------------------------------------------------------------------------------ main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=IMG, help="folder of the PNGs (default docs/img/method)")
    ap.add_argument("--doc", type=Path, default=DOC, help="the markdown file whose tables are filled")
    ap.add_argument("--tiny", action="store_true", help="one small example (a quick check that it runs)")
    ap.add_argument("--check", action="store_true", help="only check that the tables of --doc are up to date")
    args = ap.parse_args(argv)
    from curvenet.io import atomic_write

    try:
        doc = args.doc.read_text()
        new = fill(doc)
    except (OSError, ValueError) as e:
        print(f"{args.doc}: {e}", file=sys.stderr)
        return 2
    if args.check:
        if new != doc:
            print(f"{args.doc}: the tables differ from thresholds.py; run python benchmarks/method_figures.py")
            return 1
        print(f"{args.doc}: tables up to date")
        return 0
    if new != doc:
        atomic_write(args.doc, new)
        print(f"{args.doc}: tables updated")
    runs = []
    for ex in examples(args.tiny):
        run = run_stages(ex)
        if not same_network(run.net, pipeline.reconstruct_robust(ex.points)):
            print(f"{ex.name}: the stages run here differ from reconstruct_robust (update run_stages)")
            return 1
        runs.append(run)
    for p in draw_all(runs, args.out):
        print(f"{p} ({p.stat().st_size // 1024} KB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
