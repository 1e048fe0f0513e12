"""Model files: versioned JSON holding everything a prediction needs. Never pickle.

Layout (``schema_version`` 1)::

    {"format": "gyrodrift-drift-model", "schema_version": 1, "gyrodrift_version": "...",
     "encoding": "temp_range", "feature_names": [...],
     "scaler": {"kind": "standard", ...sklearn fitted attributes...},
     "lssvr": {"kernel": "rbf", "gamma": ..., "sigma": ..., "degree": ..., "coef0": ...,
               "support_vectors": [[...]], "alpha": [...], "intercept": ...},
     "training": {"n_runs": ..., "sha256": ..., "source": ...},
     "loo_residuals_deg_h": [...] (optional: leave-one-out residuals on the training runs, for intervals),
     "tuning": {...} or null}

``support_vectors`` are the training inputs after scaling. Floats are written with ``repr`` precision, so a
loaded model reproduces the saved model's predictions to the bit.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler

from gyrodrift import __version__
from gyrodrift.atomic import atomic_write_json
from gyrodrift.choices import SCALINGS
from gyrodrift.encodings import ENCODINGS, feature_names
from gyrodrift.errors import InputError
from gyrodrift.lssvr import LSSVR
from gyrodrift.model import DriftModel
from gyrodrift.tuning import TuningResult

FORMAT = "gyrodrift-drift-model"
SCHEMA_VERSION = 1

_SCALER_ATTRS = {
    "standard": ("mean_", "var_", "scale_"),
    "minmax": ("min_", "scale_", "data_min_", "data_max_", "data_range_"),
}


class ModelFileError(InputError):
    """A model file that cannot be used; the message names the file and what is wrong."""


def model_to_dict(model: DriftModel) -> dict:
    """The JSON-ready dict of a fitted model."""
    scaler = model.pipeline.named_steps["scale"]
    scaler_doc: dict = {"kind": model.scaling}
    for attr in _SCALER_ATTRS.get(model.scaling, ()):
        scaler_doc[attr] = np.asarray(getattr(scaler, attr), float).tolist()
    if model.scaling != "none":
        scaler_doc["n_samples_seen"] = int(scaler.n_samples_seen_)
    est = model.lssvr
    return {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "gyrodrift_version": __version__,
        "encoding": model.encoding,
        "feature_names": list(model.feature_names),
        "scaler": scaler_doc,
        "lssvr": {
            "kernel": est.kernel,
            "gamma": float(est.gamma),
            "sigma": float(est.sigma),
            "degree": est.degree,
            "coef0": float(est.coef0),
            "support_vectors": np.asarray(est.X_fit_, float).tolist(),
            "alpha": np.asarray(est.alpha_, float).tolist(),
            "intercept": float(est.intercept_),
        },
        "training": dict(model.training),
        "loo_residuals_deg_h": (
            None if model.loo_residuals_deg_h is None else np.asarray(model.loo_residuals_deg_h, float).tolist()
        ),
        "tuning": model.tuning.to_dict() if model.tuning is not None else None,
    }


def save_model(model: DriftModel, path) -> None:
    """Write ``model`` to ``path`` as JSON, atomically (an interrupted write leaves any old file intact)."""
    atomic_write_json(model_to_dict(model), path)


def _need(doc: dict, key: str, kind, where: str):
    if key not in doc:
        raise ModelFileError(f"{where}: missing key {key!r}")
    value = doc[key]
    if not isinstance(value, kind) or isinstance(value, bool) and kind is not bool:
        raise ModelFileError(f"{where}: key {key!r} has the wrong type ({type(value).__name__})")
    return value


def _floats(value, where: str, key: str, shape=None) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ModelFileError(f"{where}: key {key!r} must hold numbers") from None
    if shape is not None and arr.shape != shape:
        raise ModelFileError(f"{where}: key {key!r} has shape {arr.shape}, expected {shape}")
    if not np.all(np.isfinite(arr)):
        raise ModelFileError(f"{where}: key {key!r} holds non-finite values")
    return arr


def model_from_dict(doc: dict, where: str = "<model>") -> DriftModel:
    """Rebuild a model from ``model_to_dict`` output; ``where`` names the source in errors."""
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ModelFileError(f"{where}: not a gyrodrift model file (format is not {FORMAT!r})")
    version = doc.get("schema_version")
    if version != SCHEMA_VERSION:
        raise ModelFileError(
            f"{where}: schema_version {version!r} is not supported by gyrodrift {__version__} "
            f"(expected {SCHEMA_VERSION})"
        )
    encoding = _need(doc, "encoding", str, where)
    if encoding not in ENCODINGS:
        raise ModelFileError(f"{where}: unknown encoding {encoding!r}")
    n_feat = len(feature_names(encoding))
    sdoc = _need(doc, "scaler", dict, where)
    kind = _need(sdoc, "kind", str, where + " [scaler]")
    if kind not in SCALINGS:
        raise ModelFileError(f"{where}: unknown scaler kind {kind!r}")
    if kind == "none":
        scaler = "passthrough"
    else:
        scaler = StandardScaler() if kind == "standard" else MinMaxScaler()
        for attr in _SCALER_ATTRS[kind]:
            setattr(scaler, attr, _floats(_need(sdoc, attr, list, where + " [scaler]"), where, attr, (n_feat,)))
        if np.any(np.asarray(scaler.scale_) == 0.0):
            raise ModelFileError(f"{where}: key 'scale_' of the scaler holds a zero")
        scaler.n_features_in_ = n_feat
        scaler.n_samples_seen_ = int(_need(sdoc, "n_samples_seen", int, where + " [scaler]"))
    ldoc = _need(doc, "lssvr", dict, where)
    lw = where + " [lssvr]"
    sv = _floats(_need(ldoc, "support_vectors", list, lw), where, "support_vectors")
    if sv.ndim != 2 or sv.shape[1] != n_feat or sv.shape[0] < 2:
        raise ModelFileError(f"{where}: support_vectors has shape {sv.shape}, expected (n >= 2, {n_feat})")
    alpha = _floats(_need(ldoc, "alpha", list, lw), where, "alpha", (sv.shape[0],))
    intercept = float(_floats(_need(ldoc, "intercept", (int, float), lw), where, "intercept"))
    try:
        est = LSSVR(
            gamma=float(_need(ldoc, "gamma", (int, float), lw)),
            sigma=float(_need(ldoc, "sigma", (int, float), lw)),
            kernel=_need(ldoc, "kernel", str, lw),
            degree=_need(ldoc, "degree", int, lw),
            coef0=float(_need(ldoc, "coef0", (int, float), lw)),
        )
    except ValueError as exc:
        raise ModelFileError(f"{where}: {exc}") from None
    if not (est.gamma > 0 and est.sigma > 0 and np.isfinite(est.gamma) and np.isfinite(est.sigma)):
        raise ModelFileError(f"{where}: gamma and sigma must be positive, got {est.gamma} and {est.sigma}")
    if est.kernel not in ("rbf", "linear", "poly", "polynomial"):
        raise ModelFileError(f"{where}: unknown kernel {est.kernel!r}")
    if est.degree < 1:
        raise ModelFileError(f"{where}: key 'degree' must be a whole number >= 1, got {est.degree}")
    est.X_fit_ = sv
    est.alpha_ = alpha
    est.intercept_ = intercept
    est.n_features_in_ = n_feat
    tdoc = doc.get("tuning")
    tuning = None
    if tdoc is not None:
        try:
            tuning = TuningResult(**{**tdoc, "bounds": tuple(tuple(b) for b in tdoc["bounds"])})
        except (TypeError, KeyError) as exc:
            raise ModelFileError(f"{where}: malformed tuning record ({exc})") from None
    training = doc.get("training") or {}
    if not isinstance(training, dict):
        raise ModelFileError(f"{where}: key 'training' must be an object, got {type(training).__name__}")
    loo = doc.get("loo_residuals_deg_h")
    if loo is not None:
        loo = _floats(loo, where, "loo_residuals_deg_h", (sv.shape[0],))
    return DriftModel(
        encoding=encoding,
        scaling=kind,
        pipeline=Pipeline([("scale", scaler), ("lssvr", est)]),
        tuning=tuning,
        training=training,
        loo_residuals_deg_h=loo,
    )


def load_model(path) -> DriftModel:
    """Read a model file written by ``save_model``; clear ``ModelFileError`` for anything else."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot read: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ModelFileError(f"{path}: not a text file (expected JSON)") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"{path}: corrupted JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    return model_from_dict(doc, str(path))
