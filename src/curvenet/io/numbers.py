"""Numbers as text: floats as the shortest decimal that reads back to the same float64.

Text writers use these instead of a fixed ``%.17g`` (which writes ``0.49955899999999998`` for
``0.499559``): the text of a float is exactly Python's ``repr`` of it (the shortest string that
round-trips, David Gay's algorithm), so every value reads back bit for bit and files stay small.

``repr`` costs about half a microsecond a value, seconds for the million points of a large
network. With ``orjson`` installed (extra ``fast``) whole arrays are written at once in native
code (the Ryu algorithm: the same shortest digits, correctly rounded), about ten times faster:
in the range that ``repr`` writes without exponent, ``1e-4 <= |x| < 1e16``, and for zeros of
either sign, orjson's text is ``repr``'s to the byte (``tests/test_numbers.py`` checks millions
of random doubles); any other value (``1e-07``, ``1e+16``, subnormals, ``inf``, ``nan``: rare in
coordinates) goes to orjson as NaN, which it writes ``null``, and that word is replaced by the
value's ``repr``. Without orjson every value goes through ``repr``: the same text, only slower.

:func:`table_bytes` is the bulk path of every text writer: the numbers of a whole table in one
orjson call, then the text around them (separators, line ends, the fixed tags of a DXF entity)
put in by a few passes over the bytes instead of a Python string per value.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "shortest", "shortest_rows", "rows_text", "ints_text", "int_lists", "int_rows_text", "join_columns", "table_bytes",
    "table_chunks",
    "table_groups", "table_pieces", "table_text", "group_texts", "REPR_RANGE", "g_matrix",
    "g_table_bytes",
]

#: The magnitudes that ``repr`` writes without exponent (and orjson writes the same way):
#: ``REPR_RANGE[0] <= |x| < REPR_RANGE[1]``, and zero.
REPR_RANGE = (1e-4, 1e16)

#: Below this many values ``repr`` is as fast as a call into orjson.
_SMALL = 64


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


#: Bytes that stand for the glue of a column in the bulk text until they are replaced by it:
#: control characters that no number's text holds (tab, line feed and carriage return left out,
#: which glue may hold).
_MARKS = bytes(b for b in range(1, 32) if b not in (9, 10, 13))


#: The bulk writers take at most this many values at a time (rows or groups of rows): the text
#: of a chunk (about 2 MB) stays in the processor's cache through the passes over it (orjson's,
#: the search of the commas, the marking, the glue), which made the SWC table of a million
#: points 1.1 -> 0.8 s of processor time.
_CHUNK = 1 << 17

#: The glue goes into a long text in pieces of this many bytes: each piece stays in the
#: processor's cache through the passes of ``bytes.replace`` (one a glue), which made the
#: glue of a DXF's vertices 0.25 -> 0.15 s of processor time at a million points.
_FILL_PIECE = 1 << 20


def _bulk(a: np.ndarray) -> bytes:
    """``repr`` (``str`` for integers) of every value of a flat array, joined by ``,``
    (orjson, the values unlike ``repr``'s rewritten by ``repr``)."""
    if a.dtype.kind != "f":
        return _dumps(a)[1:-1]
    bad = _unlike_repr(a)
    if not bad.any():
        return _dumps(a)[1:-1]
    return b"".join(_with_repr(a, bad, b""))


def _with_repr(a: np.ndarray, bad: np.ndarray, last: bytes) -> list:
    """The pieces of the text of :func:`_bulk` of float values ``a`` whose values ``bad`` (a
    mask, a few) are unlike ``repr``'s: orjson's text of the others (the bad ones as NaN, which
    it writes ``null``) in views between the ``repr`` of the bad ones, then ``last``; a pass of
    ``bytes.find`` from one ``null`` to the next (of its ``n``, a byte no number's text holds: a
    search by ``memchr``) instead of a split of the whole text."""
    text = _dumps(np.where(bad, np.nan, a))
    view = memoryview(text)
    pieces: list = []
    at = 1  # after "["
    for x in a[bad].tolist():
        i = text.find(b"n", at)
        pieces += [view[at:i], repr(x).encode()]
        at = i + 4
    pieces += [view[at:len(text) - 1], last]  # (without the "]")
    return pieces


def _comma_text(a: np.ndarray) -> bytearray:
    """:func:`_bulk` of a flat array with a comma after every value (the last too), as a
    mutable text for the marking passes: orjson's ``[...]`` copied once, its brackets turned
    into that last comma (without a copy of the text for the slice and one for the comma)."""
    bad = _unlike_repr(a) if a.dtype.kind == "f" else None
    if bad is not None and bad.any():
        return bytearray().join(_with_repr(a, bad, b","))
    body = bytearray(_dumps(a))
    body[-1] = 44  # "]" -> ","
    del body[0]  # "[" (a move within the buffer)
    return body


def _value_texts(a: np.ndarray, int_cols: Sequence[int]) -> list[list[str]]:
    """The text of every value of an (n, m) array, row by row, without orjson."""
    m = a.shape[1]
    fmt = [str if (a.dtype.kind != "f" or j in int_cols) else repr for j in range(m)]
    conv = [(lambda v: str(int(v))) if (a.dtype.kind == "f" and j in int_cols) else f for j, f in enumerate(fmt)]
    return [[conv[j](v) for j, v in enumerate(r)] for r in a.tolist()]


def _table_input(
    rows: ArrayLike, glue: Sequence[str | bytes], groups: ArrayLike | None
) -> tuple[np.ndarray, list[bytes], np.ndarray | None]:
    """The checked arguments of :func:`table_bytes`: a C-ordered (n, m) float64 or int64
    array, the glue as bytes, the group offsets (or None)."""
    a = np.asarray(rows)
    if a.dtype.kind not in "fiu":
        a = a.astype(np.float64)
    a = np.ascontiguousarray(a, dtype=np.float64 if a.dtype.kind == "f" else np.int64)
    if a.ndim != 2 or a.shape[1] != len(glue) or not len(glue):
        raise ValueError(f"rows must be (n, {len(glue)}) for {len(glue)} glue strings, got shape {a.shape}")
    g = [x.encode() if isinstance(x, str) else bytes(x) for x in glue]
    return a, g, None if groups is None else np.asarray(groups, dtype=np.int64)


def table_bytes(rows: ArrayLike, glue: Sequence[str | bytes], *, int_cols: Sequence[int] = ()) -> bytes:
    """Every row of an (n, m) array as text: each value followed by the glue of its column.

    The bulk path of every text writer: the numbers of all rows are written in one orjson call
    and the glue goes in by a few passes over the bytes, without a Python object per value.

    Parameters
    ----------
    rows : (n, m) array_like of float or int
        Float values are written as ``repr`` writes them, integers as ``str`` does.
    glue : sequence of m str or bytes
        ``glue[j]`` follows each value of column ``j`` (``glue[m - 1]`` ends a row).
    int_cols : sequence of int
        Columns of a float array that hold integers (of magnitude below 2**53), written as
        integers (``7``, not ``7.0``).

    Returns
    -------
    bytes

    Examples
    --------
    >>> table_bytes([[1.0, 0.5], [2.0, 1e-7]], [" ", "\\n"], int_cols=[0])
    b'1 0.5\\n2 1e-07\\n'
    """
    return b"".join(table_chunks(rows, glue, int_cols=int_cols))


def table_chunks(rows: ArrayLike, glue: Sequence[str | bytes], *, int_cols: Sequence[int] = ()) -> list[bytes | bytearray]:
    """:func:`table_bytes` in pieces, for a caller that joins them with text of its own or
    decodes them one by one: no copy of the whole text (a fresh allocation of tens of MB, whose
    pages the system zeroes on first touch, costs as much as writing it).

    Parameters
    ----------
    rows, glue, int_cols
        As for :func:`table_bytes`.

    Returns
    -------
    list of bytes or bytearray
        Pieces of whole values and glue (each valid UTF-8 when the glue is), joined in order
        the text of :func:`table_bytes`.
    """
    a, g, _ = _table_input(rows, glue, None)
    if not len(a):
        return []
    step = max(1, _CHUNK // a.shape[1])
    if len(a) > step and _orjson() is not None:  # rows in chunks: the passes over them stay in cache
        return [t for i in range(0, len(a), step) for t in table_chunks(a[i:i + step], g, int_cols=int_cols)]
    if a.size < _SMALL or _orjson() is None:
        return [b"".join(t.encode() + x for r in _value_texts(a, int_cols) for t, x in zip(r, g))]
    cols = tuple(int_cols) if a.dtype.kind == "f" else ()
    if a.shape[1] == 1 and not cols:
        return [_bulk(a.ravel()).replace(b",", g[0]) + g[0]]
    body, fill, _ = _marked(a, g, cols, None)
    return fill(body)


def table_groups(
    rows: ArrayLike, glue: Sequence[str | bytes], *, groups: ArrayLike, int_cols: Sequence[int] = (),
    views: bool = False,
) -> list[bytes] | list[bytes | memoryview]:
    """:func:`table_bytes` of each group of rows, each without the glue after its last value.

    Parameters
    ----------
    rows, glue, int_cols
        As for :func:`table_bytes`.
    groups : (g + 1,) array_like of int
        Row offsets: group ``k`` is rows ``groups[k]:groups[k + 1]``.
    views : bool
        Return each group's text as a ``memoryview`` into the text of a chunk of groups
        instead of as ``bytes`` of its own: for a caller that joins the groups (with text
        between them) into one text, which then copies each byte once.

    Returns
    -------
    list of g bytes (or memoryview, with ``views``)

    Examples
    --------
    >>> table_groups([[1.0], [2.0], [3.0]], [";"], groups=[0, 2, 2, 3])
    [b'1.0;2.0', b'', b'3.0']
    """
    a, g, off = _table_input(rows, glue, groups)
    assert off is not None
    cuts = _chunk_groups(off, a.shape[1])
    if len(cuts) > 2 and _orjson() is not None:  # whole groups in chunks of about _CHUNK values
        return [t for ga, gb in zip(cuts[:-1], cuts[1:]) for t in
                table_groups(a[off[ga]:off[gb]], g, groups=off[ga:gb + 1] - off[ga], int_cols=int_cols, views=views)]
    if not len(a) or a.size < _SMALL or _orjson() is None:
        return table_pieces(a, g, groups=off, int_cols=int_cols)[0]  # (the glue in already)
    body, fill, group_mark = _marked(a, g, tuple(int_cols) if a.dtype.kind == "f" else (), off)
    text = b"".join(fill(body))
    if views:
        return _views(text, group_mark[0], off)
    return _grouped(text.split(group_mark), off)


def _chunk_groups(off: np.ndarray, m: int) -> list[int]:
    """Group indices that cut groups of rows (offsets ``off``, ``m`` values a row) into chunks
    of about :data:`_CHUNK` values (a group larger than that is a chunk of its own): the first
    group of each chunk, then ``len(off) - 1``."""
    if not len(off) or off[-1] * m <= _CHUNK:
        return [0, max(len(off) - 1, 0)]
    cuts = np.unique(np.searchsorted(off, np.arange(0, off[-1], max(1, _CHUNK // m)), side="right") - 1)
    return np.append(cuts[cuts < len(off) - 1], len(off) - 1).tolist()


def _grouped(pieces: list, off: np.ndarray) -> list[bytes]:
    """The text of each group from the pieces of the nonempty groups (empty groups get ``b""``)."""
    out = [b""] * (len(off) - 1)
    for k, piece in zip(np.flatnonzero(np.diff(off) > 0).tolist(), pieces):
        out[k] = bytes(piece)
    return out


def _views(text: bytes | bytearray, group_mark: int, off: np.ndarray,
           ends: np.ndarray | None = None) -> list[bytes | memoryview]:
    """The text of each group as a view into ``text``, whose nonempty groups each end with the
    byte ``group_mark`` (at ``ends`` when known, else found by ``bytes.find``: ``memchr``, where
    a numpy comparison of every byte costs ten times more); empty groups get ``b""``."""
    view = memoryview(text)
    out: list[bytes | memoryview] = [b""] * (len(off) - 1)
    full = np.flatnonzero(np.diff(off) > 0).tolist()
    if ends is not None:
        starts = np.concatenate([[0], ends[:-1] + 1])
        for k, a, b in zip(full, starts.tolist(), ends.tolist()):
            out[k] = view[a:b]
        return out
    mark, at = bytes([group_mark]), 0
    for k in full:
        b = text.find(mark, at)
        out[k] = view[at:b]
        at = b + 1
    return out


def _marked(
    a: np.ndarray, glue: list[bytes], int_cols: tuple, off: np.ndarray | None
) -> tuple[bytearray, Callable[[bytes | bytearray], list[bytes | bytearray]], bytes]:
    """The numbers of ``a`` with the comma after each value replaced by its column's glue when
    that is one byte long, by a mark (a control character) otherwise, and by a group mark at the
    end of each group; the ``.0`` of the integer columns marked for deletion.

    Returns the text, the function that replaces the marks by their glue (returning the text in
    pieces, to be joined), and the group mark.
    Only one-byte patterns are searched (``bytes.replace`` of a longer one costs a function
    call per match).
    """
    n, m = a.shape
    body = _comma_text(a.ravel())  # every value followed by a comma
    buf = np.frombuffer(body, dtype=np.uint8)
    commas = np.flatnonzero(buf == 44)
    free = [c for c in _MARKS if c not in set(b"".join(glue))]
    todo = []  # (mark, glue) replaced after the marking
    for j, g in enumerate(glue):
        if len(g) == 1:
            buf[commas[j::m]] = g[0]
        else:
            mark = free.pop()
            buf[commas[j::m]] = mark
            todo.append((bytes([mark]), g))
    group_mark = bytes([free.pop()])
    if off is not None:
        ends = off[1:][np.diff(off) > 0]
        buf[commas[ends * m - 1]] = group_mark[0]
    todo.sort(key=lambda mg: len(mg[1]))
    if int_cols:  # the ".0" of integers goes with the first pass of the glue
        cut = free.pop()
        for j in int_cols:
            buf[commas[j::m] - 1] = cut
            buf[commas[j::m] - 2] = cut
        todo.insert(0, (bytes([cut]), b""))

    def fill_piece(text: bytes | bytearray) -> bytes | bytearray:
        for mark, g in todo:
            text = text.replace(mark, g)
        return text

    def fill(text: bytes | bytearray) -> list[bytes | bytearray]:
        if not todo:
            return [text]
        return [fill_piece(text[i:i + _FILL_PIECE]) for i in range(0, len(text), _FILL_PIECE)]

    return body, fill, group_mark


def table_pieces(
    rows: ArrayLike, glue: Sequence[str | bytes], *, groups: ArrayLike, int_cols: Sequence[int] = ()
) -> tuple[list[bytes], Callable[[bytes | bytearray], list[bytes | bytearray]]]:
    """:func:`table_groups` with the glue put in later, for text around the groups.

    A text made of the groups and text of the caller's (free of control characters other than
    tab and line ends) joined in one piece is passed once to ``fill``, which puts in the glue:
    the long glue (a DXF entity's tags between two numbers) goes into the whole text at once
    instead of into each group.

    Parameters
    ----------
    rows, glue, int_cols
        As for :func:`table_bytes`.
    groups : (g + 1,) array_like of int
        Row offsets of the groups.

    Returns
    -------
    pieces : list of g bytes
        The groups, with marks where the glue goes.
    fill : callable
        ``fill(text)``: ``text`` (bytes) with the marks replaced by the glue, as a list of
        pieces to be joined (``[text]`` when the pieces hold their glue already).
    """
    a, g, off = _table_input(rows, glue, groups)
    assert off is not None
    if not len(a):
        return [b""] * (len(off) - 1), _as_is
    if a.size < _SMALL or _orjson() is None:
        texts = _value_texts(a, int_cols)
        out = []
        for k0, k1 in zip(off[:-1].tolist(), off[1:].tolist()):
            b = b"".join(t.encode() + x for r in texts[k0:k1] for t, x in zip(r, g))
            out.append(b[: len(b) - len(g[-1])] if k1 > k0 else b"")
        return out, _as_is
    body, fill, group_mark = _marked(a, g, tuple(int_cols) if a.dtype.kind == "f" else (), off)
    return _grouped(body.split(group_mark), off), fill


def _as_is(text: bytes | bytearray) -> list[bytes | bytearray]:
    """The ``fill`` of a text that holds its glue already."""
    return [text]


def table_text(rows: ArrayLike, glue: Sequence[str], *, int_cols: Sequence[int] = ()) -> str:
    """:func:`table_bytes` as ``str`` (its pieces decoded one by one: no copy of the whole text
    as bytes)."""
    return "".join([t.decode("utf-8") for t in table_chunks(rows, glue, int_cols=int_cols)])


def group_texts(rows: ArrayLike, glue: Sequence[str], *, groups: ArrayLike, int_cols: Sequence[int] = ()) -> list[str]:
    """:func:`table_groups` as ``str``."""
    return [str(b, "utf-8") for b in table_groups(rows, glue, groups=groups, int_cols=int_cols)]


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
    a = _as_rows(np.asarray(rows, dtype=np.float64))
    n, m = a.shape
    if n == 0:
        return ""
    if m == 0:
        return (prefix + end) * n
    text = prefix + table_text(a, [sep] * (m - 1) + [end + prefix])
    return text[: len(text) - len(prefix)]


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
    if not len(a):
        return ""
    text = table_text(a.reshape(-1, 1), [sep])
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
    n, m = a.shape
    if n == 0:
        return []
    if m == 0:
        return [prefix] * n
    return [prefix + t for t in group_texts(a, [sep] * (m - 1) + [""], groups=np.arange(n + 1))]


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
    a = np.asarray(values).ravel().astype(np.int64)
    if not len(a):
        return ""
    text = table_text(a.reshape(-1, 1), [sep])
    return text[: len(text) - len(sep)]


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
    arrays = [np.asarray(x).ravel().astype(np.int64) for x in arrays]
    if not arrays:
        return []
    sizes = np.array([len(x) for x in arrays], dtype=np.int64)
    flat = np.concatenate(arrays).reshape(-1, 1)
    return group_texts(flat, [sep], groups=np.concatenate([[0], np.cumsum(sizes)]))


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
    a = _as_rows(np.asarray(rows)).astype(np.int64)
    n, m = a.shape
    if not n:
        return ""
    if m == 0:
        return end * n
    return table_text(a, [sep] * (m - 1) + [end])


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


# ------------------------------------------------------------------ %g with a fixed precision
#: Precisions that :func:`g_matrix` computes in bulk: the scaled value (below 10**precision)
#: keeps a margin of a thousand of its ulps to the nearest rounding tie; above, ``%`` writes all.
G_BULK_PRECISION = 12

#: Magnitudes computed in bulk by :func:`g_matrix` (powers of ten within float64's range and
#: scaled values far from subnormal); zeros too. Others go through ``%``.
G_BULK_RANGE = (1e-290, 1e290)

#: Relative error bound of the scaled value ``|x| * 10**k`` (the power and the product each
#: rounded: under 2 ulps), times a safety factor of 1000: values whose scaled fraction lies this
#: close to one half are written by ``%`` (a few in a million at precision 9).
_G_TIE_MARGIN = 1e3 * 2.0**-51


#: 10.0 ** k for k = 0..308 (numpy's power of each; a table: ``**`` of an array is slow).
_POW10 = 10.0 ** np.arange(309)


def _g_digits(ax: np.ndarray, p: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Decimal exponent (n,), ``p``-digit integer mantissa (n,) and a mask of the values too
    close to a rounding tie to trust (n,), for positive finite ``ax`` in :data:`G_BULK_RANGE`:
    ``ax`` rounded to ``p`` significant digits is ``m * 10**(e - p + 1)``."""

    def scaled(e: np.ndarray) -> np.ndarray:
        k = p - 1 - e
        return np.where(k >= 0, ax * _POW10[np.maximum(k, 0)], ax / _POW10[np.maximum(-k, 0)])

    e = np.floor(np.log10(ax)).astype(np.int64)
    s = scaled(e)
    off = (s >= 10.0**p).astype(np.int64) - (s < 10.0 ** (p - 1))  # log10 one off near 10**k
    if off.any():
        e += off
        s = scaled(e)
    frac = s - np.floor(s)
    unsure = (np.abs(frac - 0.5) <= _G_TIE_MARGIN * s) | (s < 10.0 ** (p - 1)) | (s >= 10.0**p)
    m = np.floor(s + 0.5).astype(np.int64)
    up = m == 10**p  # rounded up to the next power of ten
    m[up] //= 10
    return e + up, m, unsure


def _digit_chars(m: np.ndarray, p: int) -> np.ndarray:
    """(n, p) ASCII digits of integers ``m`` (n,) of exactly ``p`` digits (orjson writes them
    when installed: a tenth of the time of numpy's divisions)."""
    if _orjson() is not None and len(m):
        text = np.frombuffer(_dumps(np.ascontiguousarray(m, dtype=np.int64)), dtype=np.uint8)
        return text[1:].reshape(len(m), p + 1)[:, :p].copy()  # each number then ',' (the last: ']')
    pw = 10 ** np.arange(p - 1, -1, -1, dtype=np.int64)
    return ((m[:, None] // pw) % 10 + ord("0")).astype(np.uint8)


def g_matrix(values: ArrayLike, precision: int, out: np.ndarray | None = None) -> np.ndarray:
    """``"%.{precision}g" % v`` of every value, as rows of bytes padded with NUL bytes.

    The padding may sit anywhere in a row (where ``%g`` drops trailing zeros, the sign of a
    positive value); removing every NUL byte of the row leaves the text. Rows of several
    columns side by side with glue columns between them, then all NUL bytes removed, make a
    table's text (:func:`g_table_bytes`).

    Parameters
    ----------
    values : (n,) array_like of float
    precision : int
        Significant digits, at least 1. Up to :data:`G_BULK_PRECISION`, values are converted
        with numpy (several times faster than ``%``); the values near a rounding tie, outside
        :data:`G_BULK_RANGE` (but zeros) or not finite go through ``%``.
    out : (n, precision + 7) uint8 ndarray, optional
        Where to write (all NUL on entry), e.g. columns of a larger table.

    Returns
    -------
    (n, precision + 7) uint8 ndarray
        ``out`` when given.
    """
    x = np.asarray(values, dtype=np.float64).ravel()
    p = int(precision)
    if p < 1:
        raise ValueError(f"precision must be at least 1, got {precision}")
    if out is None:
        out = np.zeros((len(x), p + 7), dtype=np.uint8)
    out[:, 0] = np.where(np.signbit(x), ord("-"), 0)
    ax = np.abs(x)
    done = (ax >= G_BULK_RANGE[0]) & (ax < G_BULK_RANGE[1]) if p <= G_BULK_PRECISION else np.zeros(len(x), bool)
    e, m, unsure = _g_digits(ax[done], p)
    done[np.flatnonzero(done)[unsure]] = False
    _g_layout(out, done, e[~unsure], m[~unsure], p)
    zero = x == 0
    out[zero, 1] = ord("0")
    for i in np.flatnonzero(~done & ~zero).tolist():
        t = (f"%.{p}g" % x[i]).encode()
        out[i, :] = 0
        out[i, :len(t)] = np.frombuffer(t, dtype=np.uint8)
    return out


def _g_layout(out: np.ndarray, rows: np.ndarray, e: np.ndarray, m: np.ndarray, p: int) -> None:
    """Write the ``%g`` text of mantissas ``m`` (r,) with exponents ``e`` (r,) into the rows
    ``rows`` (a mask) of ``out`` from column 1 on: fixed notation for ``-4 <= e < p``, else
    ``d.ddde+XX``; trailing zeros of the fraction (and a point left alone) are left NUL.

    The rows are sorted by their layout (the exponent, or "scientific") so that each layout is
    written into a block of consecutive rows by slices, then put in place in one copy."""
    fixed = (e >= -4) & (e < p)
    key = np.where(fixed, e + 4, p + 4).astype(np.int16)  # 0 .. p + 4
    order = np.argsort(key, kind="stable")
    key, e, chars = key[order], e[order], _digit_chars(m[order], p)
    ints = np.where((key >= 4) & (key < p + 4), key - 3, 1)  # digits before the point (1 in "d.ddde+XX")
    nz = np.zeros(len(e), dtype=np.int16)  # digits up to the last nonzero one
    for j in range(p):
        np.maximum(nz, (chars[:, j] != ord("0")) * np.int16(j + 1), out=nz)
    chars *= np.arange(p, dtype=np.int16) < np.maximum(nz, ints)[:, None]  # trailing zeros of the fraction
    dot = np.where(nz > ints, ord("."), 0).astype(np.uint8)
    body = np.zeros((len(e), out.shape[1] - 1), dtype=np.uint8)
    starts = np.searchsorted(key, np.arange(p + 6))
    for k in range(p + 5):
        a, b = starts[k], starts[k + 1]
        if a < b:
            _g_block(body[a:b], chars[a:b], dot[a:b], e[a:b], k - 4, p)
    if rows.all():  # a gather by the inverse order is faster than a scatter
        inverse = np.empty_like(order)
        inverse[order] = np.arange(len(order))
        out[:, 1:] = body[inverse]
    else:
        out[np.flatnonzero(rows)[order], 1:] = body


def _g_block(body: np.ndarray, chars: np.ndarray, dot: np.ndarray, e: np.ndarray, x: int, p: int) -> None:
    """The ``%g`` texts of one layout: fixed notation with exponent ``x`` (``-4 <= x < p``), or
    scientific (``x == p``), written into ``body`` (r, p + 6) from the digits ``chars`` (r, p)
    (trailing zeros NUL), the points ``dot`` (r,) and the exponents ``e`` (r,)."""
    if 0 <= x < p:  # d..d.ddd
        body[:, :x + 1] = chars[:, :x + 1]
        body[:, x + 1] = dot
        body[:, x + 2:p + 1] = chars[:, x + 1:]
    elif x < 0:  # 0.000ddd
        body[:, 0] = ord("0")
        body[:, 1] = ord(".")
        body[:, 2:1 - x] = ord("0")
        body[:, 1 - x:1 - x + p] = chars
    else:  # d.ddde+XX
        a = np.abs(e)
        body[:, 0] = chars[:, 0]
        body[:, 1] = dot
        body[:, 2:p + 1] = chars[:, 1:]
        body[:, p + 1] = ord("e")
        body[:, p + 2] = np.where(e < 0, ord("-"), ord("+"))
        body[:, p + 3] = np.where(a >= 100, a // 100 + ord("0"), 0)
        body[:, p + 4] = (a // 10) % 10 + ord("0")
        body[:, p + 5] = a % 10 + ord("0")


def g_table_bytes(rows: ArrayLike, precision: int, glue: Sequence[str | bytes], prefix: str | bytes = b"") -> bytes:
    """Every row of an (n, m) float array as text: ``prefix``, then each value as
    ``"%.{precision}g"`` writes it followed by the glue of its column.

    Parameters
    ----------
    rows : (n, m) array_like of float
    precision : int
        Significant digits (see :func:`g_matrix`).
    glue : sequence of m str or bytes
        ``glue[j]`` follows each value of column ``j``; no NUL bytes.
    prefix : str or bytes
        Text before each row; no NUL bytes.

    Returns
    -------
    bytes
        The text ``%`` writes with the format ``prefix + "%.9g" + glue[0] + ...`` for each row.

    Examples
    --------
    >>> g_table_bytes([[1.0, 0.1 + 0.2], [-0.0, 1e-7]], 9, [" ", "\\n"], "v ")
    b'v 1 0.3\\nv -0 1e-07\\n'
    """
    a = np.asarray(rows, dtype=np.float64)
    a = a.reshape(-1, 1) if a.ndim == 1 else a
    n, m = a.shape
    g = [x.encode() if isinstance(x, str) else bytes(x) for x in glue]
    pre = prefix.encode() if isinstance(prefix, str) else bytes(prefix)
    if len(g) != m:
        raise ValueError(f"rows must be (n, {len(g)}) for {len(g)} glue strings, got shape {a.shape}")
    if not n:
        return b""
    step = max(1, _CHUNK // m)
    if n > step:  # rows in chunks: the passes over them stay in cache
        return b"".join(g_table_bytes(a[i:i + step], precision, g, pre) for i in range(0, n, step))
    w = int(precision) + 7
    table = np.zeros((n, len(pre) + m * w + sum(map(len, g))), dtype=np.uint8)
    at = 0
    for j, text in enumerate([pre] + [b""] * m):
        if j:
            g_matrix(a[:, j - 1], precision, out=table[:, at:at + w])
            at += w
            text = g[j - 1]
        table[:, at:at + len(text)] = np.frombuffer(text, dtype=np.uint8)
        at += len(text)
    return table.tobytes().translate(None, b"\x00")
