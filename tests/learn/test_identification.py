"""Issue 10, learning side: physics encodings, hybrid target, weighted LS-SVM labels, input-dependent intervals
and out-of-range flags, model files schema 3 (schema 2 still read)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.learn.baselines import latitude_error_at, physics_inversion
from gyrodrift.learn.drift_model import fit_drift_model, select_labelled_runs
from gyrodrift.learn.kernels import squared_distances
from gyrodrift.learn.lssvm_batch import rbf_batch_errors
from gyrodrift.learn.lssvr import LSSVR
from gyrodrift.learn.model_io import load_model, model_from_dict, model_to_dict, save_model
from gyrodrift.learn.physics_base import label_weights
from gyrodrift.runs.table import RunTable, read_runs_csv
from gyrodrift.units import HOUR

# ------------------------------------------------------------------ weighted LS-SVM


def _bordered_solve(K, y, gamma, w):
    n = len(y)
    M = np.zeros((n + 1, n + 1))
    M[0, 1:] = M[1:, 0] = 1.0
    M[1:, 1:] = K + np.diag(1.0 / (gamma * w))
    sol = np.linalg.solve(M, np.concatenate([[0.0], y]))
    return sol[1:], sol[0]


def _rbf(X, Z, sigma):
    d = ((X[:, None, :] - Z[None, :, :]) ** 2).sum(-1)
    return np.exp(-d / sigma**2)


@pytest.fixture()
def weighted_problem():
    rng = np.random.default_rng(4)
    X = rng.normal(size=(25, 2))
    y = np.sin(X[:, 0]) + 0.3 * X[:, 1] + rng.normal(0, 0.05, 25)
    w = rng.uniform(0.2, 3.0, 25)
    return X, y, w


def test_weighted_lssvr_matches_a_brute_force_weighted_solve_and_refits(weighted_problem):
    X, y, w = weighted_problem
    gamma, sigma = 30.0, 1.4
    m = LSSVR(gamma=gamma, sigma=sigma).fit(X, y, sample_weight=w)
    alpha, b = _bordered_solve(_rbf(X, X, sigma), y, gamma, w)
    np.testing.assert_allclose(m.alpha_, alpha, rtol=1e-9, atol=1e-12)
    assert m.intercept_ == pytest.approx(b, rel=1e-10)
    # training residuals are e_i = alpha_i / (gamma w_i)
    np.testing.assert_allclose(y - m.predict(X), alpha / (gamma * w), rtol=1e-8, atol=1e-12)
    # closed-form weighted LOO against n weighted refits
    brute = []
    for i in range(len(y)):
        keep = np.arange(len(y)) != i
        a_i, b_i = _bordered_solve(_rbf(X[keep], X[keep], sigma), y[keep], gamma, w[keep])
        brute.append(y[i] - (_rbf(X[i : i + 1], X[keep], sigma) @ a_i + b_i)[0])
    np.testing.assert_allclose(m.loo_residuals_, brute, rtol=1e-8, atol=1e-12)
    # the tuner's batch path gives the same, stacked (n <= 32) and looped
    D = squared_distances(X)
    for kind, expected in (("train", alpha / (gamma * w)), ("loo", np.array(brute))):
        got = rbf_batch_errors(D, y, [gamma, gamma], [sigma, sigma], kind, weights=w)
        np.testing.assert_allclose(got[0], expected, rtol=1e-8, atol=1e-12)
    # equal weights are the unweighted model
    same = LSSVR(gamma=gamma, sigma=sigma).fit(X, y, sample_weight=np.full(25, 1.0))
    np.testing.assert_allclose(same.alpha_, LSSVR(gamma=gamma, sigma=sigma).fit(X, y).alpha_, rtol=1e-12)


def test_loo_scale_is_the_predictive_scale_of_the_refit_without_the_run(weighted_problem):
    X, y, _ = weighted_problem
    m = LSSVR(gamma=30.0, sigma=1.4).fit(X, y)
    for i in (0, 7, 24):
        keep = np.arange(len(y)) != i
        refit = LSSVR(gamma=30.0, sigma=1.4).fit(X[keep], y[keep])
        assert refit.predictive_scale(X[i : i + 1])[0] == pytest.approx(m.loo_scale_[i], rel=1e-8)
    # far from the data the scale grows to its prior value; near it, it is small
    far = m.predictive_scale(np.array([[40.0, -40.0]]))[0]
    near = m.predictive_scale(X[:1])[0]
    assert far > 3 * near and far > 1.0


def test_label_weights_and_left_out_runs():
    np.testing.assert_allclose(label_weights([1.0, 2.0]), [2.5, 0.625])
    runs = _synthetic_runs(12, seed=2)
    std = np.full(12, 2e-4)
    std[3] = 5e-3
    std[7] = np.inf
    with_std = runs.replace(extra={"drift_std_deg_h": std})
    kept, left = select_labelled_runs(with_std, 1e-3)
    assert left == [str(runs.run[3]), str(runs.run[7])] and len(kept) == 10
    model = fit_drift_model(with_std, encoding="physics", max_label_std_deg_h=1e-3, gamma=10.0, sigma=1.0)
    assert model.training["left_out"] == left and model.training["weighted"] and model.training["n_runs"] == 10
    # equal label sigmas: the weighted fit is the unweighted one
    eq = runs.replace(extra={"drift_std_deg_h": np.full(12, 3e-4)})
    a = fit_drift_model(eq, encoding="physics", gamma=10.0, sigma=1.0)
    b = fit_drift_model(runs, encoding="physics", gamma=10.0, sigma=1.0)
    np.testing.assert_allclose(a.predict(runs), b.predict(runs), rtol=1e-12)
    assert a.training["weighted"] and not b.training["weighted"]


# ------------------------------------------------------------------ physics encodings and the hybrid


def _synthetic_runs(n, seed=0, lat_range=(20.0, 60.0), temp_shift=0.0):
    """Runs whose drift is 0.002 + 0.0002 (tmax - 30) and whose 12 h latitude error is the closed form of a
    drift that differs from it by a temperature term (what the hybrid has to learn) plus noise."""
    rng = np.random.default_rng(seed)
    lat0 = rng.uniform(*lat_range, n)
    tmin = rng.uniform(15, 25, n) + temp_shift
    tmax = tmin + rng.uniform(8, 15, n)
    drift = 0.002 + 0.0002 * (tmax - 30.0) + rng.normal(0, 5e-4, n)
    seen = drift - 0.0001 * (tmax - tmin) + rng.normal(0, 1e-5, n)
    lat_err = latitude_error_at(12 * HOUR, seen, lat0)
    return RunTable(
        run=np.array([f"r{i}" for i in range(n)], dtype=object),
        lat_deg=lat0 + lat_err / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=drift,
    )


def test_hybrid_learns_only_the_correction_and_round_trips(tmp_path):
    train, test = _synthetic_runs(40, seed=1), _synthetic_runs(15, seed=2)
    hybrid = fit_drift_model(train, encoding="physics", target="residual", method="grid", rng=0)
    lssvr_part = hybrid.learner_[:-1].transform(test)
    np.testing.assert_allclose(
        hybrid.predict(test),
        physics_inversion(test) + hybrid.learner_.named_steps["lssvr"].predict(lssvr_part),
        rtol=1e-12,
    )
    err_h = test.drift_deg_h - hybrid.predict(test)
    err_p = test.drift_deg_h - physics_inversion(test)
    assert np.sqrt(np.mean(err_h**2)) < 0.5 * np.sqrt(np.mean(err_p**2))
    path = tmp_path / "hybrid.json"
    save_model(hybrid, path)
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 4 and doc["target"] == "residual"
    # "auto" on a table without smoother columns: the 12 h inversion
    assert doc["physics_column"] == "auto" and doc["fitted"]["physics_column"] == "drift_inversion_deg_h"
    assert doc["fitted"]["coefficient_prior"] is None
    again = load_model(path)
    np.testing.assert_array_equal(again.predict(test), hybrid.predict(test))


def test_schema_2_files_still_load_as_drift_models():
    runs = _synthetic_runs(12, seed=5)
    model = fit_drift_model(runs, encoding="temp_range", gamma=10.0, sigma=1.0)
    doc = model_to_dict(model)
    doc["schema_version"] = 2
    for key in ("target", "physics_column", "label_weighting"):
        del doc[key]
    for key in ("weighted", "left_out"):
        del doc["training"][key]
    again = model_from_dict(doc, "old.json")
    assert again.target == "drift"
    np.testing.assert_array_equal(again.predict(runs), model.predict(runs))


def test_hybrid_on_a_column_needs_it_for_every_run():
    runs = _synthetic_runs(12, seed=6)
    with_cf = runs.replace(extra={"drift_curvefit_deg_h": physics_inversion(runs)})
    m = fit_drift_model(
        with_cf, encoding="physics", target="residual", physics_column="drift_curvefit_deg_h", gamma=5.0, sigma=1.0
    )
    with pytest.raises(ValueError, match="drift_curvefit_deg_h .* missing: the table has no such column"):
        m.predict(runs)
    gap = with_cf.replace(extra={"drift_curvefit_deg_h": np.where(np.arange(12) == 3, np.nan, physics_inversion(runs))})
    with pytest.raises(ValueError, match="drift_curvefit_deg_h .* missing for run.s. r3$"):
        m.predict(gap)


def test_physics_encoding_is_latitude_free_and_the_paper_one_is_not():
    """The same drift and temperatures at 20/36/48/57 deg (closed-form latitude errors), models fitted on a
    multi-latitude fleet: the physics encoding identifies one drift, the paper's arcsec input four."""
    fleet = _synthetic_runs(40, seed=7)
    lat0 = np.array([20.0, 36.0, 48.0, 57.0])
    same = RunTable(
        run=np.array(["a", "b", "c", "d"], dtype=object),
        lat_deg=lat0 + latitude_error_at(12 * HOUR, 0.00368, lat0) / 3600.0,
        lat0_deg=lat0,
        temp_min_c=np.full(4, 20.0),
        temp_max_c=np.full(4, 31.0),
        drift_deg_h=np.full(4, np.nan),
    )
    phys = fit_drift_model(fleet, encoding="physics", method="grid", rng=0).predict(same)
    paper = fit_drift_model(fleet, encoding="temp_range", method="grid", rng=0).predict(same)
    assert np.ptp(phys) < 5e-5 * 0.01  # closed-form inputs: identical drift equivalents
    assert np.ptp(paper) > 5e-5


