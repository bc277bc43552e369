"""Terminal feedback for the CLI: progress display of slow stages, timings, the summary table.

Progress bars (rich) appear on standard error only when a stage runs longer than
:data:`PROGRESS_DELAY` seconds, standard error is a terminal and rich is installed; otherwise
nothing is drawn. Two environment variables change this (used by the tests, handy in CI logs):

``CURVENET_PROGRESS``
    ``auto`` (default), ``always`` (draw even when standard error is not a terminal),
    ``log`` (no bars: one line per stage on standard error when it ends, with its number, name,
    detail and time; for CI logs and batch jobs) or ``never``.
``CURVENET_PROGRESS_DELAY``
    Seconds a stage must run before its bar appears (default 1).

The summary table has the columns of the founding paper's Table 1; it is a rich table on a
terminal and plain aligned text otherwise (or without rich).
"""

from __future__ import annotations

import os
import sys
import threading
import time
from contextlib import contextmanager

from .._sigint import checkpoint

__all__ = ["Stages", "print_summary", "summary_rows", "PROGRESS_DELAY"]

#: A stage's progress bar appears once it has run this many seconds.
PROGRESS_DELAY = 1.0

#: Values of ``CURVENET_PROGRESS``.
PROGRESS_MODES = ("auto", "always", "log", "never")


def _progress_mode() -> str:
    mode = os.environ.get("CURVENET_PROGRESS", "auto").strip().lower()
    return mode if mode in PROGRESS_MODES else "auto"


def _delay() -> float:
    try:
        return max(0.0, float(os.environ.get("CURVENET_PROGRESS_DELAY", PROGRESS_DELAY)))
    except ValueError:
        return PROGRESS_DELAY


def _isatty(f) -> bool:
    try:
        return bool(f.isatty())
    except (AttributeError, ValueError):
        return False


class _Handle:
    """What a stage yields: ``advance()`` moves a bar with a known total."""

    def __init__(self, total):
        self.total = total
        self.done = 0
        self._lock = threading.Lock()
        self._progress = None
        self._task = None

    def advance(self, n: int = 1) -> None:
        with self._lock:
            self.done += n
            if self._progress is not None:
                self._progress.update(self._task, completed=self.done)


class Stages:
    """Run the named stages of a command, with delayed progress bars and verbose timings.

    Parameters
    ----------
    quiet : bool
        Print nothing (errors are printed by the CLI main).
    verbose : bool
        Print each stage's time on standard error when it ends.
    file : text stream, optional
        Where progress and timings go (standard error by default).
    stages : int, optional
        How many stages the command runs: bars and log lines then number them ``[i/n]``.

    Examples
    --------
    >>> st = Stages(quiet=True)
    >>> with st.stage("reading"):
    ...     pass
    >>> list(st.times)
    ['reading']
    """

    def __init__(self, *, quiet: bool = False, verbose: bool = False, file=None, stages: int | None = None):
        self.quiet = quiet
        self.verbose = verbose and not quiet
        self.file = file if file is not None else sys.stderr
        self.times: dict[str, float] = {}
        self.n_stages = stages
        self._count = 0
        mode = _progress_mode()
        self._log = not quiet and mode == "log"
        self._bars = not quiet and mode not in ("never", "log") and (mode == "always" or _isatty(self.file))
        if self._bars:
            try:
                import rich  # noqa: F401
            except ImportError:
                self._bars = False
        self._delay = _delay()

    def info(self, message: str) -> None:
        """Print a line on the stage stream when ``verbose``."""
        if self.verbose:
            print(message, file=self.file, flush=True)

    @contextmanager
    def stage(self, label: str, *, total: int | None = None, detail: str = ""):
        """Time a stage; show a bar (pulsing, or of ``total`` steps, with an ETA) if it runs long.

        Parameters
        ----------
        label : str
            The stage's name.
        total : int, optional
            Steps of the stage (files to write...): the bar then counts them and estimates the
            time left.
        detail : str
            Shown after the name (e.g. ``"1,108 points"``).

        Yields
        ------
        handle
            With ``advance(n=1)`` for stages with a ``total``.
        """
        checkpoint()  # Ctrl-C pressed since the last stage: stop before starting this one
        self._count += 1
        number = f"[{self._count}/{self.n_stages}] " if self.n_stages else ""
        shown = number + label + (f" \u00b7 {detail}" if detail else "")
        handle = _Handle(total)
        lock = threading.Lock()
        state = {"progress": None, "stopped": False}

        def start():
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                Progress,
                SpinnerColumn,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            with lock:
                if state["stopped"]:
                    return
                console = Console(file=self.file, force_terminal=_progress_mode() == "always" or None)
                cols = [SpinnerColumn(), TextColumn("[bold]{task.description}"), BarColumn()]
                if total is not None:
                    cols += [TextColumn("{task.completed}/{task.total}"), TimeRemainingColumn()]
                cols.append(TimeElapsedColumn())
                prog = Progress(*cols, console=console, transient=True)
                with handle._lock:
                    task = prog.add_task(shown, total=total, completed=handle.done)
                    handle._progress, handle._task = prog, task
                prog.start()
                state["progress"] = prog

        timer = None
        if self._bars:
            timer = threading.Timer(self._delay, start)
            timer.daemon = True
            timer.start()
        t0 = time.perf_counter()
        try:
            yield handle
        finally:
            dt = time.perf_counter() - t0
            if timer is not None:
                timer.cancel()
            with lock:
                state["stopped"] = True
                if state["progress"] is not None:
                    state["progress"].stop()
            self.times[label] = self.times.get(label, 0.0) + dt
            self.info(f"  {label}: {dt:.3f} s")
            if self._log and not self.verbose:
                print(f"curvenet: {shown}: {dt:.2f} s", file=self.file, flush=True)


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:.3g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {_fmt(x)}" for k, x in v.items()) + "}"
    return str(v)


