"""The 16 h smoother's 1-sigma on the README tour's INS (docs/studies/2026-11-27-smoother-bias-instability.md).

    python benchmarks/bench_smoother_bias_instability.py [--seeds 200] [--first 1000] [--grade tour|white|both]
                                                         [--rows FILE.jsonl]

The tour's scenario (python/gyrodrift/examples/scenarios/tour.toml: RLG-like white noise, a Gauss-Markov gyro bias
instability of 0.001 deg/h with a 1 h correlation time, a warm-up from 20 to 35 degC) cut to the 16 h the smoother
uses, simulated in memory, one seed after another; grade ``white`` is the same INS without the bias instability.
Each log is smoothed twice as `gyrodrift identify` would: with the noise measured from the log (the default: ARW
and VRW, white only) and with the scenario's noise given (``--noise tour.toml``). Reported per grade and noise:
the drift carried into navigation (`SmootherEstimate.navigation_drift_deg_h`) against the simulated constant +
thermal drift at the end of the span, and the smoothed total (the history's last point) against the same plus the
simulated Gauss-Markov z bias there: error rms and mean, mean reported 1-sigma, z = error / 1-sigma (rms, mean,
share beyond 2) with the range that holds 95 % of the z rms of as many unit normals.

The simulated Gauss-Markov z bias: a twin with the same seed and white noise 1e-20 of the tour's draws the same
normals in the same order (a term draws whenever it is on: gyrodrift-core ``imu_error``), so its z increments
minus the noise-free twin's are that bias alone (checked: the tour minus the twin is white, its hourly means'
rms printed beside ARW / sqrt(1 h)). The thermal drift is the scenario's law at the middle of the last sample.
Also printed: the 72 h label's 1-sigma (`truth`'s covariance analysis) at the tour's site with and without the
bias instability. Only reports; never fails.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from gyrodrift.ins.scenario import Scenario, load_scenario
from gyrodrift.ins.simulate import simulate
from gyrodrift.procedure.noise import load_noise_file
from gyrodrift.procedure.smoother import smooth_log
from gyrodrift.procedure.truth import label_sigma_deg_h
from gyrodrift.units import DEG_PER_H

TOUR = Path(__file__).resolve().parents[1] / "python" / "gyrodrift" / "examples" / "scenarios" / "tour.toml"
SPAN_H = 16.0


def tour(grade: str, seed: int, **changes: float) -> Scenario:
    """The tour cut to 16 h (grade ``white``: no bias instability); `changes` as ``part__key=value``."""
    d = copy.deepcopy(load_scenario(TOUR).to_toml_dict())
    d["run"].update(duration_h=SPAN_H, seed=seed)
    if grade == "white":
        d["gyro"]["bias_instability_deg_h"] = 0.0
    for k, v in changes.items():
        part, key = k.split("__")
        d[part][key] = v
    return Scenario.from_dict(d)


def law_at_end(s: Scenario) -> float:
    """The scenario's constant + thermal z drift [deg/h] at the middle of the last sample."""
    t, g = s.temperature, s.gyro
    t_h = SPAN_H - 0.5 / s.run.rate_hz / 3600.0
    decay = math.exp(-t_h / t.tau_h)
    temp = t.end_c + (t.start_c - t.end_c) * decay
    rate = -(t.start_c - t.end_c) / t.tau_h * decay  # degC/h
    return (
        g.bias_deg_h[2]
        + t.k1_deg_h_per_c * (temp - t.t0_c)
        + t.k2_deg_h_per_c2 * (temp - t.t0_c) ** 2
        + (t.k3_deg_h_per_c_per_h * rate)
    )


