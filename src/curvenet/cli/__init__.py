# PYTHON_ARGCOMPLETE_OK
"""The ``curvenet`` command-line tool: a thin front over the library.

Each command lives in ``cmd_<name>.py`` with ``register(subparsers)`` and ``run(args) -> int``;
the options they share are in ``options.py``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from .._version import __version__
from .options import add_common  # noqa: F401  (kept importable from here)

__all__ = ["main", "COMMANDS"]

#: Command modules, in the order ``--help`` lists them.
COMMANDS = (
    "reconstruct",
    "info",
    "formats",
    "render",
    "view",
    "bench",
    "surface",
    "completion",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="curvenet",
        description="Reconstruct curve networks (nodes and curve segments) from unorganized 2D/3D points.",
    )
    parser.add_argument("--version", action="version", version=f"curvenet {__version__}")
    sub = parser.add_subparsers(title="commands", dest="command", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.cmd_{name}").register(sub)
    from .examples import HelpFormatter, epilog

    for name, p in sub.choices.items():
        p.epilog = epilog(name)
        p.formatter_class = HelpFormatter
    return parser


def main(argv=None, *, exiting: bool | None = None) -> int:
    """Run the command line; returns the exit code (0 ok, 1 method failure, 2 bad usage or input,
    130, 143, 129 stopped by Ctrl-C, SIGTERM, SIGHUP with nothing written).

    Parameters
    ----------
    argv : list of str, optional
        The arguments; by default the process's own command line.
    exiting : bool, optional
        Whether the process ends when this returns (default: when ``argv`` is None, as for the
        ``curvenet`` command): stopping signals then stay ignored after the run, so that one
        coming while the interpreter shuts down cannot report a finished run as stopped.
    """
    from ..errors import CurvenetError

    parser = build_parser()
    _autocomplete(parser)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    verbose = getattr(args, "verbose", False)
    from .._sigint import Stopped, deferred

    from ..io.atomic import all_or_nothing

    try:
        # Ctrl-C, SIGTERM, SIGHUP acted on at safe points (see curvenet._sigint); the files a
        # command writes are renamed into place together when it succeeds, else none
        with deferred(exiting=argv is None if exiting is None else exiting), all_or_nothing():
            return int(args.func(args) or 0)
    except CurvenetError as exc:
        if verbose:
            import traceback

            traceback.print_exc()
        print(f"curvenet: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except BrokenPipeError:  # output piped into e.g. head: stop quietly
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return 0
    except Stopped as exc:  # SIGTERM, SIGHUP: as a shell reports a process killed by them
        import signal

        print(f"curvenet: stopped by {signal.Signals(exc.signum).name}", file=sys.stderr)
        return 128 + exc.signum
    except KeyboardInterrupt:
        print("curvenet: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        print("curvenet: error: out of memory", file=sys.stderr)
        return 1
    except Exception as exc:  # a bug: say so in one line unless --verbose
        if verbose:
            raise
        print(f"curvenet: internal error: {type(exc).__name__}: {exc} (run with --verbose for details)", file=sys.stderr)
        return 1


def _autocomplete(parser: argparse.ArgumentParser) -> None:
    """Answer a shell's completion request (argcomplete; a no-op otherwise or without it)."""
    if "_ARGCOMPLETE" not in os.environ:
        return
    try:
        import argcomplete
    except ImportError:
        return
    # a prefix of two options (--sh: --shell-inner, --shell-outer) is an argparse error that
    # stops argcomplete's parse half way (argcomplete 3.7 then fails); complete it instead
    parsers = [parser] + [p for a in parser._subparsers._group_actions for p in a.choices.values()] \
        if parser._subparsers else [parser]
    for p in parsers:
        p.allow_abbrev = False
    argcomplete.autocomplete(parser)


def console() -> None:
    sys.exit(main())
