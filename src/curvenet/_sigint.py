"""Holding Ctrl-C (and SIGTERM, SIGHUP) back while native code runs in several threads.

A KeyboardInterrupt raised in the main thread while numba's parallel kernels or scipy's
threaded k-d tree queries run can free arrays under their running threads, or break the wait
on them: the process crashes instead of stopping. :func:`held` blocks the stopping signals
(:data:`STOP_SIGNALS`) in the calling thread for the duration of such a call (threads started
meanwhile inherit the block); a signal received in between is delivered, and raised as usual,
as soon as the call returns.

Under :func:`deferred` (the command line), SIGTERM and SIGHUP are handled as Ctrl-C is: a request
acted on at the next :func:`checkpoint`, where :class:`Stopped` is raised (a KeyboardInterrupt
carrying the signal number), so that no temporary file is left behind. Once the outputs of a run
are being renamed into place (:func:`finishing`), the run is over: a stopping signal is ignored
from then on, so that an exit code of 130, 143 or 129 always means that no output was written.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["held", "deferred", "checkpoint", "finishing", "Stopped", "STOP_SIGNALS"]

#: The signals that stop the command line cleanly: Ctrl-C, ``kill``/``timeout``, a closed terminal.
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


class Stopped(KeyboardInterrupt):
    """Raised at a checkpoint for a stopping signal other than Ctrl-C (SIGTERM, SIGHUP).

    Attributes
    ----------
    signum : int
        The signal; the command line exits with ``128 + signum`` (143 for SIGTERM, 129 for
        SIGHUP), as a shell reports a process killed by it.
    """

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = int(signum)


#: Set by the handler of :func:`deferred` when a stopping signal came and was not yet acted on.
_pending = threading.Event()
#: The first such signal.
_pending_signum = [signal.SIGINT]
#: Set by :func:`finishing`: the run's outputs are being put into place, stopping signals are
#: ignored until :func:`deferred` ends.
_finishing = threading.Event()


def _stop(signum: int) -> KeyboardInterrupt:
    return KeyboardInterrupt() if signum == signal.SIGINT else Stopped(signum)


def checkpoint() -> None:
    """Raise KeyboardInterrupt (or :class:`Stopped`) if a stopping signal came under
    :func:`deferred` (a safe point); a no-op once the run is :func:`finishing`."""
    if _finishing.is_set():
        _pending.clear()
        return
    if _pending.is_set():
        _pending.clear()
        raise _stop(_pending_signum[0])


def finishing() -> None:
    """Mark the run under :func:`deferred` as over: its outputs are being renamed into place.

    From here to the end of :func:`deferred` a stopping signal is ignored and :func:`checkpoint`
    raises nothing: a signal that comes while or after the outputs are renamed cannot turn a
    run that wrote them into one reported as stopped (exit 130, 143, 129).
    """
    _finishing.set()


@contextmanager
def deferred(*, exiting: bool = False):
    """Turn Ctrl-C, SIGTERM and SIGHUP into a request acted on at the next :func:`checkpoint`
    (a second one interrupts at once). For the command line: Python's default handler raises
    KeyboardInterrupt wherever the main thread is, which can be inside code whose native
    threads are still running.

    Parameters
    ----------
    exiting : bool
        The process ends after the block (the ``curvenet`` command): the stopping signals are
        then left ignored instead of restored, so that one that comes while the interpreter
        shuts down (which can take a second after a large run) does not kill a process whose
        outputs are written, with the exit code of a stopped run.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        if _finishing.is_set():
            return  # the outputs are being put into place: the run is over
        if _pending.is_set():
            _pending.clear()
            raise _stop(_pending_signum[0])
        _pending_signum[0] = signum
        _pending.set()

    old = {}
    for s in STOP_SIGNALS:
        if s != signal.SIGINT and signal.getsignal(s) is signal.SIG_IGN:
            continue  # started under nohup: SIGHUP stays ignored
        old[s] = signal.signal(s, handler)
    _finishing.clear()
    try:
        yield
        checkpoint()
    finally:
        for s, h in old.items():
            signal.signal(s, signal.SIG_IGN if exiting else h)
        _pending.clear()
        _finishing.clear()


@contextmanager
def held():
    """Block the stopping signals in the main thread for the enclosed block (a no-op elsewhere)."""
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, set(STOP_SIGNALS))
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
    checkpoint()
