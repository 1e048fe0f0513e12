"""`estimate_white_noise` reads the sensors' white noise, not the table's turning, at any sample rate: its
fourth differences of the increments remove a cubic trend exactly and keep the turning's modulation of Earth rate
and gravity small against the noise down to 1-2 Hz (gyrodrift.procedure.noise module docs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyrodrift.earth import OMEGA_IE_RAD_S, normal_gravity
from gyrodrift.errors import InputError
from gyrodrift.ins import Scenario
from gyrodrift.ins.simulate import scenario_log
from gyrodrift.logs import ImuLog
from gyrodrift.procedure.noise import estimate_white_noise, lattice_steps
from gyrodrift.units import ARCSEC, DEG, MICRO_G

ARW, VRW = 0.0005, 5.0  # deg/sqrt(h), ug/sqrt(Hz): the RLG grade of the tests


def tilted_table(rate_hz: float, *, noise: bool, seed: int = 1) -> ImuLog:
    """One hour on the default reciprocating table (6 deg/s, 360 deg sweeps) at 40 deg, tilted by 1 deg (pitch):
    the x/y gyros see the horizontal Earth rate (9.7 deg/h) and the x/y accelerometers 0.17 m/s^2 of gravity,
    both turning with the table."""
    return scenario_log(
        Scenario.from_dict(
            {
                "site": {"lat_deg": 40.0},
                "run": {"duration_h": 1.0, "rate_hz": rate_hz, "seed": seed},
                "rotation": {"scheme": "reciprocating"},
                "gyro": {"bias_deg_h": [0.004, -0.003, 0.003], "arw_deg_rth": ARW if noise else 0.0},
                "accel": {"bias_ug": [20.0, -10.0, 5.0], "vrw_ug_rthz": VRW if noise else 0.0},
                "attitude": {"yaw_deg": 30.0, "pitch_deg": 1.0},
            }
        )
    )


@pytest.mark.parametrize("rate_hz", [1.0, 2.0])
def test_a_noise_free_tilted_table_at_low_rates_reads_as_nearly_noise_free(rate_hz):
    """Second differences read this log (the three axes' mean) as 1.1e-4 deg/sqrt(h) and 9.8 ug/sqrt(Hz) at 2 Hz
    (0.2 and 2 times the RLG grade), 6.2e-4 and 56 at 1 Hz; fourth differences 8.9e-8 and 0.008 at 2 Hz, 2.1e-6 and
    0.19 at 1 Hz (benchmarks/bench_white_noise.py). The bounds, a tenth and a fifth of the grade, lie decisively
    between."""
    n = estimate_white_noise(tilted_table(rate_hz, noise=False))
    assert n.arw_deg_rth < ARW / 10 and n.vrw_ug_rthz < VRW / 5, (n.arw_deg_rth, n.vrw_ug_rthz)


def test_a_noisy_tilted_table_at_2_hz_reads_its_noise():
    """At 2 Hz over six seeds: ARW 1.026 +- 0.007 and VRW 1.009 +- 0.010 times the simulated (second differences:
    VRW 2.15 times; benchmarks/bench_white_noise.py); the ARW's few per cent are the table's reversals, each a few
    samples of a 7200-sample hour."""
    n = estimate_white_noise(tilted_table(2.0, noise=True, seed=3))
    assert n.arw_deg_rth == pytest.approx(ARW, rel=0.06) and n.vrw_ug_rthz == pytest.approx(VRW, rel=0.06)


def test_a_cubic_trend_leaves_the_estimate_unchanged():
    """Fourth differences of a cubic in the sample index are zero: a level, north-facing IMU at rest (Earth rate
    and gravity) with a trend that ends at 1e4 times the noise (950 deg/h, 16 mg: a stand-in for the smooth signal of
    any static base) reads the same noise as without it, to rounding."""
    rate_hz, n, lat = 10.0, 36_000, math.radians(40.0)
    dt = 1.0 / rate_hz
    s_g = ARW * DEG / 60.0 * math.sqrt(dt)  # per-sample 1-sigma of a gyro increment [rad]
    s_a = VRW * MICRO_G * math.sqrt(dt)  # of an accelerometer increment [m/s]
    at_rest = {  # body right-forward-up = east-north-up
        "dtheta": np.array([0.0, math.cos(lat), math.sin(lat)]) * OMEGA_IE_RAD_S * dt,
        "dv": np.array([0.0, 0.0, float(normal_gravity(lat))]) * dt,
    }
    k = np.arange(n) / n

    def log(trend: float) -> ImuLog:
        rng = np.random.default_rng(7)  # the same noise under each trend
        cols = {"t_s": np.arange(n) * dt}
        for i, axis in enumerate("xyz"):
            cubic = trend * (i + 1) * k**3
            cols[f"dtheta_{axis}_rad"] = at_rest["dtheta"][i] + s_g * (rng.standard_normal(n) + cubic)
            cols[f"dv_{axis}_m_s"] = at_rest["dv"][i] + s_a * (rng.standard_normal(n) + cubic)
        site = {"lat_deg": 40.0, "lon_deg": 0.0, "height_m": 0.0}
        return ImuLog.from_arrays(cols, site=site, require_temperature=False)

    flat, steep = estimate_white_noise(log(0.0)), estimate_white_noise(log(1e4 / 3))
    assert flat.arw_deg_rth == pytest.approx(ARW, rel=0.03) and flat.vrw_ug_rthz == pytest.approx(VRW, rel=0.03)
    assert steep.arw_deg_rth == pytest.approx(flat.arw_deg_rth, rel=1e-6)
    assert steep.vrw_ug_rthz == pytest.approx(flat.vrw_ug_rthz, rel=1e-6)


def counted(log: ImuLog, gyro_step_rad: float, accel_step_m_s: float) -> ImuLog:
    """`log`'s first hour as a pulse counter would give it: each increment a whole number of steps, the remainder
    carried to the next sample (as examples/logs/make_examples.py writes ins_pulses.parquet)."""
    chunk = next(log.chunks(log.samples_for(3600.0)))

    def pulses(x: np.ndarray, step: float) -> np.ndarray:
        total = np.round(np.cumsum(x, axis=0) / step)
        return np.diff(total, axis=0, prepend=np.zeros((1, 3))) * step

    g, a = pulses(np.asarray(chunk.dtheta_rad), gyro_step_rad), pulses(np.asarray(chunk.dv_m_s), accel_step_m_s)
    cols = {"t_s": np.asarray(chunk.t_s)}
    for i, axis in enumerate("xyz"):
        cols[f"dtheta_{axis}_rad"], cols[f"dv_{axis}_m_s"] = g[:, i], a[:, i]
    site = {"lat_deg": 40.0, "lon_deg": 0.0, "height_m": 0.0}
    return ImuLog.from_arrays(cols, site=site, require_temperature=False)


def per_sample_sigma(rate_hz: float) -> tuple[float, float]:
    """The RLG grade's per-sample 1-sigma of a gyro increment [rad] and of an accelerometer increment [m/s]."""
    return ARW * DEG / 60.0 * math.sqrt(1.0 / rate_hz), VRW * MICRO_G * math.sqrt(1.0 / rate_hz)


def test_lattice_steps_find_a_counters_step_and_nothing_in_continuous_data():
    rng = np.random.default_rng(3)
    x = rng.standard_normal((5000, 3)) * 1e-6 + np.array([0.0, 5e-6, 1e-2])
    np.testing.assert_array_equal(lattice_steps(x), 0.0)  # continuous values, at any offset
    step = 0.01 * ARCSEC
    counts = np.round(x / step)
    np.testing.assert_allclose(lattice_steps(counts * step), step, rtol=1e-9)  # up to 2e5 steps per sample (z)
    np.testing.assert_array_equal(lattice_steps(np.ones((10, 2))), 0.0)  # one value: no lattice to see
    jump = np.repeat([[0.0], [5 * 9.80665]], 50, axis=0)  # an accelerometer that jumps to 5 g: not a counter
    np.testing.assert_array_equal(lattice_steps(jump), 0.0)
    np.testing.assert_allclose(lattice_steps(np.array([[0.0], [1.0], [3.0]]) * step), step, rtol=1e-9)


def test_fine_pulses_read_about_the_noise_of_their_unquantised_twin():
    """Steps of 0.3 times the per-sample noise: the counting adds 0.2-2.7 % to the reading over six seeds (mean 1 %;
    6 % at 0.5, 13 % at 0.8); within 4 % of the same log's reading before counting."""
    log = tilted_table(10.0, noise=True, seed=5)
    s_g, s_a = per_sample_sigma(10.0)
    twin, pulses = estimate_white_noise(log), estimate_white_noise(counted(log, 0.3 * s_g, 0.3 * s_a))
    assert 0.99 < pulses.arw_deg_rth / twin.arw_deg_rth < 1.04
    assert 0.99 < pulses.vrw_ug_rthz / twin.vrw_ug_rthz < 1.04


@pytest.mark.parametrize(("rate_hz", "gyro_step_arcsec"), [(10.0, 0.0095), (10.0, 0.1), (100.0, 1.0)])
def test_pulses_coarser_than_the_noise_are_refused_with_the_fix(rate_hz, gyro_step_arcsec):
    """Steps of one per-sample noise (0.0095 arcsec at 10 Hz: twice the limit), and an RLG's 0.1-1 arcsec pulses
    against 0.0095 (10 Hz) or 0.003 arcsec (100 Hz) of noise per sample, where the differences read 7 times the ARW,
    or 0 (a median on a coarse lattice): refused, naming the gyros and the fix."""
    log = counted(tilted_table(rate_hz, noise=True), gyro_step_arcsec * ARCSEC, 1e-7)
    with pytest.raises(
        InputError,
        match=r"steps \(pulse counts, or the file.s rounding\) too coarse.*gyro x: steps of .* arcsec.*--noise FILE",
    ) as err:
        estimate_white_noise(log)
    assert "accelerometer" not in str(err.value)  # 1e-7 m/s steps, far below its noise
