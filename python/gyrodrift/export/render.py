"""The text shared by the C and the Rust generator: comments, provenance, expressions, and the templates.

The constants are printed as `gyrodrift.export.literals.literal`, so they are the model's bits. The generated code
does the IEEE operations of Python's prediction in the same order (`gyrodrift.learn.lssvr`, "prediction arithmetic":
distances in feature order, the C library's ``exp``, ``b + sum_i alpha_i K_i`` (+ the physics estimate) as a
compensated sum in support-vector order), so on the same machine it returns the same bits; on a navigation computer
only a libm rounding ``exp`` or ``cos`` the other way can differ, by about eps times the size of the summed terms
(`numerics_note`; docs/export.md gives the measurements and what the compiler must not do).

Provenance travels with the code (`provenance_lines`): the training digest, the exporting package's version, the
encoding, scaling, kernel and hyperparameters, the target (a hybrid's physics column), and the range of each input
and feature over the training runs. The code skeletons are source files in ``templates/`` (``*.in``), filled by
`string.Template` (`fill`): ``$name`` stands for a piece of generated text.
"""

from __future__ import annotations

import json
import re
from importlib.resources import files
from string import Template

from gyrodrift import __version__
from gyrodrift.export.literals import literal
from gyrodrift.export.spec import FEATURE_EXPRESSIONS, INPUTS, ExportSpec, FeatureExpression
from gyrodrift.learn.physics_base import FLEET_PHYSICS
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS

__all__ = [
    "SCALING_STEPS",
    "comment_block",
    "expression",
    "feature_expressions",
    "fill",
    "identity",
    "numerics_note",
    "physics_doc",
    "provenance_lines",
    "scaler_arrays",
]

SCALING_STEPS: dict[str, str] = {
    "standard": "x[k] = (x[k] - {mean}[k]) / {scale}[k];",
    "minmax": "x[k] = x[k] * {scale}[k] + {offset}[k];",
}
"""The scaler's step on feature ``k`` in C and Rust (the same statement in both), its arrays named by the
language (`scaler_arrays`)."""


def identity(spec: ExportSpec) -> dict[str, str | int]:
    """The template values naming the model in both languages: the exporting version, the training digest, the
    encoding, scaling, kernel and target, and the numbers of inputs, features and support vectors."""
    return {
        "version": __version__,
        "training_sha256": spec.training["sha256"],
        "encoding": spec.encoding,
        "scaling": spec.scaling,
        "kernel": spec.kernel,
        "target": spec.target,
        "n_inputs": len(spec.inputs),
        "n_features": len(spec.feature_names),
        "n_support_vectors": spec.support_vectors.shape[0],
    }


def fill(template: str, **values: str | int) -> str:
    """The template file ``templates/<template>`` with each ``$name`` replaced by ``values[name]``."""
    text = files("gyrodrift.export").joinpath("templates", template).read_text(encoding="utf-8")
    return Template(text).substitute(values)


def scaler_arrays(spec: ExportSpec) -> list[tuple[str, object]]:
    """The scaler's arrays as (name, values), in the order the generated code declares them (none when unscaled)."""
    if spec.scaling == "standard":
        return [("mean", spec.mean), ("scale", spec.scale)]
    if spec.scaling == "minmax":
        return [("scale", spec.scale), ("offset", spec.offset)]
    return []


def comment_block(lines: list[str], marker: str) -> str:
    """``lines`` as comment lines starting with ``marker`` (``" * "``, ``"//! "``; an empty line gets it stripped)."""
    return "\n".join(marker + line if line else marker.rstrip() for line in lines)


def comment_text(value) -> str:
    """``value`` as text safe inside a C block comment and a Rust line comment: printable ASCII on one line
    (JSON escapes for the rest), no ``*/`` and no C trigraph (``??/`` would splice lines)."""
    text = json.dumps(str(value), ensure_ascii=True)[1:-1].replace("*/", "*\\/")
    return re.sub(r"\?(?=\?)", r"?\\", text)


