"""`identify` with a hybrid whose physics base is the fleet-prior smoother (``drift_smoother_fleet_deg_h``): the run
row it hands to the model carries the smoother's thermal columns, the model predicts, and the result reports the
base (the smoother's end drift re-weighted by the model's pooled k_z prior) with its 1-sigma; the model's drift is
that base plus the LSSVR's learned correction. A model with another base reports no fleet base. Synthetic runs
(no log is read: the features are given)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

from gyrodrift.choices import PHYSICS_COLUMNS
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior
from gyrodrift.procedure.identify import FLEET_BASE, identify
from gyrodrift.procedure.results import RunFeatures
from gyrodrift.procedure.writers import identification_document
from gyrodrift.runs.table import RunTable

needs_fleet_base = pytest.mark.skipif(FLEET_BASE not in PHYSICS_COLUMNS, reason="the fleet-prior base is not in")


@dataclass
class _Log:
    label: str = "new.parquet"


def _run(rng, i: int, k_true: float) -> dict:
    lat0 = rng.uniform(20.0, 60.0)
    t_lo = rng.uniform(15.0, 25.0)
    t_hi = rng.uniform(30.0, 40.0)
    drift = 0.002 + k_true * (t_hi - 28.0) + 1e-4 * rng.normal()
    k_std = rng.uniform(8e-5, 2e-4)
    return {
        "run": f"r{i}",
        "lat_deg": lat0 + 3e-4 * (drift / 0.002),
        "lat0_deg": lat0,
        "temp_min_c": t_lo,
        "temp_max_c": t_hi,
        "drift_deg_h": drift,
        "drift_std_deg_h": 1.5e-4,
        "drift_smoother_deg_h": drift + 3e-4 * rng.normal(),
        "drift_smoother_std_deg_h": 3e-4,
        "smoother_coeff_deg_h_per_c": k_true + k_std * rng.normal(),
        "smoother_coeff_std_deg_h_per_c": k_std,
        "smoother_end_coeff_cov": 0.6 * 3e-4 * k_std,
        "smoother_coeff_prior_std_deg_h_per_c": 0.01,
    }


@pytest.fixture(scope="module")
def training():
    rng = np.random.default_rng(5)
    return RunTable.from_records([_run(rng, i, 2e-4) for i in range(16)], source="train.csv")


def _features(rec: dict) -> RunFeatures:
    return RunFeatures(
        run="new",
        lat_deg=rec["lat_deg"],
        lat0_deg=rec["lat0_deg"],
        lat_err_curve_arcsec=np.zeros(13),
        temp_start_c=rec["temp_min_c"],
        temp_end_c=rec["temp_max_c"],
        temp_min_c=rec["temp_min_c"],
        temp_max_c=rec["temp_max_c"],
        drift_curvefit_deg_h=rec["drift_deg_h"],
        drift_curvefit_std_deg_h=2e-4,
        drift_smoother_deg_h=rec["drift_smoother_deg_h"],
        drift_smoother_std_deg_h=rec["drift_smoother_std_deg_h"],
        smoother_coeff_deg_h_per_c=rec["smoother_coeff_deg_h_per_c"],
        smoother_coeff_std_deg_h_per_c=rec["smoother_coeff_std_deg_h_per_c"],
        smoother_end_coeff_cov=rec["smoother_end_coeff_cov"],
        smoother_coeff_prior_std_deg_h_per_c=rec["smoother_coeff_prior_std_deg_h_per_c"],
    )


@needs_fleet_base
def test_identify_reports_the_fleet_base_and_the_model_is_base_plus_correction(training):
    model = fit_drift_model(
        training, encoding="physics", target="residual", physics_column=FLEET_BASE, gamma=10.0, sigma=1.0
    )
    assert model.physics_column_ == FLEET_BASE and model.coefficient_prior_ is not None
    rec = _run(np.random.default_rng(99), 99, 2e-4)
    f = _features(rec)
    res = identify(_Log(), model, features=f)
    mean, std = model.coefficient_prior_
    base, base_std = drift_with_coefficient_prior(
        rec["drift_smoother_deg_h"],
        rec["drift_smoother_std_deg_h"],
        rec["smoother_coeff_deg_h_per_c"],
        rec["smoother_coeff_std_deg_h_per_c"],
        rec["smoother_end_coeff_cov"],
        rec["smoother_coeff_prior_std_deg_h_per_c"],
        mean,
        std,
    )
    assert res.model_physics_column == FLEET_BASE
    assert res.coefficient_prior_deg_h_per_c == (mean, std)
    assert (res.smoother_fleet_drift_deg_h, res.smoother_fleet_drift_std_deg_h) == (base, base_std)
    assert base != rec["drift_smoother_deg_h"] and base_std < rec["drift_smoother_std_deg_h"]
    # the model's drift: that base plus the LSSVR's learned correction on the run's encoded inputs
    from gyrodrift.procedure.features import features_run_table

    table = features_run_table([f])
    correction = float(model.learner_.named_steps["lssvr"].predict(model.learner_[:-1].transform(table))[0])
    assert res.drift_deg_h == pytest.approx(base + correction, rel=0, abs=1e-12)
    assert abs(correction) > 1e-7  # a correction is learned, not zero
    doc = json.loads(json.dumps(identification_document(res), allow_nan=False))
    assert doc["model_physics_column"] == FLEET_BASE
    assert doc["smoother_fleet_drift_deg_h"] == base and doc["coefficient_prior_deg_h_per_c"] == [mean, std]
    assert doc["features"]["smoother_coeff_deg_h_per_c"] == rec["smoother_coeff_deg_h_per_c"]


def test_a_model_with_another_base_reports_no_fleet_base(training):
    model = fit_drift_model(
        training, encoding="physics", target="residual", physics_column="drift_inversion_deg_h", gamma=10.0, sigma=1.0
    )
    rec = _run(np.random.default_rng(98), 98, 2e-4)
    res = identify(_Log(), model, features=_features(rec))
    assert res.model_physics_column == "drift_inversion_deg_h"
    assert math.isnan(res.smoother_fleet_drift_deg_h) and res.coefficient_prior_deg_h_per_c is None
    doc = identification_document(res)
    assert doc["smoother_fleet_drift_deg_h"] is None and doc["coefficient_prior_deg_h_per_c"] is None


@pytest.mark.slow
@needs_fleet_base
def test_identify_command_prints_the_fleet_base_of_a_saved_model(training, tmp_path):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.ins import Scenario, simulate
    from gyrodrift.learn.model_io import save_model

    model = fit_drift_model(
        training, encoding="physics", target="residual", physics_column=FLEET_BASE, gamma=10.0, sigma=1.0
    )
    save_model(model, tmp_path / "m.json")
    scn = {
        "site": {"lat_deg": 40.0},
        "run": {"duration_h": 16.1, "rate_hz": 1.0, "seed": 4},
        "gyro": {"bias_deg_h": [0.004, -0.003, 0.002], "arw_deg_rth": 0.0005},
        "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": 5.0},
        "temperature": {"start_c": 18.0, "end_c": 36.0, "tau_h": 4.0, "t0_c": 28.0, "k1_deg_h_per_c": 2e-4},
    }
    log = simulate(Scenario.from_dict(scn), out_dir=tmp_path / "run", quiet=True)
    r = CliRunner().invoke(main, ["identify", str(log), "--model", str(tmp_path / "m.json"), "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["model_physics_column"] == FLEET_BASE and doc["smoother_model"] == "thermal"
    f = doc["features"]
    mean, std = doc["coefficient_prior_deg_h_per_c"]
    assert (mean, std) == pytest.approx(model.coefficient_prior_, rel=1e-15)
    base, base_std = drift_with_coefficient_prior(
        f["drift_smoother_deg_h"],
        f["drift_smoother_std_deg_h"],
        f["smoother_coeff_deg_h_per_c"],
        f["smoother_coeff_std_deg_h_per_c"],
        f["smoother_end_coeff_cov"],
        f["smoother_coeff_prior_std_deg_h_per_c"],
        mean,
        std,
    )
    assert doc["smoother_fleet_drift_deg_h"] == base and doc["smoother_fleet_drift_std_deg_h"] == base_std
    r = CliRunner().invoke(main, ["identify", str(log), "--model", str(tmp_path / "m.json")])
    assert r.exit_code == 0, r.output
    line = next(x for x in r.stdout.splitlines() if "training fleet's k_z prior" in x)
    assert f"{base:.6f} +- {base_std:.6f} deg/h" in line
    assert f"learned correction {doc['drift_deg_h'] - base:+.6f} deg/h" in line
