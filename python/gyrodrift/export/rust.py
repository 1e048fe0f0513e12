"""The export spec as a ``no_std`` Rust module (templates/gyrodrift_model.rs.in): only ``core``, no allocation, no
I/O, the math functions passed in; the physics functions of a hybrid (templates/hybrid.rs.in) and the fleet-prior
base (templates/fleet_base.rs.in) and its drift law (templates/law.rs.in) where the model has them."""

from __future__ import annotations

from gyrodrift.export import render
from gyrodrift.export.literals import array, literal, range_rows
from gyrodrift.export.spec import FEATURE_EXPRESSIONS, INPUTS, PHYSICS_EXPRESSIONS, ExportSpec
from gyrodrift.learn.physics_base import FLEET_PHYSICS
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS

__all__ = ["FILES", "rust_files"]

FILES = ("gyrodrift_model.rs",)
"""The module an export to Rust writes."""


def rust_files(spec: ExportSpec) -> dict[str, str]:
    """The module computing ``spec``: ``{file name: text}``."""
    text = render.fill(
        "gyrodrift_model.rs.in",
        provenance=render.comment_block(render.provenance_lines(spec), "//! "),
        numerics=render.numerics_note(spec, "//! ", "rust"),
        physics_macro=_physics_constants(spec),
        **render.identity(spec),
        fields="\n".join(f"    /// {INPUTS[n]}\n    pub {n}: f64," for n in spec.inputs),
        math_fields="\n".join(
            f"    /// `{fn}` of an f64 (e.g. `libm::{fn}`, or `f64::{fn}` with std)\n    pub {fn}: fn(f64) -> f64,"
            for fn in spec.functions
        ),
        data=_data(spec),
        features_math="math" if any(FEATURE_EXPRESSIONS[f].functions for f in spec.feature_names) else "_math",
        feature_items="\n".join(
            f"        {e}," for e in render.feature_expressions(spec, "rust", "inputs.{}", "(math.{})")
        ),
        in_range_fn=_in_range(spec),
        x_binding="let x" if spec.scaling == "none" else "let mut x",
        scale_loop=_scale_loop(spec),
        kernel_body=_kernel_body(spec),
        learned_doc=(
            "/// The identified axial gyro drift [deg/h]; check [`in_range`] first: the model does not extrapolate."
            if spec.physics is None
            else "/// The learned correction [deg/h] added to the physics estimate ([`physics_deg_h`])."
        ),
        learned="drift_deg_h" if spec.physics is None else "correction_deg_h",
    )
    if spec.physics is None:
        return {FILES[0]: text}
    expr = PHYSICS_EXPRESSIONS[spec.physics]
    hybrid = render.fill(
        "hybrid.rs.in",
        physics_doc=render.physics_doc(spec),
        physics_math="math" if expr.functions else "_math",
        physics=render.expression(expr, "rust", "inputs.{}", "(math.{})"),
    )
    if spec.temp_range_c is not None:
        lo, hi = spec.temp_range_c
        hybrid += render.fill("law.rs.in", temp_min=literal(lo), temp_max=literal(hi))
    return {FILES[0]: text + "\n" + hybrid}


def _physics_constants(spec: ExportSpec) -> str:
    """A hybrid's physics column and the fleet's k_z prior, as documented constants (nothing for ``drift``)."""
    if spec.physics is None:
        return ""
    text = f"""/// Physics estimate of the hybrid model (`physics_column`).
pub const PHYSICS: &str = "{spec.physics}";
"""
    if spec.coefficient_prior is not None:
        mean, std = spec.coefficient_prior
        text += f"""/// Mean of the training fleet's prior on k_z [deg/h/degC].
pub const COEFF_PRIOR_MEAN_DEG_H_PER_C: f64 = {literal(mean)};
/// 1-sigma of the training fleet's prior on k_z [deg/h/degC].
pub const COEFF_PRIOR_STD_DEG_H_PER_C: f64 = {literal(std)};
"""
    return text


