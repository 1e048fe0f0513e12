"""Waypoint routes: a land-vehicle route given by waypoints, turned into the segments of ``[trajectory]``.

The vehicle drives from the site through the waypoints in order, each leg on a rhumb line (constant heading: what
a segment of constant yaw drives on the ellipsoid), at the leg's cruise speed. Around a waypoint it turns at the
stated rate at the speed of the leg it leaves, on the arc of radius r = v / omega tangent to both legs: the turn
starts r tan(abs(delta) / 2) before the waypoint and ends as far after it on the next leg (delta the heading change),
so the vehicle rejoins the next leg's line and passes the waypoint at r (1 / cos(delta / 2) - 1). Speed changes
(at the stated acceleration) follow the turn on the new leg; the route starts from rest (after turning on the spot
to the first leg's heading) and ends braking to a stop on the last waypoint. A waypoint's height is reached by
the climb of its leg's straight segment (gyrodrift-core `trajectory`'s smooth profile).

Geometry: WGS-84 rhumb lines (isometric latitude for the heading, the meridian arc for the length); the turns are
laid out in the local tangent plane, whose error over a turn of length L is about L^2 / R (0.2 m for a 1 km turn).

Frames and signs: headings clockwise from North [rad] internally; the segments' yaw is counter-clockwise about Up
(yaw = -heading), as everywhere in the package.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gyrodrift.earth import radii_of_curvature

__all__ = ["Waypoint", "WaypointError", "rhumb_leg", "waypoint_route"]

_E2 = 6.69437999014e-3
"""WGS-84 first eccentricity squared."""

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(24)


@dataclass(frozen=True)
class Waypoint:
    """One waypoint: position [deg], height [m] (None: keep the previous height) and the leg to it: cruise speed
    ``speed_m_s`` [m/s] or leg time ``leg_s`` [s] (speed = leg length / leg time)."""

    lat_deg: float
    lon_deg: float
    height_m: float | None = None
    speed_m_s: float | None = None
    leg_s: float | None = None


class WaypointError(ValueError):
    """A waypoint route that cannot be driven: ``index`` (0-based waypoint, or None for the whole route), ``key``
    and what is wrong (`gyrodrift.ins.scenario` adds the file)."""

    def __init__(self, index: int | None, key: str | None, message: str):
        super().__init__(message)
        self.index = index
        self.key = key


def _meridian_arc(lat1: float, lat2: float) -> float:
    """Meridian arc length [m] from `lat1` to `lat2` [rad] (signed; 24-point Gauss-Legendre of R_M, exact to
    rounding for arcs of any length up to the latitude limit)."""
    mid, half = 0.5 * (lat1 + lat2), 0.5 * (lat2 - lat1)
    rm, _ = radii_of_curvature(mid + half * _GL_NODES)
    return float(half * np.dot(_GL_WEIGHTS, rm))


def _isometric(lat: float) -> float:
    e = math.sqrt(_E2)
    return math.atanh(math.sin(lat)) - e * math.atanh(e * math.sin(lat))


def rhumb_leg(lat1: float, lon1: float, lat2: float, lon2: float) -> tuple[float, float]:
    """(heading clockwise from North [rad], length [m]) of the WGS-84 rhumb line from (lat1, lon1) to (lat2, lon2)
    [rad], the shorter way in longitude."""
    dlon = (lon2 - lon1 + math.pi) % (2 * math.pi) - math.pi
    dpsi = _isometric(lat2) - _isometric(lat1)
    heading = math.atan2(dlon, dpsi)
    if abs(lat2 - lat1) > 1e-12:
        return heading, abs(_meridian_arc(lat1, lat2) / math.cos(heading))
    _, rn = radii_of_curvature(np.array([lat1]))
    return heading, abs(dlon) * float(rn[0]) * math.cos(lat1)


def _check_climb(index: int, climb: float, duration: float) -> None:
    """Refuse a height change `climb` [m] whose straight of `duration` [s] is too short for the core's limits."""
    from gyrodrift import _core

    w_max, a_max = _core.MAX_VEHICLE_CLIMB_RATE_M_S, _core.MAX_VEHICLE_ACCEL_M_S2
    if (
        duration <= 0
        or abs(climb) * math.pi / (2 * duration) > w_max
        or abs(climb) * math.pi**2 / (2 * duration**2) > a_max
    ):
        raise WaypointError(
            index,
            "height_m",
            f"a climb of {climb:.6g} m on a straight of {duration:.6g} s needs more than {w_max:g} m/s vertical "
            f"speed or {a_max:g} m/s^2 (a longer leg or a lower speed)",
        )


