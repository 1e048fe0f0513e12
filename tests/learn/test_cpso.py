"""Chaos PSO (`gyrodrift.learn.cpso.minimize_cpso`): what the optimiser promises, read as a specification."""

import math
import re
import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import Bounds, OptimizeResult

from gyrodrift.learn.cpso import CPSOSettings, CPSOSolver, minimize_cpso
from gyrodrift.learn.swarm import Swarm, chaos_region, logistic_chaos_points, pso_move, reseed_chaos
from gyrodrift.testing import ackley, griewank, rastrigin, rosenbrock, sphere

# (name, function, dimension, bounds, argmin)
PROBLEMS = [
    ("sphere", sphere, 3, [(-5.0, 5.0)] * 3, np.zeros(3)),
    ("rastrigin", rastrigin, 2, [(-5.12, 5.12)] * 2, np.zeros(2)),
    ("rosenbrock", rosenbrock, 2, [(-2.0, 2.0)] * 2, np.ones(2)),
    ("ackley", ackley, 4, [(-32.768, 32.768)] * 4, np.zeros(4)),
    ("griewank", griewank, 5, [(-600.0, 600.0)] * 5, np.zeros(5)),
]
IDS = [p[0] for p in PROBLEMS]


class Counted:
    """Wrap an objective: count every call (thread-safe) and record every point it was asked about."""

    def __init__(self, f, vectorized=False):
        self.f, self.vectorized = f, vectorized
        self.calls, self.points, self.batch_shapes = 0, [], []
        self._lock = threading.Lock()

    def __call__(self, x):
        x = np.array(x, dtype=float)
        with self._lock:
            if self.vectorized:
                self.calls += x.shape[0]
                self.batch_shapes.append(x.shape)
                self.points.extend(x)
            else:
                self.calls += 1
                self.points.append(x)
        if self.vectorized:
            return np.array([self.f(row) for row in x])
        return self.f(x)


def assert_identical(a: OptimizeResult, b: OptimizeResult):
    assert a.x.tobytes() == b.x.tobytes()
    assert a.fun == b.fun
    assert (a.nit, a.nfev) == (b.nit, b.nfev)
    assert a.history.tobytes() == b.history.tobytes()
    assert a.population.tobytes() == b.population.tobytes()


# --- the core contract on the five classic functions -----------------------------------------------
@pytest.mark.parametrize("name, f, d, bounds, argmin", PROBLEMS, ids=IDS)
def test_result_contract_on_classic_functions(name, f, d, bounds, argmin):
    counted = Counted(f)
    res = minimize_cpso(counted, bounds, rng=7, max_iter=60)
    lo, hi = np.array(bounds).T

    assert isinstance(res, OptimizeResult)
    assert res.success and res.nit == 60 and "Maximum number of iterations" in res.message
    assert res.x.shape == (d,)
    assert np.all((res.x >= lo) & (res.x <= hi))
    # Every point the objective ever saw (swarm and chaos search) is inside the box.
    pts = np.array(counted.points)
    assert np.all((pts >= lo) & (pts <= hi))
    # The reported value is the objective at the reported point, exactly.
    assert res.fun == f(res.x)
    # nfev counts every call, chaos ones included, and follows the documented formula.
    assert res.nfev == counted.calls == 30 * (res.nit + 1) + 10 * res.nit
    # History: one value per iteration, non-increasing, ending at fun; x_history ends at x.
    assert res.history.shape == (res.nit,)
    assert np.all(np.diff(res.history) <= 0.0)
    assert res.history[-1] == res.fun
    assert res.x_history.shape == (res.nit, d)
    assert np.array_equal(res.x_history[-1], res.x)
    assert res.fun == min(f(p) for p in pts)
    assert res.population.shape == (30, d) and res.population_fun.shape == (30,)


@pytest.mark.parametrize("name, f, d, bounds, argmin", PROBLEMS, ids=IDS)
def test_same_seed_is_bitwise_identical_and_different_seeds_differ(name, f, d, bounds, argmin):
    a = minimize_cpso(f, bounds, rng=3, max_iter=30)
    b = minimize_cpso(f, bounds, rng=3, max_iter=30)
    c = minimize_cpso(f, bounds, rng=4, max_iter=30)
    assert_identical(a, b)
    assert a.x.tobytes() != c.x.tobytes()
    # A Generator is consumed the same way as its seed.
    assert_identical(a, minimize_cpso(f, bounds, rng=np.random.default_rng(3), max_iter=30))


