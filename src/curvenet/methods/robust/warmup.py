"""The first run's compile, shared out over the processor's cores.

numba compiles each kernel of the robust method on its first use, one after the other, on one
core (its compiler holds a lock: threads cannot share the work), and keeps the result in its disk
cache. On a first run that is most of the time: about a minute at 10^6 points for a run of
8 seconds (docs/performance.md, "Compile time"). :func:`precompile` cuts the kernels into
:func:`shares` of about equal compile time and compiles each share in a process of its own, this
one included: each process runs the method on two small built-in clouds
(:func:`warm_clouds`, one noise-free and one noisy, which between them call every kernel) with
the kernels of its share compiled and every other kernel in plain Python
(:func:`~.kernels.registry.compiled_only`). The kernels land in numba's disk cache, where the
run that follows loads them. A first run compiles the kernels every run calls (:data:`COMMON`)
before it starts, and those of noisy input only (:data:`NOISY_ONLY`) when it first needs one of
them (:func:`on_first_use`): a noise-free first run does not wait for them. Nothing here
changes a result: a kernel gives the same bits compiled or not.

``python -m curvenet.methods.robust.warmup NAME ...`` compiles the kernels ``NAME`` (the
processes that :func:`precompile` starts).
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from .kernels import registry

__all__ = ["COMPILE_SECONDS", "MAX_PROCESSES", "SPACING", "NOISE", "NOISY_ONLY", "COMMON", "warm_clouds", "shares",
           "warm", "cores", "precompile", "on_first_use"]

#: Seconds numba took to compile each kernel on its first call, at the first run on this
#: project's 2-core reference machine (``python benchmarks/startup.py --part compile``,
#: 4 December 2026; helpers shared by several kernels counted with the first caller). Only
#: their ratios matter: they weigh the kernels when :func:`shares` balances the processes.
#: A kernel missing here weighs :data:`DEFAULT_SECONDS`.
COMPILE_SECONDS = {
    "strand_cuts": 16.75, "junction_nodes": 10.09, "tangents": 8.84, "noisy_tangents": 6.28,
    "shell_groups": 3.63, "linked_edges": 3.16, "vote_eig": 2.97, "chain_order": 1.62, "chain_ends": 1.44,
    "spacing": 0.97, "trim_ends": 0.82, "envelope_solve": 0.69, "components": 0.67, "end_counts": 0.49,
    "untangle": 0.45, "csr_union": 0.43, "short_links": 0.39, "vote_agreement": 0.21, "end_count": 0.1,
}

#: The kernels that only noisy input calls (the strand test's noisy tangents and link cuts, the
#: curve fit's solve; the tangent vote runs on noise-free input too): about 22 s of the
#: compile's 55 (:data:`COMPILE_SECONDS`). A run compiles them, shared out, on the first call
#: of one of them (:func:`on_first_use`), so a noise-free first run does not wait for them.
NOISY_ONLY = ("noisy_tangents", "strand_cuts", "envelope_solve")

#: The other kernels: those a run on enough points calls whatever its input (and ``untangle``,
#: which some call), compiled before the run when it will compile (:func:`precompile`).
COMMON = tuple(k for k in registry.KERNELS if k not in NOISY_ONLY)

#: weight of a kernel that :data:`COMPILE_SECONDS` does not list
DEFAULT_SECONDS = 1.0

#: At most this many processes compile at once: the longest kernel alone (``strand_cuts``) takes
#: about a quarter of the whole compile, so more processes would wait for it.
MAX_PROCESSES = 4

#: Spacing of the samples of the warm-up clouds (the cube's edge is 1).
SPACING = 0.05

#: Noise of the noisy warm-up cloud, a fraction of :data:`SPACING` (enough that the method
#: detects noise and runs its noisy stages: the strand test and the curve fit).
NOISE = 0.3


#: The clouds are 3D. A 2D input loads the same compiled kernels: numba types an array by its
#: rank and element type, not by its width (checked: a 2D first run compiles nothing more).
DIM = 3

#: Radius of the circle on the cube's top face (centred on the face; its edge is 1).
CIRCLE_RADIUS = 0.3

#: Each sample of a cube edge lies at a uniform random place in this part of its spacing (an
#: uneven sampling, as in real clouds, without two samples closer than 0.4 spacing).
JITTER = (0.2, 0.8)


def warm_clouds(seed: int = 0) -> list[np.ndarray]:
    """Two small clouds that call every kernel of the robust method: the edges of a unit cube
    (corners of valence 3) with a circle on its top face, sampled every :data:`SPACING`, as is
    and with Gaussian noise of :data:`NOISE` spacings (285 points each).

    Returns
    -------
    list of (N, 3) ndarray
    """
    rng = np.random.default_rng(seed)
    corners = np.array(list(itertools.product((0.0, 1.0), repeat=DIM)))
    parts = [corners]
    for a, b in itertools.combinations(corners, 2):
        if np.abs(a - b).sum() == 1:  # an edge of the cube
            n = int(round(1.0 / SPACING))
            t = (np.arange(n) + rng.uniform(*JITTER, n)) / n
            parts.append(a + t[:, None] * (b - a))
    r = CIRCLE_RADIUS
    th = rng.uniform(0.0, 2 * np.pi, int(2 * np.pi * r / SPACING))
    parts.append(np.c_[0.5 + r * np.cos(th), 0.5 + r * np.sin(th), np.ones_like(th)])
    clean = np.vstack(parts)
    noisy = clean + rng.normal(0.0, NOISE * SPACING, clean.shape)
    return [clean, noisy]


def shares(parts: int, names: Iterable[str] | None = None) -> list[tuple[str, ...]]:
    """The kernels ``names`` (default: all) cut into at most ``parts`` shares of about equal
    compile time (:data:`COMPILE_SECONDS`): the longest first, each to the lightest share so far.

    Returns
    -------
    list of tuple of str
        Non-empty shares, the heaviest first.
    """
    names = sorted(registry.KERNELS if names is None else names,
                   key=lambda k: (-COMPILE_SECONDS.get(k, DEFAULT_SECONDS), k))
    out: list[list[str]] = [[] for _ in range(max(1, min(int(parts), len(names))))]
    load = [0.0] * len(out)
    for name in names:
        i = min(range(len(out)), key=lambda j: (load[j], j))
        out[i].append(name)
        load[i] += COMPILE_SECONDS.get(name, DEFAULT_SECONDS)
    order = sorted(range(len(out)), key=lambda j: -load[j])
    return [tuple(out[j]) for j in order if out[j]]


def warm(names: Iterable[str]) -> None:
    """Compile the kernels ``names`` (loaded instead, when numba's cache holds them): run the
    method on :func:`warm_clouds` with those kernels compiled and the others in plain Python."""
    from .pipeline import reconstruct_robust

    with registry.compiled_only(names):
        for P in warm_clouds():
            reconstruct_robust(P)


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # (not on every platform)
        return os.cpu_count() or 1


def _child_env() -> dict:
    """This process's environment, with the directory that holds the imported ``curvenet``
    first on ``PYTHONPATH``: a child imports the same package (and so fills the same cache
    entries) even when this process found it on a path of its own (``sys.path`` edited, a
    source checkout)."""
    root = Path(__file__).resolve().parent
    for _ in __package__.split("."):  # up from curvenet/methods/robust to what holds curvenet
        root = root.parent
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(root), *filter(None, [env.get("PYTHONPATH")])])
    return env


def precompile(processes: int | None = None, names: Iterable[str] | None = None) -> None:
    """Compile the kernels ``names`` (default: all) into numba's disk cache, :func:`shares` of
    them in parallel.

    The heaviest share is compiled in this process, each other one by a child process
    (``python -m curvenet.methods.robust.warmup``, numba's cache settings inherited from the
    environment); this returns when all are done. A child that cannot start or fails costs
    nothing but time: the kernels it did not compile compile on their first use, as without
    this.

    Parameters
    ----------
    processes : int, optional
        Processes in all (this one included); default: the cores this process may use, at most
        :data:`MAX_PROCESSES`.
    names : iterable of str, optional
        Kernel names (:data:`~.kernels.registry.KERNELS`); default: all of them.
    """
    if not registry.HAVE_NUMBA:
        return
    n = min(cores(), MAX_PROCESSES) if processes is None else max(1, int(processes))
    mine, *others = shares(n, names)
    children = []
    env = _child_env()
    for share in others:
        try:
            children.append(subprocess.Popen([sys.executable, "-m", __name__, *share], stdin=subprocess.DEVNULL,
                                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env))
        except OSError:  # (no interpreter to start: this process compiles them when they run)
            pass
    try:
        warm(mine)
        for child in children:
            child.wait()
    except BaseException:  # Ctrl-C (or a failure) here: no child left behind, none waited for
        for child in children:
            child.kill()
        for child in children:
            child.wait()
        raise


def on_first_use(name: str) -> None:
    """The hook a run installs (:func:`~.kernels.registry.first_use_hook`): before the first
    compiled call of a kernel of :data:`NOISY_ONLY`, when numba's cache lacks one of them, they
    are compiled together, shared out over the cores (:func:`precompile`)."""
    if name in NOISY_ONLY and not registry.in_cache(NOISY_ONLY):
        precompile(names=NOISY_ONLY)


def main(argv: Sequence[str] | None = None) -> int:
    """Compile the kernels named on the command line (all of them without names)."""
    names = list(sys.argv[1:] if argv is None else argv)
    unknown = [n for n in names if n not in registry.KERNELS]
    if unknown:
        print(f"unknown kernel(s): {', '.join(unknown)}", file=sys.stderr)
        return 2
    warm(names or registry.KERNELS)
    return 0


if __name__ == "__main__":  # pragma: no cover - run as a child process by precompile
    sys.exit(main())
