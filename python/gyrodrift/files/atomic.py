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

The parts live beside this module: the manifest, and when it is trusted, in `gyrodrift.files.manifest`; the
temporaries in `gyrodrift.files.temporaries`; what a killed run leaves and how the next run clears it in
`gyrodrift.files.recovery`; the one-line errors in `gyrodrift.files.output_errors`.

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
  (dead PID on this host, or untouched for ``STALE_AFTER_S`` seconds) are removed by the next write into that
  folder. Nothing that does not match the pattern is ever deleted.

Every file-system failure becomes an `OutputError` naming the path and the reason (read-only file system, no
space left on the device, is a directory, permission denied); the previous outputs are left as they were.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import json
import os
import re
import stat
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

from gyrodrift.errors import OutputError
from gyrodrift.files.input_files import file_kind
from gyrodrift.files.manifest import (
    MANIFEST_FORMAT,
    MANIFEST_NAME,
    UntrustedManifestError,
    commit_set,
    describe,
    matches,
    owned_files,
    plain_name_problem,
    read_manifest,
    write_manifest,
)
from gyrodrift.files.output_errors import REASONS, naming, os_error_reason, output_error
from gyrodrift.files.recovery import clean_stale_temporaries, finish_publication
from gyrodrift.files.temporaries import TEMP_RE, create_temporary, fsync_directory, fsync_file

__all__ = [
    "OutputFolder",
    "Stage",
    "atomic_files",
    "atomic_write",
    "atomic_write_json",
    "check_complete",
    "check_output_file",
    "check_output_files",
    "output_folder",
    "recognise_json_format",
    "recognise_header",
    "staged",
    "write_json",
]

