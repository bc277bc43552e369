"""The scripts of ``benchmarks/`` as modules, for the tests that call their functions."""

import importlib.util
import sys
from pathlib import Path

#: The folder of the benchmark scripts (absent from an installed package's tests).
BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def has(name: str) -> bool:
    """Whether ``benchmarks/<name>.py`` is in this checkout."""
    return (BENCH / f"{name}.py").exists()


def load(name: str):
    """``benchmarks/<name>.py`` as the module ``curvenet_bench_<name>``, loaded once per process
    and registered in ``sys.modules`` (a script's dataclasses look their module up there);
    ``benchmarks/`` is on ``sys.path`` while it runs (a script imports its siblings:
    ``fork_stress`` imports ``robust_eval``)."""
    key = f"curvenet_bench_{name}"
    if key in sys.modules:
        return sys.modules[key]
    spec = importlib.util.spec_from_file_location(key, BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[key] = mod
    sys.path.insert(0, str(BENCH))
    try:
        spec.loader.exec_module(mod)
    except BaseException:
        del sys.modules[key]
        raise
    finally:
        sys.path.remove(str(BENCH))
    return mod
