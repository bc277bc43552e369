"""Stage 5: links that step over a junction's region are left out of the chains
(:func:`curvenet.methods.robust.chains.part_bypassed`)."""
import numpy as np
from scipy.sparse import coo_matrix

from curvenet import synth
from curvenet.metrics import compare
from curvenet.reconstruct import reconstruct
from curvenet.methods.robust import chains
from curvenet.methods.robust.chains import part_bypassed
from curvenet.methods.robust.graph import Graph, components
from curvenet.methods.robust.thresholds import CHAINS

from test_quality_kinds import _sampled


def _graph(n, links):
    """A Graph over ``n`` points with the directed links ``links`` (both directions given)."""
    a = np.array(links, dtype=np.int32)
    src = np.r_[a[:, 0], a[:, 1]].astype(np.int32)
    dst = np.r_[a[:, 1], a[:, 0]].astype(np.int32)
    m = coo_matrix((np.ones(len(src)), (src, dst)), shape=(n, n)).tocsr()
    m.sum_duplicates()
    return Graph(src, dst, m.indptr.astype(np.int64), m.indices.astype(np.int32))


def _rail(far_regions=True, region_points=2):
    """A rail along x (samples at x = 0..4 and 6..10) through a junction's region at x = 5, a
    rung up from it to another region; regions at both ends of the rail unless not
    ``far_regions``. One link joins x = 4 to x = 6 over the region."""
    P = [[float(x), 0.0] for x in range(5)] + [[float(x), 0.0] for x in range(6, 11)]  # 0-9
    rail_l, rail_r = list(range(0, 5)), list(range(5, 10))
    reg = [-1] * 10
    junction = [len(P) + i for i in range(region_points)]
    P += [[5.0, 0.0], [5.2, 0.3]][:region_points]
    reg += [0] * region_points
    rung = list(range(len(P), len(P) + 5))
    P += [[5.0, 1.0 + y] for y in range(5)]
    reg += [-1] * 5
    top = [len(P), len(P) + 1]
    P += [[5.0, 6.0], [5.3, 6.2]]
    reg += [1, 1]
    links = [(a, b) for a, b in zip(rail_l, rail_l[1:])] + [(a, b) for a, b in zip(rail_r, rail_r[1:])]
    links += [(a, b) for a, b in zip(rung, rung[1:])] + [(rung[-1], top[0]), (top[0], top[1])]
    links += [(4, j) for j in junction] + [(5, j) for j in junction] + [(rung[0], j) for j in junction]
    links += [(4, 5)]  # the link over the region
    if far_regions:
        left, right = [len(P), len(P) + 1], [len(P) + 2, len(P) + 3]
        P += [[-1.0, 0.0], [-1.2, 0.3], [11.0, 0.0], [11.2, 0.3]]
        reg += [2, 2, 3, 3]
        links += [(0, left[0]), (left[0], left[1]), (9, right[0]), (right[0], right[1])]
    P, reg = np.array(P), np.array(reg)
    return P, _graph(len(P), links), reg >= 0, reg


def _over(P, g, flagged, reg):
    chn, n = components(len(P), g.src, g.dst, ~flagged)
    out = part_bypassed(P, g, flagged, reg, chn, n)
    # the pieces are those of the links without the ones left out, numbered the same way
    keep = np.ones(len(g.src), dtype=bool)
    keep[out.dropped] = False
    chn2, n2 = components(len(P), g.src[keep], g.dst[keep], ~flagged)
    assert out.n_chn == n2 and np.array_equal(out.chn, chn2)
    d = out.dropped
    return sorted({tuple(sorted((int(a), int(b)))) for a, b in zip(g.src[d], g.dst[d])})


def test_a_link_over_a_junction_between_two_pieces_is_left_out():
    assert _over(*_rail()) == [(4, 5)]


def test_a_link_over_a_region_is_kept_where_a_piece_would_reach_no_other_region():
    # (the tip of a sharp corner whose close legs were flagged, a sample inside one region)
    assert _over(*_rail(far_regions=False)) == []


def test_a_link_over_a_lone_flagged_point_is_kept():
    assert _over(*_rail(region_points=1)) == []


def test_a_link_that_turns_at_the_region_is_kept():
    P, g, flagged, reg = _rail()
    P = P.copy()
    P[5] = [3.0, 2.0]  # the link from x = 4 now turns back, away from the region
    assert _over(P, g, flagged, reg) == []


def _with_and_without(monkeypatch, name, k):
    pts, truth = _sampled(name, "noise 0.2h", k)
    h = synth.h_of(truth)
    with_ = compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"]
    monkeypatch.setattr(chains, "CHAINS", CHAINS._replace(bypass_off=0.0))
    without = compare(reconstruct(pts, method="robust"), truth, h=h)["curve_f1"]
    monkeypatch.setattr(chains, "CHAINS", CHAINS)
    return with_, without


def test_the_ladder_and_the_streets_under_noise_gain(monkeypatch):
    # the ladder's rails at noise 0.2 h: links of 2-3 h join the rail's samples on either side
    # of the junctions' regions, so a rail stayed one chain past them and its junctions were
    # lost (sampling 6: 0.14 without the rule when it came); the streets' crossings: links
    # around a crossing's corner. Since the split chains' double edges and free branches
    # (branched.py, 6 December 2026) mend much of what a ladder's rail lost (sampling 6: 0.64
    # either way), the gain is measured over both kinds' 8 samplings: then 6 better by
    # 0.07-0.24, 3 worse (ladder 0.13 and 0.28, streets 0.07), +0.71 in all; and on one
    # sampling alone: the streets' sampling 1 until repairs.cross_pass_regions (6 December
    # 2026) mended its crossing without the rule too (0.90 without, 0.92 with); then the
    # ladder's sampling 4 (0.92 with, 0.72 without) until the rail's run-on half was judged by
    # its centroid (paired._through_halves, 7 December 2026: exact either way); now the
    # streets' sampling 4 (0.98 with, 0.76 without; over the 16: 7 better, 1 worse, +0.90)
    pairs = [_with_and_without(monkeypatch, name, k) for name in ("ladder", "streets") for k in range(8)]
    gains = [w - wo for w, wo in pairs]
    assert sum(g > 0 for g in gains) >= 2 * sum(g < 0 for g in gains) and sum(gains) >= 0.5, pairs
    with_, without = _with_and_without(monkeypatch, "streets", 4)
    assert with_ >= 0.85 and with_ - without >= 0.15, (with_, without)
