"""Interval quality over many closed-form fleets: coverage and width of the default model's 90 % interval.

Run: ``python examples/interval_study.py [--sizes 8,16,24,48,140] [--seeds 8] [--held-out 300] [--before]``
(``--seeds 8`` means seeds 1-8, or a list ``--seeds 1,2,3``; about 2 minutes per seed with the default sizes on
one core of a loaded 2-core machine). docs/studies/2026-11-27-intervals.md quotes its output.

No log is simulated: each run is drawn in closed form (`draw_runs`), as an RLG-grade unit on a static base would
be seen by ``gyrodrift features`` and ``truth``:

* temperature: a warm-up from 15-25 degC to 28-40 degC (time constant 1-6 h) and a daily swing of 0.5-2 degC
  amplitude, random phase (24 h period); the features' 12 h window is hours 4-16, the 72 h navigation hours 16-88;
* drift: a per-run constant N(0.002, 0.0008) deg/h plus a thermal law k (T - 28 degC), k ~ N(2e-4, 3e-5)
  deg/h/degC per unit; the effective drift (what a perfect method could know, what the 72 h navigation needs) is
  the drift averaged over hours 16-88;
* the 12 h latitude: the latitude error of the drift averaged over hours 4-16 (`latitude_error_at`) plus 8 arcsec
  of noise; the label (``truth``): the effective drift plus N(0, s^2), s = 1.5e-4 / sin(2 lat) deg/h
  (``drift_std_deg_h``, 1.5e-4 at 45 deg);
* the 16 h smoother: the exact linear-Gaussian posterior of (drift at hour 16, k) from a correlated measurement
  of both (1-sigmas 3e-4 cos(20 deg) / cos(lat) deg/h and 2e-4 deg/h/degC, correlation 0.8) and the smoother's
  own prior N(0, 0.01^2) on k: the columns ``drift_smoother_deg_h``, its 1-sigma and the four thermal ones, so
  ``physics_column="auto"`` takes the fleet base (as in tests/procedure/test_fleet_base.py).

Training runs at 20-60 deg; held-out runs (``--held-out`` per fleet): three quarters drawn as the training runs,
one quarter outside their range (half at 14.5-20 or 60-64 deg, half ending 4-10 degC hotter than any training
run can). Each fleet is fitted as ``gyrodrift fit`` does with no options (`fit_drift_model` with
``target="residual"``, ``encoding="temperature"``, the swarm seeded 0). Per fleet: the coverage of the nominal
90 % interval (of the held-out labels, and of the effective drifts), the median half-width, the held-out RMS
error against the effective drift, and what the interval rests on. Per size: pooled coverage, median over fleets
of width / RMS with its min-max. ``--before`` adds, on the same fleets, the interval this replaced (10 re-tuned
calibration folds, the jackknife order statistic of their scores): 11 tunings per fit.
"""

from __future__ import annotations

import argparse
import math
import time
import warnings

import numpy as np

from gyrodrift.learn.baselines import latitude_error_at
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.interval import jackknife_half_width
from gyrodrift.runs.columns import SMOOTHER_COLUMNS, SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import RunTable
from gyrodrift.units import HOUR

K_PRIOR_STD = 0.01
"""The smoother's own prior 1-sigma of k [deg/h/degC]."""


def _temperature(t_h, start, end, tau_h, swing, phase):
    """Temperature [degC] at hours ``t_h`` (rows: runs, columns: times)."""
    return (
        end[:, None]
        + (start - end)[:, None] * np.exp(-t_h[None, :] / tau_h[:, None])
        + swing[:, None] * np.sin(2 * math.pi * t_h[None, :] / 24.0 + phase[:, None])
    )


