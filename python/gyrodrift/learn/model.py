"""The drift model as a scikit-learn pipeline: run encoder, input scaler, and an LSSVR tuned inside ``fit``.

``DriftModel`` is a :class:`sklearn.pipeline.Pipeline` of three steps,

* ``encode``: :class:`RunEncoder`, a transformer from runs (a :class:`~gyrodrift.runs.table.RunTable` or its
  structured array, :meth:`RunTable.to_structured`) to the input matrix of one encoding;
* ``scale``: ``StandardScaler``, ``MinMaxScaler`` or ``"passthrough"``;
* ``lssvr``: :class:`TunedLSSVR`, which tunes (gamma, sigma) by chaos PSO, plain PSO or a grid inside its own
  ``fit`` (as ``GaussianProcessRegressor`` optimises its kernel inside ``fit``) and then fits an
  :class:`~gyrodrift.learn.lssvr.LSSVR`,

so ``clone``, ``cross_val_score`` and ``GridSearchCV`` work on the whole model (parameters such as
``encode__encoding`` or ``lssvr__objective``). :func:`make_drift_model` builds one; :func:`fit_drift_model` is
what ``gyrodrift fit`` and ``gyrodrift reproduce`` call (build, fit, with a progress bar). Predictions are axial
drifts in deg/h, the total constant to subtract from the z-gyro output (measured - estimate).

Parameters of the model itself (not of a step):

* ``target``: ``"drift"`` (the LSSVR learns the drift) or ``"residual"`` (hybrid: the LSSVR learns the label
  minus a physics estimate, and the prediction is physics + learned correction, so the learner models only
  what physics cannot, e.g. how the drift over the next 72 h follows temperature);
* ``physics_column``: the physics estimate (base) of the hybrid (``gyrodrift.choices.PHYSICS_COLUMNS``,
  computed by `physics_estimate`): ``"drift_smoother_fleet_deg_h"`` (the 16 h smoother's end drift re-weighted
  by the training fleet's pooled prior of its thermal coefficient k_z, `gyrodrift.learn.fleet_prior`: a new run with
  the prior of all training runs, ``coefficient_prior_``, a training run with the prior pooled without it),
  ``"drift_inversion_deg_h"`` (the 12 h inversion, computed from the table's latitudes), a run-table column
  (``"drift_curvefit_deg_h"``, ``"drift_smoother_deg_h"``), or ``"auto"`` (default), resolved by ``fit``
  (`resolve_physics_column`: the fleet base when the training runs allow it, else the smoother's drift, else the
  inversion) into ``physics_column_``;
* ``label_weighting``: ``"auto"`` weights the runs by their label 1-sigma when the table has a
  ``drift_std_deg_h`` column (weighted LS-SVM, ``C_i = gamma w_i``, ``w_i = mean(v) / v_i``, ``v_i = s_i^2``
  plus the base's ``b_i^2`` below), ``"none"`` never does;
* ``base_uncertainty``: ``"auto"`` (default): where the hybrid's base has a 1-sigma ``b_i`` for every training
  run (the fleet base's re-weighted one, ``drift_smoother_std_deg_h``, ``drift_curvefit_std_deg_h``; the
  inversion has none) the target label - base has the noise of both, and ``s_i^2 + b_i^2`` takes the place of
  ``s_i^2`` in the label weights, the spread model's known noise and the calibration scores, and the new run's
  own ``b(x)^2`` joins the interval; ``"none"``: never (model files of schema 3 and before);
* ``calibration_folds``: how the interval is calibrated (below); 0 by default (the closed-form leave-one-out
  residuals at the tuned hyperparameters), K >= 2 for residuals of models re-tuned without each of K folds.

Uncertainty (``predict_interval``, ``check_inputs``): an interval for the label a new run would get
(conservative for its drift itself by the label noise's share), half-width ``t c sqrt(l(x)^2 + s_rms^2 + b(x)^2)``:

* the physics' share: ``s_rms`` the training runs' rms label 1-sigma, ``b(x)`` the new run's base 1-sigma (0
  without one);
* the learner's share ``l(x)``: the 1-sigma of the learned term from a Gaussian process fitted to the LSSVR's
  target with a linear trend, one RBF length scale per input, the label 1-sigmas as known noise and a run-to-run
  term (`gyrodrift.learn.spread.SpreadGP`; larger away from the training runs), plus how far the LSSVR's prediction
  departs from the GP's mean beyond the largest such departure among the training runs; capped at the learned
  term's own prior 1-sigma over the training range (``learned_cap_deg_h_``, `SpreadGP.prior_std`), so that far
  out the interval is never wider than ``t c (sqrt(s_rms^2 + b^2) + cap)``;
* the calibration ``t c`` (``interval_scale_``, `gyrodrift.learn.spread.calibration_scale`): ``c`` the robust scale of
  the n scores ``r_i / sqrt(m_i^2 + s_i^2 + b_i^2)`` (``r_i`` run i's closed-form leave-one-out residual, ``m_i``
  the GP's leave-one-out 1-sigma of the learned term, ``s_i``, ``b_i`` its label's and base's), wild scores left
  out and named (`IntervalOutlierWarning`), times `tuning_inflation` (n) for having tuned gamma and sigma on
  those residuals; ``t`` the Student-t quantile with ``n_used - 1`` degrees of freedom. ``interval_summary`` and
  ``interval_note`` say on how many runs it rests and how much wider it is than the physics alone.

docs/identification.md, "Intervals and extrapolation", and docs/studies/2026-11-27-intervals.md (coverage and
width over 8-140-run fleets).
``check_inputs`` flags runs whose inputs lie outside the training runs' range, per input and jointly
(Mahalanobis distance of the scaled inputs beyond the largest among the training runs).
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats
from sklearn.base import BaseEstimator, RegressorMixin, TransformerMixin, clone
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler
from sklearn.utils.validation import check_is_fitted

from gyrodrift.choices import BASE_UNCERTAINTIES, MIN_THERMAL_RUNS, PHYSICS_CHOICES, PHYSICS_COLUMNS, SCALINGS, TARGETS
from gyrodrift.errors import InputError, OptionError
from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.learn.encodings import encode, feature_names
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior, pooled_coefficient_prior
from gyrodrift.learn.lssvm_system import IllConditionedWarning, check_sample_weight, condition_warning_message
from gyrodrift.learn.lssvr import LSSVR, _validate_data
from gyrodrift.learn.spread import CalibrationScale, SpreadGP, calibration_scale
from gyrodrift.learn.tuning import (
    DEFAULT_BOUNDS,
    SearchBoundWarning,
    TuningResult,
    check_bounds,
    on_search_bound,
    search_bound_message,
    tune_lssvr,
)
from gyrodrift.progress import progress
from gyrodrift.runs.table import SMOOTHER_THERMAL_COLUMNS, RunTable, as_run_table, check_smoother_thermal

__all__ = [
    "DriftModel",
    "IntervalOutlierWarning",
    "tuning_inflation",
    "FLEET_PHYSICS",
    "fleet_priors",
    "resolve_physics_column",
    "thermal_runs",
    "InputCheck",
    "label_weights",
    "physics_estimate",
    "RunEncoder",
    "TunedLSSVR",
    "fit_drift_model",
    "jackknife_half_width",
    "make_drift_model",
    "make_scaler",
    "min_runs_for_coverage",
    "training_digest",
]


DEFAULT_CALIBRATION_FOLDS = 0
"""Folds of the interval's calibration (``DriftModel(calibration_folds=...)``). 0 (default): the LSSVR's
closed-form leave-one-out residuals at the tuned gamma and sigma, with the spread model's own leave-one-out
1-sigmas, their scale inflated by `tuning_inflation` for the optimism of having tuned on them (no refit: the
calibration costs one Gaussian-process fit). K >= 2: each run's residual comes from a model fitted and tuned
without its fold (K more tunings; no inflation)."""


def tuning_inflation(n_runs: int) -> float:
    """The factor on the calibration scale of closed-form leave-one-out scores at tuned hyperparameters
    [dimensionless]: ``sqrt(1 + TUNING_OPTIMISM / sqrt(n_runs))`` (1.31 at 8 runs, 1.22 at 16, 1.14 at 48, 1.08
    at 140).

    Tuning (gamma, sigma) on the leave-one-out residuals makes them smaller than a new run's error (the search
    picks the pair that happens to fit these runs best). Measured: on closed-form fleets (examples/interval_study.py,
    seeds 11-22 at 8-48 runs, 11-13 at 140; not the seeds of the study it is judged on) the median ratio of the
    held-out runs' mean squared score to the leave-one-out one was 1.86, 1.29, 1.42, 1.37 and 1.08 at 8, 16, 24,
    48 and 140 runs; ``1 + 2 / sqrt(n)`` follows it (docs/studies/2026-11-27-intervals.md)."""
    return math.sqrt(1.0 + TUNING_OPTIMISM / math.sqrt(max(int(n_runs), 1)))


TUNING_OPTIMISM = 2.0
"""See `tuning_inflation` [sqrt(runs)]."""


class IntervalOutlierWarning(UserWarning):
    """A training run's calibration score is wild (`gyrodrift.learn.spread.calibration_scale`): it is left out of the
    interval's scale, and named."""


