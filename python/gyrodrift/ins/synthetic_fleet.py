"""A simulated fleet of 16 h alignment runs whose axial drift follows the temperature.

Used by the procedure tests and by examples/simulated_fleet.py. Each run: a reciprocating RLG INS at the
default site, ARW 0.0005 deg/sqrt(h), VRW 5 ug/sqrt(Hz), x/y gyro biases 0.005/-0.004 deg/h, accelerometer
biases 30/-20/10 ug, a random warm-up (start 15-25 degC, end 28-40 degC, time constant 0.5-3 h) and heading.
Its axial drift is the constant ``thermal_drift_deg_h(end_c) + N(0, scatter)`` (the paper's premise that the
drift follows the temperature; chosen here, not measured), which is also the run's true drift.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import simulate

__all__ = ["thermal_drift_deg_h", "simulate_fleet"]


def thermal_drift_deg_h(end_c: float) -> float:
    """The fleet's thermal law [deg/h]: 0.0015 + 0.0002 (end_c - 28)."""
    return 0.0015 + 0.0002 * (end_c - 28.0)


def simulate_fleet(
    out_dir, n_runs: int, *, rate_hz: float = 10.0, duration_h: float = 16.0, scatter_deg_h: float = 1e-4, rng=5
) -> tuple[list[Path], np.ndarray]:
    """Simulate ``n_runs`` runs into ``out_dir/runNN/imu.parquet``; returns (paths, true drifts [deg/h]).

    ``rng`` (int seed or numpy Generator) draws every run's temperature, drift scatter and heading; run ``i``
    uses noise seed ``i``. The same seed gives the same fleet.
    """
    rng = np.random.default_rng(rng)
    base = Path(out_dir)
    paths, drifts = [], []
    for i in range(n_runs):
        start, end, tau = rng.uniform(15, 25), rng.uniform(28, 40), rng.uniform(0.5, 3)
        drift = thermal_drift_deg_h(end) + rng.normal(0, scatter_deg_h)
        scn = Scenario.from_dict(
            {
                "run": {"duration_h": duration_h, "rate_hz": rate_hz, "seed": i},
                "gyro": {"bias_deg_h": [0.005, -0.004, drift], "arw_deg_rth": 0.0005},
                "accel": {"bias_ug": [30.0, -20.0, 10.0], "vrw_ug_rthz": 5.0},
                "temperature": {"start_c": start, "end_c": end, "tau_h": tau},
                "attitude": {"yaw_deg": float(rng.uniform(0, 360))},
            }
        )
        path = simulate(scn, out_dir=base / f"run{i:02d}")
        assert isinstance(path, Path)  # simulate writes a file when given a folder
        paths.append(path)
        drifts.append(drift)
    return paths, np.array(drifts)
