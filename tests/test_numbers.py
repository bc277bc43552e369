"""curvenet.io.numbers: the text of every float is ``repr``'s (so it reads back bit for bit), with
orjson's bulk path and without it."""

from __future__ import annotations

import numpy as np
import pytest

from curvenet.io import numbers
from curvenet.io.numbers import int_lists, int_rows_text, ints_text, join_columns, rows_text, shortest, shortest_rows

EDGES = [0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 2.225073858507201e-308, 1.7976931348623157e308,
         -1.7976931348623157e308, np.inf, -np.inf, np.nan, 1e-4, -1e-4, 9.999999999999999e-05, 1e16, -1e16,
         9999999999999998.0, 1e15, 123456789012345678.0, 0.1, 0.3, 1 / 3, 2.0**53, 2.0**53 + 2, 1e22, 1e23, 5e-5,
         1e-7, 0.5, 1.0, 100.0, 123456.789]


def _values(rng, n: int) -> dict:
    return {
        "normal": rng.normal(size=n) * 10,
        # random bit patterns: every exponent, subnormals, inf and nan
        "bits": rng.integers(-2**63, 2**63, size=n, dtype=np.int64).view(np.float64),
        "subnormal": rng.integers(1, 2**52, size=n, dtype=np.int64).view(np.float64) * rng.choice([-1.0, 1.0], n),
        "float32": rng.normal(size=n).astype(np.float32).astype(np.float64),
        "wide": rng.normal(size=n) * 10.0 ** rng.integers(-8, 20, size=n),
        "short": np.round(rng.normal(size=n) * 100, 3),
        "edges": np.array(EDGES * 4),
    }


@pytest.fixture(params=[True, False], ids=["orjson", "repr"])
def bulk(request, monkeypatch):
    if request.param:
        pytest.importorskip("orjson")
    else:
        monkeypatch.setattr(numbers, "_orjson", lambda: None)
    return request.param


