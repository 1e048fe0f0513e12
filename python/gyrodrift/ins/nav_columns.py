"""The columns of a navigation output declared once: ``nav.parquet`` (`NavResult.columns`) and the reference-track
file a moving base is checked against.

Each column (`gyrodrift.files.columns.Column`) has its name, unit, dtype and meaning here; the navigator's column
lists, the Parquet schema (`nav_table`) and the table of docs/scenarios.md (`gyrodrift.files.columns.markdown_table`,
checked by tests/ins/test_nav_columns.py) are derived from them. Frames and signs: velocity in ENU, attitude
pitch/roll/yaw (yaw positive counter-clockwise about Up), every error computed minus true.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pyarrow as pa

from gyrodrift.files.columns import Column, family, names

__all__ = [
    "NAV_STATE",
    "NAV_POSITION_ERRORS",
    "NAV_ATTITUDE_ERRORS",
    "NAV_VEHICLE",
    "NAV_OUTPUT",
    "NAV_COLUMNS",
    "POSITION_ERROR_COLUMNS",
    "ATTITUDE_ERROR_COLUMNS",
    "NAV_ERROR_COLUMNS",
    "VEHICLE_COLUMNS",
    "NAV_FORMAT",
    "TRACK_REQUIRED",
    "TRACK_VELOCITY",
    "TRACK_COLUMNS",
    "TRACK_VELOCITY_COLUMNS",
    "nav_table",
]


NAV_STATE = (
    Column("t_s", "s", "time since the start of navigation (`start_s` in the summary: 0 for the scenario's truth)"),
    *family(("lat_deg", "lon_deg", "height_m"), ("deg", "deg", "m"), "position"),
    *family(("vel_e_m_s", "vel_n_m_s", "vel_u_m_s"), "m/s", "velocity, ENU"),
    *family(("pitch_deg", "roll_deg", "yaw_deg"), "deg", "attitude"),
)
"""The navigated state after each kept sample: always in nav.parquet."""

NAV_POSITION_ERRORS = (
    *family(
        ("lat_err_arcsec", "lon_err_arcsec"), "arcsec", "position error, computed minus true (when the site is known)"
    ),
    Column("pos_err_nmi", "nmi", "horizontal position error, 1 nmi = 1852 m"),
)
"""Position errors against the static site or the reference track (`gyrodrift.ins.nav_errors.position_errors`):
present when the truth is known; the summary's checkpoints carry them too."""

NAV_ATTITUDE_ERRORS = family(
    ("pitch_err_arcsec", "roll_err_arcsec", "yaw_err_arcsec"),
    "arcsec",
    "Euler-angle differences, computed minus true, yaw wrapped to +-180 deg (logs with `true_*_deg` columns)",
)
"""Attitude errors (`gyrodrift.ins.nav_errors.attitude_errors_arcsec`): present when the log has the true attitude."""

NAV_VEHICLE = family(
    ("vehicle_pitch_deg", "vehicle_roll_deg", "vehicle_yaw_deg"),
    "deg",
    "moving base, when the table angle is known (an imu.parquet or an in-memory run with `table_angle_deg`, or a "
    "scenario navigated on the fly, whose simulated chunks carry it): the vehicle's attitude, "
    "C_v^n = C_b^n Rz(-table angle) (`gyrodrift.ins.vehicle`)",
)
"""The vehicle's attitude: the navigated IMU attitude with the table turn removed (moving base with a table angle)."""

NAV_OUTPUT = NAV_STATE + NAV_POSITION_ERRORS + NAV_ATTITUDE_ERRORS + NAV_VEHICLE
"""Every column nav.parquet may hold, in the order it holds them."""

NAV_COLUMNS = names(NAV_STATE)
POSITION_ERROR_COLUMNS = names(NAV_POSITION_ERRORS)
ATTITUDE_ERROR_COLUMNS = names(NAV_ATTITUDE_ERRORS)
NAV_ERROR_COLUMNS = POSITION_ERROR_COLUMNS + ATTITUDE_ERROR_COLUMNS
"""The error columns present when the truth is known (position) and the log has the true attitude (attitude)."""
VEHICLE_COLUMNS = names(NAV_VEHICLE)

NAV_FORMAT = "gyrodrift-nav/1"
"""The ``gyrodrift.format`` metadata of nav.parquet."""

TRACK_REQUIRED = (
    Column("t_s", "s", "time stamp on the IMU log's time base (the end time of its samples), strictly increasing"),
    *family(("lat_deg", "lon_deg", "height_m"), ("deg", "deg", "m"), "geodetic position (WGS-84)"),
)
"""Required columns of a reference-track file (`gyrodrift.ins.track.load_track`). The names are nav.parquet's, so a
navigation output can serve as a track once its ``t_s`` is on the log's time base."""

TRACK_VELOCITY = family(("vel_e_m_s", "vel_n_m_s", "vel_u_m_s"), "m/s", "velocity, ENU (all three or none)")
"""Optional velocity columns of a reference-track file."""

TRACK_COLUMNS = names(TRACK_REQUIRED)
TRACK_VELOCITY_COLUMNS = names(TRACK_VELOCITY)

_BY_NAME = {c.name: c for c in NAV_OUTPUT}


def nav_table(columns: Mapping[str, np.ndarray]) -> pa.Table:
    """`columns` as a pyarrow Table with the declared dtypes (no metadata); a name not declared in `NAV_OUTPUT`, or
    declared columns out of order, is a ValueError (nothing writes a column this module does not describe)."""
    order = [c.name for c in NAV_OUTPUT if c.name in columns]
    if list(columns) != order:
        unknown = [n for n in columns if n not in _BY_NAME]
        what = f"undeclared column(s) {unknown}" if unknown else f"columns out of the declared order: {list(columns)}"
        raise ValueError(f"nav table: {what} (gyrodrift.ins.nav_columns)")
    return pa.Table.from_pydict({n: pa.array(v, _BY_NAME[n].arrow_type) for n, v in columns.items()})
