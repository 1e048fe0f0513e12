"""The physics base of a hybrid drift model: which physics estimate the learner's output is added to, the fleet's
k_z prior, and the label noise (label and base 1-sigmas) that weights the learner and feeds the interval.

A hybrid (``target="residual"``) learns the label minus a physics estimate (the *base*) and predicts base + learned
correction, so the learner models only what physics cannot (e.g. how the drift over the next 72 h follows
temperature). The base (``gyrodrift.choices.PHYSICS_COLUMNS``, computed by `physics_estimate`):
``"drift_smoother_fleet_deg_h"`` (the 16 h smoother's end drift re-weighted by the training fleet's pooled prior of
its thermal coefficient k_z, `gyrodrift.learn.fleet_prior`: a new run with the prior of all training runs, a training
run with the prior pooled without it), ``"drift_inversion_deg_h"`` (the 12 h inversion, computed from the table's
latitudes), a run-table column (``"drift_curvefit_deg_h"``, ``"drift_smoother_deg_h"``), or ``"auto"``, resolved on
the training runs by `resolve_physics_column` (the fleet base when the training runs allow it, else the smoother's
drift, else the inversion).

Label noise: ``label_weighting="auto"`` weights the runs by their label 1-sigma when the table has a
``drift_std_deg_h`` column (weighted LS-SVM, ``C_i = gamma w_i``, ``w_i = mean(v) / v_i``, `label_weights`);
with ``uncertainty="auto"`` and a base 1-sigma ``b_i`` for every training run (the fleet base's re-weighted one,
``drift_smoother_std_deg_h``, ``drift_curvefit_std_deg_h``; the inversion has none) the target label - base has
the noise of both, ``v_i = s_i^2 + b_i^2``; ``"none"``: never (model files of schema 3 and before). All in deg/h.
"""

from __future__ import annotations

import numpy as np

from gyrodrift.choices import BASE_UNCERTAINTIES, MIN_THERMAL_RUNS, PHYSICS_CHOICES, PHYSICS_COLUMNS, TARGETS
from gyrodrift.errors import InputError, OptionError
from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.learn.fleet_prior import (
    drift_with_coefficient_prior,
    leave_one_out_coefficient_priors,
    pooled_coefficient_prior,
)
from gyrodrift.runs.columns import COLUMNS, PHYSICS_BASE_COLUMNS, SMOOTHER_DRIFT_COLUMNS, SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import RunTable, check_smoother_thermal

__all__ = [
    "BASE_STD_COLUMNS",
    "FLEET_PHYSICS",
    "PhysicsBase",
    "fleet_priors",
    "label_weights",
    "physics_estimate",
    "resolve_physics_column",
    "thermal_runs",
]


def label_weights(std_deg_h) -> np.ndarray:
    """Weights of runs whose labels have 1-sigma ``std_deg_h`` [deg/h]: ``w_i = mean(s^2) / s_i^2``.

    The weighted LS-SVM's per-run regularisation is then ``C_i = gamma w_i = gamma / (s_i^2 / mean(s^2))``:
    a run twice as uncertain as the average counts a quarter, and equal sigmas give the unweighted model."""
    s2 = np.asarray(std_deg_h, float) ** 2
    if s2.size == 0 or not np.all(np.isfinite(s2)) or not np.all(s2 > 0):
        raise InputError("label 1-sigmas (drift_std_deg_h) must be finite and > 0 for every training run")
    return s2.mean() / s2


FLEET_PHYSICS = "drift_smoother_fleet_deg_h"
"""The fleet-prior smoother base (``PHYSICS_COLUMNS``): computed by the model, not a table column."""

BASE_STD_COLUMNS = {name: COLUMNS[name].std for name in PHYSICS_BASE_COLUMNS} | {
    FLEET_PHYSICS: COLUMNS["drift_smoother_deg_h"].std
}
"""The run-table column of the 1-sigma of a base [deg/h] (`gyrodrift.runs.columns`; the fleet base's is re-weighted from
the smoother drift's)."""


def missing_runs(runs: RunTable, values) -> str:
    missing = [str(r) for r, v in zip(runs.run, values, strict=True) if not np.isfinite(v)]
    return f"{', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''}"


def require_column(runs: RunTable, column: str, what: str) -> np.ndarray:
    """Column ``column`` of every run; else an ``InputError`` naming the table, the column and the runs."""
    if column not in runs.extra:
        raise InputError(f"{runs.source}: column {column} ({what}) is missing: the table has no such column")
    values = runs.column(column)
    if not np.all(np.isfinite(values)):
        raise InputError(f"{runs.source}: column {column} ({what}) is missing for run(s) {missing_runs(runs, values)}")
    return np.asarray(values, float)


