"""Small inputs run the plain-Python kernels (no numba compile on a first run); same results."""

import numpy as np
import pytest

import curvenet
from curvenet import _robust_kernels as K
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
