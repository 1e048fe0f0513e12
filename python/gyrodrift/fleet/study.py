"""The accuracy study of a campaign: every identification method on the same held-out runs.

`run_study(df)` takes the runs of a campaign (`gyrodrift.fleet.store.read_runs`), splits them by run into
training and held-out runs (seeded), fits the learned methods on the training runs and evaluates every method
on the held-out ones:

* LSSVM tuned by CPSO on the paper's fitness (training MAE, eq. 16) and on the closed-form LOO MAE, by plain
  PSO and by a log grid (LOO MAE), all on the default ``physics`` encoding, label = the 72 h truth;
* Gaussian-process regression (scikit-learn, RBF + white noise, same inputs), a linear model (least squares,
  same inputs);
* the 12 h physics inversion, the 12 h curve fit, the alignment's own z estimate (no training);
* the hybrid default: ``gyrodrift fit``'s defaults (residual target on the physics base its ``physics_column``
  default ``auto`` picks, the hybrid's default encoding ``default_encoding("residual")``, CPSO on the LOO MAE,
  flagged labels and labels with a 1-sigma above ``DEFAULT_MAX_LABEL_STD_DEG_H`` left out), except the study's
  ``max_iter``; the row's note names its inputs and the base it resolved to;
* the 16 h smoother, when the campaign holds its column (`gyrodrift.procedure.smoother`);
* the 16 h smoother with the training fleet's k_z prior (``FLEET_ROW``): the training runs' thermal coefficients
  pooled (`gyrodrift.learn.fleet_prior.pooled_coefficient_prior`) and each held-out run's end drift re-weighted by
  that prior (`gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`; runs under the smoother's constant model pass
  unchanged), its interval the re-weighted 1-sigma; unavailable (a note says why) when fewer than two training
  runs carry a thermal k_z, e.g. a campaign stored before those columns existed.

Metrics (deg/h): RMS and max identification error against the simulated effective drift (the truth of the
run's noise-free twin) and against the 72 h truth of the noisy run; the share of held-out runs under 1 nmi at
hour 72 after compensating each method's estimate, and under 1 nmi over the whole 72 h, from the run's
stored linear error curves (`gyrodrift.fleet.store.linear_error_nmi`: no navigation); the coverage of nominal
90 % intervals (methods that give one). The physical-limit line is the smoother's 1-sigma over the same
held-out runs (RMS of the per-run sigmas; each method's RMS is also given as a ratio to it); NaN when the
campaign has no smoother column.

Drift laws (issue 21, `gyrodrift.fleet.law_study`): the uncompensated run, the hybrid default's constant, the law
`identify` makes of it (k1 from the smoother's k_z with the hybrid's fleet prior), the offline best constant and the
offline best law, compared by the 72 h error of the held-out runs (all, with a daily swing, without, and at a
steady temperature): ``StudyResult.drift_laws``, None (with a note) when the campaign has no k1 curves.

Curves: RMS error vs training-set size (10 .. all training runs, refitting the learned methods on nested
subsets), vs noise grade, vs site latitude (held-out runs grouped). The figures and the HTML report are in
`gyrodrift.fleet.study_report`; this module computes numbers only.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.errors import InputError, OptionError
from gyrodrift.fleet.law_study import smoother_posterior_inputs
from gyrodrift.runs.table import SMOOTHER_THERMAL_COLUMNS

__all__ = ["COVERAGE", "FLEET_ROW", "MethodResult", "StudyResult", "run_study", "split_runs"]

COVERAGE = 0.9
"""Nominal coverage of the intervals compared [-]."""
Z90 = 1.6448536269514722
ONE_NMI = 1.0
LEARNED = ("CPSO-LSSVM (LOO)", "GP regression", "linear model", "hybrid default")
"""Methods refitted for the training-size curve (the others are fixed or cost more per fit; the fleet-prior
smoother's prior is pooled again from each subset)."""
FLEET_ROW = "16 h smoother, fleet k_z prior"
"""The smoother's end drift with the training runs' pooled thermal coefficient as prior (module docstring)."""
THERMAL = SMOOTHER_THERMAL_COLUMNS
"""The smoother's thermal columns of a campaign run (`gyrodrift.runs.table.SMOOTHER_THERMAL_COLUMNS`)."""


@dataclass
class MethodResult:
    """One method on the held-out runs: estimates [deg/h], optional 90 % interval, metrics (`metrics`)."""

    name: str
    pred: np.ndarray
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None
    metrics: dict[str, float] = field(default_factory=dict)
    note: str = ""


@dataclass
class StudyResult:
    """Everything the report shows; `to_dict` is its JSON."""

    n_runs: int
    n_failed: int
    n_train: int
    n_test: int
    test_fraction: float
    seed: int
    methods: dict[str, MethodResult]
    limit_deg_h: float
    label_error_rms: float
    train_size: dict[str, Any]
    by_grade: dict[str, Any]
    by_latitude: dict[str, Any]
    test_runs: list[str]
    notes: list[str]
    drift_laws: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        def num(x):
            return None if x is None or (isinstance(x, float) and not math.isfinite(x)) else x

        def clean(obj):
            if isinstance(obj, dict):
                return {str(k): clean(v) for k, v in obj.items()}
            if isinstance(obj, list | tuple | np.ndarray):
                return [clean(v) for v in obj]
            if isinstance(obj, np.floating | float):
                return num(float(obj))
            if isinstance(obj, np.integer):
                return int(obj)
            return obj

        return clean(
            {
                "format": "gyrodrift-study/1",
                "n_runs": self.n_runs,
                "n_failed": self.n_failed,
                "n_train": self.n_train,
                "n_test": self.n_test,
                "test_fraction": self.test_fraction,
                "seed": self.seed,
                "physical_limit_deg_h": self.limit_deg_h,
                "label_error_rms_deg_h": self.label_error_rms,
                "methods": {
                    n: {"metrics": m.metrics, "note": m.note, "pred_deg_h": m.pred} for n, m in self.methods.items()
                },
                "drift_laws": self.drift_laws,
                "test_runs": self.test_runs,
                "train_size": self.train_size,
                "by_grade": self.by_grade,
                "by_latitude": self.by_latitude,
                "notes": self.notes,
            }
        )


def split_runs(n: int, test_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices (into the run list) of the training and held-out runs: a seeded permutation, by run."""
    if not (isinstance(test_fraction, float | int) and 0 < test_fraction < 1):
        raise OptionError(f"--test-fraction must be strictly between 0 and 1, got {test_fraction!r}")
    n_test = int(round(n * test_fraction))
    if n_test < 2 or n - n_test < 10:
        raise InputError(
            f"{n} successful run(s) give {n - n_test} training and {n_test} held-out runs; the study needs at least "
            "10 training and 2 held-out runs (more runs or another --test-fraction)"
        )
    perm = np.random.default_rng(seed).permutation(n)
    return np.sort(perm[n_test:]), np.sort(perm[:n_test])


def _rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x**2))) if len(x) else math.nan


def _column(runs, name: str) -> np.ndarray:
    """A numeric column of campaign runs [its unit], all NaN when the store has no such column."""
    return runs.numbers(name) if name in runs.columns else np.full(len(runs), math.nan)


def _fleet_prior(train_runs) -> tuple[float, float] | str:
    """The pooled k_z prior (mean, 1-sigma) [deg/h/degC] of the training runs, or why there is none."""
    from gyrodrift.learn.fleet_prior import pooled_coefficient_prior

    try:
        return pooled_coefficient_prior(_column(train_runs, THERMAL[0]), _column(train_runs, THERMAL[1]))
    except InputError as exc:
        return str(exc)


def _with_fleet_prior(test_runs, prior: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """The held-out runs' smoother end drift and 1-sigma [deg/h] re-weighted by the k_z prior ``(mean, std)``."""
    from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior

    d, s = drift_with_coefficient_prior(*smoother_posterior_inputs(test_runs), prior[0], prior[1])
    return np.atleast_1d(np.asarray(d, float)), np.atleast_1d(np.asarray(s, float))


def _fit_learned(name: str, train, *, seed: int, max_iter: int):
    """A fitted learned method; returns ``(predict, note, prior)``: ``predict(table) -> (pred, lo | None, hi |
    None)``, what the fit chose that the name does not say (the hybrid's physics base), or "", and the model's fleet
    k_z prior ``(mean, std)`` [deg/h/degC] when its physics base is the fleet one (`identify`'s law takes its k1
    from it), else None."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
    from sklearn.linear_model import LinearRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    from gyrodrift.choices import default_encoding
    from gyrodrift.learn.drift_model import DEFAULT_MAX_LABEL_STD_DEG_H, fit_drift_model
    from gyrodrift.learn.encodings import encode

    common: dict[str, Any] = dict(encoding="physics", rng=seed, quiet=True, max_iter=max_iter)
    specs: dict[str, dict[str, Any]] = {
        "CPSO-LSSVM (paper fitness)": dict(method="cpso", objective="train_mae"),
        "CPSO-LSSVM (LOO)": dict(method="cpso", objective="loo_mae"),
        "PSO-LSSVM (LOO)": dict(method="pso", objective="loo_mae"),
        "grid-LSSVM (LOO)": dict(method="grid", objective="loo_mae"),
        # `gyrodrift fit`'s defaults: its physics column default (auto), the hybrid's encoding, its label limit
        "hybrid default": dict(
            method="cpso",
            objective="loo_mae",
            target="residual",
            encoding=default_encoding("residual"),
            max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H,
        ),
    }
    if name in specs:
        model = fit_drift_model(train, **{**common, **specs[name]})

        def predict(t):
            return model.predict_interval(t, COVERAGE)

        note = ""
        if model.target == "residual":
            note = f"inputs {model.encoding}, physics base {model.physics_column_}"
            if model.coefficient_prior_ is not None:
                prior = model.coefficient_prior_
                note += f" (pooled k_z prior {prior[0]:.3e} +- {prior[1]:.3e} deg/h/degC)"
        return predict, note, model.coefficient_prior_
    X = encode(train, "physics")
    y = train.drift_deg_h
    if name == "linear model":
        lin = make_pipeline(StandardScaler(), LinearRegression()).fit(X, y)
        return (lambda t: (lin.predict(encode(t, "physics")), None, None)), "", None
    if name == "GP regression":
        scale = float(np.std(y)) or 1e-3
        kernel = ConstantKernel(1.0) * RBF(length_scale=np.ones(X.shape[1])) + WhiteKernel(0.1)
        from sklearn.exceptions import ConvergenceWarning

        with warnings.catch_warnings():  # a length scale at its bound: that input does not matter; not news
            warnings.simplefilter("ignore", ConvergenceWarning)
            gp = make_pipeline(
                StandardScaler(),
                GaussianProcessRegressor(kernel=kernel, normalize_y=True, n_restarts_optimizer=2, random_state=seed),
            ).fit(X, y / scale)

        def predict_gp(t):
            mean, std = gp.predict(encode(t, "physics"), return_std=True)
            return mean * scale, (mean - Z90 * std) * scale, (mean + Z90 * std) * scale

        return predict_gp, "", None
    raise ValueError(name)


def _metrics(m: MethodResult, test_runs, effective, truth, limit: float) -> dict[str, float]:
    e_eff, e_tru = effective - m.pred, truth - m.pred
    err = test_runs.errors_nmi(m.pred)
    finals, maxima = err[:, -1], np.nanmax(err, axis=1)
    out = {
        "rms_eff": _rms(e_eff),
        "max_eff": float(np.max(np.abs(e_eff))),
        "bias_eff": float(np.mean(e_eff)),
        "rms_truth": _rms(e_tru),
        "max_truth": float(np.max(np.abs(e_tru))),
        "under_1nmi_final": float(np.mean(np.asarray(finals) < ONE_NMI)),
        "under_1nmi_72h": float(np.mean(np.asarray(maxima) < ONE_NMI)),
        "ratio_to_limit": _rms(e_eff) / limit if limit > 0 else math.nan,
    }
    if m.lo is not None and m.hi is not None:
        out["coverage_eff"] = float(np.mean((m.lo <= effective) & (effective <= m.hi)))
        out["coverage_truth"] = float(np.mean((m.lo <= truth) & (truth <= m.hi)))
    return out


def run_study(
    runs,
    *,
    test_fraction: float = 0.3,
    seed: int = 0,
    max_iter: int = 60,
    train_sizes: list[int] | None = None,
    latitude_bins: int = 4,
    campaign=None,
) -> StudyResult:
    """The study on a campaign's runs (`gyrodrift.fleet.store.read_runs`, curves included); see the module doc.

    `max_iter`: tuning iterations of every CPSO/PSO fit; `train_sizes`: the training-set sizes of the curve
    (default 10, 20, 40, ... and all); `latitude_bins`: held-out runs grouped in this many latitude quantiles;
    `campaign`: the runs' `gyrodrift.fleet.spec.Campaign` (its simulated drift laws for the drift laws' physical
    limit, `gyrodrift.fleet.law_limit`), or None."""
    from gyrodrift.fleet.run_table import run_table
    from gyrodrift.learn.baselines import physics_inversion
    from gyrodrift.learn.interval import IntervalOutlierWarning
    from gyrodrift.learn.tuning import SearchBoundWarning

    n_all = len(runs)
    ok = runs.select(runs.ok)
    notes: list[str] = []
    if n_all - len(ok):
        notes.append(f"{n_all - len(ok)} failed run(s) left out (their errors are in the campaign's rows)")
    hours = set(np.round(ok.numbers("hours_truth"), 6))
    if len(hours) > 1:
        raise InputError(f"the runs were navigated over different truth spans ({sorted(hours)} h)")
    if "label_flagged" in ok.columns:
        flagged = int(np.sum([bool(v) for v in ok["label_flagged"]]))
        if flagged:
            notes.append(f"{flagged} run(s) have a truth label beyond the 1 nmi / 72 h budget (label_flagged)")
    tr_idx, te_idx = split_runs(len(ok), test_fraction, seed)
    table = run_table(ok, source="campaign")
    train, test = table.select(tr_idx), table.select(te_idx)
    test_df = ok.select(te_idx)
    effective = test_df.numbers("drift_effective_deg_h")
    truth = test_df.numbers("drift_deg_h")
    smoother_std = test_df.numbers("drift_smoother_std_deg_h")
    has_smoother = bool(np.all(np.isfinite(test_df.numbers("drift_smoother_deg_h"))))
    limit = _rms(smoother_std) if has_smoother and np.all(np.isfinite(smoother_std)) else math.nan
    if not has_smoother:
        notes.append(
            "no 16 h smoother estimates in this campaign (gyrodrift.procedure.smoother was not available when it "
            "ran): the smoother row and the physical-limit line are missing"
        )
    methods: dict[str, MethodResult] = {}
    priors: dict[str, tuple[float, float] | None] = {}
    learned = [
        "CPSO-LSSVM (paper fitness)",
        "CPSO-LSSVM (LOO)",
        "PSO-LSSVM (LOO)",
        "grid-LSSVM (LOO)",
        "GP regression",
        "linear model",
        "hybrid default",
    ]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SearchBoundWarning)
        warnings.simplefilter("always", IntervalOutlierWarning)
        for name in learned:
            predict, note, priors[name] = _fit_learned(name, train, seed=seed, max_iter=max_iter)
            pred, lo, hi = predict(test)
            methods[name] = MethodResult(name, np.asarray(pred, float), lo, hi, note=note)
    noted = {SearchBoundWarning: "tuning warned", IntervalOutlierWarning: "a fit warned"}
    for category, said in noted.items():
        for text in dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, category)):
            notes.append(f"{said}: {text}")
    for other in caught:  # any other warning goes on to the caller, as raised
        if not issubclass(other.category, tuple(noted)):
            warnings.warn_explicit(other.message, other.category, other.filename, other.lineno)
    methods["12 h physics inversion"] = MethodResult("12 h physics inversion", physics_inversion(test))
    cf, cf_std = test_df.numbers("drift_curvefit_deg_h"), test_df.numbers("drift_curvefit_std_deg_h")
    methods["12 h curve fit"] = MethodResult("12 h curve fit", cf, cf - Z90 * cf_std, cf + Z90 * cf_std)
    al, al_std = test_df.numbers("drift_align_deg_h"), test_df.numbers("drift_align_std_deg_h")
    methods["alignment z estimate"] = MethodResult("alignment z estimate", al, al - Z90 * al_std, al + Z90 * al_std)
    train_df = ok.select(tr_idx)
    if has_smoother:
        sm = test_df.numbers("drift_smoother_deg_h")
        methods["16 h smoother"] = MethodResult("16 h smoother", sm, sm - Z90 * smoother_std, sm + Z90 * smoother_std)
        prior = _fleet_prior(train_df)
        if isinstance(prior, str):
            notes.append(
                f"the '{FLEET_ROW}' row is unavailable: {prior} among the training runs (a campaign stored before "
                "the smoother's thermal columns existed, or runs under its constant model)"
            )
        else:
            d, s = _with_fleet_prior(test_df, prior)
            methods[FLEET_ROW] = MethodResult(
                FLEET_ROW,
                d,
                d - Z90 * s,
                d + Z90 * s,
                note=f"pooled k_z prior {prior[0]:.3e} +- {prior[1]:.3e} deg/h/degC",
            )
            own = _rms(s)
            methods[FLEET_ROW].metrics["own_sigma_rms"] = own
            notes.append(
                f"{FLEET_ROW}: k_z prior {prior[0]:.3e} +- {prior[1]:.3e} deg/h/degC pooled from the training runs "
                f"({int(np.sum(np.isfinite(_column(train_df, THERMAL[0]))))} with a thermal k_z); RMS of its own "
                f"1-sigma over the held-out runs {own:.2e} deg/h"
            )
    for m in methods.values():
        m.metrics = {**_metrics(m, test_df, effective, truth, limit), **m.metrics}
    if FLEET_ROW in methods:
        fleet_metrics = methods[FLEET_ROW].metrics
        fleet_metrics["ratio_to_own_sigma"] = (
            fleet_metrics["rms_eff"] / fleet_metrics["own_sigma_rms"]
            if fleet_metrics["own_sigma_rms"] > 0
            else math.nan
        )
    drift_laws = None
    k1_curves = test_df.curves is not None and np.any(np.isfinite(test_df.curves["curve_north_per_k1"]))
    if k1_curves:
        from gyrodrift.fleet.law_study import compare_laws

        drift_laws = compare_laws(
            test_df, methods["hybrid default"].pred, priors["hybrid default"], seed=seed, campaign=campaign
        )
    else:
        notes.append(
            "no drift-law comparison: the campaign holds no k1 error curves (stored before they existed, or runs "
            "without a temperature)"
        )
    # --- curves ----------------------------------------------------------------------------------------
    n_train = len(tr_idx)
    if train_sizes is None:
        train_sizes = sorted({s for s in (10, 20, 40, 80, 160, 320, 640) if s < n_train} | {n_train})
    order = np.random.default_rng(seed + 1).permutation(n_train)
    size_curve: dict[str, Any] = {"sizes": train_sizes, "rms_eff": {}}
    with warnings.catch_warnings():  # the curves use the point predictions: their fits' warnings say nothing here
        warnings.simplefilter("ignore", SearchBoundWarning)
        warnings.simplefilter("ignore", IntervalOutlierWarning)
        for name in LEARNED:
            values = []
            for size in train_sizes:
                sub = train.select(np.sort(order[:size]))
                pred = _fit_learned(name, sub, seed=seed, max_iter=max_iter)[0](test)[0]
                values.append(_rms(effective - np.asarray(pred, float)))
            size_curve["rms_eff"][name] = values
    if FLEET_ROW in methods:  # the prior pooled again from each nested subset of the training runs
        values = []
        for size in train_sizes:
            prior = _fleet_prior(train_df.select(np.sort(order[:size])))
            values.append(
                math.nan if isinstance(prior, str) else _rms(effective - _with_fleet_prior(test_df, prior)[0])
            )
        size_curve["rms_eff"][FLEET_ROW] = values
    for name in ("12 h physics inversion", "12 h curve fit") + (("16 h smoother",) if has_smoother else ()):
        size_curve["rms_eff"][name] = [methods[name].metrics["rms_eff"]] * len(train_sizes)
    grades = np.array(["(base)" if g is None else str(g) for g in test_df["grade"]], dtype=object)
    arw = test_df.numbers("arw_deg_rth")
    by_grade: dict[str, Any] = {"grades": [], "arw_deg_rth": [], "n": [], "rms_eff": {n: [] for n in methods}}
    by_grade["limit_deg_h"] = []
    for g in sorted(set(grades), key=lambda g: float(np.mean(arw[grades == g]))):
        sel = grades == g
        by_grade["grades"].append(str(g))
        by_grade["arw_deg_rth"].append(float(np.mean(arw[sel])))
        by_grade["n"].append(int(sel.sum()))
        by_grade["limit_deg_h"].append(_rms(smoother_std[sel]) if has_smoother else math.nan)
        for n, m in methods.items():
            by_grade["rms_eff"][n].append(_rms((effective - m.pred)[sel]))
    lat = np.abs(test_df.numbers("lat0_deg"))
    edges = np.quantile(lat, np.linspace(0, 1, latitude_bins + 1)) if len(lat) else np.zeros(2)
    which = np.clip(np.searchsorted(edges, lat, side="right") - 1, 0, latitude_bins - 1)
    by_lat: dict[str, Any] = {"edges_deg": edges, "center_deg": [], "n": [], "rms_eff": {n: [] for n in methods}}
    by_lat["limit_deg_h"] = []
    for b in range(latitude_bins):
        sel = which == b
        if not sel.any():
            continue
        by_lat["center_deg"].append(float(np.mean(lat[sel])))
        by_lat["n"].append(int(sel.sum()))
        by_lat["limit_deg_h"].append(_rms(smoother_std[sel]) if has_smoother else math.nan)
        for n, m in methods.items():
            by_lat["rms_eff"][n].append(_rms((effective - m.pred)[sel]))
    return StudyResult(
        n_runs=n_all,
        n_failed=n_all - len(ok),
        n_train=n_train,
        n_test=len(te_idx),
        test_fraction=float(test_fraction),
        seed=int(seed),
        methods=methods,
        limit_deg_h=limit,
        label_error_rms=_rms(truth - effective),
        train_size=size_curve,
        by_grade=by_grade,
        by_latitude=by_lat,
        test_runs=[str(r) for r in test_df["run"]],
        notes=notes,
        drift_laws=drift_laws,
    )
