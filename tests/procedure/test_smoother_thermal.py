"""The smoother's thermal model of the z drift, b_z = eps_z + k_z (T - T_ref), on warm-up logs simulated on the fly.

Noise-free: the end-of-span drift equals the simulated one (constant + k1 (T_end - T0)) within 2e-5 deg/h and k_z
equals k1 within 1e-6 deg/h/degC. The constant-drift estimate beside it is the thermal state conditioned on
k_z = 0, i.e. the smoother without that state. The model follows the log: thermal when the temperature column
varies, constant when it is flat or missing. Consistency: z-scores of the end-of-span drift over a few short, slow
seeds (the 30-seed runs at full size are in benchmarks/bench_smoother_thermal.py and
docs/studies/2026-11-23-smoother.md).
"""

import math
from dataclasses import replace

import numpy as np
import pytest

from gyrodrift.errors import InputError
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.logs import ImuLog, LogError
from gyrodrift.procedure.smoother import fleet_coefficient_prior, smooth_log

RLG = {"arw_deg_rth": 0.0005, "vrw_ug_rthz": 5.0}
K1 = 0.0002
T0 = 28.0


def warm_up(*, drift=0.002, k1=K1, tau_h=2.0, start_c=18.0, end_c=36.0, noise=None, seed=1, hours=8.0, rate=5.0):
    noise = noise or {}
    return Scenario.from_dict(
        {
            "site": {"lat_deg": 40.0},
            "run": {"duration_h": hours, "rate_hz": rate, "seed": seed},
            "gyro": {"bias_deg_h": [0.004, -0.003, drift], "arw_deg_rth": noise.get("arw_deg_rth", 0.0)},
            "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": noise.get("vrw_ug_rthz", 0.0)},
            "temperature": {"start_c": start_c, "end_c": end_c, "tau_h": tau_h, "t0_c": T0, "k1_deg_h_per_c": k1},
            "attitude": {"yaw_deg": 30.0},
        }
    )


def end_drift(s: Scenario, hours: float) -> float:
    """The simulated z drift at `hours` [deg/h]."""
    t = s.temperature
    temp = t.end_c + (t.start_c - t.end_c) * math.exp(-hours / t.tau_h)
    return s.gyro.bias_deg_h[2] + t.k1_deg_h_per_c * (temp - t.t0_c)


def test_noise_free_warm_up_gives_the_end_of_span_drift_and_the_coefficient():
    for k1, tau_h in ((K1, 1.5), (-0.0005, 3.0)):
        s = warm_up(k1=k1, tau_h=tau_h)
        est = smooth_log(scenario_log(s), hours=8.0)
        assert est.model == "thermal" and est.temp_range_c > 10.0
        assert abs(est.navigation_drift_deg_h - end_drift(s, 8.0)) < 2e-5, (est.navigation_drift_deg_h, k1)
        assert est.navigation_drift_deg_h == est.drift_end_deg_h
        assert abs(est.thermal_coeff_deg_h_per_c - k1) < 1e-6, est.thermal_coeff_deg_h_per_c
        # eps_z is the drift at T_ref; the constant model's estimate is a mean over the warm-up, not the end.
        assert abs(est.drift_ref_deg_h - (0.002 + k1 * (est.temp_ref_c - T0))) < 2e-5
        assert abs(est.drift_deg_h - end_drift(s, 8.0)) > 1e-4
        d = est.to_dict()
        assert d["model"] == "thermal" and d["thermal_coeff_deg_h_per_c"] == est.thermal_coeff_deg_h_per_c


def test_the_model_follows_the_temperature_column():
    s = warm_up(noise=RLG, seed=4)
    log = scenario_log(s)
    thermal = smooth_log(log, hours=8.0)
    constant = smooth_log(log, hours=8.0, thermal=False)
    assert thermal.model == "thermal" and constant.model == "constant"
    assert math.isnan(constant.thermal_coeff_deg_h_per_c) and math.isnan(constant.temp_range_c)
    # The constant-drift estimate beside the thermal one is the smoother without the thermal state.
    assert thermal.drift_deg_h == pytest.approx(constant.drift_deg_h, abs=1e-3 * constant.drift_std_deg_h)
    assert thermal.drift_std_deg_h == pytest.approx(constant.drift_std_deg_h, rel=1e-3)
    assert constant.navigation_drift_deg_h == constant.drift_deg_h
    # A flat temperature: the thermal state is decoupled and the constant model is reported.
    flat = smooth_log(scenario_log(warm_up(noise=RLG, seed=4, start_c=30.0, end_c=30.0)), hours=8.0)
    assert flat.model == "constant" and flat.temp_range_c == 0.0
    # A threshold above the warm-up: the constant model is reported although the state ran.
    high = smooth_log(log, hours=8.0, options={"thermal_min_range_c": 50.0})
    assert high.model == "constant"
    assert high.navigation_drift_deg_h == pytest.approx(constant.drift_deg_h, abs=1e-3 * constant.drift_std_deg_h)


