"""Run a snippet under OpenBLAS's kernels for another processor (``OPENBLAS_CORETYPE``).

OpenBLAS picks its kernels by processor; on an AVX-512 processor ``SkylakeX`` (its own) and
``Haswell`` (AVX2, what most other machines run) round some sums differently. Where the
processor has no AVX-512, forcing ``SkylakeX`` would crash, and the two agree anyway: the
tests that compare them skip there.
"""

import os
import subprocess
import sys


def has_avx512() -> bool:
    """Whether this processor has AVX-512 (Linux: /proc/cpuinfo)."""
    try:
        with open("/proc/cpuinfo") as f:
            return " avx512f" in f.read()
    except OSError:
        return False


def output_under(core: str, code: str) -> str:
    """What ``code`` prints in a fresh Python whose OpenBLAS runs the ``core`` kernels."""
    env = dict(os.environ, OPENBLAS_CORETYPE=core)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return r.stdout.strip()


def network_digest_code(setup: str, network: str) -> str:
    """A snippet for :func:`output_under` that prints the SHA-256 of a network's node
    coordinates and curve points (their float64 bits): ``setup`` (lines ending in a newline)
    imports what ``network``, an expression, needs (``np`` and ``curvenet`` are imported)."""
    return ("import hashlib, numpy as np, curvenet\n" + setup + f"n = {network}\n"
            "d = hashlib.sha256(np.ascontiguousarray(n.nodes).tobytes())\n"
            "[d.update(np.ascontiguousarray(x.points).tobytes()) for x in n.curves]\n"
            "print(d.hexdigest())\n")
