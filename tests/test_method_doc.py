"""docs/method.md: its tables match the code, its pictures exist, and the script that makes them runs.

The tables are read back from the markdown and compared value by value with
:mod:`curvenet.methods.robust.thresholds` (not only with the script's own output), so a stale
table fails here. The figure script runs on its small clean example into ``tmp_path`` (a few
seconds) and its PNGs are read back with matplotlib.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from curvenet.methods.robust import thresholds
from curvenet.methods.robust.params import RobustParams
from curvenet.methods.robust.repairs import ORDER

from bench_scripts import load

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "method_figures.py"
DOC = ROOT / "docs" / "method.md"
#: Each picture stays small enough for the repository.
MAX_PNG_BYTES = 150_000

pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="benchmarks/method_figures.py not in this checkout")


def _load():
    return load("method_figures")


def _groups() -> dict[str, tuple]:
    """Every threshold group of thresholds.py: instance name -> instance."""
    return {n: getattr(thresholds, n) for n in thresholds.__all__
            if isinstance(getattr(thresholds, n), tuple) and hasattr(getattr(thresholds, n), "_fields")}


def _block(doc: str, name: str) -> str:
    m = re.search(rf"<!-- BEGIN {name} -->\n(.*?)<!-- END {name} -->", doc, re.S)
    assert m, f"docs/method.md has no table {name}"
    return m.group(1)


def _group_table(doc: str, name: str) -> str:
    """The table under the caption of threshold group ``name`` (e.g. "SPACING")."""
    m = re.search(rf"^\*`thresholds\.{name}`:.*?\n\n((?:\|.*\n)+)", doc, re.M)
    assert m, f"docs/method.md has no table of thresholds.{name}"
    return m.group(1)


def _rows(block: str) -> dict[str, list[str]]:
    """First column (without backquotes) -> the other cells, for every table row but the header."""
    out = {}
    for line in block.splitlines():
        if line.startswith("| `"):
            cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]
            out[cells[0].strip("`")] = cells[1:]
    return out


def test_every_threshold_is_in_the_doc_with_its_value():
    doc = DOC.read_text()
    groups = _groups()
    assert len(groups) >= 13
    for name, group in groups.items():
        rows = _rows(_group_table(doc, name))
        assert list(rows) == list(group._fields), name
        for field, value in zip(group._fields, group):
            if isinstance(value, tuple):  # shown as "(a, b, ...)"
                shown = tuple(float(x) for x in rows[field][0].strip("()").split(", "))
                assert shown == pytest.approx(tuple(float(x) for x in value), rel=1e-5), f"{name}.{field}"
            else:
                shown = float(rows[field][0].replace(",", ""))
                assert shown == pytest.approx(float(value), rel=1e-5), f"{name}.{field}: doc {shown}, code {value}"
            assert rows[field][1], f"{name}.{field} has no meaning in the doc"


def test_the_meanings_are_the_field_comments():
    doc = DOC.read_text()
    src = (Path(thresholds.__file__)).read_text()
    # every "#:" comment line of thresholds.py appears, reST quotes made markdown, in its table row
    rows = {}
    for name in _groups():
        rows.update({(name, f): cells for f, cells in _rows(_group_table(doc, name)).items()})
    comments = re.findall(r"#: (.*)\n(?:\s*#: .*\n)*\s*(\w+): ", src)
    assert len(comments) > 80
    by_field = {}
    for first_line, field in comments:
        by_field.setdefault(field, []).append(first_line.replace("``", "`").strip())
    for (group, field), cells in rows.items():
        if field in by_field:
            assert any(c[:40] in cells[1] for c in by_field[field]), (group, field)


def test_the_keyword_and_repair_tables_match_the_code():
    doc = DOC.read_text()
    params = _rows(_block(doc, "PARAMS"))
    fields = dataclasses.fields(RobustParams)
    assert list(params) == [f.name for f in fields]
    for f in fields:
        if f.default is None:
            assert params[f.name][0] == "estimated"
        elif isinstance(f.default, bool):
            assert params[f.name][0] == str(f.default)
        else:
            assert float(params[f.name][0]) == f.default
    order = re.findall(r"^\| (\d+) \| `(\w+)` \|", _block(doc, "ORDER"), re.M)
    assert [(int(i), n) for i, n in order] == [(i, fn.__name__) for i, fn in enumerate(ORDER, 1)]


def test_the_doc_equals_what_the_script_writes():
    mf = _load()
    doc = DOC.read_text()
    assert mf.fill(doc) == doc
    assert mf.main(["--check", "--doc", str(DOC)]) == 0


def test_a_changed_threshold_makes_the_doc_stale(monkeypatch, tmp_path, capsys):
    mf = _load()
    monkeypatch.setattr(thresholds, "SPACING", thresholds.SPACING._replace(dedup=0.25))
    assert mf.main(["--check", "--doc", str(DOC)]) == 1
    assert "differ" in capsys.readouterr().out
    # and regenerating writes the new value
    doc = tmp_path / "method.md"
    doc.write_text(DOC.read_text())
    assert mf.main(["--check", "--doc", str(doc)]) == 1
    doc.write_text(mf.fill(doc.read_text()))
    assert _rows(_group_table(doc.read_text(), "SPACING"))["dedup"][0] == "0.25"


def test_a_new_threshold_group_needs_a_section(monkeypatch, capsys):
    mf = _load()
    extra = thresholds.SPLIT._replace()
    monkeypatch.setattr(thresholds, "EXTRA", extra, raising=False)
    monkeypatch.setattr(thresholds, "__all__", [*thresholds.__all__, "EXTRA"])
    assert "EXTRA" in mf.threshold_groups()
    assert mf.main(["--check", "--doc", str(DOC)]) == 2
    assert "without a section" in capsys.readouterr().err


def test_a_doc_without_markers_is_a_clear_error(tmp_path, capsys):
    mf = _load()
    doc = tmp_path / "method.md"
    doc.write_text("# no tables here\n")
    assert mf.main(["--check", "--doc", str(doc)]) == 2
    assert "markers missing" in capsys.readouterr().err
    assert doc.read_text() == "# no tables here\n"


def test_every_picture_referenced_exists_and_is_small():
    doc = DOC.read_text()
    refs = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", doc)
    mf = _load()
    assert sorted(Path(r).name for r in refs) == sorted(mf.FIGURES)  # one per stage, each referenced
    for r in refs:
        p = DOC.parent / r
        assert p.is_file(), r
        assert 10_000 < p.stat().st_size < MAX_PNG_BYTES, r


def test_the_script_runs_on_the_small_example(tmp_path):
    mpimg = pytest.importorskip("matplotlib.image")
    mf = _load()
    doc = tmp_path / "method.md"
    doc.write_text(DOC.read_text())
    assert mf.main(["--tiny", "--out", str(tmp_path / "img"), "--doc", str(doc)]) == 0
    assert doc.read_text() == DOC.read_text()  # the tables were up to date: left as they were
    for name in mf.FIGURES:
        p = tmp_path / "img" / name
        assert p.stat().st_size < MAX_PNG_BYTES, name
        img = mpimg.imread(p)
        assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 600, name
        assert float(img[..., :3].std()) > 0.05, f"{name} is blank"


def test_the_stage_run_is_the_pipeline_and_shows_what_the_doc_says():
    from curvenet.methods.robust.pipeline import reconstruct_robust

    mf = _load()
    runs = {ex.name: mf.run_stages(ex) for ex in mf.examples()}
    for name, run in runs.items():
        assert mf.same_network(run.net, reconstruct_robust(run.example.points)), name
    fan, fork = runs["fan"], runs["fork"]
    # what the captions of docs/method.md describe
    assert len(fan.cut) == 1 and len(fork.cut) == 0
    assert (fan.net.n_nodes, fan.net.n_curves, fork.net.n_nodes, fork.net.n_curves) == (8, 7, 6, 5)
    assert fork.reg0.max() == fork.reg.max()  # the fork's region is not split in stage 4 ...
    assert fan.reg0.max() == fan.reg.max()
    assert [n for n, _ in mf._acted(fan)] == ["attach_dangling"]
    assert [n for n, _ in mf._acted(fork)] == ["split_multiple_junctions", "prune_spurs"]  # ... but in stage 6
    assert (len(fan.traced.chains), len(fork.traced.chains)) == (6, 5)
    assert (len(fan.repairs[-1][1].chains), len(fork.repairs[-1][1].chains)) == (7, 5)
    assert len(fork.P_in) == 77 and len(fan.P_in) == 331


def test_changed_points_marks_what_a_repair_changed():
    mf = _load()
    a = mf.TopoState([np.array([0, 1, 2]), np.array([5, 6, 7])], [(0, 1), (2, 3)], [False, False],
                     [np.array([8]), np.array([3]), np.array([4]), np.array([9])], np.array([1, 1, 1, 1]))
    # region 1 absorbed into region 2 (a tip joined a junction): the chain end moves, points 3, 4 change
    b = mf.TopoState([np.array([0, 1, 2]), np.array([5, 6, 7])], [(0, 2), (2, 3)], [False, False],
                     [np.array([8]), np.zeros(0, dtype=np.int64), np.array([4, 3]), np.array([9])],
                     np.array([1, 0, 2, 1]))
    assert a.changed_points(b).tolist() == [2, 3, 4]
    assert a.changed_points(a).tolist() == []
    # a chain dropped: its points change, the others do not
    c = mf.TopoState([np.array([0, 1, 2])], [(0, 1)], [False], a.regions, np.array([1, 1, 0, 0]))
    assert a.changed_points(c).tolist() == [5, 6, 7]


def test_the_readme_paragraph_is_short_and_links_here():
    readme = (ROOT / "README.md").read_text()
    m = re.search(r"^- \*\*`robust`, the default: no parameters to set\.\*\*(.*?)(?=^- |\Z)", readme, re.S | re.M)
    assert m, "the README's robust bullet is gone"
    text = m.group(1)
    assert "(docs/method.md)" in text
    assert len(text.split()) <= 120  # was 337 words
    prose = text.replace("(docs/method.md)", "")
    depth = np.cumsum([{"(": 1, ")": -1}.get(ch, 0) for ch in prose])
    assert depth.max(initial=0) <= 1 and depth[-1] == 0  # no nested parentheses
