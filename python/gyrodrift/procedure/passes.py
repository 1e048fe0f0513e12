"""Navigation passes after alignment: several trial z-drifts navigated side by side in one read of the log.

Every pass starts at the end of alignment (sample ``alignment.samples_used``) from the aligned attitude and
velocity at the known static site, with the alignment's x/y gyro and x/y/z accelerometer bias estimates
subtracted, and the pass's own z-gyro drift (deg/h) subtracted from the z gyro (measured - estimate). All
navigators of a call see the same chunks, so N trial drifts cost one read of the log.

Errors are computed minus true against the static site: north = dlat R_M, east = dlon R_N cos(lat),
position error = hypot(north, east) / 1852 m (`gyrodrift.ins.nav_errors.position_errors`).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from gyrodrift.earth import NMI_M
from gyrodrift.ins.nav_errors import position_errors
from gyrodrift.logs import ImuLog, LogError
from gyrodrift.procedure.align import Alignment
from gyrodrift.progress import progress
from gyrodrift.units import DEG, HOUR

__all__ = ["NavCurve", "TemperatureStats", "PassResult", "navigate_after_alignment"]


@dataclass(frozen=True)
class NavCurve:
    """Position error of one navigation pass over time (computed minus true).

    Attributes
    ----------
    drift_deg_h : float
        z-gyro drift subtracted in this pass [deg/h].
    t_h : ndarray (m,)
        Time since the start of navigation (end of alignment) [h], every ``decimation_s``, and the exact end
        of the pass as the last value (also when it is not a multiple of ``decimation_s``).
    north_m, east_m : ndarray (m,)
        North and east position errors [m].
    lat_err_arcsec, lon_err_arcsec : ndarray (m,)
        Latitude and longitude errors [arcsec].
    hourly_lat_deg, hourly_lat_err_arcsec : ndarray (h + 1,)
        Latitude and its error at whole navigation hours 0, 1, ..., exact (not decimated).
    """

    drift_deg_h: float
    t_h: np.ndarray = field(repr=False)
    north_m: np.ndarray = field(repr=False)
    east_m: np.ndarray = field(repr=False)
    lat_err_arcsec: np.ndarray = field(repr=False)
    lon_err_arcsec: np.ndarray = field(repr=False)
    hourly_lat_deg: np.ndarray = field(repr=False)
    hourly_lat_err_arcsec: np.ndarray = field(repr=False)

    @property
    def pos_err_nmi(self) -> np.ndarray:
        """Horizontal position error [nmi, 1852 m]."""
        return np.hypot(self.north_m, self.east_m) / NMI_M

    @property
    def final_nmi(self) -> float:
        """Position error at the end of the pass [nmi]."""
        return float(self.pos_err_nmi[-1])

    @property
    def max_nmi(self) -> float:
        """Largest position error over the pass [nmi]."""
        return float(np.max(self.pos_err_nmi))


@dataclass(frozen=True)
class TemperatureStats:
    """System temperature over the first ``hours`` of navigation [deg C]: at the first and last sample,
    lowest and highest."""

    hours: float
    start_c: float
    end_c: float
    min_c: float
    max_c: float


@dataclass(frozen=True)
class PassResult:
    """Curves of the navigators of one read (in the order of the drifts asked) and the temperature."""

    curves: list[NavCurve]
    temperature: TemperatureStats | None
    hours: float


def navigate_after_alignment(
    log: ImuLog,
    alignment: Alignment,
    drifts_deg_h: Sequence[float],
    hours: float,
    *,
    decimation_s: float = 60.0,
    temperature_hours: float | None = None,
    chunk_samples: int = 100_000,
    threads: int | None = None,
    quiet: bool = True,
    desc: str = "navigate",
) -> PassResult:
    """Navigate `hours` after the alignment once per z drift in `drifts_deg_h`, reading the log once.

    Parameters
    ----------
    log : ImuLog
        The log that was aligned (its site is the truth).
    alignment : Alignment
        Result of `align_log` on that log.
    drifts_deg_h : sequence of float
        z-gyro drifts [deg/h] subtracted in each navigator (0 = uncompensated).
    hours : float
        Navigation length [h] after the alignment; the log must hold ``align + hours``.
    decimation_s : float
        Interval of the error curves [s] (rounded to whole samples).
    temperature_hours : float, optional
        Collect temperature statistics over the first `temperature_hours` of navigation.
    threads : int, optional
        Threads navigating the passes of one chunk side by side (default: one per pass, at most the number of
        CPUs; 1 = in turn). Results do not depend on it: each navigator sees the same samples in order.
    chunk_samples, quiet, desc
        Chunking of the read, progress bar switch and label.

    Returns
    -------
    PassResult
    """
    from gyrodrift import _core

    rate = log.rate_hz
    start = alignment.samples_used
    n_nav = log.samples_for(hours * HOUR)
    stop = start + n_nav
    if log.n_samples < stop:
        raise LogError(
            f"{log.path}: the log lasts {log.duration_s / HOUR:.3f} h; {hours:g} h of navigation after the "
            f"{start / rate / HOUR:g} h alignment take at least {stop / rate / HOUR:g} h"
        )
    per_hour = log.samples_for(HOUR)
    dec = max(1, int(round(decimation_s * rate)))
    n_temp = None if temperature_hours is None else log.samples_for(temperature_hours * HOUR)

    navs = []
    for d in drifts_deg_h:
        nav = _core.Navigator(alignment.navigator_config())
        nav.set_gyro_bias(alignment.gyro_compensation_rad_s(float(d)))
        nav.set_accel_bias(alignment.accel_compensation_m_s2())
        navs.append(nav)
    lat_parts: list[list[np.ndarray]] = [[] for _ in navs]
    lon_parts: list[list[np.ndarray]] = [[] for _ in navs]
    hourly: list[list[float]] = [[float(alignment.site.lat_deg * DEG)] for _ in navs]
    t_min = np.inf
    t_max = -np.inf
    t_start = t_end = np.nan
    done = 0
    n_threads = min(len(navs), os.cpu_count() or 1) if threads is None else max(1, min(int(threads), len(navs)))
    pool = ThreadPoolExecutor(max_workers=n_threads) if n_threads > 1 else None
    with progress(n_nav, f"{desc} {log.name}", quiet) as bar, pool or contextlib.nullcontext():
        for chunk in log.chunks(chunk_samples, stop=stop):
            end_idx = chunk.first_index + len(chunk)
            if end_idx <= start:
                continue
            if chunk.first_index < start:
                chunk = chunk.slice(start - chunk.first_index, len(chunk))
            if n_temp is not None and done < n_temp:
                tc = chunk.temp_c[: n_temp - done]
                if done == 0:
                    t_start = float(tc[0])
                t_min = min(t_min, float(tc.min()))
                t_max = max(t_max, float(tc.max()))
                t_end = float(tc[-1])
            a = 0
            while a < len(chunk):
                b = min(len(chunk), a + per_hour - (done % per_hour))
                dth = np.ascontiguousarray(chunk.dtheta_rad[a:b])
                dv = np.ascontiguousarray(chunk.dv_m_s[a:b])
                if pool is None:
                    outs = [nav.process(dth, dv, dec) for nav in navs]
                else:  # the core releases the GIL: the navigators of one segment run side by side
                    outs = list(pool.map(lambda nav, dth=dth, dv=dv: nav.process(dth, dv, dec), navs))
                for i, out in enumerate(outs):
                    if len(out["lat_rad"]):
                        lat_parts[i].append(np.asarray(out["lat_rad"], dtype=float))
                        lon_parts[i].append(np.asarray(out["lon_rad"], dtype=float))
                done += b - a
                if done % per_hour == 0:
                    for i, nav in enumerate(navs):
                        hourly[i].append(float(nav.state()["lat_rad"]))
                a = b
            bar.update(len(chunk))
    lat0 = alignment.site.lat_deg * DEG
    lon0 = alignment.site.lon_deg * DEG
    t_h = np.arange(1, done // dec + 1) * dec / rate / HOUR
    if done % dec:  # the curves always end with the exact last state (the "final" criterion's point)
        t_h = np.append(t_h, done / rate / HOUR)
        for i, nav in enumerate(navs):
            st = nav.state()
            lat_parts[i].append(np.array([float(st["lat_rad"])]))
            lon_parts[i].append(np.array([float(st["lon_rad"])]))
    curves = []
    for i, d in enumerate(drifts_deg_h):
        lat = np.concatenate(lat_parts[i]) if lat_parts[i] else np.zeros(0)
        lon = np.concatenate(lon_parts[i]) if lon_parts[i] else np.zeros(0)
        pe = position_errors(lat, lon, lat0, lon0)
        h = np.asarray(hourly[i])
        curves.append(
            NavCurve(
                drift_deg_h=float(d),
                t_h=t_h,
                north_m=pe["north_err_m"],
                east_m=pe["east_err_m"],
                lat_err_arcsec=pe["lat_err_arcsec"],
                lon_err_arcsec=pe["lon_err_arcsec"],
                hourly_lat_deg=np.rad2deg(h),
                hourly_lat_err_arcsec=(h - lat0) / DEG * 3600.0,
            )
        )
    temperature = None
    if n_temp is not None:
        temperature = TemperatureStats(float(temperature_hours), t_start, t_end, float(t_min), float(t_max))
    return PassResult(curves=curves, temperature=temperature, hours=float(hours))
