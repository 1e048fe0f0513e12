"""Tuning objectives against brute-force refits, and the tuners' contracts."""

import numpy as np
import pytest

from gyrodrift.errors import OptionError
from gyrodrift.learn.lssvr import LSSVR
from gyrodrift.learn.tuning import TuningOptions, make_objective, tune_lssvr


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
        tune_lssvr(X, y, TuningOptions(method="annealing"))
    with pytest.raises(ValueError, match="bounds must be"):
        tune_lssvr(X, y, TuningOptions(bounds=((0.0, 1.0), (1.0, 2.0))))
    with pytest.raises(ValueError, match="n_folds must be within"):
        make_objective(X, y, "kfold_mae", n_folds=1)


@pytest.mark.parametrize("method", ["cpso", "pso", "grid"])
def test_tuners_return_their_best_point_inside_bounds(data, method):
    X, y = data
    bounds = ((1e-1, 1e4), (1e-2, 1e1))
    res = tune_lssvr(
        X, y, TuningOptions(method=method, bounds=bounds, max_iter=15, n_particles=10, grid_size=12), rng=1
    )
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
    a = tune_lssvr(X, y, TuningOptions(max_iter=10, n_particles=8), rng=7)
    b = tune_lssvr(X, y, TuningOptions(max_iter=10, n_particles=8), rng=7)
    assert (a.gamma, a.sigma, a.fitness, a.nfev) == (b.gamma, b.sigma, b.fitness, b.nfev)


def test_train_mae_rewards_interpolation(data):
    # The paper's fitness keeps falling as gamma grows and sigma shrinks: why LOO is the default.
    X, y = data
    f = make_objective(X, y, "train_mae")
    vals = f(np.array([[1.0, 1.0], [1e3, 0.3], [1e5, 0.05]]))
    assert vals[0] > vals[1] > vals[2]


# --- the whole drift model as a scikit-learn pipeline, tuning inside fit ---------------------------------
@pytest.fixture(scope="module")
def paper():
    from gyrodrift.runs.datasets import load_paper

    return load_paper()


def test_tuning_inside_fit_is_the_tuner_then_an_lssvr(paper):
    from sklearn.preprocessing import StandardScaler

    from gyrodrift.learn.drift_model import fit_drift_model
    from gyrodrift.learn.encodings import encode

    model = fit_drift_model(paper.train, method="cpso", max_iter=8, n_particles=6, rng=4)
    Xs = StandardScaler().fit_transform(encode(paper.train, "temp_range"))
    res = tune_lssvr(Xs, paper.train.drift_deg_h, TuningOptions(max_iter=8, n_particles=6), rng=4)
    assert (model.tuning.gamma, model.tuning.sigma, model.tuning.history) == (res.gamma, res.sigma, res.history)
    direct = LSSVR(gamma=res.gamma, sigma=res.sigma).fit(Xs, paper.train.drift_deg_h)
    assert model.lssvr.alpha_.tobytes() == direct.alpha_.tobytes()
    assert model.loo_residuals().tobytes() == direct.loo_residuals_.tobytes()


def test_clone_gives_an_unfitted_twin_that_refits_to_the_same_bits(paper):
    from sklearn.base import clone
    from sklearn.exceptions import NotFittedError

    from gyrodrift.learn.drift_model import DriftModel, make_drift_model

    model = make_drift_model(encoding="temp_span", method="pso", max_iter=6, n_particles=6, random_state=2)
    model.fit(paper.train)
    twin = clone(model)
    assert isinstance(twin, DriftModel) and twin.get_params()["learner__lssvr__random_state"] == 2
    with pytest.raises(NotFittedError):
        twin.predict(paper.test)
    twin.fit(paper.train)
    assert twin.predict(paper.test).tobytes() == model.predict(paper.test).tobytes()


def test_cross_val_score_on_the_whole_model_equals_manual_folds(paper):
    from sklearn.model_selection import KFold, cross_val_score

    from gyrodrift.learn.drift_model import fit_drift_model, make_drift_model

    runs, y = paper.train, paper.train.drift_deg_h
    cv = KFold(4)
    scores = cross_val_score(make_drift_model(gamma=30.0, sigma=1.5), runs, y, cv=cv, scoring="neg_mean_absolute_error")
    manual = []
    for train, test in cv.split(np.arange(len(runs))):
        m = fit_drift_model(runs.select(train), gamma=30.0, sigma=1.5)
        manual.append(-np.mean(np.abs(y[test] - m.predict(runs.select(test)))))
    np.testing.assert_array_equal(scores, manual)
    # The structured-array form of the same runs gives the same scores.
    again = cross_val_score(
        make_drift_model(gamma=30.0, sigma=1.5), runs.to_structured(), y, cv=cv, scoring="neg_mean_absolute_error"
    )
    np.testing.assert_array_equal(again, scores)


