"""Ctrl-C during a campaign (a subprocess sent SIGINT): once, the runs in progress are finished and committed
and nothing new starts (exit 130); twice, it aborts at once (the workers are stopped); a rerun then completes
every run, with no duplicate, no temporary and the committed runs untouched."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from pool_processes import pool_workers
from test_campaign_store_checks import FAST

from gyrodrift.cli import main
from gyrodrift.fleet.store import read_runs

TINY = Path(__file__).resolve().parents[2] / "examples" / "campaigns" / "tiny.toml"
COUNT = 8
ABORT_COUNT = 3
"""The second Ctrl-C test's runs: 14 h at 20 Hz (about a second each, measured 1.0-1.1 s on a loaded machine), one
per worker and a third the first commit hands out (its worker starts it before the client commits), so that the
abort, ~0.35 s after that commit, meets it in progress and the rerun has at most two runs left to do (four runs
gave the rerun a third one, ~1 s more, for no claim of its own)."""


def _campaign(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "c.toml"
    p.write_text(text)
    return p


def _tiny(rate_hz: float, count: int) -> str:
    """`count` runs of the tiny campaign (14 h) at `rate_hz`."""
    text = TINY.read_text()
    assert "count = 16" in text and "rate_hz = 5.0" in text
    return text.replace("count = 16", f"count = {count}").replace("rate_hz = 5.0", f"rate_hz = {rate_hz}")


def _committed(out: Path) -> dict[str, int]:
    runs = out / "runs"
    return {p.name: p.stat().st_mtime_ns for p in runs.glob("run-*.parquet")} if runs.is_dir() else {}


def _start(src: Path, out: Path) -> subprocess.Popen:
    cmd = [sys.executable, "-c", "from gyrodrift.cli import main; main()", "campaign", str(src), "--out", str(out)]
    # a session of its own: os.killpg sends SIGINT to the client and its workers, as Ctrl-C in a terminal does
    return subprocess.Popen(
        cmd + ["--workers", "2", "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _wait_for(out: Path, n: int, proc: subprocess.Popen, timeout: float = 120.0) -> None:
    t = time.monotonic()
    while time.monotonic() - t < timeout:
        if len(_committed(out)) >= n:
            return
        if proc.poll() is not None:
            raise AssertionError(f"the campaign ended early: {proc.stderr.read() if proc.stderr else ''}")
        time.sleep(0.05)
    raise AssertionError("no run committed in time")


def _rerun_completes(src: Path, out: Path, before: dict[str, int], count: int) -> None:
    """The same command again completes the campaign (in this process, on one worker: the rerun's point is the
    store the interrupt left, not a fresh interpreter, which cost ~1 s more)."""
    res = CliRunner().invoke(main, ["campaign", str(src), "--out", str(out), "--workers", "1", "--quiet"])
    assert res.exit_code == 0, res.output
    after = _committed(out)
    assert sorted(after) == [f"run-{i:06d}.parquet" for i in range(count)]
    assert {k: after[k] for k in before} == before  # the committed runs were not rewritten
    assert not [e for e in os.listdir(out / "runs") if not e.startswith("run-")]  # no temporaries
    runs = read_runs(out)
    assert list(runs["index"]) == list(range(count)) and all(e is None for e in runs["error"])


def test_first_sigint_finishes_the_runs_in_progress_then_rerun_resumes(tmp_path):
    # test_campaign_store_checks's 2 h runs at 4 Hz (under a second each): a run is in progress at the first commit
    src, out = _campaign(tmp_path, FAST.format(count=COUNT).replace("rate_hz = 1.0", "rate_hz = 4.0")), tmp_path / "out"
    proc = _start(src, out)
    try:
        _wait_for(out, 1, proc)
        seen = len(_committed(out))
        os.killpg(proc.pid, signal.SIGINT)  # the whole group: the workers ignore it and finish their runs
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    m = re.search(r"finishing and committing the (\d+) run\(s\) in progress", err)
    assert m, err
    in_progress = int(m.group(1))
    assert 1 <= in_progress <= 2  # at most one run per worker is handed out
    before = _committed(out)
    assert seen + in_progress <= len(before) < COUNT  # the runs in progress were committed; nothing new started
    assert not [e for e in os.listdir(out / "runs") if not e.startswith("run-")]
    assert len(read_runs(out)) == len(before)  # every committed run is a whole Parquet file
    _rerun_completes(src, out, before, COUNT)


def test_second_sigint_aborts_at_once_and_stops_the_workers(tmp_path):
    psutil = pytest.importorskip("psutil")
    src, out = _campaign(tmp_path, _tiny(20.0, ABORT_COUNT)), tmp_path / "out"  # runs of seconds: the abort meets them
    proc = _start(src, out)
    try:
        _wait_for(out, 1, proc)
        workers = pool_workers(psutil, proc.pid)
        assert workers
        os.killpg(proc.pid, signal.SIGINT)
        time.sleep(0.3)
        t = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - t
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 1 and "aborted" in err and "were not committed" in err, err
    assert took < 10, took
    _gone, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive
    before = _committed(out)
    assert len(before) < ABORT_COUNT
    _rerun_completes(src, out, before, ABORT_COUNT)
