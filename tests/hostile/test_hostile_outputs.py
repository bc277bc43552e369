"""Issue 20 items 2-4: the outputs of a run are all or nothing, under failures and signals."""

import errno
import os
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

from curvenet.cli import main


@pytest.fixture
def ring(tmp_path):
    """A small point file (a circle) that reconstructs in a blink."""
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    f = tmp_path / "ring.xyz"
    np.savetxt(f, np.column_stack([np.cos(t), np.sin(t), 0 * t]))
    return f


def _files(folder):
    return sorted(p.name for p in folder.iterdir())


def _fail_on_call(monkeypatch, n, exc):
    """Make the ``n``-th ``os.fsync`` (of the n-th output file written) raise ``exc``."""
    import curvenet.io.atomic as atomic

    real = os.fsync
    calls = []

    def fsync(fd):
        calls.append(fd)
        if len(calls) == n:
            raise exc
        return real(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    return calls


def test_a_failing_second_output_changes_no_file(ring, tmp_path, monkeypatch, capsys):
    """On main, a.json was replaced, then b.obj failed (disk full)."""
    (tmp_path / "a.json").write_text("old")
    _fail_on_call(monkeypatch, 2, OSError(errno.ENOSPC, "No space left on device"))
    code = main(["reconstruct", str(ring), "-o", str(tmp_path / "a.json"), "-o", str(tmp_path / "b.obj"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "No space left on device" in err and "b.obj" in err
    assert (tmp_path / "a.json").read_text() == "old"
    assert _files(tmp_path) == ["a.json", "ring.xyz"]


def test_a_failing_picture_changes_no_file(ring, tmp_path, monkeypatch, capsys):
    pytest.importorskip("matplotlib")
    import curvenet.plots.network_png as network_png

    def boom(*a, **k):
        raise MemoryError

    monkeypatch.setattr(network_png, "render_png", boom)
    (tmp_path / "a.json").write_text("old")
    code = main(["reconstruct", str(ring), "-o", str(tmp_path / "a.json"), "-o", str(tmp_path / "b.ply"),
                 "--png", str(tmp_path / "p.png"), "-q"])
    assert code == 1 and "out of memory" in capsys.readouterr().err
    assert (tmp_path / "a.json").read_text() == "old"
    assert _files(tmp_path) == ["a.json", "ring.xyz"]


def test_the_same_file_for_network_and_mesh_is_refused(ring, tmp_path, capsys):
    """On main, ``-o m.obj --surface m.obj`` overwrote the network with the mesh (exit 0)."""
    pytest.importorskip("triangle")
    code = main(["reconstruct", str(ring), "-o", str(tmp_path / "m.obj"), "--surface", str(tmp_path / "m.obj")])
    err = capsys.readouterr().err
    assert code == 2 and "given as two outputs" in err and len(err.strip().splitlines()) == 1
    assert _files(tmp_path) == ["ring.xyz"]
    # the same file twice for the same content is fine
    code = main(["reconstruct", str(ring), "-o", str(tmp_path / "m.obj"), "-o", str(tmp_path / "m.obj"), "-q"])
    assert code == 0 and _files(tmp_path) == ["m.obj", "ring.xyz"]


def test_long_names_and_unwritable_folders_fail_before_the_work(ring, tmp_path, monkeypatch, capsys):
    """A legal 245-character name is written (on main its temporary name passed 255 bytes: exit
    1 after the work); a name over the limit, or a folder not writable, is refused before the
    input is even read (the input here is not a point file)."""
    name = "n" * 240 + ".json"
    assert main(["reconstruct", str(ring), "-o", str(tmp_path / name), "-q"]) == 0
    assert _files(tmp_path) == sorted([name, "ring.xyz"])
    bad_input = tmp_path / "bad.xyz"
    bad_input.write_text("not points\n")
    assert main(["reconstruct", str(bad_input), "-o", str(tmp_path / ("n" * 300 + ".json"))]) == 2
    assert "longer than 255 bytes" in capsys.readouterr().err
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, m: False if str(p) == str(tmp_path / "ro") else real(p, m))
    (tmp_path / "ro").mkdir()
    assert main(["reconstruct", str(bad_input), "-o", str(tmp_path / "a.json"), "-o", str(tmp_path / "ro" / "b.json")]) == 2
    assert "ro is not writable" in capsys.readouterr().err
    assert _files(tmp_path / "ro") == [] and not (tmp_path / "a.json").exists()


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_folder_is_refused(ring, tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        (tmp_path / "a.json").write_text("old")
        assert main(["reconstruct", str(ring), "-o", str(tmp_path / "a.json"), "-o", str(ro / "b.json")]) == 2
        assert (tmp_path / "a.json").read_text() == "old" and _files(ro) == []
    finally:
        ro.chmod(0o755)


@pytest.mark.parametrize("sig, code", [("SIGTERM", 143), ("SIGHUP", 129), ("SIGINT", 130)])
@pytest.mark.parametrize("during", [1, 3])
def test_a_signal_while_writing_leaves_nothing(ring, tmp_path, monkeypatch, capsys, sig, code, during):
    """A signal that comes while the first or the third of four outputs is written: exit
    128 + signal and no output, no temporary file (on main, SIGTERM and SIGHUP killed the
    process and left the temporary file)."""
    signum = getattr(signal, sig)
    import curvenet.io.atomic as atomic

    real = os.fsync
    calls = []

    def fsync(fd):
        calls.append(fd)
        if len(calls) == during:
            signal.pthread_kill(threading.main_thread().ident, signum)
        return real(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    (tmp_path / "a.json").write_text("old")
    outs = [tmp_path / n for n in ("a.json", "b.obj", "c.ply", "d.svg")]
    r = main(["reconstruct", str(ring), *[x for o in outs for x in ("-o", str(o))], "-q"])
    assert r == code
    assert (tmp_path / "a.json").read_text() == "old"
    assert _files(tmp_path) == ["a.json", "ring.xyz"]


def _catches(pid: int, signum: int) -> bool:
    """Whether process ``pid`` has a handler for ``signum`` (Linux: SigCgt in /proc; elsewhere
    assume it has, after the caller's wait)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    except OSError:
        return True
    return True


@pytest.mark.parametrize("sig, code", [("SIGTERM", 143), ("SIGHUP", 129)])
def test_a_killed_run_leaves_nothing(tmp_path, sig, code):
    """A real process stopped by ``kill`` (as ``timeout`` does) in the middle of its run."""
    import time

    rng = np.random.default_rng(0)
    th = rng.uniform(0, 2 * np.pi, 300_000)
    centers = rng.integers(0, 300, size=(300_000, 1)) * 3.0
    f = tmp_path / "many.npy"
    np.save(f, np.column_stack([np.cos(th) + centers[:, 0], np.sin(th), np.zeros_like(th)]))
    outs = [tmp_path / n for n in ("a.json", "b.obj")]
    p = subprocess.Popen([sys.executable, "-m", "curvenet.cli", "reconstruct", str(f),
                          *[x for o in outs for x in ("-o", str(o))]],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    signum = getattr(signal, sig)
    deadline = time.monotonic() + 60
    while not _catches(p.pid, signum) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)  # until the CLI handles the signal (a fixed wait fails under load)
    time.sleep(0.5)  # then into the run
    if p.poll() is not None:
        pytest.skip("the run ended before it could be stopped")
    p.send_signal(signum)
    _, err = p.communicate(timeout=120)
    assert p.returncode == code, err
    assert f"stopped by {sig}" in err and "Traceback" not in err
    assert _files(tmp_path) == ["many.npy"]


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP", "SIGINT"])
def test_a_signal_once_the_renames_began_ends_the_run_as_done(ring, tmp_path, monkeypatch, capsys, sig):
    """A signal that comes while the outputs are renamed into place: on main the renames went on
    and the run then reported itself stopped (exit 143 with every output written); now the run
    is over once its renames begin, so it exits 0 and every output is the new one."""
    signum = getattr(signal, sig)
    import curvenet.io.atomic as atomic

    real = os.replace
    calls = []

    def replace(src, dst):
        calls.append(dst)
        if len(calls) == 1:
            signal.pthread_kill(threading.main_thread().ident, signum)
        return real(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    outs = [tmp_path / n for n in ("a.json", "b.obj", "c.ply")]
    outs[0].write_text("old")
    r = main(["reconstruct", str(ring), *[x for o in outs for x in ("-o", str(o))], "-q"])
    assert r == 0 and len(calls) == 3
    assert outs[0].read_text().startswith('{"format":"curvenet"')
    assert _files(tmp_path) == ["a.json", "b.obj", "c.ply", "ring.xyz"]


def test_the_command_leaves_stopping_signals_ignored_as_it_exits(ring, tmp_path):
    """After a run of the ``curvenet`` command (``exiting``), the stopping signals stay ignored
    until the process is gone: on main the default handlers came back, and a SIGTERM while the
    interpreter shut down (over half a second after a 400k-point run with 7 outputs) killed a
    process whose outputs were all written: exit 143. A run inside a program restores them."""
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    try:
        assert main(["info", str(ring)]) == 0
        assert {s: signal.getsignal(s) for s in old} == old
        assert main(["info", str(ring)], exiting=True) == 0
        assert all(signal.getsignal(s) is signal.SIG_IGN for s in old)
    finally:
        for s, h in old.items():
            signal.signal(s, h)


@pytest.mark.parametrize("option, what", [(["--dpi", "100000"], "too large"), (["--dpi", "0"], "must be positive"),
                                          (["--dpi", "-5"], "must be positive"), (["--elev", "nan"], "elev must be"),
                                          (["--azim", "inf"], "azim must be")])
def test_bad_picture_options_fail_before_the_work(tmp_path, capsys, option, what):
    """On main --dpi 100000 ran the reconstruction, then ended in 'out of memory' (exit 1); --dpi 0
    was refused only after the work; --elev nan and --azim inf drew a picture (exit 0, with
    RuntimeWarnings). The input here is not a point file: the option is refused before it is read."""
    bad_input = tmp_path / "bad.xyz"
    bad_input.write_text("not points\n")
    code = main(["reconstruct", str(bad_input), "-o", str(tmp_path / "a.json"), "--png", str(tmp_path / "a.png"),
                 *option])
    err = capsys.readouterr().err
    assert code == 2 and what in err and len(err.strip().splitlines()) == 1, err
    net = tmp_path / "n.json"
    net.write_text("not a network")
    assert main(["render", str(net), "-o", str(tmp_path / "n.png"), *option]) == 2
    assert what in capsys.readouterr().err
    assert _files(tmp_path) == ["bad.xyz", "n.json"]


def test_an_immutable_folder_is_refused_before_the_work_even_for_root(ring, tmp_path, capsys):
    """The read-only folder of the issue, in a form root cannot write either (the immutable
    attribute; test_a_read_only_folder_is_refused is skipped under root, as in CI): refused
    before the input is read, nothing written."""
    import shutil

    ro = tmp_path / "ro"
    ro.mkdir()
    if not shutil.which("chattr") or subprocess.run(["chattr", "+i", str(ro)], capture_output=True).returncode:
        pytest.skip("chattr +i is not available here")
    try:
        bad_input = tmp_path / "bad.xyz"
        bad_input.write_text("not points\n")
        (tmp_path / "a.json").write_text("old")
        assert main(["reconstruct", str(bad_input), "-o", str(tmp_path / "a.json"), "-o", str(ro / "b.json")]) == 2
        assert "ro is not writable" in capsys.readouterr().err
        assert (tmp_path / "a.json").read_text() == "old" and _files(ro) == []
    finally:
        subprocess.run(["chattr", "-i", str(ro)], capture_output=True)


def test_standard_output_gets_nothing_when_another_output_fails(ring, tmp_path, monkeypatch, capsys):
    """``-o - --surface m.obj``: on main the network went to standard output before the surfacing
    failed (the mug at 1e-200: exit 1 with 83 kB of JSON on standard output); now standard output
    is written last."""
    import curvenet.cli.cmd_surface as cmd_surface
    from curvenet import InputError

    def boom(*a, **k):
        raise InputError("no surface")

    monkeypatch.setattr(cmd_surface, "write_surface", boom)
    code = main(["reconstruct", str(ring), "-o", "-", "--surface", str(tmp_path / "m.obj"), "-q"])
    out = capsys.readouterr()
    assert code == 2 and "no surface" in out.err and out.out == ""
    assert _files(tmp_path) == ["ring.xyz"]
