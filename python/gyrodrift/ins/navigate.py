"""Free navigation of a recorded or simulated static-base IMU run, with errors against the truth."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from gyrodrift.choices import MAX_DRIFT_DEG_H
from gyrodrift.errors import OptionError
from gyrodrift.files.atomic import OutputFolder, Stage, output_folder, staged, write_json
from gyrodrift.ins.nav_errors import attitude_errors_arcsec, position_errors
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import PARQUET_OPTIONS, ImuData
from gyrodrift.ins.stream import Track, run_navigators
from gyrodrift.ins.track import ReferenceTrack, load_track, route_of
from gyrodrift.ins.vehicle import table_angles_deg, vehicle_attitude_rad
from gyrodrift.logs import DEFAULT_CHUNK_SAMPLES, REF_HEIGHT_COLUMN, ImuLog, LogChunk, LogError, LogTruth, open_log
from gyrodrift.site import Site
from gyrodrift.units import DEG, DEG_PER_H, HOUR, MICRO_G

__all__ = [
    "NavResult",
    "navigate",
    "as_log",
    "INITIAL_SOURCES",
    "NAV_COLUMNS",
    "NAV_ERROR_COLUMNS",
    "VEHICLE_COLUMNS",
    "SUMMARY_FORMAT",
    "VERTICAL_CHANNELS",
    "vertical_reference",
]

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

VEHICLE_COLUMNS = ("vehicle_pitch_deg", "vehicle_roll_deg", "vehicle_yaw_deg")
"""Columns of nav.parquet on a moving base whose log has the table angle: the vehicle's attitude, the navigated IMU
attitude with the table turn removed (`gyrodrift.ins.vehicle`)."""

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


VERTICAL_CHANNELS = ("fixed", "damped")
"""The core navigator's vertical channels (`navigate`'s ``vertical``)."""

INITIAL_SOURCES = ("auto", "truth", "alignment")
"""Where `navigate` takes its initial state from (besides a mapping of given values)."""


def as_log(
    imu: str | os.PathLike[str] | ImuLog | ImuData | Scenario,
    *,
    site: Site | Mapping[str, float] | None = None,
    require_temperature: bool = False,
) -> ImuLog:
    """The `gyrodrift.logs.ImuLog` of any IMU source `navigate` takes (a path, an ImuLog, an ImuData, a Scenario).

    `site` replaces or completes the source's site as in `gyrodrift.logs.open_log`.
    """
    if isinstance(imu, ImuLog):
        if site is not None:
            raise OptionError("navigate: give the site to open_log, not with an opened log")
        return imu
    if isinstance(imu, Scenario):
        return ImuLog.from_scenario(imu, site=site)
    if isinstance(imu, ImuData):
        s = imu.scenario
        return ImuLog.from_arrays(
            imu.columns,
            rate_hz=s.run.rate_hz,
            site=site,
            source_site=Site(s.site.lat_deg, s.site.lon_deg, s.site.height_m),
            truth=LogTruth(s.attitude.pitch_deg, s.attitude.roll_deg, s.attitude.yaw_deg),
            require_temperature=require_temperature,
            static_s=None if s.trajectory is None else s.trajectory.static_h * 3600.0,
        )
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


def _true_start(log: ImuLog) -> tuple[dict[str, Any], int] | None:
    """The true state the log says and the sample navigation starts at, or None.

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
    state = {"lat_deg": s.lat_deg, "lon_deg": s.lon_deg, "height_m": s.height_m}
    state.update(zip(("pitch_deg", "roll_deg", "yaw_deg"), att, strict=True))
    return state, start


def _initial_from(initial: str | Mapping[str, Any], log: ImuLog) -> tuple[str, dict[str, Any], int]:
    """(source, state, start sample): source "given", "truth" or "alignment" (the state then comes later)."""
    if isinstance(initial, str):
        if initial not in INITIAL_SOURCES:
            raise OptionError(
                f"navigate: --initial must be one of {', '.join(INITIAL_SOURCES)} or a mapping, got {initial!r}"
            )
        found = None if initial == "alignment" else _true_start(log)
        if initial == "alignment" or (initial == "auto" and found is None):
            return "alignment", {}, 0
        if found is None:
            raise LogError(
                f"{log.label}: the log carries no true initial state (no gyrodrift.scenario metadata or true "
                "attitude columns, or no site); use --initial alignment (or give the initial state)"
            )
        return "truth", {**found[0], "vel_enu_m_s": [0.0, 0.0, 0.0]}, found[1]
    found = _true_start(log) if log.truth is not None else None  # the scenario's t = 0 state only
    truth = None if found is None else found[0]
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
        elif truth is not None:
            out[k] = float(truth[k])
        else:
            raise OptionError(f"navigate: {log.label} carries no truth; initial must give {k}")
    out["vel_enu_m_s"] = _vector3("initial vel_enu_m_s", initial.get("vel_enu_m_s"))
    return "given", out, 0


