"""The export spec as C99: a header and a source (templates/gyrodrift_model.h.in, .c.in), const data only, no
allocation, no I/O; the physics functions of a hybrid (templates/hybrid.c.in) and the fleet-prior base
(templates/fleet_base.c.in) and its drift law (templates/law.c.in) where the model has them."""

from __future__ import annotations

from gyrodrift.export import render
from gyrodrift.export.literals import array, literal, range_rows
from gyrodrift.export.spec import INPUTS, PHYSICS_EXPRESSIONS, ExportSpec
from gyrodrift.learn.physics_base import FLEET_PHYSICS
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS

__all__ = ["FILES", "c_files"]

FILES = ("gyrodrift_model.h", "gyrodrift_model.c")
"""The header and the source an export to C writes."""


def c_files(spec: ExportSpec) -> dict[str, str]:
    """The header and the source computing ``spec``: ``{file name: text}``."""
    provenance = render.comment_block(render.provenance_lines(spec), " * ")
    return {FILES[0]: _header(spec, provenance), FILES[1]: _source(spec, provenance)}


def _header(spec: ExportSpec, provenance: str) -> str:
    """gyrodrift_model.h: the constants, the input struct, the range type and the functions' declarations."""
    if spec.physics is None:
        physics_macro = ""
        drift_decl = (
            "/* The identified axial gyro drift [deg/h]; check gyrodrift_model_in_range first: the model does not\n"
            " * extrapolate. */\n"
            "double gyrodrift_model_drift_deg_h(const gyrodrift_model_inputs *inputs);"
        )
    else:
        physics_macro = f'#define GYRODRIFT_MODEL_PHYSICS "{spec.physics}"\n'
        if spec.coefficient_prior is not None:
            mean, std = spec.coefficient_prior
            physics_macro += (
                "/* The training fleet's prior on k_z [deg/h/degC]: mean and 1-sigma. */\n"
                f"#define GYRODRIFT_MODEL_COEFF_PRIOR_MEAN_DEG_H_PER_C {literal(mean)}\n"
                f"#define GYRODRIFT_MODEL_COEFF_PRIOR_STD_DEG_H_PER_C {literal(std)}\n"
            )
        drift_decl = f"""/* The physics estimate [deg/h]: {render.physics_doc(spec)}. */
double gyrodrift_model_physics_deg_h(const gyrodrift_model_inputs *inputs);

/* The learned correction [deg/h] added to the physics estimate. */
double gyrodrift_model_correction_deg_h(const gyrodrift_model_inputs *inputs);

/* The identified axial gyro drift [deg/h]: physics estimate + learned correction.
 * Check gyrodrift_model_in_range first: the model does not extrapolate. */
double gyrodrift_model_drift_deg_h(const gyrodrift_model_inputs *inputs);"""
        if spec.temp_range_c is not None:
            lo, hi = (literal(t) for t in spec.temp_range_c)
            drift_decl += "\n\n" + render.fill("law.h.in", temp_min=lo, temp_max=hi).rstrip("\n")
    return render.fill(
        "gyrodrift_model.h.in",
        provenance=provenance,
        physics_macro=physics_macro,
        **render.identity(spec),
        fields="\n".join(f"    double {name}; /* {INPUTS[name]} */" for name in spec.inputs),
        drift_decl=drift_decl,
    )


def _data(spec: ExportSpec) -> str:
    """The const tables: the training ranges, the scaler, the support vectors, alpha and the intercept."""
    n_inputs, n_features, n_sv = (f"GYRODRIFT_MODEL_N_{n}" for n in ("INPUTS", "FEATURES", "SUPPORT_VECTORS"))
    row = '    {{"{name}", {lo}, {hi}}}'
    data = [
        f"static const gyrodrift_model_range gyrodrift_model_input_range_table[{n_inputs}] = {{\n"
        + range_rows(spec.inputs, spec.input_ranges, row, ",\n")
        + "\n};",
        f"static const gyrodrift_model_range gyrodrift_model_feature_range_table[{n_features}] = {{\n"
        + range_rows(spec.feature_names, spec.feature_ranges, row, ",\n")
        + "\n};",
    ]
    for name, values in render.scaler_arrays(spec):
        data.append(f"static const double gyrodrift_model_{name}[{n_features}] = {_array(values)};")
    sv_rows = ",\n".join("    " + _array(sv) for sv in spec.support_vectors)
    data.append(f"static const double gyrodrift_model_support_vectors[{n_sv}][{n_features}] = {{\n{sv_rows}\n}};")
    data.append(f"static const double gyrodrift_model_alpha[{n_sv}] = {_array(spec.alpha)};")
    data.append(f"static const double gyrodrift_model_intercept = {literal(spec.intercept)};")
    return "\n\n".join(data)


