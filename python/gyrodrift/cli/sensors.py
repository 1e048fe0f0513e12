"""Commands characterising the sensors of a log: `allan` (Allan deviation and noise parameters)."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.options import (
    json_option,
    log_format_option,
    print_json,
    quiet_option,
    say_wrote,
    site_from_options,
    site_options,
)
from gyrodrift.cli.types import InputPath

__all__ = ["allan_command", "COMMANDS"]


@click.command("allan", epilog="Example: gyrodrift allan static.parquet --out allan")
@click.argument("log", type=InputPath(path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder for allan.json, allan.png and noise.toml: new, empty, or holding only gyrodrift's outputs "
    "(docs/outputs.md). Required.",
)
@site_options
@log_format_option
@json_option
@quiet_option
def allan_command(
    log: Path,
    out_dir: Path,
    lat0_deg: float | None,
    lon0_deg: float | None,
    height_m: float | None,
    log_format: Path | None,
    as_json: bool,
    quiet: bool,
) -> None:
    """Allan deviation of every gyro and accelerometer axis of a static LOG (turntable still), with the fitted
    angle/velocity random walk, Gauss-Markov bias and rate random walk, and a [gyro]/[accel] noise block
    for scenario files.
    """
    from gyrodrift.allan import allan_deviation, scenario_noise_block
    from gyrodrift.allan_output import ALLAN_FILES, allan_files
    from gyrodrift.atomic import OutputFolder
    from gyrodrift.logs import open_log

    out = OutputFolder(out_dir, "allan", ALLAN_FILES, inputs=[log])
    imu = open_log(log, site=site_from_options(lat0_deg, lon0_deg, height_m), format=log_format)
    result = allan_deviation(imu, quiet=quiet)
    paths = allan_files(result, out)
    noise = scenario_noise_block(result)
    if as_json:
        print_json(noise)
    elif not quiet:
        g, a = noise["gyro"], noise["accel"]
        click.echo(
            f"{imu.name}: gyro ARW {g['arw_deg_rth']:.4g} deg/sqrt(h), Gauss-Markov {g['bias_instability_deg_h']:.3g} "
            f"deg/h over {g['correlation_s']:.0f} s, RRW {g['rrw_deg_h_rth']:.3g} deg/h/sqrt(h); "
            f"accel VRW {a['vrw_ug_rthz']:.4g} ug/sqrt(Hz)"
        )
    say_wrote(paths, quiet=quiet, as_json=as_json)


COMMANDS = (allan_command,)
