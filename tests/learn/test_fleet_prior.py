"""The fleet prior on k_z and the re-weighted end drift against an independent information-form computation."""

import math

import numpy as np
import pytest

from gyrodrift.errors import InputError
from gyrodrift.learn.fleet_prior import (
    drift_with_coefficient_prior,
    leave_one_out_coefficient_priors,
    pooled_coefficient_prior,
)


def _information_form(d, vd, k, vk, c, s0, mean, std):
    """Joint posterior N([d, k], P) divided by the prior N(0, s0^2) on k, times N(mean, std^2): in information
    form (precision matrices add), with numpy's inverse."""
    info = np.linalg.inv(np.array([[vd, c], [c, vk]]))
    vec = info @ np.array([d, k])
    info = info + np.diag([0.0, 1.0 / std**2 - 1.0 / s0**2])
    vec = vec + np.array([0.0, mean / std**2])
    cov = np.linalg.inv(info)
    x = cov @ vec
    return x[0], math.sqrt(cov[0, 0])


def test_reweighted_drift_matches_the_information_form():
    rng = np.random.default_rng(3)
    for _ in range(50):
        sd, sk = rng.uniform(1e-4, 5e-4), rng.uniform(5e-5, 3e-4)
        rho = rng.uniform(-0.95, 0.95)
        d, k, s0 = rng.normal(0.002, 0.001), rng.normal(2e-4, 1e-4), 0.01
        mean, std = rng.normal(2e-4, 5e-5), rng.uniform(1e-5, 1e-4)
        got = drift_with_coefficient_prior(d, sd, k, sk, rho * sd * sk, s0, mean, std)
        want = _information_form(d, sd**2, k, sk**2, rho * sd * sk, s0, mean, std)
        assert got[0] == pytest.approx(want[0], rel=1e-9, abs=1e-15)
        assert got[1] == pytest.approx(want[1], rel=1e-7)
        assert got[1] <= sd * (1 + 1e-12)  # a tighter prior never widens the estimate


def test_arrays_equal_the_scalar_calls_and_constant_rows_pass_through():
    d = np.array([0.002, 0.003, 0.001])
    sd = np.array([3e-4, 2e-4, 1.9e-4])
    k = np.array([1e-4, np.nan, 3e-4])
    sk = np.array([2e-4, np.nan, 1e-4])
    c = np.array([4e-8, np.nan, -1e-8])
    s0 = np.array([0.01, np.nan, 0.01])
    got_d, got_s = drift_with_coefficient_prior(d, sd, k, sk, c, s0, 2e-4, 3e-5)
    for i in (0, 2):
        one = drift_with_coefficient_prior(d[i], sd[i], k[i], sk[i], c[i], s0[i], 2e-4, 3e-5)
        assert (got_d[i], got_s[i]) == one  # bit for bit
    assert (got_d[1], got_s[1]) == (d[1], sd[1])


def test_filter_prior_gives_the_estimate_back_and_bad_priors_are_refused():
    d, s = drift_with_coefficient_prior(0.002, 3e-4, 1e-4, 2e-4, 4e-8, 0.01, 0.0, 0.01)
    assert d == pytest.approx(0.002, abs=1e-15) and s == pytest.approx(3e-4, rel=1e-12)
    for mean, std in ((0.0, 0.0), (math.nan, 1e-4), (0.0, math.inf)):
        with pytest.raises(InputError, match="k_z prior"):
            drift_with_coefficient_prior(0.002, 3e-4, 1e-4, 2e-4, 4e-8, 0.01, mean, std)


def test_pooled_prior_is_the_random_effects_mean():
    mean, std = pooled_coefficient_prior([1e-4, 2e-4, 3e-4], [1e-4, 1e-4, 1e-4])
    assert mean == pytest.approx(2e-4) and std == pytest.approx(1e-4 / math.sqrt(3))  # Q < n - 1: no spread
    mean, std = pooled_coefficient_prior([0.0, 1e-3, 2e-3, np.nan], [1e-4, 1e-4, 1e-4, np.nan])
    assert mean == pytest.approx(1e-3) and std > 5e-4  # the units disagree far beyond their sigmas
    with pytest.raises(InputError, match="at least 2"):
        pooled_coefficient_prior([1e-4, np.nan], [1e-4, 1e-4])


def _plain_leave_one_out(k, s, rows):
    """The reference: `pooled_coefficient_prior` on the arrays with each row's entry deleted."""
    idx = np.arange(len(k))
    return np.array([pooled_coefficient_prior(k[idx != i], s[idx != i]) for i in rows])


@pytest.mark.parametrize("n", [3, 4, 9, 17, 40, 300])
def test_leave_one_out_priors_are_the_plain_calls_bit_for_bit(n, monkeypatch):
    import gyrodrift.learn.fleet_prior as fleet_prior

    monkeypatch.setattr(fleet_prior, "LOO_CHUNK_ELEMENTS", 50)  # several blocks of rows
    rng = np.random.default_rng(n)
    k = rng.normal(2e-4, 3e-5, n) * np.where(rng.random(n) < 0.3, 10.0, 1.0)  # some units far off: tau^2 > 0
    s = rng.uniform(5e-6, 1e-4, n)
    if n > 4:
        k[1], s[2] = np.nan, -s[2]  # unusable entries: no k_z, a negative sigma
    rows = np.arange(n)
    got = leave_one_out_coefficient_priors(k, s, rows)
    np.testing.assert_array_equal(got, _plain_leave_one_out(k, s, rows))  # the same floats, not just close
    assert np.any(got[:, 1] > np.sqrt(1.0 / np.sum(1.0 / s[np.isfinite(k) & (s > 0)] ** 2)))  # spread counted


def test_leave_one_out_priors_refuse_as_the_plain_calls():
    k, s = np.array([1e-4, 2e-4, np.nan]), np.array([1e-4, 1e-4, 1e-4])
    with pytest.raises(InputError, match="at least 2"):
        leave_one_out_coefficient_priors(k, s, [0])
    np.testing.assert_array_equal(leave_one_out_coefficient_priors(k, s, [2]), _plain_leave_one_out(k, s, [2]))


def test_one_prior_per_run_equals_one_call_per_run():
    rng = np.random.default_rng(8)
    d, sd = rng.normal(0.002, 0.001, 20), rng.uniform(1e-4, 3e-4, 20)
    k, sk, c = rng.normal(2e-4, 1e-4, 20), rng.uniform(5e-5, 2e-4, 20), rng.uniform(-1e-8, 4e-8, 20)
    mean, std = rng.normal(2e-4, 2e-5, 20), rng.uniform(1e-5, 5e-5, 20)
    got_d, got_s = drift_with_coefficient_prior(d, sd, k, sk, c, 0.01, mean, std)
    for i in range(20):
        assert (got_d[i], got_s[i]) == drift_with_coefficient_prior(
            d[i], sd[i], k[i], sk[i], c[i], 0.01, float(mean[i]), float(std[i])
        )  # bit for bit
    std[7] = 0.0
    with pytest.raises(InputError, match=r"k_z prior .* got .*, 0\.0$"):
        drift_with_coefficient_prior(d, sd, k, sk, c, 0.01, mean, std)
