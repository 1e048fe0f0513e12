"""Commands characterising the sensors of a log: `allan` (Allan deviation and noise parameters)."""

from __future__ import annotations

from pathlib import Path

import click

__all__ = ["allan_command", "COMMANDS"]


@click.command("allan")
@click.argument("log", type=click.Path(path_type=Path))
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder for allan.json, allan.png and noise.toml (created if needed).",
)
@click.option("--quiet", is_flag=True, help="No progress bar and no summary.")
def allan_command(log: Path, out_dir: Path, quiet: bool) -> None:
    """Allan deviation of every gyro and accelerometer axis of a static LOG (turntable still), with the fitted
    angle/velocity random walk, Gauss-Markov bias and rate random walk, and a [gyro]/[accel] noise block
    for scenario files.

    Example: gyrodrift allan static.parquet --out allan
    """
    from gyrodrift.allan import allan_deviation, scenario_noise_block
    from gyrodrift.allan_output import ALLAN_FILES, allan_files
    from gyrodrift.atomic import OutputFolder
    from gyrodrift.logs import open_log

    out = OutputFolder(out_dir, "allan", ALLAN_FILES, inputs=[log])
    imu = open_log(log)
    result = allan_deviation(imu, quiet=quiet)
    paths = allan_files(result, out)
    if not quiet:
        noise = scenario_noise_block(result)
        g, a = noise["gyro"], noise["accel"]
        click.echo(
            f"{imu.name}: gyro ARW {g['arw_deg_rth']:.4g} deg/sqrt(h), Gauss-Markov {g['bias_instability_deg_h']:.3g} "
            f"deg/h over {g['correlation_s']:.0f} s, RRW {g['rrw_deg_h_rth']:.3g} deg/h/sqrt(h); "
            f"accel VRW {a['vrw_ug_rthz']:.4g} ug/sqrt(Hz)"
        )
        click.echo("wrote " + ", ".join(str(p) for p in paths))


COMMANDS = (allan_command,)
