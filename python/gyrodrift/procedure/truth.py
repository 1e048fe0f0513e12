"""The "true" axial drift of a run: the z-gyro drift that minimises the 72 h position error after alignment.

The paper finds the training target offline: navigate after alignment without correcting the axial drift,
then simulate the compensation and keep the drift that minimises the position error over 72 h. Here:

1. One read of the log navigates two passes, z drift 0 and a trial value ``trial_deg_h``.
2. The position error is, to first order, linear in the z drift ``d`` subtracted from the gyro:
   ``north(t; d) = north_0(t) + d g_N(t)``, ``east(t; d) = east_0(t) + d g_E(t)`` with
   ``g = (curve(trial) - curve(0)) / trial`` (north and east separately; their hypot is not linear).
3. The criterion (nmi) is minimised over ``d``:

   * ``final``: the position error at the last navigated sample (hour 72),
   * ``rms``: root mean square of the position error over the samples of hours 0-72,
   * ``max``: the largest position error over hours 0-72.

   ``final`` and ``rms`` are quadratic in ``d`` once squared: closed form
   ``d* = -sum(N0 gN + E0 gE) / sum(gN^2 + gE^2)`` (over the last sample or all samples). ``max`` is convex
   in ``d`` (a maximum of norms of affine functions): `scipy.optimize.minimize_scalar` (bounded).
4. Verification: one more read navigates ``d*`` and ``d* -+ step_deg_h`` (default 0.0002 deg/h); the
   criterion is reported at the three, and ``verified`` says the navigated ``d*`` is no worse than both
   neighbours. The three also re-linearise the error at ``d*`` (central difference); if that moves the
   optimum by more than ``tolerance_deg_h`` (1e-7 deg/h), ``d*`` moves and is verified again (at most
   ``max_refinements`` = 3 times). At 0.003 deg/h the first linearisation is off by 1e-7 to 2e-6 deg/h and one
   refinement converges (next step < 1e-10 deg/h); at 0.05 deg/h it is off by up to 7e-5 deg/h and one refinement
   still converges. ``verify=False`` skips this read: ``d*`` is then the first linearisation's minimum, exact to
   about 1e-7 deg/h when ``trial_deg_h`` lies within about 5e-4 deg/h of it (the campaigns take the scenario's
   nominal drift as the trial); with the default trial, about 2e-6 deg/h for a drift of 0.003 deg/h.

The drift is the total constant to subtract from the z-gyro output (measured - estimate) [deg/h]; the
alignment's own z estimate plays no part.

Uncertainty of the label: with sensor noise, d* is the constant that best cancels this run's random
walk, not the sensor's drift. Its 1-sigma ``drift_std_deg_h`` comes from a linear covariance analysis of the 72 h
navigation with the core's error model (`_core.label_sigma`, gyrodrift-core ``label::label_sigma``: attitude,
velocity and north/east position errors driven by ARW and VRW over the navigation, and by the z gyro's
Gauss-Markov bias instability and rate random walk when the noise model has them (`SensorNoise`; a noise measured
from the log has none): d* follows their weighted average over the span, which the run's noise-free twin lacks;
the x/y ones are modulated by the table and left out; and by the noise-driven part of the alignment's leftover
attitude and velocity errors (the rest is the same in the run and in its noise-free twin): the core runs the
procedure's fine aligner as the filter it is, by covariance alone, with the table turning (`alignment_geometry`:
a simulated log's scenario, else the default scheme with the alignment's attitude; over headings and turning
schemes the 8 h sigma moves by less than 0.2 %, a table that stands still raises it by 12 %), the planner's pass
(gyrodrift-core ``aligner_covariance``). Their effect on the position error nearly returns to zero after whole
days (72 h: the sigma moves by less than 0.1 %) but not after 8 h, where leaving them out made the sigma 1.4-2
times optimistic (docs/studies/2026-11-27-label-sigma.md). What it describes is
the label minus that of the run's noise-free twin, linear in the noise and blind to the run's deterministic errors
(the drift's temperature law, the biases):
``final``: ``var = g' Cov(e(T)) g / |g|^4`` with g the position response to the drift at hour 72 and e the
position error it does not explain; ``rms``: the same for the sums over the curve points (an accumulator
state); ``max`` has no closed form and takes the ``rms`` value (an approximation). ARW and VRW are measured
from the log's first hour (`gyrodrift.procedure.noise.estimate_white_noise`) unless given. A run is
``flagged`` when that 1-sigma exceeds `label_budget_deg_h`, the drift error that moves the 72 h position by
1 nmi at 45 deg (the latitude where a label is best): near the equator or a pole the 72 h error hardly depends
on the drift, and such a label cannot tell a method within the 1 nmi / 72 h budget from one outside it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from gyrodrift.earth import NMI_M
from gyrodrift.ins.scenario import Scenario
from gyrodrift.logs import ImuLog
from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.noise import SensorNoise, estimate_white_noise
from gyrodrift.procedure.passes import check_navigation_hours, navigate_after_alignment
from gyrodrift.procedure.results import Alignment, PassResult, TrueDrift
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.procedure.truth_law import LawModel, law_basis
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, HOUR

__all__ = [
    "CRITERIA",
    "find_true_drift",
    "criterion_value",
    "minimise_linear_criterion",
    "label_sigma_deg_h",
    "label_budget_deg_h",
    "alignment_geometry",
]

CRITERIA = ("final", "rms", "max")
"""Position-error criteria over the navigation: at its end, root mean square, maximum."""


def criterion_value(north_m: np.ndarray, east_m: np.ndarray, criterion: str) -> np.ndarray:
    """Criterion [nmi] of error curves; the last axis is time (any leading axes are kept)."""
    p2 = np.asarray(north_m) ** 2 + np.asarray(east_m) ** 2
    if criterion == "final":
        return np.sqrt(p2[..., -1]) / NMI_M
    if criterion == "rms":
        return np.sqrt(p2.mean(axis=-1)) / NMI_M
    if criterion == "max":
        return np.sqrt(p2.max(axis=-1)) / NMI_M
    raise ValueError(f"unknown criterion {criterion!r}; expected one of {', '.join(CRITERIA)}")


def minimise_linear_criterion(n0, e0, gn, ge, criterion: str) -> float:
    """The drift d [deg/h] minimising the criterion of ``(n0 + d gn, e0 + d ge)`` (curves in m, g in m/(deg/h))."""
    n0, e0, gn, ge = (np.asarray(a, dtype=float) for a in (n0, e0, gn, ge))
    if criterion not in CRITERIA:
        raise ValueError(f"unknown criterion {criterion!r}; expected one of {', '.join(CRITERIA)}")
    sl = slice(-1, None) if criterion == "final" else slice(None)
    den = float(np.sum(gn[sl] ** 2 + ge[sl] ** 2))
    if not den > 0:
        raise ValueError("the position error does not depend on the z drift (zero sensitivity)")
    d_ls = -float(np.sum(n0[sl] * gn[sl] + e0[sl] * ge[sl])) / den
    if criterion != "max":
        return d_ls

    from scipy.optimize import minimize_scalar  # here: scipy.optimize costs ~0.4 s of every CLI start

    def f(d):
        return float(criterion_value(n0 + d * gn, e0 + d * ge, "max"))

    # Convex in d: bracket generously around the rms optimum (the max optimum is never far from it).
    d_rms = minimise_linear_criterion(n0, e0, gn, ge, "rms")
    half = 0.01 + abs(d_rms)
    res = minimize_scalar(
        f, bounds=(d_rms - half, d_rms + half), method="bounded", options={"xatol": 1e-12, "maxiter": 500}
    )
    return float(res.x)


def label_sigma_deg_h(
    lat_deg: float,
    noise: SensorNoise,
    *,
    criterion: str = "final",
    hours: float = 72.0,
    height_m: float = 0.0,
    att_std_arcsec: tuple[float, float, float] = (0.0, 0.0, 0.0),
    decimation_s: float = 60.0,
    align_h: float = DEFAULT_TIMELINE.align_h,
    coarse_s: float = DEFAULT_TIMELINE.coarse_s,
    geometry: Scenario | None = None,
) -> tuple[float, float]:
    """(1-sigma of the label [deg/h], sensitivity of the final position error [nmi per deg/h]) from the core's
    covariance analysis (module docstring) at latitude `lat_deg` with the noise's ARW and VRW, and its z-gyro bias
    instability and rate random walk if it has them (the rate random walk has walked `align_h` hours when the
    navigation starts). With `geometry` (the run's sample rate, rotation scheme and attitude at table angle zero,
    `alignment_geometry`) the navigation starts from the noise-driven leftovers of the procedure's fine aligner
    (`coarse_s` [s] of coarse alignment, the fine one to `align_h` [h]); None leaves them out."""
    from gyrodrift import _core

    if criterion not in CRITERIA:
        raise ValueError(f"unknown criterion {criterion!r}; expected one of {', '.join(CRITERIA)}")
    navigation = _core.FreeNavigationConfig(
        lat_rad=float(lat_deg) * DEG,
        height_m=float(height_m),
        span_s=float(hours) * HOUR,
        step_s=float(decimation_s),
        gyro_arw_rad_rts=noise.arw_rad_rts,
        accel_vrw_m_s_rts=noise.vrw_m_s_rts,
        att_sigma_rad=[float(a) * ARCSEC for a in att_std_arcsec],
        vel_sigma_m_s=0.0,
    )
    r = _core.label_sigma(
        navigation,
        rms=criterion != "final",
        gyro_bias_instability_rad_s=noise.bias_instability_deg_h * DEG_PER_H,
        gyro_correlation_s=float(noise.correlation_s),
        gyro_rrw_rad_s_rts=noise.rrw_deg_h_rth * DEG_PER_H / math.sqrt(HOUR),
        rrw_start_s=float(align_h) * HOUR,
        alignment=None if geometry is None else geometry.to_core_config(),
        alignment_end_s=float(align_h) * HOUR,
        coarse_s=float(coarse_s),
    )
    return float(r["drift_std_rad_s"]) / DEG_PER_H, float(r["sensitivity_m_per_rad_s"]) * DEG_PER_H / NMI_M


def label_budget_deg_h(hours: float = 72.0, decimation_s: float = 60.0) -> float:
    """The drift error [deg/h] that moves the position at the end of `hours` of navigation by 1 nmi at 45 deg
    latitude (the 1 nmi / 72 h budget where a label is best; the core's error model: 4.6e-4 deg/h for 72 h)."""
    _, sensitivity = label_sigma_deg_h(45.0, SensorNoise(), hours=hours, decimation_s=decimation_s)
    return 1.0 / sensitivity


def alignment_geometry(log: ImuLog, alignment: Alignment) -> Scenario:
    """The run's sample rate, rotation scheme and IMU attitude at table angle zero for the alignment's leftovers in
    the label's sigma: a simulated log's scenario; a recorded one's, the default scheme (reciprocating) with the
    alignment's attitude (module docstring: the sigma hardly depends on them while the table turns)."""
    if log.scenario is not None:
        return log.scenario
    site = alignment.site
    return Scenario.from_dict(
        {
            "site": {"lat_deg": site.lat_deg, "lon_deg": site.lon_deg, "height_m": site.height_m},
            "run": {"rate_hz": float(log.rate_hz)},
            "attitude": {
                "pitch_deg": alignment.pitch_deg,
                "roll_deg": alignment.roll_deg,
                "yaw_deg": alignment.yaw_deg,
            },
        }
    )


def find_true_drift(
    log: ImuLog,
    *,
    criterion: str = "final",
    hours: float | None = None,
    timeline: Timeline = DEFAULT_TIMELINE,
    alignment: Alignment | None = None,
    trial_deg_h: float = 0.001,
    step_deg_h: float = 0.0002,
    grid_half_width_deg_h: float = 0.002,
    grid_points: int = 81,
    tolerance_deg_h: float = 1e-7,
    max_refinements: int = 3,
    decimation_s: float = 60.0,
    temperature_hours: float | None = None,
    noise: SensorNoise | Mapping[str, Any] | None = None,
    verify: bool = True,
    law: bool = True,
    threads: int | None = None,
    chunk_samples: int = 100_000,
    quiet: bool = True,
) -> TrueDrift:
    """Find the z-gyro drift [deg/h] minimising the position-error criterion over `hours` after alignment.

    Parameters
    ----------
    log : ImuLog
        Opened log with a known site, at least ``timeline.align_h + hours`` long.
    criterion : {"final", "rms", "max"}
        See the module docstring.
    hours : float, optional
        Navigation hours after alignment (default ``timeline.truth_h``, 72 h).
    timeline : Timeline
    alignment : Alignment, optional
        Reuse an alignment of this log (else `align_log` is run).
    trial_deg_h : float
        Second linearisation point [deg/h] (the first is 0).
    step_deg_h : float
        Offset of the two verification neighbours [deg/h].
    grid_half_width_deg_h, grid_points : float, int
        The reported criterion curve spans ``d* +- grid_half_width_deg_h`` with `grid_points` values.
    tolerance_deg_h, max_refinements : float, int
        After each verification read the curves are re-linearised at ``d*`` (central difference of the
        neighbours); if the new optimum moves by more than `tolerance_deg_h` [deg/h], ``d*`` moves there and
        is verified again, at most `max_refinements` times (large drifts, where the first linearisation
        from 0 is not exact enough).
    decimation_s : float
        Interval of the error curves [s]; ``rms`` and ``max`` are taken over these samples.
    temperature_hours : float, optional
        Also collect the temperature over the first hours of navigation (the features use 12 h).
    noise : SensorNoise or mapping, optional
        ARW and VRW of the label's covariance analysis (default: measured from the log's first hour).
    verify : bool
        Navigate ``d*`` and its neighbours in a second read (and refine); False: one read, ``d*`` from the first
        linearisation, and ``optimum`` None, ``verify_drift_deg_h`` / ``verify_nmi`` empty, ``verified`` False.
    law : bool
        Also find the best drift law (`gyrodrift.procedure.truth_law`; ``TrueDrift.law``) when the log has a
        temperature: one more navigator in the first read (and in each verification read, the law at its
        optimum); T_ref the temperature at the end of the features window (``timeline.features_h``, at most
        `hours`).
    threads : int, optional
        Threads of each read (`navigate_after_alignment`; 1 = all on the calling thread).
    chunk_samples, quiet
        Read size and progress switch.

    Returns
    -------
    TrueDrift
    """
    if criterion not in CRITERIA:
        raise ValueError(f"unknown criterion {criterion!r}; expected one of {', '.join(CRITERIA)}")
    if not trial_deg_h:
        raise ValueError("trial_deg_h must be non-zero")
    hours = check_navigation_hours(timeline.truth_h if hours is None else hours, decimation_s)
    log.require_duration(
        timeline.log_hours_for(hours) * HOUR,
        f"the true drift ({timeline.align_h:g} h alignment + {hours:g} h navigation)",
        align_h=timeline.align_h,
    )
    if alignment is None:
        alignment = align_log(log, timeline=timeline, chunk_samples=chunk_samples, quiet=quiet)
    law = law and log.has_temperature
    if law and temperature_hours is None:
        temperature_hours = min(float(timeline.features_h), hours)  # T_ref: the end of the features window
    first: PassResult = navigate_after_alignment(
        log,
        alignment,
        [0.0, trial_deg_h, law_basis()] if law else [0.0, trial_deg_h],
        hours,
        decimation_s=decimation_s,
        temperature_hours=temperature_hours,
        threads=threads,
        chunk_samples=chunk_samples,
        quiet=quiet,
        desc="truth pass 1",
    )
    c0, c1 = first.curves[:2]
    gn = (c1.north_m - c0.north_m) / trial_deg_h
    ge = (c1.east_m - c0.east_m) / trial_deg_h
    law_model = None
    if law:
        assert first.temperature is not None  # asked for
        basis = first.curves[2]
        law_model = LawModel.from_basis(
            basis.north_m,
            basis.east_m,
            c0.north_m,
            c0.east_m,
            gn,
            ge,
            first.temperature.end_c,
            criterion,
            criterion_value,
        )
    law_at = (0.0, c0.north_m, c0.east_m, gn, ge)  # the linearisation of the law navigated last (or the first)
    law_navigated_nmi = math.nan
    sensitivity = float(np.hypot(gn[-1], ge[-1]) / NMI_M)
    ref_d, ref_n, ref_e = 0.0, c0.north_m, c0.east_m  # the linearisation point and its curves
    d_star = minimise_linear_criterion(ref_n, ref_e, gn, ge, criterion)
    refinements = 0
    step = math.nan
    verify_d = verify_nmi = np.zeros(0)
    second: PassResult | None = None
    while verify:
        verify_d = np.array([d_star - step_deg_h, d_star, d_star + step_deg_h])
        navigated_law = []
        if law_model is not None and law_model.determined:
            law_at = (ref_d, ref_n, ref_e, gn, ge)
            navigated_law = [law_model.law(*law_at)]
        second = navigate_after_alignment(
            log,
            alignment,
            [*verify_d, *navigated_law],
            hours,
            decimation_s=decimation_s,
            threads=threads,
            chunk_samples=chunk_samples,
            quiet=quiet,
            desc="truth verify",
        )
        lo, mid, hi = second.curves[:3]
        if navigated_law:
            law_curve = second.curves[3]
            law_navigated_nmi = float(criterion_value(law_curve.north_m, law_curve.east_m, criterion))
        # Re-linearise at d* with the central difference of the verification passes (a secant step).
        gn_c = (hi.north_m - lo.north_m) / (2.0 * step_deg_h)
        ge_c = (hi.east_m - lo.east_m) / (2.0 * step_deg_h)
        step = minimise_linear_criterion(mid.north_m, mid.east_m, gn_c, ge_c, criterion)
        ref_d, ref_n, ref_e, gn, ge = d_star, mid.north_m, mid.east_m, gn_c, ge_c
        if abs(step) <= tolerance_deg_h or refinements >= max_refinements:
            break
        d_star += step
        refinements += 1
    verified = False
    if second is not None:
        verify_nmi = np.array([float(criterion_value(c.north_m, c.east_m, criterion)) for c in second.curves[:3]])
        verified = bool(verify_nmi[1] <= verify_nmi[0] and verify_nmi[1] <= verify_nmi[2])
    grid = d_star + np.linspace(-grid_half_width_deg_h, grid_half_width_deg_h, grid_points)
    off = grid - ref_d
    # One curve at a time: the (grid_points, samples) matrix would cost memory in proportion to the hours.
    grid_nmi = np.array([criterion_value(ref_n + o * gn, ref_e + o * ge, criterion) for o in off])
    predicted = float(criterion_value(ref_n + (d_star - ref_d) * gn, ref_e + (d_star - ref_d) * ge, criterion))
    if noise is None:
        noise = estimate_white_noise(log, chunk_samples=chunk_samples)
    elif not isinstance(noise, SensorNoise):
        noise = SensorNoise.from_block(noise)
    sigma, _ = label_sigma_deg_h(
        alignment.site.lat_deg,
        noise,
        criterion=criterion,
        hours=hours,
        height_m=float(alignment.site.height_m),
        decimation_s=decimation_s,
        align_h=timeline.align_h,
        coarse_s=timeline.coarse_s,
        geometry=alignment_geometry(log, alignment),
    )
    best_law = None
    if law_model is not None:
        best_law = law_model.result(
            *law_at,
            constant_deg_h=float(d_star),
            constant_std_deg_h=sigma,
            constant_nmi=predicted,
            navigated_nmi=law_navigated_nmi,
        )
    budget = label_budget_deg_h(hours, decimation_s)
    flagged = bool(sigma > budget) or not math.isfinite(sigma)
    reason = (
        f"label 1-sigma {sigma:.2g} deg/h exceeds the 1 nmi / {hours:g} h drift budget {budget:.2g} deg/h (at 45 deg): "
        f"at {alignment.site.lat_deg:g} deg the {hours:g} h position error hardly depends on the drift"
        if flagged
        else ""
    )
    return TrueDrift(
        run=log.name,
        drift_deg_h=float(d_star),
        criterion=criterion,
        hours=hours,
        trial_deg_h=float(trial_deg_h),
        predicted_nmi=predicted,
        verify_drift_deg_h=verify_d,
        verify_nmi=verify_nmi,
        verified=verified,
        uncompensated_nmi=float(criterion_value(c0.north_m, c0.east_m, criterion)),
        grid_drift_deg_h=grid,
        grid_nmi=np.asarray(grid_nmi, dtype=float),
        sensitivity_nmi_per_deg_h=sensitivity,
        refinements=refinements,
        last_step_deg_h=float(step),
        alignment=alignment,
        base=c0,
        optimum=None if second is None else second.curves[1],
        law=best_law,
        trial=c1,
        temperature=first.temperature,
        drift_std_deg_h=sigma,
        flagged=flagged,
        flag_reason=reason,
        noise=noise.to_dict(),
        noise_note=noise.white_only_note,
    )
