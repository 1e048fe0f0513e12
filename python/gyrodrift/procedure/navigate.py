"""The ``navigate`` job: navigate an IMU log from its truth, given values or its own alignment, and publish
nav.parquet, summary.json (and navigation.png).

The navigation itself is `gyrodrift.ins.navigate.navigate_from` (free navigation from a given initial state); this
job chooses that state (the log's truth, a mapping, or `gyrodrift.procedure.align_log` over the first
``Timeline.align_h`` hours, whose x/y gyro and accelerometer bias estimates are then compensated too) and writes
the outputs as one set (docs/outputs.md).
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from gyrodrift.drift_law import DriftLaw
from gyrodrift.errors import OptionError
from gyrodrift.files.atomic import OutputFolder, Stage, output_folder, staged, write_json
from gyrodrift.ins.nav_columns import NAV_FORMAT, nav_table
from gyrodrift.ins.navigate import (
    InitialState,
    NavResult,
    NavSettings,
    as_log,
    given_start,
    navigate_from,
    true_start,
)
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import PARQUET_OPTIONS, ImuData
from gyrodrift.logs import DEFAULT_CHUNK_SAMPLES, ImuLog, LogError
from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.figures import navigation_figure, save_png
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.site import Site
from gyrodrift.units import HOUR

__all__ = ["navigate", "write_navigation", "nav_files", "INITIAL_SOURCES", "NAV_FILES", "NAV_PLOT"]

INITIAL_SOURCES = ("auto", "truth", "alignment")
"""Where `navigate` takes its initial state from (besides a mapping of given values)."""

NAV_FILES = ("nav.parquet", "summary.json")
"""The files of a navigation output, published together."""
NAV_PLOT = "navigation.png"
"""The figure `navigate --plot` adds to them."""


def nav_files(plot: bool = False) -> tuple[str, ...]:
    """The files `write_navigation` publishes (with the figure when `plot`)."""
    return NAV_FILES + ((NAV_PLOT,) if plot else ())


def navigate(
    imu: str | os.PathLike[str] | ImuLog | ImuData | Scenario,
    *,
    hours: float | None = None,
    drift_law: DriftLaw | None = None,
    gyro_bias_deg_h: Sequence[float] | None = None,
    accel_bias_ug: Sequence[float] | None = None,
    initial: str | Mapping[str, Any] = "auto",
    site: Site | Mapping[str, float] | None = None,
    timeline: Timeline | None = None,
    decimation_s: float = 1.0,
    vertical: str | None = None,
    reference: Any = None,
    out_dir: str | os.PathLike[str] | OutputFolder | None = None,
    plot: bool = False,
    chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
    quiet: bool = True,
) -> NavResult:
    """Navigate an IMU run with the Rust strapdown navigator and compare with the truth.

    Parameters
    ----------
    imu : path, ImuLog, ImuData or Scenario
        Any IMU log the other commands take (Parquet or CSV, `gyrodrift.logs`; streamed in chunks), an opened
        `ImuLog`, an in-memory `ImuData`, or a `Scenario` simulated on the fly chunk by chunk (nothing stored:
        the fast path for long runs).
    hours : float, optional
        Navigate only the first `hours` [h] of navigation (default: to the end of the log). Must cover at
        least one output step (`decimation_s`).
    drift_law : gyrodrift.drift_law.DriftLaw, optional
        The axial (z) gyro drift estimate [deg/h] subtracted from the measured z rate (compensated = measured -
        estimate); a constant is ``DriftLaw.constant(d)`` (its drift added to ``gyro_bias_deg_h[2]``, as the summary
        reports it). A law reading the temperature is evaluated on the log's ``temp_c`` sample by sample
        (`gyrodrift.ins.compensation`; a log without it is a `LogError`). Default: none.
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
        The nav.parquet columns (`gyrodrift.ins.nav_columns`): ``t_s`` [s since the navigation start],
        ``lat_deg``, ``lon_deg``, ``height_m``, ``vel_{e,n,u}_m_s`` (ENU), ``pitch_deg``, ``roll_deg``,
        ``yaw_deg``; with a known site also ``lat_err_arcsec``, ``lon_err_arcsec``, ``pos_err_nmi``, and with true
        attitude columns ``{pitch,roll,yaw}_err_arcsec`` (computed minus true). The summary holds one checkpoint
        per whole hour of navigation ``{t_h, lat_deg, lon_deg, lat_err_arcsec, lon_err_arcsec, pos_err_nmi}``,
        ``final_pos_err_nmi`` and ``max_pos_err_nmi`` (over kept samples, checkpoints and the final state),
        ``initial_source`` and ``start_s`` (log time of the navigation start [s]), ``vertical`` and
        ``vertical_reference``, ``compensation`` ("none", "constant" or "law"), ``drift_law`` (its
        `DriftLaw.to_dict`) and ``compensate_drift_deg_h`` (its ``eps_ref_deg_h``). On a moving base with the
        table angle (an imu.parquet, an in-memory run or a scenario navigated on the fly) also the vehicle's
        attitude (``vehicle_{pitch,roll,yaw}_deg``).
    """
    settings = NavSettings.checked(
        hours=hours,
        decimation_s=decimation_s,
        drift_law=drift_law,
        gyro_bias_deg_h=gyro_bias_deg_h,
        accel_bias_ug=accel_bias_ug,
        vertical=vertical,
        chunk_samples=chunk_samples,
        quiet=quiet,
    )
    if plot and out_dir is None:
        raise OptionError("navigate: --plot needs --out (the figure is written next to nav.parquet)")
    if out_dir is not None:  # checked before any work; the log itself is never one of the outputs
        source_path = imu if isinstance(imu, (str, os.PathLike)) else getattr(imu, "path", None)
        out_dir = output_folder(out_dir, "navigate", nav_files(plot), inputs=[source_path] if source_path else ())
    log = as_log(imu, site=site)
    start = _initial_state(initial, log)
    if start is None:
        start, settings = _aligned_start(log, settings, DEFAULT_TIMELINE if timeline is None else timeline)
    result = navigate_from(log, start, settings, source=imu, reference=reference)
    if out_dir is None:
        return result
    folder = write_navigation(result.columns, result.summary, out_dir, plot=plot)
    return NavResult(columns=result.columns, summary=result.summary, out_dir=folder)


def _initial_state(initial: str | Mapping[str, Any], log: ImuLog) -> InitialState | None:
    """The initial state `initial` names (the log's truth or given values), or None when it is to come from an
    alignment of the log ("alignment", or "auto" on a log without truth)."""
    if not isinstance(initial, str):
        return given_start(initial, log)
    if initial not in INITIAL_SOURCES:
        raise OptionError(
            f"navigate: --initial must be one of {', '.join(INITIAL_SOURCES)} or a mapping, got {initial!r}"
        )
    if initial == "alignment":
        return None
    found = true_start(log)
    if found is None and initial == "truth":
        raise LogError(
            f"{log.label}: the log carries no true initial state (no gyrodrift.scenario metadata or true "
            "attitude columns, or no site); use --initial alignment (or give the initial state)"
        )
    return found


def _aligned_start(log: ImuLog, settings: NavSettings, timeline: Timeline) -> tuple[InitialState, NavSettings]:
    """Align the first ``timeline.align_h`` hours of `log`: the state at the end of the alignment, and `settings`
    with the alignment's x/y gyro and accelerometer bias estimates added to the given ones."""
    if settings.hours is not None:  # refuse a navigation the log cannot hold before aligning
        log.require_duration(
            timeline.log_hours_for(settings.hours) * HOUR,
            f"navigating --hours {settings.hours:g} h after the {timeline.align_h:g} h alignment",
            align_h=timeline.align_h,
        )
    al = align_log(log, timeline=timeline, chunk_samples=settings.chunk_samples, quiet=settings.quiet)
    state = InitialState(
        "alignment",
        al.samples_used,
        al.site.lat_deg,
        al.site.lon_deg,
        al.site.height_m,
        al.pitch_deg,
        al.roll_deg,
        al.yaw_deg,
        [float(v) for v in al.vel_enu_m_s],
    )
    g = settings.gyro_bias_deg_h
    gyro = [g[0] + al.gyro_bias_deg_h[0], g[1] + al.gyro_bias_deg_h[1], g[2]]
    accel = [a + b for a, b in zip(settings.accel_bias_ug, al.accel_bias_ug, strict=True)]
    return state, dataclasses.replace(settings, gyro_bias_deg_h=gyro, accel_bias_ug=accel)


def write_navigation(
    columns: Mapping[str, np.ndarray],
    summary: Mapping[str, Any],
    out: str | os.PathLike[str] | OutputFolder | Stage,
    *,
    plot: bool = False,
) -> Path:
    """Write ``nav.parquet`` (the columns with their declared dtypes, `gyrodrift.ins.nav_columns.nav_table`,
    metadata ``gyrodrift.format = gyrodrift-nav/1``) and ``summary.json`` (and with `plot` ``navigation.png``,
    `gyrodrift.procedure.figures.navigation_figure`) into `out` as one set (`gyrodrift.files.atomic.staged`);
    return the folder."""
    table = nav_table(columns).replace_schema_metadata(
        {"gyrodrift.format": NAV_FORMAT, "gyrodrift.imu": str(summary.get("imu"))}
    )
    json.dumps(summary, allow_nan=False)  # fail before writing either file
    with staged(out, "navigate", nav_files(plot)) as stage:
        pq.write_table(table, stage.file("nav.parquet"), **PARQUET_OPTIONS)  # no dictionaries: 4x faster
        write_json(dict(summary), stage.file("summary.json"))
        if plot:
            save_png(navigation_figure(columns, summary), stage.file(NAV_PLOT))
    return stage.folder
