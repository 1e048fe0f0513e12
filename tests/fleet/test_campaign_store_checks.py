"""A campaign store checks what it resumes and reads (issue 18, item 4): a damaged run file (truncated, not
Parquet, another run's row) is named in one line by ``--run-table`` and ``study`` and run again on resume (a
note on stderr); a file gyrodrift cannot have written is refused before any work; a campaign whose every run is
too short is refused before anything is simulated; a campaign whose every run failed exits 1."""

from __future__ import annotations

import os
import shutil
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.errors import InputError
from gyrodrift.fleet.campaign import run_campaign
from gyrodrift.fleet.spec import CampaignError, check_feasible, load_campaign, parse_campaign
from gyrodrift.fleet.store import CampaignStore, read_runs

COUNT = 3
FAST = """
[campaign]
name = "fast"
count = {count}
seed = 5

[options]
align_h = 1.0
features_h = 1
truth_h = 1.0
smoother = false

[base.run]
duration_h = 2.0
rate_hz = 1.0
"""
"""2 h runs at 1 Hz: the procedure needs 1 h alignment + 1 h navigation = 2 h."""


def _write(tmp_path: Path, name: str, extra: str = "", count: int = COUNT) -> Path:
    p = tmp_path / f"{name}.toml"
    p.write_text(FAST.format(count=count) + extra)
    return p


