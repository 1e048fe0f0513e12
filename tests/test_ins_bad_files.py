"""navigate refuses damaged IMU files with the file, row and column, and writes nothing in that case."""

import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from gyrodrift.cli.navigation import navigate_command
from gyrodrift.ins import Scenario, navigate, simulate
from gyrodrift.ins.imu_file import ImuFileError


@pytest.fixture(scope="module")
def imu(tmp_path_factory):
    scn = Scenario.from_dict({"run": {"duration_h": 0.05, "rate_hz": 10.0, "seed": 1}})
    return simulate(scn, out_dir=tmp_path_factory.mktemp("imu") / "run")


def _damaged(imu, tmp_path, column, row, value):
    table = pq.read_table(imu)
    values = table.column(column).to_numpy().copy()
    values[row - 1] = value(values) if callable(value) else value
    table = table.set_column(table.schema.get_field_index(column), column, [values])
    path = tmp_path / "bad.parquet"
    pq.write_table(table, path, row_group_size=700)  # several chunks, so the check crosses chunk boundaries
    return path


def test_nan_increment_is_named(imu, tmp_path):
    bad = _damaged(imu, tmp_path, "dv_z_m_s", 101, np.nan)
    with pytest.raises(ImuFileError, match=r"bad.parquet, row 101, column dv_z_m_s: expected a finite number"):
        navigate(bad, out_dir=tmp_path / "nav", chunk_samples=64)
    assert not (tmp_path / "nav" / "nav.parquet").exists() and not (tmp_path / "nav" / "summary.json").exists()


@pytest.mark.parametrize("row", [2, 65, 1001])
def test_repeated_time_is_named_also_across_chunks(imu, tmp_path, row):
    bad = _damaged(imu, tmp_path, "t_s", row, lambda t: t[row - 2])
    with pytest.raises(ImuFileError, match=rf"row {row}, column t_s: time must be strictly increasing"):
        navigate(bad, chunk_samples=64)


def test_more_hours_than_the_file_holds(imu, tmp_path):
    r = CliRunner().invoke(navigate_command, [str(imu), "--hours", "1", "--out", str(tmp_path / "n"), "--quiet"])
    assert r.exit_code == 1 and "1 h asked but the IMU data hold 0.05 h" in r.output
