"""The fleet-prior smoother as the physics base of the hybrid drift model (issue 10, DESIGN10).

``physics_column="drift_smoother_fleet_deg_h"``: a run's base is its smoother end drift re-weighted by a prior on
its thermal coefficient k_z pooled from the training runs (`gyrodrift.learn.fleet_prior`), leave-one-out for the
training runs themselves; ``"auto"`` (the default) picks it when the table allows. The base's 1-sigma joins the
label's in the weights, the interval's Gaussian process and its calibration, and the new run's interval.

Synthetic fleets (no log is simulated): each run's smoother estimate is the exact linear-Gaussian posterior of
(end drift, k_z) from a correlated measurement of both and the smoother's own wide prior N(0, S0^2) on k_z, its
1-sigma growing with latitude (heteroscedastic), so re-weighting it by the fleet's prior is exact here.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, KFold, cross_val_score

from gyrodrift.cli import main
from gyrodrift.errors import InputError
from gyrodrift.learn.baselines import latitude_error_at
from gyrodrift.learn.drift_model import fit_drift_model, make_drift_model
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior, pooled_coefficient_prior
from gyrodrift.learn.lssvr import LSSVR
from gyrodrift.learn.model_io import ModelFileError, load_model, model_from_dict, model_to_dict, save_model
from gyrodrift.learn.physics_base import FLEET_PHYSICS, physics_estimate, resolve_physics_column
from gyrodrift.runs.columns import SMOOTHER_COLUMNS, SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import RunTable, read_runs_csv
from gyrodrift.units import HOUR

K_FLEET = 2e-4
"""The fleet's thermal coefficient [deg/h/degC]; units spread about it by `K_SPREAD`."""
K_SPREAD = 3e-5
S0 = 0.01
"""The smoother's own prior 1-sigma of k_z [deg/h/degC]."""


def synthetic_fleet(n: int, rng, *, constant=(), base_scale: float = 1.0, temp_shift: float = 0.0):
    """``(runs, effective)``: ``n`` runs with labels, label 1-sigmas and the smoother's columns (module
    docstring), and their effective drifts [deg/h] (the labels without their noise).

    The effective drift is the end-of-span drift plus a temperature term the learner has to find; the smoother's
    data determine (end drift, k_z) with 1-sigmas (a, c), correlation 0.8, ``a`` = 3e-4 base_scale deg/h at 20 deg
    growing as 1/cos(lat) (1.7 times at 60 deg). Runs whose index is in ``constant`` are under the smoother's
    constant model: their drift has 1-sigma ``a`` and no k_z columns."""
    lat0 = rng.uniform(20.0, 60.0, n)
    tmin = rng.uniform(15.0, 25.0, n) + temp_shift
    tmax = tmin + rng.uniform(8.0, 15.0, n)
    k_true = K_FLEET + rng.normal(0.0, K_SPREAD, n)
    end = 0.002 + rng.normal(0.0, 8e-4, n) + k_true * (tmax - 28.0)
    effective = end + 1.5e-4 * np.sin((tmax - tmin - 8.0) / 3.0)
    label_std = rng.uniform(5e-5, 2e-4, n)
    label = effective + label_std * rng.normal(size=n)
    seen = end - 1e-4 * (tmax - tmin) / 10.0 + rng.normal(0.0, 3e-4, n)
    a = 3e-4 * base_scale * np.cos(np.radians(20.0)) / np.cos(np.radians(lat0))
    c, rho = 2e-4, 0.8
    cols = {name: np.full(n, np.nan) for name in SMOOTHER_COLUMNS}
    for i in range(n):
        L = np.array([[a[i] ** 2, rho * a[i] * c], [rho * a[i] * c, c**2]])
        y = np.array([end[i], k_true[i]]) + np.linalg.cholesky(L) @ rng.normal(size=2)
        if i in constant:
            cols["drift_smoother_deg_h"][i] = end[i] + a[i] * rng.normal()
            cols["drift_smoother_std_deg_h"][i] = a[i]
            continue
        V = np.linalg.inv(np.linalg.inv(L) + np.diag([0.0, 1.0 / S0**2]))
        m = V @ np.linalg.solve(L, y)
        cols["drift_smoother_deg_h"][i], cols["drift_smoother_std_deg_h"][i] = m[0], math.sqrt(V[0, 0])
        cols[SMOOTHER_THERMAL_COLUMNS[0]][i], cols[SMOOTHER_THERMAL_COLUMNS[1]][i] = m[1], math.sqrt(V[1, 1])
        cols[SMOOTHER_THERMAL_COLUMNS[2]][i], cols[SMOOTHER_THERMAL_COLUMNS[3]][i] = V[0, 1], S0
    return RunTable(
        run=np.array([f"r{i}" for i in range(n)], dtype=object),
        lat_deg=lat0 + latitude_error_at(12 * HOUR, seen, lat0) / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=label,
        source="fleet.csv",
        extra={"drift_std_deg_h": label_std, **cols},
    ), effective


