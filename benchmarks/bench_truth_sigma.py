"""Calibration of `truth`'s 1-sigma: z = (truth - effective drift) / reported sigma over many seeds.

    python benchmarks/bench_truth_sigma.py [--seeds 60] [--first-seed 0] [--rate-hz 10] [--lat-deg 20,40,60]
        [--hours 72] [--workers 1] [--thermal] [--noise log|given] [--gm-rrw] [--twin-alignment] [--results FILE]

For every latitude and seed: a noisy 4 h + `--hours` static log (RLG grade: ARW 0.0005 deg/sqrt(h), VRW
5 ug/sqrt(Hz); reciprocating table; x/y gyro biases 0.004, -0.003 deg/h, accelerometer biases 20, -10, 5 ug;
yaw 30 deg, pitch 0.1 deg; z drift 0.003 deg/h), simulated on the fly at `--rate-hz`. Its `truth` (criterion
``final``, one read: ``verify=False``, trial at the nominal drift, exact to about 1e-7 deg/h) and reported
1-sigma (``drift_std_deg_h``, ARW and VRW measured from the log's first hour as `gyrodrift truth` does, or
``--noise given``: the simulated densities) are compared with the simulated effective drift, the truth of the
run's noise-free twin (same scenario and seed, ARW and VRW off: what the label's sigma describes).

``--thermal``: the issue-20 fleet's environment instead: per seed a constant N(0.002, 0.0008) deg/h, random
x/y biases and heading, a warm-up from 15-25 to 28-40 degC (tau 1-6 h) plus a daily swing of 0.5-2 degC (random
phase), drift law 0.0002 deg/h/degC (T - 28 degC); one noise-free twin per seed. It also prints z against the
time average of the simulated drift over the navigation span (not the effective drift: the 72 h error weights
the drift unevenly in time, and a daily swing is resonant with the Earth-rate error dynamics).

``--gm-rrw``: every gyro also has a Gauss-Markov bias (0.002 deg/h, 1 h) and a rate random walk
(0.0005 deg/h/sqrt(h)), as in benchmarks/bench_smoother.py; the twin has neither (as a campaign's), and `truth` is
told the noise model (``--noise given`` implied: a log's first hour does not measure them). It also prints z
against the white-noise-only sigma (what `truth` reported before it took these terms).

``--twin-alignment``: every noisy run is navigated from its twin's alignment instead of its own, so the
alignment's noise-driven errors play no part; its sigma is then the label's without them (`label_sigma_deg_h` from
the noise `truth` measured, no geometry), the one `truth` reported before it took them.

``--results FILE``: every truth is appended to FILE (one JSON line) as it is made, and the truths of the same
settings already there are not made again: a long study can be cut short, its completed seeds summarised by a
re-run with a smaller ``--seeds``, and resumed. The seeds are taken in turn across the latitudes, so a cut study
has about as many at each.

Every latitude takes the same seeds, and a seed draws the same normals at the same rate and duration whatever the
site or geometry: the latitudes of one study share their noise draws and are not independent samples (their z rms
move together); a new set of draws needs other seeds (``--first-seed``) or another rate.

Printed per latitude: the rms of z with its 95 % interval (n rms^2 / s^2 ~ chi-square with n degrees of freedom
for Gaussian z of scale s: the rms of 60 z-scores has a relative standard error of about 1 / sqrt(2 n) = 9 %),
the mean z, the observed rms deviation and the mean reported sigma (and its ratio to the sigma of the simulated ARW
and VRW on the fixed geometry: how well the log's first hour measures them). Only reports; never fails.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure import SensorNoise, find_true_drift
from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.truth import label_sigma_deg_h

RLG = {"arw_deg_rth": 0.0005, "vrw_ug_rthz": 5.0}
GM_RRW = {"bias_instability_deg_h": 0.002, "correlation_s": 3600.0, "rrw_deg_h_rth": 0.0005}
ALIGN_H = 4.0
K1_DEG_H_PER_C = 0.0002
T0_C = 28.0


def thermal_spec(seed: int, hours: float) -> dict:
    """The seed's thermal run (module docs): constant, biases, heading and the temperature profile."""
    rng = np.random.default_rng([20, seed])
    t_h = np.linspace(0.0, ALIGN_H + hours, int(4 * (ALIGN_H + hours)) + 1)
    start, end, tau = rng.uniform(15, 25), rng.uniform(28, 40), rng.uniform(1, 6)
    swing, phase = rng.uniform(0.5, 2.0), rng.uniform(0, 2 * math.pi)
    temp = end + (start - end) * np.exp(-t_h / tau) + swing * np.sin(2 * math.pi * t_h / 24.0 + phase)
    return {
        "constant": float(rng.normal(0.002, 0.0008)),
        "gyro_xy": [float(v) for v in rng.uniform(-0.006, 0.006, 2)],
        "accel_xy": [float(v) for v in rng.uniform(-40, 40, 2)],
        "yaw": float(rng.uniform(0, 360)),
        "t_h": t_h,
        "temp_c": temp,
    }


