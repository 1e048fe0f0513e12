"""The predictive spread of a drift model: a Gaussian process whose length scales are fitted to the runs.

The drift model's point estimate is the LSSVR's (`gyrodrift.learn.drift_model`); its interval needs, for every run, how
far that estimate may be from the run's drift. `SpreadGP` models the LSSVR's target (the drift, or a hybrid's
label minus physics) over the model's scaled inputs as a Gaussian process (the likelihood, its search and the
prediction computed here as scikit-learn's ``GaussianProcessRegressor`` computes them for ``_kernel``'s kernel)::

    y_i = b + beta'z_i + g(z_i) + u_i + n_i,
    b ~ N(0, c0), beta ~ N(0, sd(y)^2 I), g ~ GP(0, c1 RBF(l_1 .. l_d)), u_i ~ N(0, tau^2), n_i ~ N(0, s_i^2)

on the inputs standardised by the GP itself (z; so its bounds hold whatever the model's scaling), with a
constant ``b`` (the LSSVR's unregularised bias), a linear trend ``beta`` whose prior is one standard deviation
of the target per standard deviation of each input (fixed, ``DotProduct``: its posterior is learnt from the
runs, and its uncertainty grows linearly with the distance from them, which is what makes an extrapolation
wider even where the RBF part found an input irrelevant), one RBF length scale per input (ARD), ``u`` the
run-to-run variation the inputs do not explain (a ``WhiteKernel``) and ``n`` the label noise, whose 1-sigma
``s_i`` is known (``drift_std_deg_h``, passed as the GP's ``alpha``; zero when the table has none, then ``tau``
absorbs it). The hyperparameters (c0, c1, l, tau) are fitted by maximising the marginal likelihood (ML-II,
L-BFGS from one start and ``n_restarts`` random ones, seeded).

What it gives (unit of y, deg/h):

* ``predict_std(Z)``: the predictive standard deviation of a new run's drift, without label noise,
  ``sqrt(var(b + beta'z + g(z)) + tau^2)``. Far from the training inputs (on the scale of the fitted length
  scales, not of a tuned kernel width) ``g`` reverts to its prior and the trend's uncertainty grows with the
  distance;
* ``loo_std_``: the leave-one-out predictive standard deviation of each training label, noise included,
  ``1 / sqrt((K_y^-1)_ii)`` with ``K_y = K + diag(tau^2 + s_i^2)`` (Rasmussen & Williams 2006, eq. 5.12);
* ``prior_std()``: the 1-sigma of the learned term before any run, anywhere in the training runs' range
  (``sqrt(c0 + c1 + tau^2 + max_i |z_i|^2)``, the trend's prior at the training input farthest from their
  mean): what the learned term may be when nothing is known about it, the cap of the learner's share of the
  interval far from the runs (`gyrodrift.learn.interval.DriftInterval`);
* ``predict_mean(Z)``: the predictive mean (the model compares it with the LSSVR's prediction).

The calibration of the interval (`calibration_scale`, used by the model): the scores ``z_i`` (each training run's
out-of-sample residual over its predicted 1-sigma) give a scale ``c``, the interval's half-width is
``t_{nu}((1 + coverage)/2) c`` times a run's 1-sigma (Student-t with ``nu = n_used - 1`` degrees of freedom:
the prediction interval of one more score when ``c`` is estimated from ``n_used`` of them). ``c`` is a
robust root mean square:

1. *wild scores* are found by a leave-one-out test: the largest ``|z_i|`` against the rms of the others is,
   for normal scores, Student-t with ``m - 1`` degrees of freedom (``m`` scores left); it is flagged when its
   two-sided p-value is below ``OUTLIER_ALPHA / m`` (Bonferroni: a fleet of well-behaved scores loses one with
   probability <= 5 %), and the test repeats on the rest, at most ``n // 4`` times. Flagged scores are left out
   of the scale (the model names their runs in a warning);
2. the rest give Huber's scale (proposal 2 with the location known, 0; ``HUBER_K`` = 2): the ``c`` that solves
   ``mean(min(z_i^2 / c^2, k^2)) = E[min(Z^2, k^2)]`` for standard normal ``Z`` (consistent: ``c`` = 1 for
   unit-normal scores), so a score that is large but not flagged counts as at most ``k c``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from gyrodrift.errors import InputError
from gyrodrift.learn.kernels import check_matrix_memory

__all__ = ["SpreadGP", "LENGTH_SCALE_BOUNDS", "CalibrationScale", "calibration_scale", "OUTLIER_ALPHA", "HUBER_K"]

LENGTH_SCALE_BOUNDS = (0.3, 1e3)
"""Bounds of the RBF length scales [standard deviations of the training inputs]. Below 0.3 a length scale is
shorter than the spacing of a few dozen runs and the likelihood rewards interpolating single runs (measured on
the identification study's fleets: lengths of 0.02 made every new run an extrapolation); above 1e3 an input
does not matter."""

_AMPLITUDE_BOUNDS = (1e-4, 1e4)
_NOISE_BOUNDS = (1e-6, 1e1)
_JITTER = 1e-10


def _kernel(n_inputs: int):
    """The same covariance as scikit-learn's kernel, with the same start and bounds (for tests and benchmarks that
    compare with ``GaussianProcessRegressor``; `SpreadGP` does not import scikit-learn's GP: ~0.1 s of a start)."""
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, DotProduct, WhiteKernel

    return (
        ConstantKernel(1.0, _AMPLITUDE_BOUNDS)
        + ConstantKernel(1.0, _AMPLITUDE_BOUNDS) * RBF(np.ones(n_inputs), LENGTH_SCALE_BOUNDS)
        + WhiteKernel(0.1, _NOISE_BOUNDS)
        + ConstantKernel(1.0, "fixed") * DotProduct(0.0, "fixed")
    )


def _start_and_bounds(n_inputs: int) -> tuple[np.ndarray, np.ndarray]:
    """The likelihood search's start and bounds, log hyperparameters (log c0, log c1, log l_1 .. l_d, log tau^2):
    c0 = c1 = 1, l = 1, tau^2 = 0.1 (the order and values of `_kernel`'s ``theta`` and ``bounds``)."""
    start = np.log(np.r_[1.0, 1.0, np.ones(n_inputs), 0.1])
    bounds = np.log(np.array([_AMPLITUDE_BOUNDS, _AMPLITUDE_BOUNDS, *[LENGTH_SCALE_BOUNDS] * n_inputs, _NOISE_BOUNDS]))
    return start, bounds


def _neg_log_likelihood(theta: np.ndarray, Z: np.ndarray, sqd: np.ndarray, y: np.ndarray, noise: np.ndarray):
    """Minus the log marginal likelihood of ``_kernel``'s GP and its gradient in ``theta`` (log c0, log c1, log
    l_1 .. l_d, log tau^2), what scikit-learn's ``GaussianProcessRegressor.log_marginal_likelihood`` computes
    (R&W 2006 eqs. 2.30, 5.9) without its per-call kernel bookkeeping. ``sqd`` (d, n, n): squared differences of
    each input; ``noise``: the diagonal added (``alpha``). +inf and a zero gradient where K is not positive
    definite, as scikit-learn."""
    from scipy.linalg import cho_solve, cholesky  # here (and below): scipy.linalg costs ~0.4 s of a CLI start

    c0, c1, tau2 = math.exp(theta[0]), math.exp(theta[1]), math.exp(theta[-1])
    inv_l2 = np.exp(-2.0 * theta[2:-1])
    scaled = sqd * inv_l2[:, None, None]
    R = np.exp(-0.5 * scaled.sum(axis=0))
    K = c0 + c1 * R + Z @ Z.T
    n = len(y)
    K[np.diag_indices(n)] += tau2 + noise
    try:
        L = cholesky(K, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        return np.inf, np.zeros_like(theta)
    a = cho_solve((L, True), y, check_finite=False)
    lml = -0.5 * float(y @ a) - float(np.log(np.diag(L)).sum()) - 0.5 * n * math.log(2.0 * math.pi)
    W = np.outer(a, a) - cho_solve((L, True), np.eye(n), check_finite=False)
    WR = W * R
    grad = np.empty_like(theta)
    grad[0] = c0 * W.sum()
    grad[1] = c1 * WR.sum()
    grad[2:-1] = c1 * np.einsum("ij,kij->k", WR, scaled)
    grad[-1] = tau2 * np.trace(W)
    return -lml, -0.5 * grad


def _cross_kernel(theta: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``_kernel``'s covariance between the rows of ``A`` and ``B`` (standardised inputs) at log hyperparameters
    ``theta``, without the run-to-run term (``WhiteKernel``: on the diagonal of the training covariance only):
    ``c0 + c1 exp(-|a - b|^2_l / 2) + a'b``, the distances as scikit-learn's RBF takes them (of the inputs over their
    length scales: `scaled_squared_distances`)."""
    c0, c1 = math.exp(theta[0]), math.exp(theta[1])
    length = np.exp(theta[2:-1])
    return c0 + c1 * np.exp(-0.5 * scaled_squared_distances(A / length, B / length)) + A @ B.T


def scaled_squared_distances(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``D[i, j] = |A[i] - B[j]|^2``, the squared coordinate differences added feature by feature in order: the
    operations of ``scipy.spatial.distance.cdist(A, B, "sqeuclidean")`` (the same floats, tested), without its
    import (scipy.spatial: ~0.3 s of a start that predicts with an interval)."""
    out = np.zeros((A.shape[0], B.shape[0]))
    for k in range(A.shape[1]):
        diff = A[:, k, None] - B[None, :, k]
        out += diff * diff
    return out


def _maximise_likelihood(Z: np.ndarray, y: np.ndarray, noise: np.ndarray, n_restarts: int, seed: int):
    """ML-II log hyperparameters (`_start_and_bounds`) on standardised inputs ``Z`` and targets ``y``: L-BFGS-B
    from `_start_and_bounds`'s start and ``n_restarts`` uniform draws in the log bounds, the best kept, as
    scikit-learn's ``GaussianProcessRegressor.fit`` with ``fmin_l_bfgs_b`` does (same start, bounds, draws and
    optimiser defaults) on `_neg_log_likelihood`, 20-30x faster on a few dozen runs."""
    from scipy.optimize import minimize  # here: a model file's spread needs no search (scipy.optimize: ~0.1 s)

    sqd = (Z.T[:, :, None] - Z.T[:, None, :]) ** 2
    start, bounds = _start_and_bounds(Z.shape[1])
    starts = [start]
    rng = np.random.RandomState(seed)
    starts += [rng.uniform(bounds[:, 0], bounds[:, 1]) for _ in range(n_restarts)]
    results = [
        minimize(_neg_log_likelihood, start, args=(Z, sqd, y, noise), method="L-BFGS-B", jac=True, bounds=bounds)
        for start in starts
    ]
    return np.asarray(results[int(np.argmin([res.fun for res in results]))].x, float)


class SpreadGP:
    """A Gaussian process fitted for its predictive spread (module docstring).

    Parameters
    ----------
    theta : array_like or None
        Keyword-only, as all the parameters. Log hyperparameters of a previous fit (``theta_``): used as they
        are, nothing is optimised (how a saved model is rebuilt). None: fitted by ML-II.
    n_restarts : int
        Random restarts of the likelihood optimiser (seeded by ``random_state``).
    random_state : int

    Attributes
    ----------
    theta_ : ndarray
        Set by ``fit``, as the attributes below. The fitted log hyperparameters (log c0, log c1, log l_1 .. l_d,
        log tau^2).
    L_, alpha_ : ndarray
        Lower Cholesky factor of the training covariance (noise included) and its solve with the standardised
        targets: the predictive mean and variance (R&W 2006 algorithm 2.1) without scikit-learn's
        ``GaussianProcessRegressor`` (whose fit computes the likelihood again: a second factorisation). With
        ``theta`` given and ``loo=False`` (a model file's) they are computed on the first prediction: loading a
        model to export it never factorises the n x n covariance.
    loo_std_ : ndarray, shape (n_runs,)
        Leave-one-out predictive 1-sigma of each training label, label noise included [unit of y].
    """

    def __init__(self, *, theta=None, n_restarts: int = 0, random_state: int = 0) -> None:
        self.theta = theta
        self.n_restarts = n_restarts
        self.random_state = random_state

    def fit(self, Z, y, label_std=None, *, loo: bool = True) -> SpreadGP:
        """Fit on inputs ``Z`` (n_runs, n_inputs), targets ``y`` (n_runs,) and label 1-sigmas ``label_std``
        (n_runs,; same unit as y; None or NaN: unknown, taken as 0). ``loo=False`` skips ``loo_std_`` (an
        n x n inverse: not needed when the calibration is given, as on loading a model file)."""
        from scipy.linalg import cho_solve

        Z = np.asarray(Z, float)
        y = np.asarray(y, float)
        n = len(y)
        if Z.ndim != 2 or Z.shape[0] != n or n < 3:
            raise InputError(f"the spread model needs at least 3 runs with inputs, got Z {Z.shape}, y {y.shape}")
        check_matrix_memory(n, n, 4, "fitting the interval's Gaussian process", unit="runs")
        s = np.zeros(n) if label_std is None else np.nan_to_num(np.asarray(label_std, float), nan=0.0)
        self.z_mean_ = Z.mean(axis=0)
        z_scale = Z.std(axis=0)
        self.z_scale_ = np.where(z_scale > 0, z_scale, 1.0)
        self.y_mean_ = float(y.mean())
        self.y_scale_ = float(y.std()) or float(np.max(s)) or 1.0
        alpha = (s / self.y_scale_) ** 2 + _JITTER
        Zs, ys = self._z(Z), (y - self.y_mean_) / self.y_scale_
        self.Z_train_ = Zs
        self.n_runs_ = n
        self.z_max_sq_ = float(np.max(np.sum(Zs**2, axis=1)))
        self._labels = (ys, alpha)  # standardised targets and label noise, for `_factorise`
        if self.theta is not None and not loo:  # a model file's: factorised on the first prediction (never by export)
            self.theta_ = np.array(self.theta, float)
            return self
        # one BLAS thread (as `gyrodrift.learn.tuning.tune_lssvr`): the likelihood search's small solves and L-BFGS-B's
        # vector operations waited on OpenBLAS's threads, 2-3x slower on a quiet 2-core machine, 10-50x loaded
        with threadpool_limits(limits=1, user_api="blas"):
            if self.theta is None:
                theta = _maximise_likelihood(Zs, ys, alpha, self.n_restarts, self.random_state)
            else:
                theta = np.asarray(self.theta, float)
            self.theta_ = np.array(theta, float)
            self._factorise()
            if loo:
                inv_diag = np.diag(cho_solve((self.L_, True), np.eye(n), check_finite=False))
        if loo:
            self.loo_std_ = self.y_scale_ / np.sqrt(inv_diag)
        return self

    def _factorise(self) -> None:
        """``L_`` and ``alpha_`` at ``theta_`` (call with the BLAS on one thread, as `fit` does: the same floats)."""
        from scipy.linalg import cho_solve, cholesky

        ys, alpha = self._labels
        K = _cross_kernel(self.theta_, self.Z_train_, self.Z_train_)
        K[np.diag_indices(self.n_runs_)] += math.exp(self.theta_[-1]) + alpha
        self.L_ = cholesky(K, lower=True, check_finite=False)
        self.alpha_ = cho_solve((self.L_, True), ys, check_finite=False)

    def _z(self, Z) -> np.ndarray:
        return (np.asarray(Z, float) - self.z_mean_) / self.z_scale_

    def predict_std(self, Z) -> np.ndarray:
        """Predictive 1-sigma of a new run's drift at each row of ``Z`` [unit of y], label noise excluded
        (the run-to-run variation ``tau`` included)."""
        from scipy.linalg import solve_triangular

        Z = np.asarray(Z, float)
        check_matrix_memory(len(Z), self.n_runs_, 3, "the interval's Gaussian process", unit="runs")
        Zs = self._z(Z)
        c0, c1, tau2 = np.exp(self.theta_[[0, 1, -1]])
        with threadpool_limits(limits=1, user_api="blas"):
            if not hasattr(self, "L_"):
                self._factorise()
            V = solve_triangular(self.L_, _cross_kernel(self.theta_, self.Z_train_, Zs), lower=True, check_finite=False)
        var = c0 + c1 + tau2 + np.sum(Zs**2, axis=1) - np.sum(V**2, axis=0)  # the prior includes tau^2
        return self.y_scale_ * np.sqrt(np.maximum(var, 0.0))

    def prior_std(self) -> float:
        """The learned term's 1-sigma before any run, anywhere in the training runs' range [unit of y]: the
        constant, the RBF part, the run-to-run term and the linear trend at the training input farthest from their
        mean, ``y_scale sqrt(c0 + c1 + tau^2 + max_i |z_i|^2)`` (module docstring)."""
        c0, c1, tau2 = (float(v) for v in np.exp(self.theta_[[0, 1, -1]]))
        return self.y_scale_ * math.sqrt(c0 + c1 + tau2 + self.z_max_sq_)

    def predict_mean(self, Z) -> np.ndarray:
        """The Gaussian process's predictive mean of the target at each row of ``Z`` [unit of y]."""
        if not hasattr(self, "alpha_"):
            with threadpool_limits(limits=1, user_api="blas"):
                self._factorise()
        mean = _cross_kernel(self.theta_, self._z(Z), self.Z_train_) @ self.alpha_
        return self.y_mean_ + self.y_scale_ * mean

    def length_scales(self) -> np.ndarray:
        """The fitted RBF length scales [standard deviations of each training input]."""
        return np.exp(self.theta_[2:-1])

    def describe(self) -> str:
        """The fitted kernel in words (for reports)."""
        tau = self.y_scale_ * math.exp(0.5 * self.theta_[-1])
        return (
            f"RBF length scales {', '.join(f'{v:.3g}' for v in self.length_scales())} (input standard deviations), "
            f"unexplained run-to-run 1-sigma {tau:.2e} deg/h"
        )


OUTLIER_ALPHA = 0.05
"""Family-wise level of the wild-score test of `calibration_scale` (module docstring)."""
HUBER_K = 2.0
"""Huber's constant of `calibration_scale`'s scale (in units of the scale)."""


def _huber_beta() -> float:
    """``E[min(Z^2, k^2)]`` for standard normal Z (k = `HUBER_K`): Huber's scale is consistent at the normal. The
    normal cdf, pdf and sf as `scipy.stats.norm` computes them, from `scipy.special` (imported here: scipy.special
    costs ~0.2 s and scipy.stats ~1 s of a start that only predicts)."""
    from scipy.special import ndtr

    k = HUBER_K
    return float((2 * ndtr(k) - 1) - 2 * k * math.exp(-(k**2) / 2.0) / math.sqrt(2.0 * math.pi) + 2 * k**2 * ndtr(-k))


@dataclass(frozen=True)
class CalibrationScale:
    """The calibration of an interval from ``n`` out-of-sample scores (`calibration_scale`).

    Attributes
    ----------
    scale : float
        ``c``: Huber's scale of the kept scores times ``inflation`` (dimensionless).
    kept : ndarray of bool, shape (n,)
        False for the wild scores left out.
    inflation : float
        The factor applied for the optimism of the scores (1: none).
    raw_rms : float
        The plain rms of all scores (for reports: what one wild score does to it).
    """

    scale: float
    kept: np.ndarray
    inflation: float
    raw_rms: float

    @property
    def n_used(self) -> int:
        """How many scores the scale rests on."""
        return int(np.sum(self.kept))

    @property
    def wild(self) -> np.ndarray:
        """Indices of the wild scores left out."""
        return np.flatnonzero(~self.kept)

    def multiplier(self, coverage: float) -> float:
        """Half-width of the interval in units of a run's 1-sigma: ``t_{n_used - 1}((1 + coverage)/2) c``."""
        from scipy.special import stdtrit  # the Student-t quantile, scipy.stats.t.ppf's

        return float(stdtrit(self.n_used - 1, 0.5 + coverage / 2.0) * self.scale)


def _huber_scale(z: np.ndarray) -> float:
    """Huber's proposal-2 scale of ``z`` about 0 (module docstring), by fixed-point iteration from the rms."""
    z2 = z**2
    beta = _huber_beta()
    c2 = float(np.mean(z2))
    if c2 == 0.0:
        return 0.0
    for _ in range(200):
        new = float(np.mean(np.minimum(z2, HUBER_K**2 * c2)) / beta)
        if abs(new - c2) <= 1e-12 * c2:
            c2 = new
            break
        c2 = new
    return math.sqrt(c2)


def calibration_scale(scores, *, inflation: float = 1.0) -> CalibrationScale:
    """The robust scale of out-of-sample ``scores`` (dimensionless, signed) with wild ones left out (module
    docstring); ``inflation`` multiplies it (the model's correction for tuning on the same residuals). Needs at
    least 3 finite scores."""
    from scipy.special import stdtr

    z = np.asarray(scores, float).ravel()
    if z.size < 3 or not np.all(np.isfinite(z)):
        raise InputError(f"the interval's calibration needs at least 3 finite scores, got {z.size}")
    kept = np.ones(z.size, bool)
    for _ in range(z.size // 4):
        idx = np.flatnonzero(kept)
        m = idx.size
        i = idx[np.argmax(np.abs(z[idx]))]
        others = z[idx[idx != i]]
        rms_others = math.sqrt(float(np.mean(others**2)))
        if rms_others == 0.0:
            break
        p = 2.0 * float(stdtr(m - 1, -abs(z[i]) / rms_others))  # the t survival function (scipy.stats.t.sf's)
        if p >= OUTLIER_ALPHA / m:
            break
        kept[i] = False
    return CalibrationScale(
        scale=_huber_scale(z[kept]) * float(inflation),
        kept=kept,
        inflation=float(inflation),
        raw_rms=math.sqrt(float(np.mean(z**2))),
    )
