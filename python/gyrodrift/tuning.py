"""Hyperparameter tuning of an RBF LSSVR (gamma, sigma) by chaos PSO, plain PSO or a log grid.

Objectives (all mean absolute errors in the target's unit, deg/h for drift models):

- ``train_mae``: error on the training points themselves, the paper's fitness (eq. 16). It rewards
  interpolation (large gamma, small sigma) and says nothing about new runs; kept to reproduce the paper.
- ``loo_mae``: closed-form leave-one-out residuals (Cawley & Talbot 2004), the honest default.
- ``kfold_mae``: contiguous, unshuffled folds (runs are in time order; shuffling would leak neighbours).

The search runs in log10 space over both parameters. Every objective evaluation handles the whole swarm at
once and reuses one squared-distance matrix of the (already scaled) inputs.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
from sklearn.model_selection import KFold

from gyrodrift.choices import METHODS, OBJECTIVES
from gyrodrift.cpso import minimize_cpso
from gyrodrift.kernels import squared_distances
from gyrodrift.lssvr import lssvr_solve, rbf_batch_errors

DEFAULT_BOUNDS = ((1e-2, 1e5), (1e-3, 1e2))
"""Default search box ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)); sigma in the scaled input units."""


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


def _kfold_errors(sqdist: np.ndarray, y: np.ndarray, gammas, sigmas, n_folds: int) -> np.ndarray:
    """Held-out errors y - f(x) of contiguous k-fold CV for each (gamma, sigma): shape (m, n)."""
    m, n = len(gammas), len(y)
    errors = np.full((m, n), np.inf)
    folds = list(KFold(n_splits=n_folds, shuffle=False).split(np.arange(n)))
    for j, (g, s) in enumerate(zip(gammas, sigmas, strict=False)):
        K = np.exp(-sqdist / (s * s))
        try:
            for train, test in folds:
                alpha, b = lssvr_solve(K[np.ix_(train, train)], y[train], g)
                errors[j, test] = y[test] - (K[np.ix_(test, train)] @ alpha + b)
        except (np.linalg.LinAlgError, ValueError):
            errors[j] = np.inf
    return errors


def make_objective(X, y, objective: str = "loo_mae", *, n_folds: int = 5):
    """A vectorised objective ``f(params) -> fitness`` for (gamma, sigma) rows of ``params`` (shape (m, 2)).

    ``X`` is the scaled input matrix (n, d), ``y`` the targets (n,). Failed factorisations give +inf.
    """
    if objective not in OBJECTIVES:
        raise ValueError(f"unknown objective {objective!r}; expected one of {', '.join(OBJECTIVES)}")
    X = np.asarray(X, float)
    y = np.asarray(y, float)
    if objective == "kfold_mae" and not 2 <= n_folds <= len(y):
        raise ValueError(f"n_folds must be within [2, {len(y)}] for {len(y)} samples, got {n_folds}")
    sqdist = squared_distances(X)

    def fitness(params: np.ndarray) -> np.ndarray:
        params = np.atleast_2d(np.asarray(params, float))
        gammas, sigmas = params[:, 0], params[:, 1]
        if objective == "kfold_mae":
            errors = _kfold_errors(sqdist, y, gammas, sigmas, n_folds)
        else:
            errors = rbf_batch_errors(sqdist, y, gammas, sigmas, "train" if objective == "train_mae" else "loo")
        out = np.mean(np.abs(errors), axis=1)
        return np.where(np.isfinite(out), out, np.inf)

    return fitness


def tune_lssvr(
    X,
    y,
    *,
    objective: str = "loo_mae",
    method: str = "cpso",
    bounds=DEFAULT_BOUNDS,
    n_particles: int = 30,
    max_iter: int = 100,
    w: float = 0.75,
    c1: float = 2.0,
    c2: float = 2.0,
    chaos_steps: int = 10,
    grid_size: int = 40,
    n_folds: int = 5,
    rng=None,
    callback=None,
) -> TuningResult:
    """Tune (gamma, sigma) of an RBF LSSVR on scaled inputs ``X`` (n, d) and targets ``y`` (n,).

    ``method="cpso"`` is the paper's chaos PSO (defaults: 30 particles, 100 iterations, w 0.75, c1 = c2 = 2,
    10 chaos steps); ``"pso"`` the same swarm with the chaos search off; ``"grid"`` a ``grid_size`` x
    ``grid_size`` log grid over ``bounds``. ``callback(intermediate_result)`` is passed to the optimiser
    (called once per iteration); ``rng`` seeds the swarm.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    bounds = tuple(tuple(float(v) for v in b) for b in bounds)
    if len(bounds) != 2 or any(lo <= 0 or hi <= lo for lo, hi in bounds):
        raise ValueError(f"bounds must be ((gamma_lo, gamma_hi), (sigma_lo, sigma_hi)) with 0 < lo < hi, got {bounds}")
    fun = make_objective(X, y, objective, n_folds=n_folds)
    if method == "grid":
        if grid_size < 2:
            raise ValueError(f"grid_size must be at least 2, got {grid_size}")
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
    steps = chaos_steps if method == "cpso" else 0
    res = minimize_cpso(
        fun,
        bounds,
        n_particles=n_particles,
        max_iter=max_iter,
        w=w,
        c1=c1,
        c2=c2,
        chaos_steps=steps,
        log_scale=True,
        vectorized=True,
        rng=rng,
        callback=callback,
    )
    return TuningResult(
        gamma=float(res.x[0]),
        sigma=float(res.x[1]),
        fitness=float(res.fun),
        objective=objective,
        method=method,
        nfev=int(res.nfev),
        nit=int(res.nit),
        history=[float(v) for v in res.history],
        bounds=bounds,
        settings={"n_particles": n_particles, "max_iter": max_iter, "w": w, "c1": c1, "c2": c2, "chaos_steps": steps},
    )
