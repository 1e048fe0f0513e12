"""Planning an identification: how long to observe a static base, and what the 72 h mission will bring.

`plan_identification` answers the engineer's question before a run, by covariance analysis alone (no IMU samples
are simulated; a few seconds): for a noise block, a site, a rotation scheme, a thermal situation and a budget
(default 1 nmi at 72 h for 95 % of runs), the 1-sigma of the identified axial drift against the observation span
(alignment + static navigation, from the first sample), the predicted quantile of the 72 h position error after
compensating it, and the shortest span that meets the budget. `mission_outlook` says the same of one identified
run (`gyrodrift identify`): its drift 1-sigma and latitude give the predicted 72 h quantiles, whether the run is
ready and about how much more static time it needs otherwise. Both use `MissionErrorModel`: one implementation.

The model (docs/procedure.md, "Planning the static time"):

1. Identification. The 1-sigma ``s_id(T)`` of the drift the 16 h smoother (`gyrodrift.procedure.smoother`)
   carries into navigation after a span T from the first sample: the smoother's own filter covariance, run as a
   Riccati recursion over the same linear-Gaussian error model, priors and measurements (zero velocity and the
   known position every 10 s) with the table turning (`_core.drift_std_curve`, gyrodrift-core ``plan``). It is
   the smoother's reported 1-sigma on a run with the same settings, and the Cramer-Rao line of any method.
2. Thermal term. The smoother's thermal state is not in the planner. The drift carried into navigation misses
   k_z dT, dT [degC] the temperature change the identification does not see through (after the span, or during
   it when too small to learn k_z), k_z [deg/h/degC] known to ``coeff_std`` (a fleet prior: `gyrodrift fit`'s
   pooled k_z prior, or a datasheet): ``s(T)^2 = s_id(T)^2 + (coeff_std dT)^2``. Conservative when the span's own
   temperature change teaches the smoother k_z.
3. Mission. The north/east position error e after compensating the drift, at the end of the mission (72 h of free
   navigation from the end of the alignment), is a zero-mean 2-D Gaussian with covariance ``Sigma = Sigma_floor + W +
   s^2 g g' + g c' + c g'``: ``g`` the response to a unit drift error (close to the closed forms dL(t) = (eps cos L /
   w)(1 - cos w t) north and dlon(t) = eps sin L (t - sin(w t) / w) east, Schuler terms aside), ``Sigma_floor`` the
   floor, the error the mission keeps even with the exact drift: the angle and velocity random walks and the z gyro's
   slow bias over the mission (`_core.mission_covariance`: the Gauss-Markov bias instability stationary, which the
   drift carried into navigation leaves out, and the rate random walk from the mission's start; the x and y ones
   modulated away by the table), plus the aligner's leftover attitude and velocity errors it starts from, carried
   over the mission, with their covariance with the Gauss-Markov bias (`_core.drift_std_curve`'s
   ``alignment_cov_m2``), plus, with a rate random walk, the part ``W`` from its value at the span's end, where the
   smoother takes the drift it carries (``walk_cov_m2``, per span; every span must then end after the alignment); and
   ``c = E[(d - d_hat) p]`` the covariance of the drift error with that floor p. Both come from the same data: the
   aligner and the smoother start from the one coarse alignment and read the same noise over the 4 h alignment (the
   smoother's drift error and the aligner's leftover heading and tilts move together), and after it the same noise
   drives the smoother's error and the mission's (the smoother partly reads the noise's walk as drift, which then
   cancels part of it in the mission; the smoother splits constant and Gauss-Markov bias imperfectly). One Riccati
   pass carries the aligner (its own prior, noise model and 1 s zero-velocity updates, on the smoother's error model)
   beside the smoother and gives both (`_core.drift_std_curve`; gyrodrift-core ``plan``'s docs hold the recursion).
   The horizontal sensor biases are modulated away by the table. The share of runs within a radius r is ``P(|e| <= r)
   = (1 / 2 pi) int_0^{2 pi} (1 - exp(-r^2 / (2 s(theta)))) dtheta``, s(theta) = l1 cos^2 theta + l2 sin^2 theta (l1,
   l2 the eigenvalues of Sigma; polar coordinates of the whitened error), integrated by the midpoint rule (a smooth
   periodic integrand: the error falls geometrically with the points); quantiles by root finding on it.

Units at the edges: drift deg/h, spans and mission h, position nmi (1852 m), latitude deg.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.earth import NMI_M
from gyrodrift.errors import InputError
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.units import DEG, DEG_PER_H, HOUR

__all__ = [
    "MissionBudget",
    "MissionErrorModel",
    "Plan",
    "IdentificationCurve",
    "identification_curve",
    "mission_error_model",
    "mission_outlook",
    "norm_cdf",
    "norm_quantile",
    "plan_identification",
    "DEFAULT_QUANTILES",
]

DEFAULT_QUANTILES = (0.5, 0.9, 0.95, 0.99)
"""Probabilities of the 72 h error quantiles reported."""
_THETA_POINTS = 2048
"""Midpoints over a quarter turn for `norm_cdf` (the integrand is symmetric in each quadrant)."""
_THETA = (np.arange(_THETA_POINTS) + 0.5) * (0.5 * math.pi / _THETA_POINTS)
_COS2, _SIN2 = np.cos(_THETA) ** 2, np.sin(_THETA) ** 2
"""cos^2 and sin^2 at those midpoints, computed once: `norm_cdf` runs once per run of a fleet (the law's limit)."""
_COS2.flags.writeable = _SIN2.flags.writeable = False  # shared by every call: read-only
_MISSION_STEP_S = 60.0
"""Propagation step of the mission covariance [s]."""
_UPDATE_S = 10.0
"""The smoother's measurement interval [s] (its default)."""
_MAX_SPAN_H = 55.0
"""Longest span [h]: the smoother keeps at most 20 000 updates of 10 s."""


def _finite(name: str, value: Any, *, low: float | None = None, high: float | None = None, open_low=False) -> float:
    """A finite number within bounds, or one-line `InputError` naming `name`."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{name}: expected a finite number, got {value!r}")
    v = float(value)
    if low is not None and (v < low or (open_low and v == low)):
        raise InputError(f"{name}: expected a number {'>' if open_low else '>='} {low:g}, got {v:g}")
    if high is not None and v > high:
        raise InputError(f"{name}: expected a number <= {high:g}, got {v:g}")
    return v


@dataclass(frozen=True)
class MissionBudget:
    """A position-error budget: at most ``error_nmi`` [nmi] after ``hours`` [h] of navigation for a ``share``
    (0-1) of runs (default: 1 nmi at 72 h for 95 %)."""

    error_nmi: float = 1.0
    hours: float = 72.0
    share: float = 0.95

    def __post_init__(self):
        _finite("budget error_nmi", self.error_nmi, low=0.0, open_low=True)
        _finite("budget hours", self.hours, low=1.0 / 60.0, high=1000.0)
        s = _finite("budget share", self.share, low=0.0, open_low=True)
        if not s < 1.0:
            raise InputError(f"budget share: expected a number in (0, 1), got {s:g}")

    def describe(self) -> str:
        return f"{self.error_nmi:g} nmi at {self.hours:g} h for {100 * self.share:g} % of runs"


def _eigen(cov: np.ndarray) -> tuple[float, float]:
    c = np.asarray(cov, dtype=float)
    if c.shape != (2, 2) or not np.all(np.isfinite(c)):
        raise InputError(f"covariance: expected a finite 2 x 2 matrix, got shape {c.shape}")
    lam = np.linalg.eigvalsh(0.5 * (c + c.T))
    return float(max(lam[1], 0.0)), float(max(lam[0], 0.0))


def norm_cdf(cov, radius) -> float:
    """``P(|e| <= radius)`` for a zero-mean 2-D Gaussian e with covariance `cov` (module docs; same units squared)."""
    l1, l2 = _eigen(cov)
    r = float(radius)
    if r <= 0:
        return 0.0
    if l1 == 0.0:
        return 1.0
    s = l1 * _COS2 + l2 * _SIN2
    with np.errstate(divide="ignore", over="ignore"):
        return float(np.mean(1.0 - np.exp(-(r * r) / (2.0 * s))))


def norm_quantile(cov, p: float) -> float:
    """The radius r with ``P(|e| <= r) = p`` (0 < p < 1) for the Gaussian of `norm_cdf` (units of sqrt(cov))."""
    p = _finite("quantile probability", p, low=0.0, open_low=True)
    if not p < 1.0:
        raise InputError(f"quantile probability: expected a number in (0, 1), got {p:g}")
    l1, _ = _eigen(cov)
    if l1 == 0.0:
        return 0.0
    from scipy.optimize import brentq  # here: scipy.optimize costs ~0.4 s of every CLI start

    high = math.sqrt(-2.0 * l1 * math.log1p(-p)) * 1.0001  # the circular Gaussian of the largest axis
    return float(brentq(lambda r: norm_cdf(cov, r) - p, 0.0, high, xtol=1e-12 * high, rtol=1e-12))


@dataclass(frozen=True)
class MissionErrorModel:
    """The position error at the end of a mission after compensating a drift (module docs, point 3).

    Attributes
    ----------
    lat_deg, hours : float
        Site latitude [deg] and mission length [h] (free navigation from the end of the alignment).
    floor_cov_m2 : tuple of 2 tuples
        Covariance of the north, east floor [m^2] (the error with the exact drift: the noise's part and the
        alignment's).
    alignment_cov_m2 : tuple of 2 tuples
        The part of `floor_cov_m2` from the aligner's leftover attitude and velocity errors [m^2].
    response_m_per_deg_h : tuple of 2 floats
        North, east position error per deg/h of uncompensated drift [m/(deg/h)] (computed minus true).
    """

    lat_deg: float
    hours: float
    floor_cov_m2: tuple[tuple[float, float], tuple[float, float]]
    alignment_cov_m2: tuple[tuple[float, float], tuple[float, float]]
    response_m_per_deg_h: tuple[float, float]

    def covariance_m2(self, drift_std_deg_h: float, cross_m_deg_h=(0.0, 0.0), walk_cov_m2=None) -> np.ndarray:
        """Sigma = Sigma_floor + W + s^2 g g' + g c' + c g' [m^2] for a drift 1-sigma s [deg/h], its covariance c
        with the floor [m deg/h] (`IdentificationCurve.cross_m_deg_h`; 0: independent) and the floor's part W
        [m^2] from the z rate random walk at the span's end (`IdentificationCurve.walk_cov_m2`; None: none)."""
        s = _finite("drift_std_deg_h", drift_std_deg_h, low=0.0)
        g = np.asarray(self.response_m_per_deg_h, dtype=float)
        c = np.asarray(cross_m_deg_h, dtype=float).reshape(2)
        floor = np.asarray(self.floor_cov_m2, dtype=float)
        if walk_cov_m2 is not None:
            floor = floor + np.asarray(walk_cov_m2, dtype=float).reshape(2, 2)
        return floor + s * s * np.outer(g, g) + np.outer(g, c) + np.outer(c, g)

    def share_within(
        self, drift_std_deg_h: float, error_nmi: float, cross_m_deg_h=(0.0, 0.0), walk_cov_m2=None
    ) -> float:
        """Share of runs whose error is at most `error_nmi` [nmi]."""
        return norm_cdf(self.covariance_m2(drift_std_deg_h, cross_m_deg_h, walk_cov_m2), error_nmi * NMI_M)

    def quantile_nmi(self, drift_std_deg_h: float, p: float, cross_m_deg_h=(0.0, 0.0), walk_cov_m2=None) -> float:
        """The p-quantile of the error [nmi]."""
        return norm_quantile(self.covariance_m2(drift_std_deg_h, cross_m_deg_h, walk_cov_m2), p) / NMI_M

    def max_drift_std_deg_h(self, budget: MissionBudget, cross_per_std_m=(0.0, 0.0), walk_cov_m2=None) -> float | None:
        """The largest drift 1-sigma s [deg/h] meeting `budget`, the covariance with the floor scaling with it
        (c = s `cross_per_std_m` [m]); None when the floor alone misses it."""
        if self.share_within(0.0, budget.error_nmi, walk_cov_m2=walk_cov_m2) < budget.share:
            return None
        rho = np.asarray(cross_per_std_m, dtype=float).reshape(2)
        g = float(np.hypot(*self.response_m_per_deg_h))
        hi = 10.0 * budget.error_nmi * NMI_M / g  # a 10 nmi 1-sigma drift term: far outside any budget

        def miss(s: float) -> float:
            return self.share_within(s, budget.error_nmi, s * rho, walk_cov_m2) - budget.share

        from scipy.optimize import brentq  # here: scipy.optimize costs ~0.4 s of every CLI start

        return float(brentq(miss, 0.0, hi, xtol=1e-12))


def mission_error_model(
    lat_deg: float, noise: SensorNoise, *, hours: float = 72.0, height_m: float = 0.0, alignment_cov_m2=None
) -> MissionErrorModel:
    """The `MissionErrorModel` of a site and a noise model: the floor is the ARW's, VRW's and the z gyro's slow
    bias's over the mission (`_core.mission_covariance`, from no initial attitude or velocity error; the
    Gauss-Markov bias stationary, the rate random walk from zero at the mission's start) plus `alignment_cov_m2`
    [m^2] (2 x 2, north, east), the alignment's leftovers carried over the mission
    (`IdentificationCurve.alignment_cov_m2`; default none: the slow bias then independent of them)."""
    from gyrodrift import _core

    lat = _finite("lat_deg", lat_deg, low=-90.0, high=90.0)
    h = _finite("hours", hours, low=1.0 / 60.0, high=1000.0)
    r = _core.mission_covariance(
        _core.FreeNavigationConfig(
            lat_rad=lat * DEG,
            height_m=float(height_m),
            span_s=h * HOUR,
            step_s=_MISSION_STEP_S,
            gyro_arw_rad_rts=noise.arw_rad_rts,
            accel_vrw_m_s_rts=noise.vrw_m_s_rts,
            att_sigma_rad=[0.0, 0.0, 0.0],
            vel_sigma_m_s=0.0,
        ),
        **{k: v for k, v in noise.core_keywords().items() if k not in ("gyro_arw_rad_rts", "accel_vrw_m_s_rts")},
    )
    a = np.zeros((2, 2)) if alignment_cov_m2 is None else np.asarray(alignment_cov_m2, dtype=float)
    if a.shape != (2, 2) or not np.all(np.isfinite(a)):
        raise InputError(f"alignment_cov_m2: expected a finite 2 x 2 matrix, got shape {a.shape}")
    c = np.asarray(r["pos_cov_m2"], dtype=float) + a
    g = np.asarray(r["response_m_per_rad_s"], dtype=float) * DEG_PER_H
    if not float(np.hypot(g[0], g[1])) > 0:
        raise InputError(f"lat_deg: the {h:g} h position error does not depend on the axial drift at {lat:g} deg")
    return MissionErrorModel(
        lat_deg=lat,
        hours=h,
        floor_cov_m2=((float(c[0, 0]), float(c[0, 1])), (float(c[1, 0]), float(c[1, 1]))),
        alignment_cov_m2=((float(a[0, 0]), float(a[0, 1])), (float(a[1, 0]), float(a[1, 1]))),
        response_m_per_deg_h=(float(g[0]), float(g[1])),
    )


def _scenario_for(lat_deg: float, scenario=None):
    """The scenario whose site, rate, rotation scheme and attitude the planner uses (default: the default
    scenario at `lat_deg`)."""
    from gyrodrift.ins.scenario import Scenario

    if scenario is not None:
        return scenario
    return Scenario.from_dict({"site": {"lat_deg": float(lat_deg)}})


@dataclass(frozen=True)
class IdentificationCurve:
    """The smoother's drift against the span (`identification_curve`).

    Attributes
    ----------
    spans_h : ndarray
        Spans from the first sample [h].
    drift_std_deg_h : ndarray
        The smoother's 1-sigma of the drift carried into navigation [deg/h].
    cross_m_deg_h : ndarray, shape (spans, 2)
        E[(d - d_hat) p] [m deg/h], p the north, east floor at the mission's end (module docs, point 3).
    alignment_cov_m2 : ndarray, shape (2, 2)
        The floor's part from the aligner's leftover attitude and velocity errors [m^2] (north, east), with their
        covariance with the Gauss-Markov z bias at the mission's start, the same for every span
        (`mission_error_model`'s `alignment_cov_m2`).
    walk_cov_m2 : ndarray, shape (spans, 2, 2)
        The floor's part from the z rate random walk's value at each span's end [m^2] (module docs, point 3;
        zero without one: `MissionErrorModel.covariance_m2`'s `walk_cov_m2`).
    """

    spans_h: np.ndarray
    drift_std_deg_h: np.ndarray
    cross_m_deg_h: np.ndarray
    alignment_cov_m2: np.ndarray
    walk_cov_m2: np.ndarray


def identification_curve(
    noise: SensorNoise,
    spans_h: Sequence[float] | np.ndarray,
    *,
    scenario=None,
    lat_deg: float | None = None,
    timeline: Timeline = DEFAULT_TIMELINE,
    mission_h: float = 72.0,
) -> IdentificationCurve:
    """The smoother's drift 1-sigma after each span [h] from the first sample, its covariance with the floor of
    a mission of `mission_h` [h] from the end of the alignment (``timeline.align_h``), and the floor's part from
    the alignment (module docs, points 1 and 3; `_core.drift_std_curve`).

    `scenario` (a `gyrodrift.ins.scenario.Scenario`) gives the site, the sample rate, the rotation scheme and the
    attitude; without it the default scenario at `lat_deg`. The smoother's settings are `smooth_log`'s: its
    coarse span (``timeline.coarse_s``), the noise floored as there, no thermal state.
    """
    from gyrodrift import _core

    if scenario is None and lat_deg is None:
        raise InputError("the planner needs a scenario or a latitude (lat_deg)")
    scn = _scenario_for(lat_deg if lat_deg is not None else 0.0, scenario)
    spans = np.asarray([_finite("span_h", s, low=0.0, open_low=True) for s in spans_h], dtype=float)
    if spans.size == 0 or np.any(np.diff(spans) <= 0):
        raise InputError("span_h: expected spans in ascending order")
    mission = _finite("mission_h", mission_h, low=1.0 / 60.0, high=1000.0)
    if timeline.align_h + mission < spans[-1]:
        raise InputError(f"span_h: {spans[-1]:g} h outlasts the mission (ends at {timeline.align_h + mission:g} h)")
    if noise.rrw_deg_h_rth > 0 and spans[0] < timeline.align_h:
        raise InputError(
            f"span_h: {spans[0]:g} h ends before the alignment ({timeline.align_h:g} h): with a rate random walk the "
            "planner needs every span to end after it"
        )
    site = scn.site
    keywords: dict[str, Any] = {
        **site.core_position(),
        "rate_hz": float(scn.run.rate_hz),
        "coarse_s": float(timeline.coarse_s),
        "span_s": float(spans[-1]) * HOUR,
        "update_s": _UPDATE_S,
        "thermal": False,
        **noise.floored().core_keywords(),
    }
    config = _core.SmootherConfig(**keywords)
    out = _core.drift_std_curve(
        config,
        scn.to_core_config(),
        [float(s) * HOUR for s in spans],
        mission_start_s=timeline.align_h * HOUR,
        mission_s=mission * HOUR,
    )
    return IdentificationCurve(
        spans_h=spans,
        drift_std_deg_h=np.asarray(out["drift_std_rad_s"], dtype=float) / DEG_PER_H,
        cross_m_deg_h=np.asarray(out["cross_rad_s_m"], dtype=float).reshape(-1, 2) / DEG_PER_H,
        alignment_cov_m2=np.asarray(out["alignment_cov_m2"], dtype=float).reshape(2, 2),
        walk_cov_m2=np.asarray(out["walk_cov_m2"], dtype=float).reshape(-1, 2, 2),
    )


@dataclass(frozen=True)
class Plan:
    """What `plan_identification` found.

    Attributes
    ----------
    spans_h : ndarray
        Observation spans from the first sample [h] (alignment + static navigation).
    drift_std_id_deg_h, drift_std_deg_h : ndarray
        The smoother's drift 1-sigma [deg/h] at each span, and with the thermal term added (module docs).
    cross_m_deg_h : ndarray, shape (spans, 2)
        The drift error's covariance with the mission's floor, north and east [m deg/h].
    walk_cov_m2 : ndarray, shape (spans, 2, 2)
        The floor's part from the z rate random walk at each span's end [m^2] (`IdentificationCurve.walk_cov_m2`).
    share_within : ndarray
        Predicted share of runs within the budget's error at each span.
    quantile_nmi : ndarray
        Predicted ``budget.share`` quantile of the mission error [nmi] at each span.
    floor_quantile_nmi : float
        The same with the exact drift (the floor alone; the rate random walk's part at the span below).
    max_drift_std_deg_h : float or None
        The largest drift 1-sigma meeting the budget (None: the floor misses it), with the covariance with the floor
        scaled from the shortest span meeting it (else the longest span).
    shortest_span_h : float or None
        The shortest span of `spans_h` meeting the budget; None when none does (`reason` says why).
    reason : str
        One sentence: the answer and why.
    """

    lat_deg: float
    noise: SensorNoise
    rotation: str
    budget: MissionBudget
    coeff_std_deg_h_per_c: float
    temp_change_c: float
    spans_h: np.ndarray
    drift_std_id_deg_h: np.ndarray
    cross_m_deg_h: np.ndarray
    walk_cov_m2: np.ndarray
    drift_std_deg_h: np.ndarray
    share_within: np.ndarray
    quantile_nmi: np.ndarray
    floor_quantile_nmi: float
    max_drift_std_deg_h: float | None
    shortest_span_h: float | None
    reason: str
    mission: MissionErrorModel = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        def arr(a) -> list[float]:
            return [float(x) for x in a]

        return {
            "format": "gyrodrift-plan/1",
            "answer": self.reason,
            "shortest_span_h": self.shortest_span_h,
            "lat_deg": self.lat_deg,
            "rotation": self.rotation,
            "noise": self.noise.to_dict(),
            "budget": {
                "error_nmi": self.budget.error_nmi,
                "hours": self.budget.hours,
                "share": self.budget.share,
            },
            "thermal": {"coeff_std_deg_h_per_c": self.coeff_std_deg_h_per_c, "temp_change_c": self.temp_change_c},
            "max_drift_std_deg_h": self.max_drift_std_deg_h,
            "floor_quantile_nmi": self.floor_quantile_nmi,
            "mission": {
                "floor_cov_m2": [list(r) for r in self.mission.floor_cov_m2],
                "alignment_cov_m2": [list(r) for r in self.mission.alignment_cov_m2],
                "response_m_per_deg_h": list(self.mission.response_m_per_deg_h),
            },
            "spans_h": arr(self.spans_h),
            "drift_std_id_deg_h": arr(self.drift_std_id_deg_h),
            "cross_m_deg_h": [arr(c) for c in self.cross_m_deg_h],
            "walk_cov_m2": [[arr(r) for r in w] for w in self.walk_cov_m2],
            "drift_std_deg_h": arr(self.drift_std_deg_h),
            "share_within": arr(self.share_within),
            "quantile_nmi": arr(self.quantile_nmi),
        }


def _thermal_std(coeff_std: float, temp_change: float) -> float:
    return _finite("coeff_std_deg_h_per_c", coeff_std, low=0.0) * abs(_finite("temp_change_c", temp_change))


def plan_identification(
    noise: SensorNoise,
    *,
    scenario=None,
    lat_deg: float | None = None,
    budget: MissionBudget | None = None,
    coeff_std_deg_h_per_c: float = 0.0,
    temp_change_c: float = 0.0,
    min_span_h: float = 6.0,
    max_span_h: float = 48.0,
    step_h: float = 0.25,
    timeline: Timeline = DEFAULT_TIMELINE,
) -> Plan:
    """How long to observe: the drift 1-sigma, the predicted mission error and the shortest span meeting `budget`.

    Parameters
    ----------
    noise : SensorNoise
        The sensors' noise (`gyrodrift allan`'s noise.toml, a scenario's keys).
    scenario : Scenario, optional
        Site, sample rate, rotation scheme and attitude (default: the default scenario at `lat_deg`).
    lat_deg : float, optional
        Site latitude [deg] when no scenario is given (with one, it overrides the scenario's site).
    budget : MissionBudget, optional
        Default 1 nmi at 72 h for 95 % of runs.
    coeff_std_deg_h_per_c, temp_change_c : float
        Thermal situation: the 1-sigma of the z gyro's thermal coefficient [deg/h/degC] and the temperature change
        the identification does not see through [degC] (module docs, point 2).
    min_span_h, max_span_h, step_h : float
        The spans searched [h] from the first sample (every `step_h`; at most about 55 h: the smoother's
        20 000 updates of 10 s).
    """
    budget = budget or MissionBudget()
    lo = _finite("min_span_h", min_span_h, low=0.5)
    hi = _finite("max_span_h", max_span_h, low=lo, high=_MAX_SPAN_H)
    step = _finite("step_h", step_h, low=1.0 / 60.0, open_low=False)
    if not hi > lo:
        raise InputError(f"max_span_h: expected a number > min_span_h ({lo:g} h), got {hi:g}")
    if scenario is None:
        if lat_deg is None:
            raise InputError("the planner needs a scenario or a latitude (lat_deg)")
        scn = _scenario_for(_finite("lat_deg", lat_deg, low=-90.0, high=90.0))
    elif lat_deg is not None:
        site = dataclasses.replace(scenario.site, lat_deg=_finite("lat_deg", lat_deg, low=-90.0, high=90.0))
        scn = dataclasses.replace(scenario, site=site)
    else:
        scn = scenario
    thermal = _thermal_std(coeff_std_deg_h_per_c, temp_change_c)
    spans = np.arange(lo, hi + 1e-9, step)
    if spans[-1] < hi - 1e-9:
        spans = np.append(spans, hi)
    curve = identification_curve(noise, spans, scenario=scn, timeline=timeline, mission_h=budget.hours)
    sid, cross, walk = curve.drift_std_deg_h, curve.cross_m_deg_h, curve.walk_cov_m2
    s = np.hypot(sid, thermal)
    mission = mission_error_model(
        scn.site.lat_deg,
        noise,
        hours=budget.hours,
        height_m=scn.site.height_m,
        alignment_cov_m2=curve.alignment_cov_m2,
    )
    each = list(zip(s, cross, walk, strict=True))
    share = np.array([mission.share_within(x, budget.error_nmi, c, w) for x, c, w in each])
    quant = np.array([mission.quantile_nmi(x, budget.share, c, w) for x, c, w in each])
    meets = share >= budget.share
    at = int(np.argmax(meets)) if meets.any() else len(spans) - 1  # the span the budget's allowance is quoted at
    floor_q = mission.quantile_nmi(0.0, budget.share, walk_cov_m2=walk[at])
    s_max = mission.max_drift_std_deg_h(budget, cross[at] / sid[at] if sid[at] > 0 else (0.0, 0.0), walk[at])
    pct = f"{100 * budget.share:g} %"
    if s_max is None:
        shortest, reason = (
            None,
            (
                f"no span meets {budget.describe()}: the error floor alone (the exact drift: the noise, the gyro's "
                f"slow bias and the alignment's leftovers) leaves the {pct} quantile at {floor_q:.2f} nmi"
            ),
        )
    elif s_max <= thermal:
        shortest, reason = (
            None,
            (
                f"no span meets {budget.describe()}: the thermal term alone ({thermal:.2e} deg/h: k_z 1-sigma "
                f"{coeff_std_deg_h_per_c:g} deg/h/degC over {temp_change_c:g} degC) exceeds the {s_max:.2e} deg/h the "
                "budget allows; learn k_z better or keep the temperature steadier"
            ),
        )
    elif not meets.any():
        shortest, reason = (
            None,
            (
                f"no span up to {spans[-1]:g} h meets {budget.describe()}: the drift 1-sigma there is "
                f"{s[-1]:.2e} deg/h, the budget allows {s_max:.2e} ({pct} quantile {quant[-1]:.2f} nmi)"
            ),
        )
    else:
        i = int(np.argmax(meets))
        shortest = float(spans[i])
        if i == 0:
            reason = (
                f"the shortest span searched, {shortest:g} h, already meets {budget.describe()} ({pct} quantile "
                f"{quant[0]:.2f} nmi; drift 1-sigma {s[0]:.2e} deg/h, the budget allows {s_max:.2e})"
            )
        else:
            reason = (
                f"observe at least {shortest:g} h (alignment + static navigation) to meet {budget.describe()}: "
                f"drift 1-sigma {s[i]:.2e} deg/h (the budget allows {s_max:.2e}), {pct} quantile {quant[i]:.2f} nmi"
            )
    return Plan(
        lat_deg=float(scn.site.lat_deg),
        noise=noise,
        rotation=str(scn.rotation.scheme),
        budget=budget,
        coeff_std_deg_h_per_c=float(coeff_std_deg_h_per_c),
        temp_change_c=float(temp_change_c),
        spans_h=spans,
        drift_std_id_deg_h=sid,
        cross_m_deg_h=cross,
        walk_cov_m2=walk,
        drift_std_deg_h=s,
        share_within=share,
        quantile_nmi=quant,
        floor_quantile_nmi=floor_q,
        max_drift_std_deg_h=s_max,
        shortest_span_h=shortest,
        reason=reason,
        mission=mission,
    )


def mission_outlook(
    drift_std_deg_h: float,
    lat_deg: float,
    noise: SensorNoise,
    *,
    span_h: float,
    budget: MissionBudget | None = None,
    probs: Sequence[float] = DEFAULT_QUANTILES,
    source: str = "",
) -> dict[str, Any]:
    """What an identified drift's 1-sigma [deg/h] means for the mission at `lat_deg` (`gyrodrift identify`).

    Returns a JSON-ready dict: ``quantiles_nmi`` (probability -> predicted error quantile after compensation
    [nmi]), ``share_within`` (predicted share within the budget), ``ready`` (meets the budget), ``max_drift_std_deg_h``
    (what the budget allows), ``more_static_h`` (None when ready or when no span would do; else about how many
    more hours of static observation: the planner's curve for this noise and site with the default rotation
    scheme, scaled to pass through this run's 1-sigma at its `span_h`), and a one-line ``note``.
    """
    budget = budget or MissionBudget()
    s = _finite("drift_std_deg_h", drift_std_deg_h, low=0.0)
    span = _finite("span_h", span_h, low=0.5, high=_MAX_SPAN_H - 0.25)
    # The planner's curve from this span on, scaled through this run's 1-sigma (and its covariance with the floor).
    curve = identification_curve(noise, np.arange(span, _MAX_SPAN_H, 0.25), lat_deg=lat_deg, mission_h=budget.hours)
    mission = mission_error_model(lat_deg, noise, hours=budget.hours, alignment_cov_m2=curve.alignment_cov_m2)
    scale = s / curve.drift_std_deg_h[0] if curve.drift_std_deg_h[0] > 0 else 0.0
    stds, crosses, walks = curve.drift_std_deg_h * scale, curve.cross_m_deg_h * scale, curve.walk_cov_m2
    quant = {f"{p:g}": mission.quantile_nmi(s, p, crosses[0], walks[0]) for p in probs}
    share = mission.share_within(s, budget.error_nmi, crosses[0], walks[0])
    s_max = mission.max_drift_std_deg_h(budget, crosses[0] / s if s > 0 else (0.0, 0.0), walks[0])
    ready = share >= budget.share
    more: float | None = None
    q = mission.quantile_nmi(s, budget.share, crosses[0], walks[0])
    if ready:
        note = f"ready: predicted {100 * budget.share:g} % quantile {q:.2f} nmi meets {budget.describe()}"
    elif s_max is None:
        note = (
            f"not ready, and no static time will do: the error floor alone (the exact drift) misses {budget.describe()}"
        )
    else:
        ok = [
            k
            for k in range(1, len(stds))
            if mission.share_within(stds[k], budget.error_nmi, crosses[k], walks[k]) >= budget.share
        ][:1]
        if ok:
            more = float(curve.spans_h[ok[0]] - span)
            note = (
                f"not ready: predicted {100 * budget.share:g} % quantile {q:.2f} nmi misses {budget.describe()}; "
                f"about {more:g} h more static time would bring the drift 1-sigma from {s:.2e} to "
                f"{stds[ok[0]]:.2e} deg/h"
            )
        else:
            note = (
                f"not ready: predicted {100 * budget.share:g} % quantile {q:.2f} nmi misses {budget.describe()}, and "
                f"no span up to {_MAX_SPAN_H:g} h brings the drift 1-sigma ({s:.2e} deg/h) within it"
            )
    return {
        "drift_std_deg_h": s,
        "drift_std_source": source,
        "lat_deg": float(lat_deg),
        "budget": {"error_nmi": budget.error_nmi, "hours": budget.hours, "share": budget.share},
        "quantiles_nmi": quant,
        "share_within": share,
        "max_drift_std_deg_h": s_max,
        "ready": bool(ready),
        "more_static_h": more,
        "note": note,
    }