def navigate(
    imu: str | os.PathLike[str] | ImuLog | ImuData | Scenario,
    *,
    hours: float | None = None,
    compensate_drift_deg_h: float = 0.0,
    gyro_bias_deg_h: Sequence[float] | None = None,
    accel_bias_ug: Sequence[float] | None = None,
    initial: str | Mapping[str, Any] = "auto",
    site: Site | Mapping[str, float] | None = None,
    timeline: Any = None,
    decimation_s: float = 1.0,
    vertical: str | None = None,
    reference: Any = None,
    out_dir: str | os.PathLike[str] | OutputFolder | None = None,
    plot: bool = False,
    chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
    quiet: bool = True,
) -> NavResult:
    """Navigate a static-base IMU run with the Rust strapdown navigator and compare with the truth.

    Parameters
    ----------
    imu : path, ImuLog, ImuData or Scenario
        Any IMU log the other commands take (Parquet or CSV, `gyrodrift.logs`; streamed in chunks), an opened
        `ImuLog`, an in-memory `ImuData`, or a `Scenario` simulated on the fly chunk by chunk (nothing stored:
        the fast path for long runs).
    hours : float, optional
        Navigate only the first `hours` [h] of navigation (default: to the end of the log). Must cover at
        least one output step (`decimation_s`).
    compensate_drift_deg_h : float
        Axial (z) gyro drift estimate [deg/h], subtracted from the measured z rate
        (compensated = measured - estimate). Added to ``gyro_bias_deg_h[2]``.
    gyro_bias_deg_h, accel_bias_ug : 3 numbers, optional
        Gyro [deg/h] and accelerometer [ug] bias estimates, body x y z, subtracted from the measurements
        (added to the alignment's own estimates when the state comes from an alignment).
    initial : {"auto", "truth", "alignment"} or mapping
        Initial state. "truth": the true site and the attitude at table angle 0 from the log's scenario
        metadata (simulated logs), navigation from the first sample. "alignment": align the first
        ``timeline.align_h`` hours of the log (`gyrodrift.procedure.align_log`, needs the site) and navigate
        from the end of the alignment with its attitude, velocity and x/y gyro and accelerometer bias
        estimates. "auto" (default): "truth" when the log carries it, else "alignment". A mapping gives
        ``lat_deg, lon_deg, height_m, pitch_deg, roll_deg, yaw_deg`` [deg, m] and ``vel_enu_m_s`` (3, m/s);
        missing keys come from the truth. ``summary["initial_source"]`` says which was used.
    site : Site or mapping, optional
        The static site, as in `gyrodrift.logs.open_log` (``--lat0-deg``, ``--lon0-deg``, ``--height-m``);
        position errors are computed against it when known.
    timeline : gyrodrift.procedure.Timeline, optional
        The alignment span for ``initial="alignment"`` (default: `gyrodrift.procedure.DEFAULT_TIMELINE`, 4 h).
    decimation_s : float
        Keep the state every `decimation_s` [s] (rounded to whole samples, counted from the navigation start).
    vertical : {"fixed", "damped"}, optional
        Vertical channel of the core navigator: "fixed" holds the height (static base, level route); "damped" is a
        second-order loop towards a reference height, the log's ``ref_height_m`` column (barometric or known
        height) when it has one, else the reference track's height (the simulated route's, or `reference`'s),
        else the initial height. Default: "damped" when the log has ``ref_height_m``, else "fixed".
        ``summary["vertical"]`` and ``summary["vertical_reference"]`` say which channel and reference were used.
    reference : ReferenceTrack or path, optional
        Moving base: the true track the position errors are computed against, interpolated to the kept samples
        (`gyrodrift.ins.track`: a `ReferenceTrack` or a GNSS CSV/Parquet file with ``t_s, lat_deg, lon_deg,
        height_m`` and optionally ``vel_{e,n,u}_m_s``, times on the log's time base). Default: the simulated route
        when the source is a moving-base scenario or its imu.parquet (``[trajectory]``), else the static site.
        A track that does not cover the navigated span is a `gyrodrift.ins.track.TrackError`.
    out_dir : path-like or gyrodrift.files.atomic.OutputFolder, optional
        If given, write ``nav.parquet`` and ``summary.json`` there, published together (`write_navigation`);
        the folder is checked before navigating (docs/outputs.md): an input file is never replaced.
    plot : bool
        Also write ``navigation.png`` (position, latitude/longitude and attitude errors vs time) into `out_dir`,
        in the same publication (needs `out_dir`). Default False.
    chunk_samples : int
        Samples per call to the core.
    quiet : bool
        True hides the progress bar.

    Returns
    -------
    NavResult
        Columns ``t_s`` [s since the navigation start], ``lat_deg``, ``lon_deg``, ``height_m``,
        ``vel_{e,n,u}_m_s`` (ENU), ``pitch_deg``, ``roll_deg``, ``yaw_deg``; with a known site also
        ``lat_err_arcsec``, ``lon_err_arcsec``, ``pos_err_nmi``, and with true attitude columns
        ``{pitch,roll,yaw}_err_arcsec`` (computed minus true). The summary holds one checkpoint per whole hour
        of navigation ``{t_h, lat_deg, lon_deg, lat_err_arcsec, lon_err_arcsec, pos_err_nmi}``,
        ``final_pos_err_nmi`` and ``max_pos_err_nmi`` (over kept samples, checkpoints and the final state),
        ``initial_source`` and ``start_s`` (log time of the navigation start [s]), ``vertical`` and
        ``vertical_reference``. On a moving base with the table angle (an imu.parquet, an in-memory run or a
        scenario navigated on the fly) also the vehicle's attitude (`VEHICLE_COLUMNS`).
    """
    from gyrodrift import _core

    if not (isinstance(chunk_samples, int) and chunk_samples >= 1):
        raise OptionError(f"navigate: chunk_samples must be a positive integer, got {chunk_samples!r}")
    if not (decimation_s > 0 and math.isfinite(decimation_s)):
        raise OptionError(f"navigate: decimation_s must be > 0, got {decimation_s!r}")
    if hours is not None and not (hours > 0):
        raise OptionError(f"navigate: hours must be > 0, got {hours!r}")
    if hours is not None and not math.isfinite(hours):
        raise OptionError(f"navigate: --hours must be a finite number of hours, got {hours!r}")
    gyro_est = _vector3("gyro_bias_deg_h", gyro_bias_deg_h)
    if not (math.isfinite(compensate_drift_deg_h) and abs(compensate_drift_deg_h) <= MAX_DRIFT_DEG_H):
        raise OptionError(
            f"navigate: --drift-deg-h must be a finite drift within +-{MAX_DRIFT_DEG_H:g} deg/h (an RLG's is of "
            f"order 0.001-0.01 deg/h), got {compensate_drift_deg_h!r}"
        )
    gyro_est[2] += float(compensate_drift_deg_h)
    accel_est = _vector3("accel_bias_ug", accel_bias_ug)
    if plot and out_dir is None:
        raise OptionError("navigate: --plot needs --out (the figure is written next to nav.parquet)")
    if vertical is not None and vertical not in VERTICAL_CHANNELS:
        raise OptionError(f"navigate: vertical must be one of {', '.join(VERTICAL_CHANNELS)}, got {vertical!r}")
    if out_dir is not None:  # checked before any work; the log itself is never one of the outputs
        source_path = imu if isinstance(imu, (str, os.PathLike)) else getattr(imu, "path", None)
        out_dir = output_folder(out_dir, "navigate", nav_files(plot), inputs=[source_path] if source_path else ())
    log = as_log(imu, site=site)
    rate = log.rate_hz
    source, init, start = _initial_from(initial, log)
    dec = max(1, int(round(decimation_s * rate)))
    if source == "alignment":
        from gyrodrift.procedure.align import align_log
        from gyrodrift.procedure.timeline import DEFAULT_TIMELINE

        timeline = DEFAULT_TIMELINE if timeline is None else timeline

        if hours is not None:  # refuse a navigation the log cannot hold before aligning
            log.require_duration(
                timeline.log_hours_for(hours) * HOUR,
                f"navigating --hours {hours:g} h after the {timeline.align_h:g} h alignment",
                align_h=timeline.align_h,
            )
        al = align_log(log, timeline=timeline, chunk_samples=chunk_samples, quiet=quiet)
        start = al.samples_used
        init = {
            "lat_deg": al.site.lat_deg,
            "lon_deg": al.site.lon_deg,
            "height_m": al.site.height_m,
            "pitch_deg": al.pitch_deg,
            "roll_deg": al.roll_deg,
            "yaw_deg": al.yaw_deg,
            "vel_enu_m_s": [float(v) for v in al.vel_enu_m_s],
        }
        gyro_est = [gyro_est[0] + al.gyro_bias_deg_h[0], gyro_est[1] + al.gyro_bias_deg_h[1], gyro_est[2]]
        accel_est = [a + b for a, b in zip(accel_est, al.accel_bias_ug, strict=True)]
    available = log.n_samples - start
    after = f" after the {start / rate / HOUR:g} h alignment" if source == "alignment" else ""
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

    ref = _reference_track(reference, imu)
    if ref is not None:
        ref.require_cover(start / rate, (start + n_total) / rate, f"navigating {log.label}")
    channel = vertical or ("damped" if log.has_reference_height else "fixed")
    heights, vertical_ref = vertical_reference(channel, log, ref)
    nav = _core.Navigator(
        _core.NavigatorConfig(
            lat_rad=init["lat_deg"] * DEG,
            lon_rad=init["lon_deg"] * DEG,
            height_m=init["height_m"],
            vel_enu_m_s=init["vel_enu_m_s"],
            pitch_rad=init["pitch_deg"] * DEG,
            roll_rad=init["roll_deg"] * DEG,
            yaw_rad=init["yaw_deg"] * DEG,
            rate_hz=float(rate),
            vertical=channel,
        )
    )
    nav.set_gyro_bias([b * DEG_PER_H for b in gyro_est])
    nav.set_accel_bias([b * MICRO_G for b in accel_est])

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
        chunk_samples=chunk_samples,
        quiet=quiet,
    )
    run = _Run(
        log=log,
        start=start,
        n_samples=n_total,
        dec=dec,
        initial_source=source,
        init=init,
        compensate_drift_deg_h=float(compensate_drift_deg_h),
        gyro_est=gyro_est,
        accel_est=accel_est,
        vertical=channel,
        vertical_reference=vertical_ref,
    )
    truth_at = _truth_at(ref, log.site)
    kept_idx = start + dec * np.arange(1, n_total // dec + 1) - 1  # 0-based log samples of the kept states
    table_deg = table_kept if table_kept is not None else table_angles_deg(imu, kept_idx) if ref is not None else None
    vehicle = None
    if table_deg is not None:
        k = track.kept
        vehicle = vehicle_attitude_rad(k["pitch_rad"], k["roll_rad"], k["yaw_rad"], np.deg2rad(table_deg))
    cols = _columns(track, true_deg, truth_at, start / rate)
    if vehicle is not None:
        for name, angle in zip(VEHICLE_COLUMNS, vehicle, strict=True):
            cols[name] = np.rad2deg(angle)
    summary = _summary(run, track, cols, truth_at, ref)
    folder = None
    if out_dir is not None:
        folder = write_navigation(cols, summary, out_dir, plot=plot)
    return NavResult(columns=cols, summary=summary, out_dir=folder)


@dataclass(frozen=True)
class _Run:
    """What `navigate` did, for the summary."""

    log: ImuLog
    start: int
    n_samples: int
    dec: int
    initial_source: str
    init: dict[str, Any]
    compensate_drift_deg_h: float
    gyro_est: list[float]
    accel_est: list[float]
    vertical: str = "fixed"
    vertical_reference: str | None = None


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
    """The reference track of `navigate`: given (a ReferenceTrack or a track file), else the simulated route of a
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
        errors = {name: pe[name] for name in ("lat_err_arcsec", "lon_err_arcsec", "pos_err_nmi")}
        if true_deg is not None:
            tr = np.deg2rad(true_deg, out=true_deg)
            errors.update(
                attitude_errors_arcsec(k["pitch_rad"], k["roll_rad"], k["yaw_rad"], tr[:, 0], tr[:, 1], tr[:, 2])
            )
    vel = k["vel_enu_m_s"]
    cols: dict[str, np.ndarray] = {
        "t_s": k["t_s"],
        "lat_deg": np.rad2deg(k["lat_rad"], out=k["lat_rad"]),
        "lon_deg": np.rad2deg(k["lon_rad"], out=k["lon_rad"]),
        "height_m": k["height_m"],
        "vel_e_m_s": vel[:, 0],
        "vel_n_m_s": vel[:, 1],
        "vel_u_m_s": vel[:, 2],
        "pitch_deg": np.rad2deg(k["pitch_rad"], out=k["pitch_rad"]),
        "roll_deg": np.rad2deg(k["roll_rad"], out=k["roll_rad"]),
        "yaw_deg": np.rad2deg(k["yaw_rad"], out=k["yaw_rad"]),
    }
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

    def point(state: Mapping[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
        lat, lon = float(state["lat_rad"]), float(state["lon_rad"])
        d = dict(extra)
        d["lat_deg"] = math.degrees(lat)
        d["lon_deg"] = math.degrees(lon)
        if truth_at is not None:
            true_lat, true_lon = truth_at(np.array([run.start / rate + float(extra["t_h"]) * HOUR]))
            e = position_errors(lat, lon, true_lat[0], true_lon[0])
            d["lat_err_arcsec"] = float(e["lat_err_arcsec"])
            d["lon_err_arcsec"] = float(e["lon_err_arcsec"])
            d["pos_err_nmi"] = float(e["pos_err_nmi"])
        else:
            d["lat_err_arcsec"] = d["lon_err_arcsec"] = d["pos_err_nmi"] = None
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
        "initial_source": run.initial_source,
        "start_s": run.start / rate,
        "vertical": run.vertical,
        "vertical_reference": run.vertical_reference,
        "compensate_drift_deg_h": run.compensate_drift_deg_h,
        "gyro_bias_deg_h": run.gyro_est,
        "accel_bias_ug": run.accel_est,
        "initial": run.init,
        "truth": None
        if site is None
        else {"lat_deg": site.lat_deg, "lon_deg": site.lon_deg, "height_m": site.height_m},
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


NAV_FILES = ("nav.parquet", "summary.json")
"""The files of a navigation output, published together."""
NAV_PLOT = "navigation.png"
"""The figure `navigate --plot` adds to them."""


def nav_files(plot: bool = False) -> tuple[str, ...]:
    """The files `write_navigation` publishes (with the figure when `plot`)."""
    return NAV_FILES + ((NAV_PLOT,) if plot else ())


def write_navigation(
    columns: Mapping[str, np.ndarray],
    summary: Mapping[str, Any],
    out: str | os.PathLike[str] | OutputFolder | Stage,
    *,
    plot: bool = False,
) -> Path:
    """Write ``nav.parquet`` (the columns, float64, metadata ``gyrodrift.format = gyrodrift-nav/1``) and
    ``summary.json`` (and with `plot` ``navigation.png``, `gyrodrift.procedure.figures.navigation_figure`) into
    `out` as one set (`gyrodrift.files.atomic.staged`); return the folder."""
    table = pa.Table.from_pydict(
        {k: pa.array(v, pa.float64()) for k, v in columns.items()},
    ).replace_schema_metadata({"gyrodrift.format": "gyrodrift-nav/1", "gyrodrift.imu": str(summary.get("imu"))})
    json.dumps(summary, allow_nan=False)  # fail before writing either file
    with staged(out, "navigate", nav_files(plot)) as stage:
        pq.write_table(table, stage.file("nav.parquet"), **PARQUET_OPTIONS)  # no dictionaries: 4x faster
        write_json(dict(summary), stage.file("summary.json"))
        if plot:
            from gyrodrift.procedure.figures import navigation_figure, save_png

            save_png(navigation_figure(columns, summary), stage.file(NAV_PLOT))
    return stage.folder
