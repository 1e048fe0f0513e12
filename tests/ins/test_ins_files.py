"""imu.parquet / nav.parquet / summary.json formats, streaming, and the click commands."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.ins import ImuData, LogError, Scenario, load_scenario, simulate
from gyrodrift.ins.nav_columns import NAV_COLUMNS, NAV_ERROR_COLUMNS
from gyrodrift.logs.columns import IMU_COLUMNS, IMU_FORMAT
from gyrodrift.procedure import navigate

SMALL = """
[site]
lat_deg = 28.222
lon_deg = 112.99
[run]
duration_h = 1.05
rate_hz = 10.0
seed = 3
[rotation]
scheme = "reciprocating"
[gyro]
bias_deg_h = [0.01, -0.01, 0.003]
arw_deg_rth = 0.001
[accel]
bias_ug = [30, -20, 10]
[temperature]
start_c = 20
end_c = 30
tau_h = 0.5
k1_deg_h_per_c = 0.0001
[attitude]
yaw_deg = 30
"""


@pytest.fixture
def small_toml(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path


def test_simulate_writes_streamed_parquet_with_units_truth_and_resolved_scenario(tmp_path, small_toml):
    scn = load_scenario(small_toml)
    out = simulate(scn, out_dir=tmp_path / "run", chunk_samples=5000)
    assert out == tmp_path / "run" / "imu.parquet"
    pf = pq.ParquetFile(out)
    assert pf.schema_arrow.names == list(IMU_COLUMNS)
    assert pf.metadata.num_rows == scn.n_samples == 37800
    assert pf.num_row_groups == 8  # one row group per chunk: 7 x 5000 + 2800
    meta = {k.decode(): v.decode() for k, v in pf.schema_arrow.metadata.items()}
    assert meta["gyrodrift.format"] == IMU_FORMAT == "gyrodrift-imu/1"
    assert json.loads(meta["gyrodrift.site"]) == {"lat_deg": 28.222, "lon_deg": 112.99, "height_m": 0.0}
    assert Scenario.from_dict(json.loads(meta["gyrodrift.scenario"])) == scn
    resolved = tmp_path / "run" / "scenario.resolved.toml"
    assert load_scenario(resolved) == scn
    assert tomllib.loads(resolved.read_text())["rotation"]["span_deg"] == 360.0  # defaults written out
    # No temporary files left behind.
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == [
        ".gyrodrift-manifest.json",
        "imu.parquet",
        "scenario.resolved.toml",
    ]

    table = pq.read_table(out)
    t = table.column("t_s").to_numpy()
    np.testing.assert_allclose(t[:3], [0.1, 0.2, 0.3], rtol=1e-12)
    temp = table.column("temp_c").to_numpy()
    # Warm-up T(t) = end + (start - end) exp(-t / tau), 20 -> 30 degC with tau = 0.5 h.
    np.testing.assert_allclose(temp, 30.0 - 10.0 * np.exp(-t / 1800.0), rtol=0, atol=1e-9)
    # In-memory simulation gives the same numbers, to the bit.
    mem = simulate(scn)
    assert isinstance(mem, ImuData) and len(mem) == 37800
    for c in IMU_COLUMNS:
        np.testing.assert_array_equal(mem[c], table.column(c).to_numpy(), err_msg=c)


def test_navigate_file_memory_and_scenario_agree_and_write_outputs(tmp_path, small_toml):
    scn = load_scenario(small_toml)
    imu_path = simulate(scn, out_dir=tmp_path / "run", chunk_samples=7000)
    from_file = navigate(imu_path, out_dir=tmp_path / "run", chunk_samples=3333, decimation_s=10.0)
    from_scn = navigate(scn, decimation_s=10.0)
    from_mem = navigate(simulate(scn), decimation_s=10.0, chunk_samples=50_000)
    for c in NAV_COLUMNS + NAV_ERROR_COLUMNS:
        np.testing.assert_array_equal(from_file[c], from_scn[c], err_msg=c)
        np.testing.assert_array_equal(from_mem[c], from_scn[c], err_msg=c)

    nav = pq.read_table(tmp_path / "run" / "nav.parquet")
    assert nav.schema.names == list(NAV_COLUMNS + NAV_ERROR_COLUMNS)
    assert nav.num_rows == int(1.05 * 3600 / 10)
    np.testing.assert_allclose(nav.column("t_s").to_numpy()[:2], [10.0, 20.0])
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary == json.loads(json.dumps(from_file.summary))
    assert [c["t_h"] for c in summary["checkpoints"]] == [1]
    cp = summary["checkpoints"][0]
    # The 1 h checkpoint is the exact state at 3600 s, which is also a kept row.
    row = int(np.argmin(np.abs(nav.column("t_s").to_numpy() - 3600.0)))
    assert cp["lat_err_arcsec"] == pytest.approx(nav.column("lat_err_arcsec").to_numpy()[row], abs=1e-9)
    assert cp["pos_err_nmi"] == pytest.approx(nav.column("pos_err_nmi").to_numpy()[row], abs=1e-12)
    assert summary["final"]["t_h"] == pytest.approx(1.05)
    assert summary["max_pos_err_nmi"] >= summary["final_pos_err_nmi"] >= 0.0
    assert summary["max_pos_err_nmi"] == pytest.approx(
        max(nav.column("pos_err_nmi").to_numpy().max(), summary["final_pos_err_nmi"])
    )


def test_navigate_hours_limits_the_run(tmp_path, small_toml):
    res = navigate(load_scenario(small_toml), hours=0.5, decimation_s=60.0)
    assert res.summary["hours_navigated"] == pytest.approx(0.5)
    assert res.summary["checkpoints"] == []
    assert res["t_s"][-1] == pytest.approx(1800.0)


def test_errors_are_computed_minus_true():
    """Start 10 arcsec north of the truth with an error-free IMU: latitude error is +10 arcsec at once."""
    scn = Scenario.from_dict({"run": {"duration_h": 0.01, "rate_hz": 10.0}, "rotation": {"scheme": "none"}})
    res = navigate(scn, initial={"lat_deg": scn.site.lat_deg + 10.0 / 3600.0}, decimation_s=0.1)
    assert res["lat_err_arcsec"][0] == pytest.approx(10.0, abs=0.01)
    assert res["lon_err_arcsec"][0] == pytest.approx(0.0, abs=0.01)
    # Meridian radius written out from the WGS-84 definition (a = 6378137 m, f = 1/298.257223563).
    e2 = (1 / 298.257223563) * (2 - 1 / 298.257223563)
    s2 = np.sin(np.deg2rad(28.222)) ** 2
    r_m = 6378137.0 * (1 - e2) / (1 - e2 * s2) ** 1.5
    assert res["pos_err_nmi"][0] == pytest.approx(10.0 / 3600.0 * np.pi / 180.0 * r_m / 1852.0, rel=1e-4)


def test_navigate_refuses_missing_and_foreign_files(tmp_path):
    with pytest.raises(LogError) as info:
        navigate(tmp_path / "none.parquet")
    assert str(info.value) == f"{tmp_path / 'none.parquet'}: no such file"
    junk = tmp_path / "junk.parquet"
    junk.write_text("not parquet")
    with pytest.raises(LogError, match=r"junk.parquet: not a Parquet file"):
        navigate(junk)
    import pyarrow as pa

    other = tmp_path / "other.parquet"
    pq.write_table(pa.table({"t_s": [0.1, 0.2], "x": [1.0, 2.0]}), other)
    with pytest.raises(LogError) as info:
        navigate(other)
    assert "missing column(s) dtheta_x_rad" in str(info.value) and str(other) in str(info.value)


# --------------------------------------------------------------------------------------------------
# Click commands
# --------------------------------------------------------------------------------------------------


def test_cli_simulate_then_navigate(tmp_path, small_toml):
    runner = CliRunner()
    out = tmp_path / "cli"
    r = runner.invoke(main, ["simulate", str(small_toml), "--out", str(out), "--quiet"])
    assert r.exit_code == 0, r.output
    assert (out / "imu.parquet").exists() and (out / "scenario.resolved.toml").exists()
    r = runner.invoke(
        main,
        ["navigate", str(out / "imu.parquet"), "--hours", "1", "--drift-deg-h", "0.003", "--out", str(out)],
    )
    assert r.exit_code == 0, r.output
    assert "final position error" in r.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["compensate_drift_deg_h"] == 0.003
    assert summary["hours_navigated"] == pytest.approx(1.0)
    assert [c["t_h"] for c in summary["checkpoints"]] == [1]


def test_cli_errors_name_the_file(tmp_path):
    runner = CliRunner()
    missing = tmp_path / "missing.toml"
    r = runner.invoke(main, ["simulate", str(missing), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1
    assert f"Error: {missing}: no such file" in r.output
    bad = tmp_path / "bad.toml"
    bad.write_text("[gyro]\nbias_deg_h = [1, 2]\n")
    r = runner.invoke(main, ["simulate", str(bad), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1
    assert f"Error: {bad}: [gyro] bias_deg_h: expected 3 numbers, got 2" in r.output
    assert not (tmp_path / "o").exists()
    r = runner.invoke(main, ["navigate", str(tmp_path / "imu.parquet"), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1
    assert f"Error: {tmp_path / 'imu.parquet'}: no such file" in r.output
    r = runner.invoke(main, ["navigate", str(bad), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1 and f"{bad}: unknown log format '.toml' (expected .parquet, .pq or .csv)" in r.output
    r = runner.invoke(main, ["navigate", str(bad), "--hours", "-1", "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "--hours" in r.output


def test_temperature_series_and_axial_drift_model_reach_the_z_gyro_in_user_units(tmp_path):
    """k1 (T - T0) + k2 (T - T0)^2 + k3 dT/dt [deg/h] on the z gyro, with a measured series from a CSV."""
    (tmp_path / "temp.csv").write_text("t_h,temp_c\n0,20\n0.5,30\n1.0,25\n")
    path = tmp_path / "s.toml"
    path.write_text(
        '[run]\nduration_h = 1.0\nrate_hz = 10.0\n[rotation]\nscheme = "none"\n'
        '[temperature]\nseries_csv = "temp.csv"\nt0_c = 20.0\nk1_deg_h_per_c = 0.01\n'
        "k2_deg_h_per_c2 = 0.001\nk3_deg_h_per_c_per_h = 0.002\n"
    )
    scn = load_scenario(path)
    imu = simulate(scn)
    t = imu["t_s"]
    temp = np.interp(t / 3600.0, [0.0, 0.5, 1.0], [20.0, 30.0, 25.0])
    np.testing.assert_allclose(imu["temp_c"], temp, rtol=0, atol=1e-9)
    lat = np.deg2rad(scn.site.lat_deg)
    from gyrodrift.earth import OMEGA_IE_RAD_S
    from gyrodrift.units import DEG_PER_H

    z_rate_deg_h = (imu["dtheta_z_rad"] * 10.0 - OMEGA_IE_RAD_S * np.sin(lat)) / DEG_PER_H
    slope_c_h = np.where(t < 1800.0, 20.0, -10.0)
    expected = 0.01 * (temp - 20.0) + 0.001 * (temp - 20.0) ** 2 + 0.002 * slope_c_h
    away_from_kinks = np.abs(t - 1800.0) > 1.0
    np.testing.assert_allclose(z_rate_deg_h[away_from_kinks], expected[away_from_kinks], rtol=0, atol=2e-4)
    # x and y carry no drift.
    assert np.max(np.abs(imu["dtheta_x_rad"] * 10.0) / DEG_PER_H) < 1e-6


def test_foreign_imu_file_without_metadata_needs_an_initial_state(tmp_path):

    scn = Scenario.from_dict({"run": {"duration_h": 0.05, "rate_hz": 10.0}, "rotation": {"scheme": "none"}})
    table = simulate(scn).table()
    bare = table.select(["t_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s"])
    bare = bare.replace_schema_metadata(None)
    path = tmp_path / "foreign.parquet"
    pq.write_table(bare, path)
    with pytest.raises(LogError) as info:
        navigate(path)  # no truth: an alignment would be needed, and it needs the site
    assert str(info.value) == f"{path}: the log carries no site; give its latitude (--lat0-deg / site=)"
    with pytest.raises(LogError, match=r"foreign.parquet: the log carries no true initial state"):
        navigate(path, initial="truth", site={"lat_deg": 28.0})
    with pytest.raises(ValueError) as info:
        navigate(path, initial={"lat_deg": 28.0})
    assert str(info.value) == f"navigate: {path} carries no truth; initial must give lon_deg"
    r = CliRunner().invoke(main, ["navigate", str(path), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1 and f"Error: {path}: the log carries no site; give its latitude" in r.output

    init = {
        "lat_deg": scn.site.lat_deg,
        "lon_deg": scn.site.lon_deg,
        "height_m": 0.0,
        "pitch_deg": 0.0,
        "roll_deg": 0.0,
        "yaw_deg": 0.0,
    }
    res = navigate(path, initial=init, decimation_s=1.0, out_dir=tmp_path / "o")
    assert res.summary["rate_hz"] == pytest.approx(10.0)  # from the time stamps
    assert res.summary["truth"] is None and res.summary["final_pos_err_nmi"] is None
    assert "pos_err_nmi" not in res.columns
    np.testing.assert_allclose(res["lat_deg"], scn.site.lat_deg, rtol=0, atol=1e-9)
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["max_pos_err_nmi"] is None


def test_navigate_argument_checks():
    scn = Scenario.from_dict({"run": {"duration_h": 0.01, "rate_hz": 10.0}})
    with pytest.raises(ValueError, match=r"navigate: decimation_s must be > 0, got 0"):
        navigate(scn, decimation_s=0)
    with pytest.raises(ValueError, match=r"navigate: hours must be > 0, got -1"):
        navigate(scn, hours=-1)
    with pytest.raises(ValueError, match=r"navigate: gyro_bias_deg_h must be 3 finite numbers"):
        navigate(scn, gyro_bias_deg_h=[0.0, 0.0])
    with pytest.raises(ValueError, match=r"navigate: unknown initial key\(s\) \['lat'\]"):
        navigate(scn, initial={"lat": 1.0})
    with pytest.raises(
        TypeError, match="imu must be a path to an IMU log, an ImuLog, an ImuData or a Scenario, got int"
    ):
        navigate(3)


def test_navigate_takes_any_log_and_says_where_the_initial_state_came_from(tmp_path):
    """A CSV and a bare Parquet (no gyrodrift metadata) of the same run: the site from the options, the initial
    state from an alignment of the first 4 h, the same numbers from both formats; the simulator's own file
    still starts from its truth."""
    import pyarrow.csv as pcsv

    scn = Scenario.from_dict(
        {
            "run": {"duration_h": 4.3, "rate_hz": 10.0, "seed": 4},
            "gyro": {"bias_deg_h": [0.005, -0.004, 0.003]},
            "accel": {"bias_ug": [30.0, -20.0, 10.0]},
            "attitude": {"yaw_deg": 40.0},
        }
    )
    sim = simulate(scn, out_dir=tmp_path / "sim")
    table = pq.read_table(sim).select(["t_s", *IMU_COLUMNS[1:7], "temp_c"]).replace_schema_metadata(None)
    pcsv.write_csv(table, tmp_path / "run.csv")
    pq.write_table(table, tmp_path / "bare.parquet")
    site = ["--lat0-deg", repr(scn.site.lat_deg), "--lon0-deg", repr(scn.site.lon_deg)]
    r = CliRunner().invoke(main, ["navigate", str(tmp_path / "run.csv"), *site, "--out", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    assert "initial state from an alignment of the log's first hours" in r.output
    csv_summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert csv_summary["initial_source"] == "alignment" and csv_summary["start_s"] == pytest.approx(4 * 3600.0)
    assert csv_summary["hours_navigated"] == pytest.approx(0.3)
    assert csv_summary["truth"]["lat_deg"] == scn.site.lat_deg
    assert 0.0 < csv_summary["final_pos_err_nmi"] < 0.5  # aligned on the same data: no gross error
    bare = navigate(tmp_path / "bare.parquet", site={"lat_deg": scn.site.lat_deg, "lon_deg": scn.site.lon_deg})
    assert bare.summary["initial_source"] == "alignment"
    assert bare.summary["final_pos_err_nmi"] == pytest.approx(csv_summary["final_pos_err_nmi"], rel=1e-9)
    own = navigate(sim, hours=0.3)
    assert own.summary["initial_source"] == "truth" and own.summary["start_s"] == 0.0


def test_navigate_starts_from_the_true_attitude_columns_without_scenario_metadata(tmp_path):
    """A log with the true attitude columns and a site but no scenario: the attitude at the end of the first
    sample, navigation from the second; the result is as close to the truth as from the scenario's t = 0."""
    scn = Scenario.from_dict({"run": {"duration_h": 0.2, "rate_hz": 10.0}, "gyro": {"bias_deg_h": [0, 0, 0.01]}})
    sim = simulate(scn, out_dir=tmp_path / "sim")
    table = pq.read_table(sim)
    meta = {k: v for k, v in table.schema.metadata.items() if k != b"gyrodrift.scenario"}
    pq.write_table(table.replace_schema_metadata(meta), tmp_path / "noscn.parquet")
    own = navigate(sim)
    cols = navigate(tmp_path / "noscn.parquet")
    assert cols.summary["initial_source"] == "truth" and cols.summary["start_s"] == pytest.approx(0.1)
    assert cols.summary["n_samples"] == own.summary["n_samples"] - 1
    assert cols.summary["initial"]["yaw_deg"] == pytest.approx(table.column("true_yaw_deg")[0].as_py())
    assert cols.summary["final_pos_err_nmi"] == pytest.approx(own.summary["final_pos_err_nmi"], rel=0.05)
    # The heading error is the z bias integrated (0.01 deg/h over 0.2 h = 7.2 arcsec) from either start.
    assert cols["yaw_err_arcsec"][-1] == pytest.approx(own["yaw_err_arcsec"][-1], abs=0.1)
    assert abs(cols["yaw_err_arcsec"][0]) < 0.1
