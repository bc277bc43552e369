"""Which version of each kernel runs: plain Python or compiled by numba, side by side.

Every kernel is plain Python written in the subset numba compiles (the topic modules of this
package). :data:`KERNELS` holds, for each, the function as written (``plain``: it calls the
plain helpers of its own module's globals) and numba's version (``compiled``: built from a copy
of the function whose globals map each helper it calls to the helper's compiled version, and
``prange`` to numba's; compiled on first use and cached on disk). No module global is ever
rewritten: the two versions live apart, and :func:`compiled_for` only sets a context variable
that the dispatch functions below read. Both give the same results, bit for bit; plain Python is
only slow. Without numba (or with ``CURVENET_NO_NUMBA=1``) only the plain versions exist.

The fixed constants of the kernels (:mod:`curvenet.methods.robust.thresholds`) are appended to
their arguments here (``Kernel.groups``): the compiled code never holds a value of its own.

numba's disk cache (``cache=True``) checks only the source file of the function it caches: after
editing a helper in another module (say ``linalg.py``), a kernel that calls it (say
``frames._tangents``) loads its old compiled code until its own file changes too. Delete the
``*.nbi`` / ``*.nbc`` files of ``kernels/__pycache__`` then (tests/test_robust_kernels.py's
bit-equality checks of compiled against plain runs catch a stale cache).
"""

from __future__ import annotations

import contextvars
import os
import sys
import types
from contextlib import contextmanager
from typing import Callable, NamedTuple

import numpy as np

from ...._sigint import held
from ..thresholds import CHAINS, ENDS, LINALG, NODES, NOISY, NUMERIC, SHELL, SPACING, STRAND, STRIP, UNTANGLE, VOTE
from . import chains, frames, graph, heap, linalg, nodes, shell
from .nodes import JunctionParams

__all__ = [
    "Kernel", "KERNELS", "HAVE_NUMBA", "compiled_for", "compiled_only", "first_use_hook", "in_cache", "compile_pending", "compiled_active", "NUMBA_MIN_POINTS",
    "NUMBA_MIN_POINTS_NOISY", "STRAND_KERNELS", "PAR_MIN", "spacing", "shell_groups", "csr_union",
    "components", "chain_order", "chain_ends", "end_count", "end_counts", "tangents", "linked_edges",
    "short_links", "junction_nodes", "trim_ends", "untangle", "noisy_tangents", "strand_cuts",
    "vote_agreement", "vote_eig", "envelope_solve",
]

#: Inputs with fewer points than this run the plain-Python kernels even when numba is there,
#: unless the compiled ones are already loaded in this process: the Python kernels take about
#: a millisecond per point, less than loading compiled kernels from numba's cache (about 1 s)
#: and far less than compiling them on a first run (15 to 20 s).
NUMBA_MIN_POINTS = 2000

#: The same threshold for the kernels of the strand test, which run on noisy input only
#: (:func:`~.frames._noisy_tangents`, :func:`~.graph._strand_cuts`, and the vote of the noisy
#: tangents), when numba's disk cache already holds them (see :func:`compiled_for`): in plain
#: Python they take 2 to 10 ms a point (the 515-point tree under noise 0.3h + x3: 2.5 s in all,
#: 0.9 s with them compiled), loading them about 0.4 s; compiling them (about 30 s) is left to a
#: first run on :data:`NUMBA_MIN_POINTS` points or more.
NUMBA_MIN_POINTS_NOISY = 200

#: the kernels of the strand test (see NUMBA_MIN_POINTS_NOISY)
STRAND_KERNELS = ("noisy_tangents", "strand_cuts", "vote_agreement", "vote_eig")

#: Below this many points (the first argument's length) a parallel kernel runs on one thread:
#: starting a parallel loop costs microseconds on an idle machine, but when another process
#: keeps the other cores busy it waits for a time slice (10 to 20 ms measured on 2 cores), more
#: than the whole work of a light kernel on a small input. Results never depend on it.
PAR_MIN = {"tangents": 20_000, "noisy_tangents": 20_000, "strand_cuts": 20_000, "shell_groups": 20_000,
           "linked_edges": 200_000, "vote_eig": 200_000}

