"""`gyrodrift export` of a hybrid on the fleet-prior smoother (``drift_smoother_fleet_deg_h``): the generated C
and Rust compute the base with the operations of `gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`, so they
give its bits, on thermal rows and on constant-model rows (NaN k_z: the end drift unchanged), and on the edges of
its thermal test (a zero, underflowing or overflowing k_z 1-sigma, a zero or infinite prior 1-sigma).

The reference here is that function itself (with the model's ``coefficient_prior_``) and the LSSVR's compensated
sum with the base as its offset (`LSSVR.predict(X, offset=...)`, what `DriftModel.predict` does); the range check
is recomputed here from the training runs. Tolerance: the same bits (``==``, every row).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess

import numpy as np
import pytest

from gyrodrift.errors import InputError
from gyrodrift.export.languages import LANGUAGES, export_model
from gyrodrift.export.literals import literal
from gyrodrift.export.spec import PHYSICS_INPUTS, export_spec
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.encodings import encode
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior, pooled_coefficient_prior
from gyrodrift.learn.model_io import load_model, save_model
from gyrodrift.learn.physics_base import FLEET_PHYSICS
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import RunTable, RunTableError

CC = shutil.which("cc")
CARGO = shutil.which("cargo")
CFLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wconversion", "-Wshadow", "-Wdouble-promotion", "-Werror"]
FLEET = FLEET_PHYSICS
KZ = SMOOTHER_THERMAL_COLUMNS
FIELDS = ("lat_deg", "lat0_deg", "temp_min_c", "temp_max_c", "drift_smoother_deg_h", *KZ)
"""The fields of the generated struct of a fleet hybrid with encoding ``physics`` (it reads all four raw inputs and
`cos`), in order."""
N_RANDOM = 1500


def fleet_runs(rng: np.random.Generator, n: int = 24, n_constant: int = 5) -> RunTable:
    """Runs at three sites [deg, deg C, deg/h] with the smoother's columns: end drift and 1-sigma, and for all but
    ``n_constant`` runs (the smoother's constant model: NaN) its k_z estimate, 1-sigma, covariance with the end
    drift and own prior 1-sigma; label 1-sigmas below `fit`'s limit."""
    lat0 = rng.choice([20.5, 34.1, 51.3], n)
    err = rng.uniform(-120.0, 120.0, n)
    tmin = rng.uniform(10.0, 50.0, n)
    tmax = tmin + rng.uniform(0.5, 8.0, n)
    kz = rng.normal(2e-4, 4e-5, n)  # each unit's thermal coefficient [deg/h/degC]
    drift = 0.004 + kz * (tmax - 30.0) + 0.002 * np.sin(err / 60.0) + rng.normal(0.0, 2e-4, n)
    d_std = rng.uniform(1e-4, 5e-4, n)
    k_std = rng.uniform(5e-5, 3e-4, n)
    cov = rng.uniform(-0.9, 0.9, n) * d_std * k_std
    constant = np.zeros(n, bool)
    constant[rng.choice(n, n_constant, replace=False)] = True
    nan_where = lambda v: np.where(constant, np.nan, v)  # noqa: E731
    extra = {
        "drift_std_deg_h": rng.uniform(5e-5, 3e-4, n),
        "drift_smoother_deg_h": drift + rng.normal(0.0, d_std),
        "drift_smoother_std_deg_h": d_std,
        "smoother_coeff_deg_h_per_c": nan_where(kz + rng.normal(0.0, k_std)),
        "smoother_coeff_std_deg_h_per_c": nan_where(k_std),
        "smoother_end_coeff_cov": nan_where(cov),
        "smoother_coeff_prior_std_deg_h_per_c": nan_where(np.full(n, 1e-2)),
    }
    return RunTable(
        run=np.array([f"f{i}" for i in range(n)]),
        lat_deg=lat0 + err / 3600.0,
        lat0_deg=lat0,
        temp_min_c=tmin,
        temp_max_c=tmax,
        drift_deg_h=drift,
        extra=extra,
        source="synthetic-fleet",
    )


def _fit(train: RunTable):
    """A hybrid with the default ``physics_column="auto"`` and encoding ``physics`` fitted on ``train`` (fixed
    gamma and sigma: tuning is not tested here)."""
    return fit_drift_model(train, encoding="physics", target="residual", gamma=100.0, sigma=0.7)


def _fleet_model(train: RunTable):
    """A hybrid on the fleet-prior smoother fitted on ``train``: what ``auto`` resolves to on these runs."""
    model = _fit(train)
    assert (model.physics_column, model.physics_column_) == ("auto", FLEET)
    thermal = _thermal(train)
    assert model.coefficient_prior_ == pooled_coefficient_prior(
        train.column(KZ[0])[thermal], train.column(KZ[1])[thermal]
    )
    return model


def _base(model, rows: RunTable) -> np.ndarray:
    """The fleet base of each row [deg/h]: `drift_with_coefficient_prior` with the model's prior."""
    with np.errstate(over="ignore"):  # a k_z 1-sigma squaring to inf (an edge row): not thermal
        drift, _ = drift_with_coefficient_prior(
            rows.column("drift_smoother_deg_h"),
            rows.column("drift_smoother_std_deg_h"),
            *(rows.column(name) for name in KZ),
            *model.coefficient_prior_,
        )
    return drift


def _thermal(rows: RunTable) -> np.ndarray:
    k, sk, c, s0 = (rows.column(name) for name in KZ)
    with np.errstate(over="ignore"):
        vk = sk * sk
    return np.isfinite(k) & np.isfinite(vk) & (vk > 0) & np.isfinite(c) & np.isfinite(s0) & (s0 > 0)


def _probe_rows(train: RunTable, rng: np.random.Generator) -> RunTable:
    """The training runs, then random rows over 1.2 times each input's training range (a third without k_z: the
    constant model), then rows on the edges of the thermal test."""
    n = N_RANDOM
    cols = {}
    for name in FIELDS:
        v = train.column(name) if name in PHYSICS_INPUTS else getattr(train, name)
        v = v[np.isfinite(v)]
        lo, hi = float(v.min()), float(v.max())
        span = hi - lo or 0.5 * abs(hi)
        cols[name] = rng.uniform(lo - 0.1 * span, hi + 0.1 * span, n)
    cols["lat0_deg"] = rng.choice(train.lat0_deg, n)
    cols["lat_deg"] = cols["lat0_deg"] + rng.uniform(-130.0, 130.0, n) / 3600.0
    cols["temp_max_c"] = np.maximum(cols["temp_max_c"], cols["temp_min_c"])
    smoother_std = rng.uniform(1e-4, 5e-4, n)  # not an input (the base's drift does not depend on it); Python's
    usual = rng.random(n) < 0.8  # the smoother's prior 1-sigma (a setting): mostly a training run's
    cols[KZ[3]][usual] = rng.choice(train.column(KZ[3])[_thermal(train)], int(usual.sum()))
    constant = rng.random(n) < 1 / 3
    for name in KZ:
        cols[name][constant] = np.nan
    # the edges of the thermal test, each on a few rows: k_z 1-sigma 0, squaring to 0 or to inf, a prior 1-sigma
    # 0, negative, inf, one k_z input NaN alone, a negative k_z 1-sigma (squares to a positive variance)
    edges = [
        (KZ[1], 0.0),
        (KZ[1], 1e-170),
        (KZ[1], 1e160),
        (KZ[1], -1.5e-4),
        (KZ[3], 0.0),
        (KZ[3], -1e-2),
        (KZ[3], math.inf),
        (KZ[0], math.nan),
        (KZ[2], math.inf),
        (KZ[3], 1e-4),  # the filter's prior tighter than the fleet's: the precision can go negative
    ]
    for j, (name, value) in enumerate(edges):
        cols[name][j * 5 : j * 5 + 5] = value
    return RunTable(
        run=np.array([f"p{i}" for i in range(len(train) + n)]),
        drift_deg_h=np.full(len(train) + n, np.nan),
        **{name: np.concatenate([getattr(train, name), cols[name]]) for name in FIELDS[:4]},
        extra={
            **{name: np.concatenate([train.column(name), cols[name]]) for name in FIELDS[4:]},
            "drift_smoother_std_deg_h": np.concatenate([train.column("drift_smoother_std_deg_h"), smoother_std]),
        },
    )


def _expected(model, rows: RunTable) -> dict:
    train = model.training_["runs"]
    base = _base(model, rows)
    pred = model.lssvr.predict(model.learner_[:-1].transform(rows), offset=base)
    inside = np.ones(len(rows), bool)
    thermal, thermal_train = _thermal(rows), _thermal(train)
    for name in FIELDS:
        get = (lambda r, n=name: r.column(n)) if name in PHYSICS_INPUTS else (lambda r, n=name: getattr(r, n))
        t = get(train)[thermal_train] if name in KZ else get(train)
        ok = (get(rows) >= t.min()) & (get(rows) <= t.max())
        # without a thermal k_z, every k_z input NaN (the constant model; some but not all: neither)
        inside &= np.where(thermal, ok, ~np.isfinite(get(rows))) if name in KZ else ok
    feats, tfeats = encode(rows, model.encoding), encode(train, model.encoding)
    inside &= np.all((feats >= tfeats.min(axis=0)) & (feats <= tfeats.max(axis=0)), axis=1)
    return {"base": base, "pred": pred, "inside": inside, "thermal": thermal}


@pytest.fixture(scope="module")
def fleet():
    """(model, probe rows, expected) for a fleet hybrid with encoding ``physics``."""
    rng = np.random.default_rng(2026)
    model = _fleet_model(fleet_runs(rng))
    rows = _probe_rows(model.training_["runs"], rng)
    exp = _expected(model, rows)
    assert 0.2 < exp["thermal"].mean() < 0.8 and 50 < exp["inside"].sum() < len(rows) - 50
    assert (exp["inside"] & exp["thermal"]).sum() > 50 and (exp["inside"] & ~exp["thermal"]).sum() > 50
    assert exp["inside"][: len(model.training_["runs"])].all()  # the training runs are inside
    moved = exp["base"] != rows.column("drift_smoother_deg_h")
    assert np.array_equal(moved, exp["thermal"] & moved) and moved.sum() > 0.5 * exp["thermal"].sum()
    return model, rows, exp


def test_the_reference_is_the_models_prediction(fleet):
    """`DriftModel.predict` gives the bits the generated code is checked against, on every row: the LSSVR's
    compensated sum with `drift_with_coefficient_prior` of the row and the model's fleet prior as offset. A row
    with some but not all k_z inputs (edge rows here; neither of the smoother's models writes one) is refused by
    `predict`, naming it; the generated code takes it as the constant model and says `in_range` false."""
    model, rows, exp = fleet
    kz = np.column_stack([rows.column(name) for name in KZ])
    present = np.isfinite(kz)
    partial = present.any(axis=1) & ~present.all(axis=1)  # runs.check_smoother_thermal's rule
    whole = ~partial
    with np.errstate(over="ignore"):  # a k_z 1-sigma squaring to inf (an edge row)
        np.testing.assert_array_equal(_bits(model.predict(rows.select(whole))), _bits(exp["pred"][whole]))
    assert 0 < partial.sum() < 60 and not exp["inside"][partial].any()
    assert np.array_equal(exp["base"][partial], rows.column("drift_smoother_deg_h")[partial])
    first = int(np.flatnonzero(partial)[0])
    with pytest.raises(RunTableError, match=f"{rows.run[first]} \\(missing"):
        model.predict(rows.select(partial))


def test_auto_exports_the_base_it_resolved_to_and_the_model_file_keeps_it(fleet, tmp_path):
    """``physics_column="auto"`` resolves at fit time; export reads the resolved column (and the fleet prior
    through a model file, bit for bit)."""
    model, _, _ = fleet
    path = tmp_path / "model.json"
    save_model(model, path)
    loaded = load_model(path)
    for lang in LANGUAGES:
        assert export_model(loaded, lang) == export_model(model, lang)
    train = model.training_["runs"]
    no_kz = train.replace(extra={k: v for k, v in train.extra.items() if k not in KZ})
    no_smoother = train.replace(extra={"drift_std_deg_h": train.column("drift_std_deg_h")})
    for runs, column, fields in (
        (no_kz, "drift_smoother_deg_h", FIELDS[:5]),
        (no_smoother, "drift_inversion_deg_h", FIELDS[:4]),
    ):
        resolved = _fit(runs)
        spec = export_spec(resolved)
        assert (resolved.physics_column_, spec.physics, spec.inputs) == (column, column, fields)
        assert spec.coefficient_prior is None
        assert f'#define GYRODRIFT_MODEL_PHYSICS "{column}"' in export_model(resolved, "c")["gyrodrift_model.h"]


def _rows_text(rows: RunTable) -> str:
    cols = [rows.column(n) if n in PHYSICS_INPUTS else getattr(rows, n) for n in FIELDS]
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in np.column_stack(cols))


