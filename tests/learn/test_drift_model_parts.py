"""The drift model is its parts joined by a small meta-estimator (issue 19): a learner pipeline, a physics base, an
interval and input ranges; and a model file written before the parts existed loads with the numbers it holds, and
refitting it today gives the same file."""

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from sklearn.base import clone

from gyrodrift.cli import main
from gyrodrift.learn.drift_model import fit_drift_model, make_drift_model
from gyrodrift.learn.interval import DriftInterval
from gyrodrift.learn.model_io import load_model, model_to_dict
from gyrodrift.learn.physics_base import PhysicsBase, physics_estimate
from gyrodrift.learn.ranges import InputRanges
from gyrodrift.runs.datasets import load_paper, paper_csv_path

DATA = Path(__file__).resolve().parents[1] / "data"
BEFORE = DATA / "model_schema4_before_parts.json"
"""`gyrodrift fit paper_runs.csv --lat0-deg 45.7 --seed 1 --out model.json`, written by the code before the drift
model was split into parts (commit ad28759)."""
FLEET_BEFORE = DATA / "model_schema4_fleet_before_parts.json"
"""`gyrodrift fit runs.csv --seed 1` on the run table of ``campaign examples/campaigns/tiny.toml`` at commit ad28759:
a hybrid on the fleet-prior smoother base, its training runs with label 1-sigmas and every optional column."""


@pytest.fixture(scope="module")
def paper():
    return load_paper()


def test_a_hybrid_predicts_its_physics_base_plus_its_learner(paper):
    model = fit_drift_model(paper.train, encoding="temperature", target="residual", gamma=30.0, sigma=1.5)
    assert isinstance(model.base_, PhysicsBase) and isinstance(model.interval_, DriftInterval)
    assert isinstance(model.ranges_, InputRanges) and model.physics_column_ == "drift_inversion_deg_h"
    base = physics_estimate(paper.test, "drift_inversion_deg_h")
    np.testing.assert_allclose(model.predict(paper.test), base + model.learner_.predict(paper.test), rtol=1e-12)
    # the learner learnt the labels minus the base: its leave-one-out residuals are those of the drift
    np.testing.assert_array_equal(model.loo_residuals_deg_h, model.learner_.named_steps["lssvr"].loo_residuals_)


def test_the_parameters_are_the_learners_and_the_models_own_and_fit_leaves_them_unfitted(paper):
    model = make_drift_model(encoding="temp_span", method="grid", grid_size=5)
    params = model.get_params()
    assert params["learner__encode__encoding"] == "temp_span" and params["learner__lssvr__grid_size"] == 5
    assert {"target", "physics_column", "label_weighting", "calibration_folds", "base_uncertainty"} <= set(params)
    twin = clone(model).set_params(learner__lssvr__grid_size=4, target="residual")
    assert twin.learner.named_steps["lssvr"].grid_size == 4 and model.learner.named_steps["lssvr"].grid_size == 5
    model.fit(paper.train)
    assert not hasattr(model.learner.named_steps["lssvr"], "lssvr_")  # fit works on a clone: learner_
    assert model.learner_.named_steps["lssvr"].tuning_.settings == {"grid_size": 5}


@pytest.mark.parametrize("path", [BEFORE, FLEET_BEFORE], ids=["paper", "fleet"])
def test_a_model_file_written_before_the_parts_loads_with_its_numbers(path):
    doc = json.loads(path.read_text())
    again = model_to_dict(load_model(path))  # the training runs' digest and the fitted record are checked
    for key in ("fitted", "lssvr_params", "tuning", "warnings", "target", "physics_column", "encoding"):
        assert again[key] == doc[key], key
    assert again["training"] == doc["training"]


def test_refitting_the_file_before_the_parts_gives_the_same_numbers(tmp_path):
    out = tmp_path / "model.json"
    args = ["fit", str(paper_csv_path()), "--lat0-deg", "45.7", "--seed", "1", "--out", str(out), "--quiet"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    now, before = json.loads(out.read_text()), json.loads(BEFORE.read_text())
    for doc in (now, before):
        del doc["gyrodrift_version"], doc["training"]["source"]
    assert _same(now, before, "")


def _same(a, b, where: str) -> bool:
    """Equal JSON documents, floats to 1e-9 relative: the leave-one-out objective is computed by LAPACK's
    Cholesky inverse (dpotrf + dpotri) since 2f9687c, the file by numpy's inverse before it; the two agree to 6.3e-12
    relative here and to 2.8e-10 over random stacks (tests of `gyrodrift.learn.lssvm_batch`), and another BLAS may
    round the last bits differently.

    A list of floats (dual coefficients, residuals) is one solution of a linear system, whose rounding error is
    bounded norm-wise: each element within 1e-9 of the list's largest magnitude. Elements near zero carry the
    absolute error of the whole vector: on an Emerald Rapids Xeon (OpenBLAS's AVX-512 kernels) dual coefficient 4
    of the paper's fit, -3.7e-08 among values up to 0.055, differed from the file's by 4e-15 deg/h: 1.2e-7 of
    itself, 8e-14 of the largest."""
    if isinstance(a, dict) and isinstance(b, dict):
        assert a.keys() == b.keys(), where
        return all(_same(a[k], b[k], f"{where}.{k}") for k in a)
    if isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), where
        if b and all(isinstance(x, float) for x in a + b):
            np.testing.assert_allclose(a, b, rtol=0.0, atol=1e-9 * max(abs(y) for y in b), err_msg=where)
            return True
        return all(_same(x, y, f"{where}[{i}]") for i, (x, y) in enumerate(zip(a, b, strict=True)))
    if isinstance(a, float) and isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=0.0), where
        return True
    assert a == b, where
    return True
