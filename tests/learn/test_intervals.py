"""Intervals of the drift model: the order statistic, its coverage, its widening, and its journey through files."""

import json
import math
import warnings

import numpy as np
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.learn.drift_model import fit_drift_model, make_drift_model
from gyrodrift.learn.interval import jackknife_half_width
from gyrodrift.learn.model_io import load_model, save_model
from gyrodrift.runs.datasets import load_paper, paper_csv_path
from gyrodrift.runs.table import RunTable


def test_half_width_is_the_jackknife_order_statistic():
    r = np.array([0.5, -0.1, 0.3, -0.9, 0.2, 0.05, -0.4, 0.7, 0.6])  # n = 9
    # ceil(10 * 0.8) = 8th smallest |r| = 0.7; ceil(10 * 0.5) = 5th = 0.4.
    assert jackknife_half_width(r, 0.8) == 0.7
    assert jackknife_half_width(r, 0.5) == 0.4
    assert jackknife_half_width(r, 0.95) == math.inf  # 9 runs cannot support 95 %
    for bad in (0.0, 1.0, -0.2):
        with pytest.raises(ValueError, match="coverage must be within"):
            jackknife_half_width(r, bad)
    with pytest.raises(ValueError, match="finite leave-one-out residuals"):
        jackknife_half_width([np.nan, 1.0], 0.5)


def _synthetic(rng, n, noise):
    lat = rng.uniform(28.20, 28.25, n)
    tmin = rng.uniform(10, 55, n)
    tmax = tmin + rng.uniform(0.1, 8, n)
    drift = 0.13 * (lat - 28.222) + 2e-5 * (tmax - 40) + rng.normal(0, noise, n)
    return RunTable(
        run=np.array([str(i) for i in range(n)], dtype=object),
        lat_deg=lat,
        lat0_deg=np.full(n, 28.222),
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=drift,
    )


def test_interval_covers_new_runs_at_about_its_coverage():
    rng = np.random.default_rng(11)
    covered = []
    for _ in range(12):
        # a 15 x 15 grid: the fit tunes 11 times (the model, then its 10 calibration folds)
        model = make_drift_model(method="grid", grid_size=15).fit(_synthetic(rng, 40, 2e-4))
        test = _synthetic(rng, 500, 2e-4)
        _, lo, hi = model.predict_interval(test, 0.9)
        covered.append(np.mean((lo <= test.drift_deg_h) & (test.drift_deg_h <= hi)))
    # Nominal 90 %: averaged over 12 training sets the empirical coverage must be close to it.
    assert 0.85 <= np.mean(covered) <= 0.95, covered


def test_residuals_survive_the_model_file(tmp_path):
    paper = load_paper()
    model = fit_drift_model(paper.train, gamma=30.0, sigma=1.5)
    np.testing.assert_array_equal(model.loo_residuals(), model.lssvr.loo_residuals())
    save_model(model, tmp_path / "m.json")
    again = load_model(tmp_path / "m.json")
    np.testing.assert_array_equal(again.loo_residuals(), model.loo_residuals())
    for a, b in zip(again.predict_interval(paper.test), model.predict_interval(paper.test), strict=False):
        np.testing.assert_array_equal(a, b)
    doc = json.loads((tmp_path / "m.json").read_text())
    doc["fitted"]["loo_residuals_deg_h"] = doc["fitted"]["loo_residuals_deg_h"][:-1]
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    from gyrodrift.learn.model_io import ModelFileError

    with pytest.raises(ModelFileError, match="loo_residuals_deg_h"):
        load_model(tmp_path / "bad.json")


