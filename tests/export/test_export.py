# Over 800 lines: the C, Rust, spec and CLI checks share the 114 fitted cases (fixture `fitted`) and their reference.
"""`gyrodrift export`: the generated C and Rust reproduce `DriftModel.predict`, its features and the range check.

Every encoding x scaling is fitted (RBF, the kernel `fit` tunes) on the paper's runs and on a random synthetic
table with several sites; on the synthetic table the linear and polynomial kernels of the LSSVR are exported
too. Hybrid models (``target="residual"``: physics estimate + learned correction) are fitted for every physics
column x encoding on a synthetic table carrying the curve-fit and smoother columns (the smoother's k_z on all
but 5 runs, its constant model) and label 1-sigmas (so the fits are weighted, and one run is left out), and the
default ``gyrodrift fit`` model (a hybrid on the fleet-prior smoother) goes through the commands (fit, then
export). Each model is evaluated on 1000 rows: the training runs, then random rows spanning 1.2 times the
training range of each input (so that some fall outside it; a third without k_z). The C of every model is built in one
compiler run (each model's source wrapped in its own translation unit), the Rust in one crate.

Tolerance: ``|generated - python| <= 1e-12 * |python|`` on every row, the drifts near zero included. Python's
prediction (`gyrodrift.learn.lssvr`, "prediction arithmetic") and the generated code do the same IEEE operations in the
same order, the kernel's exp from the same C library and the sum compensated, so they agree to the last bit
here (counted). The compensated sum is checked too: Python's prediction is within 1 ulp of its terms summed
exactly (`math.fsum`, the terms recomputed here from the documented operations), however much they cancel
(condition ``S / |sum|`` with ``S = sum_i |alpha_i K_i| + |b|`` (+ ``|physics|``) printed). The measured maxima
are printed (``pytest -s``) and quoted in docs/export.md.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
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
from gyrodrift.choices import ENCODINGS, PHYSICS_COLUMNS, SCALINGS, default_encoding
from gyrodrift.cli import main
from gyrodrift.errors import InputError, OptionError
from gyrodrift.export.languages import LANGUAGES, export_model, output_names
from gyrodrift.export.render import literal
from gyrodrift.export.spec import (
    COEFFICIENT_INPUTS,
    FEATURE_EXPRESSIONS,
    INPUTS,
    PHYSICS_EXPRESSIONS,
    PHYSICS_INPUTS,
    RAW_INPUTS,
    FeatureExpression,
    export_spec,
    physics_column,
)
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.encodings import encode
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior
from gyrodrift.learn.kernels import kernel_matrix
from gyrodrift.learn.lssvr import LSSVR
from gyrodrift.learn.model_io import load_model, save_model
from gyrodrift.learn.physics_base import FLEET_PHYSICS, physics_estimate
from gyrodrift.runs.table import RunTable

TOL = 1e-12
N_ROWS = 1000
RAW = ("lat_deg", "lat0_deg", "temp_min_c", "temp_max_c")
ALL = tuple(INPUTS)  # the raw inputs, then the physics columns the navigation computer computes
FLEET = FLEET_PHYSICS
KZ = COEFFICIENT_INPUTS
PHYSICS_INPUTS_READ = {
    "drift_inversion_deg_h": (),
    "drift_curvefit_deg_h": ("drift_curvefit_deg_h",),
    "drift_smoother_deg_h": ("drift_smoother_deg_h",),
    FLEET: ("drift_smoother_deg_h", *KZ),
}
"""The inputs of each physics estimate that the navigation computer passes (the last fields of the struct)."""
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


def _hybrid_runs(rng: np.random.Generator) -> RunTable:
    """The synthetic runs with the curve-fit and smoother columns (the drift plus noise [deg/h]), the smoother's
    k_z estimate (NaN on 5 runs: its constant model) and label 1-sigmas (one beyond `gyrodrift fit`'s default
    limit of 1e-3 deg/h, so that run is left out)."""
    runs = _synthetic_runs(rng)
    n = len(runs)
    std = rng.uniform(5e-5, 4e-4, n)
    std[3] = 2e-3
    d_std, k_std = rng.uniform(5e-5, 2e-4, n), rng.uniform(5e-5, 3e-4, n)
    constant = np.isin(np.arange(n), rng.choice(n, 5, replace=False))
    kz = {
        "smoother_coeff_deg_h_per_c": rng.normal(2e-4, 4e-5, n) + rng.normal(0.0, k_std),
        "smoother_coeff_std_deg_h_per_c": k_std,
        "smoother_end_coeff_cov": rng.uniform(-0.9, 0.9, n) * d_std * k_std,
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e-2),
    }
    extra = {
        "drift_std_deg_h": std,
        "drift_curvefit_deg_h": runs.drift_deg_h + rng.normal(0.0, 4e-4, n),
        "drift_smoother_deg_h": runs.drift_deg_h + rng.normal(0.0, d_std),
        "drift_smoother_std_deg_h": d_std,
        **{name: np.where(constant, np.nan, v) for name, v in kz.items()},
    }
    return runs.replace(extra=extra, source="synthetic-hybrid")


def _thermal(runs: RunTable) -> np.ndarray:
    """Rows with the smoother's thermal k_z (the test of `drift_with_coefficient_prior`; the others: NaN)."""
    k, sk, c, s0 = (runs.column(name) for name in COEFFICIENT_INPUTS)
    return np.isfinite(k) & np.isfinite(sk * sk) & (sk * sk > 0) & np.isfinite(c) & np.isfinite(s0) & (s0 > 0)


