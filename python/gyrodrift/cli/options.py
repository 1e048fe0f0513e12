"""Options and output lines shared by the commands (the conventions of docs/cli.md).

The options of the commands that read IMU logs (the static site ``--lat0-deg``, ``--lon0-deg``, ``--height-m``
and ``--format``), the sensor noise (``--noise``, ...), an output folder ``--out``, ``--connect-timeout-s``,
``--json``, ``--quiet``, the one ``wrote ...`` line of every command that writes files, and warnings as
one ``warning: ...`` line each.
"""

from __future__ import annotations

import contextlib
import functools
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import click

from gyrodrift.cli.types import FiniteFloat, InputPath

__all__ = [
    "log_options",
    "noise_options",
    "out_folder_option",
    "choice_option",
    "connect_timeout_option",
    "json_option",
    "quiet_option",
    "print_json",
    "say_wrote",
    "show_warnings",
]


def log_options(f):
    """Add the options of a command reading an IMU log: the static site ``--lat0-deg``, ``--lon0-deg`` and
    ``--height-m`` (finite numbers; latitude strictly within +-90) and ``--format FILE``. The command receives them
    as ``site`` (the ``site`` mapping of `gyrodrift.logs.open_log`, None when no site option was given) and
    ``log_format`` (a path or None)."""

    @functools.wraps(f)
    def command(*args, lat0_deg, lon0_deg, height_m, **kwargs):
        return f(*args, site=_site_from_options(lat0_deg, lon0_deg, height_m), **kwargs)

    return _site_options(_log_format_option(command))


def _site_options(f):
    """Add ``--lat0-deg``, ``--lon0-deg`` and ``--height-m`` (finite numbers; latitude strictly within +-90)."""
    f = click.option(
        "--height-m",
        type=FiniteFloat(-1e4, 1e5),
        default=None,
        help="Site height above the ellipsoid [m]. Default: the log's, else 0.",
    )(f)
    f = click.option(
        "--lon0-deg",
        type=FiniteFloat(-360.0, 360.0),
        default=None,
        help="Site longitude [deg]. Default: the log's, else 0.",
    )(f)
    f = click.option(
        "--lat0-deg",
        type=FiniteFloat(-90.0, 90.0, min_open=True, max_open=True),
        default=None,
        help="True site latitude [deg]; needed for logs that carry no site (CSV). Default: the log's.",
    )(f)
    return f


def _site_from_options(lat0_deg: float | None, lon0_deg: float | None, height_m: float | None) -> dict | None:
    """The ``site`` mapping of `gyrodrift.logs.open_log` from the options given (None when none was)."""
    site = {}
    if lat0_deg is not None:
        site["lat_deg"] = lat0_deg
    if lon0_deg is not None:
        site["lon_deg"] = lon0_deg
    if height_m is not None:
        site["height_m"] = height_m
    return site or None


def _log_format_option(f):
    """Add ``--format FILE``: the log format description of a log with its own columns (`gyrodrift.logs.log_format`)."""
    return click.option(
        "--format",
        "log_format",
        type=InputPath(path_type=Path),
        default=None,
        help="Log format file (TOML) describing the log's own columns, units, axes, time stamps and CSV "
        "delimiter (docs/procedure.md, 'Logs in their own format'; examples/logs/). Default: the native columns "
        "(t_s, dtheta_x_rad, ...).",
    )(f)


def noise_options(f):
    """Add ``--noise FILE``, ``--gyro-arw-deg-rth`` and ``--accel-vrw-ug-rthz``: the sensor noise the smoother and
    the label's 1-sigma assume. The command receives it as ``noise``: a `gyrodrift.procedure.noise.SensorNoise`, or
    None when no noise option was given (measure it from the log)."""

    @functools.wraps(f)
    def command(*args, noise_file, gyro_arw_deg_rth, accel_vrw_ug_rthz, **kwargs):
        return f(*args, noise=_noise_from_options(noise_file, gyro_arw_deg_rth, accel_vrw_ug_rthz), **kwargs)

    click.option(
        "--accel-vrw-ug-rthz",
        type=FiniteFloat(0.0, 1e6, min_open=True),
        default=None,
        help="Accelerometer velocity random walk [ug/sqrt(Hz)] (with --gyro-arw-deg-rth, or over --noise's). "
        "Default: measured from the log.",
    )(command)
    click.option(
        "--gyro-arw-deg-rth",
        type=FiniteFloat(0.0, 1e3, min_open=True),
        default=None,
        help="Gyro angle random walk [deg/sqrt(h)] (with --accel-vrw-ug-rthz, or over --noise's). Default: "
        "measured from the log.",
    )(command)
    return click.option(
        "--noise",
        "noise_file",
        type=InputPath(path_type=Path),
        default=None,
        help="Noise file (TOML): [gyro] arw_deg_rth, [accel] vrw_ug_rthz, optionally [gyro] "
        "bias_instability_deg_h, correlation_s, rrw_deg_h_rth (a scenario file works). Default: measured from "
        "the log.",
    )(command)


