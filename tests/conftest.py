"""Fixtures shared by the whole suite: simulated logs built once per test session (once per pytest-xdist worker)."""

from __future__ import annotations

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
