"""The run table's label_flagged column (features -> fit) and the noise options of truth/features/identify."""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.errors import InputError
from gyrodrift.fleet.features import features_table
from gyrodrift.ins import Scenario, simulate
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.model_io import load_model
from gyrodrift.procedure.features import features_run_table
from gyrodrift.procedure.noise import SensorNoise, load_noise_file
from gyrodrift.procedure.timeline import Timeline
from gyrodrift.procedure.writers import features_csv_text
from gyrodrift.runs.table import RunTableError, read_runs_csv

SHORT = Timeline(align_h=0.1, features_h=1.0, truth_h=1.0, coarse_s=60.0)


def _table_csv(path, n=14, flagged=(2, 5)):
    rng = np.random.default_rng(3)
    lines = ["run,lat_deg,lat0_deg,temp_min_c,temp_max_c,drift_deg_h,drift_std_deg_h,label_flagged"]
    for i in range(n):
        lat0 = rng.uniform(20, 60)
        flag = "true" if i in flagged else ("FALSE" if i % 2 else "0")
        std = 8e-4 if i in flagged else 1.5e-4
        lines.append(
            f"r{i},{lat0 + 1e-4 * rng.normal():.9f},{lat0:.6f},{rng.uniform(15, 25):.3f},{rng.uniform(30, 40):.3f},"
            f"{0.002 + 3e-4 * rng.normal():.7f},{std},{flag}"
        )
    path.write_text("\n".join(lines) + "\n")
    return path


def test_flag_column_reads_writes_and_names_a_bad_cell(tmp_path):
    runs = read_runs_csv(_table_csv(tmp_path / "runs.csv"))
    assert runs.column("label_flagged").tolist() == [1.0 if i in (2, 5) else 0.0 for i in range(14)]
    runs.to_csv(tmp_path / "again.csv")
    text = (tmp_path / "again.csv").read_text()
    assert text.splitlines()[3].endswith(",true") and text.splitlines()[1].endswith(",false")
    again = read_runs_csv(tmp_path / "again.csv")
    np.testing.assert_array_equal(again.column("label_flagged"), runs.column("label_flagged"))
    bad = (tmp_path / "runs.csv").read_text().replace(",true\n", ",maybe\n", 1)
    (tmp_path / "bad.csv").write_text(bad)
    with pytest.raises(
        RunTableError, match=r"bad\.csv, row 4, column label_flagged: expected true or false, got 'maybe'"
    ):
        read_runs_csv(tmp_path / "bad.csv")


def test_fit_leaves_flagged_labels_out_by_default_and_says_so(tmp_path):
    data = _table_csv(tmp_path / "runs.csv")
    args = ["fit", str(data), "--gamma", "10", "--sigma", "1", "--encoding", "physics", "--quiet"]
    r = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "m.json")])
    assert r.exit_code == 0, r.output
    assert "note: left out 2 run(s) whose label truth flagged" in r.stderr and "r2, r5" in r.stderr
    model = load_model(tmp_path / "m.json")
    assert model.training["n_runs"] == 12 and model.training["left_out"] == ["r2", "r5"]
    r = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "k.json"), "--flagged-labels", "keep"])
    assert r.exit_code == 0, r.output
    assert "note: kept 2 run(s) whose label truth flagged, down-weighted by their drift_std_deg_h: r2, r5" in r.stderr
    kept = load_model(tmp_path / "k.json")
    assert kept.training["n_runs"] == 14 and kept.training["weighted"]
    w = kept.lssvr.sample_weight_
    assert w[2] < 0.1 * w[0]  # (1.5e-4 / 8e-4)^2 of an unflagged run's weight
    # the API says the same
    runs = read_runs_csv(data)
    m = fit_drift_model(runs, encoding="physics", gamma=10.0, sigma=1.0, flagged_labels="exclude")
    assert m.training_["flagged_left_out"] == ["r2", "r5"]
    with pytest.raises(InputError, match="flagged_labels"):
        fit_drift_model(runs, gamma=10.0, sigma=1.0, flagged_labels="drop")


