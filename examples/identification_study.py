"""Identification on a simulated multi-latitude thermal fleet: every method against what a perfect one could know.

Run: ``python examples/identification_study.py [--train 24] [--held-out 12] [--workers 1] [--seeds 11,12,13,14]``
(5-8 minutes per fleet at the default size on one core of a loaded machine; its output is quoted in
docs/studies/2026-11-23-identification-study.md). With several seeds (``--seeds 11,12,13,14`` or ``--seeds 4``
for 11-14) it runs one fleet per seed,
``--workers`` fleets side by side, prints each fleet's report and then the targets of issue 10 per seed and as
mean +- sd.

The fleet: a reciprocating RLG INS (ARW 0.0005 deg/sqrt(h), VRW 5 ug/sqrt(Hz), random x/y gyro and accelerometer
biases and heading) at sites drawn uniformly in 20-60 deg, each run a 76 h static log at 10 Hz simulated on the
fly (`gyrodrift.ins.simulate.scenario_log`: no log files). The system warms up from 15-25 degC to 28-40 degC
(time constant 1-6 h); the axial drift is a per-run constant N(0.002, 0.0008) deg/h plus a temperature law
0.0002 deg/h/degC (T - 28 degC) (`[temperature] k1_deg_h_per_c`). The 12 h features therefore see the drift
while the system is still warming, the 72 h after them the drift at the final temperature: what physics alone
cannot know. Held-out runs are drawn the same way, except the first ``--hot`` (2) which end hotter than any
training run (43-46 degC).

For every run: the features and the label ``truth`` (criterion ``final``) of the noisy log, the 12 h curve fit
from the same navigation. For every held-out run also the simulated effective drift, ``truth`` of its noise-free
twin (the same scenario and seed with ARW and VRW off), and the 72 h navigation compensated with each method's
drift (one read, one navigator per method). Methods:

* paper-encoding LSSVM: CPSO-LSSVM (LOO MAE) on the paper's inputs (raw 12 h latitude error in arcsec, temp range);
* physics-encoding LSSVM: the same on the drift equivalent of the latitude error;
* 12 h physics inversion; 12 h curve fit (`gyrodrift.learn.curve_fit`);
* default: what ``gyrodrift fit`` does with no options (`fit_default`: the hybrid target with its default
  encoding, the temperature range; the ``auto`` physics base, which on these tables is
  ``drift_smoother_fleet_deg_h``: the 16 h smoother's end drift re-weighted with the training runs' pooled k_z,
  leave-one-out for the training runs themselves; plus the LSSVR correction learnt on label - base);
* hybrid: fleet-prior smoother, physics-encoding correction: the default's base with the correction on the
  ``physics`` encoding (the 12 h drift equivalent and the temperature range);
* hybrid: inversion + LSSVR (the default before the fleet base): 12 h inversion + LSSVR correction learnt on
  label - inversion (``physics`` encoding); and the same with the correction on the temperatures only;
* hybrid on the curve fit: the same with the curve fit as its physics column;
* 16 h Kalman smoother (`gyrodrift.procedure.smoother`): forward filter + RTS over alignment + 12 h with zero
  velocity and the known position, its thermal model (drift = eps_z + k_z (T - T_ref), T the log's temperature)
  reporting the drift at the end of the 16 h, its +-1.645 sigma as the interval; and the hybrid on it (that
  end-of-span drift as the physics column). Its reported 1-sigma is the physical limit of these 16 h: every
  method's held-out RMS is also given as a ratio to it (the rms of the held-out runs' sigmas);
* 16 h smoother, fleet k_z prior: the smoother's end drift re-weighted with the training runs' pooled k_z as the
  prior of the coefficient (`fleet_coefficient_prior`, `SmootherEstimate.end_drift_with_coefficient_prior`).

Labels carry their 1-sigma (``truth``'s covariance analysis, ``drift_std_deg_h``), so the models are fitted as
weighted LS-SVMs (`gyrodrift fit` does the same with such a table). The run records carry the smoother's k_z
columns (``smoother_coeff_deg_h_per_c`` and the three beside it), as ``gyrodrift features`` writes them.

Then the four-latitude check: one noise-free 16 h log per latitude 20/36/48/57 deg with the same IMU, drift
0.00368 deg/h and temperature, identified by the models fitted on the fleet.
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from gyrodrift.choices import default_encoding
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.learn.curve_fit import fit_error_curves
from gyrodrift.learn.drift_model import DEFAULT_MAX_LABEL_STD_DEG_H, DriftModel, fit_drift_model
from gyrodrift.learn.tuning import SearchBoundWarning
from gyrodrift.procedure import align_log, extract_features, find_true_drift, navigate_after_alignment, smooth_log
from gyrodrift.procedure.smoother import SmootherEstimate, fleet_coefficient_prior
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import RunTable

K1_DEG_H_PER_C = 0.0002
"""The fleet's temperature law [deg/h/degC] above T0_C."""
T0_C = 28.0
ARW_DEG_RTH = 0.0005
VRW_UG_RTHZ = 5.0
COVERAGE = 0.9
FOUR_LATITUDES_DEG = (20.0, 36.0, 48.0, 57.0)
FOUR_LAT_DRIFT_DEG_H = 0.00368
FIRST_SEED = 11
DEFAULT = "default (gyrodrift fit)"
OLD_DEFAULT = "hybrid: inversion + LSSVR"
FLEET_PHYSICS_ENCODING = "hybrid: fleet-prior smoother, physics-encoding correction"
PAPER = "paper-encoding LSSVM (temp_range)"


