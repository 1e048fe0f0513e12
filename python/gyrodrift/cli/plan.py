"""`gyrodrift plan`: how long to observe a static base before the mission (`gyrodrift.procedure.plan`)."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.options import json_option, noise_options, out_folder_option, print_json, quiet_option, say_wrote

__all__ = ["plan_command", "COMMANDS"]

SCHEMES = ("none", "continuous", "reciprocating", "indexing")


@click.command(
    "plan",
    epilog="Example: gyrodrift plan --noise allan/noise.toml --lat0-deg 40 --out plan",
)
@out_folder_option("for plan.json and plan.png")
@click.option(
    "--scenario",
    "scenario_path",
    type=click.Path(path_type=Path),
    default=None,
    help="Scenario TOML file giving the site, sample rate, rotation scheme, attitude and (without NOISE options) "
    "the noise. Default: the default scenario at --lat0-deg.",
)
@noise_options
@click.option(
    "--lat0-deg",
    type=float,
    default=None,
    help="Site latitude [deg] (overrides the scenario's). Default: the scenario's; one of the two is required.",
)
@click.option(
    "--rotation",
    type=click.Choice(SCHEMES),
    default=None,
    help="Rotation scheme with its default settings (overrides the scenario's). Default: the scenario's, else "
    "reciprocating.",
)
@click.option(
    "--coeff-std-deg-h-per-c",
    type=click.FloatRange(min=0),
    default=0.0,
    show_default=True,
    help="1-sigma of the z gyro's thermal coefficient k_z [deg/h/degC] (e.g. gyrodrift fit's pooled k_z prior).",
)
@click.option(
    "--temp-change-c",
    type=float,
    default=0.0,
    show_default=True,
    help="Temperature change [degC] the identification does not see through (adds k_z 1-sigma x change).",
)
@click.option(
    "--budget-nmi",
    type=click.FloatRange(min=0, min_open=True),
    default=1.0,
    show_default=True,
    help="Position-error budget [nmi].",
)
@click.option(
    "--mission-h",
    type=click.FloatRange(min=0.1, max=1000),
    default=72.0,
    show_default=True,
    help="Hours of navigation the budget holds for [h].",
)
@click.option(
    "--share",
    type=click.FloatRange(min=0, max=1, min_open=True, max_open=True),
    default=0.95,
    show_default=True,
    help="Share of runs that must meet the budget (0-1).",
)
@click.option(
    "--min-span-h",
    type=click.FloatRange(min=0.5),
    default=6.0,
    show_default=True,
    help="Shortest observation span searched [h] from the first sample.",
)
@click.option(
    "--max-span-h",
    type=click.FloatRange(min=0.5, max=55),
    default=48.0,
    show_default=True,
    help="Longest observation span searched [h] from the first sample (at most 55).",
)
@json_option
@quiet_option
def plan_command(
    out_dir: Path,
    scenario_path: Path | None,
    noise,
    lat0_deg: float | None,
    rotation: str | None,
    coeff_std_deg_h_per_c: float,
    temp_change_c: float,
    budget_nmi: float,
    mission_h: float,
    share: float,
    min_span_h: float,
    max_span_h: float,
    as_json: bool,
    quiet: bool,
) -> None:
    """Plan the static identification: the 1-sigma of the identified axial drift against the observation span
    (alignment + static navigation), the predicted quantile of the mission's position error after compensating it
    (the error floor included: the noise over the mission and the alignment's leftovers), and the shortest span
    meeting the budget. A covariance analysis with the 16 h smoother's error model: no simulation, a few seconds.
    """
    import dataclasses

    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.ins.scenario import Rotation, Scenario, load_scenario
    from gyrodrift.procedure.noise import SensorNoise
    from gyrodrift.procedure.plan import MissionBudget, plan_identification
    from gyrodrift.procedure.plan_output import PLAN_FILES, plan_files

    if scenario_path is None and lat0_deg is None:
        raise click.UsageError("give --lat0-deg or --scenario FILE (the site)")
    out = OutputFolder(out_dir, "plan", PLAN_FILES, inputs=[] if scenario_path is None else [scenario_path])
    if scenario_path is not None:
        scenario = load_scenario(scenario_path)
        if noise is None:
            data = scenario.to_toml_dict()
            noise = SensorNoise.from_block({"gyro": data["gyro"], "accel": data["accel"]}, source=str(scenario_path))
    else:
        scenario = Scenario.from_dict({"site": {"lat_deg": float(lat0_deg or 0.0)}}, source="--lat0-deg")
    if noise is None:
        raise click.UsageError(
            "give the noise: --noise FILE, --gyro-arw-deg-rth and --accel-vrw-ug-rthz, or --scenario"
        )
    if rotation is not None:
        scenario = dataclasses.replace(scenario, rotation=Rotation(scheme=rotation))
    if not max_span_h > min_span_h:
        raise click.BadParameter(f"must be > --min-span-h ({min_span_h:g})", param_hint="--max-span-h")
    plan = plan_identification(
        noise,
        scenario=scenario,
        lat_deg=lat0_deg,
        budget=MissionBudget(error_nmi=budget_nmi, hours=mission_h, share=share),
        coeff_std_deg_h_per_c=coeff_std_deg_h_per_c,
        temp_change_c=temp_change_c,
        min_span_h=min_span_h,
        max_span_h=max_span_h,
    )
    paths = plan_files(plan, out)
    if as_json:
        print_json(plan.to_dict())
    elif not quiet:
        click.echo(plan.reason)
        for h in sorted({min_span_h, 10.0, 16.0, 24.0, max_span_h}):
            if min_span_h <= h <= max_span_h:
                i = int(abs(plan.spans_h - h).argmin())
                click.echo(
                    f"  {plan.spans_h[i]:5.2f} h: drift 1-sigma {plan.drift_std_deg_h[i]:.2e} deg/h, "
                    f"{100 * share:g} % quantile {plan.quantile_nmi[i]:.2f} nmi, "
                    f"{100 * plan.share_within[i]:.1f} % of runs within {budget_nmi:g} nmi"
                )
    say_wrote(paths, quiet=quiet, as_json=as_json)


COMMANDS = (plan_command,)
