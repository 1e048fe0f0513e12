"""Chaos particle swarm optimisation (CPSO), the hyperparameter tuner of Yu et al. (2013).

One public function, :func:`minimize_cpso`, with the calling conventions of
:func:`scipy.optimize.differential_evolution` (``bounds``, ``rng``, ``callback``, ``workers``,
``vectorized``) and an :class:`scipy.optimize.OptimizeResult` as its answer.

The paper gives the global-best PSO update (eq. 13-14) and the logistic map (eq. 15) and the settings
(30 particles, initial inertia 0.75, c1 = c2 = 2, at most 10 chaos iterations, at most 100 PSO
iterations); everything else (bounds handling, velocity clamp, the chaos search region and how its
result rejoins the swarm) is left open and is chosen and documented in :func:`minimize_cpso`.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack

import numpy as np
from scipy.optimize import Bounds, OptimizeResult

__all__ = ["minimize_cpso"]

# |z - p| below this counts as having landed on a fixed/absorbing point p of the logistic map.
_CHAOS_GUARD_ATOL = 1e-10


def minimize_cpso(
    fun: Callable[..., float],
    bounds,
    *,
    args: tuple = (),
    n_particles: int = 30,
    max_iter: int = 100,
    w: float = 0.75,
    inertia: str = "constant",
    w_end: float = 0.4,
    c1: float = 2.0,
    c2: float = 2.0,
    chaos_steps: int = 10,
    mu: float = 4.0,
    chaos_radius: float = 0.1,
    chaos_radius_end: float = 1e-6,
    vmax_frac: float | None = 0.2,
    log_scale: bool | Sequence[bool] | None = None,
    vectorized: bool = False,
    workers: int | Callable = 1,
    rng: int | np.random.Generator | None = None,
    callback: Callable[[OptimizeResult], bool | None] | None = None,
    tol: float = 0.0,
    patience: int | None = None,
) -> OptimizeResult:
    r"""Minimise ``fun`` over a box with chaos particle swarm optimisation (Yu et al. 2013, eq. 13-15).

    Each iteration ``k = 1 .. max_iter`` does, in this order:

    1. **PSO move** (eq. 13-14), global-best topology, in the search space (see ``log_scale``)::

           v <- w_k v + c1 r1 (pbest - x) + c2 r2 (gbest - x)        (13)
           x <- x + v                                                (14)

       ``r1``, ``r2`` are drawn independently per particle *and* per dimension, uniform on [0, 1)
       (the paper does not say which; per-dimension is the common form). Each velocity component is
       clamped to ``|v_i| <= vmax_frac * (high_i - low_i)``. A position that leaves the box is clipped
       onto the violated bound and that velocity component is set to zero ("absorbing wall"), so a
       particle never carries an outward velocity into the next step.
    2. The swarm is evaluated; personal bests (``pbest``) and the global best (``gbest``) are updated on
       strict improvement (ties keep the earlier point, so results do not depend on evaluation order).
    3. **Chaos local search** around ``gbest`` (eq. 15), skipped when ``chaos_steps == 0`` (plain PSO).
       A chaos vector ``z`` (one logistic-map variable per dimension, started from ``rng`` and carried
       over from one iteration to the next) is iterated ``chaos_steps`` times,
       ``z <- mu z (1 - z)`` (15), and each iterate is mapped onto the region
       ``[max(low, g - r_k), min(high, g + r_k)]`` as ``a + z (b - a)``, where
       ``r_k = rho_k (high - low)`` and ``rho_k`` shrinks geometrically from ``chaos_radius`` at the first
       iteration to ``chaos_radius_end`` at iteration ``max_iter``. The region is *clipped* to the box,
       never shifted, so a best point on a bound is searched on its inside only. All ``chaos_steps``
       candidates are generated first and evaluated as one batch (the map does not depend on the
       objective), so ``vectorized`` and ``workers`` apply to them as well; all count in ``nfev``.
       **Feedback:** if the best candidate is strictly better than ``gbest``, it becomes ``gbest`` and
       replaces the *worst* particle of the current swarm (highest current fitness, lowest index on
       ties): that particle's position, fitness and personal best become the candidate's, its velocity
       is kept. Otherwise the swarm is untouched.
    4. ``history`` records the best fitness, ``callback`` is called, and the stopping rules are checked.

    The paper says only that the logistic map "perturbs the current particles" to escape premature
    convergence, with at most 10 chaos iterations. Step 3 follows the usual CPSO reading (a chaotic local
    search around the global best, as in Liu et al. 2005) and spends exactly ``chaos_steps`` evaluations
    per iteration rather than stopping at the first improvement, so the budget (``nfev``) is fixed in
    advance and the chaos batch can be evaluated in parallel.

    Guards on the logistic map: an iterate within 1e-10 of a fixed or absorbing point (0, 0.25, 0.5,
    0.75, 1, and for general ``mu`` also ``1 - 1/mu`` and ``1/mu``), or outside (0, 1), is replaced by a
    fresh draw from ``rng``; this also catches floating-point orbits that collapse onto 0 after passing
    near 1, and the convergence onto ``1 - 1/mu`` for ``mu < 3``. Periodic orbits are not guarded: for
    ``3 < mu < ~3.57`` the map settles on a 2-, 4-, ... cycle and the chaos search visits only that many
    points per region; only ``mu`` near 4 is actually chaotic (the default, 4, covers (0, 1) densely).

    Parameters
    ----------
    fun : callable
        ``fun(x, *args) -> float`` with ``x`` of shape ``(n_dim,)`` in natural units. With
        ``vectorized=True``: ``fun(X, *args) -> ndarray`` with ``X`` of shape ``(S, n_dim)`` (one point
        per **row**; note that :func:`scipy.optimize.differential_evolution` uses the transpose) and a
        1-D result of shape ``(S,)``; ``S`` is ``n_particles`` for the swarm and ``chaos_steps`` for the
        chaos search. NaN values are treated as ``+inf``.
    bounds : sequence of (low, high) or scipy.optimize.Bounds
        Finite box, ``low < high`` in each dimension, in natural units (also for log-scaled dimensions).
    args : tuple
        Extra positional arguments for ``fun``.
    n_particles : int, default 30
        Swarm size (paper: 30), at least 2.
    max_iter : int, default 100
        Maximum number of PSO iterations (paper: 100), at least 1.
    w : float, default 0.75
        Inertia weight (paper: initial inertia 0.75). Non-negative.
    inertia : {"constant", "linear"}
        ``"constant"``: ``w_k = w``. ``"linear"``: ``w_k`` decreases linearly from ``w`` at the first
        iteration to ``w_end`` at iteration ``max_iter``.
    w_end : float, default 0.4
        Final inertia of the ``"linear"`` schedule. Non-negative.
    c1, c2 : float, default 2.0
        Cognitive and social coefficients (paper: 2 and 2). Non-negative.
    chaos_steps : int, default 10
        Logistic-map iterations (= chaos evaluations) per PSO iteration (paper: at most 10); 0 gives
        plain PSO. The chaos map draws from its own stream (split off ``rng`` at the start), so plain and
        chaos runs with the same seed start from the same swarm and move it with the same ``r1``, ``r2``
        until the first chaos improvement: a paired comparison.
    mu : float, default 4.0
        Logistic-map parameter, in (2, 4] as in eq. 15 (4 is fully chaotic on [0, 1]).
    chaos_radius, chaos_radius_end : float, default 0.1 and 1e-6
        Half-width of the chaos search region as a fraction of each dimension's search width, at the
        first and at the last iteration, geometric in between:
        ``rho_k = chaos_radius * (chaos_radius_end / chaos_radius) ** ((k - 1) / (max_iter - 1))``.
        ``0 < chaos_radius_end <= chaos_radius <= 1``. The paper gives no region; 0.1 lets the early
        chaos steps jump between neighbouring basins, and the end value 1e-6 lets the last ones refine
        ``gbest`` well below the spread the swarm itself reaches in 100 iterations with these weights.
        ``chaos_radius = chaos_radius_end`` gives a fixed region.
    vmax_frac : float or None, default 0.2
        Velocity clamp as a fraction of each dimension's search width; ``None`` disables it (with
        ``w = 0.75``, ``c1 + c2 = 4`` the unclamped swarm is outside the convergent region and explodes
        onto the bounds).
    log_scale : bool or sequence of bool, optional
        Search these dimensions in ``log10`` space (bounds must then be positive). Positions, velocities,
        the velocity clamp and the chaos region all live in the search space; ``fun`` and the result are
        in natural units (clipped to the bounds after ``10**s`` so round-off never leaves the box).
    vectorized : bool, default False
        Call ``fun`` once per batch with a 2-D array (see ``fun``). The returned array must have shape
        ``(S,)``; anything else raises ``ValueError``. Gives the same result as ``vectorized=False`` for
        the same seed when ``fun`` computes each row as the scalar version would.
    workers : int or map-like callable, default 1
        ``1``: evaluate in the calling thread. ``n > 1``: evaluate each batch on a thread pool of ``n``
        threads (useful when ``fun`` releases the GIL, as NumPy/LAPACK-heavy objectives do); ``-1``: one
        thread per CPU. A map-like callable (e.g. ``multiprocessing.Pool(4).map`` for a picklable
        ``fun``) is used as ``workers(fun, points)`` and must return results in order. Evaluation order
        never changes the result: all random numbers are drawn in the calling thread and results are
        gathered in point order. Incompatible with ``vectorized=True``.
    rng : int, numpy.random.Generator or None
        Seed or generator; the same seed gives a bitwise identical result. No global state is used.
    callback : callable, optional
        ``callback(intermediate_result)`` once per iteration with an ``OptimizeResult`` holding ``x``,
        ``fun``, ``nit``, ``nfev``. Returning ``True`` or raising ``StopIteration`` stops the run with
        ``success=True`` and a message saying so.
    tol : float, default 0.0
        Used with ``patience``: stop when the best fitness improved by no more than ``tol`` (absolute)
        over the last ``patience`` iterations.
    patience : int or None, default None
        Number of iterations for the ``tol`` rule; ``None`` always runs ``max_iter`` iterations.

    Returns
    -------
    OptimizeResult
        ``x`` (best point, natural units), ``fun`` (its fitness, ``fun(x)`` exactly), ``nit``, ``nfev``
        (every call of ``fun``, chaos ones included; each row counts once when vectorized), ``success``
        (``False`` only if no finite fitness was ever found), ``message``, ``history`` (best fitness after
        each iteration, shape ``(nit,)``, non-increasing, ``history[-1] == fun``), ``x_history`` (best
        point after each iteration, ``(nit, n_dim)``), ``population`` and ``population_fun`` (final swarm
        positions in natural units and their fitness), ``n_chaos_improvements`` (iterations in which the
        chaos search improved ``gbest``).

    Notes
    -----
    ``nfev = n_particles * (nit + 1) + chaos_steps * nit``: one initial swarm evaluation, then one swarm
    evaluation and one chaos batch per iteration. Initial positions are uniform in the search box
    (log-uniform in log-scaled dimensions), initial velocities are zero.

    References
    ----------
    Yu F., Zhang L., Xie Y., Long X., "Identification of axial RLG drifts in single-axis rotation
    inertial navigation system based on CPSO-LSSVM", Systems Engineering and Electronics 35(5), 2013.
    Liu B., Wang L., Jin Y.-H., Tang F., Huang D.-X., "Improved particle swarm optimization combined
    with chaos", Chaos, Solitons & Fractals 25(5), 1261-1271, 2005.
    """
    lo_nat, hi_nat = _validate_bounds(bounds)
    n_dim = lo_nat.size
    log_mask = _validate_log_scale(log_scale, lo_nat, hi_nat)
    n_particles = _validate_int("n_particles", n_particles, minimum=2)
    max_iter = _validate_int("max_iter", max_iter, minimum=1)
    chaos_steps = _validate_int("chaos_steps", chaos_steps, minimum=0)
    for name, value in (("w", w), ("w_end", w_end), ("c1", c1), ("c2", c2), ("tol", tol)):
        _validate_nonnegative(name, value)
    mu = float(mu)
    if not (2.0 < mu <= 4.0):
        raise ValueError(f"mu must be in (2, 4], got {mu!r}")
    if inertia not in ("constant", "linear"):
        raise ValueError(f"inertia must be 'constant' or 'linear', got {inertia!r}")
    if not (0.0 < chaos_radius <= 1.0):
        raise ValueError(f"chaos_radius must be in (0, 1], got {chaos_radius!r}")
    if not (0.0 < chaos_radius_end <= chaos_radius):
        raise ValueError(f"chaos_radius_end must be in (0, chaos_radius={chaos_radius!r}], got {chaos_radius_end!r}")
    if vmax_frac is not None and not (math.isfinite(vmax_frac) and vmax_frac > 0):
        raise ValueError(f"vmax_frac must be a positive finite number or None, got {vmax_frac!r}")
    if patience is not None:
        patience = _validate_int("patience", patience, minimum=1)
    if callback is not None and not callable(callback):
        raise ValueError(f"callback must be callable or None, got {callback!r}")
    if not callable(fun):
        raise ValueError(f"fun must be callable, got {fun!r}")
    vectorized = bool(vectorized)
    if vectorized and workers != 1:
        raise ValueError(f"workers must be 1 when vectorized=True, got {workers!r}")

    gen = np.random.default_rng(rng)

    # Search space: log10 in the log-scaled dimensions, natural elsewhere.
    lo = np.where(log_mask, np.log10(lo_nat, where=log_mask, out=lo_nat.copy()), lo_nat)
    hi = np.where(log_mask, np.log10(hi_nat, where=log_mask, out=hi_nat.copy()), hi_nat)
    width = hi - lo
    vmax = None if vmax_frac is None else vmax_frac * width

    def to_natural(s: np.ndarray) -> np.ndarray:
        x = s.copy()
        x[..., log_mask] = 10.0 ** s[..., log_mask]
        return np.clip(x, lo_nat, hi_nat)

    with ExitStack() as stack:
        mapper = _make_mapper(workers, stack)
        evaluate = _Evaluator(fun, args, vectorized, mapper)

        # Initial swarm: uniform in the search box, zero velocity.
        pos = lo + gen.random((n_particles, n_dim)) * width
        vel = np.zeros((n_particles, n_dim))
        pos_nat = to_natural(pos)
        fit = evaluate(pos_nat)
        pbest, pbest_nat, pbest_fit = pos.copy(), pos_nat.copy(), fit.copy()
        g = int(np.argmin(pbest_fit))
        gbest, gbest_nat, gbest_fit = pbest[g].copy(), pbest_nat[g].copy(), float(pbest_fit[g])

        # The chaos map gets its own stream, drawn whether or not it is used, so that a run with
        # chaos_steps=0 moves its swarm with exactly the random numbers of the chaos run (paired runs).
        chaos_gen = np.random.default_rng(gen.integers(0, 2**63))
        z = _reseed_chaos(chaos_gen.random(n_dim), chaos_gen, mu) if chaos_steps else None
        history: list[float] = []
        x_history: list[np.ndarray] = []
        n_chaos_improvements = 0
        message = "Maximum number of iterations reached."
        nit = 0

        for k in range(1, max_iter + 1):
            frac = (k - 1) / (max_iter - 1) if max_iter > 1 else 0.0
            w_k = w if inertia == "constant" else w - (w - w_end) * frac

            # Eq. (13)-(14), then velocity clamp and absorbing walls.
            r1 = gen.random((n_particles, n_dim))
            r2 = gen.random((n_particles, n_dim))
            vel = w_k * vel + c1 * r1 * (pbest - pos) + c2 * r2 * (gbest - pos)
            if vmax is not None:
                vel = np.clip(vel, -vmax, vmax)
            pos = pos + vel
            outside = (pos < lo) | (pos > hi)
            pos = np.clip(pos, lo, hi)
            vel[outside] = 0.0

            pos_nat = to_natural(pos)
            fit = evaluate(pos_nat)
            better = fit < pbest_fit
            pbest[better], pbest_nat[better], pbest_fit[better] = pos[better], pos_nat[better], fit[better]
            g = int(np.argmin(pbest_fit))
            if pbest_fit[g] < gbest_fit:
                gbest, gbest_nat, gbest_fit = pbest[g].copy(), pbest_nat[g].copy(), float(pbest_fit[g])

            if chaos_steps:
                rho = chaos_radius * (chaos_radius_end / chaos_radius) ** frac
                a = np.maximum(lo, gbest - rho * width)
                b = np.minimum(hi, gbest + rho * width)
                cand = np.empty((chaos_steps, n_dim))
                for j in range(chaos_steps):
                    z = _reseed_chaos(mu * z * (1.0 - z), chaos_gen, mu)  # eq. (15)
                    cand[j] = a + z * (b - a)
                cand = np.clip(cand, lo, hi)
                cand_nat = to_natural(cand)
                cand_fit = evaluate(cand_nat)
                j = int(np.argmin(cand_fit))
                if cand_fit[j] < gbest_fit:
                    worst = int(np.argmax(fit))
                    pos[worst], pos_nat[worst], fit[worst] = cand[j], cand_nat[j], cand_fit[j]
                    pbest[worst], pbest_nat[worst], pbest_fit[worst] = cand[j], cand_nat[j], cand_fit[j]
                    gbest, gbest_nat, gbest_fit = cand[j].copy(), cand_nat[j].copy(), float(cand_fit[j])
                    n_chaos_improvements += 1

            nit = k
            history.append(gbest_fit)
            x_history.append(gbest_nat.copy())

            if callback is not None:
                interim = OptimizeResult(x=gbest_nat.copy(), fun=gbest_fit, nit=nit, nfev=evaluate.nfev)
                try:
                    stop = callback(interim)
                except StopIteration:
                    stop = True
                if stop:
                    message = "Stopped by the callback."
                    break
            if patience is not None and nit > patience and history[-1 - patience] - gbest_fit <= tol:
                message = (
                    f"Converged: best fitness improved by no more than tol={tol!r} over the last {patience} iterations."
                )
                break

    success = math.isfinite(gbest_fit)
    if not success:
        message = "No finite objective value found. " + message
    return OptimizeResult(
        x=gbest_nat,
        fun=gbest_fit,
        nit=nit,
        nfev=evaluate.nfev,
        success=success,
        message=message,
        history=np.array(history),
        x_history=np.array(x_history).reshape(nit, n_dim),
        population=pos_nat,
        population_fun=fit,
        n_chaos_improvements=n_chaos_improvements,
    )


class _Evaluator:
    """Evaluate batches of points in natural units, count calls, map NaN to +inf."""

    def __init__(self, fun, args, vectorized, mapper):
        self.fun, self.args, self.vectorized, self.mapper = fun, tuple(args), vectorized, mapper
        self.scalar = _ScalarCall(fun, self.args)
        self.nfev = 0

    def __call__(self, points: np.ndarray) -> np.ndarray:
        n = points.shape[0]
        if self.vectorized:
            out = np.asarray(self.fun(points.copy(), *self.args), dtype=float)
            self.nfev += n
            if out.shape != (n,):
                raise ValueError(
                    f"vectorized fun must return an array of shape ({n},) for input of shape "
                    f"{points.shape}, got shape {out.shape}"
                )
        else:
            out = np.array(list(self.mapper(self.scalar, [p.copy() for p in points])), dtype=float)
            self.nfev += n
        return np.where(np.isnan(out), np.inf, out)


class _ScalarCall:
    """``fun(x, *args)`` as a float; a small picklable object so process-pool maps can ship it."""

    def __init__(self, fun, args):
        self.fun, self.args = fun, args

    def __call__(self, x: np.ndarray) -> float:
        value = np.asarray(self.fun(x, *self.args), dtype=float)
        if value.size != 1:
            raise ValueError(f"fun must return a scalar, got an array of shape {value.shape}")
        return float(value.reshape(()))


def _make_mapper(workers, stack: ExitStack):
    if callable(workers):
        return workers
    if isinstance(workers, bool):
        raise ValueError(f"workers must be a positive int, -1 or a map-like callable, got {workers!r}")
    try:
        n = operator.index(workers)
    except TypeError:
        raise ValueError(f"workers must be a positive int, -1 or a map-like callable, got {workers!r}") from None
    if n == -1:
        import os

        n = os.cpu_count() or 1
    if n < 1:
        raise ValueError(f"workers must be a positive int, -1 or a map-like callable, got {workers!r}")
    if n == 1:
        return map
    return stack.enter_context(ThreadPoolExecutor(max_workers=n)).map


def _reseed_chaos(z: np.ndarray, gen: np.random.Generator, mu: float) -> np.ndarray:
    """Replace logistic-map variables that sit on (or collapsed onto) a fixed/absorbing point."""
    traps = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.0 - 1.0 / mu, 1.0 / mu])
    z = np.array(z, dtype=float)
    while True:
        bad = (
            ~np.isfinite(z)
            | (z <= 0.0)
            | (z >= 1.0)
            | np.any(np.abs(z[:, None] - traps[None, :]) <= _CHAOS_GUARD_ATOL, axis=1)
        )
        if not bad.any():
            return z
        z[bad] = gen.random(int(bad.sum()))


def _validate_bounds(bounds) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(bounds, Bounds):
        lo = np.atleast_1d(np.asarray(bounds.lb, dtype=float))
        hi = np.atleast_1d(np.asarray(bounds.ub, dtype=float))
        lo, hi = np.broadcast_arrays(lo, hi)
        lo, hi = lo.astype(float), hi.astype(float)
    else:
        try:
            arr = np.asarray(bounds, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"bounds must be a sequence of (low, high) pairs, got {bounds!r}") from None
        if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
            raise ValueError(f"bounds must be a sequence of (low, high) pairs, got {bounds!r}")
        lo, hi = arr[:, 0].copy(), arr[:, 1].copy()
    if lo.ndim != 1 or lo.size < 1:
        raise ValueError(f"bounds must describe at least one dimension, got {bounds!r}")
    for i, (a, b) in enumerate(zip(lo.tolist(), hi.tolist(), strict=False)):
        if not (math.isfinite(a) and math.isfinite(b)):
            raise ValueError(f"bounds must be finite, got ({a!r}, {b!r}) in dimension {i}")
        if not a < b:
            raise ValueError(f"bounds must have low < high, got ({a!r}, {b!r}) in dimension {i}")
    return lo, hi


def _validate_log_scale(log_scale, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    n_dim = lo.size
    if log_scale is None or isinstance(log_scale, (bool, np.bool_)):
        mask = np.full(n_dim, bool(log_scale))
    else:
        mask = np.asarray(log_scale)
        if mask.shape != (n_dim,) or mask.dtype != bool:
            raise ValueError(f"log_scale must be a bool or a sequence of {n_dim} bools, got {log_scale!r}")
    for i in np.flatnonzero(mask):
        if lo[i] <= 0:
            raise ValueError(
                f"log_scale requires positive bounds, got ({float(lo[i])!r}, {float(hi[i])!r}) in dimension {i}"
            )
    return mask


def _validate_int(name: str, value, *, minimum: int) -> int:
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}")
    try:
        n = operator.index(value)
    except TypeError:
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}") from None
    if n < minimum:
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}")
    return n


def _validate_nonnegative(name: str, value) -> None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a non-negative number, got {value!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise ValueError(f"{name} must be a non-negative number, got {value!r}")