#: Inputs of more points than this are visited in a cache-friendly spatial order by the
#: per-point kernels (:func:`curvenet.neighbors.locality_order`); smaller ones in index order.
#: Results never depend on it.
ORDER_MIN_POINTS = 100_000

#: Blocks per thread of the parallel shell kernel (a few, for balance; one scratch set of about
#: 44 bytes a point per block). Results never depend on it.
BLOCKS_PER_THREAD = 4

#: The shell kernel numbers points with int32 ids (half the scratch memory): more points than
#: this are refused.
MAX_SHELL_POINTS = 2**31 - 1

#: The kernels whose loops run in parallel when compiled (``prange`` over independent points or
#: blocks of points); the light vote_agreement and short_links stay serial: their parallel
#: versions cost about 2 s of compile each, more than they save.
PARALLEL = frozenset({"tangents", "shell_groups", "linked_edges", "vote_eig", "noisy_tangents", "strand_cuts"})

#: Helpers inlined into their callers when compiled (as calls, the heap's cost the shell
#: kernel 25%).
INLINE = frozenset({heap._heap_pop, heap._heap_push, linalg._sym2, chains._dist2, graph._dist, frames._noisy_scales,
                    graph._mean_line_offset, graph._dist2_to, graph._spread2, graph._upper})


class Kernel(NamedTuple):
    """One kernel of the robust method, in both versions.

    Attributes
    ----------
    plain : callable
        The function as written (plain Python).
    compiled : numba dispatcher or None
        Its compiled version (None without numba).
    groups : tuple of NamedTuple
        The threshold groups appended to its arguments.
    """

    plain: Callable
    compiled: Callable | None
    groups: tuple


def _load_numba():
    """numba, unless it is missing or ``CURVENET_NO_NUMBA`` is set (None then)."""
    if os.environ.get("CURVENET_NO_NUMBA", "") in ("1", "true", "yes"):
        return None
    try:  # pragma: no cover - depends on the environment
        import numba
    except ImportError:  # pragma: no cover
        return None
    return numba


numba = _load_numba()
HAVE_NUMBA = numba is not None


def _is_kernel_function(obj) -> bool:
    """Whether ``obj`` is a plain function of a topic module of this package (a helper)."""
    return (isinstance(obj, types.FunctionType) and obj.__module__.startswith(__package__ + ".")
            and obj.__module__ != __name__)


def _compile(f, done: dict, parallel: bool = False):
    """numba's version of the plain function ``f`` (helpers first, memoized in ``done``).

    A copy of ``f`` (same code, same name, so numba's disk cache finds it) whose globals map
    every helper ``f`` calls to the helper's compiled version and ``prange`` to numba's; the
    module's own globals are left as they are.
    """
    if f in done:
        return done[f]
    ns = dict(f.__globals__)
    for name in f.__code__.co_names:
        if name == "prange":
            ns[name] = numba.prange
        elif _is_kernel_function(ns.get(name)):
            ns[name] = _compile(ns[name], done)
    copy = types.FunctionType(f.__code__, ns, f.__name__, f.__defaults__, f.__closure__)
    copy.__qualname__ = f.__qualname__
    copy.__doc__ = f.__doc__
    opts = {"cache": True, "nogil": True}
    if f in INLINE:
        opts["inline"] = "always"
    if parallel:
        opts["parallel"] = True
    done[f] = numba.njit(**opts)(copy)
    return done[f]


# each kernel: its plain function and the threshold groups appended to its arguments
_PLAIN = {
    "spacing": (frames._spacing, (SPACING,)),
    "tangents": (frames._tangents, (STRIP, LINALG)),
    "noisy_tangents": (frames._noisy_tangents, (NOISY, LINALG)),
    "vote_agreement": (frames._vote_agreement, ()),
    "vote_eig": (frames._vote_eig, (VOTE, LINALG)),
    "linked_edges": (graph._linked_edges, ()),
    "short_links": (graph._short_links, ()),
    "csr_union": (graph._csr_union, ()),
    "components": (graph._components, ()),
    "strand_cuts": (graph._strand_cuts, (STRAND, LINALG)),
    "shell_groups": (shell._shell_groups, (SHELL, NUMERIC)),
    "chain_order": (chains._chain_order, (CHAINS,)),
    "chain_ends": (chains._chain_ends, (CHAINS,)),
    "untangle": (chains._untangle, (UNTANGLE,)),
    "end_count": (nodes._end_count, ()),
    "end_counts": (nodes._end_counts, (ENDS,)),
    "junction_nodes": (nodes._junction_nodes, (ENDS, NODES, LINALG)),
    "trim_ends": (nodes._trim_ends, (ENDS,)),
    "envelope_solve": (linalg._envelope_solve, ()),
}


