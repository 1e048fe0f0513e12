"""Throughput of the Rust IMU simulator on a moving base against the static base, same sensor, same run.

    python benchmarks/bench_moving_base.py [--hours 1] [--repeat 3] [--chunk 100000]

The scenario is examples/scenarios/vehicle_test.toml (reciprocating table with the balanced span, noise on every
channel) with a short stand (36 s) so that the vehicle drives the whole timed run, and the same scenario without
``[trajectory]`` (the static base). Each is simulated `--repeat` times in chunks of `--chunk` samples into
caller-owned buffers (`fill_into`, what `simulate` and `navigate` use); the best CPU time (`time.process_time`:
this process only, so other work on a shared machine barely changes it) gives samples/s, and the ratio
moving / static is the number to compare between versions. Never fails on a slow machine: it only reports.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from gyrodrift import _core
from gyrodrift.ins import Scenario, load_scenario

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "scenarios" / "vehicle_test.toml"


def _buffers(n: int, moving: bool) -> dict[str, np.ndarray]:
    out = {k: np.empty(n) for k in ("t_s", "temp_c", "table_angle_rad", "pitch_rad", "roll_rad", "yaw_rad")}
    out["dtheta_rad"] = np.empty((n, 3))
    out["dv_m_s"] = np.empty((n, 3))
    if moving:
        out.update({k: np.empty(n) for k in ("lat_rad", "lon_rad", "height_m")})
        out["vel_enu_m_s"] = np.empty((n, 3))
    return out


def cpu_time(scn: Scenario, chunk: int, repeat: int) -> tuple[int, float]:
    """Samples of the run and the best CPU time [s] of `repeat` simulations of it."""
    moving = scn.trajectory is not None
    best = math.inf
    n = 0
    for _ in range(repeat):
        sim = _core.ImuSimulator(scn.to_core_config())
        out = _buffers(chunk, moving)
        t0 = time.process_time()
        n = 0
        while (m := sim.fill_into(out)) > 0:
            n += m
        best = min(best, time.process_time() - t0)
    return n, best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=1.0, help="simulated run [h] (default 1)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each, best CPU time kept (default 3)")
    ap.add_argument("--chunk", type=int, default=100_000, help="samples per fill_into call (default 100000)")
    args = ap.parse_args()
    base = load_scenario(EXAMPLE)
    moving = dataclasses.replace(
        base,
        run=dataclasses.replace(base.run, duration_h=args.hours),
        trajectory=dataclasses.replace(base.trajectory, static_h=0.01),
    )
    static = dataclasses.replace(moving, trajectory=None)
    rows = []
    for name, scn in (("static base", static), ("moving base", moving)):
        n, t = cpu_time(scn, args.chunk, args.repeat)
        rows.append((name, n, t))
        print(f"{name:12s}: {n} samples in {t:.3f} s CPU = {n / t / 1e6:.2f} M samples/s")
    ratio = rows[1][1] / rows[1][2] / (rows[0][1] / rows[0][2])
    print(f"moving / static throughput: {ratio:.3f} ({1 / ratio:.1f} x the static base's time per sample)")


if __name__ == "__main__":
    main()
