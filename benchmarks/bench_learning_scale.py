"""Benchmark: what the learning side costs as the fleet grows (issue 20). Prints times and ratios; never fails.

    python benchmarks/bench_learning_scale.py [--sizes 22,200,1000] [--tune-sizes 22,200] [--exact-max 200]
                                              [--model-runs 1500] [--reproduce-rounds 2] [--no-cli] [--no-calibration]

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
3. **The CLI** (subprocesses, Python's start-up and imports included), one line per issue 20 target: the command,
   the child's CPU time (user + system, what the work cost on a shared machine) and wall time, and the target
   (wall, on a quiet 2-core machine): ``gyrodrift fit`` with defaults on the paper's 22 training runs and on
   ``--sizes`` synthetic runs; ``gyrodrift reproduce`` (a forked worker beside it) alternately with the same on one
   process (``SERIAL_REPRODUCE``, the reference), ``--reproduce-rounds`` times each, and the ratio of the best walls;
   ``gyrodrift predict`` and ``gyrodrift export`` with a model
   of ``--model-runs`` runs (fitted with a fixed ``--gamma 100 --sigma 0.7`` to keep this benchmark short: the load
   does not depend on how gamma and sigma were found); then the references of the same run: ``python -c pass`` and
   the imports of the learning commands: those of ``predict``/``export`` (``gyrodrift.cli`` and the model file's
   reader, which imports no scikit-learn: ``load_predictor``) and those ``fit`` and ``reproduce`` add (the estimators:
   scikit-learn, and with it scipy.stats); and the model file's loads in this process: ``load_predictor`` (what
   ``predict``, ``identify --model`` and ``export`` do) and ``load_model`` (the estimator, for library use).
4. **Calibrating an interval against the tune it calibrates** (issue 20: the first must cost no more than the
   second): ``fit_drift_model`` with defaults on the paper's 22 training runs and on ``--sizes`` synthetic runs, in
   this process, with the CPU time of the one tune (``tune_lssvr``) and of the interval's work (the spread model's
   fit, its leave-one-out spreads, the calibration: ``DriftInterval.fit_spread``, ``loo_spreads``, ``calibrate``,
   and any out-of-fold refit ``DriftModel._out_of_fold``) measured inside the same fit, and their ratio.

Synthetic runs: ``benchmarks/bench_predict.py``'s ``synthetic_runs`` (three sites, the smoother's columns, so that
``fit``'s default hybrid resolves to the fleet-prior smoother), seed 1. The machine is shared: compare the ratios
printed in one run, and repeat for the times.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import resource
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


def child(cmd: list[str], cwd: Path) -> tuple[float, float]:
    """Wall and CPU (user + system of the child) seconds of one command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=os.environ.copy())
    dt = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        print(f"   FAILED ({done.returncode}): {' '.join(cmd)}: {done.stderr.strip().splitlines()[-1:]}")
    return dt, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def target_line(cmd: list[str], cwd: Path, target_s: float | None) -> None:
    """Run ``cmd`` and print its CPU and wall time beside its target (wall, quiet machine)."""
    wall, cpu = child(cmd, cwd)
    verdict = "(reference)" if target_s is None else f"target <= {target_s:g} s wall"
    shown = " ".join(["python" if cmd[0] == sys.executable else cmd[0], *(repr(a) if " " in a else a for a in cmd[1:])])
    print(f"   {shown:<92s} CPU {cpu:6.2f}  wall {wall:6.2f}  {verdict}")


PREDICT_IMPORTS = "import gyrodrift.cli, gyrodrift.learn.model_io"
"""The imports of ``predict`` and ``export``: the command line and the model file's reader (numpy, scipy.linalg; no
scikit-learn)."""
FIT_IMPORTS = "import gyrodrift.cli, gyrodrift.learn.model_io, gyrodrift.learn.drift_model"
"""The imports of ``fit`` and ``reproduce``: the estimators add scikit-learn (and with it scipy.stats)."""


