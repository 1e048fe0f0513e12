"""navigate refuses damaged IMU files with the file, row and column, and writes nothing in that case."""

import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.ins import Scenario, simulate
from gyrodrift.logs import LogError
from gyrodrift.procedure import navigate


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
    with pytest.raises(LogError, match=r"bad.parquet, row 101, column dv_z_m_s: empty or NaN cell"):
        navigate(bad, out_dir=tmp_path / "nav", chunk_samples=64)
    assert not (tmp_path / "nav" / "nav.parquet").exists() and not (tmp_path / "nav" / "summary.json").exists()


@pytest.mark.parametrize("row", [2, 65, 1001])
def test_repeated_time_is_named_also_across_chunks(imu, tmp_path, row):
    bad = _damaged(imu, tmp_path, "t_s", row, lambda t: t[row - 2])
    with pytest.raises(
        LogError, match=rf"row {row}, column t_s: duplicated time stamp .*; time must be strictly increasing"
    ):
        navigate(bad, chunk_samples=64)


def test_more_hours_than_the_file_holds(imu, tmp_path):
    r = CliRunner().invoke(main, ["navigate", str(imu), "--hours", "1", "--out", str(tmp_path / "n"), "--quiet"])
    assert r.exit_code == 1 and "1 h asked but the IMU data hold 0.05 h" in r.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--hours", "nan"], "Invalid value for '--hours': 'nan' is not a finite number"),
        (["--hours", "1e400"], "Invalid value for '--hours': '1e400' is not a finite number"),
        (["--hours", "1e308"], "--hours 1e+308: 1e+308 h asked but the IMU data hold 0.05 h"),
        (["--hours", "1e-9"], "--hours 1e-09 h is 0 sample(s), shorter than one output step (1 s = 10 samples)"),
        (["--drift-deg-h", "nan"], "Invalid value for '--drift-deg-h': 'nan'"),
        (["--lat0-deg", "nan"], "Invalid value for '--lat0-deg': 'nan' is not a finite number"),
        (["--lat0-deg", "90"], "Invalid value for '--lat0-deg': '90' is not in (-90, 90)"),
    ],
)
def test_navigate_options_are_one_line_errors_naming_the_option(imu, tmp_path, args, message):
    r = CliRunner().invoke(main, ["navigate", str(imu), *args, "--out", str(tmp_path / "n"), "--quiet"])
    assert r.exit_code in (1, 2) and message in r.output, r.output
    assert r.exception is None or isinstance(r.exception, SystemExit)
    assert not (tmp_path / "n" / "nav.parquet").exists()


@pytest.mark.parametrize(
    ("command", "args", "message"),
    [
        ("truth", ["--hours", "nan"], "Invalid value for '--hours'"),
        ("truth", ["--hours", "1e308"], "--hours 1e+308: more than a million hours"),
        ("truth", ["--hours", "1e-9"], "--hours 1e-09: shorter than one output step of the error curves (60 s)"),
        ("evaluate", ["--drift-deg-h", "nan"], "Invalid value for '--drift-deg-h': 'nan'"),
        ("evaluate", ["--drift-deg-h", "0.001", "--hours", "1e-9"], "--hours 1e-09: shorter than one output step"),
        ("features", ["--lat0-deg", "nan"], "Invalid value for '--lat0-deg'"),
        ("identify", ["--model", "m.json", "--lat0-deg", "nan"], "Invalid value for '--lat0-deg'"),
        ("truth", ["--lat0-deg", "nan"], "Invalid value for '--lat0-deg'"),
    ],
)
def test_procedure_options_are_one_line_errors_naming_the_option(imu, tmp_path, command, args, message):
    out = {"evaluate": ["--out", str(tmp_path / "e")], "features": ["--out", str(tmp_path / "f.csv")]}
    r = CliRunner().invoke(main, [command, str(imu), *args, *out.get(command, [])])
    assert r.exit_code in (1, 2) and message in r.output, r.output
    assert r.exception is None or isinstance(r.exception, SystemExit)
