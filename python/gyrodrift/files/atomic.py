"""Writing files and output folders so that nothing is ever lost (the rules are in docs/outputs.md).

Every command that writes goes through this module, in one of two ways:

- one file (``fit --out``, ``predict --out``, ``features --out`` and ``--curves``): `check_output_file` before the
  work, `atomic_write` after it. The new content goes to a temporary file in the destination's own folder, is
  fsynced and renamed over the destination (POSIX makes the rename atomic), so a reader sees the old file or
  the whole new one.
- a set of files in a folder (``simulate``, ``navigate``, ``reproduce``, ``truth``, ``evaluate``, ``identify``):
  `OutputFolder` checks the folder before the work and `OutputFolder.publish` stages every file as a
  temporary, then publishes the set under a journal in the folder's manifest (``.gyrodrift-manifest.json``),
  so a run killed at any moment leaves the old set or the new one, and the next run (or a reader, via
  `check_complete`) can tell which.

A manifest is trusted only if every name in it is a plain file name of its folder (no separator, not absolute,
no leading dot, no NUL, no symbolic link) and it has the shape gyrodrift writes; otherwise it is refused whole
(`UntrustedManifestError`) before anything in the folder is touched.

What may be written (checked before any work, and again at the end):

- A file is replaced only if it is a regular file written by gyrodrift (recognised by its content) or empty;
  a new path is created. Devices (``/dev/full``), FIFOs, sockets, directories and files such as
  ``/proc/version`` are refused. A symbolic link is followed: its target is replaced (the temporary is made in
  the target's folder) and the link stays.
- An output is never one of the command's inputs (same path, symlink or hard link: `os.path.samefile`).
- A folder is written only if it is new, empty, or holds nothing but gyrodrift's own outputs (files listed in
  its manifest and unchanged since); anything else is refused with one line saying why. Files of other
  gyrodrift commands in the folder are kept (``simulate --out d`` then ``navigate d/imu.parquet --out d``).
- Temporaries are named ``.NAME.gyrodrift-tmp-HOST-PID-HEX`` (HOST: 8 hex digits of the host name's hash);
  they are removed on every failure path (including KeyboardInterrupt), and stale ones left by a killed run
  (dead PID on this host, or untouched for `STALE_AFTER_S` seconds) are removed by the next write into that
  folder. Nothing that does not match the pattern is ever deleted.

Every file-system failure becomes an `OutputError` naming the path and the reason (read-only file system, no
space left on the device, is a directory, permission denied); the previous outputs are left as they were.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import hashlib
import json
import os
import re
import secrets
import socket
import stat
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

from gyrodrift.errors import OutputError
from gyrodrift.files.input_files import NotRegularFileError, file_kind, read_limited

__all__ = [
    "MANIFEST_NAME",
    "STALE_AFTER_S",
    "OutputFolder",
    "UntrustedManifestError",
    "Stage",
    "atomic_files",
    "atomic_write",
    "atomic_write_json",
    "check_complete",
    "check_output_file",
    "check_output_files",
    "clean_stale_temporaries",
    "os_error_reason",
    "output_folder",
    "recognise_json_format",
    "recognise_header",
    "staged",
    "write_json",
]

MANIFEST_NAME = ".gyrodrift-manifest.json"
"""The manifest of an output folder: which files gyrodrift wrote there, by which command, sizes and SHA-256."""
MANIFEST_FORMAT = "gyrodrift-manifest/1"
STALE_AFTER_S = 24 * 3600.0
"""A temporary untouched this long [s] is stale even when its PID cannot be checked (another host)."""

_HOST = hashlib.sha256(socket.gethostname().encode("utf-8", "replace")).hexdigest()[:8]
_TEMP_RE = re.compile(r"^\.(?P<name>.+)\.gyrodrift-tmp-(?P<host>[0-9a-f]{8})-(?P<pid>[0-9]+)-[0-9a-f]{12}$")
_HEAD_BYTES = 4096

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
    errno.EPIPE: "broken pipe (the reader went away)",
    errno.EFBIG: "file too large",
    errno.EXDEV: "on another file system",
}


def os_error_reason(exc: OSError) -> str:
    """A plain reason for a file-system failure ("read-only file system", "no space left on the device")."""
    if exc.errno is not None and exc.errno in _REASONS:
        return _REASONS[exc.errno]
    if exc.strerror:
        return exc.strerror
    if exc.errno is not None:
        return os.strerror(exc.errno)
    return str(exc).strip() or type(exc).__name__


def _fail(path: str | os.PathLike[str], reason: str) -> OutputError:
    return OutputError(f"{os.fspath(path)}: {reason}")


@contextlib.contextmanager
def _naming(path: str | os.PathLike[str], stage: Stage | None = None) -> Iterator[None]:
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
            temporary = _TEMP_RE.match(os.path.basename(where))
            if temporary is not None:  # name the file being written, not its temporary
                where = os.fspath(path) if stage is None else os.fspath(stage.folder / temporary["name"])
        raise _fail(where, os_error_reason(exc)) from exc


# --- temporaries ---------------------------------------------------------------------------------------


def _temporary_name(name: str) -> str:
    return f".{name}.gyrodrift-tmp-{_HOST}-{os.getpid()}-{secrets.token_hex(6)}"


def _create_temporary(folder: Path, name: str) -> Path:
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


def _is_stale(folder: Path, match: re.Match[str], now: float) -> bool:
    if match["host"] == _HOST and int(match["pid"]) != os.getpid() and not _pid_alive(int(match["pid"])):
        return True
    try:
        return now - os.lstat(folder / match.string).st_mtime > STALE_AFTER_S
    except FileNotFoundError:
        return False


def clean_stale_temporaries(folder: str | os.PathLike[str], keep: Iterable[str] = ()) -> list[str]:
    """Remove the temporaries a killed gyrodrift run left in `folder`; return their names.

    Only names matching ``.NAME.gyrodrift-tmp-HOST-PID-HEX`` are considered, and only those whose writer is
    dead (same host, PID not running) or that were untouched for `STALE_AFTER_S`. Names in `keep` stay.
    """
    folder = Path(folder)
    keep = set(keep)
    with contextlib.suppress(OutputError):  # temporaries of an unfinished publication wait for its recovery
        pending = (_read_manifest(folder) or {}).get("pending")
        if isinstance(pending, dict):
            keep.update(str(e.get("tmp")) for e in pending.get("files", {}).values() if isinstance(e, dict))
    removed: list[str] = []
    now = time.time()
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        match = _TEMP_RE.match(name)
        if match is None or name in keep or not _is_stale(folder, match, now):
            continue
        with contextlib.suppress(FileNotFoundError, IsADirectoryError, PermissionError, OSError):
            os.unlink(folder / name)
            removed.append(name)
    return removed


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


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


# --- what may be written --------------------------------------------------------------------------------


def _same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def _unwritable_reason(folder: Path) -> str | None:
    """Why files cannot be created, renamed and removed in the existing `folder` ("read-only file system",
    "permission denied"), or None. Asked of the file system (``access(W_OK | X_OK)``, which also reports a
    read-only mount to root), without writing anything: the check before the work that the publication at
    its end would otherwise be the first to fail."""
    try:
        if os.access(folder, os.W_OK | os.X_OK):
            return None
    except (OSError, ValueError):  # pragma: no cover - the publication says why
        return None
    try:
        if os.statvfs(folder).f_flag & getattr(os, "ST_RDONLY", 1):
            return _REASONS[errno.EROFS]
    except (OSError, AttributeError):  # pragma: no cover - no statvfs (Windows)
        pass
    return _REASONS[errno.EACCES]


def _head(path: Path) -> bytes:
    with open(path, "rb") as fh:
        return fh.read(_HEAD_BYTES)


def recognise_header(*headers: str) -> Callable[[bytes], bool]:
    """A recogniser of gyrodrift's CSV/JSON-lines outputs: the file starts with one of `headers`."""
    prefixes = tuple(h.encode() for h in headers)
    return lambda head: head.lstrip(b"\xef\xbb\xbf").startswith(prefixes)