def draw_fleet(
    n_train: int,
    n_test: int,
    n_hot: int,
    seed: int,
    rate_hz: float = 10.0,
    k1: float = K1_DEG_H_PER_C,
    tau_max_h: float = 6.0,
) -> list[dict]:
    """The run specifications: site, temperatures, per-run constant, biases, heading, noise seed."""
    rng = np.random.default_rng(seed)
    specs = []
    for i in range(n_train + n_test):
        held_out = i >= n_train
        hot = held_out and (i - n_train) < n_hot
        specs.append(
            {
                "run": f"{'test' if held_out else 'train'}{i:02d}",
                "held_out": held_out,
                "lat_deg": float(rng.uniform(20.0, 60.0)),
                "start_c": float(rng.uniform(15.0, 25.0)),
                "end_c": float(rng.uniform(43.0, 46.0) if hot else rng.uniform(28.0, 40.0)),
                "tau_h": float(rng.uniform(1.0, tau_max_h)),
                "constant_deg_h": float(rng.normal(0.002, 0.0008)),
                "gyro_xy_deg_h": [float(v) for v in rng.uniform(-0.006, 0.006, 2)],
                "accel_ug": [float(v) for v in rng.uniform(-40.0, 40.0, 3)],
                "yaw_deg": float(rng.uniform(0.0, 360.0)),
                "seed": 1000 * seed + i,
                "rate_hz": rate_hz,
                "k1": k1,
            }
        )
    return specs


def scenario(
    spec: dict, *, noise: bool, duration_h: float = 76.0, rate_hz: float = 10.0, k1: float = K1_DEG_H_PER_C
) -> Scenario:
    """The run's scenario; ``noise=False`` is its noise-free twin (same everything, ARW and VRW off)."""
    return Scenario.from_dict(
        {
            "site": {"lat_deg": spec["lat_deg"]},
            "run": {"duration_h": duration_h, "rate_hz": rate_hz, "seed": spec["seed"]},
            "gyro": {
                "bias_deg_h": [*spec["gyro_xy_deg_h"], spec["constant_deg_h"]],
                "arw_deg_rth": ARW_DEG_RTH if noise else 0.0,
            },
            "accel": {"bias_ug": spec["accel_ug"], "vrw_ug_rthz": VRW_UG_RTHZ if noise else 0.0},
            "temperature": {
                "start_c": spec["start_c"],
                "end_c": spec["end_c"],
                "tau_h": spec["tau_h"],
                "t0_c": T0_C,
                "k1_deg_h_per_c": k1,
            },
            "attitude": {"yaw_deg": spec["yaw_deg"]},
        }
    )


def smoother_columns(estimate: SmootherEstimate | None) -> dict:
    """The smoother's run-table columns: its drift carried into navigation and 1-sigma [deg/h], and under the
    thermal model its k_z, k_z 1-sigma, cov(end drift, k_z) and prior 1-sigma of k_z
    (`SmootherEstimate.thermal_columns`; NaN under the constant model or without the smoother, as
    ``gyrodrift features`` writes them)."""
    if estimate is None:
        return {
            name: math.nan for name in ("drift_smoother_deg_h", "drift_smoother_std_deg_h", *SMOOTHER_THERMAL_COLUMNS)
        }
    return {
        "drift_smoother_deg_h": estimate.navigation_drift_deg_h,
        "drift_smoother_std_deg_h": estimate.navigation_drift_std_deg_h,
        **estimate.thermal_columns(),
    }


def fit_default(train: RunTable, **kwargs) -> DriftModel:
    """What ``gyrodrift fit runs.csv --out m.json`` fits: the hybrid target and its default encoding
    (temperature), the default physics base (``auto``), weighted labels, runs beyond the default label 1-sigma
    left out; ``kwargs`` go to `fit_drift_model` (tuner, iterations, seed)."""
    return fit_drift_model(
        train,
        encoding=default_encoding("residual"),
        target="residual",
        max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H,
        **kwargs,
    )