def _data(spec: ExportSpec) -> str:
    """The static tables: the training ranges, the scaler, the support vectors, alpha and the intercept."""
    row = '    Range {{ name: "{name}", min: {lo}, max: {hi} }},'
    data = [
        "static INPUT_RANGES: [Range; N_INPUTS] = [\n" + range_rows(spec.inputs, spec.input_ranges, row, "\n") + "\n];",
        "static FEATURE_RANGES: [Range; N_FEATURES] = [\n"
        + range_rows(spec.feature_names, spec.feature_ranges, row, "\n")
        + "\n];",
    ]
    for name, values in render.scaler_arrays(spec):
        data.append(f"static {name.upper()}: [f64; N_FEATURES] = {array(values, '[]')};")
    sv_rows = "\n".join("    " + array(sv, "[]") + "," for sv in spec.support_vectors)
    data.append(f"static SUPPORT_VECTORS: [[f64; N_FEATURES]; N_SUPPORT_VECTORS] = [\n{sv_rows}\n];")
    data.append(f"static ALPHA: [f64; N_SUPPORT_VECTORS] = {array(spec.alpha, '[]')};")
    data.append(f"const INTERCEPT: f64 = {literal(spec.intercept)};")
    return "\n\n".join(data)


def _scale_loop(spec: ExportSpec) -> str:
    if spec.scaling not in render.SCALING_STEPS:
        return ""
    step = render.SCALING_STEPS[spec.scaling].format(mean="MEAN", scale="SCALE", offset="OFFSET")
    return f"""    for k in 0..N_FEATURES {{
        {step}
    }}
"""


def _kernel_body(spec: ExportSpec) -> str:
    """The kernel value ``kval`` of support vector ``sv`` against the scaled features ``x``."""
    sigma2 = f"({literal(spec.sigma)}_f64 * {literal(spec.sigma)}_f64)"
    if spec.kernel == "rbf":
        return f"""        let mut d2 = 0.0_f64;
        for k in 0..N_FEATURES {{
            let t = x[k] - sv[k];
            d2 += t * t;
        }}
        let kval = (math.exp)(-d2 / {sigma2});"""
    body = """        let mut dot = 0.0_f64;
        for k in 0..N_FEATURES {
            dot += x[k] * sv[k];
        }"""
    if spec.kernel == "linear":
        return body + "\n        let kval = dot;"
    return (
        body
        + f"""
        let base = dot / {sigma2} + {literal(spec.coef0)}_f64;
        let mut kval = base;
        for _ in 1..{spec.degree} {{
            kval *= base;
        }}"""
    )


def _in_range(spec: ExportSpec) -> str:
    """`in_range`, and before it for the fleet-prior base its functions (which `in_range` uses too)."""
    input_values = ", ".join(f"inputs.{name}" for name in spec.inputs)
    if spec.physics != FLEET_PHYSICS:
        return f"""/// True when every input and every feature lies within its training range (NaN never does).
#[must_use]
pub fn in_range(inputs: &Inputs, math: &Math) -> bool {{
    within(&INPUT_RANGES, &[{input_values}]) && within(&FEATURE_RANGES, &features(inputs, math))
}}
"""
    args = ", ".join(f"inputs.{name}" for name in SMOOTHER_THERMAL_COLUMNS)
    return (
        render.fill("fleet_base.rs.in")
        + f"""
/// True when every input and every feature lies within its training range (NaN never does); on a run without a
/// thermal k_z (the smoother's constant model: its base is the end drift) the k_z inputs must all be NaN instead.
#[must_use]
pub fn in_range(inputs: &Inputs, math: &Math) -> bool {{
    let u = [{input_values}];
    let n = if thermal({args}) {{ N_INPUTS }} else {{ N_INPUTS - {len(SMOOTHER_THERMAL_COLUMNS)} }};
    within(&INPUT_RANGES[..n], &u[..n])
        && u[n..].iter().all(|v| !v.is_finite())
        && within(&FEATURE_RANGES, &features(inputs, math))
}}
"""
    )
