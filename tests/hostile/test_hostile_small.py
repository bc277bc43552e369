"""Issue 20 item 8: the smaller promises (bad --param values, odd files, row numbers, Ctrl-C
during a read, a network without curves)."""

import signal
import threading

import numpy as np
import pytest

from curvenet import FormatError
from curvenet.cli import main
from curvenet.io import read_points


@pytest.fixture
def ring(tmp_path):
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    f = tmp_path / "ring.xyz"
    np.savetxt(f, np.column_stack([np.cos(t), np.sin(t), 0 * t]))
    return f


@pytest.mark.parametrize("param, words", [
    ("k=abc", "parameter 'k' of method 'robust' must be an integer or none, got 'abc'"),
    ("k=5.5", "parameter 'k' of method 'robust' must be an integer"),
    ("spacing=wide", "parameter 'spacing' of method 'robust' must be a number"),
    ("fit=3", "parameter 'fit' of method 'robust' must be true or false or none"),
])
def test_bad_param_values_exit_2_naming_the_parameter(ring, capsys, param, words):
    """On main: an internal TypeError (exit 1)."""
    assert main(["reconstruct", str(ring), "-p", param]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1


def test_structured_npy_with_a_string_field(tmp_path):
    a = np.zeros(5, dtype=[("x", "f8"), ("y", "U4"), ("z", "f8")])
    f = tmp_path / "s.npy"
    np.save(f, a)
    with pytest.raises(FormatError, match=r"s\.npy: field 'y' holds <U4, not numbers"):
        read_points(f)


@pytest.mark.parametrize("text", ["1 2 3\n", "1 2 3\n4 5 6\n", "1 2 3\n" * 30])
def test_too_few_or_identical_points_name_the_file(tmp_path, capsys, text):
    f = tmp_path / "few.xyz"
    f.write_text(text)
    assert main(["reconstruct", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"curvenet: error: {f}: ") and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("text, row", [
    ("1 2 3\n4 abc 6\n7 8 9\n", 2),  # a conversion error (numpy counts these from 0)
    ("# c\n\n1 2 3\n# c\n4 5 6\nx 8 9\n", 3),
    ("1 2 3\n4 5 6\n7 8\n", 3),  # a column count error (numpy counts these from 1)
    ("1 2 3\nnan 5 6\n", 2),  # the NaN error
])
def test_rows_are_counted_from_1_in_every_error(tmp_path, text, row):
    f = tmp_path / "p.xyz"
    f.write_text(text)
    with pytest.raises(Exception, match=rf"data rows? {row}\b"):
        read_points(f)


def test_a_latin1_byte_in_a_comment_is_ignored(tmp_path):
    f = tmp_path / "p.xyz"
    f.write_bytes(b"# mesur\xe9 \xe0 Gen\xe8ve\n1 2 3\n4 5 6 # \xb0C\n7 8 9\n")
    assert np.array_equal(read_points(f), [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    f.write_bytes(b"1 2 3\n4 \xe9 6\n")
    with pytest.raises(FormatError, match="data row 2"):
        read_points(f)


def test_ctrl_c_during_a_long_read_stops_it(tmp_path, monkeypatch):
    """A single Ctrl-C under the command line's handler stops the read at the next block (on
    main, the whole file was read first)."""
    from curvenet import _sigint
    from curvenet.io import points

    f = tmp_path / "p.xyz"
    np.savetxt(f, np.random.default_rng(0).random((2000, 3)))
    monkeypatch.setattr(points, "TEXT_CHUNK_BYTES", 4096)
    real = np.loadtxt
    calls = []

    def loadtxt(*a, **k):
        calls.append(1)
        if len(calls) == 1:
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)
        return real(*a, **k)

    monkeypatch.setattr(points.np, "loadtxt", loadtxt)
    with pytest.raises(KeyboardInterrupt):
        with _sigint.deferred():
            read_points(f)
    assert len(calls) == 1  # (2000 rows are about 12 blocks)
    monkeypatch.undo()
    assert len(read_points(f)) == 2000  # read in blocks, the same points
    assert np.array_equal(read_points(f), np.loadtxt(f))


def test_a_network_without_curves_is_said_and_explained(capsys):
    """On main the paper's method gave the mug 0 curves with exit 0 and no word."""
    from pathlib import Path

    mug = Path(__file__).resolve().parents[2] / "examples" / "mug.xyz"
    assert main(["reconstruct", str(mug), "--method", "paper"]) == 0
    err = capsys.readouterr().err
    assert "warning: the network has no curves" in err and "lower --tau-s" in err
    assert main(["reconstruct", str(mug), "--method", "paper", "--epsilon", "0.9"]) == 0
    assert "lower --epsilon" in capsys.readouterr().err


@pytest.mark.parametrize("raw", [b"# c\rx y z\r1 2 3\r4 5 6\r", b"# c\r\nx,y,z\r\n1,2,3\r\n4,5,6\r\n"])
def test_cr_and_crlf_line_ends(tmp_path, raw):
    """The block reader splits lines as the header detection does (\\n, \\r\\n, \\r)."""
    f = tmp_path / "p.csv"
    f.write_bytes(raw)
    assert np.array_equal(read_points(f), [[1, 2, 3], [4, 5, 6]])
