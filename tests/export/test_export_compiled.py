"""`gyrodrift export`: the generated C and Rust reproduce `DriftModel.predict`, its features and the range check.

The 114 models of tests/export/export_cases.py (fixture ``fitted``: every encoding x scaling x kernel, the hybrids
on every physics column, the default ``gyrodrift fit`` model through the commands), each on 1000 rows (the
training runs, then random rows over 1.2 times each input's training range). The C of every model is built as one
translation unit (each model's source included as it is, its names renamed by macros), the Rust in one crate.

Tolerance: ``|generated - python| <= 1e-12 * |python|`` on every row, the drifts near zero included. Python's
prediction (`gyrodrift.learn.lssvr`, "prediction arithmetic") and the generated code do the same IEEE operations in the
same order, the kernel's exp from the same C library and the sum compensated, so they agree to the last bit
here (counted). The compensated sum is checked too: Python's prediction is within 1 ulp of its terms summed
exactly (`math.fsum`, the terms recomputed here from the documented operations), however much they cancel
(condition ``S / |sum|`` with ``S = sum_i |alpha_i K_i| + |b|`` (+ ``|physics|``) printed). The measured maxima
are printed (``pytest -s``) and quoted in docs/export.md.
"""

from __future__ import annotations

import os
import re
import subprocess
import time

import numpy as np
import pytest
from export_cases import (
    ALL,
    ALL_CASES,
    CARGO,
    CC,
    CFLAGS,
    COS_CASE,
    DEFAULT_CASE,
    FLEET,
    N_ROWS,
    TOL,
    check_case,
    export_case,
    rows_text,
    thermal_rows,
)

from gyrodrift.export.spec import (
    FEATURE_EXPRESSIONS,
    physics_column,
)


def test_python_prediction_is_its_terms_summed_exactly_then_rounded(fitted):
    """The compensated sum: within 1 ulp of the exact sum of its terms on every row of every model, even where
    they cancel (condition S / |sum| up to about 1e10); numpy's kernel summed by BLAS is not."""
    cond, numpy_err = {}, {}
    for case_id in ALL_CASES:
        exp = fitted[case_id][2]
        err = np.abs(exp["pred"] - exp["exact"])
        assert np.all(err <= np.spacing(np.abs(exp["exact"]))), case_id
        cond[case_id] = np.max(exp["scale"] / np.abs(exp["exact"]))
        numpy_err[case_id] = np.max(np.abs(exp["numpy"] - exp["exact"]) / np.abs(exp["exact"]))
    assert max(cond.values()) > 1e6  # terms cancel (down to a drift ~1e-7 of its terms): the check is not trivial
    assert max(numpy_err.values()) > 1e-12  # where numpy's kernel summed by BLAS misses the 1e-12 target


# --- C ------------------------------------------------------------------------------------------------------

_C_WRAPPER = """/* Model NAME: its generated source, every gyrodrift_model_ name renamed NAME_. */
#include <stdio.h>
#include <stdlib.h>
RENAMES
#include "NAME/gyrodrift_model.c"

int NAME_run(void);

/* Rows of every input of the test on stdin; per row: drift, in range, physics, features. */
int NAME_run(void)
{
    char text[N_ALL][64];
    double u[N_ALL], f[GYRODRIFT_MODEL_N_FEATURES];
    int k;
    while (scanf(FORMAT, TEXTS) == N_ALL) {
        gyrodrift_model_inputs in;
        for (k = 0; k < N_ALL; ++k) {
            u[k] = strtod(text[k], NULL);
        }
FILL
        gyrodrift_model_features(&in, f);
        printf("%.17g %d %.17g", gyrodrift_model_drift_deg_h(&in), gyrodrift_model_in_range(&in), PHYSICS);
        for (k = 0; k < GYRODRIFT_MODEL_N_FEATURES; ++k) {
            printf(" %.17g", f[k]);
        }
        printf("\\n");
    }
    return 0;
}
UNDEFS
"""

C_RESULTS: dict[str, tuple[float, ...]] = {}
"""Case id -> (max |c - py| / |py|, fraction of rows with the same bits, max |py - exact| / |exact|,
max |numpy - exact| / |exact|, max condition S / |exact|, fraction of the rows in range), printed by
test_c_summary."""