_MIN_FOLD_RUNS = 3


def make_scaler(scaling: str):
    """The scikit-learn transformer for a scaling name (``"passthrough"`` for none)."""
    if scaling == "standard":
        return StandardScaler()
    if scaling == "minmax":
        return MinMaxScaler()
    if scaling == "none":
        return "passthrough"
    raise OptionError(f"unknown scaling {scaling!r}; expected one of {', '.join(SCALINGS)}")


def scaling_name(scaler) -> str:
    """The scaling name (``SCALINGS``) of a scale step."""
    if isinstance(scaler, str) and scaler == "passthrough" or scaler is None:
        return "none"
    if isinstance(scaler, StandardScaler):
        return "standard"
    if isinstance(scaler, MinMaxScaler):
        return "minmax"
    raise OptionError(f"unknown scale step {scaler!r}; expected StandardScaler, MinMaxScaler or 'passthrough'")


def training_digest(runs: RunTable) -> str:
    """SHA-256 of the training runs' values (run, latitudes, temperatures, drift, then any optional columns
    by name), order included. A table without optional columns has the digest of gyrodrift 0.2."""
    rows = [
        [str(r), repr(float(a)), repr(float(b)), repr(float(c)), repr(float(d)), repr(float(e))]
        for r, a, b, c, d, e in zip(
            runs.run, runs.lat_deg, runs.lat0_deg, runs.temp_min_c, runs.temp_max_c, runs.drift_deg_h, strict=False
        )
    ]
    for name, values in runs.extra.items():
        for row, v in zip(rows, values, strict=True):
            row.append(f"{name}={float(v)!r}")
    return hashlib.sha256(json.dumps(rows).encode()).hexdigest()


def label_weights(std_deg_h) -> np.ndarray:
    """Weights of runs whose labels have 1-sigma ``std_deg_h`` [deg/h]: ``w_i = mean(s^2) / s_i^2``.

    The weighted LS-SVM's per-run regularisation is then ``C_i = gamma w_i = gamma / (s_i^2 / mean(s^2))``:
    a run twice as uncertain as the average counts a quarter, and equal sigmas give the unweighted model."""
    s2 = np.asarray(std_deg_h, float) ** 2
    if s2.size == 0 or not np.all(np.isfinite(s2)) or not np.all(s2 > 0):
        raise InputError("label 1-sigmas (drift_std_deg_h) must be finite and > 0 for every training run")
    return s2.mean() / s2


FLEET_PHYSICS = "drift_smoother_fleet_deg_h"
"""The fleet-prior smoother base (``PHYSICS_COLUMNS``): computed by the model, not a table column."""

SMOOTHER_COLUMNS = ("drift_smoother_deg_h", "drift_smoother_std_deg_h")
"""The smoother's end drift and its 1-sigma [deg/h]: ``physics_column="auto"`` takes the fleet base when every
training run has both (the base itself needs the drift; its 1-sigma, re-weighted, enters the noise and the
interval)."""

THERMAL_COLUMNS = SMOOTHER_THERMAL_COLUMNS
"""The smoother's thermal coefficient k_z, its 1-sigma, cov(end drift, k_z) and its own prior 1-sigma: the fleet
base needs them in the table (empty for a run under the smoother's constant model)."""

BASE_STD_COLUMNS = {
    "drift_curvefit_deg_h": "drift_curvefit_std_deg_h",
    "drift_smoother_deg_h": "drift_smoother_std_deg_h",
    FLEET_PHYSICS: "drift_smoother_std_deg_h",
}
"""The run-table column of the 1-sigma of a base [deg/h] (the fleet base's is re-weighted from it)."""


def _missing_runs(runs: RunTable, values) -> str:
    missing = [str(r) for r, v in zip(runs.run, values, strict=True) if not np.isfinite(v)]
    return f"{', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''}"


def _require_column(runs: RunTable, column: str, what: str) -> np.ndarray:
    """Column ``column`` of every run; else an ``InputError`` naming the table, the column and the runs."""
    if column not in runs.extra:
        raise InputError(f"{runs.source}: column {column} ({what}) is missing: the table has no such column")
    values = runs.column(column)
    if not np.all(np.isfinite(values)):
        raise InputError(f"{runs.source}: column {column} ({what}) is missing for run(s) {_missing_runs(runs, values)}")
    return np.asarray(values, float)


def thermal_runs(runs: RunTable) -> np.ndarray:
    """True for the runs with the smoother's thermal estimate of k_z (every ``THERMAL_COLUMNS`` value usable: the
    test of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`); False under its constant model or without
    the columns."""
    k, sk, c, s0 = (runs.column(name) for name in THERMAL_COLUMNS)
    with np.errstate(over="ignore"):
        vk = sk * sk
    return np.isfinite(k) & np.isfinite(vk) & (vk > 0.0) & np.isfinite(c) & np.isfinite(s0) & (s0 > 0.0)


def resolve_physics_column(runs: RunTable) -> tuple[str, str]:
    """``(column, why)``: the physics base ``physics_column="auto"`` takes on training runs ``runs``.

    The fleet-prior smoother (``drift_smoother_fleet_deg_h``) when every run has ``SMOOTHER_COLUMNS`` and at
    least ``MIN_THERMAL_RUNS`` have a thermal k_z; else the smoother's drift (``drift_smoother_deg_h``) when
    every run has it; else the 12 h inversion (``drift_inversion_deg_h``). ``why`` says so in words."""
    n_thermal = int(thermal_runs(runs).sum())
    if all(runs.has_column(c) for c in SMOOTHER_COLUMNS):
        if n_thermal >= MIN_THERMAL_RUNS:
            return FLEET_PHYSICS, (
                f"every run has the smoother's drift and 1-sigma, {n_thermal} of {len(runs)} its thermal k_z: the "
                "16 h smoother's end drift with the fleet's pooled k_z prior"
            )
        why = f"{n_thermal} run(s) with the smoother's thermal k_z, the fleet prior needs {MIN_THERMAL_RUNS}"
        return "drift_smoother_deg_h", f"{why}: the 16 h smoother's end drift"
    if runs.has_column("drift_smoother_deg_h"):
        return "drift_smoother_deg_h", "no drift_smoother_std_deg_h for every run: the 16 h smoother's end drift"
    if "drift_smoother_deg_h" in runs.extra:
        values = runs.column("drift_smoother_deg_h")
        why = f"drift_smoother_deg_h is missing for run(s) {_missing_runs(runs, values)}"
    else:
        why = "no smoother columns"
    return "drift_inversion_deg_h", f"{why}: the 12 h inversion"


