"""A log is physically plausible before anything is computed from it (issue 18, item 2).

Every reader passes through `ImuLog.chunks`, which first checks the first `STATIC_CHECK_SPAN_S` seconds against a
static base (`ImuLog.check_static_base`): gravity's magnitude, body up, the Earth rate's horizontal component and,
with the table still, its vertical one. Each unit, scale, sign or axis slip of the issue is built from a simulated
log (a CSV or Parquet in its own format with a wrong format file, or a native log with slipped columns) and must
stop every command with one line naming the check, the measured and expected values and the key or column.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

import gyrodrift
from gyrodrift.cli import main
from gyrodrift.ins import Scenario, simulate
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.logs import (
    STATIC_CHECK_SPAN_S,
    ImplausibleLogError,
    LogError,
    open_log,
)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples" / "logs"
CSV_FORMAT = (EXAMPLES / "ins_export_degs.format.toml").read_text()
PAPER_RUNS = Path(gyrodrift.__file__).parent / "data" / "paper_runs.csv"
LAT = 28.222
SITE = ["--lat0-deg", str(LAT), "--lon0-deg", "112.99", "--height-m", "50"]


def _make_examples():
    spec = importlib.util.spec_from_file_location("make_examples", EXAMPLES / "make_examples.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


MAKE = _make_examples()
SCENARIO = {
    "run": {"duration_h": 0.1, "rate_hz": 10.0, "seed": 21},
    "site": {"lat_deg": LAT, "lon_deg": 112.99, "height_m": 50.0},
    "gyro": {"bias_deg_h": [0.01, -0.01, 0.003], "arw_deg_rth": 0.001},
    "accel": {"bias_ug": [50.0, -40.0, 30.0], "vrw_ug_rthz": 10.0},
    "temperature": {"start_c": 22.0, "end_c": 30.0, "tau_h": 0.05},
    "attitude": {"pitch_deg": 0.3, "roll_deg": -0.2, "yaw_deg": 40.0},
}


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    """A 0.1 h simulated static run at 10 Hz (reciprocating table): native Parquet, its columns, the ';' CSV
    export in deg/s and g (examples/logs/ins_export_degs)."""
    d = tmp_path_factory.mktemp("plaus")
    native = simulate(Scenario.from_dict(SCENARIO), out_dir=d / "sim", quiet=True)
    table = pq.read_table(native)
    cols = {c: table.column(c).to_numpy() for c in table.column_names}
    return d, native, cols, MAKE.to_degs_csv(cols, 10.0, d / "export.csv")


def _fmt(tmp_path, text, name="fmt.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _replace_unit(column, unit):
    """The example format with `column`'s unit changed (the data stay as written)."""
    old = f'[columns.{column}]\nquantity = "{"gyro" if "Gyro" in column else "accel"}_{column[-5].lower()}"\n'
    assert old in CSV_FORMAT
    text = CSV_FORMAT
    start = text.index(old) + len(old)
    end = text.index("\n", start)
    return text[:start] + f'unit = "{unit}"' + text[end:]


def _all(text, sensor, unit=None, extra=""):
    """The example format with every `sensor` ('Gyro' or 'Acc') column's unit replaced and/or `extra` keys added."""
    out = text
    for a in "XYZ":
        col = f"{sensor}{a}_{'dps' if sensor == 'Gyro' else 'g'}"
        marker = f"[columns.{col}]\n"
        i = out.index(marker) + len(marker)
        j = out.index("\n\n", i) if "\n\n" in out[i:] else len(out)
        body = out[i:j]
        if unit is not None:
            body = "\n".join(f'unit = "{unit}"' if ln.startswith("unit") else ln for ln in body.split("\n"))
        out = out[:i] + body + extra + out[j:]
    return out