def test_features_write_the_flag_and_can_skip_the_smoother(tmp_path):
    scn = Scenario.from_dict({"run": {"duration_h": 2.2, "rate_hz": 5.0, "seed": 1}})
    path = simulate(scn, out_dir=tmp_path / "run", quiet=True)
    noise = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0, source="given")
    (with_truth,) = features_table([path], timeline=SHORT, with_truth=True, smoother=False, noise=noise)
    assert math.isnan(with_truth.drift_smoother_deg_h) and math.isfinite(with_truth.drift_std_deg_h)
    assert with_truth.truth is not None and with_truth.truth.noise["source"] == "given"
    text = features_csv_text([with_truth])
    header, row = text.splitlines()
    assert header.endswith(",drift_deg_h,drift_std_deg_h,label_flagged")
    assert row.endswith(",true") or row.endswith(",false")
    table = features_run_table([with_truth])
    assert table.column("label_flagged")[0] == float(with_truth.label_flagged)


def test_noise_file_and_options(tmp_path):
    good = tmp_path / "noise.toml"
    good.write_text("[gyro]\narw_deg_rth = 0.001\nbias_deg_h = [0, 0, 0.003]\n[accel]\nvrw_ug_rthz = 8.0\n")
    noise = load_noise_file(good)
    assert (noise.arw_deg_rth, noise.vrw_ug_rthz, noise.source) == (0.001, 8.0, str(good))
    missing = tmp_path / "missing.toml"
    missing.write_text("[gyro]\narw_deg_rth = 0.001\n")
    with pytest.raises(InputError, match=r"missing\.toml: \[accel\] vrw_ug_rthz: missing \(a noise file needs"):
        load_noise_file(missing)
    text = tmp_path / "text.toml"
    text.write_text('[gyro]\narw_deg_rth = "small"\n[accel]\nvrw_ug_rthz = 5\n')
    with pytest.raises(InputError, match=r"text\.toml: \[gyro\] arw_deg_rth: expected a number, got string 'small'$"):
        load_noise_file(text)
    for body, message in (
        (
            "[gyro]\narw_deg_rth = 0.001\ncorrelation_s = 0\n[accel]\nvrw_ug_rthz = 5\n",
            r"\[gyro\] correlation_s: must be > 0",
        ),
        ("gyro = 1\n[accel]\nvrw_ug_rthz = 5\n", r"bad\.toml: \[gyro\] must be a table, got number$"),
        ("[gyro]\narw_deg_rth = 0.001\n[accel]\nvrw_ug_rthz = -5\n", r"\[accel\] vrw_ug_rthz: must be >= 0, got -5$"),
    ):
        bad = tmp_path / "bad.toml"
        bad.write_text(body)
        with pytest.raises(InputError, match=message):
            load_noise_file(bad)
    runner = CliRunner()
    for command in ("truth", "identify", "features"):
        extra = {"identify": ["--model", "m.json"], "features": ["--out", str(tmp_path / "t.csv")]}.get(command, [])
        r = runner.invoke(main, [command, "nothing.parquet", *extra, "--gyro-arw-deg-rth", "0.001"])
        assert r.exit_code == 2 and "give --gyro-arw-deg-rth and --accel-vrw-ug-rthz together" in r.output
        r = runner.invoke(main, [command, "nothing.parquet", *extra, "--noise", str(missing)])
        assert (
            r.exit_code == 1 and r.output.count("\n") == 1 and "missing.toml: [accel] vrw_ug_rthz: missing" in r.output
        ), r.output
        r = runner.invoke(main, [command, "nothing.parquet", *extra, "--accel-vrw-ug-rthz", "-1"])
        assert r.exit_code == 2 and "--accel-vrw-ug-rthz" in r.output