# ------------------------------------------------------------------ intervals and out-of-range flags


def test_intervals_widen_and_runs_outside_the_training_range_are_flagged():
    train = _synthetic_runs(60, seed=8)
    model = fit_drift_model(train, encoding="physics", target="residual", method="grid", rng=0)
    inside = _synthetic_runs(200, seed=9)
    hot = _synthetic_runs(6, seed=10, temp_shift=25.0)
    check_hot = model.check_inputs(hot)
    assert check_hot.outside.all()
    assert all(any("temp_" in s for s in names) for names in check_hot.outside_inputs)
    assert model.check_inputs(train).outside.sum() == 0
    _, lo_in, hi_in = model.predict_interval(inside, 0.9)
    _, lo_hot, hi_hot = model.predict_interval(hot, 0.9)
    assert np.min(hi_hot - lo_hot) > np.median(hi_in - lo_in)
    covered = (lo_in <= inside.drift_deg_h) & (inside.drift_deg_h <= hi_in)
    assert 0.8 <= covered.mean() <= 0.97
    # jointly outside: each input within its range, the combination not (hot start, cold end)
    joint = train.select([0]).replace(
        temp_min_c=np.array([train.temp_min_c.max() - 0.1]), temp_max_c=np.array([train.temp_max_c.min() + 0.1])
    )
    c = model.check_inputs(joint)
    if not c.outside_inputs[0]:
        assert c.outside[0] and c.mahalanobis[0] > c.mahalanobis_limit
    assert "outside the training runs' range" in c.messages(joint)[0]


