"""dask's shutdown says nothing (issue 18, item 5): `features --workers 2` used to print a `CommClosedError`
traceback under load ("Failed to communicate with scheduler during heartbeat") and nanny warnings after its
results were written."""

import logging
import os
import subprocess
import sys

import pytest

pytest.importorskip("dask.distributed")


def test_features_on_a_local_cluster_ends_without_dask_noise(tmp_path):
    from gyrodrift.ins.synthetic_fleet import simulate_fleet

    # 2 Hz, not 5: the point is what dask prints on shutdown, not the features' numbers (stderr empty at both rates;
    # the test's sum 10.9 -> 6.0 s on a loaded machine)
    logs, _ = simulate_fleet(tmp_path / "fleet", 2, rate_hz=2.0, rng=1)
    out = tmp_path / "runs.csv"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    cli = [sys.executable, "-c", "from gyrodrift.cli import main; main()"]
    # The noise given, so that stderr has no note on a measured noise (`features` says it once otherwise).
    noise = ["--gyro-arw-deg-rth", "0.0005", "--accel-vrw-ug-rthz", "5"]
    done = subprocess.run(
        [*cli, "features", *map(str, logs), *noise, "--workers", "2", "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "distributed." not in done.stderr, done.stderr
    assert done.stderr == "" and done.stdout == ""
    assert len(out.read_text().splitlines()) == 1 + 2


def test_closing_restores_this_processes_dask_log_levels():
    from gyrodrift.fleet.cluster import dask_client

    loggers = [logging.getLogger(name) for name in ("distributed", "tornado")]
    before = [lg.level for lg in loggers]
    with dask_client(workers=1, processes=False) as client:
        assert client.submit(sum, [1, 2]).result() == 3
    assert [lg.level for lg in loggers] == before