def provenance_lines(spec: ExportSpec) -> list[str]:
    """Human-readable provenance, one line each (the caller adds the comment markers)."""
    training = spec.training
    lines = [
        f"Exported by gyrodrift {__version__} (`gyrodrift export`). Do not edit: export the model file again.",
        f"Training digest (SHA-256 of the training runs): {training.get('sha256', 'unknown')}",
        f"Training runs: {training.get('n_runs', 'unknown')} from {comment_text(training.get('source', '?'))}",
    ]
    if spec.model_sha256:
        lines.append(f"Model file SHA-256: {spec.model_sha256}")
    lines += [
        f"Encoding: {spec.encoding} (features: {', '.join(spec.feature_names)})",
        f"Scaling: {spec.scaling}",
        f"Kernel: {_kernel_formula(spec)}",
        f"Hyperparameters: gamma = {literal(spec.gamma)}, sigma = {literal(spec.sigma)} (scaled input units)"
        + (f", degree = {spec.degree}, coef0 = {literal(spec.coef0)}" if spec.kernel == "poly" else ""),
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
            f"Fleet k_z prior: mean = {literal(mean)}, 1-sigma = {literal(std)} [deg/h/degC] (pooled over the "
            "training runs' k_z: gyrodrift.learn.fleet_prior.pooled_coefficient_prior)"
        )
    if spec.temp_range_c is not None:
        lo, hi = spec.temp_range_c
        lines.append(
            "Drift law: eps(T) = drift + k1 (T - T_ref) [deg/h], T_ref the temperature at the end of the 16 h span, "
            "k1 the smoother's k_z with the fleet's prior (0 on a constant-model run)"
        )
        lines.append(f"  T within the training runs' temperatures: [{literal(lo)}, {literal(hi)}] deg C")
    lines.append("Inputs read, with their range over the training runs (the range check refuses inputs outside it):")
    for name, (lo, hi) in zip(spec.inputs, spec.input_ranges, strict=True):
        note = (
            " (over the runs with k_z; must be NaN where the run has none)" if name in SMOOTHER_THERMAL_COLUMNS else ""
        )
        lines.append(f"  {name}: [{literal(lo)}, {literal(hi)}]{note}, {INPUTS[name]}")
    lines.append("Features, with their range over the training runs (checked too):")
    for name, (lo, hi) in zip(spec.feature_names, spec.feature_ranges, strict=True):
        lines.append(f"  {name}: [{literal(lo)}, {literal(hi)}] {FEATURE_EXPRESSIONS[name].unit}")
    total = "" if spec.physics is None else " = physics estimate + learned correction"
    lines.append(f"Output: identified axial gyro drift [deg/h]{total} (subtract it from the z-gyro output).")
    return lines


def _kernel_formula(spec: ExportSpec) -> str:
    if spec.kernel == "rbf":
        return "rbf, K(x, z) = exp(-|x - z|^2 / sigma^2)"
    if spec.kernel == "linear":
        return "linear, K(x, z) = x . z"
    return "poly, K(x, z) = (x . z / sigma^2 + coef0)^degree"


def physics_doc(spec: ExportSpec) -> str:
    """What the physics estimate of a hybrid is, for a comment."""
    if spec.physics == "drift_inversion_deg_h":
        return "the 12 h inversion of the latitude error, w_ie dL / (cos(lat0) (1 - cos(w_ie 12 h)))"
    if spec.physics == FLEET_PHYSICS:
        return (
            "the smoother's end drift with the fleet's k_z prior in place of its own (the end drift itself when "
            "the k_z inputs are NaN: the smoother's constant model)"
        )
    return f"the input {spec.physics}, computed by the navigation computer"


def numerics_note(spec: ExportSpec, marker: str, lang: str) -> str:
    """How the generated arithmetic matches Python's, and what it needs from the compiler (comment lines of at
    most 100 characters after ``marker``)."""
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
    lines, line = [], ""
    for word in text.split():
        if len(line) + len(word) + 1 > 100:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    lines.append(line)
    return comment_block(lines, marker)


def expression(expr: FeatureExpression, lang: str, field: str, function: str) -> str:
    """``expr`` in ``lang``, reading inputs as ``field.format(name)`` and functions as ``function.format(name)``."""
    template = expr.c if lang == "c" else expr.rust
    subst = {inp: field.format(inp) for inp in INPUTS}
    subst.update({fn: function.format(fn) for fn in expr.functions})
    return template.format(**subst)


def feature_expressions(spec: ExportSpec, lang: str, field: str, function: str) -> list[str]:
    """The expression of each feature in ``lang`` (see `expression`)."""
    return [expression(FEATURE_EXPRESSIONS[name], lang, field, function) for name in spec.feature_names]
