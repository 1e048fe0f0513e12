"""``--example NAME``: a shipped scenario or campaign (`gyrodrift.files.examples`) in place of a file argument."""

from __future__ import annotations

from pathlib import Path

import click

__all__ = ["example_option", "file_or_example"]


def example_option(kind: str):
    """The ``--example NAME`` option of a command whose file argument (a `kind` file) it replaces."""
    from gyrodrift.files.examples import EXAMPLE_KINDS

    folder = EXAMPLE_KINDS[kind]
    return click.option(
        "--example",
        "example",
        metavar="NAME",
        default=None,
        help=f"Use the {kind} NAME shipped with gyrodrift (gyrodrift/examples/{folder}/NAME.toml, the same file as "
        f"the clone's examples/{folder}/) instead of a file argument. Default: none.",
    )


def file_or_example(path: Path | None, example: str | None, kind: str, argument: str) -> Path:
    """The file a command reads: `path` (its `argument`) or the shipped example `example`, exactly one of them."""
    from gyrodrift.errors import OptionError
    from gyrodrift.files.examples import example_path

    if example is not None and path is None:
        return example_path(kind, example)
    if path is None or example is not None:
        raise OptionError(f"give {argument} or --example NAME (a {kind} shipped with gyrodrift), exactly one")
    return path
