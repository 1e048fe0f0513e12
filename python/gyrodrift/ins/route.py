"""A scenario's moving base: the ``[trajectory]`` table (route segments, or waypoints turned into segments),
validated into `Trajectory`.

docs/scenarios.md documents the keys. Every refusal names the file and the key, e.g.
``vehicle.toml: [trajectory] segments[1]: a stop needs the vehicle at rest, ...``; the error class is the
caller's (`gyrodrift.ins.scenario.ScenarioError`), carried by the `Scope`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from gyrodrift import _core
from gyrodrift.files.toml_schema import Choice, Flag, Number, Scope, show
from gyrodrift.ins.waypoints import Waypoint, WaypointError, waypoint_route

__all__ = ["SEGMENT_KINDS", "WAYPOINT_ROUTE_KEYS", "TRAJECTORY_KEYS", "Segment", "Trajectory", "read_trajectory"]

SEGMENT_KINDS = ("straight", "turn", "accelerate", "stop")
"""The kinds of route segment of ``[trajectory] segments``."""

WAYPOINT_ROUTE_KEYS = ("waypoints", "turn_rate_deg_s", "accel_m_s2")
"""Keys of ``[trajectory]`` for a route given by waypoints (`gyrodrift.ins.waypoints`) instead of segments."""

TRAJECTORY_KEYS = ("static_h", "repeat", "segments", *WAYPOINT_ROUTE_KEYS)
"""The keys of ``[trajectory]``."""

Origin = Callable[[], tuple[tuple[float, float, float], float]]
"""Gives the route's start for waypoints: the site (lat [deg], lon [deg], height [m]) and the initial yaw [deg]."""


@dataclass(frozen=True)
class Segment:
    """One segment of a land-vehicle route, resolved: ``kind`` (one of `SEGMENT_KINDS`), ``duration_s`` [s],
    longitudinal acceleration ``accel_m_s2`` [m/s^2] (accelerate; negative brakes), turn rate
    ``rate_deg_s`` [deg/s] (turn; positive counter-clockwise about Up, i.e. a left turn) and height change
    ``climb_m`` [m] (any kind but stop; a smooth profile starting and ending with zero vertical speed)."""

    kind: str
    duration_s: float
    accel_m_s2: float = 0.0
    rate_deg_s: float = 0.0
    climb_m: float = 0.0

    def to_toml_dict(self) -> dict[str, Any]:
        """The segment as its TOML table (only the keys its kind takes)."""
        out: dict[str, Any] = {"kind": self.kind, "duration_s": self.duration_s}
        if self.kind == "accelerate":
            out["accel_m_s2"] = self.accel_m_s2
        if self.kind == "turn":
            out["rate_deg_s"] = self.rate_deg_s
        if self.climb_m != 0.0:
            out["climb_m"] = self.climb_m
        return out


@dataclass(frozen=True)
class Trajectory:
    """A moving base: the vehicle stands still for ``static_h`` [h] (alignment and identification), then drives
    ``segments`` in order (cycled to the end of the run with ``repeat``). The route starts at the site's height
    and changes it by the segments' ``climb_m`` (the vehicle body stays level); the vehicle's initial yaw is
    ``[attitude] yaw_deg`` and ``[attitude] pitch_deg``/``roll_deg`` are the IMU's mounting tilt on the vehicle.
    After the last segment (without ``repeat``) the vehicle goes on straight at its last speed."""

    static_h: float = 16.0
    repeat: bool = False
    segments: tuple[Segment, ...] = ()

    def to_toml_dict(self) -> dict[str, Any]:
        """The route as its ``[trajectory]`` table (segments, also for a route given by waypoints)."""
        return {
            "static_h": self.static_h,
            "repeat": self.repeat,
            "segments": [seg.to_toml_dict() for seg in self.segments],
        }


SEGMENT_KEYS: dict[str, tuple[str, ...]] = {
    "straight": ("kind", "duration_s", "climb_m"),
    "turn": ("kind", "rate_deg_s", "duration_s", "angle_deg", "climb_m"),
    "accelerate": ("kind", "accel_m_s2", "duration_s", "to_speed_m_s", "climb_m"),
    "stop": ("kind", "duration_s"),
}
"""The keys each kind of segment takes."""

