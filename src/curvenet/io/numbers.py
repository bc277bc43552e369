"""Numbers as text: floats as the shortest decimal that reads back to the same float64.

Text writers use these instead of a fixed ``%.17g`` (which writes ``0.49955899999999998`` for
``0.499559``): the text of a float is exactly Python's ``repr`` of it (the shortest string that
round-trips, David Gay's algorithm), so every value reads back bit for bit and files stay small.

``repr`` costs about half a microsecond a value, seconds for the million points of a large
network. With ``orjson`` installed (extra ``fast``) whole arrays are written at once in native
code (the Ryu algorithm: the same shortest digits, correctly rounded), about ten times faster:
in the range that ``repr`` writes without exponent, ``1e-4 <= |x| < 1e16``, and for zeros of
either sign, orjson's text is ``repr``'s to the byte (``tests/test_numbers.py`` checks millions
of random doubles); the rows holding any other value (``1e-07``, ``1e+16``, subnormals, ``inf``,
``nan``: rare in coordinates) are rewritten by ``repr``. Without orjson every value goes through
``repr``: the same text, only slower.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "shortest", "shortest_rows", "rows_text", "ints_text", "int_lists", "int_rows_text", "join_columns", "REPR_RANGE",
]

#: The magnitudes that ``repr`` writes without exponent (and orjson writes the same way):
#: ``REPR_RANGE[0] <= |x| < REPR_RANGE[1]``, and zero.
REPR_RANGE = (1e-4, 1e16)

#: Below this many values ``repr`` is as fast as a call into orjson.
_SMALL = 64

#: Row marker inside orjson's text (orjson never writes a zero byte).
_MARK = b"\x00"


def _orjson() -> Any:
    """orjson with its numpy option, or None when it is not installed."""
    try:
        import orjson
    except ImportError:
        return None
    return orjson


def _dumps(a: Any) -> bytes:
    import orjson

    return orjson.dumps(a, option=orjson.OPT_SERIALIZE_NUMPY)


def _unlike_repr(a: np.ndarray) -> np.ndarray:
    """Mask of the values whose orjson text differs from ``repr``'s (see the module doc)."""
    with np.errstate(invalid="ignore"):
        ax = np.abs(a)
        return ~(((ax >= REPR_RANGE[0]) & (ax < REPR_RANGE[1])) | (a == 0))


def _as_rows(a: np.ndarray) -> np.ndarray:
    """``a`` as an (n, m) array (m = 1 for a 1D one; an empty one keeps its columns)."""
    if a.ndim == 1:
        return a.reshape(-1, 1)
    return a.reshape(len(a), -1) if a.size else a.reshape(len(a), a.shape[-1] if a.ndim > 1 else 0)


def _repr_row(row: np.ndarray, sep: str) -> str:
    return sep.join(map(repr, row.tolist()))


def _patch_rows(body: bytes, bad: np.ndarray, a: np.ndarray, sep: str) -> bytes:
    """``body`` (rows apart by :data:`_MARK`) with the rows ``bad`` rewritten by ``repr``."""
    marks = np.flatnonzero(np.frombuffer(body, dtype=np.uint8) == _MARK[0])
    starts = np.concatenate([[0], marks + 1])
    ends = np.concatenate([marks, [len(body)]])
    pieces = []
    prev = 0
    for i in bad.tolist():
        pieces += [body[prev:starts[i]], _repr_row(a[i], sep).encode()]
        prev = int(ends[i])
    pieces.append(body[prev:])
    return b"".join(pieces)


