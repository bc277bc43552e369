"""Atomic file output: a temporary file in the target folder, then a rename."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .._sigint import checkpoint
from ..errors import OutputError

__all__ = ["atomic_write", "check_output_path"]


def check_output_path(path, *, inputs=()) -> Path:
    """Check that ``path`` can be written as an output.

    Parameters
    ----------
    path : str or Path
        The output file.
    inputs : iterable of str or Path
        Input files of the same run; the output must not be one of them.

    Returns
    -------
    Path

    Raises
    ------
    OutputError
        When the folder does not exist, the path is a folder, or it is one of the inputs.
    """
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"{p}: cannot write output, folder {parent} does not exist")
    if p.is_dir():
        raise OutputError(f"{p}: cannot write output, it is a folder")
    for q in inputs:
        try:
            same = Path(q).resolve() == p.resolve()
        except OSError:
            same = False
        if same:
            raise OutputError(f"{p}: output path is the same as the input file")
    return p


def atomic_write(path, data, *, inputs=()) -> Path:
    """Write ``data`` to ``path`` atomically.

    The data go to a temporary file in the same folder, which is flushed, synced and renamed over
    ``path``. If anything fails (including Ctrl-C), the temporary file is removed and an existing
    ``path`` is left untouched.

    Parameters
    ----------
    path : str or Path
        Target file.
    data : bytes or str
        Content; ``str`` is written as UTF-8.
    inputs : iterable of str or Path
        Input files that must not be overwritten.

    Returns
    -------
    Path
        The written path.
    """
    p = check_output_path(path, inputs=inputs)
    if isinstance(data, str):
        data = data.encode("utf-8")
    parent = p.parent if str(p.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        if p.exists():
            try:
                os.chmod(tmp, p.stat().st_mode & 0o7777)
            except OSError:
                pass
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        checkpoint()  # Ctrl-C pressed while writing: no file (see curvenet._sigint)
        os.replace(tmp, p)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            raise OutputError(f"{p}: cannot write output ({exc.strerror or exc})") from None
        raise
    return p