_WAYPOINT_LAT_DEG = _core.MAX_LAT_DEG - 0.01
WAYPOINT_FIELDS = {
    "lat_deg": Number.in_range(-_WAYPOINT_LAT_DEG, _WAYPOINT_LAT_DEG),
    "lon_deg": Number.in_range(-_core.MAX_LON_DEG, _core.MAX_LON_DEG),
    "height_m": Number.in_range(_core.MIN_HEIGHT_M, _core.MAX_HEIGHT_M),
    "speed_m_s": Number.in_range(0.0, _core.MAX_VEHICLE_SPEED_M_S),
    "leg_s": Number.in_range(0.0, _core.MAX_DURATION_S),
}
"""A waypoint's keys (lat_deg, lon_deg required; exactly one of speed_m_s and leg_s)."""

_NUMBER = Number()


def read_trajectory(root: Scope, data: Mapping[str, Any], origin: Origin) -> Trajectory | None:
    """The ``[trajectory]`` table of the scenario mapping `data` (None without one); `origin` is asked for the
    start of a waypoint route (after the waypoints are checked)."""
    if "trajectory" not in data:
        return None
    t = root.table(data, "trajectory", TRAJECTORY_KEYS)
    scope, default = root.section("trajectory"), Trajectory()
    static_h = scope.value(t, "static_h", Number.non_negative(), default.static_h)
    repeat = scope.value(t, "repeat", Flag(), default.repeat)
    if "waypoints" in t:
        if "segments" in t:
            raise scope.fail("waypoints", "give segments or waypoints, not both")
        raw = _waypoint_segments(scope, t, repeat, origin)
    else:
        for k in WAYPOINT_ROUTE_KEYS[1:]:
            if k in t:
                raise scope.fail(k, "only with waypoints")
        raw = t.get("segments", [])
    segments: list[Segment] = []
    speed = 0.0
    for item, g in scope.tables("segments", raw):
        seg = _segment(item, g, speed)
        speed = max(0.0, speed + seg.accel_m_s2 * seg.duration_s)
        if speed < 1e-9:
            speed = 0.0
        segments.append(seg)
    return Trajectory(static_h=static_h, repeat=repeat, segments=tuple(segments))


def _waypoint_segments(scope: Scope, t: Mapping[str, Any], repeat: bool, origin: Origin) -> list[dict[str, Any]]:
    """The segments of a ``waypoints`` route (`gyrodrift.ins.waypoints`), from the site and initial yaw."""
    tables = scope.tables("waypoints", t["waypoints"], non_empty=True)
    rate = scope.value(t, "turn_rate_deg_s", Number.positive(_core.MAX_VEHICLE_YAW_RATE_DEG_S, " deg/s"), 3.0)
    accel = scope.value(t, "accel_m_s2", Number.positive(_core.MAX_VEHICLE_ACCEL_M_S2, " m/s^2"), 2.0)
    points = []
    for item, w in tables:
        item.keys(w, tuple(WAYPOINT_FIELDS))
        item.require(w, ("lat_deg", "lon_deg"))
        item.one_of(w, "speed_m_s", "leg_s")
        p = Waypoint(**item.fields(w, WAYPOINT_FIELDS))
        if (p.speed_m_s is not None and p.speed_m_s <= 0) or (p.leg_s is not None and p.leg_s <= 0):
            raise item.fail(None, "the speed (or leg time) must be > 0")
        points.append(p)
    start, yaw0 = origin()
    try:
        return waypoint_route(start, yaw0, points, turn_rate_deg_s=rate, accel_m_s2=accel, repeat=repeat)
    except WaypointError as exc:
        key = "waypoints" if exc.index is None else f"waypoints[{exc.index}]"
        raise scope.fail(key if exc.key is None else f"{key}.{exc.key}", str(exc)) from None