def test_a_log_without_temperature_uses_the_constant_model_and_thermal_true_is_refused():
    s = warm_up(noise=RLG, seed=5, hours=6.0, rate=2.0)
    chunks = list(scenario_log(s).chunks(10_000_000))
    c = chunks[0]
    cols = {"t_s": c.t_s}
    for i, axis in enumerate("xyz"):
        cols[f"dtheta_{axis}_rad"] = c.dtheta_rad[:, i].copy()
        cols[f"dv_{axis}_m_s"] = c.dv_m_s[:, i].copy()
    log = ImuLog.from_arrays(cols, site={"lat_deg": 40.0, "lon_deg": 0.0, "height_m": 0.0}, require_temperature=False)
    assert not log.has_temperature
    est = smooth_log(log, hours=6.0)
    assert est.model == "constant" and math.isnan(est.thermal_coeff_deg_h_per_c)
    with pytest.raises(LogError, match="temp_c"):
        smooth_log(log, hours=6.0, thermal=True)


def test_end_of_span_z_scores_over_a_few_seeds():
    # 6 seeds, 8 h at 2 Hz: a loose band (30 seeds at full size: docs/identification.md).
    z = []
    for seed in range(6):
        s = warm_up(noise=RLG, seed=300 + seed, rate=2.0, tau_h=2.5)
        est = smooth_log(scenario_log(s), hours=8.0)
        assert est.model == "thermal"
        z.append((est.navigation_drift_deg_h - end_drift(s, 8.0)) / est.navigation_drift_std_deg_h)
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.3 < rms < 2.0, (rms, z)


def test_a_coefficient_prior_reweights_the_end_drift_exactly():
    log = scenario_log(warm_up(noise=RLG, seed=6))
    est = smooth_log(log, hours=8.0)
    # The filter's own prior gives the end drift back; a prior pinning k_z to 0 gives the constant model.
    d, s = est.end_drift_with_coefficient_prior(0.0, est.thermal_prior_std_deg_h_per_c)
    assert d == pytest.approx(est.drift_end_deg_h, abs=1e-12) and s == pytest.approx(est.drift_end_std_deg_h)
    d0, s0 = est.end_drift_with_coefficient_prior(0.0, 1e-9)
    assert d0 == pytest.approx(est.drift_deg_h, abs=1e-3 * est.drift_std_deg_h)
    assert s0 == pytest.approx(est.drift_std_deg_h, rel=1e-3)
    # Pinned at the simulated k1: the end drift of the data's constant at that slope, nearer the truth on average.
    d1, s1 = est.end_drift_with_coefficient_prior(K1, 1e-9)
    assert s1 < est.drift_end_std_deg_h and abs(d1 - end_drift(warm_up(seed=6), 8.0)) < 4 * s1
    with pytest.raises(InputError, match="k_z prior"):
        est.end_drift_with_coefficient_prior(0.0, 0.0)
    # The constant model ignores it.
    flat = smooth_log(log, hours=8.0, thermal=False)
    assert flat.end_drift_with_coefficient_prior(K1, 1e-5) == (flat.drift_deg_h, flat.drift_std_deg_h)


def test_fleet_coefficient_prior_is_the_random_effects_mean():
    est = smooth_log(scenario_log(warm_up(seed=7, hours=6.0, rate=2.0)), hours=6.0)

    def with_k(k, s):
        return replace(est, thermal_coeff_deg_h_per_c=k, thermal_coeff_std_deg_h_per_c=s)

    # Scatter as the sigmas say: no between-unit spread, the pooled mean's own 1-sigma.
    mean, std = fleet_coefficient_prior([with_k(1e-4, 1e-4), with_k(2e-4, 1e-4), with_k(3e-4, 1e-4)])
    assert mean == pytest.approx(2e-4) and std == pytest.approx(1e-4 / math.sqrt(3))
    # Ten times the scatter: tau^2 = (Q - 2) / (sum w - sum w^2 / sum w) adds the unit-to-unit spread.
    mean, std = fleet_coefficient_prior([with_k(0.0, 1e-4), with_k(1e-3, 1e-4), with_k(2e-3, 1e-4)])
    assert mean == pytest.approx(1e-3) and std == pytest.approx(math.sqrt(1e-8 / 3 + (200 - 2) / 2e8))
    with pytest.raises(InputError, match="at least 2"):
        fleet_coefficient_prior([with_k(1e-4, 1e-4), replace(est, model="constant")])