# ------------------------------------------------------------------ the command line


def _write_csv(path, runs: RunTable, std=None):
    lines = ["run,lat_deg,lat0_deg,temp_min_c,temp_max_c,drift_deg_h" + (",drift_std_deg_h" if std is not None else "")]
    for i in range(len(runs)):
        cells = [
            str(runs.run[i]),
            repr(float(runs.lat_deg[i])),
            repr(float(runs.lat0_deg[i])),
            repr(float(runs.temp_min_c[i])),
            repr(float(runs.temp_max_c[i])),
            repr(float(runs.drift_deg_h[i])),
        ]
        if std is not None:
            cells.append(repr(float(std[i])))
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def test_fit_says_what_it_weighted_and_left_out_and_predict_flags(tmp_path):
    runs = _synthetic_runs(30, seed=11)
    std = np.full(30, 2e-4)
    std[4] = 0.004
    data = tmp_path / "runs.csv"
    _write_csv(data, runs, std)
    assert read_runs_csv(data).has_column("drift_std_deg_h")
    model = tmp_path / "m.json"
    r = CliRunner().invoke(main, ["fit", str(data), "--out", str(model), "--method", "grid", "--quiet"])
    assert r.exit_code == 0, r.output
    assert "left out 1 run(s)" in r.stderr and "r4" in r.stderr and "weighted" in r.stderr
    doc = json.loads(model.read_text())
    assert doc["training"]["left_out"] == ["r4"] and doc["training"]["weighted"] is True
    assert doc["encoding"] == "temperature" and doc["target"] == "residual"  # the hybrid's default encoding
    hot = tmp_path / "hot.csv"
    _write_csv(hot, _synthetic_runs(3, seed=12, temp_shift=30.0))
    r = CliRunner().invoke(main, ["predict", str(hot), "--model", str(model), "--coverage", "0.9"])
    assert r.exit_code == 0, r.output
    assert r.stderr.count("outside the training runs' range") == 3
    rows = r.stdout.splitlines()
    assert rows[0].split(",")[:5] == [
        "run",
        "drift_identified_deg_h",
        "drift_lo_deg_h",
        "drift_hi_deg_h",
        "outside_training_range",
    ]
    assert all(line.split(",")[4] == "1" for line in rows[1:])


