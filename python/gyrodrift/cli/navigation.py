"""Commands on the Rust core: `simulate` (scenario -> IMU log) and `navigate` (IMU log -> navigation errors)."""

from __future__ import annotations

from pathlib import Path

import click

__all__ = ["simulate_command", "navigate_command"]


@click.command("simulate")
@click.argument("scenario_toml", metavar="SCENARIO.toml", type=click.Path(path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Folder receiving imu.parquet and scenario.resolved.toml (created if needed).",
)
@click.option("--quiet", is_flag=True, help="No progress bar.")
def simulate_command(scenario_toml: Path, out_dir: Path, quiet: bool) -> None:
    """Simulate the IMU of a static-base rotation INS described by SCENARIO.toml."""
    from gyrodrift.ins.scenario import ScenarioError, load_scenario
    from gyrodrift.ins.simulate import rotation_summary, simulate

    try:
        scenario = load_scenario(scenario_toml)
    except ScenarioError as exc:
        raise click.ClickException(str(exc)) from None
    try:
        path = simulate(scenario, out_dir=out_dir, quiet=quiet)
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


@click.command("navigate")
@click.argument("imu_parquet", metavar="IMU.parquet", type=click.Path(path_type=Path))
@click.option(
    "--hours",
    type=click.FloatRange(min=0.0, min_open=True),
    default=None,
    help="Navigate only the first H hours [h] (default: the whole file).",
)
@click.option(
    "--compensate-drift-deg-h",
    type=float,
    default=0.0,
    show_default=True,
    help="Axial drift estimate [deg/h] subtracted from the z gyro (measured - estimate).",
)
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Folder receiving nav.parquet and summary.json (created if needed).",
)
@click.option("--quiet", is_flag=True, help="No progress bar and no summary line.")
def navigate_command(
    imu_parquet: Path, hours: float | None, compensate_drift_deg_h: float, out_dir: Path, quiet: bool
) -> None:
    """Navigate IMU.parquet (written by `simulate`) and report the position error against the truth."""
    from gyrodrift.ins.imu_file import ImuFileError
    from gyrodrift.ins.navigate import navigate

    try:
        result = navigate(
            imu_parquet, hours=hours, compensate_drift_deg_h=compensate_drift_deg_h, out_dir=out_dir, quiet=quiet
        )
    except ImuFileError as exc:
        raise click.ClickException(str(exc)) from None
    except ValueError as exc:  # e.g. no truth in the file, or the core refused the data
        raise click.ClickException(f"{imu_parquet}: {exc}") from None
    if not quiet:
        s = result.summary
        if s["final_pos_err_nmi"] is not None:
            click.echo(
                f"{s['hours_navigated']:.3f} h: final position error {s['final_pos_err_nmi']:.4f} nmi, "
                f"max {s['max_pos_err_nmi']:.4f} nmi; wrote {out_dir / 'nav.parquet'}, {out_dir / 'summary.json'}"
            )
        else:
            click.echo(f"wrote {out_dir / 'nav.parquet'}, {out_dir / 'summary.json'} (no truth in the file)")


COMMANDS = (simulate_command, navigate_command)
