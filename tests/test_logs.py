"""IMU logs (gyrodrift.logs): formats, kind and rate detection, streaming, and one exact message per bad log."""

from __future__ import annotations

import math

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gyrodrift.ins import Scenario, simulate
from gyrodrift.ins.imu_file import ImuFileReader
from gyrodrift.logs import INCREMENT_COLUMNS, RATE_COLUMNS, LogError, Site, open_log

RATE = 10.0


@pytest.fixture(scope="module")
def sim_parquet(tmp_path_factory):
    """A 0.2 h simulated run at 10 Hz (7200 samples) with noise, rotating, warming up."""
    scn = Scenario.from_dict(
        {
            "run": {"duration_h": 0.2, "rate_hz": RATE, "seed": 3},
            "gyro": {"bias_deg_h": [0.01, -0.01, 0.003], "arw_deg_rth": 0.001},
            "accel": {"bias_ug": [20, -20, 10], "vrw_ug_rthz": 5.0},
            "temperature": {"start_c": 20.0, "end_c": 30.0, "tau_h": 0.1},
            "site": {"lat_deg": 30.0, "lon_deg": 100.0, "height_m": 40.0},
        }
    )
    return simulate(scn, out_dir=tmp_path_factory.mktemp("logsim"), chunk_samples=1000)


def whole(log, chunk_samples=997):
    parts = list(log.chunks(chunk_samples))
    assert all(len(p) <= chunk_samples for p in parts)
    return (
        np.concatenate([p.t_s for p in parts]),
        np.concatenate([p.dtheta_rad for p in parts]),
        np.concatenate([p.dv_m_s for p in parts]),
        np.concatenate([p.temp_c for p in parts]),
        parts,
    )


def write_csv(path, cols: dict[str, np.ndarray], cells: dict[tuple[int, str], str] | None = None):
    """Write columns as CSV with repr floats; `cells` overrides some cells (row index 0 = first sample)."""
    names = list(cols)
    n = len(cols[names[0]])
    lines = [",".join(names)]
    for i in range(n):
        row = [repr(float(cols[c][i])) for c in names]
        for (r, c), text in (cells or {}).items():
            if r == i:
                row[names.index(c)] = text
        lines.append(",".join(row))
    path.write_text("\n".join(lines) + "\n")
    return path


def static_columns(n=60, rate=RATE, kind="increments"):
    """n samples of a static, level IMU: Earth rate and gravity, temperature 25 C."""
    t = np.arange(1, n + 1) / rate
    w = np.array([0.0, 6.4e-5, 3.4e-5])
    f = np.array([0.0, 0.0, 9.79])
    cols = {"t_s": t}
    if kind == "increments":
        for j, c in enumerate(INCREMENT_COLUMNS):
            cols[c] = np.full(n, (w if j < 3 else f)[j % 3] / rate)
    else:
        for j, c in enumerate(RATE_COLUMNS):
            cols[c] = np.full(n, (w if j < 3 else f)[j % 3])
    cols["temp_c"] = np.full(n, 25.0)
    return cols


# ------------------------------------------------------------------------------------------------
# Formats, detection, streaming
# ------------------------------------------------------------------------------------------------


def test_parquet_from_the_simulator_streams_the_same_samples_as_the_ins_reader(sim_parquet):
    log = open_log(sim_parquet)
    assert (log.format, log.kind, log.rate_hz, log.n_samples) == ("parquet", "increments", RATE, 7200)
    assert log.rate_source == "metadata"
    assert log.site == Site(30.0, 100.0, 40.0)
    assert log.name == sim_parquet.parent.name  # imu.parquet is named after its folder
    t, dth, dv, temp, parts = whole(log)
    ref = next(ImuFileReader(sim_parquet).chunks(10_000))
    np.testing.assert_array_equal(t, ref.t_s)
    np.testing.assert_array_equal(dth, ref.dtheta_rad)
    np.testing.assert_array_equal(dv, ref.dv_m_s)
    assert temp[0] == pytest.approx(20.0, abs=0.01) and temp[-1] == pytest.approx(30 - 10 * math.exp(-2), abs=0.01)
    assert [p.first_index for p in parts][:3] == [0, 997, 1994]


