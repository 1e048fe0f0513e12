"""Allan deviation of a static IMU log and the noise parameters that scenario files take, where the log shows them.

The overlapping Allan deviation (computed by `allantools.oadev`, octave-spaced averaging times) of each gyro and
accelerometer axis is fitted, in Allan variance, by the sum of the noise terms the simulator draws
(see docs/scenarios.md, ``[gyro]`` and ``[accel]``):

* white rate noise (angle / velocity random walk) N:   AVAR = N^2 / tau
* a first-order Gauss-Markov bias, sigma s, correlation time T:
  AVAR = (2 s^2 T / tau) [1 - T / (2 tau) (3 - 4 exp(-tau / T) + exp(-2 tau / T))]
* rate random walk K:                                  AVAR = K^2 tau / 3

Confidence intervals: each Allan deviation point gets Greenhall's equivalent degrees of freedom (edf,
`allantools.edf_greenhall`, overlapping ADEV) for the noise type that dominates the fitted curve at that tau
(white rate noise alpha 0, flicker -1, random walk -2, from the local slope of the fit), and from it the
chi-squared interval (`allantools.confidence_interval`): `CONFIDENCE_PLOT` (1 sigma) for the plot,
`CONFIDENCE` (99 % for the whole curve) to decide which terms the log shows.

The fit: each measured Allan variance is chi-squared with its edf degrees of freedom around the true one; for
each T on a log grid the variance is linear in (N^2, s^2, K^2), fitted by iteratively reweighted non-negative
least squares (the Gamma quasi-likelihood), and the T of the smallest deviance wins.

Which terms the log shows: starting from all three, a term is dropped while the fit without it leaves no more
points outside the `CONFIDENCE` interval of the Allan deviation than the fit with it (the Gauss-Markov term
first when either could go: it has two parameters). A term is reported only if the data at some averaging
time the log reaches rise above what the other terms explain, beyond the confidence interval. A Gauss-Markov
correlation time T is fitted between the shortest averaging time and a quarter of the longest: its Allan
deviation peaks near 1.9 T, and only its fall beyond the peak tells it from a rate random walk.
A term the log does not show is `None` with the reason in `AxisNoise.not_resolved`, never a number. The
classical "bias instability" of the IEEE standards (the flat floor, min ADEV / 0.664) is reported only where
the fitted curve has its minimum inside the measured averaging times (a resolved Gauss-Markov or rate random
walk term bends it up there); on a curve still falling at its longest tau the floor is not reached.

Constant channels (every increment equal: a dead or synthetic axis) have no noise to measure: they are named
and left out (`AllanResult.constant_axes`), and a log whose six channels are all constant is refused.

Units: gyro rates in rad/s inside, reported in deg/h (ADEV), deg/sqrt(h) (ARW), deg/h (Gauss-Markov sigma),
deg/h/sqrt(h) (RRW); specific force in m/s^2 inside, reported in ug (ADEV), ug/sqrt(Hz) (VRW).

The log must be static with the turntable still (rotation off): a turning table puts the table rate in the
z gyro and modulates the Earth rate on x and y, which is not sensor noise. The constant Earth rate and
gravity are constants, invisible to the Allan deviation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.errors import InputError, MissingExtraError

__all__ = [
    "AxisNoise",
    "AllanResult",
    "CONFIDENCE",
    "CONFIDENCE_PLOT",
    "allan_deviation",
    "allan_edf",
    "fit_noise",
    "gauss_markov_avar",
    "scenario_noise_axes",
    "scenario_noise_block",
    "MAX_TABLE_RATE_DEG_S",
]

_DEG = math.pi / 180.0
_UG = 9.80665e-6
_RAD_S_TO_DEG_H = 3600.0 / _DEG
_BIAS_INSTABILITY_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # 0.664: flicker floor of ADEV / B

MAX_TABLE_RATE_DEG_S = 0.01
"""Largest spread [deg/s] of the 1 s mean z rate accepted as a still turntable (Earth rate is 0.0042 deg/s)."""

CONFIDENCE = 0.99
"""Two-sided confidence of the Allan deviation band a noise term must rise above to be reported: for the whole
curve, each of its n points at 1 - 0.01 / n (Bonferroni), so that pure white noise rarely shows a spurious term."""

CONFIDENCE_PLOT = 0.6826894921370859
"""Confidence of the interval plotted and written as ``adev_lo``/``adev_hi`` (1 sigma)."""

_MAX_BASE_POINTS = 2_000_000
_REWEIGHTINGS = 4
_GM_REACH = 4.0
"""A Gauss-Markov correlation time T is fitted only up to the longest averaging time / 4: its Allan deviation
peaks near 1.9 T and only the fall beyond tells it from a rate random walk, so the log must reach past it."""
_LP_MARGIN = 1e-4
"""Above HiGHS' tolerance on the summed slacks: a lower bound that far over a threshold proves the LP exceeds it."""
_TERMS = ("white", "gauss_markov", "rrw")
# the JSON keys of white, gauss_markov, rrw and bias_instability
_GYRO_KEYS = ("arw_deg_rth", "gauss_markov_sigma_deg_h", "rrw_deg_h_rth", "bias_instability_deg_h")
_ACCEL_KEYS = ("vrw_ug_rthz", "gauss_markov_sigma_ug", "rrw_ug_per_s_rts", "bias_instability_ug")
_NAMES = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")


