"""The smoother on a gyro with a Gauss-Markov bias instability (the README tour's INS, shortened): the drift it
carries into navigation leaves the Gauss-Markov state out (the history keeps the total), and a noise measured from
the log (white only) carries the caveat `identify` prints. The calibration over seeds is in the core's
tests/smoother_bias_instability.rs (12 seeds) and docs/studies/2026-11-27-smoother-bias-instability.md (200).
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gyrodrift.ins.scenario import Scenario, load_scenario
from gyrodrift.ins.simulate import simulate
from gyrodrift.procedure.noise import SensorNoise, load_noise_file
from gyrodrift.procedure.results import Identification, RunFeatures
from gyrodrift.procedure.smoother import smooth_log

TOUR = Path(__file__).resolve().parents[2] / "python" / "gyrodrift" / "examples" / "scenarios" / "tour.toml"
HOURS = 6.0


@pytest.fixture(scope="module")
def tour_log():
    """The tour's INS, 6 h at 2 Hz (its bias instability 0.001 deg/h, 1 h)."""
    d = load_scenario(TOUR).to_toml_dict()
    d["run"].update(duration_h=HOURS, rate_hz=2.0, seed=5)
    return simulate(Scenario.from_dict(d)).log()


def test_the_carried_drift_leaves_the_gauss_markov_state_out(tour_log):
    told = load_noise_file(TOUR)
    assert told.bias_instability_deg_h == 0.001 and told.white_only_note is None
    est = smooth_log(tour_log, noise=told, hours=HOURS)
    white = smooth_log(tour_log, noise=replace(told, bias_instability_deg_h=0.0), hours=HOURS)
    assert est.model == white.model == "thermal"
    # Without Gauss-Markov states the carried drift is the history's last point (the total), to rounding.
    assert white.drift_end_deg_h == pytest.approx(white.hist_drift_deg_h[-1], abs=1e-12)
    assert white.drift_end_std_deg_h == pytest.approx(white.hist_drift_std_deg_h[-1], rel=1e-9)
    # With them, the total adds the smoothed Gauss-Markov state: a different number with a wider 1-sigma (the
    # state's end value is seen only through the last hour or so), and the carried 1-sigma lies between the
    # white model's and the total's.
    total, total_std = est.hist_drift_deg_h[-1], est.hist_drift_std_deg_h[-1]
    assert abs(total - est.drift_end_deg_h) > 1e-6
    assert white.drift_end_std_deg_h < est.drift_end_std_deg_h < total_std
    # The navigation drift is the carried one.
    assert est.navigation_drift_deg_h == est.drift_end_deg_h
    assert np.isfinite(est.drift_end_std_deg_h) and est.noise.bias_instability_deg_h == 0.001


def test_a_noise_measured_from_the_log_carries_the_white_only_caveat(tour_log):
    est = smooth_log(tour_log, hours=HOURS)
    assert est.noise.source == "log" and est.noise.bias_instability_deg_h == 0.0
    note = est.noise.white_only_note
    assert note is not None and "--noise" in note and "bias instability" in note
    assert SensorNoise(source="given").white_only_note is None
    assert SensorNoise(bias_instability_deg_h=0.001, source="log").white_only_note is None
    assert SensorNoise(rrw_deg_h_rth=1e-4, source="log").white_only_note is None
    # identify's result says it (and writes it), and says nothing when the noise was given.
    for noise, expected in ((None, note), (load_noise_file(TOUR), None)):
        sm = smooth_log(tour_log, noise=noise, hours=HOURS)
        res = _identification(sm)
        assert res.smoother_noise_note == expected and res.to_dict()["smoother_noise_note"] == expected


def _identification(sm) -> Identification:
    """An `Identification` whose features carry the smoother estimate `sm` (the other numbers do not matter)."""
    f = RunFeatures(
        run="r",
        lat_deg=28.2,
        lat0_deg=28.2,
        lat_err_curve_arcsec=np.zeros(13),
        temp_start_c=20.0,
        temp_end_c=35.0,
        temp_min_c=20.0,
        temp_max_c=35.0,
        smoother=sm,
    )
    return Identification(
        run="r",
        drift_deg_h=0.004,
        physics_drift_deg_h=0.004,
        alignment_z_drift_deg_h=0.004,
        alignment_z_drift_std_deg_h=1e-3,
        model_std_deg_h=None,
        interval_deg_h=None,
        interval_coverage=0.9,
        uncertainty_note="",
        training_error_deg_h=None,
        training_error_kind=None,
        features=f,
    )
