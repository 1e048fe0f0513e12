"""Moving base with height: climbs in the route, a log's ``ref_height_m`` column as the damped vertical channel's
reference, and its validation."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest

from gyrodrift.ins import Scenario, simulate
from gyrodrift.ins.scenario import ScenarioError
from gyrodrift.logs import LogError, open_log
from gyrodrift.procedure import navigate

HILLS = [
    {"kind": "accelerate", "accel_m_s2": 2.0, "to_speed_m_s": 20.0},
    {"kind": "straight", "duration_s": 300.0, "climb_m": 40.0},
    {"kind": "turn", "rate_deg_s": 3.0, "angle_deg": 90.0},
    {"kind": "straight", "duration_s": 200.0, "climb_m": -25.0},
    {"kind": "accelerate", "accel_m_s2": -2.0, "to_speed_m_s": 0.0, "climb_m": -1.0},
    {"kind": "stop", "duration_s": 30.0},
]


def hills(**run) -> Scenario:
    return Scenario.from_dict(
        {
            "site": {"height_m": 120.0},
            "run": {"rate_hz": 20.0, **run},
            "rotation": {"scheme": "reciprocating"},
            "attitude": {"yaw_deg": 25.0, "pitch_deg": 0.2},
            "trajectory": {"static_h": 0.01, "repeat": True, "segments": HILLS},
        },
        source="hills.toml",
    )


def test_climbs_resolve_round_trip_and_give_the_truth_its_height():
    s = hills(duration_h=0.3)
    assert [g.climb_m for g in s.trajectory.segments] == [0.0, 40.0, 0.0, -25.0, -1.0, 0.0]
    assert Scenario.from_dict(s.to_toml_dict()) == s
    imu = simulate(s)
    h, vu = imu.columns["true_height_m"], imu.columns["true_vel_u_m_s"]
    t = imu.columns["t_s"]
    # The first climb: 40 m over 300 s starting at 36 + 10 s, h = 120 + 20 (1 - cos(pi tau / 300)).
    tau = t - 46.0
    on = (tau > 0) & (tau < 300)
    np.testing.assert_allclose(h[on], 120.0 + 20.0 * (1 - np.cos(np.pi * tau[on] / 300.0)), atol=1e-9)
    np.testing.assert_allclose(vu[on], 20.0 * np.pi / 300.0 * np.sin(np.pi * tau[on] / 300.0), atol=1e-12)
    assert h[t < 36.0].tolist() == [120.0] * int(np.sum(t < 36.0))


@pytest.mark.parametrize(
    ("segment", "message"),
    [
        (
            {"kind": "straight", "duration_s": 10.0, "climb_m": 500.0},
            "hills.toml: [trajectory] segments[1].climb_m: a climb of 500 m in 10 s needs a vertical speed of 78.5",
        ),
        (
            {"kind": "straight", "duration_s": 10.0, "climb_m": "up"},
            "[trajectory] segments[1].climb_m: expected a number",
        ),
        ({"kind": "stop", "duration_s": 10.0, "climb_m": 1.0}, "segments[1].climb_m: unknown key for a stop"),
        (
            {"kind": "straight", "duration_s": 9000.0, "climb_m": -1500.0},
            "[trajectory] segments: segment 2 ends at height -1380 m",
        ),
    ],
)
def test_bad_climbs_name_the_file_and_key(segment, message):
    first = {"kind": "accelerate", "accel_m_s2": 2.0, "to_speed_m_s": 20.0}
    if segment["kind"] == "stop":
        first = {"kind": "straight", "duration_s": 1.0}
    with pytest.raises(ScenarioError) as info:
        Scenario.from_dict(
            {"site": {"height_m": 120.0}, "trajectory": {"static_h": 0.01, "segments": [first, segment]}},
            source="hills.toml",
        )
    assert message in str(info.value)


def _with_height_column(path, height: np.ndarray, out):
    """imu.parquet at `path` with a ``ref_height_m`` column added (metadata kept), written to `out`."""
    table = pq.read_table(path)
    pq.write_table(table.append_column("ref_height_m", pa.array(height, pa.float64())), out)
    return out


def test_height_column_damps_the_vertical_channel(tmp_path):
    """A simulated hilly drive written with its height as the log's ``ref_height_m`` (a perfect barometer):
    `navigate` picks the damped channel with that reference, the height follows the climbs to centimetres, and the
    horizontal error is the one with the route's own height as the reference."""
    s = hills(duration_h=0.3)
    imu = simulate(s, out_dir=tmp_path / "sim")
    true_h = pq.read_table(imu, columns=["true_height_m"]).column(0).to_numpy()
    log = _with_height_column(imu, true_h, tmp_path / "baro.parquet")

    with_column = navigate(log, decimation_s=10.0)
    su = with_column.summary
    assert su["vertical"] == "damped" and su["vertical_reference"].startswith("ref_height_m column of ")
    route = navigate(imu, decimation_s=10.0, vertical="damped")
    assert route.summary["vertical_reference"] == "height of the reference track <route>"
    fixed = navigate(imu, decimation_s=10.0)
    assert fixed.summary["vertical"] == "fixed" and fixed.summary["vertical_reference"] is None

    kept = (np.rint(with_column["t_s"] * 20.0).astype(int)) - 1
    err_h = with_column["height_m"] - true_h[kept]
    assert np.ptp(true_h) > 40.0
    assert np.max(np.abs(err_h)) < 0.05, np.max(np.abs(err_h))
    assert np.max(np.abs(fixed["height_m"] - true_h[kept])) > 30.0  # held at the start height
    # Horizontal: the same as with the route's reference (both references are the true height).
    a, b = su["max_pos_err_nmi"], route.summary["max_pos_err_nmi"]
    assert a < 1e-3 and abs(a - b) < 1e-5, (a, b)

    # A height column wins over the route; asked for a fixed channel, the column is not used.
    assert navigate(log, decimation_s=10.0, vertical="fixed").summary["vertical_reference"] is None
    # A biased barometer (+10 m) moves the navigated height by as much (times 1 + 2 g / (R w_v^2) = 1.03 in steady
    # state: the loop's gain cancelling the gravity gradient sees the offset too), and barely the horizontal.
    biased = navigate(_with_height_column(imu, true_h + 10.0, tmp_path / "biased.parquet"), decimation_s=10.0)
    late = biased["t_s"] > 600.0
    np.testing.assert_allclose(biased["height_m"][late] - true_h[kept][late], 10.3, atol=0.2)
    assert biased.summary["max_pos_err_nmi"] < 1e-3


