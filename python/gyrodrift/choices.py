"""The names of the options the API and the CLI accept, in one light module (no heavy imports).

The CLI builds its choices from here at start-up without importing scikit-learn; the modules that implement
the options (`gyrodrift.learn.physics_base`, `gyrodrift.learn.tuning`) import the same tuples.
"""

import sys

SIGMA_RANGE = (sys.float_info.min**0.5, sys.float_info.max**0.5)
"""Kernel widths whose square is a normal, finite float64: about (1.49e-154, 1.34e154) [scaled input units].

Below, the RBF kernel's ``d / sigma^2`` is ``0/0`` on its diagonal; above, every distance is lost."""

MAX_DRIFT_DEG_H = 100.0
"""Largest axial drift [deg/h] a drift to compensate may be (``--drift-deg-h``): an RLG's is of order 0.001-0.01
deg/h, a tactical-grade gyro's 1-10 deg/h; 100 deg/h is beyond any gyro an INS drift compensation serves (the
core's own limit, 0.1 rad/s = 20 626 deg/h, is the sensor's range, not a drift)."""

SCALINGS = ("standard", "minmax", "none")
"""Input scalings: zero mean / unit variance, [0, 1] per feature, or raw inputs."""

OBJECTIVES = ("train_mae", "loo_mae", "kfold_mae")
"""Tuning objectives: training MAE (the paper's eq. 16), closed-form leave-one-out MAE, contiguous k-fold MAE."""

METHODS = ("cpso", "pso", "grid")
"""Tuning methods: chaos PSO, plain PSO, log grid."""

ENCODINGS: dict[str, tuple[str, ...]] = {
    "physics": ("drift_equiv_deg_h", "temp_min_c", "temp_max_c"),
    "physics_lat": ("drift_equiv_deg_h", "temp_min_c", "temp_max_c", "lat0_deg"),
    "temperature": ("temp_min_c", "temp_max_c"),
    "temp_range": ("lat_err_arcsec", "temp_min_c", "temp_max_c"),
    "temp_mean": ("lat_err_arcsec", "temp_mean_c"),
    "temp_span": ("lat_err_arcsec", "temp_span_c"),
    "lat_only": ("lat_err_arcsec",),
}
"""Run encodings: name -> feature names (units in the names); implemented in `gyrodrift.learn.encodings`."""

PAPER_ENCODINGS = ("temp_range", "temp_mean", "temp_span", "lat_only")
"""The readings of the paper's inputs (raw 12 h latitude error in arcsec): kept for `reproduce`."""

DEFAULT_ENCODING = "physics"
"""The encoding of ``gyrodrift fit --target drift``: the 12 h latitude error as its drift equivalent at the run's
own latitude (deg/h, latitude-free), with the temperature range."""

DEFAULT_HYBRID_ENCODING = "temperature"
"""The encoding of a hybrid's correction (``gyrodrift fit``'s default ``--target residual``): the temperature
range alone. The physics base carries the navigation's information; an input derived from the same navigation
(the 12 h latitude error) shares the label's noise (``truth`` navigates the same random walk), so a correction
fed it learns that noise: on the simulated study fleet (seed 11) the residual label - base correlated 0.56 with
the inversion's disagreement with the base on the training runs, and -0.09 with it on held-out runs' effective
drifts (docs/identification.md)."""


def default_encoding(target: str) -> str:
    """``DEFAULT_HYBRID_ENCODING`` for ``target="residual"``, else ``DEFAULT_ENCODING``."""
    return DEFAULT_HYBRID_ENCODING if target == "residual" else DEFAULT_ENCODING


TARGETS = ("drift", "residual")
"""What the learner is fitted on: the drift itself, or the residual drift minus a physics estimate (hybrid)."""

PHYSICS_COLUMNS = (
    "drift_inversion_deg_h",
    "drift_curvefit_deg_h",
    "drift_smoother_deg_h",
    "drift_smoother_fleet_deg_h",
)
"""Physics estimates a hybrid model can start from: the 12 h inversion (computed from ``lat_deg`` and
``lat0_deg``), a run-table column (the 12 h curve fit; the 16 h smoother's end drift: the run table's
``PHYSICS_BASE_COLUMNS``, `gyrodrift.runs.columns`, which tests/runs/test_columns.py holds equal to these two), or
the smoother's end drift re-weighted by the training fleet's pooled prior of its thermal coefficient k_z (computed
by the model from the smoother's columns, `gyrodrift.learn.fleet_prior`)."""

PHYSICS_CHOICES = ("auto", *PHYSICS_COLUMNS)
"""What ``physics_column`` (``fit --physics-column``) accepts: a physics estimate, or ``auto`` (the default):
resolved when the model is fitted, to the fleet-prior smoother when every training run has the smoother's
columns and at least `MIN_THERMAL_RUNS` have its thermal k_z, else the smoother's drift when every run has
it, else the 12 h inversion (`gyrodrift.learn.physics_base.resolve_physics_column`)."""

MIN_THERMAL_RUNS = 3
"""Training runs with the smoother's thermal k_z that the fleet-prior base needs: each training run's own base
pools the k_z of the others (leave one out), and a pooled prior needs at least 2."""

BASE_UNCERTAINTIES = ("auto", "none")
"""Whether a hybrid's physics base's 1-sigma joins the label 1-sigma (label weights, the interval's Gaussian
process and its calibration, the new run's interval): ``auto`` where the base has one, ``none`` never (model
files written before it)."""