def _c_wrapper(name: str, files: dict[str, str], hybrid: bool) -> str:
    """Model ``name``'s part of the one translation unit: its names (functions, tables, types, all prefixed
    gyrodrift_model_) renamed ``name``_ by macros, its source included, its runner, then every macro of it undefined
    (the header's guard and constants included), so that the next model's source is read as if alone."""
    header, text = files["gyrodrift_model.h"], "".join(files.values())
    names = sorted(set(re.findall(r"\bgyrodrift_model_\w+", text + _C_WRAPPER)))
    macros = sorted(set(re.findall(r"#define (\w+)", text)))
    fill = "\n".join(f"        in.{n} = u[{k}];" for k, n in enumerate(ALL) if f"double {n};" in header)
    return (
        _C_WRAPPER.replace(
            "RENAMES", "".join(f"#define {n} NAME_{n.removeprefix('gyrodrift_model_')}\n" for n in names)
        )
        .replace("NAME", name)
        .replace("N_ALL", str(len(ALL)))
        .replace("FORMAT", '"' + " ".join(["%63s"] * len(ALL)) + '"')
        .replace("TEXTS", ", ".join(f"text[{k}]" for k in range(len(ALL))))
        .replace("FILL", fill)
        .replace("PHYSICS", "gyrodrift_model_physics_deg_h(&in)" if hybrid else "0.0")
        .replace("UNDEFS", "".join(f"#undef {n}\n" for n in [*names, *macros]))  # last: no placeholder in them
    )


@pytest.fixture(scope="module")
def c_driver(fitted, tmp_path_factory):
    """One program holding every model's C (one translation unit: one compiler run of cc1 instead of one per
    model, 40 % less CPU); ``driver k`` evaluates model k on stdin.

    Returns (path, {case id: model index}, build time [s])."""
    folder = tmp_path_factory.mktemp("c_export")
    index, parts, dispatch = {}, [], []
    for k, case_id in enumerate(ALL_CASES):
        model = fitted[case_id][0]
        name = f"m{k:03d}"
        files = export_case(case_id, model, "c")
        needs_math = model.lssvr.kernel == "rbf" or any(FEATURE_EXPRESSIONS[f].functions for f in model.feature_names)
        needs_math |= case_id == COS_CASE or (
            physics_column(model) in ("drift_inversion_deg_h", FLEET)  # cos; isfinite
        )
        assert ("#include <math.h>" in files["gyrodrift_model.c"]) == needs_math, case_id
        (folder / name).mkdir()
        for file_name, text in files.items():
            (folder / name / file_name).write_text(text)
        parts.append(_c_wrapper(name, files, model.target == "residual"))
        dispatch.append(f"    case {k}: return {name}_run();")
        index[case_id] = k
    (folder / "models.c").write_text("".join(parts))
    declarations = "".join(f"int m{k:03d}_run(void);\n" for k in range(len(ALL_CASES)))
    (folder / "main.c").write_text(
        f"#include <stdlib.h>\n{declarations}\nint main(int argc, char **argv)\n{{\n"
        f"    switch (argc > 1 ? atoi(argv[1]) : -1) {{\n"
        + "\n".join(dispatch)
        + "\n    default: return 2;\n    }\n}\n"
    )
    start = time.perf_counter()
    subprocess.run([CC, *CFLAGS, "main.c", "models.c", "-lm", "-o", "driver"], cwd=folder, check=True, timeout=600)
    return folder / "driver", index, time.perf_counter() - start


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
@pytest.mark.parametrize("case_id", ALL_CASES)
def test_c_export_reproduces_python(case_id, fitted, c_driver):
    model, rows, exp = fitted[case_id]
    driver, index, _ = c_driver
    out = subprocess.run(
        [str(driver), str(index[case_id])],
        input=rows_text(rows),
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    ).stdout.split("\n")[:-1]
    table = np.array([line.split() for line in out], float)
    assert table.shape == (N_ROWS, 3 + len(model.feature_names))
    np.testing.assert_array_equal(table[:, 3:], exp["features"])  # the features are the same bits
    np.testing.assert_array_equal(table[:, 2], exp["physics"])  # and so is a hybrid's physics estimate
    np.testing.assert_array_equal(table[:, 1].astype(bool), exp["inside"])
    assert exp["inside"][: model.training["n_runs"]].all()  # the training runs come first
    assert 50 < exp["inside"].sum() < N_ROWS - 50  # rows on both sides of the range check
    if physics_column(model) == FLEET:  # in range with a thermal k_z and without one
        thermal = thermal_rows(rows)
        assert (exp["inside"] & thermal).sum() > 20 and (exp["inside"] & ~thermal).sum() > 20
    rel, same = check_case(case_id, table[:, 0], exp)
    exact = np.abs(exp["exact"])
    C_RESULTS[case_id] = (
        rel,
        same,
        float(np.max(np.abs(exp["pred"] - exp["exact"]) / exact)),
        float(np.max(np.abs(exp["numpy"] - exp["exact"]) / exact)),
        float(np.max(exp["scale"] / exact)),
        float(exp["inside"].mean()),
    )


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_c_summary(c_driver):
    """Print the C measurements (pytest -s) for docs/export.md."""
    if not C_RESULTS:
        pytest.skip("the C cases did not run")
    groups = {
        "rbf": [v for k, v in C_RESULTS.items() if "-rbf" in k and "hybrid" not in k],
        "all target drift": [v for k, v in C_RESULTS.items() if "hybrid" not in k and k != DEFAULT_CASE],
        "hybrid": [v for k, v in C_RESULTS.items() if k.startswith("hybrid")],
        **{
            f"hybrid {p}": [v for k, v in C_RESULTS.items() if k.startswith("hybrid") and k.endswith(p)]
            for p in ("inversion", "curvefit", "smoother", "smoother_fleet")
        },
        "default fit": [C_RESULTS[DEFAULT_CASE]] if DEFAULT_CASE in C_RESULTS else [],
    }
    inside = [v[5] for v in C_RESULTS.values()]
    print(
        f"\nC: {len(C_RESULTS)} models, one build of all {c_driver[2]:.1f} s; rows in range "
        f"{min(inside):.0%} to {max(inside):.0%}, {np.mean(inside):.0%} on average"
    )
    for label, values in groups.items():
        if values:
            print(
                f"  {label} ({len(values)}): max |c - py| / |py| {max(v[0] for v in values):.3g}, rows with the "
                f"same bits {min(v[1] for v in values):.1%}; against the exact sum of the terms: py "
                f"{max(v[2] for v in values):.3g}, numpy kernel + BLAS {max(v[3] for v in values):.3g}; "
                f"condition S / |sum| up to {max(v[4] for v in values):.3g}"
            )
    print(f"  worst |c - py| / |py|: {max(C_RESULTS, key=lambda k: C_RESULTS[k][0])}")
    assert max(v[0] for v in C_RESULTS.values()) <= TOL


