"""Options shared by the commands that read IMU logs: the static site (--lat0-deg, --lon0-deg, --height-m)."""

from __future__ import annotations

import click

from gyrodrift.cli.types import FiniteFloat

__all__ = ["site_options", "site_from_options"]


def site_options(f):
    """Add ``--lat0-deg``, ``--lon0-deg`` and ``--height-m`` (finite numbers; latitude strictly within +-90)."""
    f = click.option(
        "--height-m",
        type=FiniteFloat(-1e4, 1e5),
        default=None,
        help="Site height above the ellipsoid [m] (default: the log's, else 0).",
    )(f)
    f = click.option(
        "--lon0-deg",
        type=FiniteFloat(-360.0, 360.0),
        default=None,
        help="Site longitude [deg] (default: the log's, else 0).",
    )(f)
    f = click.option(
        "--lat0-deg",
        type=FiniteFloat(-90.0, 90.0, min_open=True, max_open=True),
        default=None,
        help="True site latitude [deg]; required for logs that carry no site (CSV).",
    )(f)
    return f


def site_from_options(lat0_deg: float | None, lon0_deg: float | None, height_m: float | None) -> dict | None:
    """The ``site`` mapping of `gyrodrift.logs.open_log` from the options given (None when none was)."""
    site = {}
    if lat0_deg is not None:
        site["lat_deg"] = lat0_deg
    if lon0_deg is not None:
        site["lon_deg"] = lon0_deg
    if height_m is not None:
        site["height_m"] = height_m
    return site or None
