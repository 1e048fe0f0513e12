"""Commands on the Rust core: `simulate` (scenario -> IMU log) and `navigate` (IMU log -> navigation errors)."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.options import site_from_options, site_options
from gyrodrift.cli.types import FiniteFloat

__all__ = ["simulate_command", "navigate_command"]


@click.command("simulate")
@click.argument("scenario_toml", metavar="SCENARIO.toml", type=click.Path(path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder receiving imu.parquet and scenario.resolved.toml: new, empty, or holding only gyrodrift's "
    "outputs (docs/outputs.md).",
)
@click.option("--quiet", is_flag=True, help="No progress bar.")
def simulate_command(scenario_toml: Path, out_dir: Path, quiet: bool) -> None:
    """Simulate the IMU of a static-base rotation INS described by SCENARIO.toml."""
    from gyrodrift.atomic import OutputFolder
    from gyrodrift.ins.scenario import ScenarioError, load_scenario
    from gyrodrift.ins.simulate import SIMULATION_FILES, rotation_summary, simulate

    out = OutputFolder(out_dir, "simulate", SIMULATION_FILES, inputs=[scenario_toml])
    try:
        scenario = load_scenario(scenario_toml)
    except ScenarioError as exc:
        raise click.ClickException(str(exc)) from None
    try:
        path = simulate(scenario, out_dir=out, quiet=quiet)
    except ValueError as exc:  # the core refused the configuration
        raise click.ClickException(f"{scenario_toml}: {exc}") from None
    if not quiet:
        rot = rotation_summary(scenario)
        span = f", span {rot['span_deg']:.4f} deg" if rot["span_deg"] is not None else ""
        click.echo(
            f"wrote {path} ({scenario.n_samples} samples) and {out_dir / 'scenario.resolved.toml'}; "
            f"{scenario.rotation.scheme} rotation{span}, modulation residual "
            f"{100 * rot['modulation_residual']:.3f} % of the horizontal sensor errors"
        )


_INITIAL_WORDS = {
    "truth": "the log's truth (scenario metadata or true attitude columns)",
    "alignment": "an alignment of the log's first hours (navigation starts at its end)",
    "given": "the given values",
}


@click.command("navigate")
@click.argument("log", metavar="LOG", type=click.Path(path_type=Path))
@click.option(
    "--hours",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="Navigate only H hours [h] from the start of navigation (default: to the end of the log).",
)
@click.option(
    "--compensate-drift-deg-h",
    type=FiniteFloat(),
    default=0.0,
    show_default=True,
    help="Axial drift estimate [deg/h] subtracted from the z gyro (measured - estimate).",
)
@click.option(
    "--initial",
    type=click.Choice(["auto", "truth", "alignment"]),
    default="auto",
    show_default=True,
    help="Initial state: the log's truth (simulated logs), an alignment of its first 4 h (navigation starts at "
    "the end of it), or auto (truth when the log carries it, else alignment).",
)
@site_options
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder receiving nav.parquet and summary.json: new, empty, or holding only gyrodrift's outputs, "
    "e.g. the simulation's own folder (docs/outputs.md).",
)
@click.option("--quiet", is_flag=True, help="No progress bar and no summary line.")
def navigate_command(
    log: Path,
    hours: float | None,
    compensate_drift_deg_h: float,
    initial: str,
    lat0_deg: float | None,
    lon0_deg: float | None,
    height_m: float | None,
    out_dir: Path,
    quiet: bool,
) -> None:
    """Navigate LOG (any IMU log: Parquet or CSV) and report the position error against the static site.

    The initial state comes from the log's truth (simulated logs), else from an alignment of the log; the
    summary line and summary.json (initial_source) say which.
    """
    from gyrodrift.ins.navigate import navigate

    result = navigate(
        log,
        hours=hours,
        compensate_drift_deg_h=compensate_drift_deg_h,
        initial=initial,
        site=site_from_options(lat0_deg, lon0_deg, height_m),
        out_dir=out_dir,
        quiet=quiet,
    )
    if not quiet:
        s = result.summary
        source = f"initial state from {_INITIAL_WORDS[s['initial_source']]}"
        if s["final_pos_err_nmi"] is not None:
            click.echo(
                f"{s['hours_navigated']:.3f} h ({source}): final position error {s['final_pos_err_nmi']:.4f} nmi, "
                f"max {s['max_pos_err_nmi']:.4f} nmi; wrote {out_dir / 'nav.parquet'}, {out_dir / 'summary.json'}"
            )
        else:
            click.echo(
                f"{s['hours_navigated']:.3f} h ({source}); wrote {out_dir / 'nav.parquet'}, "
                f"{out_dir / 'summary.json'} (no site known: no position errors)"
            )


COMMANDS = (simulate_command, navigate_command)
