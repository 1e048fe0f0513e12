"""A fitted LSSVR's kernel expansion ``f(x) = b + sum_i a_i K(x_i, x)`` and its prediction arithmetic, without
scikit-learn: what `gyrodrift.learn.lssvr.LSSVR.predict` and `gyrodrift.learn.predictor.DriftPredictor` both compute
(one code), and, operation for operation, the generated C and Rust of `gyrodrift.export`.

The arithmetic (the "Prediction arithmetic" of `gyrodrift.learn.lssvr`): the kernel of each support vector from the
coordinate differences summed over the features in order (RBF ``exp(-d2 / (sigma * sigma))`` with the C library's
``exp`` through ``math.exp``; linear and polynomial: the dot product in feature order, an integer power by repeated
multiplication), then ``b + sum_i a_i K_i`` (+ an offset, the physics estimate of a hybrid model) accumulated in
support-vector order with an error-free transformation (Knuth's TwoSum, the errors summed apart: Ogita, Rump & Oishi
2005 "Sum2"). Units: ``a``, ``b``, the offset and ``f`` in the unit of the targets (deg/h for drifts); the inputs
and ``sigma`` in the scaled input units.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from gyrodrift.learn.kernels import (
    check_kernel,
    check_matrix_memory,
    check_positive,
    check_sigma,
    rbf_from_squared_distances,
)
from gyrodrift.learn.lssvm_system import NonFiniteResultError, StoredSolutionError, check_sample_weight

__all__ = ["KernelExpansion", "compensated_expansion", "prediction_kernel"]


def prediction_kernel(Z: np.ndarray, X: np.ndarray, kernel: str, sigma: float, degree: int, coef0: float) -> np.ndarray:
    """``K(z_i, X[j])`` for each support vector ``z_i`` (rows of ``Z``) and sample (columns), shape (n_train,
    n_samples), with the operations of the generated code (module docstring): features in order, the RBF kernel's
    ``exp`` from the C library (``math.exp``; numpy's own may differ by an ulp), an integer power multiplied out."""
    kernel = check_kernel(kernel)
    acc = np.zeros((Z.shape[0], X.shape[0]))
    for k in range(X.shape[1]):
        if kernel == "rbf":
            t = X[None, :, k] - Z[:, k, None]
            acc += t * t
        else:
            acc += X[None, :, k] * Z[:, k, None]
    if kernel == "linear":
        return acc
    sigma = check_sigma(sigma)
    if kernel == "rbf":
        arg = -acc / (sigma * sigma)
        return np.fromiter(map(math.exp, arg.ravel()), float, arg.size).reshape(arg.shape)
    base = acc / (sigma * sigma) + float(coef0)
    out = base.copy()
    for _ in range(1, int(degree)):  # checked by the fit
        out *= base
    return out


def compensated_expansion(KT: np.ndarray, alpha: np.ndarray, intercept, offset=None) -> np.ndarray:
    """``intercept + sum_i alpha[i] * KT[i] (+ offset)``, the terms added in that order with Knuth's TwoSum
    (``t = s + p``, ``z = t - s``, error ``(s - (t - z)) + (p - z)``, exact in binary floating point) and the
    errors summed apart and added at the end ("Sum2", Ogita, Rump & Oishi 2005): as accurate as summing in twice
    the working precision, then rounding. The generated C and Rust (`gyrodrift.export`) do the same operations.

    ``KT`` is (n_train, n_samples); ``alpha`` (n_train,) or (n_train, n_targets); ``offset`` broadcasts against the
    result, shape (n_samples,) or (n_samples, n_targets).
    """
    shape = (KT.shape[1],) + alpha.shape[1:]
    s = np.array(np.broadcast_to(np.asarray(intercept, float), shape))
    c = np.zeros(shape)
    terms: Iterable[np.ndarray] = (
        (k * a for k, a in zip(KT, alpha, strict=True))
        if alpha.ndim == 1
        else (k[:, None] * a for k, a in zip(KT, alpha, strict=True))
    )
    if offset is not None:
        terms = itertools.chain(terms, (np.broadcast_to(offset, shape),))
    for p in terms:
        t = s + p
        z = t - s
        c += (s - (t - z)) + (p - z)
        s = t
    return s + c


@dataclass(frozen=True)
class KernelExpansion:
    """A fitted LSSVR's expansion: support vectors ``X_fit_`` (scaled inputs, n x d), dual coefficients ``alpha_``
    and bias ``intercept_`` [unit of y], the kernel and its parameters (``gamma`` is the regularisation the
    coefficients were solved with, kept for reports and the export). The attribute names are
    `gyrodrift.learn.lssvr.LSSVR`'s, so that what reads a fitted LSSVR's numbers (`gyrodrift.export.spec`) reads
    either."""

    X_fit_: np.ndarray
    alpha_: np.ndarray
    intercept_: float | np.ndarray
    gamma: float
    sigma: float
    kernel: str = "rbf"
    degree: int = 3
    coef0: float = 1.0

    @classmethod
    def from_stored_solution(
        cls, X, y, *, gamma: float, sigma: float, alpha, intercept: float, sample_weight=None, rtol: float = 1e-9
    ) -> KernelExpansion:
        """An RBF expansion from a stored solution (a model file's) of the LSSVM on scaled inputs ``X`` (n x d) and
        targets ``y``, without solving the n x n system.

        Verified cheaply, O(32 n): ``sum(alpha) = 0`` and the dual equations ``K_i alpha + alpha_i/(gamma w_i) + b =
        y_i`` of up to 32 rows spread over the samples, each to ``rtol`` of the sum of the absolute values of its
        terms (a backward-stable solve leaves about ``n eps`` of it; an edited coefficient leaves far more, in every
        row its kernel reaches and in the sum). Raises :class:`StoredSolutionError` (an ``InputError``) naming what
        does not hold."""
        gamma = check_positive("gamma", gamma)
        sigma = check_sigma(sigma)
        X = np.array(X, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        n = X.shape[0]
        if X.ndim != 2 or y.shape != (n,) or n < 2 or not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
            raise StoredSolutionError(f"the stored solution needs finite inputs and targets, got {X.shape}, {y.shape}")
        w = check_sample_weight(sample_weight, n)
        alpha = np.asarray(alpha, dtype=float)
        if alpha.shape != (n,) or not np.all(np.isfinite(alpha)):
            raise StoredSolutionError(f"the stored solution must hold {n} finite dual coefficients")
        b = float(intercept)
        if not abs(alpha.sum()) <= rtol * max(np.abs(alpha).sum(), np.finfo(float).tiny):
            raise StoredSolutionError(f"the stored dual coefficients do not sum to 0 (sum {alpha.sum():.3g})")
        rows = np.unique(np.linspace(0, n - 1, min(n, 32)).round().astype(int))
        Kr = rbf_from_squared_distances(np.sum((X[rows, None, :] - X[None, :, :]) ** 2, axis=2), sigma)
        ridge = alpha[rows] / (gamma * (1.0 if w is None else w[rows]))
        residual = Kr @ alpha + ridge + b - y[rows]
        size = np.abs(Kr) @ np.abs(alpha) + np.abs(ridge) + abs(b) + np.abs(y[rows])
        bad = np.flatnonzero(~(np.abs(residual) <= rtol * size))
        if bad.size:
            i = int(rows[bad[0]])
            raise StoredSolutionError(
                f"the stored solution does not solve the LSSVM system at sample {i}: residual {residual[bad[0]]:.3g} "
                f"against terms of size {size[bad[0]]:.3g} (gamma {gamma!r}, sigma {sigma!r})"
            )
        return cls(X, alpha, b, gamma, sigma)

    def describe(self) -> str:
        return f"gamma={self.gamma!r}, sigma={self.sigma!r}, kernel={self.kernel!r}"

    def predict(self, X, offset=None) -> np.ndarray:
        """``f(x) = sum_i alpha_i K(x_i, x) + b`` (``+ offset``, one more term of each sum: a hybrid's physics
        estimate, added inside the compensated sum) at each row of ``X`` (scaled like the support vectors), in the
        unit of y. ``MemoryLimitError`` when the (n_samples, n_train) kernel would not fit in memory;
        ``NonFiniteResultError`` for a prediction that is not finite (never returned as NaN)."""
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 2 or X.shape[1] != self.X_fit_.shape[1]:
            raise ValueError(f"X has shape {X.shape}, expected (n_samples, {self.X_fit_.shape[1]})")
        check_matrix_memory(X.shape[0], self.X_fit_.shape[0], 3, "predicting with the LSSVR", unit="samples")
        alpha = np.asarray(self.alpha_, float)
        if offset is not None:
            offset = np.asarray(offset, float)
            if offset.shape != (X.shape[0],):
                raise ValueError(f"offset has shape {offset.shape}, expected ({X.shape[0]},), one value per sample")
            offset = offset.reshape((X.shape[0],) + (1,) * (alpha.ndim - 1))
        with np.errstate(over="ignore", invalid="ignore"):  # checked below
            KT = prediction_kernel(self.X_fit_, X, self.kernel, self.sigma, self.degree, self.coef0)
            out = compensated_expansion(KT, alpha, self.intercept_, offset)
        if not np.all(np.isfinite(out)):
            raise NonFiniteResultError(
                f"LSSVR: a prediction is not finite for {self.describe()} (kernel overflow on inputs far "
                "outside the training data?)"
            )
        return out
