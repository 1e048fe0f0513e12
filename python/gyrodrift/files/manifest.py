"""The manifest of an output folder (``.gyrodrift-manifest.json``): which files gyrodrift wrote there, by which
command, sizes, modification times and SHA-256, and the journal of a publication under way.

A manifest is trusted only if every name in it is a plain file name of its folder (no separator, not absolute,
no leading dot, no NUL, no symbolic link) and it has the shape gyrodrift writes; otherwise it is refused whole
(`UntrustedManifestError`) before anything in the folder is touched.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import stat
from pathlib import Path
from typing import Any

from gyrodrift.errors import OutputError
from gyrodrift.files.input_files import NotRegularFileError, read_limited
from gyrodrift.files.output_errors import os_error_reason, output_error
from gyrodrift.files.temporaries import TEMP_RE, create_temporary, fsync_directory

__all__ = [
    "MANIFEST_NAME",
    "MANIFEST_FORMAT",
    "MAX_MANIFEST_BYTES",
    "UntrustedManifestError",
    "plain_name_problem",
    "describe",
    "matches",
    "read_manifest",
    "write_manifest",
    "owned_files",
    "commit_set",
]

MANIFEST_NAME = ".gyrodrift-manifest.json"
"""The manifest of an output folder: which files gyrodrift wrote there, by which command, sizes and SHA-256."""
MANIFEST_FORMAT = "gyrodrift-manifest/1"


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            digest.update(block)
    return digest.hexdigest()


def describe(path: Path) -> dict[str, Any]:
    """What the manifest records of the file at `path`: size [bytes], modification time [ns], SHA-256."""
    st = os.stat(path)
    return {"bytes": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": _sha256(path)}


def matches(path: Path, entry: dict[str, Any]) -> bool:
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


def plain_name_problem(name: object) -> str | None:
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
        problem = plain_name_problem(name)
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
            match = TEMP_RE.match(tmp) if isinstance(tmp, str) and "/" not in tmp and "\0" not in tmp else None
            if match is None or match["name"] != name or plain_name_problem(match.string[1:]) is not None:
                raise bad(f"{where}, file {_shown(name)}:", f'"tmp" is {_shown(tmp)}, not a temporary of that file')
            names.append(match.string)
        for n in names:
            try:
                link = stat.S_ISLNK(os.lstat(folder / n).st_mode)
            except OSError:
                continue
            if link:
                raise bad(f"{where} names {_shown(n)}, which", "is a symbolic link (gyrodrift writes no links)")

    def check_files(where: str, table: dict[str, Any], journal: bool) -> None:
        files = table.get("files")
        if not isinstance(files, dict):
            raise bad(where, f'has "files" {type(files).__name__}, not a mapping of file names')
        for name, entry in files.items():
            check_entry(where, name, entry, journal)

    sets = doc["sets"]
    for command, s in sets.items():
        where = f"the set {_shown(command)}"
        if not isinstance(s, dict):
            raise bad(where, f"is {type(s).__name__}, not a mapping")
        check_files(where, s, journal=False)
    if "pending" in doc:
        pending = doc["pending"]
        where = "the pending journal"
        if not isinstance(pending, dict):
            raise bad(where, f"is {type(pending).__name__}, not a mapping")
        if not isinstance(pending.get("command"), str):
            raise bad(where, f'has "command" {_shown(pending.get("command"))}, not a command name')
        if not isinstance(pending.get("meta"), dict):
            raise bad(where, f'has "meta" {type(pending.get("meta")).__name__}, not a mapping')
        check_files(where, pending, journal=True)


def read_manifest(folder: Path) -> dict[str, Any] | None:
    """The folder's manifest, None without one; an unreadable or foreign manifest is an `OutputError`, one of
    gyrodrift's format whose entries are not plain file names of the folder (or of the wrong shape) an
    `UntrustedManifestError` (see `_validate_manifest`)."""
    path = folder / MANIFEST_NAME
    try:
        raw = read_limited(path, MAX_MANIFEST_BYTES)
        if len(raw) > MAX_MANIFEST_BYTES:
            raise output_error(path, f"a manifest of gyrodrift's outputs holds at most {MAX_MANIFEST_BYTES} bytes")
        text = raw.decode("utf-8")
    except FileNotFoundError:
        return None
    except NotRegularFileError as exc:
        raise output_error(path, f"{exc}; a manifest of gyrodrift's outputs is a regular file") from None
    except (OSError, UnicodeDecodeError) as exc:
        if isinstance(exc, OutputError):
            raise
        reason = os_error_reason(exc) if isinstance(exc, OSError) else "not UTF-8"
        raise output_error(path, f"cannot read the manifest of gyrodrift's outputs ({reason})") from None
    try:
        doc = json.loads(text)
    except (ValueError, RecursionError):
        doc = None
    if not (isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT):
        raise output_error(path, f"is not a manifest of format {MANIFEST_FORMAT}; remove it only if gyrodrift wrote it")
    if not isinstance(doc.get("sets"), dict):
        raise UntrustedManifestError(
            f'{os.fspath(path)}: "sets" is {type(doc.get("sets")).__name__}, not a mapping; gyrodrift writes no such '
            "manifest, so it refuses the whole of it and changes nothing in the folder: choose another --out folder"
        )
    _validate_manifest(folder, doc)
    return doc


def write_manifest(folder: Path, doc: dict[str, Any]) -> None:
    """Replace the manifest of `folder` by `doc`, atomically (temporary, fsync, rename, fsync of the folder)."""
    tmp = create_temporary(folder, MANIFEST_NAME)
    try:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(json.dumps(doc, indent=2, allow_nan=False) + "\n")
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, folder / MANIFEST_NAME)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    fsync_directory(folder)


def owned_files(manifest: dict[str, Any] | None) -> dict[str, list[dict[str, Any]]]:
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


def commit_set(manifest: dict[str, Any], command: str, files: dict[str, Any], meta: dict[str, Any]) -> None:
    """Record in `manifest` the set `files` of `command` (with `meta`); the files leave the sets of other commands
    (an emptied set is dropped)."""
    for other in list(manifest["sets"]):
        kept = {n: e for n, e in manifest["sets"][other].get("files", {}).items() if n not in files}
        manifest["sets"][other]["files"] = kept
        if not kept:
            del manifest["sets"][other]
    if files:
        manifest["sets"][command] = {**meta, "files": files}
