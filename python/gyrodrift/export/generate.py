"""Code generation: a fitted drift model as a C99 header/source pair or a ``no_std`` Rust module.

The generated code computes the identified axial drift [deg/h] on the navigation computer from the raw run
inputs the model reads (latitude at the 12th hour of free navigation [deg], site latitude [deg], temperature
extremes over the 12 h [deg C]), exactly as ``DriftModel.predict`` does. A hybrid model (``target="residual"``)
returns its physics estimate plus the learned correction: the 12 h inversion of the latitude error is computed
inside (`PHYSICS_EXPRESSIONS`, the operations of `gyrodrift.learn.baselines.physics_inversion`); the 12 h curve fit and
the 16 h smoother are computed by the navigation computer itself and passed in as one more input
(`PHYSICS_INPUTS`, deg/h); the fleet-prior smoother (`FLEET_PHYSICS`) takes the smoother's end drift and its k_z
estimate as inputs and re-weights them inside with the training fleet's k_z prior, baked in as two constants (the
operations of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`). The learned part is the encoding's features
(`FEATURE_EXPRESSIONS`, the same operations as `gyrodrift.learn.encodings.encode`), the scaler, the kernel (the
conventions of `gyrodrift.learn.kernels`: rbf ``exp(-|x - z|^2 / sigma^2)``, linear ``x . z``, polynomial
``(x . z / sigma^2 + coef0)^degree``), the support vectors, alpha and the intercept. Every float is printed with
17 significant digits, which round-trips a float64, so the constants are the model's bits.

The generated code does the IEEE operations of Python's prediction in the same order (`gyrodrift.learn.lssvr`,
"prediction arithmetic": distances in feature order, the C library's ``exp``, ``b + sum_i alpha_i K_i`` (+ the
physics estimate) as a compensated sum in support-vector order), so on the same machine it returns the same
bits; on a navigation computer only a libm rounding ``exp`` or ``cos`` the other way can differ, by about eps
times the size of the summed terms. docs/export.md gives the measurements and what the compiler must not do.

Provenance travels with the code, as comments and as constants and functions: the training digest (SHA-256 of
the training runs, `gyrodrift.learn.model.training_digest`), the exporting package's version, the encoding, scaling,
kernel and hyperparameters, the target (a hybrid's physics column), and the range of each input (a hybrid's
physics input included) and of each feature over the training runs, with
functions returning the ranges and one saying whether an input lies within them, so that the navigation
computer can refuse to extrapolate.

This module only builds texts (`export_model` returns ``{file name: text}``); the command writes them
(`gyrodrift.cli.export`).
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

import numpy as np

from gyrodrift import __version__
from gyrodrift.errors import InputError, OptionError
from gyrodrift.learn.encodings import encode
from gyrodrift.learn.model import FLEET_PHYSICS, THERMAL_COLUMNS, thermal_runs

__all__ = [
    "COEFFICIENT_INPUTS",
    "FEATURE_EXPRESSIONS",
    "FLEET_PHYSICS",
    "INPUTS",
    "LANGUAGES",
    "PHYSICS_EXPRESSIONS",
    "PHYSICS_INPUTS",
    "RAW_INPUTS",
    "ExportSpec",
    "FeatureExpression",
    "export_model",
    "export_spec",
    "output_names",
    "physics_column",
]

LANGUAGES: dict[str, tuple[str, ...]] = {
    "c": ("gyrodrift_model.h", "gyrodrift_model.c"),
    "rust": ("gyrodrift_model.rs",),
}
"""Target languages and the files each export writes."""

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
`gyrodrift.runs.table.OPTIONAL_COLUMNS`), passed to the generated function after the raw inputs: the 12 h curve fit,
the 16 h smoother's end drift, and for the fleet-prior smoother (`FLEET_PHYSICS`) the smoother's k_z estimate
(`COEFFICIENT_INPUTS`)."""

