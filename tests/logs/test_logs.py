"""IMU logs (gyrodrift.logs): formats, kind and rate detection, streaming, and one exact message per bad log."""

from __future__ import annotations

import math
import os

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gyrodrift.errors import OptionError
from gyrodrift.ins import Scenario, simulate
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.logs import INCREMENT_COLUMNS, RATE_COLUMNS, ImuLog, LogError, open_log
from gyrodrift.site import Site

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


def test_parquet_from_the_simulator_streams_the_same_samples_as_pyarrow_reads(sim_parquet):
    log = open_log(sim_parquet)
    assert (log.format, log.kind, log.rate_hz, log.n_samples) == ("parquet", "increments", RATE, 7200)
    assert log.rate_source == "metadata"
    assert log.site == Site(30.0, 100.0, 40.0)
    assert log.name == sim_parquet.parent.name  # imu.parquet is named after its folder
    t, dth, dv, temp, parts = whole(log)
    ref = pq.read_table(sim_parquet)
    np.testing.assert_array_equal(t, ref.column("t_s").to_numpy())
    np.testing.assert_array_equal(dth, np.column_stack([ref.column(c).to_numpy() for c in INCREMENT_COLUMNS[:3]]))
    np.testing.assert_array_equal(dv, np.column_stack([ref.column(c).to_numpy() for c in INCREMENT_COLUMNS[3:]]))
    true_deg = np.concatenate([p.true_deg for p in parts])
    np.testing.assert_array_equal(true_deg[:, 2], ref.column("true_yaw_deg").to_numpy())
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
    assert open_log(sim_parquet, site=Site(1.0, 0.0, 0.0)).site == Site(1.0, 0.0, 0.0)


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
    header = ",".join(["t_s", *INCREMENT_COLUMNS, "temp_c"]).encode()
    p.write_bytes(header + b"\n\xff\xfe\x00\x81\x82\n")
    with pytest.raises(LogError, match=r"notcsv.csv, row 2: not UTF-8 text \(byte 0xff at character 1\)"):
        open_log(p, site={"lat_deg": 28.0})


# ------------------------------------------------------------------------------------------------
# Hostile inputs (issue 8): one clear LogError each, never another exception, never a hang
# ------------------------------------------------------------------------------------------------


def good_table(n=60):
    return pa.table(static_columns(n=n))


def test_csv_header_with_spaces_around_the_names_is_read(tmp_path):
    cols = static_columns()
    path = write_csv(tmp_path / "spaced.csv", {f" {c} ": v for c, v in cols.items()})
    t, dth, _, temp, _ = whole(open_log(path, site={"lat_deg": 1.0}))
    np.testing.assert_array_equal(t, cols["t_s"])
    np.testing.assert_array_equal(dth[:, 1], cols["dtheta_y_rad"])
    np.testing.assert_array_equal(temp, cols["temp_c"])


def test_duplicated_parquet_column_is_refused(tmp_path):
    table = good_table()
    dup = pa.Table.from_arrays([*table.columns, table.column("dv_x_m_s")], names=[*table.column_names, "dv_x_m_s"])
    pq.write_table(dup, tmp_path / "dup.parquet")
    with pytest.raises(LogError, match=r"dup\.parquet, row 1: column dv_x_m_s appears more than once"):
        open_log(tmp_path / "dup.parquet", site={"lat_deg": 1.0})


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("1e400", r"gyrodrift\.rate_hz metadata must be in \[1, 100000\] Hz, got inf"),
        ("[5]", r"gyrodrift\.rate_hz metadata must be a number in Hz, got \[5\]"),
        ("true", r"gyrodrift\.rate_hz metadata must be a number in Hz, got True"),
        ("-10", r"gyrodrift\.rate_hz metadata must be in \[1, 100000\] Hz, got -10"),
        ("{", r"unreadable gyrodrift\.rate_hz metadata"),
    ],
)
def test_unusable_rate_metadata(tmp_path, value, message):
    path = tmp_path / "rate.parquet"
    pq.write_table(good_table().replace_schema_metadata({"gyrodrift.rate_hz": value}), path)
    with pytest.raises(LogError, match=message):
        open_log(path, site={"lat_deg": 1.0})


def test_damaged_data_pages_with_an_intact_footer(tmp_path):
    path = tmp_path / "damaged.parquet"
    pq.write_table(good_table(n=200), path, compression="none", row_group_size=50)
    offset = pq.ParquetFile(path).metadata.row_group(2).column(3).data_page_offset
    data = bytearray(path.read_bytes())
    for k in range(offset, offset + 64):
        data[k] ^= 0x5A
    path.write_bytes(bytes(data))
    log = open_log(path, site={"lat_deg": 1.0})  # the footer still reads
    with pytest.raises(LogError, match=r"damaged\.parquet, row 101: damaged Parquet data after sample 100"):
        list(log.chunks(50))


def test_csv_row_with_the_wrong_number_of_cells_names_the_row(tmp_path):
    path = bad_csv(tmp_path)
    lines = path.read_text().splitlines()
    lines[30] = "3.0,1,2"
    path.write_text("\n".join(lines) + "\n")
    assert stream_error(path) == f"{path}, row 31: 3 cells, expected 8 (one per header column)"


def test_non_utf8_byte_late_in_a_csv_names_the_row(tmp_path):
    path = bad_csv(tmp_path, n=3000)
    data = path.read_bytes().splitlines(keepends=True)
    data[2500] = data[2500].replace(b"25.0", b"2\xff5.0")
    path.write_bytes(b"".join(data))
    column = data[2500].index(b"\xff") + 1
    assert stream_error(path, chunk_samples=1000) == (
        f"{path}, row 2501: not UTF-8 text (byte 0xff at character {column}); expected a CSV log"
    )


