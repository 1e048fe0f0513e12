"""The offline oracle of a drift law: the (eps_ref, k1) that minimise a run's 72 h criterion given its temperature.

`gyrodrift.procedure.truth` finds the best constant; this module extends it to the law
eps(T) = eps_ref + k1 (T - T_ref) (`gyrodrift.drift_law.DriftLaw`) by the same linearity. Compensating the law
subtracts the constant eps_ref and k1 times the measured signal (T - T_ref), so to first order the error curves are

    north(t) = n0(t) + eps_ref g_N(t) + k1 h_N(t),   east(t) = e0(t) + eps_ref g_E(t) + k1 h_E(t),

g [m per deg/h] the truth's response to a constant (its secant, or the central difference of its verification
read), h [m per deg/h/degC] the response to k1: one more navigator in the truth's first read compensates
``K1_TRIAL_DEG_H_PER_C (T - BASIS_T_REF_C)`` alone (`law_basis`), and since (T - BASIS_T_REF_C) = (T - T_ref) +
(T_ref - BASIS_T_REF_C), h = (c_basis - c0) / K1_TRIAL - (T_ref - BASIS_T_REF_C) g (`k1_response`).

* T_ref is the identified law's: the temperature at the end of the features window (``RunFeatures.temp_end_c``),
  so eps_ref is comparable with the identified eps_ref and the best constant.
* The criterion is minimised over both coefficients (`best_law_coefficients`): ``final`` and ``rms`` are linear
  least squares over the last sample or all samples (``final``: two coefficients meet the two equations, north and
  east at hour 72, so its predicted final error is 0: the oracle's worth is then in its coefficients and their
  covariance); ``max`` is convex in the two: Nelder-Mead from the ``rms`` optimum.
* k3 (the rate term) is not fitted: the identified law has none (the smoother carries no rate state), and the rate
  of a daily swing is a quarter period out of phase with its temperature, so over 72 h the k3 response is nearly
  a combination of the constant's and k1's (a third column that mostly fits noise).
* Covariance at the log's noise level (`law_covariance`): the constant's label variance sigma_c^2 (the core's
  covariance analysis, `gyrodrift.procedure.truth.label_sigma_deg_h`) carried to two coefficients as least
  squares does for an error the fit does not explain that is white and isotropic over the samples used:
  ``Cov = sigma_c^2 |g|^2 (A'A)^-1``, ``A = [g h]`` stacked north and east. Its eps_ref variance is sigma_c^2 times the
  variance inflation factor of the two responses (>= 1; exactly sigma_c^2 when h is orthogonal to g). An
  approximation where the unexplained error is coloured (it is: a random walk), stated as such.
* k1 is undetermined when the temperature hardly moves over the navigation: the effective excursion
  ``sqrt(|h|^2 / |g|^2)`` [degC] (the rms of T - T_ref as the error curves weigh it) below
  ``MIN_EXCURSION_C``, or A'A singular. The best law is then the best constant (``DriftLaw.constant``; k1 = 0,
  ``determined`` False, ``note`` says why) rather than a noisy k1.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.drift_law import DriftLaw
from gyrodrift.procedure.best_law import BestLaw

__all__ = [
    "BASIS_T_REF_C",
    "CriterionValue",
    "K1_TRIAL_DEG_H_PER_C",
    "MIN_EXCURSION_C",
    "LawModel",
    "best_law_coefficients",
    "k1_response",
    "law_basis",
    "law_covariance",
]

K1_TRIAL_DEG_H_PER_C = 1e-4
"""k1 of the basis navigation [deg/h/degC] (the default campaign's thermal coefficient is 2e-4)."""
BASIS_T_REF_C = 20.0
"""T_ref of the basis navigation [deg C] (any value: `k1_response` moves it to the law's T_ref)."""
MIN_EXCURSION_C = 0.5
"""Least effective temperature excursion over the navigation [deg C] for k1 to be fitted (the smoother's least
temperature range for its thermal model)."""


CriterionValue = Callable[[np.ndarray, np.ndarray, str], Any]
"""The criterion [nmi] of error curves (north, east [m], the criterion's name):
`gyrodrift.procedure.truth.criterion_value`, handed in by the truth (which imports this module, not the reverse)."""


def law_basis() -> DriftLaw:
    """The law the basis navigator compensates: ``K1_TRIAL_DEG_H_PER_C (T - BASIS_T_REF_C)`` alone."""
    return DriftLaw(eps_ref_deg_h=0.0, t_ref_c=BASIS_T_REF_C, k1_deg_h_per_c=K1_TRIAL_DEG_H_PER_C)


def k1_response(basis_n, basis_e, n0, e0, gn, ge, t_ref_c: float) -> tuple[np.ndarray, np.ndarray]:
    """h (north, east) [m per deg/h/degC] about `t_ref_c` from the basis navigation's curves, the uncompensated
    ones (n0, e0) [m] and the constant's response g [m per deg/h]."""
    shift = t_ref_c - BASIS_T_REF_C
    hn = (np.asarray(basis_n, float) - n0) / K1_TRIAL_DEG_H_PER_C - shift * np.asarray(gn, float)
    he = (np.asarray(basis_e, float) - e0) / K1_TRIAL_DEG_H_PER_C - shift * np.asarray(ge, float)
    return hn, he


def _design(gn, ge, hn, he, criterion: str) -> np.ndarray:
    """A = [g h] over the criterion's samples, north rows then east rows."""
    sl = slice(-1, None) if criterion == "final" else slice(None)
    g = np.concatenate([np.asarray(gn, float)[sl], np.asarray(ge, float)[sl]])
    h = np.concatenate([np.asarray(hn, float)[sl], np.asarray(he, float)[sl]])
    return np.column_stack([g, h])


def best_law_coefficients(
    ref_d: float, ref_n, ref_e, gn, ge, hn, he, criterion: str, value: CriterionValue
) -> tuple[float, float]:
    """(eps_ref [deg/h], k1 [deg/h/degC]) minimising the criterion of ``ref + (eps_ref - ref_d) g + k1 h`` (`value`
    computes it; ``max`` needs it)."""
    a = _design(gn, ge, hn, he, criterion)
    sl = slice(-1, None) if criterion == "final" else slice(None)
    r = np.concatenate([np.asarray(ref_n, float)[sl], np.asarray(ref_e, float)[sl]])
    (u, k1), *_ = np.linalg.lstsq(a, -r, rcond=None)
    if criterion == "max":
        from scipy.optimize import minimize  # here: scipy.optimize costs ~0.4 s of every CLI start

        n, e = (np.asarray(x, float) for x in (ref_n, ref_e))
        gn, ge, hn, he = (np.asarray(x, float) for x in (gn, ge, hn, he))

        def f(x: np.ndarray) -> float:
            return float(value(n + x[0] * gn + x[1] * hn, e + x[0] * ge + x[1] * he, "max"))

        # Convex: start at the rms optimum, scaled so that both coordinates are of order 1.
        u_rms, k1_rms = best_law_coefficients(0.0, n, e, gn, ge, hn, he, "rms", value)
        scale = np.array([max(abs(u_rms), 1e-4), max(abs(k1_rms), 1e-5)])
        res = minimize(
            lambda y: f(y * scale),
            np.array([u_rms, k1_rms]) / scale,
            method="Nelder-Mead",
            options={"xatol": 1e-9, "fatol": 1e-12, "maxiter": 4000},
        )
        u, k1 = res.x * scale
    return float(ref_d + u), float(k1)


def law_covariance(gn, ge, hn, he, criterion: str, constant_std_deg_h: float) -> np.ndarray:
    """2 x 2 covariance of (eps_ref, k1) at the log's noise level from the constant's label 1-sigma (module
    docstring): ``sigma_c^2 |g|^2 (A'A)^-1``."""
    a = _design(gn, ge, hn, he, criterion)
    m = a.T @ a
    return constant_std_deg_h**2 * m[0, 0] * np.linalg.inv(m)


@dataclass(frozen=True)
class LawModel:
    """The law's half of a truth's linear model: h about T_ref and whether k1 can be fitted (module docstring).

    Built once from the first read (`from_basis`); `law` and `result` take the constant's current linearisation
    point (``ref_d`` [deg/h] and its curves [m]) and response g [m per deg/h].
    """

    criterion: str
    value: CriterionValue = field(repr=False)
    t_ref_c: float
    hn: np.ndarray = field(repr=False)
    he: np.ndarray = field(repr=False)
    excursion_c: float
    note: str

    @classmethod
    def from_basis(
        cls, basis_n, basis_e, n0, e0, gn, ge, t_ref_c: float, criterion: str, value: CriterionValue
    ) -> LawModel:
        hn, he = k1_response(basis_n, basis_e, n0, e0, gn, ge, t_ref_c)
        m = _design(gn, ge, hn, he, criterion)
        m = m.T @ m
        g2, h2 = float(m[0, 0]), float(m[1, 1])
        excursion = math.sqrt(h2 / g2) if g2 > 0 else math.nan
        note = ""
        if not (math.isfinite(excursion) and excursion >= MIN_EXCURSION_C):
            note = (
                f"the temperature hardly moves over the navigation (effective excursion {excursion:.2g} deg C < "
                f"{MIN_EXCURSION_C:g} deg C): k1 is undetermined, the best law is the best constant"
            )
        elif not float(np.linalg.det(m)) > 1e-12 * g2 * h2:
            note = "the responses to eps_ref and k1 are collinear: k1 is undetermined; the best law is the constant"
        return cls(criterion, value, float(t_ref_c), hn, he, excursion, note)

    @property
    def determined(self) -> bool:
        """k1 can be fitted."""
        return not self.note

    def law(self, ref_d: float, ref_n, ref_e, gn, ge) -> DriftLaw:
        """The best law's coefficients (no covariance) at this linearisation (a law to navigate)."""
        eps_ref, k1 = best_law_coefficients(ref_d, ref_n, ref_e, gn, ge, self.hn, self.he, self.criterion, self.value)
        return DriftLaw(eps_ref_deg_h=eps_ref, t_ref_c=self.t_ref_c, k1_deg_h_per_c=k1)

    def result(
        self,
        ref_d: float,
        ref_n,
        ref_e,
        gn,
        ge,
        *,
        constant_deg_h: float,
        constant_std_deg_h: float,
        constant_nmi: float,
        navigated_nmi: float = math.nan,
    ) -> BestLaw:
        """The `BestLaw`: the law at this linearisation with its covariance from the constant's 1-sigma, or the best
        constant (`constant_deg_h`, `constant_std_deg_h`, criterion `constant_nmi` [nmi]) when k1 is undetermined;
        `navigated_nmi` the criterion of a navigation compensating `law` at the same linearisation."""
        # a 1-sigma of 0 (a noise-free log: no noise measured) is no covariance: the law's 1-sigmas are unknown
        std = constant_std_deg_h if math.isfinite(constant_std_deg_h) and constant_std_deg_h > 0 else None
        if not self.determined:
            law = DriftLaw.constant(constant_deg_h, std, t_ref_c=self.t_ref_c)
            return BestLaw(law, False, self.note, constant_nmi, math.nan, self.excursion_c, self.hn, self.he)
        fit = self.law(ref_d, ref_n, ref_e, gn, ge)
        u, k1 = fit.eps_ref_deg_h - ref_d, fit.k1_deg_h_per_c
        n_pred = np.asarray(ref_n, float) + u * np.asarray(gn, float) + k1 * self.hn
        e_pred = np.asarray(ref_e, float) + u * np.asarray(ge, float) + k1 * self.he
        cov = None
        if std is not None:
            c = law_covariance(gn, ge, self.hn, self.he, self.criterion, std)
            c = 0.5 * (c + c.T)
            cov = ((float(c[0, 0]), float(c[0, 1]), 0.0), (float(c[1, 0]), float(c[1, 1]), 0.0), (0.0, 0.0, 0.0))
        law = DriftLaw(eps_ref_deg_h=fit.eps_ref_deg_h, t_ref_c=self.t_ref_c, k1_deg_h_per_c=k1, cov=cov)
        predicted = float(self.value(n_pred, e_pred, self.criterion))
        return BestLaw(law, True, "", predicted, navigated_nmi, self.excursion_c, self.hn, self.he)
