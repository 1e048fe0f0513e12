"""Drifts far outside an RLG's range or the training labels are flagged (issue 18, item 2).

A run table written in mdeg/h (the paper's labels times 1000: 0.22-3.45 'deg/h') was accepted as deg/h: `fit`
now warns naming the column and the runs, `predict` flags each drift beyond a navigation-grade RLG
(`gyrodrift.runs.table.NAVIGATION_GRADE_DRIFT_DEG_H`) or far outside the training labels in its
``outside_drift_range`` column and on stderr, and `identify` in its JSON and warnings.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import gyrodrift
from gyrodrift.cli import main
from gyrodrift.runs.table import NAVIGATION_GRADE_DRIFT_DEG_H, drift_range_problems

PAPER_RUNS = Path(gyrodrift.__file__).parent / "data" / "paper_runs.csv"
FIT = ["--lat0-deg", "28.222", "--split", "train", "--encoding", "temp_range", "--target", "drift"]


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _mdeg_table(path: Path) -> Path:
    """The paper's run table with drift_deg_h written in mdeg/h (every label times 1000)."""
    rows = list(csv.DictReader(PAPER_RUNS.open()))
    for r in rows:
        r["drift_deg_h"] = repr(float(r["drift_deg_h"]) * 1000.0)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    path.write_text(buf.getvalue())
    return path


def test_the_range_is_navigation_grade_and_the_paper_lies_well_inside():
    labels = np.array([float(r["drift_deg_h"]) for r in csv.DictReader(PAPER_RUNS.open())])
    assert np.abs(labels).max() < NAVIGATION_GRADE_DRIFT_DEG_H / 10  # 0.0035 vs 0.1 deg/h
    assert drift_range_problems(labels, labels) == [None] * len(labels)
    assert all(drift_range_problems(labels * 1000.0))  # every row of the table in mdeg/h
    lo, hi = labels.min(), labels.max()
    w = hi - lo
    far = drift_range_problems([hi + 1.5 * w, lo - 1.5 * w, hi + 0.5 * w], labels)
    assert "far outside the training labels' range" in far[0] and "far outside" in far[1] and far[2] is None
    assert "beyond a navigation-grade RLG's 0.1 deg/h" in drift_range_problems([-0.3])[0]


def test_fit_warns_about_labels_in_mdeg_h_naming_the_column_and_runs(tmp_path):
    r = _cli("fit", _mdeg_table(tmp_path / "mdeg.csv"), *FIT, "--gamma", 10, "--sigma", 1, "--out", tmp_path / "m.json")
    assert r.exit_code == 0, r.output
    line = next(ln for ln in r.output.splitlines() if ln.startswith("warning:") and "drift_deg_h" in ln)
    assert "mdeg.csv, column drift_deg_h: 22 of 22 label(s) beyond a navigation-grade RLG's 0.1 deg/h" in line
    assert "rows of run(s) 1 (0.7), 2 (0.22)" in line and "a table in mdeg/h?" in line
    ok = _cli("fit", PAPER_RUNS, *FIT, "--gamma", 10, "--sigma", 1, "--out", tmp_path / "ok.json")
    assert ok.exit_code == 0 and "beyond a navigation-grade" not in ok.output


def test_predict_flags_drifts_beyond_the_rlg_range_in_its_column_and_on_stderr(tmp_path):
    mdeg = _mdeg_table(tmp_path / "mdeg.csv")
    assert _cli("fit", mdeg, *FIT, "--gamma", 10, "--sigma", 1, "--out", tmp_path / "m.json").exit_code == 0
    r = _cli("predict", mdeg, "--model", tmp_path / "m.json", "--lat0-deg", 28.222, "--split", "test", "--json")
    assert r.exit_code == 0, r.output
    rows = [json.loads(ln) for ln in r.output.splitlines() if ln.startswith("{")]
    assert len(rows) == 10
    for row in rows:
        beyond = abs(row["drift_identified_deg_h"]) > NAVIGATION_GRADE_DRIFT_DEG_H
        assert row["outside_drift_range"] == int(beyond)
        assert (f"warning: run {row['run']}: identified drift |" in r.output) == beyond
    assert all(row["outside_drift_range"] for row in rows)  # the mdeg model predicts mdeg-sized drifts (>= 0.18)
    assert _cli("fit", PAPER_RUNS, *FIT, "--gamma", 10, "--sigma", 1, "--out", tmp_path / "ok.json").exit_code == 0
    ok = _cli("predict", PAPER_RUNS, "--model", tmp_path / "ok.json", "--lat0-deg", 28.222, "--split", "test")
    assert ok.exit_code == 0
    table = list(csv.DictReader(io.StringIO(ok.output[ok.output.index("run,") :])))
    assert [row["outside_drift_range"] for row in table] == ["0"] * 10


@pytest.mark.parametrize("value", [0.5, -2.0])
def test_a_drift_between_the_rlg_range_and_the_table_limit_is_read_and_flagged(value):
    """Beyond 0.1 deg/h a drift is flagged, not refused (a run table refuses only |drift| > 10 deg/h: no RLG)."""
    assert drift_range_problems([value])[0].startswith(f"|{value:g}| deg/h is beyond")


def test_identify_flags_a_drift_beyond_the_rlg_range_in_json_and_on_stderr(tmp_path):
    """A model fitted on the mdeg/h table identifies a simulated run's drift in 'deg/h' a thousand times too large:
    the JSON says outside_drift_range and its range_warnings line (the text output prints it as a warning)."""
    from gyrodrift.ins import Scenario, simulate

    scn = Scenario.from_dict(
        {
            "run": {"duration_h": 16.0, "rate_hz": 2.0, "seed": 4},
            "gyro": {"bias_deg_h": [0.005, -0.004, 0.002], "arw_deg_rth": 0.0005},
            "accel": {"bias_ug": [30.0, -20.0, 10.0], "vrw_ug_rthz": 5.0},
            "temperature": {"start_c": 20.0, "end_c": 38.0, "tau_h": 1.0},
        }
    )
    log = simulate(scn, out_dir=tmp_path / "run", quiet=True)
    model = tmp_path / "m.json"
    assert (
        _cli("fit", _mdeg_table(tmp_path / "mdeg.csv"), *FIT, "--gamma", 10, "--sigma", 1, "--out", model).exit_code
        == 0
    )
    r = _cli("identify", log, "--model", model, "--json", "--quiet")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.output[r.output.index("{") :])
    assert abs(doc["drift_deg_h"]) > NAVIGATION_GRADE_DRIFT_DEG_H and doc["outside_drift_range"] is True
    assert any("identified drift |" in w and "navigation-grade RLG" in w for w in doc["range_warnings"])
