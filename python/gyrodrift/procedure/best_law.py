"""The best drift law of a run as the truth reports it: a result type (`gyrodrift.procedure.truth_law` finds it).

Beside `gyrodrift.procedure.results` (which holds it in ``TrueDrift.law``), importing nothing of the procedure's
algorithms: the law, whether k1 was determined, the criterion predicted and navigated, and the error curves'
response to k1 from which any law's error follows without navigating again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.drift_law import DriftLaw

__all__ = ["BestLaw"]


@dataclass(frozen=True)
class BestLaw:
    """The best drift law of a run (module docstring).

    Attributes
    ----------
    law : DriftLaw
        (eps_ref, k1) at T_ref with their covariance; the best constant when k1 is undetermined.
    determined : bool
        k1 was fitted (False: the law is the constant, ``note`` says why).
    note : str
    predicted_nmi : float
        The criterion at the law from the linear model [nmi].
    navigated_nmi : float
        The criterion of a navigation compensating the law (the truth's verification read) [nmi]; NaN without it.
    excursion_c : float
        Effective temperature excursion ``sqrt(|h|^2 / |g|^2)`` over the criterion's samples [deg C].
    north_per_k1_m, east_per_k1_m : ndarray
        h: the error curves' response to k1 about T_ref [m per deg/h/degC] (with the truth's curves, the error of
        any law eps_ref + k1 (T - T_ref) without navigating again).
    """

    law: DriftLaw
    determined: bool
    note: str
    predicted_nmi: float
    navigated_nmi: float = math.nan
    excursion_c: float = math.nan
    north_per_k1_m: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    east_per_k1_m: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)

    def columns(self) -> dict[str, float]:
        """The run-table columns `gyrodrift.runs.columns.TRUTH_LAW_COLUMNS` (k1 0 and its 1-sigma and covariance
        NaN when k1 is undetermined; 1-sigmas NaN without a covariance)."""
        law = self.law
        c = np.full((3, 3), math.nan) if law.cov is None else np.asarray(law.cov, dtype=float)
        if not self.determined:
            c[1, :] = c[:, 1] = math.nan
        return {
            "truth_law_eps_ref_deg_h": law.eps_ref_deg_h,
            "truth_law_eps_ref_std_deg_h": math.sqrt(c[0, 0]),
            "truth_law_k1_deg_h_per_c": law.k1_deg_h_per_c,
            "truth_law_k1_std_deg_h_per_c": math.sqrt(c[1, 1]),
            "truth_law_eps_k1_cov": float(c[0, 1]),
            "truth_law_t_ref_c": law.t_ref_c,
        }

    def summary(self) -> str:
        """One line for `gyrodrift truth`: the law with its 1-sigmas and its criterion, or why it is the constant."""
        if not self.determined:
            return f"best law: the best constant ({self.note})"
        law = self.law
        sd = [math.nan, math.nan] if law.cov is None else [math.sqrt(law.cov[i][i]) for i in (0, 1)]
        navigated = f", {self.navigated_nmi:.4f} nmi navigated" if math.isfinite(self.navigated_nmi) else ""
        return (
            f"best law: {law.eps_ref_deg_h:.7f} +- {sd[0]:.7f} deg/h + ({law.k1_deg_h_per_c:.3e} +- {sd[1]:.1e} "
            f"deg/h/degC) (T - {law.t_ref_c:.2f} degC); criterion {self.predicted_nmi:.4f} nmi predicted{navigated}"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (the ``best_law`` object of truth.json)."""

        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {
            "drift_law": self.law.to_dict(),
            "k1_determined": self.determined,
            "note": self.note,
            "predicted_nmi": num(self.predicted_nmi),
            "navigated_nmi": num(self.navigated_nmi),
            "excursion_c": num(self.excursion_c),
        }
