"""The axial drift as a law of the measured temperature, and the streaming temperature rate it reads.

The axial (z, rotation-axis) gyro drift to subtract, as a function of what the navigation computer measures:

    eps(T, dT/dt) = eps_ref + k1 (T - T_ref) + k3 dT/dt

with eps [deg/h], T the system temperature [deg C], T_ref the reference temperature [deg C], k1 [deg/h/degC],
k3 [deg/h per degC/h] and dT/dt [degC/h]. A constant drift is the law with k1 = k3 = 0. Subtract the law from
the measured z rate (the sign convention of every drift in gyrodrift).

dT/dt is estimated causally, sample by sample, by `TemperatureRate`: a first-order low-pass f of the temperature
with time constant tau, and the rate read from the lag T - f, which is exact for a temperature ramp once the
filter has settled (after a few tau). The generated C and Rust of `gyrodrift export` run the same recursion.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrodrift.errors import InputError

__all__ = ["DriftLaw", "TemperatureRate", "DEFAULT_RATE_TAU_S"]

DEFAULT_RATE_TAU_S = 600.0
"""Time constant of the temperature-rate estimate [s]: long against the temperature's quantisation noise, short
against a daily swing (the lag of a 24 h sine's rate at 600 s is 2.5 deg of phase)."""

_COEFFICIENTS = ("eps_ref_deg_h", "k1_deg_h_per_c", "k3_deg_h_per_c_per_h")
"""The law's coefficients in the order of its covariance."""


@dataclass(frozen=True)
class DriftLaw:
    """eps(T, dT/dt) = eps_ref + k1 (T - T_ref) + k3 dT/dt: the axial drift to subtract [deg/h].

    Attributes
    ----------
    eps_ref_deg_h : float
        Drift at the reference temperature with a steady temperature [deg/h].
    t_ref_c : float
        Reference temperature [deg C]. An identified law takes the end-of-alignment temperature, so that
        `eps_ref_deg_h` is the constant the law replaces.
    k1_deg_h_per_c : float
        Thermal coefficient [deg/h/degC].
    k3_deg_h_per_c_per_h : float
        Temperature-rate coefficient [deg/h per degC/h] (0 unless the data support it).
    cov : tuple of tuples (3 x 3) or None
        Joint covariance of (eps_ref, k1, k3) in [deg/h, deg/h/degC, deg/h per degC/h] units; rows and columns
        of coefficients held at 0 are 0. None when unknown.
    rate_tau_s : float
        Time constant of the temperature-rate estimate [s] (`TemperatureRate`).

    >>> law = DriftLaw(eps_ref_deg_h=0.004, t_ref_c=20.0, k1_deg_h_per_c=1e-4)
    >>> round(float(law.drift_deg_h(25.0)), 12)
    0.0045
    >>> DriftLaw.constant(0.004).is_constant
    True
    """

    eps_ref_deg_h: float
    t_ref_c: float = 20.0
    k1_deg_h_per_c: float = 0.0
    k3_deg_h_per_c_per_h: float = 0.0
    cov: tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]] | None = None
    rate_tau_s: float = DEFAULT_RATE_TAU_S

    def __post_init__(self) -> None:
        for name in ("eps_ref_deg_h", "t_ref_c", "k1_deg_h_per_c", "k3_deg_h_per_c_per_h"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                raise InputError(f"drift law: {name} must be a finite number, got {value!r}")
        if not (isinstance(self.rate_tau_s, (int, float)) and self.rate_tau_s > 0 and math.isfinite(self.rate_tau_s)):
            raise InputError(f"drift law: rate_tau_s must be a finite number > 0 s, got {self.rate_tau_s!r}")
        if self.cov is not None:
            c = np.asarray(self.cov, dtype=float)
            if c.shape != (3, 3) or not np.all(np.isfinite(c)):
                raise InputError("drift law: cov must be a finite 3 x 3 matrix over (eps_ref, k1, k3)")
            if not np.allclose(c, c.T, rtol=1e-9, atol=0.0) or np.any(np.diag(c) < 0):
                raise InputError("drift law: cov must be symmetric with variances >= 0")

    @classmethod
    def constant(cls, drift_deg_h: float, std_deg_h: float | None = None, t_ref_c: float = 20.0) -> DriftLaw:
        """The constant drift `drift_deg_h` [deg/h] as a law, with its 1-sigma `std_deg_h` [deg/h] if known."""
        cov = None
        if std_deg_h is not None:
            v = float(std_deg_h) ** 2
            cov = ((v, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        return cls(eps_ref_deg_h=float(drift_deg_h), t_ref_c=float(t_ref_c), cov=cov)

    @property
    def is_constant(self) -> bool:
        """True when the law does not depend on the temperature (k1 = k3 = 0)."""
        return self.k1_deg_h_per_c == 0.0 and self.k3_deg_h_per_c_per_h == 0.0

    @property
    def uses_rate(self) -> bool:
        """True when the law reads the temperature rate (k3 != 0)."""
        return self.k3_deg_h_per_c_per_h != 0.0

    def _gradient(self, temp_c: Any, rate_c_per_h: Any) -> np.ndarray:
        """d eps / d (eps_ref, k1, k3) at each point, shape (..., 3)."""
        t = np.asarray(temp_c, dtype=float)
        r = np.asarray(rate_c_per_h, dtype=float)
        t, r = np.broadcast_arrays(t, r)
        return np.stack([np.ones_like(t), t - self.t_ref_c, r], axis=-1)

    def drift_deg_h(self, temp_c: Any, rate_c_per_h: Any = 0.0) -> np.ndarray:
        """The drift to subtract [deg/h] at temperatures `temp_c` [deg C] and rates `rate_c_per_h` [degC/h]."""
        t = np.asarray(temp_c, dtype=float)
        r = np.asarray(rate_c_per_h, dtype=float)
        return self.eps_ref_deg_h + self.k1_deg_h_per_c * (t - self.t_ref_c) + self.k3_deg_h_per_c_per_h * r

    def std_deg_h(self, temp_c: Any, rate_c_per_h: Any = 0.0) -> np.ndarray:
        """1-sigma of `drift_deg_h` [deg/h] from `cov` (NaN where `cov` is None)."""
        g = self._gradient(temp_c, rate_c_per_h)
        if self.cov is None:
            return np.full(g.shape[:-1], np.nan)
        c = np.asarray(self.cov, dtype=float)
        return np.sqrt(np.maximum(np.einsum("...i,ij,...j->...", g, c, g), 0.0))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the ``drift_law`` object of model files and ``identification.json``)."""
        out: dict[str, Any] = {
            "law": "eps_ref + k1 (T - t_ref) + k3 dT/dt",
            "eps_ref_deg_h": self.eps_ref_deg_h,
            "t_ref_c": self.t_ref_c,
            "k1_deg_h_per_c": self.k1_deg_h_per_c,
            "k3_deg_h_per_c_per_h": self.k3_deg_h_per_c_per_h,
            "rate_tau_s": self.rate_tau_s,
            "cov_order": list(_COEFFICIENTS),
            "cov": None if self.cov is None else [list(row) for row in self.cov],
        }
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<drift law>") -> DriftLaw:
        """Read the form `to_dict` writes; errors name `source` and the key."""
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: drift_law must be an object, got {type(data).__name__}")
        known = {"law", "eps_ref_deg_h", "t_ref_c", "k1_deg_h_per_c", "k3_deg_h_per_c_per_h", "rate_tau_s"}
        known |= {"cov_order", "cov"}
        unknown = sorted(set(data) - known)
        if unknown:
            raise InputError(f"{source}: drift_law has unknown key(s) {', '.join(unknown)}")
        if "eps_ref_deg_h" not in data:
            raise InputError(f"{source}: drift_law needs eps_ref_deg_h [deg/h]")
        if data.get("cov_order", list(_COEFFICIENTS)) != list(_COEFFICIENTS):
            raise InputError(f"{source}: drift_law cov_order must be {list(_COEFFICIENTS)}")
        cov = data.get("cov")
        if cov is not None:
            try:
                cov = tuple(tuple(float(v) for v in row) for row in cov)
            except (TypeError, ValueError):
                raise InputError(f"{source}: drift_law cov must be a 3 x 3 list of numbers") from None
        try:
            return cls(
                eps_ref_deg_h=data["eps_ref_deg_h"],
                t_ref_c=data.get("t_ref_c", 20.0),
                k1_deg_h_per_c=data.get("k1_deg_h_per_c", 0.0),
                k3_deg_h_per_c_per_h=data.get("k3_deg_h_per_c_per_h", 0.0),
                cov=cov,  # type: ignore[arg-type]
                rate_tau_s=data.get("rate_tau_s", DEFAULT_RATE_TAU_S),
            )
        except InputError as exc:
            raise InputError(f"{source}: {exc}") from None


class TemperatureRate:
    """Causal estimate of dT/dt [degC/h] from temperature samples at a fixed interval, chunk by chunk.

    f_k = f_(k-1) + a (T_k - f_(k-1)) with a = 1 - exp(-dt / tau) and f_0 = T_0; the rate is
    (T_k - f_k) a / ((1 - a) dt), exact for a ramp once settled. Feeding a log in chunks gives the same
    rates as feeding it whole.

    >>> est = TemperatureRate(tau_s=600.0, dt_s=1.0)
    >>> t_h = np.arange(20000) / 3600.0
    >>> rate = est.update(20.0 + 2.0 * t_h)   # a 2 degC/h ramp
    >>> round(float(rate[-1]), 9)
    2.0
    """

    def __init__(self, tau_s: float, dt_s: float) -> None:
        if not (tau_s > 0 and dt_s > 0 and math.isfinite(tau_s) and math.isfinite(dt_s)):
            raise InputError(f"temperature rate: tau_s and dt_s must be > 0 s, got {tau_s!r}, {dt_s!r}")
        self.a = -math.expm1(-dt_s / tau_s)
        self.gain_per_h = self.a / ((1.0 - self.a) * dt_s) * 3600.0
        self._state: float | None = None

    def update(self, temp_c: Any) -> np.ndarray:
        """Rates [degC/h] for the next chunk of temperatures `temp_c` [deg C]."""
        from scipy.signal import lfilter

        t = np.asarray(temp_c, dtype=float)
        if t.size == 0:
            return np.empty(0)
        if self._state is None:
            self._state = float(t[0])
        zi = np.array([(1.0 - self.a) * self._state])
        f, _ = lfilter([self.a], [1.0, -(1.0 - self.a)], t, zi=zi)
        self._state = float(f[-1])
        return (t - f) * self.gain_per_h
