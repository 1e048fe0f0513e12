"""Click parameter types shared by the commands."""

from __future__ import annotations

import math
import os
import stat

import click

from gyrodrift.choices import MAX_DRIFT_DEG_H
from gyrodrift.files.input_files import non_regular_reason

__all__ = ["DRIFT_DEG_H", "FiniteFloat", "InputPath", "MAX_DRIFT_DEG_H", "MAX_SEED", "Seed"]

MAX_SEED = 2**64 - 1
"""Largest seed [-]: the Rust core's seeds are unsigned 64-bit integers; numpy's take any integer >= 0."""


class FiniteFloat(click.ParamType):
    """A finite float (no NaN, no inf, nothing that overflows to inf), optionally within bounds.

    ``FiniteFloat()`` any finite number; ``FiniteFloat(min=0.0, min_open=True)`` a positive one;
    ``FiniteFloat(-90.0, 90.0, min_open=True, max_open=True)`` a latitude; `why` is appended to the message of a
    value out of bounds (`DRIFT_DEG_H`). A refused value is click's usage error naming the option (``Invalid value
    for '--hours': ...``), exit status 2.
    """

    name = "float"

    def __init__(
        self,
        min: float | None = None,
        max: float | None = None,
        *,
        min_open: bool = False,
        max_open: bool = False,
        why: str = "",
    ):
        self.min, self.max, self.min_open, self.max_open, self.why = min, max, min_open, max_open, why

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value):
            x = value
        else:
            try:
                x = float(value)
            except (TypeError, ValueError, OverflowError):
                self.fail(f"{value!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        low_bad = self.min is not None and (x <= self.min if self.min_open else x < self.min)
        high_bad = self.max is not None and (x >= self.max if self.max_open else x > self.max)
        if low_bad or high_bad:
            self.fail(f"{value!r} is not in {self._range()}{self.why}", param, ctx)
        return x

    def _range(self) -> str:
        lo = "-inf" if self.min is None else f"{self.min:g}"
        hi = "inf" if self.max is None else f"{self.max:g}"
        left = "(" if self.min_open or self.min is None else "["
        right = ")" if self.max_open or self.max is None else "]"
        return f"{left}{lo}, {hi}{right}"

    def __repr__(self) -> str:
        return f"FiniteFloat{self._range()}"


class Seed(click.IntRange):
    """A seed: an integer in [0, 2**64 - 1] (numpy's `SeedSequence` refuses negative ones, the Rust core takes
    unsigned 64-bit ones). Every ``--seed`` of the CLI has this type; a refused value is click's usage error
    naming the option (``Invalid value for '--seed': -1 is not in the range 0<=x<=18446744073709551615``),
    exit status 2."""

    name = "seed"

    def __init__(self) -> None:
        super().__init__(min=0, max=MAX_SEED)


class InputPath(click.Path):
    """A file the command reads (scenario, run table, model, log, format, noise or campaign file): if it exists
    it must be a regular file, or a folder where `dir_okay`. A device (``/dev/zero``, which never ends), a FIFO
    (which blocks until written), a socket, or a folder where a file is expected is click's usage error naming
    the argument, before any work (``Invalid value for 'LOG': /dev/zero is a device, not a regular file ...``),
    exit status 2. A missing path passes: the reader says so in its own words (`gyrodrift.files.input_files`).

    ``InputPath()`` a file; ``InputPath(dir_okay=True)`` a file or a folder; ``InputPath(dir_okay=True,
    file_okay=False)`` a folder; `exists` and `path_type` are click's.
    """

    def __init__(
        self, *, dir_okay: bool = False, file_okay: bool = True, exists: bool = False, path_type: type | None = None
    ):
        super().__init__(exists=exists, file_okay=True, dir_okay=True, path_type=path_type)
        self.input_dir_okay, self.input_file_okay = dir_okay, file_okay

    def convert(self, value, param, ctx):
        path = super().convert(value, param, ctx)
        where = os.fsdecode(path)
        try:
            is_dir = stat.S_ISDIR(os.stat(path).st_mode)
        except (OSError, ValueError):
            return path  # missing or unreadable: the reader's message
        if is_dir and not self.input_dir_okay:
            self.fail(f"{where} is a directory; expected a file", param, ctx)
        if not is_dir and not self.input_file_okay:
            self.fail(f"{where} is not a folder", param, ctx)
        reason = non_regular_reason(path, dir_ok=self.input_dir_okay)
        if reason is not None:
            self.fail(f"{where} {reason}; gyrodrift reads only regular files", param, ctx)
        return path


DRIFT_DEG_H = FiniteFloat(
    -MAX_DRIFT_DEG_H,
    MAX_DRIFT_DEG_H,
    why=" deg/h: an axial gyro drift (an RLG's is of order 0.001-0.01 deg/h, a tactical-grade gyro's 1-10 deg/h); "
    "is it in another unit?",
)
"""The type of ``--drift-deg-h`` (`navigate`, `evaluate`): a finite drift within +-`MAX_DRIFT_DEG_H` deg/h."""
