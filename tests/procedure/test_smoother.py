"""The 16 h smoother (issue 10 item 2) and the labels' uncertainty (item 4), on logs simulated on the fly.

Noise-free logs: the smoother's drift equals the simulated constant within 1e-5 deg/h at 20, 40 and 60 deg with
two rotation schemes. Consistency: z-scores (estimate - simulated drift) / reported sigma over 12 seeds (the
30-seed runs are in benchmarks/bench_smoother.py and docs/studies/2026-11-23-smoother.md: here looser bounds),
with white
noise only and with Gauss-Markov bias instability and rate random walk. The 1-sigma agrees with an independent
numpy covariance analysis of the same error model (scipy's matrix exponential, no data). Labels: the spread of
`truth` over noisy seeds around the noise-free twin's truth matches the reported sigma.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from gyrodrift.errors import CoreError, InputError
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure import align_log, navigate_after_alignment
from gyrodrift.procedure.noise import SensorNoise, estimate_white_noise
from gyrodrift.procedure.smoother import smooth_log
from gyrodrift.procedure.truth import (
    find_true_drift,
    label_budget_deg_h,
    label_sigma_deg_h,
    minimise_linear_criterion,
)

RLG = {"arw_deg_rth": 0.0005, "vrw_ug_rthz": 5.0}


def scenario(lat, drift=0.003, *, noise=None, seed=1, hours=16.0, rate=10.0, scheme="reciprocating", gyro=None):
    noise = noise or {}
    return Scenario.from_dict(
        {
            "site": {"lat_deg": lat},
            "run": {"duration_h": hours, "rate_hz": rate, "seed": seed},
            "rotation": {"scheme": scheme},
            "gyro": {
                "bias_deg_h": [0.004, -0.003, drift],
                "arw_deg_rth": noise.get("arw_deg_rth", 0.0),
                **(gyro or {}),
            },
            "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": noise.get("vrw_ug_rthz", 0.0)},
            "attitude": {"yaw_deg": 30.0, "pitch_deg": 0.1},
        }
    )


@pytest.mark.slow
@pytest.mark.parametrize("scheme", ["reciprocating", "continuous", "indexing"])
def test_noise_free_logs_give_the_simulated_drift_at_three_latitudes(scheme):
    for lat in (20.0, 40.0, 60.0):
        for drift in (0.003, 0.05):
            est = smooth_log(scenario_log(scenario(lat, drift, scheme=scheme)))
            assert abs(est.drift_deg_h - drift) < 1e-5, (scheme, lat, drift, est.drift_deg_h)
            # Linear regime: feedback corrections of milli-arcseconds, centimetres of position error.
            assert est.max_attitude_correction_arcsec < 0.1 and est.max_position_error_m < 0.1
            assert est.noise.source == "log" and est.noise.arw_deg_rth == pytest.approx(1e-5)


def z_scores(n, noise, gyro=None, filter_noise=None):
    z, est, sig = [], [], []
    for seed in range(n):
        log = scenario_log(scenario(40.0, noise=noise, seed=100 + seed, gyro=gyro))
        e = smooth_log(log, noise=filter_noise)
        z.append((e.drift_deg_h - 0.003) / e.drift_std_deg_h)
        est.append(e.drift_deg_h)
        sig.append(e.drift_std_deg_h)
    return np.sqrt(np.mean(np.square(z))), np.std(est), np.mean(sig)


@pytest.mark.slow
def test_white_noise_z_scores_have_unit_rms_and_the_spread_is_the_sigma():
    rms, spread, sigma = z_scores(12, RLG)
    assert 0.6 < rms < 1.5, rms
    assert 0.6 < spread / sigma < 1.5, (spread, sigma)
    # The 12 h inversion's noise at this grade is ~3.7e-4 deg/h (method.md): the 16 h hold more.
    assert sigma < 2.5e-4


@pytest.mark.slow
def test_gauss_markov_and_rate_random_walk_z_scores_with_the_noise_model_told():
    gyro = {"bias_instability_deg_h": 0.002, "correlation_s": 3600.0, "rrw_deg_h_rth": 0.0005}
    told = SensorNoise.from_block({"gyro": {**gyro, "arw_deg_rth": 0.0005}, "accel": {"vrw_ug_rthz": 5.0}})
    rms, _, sigma = z_scores(12, RLG, gyro=gyro, filter_noise=told)
    assert 0.6 < rms < 1.5, rms
    # Not told: the white-noise model is over-confident by far.
    rms_blind, _, _ = z_scores(6, RLG, gyro=gyro)
    assert rms_blind > 2.0, rms_blind


def independent_drift_sigma(lat_deg, noise, span_s=16 * 3600.0, coarse_s=300.0, update_s=10.0, rate_deg_s=6.0):
    """The z-drift 1-sigma from a numpy/scipy covariance recursion of the static-base error model (phi-angle,
    ENU, zero velocity and known position measured every `update_s`), written from docs/identification.md with
    an exact matrix exponential (Van Loan) per interval; continuous table rotation, level body."""
    lat = math.radians(lat_deg)
    w = 7.2921151467e-5
    wn, wu = w * math.cos(lat), w * math.sin(lat)
    a, e2 = 6378137.0, 0.00669437999014
    s2 = math.sin(lat) ** 2
    rm = a * (1 - e2) / (1 - e2 * s2) ** 1.5
    rn = a / math.sqrt(1 - e2 * s2)
    g = 9.7803253359 * (1 + 0.00193185265241 * s2) / math.sqrt(1 - e2 * s2)
    # states: phiE phiN phiU dvE dvN epsX epsY epsZ nabX nabY dN dE  (body level: C = Rz(table angle))
    n = 12
    arw = noise.arw_rad_rts
    vrw = noise.vrw_m_s_rts

    def F(theta):
        c, s = math.cos(theta), math.sin(theta)
        C = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
        f = np.zeros((n, n))
        f[0, 1], f[0, 2], f[1, 0], f[2, 0] = wu, -wn, -wu, wn
        f[0, 4] = -1 / rm
        f[1, 3] = 1 / rn
        f[2, 3] = math.tan(lat) / rn
        f[1, 10], f[2, 10] = -wu / rm, wn / rm
        f[0:3, 5:8] = -C
        f[3, 1], f[4, 0] = -g, g
        f[3, 4], f[4, 3] = 2 * wu, -2 * wu
        f[3:5, 8:10] = C[0:2, 0:2]
        f[10, 4], f[11, 3] = 1.0, 1.0
        return f

    qc = np.diag([arw**2] * 3 + [vrw**2] * 2 + [0.0] * 7)
    sig0 = [300 / 206265, 300 / 206265, 1200 / 206265, 1e-4, 1e-4] + [0.1 * math.pi / 180 / 3600] * 3
    sig0 += [100 * 9.80665e-6] * 2 + [0.01, 0.01]
    p = np.diag(np.square(sig0))
    h = np.zeros((4, n))
    h[0, 3] = h[1, 4] = h[2, 10] = h[3, 11] = 1.0
    r = np.diag([1e-4**2] * 2 + [0.01**2] * 2)
    rate = math.radians(rate_deg_s)

    def transition(theta):
        big = np.zeros((2 * n, 2 * n))
        big[:n, :n], big[:n, n:], big[n:, n:] = -F(theta), qc, F(theta).T
        m = expm(big * update_s)
        phi = m[n:, n:].T
        return phi, phi @ m[:n, n:]

    # The table angle at mid-interval repeats every turn (60 s at 6 deg/s: 6 updates), so each distinct angle's
    # exact transition is computed once (the same matrices as one expm per interval; 6 expm instead of 5730).
    transitions = {}
    t = 0.0
    for _ in range(int(round((span_s - coarse_s) / update_s))):
        theta = math.fmod(rate * (t + update_s / 2), 2 * math.pi)
        key = round(theta, 9)
        if key not in transitions:
            transitions[key] = transition(theta)
        phi, q = transitions[key]
        p = phi @ p @ phi.T + q
        s = h @ p @ h.T + r
        k = p @ h.T @ np.linalg.inv(s)
        p = (np.eye(n) - k @ h) @ p
        p = (p + p.T) / 2
        t += update_s
    return math.sqrt(p[7, 7]) / (math.pi / 180 / 3600)


def test_sigma_agrees_with_an_independent_covariance_analysis():
    for lat in (20.0, 60.0):
        log = scenario_log(scenario(lat, noise=RLG, scheme="continuous"))
        est = smooth_log(log, noise=SensorNoise(**RLG))
        ref = independent_drift_sigma(lat, SensorNoise(**RLG))
        assert est.drift_std_deg_h == pytest.approx(ref, rel=0.01), (lat, est.drift_std_deg_h, ref)


def test_noise_is_measured_from_the_log_and_given_noise_is_checked():
    n = estimate_white_noise(scenario_log(scenario(40.0, noise=RLG, hours=1.5)))
    assert n.arw_deg_rth == pytest.approx(0.0005, rel=0.03) and n.vrw_ug_rthz == pytest.approx(5.0, rel=0.03)
    with pytest.raises(InputError, match="unknown key 'arw'"):
        SensorNoise.from_block({"arw": 1.0})
    with pytest.raises(InputError, match="arw_deg_rth"):
        SensorNoise(arw_deg_rth=-1.0)
    log = scenario_log(scenario(40.0, hours=1.0))
    with pytest.raises(InputError, match="the smoother"):
        smooth_log(log)
    with pytest.raises(CoreError, match="update_s"):
        smooth_log(log, hours=1.0, options={"update_s": 0.05})


@pytest.mark.slow
def test_truth_spread_matches_the_label_sigma_and_the_latitude_law():
    # 40 noisy seeds at 40 deg, 2 Hz: the spread of truth around the noise-free twin's truth. The labels as a
    # campaign makes them (gyrodrift.fleet.science: the nominal drift as the trial, no verification read, the
    # scenario's noise model given): they differ from the verified ones by at most 8e-8 deg/h (0.05 % of the sigma).
    # With the noise model given, the sigma depends on the latitude, the noise and the rotation geometry, not on the
    # seed: one number (measured the same to the bit on seeds 0-2). Seed 0 goes through find_true_drift; every seed's
    # label is its first read (align, navigate z drift 0 and the trial, minimise), the same calls: seed 0's label
    # equals find_true_drift's (to the bit here; asserted to 1e-12). That leaves out, per seed, the label sigma's
    # aligner covariance pass (0.4 s) and the law navigator: 0.46 s of CPU a seed instead of 0.98.
    noise, trial = SensorNoise(**RLG), 0.003

    def label(log):
        al = align_log(log)
        c0, c1 = navigate_after_alignment(log, al, [0.0, trial], 72.0, threads=1).curves
        gn, ge = (c1.north_m - c0.north_m) / trial, (c1.east_m - c0.east_m) / trial
        return minimise_linear_criterion(c0.north_m, c0.east_m, gn, ge, "final")

    def noisy(seed):
        return scenario_log(scenario(40.0, noise=RLG, seed=seed, hours=76.0, rate=2.0))

    twin = label(scenario_log(scenario(40.0, hours=76.0, rate=2.0)))
    t = find_true_drift(noisy(0), trial_deg_h=trial, verify=False, noise=noise)
    assert not t.flagged
    dev = [t.drift_deg_h - twin]
    for seed in range(1, 40):
        dev.append(label(noisy(seed)) - twin)
    assert label(noisy(0)) == pytest.approx(t.drift_deg_h, rel=1e-12)  # the same calls, the same operations
    # Measured 1.03 (mean deviation -0.03 sigma); the ratio's standard error with 40 seeds is about 1/sqrt(80) of it,
    # 0.12. A sigma 1.5 times too large gives 0.69, 1.5 times too small 1.55: both fail.
    ratio = math.sqrt(np.mean(np.square(dev))) / t.drift_std_deg_h
    assert 0.7 < ratio < 1.4, ratio
    # 1 / (sin L cos L) away from 45 deg, and the flag near the equator and the pole.
    noise = SensorNoise(**RLG)
    s45 = label_sigma_deg_h(45.0, noise)[0]
    for lat in (10.0, 80.0):
        law = s45 * 0.5 / (math.sin(math.radians(lat)) * math.cos(math.radians(lat)))
        assert label_sigma_deg_h(lat, noise)[0] == pytest.approx(law, rel=0.2)
    budget = label_budget_deg_h()
    assert label_sigma_deg_h(45.0, noise)[0] < budget < label_sigma_deg_h(5.0, noise)[0]
    assert label_sigma_deg_h(85.0, noise)[0] > budget


def test_features_write_the_smoother_and_the_label_sigma_into_the_run_table(tmp_path):
    from gyrodrift.procedure import extract_features, write_features_csv
    from gyrodrift.runs.table import read_runs_csv

    log = scenario_log(scenario(40.0, noise=RLG, seed=3, hours=76.0, rate=2.0))
    f = extract_features(log, with_truth=True)
    assert abs(f.drift_smoother_deg_h - 0.003) < 4 * f.drift_smoother_std_deg_h
    assert f.drift_std_deg_h == f.truth.drift_std_deg_h and not f.label_flagged
    write_features_csv([f], tmp_path / "runs.csv")
    runs = read_runs_csv(tmp_path / "runs.csv", require_truth=True)
    for name in ("drift_smoother_deg_h", "drift_smoother_std_deg_h", "drift_std_deg_h"):
        assert runs.column(name)[0] == getattr(f, name)