def _direct_base(runs: RunTable, prior) -> np.ndarray:
    """`drift_with_coefficient_prior` of each run with ``prior`` (one (mean, std) per run)."""
    cols = [runs.column(c) for c in SMOOTHER_COLUMNS]
    return np.array([drift_with_coefficient_prior(*(v[i] for v in cols), *prior[i])[0] for i in range(len(runs))])


@pytest.fixture(scope="module")
def fleet():
    return synthetic_fleet(14, np.random.default_rng(3), constant=(2, 9))


def test_the_fleet_base_is_fleet_prior_leave_one_out_for_training_runs(fleet):
    train, _ = fleet
    unweighted = train.replace(extra={k: v for k, v in train.extra.items() if k != "drift_std_deg_h"})
    model = fit_drift_model(unweighted, encoding="physics", target="residual", gamma=20.0, sigma=1.5)
    assert model.physics_column_ == FLEET_PHYSICS and model.physics_column == "auto"
    k, sk = train.column(SMOOTHER_THERMAL_COLUMNS[0]), train.column(SMOOTHER_THERMAL_COLUMNS[1])
    assert model.coefficient_prior_ == pooled_coefficient_prior(k, sk)
    # each training run's base: the prior pooled from the other runs (its own k_z not counted twice)
    loo = [pooled_coefficient_prior(np.delete(k, i), np.delete(sk, i)) for i in range(len(train))]
    base = _direct_base(train, loo)
    assert base[2] == train.column("drift_smoother_deg_h")[2]  # a constant-model run keeps its smoother drift
    full = _direct_base(train, [model.coefficient_prior_] * len(train))
    thermal = np.isfinite(k)
    assert np.all(base[thermal] != full[thermal]) and np.array_equal(base[~thermal], full[~thermal])
    Z = model.learner_[:-1].transform(train)
    reference = LSSVR(gamma=20.0, sigma=1.5).fit(Z, train.drift_deg_h - base)
    np.testing.assert_array_equal(model.lssvr.alpha_, reference.alpha_)
    # a new run's base: the prior of all training runs
    new, _ = synthetic_fleet(6, np.random.default_rng(4), constant=(1,))
    new_base = _direct_base(new, [model.coefficient_prior_] * 6)
    np.testing.assert_array_equal(physics_estimate(new, FLEET_PHYSICS, prior=model.coefficient_prior_), new_base)
    expected = new_base + reference.predict(model.learner_[:-1].transform(new))
    np.testing.assert_allclose(model.predict(new), expected, rtol=0, atol=1e-15)


def test_auto_resolves_to_the_fleet_base_the_smoother_or_the_inversion(fleet):
    train, _ = fleet
    assert resolve_physics_column(train)[0] == FLEET_PHYSICS
    two_thermal = train.replace(
        extra={
            **train.extra,
            **{c: np.where(np.arange(len(train)) < 2, train.column(c), np.nan) for c in SMOOTHER_THERMAL_COLUMNS},
        }
    )
    column, why = resolve_physics_column(two_thermal)
    assert column == "drift_smoother_deg_h" and "2 run(s) with the smoother's thermal k_z" in why
    gap = train.replace(
        extra={
            **train.extra,
            "drift_smoother_deg_h": np.where(np.arange(len(train)) == 5, np.nan, train.column("drift_smoother_deg_h")),
        }
    )
    column, why = resolve_physics_column(gap)
    assert column == "drift_inversion_deg_h" and "missing for run(s) r5" in why
    bare = train.replace(extra={"drift_std_deg_h": train.column("drift_std_deg_h")})
    assert resolve_physics_column(bare) == ("drift_inversion_deg_h", "no smoother columns: the 12 h inversion")
    for table, column in ((two_thermal, "drift_smoother_deg_h"), (bare, "drift_inversion_deg_h")):
        model = fit_drift_model(table, encoding="physics", target="residual", gamma=20.0, sigma=1.5)
        assert model.physics_column_ == column and model.coefficient_prior_ is None
    # the fleet base asked for explicitly on too few thermal runs: one line saying why
    with pytest.raises(InputError, match="needs at least 3 training runs with the smoother's thermal k_z.*got 2"):
        fit_drift_model(two_thermal, target="residual", physics_column=FLEET_PHYSICS, gamma=20.0, sigma=1.5)
    # a target="drift" model has no base
    plain = fit_drift_model(train, encoding="physics", gamma=20.0, sigma=1.5)
    assert plain.physics_column_ is None and plain.coefficient_prior_ is None


