"""The curvenet JSON network format (version 1): its JSON Schema and the reader's check.

:data:`NETWORK_SCHEMA` is the format as a JSON Schema (draft 2020-12), published in
``docs/network-format.md`` and ``docs/network.schema.json``. :func:`check_network_document`
checks a parsed document against it, plus the rules a JSON Schema cannot state
(:data:`EXTRA_RULES`), and names the JSON path of the first problem. It needs no third-party
package; the tests compare it with the ``jsonschema`` package on many documents.
"""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from ..errors import FormatError

__all__ = ["NETWORK_SCHEMA", "EXTRA_RULES", "FORMAT_VERSION", "check_network_document"]

#: The version of the network format this curvenet writes and reads.
FORMAT_VERSION = 1

#: The largest finite float64: coordinates beyond it do not fit (JSON allows any size).
_FLOAT_MAX = sys.float_info.max

#: The largest input point index (int64).
_INDEX_MAX = int(np.iinfo(np.int64).max)

_COORDINATE = {"type": "number", "minimum": -_FLOAT_MAX, "maximum": _FLOAT_MAX}
_NODE_ID = {"oneOf": [{"type": "integer", "minimum": 0}, {"type": "null"}]}


def _points_schema(d: int) -> dict:
    return {"type": "array", "items": {"type": "array", "items": _COORDINATE, "minItems": d, "maxItems": d}}


#: The JSON Schema of a network document. Other keys are allowed (and ignored).
NETWORK_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://curvenet.invalid/network-1.schema.json",
    "title": "curvenet curve network, format version 1",
    "type": "object",
    "required": ["format", "version", "dimension", "nodes", "curves"],
    "properties": {
        "format": {"const": "curvenet"},
        "version": {"const": FORMAT_VERSION},
        "dimension": {"enum": [2, 3]},
        "nodes": {"type": "array"},
        "curves": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["points"],
                "properties": {
                    "points": {"type": "array"},
                    "start": _NODE_ID,
                    "end": _NODE_ID,
                    "closed": {"type": "boolean"},
                    "indices": {"type": "array", "items": {"type": "integer", "minimum": -1, "maximum": _INDEX_MAX}},
                },
                "oneOf": [
                    {"properties": {"start": {"type": "null"}, "end": {"type": "null"}}},
                    {"required": ["start", "end"],
                     "properties": {"start": {"type": "integer"}, "end": {"type": "integer"}}},
                ],
            },
        },
        "parameters": {"type": "object"},
        "stats": {"type": "object"},
    },
    "allOf": [
        {
            "if": {"properties": {"dimension": {"const": d}}},
            "then": {"properties": {
                "nodes": _points_schema(d),
                "curves": {"items": {"properties": {"points": _points_schema(d)}}},
            }},
        }
        for d in (2, 3)
    ],
}

#: What the reader checks beyond :data:`NETWORK_SCHEMA`.
EXTRA_RULES = (
    "every node id (start, end) is less than the number of nodes",
    "a curve's indices, when given, are as many as its points",
    "numbers are finite (no NaN or Infinity, which some JSON writers emit)",
)


def _show(value) -> str:
    """A short description of a JSON value for a message."""
    if isinstance(value, (dict, list)):
        return f"{'an object' if isinstance(value, dict) else 'a list'} of {len(value)} item(s)"
    text = "null" if value is None else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _fail(path: str, expected: str, value) -> None:
    raise FormatError(f"at {path}: expected {expected}, got {_show(value)}")


def _is_int(v) -> bool:
    """A JSON integer (as the JSON Schema counts them: 2 and 2.0, not true)."""
    return (type(v) is int) or (type(v) is float and v.is_integer())


def _is_number(v) -> bool:
    return type(v) in (int, float)


