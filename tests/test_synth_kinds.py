"""The synthetic analogues of real failure kinds (curvenet.synth.kinds) and their benchmark rows."""

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.errors import InputError
from curvenet.synth import cassie
from curvenet.synth.kinds import KIND_MODELS, TANGENT_ANGLES

NAMES = list(KIND_MODELS)


@pytest.fixture(scope="module")
def models():
    return {n: synth.model(n) for n in NAMES}


def _lengths_h(m):
    h = synth.h_of(m)
    return np.array([np.linalg.norm(np.diff(c.points, axis=0), axis=1).sum() / h for c in m.curves])


@pytest.mark.parametrize("name", NAMES)
def test_kind_model_is_a_clean_well_posed_network(models, name):
    m = models[name]
    h = synth.h_of(m)
    assert m.parameters["model"] == name and m.parameters["features"]
    assert 2 not in set(m.valence.tolist())
    for c in m.curves:
        if c.start is not None:
            assert np.array_equal(c.points[0], m.nodes[c.start]) and np.array_equal(c.points[-1], m.nodes[c.end])
    assert _lengths_h(m).min() >= 3.0 - 1e-9  # every curve at least 3h
    assert cassie.min_separation(m, within=2.9 * h) == np.inf  # curves sharing no node >= 3h apart (approx.)
    pts, lab = synth.sample(m, noise=0.2, rng=3)
    assert pts.shape[1] == m.dimension and len(pts) == len(lab) > 100


def test_kind_models_have_their_features(models):
    # junctions 3-5 spacings apart along one curve: ladder, comb
    for name in ("ladder", "comb"):
        m = models[name]
        h = synth.h_of(m)
        J = m.nodes[m.valence >= 3]
        d = np.linalg.norm(J[:, None] - J[None], axis=2) + np.eye(len(J)) * 1e9
        assert 2.9 * h < d.min() < 3.1 * h and (d.min(axis=1) <= 5.1 * h).all()
    # short twigs: free-end curves of 3-6 h
    tw = models["twigs"]
    short = [L for c, L in zip(tw.curves, _lengths_h(tw))
             if min(tw.valence[c.start], tw.valence[c.end]) == 1 and L <= 6.0 + 1e-9]
    assert len(short) >= 10 and min(short) >= 3.0 - 1e-9
    # streets: planar 2D with dead ends, junctions 4-5h apart
    st = models["streets"]
    assert st.dimension == 2 and 1 in set(st.valence.tolist()) and _lengths_h(st).min() < 6
    # building outline: short coplanar edges and a free loop (a window)
    ol = models["outline"]
    assert _lengths_h(ol).min() < 6 and any(c.start is None for c in ol.curves)


def test_tangent_model_has_lines_leaving_arcs_at_the_stated_angles(models):
    m = models["tangent"]
    found = []
    for v in np.flatnonzero(m.valence == 3):
        dirs = []
        for c in m.curves:
            if c.start is None or v not in (c.start, c.end):
                continue
            p = c.points if c.start == v else c.points[::-1]
            u = p[1] - p[0]  # the first step (h / 10): the tangent
            dirs.append(u / np.linalg.norm(u))
        dirs = np.array(dirs)
        cos = np.clip(dirs @ dirs.T, -1, 1)
        ang = np.degrees(np.arccos(cos[np.triu_indices(3, 1)]))
        found.append(ang.min())
    # the smallest angle between two curves at each junction: one per TANGENT_ANGLES, plus the fillet's T
    assert len(found) == len(TANGENT_ANGLES) + 1
    assert np.allclose(sorted(found)[1:], sorted(TANGENT_ANGLES + (0.0,))[1:], atol=1.0)
    assert sorted(found)[0] < 1.0


def test_model_finds_kind_models_and_rejects_unknown():
    assert synth.model("ladder").parameters["model"] == "ladder"
    with pytest.raises(InputError, match="ladder"):
        synth.model("no-such-model")


def test_run_kinds_rows():
    rows = bench.run_kinds(["emst"], ["comb"], ["clean", "noise 0.2h"])
    assert [r["condition"] for r in rows] == ["clean", "noise 0.2h"]
    assert all(r["dataset"] == "kinds" and r["model"] == "comb" and r["error"] is None for r in rows)
    assert rows[0]["true_N_n"] == synth.model("comb").n_nodes
    md = bench.write_markdown(rows, command="test")
    assert "## Analogues of real failure kinds (synthetic)" in md and "worst curve F1" in md
    with pytest.raises(InputError):
        bench.run_kinds(["emst"], ["cube"])


def test_plate_model_has_tangent_t_junctions_in_pairs(models):
    # every node: a line and an arc leaving it in opposite directions (tangent continuation)
    # and a third curve at a right angle to both, the fillet's edge to the node of the
    # other face 6h away
    m = models["plate"]
    h = synth.h_of(m)
    assert (m.valence == 3).all() and len(m.nodes) == 16
    assert sum(c.start is None for c in m.curves) == 4  # the holes, on both faces
    for v in range(len(m.nodes)):
        dirs, far = [], []
        for c in m.curves:
            if c.start is None or v not in (c.start, c.end):
                continue
            p = c.points if c.start == v else c.points[::-1]
            u = p[1] - p[0]
            dirs.append(u / np.linalg.norm(u))
            far.append(np.linalg.norm(p[-1] - p[0]) / h)
        cos = np.array(dirs) @ np.array(dirs).T
        pair = np.unravel_index(np.argmin(cos), cos.shape)
        assert cos[pair] < -0.999  # tangent continuation
        third = ({0, 1, 2} - set(pair)).pop()
        assert abs(cos[third, pair[0]]) < 1e-6 and abs(far[third] - 6.0) < 1e-6


def test_neurites_zigzag_and_stay_clear_of_themselves(models):
    m = models["neurites"]
    h = synth.h_of(m)
    assert set(m.valence.tolist()) == {1, 3}
    sharp = 0
    for c in m.curves:
        p = c.points
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        q = np.array([np.interp(t, s, p[:, k]) for t in np.arange(0, s[-1], h) for k in range(3)]).reshape(-1, 3)
        u = np.diff(q, axis=0)
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        sharp += int((np.einsum("ij,ij->i", u[1:], u[:-1]) < np.cos(np.radians(40))).sum())
        # no part within 3h of a part more than 6h away along the curve
        sq = np.arange(len(q)) * h
        D = np.linalg.norm(q[:, None] - q[None], axis=2)
        assert D[np.abs(sq[:, None] - sq[None]) > 6 * h].min() >= 3 * h - 0.05 * h
    assert sharp >= 3 * m.n_curves  # bursts of sharp turns on every branch, about