@pytest.mark.parametrize(
    "name, tol_f, tol_x",
    [("sphere", 1e-8, 1e-4), ("rosenbrock", 1e-3, 5e-2), ("rastrigin", 1e-6, 1e-4), ("ackley", 1e-3, 1e-3)],
)
def test_easy_problems_reach_the_known_optimum(name, tol_f, tol_x):
    _, f, d, bounds, argmin = PROBLEMS[IDS.index(name)]
    for seed in range(3):
        res = minimize_cpso(f, bounds, rng=seed)
        assert res.fun < tol_f, (seed, res.fun)
        np.testing.assert_allclose(res.x, argmin, atol=tol_x)


def test_griewank_ends_in_a_good_basin_far_below_its_first_iteration():
    # 5-D Griewank is not solved to the optimum by the paper's settings in 100 iterations (the
    # swarm settles in one of the many shallow minima near the origin); it must still end below
    # 1 (where the cosine product outweighs the quadratic bowl) and far below its first iteration.
    _, f, d, bounds, _ = PROBLEMS[IDS.index("griewank")]
    for seed in range(2):
        res = minimize_cpso(f, bounds, rng=seed)
        assert res.fun < 1.0 and res.fun < 0.1 * res.history[0], (seed, res.fun, res.history[0])


# --- evaluation modes give the same answer ---------------------------------------------------------
@pytest.mark.parametrize("name, f, d, bounds, argmin", PROBLEMS[:3], ids=IDS[:3])
def test_vectorized_matches_scalar_and_counts_rows(name, f, d, bounds, argmin):
    scalar = minimize_cpso(f, bounds, rng=11, max_iter=25)
    counted = Counted(f, vectorized=True)
    vec = minimize_cpso(counted, bounds, rng=11, max_iter=25, vectorized=True)
    assert_identical(scalar, vec)
    assert vec.nfev == counted.calls
    # One point per row: (n_particles, n_dim) for the swarm, (chaos_steps, n_dim) for the chaos batch.
    assert set(counted.batch_shapes) == {(30, d), (10, d)}


@pytest.mark.parametrize("threads", [2, 4])
def test_threads_give_the_identical_result(threads):
    _, f, d, bounds, _ = PROBLEMS[IDS.index("rastrigin")]
    serial = minimize_cpso(f, bounds, rng=5, max_iter=25)
    counted = Counted(f)
    parallel = minimize_cpso(counted, bounds, rng=5, max_iter=25, threads=threads)
    assert_identical(serial, parallel)
    assert parallel.nfev == counted.calls


def test_map_like_workers_callable_is_used():
    used = []

    def my_map(func, iterable):
        items = list(iterable)
        used.append(len(items))
        return [func(x) for x in reversed(items)][::-1]  # evaluated out of order, returned in order

    a = minimize_cpso(sphere, [(-1, 1)] * 2, rng=0, max_iter=5)
    b = minimize_cpso(sphere, [(-1, 1)] * 2, rng=0, max_iter=5, workers=my_map)
    assert_identical(a, b)
    assert used[0] == 30 and sum(used) == b.nfev


def test_process_pool_map_gives_the_identical_result():
    from concurrent.futures import ProcessPoolExecutor

    serial = minimize_cpso(sphere, [(-1, 1)] * 2, rng=0, max_iter=3)
    with ProcessPoolExecutor(max_workers=2) as pool:
        parallel = minimize_cpso(sphere, [(-1, 1)] * 2, rng=0, max_iter=3, workers=pool.map)
    assert_identical(serial, parallel)


def test_callback_with_truthy_numpy_bool_stops():
    res = minimize_cpso(sphere, [(-1, 1)], rng=0, callback=lambda r: np.bool_(r.nit >= 3))
    assert res.nit == 3


def test_bounds_object_equals_sequence_of_pairs():
    a = minimize_cpso(sphere, [(-1.0, 2.0), (0.5, 3.0)], rng=2, max_iter=10)
    b = minimize_cpso(sphere, Bounds([-1.0, 0.5], [2.0, 3.0]), rng=2, max_iter=10)
    assert_identical(a, b)