def _cli(*args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r


def _one_line_refusal(r, *needles):
    """Non-zero exit, one 'Error: ...' line naming every needle, no traceback."""
    assert r.exit_code != 0, r.output
    assert "Traceback" not in r.output
    lines = [ln for ln in r.output.splitlines() if ln.startswith("Error:")]
    assert len(lines) == 1, r.output
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


# ------------------------------------------------------------------------------------------------
# Legitimate logs pass
# ------------------------------------------------------------------------------------------------

SCHEMES = {
    "reciprocating": {"scheme": "reciprocating"},
    "indexing": {"scheme": "indexing"},
    "continuous": {"scheme": "continuous", "rate_deg_s": 10.0},
    "none": {"scheme": "none"},
}


@pytest.mark.parametrize(("lat", "scheme"), list(itertools.product([0.0, -35.0, 60.0, 85.0, 89.0], SCHEMES)))
def test_simulated_logs_pass_at_any_latitude_and_rotation_with_realistic_errors(lat, scheme):
    """Biases 0.5 deg/h and 1 mg (ten to a hundred times a navigation-grade RLG and accelerometer), a 3 deg tilt,
    a 2 km site: every latitude of the core's range and every table scheme pass."""
    s = Scenario.from_dict(
        {
            "run": {"duration_h": STATIC_CHECK_SPAN_S / 3600.0, "rate_hz": 10.0, "seed": 5},
            "site": {"lat_deg": lat, "height_m": 2000.0},
            "rotation": SCHEMES[scheme],
            "gyro": {"bias_deg_h": [0.5, -0.3, 0.2], "arw_deg_rth": 0.01, "scale_ppm": [100, -100, 50]},
            "accel": {"bias_ug": [1000.0, -800.0, 300.0], "vrw_ug_rthz": 20.0},
            "attitude": {"pitch_deg": 2.0, "roll_deg": -2.0, "yaw_deg": 10.0},
        }
    )
    scenario_log(s).check_static_base()  # no error


def test_a_declared_upside_down_mounting_passes_and_an_undeclared_one_is_refused(tmp_path):
    """A simulated log declaring roll 180 deg (its metadata) is what it says; the same data as a CSV, which
    declares nothing, reads 'up' pointing down and is refused."""
    s = Scenario.from_dict({"run": {"duration_h": 0.1, "rate_hz": 10.0}, "attitude": {"roll_deg": 180.0}})
    native = simulate(s, out_dir=tmp_path / "sim", quiet=True)
    open_log(native).check_static_base()
    table = pq.read_table(native)
    cols = ["t_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s", "temp_c"]
    csv = tmp_path / "flipped.csv"
    pq_cols = {c: table.column(c).to_numpy() for c in cols}
    lines = [",".join(cols)] + [",".join(repr(float(pq_cols[c][i])) for c in cols) for i in range(table.num_rows)]
    csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        ImplausibleLogError, match=r"\(specific force points up\): body up is 1[78]\d\.?\d* deg"
    ) as info:
        open_log(csv, site={"lat_deg": 28.222}).check_static_base()
    assert "column(s) dv_z_m_s (body up); a log in other units or axes needs a log format (--format" in str(info.value)


def test_a_moving_base_log_is_checked_over_its_static_part_only(tmp_path):
    """A simulated vehicle standing 0.1 h then driving: the check reads its static part; a 36 s static part is too
    short to check (`MIN_STATIC_CHECK_SPAN_S`) and the driving that follows is never taken for a static base."""
    route = [
        {"kind": "accelerate", "accel_m_s2": 2.0, "duration_s": 5.0},
        {"kind": "turn", "rate_deg_s": 3.0, "duration_s": 60.0},
    ]
    for static_h in (0.1, 0.01):
        s = Scenario.from_dict(
            {
                "run": {"duration_h": 0.3, "rate_hz": 10.0},
                "trajectory": {"static_h": static_h, "segments": route},
            }
        )
        native = simulate(s, out_dir=tmp_path / f"moving{static_h}", quiet=True)
        log = open_log(native)
        assert log.static_s == pytest.approx(static_h * 3600.0)
        log.check_static_base()
        scenario_log(s).check_static_base()


# ------------------------------------------------------------------------------------------------
# Every slip of the issue is refused in one line
# ------------------------------------------------------------------------------------------------