def recognise_json_format(*formats: str) -> Callable[[bytes], bool]:
    """A recogniser of gyrodrift's JSON files: the first 4 KiB hold ``"format": "<one of formats>"``."""
    needles = tuple(re.compile(rb'"format"\s*:\s*"' + re.escape(f.encode()) + rb'"') for f in formats)
    return lambda head: any(n.search(head) for n in needles)


def check_output_file(
    path: str | os.PathLike[str],
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
    recognise: Callable[[bytes], bool] | None = None,
    what: str = "file",
) -> Path:
    """Check that `path` may receive an output file, before any work; return the real destination.

    Parameters
    ----------
    path : path-like
        The output named by the user. A symbolic link is followed (its target is what gets replaced).
    inputs : paths
        The command's inputs; an output that is one of them (same path, link or hard link) is refused.
    recognise : callable(bytes) -> bool, optional
        Given the first 4 KiB of an existing non-empty file, True if gyrodrift wrote it (`recognise_header`,
        `recognise_json_format`); otherwise the file is refused. None: any regular file may be replaced.
    what : str
        What the file is ("model file", "run table"), for the message.

    Raises
    ------
    OutputError
        The path is an input, a directory, a device, FIFO or socket, a file gyrodrift did not write, or its
        folder does not exist; the message names the path and what to do.
    """
    given = os.fspath(path)
    for inp in inputs:
        if _same_file(given, inp):
            raise _fail(given, f"is also an input of this command ({os.fspath(inp)}); choose another output name")
    real = Path(os.path.realpath(given))
    try:
        st = os.stat(real)
    except FileNotFoundError:
        if not real.parent.is_dir():
            raise _fail(given, f"the folder {Path(given).parent} does not exist") from None
        _check_writable(given, real.parent)
        return real
    except OSError as exc:
        raise _fail(given, os_error_reason(exc)) from None
    if stat.S_ISDIR(st.st_mode):
        raise _fail(given, "is a directory (a file was expected)")
    if not stat.S_ISREG(st.st_mode):
        raise _fail(given, f"is {file_kind(st.st_mode)}; gyrodrift writes only regular files or new paths")
    if recognise is not None:
        with _naming(given):
            head = _head(real)
        if head and not recognise(head):
            raise _fail(
                given,
                f"exists and is not a {what} written by gyrodrift; gyrodrift replaces only its own outputs: "
                "choose a new name, or move the file away yourself",
            )
    _check_writable(given, real.parent)
    return real


