"""The smoother's thermal columns of the run table (k_z, its 1-sigma, cov(end drift, k_z), its prior 1-sigma):
`features` writes them from the run's `SmootherEstimate` under its thermal model and leaves them empty under the
constant model or with --no-smoother. Short warm-up logs (1 h alignment + 3 h navigation, 2 Hz)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.ins import Scenario, simulate
from gyrodrift.logs import open_log
from gyrodrift.procedure.features import extract_features, features_run_table
from gyrodrift.procedure.timeline import Timeline
from gyrodrift.procedure.writers import features_csv_text
from gyrodrift.runs.columns import OPTIONAL_COLUMNS, SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import read_runs_csv, recognise_run_table

SHORT = Timeline(align_h=1.0, features_h=3.0, truth_h=3.0, coarse_s=60.0)
FIELDS = (
    "thermal_coeff_deg_h_per_c",
    "thermal_coeff_std_deg_h_per_c",
    "end_coeff_cov",
    "thermal_prior_std_deg_h_per_c",
)


def warm_up(start_c: float, end_c: float, seed: int = 1) -> Scenario:
    return Scenario.from_dict(
        {
            "site": {"lat_deg": 40.0},
            "run": {"duration_h": 4.2, "rate_hz": 2.0, "seed": seed},
            "gyro": {"bias_deg_h": [0.004, -0.003, 0.002], "arw_deg_rth": 0.0005},
            "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": 5.0},
            "temperature": {"start_c": start_c, "end_c": end_c, "tau_h": 1.5, "t0_c": 28.0, "k1_deg_h_per_c": 2e-4},
        }
    )


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    root = tmp_path_factory.mktemp("smoother_columns")
    return {
        "thermal": simulate(warm_up(18.0, 36.0), out_dir=root / "thermal", quiet=True),
        "flat": simulate(warm_up(28.0, 28.0, seed=2), out_dir=root / "flat", quiet=True),
    }


def test_the_columns_are_the_run_table_optional_columns():
    assert set(SMOOTHER_THERMAL_COLUMNS) <= set(OPTIONAL_COLUMNS)


def test_features_write_the_smoothers_thermal_columns(logs, tmp_path):
    f = extract_features(open_log(logs["thermal"]), timeline=SHORT)
    sm = f.smoother
    assert sm is not None and sm.model == "thermal"
    row = f.row()
    for column, name in zip(SMOOTHER_THERMAL_COLUMNS, FIELDS, strict=True):
        value = getattr(sm, name)
        assert math.isfinite(value) and getattr(f, column) == value and row[column] == value, column
    # the CSV round trip and the table identify hands to the model carry the same numbers
    path = tmp_path / "runs.csv"
    path.write_text(features_csv_text([f]))
    runs = read_runs_csv(path)
    table = features_run_table([f])
    for column in SMOOTHER_THERMAL_COLUMNS:
        assert runs.column(column)[0] == getattr(f, column) == table.column(column)[0], column


def test_constant_model_and_no_smoother_leave_the_cells_empty(logs, tmp_path):
    flat = extract_features(open_log(logs["flat"]), timeline=SHORT)
    assert flat.smoother is not None and flat.smoother.model == "constant"
    assert math.isfinite(flat.drift_smoother_deg_h)
    assert all(math.isnan(getattr(flat, c)) for c in SMOOTHER_THERMAL_COLUMNS)
    skipped = extract_features(open_log(logs["thermal"]), timeline=SHORT, smoother=False)
    assert all(math.isnan(getattr(skipped, c)) for c in ("drift_smoother_deg_h", *SMOOTHER_THERMAL_COLUMNS))
    header, *rows = features_csv_text([flat, skipped]).splitlines()
    cols = header.split(",")
    for row in rows:
        cells = dict(zip(cols, row.split(","), strict=True))
        assert all(cells[c] == "" for c in SMOOTHER_THERMAL_COLUMNS), cells
    table = features_run_table([flat, skipped])
    assert all(np.isnan(table.column(c)).all() for c in SMOOTHER_THERMAL_COLUMNS)


def test_features_command_writes_them_and_replaces_a_table_written_before_them(tmp_path):
    scn = warm_up(18.0, 36.0).to_toml_dict()
    scn["run"].update(duration_h=16.1, rate_hz=1.0)
    scn["temperature"]["tau_h"] = 4.0
    log = simulate(Scenario.from_dict(scn), out_dir=tmp_path / "long", quiet=True)
    out = tmp_path / "runs.csv"
    # a run table of the previous version (no thermal columns) is still recognised as gyrodrift's: replaced
    old = "run,lat_deg,lat0_deg,temp_min_c,temp_max_c,temp_start_c,temp_end_c,drift_curvefit_deg_h,"
    old += "drift_curvefit_std_deg_h,drift_smoother_deg_h,drift_smoother_std_deg_h\nx,1,1,1,1,1,1,,,,\n"
    out.write_text(old)
    assert recognise_run_table(out.read_bytes())
    r = CliRunner().invoke(main, ["features", str(log), "--out", str(out), "--quiet"])
    assert r.exit_code == 0, r.output
    assert "note: the 1-sigma assumes white sensor noise only" in r.stderr  # no --noise: measured, white only
    f = extract_features(open_log(log))
    assert f.smoother is not None and f.smoother.model == "thermal"
    runs = read_runs_csv(out)
    for column in ("drift_smoother_deg_h", *SMOOTHER_THERMAL_COLUMNS):
        assert runs.column(column)[0] == getattr(f, column), column
    r = CliRunner().invoke(main, ["features", str(log), "--out", str(out), "--no-smoother", "--quiet"])
    assert r.exit_code == 0, r.output
    assert "white sensor noise" not in r.stderr  # neither a smoother nor a label: no 1-sigma to qualify
    runs = read_runs_csv(out)
    for column in ("drift_smoother_deg_h", *SMOOTHER_THERMAL_COLUMNS):
        assert np.isnan(runs.column(column)[0]), column
