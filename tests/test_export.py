"""`gyrodrift export`: the generated C and Rust reproduce `DriftModel.predict`, its features and the range check.

Every encoding x scaling is fitted (RBF, the kernel `fit` tunes) on the paper's runs and on a random synthetic
table with several sites; on the synthetic table the linear and polynomial kernels of the LSSVR are exported
too. Each model is evaluated on 1000 rows: the training runs, then random rows spanning 1.2 times the training
range of each raw input (so that some fall outside it).

Tolerance: ``|generated - python| <= 1e-12 * max(|python|, S)`` with ``S = sum_i |alpha_i K(x_i, x)| + |b|``,
the magnitude of the terms the kernel sum adds. Relative to ``|python|`` alone no float64 code can promise
1e-12 where the terms cancel (a drift crossing zero): numpy sums them with BLAS in another order, and the
rounding of either order is about ``eps * S``. The measured maxima are printed (``pytest -s``) and quoted in
docs/export.md.
"""

from __future__ import annotations

import itertools
import math
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import gyrodrift
from gyrodrift import export
from gyrodrift.choices import ENCODINGS, SCALINGS
from gyrodrift.cli import main
from gyrodrift.encodings import encode
from gyrodrift.errors import InputError, OptionError
from gyrodrift.kernels import kernel_matrix
from gyrodrift.lssvr import LSSVR
from gyrodrift.model import fit_drift_model
from gyrodrift.model_io import save_model
from gyrodrift.runs import RunTable

TOL = 1e-12
N_ROWS = 1000
RAW = ("lat_deg", "lat0_deg", "temp_min_c", "temp_max_c")
CC = shutil.which("cc")
CARGO = shutil.which("cargo")
CFLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2"]

# (gamma, sigma) per kernel and scaling: sigma in scaled input units, so wider for unscaled inputs.
_SIGMA = {
    "rbf": {"standard": 0.7, "minmax": 0.3, "none": 20.0},
    "linear": {"standard": 1.0, "minmax": 1.0, "none": 1.0},
    "poly": {"standard": 1.5, "minmax": 0.7, "none": 60.0},
}


def _synthetic_runs(rng: np.random.Generator, n: int = 24) -> RunTable:
    """Runs at three sites with a drift depending on the latitude error and the temperature [deg/h]."""
    lat0 = rng.choice([20.5, 34.1, 51.3], n)
    err = rng.uniform(-120.0, 120.0, n)
    tmin = rng.uniform(10.0, 50.0, n)
    tmax = tmin + rng.uniform(0.5, 8.0, n)
    drift = 0.01 * np.sin(err / 60.0) + 0.002 * (tmin + tmax - 60.0) / 40.0 + rng.normal(0.0, 3e-4, n)
    return RunTable(
        run=np.array([f"s{i}" for i in range(n)]),
        lat_deg=lat0 + err / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=drift,
        source="synthetic",
    )


def _probe_rows(train: RunTable, rng: np.random.Generator) -> RunTable:
    """The training runs, then random rows over 1.2 times the training range of each input and of the latitude
    error (N_ROWS in all)."""
    n = N_ROWS - len(train)
    cols = {}
    for name in RAW:
        v = getattr(train, name)
        lo, hi = float(v.min()), float(v.max())
        span = hi - lo or 0.5
        cols[name] = rng.uniform(lo - 0.1 * span, hi + 0.1 * span, n)
    on_site = rng.random(n) < 0.8  # mostly at a training site, so that the other inputs decide the range check
    cols["lat0_deg"][on_site] = rng.choice(train.lat0_deg, int(on_site.sum()))
    err = (train.lat_deg - train.lat0_deg) * 3600.0  # and so does the latitude error
    span = float(err.max() - err.min())
    cols["lat_deg"] = cols["lat0_deg"] + rng.uniform(err.min() - 0.1 * span, err.max() + 0.1 * span, n) / 3600.0
    cols["temp_max_c"] = np.maximum(cols["temp_max_c"], cols["temp_min_c"])
    return RunTable(
        run=np.array([f"p{i}" for i in range(N_ROWS)]),
        drift_deg_h=np.full(N_ROWS, np.nan),
        **{name: np.concatenate([getattr(train, name), cols[name]]) for name in RAW},
    )