def _check_writable(given: str | os.PathLike[str], folder: Path) -> None:
    """`OutputError` naming `given` if nothing can be written in `folder` (its output's folder), before the work."""
    reason = _unwritable_reason(folder)
    if reason is not None:
        where = "" if Path(os.fspath(given)).parent.resolve() == folder.resolve() else f" (in {folder})"
        raise _fail(given, f"cannot be written{where}: {reason}")


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike[str],
    mode: str = "w",
    encoding: str = "utf-8",
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
    recognise: Callable[[bytes], bool] | None = None,
    what: str = "file",
) -> Iterator[IO[Any]]:
    """Open a temporary file for writing; on a clean exit it atomically replaces `path`.

    `path` is checked first (`check_output_file` with `inputs`, `recognise`, `what`). Stale temporaries of
    killed runs in the destination folder are removed. On any exception (KeyboardInterrupt too) the
    temporary is removed and `path` is left as it was; an `OSError` becomes an `OutputError` naming `path`.

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
    >>> with atomic_write("result.csv") as fh:
    ...     _ = fh.write("a,b\\n1,2\\n")
    >>> open("result.csv").read()
    'a,b\\n1,2\\n'
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_write: mode must be 'w' or 'wb', got {mode!r}")
    real = check_output_file(path, inputs=inputs, recognise=recognise, what=what)
    folder = real.parent
    clean_stale_temporaries(folder)
    tmp = None
    try:
        with _naming(path):
            tmp = _create_temporary(folder, real.name)
            fh = open(tmp, "w", encoding=encoding, newline="") if mode == "w" else open(tmp, "wb")
        with _naming(path), fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        with _naming(path):
            real = check_output_file(path, inputs=inputs, recognise=recognise, what=what)  # still ours?
            os.replace(tmp, real)
        tmp = None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    _fsync_directory(folder)


def check_output_files(*targets: Mapping[str, Any]) -> list[Path]:
    """`check_output_file` for each target (a mapping of its arguments), and no two targets the same file;
    returns the real destinations."""
    reals = [check_output_file(**t) for t in targets]
    for i, real in enumerate(reals):
        for j in range(i):
            if _same_file(real, reals[j]) or real == reals[j]:
                raise _fail(targets[i]["path"], f"is also {os.fspath(targets[j]['path'])}; give two different files")
    return reals


@contextlib.contextmanager
def atomic_files(*targets: Mapping[str, Any]) -> Iterator[list[Path]]:
    """Several single files written together: none is replaced before all are written and fsynced.

    Each target is a mapping of `check_output_file`'s arguments (``path``, and optionally ``inputs``,
    ``recognise``, ``what``); two targets may not be the same file. Yields one temporary path per target
    (write each plainly). On a clean exit every target is checked again and the temporaries are renamed
    in order, so a failure while writing (a full disk) leaves every file as it was; on any exception every
    temporary is removed. Used by ``features --out ... --curves ...``.
    """
    reals = check_output_files(*targets)
    temporaries: list[Path] = []
    try:
        for t, real in zip(targets, reals, strict=True):
            clean_stale_temporaries(real.parent)
            with _naming(t["path"]):
                temporaries.append(_create_temporary(real.parent, real.name))
        try:
            yield list(temporaries)
        except OSError as exc:
            if isinstance(exc, OutputError):
                raise
            if exc.filename is not None:
                named = [k for k, tmp in enumerate(temporaries) if os.fspath(tmp) == os.fsdecode(exc.filename)]
                if not named:
                    raise
            else:  # a failed write names no file: the one being written is the last that holds data
                named = [k for k, tmp in enumerate(temporaries) if tmp.exists() and tmp.stat().st_size > 0] or [0]
            raise _fail(targets[named[-1]]["path"], os_error_reason(exc)) from exc
        for t, tmp in zip(targets, temporaries, strict=True):
            with _naming(t["path"]):
                _fsync_file(tmp)
        reals = [check_output_file(**t) for t in targets]
        for t, tmp, real in zip(targets, list(temporaries), reals, strict=True):
            with _naming(t["path"]):
                os.replace(tmp, real)
            temporaries.remove(tmp)
            _fsync_directory(real.parent)
    finally:
        for tmp in temporaries:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def _json_text(obj: Any, indent: int = 2) -> str:
    return json.dumps(obj, indent=indent, allow_nan=False) + "\n"


def atomic_write_json(obj: Any, path: str | os.PathLike[str], *, indent: int = 2, **check: Any) -> None:
    """Write `obj` as JSON (UTF-8, trailing newline) atomically to `path`; `check` goes to `atomic_write`.

    NaN and infinities are refused (`allow_nan=False`) before anything is written, because they are not JSON.
    """
    text = _json_text(obj, indent)
    with atomic_write(path, "w", **check) as fh:
        fh.write(text)


def write_json(obj: Any, path: str | os.PathLike[str], *, indent: int = 2) -> None:
    """Write `obj` as JSON to `path` (a staged file of an `OutputFolder`); NaN and infinities are refused."""
    text = _json_text(obj, indent)
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)


# --- output folders -------------------------------------------------------------------------------------


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            digest.update(block)
    return digest.hexdigest()


def _describe(path: Path) -> dict[str, Any]:
    st = os.stat(path)
    return {"bytes": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": _sha256(path)}


def _matches(path: Path, entry: dict[str, Any]) -> bool:
    """True if the file at `path` is the one `entry` describes: same size and (modification time or SHA-256)."""
    try:
        st = os.stat(path)
    except OSError:
        return False
    if not stat.S_ISREG(st.st_mode) or st.st_size != entry.get("bytes"):
        return False
    if st.st_mtime_ns == entry.get("mtime_ns"):
        return True
    try:
        return _sha256(path) == entry.get("sha256")
    except OSError:
        return False


MAX_MANIFEST_BYTES = 64 << 20
"""Largest manifest read [bytes] (a folder of 100 000 outputs needs about 20 MB)."""


class UntrustedManifestError(OutputError):
    """A file named like gyrodrift's manifest that claims its format but is not what gyrodrift writes: an entry
    that is no plain file name of the folder, or a structure of the wrong shape. Refused whole, before any
    work: acting on it could delete or replace files the program did not write."""


_SHA256_RE = re.compile(r"^[0-9a-f]{64}$")


def _shown(name: object) -> str:
    """A name from a manifest, quoted and escaped for a one-line message (at most about 80 characters)."""
    text = repr(name)
    return text if len(text) <= 80 else text[:77] + "..."


def _plain_name_problem(name: object) -> str | None:
    """Why `name` is not the name of a file gyrodrift may write in its folder, or None."""
    if not isinstance(name, str) or not name:
        return "is not a file name"
    if "\0" in name:
        return "holds a NUL character"
    if os.path.isabs(name) or name.startswith("/"):
        return "is an absolute path"
    if "/" in name or os.sep in name or (os.altsep and os.altsep in name) or "\\" in name:
        return "holds a path separator"
    if name in (".", ".."):
        return "is not a file of the folder"
    if name.startswith("."):
        return "starts with a dot (gyrodrift's outputs never do)"
    return None


def _validate_manifest(folder: Path, doc: dict[str, Any]) -> None:
    """Raise `UntrustedManifestError` naming the manifest and the first bad entry unless every set and the
    pending journal have the shape gyrodrift writes, every file name is a plain name of `folder` (no separator,
    not absolute, no leading dot, no NUL) and none of them, nor a journal's temporary, is a symbolic link."""
    path = folder / MANIFEST_NAME

    def bad(where: str, why: str) -> UntrustedManifestError:
        return UntrustedManifestError(
            f"{os.fspath(path)}: {where} {why}; gyrodrift writes no such manifest, so it refuses the whole of it "
            "and changes nothing in the folder: choose another --out folder (or remove the manifest if you are "
            "sure gyrodrift's outputs in the folder can be overwritten)"
        )

    def check_entry(where: str, name: Any, entry: Any, journal: bool) -> None:
        problem = _plain_name_problem(name)
        if problem is not None or name == MANIFEST_NAME:
            raise bad(f"{where} names {_shown(name)}, which", problem or "is the manifest itself")
        if not isinstance(entry, dict):
            raise bad(f"{where}, file {_shown(name)}:", f"is {type(entry).__name__}, not a mapping")
        for key in ("bytes", "mtime_ns"):
            value = entry.get(key)
            if isinstance(value, bool) or not isinstance(value, int) or (key == "bytes" and value < 0):
                raise bad(
                    f"{where}, file {_shown(name)}:",
                    f'"{key}" is {_shown(value)}, not a{" non-negative" if key == "bytes" else "n"} integer',
                )
        if not (isinstance(entry.get("sha256"), str) and _SHA256_RE.match(entry["sha256"])):
            raise bad(f"{where}, file {_shown(name)}:", f'"sha256" is {_shown(entry.get("sha256"))}, not 64 hex digits')
        names = [name]
        if journal:
            tmp = entry.get("tmp")
            match = _TEMP_RE.match(tmp) if isinstance(tmp, str) and "/" not in tmp and "\0" not in tmp else None
            if match is None or match["name"] != name or _plain_name_problem(match.string[1:]) is not None:
                raise bad(f"{where}, file {_shown(name)}:", f'"tmp" is {_shown(tmp)}, not a temporary of that file')
            names.append(match.string)
        for n in names:
            try:
                link = stat.S_ISLNK(os.lstat(folder / n).st_mode)
            except OSError:
                continue
            if link:
                raise bad(f"{where} names {_shown(n)}, which", "is a symbolic link (gyrodrift writes no links)")

    sets = doc["sets"]
    for command, s in sets.items():
        where = f"the set {_shown(command)}"
        if not isinstance(s, dict):
            raise bad(where, f"is {type(s).__name__}, not a mapping")
        files = s.get("files")
        if not isinstance(files, dict):
            raise bad(where, f'has "files" {type(files).__name__}, not a mapping of file names')
        for name, entry in files.items():
            check_entry(where, name, entry, journal=False)
    if "pending" in doc:
        pending = doc["pending"]
        where = "the pending journal"
        if not isinstance(pending, dict):
            raise bad(where, f"is {type(pending).__name__}, not a mapping")
        if not isinstance(pending.get("command"), str):
            raise bad(where, f'has "command" {_shown(pending.get("command"))}, not a command name')
        if not isinstance(pending.get("meta"), dict):
            raise bad(where, f'has "meta" {type(pending.get("meta")).__name__}, not a mapping')
        files = pending.get("files")
        if not isinstance(files, dict):
            raise bad(where, f'has "files" {type(files).__name__}, not a mapping of file names')
        for name, entry in files.items():
            check_entry(where, name, entry, journal=True)


