"""Networks written one curve at a time (curvenet.io.streamed): the same bytes as the writers of
the network in memory, read back by the real readers."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet import synth
from curvenet.io import network_io, read_network
from curvenet.io import streamed
from curvenet.network import Curve, CurveNetwork


class _Source:
    """A network in memory seen as a curve source (the curves handed out one at a time)."""

    def __init__(self, net: CurveNetwork):
        self.net = net
        self.nodes, self.parameters, self.stats = net.nodes, net.parameters, net.stats
        self.dimension = net.dimension

    def curve_shapes(self):
        e = self.net.edges
        return (np.array([len(c.points) for c in self.net.curves], dtype=np.int64), e[:, 0].copy(), e[:, 1].copy(),
                np.array([bool(c.closed) for c in self.net.curves], dtype=bool))

    def curves(self):
        yield from self.net.curves


def _networks():
    yield "mug", synth.model("mug")
    yield "tree", synth.model("tree")
    net = synth.model("eye")  # 2D
    yield "eye", net
    loop = Curve(np.c_[np.cos(np.linspace(0, 6, 40)), np.sin(np.linspace(0, 6, 40)), np.zeros(40)], None, None, True)
    through = Curve(np.array([[2.0, 0, 0], [3, 1, 0], [3, -1, 0], [2, 0, 0]]), 0, 0, False, np.arange(4))
    yield "loops", CurveNetwork(np.array([[2.0, 0, 0]]), [loop, through], {"a": np.float64(1.5)}, {"t": {"x": 2}})
    yield "empty", CurveNetwork(np.zeros((0, 3)), [], {}, {})


@pytest.mark.parametrize("name,net", list(_networks()), ids=[n for n, _ in _networks()])
@pytest.mark.parametrize("orjson", [True, False])
def test_streamed_bytes_equal_the_writers_in_memory(tmp_path, monkeypatch, name, net, orjson):
    if not orjson:
        import builtins

        real = builtins.__import__
        monkeypatch.setattr(builtins, "__import__", lambda n, *a, **k: (_ for _ in ()).throw(ImportError(n))
                            if n == "orjson" else real(n, *a, **k))
    monkeypatch.setattr(streamed, "BLOCK_POINTS", 64)  # many blocks
    for ext, whole in ((".json", network_io.network_to_json(net)), (".ply", network_io.network_to_ply(net))):
        out = streamed.write_network_streamed(_Source(net), tmp_path / f"n{ext}")
        want = whole.encode() if isinstance(whole, str) else whole
        assert out.read_bytes() == want, ext
    assert read_network(tmp_path / "n.json") == net


def test_other_formats_refused_and_nothing_written(tmp_path):
    from curvenet.errors import FormatError

    with pytest.raises(FormatError, match="piece by piece"):
        streamed.write_network_streamed(_Source(synth.model("mug")), tmp_path / "n.obj")
    assert list(tmp_path.iterdir()) == []


def test_a_failure_midway_leaves_no_file_and_an_old_one_untouched(tmp_path):
    net = synth.model("mug")
    old = tmp_path / "n.ply"
    old.write_bytes(b"old")

    class Broken(_Source):
        def curves(self):
            yield self.net.curves[0]
            raise OSError("disk gone")

    with pytest.raises(OSError):
        streamed.write_network_streamed(Broken(net), old)
    assert old.read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == ["n.ply"]


def test_streamed_ply_opens_in_trimesh_and_open3d(tmp_path):
    net = synth.model("mug")
    f = streamed.write_network_streamed(_Source(net), tmp_path / "n.ply")
    trimesh = pytest.importorskip("trimesh")
    path = trimesh.load(f)
    assert len(path.entities) > 0 or len(getattr(path, "vertices", [])) > 0
