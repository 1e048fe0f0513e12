"""The steps of chaos particle swarm optimisation (Yu et al. 2013, eq. 13-15) as pure functions, each tested on its
own, and the :class:`Swarm` state they move; `gyrodrift.learn.cpso.CPSOSolver` runs them one generation at a time
(and documents the choices the paper leaves open: velocity clamp, absorbing walls, the chaos region and how its
result rejoins the swarm). Positions live in the search space (log10 in log-scaled dimensions), fitness in the
objective's unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Swarm", "chaos_region", "logistic_chaos_points", "pso_move", "reseed_chaos"]

# |z - p| below this counts as having landed on a fixed/absorbing point p of the logistic map.
_CHAOS_GUARD_ATOL = 1e-10


def pso_move(
    pos: np.ndarray,
    vel: np.ndarray,
    pbest: np.ndarray,
    gbest: np.ndarray,
    r1: np.ndarray,
    r2: np.ndarray,
    *,
    w: float,
    c1: float,
    c2: float,
    vmax: np.ndarray | None,
    lo: np.ndarray,
    hi: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """One PSO move (eq. 13-14) in the search space, with the velocity clamp and absorbing walls.

    ``v <- w v + c1 r1 (pbest - x) + c2 r2 (gbest - x)``, each component clamped to ``|v_i| <= vmax_i``
    (unless ``vmax`` is None), ``x <- x + v``; a coordinate that leaves ``[lo, hi]`` is clipped onto the
    bound and its velocity set to zero. Returns new ``(pos, vel)`` arrays; the inputs are not modified.
    """
    vel = w * vel + c1 * r1 * (pbest - pos) + c2 * r2 * (gbest - pos)
    if vmax is not None:
        vel = np.clip(vel, -vmax, vmax)
    pos = pos + vel
    outside = (pos < lo) | (pos > hi)
    pos = np.clip(pos, lo, hi)
    vel[outside] = 0.0
    return pos, vel


def chaos_region(
    gbest: np.ndarray, rho: float, width: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The chaos search box ``[max(lo, g - rho w), min(hi, g + rho w)]`` around ``gbest`` (clipped, never shifted)."""
    return np.maximum(lo, gbest - rho * width), np.minimum(hi, gbest + rho * width)


def logistic_chaos_points(
    z: np.ndarray, a: np.ndarray, b: np.ndarray, steps: int, mu: float, gen: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``steps`` iterates of the guarded logistic map (eq. 15) mapped onto ``[a, b]``: ``(points, z)``.

    ``z <- mu z (1 - z)``, reseeded from ``gen`` when it lands on a trap (see :class:`CPSOSolver`); each
    iterate gives the point ``a + z (b - a)``. Returns the ``(steps, n_dim)`` points and the last ``z``
    (carried over to the next iteration).
    """
    points = np.empty((steps, z.size))
    for j in range(steps):
        z = reseed_chaos(mu * z * (1.0 - z), gen, mu)  # eq. (15)
        points[j] = a + z * (b - a)
    return points, z


@dataclass
class Swarm:
    """The state of a particle swarm: positions in the search space (``pos``) and in natural units
    (``pos_nat``), velocities, fitness, personal bests and the global best."""

    pos: np.ndarray
    pos_nat: np.ndarray
    vel: np.ndarray
    fit: np.ndarray
    pbest: np.ndarray
    pbest_nat: np.ndarray
    pbest_fit: np.ndarray
    gbest: np.ndarray
    gbest_nat: np.ndarray
    gbest_fit: float

    @classmethod
    def start(cls, pos: np.ndarray, pos_nat: np.ndarray, fit: np.ndarray) -> Swarm:
        """A swarm at rest (zero velocity) whose personal bests are its positions."""
        g = int(np.argmin(fit))
        return cls(
            pos=pos,
            pos_nat=pos_nat,
            vel=np.zeros_like(pos),
            fit=fit,
            pbest=pos.copy(),
            pbest_nat=pos_nat.copy(),
            pbest_fit=fit.copy(),
            gbest=pos[g].copy(),
            gbest_nat=pos_nat[g].copy(),
            gbest_fit=float(fit[g]),
        )

    def update_bests(self) -> None:
        """Personal and global bests from the current fitness, on strict improvement only (ties keep the old)."""
        better = self.fit < self.pbest_fit
        self.pbest[better], self.pbest_nat[better], self.pbest_fit[better] = (
            self.pos[better],
            self.pos_nat[better],
            self.fit[better],
        )
        g = int(np.argmin(self.pbest_fit))
        if self.pbest_fit[g] < self.gbest_fit:
            self.gbest, self.gbest_nat, self.gbest_fit = (
                self.pbest[g].copy(),
                self.pbest_nat[g].copy(),
                float(self.pbest_fit[g]),
            )

    def accept_chaos(self, cand: np.ndarray, cand_nat: np.ndarray, cand_fit: np.ndarray) -> bool:
        """Feedback of the chaos search: the best candidate, if strictly better than ``gbest``, becomes
        ``gbest`` and replaces the worst particle (highest current fitness, lowest index on ties: position,
        fitness and personal best; its velocity is kept). Returns whether it did."""
        j = int(np.argmin(cand_fit))
        if not cand_fit[j] < self.gbest_fit:
            return False
        worst = int(np.argmax(self.fit))
        self.pos[worst], self.pos_nat[worst], self.fit[worst] = cand[j], cand_nat[j], cand_fit[j]
        self.pbest[worst], self.pbest_nat[worst], self.pbest_fit[worst] = cand[j], cand_nat[j], cand_fit[j]
        self.gbest, self.gbest_nat, self.gbest_fit = cand[j].copy(), cand_nat[j].copy(), float(cand_fit[j])
        return True


def reseed_chaos(z: np.ndarray, gen: np.random.Generator, mu: float) -> np.ndarray:
    """Replace logistic-map variables that sit on (or collapsed onto) a fixed/absorbing point (NaN or infinite, outside
    (0, 1), or within ``_CHAOS_GUARD_ATOL`` of a trap). The test runs on Python floats (the same IEEE operations as
    numpy's, a few per variable: called ten times per iteration on a handful of variables, numpy's per-call cost
    was most of its time)."""
    traps = (0.0, 0.25, 0.5, 0.75, 1.0, 1.0 - 1.0 / mu, 1.0 / mu)
    z = np.array(z, dtype=float)
    while True:
        bad = [not 0.0 < v < 1.0 or any(abs(v - t) <= _CHAOS_GUARD_ATOL for t in traps) for v in z.tolist()]
        if not any(bad):
            return z
        mask = np.array(bad, dtype=bool)
        z[mask] = gen.random(int(mask.sum()))