def _build() -> tuple[types.MappingProxyType, types.MappingProxyType]:
    """The kernels (name -> :class:`Kernel`) and the compiled version of every plain function
    (kernels and helpers), both read-only."""
    done: dict = {}
    kernels = {}
    for name, (f, groups) in _PLAIN.items():
        jit = _compile(f, done, name in PARALLEL) if HAVE_NUMBA else None
        kernels[name] = Kernel(f, jit, groups)
    return types.MappingProxyType(kernels), types.MappingProxyType(done)


KERNELS, _COMPILED_OF = _build()


def compiled_version(f):
    """The compiled version of the plain kernel or helper ``f`` (None without numba)."""
    return _COMPILED_OF.get(f)


_COMPILED = contextvars.ContextVar("curvenet_robust_compiled", default=True)

# the kernels that run compiled inside compiled_only (None: outside it, compiled_for decides)
_ONLY: contextvars.ContextVar = contextvars.ContextVar("curvenet_robust_only", default=None)

# called with a kernel's name before its first compiled run in this process (see first_use_hook)
_FIRST_USE: contextvars.ContextVar = contextvars.ContextVar("curvenet_robust_first_use", default=None)


@contextmanager
def compiled_for(n: int, min_points: int | None = None, cached: tuple = ()):
    """Run the kernels of the enclosed block compiled when numba is there and ``n`` (the number
    of points) is at least ``min_points`` (default :data:`NUMBA_MIN_POINTS`) and numba's disk
    cache holds the kernels ``cached`` (so that they load, not compile), as plain Python
    otherwise (same results). Blocks nest: the inner one decides for its kernels. Yields
    whether they run compiled."""
    lim = NUMBA_MIN_POINTS if min_points is None else min_points
    use = HAVE_NUMBA and ((n >= lim and _in_cache(cached)) or _compiled_already())
    token = _COMPILED.set(use)
    try:
        yield use
    finally:
        _COMPILED.reset(token)


@contextmanager
def compiled_only(names):
    """Run exactly the kernels ``names`` compiled in the enclosed block, every other one in plain
    Python, whatever the number of points and numba's cache (same results either way). For the
    warm-up that compiles a share of the kernels (:mod:`curvenet.methods.robust.warmup`)."""
    token = _ONLY.set(frozenset(names) if HAVE_NUMBA else frozenset())
    try:
        yield
    finally:
        _ONLY.reset(token)


@contextmanager
def first_use_hook(hook):
    """Call ``hook(name)`` in the enclosed block before a kernel runs compiled for the first time
    in this process (numba then loads or compiles it), outside the block that holds Ctrl-C, and
    not inside :func:`compiled_only` (the warm-up's own runs). For the shared compile of the
    kernels that only some inputs call (:func:`curvenet.methods.robust.warmup.on_first_use`)."""
    token = _FIRST_USE.set(hook)
    try:
        yield
    finally:
        _FIRST_USE.reset(token)


def _cache_index(name: str) -> str | None:
    """Path of the index file numba's disk cache keeps for the kernel ``name`` (None when it is
    not compiled). numba's documentation ("Notes on caching") describes the cache as an index file
    (``.nbi``) and data files (``.nbc``) in the ``__pycache__`` folder beside the source (or in
    ``NUMBA_CACHE_DIR``); the index is named ``<module>.<qualname>-<first line>.py<version>.nbi``.
    """
    k = KERNELS[name]
    stats = getattr(k.compiled, "stats", None)  # (none: no numba, or NUMBA_DISABLE_JIT=1)
    if stats is None:
        return None
    f = k.plain
    folder = stats.cache_path
    module = os.path.splitext(os.path.basename(f.__code__.co_filename))[0]
    tag = "py%d%d%s" % (sys.version_info[0], sys.version_info[1], getattr(sys, "abiflags", ""))
    return os.path.join(folder, f"{module}.{f.__qualname__}-{f.__code__.co_firstlineno}.{tag}.nbi")


