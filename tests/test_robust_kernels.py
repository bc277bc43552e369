"""The compiled kernels of the robust method agree with their plain-Python runs and with numpy."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet.methods.robust import chains as RC
from curvenet.methods.robust import frames as RF
from curvenet.methods.robust import graph as RG
from curvenet.methods.robust import kernels as K
from curvenet.methods.robust.kernels import heap, linalg, nodes, registry as KR, shell
from curvenet.methods.robust.thresholds import ENDS, LINALG, NODES, NUMERIC, SHELL, SPACING, STRIP, TANGENTS
from curvenet import synth
from curvenet.neighbors import build_tree, knn

from blas_kernels import has_avx512, network_digest_code, output_under


def _plain(name):
    """The plain-Python version of the kernel ``name``, its threshold groups appended."""
    k = KR.KERNELS[name]
    return lambda *args: k.plain(*args, *k.groups)


def _pca_dir(Q, w=None):
    """Principal direction and eigenvalues of stacked point sets Q (n, m, d), weights w (n, m)."""
    if w is None:
        w = np.ones(Q.shape[:2])
    sw = np.maximum(w.sum(axis=1, keepdims=True), 1e-300)
    mu = (Q * w[..., None]).sum(axis=1, keepdims=True) / sw[..., None]
    Z = (Q - mu) * np.sqrt(w)[..., None]
    ev, v = np.linalg.eigh(np.einsum("nki,nkj->nij", Z, Z))
    return v[:, :, -1], ev


@pytest.fixture(scope="module")
def cloud():
    P, _ = synth.sample(synth.model("cube"), noise=0.2, outliers=0.02, rng=4)
    P = P[np.lexsort(P.T[::-1])]
    dist, idx = knn(P, 16)
    h = RF.local_spacing(dist, idx)
    return P, dist, idx, h


@pytest.mark.parametrize("d", [2, 3])
def test_eig_sym_matches_lapack(d):
    rng = np.random.default_rng(d)
    for _ in range(200):
        A = rng.normal(size=(d, 5))
        C = A @ A.T
        if rng.uniform() < 0.2:  # rank-deficient
            C = np.outer(A[:, 0], A[:, 0])
        V = np.zeros((d, d))
        ev = np.zeros(d)
        linalg._eig_sym(C.copy(), V, ev, LINALG)
        ref, vref = np.linalg.eigh(C)
        scale = max(abs(ref).max(), 1e-300)
        assert np.allclose(ev, ref, atol=1e-12 * scale)
        assert np.all(np.diff(ev) >= 0)
        assert np.allclose(V.T @ V, np.eye(d), atol=1e-12)
        if ref[-1] - ref[-2] > 1e-6 * scale:  # a well-defined principal direction
            assert abs(abs(V[:, -1] @ vref[:, -1]) - 1) < 1e-10


@pytest.mark.parametrize("d", [2, 3, 4])
def test_eig_top_matches_lapack(d):
    # closed form for d = 2, 3 (Jacobi for the rest and near-equal top eigenvalues): all the
    # eigenvalues and the top eigenvector, the same bits compiled and in plain Python
    rng = np.random.default_rng(10 + d)
    jit = KR.compiled_version(linalg._eig_top)
    for i in range(400):
        A = rng.normal(size=(d, 5)) * rng.uniform(1e-6, 1e6)
        C = A @ A.T
        kind = i % 5
        if kind == 1:  # rank one (a line)
            C = np.outer(A[:, 0], A[:, 0])
        elif kind == 2:  # nearly a line, with noise
            C = np.outer(A[:, 0], A[:, 0]) + 1e-4 * (A[:, 1:3] @ A[:, 1:3].T)
        elif kind == 3:  # two equal top eigenvalues (a plane): the Jacobi fallback
            Qm = np.linalg.qr(rng.normal(size=(d, d)))[0]
            C = Qm @ np.diag(np.r_[np.zeros(d - 2), 1.0, 1.0]) @ Qm.T
        elif kind == 4:  # an offset from isotropic
            C = C + 1e3 * abs(C).max() * np.eye(d)
        V = np.zeros((d, d))
        ev = np.zeros(d)
        linalg._eig_top(C.copy(), V, ev, LINALG)
        ref, vref = np.linalg.eigh(C)
        scale = max(abs(ref).max(), 1e-300)
        assert np.allclose(ev, ref, atol=1e-9 * scale), (i, ev, ref)
        assert abs(np.linalg.norm(V[:, -1]) - 1) < 1e-12
        if ref[-1] - ref[-2] > 1e-6 * scale:  # a well-defined principal direction
            assert abs(abs(V[:, -1] @ vref[:, -1]) - 1) < 1e-9, i
        if jit is not None:
            V2 = np.zeros((d, d))
            ev2 = np.zeros(d)
            jit(C.copy(), V2, ev2, LINALG)
            assert np.array_equal(V2[:, -1], V[:, -1]) and np.array_equal(ev2, ev)


def test_end_count_matches_numpy_prefix_sums():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(100, 3))
    for _ in range(300):
        ids = rng.integers(0, 100, size=int(rng.integers(2, 40)))
        X = P[ids[::-1]]
        seg = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(X, axis=0), axis=1))]
        lim = float(rng.choice([rng.uniform(0, seg[-1] * 1.2), seg[rng.integers(len(seg))]]))
        ref = int(np.searchsorted(seg, lim, side="right"))
        assert K.end_count(P, ids, lim) == ref
        assert nodes._end_count(P, ids, lim) == ref


@pytest.fixture(scope="module")
def eye_cloud():
    # three curves 2.5h apart, sparse places about 1.5h: some tangents need the neighbour test
    P, _ = synth.sample(synth.model("eye"), density_ratio=3.0, rng=3)
    P = P[np.lexsort(P.T[::-1])]
    dist, idx = knn(P, 16)
    return P, dist, idx, RF.local_spacing(dist, idx)


@pytest.mark.parametrize("which", ["cloud", "eye_cloud"])
def test_tangents_match_the_numpy_pca(which, request):
    P, dist, idx, h = request.getfixturevalue(which)
    win = _check_tangents(P, idx, h, K.CAND_MARGIN, None)
    assert win.any() or which == "cloud"  # the noisy cube may have none
    # a smaller margin (robust.CAND_MARGIN_CLEAN), on every other point only (the others are
    # left at zero): more directions change, never fewer
    sub = np.arange(1, len(P), 2)
    win2 = _check_tangents(P, idx, h, TANGENTS.cand_margin_clean, sub)
    assert np.all(win2[sub] >= win[sub])


def _check_tangents(P, idx, h, margin, subset):
    t, lin, chord, gain = K.tangents(P, idx, h, 12, order=subset, margin=None if subset is None else margin)
    if subset is not None:
        rest = np.setdiff1d(np.arange(len(P)), subset)
        assert not t[rest].any() and not lin[rest].any() and np.all(gain[rest] == -np.inf)
    else:
        subset = np.arange(len(P))
    # numpy reference: the stacked-array PCA
    n = len(P)
    self_ = np.arange(n)[:, None]
    t4, ev4 = _pca_dir(P[np.concatenate([self_, idx[:, :4]], axis=1)])
    lin4 = 1.0 - ev4[:, -2] / np.maximum(ev4[:, -1], 1e-300)
    Qm = P[np.concatenate([self_, idx[:, :12]], axis=1)]
    rel = Qm - P[:, None, :]

    def strip_score(u):  # (n, d) unit directions -> (n,)
        al = np.einsum("nkd,nd->nk", rel[:, 1:], u)
        q = np.maximum(np.einsum("nkd,nkd->nk", rel[:, 1:], rel[:, 1:]) - al**2, 0.0)
        near = np.abs(al) <= STRIP.a * h[:, None]
        return (np.exp(-q / (STRIP.w * h[:, None]) ** 2) * near).sum(axis=1)

    # where the 4-neighbour PCA is not clearly linear, the direction towards one of the 4 nearest
    # neighbours wins by a margin (first of the best)
    cand = rel[:, 1:5] / np.linalg.norm(rel[:, 1:5], axis=2, keepdims=True)
    sc = np.stack([strip_score(cand[:, j]) for j in range(4)], axis=1)
    j = np.argmax(sc, axis=1)
    tried = lin4 < STRIP.cand_lin
    # the gain: best neighbour direction's score minus the 4-neighbour direction's, where tried
    gain_ref = np.where(tried, sc[np.arange(n), j] - strip_score(t4), -np.inf)
    assert np.allclose(gain[subset], gain_ref[subset], atol=1e-9, rtol=0)
    win = (sc[np.arange(n), j] > strip_score(t4) + margin) & tried
    tr = np.where(win[:, None], cand[np.arange(n), j], t4)
    for _ in range(2):
        along = np.einsum("nkd,nd->nk", rel, tr)
        w = (np.einsum("nkd,nkd->nk", rel, rel) - along**2 <= h[:, None] ** 2).astype(float)
        tr, ev = _pca_dir(Qm, w)
    lin_ref = 1.0 - ev[:, -2] / np.maximum(ev[:, -1], 1e-300)
    assert np.allclose(np.abs((t[subset] * tr[subset]).sum(axis=1)), 1.0, atol=1e-9)
    assert np.allclose(lin[subset], lin_ref[subset], atol=1e-9)
    assert np.isfinite(chord[subset]).mean() > 0.8 and np.nanmin(chord[subset]) >= 0
    return win


def test_tangent_is_not_thrown_across_close_parallel_curves():
    # three parallel lines 2.5 apart, each sampled every 1.5 (local spacing about 1.5): the four
    # nearest neighbours of a middle point are two along its line and two across, whose PCA
    # points across; the tangent must still follow the lines
    x = np.arange(0.0, 60.0, 1.5)
    P = np.concatenate([np.column_stack([x + 0.5 * (j % 2), np.full_like(x, 2.5 * j), 0 * x]) for j in (-1, 0, 1)])
    P = P[np.lexsort(P.T[::-1])]
    dist, idx = knn(P, 16)
    h = RF.local_spacing(dist, idx)
    t, lin, _, _ = K.tangents(P, idx, h, 12)
    inner = (P[:, 0] > 8) & (P[:, 0] < 50)
    assert np.all(np.abs(t[inner, 0]) > 0.99)
    assert np.all(lin[inner] > 0.9)


_PY_RUN = """
import sys, numpy as np
from curvenet.methods.robust import kernels as K
from curvenet.methods.robust import frames as RF
from curvenet import synth
from curvenet.neighbors import knn
assert not K.HAVE_NUMBA
P, _ = synth.sample(synth.model("cube"), noise=0.2, outliers=0.02, rng=4)
P = P[np.lexsort(P.T[::-1])]
dist, idx = knn(P, 16)
h = RF.local_spacing(dist, idx)
t, lin, chord, gain = K.tangents(P, idx, h, 12)
sub = K.tangents(P, idx, h, 12, order=np.arange(0, len(P), 2), margin=1.0)
e = K.linked_edges(P, h, idx, t, lin, 2.5, 1.0, 0.01, 0.005, 2.0, 0.3, True)
s = K.short_links(P, h, idx, 2.5)
np.savez(sys.argv[1], t, lin, chord, gain, *sub, *e, *s)
"""


def test_compiled_and_python_runs_agree(cloud, tmp_path):
    """The kernels give the same arrays, bit for bit, with numba and as plain Python."""
    import os
    import subprocess
    import sys

    if not K.HAVE_NUMBA:
        pytest.skip("numba not installed: only the Python run exists")
    P, dist, idx, h = cloud
    t, lin, chord, gain = K.tangents(P, idx, h, 12)
    sub = K.tangents(P, idx, h, 12, order=np.arange(0, len(P), 2), margin=1.0)
    e = K.linked_edges(P, h, idx, t, lin, 2.5, 1.0, 0.01, 0.005, 2.0, 0.3, True)
    s = K.short_links(P, h, idx, 2.5)
    out = tmp_path / "py.npz"
    env = dict(os.environ, CURVENET_NO_NUMBA="1")
    r = subprocess.run([sys.executable, "-c", _PY_RUN, str(out)], env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    ref = np.load(out)
    for i, (x, key) in enumerate(zip((t, lin, chord, gain, *sub, *e, *s), ref.files)):
        if i in (3, 7):  # the gains: sums of exp, whose last bits may differ (decisions do not)
            assert np.allclose(x, ref[key], rtol=0, atol=1e-12), key
        else:
            assert np.array_equal(x, ref[key], equal_nan=True), key


def test_parallel_kernels_agree_on_all_threads_and_on_one(cloud, monkeypatch):
    """The parallel kernels give the same arrays whether their loops run on all threads or on
    one (:data:`kernels.registry.PAR_MIN`), and as the plain-Python loops."""
    P, dist, idx, h = cloud
    cand = np.arange(0, len(P), 3, dtype=np.int64)

    def run():
        t, lin, chord, _ = K.tangents(P, idx, h, 12)
        e = K.linked_edges(P, h, idx, t, lin, 2.5, 1.0, 0.01, 0.005, 2.0, 0.3, True)
        s = K.short_links(P, h, idx, 2.5)
        agree = K.vote_agreement(t, idx, 8)
        u = K.vote_eig(t, idx, 8, cand)
        indptr, indices = K.csr_union(len(P), e[0], e[1])
        g = K.shell_groups(P, h, indptr, indices, 1.5, 3.3)
        return (t, lin, chord, *e, *s, agree, *u, g)

    monkeypatch.setattr(KR, "PAR_MIN", {name: 1 << 62 for name in KR.PAR_MIN})
    one = run()
    monkeypatch.setattr(KR, "PAR_MIN", {name: 0 for name in KR.PAR_MIN})
    par = run()
    for a, b in zip(one, par):
        assert np.array_equal(a, b, equal_nan=True)
    t, lin = par[0], par[1]
    for got, ref in ((par[3:6], _plain("linked_edges")(P, h, idx, t, lin, 2.5, 1.0, 0.01, 0.005, 2.0, 0.3, True)),
                     (par[6:8], _plain("short_links")(P, h, idx, 2.5)),
                     ((par[8],), (_plain("vote_agreement")(t, idx, 8),))):
        for a, b in zip(got, ref):
            assert np.array_equal(a, b)


@pytest.mark.parametrize("lens", [False, True])
def test_linked_edges_match_the_array_formulas(cloud, lens):
    P, dist, idx, h = cloud
    t, lin, _, _ = K.tangents(P, idx, h, 12)
    link, width, wmin, gap, extra_len, lmin = 2.5, 1.0, 0.004, 0.002, 2.0, 0.3
    got = K.linked_edges(P, h, idx, t, lin, link, width, wmin, gap, extra_len, lmin, lens)
    # the same tests on flat arrays
    n, k = idx.shape
    src = np.repeat(np.arange(n), k)
    dst = idx.ravel()
    dd = dist.ravel()
    reach = link * (0.5 * (h[src] + h[dst])) + gap
    keep = (dd <= extra_len * reach) & (src != dst)
    src, dst, dd, reach = src[keep], dst[keep], dd[keep], reach[keep]
    vec = P[dst] - P[src]
    al = np.einsum("ij,ij->i", vec, t[src])
    ps = np.sqrt(np.maximum(dd**2 - al**2, 0.0))
    pd = np.sqrt(np.maximum(dd**2 - np.einsum("ij,ij->i", vec, t[dst]) ** 2, 0.0))
    w = np.maximum(width * 0.5 * (h[src] + h[dst]), wmin)
    ok = (ps <= w) | (pd <= w) | (lin[src] < lmin) | (lin[dst] < lmin) | (dd == 0)
    short = dd <= link * 0.5 * (h[src] + h[dst])
    both = (ps <= w) & (pd <= w) & (lin[src] >= lmin) & (lin[dst] >= lmin)
    sel = (ok & short) | (both & (dd <= reach))
    strip = both & (dd > 0)
    col = np.tile(np.arange(k), n)[keep]  # each edge's place in its row
    for sgn in (1.0, -1.0):
        ci = np.flatnonzero(strip & (sgn * al > 0))
        if len(ci):
            first = ci[np.r_[True, src[ci][1:] != src[ci][:-1]]]
            if lens:  # a strip edge only: out when a nearer neighbour lies in its lens, off its line
                alone = first[~sel[first]]
                first = first[sel[first]]
                for e in alone.tolist():
                    W = P[idx[src[e], :col[e]]]
                    W = W[(idx[src[e], :col[e]] != src[e]) & (idx[src[e], :col[e]] != dst[e])]
                    u = (P[dst[e]] - P[src[e]]) / dd[e]
                    rel = W - P[src[e]]
                    off = np.sqrt(np.maximum((rel**2).sum(1) - (rel @ u) ** 2, 0.0))
                    inside = (np.linalg.norm(W - P[dst[e]], axis=1) < dd[e]) & (off > w[e] * (1 + 1e-9))
                    if not inside.any():
                        first = np.r_[first, e]
            sel[first] = True
    assert np.array_equal(got[0], src[sel])
    assert np.array_equal(got[1], dst[sel])
    assert np.array_equal(got[2], dd[sel])
    a, b = K.short_links(P, h, idx, link)
    ks = np.repeat(np.arange(n), k)
    m = dist.ravel() <= link * 0.5 * (h[ks] + h[idx.ravel()])
    assert np.array_equal(a, ks[m]) and np.array_equal(b, idx.ravel()[m])


def _trim_behind_reference(P, h, ids, x, span2):
    """The numpy formula of the trimming (what robust did before the compiled kernel)."""
    if len(ids) < 4:
        return ids
    X = P[ids]
    seg = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(X, axis=0), axis=1))]
    k = int(min(np.searchsorted(seg, span2 * float(h[ids[0]])), len(ids) - 1))
    u = X[k] - x
    nu = np.linalg.norm(u)
    if nu == 0:
        return ids
    behind = (X[:k] - x) @ (u / nu) <= 0
    j = 0
    while j < len(behind) and behind[j]:
        j += 1
    return ids[min(j, len(ids) - 2):]


@pytest.mark.parametrize("py", [False, True])
def test_trim_ends_match_the_numpy_formula(py):
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 60)
    P = np.c_[t, 0.05 * np.sin(6 * t), 0.02 * rng.normal(size=60)]
    h = np.full(60, 1 / 59)
    chains, x0, x1, d0, d1 = [], [], [], [], []
    for _ in range(200):
        a, b = sorted(rng.choice(60, 2, replace=False))
        ids = np.arange(a, b + 1)
        chains.append(ids)
        # nodes near either end, often ahead of the first points (so some are behind them)
        x0.append(P[min(a + int(rng.integers(0, 6)), b)] + rng.normal(scale=0.01, size=3))
        x1.append(P[max(b - int(rng.integers(0, 6)), a)] + rng.normal(scale=0.01, size=3))
        d0.append(rng.uniform() < 0.8)
        d1.append(rng.uniform() < 0.8)
    flat = np.concatenate(chains).astype(np.int64)
    off = np.r_[0, np.cumsum([len(c) for c in chains])].astype(np.int64)
    f = _plain("trim_ends") if py else K.trim_ends
    lo, hi = f(P, h, flat, off, np.array(d0), np.array(d1), np.array(x0), np.array(x1), 12.0)
    dropped = 0
    for i, ids in enumerate(chains):
        ref = ids
        if d0[i]:
            ref = _trim_behind_reference(P, h, ref, x0[i], 12.0)
        if d1[i]:
            ref = _trim_behind_reference(P, h, ref[::-1], x1[i], 12.0)[::-1]
        assert np.array_equal(flat[lo[i]:hi[i]], ref), i
        dropped += len(ids) - len(ref)
    assert dropped > 50  # the test does trim


def _junction_reference(P, branches, jspan, through_end=False):
    """Least-squares intersection of the lines fitted (SVD) on each branch's end, numpy; each
    line through its end portion's mean, or with ``through_end`` through the branch's last point."""
    d = P.shape[1]
    A = 1e-2 * np.eye(d)
    anchor = np.mean([P[b[-1]] for b in branches], axis=0)
    rhs = 1e-2 * anchor
    for b in branches:
        X = P[b[::-1]]
        seg = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(X, axis=0), axis=1))]
        m = max(int(np.searchsorted(seg, jspan * 1.0, side="right")), min(3, len(b)))
        E = X[:m]
        c = E.mean(axis=0)
        u = np.linalg.svd(E - c)[2][0]
        if through_end:
            c = X[0]
        M = np.eye(d) - np.outer(u, u)
        A += M
        rhs += M @ c
    return np.linalg.solve(A, rhs)


@pytest.mark.parametrize("py", [False, True])
@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("noise", [0.0, 0.1])
def test_junction_nodes_match_the_numpy_least_squares(py, d, noise):
    # noise 0 (at most NODES.tangent_noise spacings): read as noise-free, each line through its
    # branch's last point; 0.1: through its end portion's mean, the portion 6 noise longer
    rng = np.random.default_rng(d)
    pts, branches, truth = [], [], []
    for j in range(30):  # junctions of 3 to 6 noisy straight branches, no region points
        x = rng.normal(size=d) * 10
        truth.append(x)
        for _ in range(int(rng.integers(3, 7))):
            u = rng.normal(size=d)
            u /= np.linalg.norm(u)
            s = np.arange(12, 1, -1) * 1.0 + 0.5  # running towards the junction, stop short
            B = x + s[:, None] * u + rng.normal(scale=0.05, size=(len(s), d))
            branches.append((j, np.arange(len(pts), len(pts) + len(s))))
            pts.extend(B)
    P = np.asarray(pts)
    h = np.ones(len(P))
    nb = np.bincount([j for j, _ in branches], minlength=30)
    bl = [b for _, b in branches]
    bflat = np.concatenate(bl).astype(np.int64)
    boff = np.r_[0, np.cumsum([len(b) for b in bl])].astype(np.int64)
    jb = np.r_[0, np.cumsum(nb)].astype(np.int64)
    roff = np.zeros(31, dtype=np.int64)
    consts = K.JunctionParams(4.0, 6.0, 1.25, 4.5, 1e9, 0.8 * 5.5, 0.9, 1.5, False)
    f = _plain("junction_nodes") if py else K.junction_nodes
    X, maybe = f(P, h, np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64), bflat, boff, jb,
                 np.zeros(0, dtype=np.int64), roff, np.ones(30), 1.0, noise, consts)
    assert not maybe.any()
    err, err_anchor = [], []
    free = noise <= NODES.tangent_noise
    for j in range(30):
        ref = _junction_reference(P, [b for jj, b in branches if jj == j], 4.0 + 6.0 * noise, through_end=free)
        assert np.allclose(X[j], ref, atol=1e-9), j
        anchor = np.mean([P[b[-1]] for jj, b in branches if jj == j], axis=0)
        err.append(np.linalg.norm(X[j] - truth[j]))
        err_anchor.append(np.linalg.norm(anchor - truth[j]))
    # and it is the junction: far nearer to it than the mean of the branch ends (>= 1.5 away)
    assert max(err) < 0.35 and np.mean(err) < 0.3 * np.mean(err_anchor)


@pytest.mark.parametrize("py", [False, True])
def test_a_branch_turning_before_the_junction_is_left_out(py, monkeypatch):
    # a T in the plane: a post (x = 0) and a stub (y = 0, x < 0) meet at the origin; the third
    # branch comes down x = 3.5 and turns along y = 0 to the origin, the turn's points in the
    # junction's region (with the region points around the origin). Its line misses the node
    # by 3.5 h and drew the least-squares node 1.1 h along the rail; the node of the two others
    # is the junction. The other reading (the post left out: the stub's and the turned
    # branch's lines meet at the turn) lies farther from the region's points.
    s = np.arange(12.0, 0.0, -1.0)
    post = np.c_[np.zeros_like(s), s]
    stub = np.c_[-np.arange(5.0, 0.0, -1.0), np.zeros(5)]
    turned = np.c_[np.full_like(s, 3.5), s + 0.5]
    region = np.array([[0.0, 0.2], [-0.3, 0.0], [0.5, -0.1], [1.5, 0.1], [2.5, 0.0]])
    P = np.vstack([post, stub, turned, region])
    ids = np.arange(len(P), dtype=np.int64)
    bl = [ids[:12], ids[12:17], ids[17:29]]
    bflat = np.concatenate(bl)
    boff = np.r_[0, np.cumsum([len(b) for b in bl])].astype(np.int64)
    consts = K.JunctionParams(4.0, 6.0, 1.25, 4.5, 1e9, 0.8 * 5.5, 0.9, 1.5, False)

    def node():
        f = _plain("junction_nodes") if py else K.junction_nodes
        X, _ = f(P, np.ones(len(P)), np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64), bflat, boff,
                 np.array([0, 3], dtype=np.int64), ids[29:], np.array([0, 5], dtype=np.int64), np.ones(1), 1.0, 0.1,
                 consts)
        return X[0]

    assert np.linalg.norm(node()) < 0.2
    if py:  # (the rule off: the three lines' node)
        monkeypatch.setattr(nodes, "_without_stray_line", lambda *a: False)
        assert np.linalg.norm(node()) > 1.0


def _tangent_junction(d, ang, gap=6.0, over=3.0):
    """A node at 0 where a line leaves a circle of radius 30 at ``ang`` degrees from its tangent
    (spacing 1, no noise), as sampled near-tangent junctions come: the arc before the node runs
    ``over`` past it (the branches are told apart only where they separate), the arc after it
    and the line stop ``gap`` short of it. Returns the junction_nodes arguments."""
    R = 30.0
    arc = lambda s: np.column_stack([R * np.sin(s / R), R * np.cos(s / R) - R])  # node at s = 0
    a = np.radians(ang)
    line = lambda r: np.column_stack([r * np.cos(a), r * np.sin(a)])  # leaves outwards (+y: away)
    parts = [arc(np.arange(-40.0, over + 1e-9, 1.0)), arc(np.arange(40.0, gap - 1e-9, -1.0)),
             line(np.arange(30.0, gap - 1e-9, -1.0))]
    P = np.concatenate(parts)
    if d == 3:  # tilted out of the xy plane
        rot = np.linalg.qr(np.array([[1.0, 0.2, 0.1], [0.3, 1.0, -0.2], [0.1, 0.4, 1.0]]))[0]
        P = np.column_stack([P, np.zeros(len(P))]) @ rot.T
    lens = [len(p) for p in parts]
    bflat = np.arange(len(P), dtype=np.int64)
    boff = np.r_[0, np.cumsum(lens)].astype(np.int64)
    consts = K.JunctionParams(4.0, 6.0, 1.25, 4.5, 16.5, 0.8 * 5.5, 0.9, 1.5, False)
    return (P, np.ones(len(P)), np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64), bflat, boff,
            np.array([0, 3], dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(2, dtype=np.int64),
            np.ones(1), 1.0, 0.0, consts)


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("ang", [0.0, 3.0, 10.0])
def test_near_tangent_junction_is_where_the_circles_meet(d, ang):
    # the lines fitted on the three ends are near-parallel (and those of the arcs are chords):
    # their least squares leaves the node to the anchor's pull along the tangent (1 to 3 away);
    # the circles fitted on the ends meet at the node. Compiled and plain runs: the same bits.
    args = _tangent_junction(d, ang)
    X, _ = _plain("junction_nodes")(*args)
    assert np.linalg.norm(X[0]) < 0.1, X[0]
    off = NODES._replace(tangent_fit=0.0)  # no circle kept: the lines' node alone
    k = KR.KERNELS["junction_nodes"]
    X0, _ = k.plain(*args, ENDS, off, LINALG)
    assert np.linalg.norm(X0[0]) > 0.5, X0[0]
    if k.compiled is not None:
        Xc, _ = k.compiled(*args, *k.groups)
        assert np.array_equal(Xc, X)


def test_near_tangent_placement_needs_the_circles_to_meet():
    # the line leaves 3 off the circle's tangent point (a line crossing near, not touching):
    # the circles do not meet within NODES.tangent_meet, the lines' node stays
    args = list(_tangent_junction(2, 0.0))
    P = args[0].copy()
    P[args[5][2]:] += [0.0, 3.0]
    args[0] = P
    k = KR.KERNELS["junction_nodes"]
    X, _ = k.plain(*args, *k.groups)
    X0, _ = k.plain(*args, ENDS, NODES._replace(tangent_fit=0.0), LINALG)
    assert np.array_equal(X, X0)


@pytest.mark.parametrize("d", [2, 3])
def test_vote_eig_matches_lapack(d):
    rng = np.random.default_rng(10 + d)
    n, m = 400, 8
    t = rng.normal(size=(n, d))
    t[: n // 2, 0] += 3.0  # half the points roughly agree
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    idx = np.stack([rng.choice(n, m, replace=False) for _ in range(n)]).astype(np.int64)
    cand = np.sort(rng.choice(n, 150, replace=False)).astype(np.int64)
    U, coh = K.vote_eig(t, idx, m, cand)
    U_py, coh_py = _plain("vote_eig")(t, idx, m, cand)
    assert np.array_equal(U, U_py) and np.array_equal(coh, coh_py)  # compiled or not, same bits
    T = t[np.concatenate([cand[:, None], idx[cand]], axis=1)]
    ev, V = np.linalg.eigh(np.einsum("nki,nkj->nij", T, T))
    ref_coh = 1.0 - ev[:, -2] / np.maximum(ev[:, -1], 1e-300)
    assert np.allclose(coh, ref_coh, atol=1e-12)
    ok = ev[:, -1] - ev[:, -2] > 1e-6
    assert ok.sum() > 100
    assert np.allclose(np.abs(np.einsum("nd,nd->n", U[ok], V[ok, :, -1])), 1.0, atol=1e-9)


def test_shell_groups_of_a_subset_equal_those_of_all(cloud):
    P, dist, idx, h = cloud
    t, lin, _, _ = K.tangents(P, idx, h, 12)
    src, dst, _ = K.linked_edges(P, h, idx, t, lin, 2.5, 1.0, 0.01, 0.005, 2.0, 0.3, True)
    indptr, indices = K.csr_union(len(P), src, dst)
    full = K.shell_groups(P, h, indptr, indices, 1.5, 3.3)
    sub = np.random.default_rng(1).choice(len(P), size=len(P) // 7, replace=False)
    part = K.shell_groups(P, h, indptr, indices, 1.5, 3.3, subset=sub)
    assert np.array_equal(part[sub], full[sub])
    rest = np.setdiff1d(np.arange(len(P)), sub)
    assert np.all(part[rest] == 0) and np.any(full[sub] != 2)


def _shell_groups_reference(P, h, indptr, indices, r_in, r_out, pts, goes_on=False):
    """Shell group counts of the points ``pts`` by scipy's dijkstra (numpy, one point at a time)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components, dijkstra

    n = len(P)
    rows = np.repeat(np.arange(n), np.diff(indptr))
    D = P[indices] - P[rows]
    w = np.sqrt((D * D).sum(axis=1))
    g = csr_matrix((np.maximum(w, 1e-300), indices, indptr), shape=(n, n))
    out = []
    for p in pts:
        # (the radii with the rounding tolerance, ties in, as the kernel compares them)
        ro, ri = r_out * h[p] * (1 + NUMERIC.rel), r_in * h[p] * (1 - NUMERIC.rel)
        rmid = 0.5 * (r_in + r_out) * h[p] * (1 - NUMERIC.rel)
        gd = dijkstra(g, indices=p, limit=ro)
        reach = np.flatnonzero(np.isfinite(gd))
        sh = reach[(gd[reach] >= ri) & (((P[reach] - P[p]) ** 2).sum(axis=1) >= ri * ri)]
        if len(sh) == 0:
            out.append(0)
            continue
        _, lab = connected_components(g[sh][:, sh], directed=False)
        top = np.zeros(lab.max() + 1)
        np.maximum.at(top, lab, gd[sh])
        # (goes_on: a group also counts when a point of it is linked to one beyond the shell)
        out_link = np.array([not np.isfinite(gd[indices[indptr[a]:indptr[a + 1]]]).all() for a in sh])
        beyond = np.zeros(lab.max() + 1, dtype=bool)
        np.logical_or.at(beyond, lab, out_link)
        out.append(int(((top >= rmid) | (goes_on & beyond)).sum()))
    return np.array(out)


