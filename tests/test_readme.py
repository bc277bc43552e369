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
    assert (tmp_path / "mug.dxf").read_text().count("POLYLINE") >= 15
    assert len(ns["mesh"].triangles) > 0