def _bits(values) -> np.ndarray:
    return np.asarray(values, float).view(np.int64)


def test_the_spec_reads_the_smoother_and_its_k_z_and_holds_the_prior(fleet):
    model, _, _ = fleet
    spec = export_spec(model)
    assert spec.physics == FLEET and spec.inputs == FIELDS and spec.functions == ("cos", "exp")
    assert spec.coefficient_prior == tuple(model.coefficient_prior_)
    train = model.training_["runs"]
    thermal = _thermal(train)
    assert 0 < thermal.sum() < len(train)
    for name, (lo, hi) in zip(spec.inputs, spec.input_ranges, strict=True):
        v = train.column(name) if name in PHYSICS_INPUTS else getattr(train, name)
        v = v[thermal] if name in KZ else v
        assert (lo, hi) == (v.min(), v.max()), name
    c = export_model(model, "c")
    rust = export_model(model, "rust")["gyrodrift_model.rs"]
    mean, std = (literal(x) for x in model.coefficient_prior_)
    assert f"#define GYRODRIFT_MODEL_COEFF_PRIOR_MEAN_DEG_H_PER_C {mean}" in c["gyrodrift_model.h"]
    assert f"#define GYRODRIFT_MODEL_COEFF_PRIOR_STD_DEG_H_PER_C {std}" in c["gyrodrift_model.h"]
    assert f"pub const COEFF_PRIOR_MEAN_DEG_H_PER_C: f64 = {mean};" in rust
    assert f"pub const COEFF_PRIOR_STD_DEG_H_PER_C: f64 = {std};" in rust
    assert "drift_smoother_std_deg_h" not in c["gyrodrift_model.h"] + rust  # the base's drift does not read it