@pytest.mark.parametrize("py", [False, True])
def test_shell_groups_match_scipy_dijkstra(py, monkeypatch):
    """The shell counts equal those from scipy's dijkstra on a cross with a dense clump at one
    end (its frontier outgrows the short list: the heap takes over), compiled and as plain
    Python; plain Python also with the list only and the heap only."""
    rng = np.random.default_rng(3)
    s = np.linspace(-20, 20, 81)
    z = np.zeros_like(s)
    clump = rng.normal(scale=1.0, size=(400, 3)) + [20.0, 0.0, 0.0]
    P = np.vstack([np.c_[s, z, z], np.c_[z, s, z], clump]) + rng.normal(scale=0.05, size=(562, 3))
    dist, idx = knn(P, 16)
    h = RF.local_spacing(dist, idx)
    keep = dist < 2.5 * h[:, None]
    src = np.repeat(np.arange(len(P)), 16)[keep.ravel()]
    indptr, indices = K.csr_union(len(P), src, idx[keep])
    pts = np.r_[np.arange(0, 162, 3), np.arange(162, 562, 9)]
    ref = _shell_groups_reference(P, h, indptr, indices, 2.5, 5.5, pts)
    assert set(ref.tolist()) >= {1, 2, 4}  # ends, curve, the crossing
    if not py:
        got = K.shell_groups(P, h, indptr, indices, 2.5, 5.5, subset=pts)
        assert np.array_equal(got[pts], ref)
        got = K.shell_groups(P, h, indptr, indices, 2.5, 5.5, subset=pts, goes_on=True)
        assert np.array_equal(got[pts], _shell_groups_reference(P, h, indptr, indices, 2.5, 5.5, pts, True))
        return
    pushes = []
    for fm in (SHELL.front_max, 0, 10**9):
        # the plain kernel calls the heap of its module's globals (the compiled one its own)
        monkeypatch.setattr(shell, "_heap_push", lambda *a, _fm=fm: pushes.append(_fm) or heap._heap_push(*a))
        got = shell._shell_groups(P, h, indptr, indices, 2.5, 5.5, False, pts.astype(np.int64), 1,
                                  SHELL._replace(front_max=fm), NUMERIC)
        assert np.array_equal(got[pts], ref), fm
    # the clump fills the short list (the heap is used), the curve points never do
    assert 0 < pushes.count(32) < pushes.count(0) and 10**9 not in pushes


