"""How the command line feels: pictures and formats from reconstruct, render and view; the summary
table; --quiet and --verbose; progress bars only on a terminal; exit codes; the documented
commands and API example of docs/usage-pictures.md."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "usage-pictures.md"


def cli(*args, cwd=None, env=None, **kw):
    e = dict(os.environ)
    e.pop("CURVENET_PROGRESS", None)
    e.pop("CURVENET_PROGRESS_DELAY", None)
    e.update(env or {})
    return subprocess.run([sys.executable, "-m", "curvenet.cli", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd, env=e, **kw)


def theta_points(n=60):
    """A 2D theta shape (circle and a diameter): 2 junctions, 3 curves."""
    t = np.linspace(0, 2 * np.pi, 4 * n, endpoint=False)
    circle = np.column_stack([np.cos(t), np.sin(t)])
    x = np.linspace(-1, 1, 2 * n + 2)[1:-1]
    return np.vstack([circle, np.column_stack([x, np.zeros_like(x)])])


@pytest.fixture(scope="module")
def run_all(tmp_path_factory):
    """One reconstruct run (default method, --fit) that writes every format and a PNG (the doc
    test adds the viewer)."""
    d = tmp_path_factory.mktemp("ux")
    np.savetxt(d / "theta.xyz", theta_points())
    outs = ["n.json", "n.obj", "n.ply", "n.dxf", "n.svg", "n.vtp", "n.graphml"]
    args = ["reconstruct", "theta.xyz"] + [a for o in outs for a in ("-o", o)] + ["--png", "n.png", "--dpi", "40", "--fit"]
    r = cli(*args, cwd=d)
    return d, r, outs


def test_reconstruct_writes_every_format_and_pictures(run_all):
    d, r, outs = run_all
    assert r.returncode == 0, r.stderr
    from curvenet.io import read_network

    net = read_network(d / "n.json")
    for o in outs + ["n.png"]:
        assert (d / o).stat().st_size > 0, o
    assert (d / "n.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "<svg" in (d / "n.svg").read_text() and "PolyData" in (d / "n.vtp").read_text()
    # --fit fitted the curves: the DXF has splines through them
    assert net.parameters.get("fit") is True
    dxf = (d / "n.dxf").read_text()
    assert dxf.count("\nSPLINE\n") == net.n_curves and "\nPOLYLINE\n" not in dxf
    assert not [p.name for p in d.iterdir() if p.name.startswith(".")]  # no temporary files left


def test_summary_table_has_the_columns_of_the_papers_table_1(run_all):
    d, r, outs = run_all
    from curvenet.io import read_network

    net = read_network(d / "n.json")
    lines = r.stdout.splitlines()
    assert lines[0].split() == ["Model", "N_n", "N_c", "N_d", "eps", "tau_S", "theta", "Time(s)"]
    row = lines[1].split()
    assert row[:4] == ["theta", str(net.n_nodes), str(net.n_curves), str(len(theta_points()))]
    assert float(row[-1]) >= 0
    assert f"Betti numbers b0={net.betti[0]} b1={net.betti[1]}" in r.stdout
    for o in outs + ["n.png"]:
        assert f"wrote {o}" in lines
    # not a terminal: no progress bar; a line (log style) only for a stage that ran over the
    # delay (1 s): a quick stage prints nothing
    for line in r.stderr.splitlines():
        m = re.fullmatch(r"curvenet: \[\d/\d\] .+: (\d+\.\d\d) s(, .+ left)?", line)
        assert m and float(m.group(1)) >= 0.995, r.stderr


def test_rich_summary_table(run_all):
    import io

    from curvenet.cli.progress import print_summary
    from curvenet.io import read_network

    d, _, _ = run_all
    net = read_network(d / "n.json")
    net.parameters.update(epsilon=2e-7, tau_s=0.02, theta=120.0, spacing_range=[0.0123456, 0.5])
    buf = io.StringIO()
    print_summary(net, "speaker", ["a.json"], file=buf, fancy=True)
    text = buf.getvalue()
    for head in ("Model", "N_n", "N_c", "N_d", "\u03b5", "\u03c4_S", "\u03b8(\u00b0)", "Time(s)"):
        assert head in text
    row = [ln for ln in text.splitlines() if "speaker" in ln][0]
    cells = [c.strip() for c in row.strip("\u2502 ").split("\u2502")]
    assert cells[:7] == ["speaker", str(net.n_nodes), str(net.n_curves), str(net.stats["N_d"]), "2e-07", "0.02", "120"]
    assert "spacing_range=[0.0123, 0.5]" in text and "wrote a.json" in text


def test_plain_text_without_rich(run_all, monkeypatch):
    import io

    from curvenet.cli.progress import Stages, print_summary
    from curvenet.io import read_network

    for mod in [m for m in sys.modules if m == "rich" or m.startswith("rich.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, "rich", None)  # import rich -> ImportError
    monkeypatch.setenv("CURVENET_PROGRESS", "always")
    st = Stages(verbose=True, file=io.StringIO())
    assert not st._bars
    with st.stage("work"):
        pass
    assert st.file.getvalue().startswith("  work: ")
    buf = io.StringIO()
    print_summary(read_network(run_all[0] / "n.json"), "theta", file=buf, fancy=True)
    assert buf.getvalue().split("\n")[0].split() == ["Model", "N_n", "N_c", "N_d", "eps", "tau_S", "theta", "Time(s)"]


def test_quiet_prints_nothing_and_verbose_prints_stages(tmp_path):
    np.savetxt(tmp_path / "t.xyz", theta_points(30))
    r = cli("reconstruct", "t.xyz", "-o", "a.json", "--method", "emst", "-q", cwd=tmp_path)
    assert r.returncode == 0 and r.stdout == "" and r.stderr == ""
    assert (tmp_path / "a.json").exists()
    r = cli("reconstruct", "t.xyz", "-o", "b.json", "--method", "emst", "--verbose", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    params = json.loads((tmp_path / "b.json").read_text())["parameters"]
    for stage in ("reading t.xyz", "reconstructing (emst)", "writing"):
        assert re.search(rf"^  {re.escape(stage)}: \d+\.\d{{3}} s$", r.stderr, re.M), (stage, r.stderr)
    assert "given parameters: none" in r.stderr and "180 points, dimension 2" in r.stderr
    assert "parameters used: " in r.stderr and f"method={params['method']}" in r.stderr
    assert "Model" in r.stdout  # the table still goes to standard output


def test_progress_bars_only_for_slow_stages_on_a_terminal(tmp_path, monkeypatch):
    np.savetxt(tmp_path / "t.xyz", theta_points(20))
    run = ["reconstruct", "t.xyz", "-o", "a.json", "--method", "emst"]
    # stages quicker than the delay draw nothing, even where drawing is forced
    r = cli(*run, cwd=tmp_path, env={"CURVENET_PROGRESS": "always", "CURVENET_PROGRESS_DELAY": "600"})
    assert r.returncode == 0 and r.stderr == ""
    from curvenet.cli.progress import Stages

    monkeypatch.setenv("CURVENET_PROGRESS", "always")
    assert Stages()._bars and not Stages(quiet=True)._bars  # --quiet wins
    monkeypatch.delenv("CURVENET_PROGRESS")
    assert not Stages()._bars  # standard error of pytest is not a terminal

    # a real terminal on standard error: a rich bar once the stage runs longer than the delay
    import pty

    try:
        master, slave = pty.openpty()
    except OSError:
        pytest.skip("no pseudo-terminal on this machine")
    e = {k: v for k, v in os.environ.items() if k != "CURVENET_PROGRESS"}
    e["CURVENET_PROGRESS_DELAY"] = "0"
    p = subprocess.Popen([sys.executable, "-m", "curvenet.cli", *run], cwd=tmp_path,
                         stdout=subprocess.PIPE, stderr=slave, env=e)
    os.close(slave)
    chunks = []
    while True:
        try:
            b = os.read(master, 4096)
        except OSError:
            break
        if not b:
            break
        chunks.append(b)
    out, _ = p.communicate(timeout=120)
    os.close(master)
    err = b"".join(chunks).decode("utf-8", "replace")
    assert p.returncode == 0 and "reconstructing" in err and "\x1b[" in err
    assert b"Model" in out  # the table on standard output, which is not a terminal: plain text


def test_view_in_process(run_all, tmp_path, capsys):
    from curvenet.cli import main

    d, _, _ = run_all
    args = ["view", str(d / "n.json"), "-o", str(tmp_path / "v.html"), "--points", str(d / "theta.xyz")]
    assert main(args + ["--max-points", "50", "-q"]) == 0
    assert capsys.readouterr().out == ""
    html = (tmp_path / "v.html").read_text()
    assert "Plotly.newPlot" in html and "50 shown" in html
    assert main(args + ["--max-points", "-1"]) == 2


def test_render_options_in_process(tmp_path, capsys):
    from curvenet import Curve, CurveNetwork
    from curvenet.cli import main
    from curvenet.io import write_network

    t = np.linspace(0, 1, 20)[:, None]
    net = CurveNetwork(np.array([[0.0, 0, 0], [1, 1, 1]]), [Curve(t * [1, 1, 1], 0, 1)])
    write_network(net, tmp_path / "n.json")
    np.savetxt(tmp_path / "p.xyz", t * [1, 1, 1] + 0.05)
    runs = {"plain": [], "angles": ["--elev", "70", "--azim", "10"], "points": ["--points", str(tmp_path / "p.xyz")]}
    out = {}
    for name, extra in runs.items():
        assert main(["render", str(tmp_path / "n.json"), "-o", str(tmp_path / f"{name}.png"), "--dpi", "30", "-q", *extra]) == 0
        out[name] = (tmp_path / f"{name}.png").read_bytes()
    assert len(set(out.values())) == 3
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize(
    "args, message",
    [
        (["render", "{net}", "-o", "x.jpg"], "must have the extension .png"),
        (["view", "{net}", "-o", "x.png"], "must have the extension .html"),
        (["reconstruct", "{pts}", "--png", "x.svg"], "must have the extension .png"),
        (["reconstruct", "{pts}", "-o", "x.xyz"], "unknown output extension"),
        (["render", "missing.json", "-o", "x.png"], "missing.json"),
        (["render", "{pts}", "-o", "x.png"], "not a valid JSON"),
        (["render", "{net}", "-o", "x.png", "--points", "{pts3}"], "dimension 3 but the network has dimension 2"),
        (["view", "{net}", "-o", "{net}"], "extension .html"),
        (["render", "{net}", "-o", "nofolder/x.png"], "does not exist"),
        (["view", "{net}"], "required"),
    ],
)
def test_bad_usage_and_input_exit_2(run_all, tmp_path, monkeypatch, capsys, args, message):
    """In process (the subprocess path is the same main(); one case runs through it below)."""
    from curvenet.cli import main

    d, _, _ = run_all
    np.savetxt(tmp_path / "p3.xyz", np.random.default_rng(0).random((10, 3)))
    subst = {"{net}": str(d / "n.json"), "{pts}": str(d / "theta.xyz"), "{pts3}": str(tmp_path / "p3.xyz")}
    monkeypatch.chdir(tmp_path)
    try:
        code = main([subst.get(a, a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    assert message in err and "Traceback" not in err
    assert not list(tmp_path.glob("x.*"))


def test_bad_picture_extension_through_subprocess(run_all, tmp_path):
    d, _, _ = run_all
    r = cli("render", d / "n.json", "-o", tmp_path / "x.jpg")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == f"curvenet: error: {tmp_path / 'x.jpg'}: the picture must have the extension .png\n"


def test_method_failure_exit_1_and_verbose_traceback(tmp_path, monkeypatch, capsys):
    import curvenet.cli as c

    rec = sys.modules["curvenet.reconstruct"]

    (tmp_path / "failing_method_mod.py").write_text(
        "from curvenet.errors import MethodError\n"
        "def failing(points):\n    raise MethodError('no curve found')\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(rec.METHODS, "failing", ("failing_method_mod", "failing"))
    np.savetxt(tmp_path / "t.xyz", theta_points(10))
    args = ["reconstruct", str(tmp_path / "t.xyz"), "-o", str(tmp_path / "o.json"), "--method", "failing"]
    assert c.main(args) == 1
    err = capsys.readouterr().err
    assert err.strip() == "curvenet: error: no curve found"
    assert c.main(args + ["--verbose"]) == 1
    err = capsys.readouterr().err
    assert "Traceback" in err and err.strip().endswith("curvenet: error: no curve found")
    assert not (tmp_path / "o.json").exists()


def test_formats_lists_new_writers_and_pictures():
    r = cli("formats")
    assert r.returncode == 0
    for ext in (".dxf", ".svg", ".vtp", ".graphml", ".png", ".html"):
        assert re.search(rf"^  {re.escape(ext)} ", r.stdout, re.M), ext


def test_help_lists_render_and_view():
    r = cli("--help")
    assert "render" in r.stdout and "view" in r.stdout
    for cmd in ("render", "view"):
        h = cli(cmd, "--help")
        assert h.returncode == 0 and "--points" in h.stdout and "--quiet" in h.stdout


# ----------------------------------------------------------------------------- the documentation
def doc_blocks(lang):
    text = DOC.read_text()
    return re.findall(rf"```{lang}\n(.*?)```", text, re.S)


def test_documented_commands_produce_every_format(tmp_path):
    """Run the shell commands of docs/usage-pictures.md from a copy of the repository root."""
    cmds = [ln.strip() for block in doc_blocks("bash") for ln in block.splitlines()
            if ln.strip().startswith("curvenet ")]
    assert cmds, "no curvenet commands in the doc"
    examples = {m for c in cmds for m in re.findall(r"examples/\S+\.xyz", c)}
    for ex in examples:
        if not (ROOT / ex).exists():
            pytest.skip(f"{ex} is not shipped yet")
        (tmp_path / ex).parent.mkdir(exist_ok=True)
        (tmp_path / ex).write_bytes((ROOT / ex).read_bytes())
    (tmp_path / "docs" / "img").mkdir(parents=True)
    outputs = []
    for c in cmds:
        args = c.split()[1:]
        r = cli(*args, cwd=tmp_path)
        assert r.returncode == 0, (c, r.stderr)
        outputs += [args[i + 1] for i, a in enumerate(args) if a in ("-o", "--png", "--html")]
    exts = {Path(o).suffix for o in outputs}
    from curvenet.io import WRITERS

    assert set(WRITERS) | {".png", ".html"} <= exts  # every format is documented and produced
    for o in outputs:
        assert (tmp_path / o).stat().st_size > 0, o
    assert "Plotly.newPlot" in (tmp_path / "mug.html").read_text()
    from curvenet.io import read_network

    net = read_network(tmp_path / "mug.json")
    assert net.n_curves > 0 and net.n_nodes > 0


def test_documented_python_example_runs(tmp_path, monkeypatch):
    blocks = doc_blocks("python")
    assert blocks
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        exec(compile(code, str(DOC), "exec"), {"__name__": "__doc_example__"})
    png, dxf = tmp_path / "helix.png", tmp_path / "helix.dxf"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ezdxf = pytest.importorskip("ezdxf")
    assert len(ezdxf.readfile(dxf).modelspace().query("POLYLINE SPLINE")) >= 1
