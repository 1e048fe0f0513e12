"""One campaign run's science, in the worker: simulate, align, navigate, find the truth, and return one row.

Per run (`process_run`; nothing written here): the scenario is simulated on the fly
(`gyrodrift.ins.simulate.scenario_log`), aligned, navigated for the 12 h features and the 72 h truth
(`extract_features` with the truth: one read for both), the 12 h curve fit; the linear 72 h error curves
(north/east error of the uncompensated navigation and their sensitivity per deg/h of compensated drift, the
secant between two navigated drifts), from which the position error after compensating any drift ``d`` is
``hypot(n0 + d gn, e0 + d ge)`` without navigating again (`gyrodrift.fleet.store.linear_error_nmi`); the 16 h
smoother estimate; the truth's best drift law beside the best constant (``TRUTH_LAW_COLUMNS``, and the error
curves' response to its k1, ``curve_north_per_k1`` / ``curve_east_per_k1``); and the simulated effective drift,
the truth of the run's noise-free twin (same scenario and seed, ARW/VRW/bias instability/RRW off). A run that
fails is a row with its error. The row's columns are those of `gyrodrift.fleet.store.run_schema`.
"""

from __future__ import annotations

import contextlib
import math
import os
import socket
import time
from collections.abc import Iterator
from typing import Any

import numpy as np

from gyrodrift.fleet.spec import Campaign
from gyrodrift.fleet.store import param_column
from gyrodrift.runs.columns import FEATURES_COLUMNS, SMOOTHER_COLUMNS, TRUTH_LAW_COLUMNS

__all__ = ["noise_model", "process_run", "trial_drift_deg_h"]

FROM_FEATURES = tuple(c for c in FEATURES_COLUMNS if c != "run" and c not in SMOOTHER_COLUMNS)
"""The run-table columns of a run taken as they are from its 12 h features (`gyrodrift.procedure.results.RunFeatures`;
the smoother's are timed on their own)."""


def noise_model(scenario):
    """The run's own noise model (its scenario's gyro and accelerometer noise keys), for the smoother and the
    truth's label sigma: a simulated run's noise is known, not measured."""
    from gyrodrift.procedure.noise import SensorNoise

    data = scenario.to_toml_dict()
    return SensorNoise.from_block({"gyro": data["gyro"], "accel": data["accel"]}, source="scenario")


def _smoother_step(log, noise, timeline) -> dict[str, float]:
    """The 16 h smoother's ``SMOOTHER_COLUMNS`` (the drift is the end-of-span drift under its thermal model)."""
    from gyrodrift.procedure.smoother import smooth_log

    res = smooth_log(log, timeline=timeline, noise=noise)
    return {
        "drift_smoother_deg_h": float(res.navigation_drift_deg_h),
        "drift_smoother_std_deg_h": float(res.navigation_drift_std_deg_h),
        **res.thermal_columns(),
    }


