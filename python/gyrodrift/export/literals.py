"""Float64 literals, arrays and range rows for generated C and Rust: 17 significant digits, the same bits."""

from __future__ import annotations

import math

from gyrodrift.errors import InputError

__all__ = ["array", "literal", "range_rows"]


def literal(x: float) -> str:
    """A float64 literal valid in C and Rust that reads back as exactly ``x`` (17 significant digits)."""
    x = float(x)
    if not math.isfinite(x):
        raise InputError(f"the model holds a non-finite number ({x}); it cannot be exported")
    text = format(x, ".17g")
    if not any(ch in text for ch in ".e"):
        text += ".0"
    assert float(text) == x  # 17 significant digits always round-trip a float64
    return text


def array(values, brackets: str) -> str:
    """``values`` as an array literal between ``brackets`` (``"{}"`` in C, ``"[]"`` in Rust)."""
    return brackets[0] + ", ".join(literal(v) for v in values) + brackets[1]


def range_rows(names, ranges, row: str, separator: str) -> str:
    """One ``row`` per name (``row.format(name=..., lo=..., hi=...)``, the bounds as literals), joined by
    ``separator``."""
    return separator.join(
        row.format(name=name, lo=literal(lo), hi=literal(hi)) for name, (lo, hi) in zip(names, ranges, strict=True)
    )
