"""Moving base (issue 13): the ``[trajectory]`` section, the simulated route and its truth columns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift import _core
from gyrodrift.earth import radii_of_curvature
from gyrodrift.ins import Scenario, load_scenario, simulate
from gyrodrift.ins.scenario import DRIVE_H, ScenarioError

ROUTE = [
    {"kind": "accelerate", "accel_m_s2": 2.0, "to_speed_m_s": 20.0},
    {"kind": "straight", "duration_s": 120.0},
    {"kind": "turn", "rate_deg_s": 3.0, "angle_deg": 90.0},
    {"kind": "straight", "duration_s": 60.0},
    {"kind": "turn", "rate_deg_s": -6.0, "duration_s": 30.0},
    {"kind": "accelerate", "accel_m_s2": -2.5, "to_speed_m_s": 0.0},
    {"kind": "stop", "duration_s": 20.0},
]


def vehicle(**run) -> Scenario:
    return Scenario.from_dict(
        {
            "run": {"rate_hz": 100.0, **run},
            "rotation": {"scheme": "reciprocating"},
            "attitude": {"yaw_deg": 25.0},
            "trajectory": {"static_h": 0.01, "repeat": True, "segments": ROUTE},
        },
        source="vehicle.toml",
    )


def test_trajectory_section_resolves_and_round_trips():
    s = vehicle(duration_h=0.2)
    tr = s.trajectory
    assert [g.kind for g in tr.segments] == [g["kind"] for g in ROUTE]
    assert tr.segments[0].duration_s == pytest.approx(10.0)  # 20 m/s at 2 m/s^2
    assert tr.segments[2].duration_s == pytest.approx(30.0)  # 90 deg at 3 deg/s
    assert tr.segments[5].duration_s == pytest.approx(8.0)  # 20 m/s down at 2.5 m/s^2
    assert Scenario.from_dict(s.to_toml_dict()) == s
    cfg = s.to_core_config()
    assert cfg.trajectory_start_s == pytest.approx(36.0) and cfg.trajectory_repeat
    # Without [run] duration_h the run is the static period plus the 72 h drive.
    assert Scenario.from_dict({"trajectory": {}}).run.duration_h == 16.0 + DRIVE_H
    assert Scenario.from_dict({}).trajectory is None


@pytest.mark.parametrize(
    ("trajectory", "message"),
    [
        ({"static_h": -1}, "[trajectory] static_h: must be >= 0"),
        ({"repeat": "yes"}, "[trajectory] repeat: expected true or false"),
        ({"segments": {"kind": "stop"}}, "[trajectory] segments: expected an array of tables"),
        ({"segments": [{"kind": "fly"}]}, "[trajectory] segments[0].kind: expected one of"),
        ({"segments": [{"kind": "straight"}]}, "[trajectory] segments[0].duration_s: expected a duration > 0 s"),
        ({"segments": [{"kind": "straight", "duration_s": 5, "speed": 3}]}, "segments[0].speed: unknown key"),
        (
            {"segments": [{"kind": "turn", "rate_deg_s": 90, "duration_s": 1}]},
            "segments[0].rate_deg_s: expected a turn",
        ),
        ({"segments": [{"kind": "turn", "rate_deg_s": 3}]}, "exactly one of duration_s and angle_deg"),
        ({"segments": [{"kind": "turn", "rate_deg_s": 3, "angle_deg": -90}]}, "with the sign of rate_deg_s"),
        ({"segments": [{"kind": "accelerate", "accel_m_s2": 20, "duration_s": 1}]}, "segments[0].accel_m_s2"),
        ({"segments": [{"kind": "accelerate", "accel_m_s2": -1, "to_speed_m_s": 5}]}, "cannot reach 5 m/s"),
        ({"segments": [{"kind": "accelerate", "accel_m_s2": 1, "duration_s": 200}]}, "outside [0, 100] m/s"),
        (
            {
                "segments": [
                    {"kind": "accelerate", "accel_m_s2": 1, "to_speed_m_s": 5},
                    {"kind": "stop", "duration_s": 9},
                ]
            },
            "segments[1]: a stop needs the vehicle at rest",
        ),
        # A repeated route that gains speed every cycle: the core refuses it when it passes 100 m/s.
        (
            {"repeat": True, "segments": [{"kind": "accelerate", "accel_m_s2": 1, "to_speed_m_s": 30}]},
            "[trajectory] segments: segment 1 ends at speed",
        ),
    ],
)
def test_bad_trajectories_name_the_file_and_key(trajectory, message):
    with pytest.raises(ScenarioError) as exc:
        Scenario.from_dict({"trajectory": trajectory}, source="vehicle.toml")
    assert str(exc.value).startswith("vehicle.toml: [trajectory]")
    assert message in str(exc.value)


def test_a_route_that_would_pass_the_latitude_limit_is_refused(tmp_path):
    path = tmp_path / "north.toml"
    path.write_text(
        '[site]\nlat_deg = 88.5\n[trajectory]\nstatic_h = 0\nsegments = [{kind = "accelerate", accel_m_s2 = 1, '
        "to_speed_m_s = 30}]\n"
    )
    with pytest.raises(ScenarioError, match=r"north.toml: \[trajectory\] segments: the route reaches latitude"):
        load_scenario(path)


def test_truth_columns_follow_the_route():
    s = vehicle(duration_h=0.1)
    imu = simulate(s)
    t = imu["t_s"]
    speed = np.hypot(imu["true_vel_e_m_s"], imu["true_vel_n_m_s"])
    assert np.all(speed[t <= 36.0] == 0.0) and np.all(imu["true_lat_deg"][t <= 36.0] == s.site.lat_deg)
    cruise = (t > 46.01) & (t < 165.99)
    np.testing.assert_allclose(speed[cruise], 20.0, rtol=0, atol=1e-9)
    # Heading during the first straight: yaw 25 deg CCW from North, so the vehicle moves north-west.
    np.testing.assert_allclose(
        np.degrees(np.arctan2(-imu["true_vel_e_m_s"][cruise], imu["true_vel_n_m_s"][cruise])), 25.0, atol=1e-9
    )
    # The position is the integral of the velocity (trapezoid on the 100 Hz samples: mm over the run).
    lat = np.radians(imu["true_lat_deg"])
    rm, rn = radii_of_curvature(lat)
    h = s.site.height_m
    dt = 1.0 / s.run.rate_hz
    dlat = np.cumsum(0.5 * dt * (imu["true_vel_n_m_s"][1:] + imu["true_vel_n_m_s"][:-1]) / (rm[1:] + h))
    north_err_m = (lat[1:] - lat[0] - dlat) * rm[1:]
    assert np.max(np.abs(north_err_m)) < 1e-3
    # The IMU yaw is the vehicle's plus the table angle (level mounting).
    veh_yaw = np.degrees(np.unwrap(np.radians(imu["true_yaw_deg"]))) - imu["table_angle_deg"]
    wrapped = (veh_yaw - veh_yaw[0] + 180.0) % 360.0 - 180.0
    assert abs(veh_yaw[0] - 25.0) < 1e-9
    turned = wrapped[np.searchsorted(t, 196.0)]
    assert turned == pytest.approx(90.0, abs=1e-6)


def test_error_free_imu_navigates_the_route():
    """The same drive navigated by the core from the true start: metres of error at most after 2 h with turns,
    stops and a reciprocating table (the 72 h case: crates/gyrodrift-core/tests/vehicle.rs, ignored test)."""
    s = vehicle(duration_h=2.0)
    nav = _core.Navigator(
        _core.NavigatorConfig(
            lat_rad=math.radians(s.site.lat_deg),
            lon_rad=math.radians(s.site.lon_deg),
            height_m=s.site.height_m,
            pitch_rad=0.0,
            roll_rad=0.0,
            yaw_rad=math.radians(25.0),
            rate_hz=100.0,
        )
    )
    sim = _core.ImuSimulator(s.to_core_config())
    worst = 0.0
    while (chunk := sim.next_chunk(200_000)) is not None:
        out = nav.process(chunk["dtheta_rad"], chunk["dv_m_s"], 100)
        idx = np.round(np.asarray(out["t_s"]) * 100).astype(int) - (sim.samples_done - len(chunk["t_s"])) - 1
        lat_t, lon_t = chunk["lat_rad"][idx], chunk["lon_rad"][idx]
        rm, rn = radii_of_curvature(lat_t)
        north = (np.asarray(out["lat_rad"]) - lat_t) * rm
        east = (np.asarray(out["lon_rad"]) - lon_t) * rn * np.cos(lat_t)
        worst = max(worst, float(np.max(np.hypot(north, east))))
    assert worst < 0.5, worst


def test_navigate_reports_errors_against_the_route(tmp_path):
    """navigate of a moving-base scenario, its in-memory run and its imu.parquet: errors against the route (an
    error-free IMU: metres), not against the static site the vehicle has left (kilometres)."""
    from gyrodrift.ins.track import ReferenceTrack
    from gyrodrift.procedure import navigate

    s = vehicle(duration_h=0.5)
    on_the_fly = navigate(s)
    assert on_the_fly.summary["reference"] == "<route>"
    assert on_the_fly.summary["max_pos_err_nmi"] < 1e-3
    path = simulate(s, out_dir=tmp_path / "run")
    from_file = navigate(path)
    assert from_file.summary["max_pos_err_nmi"] == pytest.approx(on_the_fly.summary["max_pos_err_nmi"], abs=1e-9)
    # The same navigation against the static site: the vehicle drove away from it.
    static = navigate(
        s,
        reference=ReferenceTrack(
            t_s=np.array([0.0, 1e6]),
            lat_rad=np.radians([s.site.lat_deg] * 2),
            lon_rad=np.radians([s.site.lon_deg] * 2),
            height_m=np.zeros(2),
        ),
    )
    assert static.summary["max_pos_err_nmi"] > 1.0


def test_gnss_track_file_is_interpolated_and_must_cover_the_drive(tmp_path):
    from gyrodrift.ins.track import ReferenceTrack, TrackError, load_track
    from gyrodrift.procedure import navigate

    s = vehicle(duration_h=0.3)
    route = ReferenceTrack.from_scenario(s)
    # A GNSS-like file: 0.7 s epochs (another time base than the 1 s nav output), with velocity.
    t = np.arange(0.0, 0.3 * 3600 + 0.7, 0.7)
    lat, lon, h = route.at(t)
    csv = tmp_path / "gnss.csv"
    rows = ["t_s,lat_deg,lon_deg,height_m"] + [
        ",".join(repr(float(x)) for x in row) for row in zip(t, np.degrees(lat), np.degrees(lon), h, strict=True)
    ]
    csv.write_text("\n".join(rows) + "\n")
    gnss = navigate(s, reference=csv)
    exact = navigate(s)
    # Linear interpolation between 0.7 s epochs cuts the corners of the 6 deg/s turn at 20 m/s by at most the
    # sagitta v w dt^2 / 8 = 0.13 m.
    assert abs(gnss.summary["max_pos_err_nmi"] - exact.summary["max_pos_err_nmi"]) * 1852 < 0.15
    short = tmp_path / "short.csv"
    short.write_text("\n".join(rows[: len(rows) // 2]) + "\n")
    with pytest.raises(TrackError, match=r"short.csv: the reference track covers 0 \.\. .* needs 0 \.\. 1080 s"):
        navigate(s, reference=short)
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,lat_deg,lon_deg,height_m\n0,28,112,0\n1,nan,112,0\n")
    with pytest.raises(TrackError, match=r"bad.csv: row 3, column lat_deg: expected a finite number"):
        load_track(bad)
    back = tmp_path / "back.csv"
    back.write_text("t_s,lat_deg,lon_deg,height_m\n0,28,112,0\n0,28,112,0\n")
    with pytest.raises(TrackError, match=r"back.csv: row 3, column t_s: time stamps must increase"):
        load_track(back)
    with pytest.raises(TrackError, match="missing column"):
        csv.write_text("t_s,lat_deg\n0,1\n1,2\n")
        load_track(csv)


def test_vehicle_test_example_compensation_and_modulation():
    """examples/scenarios/vehicle_test.toml at 10 Hz (the shipped file is 100 Hz; its numbers:
    docs/studies/2026-11-23-vehicle-test.md)
    with a 4.5 h stand instead of 16 h: the evaluation against the route (alignment, then 72 h of driving without
    and with the 0.003 deg/h drift compensated) goes from above 1 nmi to below it; and the horizontal sensor errors
    alone stay modulated while the vehicle turns (rotation on) but not with the table stopped."""
    import dataclasses
    from pathlib import Path

    from gyrodrift.ins.scenario import Rotation
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.ins.track import ReferenceTrack
    from gyrodrift.procedure import navigate
    from gyrodrift.procedure.evaluate import evaluate_compensation

    path = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "vehicle_test.toml"
    s = load_scenario(path)
    assert s.trajectory is not None and s.run.duration_h == 88.0 and s.run.rate_hz == 100.0
    s = dataclasses.replace(
        s,
        run=dataclasses.replace(s.run, rate_hz=10.0, duration_h=76.5),
        trajectory=dataclasses.replace(s.trajectory, static_h=4.5),
    )
    ev = evaluate_compensation(scenario_log(s), 0.003, reference=ReferenceTrack.from_scenario(s))
    assert ev.before.max_nmi > 3.0, ev.to_dict()
    assert ev.after.max_nmi < 1.0, ev.to_dict()
    horizontal = dataclasses.replace(
        s,
        run=dataclasses.replace(s.run, duration_h=16.5),
        gyro=dataclasses.replace(s.gyro, bias_deg_h=(0.01, -0.01, 0.0), arw_deg_rth=0.0),
        accel=dataclasses.replace(s.accel, vrw_ug_rthz=0.0),
    )
    rotating = navigate(horizontal, decimation_s=60.0).summary["max_pos_err_nmi"]
    still = navigate(dataclasses.replace(horizontal, rotation=Rotation(scheme="none")), decimation_s=60.0)
    assert rotating < 0.3 and still.summary["max_pos_err_nmi"] > 5 * rotating, (rotating, still.summary)


def test_cli_evaluate_on_a_moving_base_log(tmp_path):
    """`gyrodrift evaluate` of a simulated moving-base imu.parquet: errors against its route by default (route map
    added to the outputs), or against a GNSS track; a track that does not cover the drive is one line."""
    import json

    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.ins.track import ReferenceTrack

    d = vehicle(duration_h=4.5).to_toml_dict()
    d["run"]["rate_hz"] = 10.0
    d["trajectory"]["static_h"] = 4.0  # the alignment needs the vehicle standing
    s = Scenario.from_dict(d)
    imu = simulate(s, out_dir=tmp_path / "sim")
    out = tmp_path / "eval"
    r = CliRunner().invoke(main, ["evaluate", str(imu), "--drift-deg-h", "0", "--hours", "0.5", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "evaluation.json",
        "position_error.parquet",
        "position_error.png",
        "route_map.png",
    ]
    doc = json.loads((out / "evaluation.json").read_text())
    assert doc["reference"] == "<route>"
    # Error-free IMU, aligned on the stand, then 0.5 h of driving: well under 0.01 nmi against the route.
    assert doc["before"]["max_pos_err_nmi"] < 0.01
    route = ReferenceTrack.from_scenario(s)
    lat, lon, h = route.at(np.arange(0.0, 3000.0, 1.0))  # the drive needs 14400 .. 16200 s
    gnss = tmp_path / "gnss.csv"
    gnss.write_text(
        "t_s,lat_deg,lon_deg,height_m\n"
        + "".join(
            f"{t!r},{a!r},{b!r},{c!r}\n"
            for t, a, b, c in zip(
                np.arange(0.0, 3000.0, 1.0).tolist(),
                np.degrees(lat).tolist(),
                np.degrees(lon).tolist(),
                h.tolist(),
                strict=True,
            )
        )
    )
    r = CliRunner().invoke(
        main,
        [
            "evaluate",
            str(imu),
            "--drift-deg-h",
            "0",
            "--hours",
            "0.5",
            "--reference",
            str(gnss),
            "--out",
            str(tmp_path / "e2"),
        ],
    )
    assert r.exit_code == 1
    assert r.output.strip().splitlines()[-1].endswith("(time stamps on the IMU log's time base)")
    assert "gnss.csv: the reference track covers 0 .. 2999 s, navigating" in r.output
    assert "needs 14400 .. 16200 s" in r.output


def test_vehicle_attitude_columns_remove_the_table_turn(tmp_path):
    """nav.parquet of a moving-base run carries the vehicle's attitude: the navigated IMU attitude with the table
    angle removed, equal to the route's heading (error-free IMU, tilted mounting), from memory, from the file and
    from a scenario navigated on the fly."""
    from gyrodrift.ins.vehicle import vehicle_attitude_rad
    from gyrodrift.procedure import navigate

    d = vehicle(duration_h=0.2).to_toml_dict()
    d["attitude"].update(pitch_deg=0.5, roll_deg=-0.8)
    s = Scenario.from_dict(d)
    imu = simulate(s)
    nav = navigate(imu, decimation_s=1.0)
    idx = np.round(nav["t_s"] * 100).astype(int) - 1
    vp, vr, vy = vehicle_attitude_rad(
        np.radians(imu["true_pitch_deg"][idx]),
        np.radians(imu["true_roll_deg"][idx]),
        np.radians(imu["true_yaw_deg"][idx]),
        np.radians(imu["table_angle_deg"][idx]),
    )
    # The truth's vehicle attitude is the mounting tilt and the route's yaw (25 deg, +90, -180 ...).
    np.testing.assert_allclose(np.degrees(vp), 0.5, atol=1e-9)
    np.testing.assert_allclose(np.degrees(vr), -0.8, atol=1e-9)
    course = np.degrees(np.arctan2(-imu["true_vel_e_m_s"][idx], imu["true_vel_n_m_s"][idx]))
    moving = np.hypot(imu["true_vel_e_m_s"][idx], imu["true_vel_n_m_s"][idx]) > 1.0
    assert np.max(np.abs((np.degrees(vy) - course + 180) % 360 - 180)[moving]) < 1e-6
    # The navigated columns follow it to arcseconds.
    for name, truth in (("vehicle_pitch_deg", vp), ("vehicle_roll_deg", vr), ("vehicle_yaw_deg", vy)):
        diff = (nav[name] - np.degrees(truth) + 180.0) % 360.0 - 180.0
        assert np.max(np.abs(diff)) * 3600 < 1.0, name
    path = simulate(s, out_dir=tmp_path / "sim")
    from_file = navigate(path, decimation_s=1.0)
    np.testing.assert_allclose(from_file["vehicle_yaw_deg"], nav["vehicle_yaw_deg"], atol=1e-9)
    # A scenario navigated on the fly (nothing stored) takes the table angle from the simulated chunks.
    on_the_fly = navigate(s, decimation_s=1.0)
    for name in ("vehicle_pitch_deg", "vehicle_roll_deg", "vehicle_yaw_deg"):
        np.testing.assert_allclose(on_the_fly[name], nav[name], atol=1e-9)