def _in_cache(names) -> bool:
    """True when numba's disk cache holds a compiled version of every kernel ``names`` (none:
    True) that this process will load instead of compiling: see :func:`_loads_from_cache`."""
    for name in names:
        answer = _loads_from_cache(KERNELS[name].compiled)
        if answer is None:  # (a numba without the cache objects read there)
            answer = _index_newer_than_source(name)
        if not answer:
            return False
    return True


def _loads_from_cache(dispatcher) -> bool | None:
    """numba's own answer to "will ``dispatcher`` load from the disk cache": its cache index is
    fresh by numba's rule (same numba version, same source stamp: the source file's time and
    size in older numba, a hash of its content since 0.6x, so a reinstalled but unchanged source
    still loads) and holds an entry compiled for this machine's processor. None when this numba
    does not expose its cache index (the attributes read here are numba's, not documented)."""
    try:
        cache_file = dispatcher._cache._cache_file
        magic = dispatcher.targetctx.codegen().magic_tuple()
    except AttributeError:
        return None
    try:
        index = cache_file._load_index()
    except Exception:  # an unreadable index: numba would compile
        return False
    return any(len(key) > 1 and key[1] == magic for key in index)


def in_cache(names) -> bool:
    """Whether numba's disk cache holds every kernel of ``names`` for this numba and source
    (see :func:`_in_cache`)."""
    return _in_cache(names)


def _index_newer_than_source(name: str) -> bool:
    """The cache rule of older numba, for a numba whose cache objects are not readable: the
    kernel's index file exists and is newer than its source."""
    path = _cache_index(name)
    try:
        return path is not None and os.path.getmtime(path) >= os.path.getmtime(
            KERNELS[name].plain.__code__.co_filename)
    except OSError:
        return False


def _compiled_already() -> bool:
    """True once the compiled tangent kernel (which every robust run calls) ran in this process:
    numba's cache is then warm, and small inputs gain from the compiled kernels too. (The
    strand test's kernels run compiled on their own, see :data:`NUMBA_MIN_POINTS_NOISY`.)"""
    # (no signatures: numba absent, or NUMBA_DISABLE_JIT=1 made its version plain Python)
    return bool(getattr(KERNELS["tangents"].compiled, "signatures", None))


#: The kernels every robust run on :data:`NUMBA_MIN_POINTS` points or more calls, the heaviest to
#: compile (parallel): when numba's cache lacks one of them, the run starts with the compile of
#: the kernels (about a minute, see docs/performance.json "compile"). Kernels that only some
#: inputs need (``untangle``, the strand test's) compile on their first use, a few seconds each,
#: unannounced.
COMPILE_MARKERS = ("spacing", "tangents", "linked_edges", "shell_groups", "junction_nodes")


def compile_pending(n: int) -> bool:
    """True when a run on ``n`` points will compile kernels first: numba is there, ``n`` is
    enough for the compiled kernels (see :func:`compiled_for`), none has run in this process,
    and numba's disk cache lacks one of :data:`COMPILE_MARKERS` (its index file, see
    :func:`_in_cache`). The compile happens once per machine, numba version and kernel source;
    later runs load it."""
    if not HAVE_NUMBA or n < NUMBA_MIN_POINTS or _compiled_already():
        return False
    return not _in_cache(COMPILE_MARKERS)


def compiled_active() -> bool:
    """True when the kernels run compiled here (numba there, see :func:`compiled_for`; inside
    :func:`compiled_only`, when some do)."""
    only = _ONLY.get()
    if only is not None:
        return bool(only)
    return HAVE_NUMBA and _COMPILED.get()


def _kernel(name: str):
    """The version of the kernel ``name`` that runs here (see :func:`compiled_for` and
    :func:`compiled_only`)."""
    k = KERNELS[name]
    only = _ONLY.get()
    if only is not None:
        return k.compiled if name in only else k.plain
    return k.compiled if compiled_active() else k.plain


@contextmanager
def _threads_for(name: str, n: int):
    """Run the enclosed parallel kernel ``name`` on ``n`` points on one thread when ``n`` is
    under :data:`PAR_MIN` (and numba runs it)."""
    if name not in PAR_MIN or n >= PAR_MIN[name] or not compiled_active():
        yield
        return
    old = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(old)


