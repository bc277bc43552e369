"""Atomic file output: a temporary file in the target folder, then a rename.

One file: :func:`atomic_write`. Several files, all or nothing: inside :func:`all_or_nothing`,
:func:`atomic_write` only writes each file's temporary file; the renames happen together when
the block ends without error, and every temporary file is removed otherwise.
"""

from __future__ import annotations

import contextvars
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from .._sigint import checkpoint, finishing
from ..errors import OutputError

__all__ = ["atomic_write", "check_output_path", "check_outputs", "all_or_nothing", "TEMP_PREFIX", "TEMP_SUFFIX"]

#: Prefix and suffix of the temporary files, with 8 random characters between them: short, so
#: that the temporary name fits wherever the output name does.
TEMP_PREFIX = ".cn-"
TEMP_SUFFIX = ".tmp"

#: The longest file name when the system does not say (``NAME_MAX`` of Linux and macOS).
DEFAULT_NAME_MAX = 255

#: The outputs staged by the innermost :func:`all_or_nothing` (None outside).
_BATCH: contextvars.ContextVar = contextvars.ContextVar("curvenet_output_batch", default=None)


def _folder(p: Path) -> Path:
    return p.parent if str(p.parent) else Path(".")


def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return DEFAULT_NAME_MAX


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
        When the folder does not exist or cannot be written to, the name is too long for the
        file system, the path is a folder, or it is one of the inputs.
    """
    p = Path(path)
    parent = _folder(p)
    if not parent.is_dir():
        raise OutputError(f"{p}: cannot write output, folder {parent} does not exist")
    limit = _name_max(parent)
    if len(os.fsencode(p.name)) > limit:
        raise OutputError(f"{p}: cannot write output, the file name is longer than {limit} bytes")
    try:
        is_dir = p.is_dir()
    except OSError as exc:
        raise OutputError(f"{p}: cannot write output ({exc.strerror or exc})") from None
    if is_dir:
        raise OutputError(f"{p}: cannot write output, it is a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{p}: cannot write output, folder {parent} is not writable")
    for q in inputs:
        try:
            same = Path(q).resolve() == p.resolve()
        except OSError:
            same = False
        if same:
            raise OutputError(f"{p}: output path is the same as the input file")
    return p


def check_outputs(outputs, *, inputs=()) -> None:
    """Check every output of a run before the work: each path (see :func:`check_output_path`),
    and no file given twice for different contents.

    Parameters
    ----------
    outputs : iterable of (path, what)
        Each output with what it holds (e.g. ``"the network"``, ``"the mesh"``); the same path
        may come twice only for the same content.
    inputs : iterable of str or Path
        Input files of the run.

    Raises
    ------
    OutputError
    """
    seen: dict[Path, tuple[str, str]] = {}
    for path, what in outputs:
        p = check_output_path(path, inputs=inputs)
        key = p.resolve()
        if key in seen and seen[key][1] != what:
            raise OutputError(f"{p}: given as two outputs, {seen[key][1]} ({seen[key][0]}) and {what}")
        seen.setdefault(key, (str(path), what))


class _Batch:
    """Temporary files written and waiting for their renames: target -> (temporary, target)."""

    def __init__(self):
        self.staged: dict[Path, tuple[str, Path]] = {}

    def discard(self) -> None:
        for tmp, _ in self.staged.values():
            _unlink(tmp)
        self.staged.clear()

    def commit(self) -> None:
        checkpoint()  # a signal before the renames: no file changes
        finishing()  # a signal from here on: every file changes, and the run ends as done
        for key, (tmp, p) in list(self.staged.items()):
            try:
                os.replace(tmp, p)
            except OSError as exc:
                raise OutputError(f"{p}: cannot write output ({exc.strerror or exc})") from None
            del self.staged[key]


@contextmanager
def all_or_nothing():
    """Make the outputs written by :func:`atomic_write` inside the block all or nothing.

    Each output goes to its temporary file when written; when the block ends without error,
    every temporary file is renamed to its output, and on any error (a failed output,
    Ctrl-C, SIGTERM) every temporary file is removed and no output is written or changed.
    Under :func:`curvenet._sigint.deferred`, a stopping signal that comes once the renames
    have begun is ignored (:func:`curvenet._sigint.finishing`).
    A path written twice must get the same bytes.
    """
    batch = _Batch()
    token = _BATCH.set(batch)
    try:
        yield
        batch.commit()
    finally:
        _BATCH.reset(token)
        batch.discard()  # nothing left after a commit; every temporary file after an error


def _unlink(tmp) -> None:
    try:
        os.unlink(tmp)
    except OSError:
        pass


#: A ``str`` is written encoded this many characters at a time: each piece's bytes stay in the
#: processor's cache and reuse the same memory, where encoding a text of tens of MB at once
#: takes a fresh allocation whose pages the system zeroes first (0.05 s for the 80 MB of a
#: million-point SWC file).
ENCODE_PIECE = 1 << 20


def _encoded(data) -> Iterator[bytes]:
    """The bytes of ``data`` (UTF-8 for ``str``) in pieces of :data:`ENCODE_PIECE` characters;
    ``data`` an iterable of ``bytes`` and ``str`` pieces (a streamed document): each in turn."""
    if isinstance(data, str):
        for i in range(0, len(data), ENCODE_PIECE):
            yield data[i:i + ENCODE_PIECE].encode("utf-8")
    elif isinstance(data, (bytes, bytearray, memoryview)):
        yield data
    else:
        for piece in data:
            yield from _encoded(piece)


def _same_bytes(a: str, b: str) -> bool:
    """Whether the files ``a`` and ``b`` hold the same bytes (read back, not a digest)."""
    import filecmp

    try:
        return filecmp.cmp(a, b, shallow=False)
    except OSError as exc:
        raise OutputError(f"{b}: cannot read back a temporary output ({exc.strerror or exc})") from None


def _write_temp(p: Path, data) -> str:
    """Write ``data`` (``str`` as UTF-8; or an iterable of pieces, see :func:`_encoded`) to a
    new temporary file beside ``p`` (synced, with ``p``'s permissions or the default ones);
    returns its name. Removed again on any error."""
    parent = _folder(p)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=TEMP_SUFFIX, dir=parent)
        with os.fdopen(fd, "wb") as f:
            for piece in _encoded(data):
                f.write(piece)
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
        return tmp
    except BaseException as exc:
        if tmp is not None:
            _unlink(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            raise OutputError(f"{p}: cannot write output ({exc.strerror or exc})") from None
        raise


def atomic_write(path, data, *, inputs=()) -> Path:
    """Write ``data`` to ``path`` atomically.

    The data go to a temporary file in the same folder, which is flushed, synced and renamed over
    ``path``. If anything fails (including Ctrl-C), the temporary file is removed and an existing
    ``path`` is left untouched. Inside :func:`all_or_nothing` the rename waits for the end of
    the block.

    Parameters
    ----------
    path : str or Path
        Target file.
    data : bytes or str, or an iterable of them
        Content; ``str`` is written as UTF-8. An iterable (a generator) is written piece by
        piece as it yields them: a document too large to hold whole.
    inputs : iterable of str or Path
        Input files that must not be overwritten.

    Returns
    -------
    Path
        The written path.

    Raises
    ------
    OutputError
        When the file cannot be written, or (inside :func:`all_or_nothing`) when the same path
        was written before with other bytes.
    """
    p = check_output_path(path, inputs=inputs)
    batch = _BATCH.get()
    if batch is None:
        tmp = _write_temp(p, data)
        try:
            os.replace(tmp, p)
        except BaseException as exc:
            _unlink(tmp)
            if isinstance(exc, OSError):
                raise OutputError(f"{p}: cannot write output ({exc.strerror or exc})") from None
            raise
        return p
    key = p.resolve()
    tmp = _write_temp(p, data)
    if key in batch.staged:
        # (rare: compared when it happens, so that no write pays for a digest of its bytes)
        same = _same_bytes(tmp, batch.staged[key][0])
        _unlink(tmp)
        if not same:
            raise OutputError(f"{p}: written twice in one run with different contents")
        return p
    batch.staged[key] = (tmp, p)
    return p
