"""docs/troubleshooting.md: its commands run, and every option it recommends exists."""

import re
import shutil
from pathlib import Path

import pytest

from curvenet.cli import main

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "troubleshooting.md"


def test_recommended_options_exist(capsys):
    text = DOC.read_text()
    options = set(re.findall(r"`(--[a-z][a-z-]*)", text))
    assert {"--shell-inner", "--min-spur", "--link-width", "--spacing", "--tau-s", "--fit"} <= options
    helps = ""
    for cmd in ("reconstruct", "render", "view"):
        with pytest.raises(SystemExit):
            main([cmd, "--help"])
        helps += capsys.readouterr().out
    for opt in options:
        assert re.search(rf"{re.escape(opt)}\b", helps), f"{opt} is recommended but no command has it"


def test_inspection_commands_run(tmp_path, monkeypatch, capsys):
    pytest.importorskip("matplotlib")
    pytest.importorskip("plotly")
    block = re.search(r"```bash\n(.*?)```", DOC.read_text(), re.S).group(1)
    shutil.copy(ROOT / "examples" / "mug.xyz", tmp_path / "scan.xyz")
    monkeypatch.chdir(tmp_path)
    for line in block.splitlines():
        args = line.split("#")[0].split()
        assert args[0] == "curvenet"
        assert main(args[1:]) == 0, line
    out = capsys.readouterr().out
    assert "Betti numbers" in out and (tmp_path / "labels.csv").exists() and (tmp_path / "side.png").exists()
