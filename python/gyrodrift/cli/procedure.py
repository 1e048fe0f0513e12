"""Commands from an IMU log to a compensation: `features`, `truth`, `evaluate`, `identify` (`gyrodrift.procedure`)."""

from __future__ import annotations

import math
from pathlib import Path

import click

from gyrodrift.cli.navigation import compensation_of, drift_law_option
from gyrodrift.cli.options import (
    choice_option,
    connect_timeout_option,
    json_option,
    log_options,
    noise_options,
    out_folder_option,
    print_json,
    quiet_option,
    say_wrote,
)
from gyrodrift.cli.types import DRIFT_DEG_H, FiniteFloat, InputPath

__all__ = ["features_command", "truth_command", "evaluate_command", "identify_command"]

_CRITERIA = ("final", "rms", "max")
"""The criteria of the true drift (`gyrodrift.procedure.truth.CRITERIA`, not imported: the CLI starts light)."""

_hours_option = click.option(
    "--hours",
    type=FiniteFloat(min=0.0, min_open=True),
    default=72.0,
    show_default=True,
    help="Hours of free navigation [h], counted from the end of the 4 h alignment.",
)


def _open(path, site, log_format=None):
    from gyrodrift.logs import LogError, open_log

    log = open_log(path, site=site, format=log_format)
    if log.site is None:
        raise LogError(f"{path}: the log carries no site; give its latitude (--lat0-deg)")
    return log


@click.command(
    "features",
    epilog="Example: gyrodrift features fleet/*/imu.parquet --with-truth --out runs.csv",
)
@click.argument("logs", nargs=-1, required=True, type=InputPath(path_type=Path))
@click.option(
    "--out",
    "out",
    required=True,
    type=click.Path(path_type=Path),
    help="Run table to write (CSV, atomically; replaces only a run table gyrodrift wrote). Required.",
)
@log_options
@click.option(
    "--with-truth",
    is_flag=True,
    help="Also find each log's true drift [deg/h] (logs >= 76 h) -> drift_deg_h column. Default: off.",
)
@choice_option(
    "--criterion",
    _CRITERIA,
    "final",
    "Criterion of the true drift (with --with-truth): the 72 h position error at its end, RMS, or maximum.",
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Process the logs on a local dask cluster with N worker processes (needs the 'dask' extra). "
    "Default: one process, no dask.",
)
@click.option(
    "--scheduler",
    default=None,
    help="Address of a running dask scheduler (tcp://host:8786). Default: none (see --workers).",
)
@connect_timeout_option
@click.option(
    "--curves",
    type=click.Path(path_type=Path),
    default=None,
    help="Also write the hourly latitude-error curves (run, t_h, lat_err_arcsec) to this CSV. Default: none.",
)
@click.option(
    "--smoother/--no-smoother",
    default=True,
    show_default=True,
    help="Run the 16 h smoother (drift_smoother_deg_h and its 1-sigma [deg/h]; under its thermal model also k_z "
    "and its 1-sigma [deg/h/degC], cov(end drift, k_z) [(deg/h)^2/degC] and its prior 1-sigma of k_z): one more "
    "read of each log's first 16 h, about as long as the features themselves. --no-smoother leaves those columns "
    "empty. Default: --smoother.",
)
@noise_options
@json_option
@quiet_option
def features_command(
    logs,
    out,
    site,
    log_format,
    with_truth,
    criterion,
    workers,
    scheduler,
    connect_timeout_s,
    curves,
    smoother,
    noise,
    as_json,
    quiet,
):
    """Align each LOG, navigate 12 h and write one run-table row per log to --out.

    Columns: run (the log's stem), lat_deg (latitude at navigation hour 12), lat0_deg, temp_min_c,
    temp_max_c, temp_start_c, temp_end_c (over those 12 h), the 12 h curve fit and the 16 h smoother with their
    1-sigmas [deg/h], the smoother's thermal coefficient k_z with its 1-sigma, covariance with the end drift and
    prior 1-sigma (smoother_coeff_deg_h_per_c, smoother_coeff_std_deg_h_per_c, smoother_end_coeff_cov,
    smoother_coeff_prior_std_deg_h_per_c; empty under its constant model), and with --with-truth drift_deg_h, its
    1-sigma drift_std_deg_h and label_flagged.
    """
    from gyrodrift.fleet.features import features_table
    from gyrodrift.procedure.noise import SensorNoise
    from gyrodrift.procedure.writers import check_features_outputs, write_features_csv

    if workers is not None and scheduler is not None:
        raise click.UsageError("give --workers or --scheduler, not both")
    check_features_outputs(out, curves, inputs=logs)
    rows = features_table(
        [str(p) for p in logs],
        site=site,
        log_format=log_format,
        with_truth=with_truth,
        criterion=criterion,
        workers=workers,
        scheduler=scheduler,
        connect_timeout_s=connect_timeout_s,
        quiet=quiet,
        smoother=smoother,
        noise=noise,
    )
    write_features_csv(rows, out, curves=curves, inputs=logs)
    if as_json:
        print_json([row.row() for row in rows])
    say_wrote([p for p in (out, curves) if p is not None], quiet=quiet, as_json=as_json, detail=f"{len(rows)} run(s)")
    if noise is None and (smoother or with_truth):  # each log's noise measured from it: white only
        click.echo(f"note: {SensorNoise(source='log').white_only_note}", err=True)