def thermal_runs(runs: RunTable) -> np.ndarray:
    """True for the runs with the smoother's thermal estimate of k_z (every ``SMOOTHER_THERMAL_COLUMNS`` value
    usable: the test of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`); False under its constant model or
    without the columns."""
    k, sk, c, s0 = (runs.column(name) for name in SMOOTHER_THERMAL_COLUMNS)
    with np.errstate(over="ignore"):
        vk = sk * sk
    return np.isfinite(k) & np.isfinite(vk) & (vk > 0.0) & np.isfinite(c) & np.isfinite(s0) & (s0 > 0.0)


def resolve_physics_column(runs: RunTable) -> tuple[str, str]:
    """``(column, why)``: the physics base ``physics_column="auto"`` takes on training runs ``runs``.

    The fleet-prior smoother (``drift_smoother_fleet_deg_h``) when every run has ``SMOOTHER_DRIFT_COLUMNS`` and at
    least ``MIN_THERMAL_RUNS`` have a thermal k_z; else the smoother's drift (``drift_smoother_deg_h``) when
    every run has it; else the 12 h inversion (``drift_inversion_deg_h``). ``why`` says so in words."""
    n_thermal = int(thermal_runs(runs).sum())
    if all(runs.has_column(c) for c in SMOOTHER_DRIFT_COLUMNS):
        if n_thermal >= MIN_THERMAL_RUNS:
            return FLEET_PHYSICS, (
                f"every run has the smoother's drift and 1-sigma, {n_thermal} of {len(runs)} its thermal k_z: the "
                "16 h smoother's end drift with the fleet's pooled k_z prior"
            )
        why = f"{n_thermal} run(s) with the smoother's thermal k_z, the fleet prior needs {MIN_THERMAL_RUNS}"
        return "drift_smoother_deg_h", f"{why}: the 16 h smoother's end drift"
    if runs.has_column("drift_smoother_deg_h"):
        return "drift_smoother_deg_h", "no drift_smoother_std_deg_h for every run: the 16 h smoother's end drift"
    if "drift_smoother_deg_h" in runs.extra:
        values = runs.column("drift_smoother_deg_h")
        why = f"drift_smoother_deg_h is missing for run(s) {missing_runs(runs, values)}"
    else:
        why = "no smoother columns"
    return "drift_inversion_deg_h", f"{why}: the 12 h inversion"


def fleet_priors(runs: RunTable) -> tuple[tuple[float, float], np.ndarray]:
    """The fleet's k_z priors of training runs ``runs`` [deg/h/degC]: ``(prior, per_run)``.

    ``prior`` = `pooled_coefficient_prior` of every run's k_z (what a new run's base uses); ``per_run`` (n_runs,
    2): for each run with a thermal k_z the prior pooled from the *other* runs (leave one out: its own k_z is
    not counted twice, so its base is what a new run's would be), for the others ``prior`` (their base does not
    use it). ``InputError`` with fewer than ``MIN_THERMAL_RUNS`` thermal runs."""
    thermal = thermal_runs(runs)
    if int(thermal.sum()) < MIN_THERMAL_RUNS:
        raise InputError(
            f"{runs.source}: the physics base {FLEET_PHYSICS} needs at least {MIN_THERMAL_RUNS} training runs with "
            f"the smoother's thermal k_z ({', '.join(SMOOTHER_THERMAL_COLUMNS[:2])}; each run's base pools the "
            "others'), "
            f"got {int(thermal.sum())}"
        )
    k = np.where(thermal, runs.column(SMOOTHER_THERMAL_COLUMNS[0]), np.nan)
    sk = np.where(thermal, runs.column(SMOOTHER_THERMAL_COLUMNS[1]), np.nan)
    prior = pooled_coefficient_prior(k, sk)
    per_run = np.tile(np.asarray(prior, float), (len(runs), 1))
    rows = np.flatnonzero(thermal)
    per_run[rows] = leave_one_out_coefficient_priors(k, sk, rows)
    return prior, per_run


