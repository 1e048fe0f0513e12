"""Rotation schemes that cancel: the balanced reciprocating span, the 8-step indexing order, and the
modulation residual that predicts what a scheme leaves of a horizontal sensor error (issue 4, task 2).

A body-fixed horizontal bias b seen in the navigation frame is b rotated by the table angle alpha(t); over a
period of the scheme its mean is r b with r = |mean of (cos alpha, sin alpha)|, the *modulation residual*.
Position errors of horizontal biases therefore scale with r: r = 1 without rotation, 0.0196 for a 360 deg
reciprocating sweep at 6 deg/s with 10 deg/s^2 ramps (it reverses at the same heading), 0 for the
balanced span and for the order [0, 90, 180, 270, 360, 270, 180, 90].
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from gyrodrift import _core
from gyrodrift.ins import Scenario, ScenarioError
from gyrodrift.ins.simulate import rotation_summary
from gyrodrift.procedure import navigate
from gyrodrift.units import DEG

ERRORS = {"gyro": {"bias_deg_h": [0.01, 0.01, 0.0]}, "accel": {"bias_ug": [50.0, 50.0, 0.0]}}
RUN72 = {"duration_h": 72.0, "rate_hz": 10.0}
SLOW = {"scheme": "reciprocating", "rate_deg_s": 6.0, "accel_deg_s2": 10.0}


def scenario(**sections) -> Scenario:
    data = {"site": {"lat_deg": 28.222, "lon_deg": 112.99}}
    data.update(sections)
    return Scenario.from_dict(data, source="<test>")


def residual(rotation: dict) -> float:
    return rotation_summary(scenario(rotation=rotation))["modulation_residual"]


def test_residual_of_the_schemes():
    assert residual({"scheme": "none"}) == 1.0
    assert residual({"scheme": "continuous"}) == 0.0
    # Reversing at the same heading: about 2 T_r / period = T_r / (span / rate + T_r) with T_r = 1.2 s.
    t_r = 2.0 * 6.0 / 10.0
    assert residual(SLOW) == pytest.approx(t_r / (360.0 / 6.0 + t_r), rel=0.05)
    assert residual(dict(SLOW, span_deg="balanced")) < 1e-12
    # Indexing: the default 8-step order cancels, the old default [0, 180, 90, 270] leaves about 4 %.
    assert Scenario().rotation.positions_deg == (0.0, 90.0, 180.0, 270.0, 360.0, 270.0, 180.0, 90.0)
    assert residual({"scheme": "indexing"}) < 1e-12
    assert residual({"scheme": "indexing", "positions_deg": [0, 180, 90, 270]}) == pytest.approx(0.04, abs=0.005)


def test_balanced_span_is_just_short_of_a_turn_and_resolved_in_the_summary():
    span = rotation_summary(scenario(rotation=dict(SLOW, span_deg="balanced")))["span_deg"]
    direct = _core.balanced_reciprocating_span_rad(6.0 * DEG, 10.0 * DEG, 0.0) / DEG
    assert span == pytest.approx(direct, abs=1e-9)
    assert 340.0 < span < 360.0
    assert rotation_summary(scenario(rotation=SLOW))["span_deg"] == 360.0
    assert rotation_summary(scenario(rotation={"scheme": "indexing"}))["span_deg"] is None


def test_balanced_span_cancels_horizontal_errors_that_a_full_turn_leaves():
    """72 h, 0.01 deg/h + 50 ug horizontal errors, 10 deg/s^2 ramps. Without rotation about 34 nmi; the 360
    deg sweep leaves r = 2 % of it (about 0.7 nmi); the balanced span leaves only the bounded oscillation of
    the modulated errors. The measured ratio to the unrotated error matches the residual."""
    cases = [
        scenario(run=RUN72, rotation={"scheme": "none"}, **ERRORS),
        scenario(run=RUN72, rotation=SLOW, **ERRORS),
        scenario(run=RUN72, rotation=dict(SLOW, span_deg="balanced"), **ERRORS),
    ]
    with ThreadPoolExecutor(max_workers=2) as pool:
        static, plain, balanced = pool.map(lambda s: navigate(s, decimation_s=60.0), cases)
    e_static = static.checkpoint(72)["pos_err_nmi"]
    e_plain = plain.checkpoint(72)["pos_err_nmi"]
    e_bal = balanced.checkpoint(72)["pos_err_nmi"]
    assert e_plain / e_static == pytest.approx(residual(SLOW), rel=0.15)
    assert e_bal < 0.2 * e_plain, (e_bal, e_plain)
    assert balanced.summary["max_pos_err_nmi"] < 0.3 * plain.summary["max_pos_err_nmi"]


@pytest.mark.parametrize(
    "value, message",
    [
        ('"balance"', """[rotation] span_deg: expected a number > 0 or "balanced", got 'balance'"""),
        ("true", """[rotation] span_deg: expected a number > 0 or "balanced", got boolean True"""),
        ("0", "[rotation] span_deg: must be > 0, got 0"),
        ("[360]", """[rotation] span_deg: expected a number > 0 or "balanced", got array [360]"""),
    ],
)
def test_bad_span_values_name_the_key(tmp_path, value, message):
    p = tmp_path / "s.toml"
    p.write_text(f'[rotation]\nscheme = "reciprocating"\nspan_deg = {value}\n')
    from gyrodrift.ins import load_scenario

    with pytest.raises(ScenarioError) as exc:
        load_scenario(p)
    assert str(exc.value) == f"{p}: {message}"


def test_balanced_span_round_trips_and_reaches_the_core():
    s = scenario(rotation=dict(SLOW, span_deg="balanced"))
    assert s.rotation.span_deg == "balanced" and s.rotation.balanced_span
    assert Scenario.from_dict(s.to_toml_dict()) == s
    cfg = s.to_core_config()
    assert cfg.reciprocating_balanced is True
    assert scenario(rotation=SLOW).to_core_config().reciprocating_balanced is False
    # The typed config checks the new keyword's type and names it.
    base = {
        "lat_rad": 0.5,
        "rate_hz": 10.0,
        "duration_s": 10.0,
        "rotation_scheme": "reciprocating",
        "rotation_accel_rad_s2": 10 * DEG,
    }
    with pytest.raises(TypeError, match="reciprocating_balanced"):
        _core.SimulatorConfig(**base, reciprocating_balanced=1)
    sim = _core.ImuSimulator(
        _core.SimulatorConfig(**base, reciprocating_balanced=True, reciprocating_span_rad=4 * math.pi)
    )
    two = _core.balanced_reciprocating_span_rad(base.get("rotation_rate_rad_s", 6 * DEG), 10 * DEG, 0.0, 2)
    assert sim.reciprocating_span_rad == pytest.approx(two, abs=1e-12) and 3.5 * math.pi < two < 4 * math.pi
    assert sim.modulation_residual < 1e-12


def test_chunks_held_by_python_are_never_overwritten():
    """next_chunk refills the arrays of earlier chunks only once Python has dropped every reference."""
    cfg = scenario(
        run={"duration_h": 0.1, "rate_hz": 50.0, "seed": 3}, gyro={"arw_deg_rth": 0.01}, rotation=SLOW
    ).to_core_config()
    ref = _core.ImuSimulator(cfg).next_chunk(10**6)
    sim = _core.ImuSimulator(cfg)
    kept = sim.next_chunk(1000)
    view = sim.next_chunk(1000)["dtheta_rad"][:, 2]  # only a view of the second chunk survives
    expect_kept = {k: v.copy() for k, v in kept.items()}
    got = []
    while (c := sim.next_chunk(1000)) is not None:
        got.append(c["dv_m_s"].copy())
    for k, v in expect_kept.items():
        np.testing.assert_array_equal(kept[k], v)
        np.testing.assert_array_equal(kept[k], ref[k][:1000])
    np.testing.assert_array_equal(view, ref["dtheta_rad"][1000:2000, 2])
    np.testing.assert_array_equal(np.concatenate(got), ref["dv_m_s"][2000:])


def test_simulate_command_prints_the_span_and_the_residual(tmp_path):
    from click.testing import CliRunner

    from gyrodrift.cli.navigation import simulate_command

    toml = tmp_path / "s.toml"
    toml.write_text(
        '[run]\nduration_h = 0.01\nrate_hz = 10.0\n[rotation]\nspan_deg = "balanced"\naccel_deg_s2 = 10.0\n'
    )
    r = CliRunner().invoke(simulate_command, [str(toml), "--out", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert "reciprocating rotation, span 352.8115 deg, modulation residual 0.000 %" in r.output
    toml.write_text(
        '[run]\nduration_h = 0.01\nrate_hz = 10.0\n[rotation]\nscheme = "indexing"\npositions_deg = [0, 180, 90, 270]\n'
    )
    r = CliRunner().invoke(simulate_command, [str(toml), "--out", str(tmp_path / "p")])
    assert r.exit_code == 0, r.output
    assert "indexing rotation, modulation residual 4.09" in r.output
