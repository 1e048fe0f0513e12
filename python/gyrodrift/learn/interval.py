"""The interval of a drift model: the learner's spread (a Gaussian process), its calibration on out-of-sample
scores, and the half-width ``t c sqrt(l(x)^2 + s_rms^2 + b(x)^2)`` [deg/h] of an interval for the label a new run
would get (conservative for its drift itself by the label noise's share):

* the physics' share: ``s_rms`` the training runs' rms label 1-sigma, ``b(x)`` the new run's base 1-sigma (0
  without one; `gyrodrift.learn.physics_base`);
* the learner's share ``l(x)``: the 1-sigma of the learned term from a Gaussian process fitted to the LSSVR's
  target with a linear trend, one RBF length scale per input, the label 1-sigmas as known noise and a run-to-run
  term (`gyrodrift.learn.spread.SpreadGP`; larger away from the training runs), plus how far the LSSVR's prediction
  departs from the GP's mean beyond the largest such departure among the training runs; capped at the learned
  term's own prior 1-sigma over the training range (``learned_cap_deg_h_``, `SpreadGP.prior_std`), so that far
  out the interval is never wider than ``t c (sqrt(s_rms^2 + b^2) + cap)``;
* the calibration ``t c`` (``scale_``, `gyrodrift.learn.spread.calibration_scale`): ``c`` the robust scale of
  the n scores ``r_i / sqrt(m_i^2 + s_i^2 + b_i^2)`` (``r_i`` run i's out-of-sample residual: the closed-form
  leave-one-out one, or out-of-fold with ``calibration_folds``; ``m_i`` the GP's out-of-sample 1-sigma of the
  learned term, ``s_i``, ``b_i`` its label's and base's), wild scores left out and named
  (`IntervalOutlierWarning`), times `tuning_inflation` (n) for having tuned gamma and sigma on leave-one-out
  residuals; ``t`` the Student-t quantile with ``n_used - 1`` degrees of freedom. `DriftInterval.summary` and
  `DriftInterval.note` say on how many runs it rests and how much wider it is than the physics alone.

docs/identification.md, "Intervals and extrapolation", and docs/studies/2026-11-27-intervals.md (coverage and
width over 8-140-run fleets).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from gyrodrift.errors import InputError, OptionError
from gyrodrift.learn.spread import CalibrationScale, SpreadGP, calibration_scale

__all__ = [
    "DEFAULT_CALIBRATION_FOLDS",
    "MIN_FOLD_RUNS",
    "DriftInterval",
    "IntervalOutlierWarning",
    "check_coverage",
    "jackknife_half_width",
    "min_runs_for_coverage",
    "tuning_inflation",
]


DEFAULT_CALIBRATION_FOLDS = 0
"""Folds of the interval's calibration (``DriftModel(calibration_folds=...)``). 0 (default): the LSSVR's
closed-form leave-one-out residuals at the tuned gamma and sigma, with the spread model's own leave-one-out
1-sigmas, their scale inflated by `tuning_inflation` for the optimism of having tuned on them (no refit: the
calibration costs one Gaussian-process fit). K >= 2: each run's residual comes from a model fitted and tuned
without its fold (K more tunings; no inflation)."""


def tuning_inflation(n_runs: int) -> float:
    """The factor on the calibration scale of closed-form leave-one-out scores at tuned hyperparameters
    [dimensionless]: ``sqrt(1 + TUNING_OPTIMISM / sqrt(n_runs))`` (1.31 at 8 runs, 1.22 at 16, 1.14 at 48, 1.08
    at 140).

    Tuning (gamma, sigma) on the leave-one-out residuals makes them smaller than a new run's error (the search
    picks the pair that happens to fit these runs best). Measured: on closed-form fleets (examples/interval_study.py,
    seeds 11-22 at 8-48 runs, 11-13 at 140; not the seeds of the study it is judged on) the median ratio of the
    held-out runs' mean squared score to the leave-one-out one was 1.86, 1.29, 1.42, 1.37 and 1.08 at 8, 16, 24,
    48 and 140 runs; ``1 + 2 / sqrt(n)`` follows it (docs/studies/2026-11-27-intervals.md)."""
    return math.sqrt(1.0 + TUNING_OPTIMISM / math.sqrt(max(int(n_runs), 1)))


TUNING_OPTIMISM = 2.0
"""See `tuning_inflation` [sqrt(runs)]."""


class IntervalOutlierWarning(UserWarning):
    """A training run's calibration score is wild (`gyrodrift.learn.spread.calibration_scale`): it is left out of the
    interval's scale, and named."""


def check_coverage(coverage) -> float:
    if isinstance(coverage, bool) or not isinstance(coverage, (int, float)) or not 0.0 < coverage < 1.0:
        raise OptionError(f"coverage must be within (0, 1), got {coverage!r}")
    return float(coverage)


