"""The exception hierarchy of curvenet.

Every error that curvenet raises on purpose derives from :class:`CurvenetError`, so a caller can
catch one type. The command-line tool prints ``str(error)`` as a one-line message and exits with
:attr:`CurvenetError.exit_code`.
"""

from __future__ import annotations

__all__ = [
    "CurvenetError",
    "InputError",
    "FormatError",
    "OutputError",
    "MethodError",
    "MissingDependencyError",
]


class CurvenetError(Exception):
    """Base class of every error curvenet raises on purpose."""

    #: Exit code of the command-line tool for this kind of error.
    exit_code = 2


class InputError(CurvenetError, ValueError):
    """Input points or arguments are invalid (wrong shape, non-finite values, too few points...)."""


class FormatError(InputError):
    """A file cannot be read: unknown extension, malformed or truncated content."""


class OutputError(CurvenetError, OSError):
    """An output file cannot be written (missing folder, same path as the input...)."""


class MethodError(CurvenetError, RuntimeError):
    """A reconstruction method failed on valid input."""

    exit_code = 1


class MissingDependencyError(CurvenetError, ImportError):
    """An optional dependency needed for a feature is not installed."""

    exit_code = 1

    def __init__(self, package: str, feature: str, extra: str):
        super().__init__(
            f"{feature} needs the optional package '{package}': "
            f"install it with pip install \"curvenet[{extra}]\""
        )
        self.package = package
        self.extra = extra


def require(module: str, feature: str, extra: str, package: str | None = None):
    """Import an optional module, or raise :class:`MissingDependencyError`.

    Parameters
    ----------
    module : str
        Module to import, e.g. ``"plyfile"``.
    feature : str
        What needs it, for the message (e.g. ``"reading PLY files"``).
    extra : str
        The extra of curvenet that installs it.
    package : str, optional
        The PyPI name when it differs from the module name.

    Returns
    -------
    module
        The imported module.
    """
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingDependencyError(package or module, feature, extra) from None
