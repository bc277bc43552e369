"""Issue 21, progress on long runs: the method's stages by name with their share of the work, the
point count, the time left where it can be known, one line per stage off a terminal, and the
one-time numba compile announced."""

import io
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import curvenet
from curvenet.cli import progress
from curvenet.cli.progress import COMPILE_NOTE, Stages, eta_seconds, format_eta
from curvenet.methods.stages import PAPER_SHARES, ROBUST_SHARES

ROBUST_STAGES = ["neighbors", "graph", "nodes", "tracing", "assemble"]


def tee_points(n=40):
    """Three straight arms meeting at the origin, ``n`` points each, and the junction."""
    t = (np.arange(n) + 0.5) / n
    return np.vstack([np.c_[t, 0 * t], np.c_[-t, 0 * t], np.c_[0 * t, t], [[0.0, 0.0]]])


def cli(*args, cwd, env=None):
    e = {k: v for k, v in os.environ.items() if not k.startswith("CURVENET_PROGRESS")}
    e.update(env or {})
    return subprocess.run([sys.executable, "-m", "curvenet", *args], cwd=cwd, env=e, capture_output=True,
                          text=True, timeout=600)


@pytest.mark.parametrize("shares", [ROBUST_SHARES, PAPER_SHARES], ids=["robust", "paper"])
def test_stage_shares_are_fractions_that_add_up_to_one(shares):
    assert all(0 <= v < 1 for v in shares.values())
    assert sum(shares.values()) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("method, shares", [("robust", ROBUST_SHARES), ("paper", PAPER_SHARES)])
def test_methods_report_their_stages_in_order(method, shares):
    seen = []
    net = curvenet.reconstruct(tee_points(), method=method, on_stage=lambda name, share: seen.append((name, share)))
    names = [n for n, _ in seen]
    assert names == [k for k in net.stats["time"] if k != "total"]  # the timed stages, in order
    assert seen == [(n, shares[n]) for n in names]
    assert net == curvenet.reconstruct(tee_points(), method=method)  # the callback changes nothing


def test_fit_is_reported_and_emst_calls_nothing():
    seen = []
    curvenet.reconstruct(tee_points(), fit=True, on_stage=lambda n, s: seen.append(n))
    assert seen == ROBUST_STAGES + ["fit"]
    seen.clear()
    curvenet.reconstruct(tee_points(), method="emst", on_stage=lambda n, s: seen.append(n))
    assert seen == []
    with pytest.raises(curvenet.InputError, match="its parameters: spacing") as err:
        curvenet.reconstruct(tee_points(), shell=2)
    assert "on_stage" not in str(err.value)  # reconstruct's own keyword, not the method's


def test_eta_logic_and_format():
    assert eta_seconds(3.0, 0.25) == pytest.approx(9.0)
    assert eta_seconds(10.0, 0.5) == pytest.approx(10.0)
    assert eta_seconds(3.0, 0.0) is None and eta_seconds(3.0, 1.0) == 0.0 and eta_seconds(3.0, 1.2) == 0.0
    assert format_eta(None) == ""
    assert format_eta(0.4) == "under 1 s left"
    assert format_eta(42.4) == "about 42 s left"
    assert format_eta(95) == "about 2 min left"
    assert format_eta(59 * 60) == "about 59 min left"
    assert format_eta(2 * 3600 + 5 * 60 + 10) == "about 2 h 5 min left"


def test_parts_give_the_time_left_from_their_shares(monkeypatch):
    now = [0.0]  # a clock the test moves

    def fake():
        return now[0]

    monkeypatch.setattr(progress.time, "perf_counter", fake)
    monkeypatch.setenv("CURVENET_PROGRESS", "log")
    st = Stages(file=io.StringIO(), stages=1)
    with st.stage("work", detail="10 points") as h:
        assert h.eta() is None  # nothing ended: the pace is unknown
        h.method_stage("a", 0.25)
        now[0] = 2.0
        h.method_stage("b", 0.75)  # a took 2 s for 25%: 6 s left
        assert h.parts == [("a", 0.25, 2.0)]
        assert h.eta() == pytest.approx(6.0)
        now[0] = 6.0
    lines = st.file.getvalue().splitlines()
    assert lines[0] == "curvenet: [1/1] work \u00b7 10 points \u00b7 a (25% of the work): 2.00 s, about 6 s left"
    assert lines[1] == "curvenet: [1/1] work \u00b7 10 points \u00b7 b (75% of the work): 4.00 s"
    assert lines[2].startswith("curvenet: [1/1] work \u00b7 10 points: ") and len(lines) == 3


