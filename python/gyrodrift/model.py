"""The drift model: encoding of a run, input scaling and an LSSVR, fitted and used as one object.

``fit_drift_model`` is what ``gyrodrift fit`` and ``gyrodrift reproduce`` call: it encodes the training
runs, fits the scaler on them, tunes (gamma, sigma) unless given, and fits the LSSVR. Predictions are axial
drifts in deg/h, the total constant to subtract from the z-gyro output (measured - estimate).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field

import numpy as np
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler

from gyrodrift.choices import SCALINGS
from gyrodrift.encodings import encode, feature_names
from gyrodrift.lssvr import LSSVR
from gyrodrift.progress import progress
from gyrodrift.runs import RunTable
from gyrodrift.tuning import DEFAULT_BOUNDS, TuningResult, tune_lssvr


def make_scaler(scaling: str):
    """The scikit-learn transformer for a scaling name (``"passthrough"`` for none)."""
    if scaling == "standard":
        return StandardScaler()
    if scaling == "minmax":
        return MinMaxScaler()
    if scaling == "none":
        return "passthrough"
    raise ValueError(f"unknown scaling {scaling!r}; expected one of {', '.join(SCALINGS)}")


def training_digest(runs: RunTable) -> str:
    """SHA-256 of the training runs' values (run, latitudes, temperatures, drift), order included."""
    canon = json.dumps(
        [
            [str(r), repr(float(a)), repr(float(b)), repr(float(c)), repr(float(d)), repr(float(e))]
            for r, a, b, c, d, e in zip(
                runs.run, runs.lat_deg, runs.lat0_deg, runs.temp_min_c, runs.temp_max_c, runs.drift_deg_h, strict=False
            )
        ]
    )
    return hashlib.sha256(canon.encode()).hexdigest()


def jackknife_half_width(residuals, coverage: float) -> float:
    """Half-width of the jackknife prediction interval from leave-one-out residuals [their unit].

    The ceil((n + 1) coverage)-th smallest |r_i| (Barber, Candes, Ramdas, Tibshirani 2021, "Predictive
    inference with the jackknife+", the plain jackknife interval): for exchangeable runs the interval
    prediction +- half-width covers a new run's true value with probability of about ``coverage`` (the
    guarantee of the plain jackknife is weaker than jackknife+'s, but it needs no refit per left-out run).
    ``inf`` when n is too small for the coverage asked (n < coverage / (1 - coverage)).
    """
    if not 0.0 < coverage < 1.0:
        raise ValueError(f"coverage must be within (0, 1), got {coverage}")
    r = np.sort(np.abs(np.asarray(residuals, float)))
    if r.size == 0 or not np.all(np.isfinite(r)):
        raise ValueError("need finite leave-one-out residuals for an interval")
    k = math.ceil((r.size + 1) * coverage)
    return float(r[k - 1]) if k <= r.size else math.inf


def min_runs_for_coverage(coverage: float) -> int:
    """Smallest number of leave-one-out residuals for which ``jackknife_half_width`` is finite."""
    if not 0.0 < coverage < 1.0:
        raise ValueError(f"coverage must be within (0, 1), got {coverage}")
    n = 1
    while math.ceil((n + 1) * coverage) > n:
        n += 1
    return n


def _tick(bar, callback, intermediate_result):
    bar.update(1)
    return callback(intermediate_result) if callback is not None else None