def test_csv_increments_equal_the_parquet_and_rate_comes_from_time_stamps(sim_parquet, tmp_path):
    table = pq.read_table(sim_parquet)
    cols = {c: table.column(c).to_numpy() for c in ("t_s", *INCREMENT_COLUMNS, "temp_c", "table_angle_deg")}
    path = write_csv(tmp_path / "run7.csv", cols)
    log = open_log(path, site={"lat_deg": 30.0})
    assert (log.format, log.kind, log.n_samples, log.name) == ("csv", "increments", 7200, "run7")
    assert log.rate_hz == pytest.approx(RATE, rel=1e-9)
    assert log.site == Site(30.0, 0.0, 0.0)
    t, dth, dv, temp, _ = whole(log, 1000)
    np.testing.assert_array_equal(t, table.column("t_s").to_numpy())
    np.testing.assert_array_equal(dth[:, 2], table.column("dtheta_z_rad").to_numpy())
    np.testing.assert_array_equal(dv[:, 0], table.column("dv_x_m_s").to_numpy())
    np.testing.assert_array_equal(temp, table.column("temp_c").to_numpy())


def test_csv_rates_are_detected_and_converted_to_increments(tmp_path):
    path = write_csv(tmp_path / "rates.csv", static_columns(kind="rates", rate=20.0))
    log = open_log(path, site={"lat_deg": 10.0})
    assert log.kind == "rates" and log.rate_hz == pytest.approx(20.0)
    _, dth, dv, _, _ = whole(log)
    np.testing.assert_allclose(dth[5], [0.0, 6.4e-5 / 20.0, 3.4e-5 / 20.0], rtol=1e-12)
    np.testing.assert_allclose(dv[5], [0.0, 0.0, 9.79 / 20.0], rtol=1e-12)


def test_site_mapping_overrides_only_the_keys_given(sim_parquet):
    assert open_log(sim_parquet, site={"height_m": 0.0}).site == Site(30.0, 100.0, 0.0)
    assert open_log(sim_parquet, site=Site(1.0)).site == Site(1.0, 0.0, 0.0)


def test_stop_reads_only_what_is_needed_and_complains_when_the_log_is_short(sim_parquet):
    log = open_log(sim_parquet)
    parts = list(log.chunks(1000, stop=2500))
    assert sum(len(p) for p in parts) == 2500
    with pytest.raises(LogError, match=r"the log ends after 7200 samples \(0\.200 h\); 7201 samples"):
        list(log.chunks(1000, stop=7201))
    with pytest.raises(LogError, match=r"imu\.parquet: the log lasts 0\.200 h; the alignment takes at least 4 h"):
        log.require_duration(4 * 3600.0, "the alignment")


# ------------------------------------------------------------------------------------------------
# One exact message per bad log
# ------------------------------------------------------------------------------------------------


def bad_csv(tmp_path, cells=None, drop=(), n=60, tweak=None):
    cols = static_columns(n=n)
    for c in drop:
        del cols[c]
    if tweak:
        tweak(cols)
    return write_csv(tmp_path / "bad.csv", cols, cells)


def stream_error(path, chunk_samples=7):
    with pytest.raises(LogError) as info:
        list(open_log(path, site={"lat_deg": 28.0}).chunks(chunk_samples))
    return str(info.value)


def test_duplicated_time_names_row_and_column(tmp_path):
    def dup(c):
        c["t_s"][20] = c["t_s"][19]
        c["t_s"][21:] -= 0.1

    path = bad_csv(tmp_path, tweak=dup)
    msg = stream_error(path)
    assert msg == (
        f"{path}, row 22, column t_s: duplicated time stamp (2.0 s after 2.0 s); time must be strictly increasing"
    )


def test_time_going_backwards_across_a_chunk_boundary(tmp_path):
    def back(c):
        c["t_s"][14:] -= 0.25  # sample 14 is the first of the third chunk of 7

    msg = stream_error(bad_csv(tmp_path, tweak=back), chunk_samples=7)
    assert "row 16, column t_s: time goes backwards (1.25 s after 1.4 s)" in msg


