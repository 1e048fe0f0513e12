"""A simulated fleet from power-on to identified drift: docs/studies/2026-11-22-procedure.md quotes it.

Run: ``python examples/simulated_fleet.py [--runs 13] [--rate-hz 10] [--workdir DIR]``. The logs go to DIR when
given (and stay there), otherwise to a temporary folder removed at the end. It simulates 16 h
alignment runs of a reciprocating RLG INS whose axial drift follows the temperature
(0.0015 + 0.0002 (end_c - 28) deg/h plus a N(0, 1e-4) deg/h scatter), with ARW 0.0005 deg/sqrt(h),
VRW 5 ug/sqrt(Hz) and horizontal biases; extracts the features of every run (alignment + 12 h navigation),
trains a CPSO-LSSVM (LOO MAE) on the first runs, and identifies the held-out ones. It prints the held-out
errors (true minus identified) beside the physics inversion of the same 12 h latitude.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from gyrodrift.fleet.features import features_table
from gyrodrift.ins.synthetic_fleet import simulate_fleet
from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.procedure import features_run_table
from gyrodrift.runs.table import RunTable


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=13)
    ap.add_argument("--held-out", type=int, default=3)
    ap.add_argument("--rate-hz", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--workdir", type=Path, default=None)
    args = ap.parse_args()
    if args.workdir is not None:
        run(args, args.workdir)
        print(f"logs in {args.workdir}")
        return
    with tempfile.TemporaryDirectory(prefix="gyrodrift-fleet-") as tmp:  # nothing left behind
        run(args, Path(tmp))


def run(args: argparse.Namespace, base: Path) -> None:
    """Simulate the fleet into `base`, train on the first runs and print the held-out errors."""
    paths, drifts = simulate_fleet(base, args.runs, rate_hz=args.rate_hz, rng=args.seed)
    table = features_run_table(features_table(paths))
    table = RunTable(
        run=table.run,
        lat_deg=table.lat_deg,
        lat0_deg=table.lat0_deg,
        temp_min_c=table.temp_min_c,
        temp_max_c=table.temp_max_c,
        drift_deg_h=drifts,
        source=str(base),
    )
    n_train = args.runs - args.held_out
    train, test = table.select(np.arange(n_train)), table.select(np.arange(n_train, args.runs))
    for enc in ("temp_range", "lat_only"):
        model = fit_drift_model(train, encoding=enc, rng=0)
        err = test.drift_deg_h - model.predict(test)
        print(
            f"CPSO-LSSVM ({enc:10s}) held-out errors [deg/h]: {np.array2string(err, precision=2)}  "
            f"MAE {np.mean(np.abs(err)):.2e}  (LOO MAE on training {np.mean(np.abs(model.loo_residuals())):.2e})"
        )
    err = test.drift_deg_h - physics_inversion(test)
    print(
        f"physics inversion         held-out errors [deg/h]: {np.array2string(err, precision=2)}  "
        f"MAE {np.mean(np.abs(err)):.2e}"
    )


if __name__ == "__main__":
    main()
