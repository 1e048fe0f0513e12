"""The drift model's input scaling as plain numbers (`InputScaler`): what scikit-learn's ``StandardScaler`` and
``MinMaxScaler`` fit and apply, computed with the same floating-point operations and without importing scikit-learn
(~1.5 s of a start), so that a model file is read into a predictor (`gyrodrift.learn.predictor`) that scales new runs
to the same bits as the fitted pipeline (tests/learn/test_predictor.py compares them).

``standard``: ``z = (x - mean) / scale`` with the mean and the population standard deviation of the training runs
(a near-constant input keeps scale 1); ``minmax``: ``z = x * scale + offset`` mapping the training runs' [min, max]
to [0, 1] (a constant input keeps scale 1); ``none``: ``z = x``. Units: ``mean`` and ``offset`` in the encoded
input's unit (or scaled, for ``offset``), ``scale`` in the input's unit (standard) or its inverse (minmax).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gyrodrift.choices import SCALINGS
from gyrodrift.errors import OptionError

__all__ = ["InputScaler"]

_EPS = float(np.finfo(np.float64).eps)


@dataclass(frozen=True)
class InputScaler:
    """A fitted input scaling (module docstring): ``scaling`` (``SCALINGS``), ``mean``/``scale`` (standard),
    ``scale``/``offset`` (minmax), None where unused; arrays of one value per input."""

    scaling: str
    mean: np.ndarray | None = None
    scale: np.ndarray | None = None
    offset: np.ndarray | None = None

    @classmethod
    def fit(cls, scaling: str, E) -> InputScaler:
        """The scaling ``scaling`` fitted on the training runs' encoded inputs ``E`` (n_runs, n_inputs, finite), as
        scikit-learn's scaler of that name fits it (``StandardScaler``: the two-pass mean and variance with Chan,
        Golub and LeVeque's correction; ``MinMaxScaler``: the range, a near-zero one kept at 1)."""
        E = np.asarray(E, dtype=np.float64)
        if scaling == "none":
            return cls("none")
        if scaling == "standard":
            count = np.full(E.shape[1], float(E.shape[0]))
            total = np.sum(E, axis=0)
            mean = (np.zeros(E.shape[1]) + total) / count
            temp = E - total / count
            correction = np.sum(temp, axis=0)
            temp **= 2
            var = (np.sum(temp, axis=0) - correction**2 / count) / count
            n = count[0]
            constant = var <= n * _EPS * var + (n * mean * _EPS) ** 2
            scale = np.sqrt(var)
            scale[constant] = 1.0
            return cls("standard", mean=mean, scale=scale)
        if scaling == "minmax":
            low = np.min(E, axis=0)
            span = np.max(E, axis=0) - low
            span[span < 10 * _EPS] = 1.0
            scale = 1.0 / span
            return cls("minmax", scale=scale, offset=0.0 - low * scale)
        raise OptionError(f"unknown scaling {scaling!r}; expected one of {', '.join(SCALINGS)}")

    @classmethod
    def of_step(cls, scaling: str, step) -> InputScaler:
        """The numbers of a fitted pipeline's scale step ``step`` (a fitted ``StandardScaler`` or ``MinMaxScaler``,
        or ``"passthrough"``) named ``scaling``."""
        if scaling == "standard":
            return cls("standard", mean=np.asarray(step.mean_, float), scale=np.asarray(step.scale_, float))
        if scaling == "minmax":
            return cls("minmax", scale=np.asarray(step.scale_, float), offset=np.asarray(step.min_, float))
        return cls("none")

    def transform(self, E) -> np.ndarray:
        """The scaled inputs of encoded inputs ``E`` (n_runs, n_inputs): the operations of scikit-learn's
        ``transform`` (subtract then divide; multiply then add)."""
        E = np.array(E, dtype=np.float64)
        if self.scaling == "standard":
            E -= self.mean
            E /= self.scale
        elif self.scaling == "minmax":
            E *= self.scale
            E += self.offset
        return E
