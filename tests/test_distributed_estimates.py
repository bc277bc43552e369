"""The whole cloud's estimates from its tiles: exact medians without gathering the values."""

from __future__ import annotations

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from curvenet import synth  # noqa: E402
from curvenet.distributed import estimates as de  # noqa: E402
from curvenet.distributed import TileGrid, reconstruct_tiled  # noqa: E402
from curvenet.distributed import run as drun  # noqa: E402
from curvenet.methods.robust import estimate  # noqa: E402


def _median_of_parts(parts):
    """:func:`exact_median` over ``parts`` (as over tiles): the median, the first level's merged
    counts, and per later level the most counts one part handed over, per fetch the distinct
    values all parts handed over."""
    counted, fetched = [], []

    def count_in(sel, shift):
        got = [de.sparse_counts(p, shift, sel) for p in parts]
        counted.append(max(len(k) for k, _ in got))
        return de.merge_counts(got)

    def values_in(sel):
        got = [np.unique(de._within(p, sel), return_counts=True) for p in parts]
        fetched.append(sum(len(k) for k, _ in got))
        return de.merge_values(got)

    first = de.merge_counts([de.sparse_counts(p) for p in parts])
    return de.exact_median(first, count_in, values_in), first, counted, fetched


@pytest.mark.parametrize("n", [1, 2, 7, 1000, 1001, 100_000])
@pytest.mark.parametrize("spread", ["wide", "ties"])
def test_median_from_bins_is_numpys(n, spread):
    rng = np.random.default_rng(n)
    v = np.exp(rng.normal(size=n) * (8 if spread == "wide" else 1)) * 1e-3
    v[: n // 3] = v[0]  # ties across a bin
    if spread == "ties":
        v[: n // 2] = 0.25  # half the values one value (a spacing on an exact grid)
    v[rng.random(n) < 0.01] = np.nan  # (not counted)
    got, first, counted, fetched = _median_of_parts(np.array_split(rng.permutation(v), 5))
    assert got == np.median(v[np.isfinite(v)])
    # what the tiles hand over stays small whatever n: the coarse bins 16 an octave, then at
    # most two bins split in 2^8 a level, then the few distinct values of the finest bins
    f = v[np.isfinite(v)]
    octaves = np.log2(f.max() / f.min()) + 2
    levels = np.diff(de.MEDIAN_SHIFTS)
    assert len(first[0]) <= 16 * octaves
    assert len(counted) == len(levels) and all(-b <= 8 for b in levels) and max(counted) <= 2 << 8
    assert max(fetched) <= 64


def test_what_a_tile_hands_over_is_bounded_when_the_middle_bin_is_crowded():
    # a million distinct values inside one coarse bin: each level still splits the middle bins
    # in at most 2^8 (one level of 2^16 had every tile hand over tens of thousands of counts)
    rng = np.random.default_rng(3)
    v = 1.0 + rng.random(1_000_000) * 0.01
    got, _, counted, _ = _median_of_parts(np.array_split(v, 4))
    assert got == np.median(v)
    assert max(counted) <= 2 << 8


def test_bins_sort_as_the_values():
    v = np.sort(np.r_[0.0, -0.0, 5e-324, 1e-300, np.random.default_rng(0).random(1000), 1e300])
    assert (np.diff(de.bin_keys(v).astype(np.float64)) >= 0).all()


@pytest.fixture(scope="module")
def threads():
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.mark.parametrize("dups", [False, True])
def test_tiled_estimates_are_the_whole_clouds_exactly(threads, tmp_path, monkeypatch, dups):
    """A cloud larger than the estimate's sample: the spacing and noise a tiled run reports are
    those of one process on all points, bit for bit (noise-free with repeated samples: the
    duplicate rule's second pass)."""
    rng = np.random.default_rng(3)
    clouds = []
    for i, name in enumerate(("tree", "torus", "cube", "mug")):
        P, _ = synth.sample(synth.model(name), noise=0.0 if dups else 0.1, rng=i)
        clouds.append(P + [3.0 * i, 0, 0])
    P = np.vstack(clouds)
    if dups:
        P = np.vstack([P, P[rng.choice(len(P), len(P) // 20, replace=False)]])
    P = P[rng.permutation(len(P))]
    f = tmp_path / "p.npy"
    np.save(f, P)
    one = estimate(P)
    monkeypatch.setattr(drun, "ESTIMATE_POINTS", len(P) // 6)  # the sample: a few of the tiles
    net = reconstruct_tiled(f, tiles=40 * one.hmed, client=threads)
    assert net.parameters["estimates_exact"] and net.parameters["estimates_inexact_points"] == 0
    # (the repeated samples are dropped before the second medians)
    assert net.parameters["estimates_points"] == (len(np.unique(P, axis=0)) if dups else len(P))
    assert net.parameters["spacing"] == one.hmed and net.parameters["noise"] == one.sigma
    assert net.parameters["clean"] == one.clean


def test_the_sample_alone_would_differ():
    """Control: on the cloud of the test above, the estimates of the sampled tiles alone are
    not the whole cloud's (so that test checks the exact pass, not a lucky sample)."""
    clouds = [synth.sample(synth.model(m), noise=0.1, rng=i)[0] + [3.0 * i, 0, 0]
              for i, m in enumerate(("tree", "torus", "cube", "mug"))]
    P = np.vstack(clouds)
    one = estimate(P)
    keys_of = TileGrid(tuple(P.min(0)), 40 * one.hmed).keys_of(P)  # the run's grid
    uk, inv, cnt = np.unique(keys_of, axis=0, return_inverse=True, return_counts=True)
    keys = [tuple(k) for k in uk.tolist()]
    count = dict(zip(keys, cnt.tolist()))
    old = drun.ESTIMATE_POINTS
    try:
        drun.ESTIMATE_POINTS = len(P) // 6
        sample = set(drun._sample_tiles(keys, count))
    finally:
        drun.ESTIMATE_POINTS = old
    assert 0 < len(sample) < len(keys)
    mask = np.array([keys[i] in sample for i in inv.ravel()])
    part = estimate(P[mask])
    assert part.hmed != one.hmed and part.sigma != one.sigma


@pytest.mark.parametrize("noise", [0.0, 0.1])
def test_tiles_go_on_from_the_box_the_estimates_prepared(threads, tmp_path, monkeypatch, noise):
    """A cloud larger than the sample: each tile's estimate pass prepares its box with the halo
    of its reconstruction, and the reconstruction goes on from it: the network is the one the
    tiles give when they read and prepare their boxes again, bit for bit; a halo given smaller
    than the estimates need prepares nothing (the boxes differ)."""
    from curvenet.distributed import tasks

    clouds = [synth.sample(synth.model(m), noise=noise, rng=i)[0] + [3.0 * i, 0, 0]
              for i, m in enumerate(("tree", "torus", "cube", "mug"))]
    P = np.vstack(clouds)
    f = tmp_path / "p.npy"
    np.save(f, P)
    hmed = estimate(P).hmed
    monkeypatch.setattr(drun, "ESTIMATE_POINTS", len(P) // 6)
    a = reconstruct_tiled(f, tiles=40 * hmed, client=threads)
    assert a.stats["tiles_prepared"] == a.parameters["tiles"] > 1
    monkeypatch.setattr(tasks, "read_prepared", lambda root, key: None)  # every tile prepares again
    b = reconstruct_tiled(f, tiles=40 * hmed, client=threads)
    assert b.stats["tiles_prepared"] == 0
    assert a == b and a.n_curves > 0  # (nodes, curves, points and input ids, exactly)
    monkeypatch.undo()
    monkeypatch.setattr(drun, "ESTIMATE_POINTS", len(P) // 6)
    written = []
    monkeypatch.setattr(de, "write_prepared", lambda *args: written.append(args[1]))
    c = reconstruct_tiled(f, tiles=40 * hmed, client=threads, halo=0.5 * a.parameters["halo"])
    assert c.stats["tiles_prepared"] == 0 and not written


def test_points_reaching_past_their_tile_are_computed_again_exactly(threads, tmp_path, monkeypatch):
    """Outliers far from the curves reach past their tile's widened box; their values are
    computed again from the points within their reach, so that the medians are the whole
    cloud's bit for bit. Control: without that pass the tiles leave points inexact."""
    rng = np.random.default_rng(5)
    clouds = [synth.sample(synth.model(m), noise=0.1, rng=i)[0] + [3.0 * i, 0, 0]
              for i, m in enumerate(("tree", "torus", "cube", "mug"))]
    P = np.vstack(clouds)
    lo, hi = P.min(0), P.max(0)
    P = np.vstack([P, lo + (hi - lo) * rng.random((len(P) // 20, 3)) * [1, 1.5, 1.5]])  # outliers around
    P = P[rng.permutation(len(P))]
    f = tmp_path / "p.npy"
    np.save(f, P)
    one = estimate(P)
    monkeypatch.setattr(drun, "ESTIMATE_POINTS", len(P) // 6)
    net = reconstruct_tiled(f, tiles=40 * one.hmed, client=threads)
    assert net.parameters["estimates_inexact_points"] == 0 and net.parameters["estimates_exact"]
    assert (net.parameters["spacing"], net.parameters["noise"]) == (one.hmed, one.sigma)
    monkeypatch.setattr(de, "tile_fix_values", lambda root, grid, key, radius, tag: _unfixed(root, key, tag))
    raw = reconstruct_tiled(f, tiles=40 * one.hmed, client=threads)
    assert raw.parameters["estimates_inexact_points"] > 0 and not raw.parameters["estimates_exact"]


def _unfixed(root, key, tag):
    """The tile's counts as :func:`tile_values` left them (the fix pass switched off)."""
    from curvenet.distributed.scratch import read_values

    vals = {name: read_values(root, key, f"{tag}-{name}") for name in ("h", "rms")}
    far = read_values(root, key, f"{tag}-far")
    return de.TileValues(len(vals["h"]), len(far), {n: de.sparse_counts(v) for n, v in vals.items()})
