"""Identification of the axial drift of one run: alignment + 12 h navigation + the drift model.

The model (`gyrodrift.learn.drift_model.DriftModel`: an LSSVR, or a hybrid of a physics estimate and an LSSVR
correction) maps the run's features (latitude at 12 h, temperature over the 12 h) to the axial drift [deg/h], the total
constant to subtract from the z gyro. Beside it the result carries the physics inversion of the same latitude
error (`gyrodrift.learn.baselines.physics_inversion`), the 12 h curve fit of the latitude and longitude error curves
with its 1-sigma (`gyrodrift.learn.curve_fit`), the 16 h smoother's drift with its 1-sigma
(`gyrodrift.procedure.smoother`: the Cramer-Rao line of these 16 h) and the alignment's own z-drift estimate with its
1-sigma. The model's interval is a normalised cross-validation interval for the run's label
(``DriftModel.predict_interval``, default coverage 90 %; conservative for the drift itself): the physics 1-sigmas and
the spread of a Gaussian process with fitted length scales (`gyrodrift.learn.spread`; wider where the run's inputs are
far from the training runs'), scaled by the out-of-sample scores of its training runs; its note says on how many runs
it rests and how much wider it is than the physics alone (``DriftModel.interval_note``). A run outside the training
runs' range (per input or jointly, ``DriftModel.check_inputs``) is flagged (``outside_training_range``,
``range_warnings``): its drift is an extrapolation. A drift beyond a navigation-grade RLG's
`gyrodrift.runs.table.NAVIGATION_GRADE_DRIFT_DEG_H`, or far outside the training labels' range
(`gyrodrift.runs.table.drift_range_problems`), is flagged too (``outside_drift_range``, one more ``range_warnings``
line). ``model_std_deg_h`` stays None: the interval is empirical, not a Gaussian 1-sigma.

A hybrid whose physics base is the fleet-prior smoother (``DriftModel.physics_column_ ==
"drift_smoother_fleet_deg_h"``) gets the run's smoother columns, its thermal ones included (``features_run_table``),
and the result reports that base, the smoother's end drift re-weighted by the model's pooled k_z prior
(``DriftModel.coefficient_prior_``), with its 1-sigma: the model's drift is that base plus its learned correction.

The drift law (``Identification.drift_law``, a `gyrodrift.drift_law.DriftLaw`): the drift to subtract as a function
of the measured temperature, eps(T) = eps_ref + k1 (T - T_ref), identified at the end of the 16 h span (the end of
the features window, where the smoother's end drift refers to). T_ref is the temperature there
(``RunFeatures.temp_end_c``), eps_ref the identified drift (the constant the law replaces: the law at T_ref is it,
so nothing that uses the constant changes), k1 the smoother's k_z re-weighted by the model's fleet prior, exactly
as the base's end drift is (`gyrodrift.learn.fleet_prior.posterior_with_coefficient_prior`). Its covariance over
(eps_ref, k1, k3): the joint posterior of (end drift, k_z) with the learned correction's variance
(`DriftModel.learned_std_deg_h`) added to eps_ref's. k3 (the temperature-rate term) is 0: the smoother has no
rate state, so the alignment's data say nothing about it. Without the fleet base, or when the run's smoother used
its constant model (no temperature column, or a temperature that spanned less than its ``thermal_min_range_c``),
the law is the constant (k1 = k3 = 0), its 1-sigma the base's and the learned term's when both are known.
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING

import numpy as np

from gyrodrift.drift_law import DriftLaw
from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.learn.fleet_prior import posterior_with_coefficient_prior
from gyrodrift.learn.interval import min_runs_for_coverage
from gyrodrift.learn.predictor import DriftPredictor
from gyrodrift.logs import ImuLog
from gyrodrift.procedure.features import extract_features, features_run_table
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.plan import mission_outlook
from gyrodrift.procedure.results import Identification, RunFeatures
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.runs.table import drift_range_problems

if TYPE_CHECKING:
    from gyrodrift.learn.drift_model import DriftModel

__all__ = [
    "identify",
    "identified_law",
    "fleet_posterior",
    "model_physics_column",
    "FLEET_BASE",
    "NO_UNCERTAINTY_NOTE",
    "INTERVAL_NOTE",
]

FLEET_BASE = "drift_smoother_fleet_deg_h"
"""The physics base of a hybrid that starts from the smoother with the training fleet's k_z prior."""

NO_UNCERTAINTY_NOTE = "the LSSVR gives a point estimate, no predictive uncertainty"
INTERVAL_NOTE = (
    "cross-validation interval of the run's label: the physics 1-sigma (label, base) and the learner's spread at "
    "this run (a Gaussian process with fitted length scales: wider away from the training runs), scaled by the "
    "out-of-sample scores of the model's training runs; {summary}"
)


