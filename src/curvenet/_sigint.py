"""Holding Ctrl-C back while native code runs in several threads.

A KeyboardInterrupt raised in the main thread while numba's parallel kernels or scipy's
threaded k-d tree queries run can free arrays under their running threads, or break the wait
on them: the process crashes instead of stopping. :func:`held` blocks SIGINT in the calling
thread for the duration of such a call (threads started meanwhile inherit the block); a Ctrl-C
pressed in between is delivered, and raised as usual, as soon as the call returns.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["held", "deferred", "checkpoint"]

#: Set by the handler of :func:`deferred` when Ctrl-C was pressed and not yet acted on.
_pending = threading.Event()


def checkpoint() -> None:
    """Raise KeyboardInterrupt if Ctrl-C was pressed under :func:`deferred` (a safe point)."""
    if _pending.is_set():
        _pending.clear()
        raise KeyboardInterrupt


@contextmanager
def deferred():
    """Turn Ctrl-C into a request acted on at the next :func:`checkpoint` (a second Ctrl-C
    interrupts at once). For the command line: Python's default handler raises
    KeyboardInterrupt wherever the main thread is, which can be inside code whose native
    threads are still running."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        if _pending.is_set():
            raise KeyboardInterrupt
        _pending.set()

    old = signal.signal(signal.SIGINT, handler)
    try:
        yield
        checkpoint()
    finally:
        signal.signal(signal.SIGINT, old)
        _pending.clear()


@contextmanager
def held():
    """Block SIGINT in the main thread for the enclosed block (a no-op elsewhere)."""
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
    checkpoint()
