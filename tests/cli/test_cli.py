"""The CLI as a user runs it: fit, predict, and clear errors for bad files."""

import csv
import io
import json

import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.runs.datasets import paper_csv_path


@pytest.fixture
def paper_csv(tmp_path):
    p = tmp_path / "paper.csv"
    p.write_bytes(paper_csv_path().read_bytes())
    return p


def test_fit_then_predict_csv_and_jsonl(tmp_path, paper_csv):
    runner = CliRunner()
    model = tmp_path / "model.json"
    r = runner.invoke(
        main,
        [
            "fit",
            str(paper_csv),
            "--out",
            str(model),
            "--split",
            "train",
            "--lat0-deg",
            "28.222",
            "--method",
            "grid",
        ],
    )
    assert r.exit_code == 0, r.output
    assert f"wrote {model} (fitted on 22 runs" in r.output and model.exists()
    r = runner.invoke(
        main, ["predict", str(paper_csv), "--model", str(model), "--split", "test", "--lat0-deg", "28.222"]
    )
    assert r.exit_code == 0, r.output
    rows = list(csv.DictReader(io.StringIO(r.stdout)))
    assert [row["run"] for row in rows] == [str(i) for i in range(23, 33)]
    for row in rows:
        assert float(row["error_deg_h"]) == pytest.approx(
            float(row["drift_deg_h"]) - float(row["drift_identified_deg_h"])
        )
    out = tmp_path / "pred.jsonl"
    r = runner.invoke(
        main, ["predict", str(paper_csv), "--model", str(model), "--lat0-deg", "28.222", "--json", "--out", str(out)]
    )
    assert r.exit_code == 0, r.output
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(lines) == 32 and {"run", "drift_identified_deg_h"} <= set(lines[0])
    assert r.stdout == f"wrote {out} (32 run(s))\n"


def test_fit_with_fixed_parameters_needs_both(tmp_path, paper_csv):
    r = CliRunner().invoke(
        main, ["fit", str(paper_csv), "--out", str(tmp_path / "m.json"), "--lat0-deg", "28.222", "--gamma", "10"]
    )
    assert r.exit_code != 0 and "give both --gamma and --sigma" in r.output


def test_bad_data_file_is_named(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("run,lat_deg,temp_min_c,temp_max_c,drift_deg_h\n1,28.2,1,x,0.001\n")
    r = CliRunner().invoke(main, ["fit", str(bad), "--out", str(tmp_path / "m.json"), "--lat0-deg", "28.222"])
    assert r.exit_code == 1
    assert "bad.csv, row 2, column temp_max_c: expected a temperature in deg C, got 'x'" in r.output
    assert not (tmp_path / "m.json").exists()


def test_bad_model_file_is_named(tmp_path, paper_csv):
    bad = tmp_path / "model.json"
    bad.write_text("{not json")
    r = CliRunner().invoke(main, ["predict", str(paper_csv), "--model", str(bad), "--lat0-deg", "28.222"])
    assert r.exit_code == 1 and "model.json: corrupted JSON" in r.output


def test_version():
    r = CliRunner().invoke(main, ["--version"])
    assert r.exit_code == 0 and "gyrodrift" in r.output


def test_missing_output_folder_fails_before_any_work(tmp_path, paper_csv):
    r = CliRunner().invoke(
        main, ["fit", str(paper_csv), "--out", str(tmp_path / "nodir" / "m.json"), "--lat0-deg", "28.222"]
    )
    assert r.exit_code == 1 and "the folder" in r.output and "nodir does not exist" in r.output


def test_fit_says_when_a_split_column_is_ignored(tmp_path, paper_csv):
    r = CliRunner().invoke(
        main,
        [
            "fit",
            str(paper_csv),
            "--out",
            str(tmp_path / "m.json"),
            "--lat0-deg",
            "28.222",
            "--gamma",
            "10",
            "--sigma",
            "1",
        ],
    )
    assert r.exit_code == 0 and "has a split column; training on all 32 rows" in r.output


def test_warnings_become_one_line_each_on_stderr_also_when_the_command_fails():
    import warnings

    import click

    from gyrodrift.cli.options import show_warnings
    from gyrodrift.learn.interval import IntervalOutlierWarning

    @click.command()
    @click.option("--fail", is_flag=True)
    def command(fail):
        with show_warnings():
            for _ in range(2):
                warnings.warn("interval: run r7 is wild", IntervalOutlierWarning, stacklevel=1)
            warnings.warn("gamma on its bound", UserWarning, stacklevel=1)
            if fail:
                raise click.ClickException("stopped")
        click.echo("done")

    for fail in (False, True):
        result = CliRunner().invoke(command, ["--fail"] if fail else [])
        lines = result.stderr.splitlines()
        assert lines[:2] == ["warning: interval: run r7 is wild", "warning: gamma on its bound"], result.stderr
        assert "Warning:" not in result.stderr and "warnings.warn" not in result.stderr
        assert (result.exit_code, result.stdout) == ((1, "") if fail else (0, "done\n"))