def test_fit_says_which_base_and_why_and_predict_needs_the_columns(fleet, tmp_path):
    train, _ = fleet
    data, model_file = tmp_path / "fleet.csv", tmp_path / "m.json"
    train.to_csv(data)
    fixed = ["--gamma", "20", "--sigma", "1.5", "--quiet"]
    r = CliRunner().invoke(main, ["fit", str(data), "--out", str(model_file), *fixed])
    assert r.exit_code == 0, r.output
    note = next(line for line in r.stderr.splitlines() if line.startswith("note: physics base:"))
    assert note.startswith(f"note: physics base: {FLEET_PHYSICS} (every run has the smoother's drift and 1-sigma")
    assert "pooled k_z prior" in note
    assert "combined with the physics base's 1-sigma" in r.stderr
    bare = tmp_path / "bare.csv"
    train.replace(extra={"drift_std_deg_h": train.column("drift_std_deg_h")}).to_csv(bare)
    r = CliRunner().invoke(main, ["fit", str(bare), "--out", str(tmp_path / "bare.json"), *fixed])
    assert "note: physics base: drift_inversion_deg_h (no smoother columns: the 12 h inversion)" in r.stderr
    r = CliRunner().invoke(
        main,
        ["fit", str(bare), "--out", str(tmp_path / "b2.json"), "--physics-column", "drift_inversion_deg_h", *fixed],
    )
    assert "note: physics base: drift_inversion_deg_h (--physics-column)" in r.stderr
    # predict with the fleet base: a table with the columns works (interval included) ...
    new, _ = synthetic_fleet(5, np.random.default_rng(8), constant=(0,))
    new_csv = tmp_path / "new.csv"
    new.to_csv(new_csv)
    r = CliRunner().invoke(main, ["predict", str(new_csv), "--model", str(model_file), "--coverage", "0.9"])
    assert r.exit_code == 0, r.output
    got = np.array([float(line.split(",")[1]) for line in r.stdout.splitlines()[1:]])
    np.testing.assert_array_equal(got, load_model(model_file).predict(read_runs_csv(new_csv)))
    # ... one without them is one line naming the file and the column
    for drop in ("smoother_end_coeff_cov", "drift_smoother_deg_h"):
        path = tmp_path / f"no_{drop}.csv"
        new.replace(extra={k: v for k, v in new.extra.items() if k != drop}).to_csv(path)
        r = CliRunner().invoke(main, ["predict", str(path), "--model", str(model_file)])
        assert r.exit_code == 1 and "Traceback" not in r.output, r.output
        assert (
            f"{path}: column {drop} (needed by the hybrid model's physics base {FLEET_PHYSICS}) is missing" in r.output
        )
        assert len(r.output.strip().splitlines()) == 1


def test_a_run_without_the_smoother_drift_is_named(fleet):
    train, _ = fleet
    model = fit_drift_model(train, encoding="physics", target="residual", gamma=20.0, sigma=1.5)
    gap = train.replace(
        extra={
            **train.extra,
            "drift_smoother_deg_h": np.where(np.arange(14) == 4, np.nan, train.column("drift_smoother_deg_h")),
        }
    )
    message = (
        f"fleet.csv: column drift_smoother_deg_h .needed by the hybrid model's physics base {FLEET_PHYSICS}. is "
        "missing for run.s. r4$"
    )
    with pytest.raises(InputError, match=message):
        model.predict(gap)
    with pytest.raises(InputError, match=message):  # the same when fitting on the fleet base explicitly
        fit_drift_model(gap, target="residual", physics_column=FLEET_PHYSICS, gamma=20.0, sigma=1.5)
    # the base itself needs no 1-sigma (as the exported code); the interval does
    no_std = train.replace(extra={k: v for k, v in train.extra.items() if k != "drift_smoother_std_deg_h"})
    np.testing.assert_array_equal(model.predict(no_std), model.predict(train))
    with pytest.raises(InputError, match="column drift_smoother_std_deg_h .the 1-sigma of the hybrid model's physics"):
        model.predict_interval(no_std)