def _model(train: RunTable, encoding: str, scaling: str, kernel: str):
    sigma = _SIGMA[kernel][scaling]
    model = fit_drift_model(train, encoding=encoding, scaling=scaling, gamma=100.0, sigma=sigma)
    if kernel != "rbf":  # `fit` tunes RBF only; the LSSVR has the other kernels, and the export supports them
        est = LSSVR(gamma=100.0, sigma=sigma, kernel=kernel, degree=3, coef0=1.0)
        model.named_steps["lssvr"].lssvr_ = est.fit(model[:-1].transform(train), train.drift_deg_h)
    return model


def _expected(model, train: RunTable, rows: RunTable) -> dict:
    """What the generated code must give, computed in Python independently of gyrodrift.export."""
    est = model.lssvr
    K = kernel_matrix(model[:-1].transform(rows), est.X_fit_, kernel=est.kernel, sigma=est.sigma, coef0=est.coef0)
    used = [n for n in RAW if any(n in export.FEATURE_EXPRESSIONS[f].inputs for f in model.feature_names)]
    inside = np.ones(len(rows), bool)
    for name in used:
        v, t = getattr(rows, name), getattr(train, name)
        inside &= (v >= t.min()) & (v <= t.max())
    feats, tfeats = encode(rows, model.encoding), encode(train, model.encoding)
    inside &= np.all((feats >= tfeats.min(axis=0)) & (feats <= tfeats.max(axis=0)), axis=1)
    pred = model.predict(rows)
    terms = K * est.alpha_
    return {
        "pred": pred,
        "exact": np.array([math.fsum([*t, est.intercept_]) for t in terms]),  # the terms summed exactly
        "scale": np.abs(K * est.alpha_).sum(axis=1) + abs(est.intercept_),
        "inside": inside,
        "features": feats,
    }


def _cases():
    rng = np.random.default_rng(20130613)
    paper = gyrodrift.load_paper().train
    synthetic = _synthetic_runs(rng)
    out = []
    for encoding, scaling in itertools.product(ENCODINGS, SCALINGS):
        out.append(("paper", paper, encoding, scaling, "rbf"))
    for encoding, scaling, kernel in itertools.product(ENCODINGS, SCALINGS, ("rbf", "linear", "poly")):
        out.append(("synthetic", synthetic, encoding, scaling, kernel))
    return out


CASES = _cases()
CASE_IDS = [f"{d}-{e}-{s}-{k}" for d, _, e, s, k in CASES]

COS_SUFFIX = "+cos"
"""A case exported with the latitude error written as ``(lat - lat0) * 3600 * cos(0 * lat0)`` (the same bits):
the path a feature needing a math function (say, a physics-normalised encoding with cos(lat0)) will take."""
COS_CASE = CASE_IDS[0] + COS_SUFFIX
_COS_EXPRESSION = export.FeatureExpression(
    ("lat_deg", "lat0_deg"),
    "({lat_deg} - {lat0_deg}) * 3600.0 * {cos}(0.0 * {lat0_deg})",
    "({lat_deg} - {lat0_deg}) * 3600.0 * {cos}(0.0 * {lat0_deg})",
    "arcsec",
    ("cos",),
)


def _export(case_id: str, model, lang: str) -> dict[str, str]:
    """The generated files of a case (the cos case with its patched feature expression)."""
    with pytest.MonkeyPatch.context() as patch:
        if case_id.endswith(COS_SUFFIX):
            patch.setitem(export.FEATURE_EXPRESSIONS, "lat_err_arcsec", _COS_EXPRESSION)
        return export.export_model(model, lang)