@pytest.fixture(scope="module")
def fast_store(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fast")
    src = _write(tmp, "fast")
    summary = run_campaign(load_campaign(src), tmp / "out", workers=1)
    assert (summary.done, summary.failed, summary.lost) == (COUNT, 0, 0)
    return tmp / "out", src


def _copy(fast_store, tmp_path: Path) -> tuple[Path, Path]:
    out, src = fast_store
    shutil.copytree(out, tmp_path / "out")
    return tmp_path / "out", src


def _one_line_error(args: list[str], fragment: str) -> None:
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1 and fragment in r.output, r.output


def _mtimes(out: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in (out / "runs").glob("run-*.parquet")}


def test_a_truncated_run_is_named_by_readers_and_run_again_on_resume(fast_store, tmp_path):
    out, src = _copy(fast_store, tmp_path)
    victim = CampaignStore(out).run_path(1)
    data = victim.read_bytes()
    victim.write_bytes(data[: len(data) // 2])  # a copy cut short (the footer is gone)
    problem, _ = CampaignStore(out).check_run(1)
    assert problem is not None and "not a readable Parquet file" in problem
    with pytest.raises(InputError, match="run-000001.parquet: damaged run file: not a readable Parquet file"):
        read_runs(out)
    fragment = f"{victim}: damaged run file: not a readable Parquet file"
    _one_line_error(["campaign", str(out), "--run-table", str(tmp_path / "runs.csv")], fragment)
    _one_line_error(["study", str(out), "--out", str(tmp_path / "study"), "--max-iter", "2"], fragment)
    assert not (tmp_path / "runs.csv").exists()
    before = _mtimes(out)
    r = CliRunner().invoke(main, ["campaign", str(src), "--out", str(out), "--workers", "1", "--quiet"])
    assert r.exit_code == 0, r.output
    assert f"campaign: {victim}: damaged (not a readable Parquet file" in r.stderr
    assert "run 1 is run again" in r.stderr
    after = _mtimes(out)
    assert sorted(after) == [f"run-{i:06d}.parquet" for i in range(COUNT)]
    assert {k: v for k, v in after.items() if k != victim.name} == {k: v for k, v in before.items() if k != victim.name}
    assert not [e for e in os.listdir(out / "runs") if not e.startswith("run-")]  # no temporaries
    runs = read_runs(out)
    assert list(runs["index"]) == list(range(COUNT)) and all(e is None for e in runs["error"])
    fresh = read_runs(fast_store[0])
    assert runs.numbers("drift_deg_h")[1] == pytest.approx(fresh.numbers("drift_deg_h")[1], rel=0, abs=1e-12)


def test_a_run_file_holding_another_run_is_damaged(fast_store, tmp_path):
    out, _ = _copy(fast_store, tmp_path)
    bare = tmp_path / "bare"  # a manifest without its runs/ folder
    bare.mkdir()
    for name in ("campaign.toml", "campaign.json"):
        shutil.copyfile(out / name, bare / name)
    _one_line_error(["campaign", str(bare), "--run-table", str(tmp_path / "t.csv")], f"{bare / 'runs'}: no such folder")
    store = CampaignStore(out)
    (out / "runs" / "notes.txt").write_text("a file of the user's: not read, not touched\n")
    assert len(read_runs(out)) == COUNT
    shutil.copyfile(store.run_path(0), store.run_path(2))  # a whole Parquet file, but of run 0
    good, damaged = store.verify()
    assert set(good) == {0, 1} and set(damaged) == {2}
    assert "holds run 'r000000' (index 0), not r000002" in damaged[2]
    with pytest.raises(InputError, match="run-000002.parquet: damaged run file: holds run 'r000000'"):
        read_runs(out)


def test_a_run_file_gyrodrift_did_not_write_is_refused_before_any_work(fast_store, tmp_path):
    out, src = _copy(fast_store, tmp_path)
    victim = CampaignStore(out).run_path(2)
    victim.write_text("my notes, not a run\n")
    before = _mtimes(out)
    r = CliRunner().invoke(main, ["campaign", str(src), "--out", str(out), "--workers", "1", "--quiet"])
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert f"{victim}: exists and is not a campaign run written by gyrodrift" in r.output
    assert victim.read_text() == "my notes, not a run\n" and _mtimes(out) == before
    # a damaged run file that links out of the folder is not written through
    outside = tmp_path / "outside.parquet"
    outside.write_bytes(b"")
    victim.unlink()
    victim.symlink_to(outside)
    r = CliRunner().invoke(main, ["campaign", str(src), "--out", str(out), "--workers", "1", "--quiet"])
    assert r.exit_code == 1 and f"{victim}: damaged (" in r.output and "a symbolic link" in r.output, r.output
    assert outside.read_bytes() == b"" and victim.is_symlink()


def test_an_impossible_campaign_is_refused_before_simulating(tmp_path):
    short = _write(tmp_path, "short", count=2).read_text().replace("duration_h = 2.0", "duration_h = 1.5")
    (tmp_path / "short.toml").write_text(short)
    r = CliRunner().invoke(main, ["campaign", str(tmp_path / "short.toml"), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1 and "Traceback" not in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert "short.toml: [base.run] duration_h: every run lasts at most 1.5 h, shorter than the 2 h" in r.output
    assert "[options] align_h = 1 + the longer of features_h = 1 and truth_h = 1" in r.output
    assert not (tmp_path / "o").exists()  # nothing made, nothing simulated

    def campaign(extra: str, options: str = "align_h = 1.0\nfeatures_h = 1\ntruth_h = 1.0\n"):
        text = FAST.format(count=2).replace("align_h = 1.0\nfeatures_h = 1\ntruth_h = 1.0\n", options) + extra
        return parse_campaign(tomllib.loads(text), source="c.toml")

    # the default time line (4 h + 72 h) on 2 h runs: the keys say "(default)"
    with pytest.raises(CampaignError, match=r"\[options\] align_h = 4 \(default\) .* truth_h = 72 \(default\)"):
        check_feasible(campaign("", options=""))
    # a varied duration: refused only when its longest draw is too short
    with pytest.raises(CampaignError, match=r'c.toml: \[vary."run.duration_h"\]: every run lasts at most 1.9 h'):
        check_feasible(campaign('[vary."run.duration_h"]\ndist = "uniform"\nlow = 1.5\nhigh = 1.9\n'))
    with pytest.raises(CampaignError, match=r"every run lasts at most 1.8 h"):
        check_feasible(campaign('[vary."run.duration_h"]\ndist = "choice"\nvalues = [1.5, 1.8]\n'))
    check_feasible(campaign('[vary."run.duration_h"]\ndist = "choice"\nvalues = [1.5, 2.0]\n'))  # some fail
    check_feasible(campaign('[vary."run.duration_h"]\ndist = "normal"\nmean = 1.5\nstd = 0.1\n'))  # unbounded
    check_feasible(campaign(""))  # exactly the 2 h needed
    # a moving base: the vehicle must stand still over the whole time line (else every drift is silently wrong)
    drive = '[base.trajectory]\nstatic_h = 1.5\nsegments = [{ kind = "straight", duration_s = 60 }]\n'
    with pytest.raises(
        CampaignError, match=r"c.toml: \[base.trajectory\] static_h: the vehicle drives off at 1.5 h, befo"
    ):
        check_feasible(campaign(drive))
    check_feasible(campaign(drive.replace("static_h = 1.5", "static_h = 2.0")))


def test_every_run_failed_exits_1_and_some_failed_is_said(tmp_path):
    # a normal duration has no bound, so the campaign is not refused up front, but every draw is about 1.5 h
    src = _write(tmp_path, "fail", '[vary."run.duration_h"]\ndist = "normal"\nmean = 1.5\nstd = 0.01\n', count=2)
    out = tmp_path / "o"
    args = ["campaign", str(src), "--out", str(out), "--workers", "1", "--quiet"]
    _one_line_error(args, f"{out}: every run failed (2 of 2 with an error); first error: r000000: LogError:")
    assert len(read_runs(out)) == 2  # the failed runs are committed with their errors
    _one_line_error(args, f"{out}: every run failed (2 of 2 with an error)")  # a rerun still says so
    table = tmp_path / "runs.csv"
    _one_line_error(["campaign", str(out), "--run-table", str(table)], "every one of its 2 committed run(s) failed")
    assert not table.exists()
    # some runs fail: exit 0, one line on stderr with how many and the first error
    mixed = _write(tmp_path, "mixed", '[vary."run.duration_h"]\ndist = "choice"\nvalues = [1.5, 2.0]\n', count=4)
    r = CliRunner().invoke(main, ["campaign", str(mixed), "--out", str(tmp_path / "m"), "--workers", "1", "--quiet"])
    assert r.exit_code == 0, r.output
    runs = read_runs(tmp_path / "m", curves=False)
    failed = [str(run) for run, e in zip(runs["run"], runs["error"], strict=True) if e is not None]
    assert 0 < len(failed) < 4, runs["error"]
    assert f"campaign: {len(failed)} of 4 run(s) failed now; first error: {failed[0]}: LogError:" in r.stderr
