"""Reading a user's input file without hanging or exhausting memory (the one place that opens them for reading).

gyrodrift reads only regular files: a device (``/dev/zero``, ``/dev/urandom``) never ends, a FIFO blocks until
someone writes to it, a socket cannot be read as a file, a directory is not a file. `non_regular_reason` says
why a path is refused (used by the CLI's input type, `gyrodrift.cli.types.InputPath`, before any work), and
`read_limited` reads a small file (TOML, JSON manifest) with a size limit: the file is opened without blocking,
checked on its open descriptor, and at most ``max_bytes + 1`` bytes are read, never the whole of a huge file.
"""

from __future__ import annotations

import errno
import os
import stat

__all__ = ["NotRegularFileError", "file_kind", "non_regular_reason", "read_limited"]


class NotRegularFileError(OSError):
    """The path is a directory, device, FIFO or socket; ``str(exc)`` is the reason (``"is a FIFO"``)."""

    def __init__(self, path: str, kind: str):
        super().__init__(errno.EINVAL, f"is {kind}, not a regular file", path)
        self.kind = kind

    def __str__(self) -> str:
        return str(self.strerror)


def file_kind(mode: int) -> str:
    """What a file of `mode` (``st_mode``) is, for a message: "a directory", "a FIFO", "a socket", "a device"."""
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


def non_regular_reason(path: str | os.PathLike[str], *, dir_ok: bool = False) -> str | None:
    """Why the existing `path` cannot be read as an input ("is a FIFO, not a regular file"), or None: it is a
    regular file (a symbolic link is followed), a directory when `dir_ok`, or does not exist (the reader says
    so in its own words)."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):  # missing, unreadable, NUL in the name: the reader's own message
        return None
    if stat.S_ISREG(mode) or (dir_ok and stat.S_ISDIR(mode)):
        return None
    return f"is {file_kind(mode)}, not a regular file"


def read_limited(path: str | os.PathLike[str], max_bytes: int) -> bytes:
    """The bytes of the regular file `path`, at most ``max_bytes + 1`` of them (more than `max_bytes` means the
    file is too large; the rest is never read).

    Raises
    ------
    NotRegularFileError
        `path` is a directory, device, FIFO or socket (found without blocking: opened with ``O_NONBLOCK``).
    OSError
        The file cannot be opened or read (``FileNotFoundError``, ``PermissionError``, ...).
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        reason = non_regular_reason(path, dir_ok=False)  # a socket cannot be opened at all (ENXIO): say what it is
        if reason is not None:
            raise NotRegularFileError(os.fspath(path), file_kind(os.stat(path).st_mode)) from None
        raise
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise NotRegularFileError(os.fspath(path), file_kind(mode))
        chunks = []
        left = max_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)
