"""Atomic file writes: a reader sees either the old file or the whole new one, never half of it.

Every writer creates a temporary file in the destination's own folder (so the final `os.replace` is a
rename within one file system, which POSIX makes atomic), flushes and fsyncs it, then renames it over the
destination. If anything raises before the rename, the temporary file is removed and the previous file,
if any, is left untouched.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = [
    "atomic_write",
    "atomic_write_json",
    "atomic_write_parquet",
    "atomic_directory",
    "temporary_path",
    "missing_folder_message",
]


def _create_temporary(folder: Path, prefix: str, suffix: str, directory: bool = False) -> Path:
    """Create a new empty file (or folder) with a random name; unlike `tempfile.mkstemp` (0600) and
    `mkdtemp` (0700) its permissions follow the umask like any ordinary file's (0666 / 0777 & ~umask)."""
    for _ in range(100):
        candidate = folder / f"{prefix}{secrets.token_hex(6)}{suffix}"
        try:
            if directory:
                os.mkdir(candidate, 0o777)
            else:
                os.close(os.open(candidate, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:  # pragma: no cover - 48 random bits
            continue
        return candidate
    raise FileExistsError(f"cannot create a temporary file in {folder}")  # pragma: no cover


def _fsync_directory(folder: Path) -> None:
    """Persist a rename by syncing its folder (a no-op where folders cannot be opened, e.g. Windows)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - platform dependent
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover - some file systems refuse fsync on folders
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def temporary_path(path: str | os.PathLike[str], suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a fresh temporary path beside `path`; on a clean exit rename it over `path`.

    For writers that insist on opening the file themselves (e.g. `pyarrow.parquet.ParquetWriter`). The
    caller must have closed the file before the `with` block ends. The temporary file is fsynced before
    the rename. On an exception it is removed and `path` is left as it was.

    Parameters
    ----------
    path : path-like
        Final destination. Its folder must exist.
    suffix : str
        Suffix of the temporary name (the name also starts with ``.<final name>.``, so it is hidden and
        easy to attribute).
    """
    dest = Path(path)
    folder = dest.parent if str(dest.parent) else Path(".")
    tmp = _create_temporary(folder, f".{dest.name}.", suffix)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise
    _fsync_directory(folder)


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w", encoding: str = "utf-8") -> Iterator[IO[Any]]:
    """Open a temporary file for writing; on a clean exit it atomically replaces `path`.

    Parameters
    ----------
    path : path-like
        Final destination. Its folder must exist.
    mode : {"w", "wb"}
        Text or binary.
    encoding : str
        Text encoding (ignored in binary mode).

    Yields
    ------
    file object
        Write to it; do not close it yourself.

    Examples
    --------
    >>> with atomic_write("result.csv") as fh:   # doctest: +SKIP
    ...     fh.write("a,b\\n1,2\\n")
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write: mode must be 'w' or 'wb', got {mode!r}")
    with temporary_path(path) as tmp:
        if mode == "w":
            fh = open(tmp, "w", encoding=encoding, newline="")
        else:
            fh = open(tmp, "wb")
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())


def atomic_write_json(obj: Any, path: str | os.PathLike[str], *, indent: int = 2) -> None:
    """Write `obj` as JSON (UTF-8, sorted keys not imposed, trailing newline) atomically to `path`.

    NaN and infinities are refused (`allow_nan=False`) because they are not JSON.
    """
    text = json.dumps(obj, indent=indent, allow_nan=False) + "\n"
    with atomic_write(path, "w") as fh:
        fh.write(text)


def atomic_write_parquet(table: Any, path: str | os.PathLike[str], **kwargs: Any) -> None:
    """Write a `pyarrow.Table` to Parquet atomically; `kwargs` go to `pyarrow.parquet.write_table`."""
    import pyarrow.parquet as pq

    with temporary_path(path) as tmp:
        pq.write_table(table, tmp, **kwargs)


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Fill a temporary folder, then swap it in place of `path` as a whole.

    On a clean exit an existing `path` is first renamed aside, the new folder renamed into place and the
    old one deleted; two renames, so a crash between them leaves ``path`` missing but the old folder
    intact under a hidden ``.<name>.old-*`` name (never a half-written `path`). On an exception the
    temporary folder is deleted and `path` is untouched.

    Yields
    ------
    pathlib.Path
        The temporary folder to write the files into.
    """
    dest = Path(path)
    parent = dest.parent if str(dest.parent) else Path(".")
    parent.mkdir(parents=True, exist_ok=True)
    tmp = _create_temporary(parent, f".{dest.name}.", ".tmp", directory=True)
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    old = None
    if dest.exists():
        old = parent / f".{dest.name}.old-{secrets.token_hex(6)}"
        os.replace(dest, old)
    os.replace(tmp, dest)
    _fsync_directory(parent)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def missing_folder_message(path: str | os.PathLike[str]) -> str | None:
    """A message when the folder that should receive file `path` does not exist, else None.

    Commands call it before long work, so that a mistyped ``--out`` fails at once instead of after hours.
    """
    parent = Path(path).parent
    if str(parent) and not parent.is_dir():
        return f"{path}: the folder {parent} does not exist"
    return None
