"""The drift model's learner: a scikit-learn ``Pipeline`` from runs to the LSSVR's output (`make_learner`).

Three steps, so that ``clone``, ``cross_val_score`` and ``GridSearchCV`` work on the learner as on any pipeline:

* ``encode``: :class:`RunEncoder`, a transformer from runs (a :class:`~gyrodrift.runs.table.RunTable` or its
  structured array, :meth:`RunTable.to_structured`) to the input matrix of one encoding;
* ``scale``: ``StandardScaler``, ``MinMaxScaler`` or ``"passthrough"`` (`make_scaler`);
* ``lssvr``: :class:`TunedLSSVR`, which tunes (gamma, sigma) by chaos PSO, plain PSO or a grid inside its own
  ``fit`` (as ``GaussianProcessRegressor`` optimises its kernel inside ``fit``) and then fits an
  :class:`~gyrodrift.learn.lssvr.LSSVR`.

The drift model (`gyrodrift.learn.drift_model.DriftModel`) joins this learner with a physics base and an interval.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, TransformerMixin
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler
from sklearn.utils.validation import check_is_fitted

from gyrodrift.choices import SCALINGS
from gyrodrift.errors import OptionError
from gyrodrift.learn.encodings import encode, feature_names
from gyrodrift.learn.lssvm_system import check_sample_weight, condition_warning_message
from gyrodrift.learn.lssvr import LSSVR, _validate_data
from gyrodrift.learn.tuning import (
    TUNED_LSSVR_OPTIONS,
    SearchBoundWarning,
    TuningOptions,
    TuningResult,
    check_bounds,
    on_search_bound,
    search_bound_message,
    tune_lssvr,
)
from gyrodrift.learn.user_warning import warn_user
from gyrodrift.runs.table import as_run_table

__all__ = ["RunEncoder", "TunedLSSVR", "make_learner", "make_scaler", "scaling_name"]


def make_learner(*, encoding: str = "temp_range", scaling: str = "standard", **lssvr_params: Any) -> Pipeline:
    """An unfitted learner: ``RunEncoder(encoding)``, the scaler of ``scaling``, ``TunedLSSVR(**lssvr_params)``
    (unknown encodings, scalings and parameter names fail here, the last with scikit-learn's message)."""
    feature_names(encoding)
    return Pipeline(
        [
            ("encode", RunEncoder(encoding=encoding)),
            ("scale", make_scaler(scaling)),
            ("lssvr", TunedLSSVR(**lssvr_params)),
        ]
    )


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

    Parameters
    ----------
    gamma, sigma : float or None, default=None
        Keyword-only, as all the parameters. Fixed hyperparameters (sigma in the units of the scaled inputs), or
        None for both to tune them.
    objective, method, bounds, n_particles, max_iter, w, c1, c2, chaos_steps, grid_size, n_folds
        How they are tuned: the fields of :class:`~gyrodrift.learn.tuning.TuningOptions` of the same names (their
        defaults, units and meaning; `tuning_options`), flat so that ``get_params``, ``GridSearchCV`` and model
        files see them.
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
        objective: str = TuningOptions.objective,
        method: str = TuningOptions.method,
        bounds=TuningOptions.bounds,
        n_particles: int = TuningOptions.n_particles,
        max_iter: int = TuningOptions.max_iter,
        w: float = TuningOptions.w,
        c1: float = TuningOptions.c1,
        c2: float = TuningOptions.c2,
        chaos_steps: int = TuningOptions.chaos_steps,
        grid_size: int = TuningOptions.grid_size,
        n_folds: int = TuningOptions.n_folds,
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
                    self.tuning_options(),
                    rng=self.random_state,
                    callback=self.callback,
                    sample_weight=None if w is None else w[keep],
                )
            gamma, sigma = tuning.gamma, tuning.sigma
            on_bound = on_search_bound(gamma, sigma, check_bounds(tuning.bounds))
            if on_bound:
                warn_user(search_bound_message(on_bound, gamma, sigma, tuning.bounds), SearchBoundWarning)
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

    def tuning_options(self) -> TuningOptions:
        """This estimator's tuning parameters (`TUNED_LSSVR_OPTIONS`) as a `gyrodrift.learn.tuning.TuningOptions`."""
        return TuningOptions(**{name: getattr(self, name) for name in TUNED_LSSVR_OPTIONS})

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