def _coordinates(path: str, rows, d: int) -> np.ndarray:
    """(m, d) float array of a list of points; the first bad entry fails with its path."""
    if not isinstance(rows, list):
        _fail(path, f"a list of points of {d} coordinates", rows)
    fast = all(type(r) is list and len(r) == d for r in rows) and all(_is_number(x) for r in rows for x in r)
    if fast:
        try:
            arr = np.array(rows, dtype=np.float64).reshape(len(rows), d)
        except OverflowError:
            arr = None
        if arr is not None and np.isfinite(arr).all():
            return arr
    for i, r in enumerate(rows):
        if type(r) is not list or len(r) != d:
            _fail(f"{path}[{i}]", f"a point of {d} coordinates", r)
        for j, x in enumerate(r):
            if not _is_number(x):
                _fail(f"{path}[{i}][{j}]", "a number", x)
            try:
                ok = math.isfinite(float(x))
            except OverflowError:
                ok = False
            if not ok:
                _fail(f"{path}[{i}][{j}]", "a finite number that fits in float64", x)
    raise AssertionError("unreachable")  # pragma: no cover


def _node_id(path: str, v, n: int) -> None:
    if v is None:
        return
    if not _is_int(v) or v < 0:
        _fail(path, "a node id (an integer >= 0) or null", v)
    if v >= n:
        _fail(path, f"a node id below the number of nodes ({n})", v)


def _curve(path: str, c, d: int, n: int) -> None:
    if not isinstance(c, dict):
        _fail(path, "a curve object", c)
    if "points" not in c:
        _fail(path, 'a curve with "points"', c)
    pts = _coordinates(f"{path}.points", c["points"], d)
    start, end = c.get("start"), c.get("end")
    _node_id(f"{path}.start", start, n)
    _node_id(f"{path}.end", end, n)
    if (start is None) != (end is None):
        where, v = (f"{path}.end", end) if start is not None else (f"{path}.start", start)
        _fail(where, "start and end both node ids or both null", v)
    if "closed" in c and type(c["closed"]) is not bool:
        _fail(f"{path}.closed", "true or false", c["closed"])
    if "indices" in c:
        ind = c["indices"]
        if not isinstance(ind, list):
            _fail(f"{path}.indices", "a list of input point indices", ind)
        for i, v in enumerate(ind):
            if not _is_int(v) or not -1 <= v <= _INDEX_MAX:
                _fail(f"{path}.indices[{i}]", "an input point index (an integer >= -1, int64)", v)
        if len(ind) != len(pts):
            _fail(f"{path}.indices", f"as many indices as points ({len(pts)})", ind)


def check_network_document(doc) -> None:
    """Check a parsed JSON document against the network format.

    Parameters
    ----------
    doc : object
        The document as parsed by :func:`json.loads`.

    Raises
    ------
    FormatError
        ``"at <JSON path>: expected ..., got ..."`` for the first problem (in document order:
        format, version, dimension, nodes, curves, parameters, stats).
    """
    if not isinstance(doc, dict):
        _fail("$", "a curvenet network object", doc)
    if doc.get("format") != "curvenet":
        _fail("$.format", '"curvenet"', doc.get("format"))
    v = doc.get("version")
    if not (_is_int(v) and v == FORMAT_VERSION):
        _fail("$.version", f"{FORMAT_VERSION} (the network format version this curvenet reads)", v)
    d = doc.get("dimension")
    if not (_is_int(d) and d in (2, 3)):
        _fail("$.dimension", "2 or 3", d)
    d = int(d)
    if "nodes" not in doc:
        _fail("$", 'a "nodes" list', doc)
    n = len(_coordinates("$.nodes", doc["nodes"], d))
    curves = doc.get("curves")
    if not isinstance(curves, list):
        _fail("$.curves", "a list of curves", curves)
    for i, c in enumerate(curves):
        _curve(f"$.curves[{i}]", c, d, n)
    for key in ("parameters", "stats"):
        if key in doc and not isinstance(doc[key], dict):
            _fail(f"$.{key}", "an object", doc[key])