def test_args_are_passed_to_fun():
    res = minimize_cpso(lambda x, c: float(np.sum((x - c) ** 2)), [(-5, 5)] * 2, args=(1.5,), rng=0)
    np.testing.assert_allclose(res.x, [1.5, 1.5], atol=1e-4)


# --- chaos vs plain, boundaries, options -----------------------------------------------------------
def test_chaos_steps_zero_is_plain_pso_with_the_plain_budget():
    counted = Counted(sphere)
    res = minimize_cpso(counted, [(-5, 5)] * 3, rng=1, max_iter=20, chaos_steps=0)
    assert res.nfev == counted.calls == 30 * 21
    assert res.n_chaos_improvements == 0


def test_chaos_search_improves_gbest_and_feeds_back_into_the_swarm():
    res = minimize_cpso(sphere, [(-5, 5)] * 3, rng=1, max_iter=50)
    assert res.n_chaos_improvements > 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_improved_chaos_point_replaces_the_worst_particle(seed):
    # Same seed: the plain run moves the same swarm with the same random numbers, so after one
    # iteration the two swarms differ only in the worst particle, which the chaos point replaced.
    bounds = [(-5, 5)] * 3
    chaos = minimize_cpso(sphere, bounds, rng=seed, max_iter=1)
    plain = minimize_cpso(sphere, bounds, rng=seed, max_iter=1, chaos_steps=0)
    assert chaos.n_chaos_improvements == 1
    assert chaos.fun < plain.fun
    worst = int(np.argmax(plain.population_fun))
    others = np.arange(30) != worst
    assert np.array_equal(chaos.population[others], plain.population[others])
    assert np.array_equal(chaos.population[worst], chaos.x)
    assert chaos.population_fun[worst] == chaos.fun


def test_optimum_on_a_bound_is_found_and_never_left():
    # Minimum at the lower corner (1, 1): the chaos region is clipped to the box, never shifted out.
    counted = Counted(lambda x: float(np.sum(x)))
    res = minimize_cpso(counted, [(1.0, 2.0), (1.0, 2.0)], rng=0, max_iter=40)
    pts = np.array(counted.points)
    assert pts.min() >= 1.0 and pts.max() <= 2.0
    assert res.fun == pytest.approx(2.0, abs=1e-9)


def test_log_scale_finds_an_optimum_at_1e_minus_3_in_a_nine_decade_box():
    counted = Counted(lambda x: (np.log10(x[0]) + 3.0) ** 2 + (x[1] - 0.3) ** 2)
    bounds = [(1e-6, 1e3), (-1.0, 1.0)]
    res = minimize_cpso(counted, bounds, log_scale=[True, False], rng=0)
    assert res.x[0] == pytest.approx(1e-3, rel=1e-3)
    assert res.x[1] == pytest.approx(0.3, abs=1e-3)
    pts = np.array(counted.points)
    assert np.all((pts >= [1e-6, -1.0]) & (pts <= [1e3, 1.0]))
    # The initial swarm is log-uniform in the log dimension: about 6 of 9 decades lie below 1.
    initial = pts[:30, 0]
    assert 10 <= np.sum(initial < 1.0) <= 29


def test_log_scale_true_applies_to_every_dimension_and_respects_bounds():
    res = minimize_cpso(lambda x: float(np.sum(np.log10(x) ** 2)), [(1e-2, 1e2)] * 2, log_scale=True, rng=1)
    assert np.all((res.x >= 1e-2) & (res.x <= 1e2))
    np.testing.assert_allclose(res.x, [1.0, 1.0], rtol=1e-3)


def test_linear_inertia_with_equal_ends_is_constant_inertia():
    kw = dict(rng=9, max_iter=15, w=0.6)
    a = minimize_cpso(rastrigin, [(-5.12, 5.12)] * 2, inertia="constant", **kw)
    b = minimize_cpso(rastrigin, [(-5.12, 5.12)] * 2, inertia="linear", w_end=0.6, **kw)
    c = minimize_cpso(rastrigin, [(-5.12, 5.12)] * 2, inertia="linear", w_end=0.2, **kw)
    assert_identical(a, b)
    assert a.history.tobytes() != c.history.tobytes()