def _physics(model, rows: RunTable) -> np.ndarray:
    """A hybrid's physics estimate of each row [deg/h]: `physics_estimate`, or for the fleet-prior smoother
    `drift_with_coefficient_prior` with the model's fleet prior."""
    column = physics_column(model)
    if column != FLEET_PHYSICS:
        return physics_estimate(rows, column)
    names = ("drift_smoother_deg_h", "drift_smoother_std_deg_h", *COEFFICIENT_INPUTS)
    return drift_with_coefficient_prior(*(rows.column(n) for n in names), *model.coefficient_prior_)[0]


def _value(runs: RunTable, name: str) -> np.ndarray:
    """Input ``name`` (`INPUTS`) of each run: a column, or a physics column (NaN where absent)."""
    return getattr(runs, name) if name in RAW else runs.column(name)


def _probe_rows(train: RunTable, rng: np.random.Generator) -> RunTable:
    """The training runs, then random rows over 1.2 times the training range of each input and of the latitude
    error (N_ROWS in all); the physics columns the training runs have too."""
    n = N_ROWS - len(train)
    cols = {}
    # and the smoother's 1-sigma: Python's fleet base wants it (its drift does not depend on it; not exported)
    physics = [*PHYSICS_INPUTS, "drift_smoother_std_deg_h"]
    for name in [*RAW, *(c for c in physics if np.isfinite(train.column(c)).any())]:
        v = _value(train, name)
        lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
        span = hi - lo or (0.5 * abs(hi) if name in COEFFICIENT_INPUTS else 0.5)  # a k_z 1-sigma stays > 0
        cols[name] = rng.uniform(lo - 0.1 * span, hi + 0.1 * span, n)
    on_site = rng.random(n) < 0.8  # mostly at a training site, so that the other inputs decide the range check
    cols["lat0_deg"][on_site] = rng.choice(train.lat0_deg, int(on_site.sum()))
    err = (train.lat_deg - train.lat0_deg) * 3600.0  # and so does the latitude error
    span = float(err.max() - err.min())
    cols["lat_deg"] = cols["lat0_deg"] + rng.uniform(err.min() - 0.1 * span, err.max() + 0.1 * span, n) / 3600.0
    cols["temp_max_c"] = np.maximum(cols["temp_max_c"], cols["temp_min_c"])
    if "smoother_coeff_prior_std_deg_h_per_c" in cols:  # the smoother's setting: mostly a training run's
        s0 = cols["smoother_coeff_prior_std_deg_h_per_c"]
        usual = rng.random(n) < 0.8
        s0[usual] = rng.choice(train.column("smoother_coeff_prior_std_deg_h_per_c")[_thermal(train)], int(usual.sum()))
    constant = rng.random(n) < 1 / 3  # a third of the rows without k_z: the smoother's constant model
    for name in COEFFICIENT_INPUTS:
        if name in cols:
            cols[name][constant] = np.nan
    return RunTable(
        run=np.array([f"p{i}" for i in range(N_ROWS)]),
        drift_deg_h=np.full(N_ROWS, np.nan),
        **{name: np.concatenate([getattr(train, name), cols[name]]) for name in RAW},
        extra={c: np.concatenate([_value(train, c), cols[c]]) for c in cols if c not in RAW},
    )


