"""Command-line interface: a thin layer over the same functions a notebook calls."""

import click

from gyrodrift import __version__


@click.group()
@click.version_option(__version__, prog_name="gyrodrift")
def main() -> None:
    """Identify the axial gyro drift of single-axis rotation RLG inertial navigation systems."""