def test_fit_warns_on_the_search_box_edge(tmp_path):
    runs = _synthetic_runs(10, seed=13)
    data = tmp_path / "runs.csv"
    _write_csv(data, runs.replace(drift_deg_h=physics_inversion(runs)))  # a noise-free linear law: gamma at its top
    r = CliRunner().invoke(
        main, ["fit", str(data), "--out", str(tmp_path / "m.json"), "--method", "grid", "--quiet", "--target", "drift"]
    )
    assert r.exit_code == 0, r.output
    assert "warning: tuned value on the edge of its search box" in r.stderr
    assert json.loads((tmp_path / "m.json").read_text())["warnings"]


# ------------------------------------------------------------------ bad input: one line naming where


@pytest.mark.parametrize(
    ("cell", "message"),
    [
        ("-0.0002", "runs.csv, row 3, column drift_std_deg_h: expected a 1-sigma > 0 deg/h"),
        ("abc", "runs.csv, row 3, column drift_std_deg_h: expected a number in deg/h, got 'abc'"),
        ("50", "runs.csv, row 3, column drift_std_deg_h: |50.0| deg/h is not an RLG drift"),
    ],
)
def test_bad_optional_cells_name_file_row_and_column(tmp_path, cell, message):
    runs = _synthetic_runs(4, seed=14)
    data = tmp_path / "runs.csv"
    _write_csv(data, runs, np.full(4, 2e-4))
    lines = data.read_text().splitlines()
    lines[2] = lines[2].rsplit(",", 1)[0] + "," + cell
    data.write_text("\n".join(lines) + "\n")
    r = CliRunner().invoke(main, ["fit", str(data), "--out", str(tmp_path / "m.json"), "--quiet"])
    assert r.exit_code == 1 and message in r.output and "Traceback" not in r.output


def test_hybrid_on_a_missing_column_is_one_line(tmp_path):
    data = tmp_path / "runs.csv"
    _write_csv(data, _synthetic_runs(6, seed=15))
    r = CliRunner().invoke(
        main,
        ["fit", str(data), "--out", str(tmp_path / "m.json"), "--physics-column", "drift_curvefit_deg_h", "--quiet"],
    )
    assert r.exit_code == 1 and "column drift_curvefit_deg_h" in r.output and "no such column" in r.output
    assert len(r.output.strip().splitlines()) == 1 and not (tmp_path / "m.json").exists()


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("target", "bogus", "unknown target 'bogus'"),
        ("physics_column", "drift_deg_h", "unknown physics_column 'drift_deg_h'"),
        ("label_weighting", 3, "key 'label_weighting' has the wrong type"),
    ],
)
def test_edited_model_files_name_the_key(key, value, message):
    model = fit_drift_model(_synthetic_runs(8, seed=16), encoding="physics", gamma=10.0, sigma=1.0)
    doc = model_to_dict(model)
    doc[key] = value
    with pytest.raises(ValueError, match=message):
        model_from_dict(doc, "m.json")
    doc = model_to_dict(model)
    doc["training"]["left_out"] = [1]
    with pytest.raises(ValueError, match="left_out"):
        model_from_dict(doc, "m.json")


def test_fit_default_encoding_follows_the_target(tmp_path):
    """A hybrid's correction sees the temperature only; a model of the drift itself gets the physics inputs."""
    data = tmp_path / "runs.csv"
    _write_csv(data, _synthetic_runs(12, seed=5))
    for target, encoding in (("residual", "temperature"), ("drift", "physics")):
        model = tmp_path / f"{target}.json"
        args = ["fit", str(data), "--out", str(model), "--target", target, "--method", "grid", "--quiet"]
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 0, r.output
        assert json.loads(model.read_text())["encoding"] == encoding