def gauss_markov_avar(tau_s: np.ndarray, sigma: float, correlation_s: float) -> np.ndarray:
    """Allan variance of a first-order Gauss-Markov process of stationary std `sigma` and correlation time
    `correlation_s` [s], at averaging times `tau_s` [s] (same unit squared as `sigma`)."""
    x = np.asarray(tau_s, dtype=float) / correlation_s
    bracket = 1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x)
    small = x < 1e-3  # series 1 - ... = x^2/3 - x^3/12 avoids cancellation
    bracket = np.where(small, x * x / 3.0 - x**3 / 12.0, bracket)
    return 2.0 * sigma**2 * correlation_s / np.asarray(tau_s, dtype=float) * bracket


def _avar(tau: np.ndarray, white: float, gm_sigma: float, gm_correlation_s: float, rrw: float) -> np.ndarray:
    avar = white**2 / tau + rrw**2 * tau / 3.0
    if gm_sigma > 0.0:
        avar = avar + gauss_markov_avar(tau, gm_sigma, gm_correlation_s)
    return avar


@dataclass(frozen=True)
class AxisNoise:
    """The Allan deviation of one axis and the noise terms the log shows, all in SI (rad/s or m/s^2 based).

    Attributes
    ----------
    axis : str
        ``gyro_x`` ... ``accel_z``.
    tau_s, adev : ndarray
        Averaging times [s] and overlapping Allan deviation [rad/s or m/s^2].
    edf : ndarray
        Greenhall's equivalent degrees of freedom of each point.
    adev_lo, adev_hi : ndarray
        Its `CONFIDENCE_PLOT` (1 sigma) confidence interval.
    white : float or None
        N [rad/sqrt(s) or m/s/sqrt(s)]: ARW / VRW.
    gm_sigma, gm_correlation_s : float or None
        Gauss-Markov bias std [rad/s or m/s^2] and correlation time [s].
    rrw : float or None
        K [rad/s/sqrt(s) or m/s^2/sqrt(s)].
    bias_instability : float or None
        Classical flicker floor min(ADEV) / 0.664 [rad/s or m/s^2].
    not_resolved : dict
        For each of ``white``, ``gauss_markov``, ``rrw``, ``bias_instability`` that is None: why.
    fit_rms_log : float
        RMS of log(model ADEV / measured ADEV) over the points (0.05 = 5 %).
    """

    axis: str
    tau_s: np.ndarray
    adev: np.ndarray
    edf: np.ndarray
    adev_lo: np.ndarray
    adev_hi: np.ndarray
    white: float | None
    gm_sigma: float | None
    gm_correlation_s: float | None
    rrw: float | None
    bias_instability: float | None
    not_resolved: dict[str, str]
    fit_rms_log: float

    def model_adev(self, tau_s: np.ndarray) -> np.ndarray:
        """The Allan deviation of the reported terms at `tau_s` [s] (a term not resolved counts 0)."""
        return np.sqrt(
            _avar(
                np.asarray(tau_s, dtype=float),
                self.white or 0.0,
                self.gm_sigma or 0.0,
                self.gm_correlation_s or 1.0,
                self.rrw or 0.0,
            )
        )


