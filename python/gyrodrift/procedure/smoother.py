"""The 16 h smoother: the axial drift of a run from all of its alignment and navigation hours, with its 1-sigma.

A forward Kalman filter and a Rauch-Tung-Striebel smoother in the Rust core (`_core.Smoother`, gyrodrift-core
`smoother`; equations in docs/identification.md) run over the log from its first sample to the end of the
features window (``Timeline.align_h + Timeline.features_h``, 16 h by default): coarse alignment, then the zero
velocity and the known static position as measurements every 10 s with the table turning. Its z-gyro estimate
uses every sample the identification may use, and its 1-sigma is the Cramer-Rao line of the linear-Gaussian
error model: no method identifying the drift from these 16 h can do better on average.

The noise model (`SensorNoise`) is given (a scenario's or `gyrodrift allan`'s ``[gyro]``/``[accel]`` keys) or
measured from the log (ARW and VRW from the fourth differences of the increments; no bias drift, so the 1-sigma
leaves out a bias instability the sensor has: `SensorNoise.white_only_note`, which `identify` prints).

A Gauss-Markov bias (``bias_instability_deg_h``) is three more states; the drift carried into navigation leaves
its end value out (it forgets that value within its correlation time, so its mean over a mission of many
correlation times is near zero), and the history is the total. On the README tour's INS (0.001 deg/h, 1 h) the
carried drift's 1-sigma is calibrated when the noise is given and half the error when it is measured from the log
(docs/studies/2026-11-27-smoother-bias-instability.md).

Thermal model: when the log has a temperature column the z drift is modelled as eps_z + k_z (T - T_ref), k_z a
random constant [deg/h/degC] and T the log's temperature (T_ref: the temperature at the end of the coarse
alignment). The reported drift carried into navigation (`SmootherEstimate.navigation_drift_deg_h`) is then the
drift at the end of the span, eps_z + k_z (T_end - T_ref), with its 1-sigma from the joint covariance, as long as
the temperature spanned at least ``thermal_min_range_c`` (0.5 degC) after the coarse alignment; otherwise, and
without a temperature column or with ``thermal=False``, the constant-drift model's estimate (``model`` says which).
The constant-drift estimate is always reported too (``drift_deg_h``: the thermal state conditioned on k_z = 0,
exactly the posterior of the model without it).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from gyrodrift.learn.fleet_prior import pooled_coefficient_prior
from gyrodrift.logs import ImuLog, LogError
from gyrodrift.procedure.noise import SensorNoise, estimate_white_noise
from gyrodrift.procedure.results import SmootherEstimate
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.progress import progress
from gyrodrift.units import ARCSEC, DEG_PER_H, HOUR, MICRO_G

__all__ = ["smooth_log", "fleet_coefficient_prior"]


def smooth_log(
    log: ImuLog,
    *,
    timeline: Timeline = DEFAULT_TIMELINE,
    noise: SensorNoise | Mapping[str, Any] | None = None,
    hours: float | None = None,
    options: Mapping[str, Any] | None = None,
    thermal: bool | None = None,
    chunk_samples: int = 100_000,
    quiet: bool = True,
) -> SmootherEstimate:
    """Estimate the axial drift of `log` with the full-information smoother.

    Parameters
    ----------
    log : ImuLog
        Opened log with a known site, at least `hours` long.
    timeline : Timeline
        ``coarse_s`` and the default span ``align_h + features_h`` (16 h).
    noise : SensorNoise or mapping, optional
        The noise model (`SensorNoise.from_block` keys); default: ARW and VRW measured from the log's first hour.
        ARW and VRW are floored at `gyrodrift.procedure.noise.NOISE_FLOOR` (a filter needs some process noise).
    hours : float, optional
        Span from the first sample [h] (default ``timeline.align_h + timeline.features_h``).
    options : mapping, optional
        Other SI keywords of `_core.SmootherConfig` (``update_s``, priors, measurement sigmas, and for the thermal
        model ``thermal_sigma_rad_s_per_c`` (prior 1-sigma of k_z, default 0.01 deg/h/degC), ``temp_ref_c``,
        ``thermal_min_range_c``).
    thermal : bool, optional
        The thermal state k_z (module docstring). Default: on when the log has a temperature column (the thermal
        model is then reported when the temperature varied); ``True`` without a column raises `LogError`.
    chunk_samples, quiet
        Read size and progress switch.

    Returns
    -------
    SmootherEstimate
    """
    from gyrodrift import _core

    if log.site is None:
        raise LogError(f"{log.label}: the log carries no site; give its latitude (--lat0-deg / site=)")
    span_h = timeline.align_h + timeline.features_h if hours is None else float(hours)
    log.require_duration(span_h * HOUR, f"the smoother ({span_h:g} h)")
    if noise is None:
        model = estimate_white_noise(log, chunk_samples=chunk_samples)
    elif isinstance(noise, SensorNoise):
        model = noise
    else:
        model = SensorNoise.from_block(noise)
    used = model.floored()
    if thermal is None:
        thermal = log.has_temperature
    elif thermal:
        log.require_temperature("the smoother's thermal model")
    site = log.site
    config: dict[str, Any] = {
        **site.core_position(),
        "rate_hz": log.rate_hz,
        "coarse_s": float(timeline.coarse_s),
        "span_s": span_h * HOUR,
        **used.core_keywords(),
        "thermal": bool(thermal),
    }
    config.update(dict(options or {}))
    with log.core_errors():  # the core's refusals name the log
        sm_config = _core.SmootherConfig(**config)
        sm = _core.Smoother(sm_config)
        with progress(int(sm.n_samples), f"smooth {log.name}", quiet) as bar:
            for chunk in log.chunks(chunk_samples, stop=int(sm.n_samples)):
                temp = np.ascontiguousarray(chunk.temp_c, dtype=float) if thermal and chunk.temp_c is not None else None
                k = int(sm.process(np.ascontiguousarray(chunk.dtheta_rad), np.ascontiguousarray(chunk.dv_m_s), temp))
                bar.update(k)
                if sm.done:
                    break
        r = sm.result()

    def vec(key: str, scale: float) -> tuple[float, float, float]:
        v = np.asarray(r[key], dtype=float).reshape(3) / scale
        return (float(v[0]), float(v[1]), float(v[2]))

    return SmootherEstimate(
        run=log.name,
        span_h=span_h,
        drift_deg_h=float(r["drift_rad_s"]) / DEG_PER_H,
        drift_std_deg_h=float(r["drift_std_rad_s"]) / DEG_PER_H,
        drift_end_deg_h=float(r["drift_end_rad_s"]) / DEG_PER_H,
        drift_end_std_deg_h=float(r["drift_end_std_rad_s"]) / DEG_PER_H,
        model="thermal" if r["thermal"] else "constant",
        drift_ref_deg_h=float(r["drift_ref_rad_s"]) / DEG_PER_H,
        drift_ref_std_deg_h=float(r["drift_ref_std_rad_s"]) / DEG_PER_H,
        thermal_coeff_deg_h_per_c=float(r["thermal_coeff_rad_s_per_c"]) / DEG_PER_H,
        thermal_coeff_std_deg_h_per_c=float(r["thermal_coeff_std_rad_s_per_c"]) / DEG_PER_H,
        temp_ref_c=float(r["temp_ref_c"]),
        temp_end_c=float(r["temp_end_c"]),
        temp_range_c=float(r["temp_range_c"]),
        end_coeff_cov=float(r["end_coeff_cov_rad2_s2_per_c"]) / DEG_PER_H**2,
        thermal_prior_std_deg_h_per_c=(
            float(sm_config.thermal_sigma_rad_s_per_c) / DEG_PER_H if sm_config.thermal else math.nan
        ),
        gyro_bias_deg_h=vec("gyro_bias_rad_s", DEG_PER_H),
        gyro_bias_std_deg_h=vec("gyro_bias_std_rad_s", DEG_PER_H),
        accel_bias_ug=vec("accel_bias_m_s2", MICRO_G),
        accel_bias_std_ug=vec("accel_bias_std_m_s2", MICRO_G),
        hist_t_h=np.asarray(r["hist_t_s"], dtype=float) / HOUR,
        hist_drift_deg_h=np.asarray(r["hist_drift_rad_s"], dtype=float) / DEG_PER_H,
        hist_drift_std_deg_h=np.asarray(r["hist_drift_std_rad_s"], dtype=float) / DEG_PER_H,
        hist_filter_std_deg_h=np.asarray(r["hist_filter_std_rad_s"], dtype=float) / DEG_PER_H,
        noise=used,
        max_attitude_correction_arcsec=float(r["max_attitude_correction_rad"]) / ARCSEC,
        max_velocity_correction_m_s=float(r["max_velocity_correction_m_s"]),
        max_position_error_m=float(r["max_position_error_m"]),
        updates=int(r["updates"]),
    )


def fleet_coefficient_prior(estimates: Iterable[SmootherEstimate]) -> tuple[float, float]:
    """A prior for one more unit's thermal coefficient k_z from a fleet's smoother estimates [deg/h/degC].

    The random-effects pooled mean of the runs' k_z (weights 1 / sigma_i^2; DerSimonian-Laird between-unit
    variance tau^2 = max(0, (Q - (n - 1)) / (sum w - sum w^2 / sum w)), Q the weighted squared deviations) and
    the 1-sigma of a new unit's k_z about it, ``sqrt(1 / sum w + tau^2)`` (the pooled mean's own uncertainty plus
    the unit-to-unit spread). Runs without the thermal model are left out; `InputError` with fewer than two.
    Use with `SmootherEstimate.end_drift_with_coefficient_prior`.
    """
    thermal = [e for e in estimates if e.model == "thermal"]
    return pooled_coefficient_prior(
        [e.thermal_coeff_deg_h_per_c for e in thermal], [e.thermal_coeff_std_deg_h_per_c for e in thermal]
    )
