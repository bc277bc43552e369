"""Terminal feedback for the CLI: progress display of slow stages, timings, the summary table.

A stage that runs longer than :data:`PROGRESS_DELAY` seconds shows on standard error: as a bar
(rich) when standard error is a terminal, as one line when it ends otherwise (log style: its
number, name, detail and time). A stage that reports parts (the method's own stages, through
:meth:`Handle.method_stage`, the ``on_stage`` callback of :func:`curvenet.reconstruct`) shows
each part by name with its share of the work, and the time left once a part has ended
(:func:`eta_seconds`); off a terminal each part is a line of its own. A one-time numba compile is
announced on the stage it slows (:data:`COMPILE_NOTE`). Two environment variables change this
(used by the tests, handy in CI logs):

``CURVENET_PROGRESS``
    ``auto`` (default: bars on a terminal, lines for the slow stages elsewhere), ``always``
    (draw bars even when standard error is not a terminal), ``log`` (no bars: one line for every
    stage and part, however quick) or ``never``.
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

__all__ = ["Stages", "Handle", "print_summary", "summary_rows", "eta_seconds", "format_eta",
           "PROGRESS_DELAY", "COMPILE_NOTE"]

#: A stage's progress bar appears once it has run this many seconds.
PROGRESS_DELAY = 1.0

#: Said on the bar and as a log line when a stage will compile numba kernels first.
COMPILE_NOTE = "compiling numba kernels (once; later runs load them)"

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


def eta_seconds(elapsed: float, done: float) -> float | None:
    """Seconds left when the share ``done`` of the work took ``elapsed`` seconds.

    The rest is assumed to go at the same pace: ``elapsed * (1 - done) / done``.

    Parameters
    ----------
    elapsed : float
        Seconds spent so far.
    done : float
        Share of the work done, 0 to 1 (the measured shares of the stages that ended).

    Returns
    -------
    float or None
        None while nothing is done (the pace is unknown); 0 once all is done.

    Examples
    --------
    >>> eta_seconds(3.0, 0.25)
    9.0
    >>> eta_seconds(3.0, 0.0) is None
    True
    """
    if done >= 1:
        return 0.0
    if done <= 0 or elapsed < 0:
        return None
    return elapsed * (1 - done) / done


def format_eta(seconds: float | None) -> str:
    """The time left in words: ``""`` (unknown), ``"under 1 s left"``, ``"about 42 s left"``,
    ``"about 3 min left"``, ``"about 2 h 5 min left"``.

    Examples
    --------
    >>> format_eta(95)
    'about 2 min left'
    """
    if seconds is None:
        return ""
    if seconds < 1:
        return "under 1 s left"
    if seconds < 90:
        return f"about {round(seconds)} s left"
    minutes = round(seconds / 60)
    if minutes < 60:
        return f"about {minutes} min left"
    return f"about {minutes // 60} h {minutes % 60} min left"


class Handle:
    """What a stage yields: ``advance()`` moves a bar with a known total, ``method_stage`` (the
    ``on_stage`` callback of :func:`curvenet.reconstruct`) shows the part that begins."""

    def __init__(self, total, shown: str, emit, compiling: bool):
        self.total = total
        self.done = 0
        self._lock = threading.Lock()
        self._progress = None
        self._task = None
        self._shown = shown
        self._emit = emit  # emit(line text, seconds): a log line when the stage lines are wanted
        self._compiling = compiling
        self._t0 = time.perf_counter()
        self._part: tuple[str, float, float] | None = None  # (name, share, start)
        self._share_done = 0.0
        self.parts: list[tuple[str, float, float]] = []  # (name, share, seconds) of ended parts

    def advance(self, n: int = 1) -> None:
        with self._lock:
            self.done += n
            if self._progress is not None:
                self._progress.update(self._task, completed=self.done)

    def eta(self) -> float | None:
        """Seconds left in this stage from the shares of its ended parts (None: unknown, e.g.
        while kernels compile: the compile does not scale with the shares)."""
        if self._compiling or not self.parts:
            return None
        return eta_seconds(time.perf_counter() - self._t0, self._share_done)

    def _end_part(self) -> None:
        if self._part is None:
            return
        name, share, start = self._part
        dt = time.perf_counter() - start
        self.parts.append((name, share, dt))
        self._share_done = min(1.0, self._share_done + share)
        self._part = None
        left = format_eta(self.eta()) if self._share_done < 1 else ""
        self._emit(f"{self._shown} · {self._label(name, share)}", dt, left)

    @staticmethod
    def _label(name: str, share: float) -> str:
        return f"{name} ({share:.0%} of the work)" if share else name

    def method_stage(self, name: str, share: float) -> None:
        """Begin the part ``name`` worth ``share`` (0 to 1) of this stage's work (and end the
        previous one)."""
        with self._lock:
            self._end_part()
            self._part = (name, share, time.perf_counter())
            if self._progress is not None:
                self._update_bar()

    def _update_bar(self) -> None:
        note = COMPILE_NOTE if self._compiling else format_eta(self.eta())
        desc = self._shown + (f" · {self._part[0]} {self._part[1]:.0%}" if self._part else "")
        self._progress.update(self._task, description=desc, note=note,
                              total=100 if self._part or self.parts else self.total,
                              completed=100 * self._share_done if (self._part or self.parts) else self.done)

    def _close(self) -> None:
        with self._lock:
            self._end_part()


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
        tty = _isatty(self.file)
        self._log_all = not quiet and mode == "log"
        self._bars = not quiet and mode not in ("never", "log") and (mode == "always" or tty)
        # off a terminal (auto): a line for each stage or part that ran over the delay
        self._log_slow = not quiet and mode == "auto" and not tty
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

    def _line(self, text: str, seconds: float | None, note: str = "") -> None:
        """Print a log line on the stage stream: an announcement (``seconds`` None) in the log
        styles and with ``verbose`` (a bar says it otherwise); a stage or part that ended, with
        its time, in the log styles (``log``: every one; off a terminal: over the delay)."""
        if seconds is None:
            wanted = self._log_all or self._log_slow or self.verbose
        else:
            wanted = not self.verbose and (self._log_all or (self._log_slow and seconds >= self._delay))
        if wanted:
            tail = "" if seconds is None else f": {seconds:.2f} s"
            print(f"curvenet: {text}{tail}" + (f", {note}" if note else ""), file=self.file, flush=True)

    @contextmanager
    def stage(self, label: str, *, total: int | None = None, detail: str = "", compiling: bool = False):
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
        compiling : bool
            The stage compiles numba kernels first (:func:`curvenet.reconstruct.compile_pending`):
            :data:`COMPILE_NOTE` is shown on its bar and as a line when it begins (off a
            terminal), and no time left is estimated.

        Yields
        ------
        Handle
            With ``advance(n=1)`` for stages with a ``total`` and ``method_stage(name, share)``
            for stages of parts.
        """
        checkpoint()  # Ctrl-C pressed since the last stage: stop before starting this one
        self._count += 1
        number = f"[{self._count}/{self.n_stages}] " if self.n_stages else ""
        shown = number + label + (f" \u00b7 {detail}" if detail else "")
        handle = Handle(total, shown, self._line, compiling)
        if compiling:
            self._line(f"{shown}: {COMPILE_NOTE}", None)
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
                cols += [TextColumn("{task.fields[note]}"), TimeElapsedColumn()]
                prog = Progress(*cols, console=console, transient=True)
                with handle._lock:
                    task = prog.add_task(shown, total=total, completed=handle.done, note="")
                    handle._progress, handle._task = prog, task
                    handle._update_bar()
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
            handle._close()
            dt = time.perf_counter() - t0
            if timer is not None:
                timer.cancel()
            with lock:
                state["stopped"] = True
                if state["progress"] is not None:
                    state["progress"].stop()
            self.times[label] = self.times.get(label, 0.0) + dt
            self.info(f"  {label}: {dt:.3f} s")
            self._line(shown, dt)


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
