"""`gyrodrift campaign` (a simulated fleet, processed and stored run by run) and `gyrodrift study` (every
identification method on the same held-out runs): docs/campaigns.md."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.examples import example_option, file_or_example
from gyrodrift.cli.options import (
    connect_timeout_option,
    json_option,
    print_json,
    quiet_option,
    say_wrote,
    show_warnings,
)
from gyrodrift.cli.types import FiniteFloat, InputPath, Seed

__all__ = ["COMMANDS", "campaign_command", "study_command"]


@click.command(
    "campaign",
    epilog="Examples: gyrodrift campaign --example default --out fleet --workers 2 ; "
    "gyrodrift campaign fleet --run-table runs.csv ; gyrodrift campaign fleet --export-log 7 --out run7",
)
@click.argument("source", required=False, type=InputPath(exists=True, dir_okay=True, path_type=Path))
@example_option("campaign")
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="With a campaign file: the campaign folder (new, empty, or this campaign's: finished runs are skipped). "
    "With --export-log: the folder for the run's imu.parquet and scenario.resolved.toml. Default: none.",
)
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Local processes (default: one per CPU).")
@click.option("--scheduler", default=None, help="Address of a running dask scheduler (tcp://host:8786). Default: none.")
@connect_timeout_option
@click.option(
    "--limit", type=click.IntRange(min=1), default=None, help="Process at most this many pending runs. Default: all."
)
@click.option(
    "--run-table",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="SOURCE is a campaign folder: write its successful runs as a run table `gyrodrift fit` reads. Default: none.",
)
@click.option(
    "--export-log",
    "export_run",
    type=click.IntRange(min=0),
    default=None,
    help="SOURCE is a campaign folder (or file): simulate run N alone and write its log into --out. Default: none.",
)
@json_option
@quiet_option
def campaign_command(
    source, example, out, workers, scheduler, connect_timeout_s, limit, run_table, export_run, as_json, quiet
):
    """Simulate and process a campaign of runs (SOURCE: a campaign TOML file, or a shipped --example), or read a
    campaign folder.

    Each run is simulated in the worker (no log written), aligned, navigated for the 12 h features and the 72 h
    truth, its 12 h curve fit, 16 h smoother estimate and linear 72 h error curves computed, and its noise-free
    twin's truth (the simulated effective drift) found; one Parquet file per run under OUT/runs/, each written
    atomically. Rerunning the same command resumes an interrupted campaign (every run file is checked first; a
    damaged one is run again). Ctrl-C once: no new runs, the runs in progress are finished and committed (exit
    130); twice: abort at once. A campaign whose every run would be too short is refused before any work; exit 1
    when every run failed.
    """
    from gyrodrift.errors import OptionError
    from gyrodrift.fleet.campaign import CampaignFailedError, run_campaign
    from gyrodrift.fleet.run_table import run_table_rows
    from gyrodrift.fleet.spec import load_campaign
    from gyrodrift.fleet.store import CampaignStore, read_runs
    from gyrodrift.runs.table import write_run_table

    source = file_or_example(source, example, "campaign", "SOURCE")
    if source.is_dir():
        store = CampaignStore(source)
        if run_table is None and export_run is None:
            raise OptionError(f"{source} is a campaign folder: give --run-table FILE or --export-log N --out DIR")
        if run_table is not None:
            runs = read_runs(source, curves=False)
            if not runs.ok.any():  # a header-only table `fit` would refuse: say why here, write nothing
                why = f"every one of its {len(runs)} committed run(s) failed" if len(runs) else "no run is committed"
                raise CampaignFailedError(f"{source}: no successful run to write to {run_table}: {why}")
            rows, columns = run_table_rows(runs)
            write_run_table(run_table, rows, columns)
            say_wrote([run_table], quiet=quiet, as_json=as_json, detail=f"{len(rows)} run(s)")
        if export_run is not None:
            _export(store.campaign(), export_run, out, quiet, as_json)
        return
    if run_table is not None:
        raise OptionError("--run-table reads a campaign folder: give the folder as SOURCE")
    campaign = load_campaign(source)
    if export_run is not None:
        _export(campaign, export_run, out, quiet, as_json)
        return
    if out is None:
        raise OptionError("--out: give the campaign folder")
    if workers is not None and scheduler is not None:
        raise OptionError("give --workers or --scheduler, not both")
    summary = run_campaign(
        campaign,
        out,
        text=source.read_text(encoding="utf-8"),
        workers=workers,
        scheduler=scheduler,
        connect_timeout_s=connect_timeout_s,
        quiet=quiet,
        limit=limit,
    )
    doc = {
        "campaign": campaign.name,
        "folder": str(out),
        "runs": summary.total,
        "already_done": summary.skipped,
        "done_now": summary.done,
        "failed_now": summary.failed,
        "not_committed": summary.lost,
        "elapsed_s": round(summary.elapsed_s, 3),
        "interrupted": summary.interrupted,
    }
    if as_json:
        print_json(doc)
    say_wrote(
        [out],
        quiet=quiet,
        as_json=as_json,
        detail=f"{campaign.name}: {summary.done} run(s) done now ({summary.failed} failed), {summary.skipped} "
        f"already done, {summary.total - summary.skipped - summary.done} pending, in {summary.elapsed_s:.1f} s"
        + ("; interrupted: rerun the same command to resume" if summary.interrupted else ""),
    )
    if summary.interrupted:
        click.get_current_context().exit(130)  # the shell's code for a SIGINT; the runs in progress were committed
    _check_failures(summary, out)


def _check_failures(summary, out) -> None:
    """Every run of the store failed (or was lost): `CampaignFailedError` (one line, exit 1); some runs failed
    now: one line on stderr saying how many and the first error."""
    from gyrodrift.fleet.campaign import CampaignFailedError

    tried = summary.skipped + summary.done + summary.lost
    first = f"; first error: {summary.first_error}" if summary.first_error else ""
    if tried and summary.succeeded == 0:
        lost = f", {summary.lost} lost to the workers" if summary.lost else ""
        raise CampaignFailedError(
            f"{out}: every run failed ({summary.failed_before + summary.failed} of {tried} with an error{lost})"
            + (first or " (their errors are in the store)")
        )
    if summary.failed or summary.lost:
        lost = f"; {summary.lost} not committed (workers lost; rerun to resume)" if summary.lost else ""
        click.echo(f"campaign: {summary.failed} of {summary.done} run(s) failed now{lost}{first}", err=True)


def _export(campaign, index: int, out, quiet: bool, as_json: bool) -> None:
    from gyrodrift.errors import OptionError
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.ins.simulate import simulate

    if out is None:
        raise OptionError("--export-log: give --out, the folder for the run's imu.parquet")
    scenario = campaign.scenario(index)
    folder = OutputFolder(out, "simulate", ["imu.parquet", "scenario.resolved.toml"])
    path = simulate(scenario, out_dir=folder, quiet=quiet)
    say_wrote([path], quiet=quiet, as_json=as_json, detail=f"run {index} of {campaign.name}")


@click.command("study", epilog="Example: gyrodrift study fleet --out study --test-fraction 0.3 --seed 1")
@click.argument("folder", type=InputPath(exists=True, dir_okay=True, file_okay=False, path_type=Path))
@click.option(
    "--out",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder for report.html, study.json and the figures: new, empty, or holding only gyrodrift's outputs.",
)
@click.option(
    "--test-fraction",
    type=FiniteFloat(min=0.0, max=1.0, min_open=True, max_open=True),
    default=0.3,
    show_default=True,
    help="Share of the runs held out [fraction of 1] (chosen by run, seeded).",
)
@click.option("--seed", type=Seed(), default=0, show_default=True, help="Seed of the split and tuners.")
@click.option(
    "--max-iter", type=click.IntRange(min=1), default=60, show_default=True, help="CPSO/PSO iterations per fit."
)
@json_option
@quiet_option
def study_command(folder, out, test_fraction, seed, max_iter, as_json, quiet):
    """Compare every identification method on the same held-out runs of a campaign FOLDER."""
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.fleet.store import CampaignStore, read_runs
    from gyrodrift.fleet.study import run_study
    from gyrodrift.fleet.study_report import STUDY_FILES, summary_lines, write_study_report

    target = OutputFolder(out, "study", STUDY_FILES, inputs=[folder])
    runs = read_runs(folder)
    campaign = CampaignStore(folder).campaign()
    with show_warnings():
        study = run_study(runs, test_fraction=test_fraction, seed=seed, max_iter=max_iter, campaign=campaign)
    doc = study.to_dict()
    with target.publish() as stage:
        write_study_report(doc, stage)
    if as_json:
        print_json(
            {k: v for k, v in doc.items() if k != "methods"}
            | {"methods": {n: m["metrics"] for n, m in doc["methods"].items()}}
        )
    elif not quiet:
        for line in summary_lines(doc):
            click.echo(line)
    say_wrote([out / name for name in STUDY_FILES], quiet=quiet, as_json=as_json)


COMMANDS = (campaign_command, study_command)