def measure_run(spec: dict, smoother: bool = True) -> dict:
    """Features, label and curve fit of the noisy run (and the 16 h smoother unless ``smoother=False``); the
    effective drift of its noise-free twin if held out."""
    log = scenario_log(scenario(spec, noise=True, rate_hz=spec["rate_hz"], k1=spec["k1"]))
    f = extract_features(log, with_truth=True, smoother=smoother)
    base = f.truth.base
    cf = fit_error_curves(base.t_h * 3600.0, base.lat_err_arcsec, base.lon_err_arcsec, f.lat0_deg, hours=12.0)
    out = {
        "run": spec["run"],
        "lat_deg": f.lat_deg,
        "lat0_deg": f.lat0_deg,
        "temp_min_c": f.temp_min_c,
        "temp_max_c": f.temp_max_c,
        "drift_deg_h": f.drift_deg_h,
        "drift_curvefit_deg_h": cf.drift_deg_h,
        "drift_curvefit_std_deg_h": cf.drift_std_deg_h,
        **smoother_columns(f.smoother),
        "drift_std_deg_h": f.drift_std_deg_h,
        "label_flagged": f.label_flagged,
    }
    if f.smoother is not None:
        out["smoother_estimate"] = f.smoother  # for the fleet k_z prior (not a run-table column)
    if spec["held_out"]:
        twin = scenario(spec, noise=False, rate_hz=spec["rate_hz"], k1=spec["k1"])
        out["effective_deg_h"] = find_true_drift(scenario_log(twin)).drift_deg_h
    return out


def navigate_compensated(spec: dict, drifts: list[float]) -> list[float]:
    """Position error [nmi] at hour 72 of the noisy run compensated with each drift [deg/h] (one read)."""
    log = scenario_log(scenario(spec, noise=True, rate_hz=spec["rate_hz"], k1=spec["k1"]))
    res = navigate_after_alignment(log, align_log(log), drifts, 72.0)
    return [float(c.final_nmi) for c in res.curves]


def four_latitude_features(rate_hz: float = 10.0) -> RunTable:
    """Noise-free 16 h logs at ``FOUR_LATITUDES_DEG`` with the same IMU, drift and temperature."""
    rows = []
    for k, lat in enumerate(FOUR_LATITUDES_DEG):
        spec = {
            "lat_deg": lat,
            "start_c": 20.0,
            "end_c": 34.0,
            "tau_h": 3.0,
            "constant_deg_h": FOUR_LAT_DRIFT_DEG_H,
            "gyro_xy_deg_h": [0.004, -0.003],
            "accel_ug": [20.0, -10.0, 5.0],
            "yaw_deg": 30.0,
            "seed": 77 + k,
        }
        s = scenario(spec, noise=False, duration_h=16.0, rate_hz=rate_hz, k1=0.0)  # the drift stays 0.00368
        log = scenario_log(s)
        res = navigate_after_alignment(log, align_log(log), [0.0], 12.0, temperature_hours=12.0)
        c = res.curves[0]
        cf = fit_error_curves(c.t_h * 3600.0, c.lat_err_arcsec, c.lon_err_arcsec, lat, hours=12.0)
        sm = smooth_log(log)
        rows.append(
            {
                "run": f"lat{lat:g}",
                "lat_deg": float(c.hourly_lat_deg[12]),
                "lat0_deg": lat,
                "temp_min_c": res.temperature.min_c,
                "temp_max_c": res.temperature.max_c,
                "drift_curvefit_deg_h": cf.drift_deg_h,
                **smoother_columns(sm),
            }
        )
    return RunTable.from_records(rows, source="four latitudes")


def _map(fn, items, workers: int):
    if workers <= 1:
        return [fn(x) for x in items]
    with ProcessPoolExecutor(workers) as pool:
        return list(pool.map(fn, items))


def _nav_job(args):
    return navigate_compensated(*args)


