"""The planner's mission floor with the z gyro's slow bias (`_core.mission_covariance`, `mission_error_model`,
`mission_outlook`, `plan_identification`): the Gauss-Markov bias and the rate random walk against the numeric
closed forms of a drift random process, the floor's parts adding up, and the outlook and plan carrying them. The
cross terms with the smoother's and the aligner's errors are checked against a Monte Carlo of the linear model in
the core (gyrodrift-core ``plan``'s tests); the outlook against simulated runs in
docs/studies/2026-11-28-outlook-bias-instability.md."""

import math

import numpy as np
import pytest

from gyrodrift import _core
from gyrodrift.earth import NMI_M, OMEGA_IE_RAD_S, radii_of_curvature
from gyrodrift.errors import InputError
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.plan import identification_curve, mission_error_model, mission_outlook, plan_identification
from gyrodrift.units import DEG, DEG_PER_H, HOUR

RLG = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0)
RLG_GM = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0, bias_instability_deg_h=0.001, correlation_s=3600.0)
LAT = 28.222


def _floor(lat_deg: float, hours: float, **slow: float) -> np.ndarray:
    """`_core.mission_covariance`'s pos_cov [m^2] with no white noise and the given slow-bias keywords (SI)."""
    nav = _core.FreeNavigationConfig(
        lat_rad=lat_deg * DEG,
        height_m=0.0,
        span_s=hours * HOUR,
        step_s=60.0,
        gyro_arw_rad_rts=0.0,
        accel_vrw_m_s_rts=0.0,
        att_sigma_rad=[0.0, 0.0, 0.0],
        vel_sigma_m_s=0.0,
    )
    return np.asarray(_core.mission_covariance(nav, **slow)["pos_cov_m2"], dtype=float)


def _closed_form(lat_deg: float, hours: float, kernel, dt: float = 120.0) -> np.ndarray:
    """Cov of p(T) = int_0^T h(T - t) b(t) dt for a z drift process b with autocovariance kernel(t, s) [rad^2/s^2]:
    h the impulse response of the north, east error to a z drift, the derivative of the closed forms
    dL = (cos L / w)(1 - cos w t), dlon = sin L (t - sin(w t) / w) (Schuler terms aside), times the radii;
    the double integral by the midpoint rule on a `dt` grid."""
    lat = lat_deg * DEG
    rm, rn = (float(r) for r in radii_of_curvature(lat))
    w = OMEGA_IE_RAD_S
    t_end = hours * HOUR
    t = (np.arange(int(round(t_end / dt))) + 0.5) * dt
    tau = t_end - t
    h = np.stack([rm * math.cos(lat) * np.sin(w * tau), rn * math.cos(lat) * math.sin(lat) * (1.0 - np.cos(w * tau))])
    k = kernel(t[:, None], t[None, :])
    return (h @ k @ h.T) * dt * dt


@pytest.mark.parametrize("lat_deg, hours, tau_s", [(LAT, 72.0, 3600.0), (55.0, 24.0, 20_000.0)])
def test_the_gauss_markov_floor_is_the_closed_form_of_a_drift_process(lat_deg, hours, tau_s):
    # A stationary first-order Gauss-Markov z bias over the mission: sigma^2 exp(-|t - s| / tau). Within 2 % of
    # the largest entry (the Schuler terms the closed forms leave out, and the grids).
    sigma = 0.001 * DEG_PER_H
    got = _floor(lat_deg, hours, gyro_bias_instability_rad_s=sigma, gyro_correlation_s=tau_s)
    want = _closed_form(lat_deg, hours, lambda t, s: sigma**2 * np.exp(-np.abs(t - s) / tau_s))
    assert np.abs(got - want).max() < 0.02 * np.abs(want).max(), (got, want)
    assert want[1, 1] > 0.05 * NMI_M**2  # the east error: more than 0.2 nmi 1-sigma, not a rounding matter


def test_the_random_walk_floor_is_the_closed_form_from_the_missions_start():
    # A rate random walk from zero at the mission's start (the drift taken there): q min(t, s).
    q = (0.0005 * DEG_PER_H) ** 2 / HOUR
    got = _floor(LAT, 72.0, gyro_rrw_rad_s_rts=math.sqrt(q))
    want = _closed_form(LAT, 72.0, lambda t, s: q * np.minimum(t, s))
    assert np.abs(got - want).max() < 0.02 * np.abs(want).max(), (got, want)


def test_the_floor_adds_the_slow_bias_to_the_white_noise():
    # Independent sources of a linear model: the floor with both is the white one plus the slow bias's alone.
    white = np.asarray(mission_error_model(LAT, RLG).floor_cov_m2)
    both = np.asarray(mission_error_model(LAT, RLG_GM).floor_cov_m2)
    slow = _floor(LAT, 72.0, gyro_bias_instability_rad_s=0.001 * DEG_PER_H, gyro_correlation_s=3600.0)
    assert both == pytest.approx(white + slow, rel=1e-9, abs=1e-9 * np.abs(both).max())
    assert both[1, 1] > 1.5 * white[1, 1]


def test_the_outlook_counts_the_bias_instability():
    # The same drift 1-sigma (about the smoother's at 16 h told of the bias instability): with it in the noise the
    # predicted quantiles widen (the floor's part), and a noise measured from the log (white only) keeps the
    # white outlook.
    s = 4e-4
    gm = mission_outlook(s, LAT, RLG_GM, span_h=16.0)
    white = mission_outlook(s, LAT, SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0, source="log"), span_h=16.0)
    assert gm["quantiles_nmi"]["0.5"] > 1.2 * white["quantiles_nmi"]["0.5"]
    assert gm["quantiles_nmi"]["0.95"] > 1.05 * white["quantiles_nmi"]["0.95"]
    assert gm["share_within"] < white["share_within"] - 0.05


def test_a_rate_random_walk_reaches_the_plan_and_the_outlook():
    noise = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0, rrw_deg_h_rth=0.0002)
    curve = identification_curve(noise, [8.0, 16.0], lat_deg=LAT)
    walk = curve.walk_cov_m2
    assert walk.shape == (2, 2, 2) and np.all(np.isfinite(walk)) and abs(walk[1, 1, 1]) > 0
    mission = mission_error_model(LAT, noise, alignment_cov_m2=curve.alignment_cov_m2)
    for k in range(2):  # the total covariance stays a covariance
        cov = mission.covariance_m2(curve.drift_std_deg_h[k], curve.cross_m_deg_h[k], walk[k])
        assert np.all(np.linalg.eigvalsh(cov) > 0)
    plan = plan_identification(noise, lat_deg=LAT, min_span_h=6.0, max_span_h=8.0, step_h=1.0)
    assert np.asarray(plan.to_dict()["walk_cov_m2"]).shape == (3, 2, 2)
    # A span ending before the mission starts (the alignment's 4 h) is refused with a random walk, by its key.
    with pytest.raises(InputError, match=r"^span_h: 2 h ends before the alignment \(4 h\)"):
        identification_curve(noise, [2.0, 6.0], lat_deg=LAT)
    with pytest.raises(InputError, match="^span_h"):
        plan_identification(noise, lat_deg=LAT, min_span_h=3.0, max_span_h=8.0)
