"""Benchmark: wall time of ``gyrodrift reproduce`` and of its parts (issue 20's target: <= 5 s wall on 2 cores).

Run: ``python benchmarks/bench_reproduce.py [--repeat 1]``. Prints, with the references measured in the same run:

1. the command ``gyrodrift reproduce --out <tmp> --quiet`` (Python start-up and imports included), CPU (user +
   system of the child) and wall time beside issue 20's target, and the references of the same run: ``python -c
   pass`` and the imports the command pays before any work (``IMPORTS``: the command line, the reproduction, its
   report, the navigation and matplotlib);
2. in this process: ``run_reproduction(seed=0)`` (24 drift models, 15 tunings, the 72 h navigations) as it is, with
   the three 72 h navigations (``position_error_72h``) apart, and with the interval GP's hyperparameters searched
   as before issue 20's speed-up (scikit-learn's ``GaussianProcessRegressor`` L-BFGS-B search, OpenBLAS's default
   threads), its ratio, and the largest relative difference between the two results' numbers (timings left out);
   the report's figures (``make_figures``);
3. one paper-settings CPSO tuning run (30 x 100, chaos 10), the reproduction's unit of work.

Wall times depend on what else runs on the machine: the CPU times (``time.process_time`` / the child's rusage)
say how much of a wall time was the work. Only reports.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path


def child(cmd: list[str], cwd: Path) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        print(f"   FAILED ({done.returncode}): {' '.join(cmd)}: {done.stderr.strip().splitlines()[-1:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _numbers(x, path=""):
    """(path, float) of every number in a results dict, timings left out."""
    if isinstance(x, dict):
        for k, v in x.items():
            if not any(w in k for w in ("time", "seconds", "elapsed")):
                yield from _numbers(v, f"{path}/{k}")
    elif isinstance(x, list | tuple):
        for i, v in enumerate(x):
            yield from _numbers(v, f"{path}[{i}]")
    elif isinstance(x, float) and math.isfinite(x):
        yield path, x


def worst_relative_difference(a: dict, b: dict) -> tuple[float, str, int]:
    da, db = dict(_numbers(a)), dict(_numbers(b))
    worst, where = 0.0, ""
    for k, u in da.items():
        v = db.get(k)
        if v is None:
            continue
        d = abs(u - v) / max(abs(u), abs(v), 1e-300)
        if d > worst:
            worst, where = d, k
    return worst, where, len(da)


IMPORTS = (
    "import gyrodrift.cli, gyrodrift.paper.reproduce, gyrodrift.paper.report, gyrodrift.procedure.navigate, "
    "gyrodrift.ins.scenario, matplotlib.figure"
)
"""What ``gyrodrift reproduce`` imports before its work: the command line, the reproduction and its report (numpy,
scipy, scikit-learn), the navigation (the Rust core, pyarrow) and matplotlib's object API."""


@contextlib.contextmanager
def navigation_timed(reproduction, seconds: list[float]):
    """Add the wall and CPU seconds of ``reproduction.position_error_72h`` (the 72 h navigations) to ``seconds``."""
    saved = reproduction.position_error_72h

    def wrapper(*args, **kwargs):
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            return saved(*args, **kwargs)
        finally:
            seconds[0] += time.perf_counter() - t0
            seconds[1] += time.process_time() - c0

    reproduction.position_error_72h = wrapper
    try:
        yield
    finally:
        reproduction.position_error_72h = saved


