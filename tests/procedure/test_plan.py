"""The planner (`gyrodrift.procedure.plan`, `gyrodrift plan`): its drift 1-sigma against the smoother's, the
mission-error distribution against a Monte Carlo of the same Gaussian, the closed forms, the span search, bad
inputs and the command."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.earth import NMI_M, OMEGA_IE_RAD_S, radii_of_curvature
from gyrodrift.errors import InputError
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.plan import (
    MissionBudget,
    identification_curve,
    mission_error_model,
    mission_outlook,
    norm_cdf,
    norm_quantile,
    plan_identification,
)
from gyrodrift.procedure.smoother import smooth_log
from gyrodrift.procedure.timeline import Timeline
from gyrodrift.units import DEG_PER_H

RLG = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0)


RLG_GM = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0, bias_instability_deg_h=0.001, correlation_s=3600.0)


@pytest.mark.parametrize("noise", [RLG, RLG_GM], ids=["white", "bias-instability"])
def test_the_planner_sigma_is_the_smoothers_reported_sigma_on_a_simulated_run(noise):
    # A noisy 3 h log at 5 Hz, 35 deg, reciprocating table, yaw 30 deg: the smoother's reported 1-sigma is its
    # filter's covariance, which the planner runs without the samples. Tolerance 2 %: the smoother's attitude is
    # its navigator's (arcseconds off the simulator's), and its updates average the attitude the same way. Told of
    # a bias instability, both leave its Gauss-Markov state out of the drift carried into navigation (with it the
    # planner's 1-sigma would be about twice the smoother's here).
    scn = Scenario.from_dict(
        {
            "site": {"lat_deg": 35.0},
            "run": {"duration_h": 3.0, "rate_hz": 5.0, "seed": 4},
            "attitude": {"yaw_deg": 30.0},
            "gyro": {"bias_deg_h": [0.002, -0.001, 0.003], "arw_deg_rth": 0.0005},
            "accel": {"vrw_ug_rthz": 5.0},
        }
    )
    est = smooth_log(scenario_log(scn), noise=noise, hours=3.0, thermal=False)
    planned = identification_curve(noise, [3.0], scenario=scn).drift_std_deg_h[0]
    assert planned == pytest.approx(est.drift_end_std_deg_h, rel=0.02)
    assert est.model == "constant"


def test_the_drift_sigma_falls_with_the_span_and_the_noise():
    spans = [6.0, 10.0, 16.0, 24.0]
    rlg = identification_curve(RLG, spans, lat_deg=40.0).drift_std_deg_h
    quiet = identification_curve(SensorNoise(arw_deg_rth=0.0002, vrw_ug_rthz=2.0), spans, lat_deg=40.0).drift_std_deg_h
    assert np.all(np.diff(rlg) < 0) and np.all(np.diff(quiet) < 0)
    assert np.all(quiet < 0.6 * rlg)


def test_the_error_distribution_matches_a_monte_carlo_of_the_same_gaussian():
    # Quantiles and shares of |e| for three shapes (circular, 2:1, 30:1 eccentric, rotated): the integral against
    # 400 000 draws. Monte-Carlo 1-sigma of a share: sqrt(p (1 - p) / n) <= 8e-4; tolerance 4e-3. Quantiles within
    # 1 % (the Monte-Carlo quantile's own spread is about 0.2 %).
    rng = np.random.default_rng(3)
    for l1, l2, angle in ((1.0, 1.0, 0.0), (4.0, 1.0, 0.4), (900.0, 1.0, 1.1)):
        rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
        cov = rot @ np.diag([l1, l2]) @ rot.T
        e = rng.multivariate_normal([0.0, 0.0], cov, size=400_000)
        r = np.hypot(e[:, 0], e[:, 1])
        for p in (0.5, 0.9, 0.95, 0.99):
            assert norm_quantile(cov, p) == pytest.approx(np.quantile(r, p), rel=0.01)
        for radius in np.quantile(r, [0.3, 0.7, 0.97]):
            assert norm_cdf(cov, radius) == pytest.approx(np.mean(r <= radius), abs=4e-3)


def test_the_circular_case_is_the_rayleigh_law():
    cov = np.eye(2) * 2.5**2
    for p in (0.5, 0.95):
        assert norm_quantile(cov, p) == pytest.approx(2.5 * math.sqrt(-2 * math.log(1 - p)), rel=1e-9)


def test_the_mission_response_is_the_closed_forms_of_a_drift_error():
    # dL(t) = (eps cos L / w)(1 - cos w t), dlon(t) = eps sin L (t - sin(w t) / w): north (R_M + h) dL, east
    # (R_N + h) cos L dlon. At 72 h (three Earth turns) the latitude term nearly vanishes; at 66 h it does not.
    for lat, hours in ((40.0, 72.0), (20.0, 66.0), (60.0, 30.0)):
        m = mission_error_model(lat, SensorNoise(arw_deg_rth=0.0, vrw_ug_rthz=0.0), hours=hours)
        L, t, w = math.radians(lat), hours * 3600.0, OMEGA_IE_RAD_S
        rm, rn = (float(np.asarray(r).reshape(-1)[0]) for r in radii_of_curvature(np.array([L])))
        eps = DEG_PER_H
        north = rm * eps * math.cos(L) / w * (1 - math.cos(w * t))
        east = rn * math.cos(L) * eps * math.sin(L) * (t - math.sin(w * t) / w)
        scale = math.hypot(north, east)
        assert m.response_m_per_deg_h[0] == pytest.approx(north, abs=0.01 * scale)
        assert m.response_m_per_deg_h[1] == pytest.approx(east, abs=0.01 * scale)
        assert np.allclose(m.floor_cov_m2, 0.0)


def test_the_noise_floor_is_the_arw_walk():
    # method.md: N = 0.0005 deg/sqrt(h) moves the 72 h position by about 0.31 nmi per axis.
    m = mission_error_model(40.0, RLG)
    per_axis = np.sqrt(np.diag(np.asarray(m.floor_cov_m2))) / NMI_M
    assert np.all((0.25 < per_axis) & (per_axis < 0.37)), per_axis


def test_the_alignments_leftovers_join_the_floor_and_fade_at_whole_days():
    # The aligner's leftover heading and tilts drive the Earth-rate (24 h) mode of the free navigation: hundreds of
    # metres after 60 h of mission, back to a few metres after 72 h (three sidereal days and 12 min).
    at = {h: identification_curve(RLG, [16.0], lat_deg=40.0, mission_h=h).alignment_cov_m2 for h in (60.0, 72.0)}
    assert np.sqrt(np.max(np.diag(at[60.0]))) > 100.0 > 20.0 > np.sqrt(np.max(np.diag(at[72.0])))
    assert np.all(np.linalg.eigvalsh(at[60.0]) >= 0.0)
    with_alignment = mission_error_model(40.0, RLG, hours=60.0, alignment_cov_m2=at[60.0])
    without = mission_error_model(40.0, RLG, hours=60.0)
    got = np.asarray(with_alignment.floor_cov_m2) - np.asarray(without.floor_cov_m2)
    assert np.allclose(got, at[60.0], rtol=1e-9, atol=1e-9)
    assert np.asarray(with_alignment.alignment_cov_m2) == pytest.approx(at[60.0], rel=1e-12)
    with pytest.raises(InputError, match="alignment_cov_m2: expected a finite 2 x 2"):
        mission_error_model(40.0, RLG, alignment_cov_m2=[1.0, 2.0])


def test_the_shortest_span_is_the_first_to_meet_the_budget():
    plan = plan_identification(RLG, lat_deg=40.0, min_span_h=6.0, max_span_h=30.0, step_h=0.5)
    i = int(np.nonzero(plan.spans_h == plan.shortest_span_h)[0][0])
    # The drift 1-sigma falls at every span; the share rises up to the answer (beyond it, near 99 %, the drift
    # error's covariance with the floor makes it wiggle by about 1e-4).
    assert np.all(np.diff(plan.drift_std_deg_h) < 0) and np.all(np.diff(plan.share_within[: i + 1]) > 0)
    assert i > 0 and plan.share_within[i] >= 0.95 > plan.share_within[i - 1]
    assert plan.quantile_nmi[i] <= 1.0 < plan.quantile_nmi[i - 1]
    assert plan.drift_std_deg_h[i] <= plan.max_drift_std_deg_h < plan.drift_std_deg_h[i - 1]
    assert plan.reason.startswith(f"observe at least {plan.shortest_span_h:g} h")


def test_a_budget_below_the_noise_floor_has_no_span_and_says_why():
    plan = plan_identification(RLG, lat_deg=40.0, budget=MissionBudget(error_nmi=0.3), max_span_h=12.0, step_h=1.0)
    assert plan.shortest_span_h is None and plan.max_drift_std_deg_h is None
    assert "error floor" in plan.reason


def test_the_thermal_term_can_rule_out_every_span():
    plan = plan_identification(
        SensorNoise(arw_deg_rth=0.0002, vrw_ug_rthz=2.0),
        lat_deg=40.0,
        coeff_std_deg_h_per_c=1e-4,
        temp_change_c=10.0,  # 1e-3 deg/h of thermal 1-sigma: four times what the budget allows
        max_span_h=12.0,
        step_h=1.0,
    )
    assert plan.shortest_span_h is None and "thermal term" in plan.reason
    assert np.allclose(plan.drift_std_deg_h, np.hypot(plan.drift_std_id_deg_h, 1e-3))


@pytest.mark.slow
def test_mission_outlook_ready_and_not_ready():
    ok = mission_outlook(5e-5, 40.0, RLG, span_h=16.0)
    assert ok["ready"] and ok["more_static_h"] is None and ok["quantiles_nmi"]["0.95"] < 1.0
    late = mission_outlook(3e-4, 40.0, RLG, span_h=16.0)
    assert not late["ready"] and late["more_static_h"] > 0 and late["quantiles_nmi"]["0.95"] > 1.0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"lat_deg": float("nan")}, "lat_deg"),
        ({"lat_deg": 40.0, "coeff_std_deg_h_per_c": -1.0}, "coeff_std_deg_h_per_c"),
        ({"lat_deg": 40.0, "min_span_h": 10.0, "max_span_h": 8.0}, "max_span_h"),
        ({"lat_deg": 40.0, "max_span_h": 80.0}, "max_span_h"),
        ({}, "latitude"),
    ],
)
def test_bad_inputs_are_one_line_errors(kwargs, match):
    with pytest.raises(InputError, match=match) as info:
        plan_identification(RLG, **kwargs)
    assert "\n" not in str(info.value)


def test_bad_budgets_are_refused():
    for kwargs in ({"share": 1.0}, {"error_nmi": 0.0}, {"hours": float("inf")}):
        with pytest.raises(InputError, match="budget"):
            MissionBudget(**kwargs)


def test_the_command_writes_the_figure_and_the_json(tmp_path):
    out = tmp_path / "plan"
    args = ["plan", "--gyro-arw-deg-rth", "0.0002", "--accel-vrw-ug-rthz", "2", "--lat0-deg", "40"]
    args += ["--min-span-h", "6", "--max-span-h", "12", "--out", str(out), "--json"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["shortest_span_h"] is not None and doc["answer"].startswith("observe at least")
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["plan.json", "plan.png"]
    assert json.loads((out / "plan.json").read_text())["shortest_span_h"] == doc["shortest_span_h"]


def test_the_command_reads_a_scenario_and_refuses_bad_options(tmp_path):
    scn = tmp_path / "s.toml"
    scn.write_text("[site]\nlat_deg = 30.0\n[gyro]\narw_deg_rth = 0.0005\n[accel]\nvrw_ug_rthz = 5.0\n")
    res = CliRunner().invoke(main, ["plan", "--scenario", str(scn), "--max-span-h", "8", "--out", str(tmp_path / "a")])
    assert res.exit_code == 0, res.output
    assert "no span up to 8 h" in res.output
    cases = [
        (["plan", "--out", str(tmp_path / "b"), "--gyro-arw-deg-rth", "0.0005", "--accel-vrw-ug-rthz", "5"], 2),
        (["plan", "--out", str(tmp_path / "c"), "--lat0-deg", "40"], 2),
        (["plan", "--out", str(tmp_path / "d"), "--scenario", str(tmp_path / "missing.toml")], 1),
        (["plan", "--out", str(tmp_path / "e"), "--lat0-deg", "40", "--noise", str(scn), "--share", "1.5"], 2),
    ]
    for args, code in cases:
        res = CliRunner().invoke(main, args)
        assert res.exit_code == code, (args, res.output)
        assert "Traceback" not in res.output


def test_a_shorter_coarse_span_is_the_smoothers_too():
    # The timeline's coarse span reaches the core (both start the filter there).
    a = identification_curve(RLG, [6.0], lat_deg=40.0).drift_std_deg_h[0]
    b = identification_curve(RLG, [6.0], lat_deg=40.0, timeline=Timeline(coarse_s=120.0)).drift_std_deg_h[0]
    assert a != b and b == pytest.approx(a, rel=0.05)


@pytest.mark.slow
def test_identify_says_what_its_drift_sigma_means_for_the_mission():
    # A short time line (1 h alignment + 2 h) keeps the run cheap; the outlook is the planner's function of the
    # smoother's 1-sigma and the run's latitude, to the digit.
    from gyrodrift.learn.drift_model import fit_drift_model
    from gyrodrift.procedure.identify import identify
    from gyrodrift.runs.table import RunTable

    k = np.arange(6.0)
    table = RunTable(
        run=np.array([f"r{i}" for i in range(6)]),
        lat_deg=40.0 + 1e-4 * k,
        lat0_deg=np.full(6, 40.0),
        temp_min_c=20.0 + k,
        temp_max_c=25.0 + k,
        drift_deg_h=0.002 + 1e-4 * k,
        source="synthetic",
    )
    model = fit_drift_model(table, gamma=10.0, sigma=1.0)
    scn = Scenario.from_dict(
        {
            "site": {"lat_deg": 40.0},
            "run": {"duration_h": 3.0, "rate_hz": 5.0, "seed": 2},
            "gyro": {"bias_deg_h": [0.0, 0.0, 0.002], "arw_deg_rth": 0.0005},
            "accel": {"vrw_ug_rthz": 5.0},
        }
    )
    res = identify(scenario_log(scn), model, timeline=Timeline(align_h=1.0, features_h=2.0), noise=RLG)
    m = res.mission
    assert m is not None and m["drift_std_deg_h"] == res.smoother_drift_std_deg_h
    want = mission_outlook(res.smoother_drift_std_deg_h, 40.0, res.features.smoother.noise, span_h=3.0)
    assert m["quantiles_nmi"] == want["quantiles_nmi"] and m["ready"] is want["ready"] is False
    assert m["more_static_h"] > 0 and "not ready" in m["note"]
    assert res.to_dict()["mission"]["ready"] is False