def _training_error(model: DriftModel | DriftPredictor) -> tuple[float | None, str | None]:
    try:
        return float(np.mean(np.abs(model.loo_residuals()))), "loo_mae"
    except AttributeError:  # loaded from a file without residuals: no Cholesky factor kept
        pass
    if model.tuning is not None:
        return float(model.tuning.fitness), str(model.tuning.objective)
    return None, None


def model_physics_column(model: DriftModel | DriftPredictor) -> str | None:
    """The physics base a fitted model adds its output to (its resolved ``physics_column_``, else the option
    ``physics_column``), or None when it is fitted on the drift itself (``target="drift"``)."""
    if model.target != "residual":
        return None
    return str(getattr(model, "physics_column_", None) or model.physics_column)


def fleet_posterior(features: RunFeatures, prior: tuple[float, float]) -> tuple:
    """The run's smoother end drift and k_z with the k_z prior ``(mean, std)`` [deg/h/degC] in place of the
    smoother's own, with their covariance (`gyrodrift.learn.fleet_prior.posterior_with_coefficient_prior` of the
    run-table columns: the end drift is what the model's fleet base computes): ``(thermal, drift, k_z, var_drift,
    cov, var_k_z)`` as floats [deg/h, deg/h/degC]; under the smoother's constant model ``thermal`` is false, the
    drift and its variance the smoother's and the rest NaN."""
    mean, std = (float(v) for v in prior)
    out = posterior_with_coefficient_prior(
        features.drift_smoother_deg_h,
        features.drift_smoother_std_deg_h,
        features.smoother_coeff_deg_h_per_c,
        features.smoother_coeff_std_deg_h_per_c,
        features.smoother_end_coeff_cov,
        features.smoother_coeff_prior_std_deg_h_per_c,
        mean,
        std,
    )
    return (bool(out[0]), *(float(v) for v in out[1:]))


def identified_law(
    model: DriftModel | DriftPredictor, table, features: RunFeatures, drift_deg_h: float, fleet: tuple | None
) -> DriftLaw:
    """The drift law of the run (module docstring, "The drift law"): eps_ref the identified drift `drift_deg_h`
    [deg/h] at T_ref the temperature at the end of the features window (``features.temp_end_c``, the smoother's
    last sample, where its end drift refers to), k1 the smoother's k_z with the fleet's prior (`fleet_posterior`)
    when the model has the fleet base and the run's smoother its thermal model, else 0 (the constant); k3 0.
    Covariance: the fleet posterior's (end drift, k_z) block with the learned term's variance
    (`DriftModel.learned_std_deg_h`) added to eps_ref's; for the constant, eps_ref's variance is the base's plus the
    learned term's (None when either is unknown: a model without the interval, a base without a 1-sigma, or when
    the re-weighted block is no covariance: a smoother whose own k_z prior is tighter than the fleet's)."""
    t_ref = float(features.temp_end_c)
    learned_var = math.nan
    if getattr(model, "interval_", None) is not None:
        learned_var = float(model.learned_std_deg_h(table)[0]) ** 2
    if fleet is not None and fleet[0] and math.isfinite(t_ref):
        _, _, k1, var_d, cov_dk, var_k = fleet
        var_ref = var_d + learned_var
        cov = None  # unknown, or not a covariance (a smoother's own k_z prior tighter than the fleet's)
        if math.isfinite(var_ref) and var_ref >= 0.0 and var_k > 0.0 and cov_dk * cov_dk <= var_ref * var_k:
            cov = ((var_ref, cov_dk, 0.0), (cov_dk, var_k, 0.0), (0.0, 0.0, 0.0))
        return DriftLaw(eps_ref_deg_h=drift_deg_h, t_ref_c=t_ref, k1_deg_h_per_c=k1, cov=cov)
    if fleet is not None:
        base_var = fleet[3]
    else:
        _, base_std = model.base_.predict(table, with_std=True)
        base_var = 0.0 if model.target != "residual" else math.nan if base_std is None else float(base_std[0]) ** 2
    std = math.sqrt(base_var + learned_var)
    return DriftLaw.constant(
        drift_deg_h, std if math.isfinite(std) else None, t_ref_c=t_ref if math.isfinite(t_ref) else 20.0
    )