def _model(train: RunTable, encoding: str, scaling: str, kernel: str, physics: str | None = None):
    sigma = _SIGMA[kernel][scaling]
    hybrid = {} if physics is None else {"target": "residual", "physics_column": physics, "max_label_std_deg_h": 1e-3}
    model = fit_drift_model(train, encoding=encoding, scaling=scaling, gamma=100.0, sigma=sigma, **hybrid)
    if kernel != "rbf":  # `fit` tunes RBF only; the LSSVR has the other kernels, and the export supports them
        est = LSSVR(gamma=100.0, sigma=sigma, kernel=kernel, degree=3, coef0=1.0)
        model.learner_.named_steps["lssvr"].lssvr_ = est.fit(model.learner_[:-1].transform(train), train.drift_deg_h)
    return model


def _used_inputs(model) -> list[str]:
    """The inputs a model reads: those of its features and, for a hybrid, of its physics estimate."""
    exprs = [FEATURE_EXPRESSIONS[f] for f in model.feature_names]
    if model.target == "residual":
        exprs.append(PHYSICS_EXPRESSIONS[physics_column(model)])
    return [n for n in ALL if any(n in e.inputs for e in exprs)]


def _kernel_terms(est, X: np.ndarray) -> np.ndarray:
    """K(X[j], x_i), shape (n_rows, n_train), by the documented operations (gyrodrift.learn.lssvr, "prediction
    arithmetic"), written out here one row at a time: features in order, exp of the C library, powers multiplied."""
    out = np.empty((len(X), len(est.X_fit_)))
    s2 = est.sigma * est.sigma
    for j, x in enumerate(X.tolist()):
        for i, z in enumerate(est.X_fit_.tolist()):
            acc = 0.0
            for a, b in zip(x, z, strict=True):
                acc += (a - b) * (a - b) if est.kernel == "rbf" else a * b
            if est.kernel == "rbf":
                acc = math.exp(-acc / s2)
            elif est.kernel != "linear":
                base = acc / s2 + est.coef0
                acc = base
                for _ in range(1, est.degree):
                    acc *= base
            out[j, i] = acc
    return out


def _expected(model, rows: RunTable) -> dict:
    """What the generated code must give, computed in Python independently of gyrodrift.export."""
    train = model.training_["runs"]  # the runs the model was fitted on (without any left out)
    est = model.lssvr
    X = model.learner_[:-1].transform(rows)
    K = _kernel_terms(est, X)
    inside = np.ones(len(rows), bool)
    thermal = _thermal(rows)
    for name in _used_inputs(model):
        v, t = _value(rows, name), _value(train, name)
        if name in COEFFICIENT_INPUTS:  # over the training runs with k_z; NaN on a row without
            t = t[_thermal(train)]
            inside &= np.where(thermal, (v >= t.min()) & (v <= t.max()), ~np.isfinite(v))
        else:
            inside &= (v >= t.min()) & (v <= t.max())
    feats, tfeats = encode(rows, model.encoding), encode(train, model.encoding)
    inside &= np.all((feats >= tfeats.min(axis=0)) & (feats <= tfeats.max(axis=0)), axis=1)
    pred = model.predict(rows)
    physics = _physics(model, rows) if model.target == "residual" else np.zeros(len(rows))
    terms = K * est.alpha_
    # numpy's kernel (scipy's distances, numpy's exp and power) summed by BLAS: the arithmetic before the export
    # and Python agreed on theirs
    numpy_kernel = kernel_matrix(X, est.X_fit_, kernel=est.kernel, sigma=est.sigma, coef0=est.coef0)
    return {
        "pred": pred,
        # the terms summed exactly
        "exact": np.array([math.fsum([*t, est.intercept_, p]) for t, p in zip(terms, physics, strict=True)]),
        "scale": np.abs(terms).sum(axis=1) + abs(est.intercept_) + np.abs(physics),
        "numpy": numpy_kernel @ est.alpha_ + est.intercept_ + physics,
        "inside": inside,
        "features": feats,
        "physics": physics,
    }


