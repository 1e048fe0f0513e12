"""The package's exception hierarchy: every expected failure is a `GyrodriftError`.

An expected failure is one the user can fix: a malformed file (log, model file, scenario, run table),
an option out of range, data the Rust core refuses, a Dask scheduler that cannot be reached. The CLI turns
exactly these (and `OSError`, the file system's failures) into one line on stderr and exit status 1;
anything else is a bug and keeps its traceback.

Each concrete error also derives from the built-in class callers already catch (`ValueError` for bad
data and options, `ImportError` for a missing optional dependency), so ``except ValueError`` keeps working.
"""

from __future__ import annotations

__all__ = [
    "GyrodriftError",
    "InputError",
    "MissingExtraError",
    "CoreError",
    "OptionError",
    "OutputError",
]


class GyrodriftError(Exception):
    """Base of every expected failure of the package; its message is meant for the user as it is."""


class InputError(GyrodriftError, ValueError):
    """An input file or value that cannot be used; the message names the file (row, column) or option."""


class OptionError(InputError):
    """A command option or function argument out of its range; the message names the option."""


class OutputError(GyrodriftError, OSError):
    """An output location that must not or cannot be written; the message names the path and the reason."""


class CoreError(InputError):
    """The Rust core refused its configuration or data; the message names the quantity and its limit."""


class MissingExtraError(GyrodriftError, ImportError):
    """An optional part of gyrodrift whose extra is not installed; the message says which ``pip install`` adds it."""
