"""Model files: versioned JSON holding a drift model's parameters and its training runs. Never pickle.

Layout (``schema_version`` 4)::

    {"format": "gyrodrift-drift-model", "schema_version": 4, "gyrodrift_version": "...",
     "encoding": "physics", "scaling": "standard", "feature_names": [...],
     "target": "drift" or "residual", "physics_column": "auto", "label_weighting": "auto",
     "calibration_folds": 10, "base_uncertainty": "auto",
     "lssvr_params": {"gamma": null, "sigma": null, "objective": "loo_mae", "method": "cpso", "bounds": [...],
                      "n_particles": 30, "max_iter": 100, "w": 0.75, "c1": 2.0, "c2": 2.0, "chaos_steps": 10,
                      "grid_size": 40, "n_folds": 5, "random_state": 0 or null},
     "tuning": {...TuningResult...} or null,
     "fitted": {"gamma": ..., "sigma": ..., "intercept_deg_h": ..., "dual_coef_deg_h": [...],
                "condition_number": ...,
                "on_search_bound": [...], "loo_residuals_deg_h": [...], "spread_theta": [...],
                "interval_residuals_deg_h": [...], "interval_spreads_deg_h": [...], "interval_disagreement_deg_h": ...,
                "physics_column": "drift_smoother_fleet_deg_h" or ... or null,
                "coefficient_prior": [mean, std] or null},
     "warnings": ["...", ...],
     "training": {"n_runs": ..., "sha256": ..., "source": ..., "weighted": true/false, "left_out": [...],
                  "runs": [{"run": ..., "lat_deg": ..., ..., "drift_std_deg_h": ...}, ...]}}

``weighted`` says whether the label 1-sigmas (``drift_std_deg_h``) weighted the LS-SVM; ``left_out`` names the
runs ``fit`` left out because their label 1-sigma was too large. ``physics_column`` is the model's parameter
(``auto`` or a base); ``fitted.physics_column`` the base it resolved to and ``fitted.coefficient_prior`` the
fleet's k_z prior [deg/h/degC] of the fleet base: a load resolves and pools them again from the training runs
and refuses a file whose record differs (to the bit). Schema 3 files (a concrete ``physics_column``, before
``auto`` and ``base_uncertainty``) load with ``base_uncertainty = "none"``, as they were fitted; schema 2 files
(before the hybrid model and weighted labels) as ``target = "drift"`` models with unweighted labels.

Two readers: `load_predictor` reads a file into its `gyrodrift.learn.predictor.DriftPredictor` without importing
scikit-learn (what ``predict``, ``identify --model``, ``evaluate --model`` and ``export`` use: scikit-learn's import
is ~1.5 s of their start), `load_model` into the estimator (`gyrodrift.learn.drift_model.DriftModel`, for library use
and refits). Both run the checks below on the same numbers and give the same predictions to the bit
(tests/learn/test_predictor.py); the predictor refits no scaler of scikit-learn's but computes its numbers with the
same operations (`gyrodrift.learn.scaling`), and a file without the stored records is read by the estimator.

Loading rebuilds the model with :func:`gyrodrift.learn.drift_model.make_drift_model` from the parameters and fits it on
the training runs with the recorded tuning (no search is repeated) and the stored LSSVR solution: ``dual_coef_deg_h``
(the dual coefficients alpha, deg/h, one per training run), ``intercept_deg_h``, ``loo_residuals_deg_h`` and
``condition_number`` are taken as given (`gyrodrift.learn.lssvr.LSSVR.from_solution`, no n x n system is solved) after
a check that costs O(32 n): the coefficients sum to 0 and solve 32 rows of the LSSVM system for the recorded gamma,
sigma and the training runs to 1e-9 of their terms (an edited coefficient, intercept, gamma or run is refused).
Files without ``dual_coef_deg_h`` (written before) get the LSSVR solved again and its intercept and LOO residuals
checked against the record to 1e-9. The same code and data give the same floats, so a loaded model reproduces the
saved model's predictions to the bit (tested). Three more entries are taken as given: ``spread_theta`` (the log
hyperparameters of the interval's Gaussian process, `gyrodrift.learn.spread.SpreadGP`: no likelihood is maximised
again), ``interval_residuals_deg_h`` and ``interval_spreads_deg_h`` (the interval's calibration: nothing is
recomputed, the Gaussian process skips its leave-one-out inverse and factorises its covariance only when an interval
or spread is first asked for: `export` never does) and ``interval_disagreement_deg_h`` (the
largest LSSVR/GP disagreement over the training runs, ``DriftModel.interval_.disagreement_deg_h_``: no prediction on the
training runs). Files without them (written before) get them recomputed, the calibration with leave-one-out scores
(``calibration_folds`` 0). Floats are written with ``repr`` precision.

Schema 1 files (gyrodrift before the pipeline model: fitted internals, no training runs) are refused with a
message saying how to refit them.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gyrodrift import __version__
from gyrodrift.choices import (
    BASE_UNCERTAINTIES,
    ENCODINGS,
    METHODS,
    OBJECTIVES,
    PHYSICS_CHOICES,
    PHYSICS_COLUMNS,
    SCALINGS,
    TARGETS,
)
from gyrodrift.errors import GyrodriftError, InputError, OptionError
from gyrodrift.files.atomic import atomic_write_json, recognise_json_format
from gyrodrift.files.input_files import read_limited
from gyrodrift.learn.encodings import encode
from gyrodrift.learn.expansion import KernelExpansion
from gyrodrift.learn.interval import DriftInterval, tuning_inflation
from gyrodrift.learn.lssvm_system import IllConditionedWarning
from gyrodrift.learn.physics_base import PhysicsBase
from gyrodrift.learn.predictor import DriftPredictor
from gyrodrift.learn.ranges import InputRanges
from gyrodrift.learn.scaling import InputScaler
from gyrodrift.learn.training_record import file_column_order, training_digest
from gyrodrift.learn.tuning import TUNED_LSSVR_OPTIONS, SearchBoundWarning, TuningOptions, TuningResult
from gyrodrift.runs.table import RunTable, RunTableError

if TYPE_CHECKING:
    from gyrodrift.learn.drift_model import DriftModel

FORMAT = "gyrodrift-drift-model"
SCHEMA_VERSION = 4
READABLE_SCHEMAS = (2, 3, 4)

#: The TunedLSSVR parameters a model file keeps (``callback`` is not data): the fixed hyperparameters, the tuning
#: options (`gyrodrift.learn.tuning.TUNED_LSSVR_OPTIONS`) and the seed.
_PARAMS = ("gamma", "sigma", *TUNED_LSSVR_OPTIONS, "random_state")
_INT_PARAMS = tuple(f.name for f in fields(TuningOptions) if f.name in _PARAMS and f.type == "int")
_FLOAT_PARAMS = tuple(f.name for f in fields(TuningOptions) if f.name in _PARAMS and f.type == "float")

#: Digits beyond which an integer in a model file is refused before Python converts it (its limit is 4300).
_MAX_INT_DIGITS = 400


class ModelFileError(InputError):
    """A model file that cannot be used; the message names the file, the key and what is wrong."""


class _HugeInt:
    """Stands for an integer literal of more than ``_MAX_INT_DIGITS`` digits in a model file."""

    def __init__(self, digits: int) -> None:
        self.digits = digits


def _parse_int(text: str) -> int | _HugeInt:
    return _HugeInt(len(text.lstrip("-"))) if len(text) > _MAX_INT_DIGITS else int(text)


def _refuse_huge_ints(doc: Any, where: str) -> None:
    """Raise ModelFileError naming the key of the first integer of more than ``_MAX_INT_DIGITS`` digits.

    Iterative (a deeply nested document must not exhaust the stack twice). The keys are spelt out only for a
    document that has such an integer (a second walk): a model file's thousands of numbers cost no strings."""
    values: list[Any] = [doc]
    while values:
        value = values.pop()
        if isinstance(value, _HugeInt):
            break
        if isinstance(value, dict):
            values.extend(value.values())
        elif isinstance(value, list):
            values.extend(value)
    else:
        return
    stack: list[tuple[str, Any]] = [("", doc)]
    while stack:
        path, value = stack.pop()
        if isinstance(value, _HugeInt):
            raise ModelFileError(f"{where}: key {path or '<top>'!r} holds an integer of {value.digits} digits")
        if isinstance(value, dict):
            stack.extend((f"{path}.{k}" if path else str(k), v) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((f"{path}[{i}]", v) for i, v in enumerate(value))


def model_to_dict(model: DriftModel) -> dict:
    """The JSON-ready dict of a fitted model."""
    est = model.learner_.named_steps["lssvr"]
    params = {k: v for k, v in est.get_params().items() if k in _PARAMS}
    if not (params["random_state"] is None or isinstance(params["random_state"], int)):
        params["random_state"] = None  # a Generator's state is not kept: the recorded tuning stands for it
    params["bounds"] = [list(map(float, b)) for b in params["bounds"]]
    training = model.training_
    runs: RunTable = training["runs"]
    lssvr = model.lssvr
    return {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "gyrodrift_version": __version__,
        "encoding": model.encoding,
        "scaling": model.scaling,
        "feature_names": list(model.feature_names),
        "target": model.target,
        "physics_column": model.physics_column,
        "label_weighting": model.label_weighting,
        "calibration_folds": int(model.calibration_folds),
        "base_uncertainty": model.base_uncertainty,
        "lssvr_params": params,
        "tuning": model.tuning.to_dict() if model.tuning is not None else None,
        "fitted": {
            "gamma": float(lssvr.gamma),
            "sigma": float(lssvr.sigma),
            "intercept_deg_h": float(lssvr.intercept_),
            "dual_coef_deg_h": np.asarray(lssvr.alpha_, float).tolist(),
            "condition_number": float(lssvr.condition_number_),
            "on_search_bound": list(est.on_search_bound_),
            "loo_residuals_deg_h": np.asarray(model.loo_residuals_deg_h, float).tolist(),
            "spread_theta": np.asarray(model.interval_.spread_.theta_, float).tolist(),
            "interval_residuals_deg_h": np.asarray(model.interval_.residuals_, float).tolist(),
            "interval_spreads_deg_h": np.asarray(model.interval_.spreads_, float).tolist(),
            "interval_disagreement_deg_h": float(model.interval_.disagreement_deg_h_),
            "physics_column": model.physics_column_,
            "coefficient_prior": None if model.coefficient_prior_ is None else list(model.coefficient_prior_),
        },
        "warnings": model.fit_warnings(),
        "training": {
            "n_runs": int(training["n_runs"]),
            "sha256": training["sha256"],
            "source": training["source"],
            "weighted": bool(training.get("weighted", False)),
            "left_out": [str(r) for r in training.get("left_out", [])],
            "runs": [_in_file_order(record, runs) for record in runs.records()],
        },
    }


def _in_file_order(record: dict, runs: RunTable) -> dict:
    """A training run's record with its optional columns in `file_column_order`."""
    extra = [name for name in file_column_order(runs.extra) if name in record]
    return {key: record[key] for key in record if key not in runs.extra} | {key: record[key] for key in extra}


MODEL_FILE_RECOGNISER = recognise_json_format(FORMAT)
"""Recognises a model file: the only kind of existing file `save_model` (``fit --out``) replaces."""


def save_model(model: DriftModel, path, *, inputs=()) -> None:
    """Write ``model`` to ``path`` as JSON, atomically (an interrupted write leaves any old file intact).

    An existing ``path`` is replaced only if it is a gyrodrift model file (`MODEL_FILE_RECOGNISER`) or empty,
    and never if it is one of `inputs` (docs/outputs.md); otherwise `gyrodrift.errors.OutputError`.
    """
    atomic_write_json(model_to_dict(model), path, inputs=inputs, recognise=MODEL_FILE_RECOGNISER, what="model file")


def _need(doc: dict, key: str, kind, where: str):
    if key not in doc:
        raise ModelFileError(f"{where}: missing key {key!r}")
    value = doc[key]
    if isinstance(value, _HugeInt):
        raise ModelFileError(f"{where}: key {key!r} holds an integer of {value.digits} digits (out of range)")
    if not isinstance(value, kind) or isinstance(value, bool) and kind is not bool:
        raise ModelFileError(f"{where}: key {key!r} has the wrong type ({type(value).__name__})")
    return value


def _number(value, where: str, key: str) -> float:
    """A finite float from a JSON number; the message names the key."""
    if isinstance(value, _HugeInt):
        raise ModelFileError(f"{where}: key {key!r} holds an integer of {value.digits} digits (out of range)")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelFileError(f"{where}: key {key!r} must be a number, got {type(value).__name__}")
    try:
        out = float(value)
    except OverflowError:
        raise ModelFileError(f"{where}: key {key!r} holds an integer too large for a float") from None
    if not math.isfinite(out):
        raise ModelFileError(f"{where}: key {key!r} must be a finite number, got {out}")
    return out


def _numbers(value, where: str, key: str, n: int | None = None) -> list[float]:
    if not isinstance(value, list) or (n is not None and len(value) != n):
        expected = "a list of numbers" if n is None else f"a list of {n} numbers"
        raise ModelFileError(f"{where}: key {key!r} must be {expected}")
    return [_number(v, where, key) for v in value]


def _check_runs(value, where: str) -> list:
    """The run records must be a list of objects whose numbers are JSON numbers (no huge integers)."""
    if not isinstance(value, list):
        raise ModelFileError(f"{where}: key 'runs' must be a list of runs")
    for i, rec in enumerate(value, start=1):
        if isinstance(rec, dict):
            for key, v in rec.items():
                if isinstance(v, (_HugeInt, int)) and not isinstance(v, bool):
                    _number(v, f"{where} [run {i}]", key)
    return value


def _lssvr_params(doc: Any, where: str) -> dict:
    if not isinstance(doc, dict):
        raise ModelFileError(f"{where}: key 'lssvr_params' must be an object")
    unknown = sorted(set(doc) - set(_PARAMS))
    if unknown:
        raise ModelFileError(f"{where}: unknown key {unknown[0]!r} in 'lssvr_params'")
    pw = where + " [lssvr_params]"
    out: dict[str, Any] = {}
    for key in ("gamma", "sigma"):
        value = doc.get(key)
        out[key] = None if value is None else _number(value, pw, key)
    for key, allowed in (("objective", OBJECTIVES), ("method", METHODS)):
        out[key] = _need(doc, key, str, pw)
        if out[key] not in allowed:
            raise ModelFileError(f"{pw}: unknown {key} {out[key]!r}; expected one of {', '.join(allowed)}")
    bounds = _need(doc, "bounds", list, pw)
    if len(bounds) != 2:
        raise ModelFileError(f"{pw}: key 'bounds' must hold two [low, high] pairs")
    out["bounds"] = tuple(tuple(_numbers(b, pw, "bounds", 2)) for b in bounds)
    for key in _INT_PARAMS:
        out[key] = _need(doc, key, int, pw)
    for key in _FLOAT_PARAMS:
        out[key] = _number(_need(doc, key, (int, float), pw), pw, key)
    seed = doc.get("random_state")
    if seed is not None:
        seed = _need(doc, "random_state", int, pw)
    out["random_state"] = seed
    return out


def _tuning(doc: Any, where: str) -> TuningResult | None:
    if doc is None:
        return None
    tw = where + " [tuning]"
    if not isinstance(doc, dict):
        raise ModelFileError(f"{where}: key 'tuning' must be an object or null")
    try:
        bounds = _need(doc, "bounds", list, tw)
        if len(bounds) != 2:
            raise ModelFileError(f"{tw}: key 'bounds' must hold two [low, high] pairs")
        return TuningResult(
            gamma=_number(_need(doc, "gamma", (int, float), tw), tw, "gamma"),
            sigma=_number(_need(doc, "sigma", (int, float), tw), tw, "sigma"),
            fitness=_number(_need(doc, "fitness", (int, float), tw), tw, "fitness"),
            objective=_need(doc, "objective", str, tw),
            method=_need(doc, "method", str, tw),
            nfev=_need(doc, "nfev", int, tw),
            nit=_need(doc, "nit", int, tw),
            history=_numbers(_need(doc, "history", list, tw), tw, "history"),
            bounds=tuple(tuple(_numbers(b, tw, "bounds", 2)) for b in bounds),
            settings=_need(doc, "settings", dict, tw),
        )
    except ModelFileError:
        raise
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{where}: malformed tuning record ({exc})") from None


@dataclass(frozen=True)
class _Record:
    """A model file's document, checked (`_record`): what the estimator and the predictor are rebuilt from."""

    hybrid: dict
    encoding: str
    scaling: str
    params: dict
    tuning: TuningResult | None
    runs: RunTable
    sha: str
    left_out: list
    spread: dict
    solution: dict | None
    folds: int
    fitted: Any
    warnings: list


def _record(doc: dict, where: str) -> _Record:
    """Check a model file's document (format, schema, parameters, training runs and their digest, the stored
    records); ``ModelFileError`` naming ``where`` and the key otherwise."""
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ModelFileError(f"{where}: not a gyrodrift model file (format is not {FORMAT!r})")
    _refuse_huge_ints(doc, where)
    version = doc.get("schema_version")
    if type(version) is int and version == 1:  # not True or 1.0: a schema version is an integer
        training = doc.get("training")
        source = training.get("source", "its training table") if isinstance(training, dict) else "its training table"
        raise ModelFileError(
            f"{where}: a schema 1 model file (written by gyrodrift before 0.2: fitted internals, no training "
            f"runs), which this version ({__version__}) no longer reads; refit it with `gyrodrift fit` on "
            f"{source} (the same --encoding, --scaling and --seed give the same model)"
        )
    if type(version) is not int or version not in READABLE_SCHEMAS:
        raise ModelFileError(
            f"{where}: schema_version {version!r} is not supported by gyrodrift {__version__} "
            f"(expected one of {', '.join(map(str, READABLE_SCHEMAS))})"
        )
    # before schema 4: a concrete physics column, and the base's 1-sigma never joined the label's
    hybrid = {
        "target": "drift",
        "physics_column": "drift_inversion_deg_h",
        "label_weighting": "none",
        "base_uncertainty": "none",
    }
    if version >= 3:
        keys = [
            ("target", TARGETS),
            ("physics_column", PHYSICS_CHOICES if version >= 4 else PHYSICS_COLUMNS),
            ("label_weighting", ("auto", "none")),
        ]
        if version >= 4:
            keys.append(("base_uncertainty", BASE_UNCERTAINTIES))
        for key, allowed in keys:
            hybrid[key] = _need(doc, key, str, where)
            if hybrid[key] not in allowed:
                raise ModelFileError(f"{where}: unknown {key} {hybrid[key]!r}; expected one of {', '.join(allowed)}")
    encoding = _need(doc, "encoding", str, where)
    if encoding not in ENCODINGS:
        raise ModelFileError(f"{where}: unknown encoding {encoding!r}")
    scaling = _need(doc, "scaling", str, where)
    if scaling not in SCALINGS:
        raise ModelFileError(f"{where}: unknown scaling {scaling!r}")
    params = _lssvr_params(_need(doc, "lssvr_params", dict, where), where)
    tuning = _tuning(doc.get("tuning"), where)
    if tuning is None and params["gamma"] is None:
        raise ModelFileError(f"{where}: key 'tuning' is null but 'lssvr_params' fixes no gamma and sigma")
    tdoc = _need(doc, "training", dict, where)
    tw = where + " [training]"
    sha = _need(tdoc, "sha256", str, tw)
    source = _need(tdoc, "source", str, tw)
    try:
        runs = RunTable.from_records(_check_runs(_need(tdoc, "runs", list, tw), tw), source=f"{where} [training.runs]")
    except RunTableError as exc:
        raise ModelFileError(str(exc)) from None
    runs = runs.replace(source=source)
    left_out = tdoc.get("left_out", [])
    if not isinstance(left_out, list) or not all(isinstance(r, str) for r in left_out):
        raise ModelFileError(f"{tw}: key 'left_out' must be a list of run names")
    if training_digest(runs) != sha:
        raise ModelFileError(f"{where}: the training runs do not match their sha256 (key 'training.sha256'): edited?")
    spread = _spread_record(doc.get("fitted"), len(runs), where)
    solution = _solution_record(doc.get("fitted"), len(runs), where)
    folds = doc.get("calibration_folds", 0)  # files written before the cross-validated calibration: LOO
    if isinstance(folds, bool) or not isinstance(folds, int) or folds < 0 or folds == 1:
        raise ModelFileError(f"{where}: key 'calibration_folds' must be 0 or an integer >= 2, got {folds!r}")
    warned = doc.get("warnings", [])
    if not isinstance(warned, list) or not all(isinstance(w, str) for w in warned):
        raise ModelFileError(f"{where}: key 'warnings' must be a list of messages")
    parts = (hybrid, encoding, scaling, params, tuning, runs, sha, left_out, spread, solution, folds)
    return _Record(*parts, fitted=doc.get("fitted"), warnings=warned)


def model_from_dict(doc: dict, where: str = "<model>") -> DriftModel:
    """Rebuild the estimator from ``model_to_dict`` output (refit on its training runs with the recorded tuning and
    solution: scikit-learn is imported); ``where`` names the source."""
    from gyrodrift.learn.drift_model import make_drift_model

    rec = _record(doc, where)
    hybrid, params, runs, folds = rec.hybrid, rec.params, rec.runs, rec.folds
    try:
        model = make_drift_model(
            encoding=rec.encoding, scaling=rec.scaling, calibration_folds=folds, **hybrid, **params
        )
        with warnings.catch_warnings():
            # the file's "warnings" already say so; a loaded model does not repeat them
            warnings.simplefilter("ignore", SearchBoundWarning)
            warnings.simplefilter("ignore", IllConditionedWarning)
            model.fit(
                runs, lssvr__tuning=rec.tuning, lssvr__solution=rec.solution, training_sha256=rec.sha, **rec.spread
            )
            model.training_["left_out"] = list(rec.left_out)
    except GyrodriftError as exc:
        raise ModelFileError(
            f"{where}: the model cannot be rebuilt from its parameters and training runs: {exc}"
        ) from None
    except (ValueError, TypeError) as exc:  # scikit-learn's own parameter checks
        raise ModelFileError(f"{where}: bad model parameters: {exc}") from None
    _check_fitted(rec.fitted, model, where)
    return model


def predictor_from_dict(doc: dict, where: str = "<model>") -> DriftPredictor:
    """The predictor of ``model_to_dict`` output, without scikit-learn: the physics base resolved and the scaler fitted
    on the training runs again, the stored LSSVR solution verified (`KernelExpansion.from_stored_solution`, O(32 n)),
    the interval rebuilt from its stored hyperparameters and calibration, and the file's ``fitted`` record checked
    against all of it (`_check_fitted`), as `model_from_dict` does. A file without the stored solution and interval
    records (written before them) or with a zero label weight is rebuilt by `model_from_dict` (the estimator, which
    solves what is missing) and its ``predictor_`` returned. ``where`` names the source."""
    rec = _record(doc, where)
    interval_keys = {"spread_theta", "interval_calibration", "interval_disagreement"}
    if rec.solution is None or not interval_keys <= set(rec.spread):
        return model_from_dict(doc, where).predictor_
    try:
        predictor = _predictor(rec)
    except GyrodriftError as exc:
        raise ModelFileError(
            f"{where}: the model cannot be rebuilt from its parameters and training runs: {exc}"
        ) from None
    if predictor is None:
        return model_from_dict(doc, where).predictor_
    _check_fitted(rec.fitted, predictor, where)
    return predictor


def _predictor(rec: _Record) -> DriftPredictor | None:
    """The predictor of a checked record holding the stored solution and interval (`predictor_from_dict`), built
    as `gyrodrift.learn.drift_model.DriftModel.fit` builds its parts from the same records; None when a label weight
    is 0 (the estimator solves such a fit again)."""
    hybrid, params, runs, solution = rec.hybrid, rec.params, rec.runs, rec.solution
    assert solution is not None
    if (params["gamma"] is None) != (params["sigma"] is None):
        raise OptionError("give both gamma and sigma, or neither (then both are tuned)")
    tuned = params["gamma"] is None
    if tuned:
        assert rec.tuning is not None  # `_record` refuses a file that fixes neither
        gamma, sigma = rec.tuning.gamma, rec.tuning.sigma
    else:
        gamma, sigma = params["gamma"], params["sigma"]
    if len(runs) < 3:
        raise InputError(f"{runs.source}: need at least 3 training runs, got {len(runs)}")
    if not runs.has_truth:
        raise InputError(f"{runs.source}: every training run needs drift_deg_h")
    base = PhysicsBase(
        target=hybrid["target"],
        column=hybrid["physics_column"],
        uncertainty=hybrid["base_uncertainty"],
        label_weighting=hybrid["label_weighting"],
    ).fit(runs)
    weights = base.sample_weight_
    if weights is not None and not np.all(weights > 0):
        return None
    target = runs.drift_deg_h - base.training_base_
    encoded = encode(runs, rec.encoding)
    scaler = InputScaler.fit(rec.scaling, encoded)
    Z = scaler.transform(encoded)
    expansion = KernelExpansion.from_stored_solution(
        Z,
        target,
        gamma=gamma,
        sigma=sigma,
        alpha=solution["alpha"],
        intercept=solution["intercept"],
        sample_weight=weights,
    )
    interval = DriftInterval().fit_spread(Z, target, base.noise_std_, theta=rec.spread["spread_theta"], loo=False)
    residuals, spreads = (np.asarray(v, float) for v in rec.spread["interval_calibration"])
    interval.calibrate(
        Z,
        residuals,
        spreads,
        base.noise_var_,
        base.label_std_rms_,
        inflation=tuning_inflation(len(runs)) if tuned and rec.folds == 0 else 1.0,
        learned=expansion.predict,
        disagreement=rec.spread["interval_disagreement"],
    )
    return DriftPredictor(
        encoding=rec.encoding,
        scaling=rec.scaling,
        target=hybrid["target"],
        physics_column=hybrid["physics_column"],
        scaler=scaler,
        lssvr=expansion,
        base=base,
        interval=interval,
        ranges=InputRanges().fit(encoded, Z),
        training={
            "n_runs": len(runs),
            "sha256": rec.sha,
            "source": runs.source,
            "weighted": weights is not None,
            "runs": runs,
            "left_out": list(rec.left_out),
        },
        tuning=rec.tuning if tuned else None,
        loo_residuals_deg_h=np.asarray(solution["loo_residuals"], float),
        warnings=rec.warnings,
    )


def _solution_record(fitted: Any, n_runs: int, where: str) -> dict | None:
    """The LSSVR's stored solution (``dual_coef_deg_h``, ``intercept_deg_h``, ``loo_residuals_deg_h``,
    ``condition_number``) as ``TunedLSSVR.fit``'s ``solution``, or None for files written before it (then the LSSVR
    is solved again)."""
    if not isinstance(fitted, dict) or "dual_coef_deg_h" not in fitted:
        return None
    fw = where + " [fitted]"
    return {
        "alpha": _numbers(_need(fitted, "dual_coef_deg_h", list, fw), fw, "dual_coef_deg_h", n_runs),
        "intercept": _number(_need(fitted, "intercept_deg_h", (int, float), fw), fw, "intercept_deg_h"),
        "loo_residuals": _numbers(_need(fitted, "loo_residuals_deg_h", list, fw), fw, "loo_residuals_deg_h", n_runs),
        "condition_number": _number(_need(fitted, "condition_number", (int, float), fw), fw, "condition_number"),
    }


def _spread_record(fitted: Any, n_runs: int, where: str) -> dict:
    """``spread_theta`` and the interval's calibration of the file's ``fitted`` record, as `DriftModel.fit` keywords
    (none for files written before them: the spread model is then fitted again, deterministically)."""
    if not isinstance(fitted, dict):
        return {}
    fw = where + " [fitted]"
    out: dict[str, Any] = {}
    if "spread_theta" in fitted:
        out["spread_theta"] = _numbers(_need(fitted, "spread_theta", list, fw), fw, "spread_theta")
    keys = ("interval_residuals_deg_h", "interval_spreads_deg_h")
    if any(k in fitted for k in keys):
        out["interval_calibration"] = tuple(_numbers(_need(fitted, k, list, fw), fw, k, n_runs) for k in keys)
        if min(out["interval_calibration"][1]) < 0:
            raise ModelFileError(f"{fw}: key 'interval_spreads_deg_h' must hold spreads >= 0")
    if "interval_disagreement_deg_h" in fitted:
        key = "interval_disagreement_deg_h"
        out["interval_disagreement"] = _number(_need(fitted, key, (int, float), fw), fw, key)
        if out["interval_disagreement"] < 0:
            raise ModelFileError(f"{fw}: key {key!r} must be >= 0")
    return out


def _check_fitted(fitted: Any, model: DriftModel | DriftPredictor, where: str) -> None:
    """The file's ``fitted`` record must describe the rebuilt model: gamma and sigma exactly, the intercept and
    the LOO residuals to 1e-9 relative (another BLAS may round differently); else the file was edited."""
    if fitted is None:
        return
    fw = where + " [fitted]"
    if not isinstance(fitted, dict):
        raise ModelFileError(f"{where}: key 'fitted' must be an object")
    lssvr = model.lssvr
    if "physics_column" in fitted and fitted["physics_column"] != model.physics_column_:
        raise ModelFileError(
            f"{fw}: key 'physics_column' ({fitted['physics_column']!r}) differs from the base the model resolves on "
            f"its training runs ({model.physics_column_!r}): edited?"
        )
    if "coefficient_prior" in fitted:
        raw = fitted["coefficient_prior"]
        got = None if raw is None else tuple(_numbers(raw, fw, "coefficient_prior", 2))
        if got != model.coefficient_prior_:
            raise ModelFileError(
                f"{fw}: key 'coefficient_prior' ({raw!r}) differs from the fleet k_z prior pooled from the training "
                f"runs ({model.coefficient_prior_!r}): edited?"
            )
    for key, value in (("gamma", lssvr.gamma), ("sigma", lssvr.sigma)):
        if key in fitted and _number(fitted[key], fw, key) != float(value):
            raise ModelFileError(f"{fw}: key {key!r} ({fitted[key]!r}) differs from the model's {value!r}")
    checks = (
        ("intercept_deg_h", np.atleast_1d(float(lssvr.intercept_))),
        ("loo_residuals_deg_h", np.asarray(model.loo_residuals_deg_h, float)),
    )
    for key, expected in checks:
        if key not in fitted:
            continue
        raw = fitted[key]
        values = np.atleast_1d(_numbers(raw, fw, key) if isinstance(raw, list) else _number(raw, fw, key))
        if values.shape != expected.shape:
            raise ModelFileError(f"{fw}: key {key!r} has {values.size} values, the model {expected.size}")
        scale = float(np.max(np.abs(expected))) or 1.0
        if not np.allclose(values, expected, rtol=1e-9, atol=1e-12 * scale):
            raise ModelFileError(f"{fw}: key {key!r} differs from the model rebuilt from the file (edited?)")


MAX_MODEL_BYTES = 1 << 30
"""Largest model file read [bytes] (its training runs take a few hundred bytes each)."""


def load_model(path) -> DriftModel:
    """Read a model file written by ``save_model`` into the estimator (`model_from_dict`: scikit-learn is imported,
    for library use and refits); clear ``ModelFileError`` for anything else."""
    path = Path(path)
    return model_from_dict(_read_document(path), str(path))


def load_predictor(path) -> DriftPredictor:
    """Read a model file written by ``save_model`` into its predictor (`predictor_from_dict`: no scikit-learn), what
    ``predict``, ``identify --model``, ``evaluate --model`` and ``export`` use; clear ``ModelFileError`` for anything
    else."""
    path = Path(path)
    return predictor_from_dict(_read_document(path), str(path))


def _read_document(path: Path) -> Any:
    """The JSON document of a model file (size-limited, a device or FIFO refused); ``ModelFileError`` naming the
    file, the line and the column of bad JSON."""
    try:
        raw = read_limited(path, MAX_MODEL_BYTES)  # a device or FIFO is refused, never read or waited on
        if len(raw) > MAX_MODEL_BYTES:
            raise ModelFileError(f"{path}: more than {MAX_MODEL_BYTES} bytes; not a model file")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot read: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ModelFileError(f"{path}: not a text file (expected JSON)") from None
    try:
        doc = json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"{path}: corrupted JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise ModelFileError(f"{path}: JSON nested too deeply (not a model file)") from None
    except ValueError as exc:  # e.g. Python's limit on integer digits
        raise ModelFileError(f"{path}: unreadable JSON: {exc}") from None
    return doc