@dataclass
class DriftModel:
    """A fitted axial-drift model.

    Attributes
    ----------
    encoding : str
        How a run becomes an input vector (see ``gyrodrift.encodings.ENCODINGS``).
    scaling : str
        Input scaling fitted on the training runs (``SCALINGS``).
    pipeline : sklearn Pipeline
        ``scale`` then ``lssvr``; its input is ``encode(runs, encoding)``.
    tuning : TuningResult or None
        How gamma and sigma were chosen (None when given by the user).
    training : dict
        ``n_runs``, ``sha256`` (``training_digest``) and ``source`` of the training data.
    loo_residuals_deg_h : ndarray or None
        Closed-form leave-one-out residuals on the training runs [deg/h] (true minus left-out prediction),
        kept with the model (and in its file) so that intervals need no refactorisation.
    """

    encoding: str
    scaling: str
    pipeline: Pipeline
    tuning: TuningResult | None = None
    training: dict = field(default_factory=dict)
    loo_residuals_deg_h: np.ndarray | None = None

    @property
    def lssvr(self) -> LSSVR:
        return self.pipeline.named_steps["lssvr"]

    @property
    def feature_names(self) -> tuple[str, ...]:
        return feature_names(self.encoding)

    def predict(self, runs: RunTable) -> np.ndarray:
        """Identified axial drift [deg/h] for each run."""
        return self.pipeline.predict(encode(runs, self.encoding))

    def loo_residuals(self) -> np.ndarray:
        """Closed-form leave-one-out residuals on the training runs [deg/h] (true minus left-out prediction).

        The scaler is not refitted per left-out run; with 20+ runs its effect on the residuals is small.
        """
        if self.loo_residuals_deg_h is not None:
            return np.array(self.loo_residuals_deg_h, float)
        return self.lssvr.loo_residuals()

    def predict_interval(self, runs: RunTable, coverage: float = 0.9) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Identified drift and its jackknife interval [deg/h]: ``(pred, lo, hi)``.

        An empirical interval from the model's leave-one-out residuals (``jackknife_half_width``), valid for
        runs exchangeable with the training runs; it is not a Bayesian posterior (the LSSVR has none). When
        gamma and sigma were tuned on the LOO error, the same residuals were minimised by the tuning, so the
        interval is slightly optimistic (tests/test_intervals.py measures about nominal coverage with 40 runs).
        """
        pred = self.predict(runs)
        half = jackknife_half_width(self.loo_residuals(), coverage)
        return pred, pred - half, pred + half


def fit_drift_model(
    train: RunTable,
    *,
    encoding: str = "temp_range",
    scaling: str = "standard",
    objective: str = "loo_mae",
    method: str = "cpso",
    gamma: float | None = None,
    sigma: float | None = None,
    bounds=DEFAULT_BOUNDS,
    n_particles: int = 30,
    max_iter: int = 100,
    chaos_steps: int = 10,
    rng=None,
    quiet: bool = True,
    callback=None,
) -> DriftModel:
    """Fit a drift model on runs with known drift.

    With ``gamma`` and ``sigma`` both given no tuning is done; otherwise they are tuned by ``method``
    (``cpso``, ``pso`` or ``grid``) on ``objective`` (``loo_mae``, ``train_mae``, ``kfold_mae``), with a
    progress bar unless ``quiet``. ``sigma`` is in scaled input units. ``callback(intermediate_result)``,
    if given, is called once per tuning iteration as well (e.g. to drive an outer progress bar).
    """
    if not train.has_truth:
        raise ValueError(f"{train.source}: every training run needs drift_deg_h")
    if len(train) < 3:
        raise ValueError(f"{train.source}: need at least 3 training runs, got {len(train)}")
    X = encode(train, encoding)
    y = np.asarray(train.drift_deg_h, float)
    scaler = make_scaler(scaling)
    Xs = X if scaler == "passthrough" else scaler.fit(X).transform(X)
    tuning = None
    if (gamma is None) != (sigma is None):
        raise ValueError("give both gamma and sigma, or neither (then both are tuned)")
    if gamma is None:
        with progress(max_iter if method != "grid" else 1, f"tuning ({method}, {objective})", quiet, unit="it") as bar:
            tuning = tune_lssvr(
                Xs,
                y,
                objective=objective,
                method=method,
                bounds=bounds,
                n_particles=n_particles,
                max_iter=max_iter,
                chaos_steps=chaos_steps,
                rng=rng,
                callback=lambda res: _tick(bar, callback, res),
            )
        gamma, sigma = tuning.gamma, tuning.sigma
    lssvr = LSSVR(gamma=gamma, sigma=sigma).fit(Xs, y)
    pipeline = Pipeline([("scale", scaler), ("lssvr", lssvr)])
    return DriftModel(
        encoding=encoding,
        scaling=scaling,
        pipeline=pipeline,
        tuning=tuning,
        training={"n_runs": len(train), "sha256": training_digest(train), "source": train.source},
        loo_residuals_deg_h=lssvr.loo_residuals(),
    )
