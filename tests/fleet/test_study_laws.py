"""The study's drift-law comparison (issue 21, `gyrodrift.fleet.law_study`) on synthetic held-out runs whose answer
is known in closed form: each run's drift is exactly a law eps* + k1* (T - T_b), so compensating that law leaves
no error at all, a constant leaves k1* times the k1 response, and the identified law's k1 is the smoother's k_z
re-weighted by the fleet prior (the precision-weighted mean, written out here)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift.earth import NMI_M
from gyrodrift.fleet.law_study import LAW_METHODS, compare_laws, excursion_c, identified_k1, law_errors_nmi
from gyrodrift.fleet.store import CampaignRuns
from gyrodrift.fleet.study_report import law_figure, law_lines, render_html, summary_lines

T = np.linspace(0.0, 72.0, 73)
K1 = 2e-4  # deg/h/degC, every run's true k1
EPS = np.array([0.002, 0.0025, 0.0015, 0.003, 0.001, 0.002])  # deg/h at T_b
T_B = np.array([30.0, 31.0, 29.0, 33.0, 28.0, 30.5])  # the truth law's T_ref [deg C]
T_A = T_B - np.array([0.5, -1.0, 2.0, 0.0, 1.5, -0.3])  # the identified law's T_ref (end of the features window)
SWING = np.array([3.0, 5.0, 2.5, 0.0, 0.0, 0.0])  # three runs swing, three do not
H_SCALE = np.array([4.0, 3.0, 5.0, 2.0, 0.1, 0.2])  # |h| / |g| [deg C]: runs 4 and 5 at a steady temperature


def synthetic_runs(k_smoother=K1) -> CampaignRuns:
    """Six runs: g grows with the time since alignment (a heading error's Schuler-free growth), h oscillates (the
    daily swing's error); the uncompensated error is minus the true law's correction."""
    n = len(EPS)
    gn = np.outer(np.ones(n), 25000.0 * T)
    ge = np.outer(np.linspace(-0.5, 0.5, n), 13000.0 * T)
    hn = H_SCALE[:, None] * 25000.0 * T * np.sin(2 * np.pi * T / 24.0)[None, :]
    he = H_SCALE[:, None] * 13000.0 * T * np.cos(2 * np.pi * T / 24.0)[None, :] * 0.3
    n0 = -(EPS[:, None] * gn + K1 * hn)
    e0 = -(EPS[:, None] * ge + K1 * he)
    curves = {
        "curve_t_h": np.outer(np.ones(n), T),
        "curve_north0_m": n0,
        "curve_east0_m": e0,
        "curve_north_per_deg_h": gn,
        "curve_east_per_deg_h": ge,
        "curve_north_per_k1": hn,
        "curve_east_per_k1": he,
    }
    columns = {
        "index": np.arange(n),
        "error": np.array([None] * n, dtype=object),
        "param_temperature_swing_amplitude_c": SWING,
        "temp_end_c": T_A,
        "drift_deg_h": EPS + 1e-4,  # an offline best constant (not the law)
        "truth_law_eps_ref_deg_h": EPS,
        "truth_law_k1_deg_h_per_c": np.full(n, K1),
        "truth_law_t_ref_c": T_B,
        "drift_smoother_deg_h": EPS,
        "drift_smoother_std_deg_h": np.full(n, 3e-4),
        "smoother_coeff_deg_h_per_c": np.full(n, k_smoother),
        "smoother_coeff_std_deg_h_per_c": np.full(n, 1e-4),
        "smoother_end_coeff_cov": np.zeros(n),
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e30),  # no own prior to take out
    }
    return CampaignRuns(columns, curves)


def test_the_true_law_leaves_no_error_at_either_t_ref_and_a_constant_leaves_k1_times_h():
    runs = synthetic_runs()
    exact = law_errors_nmi(runs, EPS, np.full(6, K1), T_B)
    np.testing.assert_allclose(exact, 0.0, atol=1e-9)
    # the same law about T_A: eps* + k1 (T_A - T_B) at T_A
    np.testing.assert_allclose(law_errors_nmi(runs, EPS + K1 * (T_A - T_B), np.full(6, K1), T_A), 0.0, atol=1e-9)
    c = runs.curves
    constant = law_errors_nmi(runs, EPS, np.zeros(6), T_A)  # eps* as one constant: the k1 term is left
    expected = np.hypot(K1 * c["curve_north_per_k1"], K1 * c["curve_east_per_k1"]) / NMI_M
    np.testing.assert_allclose(constant, expected, rtol=1e-9, atol=1e-12)
    assert np.max(constant) > 0.1


def test_excursion_and_the_identified_k1_in_closed_form():
    runs = synthetic_runs(k_smoother=3e-4)
    g2 = np.sum(runs.curves["curve_north_per_deg_h"] ** 2 + runs.curves["curve_east_per_deg_h"] ** 2, axis=1)
    h2 = np.sum(runs.curves["curve_north_per_k1"] ** 2 + runs.curves["curve_east_per_k1"] ** 2, axis=1)
    np.testing.assert_allclose(excursion_c(runs), np.sqrt(h2 / g2), rtol=1e-12)
    # the smoother's 3e-4 +- 1e-4 and the fleet's 1e-4 +- 1e-4: the precision-weighted mean 2e-4
    np.testing.assert_allclose(identified_k1(runs, (1e-4, 1e-4)), 2e-4, rtol=1e-12)
    np.testing.assert_array_equal(identified_k1(runs, None), 0.0)  # no fleet base: identify's law is the constant
    runs.columns["smoother_end_coeff_cov"] = np.array([0.0, math.nan, 0.0, 0.0, 0.0, 0.0])  # run 1: constant model
    k1 = identified_k1(runs, (1e-4, 1e-4))
    assert k1[1] == 0.0 and k1[0] == pytest.approx(2e-4, rel=1e-12)


def test_the_identified_law_reaches_the_best_law_and_closes_the_whole_gap():
    runs = synthetic_runs()
    constant_today = EPS + K1 * (T_A - T_B)  # the law's value at T_A, the end of the features window
    doc = compare_laws(runs, constant_today, (K1, 1e-5), seed=3)
    assert doc["methods"] == list(LAW_METHODS)
    assert "law on the fleet base" not in compare_laws(runs, constant_today, None)["methods"]  # not a fleet base
    runs.columns["truth_law_k1_deg_h_per_c"] = np.full(6, 3e-4)  # the best law's k1 is not the identified one
    doc = compare_laws(runs, constant_today, (1e-4, 1e-4), seed=3)
    np.testing.assert_allclose(doc["identified_k1_deg_h_per_c"], 1.5e-4, rtol=1e-9)  # (2e-4 + 1e-4) / 2
    runs.columns["truth_law_k1_deg_h_per_c"] = np.full(6, K1)
    doc = compare_laws(runs, constant_today, (K1, 1e-5), seed=3)
    np.testing.assert_allclose(doc["identified_k1_deg_h_per_c"], K1, rtol=1e-9)
    final = doc["final_nmi"]
    np.testing.assert_allclose(final["identified law"], 0.0, atol=1e-9)
    np.testing.assert_allclose(final["offline best law"], 0.0, atol=1e-9)
    c = runs.curves
    expected = np.hypot(
        (constant_today - EPS) * c["curve_north_per_deg_h"][:, -1] - K1 * c["curve_north_per_k1"][:, -1],
        (constant_today - EPS) * c["curve_east_per_deg_h"][:, -1] - K1 * c["curve_east_per_k1"][:, -1],
    )
    np.testing.assert_allclose(final["constant today"], expected / NMI_M, rtol=1e-9)
    np.testing.assert_allclose(
        final["uncompensated"], np.hypot(c["curve_north0_m"][:, -1], c["curve_east0_m"][:, -1]) / NMI_M, rtol=1e-12
    )
    groups = doc["groups"]
    assert [groups[g]["n"] for g in ("all", "daily swing", "no swing", "steady temperature")] == [6, 3, 3, 2]
    swing = groups["daily swing"]
    law, today = swing["methods"]["identified law"], swing["methods"]["constant today"]
    assert law["rms_final_nmi"] == pytest.approx(0.0, abs=1e-9) and law["rms_final_nmi_std"] < 1e-9
    assert today["rms_final_nmi"] == pytest.approx(math.sqrt(np.mean((expected[:3] / NMI_M) ** 2)), rel=1e-9)
    assert law["under_1nmi_final"] == 1.0 and law["under_1nmi_final_std"] == 0.0
    p = today["under_1nmi_72h"]
    assert today["under_1nmi_72h_std"] == pytest.approx(math.sqrt(p * (1 - p) / 3))
    assert swing["gap_closed"]["rms_final_nmi"] == pytest.approx(1.0, abs=1e-6)
    vs = swing["identified_vs"]["constant today"]
    assert vs["d_rms_final_nmi"] == pytest.approx(-today["rms_final_nmi"], abs=1e-9) and vs["d_rms_final_nmi_std"] > 0
    assert compare_laws(runs, constant_today, (K1, 1e-5), seed=3)["groups"] == groups  # seeded bootstrap


def test_the_report_leads_with_the_law_table_and_says_when_there_is_none():
    runs = synthetic_runs()
    laws = compare_laws(runs, EPS + K1 * (T_A - T_B), (K1, 1e-5))
    metrics = {"rms_eff": 1e-4, "max_eff": 2e-4, "rms_truth": 1e-4, "max_truth": 2e-4, "ratio_to_limit": 1.0}
    metrics |= {"under_1nmi_final": 1.0, "under_1nmi_72h": 1.0}
    doc = {
        "n_runs": 6,
        "n_failed": 0,
        "n_train": 0,
        "n_test": 6,
        "seed": 0,
        "label_error_rms_deg_h": 1e-5,
        "physical_limit_deg_h": None,
        "methods": {"hybrid default": {"metrics": metrics, "note": ""}},
        "drift_laws": laws,
        "notes": [],
    }
    lines = law_lines(doc)
    assert len(lines) == 4 and lines[1].startswith("Drift laws, daily swing (3 held-out runs)")
    assert summary_lines(doc)[1:5] == lines
    images = dict.fromkeys(("laws.png", "methods.png", "train_size.png", "noise_grade.png", "latitude.png"), b"x")
    page = render_html(doc, images)
    assert page.index("Drift laws on the held-out runs") < page.index("Methods on the held-out runs")
    assert "identified law - offline best constant" in page and "gap closed" in page
    (ax,) = law_figure(doc).axes
    assert len(ax.patches) == 4 * len(LAW_METHODS)  # four groups, one bar per method
    doc["drift_laws"] = None
    assert law_lines(doc) == [] and "Drift laws" not in render_html(doc, images)
    (ax,) = law_figure(doc).axes
    assert "no drift-law comparison" in ax.texts[0].get_text()
