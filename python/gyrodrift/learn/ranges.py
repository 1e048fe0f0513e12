"""Where runs lie relative to a drift model's training runs: per input ([min, max] of the encoded inputs) and jointly
(the Mahalanobis distance of the scaled inputs beyond the largest among the training runs).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gyrodrift.runs.table import RunTable

__all__ = ["InputCheck", "InputRanges"]


@dataclass(frozen=True)
class InputCheck:
    """Where runs lie relative to a model's training runs (:meth:`gyrodrift.learn.drift_model.DriftModel.check_inputs`).

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


class InputRanges:
    """The training runs' input ranges, fitted on their encoded inputs (units in the feature names) and scaled
    inputs (`fit`), and the check of new runs against them (`check`).

    Fitted attributes: ``min_``, ``max_`` (per encoded input), ``mean_`` and ``precision_`` (mean and pseudo-inverse
    covariance of the scaled inputs) and ``mahalanobis_limit_`` (the largest training run's Mahalanobis distance).
    """

    def fit(self, encoded: np.ndarray, Z: np.ndarray) -> InputRanges:
        """Ranges of the training runs' ``encoded`` inputs and the joint spread of their scaled inputs ``Z``."""
        self.min_, self.max_ = encoded.min(axis=0), encoded.max(axis=0)
        self.mean_ = Z.mean(axis=0)
        cov = np.atleast_2d(np.cov(Z, rowvar=False))
        self.precision_ = np.linalg.pinv(cov)
        self.mahalanobis_limit_ = float(self.mahalanobis(Z).max())
        return self

    def mahalanobis(self, Z: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of each row of scaled inputs ``Z`` from the training runs' mean."""
        d = Z - self.mean_
        return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", d, self.precision_, d), 0.0))

    def check(self, encoded: np.ndarray, Z: np.ndarray, names: Sequence[str], *, rtol: float = 1e-9) -> InputCheck:
        """Flag runs (``encoded`` and scaled inputs ``Z``, inputs named ``names``) outside the training range, per
        input (with a relative tolerance ``rtol`` of the range) and jointly."""
        slack = rtol * np.maximum(self.max_ - self.min_, np.abs(self.max_))
        low = encoded < self.min_ - slack
        high = encoded > self.max_ + slack
        per = [
            tuple(
                f"{names[int(j)]} {'below' if low[i, j] else 'above'} the training range"
                for j in np.flatnonzero(low[i] | high[i])
            )
            for i in range(len(encoded))
        ]
        maha = self.mahalanobis(Z)
        joint = maha > self.mahalanobis_limit_ * (1.0 + 1e-9)
        outside = np.array([bool(p) for p in per]) | joint
        return InputCheck(
            outside=outside, outside_inputs=per, mahalanobis=maha, mahalanobis_limit=self.mahalanobis_limit_
        )