def physics_estimate(runs: RunTable, column: str = "drift_inversion_deg_h", *, prior=None, with_std: bool = False):
    """The physics estimate of each run's drift [deg/h] named by ``column`` (``PHYSICS_COLUMNS``).

    * ``"drift_inversion_deg_h"``: the 12 h inversion of the latitude error (`physics_inversion`);
    * ``"drift_smoother_fleet_deg_h"``: the smoother's end drift with the k_z prior ``prior`` in place of its own
      (`gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`): ``prior`` is ``(mean, std)`` [deg/h/degC] for
      every run (a model's ``coefficient_prior_``) or an (n_runs, 2) array, one prior per run (the leave-one-out
      priors of training runs, `fleet_priors`). Every run needs ``drift_smoother_deg_h``, and the table the
      ``SMOOTHER_THERMAL_COLUMNS`` (a run under the smoother's constant model has them empty: its base is its smoother
      drift unchanged); the 1-sigma comes from ``drift_smoother_std_deg_h`` (NaN without it);
    * any other name: an optional run-table column, which every run must have.

    A missing column gives an ``InputError`` naming the table, the column and the runs. ``with_std``: return
    ``(estimate, std)``, ``std`` the estimate's 1-sigma [deg/h] (the fleet base's re-weighted one, a column
    base's ``BASE_STD_COLUMNS`` column, NaN where a run has none; None for the inversion)."""
    if column not in PHYSICS_COLUMNS:
        raise OptionError(f"unknown physics column {column!r}; expected one of {', '.join(PHYSICS_COLUMNS)}")
    what = f"needed by the hybrid model's physics base {column}"
    if column == "drift_inversion_deg_h":
        estimate, std = physics_inversion(runs, t_h=12.0), None
    elif column == FLEET_PHYSICS:
        if prior is None:
            raise InputError(f"the physics estimate {FLEET_PHYSICS} needs the fleet's k_z prior")
        drift = require_column(runs, "drift_smoother_deg_h", what)
        drift_std = runs.column("drift_smoother_std_deg_h")
        for name in SMOOTHER_THERMAL_COLUMNS:
            if name not in runs.extra:
                raise InputError(f"{runs.source}: column {name} ({what}) is missing: the table has no such column")
        check_smoother_thermal(runs, what)
        k, sk, c, s0 = (runs.column(name) for name in SMOOTHER_THERMAL_COLUMNS)
        prior = np.asarray(prior, float)
        if prior.shape == (2,):
            estimate, std = drift_with_coefficient_prior(
                drift, drift_std, k, sk, c, s0, float(prior[0]), float(prior[1])
            )
        elif prior.shape == (len(runs), 2):  # elementwise: the floats of one call per run
            estimate, std = drift_with_coefficient_prior(drift, drift_std, k, sk, c, s0, prior[:, 0], prior[:, 1])
        else:
            raise InputError(f"a k_z prior is (mean, std) or one per run, shape ({len(runs)}, 2); got {prior.shape}")
    else:
        estimate = require_column(runs, column, what)
        std = np.asarray(runs.column(BASE_STD_COLUMNS[column]), float)
    estimate = np.asarray(estimate, float)
    return (estimate, None if std is None else np.asarray(std, float)) if with_std else estimate


