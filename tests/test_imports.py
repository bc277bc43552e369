"""The package's import graph: no import cycles, and the algorithmic core never reaches I/O,
pictures, the viewer or the command line.

Every module of ``src/curvenet`` is parsed with :mod:`ast` (nothing of it is run): imports at
module level and inside functions, relative imports resolved, imports under ``if TYPE_CHECKING:``
left out. ``from pkg import name`` is an edge to ``pkg.name`` when that is a module and to ``pkg``
(its ``__init__``) otherwise; importing ``a.b.c`` also runs the ``__init__`` of every package on
the way that is not already above the importing module, so those are edges too. Imports through
:func:`importlib.import_module` with a literal name are edges; the few with a computed name are
listed in :data:`DYNAMIC_IMPORTS` together with where their names come from.
"""

from __future__ import annotations


import ast
import importlib.util
import subprocess
import sys
from collections import deque
from pathlib import Path

import pytest

import curvenet

PACKAGE = "curvenet"
SRC = Path(curvenet.__file__).resolve().parent

#: The algorithmic core and the neutral modules below it, which must not import, directly or
#: through other modules, anything in :data:`OUTER`. ``x.*`` is the module ``x`` and everything
#: under it; a plain name is that module alone.
CORE = (
    "curvenet",  # the package itself: ``import curvenet`` must stay light
    "curvenet.methods.*",
    "curvenet.neighbors",
    "curvenet.network",
    "curvenet.metrics",
    "curvenet.synth.*",
    "curvenet.surfacing.*",
    "curvenet.validate",
    "curvenet.errors",
    "curvenet.reconstruct",
    "curvenet.style",
    "curvenet._sigint",
    "curvenet._version",
)

#: The outer layers: file formats, pictures, the viewer and the command line.
OUTER = ("curvenet.io.*", "curvenet.plots.*", "curvenet.viewer", "curvenet.cli.*")

#: Core modules allowed to reach the outer layers, with the reason. (The surface mesh writers
#: are in ``curvenet.io.mesh``, with the other writers and their bulk number formatting.)
CORE_EXCEPTIONS: dict[str, str] = {
    "curvenet": "the public facade: curvenet.save() and curvenet.load() import curvenet.io inside "
                "the functions, so `import curvenet` stays light (test_import_curvenet_stays_light)",
}


def _commands() -> list[str]:
    from curvenet.cli import COMMANDS

    return [f"curvenet.cli.cmd_{name}" for name in COMMANDS]


def _methods() -> list[str]:
    from curvenet.reconstruct import METHODS

    return sorted({module for module, _ in METHODS.values()})


#: Modules that import by a computed name: module -> (where the names come from, the targets).
#: ``curvenet.errors.require`` imports the optional third-party module its caller names.
DYNAMIC_IMPORTS = {
    "curvenet.cli": ("the command modules of curvenet.cli.COMMANDS", _commands),
    "curvenet.reconstruct": ("the method modules of curvenet.reconstruct.METHODS", _methods),
    "curvenet.bench": ("the method modules of curvenet.reconstruct.METHODS", _methods),
    "curvenet.errors": ("optional third-party modules (require)", lambda: []),
}


# --------------------------------------------------------------------------------------------
# the graph


def module_files(src: Path, package: str) -> dict[str, Path]:
    """Module name -> file for every ``.py`` file under ``src`` (the folder of ``package``)."""
    out = {}
    for f in sorted(src.rglob("*.py")):
        parts = list(f.relative_to(src).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join([package, *parts])] = f
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _statements(tree: ast.AST):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:``."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            todo.extend(node.orelse)
            continue
        todo.extend(ast.iter_child_nodes(node))


def _is_import_module(call: ast.Call) -> bool:
    f = call.func
    return (isinstance(f, ast.Attribute) and f.attr == "import_module") or (
        isinstance(f, ast.Name) and f.id in ("import_module", "__import__")
    )


