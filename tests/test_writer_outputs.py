"""The writers write the same bytes as before they were vectorised (issue 22), with and without
orjson, and their numbers are ``repr``'s.

``tests/data/writer_digests.json`` holds the SHA-256 of each writer's output for the networks of
:func:`sample_networks.writer_networks`, written by the writers of main before the change
(``python tests/test_writer_outputs.py --regenerate`` rewrites it from the writers at hand: only
do that for a deliberate change of a format).
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from sample_networks import writer_networks  # noqa: E402

from curvenet.io import WRITERS  # noqa: E402
from curvenet.io import numbers  # noqa: E402
from curvenet.io.labels import labels_to_csv  # noqa: E402

DIGESTS = Path(__file__).parent / "data" / "writer_digests.json"

#: (extension, writer options) pinned; .json depends on whether orjson is installed (its own
#: tests cover it) and .dxf is ezdxf's text (unchanged, with a creation time inside)
CASES = [
    (".obj", {}), (".ply", {}), (".ply", {"curve_ids": True}), (".svg", {}), (".svg", {"projection": "iso"}),
    (".vtp", {}), (".vtp", {"encoding": "base64"}), (".vtu", {}), (".graphml", {}), (".geojson", {}),
    (".swc", {}), (".swc", {"radius": 0.25, "sample_type": 3}),
]


def _key(name: str, ext: str, opts: dict) -> str:
    return f"{name}{ext}" + "".join(f",{k}={v}" for k, v in sorted(opts.items()))


def _labels(net) -> np.ndarray:
    n = 3 + sum(len(c.points) for c in net.curves)
    i = np.arange(n)
    return np.column_stack([np.where(i % 3 == 0, -1, i % 7), np.where(i % 5 == 0, i % 4, -1)])


def _digest(data) -> str:
    return hashlib.sha256(data.encode("utf-8") if isinstance(data, str) else data).hexdigest()


def outputs() -> dict:
    out = {}
    for name, net in writer_networks().items():
        for ext, opts in CASES:
            if name.endswith("2") and opts.get("projection") == "iso":
                continue  # a 2D network has one view
            if name == "empty" and ext == ".obj":
                continue  # main's writer raised on it (reshape of 0 rows); see test_empty_obj
            out[_key(name, ext, opts)] = _digest(WRITERS[ext][0](net, **opts))
        out[f"{name}.labels.csv"] = _digest(labels_to_csv(_labels(net)))
    return out


@pytest.fixture(scope="module")
def expected() -> dict:
    return json.loads(DIGESTS.read_text())


@pytest.mark.parametrize("orjson", [True, False], ids=["orjson", "repr"])
def test_outputs_unchanged(expected, orjson, monkeypatch):
    if orjson:
        pytest.importorskip("orjson")
    else:
        monkeypatch.setattr(numbers, "_orjson", lambda: None)
    got = outputs()
    assert set(got) == set(expected)
    differ = sorted(k for k in got if got[k] != expected[k])
    assert not differ


def _random_networks(count: int = 150) -> list:
    from curvenet import Curve, CurveNetwork

    rng = np.random.default_rng(5)
    nets = list(writer_networks().values())
    for _ in range(count):
        d, n = int(rng.integers(2, 4)), int(rng.integers(0, 6))
        curves = []
        for _ in range(int(rng.integers(0, 8))):
            m = int(rng.integers(0, 6))
            if n and rng.random() < 0.7:
                s, e = (int(x) for x in rng.integers(0, n, 2))
                curves.append(Curve(rng.normal(size=(m, d)), s, e, bool(rng.random() < 0.3)))
            else:
                curves.append(Curve(rng.normal(size=(m, d)), None, None, bool(rng.random() < 0.5)))
        nets.append(CurveNetwork(rng.normal(size=(n, d)), curves))
    return nets


def test_batched_polylines_and_lengths_are_the_network_s():
    from curvenet.io.polylines import curve_lengths, polyline_vertices, segments

    for net in _random_networks():
        v, lines = net.polyline_vertices()
        v2, lines2 = polyline_vertices(net)
        assert v.shape == v2.shape and np.array_equal(v, v2)
        assert len(lines) == len(lines2)
        assert all(a.dtype == b.dtype and np.array_equal(a, b) for a, b in zip(lines, lines2))
        for a, b in zip(net.segments(), segments(net)):
            assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
        assert np.array_equal(curve_lengths(net.curves), [c.length for c in net.curves])  # bit for bit


def test_empty_obj():
    net = writer_networks()["empty"]
    assert WRITERS[".obj"][0](net) == "# curvenet network: 0 nodes, 0 curves\n# nodes are vertices 1..0\n"


if __name__ == "__main__":
    if "--regenerate" in sys.argv:
        DIGESTS.write_text(json.dumps(outputs(), indent=1, sort_keys=True) + "\n")
        print(f"wrote {DIGESTS}")
