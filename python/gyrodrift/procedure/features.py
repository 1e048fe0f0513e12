"""Model inputs of one run: the latitude at the 12th hour of free navigation and the temperature over it.

After alignment (``Timeline.align_h``, 4 h), the log is navigated ``Timeline.features_h`` (12 h) with the
alignment's x/y gyro and accelerometer biases compensated and the z gyro NOT compensated. The features are
the latitude at navigation hour 12 (exact state after the sample at 12 h), the hourly latitude error curve
(hours 0-12, computed minus true, arcsec), and the system temperature over the same 12 h: at the first and
the last navigation sample, the lowest and the highest. The 12 h curve fit (`gyrodrift.learn.curve_fit`) of the
same navigation's latitude and longitude error curves (every 60 s) gives ``drift_curvefit_deg_h`` and its
1-sigma ``drift_curvefit_std_deg_h``. The 16 h smoother (`gyrodrift.procedure.smoother`, one more read of the
same 16 h) gives ``drift_smoother_deg_h`` and its 1-sigma ``drift_smoother_std_deg_h`` and, under its thermal
model, its thermal coefficient k_z, the k_z 1-sigma, cov(end drift, k_z) and its prior 1-sigma of k_z
(``SMOOTHER_THERMAL_COLUMNS``, what a fleet prior on k_z needs: `gyrodrift.learn.fleet_prior`).

A row of the run table (`RunFeatures.row`): the columns ``gyrodrift features`` writes
(`gyrodrift.runs.columns.FEATURES_COLUMNS`; the smoother's thermal ones empty under its constant model or without
it) and, when the truth is asked, the ``LABEL_COLUMNS``: ``drift_deg_h``, its 1-sigma ``drift_std_deg_h``
(`gyrodrift.procedure.truth`, found over 72 h in the same first read) and ``label_flagged`` (the label is beyond
the 1 nmi / 72 h budget).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from gyrodrift.errors import OptionError
from gyrodrift.learn.curve_fit import fit_error_curves
from gyrodrift.logs import ImuLog
from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.passes import navigate_after_alignment
from gyrodrift.procedure.results import (
    Alignment,
    NavCurve,
    RunFeatures,
    SmootherEstimate,
    TemperatureStats,
    TrueDrift,
)
from gyrodrift.procedure.smoother import smooth_log
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.procedure.truth import find_true_drift
from gyrodrift.runs.columns import FLAG_COLUMNS, OPTIONAL_COLUMNS
from gyrodrift.runs.table import RunTable
from gyrodrift.units import HOUR

__all__ = ["extract_features", "features_run_table"]


def _from_curve(
    log: ImuLog,
    curve: NavCurve,
    temp: TemperatureStats,
    hours: float,
    alignment: Alignment,
    truth: TrueDrift | None,
    lat0_deg: float | None,
    smoothed: SmootherEstimate | None,
) -> RunFeatures:
    k = int(round(hours))
    if abs(hours - k) > 1e-9 or len(curve.hourly_lat_deg) <= k:
        raise OptionError(f"{log.label}: the features need whole hours of navigation, got {hours!r}")
    lat = float(curve.hourly_lat_deg[k])
    lat0 = float(alignment.site.lat_deg if lat0_deg is None else lat0_deg)
    cf = fit_error_curves(curve.t_h * HOUR, curve.lat_err_arcsec, curve.lon_err_arcsec, lat0, hours=hours)
    return RunFeatures(
        run=log.name,
        lat_deg=lat,
        lat0_deg=lat0,
        lat_err_curve_arcsec=(np.asarray(curve.hourly_lat_deg[: k + 1]) - lat0) * 3600.0,
        temp_start_c=temp.start_c,
        temp_end_c=temp.end_c,
        temp_min_c=temp.min_c,
        temp_max_c=temp.max_c,
        drift_deg_h=math.nan if truth is None else truth.drift_deg_h,
        hours=float(hours),
        alignment=alignment,
        truth=truth,
        drift_curvefit_deg_h=cf.drift_deg_h,
        drift_curvefit_std_deg_h=cf.drift_std_deg_h,
        drift_smoother_deg_h=math.nan if smoothed is None else smoothed.navigation_drift_deg_h,
        drift_smoother_std_deg_h=math.nan if smoothed is None else smoothed.navigation_drift_std_deg_h,
        smoother=smoothed,
        **({} if smoothed is None else smoothed.thermal_columns()),
        drift_std_deg_h=math.nan if truth is None else truth.drift_std_deg_h,
        label_flagged=False if truth is None else truth.flagged,
    )


def extract_features(
    log: ImuLog,
    *,
    timeline: Timeline = DEFAULT_TIMELINE,
    with_truth: bool = False,
    criterion: str = "final",
    lat0_deg: float | None = None,
    alignment: Alignment | None = None,
    smoother: bool = True,
    noise: SensorNoise | None = None,
    truth_options: Mapping[str, Any] | None = None,
    chunk_samples: int = 100_000,
    quiet: bool = True,
) -> RunFeatures:
    """Align, navigate 12 h without z compensation, and extract the features of the run.

    Parameters
    ----------
    log : ImuLog
        Opened log with a known site; at least ``align_h + features_h`` (16 h) long, or
        ``align_h + truth_h`` (76 h) with `with_truth`.
    timeline : Timeline
    with_truth : bool
        Also find the true drift (`find_true_drift`, over ``truth_h``); its first read gives the features.
    criterion : {"final", "rms", "max"}
        Criterion of the true drift.
    lat0_deg : float, optional
        True latitude written to the table (default: the site's).
    alignment : Alignment, optional
        Reuse an alignment of this log.
    smoother : bool
        Also run the 16 h smoother (`smooth_log`, one more read of the first 16 h).
    noise : SensorNoise, optional
        Noise model of the smoother and of the truth's label sigma (default: measured from the log).
    truth_options : mapping, optional
        More keywords of `find_true_drift` with `with_truth` (``trial_deg_h``, ``verify``, ``threads``, ...).
    chunk_samples, quiet
        Read size and progress switch.

    Returns
    -------
    RunFeatures
    """
    hours = timeline.features_h
    log.require_duration(
        timeline.log_hours_for(hours) * HOUR,
        f"extracting the features ({timeline.align_h:g} h alignment + {hours:g} h navigation)",
    )
    smoothed = (
        smooth_log(log, timeline=timeline, noise=noise, chunk_samples=chunk_samples, quiet=quiet) if smoother else None
    )
    if with_truth:
        log.require_duration(  # checked here: features have no --hours to offer as a fix
            timeline.log_hours_for(timeline.truth_h) * HOUR,
            f"--with-truth (the true drift: {timeline.align_h:g} h alignment + {timeline.truth_h:g} h navigation)",
        )
        truth = find_true_drift(
            log,
            criterion=criterion,
            timeline=timeline,
            alignment=alignment,
            temperature_hours=hours,
            noise=noise,
            chunk_samples=chunk_samples,
            quiet=quiet,
            **dict(truth_options or {}),
        )
        assert truth.base is not None and truth.alignment is not None  # find_true_drift always sets them
        return _from_curve(log, truth.base, truth.temperature, hours, truth.alignment, truth, lat0_deg, smoothed)
    if alignment is None:
        alignment = align_log(log, timeline=timeline, chunk_samples=chunk_samples, quiet=quiet)
    res = navigate_after_alignment(
        log, alignment, [0.0], hours, temperature_hours=hours, chunk_samples=chunk_samples, quiet=quiet, desc="features"
    )
    assert res.temperature is not None  # asked for (temperature_hours)
    return _from_curve(log, res.curves[0], res.temperature, hours, alignment, None, lat0_deg, smoothed)


def features_run_table(features: list[RunFeatures], source: str = "<features>") -> RunTable:
    """The features as a `gyrodrift.runs.table.RunTable` (what `DriftModel.predict` and `fit_drift_model` take)."""
    return RunTable(
        run=np.array([f.run for f in features], dtype=object),
        lat_deg=np.array([f.lat_deg for f in features], dtype=float),
        lat0_deg=np.array([f.lat0_deg for f in features], dtype=float),
        temp_min_c=np.array([f.temp_min_c for f in features], dtype=float),
        temp_max_c=np.array([f.temp_max_c for f in features], dtype=float),
        drift_deg_h=np.array([f.drift_deg_h for f in features], dtype=float),
        source=source,
        extra={  # a flag is known only with the truth
            name: np.array([float(f.column(name)) for f in features])
            for name in OPTIONAL_COLUMNS
            if name not in FLAG_COLUMNS or all(f.truth is not None for f in features)
        },
    )