def test_without_velocity_clamp_positions_still_stay_inside_the_bounds():
    counted = Counted(sphere)
    res = minimize_cpso(counted, [(-5, 5)] * 2, rng=0, max_iter=30, vmax_frac=None)
    pts = np.array(counted.points)
    assert np.all(np.abs(pts) <= 5.0)
    assert res.fun == sphere(res.x)


@pytest.mark.parametrize("vmax_frac", [0.01, 0.05])
def test_velocity_clamp_limits_each_step_to_a_fraction_of_the_width(vmax_frac):
    counted = Counted(rastrigin)
    bounds = [(-5.12, 5.12), (0.0, 1.0)]
    minimize_cpso(counted, bounds, rng=0, max_iter=20, chaos_steps=0, vmax_frac=vmax_frac)
    swarm = np.array(counted.points).reshape(21, 30, 2)  # (iteration, particle, dim)
    steps = np.abs(np.diff(swarm, axis=0))
    vmax = vmax_frac * np.array([10.24, 1.0])
    assert np.all(steps <= vmax * (1 + 1e-12))
    assert np.any(steps >= vmax * (1 - 1e-12))  # the clamp is actually reached


def test_tol_and_patience_stop_a_stagnating_run():
    res = minimize_cpso(lambda x: 1.0, [(-1, 1)], rng=0, tol=0.0, patience=5)
    assert res.success and res.nit == 6 and res.message.startswith("Converged")
    assert res.nfev == 30 * 7 + 10 * 6


# --- callback ---------------------------------------------------------------------------------------
def test_callback_returning_true_stops_early_with_success():
    seen = []

    def cb(intermediate_result):
        seen.append((intermediate_result.nit, intermediate_result.nfev, intermediate_result.fun))
        return intermediate_result.nit == 4

    res = minimize_cpso(sphere, [(-5, 5)] * 2, rng=0, callback=cb)
    assert res.nit == 4 and res.success and "callback" in res.message
    assert [s[0] for s in seen] == [1, 2, 3, 4]
    assert [s[1] for s in seen] == [30 + 40 * k for k in (1, 2, 3, 4)]
    assert [s[2] for s in seen] == list(res.history)


def test_callback_raising_stopiteration_stops_early_with_success():
    def cb(intermediate_result):
        if intermediate_result.nit == 2:
            raise StopIteration

    res = minimize_cpso(sphere, [(-5, 5)] * 2, rng=0, callback=cb)
    assert res.nit == 2 and res.success and "callback" in res.message
    assert res.history.shape == (2,)


def test_callback_returning_none_or_false_does_not_stop():
    res = minimize_cpso(sphere, [(-5, 5)] * 2, rng=0, max_iter=7, callback=lambda r: False)
    assert res.nit == 7


# --- NaN and infinities -----------------------------------------------------------------------------
def test_nan_is_treated_as_infinity():
    def f(x):
        return float("nan") if x[0] < 0 else float(np.sum((x - 0.5) ** 2))

    res = minimize_cpso(f, [(-5, 5)] * 2, rng=0)
    assert res.success and math.isfinite(res.fun)
    np.testing.assert_allclose(res.x, [0.5, 0.5], atol=1e-4)
    assert np.all(np.diff(res.history) <= 0)


def test_all_nan_objective_reports_failure():
    res = minimize_cpso(lambda x: float("nan"), [(-1, 1)], rng=0, max_iter=3)
    assert not res.success and res.fun == math.inf
    assert "No finite objective value" in res.message


# --- the logistic map guard -------------------------------------------------------------------------
@given(
    z=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=6),
    mu=st.floats(2.0, 4.0, exclude_min=True),
    steps=st.integers(1, 60),
    seed=st.integers(0, 2**32 - 1),
)
@settings(max_examples=60, deadline=None)
def test_guarded_logistic_map_never_sits_on_a_trap(z, mu, steps, seed):
    gen = np.random.default_rng(seed)
    traps = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.0 - 1.0 / mu, 1.0 / mu])
    z = reseed_chaos(np.array(z), gen, mu)
    for _ in range(steps):
        z = reseed_chaos(mu * z * (1.0 - z), gen, mu)
        assert np.all((z > 0.0) & (z < 1.0))
        assert np.min(np.abs(z[:, None] - traps)) > 1e-10