def test_a_fleet_model_without_a_usable_prior_is_refused(fleet):
    model, _, _ = fleet
    for prior in (None, (0.0, 0.0), (math.nan, 1e-4), (2e-4, math.inf)):
        broken = _fleet_model(model.training_["runs"])
        broken.base_.coefficient_prior_ = prior  # the model's prior is its physics base's
        with pytest.raises(InputError, match="prior"):
            export_model(broken, "c")


_C_DRIVER = """#include <stdio.h>
#include <stdlib.h>
#include "gyrodrift_model.h"

/* Rows of the inputs on stdin; per row: drift, physics, in range. */
int main(void)
{
    char t[N][64];
    while (scanf(FORMAT, TEXTS) == N) {
        gyrodrift_model_inputs in = {VALUES};
        printf("%.17g %.17g %d\\n", gyrodrift_model_drift_deg_h(&in), gyrodrift_model_physics_deg_h(&in),
               gyrodrift_model_in_range(&in));
    }
    return 0;
}
"""


def _check(got: np.ndarray, exp: dict, what: str) -> None:
    """Every row the same bits (drift and base) and the same range check; the counts printed (pytest -s)."""
    for k, key in enumerate(("pred", "base")):
        same = _bits(got[:, k]) == _bits(exp[key])
        worst = int(np.argmin(same))
        assert same.all(), f"{what} {key}: row {worst}: {got[worst, k]!r} vs python {exp[key][worst]!r}"
    np.testing.assert_array_equal(got[:, 2].astype(bool), exp["inside"])
    print(
        f"\n{what}: {len(got)} rows ({int(exp['thermal'].sum())} with a thermal k_z, {int((~exp['thermal']).sum())} "
        f"without: constant model or an edge of the test; {int(exp['inside'].sum())} in range, "
        f"{int((exp['inside'] & exp['thermal']).sum())} of them with k_z): drift and base the "
        "same bits as Python on every row"
    )


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_c_gives_the_bits_of_drift_with_coefficient_prior_and_of_the_prediction(fleet, tmp_path):
    model, rows, exp = fleet
    for name, text in export_model(model, "c").items():
        (tmp_path / name).write_text(text)
    n = len(FIELDS)
    (tmp_path / "driver.c").write_text(
        _C_DRIVER.replace("FORMAT", '"' + " ".join(["%63s"] * n) + '"')
        .replace("TEXTS", ", ".join(f"t[{k}]" for k in range(n)))
        .replace("VALUES", ", ".join(f"strtod(t[{k}], NULL)" for k in range(n)))
        .replace("char t[N]", f"char t[{n}]")
        .replace("== N)", f"== {n})")
    )
    subprocess.run([CC, *CFLAGS, "driver.c", "gyrodrift_model.c", "-lm", "-o", "driver"], cwd=tmp_path, check=True)
    out = subprocess.run(
        ["./driver"], cwd=tmp_path, input=_rows_text(rows), capture_output=True, text=True, check=True, timeout=60
    ).stdout
    got = np.array([line.split() for line in out.splitlines()], float)
    assert got.shape == (len(rows), 3)
    _check(got, exp, "C")