def test_model_files_keep_the_resolved_base_and_the_prior_to_the_bit(fleet, tmp_path):
    train, _ = fleet
    model = fit_drift_model(train, encoding="physics", target="residual", gamma=20.0, sigma=1.5)
    path = tmp_path / "m.json"
    save_model(model, path)
    doc = json.loads(path.read_text())
    assert doc["physics_column"] == "auto" and doc["base_uncertainty"] == "auto"
    assert doc["fitted"]["physics_column"] == FLEET_PHYSICS
    assert doc["fitted"]["coefficient_prior"] == list(model.coefficient_prior_)
    again = load_model(path)
    assert again.coefficient_prior_ == model.coefficient_prior_ and again.physics_column_ == FLEET_PHYSICS
    new, _ = synthetic_fleet(20, np.random.default_rng(9), constant=(3,))
    for a, b in zip(again.predict_interval(new), model.predict_interval(new), strict=True):
        np.testing.assert_array_equal(a, b)
    edited = json.loads(path.read_text())
    edited["fitted"]["coefficient_prior"][0] *= 1.0 + 1e-12
    with pytest.raises(ModelFileError, match="coefficient_prior.*differs from the fleet k_z prior pooled"):
        model_from_dict(edited, "m.json")
    edited = json.loads(path.read_text())
    edited["fitted"]["physics_column"] = "drift_smoother_deg_h"
    with pytest.raises(ModelFileError, match="physics_column.*differs from the base the model resolves"):
        model_from_dict(edited, "m.json")
    # schema 3 (before "auto" and the base's 1-sigma in the noise): a concrete column, loaded as it was fitted
    old = fit_drift_model(
        train, target="residual", physics_column="drift_smoother_deg_h", base_uncertainty="none", gamma=20.0, sigma=1.5
    )
    doc3 = model_to_dict(old)
    doc3["schema_version"] = 3
    for key in ("base_uncertainty",):
        del doc3[key]
    for key in ("physics_column", "coefficient_prior"):
        del doc3["fitted"][key]
    loaded = model_from_dict(doc3, "old.json")
    assert loaded.base_uncertainty == "none" and not loaded.base_.std_used_
    for a, b in zip(loaded.predict_interval(new), old.predict_interval(new), strict=True):
        np.testing.assert_array_equal(a, b)
    doc3["physics_column"] = "auto"
    with pytest.raises(ModelFileError, match="unknown physics_column 'auto'"):
        model_from_dict(doc3, "old.json")


def test_clone_cross_validation_and_grid_search_work_with_auto():
    runs, _ = synthetic_fleet(30, np.random.default_rng(12))
    model = make_drift_model(encoding="physics", target="residual", gamma=20.0, sigma=1.5, calibration_folds=0)
    assert clone(model).get_params()["physics_column"] == "auto"
    scores = cross_val_score(model, runs, runs.drift_deg_h, cv=KFold(3))
    assert scores.shape == (3,) and np.all(np.isfinite(scores))
    search = GridSearchCV(model, {"physics_column": ["auto", "drift_inversion_deg_h"]}, cv=KFold(3)).fit(runs)
    assert search.best_estimator_.physics_column_ in (FLEET_PHYSICS, "drift_inversion_deg_h")


def _coverage(base_uncertainty: str, draws: int = 6):
    """Per draw: coverage of the new runs' labels by the 90 % interval, and the median half-width of the runs above
    45 deg (noisier base) over that of the runs below."""
    cover, ratio, lo_hi = [], [], []
    for d in range(draws):
        rng = np.random.default_rng(100 + d)
        train, _ = synthetic_fleet(40, rng)
        test, _ = synthetic_fleet(300, rng)
        model = fit_drift_model(
            train, encoding="physics", target="residual", gamma=20.0, sigma=1.5, base_uncertainty=base_uncertainty
        )
        _, lo, hi = model.predict_interval(test, 0.9)
        inside = (lo <= test.drift_deg_h) & (test.drift_deg_h <= hi)
        north = test.lat0_deg > 45.0
        cover.append(inside.mean())
        lo_hi.append((inside[~north].mean(), inside[north].mean()))
        ratio.append(np.median((hi - lo)[north]) / np.median((hi - lo)[~north]))
    return np.array(cover), np.array(ratio), np.array(lo_hi)


def test_intervals_carry_the_bases_own_uncertainty():
    """The base's 1-sigma grows with latitude (1/cos L): with it in the noise the 90 % interval covers the new runs'
    labels at about 90 % on average, wider above 45 deg than below; without it (``base_uncertainty="none"``) the
    width does not follow the base (ratio about 1) and the noisier runs are covered less than the others."""
    cover, ratio, lo_hi = _coverage("auto")
    assert 0.85 <= cover.mean() <= 0.95, cover
    assert np.all(ratio > 1.15), ratio
    assert abs(lo_hi[:, 0].mean() - lo_hi[:, 1].mean()) < 0.04, lo_hi
    _, ratio_none, lo_hi_none = _coverage("none")
    assert np.all(ratio_none < 1.05), ratio_none
    assert lo_hi_none[:, 0].mean() - lo_hi_none[:, 1].mean() > 0.04, lo_hi_none
