"""examples/identification_study.py at reduced size (8 training, 4 held-out runs at 2 Hz, short swarms): the
issue-10 claims that hold at any size and rate. The full-size numbers (four fleets at 10 Hz, 8 coverage fleets at
2 Hz) are in docs/studies/2026-11-23-identification-study.md."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from gyrodrift.choices import default_encoding

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "identification_study.py"


def measure_each_run_once(module) -> None:
    """Make the module's `measure_run` measure each run once: it is a function of the run's spec alone (the spec's
    seed draws the noise), so the coverage mode reads the study's runs again instead of simulating them anew."""
    measured: dict[str, dict] = {}
    measure = module.measure_run

    def once(spec: dict, smoother: bool = True) -> dict:
        key = json.dumps([spec, smoother], sort_keys=True)
        if key not in measured:
            measured[key] = measure(spec, smoother)
        return measured[key]

    module.measure_run = once


@pytest.fixture(scope="module")
def study():
    spec = importlib.util.spec_from_file_location("identification_study", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    measure_each_run_once(module)
    return module, module.run_study(8, 4, 2, seed=1, max_iter=20, rate_hz=2.0, quiet=True)


def test_study_runs_and_reports(study, capsys):
    module, r = study
    module.print_report(r)
    out = capsys.readouterr().out
    for row in (
        module.DEFAULT,
        module.OLD_DEFAULT,
        module.PAPER,
        module.FLEET_PHYSICS_ENCODING,
        "16 h Kalman smoother",
        "16 h smoother, fleet k_z prior",
    ):
        assert row in r["methods"] and row in out, row
    assert "default's physics base: drift_smoother_fleet_deg_h" in out
    smoother = r["methods"]["16 h Kalman smoother"]
    assert 0 < r["smoother_sigma_rms"] < smoother["max_eff"] + 1e-3
    # The fleet's k_z as the coefficient's prior narrows the smoother's end-drift 1-sigma.
    assert "fleet k_z prior" in out and 0 < r["fleet_prior"][2] < r["smoother_sigma_rms"]
    assert r["n_train"] == 8 and r["n_test"] == 4 and int(np.sum(r["out_of_range"])) >= 2
    for m in r["methods"].values():
        assert 0 <= m["under_1nmi"] <= 4 and np.all(np.isfinite(m["final_nmi"]))
        assert m["rms_eff"] <= m["max_eff"]


def test_default_is_gyrodrift_fit_on_the_fleet_prior_smoother(study):
    """The run records carry the smoother's k_z columns, so `gyrodrift fit`'s default base is the fleet one, with
    the training runs' pooled k_z (simulated 2e-4 deg/h/degC) as its prior; its predictions are not the old
    default's."""
    _, r = study
    assert r["default_physics_column"] == "drift_smoother_fleet_deg_h"
    assert r["default_encoding"] == default_encoding("residual")
    mean, std = r["default_coefficient_prior"]
    assert 0 < std < 1e-4 and abs(mean - 2e-4) < 4 * std + 5e-5
    default, old = r["methods"]["default (gyrodrift fit)"], r["methods"]["hybrid: inversion + LSSVR"]
    assert np.max(np.abs(default["pred"] - old["pred"])) > 1e-6


def test_default_beats_the_paper_encoding_and_flags_every_run_outside_the_range(study):
    module, r = study
    default = r["methods"][module.DEFAULT]
    paper = r["methods"][module.PAPER]
    assert default["rms_eff"] < paper["rms_eff"]
    assert default["out_of_range_flagged"] == int(np.sum(r["out_of_range"]))
    k = module.key_numbers(r)
    assert k["out_flagged"] == 1.0 and k["vs_paper"] == pytest.approx(default["rms_eff"] / paper["rms_eff"])


def test_same_drift_at_four_latitudes(study):
    """Noise-free logs at 20/36/48/57 deg, one drift: the physics encodings and the default give one drift, the
    paper's not."""
    module, r = study
    four = r["four_latitudes"]
    for name in (module.DEFAULT, module.OLD_DEFAULT, "physics-encoding LSSVM", "12 h physics inversion"):
        assert np.ptp(four[name]) < 5e-5, name
    assert np.ptp(four[module.PAPER]) > 5e-5
    assert abs(four["12 h physics inversion"][0] - 0.00368) < 2e-5
    assert module.key_numbers(r)["four_lat_spread"] == pytest.approx(np.ptp(four[module.DEFAULT]))


def test_seeds_summary_and_seed_option(study, capsys):
    """The --seeds summary over fleets: per seed and mean +- sd (here the one fleet twice: sd 0)."""
    module, r = study
    other = dict(r, seed=4)
    module.print_seeds_summary([r, other])
    out = capsys.readouterr().out
    assert "seeds 1, 4" in out and "held-out RMS / smoother's sigma" in out and "+- 0.00" in out
    assert module.parse_seeds("11,12,13,14") == [11, 12, 13, 14]
    assert module.parse_seeds("3") == [11, 12, 13]
    with pytest.raises(Exception, match="seeds"):
        module.parse_seeds("11,x")


def test_coverage_over_seeds_runs_at_reduced_size(study, capsys):
    """The --coverage-seeds mode (8 fleets in docs/studies/2026-11-23-identification-study.md): one fleet of
    8 + 4 runs (two hot, the others flagged or in range), the runs measured with the smoother so the default fits
    on its fleet base. The study's fleet (seed, sizes and rate), so every run is the study's, measured once
    (`measure_each_run_once`): the mode's own work here is its fits and intervals (a fleet of 8 + 2 with one hot
    run measured a run and its twin anew, ~3 s, for no claim of its own)."""
    module, _ = study
    c = module.coverage_study([1], n_train=8, n_test=4, n_hot=2, rate_hz=2.0)
    assert c["default_physics_columns"] == ["drift_smoother_fleet_deg_h"]
    for name in (module.DEFAULT, module.FLEET_PHYSICS_ENCODING, module.OLD_DEFAULT):
        assert c[name]["coverage_eff"].shape == (1,) and 0.0 <= c[name]["coverage_eff"][0] <= 1.0
        assert 0 < c[name]["rms_eff"][0] < 2e-3
        # runs flagged and runs in range alike (measured: in range 1.0, flagged 0.67-1.0, hot/in-range 1.25-1.29)
        for key in ("coverage_in_range", "coverage_flagged", "hot_half_width_ratio"):
            assert np.isfinite(c[name][key][0]), (name, key)
    module.print_coverage(c, 4)
    assert "covers the effective drift" in capsys.readouterr().out
