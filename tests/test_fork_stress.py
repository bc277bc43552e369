"""The close-junction stress script runs (its quick form), so it cannot rot."""

from __future__ import annotations

import subprocess
import sys

import pytest

from bench_scripts import BENCH, has, load

pytestmark = pytest.mark.skipif(not has("fork_stress"), reason="benchmarks/ not in this checkout")


@pytest.fixture(scope="module")
def fork_stress():
    return load("fork_stress")


def test_quick_run_counts_every_case(fork_stress):
    res = fork_stress.run("robust", quick=True)
    assert list(res) == ["clean", "noise", "ratio", "both"]
    for ok, n, fails in res.values():
        assert n == 4 and ok + len(fails) == n
    # clean forks 5h and 9h from the T, 40 and 90 degrees wide: all two junctions
    assert res["clean"][0] == 4


def test_cli_quick():
    out = subprocess.run([sys.executable, str(BENCH / "fork_stress.py"), "--quick"], capture_output=True,
                         text=True, check=True, cwd=BENCH).stdout
    assert out.count("exact") == 4 and "total" in out
