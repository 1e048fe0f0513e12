"""Commands on run tables and drift models: `fit`, `predict`, `reproduce`."""

from __future__ import annotations

import csv
import io
import json

import click

from gyrodrift.choices import (
    ENCODINGS,
    METHODS,
    MIN_THERMAL_RUNS,
    OBJECTIVES,
    PHYSICS_CHOICES,
    SCALINGS,
    SIGMA_RANGE,
    TARGETS,
    default_encoding,
)
from gyrodrift.cli.errors import write_stdout
from gyrodrift.cli.options import (
    choice_option,
    json_option,
    print_json,
    quiet_option,
    say_wrote,
    show_warnings,
)
from gyrodrift.cli.types import FiniteFloat, InputPath, Seed

PREDICTIONS_HEADERS = ("run,drift_identified_deg_h", '{"run": ')
"""How a predictions file written by `predict --out` starts (CSV header, JSON line): the only existing files
`predict --out` replaces (docs/outputs.md)."""


def _read_runs(path, lat0_deg, require_truth, split=None):
    from gyrodrift.errors import OptionError
    from gyrodrift.runs.table import read_runs_csv

    runs = read_runs_csv(path, lat0_deg=lat0_deg, require_truth=require_truth)
    if split:
        runs = runs.select(runs.split == split)
        if len(runs) == 0:
            raise OptionError(f"{path}: no rows with split = {split!r} (--split)")
    return runs


_lat0_option = click.option(
    "--lat0-deg",
    type=FiniteFloat(-90.0, 90.0),
    default=None,
    help="True site latitude [deg] of every run, for tables without a lat0_deg column. Default: the table's.",
)
_split_option = click.option(
    "--split",
    type=click.Choice(["train", "test"]),
    default=None,
    help="Use only the rows whose split column has this value. Default: every row.",
)


