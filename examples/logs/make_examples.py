"""Write the two example logs of examples/logs/ from a simulated run (docs/procedure.md, "Logs in their own format").

Run: ``python examples/logs/make_examples.py [--out examples/logs] [--minutes 2]``. It simulates a short static
run (10 Hz, rotating table, 28.222 deg N) and writes it as two devices would record it:

* ``ins_export_degs.csv`` (`ins_export_degs.format.toml`): a ';'-separated export with a two-line preamble,
  time in ms, rates in deg/s and g, the sensor axes x forward, y left, z up, temperature in deg C and a status
  column the reader ignores;
* ``ins_pulses.parquet`` (`ins_pulses.format.toml`): pulse counts per sample (gyro 0.01 arcsec, accelerometer
  0.01 mm/s per pulse), ISO time stamps, axes x right, y backward, z down, temperature in K.

`to_degs_csv` and `to_pulses_parquet` convert any simulated log's columns (the test suite uses them).
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

G0 = 9.80665
GYRO_PULSE_ARCSEC = 0.01
ACCEL_PULSE_MM_S = 0.01


def to_degs_csv(cols: dict[str, np.ndarray], rate_hz: float, path: Path) -> Path:
    """Columns of a native increments log -> the ';' CSV in deg/s and g (file x = body forward, y = -right)."""
    gyro = np.column_stack([cols[f"dtheta_{a}_rad"] for a in "xyz"]) * rate_hz * 180.0 / math.pi  # deg/s
    acc = np.column_stack([cols[f"dv_{a}_m_s"] for a in "xyz"]) * rate_hz / G0  # g
    # body (right, forward, up) -> file (x forward, y left, z up)
    gf = np.column_stack([gyro[:, 1], -gyro[:, 0], gyro[:, 2]])
    af = np.column_stack([acc[:, 1], -acc[:, 0], acc[:, 2]])
    t_ms = np.round(cols["t_s"] * 1000.0).astype(np.int64)
    lines = [
        "# INS-9000 export, serial 0042, firmware 3.1",
        "# axes: x forward, y left, z up",
        "Time_ms;GyroX_dps;GyroY_dps;GyroZ_dps;AccX_g;AccY_g;AccZ_g;Temp_C;Status",
    ]
    for i in range(len(t_ms)):
        cells = [str(t_ms[i]), *(repr(float(v)) for v in gf[i]), *(repr(float(v)) for v in af[i])]
        cells += [f"{cols['temp_c'][i]:.4f}", "OK"]
        lines.append(";".join(cells))
    path.write_text("\n".join(lines) + "\n")
    return path


def _pulses(increments: np.ndarray, weight: float) -> np.ndarray:
    """Counts whose running sum follows the running sum of the increments (a counter keeps its remainder)."""
    total = np.round(np.cumsum(increments, axis=0) / weight).astype(np.int64)
    return np.diff(total, axis=0, prepend=np.zeros((1, total.shape[1]), dtype=np.int64))


def to_pulses_parquet(cols: dict[str, np.ndarray], path: Path, start: str = "2024-05-01T08:00:00") -> Path:
    """Columns of a native increments log -> Parquet pulse counts (file x right, y backward, z down), ISO time."""
    dth = np.column_stack([cols[f"dtheta_{a}_rad"] for a in "xyz"]) * (180.0 / math.pi * 3600.0)  # arcsec
    dv = np.column_stack([cols[f"dv_{a}_m_s"] for a in "xyz"]) * 1000.0  # mm/s
    # body (right, forward, up) -> file (x right, y backward, z down)
    flip = np.array([1.0, -1.0, -1.0])
    g = _pulses(dth * flip, GYRO_PULSE_ARCSEC)
    a = _pulses(dv * flip, ACCEL_PULSE_MM_S)
    t_ns = np.datetime64(start, "ns") + np.round(cols["t_s"] * 1e9).astype("timedelta64[ns]")
    table = pa.table(
        {
            "timestamp": pa.array(t_ns, pa.timestamp("ns")),
            **{f"gyro_{k}_pulses": pa.array(g[:, i], pa.int64()) for i, k in enumerate("xyz")},
            **{f"acc_{k}_pulses": pa.array(a[:, i], pa.int64()) for i, k in enumerate("xyz")},
            "board_temp_k": pa.array(np.round(cols["temp_c"] + 273.15, 3), pa.float64()),
        }
    )
    pq.write_table(table, path)
    return path


def simulated_columns(minutes: float, workdir: Path) -> tuple[dict[str, np.ndarray], float]:
    """A short simulated static run (10 Hz) as native columns, and its rate [Hz]."""
    from gyrodrift.ins import Scenario, simulate

    scn = Scenario.from_dict(
        {
            "run": {"duration_h": minutes / 60.0, "rate_hz": 10.0, "seed": 7},
            "site": {"lat_deg": 28.222, "lon_deg": 112.99, "height_m": 50.0},
            "gyro": {"bias_deg_h": [0.005, -0.004, 0.0015], "arw_deg_rth": 0.0005},
            "accel": {"bias_ug": [20.0, -15.0, 10.0], "vrw_ug_rthz": 5.0},
            "temperature": {"start_c": 22.0, "end_c": 30.0, "tau_h": 1.0},
        }
    )
    table = pq.read_table(simulate(scn, out_dir=workdir, quiet=True))
    return {c: table.column(c).to_numpy() for c in table.column_names}, scn.run.rate_hz


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).parent)
    ap.add_argument("--minutes", type=float, default=2.0)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cols, rate = simulated_columns(args.minutes, Path(tmp) / "sim")
    print(to_degs_csv(cols, rate, args.out / "ins_export_degs.csv"))
    print(to_pulses_parquet(cols, args.out / "ins_pulses.parquet"))


if __name__ == "__main__":
    main()