@pytest.fixture(scope="module")
def fitted():
    """Case id -> (model, rows, expected), built once for the C and the Rust tests."""
    rng = np.random.default_rng(7)
    out = {}
    for case_id, (_, train, encoding, scaling, kernel) in zip(CASE_IDS, CASES, strict=True):
        model = _model(train, encoding, scaling, kernel)
        rows = _probe_rows(train, rng)
        out[case_id] = (model, rows, _expected(model, train, rows))
    out[COS_CASE] = out[CASE_IDS[0]]
    return out


def _rows_text(rows: RunTable) -> str:
    return "".join(" ".join(repr(float(getattr(rows, n)[i])) for n in RAW) + "\n" for i in range(len(rows)))


def _check(case_id: str, got: np.ndarray, exp: dict) -> tuple[float, float]:
    """Assert the tolerance; return (max error relative to |python|, max error relative to S)."""
    err = np.abs(got - exp["pred"])
    bound = TOL * np.maximum(np.abs(exp["pred"]), exp["scale"])
    worst = int(np.argmax(err / bound))
    assert np.all(err <= bound), f"{case_id}: row {worst}: {got[worst]!r} vs python {exp['pred'][worst]!r}"
    return float(np.max(err / np.abs(exp["pred"]))), float(np.max(err / exp["scale"]))


# --- every feature can be exported ------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", list(ENCODINGS))
def test_every_feature_of_every_encoding_has_a_c_and_a_rust_expression(encoding):
    for name in ENCODINGS[encoding]:
        assert name in export.FEATURE_EXPRESSIONS, f"encoding {encoding}: add {name} to FEATURE_EXPRESSIONS"
        expr = export.FEATURE_EXPRESSIONS[name]
        assert set(expr.inputs) <= set(export.RAW_INPUTS)
        for template in (expr.c, expr.rust):
            declared = {n: f"<{n}>" for n in (*expr.inputs, *expr.functions)}
            text = template.format(**declared)  # a KeyError here: the template reads an undeclared input
            assert all(f"<{n}>" in text for n in expr.inputs)


def test_a_feature_without_expression_cannot_be_exported(monkeypatch):
    model = _model(gyrodrift.load_paper().train, "temp_mean", "standard", "rbf")
    monkeypatch.delitem(export.FEATURE_EXPRESSIONS, "temp_mean_c")
    with pytest.raises(InputError, match="temp_mean_c has no C/Rust expression"):
        export.export_model(model, "c")


def test_literals_round_trip_and_are_floats_in_c_and_rust():
    for x in (0.0, -0.0, 1.0, -3.0, 1e300, -2.5e-310, 0.1, 28.222, 2.0**60, np.nextafter(1.0, 2.0)):
        text = export._lit(x)
        assert float(text) == x and np.signbit(float(text)) == np.signbit(x)
        assert "." in text or "e" in text


def test_unknown_language_is_an_option_error():
    with pytest.raises(OptionError, match="--lang"):
        export.output_names("fortran")


def test_export_is_deterministic_and_carries_provenance(fitted):
    model, _, _ = fitted[CASE_IDS[0]]
    first, second = export.export_model(model, "c", model_sha256="ab" * 32), export.export_model(model, "c")
    assert (
        first["gyrodrift_model.c"].replace(f" * Model file SHA-256: {'ab' * 32}\n", "") == second["gyrodrift_model.c"]
    )
    header = first["gyrodrift_model.h"]
    rust = export.export_model(model, "rust")["gyrodrift_model.rs"]
    for text in (header, rust):
        assert model.training["sha256"] in text and f"gyrodrift {gyrodrift.__version__}" in text
        assert f"gamma = {export._lit(model.lssvr.gamma)}" in text
    lo = float(model.training_["runs"].temp_min_c.min())
    assert f"temp_min_c: [{export._lit(lo)}," in header


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_provenance_text_cannot_break_the_generated_code(tmp_path):
    paper = gyrodrift.load_paper().train
    hostile = 'runs */ #error "x" ??/\n#error "y" \u00e9.csv'
    train = RunTable(**{**{f: getattr(paper, f) for f in (*RAW, "run", "drift_deg_h")}, "source": hostile})
    model = fit_drift_model(train, encoding="lat_only", scaling="standard", gamma=100.0, sigma=0.7)
    assert model.training["source"] == hostile
    files = export.export_model(model, "c")
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    subprocess.run([CC, *CFLAGS, "-c", "gyrodrift_model.c"], cwd=tmp_path, check=True, timeout=120)
    rust = export.export_model(model, "rust")["gyrodrift_model.rs"]
    line = next(ln for ln in rust.splitlines() if ln.startswith("//! Training runs:"))
    assert line.endswith('#error \\"y\\" \\u00e9.csv')  # one comment line, escaped


