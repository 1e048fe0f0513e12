"""What a killed run leaves in an output folder, and how the next run clears it: stale temporaries
(`clean_stale_temporaries`) and a publication journalled in the manifest but not finished (`finish_publication`,
rolled forward). Nothing that does not match the temporaries' pattern is ever deleted."""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from gyrodrift.errors import OutputError
from gyrodrift.files.manifest import commit_set, matches, read_manifest, write_manifest
from gyrodrift.files.temporaries import TEMP_RE, is_stale

__all__ = ["clean_stale_temporaries", "finish_publication"]


def clean_stale_temporaries(folder: str | os.PathLike[str], keep: Iterable[str] = ()) -> list[str]:
    """Remove the temporaries a killed gyrodrift run left in `folder`; return their names.

    Only names matching ``.NAME.gyrodrift-tmp-HOST-PID-HEX`` are considered, and only those whose writer is
    dead (same host, PID not running) or that were untouched for `STALE_AFTER_S`. Names in `keep` stay.
    """
    folder = Path(folder)
    keep = set(keep)
    with contextlib.suppress(OutputError):  # temporaries of an unfinished publication wait for its recovery
        pending = (read_manifest(folder) or {}).get("pending")
        if isinstance(pending, dict):
            keep.update(str(e.get("tmp")) for e in pending.get("files", {}).values() if isinstance(e, dict))
    removed: list[str] = []
    now = time.time()
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        match = TEMP_RE.match(name)
        if match is None or name in keep or not is_stale(folder, match, now):
            continue
        with contextlib.suppress(FileNotFoundError, IsADirectoryError, PermissionError, OSError):
            os.unlink(folder / name)
            removed.append(name)
    return removed


def finish_publication(folder: Path, manifest: dict[str, Any] | None) -> dict[str, Any] | None:
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
        if entry.get("tmp") and TEMP_RE.match(str(entry["tmp"])) and tmp.is_file() and matches(tmp, entry):
            os.replace(tmp, folder / name)
        if matches(folder / name, entry):
            files[name] = {k: entry[k] for k in ("bytes", "mtime_ns", "sha256")}
    commit_set(manifest, command, files, pending.get("meta", {}))
    write_manifest(folder, manifest)
    return manifest
