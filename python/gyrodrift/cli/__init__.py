"""The `gyrodrift` command: a thin layer over the same functions a notebook calls.

One module per family of commands, each registering its commands in the one group `main`:

- `gyrodrift.cli.learning`: `fit`, `predict`, `reproduce` (run tables and drift models);
- `gyrodrift.cli.navigation`: `simulate`, `navigate` (the Rust core on scenarios and IMU logs);
- `gyrodrift.cli.procedure`: `features`, `truth`, `evaluate`, `identify` (from an IMU log to a compensation);
- `gyrodrift.cli.plan`: `plan` (how long to observe before the mission);
- `gyrodrift.cli.sensors`: `allan` (noise of a static log).

Heavy imports (numpy, pyarrow, scikit-learn, the Rust extension) happen inside the commands, so that
``gyrodrift --help`` starts at once. Errors have one handler, `_OneLineErrors`: every expected failure
(`gyrodrift.errors.GyrodriftError`) and every file-system failure (`OSError`) becomes one line on stderr and
exit status 1; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import errno

import click

from gyrodrift import __version__
from gyrodrift.cli.errors import STDOUT_NAME, one_line_message, stdout_failure
from gyrodrift.errors import GyrodriftError

__all__ = ["main"]


class _OneLineErrors(click.Group):
    """A click group whose commands' expected failures become one-line `click.ClickException`s."""

    def invoke(self, ctx: click.Context):
        try:
            result = super().invoke(ctx)
            if failure := stdout_failure():  # stdout's last buffered bytes, while errors are still ours
                raise failure
            return result
        except (GyrodriftError, OSError) as exc:
            if isinstance(exc, OSError) and exc.filename is None and not isinstance(exc, GyrodriftError):
                exc = stdout_failure(exc) or exc  # a write to stdout failed (full device, closed pipe)
            if isinstance(exc, OSError) and exc.errno == errno.EPIPE and exc.filename == STDOUT_NAME:
                ctx.exit(1)  # the reader went away (| head): nothing to say, nobody to say it to
            raise click.ClickException(one_line_message(exc)) from None


@click.group(
    cls=_OneLineErrors,
    epilog="Example: gyrodrift simulate --example tour --out sim && gyrodrift truth sim/imu.parquet "
    "(the whole tour: README.md; the conventions shared by every command: docs/cli.md)",
)
@click.version_option(__version__, prog_name="gyrodrift")
def main() -> None:
    """Identify the axial gyro drift of single-axis rotation RLG inertial navigation systems.

    Every command reads its inputs as arguments and options in SI-with-unit names (--drift-deg-h, --hours),
    writes with --out, prints JSON with --json and stays silent with --quiet.
    """


def _register_commands() -> None:
    from gyrodrift.cli import campaign, export, learning, navigation, plan, procedure, sensors

    for module in (learning, navigation, procedure, plan, sensors, export, campaign):
        for command in module.COMMANDS:
            main.add_command(command)


_register_commands()