def cli(sizes: list[int], model_runs: int, reproduce_rounds: int) -> None:
    from gyrodrift.learn.model_io import load_model, load_predictor
    from gyrodrift.runs.datasets import load_paper

    print("3. the CLI: command, CPU and wall time [s] (Python start-up and imports included), issue 20's target")
    with tempfile.TemporaryDirectory(prefix="bench_learning_scale_") as tmp:
        d = Path(tmp)
        load_paper().runs.to_csv(d / "paper.csv")
        target_line(["gyrodrift", "fit", "paper.csv", "--split", "train", "--out", "paper.json", "--quiet"], d, 1.5)
        for n in sizes:
            synthetic_runs(n, np.random.default_rng(1)).to_csv(d / f"runs{n}.csv")
            target = 10.0 if n <= 200 else 60.0 if n <= 1000 else None
            target_line(["gyrodrift", "fit", f"runs{n}.csv", "--out", f"m{n}.json", "--quiet"], d, target)
        reproduce_against_serial(d, reproduce_rounds)
        synthetic_runs(model_runs, np.random.default_rng(2)).to_csv(d / "big.csv")
        wall, _ = child(
            ["gyrodrift", "fit", "big.csv", "--out", "big.json", "--gamma", "100", "--sigma", "0.7", "--quiet"], d
        )
        print(f"   (fit --gamma 100 --sigma 0.7 on {model_runs} runs, to make the model: {wall:.1f} s wall)")
        synthetic_runs(20, np.random.default_rng(3)).to_csv(d / "new.csv")
        predict = ["gyrodrift", "predict", "new.csv", "--model", "big.json", "--coverage", "0.9", "--out", "p.csv"]
        target_line(predict, d, 2.0)
        target_line(["gyrodrift", "export", "--model", "big.json", "--lang", "c", "--out", "c", "--quiet"], d, 2.0)
        target_line([sys.executable, "-c", "pass"], d, None)
        target_line([sys.executable, "-c", PREDICT_IMPORTS], d, None)
        target_line([sys.executable, "-c", FIT_IMPORTS], d, None)
        for load in (load_predictor, load_model):
            t0, c0 = time.perf_counter(), time.process_time()
            load(d / "big.json")
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            what = f"{load.__name__} of the {model_runs}-run model, in this process"
            print(f"   {what:<92s} CPU {cpu:6.2f}  wall {wall:6.2f}")


SERIAL_REPRODUCE = (
    "import contextlib, gyrodrift.paper.reproduce as r; "
    "r.worker_pool = lambda: contextlib.nullcontext(r.SerialExecutor()); "
    "from gyrodrift.cli import main; main()"
)
"""``gyrodrift reproduce`` with its worker's tasks run in its own process, one after the other (`SerialExecutor`, as
where the platform cannot fork): the same work on one process, the reference of the two-process command."""


def reproduce_against_serial(d: Path, rounds: int) -> None:
    """``gyrodrift reproduce`` (a forked worker beside the command's process) and the same on one process
    (``SERIAL_REPRODUCE``), alternately ``rounds`` times: the best wall of each, their CPU, the load average, and the
    ratio of the walls."""
    runs = {"two processes": ["gyrodrift"], "one process (reference)": [sys.executable, "-c", SERIAL_REPRODUCE]}
    best: dict[str, tuple[float, float]] = {}
    for k in range(rounds):
        for name, head in runs.items():
            load = os.getloadavg()[0]
            wall, cpu = child([*head, "reproduce", "--out", f"repro{k}{len(head)}", "--quiet"], d)
            print(
                f"   reproduce, {name:<24s} round {k + 1}: CPU {cpu:6.2f}  wall {wall:6.2f}  (load average {load:.2f})"
            )
            if name not in best or wall < best[name][0]:
                best[name] = (wall, cpu)
    (two, _), (one, _) = best.values()
    print(
        f"   reproduce: best wall {two:.2f} s on two processes, {one:.2f} s on one: ratio {two / one:.2f} (target 5 s)"
    )


