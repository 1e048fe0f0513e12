"""Cost of `DriftModel.predict`'s arithmetic (the generated code's operations, compensated sum) against numpy's.

    python benchmarks/bench_predict.py [--rows 1,1000,100000] [--train 22,200,1000] [--repeat 5]

`DriftModel.predict` computes each kernel value with the operations of the exported C/Rust (distances summed over
the features in order, the C library's ``exp`` through ``math.exp``) and sums ``b + sum_i alpha_i K_i + physics``
with TwoSum in support-vector order (`gyrodrift.learn.lssvr`, "prediction arithmetic"). The reference, in the same run:
the same pipeline with numpy's kernel (scipy's distances, numpy's SIMD ``exp``) summed by BLAS, ``K @ alpha + b +
physics``, which is what predict did before. Models: hybrids with encoding ``physics`` and the default
``physics_column="auto"`` (it resolves to the fleet-prior smoother on these runs: they carry the smoother's end
drift and k_z, a fifth of them on its constant model) fitted on `--train` synthetic runs from three sites; rows
drawn over the training range. CPU time (``time.process_time``, best of `--repeat`), so that other jobs on the
machine matter less. Only reports.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.kernels import kernel_matrix
from gyrodrift.learn.physics_base import physics_estimate
from gyrodrift.runs.table import RunTable


def synthetic_runs(n: int, rng: np.random.Generator) -> RunTable:
    """``n`` runs at three sites, drift from the latitude error and the temperatures [deg/h]."""
    lat0 = rng.choice([20.5, 34.1, 51.3], n)
    err = rng.uniform(-120.0, 120.0, n)
    tmin = rng.uniform(10.0, 50.0, n)
    tmax = tmin + rng.uniform(0.5, 8.0, n)
    drift = 0.01 * np.sin(err / 60.0) + 0.002 * (tmin + tmax - 60.0) / 40.0 + rng.normal(0.0, 3e-4, n)
    d_std, k_std = rng.uniform(5e-5, 2e-4, n), rng.uniform(5e-5, 3e-4, n)
    constant = rng.random(n) < 0.2  # the smoother's constant model: no k_z
    kz = {
        "smoother_coeff_deg_h_per_c": rng.normal(2e-4, 5e-5, n),
        "smoother_coeff_std_deg_h_per_c": k_std,
        "smoother_end_coeff_cov": rng.uniform(-0.9, 0.9, n) * d_std * k_std,
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e-2),
    }
    extra = {
        "drift_smoother_deg_h": drift + rng.normal(0.0, d_std),
        "drift_smoother_std_deg_h": d_std,
        **{name: np.where(constant, np.nan, v) for name, v in kz.items()},
    }
    return RunTable(
        run=np.array([f"r{i}" for i in range(n)]),
        lat_deg=lat0 + err / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=drift,
        extra=extra,
        source="bench",
    )


def numpy_predict(model, runs: RunTable) -> np.ndarray:
    """The reference: numpy's kernel summed by BLAS, plus the physics estimate (the resolved base)."""
    est = model.lssvr
    K = kernel_matrix(model.learner_[:-1].transform(runs), est.X_fit_, kernel=est.kernel, sigma=est.sigma)
    base = physics_estimate(runs, model.physics_column_, prior=model.coefficient_prior_)
    return K @ est.alpha_ + est.intercept_ + base


def cpu_seconds(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", default="1,1000,100000", help="rows predicted per call, comma-separated")
    parser.add_argument("--train", default="22,200,1000", help="training runs (support vectors), comma-separated")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    print("training runs, rows: predict [s CPU], numpy kernel + BLAS [s CPU], ratio; max |diff| / |predict|")
    print("(hybrids, encoding physics, physics base auto: resolved to the fleet-prior smoother)")
    for n_train in (int(v) for v in args.train.split(",")):
        model = fit_drift_model(
            synthetic_runs(n_train, rng), encoding="physics", target="residual", gamma=100.0, sigma=0.7
        )
        assert model.physics_column_ == "drift_smoother_fleet_deg_h", model.physics_column_
        for n_rows in (int(v) for v in args.rows.split(",")):
            rows = synthetic_runs(n_rows, rng)
            ours = cpu_seconds(lambda m=model, r=rows: m.predict(r), args.repeat)
            ref = cpu_seconds(lambda m=model, r=rows: numpy_predict(m, r), args.repeat)
            pred = model.predict(rows)
            diff = float(np.max(np.abs(pred - numpy_predict(model, rows)) / np.abs(pred)))
            print(f"{n_train:6d} {n_rows:7d}: {ours:.3g} {ref:.3g} {ours / ref:5.1f}x; {diff:.2g}")


if __name__ == "__main__":
    main()
