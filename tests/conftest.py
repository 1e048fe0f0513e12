"""Fixtures shared by the whole suite: simulated logs built once per test session (once per pytest-xdist worker),
and one reproduction of the paper shared by every worker of the session."""

from __future__ import annotations

import fcntl
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from gyrodrift.ins import Scenario, simulate


@pytest.fixture(scope="session")
def simulated_log(tmp_path_factory: pytest.TempPathFactory) -> Callable[[dict[str, Any]], Path]:
    """``simulated_log(scenario_dict)``: the path of the scenario's ``imu.parquet``, simulated once per session.

    Equal scenario dicts (the TOML sections as a dict) share one log, so a test must not modify it: copy it first.
    """
    logs: dict[str, Path] = {}

    def log_of(scenario: dict[str, Any]) -> Path:
        key = json.dumps(scenario, sort_keys=True)
        if key not in logs:
            folder = tmp_path_factory.mktemp("simulated_log")
            logs[key] = simulate(Scenario.from_dict(scenario), out_dir=folder / "run", quiet=True)
        return logs[key]

    return log_of


@pytest.fixture(scope="session")
def paper_reproduction(tmp_path_factory: pytest.TempPathFactory, worker_id: str) -> tuple[Path, dict[str, Any]]:
    """``(folder, results)`` of ``reproduce(folder, seed=3, quiet=True)``: the paper's experiment on the embedded data.

    Run once per test session: under pytest-xdist the first worker to ask runs it (its methods in a forked worker
    process, as the command does) while the others wait on a lock (POSIX flock), then read its results.json, which
    holds the same dict (JSON round-trips it exactly; test_deterministic_for_a_seed_wherever_the_methods_run
    compares a fresh run with it). Shared read-only: a test must not modify the folder.
    """
    from gyrodrift.paper.reproduce import reproduce

    base = tmp_path_factory.getbasetemp()
    root = base if worker_id == "master" else base.parent  # the session's folder, shared by its workers
    folder = root / "paper-reproduction"
    with open(root / "paper-reproduction.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if (folder / "results.json").is_file():  # published whole (atomically) by another worker
            return folder, json.loads((folder / "results.json").read_text())
        return folder, reproduce(folder, seed=3, quiet=True)
