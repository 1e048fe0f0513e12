"""The static site of a run: one `Site` for scenarios, IMU logs and the procedure."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypedDict

from gyrodrift.units import DEG

__all__ = ["Site", "CorePosition"]


class CorePosition(TypedDict):
    """A site as the keywords of the core's configs [rad, rad, m]."""

    lat_rad: float
    lon_rad: float
    height_m: float


@dataclass(frozen=True)
class Site:
    """Static site, WGS-84 geodetic: latitude and longitude [deg], height above the ellipsoid [m].

    The defaults are the site of the paper's experiments (28.222 deg N, 112.99 deg E). A scenario's
    ``[site]`` table and the ``gyrodrift.site`` metadata of an IMU log become one; `gyrodrift.logs.open_log`
    takes one as its ``site`` argument.

    >>> Site(lat_deg=45.0).lat_rad
    0.7853981633974483
    """

    lat_deg: float = 28.222
    lon_deg: float = 112.99
    height_m: float = 0.0

    @property
    def lat_rad(self) -> float:
        """Geodetic latitude [rad]."""
        return self.lat_deg * DEG

    @property
    def lon_rad(self) -> float:
        """Longitude [rad]."""
        return self.lon_deg * DEG

    def core_position(self) -> CorePosition:
        """The site as the core configs' keywords (`_core.NavigatorConfig`, `AlignerConfig`, ...):
        ``lat_rad``, ``lon_rad`` [rad] and ``height_m`` [m]."""
        return CorePosition(lat_rad=self.lat_rad, lon_rad=self.lon_rad, height_m=float(self.height_m))
