"""The first run's compile shared out over processes (curvenet.methods.robust.warmup): the shares
cover every kernel once and balance the compile, the warm-up clouds call every kernel, a child
process fills numba's cache with exactly its share, and a first run starts with it."""

import os
import subprocess
import sys

import numpy as np
import pytest

import curvenet
from curvenet import synth
from curvenet.methods.robust import warmup
from curvenet.methods.robust.kernels import registry as KR

NUMBA = pytest.mark.skipif(not KR.HAVE_NUMBA or os.environ.get("CURVENET_NO_NUMBA", "") in ("1", "true", "yes"),
                           reason="numba not installed or switched off: nothing compiles")


def _weight(share):
    return sum(warmup.COMPILE_SECONDS.get(k, warmup.DEFAULT_SECONDS) for k in share)


@pytest.mark.parametrize("parts", [1, 2, 3, 4, 100])
def test_shares_cover_every_kernel_once_and_balance_the_compile(parts):
    out = warmup.shares(parts)
    flat = [k for s in out for k in s]
    assert sorted(flat) == sorted(KR.KERNELS)  # every kernel, none twice
    assert 1 <= len(out) <= min(parts, len(KR.KERNELS)) and all(out)
    w = [_weight(s) for s in out]
    assert w == sorted(w, reverse=True)  # the heaviest first (compiled by the calling process)
    # greedy balance: no share exceeds the mean by more than the heaviest kernel
    assert max(w) <= sum(w) / len(w) + max(warmup.COMPILE_SECONDS.values()) + 1e-9


def test_two_shares_are_about_equal_and_the_weights_name_real_kernels():
    assert set(warmup.COMPILE_SECONDS) <= set(KR.KERNELS)  # no stale names
    a, b = (_weight(s) for s in warmup.shares(2))
    assert a / b < 1.1, (a, b)
    assert warmup.shares(3, ["tangents", "spacing"]) == [("tangents",), ("spacing",)]


def test_warm_clouds_call_every_kernel(monkeypatch):
    """Run the warm-up with every kernel asked for, recording the names the method dispatches
    (their plain versions run: same results, nothing compiles)."""
    called = set()

    def record(name):
        called.add(name)
        return KR.KERNELS[name].plain

    monkeypatch.setattr(KR, "_kernel", record)
    monkeypatch.setattr(KR, "HAVE_NUMBA", True)  # (compiled_only then names them, numba or not)
    warmup.warm(KR.KERNELS)
    assert called == set(KR.KERNELS), sorted(set(KR.KERNELS) - called)


def test_warm_clouds_are_small_and_deterministic():
    a, b = warmup.warm_clouds(), warmup.warm_clouds()
    assert len(a) == 2 and all(P.shape[1] == 3 and 100 < len(P) < 1000 for P in a)
    assert all(np.array_equal(p, q) for p, q in zip(a, b))


def test_compiled_only_picks_exactly_the_named_kernels():
    with KR.compiled_only(["tangents"]):
        with KR.compiled_for(10**7):  # the size rule does not override it
            assert KR._kernel("spacing") is KR.KERNELS["spacing"].plain
            assert KR._kernel("tangents") is (KR.KERNELS["tangents"].compiled if KR.HAVE_NUMBA
                                              else KR.KERNELS["tangents"].plain)
            assert KR.compiled_active() is KR.HAVE_NUMBA
    with KR.compiled_only([]):
        assert KR.compiled_active() is False and KR._kernel("tangents") is KR.KERNELS["tangents"].plain
    assert KR._ONLY.get() is None  # left as found


def test_an_unknown_kernel_name_is_refused(capsys):
    assert warmup.main(["tangents", "no_such_kernel"]) == 2
    assert "no_such_kernel" in capsys.readouterr().err


def test_the_first_run_starts_with_the_shared_compile(monkeypatch):
    calls = []
    monkeypatch.setattr(warmup, "precompile", lambda processes=None, names=None: calls.append(names))
    R = sys.modules["curvenet.reconstruct"]  # (the module: the package's name is the function)

    pts = synth.sample(synth.model("cube"), rng=0)[0]
    monkeypatch.setattr(R, "compile_pending", lambda n, method="auto": False)
    curvenet.reconstruct(pts)
    assert calls == []
    monkeypatch.setattr(R, "compile_pending", lambda n, method="auto": True)
    curvenet.reconstruct(pts)
    assert calls == [warmup.COMMON]  # (the kernels of noisy input wait for their first use)
    calls.clear()
    curvenet.reconstruct(pts, method="emst")  # another method: no compile of the robust kernels
    assert calls == []


def test_the_groups_split_the_kernels():
    assert set(warmup.COMMON) | set(warmup.NOISY_ONLY) == set(KR.KERNELS)
    assert not set(warmup.COMMON) & set(warmup.NOISY_ONLY)
    assert set(KR.COMPILE_MARKERS) <= set(warmup.COMMON)


