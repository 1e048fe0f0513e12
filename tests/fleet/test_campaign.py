"""Campaigns: file validation, seeded runs regenerated alone, the store (atomic, resumable, refuses another
campaign), failed runs, the linear error curves against a navigation, the run table, kill -9 of the client and
of a worker, a dask LocalCluster giving the same rows, an unreachable scheduler."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from pool_processes import pool_workers
from test_campaign_store_checks import FAST

from gyrodrift.cli import main
from gyrodrift.errors import InputError, OutputError
from gyrodrift.fleet.campaign import run_campaign
from gyrodrift.fleet.run_table import run_table_rows
from gyrodrift.fleet.science import trial_drift_deg_h
from gyrodrift.fleet.spec import CampaignError, load_campaign, parse_campaign
from gyrodrift.fleet.store import CURVE_COLUMNS, CampaignStore, read_runs
from gyrodrift.runs.columns import TRUTH_LAW_COLUMNS

TINY = Path(__file__).resolve().parents[2] / "examples" / "campaigns" / "tiny.toml"
VOLATILE = {"worker"} | {f"{k}_{s}_s" for k in ("t", "cpu") for s in ("align", "passes", "smoother", "twin", "total")}


def tiny_text(count: int, extra: str = "") -> str:
    text = TINY.read_text()
    assert "count = 16" in text
    return text.replace("count = 16", f"count = {count}") + extra


def write_campaign(tmp_path: Path, name: str, count: int, extra: str = "") -> Path:
    p = tmp_path / f"{name}.toml"
    p.write_text(tiny_text(count, extra))
    return p


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("campaign")
    src = write_campaign(tmp, "fleet", 12)
    summary = run_campaign(load_campaign(src), tmp / "out", workers=2)
    assert (summary.done, summary.failed, summary.lost) == (12, 0, 0)
    return tmp / "out", src


# --- the campaign file -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "vary, fragment",
    [
        (
            '[vary."site.latitude"]\ndist = "uniform"\nlow = 1\nhigh = 2\n',
            '[vary."site.latitude"]: expected a scenario key',
        ),
        ('[vary."gyro.bias_deg_h"]\ndist = "uniform"\nlow = 1\nhigh = 2\n', "a vector key takes an index"),
        ('[vary."gyro.bias_deg_h[3]"]\ndist = "uniform"\nlow = 1\nhigh = 2\n', "index out of range"),
        ('[vary."site.lon_deg"]\ndist = "gauss"\n', '[vary."site.lon_deg"] dist: expected one of'),
        ('[vary."site.lon_deg"]\ndist = "uniform"\nlow = 3\nhigh = 2\n', " high: must be >= low"),
        ('[vary."site.lon_deg"]\ndist = "log_uniform"\nlow = 0\nhigh = 2\n', " low: must be > 0"),
        ('[vary."site.lon_deg"]\ndist = "normal"\nmean = 1\n', "]: missing std"),
        ('[vary."run.seed"]\ndist = "uniform"\nlow = 1\nhigh = 2\n', "derives from [campaign] seed"),
        ('[vary."rotation.scheme"]\ndist = "choice"\nvalues = ["spin"]\n', "[rotation] scheme"),
    ],
)
def test_bad_vary_names_file_and_key(tmp_path, vary, fragment):
    p = tmp_path / "bad.toml"
    p.write_text(tiny_text(3) + "\n" + vary)
    with pytest.raises(CampaignError) as err:
        load_campaign(p)
    assert str(err.value).startswith(str(p)) and fragment in str(err.value)


def test_bad_head_grade_and_base(tmp_path):
    for text, fragment in [
        ("[campaign]\ncount = 0\n", "[campaign] count: must be >= 1, got 0"),
        ("[campaign]\ncount = 2\nseed = 1.5\n", "[campaign] seed"),
        ("[campaign]\ncount = 2\n[base.site]\nlat_deg = 95\n", "[base]: [site] lat_deg"),
        ("[campaign]\ncount = 2\n[grades.a]\nnoise = 1\n", "[grades.a] noise: unknown key (expected one of: arw"),
        ("[campaign]\ncount = 2\n[grades.a]\narw_deg_rth = 0.001\n", "no [vary.grade]"),
        ('[campaign]\ncount = 2\n[vary.grade]\ndist = "choice"\nvalues = ["x"]\n', "unknown grade 'x'"),
        ("[campaign]\ncount = 2\n[imu]\n", "[imu]: unknown section"),
        ("[campaign]\ncount = 2\n[options]\nfeatures_h = 1.5\n", "[options] features_h: expected whole hours"),
        ('grades = "x"\n[campaign]\ncount = 2\n', "[grades] must be a table, got string"),
        ("vary = 3\n[campaign]\ncount = 2\n", "[vary] must be a table, got number"),
        ("options = []\n[campaign]\ncount = 2\n", "[options] must be a table, got array"),
        (
            '[campaign]\ncount = 2\n[grades.a]\narw_deg_rth = 1e-3\n[vary.grade]\ndist = "choice"\nvalues = [[1]]\n',
            '[vary."grade"] values: unknown grade [1]',
        ),
    ]:
        p = tmp_path / "bad.toml"
        p.write_text(text)
        with pytest.raises(InputError) as err:
            load_campaign(p)
        assert str(p) in str(err.value) and fragment in str(err.value), str(err.value)


def test_runs_are_seeded_by_index_and_regenerate_alone(tmp_path):
    a = load_campaign(write_campaign(tmp_path, "a", 16))
    b = load_campaign(write_campaign(tmp_path, "b", 5))  # another count: the first runs are the same
    assert a.spec(3).scenario == b.spec(3).scenario and a.spec(3).params == b.spec(3).params
    child = np.random.SeedSequence(a.seed).spawn(16)[3].spawn(2)[1]
    assert a.spec(3).seed == int(child.generate_state(1, np.uint64)[0] >> np.uint64(1))
    seeds = {a.spec(i).seed for i in range(16)}
    assert len(seeds) == 16
    lats = np.array([a.spec(i).params["site.lat_deg"] for i in range(16)])
    assert lats.min() >= 20 and lats.max() <= 60 and np.ptp(lats) > 10
    twin = a.scenario(3, noise=False)
    assert twin.gyro.arw_deg_rth == 0 and twin.accel.vrw_ug_rthz == 0 and twin.run.seed == a.scenario(3).run.seed
    assert a.digest() != parse_campaign({**_toml(tiny_text(16)), "campaign": {"count": 16, "seed": 8}}).digest()


def _toml(text: str) -> dict:
    import tomllib

    return tomllib.loads(text)


# --- the store ---------------------------------------------------------------------------------------------


def test_store_rows_resume_and_refusals(store, tmp_path):
    out, src = store
    runs = read_runs(out)
    assert len(runs) == 12 and list(runs["index"]) == list(range(12))
    assert all(e is None for e in runs["error"])
    assert sorted(os.listdir(out / "runs")) == [f"run-{i:06d}.parquet" for i in range(12)]
    eff, truth = runs.numbers("drift_effective_deg_h"), runs.numbers("drift_deg_h")
    const = runs.numbers("param_gyro_bias_deg_h_2")
    assert np.all(np.isfinite(eff)) and np.all(np.abs(eff - truth) < 1e-3)
    # the effective drift is the constant plus the temperature law's mean over the truth span: near the constant
    assert np.all(np.abs(eff - const) < 0.003)
    # the same command again: nothing to do, nothing rewritten
    before = {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    again = run_campaign(load_campaign(src), out, workers=1)
    assert (again.skipped, again.done) == (12, 0)
    assert before == {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    other = write_campaign(tmp_path, "other", 12, '\n[vary."site.lon_deg"]\ndist = "uniform"\nlow = 0\nhigh = 10\n')
    with pytest.raises(OutputError, match="holds campaign 'tiny'"):
        run_campaign(load_campaign(other), out, workers=1)
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(OutputError, match="not empty and holds no campaign"):
        run_campaign(load_campaign(src), foreign, workers=1)


def test_run_table_is_read_by_fit(store, tmp_path):
    from gyrodrift.learn.drift_model import fit_drift_model
    from gyrodrift.runs.table import read_runs_csv, write_run_table

    out, _ = store
    runs = read_runs(out, curves=False)
    rows, columns = run_table_rows(runs)
    write_run_table(tmp_path / "runs.csv", rows, columns)
    table = read_runs_csv(tmp_path / "runs.csv", require_truth=True)
    assert len(rows) == len(table) == 12
    np.testing.assert_array_equal(table.drift_deg_h, runs.numbers("drift_deg_h"))
    model = fit_drift_model(table, encoding="physics", gamma=10.0, sigma=1.0)
    assert np.all(np.isfinite(model.predict(table)))


def test_export_log_and_linear_curves_match_navigation(store, tmp_path):
    """A run regenerated alone gives the stored truth to the bit; the linear curves predict a navigated
    compensation."""
    from gyrodrift.logs import open_log
    from gyrodrift.procedure import align_log, find_true_drift, navigate_after_alignment
    from gyrodrift.procedure.timeline import Timeline

    out, _ = store
    runs = read_runs(out)
    k = 5
    campaign = CampaignStore(out).campaign()
    res = CliRunner().invoke(main, ["campaign", str(out), "--export-log", str(k), "--out", str(tmp_path / "log")])
    assert res.exit_code == 0, res.output
    log = open_log(tmp_path / "log" / "imu.parquet")
    tl = Timeline(align_h=1.0, features_h=12.0, truth_h=13.0)
    # the campaign's truth: one read, linearised between 0 and the scenario's nominal drift (no verification read)
    truth = find_true_drift(log, timeline=tl, verify=False, trial_deg_h=trial_drift_deg_h(campaign.scenario(k), tl))
    assert truth.drift_deg_h == runs.numbers("drift_deg_h")[k]
    assert log.n_samples == campaign.scenario(k).n_samples
    d = runs.numbers("drift_effective_deg_h")[k] + 0.0007  # any estimate, not one of the secant's ends
    nav = navigate_after_alignment(log, align_log(log, timeline=tl), [d], 13.0).curves[0]
    navigated = np.hypot(nav.north_m, nav.east_m) / 1852.0
    predicted = runs.select([k]).errors_nmi([d])[0]
    assert navigated.shape == predicted.shape
    assert np.max(np.abs(navigated - predicted)) < 2e-3 * max(1.0, navigated.max())


def test_failed_runs_are_recorded_and_do_not_stop(tmp_path):
    # runs shorter than the 2 h the procedure needs fail (the log is too short); the others go on
    src = tmp_path / "short.toml"
    src.write_text(FAST.format(count=4) + '\n[vary."run.duration_h"]\ndist = "choice"\nvalues = [1.5, 2.0]\n')
    campaign = load_campaign(src)
    summary = run_campaign(campaign, tmp_path / "out", workers=1)
    runs = read_runs(tmp_path / "out")
    short = runs.numbers("param_run_duration_h") < 1.9
    assert 0 < short.sum() < 4 and summary.done == 4 and summary.failed == short.sum()
    for err, s in zip(runs["error"], short, strict=True):
        assert (err is not None) == bool(s)
        if s:
            assert "LogError" in err and "h" in err


def test_dask_local_cluster_gives_identical_rows(store, tmp_path):
    pytest.importorskip("dask.distributed")
    out, src = store
    campaign = load_campaign(src)
    # one worker process (the rows cross a process boundary and the scheduler; each worker costs an interpreter)
    run_campaign(campaign, tmp_path / "dask", dask_workers=1, limit=2)
    a, b = read_runs(out), read_runs(tmp_path / "dask")
    assert len(b) == 2
    for name, col in b.columns.items():
        if name in VOLATILE:
            continue
        x = a.columns[name][:2]
        if col.dtype.kind == "f":
            np.testing.assert_array_equal(col, x, err_msg=name)
        else:
            assert list(col) == list(x), name
    for name, c in b.curves.items():
        np.testing.assert_array_equal(c, a.curves[name][:2], err_msg=name)


def test_unreachable_scheduler_is_a_clear_error_within_seconds(tmp_path):
    pytest.importorskip("dask.distributed")
    t = time.perf_counter()
    res = CliRunner().invoke(
        main,
        [
            "campaign",
            str(write_campaign(tmp_path, "c", 2)),
            "--out",
            str(tmp_path / "o"),
            "--scheduler",
            "tcp://127.0.0.1:9",
            "--connect-timeout-s",
            "1",
            "--quiet",
        ],
    )
    assert res.exit_code == 1 and "--scheduler tcp://127.0.0.1:9: no dask scheduler answered" in res.output
    assert time.perf_counter() - t < 15


def _wait_for_runs(folder: Path, n: int, proc, timeout: float = 240.0) -> None:
    t = time.monotonic()
    while time.monotonic() - t < timeout:
        if (folder / "runs").is_dir() and len(list((folder / "runs").glob("run-*.parquet"))) >= n:
            return
        if proc.poll() is not None:
            raise AssertionError(f"the campaign ended early: {proc.stderr.read()}")
        time.sleep(0.1)
    raise AssertionError("no runs committed in time")


def _check_complete(folder: Path, count: int) -> None:
    runs = read_runs(folder)
    assert list(runs["index"]) == list(range(count))
    assert all(e is None for e in runs["error"])
    assert not [e for e in os.listdir(folder / "runs") if not e.startswith("run-")]  # no temporaries left


@pytest.mark.parametrize("victim", ["client", "worker"])
def test_kill_9_then_rerun_completes_without_duplicates(tmp_path, victim):
    """Six 2 h runs at 4 Hz (test_campaign_store_checks's campaign, under a second each): killed after two are
    committed, four are still to do, so the kill meets runs in progress."""
    psutil = pytest.importorskip("psutil")
    src = tmp_path / "k.toml"
    src.write_text(FAST.format(count=6).replace("rate_hz = 1.0", "rate_hz = 4.0"))
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-c",
        "from gyrodrift.cli import main; main()",
        "campaign",
        str(src),
        "--out",
        str(out),
        "--quiet",
        "--workers",
    ]
    proc = subprocess.Popen([*cmd, "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_runs(out, 2, proc)
        if victim == "client":
            workers = pool_workers(psutil, proc.pid)
            assert workers
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(30)
            _gone, alive = psutil.wait_procs(workers, timeout=20)  # orphaned workers notice and exit
            assert not alive
            done = len(list((out / "runs").glob("run-*.parquet")))
            assert 2 <= done < 6  # killed mid-campaign: the rerun has runs to do
            # the same command again, in this process on one worker: the rerun's point is the store the kill left
            # (an interpreter of its own cost ~1 s more)
            rerun = CliRunner().invoke(main, [*cmd[3:], "1"])
            assert rerun.exit_code == 0, rerun.output
        else:
            kids = pool_workers(psutil, proc.pid)
            assert kids
            kids[0].kill()
            assert proc.wait(120) == 0, proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    _check_complete(out, 6)


def test_cli_campaign_and_study(store, tmp_path):
    import json

    out, src = store
    res = CliRunner().invoke(main, ["campaign", str(src), "--out", str(out), "--workers", "1", "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["already_done"] == 12
    res = CliRunner().invoke(main, ["campaign", str(out)])
    assert res.exit_code == 1 and "give --run-table FILE or --export-log N" in res.output
    res = CliRunner().invoke(
        main, ["study", str(out), "--out", str(tmp_path / "study"), "--test-fraction", "0.17", "--max-iter", "8"]
    )
    assert res.exit_code == 0, res.output
    from gyrodrift.fleet.study_report import STUDY_FILES

    assert res.stdout.splitlines()[-1] == "wrote " + ", ".join(str(tmp_path / "study" / n) for n in STUDY_FILES)
    doc = json.loads((tmp_path / "study" / "study.json").read_text())
    assert doc["n_test"] == 2 and doc["n_train"] == 10
    for name in ("hybrid default", "12 h physics inversion", "GP regression", "alignment z estimate"):
        m = doc["methods"][name]["metrics"]
        assert 0 < m["rms_eff"] <= m["max_eff"] and 0 <= m["under_1nmi_final"] <= 1
    html = (tmp_path / "study" / "report.html").read_text()
    assert html.index("Summary") < html.index("Methods on the held-out runs") and "data:image/png;base64" in html
    assert math.isfinite(doc["methods"]["12 h curve fit"]["metrics"]["coverage_eff"])
    # the fleet-prior smoother: the training runs' k_z pooled, each held-out run re-weighted (checked by hand here)
    from gyrodrift.fleet.study import FLEET_ROW, split_runs
    from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior, pooled_coefficient_prior

    fleet = doc["methods"][FLEET_ROW]
    runs = read_runs(out, curves=False)
    train, test = split_runs(len(runs), 0.17, 0)
    col = {c: runs.numbers(c) for c in runs.columns if c.startswith(("smoother_", "drift_smoother"))}
    mean, std = pooled_coefficient_prior(
        col["smoother_coeff_deg_h_per_c"][train], col["smoother_coeff_std_deg_h_per_c"][train]
    )
    d, sd = drift_with_coefficient_prior(
        col["drift_smoother_deg_h"][test],
        col["drift_smoother_std_deg_h"][test],
        col["smoother_coeff_deg_h_per_c"][test],
        col["smoother_coeff_std_deg_h_per_c"][test],
        col["smoother_end_coeff_cov"][test],
        col["smoother_coeff_prior_std_deg_h_per_c"][test],
        mean,
        std,
    )
    np.testing.assert_allclose(fleet["pred_deg_h"], d, rtol=0, atol=1e-15)
    assert not np.allclose(d, col["drift_smoother_deg_h"][test])  # the prior moved them
    m = fleet["metrics"]
    assert 0 <= m["coverage_eff"] <= 1 and m["own_sigma_rms"] == pytest.approx(np.sqrt(np.mean(sd**2)))
    assert "16 h smoother with the training fleet's k_z prior" in res.output
    assert len(doc["train_size"]["rms_eff"][FLEET_ROW]) == len(doc["train_size"]["sizes"])
    from gyrodrift.choices import default_encoding

    note = doc["methods"]["hybrid default"]["note"]
    assert note.startswith(f"inputs {default_encoding('residual')}, physics base drift_smoother_fleet_deg_h"), note


def test_runs_carry_the_smoothers_thermal_columns(store, tmp_path):
    from gyrodrift.fleet.science import noise_model
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.procedure.smoother import smooth_log
    from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS
    from gyrodrift.runs.table import read_runs_csv, write_run_table

    out, src = store
    runs = read_runs(out, curves=False)
    for c in SMOOTHER_THERMAL_COLUMNS:  # the tiny fleet warms up: every run under the thermal model
        assert np.all(np.isfinite(runs.numbers(c))), c
    campaign = load_campaign(src)
    scn = campaign.scenario(3)
    est = smooth_log(scenario_log(scn), timeline=campaign.timeline, noise=noise_model(scn))
    assert est.model == "thermal"
    assert runs.numbers("drift_smoother_deg_h")[3] == est.navigation_drift_deg_h
    for c, v in est.thermal_columns().items():
        assert runs.numbers(c)[3] == v, c
    write_run_table(tmp_path / "runs.csv", *run_table_rows(runs))
    table = read_runs_csv(tmp_path / "runs.csv")
    for c in SMOOTHER_THERMAL_COLUMNS:
        np.testing.assert_array_equal(table.column(c), runs.numbers(c))


def test_a_store_written_before_the_thermal_columns_reads_resumes_and_studies(store, tmp_path, monkeypatch):
    """Run files without the four thermal columns (the previous schema): read as NaN, whichever file comes
    first; a resumed campaign adds runs with them; the study says its fleet row is unavailable. The study's fits'
    interval warnings become notes, any other warning reaches the caller."""
    import shutil
    import warnings

    import pyarrow.parquet as pq

    from gyrodrift.fleet import study as study_module
    from gyrodrift.fleet.study import FLEET_ROW, run_study
    from gyrodrift.learn.interval import IntervalOutlierWarning
    from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS

    out, src = store
    old = tmp_path / "old"
    shutil.copytree(out, old)
    for path in (old / "runs").iterdir():
        t = pq.read_table(path)
        pq.write_table(t.drop_columns(list(SMOOTHER_THERMAL_COLUMNS)), path)
    runs = read_runs(old)
    assert len(runs) == 12
    for c in SMOOTHER_THERMAL_COLUMNS:
        assert np.all(np.isnan(runs.numbers(c))), c
    assert np.all(np.isfinite(runs.numbers("drift_smoother_deg_h")))
    fit_learned = study_module._fit_learned

    def warning_fit(name, train, **kwargs):
        warnings.warn(f"interval: {name} is wild", IntervalOutlierWarning, stacklevel=1)
        warnings.warn(f"something else from {name}", RuntimeWarning, stacklevel=1)
        return fit_learned(name, train, **kwargs)

    monkeypatch.setattr(study_module, "_fit_learned", warning_fit)
    with pytest.warns(RuntimeWarning) as raised:
        study = run_study(runs, test_fraction=0.17, seed=0, max_iter=3, train_sizes=[10])
    # PSO is fitted only for the held-out runs (not for the training-size curves, whose fits warn what they warn)
    assert "something else from PSO-LSSVM (LOO)" in {str(w.message) for w in raised}
    assert "a fit warned: interval: linear model is wild" in study.notes, study.notes
    assert FLEET_ROW not in study.methods and "16 h smoother" in study.methods
    assert any(f"the '{FLEET_ROW}' row is unavailable" in n for n in study.notes), study.notes
    # resume: the last run again with today's code (the first file read is an old one); the old files stay as
    # they were, the table mixes both
    (old / "runs" / "run-000011.parquet").unlink()
    before = {p.name: p.read_bytes() for p in (old / "runs").iterdir()}
    summary = run_campaign(load_campaign(src), old, workers=1)
    assert (summary.skipped, summary.done, summary.failed) == (11, 1, 0)
    assert before == {p.name: p.read_bytes() for p in (old / "runs").iterdir() if p.name in before}
    mixed = read_runs(old, curves=False)
    fresh = read_runs(out, curves=False)
    for c in SMOOTHER_THERMAL_COLUMNS:
        v = mixed.numbers(c)
        assert v[11] == fresh.numbers(c)[11] and np.all(np.isnan(v[:11])), c


def test_one_read_path_matches_the_verified_path(tmp_path):
    """The default per-run path (the truth linearised in its one read, the twin navigated once at d*) against the
    previous one (`[options] verify = true`: verification reads, the twin's own truth) on the same runs: the
    drifts within 3e-7 deg/h (the verified truth's own tolerance is 1e-7 deg/h), every other scalar identical,
    the error curves within 1e-3 nmi for any drift within 0.002 deg/h of the truth."""
    from gyrodrift.fleet.science import process_run
    from gyrodrift.fleet.store import CampaignRuns

    fast = load_campaign(write_campaign(tmp_path, "fast", 3))
    slow_path = tmp_path / "slow.toml"
    slow_path.write_text(tiny_text(3).replace("[options]\n", "[options]\nverify = true\n"))
    slow = load_campaign(slow_path)
    assert slow.options["verify"] is True and "verify" not in fast.options
    for i in range(3):
        a, b = process_run(slow, i), process_run(fast, i)
        assert a["error"] is None and b["error"] is None
        assert a["truth_verified"] is True and b["truth_verified"] is None
        for name in ("drift_deg_h", "drift_effective_deg_h"):
            assert abs(b[name] - a[name]) < 3e-7, (i, name, b[name] - a[name])
        assert a["drift_deg_h"] != b["drift_deg_h"]  # two computations, not one
        own = ("drift_deg_h", "drift_effective_deg_h", *TRUTH_LAW_COLUMNS)  # each path's own linearisation
        for name, v in a.items():
            if isinstance(v, float) and name not in VOLATILE and name not in own:
                assert b[name] == v or (math.isnan(v) and math.isnan(b[name])), (i, name)
        law_sigmas = {"truth_law_eps_ref_deg_h": "truth_law_eps_ref_std_deg_h"}
        law_sigmas["truth_law_k1_deg_h_per_c"] = "truth_law_k1_std_deg_h_per_c"
        for name, std in law_sigmas.items():  # the best law, about each path's constant: within 3 % of its 1-sigma
            assert abs(b[name] - a[name]) <= 0.03 * a[std] or b[name] == a[name], (i, name)
        assert a["curve_north0_m"] == b["curve_north0_m"] and a["curve_east0_m"] == b["curve_east0_m"]
        runs = [CampaignRuns({}, {k: np.array([r[k]], float) for k in CURVE_COLUMNS}) for r in (a, b)]
        for d in a["drift_deg_h"] + np.array([-0.002, 0.0, 0.002]):
            ea, eb = (r.errors_nmi([d])[0] for r in runs)
            assert np.max(np.abs(ea - eb)) < 1e-3, (i, d)