_CARGO_TOML = """[package]
name = "gyrodrift_fleet_check"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
"""

_RUST_MAIN = """#[allow(dead_code)] // the functions the check does not call
mod gyrodrift_model;
use gyrodrift_model as m;
use std::io::BufRead;

fn main() {
    let math = m::Math { cos: f64::cos, exp: f64::exp };
    for line in std::io::stdin().lock().lines() {
        let u: Vec<f64> = line.unwrap().split(' ').map(|t| t.parse::<f64>().unwrap()).collect();
        let inputs = m::Inputs { FIELDS };
        let drift = m::drift_deg_h(&inputs, &math);
        let physics = m::physics_deg_h(&inputs, &math);
        println!("{drift:e} {physics:e} {}", i32::from(m::in_range(&inputs, &math)));
    }
}
"""


@pytest.mark.skipif(CARGO is None, reason="no cargo on PATH")
def test_rust_gives_the_bits_of_drift_with_coefficient_prior_and_of_the_prediction(fleet, tmp_path_factory):
    model, rows, exp = fleet
    project = tmp_path_factory.mktemp("rust_fleet")
    (project / "src").mkdir()
    (project / "Cargo.toml").write_text(_CARGO_TOML)
    (project / "src" / "gyrodrift_model.rs").write_text(export_model(model, "rust")["gyrodrift_model.rs"])
    fields = ", ".join(f"{name}: u[{k}]" for k, name in enumerate(FIELDS))
    (project / "src" / "main.rs").write_text(_RUST_MAIN.replace("FIELDS", fields))
    env = {**os.environ, "CARGO_TARGET_DIR": str(tmp_path_factory.getbasetemp() / "cargo-target-fleet")}
    build = subprocess.run(
        ["cargo", "build", "--offline", "--quiet", "--release"], cwd=project, env=env, capture_output=True, text=True
    )
    assert build.returncode == 0 and "warning" not in build.stderr, build.stderr[-4000:]
    run = subprocess.run(
        ["cargo", "run", "--offline", "--quiet", "--release"],
        cwd=project,
        env=env,
        input=_rows_text(rows),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr[-4000:]
    got = np.array([line.split() for line in run.stdout.splitlines()], float)
    assert got.shape == (len(rows), 3)
    _check(got, exp, "Rust")
