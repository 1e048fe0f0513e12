"""The drift model as a scikit-learn pipeline: run encoder, input scaler, and an LSSVR tuned inside ``fit``.

``DriftModel`` is a :class:`sklearn.pipeline.Pipeline` of three steps,

* ``encode``: :class:`RunEncoder`, a transformer from runs (a :class:`~gyrodrift.runs.RunTable` or its
  structured array, :meth:`RunTable.to_structured`) to the input matrix of one encoding;
* ``scale``: ``StandardScaler``, ``MinMaxScaler`` or ``"passthrough"``;
* ``lssvr``: :class:`TunedLSSVR`, which tunes (gamma, sigma) by chaos PSO, plain PSO or a grid inside its own
  ``fit`` (as ``GaussianProcessRegressor`` optimises its kernel inside ``fit``) and then fits an
  :class:`~gyrodrift.lssvr.LSSVR`,

so ``clone``, ``cross_val_score`` and ``GridSearchCV`` work on the whole model (parameters such as
``encode__encoding`` or ``lssvr__objective``). :func:`make_drift_model` builds one; :func:`fit_drift_model` is
what ``gyrodrift fit`` and ``gyrodrift reproduce`` call (build, fit, with a progress bar). Predictions are axial
drifts in deg/h, the total constant to subtract from the z-gyro output (measured - estimate).
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, TransformerMixin
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler
from sklearn.utils.validation import check_is_fitted

from gyrodrift.choices import SCALINGS
from gyrodrift.encodings import encode, feature_names
from gyrodrift.errors import InputError, OptionError
from gyrodrift.lssvr import LSSVR, _validate_data, condition_warning_message
from gyrodrift.progress import progress
from gyrodrift.runs import RunTable, as_run_table
from gyrodrift.tuning import (
    DEFAULT_BOUNDS,
    SearchBoundWarning,
    TuningResult,
    check_bounds,
    on_search_bound,
    search_bound_message,
    tune_lssvr,
)

__all__ = [
    "DriftModel",
    "RunEncoder",
    "TunedLSSVR",
    "fit_drift_model",
    "jackknife_half_width",
    "make_drift_model",
    "make_scaler",
    "min_runs_for_coverage",
    "training_digest",
]


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
    """SHA-256 of the training runs' values (run, latitudes, temperatures, drift), order included."""
    canon = json.dumps(
        [
            [str(r), repr(float(a)), repr(float(b)), repr(float(c)), repr(float(d)), repr(float(e))]
            for r, a, b, c, d, e in zip(
                runs.run, runs.lat_deg, runs.lat0_deg, runs.temp_min_c, runs.temp_max_c, runs.drift_deg_h, strict=False
            )
        ]
    )
    return hashlib.sha256(canon.encode()).hexdigest()


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
    """Runs -> the input matrix of an encoding (a stateless transformer; see :mod:`gyrodrift.encodings`).

    Parameters
    ----------
    encoding : str, default="temp_range"
        A key of ``gyrodrift.encodings.ENCODINGS`` (keyword-only).

    ``X`` of ``fit``/``transform`` is a :class:`~gyrodrift.runs.RunTable` or a 1-D structured array with its
    fields (:meth:`RunTable.to_structured`, :func:`gyrodrift.runs.as_run_table`); ``transform`` returns an
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
    """An RBF :class:`~gyrodrift.lssvr.LSSVR` whose (gamma, sigma) are tuned inside ``fit``.

    With ``gamma`` and ``sigma`` both given nothing is tuned; otherwise ``fit`` tunes them with
    :func:`gyrodrift.tuning.tune_lssvr` (``method`` on ``objective`` over ``bounds``) and fits the LSSVR with the
    result. A tuned value on the edge of its search box gives a :class:`~gyrodrift.tuning.SearchBoundWarning`
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

    def fit(self, X, y, *, tuning: TuningResult | None = None) -> TunedLSSVR:
        """Tune (unless fixed) and fit.

        ``tuning``, a :class:`~gyrodrift.tuning.TuningResult` of an earlier fit on the same data (a model
        file's record), skips the search and uses its gamma and sigma: how a saved model is rebuilt.
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
                tuning = tune_lssvr(
                    X,
                    y,
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
                )
            gamma, sigma = tuning.gamma, tuning.sigma
            on_bound = on_search_bound(gamma, sigma, check_bounds(tuning.bounds))
            if on_bound:
                warnings.warn(
                    search_bound_message(on_bound, gamma, sigma, tuning.bounds), SearchBoundWarning, stacklevel=2
                )
        self.lssvr_ = LSSVR(gamma=gamma, sigma=sigma).fit(X, y)
        self.gamma_, self.sigma_ = float(gamma), float(sigma)
        self.tuning_ = tuning
        self.on_search_bound_ = on_bound
        self.loo_residuals_ = self.lssvr_.loo_residuals_
        self.n_iter_ = tuning.nit if tuning is not None else 1
        return self

    def predict(self, X) -> np.ndarray:
        """The fitted LSSVR's predictions [unit of y]."""
        check_is_fitted(self, "lssvr_")
        X = _validate_data(self, X, dtype=np.float64, reset=False)
        return self.lssvr_.predict(X)

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