def run_study(
    n_train: int = 24,
    n_test: int = 12,
    n_hot: int = 2,
    seed: int = 11,
    workers: int = 1,
    max_iter: int = 100,
    four_latitudes: bool = True,
    quiet: bool = False,
    rate_hz: float = 10.0,
    k1: float = K1_DEG_H_PER_C,
    tau_max_h: float = 6.0,
) -> dict:
    """The whole study; returns a dict of per-method numbers (see ``print_report``)."""
    t_start = time.perf_counter()
    specs = draw_fleet(n_train, n_test, n_hot, seed, rate_hz, k1, tau_max_h)
    rows = _map(measure_run, specs, workers)
    if not quiet:
        print(f"simulated and measured {len(rows)} runs in {time.perf_counter() - t_start:.0f} s", flush=True)
    records = [{k: v for k, v in r.items() if k not in ("effective_deg_h", "smoother_estimate")} for r in rows]
    table = RunTable.from_records(records, source="simulated fleet")
    train, test = table.select(np.arange(n_train)), table.select(np.arange(n_train, n_train + n_test))
    effective = np.array([r["effective_deg_h"] for r in rows[n_train:]])
    tuner = dict(method="cpso", objective="loo_mae", max_iter=max_iter, rng=0, quiet=True)
    common = dict(max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H, **tuner)
    models = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SearchBoundWarning)
        models[PAPER] = fit_drift_model(train, encoding="temp_range", **common)
        models["physics-encoding LSSVM"] = fit_drift_model(train, encoding="physics", **common)
        models[DEFAULT] = fit_default(train, **tuner)
        models[FLEET_PHYSICS_ENCODING] = fit_drift_model(
            train, encoding="physics", target="residual", physics_column="drift_smoother_fleet_deg_h", **common
        )
        models[OLD_DEFAULT] = fit_drift_model(
            train, encoding="physics", target="residual", physics_column="drift_inversion_deg_h", **common
        )
        models["hybrid, temperature-only correction"] = fit_drift_model(
            train, encoding="temperature", target="residual", physics_column="drift_inversion_deg_h", **common
        )
        models["hybrid: curve fit + LSSVR"] = fit_drift_model(
            train, encoding="physics", target="residual", physics_column="drift_curvefit_deg_h", **common
        )
        models["hybrid: 16 h smoother + LSSVR"] = fit_drift_model(
            train, encoding="physics", target="residual", physics_column="drift_smoother_deg_h", **common
        )
    edge_warnings = sorted({str(w.message) for w in caught if issubclass(w.category, SearchBoundWarning)})
    z90 = 1.6448536269514722
    methods: dict[str, dict] = {}
    for name, model in models.items():
        pred, lo, hi = model.predict_interval(test, COVERAGE)
        check = model.check_inputs(test)
        methods[name] = {"pred": pred, "lo": lo, "hi": hi, "flagged": check.outside, "model": model}
    cf, cf_std = test.column("drift_curvefit_deg_h"), test.column("drift_curvefit_std_deg_h")
    methods["12 h physics inversion"] = {"pred": physics_inversion(test)}
    methods["12 h curve fit"] = {"pred": cf, "lo": cf - z90 * cf_std, "hi": cf + z90 * cf_std}
    sm, sm_std = test.column("drift_smoother_deg_h"), test.column("drift_smoother_std_deg_h")
    methods["16 h Kalman smoother"] = {"pred": sm, "lo": sm - z90 * sm_std, "hi": sm + z90 * sm_std}
    # The smoother's end drift with the training runs' k_z as its prior (what the fleet knows of the coefficient).
    fleet_prior = fleet_coefficient_prior([r["smoother_estimate"] for r in rows[:n_train]])
    fleet = np.array([r["smoother_estimate"].end_drift_with_coefficient_prior(*fleet_prior) for r in rows[n_train:]])
    fp, fp_std = fleet[:, 0], fleet[:, 1]
    methods["16 h smoother, fleet k_z prior"] = {"pred": fp, "lo": fp - z90 * fp_std, "hi": fp + z90 * fp_std}
    names = list(methods)
    held_specs = specs[n_train:]
    nav = _map(
        _nav_job, [(s, [float(methods[n]["pred"][i]) for n in names]) for i, s in enumerate(held_specs)], workers
    )
    nav = np.array(nav)  # (n_test, n_methods)
    out_of_range = (
        (test.temp_max_c > train.temp_max_c.max())
        | (test.temp_min_c < train.temp_min_c.min())
        | (test.temp_min_c > train.temp_min_c.max())
        | (test.temp_max_c < train.temp_max_c.min())
    )
    results = {
        "methods": {},
        "n_train": n_train,
        "n_test": n_test,
        "out_of_range": out_of_range,
        "effective": effective,
        "truth": test.drift_deg_h,
        "edge_warnings": edge_warnings,
        "seed": seed,
        "default_physics_column": models[DEFAULT].physics_column_,
        "default_encoding": models[DEFAULT].encoding,
        "default_coefficient_prior": models[DEFAULT].coefficient_prior_,
    }
    for j, name in enumerate(names):
        m = methods[name]
        e_eff = effective - m["pred"]
        e_tru = test.drift_deg_h - m["pred"]
        entry = {
            "pred": np.asarray(m["pred"], float),
            "bias_eff": float(np.mean(e_eff)),
            "rms_eff": float(np.sqrt(np.mean(e_eff**2))),
            "max_eff": float(np.max(np.abs(e_eff))),
            "rms_truth": float(np.sqrt(np.mean(e_tru**2))),
            "max_truth": float(np.max(np.abs(e_tru))),
            "under_1nmi": int(np.sum(nav[:, j] < 1.0)),
            "final_nmi": nav[:, j],
        }
        if "lo" in m:
            entry["coverage_eff"] = float(np.mean((m["lo"] <= effective) & (effective <= m["hi"])))
            entry["coverage_truth"] = float(np.mean((m["lo"] <= test.drift_deg_h) & (test.drift_deg_h <= m["hi"])))
            entry["half_width_in"] = float(np.mean((m["hi"] - m["lo"])[~out_of_range]) / 2)
            entry["half_width_out"] = (
                float(np.mean((m["hi"] - m["lo"])[out_of_range]) / 2) if out_of_range.any() else math.nan
            )
        if "flagged" in m:
            entry["flagged"] = int(np.sum(m["flagged"]))
            entry["out_of_range_flagged"] = int(np.sum(m["flagged"] & out_of_range))
        results["methods"][name] = entry
    results["label_error_rms"] = float(np.sqrt(np.mean((test.drift_deg_h - effective) ** 2)))
    results["smoother_sigma_rms"] = float(np.sqrt(np.mean(sm_std**2)))
    results["fleet_prior"] = (*fleet_prior, float(np.sqrt(np.mean(fp_std**2))))
    results["label_sigma_rms"] = float(np.sqrt(np.mean(test.column("drift_std_deg_h") ** 2)))
    if four_latitudes:
        four = four_latitude_features(rate_hz)
        results["four_latitudes"] = {name: methods[name]["model"].predict(four) for name in models}
        results["four_latitudes"]["12 h physics inversion"] = physics_inversion(four)
        results["four_latitudes"]["16 h Kalman smoother"] = four.column("drift_smoother_deg_h")
    results["elapsed_s"] = time.perf_counter() - t_start
    return results