def _read_manifest(folder: Path) -> dict[str, Any] | None:
    """The folder's manifest, None without one; an unreadable or foreign manifest is an `OutputError`, one of
    gyrodrift's format whose entries are not plain file names of the folder (or of the wrong shape) an
    `UntrustedManifestError` (see `_validate_manifest`)."""
    path = folder / MANIFEST_NAME
    try:
        raw = read_limited(path, MAX_MANIFEST_BYTES)
        if len(raw) > MAX_MANIFEST_BYTES:
            raise _fail(path, f"a manifest of gyrodrift's outputs holds at most {MAX_MANIFEST_BYTES} bytes")
        text = raw.decode("utf-8")
    except FileNotFoundError:
        return None
    except NotRegularFileError as exc:
        raise _fail(path, f"{exc}; a manifest of gyrodrift's outputs is a regular file") from None
    except (OSError, UnicodeDecodeError) as exc:
        if isinstance(exc, OutputError):
            raise
        reason = os_error_reason(exc) if isinstance(exc, OSError) else "not UTF-8"
        raise _fail(path, f"cannot read the manifest of gyrodrift's outputs ({reason})") from None
    try:
        doc = json.loads(text)
    except (ValueError, RecursionError):
        doc = None
    if not (isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT):
        raise _fail(path, f"is not a manifest of format {MANIFEST_FORMAT}; remove it only if gyrodrift wrote it")
    if not isinstance(doc.get("sets"), dict):
        raise UntrustedManifestError(
            f'{os.fspath(path)}: "sets" is {type(doc.get("sets")).__name__}, not a mapping; gyrodrift writes no such '
            "manifest, so it refuses the whole of it and changes nothing in the folder: choose another --out folder"
        )
    _validate_manifest(folder, doc)
    return doc


