"""The `gyrodrift` command: a thin layer over the same functions a notebook calls.

One module per family of commands, each registering its commands in the one group `main`:

- `gyrodrift.cli.learning`: `fit`, `predict`, `reproduce` (run tables and drift models);
- `gyrodrift.cli.navigation`: `simulate`, `navigate` (the Rust core on scenarios and IMU logs);
- `gyrodrift.cli.procedure`: `features`, `truth`, `evaluate`, `identify` (from an IMU log to a compensation);
- `gyrodrift.cli.sensors`: `allan` (noise of a static log).

Heavy imports (numpy, pyarrow, scikit-learn, the Rust extension) happen inside the commands, so that
``gyrodrift --help`` starts at once. Errors have one handler, `_OneLineErrors`: every expected failure
(`gyrodrift.errors.GyrodriftError`) and every file-system failure (`OSError`) becomes one line on stderr and
exit status 1; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import click

from gyrodrift import __version__
from gyrodrift.cli.errors import one_line_message
from gyrodrift.errors import GyrodriftError

__all__ = ["main"]


class _OneLineErrors(click.Group):
    """A click group whose commands' expected failures become one-line `click.ClickException`s."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except (GyrodriftError, OSError) as exc:
            raise click.ClickException(one_line_message(exc)) from None


@click.group(cls=_OneLineErrors)
@click.version_option(__version__, prog_name="gyrodrift")
def main() -> None:
    """Identify the axial gyro drift of single-axis rotation RLG inertial navigation systems."""


def _register_commands() -> None:
    from gyrodrift.cli import learning, navigation, procedure, sensors

    for module in (learning, navigation, procedure, sensors):
        for command in module.COMMANDS:
            main.add_command(command)


_register_commands()