@click.command("truth", epilog="Example: gyrodrift truth sim/imu.parquet --criterion final --out truth")
@click.argument("log", type=InputPath(path_type=Path))
@choice_option(
    "--criterion",
    _CRITERIA,
    "final",
    "Position-error criterion over the navigation: at its end, RMS, or maximum.",
)
@_hours_option
@log_options
@out_folder_option("for true_drift.json, criterion.png, alignment.json and alignment_z_sigma.png", required=False)
@noise_options
@json_option
@quiet_option
def truth_command(log, criterion, hours, site, log_format, out_dir, noise, as_json, quiet):
    """Find the z-gyro drift [deg/h] minimising the position error of the navigation after alignment."""
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.procedure.truth import find_true_drift
    from gyrodrift.procedure.writers import ALIGNMENT_FILES, TRUTH_FILES, write_alignment, write_truth

    out = None if out_dir is None else OutputFolder(out_dir, "truth", TRUTH_FILES + ALIGNMENT_FILES, inputs=[log])
    imu = _open(log, site, log_format)
    res = find_true_drift(imu, criterion=criterion, hours=hours, noise=noise, quiet=quiet)
    if out is not None:
        with out.publish() as stage:
            write_truth(res, stage)
            write_alignment(res.alignment, stage)
    if out is not None:
        say_wrote([out_dir / name for name in TRUTH_FILES + ALIGNMENT_FILES], quiet=quiet, as_json=True)
    if as_json:
        print_json(res.to_dict())
        return
    if quiet and out is not None:
        return
    v = res.verify_nmi
    click.echo(
        f"{res.run}: true drift {res.drift_deg_h:.7f} +- {res.drift_std_deg_h:.7f} deg/h (1-sigma of the label at the "
        f"log's noise level; {criterion} criterion over {hours:g} h)"
    )
    if res.noise_note is not None:
        click.echo(f"  note: {res.noise_note}")
    if res.flagged:
        click.echo(f"warning: {res.run}: label flagged: {res.flag_reason}", err=True)
    click.echo(
        f"  criterion: {res.uncompensated_nmi:.4f} nmi uncompensated, {v[1]:.4f} nmi at the optimum "
        f"(navigated), {v[0]:.4f} / {v[2]:.4f} nmi at -/+ "
        f"{res.verify_drift_deg_h[2] - res.drift_deg_h:.4g} deg/h"
        f" -> {'verified' if res.verified else 'NOT verified'}"
    )
    if res.law is not None:
        click.echo(f"  {res.law.summary()}")
    click.echo(
        f"  alignment z estimate {res.alignment.z_drift_deg_h:.5f} +- {res.alignment.z_drift_std_deg_h:.5f} "
        f"deg/h (1-sigma, not used)"
    )


