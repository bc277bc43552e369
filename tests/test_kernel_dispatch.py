"""Small inputs run the plain-Python kernels (no numba compile on a first run); same results."""

import numpy as np
import pytest

import curvenet
from curvenet.methods.robust import kernels as K
from curvenet import synth


def _sig(net):
    c = net.canonical()
    return [(x.start, x.end, x.indices.tolist(), np.round(x.points, 9).tolist()) for x in c.curves], np.round(c.nodes, 9).tolist()


def test_size_picks_the_kernels(monkeypatch):
    monkeypatch.setattr(K, "_compiled_already", lambda: False)  # as in a fresh process
    with K.compiled_for(10) as use:
        assert use is False
        assert K._kernel("tangents") is K._PY["tangents"]
        assert K._pca01 is K._PY_HELPERS["_pca01"]
    with K.compiled_for(10**6) as use:
        assert use is K.HAVE_NUMBA


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_python_and_compiled_paths_agree(monkeypatch):
    truth = synth.model("crossing")
    pts, _ = synth.sample(truth, noise=0.3, density_ratio=3, rng=4)
    monkeypatch.setattr(K, "NUMBA_MIN_POINTS", 10**9)
    with monkeypatch.context() as m:
        m.setattr(K, "_compiled_already", lambda: False)  # the Python run, even after compiled ones
        a = curvenet.reconstruct(pts)
    monkeypatch.setattr(K, "NUMBA_MIN_POINTS", 0)
    b = curvenet.reconstruct(pts)
    assert _sig(a) == _sig(b)


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_small_inputs_use_compiled_kernels_once_loaded(monkeypatch):
    truth = synth.model("cube")
    pts, _ = synth.sample(truth, rng=1)
    monkeypatch.setattr(K, "NUMBA_MIN_POINTS", 0)
    curvenet.reconstruct(pts)  # compiles or loads every kernel that runs
    monkeypatch.setattr(K, "NUMBA_MIN_POINTS", 10**9)
    assert K._compiled_already()
    with K.compiled_for(10) as use:
        assert use is True


@pytest.mark.skipif(not K.HAVE_NUMBA, reason="numba not installed")
def test_small_noisy_input_runs_the_strand_kernels_compiled_once_cached(monkeypatch):
    # the strand test costs 2-10 ms a point in plain Python: over NUMBA_MIN_POINTS_NOISY points
    # its kernels run compiled when numba's cache holds them (a load, not a compile), the rest
    # of a small input as plain Python; the same result
    truth = synth.model("crossing")
    pts, _ = synth.sample(truth, noise=0.3, density_ratio=3, rng=4)
    assert K.NUMBA_MIN_POINTS_NOISY <= len(pts) < K.NUMBA_MIN_POINTS
    with monkeypatch.context() as m:
        m.setattr(K, "NUMBA_MIN_POINTS", 0)
        curvenet.reconstruct(pts)  # compiles (or loads) every kernel: numba caches them
    assert K._in_cache(K.STRAND_KERNELS)
    monkeypatch.setattr(K, "_compiled_already", lambda: False)  # as in a fresh process
    seen: dict[str, set] = {}
    kernel = K._kernel

    def spy(name):
        f = kernel(name)
        seen.setdefault(name, set()).add(f is K._PY[name])
        return f

    monkeypatch.setattr(K, "_kernel", spy)
    a = curvenet.reconstruct(pts)
    assert seen["noisy_tangents"] == {False} and seen["strand_cuts"] == {False}
    assert seen["tangents"] == {True} and seen["shell_groups"] == {True}
    # not in the cache (a first run after installing): plain Python, no compile
    monkeypatch.setattr(K, "_in_cache", lambda names: not names)
    seen.clear()
    b = curvenet.reconstruct(pts)
    assert seen["strand_cuts"] == {True} and seen["noisy_tangents"] == {True}
    assert _sig(a) == _sig(b)