@click.command(epilog="Example: gyrodrift fit runs.csv --split train --out model.json")
@click.argument("data", type=InputPath())
@click.option(
    "--out",
    "out",
    required=True,
    type=click.Path(),
    help="Model file to write (JSON, atomically; replaces only a model file gyrodrift wrote). Required.",
)
@click.option(
    "--encoding",
    type=click.Choice(list(ENCODINGS)),
    default=None,
    help="Model inputs: temperature (the temperature range alone; the default for --target residual: the "
    "physics base carries the navigation), physics (drift equivalent of the 12 h latitude error at the run's "
    "latitude, and the temperature range; the default for --target drift), physics_lat (plus the site "
    "latitude), or one of the paper's readings (raw arcsec).",
)
@choice_option(
    "--target",
    TARGETS,
    "residual",
    "residual: hybrid model, physics estimate (--physics-column) plus a learned temperature correction; "
    "drift: the LSSVR learns the drift itself.",
)
@choice_option(
    "--physics-column",
    PHYSICS_CHOICES,
    "auto",
    "Physics estimate of the hybrid: auto (the 16 h smoother with the fleet's pooled k_z prior when every "
    f"run has the smoother's columns and at least {MIN_THERMAL_RUNS} its thermal k_z, else the smoother's drift "
    "when every run has it, else the 12 h inversion; said on stderr), the 12 h inversion, a run-table column, or "
    "the fleet-prior smoother (drift_smoother_fleet_deg_h).",
)
@click.option(
    "--max-label-std-deg-h",
    type=FiniteFloat(0.0, min_open=True),
    default=None,
    help="Leave out runs whose drift_std_deg_h exceeds this [deg/h]; runs with drift_std_deg_h are weighted by it "
    "(weighted LS-SVM) unless --no-label-weights. Default: 0.001.",
)
@click.option("--no-label-weights", is_flag=True, help="Do not weight the runs by drift_std_deg_h. Default: weighted.")
@choice_option(
    "--flagged-labels",
    ("exclude", "keep"),
    "exclude",
    "Runs whose label_flagged is true (truth's label 1-sigma beyond the 1 nmi / 72 h budget): leave them "
    "out, or keep them, down-weighted by their drift_std_deg_h.",
)
@choice_option("--scaling", SCALINGS, "standard", "Scaling of the encoded inputs before the kernel.")
@choice_option("--objective", OBJECTIVES, "loo_mae", "What the tuning minimises (leave-one-out MAE [deg/h], ...).")
@choice_option("--method", METHODS, "cpso", "Tuner of gamma and sigma (chaos PSO, plain PSO, grid, ...).")
@click.option(
    "--gamma",
    type=FiniteFloat(0.0, min_open=True),
    default=None,
    help="Fix the regularisation gamma [-] (with --sigma) instead of tuning. Default: tuned.",
)
@click.option(
    "--sigma",
    type=FiniteFloat(*SIGMA_RANGE),
    default=None,
    help="Fix the RBF width sigma [scaled input units] (its square must be a normal float64) instead of tuning. "
    "Default: tuned.",
)
@click.option(
    "--seed",
    type=Seed(),
    default=0,
    show_default=True,
    help="Seed of the swarm (an integer >= 0); same seed, same model.",
)
@_lat0_option
@_split_option
@json_option
@quiet_option
def fit(
    data,
    out,
    encoding,
    target,
    physics_column,
    max_label_std_deg_h,
    no_label_weights,
    flagged_labels,
    scaling,
    objective,
    method,
    gamma,
    sigma,
    seed,
    lat0_deg,
    split,
    as_json,
    quiet,
):
    """Fit a drift model on DATA.csv (runs with drift_deg_h) and write it to --out.

    Warnings (a tuned value on the edge of its search box, an ill-conditioned solve) go to stderr and into the
    model file's "warnings". Runs left out for their label 1-sigma, the weighting, and the hybrid's physics
    base (which one --physics-column auto took, and why) are said on stderr and kept in the file.
    """
    from gyrodrift.errors import OptionError
    from gyrodrift.files.atomic import check_output_file
    from gyrodrift.learn.drift_model import DEFAULT_MAX_LABEL_STD_DEG_H, fit_drift_model
    from gyrodrift.learn.lssvm_system import IllConditionedError
    from gyrodrift.learn.model_io import MODEL_FILE_RECOGNISER, save_model

    if (gamma is None) != (sigma is None):
        raise OptionError("give both --gamma and --sigma, or neither (then both are tuned)")

    check_output_file(out, inputs=[data], recognise=MODEL_FILE_RECOGNISER, what="model file")
    runs = _read_runs(data, lat0_deg, True, split)
    _warn_labels_beyond_rlg(data, runs)
    if split is None and any(runs.split):
        click.echo(
            f"note: {data} has a split column; training on all {len(runs)} rows "
            "(--split train uses the training rows only)",
            err=True,
        )
    try:
        with show_warnings():
            model = fit_drift_model(
                runs,
                encoding=default_encoding(target) if encoding is None else encoding,
                scaling=scaling,
                objective=objective,
                method=method,
                gamma=gamma,
                sigma=sigma,
                rng=seed,
                quiet=quiet,
                target=target,
                physics_column=physics_column,
                label_weighting="none" if no_label_weights else "auto",
                max_label_std_deg_h=DEFAULT_MAX_LABEL_STD_DEG_H if max_label_std_deg_h is None else max_label_std_deg_h,
                flagged_labels=flagged_labels,
            )
    except IllConditionedError as exc:
        if gamma is None:
            raise
        raise OptionError(f"--gamma {gamma:g} --sigma {sigma:g}: {exc}") from None
    training = model.training
    flagged_out, flagged_kept = training.get("flagged_left_out", []), training.get("flagged_kept", [])
    if flagged_out:
        click.echo(
            f"note: left out {len(flagged_out)} run(s) whose label truth flagged (label_flagged: 1-sigma beyond the "
            f"1 nmi / 72 h budget; --flagged-labels keep keeps them down-weighted): {', '.join(flagged_out)}",
            err=True,
        )
    too_uncertain = [r for r in training["left_out"] if r not in flagged_out]
    if too_uncertain:
        limit = DEFAULT_MAX_LABEL_STD_DEG_H if max_label_std_deg_h is None else max_label_std_deg_h
        click.echo(
            f"note: left out {len(too_uncertain)} run(s) whose drift_std_deg_h exceeds {limit:g} deg/h "
            f"(too uncertain to label): {', '.join(too_uncertain)}",
            err=True,
        )
    if flagged_kept:
        how = "down-weighted by their drift_std_deg_h" if training["weighted"] else "unweighted (no label weights)"
        click.echo(
            f"note: kept {len(flagged_kept)} run(s) whose label truth flagged, {how}: {', '.join(flagged_kept)}",
            err=True,
        )
    if training["weighted"]:
        how = (
            "their label 1-sigma drift_std_deg_h combined with the physics base's 1-sigma"
            if model.base_.std_used_
            else "their label 1-sigma drift_std_deg_h"
        )
        click.echo(f"note: runs weighted by {how} (weighted LS-SVM)", err=True)
    elif "drift_std_deg_h" in runs.extra and not no_label_weights:
        click.echo("note: drift_std_deg_h is missing for some runs; the runs are not weighted", err=True)
    save_model(model, out, inputs=[data])
    est = model.lssvr
    loo = model.loo_residuals()
    loo_mae = float(abs(loo).mean())
    if as_json:
        print_json(
            {
                "model": str(out),
                "n_runs": training["n_runs"],
                "encoding": model.encoding,
                "target": target,
                "physics_column": model.physics_column_,
                "coefficient_prior_deg_h_per_c": None
                if model.coefficient_prior_ is None
                else list(model.coefficient_prior_),
                "gamma": float(est.gamma),
                "sigma": float(est.sigma),
                "loo_mae_deg_h": loo_mae,
                "interval": model.interval_summary(0.9),
                "warnings": list(model.fit_warnings()),
            }
        )
    say_wrote(
        [out],
        quiet=quiet,
        as_json=as_json,
        detail=f"fitted on {training['n_runs']} runs, {model.encoding}, target {target}: gamma = {est.gamma:.6g}, "
        f"sigma = {est.sigma:.6g}, LOO MAE = {loo_mae:.3e} deg/h",
    )
    # after the model and the summary are written: a failed write stays the command's one line
    if model.target == "residual":
        why = "--physics-column" if physics_column != "auto" else model.base_.reason_
        prior = model.coefficient_prior_
        if prior is not None:
            why += f"; pooled k_z prior {prior[0]:.3e} +- {prior[1]:.3e} deg/h/degC"
        click.echo(f"note: physics base: {model.physics_column_} ({why})", err=True)
    click.echo(f"note: {model.interval_note(0.9)}", err=True)


