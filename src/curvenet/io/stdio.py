"""Standard input and output as ``-``: points read from a pipe, a network written to one.

Readers take files, so the bytes of standard input go to a temporary file named after the
given format (``stdin.xyz``...) and are read from there; errors name ``<stdin>``.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import BinaryIO, Sequence

import numpy as np

from ..errors import CurvenetError, FormatError

__all__ = ["STDIO", "read_points_stdin", "stdout_extension", "write_stdout"]

#: The path that stands for standard input or standard output.
STDIO = "-"


def _extension(fmt: str | None, what: str) -> str:
    if not fmt:
        raise FormatError(f"{what} needs --format (e.g. --format xyz): there is no file extension to go by")
    return "." + str(fmt).strip().lower().lstrip(".")


def stdout_extension(fmt: str | None) -> str:
    """The writer extension of ``--output-format`` (``"json"`` -> ``".json"``)."""
    return _extension(fmt, "standard output (-o -)")


def read_points_stdin(
    fmt: str | None,
    *,
    columns: Sequence[int | str] | None = None,
    drop_nonfinite: bool = False,
    stream: BinaryIO | None = None,
) -> np.ndarray:
    """Read points from standard input (or ``stream``) in the format ``fmt`` (an extension).

    Parameters
    ----------
    fmt : str
        A readable extension without or with the dot: ``"xyz"``, ``".csv"``, ``"npy"``...
    columns, drop_nonfinite
        As in :func:`curvenet.io.read_points`.
    stream : binary file, optional
        Standard input's buffer by default.

    Returns
    -------
    (N, d) ndarray of float64

    Raises
    ------
    FormatError
        Without a format, with an unknown one, or when the data do not parse (the message
        names ``<stdin>``).
    """
    from . import READERS, read_points

    ext = _extension(fmt, "standard input (-)")
    if ext not in READERS:
        raise FormatError(f"<stdin>: unknown point format {ext!r}; readable: {', '.join(sorted(READERS))}")
    data = (stream if stream is not None else sys.stdin.buffer).read()
    with tempfile.TemporaryDirectory(prefix="curvenet-stdin-") as tmp:
        path = Path(tmp) / f"stdin{ext}"
        path.write_bytes(data)
        try:
            return read_points(path, columns=columns, drop_nonfinite=drop_nonfinite)
        except CurvenetError as exc:
            exc.args = (str(exc).replace(str(path), "<stdin>"),) + exc.args[1:]
            raise


def write_stdout(data: str | bytes, stream: BinaryIO | None = None) -> None:
    """Write a writer's text or bytes to standard output (or ``stream``, a binary file)."""
    out = stream if stream is not None else sys.stdout.buffer
    out.write(data.encode("utf-8") if isinstance(data, str) else data)
    out.flush()