def test_guard_keeps_good_values_and_replaces_traps():
    gen = np.random.default_rng(0)
    z = reseed_chaos(np.array([0.0, 0.25, 0.5, 0.75, 1.0, 0.3, 1e-12]), gen, 4.0)
    assert z[5] == 0.3
    assert np.all(np.abs(z[[0, 1, 2, 3, 4, 6]] - np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1e-12])) > 1e-10)


def _reseed_with_numpy(z, gen, mu):
    """The guard written with numpy masks (the reference of `reseed_chaos`'s Python-float test)."""
    traps = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.0 - 1.0 / mu, 1.0 / mu])
    z = np.array(z, dtype=float)
    while True:
        near = np.any(np.abs(z[:, None] - traps[None, :]) <= 1e-10, axis=1)
        bad = ~np.isfinite(z) | (z <= 0.0) | (z >= 1.0) | near
        if not bad.any():
            return z
        z[bad] = gen.random(int(bad.sum()))


def test_guard_is_the_numpy_mask_bit_for_bit():
    rng = np.random.default_rng(4)
    for mu in (2.5, 3.2, 4.0):
        z = np.r_[rng.random(40), 0.0, 0.25, 0.5 + 5e-11, 0.75, 1.0, 1.0 - 1.0 / mu, 1.0 / mu, 1e-12, -0.1, 1.5]
        z = np.r_[z, np.nan, np.inf, -np.inf, 0.5 + 2e-10]
        for seed in range(5):
            got = reseed_chaos(z, np.random.default_rng(seed), mu)
            want = _reseed_with_numpy(z, np.random.default_rng(seed), mu)
            np.testing.assert_array_equal(got, want)  # the same draws in the same places
            assert got[-1] == 0.5 + 2e-10  # beyond the guard: kept


@pytest.mark.parametrize("mu", [2.5, 2.9, 4.0])
def test_chaos_search_does_not_collapse_onto_a_fixed_point(mu):
    # For mu < 3 the map converges onto 1 - 1/mu; the guard reseeds, so chaos points keep varying.
    # (For 3 < mu < 3.57 the map settles on a periodic orbit; that is the map, not a collapse.)
    counted = Counted(sphere)
    minimize_cpso(counted, [(-1, 1)], rng=0, n_particles=2, max_iter=100, mu=mu)
    chaos_pts = np.array([p for i, p in enumerate(counted.points[2:]) if i % 12 >= 2]).ravel()
    late = chaos_pts[-200:]
    assert np.unique(late).size > 150


# --- a property over random boxes -------------------------------------------------------------------
@given(
    lows=st.lists(st.floats(-1e3, 1e3), min_size=1, max_size=4),
    widths=st.data(),
    seed=st.integers(0, 2**32 - 1),
    chaos_steps=st.integers(0, 4),
)
@settings(max_examples=25, deadline=None)
def test_any_box_keeps_results_inside_and_history_monotone(lows, widths, seed, chaos_steps):
    w = widths.draw(st.lists(st.floats(1e-6, 1e3), min_size=len(lows), max_size=len(lows)))
    bounds = [(lo, lo + wi) for lo, wi in zip(lows, w, strict=False) if lo + wi > lo]
    if not bounds:
        return
    counted = Counted(lambda x: float(np.sum(np.sin(x) * x)))
    res = minimize_cpso(counted, bounds, rng=seed, n_particles=5, max_iter=6, chaos_steps=chaos_steps)
    lo, hi = np.array(bounds).T
    pts = np.array(counted.points)
    assert np.all((pts >= lo) & (pts <= hi))
    assert res.nfev == counted.calls == 5 * 7 + chaos_steps * 6
    assert np.all(np.diff(res.history) <= 0) and res.history[-1] == res.fun


