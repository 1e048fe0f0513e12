"""Reading a user's TOML file (scenario, campaign, log format, noise model) with one-line errors.

Every TOML file gyrodrift reads goes through `read_toml`: a missing or unreadable file, a directory, device, FIFO or
socket (refused without blocking or reading it), an oversized file (at most ``max_bytes + 1`` bytes are read), bytes
that are not UTF-8, invalid TOML, integers beyond Python's digit limit and tables nested too deeply all become
the caller's error class with a message that starts with the file name. What the keys mean is the caller's job.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Callable
from typing import Any

from gyrodrift.files.input_files import NotRegularFileError, read_limited

__all__ = ["read_toml", "MAX_TOML_BYTES"]

MAX_TOML_BYTES = 1 << 20
"""Largest TOML file read [bytes]: the files gyrodrift reads are a few kB; anything this large is a mistake."""


def read_toml(
    path: str | os.PathLike[str],
    error: Callable[[str], Exception],
    *,
    expected: str,
    max_bytes: int = MAX_TOML_BYTES,
) -> dict[str, Any]:
    """The TOML document in `path` as a dict, or `error(message)` raised with a message naming the file.

    Parameters
    ----------
    path : path-like
        The file to read.
    error : callable
        Builds the exception to raise from a message (an error class of the caller, e.g. `ScenarioError`).
    expected : str
        What the file should be, for the messages (e.g. "a scenario TOML file").
    max_bytes : int
        Refuse files larger than this [bytes].
    """
    source = str(path)
    try:
        raw = read_limited(path, max_bytes)
    except FileNotFoundError:
        raise error(f"{source}: no such file") from None
    except NotRegularFileError as exc:
        raise error(f"{source}: {exc} (expected {expected})") from None
    except OSError as exc:
        raise error(f"{source}: cannot read: {exc.strerror or exc}") from None
    except ValueError:  # a NUL in the name
        raise error(f"{source}: not a valid file name (expected {expected})") from None
    if len(raw) > max_bytes:
        raise error(f"{source}: more than {max_bytes} bytes; {expected} holds at most {max_bytes}")
    try:
        return tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise error(f"{source}: not UTF-8 text (byte {exc.start}; expected {expected})") from None
    except (tomllib.TOMLDecodeError, ValueError) as exc:  # ValueError: e.g. an integer of more than 4300 digits
        raise error(f"{source}: invalid TOML: {exc}") from None
    except RecursionError:
        raise error(f"{source}: invalid TOML: arrays or tables nested too deeply") from None