@contextlib.contextmanager
def gp_search_as_before():
    """The interval GP's hyperparameters searched by scikit-learn's GaussianProcessRegressor, default BLAS threads."""
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor

    import gyrodrift.learn.spread as spread

    def search(Z, y, noise, n_restarts, seed):
        kernel = spread._kernel(Z.shape[1])
        gp = GaussianProcessRegressor(kernel, alpha=noise, n_restarts_optimizer=n_restarts, random_state=seed)
        return gp.fit(Z, y).kernel_.theta

    saved = spread._maximise_likelihood, spread.threadpool_limits
    spread._maximise_likelihood = search
    spread.threadpool_limits = lambda **_: contextlib.nullcontext()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)  # as SpreadGP did then: a length scale at its bound
            yield
    finally:
        spread._maximise_likelihood, spread.threadpool_limits = saved


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="repetitions of each measurement (best kept)")
    args = parser.parse_args()
    rep = max(1, args.repeat)

    print("1. the command: CPU and wall time [s], issue 20's target (wall, quiet 2-core machine)")
    with tempfile.TemporaryDirectory(prefix="bench_reproduce_") as tmp:
        d = Path(tmp)
        runs = [child(["gyrodrift", "reproduce", "--out", f"out{i}", "--quiet"], d) for i in range(rep)]
        wall, cpu = min(runs)
        print(f"   {'gyrodrift reproduce --out DIR --quiet':<48s} CPU {cpu:6.2f}  wall {wall:6.2f}  target <= 5 s wall")
        wall, cpu = min(child([sys.executable, "-c", IMPORTS], d) for _ in range(rep))
        print(f"   {'python -c IMPORTS (the imports it pays)':<48s} CPU {cpu:6.2f}  wall {wall:6.2f}  (reference)")
        wall, cpu = min(child([sys.executable, "-c", "pass"], d) for _ in range(rep))
        print(f"   {'python -c pass':<48s} CPU {cpu:6.2f}  wall {wall:6.2f}  (reference)")

    import gyrodrift.paper.reproduce as reproduction
    from gyrodrift.paper.reproduce import run_reproduction

    print("2. in this process, wall / CPU [s]")
    run_reproduction(seed=0, quiet=True)  # warm: imports, caches
    navigation = [0.0, 0.0]
    with navigation_timed(reproduction, navigation):
        now = min((timed(lambda: run_reproduction(seed=0, quiet=True)) for _ in range(rep)), key=lambda r: r[1])
    print(f"   run_reproduction(seed=0)                   : {now[1]:6.2f} / {now[2]:6.2f}")
    wall, cpu = navigation[0] / rep, navigation[1] / rep
    print(f"   of which the three 72 h navigations        : {wall:6.2f} / {cpu:6.2f}  (mean of {rep})")
    with gp_search_as_before():
        old = min((timed(lambda: run_reproduction(seed=0, quiet=True)) for _ in range(rep)), key=lambda r: r[1])
    print(
        f"   the same, the GP searched as before        : {old[1]:6.2f} / {old[2]:6.2f}  "
        f"(now / before: wall {now[1] / old[1]:.2f}, CPU {now[2] / old[2]:.2f})"
    )
    worst, where, n = worst_relative_difference(now[0], old[0])
    print(f"   largest relative difference of {n} numbers: {worst:.1e} ({where})")
    from gyrodrift.paper.report import make_figures

    make_figures(now[0])  # warm: matplotlib's import and font cache
    _, wall, cpu = min((timed(lambda: make_figures(now[0])) for _ in range(rep)), key=lambda r: r[1])
    print(f"   the report's 4 figures (make_figures)      : {wall:6.2f} / {cpu:6.2f}")

    from sklearn.preprocessing import StandardScaler

    from gyrodrift.learn.encodings import encode
    from gyrodrift.learn.tuning import TuningOptions, tune_lssvr
    from gyrodrift.runs.datasets import load_paper

    data = load_paper()
    X = StandardScaler().fit_transform(encode(data.train, "temp_range"))
    _, wall, cpu = timed(lambda: tune_lssvr(X, data.train.drift_deg_h, TuningOptions(objective="train_mae"), rng=0))
    print("3. reference")
    print(f"   one CPSO tuning run (30 x 100, chaos 10)   : {wall:6.2f} / {cpu:6.2f}")


if __name__ == "__main__":
    main()
