"""The daily-swing example campaign (issue 21): every run swings by 2-6 deg C a day on a warm-up, and the campaign
spec draws the swing keys like any other key."""

from __future__ import annotations

from pathlib import Path

import pytest

from gyrodrift.fleet.spec import CampaignError, load_campaign, parse_campaign

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "campaigns" / "daily_swings.toml"


def test_every_run_swings_2_to_6_c_on_a_warm_up():
    c = load_campaign(EXAMPLE)
    amplitudes = []
    for i in range(0, c.count, 7):
        t = c.scenario(i).temperature
        assert 2.0 <= t.swing_amplitude_c <= 6.0
        assert 0.0 <= t.swing_phase_deg <= 360.0 and t.swing_period_h == 24.0
        assert t.start_c != t.end_c and t.series_t_h is None  # the warm-up is there too
        amplitudes.append(t.swing_amplitude_c)
    assert max(amplitudes) - min(amplitudes) > 2.0  # drawn, not fixed


def test_a_swing_that_makes_no_valid_run_is_refused_naming_the_key():
    data = {
        "campaign": {"count": 2},
        "base": {"temperature": {"start_c": 195.0, "end_c": 195.0}},
        "vary": {"temperature.swing_amplitude_c": {"dist": "uniform", "low": 1.0, "high": 10.0}},
    }
    with pytest.raises(CampaignError) as err:
        parse_campaign(data, source="c.toml")
    text = str(err.value)
    assert (
        text.startswith("c.toml: ") and 'vary."temperature.swing_amplitude_c"' in text and "swing_amplitude_c" in text
    )


SWING_CAMPAIGN = """
[campaign]
count = 2
seed = 5

[options]
align_h = 1.0
features_h = 6
truth_h = 12.0
smoother = false

[base.site]
lat_deg = 40.0

[base.run]
duration_h = 13.0
rate_hz = 5.0

[base.gyro]
bias_deg_h = [0.0, 0.0, 0.002]

[base.temperature]
start_c = 24.0
end_c = 30.0
tau_h = 1.0
swing_period_h = 6.0
t0_c = 28.0
k1_deg_h_per_c = 0.0002

[vary."temperature.swing_amplitude_c"]
dist = "choice"
values = [4.0]
"""


def test_a_campaign_stores_the_best_law_beside_the_best_constant(tmp_path):
    import math

    import numpy as np

    from gyrodrift.fleet.campaign import run_campaign
    from gyrodrift.fleet.store import read_runs
    from gyrodrift.runs.columns import TRUTH_LAW_COLUMNS

    path = tmp_path / "swing.toml"
    path.write_text(SWING_CAMPAIGN, encoding="utf-8")
    run_campaign(load_campaign(path), tmp_path / "fleet", text=SWING_CAMPAIGN, workers=1, quiet=True)
    runs = read_runs(tmp_path / "fleet")
    assert runs.ok.all()
    sigmas = {"truth_law_eps_ref_std_deg_h", "truth_law_k1_std_deg_h_per_c", "truth_law_eps_k1_cov"}
    for c in TRUTH_LAW_COLUMNS:
        # the campaign's runs are noise-free (no ARW, no VRW): the law is known, its 1-sigmas are not (NaN, not 0)
        assert np.isfinite(runs.numbers(c)).all() if c not in sigmas else np.isnan(runs.numbers(c)).all(), c
    k1 = runs.numbers("truth_law_k1_deg_h_per_c")
    assert np.all(k1 > 0)  # the sensor's sign (its size also absorbs the 1 h alignment's errors at the 12 h end)
    # The stored curves give the law's criterion to first order: better than the best constant's at the end.
    c = runs.curves
    assert c is not None
    for i in range(len(runs)):
        eps = runs.numbers("truth_law_eps_ref_deg_h")[i]
        n = c["curve_north0_m"][i] + eps * c["curve_north_per_deg_h"][i] + k1[i] * c["curve_north_per_k1"][i]
        e = c["curve_east0_m"][i] + eps * c["curve_east_per_deg_h"][i] + k1[i] * c["curve_east_per_k1"][i]
        law_final_nmi = math.hypot(n[-1], e[-1]) / 1852.0
        const_final_nmi = runs.errors_nmi(runs.numbers("drift_deg_h"))[i, -1]
        assert law_final_nmi < 0.5 * const_final_nmi
    # campaign --run-table writes the law beside the label, and the run-table reader takes it back
    from gyrodrift.fleet.run_table import run_table_rows
    from gyrodrift.runs.table import read_runs_csv, write_run_table

    write_run_table(tmp_path / "runs.csv", *run_table_rows(runs))
    table = read_runs_csv(tmp_path / "runs.csv", require_truth=True)
    header = (tmp_path / "runs.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    for c in TRUTH_LAW_COLUMNS:
        assert (c in header) == (c not in sigmas), c  # a column unknown in every run is not written
        if c in table.extra:  # the columns the reader keeps (T_ref is read and checked, not kept)
            np.testing.assert_allclose(table.extra[c], runs.numbers(c), rtol=1e-12, err_msg=c)
    assert {"truth_law_eps_ref_deg_h", "truth_law_k1_deg_h_per_c"} <= set(table.extra)
