"""Stage reports of the methods: the callback type and each method's stages with their shares.

A method that reports its stages takes a keyword ``on_stage`` (:data:`OnStage`) and calls it as
each stage begins, with the stage's name and its share of the method's work. The shares are the
stage times measured by ``benchmarks/performance.py`` (``docs/performance.json``, the rows of
10^6 and 10^7 points, where progress matters), as fractions of the method's time, rounded to two
places; they add up to 1 over the stages that always run. A caller (the command line's progress
display) turns them into a fraction done and a time left.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

__all__ = ["OnStage", "ROBUST_SHARES", "PAPER_SHARES", "report_stage"]

#: ``on_stage(name, share)``: called as a stage begins, with its name and its share (0 to 1) of
#: the method's work.
OnStage = Callable[[str, float], None]

#: The robust method's stages in order (the keys of ``network.stats["time"]``) -> share of the
#: work. Measured (docs/performance.json, 10^6 / 10^7 points): neighbors 0.20 / 0.24, graph
#: 0.36 / 0.41, nodes 0.14 / 0.12, tracing 0.085 / 0.083, assemble 0.21 / 0.15. ``fit`` runs
#: only under noise (about 5% of a noisy run at 10^5 points, benchmarks/fit_eval.py --timing)
#: and is not in those runs: share 0 (the time left ignores it). ``branches`` (stage 9: the
#: network's unexplained branches) runs only under noise too, and is small: share 0.
ROBUST_SHARES: Mapping[str, float] = {
    "neighbors": 0.22,
    "graph": 0.39,
    "nodes": 0.13,
    "tracing": 0.08,
    "assemble": 0.18,
    "fit": 0.0,
    "branches": 0.0,
}

#: The paper's method's stages in order -> share of the work. Measured (docs/performance.json,
#: 10^6 points): neighbors 0.149, nodes (Algorithm 1) 0.713, tracing (Algorithm 2) 0.109,
#: merging (the reverse search) 0.029.
PAPER_SHARES: Mapping[str, float] = {
    "neighbors": 0.15,
    "nodes": 0.71,
    "tracing": 0.11,
    "merging": 0.03,
}


def report_stage(on_stage: OnStage | None, shares: Mapping[str, float], name: str) -> None:
    """Call ``on_stage(name, shares[name])`` when a callback is given.

    Parameters
    ----------
    on_stage : callable or None
        The caller's callback (:data:`OnStage`).
    shares : mapping of str to float
        The method's stages and their shares (:data:`ROBUST_SHARES`, :data:`PAPER_SHARES`).
    name : str
        The stage that begins (a key of ``shares``).
    """
    if on_stage is not None:
        on_stage(name, shares[name])