def fleet_priors(runs: RunTable) -> tuple[tuple[float, float], np.ndarray]:
    """The fleet's k_z priors of training runs ``runs`` [deg/h/degC]: ``(prior, per_run)``.

    ``prior`` = `pooled_coefficient_prior` of every run's k_z (what a new run's base uses); ``per_run`` (n_runs,
    2): for each run with a thermal k_z the prior pooled from the *other* runs (leave one out: its own k_z is
    not counted twice, so its base is what a new run's would be), for the others ``prior`` (their base does not
    use it). ``InputError`` with fewer than ``MIN_THERMAL_RUNS`` thermal runs."""
    thermal = thermal_runs(runs)
    if int(thermal.sum()) < MIN_THERMAL_RUNS:
        raise InputError(
            f"{runs.source}: the physics base {FLEET_PHYSICS} needs at least {MIN_THERMAL_RUNS} training runs with "
            f"the smoother's thermal k_z ({', '.join(THERMAL_COLUMNS[:2])}; each run's base pools the others'), "
            f"got {int(thermal.sum())}"
        )
    k = np.where(thermal, runs.column(THERMAL_COLUMNS[0]), np.nan)
    sk = np.where(thermal, runs.column(THERMAL_COLUMNS[1]), np.nan)
    prior = pooled_coefficient_prior(k, sk)
    per_run = np.tile(np.asarray(prior, float), (len(runs), 1))
    for i in np.flatnonzero(thermal):
        others = np.arange(len(runs)) != i
        per_run[i] = pooled_coefficient_prior(k[others], sk[others])
    return prior, per_run


def physics_estimate(runs: RunTable, column: str = "drift_inversion_deg_h", *, prior=None, with_std: bool = False):
    """The physics estimate of each run's drift [deg/h] named by ``column`` (``PHYSICS_COLUMNS``).

    * ``"drift_inversion_deg_h"``: the 12 h inversion of the latitude error (`physics_inversion`);
    * ``"drift_smoother_fleet_deg_h"``: the smoother's end drift with the k_z prior ``prior`` in place of its own
      (`gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`): ``prior`` is ``(mean, std)`` [deg/h/degC] for
      every run (a model's ``coefficient_prior_``) or an (n_runs, 2) array, one prior per run (the leave-one-out
      priors of training runs, `fleet_priors`). Every run needs ``drift_smoother_deg_h``, and the table the
      ``THERMAL_COLUMNS`` (a run under the smoother's constant model has them empty: its base is its smoother
      drift unchanged); the 1-sigma comes from ``drift_smoother_std_deg_h`` (NaN without it);
    * any other name: an optional run-table column, which every run must have.

    A missing column gives an ``InputError`` naming the table, the column and the runs. ``with_std``: return
    ``(estimate, std)``, ``std`` the estimate's 1-sigma [deg/h] (the fleet base's re-weighted one, a column
    base's ``BASE_STD_COLUMNS`` column, NaN where a run has none; None for the inversion)."""
    if column not in PHYSICS_COLUMNS:
        raise OptionError(f"unknown physics column {column!r}; expected one of {', '.join(PHYSICS_COLUMNS)}")
    what = f"needed by the hybrid model's physics base {column}"
    if column == "drift_inversion_deg_h":
        estimate, std = physics_inversion(runs, t_h=12.0), None
    elif column == FLEET_PHYSICS:
        if prior is None:
            raise InputError(f"the physics estimate {FLEET_PHYSICS} needs the fleet's k_z prior")
        drift = _require_column(runs, "drift_smoother_deg_h", what)
        drift_std = runs.column("drift_smoother_std_deg_h")
        for name in THERMAL_COLUMNS:
            if name not in runs.extra:
                raise InputError(f"{runs.source}: column {name} ({what}) is missing: the table has no such column")
        check_smoother_thermal(runs, what)
        k, sk, c, s0 = (runs.column(name) for name in THERMAL_COLUMNS)
        prior = np.asarray(prior, float)
        if prior.shape == (2,):
            estimate, std = drift_with_coefficient_prior(
                drift, drift_std, k, sk, c, s0, float(prior[0]), float(prior[1])
            )
        elif prior.shape == (len(runs), 2):
            pairs = [
                drift_with_coefficient_prior(drift[i], drift_std[i], k[i], sk[i], c[i], s0[i], *map(float, prior[i]))
                for i in range(len(runs))
            ]
            estimate = np.array([p[0] for p in pairs], float)
            std = np.array([p[1] for p in pairs], float)
        else:
            raise InputError(f"a k_z prior is (mean, std) or one per run, shape ({len(runs)}, 2); got {prior.shape}")
    else:
        estimate = _require_column(runs, column, what)
        std = np.asarray(runs.column(BASE_STD_COLUMNS[column]), float)
    estimate = np.asarray(estimate, float)
    return (estimate, None if std is None else np.asarray(std, float)) if with_std else estimate


def _check_coverage(coverage) -> float:
    if isinstance(coverage, bool) or not isinstance(coverage, (int, float)) or not 0.0 < coverage < 1.0:
        raise OptionError(f"coverage must be within (0, 1), got {coverage!r}")
    return float(coverage)


def jackknife_half_width(residuals, coverage: float) -> float:
    """Half-width of the jackknife prediction interval from leave-one-out residuals [their unit].

    The ceil((n + 1) coverage)-th smallest |r_i| (Barber, Candes, Ramdas, Tibshirani 2021, "Predictive
    inference with the jackknife+", the plain jackknife interval): for exchangeable runs the interval
    prediction +- half-width covers a new run's true value with probability of about ``coverage`` (the
    guarantee of the plain jackknife is weaker than jackknife+'s, but it needs no refit per left-out run).
    ``inf`` when n is too small for the coverage asked (n < coverage / (1 - coverage)).
    """
    coverage = _check_coverage(coverage)
    r = np.sort(np.abs(np.asarray(residuals, float)))
    if r.size == 0 or not np.all(np.isfinite(r)):
        raise InputError("need finite leave-one-out residuals for an interval")
    k = math.ceil((r.size + 1) * coverage)
    return float(r[k - 1]) if k <= r.size else math.inf


def min_runs_for_coverage(coverage: float) -> int:
    """Smallest number of leave-one-out residuals for which ``jackknife_half_width`` is finite."""
    coverage = _check_coverage(coverage)
    n = 1
    while math.ceil((n + 1) * coverage) > n:
        n += 1
    return n


# --------------------------------------------------------------------------------------------------
# The steps
# --------------------------------------------------------------------------------------------------


