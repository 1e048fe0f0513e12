"""The static site of a run: one `Site` for scenarios, IMU logs and the procedure."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Site"]


@dataclass(frozen=True)
class Site:
    """Static site, WGS-84 geodetic: latitude and longitude [deg], height above the ellipsoid [m].

    The defaults are the site of the paper's experiments (28.222 deg N, 112.99 deg E). A scenario's
    ``[site]`` table and the ``gyrodrift.site`` metadata of an IMU log become one; `gyrodrift.logs.open_log`
    takes one as its ``site`` argument.
    """

    lat_deg: float = 28.222
    lon_deg: float = 112.99
    height_m: float = 0.0
