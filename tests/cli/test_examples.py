"""Issue 22: the example scenarios and campaigns ship in the package and are reachable by name from any folder."""

import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

import gyrodrift
from gyrodrift.cli import main
from gyrodrift.files.examples import EXAMPLE_KINDS, example_names, example_path

ROOT = Path(__file__).resolve().parents[2]


def test_every_shipped_example_loads_and_is_in_the_wheel():
    from gyrodrift.fleet.spec import load_campaign
    from gyrodrift.ins.scenario import load_scenario

    assert "tour" in example_names("scenario") and "tiny" in example_names("campaign")
    for name in example_names("scenario"):
        assert load_scenario(example_path("scenario", name)).n_samples > 0
    for name in example_names("campaign"):
        assert load_campaign(example_path("campaign", name)).name
    include = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["maturin"]["include"]
    globs = [i["path"] for i in include if i.get("format") == "wheel"]
    package = Path(gyrodrift.__file__).parent  # the clone's python/gyrodrift, or an installed copy of it
    for kind, folder in EXAMPLE_KINDS.items():
        for name in example_names(kind):
            in_package = example_path(kind, name).relative_to(package)
            rel = Path("python/gyrodrift") / in_package  # where the clone holds it
            assert (ROOT / rel).is_file() and any(rel.match(g) for g in globs), f"{rel} is not in the wheel"
            # one copy: the clone's examples/<folder> is a link to the package's
            assert (ROOT / "examples" / folder).resolve() == (ROOT / rel).parent.resolve()


def test_simulate_and_campaign_by_name_from_a_scratch_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert not (tmp_path / "examples").exists()
    r = CliRunner().invoke(main, ["simulate", "--example", "tour", "--duration-h", "0.05", "--out", "sim"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "sim" / "imu.parquet").is_file() and "1800 samples, 0.05 h at 10 Hz" in r.output
    r = CliRunner().invoke(main, ["campaign", "--example", "tiny", "--limit", "1", "--workers", "1", "--out", "fleet"])
    assert r.exit_code == 0, r.output
    assert len(list((tmp_path / "fleet" / "runs").glob("run-*.parquet"))) == 1


@pytest.mark.parametrize(
    "args, message",
    [
        (["simulate", "--out", "x"], "give SCENARIO.toml or --example NAME (a scenario shipped with gyrodrift)"),
        (["simulate", "s.toml", "--example", "tour", "--out", "x"], "give SCENARIO.toml or --example NAME"),
        (["simulate", "--example", "nope", "--out", "x"], "--example nope: no such scenario; expected one of"),
        (["campaign", "--example", "tour", "--out", "x"], "--example tour: no such campaign; expected one of"),
    ],
)
def test_example_misuse_is_one_line(tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 1 and message in r.output and len(r.output.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_the_main_help_example_uses_a_shipped_example():
    r = CliRunner().invoke(main, ["--help"])
    assert "gyrodrift simulate --example tour --out sim" in " ".join(r.output.split())
