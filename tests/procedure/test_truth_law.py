"""Truth's best drift law (gyrodrift.procedure.truth_law): the least squares against brute force, the covariance
against Monte Carlo, the basis's T_ref shift, and on simulated runs with a daily swing the law recovered, navigated
and better than the best constant; without temperature change the constant, said so."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import minimize

from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure.passes import navigate_after_alignment
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.procedure.truth import criterion_value, find_true_drift
from gyrodrift.procedure.truth_law import (
    BASIS_T_REF_C,
    K1_TRIAL_DEG_H_PER_C,
    LawModel,
    best_law_coefficients,
    k1_response,
    law_covariance,
)


def curves(seed: int, n: int = 200):
    """Random smooth error curves [m] and responses g [m per deg/h], h [m per deg/h/degC]."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n)
    n0, e0 = (np.polyval(rng.normal(size=4), t) * 3000.0 for _ in range(2))
    gn, ge = (np.polyval(rng.normal(size=3), t) * 4e5 for _ in range(2))
    hn, he = (np.polyval(rng.normal(size=4), t) * 2e5 for _ in range(2))
    return n0, e0, gn, ge, hn, he


@pytest.mark.parametrize("criterion", ["final", "rms", "max"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_coefficients_minimise_the_criterion_like_brute_force(criterion, seed):
    n0, e0, gn, ge, hn, he = curves(seed)
    ref_d = 0.001

    def f(x):
        u, k1 = x[0] - ref_d, x[1]
        return float(criterion_value(n0 + u * gn + k1 * hn, e0 + u * ge + k1 * he, criterion))

    eps, k1 = best_law_coefficients(ref_d, n0, e0, gn, ge, hn, he, criterion, criterion_value)
    # Brute force: Nelder-Mead from several starts on the criterion itself.
    best = min(
        (
            minimize(f, x0, method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 20000})
            for x0 in ([0.0, 0.0], [0.01, 0.001], [-0.01, -0.001])
        ),
        key=lambda r: r.fun,
    )
    assert f([eps, k1]) <= best.fun * (1 + 1e-6) + 1e-12
    if criterion == "final":
        assert f([eps, k1]) < 1e-9  # two coefficients meet north and east at the end


def test_covariance_matches_monte_carlo_for_white_isotropic_error():
    _, _, gn, ge, hn, he = curves(7, n=60)
    s = 30.0  # [m] white, isotropic unexplained error on every sample
    a = np.column_stack([np.concatenate([gn, ge]), np.concatenate([hn, he])])
    sigma_c = s / math.sqrt(float(np.sum(gn**2 + ge**2)))  # the constant's rms label 1-sigma for that error
    cov = law_covariance(gn, ge, hn, he, "rms", sigma_c)
    rng = np.random.default_rng(0)
    draws = []
    for _ in range(4000):
        e = rng.normal(0.0, s, size=a.shape[0])
        draws.append(best_law_coefficients(0.0, e[:60], e[60:], gn, ge, hn, he, "rms", criterion_value))
    mc = np.cov(np.asarray(draws).T)
    assert np.allclose(np.sqrt(np.diag(cov)), np.sqrt(np.diag(mc)), rtol=0.05)
    corr = cov[0, 1] / math.sqrt(cov[0, 0] * cov[1, 1])
    assert corr == pytest.approx(mc[0, 1] / math.sqrt(mc[0, 0] * mc[1, 1]), abs=0.05)
    assert cov[0, 0] >= sigma_c**2 * (1 - 1e-12)  # the law's eps_ref is never better known than the constant


def test_k1_response_moves_the_basis_to_the_laws_t_ref():
    n0, e0, gn, ge, hn, he = curves(4)
    t_ref = 31.5
    # The basis compensates K1 (T - BASIS_T_REF_C) = K1 (T - t_ref) + K1 (t_ref - BASIS_T_REF_C): linear model.
    bn = n0 + K1_TRIAL_DEG_H_PER_C * (hn + (t_ref - BASIS_T_REF_C) * gn)
    be = e0 + K1_TRIAL_DEG_H_PER_C * (he + (t_ref - BASIS_T_REF_C) * ge)
    rn, re_ = k1_response(bn, be, n0, e0, gn, ge, t_ref)
    assert np.allclose(rn, hn, rtol=0, atol=1e-6 * np.abs(hn).max())
    assert np.allclose(re_, he, rtol=0, atol=1e-6 * np.abs(he).max())


def test_flat_temperature_gives_the_constant_and_says_so():
    n0, e0, gn, ge, _, _ = curves(5)
    model = LawModel.from_basis(
        n0, e0, n0, e0, gn, ge, BASIS_T_REF_C, "final", criterion_value
    )  # basis = base: no excursion
    assert not model.determined and "undetermined" in model.note
    best = model.result(0.0, n0, e0, gn, ge, constant_deg_h=0.0025, constant_std_deg_h=1e-4, constant_nmi=0.2)
    assert best.law.is_constant and best.law.eps_ref_deg_h == 0.0025 and not best.determined
    assert best.law.std_deg_h(20.0) == pytest.approx(1e-4)


TIMELINE = Timeline(align_h=4.0, features_h=12, truth_h=24.0, coarse_s=DEFAULT_TIMELINE.coarse_s)
K1_TRUE, T0_C, D0 = 2e-4, 28.0, 0.002


def swing_log(amplitude_c: float, start_c: float = 20.0, end_c: float = 30.0):
    s = Scenario.from_dict(
        {
            "site": {"lat_deg": 40.0},
            "run": {"duration_h": 28.0, "rate_hz": 5.0, "seed": 3},
            "gyro": {"bias_deg_h": [0.0, 0.0, D0]},
            "temperature": {
                "start_c": start_c,
                "end_c": end_c,
                "tau_h": 2.0,
                "swing_amplitude_c": amplitude_c,
                "swing_period_h": 12.0,
                "t0_c": T0_C,
                "k1_deg_h_per_c": K1_TRUE,
            },
        }
    )
    return scenario_log(s)


NOISE = {"gyro": {"arw_deg_rth": 0.0005}, "accel": {"vrw_ug_rthz": 5.0}}


@pytest.mark.parametrize("criterion", ["final", "rms"])
def test_noise_free_swing_recovers_the_law_and_beats_the_constant(criterion):
    log = swing_log(4.0)
    tr = find_true_drift(log, timeline=TIMELINE, hours=24.0, criterion=criterion, noise=NOISE)
    best = tr.law
    assert best is not None and best.determined and best.excursion_c > 1.0
    law = best.law
    # Near the sensor's own law at T_ref: the oracle also absorbs the alignment's errors (the warm-up and the swing
    # move the drift during the alignment), which the sensor's law does not cancel.
    assert law.k1_deg_h_per_c == pytest.approx(K1_TRUE, rel=0.5)
    assert law.eps_ref_deg_h == pytest.approx(D0 + K1_TRUE * (law.t_ref_c - T0_C), abs=5e-4)
    # The optimum by navigation: moving either coefficient worsens the navigated criterion.
    steps = [(0.0, 0.0), (2e-4, 0.0), (-2e-4, 0.0), (0.0, 4e-5), (0.0, -4e-5)]
    trials = [
        replace(law, eps_ref_deg_h=law.eps_ref_deg_h + a, k1_deg_h_per_c=law.k1_deg_h_per_c + b) for a, b in steps
    ]
    nav = navigate_after_alignment(log, tr.alignment, trials, 24.0)
    values = [float(criterion_value(c.north_m, c.east_m, criterion)) for c in nav.curves]
    assert values[0] == pytest.approx(best.navigated_nmi, rel=1e-9)
    assert values[0] < min(values[1:])
    # Verified by a navigation at the optimum: close to the prediction, well below the best constant's.
    assert math.isfinite(best.navigated_nmi)
    assert best.navigated_nmi < 0.5 * tr.verify_nmi[1]
    assert best.navigated_nmi == pytest.approx(best.predicted_nmi, abs=0.01)
    assert law.cov is not None and law.cov[0][0] >= tr.drift_std_deg_h**2 * (1 - 1e-9)
    assert tr.to_dict()["best_law"]["drift_law"]["k1_deg_h_per_c"] == law.k1_deg_h_per_c


def test_constant_temperature_reports_the_best_constant():
    log = swing_log(0.0, start_c=26.0, end_c=26.0)
    tr = find_true_drift(log, timeline=TIMELINE, hours=24.0, noise=NOISE, verify=False)
    best = tr.law
    assert best is not None and not best.determined and "undetermined" in best.note
    assert best.law.is_constant and best.law.eps_ref_deg_h == tr.drift_deg_h
    assert best.law.t_ref_c == 26.0


def test_law_off_or_no_temperature_gives_none():
    log = swing_log(4.0)
    tr = find_true_drift(log, timeline=TIMELINE, hours=24.0, noise=NOISE, verify=False, law=False)
    assert tr.law is None and tr.to_dict()["best_law"] is None


def test_truth_command_prints_the_best_law(tmp_path):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.ins.simulate import simulate

    scenario = swing_log(4.0).scenario
    simulate(scenario, out_dir=tmp_path / "run")
    args = ["truth", str(tmp_path / "run" / "imu.parquet"), "--hours", "24", "--gyro-arw-deg-rth", "0.0005"]
    r = CliRunner().invoke(main, [*args, "--accel-vrw-ug-rthz", "5"])
    assert r.exit_code == 0, r.output
    line = next(x for x in r.output.splitlines() if "best law" in x)
    assert "deg/h/degC) (T - " in line and "nmi navigated" in line


def test_features_with_truth_write_the_best_law(tmp_path):
    from gyrodrift.procedure import extract_features
    from gyrodrift.procedure.writers import features_csv_text
    from gyrodrift.runs.columns import TRUTH_LAW_COLUMNS
    from gyrodrift.runs.table import read_runs_csv

    f = extract_features(swing_log(4.0), with_truth=True, timeline=TIMELINE, smoother=False, noise=NOISE)
    assert f.truth is not None and f.truth.law is not None
    (tmp_path / "runs.csv").write_text(features_csv_text([f]), encoding="utf-8")
    runs = read_runs_csv(tmp_path / "runs.csv", require_truth=True)
    header, row = (tmp_path / "runs.csv").read_text(encoding="utf-8").splitlines()
    cells = dict(zip(header.split(","), row.split(","), strict=True))
    for name, value in f.truth.law.columns().items():
        assert name in TRUTH_LAW_COLUMNS
        assert float(cells[name]) == pytest.approx(value, rel=1e-12)
        if name != "truth_law_t_ref_c":  # kept by the reader (T_ref is read and left: not drift-sized)
            assert runs.column(name)[0] == pytest.approx(value, rel=1e-12)
    assert float(cells["truth_law_t_ref_c"]) == f.temp_end_c  # T_ref: the end of the features window
