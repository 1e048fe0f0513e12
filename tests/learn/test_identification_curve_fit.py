"""The 12 h curve fit (gyrodrift.learn.curve_fit): its drift response against the navigator and the textbook closed
form, and the fit on noise-free simulated logs."""

from __future__ import annotations

import numpy as np
import pytest

from gyrodrift.errors import InputError
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.learn.baselines import latitude_error_at
from gyrodrift.learn.curve_fit import drift_response, error_responses, fit_error_curves
from gyrodrift.logs import ImuLog
from gyrodrift.procedure import align_log, navigate_after_alignment


def _log(lat_deg: float, drift: float, arw: float = 0.0) -> ImuLog:
    return scenario_log(
        Scenario.from_dict(
            {
                "site": {"lat_deg": lat_deg},
                "run": {"duration_h": 16.05, "rate_hz": 5.0, "seed": 3},
                "gyro": {"bias_deg_h": [0.005, -0.004, drift], "arw_deg_rth": arw},
                "accel": {"bias_ug": [30.0, -20.0, 10.0]},
                "temperature": {"start_c": 20.0, "end_c": 35.0, "tau_h": 2.0},
                "attitude": {"yaw_deg": 33.0},
            }
        )
    )


@pytest.mark.parametrize("lat_deg", [20.0, 57.0])
def test_drift_column_matches_the_navigator_and_the_fit_recovers_the_drift(lat_deg):
    log = _log(lat_deg, 0.003)
    res = navigate_after_alignment(log, align_log(log), [0.0, 0.001], 12.0)
    c0, c1 = res.curves
    t = c0.t_h * 3600.0
    lat_r, lon_r = drift_response(t, lat_deg)
    # the navigator's response to the drift: two passes whose compensated drifts differ by 0.001 deg/h
    nav_lat = (c0.lat_err_arcsec - c1.lat_err_arcsec) / 0.001
    nav_lon = (c0.lon_err_arcsec - c1.lon_err_arcsec) / 0.001
    assert np.max(np.abs(nav_lat - lat_r)) < 1e-3 * np.max(np.abs(lat_r))  # measured 2-3e-4
    assert np.max(np.abs(nav_lon - lon_r)) < 1e-3 * np.max(np.abs(lon_r))  # measured 3-6e-4
    fit = fit_error_curves(t, c0.lat_err_arcsec, c0.lon_err_arcsec, lat_deg)
    assert fit.drift_deg_h == pytest.approx(0.003, abs=2e-6)  # measured 3e-7
    assert fit.residual_rms_arcsec < 0.05 and fit.drift_std_deg_h < 1e-5


def test_exact_column_is_the_textbook_response_plus_schuler_terms():
    t = np.arange(1, 721) * 60.0
    exact, _ = drift_response(t, 40.0)
    text = latitude_error_at(t, 1.0, 40.0)
    assert np.max(np.abs(exact - text)) < 0.01 * np.max(np.abs(text))  # measured 0.35 %
    assert np.max(np.abs(exact - text)) > 1e-4 * np.max(np.abs(text))  # the Schuler terms are there
    lat, lon = error_responses(t, 40.0)
    assert lat.shape == lon.shape == (720, 6)


def test_curve_fit_refuses_bad_curves():
    t = np.arange(1, 721) * 60.0
    with pytest.raises(InputError, match="evenly spaced"):
        error_responses(t[::-1], 40.0)
    with pytest.raises(InputError, match="one length"):
        fit_error_curves(t, np.zeros(720), np.zeros(719), 40.0)
    bad = np.zeros(720)
    bad[5] = np.nan
    with pytest.raises(InputError, match="NaN"):
        fit_error_curves(t, bad, np.zeros(720), 40.0)
