"""Ground-truth models and the sampler."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from curvenet import synth
from curvenet.errors import InputError
from curvenet.metrics import densify

from blas_kernels import has_avx512, output_under

NAMES = synth.model_names()


@pytest.fixture(scope="module")
def models():
    return {n: synth.model(n) for n in NAMES}


def test_enough_models_and_features(models):
    assert len(models) >= 12
    valences = set()
    for m in models.values():
        valences |= set(m.valence.tolist())
    assert {1, 3, 4, 5, 6} <= valences and max(valences) >= 8
    assert any(m.dimension == 2 for m in models.values())
    assert any(c.start is None for m in models.values() for c in m.curves)  # free loops


@pytest.mark.parametrize("name", NAMES)
def test_model_is_a_clean_network(models, name):
    m = models[name]
    h = synth.h_of(m)
    assert h > 0 and m.parameters["model"] == name
    assert 2 not in set(m.valence.tolist())  # corners are not nodes
    for c in m.curves:
        if c.start is not None:
            assert np.array_equal(c.points[0], m.nodes[c.start])
            assert np.array_equal(c.points[-1], m.nodes[c.end])
        else:
            assert c.closed
        step = np.linalg.norm(np.diff(c.points, axis=0), axis=1)
        assert step.max() <= h / 10 + 1e-9  # densely sampled
    b0, b1 = m.betti
    assert b0 >= 1 and b1 >= 0


def test_eye_curves_are_2_5h_apart(models):
    m = models["eye"]
    h = synth.h_of(m)
    between = [c for c in m.curves if c.start is not None and {c.start, c.end} == {0, 1}]
    assert len(between) == 3
    mids = np.array([c.points[len(c.points) // 2] for c in between])
    d = sorted(np.linalg.norm(mids[:, None] - mids[None], axis=2)[np.triu_indices(3, 1)])
    assert d[0] == pytest.approx(2.5 * h, rel=0.01) and d[2] == pytest.approx(5 * h, rel=0.01)


def test_sample_clean_lies_on_curves_with_spacing_h(models):
    m = models["torus"]
    h = synth.h_of(m)
    P, L = synth.sample(m)
    total = sum(c.length for c in m.curves)
    assert abs(len(P) - total / h) < 0.02 * total / h
    nn = cKDTree(P).query(P, k=2)[0][:, 1]
    assert np.allclose(np.median(nn), h, rtol=0.02)
    for cid in (0, 7, 30):
        q = P[L == cid]
        d = cKDTree(densify(m.curves[cid].points, h / 50)).query(q)[0]
        assert d.max() < h / 100
    # every node is sampled exactly
    assert cKDTree(P).query(m.nodes)[0].max() < 1e-12


def test_sample_reproducible_and_shuffled(models):
    m = models["cube"]
    a = synth.sample(m, noise=0.2, density_ratio=3, outliers=0.05, rng=3)
    b = synth.sample(m, noise=0.2, density_ratio=3, outliers=0.05, rng=3)
    c = synth.sample(m, noise=0.2, density_ratio=3, outliers=0.05, rng=4)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])
    assert np.any(np.diff(a[1]) < 0)  # not grouped by curve


def test_sample_noise_level(models):
    m = models["window"]
    h = synth.h_of(m)
    P, L = synth.sample(m, noise=0.3, rng=1)
    dense = np.vstack([densify(c.points, h / 20) for c in m.curves])
    d = cKDTree(dense).query(P)[0]
    # in 3D the offset from a curve has 2 normal components: E[d^2] = 2 sigma^2
    assert np.sqrt(np.mean(d**2)) == pytest.approx(np.sqrt(2) * 0.3 * h, rel=0.15)


def test_sample_density_ratio(models):
    m = models["torus"]
    h = synth.h_of(m)
    P, _ = synth.sample(m, density_ratio=3, rng=2)
    nn = cKDTree(P).query(P, k=2)[0][:, 1] / h
    lo, hi = np.percentile(nn, [1, 99])
    assert lo == pytest.approx(2 / 3, abs=0.05) and hi == pytest.approx(2.0, abs=0.15)
    total = sum(c.length for c in m.curves)
    assert abs(len(P) - total / h) < 0.1 * total / h


def test_sample_outliers(models):
    m = models["fan"]
    P, L = synth.sample(m, outliers=0.1, rng=5)
    n_curve = (L >= 0).sum()
    assert (L == -1).sum() == round(0.1 * n_curve)
    assert P.shape[1] == 2


def test_bad_arguments(models):
    with pytest.raises(InputError):
        synth.model("nope")
    for kw in ({"h": -1.0}, {"noise": -0.1}, {"density_ratio": 0.5}, {"outliers": -1}):
        with pytest.raises(InputError):
            synth.sample(models["cube"], **kw)


# ------------------------------------------------------------------------- CASSIE sketches
def _write_sketch(path):
    import json

    data = {
        "strokes": [{"id": 0, "segments": [0, 1]}, {"id": 1, "segments": [2]}],
        "segments": [
            # a cubic Bézier whose control points are evenly spaced on a line: the line itself
            {"id": 0, "stroke_id": 0, "ctrl_pts": [[[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]], "nodes": [0, 1]},
            {"id": 1, "stroke_id": 0, "ctrl_pts": [[[3, 0, 0], [3, 2, 0]]], "nodes": [1, 2]},
            # drawn from its end node to its start node: must be reoriented
            {"id": 2, "stroke_id": 1, "ctrl_pts": [[[0, 1, 1], [0, 0.5, 0.5], [0, 0.25, 0.1], [0, 0, 0]]],
             "nodes": [3, 0]},
        ],
        "nodes": [
            {"id": 0, "position": [0, 0, 0], "neighbor_edges": [0, 2]},
            {"id": 1, "position": [3, 0, 0], "neighbor_edges": [0, 1]},
            {"id": 2, "position": [3, 2, 0], "neighbor_edges": [1]},
            {"id": 3, "position": [0, 1, 1], "neighbor_edges": [2]},
        ],
    }
    path.write_text(json.dumps(data))


def test_cassie_loader_on_a_handmade_file(tmp_path):
    f = tmp_path / "tiny.json"
    _write_sketch(f)
    raw = synth.cassie.load(f, contract=False, step=0.01)
    assert raw.n_nodes == 4 and raw.n_curves == 3
    c0 = raw.curves[0]
    assert np.allclose(c0.points[:, 1:], 0) and c0.length == pytest.approx(3.0)
    assert np.abs(np.diff(c0.points[:, 0])).max() <= 0.01 + 1e-12
    for c in raw.curves:
        assert np.array_equal(c.points[0], raw.nodes[c.start]) and np.array_equal(c.points[-1], raw.nodes[c.end])
    net = synth.cassie.load(f, step=0.01)  # node 0 and node 1 have valence 2: all one curve
    assert net.n_nodes == 2 and net.n_curves == 1
    assert net.curves[0].length == pytest.approx(3.0 + 2.0 + raw.curves[2].length)
    assert net.parameters["h"] == 0.002


def test_cassie_missing():
    with pytest.raises(InputError):
        synth.cassie.load("no-such-sketch-xyz")


cassie_needed = pytest.mark.skipif(not synth.cassie.available(), reason="CASSIE dataset not found")


@cassie_needed
def test_cassie_free_creations_present():
    names = {p.stem for p in (synth.cassie.root() / "sketch_graph").glob("*.json")}
    assert len(synth.cassie.FREE_CREATIONS) == 16 and set(synth.cassie.FREE_CREATIONS) <= names


@cassie_needed
def test_cassie_study_sketches_are_the_others():
    names = synth.cassie.study_sketches()
    assert len(names) == 48 and names == sorted(names)
    assert not set(names) & set(synth.cassie.FREE_CREATIONS)
    assert all(len(n) == 6 and n[2] == "-" for n in names)


def test_cassie_study_sketches_without_the_dataset(monkeypatch, tmp_path):
    monkeypatch.setenv("CURVENET_CASSIE", str(tmp_path))
    assert synth.cassie.study_sketches() == []


@cassie_needed
def test_cassie_hat():
    net = synth.cassie.load("hat")
    assert net.dimension == 3 and 2 not in set(net.valence.tolist())
    assert net.n_nodes > 50 and net.n_curves > 100
    for c in net.curves:
        if c.start is not None:
            assert np.array_equal(c.points[0], net.nodes[c.start])
    # the hat's curves that share no node stay more than 3h (6 mm) apart
    assert synth.cassie.min_separation(net, within=0.006) == float("inf")
    P, L = synth.sample(net, h=0.002)
    assert abs(len(P) - sum(c.length for c in net.curves) / 0.002) < 0.02 * len(P)


def test_fork_network():
    net = synth.fork(7, 30)
    assert net.n_nodes == 6 and net.n_curves == 5 and net.parameters["h"] == 1.0
    assert sorted(net.valence.tolist()) == [1, 1, 1, 1, 3, 3]
    tip = net.nodes[4]
    assert np.isclose(np.linalg.norm(tip - [0, 7]), 30) and np.isclose(np.degrees(np.arctan2(tip[0], tip[1] - 7)), 30)
    for c in net.curves:  # straight, sampled every 0.1 h, ending at its nodes
        assert np.allclose(c.points[0], net.nodes[c.start]) and np.allclose(c.points[-1], net.nodes[c.end])
        assert np.linalg.norm(np.diff(c.points, axis=0), axis=1).max() <= 0.1 + 1e-12


@pytest.mark.parametrize("args", [(0, 30), (7, 0), (7, 90), (7, 30, -1.0)])
def test_fork_bad_arguments(args):
    with pytest.raises(InputError):
        synth.fork(*args)


@pytest.mark.skipif(not has_avx512(), reason="OpenBLAS picks other kernels only on AVX-512 processors")
def test_samples_do_not_depend_on_openblas_s_processor_kernels():
    # every model and kind model, sampled under noise and density ratio 3: the same points to
    # the bit under OpenBLAS's Haswell and SkylakeX kernels (the generators' @ and vector norms
    # went to BLAS: the tree model and most density-ratio samplings differed in their last bits)
    code = ("import hashlib, numpy as np\n"
            "from curvenet import synth\n"
            "d = hashlib.sha256()\n"
            "for m in [*synth.MODELS, *synth.KIND_MODELS]:\n"
            "    t = synth.model(m)\n"
            "    d.update(np.ascontiguousarray(t.nodes).tobytes())\n"
            "    d.update(synth.sample(t, noise=0.3, density_ratio=3, rng=5)[0].tobytes())\n"
            "print(d.hexdigest())\n")
    assert output_under("Haswell", code) == output_under("SkylakeX", code)
