"""gyrodrift.ins: scenarios, IMU simulation and free navigation of a static-base rotation INS.

The per-sample work runs in the Rust core (`gyrodrift._core.ImuSimulator`, `gyrodrift._core.Navigator`);
this package validates scenario files into typed objects, converts user units to SI at the boundary
(docs/ins-binding-contract.md), streams IMU data through Parquet files and reports errors in user units.

Public API
----------
load_scenario(path) -> Scenario
simulate(scenario, *, out_dir=None, chunk_samples=100_000, quiet=True) -> ImuData | Path
navigate(imu, *, hours=None, compensate_drift_deg_h=0.0, gyro_bias_deg_h=None, accel_bias_ug=None,
         initial="auto", site=None, decimation_s=1.0, out_dir=None, quiet=True) -> NavResult

IMU logs (files, in-memory arrays, scenarios simulated on the fly) are read by `gyrodrift.logs`; a bad one
raises `LogError`.
"""

from gyrodrift.ins.navigate import NavResult, navigate
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
    "LogError",
    "NavResult",
    "Rotation",
    "Run",
    "Scenario",
    "ScenarioError",
    "Site",
    "Temperature",
    "load_scenario",
    "navigate",
    "simulate",
    "write_scenario_toml",
]
