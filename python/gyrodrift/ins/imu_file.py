"""The IMU time-series format (``imu.parquet``): column names, metadata, and reading it back in chunks.

One row per IMU sample; every column name carries its unit (see docs/scenarios.md):

``t_s`` end time of the sample [s]; ``dtheta_{x,y,z}_rad`` angle increments over the sample [rad] and
``dv_{x,y,z}_m_s`` velocity increments [m/s], body frame (x right, y forward, z up); ``temp_c`` system
temperature [deg C]; ``table_angle_deg`` turntable angle about body Up [deg]; ``true_{pitch,roll,yaw}_deg``
true body attitude at the end of the sample [deg].

File key-value metadata (UTF-8 JSON values): ``gyrodrift.format`` = ``"gyrodrift-imu/1"``,
``gyrodrift.scenario`` the resolved scenario in user units (TOML-shaped dict), ``gyrodrift.site`` the true
static position ``{lat_deg, lon_deg, height_m}``, ``gyrodrift.rate_hz`` the sample rate [Hz].
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from gyrodrift.errors import InputError
from gyrodrift.ins.scenario import Scenario

__all__ = [
    "IMU_FORMAT",
    "IMU_COLUMNS",
    "TRUTH_COLUMNS",
    "ImuFileError",
    "ImuChunk",
    "ImuTruth",
    "imu_schema",
    "ImuFileReader",
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
TRUTH_COLUMNS = ("true_pitch_deg", "true_roll_deg", "true_yaw_deg")
IMU_COLUMNS = SENSOR_COLUMNS + ("temp_c", "table_angle_deg") + TRUTH_COLUMNS
"""All columns of imu.parquet, in file order (all float64)."""


class ImuFileError(InputError):
    """An IMU file is missing, unreadable or not in the imu.parquet format; the message names the file."""


@dataclass(frozen=True)
class ImuTruth:
    """What is known of the truth of a static run: site [deg, deg, m], initial attitude [deg], rate [Hz]."""

    lat_deg: float
    lon_deg: float
    height_m: float
    pitch_deg: float
    roll_deg: float
    yaw_deg: float


@dataclass(frozen=True)
class ImuChunk:
    """A run of consecutive samples: ``dtheta_rad`` (n, 3), ``dv_m_s`` (n, 3), ``t_s`` (n,), and the true
    attitude ``true_deg`` (n, 3) as pitch, roll, yaw (None when unknown)."""

    t_s: np.ndarray
    dtheta_rad: np.ndarray
    dv_m_s: np.ndarray
    true_deg: np.ndarray | None

    def __len__(self) -> int:
        return len(self.t_s)

    def slice(self, a: int, b: int) -> ImuChunk:
        return ImuChunk(
            self.t_s[a:b],
            self.dtheta_rad[a:b],
            self.dv_m_s[a:b],
            None if self.true_deg is None else self.true_deg[a:b],
        )


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
    return pa.schema([pa.field(c, pa.float64()) for c in IMU_COLUMNS], metadata=meta)


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
    return pa.Table.from_pydict(cols, schema=schema)


def table_to_chunk(table: pa.Table | pa.RecordBatch) -> ImuChunk:
    """Pull the navigation inputs out of an imu.parquet table or record batch."""
    names = table.schema.names

    def col(name: str) -> np.ndarray:
        return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64)

    dth = np.column_stack([col("dtheta_x_rad"), col("dtheta_y_rad"), col("dtheta_z_rad")])
    dv = np.column_stack([col("dv_x_m_s"), col("dv_y_m_s"), col("dv_z_m_s")])
    truth = None
    if all(c in names for c in TRUTH_COLUMNS):
        truth = np.column_stack([col(c) for c in TRUTH_COLUMNS])
    return ImuChunk(col("t_s"), dth, dv, truth)


class ImuFileReader:
    """Open an imu.parquet file, check its format, and stream it in chunks.

    Attributes
    ----------
    path : pathlib.Path
    n_samples : int
    rate_hz : float
        From the metadata, else from the first two time stamps.
    truth : ImuTruth or None
        The true static site and initial attitude, when the metadata carries the scenario.
    scenario : dict or None
        The resolved scenario (TOML-shaped, user units) from the metadata.
    """

    def __init__(self, path: str | os.PathLike[str]):
        self.path = Path(path)
        name = str(path)
        if not self.path.exists():
            raise ImuFileError(f"{name}: no such file")
        try:
            self._pf = pq.ParquetFile(self.path)
        except (pa.ArrowInvalid, OSError) as exc:
            raise ImuFileError(f"{name}: not a Parquet file ({exc})") from None
        schema = self._pf.schema_arrow
        missing = [c for c in SENSOR_COLUMNS if c not in schema.names]
        if missing:
            raise ImuFileError(f"{name}: missing column(s) {', '.join(missing)} (not an imu.parquet file)")
        meta = {k.decode(): v.decode() for k, v in (schema.metadata or {}).items()}
        self.n_samples = self._pf.metadata.num_rows
        if self.n_samples < 1:
            raise ImuFileError(f"{name}: no samples")
        self.scenario: dict[str, Any] | None = None
        self.truth: ImuTruth | None = None
        try:
            if "gyrodrift.scenario" in meta:
                self.scenario = json.loads(meta["gyrodrift.scenario"])
                site = self.scenario.get("site", {})
                att = self.scenario.get("attitude", {})
                self.truth = ImuTruth(
                    lat_deg=float(site["lat_deg"]),
                    lon_deg=float(site["lon_deg"]),
                    height_m=float(site["height_m"]),
                    pitch_deg=float(att.get("pitch_deg", 0.0)),
                    roll_deg=float(att.get("roll_deg", 0.0)),
                    yaw_deg=float(att.get("yaw_deg", 0.0)),
                )
            rate = json.loads(meta["gyrodrift.rate_hz"]) if "gyrodrift.rate_hz" in meta else None
        except (ValueError, KeyError, TypeError) as exc:
            raise ImuFileError(f"{name}: unreadable gyrodrift metadata ({exc})") from None
        if rate is None:
            t = self._pf.read_row_group(0, columns=["t_s"]).column(0).to_numpy()
            if len(t) < 2 or not t[1] > t[0]:
                raise ImuFileError(f"{name}: cannot tell the sample rate (no gyrodrift.rate_hz metadata)")
            rate = 1.0 / (t[1] - t[0])
        self.rate_hz = float(rate)
        self._has_truth_columns = all(c in schema.names for c in TRUTH_COLUMNS)

    def chunks(self, chunk_samples: int) -> Iterator[ImuChunk]:
        """Yield consecutive chunks of at most `chunk_samples` samples, never the whole file at once.

        Every chunk is checked before it is handed on: finite time and increments, strictly increasing time
        (also across chunks); a bad sample raises `ImuFileError` naming the file, the sample (1-based row) and
        the column.
        """
        cols = list(SENSOR_COLUMNS) + (list(TRUTH_COLUMNS) if self._has_truth_columns else [])
        first, prev_t = 0, None
        for batch in self._pf.iter_batches(batch_size=chunk_samples, columns=cols):
            chunk = table_to_chunk(batch)
            self._check(chunk, first, prev_t)
            first += len(chunk.t_s)
            prev_t = float(chunk.t_s[-1]) if len(chunk.t_s) else prev_t
            yield chunk

    def _check(self, chunk: ImuChunk, first: int, prev_t: float | None) -> None:
        where = lambda i, column: f"{self.path}, row {first + i + 1}, column {column}"  # noqa: E731
        for name, values in (("t_s", chunk.t_s[:, None]), ("dtheta", chunk.dtheta_rad), ("dv", chunk.dv_m_s)):
            bad = ~np.isfinite(values)
            if bad.any():
                i, j = (int(k[0]) for k in np.nonzero(bad))
                column = name if name == "t_s" else SENSOR_COLUMNS[1 + j + (3 if name == "dv" else 0)]
                raise ImuFileError(f"{where(i, column)}: expected a finite number, got {float(values[i, j])!r}")
        t = chunk.t_s if prev_t is None else np.concatenate([[prev_t], chunk.t_s])
        back = np.flatnonzero(np.diff(t) <= 0.0)
        if back.size:
            i = int(back[0]) + (0 if prev_t is not None else 1)
            raise ImuFileError(
                f"{where(i, 't_s')}: time must be strictly increasing "
                f"({float(t[back[0] + 1])!r} s after {float(t[back[0]])!r} s)"
            )