def _array(values) -> str:
    return array(values, "{}")


def _kernel_body(spec: ExportSpec) -> str:
    """The declarations and the kernel value ``kval`` of support vector ``i`` against the scaled features ``x``."""
    decls = "        double kval, term, next, back;\n" + (
        "        double base;\n        int j;\n" if spec.kernel == "poly" else ""
    )
    sigma2 = f"({literal(spec.sigma)} * {literal(spec.sigma)})"
    if spec.kernel == "rbf":
        return (
            decls
            + f"""        double d2 = 0.0;
        for (k = 0; k < GYRODRIFT_MODEL_N_FEATURES; ++k) {{
            const double t = x[k] - gyrodrift_model_support_vectors[i][k];
            d2 += t * t;
        }}
        kval = exp(-d2 / {sigma2});"""
        )
    body = (
        decls
        + """        double dot = 0.0;
        for (k = 0; k < GYRODRIFT_MODEL_N_FEATURES; ++k) {
            dot += x[k] * gyrodrift_model_support_vectors[i][k];
        }"""
    )
    if spec.kernel == "linear":
        return body + "\n        kval = dot;"
    return (
        body
        + f"""
        base = dot / {sigma2} + {literal(spec.coef0)};
        kval = base;
        for (j = 1; j < {spec.degree}; ++j) {{
            kval *= base;
        }}"""
    )


def _source(spec: ExportSpec, provenance: str) -> str:
    """gyrodrift_model.c: the data tables, the features, the range check, the kernel sum and the drift."""
    scale_loop = ""
    if spec.scaling in render.SCALING_STEPS:
        step = render.SCALING_STEPS[spec.scaling].format(
            **{name: f"gyrodrift_model_{name}" for name in ("mean", "scale", "offset")}
        )
        scale_loop = f"""    for (k = 0; k < GYRODRIFT_MODEL_N_FEATURES; ++k) {{
        {step}
    }}
"""
    fleet = spec.physics == FLEET_PHYSICS
    used = [*spec.functions, *(["isfinite"] if fleet else [])]
    input_count = "GYRODRIFT_MODEL_N_INPUTS"
    fleet_functions = no_coefficient = ""
    if fleet:
        args = ", ".join(f"inputs->{name}" for name in SMOOTHER_THERMAL_COLUMNS)
        n_constant = len(SMOOTHER_THERMAL_COLUMNS)  # a constant-model run checks the inputs before the k_z ones
        input_count = f"gyrodrift_model_thermal({args}) ? {input_count} : {input_count} - {n_constant}"
        fleet_functions = render.fill("fleet_base.c.in") + "\n"
        no_coefficient = """    for (k = n_inputs; k < GYRODRIFT_MODEL_N_INPUTS; ++k) {
        if (isfinite(u[k])) {
            return 0; /* without a thermal k_z, a k_z input that is not NaN: neither model of the smoother */
        }
    }
"""
    features = render.feature_expressions(spec, "c", "inputs->{}", "{}")
    source = render.fill(
        "gyrodrift_model.c.in",
        provenance=provenance,
        numerics=render.numerics_note(spec, " * ", "c"),
        libm=f"#include <math.h> /* {', '.join(used)} */\n" if used else "",
        data=_data(spec),
        fleet_functions=fleet_functions,
        feature_lines="\n".join(f"    features[{k}] = {e};" for k, e in enumerate(features)),
        input_values=", ".join(f"inputs->{name}" for name in spec.inputs),
        input_count=input_count,
        no_coefficient=no_coefficient,
        scale_loop=scale_loop,
        kernel_body=_kernel_body(spec),
        learned="gyrodrift_model_drift_deg_h" if spec.physics is None else "gyrodrift_model_correction_deg_h",
    )
    if spec.physics is None:
        return source
    physics = render.expression(PHYSICS_EXPRESSIONS[spec.physics], "c", "inputs->{}", "{}")
    source += "\n" + render.fill("hybrid.c.in", physics=physics)
    if spec.temp_range_c is None:
        return source
    return source + render.fill("law.c.in")