def process_run(campaign: Campaign, index: int, *, chunk_samples: int = 100_000) -> dict[str, Any]:
    """Everything the study needs about run `index`, as one row (see the module docstring); never raises for a
    failing run (the row carries ``error``)."""
    spec = campaign.spec(index)
    row: dict[str, Any] = {"run": spec.run, "index": index, "seed": spec.seed, "grade": spec.grade}
    row.update({param_column(k): v for k, v in spec.params.items() if k != "grade"})
    row["worker"] = f"{socket.gethostname()}-{os.getpid()}"
    t_start, cpu_start = time.perf_counter(), time.process_time()
    try:
        row.update(_measure(campaign, index, chunk_samples))
        row["error"] = None
    except Exception as exc:  # a failed run is a row with its error; the campaign goes on
        row["error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:2000]
    row["t_total_s"] = time.perf_counter() - t_start
    row["cpu_total_s"] = time.process_time() - cpu_start
    return row


def trial_drift_deg_h(scenario, timeline) -> float:
    """Where a run's truth is linearised [deg/h]: the scenario's z drift (constant + temperature law, the warm-up
    with its daily swing) averaged over the truth span. A numerical choice only (the truth is still found by
    navigating and minimising): a trial within about 5e-4 deg/h of the answer makes the first linearisation exact
    to about 1e-7 deg/h, so the truth needs no verification read. 0.001 deg/h (`find_true_drift`'s default) when
    that average is within 1e-4 deg/h of 0 or not finite."""
    t = scenario.temperature
    t_h = np.linspace(timeline.align_h, timeline.align_h + timeline.truth_h, 1001)
    with np.errstate(all="ignore"):
        if t.series_t_h is not None and t.series_temp_c is not None:
            temp = np.interp(t_h, np.asarray(t.series_t_h, float), np.asarray(t.series_temp_c, float))
        else:
            swing = t.swing_amplitude_c * np.sin(2.0 * np.pi * t_h / t.swing_period_h + np.deg2rad(t.swing_phase_deg))
            temp = t.end_c + (t.start_c - t.end_c) * np.exp(-t_h / t.tau_h) + swing
        dtemp = temp - t.t0_c
        law = t.k1_deg_h_per_c * dtemp + t.k2_deg_h_per_c2 * dtemp**2 + t.k3_deg_h_per_c_per_h * np.gradient(temp, t_h)
        d = float(scenario.gyro.bias_deg_h[2] + np.mean(law))
    return d if math.isfinite(d) and abs(d) >= 1e-4 else 1e-3


@contextlib.contextmanager
def _stage(out: dict[str, Any], name: str) -> Iterator[None]:
    """Time a stage of a run into ``out``: ``t_NAME_s`` wall and ``cpu_NAME_s`` CPU seconds (the process's CPU
    time, which is the run's: a run keeps to one thread, ``threads=1`` on every read)."""
    w, c = time.perf_counter(), time.process_time()
    try:
        yield
    finally:
        out[f"t_{name}_s"] = time.perf_counter() - w
        out[f"cpu_{name}_s"] = time.process_time() - c


def _measure(campaign: Campaign, index: int, chunk_samples: int) -> dict[str, Any]:
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.procedure import align_log, extract_features, find_true_drift, navigate_after_alignment
    from gyrodrift.procedure.truth import minimise_linear_criterion

    verify = bool(campaign.options.get("verify", False))
    out: dict[str, Any] = {}
    scn = campaign.scenario(index)
    out["arw_deg_rth"] = scn.gyro.arw_deg_rth
    out["vrw_ug_rthz"] = scn.accel.vrw_ug_rthz
    log = scenario_log(scn)
    timeline = campaign.timeline
    with _stage(out, "align"):
        alignment = align_log(log, timeline=timeline, chunk_samples=chunk_samples)
    with _stage(out, "passes"):
        noise = noise_model(scn)
        truth_options: dict[str, Any] = {"threads": 1}  # a run keeps to one core: workers give the parallelism
        if not verify:  # one read: the features, and the truth linearised between 0 and the trial drift
            truth_options.update(verify=False, trial_deg_h=trial_drift_deg_h(scn, timeline))
        f = extract_features(
            log,
            with_truth=True,
            timeline=timeline,
            alignment=alignment,
            smoother=False,  # timed on its own below
            noise=noise,
            truth_options=truth_options,
            chunk_samples=chunk_samples,
        )
        truth = f.truth
        assert truth is not None and truth.base is not None and truth.trial is not None  # find_true_drift sets them
        base, d_star = truth.base, truth.drift_deg_h
        n0, e0 = base.north_m, base.east_m
        if not verify:  # the secant of the read: 0 -> trial, within about 5e-4 deg/h of d*
            gn = (truth.trial.north_m - n0) / truth.trial_deg_h
            ge = (truth.trial.east_m - e0) / truth.trial_deg_h
        else:
            opt = truth.optimum
            assert opt is not None
            if abs(d_star) >= 2e-4:  # the secant 0 -> d*: exact at both ends, estimates fall between or near them
                gn, ge = (opt.north_m - n0) / d_star, (opt.east_m - e0) / d_star
            else:  # too close to 0 for a secant: one more pass 0.001 deg/h away from d*, curves about d = 0
                extra = navigate_after_alignment(
                    log, alignment, [d_star + 1e-3], truth.hours, threads=1, chunk_samples=chunk_samples
                ).curves[0]
                gn, ge = (extra.north_m - opt.north_m) / 1e-3, (extra.east_m - opt.east_m) / 1e-3
                n0, e0 = opt.north_m - d_star * gn, opt.east_m - d_star * ge
    out.update({c: getattr(f, c) for c in FROM_FEATURES})
    out.update(
        drift_deg_h=d_star,
        drift_std_deg_h=float(truth.drift_std_deg_h),
        label_flagged=bool(truth.flagged),
        truth_verified=bool(truth.verified) if verify else None,
        drift_align_deg_h=alignment.gyro_bias_deg_h[2],
        drift_align_std_deg_h=alignment.gyro_bias_std_deg_h[2],
        uncompensated_final_nmi=truth.uncompensated_nmi,
        hours_truth=truth.hours,
    )
    law = truth.law  # the best law beside the best constant (NaN and empty curves without a temperature)
    out.update(dict.fromkeys(TRUTH_LAW_COLUMNS, math.nan) if law is None else law.columns())
    out.update(
        curve_t_h=np.asarray(base.t_h, np.float32).tolist(),
        curve_north0_m=np.asarray(n0, np.float32).tolist(),
        curve_east0_m=np.asarray(e0, np.float32).tolist(),
        curve_north_per_deg_h=np.asarray(gn, np.float32).tolist(),
        curve_east_per_deg_h=np.asarray(ge, np.float32).tolist(),
        curve_north_per_k1=[] if law is None else np.asarray(law.north_per_k1_m, np.float32).tolist(),
        curve_east_per_k1=[] if law is None else np.asarray(law.east_per_k1_m, np.float32).tolist(),
    )
    # --- the 16 h smoother: its own read of the first 16 h (a seventh of a run's simulation) ---
    out.update(dict.fromkeys(SMOOTHER_COLUMNS, math.nan))
    out["smoother_error"] = None
    with _stage(out, "smoother"):
        if campaign.options.get("smoother", True):
            try:  # a smoother failure is recorded beside the run's other results, which stay valid
                out.update(_smoother_step(log, noise, timeline))
            except Exception as exc:
                out["smoother_error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:2000]
    # --- the noise-free twin: aligned on its own, navigated once at d* ---
    with _stage(out, "twin"):
        twin_scn = campaign.scenario(index, noise=False)
        twin_log = scenario_log(twin_scn)
        if verify:
            twin = find_true_drift(
                twin_log, timeline=timeline, noise=noise_model(twin_scn), threads=1, chunk_samples=chunk_samples
            )
            out["drift_effective_deg_h"] = twin.drift_deg_h
        else:  # the twin's error differs from the run's by the noise's effect: its sensitivity to the drift is the
            # run's (same site, motion and sensor model), so one pass at d* and one linear step give its optimum
            twin_alignment = align_log(twin_log, timeline=timeline, chunk_samples=chunk_samples)
            at = navigate_after_alignment(
                twin_log, twin_alignment, [d_star], truth.hours, threads=1, chunk_samples=chunk_samples
            ).curves[0]
            step = minimise_linear_criterion(at.north_m, at.east_m, gn, ge, truth.criterion)
            out["drift_effective_deg_h"] = d_star + step
    return out
