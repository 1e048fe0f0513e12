"""Click parameter types shared by the commands."""

from __future__ import annotations

import math

import click

__all__ = ["FiniteFloat", "MAX_SEED", "Seed"]

MAX_SEED = 2**64 - 1
"""Largest seed [-]: the Rust core's seeds are unsigned 64-bit integers; numpy's take any integer >= 0."""


class FiniteFloat(click.ParamType):
    """A finite float (no NaN, no inf, nothing that overflows to inf), optionally within bounds.

    ``FiniteFloat()`` any finite number; ``FiniteFloat(min=0.0, min_open=True)`` a positive one;
    ``FiniteFloat(-90.0, 90.0, min_open=True, max_open=True)`` a latitude. A refused value is click's usage
    error naming the option (``Invalid value for '--hours': ...``), exit status 2.
    """

    name = "float"

    def __init__(
        self, min: float | None = None, max: float | None = None, *, min_open: bool = False, max_open: bool = False
    ):
        self.min, self.max, self.min_open, self.max_open = min, max, min_open, max_open

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
            self.fail(f"{value!r} is not in {self._range()}", param, ctx)
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
