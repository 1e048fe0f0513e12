"""Benchmark: what the learning side costs as the fleet grows (issue 20). Prints times and ratios; never fails.

    python benchmarks/bench_learning_scale.py [--sizes 22,200,1000] [--tune-sizes 22,200] [--exact-max 200]
                                              [--model-runs 1500] [--no-cli]

1. **One LOO evaluation** of the tuner (closed-form LOO residuals of one (gamma, sigma) candidate) on ``n`` runs,
   per candidate, three ways in the same process: ``rbf_batch_errors`` with the BLAS's default threads (what the
   tuner did before), the same with one BLAS thread (what ``tune_lssvr`` does now), and 30 gammas of one sigma from
   one ``RBFEigenSystem`` (a grid's column, particles on a sigma bound); with the largest relative difference of
   the eigen path from the Cholesky path.
2. **One CPSO tuning run** with the paper's settings (30 particles x 100 iterations, 10 chaos steps, LOO MAE) on
   ``--tune-sizes`` runs: wall and CPU time with the sigmas snapped to a log grid (the default for n > 32,
   ``gyrodrift.learn.tuning.sigma_step_for``) and, up to ``--exact-max`` runs, the same seed unsnapped (as before): the
   ratio and the tuned LOO MAE of both; for n <= 200 also the ratio of the default BLAS threads to one, measured on
   the first 10 iterations (the default-thread run of 100 iterations takes minutes at 200 runs).
3. **The CLI** (subprocesses, wall time including Python's start-up and imports): ``gyrodrift fit`` with defaults on
   the paper's 22 training runs and on ``--sizes`` synthetic runs; ``gyrodrift reproduce``; ``gyrodrift predict``
   and ``gyrodrift export`` with a model of ``--model-runs`` runs (fitted with a fixed ``--gamma 100 --sigma 0.7``
   to keep this benchmark short: the load does not depend on how gamma and sigma were found), and the model file's
   load alone in this process (what ``identify`` adds to its alignment and navigation).

Synthetic runs: ``benchmarks/bench_predict.py``'s ``synthetic_runs`` (three sites, the smoother's columns, so that
``fit``'s default hybrid resolves to the fleet-prior smoother), seed 1. The machine is shared: compare the ratios
printed in one run, and repeat for the times.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from sklearn.preprocessing import StandardScaler
from threadpoolctl import threadpool_limits

from gyrodrift.learn.encodings import encode
from gyrodrift.learn.kernels import squared_distances
from gyrodrift.learn.lssvm_batch import RBFEigenSystem, rbf_batch_errors
from gyrodrift.learn.tuning import TuningOptions, tune_lssvr

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_predict import synthetic_runs


def best_seconds(fn, repeat: int = 3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def scaled_inputs(n: int):
    runs = synthetic_runs(n, np.random.default_rng(1))
    return StandardScaler().fit_transform(encode(runs, "temp_range")), runs.drift_deg_h


def loo_evaluation(sizes: list[int]) -> None:
    print("1. one LOO evaluation [ms per candidate]: default BLAS threads, one thread, eigen (30 gammas / sigma)")
    for n in sizes:
        X, y = scaled_inputs(n)
        D = squared_distances(X)
        rng = np.random.default_rng(0)
        m = 30 if n <= 300 else 6
        gammas, sigmas = 10 ** rng.uniform(-2, 5, m), 10 ** rng.uniform(-0.5, 1.0, m)
        threads = best_seconds(lambda D=D, y=y, g=gammas, s=sigmas: rbf_batch_errors(D, y, g, s, "loo"), 2) / m
        with threadpool_limits(limits=1, user_api="blas"):
            one = best_seconds(lambda D=D, y=y, g=gammas, s=sigmas: rbf_batch_errors(D, y, g, s, "loo"), 2) / m
            g30 = 10 ** np.linspace(-2, 5, 30)
            eig = best_seconds(lambda D=D, y=y, g=g30: RBFEigenSystem(D, 1.0).errors(g, y, "loo"), 2) / 30
            chol = rbf_batch_errors(D, y, g30, np.full(30, 1.0 + 1e-15), "loo")  # distinct sigmas: no sharing
            E = RBFEigenSystem(D, 1.0).errors(g30, y, "loo")
        ok = np.isfinite(chol).all(axis=1) & np.isfinite(E).all(axis=1)
        dev = float(np.max(np.abs(E[ok] - chol[ok]) / np.max(np.abs(chol[ok]), axis=1, keepdims=True)))
        print(
            f"   n = {n:5d}: {1e3 * threads:9.3f} {1e3 * one:9.3f} {1e3 * eig:9.3f}   "
            f"threads/one {threads / one:5.1f}x, one/eigen {one / eig:5.1f}x; eigen vs Cholesky {dev:.1e} relative"
        )


def tuning_runs(sizes: list[int], exact_max: int) -> None:
    print(
        "2. one CPSO tuning run (30 x 100, chaos 10, loo_mae, seed 0): sigmas snapped (the default for n > 32, "
        "tuning.sigma_step_for) against the same run unsnapped (sigma_step=None, as before); wall and CPU seconds"
    )
    for n in sizes:
        X, y = scaled_inputs(n)
        t0, c0 = time.perf_counter(), time.process_time()
        res = tune_lssvr(X, y, rng=0)
        whole, cpu = time.perf_counter() - t0, time.process_time() - c0
        step = res.settings.get("sigma_step_decades")
        how = "off, n <= 32" if step is None else f"step {step:g} decade"
        print(
            f"   n = {n:5d}: snapped ({how}): {whole:7.2f} s wall, {cpu:7.2f} s CPU, nfev {res.nfev}, "
            f"gamma {res.gamma:.6g}, sigma {res.sigma:.6g}, LOO MAE {res.fitness:.6e}"
        )
        if n <= exact_max:
            t0, c0 = time.perf_counter(), time.process_time()
            old = tune_lssvr(X, y, TuningOptions(sigma_step=None), rng=0)
            whole_old, cpu_old = time.perf_counter() - t0, time.process_time() - c0
            print(
                f"   {'':9s} unsnapped:            {whole_old:7.2f} s wall, {cpu_old:7.2f} s CPU, nfev {old.nfev}, "
                f"gamma {old.gamma:.6g}, sigma {old.sigma:.6g}, LOO MAE {old.fitness:.6e}\n"
                f"   {'':9s} unsnapped/snapped: {whole_old / whole:5.1f}x wall, {cpu_old / cpu:5.1f}x CPU; "
                f"LOO MAE snapped/unsnapped - 1 = {res.fitness / old.fitness - 1:+.2e}"
            )
        if n <= 200:
            t0 = time.perf_counter()
            short_one = tune_lssvr(X, y, TuningOptions(max_iter=10, sigma_step=None), rng=0)
            one = time.perf_counter() - t0
            with threadpool_limits(limits=None):  # tune_lssvr's own limit applies inside: measure the old code path
                t0 = time.perf_counter()
                short = _tune_default_threads(X, y, max_iter=10)
                threads = time.perf_counter() - t0
            same = (short.gamma, short.sigma) == (short_one.gamma, short_one.sigma)
            print(
                f"   {'':9s} first 10 iterations unsnapped: default BLAS threads {threads:.2f} s, one thread "
                f"{one:.2f} s ({threads / one:.1f}x), same result: {same}"
            )


def _tune_default_threads(X, y, max_iter: int):
    """The tuning run as before the one-thread limit: the same objective and swarm, the BLAS's own threads."""
    from gyrodrift.learn.cpso import minimize_cpso
    from gyrodrift.learn.tuning import DEFAULT_BOUNDS, TuningResult, make_objective

    fun = make_objective(X, y, "loo_mae")
    r = minimize_cpso(fun, DEFAULT_BOUNDS, max_iter=max_iter, chaos_steps=10, log_scale=True, vectorized=True, rng=0)
    return TuningResult(float(r.x[0]), float(r.x[1]), float(r.fun), "loo_mae", "cpso", int(r.nfev), int(r.nit))