class RunEncoder(TransformerMixin, BaseEstimator):
    """Runs -> the input matrix of an encoding (a stateless transformer; see :mod:`gyrodrift.learn.encodings`).

    Parameters
    ----------
    encoding : str, default="temp_range"
        A key of ``gyrodrift.learn.encodings.ENCODINGS`` (keyword-only).

    ``X`` of ``fit``/``transform`` is a :class:`~gyrodrift.runs.table.RunTable` or a 1-D structured array with its
    fields (:meth:`RunTable.to_structured`, :func:`gyrodrift.runs.table.as_run_table`); ``transform`` returns an
    ``(n_runs, n_features)`` float array whose columns ``get_feature_names_out()`` names (units in the names).
    """

    def __init__(self, *, encoding: str = "temp_range") -> None:
        self.encoding = encoding

    def fit(self, X, y=None) -> RunEncoder:
        """Check the encoding and the runs (nothing is learnt)."""
        names = feature_names(self.encoding)
        as_run_table(X)
        self.n_features_out_ = len(names)
        return self

    def transform(self, X) -> np.ndarray:
        """The input matrix ``encode(runs, encoding)``, shape (n_runs, n_features)."""
        return encode(as_run_table(X), self.encoding)

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """Names of the encoded features (units in the names)."""
        return np.asarray(feature_names(self.encoding), dtype=object)


class TunedLSSVR(RegressorMixin, BaseEstimator):
    """An RBF :class:`~gyrodrift.learn.lssvr.LSSVR` whose (gamma, sigma) are tuned inside ``fit``.

    With ``gamma`` and ``sigma`` both given nothing is tuned; otherwise ``fit`` tunes them with
    :func:`gyrodrift.learn.tuning.tune_lssvr` (``method`` on ``objective`` over ``bounds``) and fits the LSSVR with the
    result. A tuned value on the edge of its search box gives a :class:`~gyrodrift.learn.tuning.SearchBoundWarning`
    (as scikit-learn's ``GaussianProcessRegressor`` warns on kernel bounds); ill-conditioning gives the LSSVR's
    warning or error.

    Parameters (all keyword-only)
    -----------------------------
    gamma, sigma : float or None, default=None
        Fixed hyperparameters (sigma in the units of the scaled inputs), or None for both to tune them.
    objective : {"loo_mae", "train_mae", "kfold_mae"}, default="loo_mae"
    method : {"cpso", "pso", "grid"}, default="cpso"
    bounds : ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)), default=``DEFAULT_BOUNDS``
    n_particles, max_iter, w, c1, c2, chaos_steps : swarm settings (the paper's by default)
    grid_size : int, default=40
        Points per axis of the ``"grid"`` method.
    n_folds : int, default=5
        Folds of ``"kfold_mae"``.
    random_state : int, numpy Generator or None
        Seeds the swarm; an int gives the same result every time, a Generator is consumed.
    callback : callable or None
        ``callback(intermediate_result)`` once per tuning iteration (e.g. a progress bar).

    Attributes
    ----------
    lssvr_ : LSSVR
        The fitted LSSVR.
    gamma_, sigma_ : float
        The hyperparameters used.
    tuning_ : TuningResult or None
        How they were tuned (None when given).
    on_search_bound_ : list of str
        Tuned values on the edge of their search box (``"gamma"``, ``"sigma"``).
    loo_residuals_ : ndarray, shape (n_samples,)
        Exact leave-one-out residuals of the fitted LSSVR, observed minus predicted [unit of y]
        (``LSSVR.loo_residuals_``).
    n_iter_ : int
        Tuning iterations run (``tuning_.nit``; 1 for the grid, and for given gamma and sigma: one fit).
    n_features_in_ : int
    """

    def __init__(
        self,
        *,
        gamma: float | None = None,
        sigma: float | None = None,
        objective: str = "loo_mae",
        method: str = "cpso",
        bounds=DEFAULT_BOUNDS,
        n_particles: int = 30,
        max_iter: int = 100,
        w: float = 0.75,
        c1: float = 2.0,
        c2: float = 2.0,
        chaos_steps: int = 10,
        grid_size: int = 40,
        n_folds: int = 5,
        random_state: int | np.random.Generator | None = None,
        callback: Callable[[Any], Any] | None = None,
    ) -> None:
        self.gamma = gamma
        self.sigma = sigma
        self.objective = objective
        self.method = method
        self.bounds = bounds
        self.n_particles = n_particles
        self.max_iter = max_iter
        self.w = w
        self.c1 = c1
        self.c2 = c2
        self.chaos_steps = chaos_steps
        self.grid_size = grid_size
        self.n_folds = n_folds
        self.random_state = random_state
        self.callback = callback

    def fit(
        self, X, y, *, tuning: TuningResult | None = None, sample_weight=None, solution: dict | None = None
    ) -> TunedLSSVR:
        """Tune (unless fixed) and fit.

        ``tuning``, a :class:`~gyrodrift.learn.tuning.TuningResult` of an earlier fit on the same data (a model
        file's record), skips the search and uses its gamma and sigma: how a saved model is rebuilt.
        ``sample_weight`` (> 0 per sample) weights the LS-SVM and the tuning fitness (``gyrodrift.learn.lssvm_system``).
        ``solution``, a model file's stored LSSVR solution (``alpha``, ``intercept``, ``loo_residuals``,
        ``condition_number``), is used as given after `LSSVR.from_solution`'s O(32 n) check (with every sample
        weight > 0): how a saved model is rebuilt without solving the n x n system.
        """
        X, y = _validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        if (self.gamma is None) != (self.sigma is None):
            raise OptionError("give both gamma and sigma, or neither (then both are tuned)")
        on_bound: list[str] = []
        if self.gamma is not None and self.sigma is not None:
            gamma, sigma = self.gamma, self.sigma
            tuning = None
        else:
            if tuning is None:
                w = check_sample_weight(sample_weight, len(y), allow_zero=True)
                keep = slice(None) if w is None else w > 0  # a zero weight leaves its sample out
                tuning = tune_lssvr(
                    X[keep],
                    y[keep],
                    objective=self.objective,
                    method=self.method,
                    bounds=self.bounds,
                    n_particles=self.n_particles,
                    max_iter=self.max_iter,
                    w=self.w,
                    c1=self.c1,
                    c2=self.c2,
                    chaos_steps=self.chaos_steps,
                    grid_size=self.grid_size,
                    n_folds=self.n_folds,
                    rng=self.random_state,
                    callback=self.callback,
                    sample_weight=None if w is None else w[keep],
                )
            gamma, sigma = tuning.gamma, tuning.sigma
            on_bound = on_search_bound(gamma, sigma, check_bounds(tuning.bounds))
            if on_bound:
                warnings.warn(
                    search_bound_message(on_bound, gamma, sigma, tuning.bounds), SearchBoundWarning, stacklevel=2
                )
        positive = sample_weight is None or bool(np.all(np.asarray(sample_weight, float) > 0))
        if solution is not None and positive:
            self.lssvr_ = LSSVR.from_solution(X, y, gamma=gamma, sigma=sigma, sample_weight=sample_weight, **solution)
        else:
            self.lssvr_ = LSSVR(gamma=gamma, sigma=sigma).fit(X, y, sample_weight=sample_weight)
        self.gamma_, self.sigma_ = float(gamma), float(sigma)
        self.tuning_ = tuning
        self.on_search_bound_ = on_bound
        self.loo_residuals_ = self.lssvr_.loo_residuals_
        self.n_iter_ = tuning.nit if tuning is not None else 1
        return self

    def predict(self, X, offset=None) -> np.ndarray:
        """The fitted LSSVR's predictions [unit of y] (``offset``: one more term of each sum, `LSSVR.predict`)."""
        check_is_fitted(self, "lssvr_")
        X = _validate_data(self, X, dtype=np.float64, reset=False)
        return self.lssvr_.predict(X, offset=offset)

    def fit_warnings(self) -> list[str]:
        """What ``fit`` warned about (edge of the search box, ill-conditioning), as messages."""
        check_is_fitted(self, "lssvr_")
        out = []
        if self.on_search_bound_ and self.tuning_ is not None:
            out.append(search_bound_message(self.on_search_bound_, self.gamma_, self.sigma_, self.tuning_.bounds))
        cond = condition_warning_message(self.lssvr_.condition_number_, f"for {self.lssvr_._describe()}")
        if cond:
            out.append(cond)
        return out


