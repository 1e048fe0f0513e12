"""WGS-84 Earth constants and functions, re-exported from the Rust core (gyrodrift-core `earth`), the one place
that owns the Earth's numbers; this module only shapes numpy arrays for it.

Units: SI (m, rad, rad/s). `NMI_M` is the international nautical mile, 1852 m exactly.
"""

import numpy as np

from gyrodrift import _core

WGS84_A_M: float = _core.WGS84_A_M
WGS84_F: float = _core.WGS84_F
OMEGA_IE_RAD_S: float = _core.OMEGA_IE_RAD_S
NMI_M: float = _core.NMI_M

__all__ = ["WGS84_A_M", "WGS84_F", "OMEGA_IE_RAD_S", "NMI_M", "normal_gravity", "radii_of_curvature"]


def normal_gravity(lat_rad, height_m=0.0) -> np.ndarray:
    """Normal gravity magnitude [m/s^2] (WGS-84 Somigliana with height correction).

    `lat_rad` geodetic latitude [rad], `height_m` height above the ellipsoid [m]; both broadcast.
    Gravity points down: the ENU vector is (0, 0, -g).
    """
    lat, h = np.broadcast_arrays(np.asarray(lat_rad, float), np.asarray(height_m, float))
    out = _core.normal_gravity(np.ascontiguousarray(lat.ravel()), np.ascontiguousarray(h.ravel()))
    return out.reshape(lat.shape)


def radii_of_curvature(lat_rad) -> tuple[np.ndarray, np.ndarray]:
    """WGS-84 meridian R_M and prime-vertical R_N radii of curvature [m] at geodetic latitude `lat_rad` [rad]
    (any shape; the core's `earth::meridian_radius`, `earth::transverse_radius`)."""
    lat = np.asarray(lat_rad, dtype=float)
    flat = np.ascontiguousarray(lat.ravel())
    return _core.meridian_radius(flat).reshape(lat.shape), _core.transverse_radius(flat).reshape(lat.shape)