def draw_runs(rng, n: int, *, n_lat_out: int = 0, n_hot: int = 0, prefix: str = "r") -> tuple[RunTable, np.ndarray]:
    """``(runs, effective)``: ``n`` closed-form runs (module docstring) and their effective drifts [deg/h].

    Drawn as training runs (20-60 deg, ending 28-40 degC) but the last ``n_lat_out + n_hot``: first
    ``n_lat_out`` at 14.5-20 or 60-64 deg, then ``n_hot`` ending 44-50 degC (4-10 degC beyond any training run)."""
    kind = np.array(["train"] * (n - n_lat_out - n_hot) + ["lat_out"] * n_lat_out + ["hot"] * n_hot)
    low = rng.random(n) < 0.5
    lat_out = np.where(low, rng.uniform(14.5, 20.0, n), rng.uniform(60.0, 64.0, n))
    lat0 = np.where(kind == "lat_out", lat_out, rng.uniform(20.0, 60.0, n))
    end = np.where(kind == "hot", rng.uniform(44.0, 50.0, n), rng.uniform(28.0, 40.0, n))
    start = rng.uniform(15.0, 25.0, n)
    tau_h = rng.uniform(1.0, 6.0, n)
    swing = rng.uniform(0.5, 2.0, n)
    phase = rng.uniform(0.0, 2 * math.pi, n)
    const = rng.normal(0.002, 8e-4, n)
    k = rng.normal(2e-4, 3e-5, n)
    window = np.linspace(4.0, 16.0, 73)  # the features' 12 h, every 10 min
    nav = np.linspace(16.0, 88.0, 433)
    temp12 = _temperature(window, start, end, tau_h, swing, phase)
    drift12 = const + k * (temp12.mean(axis=1) - 28.0)
    effective = const + k * (_temperature(nav, start, end, tau_h, swing, phase).mean(axis=1) - 28.0)
    end_drift = const + k * (_temperature(np.array([16.0]), start, end, tau_h, swing, phase)[:, 0] - 28.0)
    label_std = 1.5e-4 / np.sin(np.radians(2 * lat0))
    label = effective + label_std * rng.normal(size=n)
    lat12 = lat0 + (latitude_error_at(12 * HOUR, drift12, lat0) + rng.normal(0.0, 8.0, n)) / 3600.0
    a = 3e-4 * math.cos(math.radians(20.0)) / np.cos(np.radians(lat0))
    c, rho = 2e-4, 0.8
    cols = {name: np.empty(n) for name in SMOOTHER_COLUMNS}
    for i in range(n):
        meas_cov = np.array([[a[i] ** 2, rho * a[i] * c], [rho * a[i] * c, c**2]])
        y = np.array([end_drift[i], k[i]]) + np.linalg.cholesky(meas_cov) @ rng.normal(size=2)
        post = np.linalg.inv(np.linalg.inv(meas_cov) + np.diag([0.0, 1.0 / K_PRIOR_STD**2]))
        m = post @ np.linalg.solve(meas_cov, y)
        cols["drift_smoother_deg_h"][i], cols["drift_smoother_std_deg_h"][i] = m[0], math.sqrt(post[0, 0])
        cols[SMOOTHER_THERMAL_COLUMNS[0]][i], cols[SMOOTHER_THERMAL_COLUMNS[1]][i] = m[1], math.sqrt(post[1, 1])
        cols[SMOOTHER_THERMAL_COLUMNS[2]][i], cols[SMOOTHER_THERMAL_COLUMNS[3]][i] = post[0, 1], K_PRIOR_STD
    table = RunTable(
        run=np.array([f"{prefix}{i}" for i in range(n)], dtype=object),
        lat_deg=lat12,
        lat0_deg=lat0,
        temp_min_c=temp12.min(axis=1),
        temp_max_c=temp12.max(axis=1),
        drift_deg_h=label,
        source="closed-form fleet",
        extra={"drift_std_deg_h": label_std, **cols},
    )
    return table, effective