def _noise_from_options(noise_file, gyro_arw_deg_rth: float | None, accel_vrw_ug_rthz: float | None):
    """The `SensorNoise` of the noise options, or None (measure it from the log)."""
    from dataclasses import replace

    from gyrodrift.procedure.noise import SensorNoise, load_noise_file

    if noise_file is None:
        if (gyro_arw_deg_rth is None) != (accel_vrw_ug_rthz is None):
            raise click.UsageError("give --gyro-arw-deg-rth and --accel-vrw-ug-rthz together (or --noise FILE)")
        if gyro_arw_deg_rth is None or accel_vrw_ug_rthz is None:
            return None
        return SensorNoise(arw_deg_rth=gyro_arw_deg_rth, vrw_ug_rthz=accel_vrw_ug_rthz, source="given")
    noise = load_noise_file(noise_file)
    if gyro_arw_deg_rth is not None:
        noise = replace(noise, arw_deg_rth=gyro_arw_deg_rth)
    if accel_vrw_ug_rthz is not None:
        noise = replace(noise, vrw_ug_rthz=accel_vrw_ug_rthz)
    return noise


def out_folder_option(files: str, *, required: bool = True, note: str = ""):
    """An option ``--out`` (the command's ``out_dir``): the folder receiving `files` ("for plan.json and
    plan.png"), new, empty, or holding only gyrodrift's outputs (`note` added to that rule). Not `required`: the
    command saves its result there only when given, and prints it either way."""
    rule = f"new, empty, or holding only gyrodrift's outputs{note} (docs/outputs.md)"
    presence: dict[str, Any] = {"required": True} if required else {"default": None}
    if required:
        text = f"Folder {files}: {rule}. Required."
    else:
        text = f"Also save the result: folder {files}, {rule}. Default: print only."
    return click.option("--out", "out_dir", type=click.Path(path_type=Path), help=text, **presence)


def choice_option(name: str, choices, default: str, help_text: str):
    """An option `name` taking one of `choices` [str], `default` when not given (shown in the help)."""
    return click.option(name, type=click.Choice(list(choices)), default=default, show_default=True, help=help_text)


def connect_timeout_option(f):
    """Add ``--connect-timeout-s``: how long to wait for a dask scheduler (``--scheduler``) to answer [s]."""
    return click.option(
        "--connect-timeout-s",
        type=FiniteFloat(min=0.0, max=3600.0, min_open=True),
        default=10.0,
        show_default=True,
        help="Time [s] to wait for --scheduler to answer before giving up.",
    )(f)


def json_option(f):
    """Add ``--json``: print the result as one JSON document on stdout (human lines go to stderr)."""
    return click.option(
        "--json",
        "as_json",
        is_flag=True,
        help="Print the result as JSON on stdout (the 'wrote ...' line goes to stderr). Default: text.",
    )(f)


def quiet_option(f):
    """Add ``--quiet``: no progress bar, summary or 'wrote ...' line (a result asked for on stdout still prints)."""
    return click.option(
        "--quiet",
        is_flag=True,
        help="No progress bar, summary or 'wrote ...' line; a result with no other place (stdout, --json) still "
        "prints, and warnings and notes still go to stderr. Default: off.",
    )(f)


def print_json(doc) -> None:
    """Print `doc` as indented JSON on stdout (NaN refused: not JSON)."""
    import json

    from gyrodrift.cli.errors import write_stdout

    write_stdout(json.dumps(_finite(doc), indent=2, allow_nan=False, default=str) + "\n")


def _finite(x):
    """`x` with every NaN or infinity replaced by None (JSON has no such numbers)."""
    import math

    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if hasattr(x, "tolist") and not isinstance(x, str):  # numpy scalars and arrays
        return _finite(x.tolist())
    return x


def say_wrote(paths, *, quiet: bool, as_json: bool = False, detail: str = "") -> None:
    """The one ``wrote PATH, PATH (detail)`` line of a command that wrote files: stdout, or stderr with --json so
    that stdout stays one JSON document; nothing with --quiet."""
    if quiet:
        return
    text = "wrote " + ", ".join(str(p) for p in paths) + (f" ({detail})" if detail else "")
    click.echo(text, err=as_json)


@contextlib.contextmanager
def show_warnings() -> Iterator[None]:
    """Collect the warnings raised inside (e.g. a tuned value on its search bound, an interval's outlying runs) and
    print each distinct one as one ``warning: ...`` line on stderr, instead of Python's two-line format naming a
    source line; also when the block raises."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        finally:
            for text in dict.fromkeys(str(w.message) for w in caught):
                click.echo(f"warning: {text}", err=True)
