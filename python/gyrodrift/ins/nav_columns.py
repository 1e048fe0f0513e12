"""The columns of a navigation output declared once: ``nav.parquet`` (`NavResult.columns`) and the reference-track
file a moving base is checked against.

Each column has its name, unit, dtype and meaning here; the navigator's column lists, the Parquet schema
(`nav_table`) and the table of docs/scenarios.md (`markdown_table`, checked by tests/ins/test_nav_columns.py) are
derived from them. Frames and signs: velocity in ENU, attitude pitch/roll/yaw (yaw positive counter-clockwise about
Up), every error computed minus true.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

__all__ = [
    "Column",
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
    "names",
    "nav_table",
    "markdown_table",
]


@dataclass(frozen=True)
class Column:
    """One column of a navigation table: its name, unit (as the docs print it), numpy dtype and meaning."""

    name: str
    unit: str
    meaning: str
    dtype: str = "float64"


def _family(names: Sequence[str], units: str | Sequence[str], meaning: str) -> tuple[Column, ...]:
    """Columns that share one meaning (one row of the docs table); `units` one for all or one per column."""
    per_column = [units] * len(names) if isinstance(units, str) else list(units)
    return tuple(Column(n, u, meaning) for n, u in zip(names, per_column, strict=True))


def names(columns: Sequence[Column]) -> tuple[str, ...]:
    """The names of `columns`, in order."""
    return tuple(c.name for c in columns)


NAV_STATE = (
    Column("t_s", "s", "time since the start of navigation (`start_s` in the summary: 0 for the scenario's truth)"),
    *_family(("lat_deg", "lon_deg", "height_m"), ("deg", "deg", "m"), "position"),
    *_family(("vel_e_m_s", "vel_n_m_s", "vel_u_m_s"), "m/s", "velocity, ENU"),
    *_family(("pitch_deg", "roll_deg", "yaw_deg"), "deg", "attitude"),
)
"""The navigated state after each kept sample: always in nav.parquet."""

NAV_POSITION_ERRORS = (
    *_family(
        ("lat_err_arcsec", "lon_err_arcsec"), "arcsec", "position error, computed minus true (when the site is known)"
    ),
    Column("pos_err_nmi", "nmi", "horizontal position error, 1 nmi = 1852 m"),
)
"""Position errors against the static site or the reference track (`gyrodrift.ins.nav_errors.position_errors`):
present when the truth is known; the summary's checkpoints carry them too."""

NAV_ATTITUDE_ERRORS = _family(
    ("pitch_err_arcsec", "roll_err_arcsec", "yaw_err_arcsec"),
    "arcsec",
    "Euler-angle differences, computed minus true, yaw wrapped to +-180 deg (logs with `true_*_deg` columns)",
)
"""Attitude errors (`gyrodrift.ins.nav_errors.attitude_errors_arcsec`): present when the log has the true attitude."""

NAV_VEHICLE = _family(
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
    *_family(("lat_deg", "lon_deg", "height_m"), ("deg", "deg", "m"), "geodetic position (WGS-84)"),
)
"""Required columns of a reference-track file (`gyrodrift.ins.track.load_track`). The names are nav.parquet's, so a
navigation output can serve as a track once its ``t_s`` is on the log's time base."""

TRACK_VELOCITY = _family(("vel_e_m_s", "vel_n_m_s", "vel_u_m_s"), "m/s", "velocity, ENU (all three or none)")
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
    return pa.Table.from_pydict(
        {n: pa.array(v, pa.from_numpy_dtype(np.dtype(_BY_NAME[n].dtype))) for n, v in columns.items()}
    )


def markdown_table(columns: Sequence[Column]) -> str:
    """The docs table of `columns`: one row per run of consecutive columns sharing a meaning, their units joined
    (one unit when they all share it)."""
    rows = ["| column | unit | meaning |", "|---|---|---|"]
    groups: list[list[Column]] = []
    for c in columns:
        if groups and groups[-1][0].meaning == c.meaning:
            groups[-1].append(c)
        else:
            groups.append([c])
    for group in groups:
        units = [c.unit for c in group]
        unit = units[0] if len(set(units)) == 1 else ", ".join(units)
        rows.append(f"| {', '.join(f'`{c.name}`' for c in group)} | {unit} | {group[0].meaning} |")
    return "\n".join(rows)
