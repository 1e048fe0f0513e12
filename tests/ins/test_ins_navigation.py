"""Physics acceptance tests of simulation + navigation through the Python API (issue 4).

Closed forms (static base, ENU, phi-angle error model, constant axial drift eps at latitude L):
    dL(t)   = (eps cos L / w_ie) (1 - cos w_ie t)          (latitude error, largest at ~12 h: 2 eps cos L / w_ie)
    dlon(t) = eps sin L (t - sin(w_ie t) / w_ie)            (longitude error)
    north = dL R_M, east = dlon R_N cos L, position error = hypot(north, east) / 1852 m.
They are computed here from the constants, never pasted.

Long runs go through `navigate(scenario)`, which streams the core simulator into the core navigator chunk by
chunk. Rates: the error-free check runs at 100 Hz as issue 4 asks for the paper's reciprocating table and at 25 Hz
for the other schemes (its margin measured at both, see the test); the others use 10-20 Hz, enough for static-base
dynamics with a 6 deg/s table (the core's coning/sculling terms are exact for a single-axis rate).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from gyrodrift.drift_law import DriftLaw
from gyrodrift.earth import NMI_M, OMEGA_IE_RAD_S
from gyrodrift.ins import Scenario, simulate
from gyrodrift.ins.nav_errors import radii_of_curvature
from gyrodrift.procedure import navigate
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, DEG_PER_SQRT_H, HOUR

LAT_DEG = 28.222
W = OMEGA_IE_RAD_S


def scenario(**sections) -> Scenario:
    """A scenario at the paper's latitude with the given sections (TOML-shaped dicts)."""
    data = {"site": {"lat_deg": LAT_DEG, "lon_deg": 112.99}}
    data.update(sections)
    return Scenario.from_dict(data, source="<test>")


