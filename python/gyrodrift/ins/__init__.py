"""gyrodrift.ins: scenarios, IMU simulation and free navigation of a rotation INS from a given initial state.

The per-sample work runs in the Rust core (`gyrodrift._core.ImuSimulator`, `gyrodrift._core.Navigator`);
this package validates scenario files into typed objects, converts user units to SI at the boundary
(docs/ins-binding-contract.md), streams IMU data through Parquet files and reports errors in user units.

Public API
----------
load_scenario(path) -> Scenario
simulate(scenario, *, out_dir=None, chunk_samples=100_000, quiet=True) -> ImuData | Path
navigate_from(log, initial: InitialState, settings: NavSettings, *, source=None, reference=None) -> NavResult

The ``navigate`` job (the initial state from the log's truth or its alignment, files written) is
`gyrodrift.procedure.navigate`.

IMU logs (files, in-memory arrays, scenarios simulated on the fly) are read by `gyrodrift.logs`; a bad one
raises `LogError`.
"""

from gyrodrift.ins.navigate import InitialState, NavResult, NavSettings, navigate_from
from gyrodrift.ins.scenario import (
    Accel,
    Attitude,
    Gyro,
    Rotation,
    Run,
    Scenario,
    ScenarioError,
    Temperature,
    load_scenario,
    write_scenario_toml,
)
from gyrodrift.ins.simulate import ImuData, simulate
from gyrodrift.logs import LogError
from gyrodrift.site import Site

__all__ = [
    "Accel",
    "Attitude",
    "Gyro",
    "ImuData",
    "InitialState",
    "LogError",
    "NavResult",
    "NavSettings",
    "Rotation",
    "Run",
    "Scenario",
    "ScenarioError",
    "Site",
    "Temperature",
    "load_scenario",
    "navigate_from",
    "simulate",
    "write_scenario_toml",
]
