"""Commands on the Rust core: `simulate` (scenario -> IMU log) and `navigate` (IMU log -> navigation errors)."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.examples import example_option, file_or_example
from gyrodrift.cli.options import (
    choice_option,
    json_option,
    log_options,
    out_folder_option,
    print_json,
    quiet_option,
    say_wrote,
)
from gyrodrift.cli.types import DRIFT_DEG_H, FiniteFloat, InputPath, Seed

__all__ = ["simulate_command", "navigate_command", "drift_law_option", "compensation_of"]

drift_law_option = click.option(
    "--drift-law",
    "drift_law_path",
    metavar="FILE",
    type=InputPath(path_type=Path),
    default=None,
    help="Drift law to compensate instead of a constant: a JSON file holding a drift_law object (identification.json "
    "of `gyrodrift identify`, or the law alone), eps_ref + k1 (T - t_ref) + k3 dT/dt [deg/h] evaluated sample by "
    "sample on the log's temp_c. Not with --drift-deg-h. Default: none.",
)


def compensation_of(drift_deg_h: float | None, drift_law_path: Path | None):
    """The `gyrodrift.drift_law.DriftLaw` of ``--drift-deg-h`` (a constant) or ``--drift-law`` (read from its file),
    or None when neither is given; both is a usage error."""
    from gyrodrift.drift_law import DriftLaw
    from gyrodrift.ins.compensation import load_drift_law

    if drift_deg_h is not None and drift_law_path is not None:
        raise click.UsageError("give --drift-deg-h (a constant) or --drift-law (a law), not both")
    if drift_law_path is not None:
        return load_drift_law(drift_law_path)
    return None if drift_deg_h is None else DriftLaw.constant(drift_deg_h)


@click.command(
    "simulate",
    epilog="Example: gyrodrift simulate --example tour --seed 2 --duration-h 20 --out sim",
)
@click.argument("scenario_toml", metavar="[SCENARIO.toml]", required=False, type=InputPath(path_type=Path))
@example_option("scenario")
@out_folder_option("receiving imu.parquet and scenario.resolved.toml")
@click.option(
    "--duration-h",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="Length of the simulated log [h], over [run] duration_h. Default: the scenario's.",
)
@click.option(
    "--seed",
    type=Seed(),
    default=None,
    help="Seed of the sensor noise (an integer >= 0), over [run] seed. Default: the scenario's.",
)
@click.option(
    "--rate-hz",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="IMU sample rate [Hz], over [run] rate_hz. Default: the scenario's.",
)
@json_option
@quiet_option
def simulate_command(
    scenario_toml: Path | None,
    example: str | None,
    out_dir: Path,
    duration_h: float | None,
    seed: int | None,
    rate_hz: float | None,
    as_json: bool,
    quiet: bool,
) -> None:
    """Simulate the IMU of a rotation INS described by SCENARIO.toml (or by a shipped --example).

    --duration-h, --seed and --rate-hz replace the scenario's [run] values; they are checked as the file's keys
    are and recorded in scenario.resolved.toml.
    """
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.ins.scenario import Scenario, ScenarioError, load_scenario
    from gyrodrift.ins.simulate import SIMULATION_FILES, rotation_summary, simulate

    scenario_toml = file_or_example(scenario_toml, example, "scenario", "SCENARIO.toml")
    out = OutputFolder(out_dir, "simulate", SIMULATION_FILES, inputs=[scenario_toml])
    scenario = load_scenario(scenario_toml)
    overrides = {"duration_h": duration_h, "seed": seed, "rate_hz": rate_hz}
    given = {k: v for k, v in overrides.items() if v is not None}
    if given:
        data = scenario.to_toml_dict()
        data["run"].update(given)
        flags = " ".join(f"--{k.replace('_', '-')} {v:g}" for k, v in given.items())
        scenario = Scenario.from_dict(data, source=f"{scenario_toml} with {flags}", base_dir=scenario_toml.parent)
    try:
        path = simulate(scenario, out_dir=out, quiet=quiet)
    except ValueError as exc:  # the core refused the configuration: name the file it came from
        if str(exc).startswith(str(scenario_toml)):
            raise
        raise ScenarioError(f"{scenario_toml}: {exc}") from None
    rot = rotation_summary(scenario)
    resolved = out_dir / "scenario.resolved.toml"
    if as_json:
        print_json(
            {
                "imu": str(path),
                "scenario": str(resolved),
                "n_samples": scenario.n_samples,
                "run": scenario.to_toml_dict()["run"],
                "rotation": {"scheme": scenario.rotation.scheme, **rot},
            }
        )
    span = f", span {rot['span_deg']:.4f} deg" if rot["span_deg"] is not None else ""
    say_wrote(
        [path, resolved],
        quiet=quiet,
        as_json=as_json,
        detail=f"{scenario.n_samples} samples, {scenario.run.duration_h:g} h at {scenario.run.rate_hz:g} Hz, seed "
        f"{scenario.run.seed}; {scenario.rotation.scheme} rotation{span}, modulation residual "
        f"{100 * rot['modulation_residual']:.3f} % of the horizontal sensor errors",
    )


_INITIAL_WORDS = {
    "truth": "the log's truth (scenario metadata or true attitude columns)",
    "alignment": "an alignment of the log's first hours (navigation starts at its end)",
    "given": "the given values",
}


@click.command(
    "navigate",
    epilog="Example: gyrodrift navigate sim/imu.parquet --hours 12 --drift-deg-h 0.0038 --out nav",
)
@click.argument("log", metavar="LOG", type=InputPath(path_type=Path))
@click.option(
    "--hours",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="Hours of free navigation [h], counted from the start of navigation (the end of the alignment when the "
    "initial state comes from one). Default: to the end of the log.",
)
@click.option(
    "--drift-deg-h",
    type=DRIFT_DEG_H,
    default=None,
    help="Axial drift estimate [deg/h] subtracted from the z gyro (measured - estimate). Default: none.",
)
@drift_law_option
@click.option(
    "--compensate-drift-deg-h",
    "old_drift_deg_h",
    type=DRIFT_DEG_H,
    default=None,
    hidden=True,
    help="Deprecated name of --drift-deg-h [deg/h].",
)
@choice_option(
    "--initial",
    ("auto", "truth", "alignment"),
    "auto",
    "Initial state: the log's truth (simulated logs), an alignment of its first 4 h (navigation starts at "
    "the end of it), or auto (truth when the log carries it, else alignment).",
)
@log_options
@out_folder_option(
    "receiving nav.parquet (the curves: state and errors every 1 s) and summary.json, and navigation.png with --plot",
    note=", e.g. the simulation's own folder",
)
@click.option(
    "--plot",
    is_flag=True,
    help="Also write navigation.png into --out: position error [nmi] with the 1 nmi line, latitude/longitude "
    "errors [arcsec] and, for logs with the true attitude, pitch/roll/yaw errors [arcsec] vs time [h]. "
    "Default: off.",
)
@json_option
@quiet_option
def navigate_command(
    log: Path,
    hours: float | None,
    drift_deg_h: float | None,
    drift_law_path: Path | None,
    old_drift_deg_h: float | None,
    initial: str,
    site: dict | None,
    log_format: Path | None,
    out_dir: Path,
    plot: bool,
    as_json: bool,
    quiet: bool,
) -> None:
    """Navigate LOG (any IMU log: Parquet or CSV) and report the position error against the static site.

    The initial state comes from the log's truth (simulated logs), else from an alignment of the log; the
    summary line and summary.json (initial_source) say which, and which axial drift was compensated (compensation,
    drift_law).
    """
    from gyrodrift.errors import OptionError
    from gyrodrift.ins.compensation import compensation_words
    from gyrodrift.procedure.navigate import nav_files, navigate

    if old_drift_deg_h is not None:
        if drift_deg_h is not None:
            raise OptionError("give --drift-deg-h only (--compensate-drift-deg-h is its deprecated name)")
        click.echo("warning: --compensate-drift-deg-h is deprecated; use --drift-deg-h", err=True)
        drift_deg_h = old_drift_deg_h
    law = compensation_of(drift_deg_h, drift_law_path)
    from gyrodrift.logs import ImuLog, open_log

    imu: Path | ImuLog = log
    if log_format is not None:  # the site goes to the log it completes
        imu, site = open_log(log, site=site, format=log_format, require_temperature=False), None
    result = navigate(
        imu,
        hours=hours,
        drift_law=law,
        initial=initial,
        site=site,
        out_dir=out_dir,
        plot=plot,
        quiet=quiet,
    )
    s = result.summary
    if as_json:
        print_json(s)
    written = [out_dir / name for name in nav_files(plot)]
    source = f"initial state from {_INITIAL_WORDS[s['initial_source']]}"
    if s.get("vertical") == "damped":
        source += f", vertical channel damped to the {s['vertical_reference']}"
    source += ", no axial drift compensated" if law is None else f", compensating the {compensation_words(law)}"
    if s["final_pos_err_nmi"] is not None:
        detail = (
            f"{s['hours_navigated']:.3f} h, {source}: final position error {s['final_pos_err_nmi']:.4f} nmi, "
            f"max {s['max_pos_err_nmi']:.4f} nmi"
        )
    else:
        detail = f"{s['hours_navigated']:.3f} h, {source}; no site known: no position errors"
    say_wrote(written, quiet=quiet, as_json=as_json, detail=detail)


COMMANDS = (simulate_command, navigate_command)