def _cases():
    rng = np.random.default_rng(20130613)
    paper = gyrodrift.load_paper().train
    synthetic = _synthetic_runs(rng)
    hybrid = _hybrid_runs(rng)
    out = []
    for encoding, scaling in itertools.product(ENCODINGS, SCALINGS):
        out.append(("paper", paper, encoding, scaling, "rbf", None))
    for encoding, scaling, kernel in itertools.product(ENCODINGS, SCALINGS, ("rbf", "linear", "poly")):
        out.append(("synthetic", synthetic, encoding, scaling, kernel, None))
    for (i, physics), (j, encoding) in itertools.product(enumerate(PHYSICS_COLUMNS), enumerate(ENCODINGS)):
        scaling = SCALINGS[(i + j) % len(SCALINGS)]  # every scaling with every physics column
        out.append(("hybrid", hybrid, encoding, scaling, "rbf", physics))
    return out


CASES = _cases()
CASE_IDS = [
    f"{d}-{e}-{s}-{k}" + ("" if p is None else "-" + p.removeprefix("drift_").removesuffix("_deg_h"))
    for d, _, e, s, k, p in CASES
]
DEFAULT_CASE = "cli-default-fit"
"""The model of `gyrodrift fit TABLE --out model.json` with every default (a hybrid on the fleet-prior smoother,
which `auto` resolves to on a table with the smoother's k_z, weighted by the label 1-sigmas, one run left out),
exported by `gyrodrift export`."""
_CLI_EXPORTS: dict[str, dict[str, str]] = {}
"""Language -> the files `gyrodrift export` wrote for DEFAULT_CASE (filled by the `fitted` fixture)."""

COS_SUFFIX = "+cos"
"""A case exported with the latitude error written as ``(lat - lat0) * 3600 * cos(0 * lat0)`` (the same bits):
the path a feature needing a math function (say, a physics-normalised encoding with cos(lat0)) will take."""
COS_CASE = CASE_IDS[0] + COS_SUFFIX
_COS_EXPRESSION = FeatureExpression(
    ("lat_deg", "lat0_deg"),
    "({lat_deg} - {lat0_deg}) * 3600.0 * {cos}(0.0 * {lat0_deg})",
    "({lat_deg} - {lat0_deg}) * 3600.0 * {cos}(0.0 * {lat0_deg})",
    "arcsec",
    ("cos",),
)


def _export(case_id: str, model, lang: str) -> dict[str, str]:
    """The generated files of a case (the cos case with its patched feature expression; the default `fit`
    model's from the command)."""
    if case_id == DEFAULT_CASE:
        return _CLI_EXPORTS[lang]
    with pytest.MonkeyPatch.context() as patch:
        if case_id.endswith(COS_SUFFIX):
            patch.setitem(FEATURE_EXPRESSIONS, "lat_err_arcsec", _COS_EXPRESSION)
        return export_model(model, lang)


@pytest.fixture(scope="module")
def default_fit_file(tmp_path_factory):
    """A model file of `gyrodrift fit` with every default, on the hybrid synthetic table (CSV)."""
    folder = tmp_path_factory.mktemp("default_fit")
    table = folder / "runs.csv"
    _hybrid_runs(np.random.default_rng(20130613)).to_csv(table)
    r = CliRunner().invoke(main, ["fit", str(table), "--out", str(folder / "model.json"), "--quiet"])
    assert r.exit_code == 0, r.output
    return folder / "model.json"


