"""Waypoint routes in ``[trajectory]``: rhumb legs, turns tangent to the legs, speed changes, heights, and the
errors naming the file, key and waypoint."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift.earth import radii_of_curvature
from gyrodrift.ins import Scenario
from gyrodrift.ins.scenario import ScenarioError
from gyrodrift.ins.track import ReferenceTrack
from gyrodrift.ins.waypoints import rhumb_leg

SITE = {"lat_deg": 28.222, "lon_deg": 112.99, "height_m": 50.0}
WAYPOINTS = [
    {"lat_deg": 28.25, "lon_deg": 112.99, "speed_m_s": 20.0},
    {"lat_deg": 28.25, "lon_deg": 113.03, "speed_m_s": 15.0, "height_m": 80.0},
    {"lat_deg": 28.222, "lon_deg": 112.99, "leg_s": 400.0},
]


def route(waypoints=WAYPOINTS, **trajectory) -> Scenario:
    return Scenario.from_dict(
        {
            "site": SITE,
            "run": {"duration_h": 0.6, "rate_hz": 10.0},
            "attitude": {"yaw_deg": 10.0},
            "trajectory": {"static_h": 0.01, "turn_rate_deg_s": 3.0, "accel_m_s2": 2.0, "waypoints": waypoints}
            | trajectory,
        },
        source="wp.toml",
    )


def _offset_m(lat, lon, lat0, lon0):
    """(north, east) [m] of (lat, lon) from (lat0, lon0) [rad] in the local tangent plane."""
    rm, rn = radii_of_curvature(np.array([lat0]))
    return (lat - lat0) * rm[0], (lon - lon0) * rn[0] * math.cos(lat0)


def test_rhumb_legs_along_a_meridian_and_the_equator():
    # Along a meridian the rhumb line is the meridian: heading 0 and the meridian arc (Simpson, independent).
    lat1, lat2 = math.radians(10.0), math.radians(11.0)
    x = np.linspace(lat1, lat2, 2001)
    rm, _ = radii_of_curvature(x)
    w = np.ones_like(x)
    w[1:-1:2], w[2:-1:2] = 4, 2
    arc = float(np.dot(w, rm)) * (x[1] - x[0]) / 3
    heading, length = rhumb_leg(lat1, 0.3, lat2, 0.3)
    assert heading == 0.0 and length == pytest.approx(arc, abs=1e-6)
    # Along the equator: west, a * dlon.
    heading, length = rhumb_leg(0.0, 0.01, 0.0, 0.0)
    assert heading == pytest.approx(-math.pi / 2) and length == pytest.approx(6378137.0 * 0.01, rel=1e-12)
    # A short diagonal leg (640 m): heading and length as in the plane at its middle latitude (to ~(L / R)^2).
    heading, length = rhumb_leg(0.5, 2.0, 0.5 + 1e-4, 2.0 + 1e-4)
    rm, rn = radii_of_curvature(np.array([0.5 + 0.5e-4]))
    north, east = 1e-4 * rm[0], 1e-4 * rn[0] * math.cos(0.5 + 0.5e-4)
    assert heading == pytest.approx(math.atan2(east, north), abs=1e-8)
    assert length == pytest.approx(math.hypot(north, east), rel=1e-8)


def test_waypoint_route_reaches_its_waypoints():
    """The simulated route (the core's, at 1 Hz, interpolated) passes each corner waypoint at the distance of a
    turn tangent to both legs, r (1 / cos(delta / 2) - 1) with r = v / omega, stops on the last waypoint, and has
    the waypoints' heights. Tolerance 0.5 m: the turns are laid out in the local plane (error ~ L^2 / R, 0.2 m for
    a 1.3 km turn); measured 1.5 cm at the stop and below 1 cm at the corners."""
    s = route()
    assert Scenario.from_dict(s.to_toml_dict()) == s  # resolved as segments
    kinds = [g.kind for g in s.trajectory.segments]
    assert kinds[:3] == ["turn", "accelerate", "straight"] and kinds[-1] == "accelerate"
    track = ReferenceTrack.from_scenario(s)
    t = np.arange(0.0, track.t_s[-1], 0.05)
    lat, lon, h = track.at(t)
    points = [(math.radians(SITE["lat_deg"]), math.radians(SITE["lon_deg"]))] + [
        (math.radians(w["lat_deg"]), math.radians(w["lon_deg"])) for w in WAYPOINTS
    ]
    headings = [rhumb_leg(*points[i], *points[i + 1])[0] for i in range(3)]
    omega = math.radians(3.0)
    for i, speed in ((0, 20.0), (1, 15.0)):
        delta = abs((headings[i + 1] - headings[i] + math.pi) % (2 * math.pi) - math.pi)
        expected = speed / omega * (1 / math.cos(delta / 2) - 1)
        north, east = _offset_m(lat, lon, *points[i + 1])
        closest = np.argmin(np.hypot(north, east))
        assert np.hypot(north, east)[closest] == pytest.approx(expected, abs=0.5), i
        assert h[closest] == pytest.approx([50.0, 80.0][i], abs=1e-6)
    north, east = _offset_m(lat[-1], lon[-1], *points[3])
    assert math.hypot(north, east) < 0.5
    assert h[-1] == pytest.approx(80.0)  # the last waypoint keeps the previous height
    v = track.vel_enu_m_s
    assert v is not None and np.max(np.abs(v[-60:])) == 0.0  # at rest on the last waypoint


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"segments": []}, "wp.toml: [trajectory] waypoints: give segments or waypoints, not both"),
        ({"waypoints": []}, "[trajectory] waypoints: expected a non-empty array of tables"),
        ({"waypoints": [{"lon_deg": 1.0, "speed_m_s": 1.0}]}, "[trajectory] waypoints[0]: missing lat_deg"),
        (
            {"waypoints": [{"lat_deg": 28.3, "lon_deg": 112.99}]},
            "[trajectory] waypoints[0]: give exactly one of speed_m_s and leg_s",
        ),
        (
            {"waypoints": [{"lat_deg": 95.0, "lon_deg": 112.99, "speed_m_s": 5.0}]},
            "[trajectory] waypoints[0].lat_deg: must be between",
        ),
        (
            {"waypoints": [{"lat_deg": 28.3, "lon_deg": 112.99, "speed_m_s": 200.0}]},
            "[trajectory] waypoints[0].speed_m_s: must be between 0 and 100",
        ),
        (
            {"waypoints": [{"lat_deg": 28.3, "lon_deg": 112.99, "speed_m_s": 5.0, "fly": 1}]},
            "[trajectory] waypoints[0].fly: unknown key",
        ),
        (
            {"waypoints": [WAYPOINTS[0], {"lat_deg": 28.2503, "lon_deg": 112.99, "speed_m_s": 20.0}]},
            "[trajectory] waypoints[1]: the leg of 33.2",
        ),
        (
            {"waypoints": [{"lat_deg": 28.223, "lon_deg": 112.99, "speed_m_s": 5.0, "height_m": 5000.0}]},
            "[trajectory] waypoints[0].height_m: a climb of 4950 m on a straight of",
        ),
        ({"turn_rate_deg_s": 0.0}, "[trajectory] turn_rate_deg_s: must be > 0"),
    ],
)
def test_bad_waypoint_routes_name_the_file_key_and_waypoint(change, message):
    kw = {k: v for k, v in change.items() if k != "waypoints"}
    with pytest.raises(ScenarioError) as info:
        route(change.get("waypoints", WAYPOINTS), **kw)
    assert message in str(info.value)
    with pytest.raises(ScenarioError, match=r"\[trajectory\] accel_m_s2: only with waypoints"):
        Scenario.from_dict({"trajectory": {"accel_m_s2": 1.0, "segments": []}}, source="wp.toml")


def test_a_repeated_waypoint_route_past_the_latitude_limit_names_the_waypoints():
    with pytest.raises(ScenarioError) as info:
        Scenario.from_dict(
            {
                "site": {"lat_deg": 88.0},
                "trajectory": {"static_h": 0.0, "repeat": True, "waypoints": [WAYPOINTS[0] | {"lat_deg": 88.5}]},
            },
            source="wp.toml",
        )
    assert str(info.value).startswith("wp.toml: [trajectory] waypoints: the route reaches latitude 88.99")
