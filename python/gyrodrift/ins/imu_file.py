"""The IMU time-series format written by the simulator (``imu.parquet``): column names, schema and metadata.

Reading it back (with every other IMU log) is `gyrodrift.logs`: the one reader and its checks.

One row per IMU sample; every column name carries its unit (see docs/scenarios.md):

``t_s`` end time of the sample [s]; ``dtheta_{x,y,z}_rad`` angle increments over the sample [rad] and
``dv_{x,y,z}_m_s`` velocity increments [m/s], body frame (x right, y forward, z up); ``temp_c`` system
temperature [deg C]; ``table_angle_deg`` turntable angle about body Up [deg]; ``true_{pitch,roll,yaw}_deg``
true body attitude at the end of the sample [deg]. A moving-base run (scenario with ``[trajectory]``) also has
``true_lat_deg``, ``true_lon_deg`` [deg], ``true_height_m`` [m] and ``true_vel_{e,n,u}_m_s`` [m/s, ENU]: the
vehicle's true position and velocity at the end of the sample (`ROUTE_COLUMNS`).

File key-value metadata (UTF-8 JSON values): ``gyrodrift.format`` = ``"gyrodrift-imu/1"``,
``gyrodrift.scenario`` the resolved scenario in user units (TOML-shaped dict), ``gyrodrift.site`` the true
static position ``{lat_deg, lon_deg, height_m}``, ``gyrodrift.rate_hz`` the sample rate [Hz].
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pyarrow as pa

from gyrodrift.ins.scenario import Scenario
from gyrodrift.logs import TRUTH_COLUMNS

__all__ = [
    "IMU_FORMAT",
    "IMU_COLUMNS",
    "ROUTE_COLUMNS",
    "TRUTH_COLUMNS",
    "imu_columns",
    "imu_schema",
    "core_chunk_to_table",
]

IMU_FORMAT = "gyrodrift-imu/1"
"""Value of the ``gyrodrift.format`` metadata key of imu.parquet files written by this version."""

SENSOR_COLUMNS = (
    "t_s",
    "dtheta_x_rad",
    "dtheta_y_rad",
    "dtheta_z_rad",
    "dv_x_m_s",
    "dv_y_m_s",
    "dv_z_m_s",
)
IMU_COLUMNS = SENSOR_COLUMNS + ("temp_c", "table_angle_deg") + TRUTH_COLUMNS
"""All columns of a static-base imu.parquet, in file order (all float64)."""

ROUTE_COLUMNS = (
    "true_lat_deg",
    "true_lon_deg",
    "true_height_m",
    "true_vel_e_m_s",
    "true_vel_n_m_s",
    "true_vel_u_m_s",
)
"""The true position and velocity columns a moving-base imu.parquet adds after `IMU_COLUMNS`."""


def imu_columns(scenario: Scenario) -> tuple[str, ...]:
    """The columns of the imu.parquet of `scenario`, in file order (`ROUTE_COLUMNS` added on a moving base)."""
    return IMU_COLUMNS + (ROUTE_COLUMNS if scenario.trajectory is not None else ())


def imu_schema(scenario: Scenario) -> pa.Schema:
    """The Arrow schema of imu.parquet, with the scenario and truth in its key-value metadata."""
    meta = {
        "gyrodrift.format": IMU_FORMAT,
        "gyrodrift.scenario": json.dumps(scenario.to_toml_dict()),
        "gyrodrift.site": json.dumps(
            {"lat_deg": scenario.site.lat_deg, "lon_deg": scenario.site.lon_deg, "height_m": scenario.site.height_m}
        ),
        "gyrodrift.rate_hz": json.dumps(scenario.run.rate_hz),
    }
    return pa.schema([pa.field(c, pa.float64()) for c in imu_columns(scenario)], metadata=meta)


def core_chunk_to_table(chunk: dict[str, Any], schema: pa.Schema) -> pa.Table:
    """Convert one `_core.ImuSimulator.next_chunk` dict (SI) to an imu.parquet table (unit-named columns)."""
    dth = np.asarray(chunk["dtheta_rad"], dtype=np.float64)
    dv = np.asarray(chunk["dv_m_s"], dtype=np.float64)
    cols = {
        "t_s": np.asarray(chunk["t_s"], dtype=np.float64),
        "dtheta_x_rad": dth[:, 0],
        "dtheta_y_rad": dth[:, 1],
        "dtheta_z_rad": dth[:, 2],
        "dv_x_m_s": dv[:, 0],
        "dv_y_m_s": dv[:, 1],
        "dv_z_m_s": dv[:, 2],
        "temp_c": np.asarray(chunk["temp_c"], dtype=np.float64),
        "table_angle_deg": np.rad2deg(np.asarray(chunk["table_angle_rad"], dtype=np.float64)),
        "true_pitch_deg": np.rad2deg(np.asarray(chunk["pitch_rad"], dtype=np.float64)),
        "true_roll_deg": np.rad2deg(np.asarray(chunk["roll_rad"], dtype=np.float64)),
        "true_yaw_deg": np.rad2deg(np.asarray(chunk["yaw_rad"], dtype=np.float64)),
    }
    if "true_lat_deg" in schema.names:
        vel = np.asarray(chunk["vel_enu_m_s"], dtype=np.float64)
        cols["true_lat_deg"] = np.rad2deg(np.asarray(chunk["lat_rad"], dtype=np.float64))
        cols["true_lon_deg"] = np.rad2deg(np.asarray(chunk["lon_rad"], dtype=np.float64))
        cols["true_height_m"] = np.asarray(chunk["height_m"], dtype=np.float64)
        cols["true_vel_e_m_s"], cols["true_vel_n_m_s"], cols["true_vel_u_m_s"] = vel[:, 0], vel[:, 1], vel[:, 2]
    return pa.Table.from_pydict(cols, schema=schema)
