"""Free navigation of a recorded or simulated static-base IMU run, with errors against the truth."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from gyrodrift.atomic import atomic_write_json, atomic_write_parquet
from gyrodrift.ins.imu_file import ImuChunk, ImuFileReader, ImuTruth
from gyrodrift.ins.nav_errors import attitude_errors_arcsec, position_errors
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import DEFAULT_CHUNK_SAMPLES, ImuData, iter_core_chunks
from gyrodrift.progress import progress
from gyrodrift.units import DEG, DEG_PER_H, HOUR, MICRO_G

__all__ = ["NavResult", "navigate", "NAV_COLUMNS", "NAV_ERROR_COLUMNS", "SUMMARY_FORMAT"]

NAV_COLUMNS = (
    "t_s",
    "lat_deg",
    "lon_deg",
    "height_m",
    "vel_e_m_s",
    "vel_n_m_s",
    "vel_u_m_s",
    "pitch_deg",
    "roll_deg",
    "yaw_deg",
)
"""Columns of nav.parquet always present (navigated state after each kept sample)."""

NAV_ERROR_COLUMNS = (
    "lat_err_arcsec",
    "lon_err_arcsec",
    "pos_err_nmi",
    "pitch_err_arcsec",
    "roll_err_arcsec",
    "yaw_err_arcsec",
)
"""Columns of nav.parquet present when the truth is known (computed minus true)."""

SUMMARY_FORMAT = "gyrodrift-nav-summary/1"


@dataclass(frozen=True)
class NavResult:
    """The outcome of `navigate`.

    Attributes
    ----------
    columns : dict of str to numpy.ndarray
        nav.parquet columns (`NAV_COLUMNS`, plus `NAV_ERROR_COLUMNS` when the truth is known), one row per
        kept sample (every ``decimation_s``).
    summary : dict
        The content of summary.json (hourly checkpoints, final and maximum position error).
    out_dir : pathlib.Path or None
        Where nav.parquet and summary.json were written, if anywhere.
    """

    columns: dict[str, np.ndarray]
    summary: dict[str, Any]
    out_dir: Path | None = None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def table(self) -> pa.Table:
        """The columns as a pyarrow Table (float64)."""
        return pa.Table.from_pydict({k: pa.array(v, pa.float64()) for k, v in self.columns.items()})

    def checkpoint(self, t_h: int) -> dict[str, Any]:
        """The summary checkpoint at whole hour `t_h` (KeyError if the run did not reach it)."""
        for c in self.summary["checkpoints"]:
            if c["t_h"] == t_h:
                return c
        raise KeyError(f"no checkpoint at {t_h} h")


@dataclass(frozen=True)
class _Source:
    chunks: Iterator[ImuChunk]
    n_samples: int
    rate_hz: float
    truth: ImuTruth | None
    label: str


def _core_source(scenario: Scenario, chunk_samples: int) -> Iterator[ImuChunk]:
    for c in iter_core_chunks(scenario, chunk_samples):
        true_deg = np.rad2deg(np.column_stack([c["pitch_rad"], c["roll_rad"], c["yaw_rad"]]))
        yield ImuChunk(np.asarray(c["t_s"]), np.asarray(c["dtheta_rad"]), np.asarray(c["dv_m_s"]), true_deg)


def _open_source(imu: Any, chunk_samples: int) -> _Source:
    if isinstance(imu, Scenario):
        s = imu
        truth = ImuTruth(
            s.site.lat_deg,
            s.site.lon_deg,
            s.site.height_m,
            s.attitude.pitch_deg,
            s.attitude.roll_deg,
            s.attitude.yaw_deg,
        )
        return _Source(_core_source(s, chunk_samples), s.n_samples, s.run.rate_hz, truth, "<scenario>")
    if isinstance(imu, ImuData):
        s = imu.scenario
        truth = ImuTruth(
            s.site.lat_deg,
            s.site.lon_deg,
            s.site.height_m,
            s.attitude.pitch_deg,
            s.attitude.roll_deg,
            s.attitude.yaw_deg,
        )
        return _Source(imu.chunks(chunk_samples), len(imu), s.run.rate_hz, truth, "<memory>")
    if isinstance(imu, (str, os.PathLike)):
        reader = ImuFileReader(imu)
        return _Source(reader.chunks(chunk_samples), reader.n_samples, reader.rate_hz, reader.truth, str(imu))
    raise TypeError(f"navigate: imu must be a path to imu.parquet, an ImuData or a Scenario, got {type(imu).__name__}")


def _vector3(name: str, value: Sequence[float] | None) -> list[float]:
    if value is None:
        return [0.0, 0.0, 0.0]
    v = [float(x) for x in value]
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise ValueError(f"navigate: {name} must be 3 finite numbers, got {value!r}")
    return v


def _initial_state(initial: str | Mapping[str, Any], truth: ImuTruth | None, label: str) -> dict[str, Any]:
    keys = ("lat_deg", "lon_deg", "height_m", "pitch_deg", "roll_deg", "yaw_deg")
    if isinstance(initial, str):
        if initial != "truth":
            raise ValueError(f"navigate: initial must be 'truth' or a mapping, got {initial!r}")
        given: Mapping[str, Any] = {}
    else:
        given = initial
        unknown = set(given) - set(keys) - {"vel_enu_m_s"}
        if unknown:
            raise ValueError(f"navigate: unknown initial key(s) {sorted(unknown)} (expected {keys + ('vel_enu_m_s',)})")
    out: dict[str, Any] = {}
    for k in keys:
        if k in given:
            out[k] = float(given[k])
        elif truth is not None:
            out[k] = float(getattr(truth, k))
        else:
            raise ValueError(f"navigate: {label} carries no truth; initial must give {k}")
    out["vel_enu_m_s"] = _vector3("initial vel_enu_m_s", given.get("vel_enu_m_s"))
    return out


def navigate(
    imu: str | os.PathLike[str] | ImuData | Scenario,
    *,
    hours: float | None = None,
    compensate_drift_deg_h: float = 0.0,
    gyro_bias_deg_h: Sequence[float] | None = None,
    accel_bias_ug: Sequence[float] | None = None,
    initial: str | Mapping[str, Any] = "truth",
    decimation_s: float = 1.0,
    vertical: str = "fixed",
    out_dir: str | os.PathLike[str] | None = None,
    chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
    quiet: bool = True,
) -> NavResult:
    """Navigate a static-base IMU run with the Rust strapdown navigator and compare with the truth.

    Parameters
    ----------
    imu : path, ImuData or Scenario
        An ``imu.parquet`` file (streamed in chunks), an in-memory `ImuData`, or a `Scenario` simulated on
        the fly chunk by chunk (nothing stored: the fast path for long runs).
    hours : float, optional
        Navigate only the first `hours` [h] (default: the whole run).
    compensate_drift_deg_h : float
        Axial (z) gyro drift estimate [deg/h], subtracted from the measured z rate
        (compensated = measured - estimate). Added to ``gyro_bias_deg_h[2]``.
    gyro_bias_deg_h, accel_bias_ug : 3 numbers, optional
        Gyro [deg/h] and accelerometer [ug] bias estimates, body x y z, subtracted from the measurements.
    initial : "truth" or mapping
        Initial state. "truth": the true site and the attitude at table angle 0 from the scenario. A
        mapping may give ``lat_deg, lon_deg, height_m, pitch_deg, roll_deg, yaw_deg`` [deg, m] and
        ``vel_enu_m_s`` (3, m/s); missing keys come from the truth.
    decimation_s : float
        Keep the state every `decimation_s` [s] (rounded to whole samples, counted from the run start).
    vertical : {"fixed", "damped"}
        Vertical channel of the core navigator ("fixed": height held, static base).
    out_dir : path-like, optional
        If given, write ``nav.parquet`` and ``summary.json`` there (atomically).
    chunk_samples : int
        Samples per call to the core.
    quiet : bool
        True hides the progress bar.

    Returns
    -------
    NavResult
        Columns ``t_s`` [s], ``lat_deg``, ``lon_deg``, ``height_m``, ``vel_{e,n,u}_m_s`` (ENU),
        ``pitch_deg``, ``roll_deg``, ``yaw_deg``; with a known truth also ``lat_err_arcsec``,
        ``lon_err_arcsec``, ``pos_err_nmi`` and ``{pitch,roll,yaw}_err_arcsec`` (computed minus true). The
        summary holds one checkpoint per whole hour ``{t_h, lat_deg, lon_deg, lat_err_arcsec,
        lon_err_arcsec, pos_err_nmi}``, ``final_pos_err_nmi`` and ``max_pos_err_nmi`` (over kept samples,
        checkpoints and the final state).
    """
    from gyrodrift import _core

    if not (isinstance(chunk_samples, int) and chunk_samples >= 1):
        raise ValueError(f"navigate: chunk_samples must be a positive integer, got {chunk_samples!r}")
    if not (decimation_s > 0 and math.isfinite(decimation_s)):
        raise ValueError(f"navigate: decimation_s must be > 0, got {decimation_s!r}")
    src = _open_source(imu, chunk_samples)
    rate = src.rate_hz
    n_total = src.n_samples
    if hours is not None:
        if not (hours > 0 and math.isfinite(hours)):
            raise ValueError(f"navigate: hours must be > 0, got {hours!r}")
        asked = int(round(hours * HOUR * rate))
        if asked > n_total:
            raise ValueError(f"navigate: {hours:g} h asked but the IMU data hold {n_total / (HOUR * rate):.4g} h")
        n_total = asked
    dec = max(1, int(round(decimation_s * rate)))
    per_hour = int(round(HOUR * rate))
    init = _initial_state(initial, src.truth, src.label)

    gyro_est = _vector3("gyro_bias_deg_h", gyro_bias_deg_h)
    gyro_est[2] += float(compensate_drift_deg_h)
    accel_est = _vector3("accel_bias_ug", accel_bias_ug)

    nav = _core.Navigator(
        {
            "lat_rad": init["lat_deg"] * DEG,
            "lon_rad": init["lon_deg"] * DEG,
            "height_m": init["height_m"],
            "vel_enu_m_s": init["vel_enu_m_s"],
            "pitch_rad": init["pitch_deg"] * DEG,
            "roll_rad": init["roll_deg"] * DEG,
            "yaw_rad": init["yaw_deg"] * DEG,
            "rate_hz": float(rate),
            "vertical": vertical,
        }
    )
    nav.set_gyro_bias([b * DEG_PER_H for b in gyro_est])
    nav.set_accel_bias([b * MICRO_G for b in accel_est])

    parts: list[dict[str, np.ndarray]] = []
    true_parts: list[np.ndarray] = []
    hourly: list[tuple[int, dict[str, Any]]] = []
    done = 0
    with progress(n_total, "navigate", quiet) as bar:
        for chunk in src.chunks:
            if done >= n_total:
                break
            chunk = chunk.slice(0, n_total - done)
            a = 0
            while a < len(chunk):
                # Split at whole hours so every checkpoint is the exact state at k * 3600 s.
                b = min(len(chunk), a + per_hour - (done % per_hour))
                seg = chunk.slice(a, b)
                out = nav.process(
                    np.ascontiguousarray(seg.dtheta_rad, dtype=np.float64),
                    np.ascontiguousarray(seg.dv_m_s, dtype=np.float64),
                    dec,
                )
                first = (dec - 1 - done) % dec
                if len(out["t_s"]):
                    parts.append(out)
                    if seg.true_deg is not None:
                        true_parts.append(seg.true_deg[first::dec])
                done += len(seg)
                if done % per_hour == 0:
                    hourly.append((done // per_hour, nav.state()))
                a = b
            bar.update(len(chunk))
    final = nav.state()
    return _finish(
        parts,
        true_parts,
        hourly,
        final,
        src,
        init,
        rate,
        dec,
        n_total,
        done,
        compensate_drift_deg_h,
        gyro_est,
        accel_est,
        out_dir,
    )


def _finish(
    parts,
    true_parts,
    hourly,
    final,
    src,
    init,
    rate,
    dec,
    n_total,
    done,
    compensate_drift_deg_h,
    gyro_est,
    accel_est,
    out_dir,
) -> NavResult:
    def cat(key: str) -> np.ndarray:
        return np.concatenate([np.asarray(p[key], dtype=float) for p in parts]) if parts else np.zeros(0)

    vel = (
        np.concatenate([np.asarray(p["vel_enu_m_s"], dtype=float).reshape(-1, 3) for p in parts])
        if parts
        else np.zeros((0, 3))
    )
    cols: dict[str, np.ndarray] = {
        "t_s": cat("t_s"),
        "lat_deg": np.rad2deg(cat("lat_rad")),
        "lon_deg": np.rad2deg(cat("lon_rad")),
        "height_m": cat("height_m"),
        "vel_e_m_s": vel[:, 0],
        "vel_n_m_s": vel[:, 1],
        "vel_u_m_s": vel[:, 2],
        "pitch_deg": np.rad2deg(cat("pitch_rad")),
        "roll_deg": np.rad2deg(cat("roll_rad")),
        "yaw_deg": np.rad2deg(cat("yaw_rad")),
    }
    truth = src.truth
    lat0 = lon0 = None
    if truth is not None:
        lat0, lon0 = truth.lat_deg * DEG, truth.lon_deg * DEG
        pe = position_errors(cols["lat_deg"] * DEG, cols["lon_deg"] * DEG, lat0, lon0)
        cols["lat_err_arcsec"] = pe["lat_err_arcsec"]
        cols["lon_err_arcsec"] = pe["lon_err_arcsec"]
        cols["pos_err_nmi"] = pe["pos_err_nmi"]
        if true_parts and sum(len(t) for t in true_parts) == len(cols["t_s"]):
            tr = np.deg2rad(np.concatenate(true_parts))
            ae = attitude_errors_arcsec(
                cols["pitch_deg"] * DEG, cols["roll_deg"] * DEG, cols["yaw_deg"] * DEG, tr[:, 0], tr[:, 1], tr[:, 2]
            )
            cols.update(ae)

    def point(state: Mapping[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
        lat, lon = float(state["lat_rad"]), float(state["lon_rad"])
        d = dict(extra)
        d["lat_deg"] = math.degrees(lat)
        d["lon_deg"] = math.degrees(lon)
        if truth is not None:
            e = position_errors(lat, lon, lat0, lon0)
            d["lat_err_arcsec"] = float(e["lat_err_arcsec"])
            d["lon_err_arcsec"] = float(e["lon_err_arcsec"])
            d["pos_err_nmi"] = float(e["pos_err_nmi"])
        else:
            d["lat_err_arcsec"] = d["lon_err_arcsec"] = d["pos_err_nmi"] = None
        return d

    checkpoints = [point(st, {"t_h": k}) for k, st in hourly]
    final_pt = point(final, {"t_h": done / (HOUR * rate)})
    summary: dict[str, Any] = {
        "format": SUMMARY_FORMAT,
        "imu": src.label,
        "rate_hz": rate,
        "n_samples": done,
        "hours_navigated": done / (HOUR * rate),
        "decimation_s": dec / rate,
        "compensate_drift_deg_h": float(compensate_drift_deg_h),
        "gyro_bias_deg_h": gyro_est,
        "accel_bias_ug": accel_est,
        "initial": init,
        "truth": None
        if truth is None
        else {"lat_deg": truth.lat_deg, "lon_deg": truth.lon_deg, "height_m": truth.height_m},
        "checkpoints": checkpoints,
        "final": final_pt,
        "final_pos_err_nmi": final_pt["pos_err_nmi"],
        "max_pos_err_nmi": None,
    }
    if truth is not None:
        candidates = [final_pt["pos_err_nmi"]] + [c["pos_err_nmi"] for c in checkpoints]
        if len(cols["pos_err_nmi"]):
            candidates.append(float(np.max(cols["pos_err_nmi"])))
        summary["max_pos_err_nmi"] = max(candidates)

    folder = None
    if out_dir is not None:
        folder = Path(out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        table = pa.Table.from_pydict(
            {k: pa.array(v, pa.float64()) for k, v in cols.items()},
        ).replace_schema_metadata({"gyrodrift.format": "gyrodrift-nav/1", "gyrodrift.imu": src.label})
        json.dumps(summary, allow_nan=False)  # fail before writing either file: the two always match
        atomic_write_parquet(table, folder / "nav.parquet")
        atomic_write_json(summary, folder / "summary.json")
    return NavResult(columns=cols, summary=summary, out_dir=folder)
