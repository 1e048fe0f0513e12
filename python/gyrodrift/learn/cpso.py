"""Chaos particle swarm optimisation (CPSO), the hyperparameter tuner of Yu et al. (2013).

:class:`CPSOSolver` runs the optimisation one generation at a time, with the PSO move, the chaos search and
its feedback as separate steps (as scipy's ``DifferentialEvolutionSolver``); :func:`minimize_cpso` is the
one-call form, with the calling conventions of :func:`scipy.optimize.differential_evolution` (``bounds``,
``rng``, ``callback``, ``workers`` as a map-like callable, ``vectorized``) and an
:class:`scipy.optimize.OptimizeResult` as its answer. Integer parallelism is ``threads`` (a thread pool), not
``workers``: scipy reads an integer ``workers`` as a number of processes.

The paper gives the global-best PSO update (eq. 13-14) and the logistic map (eq. 15) and the settings
(30 particles, initial inertia 0.75, c1 = c2 = 2, at most 10 chaos iterations, at most 100 PSO
iterations); everything else (bounds handling, velocity clamp, the chaos search region and how its
result rejoins the swarm) is left open and is chosen and documented in :class:`CPSOSolver`.
"""

from __future__ import annotations

import math
import operator
import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from gyrodrift.errors import OptionError
from gyrodrift.learn.swarm import Swarm, chaos_region, logistic_chaos_points, pso_move, reseed_chaos

if TYPE_CHECKING:  # scipy.optimize is imported where a result is made: ~0.3 s of every learning command's start
    from scipy.optimize import OptimizeResult

__all__ = ["CPSOSettings", "CPSOSolver", "check_seed", "minimize_cpso"]

Mapper = Callable[[Callable[[np.ndarray], float], Iterable[np.ndarray]], Iterable[float]]


