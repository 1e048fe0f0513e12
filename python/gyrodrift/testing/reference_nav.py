"""A plain per-sample numpy strapdown navigator: the readable reference and independent oracle.

It implements the same interface as `gyrodrift._core.Navigator` (docs/ins-binding-contract.md) one sample
at a time, in the textbook form (Savage; Yan Gongmin's PSINS `insupdate`), so that

* tests can check the Rust navigator against an implementation written independently, and
* benchmarks/bench_navigation.py can measure what the Rust core buys over a straightforward numpy loop.

It is slow (tens of microseconds per sample) and meant for minutes of data, not days.

Frames and conventions
----------------------
Navigation frame n: local-level East-North-Up. Body frame b: Right-Forward-Up. Attitude q = q_b^n (Hamilton,
scalar first), Euler angles with C_b^n = Rz(yaw) Rx(pitch) Ry(roll), yaw counter-clockwise about Up.
Inputs per sample: angle increment dtheta [rad] and velocity increment dv [m/s] in b over dt = 1/rate_hz.
Bias estimates are subtracted (compensated = measured - estimate).

Per-sample update (k-1 -> k), Earth quantities evaluated at the start of the interval
-------------------------------------------------------------------------------------
1. Coning and sculling with the previous sample (two-sample "previous + current" form):
       phi   = dtheta_k + (1/12) dtheta_{k-1} x dtheta_k
       dv_b  = dv_k + 1/2 dtheta_k x dv_k + (1/12) (dtheta_{k-1} x dv_k + dv_{k-1} x dtheta_k)
2. Rates: w_ie^n = w_ie (0, cos L, sin L); w_en^n = (-v_N/(R_M+h), v_E/(R_N+h), v_E tan L/(R_N+h));
   w_in = w_ie + w_en.
3. Velocity: v_k = v_{k-1} + (I - 1/2 [w_in dt x]) C_b^n dv_b + (g^n - (2 w_ie + w_en) x v_{k-1}) dt,
   g^n = (0, 0, -g(L, h)) (WGS-84 normal gravity).
4. Position (trapezoidal velocity): L += v_N,mid dt / (R_M + h), lambda += v_E,mid dt / ((R_N + h) cos L).
   Vertical "fixed": v_U = 0 and h held.
5. Attitude: q_k = q(-w_in dt) o q_{k-1} o q(phi), q(.) the quaternion of a rotation vector; normalised.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from gyrodrift.earth import OMEGA_IE_RAD_S, WGS84_A_M, WGS84_F, normal_gravity

__all__ = ["ReferenceNavigator", "euler_to_quat", "quat_to_euler", "rotvec_to_quat", "quat_mul"]

_E2 = WGS84_F * (2.0 - WGS84_F)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors (np.cross is general but ten times slower on single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def quat_mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product p o q (scalar first)."""
    p0, p1, p2, p3 = p
    q0, q1, q2, q3 = q
    return np.array(
        [
            p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
            p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
            p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
            p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0,
        ]
    )


def rotvec_to_quat(phi: np.ndarray) -> np.ndarray:
    """Quaternion of the rotation vector `phi` [rad]: ``(cos(|phi|/2), phi sin(|phi|/2)/|phi|)``."""
    angle = float(np.linalg.norm(phi))
    if angle < 1e-12:
        return np.array([1.0, 0.5 * phi[0], 0.5 * phi[1], 0.5 * phi[2]])
    s = math.sin(0.5 * angle) / angle
    return np.array([math.cos(0.5 * angle), phi[0] * s, phi[1] * s, phi[2] * s])


def quat_to_dcm(q: np.ndarray) -> np.ndarray:
    """C_b^n of q_b^n."""
    q0, q1, q2, q3 = q
    return np.array(
        [
            [q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)],
            [2 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 - q0 * q1)],
            [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3],
        ]
    )


def euler_to_quat(pitch: float, roll: float, yaw: float) -> np.ndarray:
    """q_b^n = qz(yaw) o qx(pitch) o qy(roll) [rad]."""
    qz = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
    qx = np.array([math.cos(pitch / 2), math.sin(pitch / 2), 0.0, 0.0])
    qy = np.array([math.cos(roll / 2), 0.0, math.sin(roll / 2), 0.0])
    return quat_mul(quat_mul(qz, qx), qy)


def quat_to_euler(q: np.ndarray) -> tuple[float, float, float]:
    """(pitch, roll, yaw) [rad] of q_b^n: pitch = asin(C32), roll = atan2(-C31, C33), yaw = atan2(-C12, C22)."""
    c = quat_to_dcm(q)
    pitch = math.asin(max(-1.0, min(1.0, c[2, 1])))
    roll = math.atan2(-c[2, 0], c[2, 2])
    yaw = math.atan2(-c[0, 1], c[1, 1])
    return pitch, roll, yaw