def scenario(
    lat: float, seed: int, rate: float, hours: float, *, noise: bool, thermal: bool, gm_rrw: bool = False
) -> Scenario:
    """The run (``noise=False``: its noise-free twin, the same scenario and seed with every noise term off)."""
    gyro: dict = {"bias_deg_h": [0.004, -0.003, 0.003], "arw_deg_rth": RLG["arw_deg_rth"] if noise else 0.0}
    if gm_rrw and noise:
        gyro.update(GM_RRW)
    accel: dict = {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": RLG["vrw_ug_rthz"] if noise else 0.0}
    data: dict = {
        "site": {"lat_deg": lat},
        "run": {"duration_h": ALIGN_H + hours, "rate_hz": rate, "seed": seed},
        "rotation": {"scheme": "reciprocating"},
        "gyro": gyro,
        "accel": accel,
        "attitude": {"yaw_deg": 30.0, "pitch_deg": 0.1},
    }
    if thermal:
        s = thermal_spec(seed, hours)
        gyro["bias_deg_h"] = [*s["gyro_xy"], s["constant"]]
        accel["bias_ug"] = [*s["accel_xy"], 5.0]
        data["attitude"] = {"yaw_deg": s["yaw"]}
        data["temperature"] = {
            "series_t_h": [float(v) for v in s["t_h"]],
            "series_temp_c": [float(v) for v in s["temp_c"]],
            "t0_c": T0_C,
            "k1_deg_h_per_c": K1_DEG_H_PER_C,
        }
    return Scenario.from_dict(data)


def mean_simulated_drift(seed: int, hours: float) -> float:
    """Time average [deg/h] of the thermal run's simulated z drift over the navigation span."""
    s = thermal_spec(seed, hours)
    t = np.linspace(ALIGN_H, ALIGN_H + hours, 4001)
    temp = np.interp(t, s["t_h"], s["temp_c"])
    return s["constant"] + K1_DEG_H_PER_C * float(np.mean(temp - T0_C))


def one(task: tuple) -> tuple:
    """``(task, drift [deg/h], reported sigma [deg/h])`` of one truth."""
    lat, seed, rate, hours, noise, thermal, noise_mode, gm_rrw, twin_alignment = task
    log = scenario_log(scenario(lat, seed, rate, hours, noise=noise, thermal=thermal, gm_rrw=gm_rrw))
    alignment = None
    if twin_alignment and noise:
        alignment = align_log(scenario_log(scenario(lat, seed, rate, hours, noise=False, thermal=thermal)))
    trial = thermal_spec(seed, hours)["constant"] if thermal else 0.003
    told = SensorNoise(**RLG, **(GM_RRW if gm_rrw else {}))
    t = find_true_drift(
        log,
        alignment=alignment,
        hours=hours,
        verify=False,
        trial_deg_h=trial,
        threads=1,
        noise=told if noise_mode == "given" or not noise else None,
    )
    if alignment is None:
        return task, t.drift_deg_h, t.drift_std_deg_h
    return task, t.drift_deg_h, label_sigma_deg_h(lat, SensorNoise.from_block(t.noise), hours=hours)[0]


def recorded(path: Path | None) -> dict:
    """The truths already in the results file: task -> (drift, sigma) (none without a file)."""
    if path is None or not path.exists():
        return {}
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return {tuple(r["task"]): (r["drift_deg_h"], r["sigma_deg_h"]) for r in rows}


def rms_interval(z: np.ndarray, level: float = 0.95) -> tuple[float, float, float]:
    """rms of z and its `level` interval for the scale of Gaussian z (n rms^2 / s^2 ~ chi-square, n dof)."""
    n = len(z)
    rms = float(np.sqrt(np.mean(z**2)))
    lo = rms * math.sqrt(n / chi2.ppf(0.5 + level / 2, n))
    hi = rms * math.sqrt(n / chi2.ppf(0.5 - level / 2, n))
    return rms, lo, hi


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--rate-hz", type=float, default=10.0)
    ap.add_argument("--lat-deg", default="20,40,60", help="comma-separated latitudes [deg]")
    ap.add_argument("--hours", type=float, default=72.0, help="navigation span of truth [h]")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--thermal", action="store_true", help="warm-up and daily swing, a twin per seed")
    ap.add_argument("--noise", choices=("log", "given"), default="log", help="ARW/VRW of the sigma")
    ap.add_argument("--gm-rrw", action="store_true", help="Gauss-Markov bias and rate random walk on every gyro")
    ap.add_argument("--twin-alignment", action="store_true", help="navigate each noisy run from its twin's alignment")
    ap.add_argument("--results", type=Path, help="JSON-lines file: each truth appended as made, reused when there")
    a = ap.parse_args()
    if a.gm_rrw:
        a.noise = "given"
    lats = [float(v) for v in a.lat_deg.split(",")]
    seeds = range(a.first_seed, a.first_seed + a.seeds)
    common = (a.thermal, a.noise, a.gm_rrw, a.twin_alignment)
    tasks = []
    for s in seeds:  # seed by seed across the latitudes: a study cut short has about as many at each
        for lat in lats:
            if a.thermal or s == a.first_seed:
                tasks.append((lat, s, a.rate_hz, a.hours, False, *common))
            tasks.append((lat, s, a.rate_hz, a.hours, True, *common))
    done = recorded(a.results)
    todo = [t for t in tasks if t not in done]
    out = {(t[0], t[1], t[4]): done[t] for t in tasks if t in done}
    t0 = time.perf_counter()
    with Pool(a.workers) as pool:
        for task, d, s in pool.imap(one, todo):
            out[(task[0], task[1], task[4])] = (d, s)
            if a.results is not None:
                with a.results.open("a") as f:
                    f.write(json.dumps({"task": list(task), "drift_deg_h": d, "sigma_deg_h": s}) + "\n")
    wall = time.perf_counter() - t0
    env = "thermal (warm-up + daily swing)" if a.thermal else "constant drift"
    env += ", Gauss-Markov + rate random walk" if a.gm_rrw else ""
    env += ", navigated from the twin's alignment" if a.twin_alignment else ""
    print(
        f"truth's 1-sigma: {a.seeds} seeds ({seeds[0]}-{seeds[-1]}), {a.rate_hz:g} Hz, {a.hours:g} h navigation, "
        f"{env}, noise {a.noise}; {len(todo)} truths made in {wall:.0f} s with {a.workers} worker(s), "
        f"{len(tasks) - len(todo)} read from {a.results}"
    )
    for lat in lats:
        dev, sig, dev_mean = [], [], []
        for s in seeds:
            twin = out[(lat, s if a.thermal else a.first_seed, False)][0]
            d, sigma = out[(lat, s, True)]
            dev.append(d - twin)
            sig.append(sigma)
            if a.thermal:
                dev_mean.append(d - mean_simulated_drift(s, a.hours))
        z = np.array(dev) / np.array(sig)
        rms, lo, hi = rms_interval(z)
        geometry = (
            None if a.twin_alignment else scenario(lat, a.first_seed, a.rate_hz, a.hours, noise=True, thermal=False)
        )
        simulated = label_sigma_deg_h(lat, SensorNoise(**RLG), hours=a.hours, geometry=geometry)[0]
        print(
            f"  {lat:4.0f} deg: z rms {rms:.3f} (95 % {lo:.2f}-{hi:.2f}), mean z {np.mean(z):+.2f}; observed rms "
            f"{math.sqrt(np.mean(np.square(dev))):.3e}, mean reported sigma {np.mean(sig):.3e} deg/h "
            f"({np.mean(sig) / simulated:.4f} of the simulated white densities' {simulated:.3e})"
        )
        if a.gm_rrw:
            white = label_sigma_deg_h(lat, SensorNoise(**RLG), hours=a.hours, geometry=geometry)[0]
            rms_w, lo_w, hi_w = rms_interval(np.array(dev) / white)
            print(
                f"         against the white-noise-only sigma {white:.3e} deg/h: z rms {rms_w:.3f} "
                f"(95 % {lo_w:.2f}-{hi_w:.2f})"
            )
        if a.thermal:
            zm = np.array(dev_mean) / np.array(sig)
            rms_m, lo_m, hi_m = rms_interval(zm)
            print(
                f"         against the time-averaged simulated drift instead: z rms {rms_m:.3f} "
                f"(95 % {lo_m:.2f}-{hi_m:.2f}), mean z {np.mean(zm):+.2f}"
            )


if __name__ == "__main__":
    main()
