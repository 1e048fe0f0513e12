"""Navigation passes after alignment: several trial z-drifts navigated side by side in one read of the log.

Every pass starts at the end of alignment (sample ``alignment.samples_used``) from the aligned attitude and
velocity at the known static site, with the alignment's x/y gyro and x/y/z accelerometer bias estimates
subtracted, and the pass's own z-gyro drift (deg/h) subtracted from the z gyro (measured - estimate): a constant, or a
`gyrodrift.drift_law.DriftLaw` evaluated sample by sample on the log's temperature (`gyrodrift.ins.compensation`). All
navigators of a call see the same chunks (`gyrodrift.ins.stream.run_navigators`, the engine `navigate` uses
too), so N trial drifts cost one read of the log.

Errors are computed minus true against the static site: north = dlat R_M, east = dlon R_N cos(lat),
position error = hypot(north, east) / 1852 m (`gyrodrift.ins.nav_errors.position_errors`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from gyrodrift import _core
from gyrodrift.drift_law import DriftLaw
from gyrodrift.errors import OptionError
from gyrodrift.ins.compensation import axial_bias
from gyrodrift.ins.nav_errors import position_errors
from gyrodrift.ins.navigate import vertical_reference
from gyrodrift.ins.stream import run_navigators
from gyrodrift.logs import ImuLog, LogError
from gyrodrift.procedure.results import Alignment, NavCurve, PassResult, TemperatureStats
from gyrodrift.units import DEG, HOUR

__all__ = ["navigate_after_alignment", "check_navigation_hours"]


def check_navigation_hours(hours: float, decimation_s: float) -> float:
    """`hours` [h] as a float if it is a finite navigation length of at least one output step (`decimation_s`
    [s]); `OptionError` naming ``--hours`` otherwise (NaN, inf, 1e308 h, 1e-9 h)."""
    try:
        h = float(hours)
    except (TypeError, ValueError):
        raise OptionError(f"--hours: expected a number of hours, got {hours!r}") from None
    if not math.isfinite(h) or not h > 0:
        raise OptionError(f"--hours: expected a positive finite number of hours, got {hours!r}")
    if h * HOUR < decimation_s:
        raise OptionError(
            f"--hours {h:g}: shorter than one output step of the error curves ({decimation_s:g} s); nothing would be "
            "navigated"
        )
    if h > 1e6:
        raise OptionError(f"--hours {h:g}: more than a million hours; no log is that long")
    return h


def navigate_after_alignment(
    log: ImuLog,
    alignment: Alignment,
    drifts_deg_h: Sequence[float | DriftLaw],
    hours: float,
    *,
    decimation_s: float = 60.0,
    temperature_hours: float | None = None,
    chunk_samples: int = 100_000,
    threads: int | None = None,
    quiet: bool = True,
    desc: str = "navigate",
    reference: Any = None,
) -> PassResult:
    """Navigate `hours` after the alignment once per z drift in `drifts_deg_h`, reading the log once.

    Parameters
    ----------
    log : ImuLog
        The log that was aligned (its site is the truth).
    alignment : Alignment
        Result of `align_log` on that log.
    drifts_deg_h : sequence of float or DriftLaw
        The z-gyro drift subtracted in each navigator: a constant [deg/h] (0 = uncompensated), or a drift law (its
        ``eps_ref_deg_h`` the curve's ``drift_deg_h``; a law reading the temperature needs the log's ``temp_c``).
    hours : float
        Navigation length [h] after the alignment; the log must hold ``align + hours``.
    decimation_s : float
        Interval of the error curves [s] (rounded to whole samples).
    temperature_hours : float, optional
        Collect temperature statistics over the first `temperature_hours` of navigation.
    threads : int, optional
        Threads navigating the passes of one chunk side by side (default: one per pass, at most the number of
        CPUs, and the log read ahead on one more thread; 1 = everything on the calling thread: passes in turn,
        no read-ahead). Results do not depend on it: each navigator sees the same samples in order.
    chunk_samples, quiet, desc
        Chunking of the read, progress bar switch and label.
    reference : gyrodrift.ins.track.ReferenceTrack, optional
        Moving base: the true track (log time base) the errors are computed against instead of the static site;
        it must cover the navigation (`TrackError` otherwise).

    Returns
    -------
    PassResult
    """
    rate = log.rate_hz
    start = alignment.samples_used
    hours = check_navigation_hours(hours, decimation_s)
    n_nav = log.samples_for(hours * HOUR)
    stop = start + n_nav
    if log.n_samples < stop:
        raise LogError(
            f"{log.label}: the log lasts {log.duration_s / HOUR:.3f} h; {hours:g} h of navigation after the "
            f"{start / rate / HOUR:g} h alignment take at least {stop / rate / HOUR:g} h"
        )
    dec = max(1, int(round(decimation_s * rate)))
    if n_nav < dec:
        raise OptionError(
            f"--hours {hours:g}: {n_nav} sample(s) of navigation, shorter than one output step "
            f"({dec / rate:g} s); the curves would be empty"
        )
    n_temp = None
    if temperature_hours is not None:
        log.require_temperature("the temperature statistics")
        n_temp = log.samples_for(temperature_hours * HOUR)
    temp = {"start": np.nan, "end": np.nan, "min": np.inf, "max": -np.inf}

    def temperature(piece, done: int) -> None:
        if n_temp is None or done >= n_temp:
            return
        tc = piece.temp_c[: n_temp - done]
        if done == 0:
            temp["start"] = float(tc[0])
        temp["min"] = min(temp["min"], float(tc.min()))
        temp["max"] = max(temp["max"], float(tc.max()))
        temp["end"] = float(tc[-1])

    # The vertical channel as `navigate` chooses it: damped towards the log's ref_height_m column, else towards
    # the reference track's height (moving base); held fixed on a static base without a height column.
    channel = "damped" if log.has_reference_height or reference is not None else "fixed"
    heights, vertical_ref = vertical_reference(channel, log, reference)
    laws = [d if isinstance(d, DriftLaw) else DriftLaw.constant(float(d)) for d in drifts_deg_h]
    navs = []
    for law in laws:
        nav = _core.Navigator(alignment.navigator_config(vertical=channel))
        nav.set_gyro_bias(alignment.gyro_compensation_rad_s(law.eps_ref_deg_h))
        nav.set_accel_bias(alignment.accel_compensation_m_s2())
        navs.append(nav)
    # The alignment estimates no z gyro bias: a law's per-sample bias is the law alone.
    biases = [axial_bias(law, log) for law in laws]
    if reference is not None:
        reference.require_cover(start / rate, stop / rate, f"navigating {log.label} after the alignment")
    tracks = run_navigators(
        log,
        navs,
        n_samples=n_nav,
        start=start,
        decimation=dec,
        keys=("lat_rad", "lon_rad"),
        observe=temperature,
        reference=heights,
        axial_bias=None if all(b is None for b in biases) else biases,
        threads=threads,
        chunk_samples=chunk_samples,
        quiet=quiet,
        desc=f"{desc} {log.name}",
    )
    t_h = np.arange(1, n_nav // dec + 1) * dec / rate / HOUR
    exact_end = n_nav % dec != 0  # the curves always end with the exact last state (the "final" criterion's point)
    if exact_end:
        t_h = np.append(t_h, n_nav / rate / HOUR)
    hours_done = np.arange(0, len(tracks[0].hourly) + 1, dtype=float) if tracks else np.zeros(1)
    if reference is None:
        lat0, lon0 = alignment.site.lat_rad, alignment.site.lon_rad
        hourly_true = np.full(len(hours_done), lat0)
    else:
        lat0, lon0, _ = reference.at(start / rate + t_h * HOUR)
        hourly_true = reference.at(start / rate + hours_done * HOUR)[0]
    curves = []
    for law, track in zip(laws, tracks, strict=True):
        lat, lon = track.kept["lat_rad"], track.kept["lon_rad"]
        if exact_end:
            lat = np.append(lat, float(track.final["lat_rad"]))
            lon = np.append(lon, float(track.final["lon_rad"]))
        pe = position_errors(lat, lon, lat0, lon0)
        h = np.array([hourly_true[0]] + [float(st["lat_rad"]) for _, st in track.hourly])
        curves.append(
            NavCurve(
                drift_deg_h=law.eps_ref_deg_h,
                t_h=t_h,
                north_m=pe["north_err_m"],
                east_m=pe["east_err_m"],
                lat_err_arcsec=pe["lat_err_arcsec"],
                lon_err_arcsec=pe["lon_err_arcsec"],
                hourly_lat_deg=np.rad2deg(h),
                hourly_lat_err_arcsec=(h - hourly_true[: len(h)]) / DEG * 3600.0,
            )
        )
    temperature_stats = None
    if temperature_hours is not None:
        temperature_stats = TemperatureStats(
            float(temperature_hours), temp["start"], temp["end"], float(temp["min"]), float(temp["max"])
        )
    return PassResult(
        curves=curves,
        temperature=temperature_stats,
        hours=float(hours),
        vertical=channel,
        vertical_reference=vertical_ref,
    )
