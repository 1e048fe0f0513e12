"""Benchmark: a CPSO tuning run on the paper data, and the batched LOO objective vs a naive one.

Run: ``python benchmarks/bench_tuning.py``. Prints evaluations per second of

- the batched closed-form LOO objective (``gyrodrift.learn.tuning.make_objective``: one squared-distance matrix,
  one Cholesky factor per candidate, LOO residuals in closed form), and
- a naive reference measured in the same run: per particle, per left-out run, a bordered
  ``np.linalg.solve`` of the (n) x (n) LSSVM system on the remaining runs (brute-force LOO),

and their ratio, plus the wall time of a whole paper-settings tuning run (30 particles x 100 iterations,
10 chaos steps). Never fails because a machine is slow; the two agree to rounding (checked and printed).
"""

from __future__ import annotations

import time

import numpy as np
from sklearn.preprocessing import StandardScaler

from gyrodrift.learn.encodings import encode
from gyrodrift.learn.tuning import TuningOptions, make_objective, tune_lssvr
from gyrodrift.runs.datasets import load_paper


def naive_loo_mae(X, y, params):
    """Brute-force LOO MAE for each (gamma, sigma) row, bordered system solved with np.linalg.solve."""
    n = len(y)
    out = np.empty(len(params))
    for j, (gamma, sigma) in enumerate(params):
        errs = np.empty(n)
        for i in range(n):
            keep = np.arange(n) != i
            Xt, yt = X[keep], y[keep]
            d2 = ((Xt[:, None, :] - Xt[None, :, :]) ** 2).sum(-1)
            K = np.exp(-d2 / sigma**2)
            A = np.zeros((n, n))
            A[0, 1:] = 1.0
            A[1:, 0] = 1.0
            A[1:, 1:] = K + np.eye(n - 1) / gamma
            sol = np.linalg.solve(A, np.r_[0.0, yt])
            k = np.exp(-((Xt - X[i]) ** 2).sum(-1) / sigma**2)
            errs[i] = y[i] - (k @ sol[1:] + sol[0])
        out[j] = np.mean(np.abs(errs))
    return out


def best_rate(fn, min_time=1.0):
    """Calls per second, the best of repeated timing blocks of at least ``min_time`` s in total."""
    calls, start, best = 0, time.perf_counter(), 0.0
    while True:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        best = max(best, 1.0 / dt)
        calls += 1
        if time.perf_counter() - start > min_time and calls >= 3:
            return best


def main():
    data = load_paper()
    X = StandardScaler().fit_transform(encode(data.train, "temp_range"))
    y = data.train.drift_deg_h
    rng = np.random.default_rng(0)
    params = np.column_stack([10 ** rng.uniform(-2, 5, 30), 10 ** rng.uniform(-3, 2, 30)])
    batched = make_objective(X, y, "loo_mae")
    a, b = batched(params), naive_loo_mae(X, y, params)
    finite = np.isfinite(a)
    dev = np.max(np.abs(a[finite] - b[finite]) / np.abs(b[finite]))
    fast = best_rate(lambda: batched(params)) * len(params)
    slow = best_rate(lambda: naive_loo_mae(X, y, params), min_time=2.0) * len(params)
    print(f"paper data: n = {len(y)} training runs, 3 inputs, swarm of {len(params)}")
    print(f"batched closed-form LOO objective : {fast:12.0f} evaluations/s")
    print(f"naive bordered np.linalg.solve LOO: {slow:12.0f} evaluations/s")
    print(f"ratio                             : {fast / slow:12.1f} x   (max relative difference {dev:.1e})")
    t0 = time.perf_counter()
    res = tune_lssvr(X, y, TuningOptions(objective="loo_mae", method="cpso"), rng=0)
    dt = time.perf_counter() - t0
    print(
        f"CPSO tuning run, 30 x 100, chaos 10: {dt:.2f} s, nfev = {res.nfev}, "
        f"{res.nfev / dt:.0f} evaluations/s, LOO MAE {res.fitness:.3e} deg/h "
        f"at gamma {res.gamma:.4g}, sigma {res.sigma:.4g}"
    )


if __name__ == "__main__":
    main()
