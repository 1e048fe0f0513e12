"""Least-squares support vector regression as a scikit-learn estimator (:class:`LSSVR`).

The model of Yu et al. (2013) that maps the 12 h navigation latitude and the temperature change to the axial gyro
drift: ``f(x) = sum_i a_i K(x_i, x) + b`` with the dual coefficients ``a`` and the bias ``b`` of the LSSVM's
bordered system, its Cholesky solution, closed-form leave-one-out residuals, the weighted LS-SVM and the refusals
(`gyrodrift.learn.lssvm_system`). Sign convention: a residual is observed minus predicted, ``y - f``.

Predictive scale (the LSSVM read as a Gaussian process with prior covariance ``K``, noise ``1/(gamma w_i)``
and a flat prior on the bias; Rasmussen & Williams 2006, sec. 2.7): the predictive variance of a new
observation at ``x`` (weight 1), in units of the prior variance, is

    v(x)^2 = k(x, x) - k' H^-1 k + (1 - 1'H^-1 k)^2 / s + 1/gamma,     k = K(X_train, x),

and the leave-one-out predictive variance of training sample ``i`` is ``1 / ((H^-1)_ii - p_i^2 / s)``, the
denominator of its LOO residual. ``LSSVR.predictive_scale`` returns ``v``; ``loo_scale_`` the LOO one. Far
from the training inputs ``k -> 0`` and ``v`` grows to its prior value: the interval widens there.

Prediction arithmetic (`LSSVR.predict` through `gyrodrift.learn.expansion`, which the drift model's predictor
shares, and the generated C and Rust of `gyrodrift.export`, operation for operation): the kernel of each support
vector from the coordinate differences summed over the features in order (RBF ``exp(-d2 / (sigma * sigma))`` with
the C library's ``exp`` through ``math.exp``; linear and polynomial: the dot product in feature order, an integer
power by repeated multiplication), then ``b + sum_i a_i K_i`` (+ an offset, the physics estimate of a hybrid model)
accumulated in support-vector order with an error-free transformation (Knuth's TwoSum; the errors summed apart and
added at the end, Ogita, Rump & Oishi 2005 "Sum2"). The result is as accurate as if summed in twice the working
precision and then rounded, so the cancelling terms of a drift near zero lose nothing in the sum; what remains is
the rounding of each term (about ``eps sum_i |a_i K_i|``, the condition of the sum). numpy's own ``exp`` (a SIMD
version on some CPUs) and BLAS's ``K @ a`` (another order, fused multiply-adds) would differ from the generated code
in the last bits (docs/export.md gives the numbers).

Conversions for cross-checks: scikit-learn ``KernelRidge(alpha=1/gamma, kernel="rbf", gamma=1/sigma^2)``
fitted on ``y - b`` has ``dual_coef_ == a``; LS-SVMlab 1.8 ``sig2 = sigma^2 / 2`` (docs/conventions.md).
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from gyrodrift.learn.expansion import KernelExpansion
from gyrodrift.learn.kernels import (
    check_kernel,
    check_matrix_memory,
    check_positive,
    check_sigma,
    kernel_matrix,
)
from gyrodrift.learn.lssvm_system import (
    NonFiniteResultError,
    StoredSolutionError,
    check_condition,
    check_sample_weight,
    cho_solve,
    cholesky_upper,
    condition_estimate,
    h_matrix,
    inverse_diagonal,
    not_positive_definite,
    one_norm,
    solve_factored,
)

try:  # scikit-learn >= 1.6
    from sklearn.utils.validation import validate_data as _validate_data
except ImportError:  # pragma: no cover - older scikit-learn

    def _validate_data(estimator, *args, **kwargs):
        return estimator._validate_data(*args, **kwargs)


__all__ = ["LSSVR"]


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
        raise :class:`~gyrodrift.learn.lssvm_system.IllConditionedError`.

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
        """Fit the LSSVM (weighted with ``sample_weight``: ``H = K + diag(1/(gamma w))``,
        `gyrodrift.learn.lssvm_system`).

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
        H = h_matrix(K, gamma, copy=False, weights=weights)  # K is ours: overwrite it
        anorm = one_norm(H)
        U = cholesky_upper(H)
        if U is None:
            raise not_positive_definite(
                f"for {self._describe()}",
                "Lower gamma (more regularisation), change sigma, or remove duplicated training samples.",
            )
        cond = condition_estimate(U, anorm)
        check_condition(cond, f"for {self._describe()}")
        alpha, intercept, _, _ = solve_factored(U, y)
        p = cho_solve(U, np.ones(n))
        denom = inverse_diagonal(U) - p * p / p.sum()
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
        return self.expansion().predict(X, offset=offset)

    def expansion(self) -> KernelExpansion:
        """The fitted expansion (support vectors, dual coefficients, bias, kernel) that predicts: `predict` and
        `gyrodrift.learn.predictor.DriftPredictor` share its arithmetic."""
        check_is_fitted(self, ("alpha_", "intercept_", "X_fit_"))
        return KernelExpansion(
            self.X_fit_, self.alpha_, self.intercept_, self.gamma, self.sigma, self.kernel, self.degree, self.coef0
        )

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
        X, y = _validate_data(est, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2, copy=True)
        n = X.shape[0]
        w = check_sample_weight(sample_weight, n)
        loo = np.asarray(loo_residuals, dtype=float)
        if loo.shape != (n,) or not np.all(np.isfinite(loo)):
            raise StoredSolutionError(f"the stored solution must hold {n} finite dual coefficients and LOO residuals")
        expansion = KernelExpansion.from_stored_solution(
            X, y, gamma=gamma, sigma=sigma, alpha=alpha, intercept=intercept, sample_weight=w, rtol=rtol
        )
        alpha, b = expansion.alpha_, expansion.intercept_
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
            H = h_matrix(self._kernel(self.X_fit_), float(self.gamma), copy=False, weights=self.sample_weight_)
            self.factor_ = cholesky_upper(H)
            if self.factor_ is None:  # pragma: no cover - from_solution verified a solvable system
                raise not_positive_definite(f"for {self._describe()}", "Refit the model.")
        U = self.factor_
        hk = cho_solve(U, k)
        p = cho_solve(U, np.ones(U.shape[0]))
        s = p.sum()
        var = kxx - np.einsum("ij,ij->j", k, hk) + (1.0 - p @ k) ** 2 / s
        return np.sqrt(np.maximum(var, 0.0) + 1.0 / float(self.gamma))

    def loo_residuals(self) -> np.ndarray:
        """A copy of :attr:`loo_residuals_`, the exact leave-one-out residuals of the fitted model."""
        check_is_fitted(self, ("alpha_", "intercept_", "X_fit_"))
        return np.array(self.loo_residuals_, copy=True)


#: n x n float64 matrices alive at once in ``LSSVR.fit`` (distances, kernel/H, its factor, the inverse factor).
_FIT_MATRICES = 4
