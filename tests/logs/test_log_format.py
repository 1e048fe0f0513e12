"""Logs in their own format (gyrodrift.logs.log_format + open_log(format=...)): a simulated log converted into the two
shipped example formats reads back as the original increments and navigates alike; bad format files and bad
cells are named."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gyrodrift.ins import Scenario, simulate
from gyrodrift.logs import LogError, open_log
from gyrodrift.logs.log_format import LogFormat, LogFormatError, load_log_format
from gyrodrift.procedure import navigate

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples" / "logs"
CSV_FORMAT = EXAMPLES / "ins_export_degs.format.toml"
PULSE_FORMAT = EXAMPLES / "ins_pulses.format.toml"


def _make_examples():
    spec = importlib.util.spec_from_file_location("make_examples", EXAMPLES / "make_examples.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


MAKE = _make_examples()
SCENARIO = {
    "run": {"duration_h": 0.1, "rate_hz": 10.0, "seed": 11},
    "site": {"lat_deg": 28.222, "lon_deg": 112.99, "height_m": 50.0},
    "gyro": {"bias_deg_h": [0.005, -0.004, 0.0015], "arw_deg_rth": 0.0005},
    "accel": {"bias_ug": [20.0, -15.0, 10.0], "vrw_ug_rthz": 5.0},
    "temperature": {"start_c": 22.0, "end_c": 30.0, "tau_h": 0.05},
    "attitude": {"pitch_deg": 0.3, "roll_deg": -0.2, "yaw_deg": 40.0},
}


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """A 0.1 h simulated static run (3600 samples at 10 Hz) in the native layout and in both example formats."""
    d = tmp_path_factory.mktemp("fmt")
    scn = Scenario.from_dict(SCENARIO)
    native = simulate(scn, out_dir=d / "sim", quiet=True)
    table = pq.read_table(native)
    cols = {c: table.column(c).to_numpy() for c in table.column_names}
    csv_path = MAKE.to_degs_csv(cols, 10.0, d / "export.csv")
    pq_path = MAKE.to_pulses_parquet(cols, d / "pulses.parquet")
    return scn, native, cols, csv_path, pq_path


def _whole(log, chunk=777):
    parts = list(log.chunks(chunk))
    return (
        np.concatenate([p.t_s for p in parts]),
        np.concatenate([p.dtheta_rad for p in parts]),
        np.concatenate([p.dv_m_s for p in parts]),
        np.concatenate([p.temp_c for p in parts]),
    )


def test_the_degs_csv_reads_back_as_the_original_increments(simulated):
    _, _, cols, csv_path, _ = simulated
    log = open_log(csv_path, format=CSV_FORMAT, site={"lat_deg": 28.222})
    assert (log.kind, log.rate_hz, log.n_samples) == ("rates", 10.0, len(cols["t_s"]))
    t, dth, dv, temp = _whole(log)
    np.testing.assert_allclose(t, cols["t_s"], atol=1e-9)
    for j, a in enumerate("xyz"):  # repr floats: exact to a few ulps after deg/s -> rad and the axis swap
        np.testing.assert_allclose(dth[:, j], cols[f"dtheta_{a}_rad"], rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(dv[:, j], cols[f"dv_{a}_m_s"], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(temp, cols["temp_c"], atol=5e-5)  # written with 4 decimals


def test_the_pulse_parquet_reads_back_as_the_original_increments_to_one_pulse(simulated):
    _, _, cols, _, pq_path = simulated
    log = open_log(pq_path, format=PULSE_FORMAT, site={"lat_deg": 28.222})
    assert (log.kind, log.rate_hz, log.n_samples) == ("increments", 10.0, len(cols["t_s"]))
    t, dth, dv, temp = _whole(log)
    np.testing.assert_allclose(t, cols["t_s"] - cols["t_s"][0], atol=1e-9)  # ISO: seconds since the first sample
    arcsec = math.pi / 180.0 / 3600.0
    for j, a in enumerate("xyz"):
        # each sample within one pulse, and the running sum within half a pulse (the counter keeps its remainder)
        assert np.max(np.abs(dth[:, j] - cols[f"dtheta_{a}_rad"])) <= 0.01 * arcsec * (1 + 1e-9)
        assert np.max(np.abs(np.cumsum(dth[:, j]) - np.cumsum(cols[f"dtheta_{a}_rad"]))) <= 0.005 * arcsec * 1.001
        assert np.max(np.abs(np.cumsum(dv[:, j]) - np.cumsum(cols[f"dv_{a}_m_s"]))) <= 0.005e-3 * 1.001
    np.testing.assert_allclose(temp, cols["temp_c"], atol=6e-4)  # kelvin with 3 decimals


def test_navigation_of_each_format_matches_the_native_log(simulated):
    scn, native, _, csv_path, pq_path = simulated
    a = scn.attitude
    initial = {
        "lat_deg": 28.222,
        "lon_deg": 112.99,
        "height_m": 50.0,
        "pitch_deg": a.pitch_deg,
        "roll_deg": a.roll_deg,
        "yaw_deg": a.yaw_deg,
    }
    site = {"lat_deg": 28.222, "lon_deg": 112.99, "height_m": 50.0}
    ref = navigate(open_log(native, require_temperature=False), initial=initial)
    for path, fmt, tol_arcsec in ((csv_path, CSV_FORMAT, 1e-6), (pq_path, PULSE_FORMAT, 2e-3)):
        got = navigate(open_log(path, format=fmt, site=site, require_temperature=False), initial=initial)
        for c in ("lat_err_arcsec", "lon_err_arcsec"):
            np.testing.assert_allclose(got[c], ref[c], atol=tol_arcsec)
        assert got.summary["final_pos_err_nmi"] == pytest.approx(ref.summary["final_pos_err_nmi"], abs=1e-4)


def test_the_shipped_examples_open_with_their_formats():
    for log_name, fmt in (("ins_export_degs.csv", CSV_FORMAT), ("ins_pulses.parquet", PULSE_FORMAT)):
        log = open_log(EXAMPLES / log_name, format=fmt, site={"lat_deg": 28.222})
        chunk = next(log.chunks(50))
        assert log.rate_hz == 10.0 and log.n_samples == 1200
        # static, z up: the accelerometers' z increments are about +g * dt, and the table turns about z
        assert np.all(np.abs(chunk.dv_m_s[:, 2] - 9.79 * 0.1) < 0.01)
        assert np.all(np.abs(chunk.dv_m_s[:, :2]) < 0.002)


def _fmt(**over):
    base = load_log_format(CSV_FORMAT)
    data = {
        "csv": {"delimiter": ";", "header_row": 3, "comment": "#"},
        "axes": {"right": "-y", "forward": "x", "up": "z"},
        "columns": {c.name: {"quantity": c.quantity, "unit": c.unit} for c in base.columns},
    }
    for k, v in over.items():
        data[k] = v
    return data


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"extra": {}}, "<t>: [extra]: unknown section (expected one of: csv, axes, columns)"),
        ({"csv": {"delim": ";"}}, "<t>: [csv] delim: unknown key (expected one of: delimiter, header_row, comment)"),
        ({"csv": {"delimiter": ";;"}}, "<t>: [csv] delimiter: expected one character"),
        ({"axes": {"right": "y", "forward": "x", "up": "z"}}, "<t>: [axes]: the mapping is a mirror"),
        ({"axes": {"right": "x", "forward": "x", "up": "z"}}, "<t>: [axes]: each file axis once"),
        ({"axes": {"right": "w"}}, "<t>: [axes] right: expected a file axis with an optional sign"),
    ],
)
def test_format_file_errors_name_the_key(change, message):
    with pytest.raises(LogFormatError) as err:
        LogFormat.from_dict(_fmt(**change), "<t>")
    assert str(err.value).startswith(message)


def test_column_errors_name_the_column_and_key():
    d = _fmt()
    d["columns"]["GyroX_dps"] = {"quantity": "gyro_x", "unit": "deg/min"}
    with pytest.raises(LogFormatError, match=r"<t>: \[columns.GyroX_dps\] unit: expected one of .*deg/s.*'deg/min'"):
        LogFormat.from_dict(d, "<t>")
    d = _fmt()
    d["columns"]["GyroX_dps"]["gain"] = 2
    with pytest.raises(LogFormatError, match=r"\[columns.GyroX_dps\] gain: unknown key"):
        LogFormat.from_dict(d, "<t>")
    d = _fmt()
    d["columns"]["GyroX_dps"]["unit"] = "deg"
    with pytest.raises(LogFormatError, match=r"mixed increments \(GyroX_dps\) and rates"):
        LogFormat.from_dict(d, "<t>")
    d = _fmt()
    del d["columns"]["AccZ_g"]
    with pytest.raises(LogFormatError, match=r"\[columns\]: no column for accel_z"):
        LogFormat.from_dict(d, "<t>")
    d = _fmt()
    d["columns"]["GyroX_dps"] = {"quantity": "gyro_x", "unit": "pulse", "pulse_weight": 0.1}
    with pytest.raises(LogFormatError, match=r"needs pulse_weight \(a number > 0\) and pulse_unit"):
        LogFormat.from_dict(d, "<t>")


@pytest.mark.parametrize(
    ("column", "message"),
    [
        ({"quantity": ["gyro_x"], "unit": "deg/s"}, "<t>: [columns.GyroX_dps] quantity: expected one of time, gyro_x"),
        ({"quantity": "gyro_x", "unit": {}}, "<t>: [columns.GyroX_dps] unit: expected one of rad, mrad"),
        (
            {"quantity": "gyro_x", "unit": "pulse", "pulse_weight": 1, "pulse_unit": []},
            "<t>: [columns.GyroX_dps] pulse_unit: expected one of rad, mrad, urad, deg, arcsec, got []",
        ),
        ({"quantity": "gyro_x", "unit": "deg/s", "scale": "2"}, "<t>: [columns.GyroX_dps] scale: expected a number"),
        ({"quantity": "gyro_x", "unit": "deg/s", "scale": 0}, "<t>: [columns.GyroX_dps] scale: must not be 0"),
    ],
)
def test_a_column_of_the_wrong_shape_is_a_format_error_naming_the_key(column, message):
    d = _fmt()
    d["columns"]["GyroX_dps"] = column
    with pytest.raises(LogFormatError) as err:
        LogFormat.from_dict(d, "<t>")
    assert str(err.value).startswith(message)


def test_a_format_file_that_is_not_toml_names_the_file(tmp_path):
    bad = tmp_path / "f.toml"
    bad.write_text("[csv\n")
    with pytest.raises(LogFormatError, match=r"f.toml: invalid TOML"):
        load_log_format(bad)
    with pytest.raises(LogFormatError, match=r"nothere.toml: no such file"):
        open_log(EXAMPLES / "ins_export_degs.csv", format=tmp_path / "nothere.toml")


def _export(tmp_path, lines_after_header: list[str]) -> Path:
    text = (EXAMPLES / "ins_export_degs.csv").read_text().splitlines()
    p = tmp_path / "x.csv"
    p.write_text("\n".join(text[:3] + lines_after_header + text[3 + len(lines_after_header) :]) + "\n")
    return p


def test_bad_cells_name_the_files_own_line_and_column(tmp_path):
    text = (EXAMPLES / "ins_export_degs.csv").read_text().splitlines()
    row = text[12].split(";")  # file line 13
    row[2] = "abc"
    text[12] = ";".join(row)
    text.insert(8, "# a comment in the middle is skipped")  # line numbers below it move by one
    p = tmp_path / "bad.csv"
    p.write_text("\n".join(text) + "\n")
    log = open_log(p, format=CSV_FORMAT, site={"lat_deg": 28.222})
    with pytest.raises(LogError) as err:
        list(log.chunks(100))
    assert str(err.value) == f"{p}, row 14, column GyroY_dps (gyro_y, deg/s): expected a number, got 'abc'"

    text = (EXAMPLES / "ins_export_degs.csv").read_text().splitlines()
    row = text[20].split(";")  # file line 21: GyroZ (body up) at an impossible rate
    row[3] = "5000"
    text[20] = ";".join(row)
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(LogError) as err:
        list(open_log(p, format=CSV_FORMAT, site={"lat_deg": 28.222}).chunks(100))
    assert str(err.value).startswith(
        f"{p}, row 21, column GyroZ_dps (gyro_z, deg/s; body up = +GyroZ_dps): impossible magnitude: angular rate "
        "5000 deg/s"
    )


def test_a_missing_column_names_the_file_columns(tmp_path):
    text = (EXAMPLES / "ins_export_degs.csv").read_text().replace("AccY_g", "AccY")
    p = tmp_path / "renamed.csv"
    p.write_text(text)
    with pytest.raises(LogError) as err:
        open_log(p, format=CSV_FORMAT, site={"lat_deg": 28.222})
    assert str(err.value).startswith(f"{p}, row 3: no column 'AccY_g' (the accel_y column of the log format ")
    assert "the file's columns are: Time_ms, GyroX_dps" in str(err.value)


def test_a_bad_iso_time_stamp_is_named(tmp_path):
    t = pq.read_table(EXAMPLES / "ins_pulses.parquet")
    times = t.column("timestamp").cast(pa.string()).to_pylist()
    times[5] = "yesterday"
    p = tmp_path / "iso.parquet"
    pq.write_table(t.set_column(0, "timestamp", pa.array(times, pa.string())), p)
    with pytest.raises(LogError, match=r"iso.parquet, row 6, column timestamp \(time, iso\): expected an ISO 8601"):
        list(open_log(p, format=PULSE_FORMAT, site={"lat_deg": 28.222}).chunks(100))


def test_navigate_cli_reads_a_formatted_log_and_plots(simulated, tmp_path):
    """`navigate --format --plot`: the true attitude columns named by the format start the navigation, the figure is
    published with nav.parquet, and the errors equal those of the native log."""
    from click.testing import CliRunner

    from gyrodrift.cli import main

    _, native, _, _, pq_path = simulated
    table = pq.read_table(pq_path)
    truth = pq.read_table(native, columns=["true_pitch_deg", "true_roll_deg", "true_yaw_deg"])
    for c in truth.column_names:
        table = table.append_column(c, truth.column(c))
    log = tmp_path / "with_truth.parquet"
    pq.write_table(table, log)
    fmt = tmp_path / "fmt.toml"
    fmt.write_text(
        PULSE_FORMAT.read_text()
        + "".join(f'\n[columns.true_{q}_deg]\nquantity = "true_{q}"\nunit = "deg"\n' for q in ("pitch", "roll", "yaw"))
    )
    site = ["--lat0-deg", "28.222", "--lon0-deg", "112.99", "--height-m", "50"]
    r = CliRunner().invoke(
        main, ["navigate", str(log), "--format", str(fmt), *site, "--plot", "--out", str(tmp_path / "o")]
    )
    assert r.exit_code == 0, r.output
    assert "navigation.png" in r.output and "initial state from the log's truth" in r.output
    assert (tmp_path / "o" / "navigation.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    got = pq.read_table(tmp_path / "o" / "nav.parquet")
    ref = navigate(open_log(native, require_temperature=False), initial="truth")
    # the native log starts from its scenario metadata at t = 0, the formatted one from its first truth row
    # (one sample later): both stay far below 0.01 arcsec of each other over 0.1 h
    lat = got.column("lat_err_arcsec").to_numpy()
    assert len(lat) >= len(ref["lat_err_arcsec"]) - 1
    np.testing.assert_allclose(lat, ref["lat_err_arcsec"][: len(lat)], atol=0.02)
    assert got.column("yaw_err_arcsec").null_count == 0


def test_features_of_a_formatted_log_equal_the_native_logs(tmp_path):
    """The procedure reads through the same reader: features (alignment + navigation) of the ';' CSV export in
    deg/s and g equal those of the native log (the CLI's --format goes the same way)."""
    from gyrodrift.fleet.features import features_table
    from gyrodrift.procedure.timeline import Timeline

    scn = Scenario.from_dict({**SCENARIO, "run": {"duration_h": 1.15, "rate_hz": 5.0, "seed": 4}})
    native = simulate(scn, out_dir=tmp_path / "sim", quiet=True)
    table = pq.read_table(native)
    csv_path = MAKE.to_degs_csv({c: table.column(c).to_numpy() for c in table.column_names}, 5.0, tmp_path / "x.csv")
    short = Timeline(align_h=0.1, features_h=1.0, truth_h=1.0, coarse_s=60.0)
    site = {"lat_deg": 28.222, "lon_deg": 112.99, "height_m": 50.0}
    (ref,) = features_table([native], timeline=short)
    (got,) = features_table([csv_path], log_format=CSV_FORMAT, site=site, timeline=short)
    assert got.lat_deg == pytest.approx(ref.lat_deg, abs=1e-10)
    assert got.lat_err_arcsec == pytest.approx(ref.lat_err_arcsec, abs=1e-5)
    assert got.temp_end_c == pytest.approx(ref.temp_end_c, abs=1e-4)


def test_spaces_around_the_files_column_names_are_ignored(tmp_path):
    lines = (EXAMPLES / "ins_export_degs.csv").read_text().splitlines()
    lines[2] = "; ".join(f" {name}" for name in lines[2].split(";"))
    p = tmp_path / "spaced.csv"
    p.write_text("\n".join(lines) + "\n")
    ref = _whole(open_log(EXAMPLES / "ins_export_degs.csv", format=CSV_FORMAT, site={"lat_deg": 28.222}))
    got = _whole(open_log(p, format=CSV_FORMAT, site={"lat_deg": 28.222}))
    for a, b in zip(got, ref, strict=True):
        np.testing.assert_array_equal(a, b)


def test_iso_time_stamps_in_a_csv(tmp_path):
    """ISO 8601 text time stamps (with Z) read as seconds since the first sample; a bad one is named by line."""
    lines = (EXAMPLES / "ins_export_degs.csv").read_text().splitlines()
    start = np.datetime64("2024-05-01T08:00:00", "ms")
    out = lines[:3]
    for line in lines[3:]:
        cells = line.split(";")
        cells[0] = str(start + np.timedelta64(int(cells[0]), "ms")) + "Z"
        out.append(";".join(cells))
    p = tmp_path / "iso.csv"
    p.write_text("\n".join(out) + "\n")
    fmt = tmp_path / "iso.toml"
    fmt.write_text(CSV_FORMAT.read_text().replace('unit = "ms"', 'unit = "iso"'))
    site = {"lat_deg": 28.222}
    t, dth, dv, _ = _whole(open_log(p, format=fmt, site=site), chunk=300)
    t_ref, dth_ref, dv_ref, _ = _whole(open_log(EXAMPLES / "ins_export_degs.csv", format=CSV_FORMAT, site=site))
    np.testing.assert_allclose(t, t_ref - t_ref[0], atol=1e-9)
    np.testing.assert_array_equal(dth, dth_ref)
    out[700] = "2024-05-01 nonsense;" + out[700].split(";", 1)[1]  # file line 701
    p.write_text("\n".join(out) + "\n")
    with pytest.raises(LogError, match=r"iso.csv, row 701, column Time_ms \(time, iso\): expected an ISO 8601"):
        list(open_log(p, format=fmt, site=site).chunks(300))
