"""A refusal of the Rust core while it processes a log (aligner, smoother, navigators) names the log file.

The core's `CoreError` knows the quantity and the time, not the file: `ImuLog.core_errors` adds the log's label
(and the row the core's time is counted from, when that is not the log's first sample).
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.errors import CoreDivergedError, CoreError
from gyrodrift.ins.stream import run_navigators
from gyrodrift.logs import ImuLog, open_log

G = 9.80665


@pytest.fixture(scope="module")
def five_g_log(tmp_path_factory) -> str:
    """16.2 h at 1 Hz of a static IMU with 5 g on the x accelerometer after its first 400 s: no static base the
    aligner or the smoother can explain (the samples themselves are within the sensor limits, and the first 400 s,
    a level IMU at 30 deg with the Earth rate, pass the reader's static-base check)."""
    n = int(16.2 * 3600)
    w = 7.2921151467e-5
    cols = {"t_s": np.arange(1, n + 1, dtype=float)}
    cols.update({"dtheta_x_rad": np.zeros(n), "dtheta_y_rad": np.full(n, w * np.cos(np.pi / 6))})
    cols["dtheta_z_rad"] = np.full(n, w * np.sin(np.pi / 6))
    dv_x = np.where(cols["t_s"] > 400.0, 5 * G, 0.0)
    cols.update({"dv_x_m_s": dv_x, "dv_y_m_s": np.zeros(n), "dv_z_m_s": np.full(n, G)})
    cols["temp_c"] = np.full(n, 30.0)
    path = tmp_path_factory.mktemp("five_g") / "five_g.parquet"
    pq.write_table(pa.table(cols), path)
    return str(path)


@pytest.mark.parametrize(
    ("command", "who"),
    [("navigate", "the fine alignment's"), ("features", "the smoother's")],
    ids=["aligner", "smoother"],
)
def test_a_core_refusal_of_the_log_names_the_file_in_one_line(five_g_log, tmp_path, command, who):
    out = tmp_path / ("nav" if command == "navigate" else "runs.csv")
    r = CliRunner().invoke(main, [command, five_g_log, "--lat0-deg", "30", "--out", str(out), "--quiet"])
    assert r.exit_code == 1, r.output
    assert r.output.count("\n") == 1 and "Traceback" not in r.output, r.output
    assert r.output.startswith(f"Error: {five_g_log}: "), r.output  # the file first, then the core's message
    assert "at t = " in r.output and who in r.output and "static base" in r.output, r.output
    assert not out.exists()


def test_the_kind_and_its_attributes_are_kept_and_a_named_error_is_not_named_twice(five_g_log):
    log = open_log(five_g_log, site={"lat_deg": 30.0})
    with pytest.raises(CoreError) as info, log.core_errors(), log.core_errors():
        err = CoreDivergedError("accel_bias_m_s2: at t = 3 s: no static base")
        err.key, err.t_s = "accel_bias_m_s2", 3.0
        raise err
    assert str(info.value) == f"{five_g_log}: accel_bias_m_s2: at t = 3 s: no static base"
    assert type(info.value) is CoreDivergedError
    assert (info.value.key, info.value.t_s) == ("accel_bias_m_s2", 3.0)
    assert type(info.value.__cause__) is CoreDivergedError


class _Refusing:
    """A navigator whose core refuses the second piece it is given (as `_core.Navigator` does when diverging)."""

    def __init__(self):
        self.calls = 0

    def process(self, dtheta, dv, decimation):
        self.calls += 1
        if self.calls == 2:
            raise CoreError("dtheta_rad: at t = 7 s: the navigated state left the Earth")
        return {"lat_rad": np.zeros(len(dtheta) // decimation)}

    def state(self):
        return {"lat_rad": 0.0}


def test_navigation_names_the_log_and_the_row_its_time_counts_from():
    n = 100
    cols = {"t_s": np.arange(1, n + 1) / 10.0, "temp_c": np.full(n, 20.0)}
    cols.update({f"dtheta_{a}_rad": np.zeros(n) for a in "xyz"})
    cols.update({f"dv_{a}_m_s": np.full(n, G if a == "z" else 0.0) for a in "xyz"})
    log = ImuLog.from_arrays(cols, label="nav.csv")
    with pytest.raises(
        CoreError, match=r"^nav\.csv: dtheta_rad: at t = 7 s: the navigated .* \(t counted from row 31\)$"
    ):
        run_navigators(log, [_Refusing()], n_samples=60, start=30, keys=("lat_rad",), threads=1, chunk_samples=20)
