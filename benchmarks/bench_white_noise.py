"""The white noise a log reads as, by the order of the differences and the sample rate
(docs/studies/2026-11-28-white-noise-low-rates.md).

    python benchmarks/bench_white_noise.py [--seeds 6] [--tilt-deg 1.0]

One hour on each turning scheme of the default table (6 deg/s; 360 deg sweeps, 90 deg steps or continuous) at
40 deg, tilted by `--tilt-deg` (pitch), at 1, 2 and 10 Hz: the ARW and VRW read from the increments' differences of
order 2, 3 and 4 (1.4826 x the median absolute difference / sqrt(C(2k, k)), averaged over the three axes) as
multiples of the simulated 0.0005 deg/sqrt(h) and 5 ug/sqrt(Hz) (mean and spread over `--seeds` seeds), and the
same on the noise-free log in deg/sqrt(h) and ug/sqrt(Hz); then the relative spread of the reading by order on
pure white noise (400 draws of 36 000 samples, numpy). The order used by `estimate_white_noise`
(`gyrodrift.procedure.noise.DIFFERENCE_ORDER`) is recomputed here from the whole hour and checked against it
(one chunk: the same numbers to rounding). Only reports.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from gyrodrift.ins import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure.noise import DIFFERENCE_ORDER, estimate_white_noise
from gyrodrift.units import DEG, MICRO_G

ARW, VRW = 0.0005, 5.0
ORDERS = (2, 3, 4)


def read_noise(log, order: int) -> tuple[float, float]:
    """(ARW [deg/sqrt(h)], VRW [ug/sqrt(Hz)]) from the first hour's differences of `order`, all in memory."""
    n = log.samples_for(3600.0)
    chunks = list(log.chunks(n, stop=n))
    gyro = np.vstack([np.asarray(c.dtheta_rad) for c in chunks])
    accel = np.vstack([np.asarray(c.dv_m_s) for c in chunks])
    scale = math.sqrt(math.comb(2 * order, order)) * math.sqrt(1.0 / log.rate_hz)

    def sigma(x: np.ndarray) -> float:
        return float(np.mean(1.482602218505602 * np.median(np.abs(np.diff(x, order, axis=0)), axis=0))) / scale

    return sigma(gyro) / DEG * 60.0, sigma(accel) / MICRO_G


def log_of(scheme: str, rate_hz: float, tilt_deg: float, seed: int, noise: bool):
    return scenario_log(
        Scenario.from_dict(
            {
                "site": {"lat_deg": 40.0},
                "run": {"duration_h": 1.0, "rate_hz": rate_hz, "seed": seed},
                "rotation": {"scheme": scheme},
                "gyro": {"bias_deg_h": [0.004, -0.003, 0.003], "arw_deg_rth": ARW if noise else 0.0},
                "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": VRW if noise else 0.0},
                "attitude": {"yaw_deg": 30.0, "pitch_deg": tilt_deg},
            }
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--tilt-deg", type=float, default=1.0)
    args = parser.parse_args()
    print(f"tilt {args.tilt_deg} deg; noisy: read / simulated, mean +- spread over {args.seeds} seeds")
    print(
        f"{'scheme':14} {'Hz':>4}  "
        + "  ".join(f"{'k=' + str(k) + ' ARW':>16} {'k=' + str(k) + ' VRW':>16}" for k in ORDERS)
    )
    for scheme in ("reciprocating", "indexing", "continuous"):
        for rate_hz in (1.0, 2.0, 10.0):
            ratios = {k: [] for k in ORDERS}
            for seed in range(1, args.seeds + 1):
                log = log_of(scheme, rate_hz, args.tilt_deg, seed, noise=True)
                for k in ORDERS:
                    arw, vrw = read_noise(log, k)
                    ratios[k].append((arw / ARW, vrw / VRW))
                    if k == DIFFERENCE_ORDER:
                        used = estimate_white_noise(log)
                        assert math.isclose(used.arw_deg_rth, arw, rel_tol=1e-9), (used.arw_deg_rth, arw)
                        assert math.isclose(used.vrw_ug_rthz, vrw, rel_tol=1e-9), (used.vrw_ug_rthz, vrw)
            cells = []
            for k in ORDERS:
                r = np.array(ratios[k])
                cells += [
                    f"{r[:, 0].mean():7.3f} +- {r[:, 0].std():5.3f}",
                    f"{r[:, 1].mean():7.3f} +- {r[:, 1].std():5.3f}",
                ]
            print(f"{scheme:14} {rate_hz:4.0f}  " + "  ".join(f"{c:>16}" for c in cells))
    print("noise-free: ARW [deg/sqrt(h)] and VRW [ug/sqrt(Hz)] read")
    for scheme in ("reciprocating", "indexing", "continuous"):
        for rate_hz in (1.0, 2.0, 10.0):
            log = log_of(scheme, rate_hz, args.tilt_deg, 1, noise=False)
            read = [read_noise(log, k) for k in ORDERS]
            print(f"{scheme:14} {rate_hz:4.0f}  " + "  ".join(f"{a:16.2e} {v:16.3g}" for a, v in read))
    white = np.random.default_rng(0).standard_normal((400, 36_000))
    for k in ORDERS:
        read = 1.482602218505602 * np.median(np.abs(np.diff(white, k, axis=1)), axis=1) / math.sqrt(math.comb(2 * k, k))
        print(f"pure white noise, order {k}: mean {read.mean():.4f}, relative spread {read.std() / read.mean():.5f}")


if __name__ == "__main__":
    main()
