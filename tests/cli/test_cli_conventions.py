"""The CLI's shared conventions (docs/cli.md), checked on every command: help texts with units, defaults and an
example; one name per quantity; --json, --quiet and site options where the conventions put them; simulate's
[run] overrides."""

from __future__ import annotations

import re
import shlex
import tomllib
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.cli.types import FiniteFloat

TOUR = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "tour.toml"
COMMANDS = sorted(main.commands)
READS_A_LOG = {"navigate", "features", "truth", "evaluate", "identify", "allan"}
TAKES_A_MODEL = {"predict", "identify", "evaluate", "export"}
UNIT = re.compile(r"\[[^\]]+\]")


def _options(name):
    return [p for p in main.commands[name].params if isinstance(p, click.Option) and not p.hidden]


@pytest.mark.parametrize("name", COMMANDS)
def test_every_option_is_described_with_its_unit_and_default(name):
    for opt in _options(name):
        flag = opt.opts[0]
        assert opt.help and len(opt.help) > 15, f"{name} {flag}: no help text"
        if isinstance(opt.type, FiniteFloat) or opt.type in (click.FLOAT,):
            assert UNIT.search(opt.help), f"{name} {flag}: a number without a [unit] in its help: {opt.help!r}"
        if not opt.required and not opt.is_flag and not opt.show_default:
            assert "default" in opt.help.lower(), f"{name} {flag}: optional, but its help does not say the default"
        if opt.is_flag:
            assert "default" in opt.help.lower(), f"{name} {flag}: a flag whose help does not say the default"


@pytest.mark.parametrize("name", COMMANDS)
def test_every_help_ends_with_an_example_that_parses(name):
    command = main.commands[name]
    r = CliRunner().invoke(main, [name, "--help"])
    assert r.exit_code == 0, r.output
    assert re.match(f"Examples?: gyrodrift {name} ", command.epilog), command.epilog
    tail = r.output[r.output.rindex("Example") :]  # the epilog closes the help (click wraps it)
    assert " ".join(tail.split()) == " ".join(command.epilog.split())
    for example in command.epilog.split(":", 1)[1].split(" ; "):
        words = shlex.split(example)
        assert words[:2] == ["gyrodrift", name]
        flags = {o for p in command.params for o in getattr(p, "opts", [])}
        assert {w.split("=")[0] for w in words if w.startswith("--")} <= flags, example
        with click.Context(command, info_name=name, resilient_parsing=True) as ctx:
            command.parse_args(ctx, words[2:])  # the example's words parse (no missing value, no extra argument)


def test_the_group_help_ends_with_an_example():
    r = CliRunner().invoke(main, ["--help"])
    assert r.exit_code == 0 and "Example: gyrodrift simulate" in r.output


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_has_json_and_quiet(name):
    flags = {o for p in _options(name) for o in p.opts}
    assert {"--json", "--quiet"} <= flags, name


def test_one_name_per_quantity():
    for name in COMMANDS:
        flags = {o for p in _options(name) for o in p.opts}
        assert ({"--lat0-deg", "--lon0-deg", "--height-m"} <= flags) == (name in READS_A_LOG) or name in {
            "fit",
            "predict",
        }, name
        assert ("--model" in flags) == (name in TAKES_A_MODEL), name
        assert "--compensate-drift-deg-h" not in flags
        args = [p for p in main.commands[name].params if isinstance(p, click.Argument)]
        assert not any("model" in (a.name or "") for a in args), f"{name}: the model is --model FILE, not positional"
    assert "--drift-deg-h" in {o for p in _options("navigate") for o in p.opts}


def test_deprecated_drift_option_still_works_and_says_so(tmp_path):
    out = tmp_path / "sim"
    r = CliRunner().invoke(main, ["simulate", str(TOUR), "--duration-h", "0.05", "--out", str(out), "--quiet"])
    assert r.exit_code == 0, r.output
    args = ["navigate", str(out / "imu.parquet"), "--out", str(out), "--quiet"]
    r = CliRunner().invoke(main, [*args, "--compensate-drift-deg-h", "0.003"])
    assert r.exit_code == 0, r.output
    assert "--compensate-drift-deg-h is deprecated; use --drift-deg-h" in r.stderr
    r = CliRunner().invoke(main, [*args, "--compensate-drift-deg-h", "0.003", "--drift-deg-h", "0.003"])
    assert r.exit_code == 1 and "give --drift-deg-h only" in r.stderr


def test_simulate_overrides_are_validated_and_recorded(tmp_path):
    out = tmp_path / "sim"
    r = CliRunner().invoke(
        main,
        ["simulate", str(TOUR), "--duration-h", "0.1", "--seed", "7", "--rate-hz", "20", "--out", str(out), "--json"],
    )
    assert r.exit_code == 0, r.output
    resolved = tomllib.loads((out / "scenario.resolved.toml").read_text())["run"]
    assert resolved == {"duration_h": 0.1, "rate_hz": 20.0, "seed": 7}
    assert '"n_samples": 7200' in r.stdout and r.stderr.startswith(f"wrote {out / 'imu.parquet'}")
    r = CliRunner().invoke(main, ["simulate", str(TOUR), "--duration-h", "1e9", "--out", str(tmp_path / "x")])
    assert r.exit_code == 1
    assert "with --duration-h 1e+09: [run] duration_h" in r.stderr and "Traceback" not in r.output
    r = CliRunner().invoke(main, ["simulate", str(TOUR), "--seed", "-1", "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and "--seed" in r.stderr
    assert not (tmp_path / "x").exists()


def test_quiet_writes_nothing_and_json_keeps_stdout_parseable(tmp_path):
    import json

    out = tmp_path / "sim"
    r = CliRunner().invoke(main, ["simulate", str(TOUR), "--duration-h", "0.05", "--out", str(out), "--quiet"])
    assert r.exit_code == 0 and r.stdout == "" and r.stderr == ""
    r = CliRunner().invoke(main, ["navigate", str(out / "imu.parquet"), "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["initial_source"] == "truth"
    assert r.stderr.startswith(f"wrote {out / 'nav.parquet'}, {out / 'summary.json'} (")


def test_the_paper_table_as_a_cli_run_table(tmp_path):
    """`load_paper().runs.to_csv` (the README's way) gives a table `fit --split train` and `predict` read as is."""
    import gyrodrift as gd
    from gyrodrift.runs.table import read_runs_csv

    paper = gd.load_paper().runs
    path = tmp_path / "paper.csv"
    paper.to_csv(path)
    back = read_runs_csv(path, require_truth=True)  # lat0_deg is a column now: no --lat0-deg needed
    for name in ("run", "split", "lat_deg", "lat0_deg", "temp_min_c", "temp_max_c", "drift_deg_h"):
        assert list(getattr(back, name)) == list(getattr(paper, name)), name
    model = tmp_path / "model.json"
    r = CliRunner().invoke(main, ["fit", str(path), "--split", "train", "--method", "grid", "--out", str(model)])
    assert r.exit_code == 0 and "fitted on 22 runs" in r.stdout, r.output
    r = CliRunner().invoke(main, ["predict", str(path), "--split", "test", "--model", str(model)])
    assert r.exit_code == 0 and len(r.stdout.splitlines()) == 11, r.output
    (tmp_path / "notes.csv").write_text("my notes\n")
    with pytest.raises(OSError, match="notes.csv"):
        paper.to_csv(tmp_path / "notes.csv")  # replaces only a run table
    assert (tmp_path / "notes.csv").read_text() == "my notes\n"
