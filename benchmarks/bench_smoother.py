"""The 16 h smoother and the labels' 1-sigma at full size (docs/studies/2026-11-23-smoother.md).

    python benchmarks/bench_smoother.py [--seeds 30] [--rate-hz 10] [--label-seeds 30]

1. Noise-free accuracy: 16 h logs at 20, 40, 60 deg, reciprocating / continuous / indexing, drifts 0.003 and
   0.05 deg/h: smoother drift minus the simulated constant, and the linearity diagnostics.
2. Consistency at 40 deg, RLG grade (ARW 0.0005 deg/sqrt(h), VRW 5 ug/sqrt(Hz)), `--seeds` seeds: the z-scores
   (estimate - simulated drift) / reported sigma, white noise only, and with a Gauss-Markov bias (0.002 deg/h,
   1 h) and rate random walk (0.0005 deg/h/sqrt(h)) on every gyro, the filter told that model; their RMS,
   the Monte-Carlo spread against the mean reported sigma.
3. Labels: `--label-seeds` noisy 76 h logs at 40 deg (2 Hz): the spread of `truth` (criteria final and rms)
   around the noise-free twin's truth against its reported 1-sigma; the reported sigma at 3-88 deg against
   1/(sin L cos L).
4. Runtime of the smoother per 16 h log at `--rate-hz` and 100 Hz, against a bare read of the same log in the
   same run (the scenario simulated on the fly: the read includes simulating it).
Only reports; never fails on a slow machine.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure import SensorNoise, find_true_drift, smooth_log
from gyrodrift.procedure.truth import label_budget_deg_h, label_sigma_deg_h

RLG = {"arw_deg_rth": 0.0005, "vrw_ug_rthz": 5.0}
GM_RRW = {"bias_instability_deg_h": 0.002, "correlation_s": 3600.0, "rrw_deg_h_rth": 0.0005}


def scenario(lat, drift=0.003, *, noise=None, seed=1, hours=16.0, rate=10.0, scheme="reciprocating", gyro=None):
    noise = noise or {}
    return Scenario.from_dict(
        {
            "site": {"lat_deg": lat},
            "run": {"duration_h": hours, "rate_hz": rate, "seed": seed},
            "rotation": {"scheme": scheme},
            "gyro": {
                "bias_deg_h": [0.004, -0.003, drift],
                "arw_deg_rth": noise.get("arw_deg_rth", 0.0),
                **(gyro or {}),
            },
            "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": noise.get("vrw_ug_rthz", 0.0)},
            "attitude": {"yaw_deg": 30.0, "pitch_deg": 0.1},
        }
    )


def noise_free(rate: float) -> None:
    print("1. noise-free 16 h logs: smoother drift - simulated constant [deg/h]")
    for scheme in ("reciprocating", "continuous", "indexing"):
        for lat in (20.0, 40.0, 60.0):
            errs, att, pos = [], 0.0, 0.0
            for drift in (0.003, 0.05):
                e = smooth_log(scenario_log(scenario(lat, drift, scheme=scheme, rate=rate)))
                errs.append(e.drift_deg_h - drift)
                att, pos = max(att, e.max_attitude_correction_arcsec), max(pos, e.max_position_error_m)
            print(
                f"  {scheme:13s} {lat:4.0f} deg: {errs[0]:+.1e} (0.003), {errs[1]:+.1e} (0.05); largest correction "
                f"after 1 h {att:.1e} arcsec, position error {pos:.3f} m"
            )


def consistency(n: int, rate: float) -> None:
    print(f"2. z-scores over {n} seeds at 40 deg, RLG grade")
    for label, gyro, told in (
        ("white noise only", None, SensorNoise(**RLG)),
        ("Gauss-Markov + RRW, told", GM_RRW, SensorNoise(**RLG, **GM_RRW)),
        ("Gauss-Markov + RRW, not told", GM_RRW, SensorNoise(**RLG)),
    ):
        est, sig = [], []
        for seed in range(n):
            e = smooth_log(scenario_log(scenario(40.0, noise=RLG, seed=100 + seed, gyro=gyro, rate=rate)), noise=told)
            est.append(e.drift_deg_h - 0.003)
            sig.append(e.drift_std_deg_h)
        z = np.array(est) / np.array(sig)
        print(
            f"  {label:30s} z rms {np.sqrt(np.mean(z**2)):.2f} (mean {np.mean(z):+.2f}); spread {np.std(est):.2e}, "
            f"mean sigma {np.mean(sig):.2e} deg/h"
        )


def labels(n: int) -> None:
    print(f"3. labels: truth over {n} noisy 76 h logs at 40 deg (2 Hz) around the noise-free twin's truth")
    for criterion in ("final", "rms"):
        twin = find_true_drift(scenario_log(scenario(40.0, hours=76.0, rate=2.0)), criterion=criterion)
        dev, sig = [], []
        for seed in range(n):
            log = scenario_log(scenario(40.0, noise=RLG, seed=seed, hours=76.0, rate=2.0))
            t = find_true_drift(log, criterion=criterion)
            dev.append(t.drift_deg_h - twin.drift_deg_h)
            sig.append(t.drift_std_deg_h)
        obs = math.sqrt(np.mean(np.square(dev)))
        print(
            f"  {criterion:5s}: observed rms {obs:.2e}, reported sigma {np.mean(sig):.2e} deg/h: "
            f"ratio {obs / np.mean(sig):.2f}"
        )
    noise = SensorNoise(**RLG)
    s45 = label_sigma_deg_h(45.0, noise)[0]
    for lat in (3.0, 10.0, 45.0, 80.0, 88.0):
        s = label_sigma_deg_h(lat, noise)[0]
        law = s45 * 0.5 / (math.sin(math.radians(lat)) * math.cos(math.radians(lat)))
        print(f"  {lat:4.0f} deg: sigma {s:.2e} deg/h, {s / law:.3f} of 1/(sin L cos L)")
    print(f"  flag threshold (1 nmi / 72 h budget at 45 deg): {label_budget_deg_h():.2e} deg/h")


def runtime(rate: float) -> None:
    print("4. runtime per 16 h log (best of 3)")
    for r in (rate, 100.0):
        log = scenario_log(scenario(40.0, noise=RLG, rate=r))
        read, smooth = math.inf, math.inf
        for _ in range(3):
            t = time.perf_counter()
            for _chunk in log.chunks(100_000):
                pass
            read = min(read, time.perf_counter() - t)
            t = time.perf_counter()
            smooth_log(log, noise=SensorNoise(**RLG))
            smooth = min(smooth, time.perf_counter() - t)
        print(
            f"  {r:g} Hz: smoother {smooth:.2f} s, bare read (simulated on the fly) {read:.2f} s: {smooth / read:.2f} x"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--label-seeds", type=int, default=30)
    ap.add_argument("--rate-hz", type=float, default=10.0)
    a = ap.parse_args()
    noise_free(a.rate_hz)
    consistency(a.seeds, a.rate_hz)
    labels(a.label_seeds)
    runtime(a.rate_hz)


if __name__ == "__main__":
    main()
