"""Errors of many RBF LSSVMs (one per (gamma, sigma) candidate) on one training set at once: the tuner's objective.

:func:`rbf_batch_errors` stacks small problems (n <= 32) and loops over larger ones with LAPACK; candidates that
share one sigma come from one eigendecomposition (:class:`RBFEigenSystem`, every gamma in O(n^2)), kept across
calls in an :class:`EigenCache`. The system, its closed-form leave-one-out residuals and its refusals are those of
`gyrodrift.learn.lssvm_system`; residuals are observed minus predicted, in the unit of ``y`` (deg/h for drifts).
"""

from __future__ import annotations

import math
import operator
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.linalg import lapack

from gyrodrift.learn.kernels import check_sigma, rbf_from_squared_distances
from gyrodrift.learn.lssvm_system import (
    COND_REFUSE,
    check_sample_weight,
    check_square_system,
    cho_solve,
    cholesky_upper,
    condition_estimate,
    loo_from_factor,
    one_norm,
)

__all__ = ["EIG_MIN_GROUP", "STACKED_MAX_N", "BatchErrors", "EigenCache", "RBFEigenSystem", "rbf_batch_errors"]


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
        Sample weights of a weighted LS-SVM (`gyrodrift.learn.lssvm_system`): ``H = K + diag(1/(gamma w))``.
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
    Two implementations, chosen by n (the measurements behind the choice: docs/studies/2026-11-27-learning-speed.md,
    "rbf_batch_errors: the two implementations, measured"):

    * n <= 32 (the paper has n = 22): the candidates' kernels, products and reductions are computed on
      one (m, n, n) stack, which removes the per-candidate Python overhead of the public functions (their
      validation and copies), dominant at this size; each ``H^-1`` comes from LAPACK ``dpotrf`` and
      ``dpotri`` on its slice of the stack, in place (a non-PD candidate is flagged alone), and the condition
      number is the exact 1-norm one of the stack.
    * n > 32: a Python loop over candidates calling LAPACK ``dpotrf``/``dpotrs`` (and ``dtrtri`` for
      "loo") directly, with ``dpocon`` for the condition number. numpy's stacked routines have no triangular
      solve or inverse, so a stack would need a general inverse of each factor, several times slower than
      ``dtrtri``/``dpotrs`` at n >= 100, and m*n*n memory. Building each kernel from ``sqdist`` in place of
      calling the public functions saves their validation (symmetry check, copies).
    """
    return BatchErrors(sqdist, y, kind, weights, threads, cache)(gammas, sigmas)


class BatchErrors:
    """`rbf_batch_errors` on one training set, its inputs checked once: ``BatchErrors(sqdist, y, kind, weights,
    threads, cache)(gammas, sigmas)`` is ``rbf_batch_errors(sqdist, y, gammas, sigmas, kind, weights, threads,
    cache)`` (the same rows, the same errors for bad input). The tuner's objective calls it twice per swarm
    iteration; checking the n x n distances, the targets and the weights on every call was a fifth of a
    paper-size call."""

    def __init__(self, sqdist, y, kind: str = "train", weights=None, threads: int = 1, cache=None) -> None:
        if kind not in ("train", "loo"):
            raise ValueError(f"kind must be 'train' or 'loo', got {kind!r}")
        D, y = check_square_system(sqdist, y, "sqdist", "matrix", multi_output=False)
        if not (np.all(np.isfinite(D)) and np.all(D >= 0.0)):
            raise ValueError("sqdist must be finite and non-negative")
        if not np.all(np.isfinite(y)):
            raise ValueError("y contains NaN or infinity")
        self.D, self.y, self.kind = D, y, kind
        self.w = check_sample_weight(weights, D.shape[0])
        self.threads = _check_threads(threads)
        self.cache = cache

    def __call__(self, gammas, sigmas) -> np.ndarray:
        """The (m, n) errors of the candidates (``rbf_batch_errors``'s Returns)."""
        g, sg = np.broadcast_arrays(np.asarray(gammas, dtype=float), np.asarray(sigmas, dtype=float))
        g, sg = g.ravel(), sg.ravel()
        for name, values in (("gammas", g), ("sigmas", sg)):
            bad = np.flatnonzero(~(np.isfinite(values) & (values > 0.0)))
            if bad.size:
                raise ValueError(f"{name}[{bad[0]}] must be a finite number > 0, got {float(values[bad[0]])!r}")
        D, y, kind, w, cache = self.D, self.y, self.kind, self.w, self.cache
        if D.shape[0] <= STACKED_MAX_N:
            return _rbf_batch_stacked(D, y, g, sg, kind, w)
        if cache is not None and not cache.serves(D, w):
            raise ValueError("cache belongs to another training set (EigenCache(sqdist, weights) of these)")
        return _rbf_batch_loop(D, y, g, sg, kind, w, self.threads, cache)


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
STACKED_MAX_N = 32


def _rbf_batch_stacked(D, y, g, sg, kind, w=None):
    """All candidates on one (m, n, n) stack: the kernels, the products and the reductions in numpy on the whole
    stack, each ``H^-1`` by LAPACK ``dpotrf`` + ``dpotri`` (the inverse from the Cholesky factor, in place: about 10 us
    a candidate at n = 22, where numpy's stacked ``cholesky`` and ``inv`` of the factor took twice that; see
    `rbf_batch_errors`' Notes). A candidate that is not positive definite gets a row of +inf."""
    n, m = D.shape[0], g.size
    H = rbf_from_squared_distances(D, sg[:, None, None])
    diag = np.arange(n)
    H[:, diag, diag] += 1.0 / g[:, None] if w is None else 1.0 / (g[:, None] * w[None, :])
    anorm = np.abs(H).sum(axis=1).max(axis=1)  # ||H||_1 (H symmetric)
    pd = np.ones(m, dtype=bool)
    for j in range(m):
        # H[j].T (= H[j]) is Fortran-ordered: LAPACK works in place, the upper triangle of H[j] ends up holding H^-1's
        U, info = lapack.dpotrf(H[j].T, lower=1, clean=0, overwrite_a=1)
        if info == 0:
            _, info = lapack.dpotri(U, lower=1, overwrite_c=1)
        pd[j] = info == 0
    upper, lower = np.triu_indices(n, 1)
    Hinv = H
    Hinv[:, lower, upper] = Hinv[:, upper, lower]  # the whole symmetric H^-1
    Hinv[~pd] = 0.0  # rows refused below
    pq = Hinv @ np.column_stack([np.ones(n), y])
    p, q = pq[:, :, 0], pq[:, :, 1]
    s = p.sum(axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = q - (q.sum(axis=1, keepdims=True) / s) * p
        if kind == "train":
            out = alpha / g[:, None] if w is None else alpha / (g[:, None] * w[None, :])
        else:
            out = alpha / (Hinv[:, diag, diag] - p * p / s)
    # The exact 1-norm condition number (>= the dpocon estimate LSSVR.fit uses, so a candidate kept here is never
    # refused by the final fit), from the inverse at hand.
    cond = anorm * np.abs(Hinv).sum(axis=1).max(axis=1)
    out[~(pd & (cond < COND_REFUSE))] = np.inf
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
        anorm = one_norm(H)
        U = cholesky_upper(H)
        if U is None or not condition_estimate(U, anorm) < COND_REFUSE:  # as LSSVR.fit refuses it
            out[j] = np.inf
            return
        pq = cho_solve(U, B)
        p, q = pq[:, 0], pq[:, 1]
        s = p.sum()
        alpha = q - (q.sum() / s) * p
        if kind == "train":
            out[j] = alpha / g[j] if w is None else alpha / (g[j] * w)
        else:
            out[j] = loo_from_factor(U, alpha, p, s)

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
    residuals of `gyrodrift.learn.lssvm_system`) cost O(n^2) per gamma (matrix products when several gammas are asked at
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
