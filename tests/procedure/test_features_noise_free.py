"""features --with-truth on a noise-free log told its noise is zero: the label's 1-sigma is 0 (nothing to measure),
which the run table holds as unknown (an empty cell; the reader expects a 1-sigma > 0) and reads back."""

from __future__ import annotations

import math

import numpy as np

from gyrodrift.ins import Scenario, simulate
from gyrodrift.logs import open_log
from gyrodrift.procedure.features import extract_features
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.timeline import Timeline
from gyrodrift.procedure.writers import write_features_csv
from gyrodrift.runs.table import read_runs_csv

SHORT = Timeline(align_h=0.1, features_h=1.0, truth_h=1.0, coarse_s=60.0)


def test_a_noise_free_label_has_an_unknown_sigma_and_reads_back(tmp_path):
    scn = Scenario.from_dict(
        {"run": {"duration_h": 1.2, "rate_hz": 5.0}, "gyro": {"arw_deg_rth": 0.0}, "accel": {"vrw_ug_rthz": 0.0}}
    )
    log = open_log(simulate(scn, out_dir=tmp_path / "run", quiet=True))
    noise = SensorNoise(arw_deg_rth=0.0, vrw_ug_rthz=0.0, source="given")
    f = extract_features(log, timeline=SHORT, with_truth=True, smoother=False, noise=noise)
    assert f.drift_std_deg_h == 0.0 and math.isfinite(f.drift_deg_h)  # no noise: the label is exact
    out = tmp_path / "runs.csv"
    write_features_csv([f], out)
    header, row = out.read_text(encoding="utf-8").splitlines()
    cells = dict(zip(header.split(","), row.split(","), strict=True))
    assert cells["drift_std_deg_h"] == "" and float(cells["drift_deg_h"]) == f.drift_deg_h
    table = read_runs_csv(out, require_truth=True)
    assert np.isnan(table.column("drift_std_deg_h")).all()
    np.testing.assert_array_equal(table.drift_deg_h, [f.drift_deg_h])
