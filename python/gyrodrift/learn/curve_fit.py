"""The 12 h curve fit: the axial drift from the whole latitude and longitude error curves of the navigation.

The physics inversion uses one number, the latitude error at hour 12. The navigation computes the whole curves
(every 60 s, hours 0-12); on a static base they follow the linear error equations below, so the drift is the
coefficient of its response in a least-squares fit of both curves, with nuisance terms for what else excites
them: the initial attitude errors left by the alignment (which also start the Schuler oscillation) and the
initial velocity errors.

Static-base error equations (phi-angle model, ENU navigation frame, velocity zero, vertical channel left out;
w_N = w_ie cos L, w_U = w_ie sin L, R Earth radius, g gravity, eps gyro error measured - true, nav frame):

    phi_E' =  w_U phi_N - w_N phi_U - dv_N / R             - eps_E
    phi_N' = -w_U phi_E - w_U dL    + dv_E / R             - eps_N
    phi_U' =  w_N phi_E + w_N dL    + tan L dv_E / R       - eps_U
    dv_E'  = -g phi_N + 2 w_U dv_N
    dv_N'  =  g phi_E - 2 w_U dv_E
    dL'    =  dv_N / R
    dlon'  =  dv_E / (R cos L)

(Schuler w_s = sqrt(g / R), period 84.4 min; Foucault 2 w_U; Earth rate w_ie.) With the table rotating, the
horizontal gyro and accelerometer biases are modulated to zero mean and are left out; the axial drift eps_U is
not modulated. The system x' = F x + G eps_U is linear and time-invariant, so every response is exact and in
closed form, x(t) = e^{F t} x0 + (int_0^t e^{F s} ds) G eps_U, evaluated here with one matrix exponential of
the augmented system per time step (scipy.linalg.expm) and propagated over the decimated grid. Averaged over
the Schuler oscillation (w_s >> w_ie) the eps_U column is the textbook response

    dL(t)   = (eps_U cos L / w_ie) (1 - cos w_ie t)
    dlon(t) = (eps_U sin L / w_ie) (w_ie t - sin w_ie t) / cos L       (longitude; east error dlon R cos L)

(`gyrodrift.learn.baselines.latitude_error_at`); the exact column adds the Schuler and Foucault terms these omit.
tests/test_curve_fit.py checks the eps_U column against the navigator (two passes of one noise-free log whose
compensated drifts differ: their difference is the navigator's drift response) and the fit on noise-free logs.

Parameters fitted: eps_U [deg/h] and the nuisance phi_E0, phi_N0, phi_U0 [arcsec], dv_E0, dv_N0 [m/s]. Both
curves are weighted as ground distances (longitude times cos L). The 1-sigma of eps_U is the least-squares one
from the residual scatter, inflated for its serial correlation (AR(1) effective sample size): the residuals of
a noisy run are ARW-driven random walks, not white noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gyrodrift.earth import OMEGA_IE_RAD_S, WGS84_A_M, WGS84_F, normal_gravity
from gyrodrift.errors import InputError
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, HOUR

__all__ = ["PARAMETERS", "CurveFit", "drift_response", "error_responses", "fit_error_curves"]

PARAMETERS = ("eps_U_deg_h", "phi_E0_arcsec", "phi_N0_arcsec", "phi_U0_arcsec", "dv_E0_m_s", "dv_N0_m_s")
"""What the curve fit estimates (the drift first), with units."""

# state order of the error model
_PHI_E, _PHI_N, _PHI_U, _DV_E, _DV_N, _DL, _DLON = range(7)


def _earth(lat0_deg: float) -> tuple[float, float, float]:
    """(R [m], g [m/s^2], L [rad]): Gaussian mean radius sqrt(R_M R_N) and normal gravity at the site."""
    lat = float(lat0_deg) * DEG
    e2 = WGS84_F * (2.0 - WGS84_F)
    s2 = math.sin(lat) ** 2
    r_n = WGS84_A_M / math.sqrt(1.0 - e2 * s2)
    r_m = WGS84_A_M * (1.0 - e2) / (1.0 - e2 * s2) ** 1.5
    return math.sqrt(r_m * r_n), float(normal_gravity(lat)), lat


def error_matrix(lat0_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """``(F, G)`` of the static-base error equations (module docstring) at latitude ``lat0_deg`` [deg].

    States (SI): phi_E, phi_N, phi_U [rad], dv_E, dv_N [m/s], dL, dlon [rad]; ``G`` is the column of eps_U
    [rad/s]."""
    R, g, lat = _earth(lat0_deg)
    w_n, w_u = OMEGA_IE_RAD_S * math.cos(lat), OMEGA_IE_RAD_S * math.sin(lat)
    F = np.zeros((7, 7))
    F[_PHI_E, [_PHI_N, _PHI_U, _DV_N]] = (w_u, -w_n, -1.0 / R)
    F[_PHI_N, [_PHI_E, _DL, _DV_E]] = (-w_u, -w_u, 1.0 / R)
    F[_PHI_U, [_PHI_E, _DL, _DV_E]] = (w_n, w_n, math.tan(lat) / R)
    F[_DV_E, [_PHI_N, _DV_N]] = (-g, 2.0 * w_u)
    F[_DV_N, [_PHI_E, _DV_E]] = (g, -2.0 * w_u)
    F[_DL, _DV_N] = 1.0 / R
    F[_DLON, _DV_E] = 1.0 / (R * math.cos(lat))
    G = np.zeros(7)
    G[_PHI_U] = -1.0
    return F, G


def error_responses(t_s, lat0_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Latitude and longitude error responses [arcsec] at times ``t_s`` [s] to each of ``PARAMETERS``.

    Returns ``(lat, lon)``, each of shape (len(t_s), 6): the response to 1 deg/h of eps_U, 1 arcsec of each
    initial attitude error and 1 m/s of each initial velocity error (longitude in arcsec of longitude, not of
    ground). ``t_s`` must be evenly spaced, starting at one step (the navigation's curve times) or at 0.
    """
    from scipy.linalg import expm  # here: scipy.linalg costs ~0.4 s of a CLI start that fits no curve

    t = np.asarray(t_s, float)
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)):
        raise InputError("curve times must be a 1-D array of at least 2 finite times [s]")
    dt = float(t[1] - t[0])
    if (
        not dt > 0
        or not np.allclose(np.diff(t), dt, rtol=1e-6, atol=1e-6)
        or not (math.isclose(t[0], dt, rel_tol=1e-6) or t[0] == 0.0)
    ):
        raise InputError("curve times must be evenly spaced and start at 0 or at one step [s]")
    F, G = error_matrix(lat0_deg)
    # augmented state: 7 error states, then the constant eps_U; columns of X0 are the 6 parameters
    A = np.zeros((8, 8))
    A[:7, :7] = F
    A[:7, 7] = G
    X = np.zeros((8, 6))
    X[7, 0] = DEG_PER_H
    X[_PHI_E, 1] = X[_PHI_N, 2] = X[_PHI_U, 3] = ARCSEC
    X[_DV_E, 4] = X[_DV_N, 5] = 1.0
    step = expm(A * dt)
    out = np.empty((t.size, 2, 6))
    if t[0] != 0.0:
        X = step @ X
    for k in range(t.size):
        out[k] = X[[_DL, _DLON]]
        X = step @ X
    return out[:, 0, :] / ARCSEC, out[:, 1, :] / ARCSEC


