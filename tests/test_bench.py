"""The benchmark runner, its report and the `curvenet bench` command (small sizes)."""

import importlib
import json
import subprocess
import sys

import numpy as np
import pytest

from curvenet import bench, synth
from curvenet.errors import InputError
from curvenet.metrics import compare

rec = importlib.import_module("curvenet.reconstruct")  # the module (the package exports the function)


@pytest.fixture(scope="module")
def rows():
    return bench.run_bench(["emst"], ["crossing", "cube"], quick=True)


def test_rows_cover_models_and_conditions(rows):
    assert len(rows) == 2 * len(bench.CONDITIONS)
    assert {(r["model"], r["condition"]) for r in rows} == {
        (m, c) for m in ("crossing", "cube") for c in bench.CONDITIONS
    }
    for r in rows:
        for k in ("N_n", "N_c", "N_d", "parameters", "time", "node_f1", "curve_f1", "exact_topology",
                  "node_offset_h", "true_N_n", "true_N_c"):
            assert k in r, k
        assert r["error"] is None and r["parameters"] == {"k": 12}


def test_rows_are_the_metrics_of_the_method(rows):
    r = next(x for x in rows if x["model"] == "cube" and x["condition"] == "noise 0.2h")
    truth = synth.model("cube")
    pts, _ = synth.sample(truth, rng=bench.run_seed("cube", "noise 0.2h"), noise=0.2)
    assert r["N_d"] == len(pts)
    net = rec.reconstruct(pts, method="emst")
    m = compare(net, truth, h=synth.h_of(truth))
    assert (r["N_n"], r["N_c"]) == (net.n_nodes, net.n_curves)
    assert r["curve_f1"] == m["curve_f1"] and r["node_f1"] == m["node_f1"]
    # deterministic: the same run gives the same rows
    again = bench.run_bench(["emst"], ["cube"], ["noise 0.2h"], quick=True)[0]
    assert again["curve_f1"] == r["curve_f1"] and again["N_c"] == r["N_c"]


def test_markdown_and_json(rows, tmp_path):
    md = bench.write_markdown(rows, tmp_path / "b.md", command="test")
    assert (tmp_path / "b.md").read_text() == md
    assert "| Model | true N_n / N_c | Method | N_n | N_c | N_d | Parameters | Time (s)" in md
    assert "**crossing**" in md and "**cube**" in md and "Machine:" in md
    for c in bench.CONDITIONS:
        assert f"## Synthetic models, {c}" in md
    bench.write_json(rows, tmp_path / "b.json", extra={"machine": bench.machine()})
    data = json.loads((tmp_path / "b.json").read_text())
    assert len(data["rows"]) == len(rows) and data["machine"]["cores"] >= 1


def test_summary_means(rows):
    s = bench.summarize(rows)
    clean = next(x for x in s if x["condition"] == "clean" and x["method"] == "emst")
    vals = [r["curve_f1"] for r in rows if r["condition"] == "clean"]
    assert clean["n"] == 2 and clean["curve_f1"] == pytest.approx(np.mean(vals))


def _row(model, method, f1, cond="clean", dataset="synthetic", error=None):
    return {"dataset": dataset, "condition": cond, "model": model, "method": method,
            "curve_f1": None if error else f1, "error": error}


def test_head_to_head_counts_model_by_model():
    rows = [
        _row("a", "robust", 1.0), _row("a", "emst", 1.0), _row("a", "paper-tuned", 0.5),
        _row("b", "robust", 0.8), _row("b", "emst", 0.9), _row("b", "paper-tuned", 0.8),
        _row("c", "robust", 0.9), _row("c", "emst", 0.1), _row("c", "paper-tuned", None, error="boom"),
        _row("d", "robust", 0.500), _row("d", "emst", 0.497),  # under the tables' two decimals
        _row("a", "robust", 0.0, cond="noise"), _row("a", "emst", None, cond="noise", error="boom"),
    ]
    h = {(e["condition"], e["other"]): e for e in bench.head_to_head(rows)}
    assert set(h) == {("clean", "paper-tuned"), ("clean", "emst"), ("noise", "emst")}
    e = h[("clean", "emst")]
    assert [m for m, _, _ in e["better"]] == ["c"]
    assert [m for m, _, _ in e["same"]] == ["a", "d"]
    assert e["worse"] == [("b", 0.8, 0.9)]
    e = h[("clean", "paper-tuned")]
    # a failed run of the other method counts for robust; d has no paper-tuned row
    assert [m for m, _, _ in e["better"]] == ["a", "c"] and [m for m, _, _ in e["same"]] == ["b"]
    assert [m for m, _, _ in h[("noise", "emst")]["better"]] == ["a"]
    lines = bench._head_to_head_lines(rows)
    assert "## Head to head (curve F1, model by model)" in lines
    assert "| synthetic | clean | emst | 1 | 2 | 1 | b 0.80 / 0.90, a 1.00 / 1.00, d 0.50 / 0.50 |" in lines
    assert "| synthetic | noise | emst | 1 | 0 | 0 | none |" in lines
    assert bench._head_to_head_lines([_row("a", "emst", 1.0)]) == []


