"""The README: it opens with the two set-up commands, and its Python API example runs as written."""

import os
import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_readme_opens_with_the_two_commands():
    first = re.search(r"```bash\n(.*?)```", README, re.S).group(1).strip().splitlines()
    assert first == [
        'pip install ".[all]" && curvenet reconstruct examples/mug.xyz -o mug.json --png mug.png',
        'pip install ".[test]" && pytest',
    ]
    assert (ROOT / "examples" / "mug.xyz").is_file()
    ci = (ROOT / ".ci" / "run").read_text()
    assert 'pip install ".[test]" && pytest' in ci


def test_api_example_runs(tmp_path, monkeypatch):
    block = re.search(r"## Python API\n\n```python\n(.*?)```", README, re.S).group(1)
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    ns = {}
    exec(compile(block, "README.md", "exec"), ns)
    net = ns["net"]
    assert net.n_nodes == 10 and net.n_curves == 15  # the mug's true network
    assert (tmp_path / "mug.png").stat().st_size > 10_000
    # the mug's points are noisy: its curves are fitted, and the DXF holds them as splines
    assert net.parameters["fit"] is True
    assert (tmp_path / "mug.dxf").read_text().count("\nSPLINE\n") == 15
    assert len(ns["mesh"].triangles) > 0
    assert (ns["paper"].n_nodes, ns["paper"].n_curves) == (8, 12)  # a meaningful paper example


def test_usage_paper_example_gives_a_network(tmp_path, monkeypatch, capsys):
    """The Usage block's paper example (clean cube points, then --method paper) finds the cube."""
    import json
    import subprocess
    import sys

    from curvenet.cli import main

    block = re.search(r"## Usage\n\n```bash\n(.*?)```", README, re.S).group(1).splitlines()
    make = next(line for line in block if line.startswith("python -c"))
    run = next(line for line in block if "--method paper" in line)
    monkeypatch.chdir(tmp_path)
    code = re.search(r'-c "(.*)"', make).group(1)
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    subprocess.run([sys.executable, "-c", code], check=True, cwd=tmp_path, env=env, timeout=120)
    args = run.split("#")[0].split()
    assert args[0] == "curvenet" and main(args[1:]) == 0
    out = json.loads((tmp_path / "cube.json").read_text())
    assert (len(out["nodes"]), len(out["curves"])) == (8, 12)
