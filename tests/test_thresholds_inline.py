"""No number hides inline in the robust method (issue 19): every fixed constant is a documented
field of :mod:`curvenet.methods.robust.thresholds`.

Every function of ``src/curvenet/methods/robust`` (its kernels too; bodies, default values and
decorators) is parsed with :mod:`ast` and its numeric literals are listed. Allowed are 0, 1, 2
and 0.5 (a minus sign is an operator: ``-1`` is the literal 1). The package uses -1 as an index
sentinel (a chain end without region, ``np.full(n, -1)``), for the last element ``x[-1]``, a
reversal ``[::-1]``, ``reshape(-1, d)`` and a sign; -2 only as a slice bound (``X[:-2]``);
-0.5 only in the Gaussian weight ``exp(-0.5 r^2 / b^2)``.
Outside functions, a number may only be the value of a module constant with an UPPER_CASE name
and a ``#:`` comment on the lines above it (the kernels' dispatch settings of
``kernels/registry.py``, whose results never depend on them).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import curvenet.methods.robust as robust

ROBUST = Path(robust.__file__).resolve().parent
ALLOWED = {0, 1, 2, 0.5}


def _is_number(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and type(node.value) in (int, float, complex)


def inline_numbers(source: str) -> list[tuple[int, str, object]]:
    """``(line, function, value)`` of every numeric literal in a function of ``source`` that
    is not in :data:`ALLOWED` (a unary minus taken with its number)."""
    tree = ast.parse(source)
    found = {}  # (line, column) -> (innermost function, value): ast.walk visits outer ones first
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        for node in ast.walk(fn):
            if _is_number(node) and abs(node.value) not in ALLOWED:
                found[(node.lineno, node.col_offset)] = (getattr(fn, "name", "<lambda>"), node.value)
    return [(line, name, value) for (line, _), (name, value) in sorted(found.items())]


def module_numbers(source: str) -> list[tuple[int, object]]:
    """``(line, value)`` of every numeric literal outside functions that is not in
    :data:`ALLOWED` and is not the value of a module constant named in UPPER_CASE with a ``#:``
    comment above it."""
    tree = ast.parse(source)
    lines = source.splitlines()
    in_function = {id(n) for fn in ast.walk(tree) if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
                   for n in ast.walk(fn)}
    documented = set()
    for stmt in tree.body:
        if isinstance(stmt, (ast.Assign, ast.AnnAssign)):
            targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
            names = [t.id for t in targets if isinstance(t, ast.Name)]
            above = lines[stmt.lineno - 2].strip() if stmt.lineno >= 2 else ""
            if names and all(n.isupper() for n in names) and above.startswith("#:"):
                documented |= {id(n) for n in ast.walk(stmt)}
    return sorted({(n.lineno, n.value) for n in ast.walk(tree)
                   if _is_number(n) and abs(n.value) not in ALLOWED and id(n) not in in_function
                   and id(n) not in documented}, key=lambda t: (t[0], str(t[1])))


def _modules() -> list[Path]:
    return sorted(p for p in ROBUST.rglob("*.py") if p.name != "thresholds.py")


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(ROBUST)))
def test_no_number_inline_in_a_function(path):
    found = inline_numbers(path.read_text(encoding="utf-8"))
    assert not found, (f"{path.relative_to(ROBUST.parents[2])}: numbers inline (make each a documented field of "
                       "thresholds.py): " + ", ".join(f"line {ln} in {fn}(): {v!r}" for ln, fn, v in found))


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(ROBUST)))
def test_no_undocumented_module_number(path):
    found = module_numbers(path.read_text(encoding="utf-8"))
    assert not found, f"{path.relative_to(ROBUST.parents[2])}: undocumented numbers at module level: {found}"


def test_the_scan_sees_what_it_must():
    """The checks fail on an inline number, wherever it hides, and let the allowed ones pass."""
    src = (
        "def f(x, k=16):\n"                      # a default value
        "    y = x[-1] + x[::-1][0] * 0.5\n"     # allowed: -1, 0, 0.5
        "    z = 1.2 * x * 2\n"                  # 1.2 is a threshold inline
        "    w = [v for v in x if v > 1e-9]\n"  # in a comprehension
        "    return -3 + (lambda t: t / 7.5)(z)\n"
    )
    got = inline_numbers(src)
    assert [(ln, v) for ln, _, v in got] == [(1, 16), (3, 1.2), (4, 1e-9), (5, 3), (5, 7.5)]
    assert inline_numbers("def g(a):\n    return a[:-2] - 1 + 2 * a[0] ** 0.5\n") == []
    mod = "#: documented\nLIMIT = 2000\nOTHER = 300\nlower = 40\n"
    assert module_numbers(mod) == [(3, 300), (4, 40)]


def test_the_package_is_scanned():
    names = {str(p.relative_to(ROBUST)) for p in _modules()}
    assert {"pipeline.py", "repairs.py", "curves.py", "kernels/linalg.py", "kernels/registry.py"} <= names
    assert "thresholds.py" not in names


def test_every_threshold_says_where_its_value_came_from():
    """Each field of thresholds.py has a ``#:`` comment (its meaning) ending in an ``origin:``
    part, which docs/method.md shows in the origin column of its table."""
    import re

    from curvenet.methods.robust import thresholds

    src = (ROBUST / "thresholds.py").read_text(encoding="utf-8")
    tree = ast.parse(src)
    lines = src.splitlines()
    missing, n = [], 0
    for cls in (c for c in tree.body if isinstance(c, ast.ClassDef)):
        for item in (i for i in cls.body if isinstance(i, ast.AnnAssign)):
            n += 1
            comment, i = [], item.lineno - 2
            while i >= 0 and lines[i].strip().startswith("#:"):
                comment.insert(0, lines[i].strip()[2:].strip())
                i -= 1
            text = " ".join(comment)
            meaning, _, origin = text.partition("origin: ")
            if not meaning.strip() or not origin.strip():
                missing.append(f"{cls.name}.{item.target.id}")
    groups = [g for g in thresholds.__all__ if g.isupper()]
    assert n == sum(len(getattr(thresholds, g)._fields) for g in groups)
    assert not missing, f"fields without a meaning and an origin: {missing}"
    doc = (Path(__file__).resolve().parents[1] / "docs" / "method.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `\w+` \| [^|]+ \| .+ \| (.*) \|$", doc, re.M)
    assert len(rows) >= n and all(r.strip() for r in rows[-n:])