# --- C ------------------------------------------------------------------------------------------------------

_C_DRIVER = """#include <stdio.h>
#include <stdlib.h>
#include "gyrodrift_model.h"

int main(void)
{
    char text[4][64];
    double u[4], f[GYRODRIFT_MODEL_N_FEATURES];
    int k;
    while (scanf("%63s %63s %63s %63s", text[0], text[1], text[2], text[3]) == 4) {
        gyrodrift_model_inputs in;
        for (k = 0; k < 4; ++k) {
            u[k] = strtod(text[k], NULL);
        }
FILL
        gyrodrift_model_features(&in, f);
        printf("%.17g %d", gyrodrift_model_drift_deg_h(&in), gyrodrift_model_in_range(&in));
        for (k = 0; k < GYRODRIFT_MODEL_N_FEATURES; ++k) {
            printf(" %.17g", f[k]);
        }
        printf("\\n");
    }
    return 0;
}
"""

C_RESULTS: dict[str, tuple[float, ...]] = {}
"""Case id -> (max |c - py| / |py|, max |c - py| / S, compile + link [s], max |c - exact| / |exact|,
max |py - exact| / |exact|, max |c - py| / |py| where |py| >= S / 10), printed by test_c_summary."""


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
@pytest.mark.parametrize("case_id", [*CASE_IDS, COS_CASE])
def test_c_export_reproduces_python(case_id, fitted, tmp_path):
    model, rows, exp = fitted[case_id]
    files = _export(case_id, model, "c")
    needs_math = any(export.FEATURE_EXPRESSIONS[f].functions for f in model.feature_names)
    assert ("#include <math.h>" in files["gyrodrift_model.c"]) == (
        model.lssvr.kernel == "rbf" or case_id == COS_CASE or needs_math
    )
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    fill = "\n".join(
        f"        in.{n} = u[{k}];" for k, n in enumerate(RAW) if f"double {n};" in files["gyrodrift_model.h"]
    )
    (tmp_path / "driver.c").write_text(_C_DRIVER.replace("FILL", fill))
    start = time.perf_counter()
    subprocess.run(
        [CC, *CFLAGS, "driver.c", "gyrodrift_model.c", "-lm", "-o", "driver"], cwd=tmp_path, check=True, timeout=120
    )
    compile_s = time.perf_counter() - start
    out = subprocess.run(
        [str(tmp_path / "driver")], input=_rows_text(rows), capture_output=True, text=True, check=True, timeout=60
    ).stdout.split("\n")[:-1]
    table = np.array([line.split() for line in out], float)
    assert table.shape == (N_ROWS, 2 + len(model.feature_names))
    np.testing.assert_array_equal(table[:, 2:], exp["features"])  # the features are the same bits
    np.testing.assert_array_equal(table[:, 1].astype(bool), exp["inside"])
    assert exp["inside"][: model.training["n_runs"]].all()  # the training runs come first
    assert 50 < exp["inside"].sum() < N_ROWS - 50  # rows on both sides of the range check
    rel, rel_s = _check(case_id, table[:, 0], exp)
    # against the exactly summed terms, the generated order does as well as numpy's
    c_exact = np.abs(table[:, 0] - exp["exact"])
    assert np.all(c_exact <= TOL * np.maximum(np.abs(exp["exact"]), exp["scale"]))
    np_exact = float(np.max(np.abs(exp["pred"] - exp["exact"]) / np.abs(exp["exact"])))
    large = np.abs(exp["pred"]) >= 0.1 * exp["scale"]  # rows whose terms do not cancel much
    rel_large = float(np.max(np.abs(table[large, 0] - exp["pred"][large]) / np.abs(exp["pred"][large]), initial=0.0))
    C_RESULTS[case_id] = (rel, rel_s, compile_s, float(np.max(c_exact / np.abs(exp["exact"]))), np_exact, rel_large)


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_c_summary():
    """Print the C measurements (pytest -s) for docs/export.md."""
    if not C_RESULTS:
        pytest.skip("the C cases did not run")
    rbf = [v for k, v in C_RESULTS.items() if k.endswith("-rbf")]
    every = list(C_RESULTS.values())

    def top(values, i):
        return max(v[i] for v in values)

    print(
        f"\nC: {len(every)} models; max |c - py| / |py|: rbf {top(rbf, 0):.3g}, all {top(every, 0):.3g} "
        f"({max(C_RESULTS, key=lambda k: C_RESULTS[k][0])}); max |c - py| / S: {top(every, 1):.3g}; "
        f"compile+link per model {np.median([v[2] for v in every]):.2f} s (median), {top(every, 2):.2f} s (max); "
        f"against the exactly summed terms, rbf: c {top(rbf, 3):.3g}, numpy {top(rbf, 4):.3g}; all: c "
        f"{top(every, 3):.3g}, numpy {top(every, 4):.3g}; max |c - py| / |py| where |py| >= S/10: {top(every, 5):.3g}"
    )
    assert max(v[1] for v in C_RESULTS.values()) < TOL


