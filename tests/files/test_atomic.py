"""gyrodrift.files.atomic (with manifest, temporaries, recovery): nothing a command did not write is ever lost,
and outputs are whole or absent.

Single files (atomic_write), output folders published as one set (OutputFolder), what may be written
(inputs, devices, FIFOs, symlinks, foreign files and folders), temporaries (removed on failure, stale ones
cleaned) and interrupted publications (journal, recovery, check_complete, a real SIGKILL).
"""

import errno
import json
import os
import random
import signal
import socket
import subprocess
import sys
import textwrap
import time

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gyrodrift.errors import OutputError
from gyrodrift.files import atomic
from gyrodrift.files.atomic import (
    OutputFolder,
    atomic_write,
    atomic_write_json,
    check_complete,
    check_output_file,
    recognise_header,
    write_json,
)
from gyrodrift.files.manifest import MANIFEST_NAME
from gyrodrift.files.recovery import clean_stale_temporaries
from gyrodrift.files.temporaries import HOST, STALE_AFTER_S


def _leftovers(folder):
    """Hidden entries other than the manifest: temporaries must never stay behind."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(".") and p.name != MANIFEST_NAME)


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


# --- one file ---------------------------------------------------------------------------------------------


def test_text_write_replaces_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "out.txt"
    path.write_text("old\n")
    with atomic_write(path) as fh:
        fh.write("new\n")
        # Until the block ends the destination still holds the old content.
        assert path.read_text() == "old\n"
    assert path.read_text() == "new\n"
    assert _leftovers(tmp_path) == []


def test_binary_write(tmp_path):
    path = tmp_path / "blob.bin"
    with atomic_write(path, "wb") as fh:
        fh.write(b"\x00\x01\x02")
    assert path.read_bytes() == b"\x00\x01\x02"


def test_interrupted_write_keeps_the_old_file_and_removes_the_temporary(tmp_path):
    path = tmp_path / "result.json"
    path.write_text('{"ok": true}\n')
    with pytest.raises(RuntimeError, match="power cut"):
        with atomic_write(path) as fh:
            fh.write('{"ok": fal')  # half a file...
            raise RuntimeError("power cut")
    assert path.read_text() == '{"ok": true}\n'
    assert _leftovers(tmp_path) == []


def test_interrupted_first_write_creates_nothing(tmp_path):
    path = tmp_path / "new.txt"
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(path) as fh:
            fh.write("partial")
            raise KeyboardInterrupt
    assert not path.exists()
    assert list(tmp_path.iterdir()) == []


def test_bad_mode_is_refused(tmp_path):
    with pytest.raises(ValueError, match="mode must be 'w' or 'wb', got 'a'"):
        with atomic_write(tmp_path / "x", "a"):
            pass


def test_json_round_trip_and_nan_refused_without_touching_old_file(tmp_path):
    path = tmp_path / "s.json"
    atomic_write_json({"a": [1, 2.5], "b": "x"}, path)
    assert json.loads(path.read_text()) == {"a": [1, 2.5], "b": "x"}
    with pytest.raises(ValueError):
        atomic_write_json({"a": float("nan")}, path)
    assert json.loads(path.read_text()) == {"a": [1, 2.5], "b": "x"}
    assert _leftovers(tmp_path) == []


def test_written_files_get_ordinary_permissions(tmp_path):
    old = os.umask(0o022)
    try:
        atomic_write_json({"a": 1}, tmp_path / "a.json")
        with OutputFolder(tmp_path / "d", "test", ["f"]).publish() as stage:
            stage.file("f").write_text("x")
    finally:
        os.umask(old)
    assert (tmp_path / "a.json").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "d" / "f").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "d").stat().st_mode & 0o777 == 0o755


# --- what may be written ----------------------------------------------------------------------------------


def test_an_output_that_is_an_input_is_refused_by_path_symlink_and_hard_link(tmp_path):
    data = tmp_path / "runs.csv"
    data.write_text("run,lat_deg\n")
    (tmp_path / "link.csv").symlink_to(data)
    os.link(data, tmp_path / "hard.csv")
    for out in (data, tmp_path / "link.csv", tmp_path / "hard.csv", tmp_path / "." / "runs.csv"):
        with pytest.raises(OutputError, match="is also an input of this command"):
            with atomic_write(out, inputs=[data]) as fh:
                fh.write("x")
    assert data.read_text() == "run,lat_deg\n"
    assert _leftovers(tmp_path) == []


def test_directories_fifos_sockets_and_devices_are_refused(tmp_path):
    (tmp_path / "dir.csv").mkdir()
    os.mkfifo(tmp_path / "fifo")
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp_path / "sock"))
    cases = {"dir.csv": "is a directory", "fifo": "is a FIFO", "sock": "is a socket"}
    try:
        os.mknod(tmp_path / "full", 0o666 | 0o020000, os.makedev(1, 7))  # a /dev/full of our own (root only)
        cases["full"] = "is a device"
    except (PermissionError, OSError):
        pass
    try:
        for name, reason in cases.items():
            with pytest.raises(OutputError, match=f"{name}: {reason}"):
                check_output_file(tmp_path / name)
            with pytest.raises(OutputError, match=reason):
                atomic_write_json({"a": 1}, tmp_path / name)
        assert (tmp_path / "dir.csv").is_dir() and (tmp_path / "fifo").is_fifo()
    finally:
        sock.close()
    assert _leftovers(tmp_path) == []


def test_a_file_gyrodrift_did_not_write_is_refused_and_kept(tmp_path):
    ours = recognise_header("run,t_h,lat_err_arcsec\n")
    path = tmp_path / "curves.csv"
    path.write_text("my notes\n")
    with pytest.raises(OutputError, match="exists and is not a curves table written by gyrodrift"):
        with atomic_write(path, recognise=ours, what="curves table") as fh:
            fh.write("run,t_h,lat_err_arcsec\n")
    assert path.read_text() == "my notes\n"
    with pytest.raises(OutputError, match="/proc/version: exists and is not a"):
        check_output_file("/proc/version", recognise=ours)
    path.write_text("")  # an empty file holds nothing to lose
    with atomic_write(path, recognise=ours) as fh:
        fh.write("run,t_h,lat_err_arcsec\n1,0,0.5\n")
    with atomic_write(path, recognise=ours) as fh:  # our own output: replaced
        fh.write("run,t_h,lat_err_arcsec\n2,0,0.5\n")
    assert path.read_text().endswith("2,0,0.5\n")
    assert _leftovers(tmp_path) == []


def test_a_symlink_is_followed_its_target_replaced_and_the_link_kept(tmp_path):
    (tmp_path / "models").mkdir()
    target = tmp_path / "models" / "m.json"
    target.write_text('{"old": 1}\n')
    link = tmp_path / "current.json"
    link.symlink_to(target)
    atomic_write_json({"new": 2}, link)
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert json.loads(target.read_text()) == {"new": 2}
    dangling = tmp_path / "next.json"
    dangling.symlink_to(tmp_path / "models" / "next.json")
    atomic_write_json({"n": 3}, dangling)
    assert dangling.is_symlink() and json.loads((tmp_path / "models" / "next.json").read_text()) == {"n": 3}
    assert _leftovers(tmp_path) == [] and _leftovers(tmp_path / "models") == []


def test_a_missing_folder_is_named_before_any_work(tmp_path):
    with pytest.raises(OutputError, match="the folder .*nope does not exist"):
        check_output_file(tmp_path / "nope" / "m.json")


# --- injected file-system failures --------------------------------------------------------------------------


class _FailingFile:
    """A file object whose writes fail with `code`, as on a full or read-only device."""

    def __init__(self, fh, code):
        self._fh, self._code = fh, code

    def write(self, data):
        raise OSError(self._code, os.strerror(self._code))

    def __getattr__(self, name):
        return getattr(self._fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._fh.close()


@pytest.mark.parametrize("code, reason", [(errno.ENOSPC, "no space left on the device"), (errno.EROFS, "read-only")])
def test_a_failing_write_is_one_error_naming_the_file_and_leaves_the_old_one(tmp_path, monkeypatch, code, reason):
    path = tmp_path / "m.json"
    atomic_write_json({"v": 1}, path)
    monkeypatch.setattr(atomic, "open", lambda *a, **k: _FailingFile(open(*a, **k), code), raising=False)
    with pytest.raises(OutputError, match=f"m.json: {reason}"):
        atomic_write_json({"v": 2}, path)
    assert json.loads(path.read_text()) == {"v": 1}
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize(
    "code, reason",
    [(errno.ENOSPC, "no space left"), (errno.EROFS, "read-only file system"), (errno.EACCES, "permission denied")],
)
def test_a_failing_rename_or_create_leaves_everything_as_it_was(tmp_path, monkeypatch, code, reason):
    path = tmp_path / "m.json"
    atomic_write_json({"v": 1}, path)

    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code), args[0] if args else None)

    monkeypatch.setattr(atomic.os, "replace", fail)
    with pytest.raises(OutputError, match=f"m.json: {reason}"):
        atomic_write_json({"v": 2}, path)
    monkeypatch.undo()
    assert json.loads(path.read_text()) == {"v": 1}
    assert _leftovers(tmp_path) == []
    real_open = os.open
    monkeypatch.setattr(
        atomic.os, "open", lambda p, flags, *a: fail(p) if flags & os.O_CREAT else real_open(p, flags, *a)
    )
    with pytest.raises(OutputError, match=reason):
        atomic_write_json({"v": 3}, path)
    with pytest.raises(OutputError, match=reason):
        with OutputFolder(tmp_path / "set", "test", ["a"]).publish() as stage:
            stage.file("a").write_text("x")
    monkeypatch.undo()
    assert json.loads(path.read_text()) == {"v": 1} and not (tmp_path / "set").exists()
    assert _leftovers(tmp_path) == []


def test_a_parquet_write_failing_with_no_space_names_the_file(tmp_path, monkeypatch):
    folder = tmp_path / "nav"
    with OutputFolder(folder, "navigate", ["nav.parquet"]).publish() as stage:
        pq.write_table(pa.table({"t_s": [0.0]}), stage.file("nav.parquet"))
    before = _snapshot(folder)

    def full(table, where, **kwargs):
        with open(where, "wb") as fh:
            fh.write(b"PAR1 half")
        raise OSError(errno.ENOSPC, "Error writing bytes to file. Detail: [errno 28] No space left on device")

    monkeypatch.setattr(pq, "write_table", full)
    with pytest.raises(OutputError, match=r"nav[/\\]nav.parquet: no space left on the device"):
        with OutputFolder(folder, "navigate", ["nav.parquet"]).publish() as stage:
            pq.write_table(pa.table({"t_s": [1.0]}), stage.file("nav.parquet"))
    assert _snapshot(folder) == before and _leftovers(folder) == []


# --- output folders ---------------------------------------------------------------------------------------


def _publish(folder, command, files, **kwargs):
    with OutputFolder(folder, command, list(files), **kwargs).publish() as stage:
        for name, text in files.items():
            stage.file(name).write_text(text)


def test_a_set_is_published_with_a_manifest_and_republished_in_place(tmp_path):
    folder = tmp_path / "nav"
    _publish(folder, "navigate", {"nav.parquet": "n1", "summary.json": "s1"})
    manifest = json.loads((folder / MANIFEST_NAME).read_text())
    files = manifest["sets"]["navigate"]["files"]
    assert sorted(files) == ["nav.parquet", "summary.json"] and files["summary.json"]["bytes"] == 2
    assert len(files["nav.parquet"]["sha256"]) == 64 and "pending" not in manifest
    _publish(folder, "navigate", {"nav.parquet": "n2", "summary.json": "s2"})
    assert (folder / "nav.parquet").read_text() == "n2" and (folder / "summary.json").read_text() == "s2"
    check_complete(folder / "nav.parquet")
    assert _leftovers(folder) == []


def test_a_folder_with_foreign_files_is_refused_before_any_work_and_kept(tmp_path):
    folder = tmp_path / "d"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    with pytest.raises(OutputError, match=r"holds files gyrodrift did not write.*\(notes.txt\).*choose another --out"):
        OutputFolder(folder, "reproduce", ["results.json"])
    assert _snapshot(folder) == {"notes.txt": b"mine"}


def test_a_changed_output_is_no_longer_ours(tmp_path):
    folder = tmp_path / "d"
    _publish(folder, "evaluate", {"evaluation.json": "{}", "position_error.png": "png"})
    (folder / "evaluation.json").write_text('{"edited": "by hand"}')
    with pytest.raises(OutputError, match=r"changed since \(evaluation.json\)"):
        OutputFolder(folder, "evaluate", ["evaluation.json", "position_error.png"])
    with pytest.raises(OutputError, match="together with evaluation.json, which has changed"):
        check_complete(folder / "position_error.png")


def test_outputs_of_other_commands_are_kept_and_an_input_inside_is_never_replaced(tmp_path):
    folder = tmp_path / "sim"
    _publish(folder, "simulate", {"imu.parquet": "imu", "scenario.resolved.toml": "toml"})
    _publish(folder, "navigate", {"nav.parquet": "nav", "summary.json": "sum"}, inputs=[folder / "imu.parquet"])
    assert _snapshot(folder)["imu.parquet"] == b"imu"
    sets = json.loads((folder / MANIFEST_NAME).read_text())["sets"]
    assert sorted(sets) == ["navigate", "simulate"]
    with pytest.raises(OutputError, match="would replace an input of this command"):
        OutputFolder(folder, "navigate", ["imu.parquet"], inputs=[folder / "imu.parquet"])
    with pytest.raises(OutputError, match="would replace an input"):  # the same file through a symlink
        (tmp_path / "alias.parquet").symlink_to(folder / "imu.parquet")
        OutputFolder(folder, "navigate", ["imu.parquet"], inputs=[tmp_path / "alias.parquet"])
    check_complete(folder / "imu.parquet")


def test_a_file_where_a_folder_is_expected_is_refused(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(OutputError, match="f: is a file, not a folder"):
        OutputFolder(tmp_path / "f", "truth", ["a"])
    with pytest.raises(OutputError, match="cannot be created: .*f is not a folder"):
        OutputFolder(tmp_path / "f" / "sub", "truth", ["a"])


def test_the_current_folder_is_a_valid_output_when_empty(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _publish(".", "reproduce", {"results.json": "{}"})
    _publish(".", "reproduce", {"results.json": "{}\n"})
    assert sorted(os.listdir(tmp_path)) == [MANIFEST_NAME, "results.json"]


def test_a_failed_publication_leaves_the_previous_set_and_no_temporary(tmp_path):
    folder = tmp_path / "r"
    _publish(folder, "reproduce", {"results.json": "old", "report.md": "old"})
    before = _snapshot(folder)
    for exc in (RuntimeError("boom"), KeyboardInterrupt()):
        with pytest.raises(type(exc)):
            with OutputFolder(folder, "reproduce", ["results.json", "report.md"]).publish() as stage:
                stage.file("results.json").write_text("new")
                raise exc
        assert _snapshot(folder) == before and _leftovers(folder) == []
    with pytest.raises(RuntimeError):  # a folder made for the run goes again
        with OutputFolder(tmp_path / "a" / "b", "truth", ["x"]).publish() as stage:
            stage.file("x").write_text("x")
            raise RuntimeError
    assert sorted(os.listdir(tmp_path)) == ["r"]


def test_files_the_new_set_lacks_are_removed_only_when_ours(tmp_path):
    folder = tmp_path / "d"
    _publish(folder, "identify", {"identification.json": "1", "extra.png": "2"})
    _publish(folder, "identify", {"identification.json": "3"})
    assert sorted(os.listdir(folder)) == [MANIFEST_NAME, "identification.json"]


def test_a_foreign_or_broken_manifest_is_refused_not_overwritten(tmp_path):
    folder = tmp_path / "d"
    folder.mkdir()
    (folder / MANIFEST_NAME).write_text("not json")
    with pytest.raises(OutputError, match="is not a manifest of format gyrodrift-manifest/1"):
        OutputFolder(folder, "truth", ["a"])
    assert (folder / MANIFEST_NAME).read_text() == "not json"


# --- temporaries and interrupted publications ----------------------------------------------------------------


def _dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_stale_temporaries_are_cleaned_and_nothing_else(tmp_path):
    folder = tmp_path / "d"
    folder.mkdir()
    host = HOST
    other = "0" * 8 if host != "0" * 8 else "1" * 8
    dead = folder / f".nav.parquet.gyrodrift-tmp-{host}-{_dead_pid()}-{'a' * 12}"
    live = folder / f".nav.parquet.gyrodrift-tmp-{host}-{os.getppid()}-{'b' * 12}"
    old = folder / f".summary.json.gyrodrift-tmp-{other}-1-{'c' * 12}"
    young = folder / f".summary.json.gyrodrift-tmp-{other}-1-{'d' * 12}"
    users = [folder / ".nav.parquet.gyrodrift-tmp-mine", folder / ".hidden"]
    for p in (dead, live, old, young, *users):
        p.write_text("x" * 1000)
    os.utime(old, (time.time() - STALE_AFTER_S - 60,) * 2)
    atomic_write_json({"a": 1}, folder / "m.json")  # the next run into the folder cleans up
    assert not dead.exists() and not old.exists()
    assert live.exists() and young.exists() and all(p.exists() for p in users)
    assert clean_stale_temporaries(folder) == []


def test_a_killed_runs_temporaries_go_when_the_next_publication_starts(tmp_path):
    folder = tmp_path / "sim"
    _publish(folder, "simulate", {"imu.parquet": "1"})
    stale = folder / f".imu.parquet.gyrodrift-tmp-{HOST}-{_dead_pid()}-{'e' * 12}"
    stale.write_bytes(b"x" * 10000)  # what a SIGKILLed 72 h simulate leaves (1 GB in real life)
    OutputFolder(folder, "simulate", ["imu.parquet"])  # a stale temporary is no foreign file
    with OutputFolder(folder, "simulate", ["imu.parquet"]).publish() as stage:
        assert not stale.exists()  # gone before this run writes its own
        stage.file("imu.parquet").write_text("2")
    assert _leftovers(folder) == []


def _torn(folder, monkeypatch):
    """Publish n2/s2 over n1/s1, 'killed' after nav.parquet is renamed: no recovery, no cleanup."""
    _publish(folder, "navigate", {"nav.parquet": "n1", "summary.json": "s1"})
    real_replace = os.replace

    class Killed(BaseException):
        pass

    def replace(src, dst):
        if str(dst).endswith("summary.json"):
            raise Killed
        real_replace(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    monkeypatch.setattr(atomic, "finish_publication", lambda folder, manifest: manifest)
    monkeypatch.setattr(atomic.Stage, "_discard", lambda self: None)
    with pytest.raises(Killed):
        _publish(folder, "navigate", {"nav.parquet": "n2", "summary.json": "s2"})
    monkeypatch.undo()


def test_a_torn_set_is_told_by_readers_and_completed_by_the_next_run(tmp_path, monkeypatch):
    folder = tmp_path / "nav"
    _torn(folder, monkeypatch)
    assert (folder / "nav.parquet").read_text() == "n2" and (folder / "summary.json").read_text() == "s1"
    for name in ("nav.parquet", "summary.json"):
        with pytest.raises(OutputError, match="unfinished output of `gyrodrift navigate`.*run the command again"):
            check_complete(folder / name)
    clean_stale_temporaries(folder)  # the journal's temporaries are kept for the recovery
    OutputFolder(folder, "navigate", ["nav.parquet", "summary.json"])  # still recognised as ours
    _publish(folder, "simulate", {"imu.parquet": "i"})  # any publication into the folder completes it first
    assert (folder / "summary.json").read_text() == "s2"
    check_complete(folder / "nav.parquet")
    assert _leftovers(folder) == []


def test_a_failing_rename_mid_set_rolls_forward_to_the_new_set(tmp_path, monkeypatch):
    folder = tmp_path / "nav"
    _publish(folder, "navigate", {"nav.parquet": "n1", "summary.json": "s1"})
    real_replace = os.replace
    failed = []

    def replace(src, dst):
        if str(dst).endswith("summary.json") and not failed:
            failed.append(dst)
            raise OSError(errno.EIO, "Input/output error", src)
        real_replace(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    with pytest.raises(OutputError, match="summary.json: input/output error"):
        _publish(folder, "navigate", {"nav.parquet": "n2", "summary.json": "s2"})
    assert _snapshot(folder)["nav.parquet"] == b"n2" and _snapshot(folder)["summary.json"] == b"s2"
    check_complete(folder / "summary.json")
    assert _leftovers(folder) == []


_WRITER = textwrap.dedent(
    """
    import sys
    from gyrodrift.files.atomic import OutputFolder
    folder = sys.argv[1]
    v = 0
    while True:
        v += 1
        with OutputFolder(folder, "navigate", ["nav.parquet", "summary.json"]).publish() as stage:
            stage.file("nav.parquet").write_text(f"{v}\\n" * 20000)
            stage.file("summary.json").write_text(f"{v}")
        if v == 1:
            print("ready", flush=True)
    """
)


def test_sigkill_at_a_random_moment_leaves_the_old_or_the_new_set_or_a_told_one(tmp_path):
    rng = random.Random(8)
    outcomes = {"whole": 0, "torn_then_completed": 0}
    for trial in range(6):
        folder = tmp_path / f"k{trial}"
        proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(folder)], stdout=subprocess.PIPE)
        assert proc.stdout.readline() == b"ready\n"
        time.sleep(rng.uniform(0.0, 0.3))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        try:
            check_complete(folder / "nav.parquet")
            check_complete(folder / "summary.json")
            outcomes["whole"] += 1
        except OutputError:
            outcomes["torn_then_completed"] += 1
            OutputFolder(folder, "navigate", ["nav.parquet", "summary.json"])
            _publish(folder, "simulate", {"imu.parquet": "i"})  # the next run into it completes the set
            check_complete(folder / "nav.parquet")
        v = (folder / "summary.json").read_text()
        assert set((folder / "nav.parquet").read_text().split()) == {v}
        clean_stale_temporaries(folder)
        _publish(folder, "navigate", {"nav.parquet": "z", "summary.json": "z"})
        assert _leftovers(folder) == []
    assert sum(outcomes.values()) == 6


def test_write_json_refuses_nan_before_writing(tmp_path):
    with pytest.raises(ValueError):
        write_json({"x": float("inf")}, tmp_path / "a.json")
    assert not (tmp_path / "a.json").exists()