SLIPS = {
    # gyro in deg/s declared deg/h: the Earth rate 3600 times too small
    "gyro deg/s declared deg/h": (
        lambda: _all(CSV_FORMAT, "Gyro", unit="deg/h"),
        [
            "(horizontal Earth rate)",
            "expected 13.08 to 13.42 deg/h",
            "[columns.GyroX_dps] unit/scale (gyro_x, deg/h",
            "[columns.GyroZ_dps] unit/scale",
        ],
    ),
    "gyro scale = 1/3600": (
        lambda: _all(CSV_FORMAT, "Gyro", extra=f"\nscale = {1 / 3600!r}"),
        ["(horizontal Earth rate)", "[columns.GyroY_dps] unit/scale (gyro_y, deg/s"],
    ),
    "gyro deg/s declared rad/s": (
        lambda: _all(CSV_FORMAT, "Gyro", unit="rad/s"),
        ["(horizontal Earth rate)", "[columns.GyroX_dps] unit/scale (gyro_x, rad/s"],
    ),
    "accel g declared m/s^2": (
        lambda: _all(CSV_FORMAT, "Acc", unit="m/s^2"),
        ["(specific force magnitude): measured 0.99", "expected 9.79", "[columns.AccZ_g] unit/scale (accel_z, m/s^2"],
    ),
    "accel mg-sized values declared ug": (  # g written, 'mg' and 'ug' both off by 1000 and 1e6 from it
        lambda: _all(CSV_FORMAT, "Acc", unit="ug"),
        ["(specific force magnitude)", "[columns.AccX_g] unit/scale (accel_x, ug"],
    ),
    "upside-down axes": (
        lambda: CSV_FORMAT.replace('right = "-y"', 'right = "y"').replace('up = "z"', 'up = "-z"'),
        ["(specific force points up): body up is 179.", "[columns.AccZ_g] unit/scale", "[axes] up"],
    ),
    "z gyro sign flipped": (  # the table turns the other way: the de-rotated Earth rate smears away
        lambda: CSV_FORMAT.replace(
            '[columns.GyroZ_dps]\nquantity = "gyro_z"\nunit = "deg/s"',
            '[columns.GyroZ_dps]\nquantity = "gyro_z"\nunit = "deg/s"\nscale = -1.0',
        ),
        ["(horizontal Earth rate)", "de-rotated by the table angle", "[columns.GyroZ_dps] unit/scale"],
    ),
    "one horizontal gyro sign flipped": (  # a mirrored gyro pair sees the Earth rate turn against the table
        lambda: CSV_FORMAT.replace(
            '[columns.GyroX_dps]\nquantity = "gyro_x"\nunit = "deg/s"',
            '[columns.GyroX_dps]\nquantity = "gyro_x"\nunit = "deg/s"\nscale = -1.0',
        ),
        ["(horizontal Earth rate)", "[columns.GyroX_dps] unit/scale"],
    ),
}


@pytest.mark.parametrize("case", list(SLIPS))
def test_each_slip_of_a_formatted_csv_is_one_line_naming_the_check_and_key(sim, tmp_path, case):
    _, _, _, csv_path = sim
    text, needles = SLIPS[case]
    fmt = _fmt(tmp_path, text())
    r = _cli("allan", csv_path, "--format", fmt, *SITE, "--out", tmp_path / "o")
    line = _one_line_refusal(r, f"Error: {csv_path}: not a static base over its first 300 s", *needles, str(fmt))
    assert not (tmp_path / "o").exists(), line  # nothing written


def test_the_correct_format_passes(sim, tmp_path):
    _, _, _, csv_path = sim
    log = open_log(csv_path, format=_fmt(tmp_path, CSV_FORMAT), site={"lat_deg": LAT})
    log.check_static_base()
    assert sum(len(c) for c in log.chunks(1000)) == 3600


def test_an_ug_log_declared_mg_is_refused_by_the_magnitude_limit(sim, tmp_path):
    """Accelerometers written in ug but declared mg read 1000 g: the 100 g limit already names the row."""
    _, _, cols, _ = sim
    d = tmp_path / "ug"
    d.mkdir()
    scaled = dict(cols)
    path = MAKE.to_degs_csv(scaled, 10.0, d / "export.csv")
    text = path.read_text().splitlines()
    out = text[:3]
    for ln in text[3:]:
        cells = ln.split(";")
        cells[4:7] = [repr(float(c) * 1e6) for c in cells[4:7]]
        out.append(";".join(cells))
    path.write_text("\n".join(out) + "\n")
    r = _cli(
        "allan", path, "--format", _fmt(tmp_path, _all(CSV_FORMAT, "Acc", unit="mg")), *SITE, "--out", tmp_path / "o"
    )
    _one_line_refusal(r, "row 4, column AccZ_g (accel_z, mg; body up = +AccZ_g): impossible magnitude")