@click.command("evaluate", epilog="Example: gyrodrift evaluate sim/imu.parquet --model model.json --out eval")
@click.argument("log", type=InputPath(path_type=Path))
@click.option(
    "--drift-deg-h",
    type=DRIFT_DEG_H,
    default=None,
    help="Axial drift estimate [deg/h] to compensate (subtracted from the z gyro). Default: none; give it, "
    "--drift-law or --model.",
)
@drift_law_option
@click.option(
    "--model",
    "model_path",
    type=InputPath(path_type=Path),
    default=None,
    help="Drift model file (JSON, from `gyrodrift fit`) identifying the drift to compensate (the drift law `identify` "
    "reports). Default: none; give it, --drift-deg-h or --drift-law.",
)
@out_folder_option(
    "for evaluation.json, position_error.png and its curves position_error.parquet (before/after, t_h, lat/lon "
    "errors [arcsec], position error [nmi])"
)
@_hours_option
@click.option(
    "--reference",
    "reference",
    type=InputPath(path_type=Path),
    default=None,
    help="Moving base: reference track (GNSS CSV/Parquet: t_s, lat_deg, lon_deg, height_m, optional "
    "vel_e/n/u_m_s; times on the log's time base) to compute the errors against; adds route_map.png. "
    "Default: the simulated route of a moving-base imu.parquet, else the static site.",
)
@log_options
@json_option
@quiet_option
def evaluate_command(
    log, drift_deg_h, drift_law_path, model_path, out_dir, hours, reference, site, log_format, as_json, quiet
):
    """Navigate LOG 72 h after alignment without and with compensating the axial drift; plot both errors.

    The drift is a constant (--drift-deg-h), a law of the log's temperature (--drift-law), or the law `identify`
    reports with the model (--model); evaluation.json (compensation, drift_law) and the closing line say which.
    """
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.ins.compensation import compensation_words
    from gyrodrift.ins.track import route_of
    from gyrodrift.procedure.evaluate import evaluate_compensation
    from gyrodrift.procedure.identify import identify
    from gyrodrift.procedure.writers import evaluation_files, write_evaluation

    if sum(x is not None for x in (drift_deg_h, drift_law_path, model_path)) != 1:
        raise click.UsageError("give exactly one of --drift-deg-h, --drift-law or --model")
    law = compensation_of(drift_deg_h, drift_law_path)
    moving = reference is not None or route_of(log) is not None
    inputs = [p for p in (log, drift_law_path, model_path, reference) if p is not None]
    out = OutputFolder(out_dir, "evaluate", evaluation_files(moving), inputs=inputs)
    imu = _open(log, site, log_format)
    alignment = None
    source = "given" if drift_law_path is None else str(drift_law_path)
    if model_path is not None:
        ident = identify(imu, model_path, quiet=quiet)
        law, alignment, source = ident.drift_law, ident.features.alignment, str(model_path)
    assert law is not None  # exactly one source was given
    ev = evaluate_compensation(
        imu, law, hours=hours, alignment=alignment, source=source, quiet=quiet, reference=reference
    )
    paths = write_evaluation(ev, out)
    if as_json:
        print_json(ev.to_dict())
    say_wrote(
        list(paths.values()),
        quiet=quiet,
        as_json=as_json,
        detail=f"{ev.run}: compensating the {compensation_words(law)}: {hours:g} h position error "
        f"{ev.before.final_nmi:.3f} -> {ev.after.final_nmi:.3f} nmi (final), "
        f"{ev.before.max_nmi:.3f} -> {ev.after.max_nmi:.3f} nmi (max)",
    )