# --- Rust -------------------------------------------------------------------------------------------------

_CARGO_TOML = """[package]
name = "gyrodrift_export_check"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]

# The models are checked by tests/check.rs: no unit-test build of the library nor rustdoc run (it has no tests),
# no debug info, no incremental cache (half the build's CPU; the code and its arithmetic are the same).
[lib]
test = false
doctest = false

[profile.dev]
debug = false
incremental = false
"""

_RUST_RUNNER = """use gyrodrift_export_check as g;

/// Rows "u0 .. uN-1 python bound inside physics f...": checks one model, prints its worst relative error and
/// the number of rows with the same bits as Python's.
fn run(name: &str, data: &str, eval: &dyn Fn(&[f64]) -> (f64, bool, f64, Vec<f64>)) {
    let (mut rel, mut same, mut n) = (0.0_f64, 0usize, 0usize);
    for line in data.lines() {
        let v: Vec<f64> = line.split(' ').map(|t| t.parse::<f64>().unwrap()).collect();
        let (pred, inside, physics, features) = eval(&v[0..N_ALL]);
        let (python, bound) = (v[N_ALL], v[N_ALL + 1]);
        let err = (pred - python).abs();
        assert!(err <= bound, "{name}: row {n}: {pred:e} vs python {python:e}");
        assert_eq!(inside, v[N_ALL + 2] != 0.0, "{name}: row {n}: range check");
        assert_eq!(physics.to_bits(), v[N_ALL + 3].to_bits(), "{name}: row {n}: physics estimate");
        assert_eq!(features, v[N_ALL + 4..].to_vec(), "{name}: row {n}: features");
        rel = rel.max(err / python.abs());
        same += usize::from(pred.to_bits() == python.to_bits());
        n += 1;
    }
    assert!(n >= 1000);
    println!("RESULT {name} {rel:e} {same} {n}");
}
"""