# --- Rust -------------------------------------------------------------------------------------------------

_CARGO_TOML = """[package]
name = "gyrodrift_export_check"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
"""

_RUST_RUNNER = """use gyrodrift_export_check as g;

/// Rows "u0 u1 u2 u3 python bound inside f...": checks one model, prints its worst relative errors.
fn run(name: &str, data: &str, eval: &dyn Fn(&[f64]) -> (f64, bool, Vec<f64>)) {
    let (mut rel, mut rel_s, mut n) = (0.0_f64, 0.0_f64, 0usize);
    for line in data.lines() {
        let v: Vec<f64> = line.split(' ').map(|t| t.parse::<f64>().unwrap()).collect();
        let (pred, inside, features) = eval(&v[0..4]);
        let (python, bound, scale) = (v[4], v[5], v[6]);
        let err = (pred - python).abs();
        assert!(err <= bound, "{name}: row {n}: {pred:e} vs python {python:e}");
        assert_eq!(inside, v[7] != 0.0, "{name}: row {n}: range check");
        assert_eq!(features, v[8..].to_vec(), "{name}: row {n}: features");
        rel = rel.max(err / python.abs());
        rel_s = rel_s.max(err / scale);
        n += 1;
    }
    assert!(n >= 1000);
    println!("RESULT {name} {rel:e} {rel_s:e}");
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
    tests = [_RUST_RUNNER]
    names = {}
    for i, case_id in enumerate([*CASE_IDS, COS_CASE]):
        model, rows, exp = fitted[case_id]
        module = f"m{i:02d}"
        names[module] = case_id
        text = _export(case_id, model, "rust")["gyrodrift_model.rs"]
        (project / "src" / f"{module}.rs").write_text(text)
        lib.append(f"pub mod {module};")
        bound = TOL * np.maximum(np.abs(exp["pred"]), exp["scale"])
        lines = []
        for r in range(N_ROWS):
            values = [getattr(rows, n)[r] for n in RAW]
            values += [exp["pred"][r], bound[r], exp["scale"][r], float(exp["inside"][r]), *exp["features"][r]]
            lines.append(" ".join(repr(float(v)) for v in values))
        (project / "data" / f"{module}.txt").write_text("\n".join(lines) + "\n")
        fields = ", ".join(f"{n}: u[{k}]" for k, n in enumerate(RAW) if f"pub {n}: f64" in text)
        math = ", ".join(f"{fn}: f64::{fn}" for fn in ("exp", "cos") if f"pub {fn}: fn(f64) -> f64" in text)
        tests.append(
            f"""
