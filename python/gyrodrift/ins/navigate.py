"""Free navigation of a recorded or simulated IMU run from a given initial state, with errors against the truth.

`navigate_from` runs the Rust strapdown navigator over a log from an `InitialState` (the log's truth, given values
or an alignment's result) with given bias estimates and an axial drift law subtracted (`NavSettings`; the law sample by
sample on the log's temperature, `gyrodrift.ins.compensation`) and returns the nav.parquet columns
(`gyrodrift.ins.nav_columns`) and the summary; `gyrodrift.procedure.navigate` is the job that chooses the initial
state (aligning the log when it carries no truth) and writes the files.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from gyrodrift import _core
from gyrodrift.choices import MAX_DRIFT_DEG_H
from gyrodrift.drift_law import DriftLaw
from gyrodrift.errors import OptionError
from gyrodrift.ins.compensation import axial_bias, compensation_record
from gyrodrift.ins.nav_columns import (
    ATTITUDE_ERROR_COLUMNS,
    NAV_COLUMNS,
    POSITION_ERROR_COLUMNS,
    VEHICLE_COLUMNS,
    nav_table,
)
from gyrodrift.ins.nav_errors import attitude_errors_arcsec, position_errors
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import ImuData, scenario_log
from gyrodrift.ins.stream import Track, run_navigators
from gyrodrift.ins.track import ReferenceTrack, load_track, route_of
from gyrodrift.ins.vehicle import table_angles_deg, vehicle_attitude_rad
from gyrodrift.logs import REF_HEIGHT_COLUMN, ImuLog, LogChunk, open_log
from gyrodrift.site import Site
from gyrodrift.units import DEG, DEG_PER_H, HOUR, MICRO_G

__all__ = [
    "InitialState",
    "NavResult",
    "NavSettings",
    "navigate_from",
    "true_start",
    "given_start",
    "as_log",
    "SUMMARY_FORMAT",
    "VERTICAL_CHANNELS",
    "vertical_reference",
]

SUMMARY_FORMAT = "gyrodrift-nav-summary/1"


@dataclass(frozen=True)
class NavResult:
    """The outcome of a navigation (`navigate_from`, `gyrodrift.procedure.navigate`).

    Attributes
    ----------
    columns : dict of str to numpy.ndarray
        nav.parquet columns (`gyrodrift.ins.nav_columns`: the state, plus the errors when the truth is known), one
        row per kept sample (every ``decimation_s``).
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
        """The columns as a pyarrow Table (the declared dtypes, float64)."""
        return nav_table(self.columns)

    def checkpoint(self, t_h: int) -> dict[str, Any]:
        """The summary checkpoint at whole hour `t_h` (KeyError if the run did not reach it)."""
        for c in self.summary["checkpoints"]:
            if c["t_h"] == t_h:
                return c
        raise KeyError(f"no checkpoint at {t_h} h")


VERTICAL_CHANNELS = ("fixed", "damped")
"""The core navigator's vertical channels (`NavSettings.vertical`)."""


@dataclass(frozen=True)
class InitialState:
    """Where a free navigation starts: the state at the end of log sample ``start - 1`` (user units).

    Attributes
    ----------
    source : {"truth", "given", "alignment"}
        Where the state came from (summary.json's ``initial_source``).
    start : int
        The first log sample navigated (0-based).
    lat_deg, lon_deg, height_m : float
        Geodetic position [deg, deg, m].
    pitch_deg, roll_deg, yaw_deg : float
        Attitude [deg] (yaw positive counter-clockwise about Up).
    vel_enu_m_s : list of 3 float
        Velocity, ENU [m/s].
    """

    source: str
    start: int
    lat_deg: float
    lon_deg: float
    height_m: float
    pitch_deg: float
    roll_deg: float
    yaw_deg: float
    vel_enu_m_s: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])

    def state(self) -> dict[str, Any]:
        """The state as summary.json's ``initial``: position, attitude and ``vel_enu_m_s``."""
        return {k: getattr(self, k) for k in _STATE_KEYS + ("vel_enu_m_s",)}