class DriftModel(Pipeline):
    """A drift model: ``encode`` (RunEncoder) -> ``scale`` -> ``lssvr`` (TunedLSSVR), a scikit-learn Pipeline.

    Build it with :func:`make_drift_model`. ``fit(runs)`` takes the targets from ``runs.drift_deg_h`` when
    ``y`` is not given. The properties below read the steps; ``training_`` (set by ``fit``) describes the
    training runs: ``n_runs``, ``sha256`` (``training_digest``), ``source``, and ``runs`` (the table itself,
    kept so that a model file can hold its training data).
    """

    def fit(self, X, y=None, **params) -> DriftModel:
        """Fit on runs (RunTable or structured array) and drifts ``y`` [deg/h] (default: the runs' own)."""
        runs = as_run_table(X)
        if y is None:
            if not runs.has_truth:
                raise InputError(f"{runs.source}: every training run needs drift_deg_h")
            trained = runs
        else:
            trained = _with_drift(runs, y)
        if len(runs) < 3:
            raise InputError(f"{runs.source}: need at least 3 training runs, got {len(runs)}")
        super().fit(X, trained.drift_deg_h, **params)
        self.training_: dict[str, Any] = {
            "n_runs": len(trained),
            "sha256": training_digest(trained),
            "source": trained.source,
            "runs": trained,
        }
        return self

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
        """``n_runs``, ``sha256`` and ``source`` of the training runs."""
        check_is_fitted(self, "training_")
        return {k: v for k, v in self.training_.items() if k != "runs"}

    @property
    def feature_names(self) -> tuple[str, ...]:
        return feature_names(self.encoding)

    @property
    def loo_residuals_deg_h(self) -> np.ndarray:
        """Closed-form leave-one-out residuals on the training runs [deg/h] (true minus left-out prediction).

        The scaler is not refitted per left-out run; with 20+ runs its effect on the residuals is small.
        """
        return self.named_steps["lssvr"].loo_residuals_

    def loo_residuals(self) -> np.ndarray:
        """A copy of :attr:`loo_residuals_deg_h`."""
        return np.array(self.loo_residuals_deg_h, float)

    def fit_warnings(self) -> list[str]:
        """What fitting warned about: tuned values on the edge of their search box, ill-conditioning."""
        return self.named_steps["lssvr"].fit_warnings()

    def predict_interval(self, runs, coverage: float = 0.9) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Identified drift and its jackknife interval [deg/h]: ``(pred, lo, hi)``.

        An empirical interval from the model's leave-one-out residuals (``jackknife_half_width``), valid for
        runs exchangeable with the training runs; it is not a Bayesian posterior (the LSSVR has none). When
        gamma and sigma were tuned on the LOO error, the same residuals were minimised by the tuning, so the
        interval is slightly optimistic (tests/test_intervals.py measures about nominal coverage with 40 runs).
        """
        half = jackknife_half_width(self.loo_residuals(), coverage)
        pred = self.predict(runs)
        return pred, pred - half, pred + half


def _with_drift(runs: RunTable, y) -> RunTable:
    """``runs`` with its drift column replaced by ``y`` [deg/h] (what the model was trained on)."""
    y = np.asarray(y, float)
    if y.shape != (len(runs),):
        raise InputError(f"{runs.source}: y has shape {y.shape}, expected ({len(runs)},), one drift per run")
    return RunTable(
        run=runs.run,
        lat_deg=runs.lat_deg,
        lat0_deg=runs.lat0_deg,
        temp_min_c=runs.temp_min_c,
        temp_max_c=runs.temp_max_c,
        drift_deg_h=y,
        split=runs.split,
        source=runs.source,
    )


def make_drift_model(
    *,
    encoding: str = "temp_range",
    scaling: str = "standard",
    **lssvr_params: Any,
) -> DriftModel:
    """An unfitted :class:`DriftModel`: ``RunEncoder(encoding)``, the scaler, ``TunedLSSVR(**lssvr_params)``."""
    feature_names(encoding)
    TunedLSSVR(**lssvr_params)  # unknown names fail here, with scikit-learn's message
    return DriftModel(
        [
            ("encode", RunEncoder(encoding=encoding)),
            ("scale", make_scaler(scaling)),
            ("lssvr", TunedLSSVR(**lssvr_params)),
        ]
    )


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
) -> DriftModel:
    """Build and fit a drift model on runs with known drift (``make_drift_model`` then ``fit``).

    With ``gamma`` and ``sigma`` both given no tuning is done; otherwise they are tuned by ``method``
    (``cpso``, ``pso`` or ``grid``) on ``objective`` (``loo_mae``, ``train_mae``, ``kfold_mae``), with a
    progress bar unless ``quiet``. ``sigma`` is in scaled input units. ``callback(intermediate_result)``,
    if given, is called once per tuning iteration as well (e.g. to drive an outer progress bar). ``rng`` is
    the ``random_state`` of the tuner. The returned model keeps no callback.
    """
    if not train.has_truth:
        raise InputError(f"{train.source}: every training run needs drift_deg_h")
    if len(train) < 3:
        raise InputError(f"{train.source}: need at least 3 training runs, got {len(train)}")
    if (gamma is None) != (sigma is None):
        raise OptionError("give both gamma and sigma, or neither (then both are tuned)")
    model = make_drift_model(
        encoding=encoding,
        scaling=scaling,
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
    return model
