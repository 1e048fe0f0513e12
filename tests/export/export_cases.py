"""The models of the export tests and what their generated code must give (shared by test_export.py,
test_export_compiled.py and the fixtures of tests/export/conftest.py).

Every encoding x scaling is fitted (RBF, the kernel `fit` tunes) on the paper's runs and on a random synthetic
table with several sites; on the synthetic table the linear and polynomial kernels of the LSSVR are exported
too. Hybrid models (``target="residual"``: physics estimate + learned correction) are fitted for every physics
column x encoding on a synthetic table carrying the curve-fit and smoother columns (the smoother's k_z on all
but 5 runs, its constant model) and label 1-sigmas (so the fits are weighted, and one run is left out), and the
default ``gyrodrift fit`` model (a hybrid on the fleet-prior smoother) goes through the commands (fit, then
export). Each model is evaluated on 1000 rows: the training runs, then random rows spanning 1.2 times the
training range of each input (so that some fall outside it; a third without k_z). `python_reference` computes,
independently of gyrodrift.export, what the generated code must return on them.
"""

from __future__ import annotations

import itertools
import math
import shutil

import numpy as np
import pytest

import gyrodrift
from gyrodrift.choices import ENCODINGS, PHYSICS_COLUMNS, SCALINGS
from gyrodrift.export.languages import export_model
from gyrodrift.export.spec import (
    FEATURE_EXPRESSIONS,
    INPUTS,
    PHYSICS_EXPRESSIONS,
    PHYSICS_INPUTS,
    FeatureExpression,
    physics_column,
)
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.encodings import encode
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior
from gyrodrift.learn.kernels import kernel_matrix
from gyrodrift.learn.lssvr import LSSVR
from gyrodrift.learn.physics_base import FLEET_PHYSICS, physics_estimate
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import RunTable

TOL = 1e-12
N_ROWS = 1000
RAW = ("lat_deg", "lat0_deg", "temp_min_c", "temp_max_c")
ALL = tuple(INPUTS)  # the raw inputs, then the physics columns the navigation computer computes
FLEET = FLEET_PHYSICS
KZ = SMOOTHER_THERMAL_COLUMNS
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


def synthetic_runs(rng: np.random.Generator, n: int = 24) -> RunTable:
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


def hybrid_runs(rng: np.random.Generator) -> RunTable:
    """The synthetic runs with the curve-fit and smoother columns (the drift plus noise [deg/h]), the smoother's
    k_z estimate (NaN on 5 runs: its constant model) and label 1-sigmas (one beyond `gyrodrift fit`'s default
    limit of 1e-3 deg/h, so that run is left out)."""
    runs = synthetic_runs(rng)
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


def thermal_rows(runs: RunTable) -> np.ndarray:
    """Rows with the smoother's thermal k_z (the test of `drift_with_coefficient_prior`; the others: NaN)."""
    k, sk, c, s0 = (runs.column(name) for name in SMOOTHER_THERMAL_COLUMNS)
    return np.isfinite(k) & np.isfinite(sk * sk) & (sk * sk > 0) & np.isfinite(c) & np.isfinite(s0) & (s0 > 0)


def physics_reference(model, rows: RunTable) -> np.ndarray:
    """A hybrid's physics estimate of each row [deg/h]: `physics_estimate`, or for the fleet-prior smoother
    `drift_with_coefficient_prior` with the model's fleet prior."""
    column = physics_column(model)
    if column != FLEET_PHYSICS:
        return physics_estimate(rows, column)
    names = ("drift_smoother_deg_h", "drift_smoother_std_deg_h", *SMOOTHER_THERMAL_COLUMNS)
    return drift_with_coefficient_prior(*(rows.column(n) for n in names), *model.coefficient_prior_)[0]


def input_values(runs: RunTable, name: str) -> np.ndarray:
    """Input ``name`` (`INPUTS`) of each run: a column, or a physics column (NaN where absent)."""
    return getattr(runs, name) if name in RAW else runs.column(name)


def probe_rows(train: RunTable, rng: np.random.Generator) -> RunTable:
    """The training runs, then random rows over 1.2 times the training range of each input and of the latitude
    error (N_ROWS in all); the physics columns the training runs have too."""
    n = N_ROWS - len(train)
    cols = {}
    # and the smoother's 1-sigma: Python's fleet base wants it (its drift does not depend on it; not exported)
    physics = [*PHYSICS_INPUTS, "drift_smoother_std_deg_h"]
    for name in [*RAW, *(c for c in physics if np.isfinite(train.column(c)).any())]:
        v = input_values(train, name)
        lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
        span = hi - lo or (0.5 * abs(hi) if name in SMOOTHER_THERMAL_COLUMNS else 0.5)  # a k_z 1-sigma stays > 0
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
        s0[usual] = rng.choice(
            train.column("smoother_coeff_prior_std_deg_h_per_c")[thermal_rows(train)], int(usual.sum())
        )
    constant = rng.random(n) < 1 / 3  # a third of the rows without k_z: the smoother's constant model
    for name in SMOOTHER_THERMAL_COLUMNS:
        if name in cols:
            cols[name][constant] = np.nan
    return RunTable(
        run=np.array([f"p{i}" for i in range(N_ROWS)]),
        drift_deg_h=np.full(N_ROWS, np.nan),
        **{name: np.concatenate([getattr(train, name), cols[name]]) for name in RAW},
        extra={c: np.concatenate([input_values(train, c), cols[c]]) for c in cols if c not in RAW},
    )