def rows_text(rows: ArrayLike, prefix: str = "", sep: str = " ", end: str = "\n") -> str:
    """Each row of an (n, m) array as a line: ``prefix``, the row's shortest decimals joined by
    ``sep``, then ``end``.

    Parameters
    ----------
    rows : (n, m) array_like of float
    prefix, sep, end : str
        Text before each row, between its values and after it.

    Returns
    -------
    str
        Every value as ``repr`` writes it.

    Examples
    --------
    >>> rows_text([[0.499559, 1.0], [1e-7, -0.0]], "v ")
    'v 0.499559 1.0\\nv 1e-07 -0.0\\n'
    """
    a = np.ascontiguousarray(_as_rows(np.asarray(rows, dtype=np.float64)))
    n, m = a.shape
    if n == 0:
        return ""
    if m == 0 or a.size < _SMALL or _orjson() is None:
        return "".join(prefix + _repr_row(r, sep) + end for r in a)
    body = _dumps(a)[2:-2].replace(b"],[", _MARK).replace(b",", sep.encode())
    bad = np.flatnonzero(_unlike_repr(a).any(axis=1))
    if len(bad):
        body = _patch_rows(body, bad, a, sep)
    return prefix + body.replace(_MARK, (end + prefix).encode()).decode("ascii") + end


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
        ``sep.join(map(repr, values))``.

    Examples
    --------
    >>> shortest([0.499559, 1.0, 1e-7])
    '0.499559 1.0 1e-07'
    """
    a = np.asarray(values, dtype=np.float64).ravel()
    if len(a) < _SMALL or _orjson() is None:
        return sep.join(map(repr, a.tolist()))
    text = rows_text(a.reshape(-1, 1), "", "", sep)
    return text[: len(text) - len(sep)]


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
    a = _as_rows(np.asarray(rows, dtype=np.float64))
    if a.size < _SMALL or _orjson() is None:
        return [prefix + _repr_row(r, sep) for r in a]
    return rows_text(a, prefix, sep, "\x00").split("\x00")[:-1]


def ints_text(values: ArrayLike, sep: str = " ") -> str:
    """Integers as decimal text joined by ``sep`` (``str`` of each).

    Parameters
    ----------
    values : array_like of int
        Any shape; flattened in C order.
    sep : str

    Returns
    -------
    str
    """
    a = np.ascontiguousarray(np.asarray(values).ravel(), dtype=np.int64)
    if len(a) < _SMALL or _orjson() is None:
        return sep.join(map(str, a.tolist()))
    return _dumps(a)[1:-1].decode("ascii").replace(",", sep)


def int_lists(arrays: Sequence[np.ndarray], sep: str = " ") -> list[str]:
    """:func:`ints_text` of each array of a list (one call for all: many short arrays).

    Parameters
    ----------
    arrays : sequence of (m_i,) array_like of int
    sep : str

    Returns
    -------
    list of str
    """
    arrays = [np.ascontiguousarray(np.asarray(x).ravel(), dtype=np.int64) for x in arrays]
    if not arrays:
        return []
    if sum(len(x) for x in arrays) < _SMALL or _orjson() is None:
        return [sep.join(map(str, x.tolist())) for x in arrays]
    return _dumps(arrays)[2:-2].decode("ascii").replace(",", sep).split("]" + sep + "[")


def int_rows_text(rows: ArrayLike, sep: str = " ", end: str = "\n") -> str:
    """Each row of an (n, m) integer array as a line: its values joined by ``sep``, then ``end``.

    Parameters
    ----------
    rows : (n, m) array_like of int
    sep, end : str

    Returns
    -------
    str
    """
    a = np.ascontiguousarray(_as_rows(np.asarray(rows)), dtype=np.int64)
    if not len(a):
        return ""
    if a.shape[1] == 0 or a.size < _SMALL or _orjson() is None:
        return "".join(sep.join(map(str, r)) + end for r in a.tolist())
    body = _dumps(a)[2:-2].replace(b"],[", _MARK).replace(b",", sep.encode())
    return body.replace(_MARK, end.encode()).decode("ascii") + end


def join_columns(blocks: Sequence[str], sep: str = " ", end: str = "\n") -> str:
    """Lines side by side: line ``i`` of the result is line ``i`` of each block joined by ``sep``.

    Parameters
    ----------
    blocks : sequence of str
        Texts of the same number of lines, each line ended by ``end``.
    sep, end : str

    Returns
    -------
    str
    """
    cols = [b.split(end)[:-1] if b else [] for b in blocks]
    if not cols or not cols[0]:
        return ""
    if any(len(c) != len(cols[0]) for c in cols):
        raise ValueError("blocks of different numbers of lines")
    return end.join(map(sep.join, zip(*cols))) + end
