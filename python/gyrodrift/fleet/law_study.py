"""The study's drift-law comparison (issue 21): the 72 h error of compensating a constant or a law, per run.

From a held-out run's stored linear 72 h error curves (`gyrodrift.fleet.store.CURVE_COLUMNS`: no navigation), the
north/east error after compensating the law eps(T) = eps_ref + k1 (T - T_ref) is, to first order,

    north(t) = n0(t) + eps_b g_N(t) + k1 h_N(t),   east(t) = e0(t) + eps_b g_E(t) + k1 h_E(t),

g the response to a constant [m per deg/h] (``curve_north_per_deg_h``...), h the response to k1 about the truth
law's T_ref T_b (``curve_north_per_k1``..., [m per deg/h/degC]; ``truth_law_t_ref_c``), and eps_b the law's value
at T_b: a law eps_ref + k1 (T - T_a) is the law [eps_ref + k1 (T_b - T_a)] + k1 (T - T_b). A constant is the law
with k1 = 0 (`gyrodrift.fleet.store.linear_error_nmi` on the same curves). The methods (``LAW_METHODS``):

* ``uncompensated``: nothing subtracted;
* ``constant today``: the hybrid default's drift (the study's ``hybrid default`` row), subtracted as one constant;
* ``identified law``: what `gyrodrift.procedure.identify` reports for that model: eps_ref the same drift at T_ref =
  the temperature at the end of the features window (``temp_end_c``), k1 the smoother's k_z re-weighted by the
  model's fleet prior on k_z (`gyrodrift.learn.fleet_prior.posterior_with_coefficient_prior`, as identify's
  ``fleet_posterior``); k1 = 0 (the constant) for a run under the smoother's constant model, or for every run when
  the model's physics base is not the fleet one;
* ``law on the fleet base`` (only with the fleet prior): the identified law without the learned correction, eps_ref
  the hybrid's physics base (the smoother's end drift with the fleet prior, which refers to T_ref) and the same k1:
  the learned correction is trained towards the 72 h best constant, a time average of the drift, so adding it to
  the law's value at T_ref counts the law's own temperature term a second time (this row measures by how much);
* ``offline best constant``: the 72 h truth ``drift_deg_h`` (known only offline);
* ``offline best law``: the truth's best law (``truth_law_*``, known only offline).

Groups of held-out runs (``GROUPS``): all; ``daily swing``: the campaign varied ``temperature.swing_amplitude_c``
and drew more than 0 for the run (its ``param_temperature_swing_amplitude_c``; a swing fixed in the campaign's
base is not a column and is not recognised); ``no swing``: the others; ``steady temperature``: runs without a swing
whose effective temperature excursion over the navigation, ``sqrt(sum |h|^2 / sum |g|^2)`` over all samples of the
curves (the rms of T - T_b as the error curves weigh it [deg C]), is below
`gyrodrift.procedure.truth_law.MIN_EXCURSION_C` (where the truth itself finds k1 undetermined).

Metrics per group and method: the share of runs under 1 nmi at the 72 h end and over the whole 72 h with their
binomial 1-sigma ``sqrt(p (1 - p) / n)``, and the RMS over the runs of the 72 h final error [nmi] with its bootstrap
1-sigma. Comparisons (paired, the same bootstrap resamples of the runs): the identified law minus the constant
today and minus the offline best constant (shares and RMS, with 1-sigma), and the share of the gap between the
constant today and the offline best law that the identified law closes, ``(today - law) / (today - best law)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gyrodrift.fleet.store import linear_error_nmi
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS

__all__ = [
    "BOOTSTRAP",
    "GROUPS",
    "LAW_METHODS",
    "SWING_COLUMN",
    "compare_laws",
    "excursion_c",
    "fleet_base_deg_h",
    "identified_k1",
    "law_covariance",
    "law_errors_nmi",
    "run_groups",
    "smoother_posterior_inputs",
]

LAW_METHODS = (
    "uncompensated",
    "constant today",
    "identified law",
    "law on the fleet base",
    "offline best constant",
    "offline best law",
)
"""The rows of the comparison, in the report's order (module docstring); ``law on the fleet base`` only with a fleet
prior."""
GROUPS = ("all", "daily swing", "no swing", "steady temperature")
"""The held-out run groups (module docstring)."""
SWING_COLUMN = "param_temperature_swing_amplitude_c"
"""The campaign column of a varied daily swing amplitude [deg C]."""
BOOTSTRAP = 2000
"""Bootstrap resamples of the held-out runs for the RMS's and the paired differences' 1-sigma."""
ONE_NMI = 1.0


def _curve(runs, name: str) -> np.ndarray:
    assert runs.curves is not None, "the runs were read without their curves"
    return runs.curves[name]


def law_errors_nmi(runs, eps_ref_deg_h, k1_deg_h_per_c, t_ref_c) -> np.ndarray:
    """Position error [nmi], shape (runs, points), after compensating per run the law eps_ref [deg/h] + k1
    [deg/h/degC] (T - T_ref [deg C]) (module docstring); a run with k1 = 0 needs no k1 curve (a constant)."""
    eps, k1, t_a = (np.asarray(x, float).reshape(-1, 1) for x in (eps_ref_deg_h, k1_deg_h_per_c, t_ref_c))
    t_b = runs.numbers("truth_law_t_ref_c").reshape(-1, 1)
    constant = k1 == 0.0
    eps_b = np.where(constant, eps, eps + k1 * (t_b - t_a))
    shift_n = np.where(constant, 0.0, k1 * _curve(runs, "curve_north_per_k1"))
    shift_e = np.where(constant, 0.0, k1 * _curve(runs, "curve_east_per_k1"))
    return linear_error_nmi(
        _curve(runs, "curve_north0_m") + shift_n,
        _curve(runs, "curve_east0_m") + shift_e,
        _curve(runs, "curve_north_per_deg_h"),
        _curve(runs, "curve_east_per_deg_h"),
        eps_b,
    )


def excursion_c(runs) -> np.ndarray:
    """Each run's effective temperature excursion over the navigation [deg C]: ``sqrt(sum |h|^2 / sum |g|^2)`` over
    all samples of its curves (NaN without a k1 curve)."""
    h2 = np.sum(_curve(runs, "curve_north_per_k1") ** 2 + _curve(runs, "curve_east_per_k1") ** 2, axis=1)
    g2 = np.sum(_curve(runs, "curve_north_per_deg_h") ** 2 + _curve(runs, "curve_east_per_deg_h") ** 2, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(h2 / g2)


def run_groups(runs) -> dict[str, np.ndarray]:
    """The masks of ``GROUPS`` over `runs` (module docstring)."""
    from gyrodrift.procedure.truth_law import MIN_EXCURSION_C

    n = len(runs)
    swing = runs.numbers(SWING_COLUMN) > 0.0 if SWING_COLUMN in runs.columns else np.zeros(n, bool)
    with np.errstate(invalid="ignore"):
        steady = ~swing & (excursion_c(runs) < MIN_EXCURSION_C)
    return {"all": np.ones(n, bool), "daily swing": swing, "no swing": ~swing, "steady temperature": steady}


def smoother_posterior_inputs(runs) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The runs' smoother end drift and its 1-sigma [deg/h], then its thermal columns (`SMOOTHER_THERMAL_COLUMNS`:
    k_z, its 1-sigma, cov(end drift, k_z), its own prior 1-sigma; all NaN where the store has none): the first six
    arguments of `gyrodrift.learn.fleet_prior`'s re-weighting."""

    def column(name: str) -> np.ndarray:
        return runs.numbers(name) if name in runs.columns else np.full(len(runs), math.nan)

    coeff, coeff_std, cov, prior_std = (column(c) for c in SMOOTHER_THERMAL_COLUMNS)
    return column("drift_smoother_deg_h"), column("drift_smoother_std_deg_h"), coeff, coeff_std, cov, prior_std


