"""One line for every expected failure: the message the CLI prints before exiting with status 1."""

from __future__ import annotations

import errno
import os

__all__ = ["one_line_message"]

_REASONS = {
    errno.EROFS: "read-only file system",
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EISDIR: "is a directory (a file was expected)",
    errno.ENOTDIR: "a path component is not a directory",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.ENOENT: "no such file or directory",
    errno.EEXIST: "already exists",
    errno.EBUSY: "device or resource busy",
    errno.ENAMETOOLONG: "file name too long",
    errno.EIO: "input/output error",
}


def one_line_message(exc: BaseException) -> str:
    """The user-facing one-line message of an expected failure.

    A `GyrodriftError` already carries its message (file, row, column, option). An `OSError` is described
    by its path(s) and a plain reason, e.g. ``out/model.json: read-only file system``.
    """
    if isinstance(exc, OSError) and exc.errno is not None and not _has_own_message(exc):
        reason = _REASONS.get(exc.errno) or exc.strerror or os.strerror(exc.errno)
        paths = [p for p in (exc.filename, exc.filename2) if p is not None]
        where = " -> ".join(os.fsdecode(p) for p in paths)
        return f"{where}: {reason}" if where else reason
    text = str(exc).strip()
    return " ".join(text.split("\n")) if text else type(exc).__name__


def _has_own_message(exc: OSError) -> bool:
    """True for the package's own OSError subclasses, whose message is already written for the user."""
    from gyrodrift.errors import GyrodriftError

    return isinstance(exc, GyrodriftError)
