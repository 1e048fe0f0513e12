"""A campaign on a real dask cluster (issue 18, item 7): a ``dask scheduler`` and two ``dask worker`` processes on
the loopback address, started once for the module from the ``dask`` command line. Killing one worker with
SIGKILL mid-run, or the client (``gyrodrift campaign --scheduler``) and resuming, leaves every run in the store
exactly once and no temporary file. Every wait has a deadline and every process started here is killed (its whole
process group) when the module's tests end, passed or not."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import sysconfig
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from test_campaign_store_checks import FAST

from gyrodrift.cli import main
from gyrodrift.fleet.store import read_runs

COUNT = 4
CAMPAIGN = FAST.format(count=COUNT).replace("rate_hz = 1.0", "rate_hz = 4.0") + (
    '\n[vary."site.lat_deg"]\ndist = "uniform"\nlow = 20.0\nhigh = 60.0\n'
)
"""Four 2 h runs at 4 Hz (1 h alignment, 1 h navigation; test_campaign_store_checks's): about 2 s each on a quiet
machine."""

DEADLINE_S = 90.0
"""The longest any single wait of these tests may take [s] (a loaded 2-core machine)."""


def _dask() -> str:
    pytest.importorskip("distributed")
    exe = Path(sysconfig.get_path("scripts")) / "dask"
    if not exe.is_file():
        pytest.skip("the dask command line (dask[distributed]) is not installed next to this Python")
    return str(exe)


def _kill_group(proc: subprocess.Popen) -> None:
    """SIGKILL the process group `proc` leads (it was started in a session of its own) and reap it."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:  # pragma: no cover - SIGKILL is not ignored
        pass


def _wait(what: str, ready, procs=(), timeout: float = DEADLINE_S) -> None:
    """Poll `ready()` until true; fail naming `what` after `timeout` s or when one of `procs` has ended."""
    t = time.monotonic()
    while time.monotonic() - t < timeout:
        if ready():
            return
        for p, log in procs:
            if p.poll() is not None:
                raise AssertionError(f"{what}: a process ended early (exit {p.returncode}):\n{log.read_text()[-3000:]}")
        time.sleep(0.1)
    raise AssertionError(f"{what}: not within {timeout:g} s")


@dataclass
class Cluster:
    address: str
    workers: list[subprocess.Popen]
    start: Any  # start(args, log, stdout=None) -> Popen (log and stdout: file paths), torn down with the cluster
    watcher: Any  # a dask Client of the test's, to see what the scheduler has the workers doing

    def worker(self, address: str) -> subprocess.Popen:
        """The worker process serving at `address` (by the name ``wK`` it was started with)."""
        name = self.watcher.scheduler_info()["workers"][address]["name"]
        return self.workers[int(str(name)[1:])]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler on a free loopback port (port 0: the system picks it; the address is read from its scheduler
    file) and two single-thread workers with no dashboard, each in a local directory of its own. Shared by the
    module's tests (each cluster start is three interpreters): the worker-kill test leaves one worker, which the
    client-kill test needs (it only needs the scheduler and a worker to run on)."""
    dask = _dask()
    tmp_path = tmp_path_factory.mktemp("cluster")
    procs: list[subprocess.Popen] = []
    logs: list[object] = []
    watcher = None

    def start(args: list[str], log_path: Path, stdout_path: Path | None = None) -> subprocess.Popen:
        log = open(log_path, "w")  # files, not pipes: dask's logging can never block on them
        logs.append(log)
        stdout = subprocess.STDOUT
        if stdout_path is not None:
            stdout = open(stdout_path, "w")
            logs.append(stdout)
        proc = subprocess.Popen(
            args,
            stdout=log if stdout_path is None else stdout,
            stderr=subprocess.STDOUT if stdout_path is None else log,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
            env={**os.environ, "DASK_TEMPORARY_DIRECTORY": str(tmp_path / "scratch")},  # not /tmp/dask-scratch-space
        )
        procs.append(proc)
        return proc

    try:
        sched_file = tmp_path / "scheduler.json"
        scheduler = start(
            [dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard"]
            + ["--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(sched_file)],
            tmp_path / "scheduler.log",
        )

        def address() -> str | None:
            try:
                return json.loads(sched_file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                return None

        _wait("the scheduler's address", lambda: address() is not None, [(scheduler, tmp_path / "scheduler.log")])
        addr = address()
        assert addr is not None and addr.startswith("tcp://127.0.0.1:")
        workers = []
        for k in range(2):
            (tmp_path / f"w{k}").mkdir()
            workers.append(
                start(
                    [dask, "worker", addr, "--nthreads", "1", "--no-dashboard", "--no-nanny", "--host", "127.0.0.1"]
                    + ["--local-directory", str(tmp_path / f"w{k}"), "--name", f"w{k}", "--death-timeout", "60"],
                    tmp_path / f"worker{k}.log",
                )
            )
        from dask.distributed import Client

        watcher = Client(addr, timeout=DEADLINE_S)  # the test's own view of the scheduler
        watcher.wait_for_workers(2, timeout=DEADLINE_S)
        yield Cluster(addr, workers, start, watcher)
    finally:
        if watcher is not None:
            watcher.close(timeout=30)
        for proc in reversed(procs):
            _kill_group(proc)
        for log in logs:
            log.close()


def _campaign_cmd(src: Path, out: Path, address: str) -> list[str]:
    cli = [sys.executable, "-c", "from gyrodrift.cli import main; main()", "campaign", str(src), "--out", str(out)]
    return [*cli, "--scheduler", address, "--connect-timeout-s", "30", "--quiet", "--json"]


def _files(out: Path) -> dict[str, int]:
    runs = out / "runs"
    return {p.name: p.stat().st_mtime_ns for p in runs.glob("run-*.parquet")} if runs.is_dir() else {}


def _check_every_run_once(out: Path) -> None:
    assert sorted(_files(out)) == [f"run-{i:06d}.parquet" for i in range(COUNT)]
    assert not [e for e in os.listdir(out / "runs") if not e.startswith("run-")]  # no temporaries left
    runs = read_runs(out)
    assert list(runs["index"]) == list(range(COUNT)) and list(runs["run"]) == [f"r{i:06d}" for i in range(COUNT)]
    assert all(e is None for e in runs["error"]), runs["error"]


def _worker_pid(out: Path, name: str) -> int:
    """The pid of the worker that processed committed run file `name` (its ``worker`` column: host-pid)."""
    import pyarrow.parquet as pq

    return int(pq.read_table(out / "runs" / name, columns=["worker"]).column("worker")[0].as_py().rsplit("-", 1)[1])


def _start_campaign(cluster: Cluster, tmp_path: Path) -> tuple[Path, Path, subprocess.Popen]:
    """``(campaign file, store, client)``: `CAMPAIGN` started on `cluster`, once its first run is committed."""
    src, out = tmp_path / "c.toml", tmp_path / "out"
    src.write_text(CAMPAIGN)
    client = cluster.start(_campaign_cmd(src, out, cluster.address), tmp_path / "client.log", tmp_path / "client.json")
    _wait("the first run committed", lambda: len(_files(out)) >= 1, [(client, tmp_path / "client.log")])
    return src, out, client


@pytest.mark.slow  # 23-26 s at a load average of 7-12 on 2 cores, 65-75 s at 17-26 (interpreter start-ups)
def test_a_worker_killed_mid_run_loses_nothing_and_duplicates_nothing(cluster, tmp_path):
    _, out, client = _start_campaign(cluster, tmp_path)
    processing = {addr: keys for addr, keys in cluster.watcher.processing().items() if keys}
    assert processing, "every run was done before a worker could be killed: make the runs longer"
    victim = cluster.worker(sorted(processing)[0])  # a worker in the middle of a run
    assert victim.poll() is None
    os.killpg(victim.pid, signal.SIGKILL)
    victim.wait(timeout=30)
    _wait("the campaign", lambda: client.poll() is not None, timeout=3 * DEADLINE_S)
    assert client.returncode == 0, (tmp_path / "client.log").read_text()
    doc = json.loads((tmp_path / "client.json").read_text())
    assert (doc["done_now"], doc["failed_now"], doc["not_committed"]) == (COUNT, 0, 0), doc
    _check_every_run_once(out)
    survivor = next(w for w in cluster.workers if w is not victim)
    pids = {_worker_pid(out, name) for name in _files(out)}
    assert survivor.pid in pids  # the surviving worker took the runs over


@pytest.mark.slow  # 23-26 s at a load average of 7-12 on 2 cores, 65-75 s at 17-26 (interpreter start-ups)
def test_the_client_killed_mid_run_resumes_every_run_once(cluster, tmp_path):
    src, out, client = _start_campaign(cluster, tmp_path)
    os.killpg(client.pid, signal.SIGKILL)
    client.wait(timeout=30)
    before = _files(out)
    assert 1 <= len(before) < COUNT
    # the same command again, in this process (the resume's point is the store the kill left and the cluster's
    # workers; a client interpreter of its own, importing dask, cost ~1.5 s more)
    rerun = CliRunner().invoke(main, _campaign_cmd(src, out, cluster.address)[3:])
    assert rerun.exit_code == 0, rerun.output
    doc = json.loads(rerun.stdout)
    assert doc["already_done"] == len(before) and doc["done_now"] == COUNT - len(before), doc
    _check_every_run_once(out)
    after = _files(out)
    assert {k: after[k] for k in before} == before  # the runs committed before the kill were not rewritten