@pytest.mark.parametrize("py", [False, True])
def test_shell_groups_count_a_branch_reaching_the_middle_exactly(py):
    """Three branches leave a corner at right angles, sampled every spacing exactly; on the
    finest shell of the re-tests (1.25 to 2.75 spacings, middle at 2) each branch's shell point
    lies 2 spacings out: exactly at the middle, where only the last bit of the sum of two steps
    against the spacing decided (the spacing one ulp over 0.02: none of the three counted)."""
    step = 0.02
    k = np.arange(1, 9)[:, None] * step
    z = np.zeros_like(k)
    P = np.vstack([[[0.0, 0.0, 0.0]], np.c_[k, z, z], np.c_[z, k, z], np.c_[z, z, k]])
    n = len(P)
    src, dst = [], []
    for a in range(n):  # links to the next samples along each branch (and the corner)
        for b in range(n):
            if a != b and np.linalg.norm(P[a] - P[b]) < 1.01 * step:
                src.append(a)
                dst.append(b)
    indptr, indices = K.csr_union(n, np.array(src), np.array(dst))
    h = np.full(n, np.nextafter(step, 1.0))
    pts = np.array([0], dtype=np.int64)
    if py:
        got = shell._shell_groups(P, h, indptr, indices, 1.25, 2.75, False, pts, 1, SHELL, NUMERIC)
    else:
        got = K.shell_groups(P, h, indptr, indices, 1.25, 2.75, subset=pts)
    assert got[0] == 3
    assert _shell_groups_reference(P, h, indptr, indices, 1.25, 2.75, pts)[0] == 3


