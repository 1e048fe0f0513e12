"""Command putting a drift model on the navigation computer: `export` (C99 or no_std Rust source)."""

from __future__ import annotations

from pathlib import Path

import click


@click.command("export")
@click.argument("model_file", metavar="MODEL.json", type=click.Path(path_type=Path))
@click.option(
    "--lang",
    required=True,
    metavar="c|rust",
    help="c: gyrodrift_model.h and gyrodrift_model.c (C99); rust: gyrodrift_model.rs (a no_std module).",
)
@click.option(
    "--out",
    "out_dir",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder for the generated files: new, empty, or holding only gyrodrift's outputs (docs/outputs.md).",
)
def export_command(model_file: Path, lang: str, out_dir: Path) -> None:
    """Write MODEL.json as source code computing the identified drift [deg/h] on a navigation computer.

    The code carries the model's provenance and the training ranges of its inputs, with a function saying
    whether an input lies within them (docs/export.md).

    Example: gyrodrift export model.json --lang c --out nav/
    """
    import hashlib

    from gyrodrift.atomic import OutputFolder
    from gyrodrift.export import export_model, output_names
    from gyrodrift.model_io import load_model

    names = output_names(lang)
    out = OutputFolder(out_dir, f"export --lang {lang}", names, inputs=[model_file])
    model = load_model(model_file)
    digest = hashlib.sha256(model_file.read_bytes()).hexdigest()
    files = export_model(model, lang, model_sha256=digest)
    with out.publish() as stage:
        for name, text in files.items():
            stage.file(name).write_text(text, encoding="utf-8")
    click.echo(f"{', '.join(str(out_dir / name) for name in names)} ({model.encoding}, {model.lssvr.kernel})")


COMMANDS = (export_command,)
