"""The drift model: a small meta-estimator joining a learner, a physics base, an interval and input ranges.

As scikit-learn's ``TransformedTargetRegressor`` joins a regressor and a target transformer, :class:`DriftModel`
joins four parts, each a module of its own:

* the learner (`gyrodrift.learn.learner`): a ``Pipeline`` of run encoder, input scaler and an LSSVR tuned inside
  ``fit`` (its parameters ``learner__encode__encoding``, ``learner__lssvr__objective``, ...);
* the physics base (`gyrodrift.learn.physics_base.PhysicsBase`): for ``target="residual"`` (hybrid) the physics
  estimate the learner's output is added to (``physics_column``), the fleet's k_z prior, and the label noise that
  weights the learner (``label_weighting``, ``base_uncertainty``);
* the interval (`gyrodrift.learn.interval.DriftInterval`): the learner's spread and its calibration on out-of-sample
  scores (``calibration_folds``);
* the input ranges (`gyrodrift.learn.ranges.InputRanges`): where new runs lie relative to the training runs.

``clone``, ``cross_val_score`` and ``GridSearchCV`` work on the whole model. :func:`make_drift_model` builds one;
:func:`fit_drift_model` is what ``gyrodrift fit`` and ``gyrodrift reproduce`` call (build, fit, with a progress
bar). Predictions are axial drifts in deg/h, the total constant to subtract from the z-gyro output (measured -
estimate).

Parameters of the model itself (not of a part): ``target`` (``"drift"``: the LSSVR learns the drift, or
``"residual"``: the hybrid, physics + learned correction), ``physics_column`` (``"auto"`` by default, resolved by
``fit`` into ``physics_column_``), ``label_weighting``, ``base_uncertainty`` (`gyrodrift.learn.physics_base`) and
``calibration_folds`` (`gyrodrift.learn.interval.DEFAULT_CALIBRATION_FOLDS`).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.pipeline import Pipeline
from sklearn.utils.validation import check_is_fitted

from gyrodrift.errors import InputError, OptionError
from gyrodrift.learn.encodings import feature_names
from gyrodrift.learn.interval import (
    DEFAULT_CALIBRATION_FOLDS,
    MIN_FOLD_RUNS,
    DriftInterval,
    IntervalOutlierWarning,
    tuning_inflation,
)
from gyrodrift.learn.learner import make_learner, scaling_name
from gyrodrift.learn.lssvm_system import IllConditionedWarning
from gyrodrift.learn.lssvr import LSSVR
from gyrodrift.learn.physics_base import PhysicsBase
from gyrodrift.learn.predictor import DriftPredictor
from gyrodrift.learn.ranges import InputCheck, InputRanges
from gyrodrift.learn.scaling import InputScaler
from gyrodrift.learn.training_record import training_digest
from gyrodrift.learn.tuning import SearchBoundWarning, TuningOptions, TuningResult
from gyrodrift.learn.user_warning import warn_user
from gyrodrift.progress import progress
from gyrodrift.runs.table import RunTable, as_run_table

__all__ = [
    "DEFAULT_MAX_LABEL_STD_DEG_H",
    "FLAGGED_LABELS",
    "DriftModel",
    "fit_drift_model",
    "flagged_labels_mask",
    "make_drift_model",
    "select_labelled_runs",
]


class DriftModel(RegressorMixin, BaseEstimator):
    """A drift model: ``learner`` (a ``Pipeline`` ending in a ``TunedLSSVR`` step named ``lssvr``, e.g.
    `gyrodrift.learn.learner.make_learner`) joined with a physics base, an interval and input ranges (module
    docstring). Build it with :func:`make_drift_model`.

    ``fit(runs)`` takes the targets from ``runs.drift_deg_h`` when ``y`` is not given. Fitted attributes:
    ``learner_`` (the fitted clone of ``learner``), ``base_`` (`PhysicsBase`), ``interval_`` (`DriftInterval`),
    ``ranges_`` (`InputRanges`) and ``training_``: ``n_runs``, ``sha256`` (``training_digest``), ``source``,
    ``weighted`` (whether the label 1-sigmas weighted the fit), and ``runs`` (the table itself, kept so that a model
    file can hold its training data). ``physics_column_`` (the resolved base, None for ``target="drift"``) and
    ``coefficient_prior_`` (the fleet base's k_z prior ``(mean, std)`` [deg/h/degC], else None) are the base's.
    """

    def __init__(
        self,
        learner: Pipeline,
        *,
        target: str = "drift",
        physics_column: str = "auto",
        label_weighting: str = "auto",
        calibration_folds: int = DEFAULT_CALIBRATION_FOLDS,
        base_uncertainty: str = "auto",
    ) -> None:
        self.learner = learner
        self.target = target
        self.physics_column = physics_column
        self.label_weighting = label_weighting
        self.calibration_folds = calibration_folds
        self.base_uncertainty = base_uncertainty

    def _physics_base(self) -> PhysicsBase:
        return PhysicsBase(
            target=self.target,
            column=self.physics_column,
            uncertainty=self.base_uncertainty,
            label_weighting=self.label_weighting,
        )

    def check_options(self) -> None:
        """``OptionError`` naming an unknown target, physics column, base uncertainty, label weighting, or
        ``calibration_folds`` other than 0 or an integer >= 2."""
        self._physics_base().check_options()
        folds = self.calibration_folds
        if isinstance(folds, bool) or not isinstance(folds, (int, np.integer)) or folds < 0 or folds == 1:
            raise OptionError(f"calibration_folds must be 0 (leave-one-out) or an integer >= 2, got {folds!r}")

    def fit(
        self,
        X,
        y=None,
        *,
        spread_theta=None,
        interval_calibration=None,
        interval_disagreement=None,
        training_sha256=None,
        **fit_params,
    ) -> DriftModel:
        """Fit on runs (RunTable or structured array) and drifts ``y`` [deg/h] (default: the runs' own).

        The physics base first (`PhysicsBase.fit`: with ``target="residual"`` the learner is fitted on ``y`` minus
        its estimate, and with ``label_weighting="auto"`` and a ``drift_std_deg_h`` value for every run it is
        weighted by `label_weights`), then the learner (``fit_params`` go to its ``fit``, e.g.
        ``lssvr__tuning``), the input ranges, and the interval's spread model and calibration scores
        (`gyrodrift.learn.interval`). ``spread_theta``, ``interval_calibration`` (out-of-sample residuals and
        spreads), ``interval_disagreement`` (``interval_.disagreement_deg_h_``) and ``training_sha256`` (the
        training runs' `training_digest`, which the caller checked), a model file's record, are used as given: no
        likelihood is maximised, no fold refitted, no leave-one-out spread or training prediction computed, the runs
        not hashed again: how a saved model is rebuilt.
        """
        self.check_options()
        runs = as_run_table(X)
        if y is None:
            if not runs.has_truth:
                raise InputError(f"{runs.source}: every training run needs drift_deg_h")
            trained = runs
        else:
            trained = _with_drift(runs, y)
        if len(runs) < 3:
            raise InputError(f"{runs.source}: need at least 3 training runs, got {len(runs)}")
        base = self.base_ = self._physics_base().fit(trained)
        if base.sample_weight_ is not None:
            fit_params = {**fit_params, "lssvr__sample_weight": base.sample_weight_}
        target = trained.drift_deg_h - base.training_base_
        self.learner_: Pipeline = clone(self.learner).fit(runs, target, **fit_params)
        self.training_: dict[str, Any] = {
            "n_runs": len(trained),
            "sha256": training_digest(trained) if training_sha256 is None else training_sha256,
            "source": trained.source,
            "weighted": base.sample_weight_ is not None,
            "runs": trained,
        }
        Z = self.learner_[:-1].transform(runs)
        self.ranges_ = InputRanges().fit(self.learner_.named_steps["encode"].transform(runs), Z)
        interval = DriftInterval().fit_spread(
            Z, target, base.noise_std_, theta=spread_theta, loo=interval_calibration is None
        )
        if interval_calibration is not None:
            residuals, spreads = (np.asarray(v, float) for v in interval_calibration)
            if not (residuals.shape == spreads.shape == (len(trained),)) or not np.all(np.isfinite(residuals)):
                raise InputError(f"the interval's calibration must hold {len(trained)} residuals and spreads")
        elif self.calibration_folds == 0 or len(trained) < 2 * MIN_FOLD_RUNS:
            residuals = np.asarray(self.loo_residuals_deg_h, float)
            spreads = interval.loo_spreads(base.noise_var_)
        else:
            residuals, spreads = self._out_of_fold(trained, interval.spread_.theta_)
        tuned = self.learner_.named_steps["lssvr"].tuning_ is not None
        inflation = tuning_inflation(len(trained)) if tuned and self.calibration_folds == 0 else 1.0
        self.interval_ = interval.calibrate(
            Z,
            residuals,
            spreads,
            base.noise_var_,
            base.label_std_rms_,
            inflation=inflation,
            learned=self.learner_.named_steps["lssvr"].predict,
            disagreement=interval_disagreement,
        )
        if interval_calibration is None:  # a loaded model's file carries the warning already
            for text in self.interval_warnings():
                warn_user(text, IntervalOutlierWarning)
        return self

    @property
    def predictor_(self) -> DriftPredictor:
        """The fitted parts as a `gyrodrift.learn.predictor.DriftPredictor`, built from them on each access (so it
        follows the fitted attributes): what `predict`, `predict_interval`, `check_inputs` and the interval's
        summaries delegate to, and what a model file is read into without scikit-learn
        (`gyrodrift.learn.model_io.load_predictor`)."""
        check_is_fitted(self, "interval_")
        return DriftPredictor(
            encoding=self.encoding,
            scaling=self.scaling,
            target=self.target,
            physics_column=self.physics_column,
            scaler=InputScaler.of_step(self.scaling, self.learner_.named_steps["scale"]),
            lssvr=self.lssvr.expansion(),
            base=self.base_,
            interval=self.interval_,
            ranges=self.ranges_,
            training=self.training_,
            tuning=self.tuning,
            loo_residuals_deg_h=self.loo_residuals_deg_h,
            warnings=self.fit_warnings(),
        )

    def _out_of_fold(self, trained: RunTable, spread_theta) -> tuple[np.ndarray, np.ndarray]:
        """``(r, m)`` [deg/h]: ``r_i`` the residual of run i under a model fitted and tuned on the other folds
        (``calibration_folds`` folds, run i in fold ``i mod K``), ``m_i`` that model's spread at run i (the
        hyperparameters ``spread_theta`` of the full model's spread, refitted on the fold's runs without a new
        likelihood search: what matters here is that gamma and sigma are tuned without the fold). Each part starts
        from the fitted learner's parameters (a random generator in the state the full fit left it)."""
        n = len(trained)
        k = min(int(self.calibration_folds), n)
        fold = np.arange(n) % k
        residuals, spreads = np.empty(n), np.empty(n)
        with warnings.catch_warnings():  # the full model's warnings are the ones that count
            warnings.simplefilter("ignore", SearchBoundWarning)
            warnings.simplefilter("ignore", IllConditionedWarning)
            for j in range(k):
                part = clone(self).set_params(
                    learner=clone(self.learner_), calibration_folds=0, learner__lssvr__callback=None
                )
                part.fit(trained.select(fold != j), spread_theta=spread_theta)
                held = trained.select(fold == j)
                spreads[fold == j] = part.predict_spread(held)
                residuals[fold == j] = held.drift_deg_h - part.predict(held)
        return residuals, spreads

    def predict(self, X) -> np.ndarray:
        """Identified drift [deg/h] of each run (`gyrodrift.learn.predictor.DriftPredictor.predict`: the LSSVR's
        output, plus the physics estimate for a hybrid, added inside the LSSVR's compensated sum)."""
        return self.predictor_.predict(X)

    def score(self, X, y=None, sample_weight=None) -> float:
        """R^2 of the identified drifts (``predict``) against ``y`` (default: the runs' drifts)."""
        from sklearn.metrics import r2_score

        runs = as_run_table(X)
        y = runs.drift_deg_h if y is None else y
        return float(r2_score(y, self.predict(runs), sample_weight=sample_weight))

    @property
    def physics_column_(self) -> str | None:
        """The physics base the fit resolved (``base_.column_``; None for ``target="drift"``)."""
        return self.base_.column_

    @property
    def coefficient_prior_(self) -> tuple[float, float] | None:
        """The fleet base's k_z prior ``(mean, std)`` [deg/h/degC] pooled from all training runs
        (``base_.coefficient_prior_``), else None."""
        return self.base_.coefficient_prior_

    @property
    def encoding(self) -> str:
        """The run encoding (``learner__encode__encoding``)."""
        return str(self.learner.named_steps["encode"].encoding)

    @property
    def scaling(self) -> str:
        """The input scaling name (``SCALINGS``)."""
        return scaling_name(self.learner.named_steps["scale"])

    @property
    def scaler_(self) -> InputScaler:
        """The fitted input scaling as plain numbers (`gyrodrift.learn.scaling.InputScaler`)."""
        return InputScaler.of_step(self.scaling, self.learner_.named_steps["scale"])

    @property
    def lssvr(self) -> LSSVR:
        """The fitted LSSVR (inside the learner's ``lssvr`` step)."""
        return self.learner_.named_steps["lssvr"].lssvr_

    @property
    def tuning(self) -> TuningResult | None:
        """How gamma and sigma were tuned (None when given)."""
        return self.learner_.named_steps["lssvr"].tuning_

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
        return self.learner_.named_steps["lssvr"].loo_residuals_

    def loo_residuals(self) -> np.ndarray:
        """A copy of :attr:`loo_residuals_deg_h`."""
        return np.array(self.loo_residuals_deg_h, float)

    def fit_warnings(self) -> list[str]:
        """What fitting warned about: tuned values on the edge of their search box, ill-conditioning, wild
        calibration scores (`interval_warnings`)."""
        return self.learner_.named_steps["lssvr"].fit_warnings() + self.interval_warnings()

    def interval_warnings(self) -> list[str]:
        """One message naming the training runs whose calibration score is wild (`DriftInterval.warnings`)."""
        check_is_fitted(self, "interval_")
        return self.interval_.warnings(self.training_["runs"].run)

    def interval_scores(self) -> np.ndarray:
        """The calibration scores of the interval (dimensionless, signed): each training run's out-of-sample
        residual divided by its predicted spread (`gyrodrift.learn.interval`)."""
        check_is_fitted(self, "interval_")
        return np.array(self.interval_.scores_, float)

    def predict_spread(self, runs) -> np.ndarray:
        """The spread model's 1-sigma of each run's drift [deg/h] (`SpreadGP.predict_std`; label noise
        excluded); grows away from the training runs on the scale of its fitted length scales."""
        return self.predictor_.predict_spread(runs)

    def predict_interval(self, runs, coverage: float = 0.9) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Identified drift and its interval [deg/h]: ``(pred, lo, hi)``.

        An interval for the run's label (the `truth` a new run would get, at the training runs' rms label
        1-sigma): half-width ``t c sqrt(min(spread(x), U)^2 + s_rms^2 + b(x)^2)``
        (`gyrodrift.learn.interval.DriftInterval.half_width`), with ``spread`` the spread model's 1-sigma of the
        learned term at the run (`predict_spread`, wider away from the training runs), ``U`` its cap, ``b`` the
        run's base 1-sigma when ``base_.std_used_`` (else 0; a run without it: ``InputError``), and ``t c`` the
        calibration. Far from the training runs it widens, never past ``t c (sqrt(s_rms^2 + b^2) + U)``: the physics
        alone plus the learned term's own uncertainty. Not a Bayesian posterior. tests/learn/test_intervals.py,
        docs/identification.md.
        """
        return self.predictor_.predict_interval(runs, coverage)

    def learned_std_deg_h(self, runs) -> np.ndarray:
        """The 1-sigma of each run's learned term [deg/h] (the LSSVR's output: the whole drift for
        ``target="drift"``, the correction added to the base for a hybrid): the interval's learner share
        (`gyrodrift.learn.interval.DriftInterval.sigmas`, the spread model's 1-sigma at the run, capped) times its
        calibration scale c (without the coverage's t quantile). What the identified drift law adds to the variance
        of its eps_ref (`gyrodrift.procedure.identify`); a Gaussian reading of the empirical interval."""
        return self.predictor_.learned_std_deg_h(runs)

    def interval_summary(self, coverage: float = 0.9) -> dict:
        """What the interval rests on (`gyrodrift.learn.interval.DriftInterval.summary`). O(n): no prediction."""
        return self.predictor_.interval_summary(coverage)

    def interval_note(self, coverage: float = 0.9) -> str:
        """`interval_summary` in one line (what ``fit`` and ``identify`` say)."""
        return self.predictor_.interval_note(coverage)

    def check_inputs(self, runs, *, rtol: float = 1e-9) -> InputCheck:
        """Flag runs whose inputs lie outside the training runs' range, per input ([min, max] of the encoded
        inputs, with a relative tolerance ``rtol`` of the range) and jointly (Mahalanobis distance of the
        scaled inputs beyond the largest among the training runs): `gyrodrift.learn.ranges.InputRanges.check`."""
        return self.predictor_.check_inputs(runs, rtol=rtol)


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
    """An unfitted :class:`DriftModel`: the learner ``make_learner(encoding, scaling, **lssvr_params)`` with
    ``target``, ``physics_column``, ``label_weighting``, ``calibration_folds`` and ``base_uncertainty`` as in the
    module docstring (checked here)."""
    model = DriftModel(
        make_learner(encoding=encoding, scaling=scaling, **lssvr_params),
        target=target,
        physics_column=physics_column,
        label_weighting=label_weighting,
        calibration_folds=calibration_folds,
        base_uncertainty=base_uncertainty,
    )
    model.check_options()
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
    objective: str = TuningOptions.objective,
    method: str = TuningOptions.method,
    gamma: float | None = None,
    sigma: float | None = None,
    bounds=TuningOptions.bounds,
    n_particles: int = TuningOptions.n_particles,
    max_iter: int = TuningOptions.max_iter,
    chaos_steps: int = TuningOptions.chaos_steps,
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
            model.set_params(learner__lssvr__callback=lambda res: _tick(bar, callback, res))
            try:
                model.fit(train)
            finally:  # the returned model keeps no callback, in its parameters nor in its fitted learner
                model.set_params(learner__lssvr__callback=None)
                if hasattr(model, "learner_"):
                    model.learner_.set_params(lssvr__callback=None)
    else:
        model.fit(train)
    excluded = flagged_names if flagged_labels == "exclude" else []
    model.training_["left_out"] = excluded + left_out
    model.training_["flagged_left_out"] = excluded
    model.training_["flagged_kept"] = [] if excluded else [r for r in flagged_names if r not in left_out]
    return model