@pytest.mark.filterwarnings("ignore::gyrodrift.learn.tuning.SearchBoundWarning")
def test_grid_search_over_encoding_scaling_and_objective(paper):
    from sklearn.model_selection import GridSearchCV
    from sklearn.preprocessing import StandardScaler

    from gyrodrift.learn.drift_model import DriftModel, make_drift_model

    grid = {
        "learner__encode__encoding": ["temp_range", "lat_only"],
        "learner__scale": [StandardScaler(), "passthrough"],
        "learner__lssvr__objective": ["loo_mae", "train_mae"],
    }
    search = GridSearchCV(make_drift_model(method="grid", grid_size=6), grid, cv=3, scoring="neg_mean_absolute_error")
    search.fit(paper.train, paper.train.drift_deg_h)
    assert len(search.cv_results_["params"]) == 8
    best = search.best_estimator_
    assert isinstance(best, DriftModel) and best.encoding == search.best_params_["learner__encode__encoding"]
    assert best.training["n_runs"] == 22 and np.all(np.isfinite(best.predict(paper.test)))


def test_estimator_parameters_are_keyword_only():
    from gyrodrift.learn.learner import RunEncoder, TunedLSSVR

    for cls in (LSSVR, TunedLSSVR, RunEncoder):
        with pytest.raises(TypeError):
            cls(1.0)


def test_edge_of_the_search_box_is_warned_and_recorded(paper):
    from gyrodrift.learn.drift_model import make_drift_model
    from gyrodrift.learn.tuning import SearchBoundWarning, on_search_bound

    model = make_drift_model(method="grid", grid_size=5, bounds=((1.0, 2.0), (0.5, 0.6)))
    with pytest.warns(SearchBoundWarning, match=r"gamma = 2 in \[1, 2\]"):
        model.fit(paper.train)
    assert model.learner_.named_steps["lssvr"].on_search_bound_ == on_search_bound(
        model.lssvr.gamma, model.lssvr.sigma, ((1.0, 2.0), (0.5, 0.6))
    )
    assert "gamma" in model.learner_.named_steps["lssvr"].on_search_bound_
    assert model.fit_warnings()[0].startswith("tuned value on the edge of its search box")
    assert on_search_bound(1.5, 0.55, ((1.0, 2.0), (0.5, 0.6))) == []
    assert on_search_bound(1.0 + 1e-7, 0.6, ((1.0, 2.0), (0.5, 0.6))) == ["gamma", "sigma"]


def test_edge_is_measured_in_the_searched_log_space_relative_to_the_box_width():
    """Issue 20: a swarm that pressed against gamma's top ended at 99999.12 in [1e-2, 1e5] (5.5e-7 of the log10
    width away) and was not warned; 1e-3 of the width is the line (a factor 10**0.007 = 1.016 in gamma)."""
    from gyrodrift.learn.tuning import (
        DEFAULT_BOUNDS,
        EDGE_FRACTION,
        edge_distance,
        on_search_bound,
        search_bound_message,
    )

    assert edge_distance(99999.12, 1e-2, 1e5) == pytest.approx(np.log10(1e5 / 99999.12) / 7.0, rel=1e-9)
    assert on_search_bound(99999.12, 1.0, DEFAULT_BOUNDS) == ["gamma"]
    assert "99999.1 in [0.01, 100000] (5.5e-07 of the box's log10 width" in search_bound_message(
        ["gamma"], 99999.12, 1.0, DEFAULT_BOUNDS
    )
    inside = 1e5 / 10 ** (7 * EDGE_FRACTION * 3)  # three times the line inside: not on the edge
    assert on_search_bound(inside, 1.0, DEFAULT_BOUNDS) == []
    near_low = 1e-3 * 10 ** (5 * EDGE_FRACTION / 3)  # a third of the line above sigma's bottom
    assert on_search_bound(10.0, near_low, DEFAULT_BOUNDS) == ["sigma"]
    assert edge_distance(np.sqrt(1e-2 * 1e5), 1e-2, 1e5) == pytest.approx(0.5)


@pytest.mark.filterwarnings("ignore::gyrodrift.learn.tuning.SearchBoundWarning")
def test_tuned_lssvr_passes_scikit_learns_estimator_checks():
    from sklearn.utils.estimator_checks import check_estimator

    from gyrodrift.learn.learner import TunedLSSVR

    for est in (TunedLSSVR(gamma=1.0, sigma=1.0), TunedLSSVR(method="grid", grid_size=3)):
        results = check_estimator(est, on_fail=None)
        failed = [(r["check_name"], str(r["exception"])[:200]) for r in results if r["status"] == "failed"]
        assert len(results) > 40 and failed == []


