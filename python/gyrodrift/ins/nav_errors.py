"""Navigation errors against a known static truth: position in arcsec and nautical miles, attitude in arcsec.

Sign: every error is computed minus true. Horizontal position error: north = dlat R_M(lat_true),
east = dlon R_N(lat_true) cos(lat_true) (WGS-84 radii on the ellipsoid, where the nautical mile is
measured; `radii_of_curvature` is the Rust core's, re-exported from `gyrodrift.earth`),
total = hypot(north, east) / 1852 m.
"""

from __future__ import annotations

import numpy as np

from gyrodrift.earth import NMI_M, radii_of_curvature
from gyrodrift.units import ARCSEC

__all__ = ["radii_of_curvature", "wrap_pi", "position_errors", "attitude_errors_arcsec"]


def wrap_pi(x):
    """Wrap angles [rad] to [-pi, pi)."""
    return (np.asarray(x, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


def position_errors(lat_rad, lon_rad, true_lat_rad, true_lon_rad) -> dict[str, np.ndarray]:
    """Position errors (computed minus true).

    Returns
    -------
    dict
        ``lat_err_arcsec``, ``lon_err_arcsec`` [arcsec], ``north_err_m``, ``east_err_m`` [m] and
        ``pos_err_nmi`` [nmi, 1852 m] (horizontal distance, always >= 0).
    """
    dlat = np.asarray(lat_rad, dtype=float) - true_lat_rad
    dlon = wrap_pi(np.asarray(lon_rad, dtype=float) - true_lon_rad)
    r_m, r_n = radii_of_curvature(true_lat_rad)
    north = dlat * r_m
    east = dlon * r_n * np.cos(true_lat_rad)
    return {
        "lat_err_arcsec": dlat / ARCSEC,
        "lon_err_arcsec": dlon / ARCSEC,
        "north_err_m": north,
        "east_err_m": east,
        "pos_err_nmi": np.hypot(north, east) / NMI_M,
    }


def attitude_errors_arcsec(pitch_rad, roll_rad, yaw_rad, true_pitch_rad, true_roll_rad, true_yaw_rad):
    """Euler-angle differences (computed minus true) [arcsec], yaw wrapped to +-180 deg.

    These are differences of pitch, roll and yaw, not the small-angle misalignment vector phi; for
    small tilts the yaw difference equals the azimuth misalignment.
    """
    return {
        "pitch_err_arcsec": wrap_pi(np.asarray(pitch_rad) - true_pitch_rad) / ARCSEC,
        "roll_err_arcsec": wrap_pi(np.asarray(roll_rad) - true_roll_rad) / ARCSEC,
        "yaw_err_arcsec": wrap_pi(np.asarray(yaw_rad) - true_yaw_rad) / ARCSEC,
    }
