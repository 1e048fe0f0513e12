"""Temporaries of gyrodrift's writes: named after their file (``.NAME.gyrodrift-tmp-HOST-PID-HEX``, HOST: 8 hex
digits of the host name's hash), created with the permissions of an ordinary file, stale once their writer is
dead (same host, PID not running) or untouched for `STALE_AFTER_S`, and made durable (fsync of a file, and of
the folder holding a rename)."""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import socket
from pathlib import Path

__all__ = ["STALE_AFTER_S", "HOST", "TEMP_RE", "create_temporary", "is_stale", "fsync_file", "fsync_directory"]

STALE_AFTER_S = 24 * 3600.0
"""A temporary untouched this long [s] is stale even when its PID cannot be checked (another host)."""

HOST = hashlib.sha256(socket.gethostname().encode("utf-8", "replace")).hexdigest()[:8]
"""This host in temporaries' names (a PID is checked only on its own host)."""
TEMP_RE = re.compile(r"^\.(?P<name>.+)\.gyrodrift-tmp-(?P<host>[0-9a-f]{8})-(?P<pid>[0-9]+)-[0-9a-f]{12}$")
"""A temporary's name: the file it stands for (``name``), the writer's ``host`` and ``pid``."""


def _temporary_name(name: str) -> str:
    return f".{name}.gyrodrift-tmp-{HOST}-{os.getpid()}-{secrets.token_hex(6)}"


def create_temporary(folder: Path, name: str) -> Path:
    """Create a new empty file named like a gyrodrift temporary of `name` in `folder`. Unlike
    `tempfile.mkstemp` (0600) its permissions follow the umask like any ordinary file's (0666 & ~umask)."""
    while True:
        candidate = folder / _temporary_name(name)
        try:
            os.close(os.open(candidate, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:  # pragma: no cover - 48 random bits
            continue
        return candidate


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - someone else's live process
        return True
    except OSError:  # pragma: no cover - platform without signals
        return True
    return True


def is_stale(folder: Path, match: re.Match[str], now: float) -> bool:
    """True if the temporary `match` (of `TEMP_RE`) in `folder` was left by a dead writer or is older than
    `STALE_AFTER_S` at `now` [s since the epoch]."""
    if match["host"] == HOST and int(match["pid"]) != os.getpid() and not _pid_alive(int(match["pid"])):
        return True
    try:
        return now - os.lstat(folder / match.string).st_mtime > STALE_AFTER_S
    except FileNotFoundError:
        return False


def fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_directory(folder: Path) -> None:
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