@dataclass(frozen=True)
class CPSOSettings:
    """The swarm's numbers, checked when made (`OptionError` naming the field); the defaults are the paper's where
    it gives one (Yu et al. 2013: 30 particles, initial inertia 0.75, c1 = c2 = 2, at most 10 chaos iterations, at
    most 100 PSO iterations). :class:`CPSOSolver` describes the algorithm that uses them.

    Attributes
    ----------
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
    tol : float, default 0.0
        Used with ``patience``: stop when the best fitness improved by no more than ``tol`` (absolute)
        over the last ``patience`` iterations.
    patience : int or None, default None
        Number of iterations for the ``tol`` rule; ``None`` always runs ``max_iter`` iterations.
    """

    n_particles: int = 30
    max_iter: int = 100
    w: float = 0.75
    inertia: str = "constant"
    w_end: float = 0.4
    c1: float = 2.0
    c2: float = 2.0
    chaos_steps: int = 10
    mu: float = 4.0
    chaos_radius: float = 0.1
    chaos_radius_end: float = 1e-6
    vmax_frac: float | None = 0.2
    tol: float = 0.0
    patience: int | None = None

    def __post_init__(self) -> None:
        def keep(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        keep("n_particles", _validate_int("n_particles", self.n_particles, minimum=2))
        keep("max_iter", _validate_int("max_iter", self.max_iter, minimum=1))
        keep("chaos_steps", _validate_int("chaos_steps", self.chaos_steps, minimum=0))
        for name in ("w", "w_end", "c1", "c2", "tol"):
            _validate_nonnegative(name, getattr(self, name))
        keep("mu", float(self.mu))
        if not (2.0 < self.mu <= 4.0):
            raise OptionError(f"mu must be in (2, 4], got {self.mu!r}")
        if self.inertia not in ("constant", "linear"):
            raise OptionError(f"inertia must be 'constant' or 'linear', got {self.inertia!r}")
        if not (0.0 < self.chaos_radius <= 1.0):
            raise OptionError(f"chaos_radius must be in (0, 1], got {self.chaos_radius!r}")
        if not (0.0 < self.chaos_radius_end <= self.chaos_radius):
            raise OptionError(
                f"chaos_radius_end must be in (0, chaos_radius={self.chaos_radius!r}], got {self.chaos_radius_end!r}"
            )
        vmax_frac = self.vmax_frac
        if vmax_frac is not None and not (math.isfinite(vmax_frac) and vmax_frac > 0):
            raise OptionError(f"vmax_frac must be a positive finite number or None, got {vmax_frac!r}")
        if self.patience is not None:
            keep("patience", _validate_int("patience", self.patience, minimum=1))


def minimize_cpso(
    fun: Callable[..., Any],
    bounds,
    *,
    args: tuple = (),
    n_particles: int = CPSOSettings.n_particles,
    max_iter: int = CPSOSettings.max_iter,
    w: float = CPSOSettings.w,
    inertia: str = CPSOSettings.inertia,
    w_end: float = CPSOSettings.w_end,
    c1: float = CPSOSettings.c1,
    c2: float = CPSOSettings.c2,
    chaos_steps: int = CPSOSettings.chaos_steps,
    mu: float = CPSOSettings.mu,
    chaos_radius: float = CPSOSettings.chaos_radius,
    chaos_radius_end: float = CPSOSettings.chaos_radius_end,
    vmax_frac: float | None = CPSOSettings.vmax_frac,
    tol: float = CPSOSettings.tol,
    patience: int | None = CPSOSettings.patience,
    log_scale: bool | Sequence[bool] | None = None,
    vectorized: bool = False,
    workers: int | Mapper = 1,
    threads: int = 1,
    rng: int | np.random.Generator | None = None,
    callback: Callable[[OptimizeResult], bool | None] | None = None,
) -> OptimizeResult:
    """Minimise ``fun`` over a box with chaos particle swarm optimisation (Yu et al. 2013, eq. 13-15).

    ``CPSOSolver(fun, bounds, CPSOSettings(n_particles, ..., patience), args=..., ...).solve()``: the swarm's
    numbers are :class:`CPSOSettings`'s fields of the same names (defaults, units and limits there), the algorithm
    and the result are :class:`CPSOSolver`'s.

    Parameters
    ----------
    bounds : sequence of (low, high) or scipy.optimize.Bounds
        Finite box, ``low < high`` in each dimension, in natural units (also for log-scaled dimensions).
    args : tuple
        Extra positional arguments for ``fun``.
    log_scale : bool or sequence of bool, optional
        Search these dimensions in ``log10`` space (bounds must then be positive). Positions, velocities,
        the velocity clamp and the chaos region all live in the search space; ``fun`` and the result are
        in natural units (clipped to the bounds after ``10**s`` so round-off never leaves the box).
    vectorized : bool, default False
        Call ``fun`` once per batch with a 2-D array (see ``fun``). The returned array must have shape
        ``(S,)``; anything else raises ``ValueError``. Gives the same result as ``vectorized=False`` for
        the same seed when ``fun`` computes each row as the scalar version would.
    workers : 1 or map-like callable, default 1
        ``1``: evaluate in the calling thread. A map-like callable (e.g. ``multiprocessing.Pool(4).map`` or
        ``ProcessPoolExecutor(4).map`` for a picklable ``fun``) is used as ``workers(fun, points)`` and must
        return results in order. Unlike :func:`scipy.optimize.differential_evolution`, an integer
        ``workers > 1`` is refused rather than read as a number of *processes*: threads are asked for
        with ``threads``, processes by passing a pool's ``map``.
    threads : int, default 1
        Evaluate each batch on a thread pool of this many threads (useful when ``fun`` releases the GIL,
        as NumPy/LAPACK-heavy objectives do); ``-1``: one thread per CPU; ``1``: no pool. Not together
        with ``workers`` or ``vectorized=True``. Evaluation order never changes the result: all random
        numbers are drawn in the calling thread and results are gathered in point order.
    rng : int, numpy.random.Generator or None
        Seed or generator; the same seed gives a bitwise identical result. No global state is used.
    callback : callable, optional
        ``callback(intermediate_result)`` once per iteration with an ``OptimizeResult`` holding ``x``,
        ``fun``, ``nit``, ``nfev``. Returning ``True`` or raising ``StopIteration`` stops the run with
        ``success=True`` and a message saying so.
    n_particles, max_iter, w, inertia, w_end, c1, c2, chaos_steps, mu, chaos_radius, chaos_radius_end, vmax_frac, \
tol, patience
        The swarm's numbers (:class:`CPSOSettings`).

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``nit``, ``nfev``, ``success``, ``message``, ``history``, ``x_history``, ``population``,
        ``population_fun``, ``n_chaos_improvements`` (:class:`CPSOSolver`).
    """
    settings = CPSOSettings(
        n_particles=n_particles,
        max_iter=max_iter,
        w=w,
        inertia=inertia,
        w_end=w_end,
        c1=c1,
        c2=c2,
        chaos_steps=chaos_steps,
        mu=mu,
        chaos_radius=chaos_radius,
        chaos_radius_end=chaos_radius_end,
        vmax_frac=vmax_frac,
        tol=tol,
        patience=patience,
    )
    with CPSOSolver(
        fun,
        bounds,
        settings,
        args=args,
        log_scale=log_scale,
        vectorized=vectorized,
        workers=workers,
        threads=threads,
        rng=rng,
        callback=callback,
    ) as solver:
        return solver.solve()


# --------------------------------------------------------------------------------------------------
# The solver
# --------------------------------------------------------------------------------------------------


class CPSOSolver:
    r"""Chaos particle swarm optimisation of ``fun`` over a box (Yu et al. 2013, eq. 13-15), one generation at a time.

    Used as ``with CPSOSolver(fun, bounds, ...) as solver: result = solver.solve()``, or iterated
    (``for x, f in solver: ...``, one PSO iteration per item, as scipy's ``DifferentialEvolutionSolver``).
    Each phase is a method of its own (:meth:`init_population`, :meth:`pso_move`, :meth:`update_bests`,
    :meth:`chaos_search`, :meth:`chaos_feedback`), built on pure step functions (:func:`pso_move`,
    :func:`chaos_region`, :func:`logistic_chaos_points`) and the :class:`Swarm` state, each tested alone.

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
       objective), so ``vectorized``, ``workers`` and ``threads`` apply to them as well; all count in ``nfev``.
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
    fun, bounds, args, log_scale, vectorized, workers, threads, rng, callback
        As :func:`minimize_cpso`.
    settings : CPSOSettings, optional
        The swarm's numbers (swarm size, iterations, weights, chaos search, stopping rule); None: the
        defaults (the paper's).

    Attributes
    ----------
    swarm : Swarm
        The current swarm (search-space and natural positions, velocities, fitness, personal and global
        bests); ``None`` before :meth:`init_population`.
    nit : int
        Iterations done. ``history``, ``x_history``, ``n_chaos_improvements`` and ``message`` as in the
        result.

    The result (:meth:`result`, :meth:`solve`) is an ``OptimizeResult`` holding ``x`` (best point, natural
    units), ``fun`` (its fitness, ``fun(x)`` exactly), ``nit``, ``nfev`` (every call of ``fun``, chaos ones
    included; each row counts once when vectorized), ``success`` (``False`` only if no finite fitness was
    ever found), ``message``, ``history`` (best fitness after each iteration, shape ``(nit,)``,
    non-increasing, ``history[-1] == fun``), ``x_history`` (best point after each iteration,
    ``(nit, n_dim)``), ``population`` and ``population_fun`` (final swarm positions in natural units and
    their fitness), ``n_chaos_improvements`` (iterations in which the chaos search improved ``gbest``).

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

    def __init__(
        self,
        fun: Callable[..., Any],
        bounds,
        settings: CPSOSettings | None = None,
        *,
        args: tuple = (),
        log_scale: bool | Sequence[bool] | None = None,
        vectorized: bool = False,
        workers: int | Mapper = 1,
        threads: int = 1,
        rng: int | np.random.Generator | None = None,
        callback: Callable[[OptimizeResult], bool | None] | None = None,
    ) -> None:
        self.settings = CPSOSettings() if settings is None else settings
        if not isinstance(self.settings, CPSOSettings):
            raise OptionError(f"settings must be a CPSOSettings, got {settings!r}")
        self.lo_nat, self.hi_nat = _validate_bounds(bounds)
        self.n_dim = self.lo_nat.size
        self.log_mask = _validate_log_scale(log_scale, self.lo_nat, self.hi_nat)
        if callback is not None and not callable(callback):
            raise OptionError(f"callback must be callable or None, got {callback!r}")
        self.callback = callback
        if not callable(fun):
            raise OptionError(f"fun must be callable, got {fun!r}")
        self.vectorized = bool(vectorized)
        n_threads = _validate_threads(threads)
        if not callable(workers) and (isinstance(workers, bool) or workers != 1):
            raise OptionError(
                f"workers must be 1 or a map-like callable, got {workers!r} (scipy reads an integer as a number "
                "of processes: pass threads=n for a thread pool, or workers=pool.map for a process pool)"
            )
        if self.vectorized and (workers != 1 or n_threads != 1):
            raise OptionError(
                f"workers and threads must be 1 when vectorized=True, got workers={workers!r}, threads={threads!r}"
            )
        if callable(workers) and n_threads != 1:
            raise OptionError(f"give workers (a map-like callable) or threads, not both (threads={threads!r})")

        self._gen = np.random.default_rng(check_seed(rng, "rng"))
        # Search space: log10 in the log-scaled dimensions, natural elsewhere.
        lo_nat, hi_nat, log_mask = self.lo_nat, self.hi_nat, self.log_mask
        self.lo = np.where(log_mask, np.log10(lo_nat, where=log_mask, out=lo_nat.copy()), lo_nat)
        self.hi = np.where(log_mask, np.log10(hi_nat, where=log_mask, out=hi_nat.copy()), hi_nat)
        self.width = self.hi - self.lo
        vmax_frac = self.settings.vmax_frac
        self.vmax = None if vmax_frac is None else vmax_frac * self.width

        self._stack = ExitStack()
        mapper: Mapper = workers if callable(workers) else map
        if n_threads > 1:
            mapper = self._stack.enter_context(ThreadPoolExecutor(max_workers=n_threads)).map
        self._evaluate = _Evaluator(fun, args, self.vectorized, mapper)

        self.swarm: Swarm | None = None
        self._chaos_gen: np.random.Generator | None = None
        self._z: np.ndarray | None = None
        self.nit = 0
        self.history: list[float] = []
        self.x_history: list[np.ndarray] = []
        self.n_chaos_improvements = 0
        self.message = "Maximum number of iterations reached."
        self._stopped = False

    # -- context management (the thread pool, if any) ---------------------------------------------
    def __enter__(self) -> CPSOSolver:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        """Shut down the thread pool (if any); the solver can still report its result."""
        self._stack.close()

    # -- phases --------------------------------------------------------------------------------------
    @property
    def nfev(self) -> int:
        """Objective evaluations so far (each row counts once when vectorized)."""
        return self._evaluate.nfev

    def to_natural(self, s: np.ndarray) -> np.ndarray:
        """Search-space points to natural units (``10**s`` in log dimensions), clipped to the bounds."""
        x = s.copy()
        x[..., self.log_mask] = 10.0 ** s[..., self.log_mask]
        return np.clip(x, self.lo_nat, self.hi_nat)

    def init_population(self) -> Swarm:
        """Phase 0: a swarm uniform in the search box at rest, evaluated; the chaos map's own stream."""
        pos = self.lo + self._gen.random((self.settings.n_particles, self.n_dim)) * self.width
        pos_nat = self.to_natural(pos)
        self.swarm = Swarm.start(pos, pos_nat, self._evaluate(pos_nat))
        # The chaos map gets its own stream, drawn whether or not it is used, so that a run with
        # chaos_steps=0 moves its swarm with exactly the random numbers of the chaos run (paired runs).
        self._chaos_gen = np.random.default_rng(self._gen.integers(0, 2**63))
        if self.settings.chaos_steps:
            self._z = reseed_chaos(self._chaos_gen.random(self.n_dim), self._chaos_gen, self.settings.mu)
        return self.swarm

    def schedule_fraction(self, k: int) -> float:
        """``(k - 1) / (max_iter - 1)``: where iteration ``k`` lies between the first and the last (0 to 1)."""
        return (k - 1) / (self.settings.max_iter - 1) if self.settings.max_iter > 1 else 0.0

    def inertia_weight(self, k: int) -> float:
        """Inertia ``w_k`` of iteration ``k`` (constant, or linear from ``w`` to ``w_end``)."""
        return (
            self.settings.w
            if self.settings.inertia == "constant"
            else self.settings.w - (self.settings.w - self.settings.w_end) * self.schedule_fraction(k)
        )

    def chaos_radius_at(self, k: int) -> float:
        """``rho_k``: the chaos region's half-width as a fraction of the search width, geometric in ``k``."""
        return self.settings.chaos_radius * (
            self.settings.chaos_radius_end / self.settings.chaos_radius
        ) ** self.schedule_fraction(k)

    def pso_move(self, k: int) -> None:
        """Phase 1 of iteration ``k``: draw ``r1``, ``r2`` and move the swarm (:func:`pso_move`)."""
        s = self._require_swarm()
        r1 = self._gen.random((self.settings.n_particles, self.n_dim))
        r2 = self._gen.random((self.settings.n_particles, self.n_dim))
        s.pos, s.vel = pso_move(
            s.pos,
            s.vel,
            s.pbest,
            s.gbest,
            r1,
            r2,
            w=self.inertia_weight(k),
            c1=self.settings.c1,
            c2=self.settings.c2,
            vmax=self.vmax,
            lo=self.lo,
            hi=self.hi,
        )

    def update_bests(self) -> None:
        """Phase 2: evaluate the moved swarm and update personal and global bests."""
        s = self._require_swarm()
        s.pos_nat = self.to_natural(s.pos)
        s.fit = self._evaluate(s.pos_nat)
        s.update_bests()

    def chaos_search(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Phase 3 of iteration ``k``: the ``chaos_steps`` chaos candidates around ``gbest``, evaluated as one
        batch: ``(search-space points, natural points, fitness)``."""
        s = self._require_swarm()
        assert self._z is not None and self._chaos_gen is not None, "chaos search needs chaos_steps > 0"
        a, b = chaos_region(s.gbest, self.chaos_radius_at(k), self.width, self.lo, self.hi)
        cand, self._z = logistic_chaos_points(
            self._z, a, b, self.settings.chaos_steps, self.settings.mu, self._chaos_gen
        )
        cand = np.clip(cand, self.lo, self.hi)
        cand_nat = self.to_natural(cand)
        return cand, cand_nat, self._evaluate(cand_nat)

    def chaos_feedback(self, cand: np.ndarray, cand_nat: np.ndarray, cand_fit: np.ndarray) -> bool:
        """Phase 4: let an improving chaos candidate into the swarm (:meth:`Swarm.accept_chaos`)."""
        accepted = self._require_swarm().accept_chaos(cand, cand_nat, cand_fit)
        self.n_chaos_improvements += int(accepted)
        return accepted

    # -- iteration -----------------------------------------------------------------------------------
    def __iter__(self) -> Iterator[tuple[np.ndarray, float]]:
        return self

    def __next__(self) -> tuple[np.ndarray, float]:
        """One generation (move, bests, chaos search and feedback, record, callback, stopping rules).

        Returns the best point (natural units) and its fitness; ``StopIteration`` after ``max_iter``
        iterations or once the callback or the ``tol``/``patience`` rule stopped the run.
        """
        if self.swarm is None:
            self.init_population()
        if self._stopped or self.nit >= self.settings.max_iter:
            self.close()
            raise StopIteration
        k = self.nit + 1
        self.pso_move(k)
        self.update_bests()
        if self.settings.chaos_steps:
            self.chaos_feedback(*self.chaos_search(k))
        s = self._require_swarm()
        self.nit = k
        self.history.append(s.gbest_fit)
        self.x_history.append(s.gbest_nat.copy())
        if self.callback is not None:
            from scipy.optimize import OptimizeResult

            interim = OptimizeResult(x=s.gbest_nat.copy(), fun=s.gbest_fit, nit=self.nit, nfev=self.nfev)
            try:
                stop = self.callback(interim)
            except StopIteration:
                stop = True
            if stop:
                self.message = "Stopped by the callback."
                self._stopped = True
        if (
            not self._stopped
            and self.settings.patience is not None
            and self.nit > self.settings.patience
            and self.history[-1 - self.settings.patience] - s.gbest_fit <= self.settings.tol
        ):
            self.message = (
                f"Converged: best fitness improved by no more than tol={self.settings.tol!r} over the last "
                f"{self.settings.patience} iterations."
            )
            self._stopped = True
        return s.gbest_nat.copy(), s.gbest_fit

    def solve(self) -> OptimizeResult:
        """Run the remaining generations and return :meth:`result`."""
        for _ in self:
            pass
        return self.result()

    def result(self) -> OptimizeResult:
        """The ``OptimizeResult`` of the generations run so far (see the class docstring)."""
        from scipy.optimize import OptimizeResult

        s = self._require_swarm()
        success = math.isfinite(s.gbest_fit)
        message = self.message if success else "No finite objective value found. " + self.message
        return OptimizeResult(
            x=s.gbest_nat,
            fun=s.gbest_fit,
            nit=self.nit,
            nfev=self.nfev,
            success=success,
            message=message,
            history=np.array(self.history),
            x_history=np.array(self.x_history).reshape(self.nit, self.n_dim),
            population=s.pos_nat,
            population_fun=s.fit,
            n_chaos_improvements=self.n_chaos_improvements,
        )

    def _require_swarm(self) -> Swarm:
        if self.swarm is None:
            raise RuntimeError("call init_population() first")
        return self.swarm


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
                raise OptionError(
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
            raise OptionError(f"fun must return a scalar, got an array of shape {value.shape}")
        return float(value.reshape(()))


def _validate_threads(threads) -> int:
    message = f"threads must be a positive int or -1, got {threads!r}"
    if isinstance(threads, bool):
        raise OptionError(message)
    try:
        n = operator.index(threads)
    except TypeError:
        raise OptionError(message) from None
    if n == -1:
        return os.cpu_count() or 1
    if n < 1:
        raise OptionError(message)
    return n


def _validate_bounds(bounds) -> tuple[np.ndarray, np.ndarray]:
    from scipy.optimize import Bounds

    if isinstance(bounds, Bounds):
        lo = np.atleast_1d(np.asarray(bounds.lb, dtype=float))
        hi = np.atleast_1d(np.asarray(bounds.ub, dtype=float))
        lo, hi = np.broadcast_arrays(lo, hi)
        lo, hi = lo.astype(float), hi.astype(float)
    else:
        try:
            arr = np.asarray(bounds, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"bounds must be a sequence of (low, high) pairs, got {bounds!r}") from None
        if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
            raise OptionError(f"bounds must be a sequence of (low, high) pairs, got {bounds!r}")
        lo, hi = arr[:, 0].copy(), arr[:, 1].copy()
    if lo.ndim != 1 or lo.size < 1:
        raise OptionError(f"bounds must describe at least one dimension, got {bounds!r}")
    for i, (a, b) in enumerate(zip(lo.tolist(), hi.tolist(), strict=False)):
        if not (math.isfinite(a) and math.isfinite(b)):
            raise OptionError(f"bounds must be finite, got ({a!r}, {b!r}) in dimension {i}")
        if not a < b:
            raise OptionError(f"bounds must have low < high, got ({a!r}, {b!r}) in dimension {i}")
    return lo, hi


def _validate_log_scale(log_scale, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    n_dim = lo.size
    if log_scale is None or isinstance(log_scale, (bool, np.bool_)):
        mask = np.full(n_dim, bool(log_scale))
    else:
        mask = np.asarray(log_scale)
        if mask.shape != (n_dim,) or mask.dtype != bool:
            raise OptionError(f"log_scale must be a bool or a sequence of {n_dim} bools, got {log_scale!r}")
    for i in np.flatnonzero(mask):
        if lo[i] <= 0:
            raise OptionError(
                f"log_scale requires positive bounds, got ({float(lo[i])!r}, {float(hi[i])!r}) in dimension {i}"
            )
    return mask


def check_seed(seed, name: str = "seed"):
    """`seed` as it is if it is None or a numpy generator, seed sequence or bit generator; an integer seed must be
    an int >= 0 (not a bool): anything else is an `OptionError` naming `name` (numpy's own refusal of -1 is a
    ValueError deep in `SeedSequence`)."""
    if seed is None or isinstance(seed, (np.random.Generator, np.random.SeedSequence, np.random.BitGenerator)):
        return seed
    return _validate_int(name, seed, minimum=0)


def _validate_int(name: str, value, *, minimum: int) -> int:
    if isinstance(value, (bool, np.bool_)):
        raise OptionError(f"{name} must be an int >= {minimum}, got {value!r}")
    try:
        n = operator.index(value)
    except TypeError:
        raise OptionError(f"{name} must be an int >= {minimum}, got {value!r}") from None
    if n < minimum:
        raise OptionError(f"{name} must be an int >= {minimum}, got {value!r}")
    return n


def _validate_nonnegative(name: str, value) -> None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{name} must be a non-negative number, got {value!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise OptionError(f"{name} must be a non-negative number, got {value!r}")
