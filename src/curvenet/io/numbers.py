"""Floats as text: the shortest decimal string that reads back to the same float64.

Text writers use these instead of a fixed ``%.17g`` (which writes ``0.49955899999999998`` for
``0.499559``): Python's ``repr`` of a float is the shortest string that round-trips
(David Gay's algorithm), so every value reads back bit for bit and files stay small.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["shortest", "shortest_rows"]


def shortest(values: ArrayLike, sep: str = " ") -> str:
    """The values as shortest round-trip decimals, joined by ``sep``.

    Parameters
    ----------
    values : array_like of float
        Any shape; flattened in C order.
    sep : str
        Separator.

    Returns
    -------
    str

    Examples
    --------
    >>> shortest([0.499559, 1.0, 1e-7])
    '0.499559 1.0 1e-07'
    """
    return sep.join(map(repr, np.asarray(values, dtype=np.float64).ravel().tolist()))


def shortest_rows(rows: ArrayLike, prefix: str = "", sep: str = " ") -> list[str]:
    """One line per row of an (n, m) array: ``prefix`` then the row's shortest decimals.

    Parameters
    ----------
    rows : (n, m) array_like of float
    prefix : str
        Text before each row (e.g. ``"v "`` for OBJ vertices).
    sep : str
        Separator between the values of a row.

    Returns
    -------
    list of str
    """
    a = np.asarray(rows, dtype=np.float64)
    return [prefix + sep.join(map(repr, r)) for r in a.reshape(len(a), -1).tolist()]