def run_all(cases):
    """Navigate several scenarios on two threads (the core releases the GIL). cases: list of (scn, kwargs)."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = [pool.submit(navigate, scn, **kw) for scn, kw in cases]
        return [f.result() for f in futures]


def closed_form_axial(eps_rad_s: float, lat_rad: float, t_s):
    """(dL, dlon) [rad] and the position error [nmi] of a constant axial drift (see the module docstring)."""
    t = np.asarray(t_s, dtype=float)
    d_lat = eps_rad_s * math.cos(lat_rad) / W * (1.0 - np.cos(W * t))
    d_lon = eps_rad_s * math.sin(lat_rad) * (t - np.sin(W * t) / W)
    r_m, r_n = radii_of_curvature(lat_rad)
    pos = np.hypot(d_lat * r_m, d_lon * r_n * math.cos(lat_rad)) / NMI_M
    return d_lat, d_lon, pos


# --------------------------------------------------------------------------------------------------
# Error-free IMU: the navigator stays put for 72 h with every rotation scheme
# --------------------------------------------------------------------------------------------------

ROTATIONS = {
    "none": {"scheme": "none"},
    "continuous": {"scheme": "continuous", "rate_deg_s": 6.0},
    "reciprocating": {"scheme": "reciprocating", "rate_deg_s": 6.0, "span_deg": 360.0},
    "indexing": {"scheme": "indexing", "rate_deg_s": 6.0, "positions_deg": [0, 180, 90, 270], "dwell_s": 300.0},
}


@pytest.mark.slow
def test_error_free_imu_72h_every_scheme_stays_within_001_nmi():
    # Issue 4's 100 Hz for the paper's scheme (reciprocating); the other schemes at 25 Hz, a quarter of the samples:
    # the turning schemes' error falls as 1/rate^2 (worst scheme 1.35e-3 nmi at 10 Hz, 3.2e-4 at 20, 2.0e-4 at 25,
    # 5.1e-5 at 50, 1.3e-5 at 100; yaw 4.9e-3 arcsec at 25 Hz), so the bound keeps a 50x margin; an axial drift of
    # 1e-5 deg/h (closed form 0.018 nmi) fails it at 25 Hz with every scheme (measured 0.0177 nmi)
    cases = [
        (
            scenario(
                run={"duration_h": 72.0, "rate_hz": 100.0 if name == "reciprocating" else 25.0},
                rotation=rot,
                attitude={"pitch_deg": 0.5, "roll_deg": -0.3, "yaw_deg": 20.0},
            ),
            {"decimation_s": 600.0},
        )
        for name, rot in ROTATIONS.items()
    ]
    results = run_all(cases)
    for name, res in zip(ROTATIONS, results, strict=False):
        s = res.summary
        assert s["hours_navigated"] == pytest.approx(72.0)
        assert len(s["checkpoints"]) == 72, name
        assert s["max_pos_err_nmi"] < 0.01, f"{name}: {s['max_pos_err_nmi']:.2e} nmi"
        # Attitude truth follows the table: yaw error stays small although yaw itself turns.
        assert np.max(np.abs(res["yaw_err_arcsec"])) < 1.0, name


# --------------------------------------------------------------------------------------------------
# Axial drift alone: closed forms, with and without rotation
# --------------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["none", "reciprocating"])
def test_axial_drift_matches_the_closed_form(rotation):
    eps = 0.003 * DEG_PER_H
    lat = LAT_DEG * DEG
    scn = scenario(
        run={"duration_h": 72.0, "rate_hz": 10.0}, rotation=ROTATIONS[rotation], gyro={"bias_deg_h": [0.0, 0.0, 0.003]}
    )
    res = navigate(scn, decimation_s=600.0)

    # Latitude error at 12 h within 1 % of 2 eps cos L / w_ie.
    peak = 2.0 * eps * math.cos(lat) / W / ARCSEC
    lat12 = res.checkpoint(12)["lat_err_arcsec"]
    assert lat12 == pytest.approx(peak, rel=0.01), f"{lat12:.3f} vs {peak:.3f} arcsec"
    assert lat12 > 0  # a positive axial drift raises the latitude (computed minus true)

    # Position error at 72 h within 2 % of the closed form.
    _, _, pos72 = closed_form_axial(eps, lat, 72 * HOUR)
    got = res.checkpoint(72)["pos_err_nmi"]
    assert got == pytest.approx(float(pos72), rel=0.02), f"{got:.4f} vs {float(pos72):.4f} nmi"

    # The whole hourly history follows the closed form (latitude to 1 arcsec, position to 2 %).
    t = np.array([c["t_h"] for c in res.summary["checkpoints"]]) * HOUR
    d_lat, _, pos = closed_form_axial(eps, lat, t)
    lat_err = np.array([c["lat_err_arcsec"] for c in res.summary["checkpoints"]])
    pos_err = np.array([c["pos_err_nmi"] for c in res.summary["checkpoints"]])
    np.testing.assert_allclose(lat_err, d_lat / ARCSEC, atol=1.0)
    np.testing.assert_allclose(pos_err[5:], pos[5:], rtol=0.02)


@pytest.mark.slow
def test_compensating_the_axial_drift_removes_it_and_the_sign_is_measured_minus_estimate():
    scn = scenario(
        run={"duration_h": 13.0, "rate_hz": 10.0},
        rotation=ROTATIONS["reciprocating"],
        gyro={"bias_deg_h": [0.0, 0.0, 0.003]},
    )
    good, wrong = run_all(
        [
            (scn, {"drift_law": DriftLaw.constant(0.003), "decimation_s": 600.0}),
            (scn, {"drift_law": DriftLaw.constant(-0.003), "decimation_s": 600.0}),
        ]
    )
    peak = 2.0 * 0.003 * DEG_PER_H * math.cos(LAT_DEG * DEG) / W / ARCSEC
    assert abs(good.checkpoint(12)["lat_err_arcsec"]) < 0.01 * peak
    assert good.summary["max_pos_err_nmi"] < 0.01
    # Adding the drift instead of removing it doubles the error.
    assert wrong.checkpoint(12)["lat_err_arcsec"] == pytest.approx(2.0 * peak, rel=0.01)
    assert good.summary["compensate_drift_deg_h"] == 0.003


# --------------------------------------------------------------------------------------------------
# Horizontal sensor errors are modulated away by rotation
# --------------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_horizontal_errors_rotation_cancels_them():
    """0.01 deg/h x/y gyro biases + 50 ug x/y accelerometer biases, 72 h.

    Reciprocating rotation turns round at the same table angle (0 = 360 deg) at both ends of its sweep; each
    move of `span` at rate w takes span/w + T_r (T_r = 2 w / accel, the cycloidal ramp time), so the table
    spends an extra T_r per move near angle 0 and a fraction f = T_r / (span/w + T_r) of the horizontal errors
    is left unmodulated: the error is f times the error without rotation. With a 100 deg/s^2 turntable
    f = 0.2 % (< 0.1 nmi); with 10 deg/s^2 f = 2 % (about 0.7 nmi).
    """
    errors = {"gyro": {"bias_deg_h": [0.01, 0.01, 0.0]}, "accel": {"bias_ug": [50.0, 50.0, 0.0]}}
    run72 = {"duration_h": 72.0, "rate_hz": 10.0}
    fast = {"scheme": "reciprocating", "rate_deg_s": 6.0, "span_deg": 360.0, "accel_deg_s2": 100.0}
    slow = dict(fast, accel_deg_s2=10.0)
    cases = [
        (scenario(run=run72, rotation=ROTATIONS["none"], **errors), {"decimation_s": 60.0}),
        (scenario(run=dict(run72, rate_hz=20.0), rotation=fast, **errors), {"decimation_s": 60.0}),
        (scenario(run=run72, rotation=slow, **errors), {"decimation_s": 60.0}),
        (scenario(run=run72, rotation=ROTATIONS["indexing"], **errors), {"decimation_s": 60.0}),
    ]
    static, recip_fast, recip_slow, index = run_all(cases)
    e_static = static.checkpoint(72)["pos_err_nmi"]
    assert 20.0 < e_static < 50.0, f"no rotation: {e_static:.2f} nmi (expected about 34)"
    assert recip_fast.summary["max_pos_err_nmi"] < 0.1, recip_fast.summary["max_pos_err_nmi"]
    assert index.summary["max_pos_err_nmi"] < 0.3, index.summary["max_pos_err_nmi"]
    for rot, res in ((fast, recip_fast), (slow, recip_slow)):
        w = rot["rate_deg_s"]
        t_ramp = 2.0 * w / rot["accel_deg_s2"]
        f = t_ramp / (rot["span_deg"] / w + t_ramp)
        assert res.checkpoint(72)["pos_err_nmi"] == pytest.approx(f * e_static, rel=0.1), rot


# --------------------------------------------------------------------------------------------------
# z scale-factor error: unidirectional rotation makes axial drift, reversal does not
# --------------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_z_scale_factor_error_is_axial_drift_only_under_unidirectional_rotation():
    ppm, rate_deg_s = 5.0, 6.0
    extra_deg_h = ppm * 1e-6 * rate_deg_s * 3600.0  # 0.108 deg/h
    base = {"run": {"duration_h": 13.0, "rate_hz": 10.0}}
    cases = [
        (
            scenario(
                rotation={"scheme": "continuous", "rate_deg_s": rate_deg_s}, gyro={"scale_ppm": [0, 0, ppm]}, **base
            ),
            {"decimation_s": 600.0},
        ),
        (
            scenario(rotation={"scheme": "none"}, gyro={"bias_deg_h": [0, 0, extra_deg_h]}, **base),
            {"decimation_s": 600.0},
        ),
        (
            scenario(
                rotation={"scheme": "reciprocating", "rate_deg_s": rate_deg_s}, gyro={"scale_ppm": [0, 0, ppm]}, **base
            ),
            {"decimation_s": 600.0},
        ),
    ]
    uni, equivalent, recip = run_all(cases)
    lat_uni = uni.checkpoint(12)["lat_err_arcsec"]
    lat_eq = equivalent.checkpoint(12)["lat_err_arcsec"]
    peak = 2.0 * extra_deg_h * DEG_PER_H * math.cos(LAT_DEG * DEG) / W / ARCSEC
    # Continuous rotation + scale error behaves as an axial drift of scale x rate ...
    assert lat_uni == pytest.approx(lat_eq, rel=0.01)
    assert lat_uni == pytest.approx(peak, rel=0.05)
    # ... a reversing scheme leaves only a bounded sawtooth (< 1 % of it).
    assert abs(recip.checkpoint(12)["lat_err_arcsec"]) < 0.01 * abs(lat_uni)
    assert recip.summary["max_pos_err_nmi"] < 0.01 * uni.summary["max_pos_err_nmi"]


# --------------------------------------------------------------------------------------------------
# Noise models, through the simulate output
# --------------------------------------------------------------------------------------------------


def _earth_rate_body(lat_rad):
    """Body-frame Earth rate [rad/s] for a level IMU with yaw 0 and no rotation (x east, y north, z up)."""
    return np.array([0.0, W * math.cos(lat_rad), W * math.sin(lat_rad)])


def test_angle_random_walk_grows_as_sqrt_t_across_seeds():
    arw = 0.01  # deg/sqrt(h), large so the walk dominates float round-off
    rate, seeds = 10.0, 32
    lat = LAT_DEG * DEG
    walks, first = [], None
    for seed in range(seeds):
        imu = simulate(
            scenario(
                run={"duration_h": 1.0, "rate_hz": rate, "seed": seed},
                rotation={"scheme": "none"},
                gyro={"arw_deg_rth": arw},
            )
        )
        first = imu["dtheta_x_rad"] if first is None else first
        truth = _earth_rate_body(lat)
        t = imu["t_s"]
        for axis, name in enumerate(("dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad")):
            walks.append(np.cumsum(imu[name]) - truth[axis] * t)
    walks = np.array(walks)
    i900, i3600 = int(900 * rate) - 1, int(3600 * rate) - 1
    std900, std3600 = walks[:, i900].std(), walks[:, i3600].std()
    n = arw * DEG_PER_SQRT_H
    assert std900 == pytest.approx(n * math.sqrt(900.0), rel=0.25)
    assert std3600 == pytest.approx(n * math.sqrt(3600.0), rel=0.25)
    assert std3600 / std900 == pytest.approx(2.0, rel=0.2)
    # Different seeds give different walks, the same seed the same one to the bit.
    again = simulate(
        scenario(
            run={"duration_h": 1.0, "rate_hz": rate, "seed": 0}, rotation={"scheme": "none"}, gyro={"arw_deg_rth": arw}
        )
    )
    np.testing.assert_array_equal(again["dtheta_x_rad"], first)
    assert not np.array_equal(walks[0], walks[3])  # seed 0 vs seed 1, same axis


def test_gauss_markov_variance_does_not_depend_on_the_sample_rate():
    sigma_deg_h, tau_s = 0.05, 20.0
    lat = LAT_DEG * DEG
    variances = {}
    for rate in (10.0, 100.0):
        samples = []
        for seed in range(4):
            imu = simulate(
                scenario(
                    run={"duration_h": 4000.0 / HOUR, "rate_hz": rate, "seed": seed},
                    rotation={"scheme": "none"},
                    gyro={"bias_instability_deg_h": sigma_deg_h, "correlation_s": tau_s},
                )
            )
            truth = _earth_rate_body(lat)
            for axis, name in enumerate(("dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad")):
                samples.append(imu[name] * rate - truth[axis])  # the bias [rad/s], sample by sample
        variances[rate] = float(np.mean(np.concatenate(samples) ** 2))
    expected = (sigma_deg_h * DEG_PER_H) ** 2
    assert variances[10.0] == pytest.approx(expected, rel=0.15)
    assert variances[100.0] == pytest.approx(expected, rel=0.15)
    assert variances[100.0] / variances[10.0] == pytest.approx(1.0, rel=0.15)