def drift_response(t_s, lat0_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Latitude and longitude error [arcsec] per deg/h of axial drift at times ``t_s`` [s] (exact column)."""
    lat, lon = error_responses(t_s, lat0_deg)
    return lat[:, 0], lon[:, 0]


@dataclass(frozen=True)
class CurveFit:
    """Result of :func:`fit_error_curves`.

    Attributes
    ----------
    drift_deg_h, drift_std_deg_h : float
        Axial drift (the constant to subtract from the z gyro) and its 1-sigma [deg/h].
    params : dict
        Every fitted parameter (``PARAMETERS``, units in the names).
    residual_rms_arcsec : float
        Root mean square of the weighted residuals (ground arcsec).
    n_eff : float
        Effective number of independent residuals (AR(1)) used for the 1-sigma.
    """

    drift_deg_h: float
    drift_std_deg_h: float
    params: dict
    residual_rms_arcsec: float
    n_eff: float


def fit_error_curves(t_s, lat_err_arcsec, lon_err_arcsec, lat0_deg: float, *, hours: float = 12.0) -> CurveFit:
    """Least-squares fit of the latitude and longitude error curves [arcsec, computed minus true] at times
    ``t_s`` [s after the end of the alignment] to the responses of ``PARAMETERS`` (module docstring).

    Only samples with ``t_s <= hours`` h are used (the 12 h of the features; a 72 h truth curve may be given).
    """
    t = np.asarray(t_s, float)
    lat_e = np.asarray(lat_err_arcsec, float)
    lon_e = np.asarray(lon_err_arcsec, float)
    if not (t.shape == lat_e.shape == lon_e.shape) or t.ndim != 1:
        raise InputError("t_s, lat_err_arcsec and lon_err_arcsec must be 1-D arrays of one length")
    keep = t <= hours * HOUR * (1 + 1e-12)
    t, lat_e, lon_e = t[keep], lat_e[keep], lon_e[keep]
    if t.size < 2 * len(PARAMETERS):
        raise InputError(f"the curve fit needs at least {2 * len(PARAMETERS)} samples within {hours:g} h")
    if not (np.all(np.isfinite(lat_e)) and np.all(np.isfinite(lon_e))):
        raise InputError("the error curves hold NaN or infinite values")
    c = math.cos(float(lat0_deg) * DEG)
    r_lat, r_lon = error_responses(t, lat0_deg)
    A = np.vstack([r_lat, r_lon * c])
    b = np.concatenate([lat_e, lon_e * c])
    scale = np.linalg.norm(A, axis=0)
    coef, *_ = np.linalg.lstsq(A / scale, b, rcond=None)
    coef = coef / scale
    resid = b - A @ coef
    n, p = b.size, A.shape[1]
    sigma2 = float(resid @ resid) / (n - p)
    # serial correlation of the residuals, per curve (AR(1)): n_eff = n (1 - rho) / (1 + rho)
    rhos = []
    for r in (resid[: t.size], resid[t.size :]):
        den = float(r @ r)
        rhos.append(float(r[1:] @ r[:-1]) / den if den > 0 else 0.0)
    rho = min(max(float(np.mean(rhos)), 0.0), 0.999)
    n_eff = max(n * (1.0 - rho) / (1.0 + rho), p + 1.0)
    cov = np.linalg.inv((A / scale).T @ (A / scale)) / np.outer(scale, scale)
    std = math.sqrt(sigma2 * cov[0, 0] * n / n_eff)
    return CurveFit(
        drift_deg_h=float(coef[0]),
        drift_std_deg_h=std,
        params={k: float(v) for k, v in zip(PARAMETERS, coef, strict=True)},
        residual_rms_arcsec=math.sqrt(float(resid @ resid) / n),
        n_eff=float(n_eff),
    )