def jackknife_half_width(residuals, coverage: float) -> float:
    """Half-width of the jackknife prediction interval from leave-one-out residuals [their unit].

    The ceil((n + 1) coverage)-th smallest ``|r_i|`` (Barber, Candes, Ramdas, Tibshirani 2021, "Predictive
    inference with the jackknife+", the plain jackknife interval): for exchangeable runs the interval
    prediction +- half-width covers a new run's true value with probability of about ``coverage`` (the
    guarantee of the plain jackknife is weaker than jackknife+'s, but it needs no refit per left-out run).
    ``inf`` when n is too small for the coverage asked (n < coverage / (1 - coverage)).
    """
    coverage = check_coverage(coverage)
    r = np.sort(np.abs(np.asarray(residuals, float)))
    if r.size == 0 or not np.all(np.isfinite(r)):
        raise InputError("need finite leave-one-out residuals for an interval")
    k = math.ceil((r.size + 1) * coverage)
    return float(r[k - 1]) if k <= r.size else math.inf


def min_runs_for_coverage(coverage: float) -> int:
    """Smallest number of leave-one-out residuals for which ``jackknife_half_width`` is finite."""
    coverage = check_coverage(coverage)
    n = 1
    while math.ceil((n + 1) * coverage) > n:
        n += 1
    return n


MIN_FOLD_RUNS = 3
"""Fewest runs per fold of an out-of-fold calibration: with fewer than twice as many training runs the closed-form
leave-one-out residuals calibrate the interval whatever ``calibration_folds`` asks."""


