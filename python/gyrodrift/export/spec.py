"""The export spec: what a fitted drift model computes, described once for every target language.

The generated code computes the identified axial drift [deg/h] on the navigation computer from the raw run
inputs the model reads (latitude at the 12th hour of free navigation [deg], site latitude [deg], temperature
extremes over the 12 h [deg C]), exactly as ``DriftModel.predict`` does. A hybrid model (``target="residual"``)
returns its physics estimate plus the learned correction: the 12 h inversion of the latitude error is computed
inside (`PHYSICS_EXPRESSIONS`, the operations of `gyrodrift.learn.baselines.physics_inversion`); the 12 h curve fit
and the 16 h smoother are computed by the navigation computer itself and passed in as one more input
(`PHYSICS_INPUTS`, deg/h); the fleet-prior smoother (`FLEET_PHYSICS`) takes the smoother's end drift and its k_z
estimate as inputs and re-weights them inside with the training fleet's k_z prior, baked in as two constants (the
operations of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`); such a model also exports its drift law
(`gyrodrift.procedure.identify`, "The drift law": the drift at the temperature measured in navigation, eps_ref + k1
(T - T_ref) with k1 the re-weighted k_z) and the training runs' temperature range to check T against
(``temp_range_c``). The learned part is the encoding's
features (`FEATURE_EXPRESSIONS`, the same operations as `gyrodrift.learn.encodings.encode`), the scaler, the kernel
(the conventions of `gyrodrift.learn.kernels`: rbf ``exp(-|x - z|^2 / sigma^2)``, linear ``x . z``, polynomial
``(x . z / sigma^2 + coef0)^degree``), the support vectors, alpha and the intercept.

`export_spec` reads these numbers from a fitted model into an `ExportSpec`, with the provenance (the training
digest, `gyrodrift.learn.training_record.training_digest`, the encoding, scaling, kernel and hyperparameters, the
target) and the range of each input and feature over the training runs, so that the navigation computer can refuse
to extrapolate. The languages write it out: `gyrodrift.export.c`, `gyrodrift.export.rust`
(`gyrodrift.export.languages.export_model`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from gyrodrift.earth import OMEGA_IE_RAD_S
from gyrodrift.errors import InputError
from gyrodrift.export.literals import literal
from gyrodrift.learn.encodings import encode
from gyrodrift.learn.physics_base import FLEET_PHYSICS, thermal_runs
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, HOUR

__all__ = [
    "FEATURE_EXPRESSIONS",
    "INPUTS",
    "PHYSICS_EXPRESSIONS",
    "PHYSICS_INPUTS",
    "RAW_INPUTS",
    "ExportSpec",
    "FeatureExpression",
    "export_spec",
    "physics_column",
]

RAW_INPUTS: dict[str, str] = {
    "lat_deg": "latitude at the 12th hour of free navigation [deg]",
    "lat0_deg": "true site latitude [deg]",
    "temp_min_c": "lowest system temperature over the 12 h [deg C]",
    "temp_max_c": "highest system temperature over the 12 h [deg C]",
}
"""The raw run inputs (`gyrodrift.runs.table.RunTable` columns) a generated function can read, with their units."""

PHYSICS_INPUTS: dict[str, str] = {
    "drift_curvefit_deg_h": "axial drift from the navigation computer's 12 h curve fit of the latitude error [deg/h]",
    "drift_smoother_deg_h": "axial drift from the navigation computer's 16 h smoother over the alignment log [deg/h]",
    "smoother_coeff_deg_h_per_c": "the smoother's thermal coefficient k_z [deg/h/degC] (NaN under its constant model)",
    "smoother_coeff_std_deg_h_per_c": "1-sigma of the smoother's k_z [deg/h/degC] (NaN under its constant model)",
    "smoother_end_coeff_cov": "cov(smoother end drift, k_z) [deg/h x deg/h/degC] (NaN under its constant model)",
    "smoother_coeff_prior_std_deg_h_per_c": "the smoother's own prior 1-sigma of k_z [deg/h/degC] "
    "(NaN under its constant model)",
}
"""Inputs of a hybrid's physics estimate that the navigation computer computes itself (run-table columns,
`gyrodrift.runs.columns.OPTIONAL_COLUMNS`), passed to the generated function after the raw inputs: the 12 h curve fit,
the 16 h smoother's end drift, and for the fleet-prior smoother (`FLEET_PHYSICS`) the smoother's k_z estimate
(`gyrodrift.runs.columns.SMOOTHER_THERMAL_COLUMNS`, the last inputs of the struct). The k_z inputs are NaN for a run
whose smoother used its constant model, whose base is then its end drift unchanged; the range check wants them all
NaN there (some but not all is neither of the smoother's models; the base passes such a run through as constant, as
`drift_with_coefficient_prior` does), else within their range over the training runs that had them."""

INPUTS: dict[str, str] = {**RAW_INPUTS, **PHYSICS_INPUTS}
"""Every input a generated function can read, in the order of its fields, with its unit."""


@dataclass(frozen=True)
class FeatureExpression:
    """How one feature of `gyrodrift.choices.ENCODINGS` is computed from the raw inputs in generated code.

    ``c`` and ``rust`` are expression templates: ``{lat_deg}`` and the other `INPUTS` stand for the input
    fields, ``{cos}`` (and any other name in ``functions``) for the math function, so that the same operations,
    in the same order, as `gyrodrift.learn.encodings.encode` are written in each language.
    """

    inputs: tuple[str, ...]
    c: str
    rust: str
    unit: str
    functions: tuple[str, ...] = ()


def _drift_equiv_template() -> str:
    """C/Rust template of the drift equivalent of the 12 h latitude error (`physics_inversion`)."""
    w = OMEGA_IE_RAD_S
    one_minus_cos = 1.0 - math.cos(w * 12.0 * HOUR)
    return (
        f"{literal(w)} * (({{lat_deg}} - {{lat0_deg}}) * 3600.0 * {literal(ARCSEC)}) / "
        f"({{cos}}({{lat0_deg}} * {literal(DEG)}) * {literal(one_minus_cos)}) / {literal(DEG_PER_H)}"
    )


_DRIFT_EQUIV = _drift_equiv_template()

FEATURE_EXPRESSIONS: dict[str, FeatureExpression] = {
    "lat_err_arcsec": FeatureExpression(
        ("lat_deg", "lat0_deg"), "({lat_deg} - {lat0_deg}) * 3600.0", "({lat_deg} - {lat0_deg}) * 3600.0", "arcsec"
    ),
    "temp_min_c": FeatureExpression(("temp_min_c",), "{temp_min_c}", "{temp_min_c}", "deg C"),
    "temp_max_c": FeatureExpression(("temp_max_c",), "{temp_max_c}", "{temp_max_c}", "deg C"),
    "temp_mean_c": FeatureExpression(
        ("temp_min_c", "temp_max_c"),
        "0.5 * ({temp_min_c} + {temp_max_c})",
        "0.5 * ({temp_min_c} + {temp_max_c})",
        "deg C",
    ),
    "temp_span_c": FeatureExpression(
        ("temp_min_c", "temp_max_c"), "{temp_max_c} - {temp_min_c}", "{temp_max_c} - {temp_min_c}", "deg C"
    ),
    "lat0_deg": FeatureExpression(("lat0_deg",), "{lat0_deg}", "{lat0_deg}", "deg"),
    # gyrodrift.learn.baselines.physics_inversion at 12 h, operation for operation (its constants as 17-digit literals)
    "drift_equiv_deg_h": FeatureExpression(("lat_deg", "lat0_deg"), _DRIFT_EQUIV, _DRIFT_EQUIV, "deg/h", ("cos",)),
}
"""Every feature name of every encoding, as generated C and Rust (tests/export/test_export.py checks that none is
missing: a new encoding must add its features here)."""

_FLEET_ARGS = ", ".join(f"{{{name}}}" for name in ("drift_smoother_deg_h", *SMOOTHER_THERMAL_COLUMNS))

PHYSICS_EXPRESSIONS: dict[str, FeatureExpression] = {
    # learn.physics_base.physics_estimate: physics_inversion(runs, t_h=12.0), the same operations as the feature
    "drift_inversion_deg_h": FeatureExpression(("lat_deg", "lat0_deg"), _DRIFT_EQUIV, _DRIFT_EQUIV, "deg/h", ("cos",)),
    **{
        name: FeatureExpression((name,), f"{{{name}}}", f"{{{name}}}", "deg/h")
        for name in ("drift_curvefit_deg_h", "drift_smoother_deg_h")
    },
    # drift_with_coefficient_prior(drift, ., coeff, coeff_std, cov, prior_std, *coefficient_prior_)[0]: a function
    # of the generated code (templates/fleet_base.c.in, fleet_base.rs.in) reading the fleet prior's constants
    FLEET_PHYSICS: FeatureExpression(
        ("drift_smoother_deg_h", *SMOOTHER_THERMAL_COLUMNS),
        f"gyrodrift_model_fleet_base_deg_h({_FLEET_ARGS})",
        f"fleet_base_deg_h({_FLEET_ARGS})",
        "deg/h",
    ),
}
"""The physics estimate of a hybrid model (``physics_column_``, `gyrodrift.choices.PHYSICS_COLUMNS`) in generated
code: the 12 h inversion computed from the latitudes, an input (`PHYSICS_INPUTS`) read as it is, or the smoother's
end drift re-weighted by the fleet's k_z prior (`FLEET_PHYSICS`)."""


