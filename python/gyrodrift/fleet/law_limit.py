"""The physical limit of a drift law's 72 h final error (issue 21): what the law's covariance and the noise imply.

From a held-out run's stored linear error curves (`gyrodrift.fleet.law_study`), the 2-D (north, east) error at the
72 h end after compensating the law theta = (eps_b, k1) [deg/h, deg/h/degC] (eps_b its value at the truth's T_ref
T_b) is

    e = n0 + J theta,   J = [[g_N, h_N], [g_E, h_E]] at the last sample (`final_sensitivity`) [m per deg/h, m per
    deg/h/degC],

and with theta_0 the simulated law, e = J (theta - theta_0) + w, where w = n0 + J theta_0 is what the run's noise
(angle and velocity random walk, the alignment's leftovers) leaves when the true law itself is compensated. The
linear-Gaussian model of the two terms:

* the identification error theta - theta_0 ~ N(0, P), P the law's covariance over (eps_b, k1): for the identified
  law the 16 h smoother's joint posterior of (end drift, k_z) with the fleet's k_z prior
  (`gyrodrift.learn.fleet_prior.posterior_with_coefficient_prior`, the block `gyrodrift.procedure.identify` reports
  as the law's covariance; `identify` adds the learned correction's variance to eps_ref's, left out here: the limit
  is what the 16 h data give); an eps_ref about another T_ref T_a moves to T_b with its covariance
  (``A P A'``, A = [[1, T_b - T_a], [0, 1]]);
* the noise floor w ~ N(0, s^2 I): s = sigma_c ``|g|``, the label's 1-sigma (``drift_std_deg_h``, the core's covariance
  analysis, `gyrodrift.procedure.truth.label_sigma_deg_h`) times the final error's sensitivity to a constant, the
  per-axis final-error 1-sigma of the noise, taken isotropic (the approximation of the truth law's covariance,
  `gyrodrift.procedure.truth_law.law_covariance`);
* the two independent. They are not quite: the 72 h navigation starts at the end of the alignment, so its first
  12 h of noise are the features window's, which the identification sees. The part of w driven by the noise
  after the 16 h span (`future_noise_std_nmi`: the per-axis 1-sigma of a navigation over ``truth_h - features_h``
  hours from an exact state, `label_sigma_deg_h` without leftovers) is independent of any 16 h estimate, so
  ``2 s_future^2`` is a lower bound of E|e|^2 for every law identified from the 16 h, however good.

A tighter bound for every law identified from the 16 h (`lower_bound_mean_square_nmi2`), in the same model: with
w = w_past + w_future (independent increments), e = [J (theta - theta_0) + w_past] + w_future and the bracket a
function of the 16 h data and their noise only, so E|e|^2 >= 2 s_future^2 + tr Cov(J theta_0 - w_past | data).
With a = tr(J P J'), P the covariance of theta_0 given the data, and b = 2 (s^2 - s_future^2) >= tr Cov(w_past |
data), Cauchy-Schwarz on the cross term gives tr Cov(...) >= (sqrt(a) - sqrt(b))^2 where b < a: the most the data
could do is know the past noise exactly and have it cancel the identification error exactly. The bound is reached
when they do (tests/fleet/test_law_limit.py's adversarial Monte Carlo).

So E|e|^2 = tr(J P J') + 2 s^2 (`predicted_mean_square_nmi2`), and the probability that ``|e|`` < 1 nmi is that of a
zero-mean 2-D Gaussian with covariance J P J' + s^2 I (the planner's `gyrodrift.procedure.plan.norm_cdf`). Where the
simulated law is known (`simulated_law`: the campaign's scenario of each run, its z-gyro bias plus k1 (T_b - t0_c),
with no k2, k3, bias instability or rate random walk) the observed parts are reported beside the predicted ones:
``|J (theta - theta_0)|``, ``|w|``, and the z-scores of eps_b's and k1's errors against P (`limit_report`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = [
    "final_sensitivity",
    "future_noise_std_nmi",
    "limit_report",
    "lower_bound_mean_square_nmi2",
    "noise_floor_std_nmi",
    "predicted_mean_square_nmi2",
    "simulated_law",
]


def _column(runs, name: str) -> np.ndarray:
    return runs.numbers(name) if name in runs.columns else np.full(len(runs), math.nan)


def final_sensitivity(runs) -> np.ndarray:
    """J of each run, shape (runs, 2, 2): rows north, east [m]; columns per deg/h of eps_b and per deg/h/degC of
    k1, at the last sample of the curves (module docstring)."""
    c = runs.curves
    assert c is not None, "the runs were read without their curves"
    north = np.stack([c["curve_north_per_deg_h"][:, -1], c["curve_north_per_k1"][:, -1]], axis=-1)
    east = np.stack([c["curve_east_per_deg_h"][:, -1], c["curve_east_per_k1"][:, -1]], axis=-1)
    return np.stack([north, east], axis=1).astype(float)


def noise_floor_std_nmi(runs) -> np.ndarray:
    """s of each run [nmi]: the label's 1-sigma (``drift_std_deg_h``) times ``|g|`` at the 72 h end, the per-axis
    1-sigma of the final error the noise leaves with the true law compensated (module docstring); NaN without the
    label's 1-sigma."""
    from gyrodrift.earth import NMI_M

    g = final_sensitivity(runs)[:, :, 0]
    return _column(runs, "drift_std_deg_h") * np.hypot(g[:, 0], g[:, 1]) / NMI_M