@click.command("identify", epilog="Example: gyrodrift identify sim/imu.parquet --model model.json --out ident")
@click.argument("log", type=InputPath(path_type=Path))
@click.option(
    "--model",
    "model_path",
    required=True,
    type=InputPath(path_type=Path),
    help="Drift model file (JSON, from `gyrodrift fit`). Required.",
)
@log_options
@out_folder_option("for identification.json, alignment.json and alignment_z_sigma.png", required=False)
@noise_options
@json_option
@quiet_option
def identify_command(log, model_path, site, log_format, out_dir, noise, as_json, quiet):
    """Align LOG, navigate 12 h and identify its axial drift with the model."""
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.procedure.identify import identify
    from gyrodrift.procedure.writers import (
        ALIGNMENT_FILES,
        IDENTIFICATION_FILES,
        identification_document,
        write_alignment,
        write_identification,
    )

    files = IDENTIFICATION_FILES + ALIGNMENT_FILES
    out = None if out_dir is None else OutputFolder(out_dir, "identify", files, inputs=[log, model_path])
    imu = _open(log, site, log_format)
    res = identify(imu, model_path, noise=noise, quiet=quiet)
    doc = identification_document(res)
    if out is not None:
        with out.publish() as stage:
            write_identification(res, stage)
            write_alignment(res.features.alignment, stage)
        say_wrote([out_dir / name for name in files], quiet=quiet, as_json=True)
    if as_json:
        print_json(doc)
        return
    if quiet and out is not None:
        return
    f = res.features
    for line in res.range_warnings:
        click.echo(f"warning: {line}", err=True)
    click.echo(f"{res.run}: identified axial drift {res.drift_deg_h:.6f} deg/h (model {model_path})")
    if res.interval_deg_h is not None:
        lo, hi = res.interval_deg_h
        click.echo(f"  {100 * res.interval_coverage:g} % interval: [{lo:.6f}, {hi:.6f}] deg/h ({res.uncertainty_note})")
    else:
        click.echo(f"  model uncertainty: none ({res.uncertainty_note})")
    if res.training_error_deg_h is not None:
        click.echo(f"  error on its training runs ({res.training_error_kind}) {res.training_error_deg_h:.2e} deg/h")
    click.echo(
        f"  physics inversion of the 12 h latitude error ({f.lat_err_arcsec:.3f} arcsec): "
        f"{res.physics_drift_deg_h:.6f} deg/h"
    )
    click.echo(
        f"  12 h curve fit of the latitude and longitude errors: {res.curvefit_drift_deg_h:.6f} +- "
        f"{res.curvefit_drift_std_deg_h:.6f} deg/h (1-sigma)"
    )
    sm = f.smoother
    thermal_note = (
        ""
        if sm is None or sm.model != "thermal"
        else f", thermal model: the drift at the end of the span ({sm.temp_end_c:.1f} degC), k_z "
        f"{sm.thermal_coeff_deg_h_per_c:.2e} +- {sm.thermal_coeff_std_deg_h_per_c:.2e} deg/h/degC"
    )
    click.echo(
        f"  16 h smoother (alignment + 12 h, zero velocity and known position{thermal_note}): "
        f"{res.smoother_drift_deg_h:.6f} +- {res.smoother_drift_std_deg_h:.6f} deg/h (1-sigma: the Cramer-Rao "
        "line of these 16 h)"
    )
    if res.smoother_noise_note is not None:
        click.echo(f"    note: {res.smoother_noise_note}")
    if res.coefficient_prior_deg_h_per_c is not None:
        mean, std = res.coefficient_prior_deg_h_per_c
        click.echo(
            f"  16 h smoother with the training fleet's k_z prior ({mean:.2e} +- {std:.2e} deg/h/degC), the model's "
            f"physics base: {res.smoother_fleet_drift_deg_h:.6f} +- {res.smoother_fleet_drift_std_deg_h:.6f} deg/h "
            f"(1-sigma); the model's learned correction {res.drift_deg_h - res.smoother_fleet_drift_deg_h:+.6f} deg/h"
        )
    click.echo(f"  {_law_line(res)}")
    if res.mission is not None:
        q = ", ".join(f"{100 * float(p):g} % {v:.2f}" for p, v in res.mission["quantiles_nmi"].items())
        click.echo(f"  72 h mission after compensation (from {res.mission['drift_std_source']}): {q} nmi")
        click.echo(f"    {res.mission['note']}")
    click.echo(
        f"  alignment z estimate: {res.alignment_z_drift_deg_h:.6f} +- {res.alignment_z_drift_std_deg_h:.6f} "
        f"deg/h (1-sigma)"
    )
    click.echo(
        f"  temperature over 12 h: {f.temp_min_c:.2f} ~ {f.temp_max_c:.2f} deg C "
        f"(start {f.temp_start_c:.2f}, end {f.temp_end_c:.2f})"
    )


def _law_line(res) -> str:
    """The identified drift law in one line: its formula, coefficients with 1-sigma and the constant it replaces."""
    law = res.drift_law
    std = res.drift_law_std_deg_h
    sigma = "" if not math.isfinite(std) else f" +- {std:.6f}"
    if law.is_constant:
        return (
            f"drift law: the constant {law.eps_ref_deg_h:.6f}{sigma} deg/h (k1 = 0: no fleet k_z prior in the model "
            "or no thermal model in the smoother)"
        )
    k1_std = "" if law.cov is None else f" +- {math.sqrt(law.cov[1][1]):.2e}"
    return (
        f"drift law: eps(T) = {law.eps_ref_deg_h:.6f}{sigma} + {law.k1_deg_h_per_c:.3e}{k1_std} deg/h/degC x "
        f"(T - {law.t_ref_c:.2f} degC) deg/h (1-sigma), replacing the constant {res.drift_deg_h:.6f} deg/h"
    )


COMMANDS = (features_command, truth_command, evaluate_command, identify_command)