# --------------------------------------------------------------------------------------------------
# The pipeline
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class InputCheck:
    """Where runs lie relative to a model's training runs (:meth:`DriftModel.check_inputs`).

    Attributes
    ----------
    outside : ndarray of bool, shape (n_runs,)
        True for a run outside the training range (any input, or jointly).
    outside_inputs : list of tuple of str
        Per run, the names of the inputs outside the training runs' [min, max].
    mahalanobis : ndarray, shape (n_runs,)
        Mahalanobis distance of the scaled inputs from the training runs' mean (their covariance).
    mahalanobis_limit : float
        The largest such distance among the training runs: beyond it a run is outside jointly.
    """

    outside: np.ndarray
    outside_inputs: list
    mahalanobis: np.ndarray
    mahalanobis_limit: float

    def messages(self, runs: RunTable) -> list[str]:
        """One line per run outside the training range (empty when none is)."""
        out = []
        for i in np.flatnonzero(self.outside):
            what = (
                ", ".join(self.outside_inputs[i]) if self.outside_inputs[i] else "jointly: each input within its range"
            )
            out.append(
                f"run {runs.run[i]}: outside the training runs' range ({what}; Mahalanobis distance "
                f"{self.mahalanobis[i]:.2f}, training maximum {self.mahalanobis_limit:.2f}): an extrapolation"
            )
        return out


