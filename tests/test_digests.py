"""The default method's networks stay identical to the bit (issue 19: a redesign, not a retune).

Twenty runs of the robustness sweep (every condition, many models and samplings, two CASSIE
sketches when the dataset is there) are compared with the digests stored from main before the
redesign (``tests/data/robust_digests.json``, written by ``benchmarks/robust_digests.py``,
which also checks the whole sweep by hand).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from bench_scripts import load

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "robust_digests.py"


DIG = load("robust_digests")
STORED = json.loads(DIG.STORE.read_text())["digests"]


@pytest.mark.parametrize("run_id", DIG.SUBSET)
def test_network_is_unchanged(run_id):
    got = DIG.digest_of(run_id)
    if got is None:
        pytest.skip(f"{run_id}: the CASSIE dataset is not here")
    assert got == STORED[run_id], f"{run_id}: the network differs from the stored one"


def test_digest_sees_one_bit():
    """A digest changes when one node coordinate moves by one unit in the last place."""
    import numpy as np

    from curvenet import synth
    from curvenet.reconstruct import reconstruct

    net = reconstruct(synth.sample(synth.model("crossing"), rng=3)[0], method="robust")
    d0 = DIG.network_digest(net)
    net.nodes[0, 0] = np.nextafter(net.nodes[0, 0], np.inf)
    assert DIG.network_digest(net) != d0


def test_subset_covers_every_condition_and_is_stored():
    conds = {r.split("/")[2] for r in DIG.SUBSET if r.startswith("synthetic/")}
    assert conds == set(DIG.CONDITION_NAMES)
    assert set(DIG.SUBSET) <= set(STORED)
    assert len(STORED) >= 512