COEFFICIENT_INPUTS: tuple[str, ...] = THERMAL_COLUMNS
"""The smoother's k_z estimate (`gyrodrift.learn.model.THERMAL_COLUMNS`), read by the fleet-prior smoother base
(`FLEET_PHYSICS`); the last inputs of the struct. NaN for a run whose smoother used its constant model, whose base
is then its end drift unchanged. The range check wants them all NaN there (some but not all is neither of the
smoother's models; the base passes such a run through as constant, as `drift_with_coefficient_prior` does), else
within their range."""

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
    from gyrodrift.earth import OMEGA_IE_RAD_S
    from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, HOUR

    w = OMEGA_IE_RAD_S
    one_minus_cos = 1.0 - math.cos(w * 12.0 * HOUR)
    lit = lambda x: format(float(x), ".17g")  # noqa: E731 - reads back as the same float64
    return (
        f"{lit(w)} * (({{lat_deg}} - {{lat0_deg}}) * 3600.0 * {lit(ARCSEC)}) / "
        f"({{cos}}({{lat0_deg}} * {lit(DEG)}) * {lit(one_minus_cos)}) / {lit(DEG_PER_H)}"
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

_FLEET_ARGS = ", ".join(f"{{{name}}}" for name in ("drift_smoother_deg_h", *COEFFICIENT_INPUTS))

PHYSICS_EXPRESSIONS: dict[str, FeatureExpression] = {
    # gyrodrift.learn.model.physics_estimate: physics_inversion(runs, t_h=12.0), the same operations as the feature
    "drift_inversion_deg_h": FeatureExpression(("lat_deg", "lat0_deg"), _DRIFT_EQUIV, _DRIFT_EQUIV, "deg/h", ("cos",)),
    **{
        name: FeatureExpression((name,), f"{{{name}}}", f"{{{name}}}", "deg/h")
        for name in ("drift_curvefit_deg_h", "drift_smoother_deg_h")
    },
    # drift_with_coefficient_prior(drift, ., coeff, coeff_std, cov, prior_std, *coefficient_prior_)[0]: a function
    # of the generated code (`_c_fleet_functions`, `_RUST_FLEET_FUNCTIONS`) reading the fleet prior's constants
    FLEET_PHYSICS: FeatureExpression(
        ("drift_smoother_deg_h", *COEFFICIENT_INPUTS),
        f"gyrodrift_model_fleet_base_deg_h({_FLEET_ARGS})",
        f"fleet_base_deg_h({_FLEET_ARGS})",
        "deg/h",
    ),
}
"""The physics estimate of a hybrid model (``physics_column_``, `gyrodrift.choices.PHYSICS_COLUMNS`) in generated
code: the 12 h inversion computed from the latitudes, an input (`PHYSICS_INPUTS`) read as it is, or the smoother's
end drift re-weighted by the fleet's k_z prior (`FLEET_PHYSICS`)."""

_PREFIX = "gyrodrift_model"


@dataclass(frozen=True)
class ExportSpec:
    """Everything the generated code needs, as plain numbers (read from a fitted `DriftModel`).

    ``input_ranges`` and ``feature_ranges`` hold (min, max) of each input (``inputs``, `INPUTS`: the raw inputs the
    features or the physics estimate read, then a physics column passed in) and of each feature (``feature_names``)
    over the training runs, in their units (the k_z inputs, `COEFFICIENT_INPUTS`, over the runs with a thermal
    estimate); ``physics`` is the hybrid's physics column (None when the model learns the drift itself,
    ``target="drift"``); ``coefficient_prior`` the fleet's k_z prior (mean, 1-sigma) [deg/h/degC] of the
    fleet-prior base (`FLEET_PHYSICS`), else None; ``mean``/
    ``scale`` (standard: ``(x - mean) / scale``) or ``scale``/``offset`` (minmax: ``x * scale + offset``)
    the scaler; ``support_vectors`` are in scaled units.
    """

    encoding: str
    scaling: str
    target: str
    physics: str | None
    coefficient_prior: tuple[float, float] | None
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


def output_names(lang: str) -> tuple[str, ...]:
    """The files an export to ``lang`` writes; `OptionError` (naming ``--lang``) for an unknown language."""
    try:
        return LANGUAGES[lang]
    except (KeyError, TypeError):
        raise OptionError(f"--lang: unknown language {lang!r}; expected one of {', '.join(LANGUAGES)}") from None


def _ranges(values: np.ndarray) -> tuple[tuple[float, float], ...]:
    """(min, max) of each column of ``values``."""
    values = np.asarray(values, float).reshape(len(values), -1)
    return tuple((float(lo), float(hi)) for lo, hi in zip(values.min(axis=0), values.max(axis=0), strict=True))


def export_spec(model, *, model_sha256: str | None = None) -> ExportSpec:
    """The numbers of a fitted `gyrodrift.learn.model.DriftModel` that the generated code needs.

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
            "gyrodrift.export.generate.PHYSICS_EXPRESSIONS; it cannot be exported"
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
            "gyrodrift.export.generate.FEATURE_EXPRESSIONS; it cannot be exported"
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
    scaler = model.named_steps["scale"]
    runs = getattr(model, "training_", {}).get("runs")
    if runs is None:
        raise InputError("the model does not carry its training runs (needed for the input ranges); refit it")
    mean = scale = offset = None
    if model.scaling == "standard":
        mean, scale = np.asarray(scaler.mean_, float), np.asarray(scaler.scale_, float)
    elif model.scaling == "minmax":
        scale, offset = np.asarray(scaler.scale_, float), np.asarray(scaler.min_, float)
    input_ranges = []
    for name in inputs:
        values = runs.column(name) if name in PHYSICS_INPUTS else getattr(runs, name)
        if name in COEFFICIENT_INPUTS:  # the runs with a thermal estimate (the others do not read them)
            values = values[thermal_runs(runs)]
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise InputError(f"input {name} of the model is missing for some training runs; it cannot be exported")
        input_ranges.append((float(values.min()), float(values.max())))
    return ExportSpec(
        encoding=model.encoding,
        scaling=model.scaling,
        target=target,
        physics=physics,
        coefficient_prior=prior,
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


def export_model(model, lang: str, *, model_sha256: str | None = None) -> dict[str, str]:
    """The generated files of ``model`` for ``lang`` (``"c"`` or ``"rust"``): ``{file name: text}``.

    The texts depend only on the model, ``model_sha256`` and the package version (no time stamp), so exporting
    the same model twice gives the same bytes.
    """
    output_names(lang)
    spec = export_spec(model, model_sha256=model_sha256)
    return _c_files(spec) if lang == "c" else _rust_files(spec)


# --- literals and provenance ---------------------------------------------------------------------------


def _lit(x: float) -> str:
    """A float64 literal valid in C and Rust that reads back as exactly ``x`` (17 significant digits)."""
    x = float(x)
    if not math.isfinite(x):
        raise InputError(f"the model holds a non-finite number ({x}); it cannot be exported")
    text = format(x, ".17g")
    if not any(ch in text for ch in ".e"):
        text += ".0"
    assert float(text) == x  # 17 significant digits always round-trip a float64
    return text


def _comment_text(value) -> str:
    """``value`` as text safe inside a C block comment and a Rust line comment: printable ASCII on one line
    (JSON escapes for the rest), no ``*/`` and no C trigraph (``??/`` would splice lines)."""
    text = json.dumps(str(value), ensure_ascii=True)[1:-1].replace("*/", "*\\/")
    return re.sub(r"\?(?=\?)", r"?\\", text)


def _provenance_lines(spec: ExportSpec) -> list[str]:
    """Human-readable provenance, one line each (the caller adds the comment markers)."""
    training = spec.training
    lines = [
        f"Exported by gyrodrift {__version__} (`gyrodrift export`). Do not edit: export the model file again.",
        f"Training digest (SHA-256 of the training runs): {training.get('sha256', 'unknown')}",
        f"Training runs: {training.get('n_runs', 'unknown')} from {_comment_text(training.get('source', '?'))}",
    ]
    if spec.model_sha256:
        lines.append(f"Model file SHA-256: {spec.model_sha256}")
    lines += [
        f"Encoding: {spec.encoding} (features: {', '.join(spec.feature_names)})",
        f"Scaling: {spec.scaling}",
        f"Kernel: {_kernel_formula(spec)}",
        f"Hyperparameters: gamma = {_lit(spec.gamma)}, sigma = {_lit(spec.sigma)} (scaled input units)"
        + (f", degree = {spec.degree}, coef0 = {_lit(spec.coef0)}" if spec.kernel == "poly" else ""),
        f"Support vectors: {spec.support_vectors.shape[0]}",
        "Label weighting at fit time: "
        + ("weighted by drift_std_deg_h" if training.get("weighted") else "none")
        + " (folded into alpha and the intercept; nothing at prediction time)",
    ]
    if spec.physics is None:
        lines.append("Target: drift (the learned function is the drift)")
    else:
        if spec.physics == "drift_inversion_deg_h":
            how = "computed here from lat_deg and lat0_deg (gyrodrift.learn.baselines.physics_inversion at 12 h)"
        elif spec.physics == FLEET_PHYSICS:
            how = (
                "computed here from the smoother's end drift and k_z estimate with the training fleet's k_z prior "
                "(gyrodrift.learn.fleet_prior.drift_with_coefficient_prior); the end drift unchanged on a run whose "
                "smoother used its constant model (NaN k_z inputs)"
            )
        else:
            how = "an input, computed by the navigation computer"
        lines.append(
            "Target: residual (hybrid): drift = physics estimate + learned correction; "
            f"physics estimate: {spec.physics} [deg/h], {how}"
        )
    if spec.coefficient_prior is not None:
        mean, std = spec.coefficient_prior
        lines.append(
            f"Fleet k_z prior: mean = {_lit(mean)}, 1-sigma = {_lit(std)} [deg/h/degC] (pooled over the training "
            "runs' k_z: gyrodrift.learn.fleet_prior.pooled_coefficient_prior)"
        )
    lines.append("Inputs read, with their range over the training runs (the range check refuses inputs outside it):")
    for name, (lo, hi) in zip(spec.inputs, spec.input_ranges, strict=True):
        note = " (over the runs with k_z; must be NaN where the run has none)" if name in COEFFICIENT_INPUTS else ""
        lines.append(f"  {name}: [{_lit(lo)}, {_lit(hi)}]{note}, {INPUTS[name]}")
    lines.append("Features, with their range over the training runs (checked too):")
    for name, (lo, hi) in zip(spec.feature_names, spec.feature_ranges, strict=True):
        lines.append(f"  {name}: [{_lit(lo)}, {_lit(hi)}] {FEATURE_EXPRESSIONS[name].unit}")
    total = "" if spec.physics is None else " = physics estimate + learned correction"
    lines.append(f"Output: identified axial gyro drift [deg/h]{total} (subtract it from the z-gyro output).")
    return lines


def _kernel_formula(spec: ExportSpec) -> str:
    if spec.kernel == "rbf":
        return "rbf, K(x, z) = exp(-|x - z|^2 / sigma^2)"
    if spec.kernel == "linear":
        return "linear, K(x, z) = x . z"
    return "poly, K(x, z) = (x . z / sigma^2 + coef0)^degree"


def _expression(expr: FeatureExpression, lang: str, field: str, function: str) -> str:
    """``expr`` in ``lang``, reading inputs as ``field.format(name)`` and functions as ``function.format(name)``."""
    template = expr.c if lang == "c" else expr.rust
    subst = {inp: field.format(inp) for inp in INPUTS}
    subst.update({fn: function.format(fn) for fn in expr.functions})
    return template.format(**subst)


def _feature_exprs(spec: ExportSpec, lang: str, field: str, function: str) -> list[str]:
    """The expression of each feature in ``lang`` (see `_expression`)."""
    return [_expression(FEATURE_EXPRESSIONS[name], lang, field, function) for name in spec.feature_names]


# --- C ---------------------------------------------------------------------------------------------------


def _c_array(values) -> str:
    return "{" + ", ".join(_lit(v) for v in values) + "}"


def _c_range_table(name: str, count: str, names, ranges) -> str:
    rows = ",\n".join(f'    {{"{n}", {_lit(lo)}, {_lit(hi)}}}' for n, (lo, hi) in zip(names, ranges, strict=True))
    return f"static const {_PREFIX}_range {name}[{count}] = {{\n{rows}\n}};"


def _c_files(spec: ExportSpec) -> dict[str, str]:
    header_name, source_name = LANGUAGES["c"]
    P, U = _PREFIX, _PREFIX.upper()
    guard = U + "_H"
    nf, nsv, ni = len(spec.feature_names), spec.support_vectors.shape[0], len(spec.inputs)
    prov = "\n".join(" * " + line if line else " *" for line in _provenance_lines(spec))
    fields = "\n".join(f"    double {name}; /* {INPUTS[name]} */" for name in spec.inputs)
    learned = f"{P}_drift_deg_h" if spec.physics is None else f"{P}_correction_deg_h"
    if spec.physics is None:
        physics_macro = ""
        drift_decl = f"""/* The identified axial gyro drift [deg/h]; check {P}_in_range first: the model does not
 * extrapolate. */
double {P}_drift_deg_h(const {P}_inputs *inputs);"""
    else:
        physics_macro = f'#define {U}_PHYSICS "{spec.physics}"\n'
        if spec.coefficient_prior is not None:
            mean, std = spec.coefficient_prior
            physics_macro += (
                f"/* The training fleet's prior on k_z [deg/h/degC]: mean and 1-sigma. */\n"
                f"#define {U}_COEFF_PRIOR_MEAN_DEG_H_PER_C {_lit(mean)}\n"
                f"#define {U}_COEFF_PRIOR_STD_DEG_H_PER_C {_lit(std)}\n"
            )
        drift_decl = f"""/* The physics estimate [deg/h]: {_physics_doc(spec)}. */
double {P}_physics_deg_h(const {P}_inputs *inputs);

/* The learned correction [deg/h] added to the physics estimate. */
double {P}_correction_deg_h(const {P}_inputs *inputs);

/* The identified axial gyro drift [deg/h]: physics estimate + learned correction.
 * Check {P}_in_range first: the model does not extrapolate. */
double {P}_drift_deg_h(const {P}_inputs *inputs);"""
    header = f"""/*
 * {header_name}: the identified axial gyro drift model, C99, no allocation, no I/O, const data only.
 *
{prov}
 */
#ifndef {guard}
#define {guard}

#define {U}_GYRODRIFT_VERSION "{__version__}"
#define {U}_TRAINING_SHA256 "{spec.training["sha256"]}"
#define {U}_ENCODING "{spec.encoding}"
#define {U}_SCALING "{spec.scaling}"
#define {U}_KERNEL "{spec.kernel}"
#define {U}_TARGET "{spec.target}"
{physics_macro}#define {U}_N_INPUTS {ni}
#define {U}_N_FEATURES {nf}
#define {U}_N_SUPPORT_VECTORS {nsv}

/* The inputs the model reads. */
typedef struct {P}_inputs {{
{fields}
}} {P}_inputs;

/* The range of one input or feature over the training runs (name, then min and max in its unit). */
typedef struct {P}_range {{
    const char *name;
    double min;
    double max;
}} {P}_range;

/* The {ni} training ranges of the inputs, in the order of the fields of {P}_inputs. */
const {P}_range *{P}_input_ranges(void);

/* The {nf} training ranges of the features, in the order of {P}_features. */
const {P}_range *{P}_feature_ranges(void);

/* The model's features of `inputs` (the same operations as gyrodrift.learn.encodings.encode). */
void {P}_features(const {P}_inputs *inputs, double features[{U}_N_FEATURES]);

/* 1 when every input and every feature lies within its training range (NaN never does), else 0. */
int {P}_in_range(const {P}_inputs *inputs);

{drift_decl}

#endif /* {guard} */
"""
    feats = _feature_exprs(spec, "c", "inputs->{}", "{}")
    feature_lines = "\n".join(f"    features[{k}] = {e};" for k, e in enumerate(feats))
    input_values = ", ".join(f"inputs->{name}" for name in spec.inputs)
    data = [
        _c_range_table(f"{P}_input_range_table", f"{U}_N_INPUTS", spec.inputs, spec.input_ranges),
        _c_range_table(f"{P}_feature_range_table", f"{U}_N_FEATURES", spec.feature_names, spec.feature_ranges),
    ]
    scale_loop = ""
    if spec.scaling == "standard":
        data.append(f"static const double {P}_mean[{U}_N_FEATURES] = {_c_array(spec.mean)};")
        data.append(f"static const double {P}_scale[{U}_N_FEATURES] = {_c_array(spec.scale)};")
        scale_loop = f"""    for (k = 0; k < {U}_N_FEATURES; ++k) {{
        x[k] = (x[k] - {P}_mean[k]) / {P}_scale[k];
    }}
"""
    elif spec.scaling == "minmax":
        data.append(f"static const double {P}_scale[{U}_N_FEATURES] = {_c_array(spec.scale)};")
        data.append(f"static const double {P}_offset[{U}_N_FEATURES] = {_c_array(spec.offset)};")
        scale_loop = f"""    for (k = 0; k < {U}_N_FEATURES; ++k) {{
        x[k] = x[k] * {P}_scale[k] + {P}_offset[k];
    }}
"""
    sv_rows = ",\n".join("    " + _c_array(row) for row in spec.support_vectors)
    data.append(f"static const double {P}_support_vectors[{U}_N_SUPPORT_VECTORS][{U}_N_FEATURES] = {{\n{sv_rows}\n}};")
    data.append(f"static const double {P}_alpha[{U}_N_SUPPORT_VECTORS] = {_c_array(spec.alpha)};")
    data.append(f"static const double {P}_intercept = {_lit(spec.intercept)};")
    sigma2 = f"({_lit(spec.sigma)} * {_lit(spec.sigma)})"
    if spec.kernel == "rbf":
        kernel_body = f"""        double d2 = 0.0;
        for (k = 0; k < {U}_N_FEATURES; ++k) {{
            const double t = x[k] - {P}_support_vectors[i][k];
            d2 += t * t;
        }}
        kval = exp(-d2 / {sigma2});"""
    else:
        kernel_body = f"""        double dot = 0.0;
        for (k = 0; k < {U}_N_FEATURES; ++k) {{
            dot += x[k] * {P}_support_vectors[i][k];
        }}"""
        if spec.kernel == "linear":
            kernel_body += "\n        kval = dot;"
        else:
            kernel_body += f"""
        base = dot / {sigma2} + {_lit(spec.coef0)};
        kval = base;
        for (j = 1; j < {spec.degree}; ++j) {{
            kval *= base;
        }}"""
    decls = "        double kval, term, next, back;\n" + (
        "        double base;\n        int j;\n" if spec.kernel == "poly" else ""
    )
    fleet = spec.physics == FLEET_PHYSICS
    used = [*spec.functions, *(["isfinite"] if fleet else [])]
    libm = f"#include <math.h> /* {', '.join(used)} */\n" if used else ""
    input_count = f"{U}_N_INPUTS"
    fleet_functions = no_coefficient = ""
    if fleet:
        args = ", ".join(f"inputs->{name}" for name in COEFFICIENT_INPUTS)
        input_count = f"{P}_thermal({args}) ? {U}_N_INPUTS : {U}_N_INPUTS - {len(COEFFICIENT_INPUTS)}"
        fleet_functions = _c_fleet_functions() + "\n\n"
        no_coefficient = f"""    for (k = n_inputs; k < {U}_N_INPUTS; ++k) {{
        if (isfinite(u[k])) {{
            return 0; /* without a thermal k_z, a k_z input that is not NaN: neither model of the smoother */
        }}
    }}
"""
    source = f"""/*
 * {source_name}: the identified axial gyro drift model (see {header_name} for the interface).
 *
{prov}
 *
{_numerics_note(spec, " * ", "c")}
 */
#include "{header_name}"
#include <float.h>
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 2
#error "gyrodrift_model.c needs double arithmetic rounded to double (x87 extended precision: use SSE2)"
#endif
#ifdef __clang__
#pragma STDC FP_CONTRACT OFF /* Python rounds every product; gcc: compile with -ffp-contract=off or -std=c99 */
#endif
{libm}

{(chr(10) + chr(10)).join(data)}

{fleet_functions}const {P}_range *{P}_input_ranges(void)
{{
    return {P}_input_range_table;
}}

const {P}_range *{P}_feature_ranges(void)
{{
    return {P}_feature_range_table;
}}

void {P}_features(const {P}_inputs *inputs, double features[{U}_N_FEATURES])
{{
{feature_lines}
}}

int {P}_in_range(const {P}_inputs *inputs)
{{
    const double u[{U}_N_INPUTS] = {{{input_values}}};
    const int n_inputs = {input_count};
    double x[{U}_N_FEATURES];
    int k;
    for (k = 0; k < n_inputs; ++k) {{
        if (!(u[k] >= {P}_input_range_table[k].min && u[k] <= {P}_input_range_table[k].max)) {{
            return 0;
        }}
    }}
{no_coefficient}    {P}_features(inputs, x);
    for (k = 0; k < {U}_N_FEATURES; ++k) {{
        if (!(x[k] >= {P}_feature_range_table[k].min && x[k] <= {P}_feature_range_table[k].max)) {{
            return 0;
        }}
    }}
    return 1;
}}

/* The intercept + sum_i alpha_i K_i in support-vector order, compensated: sum[0] the rounded sum, sum[1] the
 * sum of the rounding errors (TwoSum, exact), to be added at the end (gyrodrift.learn.lssvr, "Sum2"). */
static void {P}_kernel_sum(const {P}_inputs *inputs, double sum[2])
{{
    double x[{U}_N_FEATURES];
    double acc = {P}_intercept, err = 0.0;
    int i, k;
    {P}_features(inputs, x);
{scale_loop}    for (i = 0; i < {U}_N_SUPPORT_VECTORS; ++i) {{
{decls}{kernel_body}
        term = {P}_alpha[i] * kval;
        next = acc + term;
        back = next - acc;
        err += (acc - (next - back)) + (term - back);
        acc = next;
    }}
    sum[0] = acc;
    sum[1] = err;
}}

double {learned}(const {P}_inputs *inputs)
{{
    double sum[2];
    {P}_kernel_sum(inputs, sum);
    return sum[0] + sum[1];
}}
"""
    if spec.physics is not None:
        physics = _expression(PHYSICS_EXPRESSIONS[spec.physics], "c", "inputs->{}", "{}")
        source += f"""
double {P}_physics_deg_h(const {P}_inputs *inputs)
{{
    return {physics};
}}

/* The physics estimate is one more term of the compensated sum (not added to the rounded correction). */
double {P}_drift_deg_h(const {P}_inputs *inputs)
{{
    double sum[2], term, next, back;
    {P}_kernel_sum(inputs, sum);
    term = {P}_physics_deg_h(inputs);
    next = sum[0] + term;
    back = next - sum[0];
    return next + (sum[1] + ((sum[0] - (next - back)) + (term - back)));
}}
"""
    return {header_name: header, source_name: source}


def _c_fleet_functions() -> str:
    """The C of the fleet-prior base (`FLEET_PHYSICS`): `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`'s
    end drift, operation for operation (``x**2`` in numpy is ``x * x``)."""
    P, U = _PREFIX, _PREFIX.upper()
    return f"""/* 1 when the smoother's k_z estimate is there (its thermal model), 0 for a constant-model run (NaN k_z):
 * the test of gyrodrift.learn.fleet_prior.drift_with_coefficient_prior. */
static int {P}_thermal(double coeff, double coeff_std, double cov, double prior_std)
{{
    const double vk = coeff_std * coeff_std;
    return isfinite(coeff) && isfinite(vk) && vk > 0.0 && isfinite(cov) && isfinite(prior_std) && prior_std > 0.0;
}}

/* The smoother's end drift [deg/h] with the fleet's prior N(mean, std^2) on k_z in place of its own N(0, s0^2),
 * the operations of gyrodrift.learn.fleet_prior.drift_with_coefficient_prior in order; the end drift itself on a
 * constant-model run. */
static double {P}_fleet_base_deg_h(double drift, double coeff, double coeff_std, double cov, double prior_std)
{{
    const double mean = {U}_COEFF_PRIOR_MEAN_DEG_H_PER_C, std = {U}_COEFF_PRIOR_STD_DEG_H_PER_C;
    const double vk = coeff_std * coeff_std;
    double lever, precision, coeff_new;
    if (!{P}_thermal(coeff, coeff_std, cov, prior_std)) {{
        return drift;
    }}
    lever = cov / vk;
    precision = 1.0 / vk - 1.0 / (prior_std * prior_std) + 1.0 / (std * std);
    coeff_new = (coeff / vk + mean / (std * std)) / precision;
    return drift + lever * (coeff_new - coeff);
}}"""


def _physics_doc(spec: ExportSpec) -> str:
    """What the physics estimate of a hybrid is, for a comment."""
    if spec.physics == "drift_inversion_deg_h":
        return "the 12 h inversion of the latitude error, w_ie dL / (cos(lat0) (1 - cos(w_ie 12 h)))"
    if spec.physics == FLEET_PHYSICS:
        return (
            "the smoother's end drift with the fleet's k_z prior in place of its own (the end drift itself when "
            "the k_z inputs are NaN: the smoother's constant model)"
        )
    return f"the input {spec.physics}, computed by the navigation computer"


def _numerics_note(spec: ExportSpec, marker: str, lang: str) -> str:
    """How the generated arithmetic matches Python's, and what it needs from the compiler (comment lines)."""
    functions = " and ".join(spec.functions)
    text = (
        "Numerics: the same IEEE operations, in the same order, as Python's DriftModel.predict (gyrodrift.learn.lssvr, "
        "prediction arithmetic): features, scaling, kernel per support vector, and the intercept + sum_i alpha_i "
        "K_i" + (" + physics estimate" if spec.physics is not None else "") + " as a compensated sum (TwoSum), "
        "accurate to the rounding of its terms even where they cancel"
        + (f"; {functions} from the C library (Python's: math.exp, numpy's cos)" if spec.functions else "")
        + (
            ". Compile without fast-math options: no reassociation, no contraction into fused multiply-adds "
            "(-ffp-contract=off; ISO modes such as -std=c99 are off by default in gcc), double evaluated in double."
            if lang == "c"
            else " (pass the platform's, f64::exp / f64::cos with std, for the same bits; libm's port may differ "
            "by an ulp)."
            if spec.functions
            else "."
        )
    )
    words, lines, line = text.split(), [], ""
    for word in words:
        if len(line) + len(word) + 1 > 100:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    lines.append(line)
    return "\n".join(marker + ln for ln in lines)


# --- Rust ------------------------------------------------------------------------------------------------


def _rust_array(values) -> str:
    return "[" + ", ".join(_lit(v) for v in values) + "]"


def _rust_range_table(name: str, count: str, names, ranges) -> str:
    rows = "\n".join(
        f'    Range {{ name: "{n}", min: {_lit(lo)}, max: {_lit(hi)} }},'
        for n, (lo, hi) in zip(names, ranges, strict=True)
    )
    return f"static {name}: [Range; {count}] = [\n{rows}\n];"


_RUST_FLEET_FUNCTIONS = """/// True when the smoother's k_z estimate is there (its thermal model), false for a
/// constant-model run (NaN k_z): the test of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`.
fn thermal(coeff: f64, coeff_std: f64, cov: f64, prior_std: f64) -> bool {
    let vk = coeff_std * coeff_std;
    coeff.is_finite() && vk.is_finite() && vk > 0.0 && cov.is_finite() && prior_std.is_finite() && prior_std > 0.0
}

/// The smoother's end drift [deg/h] with the fleet's prior N(mean, std^2) on k_z in place of its own N(0, s0^2),
/// the operations of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior` in order; the end drift itself on a
/// constant-model run.
fn fleet_base_deg_h(drift: f64, coeff: f64, coeff_std: f64, cov: f64, prior_std: f64) -> f64 {
    let (mean, std) = (COEFF_PRIOR_MEAN_DEG_H_PER_C, COEFF_PRIOR_STD_DEG_H_PER_C);
    let vk = coeff_std * coeff_std;
    if !thermal(coeff, coeff_std, cov, prior_std) {
        return drift;
    }
    let lever = cov / vk;
    let precision = 1.0 / vk - 1.0 / (prior_std * prior_std) + 1.0 / (std * std);
    let coeff_new = (coeff / vk + mean / (std * std)) / precision;
    drift + lever * (coeff_new - coeff)
}"""


def _rust_files(spec: ExportSpec) -> dict[str, str]:
    (file_name,) = LANGUAGES["rust"]
    nf, nsv, ni = len(spec.feature_names), spec.support_vectors.shape[0], len(spec.inputs)
    prov = "\n".join("//! " + line if line else "//!" for line in _provenance_lines(spec))
    fields = "\n".join(f"    /// {INPUTS[n]}\n    pub {n}: f64," for n in spec.inputs)
    math_fields = "\n".join(
        f"    /// `{fn}` of an f64 (e.g. `libm::{fn}`, or `f64::{fn}` with std)\n    pub {fn}: fn(f64) -> f64,"
        for fn in spec.functions
    )
    feats = _feature_exprs(spec, "rust", "inputs.{}", "(math.{})")
    features_math = "math" if any(FEATURE_EXPRESSIONS[f].functions for f in spec.feature_names) else "_math"
    feature_items = "\n".join(f"        {e}," for e in feats)
    input_values = ", ".join(f"inputs.{name}" for name in spec.inputs)
    data = [
        _rust_range_table("INPUT_RANGES", "N_INPUTS", spec.inputs, spec.input_ranges),
        _rust_range_table("FEATURE_RANGES", "N_FEATURES", spec.feature_names, spec.feature_ranges),
    ]
    scale_loop = ""
    if spec.scaling == "standard":
        data.append(f"static MEAN: [f64; N_FEATURES] = {_rust_array(spec.mean)};")
        data.append(f"static SCALE: [f64; N_FEATURES] = {_rust_array(spec.scale)};")
        scale_loop = """    for k in 0..N_FEATURES {
        x[k] = (x[k] - MEAN[k]) / SCALE[k];
    }
"""
    elif spec.scaling == "minmax":
        data.append(f"static SCALE: [f64; N_FEATURES] = {_rust_array(spec.scale)};")
        data.append(f"static OFFSET: [f64; N_FEATURES] = {_rust_array(spec.offset)};")
        scale_loop = """    for k in 0..N_FEATURES {
        x[k] = x[k] * SCALE[k] + OFFSET[k];
    }
"""
    sv_rows = "\n".join("    " + _rust_array(row) + "," for row in spec.support_vectors)
    data.append(f"static SUPPORT_VECTORS: [[f64; N_FEATURES]; N_SUPPORT_VECTORS] = [\n{sv_rows}\n];")
    data.append(f"static ALPHA: [f64; N_SUPPORT_VECTORS] = {_rust_array(spec.alpha)};")
    data.append(f"const INTERCEPT: f64 = {_lit(spec.intercept)};")
    sigma2 = f"({_lit(spec.sigma)}_f64 * {_lit(spec.sigma)}_f64)"
    if spec.kernel == "rbf":
        kernel_body = f"""        let mut d2 = 0.0_f64;
        for k in 0..N_FEATURES {{
            let t = x[k] - sv[k];
            d2 += t * t;
        }}
        let kval = (math.exp)(-d2 / {sigma2});"""
    else:
        kernel_body = """        let mut dot = 0.0_f64;
        for k in 0..N_FEATURES {
            dot += x[k] * sv[k];
        }"""
        if spec.kernel == "linear":
            kernel_body += "\n        let kval = dot;"
        else:
            kernel_body += f"""
        let base = dot / {sigma2} + {_lit(spec.coef0)}_f64;
        let mut kval = base;
        for _ in 1..{spec.degree} {{
            kval *= base;
        }}"""
    if spec.physics == FLEET_PHYSICS:
        args = ", ".join(f"inputs.{name}" for name in COEFFICIENT_INPUTS)
        in_range_fn = f"""{_RUST_FLEET_FUNCTIONS}

/// True when every input and every feature lies within its training range (NaN never does); on a run without a
/// thermal k_z (the smoother's constant model: its base is the end drift) the k_z inputs must all be NaN instead.
#[must_use]
pub fn in_range(inputs: &Inputs, math: &Math) -> bool {{
    let u = [{input_values}];
    let n = if thermal({args}) {{ N_INPUTS }} else {{ N_INPUTS - {len(COEFFICIENT_INPUTS)} }};
    within(&INPUT_RANGES[..n], &u[..n])
        && u[n..].iter().all(|v| !v.is_finite())
        && within(&FEATURE_RANGES, &features(inputs, math))
}}
"""
    else:
        in_range_fn = f"""/// True when every input and every feature lies within its training range (NaN never does).
#[must_use]
pub fn in_range(inputs: &Inputs, math: &Math) -> bool {{
    within(&INPUT_RANGES, &[{input_values}]) && within(&FEATURE_RANGES, &features(inputs, math))
}}
"""
    x_binding = "let x" if spec.scaling == "none" else "let mut x"
    learned = "drift_deg_h" if spec.physics is None else "correction_deg_h"
    if spec.physics is None:
        learned_doc = (
            "/// The identified axial gyro drift [deg/h]; check [`in_range`] first: the model does not extrapolate."
        )
        physics_macro = hybrid_fns = ""
    else:
        learned_doc = "/// The learned correction [deg/h] added to the physics estimate ([`physics_deg_h`])."
        physics_macro = f"""/// Physics estimate of the hybrid model (`physics_column`).
pub const PHYSICS: &str = "{spec.physics}";
"""
        if spec.coefficient_prior is not None:
            mean, std = spec.coefficient_prior
            physics_macro += f"""/// Mean of the training fleet's prior on k_z [deg/h/degC].
pub const COEFF_PRIOR_MEAN_DEG_H_PER_C: f64 = {_lit(mean)};
/// 1-sigma of the training fleet's prior on k_z [deg/h/degC].
pub const COEFF_PRIOR_STD_DEG_H_PER_C: f64 = {_lit(std)};
"""
        expr = PHYSICS_EXPRESSIONS[spec.physics]
        physics_math = "math" if expr.functions else "_math"
        hybrid_fns = f"""
/// The physics estimate [deg/h]: {_physics_doc(spec)}.
#[must_use]
pub fn physics_deg_h(inputs: &Inputs, {physics_math}: &Math) -> f64 {{
    {_expression(expr, "rust", "inputs.{}", "(math.{})")}
}}

/// The identified axial gyro drift [deg/h]: physics estimate + learned correction; check [`in_range`] first: the
/// model does not extrapolate.
#[must_use]
pub fn drift_deg_h(inputs: &Inputs, math: &Math) -> f64 {{
    // the physics estimate is one more term of the compensated sum (not added to the rounded correction)
    let (acc, err) = kernel_sum(inputs, math);
    let term = physics_deg_h(inputs, math);
    let next = acc + term;
    let back = next - acc;
    next + (err + ((acc - (next - back)) + (term - back)))
}}
"""
    text = f"""//! {file_name}: the identified axial gyro drift model, `no_std` (only `core`), no allocation, no I/O.
//!
{prov}
//!
{_numerics_note(spec, "//! ", "rust")}
#![allow(clippy::doc_markdown, clippy::excessive_precision, clippy::needless_range_loop, clippy::unreadable_literal)]

/// Version of gyrodrift that exported this module.
pub const GYRODRIFT_VERSION: &str = "{__version__}";
/// SHA-256 of the training runs (`gyrodrift.learn.model.training_digest`).
pub const TRAINING_SHA256: &str = "{spec.training["sha256"]}";
/// Encoding of a run into the model's features.
pub const ENCODING: &str = "{spec.encoding}";
/// Input scaling fitted on the training runs.
pub const SCALING: &str = "{spec.scaling}";
/// Kernel of the LSSVR.
pub const KERNEL: &str = "{spec.kernel}";
/// What the LSSVR learned: "drift", or "residual" (hybrid: drift = physics estimate + learned correction).
pub const TARGET: &str = "{spec.target}";
{physics_macro}/// Number of raw inputs (fields of [`Inputs`]).
pub const N_INPUTS: usize = {ni};
/// Number of features.
pub const N_FEATURES: usize = {nf};
/// Number of support vectors (training runs).
pub const N_SUPPORT_VECTORS: usize = {nsv};

/// The inputs the model reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inputs {{
{fields}
}}

/// The math functions the model needs (`core` has none): pass e.g. `libm`'s, or std's.
#[derive(Clone, Copy, Debug)]
pub struct Math {{
{math_fields}
}}

/// The range of one input or feature over the training runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {{
    /// Input or feature name (the unit is in the name or in the field's documentation).
    pub name: &'static str,
    /// Smallest value over the training runs.
    pub min: f64,
    /// Largest value over the training runs.
    pub max: f64,
}}

{(chr(10) + chr(10)).join(data)}

/// The training range of each input, in the order of the fields of [`Inputs`].
#[must_use]
pub fn input_ranges() -> &'static [Range; N_INPUTS] {{
    &INPUT_RANGES
}}

/// The training range of each feature, in the order of [`features`].
#[must_use]
pub fn feature_ranges() -> &'static [Range; N_FEATURES] {{
    &FEATURE_RANGES
}}

/// The model's features of `inputs` (the same operations as `gyrodrift.learn.encodings.encode`).
#[must_use]
pub fn features(inputs: &Inputs, {features_math}: &Math) -> [f64; N_FEATURES] {{
    [
{feature_items}
    ]
}}

fn within(ranges: &[Range], values: &[f64]) -> bool {{
    ranges.iter().zip(values.iter()).all(|(r, &v)| v >= r.min && v <= r.max)
}}

{in_range_fn}
/// The intercept + `sum_i alpha_i K_i` in support-vector order, compensated: the rounded sum and the sum of the
/// rounding errors (`TwoSum`, exact), to be added at the end (`gyrodrift.learn.lssvr`, "Sum2").
#[allow(clippy::trivially_copy_pass_by_ref)] // as the public functions, which take `&Math`
fn kernel_sum(inputs: &Inputs, math: &Math) -> (f64, f64) {{
    {x_binding} = features(inputs, math);
{scale_loop}    let (mut acc, mut err) = (INTERCEPT, 0.0_f64);
    for (sv, &alpha) in SUPPORT_VECTORS.iter().zip(ALPHA.iter()) {{
{kernel_body}
        let term = alpha * kval;
        let next = acc + term;
        let back = next - acc;
        err += (acc - (next - back)) + (term - back);
        acc = next;
    }}
    (acc, err)
}}

{learned_doc}
#[must_use]
pub fn {learned}(inputs: &Inputs, math: &Math) -> f64 {{
    let (acc, err) = kernel_sum(inputs, math);
    acc + err
}}
{hybrid_fns}"""
    return {file_name: text}
