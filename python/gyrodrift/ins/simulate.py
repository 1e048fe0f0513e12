"""Simulate a rotating IMU from a scenario: in memory, streamed to ``imu.parquet``, or read on the fly as a log.

``imu.parquet``'s columns, schema and metadata are declared in `gyrodrift.logs.columns` (`imu_file_schema`), beside
the columns every log reader takes; reading it back (with every other IMU log) is `gyrodrift.logs`. A scenario
read as a log without storing it is `scenario_log`.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from gyrodrift.files.atomic import OutputFolder, output_folder
from gyrodrift.files.toml_writer import dumps_toml
from gyrodrift.ins.scenario import Scenario
from gyrodrift.logs import ImuLog, LogTruth
from gyrodrift.logs.columns import ROUTE_COLUMNS, imu_file_schema
from gyrodrift.logs.source import Layout, LogSource, Provenance, RawBlock, SampleRate, check_rate
from gyrodrift.progress import progress
from gyrodrift.site import Site

__all__ = [
    "ImuData",
    "simulate",
    "scenario_log",
    "iter_core_chunks",
    "rotation_summary",
    "imu_schema",
    "DEFAULT_CHUNK_SAMPLES",
    "SIMULATION_FILES",
]

SIMULATION_FILES = ("imu.parquet", "scenario.resolved.toml")
"""The files of a simulation output, published together."""

DEFAULT_CHUNK_SAMPLES = 100_000
"""Samples per chunk (and per Parquet row group): 1000 s at 100 Hz, about 10 MB of columns."""


PARQUET_OPTIONS = {"use_dictionary": False, "compression": "zstd", "use_byte_stream_split": True}
"""How imu.parquet is encoded: noisy float64 columns gain nothing from dictionaries (which cost 5x in
speed); byte-stream-split + zstd halves the size (about 40 bytes per sample) at 2-3 M samples/s."""


@dataclass(frozen=True)
class ImuData:
    """A simulated run held in memory: the imu.parquet columns as numpy arrays, and its scenario.

    ``columns`` maps every column of the scenario's imu.parquet (`imu_schema`) to a float64 array (units in the
    names). `navigate` accepts an ImuData just like an imu.parquet path.
    """

    columns: dict[str, np.ndarray]
    scenario: Scenario
    schema: pa.Schema = field(repr=False, compare=False, default=None)

    def __len__(self) -> int:
        return len(self.columns["t_s"])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def table(self) -> pa.Table:
        """The run as a pyarrow Table with the imu.parquet schema and metadata."""
        return pa.Table.from_pydict(self.columns, schema=self.schema or imu_schema(self.scenario))

    def log(self, *, site: Site | Mapping[str, float] | None = None, require_temperature: bool = True) -> ImuLog:
        """The run as an IMU log (`gyrodrift.logs.ImuLog.from_arrays`, nothing copied): rate, site, true initial
        attitude and static part from the scenario; `site` replaces or completes the scenario's as in
        `gyrodrift.logs.open_log`."""
        s = self.scenario
        known = _provenance(s)
        return ImuLog.from_arrays(
            self.columns,
            rate_hz=s.run.rate_hz,
            site=site,
            source_site=known.site,
            truth=known.truth,
            require_temperature=require_temperature,
            static_s=known.static_s,
        )


def _provenance(scenario: Scenario) -> Provenance:
    """What `scenario` says about its run: the true site, the true initial attitude [deg] and, on a moving base, the
    static part at the start [s] (``[trajectory] static_h``)."""
    a, trajectory = scenario.attitude, scenario.trajectory
    static_s = None if trajectory is None else trajectory.static_h * 3600.0
    return Provenance(scenario.site, LogTruth(a.pitch_deg, a.roll_deg, a.yaw_deg), static_s)


def imu_schema(scenario: Scenario) -> pa.Schema:
    """The Arrow schema of the imu.parquet of `scenario`: its columns (`gyrodrift.logs.columns.IMU_COLUMNS`, and
    `ROUTE_COLUMNS` on a moving base) and the scenario, site and rate in its key-value metadata."""
    return imu_file_schema(
        scenario=scenario.to_toml_dict(),
        site=scenario.site,
        rate_hz=scenario.run.rate_hz,
        moving=scenario.trajectory is not None,
    )


def _table(chunk: dict[str, Any], schema: pa.Schema) -> pa.Table:
    """One `_core.ImuSimulator.next_chunk` dict (SI) as an imu.parquet table (unit-named columns)."""
    dth = np.asarray(chunk["dtheta_rad"], dtype=np.float64)
    dv = np.asarray(chunk["dv_m_s"], dtype=np.float64)
    values = [
        np.asarray(chunk["t_s"], dtype=np.float64),
        *dth.T,
        *dv.T,
        np.asarray(chunk["temp_c"], dtype=np.float64),
        *(np.rad2deg(np.asarray(chunk[k], dtype=np.float64)) for k in _ANGLES_RAD),
    ]
    if ROUTE_COLUMNS[0] in schema.names:
        vel = np.asarray(chunk["vel_enu_m_s"], dtype=np.float64)
        values += [
            np.rad2deg(np.asarray(chunk["lat_rad"], dtype=np.float64)),
            np.rad2deg(np.asarray(chunk["lon_rad"], dtype=np.float64)),
            np.asarray(chunk["height_m"], dtype=np.float64),
            *vel.T,
        ]
    return pa.Table.from_pydict(dict(zip(schema.names, values, strict=True)), schema=schema)


_ANGLES_RAD = ("table_angle_rad", "pitch_rad", "roll_rad", "yaw_rad")
"""The core chunk's angles [rad] behind imu.parquet's ``table_angle_deg`` and true attitude [deg], in file order."""


def rotation_summary(scenario: Scenario) -> dict:
    """What the turntable scheme of `scenario` does to horizontal sensor errors.

    Returns ``{"modulation_residual": r, "span_deg": s}``: r is the fraction of a body-fixed horizontal
    gyro or accelerometer bias left un-modulated (the magnitude of the time average of (cos, sin) of the table angle
    over one period: 1 without rotation, 0 for continuous rotation; the navigation error it causes scales with r);
    s is the reciprocating span actually turned [deg] (the balanced span resolved), None for other schemes.
    """
    from gyrodrift import _core

    sim = _core.ImuSimulator(scenario.to_core_config())
    span = sim.reciprocating_span_rad
    return {
        "modulation_residual": sim.modulation_residual,
        "span_deg": None if span is None else float(np.degrees(span)),
    }


def iter_core_chunks(scenario: Scenario, chunk_samples: int) -> Iterator[dict]:
    """Yield the raw SI chunks of `gyrodrift._core.ImuSimulator` for `scenario` (see the binding contract)."""
    from gyrodrift import _core

    if chunk_samples < 1:
        raise ValueError(f"chunk_samples must be >= 1, got {chunk_samples}")
    sim = _core.ImuSimulator(scenario.to_core_config())
    while True:
        chunk = sim.next_chunk(chunk_samples)
        if chunk is None:
            return
        yield chunk


def simulate(
    scenario: Scenario,
    *,
    out_dir: str | os.PathLike[str] | OutputFolder | None = None,
    chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
    quiet: bool = True,
) -> ImuData | Path:
    """Simulate the IMU output of a static-base single-axis rotation INS.

    Parameters
    ----------
    scenario : Scenario
        The run (site, duration, rotation scheme, sensor errors, temperature); see `load_scenario`.
    out_dir : path-like, optional
        None: return the whole run in memory (an `ImuData`; mind the size: 12 float64 columns, about
        100 bytes per sample, i.e. 35 MB per hour at 100 Hz, 2.5 GB for 72 h). Otherwise the folder (created if needed)
        receives ``imu.parquet`` (written chunk by chunk, one row group per chunk, never the whole run in
        memory) and ``scenario.resolved.toml`` (every default written out), published together when the run
        is complete (`gyrodrift.files.atomic.OutputFolder`; the folder is checked before simulating, docs/outputs.md).
    chunk_samples : int
        Samples asked from the core at a time (and rows per Parquet row group).
    quiet : bool
        True hides the progress bar (it is also hidden when stderr is not a terminal).

    Returns
    -------
    ImuData or pathlib.Path
        The in-memory run, or the path of the written ``imu.parquet``.

    Notes
    -----
    Increments are body-frame (x right, y forward, z up) angle [rad] and velocity [m/s] increments over each
    sample, as the core's measurement model produces them: ``w_meas = (I + diag(scale) + M) w_true + b +
    b_gm(t) + b_rrw(t) + b_temp(t) e_z + noise``.
    """
    schema = imu_schema(scenario)
    out = None if out_dir is None else output_folder(out_dir, "simulate", SIMULATION_FILES)
    bar = progress(scenario.n_samples, "simulate", quiet)
    with bar:
        if out_dir is None:
            parts: dict[str, list[np.ndarray]] = {c: [] for c in schema.names}
            for chunk in iter_core_chunks(scenario, chunk_samples):
                table = _table(chunk, schema)
                for c in schema.names:
                    parts[c].append(table.column(c).to_numpy())
                bar.update(table.num_rows)
            cols = {c: (np.concatenate(v) if v else np.zeros(0)) for c, v in parts.items()}
            return ImuData(columns=cols, scenario=scenario, schema=schema)

        assert out is not None  # out_dir was given
        with out.publish() as stage:
            with pq.ParquetWriter(stage.file("imu.parquet"), schema, **PARQUET_OPTIONS) as writer:
                for chunk in iter_core_chunks(scenario, chunk_samples):
                    table = _table(chunk, schema)
                    writer.write_table(table, row_group_size=max(table.num_rows, 1))
                    bar.update(table.num_rows)
            resolved = dumps_toml(
                scenario.to_toml_dict(),
                header="Resolved scenario written by gyrodrift simulate: every default written out.\n"
                "Units are in the key names; see docs/scenarios.md.",
            )
            with open(stage.file("scenario.resolved.toml"), "w", encoding="utf-8", newline="") as fh:
                fh.write(resolved)
        return out.path / "imu.parquet"


@dataclass(frozen=True, kw_only=True)
class _ScenarioSource(LogSource):
    """The samples of a scenario simulated on the fly by the core, chunk by chunk (nothing stored)."""

    format: str = "scenario"

    def blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        for c in iter_core_chunks(self.scenario, chunk_samples):
            yield RawBlock(
                np.asarray(c["t_s"], dtype=float),
                (np.asarray(c["dtheta_rad"], dtype=float), np.asarray(c["dv_m_s"], dtype=float)),
                np.asarray(c["temp_c"], dtype=float),
                tuple(np.rad2deg(np.asarray(c[k], dtype=float)) for k in _ANGLES_RAD[1:]),
                table_angle_deg=np.rad2deg(np.asarray(c["table_angle_rad"], dtype=float)),
            )


def scenario_log(scenario: Scenario, *, site: Site | Mapping[str, float] | None = None) -> ImuLog:
    """A log simulated on the fly from `scenario`, chunk by chunk (nothing stored): every read re-simulates it.

    Site, true initial attitude, true attitude columns and table angle come from the scenario (`site` replaces or
    completes its site as in `gyrodrift.logs.open_log`); the log's ``scenario`` is `scenario` (its route).
    """
    label = "<scenario>"
    source = _ScenarioSource(
        label=label,
        layout=Layout.of_kind("increments", has_temperature=True, has_truth_columns=True),
        rate=SampleRate(check_rate(scenario.run.rate_hz, label), "scenario"),
        n_samples=scenario.n_samples,
        provenance=_provenance(scenario),
        name="scenario",
        scenario=scenario,
    )
    return ImuLog(source, site=site)
