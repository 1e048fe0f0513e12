"""Benchmark: wall time of ``gyrodrift reproduce`` (all methods, no report) on one core.

Run: ``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/bench_reproduce.py``. Prints the time of the
whole reproduction and, as the reference measured in the same run, the time of one paper-settings CPSO tuning
run, with the ratio (the reproduction does 9 swarm runs, 3 grids and 9 fixed fits).
"""

from __future__ import annotations

import time

from sklearn.preprocessing import StandardScaler

from gyrodrift.datasets import load_paper
from gyrodrift.encodings import encode
from gyrodrift.reproduce import run_reproduction
from gyrodrift.tuning import tune_lssvr


def main():
    data = load_paper()
    X = StandardScaler().fit_transform(encode(data.train, "temp_range"))
    t0 = time.perf_counter()
    tune_lssvr(X, data.train.drift_deg_h, objective="train_mae", rng=0)
    one = time.perf_counter() - t0
    t0 = time.perf_counter()
    run_reproduction(seed=0, quiet=True)
    whole = time.perf_counter() - t0
    print(f"one CPSO tuning run (30 x 100, chaos 10): {one:.2f} s")
    print(f"whole reproduction (no report)         : {whole:.2f} s  ({whole / one:.1f} x one tuning run)")


if __name__ == "__main__":
    main()
