"""How a failed write is reported: an `OutputError` naming the path and a plain reason ("read-only file system",
"no space left on the device"), also for a temporary (named by the file it stands for)."""

from __future__ import annotations

import contextlib
import errno
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Protocol

from gyrodrift.errors import OutputError
from gyrodrift.files.temporaries import TEMP_RE

__all__ = ["REASONS", "os_error_reason", "output_error", "naming", "Writing"]

REASONS = {
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
    errno.EPIPE: "broken pipe (the reader went away)",
    errno.EFBIG: "file too large",
    errno.EXDEV: "on another file system",
}
"""Plain reasons of the file-system failures a write meets, by errno."""


def os_error_reason(exc: OSError) -> str:
    """A plain reason for a file-system failure ("read-only file system", "no space left on the device")."""
    if exc.errno is not None and exc.errno in REASONS:
        return REASONS[exc.errno]
    if exc.strerror:
        return exc.strerror
    if exc.errno is not None:
        return os.strerror(exc.errno)
    return str(exc).strip() or type(exc).__name__


def output_error(path: str | os.PathLike[str], reason: str) -> OutputError:
    """``OutputError("<path>: <reason>")``."""
    return OutputError(f"{os.fspath(path)}: {reason}")


class Writing(Protocol):
    """A set of files being written in `folder` (an `gyrodrift.files.atomic.Stage`), `last` the one written last."""

    folder: Path
    last: str | None


@contextlib.contextmanager
def naming(path: str | os.PathLike[str], stage: Writing | None = None) -> Iterator[None]:
    """Turn an `OSError` raised inside the block into an `OutputError` naming the file and the reason: the
    error's own file name (a temporary named by its final file); without one (a failed ``write``), the file
    `stage` was writing last, else `path`. The package's own errors pass through."""
    try:
        yield
    except OutputError:
        raise
    except OSError as exc:
        where = os.fspath(path)
        if stage is not None and stage.last is not None:
            where = os.fspath(stage.folder / stage.last)
        if exc.filename is not None:
            where = os.fsdecode(exc.filename)
            temporary = TEMP_RE.match(os.path.basename(where))
            if temporary is not None:  # name the file being written, not its temporary
                where = os.fspath(path) if stage is None else os.fspath(stage.folder / temporary["name"])
        raise output_error(where, os_error_reason(exc)) from exc