def identified_k1(runs, prior: tuple[float, float] | None) -> np.ndarray:
    """The identified law's k1 of each run [deg/h/degC]: the smoother's k_z re-weighted by the k_z prior ``(mean,
    std)`` (as `gyrodrift.procedure.identify.fleet_posterior`), 0 under the smoother's constant model or without a
    prior (a model whose physics base is not the fleet one: identify's law is then the constant)."""
    from gyrodrift.learn.fleet_prior import posterior_with_coefficient_prior

    if prior is None:
        return np.zeros(len(runs))
    thermal, _, k1, *_ = posterior_with_coefficient_prior(*smoother_posterior_inputs(runs), prior[0], prior[1])
    usable = np.asarray(thermal, bool) & np.isfinite(runs.numbers("temp_end_c"))
    return np.where(usable, np.asarray(k1, float), 0.0)


def fleet_base_deg_h(runs, prior: tuple[float, float]) -> np.ndarray:
    """The hybrid's fleet physics base of each run [deg/h]: the smoother's end drift re-weighted by the k_z prior
    ``(mean, std)`` (its own drift under its constant model)."""
    from gyrodrift.learn.fleet_prior import posterior_with_coefficient_prior

    _, drift, *_ = posterior_with_coefficient_prior(*smoother_posterior_inputs(runs), prior[0], prior[1])
    return np.atleast_1d(np.asarray(drift, float))


