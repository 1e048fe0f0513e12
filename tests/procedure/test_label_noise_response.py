"""The label's error is the noise's alone: what `truth`'s 1-sigma assumes of a run and its noise-free twin.

`truth`'s 1-sigma (`label_sigma_deg_h`) describes d* - d*_twin, the truth of a noisy run minus that of its
noise-free twin (same scenario and seed, every noise term off), as a linear function of the white noise that
does not depend on the run's deterministic errors. Checked on simulated runs with the same noise draws (the
simulator draws the same normals for the same seed, rate and duration whatever the biases or temperature): a
warm-up and daily swing of the axial drift and other constant biases leave d* - d*_twin unchanged, and doubling
the noise densities doubles it.
"""

from __future__ import annotations

import numpy as np
import pytest

from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.procedure import SensorNoise, find_true_drift

HOURS = 24.0
ALIGN_H = 4.0


def _run(*, noise_scale: float, thermal: bool) -> Scenario:
    """A 2 Hz reciprocating run at 40 deg, RLG noise times `noise_scale`; `thermal`: warm-up, daily swing and
    other constant biases."""
    data: dict = {
        "site": {"lat_deg": 40.0},
        "run": {"duration_h": ALIGN_H + HOURS, "rate_hz": 2.0, "seed": 7},
        "rotation": {"scheme": "reciprocating"},
        "gyro": {"bias_deg_h": [0.004, -0.003, 0.003], "arw_deg_rth": 0.0005 * noise_scale},
        "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": 5.0 * noise_scale},
        "attitude": {"yaw_deg": 30.0},
    }
    if thermal:
        t_h = np.linspace(0.0, ALIGN_H + HOURS, 113)
        temp = 35.0 - 15.0 * np.exp(-t_h / 3.0) + 1.5 * np.sin(2 * np.pi * t_h / 24.0 + 1.0)
        data["gyro"]["bias_deg_h"] = [-0.005, 0.006, 0.002]
        data["accel"]["bias_ug"] = [-35.0, 30.0, 5.0]
        data["temperature"] = {
            "series_t_h": t_h.tolist(),
            "series_temp_c": temp.tolist(),
            "t0_c": 28.0,
            "k1_deg_h_per_c": 0.0002,
        }
    return Scenario.from_dict(data)


def _truth(scenario: Scenario) -> float:
    told = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0)
    return find_true_drift(
        scenario_log(scenario), hours=HOURS, verify=False, trial_deg_h=0.003, threads=1, noise=told
    ).drift_deg_h


@pytest.mark.slow
def test_the_label_error_is_linear_in_the_noise_and_blind_to_the_deterministic_errors():
    twin = _truth(_run(noise_scale=0.0, thermal=False))  # the noise-free twin of the plain and the double run
    plain = _truth(_run(noise_scale=1.0, thermal=False)) - twin
    hot = _truth(_run(noise_scale=1.0, thermal=True)) - _truth(_run(noise_scale=0.0, thermal=True))
    double = _truth(_run(noise_scale=2.0, thermal=False)) - twin
    sigma = 2.5e-4  # deg/h: the order of the label's 1-sigma here; the error must be a sizable part of it
    assert abs(plain) > 0.05 * sigma
    # The drift's warm-up and swing (up to 0.0014 deg/h) and the other biases move it by under 0.1 % of itself.
    assert hot == pytest.approx(plain, rel=1e-3)
    assert double == pytest.approx(2.0 * plain, rel=1e-3)
