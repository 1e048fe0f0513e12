"""Scenario limits come from the core (one source), and no scenario file gives anything but a Scenario or a
ScenarioError naming the file and the key: the TOML items of issue 8 and a property test over bytes."""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrodrift import _core
from gyrodrift.ins.scenario import Scenario, ScenarioError, load_scenario

VALID = b"""[site]
lat_deg = 30.5
lon_deg = -10.0
height_m = 120.0

[run]
duration_h = 0.01
rate_hz = 50.0
seed = 7

[rotation]
scheme = "reciprocating"
rate_deg_s = 9.0
span_deg = 180.0
dwell_s = 2.0

[gyro]
bias_deg_h = [0.01, -0.02, 0.003]
arw_deg_rth = 0.001

[accel]
bias_ug = [50.0, -50.0, 20.0]

[temperature]
start_c = 15.0
end_c = 35.0
tau_h = 2.0
k1_deg_h_per_c = 1e-4

[attitude]
pitch_deg = 1.0
yaw_deg = 45.0
"""


def _load(tmp_path: Path, text: str | bytes, name: str = "s.toml") -> Scenario:
    p = tmp_path / name
    p.write_bytes(text.encode() if isinstance(text, str) else text)
    return load_scenario(p)


def _error(tmp_path: Path, text: str | bytes) -> str:
    with pytest.raises(ScenarioError) as info:
        _load(tmp_path, text)
    return str(info.value)


@pytest.mark.parametrize(
    "text,where",
    [
        ("[run]\nrate_hz = 1e308\n", "[run] rate_hz: must be between 1 and 100000"),
        ("[run]\nduration_h = 1e306\n", "[run] duration_h: must be at most 2777.78 h"),
        ("[run]\nrate_hz = " + "9" * 5000 + "\n", "invalid TOML"),
        ("[run]\nseed = " + "9" * 5000 + "\n", "invalid TOML"),
        ("[site]\nlat_deg = " + "9" * 400 + "\n", "[site] lat_deg: expected a finite number, got an integer of"),
        ("[run]\nseed = " + "9" * 400 + "\n", "[run] seed: must be < 2**64, got an integer of"),
        ("[gyro]\nbias_deg_h = " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
        ("[gyro]\nbias_deg_h = [[[0]], 0, 0]\n", "[gyro] bias_deg_h: element 0: expected a number, got array"),
        ("[rotation]\nspan_deg = 1e-300\n", "[rotation] span_deg: the reciprocating period of"),
        (
            '[rotation]\nscheme = "indexing"\npositions_deg = [0, 1e-300]\ndwell_s = 0\n',
            "[rotation] positions_deg: the indexing cycle of",
        ),
        ("[rotation]\nrate_deg_s = 1e300\n", "[rotation] rate_deg_s: must be at most 572.958 deg/s"),
        ("[gyro]\narw_deg_rth = 400\n", "[gyro] arw_deg_rth: angle random walk 400 deg/sqrt(h) is outside"),
        ("[gyro]\nbias_deg_h = [1e5, 0, 0]\n", "[gyro] bias_deg_h: gyro bias (100000, 0, 0) deg/h is outside"),
        ("[accel]\nbias_ug = [2e6, 0, 0]\n", "[accel] bias_ug: accelerometer bias (2000000, 0, 0) ug is outside"),
        ("[site]\nheight_m = 1e5\n", "[site] height_m: must be between -1000 and 20000"),
        (
            '[rotation]\nscheme = "indexing"\npositions_deg = [' + ", ".join(["0, 57000"] * 600) + "]\n",
            "[rotation] positions_deg: 1200 positions, expected 1 to 1000",
        ),
        ("[site]\nlat_deg = 89.5\n", "[site] lat_deg: must be between -89 and 89"),
    ],
)
def test_issue_8_scenario_items_are_scenario_errors(tmp_path, text, where):
    t0 = time.perf_counter()
    msg = _error(tmp_path, text)
    assert msg.startswith(str(tmp_path / "s.toml") + ": ")
    assert where in msg, msg
    assert time.perf_counter() - t0 < 5.0  # refused, not simulated for minutes


def test_non_utf8_and_bad_series_csv_name_the_key(tmp_path):
    (tmp_path / "t.csv").write_bytes(b"t_h,temp_c\n0,20\n1,\xff\xfe21\n")
    msg = _error(tmp_path, '[temperature]\nseries_csv = "t.csv"\n')
    assert "[temperature] series_csv:" in msg and "not UTF-8" in msg, msg
    (tmp_path / "n.csv").write_bytes(b"t_h,temp_c\n0,20\n1,2\x001\n")
    msg = _error(tmp_path, '[temperature]\nseries_csv = "n.csv"\n')
    assert "[temperature] series_csv:" in msg, msg
    (tmp_path / "d.csv").mkdir()
    assert "series_csv" in _error(tmp_path, '[temperature]\nseries_csv = "d.csv"\n')
    (tmp_path / "h.csv").write_text("t_h,temp_c\n0,20\n1,350\n")
    assert "[temperature] series_csv: must be finite and in [-100, 200] deg C" in _error(
        tmp_path, '[temperature]\nseries_csv = "h.csv"\n'
    )


def test_limits_are_the_cores(tmp_path):
    # The edge values the core accepts load; one step beyond is refused by the scenario with its key.
    edge = (
        f"[site]\nlat_deg = {_core.MAX_LAT_DEG}\nheight_m = {_core.MAX_HEIGHT_M}\n"
        f"[run]\nrate_hz = {_core.MIN_RATE_HZ}\n"
    )
    s = _load(tmp_path, edge)
    assert s.site.lat_deg == _core.MAX_LAT_DEG
    s.to_core_config()  # the core takes what the scenario took
    beyond = math.nextafter(_core.MAX_LAT_DEG, 90.0)
    assert "[site] lat_deg" in _error(tmp_path, f"[site]\nlat_deg = {beyond!r}\n")
    assert "[site] height_m" in _error(tmp_path, f"[site]\nheight_m = {_core.MAX_HEIGHT_M + 1}\n")
    assert "[run] rate_hz" in _error(tmp_path, f"[run]\nrate_hz = {_core.MAX_RATE_HZ * 2}\n")


def _mutations(data: bytes):
    """Byte strings near a valid scenario: deletions, insertions and replacements of short runs."""
    pos = st.integers(0, len(data))
    junk = st.binary(min_size=1, max_size=8) | st.sampled_from(
        [b"1e308", b"-", b"[", b"]", b'"', b"=", b"\n", b"9" * 30, b"nan", b"inf", b"0", b"\xff", b"balanced"]
    )
    delete = st.tuples(pos, st.integers(1, 12)).map(lambda t: data[: t[0]] + data[t[0] + t[1] :])
    insert = st.tuples(pos, junk).map(lambda t: data[: t[0]] + t[1] + data[t[0] :])
    replace = st.tuples(pos, junk).map(lambda t: data[: t[0]] + t[1] + data[t[0] + len(t[1]) :])
    return delete | insert | replace


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=200) | _mutations(VALID))
def test_any_bytes_give_a_scenario_or_a_scenario_error(data):
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "fuzz.toml"
        p.write_bytes(data)
        try:
            s = load_scenario(p)
        except ScenarioError as exc:
            assert str(exc).startswith(str(p)), str(exc)
            return
    # Whatever the scenario accepted, the core takes (one source of limits) without simulating.
    sim = _core.ImuSimulator(s.to_core_config())
    assert sim.n_samples == s.n_samples