@pytest.mark.parametrize("py", [False, True])
@pytest.mark.parametrize("goes_on", [False, True])
def test_shell_groups_count_a_branch_going_on_past_a_thin_shell(py, goes_on):
    """A curve point on the finest shell of the re-tests (1.25 to 2.75 spacings, middle at 2):
    each side has one sample in the shell, at 1.9 spacings (short of the middle), the next at
    3 (beyond the shell): with ``goes_on`` 2 groups (a curve), else 0 (the sampling's phase
    decides)."""
    x = np.array([0.0, 1.0, 1.9, 3.0, 4.0])
    x = np.r_[x, -x[1:]]
    P = np.c_[x, np.zeros_like(x), np.zeros_like(x)]
    order = np.argsort(x)
    indptr, indices = K.csr_union(len(P), np.r_[order[:-1], order[1:]], np.r_[order[1:], order[:-1]])
    h = np.ones(len(P))
    pts = np.array([0], dtype=np.int64)
    if py:
        got = shell._shell_groups(P, h, indptr, indices, 1.25, 2.75, goes_on, pts, 1, SHELL, NUMERIC)
    else:
        got = K.shell_groups(P, h, indptr, indices, 1.25, 2.75, subset=pts, goes_on=goes_on)
    assert got[0] == (2 if goes_on else 0)
    assert _shell_groups_reference(P, h, indptr, indices, 1.25, 2.75, pts, goes_on)[0] == got[0]