def test_candidate_threads_and_cached_eigendecompositions_fit_in_the_available_memory(monkeypatch):
    import gyrodrift.learn.tuning as tuning

    n, matrix = 500, 8 * 500 * 500
    monkeypatch.setattr(tuning, "available_memory_bytes", lambda: 100 * matrix)
    # 96 spare matrices, 3 for the second thread: the cache takes a quarter of the 93 left (2 matrices each)
    assert tuning._fit_in_memory(n, 2) == (2, 23)
    monkeypatch.setattr(tuning, "available_memory_bytes", lambda: 7 * matrix)  # one candidate + one thread more
    assert tuning._fit_in_memory(n, 4) == (2, 0)
    monkeypatch.setattr(tuning, "available_memory_bytes", lambda: 6 * matrix)  # one candidate + one cached sigma
    assert tuning._fit_in_memory(n, 4) == (1, 1)
    monkeypatch.setattr(tuning, "available_memory_bytes", lambda: None)  # unknown: as asked, the byte budget
    assert tuning._fit_in_memory(n, 3) == (3, tuning.EIGEN_CACHE_BYTES // (16 * n * n))
    monkeypatch.setattr(tuning, "available_memory_bytes", lambda: 10**12)  # plenty: never past the byte budget
    for n in (40, 200, 1000, 3000):
        threads, size = tuning._fit_in_memory(n, 2)
        assert threads == 2 and 4 <= size and (size == 4 or size * 16 * n * n <= tuning.EIGEN_CACHE_BYTES)


def _smooth_data(n, seed=5):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, size=(n, 2))
    return X, np.sin(2 * X[:, 0]) + 0.3 * X[:, 1] + 0.05 * rng.standard_normal(n)


def test_snapped_sigmas_give_the_exact_objective_at_the_snapped_sigma():
    from gyrodrift.learn.tuning import DEFAULT_BOUNDS, snap_sigmas

    X, y = _smooth_data(60)
    step, (low, high) = 0.05, DEFAULT_BOUNDS[1]
    rng = np.random.default_rng(1)
    # 40 candidates in a narrow sigma band: several share a snapped sigma (eigendecompositions, cached)
    params = np.column_stack([10 ** rng.uniform(-1, 3, 40), 10 ** rng.uniform(-0.3, 0.1, 40)])
    params[:3, 1] = [low, high, 1.5 * low]  # on and beside the bounds
    snapped = snap_sigmas(params[:, 1], step, low, high)
    k = np.log10(snapped / low) / step
    assert np.all(np.abs(k - np.round(k)) < 1e-9) and np.all((low <= snapped) & (snapped <= high))
    assert np.all(np.abs(np.log10(snapped / params[:, 1])) <= step / 2 + 1e-12)
    fun = make_objective(X, y, "loo_mae", sigma_snap=(step, low, high), threads=2)
    first, again = fun(params), fun(params[::-1])[::-1]  # the second call from the cache
    exact = np.array(
        [make_objective(X, y, "loo_mae")(np.array([[g, s]]))[0] for g, s in zip(params[:, 0], snapped, strict=True)]
    )
    assert np.all(np.isfinite(exact))
    np.testing.assert_allclose(first, exact, rtol=1e-8)
    np.testing.assert_allclose(again, exact, rtol=1e-8)


def test_snapping_leaves_small_sets_alone_and_reports_the_snapped_sigma(paper):
    from sklearn.preprocessing import StandardScaler

    from gyrodrift.learn.encodings import encode
    from gyrodrift.learn.tuning import SIGMA_STEP_DECADES, SIGMA_STEP_MAX, SNAP_MIN_N, sigma_step_for, snap_sigmas

    steps = [sigma_step_for(n) for n in range(SNAP_MIN_N + 1, 3000)]
    assert sigma_step_for(SNAP_MIN_N) is None and steps[0] == SIGMA_STEP_DECADES == sigma_step_for(200)
    assert np.all(np.diff(steps) >= 0) and sigma_step_for(1000) == SIGMA_STEP_MAX == steps[-1]

    Xs = StandardScaler().fit_transform(encode(paper.train, "temp_range"))
    y = paper.train.drift_deg_h
    assert len(y) <= SNAP_MIN_N
    before = tune_lssvr(
        Xs, y, TuningOptions(max_iter=15, sigma_step=None), rng=3
    )  # the swarm as before snapping existed
    now = tune_lssvr(Xs, y, TuningOptions(max_iter=15), rng=3)
    assert (now.gamma, now.sigma, now.fitness, now.history) == (
        before.gamma,
        before.sigma,
        before.fitness,
        before.history,
    )
    assert "sigma_step_decades" not in now.settings

    X, y = _smooth_data(SNAP_MIN_N + 8)
    res = tune_lssvr(X, y, TuningOptions(max_iter=15, n_particles=10), rng=3)
    step = res.settings["sigma_step_decades"]
    assert res.sigma == snap_sigmas(res.sigma, step, *res.bounds[1])
    exact = make_objective(X, y, "loo_mae")(np.array([[res.gamma, res.sigma]]))[0]
    assert res.fitness == pytest.approx(exact, rel=1e-8)
    with pytest.raises(OptionError, match="sigma_step must be"):
        tune_lssvr(X, y, TuningOptions(sigma_step=0.0))