class PhysicsBase:
    """The physics base and the label noise of a drift model, resolved on its training runs (module docstring).

    Parameters (keyword-only): ``target`` (``"drift"``: no base, the learner learns the drift itself;
    ``"residual"``: the hybrid), ``column`` (``PHYSICS_CHOICES``), ``uncertainty`` (``BASE_UNCERTAINTIES``),
    ``label_weighting`` (``"auto"`` or ``"none"``).

    Fitted attributes (`fit`): ``column_`` (the resolved base, None for ``target="drift"``), ``reason_`` (why, in
    words), ``coefficient_prior_`` (the fleet base's k_z prior ``(mean, std)`` [deg/h/degC] pooled from all training
    runs, else None), ``std_used_`` (whether the base's 1-sigma joins the label's); on the training runs, in deg/h:
    ``training_base_`` (the base, a fleet base with each run's leave-one-out prior; zeros without a base),
    ``noise_var_`` [(deg/h)^2] and ``noise_std_`` (label and base 1-sigma combined; None without either),
    ``label_std_rms_`` (the rms label 1-sigma, 0 without labels' 1-sigmas) and ``sample_weight_`` (the learner's
    `label_weights`, or None when the fit is unweighted).
    """

    def __init__(
        self,
        *,
        target: str = "drift",
        column: str = "auto",
        uncertainty: str = "auto",
        label_weighting: str = "auto",
    ) -> None:
        self.target = target
        self.column = column
        self.uncertainty = uncertainty
        self.label_weighting = label_weighting

    def _check_fitted(self) -> None:
        if not hasattr(self, "column_"):
            raise AttributeError("this PhysicsBase is not fitted yet: call fit with the training runs first")

    def check_options(self) -> None:
        """``OptionError`` naming an unknown target, column, uncertainty or label weighting."""
        if self.target not in TARGETS:
            raise OptionError(f"unknown target {self.target!r}; expected one of {', '.join(TARGETS)}")
        if self.column not in PHYSICS_CHOICES:
            raise OptionError(f"unknown physics column {self.column!r}; expected one of {', '.join(PHYSICS_CHOICES)}")
        if self.uncertainty not in BASE_UNCERTAINTIES:
            raise OptionError(
                f"unknown base uncertainty {self.uncertainty!r}; expected one of {', '.join(BASE_UNCERTAINTIES)}"
            )
        if self.label_weighting not in ("auto", "none"):
            raise OptionError(f"unknown label weighting {self.label_weighting!r}; expected auto or none")

    def fit(self, trained: RunTable) -> PhysicsBase:
        """Resolve the base on the training runs ``trained`` (their labels in ``drift_deg_h``) and their noise."""
        self.check_options()
        base, base_std = self._resolve(trained)
        label_std = trained.column("drift_std_deg_h") if trained.has_column("drift_std_deg_h") else None
        s = np.zeros(len(trained)) if label_std is None else np.asarray(label_std, float)
        # the target label - base carries the noise of both: its variance [(deg/h)^2] and 1-sigma
        self.noise_var_ = s**2 if base_std is None else s**2 + base_std**2
        self.noise_std_ = label_std if base_std is None else np.sqrt(self.noise_var_)
        weighted = self.label_weighting == "auto" and label_std is not None
        self.sample_weight_ = label_weights(self.noise_std_) if weighted else None
        self.label_std_rms_ = float(np.sqrt(np.mean(s**2)))
        self.training_base_ = base
        return self

    def _resolve(self, trained: RunTable) -> tuple[np.ndarray, np.ndarray | None]:
        """Set ``column_``, ``reason_``, ``coefficient_prior_`` and ``std_used_``; return the training runs' base
        [deg/h] (a fleet base with each run's leave-one-out prior) and its 1-sigma [deg/h] when it joins the label
        noise (else None)."""
        self.coefficient_prior_: tuple[float, float] | None = None
        self.std_used_ = False
        if self.target != "residual":
            self.column_: str | None = None
            self.reason_ = "none: the LSSVR learns the drift itself (target drift)"
            return np.zeros(len(trained)), None
        if self.column == "auto":
            column, why = resolve_physics_column(trained)
        else:
            column, why = self.column, "as given"
        per_run = None
        if column == FLEET_PHYSICS:  # a missing drift named per run before the count of thermal runs
            require_column(trained, "drift_smoother_deg_h", f"needed by the hybrid model's physics base {column}")
            prior, per_run = fleet_priors(trained)
            self.coefficient_prior_ = (float(prior[0]), float(prior[1]))
        base, std = physics_estimate(trained, column, prior=per_run, with_std=True)
        self.column_, self.reason_ = column, why
        self.std_used_ = bool(self.uncertainty == "auto" and std is not None and np.all(np.isfinite(std)))
        return base, (std if self.std_used_ else None)

    def predict(self, runs: RunTable, *, with_std: bool = False):
        """What the learner's output is added to for new runs [deg/h]: the physics estimate (residual target; a fleet
        base with the prior of every training run, ``coefficient_prior_``) or 0. ``with_std``: ``(base, its
        1-sigma or None)``."""
        self._check_fitted()
        if self.column_ is None:
            return (np.zeros(len(runs)), None) if with_std else np.zeros(len(runs))
        prior = self.coefficient_prior_ if self.column_ == FLEET_PHYSICS else None
        return physics_estimate(runs, self.column_, prior=prior, with_std=with_std)

    def predict_std(self, runs: RunTable) -> np.ndarray | None:
        """The base's 1-sigma of each run [deg/h] when it joins the interval (``std_used_``); else None. A run
        without it: ``InputError`` naming the table, the column and the runs."""
        self._check_fitted()
        if not self.std_used_:
            return None
        _, std = self.predict(runs, with_std=True)
        if not np.all(np.isfinite(std)):
            raise InputError(
                f"{runs.source}: column {BASE_STD_COLUMNS[str(self.column_)]} (the 1-sigma of the hybrid "
                f"model's physics base, in its interval) is missing for run(s) {missing_runs(runs, std)}"
            )
        return std