@pytest.fixture(scope="module")
def fitted(default_fit_file, tmp_path_factory):
    """Case id -> (model, rows, expected), built once for the C and the Rust tests."""
    rng = np.random.default_rng(7)
    out = {}
    for case_id, (_, train, encoding, scaling, kernel, physics) in zip(CASE_IDS, CASES, strict=True):
        model = _model(train, encoding, scaling, kernel, physics)
        rows = _probe_rows(model.training_["runs"], rng)
        out[case_id] = (model, rows, _expected(model, rows))
    out[COS_CASE] = out[CASE_IDS[0]]
    model = load_model(default_fit_file)
    assert (model.encoding, model.target, model.physics_column) == (default_encoding("residual"), "residual", "auto")
    assert model.physics_column_ == FLEET and model.coefficient_prior_ is not None  # resolved on the smoother's k_z
    assert model.training["weighted"] and model.training_["left_out"]
    rows = _probe_rows(model.training_["runs"], rng)
    out[DEFAULT_CASE] = (model, rows, _expected(model, rows))
    for lang in LANGUAGES:
        folder = tmp_path_factory.mktemp(f"default_export_{lang}")
        args = ["export", "--model", str(default_fit_file), "--lang", lang, "--out", str(folder), "--quiet"]
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 0, r.output
        _CLI_EXPORTS[lang] = {name: (folder / name).read_text() for name in LANGUAGES[lang]}
    return out


ALL_CASES = [*CASE_IDS, COS_CASE, DEFAULT_CASE]


def _rows_text(rows: RunTable) -> str:
    """One line per row: every input of `ALL` (nan where the row has none: a physics column the rows do not have,
    k_z under the smoother's constant model)."""
    values = np.column_stack([_value(rows, n) for n in ALL])
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in values)


def _check(case_id: str, got: np.ndarray, exp: dict) -> tuple[float, float]:
    """Assert the tolerance; return (max error relative to |python|, fraction of rows with the same bits)."""
    err = np.abs(got - exp["pred"])
    bound = TOL * np.abs(exp["pred"])
    worst = int(np.argmax(err - bound))
    assert np.all(err <= bound), f"{case_id}: row {worst}: {got[worst]!r} vs python {exp['pred'][worst]!r}"
    return float(np.max(err / np.abs(exp["pred"]))), float(np.mean(got == exp["pred"]))


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
    model = _model(_hybrid_runs(np.random.default_rng(5)), encoding, "standard", "rbf", physics)
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
        train = train[_thermal(runs)] if name in KZ else train  # k_z: over the runs with one
        lo, hi = literal(train.min()), literal(train.max())
        assert f'{{"{name}", {lo}, {hi}}}' in export_model(model, "c")["gyrodrift_model.c"]
        assert f'Range {{ name: "{name}", min: {lo}, max: {hi} }}' in rust
        assert f"{name}: [{lo}, {hi}]" in header  # provenance
    if physics == FLEET:  # the fleet prior: constants
        mean, std = (literal(v) for v in model.coefficient_prior_)
        assert f"#define GYRODRIFT_MODEL_COEFF_PRIOR_MEAN_DEG_H_PER_C {mean}" in header
        assert f"pub const COEFF_PRIOR_STD_DEG_H_PER_C: f64 = {std};" in rust


def test_label_weights_change_the_model_but_need_nothing_at_prediction(fitted):
    weighted, _, _ = fitted[DEFAULT_CASE]
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
        *_export(DEFAULT_CASE, weighted, "c").values(),
        _export(DEFAULT_CASE, weighted, "rust")["gyrodrift_model.rs"],
    ]
    assert all("drift_std" not in re.sub(r"Label weighting[^\n]*", "", text) for text in files)
    raw = tuple(n for n in RAW if any(n in FEATURE_EXPRESSIONS[f].inputs for f in ENCODINGS[encoding]))
    fleet_fields = (*raw, "drift_smoother_deg_h", *KZ)  # the encoding's, then the fleet-prior smoother's
    assert export_spec(unweighted).inputs == export_spec(weighted).inputs == fleet_fields


def test_a_feature_without_expression_cannot_be_exported(monkeypatch):
    model = _model(gyrodrift.load_paper().train, "temp_mean", "standard", "rbf")
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


def test_export_is_deterministic_and_carries_provenance(fitted):
    model, _, _ = fitted[CASE_IDS[0]]
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
    model = _model(gyrodrift.load_paper().train, "lat_only", "standard", "rbf")
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


# --- C ------------------------------------------------------------------------------------------------------

_C_PUBLIC = (
    "input_ranges",
    "feature_ranges",
    "features",
    "in_range",
    "physics_deg_h",
    "correction_deg_h",
    "drift_deg_h",
)

_C_WRAPPER = """/* Model NAME: its generated source in a translation unit of its own, public names prefixed. */
#include <stdio.h>
#include <stdlib.h>
DEFINES
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
"""

