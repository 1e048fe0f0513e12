"""Command putting a drift model on the navigation computer: `export` (C99 or no_std Rust source)."""

from __future__ import annotations

from pathlib import Path

import click

from gyrodrift.cli.options import json_option, out_folder_option, print_json, quiet_option, say_wrote
from gyrodrift.cli.types import InputPath


@click.command("export", epilog="Example: gyrodrift export --model model.json --lang c --out nav")
@click.option(
    "--model",
    "model_file",
    required=True,
    type=InputPath(path_type=Path),
    help="Drift model file (JSON, from `gyrodrift fit`). Required.",
)
@click.option(
    "--lang",
    required=True,
    metavar="c|rust",
    help="c: gyrodrift_model.h and gyrodrift_model.c (C99); rust: gyrodrift_model.rs (a no_std module). Required.",
)
@out_folder_option("for the generated files")
@json_option
@quiet_option
def export_command(model_file: Path, lang: str, out_dir: Path, as_json: bool, quiet: bool) -> None:
    """Write the --model file as source code computing the identified drift [deg/h] on a navigation computer.

    The code carries the model's provenance and the training ranges of its inputs, with a function saying
    whether an input lies within them (docs/export.md). A hybrid model (the default of `fit`) returns its
    physics estimate plus the learned correction: the 12 h inversion is computed from the latitudes; the curve
    fit or the smoother is one more input [deg/h] that the navigation computer computes; the fleet-prior smoother
    is computed from the smoother's end drift and k_z estimate (inputs) with the fleet's k_z prior (constants).
    """
    import hashlib

    from gyrodrift.export.languages import export_model, output_names
    from gyrodrift.export.spec import export_spec, physics_column
    from gyrodrift.files.atomic import OutputFolder
    from gyrodrift.learn.model_io import load_predictor

    names = output_names(lang)
    out = OutputFolder(out_dir, f"export --lang {lang}", names, inputs=[model_file])
    model = load_predictor(model_file)  # no scikit-learn: ~1.5 s of a start
    digest = hashlib.sha256(model_file.read_bytes()).hexdigest()
    files = export_model(model, lang, model_sha256=digest)
    with out.publish() as stage:
        for name, text in files.items():
            stage.file(name).write_text(text, encoding="utf-8")
    paths = [out_dir / name for name in names]
    physics = physics_column(model)
    prior = getattr(model, "coefficient_prior_", None)
    if as_json:
        temp_range = export_spec(model).temp_range_c
        print_json(
            {
                "files": [str(p) for p in paths],
                "encoding": model.encoding,
                "kernel": model.lssvr.kernel,
                "target": model.target,
                "physics_column": physics,
                # the fleet-prior base's k_z prior baked into the code: [mean, 1-sigma] deg/h/degC, else null
                "coefficient_prior_deg_h_per_c": None if prior is None else list(prior),
                # the drift law's temperature range (the training runs' temperatures) [deg C], else null
                "law_temp_range_c": None if temp_range is None else list(temp_range),
            }
        )
    detail = f"{model.encoding}, {model.lssvr.kernel}" + ("" if physics is None else f", hybrid on {physics}")
    say_wrote(paths, quiet=quiet, as_json=as_json, detail=detail)


COMMANDS = (export_command,)