@pytest.mark.parametrize(
    ("column", "factor", "needle"),
    [
        ("dtheta", 1.0 / 3600.0, "(horizontal Earth rate)"),
        ("dtheta", 180.0 / math.pi, "(horizontal Earth rate)"),
        ("dv", 1.0 / 9.80665, "(specific force magnitude)"),
    ],
)
def test_a_native_parquet_with_slipped_columns_is_refused(sim, tmp_path, column, factor, needle):
    """A native log (no format file) whose sensor columns hold other units: the message names the columns and says
    a log in other units needs --format."""
    _, native, _, _ = sim
    table = pq.read_table(native)
    for a in "xyz":
        name = f"{column}_{a}_{'rad' if column == 'dtheta' else 'm_s'}"
        table = table.set_column(
            table.column_names.index(name), name, pa.array(pq.read_table(native).column(name).to_numpy() * factor)
        )
    path = tmp_path / "slipped.parquet"
    pq.write_table(table, path)
    r = _cli("navigate", path, "--out", tmp_path / "o")
    _one_line_refusal(r, needle, f"{column}_x_", "a log in other units or axes needs a log format (--format FILE")


def test_a_csv_without_the_native_columns_is_told_to_use_a_format(sim):
    _, _, _, csv_path = sim
    with pytest.raises(LogError) as info:
        open_log(csv_path, site={"lat_deg": LAT})
    assert "describe the file's own columns with a log format (--format FILE" in str(info.value)


def test_the_check_runs_before_the_procedure_and_its_refusal_is_remembered_only_on_success(sim, tmp_path):
    """`features` of a slipped 16 h log is refused before the alignment (the first chunk); the same Parquet in its
    right format passes and is not checked twice."""
    d, _, _, _ = sim
    s = Scenario.from_dict(SCENARIO | {"run": {"duration_h": 16.0, "rate_hz": 2.0, "seed": 4}})
    native = simulate(s, out_dir=d / "long", quiet=True)
    pulses = MAKE.to_pulses_parquet(
        {c: pq.read_table(native).column(c).to_numpy() for c in pq.read_table(native).column_names},
        tmp_path / "p.parquet",
    )
    good = (EXAMPLES / "ins_pulses.format.toml").read_text()
    bad = _fmt(tmp_path, good.replace('pulse_unit = "arcsec"', 'pulse_unit = "urad"'), "bad.toml")
    assert bad.read_text() != good
    r = _cli("features", pulses, "--format", bad, *SITE, "--out", tmp_path / "runs.csv", "--quiet")
    _one_line_refusal(r, "(horizontal Earth rate)", "pulse")
    assert not (tmp_path / "runs.csv").exists()
    log = open_log(pulses, format=_fmt(tmp_path, good, "good.toml"), site={"lat_deg": LAT})
    log.check_static_base()
    assert log._static_checked


def test_identify_refuses_a_deg_s_log_declared_deg_h(sim, tmp_path):
    """The issue's first case: `identify` printed an axial drift of -7.11 deg/h, exit 0; now one line, exit 1."""
    d, _, _, _ = sim
    s = Scenario.from_dict(SCENARIO | {"run": {"duration_h": 16.0, "rate_hz": 2.0, "seed": 4}})
    native = simulate(s, out_dir=d / "long_id", quiet=True)
    cols = {c: pq.read_table(native).column(c).to_numpy() for c in pq.read_table(native).column_names}
    csv_path = MAKE.to_degs_csv(cols, 2.0, tmp_path / "export.csv")
    model = tmp_path / "model.json"
    fit = ["fit", PAPER_RUNS, "--lat0-deg", LAT, "--split", "train", "--encoding", "temp_range", "--target", "drift"]
    assert _cli(*fit, "--gamma", 10, "--sigma", 1, "--out", model).exit_code == 0
    fmt = _fmt(tmp_path, _all(CSV_FORMAT, "Gyro", unit="deg/h"))
    r = _cli("identify", csv_path, "--model", model, "--format", fmt, *SITE)
    _one_line_refusal(r, "(horizontal Earth rate)", "deg/h")
    assert "drift" not in r.output.split("Error:")[0]


def test_the_check_reads_only_the_span_chunk_by_chunk(sim, monkeypatch):
    """Streaming: the check reads the first `STATIC_CHECK_SPAN_S` of the log (3000 of 3600 samples here), in chunks of
    at most `DEFAULT_CHUNK_SAMPLES`, and passing is remembered (a second `chunks` does not read it again)."""
    _, native, _, _ = sim
    log = open_log(native)
    seen = []
    source = log._source_blocks

    def counting(chunk_samples):
        for raw in source(chunk_samples):
            seen.append(len(raw.t))
            yield raw

    monkeypatch.setattr(log, "_source_blocks", counting)
    log.check_static_base()
    assert sum(seen) == int(STATIC_CHECK_SPAN_S * 10.0) and max(seen) <= 3000
    seen.clear()
    assert sum(len(c) for c in log.chunks(500)) == 3600 and sum(seen) == 3600  # the stream alone