@dataclass(frozen=True)
class ExportSpec:
    """Everything the generated code needs, as plain numbers (read from a fitted `DriftModel`).

    ``input_ranges`` and ``feature_ranges`` hold (min, max) of each input (``inputs``, `INPUTS`: the raw inputs the
    features or the physics estimate read, then a physics column passed in) and of each feature (``feature_names``)
    over the training runs, in their units (the k_z inputs, ``SMOOTHER_THERMAL_COLUMNS``, over the runs with a thermal
    estimate); ``physics`` is the hybrid's physics column (None when the model learns the drift itself,
    ``target="drift"``); ``coefficient_prior`` the fleet's k_z prior (mean, 1-sigma) [deg/h/degC] of the
    fleet-prior base (`FLEET_PHYSICS`), else None; ``temp_range_c`` the training runs' system temperatures
    (lowest ``temp_min_c``, highest ``temp_max_c``) [deg C] that the drift law of the fleet-prior base may be
    evaluated at (None without the law); ``mean``/
    ``scale`` (standard: ``(x - mean) / scale``) or ``scale``/``offset`` (minmax: ``x * scale + offset``)
    the scaler; ``support_vectors`` are in scaled units.
    """

    encoding: str
    scaling: str
    target: str
    physics: str | None
    coefficient_prior: tuple[float, float] | None
    temp_range_c: tuple[float, float] | None
    feature_names: tuple[str, ...]
    inputs: tuple[str, ...]
    functions: tuple[str, ...]
    kernel: str
    gamma: float
    sigma: float
    degree: int
    coef0: float
    support_vectors: np.ndarray
    alpha: np.ndarray
    intercept: float
    mean: np.ndarray | None
    scale: np.ndarray | None
    offset: np.ndarray | None
    input_ranges: tuple[tuple[float, float], ...]
    feature_ranges: tuple[tuple[float, float], ...]
    training: dict
    model_sha256: str | None