def _segment(scope: Scope, g: Mapping[str, Any], speed: float) -> Segment:
    """One route segment (`scope` names it in messages), entered at `speed` [m/s]."""
    kind = Choice(SEGMENT_KINDS).read(scope, "kind", g.get("kind"))
    scope.keys(g, SEGMENT_KEYS[kind], what=f" for {'an' if kind == 'accelerate' else 'a'} {kind} segment")
    duration = scope.value(g, "duration_s", _NUMBER, math.nan)
    accel = rate = 0.0
    max_speed = _core.MAX_VEHICLE_SPEED_M_S
    if kind == "turn":
        rate = _nonzero(
            scope, g, "rate_deg_s", "a turn rate with 0 < |rate|", _core.MAX_VEHICLE_YAW_RATE_DEG_S, "deg/s"
        )
        scope.one_of(g, "duration_s", "angle_deg")
        if "angle_deg" in g:
            duration = _turn_duration(scope, g, rate)
    elif kind == "accelerate":
        accel = _nonzero(scope, g, "accel_m_s2", "0 < |accel|", _core.MAX_VEHICLE_ACCEL_M_S2, "m/s^2")
        scope.one_of(g, "duration_s", "to_speed_m_s")
        if "to_speed_m_s" in g:
            duration = _acceleration_duration(scope, g, accel, speed)
    if not (duration > 0 and math.isfinite(duration)):
        raise scope.fail("duration_s", f"expected a duration > 0 s, got {show(g.get('duration_s'))}")
    if kind == "stop" and speed != 0.0:
        raise scope.fail(
            None,
            f"a stop needs the vehicle at rest, it moves at {speed:.6g} m/s "
            "(brake first: an accelerate segment with to_speed_m_s = 0)",
        )
    end = speed + accel * duration
    if not (-1e-9 <= end <= max_speed):
        raise scope.fail(None, f"the speed after this segment, {end:.6g} m/s, is outside [0, {max_speed:.6g}] m/s")
    climb = scope.value(g, "climb_m", _NUMBER, 0.0)
    _check_climb(scope, climb, duration)
    return Segment(kind=kind, duration_s=duration, accel_m_s2=accel, rate_deg_s=rate, climb_m=climb)


def _nonzero(scope: Scope, g: Mapping[str, Any], key: str, what: str, limit: float, unit: str) -> float:
    """The number at `key` (required), with 0 < |value| <= `limit` [`unit`] (``expected <what> <= limit unit, got
    ...`` otherwise)."""
    v = scope.value(g, key, _NUMBER, math.nan)
    if not (0 < abs(v) <= limit):
        raise scope.fail(key, f"expected {what} <= {limit:.6g} {unit}, got {show(g.get(key))}")
    return v


def _turn_duration(scope: Scope, g: Mapping[str, Any], rate: float) -> float:
    """The duration [s] of a turn at `rate` [deg/s] through ``angle_deg`` (non-zero, of the rate's sign)."""
    angle = scope.value(g, "angle_deg", _NUMBER, math.nan)
    if angle == 0 or (angle > 0) != (rate > 0):
        raise scope.fail("angle_deg", f"must be non-zero with the sign of rate_deg_s, got {show(g['angle_deg'])}")
    return angle / rate


def _acceleration_duration(scope: Scope, g: Mapping[str, Any], accel: float, speed: float) -> float:
    """The duration [s] of an acceleration `accel` [m/s^2] from `speed` [m/s] to ``to_speed_m_s``."""
    target = scope.value(g, "to_speed_m_s", _NUMBER, math.nan)
    max_speed = _core.MAX_VEHICLE_SPEED_M_S
    if not (0 <= target <= max_speed) or (target - speed) * accel <= 0:
        raise scope.fail(
            "to_speed_m_s",
            f"cannot reach {show(g['to_speed_m_s'])} m/s from {speed:.6g} m/s at {accel:.6g} m/s^2 "
            f"(speeds within [0, {max_speed:.6g}] m/s)",
        )
    return (target - speed) / accel


def _check_climb(scope: Scope, climb: float, duration: float) -> None:
    """Refuse a climb [m] over `duration` [s] whose smooth profile (gyrodrift-core `trajectory`) needs a vertical
    speed or acceleration beyond the vehicle's limits."""
    w, a = abs(climb) * math.pi / (2 * duration), abs(climb) * math.pi**2 / (2 * duration**2)
    if w > _core.MAX_VEHICLE_CLIMB_RATE_M_S or a > _core.MAX_VEHICLE_ACCEL_M_S2:
        raise scope.fail(
            "climb_m",
            f"a climb of {climb:.6g} m in {duration:.6g} s needs a vertical speed of {w:.3g} m/s and "
            f"acceleration {a:.3g} m/s^2 (at most {_core.MAX_VEHICLE_CLIMB_RATE_M_S:.6g} m/s and "
            f"{_core.MAX_VEHICLE_ACCEL_M_S2:.6g} m/s^2: a longer segment or a smaller climb)",
        )