def test_bad_height_column_is_named_by_file_row_and_column(tmp_path):
    s = hills(duration_h=0.05)
    imu = simulate(s)
    cols = {k: np.asarray(v) for k, v in imu.columns.items()}
    n = len(cols["t_s"])
    names = ["t_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s"]
    for bad, expected in [(np.nan, "empty or NaN cell"), (25_000.0, "reference height 25000 m is outside")]:
        h = np.full(n, 120.0)
        h[7] = bad
        path = tmp_path / "baro.csv"
        table = pa.table({**{c: cols[c] for c in names}, "ref_height_m": h})
        pacsv.write_csv(table, path)
        log = open_log(path, site={"lat_deg": 28.0, "lon_deg": 113.0}, require_temperature=False)
        assert log.has_reference_height
        with pytest.raises(LogError) as info:
            for _ in log.chunks(1000):
                pass
        assert f"{path}, row 9, column ref_height_m: {expected}" in str(info.value)
    with pytest.raises(Exception, match="vertical must be one of fixed, damped"):
        navigate(imu, vertical="baro")


def test_a_formatted_log_names_its_own_height_column(tmp_path):
    """A log in its own format maps a column to ``quantity = "ref_height"`` in feet: read in metres, and a bad
    value is named by the file's line and its own column."""
    s = hills(duration_h=0.05)
    imu = simulate(s)
    cols = {k: np.asarray(v) for k, v in imu.columns.items()}
    n = len(cols["t_s"])
    baro_ft = np.full(n, 120.0 / 0.3048)
    baro_ft[11] = np.inf
    names = {"Time": "t_s", "Baro": None}
    for ax in "xyz":
        names[f"Gx{ax}"] = f"dtheta_{ax}_rad"
        names[f"Ax{ax}"] = f"dv_{ax}_m_s"
    table = pa.table({k: (baro_ft if v is None else cols[v]) for k, v in names.items()})
    path = tmp_path / "baro.csv"
    pacsv.write_csv(table, path)
    fmt = tmp_path / "baro.format.toml"
    lines = [
        '[columns.Time]\nquantity = "time"\nunit = "s"\n',
        '[columns.Baro]\nquantity = "ref_height"\nunit = "ft"\n',
    ]
    for ax in "xyz":
        lines.append(f'[columns.Gx{ax}]\nquantity = "gyro_{ax}"\nunit = "rad"\n')
        lines.append(f'[columns.Ax{ax}]\nquantity = "accel_{ax}"\nunit = "m/s"\n')
    fmt.write_text("\n".join(lines))
    log = open_log(path, site={"lat_deg": 28.0, "lon_deg": 113.0}, format=fmt, require_temperature=False)
    assert log.has_reference_height
    first = next(log.chunks(5, stop=5))
    assert first.ref_height_m is not None
    np.testing.assert_allclose(first.ref_height_m, 120.0, rtol=1e-15)
    with pytest.raises(LogError) as info:
        for _ in log.chunks(1000):
            pass
    assert f"{path}, row 13, column Baro" in str(info.value) and "expected a finite number" in str(info.value)


