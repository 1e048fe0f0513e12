"""Hyperparameter tuning of an RBF LSSVR (gamma, sigma) by chaos PSO, plain PSO or a log grid.

Objectives (all mean absolute errors in the target's unit, deg/h for drift models):

- ``train_mae``: error on the training points themselves, the paper's fitness (eq. 16). It rewards
  interpolation (large gamma, small sigma) and says nothing about new runs; kept to reproduce the paper.
- ``loo_mae``: closed-form leave-one-out residuals (Cawley & Talbot 2004), the honest default.
- ``kfold_mae``: contiguous, unshuffled folds (runs are in time order; shuffling would leak neighbours).

The search runs in log10 space over both parameters. Every objective evaluation handles the whole swarm at
once and reuses one squared-distance matrix of the (already scaled) inputs; candidates that share one sigma (a
grid's column, particles clipped onto a sigma bound) share one eigendecomposition, kept for the next calls
(``gyrodrift.learn.lssvm_batch.rbf_batch_errors``, ``EigenCache``): a swarm pressing on a sigma bound evaluates the
particles there in O(n^2) each. Their values agree with the per-candidate Cholesky path to about cond(H) eps (1e-12 to
1e-9 relative), so a swarm's trajectory may differ from before only where two candidates tie to that precision.

BLAS threads: :func:`tune_lssvr` runs its thousands of small factorisations with one BLAS thread
(``threadpoolctl``, a dependency of scikit-learn). OpenBLAS's own threads cost more than they give on matrices of
this size, and on a loaded machine they wait for each other: one 10-iteration CPSO run on 200 synthetic runs took
44.6 s with the default threads and 2.05 s with one, measured in the same process on the shared 2-core development
machine (``benchmarks/bench_learning_scale.py`` prints the ratio on any machine). Instead, the candidates of each
swarm evaluation are shared among ``os.cpu_count()`` threads (scipy's LAPACK wrappers release the GIL: a Python
thread keeps counting during their calls; the values do not depend on it). On the loaded development machine this
gained nothing measurable (the process got a fifth of a core); on a quiet 2-core machine it should halve the tuning
time for n > 32 (not measured there).

Snapped sigmas: for more than ``SNAP_MIN_N`` (32) samples, :func:`tune_lssvr` moves every sigma the swarm asks for
onto a log grid anchored at the lower sigma bound (step :func:`sigma_step_for`: 0.01 decade up to 200 samples,
linear to 0.1 decade at 1000) before evaluating it, and reports the snapped sigma as the tuned one (with the fitness
evaluated there; ``settings`` records the step). Each grid point the swarm comes back to is then served by one
cached eigendecomposition (``EigenCache.wants``: from its second visit on; at most ``EIGEN_CACHE_BYTES`` of them),
every gamma of it in O(n^2); at n = 1000 an eigendecomposition costs about 5 Cholesky factorisations, and a CPSO run
of 4030 evaluations decomposes a few dozen grid points. The swarm's trajectory differs from the unsnapped one; the
paper's 22 runs (n <= 32) keep it to the bit (``sigma_step=None`` turns snapping off everywhere). A sigma within
half a step of a bound snaps onto it and is reported on the edge (``on_search_bound``).

Measured by ``python benchmarks/bench_learning_scale.py --sizes 22,200,1000 --tune-sizes 22,200,1000 --exact-max
1000 --no-cli`` (synthetic runs, seed 0, the shared 2-core machine at load 6-9, so CPU seconds are the comparable
figure): n = 200, step 0.01: 2.55 s CPU against 6.21 s unsnapped, tuned LOO MAE 2.666237e-4 against 2.666175e-4
(+2.3e-5 relative); n = 1000, step 0.1: 15.1 s CPU against 198.0 s unsnapped (13.1x), LOO MAE 2.430941e-4 against
2.430574e-4 (+1.5e-4 relative, far below the LOO MAE's own sampling error, of order n^-1/2).
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, field, fields

import numpy as np
from threadpoolctl import threadpool_limits

from gyrodrift.choices import METHODS, OBJECTIVES
from gyrodrift.errors import OptionError
from gyrodrift.learn.cpso import CPSOSettings, CPSOSolver
from gyrodrift.learn.kernels import SIGMA_MAX, SIGMA_MIN, available_memory_bytes, check_matrix_memory, squared_distances
from gyrodrift.learn.lssvm_batch import STACKED_MAX_N, BatchErrors, EigenCache
from gyrodrift.learn.lssvm_system import check_sample_weight, lssvr_solve

DEFAULT_BOUNDS = ((1e-2, 1e5), (1e-3, 1e2))
"""Default search box ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)); sigma in the scaled input units."""


@dataclass(frozen=True)
class TuningOptions:
    """How (gamma, sigma) of an RBF LSSVR are tuned: the options of :func:`tune_lssvr`, declared once (the flat
    parameters of `gyrodrift.learn.learner.TunedLSSVR`, `TUNED_LSSVR_OPTIONS`, and a model file's ``lssvr_params``
    are these names).

    Attributes
    ----------
    objective : {"loo_mae", "train_mae", "kfold_mae"}, default "loo_mae"
        The fitness, a mean absolute error in the target's unit (deg/h for drift models; module docstring).
    method : {"cpso", "pso", "grid"}, default "cpso"
        The paper's chaos PSO, the same swarm with the chaos search off, or a ``grid_size`` x ``grid_size`` log grid.
    bounds : ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)), default ``DEFAULT_BOUNDS``
        The search box, searched in log10 of both; gamma dimensionless, sigma in the scaled input units.
    n_particles, max_iter, w, c1, c2, chaos_steps
        The swarm's size, iterations, inertia, cognitive and social coefficients and chaos steps per iteration
        (:class:`~gyrodrift.learn.cpso.CPSOSettings`, whose defaults are the paper's); ``"pso"`` runs
        ``chaos_steps = 0``, ``"grid"`` none of them.
    grid_size : int, default 40
        Points per axis of the ``"grid"`` method.
    n_folds : int, default 5
        Folds of ``"kfold_mae"`` (contiguous, unshuffled).
    sigma_step : float [decades], "auto" or None, default "auto"
        For more than ``SNAP_MIN_N`` samples the swarm's sigmas are snapped onto a log grid of this step anchored
        at the lower sigma bound (``"auto"``: :func:`sigma_step_for`; None: off; module docstring, "Snapped
        sigmas"); not for ``"grid"`` or ``"kfold_mae"``.
    """

    objective: str = "loo_mae"
    method: str = "cpso"
    bounds: tuple = DEFAULT_BOUNDS
    n_particles: int = CPSOSettings.n_particles
    max_iter: int = CPSOSettings.max_iter
    w: float = CPSOSettings.w
    c1: float = CPSOSettings.c1
    c2: float = CPSOSettings.c2
    chaos_steps: int = CPSOSettings.chaos_steps
    grid_size: int = 40
    n_folds: int = 5
    sigma_step: float | str | None = "auto"

    def swarm(self) -> CPSOSettings:
        """The swarm's settings of ``method`` (``"pso"``: no chaos steps)."""
        steps = self.chaos_steps if self.method == "cpso" else 0
        return CPSOSettings(
            n_particles=self.n_particles, max_iter=self.max_iter, w=self.w, c1=self.c1, c2=self.c2, chaos_steps=steps
        )


TUNED_LSSVR_OPTIONS = tuple(f.name for f in fields(TuningOptions) if f.name != "sigma_step")
"""The `TuningOptions` that `gyrodrift.learn.learner.TunedLSSVR` takes as (flat, scikit-learn) parameters and a model
file keeps; ``sigma_step`` stays at its default there."""

EDGE_FRACTION = 1e-3
"""A tuned value closer to a bound of its search box than this fraction of the box's width, both measured in the
space the tuner searches (log10 of gamma and of sigma), counts as on the edge. The chaos search's last regions are
1e-6 of the width (``gyrodrift.learn.cpso``, ``chaos_radius_end``), so a swarm pressing against a wall ends within about
that of it without landing on it: ``fit --target drift --encoding temp_range`` on a thermal fleet ended at gamma
99999.12 in [1e-2, 1e5], 5.5e-7 of the width from the top, which a relative tolerance of 1e-6 on the value missed.
1e-3 of the default box is a factor 1.016 in gamma and 1.012 in sigma."""


class SearchBoundWarning(UserWarning):
    """A tuned hyperparameter lies on the edge of its search box: the optimum may lie outside it."""


def edge_distance(value: float, low: float, high: float) -> float:
    """Distance of ``value`` from the nearer bound of ``[low, high]`` as a fraction of the width, in log10 space
    (the tuner's search space): 0 on a bound, 0.5 at the geometric centre; negative outside the box."""
    lv, ll, lh = math.log10(value), math.log10(low), math.log10(high)
    return min(lv - ll, lh - lv) / (lh - ll)


def on_search_bound(gamma: float, sigma: float, bounds) -> list[str]:
    """Names of the tuned values (``"gamma"``, ``"sigma"``) within ``EDGE_FRACTION`` of the box width of a bound of
    ``bounds`` (``edge_distance``)."""
    values = {"gamma": float(gamma), "sigma": float(sigma)}
    return [
        name
        for name, (low, high) in zip(values, bounds, strict=False)
        if edge_distance(values[name], float(low), float(high)) <= EDGE_FRACTION
    ]


def search_bound_message(names: list[str], gamma: float, sigma: float, bounds) -> str:
    """The warning for tuned values on the edge of their search box (empty ``names``: no warning, "")."""
    if not names:
        return ""
    values = {"gamma": gamma, "sigma": sigma}
    boxes = dict(zip(("gamma", "sigma"), bounds, strict=False))
    parts = [
        f"{n} = {values[n]:.6g} in [{boxes[n][0]:g}, {boxes[n][1]:g}] "
        f"({edge_distance(values[n], *boxes[n]):.2g} of the box's log10 width from its bound)"
        for n in names
    ]
    return (
        f"tuned value on the edge of its search box: {'; '.join(parts)}; the optimum may lie outside the box, "
        "and the LOO error understates the error on new runs"
    )


@dataclass
class TuningResult:
    """Outcome of a tuning run.

    ``history`` is the best fitness after each iteration (grid: a single value); ``nfev`` counts every
    objective evaluation, chaos-search ones included.
    """

    gamma: float
    sigma: float
    fitness: float
    objective: str
    method: str
    nfev: int
    nit: int
    history: list[float] = field(default_factory=list)
    bounds: tuple = DEFAULT_BOUNDS
    settings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        d = asdict(self)
        d["bounds"] = [list(b) for b in self.bounds]
        return d


def check_bounds(bounds) -> tuple[tuple[float, float], tuple[float, float]]:
    """``((gamma_lo, gamma_hi), (sigma_lo, sigma_hi))`` as floats with ``0 < lo < hi``, finite, and sigma within
    ``[SIGMA_MIN, SIGMA_MAX]`` of :mod:`gyrodrift.learn.kernels`; else :class:`OptionError`."""
    try:
        pairs = tuple(tuple(float(v) for v in b) for b in bounds)
    except (TypeError, ValueError, OverflowError):
        raise OptionError(f"bounds must be ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)), got {bounds!r}") from None
    if (
        len(pairs) != 2
        or any(len(p) != 2 for p in pairs)
        or any(not (0 < lo < hi < np.inf) for lo, hi in pairs)
        or not (SIGMA_MIN <= pairs[1][0] and pairs[1][1] <= SIGMA_MAX)
    ):
        raise OptionError(
            "bounds must be ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)) with 0 < lo < hi finite and sigma within "
            f"[{SIGMA_MIN:.3g}, {SIGMA_MAX:.3g}], got {pairs}"
        )
    return (pairs[0], pairs[1])  # type: ignore[return-value]


def _kfold_errors(sqdist: np.ndarray, y: np.ndarray, gammas, sigmas, n_folds: int, weights=None) -> np.ndarray:
    """Held-out errors y - f(x) of contiguous k-fold CV for each (gamma, sigma): shape (m, n).

    With sample ``weights`` the fold's ``H = K + diag(1/(gamma w))`` (``lssvr_solve`` adds ``I/gamma``, so the
    rest of the diagonal is added to its ``K``)."""
    from sklearn.model_selection import KFold  # here: only this objective needs it (sklearn.metrics comes with it)

    m, n = len(gammas), len(y)
    errors = np.full((m, n), np.inf)
    folds = list(KFold(n_splits=n_folds, shuffle=False).split(np.arange(n)))
    for j, (g, s) in enumerate(zip(gammas, sigmas, strict=False)):
        K = np.exp(-sqdist / (s * s))
        try:
            for train, test in folds:
                Kt = K[np.ix_(train, train)]
                if weights is not None:
                    Kt = Kt + np.diag(1.0 / (g * weights[train]) - 1.0 / g)
                alpha, b = lssvr_solve(Kt, y[train], g)
                errors[j, test] = y[test] - (K[np.ix_(test, train)] @ alpha + b)
        except (np.linalg.LinAlgError, ValueError):
            errors[j] = np.inf
    return errors


EIGEN_CACHE_BYTES = 512 * 2**20
"""Most memory the tuner's cached eigendecompositions may hold (``gyrodrift.learn.lssvm_batch.EigenCache``, 16 n^2
bytes per sigma: 32 sigmas at n = 1000), and never more than half of the memory left beside the candidates."""

SIGMA_STEP_DECADES = 0.01
"""Grid step, in decades, onto which the swarm's sigmas are snapped for ``SNAP_MIN_N`` < n <= 200 samples (a
factor 1.023 in sigma); it grows linearly to ``SIGMA_STEP_MAX`` at 1000 samples (:func:`sigma_step_for`). See the
module docstring ("Snapped sigmas")."""

SIGMA_STEP_MAX = 0.1
"""Coarsest snapping step, in decades (a factor 1.26 in sigma), from n = 1000 samples on."""

SNAP_MIN_N = STACKED_MAX_N
"""Sigmas are snapped only for more training samples than this (the paper's 22 runs keep the swarm of before)."""


def _fit_in_memory(n: int, threads: int) -> tuple[int, int]:
    """``(threads, cache size)`` whose n x n float64 matrices fit in the available memory beside the 4 of one
    candidate: 3 more per extra thread (its H, factor, inverse factor); the cached eigendecompositions (2 each) take
    at most half of what is left, at most ``EIGEN_CACHE_BYTES``, and at least 4 when the memory allows."""
    avail = available_memory_bytes()
    spare = 10**9 if avail is None else avail // (8 * n * n) - 4
    threads = max(1, min(int(threads), 1 + max(spare, 0) // 3))
    left = spare - 3 * (threads - 1)
    budget = max(4, EIGEN_CACHE_BYTES // (16 * n * n))
    return threads, int(max(0, min(budget, left // 2 if left < 16 else left // 4)))


def sigma_step_for(n: int) -> float | None:
    """The default snapping step [decades] for ``n`` training samples: None (no snapping) for n <= ``SNAP_MIN_N``,
    ``SIGMA_STEP_DECADES`` up to 200 samples, linear from there to ``SIGMA_STEP_MAX`` at 1000 and that above. An
    eigendecomposition costs O(n^3) and the swarm comes back to fewer grid points of a coarser grid: at 200 samples
    one costs about 2 Cholesky factorisations and a fine grid is nearly free, at 1000 about 5 and the grid's
    coarseness halves the tuning's cost (module docstring, "Snapped sigmas")."""
    if n <= SNAP_MIN_N:
        return None
    fraction = min(1.0, max(0.0, (n - 200.0) / 800.0))
    return SIGMA_STEP_DECADES + fraction * (SIGMA_STEP_MAX - SIGMA_STEP_DECADES)


def snap_sigmas(sigmas, step_decades: float, low: float, high: float) -> np.ndarray:
    """``sigmas`` moved to the nearest point of the log grid ``low * 10**(k step_decades)``, k = 0, 1, ..., clipped
    to ``[low, high]`` (``high`` itself is a grid point then). Same unit as the sigmas (scaled input units)."""
    s = np.asarray(sigmas, dtype=float)
    k = np.round((np.log10(s) - math.log10(low)) / step_decades)
    return np.clip(low * 10.0 ** (k * step_decades), low, high)


def make_objective(
    X,
    y,
    objective: str = "loo_mae",
    *,
    n_folds: int = 5,
    sample_weight=None,
    threads: int = 1,
    sigma_snap: tuple[float, float, float] | None = None,
):
    """A vectorised objective ``f(params) -> fitness`` for (gamma, sigma) rows of ``params`` (shape (m, 2)).

    ``X`` is the scaled input matrix (n, d), ``y`` the targets (n,). Failed factorisations give +inf. With
    ``sample_weight`` (w_i > 0) the LSSVMs are weighted (``gyrodrift.learn.lssvm_system``) and the fitness is the
    weighted mean absolute error ``sum w_i |e_i| / sum w_i``. ``threads``: the candidates of one call are shared among
    that many threads (``gyrodrift.learn.lssvm_batch.rbf_batch_errors``; the values do not depend on it).
    ``sigma_snap`` = ``(step_decades, low, high)``: every sigma is first moved onto that grid (:func:`snap_sigmas`),
    so the value is the objective at the snapped sigma.
    """
    if objective not in OBJECTIVES:
        raise OptionError(f"unknown objective {objective!r}; expected one of {', '.join(OBJECTIVES)}")
    X = np.asarray(X, float)
    y = np.asarray(y, float)
    if objective == "kfold_mae" and not 2 <= n_folds <= len(y):
        raise OptionError(f"n_folds must be within [2, {len(y)}] for {len(y)} samples, got {n_folds}")
    # distances, one candidate's H, its factor and inverse factor; the stacked path (n <= 32) is small
    check_matrix_memory(len(y), len(y), 4, "tuning the LSSVR", unit="samples")
    threads, cache_size = _fit_in_memory(len(y), threads)
    sqdist = squared_distances(X)
    w = check_sample_weight(sample_weight, len(y))
    # sigmas the swarm asks for again (particles on a sigma bound)
    cache = EigenCache(sqdist, w, size=cache_size) if cache_size else None
    kind = "train" if objective == "train_mae" else "loo"
    batch = None if objective == "kfold_mae" else BatchErrors(sqdist, y, kind, w, threads, cache)

    def fitness(params: np.ndarray) -> np.ndarray:
        params = np.atleast_2d(np.asarray(params, float))
        gammas, sigmas = params[:, 0], params[:, 1]
        if sigma_snap is not None:
            sigmas = snap_sigmas(sigmas, *sigma_snap)
        if batch is None:
            errors = _kfold_errors(sqdist, y, gammas, sigmas, n_folds, w)
        else:
            errors = batch(gammas, sigmas)
        out = np.mean(np.abs(errors), axis=1) if w is None else np.abs(errors) @ w / w.sum()
        return np.where(np.isfinite(out), out, np.inf)

    return fitness


def tune_lssvr(
    X, y, options: TuningOptions | None = None, *, rng=None, callback=None, sample_weight=None
) -> TuningResult:
    """Tune (gamma, sigma) of an RBF LSSVR on scaled inputs ``X`` (n, d) and targets ``y`` (n,) as ``options`` say
    (:class:`TuningOptions`; None: its defaults, the paper's chaos PSO on the LOO MAE).

    ``callback(intermediate_result)`` is passed to the optimiser (called once per iteration); ``rng`` seeds the
    swarm; ``sample_weight`` weights the LSSVMs and the fitness (``make_objective``).
    """
    options = TuningOptions() if options is None else options
    method, objective, bounds, sigma_step = options.method, options.objective, options.bounds, options.sigma_step
    if method not in METHODS:
        raise OptionError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    bounds = check_bounds(bounds)
    if sigma_step == "auto":
        sigma_step = sigma_step_for(len(y))
    elif sigma_step is not None and not (
        isinstance(sigma_step, (int, float)) and not isinstance(sigma_step, bool) and 0 < sigma_step < math.inf
    ):
        raise OptionError(f"sigma_step must be 'auto', a finite number of decades > 0 or None, got {sigma_step!r}")
    threads = os.cpu_count() or 1  # module docstring: "BLAS threads"
    snap = (
        (float(sigma_step), *bounds[1])
        if sigma_step is not None and method != "grid" and objective != "kfold_mae" and len(y) > SNAP_MIN_N
        else None
    )
    fun = make_objective(
        X, y, objective, n_folds=options.n_folds, sample_weight=sample_weight, threads=threads, sigma_snap=snap
    )
    with threadpool_limits(limits=1, user_api="blas"):  # module docstring: "BLAS threads"
        if method == "grid":
            grid_size = options.grid_size
            if grid_size < 2:
                raise OptionError(f"grid_size must be at least 2, got {grid_size}")
            g = np.logspace(np.log10(bounds[0][0]), np.log10(bounds[0][1]), grid_size)
            s = np.logspace(np.log10(bounds[1][0]), np.log10(bounds[1][1]), grid_size)
            gg, ss = np.meshgrid(g, s, indexing="ij")
            params = np.column_stack([gg.ravel(), ss.ravel()])
            values = fun(params)
            best = int(np.argmin(values))
            return TuningResult(
                gamma=float(params[best, 0]),
                sigma=float(params[best, 1]),
                fitness=float(values[best]),
                objective=objective,
                method=method,
                nfev=len(values),
                nit=1,
                history=[float(values[best])],
                bounds=bounds,
                settings={"grid_size": grid_size},
            )
        swarm = options.swarm()
        with CPSOSolver(fun, bounds, swarm, log_scale=True, vectorized=True, rng=rng, callback=callback) as solver:
            res = solver.solve()
        sigma = float(res.x[1]) if snap is None else float(snap_sigmas(res.x[1], *snap))
        settings = {} if snap is None else {"sigma_step_decades": snap[0]}
        return TuningResult(
            gamma=float(res.x[0]),
            sigma=sigma,
            fitness=float(res.fun),
            objective=objective,
            method=method,
            nfev=int(res.nfev),
            nit=int(res.nit),
            history=[float(v) for v in res.history],
            bounds=bounds,
            settings={
                "n_particles": options.n_particles,
                "max_iter": options.max_iter,
                "w": options.w,
                "c1": options.c1,
                "c2": options.c2,
                "chaos_steps": swarm.chaos_steps,
                **settings,
            },
        )
