"""The LSSVM's linear system (Suykens' LSSVM with an unregularised bias): its Cholesky solution, the closed-form
leave-one-out residuals and the conditioning checks shared by the estimator (`gyrodrift.learn.lssvr.LSSVR`) and the
tuner's batches (`gyrodrift.learn.lssvm_batch`).

The LSSVM of Yu et al. (2013) maps the 12 h navigation latitude and the temperature change to the axial gyro
drift. Given training inputs ``x_i`` (units: whatever the caller scaled) and targets ``y_i``
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
with 1-sigma ``s_i``, ``w_i = mean(s^2) / s_i^2`` (``gyrodrift.learn.physics_base.label_weights``).

If the Cholesky factorisation fails (``H`` not numerically positive definite, e.g. an enormous gamma with
a singular kernel matrix - duplicated training points - or an indefinite polynomial kernel with
``coef0 < 0``) the functions raise :class:`IllConditionedError` (a ``numpy.linalg.LinAlgError``,
itself a ``ValueError``), as they do when the condition number reaches ``COND_REFUSE``: one refusal, whichever
path a given BLAS takes.
No jitter is ever added silently: lower gamma (more regularisation) instead.
:func:`gyrodrift.learn.lssvm_batch.rbf_batch_errors` is the exception to raising: it returns rows of ``+inf`` so that a
tuner survives.
"""

from __future__ import annotations

import math

import numpy as np

from gyrodrift.errors import GyrodriftError, InputError
from gyrodrift.learn.kernels import check_positive
from gyrodrift.learn.user_warning import warn_user