def _rms(x: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.sqrt(np.mean(np.asarray(x, float) ** 2, axis=axis))


def _group_metrics(finals: dict, maxima: dict, rows: np.ndarray, seed: int) -> dict[str, Any]:
    """The ``GROUPS`` entry of one group (`compare_laws`): per method and the paired comparisons."""
    n = int(rows.size)
    out: dict[str, Any] = {"n": n, "methods": {}, "identified_vs": {}, "gap_closed": {}}
    if n == 0:
        return out
    boot = rows[np.random.default_rng(seed).integers(0, n, size=(BOOTSTRAP, n))]  # paired: one set for all
    for name in finals:
        f, m = finals[name][rows], maxima[name][rows]
        shares = {"under_1nmi_final": float(np.mean(f < ONE_NMI)), "under_1nmi_72h": float(np.mean(m < ONE_NMI))}
        out["methods"][name] = {
            **shares,
            **{f"{s}_std": math.sqrt(v * (1.0 - v) / n) for s, v in shares.items()},
            "rms_final_nmi": float(_rms(f)),
            "rms_final_nmi_std": float(np.std(_rms(finals[name][boot]))),
        }
    law_f, law_m = finals["identified law"], maxima["identified law"]
    for other in ("constant today", "offline best constant"):
        f, m = finals[other], maxima[other]
        d_final = np.mean(law_f[boot] < ONE_NMI, axis=1) - np.mean(f[boot] < ONE_NMI, axis=1)
        d_72h = np.mean(law_m[boot] < ONE_NMI, axis=1) - np.mean(m[boot] < ONE_NMI, axis=1)
        d_rms = _rms(law_f[boot]) - _rms(f[boot])
        out["identified_vs"][other] = {
            "d_under_1nmi_final": float(np.mean(law_f[rows] < ONE_NMI) - np.mean(f[rows] < ONE_NMI)),
            "d_under_1nmi_final_std": float(np.std(d_final)),
            "d_under_1nmi_72h": float(np.mean(law_m[rows] < ONE_NMI) - np.mean(m[rows] < ONE_NMI)),
            "d_under_1nmi_72h_std": float(np.std(d_72h)),
            "d_rms_final_nmi": float(_rms(law_f[rows]) - _rms(f[rows])),
            "d_rms_final_nmi_std": float(np.std(d_rms)),
        }
    for key in ("rms_final_nmi", "under_1nmi_final", "under_1nmi_72h"):
        today, law, best = (out["methods"][k][key] for k in ("constant today", "identified law", "offline best law"))
        out["gap_closed"][key] = (today - law) / (today - best) if today != best else math.nan
    return out


def law_covariance(runs, prior: tuple[float, float], t_ref_c) -> np.ndarray:
    """The identified law's covariance over (eps_b, k1) per run, shape (runs, 2, 2) [deg/h, deg/h/degC]: the fleet
    posterior's (end drift, k_z) block (`gyrodrift.learn.fleet_prior.posterior_with_coefficient_prior`, as
    `gyrodrift.procedure.identify` reports it without the learned term's variance: what the 16 h data give), the
    end drift's variance alone under the smoother's constant model; moved from `t_ref_c` (T_a) to the truth's T_ref
    T_b as ``A P A'``, A = [[1, T_b - T_a], [0, 1]] (`gyrodrift.fleet.law_limit`)."""
    from gyrodrift.learn.fleet_prior import posterior_with_coefficient_prior

    thermal, _, _, var_d, cov_dk, var_k = posterior_with_coefficient_prior(
        *smoother_posterior_inputs(runs), prior[0], prior[1]
    )
    thermal = np.asarray(thermal, bool) & np.isfinite(runs.numbers("temp_end_c"))
    cov_dk, var_k = np.where(thermal, cov_dk, 0.0), np.where(thermal, var_k, 0.0)
    p = np.stack([np.stack([var_d, cov_dk], -1), np.stack([cov_dk, var_k], -1)], axis=1)
    a = np.zeros_like(p)
    a[:, 0, 0] = a[:, 1, 1] = 1.0
    a[:, 0, 1] = runs.numbers("truth_law_t_ref_c") - np.asarray(t_ref_c, float)
    return a @ p @ np.swapaxes(a, 1, 2)


def compare_laws(
    runs, constant_deg_h, prior: tuple[float, float] | None, *, seed: int = 0, campaign=None
) -> dict[str, Any]:
    """The comparison on the held-out `runs` (`gyrodrift.fleet.store.CampaignRuns` with curves): `constant_deg_h`
    the hybrid default's drift per run [deg/h], `prior` its fleet k_z prior ``(mean, std)`` [deg/h/degC] or None
    (module docstring); `campaign` (`gyrodrift.fleet.spec.Campaign`, optional) gives the simulated laws and the
    time line of the physical limit. Returns the JSON-ready ``drift_laws`` section of ``study.json``: ``methods``,
    ``groups`` (each with ``n``, per-method metrics, ``identified_vs`` and ``gap_closed``), ``how`` (the split and
    the noise in words), the per-run ``final_nmi`` of every method, the runs' ``excursion_c`` and, with a fleet
    prior, ``limit``: the physical limit of the identified law and of the law on the fleet base
    (`gyrodrift.fleet.law_limit.limit_report`, the data's covariance `law_covariance`), else None."""
    from gyrodrift.fleet.law_limit import limit_report, simulated_law
    from gyrodrift.procedure.timeline import DEFAULT_TIMELINE
    from gyrodrift.procedure.truth_law import MIN_EXCURSION_C

    zeros = np.zeros(len(runs))
    t_end = runs.numbers("temp_end_c")
    k1 = identified_k1(runs, prior)
    coefficients = {
        "uncompensated": (zeros, zeros, t_end),
        "constant today": (np.asarray(constant_deg_h, float), zeros, t_end),
        "identified law": (np.asarray(constant_deg_h, float), k1, t_end),
    }
    if prior is not None:
        coefficients["law on the fleet base"] = (fleet_base_deg_h(runs, prior), k1, t_end)
    coefficients |= {
        "offline best constant": (runs.numbers("drift_deg_h"), zeros, t_end),
        "offline best law": (
            runs.numbers("truth_law_eps_ref_deg_h"),
            runs.numbers("truth_law_k1_deg_h_per_c"),
            runs.numbers("truth_law_t_ref_c"),
        ),
    }
    finals, maxima = {}, {}
    for name, (eps, slope, t_ref) in coefficients.items():
        err = law_errors_nmi(runs, eps, slope, t_ref)
        finals[name], maxima[name] = err[:, -1], np.max(err, axis=1)
    masks = run_groups(runs)
    groups = {g: _group_metrics(finals, maxima, np.flatnonzero(mask), seed) for g, mask in masks.items()}
    limit = None
    if prior is not None:
        cov = law_covariance(runs, prior, t_end)
        laws = {
            name: (eps + slope * (runs.numbers("truth_law_t_ref_c") - t_ref), slope, cov)
            for name, (eps, slope, t_ref) in coefficients.items()
            if name in ("identified law", "law on the fleet base")
        }
        timeline = DEFAULT_TIMELINE if campaign is None else campaign.timeline
        limit = limit_report(
            runs,
            laws,
            finals,
            masks,
            future_hours=timeline.truth_h - timeline.features_h,
            simulated=None if campaign is None else simulated_law(campaign, runs),
        )
    return {
        "methods": list(coefficients),
        "groups": groups,
        "identified_k1_deg_h_per_c": k1,
        "k1_prior_deg_h_per_c": None if prior is None else [float(prior[0]), float(prior[1])],
        "excursion_c": excursion_c(runs),
        "final_nmi": finals,
        "limit": limit,
        "how": (
            "72 h errors from each run's linear error curves (no navigation); daily swing: "
            f"{SWING_COLUMN} > 0; steady temperature: no swing and an effective excursion over the navigation "
            f"under {MIN_EXCURSION_C:g} deg C; shares with their binomial 1-sigma, RMS and paired differences with "
            f"a bootstrap 1-sigma ({BOOTSTRAP} resamples of the runs, seed {seed})"
        ),
    }