def test_gap_names_the_step(tmp_path):
    def gap(c):
        c["t_s"][30:] += 0.05

    msg = stream_error(bad_csv(tmp_path, tweak=gap))
    assert "row 32, column t_s: gap in time: step 0.15 s from 3.0 s, expected 0.1 s (rate 10 Hz, tolerance 1%)" in msg


def test_dt_within_one_percent_is_no_gap(tmp_path):
    def jitter(c):
        c["t_s"][30:] += 0.0009

    list(open_log(bad_csv(tmp_path, tweak=jitter), site={"lat_deg": 1.0}).chunks(7))


@pytest.mark.parametrize("text", ["", "nan", "NaN"])
def test_nan_or_empty_cell(tmp_path, text):
    path = bad_csv(tmp_path, cells={(40, "dv_y_m_s"): text})
    assert stream_error(path) == f"{path}, row 42, column dv_y_m_s: empty or NaN cell"


def test_non_numeric_cell(tmp_path):
    path = bad_csv(tmp_path, cells={(9, "dtheta_z_rad"): "abc"})
    assert stream_error(path) == f"{path}, row 11, column dtheta_z_rad: expected a number, got 'abc'"


def test_impossible_rate(tmp_path):
    path = bad_csv(tmp_path, cells={(5, "dtheta_x_rad"): repr(2000 * math.pi / 180 / RATE)})
    assert stream_error(path) == (
        f"{path}, row 7, column dtheta_x_rad: impossible magnitude: angular rate 2000 deg/s exceeds 1000 deg/s"
    )


def test_impossible_specific_force(tmp_path):
    path = bad_csv(tmp_path, cells={(50, "dv_z_m_s"): repr(-150 * 9.80665 / RATE)})
    assert stream_error(path) == (
        f"{path}, row 52, column dv_z_m_s: impossible magnitude: specific force 150 g exceeds 100 g"
    )


def test_missing_temperature_column(tmp_path):
    path = bad_csv(tmp_path, drop=["temp_c"])
    with pytest.raises(LogError) as info:
        open_log(path)
    assert str(info.value) == (
        f"{path}, row 1: missing column temp_c (system temperature, deg C; the features need it)"
    )


def test_missing_sensor_columns(tmp_path):
    path = bad_csv(tmp_path, drop=["dv_y_m_s"])
    with pytest.raises(LogError, match=r"row 1: missing column\(s\) dv_y_m_s: a log needs the increments"):
        open_log(path)


def test_parquet_rows_are_sample_indices(tmp_path):
    cols = static_columns(n=30)
    cols["dtheta_y_rad"][12] = np.nan
    path = tmp_path / "bad.parquet"
    pq.write_table(pa.table(cols), path)
    log = open_log(path, site={"lat_deg": 1.0})
    assert log.rate_source == "time stamps" and log.rate_hz == pytest.approx(RATE)
    with pytest.raises(LogError) as info:
        list(log.chunks(8))
    assert str(info.value) == f"{path}, row 13, column dtheta_y_rad: empty or NaN cell"


def test_unusable_files(tmp_path):
    with pytest.raises(LogError, match=r"nope\.csv: no such file"):
        open_log(tmp_path / "nope.csv")
    (tmp_path / "x.txt").write_text("t_s\n")
    with pytest.raises(LogError, match=r"x\.txt: unknown log format '\.txt'"):
        open_log(tmp_path / "x.txt")
    (tmp_path / "x.parquet").write_text("not parquet")
    with pytest.raises(LogError, match=r"x\.parquet: not a Parquet file"):
        open_log(tmp_path / "x.parquet")
    path = bad_csv(tmp_path)
    with pytest.raises(LogError, match=r"bad\.csv: the log carries no site"):
        open_log(path, site={"height_m": 3.0})


def test_a_binary_csv_log_is_named(tmp_path):
    p = tmp_path / "notcsv.csv"
    p.write_bytes(b"t_s,dtheta_x_rad\n\xff\xfe\x00\x81\x82\n")
    with pytest.raises(LogError, match=r"notcsv.csv: not UTF-8 text"):
        open_log(p, site={"lat_deg": 28.0})