def one_seed(grade: str, seed: int, free_z: np.ndarray, noises: dict) -> dict:
    s = tour(grade, seed)
    data = simulate(s)
    dt = 1.0 / s.run.rate_hz
    row: dict = {"grade": grade, "seed": seed, "law_end": law_at_end(s), "gm_end": 0.0, "white_check": math.nan}
    if grade == "tour":
        twin = simulate(tour(grade, seed, gyro__arw_deg_rth=1e-20, accel__vrw_ug_rthz=1e-20))
        row["gm_end"] = float(twin["dtheta_z_rad"][-1] - free_z[-1]) / dt / DEG_PER_H
        white = (data["dtheta_z_rad"] - twin["dtheta_z_rad"]) / dt / DEG_PER_H
        per_h = int(round(3600.0 / dt))
        hourly = white[: len(white) // per_h * per_h].reshape(-1, per_h).mean(axis=1)
        row["white_check"] = float(np.sqrt(np.mean(hourly**2)))
    log = data.log()
    for name, noise in noises.items():
        e = smooth_log(log, noise=noise)
        row[name] = {
            "carried": e.navigation_drift_deg_h,
            "carried_std": e.navigation_drift_std_deg_h,
            "total": float(e.hist_drift_deg_h[-1]),
            "total_std": float(e.hist_drift_std_deg_h[-1]),
            "model": e.model,
            "arw": e.noise.arw_deg_rth,
        }
    return row


def summary(rows: list[dict], name: str, which: str) -> str:
    est = np.array([r[name][which] for r in rows])
    std = np.array([r[name][which + "_std"] for r in rows])
    truth = np.array([r["law_end"] + (r["gm_end"] if which == "total" else 0.0) for r in rows])
    err = est - truth
    z = err / std
    n = len(z)
    lo, hi = (math.sqrt(chi2.ppf(q, n) / n) for q in (0.025, 0.975))
    return (
        f"error rms {np.sqrt(np.mean(err**2)):.2e} (mean {np.mean(err):+.1e}), mean 1-sigma {np.mean(std):.2e} "
        f"deg/h; z rms {np.sqrt(np.mean(z**2)):.3f} (95 % of unit normals: {lo:.2f}-{hi:.2f}), mean {np.mean(z):+.2f}, "
        f"|z| > 2: {np.mean(np.abs(z) > 2):.3f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--first", type=int, default=1000)
    ap.add_argument("--grade", choices=["tour", "white", "both"], default="both")
    ap.add_argument("--rows", type=Path, default=None, help="append each seed's numbers to this JSON-lines file")
    a = ap.parse_args()
    given = load_noise_file(TOUR)
    print(f"tour.toml noise: {given}")
    for lat_noise, what in ((given, "with"), (replace(given, bias_instability_deg_h=0.0), "without")):
        sigma = label_sigma_deg_h(load_scenario(TOUR).site.lat_deg, lat_noise)[0]
        print(f"72 h label 1-sigma ({what} the bias instability): {sigma:.3e} deg/h")
    for grade in ("tour", "white") if a.grade == "both" else (a.grade,):
        noises = {"measured": None, "given": given if grade == "tour" else replace(given, bias_instability_deg_h=0.0)}
        free = tour(grade, 0, gyro__arw_deg_rth=0.0, accel__vrw_ug_rthz=0.0, gyro__bias_instability_deg_h=0.0)
        free_z = simulate(free)["dtheta_z_rad"]
        rows, t0 = [], time.perf_counter()
        for seed in range(a.first, a.first + a.seeds):
            row = one_seed(grade, seed, free_z, noises)
            rows.append(row)
            if a.rows is not None:
                with open(a.rows, "a", encoding="utf-8") as fh:
                    fh.write(json.dumps(row) + "\n")
        print(f"grade {grade}: {len(rows)} seeds ({a.first}-{a.first + a.seeds - 1}), {time.perf_counter() - t0:.0f} s")
        if grade == "tour":
            gm = np.array([r["gm_end"] for r in rows])
            check = np.mean([r["white_check"] for r in rows])
            print(
                f"  simulated GM z bias at the end: sd {gm.std():.2e} deg/h; tour minus twin, hourly means' rms "
                f"{check:.2e} deg/h (white noise alone: ARW / sqrt(1 h) = {given.arw_deg_rth:.2e})"
            )
        for name in noises:
            models = sorted({r[name]["model"] for r in rows})
            arw = np.mean([r[name]["arw"] for r in rows])
            print(f"  noise {name} (ARW {arw:.6f} deg/sqrt(h), models {', '.join(models)}):")
            print(f"    carried vs constant + thermal:           {summary(rows, name, 'carried')}")
            print(f"    total vs constant + thermal + GM at end: {summary(rows, name, 'total')}")


if __name__ == "__main__":
    main()