def test_bad_names():
    with pytest.raises(InputError):
        bench.run_bench(["nope"], ["cube"], quick=True)
    with pytest.raises(InputError):
        bench.run_bench(["emst"], ["nope"], quick=True)
    with pytest.raises(InputError):
        bench.run_bench(["emst"], ["cube"], ["nope"], quick=True)


def test_missing_and_failing_methods(monkeypatch):
    monkeypatch.setitem(rec.METHODS, "ghost", ("curvenet.no_such_module", "f"))
    monkeypatch.setitem(rec.METHODS, "broken", ("curvenet.validate", "as_points"))  # returns no network
    assert "ghost" not in bench.available_methods()
    rows = bench.run_bench(["ghost", "broken", "emst"], ["cube"], ["clean"], quick=True)
    assert [r["method"] for r in rows] == ["broken", "emst"]
    assert rows[0]["error"] and rows[0]["curve_f1"] == 0.0 and rows[1]["error"] is None


def test_tune_paper_is_never_worse_than_fixed():
    pytest.importorskip("curvenet.methods.paper")
    truth = synth.model("crossing")
    h = synth.h_of(truth)
    pts, _ = synth.sample(truth)
    grid = {"epsilon": (1e-3, 3e-2), "tau_s": (5.0,), "theta": (120.0,)}
    params, m = bench.tune_paper(pts, truth, h=h, grid=grid)
    assert set(params) == {"epsilon", "tau_s", "theta"}
    fixed = compare(rec.reconstruct(pts, method="paper"), truth, h=h)
    assert m["curve_f1"] >= fixed["curve_f1"]
    again = compare(rec.reconstruct(pts, method="paper", **params), truth, h=h)
    assert again["curve_f1"] == m["curve_f1"]


