"""The daily swing of the scenario temperature: the simulated temperature and the axial drift it drives against
their closed forms, the keys' checks and conversions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift import _core
from gyrodrift.earth import OMEGA_IE_RAD_S
from gyrodrift.ins.scenario import Scenario, ScenarioError
from gyrodrift.units import DEG, DEG_PER_H, HOUR

LAT_DEG = 30.0
START_C, END_C, TAU_H = 15.0, 25.0, 2.0
AMP_C, PERIOD_H, PHASE_DEG = 3.0, 6.0, 40.0
T0_C, K1, K2, K3 = 20.0, 2e-4, 1e-5, 5e-3  # deg/h/degC, deg/h/degC^2, deg/h per degC/h


def swing_scenario(rate_hz: float = 1.0, duration_h: float = 20.0) -> Scenario:
    return Scenario.from_dict(
        {
            "site": {"lat_deg": LAT_DEG},
            "run": {"duration_h": duration_h, "rate_hz": rate_hz},
            "rotation": {"scheme": "none"},
            "temperature": {
                "start_c": START_C,
                "end_c": END_C,
                "tau_h": TAU_H,
                "swing_amplitude_c": AMP_C,
                "swing_period_h": PERIOD_H,
                "swing_phase_deg": PHASE_DEG,
                "t0_c": T0_C,
                "k1_deg_h_per_c": K1,
                "k2_deg_h_per_c2": K2,
                "k3_deg_h_per_c_per_h": K3,
            },
        }
    )


def closed_form(t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """T(t) [deg C] and dT/dt [deg C/h] of the warm-up plus the swing."""
    t_h = t_s / HOUR
    w = 2.0 * math.pi / PERIOD_H
    e = np.exp(-t_h / TAU_H)
    angle = w * t_h + PHASE_DEG * DEG
    temp = END_C + (START_C - END_C) * e + AMP_C * np.sin(angle)
    rate = -(START_C - END_C) / TAU_H * e + AMP_C * w * np.cos(angle)
    return temp, rate


def run_whole(scenario: Scenario) -> dict[str, np.ndarray]:
    sim = _core.ImuSimulator(scenario.to_core_config())
    parts: list[dict[str, np.ndarray]] = []
    while (chunk := sim.next_chunk(7000)) is not None:  # chunks not a multiple of the 256-sample resync
        parts.append(chunk)
    return {k: np.concatenate([np.asarray(p[k]) for p in parts]) for k in ("t_s", "temp_c", "dtheta_rad")}


def test_simulated_temperature_and_axial_drift_follow_the_closed_form():
    s = swing_scenario()
    out = run_whole(s)
    t, dt = out["t_s"], 1.0 / s.run.rate_hz
    temp, _ = closed_form(t)
    # The recurrence (exact every 256 samples) against the closed form at every sample end.
    assert np.max(np.abs(out["temp_c"] - temp)) < 1e-10
    # Level, no table: dtheta_z / dt = w_ie sin(lat) + drift(T, dT/dt) at the middle of each sample.
    mid_temp, mid_rate = closed_form(t - 0.5 * dt)
    d = mid_temp - T0_C
    drift_deg_h = K1 * d + K2 * d * d + K3 * mid_rate
    measured_deg_h = (out["dtheta_rad"][:, 2] / dt - OMEGA_IE_RAD_S * math.sin(LAT_DEG * DEG)) / DEG_PER_H
    scale = float(np.max(np.abs(drift_deg_h)))
    assert scale > 0.01  # the rate term alone: K3 * A * 2 pi / P = 0.0157 deg/h
    assert np.max(np.abs(measured_deg_h - drift_deg_h)) < 1e-9 * scale
    # The swing is there: the temperature spans the warm-up plus twice the amplitude over the day.
    assert out["temp_c"].max() - out["temp_c"].min() > 2 * AMP_C


def test_no_swing_by_default():
    s = Scenario.from_dict(
        {"run": {"duration_h": 3.0, "rate_hz": 1.0}, "temperature": {"start_c": 22.0, "end_c": 22.0}}
    )
    assert s.temperature.swing_amplitude_c == 0.0
    out = run_whole(s)
    assert np.all(out["temp_c"] == 22.0)
    c = s.to_core_config()
    assert (c.temp_swing_amplitude_c, c.temp_swing_period_s, c.temp_swing_phase_rad) == (0.0, 86400.0, 0.0)


def test_swing_keys_convert_to_the_core_units():
    c = swing_scenario().to_core_config()
    assert c.temp_swing_amplitude_c == AMP_C
    assert c.temp_swing_period_s == PERIOD_H * 3600.0
    assert c.temp_swing_phase_rad == pytest.approx(PHASE_DEG * math.pi / 180.0, rel=1e-15)
    again = Scenario.from_dict(swing_scenario().to_toml_dict())
    assert again == swing_scenario()


@pytest.mark.parametrize(
    "temperature, message",
    [
        ({"swing_amplitude_c": -1.0}, "[temperature] swing_amplitude_c: "),
        ({"swing_period_h": 0.0}, "[temperature] swing_period_h: "),
        ({"swing_phase_deg": "x"}, "[temperature] swing_phase_deg: "),
        ({"start_c": 190.0, "end_c": 195.0, "swing_amplitude_c": 10.0}, "[temperature] swing_amplitude_c: "),
        (
            {"series_t_h": [0.0, 1.0], "series_temp_c": [20.0, 21.0], "swing_amplitude_c": 2.0},
            "[temperature] swing_amplitude_c: expected 0 with a temperature series",
        ),
    ],
)
def test_bad_swing_keys_name_the_key(temperature, message):
    with pytest.raises(ScenarioError) as err:
        Scenario.from_dict({"temperature": temperature}, source="s.toml")
    assert str(err.value).startswith("s.toml: ")
    assert message in str(err.value)
    assert "\n" not in str(err.value)