def summary_rows(net, name: str):
    """Header and row of the summary, in the form of the paper's Table 1.

    Returns
    -------
    head : list of str
        ``Model, N_n, N_c, N_d, eps, tau_S, theta, Time(s)``
    row : list of str
    """
    p = net.parameters
    t = net.stats.get("time", {}).get("total")
    head = ["Model", "N_n", "N_c", "N_d", "eps", "tau_S", "theta", "Time(s)"]
    row = [name, str(net.n_nodes), str(net.n_curves), _fmt(net.stats.get("N_d")),
           _fmt(p.get("epsilon")), _fmt(p.get("tau_s")), _fmt(p.get("theta")),
           "-" if t is None else f"{t:.3f}"]
    return head, row


def print_summary(net, name: str, outputs=(), *, file=None, fancy: bool | None = None) -> None:
    """Print the result in the form of the paper's Table 1, then the other parameters and outputs.

    Parameters
    ----------
    net : CurveNetwork
    name : str
        The model name (the input file's stem).
    outputs : iterable of str
        Files written, listed after the table.
    file : text stream, optional
        Standard output by default.
    fancy : bool, optional
        Draw a rich table; by default when ``file`` is a terminal and rich is installed.
    """
    file = file if file is not None else sys.stdout
    head, row = summary_rows(net, name)
    other = {k: v for k, v in net.parameters.items() if k not in ("epsilon", "tau_s", "theta")}
    b0, b1 = net.betti
    if fancy is None:
        fancy = _isatty(file)
    if fancy:
        try:
            from rich.console import Console
            from rich.table import Table
        except ImportError:
            fancy = False
    if fancy:
        console = Console(file=file)
        table = Table(title="curvenet reconstruction", title_justify="left")
        pretty = ["Model", "N_n", "N_c", "N_d", "\u03b5", "\u03c4_S", "\u03b8(\u00b0)", "Time(s)"]
        for i, h in enumerate(pretty):
            table.add_column(h, justify="left" if i == 0 else "right")
        table.add_row(*row)
        console.print(table)
        console.print(f"Betti numbers b0={b0} b1={b1}", highlight=False)
        if other:
            console.print("parameters: " + ", ".join(f"{k}={_fmt(v)}" for k, v in other.items()), highlight=False)
        for out in outputs:
            console.print(f"wrote {out}", highlight=False)
        return
    w = [max(len(a), len(b)) for a, b in zip(head, row)]
    print("  ".join(a.ljust(n) for a, n in zip(head, w)).rstrip(), file=file)
    print("  ".join(b.ljust(n) for b, n in zip(row, w)).rstrip(), file=file)
    print(f"Betti numbers b0={b0} b1={b1}", file=file)
    if other:
        print("parameters: " + ", ".join(f"{k}={_fmt(v)}" for k, v in other.items()), file=file)
    for out in outputs:
        print(f"wrote {out}", file=file)