def identify(
    log: ImuLog,
    model: DriftModel | DriftPredictor | str | os.PathLike[str],
    *,
    timeline: Timeline = DEFAULT_TIMELINE,
    lat0_deg: float | None = None,
    features: RunFeatures | None = None,
    chunk_samples: int = 100_000,
    coverage: float = 0.9,
    noise: SensorNoise | None = None,
    quiet: bool = True,
) -> Identification:
    """Identify the axial drift of a run with a fitted drift model.

    Parameters
    ----------
    log : ImuLog
        Opened log with a known site, at least ``align_h + features_h`` (16 h) long.
    model : DriftModel, DriftPredictor or path
        A fitted model, its predictor, or its JSON file (read without scikit-learn:
        `gyrodrift.learn.model_io.load_predictor`).
    timeline, lat0_deg, chunk_samples, quiet
        As in `extract_features`.
    features : RunFeatures, optional
        Reuse features already extracted from this log.
    coverage : float
        Coverage of the interval (0.9: 90 %).
    noise : SensorNoise, optional
        Noise model of the 16 h smoother (default: measured from the log).

    Returns
    -------
    Identification
    """
    if isinstance(model, (str, os.PathLike)):
        from gyrodrift.learn.model_io import load_predictor

        model = load_predictor(model)
    if features is None:
        features = extract_features(
            log, timeline=timeline, lat0_deg=lat0_deg, noise=noise, chunk_samples=chunk_samples, quiet=quiet
        )
    table = features_run_table([features], source=log.label)
    drift = float(model.predict(table)[0])
    interval, note = None, NO_UNCERTAINTY_NOTE
    if model.loo_residuals_deg_h is not None:
        n = len(model.loo_residuals_deg_h)
        _, lo, hi = model.predict_interval(table, coverage)
        if math.isfinite(lo[0]) and math.isfinite(hi[0]):
            interval, note = (float(lo[0]), float(hi[0])), INTERVAL_NOTE.format(summary=model.interval_note(coverage))
        else:
            note = (
                f"{NO_UNCERTAINTY_NOTE}; its {n} training runs are too few for a {100 * coverage:g} % "
                f"jackknife interval (needs at least {min_runs_for_coverage(coverage)})"
            )
    physics = float(physics_inversion(table, t_h=features.hours)[0])
    check = model.check_inputs(table)
    implausible = drift_range_problems([drift], model.training_["runs"].drift_deg_h)[0]
    warnings = tuple(check.messages(table)) + (() if implausible is None else (f"identified drift {implausible}",))
    err, kind = _training_error(model)
    base_column = model_physics_column(model)
    prior = getattr(model, "coefficient_prior_", None) if base_column == FLEET_BASE else None
    fleet = None if prior is None else fleet_posterior(features, prior)
    base_drift, base_std = (math.nan, math.nan) if fleet is None else (fleet[1], math.sqrt(max(fleet[3], 0.0)))
    al = features.alignment
    sm, fleet_ok = features.smoother, math.isfinite(base_std)
    sigma = base_std if fleet_ok else features.drift_smoother_std_deg_h
    mission = None  # what the drift's 1-sigma means for the 72 h (gyrodrift.procedure.plan, as `gyrodrift plan`)
    if sm is not None and math.isfinite(sigma):
        src = "the smoother with the fleet's k_z prior" if fleet_ok else "the smoother (the Cramer-Rao line)"
        mission = mission_outlook(sigma, features.lat0_deg, sm.noise, span_h=sm.span_h, source=src)
    return Identification(
        run=features.run,
        drift_deg_h=drift,
        physics_drift_deg_h=physics,
        alignment_z_drift_deg_h=math.nan if al is None else al.z_drift_deg_h,
        alignment_z_drift_std_deg_h=math.nan if al is None else al.z_drift_std_deg_h,
        model_std_deg_h=None,
        interval_deg_h=interval,
        interval_coverage=coverage,
        uncertainty_note=note,
        training_error_deg_h=err,
        training_error_kind=kind,
        features=features,
        curvefit_drift_deg_h=features.drift_curvefit_deg_h,
        curvefit_drift_std_deg_h=features.drift_curvefit_std_deg_h,
        smoother_drift_deg_h=features.drift_smoother_deg_h,
        smoother_drift_std_deg_h=features.drift_smoother_std_deg_h,
        outside_training_range=bool(check.outside[0]),
        range_warnings=warnings,
        outside_drift_range=implausible is not None,
        model_physics_column=base_column,
        smoother_fleet_drift_deg_h=base_drift,
        smoother_fleet_drift_std_deg_h=base_std,
        coefficient_prior_deg_h_per_c=None if prior is None else (float(prior[0]), float(prior[1])),
        mission=mission,
        drift_law=identified_law(model, table, features, drift, fleet),
    )