@dataclass(frozen=True)
class NavSettings:
    """How a free navigation runs, checked (`NavSettings.checked`), user units.

    Attributes
    ----------
    hours : float or None
        Navigation length [h] from the initial state (None: to the end of the log).
    decimation_s : float
        Keep the state every `decimation_s` [s] (rounded to whole samples, counted from the navigation start).
    drift_law : DriftLaw or None
        The axial drift to subtract (None: none). Its ``eps_ref_deg_h`` is included in ``gyro_bias_deg_h[2]``; a
        law that reads the temperature adds k1 (T - T_ref) + k3 dT/dt sample by sample on the log's ``temp_c``
        (`gyrodrift.ins.compensation`).
    gyro_bias_deg_h, accel_bias_ug : list of 3 float
        Gyro [deg/h] and accelerometer [ug] bias estimates, body x y z, subtracted from the measurements
        (compensated = measured - estimate).
    vertical : {"fixed", "damped"} or None
        The vertical channel (None: "damped" when the log has ``ref_height_m``, else "fixed").
    chunk_samples : int
        Samples per call to the core.
    quiet : bool
        True hides the progress bar.
    """

    hours: float | None
    decimation_s: float
    drift_law: DriftLaw | None
    gyro_bias_deg_h: list[float]
    accel_bias_ug: list[float]
    vertical: str | None
    chunk_samples: int
    quiet: bool

    @classmethod
    def checked(
        cls,
        *,
        hours: float | None,
        decimation_s: float,
        drift_law: DriftLaw | None,
        gyro_bias_deg_h: Sequence[float] | None,
        accel_bias_ug: Sequence[float] | None,
        vertical: str | None,
        chunk_samples: int,
        quiet: bool,
    ) -> NavSettings:
        """The settings of `gyrodrift.procedure.navigate`'s keywords (whose defaults they are), each checked
        (`OptionError` naming it); a bias left None is zero, and the drift law's ``eps_ref_deg_h`` is added to the z
        gyro bias estimate."""
        if not (isinstance(chunk_samples, int) and chunk_samples >= 1):
            raise OptionError(f"navigate: chunk_samples must be a positive integer, got {chunk_samples!r}")
        if not (decimation_s > 0 and math.isfinite(decimation_s)):
            raise OptionError(f"navigate: decimation_s must be > 0, got {decimation_s!r}")
        if hours is not None and not (hours > 0):
            raise OptionError(f"navigate: hours must be > 0, got {hours!r}")
        if hours is not None and not math.isfinite(hours):
            raise OptionError(f"navigate: --hours must be a finite number of hours, got {hours!r}")
        gyro_est = _vector3("gyro_bias_deg_h", gyro_bias_deg_h)
        if drift_law is not None:
            if not isinstance(drift_law, DriftLaw):
                raise TypeError(f"navigate: drift_law must be a DriftLaw, got {type(drift_law).__name__}")
            if not abs(drift_law.eps_ref_deg_h) <= MAX_DRIFT_DEG_H:
                raise OptionError(
                    f"navigate: the drift law's eps_ref_deg_h (--drift-deg-h) must be a finite drift within "
                    f"+-{MAX_DRIFT_DEG_H:g} deg/h (an RLG's is of order 0.001-0.01 deg/h), got "
                    f"{drift_law.eps_ref_deg_h!r}"
                )
            gyro_est[2] += drift_law.eps_ref_deg_h
        accel_est = _vector3("accel_bias_ug", accel_bias_ug)
        if vertical is not None and vertical not in VERTICAL_CHANNELS:
            raise OptionError(f"navigate: vertical must be one of {', '.join(VERTICAL_CHANNELS)}, got {vertical!r}")
        return cls(
            hours=hours,
            decimation_s=decimation_s,
            drift_law=drift_law,
            gyro_bias_deg_h=gyro_est,
            accel_bias_ug=accel_est,
            vertical=vertical,
            chunk_samples=chunk_samples,
            quiet=quiet,
        )