def _chain_order_reference(n, src, dst, dd, chn, n_chn):
    """scipy's double Dijkstra sweep of every chain, numpy (the former robust._order_chains)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    inside = (chn[src] >= 0) & (chn[src] == chn[dst])
    g = coo_matrix((np.maximum(dd[inside], 1e-12), (src[inside], dst[inside])), shape=(n, n)).tocsr()
    ids = np.flatnonzero(chn >= 0)
    lab = chn[ids]
    _, first = np.unique(lab, return_index=True)
    d0 = dijkstra(g, directed=False, indices=ids[first], min_only=True)
    o = np.lexsort((ids, -d0[ids], lab))
    ls = lab[o]
    f = np.r_[True, ls[1:] != ls[:-1]]
    e1 = np.empty(n_chn, dtype=np.int64)
    e1[ls[f]] = ids[o[f]]
    d1 = dijkstra(g, directed=False, indices=e1, min_only=True)
    par = d1[ids]
    o = np.lexsort((ids, par, lab))
    return ids[o], par[o], np.flatnonzero(np.r_[True, lab[o][1:] != lab[o][:-1], True])


@pytest.mark.parametrize("py", [False, True])
def test_chain_order_matches_scipy_dijkstra(py):
    """Chains of a random linked graph (cycles, branches, single points) ordered as by scipy's
    dijkstra, bit for bit, compiled and as plain Python; also with many equal distances."""
    rng = np.random.default_rng(5)
    P = rng.uniform(size=(3000, 3))
    dist, idx = knn(P, 6)
    keep = dist < np.median(dist)  # sparse: many components, paths and cycles
    n = len(P)
    src = np.repeat(np.arange(n), 6)[keep.ravel()]
    dst, dd = idx[keep], dist[keep]
    mask = rng.uniform(size=n) < 0.9  # "flagged" points cut the graph further
    chn, n_chn = RG.components(n, src, dst, mask)
    f = _plain("chain_order") if py else K.chain_order
    for w in (dd, np.round(dd / dd.mean(), 1), np.zeros_like(dd)):
        ids_o, par_o, bounds = f(n, src, dst, np.ascontiguousarray(w), chn, n_chn)
        ref = _chain_order_reference(n, src, dst, w, chn, n_chn)
        assert n_chn > 100 and np.diff(bounds).max() > 20 and len(ids_o) == mask.sum()
        for x, y in zip((ids_o, par_o, bounds), ref):
            assert np.array_equal(x, y)


@pytest.mark.parametrize("py", [False, True])
def test_end_counts_match_end_portion(py):
    """The batched end counts are the lengths of robust._end_portion, list by list."""
    rng = np.random.default_rng(1)
    P = rng.normal(size=(200, 3))
    h = rng.uniform(0.5, 2.0, size=200)
    lists = [rng.integers(0, 200, size=int(rng.integers(0, 30))) for _ in range(300)]
    flat = np.concatenate(lists).astype(np.int64)
    off = np.r_[0, np.cumsum([len(x) for x in lists])].astype(np.int64)
    f = _plain("end_counts") if py else K.end_counts
    for span in (0.0, 3.0, 4.0):
        m = f(P, h, flat, off, span)
        assert [int(x) for x in m] == [len(RC.end_portion(P, h, ids, span=span)) for ids in lists]


def _components_reference(n, a, b, mask):
    """scipy's connected components, relabelled by lowest point (the former robust._components)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    sel = mask[a] & mask[b]
    g = coo_matrix((np.ones(int(sel.sum())), (a[sel], b[sel])), shape=(n, n)).tocsr()
    _, lab = connected_components(g, directed=False)
    ids = np.flatnonzero(mask)
    uniq, first = np.unique(lab[ids], return_index=True)
    remap = np.full(lab.max() + 1, -1, dtype=np.int64)
    remap[uniq[np.argsort(ids[first])]] = np.arange(len(uniq))
    out = np.full(n, -1, dtype=np.int64)
    out[ids] = remap[lab[ids]]
    return out, len(uniq)


