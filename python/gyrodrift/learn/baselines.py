"""Baselines every learned drift model has to beat.

The physics inversion: a constant axial drift eps_U on a static base at latitude L gives a bounded latitude
error dL(t) = (eps_U cos L / w_ie)(1 - cos w_ie t) (phi-angle error model, ENU), largest at 12 h where
dL = 2 eps_U cos L / w_ie. Inverting it at t = 12 h (sidereal half-day effects are ignored: w_ie * 12 h is
pi to 0.3 %, which changes 1 - cos by < 0.01 %):

    eps_U = w_ie dL / (2 cos L)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gyrodrift.earth import OMEGA_IE_RAD_S
from gyrodrift.runs.table import RunTable
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, HOUR

if TYPE_CHECKING:
    from sklearn.linear_model import LinearRegression


def latitude_error_at(t_s, drift_deg_h, lat0_deg):
    """Closed-form latitude error [arcsec] at time ``t_s`` [s] for a constant axial drift [deg/h].

    Computed minus true; a positive drift (gyro z reads too high) gives a positive error.
    """
    eps = np.asarray(drift_deg_h, float) * DEG_PER_H
    lat0 = np.asarray(lat0_deg, float) * DEG
    w = OMEGA_IE_RAD_S
    return eps * np.cos(lat0) / w * (1.0 - np.cos(w * np.asarray(t_s, float))) / ARCSEC


def position_error_of_drift_nmi(t_s, drift_deg_h, lat0_deg):
    """Closed-form horizontal position error [nmi, 1852 m] at time ``t_s`` [s] of a constant residual axial drift
    [deg/h] on a static base at ``lat0_deg`` (same phi-angle model as `latitude_error_at`).

    north = R_M dL(t), dL(t) = (eps cos L / w_ie)(1 - cos w_ie t); east = R_N cos L dlon(t),
    dlon(t) = eps sin L (t - sin(w_ie t) / w_ie) (WGS-84 radii at L). At 28.222 deg a residual of 0.001 deg/h
    gives 1.80 nmi at 72 h. The error is even in the drift's sign.
    """
    from gyrodrift.earth import radii_of_curvature
    from gyrodrift.units import NMI_M

    eps = np.asarray(drift_deg_h, float) * DEG_PER_H
    lat0 = np.asarray(lat0_deg, float) * DEG
    t = np.asarray(t_s, float)
    w = OMEGA_IE_RAD_S
    r_m, r_n = radii_of_curvature(lat0)
    north = r_m * eps * np.cos(lat0) / w * (1.0 - np.cos(w * t))
    east = r_n * np.cos(lat0) * eps * np.sin(lat0) * (t - np.sin(w * t) / w)
    return np.hypot(north, east) / NMI_M


def physics_inversion(runs: RunTable, t_h: float = 12.0) -> np.ndarray:
    """Axial drift [deg/h] from the latitude error at ``t_h`` hours, exact inversion of ``latitude_error_at``."""
    w = OMEGA_IE_RAD_S
    lat0 = runs.lat0_deg * DEG
    d_lat = runs.lat_err_arcsec * ARCSEC
    eps = w * d_lat / (np.cos(lat0) * (1.0 - np.cos(w * t_h * HOUR)))
    return eps / DEG_PER_H


def fit_latitude_line(train: RunTable) -> LinearRegression:
    """Least-squares line drift_deg_h = a * lat_err_arcsec + b fitted on ``train``."""
    from sklearn.linear_model import LinearRegression  # here: its import costs ~0.2 s of every command's start

    model = LinearRegression()
    model.fit(train.lat_err_arcsec.reshape(-1, 1), train.drift_deg_h)
    return model