class DriftModel(Pipeline):
    """A drift model: ``encode`` (RunEncoder) -> ``scale`` -> ``lssvr`` (TunedLSSVR), a scikit-learn Pipeline.

    Build it with :func:`make_drift_model`. ``fit(runs)`` takes the targets from ``runs.drift_deg_h`` when
    ``y`` is not given. The properties below read the steps; ``training_`` (set by ``fit``) describes the
    training runs: ``n_runs``, ``sha256`` (``training_digest``), ``source``, ``weighted`` (whether the label
    1-sigmas weighted the fit), and ``runs`` (the table itself, kept so that a model file can hold its
    training data). ``target``, ``physics_column``, ``label_weighting``, ``base_uncertainty`` and
    ``calibration_folds``: see the module docstring.

    Fitted attributes of the base: ``physics_column_`` (the resolved base, None for ``target="drift"``),
    ``physics_reason_`` (why ``auto`` took it, in words), ``coefficient_prior_`` (the fleet base's k_z prior
    ``(mean, std)`` [deg/h/degC] pooled from all training runs, else None) and ``base_std_used_`` (whether the
    base's 1-sigma joined the label's).
    """

    def __init__(
        self,
        steps,
        *,
        transform_input=None,
        memory=None,
        verbose=False,
        target: str = "drift",
        physics_column: str = "auto",
        label_weighting: str = "auto",
        calibration_folds: int = DEFAULT_CALIBRATION_FOLDS,
        base_uncertainty: str = "auto",
    ) -> None:
        super().__init__(steps, transform_input=transform_input, memory=memory, verbose=verbose)
        self.target = target
        self.physics_column = physics_column
        self.label_weighting = label_weighting
        self.calibration_folds = calibration_folds
        self.base_uncertainty = base_uncertainty

    def _check_options(self) -> None:
        if self.target not in TARGETS:
            raise OptionError(f"unknown target {self.target!r}; expected one of {', '.join(TARGETS)}")
        if self.physics_column not in PHYSICS_CHOICES:
            raise OptionError(
                f"unknown physics column {self.physics_column!r}; expected one of {', '.join(PHYSICS_CHOICES)}"
            )
        if self.base_uncertainty not in BASE_UNCERTAINTIES:
            raise OptionError(
                f"unknown base uncertainty {self.base_uncertainty!r}; expected one of {', '.join(BASE_UNCERTAINTIES)}"
            )
        if self.label_weighting not in ("auto", "none"):
            raise OptionError(f"unknown label weighting {self.label_weighting!r}; expected auto or none")
        folds = self.calibration_folds
        if isinstance(folds, bool) or not isinstance(folds, (int, np.integer)) or folds < 0 or folds == 1:
            raise OptionError(f"calibration_folds must be 0 (leave-one-out) or an integer >= 2, got {folds!r}")

    def _resolve_physics(self, trained: RunTable) -> tuple[np.ndarray, np.ndarray | None]:
        """Set ``physics_column_`` (the resolved base), ``physics_reason_`` (why, in words), ``coefficient_prior_``
        and ``base_std_used_``; return the training runs' base [deg/h] (a fleet base with each run's
        leave-one-out prior) and its 1-sigma [deg/h] when it joins the label noise (else None)."""
        self.coefficient_prior_: tuple[float, float] | None = None
        self.base_std_used_ = False
        if self.target != "residual":
            self.physics_column_: str | None = None
            self.physics_reason_ = "none: the LSSVR learns the drift itself (target drift)"
            return np.zeros(len(trained)), None
        if self.physics_column == "auto":
            column, why = resolve_physics_column(trained)
        else:
            column, why = self.physics_column, "as given"
        per_run = None
        if column == FLEET_PHYSICS:  # a missing drift named per run before the count of thermal runs
            _require_column(trained, "drift_smoother_deg_h", f"needed by the hybrid model's physics base {column}")
            prior, per_run = fleet_priors(trained)
            self.coefficient_prior_ = (float(prior[0]), float(prior[1]))
        base, std = physics_estimate(trained, column, prior=per_run, with_std=True)
        self.physics_column_, self.physics_reason_ = column, why
        self.base_std_used_ = bool(self.base_uncertainty == "auto" and std is not None and np.all(np.isfinite(std)))
        return base, (std if self.base_std_used_ else None)

    def _base(self, runs: RunTable, *, with_std: bool = False):
        """What the LSSVR's output is added to for new runs [deg/h]: the physics estimate (residual target; a fleet
        base with the prior of every training run, ``coefficient_prior_``) or 0. ``with_std``: ``(base, its
        1-sigma or None)``."""
        if self.target != "residual":
            return (np.zeros(len(runs)), None) if with_std else np.zeros(len(runs))
        check_is_fitted(self, "physics_column_")
        column = str(self.physics_column_)
        prior = self.coefficient_prior_ if column == FLEET_PHYSICS else None
        return physics_estimate(runs, column, prior=prior, with_std=with_std)

    def fit(
        self, X, y=None, *, spread_theta=None, interval_calibration=None, interval_disagreement=None, **params
    ) -> DriftModel:
        """Fit on runs (RunTable or structured array) and drifts ``y`` [deg/h] (default: the runs' own).

        With ``label_weighting="auto"`` and a ``drift_std_deg_h`` value for every run the LS-SVM is weighted
        by ``label_weights``; with ``target="residual"`` it is fitted on ``y`` minus the physics estimate.
        Then the interval's spread model (`gyrodrift.learn.spread.SpreadGP`) and its calibration scores (module
        docstring). ``spread_theta``, ``interval_calibration`` (out-of-sample residuals and spreads) and
        ``interval_disagreement`` (``disagreement_deg_h_``), a model file's record, are used as given: no
        likelihood is maximised, no fold refitted, no leave-one-out spread or training prediction computed: how a
        saved model is rebuilt.
        """
        self._check_options()
        runs = as_run_table(X)
        if y is None:
            if not runs.has_truth:
                raise InputError(f"{runs.source}: every training run needs drift_deg_h")
            trained = runs
        else:
            trained = _with_drift(runs, y)
        if len(runs) < 3:
            raise InputError(f"{runs.source}: need at least 3 training runs, got {len(runs)}")
        base, base_std = self._resolve_physics(trained)
        label_std = trained.column("drift_std_deg_h") if trained.has_column("drift_std_deg_h") else None
        s = np.zeros(len(trained)) if label_std is None else np.asarray(label_std, float)
        # the target label - base carries the noise of both: its variance [(deg/h)^2] and 1-sigma
        noise_var = s**2 if base_std is None else s**2 + base_std**2
        noise_std = label_std if base_std is None else np.sqrt(noise_var)
        weighted = self.label_weighting == "auto" and label_std is not None
        if weighted:
            params = {**params, "lssvr__sample_weight": label_weights(noise_std)}
        super().fit(runs, trained.drift_deg_h - base, **params)
        self.training_: dict[str, Any] = {
            "n_runs": len(trained),
            "sha256": training_digest(trained),
            "source": trained.source,
            "weighted": bool(weighted),
            "runs": trained,
        }
        Z = self[:-1].transform(runs)
        encoded = self.named_steps["encode"].transform(runs)
        self.input_min_, self.input_max_ = encoded.min(axis=0), encoded.max(axis=0)
        self.input_mean_ = Z.mean(axis=0)
        cov = np.atleast_2d(np.cov(Z, rowvar=False))
        self.input_precision_ = np.linalg.pinv(cov)
        self.mahalanobis_limit_ = float(self._mahalanobis(Z).max())
        self.spread_ = SpreadGP(theta=spread_theta).fit(
            Z, trained.drift_deg_h - base, noise_std, loo=interval_calibration is None
        )
        if interval_calibration is not None:
            residuals, spreads = (np.asarray(v, float) for v in interval_calibration)
            if not (residuals.shape == spreads.shape == (len(trained),)) or not np.all(np.isfinite(residuals)):
                raise InputError(f"the interval's calibration must hold {len(trained)} residuals and spreads")
        elif self.calibration_folds == 0 or len(trained) < 2 * _MIN_FOLD_RUNS:
            residuals = np.asarray(self.loo_residuals_deg_h, float)
            spreads = np.sqrt(np.maximum(self.spread_.loo_std_**2 - noise_var, 0.0))
        else:
            residuals, spreads = self._out_of_fold(trained)
        self.interval_residuals_, self.interval_spreads_ = residuals, spreads
        self.label_std_rms_ = float(np.sqrt(np.mean(s**2)))
        self.interval_scores_ = residuals / np.sqrt(spreads**2 + noise_var)
        tuned = self.named_steps["lssvr"].tuning_ is not None
        inflation = tuning_inflation(len(trained)) if tuned and self.calibration_folds == 0 else 1.0
        self.interval_scale_: CalibrationScale = calibration_scale(self.interval_scores_, inflation=inflation)
        self.learned_cap_deg_h_ = self.spread_.prior_std()
        self.disagreement_deg_h_ = (
            float(np.max(self._disagreement(Z))) if interval_disagreement is None else float(interval_disagreement)
        )
        self.physics_std_deg_h_ = np.sqrt(noise_var)  # the training runs' physics-known 1-sigma (label, base)
        if interval_calibration is None:  # a loaded model's file carries the warning already
            for text in self.interval_warnings():
                warnings.warn(text, IntervalOutlierWarning, stacklevel=2)
        return self

    def interval_warnings(self) -> list[str]:
        """One message naming the training runs whose calibration score is wild (left out of the interval's
        scale; `gyrodrift.learn.spread.calibration_scale`), or none."""
        check_is_fitted(self, "interval_scale_")
        cal = self.interval_scale_
        if not len(cal.wild):
            return []
        runs = self.training_["runs"].run
        wild = ", ".join(f"{runs[i]} ({self.interval_scores_[i]:+.2f})" for i in cal.wild)
        return [
            f"interval: calibration score(s) of run(s) {wild} are wild against the scale "
            f"{cal.scale / cal.inflation:.2f} of the other {cal.n_used} runs (leave-one-out t-test, family-wise 5 %): "
            f"left out of the interval's scale "
            f"(with them its plain rms would be {cal.raw_rms:.2f}); check those runs' labels and inputs"
        ]

    def _out_of_fold(self, trained: RunTable) -> tuple[np.ndarray, np.ndarray]:
        """``(r, m)`` [deg/h]: ``r_i`` the residual of run i under a model fitted and tuned on the other folds
        (``calibration_folds`` folds, run i in fold ``i mod K``), ``m_i`` that model's spread at run i (its
        hyperparameters those of the full model's spread, refitted on the fold's runs without a new likelihood
        search: what matters here is that gamma and sigma are tuned without the fold)."""
        n = len(trained)
        k = min(int(self.calibration_folds), n)
        fold = np.arange(n) % k
        residuals, spreads = np.empty(n), np.empty(n)
        with warnings.catch_warnings():  # the full model's warnings are the ones that count
            warnings.simplefilter("ignore", SearchBoundWarning)
            warnings.simplefilter("ignore", IllConditionedWarning)
            for j in range(k):
                part = clone(self).set_params(calibration_folds=0, lssvr__callback=None)
                part.fit(trained.select(fold != j), spread_theta=self.spread_.theta_)
                held = trained.select(fold == j)
                spreads[fold == j] = part.spread_.predict_std(part[:-1].transform(held))
                residuals[fold == j] = held.drift_deg_h - part.predict(held)
        return residuals, spreads

    def predict(self, X, **params) -> np.ndarray:
        """Identified drift [deg/h] of each run: the LSSVR's output (plus the physics estimate for a hybrid, added
        inside the LSSVR's compensated sum: `LSSVR.predict`)."""
        runs = as_run_table(X)
        if self.target != "residual":
            return super().predict(runs, **params)
        # the last step called directly: an offset routed through Pipeline.predict would need metadata requests
        return self.named_steps["lssvr"].predict(self[:-1].transform(runs), offset=self._base(runs), **params)

    def score(self, X, y=None, sample_weight=None, **params) -> float:
        """R^2 of the identified drifts (``predict``) against ``y`` (default: the runs' drifts)."""
        from sklearn.metrics import r2_score

        runs = as_run_table(X)
        y = runs.drift_deg_h if y is None else y
        return float(r2_score(y, self.predict(runs), sample_weight=sample_weight))

    @property
    def encoding(self) -> str:
        """The run encoding (``encode__encoding``)."""
        return str(self.named_steps["encode"].encoding)

    @property
    def scaling(self) -> str:
        """The input scaling name (``SCALINGS``)."""
        return scaling_name(self.named_steps["scale"])

    @property
    def lssvr(self) -> LSSVR:
        """The fitted LSSVR (inside the ``lssvr`` step)."""
        return self.named_steps["lssvr"].lssvr_

    @property
    def tuning(self) -> TuningResult | None:
        """How gamma and sigma were tuned (None when given)."""
        return self.named_steps["lssvr"].tuning_

    @property
    def training(self) -> dict:
        """``n_runs``, ``sha256``, ``source`` and ``weighted`` of the training runs."""
        check_is_fitted(self, "training_")
        return {k: v for k, v in self.training_.items() if k != "runs"}

    @property
    def feature_names(self) -> tuple[str, ...]:
        return feature_names(self.encoding)

    @property
    def loo_residuals_deg_h(self) -> np.ndarray:
        """Closed-form leave-one-out residuals on the training runs [deg/h] (true minus left-out prediction).

        The scaler is not refitted per left-out run; with 20+ runs its effect on the residuals is small. For a
        hybrid these are the residuals of the drift too: a run's base does not depend on the others, except the
        fleet base's k_z prior, which for a training run is pooled from the others already.
        """
        return self.named_steps["lssvr"].loo_residuals_

    def loo_residuals(self) -> np.ndarray:
        """A copy of :attr:`loo_residuals_deg_h`."""
        return np.array(self.loo_residuals_deg_h, float)

    def fit_warnings(self) -> list[str]:
        """What fitting warned about: tuned values on the edge of their search box, ill-conditioning, wild
        calibration scores (`interval_warnings`)."""
        return self.named_steps["lssvr"].fit_warnings() + self.interval_warnings()

    def interval_scores(self) -> np.ndarray:
        """The calibration scores of the interval (dimensionless, signed): each training run's out-of-fold
        residual divided by its predicted spread (module docstring)."""
        check_is_fitted(self, "interval_scores_")
        return np.array(self.interval_scores_, float)

    def predict_spread(self, runs) -> np.ndarray:
        """The spread model's 1-sigma of each run's drift [deg/h] (`SpreadGP.predict_std`; label noise
        excluded); grows away from the training runs on the scale of its fitted length scales."""
        check_is_fitted(self, "spread_")
        return self.spread_.predict_std(self[:-1].transform(as_run_table(runs)))

    def _disagreement(self, Z: np.ndarray) -> np.ndarray:
        """``|LSSVR(z) - GP mean(z)|`` [deg/h]: how far the two learners of the same target part at scaled inputs
        ``Z`` (both fit the training runs; away from them the LSSVR's extrapolation may leave the GP's)."""
        return np.abs(self.named_steps["lssvr"].predict(Z) - self.spread_.predict_mean(Z))

    def _interval_sigmas(self, runs: RunTable) -> tuple[np.ndarray, np.ndarray]:
        """``(learned, physics)`` 1-sigmas [deg/h] of each run's label about its prediction, before calibration:
        ``learned = min(sqrt(spread(x)^2 + e(x)^2), learned_cap_deg_h_)`` with ``e(x)`` the disagreement of the
        LSSVR and the GP mean beyond the largest among the training runs (``disagreement_deg_h_``),
        ``physics = sqrt(s_rms^2 + b(x)^2)``."""
        Z = self[:-1].transform(runs)
        excess = np.maximum(self._disagreement(Z) - self.disagreement_deg_h_, 0.0)
        learned = np.minimum(np.hypot(self.spread_.predict_std(Z), excess), self.learned_cap_deg_h_)
        if not self.base_std_used_:
            return learned, np.full(len(runs), self.label_std_rms_)
        _, base_std = self._base(runs, with_std=True)
        if not np.all(np.isfinite(base_std)):
            raise InputError(
                f"{runs.source}: column {BASE_STD_COLUMNS[str(self.physics_column_)]} (the 1-sigma of the hybrid "
                f"model's physics base, in its interval) is missing for run(s) {_missing_runs(runs, base_std)}"
            )
        return learned, np.sqrt(self.label_std_rms_**2 + base_std**2)

    def predict_interval(self, runs, coverage: float = 0.9) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Identified drift and its interval [deg/h]: ``(pred, lo, hi)``.

        An interval for the run's label (the `truth` a new run would get, at the training runs' rms label
        1-sigma ``label_std_rms_``): half-width ``t c sqrt(min(spread(x), U)^2 + s_rms^2 + b(x)^2)``, with
        ``spread`` the spread model's 1-sigma of the learned term at the run (`predict_spread`, wider away from the
        training runs), ``U`` its cap (``learned_cap_deg_h_``, `SpreadGP.prior_std`: the learned term's 1-sigma
        before any run), ``b`` the run's base 1-sigma when ``base_std_used_`` (else 0; a run without it:
        ``InputError``), and ``t c`` the calibration (``interval_scale_.multiplier(coverage)``: Student-t quantile
        times the robust scale of the training runs' out-of-sample scores, `gyrodrift.learn.spread.calibration_scale`).
        Far from the training runs it widens, never past ``t c (sqrt(s_rms^2 + b^2) + U)``: the physics alone plus
        the learned term's own uncertainty. Not a Bayesian posterior. tests/learn/test_intervals.py,
        docs/identification.md.
        """
        coverage = _check_coverage(coverage)
        check_is_fitted(self, "interval_scale_")
        runs = as_run_table(runs)
        pred = self.predict(runs)
        learned, physics = self._interval_sigmas(runs)
        half = self.interval_scale_.multiplier(coverage) * np.sqrt(learned**2 + physics**2)
        return pred, pred - half, pred + half

    def interval_summary(self, coverage: float = 0.9) -> dict:
        """What the interval rests on: ``n_runs`` (training runs), ``n_used`` (scores in its scale),
        ``wild_runs`` (left out: `interval_warnings`), ``scale`` (c, inflation included), ``inflation``,
        ``multiplier`` (t c at ``coverage``), ``learned_cap_deg_h``, and ``physics_ratio``: the median over the
        training runs of the half-width at their out-of-sample 1-sigma, ``t c sqrt(m_i^2 + p_i^2)``, over the
        physics alone's, ``z p_i`` (``p_i = sqrt(s_i^2 + b_i^2)`` the run's label and base 1-sigma, ``m_i`` the
        learner's, ``z`` the normal quantile; None when the physics gives no 1-sigma). O(n): no prediction."""
        coverage = _check_coverage(coverage)
        check_is_fitted(self, "interval_scale_")
        cal = self.interval_scale_
        train = self.training_["runs"]
        mult = cal.multiplier(coverage)
        physics = self.physics_std_deg_h_
        ratio = None
        if np.all(physics > 0):
            z = float(stats.norm.ppf(0.5 + coverage / 2.0))
            ratio = float(np.median(mult * np.hypot(self.interval_spreads_, physics) / (z * physics)))
        return {
            "coverage": coverage,
            "n_runs": len(train),
            "n_used": cal.n_used,
            "wild_runs": [str(train.run[i]) for i in cal.wild],
            "scale": cal.scale,
            "inflation": cal.inflation,
            "multiplier": mult,
            "learned_cap_deg_h": float(self.learned_cap_deg_h_),
            "physics_ratio": ratio,
        }

    def interval_note(self, coverage: float = 0.9) -> str:
        """`interval_summary` in one line (what ``fit`` and ``identify`` say)."""
        s = self.interval_summary(coverage)
        rests = (
            f"rests on {s['n_used']} of {s['n_runs']} training runs"
            if s["wild_runs"]
            else (f"rests on {s['n_runs']} training runs")
        )
        how = f"calibration scale {s['scale']:.2f}"
        if s["inflation"] != 1.0:
            how += f" incl. x{s['inflation']:.2f} for tuning on the leave-one-out residuals"
        wider = (
            "no physics 1-sigma to compare with"
            if s["physics_ratio"] is None
            else f"{s['physics_ratio']:.2f} times the physics alone (label and base 1-sigma) at the median training run"
        )
        return f"{100 * s['coverage']:g} % interval {rests} ({how}); {wider}"

    def _mahalanobis(self, Z: np.ndarray) -> np.ndarray:
        d = Z - self.input_mean_
        return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", d, self.input_precision_, d), 0.0))

    def check_inputs(self, runs, *, rtol: float = 1e-9) -> InputCheck:
        """Flag runs whose inputs lie outside the training runs' range, per input ([min, max] of the encoded
        inputs, with a relative tolerance ``rtol`` of the range) and jointly (Mahalanobis distance of the
        scaled inputs beyond the largest among the training runs)."""
        check_is_fitted(self, "input_min_")
        runs = as_run_table(runs)
        encoded = self.named_steps["encode"].transform(runs)
        slack = rtol * np.maximum(self.input_max_ - self.input_min_, np.abs(self.input_max_))
        low = encoded < self.input_min_ - slack
        high = encoded > self.input_max_ + slack
        names = self.feature_names
        per = [
            tuple(
                f"{names[j]} {'below' if low[i, j] else 'above'} the training range"
                for j in np.flatnonzero(low[i] | high[i])
            )
            for i in range(len(runs))
        ]
        maha = self._mahalanobis(self[:-1].transform(runs))
        joint = maha > self.mahalanobis_limit_ * (1.0 + 1e-9)
        outside = np.array([bool(p) for p in per]) | joint
        return InputCheck(
            outside=outside, outside_inputs=per, mahalanobis=maha, mahalanobis_limit=self.mahalanobis_limit_
        )


def _with_drift(runs: RunTable, y) -> RunTable:
    """``runs`` with its drift column replaced by ``y`` [deg/h] (what the model was trained on)."""
    y = np.asarray(y, float)
    if y.shape != (len(runs),):
        raise InputError(f"{runs.source}: y has shape {y.shape}, expected ({len(runs)},), one drift per run")
    return runs.replace(drift_deg_h=y)


def make_drift_model(
    *,
    encoding: str = "temp_range",
    scaling: str = "standard",
    target: str = "drift",
    physics_column: str = "auto",
    label_weighting: str = "auto",
    calibration_folds: int = DEFAULT_CALIBRATION_FOLDS,
    base_uncertainty: str = "auto",
    **lssvr_params: Any,
) -> DriftModel:
    """An unfitted :class:`DriftModel`: ``RunEncoder(encoding)``, the scaler, ``TunedLSSVR(**lssvr_params)``;
    ``target``, ``physics_column``, ``label_weighting`` and ``calibration_folds`` as in the module docstring."""
    feature_names(encoding)
    TunedLSSVR(**lssvr_params)  # unknown names fail here, with scikit-learn's message
    model = DriftModel(
        [
            ("encode", RunEncoder(encoding=encoding)),
            ("scale", make_scaler(scaling)),
            ("lssvr", TunedLSSVR(**lssvr_params)),
        ],
        target=target,
        physics_column=physics_column,
        label_weighting=label_weighting,
        calibration_folds=calibration_folds,
        base_uncertainty=base_uncertainty,
    )
    model._check_options()
    return model


DEFAULT_MAX_LABEL_STD_DEG_H = 1e-3
"""Training runs whose label 1-sigma (``drift_std_deg_h``) exceeds this [deg/h] are left out by
:func:`select_labelled_runs`: twice the 1 nmi / 72 h budget at mid latitudes (~4.7e-4 deg/h at 40 deg), such a
label says little about the drift (runs near the equator or a pole)."""


def select_labelled_runs(runs: RunTable, max_label_std_deg_h: float | None = DEFAULT_MAX_LABEL_STD_DEG_H):
    """``(kept, left_out)``: the runs whose label 1-sigma is at most ``max_label_std_deg_h`` [deg/h] (all of
    them without a ``drift_std_deg_h`` column or with None), and the names of the others."""
    if max_label_std_deg_h is None or "drift_std_deg_h" not in runs.extra:
        return runs, []
    std = runs.column("drift_std_deg_h")
    bad = std > max_label_std_deg_h  # NaN (unknown) is kept; infinite (unlabelable) is left out
    return runs.select(~bad), [str(r) for r in runs.run[bad]]


FLAGGED_LABELS = ("exclude", "keep")
"""What `fit_drift_model` does with runs whose ``label_flagged`` is true: leave them out (default) or keep them
(weighted by their ``drift_std_deg_h`` when the fit is weighted)."""


def flagged_labels_mask(runs: RunTable) -> np.ndarray:
    """True for the runs whose ``label_flagged`` column is true (unknown and absent: False)."""
    return np.asarray(runs.column("label_flagged") == 1.0, bool)


def _tick(bar, callback, intermediate_result):
    bar.update(1)
    return callback(intermediate_result) if callback is not None else None


def fit_drift_model(
    train: RunTable,
    *,
    encoding: str = "temp_range",
    scaling: str = "standard",
    objective: str = "loo_mae",
    method: str = "cpso",
    gamma: float | None = None,
    sigma: float | None = None,
    bounds=DEFAULT_BOUNDS,
    n_particles: int = 30,
    max_iter: int = 100,
    chaos_steps: int = 10,
    rng=None,
    quiet: bool = True,
    callback=None,
    target: str = "drift",
    physics_column: str = "auto",
    label_weighting: str = "auto",
    max_label_std_deg_h: float | None = None,
    calibration_folds: int = DEFAULT_CALIBRATION_FOLDS,
    flagged_labels: str = "exclude",
    base_uncertainty: str = "auto",
) -> DriftModel:
    """Build and fit a drift model on runs with known drift (``make_drift_model`` then ``fit``).

    ``max_label_std_deg_h``: leave out runs whose label 1-sigma exceeds it (``select_labelled_runs``; the
    model's ``training_["left_out"]`` names them). ``flagged_labels``: ``"exclude"`` leaves out the runs whose
    ``label_flagged`` is true (named in ``training_["left_out"]`` and ``training_["flagged_left_out"]``),
    ``"keep"`` keeps them (``training_["flagged_kept"]``), down-weighted by their label 1-sigma when the fit is
    weighted. ``target``, ``physics_column``, ``label_weighting``: the
    module docstring.

    With ``gamma`` and ``sigma`` both given no tuning is done; otherwise they are tuned by ``method``
    (``cpso``, ``pso`` or ``grid``) on ``objective`` (``loo_mae``, ``train_mae``, ``kfold_mae``), with a
    progress bar unless ``quiet``. ``sigma`` is in scaled input units. ``callback(intermediate_result)``,
    if given, is called once per tuning iteration as well (e.g. to drive an outer progress bar). ``rng`` is
    the ``random_state`` of the tuner. The returned model keeps no callback.
    """
    if not train.has_truth:
        raise InputError(f"{train.source}: every training run needs drift_deg_h")
    if flagged_labels not in FLAGGED_LABELS:
        raise OptionError(f"unknown flagged_labels {flagged_labels!r}; expected one of {', '.join(FLAGGED_LABELS)}")
    flags = flagged_labels_mask(train)
    flagged_names = [str(r) for r in train.run[flags]]
    if flagged_labels == "exclude":
        train = train.select(~flags)
    train, left_out = select_labelled_runs(train, max_label_std_deg_h)
    if len(train) < 3:
        raise InputError(f"{train.source}: need at least 3 training runs, got {len(train)}")
    if (gamma is None) != (sigma is None):
        raise OptionError("give both gamma and sigma, or neither (then both are tuned)")
    model = make_drift_model(
        encoding=encoding,
        scaling=scaling,
        target=target,
        physics_column=physics_column,
        label_weighting=label_weighting,
        calibration_folds=calibration_folds,
        base_uncertainty=base_uncertainty,
        objective=objective,
        method=method,
        gamma=gamma,
        sigma=sigma,
        bounds=bounds,
        n_particles=n_particles,
        max_iter=max_iter,
        chaos_steps=chaos_steps,
        random_state=rng,
    )
    if gamma is None:
        with progress(max_iter if method != "grid" else 1, f"tuning ({method}, {objective})", quiet, unit="it") as bar:
            model.set_params(lssvr__callback=lambda res: _tick(bar, callback, res))
            try:
                model.fit(train)
            finally:
                model.set_params(lssvr__callback=None)
    else:
        model.fit(train)
    excluded = flagged_names if flagged_labels == "exclude" else []
    model.training_["left_out"] = excluded + left_out
    model.training_["flagged_left_out"] = excluded
    model.training_["flagged_kept"] = [] if excluded else [r for r in flagged_names if r not in left_out]
    return model