def _wrap(angle: float) -> float:
    """`angle` [rad] in (-pi, pi]."""
    a = (angle + math.pi) % (2 * math.pi) - math.pi
    return math.pi if a == -math.pi else a


def waypoint_route(
    start_deg: tuple[float, float, float],
    yaw0_deg: float,
    waypoints: Sequence[Waypoint],
    *,
    turn_rate_deg_s: float,
    accel_m_s2: float,
    repeat: bool = False,
) -> list[dict[str, float | str]]:
    """The ``[trajectory]`` segments (TOML tables: ``kind``, ``duration_s``, ...) driving from `start_deg`
    (lat [deg], lon [deg], height [m]) with the vehicle's yaw `yaw0_deg` [deg, CCW about Up] through `waypoints`.

    `turn_rate_deg_s` [deg/s, > 0] is the rate of every turn, `accel_m_s2` [m/s^2, > 0] of every speed change.
    With `repeat` the vehicle turns on the spot back to `yaw0_deg` after stopping on the last waypoint, so that the
    repeated segments drive the same figure (a loop should end at the site). Raises `WaypointError` naming the
    waypoint when a leg is too short for its turns and speed changes, or has no length.
    """
    omega = math.radians(turn_rate_deg_s)
    segments: list[dict[str, float | str]] = []

    def turn(angle: float) -> None:  # angle [rad], CCW positive
        if abs(angle) > 1e-12:
            rate = math.copysign(turn_rate_deg_s, angle)
            segments.append({"kind": "turn", "rate_deg_s": rate, "duration_s": math.degrees(angle) / rate})

    def change_speed(v0: float, v1: float) -> None:
        if v1 != v0:
            a = math.copysign(accel_m_s2, v1 - v0)
            segments.append({"kind": "accelerate", "accel_m_s2": a, "duration_s": (v1 - v0) / a})

    lat, lon, height = (math.radians(start_deg[0]), math.radians(start_deg[1]), start_deg[2])
    legs = []
    for i, w in enumerate(waypoints):
        lat2, lon2 = math.radians(w.lat_deg), math.radians(w.lon_deg)
        heading, length = rhumb_leg(lat, lon, lat2, lon2)
        if length < 1e-3:
            raise WaypointError(i, None, "the waypoint is where the previous one is (a leg needs a length)")
        if w.speed_m_s is not None:
            speed = w.speed_m_s
        else:
            assert w.leg_s is not None  # the scenario reader requires one of them
            speed = length / w.leg_s
        h2 = height if w.height_m is None else w.height_m
        legs.append((-heading, length, speed, h2 - height))
        lat, lon, height = lat2, lon2, h2

    yaw = math.radians(yaw0_deg)
    turn(_wrap(legs[0][0] - yaw))
    yaw = legs[0][0]
    v = 0.0
    entry = 0.0  # length of the leg used by the turn into it [m]
    for i, (leg_yaw, length, speed, climb) in enumerate(legs):
        last = i == len(legs) - 1
        delta = 0.0 if last else _wrap(legs[i + 1][0] - leg_yaw)
        exit_len = speed * speed / (2 * accel_m_s2) if last else speed / omega * math.tan(abs(delta) / 2)
        speed_len = abs(speed * speed - v * v) / (2 * accel_m_s2)
        straight = length - entry - speed_len - exit_len
        if straight < 0:
            raise WaypointError(
                i,
                None,
                f"the leg of {length:.6g} m is too short for its turns and speed changes at {speed:.6g} m/s "
                f"(they take {entry + speed_len + exit_len:.6g} m: a lower speed, a higher turn rate or "
                "acceleration, or a longer leg)",
            )
        change_speed(v, speed)
        v = speed
        seg: dict[str, float | str] = {"kind": "straight", "duration_s": straight / speed}
        if climb:
            seg["climb_m"] = climb
        if climb:
            _check_climb(i, climb, straight / speed)
        if straight > 0:
            segments.append(seg)
        if last:
            change_speed(v, 0.0)
            v = 0.0
        else:
            turn(delta)
        entry = exit_len
    if repeat:
        turn(_wrap(math.radians(yaw0_deg) - legs[-1][0]))
    return segments