def raw_imports(name: str, path: Path, modules) -> tuple[list[tuple[str, int]], list[int]]:
    """Absolute names imported by module ``name`` (with line numbers), and the lines of
    imports by a computed name.

    ``from pkg import x`` gives ``pkg.x`` when that is a module of ``modules``, else ``pkg``.
    """
    is_pkg = path.name == "__init__.py"
    here = name.split(".") if is_pkg else name.split(".")[:-1]
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found, computed = [], []
    for node in _statements(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                up = here[: len(here) - (node.level - 1)]
                base = ".".join(up + ([node.module] if node.module else []))
            else:
                base = node.module
            for a in node.names:
                sub = f"{base}.{a.name}"
                found.append((sub if sub in modules else base, node.lineno))
        elif isinstance(node, ast.Call) and _is_import_module(node) and node.args:
            arg = node.args[0]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                found.append((arg.value, node.lineno))
            else:
                computed.append(node.lineno)
    return found, computed


def build_graph(src: Path, package: str, dynamic=None):
    """The import graph of a package.

    Returns
    -------
    edges : dict
        module -> {imported module of the package: first line of the import}.
    computed : dict
        module -> lines of imports by a computed name that ``dynamic`` does not account for.
    files : dict
        module -> file.
    """
    dynamic = dynamic or {}
    files = module_files(src, package)
    edges: dict[str, dict[str, int]] = {m: {} for m in files}
    computed: dict[str, list[int]] = {}
    for mod, path in files.items():
        found, dyn = raw_imports(mod, path, files)
        if dyn:
            if mod in dynamic:
                found += [(t, dyn[0]) for t in dynamic[mod][1]()]
            else:
                computed[mod] = dyn
        above = {".".join(mod.split(".")[:k]) for k in range(1, mod.count(".") + 2)}
        for target, line in found:
            parts = target.split(".")
            if parts[0] != package:
                continue
            # the packages on the way run their __init__ unless they are already above us
            chain = [".".join(parts[:k]) for k in range(1, len(parts))]
            for t in [c for c in chain if c not in above] + [target]:
                if t in files and t != mod:
                    edges[mod].setdefault(t, line)
    return edges, computed, files


def strongly_connected(edges: dict[str, dict[str, int]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = 0
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return sorted(out)


def describe_cycles(edges, files, src: Path) -> str:
    lines = []
    for comp in strongly_connected(edges):
        lines.append("import cycle among: " + ", ".join(comp))
        for a in comp:
            for b, line in sorted(edges[a].items()):
                if b in comp:
                    lines.append(f"    {a} -> {b}  ({files[a].relative_to(src.parent)}:{line})")
    return "\n".join(lines)


def _under(mod: str, patterns) -> bool:
    """Whether ``mod`` matches one of ``patterns`` (``x.*``: ``x`` and below; ``x``: ``x``)."""
    return any(mod == p.removesuffix(".*") or (p.endswith(".*") and mod.startswith(p[:-1]))
               for p in patterns)


def core_violations(edges, files, src: Path, core=CORE, outer=OUTER, exceptions=CORE_EXCEPTIONS) -> str:
    """Each core module that reaches an outer module, with the chain of imports."""
    core_mods = [m for m in sorted(edges) if _under(m, core)]
    lines = []
    for start in core_mods:
        if start in exceptions:
            continue
        prev = {start: None}
        todo = deque([start])
        hit = None
        while todo and hit is None:
            v = todo.popleft()
            for w in sorted(edges[v]):
                if w not in prev:
                    prev[w] = v
                    if _under(w, outer):
                        hit = w
                        break
                    todo.append(w)
        if hit:
            chain = [hit]
            while prev[chain[-1]] is not None:
                chain.append(prev[chain[-1]])
            chain = chain[::-1]
            steps = [f"{a} ({files[a].relative_to(src.parent)}:{edges[a][b]})" for a, b in zip(chain, chain[1:])]
            lines.append(f"{start} reaches {hit}: " + " -> ".join(steps + [hit]))
    return "\n".join(lines)


@pytest.fixture(scope="module")
def graph():
    return build_graph(SRC, PACKAGE, DYNAMIC_IMPORTS)


# --------------------------------------------------------------------------------------------
# the package


def test_no_import_cycles(graph):
    edges, _, files = graph
    report = describe_cycles(edges, files, SRC)
    if report:
        pytest.fail("\n" + report, pytrace=False)


def test_core_does_not_reach_io_plots_viewer_or_cli(graph):
    edges, _, files = graph
    report = core_violations(edges, files, SRC)
    if report:
        pytest.fail("\n" + report, pytrace=False)


def test_nothing_below_the_cli_imports_it(graph):
    edges, _, files = graph
    cli = ("curvenet.cli.*",)
    above = ("curvenet.__main__",)  # ``python -m curvenet``: an entry point, above the CLI
    bad = [f"{a} -> {b} ({files[a].relative_to(SRC.parent)}:{line})"
           for a in sorted(edges) if not _under(a, cli) and a not in above
           for b, line in sorted(edges[a].items()) if _under(b, cli)]
    if bad:
        pytest.fail("imports of the CLI from below it:\n" + "\n".join(bad), pytrace=False)


def test_every_computed_import_is_accounted_for(graph):
    _, computed, files = graph
    assert not computed, (
        "imports by a computed name the graph cannot follow (list them in DYNAMIC_IMPORTS): "
        + ", ".join(f"{files[m].relative_to(SRC.parent)}:{ls}" for m, ls in sorted(computed.items()))
    )


def test_core_and_outer_lists_name_real_modules(graph):
    edges, _, _ = graph
    for p in CORE + OUTER:
        assert any(_under(m, (p,)) for m in edges), f"{p} names no module"
    for mods in DYNAMIC_IMPORTS.values():
        for m in mods[1]():
            assert m in edges and importlib.util.find_spec(m), m


def test_graph_sees_imports_inside_functions_and_dynamic_ones(graph):
    edges, _, _ = graph
    # inside a function (cmd_bench.run), a literal-free import_module (cli -> its commands), a
    # relative import two levels up
    assert "curvenet.bench" in edges["curvenet.cli.cmd_bench"]
    assert "curvenet.cli.cmd_bench" in edges["curvenet.cli"]
    assert "curvenet.methods.robust" in edges["curvenet.reconstruct"]
    assert "curvenet.network" in edges["curvenet.methods.robust.pipeline"]


def _defined_names(path: Path) -> set[str]:
    """Names a module defines at its top level (functions, classes, assignments)."""
    out = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for t in node.targets if isinstance(node, ast.Assign) else [node.target]:
                out |= {n.id for n in ast.walk(t) if isinstance(n, ast.Name)}
    return out


def test_colours_and_node_kinds_are_defined_once(graph):
    """The shared look lives in curvenet.style and node kinds on CurveNetwork: no copies."""
    import curvenet.style

    _, _, files = graph
    names = set(curvenet.style.__all__) | {"node_kinds", "KEY_DECIMALS"}
    copies = {m: sorted(_defined_names(f) & names) for m, f in files.items() if m != "curvenet.style"}
    copies = {m: c for m, c in copies.items() if c}
    assert not copies, f"defined outside curvenet.style: {copies}"


# --------------------------------------------------------------------------------------------
# the checker itself, on tiny packages


def _package(root: Path, files: dict[str, str]) -> Path:
    src = root / "pkg"
    for rel, text in files.items():
        f = src / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
    return src


def test_checker_finds_a_cycle_through_a_function_level_import(tmp_path):
    src = _package(tmp_path, {
        "__init__.py": "",
        "a.py": "from .b import f\n",
        "b.py": "def f():\n    from . import a\n",
        "c.py": "from .a import f\n",
    })
    edges, _, files = build_graph(src, "pkg")
    assert strongly_connected(edges) == [["pkg.a", "pkg.b"]]
    report = describe_cycles(edges, files, src)
    assert "pkg.a, pkg.b" in report and "pkg/b.py:2" in report


def test_checker_sees_init_reexports_and_parent_imports(tmp_path):
    src = _package(tmp_path, {
        "__init__.py": "",
        "sub/__init__.py": "from .x import y\n\ndef helper():\n    pass\n",
        "sub/x.py": "from . import helper\ny = 1\n",
        "z.py": "from .sub.x import y\n",
    })
    edges, _, _ = build_graph(src, "pkg")
    assert strongly_connected(edges) == [["pkg.sub", "pkg.sub.x"]]
    # z imports pkg.sub.x, so pkg.sub's __init__ runs too
    assert set(edges["pkg.z"]) == {"pkg.sub", "pkg.sub.x"}


def test_checker_ignores_type_checking_and_follows_literal_import_module(tmp_path):
    src = _package(tmp_path, {
        "__init__.py": "",
        "a.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .b import T\n",
        "b.py": "import importlib\nimportlib.import_module('pkg.a')\n",
        "c.py": "import importlib\nname = 'pkg.a'\nimportlib.import_module(name)\n",
    })
    edges, computed, _ = build_graph(src, "pkg")
    assert edges["pkg.a"] == {} and edges["pkg.b"] == {"pkg.a": 2}
    assert strongly_connected(edges) == []
    assert computed == {"pkg.c": [3]}


def test_checker_reports_the_chain_from_core_to_outer(tmp_path):
    src = _package(tmp_path, {
        "__init__.py": "",
        "core.py": "def f():\n    from .helper import g\n",
        "helper.py": "from .io import write\n",
        "io.py": "def write():\n    pass\n",
    })
    edges, _, files = build_graph(src, "pkg")
    report = core_violations(edges, files, src, core=("pkg.core",), outer=("pkg.io",), exceptions={})
    assert report == "pkg.core reaches pkg.io: pkg.core (pkg/core.py:2) -> pkg.helper (pkg/helper.py:1) -> pkg.io"


def test_import_curvenet_stays_light():
    """``import curvenet`` loads none of the outer layers (the facade imports them when called)."""
    code = ("import sys, curvenet; bad = sorted(m for m in sys.modules if m.split('.')[:2] in "
            "(['curvenet', 'io'], ['curvenet', 'plots'], ['curvenet', 'viewer'], ['curvenet', 'cli'])); "
            "print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"import curvenet loaded: {out}"
