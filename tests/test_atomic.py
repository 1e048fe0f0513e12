"""Atomic writes: a reader sees the old file or the whole new one, never a half-written file."""

import json
import os

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gyrodrift.atomic import atomic_directory, atomic_write, atomic_write_json, atomic_write_parquet


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


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


def test_parquet_round_trip_and_interrupted_parquet_write(tmp_path, monkeypatch):
    path = tmp_path / "t.parquet"
    table = pa.table({"t_s": [0.0, 1.0], "lat_deg": [28.0, 28.1]})
    atomic_write_parquet(table, path)
    assert pq.read_table(path).equals(table)

    def broken_write_table(tbl, where, **kwargs):
        with open(where, "wb") as fh:
            fh.write(b"PAR1 half")
        raise OSError("disk full")

    monkeypatch.setattr(pq, "write_table", broken_write_table)
    with pytest.raises(OSError, match="disk full"):
        atomic_write_parquet(pa.table({"t_s": [5.0]}), path)
    assert pq.read_table(path).equals(table)
    assert _leftovers(tmp_path) == []


def test_atomic_directory_swaps_whole_folder_or_nothing(tmp_path):
    dest = tmp_path / "run"
    with atomic_directory(dest) as d:
        (d / "a.txt").write_text("1")
    assert (dest / "a.txt").read_text() == "1"

    with pytest.raises(RuntimeError):
        with atomic_directory(dest) as d:
            (d / "a.txt").write_text("2")
            (d / "b.txt").write_text("half")
            raise RuntimeError("stop")
    assert sorted(os.listdir(dest)) == ["a.txt"]
    assert (dest / "a.txt").read_text() == "1"

    with atomic_directory(dest) as d:
        (d / "b.txt").write_text("3")
    assert sorted(os.listdir(dest)) == ["b.txt"]
    assert _leftovers(tmp_path) == []


def test_written_files_get_ordinary_permissions(tmp_path):
    old = os.umask(0o022)
    try:
        atomic_write_json({"a": 1}, tmp_path / "a.json")
        atomic_write_parquet(pa.table({"x": [1.0]}), tmp_path / "a.parquet")
        with atomic_directory(tmp_path / "d") as d:
            (d / "f").write_text("x")
    finally:
        os.umask(old)
    assert (tmp_path / "a.json").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "a.parquet").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "d").stat().st_mode & 0o777 == 0o755