def wall(cmd: list[str], cwd: Path) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=os.environ.copy())
    dt = time.perf_counter() - t0
    if done.returncode != 0:
        print(f"   FAILED ({done.returncode}): {' '.join(cmd)}: {done.stderr.strip().splitlines()[-1:]}")
    return dt


def cli(sizes: list[int], model_runs: int) -> None:
    from gyrodrift.learn.model_io import load_model
    from gyrodrift.runs.datasets import load_paper

    print("3. the CLI, wall time [s] (Python start-up and imports included)")
    with tempfile.TemporaryDirectory(prefix="bench_learning_scale_") as tmp:
        d = Path(tmp)
        load_paper().runs.to_csv(d / "paper.csv")
        t = wall(["gyrodrift", "fit", "paper.csv", "--split", "train", "--out", "paper.json", "--quiet"], d)
        print(f"   fit, defaults, the paper's 22 training runs: {t:7.2f}")
        for n in sizes:
            synthetic_runs(n, np.random.default_rng(1)).to_csv(d / f"runs{n}.csv")
            t = wall(["gyrodrift", "fit", f"runs{n}.csv", "--out", f"m{n}.json", "--quiet"], d)
            print(f"   fit, defaults, {n} synthetic runs: {t:7.2f}")
        t = wall(["gyrodrift", "reproduce", "--out", "repro", "--quiet"], d)
        print(f"   reproduce (seed 0): {t:7.2f}")
        synthetic_runs(model_runs, np.random.default_rng(2)).to_csv(d / "big.csv")
        t = wall(["gyrodrift", "fit", "big.csv", "--out", "big.json", "--gamma", "100", "--sigma", "0.7", "--quiet"], d)
        print(f"   (fit --gamma 100 --sigma 0.7 on {model_runs} runs, to make the model: {t:.1f})")
        synthetic_runs(20, np.random.default_rng(3)).to_csv(d / "new.csv")
        t = wall(["gyrodrift", "predict", "new.csv", "--model", "big.json", "--coverage", "0.9", "--out", "p.csv"], d)
        print(f"   predict 20 runs with the {model_runs}-run model: {t:7.2f}")
        t = wall(["gyrodrift", "export", "--model", "big.json", "--lang", "c", "--out", "c", "--quiet"], d)
        print(f"   export --lang c of the {model_runs}-run model: {t:7.2f}")
        t = wall([sys.executable, "-c", "pass"], d)
        print(f"   (python -c pass: {t:.2f})")
        t0 = time.perf_counter()
        load_model(d / "big.json")
        print(f"   load_model of the {model_runs}-run model, in this process: {time.perf_counter() - t0:7.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="22,200,1000", help="training runs, comma-separated (sections 1 and 3)")
    parser.add_argument("--tune-sizes", default="22,200", help="training runs of section 2, comma-separated")
    parser.add_argument(
        "--exact-max", type=int, default=200, help="largest n of section 2 also tuned unsnapped (minutes at 1000)"
    )
    parser.add_argument("--model-runs", type=int, default=1500, help="training runs of the model predict/export load")
    parser.add_argument("--no-cli", action="store_true", help="skip section 3")
    args = parser.parse_args()
    sizes = [int(v) for v in args.sizes.split(",")]
    loo_evaluation(sizes)
    tuning_runs([int(v) for v in args.tune_sizes.split(",") if v], args.exact_max)
    if not args.no_cli:
        cli([n for n in sizes if n != 22], args.model_runs)


if __name__ == "__main__":
    main()