def physics_column(model) -> str | None:
    """The physics column of a hybrid ``model`` (the resolved ``physics_column_`` of a model fitted with
    ``physics_column="auto"``, else ``physics_column``), or None when it learns the drift itself."""
    if str(getattr(model, "target", "drift")) != "residual":
        return None
    resolved = getattr(model, "physics_column_", None)
    physics = str(resolved if resolved is not None else model.physics_column)
    if physics == "auto":
        raise InputError("the hybrid model's physics column was never resolved (physics_column_); refit it")
    return physics


def _ranges(values: np.ndarray) -> tuple[tuple[float, float], ...]:
    """(min, max) of each column of ``values``."""
    values = np.asarray(values, float).reshape(len(values), -1)
    return tuple((float(lo), float(hi)) for lo, hi in zip(values.min(axis=0), values.max(axis=0), strict=True))


def export_spec(model, *, model_sha256: str | None = None) -> ExportSpec:
    """The numbers of a fitted drift model that the generated code needs: a `gyrodrift.learn.drift_model.DriftModel`
    or the `gyrodrift.learn.predictor.DriftPredictor` of a model file (`gyrodrift.learn.model_io.load_predictor`).

    ``model_sha256`` (the SHA-256 of the model file's bytes, if known) is recorded in the provenance.
    Raises `InputError` if a feature of the model's encoding has no entry in `FEATURE_EXPRESSIONS`, or a hybrid's
    physics column none in `PHYSICS_EXPRESSIONS`.

    Prediction needs only what is read here: the features, the scaler, the support vectors, alpha, the intercept
    and the physics estimate. How the fit got there (label weights ``C_i = gamma w_i``, left-out runs, the tuning)
    is folded into alpha and the intercept.
    """
    target = str(getattr(model, "target", "drift"))
    physics = physics_column(model)
    if target not in ("drift", "residual"):
        raise InputError(f"unknown model target {target!r}; expected drift or residual")
    if physics is not None and physics not in PHYSICS_EXPRESSIONS:
        raise InputError(
            f"physics column {physics!r} of the hybrid model has no C/Rust expression in "
            "gyrodrift.export.spec.PHYSICS_EXPRESSIONS; it cannot be exported"
        )
    prior = None
    if physics == FLEET_PHYSICS:
        prior = getattr(model, "coefficient_prior_", None)
        if prior is None or len(prior) != 2:
            raise InputError(f"the hybrid model on {FLEET_PHYSICS} has no fleet k_z prior (coefficient_prior_)")
        prior = (float(prior[0]), float(prior[1]))
        if not (math.isfinite(prior[0]) and math.isfinite(prior[1]) and prior[1] > 0.0):
            raise InputError(f"the model's fleet k_z prior needs a finite mean and a positive 1-sigma, got {prior}")
    names = tuple(model.feature_names)
    missing = [name for name in names if name not in FEATURE_EXPRESSIONS]
    if missing:
        raise InputError(
            f"encoding {model.encoding!r}: feature {', '.join(missing)} has no C/Rust expression in "
            "gyrodrift.export.spec.FEATURE_EXPRESSIONS; it cannot be exported"
        )
    exprs = [FEATURE_EXPRESSIONS[f] for f in names]
    if physics is not None:
        exprs.append(PHYSICS_EXPRESSIONS[physics])
    inputs = tuple(name for name in INPUTS if any(name in e.inputs for e in exprs))
    functions = tuple(sorted({fn for e in exprs for fn in e.functions}))
    training = dict(model.training)
    if not re.fullmatch(r"[0-9a-f]{64}", str(training.get("sha256", ""))):
        raise InputError(f"the model's training digest is not a SHA-256 hex digest: {training.get('sha256')!r}")
    est = model.lssvr
    kernel = "poly" if est.kernel == "polynomial" else str(est.kernel)
    if kernel == "rbf":
        functions = tuple(sorted({*functions, "exp"}))
    sv = np.asarray(est.X_fit_, float)
    alpha = np.asarray(est.alpha_, float)
    if alpha.ndim != 1:
        raise InputError(f"a model with {alpha.shape[1]} targets cannot be exported (one drift per run expected)")
    scaler = model.scaler_
    runs = getattr(model, "training_", {}).get("runs")
    if runs is None:
        raise InputError("the model does not carry its training runs (needed for the input ranges); refit it")
    mean = scale = offset = None
    if model.scaling == "standard":
        mean, scale = np.asarray(scaler.mean, float), np.asarray(scaler.scale, float)
    elif model.scaling == "minmax":
        scale, offset = np.asarray(scaler.scale, float), np.asarray(scaler.offset, float)
    input_ranges = []
    for name in inputs:
        values = runs.column(name) if name in PHYSICS_INPUTS else getattr(runs, name)
        if name in SMOOTHER_THERMAL_COLUMNS:  # the runs with a thermal estimate (the others do not read them)
            values = values[thermal_runs(runs)]
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise InputError(f"input {name} of the model is missing for some training runs; it cannot be exported")
        input_ranges.append((float(values.min()), float(values.max())))
    temp_range = None
    if prior is not None:  # the drift law's temperatures: those of the training runs
        temp_range = (float(np.min(runs.temp_min_c)), float(np.max(runs.temp_max_c)))
        if not (math.isfinite(temp_range[0]) and math.isfinite(temp_range[1])):
            raise InputError(
                "the training runs' temperatures (temp_min_c, temp_max_c) are missing; it cannot be exported"
            )
    return ExportSpec(
        encoding=model.encoding,
        scaling=model.scaling,
        target=target,
        physics=physics,
        coefficient_prior=prior,
        temp_range_c=temp_range,
        feature_names=names,
        inputs=inputs,
        functions=functions,
        kernel=kernel,
        gamma=float(est.gamma),
        sigma=float(est.sigma),
        degree=int(est.degree),
        coef0=float(est.coef0),
        support_vectors=sv,
        alpha=alpha,
        intercept=float(est.intercept_),
        mean=mean,
        scale=scale,
        offset=offset,
        input_ranges=tuple(input_ranges),
        feature_ranges=_ranges(encode(runs, model.encoding)),
        training=training,
        model_sha256=model_sha256,
    )
