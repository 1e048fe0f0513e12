"""gyrodrift.ins: scenarios, IMU simulation and free navigation of a rotation INS from a given initial state.

Public names: `load_scenario`, `Scenario` and its sections, `simulate` -> `ImuData`, `navigate_from` (an
`InitialState`, `NavSettings`) -> `NavResult`; `Site`, `LogError`. The ``navigate`` job (initial state from the log's
truth or its alignment, files written) is `gyrodrift.procedure.navigate`.
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