__all__ = [
    "COND_REFUSE",
    "COND_WARN",
    "IllConditionedError",
    "IllConditionedWarning",
    "NonFiniteResultError",
    "StoredSolutionError",
    "check_condition",
    "check_sample_weight",
    "check_square_system",
    "cho_solve",
    "cholesky_upper",
    "condition_estimate",
    "condition_warning_message",
    "h_matrix",
    "inverse_diagonal",
    "loo_from_factor",
    "lssvr_loo_residuals",
    "lssvr_solve",
    "not_positive_definite",
    "one_norm",
    "solve_factored",
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


class IllConditionedWarning(UserWarning):
    """``H = K + I/gamma`` is ill-conditioned (``cond > COND_WARN``): results may be off beyond 1e-3 relative."""


class StoredSolutionError(InputError):
    """A stored LSSVR solution (a model file's) that does not solve the LSSVM system it claims to solve."""


class NonFiniteResultError(InputError):
    """The kernel matrix, the solution or a prediction is not finite (overflow in the kernel or the solve)."""


def one_norm(H: np.ndarray) -> float:
    """``||H||_1``, the largest absolute column sum (the norm ``dpocon`` expects)."""
    return float(np.abs(H).sum(axis=0).max())


def condition_estimate(U: np.ndarray, anorm: float) -> float:
    """1-norm condition number estimate of ``H = U'U`` from its Cholesky factor (LAPACK ``dpocon``, O(n^2))."""
    from scipy.linalg import lapack  # here (and below): scipy.linalg costs ~0.4 s of a CLI start

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
        warn_user(message, IllConditionedWarning)


def not_positive_definite(what: str, hint: str) -> IllConditionedError:
    """The refusal for a failed Cholesky factorisation, in the words of :func:`check_condition`'s."""
    return IllConditionedError(
        f"LSSVR: H = K + I/gamma {what} cannot be solved: it is not numerically positive definite (the Cholesky "
        f"factorisation failed: its condition number is beyond 1/eps = {COND_REFUSE:.3g}, or the kernel is "
        f"indefinite). {hint}"
    )


# --------------------------------------------------------------------------------------------------
# Linear algebra helpers (one Cholesky factor, triangular solves; LAPACK through scipy.linalg.lapack)
# --------------------------------------------------------------------------------------------------


def cholesky_upper(H: np.ndarray) -> np.ndarray | None:
    """Upper Cholesky factor ``U`` (``U'U = H``) of the symmetric matrix ``H``, or None if not PD.

    ``H`` is overwritten. Only one triangle is read. ``H.T`` (= ``H``) is handed to LAPACK so that a
    C-ordered ``H`` arrives as a Fortran-ordered array without a copy; ``U`` is Fortran-ordered too, so
    the later ``dpotrs``/``dtrtri`` calls do not copy it either.
    """
    from scipy.linalg import lapack

    U, info = lapack.dpotrf(H.T, lower=0, clean=1, overwrite_a=1)
    return U if info == 0 else None


def cho_solve(U: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Solve ``U'U X = B`` (``dpotrs``, two triangular solves)."""
    from scipy.linalg import lapack

    X, info = lapack.dpotrs(U, B, lower=0)
    if info != 0:  # pragma: no cover - only on invalid arguments
        raise np.linalg.LinAlgError(f"dpotrs failed with info={info}")
    return X


def inverse_diagonal(U: np.ndarray) -> np.ndarray:
    """``diag(H^-1)`` for ``H = U'U``: ``H^-1 = U^-1 U^-T``, so row sums of squares of ``U^-1`` (``dtrtri``)."""
    from scipy.linalg import lapack

    Uinv, info = lapack.dtrtri(U, lower=0)
    if info != 0:  # pragma: no cover - a successful dpotrf has a non-zero diagonal
        raise np.linalg.LinAlgError(f"dtrtri failed with info={info}")
    return np.einsum("ik,ik->i", Uinv, Uinv)


def h_matrix(K: np.ndarray, gamma: float, copy: bool = True, weights: np.ndarray | None = None) -> np.ndarray:
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


def solve_factored(U: np.ndarray, y: np.ndarray):
    """(alpha, b, p, s) from the Cholesky factor of H; ``y`` of shape (n,) or (n, k)."""
    n = U.shape[0]
    y2 = y.reshape(n, -1)
    pq = cho_solve(U, np.column_stack([np.ones(n), y2]))
    p, q = pq[:, 0], pq[:, 1:]
    s = p.sum()
    b = q.sum(axis=0) / s
    alpha = q - p[:, None] * b
    if y.ndim == 1:
        return alpha[:, 0], float(b[0]), p, s
    return alpha, b, p, s


def loo_from_factor(U: np.ndarray, alpha: np.ndarray, p: np.ndarray, s: float) -> np.ndarray:
    denom = inverse_diagonal(U) - p * p / s
    return alpha / (denom if alpha.ndim == 1 else denom[:, None])


def check_square_system(M, y, name: str, what: str, *, multi_output: bool) -> tuple[np.ndarray, np.ndarray]:
    """``M`` (an n x n ``what`` named ``name``, n >= 2) and the targets ``y`` (shape (n,), or (n, k) with
    ``multi_output``) as float arrays; else ``ValueError`` naming what does not fit."""
    M = np.asarray(M, dtype=float)
    y = np.asarray(y, dtype=float)
    if M.ndim != 2 or M.shape[0] != M.shape[1]:
        raise ValueError(f"{name} must be a square 2-D {what}, got shape {M.shape}")
    n = M.shape[0]
    if n < 2:
        raise ValueError(f"the LSSVM needs at least 2 samples, got n_samples={n}")
    if y.ndim not in ((1, 2) if multi_output else (1,)) or y.shape[0] != n:
        shapes = f"({n},) or ({n}, k)" if multi_output else f"({n},)"
        raise ValueError(f"y must have shape {shapes} to match {name} of shape {M.shape}, got {y.shape}")
    return M, y


def _check_system(K, y, gamma):
    gamma = check_positive("gamma", gamma)
    K, y = check_square_system(K, y, "K", "kernel matrix", multi_output=True)
    if not np.all(np.isfinite(K)):
        raise ValueError("K contains NaN or infinity")
    if not np.all(np.isfinite(y)):
        raise ValueError("y contains NaN or infinity")
    scale = np.max(np.abs(K)) if K.size else 0.0
    if not np.allclose(K, K.T, rtol=0.0, atol=1e-12 * scale):
        raise ValueError("K must be symmetric")
    return K, y, gamma


def _factor_or_raise(K: np.ndarray, gamma: float, what: str) -> np.ndarray:
    H = h_matrix(K, gamma)
    anorm = one_norm(H)
    U = cholesky_upper(H)
    if U is None:
        raise not_positive_definite(what, "Lower gamma (more regularisation) or use a positive semi-definite kernel.")
    check_condition(condition_estimate(U, anorm), what)
    return U


# --------------------------------------------------------------------------------------------------
# Functional core (used by gyrodrift.learn.tuning and the tests' cross-checks)
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
    IllConditionedError
        ``K + I/gamma`` is not numerically positive definite (message names gamma).
    """
    K, y, gamma = _check_system(K, y, gamma)
    U = _factor_or_raise(K, gamma, f"for gamma={gamma!r}")
    alpha, b, _, _ = solve_factored(U, y)
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
    ValueError, IllConditionedError
        As :func:`lssvr_solve`.
    """
    K, y, gamma = _check_system(K, y, gamma)
    U = _factor_or_raise(K, gamma, f"for gamma={gamma!r}")
    alpha, _, p, s = solve_factored(U, y)
    return loo_from_factor(U, alpha, p, s)