@pytest.mark.skipif(CARGO is None, reason="no cargo on PATH")
def test_rust_export_reproduces_python(fitted, tmp_path_factory):
    project = tmp_path_factory.mktemp("rust_export")
    (project / "src").mkdir()
    (project / "tests").mkdir()
    (project / "data").mkdir()
    (project / "Cargo.toml").write_text(_CARGO_TOML)
    lib = ["#![no_std]", "// Every exported model, compiled without std."]
    tests = [_RUST_RUNNER.replace("N_ALL", str(len(ALL)))]
    names = {}
    for i, case_id in enumerate(ALL_CASES):
        model, rows, exp = fitted[case_id]
        module = f"m{i:03d}"
        names[module] = case_id
        text = export_case(case_id, model, "rust")["gyrodrift_model.rs"]
        (project / "src" / f"{module}.rs").write_text(text)
        lib.append(f"pub mod {module};")
        bound = TOL * np.abs(exp["pred"])
        lines = []
        for r, inputs in enumerate(rows_text(rows).splitlines()):
            values = [exp["pred"][r], bound[r], float(exp["inside"][r]), exp["physics"][r]]
            lines.append(" ".join([inputs, *(repr(float(v)) for v in [*values, *exp["features"][r]])]))
        (project / "data" / f"{module}.txt").write_text("\n".join(lines) + "\n")
        fields = ", ".join(f"{n}: u[{k}]" for k, n in enumerate(ALL) if f"pub {n}: f64" in text)
        math = ", ".join(f"{fn}: f64::{fn}" for fn in ("exp", "cos") if f"pub {fn}: fn(f64) -> f64" in text)
        physics = "m::physics_deg_h(&inputs, &math)" if model.target == "residual" else "0.0"
        tests.append(
            f"""
#[test]
fn {module}() {{
    use g::{module} as m;
    let math = m::Math {{ {math} }};
    run("{module}", include_str!("../data/{module}.txt"), &|u: &[f64]| {{
        let inputs = m::Inputs {{ {fields} }};
        (m::drift_deg_h(&inputs, &math), m::in_range(&inputs, &math), {physics}, m::features(&inputs, &math).to_vec())
    }});
}}
"""
        )
    (project / "src" / "lib.rs").write_text("\n".join(lib) + "\n")
    (project / "tests" / "check.rs").write_text("".join(tests))
    env = {**os.environ, "CARGO_TARGET_DIR": str(tmp_path_factory.getbasetemp() / "cargo-target")}
    start = time.perf_counter()
    build = subprocess.run(
        [CARGO, "test", "--offline", "--no-run", "--quiet"], cwd=project, env=env, capture_output=True, text=True
    )
    compile_s = time.perf_counter() - start
    assert build.returncode == 0, build.stderr[-4000:]
    assert "warning" not in build.stderr, build.stderr[-4000:]
    run = subprocess.run(
        [CARGO, "test", "--offline", "--quiet", "--", "--nocapture", "--test-threads=2"],
        cwd=project,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, (run.stdout + run.stderr)[-4000:]
    results = {}
    for module, rel, same, n in re.findall(r"RESULT (m\d+) (\S+) (\d+) (\d+)\n", run.stdout):
        results[names[module]] = (float(rel), int(same) / int(n))
    assert set(results) == set(ALL_CASES)
    groups = {
        "rbf": [v for k, v in results.items() if "-rbf" in k and "hybrid" not in k],
        "all target drift": [v for k, v in results.items() if "hybrid" not in k and k != DEFAULT_CASE],
        **{
            f"hybrid {p}": [v for k, v in results.items() if k.startswith("hybrid") and k.endswith(p)]
            for p in ("inversion", "curvefit", "smoother", "smoother_fleet")
        },
        "default fit": [results[DEFAULT_CASE]],
    }
    print(f"\nRust: {len(results)} models, cargo test build of all {compile_s:.1f} s")
    for label, values in groups.items():
        if values:
            print(
                f"  {label} ({len(values)}): max |rs - py| / |py| {max(v[0] for v in values):.3g}, "
                f"rows with the same bits {min(v[1] for v in values):.1%}"
            )