# --- bad inputs -------------------------------------------------------------------------------------
GOOD = [(-1.0, 1.0), (-1.0, 1.0)]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(bounds=[(1.0, 1.0)]), "bounds must have low < high, got (1.0, 1.0) in dimension 0"),
        (dict(bounds=[(0, 1), (2.0, -2.0)]), "bounds must have low < high, got (2.0, -2.0) in dimension 1"),
        (dict(bounds=[(0.0, math.inf)]), "bounds must be finite, got (0.0, inf) in dimension 0"),
        (dict(bounds=[(math.nan, 1.0)]), "bounds must be finite, got (nan, 1.0) in dimension 0"),
        (dict(bounds=[(0, 1, 2)]), "bounds must be a sequence of (low, high) pairs, got [(0, 1, 2)]"),
        (dict(bounds=[]), "bounds must be a sequence of (low, high) pairs, got []"),
        (dict(log_scale=True), "log_scale requires positive bounds, got (-1.0, 1.0) in dimension 0"),
        (dict(log_scale=[True]), "log_scale must be a bool or a sequence of 2 bools, got [True]"),
        (dict(n_particles=1), "n_particles must be an int >= 2, got 1"),
        (dict(n_particles=2.5), "n_particles must be an int >= 2, got 2.5"),
        (dict(max_iter=0), "max_iter must be an int >= 1, got 0"),
        (dict(mu=2.0), "mu must be in (2, 4], got 2.0"),
        (dict(mu=4.5), "mu must be in (2, 4], got 4.5"),
        (dict(chaos_steps=-1), "chaos_steps must be an int >= 0, got -1"),
        (dict(w=-0.1), "w must be a non-negative number, got -0.1"),
        (dict(w_end=-0.4), "w_end must be a non-negative number, got -0.4"),
        (dict(c1=-2.0), "c1 must be a non-negative number, got -2.0"),
        (dict(c2=-2.0), "c2 must be a non-negative number, got -2.0"),
        (dict(inertia="exponential"), "inertia must be 'constant' or 'linear', got 'exponential'"),
        (dict(vmax_frac=0.0), "vmax_frac must be a positive finite number or None, got 0.0"),
        (dict(chaos_radius=0.0), "chaos_radius must be in (0, 1], got 0.0"),
        (dict(chaos_radius_end=0.5), "chaos_radius_end must be in (0, chaos_radius=0.1], got 0.5"),
        (dict(patience=0), "patience must be an int >= 1, got 0"),
        (dict(workers=0), "workers must be 1 or a map-like callable, got 0"),
        (dict(workers=2), "workers must be 1 or a map-like callable, got 2 (scipy reads an integer as a number of"),
        (dict(threads=0), "threads must be a positive int or -1, got 0"),
        (dict(workers=map, threads=2), "give workers (a map-like callable) or threads, not both"),
        (
            dict(vectorized=True, threads=2),
            "workers and threads must be 1 when vectorized=True, got workers=1, threads=2",
        ),
    ],
)
def test_bad_inputs_raise_naming_argument_and_value(kwargs, message):
    kwargs = {"bounds": GOOD, "max_iter": 2, **kwargs}
    bounds = kwargs.pop("bounds")
    with pytest.raises(ValueError, match=re.escape(message)):
        minimize_cpso(sphere, bounds, **kwargs)


@pytest.mark.parametrize(
    "returned, shape", [(lambda X: np.sum(X, axis=1, keepdims=True), "(30, 1)"), (lambda X: 0.0, "()")]
)
def test_vectorized_output_shape_is_validated(returned, shape):
    message = f"must return an array of shape (30,) for input of shape (30, 2), got shape {shape}"
    with pytest.raises(ValueError, match=re.escape(message)):
        minimize_cpso(returned, GOOD, vectorized=True, max_iter=2)


def test_scalar_fun_returning_an_array_is_rejected():
    with pytest.raises(ValueError, match=re.escape("fun must return a scalar, got an array of shape (2,)")):
        minimize_cpso(lambda x: x, GOOD, max_iter=2)


