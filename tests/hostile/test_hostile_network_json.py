"""Issue 20 item 6: the network reader checks the whole document against the published schema."""

import copy
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from curvenet import FormatError
from curvenet.io import read_network
from curvenet.io.network_schema import NETWORK_SCHEMA

DOCS = Path(__file__).resolve().parents[2] / "docs"

VALID = {
    "format": "curvenet",
    "version": 1,
    "dimension": 3,
    "nodes": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    "curves": [
        {"points": [[0.0, 0.0, 0.0], [0.5, 0.1, 0.0], [1.0, 0.0, 0.0]], "start": 0, "end": 1,
         "closed": False, "indices": [0, 1, 2]},
        {"points": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "start": 1, "end": 2},
        {"points": [[5.0, 5.0, 5.0], [6.0, 5.0, 5.0], [5.0, 6.0, 5.0]], "start": None, "end": None,
         "closed": True, "indices": [-1, 4, 5]},
    ],
    "parameters": {"method": "robust", "spacing": 0.1},
    "stats": {"N_n": 3},
}

#: values put in place of every value of the document
REPLACEMENTS = [None, "0", 0.5, -1, 0, 2, 3, True, [], {}, [1.0, 2.0], [[1.0, 2.0, 3.0]], 10**400, -2]


def _paths(doc, path=()):
    yield path
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, path + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, path + (i,))


def _mutations():
    out = []
    for path in _paths(VALID):
        if not path:
            continue
        for r in REPLACEMENTS:
            d = copy.deepcopy(VALID)
            parent = d
            for key in path[:-1]:
                parent = parent[key]
            parent[path[-1]] = r
            out.append(d)
        if isinstance(path[-1], str) or len(path) <= 3:
            d = copy.deepcopy(VALID)
            parent = d
            for key in path[:-1]:
                parent = parent[key]
            del parent[path[-1]]
            out.append(d)
    return out


def _extra_rules_hold(doc) -> bool:
    """The rules of EXTRA_RULES (for a document the schema accepts)."""
    n = len(doc["nodes"])
    for c in doc["curves"]:
        for v in (c.get("start"), c.get("end")):
            if v is not None and v >= n:
                return False
        if "indices" in c and len(c["indices"]) != len(c["points"]):
            return False
    return True


def test_docs_publish_the_schema_the_reader_uses():
    assert json.loads((DOCS / "network.schema.json").read_text()) == NETWORK_SCHEMA
    page = (DOCS / "network-format.md").read_text()
    blocks = re.findall(r"```json\n(.*?)```", page, flags=re.S)
    assert json.loads(blocks[-1]) == NETWORK_SCHEMA
    jsonschema = pytest.importorskip("jsonschema")
    jsonschema.Draft202012Validator.check_schema(NETWORK_SCHEMA)
    jsonschema.validate(json.loads(blocks[0]), NETWORK_SCHEMA)  # the page's example is valid


def test_reader_agrees_with_the_schema_on_every_mutation(tmp_path):
    """Every value of a small network replaced by each of 14 others or deleted: the reader
    accepts exactly the documents the schema (and the extra rules) accept, and refuses the
    others with one line naming the file and a JSON path."""
    jsonschema = pytest.importorskip("jsonschema")
    validator = jsonschema.Draft202012Validator(NETWORK_SCHEMA)
    docs = _mutations()
    assert len(docs) > 500
    f = tmp_path / "n.json"
    accepted = 0
    for doc in docs:
        expect = validator.is_valid(doc) and _extra_rules_hold(doc)
        f.write_text(json.dumps(doc))
        try:
            net = read_network(f)
        except FormatError as exc:
            msg = str(exc)
            assert not expect, (doc, msg)
            assert "\n" not in msg and msg.startswith(f"{f}: ") and " at $" in msg, msg
            continue
        assert expect, doc
        accepted += 1
        assert np.isfinite(net.nodes).all()
    assert 0 < accepted < len(docs) // 2


@pytest.mark.parametrize("text, where", [
    ('"banana"', "at $:"),
    ('{"format": "curvenet", "version": 1, "dimension": 3, "nodes": [[NaN, 0, 0]], "curves": []}', "$.nodes[0][0]"),
    ('{"format": "curvenet", "version": 1, "dimension": 3, "nodes": [[1e999, 0, 0]], "curves": []}', "$.nodes[0][0]"),
    ('{"format": "curvenet", "version": 1, "dimension": 3, "nodes": [], "curves": [{"points": [[0, 0, Infinity]]}]}',
     "$.curves[0].points[0][2]"),
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ('{"format": "curvenet", "version": 1, "dimension": 3, "nodes": [[' + "9" * 5000 + ", 0, 0]], \"curves\": []}",
     "5000 digits"),
])
def test_hostile_json_text(tmp_path, text, where):
    f = tmp_path / "n.json"
    f.write_text(text)
    with pytest.raises(FormatError, match=re.escape(where)):
        read_network(f)


def cli(*args):
    return subprocess.run([sys.executable, "-m", "curvenet.cli", *map(str, args)], capture_output=True, text=True)


@pytest.mark.parametrize("command", ["info", "render", "view", "surface"])
def test_every_command_refuses_a_bad_network(tmp_path, command):
    """On main, "version": 2 was read by all four commands (exit 0)."""
    doc = copy.deepcopy(VALID)
    doc["version"] = 2
    f = tmp_path / "n.json"
    f.write_text(json.dumps(doc))
    out = {"info": [], "render": ["-o", tmp_path / "o.png"], "view": ["-o", tmp_path / "o.html"],
           "surface": ["-o", tmp_path / "o.obj"]}[command]
    r = cli(command, f, *out)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip() == (f"curvenet: error: {f}: invalid curvenet network at $.version: expected 1 "
                                "(the network format version this curvenet reads), got 2")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["n.json"]
