"""Small inputs run the plain-Python kernels (no numba compile on a first run); same results.
The two versions of every kernel live side by side: switching never rewrites a module global."""

import os

import numpy as np
import pytest

import curvenet
from curvenet.methods.robust import kernels as K
from curvenet.methods.robust.kernels import chains, frames, graph, heap, linalg, nodes, shell
from curvenet.methods.robust.kernels import registry as KR
from curvenet import synth


def _sig(net):
    c = net.canonical()
    return [(x.start, x.end, x.indices.tolist(), np.round(x.points, 9).tolist()) for x in c.curves], np.round(c.nodes, 9).tolist()


def test_size_picks_the_kernels(monkeypatch):
    monkeypatch.setattr(KR, "_compiled_already", lambda: False)  # as in a fresh process
    with K.compiled_for(10) as use:
        assert use is False
        assert KR._kernel("tangents") is KR.KERNELS["tangents"].plain is frames._tangents
    with K.compiled_for(10**6) as use:
        assert use is K.HAVE_NUMBA
        if use:
            assert KR._kernel("tangents") is KR.KERNELS["tangents"].compiled


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_python_and_compiled_paths_agree(monkeypatch):
    truth = synth.model("crossing")
    pts, _ = synth.sample(truth, noise=0.3, density_ratio=3, rng=4)
    monkeypatch.setattr(KR, "NUMBA_MIN_POINTS", 10**9)
    with monkeypatch.context() as m:
        m.setattr(KR, "_compiled_already", lambda: False)  # the Python run, even after compiled ones
        a = curvenet.reconstruct(pts)
    monkeypatch.setattr(KR, "NUMBA_MIN_POINTS", 0)
    b = curvenet.reconstruct(pts)
    assert _sig(a) == _sig(b)


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_small_inputs_use_compiled_kernels_once_loaded(monkeypatch):
    truth = synth.model("cube")
    pts, _ = synth.sample(truth, rng=1)
    monkeypatch.setattr(KR, "NUMBA_MIN_POINTS", 0)
    curvenet.reconstruct(pts)  # compiles or loads every kernel that runs
    monkeypatch.setattr(KR, "NUMBA_MIN_POINTS", 10**9)
    assert KR._compiled_already()
    with K.compiled_for(10) as use:
        assert use is True


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_small_noisy_input_runs_the_strand_kernels_compiled_once_cached(monkeypatch):
    # the strand test costs 2-10 ms a point in plain Python: over NUMBA_MIN_POINTS_NOISY points
    # its kernels run compiled when numba's cache holds them (a load, not a compile), the rest
    # of a small input as plain Python; the same result
    truth = synth.model("crossing")
    pts, _ = synth.sample(truth, noise=0.3, density_ratio=3, rng=4)
    assert K.NUMBA_MIN_POINTS_NOISY <= len(pts) < KR.NUMBA_MIN_POINTS
    with monkeypatch.context() as m:
        m.setattr(KR, "NUMBA_MIN_POINTS", 0)
        curvenet.reconstruct(pts)  # compiles (or loads) every kernel: numba caches them
    # in the cache (numba's index files: tests below check that _in_cache reads them); given,
    # not read here: in one CI run the index files were not found after this run (not
    # reproduced, in the suite's order or alone, in an editable or a built install)
    monkeypatch.setattr(KR, "_in_cache", lambda names: True)
    monkeypatch.setattr(KR, "_compiled_already", lambda: False)  # as in a fresh process
    seen: dict[str, set] = {}
    kernel = KR._kernel

    def spy(name):
        f = kernel(name)
        seen.setdefault(name, set()).add(f is KR.KERNELS[name].plain)
        return f

    monkeypatch.setattr(KR, "_kernel", spy)
    a = curvenet.reconstruct(pts)
    assert seen["noisy_tangents"] == {False} and seen["strand_cuts"] == {False}
    assert seen["tangents"] == {True} and seen["shell_groups"] == {True}
    # not in the cache (a first run after installing): plain Python, no compile
    monkeypatch.setattr(KR, "_in_cache", lambda names: not names)
    seen.clear()
    b = curvenet.reconstruct(pts)
    assert seen["strand_cuts"] == {True} and seen["noisy_tangents"] == {True}
    assert _sig(a) == _sig(b)


_MODULES = (K, KR, chains, frames, graph, heap, linalg, nodes, shell)


def _globals():
    return {(m.__name__, k): v for m in _MODULES for k, v in vars(m).items()}


def _same_globals(a, b):
    return a.keys() == b.keys() and all(a[k] is b[k] for k in a)