def test_label_sigma_matches_the_closed_form_of_the_earth_rate_error_model():
    # An independent derivation of truth's 1-sigma (criterion final, span T, ARW N, no VRW). Over many Schuler
    # periods the psi-angle error obeys psi' = -Omega x psi + eps (Omega the Earth rate), and the horizontal
    # position angle is psi_h minus a Schuler oscillation driven by the same gyro noise. White isotropic eps of
    # density N: psi_h has N^2 T per horizontal axis (rotations keep it isotropic), the oscillation N^2 T / 2
    # (their cross term stays bounded): var(position angle) = 1.5 N^2 T per axis. A constant z drift d moves the
    # position angle by d (sin L cos L (T - sin(W T) / W), cos L (1 - cos(W T)) / W) (east, north; method.md's
    # dlon and dL). d* - d = -g'e / |g|^2, so sigma(d*) = sqrt(1.5 T) N / |g| (the Earth radius cancels).
    from gyrodrift.procedure.truth import label_sigma_deg_h

    w = 7.2921151467e-5  # rad/s
    arw = 0.0005  # deg/sqrt(h)
    for hours in (24.0, 72.0):
        t = hours * 3600.0
        for lat in (20.0, 40.0, 60.0):
            lat_r = math.radians(lat)
            g = math.hypot(
                math.sin(lat_r) * math.cos(lat_r) * (t - math.sin(w * t) / w),
                math.cos(lat_r) * (1.0 - math.cos(w * t)) / w,
            )
            closed = math.sqrt(1.5 * t) * arw / 60.0 / g * 3600.0  # deg/h (N in deg/sqrt(s) times s^0.5 / s)
            core = label_sigma_deg_h(lat, SensorNoise(arw_deg_rth=arw, vrw_ug_rthz=0.0), hours=hours)[0]
            # the closed form drops the bounded Schuler cross terms: within 0.6 % at these spans and latitudes
            assert core == pytest.approx(closed, rel=0.015), (hours, lat, core, closed)
            # VRW at RLG grade (5 ug/sqrt(Hz)) adds under 0.5 %; the sigma is linear in the ARW
            with_vrw = label_sigma_deg_h(lat, SensorNoise(arw_deg_rth=arw, vrw_ug_rthz=5.0), hours=hours)[0]
            assert core < with_vrw < 1.005 * core
            double = label_sigma_deg_h(lat, SensorNoise(arw_deg_rth=2 * arw, vrw_ug_rthz=0.0), hours=hours)[0]
            assert double == pytest.approx(2 * core, rel=1e-6)


def test_label_sigma_takes_the_z_gyro_bias_instability_and_rate_random_walk_in_user_units():
    # The core's covariance analysis is checked against closed forms in crates/gyrodrift-core/tests/smoother.rs;
    # here the units the procedure hands it. A Gauss-Markov bias whose correlation time dwarfs the span is a
    # random constant the label absorbs in full: sigma = bias_instability_deg_h.
    from gyrodrift.procedure.truth import label_sigma_deg_h

    const = SensorNoise(arw_deg_rth=0.0, vrw_ug_rthz=0.0, bias_instability_deg_h=0.002, correlation_s=1e9)
    assert label_sigma_deg_h(40.0, const)[0] == pytest.approx(0.002, rel=0.01)
    # A rate random walk's value when the navigation starts (after align_h hours) adds rrw^2 align_h.
    rrw = SensorNoise(arw_deg_rth=0.0, vrw_ug_rthz=0.0, rrw_deg_h_rth=0.0005)
    s4, s0 = (label_sigma_deg_h(40.0, rrw, align_h=a)[0] for a in (4.0, 0.0))
    assert s4**2 - s0**2 == pytest.approx(0.0005**2 * 4.0, rel=1e-6)
    # White noise alone is unchanged by the new terms' defaults, and they add to it.
    white = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0)
    both = SensorNoise(arw_deg_rth=0.0005, vrw_ug_rthz=5.0, bias_instability_deg_h=0.002, correlation_s=1e9)
    assert label_sigma_deg_h(40.0, both)[0] ** 2 == pytest.approx(
        label_sigma_deg_h(40.0, white)[0] ** 2 + label_sigma_deg_h(40.0, const)[0] ** 2, rel=1e-6
    )