class DriftInterval:
    """The interval of a drift model, fitted in two steps on the training runs' scaled inputs ``Z`` (module
    docstring): `fit_spread` (the Gaussian process of the learned term), then `calibrate` (the out-of-sample scores
    and their scale). All in deg/h.

    Fitted attributes: ``spread_`` (`SpreadGP`), ``residuals_`` and ``spreads_`` (each training run's out-of-sample
    residual and the learner's 1-sigma there), ``scores_`` (the calibration scores, dimensionless), ``scale_``
    (`CalibrationScale`), ``learned_cap_deg_h_``, ``disagreement_deg_h_`` (the largest LSSVR/GP disagreement over
    the training runs), ``physics_std_deg_h_`` (each training run's label and base 1-sigma) and ``label_std_rms_``.
    """

    def fit_spread(self, Z, target, noise_std, *, theta=None, loo: bool = True) -> DriftInterval:
        """Fit the spread model to the learner's target ``target`` at scaled inputs ``Z`` with the known noise
        1-sigma ``noise_std`` (None: none known); ``theta``: its log hyperparameters as given (a model file's), no
        likelihood maximised; ``loo``: compute its leave-one-out 1-sigmas (`loo_spreads`)."""
        self.spread_ = SpreadGP(theta=theta).fit(Z, target, noise_std, loo=loo)
        return self

    def loo_spreads(self, noise_var) -> np.ndarray:
        """The learner's leave-one-out 1-sigma at each training run: the spread model's, label and base noise
        (variance ``noise_var`` [(deg/h)^2]) taken out."""
        return np.sqrt(np.maximum(self.spread_.loo_std_**2 - noise_var, 0.0))

    def calibrate(
        self,
        Z,
        residuals,
        spreads,
        noise_var,
        label_std_rms: float,
        *,
        inflation: float,
        learned: Callable[[np.ndarray], np.ndarray],
        disagreement: float | None = None,
    ) -> DriftInterval:
        """Calibrate on the training runs' out-of-sample ``residuals`` and learner 1-sigmas ``spreads`` with label and
        base noise variance ``noise_var``; ``inflation`` multiplies the scale (`tuning_inflation`, or 1);
        ``learned(Z)``: the LSSVR's learned term at scaled inputs (for the disagreement with the GP's mean, unless
        ``disagreement`` is given: a model file's record)."""
        self.residuals_, self.spreads_ = residuals, spreads
        self.label_std_rms_ = float(label_std_rms)
        self.scores_ = residuals / np.sqrt(spreads**2 + noise_var)
        self.scale_: CalibrationScale = calibration_scale(self.scores_, inflation=inflation)
        self.learned_cap_deg_h_ = self.spread_.prior_std()
        self.disagreement_deg_h_ = (
            float(np.max(self.disagreement(Z, learned(Z)))) if disagreement is None else float(disagreement)
        )
        self.physics_std_deg_h_ = np.sqrt(noise_var)  # the training runs' physics-known 1-sigma (label, base)
        return self

    def disagreement(self, Z, learned) -> np.ndarray:
        """``|LSSVR(z) - GP mean(z)|`` [deg/h] at scaled inputs ``Z`` given the LSSVR's learned term ``learned`` there
        (both fit the training runs; away from them the LSSVR's extrapolation may leave the GP's)."""
        return np.abs(learned - self.spread_.predict_mean(Z))

    def sigmas(self, Z, learned, base_std) -> tuple[np.ndarray, np.ndarray]:
        """``(learned, physics)`` 1-sigmas [deg/h] of each run's label about its prediction, before calibration:
        ``learned = min(sqrt(spread(x)^2 + e(x)^2), learned_cap_deg_h_)`` with ``e(x)`` the disagreement of the
        LSSVR's ``learned`` term and the GP mean beyond the largest among the training runs
        (``disagreement_deg_h_``), ``physics = sqrt(s_rms^2 + b(x)^2)`` (``base_std`` b, None: 0)."""
        excess = np.maximum(self.disagreement(Z, learned) - self.disagreement_deg_h_, 0.0)
        out = np.minimum(np.hypot(self.spread_.predict_std(Z), excess), self.learned_cap_deg_h_)
        if base_std is None:
            return out, np.full(len(Z), self.label_std_rms_)
        return out, np.sqrt(self.label_std_rms_**2 + base_std**2)

    def half_width(self, Z, learned, base_std, coverage: float) -> np.ndarray:
        """The interval's half-width [deg/h] at ``coverage``: ``t c sqrt(l(x)^2 + p(x)^2)`` (`sigmas`)."""
        learned_std, physics = self.sigmas(Z, learned, base_std)
        return self.scale_.multiplier(coverage) * np.sqrt(learned_std**2 + physics**2)

    def summary(self, coverage: float, runs: Sequence[str]) -> dict:
        """What the interval rests on (training run names ``runs``): ``n_runs``, ``n_used`` (scores in its scale),
        ``wild_runs`` (left out: `warnings`), ``scale`` (c, inflation included), ``inflation``, ``multiplier`` (t c
        at ``coverage``), ``learned_cap_deg_h``, and ``physics_ratio``: the median over the training runs of the
        half-width at their out-of-sample 1-sigma, ``t c sqrt(m_i^2 + p_i^2)``, over the physics alone's, ``z p_i``
        (``p_i = sqrt(s_i^2 + b_i^2)`` the run's label and base 1-sigma, ``m_i`` the learner's, ``z`` the normal
        quantile; None when the physics gives no 1-sigma). O(n): no prediction."""
        coverage = check_coverage(coverage)
        cal = self.scale_
        mult = cal.multiplier(coverage)
        physics = self.physics_std_deg_h_
        ratio = None
        if np.all(physics > 0):
            from scipy.special import ndtri  # the normal quantile; here: scipy.special costs ~0.2 s of a start

            z = float(ndtri(0.5 + coverage / 2.0))
            ratio = float(np.median(mult * np.hypot(self.spreads_, physics) / (z * physics)))
        return {
            "coverage": coverage,
            "n_runs": len(runs),
            "n_used": cal.n_used,
            "wild_runs": [str(runs[i]) for i in cal.wild],
            "scale": cal.scale,
            "inflation": cal.inflation,
            "multiplier": mult,
            "learned_cap_deg_h": float(self.learned_cap_deg_h_),
            "physics_ratio": ratio,
        }

    def note(self, coverage: float, runs: Sequence[str]) -> str:
        """`summary` in one line (what ``fit`` and ``identify`` say)."""
        s = self.summary(coverage, runs)
        rests = (
            f"rests on {s['n_used']} of {s['n_runs']} training runs"
            if s["wild_runs"]
            else (f"rests on {s['n_runs']} training runs")
        )
        how = f"calibration scale {s['scale']:.2f}"
        if s["inflation"] != 1.0:
            how += f" incl. x{s['inflation']:.2f} for tuning on the leave-one-out residuals"
        wider = (
            "no physics 1-sigma to compare with"
            if s["physics_ratio"] is None
            else f"{s['physics_ratio']:.2f} times the physics alone (label and base 1-sigma) at the median training run"
        )
        return f"{100 * s['coverage']:g} % interval {rests} ({how}); {wider}"

    def warnings(self, runs: Sequence[str]) -> list[str]:
        """One message naming the training runs (names ``runs``) whose calibration score is wild (left out of the
        interval's scale; `gyrodrift.learn.spread.calibration_scale`), or none."""
        cal = self.scale_
        if not len(cal.wild):
            return []
        wild = ", ".join(f"{runs[i]} ({self.scores_[i]:+.2f})" for i in cal.wild)
        return [
            f"interval: calibration score(s) of run(s) {wild} are wild against the scale "
            f"{cal.scale / cal.inflation:.2f} of the other {cal.n_used} runs (leave-one-out t-test, family-wise 5 %): "
            f"left out of the interval's scale "
            f"(with them its plain rms would be {cal.raw_rms:.2f}); check those runs' labels and inputs"
        ]
