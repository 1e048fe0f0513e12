"""Progress bars for long runs: a tiny wrapper so every command shows (or hides) progress the same way."""

from __future__ import annotations

import os
import shutil
import sys

from tqdm import tqdm

__all__ = ["progress"]

SCALED_FROM = 10_000
"""Totals from this count on show with SI prefixes (``1.2M/8.6M sample``), smaller ones as integers (``1/4 run``)."""


def progress(total: int | None, desc: str, quiet: bool = False, *, unit: str = "sample") -> tqdm:
    """Return a tqdm bar writing to stderr; use as a context manager and call ``bar.update(n)``.

    Parameters
    ----------
    total : int or None
        Expected total of the `update` increments (None: unknown, the bar only counts). Counts below
        `SCALED_FROM` show as integers, larger ones with SI prefixes.
    desc : str
        Label shown before the bar.
    quiet : bool
        True silences the bar completely.
    unit : str
        Name of one increment.

    Notes
    -----
    The bar is also disabled when stderr is not a terminal (logs, CI, pipes), so redirected output
    never fills with carriage-return lines. A disabled bar still accepts `update` and `close`.
    On a terminal it follows the terminal's size, unless the terminal reports none (0 x 0: a
    pseudo-terminal opened without a size, as ``script`` or ``docker exec -t`` can give), where tqdm would
    draw nothing: then it takes ``COLUMNS`` x ``LINES`` or 80 x 24.
    """
    disable = bool(quiet) or not _stderr_is_tty()
    size = None if disable else _size_of_an_unsized_terminal()
    return tqdm(
        total=total,
        desc=desc,
        unit=unit,
        unit_scale=total is not None and total >= SCALED_FROM,
        disable=disable,
        file=sys.stderr,
        dynamic_ncols=size is None,
        ncols=None if size is None else size.columns,
        nrows=None if size is None else size.lines,
        leave=False,
    )


def _size_of_an_unsized_terminal() -> os.terminal_size | None:
    """None when stderr's terminal reports its size (the bar follows it), else the size to draw in: ``COLUMNS`` x
    ``LINES`` or 80 x 24 (`shutil.get_terminal_size`'s fallback)."""
    try:
        if os.get_terminal_size(sys.stderr.fileno()).columns > 0:
            return None
    except (AttributeError, OSError, ValueError):  # no file descriptor (a stream in memory), or not a terminal
        return None
    size = shutil.get_terminal_size()
    return os.terminal_size((size.columns or 80, size.lines or 24))


def _stderr_is_tty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # closed or replaced stream
        return False
