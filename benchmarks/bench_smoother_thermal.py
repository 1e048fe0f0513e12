"""The smoother's thermal model on a warming fleet: z-scores of its end-of-span drift
(docs/studies/2026-11-23-smoother.md).

    python benchmarks/bench_smoother_thermal.py [--seeds 30] [--rate-hz 10] [--workers 1]

Each seed is one run drawn as the identification study's fleet (examples/identification_study.py): site
uniform in 20-60 deg, RLG grade (ARW 0.0005 deg/sqrt(h), VRW 5 ug/sqrt(Hz)), random x/y gyro and accelerometer
biases and heading, a warm-up from 15-25 degC to 28-40 degC with time constant 1-6 h, z drift = per-run constant
N(0.002, 0.0008) deg/h + 0.0002 deg/h/degC (T - 28 degC). The smoother runs over the first 16 h of the noisy log
(thermal model by default: the log has a temperature column); its reported drift is the end-of-span drift with
its 1-sigma. Two references:

* the simulated drift at the end of the span, constant + k1 (T(16 h) - 28 degC): what the thermal model
  estimates (z-scores should have RMS near 1);
* the 72 h effective drift, ``truth`` (final) of the run's noise-free twin over the 72 h navigation: what the
  system needs (the temperature keeps changing after the 16 h, so this z-score also holds the model's gap).

The same z-scores for the constant-drift estimate (the thermal state conditioned on k_z = 0) beside them, and for
the end drift with a fleet prior on k_z (`fleet_coefficient_prior` of the other seeds' estimates, leave one out;
`SmootherEstimate.end_drift_with_coefficient_prior`).
Only reports; never fails on a slow machine.
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure import find_true_drift, smooth_log
from gyrodrift.procedure.smoother import fleet_coefficient_prior

K1 = 0.0002
T0 = 28.0
SPAN_H = 16.0


def draw(seed: int, rate_hz: float) -> dict:
    """One run of the fleet (the identification study's distributions)."""
    rng = np.random.default_rng([seed, 2026])
    return {
        "lat_deg": float(rng.uniform(20.0, 60.0)),
        "start_c": float(rng.uniform(15.0, 25.0)),
        "end_c": float(rng.uniform(28.0, 40.0)),
        "tau_h": float(rng.uniform(1.0, 6.0)),
        "constant_deg_h": float(rng.normal(0.002, 0.0008)),
        "gyro_xy_deg_h": [float(v) for v in rng.uniform(-0.006, 0.006, 2)],
        "accel_ug": [float(v) for v in rng.uniform(-40.0, 40.0, 3)],
        "yaw_deg": float(rng.uniform(0.0, 360.0)),
        "seed": 5000 + seed,
        "rate_hz": rate_hz,
    }


def scenario(spec: dict, *, noise: bool, hours: float) -> Scenario:
    return Scenario.from_dict(
        {
            "site": {"lat_deg": spec["lat_deg"]},
            "run": {"duration_h": hours, "rate_hz": spec["rate_hz"], "seed": spec["seed"]},
            "gyro": {
                "bias_deg_h": [*spec["gyro_xy_deg_h"], spec["constant_deg_h"]],
                "arw_deg_rth": 0.0005 if noise else 0.0,
            },
            "accel": {"bias_ug": spec["accel_ug"], "vrw_ug_rthz": 5.0 if noise else 0.0},
            "temperature": {
                "start_c": spec["start_c"],
                "end_c": spec["end_c"],
                "tau_h": spec["tau_h"],
                "t0_c": T0,
                "k1_deg_h_per_c": K1,
            },
            "attitude": {"yaw_deg": spec["yaw_deg"]},
        }
    )


def one(args: tuple[int, float]) -> dict:
    """Smoother on the noisy 16 h, the simulated end drift, the twin's 72 h effective drift."""
    seed, rate_hz = args
    spec = draw(seed, rate_hz)
    est = smooth_log(scenario_log(scenario(spec, noise=True, hours=SPAN_H)))
    temp_end = spec["end_c"] + (spec["start_c"] - spec["end_c"]) * math.exp(-SPAN_H / spec["tau_h"])
    effective = find_true_drift(scenario_log(scenario(spec, noise=False, hours=76.0))).drift_deg_h
    return {
        "model": est.model,
        "nav": est.navigation_drift_deg_h,
        "nav_std": est.navigation_drift_std_deg_h,
        "const": est.drift_deg_h,
        "const_std": est.drift_std_deg_h,
        "k": est.thermal_coeff_deg_h_per_c,
        "k_std": est.thermal_coeff_std_deg_h_per_c,
        "end": spec["constant_deg_h"] + K1 * (temp_end - T0),
        "effective": effective,
        "estimate": est,
    }


def rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--rate-hz", type=float, default=10.0)
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args()
    t0 = time.perf_counter()
    jobs = [(s, args.rate_hz) for s in range(args.seeds)]
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            rows = list(pool.map(one, jobs))
    else:
        rows = [one(j) for j in jobs]
    col = {k: np.array([r[k] for r in rows]) for k in rows[0] if k not in ("model", "estimate")}
    ests = [r["estimate"] for r in rows]
    fleet = []
    for i, e in enumerate(ests):
        mean, std = fleet_coefficient_prior(ests[:i] + ests[i + 1 :])
        fleet.append(e.end_drift_with_coefficient_prior(mean, std))
    col["fleet"] = np.array([f[0] for f in fleet])
    col["fleet_std"] = np.array([f[1] for f in fleet])
    models = [r["model"] for r in rows]
    print(
        f"{args.seeds} seeds at {args.rate_hz:g} Hz, 16 h smoother; models reported: {models.count('thermal')} thermal"
    )
    z = {
        "thermal end drift vs simulated end drift": (col["nav"] - col["end"]) / col["nav_std"],
        "thermal end drift vs 72 h effective drift": (col["nav"] - col["effective"]) / col["nav_std"],
        "constant model vs simulated end drift": (col["const"] - col["end"]) / col["const_std"],
        "constant model vs 72 h effective drift": (col["const"] - col["effective"]) / col["const_std"],
        "k_z vs simulated k1": (col["k"] - K1) / col["k_std"],
        "fleet-prior end drift vs simulated end drift": (col["fleet"] - col["end"]) / col["fleet_std"],
        "fleet-prior end drift vs 72 h effective drift": (col["fleet"] - col["effective"]) / col["fleet_std"],
    }
    for name, v in z.items():
        print(f"  z-score rms {rms(v):5.2f}  mean {np.mean(v):+5.2f}  {name}")
    print(
        f"  thermal: rms error vs end {rms(col['nav'] - col['end']):.2e}, vs effective "
        f"{rms(col['nav'] - col['effective']):.2e}, reported 1-sigma (rms) {rms(col['nav_std']):.2e} deg/h"
    )
    print(
        f"  constant: rms error vs end {rms(col['const'] - col['end']):.2e}, vs effective "
        f"{rms(col['const'] - col['effective']):.2e}, reported 1-sigma (rms) {rms(col['const_std']):.2e} deg/h"
    )
    print(
        f"  fleet k_z prior: rms error vs end {rms(col['fleet'] - col['end']):.2e}, vs effective "
        f"{rms(col['fleet'] - col['effective']):.2e}, reported 1-sigma (rms) {rms(col['fleet_std']):.2e} deg/h"
    )
    print(
        f"  k_z: mean {np.mean(col['k']):.2e}, spread {np.std(col['k']):.2e}, reported 1-sigma (rms) "
        f"{rms(col['k_std']):.2e} deg/h/degC (simulated {K1:g})"
    )
    print(f"  end drift - effective drift (simulated, no noise): rms {rms(col['end'] - col['effective']):.2e} deg/h")
    print(f"elapsed {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