def test_cli_quick(tmp_path):
    pytest.importorskip("curvenet.cli")
    cmd = [sys.executable, "-m", "curvenet.cli", "bench", "--quick", "--methods", "emst", "--no-cassie",
           "--no-figures", "--conditions", "clean", "--out", str(tmp_path)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    md = (tmp_path / "benchmarks.md").read_text()
    assert "curvenet bench --quick" in md and "| emst |" in md.replace("|  |  | emst", "| emst")
    data = json.loads((tmp_path / "benchmarks.json").read_text())
    assert {r["model"] for r in data["rows"]} == set(bench.QUICK_MODELS)
    assert "synthetic clean" in res.stdout.replace("  ", " ").replace("  ", " ")
    if bench.surfacing_available():  # a quick run surfaces the saddle (and again with its border named)
        assert [r["model"] for r in data["surfacing"]] == ["saddle", "saddle (opening given)"]
        assert "## Surfacing" in md and "| surfaces | saddle | 12 | 20 | 9 (9) | 1 (1) | 0 | 0 | 0 | 0 |" in md


def test_cli_missing_out_folder(tmp_path):
    pytest.importorskip("curvenet.cli")
    from curvenet.cli import main

    assert main(["bench", "--quick", "--methods", "emst", "--out", str(tmp_path / "nope"), "-q"]) != 0


def test_figures(tmp_path):
    pytest.importorskip("matplotlib")
    pytest.importorskip("curvenet.methods.paper")
    from curvenet.plots import bench_figures

    sweep = bench.eps_sweep("crossing", [1e-3, 1e-2])
    assert sweep["true_N_n"] == 7 and len(sweep["N_c"]) == 2
    p = bench_figures.figure7(sweep, tmp_path / "f7.png")
    q = bench_figures.figure8(bench.method_vs_emst("fig8", "emst"), tmp_path / "f8.png")
    for f in (p, q):
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_method_vs_emst_data():
    data = bench.method_vs_emst("fig8", "emst", condition="noise 0.2h")
    truth = synth.model("fig8")
    pts, _ = synth.sample(truth, rng=bench.run_seed("fig8", "noise 0.2h"), noise=0.2)
    np.testing.assert_array_equal(data["points"], pts)
    assert (data["true_N_n"], data["true_N_c"]) == (truth.n_nodes, truth.n_curves)
    assert [d["method"] for d in data["panels"]] == ["emst", "emst"]
    for d in data["panels"]:
        s = compare(d["network"], truth, h=synth.h_of(truth))
        assert (d["curve_f1"], d["exact_topology"]) == (s["curve_f1"], s["exact_topology"])


def test_figures_only_draw_what_they_are_given(tmp_path, monkeypatch):
    """The figure functions compute nothing: they draw the data handed to them."""
    pytest.importorskip("matplotlib")
    from curvenet import Curve, CurveNetwork
    from curvenet.plots import bench_figures

    def no_reconstruction(*args, **kwargs):
        raise AssertionError("a figure function ran a reconstruction")

    monkeypatch.setattr(rec, "reconstruct", no_reconstruction)
    monkeypatch.setattr(bench, "reconstruct", no_reconstruction)
    line = CurveNetwork(np.array([[0.0, 0.0], [1.0, 0.0]]), [Curve(np.array([[0.0, 0.0], [0.5, 0.1], [1.0, 0.0]]), 0, 1)])
    data = {"model": "hand-made", "condition": "clean", "points": np.array([[0.0, 0.0], [0.5, 0.1], [1.0, 0.0]]),
            "true_N_n": 2, "true_N_c": 1,
            "panels": [{"method": m, "network": line, "curve_f1": 1.0, "exact_topology": True} for m in ("a", "b")]}
    assert bench_figures.figure8(data, tmp_path / "f8.png").read_bytes()[:4] == b"\x89PNG"
    sweep = {"model": "hand-made", "epsilon": [1e-3, 1e-2], "contracted_N_n": [2, 2], "contracted_N_c": [1, 1],
             "true_N_n": 2, "true_N_c": 1, "node_f1": [1.0, 1.0], "curve_f1": [1.0, 0.5], "exact_topology": [1, 0]}
    assert bench_figures.figure7(sweep, tmp_path / "f7.png").read_bytes()[:4] == b"\x89PNG"


def test_python_m_bench_points_to_the_cli():
    r = subprocess.run([sys.executable, "-m", "curvenet.bench"], capture_output=True, text=True)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.strip() == (
        "curvenet: error: run the benchmark with `curvenet bench` (or `python -m curvenet.cli bench`)"
    )


def test_tune_each_condition_and_extra_conditions():
    pytest.importorskip("curvenet.methods.paper")
    rows = bench.run_bench(["paper-tuned", "paper"], ["crossing"], ["noise 0.2h", "outliers 2%"], quick=True,
                           tune_on="each")
    by = {(r["condition"], r["method"]): r for r in rows}
    for c in ("noise 0.2h", "outliers 2%"):
        assert by[c, "paper-tuned"]["tuned_on"] == c
        # the defaults are among the candidates, so the oracle is never worse than the fixed setting
        assert by[c, "paper-tuned"]["curve_f1"] >= by[c, "paper"]["curve_f1"]
    n_clean = bench.run_bench(["emst"], ["crossing"], ["clean"], quick=True)[0]["N_d"]
    assert by["outliers 2%", "paper"]["N_d"] == n_clean + round(0.02 * n_clean)
    with pytest.raises(InputError):
        bench.run_bench(["emst"], ["crossing"], quick=True, tune_on="sometimes")


def test_seed_spread_scores_every_sampling():
    models, conds = ["tree", "eye"], ["clean", "noise 0.3h + density x3"]
    sp = bench.seed_spread("robust", 2, models, conds)
    assert [s["condition"] for s in sp] == conds
    for s in sp:
        rows = [r for k in range(2) for r in bench.run_bench(["robust"], models, [s["condition"]], seed=k)]
        f1 = [r["curve_f1"] for r in rows]
        assert s["mean"] == pytest.approx(np.mean(f1))
        assert s["seed0"] == pytest.approx(np.mean(f1[:2]))
        assert s["worst_seed"] == pytest.approx(min(np.mean(f1[:2]), np.mean(f1[2:])))
        assert len(s["misses"]) == sum(f < 1 for f in f1)
    md = bench.write_markdown([], None, spread=sp)
    assert "## Seed spread (2 samplings, `robust`)" in md
    assert md.count("\n| noise 0.3h + density x3 |") == 1
    assert "analogues of real failure kinds" not in md
    both = bench.write_markdown([], None, spread=sp, kind_spread=sp[:1])
    assert "## Seed spread, analogues of real failure kinds (2 samplings, `robust`)" in both
    assert both.count("\n| clean |") == 2 and both.count("\n| noise 0.3h + density x3 |") == 1


def test_study_sketches_are_a_separate_check():
    from curvenet.synth import cassie

    if not cassie.available():
        pytest.skip("CASSIE dataset not found")
    names = cassie.study_sketches()[:2]
    rows = bench.run_cassie(["robust"], names, tune=False, dataset="cassie-study")
    assert [r["model"] for r in rows] == names and {r["dataset"] for r in rows} == {"cassie-study"}
    md = bench.write_markdown(rows, None)
    assert "## Check (CASSIE user-study sketches, 2, 2 mm spacing)" in md
    assert "## CASSIE free creations" not in md  # no per-sketch table of the free creations


def test_outlier_table_scores_every_set():
    from curvenet.synth import realdev

    rd = ["bld_zurich_c0961fd6"] if realdev.available() else []
    rows = bench.run_outliers(["crossing"], ["comb"], rd)
    assert [r["group"] for r in rows] == ["synthetic", "kinds", *(["realdev"] if rd else [])]
    assert {r["dataset"] for r in rows} == {"outliers"}
    assert {(r["method"], r["condition"]) for r in rows} == {("robust", bench.OUTLIER_CONDITION)}
    # the same points as the kinds table's run under that condition (its seed), with the outliers
    ref = bench.run_kinds(["robust"], ["comb"], [bench.OUTLIER_CONDITION])[0]
    assert rows[1]["N_d"] == ref["N_d"] and rows[1]["curve_f1"] == ref["curve_f1"]
    n_clean = bench.run_bench(["emst"], ["crossing"], ["clean"])[0]["N_d"]
    assert rows[0]["N_d"] == n_clean + round(0.02 * n_clean)
    md = bench.write_markdown(rows, None)
    assert f"## Outliers ({bench.OUTLIER_CONDITION}, `robust`)" in md
    line = next(x for x in md.splitlines() if x.startswith("| kinds | 1 |"))
    f1 = rows[1]["curve_f1"]
    assert f"{f1:.2f} (comb)" in line
    assert ("0 of 1" if f1 < bench.OUTLIER_TARGET else "1 of 1") in line.split("|")[5]
    # nothing of the outlier runs enters the other tables' means
    assert all(s["dataset"] != "synthetic" or s["condition"] != bench.OUTLIER_CONDITION
               for s in bench.summarize(rows))


def test_surfacing_section_measures_against_the_true_surface():
    """The surfacing rows of the benchmark: the saddle's reconstructed network surfaced as the
    designer's 9 patches with its one border, 0 self-intersections, within the targets; the
    report's table marks a row over a target as missed and counts it."""
    if not bench.surfacing_available():
        pytest.skip("the surface extra is not installed")
    from curvenet.surfacing.evaluation import HAUSDORFF_TARGET, MEAN_TARGET

    rows = bench.run_surfacing(["saddle"], [])
    r = rows[0]
    assert r["model"] == "saddle" and r["patches"] == r["true_patches"] == 9
    assert r["boundary_loops"] == r["true_boundary_loops"] == 1 and r["self_x"] == 0 and r["non_manifold"] == 0
    assert r["distances"][0] <= MEAN_TARGET and r["hausdorff"] <= HAUSDORFF_TARGET and r["target"]
    assert r["hausdorff"] == max(r["distances"][1], r["distances"][3]) and r["time"] > 0 and r["ref"] > 0
    lid = dict(r, model="vase", distances=(0.49, 14.8, 0.13, 0.68), hausdorff=14.8, target=False,
               true_patches=13, patches=14)
    md = "\n".join(bench._surfacing_lines(rows + [lid]))
    assert "| surfaces | vase |" in md and "| 14.80 | **missed** |" in md
    assert f"Known surfaces at both targets: {len(rows)} of {len(rows) + 1} (missed: vase)" in md
    assert bench._surfacing_lines([]) == []


def test_families_are_scored_and_tabled():
    from curvenet.metrics import contract
    from curvenet.synth import families

    rows = bench.run_families(["comb", "facade"], members=2, conditions=["clean"])
    assert [(r["family"], r["model"]) for r in rows] == [("comb", "comb#0"), ("comb", "comb#1"),
                                                         ("facade", "facade#0"), ("facade", "facade#1")]
    assert all(r["dataset"] == "families" and r["method"] == "robust" and r["condition"] == "clean" for r in rows)
    assert rows[3]["true_N_n"] == contract(families.member("facade", 1)).n_nodes
    text = bench.write_markdown(rows)
    section = text[text.index("## Families drawn at random"):]
    f1 = np.mean([r["curve_f1"] for r in rows[2:]])
    assert f"| facade | clean | 2 | {f1:.3f} |" in section
    with pytest.raises(InputError, match="unknown family"):
        bench.run_families(["castle"], members=1)