@pytest.mark.parametrize("py", [False, True])
def test_components_match_scipy(py):
    rng = np.random.default_rng(2)
    f = _plain("components") if py else K.components
    for n, m, frac in ((1, 0, 1.0), (50, 0, 0.5), (3000, 2500, 0.8), (3000, 6000, 0.9), (500, 3000, 0.3)):
        a = rng.integers(0, n, size=m)
        b = rng.integers(0, n, size=m)
        mask = rng.uniform(size=n) < frac
        lab, count = f(n, a, b, mask)
        ref, rcount = _components_reference(n, a, b, mask)
        assert count == rcount and np.array_equal(lab, ref)


@pytest.mark.parametrize("py", [False, True])
def test_csr_union_lists_each_neighbour_once_in_first_order(py):
    """Each row of the union's CSR holds every neighbour of the point once (a pair linked both
    ways, or twice the same way, is one edge), in the order of its first place: the out-links
    in link order, then the in-links in link order."""
    rng = np.random.default_rng(5)
    n = 400
    a = rng.integers(0, n, size=1500).astype(np.int32)
    b = rng.integers(0, n, size=1500).astype(np.int32)
    keep = a != b
    a, b = a[keep], b[keep]
    src, dst = np.r_[a, b[:600], a[:200]], np.r_[b, a[:600], b[:200]]  # both ways, and repeats
    f = _plain("csr_union") if py else K.csr_union
    indptr, indices = f(n, src, dst)
    assert indptr.dtype == np.int64 and indices.dtype == src.dtype and indptr[-1] == len(indices)
    for i in range(n):
        want = [int(y) for x, y in zip(src, dst) if x == i] + [int(x) for x, y in zip(src, dst) if y == i]
        first = list(dict.fromkeys(want))
        assert indices[indptr[i]:indptr[i + 1]].tolist() == first