def test_a_compiling_stage_is_announced_once_and_estimates_no_time_left(monkeypatch):
    monkeypatch.setenv("CURVENET_PROGRESS", "log")
    st = Stages(file=io.StringIO(), stages=2)
    with st.stage("reconstructing (robust)", detail="5,000 points", compiling=True) as h:
        h.method_stage("neighbors", 0.5)
        h.method_stage("graph", 0.5)
        assert h.eta() is None
    with st.stage("writing"):
        pass
    text = st.file.getvalue()
    assert text.count(COMPILE_NOTE) == 1 and " left" not in text
    assert text.splitlines()[0] == f"curvenet: [1/2] reconstructing (robust) \u00b7 5,000 points: {COMPILE_NOTE}"
    quiet = Stages(quiet=True, file=io.StringIO())
    with quiet.stage("x", compiling=True) as h:
        h.method_stage("a", 1.0)
    assert quiet.file.getvalue() == ""


def test_off_a_terminal_one_line_per_stage_in_order_with_the_point_count(tmp_path):
    """A subprocess whose standard error is a pipe (not a terminal), default progress mode: a
    line for each stage that ran over the delay (0 here: every stage)."""
    np.savetxt(tmp_path / "t.xyz", tee_points())
    r = cli("reconstruct", "t.xyz", "-o", "a.json", cwd=tmp_path, env={"CURVENET_PROGRESS_DELAY": "0"})
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    head = r"curvenet: \[2/3\] reconstructing \(robust\) \u00b7 121 points"
    expected = ([r"curvenet: \[1/3\] reading t\.xyz: \d+\.\d\d s"]
                + [rf"{head} \u00b7 {name} \(\d+% of the work\): \d+\.\d\d s(, (about \d+ s|under 1 s) left)?"
                   for name in ROBUST_STAGES]
                + [rf"{head}: \d+\.\d\d s", r"curvenet: \[3/3\] writing \u00b7 1 file\(s\): \d+\.\d\d s"])
    assert len(lines) == len(expected), r.stderr
    for line, pattern in zip(lines, expected):
        assert re.fullmatch(pattern, line), (line, pattern)
    assert "Model" in r.stdout and "Model" not in r.stderr


def test_compile_pending_is_false_where_nothing_compiles():
    from curvenet.methods.robust.kernels.registry import NUMBA_MIN_POINTS

    from curvenet.reconstruct import compile_pending

    assert compile_pending(NUMBA_MIN_POINTS - 1) is False  # plain-Python kernels
    assert compile_pending(10**6, method="paper") is False and compile_pending(10**6, method="emst") is False


@pytest.mark.slow
def test_the_one_time_compile_is_announced_once(tmp_path):
    """With an empty numba cache (NUMBA_CACHE_DIR) the first run on enough points announces the
    compile, once; the second run loads the kernels and says nothing of it. (About a minute:
    the compile itself.)"""
    pytest.importorskip("numba")
    from curvenet.methods.robust.kernels.registry import NUMBA_MIN_POINTS

    cache = tmp_path / "numba-cache"
    cache.mkdir()
    rng = np.random.default_rng(0)
    pts = tee_points(NUMBA_MIN_POINTS // 3 + 10) + rng.normal(0, 1e-4, (3 * (NUMBA_MIN_POINTS // 3 + 10) + 1, 2))
    np.savetxt(tmp_path / "t.xyz", pts)
    env = {"NUMBA_CACHE_DIR": str(cache), "CURVENET_PROGRESS": "log"}
    if os.environ.get("CURVENET_NO_NUMBA", "") in ("1", "true", "yes"):
        pytest.skip("numba switched off (CURVENET_NO_NUMBA): nothing compiles")
    first = cli("reconstruct", "t.xyz", "-o", "a.json", cwd=tmp_path, env=env)
    assert first.returncode == 0, first.stderr
    assert first.stderr.count(COMPILE_NOTE) == 1, first.stderr
    assert re.search(rf"^curvenet: \[2/3\] reconstructing \(robust\) \u00b7 [\d,]+ points: {re.escape(COMPILE_NOTE)}$",
                     first.stderr, re.M), first.stderr
    assert any(cache.rglob("*.nbi"))  # the kernels went to the given cache
    second = cli("reconstruct", "t.xyz", "-o", "b.json", cwd=tmp_path, env=env)
    assert second.returncode == 0, second.stderr
    assert COMPILE_NOTE not in second.stderr and "reconstructing (robust)" in second.stderr
    assert curvenet.load(tmp_path / "a.json") == curvenet.load(tmp_path / "b.json")  # compiled = loaded



def test_the_paper_method_help_example_gives_a_meaningful_network(tmp_path):
    """The ``--method paper`` example of ``curvenet reconstruct --help``, run as written from a
    copy of the shipped examples, finds the clean cube's 8 corners and 12 edges (it was the
    noisy mug: 1 node, 0 curves)."""
    import shlex
    import shutil

    from curvenet.cli.examples import EXAMPLES

    root = Path(__file__).resolve().parents[1]
    shutil.copytree(root / "examples", tmp_path / "examples")
    [args] = [shlex.split(c) for c in EXAMPLES["reconstruct"] if "--method paper" in c]
    r = cli(*args[1:], cwd=tmp_path)
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    net = curvenet.load(tmp_path / args[args.index("-o") + 1])
    assert (net.n_nodes, net.n_curves, net.betti) == (8, 12, (1, 5))
