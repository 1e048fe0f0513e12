"""The IMU log columns and the ``imu.parquet`` format, declared once: name, unit, dtype and meaning of each column.

Every column tuple of the readers (`INCREMENT_COLUMNS`, `RATE_COLUMNS`, ...), the header checks, the Parquet schema
the simulator writes (`imu_file_schema`) come from the `Column`s below (`gyrodrift.files.columns`);
tests/logs/test_log_columns.py checks the column tables of docs/procedure.md and docs/scenarios.md against them.

Body frame x right, y forward, z up (z = the turntable's axis); every name carries its unit.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import pyarrow as pa

from gyrodrift.files.columns import Column, family, names
from gyrodrift.site import Site

__all__ = [
    "TIME",
    "INCREMENTS",
    "RATES",
    "TEMPERATURE",
    "TRUTH",
    "REF_HEIGHT",
    "TABLE_ANGLE",
    "ROUTE",
    "LOG_COLUMNS",
    "INCREMENT_COLUMNS",
    "RATE_COLUMNS",
    "TRUTH_COLUMNS",
    "REF_HEIGHT_COLUMN",
    "IMU_FORMAT",
    "IMU_COLUMNS",
    "ROUTE_COLUMNS",
    "FORMAT_KEY",
    "SCENARIO_KEY",
    "SITE_KEY",
    "RATE_KEY",
    "imu_file_schema",
]


def _axes(template: str, unit: str, meaning: str, axes: str = "xyz") -> tuple[Column, ...]:
    """The columns of one three-axis quantity: `template` with ``{}`` replaced by each of `axes`."""
    return family([template.format(axis) for axis in axes], unit, meaning)


TIME = Column("t_s", "s", "end time of the sample, strictly increasing")
INCREMENTS = _axes("dtheta_{}_rad", "rad", "angle increments over the sample") + _axes(
    "dv_{}_m_s", "m/s", "velocity (specific-force) increments over the sample"
)
"""Increments: angle [rad] then velocity [m/s] increments over the sample, body x y z (a log of kind
``increments``)."""
RATES = _axes("gyro_{}_rad_s", "rad/s", "angular rate, mean over the sample") + _axes(
    "accel_{}_m_s2", "m/s^2", "specific force, mean over the sample"
)
"""Rates: angular rate [rad/s] then specific force [m/s^2], body x y z (a log of kind ``rates``)."""
TEMPERATURE = Column("temp_c", "deg C", "system temperature")
TRUTH = tuple(
    Column(f"true_{angle}_deg", "deg", "true body attitude at the end of the sample")
    for angle in ("pitch", "roll", "yaw")
)
"""The true attitude at the end of each sample [deg] (simulated logs; optional in a log)."""
REF_HEIGHT = Column(
    "ref_height_m", "m", "known height above the ellipsoid at the end of the sample (barometric, map, GNSS)"
)
"""An optional reference height [m]: the vertical reference of `navigate`'s damped vertical channel."""
TABLE_ANGLE = Column("table_angle_deg", "deg", "turntable angle about body Up (counter-clockwise positive)")
ROUTE = (
    Column("true_lat_deg", "deg", "moving base only: the vehicle's true position at the end of the sample"),
    Column("true_lon_deg", "deg", "moving base only: the vehicle's true position at the end of the sample"),
    Column("true_height_m", "m", "moving base only: the vehicle's true position at the end of the sample"),
    *_axes("true_vel_{}_m_s", "m/s", "moving base only: its true velocity, ENU", axes="enu"),
)
"""The true position and velocity (ENU) of a moving base at the end of each sample (imu.parquet only)."""

LOG_COLUMNS = (TIME, *INCREMENTS, *RATES, TEMPERATURE, *TRUTH, REF_HEIGHT)
"""Every column an IMU log reader uses (order free in a log, extra columns ignored)."""
INCREMENT_COLUMNS = names(INCREMENTS)
RATE_COLUMNS = names(RATES)
TRUTH_COLUMNS = names(TRUTH)
REF_HEIGHT_COLUMN = REF_HEIGHT.name

IMU_FORMAT = "gyrodrift-imu/1"
"""Value of the ``gyrodrift.format`` metadata key of imu.parquet files written by this version."""
_IMU_FILE = (TIME, *INCREMENTS, TEMPERATURE, TABLE_ANGLE, *TRUTH)
IMU_COLUMNS = names(_IMU_FILE)
"""All columns of a static-base imu.parquet, in file order (all float64)."""
ROUTE_COLUMNS = names(ROUTE)
"""The true position and velocity columns a moving-base imu.parquet adds after `IMU_COLUMNS`."""

FORMAT_KEY = "gyrodrift.format"
"""imu.parquet metadata: the format, `IMU_FORMAT` (a plain string)."""
SCENARIO_KEY = "gyrodrift.scenario"
"""imu.parquet metadata: the resolved scenario in user units (TOML-shaped, JSON)."""
SITE_KEY = "gyrodrift.site"
"""imu.parquet metadata: the true static position ``{lat_deg, lon_deg, height_m}`` (JSON)."""
RATE_KEY = "gyrodrift.rate_hz"
"""imu.parquet metadata: the sample rate [Hz] (a JSON number)."""


def imu_file_schema(*, scenario: Mapping[str, Any], site: Site, rate_hz: float, moving: bool) -> pa.Schema:
    """The Arrow schema of an imu.parquet: its columns (`ROUTE_COLUMNS` added on a `moving` base) and metadata.

    `scenario` is the resolved scenario in user units (``Scenario.to_toml_dict()``), `site` its true static site,
    `rate_hz` the sample rate [Hz].
    """
    meta = {
        FORMAT_KEY: IMU_FORMAT,
        SCENARIO_KEY: json.dumps(scenario),
        SITE_KEY: json.dumps({"lat_deg": site.lat_deg, "lon_deg": site.lon_deg, "height_m": site.height_m}),
        RATE_KEY: json.dumps(rate_hz),
    }
    columns = _IMU_FILE + (ROUTE if moving else ())
    return pa.schema([pa.field(c.name, c.arrow_type) for c in columns], metadata=meta)