_HEAD_BYTES = 4096


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
            return REASONS[errno.EROFS]
    except (OSError, AttributeError):  # pragma: no cover - no statvfs (Windows)
        pass
    return REASONS[errno.EACCES]


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
            raise output_error(
                given, f"is also an input of this command ({os.fspath(inp)}); choose another output name"
            )
    real = Path(os.path.realpath(given))
    try:
        st = os.stat(real)
    except FileNotFoundError:
        if not real.parent.is_dir():
            raise output_error(given, f"the folder {Path(given).parent} does not exist") from None
        _check_writable(given, real.parent)
        return real
    except OSError as exc:
        raise output_error(given, os_error_reason(exc)) from None
    if stat.S_ISDIR(st.st_mode):
        raise output_error(given, "is a directory (a file was expected)")
    if not stat.S_ISREG(st.st_mode):
        raise output_error(given, f"is {file_kind(st.st_mode)}; gyrodrift writes only regular files or new paths")
    if recognise is not None:
        with naming(given):
            head = _head(real)
        if head and not recognise(head):
            raise output_error(
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
        raise output_error(given, f"cannot be written{where}: {reason}")


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
        with naming(path):
            tmp = create_temporary(folder, real.name)
            fh = open(tmp, "w", encoding=encoding, newline="") if mode == "w" else open(tmp, "wb")
        with naming(path), fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        with naming(path):
            real = check_output_file(path, inputs=inputs, recognise=recognise, what=what)  # still ours?
            os.replace(tmp, real)
        tmp = None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    fsync_directory(folder)


def check_output_files(*targets: Mapping[str, Any]) -> list[Path]:
    """`check_output_file` for each target (a mapping of its arguments), and no two targets the same file;
    returns the real destinations."""
    reals = [check_output_file(**t) for t in targets]
    for i, real in enumerate(reals):
        for j in range(i):
            if _same_file(real, reals[j]) or real == reals[j]:
                raise output_error(
                    targets[i]["path"], f"is also {os.fspath(targets[j]['path'])}; give two different files"
                )
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
            with naming(t["path"]):
                temporaries.append(create_temporary(real.parent, real.name))
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
            raise output_error(targets[named[-1]]["path"], os_error_reason(exc)) from exc
        for t, tmp in zip(targets, temporaries, strict=True):
            with naming(t["path"]):
                fsync_file(tmp)
        reals = [check_output_file(**t) for t in targets]
        for t, tmp, real in zip(targets, list(temporaries), reals, strict=True):
            with naming(t["path"]):
                os.replace(tmp, real)
            temporaries.remove(tmp)
            fsync_directory(real.parent)
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
        manifest = read_manifest(p.parent)
    except UntrustedManifestError:
        raise
    except OutputError:
        return
    if manifest is None:
        return
    pending = manifest.get("pending")
    if isinstance(pending, dict) and p.name in pending.get("files", {}):
        raise output_error(
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
                raise output_error(
                    p,
                    f"written by `gyrodrift {command}` together with {name}, which has changed or is missing since; "
                    "run the command again",
                )


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
        if plain_name_problem(name) is not None:  # the rule a manifest's names are held to
            raise ValueError(f"{name!r} is not a plain output file name")
        with naming(self.folder / name):
            self.files[name] = create_temporary(self.folder, name)
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
                    raise output_error(
                        folder / name, f"would replace an input of this command ({inp}); choose another --out folder"
                    )
        try:
            st = os.stat(folder)
        except (FileNotFoundError, NotADirectoryError):
            ancestor = folder.parent
            while not ancestor.exists() and ancestor != ancestor.parent:
                ancestor = ancestor.parent
            if ancestor.exists() and not ancestor.is_dir():
                raise output_error(folder, f"cannot be created: {ancestor} is not a folder") from None
            reason = _unwritable_reason(ancestor)
            if reason is not None:
                raise output_error(folder, f"cannot be created in {ancestor}: {reason}") from None
            return
        except OSError as exc:
            raise output_error(folder, os_error_reason(exc)) from None
        if not stat.S_ISDIR(st.st_mode):
            raise output_error(
                folder, f"is {'a file' if stat.S_ISREG(st.st_mode) else file_kind(st.st_mode)}, not a folder"
            )
        manifest = read_manifest(folder)
        owned = owned_files(manifest)
        foreign = []
        with naming(folder):
            entries = sorted(os.listdir(folder))
        for entry in entries:
            if entry == MANIFEST_NAME or TEMP_RE.match(entry):
                continue
            if not any(matches(folder / entry, e) for e in owned.get(entry, ())):
                foreign.append(entry)
        if foreign:
            shown = ", ".join(foreign[:3]) + (f" and {len(foreign) - 3} more" if len(foreign) > 3 else "")
            raise output_error(
                folder,
                f"holds files gyrodrift did not write or that changed since ({shown}); gyrodrift writes only into "
                "a new or empty folder or one holding only its own outputs: choose another --out folder",
            )
        reason = _unwritable_reason(folder)
        if reason is not None:
            raise output_error(folder, f"cannot be written: {reason}")

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
        with naming(folder):
            missing = folder
            while not missing.exists() and missing != missing.parent:
                created.append(missing)
                missing = missing.parent
            folder.mkdir(parents=True, exist_ok=True)
        clean_stale_temporaries(folder)  # a killed run's gigabytes go before this run adds its own
        stage = Stage(folder)
        try:
            with naming(folder, stage):
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
            fsync_file(tmp)
        with _locked(folder):
            manifest = finish_publication(folder, read_manifest(folder))
            self.check(stage.files)
            clean_stale_temporaries(folder, keep=[t.name for t in stage.files.values()])
            if manifest is None:
                manifest = {"format": MANIFEST_FORMAT, "sets": {}}
            from gyrodrift import __version__

            meta = {
                "gyrodrift_version": __version__,
                "written_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            }
            described = {name: describe(tmp) for name, tmp in stage.files.items()}
            old = manifest["sets"].get(self.command, {}).get("files", {})
            manifest["pending"] = {
                "command": self.command,
                "meta": meta,
                "files": {name: {**d, "tmp": stage.files[name].name} for name, d in described.items()},
            }
            write_manifest(folder, manifest)
            journal = dict(stage.files)
            stage.files.clear()  # from here on the journal owns the temporaries: a failure rolls forward
            try:
                for name, tmp in journal.items():
                    os.replace(tmp, folder / name)
            except BaseException:
                with contextlib.suppress(Exception):
                    finish_publication(folder, read_manifest(folder))
                raise
            fsync_directory(folder)
            del manifest["pending"]
            commit_set(manifest, self.command, described, meta)
            write_manifest(folder, manifest)
            for name, entry in old.items():
                if name not in described and matches(folder / name, entry):
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