def _warn_labels_beyond_rlg(data, runs) -> None:
    """A 'warning:' line naming the runs whose drift_deg_h label is beyond a navigation-grade RLG (fit goes on:
    such a fleet may be real, and every drift its model then predicts that far is flagged too)."""
    from gyrodrift.runs.table import NAVIGATION_GRADE_DRIFT_DEG_H, drift_range_problems

    bad = [i for i, why in enumerate(drift_range_problems(runs.drift_deg_h)) if why]
    if bad:
        shown = ", ".join(f"{runs.run[i]} ({runs.drift_deg_h[i]:.6g})" for i in bad[:10]) + (
            " ..." if len(bad) > 10 else ""
        )
        click.echo(
            f"warning: {data}, column drift_deg_h: {len(bad)} of {len(runs)} label(s) beyond a navigation-grade RLG's "
            f"{NAVIGATION_GRADE_DRIFT_DEG_H:g} deg/h, rows of run(s) {shown}: drift_deg_h is in deg/h (a table in "
            "mdeg/h?); the model will predict drifts of that size",
            err=True,
        )


@click.command(epilog="Example: gyrodrift predict runs.csv --model model.json --coverage 0.9")
@click.argument("data", type=InputPath())
@click.option(
    "--model",
    "model_file",
    required=True,
    type=InputPath(),
    help="Drift model file (JSON, from `gyrodrift fit`). Required.",
)
@click.option(
    "--out",
    type=click.Path(),
    default=None,
    help="Also save the predictions in this file (atomically; replaces only a predictions file gyrodrift wrote). "
    "Default: print them on stdout.",
)
@click.option(
    "--coverage",
    type=FiniteFloat(0.0, 1.0, min_open=True, max_open=True),
    default=None,
    help="Add an interval of the drift of this coverage [-] (e.g. 0.9), calibrated on the model's out-of-fold "
    "residuals and wider away from its training runs. "
    "Default: no interval.",
)
@_lat0_option
@_split_option
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="JSON lines (one object per run) instead of CSV. Default: CSV.",
)
@click.option("--format", "fmt", type=click.Choice(["csv", "jsonl"]), default=None, hidden=True)
@quiet_option
def predict(data, model_file, out, coverage, lat0_deg, split, as_json, fmt, quiet):
    """Identify the axial drift [deg/h] of each run in DATA.csv with the --model file.

    Runs whose inputs lie outside the training runs' range (per input, or jointly) get
    outside_training_range = 1 and a warning line on stderr: their drift is an extrapolation, and their
    interval (--coverage) is wider there. A drift beyond a navigation-grade RLG's 0.1 deg/h, or far outside the
    training labels' range, gets outside_drift_range = 1 and a warning line.
    """
    import numpy as np

    from gyrodrift.errors import OptionError
    from gyrodrift.files.atomic import atomic_write, check_output_file, recognise_header
    from gyrodrift.learn.interval import min_runs_for_coverage
    from gyrodrift.learn.model_io import load_predictor

    if fmt is not None:
        click.echo("warning: --format is deprecated; CSV is the default and --json gives JSON lines", err=True)
        as_json = as_json or fmt == "jsonl"
    target = {
        "inputs": [model_file, data],
        "recognise": recognise_header(*PREDICTIONS_HEADERS),
        "what": "predictions file",
    }
    if out is not None:
        check_output_file(out, **target)
    model = load_predictor(model_file)  # no scikit-learn: ~1.5 s of a start
    runs = _read_runs(data, lat0_deg, False, split)
    if coverage is not None:
        pred, lo, hi = model.predict_interval(runs, coverage)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            n = len(model.loo_residuals_deg_h)
            raise OptionError(
                f"{model_file}: {n} training runs are too few for a {100 * coverage:g} % jackknife interval "
                f"(needs at least {min_runs_for_coverage(coverage)}); lower --coverage"
            )
    else:
        pred = model.predict(runs)
    check = model.check_inputs(runs)
    for line in check.messages(runs):
        click.echo(f"warning: {line}", err=True)
    from gyrodrift.runs.table import drift_range_problems

    implausible = drift_range_problems(pred, model.training_["runs"].drift_deg_h)
    for name, why in zip(runs.run, implausible, strict=True):
        if why:
            click.echo(f"warning: run {name}: identified drift {why}", err=True)
    rows = []
    for i, rec in enumerate(runs.records()):
        row = {"run": rec["run"], "drift_identified_deg_h": float(pred[i])}
        if coverage is not None:
            row["drift_lo_deg_h"], row["drift_hi_deg_h"] = float(lo[i]), float(hi[i])
        row["outside_training_range"] = int(check.outside[i])
        row["outside_drift_range"] = int(implausible[i] is not None)
        if "drift_deg_h" in rec:
            row["drift_deg_h"] = rec["drift_deg_h"]
            row["error_deg_h"] = rec["drift_deg_h"] - float(pred[i])
        rows.append(row)
    buf = io.StringIO()
    if as_json:
        for row in rows:
            buf.write(json.dumps(row) + "\n")
    else:
        fields = max((list(r) for r in rows), key=len)
        writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n", restval="")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in row.items()})
    if out is None:
        write_stdout(buf.getvalue())
    else:
        with atomic_write(out, **target) as handle:
            handle.write(buf.getvalue())
        say_wrote([out], quiet=quiet, detail=f"{len(rows)} run(s)")


