"""The package's exception hierarchy: every expected failure is a `GyrodriftError`.

An expected failure is one the user can fix: a malformed file (log, model file, scenario, run table),
an option out of range, data the Rust core refuses, a Dask scheduler that cannot be reached. The CLI turns
exactly these (and `OSError`, the file system's failures) into one line on stderr and exit status 1;
anything else is a bug and keeps its traceback.

Each concrete error also derives from the built-in class callers already catch (`ValueError` for bad
data and options, `ImportError` for a missing optional dependency), so ``except ValueError`` keeps working.

The Rust core's refusals are `CoreError`, one subclass per kind of `gyrodrift_core::error::CoreError` (mapped once
in the binding, crates/gyrodrift-py/src/errors.rs, as polars maps its errors): `CoreSettingError` (also an
`OptionError`), `CoreShapeError`, `CoreSampleError`, `CoreDivergedError` and `CoreIncompleteError`, each with the
core's fields as attributes.
"""

from __future__ import annotations

__all__ = [
    "GyrodriftError",
    "InputError",
    "MissingExtraError",
    "CoreError",
    "CoreSettingError",
    "CoreShapeError",
    "CoreSampleError",
    "CoreDivergedError",
    "CoreIncompleteError",
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
    """The Rust core refused its configuration or data; the message names the quantity and its limit.

    The base of the core's five kinds below (the binding raises only those); ``key`` names the setting or input
    by its SI keyword (e.g. ``"lat_rad"``, ``"dtheta_rad"``; ``"samples"`` for an incomplete span).
    """

    key: str | None = None


class CoreSettingError(CoreError, OptionError):
    """A core setting out of its range or inconsistent with another one (``key`` names the keyword)."""


class CoreShapeError(CoreError):
    """Input arrays or values whose type, length or shape the core cannot take (``key`` names the argument)."""


class CoreSampleError(CoreError):
    """An input sample no IMU delivers (not finite, or beyond the sensor limits); ``index`` counts from 0 within
    the call."""

    index: int


class CoreDivergedError(CoreError):
    """An estimate or the navigated state left its physical range ``t_s`` [s] after the first sample the core was
    given: the data do not fit the model (e.g. a log that is not a static base)."""

    t_s: float


class CoreIncompleteError(CoreError):
    """A result asked for before its span is complete: ``done`` of ``needed`` samples processed."""

    done: int
    needed: int


class MissingExtraError(GyrodriftError, ImportError):
    """An optional part of gyrodrift whose extra is not installed; the message says which ``pip install`` adds it."""