def held_out(rng, n: int) -> tuple[RunTable, np.ndarray, np.ndarray]:
    """``(runs, effective, outside)``: ``n`` held-out runs, a quarter of them outside the training range (half in
    latitude, half hotter); ``outside`` marks those drawn outside."""
    n_out = n // 4
    runs, effective = draw_runs(rng, n, n_lat_out=n_out - n_out // 2, n_hot=n_out // 2, prefix="h")
    return runs, effective, np.r_[np.zeros(n - n_out, bool), np.ones(n_out, bool)]


def before(train: RunTable, test: RunTable, coverage: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
    """``(pred, half)``: the interval before issue 20 on the same fleet: the default model with 10 re-tuned
    calibration folds, the jackknife order statistic ``q`` of their scores, ``q sqrt(spread^2 + s_rms^2 + b^2)``
    (no cap)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = fit_drift_model(train, encoding="temperature", target="residual", rng=0, calibration_folds=10)
    q = jackknife_half_width(model.interval_scores(), coverage)
    _, base_std = model.base_.predict(test, with_std=True)
    half = q * np.sqrt(model.predict_spread(test) ** 2 + model.interval_.label_std_rms_**2 + base_std**2)
    return model.predict(test), half


def one_fleet(n_train: int, seed: int, n_held: int, coverage: float = 0.9, with_before: bool = False) -> dict:
    """Fit the default model on ``n_train`` runs of fleet ``seed`` and measure its interval on ``n_held`` runs
    (``with_before``: also the interval before issue 20, `before`)."""
    rng = np.random.default_rng([seed, n_train])
    train, _ = draw_runs(rng, n_train)
    test, effective, outside = held_out(rng, n_held)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = fit_drift_model(train, encoding="temperature", target="residual", rng=0)
    seconds = time.perf_counter() - t0
    pred, lo, hi = model.predict_interval(test, coverage)
    half = (hi - lo) / 2
    err = effective - pred
    summary = model.interval_summary(coverage)
    # the held-out runs' scores, normalised as the training runs' (their own label 1-sigma): their rms against the
    # scale of the training runs' leave-one-out scores measures the optimism of tuning on those (`tuning_inflation`)
    learned = np.minimum(model.predict_spread(test), model.interval_.learned_cap_deg_h_)
    _, base_std = model.base_.predict(test, with_std=True)
    z = (test.drift_deg_h - pred) / np.sqrt(learned**2 + test.column("drift_std_deg_h") ** 2 + base_std**2)
    return {
        "n_train": n_train,
        "seed": seed,
        "cover_label": float(np.mean((lo <= test.drift_deg_h) & (test.drift_deg_h <= hi))),
        "cover_effective": float(np.mean((lo <= effective) & (effective <= hi))),
        "cover_effective_outside": float(np.mean(((lo <= effective) & (effective <= hi))[outside])),
        "half_median": float(np.median(half)),
        "rms": float(np.sqrt(np.mean(err**2))),
        "rms_inside": float(np.sqrt(np.mean(err[~outside] ** 2))),
        "half_outside_ratio": float(np.median(half[outside]) / np.median(half[~outside])),
        "seconds": seconds,
        "z_heldout_rms": float(np.sqrt(np.mean(z[~outside] ** 2))),
        "z_loo_scale": model.interval_.scale_.scale / model.interval_.scale_.inflation,
        "summary": summary,
        "warnings": [str(w.message) for w in caught if "interval" in str(w.message)],
    } | (_before_numbers(train, test, effective, coverage) if with_before else {})


def _before_numbers(train, test, effective, coverage) -> dict:
    pred, half = before(train, test, coverage)
    rms = float(np.sqrt(np.mean((effective - pred) ** 2)))
    inside = np.abs(test.drift_deg_h - pred) <= half
    return {"before_cover_label": float(np.mean(inside)), "before_ratio": float(np.median(half)) / rms}


def parse_list(text: str) -> list[int]:
    return [int(v) for v in text.split(",") if v.strip()]


def parse_seeds(text: str) -> list[int]:
    """``--seeds``: a comma-separated list (``1,2,3``) or one number N meaning seeds 1..N."""
    values = parse_list(text)
    return list(range(1, values[0] + 1)) if len(values) == 1 and "," not in text else values


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=parse_list, default=[8, 16, 24, 48, 140], help="training fleet sizes")
    ap.add_argument("--seeds", type=parse_seeds, default=list(range(1, 9)), help="N (seeds 1..N) or a list")
    ap.add_argument("--held-out", type=int, default=300, help="held-out runs per fleet")
    ap.add_argument(
        "--before", action="store_true", help="also the interval before issue 20 (10 re-tuned folds, jackknife)"
    )
    args = ap.parse_args()
    print(
        f"# python examples/interval_study.py --sizes {','.join(map(str, args.sizes))} "
        f"--seeds {','.join(map(str, args.seeds))} --held-out {args.held_out}{' --before' if args.before else ''}"
    )
    print(
        "size seed  cover_label cover_eff cover_out  half_med   rms_eff    half/rms out/in  used  z_loo z_held  "
        "x_phys  fit_s"
    )
    rows = []
    for size in args.sizes:
        for seed in args.seeds:
            r = one_fleet(size, seed, args.held_out, with_before=args.before)
            rows.append(r)
            s = r["summary"]
            phys = math.nan if s["physics_ratio"] is None else s["physics_ratio"]
            print(
                f"{size:4d} {seed:4d}  {r['cover_label']:10.3f} {r['cover_effective']:9.3f} "
                f"{r['cover_effective_outside']:9.3f}  {r['half_median']:.3e}  {r['rms']:.3e}  "
                f"{r['half_median'] / r['rms']:7.2f} {r['half_outside_ratio']:6.2f}  {s['n_used']:4d}  "
                f"{r['z_loo_scale']:5.2f} {r['z_heldout_rms']:6.2f}  {phys:6.2f}  {r['seconds']:5.1f}  "
                + (f"before: {r['before_cover_label']:.3f} {r['before_ratio']:.2f}  " if args.before else "")
                + f"{'; '.join(r['warnings'])[:60]}",
                flush=True,
            )
    print()
    print(
        "size  fleets  pooled_cover_label  pooled_cover_eff  half/rms median (min-max)  "
        "(z_held/z_loo)^2 median  fit s median"
    )
    for size in args.sizes:
        rs = [r for r in rows if r["n_train"] == size]
        ratio = np.array([r["half_median"] / r["rms"] for r in rs])
        opt = np.array([(r["z_heldout_rms"] / r["z_loo_scale"]) ** 2 for r in rs])
        print(
            f"{size:4d}  {len(rs):6d}  {np.mean([r['cover_label'] for r in rs]):18.3f}  "
            f"{np.mean([r['cover_effective'] for r in rs]):16.3f}  "
            f"{np.median(ratio):8.2f} ({ratio.min():.2f}-{ratio.max():.2f})         "
            f"{np.median(opt):10.2f}              {np.median([r['seconds'] for r in rs]):.2f}"
        )
        if args.before:
            b = np.array([r["before_ratio"] for r in rs])
            cover = np.mean([r["before_cover_label"] for r in rs])
            print(
                f"      before issue 20: pooled coverage of the labels {cover:.3f}"
                f", half/rms median {np.median(b):.2f} ({b.min():.2f}-{b.max():.2f})"
            )


if __name__ == "__main__":
    main()
