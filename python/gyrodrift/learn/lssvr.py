"""Least-squares support vector regression (Suykens' LSSVM with an unregularised bias).

The model of Yu et al. (2013) that maps the 12 h navigation latitude and the temperature change to the
axial gyro drift. Given training inputs ``x_i`` (units: whatever the caller scaled) and targets ``y_i``
(deg/h for drift targets in this project) it solves the dual system

    [ 0   1'          ] [b]   [0]
    [ 1   K + I/gamma ] [a] = [y]          f(x) = sum_i a_i K(x_i, x) + b

where ``gamma`` is the regularisation (larger = less regularisation) and ``K`` the kernel matrix
(:mod:`gyrodrift.learn.kernels`; RBF ``exp(-|x - z|^2 / sigma^2)``). ``b`` has the unit of ``y``; with the
dimensionless RBF kernel ``a`` has the unit of ``y`` too.

How it is solved: ``H = K + I/gamma`` is symmetric positive definite for every positive semi-definite
kernel; with its Cholesky factor ``H = U'U`` (LAPACK ``dpotrf``, the routine behind
``scipy.linalg.cho_factor``) two solves give ``p = H^-1 1`` and ``q = H^-1 y``, then
``b = 1'q / 1'p`` and ``a = q - b p``. The bordered matrix is never factorised and nothing is
pseudo-inverted. Consequences used below:

* ``sum(a) = 0`` (the first row of the system);
* training residuals are ``y_i - f(x_i) = a_i / gamma`` (the LSSVM error variables ``e_i``);
* exact leave-one-out residuals (Cawley & Talbot 2004)
  ``r_i = y_i - f_(-i)(x_i) = a_i / ((H^-1)_ii - p_i^2 / s)`` with ``s = 1'p``.

Sign convention everywhere in this module: a residual is observed minus predicted, ``y - f``.

Weighted LS-SVM (Suykens et al. 2002, per-sample regularisation): with sample weights ``w_i > 0`` the primal
is ``min 1/2 |w|^2 + gamma/2 sum_i w_i e_i^2``, i.e. ``C_i = gamma w_i``; eliminating ``e_i = a_i / (gamma w_i)``
gives the same bordered system with ``H = K + diag(1 / (gamma w_i))``. Everything above holds with that ``H``:
removing sample ``i`` still removes row and column ``i`` of the bordered matrix, so the closed-form LOO
residuals keep their form (tests compare both with brute-force weighted solves and refits). For drift labels
with 1-sigma ``s_i``, ``w_i = mean(s^2) / s_i^2`` (``gyrodrift.learn.model.label_weights``).

Predictive scale (the LSSVM read as a Gaussian process with prior covariance ``K``, noise ``1/(gamma w_i)``
and a flat prior on the bias; Rasmussen & Williams 2006, sec. 2.7): the predictive variance of a new
observation at ``x`` (weight 1), in units of the prior variance, is

    v(x)^2 = k(x, x) - k' H^-1 k + (1 - 1'H^-1 k)^2 / s + 1/gamma,     k = K(X_train, x),

and the leave-one-out predictive variance of training sample ``i`` is ``1 / ((H^-1)_ii - p_i^2 / s)``, the
denominator of its LOO residual. ``LSSVR.predictive_scale`` returns ``v``; ``loo_scale_`` the LOO one. Far
from the training inputs ``k -> 0`` and ``v`` grows to its prior value: the interval widens there.

If the Cholesky factorisation fails (``H`` not numerically positive definite, e.g. an enormous gamma with
a singular kernel matrix - duplicated training points - or an indefinite polynomial kernel with
``coef0 < 0``) the functions raise :class:`IllConditionedError` (a ``numpy.linalg.LinAlgError``,
itself a ``ValueError``), as they do when the condition number reaches ``COND_REFUSE``: one refusal, whichever
path a given BLAS takes (``NotPositiveDefiniteError`` is the same class).
No jitter is ever added silently: lower gamma (more regularisation) instead.
:func:`rbf_batch_errors` is the exception to raising: it returns rows of ``+inf`` so that a tuner survives.

Prediction arithmetic (`LSSVR.predict`, and the generated C and Rust of `gyrodrift.export.generate`, operation for
operation): the kernel of each support vector from the coordinate differences summed over the features in
order (RBF ``exp(-d2 / (sigma * sigma))`` with the C library's ``exp`` through ``math.exp``; linear and
polynomial: the dot product in feature order, an integer power by repeated multiplication), then
``b + sum_i a_i K_i`` (+ an offset, the physics estimate of a hybrid model) accumulated in support-vector order
with an error-free transformation (Knuth's TwoSum; the errors summed apart and added at the end, Ogita, Rump
& Oishi 2005 "Sum2"). The result is as accurate as if summed in twice the working precision and then rounded,
so the cancelling terms of a drift near zero lose nothing in the sum; what remains is the rounding of each
term (about ``eps sum_i |a_i K_i|``, the condition of the sum). numpy's own ``exp`` (a SIMD version on some
CPUs) and BLAS's ``K @ a`` (another order, fused multiply-adds) would differ from the generated code in the last
bits (docs/export.md gives the numbers).

Conversions for cross-checks: scikit-learn ``KernelRidge(alpha=1/gamma, kernel="rbf", gamma=1/sigma^2)``
fitted on ``y - b`` has ``dual_coef_ == a``; LS-SVMlab 1.8 ``sig2 = sigma^2 / 2`` (docs/conventions.md).
"""

from __future__ import annotations

import itertools
import math
import operator
import warnings
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.linalg import lapack
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from gyrodrift.errors import GyrodriftError, InputError
from gyrodrift.learn.kernels import (
    check_kernel,
    check_matrix_memory,
    check_positive,
    check_sigma,
    kernel_matrix,
    rbf_from_squared_distances,
    squared_distances,  # re-exported: the tuner's inputs to rbf_batch_errors
)

try:  # scikit-learn >= 1.6
    from sklearn.utils.validation import validate_data as _validate_data
except ImportError:  # pragma: no cover - older scikit-learn

    def _validate_data(estimator, *args, **kwargs):
        return estimator._validate_data(*args, **kwargs)


__all__ = [
    "COND_REFUSE",
    "COND_WARN",
    "EigenCache",
    "LSSVR",
    "IllConditionedError",
    "IllConditionedWarning",
    "NonFiniteResultError",
    "NotPositiveDefiniteError",
    "RBFEigenSystem",
    "StoredSolutionError",
    "lssvr_solve",
    "lssvr_loo_residuals",
    "rbf_batch_errors",
    "squared_distances",
]


_EPS = float(np.finfo(float).eps)

COND_REFUSE = 1.0 / _EPS
"""Condition number of ``H`` (1-norm estimate) at and above which a solve is refused (about 4.5e15).

``cond(H) * eps`` bounds the relative error of the solution; at ``1/eps`` no digit is guaranteed (LAPACK's
own singularity criterion, and the threshold at which scipy's ``solve`` and scikit-learn's ``KernelRidge``
warn). Measured on the paper's 22 runs against a 60-digit solution: cond 3.2e15 gave alpha to 1.6 %, cond
2.7e18 (gamma 1e16, sigma 100) gave a LOO MAE of 0.0132 deg/h against an exact 0.0045."""

COND_WARN = 1e-3 / _EPS
"""Condition number of ``H`` above which a solve is kept but warned about (about 4.5e12): the error bound
``cond * eps`` exceeds 1e-3, so the third significant digit of alpha, the predictions and the LOO residuals
is not guaranteed (measured errors on the paper's runs are ~50x below the bound: 1.2e-4 at cond 3.2e13)."""