def test_evaluate_damps_the_vertical_channel_on_a_moving_base(tmp_path):
    """`evaluate_compensation` on the hilly drive navigates with the damped channel: towards the route's height for
    the scenario simulated on the fly (whose route is also the reference track: before, such a log was compared
    with the static site, 6.8 nmi off), towards the log's ``ref_height_m`` column for a file that has one. Both
    stay on the route to metres, and agree with each other."""
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.procedure.evaluate import evaluate_compensation
    from gyrodrift.procedure.timeline import Timeline

    s = Scenario.from_dict(
        {
            "site": {"height_m": 120.0},
            "run": {"rate_hz": 20.0, "duration_h": 0.4},
            "rotation": {"scheme": "reciprocating"},
            "attitude": {"yaw_deg": 25.0},
            "trajectory": {"static_h": 0.1, "repeat": True, "segments": HILLS},
        },
        source="hills.toml",
    )
    timeline = Timeline(align_h=0.1, features_h=0.1, truth_h=0.25, coarse_s=60.0)
    on_the_fly = evaluate_compensation(scenario_log(s), 0.0, timeline=timeline, decimation_s=10.0).to_dict()
    assert on_the_fly["reference"] == "<route>"
    assert on_the_fly["vertical"] == "damped"
    assert on_the_fly["vertical_reference"] == "height of the reference track <route>"

    imu = simulate(s, out_dir=tmp_path / "sim")
    true_h = pq.read_table(imu, columns=["true_height_m"]).column(0).to_numpy()
    baro = _with_height_column(imu, true_h, tmp_path / "baro.parquet")
    from_column = evaluate_compensation(open_log(baro), 0.0, timeline=timeline, decimation_s=10.0).to_dict()
    assert from_column["vertical"] == "damped"
    assert from_column["vertical_reference"].startswith("ref_height_m column of ")

    a, b = on_the_fly["before"]["max_pos_err_nmi"], from_column["before"]["max_pos_err_nmi"]
    assert a < 1e-3 and abs(a - b) < 1e-5, (a, b)