def future_noise_std_nmi(runs, hours: float) -> np.ndarray:
    """The per-axis 1-sigma [nmi] of the final error a navigation of `hours` from an exact state collects from the
    run's noise (its ``lat_deg``, ``arw_deg_rth`` and ``vrw_ug_rthz``; `gyrodrift.procedure.truth.label_sigma_deg_h`,
    isotropic): with ``truth_h - features_h`` hours, the noise after the 16 h span (module docstring); NaN for a run
    without those columns."""
    from gyrodrift.procedure.noise import SensorNoise
    from gyrodrift.procedure.truth import label_sigma_deg_h

    out = np.full(len(runs), math.nan)
    lat, arw, vrw = (_column(runs, c) for c in ("lat_deg", "arw_deg_rth", "vrw_ug_rthz"))
    done: dict[tuple[float, float, float], float] = {}  # runs that share a site and a grade share the analysis
    for i in np.flatnonzero(np.isfinite(lat) & np.isfinite(arw) & np.isfinite(vrw)):
        key = (float(lat[i]), float(arw[i]), float(vrw[i]))
        if key not in done:
            noise = SensorNoise(arw_deg_rth=key[1], vrw_ug_rthz=key[2])
            sigma_deg_h, nmi_per_deg_h = label_sigma_deg_h(key[0], noise, hours=hours)
            done[key] = sigma_deg_h * nmi_per_deg_h
        out[i] = done[key]
    return out


def lower_bound_mean_square_nmi2(identification_nmi2, floor_std_nmi, future_std_nmi) -> np.ndarray:
    """The lower bound of E|e|^2 [nmi^2] of any law identified from the 16 h (module docstring): ``2 s_f^2 +
    max(sqrt(a) - sqrt(b), 0)^2`` with a the identification part tr(J P J') [nmi^2], b = 2 (s^2 - s_f^2) the past
    noise's (0 if negative), s and s_f the per-axis 1-sigmas of all the noise and of the noise after 16 h [nmi]."""
    s, s_f = np.asarray(floor_std_nmi, float), np.asarray(future_std_nmi, float)
    past = np.maximum(2.0 * (s * s - s_f * s_f), 0.0)
    return 2.0 * s_f * s_f + np.maximum(np.sqrt(np.asarray(identification_nmi2, float)) - np.sqrt(past), 0.0) ** 2


def predicted_mean_square_nmi2(sensitivity, cov, floor_std_nmi) -> np.ndarray:
    """E|e|^2 [nmi^2] per run: tr(J P J') + 2 s^2 with J `sensitivity` (runs, 2, 2) [m per unit], P `cov` (runs,
    2, 2) and s `floor_std_nmi` (runs,) [nmi] (module docstring)."""
    from gyrodrift.earth import NMI_M

    j = np.asarray(sensitivity, float) / NMI_M
    return np.einsum("nij,njk,nik->n", j, np.asarray(cov, float), j) + 2.0 * np.asarray(floor_std_nmi, float) ** 2


def simulated_law(campaign, runs) -> tuple[np.ndarray, np.ndarray]:
    """The simulated law of each run about the truth's T_ref T_b (``truth_law_t_ref_c``): (eps_b [deg/h], k1
    [deg/h/degC]) from its scenario in `campaign` (`gyrodrift.fleet.spec.Campaign`): the z-gyro bias plus
    k1 (T_b - t0_c), and k1. NaN for a run whose axial drift is not such a law (k2 or k3 not 0, a gyro bias
    instability or rate random walk)."""
    t_b = runs.numbers("truth_law_t_ref_c")
    eps, k1 = np.full(len(runs), math.nan), np.full(len(runs), math.nan)
    for i, index in enumerate(runs.numbers("index").astype(int)):
        scn = campaign.scenario(int(index))
        t, g = scn.temperature, scn.gyro
        if t.k2_deg_h_per_c2 or t.k3_deg_h_per_c_per_h or g.bias_instability_deg_h or g.rrw_deg_h_rth:
            continue
        eps[i] = g.bias_deg_h[2] + t.k1_deg_h_per_c * (t_b[i] - t.t0_c)
        k1[i] = t.k1_deg_h_per_c
    return eps, k1


