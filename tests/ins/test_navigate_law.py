"""Compensating a drift law sample by sample (issue 21 item 2): `gyrodrift.ins.compensation`, ``navigate`` and
``evaluate`` with a `DriftLaw`.

The simulator adds k1 (T - t0) to the z gyro on the scenario's temperature ([temperature] k1_deg_h_per_c, t0_c), so
its own law is known exactly: eps_ref = the z bias at T_ref = t0 with the scenario's k1. Compensating it must leave
the navigation of a run without any axial drift (the same noise, seed for seed), while no constant can.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from gyrodrift import _core
from gyrodrift.cli import main
from gyrodrift.drift_law import DriftLaw
from gyrodrift.earth import NMI_M
from gyrodrift.errors import InputError
from gyrodrift.ins import Scenario
from gyrodrift.ins.compensation import AxialBias, load_drift_law
from gyrodrift.ins.nav_errors import radii_of_curvature
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.ins.stream import run_navigators
from gyrodrift.procedure import navigate
from gyrodrift.units import ARCSEC, DEG_PER_H

BIAS_Z = 0.004
"""The z gyro bias at t0 [deg/h]."""
K1 = 3e-4
"""The simulated thermal coefficient [deg/h/degC]: 20 -> 40 degC moves the drift by 0.006 deg/h."""


def _scenario(thermal: bool, *, hours: float = 72.0, k3: float = 0.0) -> Scenario:
    d = {
        "run": {"duration_h": hours, "rate_hz": 10.0, "seed": 3},
        "rotation": {"scheme": "reciprocating", "rate_deg_s": 6.0},
        "gyro": {"bias_deg_h": [0.0, 0.0, BIAS_Z if thermal else 0.0], "arw_deg_rth": 0.0002},
    }
    if thermal:
        d["temperature"] = {
            "start_c": 20.0,
            "end_c": 40.0,
            "tau_h": 6.0,
            "k1_deg_h_per_c": K1,
            "k3_deg_h_per_c_per_h": k3,
            "t0_c": 20.0,
        }
    return Scenario.from_dict(d, source="<test_navigate_law>")


SIMULATOR_LAW = DriftLaw(eps_ref_deg_h=BIAS_Z, t_ref_c=20.0, k1_deg_h_per_c=K1)


def _north_east_m(result) -> np.ndarray:
    """The (north, east) position errors [m] of a navigation, (m, 2)."""
    lat = math.radians(float(result.summary["truth"]["lat_deg"]))
    r_m, r_n = radii_of_curvature(lat)
    return np.column_stack(
        [result["lat_err_arcsec"] * ARCSEC * r_m, result["lon_err_arcsec"] * ARCSEC * r_n * math.cos(lat)]
    )


def test_compensating_the_simulators_own_law_leaves_the_noise_floor_and_no_constant_does():
    floor = navigate(_scenario(False), decimation_s=60.0)  # the same noise, no axial drift at all
    law = navigate(_scenario(True), drift_law=SIMULATOR_LAW, decimation_s=60.0)
    excess_law = np.max(np.hypot(*(_north_east_m(law) - _north_east_m(floor)).T)) / NMI_M
    assert excess_law < 1e-4  # what the law leaves beyond the noise over the 72 h [nmi]
    assert law.summary["final_pos_err_nmi"] == pytest.approx(floor.summary["final_pos_err_nmi"], abs=1e-4)
    assert law.summary["compensation"] == "law" and law.summary["drift_law"] == SIMULATOR_LAW.to_dict()

    # The best constant, by brute force over a fine grid: the errors are linear in the compensated constant
    # (two navigations give the line; a third at the best constant checks it).
    c0, c1 = 0.0, 0.012
    e0 = _north_east_m(navigate(_scenario(True), drift_law=DriftLaw.constant(c0), decimation_s=60.0))
    e1 = _north_east_m(navigate(_scenario(True), drift_law=DriftLaw.constant(c1), decimation_s=60.0))
    grid = np.linspace(c0, c1, 1201)
    floor_ne = _north_east_m(floor)

    def excess(e: np.ndarray) -> float:
        return float(np.max(np.hypot(*(e - floor_ne).T)) / NMI_M)

    predicted = [excess(e0 + (c - c0) / (c1 - c0) * (e1 - e0)) for c in grid]
    best = float(grid[int(np.argmin(predicted))])
    at_best = navigate(_scenario(True), drift_law=DriftLaw.constant(best), decimation_s=60.0)
    assert excess(_north_east_m(at_best)) == pytest.approx(min(predicted), rel=0.01)
    # Between the drift at the start (20 degC) and at the end (about 40 degC), and far from the floor.
    assert BIAS_Z < best < BIAS_Z + 20.0 * K1
    assert min(predicted) > 1000.0 * excess_law and min(predicted) > 0.1


def _config(scn: Scenario) -> _core.NavigatorConfig:
    """The core navigator's configuration at the scenario's true initial state."""
    att = scn.attitude
    return _core.NavigatorConfig(
        **scn.site.core_position(),
        pitch_rad=math.radians(att.pitch_deg),
        roll_rad=math.radians(att.roll_deg),
        yaw_rad=math.radians(att.yaw_deg),
        rate_hz=scn.run.rate_hz,
        vertical="fixed",
    )


def _assert_same_state(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(np.asarray(a[key]), np.asarray(b[key]), err_msg=key)


def test_a_constant_law_is_the_constant_bias_bit_for_bit():
    """The per-sample path with a constant law gives the bits of today's constant bias: in the core, and through the
    streaming engine with `AxialBias` (which `navigate` only uses for a law that reads the temperature)."""
    scn = _scenario(True, hours=1.5)
    law = DriftLaw.constant(0.0042)
    cfg = _config(scn)
    constant, per_sample, streamed = (_core.Navigator(cfg) for _ in range(3))
    constant.set_gyro_bias([0.0, 0.0, law.eps_ref_deg_h * DEG_PER_H])
    log = scenario_log(scn)
    chunk = next(log.chunks(20_000))
    n = len(chunk)
    a = constant.process(chunk.dtheta_rad, chunk.dv_m_s, 7)
    b = per_sample.process(chunk.dtheta_rad, chunk.dv_m_s, 7, None, np.full(n, law.eps_ref_deg_h * DEG_PER_H))
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    _assert_same_state(constant.state(), per_sample.state())

    constant = _core.Navigator(cfg)
    constant.set_gyro_bias([0.0, 0.0, law.eps_ref_deg_h * DEG_PER_H])
    tracks = run_navigators(
        log, [constant, streamed], n_samples=log.n_samples, decimation=600, axial_bias=[None, AxialBias(law, 10.0)]
    )
    for key in tracks[0].kept:
        np.testing.assert_array_equal(tracks[0].kept[key], tracks[1].kept[key])
    _assert_same_state(tracks[0].final, tracks[1].final)
    # And `navigate` with the constant law is the constant bias of the settings (the summary's numbers).
    nav = navigate(scn, drift_law=law, decimation_s=600.0)
    ref = navigate(scn, gyro_bias_deg_h=[0.0, 0.0, 0.0042], decimation_s=600.0)
    np.testing.assert_array_equal(nav["pos_err_nmi"], ref["pos_err_nmi"])
    assert nav.summary["compensation"] == "constant" and nav.summary["compensate_drift_deg_h"] == 0.0042


def test_the_chunking_does_not_change_a_law_reading_the_temperature_rate():
    scn = _scenario(True, hours=3.0, k3=0.01)
    law = DriftLaw(eps_ref_deg_h=BIAS_Z, t_ref_c=20.0, k1_deg_h_per_c=K1, k3_deg_h_per_c_per_h=0.01)
    whole = navigate(scn, drift_law=law, decimation_s=60.0, chunk_samples=200_000)
    pieces = navigate(scn, drift_law=law, decimation_s=60.0, chunk_samples=7_777)
    # The temperature rate's filter runs chunk by chunk (scipy's lfilter with its state): rounding only.
    np.testing.assert_allclose(pieces["lat_deg"], whole["lat_deg"], rtol=0, atol=1e-13)
    np.testing.assert_allclose(pieces["lon_deg"], whole["lon_deg"], rtol=0, atol=1e-13)
    # The rate term matters: without it the error is larger (the simulator's k3 uses its exact dT/dt).
    no_rate = navigate(scn, drift_law=SIMULATOR_LAW, decimation_s=60.0)
    assert whole.summary["final_pos_err_nmi"] < no_rate.summary["final_pos_err_nmi"]


def test_axial_bias_carries_the_temperature_rate_across_pieces():
    law = DriftLaw(eps_ref_deg_h=0.003, t_ref_c=25.0, k1_deg_h_per_c=2e-4, k3_deg_h_per_c_per_h=0.05)
    scn = _scenario(True, hours=1.0)
    log = scenario_log(scn)
    chunk = next(log.chunks(log.n_samples))
    whole = AxialBias(law, 10.0, other_z_deg_h=0.001)(chunk)
    bias = AxialBias(law, 10.0, other_z_deg_h=0.001)
    split = np.concatenate([bias(chunk.slice(0, 1234)), bias(chunk.slice(1234, len(chunk)))])
    # Equal to rounding: the rate's T - f cancels digits (1e-10 deg/h is 1e-8 of the law's 0.01 deg/h).
    np.testing.assert_allclose(split, whole, rtol=0, atol=1e-10 * DEG_PER_H)
    # Independent: the law on the temperature with a brute-force causal low-pass (the recursion, in Python).
    a = -math.expm1(-0.1 / law.rate_tau_s)
    f, rate = float(chunk.temp_c[0]), []
    for t in chunk.temp_c:
        f += a * (float(t) - f)
        rate.append((float(t) - f) * a / ((1.0 - a) * 0.1) * 3600.0)
    expected = (0.001 + 0.003 + 2e-4 * (chunk.temp_c - 25.0) + 0.05 * np.array(rate)) * DEG_PER_H
    np.testing.assert_allclose(whole, expected, rtol=0, atol=1e-10 * DEG_PER_H)


# --------------------------------------------------------------------------------------------------
# Files and command line
# --------------------------------------------------------------------------------------------------


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def thermal_log(tmp_path_factory):
    """A 5.2 h simulated log with the thermal drift (4 h alignment + 1.2 h of navigation)."""
    from gyrodrift.ins import simulate

    out = tmp_path_factory.mktemp("thermal")
    return simulate(_scenario(True, hours=5.2), out_dir=out / "sim", quiet=True)


def test_load_drift_law_reads_identification_files_and_bare_laws_and_names_file_and_key(tmp_path):
    ident = tmp_path / "identification.json"
    ident.write_text(json.dumps({"format": "gyrodrift-identification/1", "drift_law": SIMULATOR_LAW.to_dict()}))
    assert load_drift_law(ident) == SIMULATOR_LAW
    bare = tmp_path / "law.json"
    bare.write_text(json.dumps(SIMULATOR_LAW.to_dict()))
    assert load_drift_law(bare) == SIMULATOR_LAW
    cases = {
        "not JSON {": "corrupted JSON at line 1",
        "[1, 2]": "expected a JSON object holding drift_law, got list",
        '{"drift": 1}': "no drift_law key",
        '{"drift_law": null}': "drift_law is null",
        '{"drift_law": {"k1_deg_h_per_c": 1e-4}}': "drift_law needs eps_ref_deg_h",
        '{"drift_law": {"eps_ref_deg_h": 0.004, "k2": 1}}': "unknown key(s) k2",
        '{"drift_law": {"eps_ref_deg_h": 0.004, "k1_deg_h_per_c": "x"}}': "k1_deg_h_per_c must be a finite number",
    }
    for text, message in cases.items():
        bad = tmp_path / "bad.json"
        bad.write_text(text)
        with pytest.raises(InputError, match=r"bad\.json: .*" + message.replace("(", r"\(").replace(")", r"\)")):
            load_drift_law(bad)


def test_cli_navigate_and_evaluate_take_a_law_and_say_so(tmp_path, thermal_log):
    law_file = tmp_path / "law.json"
    law_file.write_text(json.dumps({"drift_law": SIMULATOR_LAW.to_dict()}))
    r = _run("navigate", thermal_log, "--hours", "1", "--drift-law", law_file, "--out", tmp_path / "nav", "--quiet")
    assert r.exit_code == 0, r.output
    summary = json.loads((tmp_path / "nav" / "summary.json").read_text())
    assert summary["compensation"] == "law" and summary["drift_law"] == SIMULATOR_LAW.to_dict()
    r = _run("navigate", thermal_log, "--hours", "1", "--drift-law", law_file, "--out", tmp_path / "nav2", "--plot")
    assert "compensating the drift law 0.004000 deg/h at 20.0 degC, k1 0.0003 deg/h/degC" in r.output
    assert (tmp_path / "nav2" / "navigation.png").stat().st_size > 0
    r = _run("navigate", thermal_log, "--hours", "1", "--drift-deg-h", "0.004", "--out", tmp_path / "nav3")
    assert r.exit_code == 0 and "compensating the constant 0.004000 deg/h" in r.output

    r = _run("evaluate", thermal_log, "--hours", "1", "--drift-law", law_file, "--out", tmp_path / "ev")
    assert r.exit_code == 0, r.output
    assert "compensating the drift law 0.004000 deg/h" in r.output
    doc = json.loads((tmp_path / "ev" / "evaluation.json").read_text())
    assert doc["compensation"] == "law" and doc["drift_law"] == SIMULATOR_LAW.to_dict()
    assert doc["drift_source"] == str(law_file) and doc["drift_deg_h"] == BIAS_Z


def test_cli_refuses_two_compensations_a_bad_law_file_and_a_law_without_temperature(tmp_path, thermal_log):
    law_file = tmp_path / "law.json"
    law_file.write_text(json.dumps(SIMULATOR_LAW.to_dict()))
    both = ("--drift-deg-h", "0.004", "--drift-law", law_file)
    r = _run("navigate", thermal_log, *both, "--out", tmp_path / "o")
    assert r.exit_code == 2 and "give --drift-deg-h (a constant) or --drift-law (a law), not both" in r.output
    r = _run("evaluate", thermal_log, *both, "--out", tmp_path / "o")
    assert r.exit_code == 2 and "give exactly one of --drift-deg-h, --drift-law or --model" in r.output

    bad = tmp_path / "bad.json"
    bad.write_text('{"drift_law": {"eps_ref_deg_h": 0.004, "k1_deg_h_per_c": null}}')
    r = _run("navigate", thermal_log, "--drift-law", bad, "--out", tmp_path / "o")
    assert r.exit_code == 1 and f"{bad}: drift law: k1_deg_h_per_c must be a finite number" in r.output
    assert "Traceback" not in r.output and not (tmp_path / "o").exists()

    no_temp = tmp_path / "no_temp.parquet"
    pq.write_table(pq.read_table(thermal_log).drop(["temp_c"]), no_temp)
    r = _run("navigate", no_temp, "--hours", "1", "--drift-law", law_file, "--out", tmp_path / "o")
    assert r.exit_code == 1, r.output
    assert "no_temp.parquet" in r.output and "missing column temp_c" in r.output and "drift law" in r.output
    # A constant needs no temperature.
    r = _run("navigate", no_temp, "--hours", "1", "--drift-deg-h", "0.004", "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output


def test_a_law_beyond_any_drift_is_refused_naming_the_row_and_the_temperature(tmp_path, thermal_log):
    law = DriftLaw(eps_ref_deg_h=0.004, t_ref_c=20.0, k1_deg_h_per_c=500.0)  # 100 deg/h at 20.2 degC
    with pytest.raises(InputError, match=r"imu\.parquet, row \d+: the drift law gives 100\.\d+ deg/h at temp_c 20\.2"):
        navigate(thermal_log, drift_law=law, hours=1.0)
    # Checked before the core, which would refuse 0.1 rad/s only (its own message names axial_bias_rad_s).
    core = _core.Navigator(_config(_scenario(False, hours=0.1)))
    with pytest.raises(InputError, match="axial_bias_rad_s: sample 1: axial gyro bias 20700 deg/h"):
        core.process(np.zeros((3, 3)), np.zeros((3, 3)), 1, None, np.array([0.0, 20700.0, 0.0]) * DEG_PER_H)