@dataclass(frozen=True)
class AllanResult:
    """Allan deviations and noise fits of the axes of one static log.

    Attributes
    ----------
    log : str
        The log's file name.
    rate_hz, duration_s, base_tau_s : float
        Sample rate [Hz], length [s], and the shortest averaging time used [s] (a multiple of the sample
        interval when a long log is thinned to at most 2 million phase points).
    axes : list of AxisNoise
        The axes that vary, in the order gyro x, y, z, accel x, y, z.
    constant_axes : dict
        Axes whose every increment is the same, left out: name -> their constant rate [rad/s or m/s^2].
    """

    log: str
    rate_hz: float
    duration_s: float
    base_tau_s: float
    axes: list[AxisNoise] = field(default_factory=list)
    constant_axes: dict[str, float] = field(default_factory=dict)

    def axis(self, name: str) -> AxisNoise:
        """The `AxisNoise` called `name` (``gyro_x`` ... ``accel_z``); KeyError for a constant axis."""
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary in user units (deg/h, deg/sqrt(h), ug, ug/sqrt(Hz)); a term the log does not
        show is null, with the reason under the axis' ``not_resolved`` (keyed by the term's JSON key; the
        Gauss-Markov correlation time is null with its sigma)."""

        def scaled(v: float | None, k: float) -> float | None:
            return None if v is None else v * k

        axes: dict[str, dict[str, Any]] = {}
        for a in self.axes:
            entry: dict[str, Any]
            if a.axis.startswith("gyro"):
                k, unit = _RAD_S_TO_DEG_H, "deg_h"
                keys = dict(zip((*_TERMS, "bias_instability"), _GYRO_KEYS, strict=True))
                entry = {
                    "arw_deg_rth": scaled(a.white, 60.0 / _DEG),
                    "bias_instability_deg_h": scaled(a.bias_instability, k),
                    "gauss_markov_sigma_deg_h": scaled(a.gm_sigma, k),
                    "rrw_deg_h_rth": scaled(a.rrw, k * 60.0),
                }
            else:
                k, unit = 1.0 / _UG, "ug"
                keys = dict(zip((*_TERMS, "bias_instability"), _ACCEL_KEYS, strict=True))
                entry = {
                    "vrw_ug_rthz": scaled(a.white, k),
                    "bias_instability_ug": scaled(a.bias_instability, k),
                    "gauss_markov_sigma_ug": scaled(a.gm_sigma, k),
                    "rrw_ug_per_s_rts": scaled(a.rrw, k),
                }
            entry = {
                "tau_s": a.tau_s.tolist(),
                f"adev_{unit}": (a.adev * k).tolist(),
                f"adev_lo_{unit}": (a.adev_lo * k).tolist(),
                f"adev_hi_{unit}": (a.adev_hi * k).tolist(),
                "edf": a.edf.tolist(),
                **entry,
                "gauss_markov_correlation_s": a.gm_correlation_s,
                "not_resolved": {keys[t]: why for t, why in a.not_resolved.items()},
                "fit_rms_log": a.fit_rms_log,
            }
            axes[a.axis] = entry
        constant = {
            name: {"value_deg_h": v * _RAD_S_TO_DEG_H} if name.startswith("gyro") else {"value_ug": v / _UG}
            for name, v in self.constant_axes.items()
        }
        return {
            "format": "gyrodrift-allan/2",
            "log": self.log,
            "rate_hz": self.rate_hz,
            "duration_s": self.duration_s,
            "base_tau_s": self.base_tau_s,
            "confidence": CONFIDENCE,
            "axes": axes,
            "constant_axes": constant,
            "scenario_noise": scenario_noise_block(self),
            "scenario_noise_axes": scenario_noise_axes(self),
        }


# scenario key -> (sensor, AxisNoise attribute, factor from SI)
_SCENARIO_KEYS = {
    "arw_deg_rth": ("gyro", "white", 60.0 / _DEG),
    "bias_instability_deg_h": ("gyro", "gm_sigma", _RAD_S_TO_DEG_H),
    "rrw_deg_h_rth": ("gyro", "rrw", _RAD_S_TO_DEG_H * 60.0),
    "vrw_ug_rthz": ("accel", "white", 1.0 / _UG),
}


def scenario_noise_axes(result: AllanResult) -> dict[str, dict[str, list[str]]]:
    """For each key of `scenario_noise_block`, the axes whose value it averages (empty: no axis shows the term,
    the key is 0). ``correlation_s`` goes with ``bias_instability_deg_h``."""
    out: dict[str, dict[str, list[str]]] = {"gyro": {}, "accel": {}}
    for key, (sensor, attr, _) in _SCENARIO_KEYS.items():
        used = [a.axis for a in result.axes if a.axis.startswith(sensor) and getattr(a, attr) is not None]
        out[sensor][key] = used
        if key == "bias_instability_deg_h":
            out[sensor]["correlation_s"] = used
    return out


def scenario_noise_block(result: AllanResult) -> dict[str, dict[str, float]]:
    """The ``[gyro]`` / ``[accel]`` noise keys of a scenario file matching the log.

    Each key is the mean over the axes that show the term (`scenario_noise_axes` names them; constant axes
    and axes where the term is not resolved are left out); a term no axis shows is 0, the simulator's "none"
    (``correlation_s`` is then left out). The simulator draws one noise level for all three axes; the per-axis
    values are in `AllanResult`. Accelerometer bias drift (Gauss-Markov, RRW) has no scenario key.
    """
    block: dict[str, dict[str, float]] = {"gyro": {}, "accel": {}}
    for key, (sensor, attr, factor) in _SCENARIO_KEYS.items():
        values = [getattr(a, attr) for a in result.axes if a.axis.startswith(sensor) and getattr(a, attr) is not None]
        block[sensor][key] = float(np.mean(values)) * factor if values else 0.0
        if key == "bias_instability_deg_h" and values:
            corr = [a.gm_correlation_s for a in result.axes if a.axis.startswith("gyro") and a.gm_correlation_s]
            block[sensor]["correlation_s"] = float(np.exp(np.mean(np.log(corr))))
    return block


def _allantools() -> Any:
    """allantools, the optional extra behind `gyrodrift allan` (``pip install "gyrodrift[allan]"``)."""
    try:
        import allantools
    except ImportError:
        raise MissingExtraError(
            'the Allan deviation (gyrodrift allan) needs allantools: pip install "gyrodrift[allan]"'
        ) from None
    return allantools


def allan_edf(tau_s: np.ndarray, alpha: np.ndarray, n_phase: int, base_tau_s: float) -> np.ndarray:
    """Greenhall's equivalent degrees of freedom (`allantools.edf_greenhall`, overlapping ADEV) of each point.

    `alpha` is the noise type at each `tau_s` (frequency PSD exponent: 0 white rate, -1 flicker, -2 random walk),
    `n_phase` the number of phase points and `base_tau_s` their spacing [s].
    """
    allantools = _allantools()
    m = np.maximum(np.round(np.asarray(tau_s, dtype=float) / base_tau_s), 1).astype(int)
    return np.array(
        [
            allantools.edf_greenhall(int(a), 2, int(mi), int(n_phase), overlapping=True)
            for a, mi in zip(alpha, m, strict=True)
        ]
    )


def _intervals(dev: np.ndarray, edf: np.ndarray, ci: float) -> tuple[np.ndarray, np.ndarray]:
    allantools = _allantools()
    bounds = np.array(
        [allantools.confidence_interval(float(d), float(e), ci=ci) for d, e in zip(dev, edf, strict=True)]
    )
    return bounds[:, 0], bounds[:, 1]


def _noise_type(tau: np.ndarray, avar: np.ndarray) -> np.ndarray:
    """The noise type alpha (0, -1, -2) from the local slope mu of log AVAR vs log tau (mu = -alpha - 1)."""
    mu = np.gradient(np.log(avar), np.log(tau)) if len(tau) > 1 else np.array([-1.0])
    return np.clip(np.round(-mu - 1.0), -2, 0).astype(int)


class _Fit:
    """A fit of a subset of the terms to one Allan variance curve: each measured variance is chi-squared with its
    edf degrees of freedom around the model (a Gamma variable of shape edf/2), so the coefficients are the
    iteratively reweighted non-negative least-squares solution (weights 1 / (model * sqrt(2/edf)), the Gamma
    quasi-likelihood) and a fit is judged by its Gamma deviance."""

    def __init__(self, tau: np.ndarray, avar: np.ndarray, edf: np.ndarray):
        self.tau, self.avar, self.shape = tau, avar, edf / 2.0
        self.rel = np.clip(np.sqrt(2.0 / edf), 0.01, None)  # relative 1-sigma of each variance
        self.inside_at = len(self.grid()) // 2
        """Grid index of the correlation time that last put a Gauss-Markov fit inside the band: `violation` starts
        its scan there (a subset's feasible T is usually near its superset's), so its early exit comes sooner."""

    def solve(self, terms: frozenset[str], corr: float) -> tuple[float, dict[str, float]]:
        """(Gamma deviance, {term: coefficient}) for the given correlation time [s]."""
        from scipy.optimize import nnls

        names, design = self.design(terms, corr)
        model = self.avar
        for _ in range(_REWEIGHTINGS):
            w = 1.0 / (np.clip(model, 1e-3 * self.avar, 1e3 * self.avar) * self.rel)
            coef, _ = nnls(design * w[:, None], self.avar * w)
            model = design @ coef
        ratio = self.avar / np.maximum(model, 1e-300)
        deviance = float(np.sum(2.0 * self.shape * (ratio - 1.0 - np.log(ratio))))
        return deviance, dict(zip(names, (float(c) for c in coef), strict=True))

    def design(self, terms: frozenset[str], corr: float) -> tuple[list[str], np.ndarray]:
        """The terms in `_TERMS` order and their Allan variance columns at unit coefficient."""
        tau = self.tau
        cols = {"white": 1.0 / tau, "rrw": tau / 3.0}
        if "gauss_markov" in terms:
            cols["gauss_markov"] = gauss_markov_avar(tau, 1.0, corr)
        names = [t for t in _TERMS if t in terms]
        return names, np.column_stack([cols[t] for t in names])

    def violation(self, terms: frozenset[str], lo2: np.ndarray, hi2: np.ndarray, above: float = math.inf) -> float:
        """The smallest total relative distance, over all non-negative coefficients (and correlation times on the
        grid), of the Allan variance of `terms` from the band ``[lo2, hi2]``: a linear program, 0 when the terms
        fit inside the band at every point.

        inf when it is sure to exceed `above`: one LP with the Gauss-Markov columns of every grid correlation time
        at once (a lower bound of each single-T one) exceeding `above` + `_LP_MARGIN` skips the scan of the grid.
        """
        if not terms:
            return float(len(lo2))
        grid = self.grid()
        if "gauss_markov" not in terms:
            return self._band_distance(self.design(terms, math.nan)[1], lo2, hi2)
        if math.isfinite(above):
            others = self.design(terms - {"gauss_markov"}, math.nan)[1] if len(terms) > 1 else np.empty((len(lo2), 0))
            every_t = np.column_stack([gauss_markov_avar(self.tau, 1.0, float(c)) for c in grid])
            if self._band_distance(np.hstack([others, every_t]), lo2, hi2) > above + _LP_MARGIN:
                return math.inf
        # The minimum over the grid does not depend on the scan order; a feasible T (0) ends the scan, so it
        # starts at the last feasible one and widens both ways until the whole grid is covered.
        best = math.inf
        for k in sorted(range(len(grid)), key=lambda k: (abs(k - self.inside_at), k)):
            best = min(best, self._band_distance(self.design(terms, float(grid[k]))[1], lo2, hi2))
            if best <= 0.0:
                self.inside_at = k
                break
        return best

    def _band_distance(self, design: np.ndarray, lo2: np.ndarray, hi2: np.ndarray) -> float:
        """The LP of `violation` for fixed design columns: min sum(s) over c >= 0, s >= 0 with
        lo2 (1 - s) <= design c <= hi2 (1 + s) (inf if HiGHS fails)."""
        from scipy.optimize import linprog

        n = len(self.tau)
        scale = 1.0 / np.max(design / lo2[:, None], axis=0)  # columns of order 1
        d = design * scale
        # rows: -(d/lo2) c - s <= -1 (above the lower bound), (d/hi2) c - s <= 1 (below the upper one)
        a_ub = np.block([[-d / lo2[:, None], -np.eye(n)], [d / hi2[:, None], -np.eye(n)]])
        b_ub = np.concatenate([-np.ones(n), np.ones(n)])
        cost = np.concatenate([np.zeros(d.shape[1]), np.ones(n)])
        res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=(0, None), method="highs")
        return float(res.fun) if res.status == 0 else math.inf

    def grid(self) -> np.ndarray:
        """The correlation times tried [s]: from the shortest averaging time to the longest / `_GM_REACH`."""
        return np.geomspace(self.tau[0], max(self.tau[0], self.tau[-1] / _GM_REACH), 48)

    def best(self, terms: frozenset[str]) -> tuple[float, dict[str, float], float]:
        """The best fit of `terms`: (residual, coefficients, correlation time [s] or nan without Gauss-Markov)."""
        from scipy.optimize import minimize_scalar

        if "gauss_markov" not in terms:
            resid, coef = self.solve(terms, math.nan)
            return resid, coef, math.nan
        grid = self.grid()
        fits = [self.solve(terms, c) for c in grid]
        k = int(np.argmin([f[0] for f in fits]))
        corr, (resid, coef) = float(grid[k]), fits[k]
        lo, hi = np.log(grid[max(k - 1, 0)]), np.log(grid[min(k + 1, len(grid) - 1)])
        opt = minimize_scalar(lambda x: self.solve(terms, math.exp(x))[0], bounds=(lo, hi), method="bounded")
        if opt.fun < resid:
            corr = math.exp(opt.x)
            resid, coef = self.solve(terms, corr)
        return resid, coef, corr

    def model(self, coef: dict[str, float], corr: float) -> np.ndarray:
        return _avar(
            self.tau,
            math.sqrt(coef.get("white", 0.0)),
            math.sqrt(coef.get("gauss_markov", 0.0)),
            corr if math.isfinite(corr) else 1.0,
            math.sqrt(coef.get("rrw", 0.0)),
        )


def fit_noise(
    tau_s: np.ndarray, adev: np.ndarray, edf: np.ndarray, *, axis: str = "axis", confidence: float = CONFIDENCE
) -> AxisNoise:
    """Fit white noise, a Gauss-Markov bias and rate random walk to one Allan deviation curve, keeping the terms
    the data show beyond the `confidence` interval of the Allan deviation (module docstring).

    Parameters
    ----------
    tau_s, adev : ndarray
        Averaging times [s] and Allan deviation (any unit).
    edf : ndarray
        Equivalent degrees of freedom of each point (`allan_edf`).
    axis : str
        Name carried into the result.
    confidence : float
        Two-sided confidence of the interval a term must rise above.
    """
    tau = np.asarray(tau_s, dtype=float)
    dev = np.asarray(adev, dtype=float)
    dof = np.asarray(edf, dtype=float)
    ok = np.isfinite(dev) & (dev > 0.0) & np.isfinite(tau) & (tau > 0.0) & np.isfinite(dof) & (dof > 0.0)
    if ok.sum() < 3:
        raise InputError(f"{axis}: fewer than 3 usable Allan deviation points; the log is too short or constant")
    tau, dev, dof = tau[ok], dev[ok], dof[ok]
    avar = dev**2
    fit = _Fit(tau, avar, dof)
    lo, hi = _intervals(dev, dof, 1.0 - (1.0 - confidence) / len(dev))  # for the whole curve (Bonferroni)

    # Backward elimination: drop a term while the others alone can still stay as close to the confidence band as
    # with it (`_Fit.violation`: 0 when some non-negative combination lies inside the band at every point).
    kept = frozenset(_TERMS)
    miss = fit.violation(kept, lo**2, hi**2)
    while len(kept) > 1:
        trials = []
        for term in sorted(kept):
            without = fit.violation(kept - {term}, lo**2, hi**2, above=miss + 1e-6)
            # within the LP's tolerance; parsimony first: the two-parameter Gauss-Markov term goes if it can
            if without <= miss + 1e-6:
                trials.append((term != "gauss_markov", without, term))
        if not trials:
            break
        _, miss, term = min(trials)
        kept = kept - {term}
    _, coef, corr = fit.best(kept)
    values = {t: (math.sqrt(coef[t]) if coef.get(t, 0.0) > 0.0 else None) for t in _TERMS}
    tau_range = f"{tau[0]:.3g}-{tau[-1]:.3g} s"
    hint = {
        "white": "",
        "gauss_markov": f"; a correlation time is resolved from {tau[0]:.3g} to {tau[-1] / _GM_REACH:.3g} s (the log "
        "must reach past the peak of its Allan deviation, near 1.9 T)",
        "rrw": "; a rate random walk rises at the longest averaging times: a longer log reaches further",
    }
    not_resolved = {}
    for term in _TERMS:
        if values[term] is None:
            not_resolved[term] = (
                f"not resolved: without it the fit stays within the {confidence:.0%} confidence interval of the Allan "
                f"deviation at every averaging time the log reaches ({tau_range}){hint[term]}"
            )
    gm_corr = corr if values["gauss_markov"] is not None else None
    model_dev = np.sqrt(
        _avar(
            np.geomspace(tau[0], tau[-1], 400),
            values["white"] or 0.0,
            values["gauss_markov"] or 0.0,
            gm_corr or 1.0,
            values["rrw"] or 0.0,
        )
    )
    k_min = int(np.argmin(model_dev))
    if 0 < k_min < len(model_dev) - 1 and (values["gauss_markov"] is not None or values["rrw"] is not None):
        bias_instability: float | None = float(np.min(dev)) / _BIAS_INSTABILITY_FACTOR
    else:
        bias_instability = None
        not_resolved["bias_instability"] = (
            f"not resolved: the fitted Allan deviation has no floor within the averaging times the log reaches "
            f"({tau_range}); it is still falling at the longest"
        )
    lo_plot, hi_plot = _intervals(dev, dof, CONFIDENCE_PLOT)
    fitted = np.sqrt(np.maximum(fit.model(coef, corr), 1e-300))
    return AxisNoise(
        axis=axis,
        tau_s=tau,
        adev=dev,
        edf=dof,
        adev_lo=lo_plot,
        adev_hi=hi_plot,
        white=values["white"],
        gm_sigma=values["gauss_markov"],
        gm_correlation_s=gm_corr,
        rrw=values["rrw"],
        bias_instability=bias_instability,
        not_resolved=not_resolved,
        fit_rms_log=float(np.sqrt(np.mean(np.log(fitted / dev) ** 2))),
    )


def _axis_noise(tau: np.ndarray, adev: np.ndarray, n_phase: int, base_tau: float, axis: str) -> AxisNoise:
    """`fit_noise` with Greenhall's edf for the noise type the fit finds at each tau (two passes: white rate
    noise everywhere first, then the local slope of the first fit)."""
    first = fit_noise(tau, adev, allan_edf(tau, np.zeros(len(tau)), n_phase, base_tau), axis=axis)
    avar = first.model_adev(tau) ** 2
    alpha = _noise_type(tau, np.where(avar > 0, avar, adev**2))
    return fit_noise(tau, adev, allan_edf(tau, alpha, n_phase, base_tau), axis=axis)


def allan_deviation(log: Any, *, chunk_samples: int = 200_000, quiet: bool = True) -> AllanResult:
    """Allan deviations and noise fits of every varying axis of a static log with the turntable still.

    Parameters
    ----------
    log : ImuLog
        An opened log (`gyrodrift.logs.open_log`); it is streamed once (memory: the cumulative angle and
        velocity at most 2 million points per axis, whatever the log length).
    chunk_samples : int
        Samples per streamed chunk.
    quiet : bool
        True hides the progress bar.

    Raises
    ------
    InputError
        The log is shorter than 100 samples, its turntable turns (z rate varying by more than
        `MAX_TABLE_RATE_DEG_S` between 1 s means), or all six channels are constant.
    """
    from gyrodrift.progress import progress

    allantools = _allantools()

    n = int(log.n_samples)
    if n < 100:
        raise InputError(f"{log.path}: {n} samples; an Allan deviation needs at least 100 (minutes of a static log)")
    stride = max(1, math.ceil(n / _MAX_BASE_POINTS))
    per_second = max(1, int(round(log.rate_hz)))
    n_points = n // stride
    phase = np.empty((n_points + 1, 6))
    phase[0] = 0.0
    total = np.zeros(6)
    lowest, highest = np.full(6, np.inf), np.full(6, -np.inf)  # of the increments: a constant channel
    filled = 1
    carry = 0  # samples of the current stride already summed
    z_means: list[float] = []
    z_acc, z_cnt = 0.0, 0
    with progress(n, "allan", quiet, unit="sample") as bar:
        for chunk in log.chunks(chunk_samples):
            inc = np.hstack([chunk.dtheta_rad, chunk.dv_m_s])
            lowest, highest = np.minimum(lowest, inc.min(axis=0)), np.maximum(highest, inc.max(axis=0))
            # still-table check on 1 s means of the z rate: the second begun in the previous chunk, then the
            # chunk's whole seconds (one row each), then the start of the next second
            dz = chunk.dtheta_rad[:, 2]
            i = min(per_second - z_cnt, len(dz)) if z_cnt else 0
            if i:
                z_acc += float(dz[:i].sum())
                z_cnt += i
                if z_cnt == per_second:
                    z_means.append(z_acc * log.rate_hz / per_second)
                    z_acc, z_cnt = 0.0, 0
            whole = (len(dz) - i) // per_second * per_second
            seconds = dz[i : i + whole].reshape(-1, per_second).sum(axis=1)
            z_means.extend((seconds * log.rate_hz / per_second).tolist())
            if len(dz) > i + whole:
                z_acc, z_cnt = float(dz[i + whole :].sum()), len(dz) - i - whole
            cum = total + np.cumsum(inc, axis=0)
            # phase points at the end of every `stride` samples
            first = (stride - carry) - 1
            idx = np.arange(first, len(inc), stride)
            idx = idx[: max(0, min(len(idx), n_points + 1 - filled))]
            phase[filled : filled + len(idx)] = cum[idx]
            filled += len(idx)
            carry = (carry + len(inc)) % stride
            total = cum[-1]
            bar.update(len(inc))
    phase = phase[:filled]
    if z_means:
        spread = (max(z_means) - min(z_means)) / _DEG
        if spread > MAX_TABLE_RATE_DEG_S:
            raise InputError(
                f"{log.path}: the z rate varies by {spread:.3g} deg/s between 1 s means: the turntable turns. "
                f"An Allan deviation needs a static log with the rotation off (at most {MAX_TABLE_RATE_DEG_S} deg/s)"
            )
    constant = {name: float(lowest[k]) * log.rate_hz for k, name in enumerate(_NAMES) if lowest[k] == highest[k]}
    if len(constant) == len(_NAMES):
        raise InputError(
            f"{log.path}: every gyro and accelerometer channel is constant (each sample equals the first): there is "
            "no sensor noise to measure. An Allan deviation needs the raw increments of a real or simulated IMU"
        )
    base_tau = stride / log.rate_hz
    axes = []
    for k, name in enumerate(_NAMES):
        if name in constant:
            continue
        taus, adev, _, _ = allantools.oadev(phase[:, k], rate=1.0 / base_tau, data_type="phase", taus="octave")
        axes.append(_axis_noise(np.asarray(taus, float), np.asarray(adev, float), len(phase), base_tau, name))
    return AllanResult(
        log=str(log.path),
        rate_hz=float(log.rate_hz),
        duration_s=n / log.rate_hz,
        base_tau_s=base_tau,
        axes=axes,
        constant_axes=constant,
    )