def _write_manifest(folder: Path, doc: dict[str, Any]) -> None:
    tmp = _create_temporary(folder, MANIFEST_NAME)
    try:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(_json_text(doc))
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, folder / MANIFEST_NAME)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_directory(folder)


def _owned(manifest: dict[str, Any] | None) -> dict[str, list[dict[str, Any]]]:
    """File name -> the manifest entries (committed sets and an unfinished publication) describing it."""
    owned: dict[str, list[dict[str, Any]]] = {}
    if manifest is None:
        return owned
    for s in manifest["sets"].values():
        for name, entry in s.get("files", {}).items():
            owned.setdefault(name, []).append(entry)
    pending = manifest.get("pending")
    if isinstance(pending, dict):
        for name, entry in pending.get("files", {}).items():
            owned.setdefault(name, []).append(entry)
    return owned


@contextlib.contextmanager
def _locked(folder: Path) -> Iterator[None]:
    """Hold an exclusive advisory lock on `folder` (one publication at a time; no-op without `fcntl`)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        with contextlib.suppress(OSError):  # a file system without locks (some network ones): go on unlocked
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _recover(folder: Path, manifest: dict[str, Any] | None) -> dict[str, Any] | None:
    """Finish a publication a killed run left half done (under the folder's lock): every staged file whose
    temporary is still there is renamed into place (it was complete and fsynced before the journal was
    written), and the set is committed with the files that match it. Returns the manifest now on disk."""
    if manifest is None or not isinstance(manifest.get("pending"), dict):
        return manifest
    pending = manifest.pop("pending")
    command = str(pending.get("command", "?"))
    files: dict[str, Any] = {}
    for name, entry in pending.get("files", {}).items():
        tmp = folder / str(entry.get("tmp", ""))
        if entry.get("tmp") and _TEMP_RE.match(str(entry["tmp"])) and tmp.is_file() and _matches(tmp, entry):
            os.replace(tmp, folder / name)
        if _matches(folder / name, entry):
            files[name] = {k: entry[k] for k in ("bytes", "mtime_ns", "sha256")}
    _commit_set(manifest, command, files, pending.get("meta", {}))
    _write_manifest(folder, manifest)
    return manifest


def _commit_set(manifest: dict[str, Any], command: str, files: dict[str, Any], meta: dict[str, Any]) -> None:
    for other in list(manifest["sets"]):
        kept = {n: e for n, e in manifest["sets"][other].get("files", {}).items() if n not in files}
        manifest["sets"][other]["files"] = kept
        if not kept:
            del manifest["sets"][other]
    if files:
        manifest["sets"][command] = {**meta, "files": files}


def check_complete(path: str | os.PathLike[str]) -> None:
    """Refuse to read a file of a torn output set (for the package's loaders of its own outputs).

    If `path`'s folder has a manifest and lists `path`, no publication of it may be unfinished and every file
    of its set must still be there with the size it was written with (no hashing: a loader calls this at
    every open); otherwise `OutputError` says which file and what to do. A file outside any manifest (a
    user's file, an older gyrodrift's output) passes, and so does a file beside an unreadable manifest or one of
    another format; a manifest of gyrodrift's format whose entries are not plain file names of the folder (or of
    the wrong shape) is refused (`UntrustedManifestError`).
    """
    p = Path(path)
    try:
        manifest = _read_manifest(p.parent)
    except UntrustedManifestError:
        raise
    except OutputError:
        return
    if manifest is None:
        return
    pending = manifest.get("pending")
    if isinstance(pending, dict) and p.name in pending.get("files", {}):
        raise _fail(
            p,
            f"part of an unfinished output of `gyrodrift {pending.get('command', '?')}` (the run was interrupted); "
            "run the command again",
        )
    for command, s in manifest["sets"].items():
        files = s.get("files", {})
        if p.name not in files:
            continue
        for name, entry in files.items():
            try:
                same = os.stat(p.parent / name).st_size == entry.get("bytes")
            except OSError:
                same = False
            if not same:
                raise _fail(
                    p,
                    f"written by `gyrodrift {command}` together with {name}, which has changed or is missing since; "
                    "run the command again",
                )


class Stage:
    """The files of one publication, written as temporaries in the output folder (see `OutputFolder.publish`)."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.files: dict[str, Path] = {}  # name -> temporary, until the publication's journal owns them
        self.last: str | None = None  # the file written last, to name a failed write (which has no file name)

    def file(self, name: str) -> Path:
        """The path to write the output `name` to (a fresh temporary; write it plainly, it is published with
        the rest of the set). Writers taking a stage call this for each of their files."""
        if name in self.files:
            raise ValueError(f"{name} is staged twice")
        if _plain_name_problem(name) is not None:  # the rule a manifest's names are held to
            raise ValueError(f"{name!r} is not a plain output file name")
        with _naming(self.folder / name):
            self.files[name] = _create_temporary(self.folder, name)
        self.last = name
        return self.files[name]

    def _discard(self) -> None:
        for tmp in self.files.values():
            with contextlib.suppress(OSError):
                os.unlink(tmp)


class OutputFolder:
    """A folder receiving a set of files published together; checked at construction, before any work.

    Parameters
    ----------
    path : path-like
        The folder (created with its parents at publication if missing).
    command : str
        The command writing the set (``"navigate"``); recorded in the manifest.
    names : sequence of str
        The files the command will write (checked against the inputs and the folder's content now).
    inputs : paths
        The command's inputs: none of them may be one of the files written.

    Raises
    ------
    OutputError
        `path` is not a folder, an output would replace an input, or the folder holds files gyrodrift did
        not write (the message lists a few and says what to do).

    Examples
    --------
    >>> out = OutputFolder("run", "navigate", ["nav.parquet", "summary.json"], inputs=["imu.parquet"])  # doctest: +SKIP
    >>> # ... hours of work ...
    >>> with out.publish() as stage:  # doctest: +SKIP
    ...     pq.write_table(table, stage.file("nav.parquet"))
    ...     write_json(summary, stage.file("summary.json"))
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        command: str,
        names: Iterable[str],
        *,
        inputs: Iterable[str | os.PathLike[str]] = (),
    ):
        self.path = Path(path)
        self.command = command
        self.names = tuple(names)
        self.inputs = tuple(Path(p) for p in inputs)
        self.check()

    def check(self, names: Iterable[str] | None = None) -> None:
        """Raise `OutputError` unless the folder may receive `names` (default: the planned ones)."""
        names = self.names if names is None else tuple(names)
        folder = self.path
        for name in names:
            for inp in self.inputs:
                if _same_file(folder / name, inp):
                    raise _fail(
                        folder / name, f"would replace an input of this command ({inp}); choose another --out folder"
                    )
        try:
            st = os.stat(folder)
        except (FileNotFoundError, NotADirectoryError):
            ancestor = folder.parent
            while not ancestor.exists() and ancestor != ancestor.parent:
                ancestor = ancestor.parent
            if ancestor.exists() and not ancestor.is_dir():
                raise _fail(folder, f"cannot be created: {ancestor} is not a folder") from None
            reason = _unwritable_reason(ancestor)
            if reason is not None:
                raise _fail(folder, f"cannot be created in {ancestor}: {reason}") from None
            return
        except OSError as exc:
            raise _fail(folder, os_error_reason(exc)) from None
        if not stat.S_ISDIR(st.st_mode):
            raise _fail(folder, f"is {'a file' if stat.S_ISREG(st.st_mode) else file_kind(st.st_mode)}, not a folder")
        manifest = _read_manifest(folder)
        owned = _owned(manifest)
        foreign = []
        with _naming(folder):
            entries = sorted(os.listdir(folder))
        for entry in entries:
            if entry == MANIFEST_NAME or _TEMP_RE.match(entry):
                continue
            if not any(_matches(folder / entry, e) for e in owned.get(entry, ())):
                foreign.append(entry)
        if foreign:
            shown = ", ".join(foreign[:3]) + (f" and {len(foreign) - 3} more" if len(foreign) > 3 else "")
            raise _fail(
                folder,
                f"holds files gyrodrift did not write or that changed since ({shown}); gyrodrift writes only into "
                "a new or empty folder or one holding only its own outputs: choose another --out folder",
            )
        reason = _unwritable_reason(folder)
        if reason is not None:
            raise _fail(folder, f"cannot be written: {reason}")

    @contextlib.contextmanager
    def publish(self) -> Iterator[Stage]:
        """Stage the set's files, then publish them together.

        Yields a `Stage`; write each file to ``stage.file(name)``. On a clean exit, under the folder's lock:
        a publication a killed run left unfinished is completed, stale temporaries are removed, the folder is
        checked again, the staged files are fsynced and described (size, SHA-256) in a journal in the
        manifest, renamed into place, and the set is committed in the manifest; files of this command's
        previous set that the new set does not have are removed (they are gyrodrift's own). On an exception
        every temporary is removed, a folder created for the run is removed again if empty, and the
        previous outputs are untouched.
        """
        created = []
        folder = self.path
        with _naming(folder):
            missing = folder
            while not missing.exists() and missing != missing.parent:
                created.append(missing)
                missing = missing.parent
            folder.mkdir(parents=True, exist_ok=True)
        clean_stale_temporaries(folder)  # a killed run's gigabytes go before this run adds its own
        stage = Stage(folder)
        try:
            with _naming(folder, stage):
                yield stage
                stage.last = None
                self._commit(stage)
        except BaseException:
            stage._discard()
            for made in created:
                with contextlib.suppress(OSError):
                    os.rmdir(made)
            raise

    def _commit(self, stage: Stage) -> None:
        folder = self.path
        for tmp in stage.files.values():
            _fsync_file(tmp)
        with _locked(folder):
            manifest = _recover(folder, _read_manifest(folder))
            self.check(stage.files)
            clean_stale_temporaries(folder, keep=[t.name for t in stage.files.values()])
            if manifest is None:
                manifest = {"format": MANIFEST_FORMAT, "sets": {}}
            from gyrodrift import __version__

            meta = {
                "gyrodrift_version": __version__,
                "written_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            }
            described = {name: _describe(tmp) for name, tmp in stage.files.items()}
            old = manifest["sets"].get(self.command, {}).get("files", {})
            manifest["pending"] = {
                "command": self.command,
                "meta": meta,
                "files": {name: {**d, "tmp": stage.files[name].name} for name, d in described.items()},
            }
            _write_manifest(folder, manifest)
            journal = dict(stage.files)
            stage.files.clear()  # from here on the journal owns the temporaries: a failure rolls forward
            try:
                for name, tmp in journal.items():
                    os.replace(tmp, folder / name)
            except BaseException:
                with contextlib.suppress(Exception):
                    _recover(folder, _read_manifest(folder))
                raise
            _fsync_directory(folder)
            del manifest["pending"]
            _commit_set(manifest, self.command, described, meta)
            _write_manifest(folder, manifest)
            for name, entry in old.items():
                if name not in described and _matches(folder / name, entry):
                    with contextlib.suppress(OSError):
                        os.unlink(folder / name)


def output_folder(
    out: str | os.PathLike[str] | OutputFolder,
    command: str,
    names: Iterable[str],
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> OutputFolder:
    """`out` itself if it is an `OutputFolder` (checked by a caller that knows more inputs, e.g. the CLI), else
    ``OutputFolder(out, command, names, inputs=inputs)`` (checked now)."""
    if isinstance(out, OutputFolder):
        out.check()
        return out
    return OutputFolder(out, command, names, inputs=inputs)


@contextlib.contextmanager
def staged(out: str | os.PathLike[str] | OutputFolder | Stage, command: str, names: Iterable[str]) -> Iterator[Stage]:
    """The stage a writer of several files writes into.

    `out` may be a `Stage` of a larger publication (yielded as it is: the caller publishes), an `OutputFolder`
    already checked by the caller (e.g. the CLI, which knows the inputs), or a folder path (checked now, for
    `command` and `names`, and published as one set when the block ends).
    """
    if isinstance(out, Stage):
        yield out
        return
    with output_folder(out, command, names).publish() as stage:
        yield stage
