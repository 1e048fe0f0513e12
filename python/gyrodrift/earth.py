"""WGS-84 Earth constants, re-exported from the Rust core so one module owns the numbers.

Units: SI (m, rad/s). `NMI_M` is the international nautical mile, 1852 m exactly.
"""

import numpy as np

from gyrodrift import _core

WGS84_A_M: float = _core.WGS84_A_M
WGS84_F: float = _core.WGS84_F
OMEGA_IE_RAD_S: float = _core.OMEGA_IE_RAD_S
NMI_M: float = _core.NMI_M


def normal_gravity(lat_rad, height_m=0.0) -> np.ndarray:
    """Normal gravity magnitude [m/s^2] (WGS-84 Somigliana with height correction).

    `lat_rad` geodetic latitude [rad], `height_m` height above the ellipsoid [m]; both broadcast.
    Gravity points down: the ENU vector is (0, 0, -g).
    """
    lat, h = np.broadcast_arrays(np.asarray(lat_rad, float), np.asarray(height_m, float))
    out = _core.normal_gravity(np.ascontiguousarray(lat.ravel()), np.ascontiguousarray(h.ravel()))
    return out.reshape(lat.shape)