def test_switching_versions_rewrites_no_module_global(monkeypatch):
    # whole runs, compiled then plain then compiled (both orders), on a noisy input: every kernel
    # runs (the strand test's too); the modules' globals are the same objects during each run
    # and after, and the plain kernels keep calling plain helpers
    truth = synth.model("crossing")
    pts, _ = synth.sample(truth, noise=0.3, density_ratio=3, rng=4)
    before = _globals()
    seen = []
    kernel = KR._kernel

    def spy(name):
        assert _same_globals(_globals(), before), name
        f = kernel(name)
        seen.append(f is KR.KERNELS[name].plain)
        return f

    monkeypatch.setattr(KR, "_kernel", spy)
    before = _globals()
    sigs = []
    for compiled in (K.HAVE_NUMBA, False, K.HAVE_NUMBA):
        with monkeypatch.context() as m:
            m.setattr(KR, "_compiled_already", lambda: compiled)
            m.setattr(KR, "NUMBA_MIN_POINTS", 0 if compiled else 10**9)
            m.setattr(K, "NUMBA_MIN_POINTS_NOISY", 0 if compiled else 10**9)
            before = _globals()
            seen.clear()
            sigs.append(_sig(curvenet.reconstruct(pts)))
            assert set(seen) == {not compiled}
            assert _same_globals(_globals(), before)
    assert sigs[0] == sigs[1] == sigs[2]
    for f in (frames._tangents_block, frames._noisy_tangent_at, graph._strand_cuts):
        assert f.__globals__["_pca01"] is linalg._pca01
    assert nodes._fit_end.__globals__["_eig_top"] is linalg._eig_top
    assert shell._shell_groups_block.__globals__["_heap_push"] is heap._heap_push


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_in_cache_reads_numba_s_index_file(monkeypatch, tmp_path):
    # the index numba writes beside the source once a kernel is compiled: _in_cache finds it
    KR.KERNELS["csr_union"].compiled(3, np.array([0, 1]), np.array([1, 2]))
    path = KR._cache_index("csr_union")
    assert os.path.isfile(path) and KR._in_cache(("csr_union",)) and KR._in_cache(())
    # numba's own rule decides; where this numba does not expose it, the index must be newer
    # than the source
    monkeypatch.setattr(KR, "_loads_from_cache", lambda dispatcher: None)
    src = KR.KERNELS["csr_union"].plain.__code__.co_filename
    for name, age, found in (("fresh.nbi", 10, True), ("stale.nbi", -10, False)):
        index = tmp_path / name
        index.write_bytes(b"")
        os.utime(index, (os.path.getmtime(src) + age, os.path.getmtime(src) + age))
        monkeypatch.setattr(KR, "_cache_index", lambda name, index=index: str(index))
        assert KR._in_cache(("csr_union",)) is found
    monkeypatch.setattr(KR, "_cache_index", lambda name: str(tmp_path / "missing.nbi"))
    assert not KR._in_cache(("csr_union",))


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_loads_from_cache_predicts_what_numba_does(tmp_path):
    """The answer of _loads_from_cache before a first call is what numba then does (a cache hit
    or a compile): no index yet; the source reinstalled unchanged (a newer file time: the last
    CI run failed there, on a cache left by an earlier install of the same kernels, which numba
    0.68 loads); the source edited."""
    import importlib.util

    import numba

    source = tmp_path / "cached_kernel.py"
    text = "import numba\n\n@numba.njit(cache=True)\ndef f(x):\n    return x + 1\n"

    def fresh(tag):  # the module imported anew: a new dispatcher, as in a new process
        spec = importlib.util.spec_from_file_location(f"cached_kernel_{tag}", source)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module.f

    def predicted_and_done(tag):
        f = fresh(tag)
        predicted = KR._loads_from_cache(f)
        assert f(1) == 2
        return predicted, sum(f.stats.cache_hits.values()) > 0

    source.write_text(text)
    assert predicted_and_done("a") == (False, False)  # compiled and saved
    assert predicted_and_done("b") == (True, True)  # loaded
    later = os.path.getmtime(source) + 100
    source.write_text(text)  # reinstalled: same content, a newer time
    os.utime(source, (later, later))
    predicted, done = predicted_and_done("c")
    assert predicted == done
    if tuple(int(v) for v in numba.__version__.split(".")[:2]) >= (0, 68):
        assert done  # (numba 0.68 stamps the source by its content)
    source.write_text(text.replace("x + 1", "1 + x"))  # edited
    os.utime(source, (later + 100, later + 100))
    assert predicted_and_done("d") == (False, False)