def print_report(r: dict) -> None:
    """The numbers docs/studies/2026-11-23-identification-study.md quotes."""
    print(
        f"{r['n_train']} training runs, {r['n_test']} held out ({int(np.sum(r['out_of_range']))} outside the training "
        f"temperature range); labels (noisy truth) vs effective drift: rms {r['label_error_rms']:.2e} deg/h"
    )
    w = max(len(n) for n in r["methods"])
    head = (
        f"{'method':{w}s} {'mean eff':>9s} {'rms eff':>9s} {'max eff':>9s} {'rms truth':>9s} {'max truth':>9s} "
        f"{'cov90':>6s} {'hw in/out':>17s} {'<1nmi':>6s} {'flagged':>8s}"
    )
    print(head)
    for name, m in r["methods"].items():
        cov = f"{100 * m['coverage_eff']:5.0f}%" if "coverage_eff" in m else "     -"
        hw = f"{m['half_width_in']:.1e}/{m['half_width_out']:.1e}" if "half_width_in" in m else "-"
        fl = (
            f"{m['out_of_range_flagged']}/{int(np.sum(r['out_of_range']))}+{m['flagged'] - m['out_of_range_flagged']}"
            if "flagged" in m
            else "-"
        )
        print(
            f"{name:{w}s} {m['bias_eff']:9.2e} {m['rms_eff']:9.2e} {m['max_eff']:9.2e} {m['rms_truth']:9.2e} "
            f"{m['max_truth']:9.2e} "
            f"{cov:>6s} {hw:>17s} {m['under_1nmi']:3d}/{r['n_test']:<2d} {fl:>8s}"
        )
    prior = r["default_coefficient_prior"]
    print(
        f"default's physics base: {r['default_physics_column']}"
        + (f" (k_z prior {prior[0]:.2e} +- {prior[1]:.2e} deg/h/degC)" if prior is not None else "")
        + f"; its correction's encoding: {r['default_encoding']}"
    )
    k = key_numbers(r)
    print(f"default / paper-encoding held-out RMS (vs effective drift): {k['vs_paper']:.2f} (target <= 0.7)")
    limit = r["smoother_sigma_rms"]
    print(
        f"16 h smoother's reported 1-sigma (rms over the held-out runs): {limit:.2e} deg/h; labels' 1-sigma "
        f"(truth's covariance analysis): {r['label_sigma_rms']:.2e} deg/h (observed {r['label_error_rms']:.2e})"
    )
    print(f"default held-out RMS / smoother's sigma: {k['vs_sigma']:.2f} (target <= 1.3)")
    k_mean, k_std, fp_sigma = r["fleet_prior"]
    print(
        f"fleet k_z prior from the training runs' smoothers: {k_mean:.2e} +- {k_std:.2e} deg/h/degC; the smoother's "
        f"1-sigma with it (rms over the held-out runs): {fp_sigma:.2e} deg/h; default's RMS / it: "
        f"{k['vs_fleet_sigma']:.2f}"
    )
    print("held-out RMS (vs effective drift) / smoother's sigma:")
    for name, m in r["methods"].items():
        print(f"  {name:{w}s} {m['rms_eff'] / limit:5.2f}")
    if r["edge_warnings"]:
        for msg in r["edge_warnings"]:
            print(f"fit warned: {msg}")
    if "four_latitudes" in r:
        print(
            f"same drift {FOUR_LAT_DRIFT_DEG_H} deg/h, noise-free, at "
            f"{', '.join(f'{v:g}' for v in FOUR_LATITUDES_DEG)} deg:"
        )
        for name, pred in r["four_latitudes"].items():
            print(f"  {name:{w}s} {' '.join(f'{p:.6f}' for p in pred)}  spread {np.ptp(pred):.1e} deg/h")
    print(f"elapsed {r['elapsed_s']:.0f} s")