def test_devices_fifos_and_folders_are_refused_without_blocking(tmp_path):
    with pytest.raises(LogError, match=r"/dev/zero: not a regular file"):
        open_log("/dev/zero")
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    with pytest.raises(LogError, match=r"pipe\.csv: not a regular file \(a device, FIFO or socket\)"):
        open_log(fifo)  # opening a FIFO for reading would block until a writer comes
    (tmp_path / "dir.parquet").mkdir()
    with pytest.raises(LogError, match=r"dir\.parquet: is a folder"):
        open_log(tmp_path / "dir.parquet")


def test_bool_or_text_parquet_columns_are_refused(tmp_path):
    table = good_table()
    i = table.schema.get_field_index("dtheta_x_rad")
    pq.write_table(table.set_column(i, "dtheta_x_rad", pa.array(np.zeros(60, bool))), tmp_path / "b.parquet")
    with pytest.raises(LogError, match=r"b\.parquet, column dtheta_x_rad: expected numbers \(float64\), got .* bool"):
        open_log(tmp_path / "b.parquet", site={"lat_deg": 1.0})
    pq.write_table(table.set_column(i, "dtheta_x_rad", pa.array(["0"] * 60)), tmp_path / "s.parquet")
    with pytest.raises(LogError, match=r"s\.parquet, column dtheta_x_rad: expected numbers"):
        open_log(tmp_path / "s.parquet", site={"lat_deg": 1.0})


@pytest.mark.parametrize("temp", [303.15, 1e6, -273.0])
def test_temperatures_outside_the_run_table_limits_are_refused(tmp_path, temp):
    """The same limits as the run tables (gyrodrift.runs.table.TEMPERATURE_LIMITS_C): a kelvin value is refused."""
    from gyrodrift.runs.table import TEMPERATURE_LIMITS_C

    assert TEMPERATURE_LIMITS_C == (-100.0, 200.0)

    def warm(c):
        c["temp_c"][44] = temp

    assert stream_error(bad_csv(tmp_path, tweak=warm)) == (
        f"{tmp_path / 'bad.csv'}, row 46, column temp_c: temperature {temp:.6g} deg C is outside [-100, 200] deg C "
        "(a system temperature in deg C, not kelvin)"
    )


def test_the_rate_limit_is_the_same_for_every_source(tmp_path):
    """A 2865 deg/s spike is refused by the file reader and by the in-memory source alike."""
    cols = static_columns()
    cols["dtheta_z_rad"][20] = math.radians(2865.0) / RATE
    pq.write_table(pa.table(cols), tmp_path / "spike.parquet")
    expected = "row 21, column dtheta_z_rad: impossible magnitude: angular rate 2865 deg/s exceeds 1000 deg/s"
    with pytest.raises(LogError, match=expected):
        list(open_log(tmp_path / "spike.parquet", site={"lat_deg": 1.0}).chunks(16))
    with pytest.raises(LogError, match=expected):
        list(ImuLog.from_arrays(cols, rate_hz=RATE).chunks(16))


@pytest.mark.parametrize(
    ("site", "flag"), [({"lat_deg": math.nan}, "--lat0-deg"), ({"lon_deg": math.inf}, "--lon0-deg")]
)
def test_non_finite_site_values_name_the_option(sim_parquet, site, flag):
    with pytest.raises(OptionError, match=rf"{flag} \(\w+\): expected a finite number"):
        open_log(sim_parquet, site=site)


def test_the_site_must_lie_within_the_cores_limits(sim_parquet, tmp_path):
    """The reader refuses the sites the core would refuse, naming the option or the file (not a core key)."""
    with pytest.raises(OptionError, match=r"--lat0-deg \(lat_deg\): 89\.5 deg is outside \[-89, 89\] deg"):
        open_log(sim_parquet, site={"lat_deg": 89.5})
    with pytest.raises(OptionError, match=r"--height-m \(height_m\): 50000\.0 m is outside \[-1000, 20000\] m"):
        open_log(sim_parquet, site={"height_m": 50000.0})
    table = pq.read_table(sim_parquet)
    meta = {**table.schema.metadata, b"gyrodrift.site": b'{"lat_deg": 89.5, "lon_deg": 0, "height_m": 0}'}
    pq.write_table(table.replace_schema_metadata(meta), tmp_path / "polar.parquet")
    with pytest.raises(LogError, match=r"polar\.parquet: the site's lat_deg 89\.5 deg is outside \[-89, 89\] deg"):
        open_log(tmp_path / "polar.parquet")


def test_one_site_class_for_scenarios_and_logs(sim_parquet):
    from gyrodrift.ins import Site as InsSite

    assert InsSite is Site
    assert open_log(sim_parquet, site=InsSite(10.0, 20.0, 30.0)).site == Site(10.0, 20.0, 30.0)


def test_the_scenario_source_streams_what_the_simulator_writes(sim_parquet):
    import json

    meta = pq.ParquetFile(sim_parquet).schema_arrow.metadata
    scn = Scenario.from_dict(json.loads(meta[b"gyrodrift.scenario"]))
    on_the_fly = scenario_log(scn)
    assert (on_the_fly.rate_hz, on_the_fly.n_samples, on_the_fly.site) == (RATE, 7200, Site(30.0, 100.0, 40.0))
    a, b = whole(on_the_fly, 1000), whole(open_log(sim_parquet), 1000)
    for x, y in zip(a[:4], b[:4], strict=True):
        np.testing.assert_array_equal(x, y)
