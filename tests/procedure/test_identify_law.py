"""The drift law `identify` reports (`gyrodrift.procedure.identify`, "The drift law"): eps_ref the identified
drift (the law at T_ref is the constant, to the bit), T_ref the temperature at the end of the features window, k1
and the covariance from the fleet posterior of (end drift, k_z) (`posterior_with_coefficient_prior`, itself tested
against a brute-force conditioning in tests/learn/test_fleet_prior_posterior.py) with the learned term's variance
on eps_ref; the constant where the model has no fleet base or the smoother no thermal model. Synthetic runs (the
features are given), then one simulated 16 h log through the CLI (slow)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from test_procedure_identify_fleet import _features, _Log, _run

from gyrodrift.drift_law import DriftLaw
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.fleet_prior import posterior_with_coefficient_prior
from gyrodrift.procedure.features import features_run_table
from gyrodrift.procedure.identify import FLEET_BASE, identify
from gyrodrift.procedure.writers import identification_document
from gyrodrift.runs.table import RunTable


@pytest.fixture(scope="module")
def fleet_model():
    rng = np.random.default_rng(5)
    training = RunTable.from_records([_run(rng, i, 2e-4) for i in range(16)], source="train.csv")
    return fit_drift_model(
        training, encoding="physics", target="residual", physics_column=FLEET_BASE, gamma=10.0, sigma=1.0
    )


def _posterior(rec: dict, prior) -> tuple:
    return posterior_with_coefficient_prior(
        rec["drift_smoother_deg_h"],
        rec["drift_smoother_std_deg_h"],
        rec["smoother_coeff_deg_h_per_c"],
        rec["smoother_coeff_std_deg_h_per_c"],
        rec["smoother_end_coeff_cov"],
        rec["smoother_coeff_prior_std_deg_h_per_c"],
        *prior,
    )


def test_the_law_of_a_thermal_run_is_the_fleet_posterior_and_at_t_ref_the_constant(fleet_model):
    rec = _run(np.random.default_rng(99), 99, 2e-4)
    f = _features(rec)
    res = identify(_Log(), fleet_model, features=f)
    law = res.drift_law
    assert not law.is_constant and not law.uses_rate
    # at T_ref the law is the constant identify reports, bit for bit
    assert law.t_ref_c == f.temp_end_c and law.eps_ref_deg_h == res.drift_deg_h
    assert float(law.drift_deg_h(f.temp_end_c)) == res.drift_deg_h
    thermal, d, k, vd, cdk, vk = _posterior(rec, fleet_model.coefficient_prior_)
    assert bool(thermal) and law.k1_deg_h_per_c == float(k)
    # k1 lies between the run's own k_z and the fleet's mean (shrinkage), its variance below both
    mean, std = fleet_model.coefficient_prior_
    lo, hi = sorted((rec["smoother_coeff_deg_h_per_c"], mean))
    assert lo < law.k1_deg_h_per_c < hi and vk < min(std, rec["smoother_coeff_std_deg_h_per_c"]) ** 2
    learned = float(fleet_model.learned_std_deg_h(features_run_table([f]))[0])
    assert learned > 0.0
    cov = np.array(law.cov)
    np.testing.assert_allclose(cov[:2, :2], [[vd + learned**2, cdk], [cdk, vk]], rtol=1e-14)
    assert np.all(cov[2] == 0.0) and np.all(cov[:, 2] == 0.0)  # k3 held at 0
    assert res.drift_law_std_deg_h == pytest.approx(math.sqrt(vd + learned**2), rel=1e-14)
    assert res.drift_law_std_deg_h > res.smoother_fleet_drift_std_deg_h  # the learned term's share on top
    # 5 degC above T_ref: eps_ref + 5 k1, 1-sigma from the gradient (1, 5, 0)
    assert float(law.drift_deg_h(f.temp_end_c + 5.0)) == pytest.approx(res.drift_deg_h + 5.0 * float(k), rel=1e-13)
    g = np.array([1.0, 5.0, 0.0])
    assert float(law.std_deg_h(f.temp_end_c + 5.0)) == pytest.approx(math.sqrt(g @ cov @ g), rel=1e-13)
    doc = json.loads(json.dumps(identification_document(res), allow_nan=False))
    assert DriftLaw.from_dict(doc["drift_law"], "identification.json") == law


def test_a_constant_model_run_and_another_base_give_the_constant(fleet_model):
    rec = _run(np.random.default_rng(7), 7, 2e-4)
    for key in ("smoother_coeff_deg_h_per_c", "smoother_coeff_std_deg_h_per_c", "smoother_end_coeff_cov"):
        rec[key] = math.nan
    rec["smoother_coeff_prior_std_deg_h_per_c"] = math.nan
    f = _features(rec)
    res = identify(_Log(), fleet_model, features=f)
    law = res.drift_law
    assert law.is_constant and law.eps_ref_deg_h == res.drift_deg_h and law.t_ref_c == f.temp_end_c
    learned = float(fleet_model.learned_std_deg_h(features_run_table([f]))[0])
    want = math.sqrt(rec["drift_smoother_std_deg_h"] ** 2 + learned**2)
    assert res.drift_law_std_deg_h == pytest.approx(want, rel=1e-14)
    assert identification_document(res)["drift_law"]["k1_deg_h_per_c"] == 0.0

    training = fleet_model.training_["runs"]
    other = fit_drift_model(
        training, encoding="physics", target="residual", physics_column="drift_inversion_deg_h", gamma=10.0, sigma=1.0
    )
    res = identify(_Log(), other, features=_features(_run(np.random.default_rng(8), 8, 2e-4)))
    assert res.drift_law.is_constant and res.drift_law.eps_ref_deg_h == res.drift_deg_h
    assert res.drift_law.cov is None and math.isnan(res.drift_law_std_deg_h)  # the inversion has no 1-sigma
    learner = fit_drift_model(training, encoding="physics", target="drift", gamma=10.0, sigma=1.0)
    res = identify(_Log(), learner, features=_features(_run(np.random.default_rng(9), 9, 2e-4)))
    table = features_run_table([res.features])
    assert res.drift_law.is_constant
    assert res.drift_law_std_deg_h == pytest.approx(float(learner.learned_std_deg_h(table)[0]), rel=1e-14)


@pytest.mark.slow
def test_identify_command_reports_the_law_of_a_warming_log(fleet_model, tmp_path):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.ins import Scenario, simulate
    from gyrodrift.learn.model_io import save_model
    from gyrodrift.logs import open_log

    save_model(fleet_model, tmp_path / "m.json")
    scn = {
        "site": {"lat_deg": 40.0},
        "run": {"duration_h": 16.1, "rate_hz": 1.0, "seed": 4},
        "gyro": {"bias_deg_h": [0.004, -0.003, 0.002], "arw_deg_rth": 0.0005},
        "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": 5.0},
        "temperature": {"start_c": 18.0, "end_c": 36.0, "tau_h": 4.0, "t0_c": 28.0, "k1_deg_h_per_c": 2e-4},
    }
    log = simulate(Scenario.from_dict(scn), out_dir=tmp_path / "run", quiet=True)
    res = identify(open_log(log), tmp_path / "m.json")
    sm = res.features.smoother
    assert sm.model == "thermal"
    # T_ref: the features' end-of-window temperature is the smoother's last sample, where its end drift refers to
    assert res.drift_law.t_ref_c == sm.temp_end_c == res.features.temp_end_c
    assert res.drift_law.eps_ref_deg_h == res.drift_deg_h and not res.drift_law.is_constant
    # the simulated unit's k1 (2e-4 deg/h/degC) within 3 of the law's 1-sigmas
    assert abs(res.drift_law.k1_deg_h_per_c - 2e-4) < 3.0 * math.sqrt(res.drift_law.cov[1][1])
    r = CliRunner().invoke(main, ["identify", str(log), "--model", str(tmp_path / "m.json"), "--json", "--quiet"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert DriftLaw.from_dict(doc["drift_law"]) == res.drift_law
    r = CliRunner().invoke(main, ["identify", str(log), "--model", str(tmp_path / "m.json")])
    assert r.exit_code == 0, r.output
    (line,) = [x for x in r.stdout.splitlines() if "drift law" in x]
    law = res.drift_law
    assert f"eps(T) = {law.eps_ref_deg_h:.6f} +- {res.drift_law_std_deg_h:.6f} + {law.k1_deg_h_per_c:.3e}" in line
    assert f"(T - {law.t_ref_c:.2f} degC)" in line and f"replacing the constant {res.drift_deg_h:.6f} deg/h" in line


def test_a_fleet_model_file_written_before_the_law_gives_the_law():
    """Model files carry what the law needs already (the fleet prior, the training runs): the fleet model file
    pinned in tests/data (written at ad28759) loads and gives a law whose k1 is its fleet posterior's."""
    from pathlib import Path

    from gyrodrift.learn.model_io import load_model

    model = load_model(Path(__file__).parents[1] / "data" / "model_schema4_fleet_before_parts.json")
    assert model.physics_column_ == FLEET_BASE
    rec = _run(np.random.default_rng(3), 3, 2e-4)
    res = identify(_Log(), model, features=_features(rec))
    _, _, k, _, _, vk = _posterior(rec, model.coefficient_prior_)
    assert res.drift_law.k1_deg_h_per_c == float(k) and res.drift_law.cov[1][1] == float(vk)
    assert res.drift_law.eps_ref_deg_h == res.drift_deg_h and math.isfinite(res.drift_law_std_deg_h)