KEY_NUMBERS = (
    ("vs_sigma", "held-out RMS / smoother's sigma", "<= 1.3"),
    ("vs_paper", "held-out RMS / paper-encoding LSSVM's", "<= 0.7"),
    ("vs_fleet_sigma", "held-out RMS / fleet-prior smoother's sigma", "<= 1.3"),
    ("coverage", "90 % interval covers (effective drift)", "0.8-0.97"),
    ("under_1nmi", "share of runs under 1 nmi at 72 h", "-"),
    ("four_lat_spread", "four-latitude spread [deg/h]", "<= 5e-5"),
    ("out_flagged", "runs outside the range flagged (share)", "1"),
)
"""The issue-10 targets reported per seed (key, what, target)."""


def key_numbers(r: dict, name: str = DEFAULT) -> dict:
    """The issue-10 target quantities of method ``name`` in one study's results ``r`` (see ``KEY_NUMBERS``)."""
    m = r["methods"][name]
    n_out = int(np.sum(r["out_of_range"]))
    return {
        "vs_sigma": m["rms_eff"] / r["smoother_sigma_rms"],
        "vs_paper": m["rms_eff"] / r["methods"][PAPER]["rms_eff"],
        "vs_fleet_sigma": m["rms_eff"] / r["fleet_prior"][2],
        "coverage": m.get("coverage_eff", math.nan),
        "under_1nmi": m["under_1nmi"] / r["n_test"],
        "four_lat_spread": float(np.ptp(r["four_latitudes"][name]))
        if name in r.get("four_latitudes", {})
        else math.nan,
        "out_flagged": m["out_of_range_flagged"] / n_out if "flagged" in m and n_out else math.nan,
    }


def mean_sd(v) -> tuple[float, float]:
    """The mean and the sample standard deviation (ddof 1) of the finite values of ``v`` (NaN when there are
    none, the sd NaN with fewer than two)."""
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    return (float(np.mean(v)) if v.size else math.nan), (float(np.std(v, ddof=1)) if v.size > 1 else math.nan)


def _fmt(key: str, v: float) -> str:
    return f"{v:.1e}" if key == "four_lat_spread" else f"{v:.2f}"


def print_seeds_summary(results: list[dict]) -> None:
    """Per seed and mean +- sd over the seeds: the default's issue-10 quantities, then every method's held-out RMS
    over the smoother's sigma and over the paper-encoding LSSVM's."""
    seeds = [r["seed"] for r in results]
    print(f"\n== {len(seeds)} fleets (seeds {', '.join(map(str, seeds))}): the default against the targets ==")
    print(f"default's physics base per seed: {', '.join(sorted({r['default_physics_column'] for r in results}))}")
    head = "".join(f"{'s' + str(s):>9s}" for s in seeds)
    print(f"{'quantity':46s} {'target':>8s}{head}  {'mean +- sd':>18s}")
    for name in (DEFAULT, FLEET_PHYSICS_ENCODING, OLD_DEFAULT):
        print(f"{name}:")
        per_seed = [key_numbers(r, name) for r in results]
        for key, what, target in KEY_NUMBERS:
            v = np.array([p[key] for p in per_seed])
            cells = "".join(f"{_fmt(key, x):>9s}" for x in v)
            print(f"  {what:44s} {target:>8s}{cells}  {_fmt(key, mean_sd(v)[0]):>8s} +- {_fmt(key, mean_sd(v)[1])}")
    print("every method, held-out RMS (vs effective drift) / smoother's sigma, and / paper-encoding LSSVM's:")
    w = max(len(n) for n in results[0]["methods"])
    print(f"  {'method':{w}s}{head}  {'mean +- sd':>12s}; {'/ paper':>7s} mean +- sd")
    for name in results[0]["methods"]:
        a = np.array([[key_numbers(r, name)[k] for k in ("vs_sigma", "vs_paper")] for r in results])
        cells = "".join(f"{x:>9.2f}" for x in a[:, 0])
        (m0, s0), (m1, s1) = mean_sd(a[:, 0]), mean_sd(a[:, 1])
        print(f"  {name:{w}s}{cells}  {m0:.2f} +- {s0:.2f}; / paper {m1:.2f} +- {s1:.2f}")