def test_predict_command_prints_the_interval(tmp_path):
    paper = load_paper()
    save_model(fit_drift_model(paper.train, gamma=30.0, sigma=1.5), tmp_path / "m.json")
    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    r = CliRunner().invoke(
        main,
        [
            "predict",
            str(csv_path),
            "--model",
            str(tmp_path / "m.json"),
            "--lat0-deg",
            "28.222",
            "--split",
            "test",
            "--coverage",
            "0.8",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    rows = [json.loads(line) for line in r.stdout.splitlines()]
    for row in rows:
        assert row["drift_lo_deg_h"] < row["drift_identified_deg_h"] < row["drift_hi_deg_h"]
    r = CliRunner().invoke(
        main,
        ["predict", str(csv_path), "--model", str(tmp_path / "m.json"), "--lat0-deg", "28.222", "--coverage", "1.5"],
    )
    assert r.exit_code == 2 and "--coverage" in r.output


def test_a_small_fleet_gets_a_finite_wider_interval_and_the_fit_says_on_what_it_rests(tmp_path):
    """The Student-t calibration needs no minimum fleet for the coverage (the jackknife's order statistic needed
    9 runs for 90 %): 5 runs give a finite interval, wider than 22 runs' by the t quantile with 4 degrees of
    freedom; ``fit`` says how many runs it rests on and how it compares with the physics alone."""
    from gyrodrift.learn.interval import min_runs_for_coverage

    assert [min_runs_for_coverage(c) for c in (0.5, 0.8, 0.9, 0.95)] == [1, 4, 9, 19]  # the jackknife's, kept
    paper = load_paper()
    small = fit_drift_model(paper.train.select(np.arange(5)), gamma=30.0, sigma=1.5)
    assert small.interval_.scale_.multiplier(0.9) == pytest.approx(2.132 * small.interval_.scale_.scale, rel=1e-3)
    save_model(small, tmp_path / "small.json")
    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    args = ["predict", str(csv_path), "--model", str(tmp_path / "small.json"), "--lat0-deg", "28.222", "--json"]
    r = CliRunner().invoke(main, args + ["--coverage", "0.9"])
    assert r.exit_code == 0 and "Infinity" not in r.output, r.output
    rows = [json.loads(line) for line in r.stdout.splitlines()]
    assert all(row["drift_lo_deg_h"] < row["drift_identified_deg_h"] < row["drift_hi_deg_h"] for row in rows)
    r = CliRunner().invoke(
        main,
        [
            "fit",
            str(csv_path),
            "--out",
            str(tmp_path / "m.json"),
            "--lat0-deg",
            "28.222",
            "--gamma",
            "30",
            "--sigma",
            "1.5",
            "--split",
            "train",
            "--quiet",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    note = next(line for line in r.stderr.splitlines() if line.startswith("note: 90 % interval rests on"))
    summary = json.loads(r.stdout)["interval"]
    assert summary["n_runs"] == 22 and summary["n_used"] + len(summary["wild_runs"]) == 22
    assert f"rests on {summary['n_used']}" in note
    # the paper's table has no label 1-sigma (and the inversion base none): nothing physical to compare with
    assert summary["physics_ratio"] is None and note.endswith("no physics 1-sigma to compare with")


@pytest.mark.parametrize("bad", ["nan", "inf", "0", "1"])
def test_predict_refuses_a_coverage_that_is_not_a_probability(tmp_path, bad):
    paper = load_paper()
    save_model(fit_drift_model(paper.train, gamma=30.0, sigma=1.5), tmp_path / "m.json")
    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    r = CliRunner().invoke(
        main, ["predict", str(csv_path), "--model", str(tmp_path / "m.json"), "--lat0-deg", "28.222", "--coverage", bad]
    )
    assert r.exit_code == 2 and "Invalid value for '--coverage'" in r.output and "NaN" not in r.output
    from gyrodrift.errors import OptionError

    with pytest.raises(OptionError, match="coverage must be within"):
        jackknife_half_width([1.0, 2.0], float(bad))


def _heteroscedastic_runs(rng, n):
    """Runs whose drift is a known function of the temperature plus a run-to-run scatter (the "effective" drift
    a perfect method could know), labelled with noise of a known, run-dependent 1-sigma (drift_std_deg_h, as
    truth's covariance analysis gives it; 5e-5 to 3e-4 deg/h, around the 1.5e-4 of RLG-grade labels at mid
    latitudes). Returns (table of labels, effective drifts)."""
    from gyrodrift.learn.baselines import latitude_error_at
    from gyrodrift.units import HOUR

    lat0 = rng.uniform(20.0, 60.0, n)
    tmin = rng.uniform(15.0, 25.0, n)
    tmax = tmin + rng.uniform(8.0, 15.0, n)
    effective = 0.002 + 0.0002 * (tmax - 30.0) + rng.normal(0.0, 1e-4, n)
    seen = effective - 0.0001 * (tmax - tmin) + rng.normal(0.0, 1.5e-4, n)  # what the 12 h navigation saw
    sigma = rng.uniform(5e-5, 3e-4, n)
    table = RunTable(
        run=np.array([f"r{i}" for i in range(n)], dtype=object),
        lat_deg=lat0 + latitude_error_at(12 * HOUR, seen, lat0) / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=effective + rng.normal(0.0, sigma),
        extra={"drift_std_deg_h": sigma},
    )
    return table, effective


def test_weighted_interval_is_calibrated_over_many_draws():
    """Weighted hybrid models on 30 runs with heteroscedastic label noise, 8 draws of 300 new runs: the 90 %
    interval covers the new runs' labels 0.83-0.96 of the time on average, and their effective drifts at least
    as often, while the same intervals at 0.6 or 1.6 times their width fall outside that band (the band tells a
    calibrated interval from others)."""
    rng = np.random.default_rng(2024)
    covered: dict = {0.6: [], 1.0: [], 1.6: [], "effective": []}
    for _ in range(8):
        train, _ = _heteroscedastic_runs(rng, 30)
        test, effective = _heteroscedastic_runs(rng, 300)
        model = make_drift_model(encoding="physics", target="residual", method="grid", grid_size=15).fit(train)
        assert model.training["weighted"]
        pred, lo, hi = model.predict_interval(test, 0.9)
        for factor in (0.6, 1.0, 1.6):
            covered[factor].append(np.mean(np.abs(test.drift_deg_h - pred) <= factor * (hi - lo) / 2))
        covered["effective"].append(np.mean((lo <= effective) & (effective <= hi)))
    mean = {k: float(np.mean(v)) for k, v in covered.items()}
    assert 0.83 <= mean[1.0] <= 0.96, mean
    assert mean[0.6] < 0.83 and mean[1.6] > 0.96, mean
    assert mean["effective"] >= mean[1.0] - 0.01, mean


def test_far_outside_the_training_range_the_interval_widens_markedly_and_is_flagged():
    rng = np.random.default_rng(5)
    train, _ = _heteroscedastic_runs(rng, 40)
    inside, _ = _heteroscedastic_runs(rng, 100)
    far = inside.replace(temp_min_c=inside.temp_min_c + 30.0, temp_max_c=inside.temp_max_c + 30.0)
    model = fit_drift_model(train, encoding="physics", target="residual", method="grid", rng=0)
    _, lo_in, hi_in = model.predict_interval(inside, 0.9)
    _, lo_far, hi_far = model.predict_interval(far, 0.9)
    # the spread model's length scales are fitted (not a kernel width at its search-box edge): 30 degC beyond
    # the training runs, about 3 of their temperature standard deviations, is far on that scale
    assert np.min(hi_far - lo_far) > 3.0 * np.median(hi_in - lo_in)
    assert model.check_inputs(far).outside.all()
    assert np.all(model.interval_.spread_.length_scales() < 1e3)


# --------------------------------------------------------------------------------------------------
# The calibration scale (gyrodrift.learn.spread.calibration_scale)
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [8, 16, 48])
def test_the_scale_gives_its_coverage_on_well_specified_scores(n):
    """Scores drawn from N(0, 2.5^2) (a well-specified model whose 1-sigmas are 2.5 times too small): over 4000
    seeded fleets the interval t c covers one more score 0.90 of the time within 4 binomial standard deviations
    (0.019), and the scale is consistent (its mean within 4 % of 2.5)."""
    from gyrodrift.learn.spread import calibration_scale

    rng = np.random.default_rng(n)
    trials = 4000
    covered, scales = 0, []
    for _ in range(trials):
        cal = calibration_scale(rng.normal(0.0, 2.5, n))
        covered += abs(rng.normal(0.0, 2.5)) <= cal.multiplier(0.9)
        scales.append(cal.scale)
    tolerance = 4 * math.sqrt(0.9 * 0.1 / trials)
    assert abs(covered / trials - 0.9) <= tolerance, covered / trials
    assert np.mean(scales) == pytest.approx(2.5, rel=0.04)


def test_one_wild_score_is_named_and_barely_moves_the_scale():
    from gyrodrift.learn.spread import calibration_scale

    rng = np.random.default_rng(7)
    z = rng.normal(size=16)
    clean = calibration_scale(z)
    assert clean.n_used == 16 and clean.inflation == 1.0
    wild = z.copy()
    wild[5] = 6.24 * np.sqrt(np.mean(z**2)) * 3  # one fold's re-tuned model that fitted wildly
    cal = calibration_scale(wild)
    assert list(cal.wild) == [5] and cal.n_used == 15
    assert cal.multiplier(0.9) == pytest.approx(clean.multiplier(0.9), rel=0.15)
    assert cal.raw_rms > 3 * clean.raw_rms  # what the plain rms would have made of it
    # an order statistic at n = 16 would be the wild score itself
    assert jackknife_half_width(wild, 0.9) == abs(wild[5])


def test_a_wild_training_run_is_named_in_a_warning_and_does_not_set_the_width():
    from gyrodrift.learn.interval import IntervalOutlierWarning

    rng = np.random.default_rng(31)
    train, _ = _heteroscedastic_runs(rng, 40)
    test, _ = _heteroscedastic_runs(rng, 200)
    fixed = {"encoding": "physics", "target": "residual", "gamma": 20.0, "sigma": 1.5}
    clean = fit_drift_model(train, **fixed)
    assert clean.interval_warnings() == []
    summary = clean.interval_summary(0.9)
    assert summary["physics_ratio"] > 1.0 and summary["n_used"] == 40  # the learner adds to the label noise
    assert "times the physics alone (label and base 1-sigma)" in clean.interval_note(0.9)
    labels = train.drift_deg_h.copy()
    labels[7] += 8 * train.column("drift_std_deg_h")[7]  # a mislabelled run: 8 sigma off
    with pytest.warns(IntervalOutlierWarning, match=r"run\(s\) r7 \(\+"):
        bad = fit_drift_model(train.replace(drift_deg_h=labels), **fixed)
    assert "r7" in " ".join(bad.fit_warnings())
    assert bad.interval_summary()["wild_runs"] == ["r7"]
    width = [np.median(np.diff(m.predict_interval(test, 0.9)[1:], axis=0)) for m in (clean, bad)]
    assert width[1] / width[0] < 1.25, width


def test_the_interval_is_capped_far_outside_the_training_range():
    """Far outside the training runs the learner's share of the width stops at its own uncertainty (the spread
    model's prior 1-sigma over the training range): the half-width never exceeds the physics alone's plus that, at
    the same calibration, however far the run."""
    rng = np.random.default_rng(5)
    train, _ = _heteroscedastic_runs(rng, 40)
    inside, _ = _heteroscedastic_runs(rng, 50)
    model = fit_drift_model(train, encoding="physics", target="residual", gamma=20.0, sigma=1.5)
    mult, cap = model.interval_.scale_.multiplier(0.9), model.interval_.learned_cap_deg_h_
    physics = model.interval_.label_std_rms_  # the inversion base has no 1-sigma
    widths = []
    for shift in (0.0, 30.0, 300.0, 3000.0):
        far = inside.replace(temp_min_c=inside.temp_min_c + shift, temp_max_c=inside.temp_max_c + shift)
        pred, lo, hi = model.predict_interval(far, 0.9)
        half = (hi - lo) / 2
        assert np.all(half <= mult * (physics + cap) * (1 + 1e-12)), shift
        assert np.all(np.isfinite(pred)) and np.all(lo < pred) and np.all(pred < hi)
        widths.append(np.median(half))
    assert widths[1] > 1.5 * widths[0]  # it does widen away from the runs ...
    # ... up to the cap, reached far out: sqrt(cap^2 + physics^2) in units of the calibration
    assert widths[3] == pytest.approx(mult * math.hypot(cap, physics), rel=1e-9)


@pytest.mark.parametrize("n_inputs", [1, 3])
def test_the_spread_likelihood_search_is_scikit_learns(n_inputs):
    """SpreadGP's own likelihood and L-BFGS-B search (issue 20: 20-30x faster) give scikit-learn's values, gradient
    and optimum (its GaussianProcessRegressor with fmin_l_bfgs_b, restarts included)."""
    from sklearn.gaussian_process import GaussianProcessRegressor

    from gyrodrift.learn.spread import _kernel, _maximise_likelihood, _neg_log_likelihood, _start_and_bounds

    rng = np.random.default_rng(n_inputs)
    Z = rng.normal(size=(22, n_inputs))
    y = np.sin(Z[:, 0]) + 0.1 * rng.normal(size=22)
    noise = rng.uniform(0.0, 0.01, 22) + 1e-10
    kernel = _kernel(n_inputs)
    ref = GaussianProcessRegressor(kernel, alpha=noise, optimizer=None).fit(Z, y)
    sqd = (Z.T[:, :, None] - Z.T[:, None, :]) ** 2
    for _ in range(3):
        theta = 0.3 * rng.uniform(kernel.bounds[:, 0], kernel.bounds[:, 1])
        lml, grad = ref.log_marginal_likelihood(theta, eval_gradient=True)
        mine, mine_grad = _neg_log_likelihood(theta, Z, sqd, y, noise)
        assert mine == pytest.approx(-lml, rel=1e-10)
        np.testing.assert_allclose(mine_grad, -grad, rtol=1e-8, atol=1e-10 * np.max(np.abs(grad)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scikit-learn's ConvergenceWarning at a bound
        fitted = GaussianProcessRegressor(kernel, alpha=noise, n_restarts_optimizer=2, random_state=0).fit(Z, y)
    start, bounds = _start_and_bounds(n_inputs)
    np.testing.assert_array_equal(start, kernel.theta)
    np.testing.assert_array_equal(bounds, kernel.bounds)
    ours = _maximise_likelihood(Z, y, noise, 2, 0)
    np.testing.assert_allclose(ours, fitted.kernel_.theta, atol=1e-4)


def test_the_spread_prediction_is_scikit_learns_at_the_same_hyperparameters():
    """SpreadGP's own predictive mean, 1-sigma and LOO 1-sigma (issue 20: no GaussianProcessRegressor, whose fit
    factorises twice) equal scikit-learn's GP at the fitted hyperparameters, near and far from the runs."""
    from sklearn.gaussian_process import GaussianProcessRegressor

    from gyrodrift.learn.spread import SpreadGP, _kernel

    rng = np.random.default_rng(7)
    Z = rng.normal(size=(40, 2))
    y = np.sin(Z[:, 0]) + 0.1 * rng.normal(size=40)
    s = rng.uniform(0.0, 0.05, 40)
    gp = SpreadGP().fit(Z, y, s)
    ref = GaussianProcessRegressor(
        _kernel(2).clone_with_theta(gp.theta_), alpha=(s / gp.y_scale_) ** 2 + 1e-10, optimizer=None
    ).fit(gp._z(Z), (y - gp.y_mean_) / gp.y_scale_)
    new = np.vstack([3.0 * rng.normal(size=(30, 2)), Z[:5]])
    mean, std = ref.predict(gp._z(new), return_std=True)
    np.testing.assert_allclose(gp.predict_std(new), gp.y_scale_ * std, rtol=1e-9)
    np.testing.assert_allclose(gp.predict_mean(new), gp.y_mean_ + gp.y_scale_ * mean, rtol=0, atol=1e-9 * gp.y_scale_)
    loo = gp.y_scale_ / np.sqrt(np.diag(np.linalg.inv(ref.L_ @ ref.L_.T)))
    np.testing.assert_allclose(gp.loo_std_, loo, rtol=1e-8)
