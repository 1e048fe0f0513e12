"""A fitted drift model's predictions without scikit-learn: `DriftPredictor`.

The parts a prediction needs, as plain fitted objects: the run encoding (`gyrodrift.learn.encodings`), the input
scaling (`gyrodrift.learn.scaling.InputScaler`), the LSSVR's kernel expansion (`gyrodrift.learn.expansion`), the
physics base (`gyrodrift.learn.physics_base.PhysicsBase`), the interval (`gyrodrift.learn.interval.DriftInterval`) and
the input ranges (`gyrodrift.learn.ranges.InputRanges`), with the training runs. One way to predict: a fitted
`gyrodrift.learn.drift_model.DriftModel` delegates its predictions, intervals and range checks to its
``predictor_``; `gyrodrift.learn.model_io.load_predictor` reads a model file into one without importing scikit-learn
(~1.5 s of a start), which ``gyrodrift predict``, ``identify --model``, ``evaluate --model`` and ``export`` use.
Predictions are axial drifts in deg/h, the total constant to subtract from the z-gyro output (measured - estimate).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gyrodrift.learn.encodings import encode, feature_names
from gyrodrift.learn.expansion import KernelExpansion
from gyrodrift.learn.interval import DriftInterval, check_coverage
from gyrodrift.learn.physics_base import PhysicsBase
from gyrodrift.learn.ranges import InputCheck, InputRanges
from gyrodrift.learn.scaling import InputScaler
from gyrodrift.runs.table import RunTable, as_run_table

__all__ = ["DriftPredictor"]


class DriftPredictor:
    """A fitted drift model's prediction (module docstring).

    Attributes: ``encoding``, ``scaling``, ``target`` (``"drift"`` or ``"residual"``), ``physics_column`` (the
    model's parameter, e.g. ``"auto"``), ``scaler_`` (`InputScaler`), ``lssvr`` (`KernelExpansion`), ``base_``,
    ``interval_``, ``ranges_``, ``training_`` (``n_runs``, ``sha256``, ``source``, ``weighted``, ``left_out`` and the
    ``runs`` themselves), ``tuning`` (`gyrodrift.learn.tuning.TuningResult` or None), ``loo_residuals_deg_h`` (the
    LSSVR's closed-form leave-one-out residuals on the training runs) and ``warnings`` (what the fit warned about,
    as recorded).
    """

    def __init__(
        self,
        *,
        encoding: str,
        scaling: str,
        target: str,
        physics_column: str,
        scaler: InputScaler,
        lssvr: KernelExpansion,
        base: PhysicsBase,
        interval: DriftInterval,
        ranges: InputRanges,
        training: dict[str, Any],
        tuning=None,
        loo_residuals_deg_h,
        warnings: list[str] | None = None,
    ) -> None:
        self.encoding = encoding
        self.scaling = scaling
        self.target = target
        self.physics_column = physics_column
        self.scaler_ = scaler
        self.lssvr = lssvr
        self.base_ = base
        self.interval_ = interval
        self.ranges_ = ranges
        self.training_ = training
        self.tuning = tuning
        self.loo_residuals_deg_h = loo_residuals_deg_h
        self.warnings = list(warnings or [])

    @property
    def physics_column_(self) -> str | None:
        """The physics base the fit resolved (``base_.column_``; None for ``target="drift"``)."""
        return self.base_.column_

    @property
    def coefficient_prior_(self) -> tuple[float, float] | None:
        """The fleet base's k_z prior ``(mean, std)`` [deg/h/degC] pooled from all training runs, else None."""
        return self.base_.coefficient_prior_

    @property
    def feature_names(self) -> tuple[str, ...]:
        return feature_names(self.encoding)

    @property
    def training(self) -> dict:
        """``n_runs``, ``sha256``, ``source``, ``weighted`` (and ``left_out``) of the training runs."""
        return {k: v for k, v in self.training_.items() if k != "runs"}

    def loo_residuals(self) -> np.ndarray:
        """A copy of ``loo_residuals_deg_h`` [deg/h] (true minus left-out prediction)."""
        return np.array(self.loo_residuals_deg_h, float)

    def fit_warnings(self) -> list[str]:
        """What fitting warned about, as recorded (edge of the search box, ill-conditioning, wild calibration
        scores)."""
        return list(self.warnings)

    def scaled_inputs(self, runs: RunTable) -> np.ndarray:
        """The scaled model inputs of ``runs`` (n_runs, n_inputs)."""
        return self.scaler_.transform(encode(runs, self.encoding))

    def _learned(self, runs: RunTable) -> tuple[np.ndarray, np.ndarray]:
        """``(Z, learned)``: the scaled inputs of ``runs`` and the LSSVR's output there [deg/h] (no base)."""
        Z = self.scaled_inputs(runs)
        return Z, self.lssvr.predict(Z)

    def predict(self, X) -> np.ndarray:
        """Identified drift [deg/h] of each run: the LSSVR's output (plus the physics estimate for a hybrid, added
        inside the LSSVR's compensated sum: `gyrodrift.learn.expansion.KernelExpansion.predict`)."""
        runs = as_run_table(X)
        offset = self.base_.predict(runs) if self.target == "residual" else None
        return self.lssvr.predict(self.scaled_inputs(runs), offset=offset)

    def predict_spread(self, runs) -> np.ndarray:
        """The spread model's 1-sigma of each run's learned term [deg/h] (`SpreadGP.predict_std`; label noise
        excluded); grows away from the training runs on the scale of its fitted length scales."""
        return self.interval_.spread_.predict_std(self.scaled_inputs(as_run_table(runs)))

    def predict_interval(self, runs, coverage: float = 0.9) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Identified drift and its interval [deg/h]: ``(pred, lo, hi)``, half-width ``t c sqrt(min(spread(x), U)^2
        + s_rms^2 + b(x)^2)`` (`gyrodrift.learn.interval.DriftInterval.half_width`; `DriftModel.predict_interval`
        says what each term is)."""
        coverage = check_coverage(coverage)
        runs = as_run_table(runs)
        pred = self.predict(runs)
        Z, learned = self._learned(runs)
        half = self.interval_.half_width(Z, learned, self.base_.predict_std(runs), coverage)
        return pred, pred - half, pred + half

    def learned_std_deg_h(self, runs) -> np.ndarray:
        """The 1-sigma of each run's learned term [deg/h]: the interval's learner share times its calibration scale
        c (`DriftModel.learned_std_deg_h`)."""
        Z, learned = self._learned(as_run_table(runs))
        learned_std, _ = self.interval_.sigmas(Z, learned, None)
        return np.asarray(learned_std, float) * float(self.interval_.scale_.scale)

    def interval_summary(self, coverage: float = 0.9) -> dict:
        """What the interval rests on (`gyrodrift.learn.interval.DriftInterval.summary`). O(n): no prediction."""
        return self.interval_.summary(check_coverage(coverage), self.training_["runs"].run)

    def interval_note(self, coverage: float = 0.9) -> str:
        """`interval_summary` in one line (what ``fit`` and ``identify`` say)."""
        return self.interval_.note(check_coverage(coverage), self.training_["runs"].run)

    def interval_warnings(self) -> list[str]:
        """One message naming the training runs whose calibration score is wild (`DriftInterval.warnings`)."""
        return self.interval_.warnings(self.training_["runs"].run)

    def check_inputs(self, runs, *, rtol: float = 1e-9) -> InputCheck:
        """Flag runs whose inputs lie outside the training runs' range, per input and jointly
        (`gyrodrift.learn.ranges.InputRanges.check`)."""
        runs = as_run_table(runs)
        encoded = encode(runs, self.encoding)
        return self.ranges_.check(encoded, self.scaler_.transform(encoded), self.feature_names, rtol=rtol)