# --- the solver class and its steps, each on its own -------------------------------------------------
def test_pso_move_follows_eq_13_14_then_clamps_and_absorbs():
    one = np.ones((1, 2))
    pos, vel = np.zeros((1, 2)), np.array([[1.0, -1.0]])
    pbest, gbest = np.array([[1.0, 1.0]]), np.array([[2.0, -3.0]])
    kw = dict(w=0.5, c1=2.0, c2=2.0, lo=np.array([-2.0, -2.0]), hi=np.array([0.5, 2.0]))
    # v = 0.5 v + 2 * 0.5 (pbest - x) + 2 * 0.5 (gbest - x) = (3.5, -2.5), unclamped
    new_pos, new_vel = pso_move(pos, vel, pbest, gbest, 0.5 * one, 0.5 * one, vmax=None, **kw)
    # x = (3.5, -2.5) leaves the box on both sides: clipped onto the bounds, velocity zeroed
    np.testing.assert_array_equal(new_pos, [[0.5, -2.0]])
    np.testing.assert_array_equal(new_vel, [[0.0, 0.0]])
    new_pos, new_vel = pso_move(pos, vel, pbest, gbest, 0.5 * one, 0.5 * one, vmax=np.array([0.25, 1.0]), **kw)
    np.testing.assert_array_equal(new_vel, [[0.25, -1.0]])  # clamped, inside: kept
    np.testing.assert_array_equal(new_pos, [[0.25, -1.0]])
    np.testing.assert_array_equal(pos, [[0.0, 0.0]])  # inputs untouched
    np.testing.assert_array_equal(vel, [[1.0, -1.0]])


def test_chaos_region_is_clipped_to_the_box_never_shifted():
    a, b = chaos_region(np.array([0.95, 0.5]), 0.1, np.array([1.0, 2.0]), np.zeros(2), np.ones(2))
    np.testing.assert_allclose(a, [0.85, 0.3])
    np.testing.assert_allclose(b, [1.0, 0.7])


def test_logistic_chaos_points_iterate_eq_15_onto_the_region():
    gen = np.random.default_rng(0)
    pts, z = logistic_chaos_points(np.array([0.3]), np.array([10.0]), np.array([20.0]), 2, 4.0, gen)
    z1 = 4.0 * 0.3 * 0.7
    z2 = 4.0 * z1 * (1.0 - z1)
    np.testing.assert_allclose(pts[:, 0], [10.0 + 10.0 * z1, 10.0 + 10.0 * z2])
    assert z[0] == pytest.approx(z2)


def test_swarm_bests_move_on_strict_improvement_only_and_chaos_replaces_the_worst():
    pos = np.array([[0.0], [1.0], [2.0]])
    s = Swarm.start(pos.copy(), pos.copy(), np.array([3.0, 1.0, 3.0]))
    assert s.gbest_fit == 1.0 and s.gbest[0] == 1.0
    s.pos = np.array([[5.0], [6.0], [7.0]])
    s.pos_nat, s.fit = s.pos.copy(), np.array([3.0, 0.5, 4.0])  # particle 0 ties: keeps its old best
    s.update_bests()
    np.testing.assert_array_equal(s.pbest[:, 0], [0.0, 6.0, 2.0])
    assert s.gbest_fit == 0.5 and s.gbest[0] == 6.0
    cand = np.array([[9.0], [8.0]])
    assert not s.accept_chaos(cand, cand, np.array([0.5, 0.7]))  # equal to gbest: rejected
    assert s.accept_chaos(cand, cand, np.array([0.6, 0.1]))
    assert s.pos[2, 0] == 8.0 and s.fit[2] == 0.1 and s.pbest[2, 0] == 8.0  # worst (fit 4.0) replaced
    assert s.gbest_fit == 0.1 and s.gbest[0] == 8.0


def test_solver_iterates_one_generation_at_a_time_like_minimize_cpso():
    bounds = [(-5.12, 5.12)] * 2
    whole = minimize_cpso(rastrigin, bounds, rng=3, max_iter=12)
    with CPSOSolver(rastrigin, bounds, CPSOSettings(max_iter=12), rng=3) as solver:
        steps = [(x.copy(), f) for x, f in solver]
        assert len(steps) == 12 == solver.nit
        assert [f for _, f in steps] == list(whole.history)
        assert_identical(solver.result(), whole)
    # Phases called by hand give the same swarm as the iteration.
    manual = CPSOSolver(rastrigin, bounds, CPSOSettings(max_iter=12), rng=3)
    manual.init_population()
    manual.pso_move(1)
    manual.update_bests()
    manual.chaos_feedback(*manual.chaos_search(1))
    first = CPSOSolver(rastrigin, bounds, CPSOSettings(max_iter=12), rng=3)
    next(first)
    assert manual.swarm.pos.tobytes() == first.swarm.pos.tobytes()
    assert manual.swarm.gbest_fit == first.swarm.gbest_fit == whole.history[0]