class ReferenceNavigator:
    """Per-sample numpy strapdown navigator with the interface of `gyrodrift._core.Navigator`.

    Parameters
    ----------
    config : mapping
        SI keys of the binding contract: ``lat_rad``, ``lon_rad``, ``height_m``, ``vel_enu_m_s`` (optional),
        ``pitch_rad``, ``roll_rad``, ``yaw_rad``, ``rate_hz``, ``vertical`` (only ``"fixed"``).
    """

    def __init__(self, config: Mapping[str, Any]):
        vertical = config.get("vertical", "fixed")
        if vertical != "fixed":
            raise ValueError(f"ReferenceNavigator: only vertical='fixed' is implemented, got {vertical!r}")
        self.lat = float(config["lat_rad"])
        self.lon = float(config["lon_rad"])
        self.h = float(config["height_m"])
        self.v = np.array(config.get("vel_enu_m_s", (0.0, 0.0, 0.0)), dtype=float)
        self.v[2] = 0.0
        self.q = euler_to_quat(float(config["pitch_rad"]), float(config["roll_rad"]), float(config["yaw_rad"]))
        self.dt = 1.0 / float(config["rate_hz"])
        self.count = 0
        self.gyro_bias = np.zeros(3)
        self.accel_bias = np.zeros(3)
        self.prev_dtheta = np.zeros(3)
        self.prev_dv = np.zeros(3)

    def set_gyro_bias(self, b_rad_s) -> None:
        """Gyro bias estimate [rad/s], body x y z, subtracted from every following sample."""
        self.gyro_bias = np.array(b_rad_s, dtype=float)

    def set_accel_bias(self, b_m_s2) -> None:
        """Accelerometer bias estimate [m/s^2], body x y z, subtracted from every following sample."""
        self.accel_bias = np.array(b_m_s2, dtype=float)

    def step(self, dtheta: np.ndarray, dv: np.ndarray) -> None:
        """Navigate one sample (raw increments [rad], [m/s] in b)."""
        dt = self.dt
        dtheta = dtheta - self.gyro_bias * dt
        dv = dv - self.accel_bias * dt

        # 1. coning and sculling
        phi = dtheta + cross3(self.prev_dtheta, dtheta) / 12.0
        dv_b = dv + 0.5 * cross3(dtheta, dv) + (cross3(self.prev_dtheta, dv) + cross3(self.prev_dv, dtheta)) / 12.0
        self.prev_dtheta, self.prev_dv = dtheta, dv

        # 2. Earth and transport rates at the start of the interval
        sin_l, cos_l = math.sin(self.lat), math.cos(self.lat)
        d = 1.0 - _E2 * sin_l * sin_l
        r_n = WGS84_A_M / math.sqrt(d) + self.h
        r_m = WGS84_A_M * (1.0 - _E2) / (d * math.sqrt(d)) + self.h
        w_ie = np.array([0.0, OMEGA_IE_RAD_S * cos_l, OMEGA_IE_RAD_S * sin_l])
        w_en = np.array([-self.v[1] / r_m, self.v[0] / r_n, self.v[0] * sin_l / cos_l / r_n])
        w_in = w_ie + w_en
        g_n = np.array([0.0, 0.0, -float(normal_gravity(self.lat, self.h))])

        # 3. velocity
        dv_n = quat_to_dcm(self.q) @ dv_b
        dv_n = dv_n - 0.5 * cross3(w_in * dt, dv_n)
        v_new = self.v + dv_n + (g_n - cross3(2.0 * w_ie + w_en, self.v)) * dt
        v_new[2] = 0.0  # vertical channel fixed

        # 4. position
        v_mid = 0.5 * (self.v + v_new)
        self.lat += v_mid[1] * dt / r_m
        self.lon += v_mid[0] * dt / (r_n * cos_l)
        self.v = v_new

        # 5. attitude
        q = quat_mul(quat_mul(rotvec_to_quat(-w_in * dt), self.q), rotvec_to_quat(phi))
        self.q = q / np.linalg.norm(q)
        self.count += 1

    def state(self) -> dict[str, Any]:
        """Current state, the keys of `_core.Navigator.state` (SI)."""
        pitch, roll, yaw = quat_to_euler(self.q)
        return {
            "t_s": self.count * self.dt,
            "lat_rad": self.lat,
            "lon_rad": self.lon,
            "height_m": self.h,
            "vel_enu_m_s": self.v.tolist(),
            "pitch_rad": pitch,
            "roll_rad": roll,
            "yaw_rad": yaw,
        }

    def process(self, dtheta_rad: np.ndarray, dv_m_s: np.ndarray, decimation: int = 1) -> dict[str, np.ndarray]:
        """Navigate the samples; return the state after every `decimation`-th sample counted from the run start."""
        dtheta_rad = np.asarray(dtheta_rad, dtype=float)
        dv_m_s = np.asarray(dv_m_s, dtype=float)
        if dtheta_rad.shape != dv_m_s.shape or dtheta_rad.ndim != 2 or dtheta_rad.shape[1] != 3:
            raise ValueError(f"dtheta_rad {dtheta_rad.shape} and dv_m_s {dv_m_s.shape} must both be (n, 3)")
        rows = []
        for k in range(len(dtheta_rad)):
            self.step(dtheta_rad[k], dv_m_s[k])
            if self.count % decimation == 0:
                rows.append(self.state())
        keys = ("t_s", "lat_rad", "lon_rad", "height_m", "pitch_rad", "roll_rad", "yaw_rad")
        out = {k: np.array([r[k] for r in rows], dtype=float) for k in keys}
        out["vel_enu_m_s"] = np.array([r["vel_enu_m_s"] for r in rows], dtype=float).reshape(-1, 3)
        return out
