"""Stage 5: a chain's end reads the regions it touches within one link of it
(``CHAINS.end_reach``, :func:`curvenet.methods.robust.kernels.chains._chain_ends`)."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import synth
from curvenet.methods.robust import chains
from curvenet.methods.robust.kernels import registry
from curvenet.methods.robust.thresholds import CHAINS
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct

from test_quality_kinds import _sampled


def _with_reach(monkeypatch, reach):
    """The chains' ends read over ``reach`` spacings: the kernel's threshold group and the
    Python readers' (passed regions, short chains) alike."""
    ch = CHAINS._replace(end_reach=reach)
    kernels = dict(registry.KERNELS)
    kernels["chain_ends"] = kernels["chain_ends"]._replace(groups=(ch,))
    monkeypatch.setattr(registry, "KERNELS", kernels)
    monkeypatch.setattr(chains, "CHAINS", ch)


def _score(name, condition, k):
    pts, truth = _sampled(name, condition, k)
    return compare(reconstruct(pts, method="robust"), truth, h=synth.h_of(truth))


def _ends(n):
    """One chain of ``n`` points 1 apart along x, its start touching region 0 (its first point
    linked to it) and regions 1 (three contacts) and 2 past that, as ``_chain_ends`` reads them."""
    h = np.ones(n)
    ids = np.arange(n, dtype=np.int64)
    par = np.arange(n, dtype=np.float64)
    bounds = np.array([0, n], dtype=np.int64)
    c_reg = np.array([0, 1, 1, 1], dtype=np.int64)
    c_par = np.array([0.0, 2.0, 3.0, 3.0])  # region 1: 2 and 3 spacings from the start
    cb = np.array([0, 4], dtype=np.int64)
    return h, ids, par, bounds, c_reg, c_par, cb


@pytest.mark.parametrize("reach, start", [(CHAINS.end_reach, 0), (4.0, 1)])
def test_the_start_takes_the_region_within_its_reach(reach, start):
    from curvenet.methods.robust.kernels.chains import _chain_ends

    ends, touch = _chain_ends(*_ends(12), CHAINS._replace(end_reach=reach))
    assert touch.tolist() == [True]
    # within 2.5 spacings: region 0 (one contact) and region 1 (one, at 2): the lower id; over
    # 4 spacings region 1's three contacts outnumber region 0's one
    assert ends[0, 0] == start and ends[0, 1] == -1


def test_the_outline_under_noise_keeps_its_junctions(monkeypatch):
    # the building outline at noise 0.2 h, sampling 7: a chain's end read over 4 spacings went
    # to a region it passes 3-4 h before its end (more contacts than the region at its last
    # samples): 25 of 26 nodes, curve F1 0.940; read within a link, exact
    assert CHAINS.end_reach < 4.0
    now = _score("outline", "noise 0.2h", 7)
    assert now["exact_topology"] and now["curve_f1"] == 1.0
    _with_reach(monkeypatch, 4.0)
    before = _score("outline", "noise 0.2h", 7)
    assert not before["exact_topology"] and before["curve_f1"] < 0.95