def fit_case(train: RunTable, encoding: str, scaling: str, kernel: str, physics: str | None = None):
    sigma = _SIGMA[kernel][scaling]
    hybrid = {} if physics is None else {"target": "residual", "physics_column": physics, "max_label_std_deg_h": 1e-3}
    model = fit_drift_model(train, encoding=encoding, scaling=scaling, gamma=100.0, sigma=sigma, **hybrid)
    if kernel != "rbf":  # `fit` tunes RBF only; the LSSVR has the other kernels, and the export supports them
        est = LSSVR(gamma=100.0, sigma=sigma, kernel=kernel, degree=3, coef0=1.0)
        model.learner_.named_steps["lssvr"].lssvr_ = est.fit(model.learner_[:-1].transform(train), train.drift_deg_h)
    return model


def used_inputs(model) -> list[str]:
    """The inputs a model reads: those of its features and, for a hybrid, of its physics estimate."""
    exprs = [FEATURE_EXPRESSIONS[f] for f in model.feature_names]
    if model.target == "residual":
        exprs.append(PHYSICS_EXPRESSIONS[physics_column(model)])
    return [n for n in ALL if any(n in e.inputs for e in exprs)]


def kernel_terms(est, X: np.ndarray) -> np.ndarray:
    """K(X[j], x_i), shape (n_rows, n_train), by the documented operations (gyrodrift.learn.lssvr, "prediction
    arithmetic"), written out here element by element (numpy's +, -, * and / round each element as Python's float
    operations do): features summed in order, exp of the C library (`math.exp`), powers multiplied."""
    acc = np.zeros((len(X), len(est.X_fit_)))
    for k in range(X.shape[1]):  # feature k of every (row, support vector) pair
        a, b = X[:, k, None], est.X_fit_[None, :, k]
        acc = acc + ((a - b) * (a - b) if est.kernel == "rbf" else a * b)
    if est.kernel == "rbf":
        scaled = (-acc / (est.sigma * est.sigma)).ravel().tolist()
        return np.fromiter(map(math.exp, scaled), float, len(scaled)).reshape(acc.shape)
    if est.kernel == "linear":
        return acc
    base = acc / (est.sigma * est.sigma) + est.coef0
    out = base
    for _ in range(1, est.degree):
        out = out * base
    return out


def python_reference(model, rows: RunTable) -> dict:
    """What the generated code must give, computed in Python independently of gyrodrift.export."""
    train = model.training_["runs"]  # the runs the model was fitted on (without any left out)
    est = model.lssvr
    X = model.learner_[:-1].transform(rows)
    K = kernel_terms(est, X)
    inside = np.ones(len(rows), bool)
    thermal = thermal_rows(rows)
    for name in used_inputs(model):
        v, t = input_values(rows, name), input_values(train, name)
        if name in SMOOTHER_THERMAL_COLUMNS:  # over the training runs with k_z; NaN on a row without
            t = t[thermal_rows(train)]
            inside &= np.where(thermal, (v >= t.min()) & (v <= t.max()), ~np.isfinite(v))
        else:
            inside &= (v >= t.min()) & (v <= t.max())
    feats, tfeats = encode(rows, model.encoding), encode(train, model.encoding)
    inside &= np.all((feats >= tfeats.min(axis=0)) & (feats <= tfeats.max(axis=0)), axis=1)
    pred = model.predict(rows)
    physics = physics_reference(model, rows) if model.target == "residual" else np.zeros(len(rows))
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
    synthetic = synthetic_runs(rng)
    hybrid = hybrid_runs(rng)
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
CLI_EXPORTS: dict[str, dict[str, str]] = {}
"""Language -> the files `gyrodrift export` wrote for DEFAULT_CASE (filled by the `default_model` fixture)."""

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


def export_case(case_id: str, model, lang: str) -> dict[str, str]:
    """The generated files of a case (the cos case with its patched feature expression; the default `fit`
    model's from the command)."""
    if case_id == DEFAULT_CASE:
        return CLI_EXPORTS[lang]
    with pytest.MonkeyPatch.context() as patch:
        if case_id.endswith(COS_SUFFIX):
            patch.setitem(FEATURE_EXPRESSIONS, "lat_err_arcsec", _COS_EXPRESSION)
        return export_model(model, lang)


ALL_CASES = [*CASE_IDS, COS_CASE, DEFAULT_CASE]


def rows_text(rows: RunTable) -> str:
    """One line per row: every input of `ALL` (nan where the row has none: a physics column the rows do not have,
    k_z under the smoother's constant model)."""
    values = np.column_stack([input_values(rows, n) for n in ALL])
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in values)


def check_case(case_id: str, got: np.ndarray, exp: dict) -> tuple[float, float]:
    """Assert the tolerance; return (max error relative to |python|, fraction of rows with the same bits)."""
    err = np.abs(got - exp["pred"])
    bound = TOL * np.abs(exp["pred"])
    worst = int(np.argmax(err - bound))
    assert np.all(err <= bound), f"{case_id}: row {worst}: {got[worst]!r} vs python {exp['pred'][worst]!r}"
    return float(np.max(err / np.abs(exp["pred"]))), float(np.mean(got == exp["pred"]))