@click.command(epilog="Example: gyrodrift reproduce --out paper --seed 1")
@click.option(
    "--out",
    "out_dir",
    type=click.Path(),
    default="gyrodrift-reproduce",
    show_default=True,
    help="Folder for results.json, report.md, report.html and the figures: new, empty, or holding only "
    "gyrodrift's outputs (published together; docs/outputs.md).",
)
@click.option(
    "--seed",
    type=Seed(),
    default=0,
    show_default=True,
    help="Seeds every swarm (an integer >= 0); same seed, same results.",
)
@json_option
@quiet_option
def reproduce(out_dir, seed, as_json, quiet):
    """Reproduce the paper's experiment on its embedded data, with baselines and a report."""
    import time

    from gyrodrift.paper.report import summary_lines
    from gyrodrift.paper.reproduce import reproduce as run

    started = time.monotonic()  # wall time of the whole command: tuning, the 72 h simulation, figures, writing
    results = run(out_dir, seed=seed, quiet=quiet)  # checks out_dir before the work
    if as_json:
        print_json(results)
    elif not quiet:
        for line in summary_lines(results):
            click.echo(line)
    names = ("report.html", "report.md", "results.json")
    say_wrote(
        [f"{out_dir}/{name}" for name in names],
        quiet=quiet,
        as_json=as_json,
        detail=f"and the figures; wall time {time.monotonic() - started:.1f} s",
    )


COMMANDS = (fit, predict, reproduce)
