"""The start-up benchmark script runs (tiny sizes, its writers part), so it cannot rot; its
network cache reads back the network it saved. No timing assertions."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "startup.py"
pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="benchmarks/startup.py not in this checkout")


def _load():
    sys.path.insert(0, str(SCRIPT.parent))
    spec = importlib.util.spec_from_file_location("curvenet_startup_bench", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_network_cache_round_trip(tmp_path):
    from sample_networks import writer_networks

    bench = _load()
    for name, net in writer_networks().items():
        path = tmp_path / f"{name}.npz"
        bench.save_network(net, path)
        back = bench.load_network(path)
        assert back == net and back.parameters == net.parameters


def test_writers_part_runs(tmp_path):
    from curvenet.io import WRITERS

    r = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--part", "writers", "--cache", str(tmp_path),
                        "--formats", ",".join(e for e in WRITERS if e != ".dxf")],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    for ext in WRITERS:
        if ext != ".dxf":
            assert f"  {ext} " in r.stdout
    assert "x query" in r.stdout and (tmp_path / "curvenet_startup_net_3000.npz").exists()