def test_a_noise_free_run_calls_no_kernel_of_noisy_input(monkeypatch):
    # (else a noise-free first run would wait for their compile)
    called = set()
    kernel = KR._kernel
    monkeypatch.setattr(KR, "_kernel", lambda name: called.add(name) or kernel(name))
    clean, noisy = warmup.warm_clouds()
    with KR.compiled_only([]):  # (plain kernels: nothing compiles)
        curvenet.reconstruct(clean)
    assert called and not called & set(warmup.NOISY_ONLY), sorted(called & set(warmup.NOISY_ONLY))
    with KR.compiled_only([]):
        curvenet.reconstruct(noisy)
    assert set(warmup.NOISY_ONLY) <= called


def test_the_kernels_of_noisy_input_compile_together_on_first_use(monkeypatch):
    calls = []
    monkeypatch.setattr(warmup, "precompile", lambda processes=None, names=None: calls.append(names))
    cached = {"now": False}
    monkeypatch.setattr(KR, "_in_cache", lambda names: cached["now"])
    warmup.on_first_use("tangents")  # a kernel every run calls: compiled before the run
    assert calls == []
    warmup.on_first_use("strand_cuts")
    assert calls == [warmup.NOISY_ONLY]
    cached["now"] = True
    warmup.on_first_use("noisy_tangents")  # in the cache now: loaded, nothing compiled
    assert calls == [warmup.NOISY_ONLY]


def test_the_first_use_hook_runs_before_a_kernel_s_first_compiled_call(monkeypatch):
    # a stand-in for a compiled kernel that has not run yet in this process (no signatures)
    def fake(*args):
        return "ran"

    fake.signatures = []
    k = KR.KERNELS["end_count"]
    monkeypatch.setattr(KR, "KERNELS", {**KR.KERNELS, "end_count": KR.Kernel(k.plain, fake, ())})
    monkeypatch.setattr(KR, "compiled_active", lambda: True)
    monkeypatch.setattr(KR, "HAVE_NUMBA", True)
    seen = []
    with KR.first_use_hook(seen.append):
        assert KR._run("end_count", ()) == "ran"
        assert seen == ["end_count"]
        with KR.compiled_only(["end_count"]):  # the warm-up's own runs: no hook
            KR._run("end_count", ())
        assert seen == ["end_count"]
        fake.signatures = ["loaded"]  # it ran once: no hook any more
        KR._run("end_count", ())
        assert seen == ["end_count"]
    fake.signatures = []
    KR._run("end_count", ())  # outside the block: no hook
    assert seen == ["end_count"]


def _cached(cache, names):
    code = (f"from curvenet.methods.robust.kernels import registry as KR; "
            f"print([KR._in_cache([n]) for n in {list(names)!r}])")
    out = subprocess.run([sys.executable, "-c", code], env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return eval(out.stdout.strip())


@NUMBA
def test_a_child_compiles_exactly_its_share_into_the_cache(tmp_path):
    cache = tmp_path / "numba-cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    run = subprocess.run([sys.executable, "-m", "curvenet.methods.robust.warmup", "end_count", "csr_union"],
                         env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert _cached(cache, ["end_count", "csr_union", "tangents"]) == [True, True, False]


@NUMBA
def test_precompile_runs_the_shares_in_parallel_processes(tmp_path):
    """Two tiny shares: one compiled by the calling process, one by a child; both end in the
    cache the environment names."""
    cache = tmp_path / "numba-cache"
    code = ("from curvenet.methods.robust import warmup as W; "
            "W.shares = lambda n, names=None: [('end_count',), ('csr_union',)][:n]; "
            "W.precompile(processes=2)")
    run = subprocess.run([sys.executable, "-c", code], env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert _cached(cache, ["end_count", "csr_union", "components"]) == [True, True, False]


def test_an_interrupted_precompile_kills_its_children(monkeypatch):
    # Ctrl-C during this process's own share: every child is killed, none waited for first
    class Child:
        made = []

        def __init__(self, *a, **k):
            self.killed = False
            Child.made.append(self)

        def kill(self):
            self.killed = True

        def wait(self):
            assert self.killed, "waited for a child that was not killed"

    def interrupted(names):
        raise KeyboardInterrupt

    monkeypatch.setattr(KR, "HAVE_NUMBA", True)
    monkeypatch.setattr(warmup.subprocess, "Popen", Child)
    monkeypatch.setattr(warmup, "warm", interrupted)
    with pytest.raises(KeyboardInterrupt):
        warmup.precompile(processes=3)
    assert len(Child.made) == 2 and all(c.killed for c in Child.made)
