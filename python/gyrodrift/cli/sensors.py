"""Commands characterising the sensors of a log: `allan` (Allan deviation and noise parameters)."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.options import json_option, log_options, out_folder_option, print_json, quiet_option, say_wrote
from gyrodrift.cli.types import InputPath

__all__ = ["allan_command", "COMMANDS"]


@click.command("allan", epilog="Example: gyrodrift allan static.parquet --out allan")
@click.argument("log", type=InputPath(path_type=Path))
@out_folder_option("for allan.json, allan.png and noise.toml")
@log_options
@json_option
@quiet_option
def allan_command(
    log: Path,
    out_dir: Path,
    site: dict | None,
    log_format: Path | None,
    as_json: bool,
    quiet: bool,
) -> None:
    """Allan deviation of every gyro and accelerometer axis of a static LOG (turntable still), with the angle/velocity
    random walk, Gauss-Markov bias and rate random walk the log shows (a term not above the 99 % confidence interval
    of the Allan deviation at the averaging times the log reaches is "not resolved"), and a [gyro]/[accel] noise
    block for scenario files that says which axes it averages. Constant channels are named and left out; a log
    whose channels are all constant is refused. --json prints allan.json without its curves.
    """
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.logs import open_log
    from gyrodrift.sensors.allan import allan_deviation
    from gyrodrift.sensors.allan_output import ALLAN_FILES, allan_files, noise_summary

    out = OutputFolder(out_dir, "allan", ALLAN_FILES, inputs=[log])
    imu = open_log(log, site=site, format=log_format)
    result = allan_deviation(imu, quiet=quiet)
    if result.constant_axes:
        click.echo(
            f"warning: {imu.name}: {', '.join(result.constant_axes)} constant (every sample equal): no noise to "
            "measure, left out of the noise block",
            err=True,
        )
    paths = allan_files(result, out)
    if as_json:
        doc = result.to_dict()
        curves = ("tau_s", "adev_", "edf")
        doc["axes"] = {
            name: {k: v for k, v in entry.items() if not k.startswith(curves)} for name, entry in doc["axes"].items()
        }
        print_json(doc)
    elif not quiet:
        click.echo(f"{imu.name}: {noise_summary(result)}")
    say_wrote(paths, quiet=quiet, as_json=as_json)


COMMANDS = (allan_command,)
