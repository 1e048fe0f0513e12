"""The joint posterior of (end drift, k_z) under the fleet's k_z prior (`posterior_with_coefficient_prior`) against
a brute-force Gaussian conditioning: a linear-Gaussian model y = H x + v of the state x = (end drift, k_z), the
posterior computed from the data twice, once under the filter's prior N(0, s0^2) on k_z (what the smoother reports)
and once under the fleet's N(mean, std^2) (the truth the re-weighting must reach), each by the conditioning formula
of a joint Gaussian (x | y), with numpy's solve. Tolerance: relative 1e-8 of the posterior's scale (the two routes
round differently)."""

from __future__ import annotations

import numpy as np
import pytest

from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior, posterior_with_coefficient_prior


def _condition(prior_mean: np.ndarray, prior_cov: np.ndarray, H: np.ndarray, R: np.ndarray, y: np.ndarray):
    """x | y for x ~ N(prior_mean, prior_cov), y = H x + v, v ~ N(0, R): the joint Gaussian's conditional."""
    S = H @ prior_cov @ H.T + R
    gain = np.linalg.solve(S, H @ prior_cov).T
    return prior_mean + gain @ (y - H @ prior_mean), prior_cov - gain @ H @ prior_cov


def _case(rng: np.random.Generator):
    """A run: 40 observations of (end drift, k_z) through a random design (the drift's change with the temperature
    seen through the heading error), a proper prior on the drift, the filter's wide prior on k_z and a fleet
    prior [deg/h, deg/h/degC]."""
    n = 40
    H = np.column_stack([np.ones(n), rng.uniform(-3.0, 3.0, n)]) * rng.uniform(0.5, 2.0, (n, 1))
    R = np.diag(rng.uniform(0.5, 2.0, n) * 1e-7)
    x_true = np.array([0.003, 2e-4])
    y = H @ x_true + rng.normal(0.0, np.sqrt(np.diag(R)))
    drift_prior_std, s0 = 0.05, 0.01
    mean, std = rng.normal(2e-4, 5e-5), rng.uniform(1e-5, 1e-4)
    filt = _condition(np.zeros(2), np.diag([drift_prior_std**2, s0**2]), H, R, y)
    fleet = _condition(np.array([0.0, mean]), np.diag([drift_prior_std**2, std**2]), H, R, y)
    return filt, fleet, s0, (mean, std)


def test_the_reweighted_joint_posterior_is_the_fleet_priors_conditioning():
    rng = np.random.default_rng(21)
    for _ in range(30):
        (m, P), (m_want, P_want), s0, (mean, std) = _case(rng)
        thermal, d, k, vd, cdk, vk = posterior_with_coefficient_prior(
            m[0], np.sqrt(P[0, 0]), m[1], np.sqrt(P[1, 1]), P[0, 1], s0, mean, std
        )
        assert bool(thermal)
        got = np.array([[vd, cdk], [cdk, vk]])
        assert np.array([d, k]) == pytest.approx(m_want, rel=1e-8, abs=1e-8 * np.sqrt(np.diag(P_want)).max())
        np.testing.assert_allclose(got, P_want, rtol=1e-8, atol=1e-8 * np.abs(P_want).max())
        # the data moved the fleet's prior: the joint posterior is not the prior
        assert vk < std**2 and abs(cdk) > 0.0
        # the drift's marginal is drift_with_coefficient_prior, bit for bit
        assert drift_with_coefficient_prior(m[0], np.sqrt(P[0, 0]), m[1], np.sqrt(P[1, 1]), P[0, 1], s0, mean, std) == (
            float(d),
            float(np.sqrt(vd)),
        )


def test_a_constant_model_run_keeps_its_drift_and_has_no_coefficient():
    thermal, d, k, vd, cdk, vk = posterior_with_coefficient_prior(
        np.array([0.002, 0.003]),
        np.array([3e-4, 2e-4]),
        np.array([np.nan, 1e-4]),
        np.array([np.nan, 2e-4]),
        np.array([np.nan, 1e-8]),
        np.array([np.nan, 0.01]),
        2e-4,
        3e-5,
    )
    assert thermal.tolist() == [False, True]
    assert (d[0], vd[0]) == (0.002, 3e-4**2)
    assert np.isnan([k[0], cdk[0], vk[0]]).all() and np.isfinite([k[1], cdk[1], vk[1]]).all()