#[test]
fn {module}() {{
    use g::{module} as m;
    let math = m::Math {{ {math} }};
    run("{module}", include_str!("../data/{module}.txt"), &|u: &[f64]| {{
        let inputs = m::Inputs {{ {fields} }};
        (m::drift_deg_h(&inputs, &math), m::in_range(&inputs, &math), m::features(&inputs, &math).to_vec())
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
    for module, rel, rel_s in re.findall(r"RESULT (m\d+) (\S+) (\S+)\n", run.stdout):
        results[names[module]] = (float(rel), float(rel_s))
    assert set(results) == {*CASE_IDS, COS_CASE}
    rbf = [v for k, v in results.items() if k.endswith("-rbf")]
    print(
        f"\nRust: {len(results)} models; max |rs - py| / |py|: rbf {max(v[0] for v in rbf):.3g}, all "
        f"{max(v[0] for v in results.values()):.3g}; max |rs - py| / S: {max(v[1] for v in results.values()):.3g}; "
        f"cargo test build of all {len(results)} modules {compile_s:.1f} s"
    )


# --- the command --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def model_file(tmp_path_factory, fitted):
    path = tmp_path_factory.mktemp("model") / "model.json"
    save_model(fitted[CASE_IDS[0]][0], path)
    return path


def test_cli_writes_c_and_rust_into_one_folder(model_file, tmp_path):
    out = tmp_path / "nav"
    for lang in ("c", "rust"):
        r = CliRunner().invoke(main, ["export", "--model", str(model_file), "--lang", lang, "--out", str(out)])
        assert r.exit_code == 0, r.output
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["gyrodrift_model.c", "gyrodrift_model.h", "gyrodrift_model.rs"]
    import hashlib

    digest = hashlib.sha256(model_file.read_bytes()).hexdigest()
    before = {n: (out / n).read_bytes() for n in names}
    assert all(digest.encode() in b for b in before.values())
    r = CliRunner().invoke(main, ["export", "--model", str(model_file), "--lang", "c", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert {n: (out / n).read_bytes() for n in names} == before  # same model, same bytes; Rust file kept


@pytest.mark.parametrize("problem", ["corrupted model", "unknown lang", "out is a file", "out holds a user's file"])
def test_cli_bad_inputs_are_one_line_errors(problem, model_file, tmp_path):
    model, lang, out = str(model_file), "c", tmp_path / "out"
    expected = "out"
    if problem == "corrupted model":
        bad = tmp_path / "bad.json"
        bad.write_text(model_file.read_text()[:200])
        model, expected = str(bad), "bad.json: corrupted JSON"
    elif problem == "unknown lang":
        lang, expected = "fortran", "--lang: unknown language 'fortran'"
    elif problem == "out is a file":
        out.write_text("mine")
        expected = "is a file, not a folder"
    else:
        out.mkdir()
        (out / "notes.txt").write_text("mine")
        expected = "notes.txt"
    r = CliRunner().invoke(main, ["export", "--model", model, "--lang", lang, "--out", str(out)])
    assert r.exit_code == 1, r.output
    assert r.output.count("\n") == 1 and r.output.startswith("Error: ") and expected in r.output, r.output
    assert "Traceback" not in r.output
    assert not list(Path(tmp_path).glob("out/gyrodrift_model*"))
