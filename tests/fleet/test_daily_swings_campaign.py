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