def _study_job(args: tuple[int, dict]) -> dict:
    seed, kwargs = args
    return run_study(seed=seed, workers=1, quiet=True, **kwargs)


def run_seeds(seeds, workers: int = 1, **kwargs):
    """``run_study`` on one fleet per seed; with ``workers`` > 1 the fleets run side by side (each simulated on one
    core), else one after the other with ``workers`` processes simulating each fleet's runs. Yields each fleet's
    results in seed order."""
    seeds = list(seeds)
    if workers <= 1 or len(seeds) == 1:
        for seed in seeds:
            yield run_study(seed=seed, workers=workers, **kwargs)
        return
    with ProcessPoolExecutor(min(workers, len(seeds))) as pool:
        yield from pool.map(_study_job, [(s, kwargs) for s in seeds])


def _measure_smoothed(spec: dict) -> dict:
    return measure_run(spec, smoother=True)


def coverage_study(
    seeds, n_train: int = 24, n_test: int = 24, n_hot: int = 2, rate_hz: float = 2.0, workers: int = 1
) -> dict:
    """Coverage of the 90 % intervals over several fleets (one per seed), without the navigation or the
    four-latitude check, for the default model (`fit_default`, on the fleet-prior smoother base: the runs are
    measured with the smoother), the same base with the physics-encoding correction and the earlier default
    (inversion + LSSVR) on the same runs: per seed the share
    of held-out runs whose effective drift (and whose label) the interval covers, in range and flagged, the
    half-width of the hot runs over that of the runs in range, and the held-out RMS against the effective drift.
    Returns ``{model name: {quantity: per-seed array}}`` plus ``"seeds"`` and prints nothing."""
    keys = (
        "coverage_eff",
        "coverage_truth",
        "coverage_in_range",
        "coverage_flagged",
        "hot_half_width_ratio",
        "rms_eff",
    )
    per: dict[str, list[list[float]]] = {DEFAULT: [], FLEET_PHYSICS_ENCODING: [], OLD_DEFAULT: []}
    physics_columns = []
    for seed in seeds:
        specs = draw_fleet(n_train, n_test, n_hot, seed, rate_hz)
        rows = _map(_measure_smoothed, specs, workers)
        table = RunTable.from_records(
            [{k: v for k, v in r.items() if k not in ("effective_deg_h", "smoother_estimate")} for r in rows],
            source=f"fleet {seed}",
        )
        train, test = table.select(np.arange(n_train)), table.select(np.arange(n_train, n_train + n_test))
        effective = np.array([r["effective_deg_h"] for r in rows[n_train:]])
        hot = np.arange(n_test) < n_hot
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SearchBoundWarning)
            models = {
                DEFAULT: fit_default(train, rng=0),
                FLEET_PHYSICS_ENCODING: fit_drift_model(
                    train,
                    encoding="physics",
                    target="residual",
                    physics_column="drift_smoother_fleet_deg_h",
                    max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H,
                    rng=0,
                ),
                OLD_DEFAULT: fit_drift_model(
                    train,
                    encoding="physics",
                    target="residual",
                    physics_column="drift_inversion_deg_h",
                    max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H,
                    rng=0,
                ),
            }
        physics_columns.append(models[DEFAULT].physics_column_)
        for name, model in models.items():
            pred, lo, hi = model.predict_interval(test, COVERAGE)
            flagged = model.check_inputs(test).outside
            cov = (lo <= effective) & (effective <= hi)
            half = (hi - lo) / 2
            per[name].append(
                [
                    float(np.mean(cov)),
                    float(np.mean((lo <= test.drift_deg_h) & (test.drift_deg_h <= hi))),
                    float(np.mean(cov[~flagged])) if (~flagged).any() else math.nan,
                    float(np.mean(cov[flagged])) if flagged.any() else math.nan,
                    float(np.mean(half[hot]) / np.mean(half[~flagged])) if hot.any() and (~flagged).any() else math.nan,
                    float(np.sqrt(np.mean((effective - pred) ** 2))),
                ]
            )
    out: dict = {"seeds": list(seeds), "default_physics_columns": physics_columns}
    for name, rows_cov in per.items():
        a = np.array(rows_cov)
        out[name] = {key: a[:, j] for j, key in enumerate(keys)}
    return out