def _run(name: str, args: tuple, n: int = 0):
    """Run the kernel ``name`` on ``args`` (its groups appended), ``n`` points for
    :func:`_threads_for`; Ctrl-C waits for it (see curvenet._sigint)."""
    hook = _FIRST_USE.get()
    if hook is not None and _ONLY.get() is None and compiled_active() and not getattr(
            KERNELS[name].compiled, "signatures", None):
        hook(name)
    with held(), _threads_for(name, n):
        return _kernel(name)(*args, *KERNELS[name].groups)


def _dispatch(name: str):
    """A function that runs the kernel ``name`` compiled or in plain Python (see compiled_for)."""

    def run(*args):
        return _run(name, args, len(args[0]) if name in PAR_MIN else 0)

    f = KERNELS[name].plain
    run.__name__ = run.__qualname__ = name
    run.__doc__ = f"Run the kernel :func:`{f.__module__}.{f.__name__}`, compiled or in plain Python."
    return run


spacing = _dispatch("spacing")
components = _dispatch("components")
chain_order = _dispatch("chain_order")
chain_ends = _dispatch("chain_ends")
linked_edges = _dispatch("linked_edges")
short_links = _dispatch("short_links")
csr_union = _dispatch("csr_union")
end_count = _dispatch("end_count")
end_counts = _dispatch("end_counts")
trim_ends = _dispatch("trim_ends")
untangle = _dispatch("untangle")
strand_cuts = _dispatch("strand_cuts")
vote_agreement = _dispatch("vote_agreement")
vote_eig = _dispatch("vote_eig")
envelope_solve = _dispatch("envelope_solve")


def _order(P):
    """A cache-friendly visiting order of the points (results never depend on it)."""
    if P.shape[0] <= ORDER_MIN_POINTS:
        return np.arange(P.shape[0], dtype=np.int64)
    from ....neighbors import locality_order

    return locality_order(P)


def tangents(P, idx, h, m, order=None, margin=None):
    """Tangent, linearity, strip chord distance and candidate gain of every point: see
    :func:`~.frames._tangents` (``order``: the visiting order when already computed, see
    :func:`_order`, or a subset of the points; ``margin``: default ``STRIP.cand_margin``)."""
    margin = STRIP.cand_margin if margin is None else float(margin)
    order = _order(P) if order is None else np.ascontiguousarray(order, dtype=np.int64)
    return _run("tangents", (P, idx, h, m, order, margin), len(order))


def noisy_tangents(P, rows, idx, h, sig):
    """Noisy tangents and linearity of the points ``rows``: see :func:`~.frames._noisy_tangents`."""
    return _run("noisy_tangents", (P, rows, idx, h, sig), len(rows))


def shell_groups(P, h, indptr, indices, r_in, r_out, subset=None, order=None, goes_on=False):
    """Shell group count of every point (or of the points ``subset``, the others 0): see
    :func:`~.shell._shell_groups` (``order``: the visiting order of all points when already
    computed, see :func:`_order`; ``goes_on``: a group going on past the shell counts too)."""
    if P.shape[0] >= MAX_SHELL_POINTS:
        raise ValueError("too many points for the shell test (int32 ids)")
    if subset is not None:
        order = np.sort(np.asarray(subset, dtype=np.int64))
    elif order is None:
        order = _order(P)
    par = compiled_active() and len(order) >= PAR_MIN["shell_groups"]
    nblocks = BLOCKS_PER_THREAD * numba.get_num_threads() if par else 1
    return _run("shell_groups", (P, h, indptr, indices, r_in, r_out, bool(goes_on), order, nblocks), len(order))


def junction_nodes(P, h, indptr, indices, bflat, boff, jb, rflat, roff, hj, width, noise, params):
    """Node position of many junctions at once: see :func:`~.nodes._junction_nodes`
    (``params``: a :class:`~.nodes.JunctionParams`)."""
    if not isinstance(params, JunctionParams):
        raise TypeError(f"junction_nodes takes a JunctionParams, got {type(params).__name__}")
    # one field type per field: the compiled kernel is typed (and cached) once
    params = JunctionParams(*(float(v) for v in params[:-1]), bool(params.use_graph))
    return _run("junction_nodes", (P, h, indptr, indices, bflat, boff, jb, rflat, roff, hj, width, noise, params))
