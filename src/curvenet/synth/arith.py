"""Vector arithmetic of the generators without BLAS: the same bits on every processor.

numpy hands ``@``, ``np.dot`` and the norm of a whole vector (``np.linalg.norm(v)``) to BLAS,
whose kernels depend on the processor: OpenBLAS's AVX-512 kernels round differently from its
AVX2 ones (``OPENBLAS_CORETYPE`` forces either). The generated points then differed in their last
bits from one machine to another, and with them the networks reconstructed from them (56 of the
576 digest runs, e.g. every sampling of the tree model). These functions multiply element by
element and add in a fixed order instead.
"""

from __future__ import annotations

import numpy as np

__all__ = ["norm", "matvec", "matmul"]


def norm(v) -> float:
    """Euclidean length of the vector ``v`` (d,)."""
    v = np.asarray(v, dtype=np.float64)
    return float(np.sqrt(np.sum(v * v)))


def matvec(A, x) -> np.ndarray:
    """``A @ x`` for ``A`` (..., m, n) and ``x`` (n,): an array (..., m)."""
    return np.sum(np.asarray(A, dtype=np.float64) * np.asarray(x, dtype=np.float64), axis=-1)


def matmul(A, B) -> np.ndarray:
    """``A @ B`` for ``A`` (m, n) and ``B`` (n, p): an array (m, p)."""
    A = np.asarray(A, dtype=np.float64)
    B = np.asarray(B, dtype=np.float64)
    return np.sum(A[:, :, None] * B[None, :, :], axis=1)
