"""Options shared by every command of the command line."""

from __future__ import annotations

import argparse

__all__ = ["add_common"]


def add_common(p: argparse.ArgumentParser) -> None:
    """The options every command has: ``--quiet`` and ``--verbose``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The parser of one command.
    """
    g = p.add_mutually_exclusive_group()
    g.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    g.add_argument("-v", "--verbose", action="store_true", help="print more, and tracebacks on errors")
