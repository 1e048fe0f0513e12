"""The drift law's physical limit (`gyrodrift.fleet.law_limit`) against independent references: closed forms, and a
Monte Carlo of the linear model on one synthetic run copied many times (the law's coefficients drawn from their
covariance, the noise floor drawn isotropic), whose observed RMS, share under 1 nmi and z-scores must match the
predicted ones within their sampling error."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift.earth import NMI_M
from gyrodrift.fleet.law_limit import limit_report, simulated_law
from gyrodrift.fleet.law_study import law_covariance, law_errors_nmi
from gyrodrift.fleet.spec import load_campaign
from gyrodrift.fleet.store import CampaignRuns

N = 8000
J = np.array([[2.5e6, 6e6], [-1.5e6, 4e6]])  # m per deg/h, m per deg/h/degC at 72 h (1.6 nmi per 1e-3 deg/h)
P = np.array([[9e-8, -2e-10], [-2e-10, 4e-11]])  # (eps_b, k1) covariance: 3e-4 deg/h, 6.3e-6 deg/h/degC
LABEL_STD = 2e-4  # deg/h: s = LABEL_STD |g| / NMI_M per axis
THETA0 = np.array([0.002, 2e-4])


def monte_carlo_runs(rng, cov_scale: float = 1.0):
    """N copies of one run: the true law THETA0, the noise floor w ~ N(0, s^2 I), the identified law drawn from
    N(THETA0, cov_scale P); curves of two samples, the last one the 72 h end."""
    g = J[:, 0]
    s_m = LABEL_STD * np.hypot(*g)  # per-axis 1-sigma of w [m]
    w = rng.normal(0.0, s_m, size=(N, 2))
    n0 = w - J @ THETA0
    theta = rng.multivariate_normal(THETA0, cov_scale * P, size=N)
    t_b = np.full(N, 30.0)

    def pair(last):
        return np.stack([np.zeros(N), last], axis=1)

    curves = {
        "curve_t_h": pair(np.full(N, 72.0)),
        "curve_north0_m": pair(n0[:, 0]),
        "curve_east0_m": pair(n0[:, 1]),
        "curve_north_per_deg_h": pair(np.full(N, J[0, 0])),
        "curve_east_per_deg_h": pair(np.full(N, J[1, 0])),
        "curve_north_per_k1": pair(np.full(N, J[0, 1])),
        "curve_east_per_k1": pair(np.full(N, J[1, 1])),
    }
    columns = {"index": np.arange(N), "truth_law_t_ref_c": t_b, "drift_std_deg_h": np.full(N, LABEL_STD)}
    runs = CampaignRuns(columns, curves)
    finals = {"law": law_errors_nmi(runs, theta[:, 0], theta[:, 1], t_b)[:, -1]}
    return runs, theta, finals


def with_past_noise(rng, cancel: float):
    """N copies of one run whose noise has a past part w_past = -cancel J (theta - THETA0) (the identification error
    cancelled by a share `cancel` of itself: the bound's worst case) and an independent future part of the 1-sigma
    `future_noise_std_nmi` gives the run's site and grade; ``drift_std_deg_h`` says the total noise's 1-sigma."""
    from gyrodrift.fleet.law_limit import future_noise_std_nmi

    g = J[:, 0]
    columns = {"index": np.arange(N), "truth_law_t_ref_c": np.full(N, 30.0)}
    columns |= {"lat_deg": np.full(N, 40.0), "arw_deg_rth": np.full(N, 5e-4), "vrw_ug_rthz": np.full(N, 5.0)}
    s_f = float(future_noise_std_nmi(CampaignRuns(columns, None), 60.0)[0])  # per axis [nmi]
    a = float(np.trace(J @ P @ J.T)) / NMI_M**2
    s = math.sqrt(s_f**2 + cancel**2 * a / 2.0)  # the past part's mean square, cancel^2 a, split over two axes
    columns["drift_std_deg_h"] = np.full(N, s * NMI_M / np.hypot(*g))
    theta = rng.multivariate_normal(THETA0, P, size=N)
    w = -cancel * (theta - THETA0) @ J.T + rng.normal(0.0, s_f * NMI_M, size=(N, 2))
    n0 = w - J @ THETA0

    def pair(last):
        return np.stack([np.zeros(N), last], axis=1)

    curves = {"curve_t_h": pair(np.full(N, 72.0)), "curve_north0_m": pair(n0[:, 0]), "curve_east0_m": pair(n0[:, 1])}
    for axis, row in (("north", 0), ("east", 1)):
        curves[f"curve_{axis}_per_deg_h"] = pair(np.full(N, J[row, 0]))
        curves[f"curve_{axis}_per_k1"] = pair(np.full(N, J[row, 1]))
    runs = CampaignRuns(columns, curves)
    return runs, theta, {"law": law_errors_nmi(runs, theta[:, 0], theta[:, 1], columns["truth_law_t_ref_c"])[:, -1]}


def test_the_lower_bound_is_reached_when_the_past_noise_cancels_the_identification_error():
    runs, theta, finals = with_past_noise(np.random.default_rng(11), cancel=0.6)
    entry = report(runs, theta, finals)
    row = entry["laws"]["law"]
    assert row["lower_bound_rms_nmi"] < entry["laws"]["law"]["predicted_rms_nmi"]
    assert row["observed_rms_nmi"] == pytest.approx(row["lower_bound_rms_nmi"], rel=0.02)  # reached: E|e|^2 is it
    runs, theta, finals = with_past_noise(np.random.default_rng(12), cancel=-0.6)  # the past noise adds instead
    row = report(runs, theta, finals)["laws"]["law"]
    assert row["observed_rms_nmi"] > 1.3 * row["lower_bound_rms_nmi"]
    assert row["observed_rms_nmi"] > row["predicted_rms_nmi"] * 1.05  # correlated, not the independent prediction


def report(runs, theta, finals):
    laws = {"law": (theta[:, 0], theta[:, 1], np.broadcast_to(P, (N, 2, 2)))}
    truth = (np.full(N, THETA0[0]), np.full(N, THETA0[1]))
    out = limit_report(runs, laws, finals, {"all": np.ones(N, bool)}, future_hours=60.0, simulated=truth)
    return out["groups"]["all"]


def test_the_predicted_limit_matches_a_monte_carlo_of_the_linear_model():
    runs, theta, finals = monte_carlo_runs(np.random.default_rng(7))
    entry = report(runs, theta, finals)
    row = entry["laws"]["law"]
    jn = J / NMI_M
    s = LABEL_STD * np.hypot(*J[:, 0]) / NMI_M
    ident = float(np.trace(jn @ P @ jn.T))  # closed form of the identification part
    assert row["predicted_identification_rms_nmi"] == pytest.approx(math.sqrt(ident), rel=1e-12)
    assert row["predicted_rms_nmi"] == pytest.approx(math.sqrt(ident + 2 * s * s), rel=1e-12)
    assert entry["noise_floor_rms_nmi"] == pytest.approx(math.sqrt(2) * s, rel=1e-12)
    # sampling error of these RMS over N draws: about 0.6 % (half the relative spread of |e|^2, about 1, over
    # sqrt(N)); 2 % (the worst of ten other seeds: 1.3 %)
    assert row["ratio"] == pytest.approx(1.0, abs=0.02)
    assert row["ratio_identification"] == pytest.approx(1.0, abs=0.02)
    assert entry["observed_noise_floor_rms_nmi"] == pytest.approx(math.sqrt(2) * s, rel=0.02)
    p = row["predicted_under_1nmi_final"]
    assert 0.2 < p < 0.95  # a share the test can see move
    assert abs(row["observed_under_1nmi_final"] - p) < 4.0 * math.sqrt(p * (1 - p) / N)
    assert row["z_eps_ref_rms"] == pytest.approx(1.0, abs=0.03)
    assert row["z_k1_rms"] == pytest.approx(1.0, abs=0.03)
    assert abs(row["z_eps_ref_mean"]) < 0.045 and abs(row["z_k1_mean"]) < 0.045  # 4 standard errors, 1 / sqrt(N)
    assert math.isnan(entry["future_noise_rms_nmi"])  # no latitude or noise columns: not computed
    assert math.isnan(row["lower_bound_rms_nmi"])


def test_a_law_twice_as_uncertain_as_its_covariance_says_is_caught():
    runs, theta, finals = monte_carlo_runs(np.random.default_rng(8), cov_scale=4.0)
    row = report(runs, theta, finals)["laws"]["law"]
    assert row["ratio_identification"] == pytest.approx(2.0, abs=0.05)
    assert row["z_eps_ref_rms"] == pytest.approx(2.0, abs=0.06)
    assert row["ratio"] > 1.3
    assert row["observed_under_1nmi_final"] < row["predicted_under_1nmi_final"] - 0.05


def test_law_covariance_moves_to_the_truths_t_ref():
    n = 3
    columns = {
        "index": np.arange(n),
        "temp_end_c": np.array([30.0, 31.0, 29.0]),
        "truth_law_t_ref_c": np.array([30.0, 33.0, 28.0]),
        "drift_smoother_deg_h": np.full(n, 0.002),
        "drift_smoother_std_deg_h": np.full(n, 3e-4),
        "smoother_coeff_deg_h_per_c": np.full(n, 2e-4),
        "smoother_coeff_std_deg_h_per_c": np.full(n, 1e-4),
        "smoother_end_coeff_cov": np.full(n, 5e-9),
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e30),
    }
    runs = CampaignRuns(columns, None)
    cov = law_covariance(runs, (2e-4, 1e-5), columns["temp_end_c"])
    # the fleet posterior in closed form: the k_z precision 1/V_k + 1/std^2, the drift moved along its lever
    vk = 1.0 / (1.0 / 1e-8 + 1.0 / 1e-10)
    lever = 5e-9 / 1e-8
    var_d, cov_dk = 9e-8 - lever * 5e-9 + lever**2 * vk, lever * vk
    dt = columns["truth_law_t_ref_c"] - columns["temp_end_c"]
    np.testing.assert_allclose(cov[:, 0, 0], var_d + 2 * dt * cov_dk + dt**2 * vk, rtol=1e-9)
    np.testing.assert_allclose(cov[:, 0, 1], cov_dk + dt * vk, rtol=1e-9)
    np.testing.assert_allclose(cov[:, 1, 1], vk, rtol=1e-9)


def test_simulated_law_reads_the_campaigns_scenarios():
    from importlib.resources import files

    campaign = load_campaign(files("gyrodrift") / "examples" / "campaigns" / "daily_swings.toml")
    index = np.array([3, 0, 17])
    t_b = np.array([30.0, 25.0, 35.5])
    runs = CampaignRuns({"index": index, "truth_law_t_ref_c": t_b}, None)
    eps, k1 = simulated_law(campaign, runs)
    for i, run in enumerate(index):
        scn = campaign.scenario(int(run))
        t = scn.temperature
        assert k1[i] == t.k1_deg_h_per_c == 2e-4
        assert eps[i] == pytest.approx(scn.gyro.bias_deg_h[2] + 2e-4 * (t_b[i] - t.t0_c), rel=1e-12)
    assert len(set(eps - 2e-4 * t_b)) == 3  # each run its own bias


def test_compare_laws_reports_the_limit_and_the_summary_says_it():
    from gyrodrift.fleet.law_study import compare_laws
    from gyrodrift.fleet.study_report import law_lines

    runs, theta, _ = monte_carlo_runs(np.random.default_rng(9))
    n = 300
    runs = runs.select(np.arange(n))
    theta = theta[:n]
    runs.columns |= {
        "error": np.array([None] * n, dtype=object),
        "temp_end_c": np.full(n, 30.0),
        "drift_deg_h": np.full(n, THETA0[0]),
        "truth_law_eps_ref_deg_h": np.full(n, THETA0[0]),
        "truth_law_k1_deg_h_per_c": np.full(n, THETA0[1]),
        "drift_smoother_deg_h": theta[:, 0],
        "drift_smoother_std_deg_h": np.full(n, math.sqrt(P[0, 0])),
        "smoother_coeff_deg_h_per_c": theta[:, 1],
        "smoother_coeff_std_deg_h_per_c": np.full(n, math.sqrt(P[1, 1])),
        "smoother_end_coeff_cov": np.full(n, P[0, 1]),
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e30),
    }
    laws = compare_laws(runs, theta[:, 0], (THETA0[1], 1e3), seed=0)  # a prior that adds nothing
    limit = laws["limit"]["groups"]["all"]
    row = limit["laws"]["identified law"]
    assert limit["n"] == n and "n_simulated" not in limit  # no campaign: no simulated law
    assert row["predicted_identification_rms_nmi"] == pytest.approx(math.sqrt(np.trace(J @ P @ J.T)) / NMI_M, rel=1e-6)
    assert row["observed_rms_nmi"] == pytest.approx(laws["groups"]["all"]["methods"]["identified law"]["rms_final_nmi"])
    assert row["ratio"] == pytest.approx(1.0, abs=0.15)  # 300 draws
    doc = {"drift_laws": laws}
    (line,) = [s for s in law_lines(doc) if s.startswith("Physical limit of the identified law, all:")]
    assert f"predicted RMS {row['predicted_rms_nmi']:.3g} nmi" in line
    laws["limit"] = None  # a study.json written before the limit: no line
    assert not [s for s in law_lines(doc) if s.startswith("Physical limit")]