def as_log(
    imu: str | os.PathLike[str] | ImuLog | ImuData | Scenario,
    *,
    site: Site | Mapping[str, float] | None = None,
    require_temperature: bool = False,
) -> ImuLog:
    """The `gyrodrift.logs.ImuLog` of any IMU source `gyrodrift.procedure.navigate` takes (a path, an ImuLog, an
    ImuData, a Scenario).

    `site` replaces or completes the source's site as in `gyrodrift.logs.open_log`.
    """
    if isinstance(imu, ImuLog):
        if site is not None:
            raise OptionError("navigate: give the site to open_log, not with an opened log")
        return imu
    if isinstance(imu, Scenario):
        return scenario_log(imu, site=site)
    if isinstance(imu, ImuData):
        return imu.log(site=site, require_temperature=require_temperature)
    if isinstance(imu, (str, os.PathLike)):
        return open_log(imu, site=site, require_temperature=require_temperature)
    raise TypeError(
        f"navigate: imu must be a path to an IMU log, an ImuLog, an ImuData or a Scenario, got {type(imu).__name__}"
    )


def _vector3(name: str, value: Sequence[float] | None) -> list[float]:
    if value is None:
        return [0.0, 0.0, 0.0]
    v = [float(x) for x in value]
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise OptionError(f"navigate: {name} must be 3 finite numbers, got {value!r}")
    return v


_STATE_KEYS = ("lat_deg", "lon_deg", "height_m", "pitch_deg", "roll_deg", "yaw_deg")


def true_start(log: ImuLog) -> InitialState | None:
    """The true initial state the log says (source "truth", at rest), or None.

    The ``gyrodrift.scenario`` metadata gives the attitude at t = 0 (navigation from the first sample); else the
    true attitude columns give it at the end of the first sample (navigation from the second). Both need the site.
    """
    if log.site is None:
        return None
    att: tuple[float, ...]
    if log.truth is not None:
        att, start = (log.truth.pitch_deg, log.truth.roll_deg, log.truth.yaw_deg), 0
    elif log.has_truth_columns:
        first = next(log.chunks(1, stop=1)).truth
        assert first is not None  # has_truth_columns: every chunk carries them
        att, start = tuple(float(c[0]) for c in first), 1
    else:
        return None
    s = log.site
    pitch, roll, yaw = att
    return InitialState("truth", start, s.lat_deg, s.lon_deg, s.height_m, pitch, roll, yaw)


def given_start(initial: Mapping[str, Any], log: ImuLog) -> InitialState:
    """The initial state of given values (source "given", navigation from the first sample): ``lat_deg, lon_deg,
    height_m, pitch_deg, roll_deg, yaw_deg`` [deg, m] and ``vel_enu_m_s`` (3, m/s, default at rest); a key left out
    comes from the scenario's t = 0 truth (`OptionError` when the log has none)."""
    found = true_start(log) if log.truth is not None else None  # the scenario's t = 0 state only
    unknown = set(initial) - set(_STATE_KEYS) - {"vel_enu_m_s"}
    if unknown:
        raise OptionError(
            f"navigate: unknown initial key(s) {sorted(unknown)} (expected {_STATE_KEYS + ('vel_enu_m_s',)})"
        )
    out: dict[str, Any] = {}
    for k in _STATE_KEYS:
        if k in initial:
            v = float(initial[k])
            if not math.isfinite(v):
                raise OptionError(f"navigate: initial {k} must be a finite number, got {initial[k]!r}")
            out[k] = v
        elif found is not None:
            out[k] = float(getattr(found, k))
        else:
            raise OptionError(f"navigate: {log.label} carries no truth; initial must give {k}")
    return InitialState("given", 0, **out, vel_enu_m_s=_vector3("initial vel_enu_m_s", initial.get("vel_enu_m_s")))