class IllConditionedError(GyrodriftError, np.linalg.LinAlgError):
    """``H = K + I/gamma`` cannot be solved to any digit: the one refusal of this module, whichever way it shows.

    Either the Cholesky factorisation fails (``H`` not numerically positive definite: a nearly singular ``H``
    whose rounding leaves a pivot <= 0, or an indefinite kernel) or it succeeds and the condition number
    reaches ``COND_REFUSE``. For a nearly singular ``H`` which of the two happens depends on the last bits of
    the BLAS (an AMD EPYC's OpenBLAS fails the factorisation of the paper's runs at gamma 1e16, sigma 100,
    where another machine estimated cond 2.7e18), so both raise this class with one message
    ("LSSVR: H = K + I/gamma <what> cannot be solved: <why>. <hint>"). A ``numpy.linalg.LinAlgError`` (and
    therefore a ``ValueError``).
    """


NotPositiveDefiniteError = IllConditionedError
"""The former name of the Cholesky-failure refusal: the same class as :class:`IllConditionedError`."""


class IllConditionedWarning(UserWarning):
    """``H = K + I/gamma`` is ill-conditioned (``cond > COND_WARN``): results may be off beyond 1e-3 relative."""


class StoredSolutionError(InputError):
    """A stored LSSVR solution (a model file's) that does not solve the LSSVM system it claims to solve."""


class NonFiniteResultError(InputError):
    """The kernel matrix, the solution or a prediction is not finite (overflow in the kernel or the solve)."""


def _one_norm(H: np.ndarray) -> float:
    """``||H||_1``, the largest absolute column sum (the norm ``dpocon`` expects)."""
    return float(np.abs(H).sum(axis=0).max())


def _condition_number(U: np.ndarray, anorm: float) -> float:
    """1-norm condition number estimate of ``H = U'U`` from its Cholesky factor (LAPACK ``dpocon``, O(n^2))."""
    rcond, info = lapack.dpocon(U, anorm, uplo="U")
    if info != 0:  # pragma: no cover - only on invalid arguments
        raise np.linalg.LinAlgError(f"dpocon failed with info={info}")
    return math.inf if rcond == 0.0 else 1.0 / float(rcond)


def condition_warning_message(cond: float, what: str) -> str:
    """The ill-conditioning warning for ``cond > COND_WARN`` ("" below); ``what`` names the system."""
    if not cond > COND_WARN:
        return ""
    return (
        f"LSSVR: H = K + I/gamma {what} has condition number {cond:.3g} > {COND_WARN:.3g}: the solution, the "
        f"predictions and the LOO residuals may be off by up to {cond * _EPS:.2g} relative. Lower gamma (more "
        "regularisation) or sigma."
    )


def check_condition(cond: float, what: str) -> None:
    """Refuse (``IllConditionedError``) at ``cond >= COND_REFUSE``, warn (``IllConditionedWarning``) above
    ``COND_WARN``; ``what`` names the system (e.g. its gamma and sigma) in the message."""
    if not cond < COND_REFUSE:
        raise IllConditionedError(
            f"LSSVR: H = K + I/gamma {what} cannot be solved: its condition number {cond:.3g} >= 1/eps = "
            f"{COND_REFUSE:.3g}, no digit of its solution is correct. Lower gamma (more regularisation) or sigma."
        )
    message = condition_warning_message(cond, what)
    if message:
        warnings.warn(message, IllConditionedWarning, stacklevel=3)


def _not_positive_definite(what: str, hint: str) -> IllConditionedError:
    """The refusal for a failed Cholesky factorisation, in the words of :func:`check_condition`'s."""
    return IllConditionedError(
        f"LSSVR: H = K + I/gamma {what} cannot be solved: it is not numerically positive definite (the Cholesky "
        f"factorisation failed: its condition number is beyond 1/eps = {COND_REFUSE:.3g}, or the kernel is "
        f"indefinite). {hint}"
    )


# --------------------------------------------------------------------------------------------------
# Linear algebra helpers (one Cholesky factor, triangular solves; LAPACK through scipy.linalg.lapack)
# --------------------------------------------------------------------------------------------------


def _cholesky_upper(H: np.ndarray) -> np.ndarray | None:
    """Upper Cholesky factor ``U`` (``U'U = H``) of the symmetric matrix ``H``, or None if not PD.

    ``H`` is overwritten. Only one triangle is read. ``H.T`` (= ``H``) is handed to LAPACK so that a
    C-ordered ``H`` arrives as a Fortran-ordered array without a copy; ``U`` is Fortran-ordered too, so
    the later ``dpotrs``/``dtrtri`` calls do not copy it either.
    """
    U, info = lapack.dpotrf(H.T, lower=0, clean=1, overwrite_a=1)
    return U if info == 0 else None


