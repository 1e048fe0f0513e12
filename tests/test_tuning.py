"""Tuning objectives against brute-force refits, and the tuners' contracts."""

import numpy as np
import pytest

from gyrodrift.lssvr import LSSVR
from gyrodrift.tuning import make_objective, tune_lssvr


@pytest.fixture
def data():
    rng = np.random.default_rng(3)
    X = rng.uniform(-1, 1, size=(18, 2))
    y = np.sin(2 * X[:, 0]) + 0.3 * X[:, 1] + 0.05 * rng.standard_normal(18)
    return X, y


def _brute(X, y, gamma, sigma, objective, n_folds=5):
    n = len(y)
    if objective == "train_mae":
        return np.mean(np.abs(y - LSSVR(gamma=gamma, sigma=sigma).fit(X, y).predict(X)))
    if objective == "loo_mae":
        folds = [[i] for i in range(n)]
    else:  # contiguous, unshuffled folds of sizes differing by at most one
        sizes = np.full(n_folds, n // n_folds)
        sizes[: n % n_folds] += 1
        edges = np.r_[0, np.cumsum(sizes)]
        folds = [list(range(edges[k], edges[k + 1])) for k in range(n_folds)]
    errs = np.empty(n)
    for test in folds:
        train = np.setdiff1d(np.arange(n), test)
        errs[test] = y[test] - LSSVR(gamma=gamma, sigma=sigma).fit(X[train], y[train]).predict(X[test])
    return np.mean(np.abs(errs))


@pytest.mark.parametrize("objective", ["train_mae", "loo_mae", "kfold_mae"])
def test_objectives_equal_brute_force_refits(data, objective):
    X, y = data
    params = np.array([[0.5, 0.3], [10.0, 1.0], [300.0, 2.5]])
    got = make_objective(X, y, objective)(params)
    want = [_brute(X, y, g, s, objective) for g, s in params]
    np.testing.assert_allclose(got, want, rtol=1e-7)


def test_unknown_objective_and_method(data):
    X, y = data
    with pytest.raises(ValueError, match="unknown objective 'mse'"):
        make_objective(X, y, "mse")
    with pytest.raises(ValueError, match="unknown method 'annealing'"):
        tune_lssvr(X, y, method="annealing")
    with pytest.raises(ValueError, match="bounds must be"):
        tune_lssvr(X, y, bounds=((0.0, 1.0), (1.0, 2.0)))
    with pytest.raises(ValueError, match="n_folds must be within"):
        make_objective(X, y, "kfold_mae", n_folds=1)


@pytest.mark.parametrize("method", ["cpso", "pso", "grid"])
def test_tuners_return_their_best_point_inside_bounds(data, method):
    X, y = data
    bounds = ((1e-1, 1e4), (1e-2, 1e1))
    res = tune_lssvr(X, y, method=method, bounds=bounds, max_iter=15, n_particles=10, grid_size=12, rng=1)
    assert bounds[0][0] <= res.gamma <= bounds[0][1] and bounds[1][0] <= res.sigma <= bounds[1][1]
    # The reported fitness is the objective at the reported point.
    assert res.fitness == pytest.approx(_brute(X, y, res.gamma, res.sigma, "loo_mae"), rel=1e-7)
    assert np.all(np.diff(res.history) <= 0)
    if method == "grid":
        assert res.nfev == 144
    # Tuned LOO beats a poor fixed choice on this smooth problem.
    assert res.fitness < _brute(X, y, 0.1, 0.01, "loo_mae")


def test_cpso_tuning_is_reproducible(data):
    X, y = data
    a = tune_lssvr(X, y, max_iter=10, n_particles=8, rng=7)
    b = tune_lssvr(X, y, max_iter=10, n_particles=8, rng=7)
    assert (a.gamma, a.sigma, a.fitness, a.nfev) == (b.gamma, b.sigma, b.fitness, b.nfev)


def test_train_mae_rewards_interpolation(data):
    # The paper's fitness keeps falling as gamma grows and sigma shrinks: why LOO is the default.
    X, y = data
    f = make_objective(X, y, "train_mae")
    vals = f(np.array([[1.0, 1.0], [1e3, 0.3], [1e5, 0.05]]))
    assert vals[0] > vals[1] > vals[2]