@pytest.mark.parametrize("k", [4, 5, 9, 16])
def test_spacing_kernel_matches_the_numpy_formula(cloud, k):
    """robust.local_spacing gives the same bits compiled (one pass) as by its numpy formula,
    duplicate samples included."""
    P = cloud[0]
    rng = np.random.default_rng(3)
    P = np.vstack([P, P[rng.choice(len(P), len(P) // 20)]])  # coincident samples
    P = P[np.lexsort(P.T[::-1])]
    dist, idx = knn(P, k)
    got = RF._spacing_floor(K.spacing(dist, idx, SPACING.dup, SPACING.dup_k))  # compiled when numba is there
    py = RF._spacing_floor(_plain("spacing")(dist, idx, SPACING.dup, SPACING.dup_k))
    token = KR._COMPILED.set(False)
    try:
        ref = RF.local_spacing(dist, idx)  # the numpy formula
    finally:
        KR._COMPILED.reset(token)
    assert np.array_equal(got, ref) and np.array_equal(py, ref)


def _spike(dim, rng, n=20, shuffle=True):
    """A sharp spike (two legs 10 degrees apart meeting at an apex) sampled every 1, and the
    order of its points along it: with ``shuffle``, the points near the apex are given
    alternately from either leg (by distance from the apex), as a chain linked across the
    legs comes out ordered."""
    a = np.radians(5.0)
    s = np.arange(1, n + 1, dtype=float)
    true = np.r_[np.c_[s * np.cos(a), s * np.sin(a)][::-1], np.zeros((1, 2)), np.c_[s * np.cos(a), -s * np.sin(a)]]
    true = true + 0.02 * rng.normal(size=true.shape)
    if dim == 3:
        true = np.c_[true, 0.02 * rng.normal(size=len(true))]
    o = np.arange(len(true))
    if shuffle:
        inner = np.arange(n - 8, n + 9)  # the apex is point n
        o[n - 8:n + 9] = inner[np.argsort(np.abs(inner - n), kind="stable")]
    return true[o], np.argsort(o)


def _polylen(X):
    return float(np.linalg.norm(np.diff(X, axis=0), axis=1).sum())


@pytest.mark.parametrize("py", [False, True])
@pytest.mark.parametrize("dim", [2, 3])
def test_untangle_makes_a_zigzag_a_path(py, dim):
    rng = np.random.default_rng(dim)
    X1, back = _spike(dim, rng)
    X2, _ = _spike(dim, rng, n=12, shuffle=False)  # already a path: left alone
    X = np.r_[X1, X2, X1[:3]]
    off = np.array([0, len(X1), len(X1) + len(X2), len(X)], dtype=np.int64)
    which = np.array([0, 1, 2], dtype=np.int64)
    f = _plain("untangle") if py else K.untangle
    order = f(X, off, which, 32, -0.5)
    assert sorted(order.tolist()) == list(range(len(X)))
    for c in range(3):
        seg = order[off[c]:off[c + 1]]
        assert sorted(seg.tolist()) == list(range(off[c], off[c + 1]))  # within its curve
        assert seg[0] == off[c] and seg[-1] == off[c + 1] - 1  # ends kept
    Y = X[order[:len(X1)]]
    # the zigzag is much longer than the spike; untangled, it is the spike walked in order
    assert _polylen(X1) > 1.2 * _polylen(X1[back])
    assert _polylen(Y) <= _polylen(X1[back]) * (1 + 1e-9)
    d = np.diff(Y, axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    assert ((d[1:] * d[:-1]).sum(axis=1) < -0.5).sum() == 1  # only at the apex
    assert np.array_equal(order[len(X1):], np.arange(len(X1), len(X)))  # the path, the short one
    # compiled and Python runs agree
    assert np.array_equal(order, _plain("untangle")(X, off, which, 32, -0.5))


def _strands(gap, n=60, sigma=0.3, seed=0):
    """Points of parallel lines ``gap`` apart along x (one line for ``gap=None``), spacing 1.5,
    Gaussian noise ``sigma`` per coordinate; with their line labels."""
    rng = np.random.default_rng(seed)
    x = np.arange(n) * 1.5
    ys = [0.0] if gap is None else [0.0, gap]
    P = np.vstack([np.column_stack([x, np.full(n, y), np.zeros(n)]) for y in ys])
    lab = np.repeat(np.arange(len(ys)), n)
    return P + rng.normal(scale=sigma, size=P.shape), lab


@pytest.mark.parametrize("compiled", [False, True])
def test_strand_cuts_cut_only_links_across_strands(compiled):
    if compiled and not K.HAVE_NUMBA:
        pytest.skip("numba not installed")
    for gap in (None, 2.5):
        P, lab = _strands(gap)
        dist, idx = knn(P, 16, ordered=True)
        h = RF.local_spacing(dist, idx)
        t, lin = RF.noisy_tangents(P, h, 0.3, build_tree(P), dist, idx)
        src = np.repeat(np.arange(len(P)), 16)
        dst = idx.ravel()
        with K.compiled_for(10**6 if compiled else 0):
            cut = K.strand_cuts(P, h, idx, t, src, dst, 0.3)
        across = lab[src] != lab[dst]
        assert not (cut & ~across).any()  # no link along a strand is cut
        if gap is not None:
            assert cut[across].mean() > 0.5  # most links across are
            # the noisy tangents run along the strands
            assert np.median(np.abs(t[:, 0])) > 0.99


def test_noisy_tangents_compiled_and_python_agree():
    if not K.HAVE_NUMBA:
        pytest.skip("numba not installed")
    P, _ = _strands(2.5, n=30)
    dist, idx = knn(P, 32, ordered=True)
    h = RF.local_spacing(dist[:, :16], idx[:, :16])
    out = []
    for n in (0, 10**6):
        with K.compiled_for(n):
            out.append(K.noisy_tangents(P, np.arange(len(P)), idx, h, 0.3))
    t0, l0 = out[0]
    t1, l1 = out[1]
    np.testing.assert_allclose(np.abs(np.einsum("nd,nd->n", t0, t1)), 1.0, atol=1e-9)
    np.testing.assert_allclose(l0, l1, atol=1e-9)


def test_noisy_tangents_read_nothing_beyond_their_reach():
    # points whose 16th neighbour lies beyond noisy_reach take the method's 16 neighbours
    # instead of a 32-neighbour query: the same tangents to the bit
    P, _ = _strands(2.5, n=60)
    P = np.vstack([P, _strands(None, n=120)[0] + [0.0, 40.0, 0.0]])  # plus a lone strand
    dist, idx = knn(P, 16, ordered=True)
    h = RF.local_spacing(dist, idx)
    short = dist[:, -1] > K.noisy_reach(h, 0.3)
    assert 0.2 < short.mean() < 0.9  # both paths taken
    tree = build_tree(P)
    t1, l1 = RF.noisy_tangents(P, h, 0.3, tree, dist, idx)
    t2, l2 = RF.noisy_tangents(P, h, 0.3, tree, np.zeros_like(dist), idx)  # all queried (32)
    assert np.array_equal(t1, t2) and np.array_equal(l1, l2)
    # a user's k above 32 (six strands, so that the 40th neighbour is within reach): its first
    # 32 neighbours serve, the same bits as the 32-neighbour query
    P = np.vstack([_strands(2.5, n=60, seed=s)[0] + [0.0, 5.0 * s, 0.0] for s in range(3)])
    dist, idx = knn(P, 16, ordered=True)
    h = RF.local_spacing(dist, idx)
    d40, i40 = knn(P, 40, ordered=True)
    assert (d40[:, -1] < K.noisy_reach(h, 0.3)).any()
    tree = build_tree(P)
    t2, l2 = RF.noisy_tangents(P, h, 0.3, tree, np.zeros_like(dist), idx)
    t3, l3 = RF.noisy_tangents(P, h, 0.3, tree, d40, i40)
    assert np.array_equal(t2, t3) and np.array_equal(l2, l3)


def test_knn_of_some_rows_equals_the_full_query():
    rng = np.random.default_rng(3)
    P = rng.random((500, 3))
    P[7] = P[8]  # a duplicate: the point itself may not come first
    dist, idx = knn(P, 12)
    rows = np.array([8, 7, 400, 3, 499])
    d, i = knn(P, 12, rows=rows)
    assert np.array_equal(i, idx[rows]) and np.array_equal(d, dist[rows])
    assert not (i == rows[:, None]).any()  # the point itself excluded


@pytest.mark.parametrize("compiled", [False, True])
def test_strand_cuts_survive_a_link_to_a_far_outlier(compiled):
    """Issue 20 item 7: a link from a strand to an outlier far across it (every mean-shift
    weight around the outlier underflows to 0) stopped the compiled kernel with
    ZeroDivisionError; the link is simply not cut, compiled or not, without a warning."""
    if compiled and not K.HAVE_NUMBA:
        pytest.skip("numba not installed")
    import warnings

    for across in (30.0, 100.0, 1000.0):  # the outlier, this far across the strand
        P, _ = _strands(None)
        P = np.vstack([P, [[P[30, 0], across, 0.0]]])
        q = len(P) - 1
        dist, idx = knn(P, 16, ordered=True)
        h = RF.local_spacing(dist, idx)
        t = np.zeros_like(P)
        t[:, 0] = 1.0  # every tangent along the strand, the outlier's too (a candidate link)
        src = np.array([30, 31], dtype=np.int64)
        dst = np.array([q, 32], dtype=np.int64)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # the plain-Python run divided by zero with a warning
            with K.compiled_for(10**6 if compiled else 0):
                cut = K.strand_cuts(P, h, idx, t, src, dst, 0.3)
        assert not cut.any()


def _fit_system(rng, sizes, loops):
    """The curve fit's kind of system: I + R^T R, R the weighted second differences of curves of
    ``sizes`` samples (closed where ``loops``), one block per curve; as scipy CSR."""
    import scipy.sparse as sp

    blocks = []
    for n, closed in zip(sizes, loops):
        rows, cols, vals = [], [], []
        for i in range(n if closed else n - 2):
            w = rng.uniform(0.2, 30.0)
            for o, v in ((0, 1.0), (1, -2.0), (2, 1.0)):
                rows.append(i)
                cols.append((i + o) % n)
                vals.append(v * w)
        R = sp.csr_matrix((vals, (rows, cols)), shape=(n if closed else n - 2, n))
        blocks.append(sp.identity(n) + R.T @ R)
    return sp.block_diag(blocks, format="csr")


@pytest.mark.parametrize("sizes, loops", [((40,), (False,)), ((3, 17, 60), (False,) * 3),
                                          ((5,), (True,)), ((12, 80, 7), (True, False, True))])
def test_envelope_solve_matches_numpy_and_is_the_same_compiled(sizes, loops):
    # the curve fit's solve (open curves banded, loops with their wrap-around): the dense
    # solution to 1e-12, and the compiled kernel gives the plain run's bits
    import scipy.sparse as sp

    rng = np.random.default_rng(len(sizes) + sum(sizes))
    A = _fit_system(rng, sizes, loops)
    low = sp.tril(A, format="csr")
    low.sort_indices()
    args = (low.indptr.astype(np.int64), low.indices.astype(np.int64), low.data.copy())
    for d in (2, 3):
        rhs = rng.normal(scale=5.0, size=(A.shape[0], d))
        x = _plain("envelope_solve")(*args, rhs)
        ref = np.linalg.solve(A.toarray(), rhs)
        np.testing.assert_allclose(x, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
        if K.HAVE_NUMBA:
            assert np.array_equal(KR.KERNELS["envelope_solve"].compiled(*args, rhs), x)


@pytest.mark.skipif(not has_avx512(), reason="OpenBLAS picks other kernels only on AVX-512 processors")
def test_noisy_network_does_not_depend_on_openblas_s_processor_kernels():
    # the curve fit's banded Cholesky and sparse LU (LAPACK, SuperLU) gave other last bits
    # with OpenBLAS's AVX-512 kernels (12 of the 20 CI digest runs differed between its Haswell
    # and SkylakeX kernels): the same network to the bit under both
    code = network_digest_code("from curvenet import synth\n"
                               "pts, _ = synth.sample(synth.model('wheel'), noise=0.2, rng=11)\n",
                               "curvenet.reconstruct(pts).canonical()")
    assert output_under("Haswell", code) == output_under("SkylakeX", code)


@pytest.mark.skipif(not has_avx512(), reason="OpenBLAS picks other kernels only on AVX-512 processors")
def test_corner_fit_does_not_depend_on_openblas_s_processor_kernels():
    # the fit's corner test (curves._hinge_gain) solved its 3 x 3 least squares by matmul and
    # LAPACK: under OpenBLAS's Haswell kernels the knots' last bits differed, and so did the
    # corners model's fitted curves at noise 0.3 h + x3, sampling 2 (one of the CI digest runs)
    code = network_digest_code("from curvenet import synth\n"
                               "from curvenet.bench import CONDITIONS, run_seed\n"
                               "c = 'noise 0.3h + density x3'\n"
                               "pts, _ = synth.sample(synth.model('corners'), rng=run_seed('corners', c) + 2, **CONDITIONS[c])\n",
                               "curvenet.reconstruct(pts)")
    assert output_under("Haswell", code) == output_under("SkylakeX", code)


def _node_offsets(args, nodes_off):
    """Distance from the origin (the true node) of the junction_nodes kernel's first node, with
    the settings as they are and with ``nodes_off`` as the NODES group; the compiled run (when
    numba is there) checked to give the plain run's bits."""
    k = KR.KERNELS["junction_nodes"]
    X, _ = k.plain(*args, *k.groups)
    Xo, _ = k.plain(*args, ENDS, nodes_off, LINALG)
    if k.compiled is not None:
        Xc, _ = k.compiled(*args, *k.groups)
        assert np.array_equal(Xc, X)
    return np.linalg.norm(X[0]), np.linalg.norm(Xo[0])


@pytest.mark.parametrize("ang", [0.0, 3.0, 10.0])
def test_near_tangent_junction_under_noise(ang):
    # the junction of test_near_tangent_junction_is_where_the_circles_meet with noise 0.1 on
    # every coordinate (the noise scale given: 0.13, as estimated), 4 samplings: the circles,
    # each fitted over the longest span its points fit, place the node within 1.5 of it (0.02
    # to 1.46), the lines' node (no circle fits: tangent_rc 0) lies 0.3-4.4 off; compiled and
    # plain runs give the same bits
    now, lines = [], []
    for seed in range(4):
        args = list(_tangent_junction(2, ang))
        args[0] = args[0] + np.random.default_rng(seed).normal(scale=0.1, size=args[0].shape)
        args[11] = 0.13
        a, b = _node_offsets(args, NODES._replace(tangent_rc=0.0))
        now.append(a)
        lines.append(b)
    assert max(now) < 1.5 and np.mean(now) + 1.0 < np.mean(lines), (now, lines)


def _strand_junction(ang, noise, seed):
    """The near-tangent junction of :func:`_tangent_junction` (2D, a line leaving a circle of
    radius 30 at ``ang`` degrees, node at 0) as the pipeline hands it over under noise: the
    branches end where the region begins (arc before the node up to 3 short of it, arc after it
    and line from 6 on), the region holds both strands' samples in between; every sample moved
    by Gaussian noise of ``noise`` per coordinate. Returns the junction_nodes arguments."""
    R = 30.0
    arc = lambda s: np.column_stack([R * np.sin(s / R), R * np.cos(s / R) - R])
    a = np.radians(ang)
    line = lambda r: np.column_stack([r * np.cos(a), r * np.sin(a)])
    parts = [arc(np.arange(-40.0, -3.0 + 1e-9, 1.0)), arc(np.arange(40.0, 6.0 - 1e-9, -1.0)),
             line(np.arange(30.0, 6.0 - 1e-9, -1.0))]
    region = [arc(np.arange(-2.0, 5.0 + 1e-9, 1.0)), line(np.arange(0.5, 5.5 + 1e-9, 1.0))]
    P = np.concatenate(parts + region)
    P = P + np.random.default_rng(seed).normal(scale=noise, size=P.shape)
    nb = sum(len(p) for p in parts)
    boff = np.r_[0, np.cumsum([len(p) for p in parts])].astype(np.int64)
    rflat = np.arange(nb, len(P), dtype=np.int64)
    consts = K.JunctionParams(4.0, 6.0, 1.25, 4.5, 16.5, 0.8 * 5.5, 0.9, 1.5, False)
    return (P, np.ones(len(P)), np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64),
            np.arange(nb, dtype=np.int64), boff, np.array([0, 3], dtype=np.int64), rflat,
            np.array([0, len(rflat)], dtype=np.int64), np.ones(1), 1.0, 1.3 * noise, consts)


@pytest.mark.parametrize("ang", [0.0, 5.0])
def test_strand_step_places_a_near_tangent_junction_under_noise(ang):
    # noise 0.2, 6 samplings: where one strand (the arc before the node) becomes two (the arc
    # after it and the line) the samples per length step up; the node moved there when the step
    # lies over NODES.tangent_keep from the circles' node (measured: mean 1.05 at 0 degrees and
    # 1.07 at 5, against 1.91 and 1.92 with the step off, 1.9-2.6 with the lines alone);
    # compiled and plain runs give the same bits
    now, off = [], []
    for seed in range(6):
        a, b = _node_offsets(_strand_junction(ang, 0.2, seed), NODES._replace(tangent_ratio=np.inf))
        now.append(a)
        off.append(b)
    assert max(now) < 3.0 and np.mean(now) + 0.5 < np.mean(off), (now, off)


def _corner_cut(bump: bool):
    """Points on a line with a gap from x = 0 to x = 4 (spacing 1, tangents along the line),
    with (``bump``) or without three samples of a detour 1.5-1.8 spacings off the line over the
    gap: the edge from 0 to 4 then cuts the corner of a curve that runs through those samples."""
    line = np.c_[np.r_[-3.0, -2.0, -1.0, 0.0, 4.0, 5.0, 6.0, 7.0], np.zeros(8)]
    over = np.array([[1.0, 1.5], [2.0, 1.8], [3.0, 1.5]]) if bump else np.zeros((0, 2))
    P = np.vstack([line, over])
    t = np.tile([1.0, 0.0], (len(P), 1))
    t[len(line):] = [0.0, 1.0]  # the detour's samples: tangents across the line (no strip edge)
    dist, idx = knn(P, min(8, len(P)))
    h, lin = np.ones(len(P)), np.ones(len(P))
    return P, idx, h, t, lin


@pytest.mark.parametrize("plain", [False, True])
def test_strip_edge_over_a_gap_is_kept_and_one_cutting_a_corner_is_not(plain):
    """The lens test of the strip edges (noisy input): an edge kept only as the nearest neighbour
    along the tangent bridges a gap, so no nearer sample lies in its lens off its line; where
    the samples of a detour do, the edge cuts a corner and is left out (with ``lens`` only)."""
    f = _plain("linked_edges") if plain else K.linked_edges
    for bump in (False, True):
        P, idx, h, t, lin = _corner_cut(bump)
        for lens in (False, True):
            src, dst, _ = f(P, h, idx, t, lin, 2.5, 1.0, 0.0, 0.0, 2.0, 0.3, lens)
            edges = set(zip(src.tolist(), dst.tolist()))
            assert ((3, 4) in edges) == (not (bump and lens)), (bump, lens)
            assert ((4, 3) in edges) == (not (bump and lens)), (bump, lens)


def test_the_corner_test_s_3x3_solve_matches_lapack_and_never_raises():
    import warnings

    from curvenet.methods.robust.curves import _solve3

    rng = np.random.default_rng(3)
    A = rng.normal(size=(50, 9, 3))
    M = np.einsum("cki,ckj->cij", A, A)  # (normal equations: symmetric, well conditioned)
    B = rng.normal(size=(50, 3, 2))
    np.testing.assert_allclose(_solve3(M, B), np.linalg.solve(M, B), rtol=1e-10, atol=1e-12)
    M[0] = np.outer([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])  # singular: no solution, no error
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        X = _solve3(M, B)
    assert not np.isfinite(X[0]).all() and np.isfinite(X[1:]).all()
