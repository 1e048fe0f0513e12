"""The predictor (`gyrodrift.learn.predictor.DriftPredictor`) a model file is read into without scikit-learn
(`load_predictor`): the same predictions, intervals and range checks as the fitted estimator, on models of every
target, several encodings and scalings, weighted or not, tuned or fixed; its input scaling against scikit-learn's
scalers; and the commands that use it leave scikit-learn unimported.

Tolerance: 0 (the same floats). The predictor and the estimator run the same operations on the same numbers on
purpose: the estimator delegates to its own predictor, and a loaded predictor's scaler is fitted with the operations
of scikit-learn's (compared to the bit below), so a difference in the last bit is a bug, not rounding.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from sklearn.preprocessing import MinMaxScaler, StandardScaler

from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.model_io import ModelFileError, load_model, load_predictor, model_to_dict, save_model
from gyrodrift.learn.scaling import InputScaler
from gyrodrift.runs.datasets import load_paper
from gyrodrift.runs.table import RunTable


def fleet(rng: np.random.Generator, n: int) -> RunTable:
    """Runs at three sites [deg, deg C, deg/h] with label 1-sigmas and the smoother's columns (its thermal k_z on
    all but 4 runs), so that the default hybrid resolves to the fleet-prior smoother and the fit is weighted."""
    lat0 = rng.choice([20.5, 34.1, 51.3], n)
    err = rng.uniform(-120.0, 120.0, n)
    tmin = rng.uniform(10.0, 50.0, n)
    tmax = tmin + rng.uniform(0.5, 8.0, n)
    kz = rng.normal(2e-4, 4e-5, n)
    drift = 0.004 + kz * (tmax - 30.0) + 0.002 * np.sin(err / 60.0) + rng.normal(0.0, 2e-4, n)
    d_std, k_std = rng.uniform(1e-4, 5e-4, n), rng.uniform(5e-5, 3e-4, n)
    constant = np.zeros(n, bool)
    constant[:4] = True
    thermal = {
        "smoother_coeff_deg_h_per_c": kz + rng.normal(0.0, k_std),
        "smoother_coeff_std_deg_h_per_c": k_std,
        "smoother_end_coeff_cov": rng.uniform(-0.9, 0.9, n) * d_std * k_std,
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e-2),
    }
    extra = {
        "drift_std_deg_h": rng.uniform(5e-5, 3e-4, n),
        "drift_smoother_deg_h": drift + rng.normal(0.0, d_std),
        "drift_smoother_std_deg_h": d_std,
        **{name: np.where(constant, np.nan, v) for name, v in thermal.items()},
    }
    return RunTable(
        run=np.array([f"f{i}" for i in range(n)]),
        lat_deg=lat0 + err / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=drift,
        extra=extra,
        source="fleet",
    )


PAPER = load_paper()
FLEET_TRAIN, FLEET_NEW = fleet(np.random.default_rng(5), 30), fleet(np.random.default_rng(6), 40)
CASES = {
    "drift, temp_range, standard, tuned": (PAPER, dict(max_iter=8, rng=0)),
    "drift, temp_mean, minmax, fixed": (PAPER, dict(encoding="temp_mean", scaling="minmax", gamma=50.0, sigma=0.3)),
    "drift, temp_span, none, fixed": (PAPER, dict(encoding="temp_span", scaling="none", gamma=100.0, sigma=20.0)),
    "residual on the inversion, physics": (
        PAPER,
        dict(encoding="physics", target="residual", gamma=30.0, sigma=1.0),
    ),
    "residual on the fleet base, weighted, tuned": (FLEET_TRAIN, dict(target="residual", max_iter=8, rng=1)),
    "residual on the fleet base, out-of-fold calibration": (
        FLEET_TRAIN,
        dict(target="residual", gamma=100.0, sigma=0.7, calibration_folds=5),
    ),
}


def _same(a, b) -> None:
    np.testing.assert_allclose(a, b, rtol=0.0, atol=0.0)  # tolerance 0: the same operations (module docstring)


@pytest.mark.parametrize("case", list(CASES))
def test_the_predictor_of_a_model_file_predicts_as_the_fitted_estimator(tmp_path, case):
    data, options = CASES[case]
    train = data.train if data is PAPER else data
    new = data.test if data is PAPER else FLEET_NEW
    model = fit_drift_model(train, **options)
    path = tmp_path / "model.json"
    save_model(model, path)
    loaded = load_predictor(path)
    assert type(loaded).__name__ == "DriftPredictor"
    for runs in (new, train):
        _same(loaded.predict(runs), model.predict(runs))
        for got, want in zip(loaded.predict_interval(runs, 0.9), model.predict_interval(runs, 0.9), strict=True):
            _same(got, want)
        _same(loaded.learned_std_deg_h(runs), model.learned_std_deg_h(runs))
        _same(loaded.predict_spread(runs), model.predict_spread(runs))
        check, want = loaded.check_inputs(runs), model.check_inputs(runs)
        _same(check.mahalanobis, want.mahalanobis)
        assert check.outside.tolist() == want.outside.tolist() and check.outside_inputs == want.outside_inputs
    assert loaded.interval_note(0.8) == model.interval_note(0.8)
    assert loaded.interval_summary(0.9) == model.interval_summary(0.9)
    assert loaded.fit_warnings() == model.fit_warnings()
    assert (loaded.physics_column_, loaded.coefficient_prior_) == (model.physics_column_, model.coefficient_prior_)
    assert loaded.training == load_model(path).training  # a file keeps no flagged_* lists
    _same(loaded.loo_residuals(), model.loo_residuals())
    assert loaded.tuning == model.tuning


def test_a_file_without_the_stored_solution_is_rebuilt_by_the_estimator(tmp_path):
    model = fit_drift_model(PAPER.train, gamma=10.0, sigma=1.0)
    doc = model_to_dict(model)
    del doc["fitted"]["dual_coef_deg_h"]
    path = tmp_path / "old.json"
    path.write_text(json.dumps(doc))
    _same(load_predictor(path).predict(PAPER.test), model.predict(PAPER.test))


def test_an_edited_coefficient_is_refused_by_the_predictor_as_by_the_estimator(tmp_path):
    doc = model_to_dict(fit_drift_model(PAPER.train, gamma=10.0, sigma=1.0))
    doc["fitted"]["dual_coef_deg_h"][0] += 1e-3
    doc["fitted"]["dual_coef_deg_h"][1] -= 1e-3  # still summing to 0
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(doc))
    for load in (load_model, load_predictor):
        with pytest.raises(ModelFileError, match=r"edited.json: .*stored solution does not solve the LSSVM system"):
            load(path)


@pytest.mark.parametrize("scaling, sklearn_scaler", [("standard", StandardScaler), ("minmax", MinMaxScaler)])
def test_the_input_scaler_fits_and_scales_as_scikit_learns_to_the_bit(scaling, sklearn_scaler):
    rng = np.random.default_rng(3)
    for trial in range(300):
        n, d = int(rng.integers(3, 200)), int(rng.integers(1, 5))
        E = rng.normal(rng.uniform(-1e3, 1e3, d), 10 ** rng.uniform(-8, 3, d), (n, d))
        if trial % 5 == 0:
            E[:, 0] = 3.7  # a constant input keeps scale 1
        new = rng.normal(E.mean(axis=0), E.std(axis=0) + 1.0, (7, d))
        ours, theirs = InputScaler.fit(scaling, E), sklearn_scaler().fit(E)
        _same(ours.transform(new), theirs.transform(new))
        _same(ours.transform(E), theirs.transform(E))
        step = InputScaler.of_step(scaling, theirs)
        _same(step.scale, ours.scale)
        _same(step.mean if scaling == "standard" else step.offset, ours.mean if scaling == "standard" else ours.offset)


LOADED = "sorted(m for m in sys.modules if m.split('.')[0] == 'sklearn' or m.startswith('scipy.stats'))"


@pytest.mark.parametrize(
    "command",
    [
        ["predict", "new.csv", "--model", "model.json", "--coverage", "0.9", "--out", "p.csv", "--quiet"],
        ["export", "--model", "model.json", "--lang", "c", "--out", "c", "--quiet"],
    ],
)
def test_predict_and_export_leave_scikit_learn_unimported(tmp_path, command):
    model = fit_drift_model(FLEET_TRAIN, target="residual", gamma=100.0, sigma=0.7)
    save_model(model, tmp_path / "model.json")
    FLEET_NEW.to_csv(tmp_path / "new.csv")
    code = (
        "import sys\nfrom gyrodrift.cli import main\n"
        f"main({command!r}, standalone_mode=False)\n"
        f"print('LOADED', {LOADED}, file=sys.stderr)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    line = [row for row in done.stderr.splitlines() if row.startswith("LOADED")]
    assert line == ["LOADED []"], done.stderr
    assert (tmp_path / command[command.index("--out") + 1]).exists()


def test_the_spread_models_distances_are_cdists_to_the_bit():
    from scipy.spatial.distance import cdist

    from gyrodrift.learn.spread import scaled_squared_distances

    rng = np.random.default_rng(4)
    for _ in range(100):
        d = int(rng.integers(1, 6))
        A = rng.normal(size=(int(rng.integers(1, 120)), d)) * rng.uniform(0.01, 100.0, d)
        B = rng.normal(size=(int(rng.integers(1, 40)), d)) * rng.uniform(0.01, 100.0, d)
        _same(scaled_squared_distances(A, B), cdist(A, B, "sqeuclidean"))