C_RESULTS: dict[str, tuple[float, ...]] = {}
"""Case id -> (max |c - py| / |py|, fraction of rows with the same bits, max |py - exact| / |exact|,
max |numpy - exact| / |exact|, max condition S / |exact|, fraction of the rows in range), printed by
test_c_summary."""


def _c_wrapper(name: str, header: str, hybrid: bool) -> str:
    fill = "\n".join(f"        in.{n} = u[{k}];" for k, n in enumerate(ALL) if f"double {n};" in header)
    return (
        _C_WRAPPER.replace("DEFINES", "\n".join(f"#define gyrodrift_model_{f} NAME_{f}" for f in _C_PUBLIC))
        .replace("NAME", name)
        .replace("N_ALL", str(len(ALL)))
        .replace("FORMAT", '"' + " ".join(["%63s"] * len(ALL)) + '"')
        .replace("TEXTS", ", ".join(f"text[{k}]" for k in range(len(ALL))))
        .replace("FILL", fill)
        .replace("PHYSICS", "gyrodrift_model_physics_deg_h(&in)" if hybrid else "0.0")
    )


@pytest.fixture(scope="module")
def c_driver(fitted, tmp_path_factory):
    """One program holding every model's C (one compiler run); ``driver k`` evaluates model k on stdin.

    Returns (path, {case id: model index}, build time [s])."""
    folder = tmp_path_factory.mktemp("c_export")
    index, sources, dispatch = {}, [], []
    for k, case_id in enumerate(ALL_CASES):
        model = fitted[case_id][0]
        name = f"m{k:03d}"
        files = _export(case_id, model, "c")
        needs_math = model.lssvr.kernel == "rbf" or any(FEATURE_EXPRESSIONS[f].functions for f in model.feature_names)
        needs_math |= case_id == COS_CASE or (
            physics_column(model) in ("drift_inversion_deg_h", FLEET)  # cos; isfinite
        )
        assert ("#include <math.h>" in files["gyrodrift_model.c"]) == needs_math, case_id
        (folder / name).mkdir()
        for file_name, text in files.items():
            (folder / name / file_name).write_text(text)
        (folder / f"{name}.c").write_text(_c_wrapper(name, files["gyrodrift_model.h"], model.target == "residual"))
        sources.append(f"{name}.c")
        dispatch.append(f"    case {k}: return {name}_run();")
        index[case_id] = k
    declarations = "".join(f"int m{k:03d}_run(void);\n" for k in range(len(ALL_CASES)))
    (folder / "main.c").write_text(
        f"#include <stdlib.h>\n{declarations}\nint main(int argc, char **argv)\n{{\n"
        f"    switch (argc > 1 ? atoi(argv[1]) : -1) {{\n"
        + "\n".join(dispatch)
        + "\n    default: return 2;\n    }\n}\n"
    )
    start = time.perf_counter()
    subprocess.run([CC, *CFLAGS, "main.c", *sources, "-lm", "-o", "driver"], cwd=folder, check=True, timeout=600)
    return folder / "driver", index, time.perf_counter() - start


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
@pytest.mark.parametrize("case_id", ALL_CASES)
def test_c_export_reproduces_python(case_id, fitted, c_driver):
    model, rows, exp = fitted[case_id]
    driver, index, _ = c_driver
    out = subprocess.run(
        [str(driver), str(index[case_id])],
        input=_rows_text(rows),
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
        thermal = _thermal(rows)
        assert (exp["inside"] & thermal).sum() > 20 and (exp["inside"] & ~thermal).sum() > 20
    rel, same = _check(case_id, table[:, 0], exp)
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
        text = _export(case_id, model, "rust")["gyrodrift_model.rs"]
        (project / "src" / f"{module}.rs").write_text(text)
        lib.append(f"pub mod {module};")
        bound = TOL * np.abs(exp["pred"])
        lines = []
        for r, inputs in enumerate(_rows_text(rows).splitlines()):
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


# --- the command --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def model_file(tmp_path_factory, fitted):
    path = tmp_path_factory.mktemp("model") / "model.json"
    save_model(fitted[CASE_IDS[0]][0], path)
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
