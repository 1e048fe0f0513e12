"""Jackknife intervals of the drift model: the order statistic, its coverage, and its journey through files."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.datasets import load_paper, paper_csv_path
from gyrodrift.model import fit_drift_model, jackknife_half_width
from gyrodrift.model_io import load_model, save_model
from gyrodrift.runs import RunTable


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
        model = fit_drift_model(_synthetic(rng, 40, 2e-4), method="grid", rng=0)
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
    from gyrodrift.model_io import ModelFileError

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


def test_too_few_runs_for_the_coverage_is_said_not_printed_as_infinity(tmp_path):
    from gyrodrift.model import min_runs_for_coverage

    assert [min_runs_for_coverage(c) for c in (0.5, 0.8, 0.9, 0.95)] == [1, 4, 9, 19]
    paper = load_paper()
    small = paper.train.select(np.arange(5))
    save_model(fit_drift_model(small, gamma=30.0, sigma=1.5), tmp_path / "small.json")
    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    args = ["predict", str(csv_path), "--model", str(tmp_path / "small.json"), "--lat0-deg", "28.222", "--json"]
    r = CliRunner().invoke(main, args + ["--coverage", "0.9"])
    assert (
        r.exit_code == 1 and "5 training runs are too few for a 90 % jackknife interval (needs at least 9)" in r.output
    )
    r = CliRunner().invoke(main, args + ["--coverage", "0.8"])
    assert r.exit_code == 0 and "Infinity" not in r.output


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