def _cho_solve(U: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Solve ``U'U X = B`` (``dpotrs``, two triangular solves)."""
    X, info = lapack.dpotrs(U, B, lower=0)
    if info != 0:  # pragma: no cover - only on invalid arguments
        raise np.linalg.LinAlgError(f"dpotrs failed with info={info}")
    return X


def _inverse_diagonal(U: np.ndarray) -> np.ndarray:
    """``diag(H^-1)`` for ``H = U'U``: ``H^-1 = U^-1 U^-T``, so row sums of squares of ``U^-1`` (``dtrtri``)."""
    Uinv, info = lapack.dtrtri(U, lower=0)
    if info != 0:  # pragma: no cover - a successful dpotrf has a non-zero diagonal
        raise np.linalg.LinAlgError(f"dtrtri failed with info={info}")
    return np.einsum("ik,ik->i", Uinv, Uinv)


def _h_matrix(K: np.ndarray, gamma: float, copy: bool = True, weights: np.ndarray | None = None) -> np.ndarray:
    """``H = K + I/gamma`` or, with sample ``weights``, ``K + diag(1/(gamma w))`` (a new array unless ``copy``
    is False)."""
    H = np.array(K, dtype=float, copy=copy)
    H.flat[:: H.shape[0] + 1] += 1.0 / gamma if weights is None else 1.0 / (gamma * weights)
    return H


def check_sample_weight(sample_weight, n: int, *, allow_zero: bool = False) -> np.ndarray | None:
    """Sample weights as a float array of shape (n,), each finite and > 0 (``allow_zero``: >= 0, not all 0),
    or None; else ``ValueError``."""
    if sample_weight is None:
        return None
    w = np.asarray(sample_weight, dtype=float)
    if w.ndim == 0:
        w = np.full(n, float(w))
    if w.shape != (n,):
        raise ValueError(f"sample_weight must have shape ({n},), got {w.shape}")
    if allow_zero and np.all(np.isfinite(w)) and np.all(w >= 0) and np.any(w > 0):
        return w
    if not np.all(np.isfinite(w)) or not np.all(w > 0):
        raise ValueError(
            "sample weights must be finite numbers > 0 (a zero weight would make a sample's regularisation "
            "infinite: leave the sample out instead)"
        )
    return w


def _solve_factored(U: np.ndarray, y: np.ndarray):
    """(alpha, b, p, s) from the Cholesky factor of H; ``y`` of shape (n,) or (n, k)."""
    n = U.shape[0]
    y2 = y.reshape(n, -1)
    pq = _cho_solve(U, np.column_stack([np.ones(n), y2]))
    p, q = pq[:, 0], pq[:, 1:]
    s = p.sum()
    b = q.sum(axis=0) / s
    alpha = q - p[:, None] * b
    if y.ndim == 1:
        return alpha[:, 0], float(b[0]), p, s
    return alpha, b, p, s


def _loo_from_factor(U: np.ndarray, alpha: np.ndarray, p: np.ndarray, s: float) -> np.ndarray:
    denom = _inverse_diagonal(U) - p * p / s
    return alpha / (denom if alpha.ndim == 1 else denom[:, None])


def _check_system(K, y, gamma):
    gamma = check_positive("gamma", gamma)
    K = np.asarray(K, dtype=float)
    y = np.asarray(y, dtype=float)
    if K.ndim != 2 or K.shape[0] != K.shape[1]:
        raise ValueError(f"K must be a square 2-D kernel matrix, got shape {K.shape}")
    n = K.shape[0]
    if n < 2:
        raise ValueError(f"the LSSVM needs at least 2 samples, got n_samples={n}")
    if y.ndim not in (1, 2) or y.shape[0] != n:
        raise ValueError(f"y must have shape ({n},) or ({n}, k) to match K of shape {K.shape}, got {y.shape}")
    if not np.all(np.isfinite(K)):
        raise ValueError("K contains NaN or infinity")
    if not np.all(np.isfinite(y)):
        raise ValueError("y contains NaN or infinity")
    scale = np.max(np.abs(K)) if K.size else 0.0
    if not np.allclose(K, K.T, rtol=0.0, atol=1e-12 * scale):
        raise ValueError("K must be symmetric")
    return K, y, gamma


def _factor_or_raise(K: np.ndarray, gamma: float, what: str) -> np.ndarray:
    H = _h_matrix(K, gamma)
    anorm = _one_norm(H)
    U = _cholesky_upper(H)
    if U is None:
        raise _not_positive_definite(what, "Lower gamma (more regularisation) or use a positive semi-definite kernel.")
    check_condition(_condition_number(U, anorm), what)
    return U


# --------------------------------------------------------------------------------------------------
# Functional core (used by gyrodrift.learn.tuning)
# --------------------------------------------------------------------------------------------------


def lssvr_solve(K, y, gamma):
    """Solve the LSSVM dual system for a precomputed kernel matrix.

    Parameters
    ----------
    K : array_like, shape (n, n)
        Symmetric kernel matrix of the training inputs (only its lower triangle is used by the
        factorisation; symmetry is checked to 1e-12 relative).
    y : array_like, shape (n,) or (n, k)
        Targets (deg/h for drift targets). Several columns share one factorisation.
    gamma : float
        Regularisation, > 0 (larger = less regularisation).

    Returns
    -------
    alpha : ndarray, shape (n,) or (n, k)
        Dual coefficients, ``sum(alpha, axis=0) == 0``; unit of ``y``.
    b : float or ndarray of shape (k,)
        Bias (intercept), unit of ``y``. Prediction: ``f(x) = K(x, X) @ alpha + b``.

    Raises
    ------
    ValueError
        Bad shapes, NaN/inf, n < 2, gamma not a finite number > 0, K not symmetric.
    NotPositiveDefiniteError
        ``K + I/gamma`` is not numerically positive definite (message names gamma).
    """
    K, y, gamma = _check_system(K, y, gamma)
    U = _factor_or_raise(K, gamma, f"for gamma={gamma!r}")
    alpha, b, _, _ = _solve_factored(U, y)
    return alpha, b


def lssvr_loo_residuals(K, y, gamma) -> np.ndarray:
    """Exact leave-one-out residuals of the LSSVM, in closed form (Cawley & Talbot 2004).

    ``r_i = y_i - f_(-i)(x_i)`` where ``f_(-i)`` is the LSSVM (same kernel, same gamma, with its own
    bias) trained without sample ``i``. Computed as ``alpha_i / ((H^-1)_ii - p_i^2 / s)`` with
    ``H = K + I/gamma``, ``p = H^-1 1``, ``s = 1'p``: one Cholesky factorisation and one triangular
    inverse, O(n^3), instead of n refits. Equals brute-force refits to rounding.

    Parameters
    ----------
    K : array_like, shape (n, n)
        Symmetric kernel matrix, n >= 2.
    y : array_like, shape (n,) or (n, k)
        Targets (deg/h for drift targets).
    gamma : float
        Regularisation, > 0.

    Returns
    -------
    ndarray, shape of ``y``
        Leave-one-out residuals, observed minus predicted, unit of ``y``.

    Raises
    ------
    ValueError, NotPositiveDefiniteError
        As :func:`lssvr_solve`.
    """
    K, y, gamma = _check_system(K, y, gamma)
    U = _factor_or_raise(K, gamma, f"for gamma={gamma!r}")
    alpha, _, p, s = _solve_factored(U, y)
    return _loo_from_factor(U, alpha, p, s)


def rbf_batch_errors(
    sqdist, y, gammas, sigmas, kind: str = "train", weights=None, threads: int = 1, cache: EigenCache | None = None
) -> np.ndarray:
    """Per-sample errors of m RBF-LSSVMs (one per (gamma, sigma) candidate) on one training set.

    The tuner's workhorse: the squared distances are computed once (:func:`gyrodrift.learn.kernels.
    squared_distances`) and every candidate costs one Cholesky factorisation of
    ``H = exp(-sqdist / sigma^2) + I/gamma`` plus O(n^2) work (``kind="train"``) or one more triangular
    inverse (``kind="loo"``).

    Parameters
    ----------
    sqdist : array_like, shape (n, n)
        Squared distances between the (scaled) training inputs, symmetric with a zero diagonal.
    y : array_like, shape (n,)
        Targets (deg/h for drift targets).
    gammas, sigmas : array_like, shape (m,) (or scalars, broadcast against each other)
        Candidate regularisations and RBF widths, each a finite number > 0 (a bad value is a caller bug
        and raises ``ValueError`` naming the index and value).
    kind : {"train", "loo"}
        ``"train"``: ``y_i - f(x_i)`` on the training points (``= alpha_i / gamma``); the paper's fitness
        (Yu et al. 2013, eq. 16) is ``mean(abs(errors), axis=1)``. ``"loo"``: the exact leave-one-out
        residuals ``y_i - f_(-i)(x_i)`` (see :func:`lssvr_loo_residuals`).
    weights : array_like, shape (n,), optional
        Sample weights of a weighted LS-SVM (module docstring): ``H = K + diag(1/(gamma w))``.
    threads : int, default 1
        For n > 32, the candidates are shared among this many threads (the rows do not depend on it). Give the
        BLAS one thread meanwhile (``threadpoolctl``), as ``gyrodrift.learn.tuning.tune_lssvr`` does.
    cache : EigenCache, optional
        For n > 32, the eigendecompositions of recently used sigmas of this training set (``EigenCache(sqdist,
        weights)``, kept across calls): a candidate on a cached sigma costs O(n^2) (a swarm whose particles sit on
        a sigma bound asks for that sigma every iteration, a swarm whose sigmas are snapped to a grid comes back to
        its grid points); a sigma the cache saw in an earlier call is decomposed and kept (``EigenCache.wants``).

    Returns
    -------
    ndarray, shape (m, n)
        Row j holds the errors of candidate j, observed minus predicted, unit of ``y``. A candidate whose
        ``H`` is not numerically positive definite, or whose condition number reaches ``COND_REFUSE`` (its
        solution has no correct digit; ``LSSVR.fit`` refuses it), gets a row of ``+inf`` instead of an exception.

    Notes
    -----
    Two implementations, chosen by n and measured against per-candidate loops on the 2-core development
    machine (m = 30 candidates, gamma log-uniform in [0.1, 1000], sigma log-uniform in [0.3, 3] times the
    input scale, best of several runs, ``OPENBLAS_NUM_THREADS=1``; the machine was shared, so
    individual numbers scatter by up to 2x between runs):

    ==========  ==================  ===============  ====================  ========================
    n, kind     this function       loop of          loop of               numpy stack for every n
                                    ``LSSVR.fit``    ``lssvr_solve`` /     (``cholesky`` +
                                                     ``lssvr_loo_...``     ``inv(L)`` on (m, n, n))
    ==========  ==================  ===============  ====================  ========================
    22 train    0.37 ms (stacked)   8.3 ms           1.5 ms                0.35 ms
    22 loo      0.39 ms (stacked)   6.2 ms           1.8 ms                0.37 ms
    100 train   2.1 ms (loop)       12 ms            4.5 ms                15 ms
    100 loo     4.0 ms (loop)       14 ms            6.5 ms                13 ms
    200 train   8.1 ms (loop)       35 ms            20 ms                 74 ms
    200 loo     22 ms (loop)        36 ms            33 ms                 60 ms
    500 train   72 ms (loop)        126 ms           104 ms                537 ms
    500 loo     159 ms (loop)       201 ms           193 ms                524 ms
    ==========  ==================  ===============  ====================  ========================

    * n <= 32 (the paper has n = 22): the candidates are stacked into an (m, n, n) array and
      factorised by ``np.linalg.cholesky``, then ``np.linalg.inv`` of the triangular factors; this
      removes the per-candidate Python and LAPACK-wrapper overhead (about 15 us per candidate), which
      dominates at this size. One non-PD candidate makes the stacked Cholesky raise for all of them;
      the function then falls back to the loop below, which flags candidates individually.
    * n > 32: a Python loop over candidates calling LAPACK ``dpotrf``/``dpotrs`` (and ``dtrtri`` for
      "loo") directly. numpy's stacked routines have no triangular solve or inverse, so the stack
      needs a general inverse of each factor, 3-7x slower than ``dtrtri``/``dpotrs`` at n >= 100,
      and m*n*n memory. Building each kernel from ``sqdist`` in place of calling the public
      functions saves their validation (symmetry check, copies).

    The condition check (exact 1-norm condition number for the stack, ``dpocon`` in the loop) came later;
    with it, on the same shared machine: n = 22 train 0.46 ms, loo 0.48 ms; n = 100 train 2.7 ms, loo 4.5 ms.
    """
    if kind not in ("train", "loo"):
        raise ValueError(f"kind must be 'train' or 'loo', got {kind!r}")
    D = np.asarray(sqdist, dtype=float)
    y = np.asarray(y, dtype=float)
    if D.ndim != 2 or D.shape[0] != D.shape[1]:
        raise ValueError(f"sqdist must be a square 2-D matrix, got shape {D.shape}")
    n = D.shape[0]
    if n < 2:
        raise ValueError(f"the LSSVM needs at least 2 samples, got n_samples={n}")
    if y.ndim != 1 or y.shape[0] != n:
        raise ValueError(f"y must have shape ({n},) to match sqdist of shape {D.shape}, got {y.shape}")
    if not (np.all(np.isfinite(D)) and np.all(D >= 0.0)):
        raise ValueError("sqdist must be finite and non-negative")
    if not np.all(np.isfinite(y)):
        raise ValueError("y contains NaN or infinity")
    g, sg = np.broadcast_arrays(np.asarray(gammas, dtype=float), np.asarray(sigmas, dtype=float))
    g, sg = g.ravel(), sg.ravel()
    for name, values in (("gammas", g), ("sigmas", sg)):
        bad = np.flatnonzero(~(np.isfinite(values) & (values > 0.0)))
        if bad.size:
            raise ValueError(f"{name}[{bad[0]}] must be a finite number > 0, got {float(values[bad[0]])!r}")

    w = check_sample_weight(weights, n)
    threads = _check_threads(threads)
    if n <= _STACKED_MAX_N:
        try:
            return _rbf_batch_stacked(D, y, g, sg, kind, w)
        except np.linalg.LinAlgError:
            pass  # a non-PD candidate spoils the whole stack: redo candidate by candidate
    if cache is not None and not cache.serves(D, w):
        raise ValueError("cache belongs to another training set (EigenCache(sqdist, weights) of these)")
    return _rbf_batch_loop(D, y, g, sg, kind, w, threads, cache)


def _check_threads(threads) -> int:
    """``threads`` as an int >= 1, else ``ValueError``."""
    try:
        value = operator.index(threads)
    except TypeError:
        value = 0
    if isinstance(threads, bool) or value < 1:
        raise ValueError(f"threads must be an int >= 1, got {threads!r}")
    return value


#: Largest n for which :func:`rbf_batch_errors` stacks the candidates (see its Notes).
_STACKED_MAX_N = 32


def _rbf_batch_stacked(D, y, g, sg, kind, w=None):
    """All candidates at once: ``np.linalg.cholesky`` and a triangular inverse on an (m, n, n) stack.

    Raises ``LinAlgError`` if any candidate is not positive definite.
    """
    n = D.shape[0]
    H = rbf_from_squared_distances(D, sg[:, None, None])
    H[:, np.arange(n), np.arange(n)] += 1.0 / g[:, None] if w is None else 1.0 / (g[:, None] * w[None, :])
    anorm = np.abs(H).sum(axis=1).max(axis=1)  # ||H||_1 (H symmetric)
    L = np.linalg.cholesky(H)  # lower, H = L L'
    # No stacked triangular inverse in numpy: inv() of the triangular factor (LU, O(n^3) like dtrtri
    # but with a larger constant) is still the fastest for small n; H^-1 = L^-T L^-1.
    Linv = np.linalg.inv(L)
    B = np.column_stack([np.ones(n), y])
    pq = np.swapaxes(Linv, 1, 2) @ (Linv @ B)
    p, q = pq[:, :, 0], pq[:, :, 1]
    s = p.sum(axis=1, keepdims=True)
    alpha = q - (q.sum(axis=1, keepdims=True) / s) * p
    if kind == "train":
        out = alpha / g[:, None] if w is None else alpha / (g[:, None] * w[None, :])
    else:
        hinv_diag = np.einsum("mki,mki->mi", Linv, Linv)
        out = alpha / (hinv_diag - p * p / s)
    # The exact 1-norm condition number (>= the dpocon estimate LSSVR.fit uses, so a candidate kept here is
    # never refused by the final fit): small stacks, one more (m, n, n) product.
    cond = anorm * np.abs(np.swapaxes(Linv, 1, 2) @ Linv).sum(axis=1).max(axis=1)
    out[~(cond < COND_REFUSE)] = np.inf
    return out


def _rbf_batch_loop(D, y, g, sg, kind, w=None, threads: int = 1, cache: EigenCache | None = None):
    """Candidate by candidate with LAPACK ``dpotrf``/``dpotrs``/``dtrtri``; non-PD rows are +inf. Candidates sharing
    one sigma, ``EIG_MIN_GROUP`` or more of them, or one in ``cache``, or one ``cache`` saw in an earlier call (a
    sigma asked for again: :meth:`EigenCache.wants`), come from one :class:`RBFEigenSystem` instead (kept in
    ``cache``). ``threads`` > 1: the candidates and the new eigendecompositions are shared among that many threads
    (scipy's and numpy's LAPACK wrappers release the GIL; each is computed exactly as alone, so the rows do not
    depend on ``threads``)."""
    n = D.shape[0]
    out = np.empty((g.size, n))
    B = np.column_stack([np.ones(n), y])
    diag = np.arange(n) * (n + 1)
    values, inverse, counts = np.unique(sg, return_inverse=True, return_counts=True)
    alone = np.ones(g.size, dtype=bool)
    systems: dict[int, RBFEigenSystem | None] = {}
    for k, sigma in enumerate(values.tolist()):
        systems[k] = None if cache is None else cache.get(sigma)
        if systems[k] is not None or counts[k] >= EIG_MIN_GROUP or (cache is not None and cache.wants(sigma)):
            alone[inverse == k] = False
    if cache is not None:
        cache.saw(values.tolist())

    def group(k: int) -> None:
        system = systems[k]
        if system is None:
            system = systems[k] = RBFEigenSystem(D, float(values[k]), w)
        rows = np.flatnonzero(inverse == k)
        out[rows] = system.errors(g[rows], y, kind)

    def candidate(j: int) -> None:
        H = rbf_from_squared_distances(D, sg[j])
        H.flat[diag] += 1.0 / g[j] if w is None else 1.0 / (g[j] * w)
        anorm = _one_norm(H)
        U = _cholesky_upper(H)
        if U is None or not _condition_number(U, anorm) < COND_REFUSE:  # as LSSVR.fit refuses it
            out[j] = np.inf
            return
        pq = _cho_solve(U, B)
        p, q = pq[:, 0], pq[:, 1]
        s = p.sum()
        alpha = q - (q.sum() / s) * p
        if kind == "train":
            out[j] = alpha / g[j] if w is None else alpha / (g[j] * w)
        else:
            out[j] = _loo_from_factor(U, alpha, p, s)

    groups = [k for k in systems if not alone[inverse == k].any()]
    todo = [(group, k) for k in groups] + [(candidate, int(j)) for j in np.flatnonzero(alone)]
    if threads > 1 and len(todo) > 1:
        with ThreadPoolExecutor(min(threads, len(todo))) as pool:
            list(pool.map(lambda task: task[0](task[1]), todo))
    else:
        for task, arg in todo:
            task(arg)
    if cache is not None:
        for k in groups:
            cache.put(float(values[k]), systems[k])  # type: ignore[arg-type]
    return out


# --------------------------------------------------------------------------------------------------
# One eigendecomposition per sigma, every gamma from it (the tuner's grid, fold scores at fixed hyperparameters)
# --------------------------------------------------------------------------------------------------

#: Smallest number of candidates sharing one sigma for which :func:`rbf_batch_errors` (n > 32) takes them from
#: one eigendecomposition instead of one Cholesky factor each: ``eigh`` costs about 4-5 factorisations with their
#: triangular inverse (measured at n = 200 and 1000, one BLAS thread; ``benchmarks/bench_tuning.py``).
EIG_MIN_GROUP = 6


class EigenCache:
    """The :class:`RBFEigenSystem` of the ``size`` most recently used sigmas of one training set (``sqdist`` and
    ``weights`` as given to :func:`rbf_batch_errors`, which refuses a cache of another set). Memory: two n x n
    float64 matrices per sigma (16 MB at n = 1000); never more than ``size`` of them.

    It also remembers every sigma it was asked about (a set of floats, not matrices): a sigma asked for a second
    time is worth an eigendecomposition (:meth:`wants`) even alone, since a swarm whose sigmas are snapped to a grid
    (``gyrodrift.learn.tuning``) keeps coming back to the same few. An eigendecomposition costs about 2 (n = 200) to 5
    (n = 1000) Cholesky factorisations with their triangular inverse, so paying it on the second visit costs at
    most that much more than the Cholesky path for a sigma never seen again."""

    def __init__(self, sqdist, weights=None, size: int = 4) -> None:
        self._sqdist, self._weights, self.size = sqdist, weights, int(size)
        self._systems: dict[float, RBFEigenSystem] = {}
        self._seen: set[float] = set()

    def wants(self, sigma: float) -> bool:
        """Whether ``sigma`` was asked about before (:meth:`saw`): take it from an eigendecomposition and keep it."""
        return sigma in self._seen

    def saw(self, sigmas) -> None:
        """Remember that ``sigmas`` were asked about."""
        self._seen.update(float(v) for v in sigmas)

    def __len__(self) -> int:
        return len(self._systems)

    def serves(self, sqdist, weights) -> bool:
        """Whether this cache belongs to the training set ``(sqdist, weights)`` (the same arrays, or equal ones)."""
        same_w = (weights is None and self._weights is None) or (
            weights is not None and self._weights is not None and np.array_equal(weights, self._weights)
        )
        return same_w and (sqdist is self._sqdist or np.array_equal(sqdist, self._sqdist))

    def get(self, sigma: float) -> RBFEigenSystem | None:
        system = self._systems.pop(sigma, None)
        if system is not None:
            self._systems[sigma] = system  # most recent last
        return system

    def put(self, sigma: float, system: RBFEigenSystem) -> None:
        self._systems[sigma] = system
        while len(self._systems) > self.size:
            del self._systems[next(iter(self._systems))]


class RBFEigenSystem:
    """The RBF LSSVM of one kernel width for every gamma, from one eigendecomposition (weighted or not).

    With sample weights ``w`` (all 1 when None) ``H = K + diag(1/(gamma w))``; with ``S = diag(sqrt(w))``,
    ``H = S^-1 (S K S + I/gamma) S^-1`` and ``S K S = V diag(lam) V'`` (LAPACK ``dsyevd`` via ``numpy.linalg.eigh``,
    O(n^3) once), so for any gamma ``H^-1 = S V diag(d) V' S`` with ``d = 1/(lam + 1/gamma)``: the bordered
    system's ``p = H^-1 1``, ``q = H^-1 y``, ``alpha``, ``b`` and ``diag(H^-1)`` (hence the closed-form LOO
    residuals of the module docstring) cost O(n^2) per gamma (matrix products when several gammas are asked at
    once). ``H`` is positive definite iff every ``lam + 1/gamma > 0``.

    Condition number: ``cond_bound(gamma)`` is an upper bound of the 1-norm condition number of ``H`` (the one
    ``LSSVR.fit`` estimates with ``dpocon``, which never exceeds the exact one): ``||H||_1`` exactly (column sums
    of ``K`` plus the diagonal term) times ``sqrt(n) ||H^-1||_2 <= sqrt(n) max(w) max(d)``. So a candidate this
    class keeps (bound < ``COND_REFUSE``) is never refused by the final fit; it may refuse a candidate whose
    exact 1-norm condition number is up to ``sqrt(n) max(w)/min(w)`` times lower, i.e. only at condition
    numbers beyond 1e12 (gamma > ~1e12 with a nearly singular kernel): far outside the default search box.

    Agreement with the Cholesky path (``lssvr_solve``, ``lssvr_loo_residuals``, ``LSSVR``): both are backward
    stable, so they agree to about ``cond(H) * eps`` relative (tests: 1e-8 relative at cond <= 1e6).

    Parameters
    ----------
    sqdist : array_like, shape (n, n)
        Squared distances of the scaled training inputs (``squared_distances``), n >= 2.
    sigma : float
        RBF width, scaled input units.
    weights : array_like, shape (n,), optional
        Sample weights > 0 (``check_sample_weight``).
    """

    def __init__(self, sqdist, sigma: float, weights=None) -> None:
        D = np.asarray(sqdist, dtype=float)
        n = D.shape[0]
        self.sigma = check_sigma(sigma)
        self.weights = check_sample_weight(weights, n)
        self.n = n
        K = rbf_from_squared_distances(D, self.sigma)
        self._colsum = K.sum(axis=0) - 1.0  # K >= 0 with a unit diagonal: ||H||_1 = max(colsum + 1 + 1/(gamma w))
        sw = np.ones(n) if self.weights is None else np.sqrt(self.weights)
        if self.weights is not None:
            K *= sw[:, None]
            K *= sw[None, :]
        self.lam, V = np.linalg.eigh(K)
        self._sw = sw
        self._V = V
        self._V2 = V * V
        self._c1 = V.T @ sw  # V' S 1
        self._y: np.ndarray | None = None
        self._cy = self._c1

    def _d(self, gammas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(d, ok)``: ``1/(lam + 1/gamma)`` as an (n, m) array and which gammas give a positive definite H."""
        shifted = self.lam[:, None] + 1.0 / gammas[None, :]
        ok = np.all(shifted > 0.0, axis=0)
        with np.errstate(divide="ignore"):
            d = np.where(shifted > 0.0, 1.0 / np.where(shifted > 0.0, shifted, 1.0), 0.0)
        return d, ok

    def cond_bound(self, gammas) -> np.ndarray:
        """Upper bound of the 1-norm condition number of ``H`` for each gamma (class docstring); inf when not PD."""
        g = np.atleast_1d(np.asarray(gammas, dtype=float))
        w = np.ones(self.n) if self.weights is None else self.weights
        anorm = np.max(self._colsum[None, :] + 1.0 + 1.0 / (g[:, None] * w[None, :]), axis=1)
        shifted = self.lam.min() + 1.0 / g
        with np.errstate(divide="ignore"):
            inv_norm = np.where(shifted > 0.0, np.max(w) / np.where(shifted > 0.0, shifted, 1.0), np.inf)
        return anorm * math.sqrt(self.n) * inv_norm

    def solve(self, gammas, y):
        """``(alpha, b, hinv_diag, p, s)`` for each gamma: alpha, diag(H^-1), p of shape (m, n); b, s of shape (m,).

        Rows of gammas whose ``H`` is not positive definite are NaN."""
        g = np.atleast_1d(np.asarray(gammas, dtype=float))
        y = np.asarray(y, dtype=float)
        d, ok = self._d(g)
        V, sw = self._V, self._sw
        if self._y is None or not np.array_equal(self._y, y):  # the tuner asks about one y again and again
            self._y, self._cy = y.copy(), V.T @ (sw * y)
        cy = self._cy
        c1 = self._c1
        s = c1**2 @ d  # 1' H^-1 1
        b = (c1 * cy) @ d / s
        m = g.size
        # p and alpha from one pass over V (memory-bound at large n)
        pa = sw[:, None] * (V @ np.hstack([c1[:, None] * d, (cy[:, None] - c1[:, None] * b[None, :]) * d]))
        p, alpha = pa[:, :m], pa[:, m:]
        hinv_diag = (sw * sw)[:, None] * (self._V2 @ d)
        out = alpha.T, b, hinv_diag.T, p.T, s
        for a in out:
            a[~ok] = np.nan
        return out

    def errors(self, gammas, y, kind: str = "loo") -> np.ndarray:
        """Per-sample errors (observed minus predicted) of each gamma, shape (m, n): ``"loo"`` the closed-form
        leave-one-out residuals, ``"train"`` the training residuals ``alpha / (gamma w)``; rows of gammas whose H is
        not positive definite or whose ``cond_bound`` reaches ``COND_REFUSE`` are +inf (as ``rbf_batch_errors``)."""
        g = np.atleast_1d(np.asarray(gammas, dtype=float))
        alpha, _, hinv_diag, p, s = self.solve(g, y)
        if kind == "train":
            w = 1.0 if self.weights is None else self.weights[None, :]
            out = alpha / (g[:, None] * w)
        else:
            out = alpha / (hinv_diag - p * p / s[:, None])
        out[~(self.cond_bound(g) < COND_REFUSE)] = np.inf
        out[~np.all(np.isfinite(out), axis=1)] = np.inf
        return out

    def loo(self, gamma: float, y) -> tuple[np.ndarray, np.ndarray]:
        """``(residuals, loo_scale)`` of one gamma: the closed-form LOO residuals [unit of y] and the LOO predictive
        scale ``1/sqrt((H^-1)_ii - p_i^2/s)`` [prior std units], as ``LSSVR.loo_residuals_`` and ``loo_scale_``."""
        alpha, _, hinv_diag, p, s = self.solve([gamma], y)
        denom = hinv_diag[0] - p[0] ** 2 / s[0]
        return alpha[0] / denom, 1.0 / np.sqrt(np.maximum(denom, np.finfo(float).tiny))

    def fold_residuals(self, gamma: float, y, folds) -> np.ndarray:
        """Held-out residuals ``y_S - f_(-S)(x_S)`` of each fold S (an array of fold labels, one per sample) of the
        LSSVM refitted without S at the same gamma and sigma, in closed form: ``e_S = C_SS^-1 alpha_S`` with
        ``C = H^-1 - p p'/s`` (the alpha block of the bordered inverse; An, Liu & Venkatesh 2007). O(n^3) once
        for ``C``, then one small solve per fold; equals refits to rounding (tested)."""
        folds = np.asarray(folds)
        if folds.shape != (self.n,):
            raise ValueError(f"folds must hold one label per sample, shape ({self.n},), got {folds.shape}")
        alpha, _, _, p, s = self.solve([gamma], y)
        d, _ = self._d(np.array([float(gamma)]))
        SV = self._sw[:, None] * self._V
        C = (SV * d[:, 0]) @ SV.T - np.outer(p[0], p[0]) / s[0]
        out = np.empty(self.n)
        for label in np.unique(folds):
            idx = np.flatnonzero(folds == label)
            if self.n - idx.size < 2:
                raise ValueError("a fold must leave at least 2 samples in training")
            out[idx] = np.linalg.solve(C[np.ix_(idx, idx)], alpha[0, idx])
        return out


# --------------------------------------------------------------------------------------------------
# scikit-learn estimator
# --------------------------------------------------------------------------------------------------


class LSSVR(RegressorMixin, BaseEstimator):
    """Least-squares support vector regression (Suykens) with an unregularised bias.

    Solves ``[0 1'; 1 K + I/gamma] [b; alpha] = [0; y]`` and predicts
    ``f(x) = sum_i alpha_i K(x_i, x) + b``. Works in ``Pipeline``, ``GridSearchCV`` and ``clone``.

    Parameters
    ----------
    All parameters are keyword-only.

    gamma : float, default=1.0
        Regularisation, > 0; larger = less regularisation (gamma -> inf interpolates the training data).
        Unrelated to scikit-learn's kernel ``gamma``: here the kernel width is ``sigma``.
    sigma : float, default=1.0
        Kernel width, > 0, in the units of the (scaled) inputs. rbf:
        ``exp(-|x - z|^2 / sigma^2)`` (no factor 2); poly: ``(x.z / sigma^2 + coef0)^degree``;
        ignored by linear (but still validated).
    kernel : {"rbf", "linear", "poly", "polynomial"}, default="rbf"
    degree : int, default=3
        Polynomial degree (poly only), integer >= 1.
    coef0 : float, default=1.0
        Polynomial offset (poly only). With ``coef0 < 0`` the kernel may be indefinite and ``fit`` may
        raise :class:`NotPositiveDefiniteError`.

    Attributes
    ----------
    alpha_ : ndarray, shape (n_samples,) or (n_samples, n_targets)
        Dual coefficients; they sum to zero over the samples. Unit of ``y``.
    intercept_ : float or ndarray of shape (n_targets,)
        Bias ``b``, unit of ``y`` (deg/h for drift targets).
    X_fit_ : ndarray, shape (n_samples, n_features)
        Training inputs (a float64 copy), needed by ``predict``.
    loo_residuals_ : ndarray, shape of the training ``y``
        Exact leave-one-out residuals ``r_i = y_i - f_(-i)(x_i)`` (observed minus predicted; Cawley & Talbot
        2004), ``f_(-i)`` being this LSSVM (same hyperparameters, own bias) refitted without sample ``i``;
        computed in closed form from the Cholesky factor as ``alpha_i / ((H^-1)_ii - p_i^2 / s)``,
        ``p = H^-1 1``, ``s = 1'p``. Unit of ``y``; ``mean(r**2)`` is the PRESS / LOO mean squared error.
    condition_number_ : float
        1-norm condition number estimate of ``H = K + I/gamma`` (LAPACK ``dpocon``); see ``COND_WARN`` and
        ``COND_REFUSE``.
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        Only when ``X`` had string column names.

    Notes
    -----
    * Multi-output: a 2-D ``y`` of shape (n, k) is supported; the k problems share one factorisation.
    * Failure mode: if ``K + I/gamma`` is not numerically positive definite ``fit`` raises
      :class:`IllConditionedError` naming gamma, sigma and the kernel; no jitter is added.
    * Cross-checks: scikit-learn ``KernelRidge(alpha=1/gamma, kernel="rbf", gamma=1/sigma^2)`` fitted on
      ``y - intercept_`` gives ``dual_coef_ == alpha_``; poly maps to ``KernelRidge(kernel="poly",
      gamma=1/sigma^2, coef0=coef0, degree=degree)``; linear to ``kernel="linear"``.
      LS-SVMlab 1.8: ``sig2 = sigma^2 / 2``.
    * The training residuals are ``y - predict(X) = alpha_ / gamma``; ``loo_residuals_`` holds the
      exact leave-one-out residuals. Both are observed minus predicted.
    * Conditioning: ``fit`` refuses ``cond(H) >= COND_REFUSE`` (``IllConditionedError``) and warns above
      ``COND_WARN`` (``IllConditionedWarning``), as scikit-learn's ``KernelRidge`` warns; non-finite kernels,
      solutions and predictions raise ``NonFiniteResultError`` instead of returning NaN.

    Examples
    --------
    >>> import numpy as np
    >>> X = np.linspace(0, 1, 20)[:, None]
    >>> model = LSSVR(gamma=100.0, sigma=0.3).fit(X, np.sin(6 * X[:, 0]))
    >>> bool(abs(model.alpha_.sum()) < 1e-9)
    True
    """

    def __init__(self, *, gamma=1.0, sigma=1.0, kernel="rbf", degree=3, coef0=1.0):
        self.gamma = gamma
        self.sigma = sigma
        self.kernel = kernel
        self.degree = degree
        self.coef0 = coef0

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        tags.input_tags.sparse = False
        return tags

    def _more_tags(self):  # pragma: no cover - scikit-learn < 1.6
        return {"multioutput": True}

    def _kernel(self, X, Z=None):
        return kernel_matrix(X, Z, kernel=self.kernel, sigma=self.sigma, degree=self.degree, coef0=self.coef0)

    def _describe(self) -> str:
        return f"gamma={self.gamma!r}, sigma={self.sigma!r}, kernel={self.kernel!r}"

    def fit(self, X, y, sample_weight=None):
        """Fit the LSSVM (weighted with ``sample_weight``: ``H = K + diag(1/(gamma w))``, module docstring).

        Parameters
        ----------
        X : array_like, shape (n_samples, n_features)
            Training inputs (scaled by the caller), n_samples >= 2, finite.
        y : array_like, shape (n_samples,) or (n_samples, n_targets)
            Targets, finite (deg/h for drift targets).
        sample_weight : array_like, shape (n_samples,), optional
            Per-sample weights > 0 (regularisation ``C_i = gamma w_i``); None: all 1.

        Returns
        -------
        self : LSSVR

        Raises
        ------
        ValueError
            gamma not a finite number > 0, sigma outside [SIGMA_MIN, SIGMA_MAX] (``gyrodrift.learn.kernels``),
            unknown kernel, bad degree/coef0, NaN/inf, fewer than 2 samples, inconsistent lengths.
        MemoryLimitError
            The n x n matrices would not fit in the available memory (checked before allocating).
        IllConditionedError
            ``K + I/gamma`` not numerically positive definite, or ``cond(K + I/gamma) >= COND_REFUSE`` (one
            class, one message naming gamma, sigma and kernel); above ``COND_WARN`` an
            ``IllConditionedWarning`` is issued.
        NonFiniteResultError
            The kernel matrix or the solution is not finite (overflow).
        """
        gamma = check_positive("gamma", self.gamma)
        check_sigma(self.sigma)
        check_kernel(self.kernel)
        X, y = _validate_data(
            self, X, y, dtype=np.float64, multi_output=True, y_numeric=True, ensure_min_samples=2, copy=True
        )  # X_fit_ must not alias the caller's X
        y = np.asarray(y, dtype=np.float64)
        weights = check_sample_weight(sample_weight, X.shape[0], allow_zero=True)
        if weights is not None and np.any(weights == 0):
            return self._fit_without_zero_weights(X, y, weights)
        n = X.shape[0]
        check_matrix_memory(n, n, _FIT_MATRICES, "fitting the LSSVR", unit="samples")
        K = self._kernel(X)
        if not np.all(np.isfinite(K)):
            raise NonFiniteResultError(
                f"LSSVR: the kernel matrix is not finite for {self._describe()} (overflow); scale the inputs "
                "or change sigma"
            )
        H = _h_matrix(K, gamma, copy=False, weights=weights)  # K is ours: overwrite it
        anorm = _one_norm(H)
        U = _cholesky_upper(H)
        if U is None:
            raise _not_positive_definite(
                f"for {self._describe()}",
                "Lower gamma (more regularisation), change sigma, or remove duplicated training samples.",
            )
        cond = _condition_number(U, anorm)
        check_condition(cond, f"for {self._describe()}")
        alpha, intercept, _, _ = _solve_factored(U, y)
        p = _cho_solve(U, np.ones(n))
        denom = _inverse_diagonal(U) - p * p / p.sum()
        loo = alpha / (denom if alpha.ndim == 1 else denom[:, None])
        if not (np.all(np.isfinite(alpha)) and np.all(np.isfinite(intercept)) and np.all(np.isfinite(loo))):
            raise NonFiniteResultError(f"LSSVR: the solution is not finite for {self._describe()}")
        self.alpha_, self.intercept_ = alpha, intercept
        self.loo_residuals_ = loo
        self.loo_scale_ = 1.0 / np.sqrt(np.maximum(denom, np.finfo(float).tiny))
        self.factor_ = U
        self.sample_weight_ = np.ones(n) if weights is None else weights
        self.condition_number_ = cond
        self.X_fit_ = X
        return self

    def predict(self, X, offset=None):
        """Predict ``f(x) = sum_i alpha_i K(x_i, x) + b`` (``+ offset``), with the arithmetic of the generated code.

        The module docstring ("Prediction arithmetic") gives the operations: kernel values as the C/Rust export
        computes them, and a compensated sum, so that a prediction near zero from cancelling terms is still
        accurate to the rounding of the terms themselves.

        Parameters
        ----------
        X : array_like, shape (n_samples, n_features)
            Inputs scaled like the training inputs, finite.
        offset : array_like, shape (n_samples,), optional
            One more term of each sample's sum, in the unit of ``y`` (a hybrid model's physics estimate, deg/h):
            added inside the compensated sum, not after its rounding.

        Returns
        -------
        ndarray, shape (n_samples,) or (n_samples, n_targets)
            Predictions in the unit of ``y`` (deg/h for drift targets).

        Raises
        ------
        MemoryLimitError
            The (n_samples, n_train) kernel matrix would not fit in the available memory.
        NonFiniteResultError
            A prediction is not finite (kernel overflow); never returned as NaN.
        """
        check_is_fitted(self, ("alpha_", "intercept_", "X_fit_"))
        X = _validate_data(self, X, dtype=np.float64, reset=False)
        check_matrix_memory(X.shape[0], self.X_fit_.shape[0], 3, "predicting with the LSSVR", unit="samples")
        alpha = np.asarray(self.alpha_, float)
        if offset is not None:
            offset = np.asarray(offset, float)
            if offset.shape != (X.shape[0],):
                raise ValueError(f"offset has shape {offset.shape}, expected ({X.shape[0]},), one value per sample")
            offset = offset.reshape((X.shape[0],) + (1,) * (alpha.ndim - 1))
        with np.errstate(over="ignore", invalid="ignore"):  # checked below
            out = _compensated_expansion(self._prediction_kernel(X), alpha, self.intercept_, offset)
        if not np.all(np.isfinite(out)):
            raise NonFiniteResultError(
                f"LSSVR: a prediction is not finite for {self._describe()} (kernel overflow on inputs far "
                "outside the training data?)"
            )
        return out

    def _prediction_kernel(self, X: np.ndarray) -> np.ndarray:
        """``K(x_i, X[j])`` for each support vector ``x_i`` (rows) and sample (columns), shape (n_train, n_samples),
        with the operations of the generated code (module docstring): features in order, the RBF kernel's ``exp``
        from the C library (``math.exp``; numpy's own may differ by an ulp), an integer power multiplied out."""
        kernel = check_kernel(self.kernel)
        Z = self.X_fit_
        acc = np.zeros((Z.shape[0], X.shape[0]))
        for k in range(X.shape[1]):
            if kernel == "rbf":
                t = X[None, :, k] - Z[:, k, None]
                acc += t * t
            else:
                acc += X[None, :, k] * Z[:, k, None]
        if kernel == "linear":
            return acc
        sigma = check_sigma(self.sigma)
        if kernel == "rbf":
            arg = -acc / (sigma * sigma)
            return np.fromiter(map(math.exp, arg.ravel()), float, arg.size).reshape(arg.shape)
        base = acc / (sigma * sigma) + float(self.coef0)
        out = base.copy()
        for _ in range(1, int(self.degree)):  # checked by fit
            out *= base
        return out

    def _fit_without_zero_weights(self, X, y, weights):
        """A zero weight leaves its sample out: fit on the others; the left-out samples' "leave-one-out"
        residuals and scales are those of plain predictions (they were never in)."""
        keep = weights > 0
        if keep.sum() < 2:
            raise ValueError("the LSSVM needs at least 2 samples with a non-zero weight")
        self.fit(X[keep], y[keep], sample_weight=weights[keep])
        loo = np.empty_like(y)
        loo[keep] = self.loo_residuals_
        loo[~keep] = y[~keep] - self.predict(X[~keep])
        scale = np.empty(len(y))
        scale[keep] = self.loo_scale_
        scale[~keep] = self.predictive_scale(X[~keep])
        self.loo_residuals_, self.loo_scale_, self.sample_weight_ = loo, scale, weights
        return self

    @classmethod
    def from_solution(
        cls,
        X,
        y,
        *,
        gamma: float,
        sigma: float,
        alpha,
        intercept: float,
        loo_residuals,
        condition_number: float,
        sample_weight=None,
        rtol: float = 1e-9,
    ) -> LSSVR:
        """A fitted RBF LSSVR from a stored solution (a model file's), without solving the n x n system.

        Verified cheaply, O(32 n): ``sum(alpha) = 0`` and the dual equations ``K_i alpha + alpha_i/(gamma w_i) + b =
        y_i`` of up to 32 rows spread over the samples, each to ``rtol`` of the sum of the absolute values of its
        terms (a backward-stable solve leaves about ``n eps`` of it; an edited coefficient leaves far more, in every
        row its kernel reaches and in the sum). ``loo_residuals`` and ``condition_number`` are taken as stored (an
        O(n^3) inverse would be needed to recompute them); ``predictive_scale`` factorises ``H`` on first use.
        Raises :class:`StoredSolutionError` (an ``InputError``, a ``ValueError``) naming what does not hold. ``X``
        (scaled inputs, n x d) and ``y`` as given to ``fit``.
        """
        est = cls(gamma=gamma, sigma=sigma)
        gamma = check_positive("gamma", gamma)
        sigma = check_sigma(sigma)
        X, y = _validate_data(est, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2, copy=True)
        n = X.shape[0]
        w = check_sample_weight(sample_weight, n)
        alpha = np.asarray(alpha, dtype=float)
        loo = np.asarray(loo_residuals, dtype=float)
        if alpha.shape != (n,) or loo.shape != (n,) or not (np.all(np.isfinite(alpha)) and np.all(np.isfinite(loo))):
            raise StoredSolutionError(f"the stored solution must hold {n} finite dual coefficients and LOO residuals")
        b = float(intercept)
        if not abs(alpha.sum()) <= rtol * max(np.abs(alpha).sum(), np.finfo(float).tiny):
            raise StoredSolutionError(f"the stored dual coefficients do not sum to 0 (sum {alpha.sum():.3g})")
        rows = np.unique(np.linspace(0, n - 1, min(n, 32)).round().astype(int))
        Kr = rbf_from_squared_distances(squared_distances(X[rows], X), sigma)
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
        est.alpha_, est.intercept_, est.X_fit_ = alpha, b, X
        est.loo_residuals_ = loo
        est.sample_weight_ = np.ones(n) if w is None else w
        est.condition_number_ = float(condition_number)
        return est

    def predictive_scale(self, X) -> np.ndarray:
        """``v(x)``, the predictive standard deviation of a new observation (weight 1) at each row of ``X`` in
        units of the prior (kernel) standard deviation (module docstring); dimensionless, >= 1/sqrt(gamma).

        Multiply by a scale fitted on the leave-one-out residuals (``r_i / loo_scale_[i]``) to get deg/h.
        """
        check_is_fitted(self, ("alpha_", "X_fit_"))
        X = _validate_data(self, X, dtype=np.float64, reset=False)
        check_matrix_memory(X.shape[0], self.X_fit_.shape[0], 3, "predicting with the LSSVR", unit="samples")
        k = self._kernel(self.X_fit_, X)  # (n_train, m)
        kxx = np.array([float(self._kernel(x[None, :])[0, 0]) for x in X]) if self.kernel != "rbf" else 1.0
        if not hasattr(self, "factor_"):  # rebuilt from a stored solution (from_solution): factorise once, now
            H = _h_matrix(self._kernel(self.X_fit_), float(self.gamma), copy=False, weights=self.sample_weight_)
            self.factor_ = _cholesky_upper(H)
            if self.factor_ is None:  # pragma: no cover - from_solution verified a solvable system
                raise _not_positive_definite(f"for {self._describe()}", "Refit the model.")
        U = self.factor_
        hk = _cho_solve(U, k)
        p = _cho_solve(U, np.ones(U.shape[0]))
        s = p.sum()
        var = kxx - np.einsum("ij,ij->j", k, hk) + (1.0 - p @ k) ** 2 / s
        return np.sqrt(np.maximum(var, 0.0) + 1.0 / float(self.gamma))

    def loo_residuals(self) -> np.ndarray:
        """A copy of :attr:`loo_residuals_`, the exact leave-one-out residuals of the fitted model."""
        check_is_fitted(self, ("alpha_", "intercept_", "X_fit_"))
        return np.array(self.loo_residuals_, copy=True)


def _compensated_expansion(KT: np.ndarray, alpha: np.ndarray, intercept, offset=None) -> np.ndarray:
    """``intercept + sum_i alpha[i] * KT[i] (+ offset)``, the terms added in that order with Knuth's TwoSum
    (``t = s + p``, ``z = t - s``, error ``(s - (t - z)) + (p - z)``, exact in binary floating point) and the
    errors summed apart and added at the end ("Sum2", Ogita, Rump & Oishi 2005): as accurate as summing in twice
    the working precision, then rounding. The generated C and Rust (`gyrodrift.export.generate`) do the same operations.

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


#: n x n float64 matrices alive at once in ``LSSVR.fit`` (distances, kernel/H, its factor, the inverse factor).
_FIT_MATRICES = 4
