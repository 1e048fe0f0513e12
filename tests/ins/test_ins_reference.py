"""The numpy reference navigator: checked against the closed form, then used as an oracle for the Rust one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift.earth import OMEGA_IE_RAD_S, normal_gravity
from gyrodrift.ins import Scenario, simulate
from gyrodrift.ins.nav_errors import position_errors, radii_of_curvature
from gyrodrift.procedure import navigate
from gyrodrift.testing.reference_nav import ReferenceNavigator, euler_to_quat, quat_to_euler
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H

W = OMEGA_IE_RAD_S


def test_euler_quaternion_round_trip():
    for pitch, roll, yaw in [(0.1, -0.2, 0.3), (-1.2, 2.9, -3.0), (0.0, 0.0, 0.0)]:
        assert quat_to_euler(euler_to_quat(pitch, roll, yaw)) == pytest.approx((pitch, roll, yaw), abs=1e-12)


def test_reference_navigator_axial_drift_closed_form_at_12h():
    """A level static IMU (yaw 0, x east) sensing Earth rate, gravity and eps on z, sampled at 0.1 Hz (constant
    inputs: the 12 h latitude error is 2.6e-4 below the closed form at 0.1 Hz, 8e-5 at 0.5 Hz): latitude error at
    12 h within 1 % of 2 eps cos L / w_ie."""
    lat = 28.222 * DEG
    eps = 0.003 * DEG_PER_H
    rate = 0.1
    dt = 1.0 / rate
    n = int(12 * 3600 * rate)
    dtheta = np.tile([0.0, W * math.cos(lat) * dt, (W * math.sin(lat) + eps) * dt], (n, 1))
    dv = np.tile([0.0, 0.0, float(normal_gravity(lat, 0.0)) * dt], (n, 1))
    nav = ReferenceNavigator(
        {
            "lat_rad": lat,
            "lon_rad": 0.0,
            "height_m": 0.0,
            "pitch_rad": 0.0,
            "roll_rad": 0.0,
            "yaw_rad": 0.0,
            "rate_hz": rate,
        }
    )
    out = nav.process(dtheta, dv, decimation=n)
    lat_err = (out["lat_rad"][-1] - lat) / ARCSEC
    assert lat_err == pytest.approx(2 * eps * math.cos(lat) / W / ARCSEC, rel=0.01)


def test_rust_navigator_agrees_with_the_numpy_reference_over_10_min_at_100hz():
    """Tilted, rotating IMU with large biases and noise, so the position moves by tens of metres and the
    attitude turns through 3600 deg: the two navigators agree to a few millimetres."""
    scn = Scenario.from_dict(
        {
            "run": {"duration_h": 10.0 / 60.0, "rate_hz": 100.0, "seed": 5},
            "rotation": {"scheme": "continuous", "rate_deg_s": 6.0},
            "gyro": {"bias_deg_h": [0.5, -0.3, 0.2], "arw_deg_rth": 0.01},
            "accel": {"bias_ug": [1000.0, -800.0, 300.0], "vrw_ug_rthz": 20.0},
            "attitude": {"pitch_deg": 2.0, "roll_deg": -3.0, "yaw_deg": 30.0},
        }
    )
    imu = simulate(scn)
    rust = navigate(imu, decimation_s=1.0)

    ref = ReferenceNavigator(
        {
            "lat_rad": scn.site.lat_deg * DEG,
            "lon_rad": scn.site.lon_deg * DEG,
            "height_m": scn.site.height_m,
            "pitch_rad": scn.attitude.pitch_deg * DEG,
            "roll_rad": scn.attitude.roll_deg * DEG,
            "yaw_rad": scn.attitude.yaw_deg * DEG,
            "rate_hz": scn.run.rate_hz,
            "vertical": "fixed",
        }
    )
    dtheta = np.column_stack([imu["dtheta_x_rad"], imu["dtheta_y_rad"], imu["dtheta_z_rad"]])
    dv = np.column_stack([imu["dv_x_m_s"], imu["dv_y_m_s"], imu["dv_z_m_s"]])
    out = ref.process(dtheta, dv, decimation=100)

    np.testing.assert_allclose(rust["t_s"], out["t_s"], rtol=0, atol=1e-9)
    # The run really moves: tens of metres of position error by the end.
    moved = position_errors(out["lat_rad"], out["lon_rad"], scn.site.lat_deg * DEG, scn.site.lon_deg * DEG)
    assert np.max(moved["pos_err_nmi"]) * 1852.0 > 50.0
    r_m, r_n = radii_of_curvature(scn.site.lat_deg * DEG)
    north = (np.deg2rad(rust["lat_deg"]) - out["lat_rad"]) * r_m
    east = (np.deg2rad(rust["lon_deg"]) - out["lon_rad"]) * r_n * math.cos(scn.site.lat_deg * DEG)
    gap = np.hypot(north, east)
    print(f"max position gap {gap.max() * 1000:.3f} mm, moved {np.max(moved['pos_err_nmi']) * 1852:.1f} m")
    assert gap.max() < 0.005  # m
    vel = np.column_stack([rust["vel_e_m_s"], rust["vel_n_m_s"], rust["vel_u_m_s"]])
    np.testing.assert_allclose(vel, out["vel_enu_m_s"], rtol=0, atol=1e-5)
    for k in ("pitch", "roll"):
        np.testing.assert_allclose(np.deg2rad(rust[f"{k}_deg"]), out[f"{k}_rad"], rtol=0, atol=0.01 * ARCSEC)
    dyaw = (np.deg2rad(rust["yaw_deg"]) - out["yaw_rad"] + np.pi) % (2 * np.pi) - np.pi
    assert np.max(np.abs(dyaw)) < 0.01 * ARCSEC