@contextlib.contextmanager
def cpu_of(owner, names: tuple[str, ...], seconds: dict[str, float], key: str):
    """Add the CPU time spent in ``owner``'s attributes ``names`` (calls not nested in each other) to
    ``seconds[key]`` while inside."""
    saved = {name: getattr(owner, name) for name in names}

    def timed(fn):
        def wrapper(*args, **kwargs):
            c0 = time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                seconds[key] += time.process_time() - c0

        return wrapper

    for name, fn in saved.items():
        setattr(owner, name, timed(fn))
    try:
        yield
    finally:
        for name, fn in saved.items():
            setattr(owner, name, fn)


def calibration_against_tune(sizes: list[int]) -> None:
    import warnings

    import gyrodrift.learn.learner as learner
    from gyrodrift.choices import default_encoding
    from gyrodrift.learn.drift_model import DEFAULT_MAX_LABEL_STD_DEG_H, DriftModel, fit_drift_model
    from gyrodrift.learn.interval import DriftInterval
    from gyrodrift.runs.datasets import load_paper

    print(
        "4. calibrating the interval against the one tune it calibrates: fit_drift_model with defaults, CPU [s] "
        "of the tune (tune_lssvr) and of the interval (spread fit, LOO spreads, calibration, out-of-fold refits)"
    )
    cases = [("the paper's 22 training runs", load_paper().train)]
    cases += [(f"{n} synthetic runs", synthetic_runs(n, np.random.default_rng(1))) for n in sizes if n != 22]
    for name, runs in cases:
        seconds = {"tune": 0.0, "interval": 0.0}
        interval_parts = ("fit_spread", "loo_spreads", "calibrate")
        with (
            cpu_of(learner, ("tune_lssvr",), seconds, "tune"),
            cpu_of(DriftInterval, interval_parts, seconds, "interval"),
            cpu_of(DriftModel, ("_out_of_fold",), seconds, "interval"),
            warnings.catch_warnings(),
        ):
            warnings.simplefilter("ignore")
            c0 = time.process_time()
            fit_drift_model(  # as `gyrodrift fit` with its defaults
                runs,
                target="residual",
                encoding=default_encoding("residual"),
                max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H,
                rng=0,
            )
            whole = time.process_time() - c0
        print(
            f"   {name:28s}: fit {whole:7.2f}, tune {seconds['tune']:7.2f}, interval {seconds['interval']:7.2f}; "
            f"interval / tune {seconds['interval'] / seconds['tune']:.3f} (issue 20: <= 1)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="22,200,1000", help="training runs, comma-separated (sections 1 and 3)")
    parser.add_argument("--tune-sizes", default="22,200", help="training runs of section 2, comma-separated")
    parser.add_argument(
        "--exact-max", type=int, default=200, help="largest n of section 2 also tuned unsnapped (minutes at 1000)"
    )
    parser.add_argument("--model-runs", type=int, default=1500, help="training runs of the model predict/export load")
    parser.add_argument(
        "--reproduce-rounds", type=int, default=2, help="rounds of reproduce on two processes and on one (section 3)"
    )
    parser.add_argument("--no-cli", action="store_true", help="skip section 3")
    parser.add_argument("--no-calibration", action="store_true", help="skip section 4")
    args = parser.parse_args()
    sizes = [int(v) for v in args.sizes.split(",")]
    loo_evaluation(sizes)
    tuning_runs([int(v) for v in args.tune_sizes.split(",") if v], args.exact_max)
    if not args.no_cli:
        cli([n for n in sizes if n != 22], args.model_runs, args.reproduce_rounds)
    if not args.no_calibration:
        calibration_against_tune(sizes)


if __name__ == "__main__":
    main()