def _rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def limit_report(runs, laws: dict, finals: dict, groups: dict, *, future_hours: float, simulated=None) -> dict:
    """The ``limit`` section of ``study.json``'s ``drift_laws`` (module docstring).

    `laws`: per method name, ``(eps_b, k1, cov)`` per run (deg/h at T_b, deg/h/degC, (runs, 2, 2)); `finals`: the
    observed 72 h final error [nmi] per method (`gyrodrift.fleet.law_study.compare_laws`); `groups`: the run masks;
    `future_hours`: ``truth_h - features_h``; `simulated`: `simulated_law`'s (eps_b, k1), or None. Per group: the
    noise floor's predicted RMS ``2 s^2`` (and observed ``|w|`` with the simulated law), the future noise's RMS, and per
    law the predicted RMS (identification part and total), the lower bound's RMS (`lower_bound_mean_square_nmi2`;
    NaN without the noise columns), the observed RMS, their ratio, the
    predicted and observed shares under 1 nmi at 72 h, and with the simulated law the observed identification RMS
    and the z-scores (rms and mean) of eps_b's and k1's errors."""
    from gyrodrift.earth import NMI_M
    from gyrodrift.procedure.plan import norm_cdf

    sens = final_sensitivity(runs)
    s = noise_floor_std_nmi(runs)
    s_future = future_noise_std_nmi(runs, future_hours)
    n0 = np.stack([runs.curves["curve_north0_m"][:, -1], runs.curves["curve_east0_m"][:, -1]], axis=-1)
    truth = None if simulated is None else np.stack([np.asarray(v, float) for v in simulated], axis=-1)
    floor_cov = s[:, None, None] ** 2 * np.eye(2)
    per_law = {}
    for name, (eps, k1, cov) in laws.items():
        theta = np.stack([np.asarray(eps, float), np.asarray(k1, float)], axis=-1)
        ident = predicted_mean_square_nmi2(sens, cov, np.zeros(len(runs)))
        j = sens / NMI_M
        total = j @ cov @ np.swapaxes(j, 1, 2) + floor_cov
        share = np.array([norm_cdf(c, 1.0) if np.all(np.isfinite(c)) else math.nan for c in total])
        bound = lower_bound_mean_square_nmi2(ident, s, s_future)
        per_law[name] = (theta, np.asarray(cov, float), ident, share, bound)
    out: dict[str, Any] = {"groups": {}}
    for group, mask in groups.items():
        m = np.asarray(mask, bool) & np.isfinite(s)
        entry: dict[str, Any] = {
            "n": int(m.sum()),
            "noise_floor_rms_nmi": _rms(np.sqrt(2.0) * s[m]),
            "future_noise_rms_nmi": _rms(np.sqrt(2.0) * s_future[m]),
            "laws": {},
        }
        known = m if truth is None else m & np.all(np.isfinite(truth), axis=1)
        if truth is not None:
            w = n0 + np.einsum("nij,nj->ni", sens, np.nan_to_num(truth))
            entry["n_simulated"] = int(known.sum())
            entry["observed_noise_floor_rms_nmi"] = _rms(np.hypot(w[known, 0], w[known, 1]) / NMI_M)
        for name, (theta, cov, ident, share, bound) in per_law.items():
            predicted = math.sqrt(float(np.mean(ident[m] + 2.0 * s[m] ** 2))) if m.any() else math.nan
            observed = _rms(finals[name][m])
            row = {
                "predicted_identification_rms_nmi": _rms(np.sqrt(ident[m])),
                "predicted_rms_nmi": predicted,
                "lower_bound_rms_nmi": math.sqrt(float(np.mean(bound[m]))) if m.any() else math.nan,
                "observed_rms_nmi": observed,
                "ratio": observed / predicted if predicted > 0 else math.nan,
                "predicted_under_1nmi_final": float(np.mean(share[m])) if m.any() else math.nan,
                "observed_under_1nmi_final": float(np.mean(finals[name][m] < 1.0)) if m.any() else math.nan,
            }
            if truth is not None and known.any():
                err = theta[known] - truth[known]
                e_id = np.einsum("nij,nj->ni", sens[known], err) / NMI_M
                with np.errstate(divide="ignore", invalid="ignore"):  # k1's 0 variance under a constant model
                    z = err / np.sqrt(np.diagonal(cov[known], axis1=1, axis2=2))
                row["observed_identification_rms_nmi"] = _rms(np.hypot(e_id[:, 0], e_id[:, 1]))
                row["ratio_identification"] = row["observed_identification_rms_nmi"] / _rms(np.sqrt(ident[known]))
                for k, coefficient in enumerate(("eps_ref", "k1")):
                    zk = z[:, k][np.isfinite(z[:, k])]
                    row[f"z_{coefficient}_rms"] = _rms(zk)
                    row[f"z_{coefficient}_mean"] = float(np.mean(zk)) if zk.size else math.nan
            entry["laws"][name] = row
        out["groups"][group] = entry
    out["predicted_rms_final_nmi"] = {
        name: np.sqrt(ident + 2.0 * s**2) for name, (_, _, ident, _, _) in per_law.items()
    }  # per run: sqrt(E|e|^2)
    return out