@pytest.mark.parametrize("kind", list(_values(np.random.default_rng(0), 1)))
def test_floats_are_repr(kind, bulk):
    a = _values(np.random.default_rng(1), 15_000)[kind]
    rows = a[: len(a) // 3 * 3].reshape(-1, 3)
    assert rows_text(rows, "v ", " ", "\n") == "".join("v " + " ".join(map(repr, r)) + "\n" for r in rows.tolist())
    assert shortest(a, ";") == ";".join(map(repr, a.tolist()))
    assert shortest_rows(rows, "[", ", ") == ["[" + ", ".join(map(repr, r)) for r in rows.tolist()]
    assert shortest_rows(rows, "", "\n") == ["\n".join(map(repr, r)) for r in rows.tolist()]
    finite = a[np.isfinite(a)]
    back = np.array([float(t) for t in shortest(finite).split()])
    assert np.array_equal(back.view(np.int64), finite.view(np.int64))  # bit for bit, signs of zero too


def test_integers(bulk):
    rng = np.random.default_rng(2)
    i = np.concatenate([rng.integers(-2**63, 2**63, size=3000, dtype=np.int64),
                        np.array([0, -1, 2**63 - 1, -2**63], dtype=np.int64)])
    assert ints_text(i, ",") == ",".join(map(str, i.tolist()))
    parts = [i[:0], i[:5], i[5:5], i[5:100], i[100:], i[:0]]
    assert int_lists(parts) == [" ".join(map(str, p.tolist())) for p in parts]
    r = i[:3000].reshape(-1, 3)
    assert int_rows_text(r, ",") == "".join(",".join(map(str, x)) + "\n" for x in r.tolist())


def test_empty_and_small(bulk):
    assert rows_text(np.zeros((0, 3)), "v ") == ""
    assert shortest([]) == ""
    assert shortest_rows(np.zeros((0, 2))) == []
    assert ints_text([]) == ""
    assert int_lists([]) == []
    assert rows_text([[1.0, 2.0]], "v ") == "v 1.0 2.0\n"
    assert join_columns(["a\nbb\n", "1\n2\n"]) == "a 1\nbb 2\n"
    assert join_columns(["", ""]) == ""


def _table_by_hand(a, glue, int_cols=(), groups=None) -> list[str] | str:
    def text(v, j):
        return str(int(v)) if (isinstance(v, int) or j in int_cols) else repr(v)

    rows = ["".join(text(v, j) + g for j, (v, g) in enumerate(zip(r, glue))) for r in a.tolist()]
    if groups is None:
        return "".join(rows)
    out = []
    for k0, k1 in zip(groups[:-1], groups[1:]):
        t = "".join(rows[k0:k1])
        out.append(t[: len(t) - len(glue[-1])] if k1 > k0 else "")
    return out


@pytest.mark.parametrize("piece", [None, 7], ids=["whole", "in-pieces"])
@pytest.mark.parametrize("kind", ["normal", "bits", "edges"])
def test_table_text(kind, piece, bulk, monkeypatch):
    from curvenet.io.numbers import group_texts, table_pieces, table_text

    if piece:  # the glue put in by pieces of a few bytes
        monkeypatch.setattr(numbers, "_FILL_PIECE", piece)

    rng = np.random.default_rng(3)
    a = _values(rng, 3000)[kind][:3000 // 4 * 4].reshape(-1, 4)
    a[:, 0] = rng.integers(-10**15, 10**15, size=len(a))  # an integer column among floats
    a[::7, 0] = 0
    groups = np.sort(np.r_[0, rng.integers(0, len(a), 40), len(a), len(a), 0, 3, 3])
    for glue in (["\n 10\n", ",", ", ", "\nVERTEX\n"], [" ", " ", " ", "\n"], ["", "x", ";", ""]):
        assert table_text(a, glue, int_cols=[0]) == _table_by_hand(a, glue, [0])
        want = _table_by_hand(a, glue, [0], groups.tolist())
        assert group_texts(a, glue, int_cols=[0], groups=groups) == want
        views = numbers.table_groups(a, glue, int_cols=[0], groups=groups, views=True)
        assert [bytes(v).decode() for v in views] == want
        pieces, fill = table_pieces(a, glue, int_cols=[0], groups=groups)
        assert b"".join(fill(b"|".join(pieces))).decode().split("|") == want
        assert table_text(a[:, 1:], glue[1:]) == _table_by_hand(a[:, 1:], glue[1:])
    i = rng.integers(-2**63, 2**63, size=(500, 2), dtype=np.int64)
    assert table_text(i, [",", "\n"]) == _table_by_hand(i, [",", "\n"])
    assert table_text(np.zeros((0, 2)), [" ", "\n"]) == ""
    assert group_texts(np.zeros((0, 2)), [" ", "\n"], groups=[0, 0, 0]) == ["", ""]
    with pytest.raises(ValueError):
        table_text(np.zeros((3, 2)), ["\n"])


def _g_values() -> np.ndarray:
    """Doubles of every magnitude, powers of ten and their neighbours, halves (rounding ties at
    low precision), integers, zeros of both signs, subnormals and non-finite values."""
    rng = np.random.default_rng(11)
    p10 = 10.0 ** np.arange(-300, 300)
    return np.concatenate([
        rng.normal(size=20000) * 10.0 ** rng.integers(-30, 30, 20000), rng.random(5000),
        np.round(rng.normal(size=5000), 3), p10, np.nextafter(p10, 0), np.nextafter(p10, np.inf),
        (rng.integers(1, 10**9, 5000) + 0.5) * 10.0 ** rng.integers(-12, 12, 5000),
        rng.integers(-10**12, 10**12, 5000).astype(float),
        [0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, -1e-310, 1e300, 1.5, 2.5, 0.5, 999999999.5, 9999999995.0],
    ])


@pytest.mark.parametrize("precision", [1, 4, 9, 12, 13, 17])
def test_g_matrix_is_percent_g(precision, bulk):
    x = _g_values()
    mat = numbers.g_matrix(x, precision)
    got = [row[row != 0].tobytes() for row in mat]
    want = [(f"%.{precision}g" % v).encode() for v in x.tolist()]
    assert got == want


def test_g_table_bytes(bulk):
    x = _g_values()[:30000].reshape(-1, 3)
    want = "".join("v %.9g %.9g %.9g\n" % tuple(r) for r in x.tolist()).encode()
    assert numbers.g_table_bytes(x, 9, [" ", " ", "\n"], "v ") == want
    assert numbers.g_table_bytes(np.zeros((0, 3)), 9, [" ", " ", "\n"]) == b""
    with pytest.raises(ValueError):
        numbers.g_matrix([1.0], 0)


def test_chunks_change_nothing(monkeypatch):
    """The bulk writers work in chunks of numbers.{_CHUNK} values (whole rows, whole groups):
    tiny chunks give the text of one chunk."""
    pytest.importorskip("orjson")
    rng = np.random.default_rng(12)
    x = rng.normal(size=(3000, 3)) * 10.0 ** rng.integers(-8, 8, (3000, 1))
    ints = rng.integers(-10**6, 10**6, (3000, 3))
    off = np.unique(np.r_[0, rng.integers(0, 3000, 200), 3000])
    off = np.insert(off, 5, off[5])  # an empty group
    xi = x.copy()
    xi[:, 1] = ints[:, 1]  # an integer column

    def run():
        return (numbers.table_bytes(x, [" ", " 1.5 ", "\n"]), numbers.table_groups(ints, [" ", " ", "\nf "], groups=off),
                numbers.g_table_bytes(x, 9, [" ", " ", "\n"], "v "),
                [bytes(v) for v in numbers.table_groups(xi, [" ", " 1.5 ", "\n"], groups=off, int_cols=[1], views=True)])

    whole = run()
    for chunk in (7, 100, 4096):
        monkeypatch.setattr(numbers, "_CHUNK", chunk)
        assert run() == whole


def test_table_chunks_join_to_the_table(monkeypatch):
    """table_chunks: pieces that join to table_bytes' text and decode one by one (non-ASCII
    glue, chunks and fill pieces of a few values and bytes)."""
    pytest.importorskip("orjson")
    rng = np.random.default_rng(14)
    a = rng.normal(size=(700, 3)) * 10.0 ** rng.integers(-8, 8, (700, 1))
    a[:, 0] = rng.integers(-10**6, 10**6, 700)
    glue = [" ", " → ", "\n"]
    want = _table_by_hand(a, glue, [0]).encode("utf-8")
    for chunk, piece in ((numbers._CHUNK, numbers._FILL_PIECE), (30, 7), (7, 3)):
        monkeypatch.setattr(numbers, "_CHUNK", chunk)
        monkeypatch.setattr(numbers, "_FILL_PIECE", piece)
        chunks = numbers.table_chunks(a, glue, int_cols=[0])
        assert b"".join(chunks) == want == numbers.table_bytes(a, glue, int_cols=[0])
        assert "".join(bytes(t).decode("utf-8") for t in chunks) == want.decode("utf-8")
        assert len(chunks) > 1 or chunk == numbers._CHUNK
    assert numbers.table_chunks(np.zeros((0, 3)), glue) == []
