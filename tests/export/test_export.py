"""`gyrodrift export`: the export spec (every feature and physics column has a C and a Rust expression, a
hybrid's inputs, label weights, bad models), literals, provenance, determinism, and the command; the generated
code compiled and compared with Python is test_export_compiled.py, the models tests/export/export_cases.py.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from export_cases import (
    CC,
    CFLAGS,
    DEFAULT_CASE,
    FLEET,
    KZ,
    PHYSICS_INPUTS_READ,
    RAW,
    export_case,
    fit_case,
    hybrid_runs,
    thermal_rows,
)

import gyrodrift
from gyrodrift.choices import ENCODINGS, PHYSICS_COLUMNS, default_encoding
from gyrodrift.cli import main
from gyrodrift.errors import InputError, OptionError
from gyrodrift.export.languages import export_model, output_names
from gyrodrift.export.literals import literal
from gyrodrift.export.spec import (
    FEATURE_EXPRESSIONS,
    INPUTS,
    PHYSICS_EXPRESSIONS,
    PHYSICS_INPUTS,
    RAW_INPUTS,
    export_spec,
)
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.model_io import load_model, save_model
from gyrodrift.learn.physics_base import physics_estimate
from gyrodrift.runs.table import RunTable

# --- every feature can be exported ------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", list(ENCODINGS))
def test_every_feature_of_every_encoding_has_a_c_and_a_rust_expression(encoding):
    for name in ENCODINGS[encoding]:
        assert name in FEATURE_EXPRESSIONS, f"encoding {encoding}: add {name} to FEATURE_EXPRESSIONS"
        expr = FEATURE_EXPRESSIONS[name]
        assert set(expr.inputs) <= set(RAW_INPUTS)
        for template in (expr.c, expr.rust):
            declared = {n: f"<{n}>" for n in (*expr.inputs, *expr.functions)}
            text = template.format(**declared)  # a KeyError here: the template reads an undeclared input
            assert all(f"<{n}>" in text for n in expr.inputs)


@pytest.mark.parametrize("physics", PHYSICS_COLUMNS)
def test_every_physics_column_has_a_c_and_a_rust_expression(physics):
    expr = PHYSICS_EXPRESSIONS[physics]
    assert set(expr.inputs) <= set(INPUTS) and expr.unit == "deg/h"
    if physics == "drift_inversion_deg_h":  # computed from the latitudes, as the physics feature is
        assert expr == dataclasses.replace(FEATURE_EXPRESSIONS["drift_equiv_deg_h"], unit="deg/h")
    elif physics == FLEET:  # computed from the smoother's end drift and k_z, which the navigation computer passes
        assert expr.inputs == ("drift_smoother_deg_h", *KZ) and set(expr.inputs) <= set(PHYSICS_INPUTS)
    else:  # the navigation computer computes it: an input, read as it is
        assert expr.inputs == (physics,) and physics in PHYSICS_INPUTS and "deg/h" in INPUTS[physics]


@pytest.mark.parametrize(
    ("physics", "encoding", "fields", "functions"),
    [
        ("drift_inversion_deg_h", "physics", RAW, ("cos", "exp")),
        ("drift_inversion_deg_h", "temperature", RAW, ("cos", "exp")),  # the latitudes for the physics alone
        ("drift_curvefit_deg_h", "temperature", ("temp_min_c", "temp_max_c", "drift_curvefit_deg_h"), ("exp",)),
        ("drift_smoother_deg_h", "lat_only", ("lat_deg", "lat0_deg", "drift_smoother_deg_h"), ("exp",)),
        (FLEET, "temperature", ("temp_min_c", "temp_max_c", "drift_smoother_deg_h", *KZ), ("exp",)),
    ],
)
def test_a_hybrid_reads_its_physics_inputs_and_checks_their_range(physics, encoding, fields, functions):
    model = fit_case(hybrid_runs(np.random.default_rng(5)), encoding, "standard", "rbf", physics)
    spec = export_spec(model)
    assert spec.inputs == fields and spec.functions == functions and spec.physics == physics
    header = export_model(model, "c")["gyrodrift_model.h"]
    rust = export_model(model, "rust")["gyrodrift_model.rs"]
    assert re.findall(r"    double (\w+); /\*", header) == list(fields)
    assert re.findall(r"    pub (\w+): f64,", rust.split("pub struct Inputs")[1].split("}")[0]) == list(fields)
    assert "double gyrodrift_model_physics_deg_h(const gyrodrift_model_inputs *inputs);" in header
    assert (
        f'#define GYRODRIFT_MODEL_PHYSICS "{physics}"' in header and f'pub const PHYSICS: &str = "{physics}";' in rust
    )
    assert re.search(r"pub fn physics_deg_h\(inputs: &Inputs, _?math: &Math\) -> f64", rust)
    assert "pub fn correction_deg_h(inputs: &Inputs, math: &Math) -> f64" in rust
    runs = model.training_["runs"]
    for name in fields[-len(PHYSICS_INPUTS_READ[physics]) :] if PHYSICS_INPUTS_READ[physics] else ():
        train = runs.column(name)  # the extra inputs' training ranges are in the range check
        train = train[thermal_rows(runs)] if name in KZ else train  # k_z: over the runs with one
        lo, hi = literal(train.min()), literal(train.max())
        assert f'{{"{name}", {lo}, {hi}}}' in export_model(model, "c")["gyrodrift_model.c"]
        assert f'Range {{ name: "{name}", min: {lo}, max: {hi} }}' in rust
        assert f"{name}: [{lo}, {hi}]" in header  # provenance
    if physics == FLEET:  # the fleet prior: constants
        mean, std = (literal(v) for v in model.coefficient_prior_)
        assert f"#define GYRODRIFT_MODEL_COEFF_PRIOR_MEAN_DEG_H_PER_C {mean}" in header
        assert f"pub const COEFF_PRIOR_STD_DEG_H_PER_C: f64 = {std};" in rust


def test_label_weights_change_the_model_but_need_nothing_at_prediction(default_model):
    weighted = default_model
    assert weighted.training["weighted"]
    runs = weighted.training_["runs"]
    est = weighted.lssvr
    encoding = default_encoding("residual")
    plain = fit_drift_model(runs, encoding=encoding, target="residual", gamma=est.gamma, sigma=est.sigma)
    unweighted = fit_drift_model(
        runs, encoding=encoding, target="residual", gamma=est.gamma, sigma=est.sigma, label_weighting="none"
    )
    np.testing.assert_array_equal(plain.lssvr.alpha_, est.alpha_)  # the same fit as the command's
    assert np.max(np.abs(unweighted.lssvr.alpha_ - est.alpha_)) > 1e-3 * np.max(np.abs(est.alpha_))  # weights matter
    files = [
        *export_case(DEFAULT_CASE, weighted, "c").values(),
        export_case(DEFAULT_CASE, weighted, "rust")["gyrodrift_model.rs"],
    ]
    assert all("drift_std" not in re.sub(r"Label weighting[^\n]*", "", text) for text in files)
    raw = tuple(n for n in RAW if any(n in FEATURE_EXPRESSIONS[f].inputs for f in ENCODINGS[encoding]))
    fleet_fields = (*raw, "drift_smoother_deg_h", *KZ)  # the encoding's, then the fleet-prior smoother's
    assert export_spec(unweighted).inputs == export_spec(weighted).inputs == fleet_fields


def test_a_feature_without_expression_cannot_be_exported(monkeypatch):
    model = fit_case(gyrodrift.load_paper().train, "temp_mean", "standard", "rbf")
    monkeypatch.delitem(FEATURE_EXPRESSIONS, "temp_mean_c")
    with pytest.raises(InputError, match="temp_mean_c has no C/Rust expression"):
        export_model(model, "c")


def test_literals_round_trip_and_are_floats_in_c_and_rust():
    for x in (0.0, -0.0, 1.0, -3.0, 1e300, -2.5e-310, 0.1, 28.222, 2.0**60, np.nextafter(1.0, 2.0)):
        text = literal(x)
        assert float(text) == x and np.signbit(float(text)) == np.signbit(x)
        assert "." in text or "e" in text


def test_unknown_language_is_an_option_error():
    with pytest.raises(OptionError, match="--lang"):
        output_names("fortran")


def test_export_is_deterministic_and_carries_provenance(first_model):
    model = first_model
    first, second = export_model(model, "c", model_sha256="ab" * 32), export_model(model, "c")
    assert (
        first["gyrodrift_model.c"].replace(f" * Model file SHA-256: {'ab' * 32}\n", "") == second["gyrodrift_model.c"]
    )
    header = first["gyrodrift_model.h"]
    rust = export_model(model, "rust")["gyrodrift_model.rs"]
    for text in (header, rust):
        assert model.training["sha256"] in text and f"gyrodrift {gyrodrift.__version__}" in text
        assert f"gamma = {literal(model.lssvr.gamma)}" in text
    lo = float(model.training_["runs"].temp_min_c.min())
    assert f"temp_min_c: [{literal(lo)}," in header


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_provenance_text_cannot_break_the_generated_code(tmp_path):
    paper = gyrodrift.load_paper().train
    hostile = 'runs */ #error "x" ??/\n#error "y" \u00e9.csv'
    train = RunTable(**{**{f: getattr(paper, f) for f in (*RAW, "run", "drift_deg_h")}, "source": hostile})
    model = fit_drift_model(train, encoding="lat_only", scaling="standard", gamma=100.0, sigma=0.7)
    assert model.training["source"] == hostile
    files = export_model(model, "c")
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    subprocess.run([CC, *CFLAGS, "-c", "gyrodrift_model.c"], cwd=tmp_path, check=True, timeout=120)
    rust = export_model(model, "rust")["gyrodrift_model.rs"]
    line = next(ln for ln in rust.splitlines() if ln.startswith("//! Training runs:"))
    assert line.endswith('#error \\"y\\" \\u00e9.csv')  # one comment line, escaped


def test_a_hybrids_physics_estimate_is_a_term_of_the_sum_also_with_metadata_routing():
    import sklearn

    paper = gyrodrift.load_paper()
    model = fit_drift_model(paper.train, encoding="physics", target="residual", gamma=100.0, sigma=0.7)
    X = model.learner_[:-1].transform(paper.test)
    physics = physics_estimate(paper.test, "drift_inversion_deg_h")
    pred = model.predict(paper.test)
    np.testing.assert_array_equal(pred, model.lssvr.predict(X, offset=physics))
    with sklearn.config_context(enable_metadata_routing=True):  # the offset is not routed through the Pipeline
        np.testing.assert_array_equal(model.predict(paper.test), pred)
    with pytest.raises(ValueError, match="one value per sample"):
        model.lssvr.predict(X, offset=physics[:-1])


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_the_c_source_refuses_x87_extended_precision(tmp_path):
    """Double rounding in 80-bit registers would break the compensated sum's exact error terms: no silent build."""
    model = fit_case(gyrodrift.load_paper().train, "lat_only", "standard", "rbf")
    for name, text in export_model(model, "c").items():
        (tmp_path / name).write_text(text)
    x87 = subprocess.run(
        [CC, *CFLAGS, "-m32", "-mfpmath=387", "-fsyntax-only", "gyrodrift_model.c"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    if "unrecognized" in x87.stderr or "not supported" in x87.stderr:
        pytest.skip(f"{CC} cannot target x87: {x87.stderr[:200]}")
    assert x87.returncode != 0 and "x87 extended precision" in x87.stderr, x87.stderr
    sse = subprocess.run([CC, *CFLAGS, "-fsyntax-only", "gyrodrift_model.c"], cwd=tmp_path, capture_output=True)
    assert sse.returncode == 0, sse.stderr


# --- the command --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def model_file(tmp_path_factory, first_model):
    path = tmp_path_factory.mktemp("model") / "model.json"
    save_model(first_model, path)
    return path


def test_cli_exports_the_default_fit_model_as_a_hybrid(default_fit_file, tmp_path):
    r = CliRunner().invoke(main, ["export", "--model", str(default_fit_file), "--lang", "c", "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    assert f"hybrid on {FLEET}" in r.output
    args = ["export", "--model", str(default_fit_file), "--lang", "rust", "--out", str(tmp_path), "--json"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)  # one JSON document; the "wrote" line goes to stderr
    assert (doc["encoding"], doc["target"], doc["physics_column"]) == (default_encoding("residual"), "residual", FLEET)
    assert doc["coefficient_prior_deg_h_per_c"] == list(load_model(default_fit_file).coefficient_prior_)


def test_cli_writes_c_and_rust_into_one_folder(model_file, tmp_path):
    out = tmp_path / "nav"
    for lang in ("c", "rust"):
        r = CliRunner().invoke(main, ["export", "--model", str(model_file), "--lang", lang, "--out", str(out)])
        assert r.exit_code == 0, r.output
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["gyrodrift_model.c", "gyrodrift_model.h", "gyrodrift_model.rs"]

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