def print_coverage(c: dict, n_test: int) -> None:
    """The coverage numbers docs/studies/2026-11-23-identification-study.md quotes (mean and sd over the seeds)."""
    print(
        f"90 % intervals over {len(c['seeds'])} fleets of {n_test} held-out runs (default's physics base: "
        f"{', '.join(sorted(set(c['default_physics_columns'])))}):"
    )
    names = (DEFAULT, FLEET_PHYSICS_ENCODING, OLD_DEFAULT)
    short = ("default (gyrodrift fit)", "fleet base, physics enc.", "inversion + LSSVR")
    print(f"  {'':30s} " + " ".join(f"{n:>26s}" for n in short))
    for key, what in (
        ("coverage_eff", "covers the effective drift"),
        ("coverage_truth", "covers the label (noisy truth)"),
        ("coverage_in_range", "effective drift, runs in range"),
        ("coverage_flagged", "effective drift, flagged runs"),
        ("hot_half_width_ratio", "half-width hot / in range"),
        ("rms_eff", "held-out RMS [deg/h]"),
    ):
        cells = []
        for name in names:
            v = c[name][key]
            f = ".2e" if key == "rms_eff" else ".3f"
            mean, sd = mean_sd(v)
            cells.append(f"mean {mean:{f}} sd {sd:{f}}")
        print(f"  {what:30s} " + " ".join(f"{c:>26s}" for c in cells))


def parse_seeds(text: str) -> list[int]:
    """``--seeds``: a comma-separated list of seeds (``11,12,13``), or one number N meaning N seeds from 11."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [int(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seeds like 11,12,13 or a count like 4, got {text!r}") from None
    if len(values) == 1:
        if values[0] < 1:
            raise argparse.ArgumentTypeError(f"expected a positive count of seeds, got {text!r}")
        return list(range(FIRST_SEED, FIRST_SEED + values[0]))
    return values


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train", type=int, default=24)
    ap.add_argument("--held-out", type=int, default=12)
    ap.add_argument("--hot", type=int, default=2, help="held-out runs hotter than any training run")
    ap.add_argument(
        "--seeds",
        type=parse_seeds,
        default=[FIRST_SEED],
        help=f"fleets: seeds separated by commas (11,12,13,14), or a count N (seeds {FIRST_SEED}..{FIRST_SEED}+N-1); "
        f"default {FIRST_SEED}",
    )
    ap.add_argument(
        "--workers",
        type=int,
        default=1,
        help="processes: runs simulated side by side (one seed), or fleets side by side (several seeds)",
    )
    ap.add_argument("--k1", type=float, default=K1_DEG_H_PER_C, help="temperature law [deg/h/degC]")
    ap.add_argument("--tau-max-h", type=float, default=6.0, help="longest warm-up time constant [h]")
    ap.add_argument(
        "--coverage-seeds",
        type=int,
        default=0,
        help="instead of the study: the intervals' coverage over this many fleets (seeds 1..N, --train training "
        "and 2 x --held-out held-out runs each, 2 Hz with the smoother, no navigation)",
    )
    args = ap.parse_args()
    t0 = time.perf_counter()
    if args.coverage_seeds:
        print(
            f"python examples/identification_study.py --coverage-seeds {args.coverage_seeds} --train {args.train} "
            f"--held-out {args.held_out} --hot {args.hot}"
        )
        c = coverage_study(
            range(1, args.coverage_seeds + 1), args.train, 2 * args.held_out, args.hot, 2.0, args.workers
        )
        print_coverage(c, 2 * args.held_out)
        print(f"wall time {time.perf_counter() - t0:.0f} s")
        return
    print(
        f"python examples/identification_study.py --train {args.train} --held-out {args.held_out} --hot {args.hot} "
        f"--seeds {','.join(map(str, args.seeds))} --k1 {args.k1:g} --tau-max-h {args.tau_max_h:g}"
    )
    results = []
    for r in run_seeds(
        args.seeds,
        args.workers,
        n_train=args.train,
        n_test=args.held_out,
        n_hot=args.hot,
        k1=args.k1,
        tau_max_h=args.tau_max_h,
    ):
        if len(args.seeds) > 1:
            print(f"\n== seed {r['seed']} ==")
        print_report(r)
        results.append(r)
    if len(results) > 1:
        print_seeds_summary(results)
    print(f"wall time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
