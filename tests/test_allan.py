"""Allan deviation of static logs: the noise model's closed forms, the fit, recovery of simulated noise."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from gyrodrift.allan import allan_deviation, fit_noise, gauss_markov_avar
from gyrodrift.cli import main
from gyrodrift.errors import InputError
from gyrodrift.ins import Scenario, simulate
from gyrodrift.logs import open_log

DEG = math.pi / 180.0


def test_gauss_markov_avar_limits():
    sigma, corr = 2.0, 50.0
    tau_long = np.array([1e5, 1e6])
    assert np.allclose(gauss_markov_avar(tau_long, sigma, corr), 2 * sigma**2 * corr / tau_long, rtol=2e-3)
    tau_short = np.array([1e-3, 1e-2])
    assert np.allclose(gauss_markov_avar(tau_short, sigma, corr), 2 * sigma**2 * tau_short / (3 * corr), rtol=1e-3)
    # continuous across the series switch
    x = np.array([0.999e-3, 1.001e-3]) * corr
    v = gauss_markov_avar(x, sigma, corr)
    assert abs(v[1] / v[0] - 1.0) < 5e-3


@settings(max_examples=40, deadline=None)
@given(
    white=st.floats(1e-4, 1e-1),
    gm=st.floats(0.0, 1e-1),
    corr=st.floats(10.0, 1000.0),
    rrw=st.floats(0.0, 1e-4),
)
def test_fit_recovers_an_exact_model_curve(white, gm, corr, rrw):
    tau = np.geomspace(0.01, 1e4, 21)
    avar = white**2 / tau + rrw**2 * tau / 3 + gauss_markov_avar(tau, gm, corr)
    fit = fit_noise(tau, np.sqrt(avar), 1e-3 * np.sqrt(avar))
    assert fit.fit_rms_log < 0.02
    assert np.allclose(fit.model_adev(tau), np.sqrt(avar), rtol=0.05)
    assert fit.white == pytest.approx(white, rel=0.05)


def _static_log(tmp_path, seed, arw=0.002, vrw=20.0, hours=1.0, scheme="none"):
    scn = Scenario.from_dict(
        {
            "run": {"duration_h": hours, "rate_hz": 100.0, "seed": seed},
            "rotation": {"scheme": scheme},
            "gyro": {"arw_deg_rth": arw, "bias_instability_deg_h": 0.003, "correlation_s": 300.0},
            "accel": {"vrw_ug_rthz": vrw},
        }
    )
    return simulate(scn, out_dir=tmp_path / f"run{seed}")


@pytest.mark.parametrize("seed", [1, 2])
def test_recovers_simulated_arw_and_vrw_within_10_percent(tmp_path, seed):
    result = allan_deviation(open_log(_static_log(tmp_path, seed)))
    doc = result.to_dict()
    for axis in ("gyro_x", "gyro_y", "gyro_z"):
        assert doc["axes"][axis]["arw_deg_rth"] == pytest.approx(0.002, rel=0.10)
    for axis in ("accel_x", "accel_y", "accel_z"):
        assert doc["axes"][axis]["vrw_ug_rthz"] == pytest.approx(20.0, rel=0.10)
    # the white-noise part of the curve at 1 s equals the closed form N / sqrt(tau) within its error bar
    gx = result.axis("gyro_x")
    i = int(np.argmin(abs(gx.tau_s - 1.0)))
    n_rad = 0.002 * DEG / 60.0
    expected = math.sqrt(n_rad**2 / gx.tau_s[i] + gauss_markov_avar(gx.tau_s[i : i + 1], 0.003 * DEG / 3600, 300.0)[0])
    assert abs(gx.adev[i] - expected) < 4 * gx.adev_err[i]


def test_a_turning_table_is_refused(tmp_path):
    with pytest.raises(InputError, match=r"the turntable turns.*rotation off"):
        allan_deviation(open_log(_static_log(tmp_path, 3, hours=0.1, scheme="continuous")))


def test_cli_writes_json_png_and_a_noise_block_a_scenario_accepts(tmp_path):
    log = _static_log(tmp_path, 4)
    out = tmp_path / "allan"
    r = CliRunner().invoke(main, ["allan", str(log), "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "ARW" in r.output and "wrote" in r.output
    assert {p.name for p in out.iterdir()} >= {"allan.json", "allan.png", "noise.toml"}
    block = tomllib.loads((out / "noise.toml").read_text())
    scn = Scenario.from_dict({**block, "run": {"duration_h": 0.5, "rate_hz": 100.0}, "rotation": {"scheme": "none"}})
    assert scn is not None
    assert block["gyro"]["arw_deg_rth"] == pytest.approx(0.002, rel=0.10)
    assert block["accel"]["vrw_ug_rthz"] == pytest.approx(20.0, rel=0.10)


def test_cli_on_a_missing_log_is_one_line(tmp_path):
    r = CliRunner().invoke(main, ["allan", str(tmp_path / "nope.parquet"), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1 and "Traceback" not in r.output and "nope.parquet" in r.output