def navigate_from(
    log: ImuLog,
    initial: InitialState,
    settings: NavSettings,
    *,
    source: Any = None,
    reference: Any = None,
) -> NavResult:
    """Navigate `log` freely from `initial` with the Rust strapdown navigator and compare with the truth.

    Parameters
    ----------
    log : ImuLog
        The IMU log (streamed in chunks from ``initial.start``).
    initial : InitialState
        The state at the navigation start (`true_start`, `given_start`, or an alignment's result).
    settings : NavSettings
        Length, output step, bias estimates and drift law subtracted, vertical channel, chunking. A drift law
        reading the temperature needs the log's ``temp_c`` (`gyrodrift.logs.LogError` otherwise).
    source : path, ImuData or Scenario, optional
        What `log` was opened from: a moving-base source's simulated route is the default reference and its table
        angle gives the vehicle's attitude (`VEHICLE_COLUMNS`).
    reference : ReferenceTrack or path, optional
        Moving base: the true track the position errors are computed against (`gyrodrift.procedure.navigate`).

    Returns
    -------
    NavResult
        The columns (`gyrodrift.ins.nav_columns`) and the summary; ``out_dir`` None (nothing written).
    """
    rate = log.rate_hz
    start = initial.start
    dec = max(1, int(round(settings.decimation_s * rate)))
    hours = settings.hours
    available = log.n_samples - start
    after = f" after the {start / rate / HOUR:g} h alignment" if initial.source == "alignment" else ""
    if hours is None:
        n_total = available
    else:
        asked = hours * HOUR * rate
        if not asked <= available + 0.5:
            raise OptionError(
                f"navigate: --hours {hours:g}: {hours:g} h asked but the IMU data hold "
                f"{available / (HOUR * rate):.4g} h{after}"
            )
        n_total = int(round(asked))
    if n_total < dec:
        raise OptionError(
            f"navigate: --hours {hours if hours is not None else available / (HOUR * rate):g} h is "
            f"{n_total} sample(s){after}, shorter than one output step ({dec / rate:g} s = {dec} samples)"
        )

    source = log if source is None else source
    ref = _reference_track(reference, source)
    if ref is not None:
        ref.require_cover(start / rate, (start + n_total) / rate, f"navigating {log.label}")
    channel = settings.vertical or ("damped" if log.has_reference_height else "fixed")
    heights, vertical_ref = vertical_reference(channel, log, ref)
    nav = _core.Navigator(
        _core.NavigatorConfig(
            lat_rad=initial.lat_deg * DEG,
            lon_rad=initial.lon_deg * DEG,
            height_m=initial.height_m,
            vel_enu_m_s=initial.vel_enu_m_s,
            pitch_rad=initial.pitch_deg * DEG,
            roll_rad=initial.roll_deg * DEG,
            yaw_rad=initial.yaw_deg * DEG,
            rate_hz=float(rate),
            vertical=channel,
        )
    )
    nav.set_gyro_bias([b * DEG_PER_H for b in settings.gyro_bias_deg_h])
    nav.set_accel_bias([b * MICRO_G for b in settings.accel_bias_ug])
    law = settings.drift_law
    # A law reading the temperature: the z bias per sample (the other z estimate is the given one, exact to rounding).
    law_bias = None if law is None else axial_bias(law, log, settings.gyro_bias_deg_h[2] - law.eps_ref_deg_h)

    true_deg = np.empty((n_total // dec, 3)) if log.has_truth_columns else None
    # A scenario navigated on the fly carries its table angle in the chunks: kept for the vehicle attitude.
    table_kept = np.empty(n_total // dec) if ref is not None and log.format == "scenario" else None

    def keep(piece: LogChunk, done: int) -> None:  # the true attitude and table angle at the kept samples (copied)
        first = (dec - 1 - done) % dec
        k = len(range(first, len(piece), dec))
        rows = slice((done + first) // dec, (done + first) // dec + k)
        if true_deg is not None:
            assert piece.truth is not None  # every chunk of a log with truth columns carries them
            for j, column in enumerate(piece.truth):
                true_deg[rows, j] = column[first::dec]
        if table_kept is not None and piece.table_angle_deg is not None:
            table_kept[rows] = piece.table_angle_deg[first::dec]

    (track,) = run_navigators(
        log,
        [nav],
        n_samples=n_total,
        start=start,
        decimation=dec,
        observe=keep if true_deg is not None or table_kept is not None else None,
        reference=heights,
        axial_bias=None if law_bias is None else [law_bias],
        chunk_samples=settings.chunk_samples,
        quiet=settings.quiet,
    )
    run = _Run(log, initial, settings, n_total, dec, channel, vertical_ref)
    truth_at = _truth_at(ref, log.site)
    kept_idx = start + dec * np.arange(1, n_total // dec + 1) - 1  # 0-based log samples of the kept states
    table_deg: np.ndarray | None
    if table_kept is not None:
        table_deg = table_kept
    else:
        table_deg = table_angles_deg(source, kept_idx) if ref is not None else None
    vehicle = None
    if table_deg is not None:
        k = track.kept
        vehicle = vehicle_attitude_rad(k["pitch_rad"], k["roll_rad"], k["yaw_rad"], np.deg2rad(table_deg))
    cols = _columns(track, true_deg, truth_at, start / rate)
    if vehicle is not None:
        for name, angle in zip(VEHICLE_COLUMNS, vehicle, strict=True):
            cols[name] = np.rad2deg(angle)
    return NavResult(columns=cols, summary=_summary(run, track, cols, truth_at, ref))


@dataclass(frozen=True)
class _Run:
    """What `navigate_from` did, for the summary."""

    log: ImuLog
    initial: InitialState
    settings: NavSettings
    n_samples: int
    dec: int
    vertical: str
    vertical_reference: str | None


def vertical_reference(
    channel: str, log: ImuLog, ref: ReferenceTrack | None
) -> tuple[Callable[[LogChunk], np.ndarray] | None, str | None]:
    """The damped channel's reference heights per piece of the log and what the summary calls them: the log's
    ``ref_height_m`` column, else the reference track's height at the samples' times, else the initial height
    (None: the navigator keeps its own). A fixed channel has no reference."""
    if channel != "damped":
        return None, None
    if log.has_reference_height:

        def from_log(piece: LogChunk) -> np.ndarray:
            assert piece.ref_height_m is not None  # every chunk of a log with the column carries it
            return piece.ref_height_m

        return from_log, f"{REF_HEIGHT_COLUMN} column of {log.label}"
    if ref is not None:

        def from_track(piece: LogChunk) -> np.ndarray:
            return ref.at(piece.t_s)[2]

        return from_track, f"height of the reference track {ref.label}"
    return None, "initial height"


TruthAt = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
"""The true (lat, lon) [rad] at log times [s]."""


def _truth_at(ref: ReferenceTrack | None, site: Site | None) -> TruthAt | None:
    """The true position over time: the reference track's (moving base), else the static site's, else None."""
    if ref is not None:

        def along(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            lat, lon, _ = ref.at(t)
            return lat, lon

        return along
    if site is None:
        return None
    lat0, lon0 = site.lat_rad, site.lon_rad
    return lambda t: (np.full(np.shape(t), lat0), np.full(np.shape(t), lon0))


def _reference_track(reference: Any, imu: Any) -> ReferenceTrack | None:
    """The reference track of a navigation: given (a ReferenceTrack or a track file), else the simulated route of a
    moving-base source, else None (static base: the site)."""
    if isinstance(reference, ReferenceTrack):
        return reference
    if reference is not None:
        return load_track(reference)
    scenario = route_of(imu)
    return None if scenario is None else ReferenceTrack.from_scenario(scenario)


def _columns(
    track: Track, true_deg: np.ndarray | None, truth_at: TruthAt | None, start_s: float
) -> dict[str, np.ndarray]:
    """nav.parquet columns from the kept states (user units), with errors against the truth (the static site or
    the reference track at the log time `start_s` + t_s) and the true attitude.

    The angles are converted in place (the errors are computed from the radians first), so the kept arrays
    become the columns without a second copy of the output.
    """
    k = track.kept
    errors: dict[str, np.ndarray] = {}
    if truth_at is not None:
        true_lat, true_lon = truth_at(start_s + k["t_s"])
        pe = position_errors(k["lat_rad"], k["lon_rad"], true_lat, true_lon)
        errors = {name: pe[name] for name in POSITION_ERROR_COLUMNS}
        if true_deg is not None:
            tr = np.deg2rad(true_deg, out=true_deg)
            att = attitude_errors_arcsec(k["pitch_rad"], k["roll_rad"], k["yaw_rad"], tr[:, 0], tr[:, 1], tr[:, 2])
            errors.update((name, att[name]) for name in ATTITUDE_ERROR_COLUMNS)
    vel = k["vel_enu_m_s"]
    state = (  # in the order of NAV_COLUMNS
        k["t_s"],
        np.rad2deg(k["lat_rad"], out=k["lat_rad"]),
        np.rad2deg(k["lon_rad"], out=k["lon_rad"]),
        k["height_m"],
        vel[:, 0],
        vel[:, 1],
        vel[:, 2],
        np.rad2deg(k["pitch_rad"], out=k["pitch_rad"]),
        np.rad2deg(k["roll_rad"], out=k["roll_rad"]),
        np.rad2deg(k["yaw_rad"], out=k["yaw_rad"]),
    )
    cols = dict(zip(NAV_COLUMNS, state, strict=True))
    cols.update(errors)
    return cols


def _summary(
    run: _Run,
    track: Track,
    cols: Mapping[str, np.ndarray],
    truth_at: TruthAt | None = None,
    ref: ReferenceTrack | None = None,
) -> dict[str, Any]:
    """The content of summary.json (user units)."""
    site = run.log.site
    rate = run.log.rate_hz
    law = run.settings.drift_law

    def point(state: Mapping[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
        lat, lon = float(state["lat_rad"]), float(state["lon_rad"])
        d = dict(extra)
        d["lat_deg"] = math.degrees(lat)
        d["lon_deg"] = math.degrees(lon)
        if truth_at is not None:
            true_lat, true_lon = truth_at(np.array([run.initial.start / rate + float(extra["t_h"]) * HOUR]))
            e = position_errors(lat, lon, true_lat[0], true_lon[0])
            d.update((name, float(e[name])) for name in POSITION_ERROR_COLUMNS)
        else:
            d.update(dict.fromkeys(POSITION_ERROR_COLUMNS))
        return d

    checkpoints = [point(st, {"t_h": k}) for k, st in track.hourly]
    final_pt = point(track.final, {"t_h": run.n_samples / (HOUR * rate)})
    summary: dict[str, Any] = {
        "format": SUMMARY_FORMAT,
        "imu": run.log.label,
        "rate_hz": rate,
        "n_samples": run.n_samples,
        "hours_navigated": run.n_samples / (HOUR * rate),
        "decimation_s": run.dec / rate,
        "initial_source": run.initial.source,
        "start_s": run.initial.start / rate,
        "vertical": run.vertical,
        "vertical_reference": run.vertical_reference,
        "compensate_drift_deg_h": 0.0 if law is None else law.eps_ref_deg_h,
        **compensation_record(law),
        "gyro_bias_deg_h": run.settings.gyro_bias_deg_h,
        "accel_bias_ug": run.settings.accel_bias_ug,
        "initial": run.initial.state(),
        "truth": None if site is None else dataclasses.asdict(site),
        "reference": None if ref is None else ref.label,
        "checkpoints": checkpoints,
        "final": final_pt,
        "final_pos_err_nmi": final_pt["pos_err_nmi"],
        "max_pos_err_nmi": None,
    }
    if truth_at is not None:
        candidates = [final_pt["pos_err_nmi"]] + [c["pos_err_nmi"] for c in checkpoints]
        if len(cols["pos_err_nmi"]):
            candidates.append(float(np.max(cols["pos_err_nmi"])))
        summary["max_pos_err_nmi"] = max(candidates)
    return summary
