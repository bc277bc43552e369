"""The real-dev loader (curvenet.synth.realdev) and its benchmark table."""

import json

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.errors import FormatError, InputError
from curvenet.synth import realdev

needs_data = pytest.mark.skipif(not realdev.available(), reason="real-dev dataset not found")


def _write(tmp_path, **over):
    data = {"name": "t", "kind": "neuron", "source": "test", "licence": "-", "spacing": 0.1,
            "nodes": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
            "curves": [{"points": [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]], "start": 0, "end": 1, "closed": False},
                       {"points": [[0, 0, 0], [0, 1, 0]], "start": 0, "end": 2, "closed": False},
                       {"points": [[0, 0, 0], [0, 0, 1]], "start": 0, "end": 3, "closed": False}]}
    data.update(over)
    p = tmp_path / "t.json"
    p.write_text(json.dumps(data))
    return p


def test_load_a_file(tmp_path):
    net = realdev.load(_write(tmp_path))
    assert (net.n_nodes, net.n_curves) == (4, 3) and net.parameters["h"] == 0.1
    assert net.parameters["kind"] == "neuron" and net.parameters["model"] == "t"
    assert sorted(net.valence.tolist()) == [1, 1, 1, 3]


@pytest.mark.parametrize("over, msg", [
    ({"spacing": -1}, "spacing"),
    ({"nodes": "x"}, "not a real-dev"),
    ({"curves": [{"points": [[0, 0, 0], [1, 0, 0]], "start": 0, "end": 9}]}, "out of range"),
    ({"curves": [{"points": [[0, 0, 0], [2, 0, 0]], "start": 0, "end": 1}]}, "start and end"),
    ({"curves": [{"points": [[0, 0]], "start": 0, "end": 1}]}, "3D points"),
])
def test_bad_files_are_format_errors(tmp_path, over, msg):
    with pytest.raises(FormatError, match=msg):
        realdev.load(_write(tmp_path, **over))


def test_missing_model_is_an_input_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CURVENET_REALDEV", str(tmp_path))
    assert not realdev.available() and realdev.names() == []
    with pytest.raises(InputError, match="CURVENET_REALDEV"):
        realdev.load("nrn_nothing")
    with pytest.raises(InputError):
        realdev.names("tree")
    assert bench.run_realdev(["emst"]) == []


@needs_data
def test_every_model_loads_as_its_readme_says():
    names = realdev.names()
    assert len(names) == 20 and len(realdev.names("neuron")) == 10 and len(realdev.names("building")) == 10
    for n in names:
        raw = json.loads((realdev.root() / f"{n}.json").read_text())
        net = realdev.load(n, contract=False)
        assert (net.n_nodes, net.n_curves) == (len(raw["nodes"]), len(raw["curves"]))
        c = realdev.load(n)
        assert 2 not in set(c.valence.tolist())
        # the free loops are the files' closed curves
        assert sum(x.start is None for x in c.curves) == sum(bool(x["closed"]) for x in raw["curves"])


@needs_data
def test_clean_sample_size_matches_the_readme():
    # "points at h" of the README table for two models: our sampler follows its recipe
    for name, n in (("bld_zurich_82037b5d", 2051), ("nrn_CTh5080328L_s4", 2050)):
        pts, _ = synth.sample(realdev.load(name))
        assert abs(len(pts) - n) <= 0.01 * n


@needs_data
def test_run_realdev_rows():
    rows = bench.run_realdev(["emst"], ["bld_zurich_c0961fd6", "nrn_CTh5080328L_s4"])
    assert len(rows) == 2 * len(bench.REALDEV_CONDITIONS)
    assert {r["kind"] for r in rows} == {"building", "neuron"}
    assert all(r["dataset"] == "realdev" and r["error"] is None for r in rows)
    md = bench.write_markdown(rows, command="test")
    assert "## Real networks (real-dev" in md and "| building | clean | emst | 1 |" in md
    assert np.isfinite([r["curve_f1"] for r in rows]).all()
