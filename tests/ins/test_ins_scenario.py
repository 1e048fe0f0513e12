"""Scenario files: defaults, validation with exact messages, unit conversions, round trip."""

import math
import tomllib
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gyrodrift import _core
from gyrodrift.files.toml_writer import dumps_toml
from gyrodrift.ins.scenario import Scenario, ScenarioError, load_scenario, write_scenario_toml
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, DEG_PER_SQRT_H, HOUR, MICRO_G


def write(tmp_path, text, name="scenario.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_empty_file_gives_the_documented_defaults(tmp_path):
    s = load_scenario(write(tmp_path, ""))
    assert (s.site.lat_deg, s.site.lon_deg, s.site.height_m) == (28.222, 112.99, 0.0)
    assert (s.run.duration_h, s.run.rate_hz, s.run.seed) == (16.0, 100.0, 0)
    assert (s.rotation.scheme, s.rotation.rate_deg_s, s.rotation.span_deg, s.rotation.dwell_s) == (
        "reciprocating",
        6.0,
        360.0,
        0.0,
    )
    assert s.rotation.accel_deg_s2 == 100.0
    assert s.gyro.bias_deg_h == (0.0, 0.0, 0.0)
    assert s.temperature.series_t_h is None
    assert s.n_samples == 16 * 3600 * 100


def test_indexing_dwell_defaults_to_300_s(tmp_path):
    s = load_scenario(write(tmp_path, '[rotation]\nscheme = "indexing"\n'))
    assert s.rotation.dwell_s == 300.0
    assert s.rotation.positions_deg == (0.0, 90.0, 180.0, 270.0, 360.0, 270.0, 180.0, 90.0)


def test_scenario_is_frozen():
    s = Scenario()
    with pytest.raises(AttributeError):
        s.site.lat_deg = 0.0  # type: ignore[misc]


BAD = [
    ("[gyro]\nbias_deg_h = [0.001, 0.002]\n", "[gyro] bias_deg_h: expected 3 numbers, got 2"),
    ("[gyro]\nmisalignment_arcsec = [1, 2, 3]\n", "[gyro] misalignment_arcsec: expected 6 numbers, got 3"),
    ("[gyro]\nbias_deg_h = 0.001\n", "[gyro] bias_deg_h: expected 3 numbers, got number 0.001"),
    ('[gyro]\nbias_deg_h = [0, "a", 0]\n', "[gyro] bias_deg_h: element 1: expected a number, got string 'a'"),
    ("[site]\nlat_deg = 95.0\n", "[site] lat_deg: must be between -89 and 89, got 95"),
    ("[site]\nlat_deg = -90\n", "[site] lat_deg: must be between -89 and 89, got -90"),
    ('[site]\nlat_deg = "28.2"\n', "[site] lat_deg: expected a number, got string '28.2'"),
    ("[site]\nlat_deg = nan\n", "[site] lat_deg: expected a finite number, got nan"),
    ("[run]\nduration_h = 0\n", "[run] duration_h: must be > 0, got 0"),
    ("[run]\nduration_h = -1.5\n", "[run] duration_h: must be > 0, got -1.5"),
    ("[run]\nrate_hz = true\n", "[run] rate_hz: expected a number, got boolean True"),
    ("[run]\nseed = 1.5\n", "[run] seed: expected an integer, got number 1.5"),
    ("[run]\nseed = -3\n", "[run] seed: must be >= 0, got -3"),
    ("[rotation]\nrate_deg_s = -6\n", "[rotation] rate_deg_s: must be > 0, got -6"),
    ("[rotation]\ndwell_s = -1\n", "[rotation] dwell_s: must be >= 0, got -1"),
    (
        '[rotation]\nscheme = "spin"\n',
        "[rotation] scheme: expected one of 'none', 'continuous', 'reciprocating', 'indexing', got 'spin'",
    ),
    ("[rotation]\npositions_deg = []\n", "[rotation] positions_deg: expected at least 1 number, got 0"),
    ("[gyro]\narw_deg_rth = -0.001\n", "[gyro] arw_deg_rth: must be >= 0, got -0.001"),
    ("[gyro]\ncorrelation_s = 0\n", "[gyro] correlation_s: must be > 0, got 0"),
    ("[accel]\nvrw_ug_rthz = -1\n", "[accel] vrw_ug_rthz: must be >= 0, got -1"),
    (
        "[gyro]\nbias = [0, 0, 0]\n",
        "[gyro] bias: unknown key (expected one of: bias_deg_h, arw_deg_rth, bias_instability_deg_h, "
        "correlation_s, rrw_deg_h_rth, scale_ppm, misalignment_arcsec)",
    ),
    (
        "[imu]\nrate_hz = 100\n",
        "unknown section [imu] (expected one of: site, run, rotation, gyro, accel, temperature, attitude, trajectory)",
    ),
    ("site = 3\n", "[site] must be a table, got number"),
    ("[attitude]\npitch_deg = 90\n", "[attitude] pitch_deg: must be strictly between -90 and 90, got 90"),
    ("[temperature]\ntau_h = 0\n", "[temperature] tau_h: must be > 0, got 0"),
    (
        "[temperature]\nseries_t_h = [0, 1]\n",
        "[temperature] series_temp_c: missing (required together with series_t_h)",
    ),
    (
        "[temperature]\nseries_t_h = [0, 1]\nseries_temp_c = [20, 21, 22]\n",
        "[temperature] series_temp_c: expected 2 numbers (as series_t_h), got 3",
    ),
    (
        "[temperature]\nseries_t_h = [0, 2, 1]\nseries_temp_c = [20, 21, 22]\n",
        "[temperature] series_t_h: times must be strictly increasing",
    ),
    ("[temperature]\nseries_csv = 3\n", "[temperature] series_csv: expected a file name, got number 3"),
    (
        "[trajectory]\nsegments = [{kind = [1]}]\n",
        "[trajectory] segments[0].kind: expected one of 'straight', 'turn', 'accelerate', 'stop', got [1]",
    ),
    (
        '[trajectory]\nsegments = [{kind = "straight", duration_s = "5"}]\n',
        "[trajectory] segments[0].duration_s: expected a number, got string '5'",
    ),
]


@pytest.mark.parametrize("text, message", BAD, ids=[m[:45] for _, m in BAD])
def test_bad_input_raises_with_file_and_key_in_the_message(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value) == f"{path}: {message}"


def test_missing_file_and_invalid_toml(tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(ScenarioError) as info:
        load_scenario(missing)
    assert str(info.value) == f"{missing}: no such file"
    broken = write(tmp_path, "[site\nlat_deg = 1\n", "broken.toml")
    with pytest.raises(ScenarioError) as info:
        load_scenario(broken)
    assert str(info.value).startswith(f"{broken}: invalid TOML: ")


def test_message_names_a_relative_file_as_given(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write(tmp_path, "[gyro]\nbias_deg_h = [0.001, 0.002]\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario("scenario.toml")
    assert str(info.value) == "scenario.toml: [gyro] bias_deg_h: expected 3 numbers, got 2"


def test_series_csv_is_read_relative_to_the_toml_folder(tmp_path):
    sub = tmp_path / "runs"
    sub.mkdir()
    (sub / "temp.csv").write_text("t_h,temp_c\n0,20.0\n1,25.5\n16,30\n")
    s = load_scenario(write(sub, '[temperature]\nseries_csv = "temp.csv"\n'))
    assert s.temperature.series_t_h == (0.0, 1.0, 16.0)
    assert s.temperature.series_temp_c == (20.0, 25.5, 30.0)
    cfg = s.to_core_config()
    assert cfg.temp_series_t_s == [0.0, 3600.0, 57600.0]
    assert cfg.temp_series_c == [20.0, 25.5, 30.0]


def test_series_csv_errors_name_the_csv(tmp_path):
    path = write(tmp_path, '[temperature]\nseries_csv = "missing.csv"\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value) == f"{path}: [temperature] series_csv: {tmp_path / 'missing.csv'}: no such file"
    (tmp_path / "bad.csv").write_text("t_h,temp_c\n0,20\n1,warm\n")
    path = write(tmp_path, '[temperature]\nseries_csv = "bad.csv"\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value) == (
        f"{path}: [temperature] series_csv: {tmp_path / 'bad.csv'}:3: expected numbers in t_h, temp_c"
    )
    (tmp_path / "cols.csv").write_text("time,T\n0,20\n")
    path = write(tmp_path, '[temperature]\nseries_csv = "cols.csv"\n')
    with pytest.raises(ScenarioError, match="expected columns t_h, temp_c"):
        load_scenario(path)


FULL = """
[site]
lat_deg = 30.5
lon_deg = -10.0
height_m = 120.0
[run]
duration_h = 2.5
rate_hz = 200
seed = 7
[rotation]
scheme = "indexing"
rate_deg_s = 9.0
accel_deg_s2 = 20.0
span_deg = 180.0
positions_deg = [0, 90, 180, 270]
dwell_s = 60
[gyro]
bias_deg_h = [0.01, -0.02, 0.003]
arw_deg_rth = 0.001
bias_instability_deg_h = 0.002
correlation_s = 1800
rrw_deg_h_rth = 0.0001
scale_ppm = [1, 2, 5]
misalignment_arcsec = [1, 2, 3, 4, 5, 6]
[accel]
bias_ug = [50, -50, 20]
vrw_ug_rthz = 10
scale_ppm = [10, 20, 30]
[temperature]
start_c = 15
end_c = 35
tau_h = 2
t0_c = 25
k1_deg_h_per_c = 0.0001
k2_deg_h_per_c2 = 0.00001
k3_deg_h_per_c_per_h = 0.0005
[attitude]
pitch_deg = 1.0
roll_deg = -2.0
yaw_deg = 45.0
"""


def test_unit_conversions_to_the_core_config(tmp_path):
    cfg = load_scenario(write(tmp_path, FULL)).to_core_config()
    close = lambda a, b: pytest.approx(b, rel=1e-14, abs=0)  # noqa: E731
    assert cfg.lat_rad == close(cfg, 30.5 * math.pi / 180)
    assert cfg.lon_rad == close(cfg, -10.0 * math.pi / 180)
    assert cfg.duration_s == 9000.0 and cfg.rate_hz == 200.0 and cfg.seed == 7
    assert cfg.rotation_scheme == "indexing"
    assert cfg.rotation_rate_rad_s == close(cfg, 9 * math.pi / 180)
    assert cfg.positions_rad == pytest.approx([0, math.pi / 2, math.pi, 1.5 * math.pi], rel=1e-15)
    assert cfg.dwell_s == 60.0
    # deg/h -> rad/s: 1 deg/h = pi / 180 / 3600 rad/s = 4.84813681109536e-06 rad/s
    assert cfg.gyro_bias_rad_s == pytest.approx(
        [0.01 * 4.84813681109536e-06, -0.02 * 4.84813681109536e-06, 0.003 * 4.84813681109536e-06], rel=1e-13
    )
    # deg/sqrt(h) -> rad/sqrt(s): divide by sqrt(3600) = 60
    assert cfg.gyro_arw_rad_rts == close(cfg, 0.001 * math.pi / 180 / 60)
    assert cfg.gyro_bias_instability_rad_s == close(cfg, 0.002 * DEG_PER_H)
    assert cfg.gyro_rrw_rad_s_rts == close(cfg, 0.0001 * math.pi / 180 / 3600 / 60)
    assert cfg.gyro_scale == pytest.approx([1e-6, 2e-6, 5e-6], rel=1e-15)
    assert cfg.gyro_misalignment_rad == pytest.approx([k * math.pi / 180 / 3600 for k in range(1, 7)], rel=1e-14)
    # ug -> m/s^2 with 1 ug = 9.80665e-6 m/s^2 exactly
    assert cfg.accel_bias_m_s2 == pytest.approx([50 * 9.80665e-6, -50 * 9.80665e-6, 20 * 9.80665e-6], rel=1e-15)
    assert cfg.accel_vrw_m_s_rts == close(cfg, 10 * 9.80665e-6)
    assert cfg.accel_scale == pytest.approx([1e-5, 2e-5, 3e-5], rel=1e-15)
    assert (cfg.temp_start_c, cfg.temp_end_c, cfg.temp_tau_s, cfg.drift_t0_c) == (15, 35, 7200, 25)
    assert cfg.drift_k1_rad_s_per_c == close(cfg, 1e-4 * DEG_PER_H)
    assert cfg.drift_k2_rad_s_per_c2 == close(cfg, 1e-5 * DEG_PER_H)
    # k3: (deg/h) per (degC/h) -> (rad/s) per (degC/s): a 1 degC/h ramp = 1/3600 degC/s gives the same drift.
    k3 = cfg.drift_k3_rad_s_per_c_per_s
    assert k3 * (1.0 / 3600.0) == close(cfg, 0.0005 * DEG_PER_H)
    assert (cfg.pitch_rad, cfg.roll_rad, cfg.yaw_rad) == pytest.approx((DEG, -2 * DEG, 45 * DEG), rel=1e-15)
    assert cfg.temp_series_t_s is None and cfg.temp_series_c is None


def test_units_module_values_used():
    assert DEG_PER_SQRT_H == pytest.approx(math.pi / 180 / 60, rel=1e-15)
    assert ARCSEC == pytest.approx(math.pi / 648000, rel=1e-15)
    assert MICRO_G == 9.80665e-6 and HOUR == 3600.0


def test_resolved_toml_round_trips(tmp_path):
    s = load_scenario(write(tmp_path, FULL))
    text = dumps_toml(s.to_toml_dict())
    assert Scenario.from_dict(tomllib.loads(text)) == s
    (tmp_path / "temp.csv").write_text("t_h,temp_c\n0,20\n3,22\n")
    s2 = load_scenario(write(tmp_path, '[temperature]\nseries_csv = "temp.csv"\n', "b.toml"))
    d = s2.to_toml_dict()
    assert d["temperature"]["series_t_h"] == [0.0, 3.0] and "series_csv" not in d["temperature"]
    assert Scenario.from_dict(tomllib.loads(dumps_toml(d))) == s2
    write_scenario_toml(s2, tmp_path / "resolved.toml", header="resolved")
    assert load_scenario(tmp_path / "resolved.toml") == s2
    assert (tmp_path / "resolved.toml").read_text().startswith("# resolved\n")


finite = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(
    lat=st.floats(min_value=-_core.MAX_LAT_DEG, max_value=_core.MAX_LAT_DEG),
    bias=st.lists(finite, min_size=3, max_size=3),
    ug=st.lists(finite, min_size=3, max_size=3),
    rate=st.floats(min_value=1.0, max_value=2000.0),
)
def test_round_trip_and_si_conversion_property(lat, bias, ug, rate):
    s = Scenario.from_dict(
        {
            "site": {"lat_deg": lat},
            "gyro": {"bias_deg_h": bias},
            "accel": {"bias_ug": ug},
            "run": {"rate_hz": rate, "duration_h": 0.01},
        }
    )
    assert Scenario.from_dict(tomllib.loads(dumps_toml(s.to_toml_dict()))) == s
    cfg = s.to_core_config()
    for b, si in zip(bias, cfg.gyro_bias_rad_s, strict=False):
        assert si == pytest.approx(b * math.pi / 648000.0, rel=1e-12, abs=1e-300)
    for u, si in zip(ug, cfg.accel_bias_m_s2, strict=False):
        assert si == pytest.approx(u * 9.80665e-6, rel=1e-12, abs=1e-300)


EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def test_example_scenarios_load_and_say_what_they_claim():
    paper = load_scenario(EXAMPLES / "paper_static.toml")
    assert (paper.site.lat_deg, paper.run.duration_h, paper.rotation.scheme) == (28.222, 16.0, "reciprocating")
    axial = load_scenario(EXAMPLES / "axial_drift_only.toml")
    assert axial.gyro.bias_deg_h == (0.0, 0.0, 0.003) and axial.accel.bias_ug == (0.0, 0.0, 0.0)
    horiz = load_scenario(EXAMPLES / "horizontal_errors.toml")
    assert horiz.gyro.bias_deg_h == (0.01, 0.01, 0.0) and horiz.accel.bias_ug == (50.0, 50.0, 0.0)
    assert horiz.run.duration_h == axial.run.duration_h == 72.0
