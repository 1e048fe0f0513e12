"""Kernels of the LSSVM: conventions (sigma^2 in the RBF denominator, no factor 2), exactness, errors."""

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from sklearn.metrics import pairwise

from gyrodrift.learn.kernels import (
    check_kernel,
    check_positive,
    kernel_matrix,
    linear_kernel,
    polynomial_kernel,
    rbf_from_squared_distances,
    rbf_kernel,
    squared_distances,
)

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@st.composite
def point_sets(draw, max_n=12, max_d=4):
    n = draw(st.integers(1, max_n))
    d = draw(st.integers(1, max_d))
    return draw(arrays(np.float64, (n, d), elements=finite))


@settings(max_examples=60, deadline=None)
@given(point_sets())
def test_squared_distances_exact_zero_diagonal_symmetric_nonnegative(X):
    D = squared_distances(X)
    assert D.shape == (len(X), len(X))
    assert np.all(np.diag(D) == 0.0)
    assert np.array_equal(D, D.T)
    assert np.all(D >= 0.0)
    brute = ((X[:, None, :] - X[None, :, :]) ** 2).sum(axis=-1)
    np.testing.assert_allclose(D, brute, rtol=1e-12, atol=0)


def test_squared_distances_duplicates_are_exactly_zero_where_expansion_is_not():
    # Large, nearly equal coordinates: |x|^2 + |z|^2 - 2 x.z loses everything to cancellation.
    X = np.array([[1e8 + 0.1, 3.0], [1e8 + 0.1, 3.0], [1e8 + 0.3, 3.0]])
    D = squared_distances(X)
    assert D[0, 1] == 0.0 and D[1, 0] == 0.0
    assert D[0, 2] == pytest.approx(0.04, rel=1e-6)


def test_squared_distances_cross_matrix():
    X = np.array([[0.0, 0.0], [1.0, 2.0]])
    Z = np.array([[3.0, 4.0], [0.0, 0.0], [1.0, 0.0]])
    np.testing.assert_array_equal(squared_distances(X, Z), [[25.0, 0.0, 1.0], [8.0, 5.0, 4.0]])


def test_squared_distances_errors():
    with pytest.raises(ValueError, match=r"X must be a 2-D array \(n_samples, n_features\), got shape \(3,\)"):
        squared_distances(np.zeros(3))
    with pytest.raises(ValueError, match="X has 2 features but Z has 3"):
        squared_distances(np.zeros((2, 2)), np.zeros((2, 3)))


def test_rbf_has_sigma_squared_denominator_without_factor_two():
    sigma = 0.37
    K = rbf_kernel(np.array([[0.0]]), np.array([[sigma], [2 * sigma]]), sigma=sigma)
    # exp(-1) at one sigma (a factor 2 would give exp(-1/2)); exp(-4) at two sigma.
    np.testing.assert_allclose(K, [[np.exp(-1.0), np.exp(-4.0)]], rtol=1e-15)


@settings(max_examples=40, deadline=None)
@given(point_sets(max_d=3), st.floats(0.05, 20.0))
def test_rbf_matches_sklearn_with_gamma_one_over_sigma_squared(X, sigma):
    X = X / 100.0
    K = rbf_kernel(X, sigma=sigma)
    brute = np.exp(-((X[:, None, :] - X[None, :, :]) ** 2).sum(axis=-1) / sigma**2)
    np.testing.assert_allclose(K, brute, rtol=1e-12, atol=1e-300)
    # scikit-learn expands |x|^2 + |z|^2 - 2 x.z, which loses ~eps |x|^2 / sigma^2 to cancellation
    # (hypothesis found 2e-12 for equal points at |x|^2 / sigma^2 ~ 5e3); hence the looser tolerance.
    np.testing.assert_allclose(K, pairwise.rbf_kernel(X, gamma=1 / sigma**2), rtol=1e-12, atol=1e-9)


def test_rbf_from_squared_distances_broadcasts_a_stack_of_widths():
    D = squared_distances(np.arange(4.0)[:, None])
    sig = np.array([0.5, 1.0, 3.0])
    stack = rbf_from_squared_distances(D, sig[:, None, None])
    assert stack.shape == (3, 4, 4)
    for k, s in enumerate(sig):
        # numpy's exp may take a SIMD or a scalar path by array layout: the same values to 2 ulps
        np.testing.assert_array_max_ulp(stack[k], rbf_from_squared_distances(D, s), maxulp=2)


def test_linear_and_polynomial_match_sklearn():
    rng = np.random.default_rng(3)
    X, Z = rng.normal(size=(7, 3)), rng.normal(size=(5, 3))
    # two BLAS dot products (summation order, FMA): equal to a few ulps of the terms' size |x||z|, not of a
    # result that may cancel towards 0
    scale = np.linalg.norm(X, axis=1)[:, None] * np.linalg.norm(Z, axis=1)[None, :]
    np.testing.assert_array_less(
        np.abs(linear_kernel(X, Z) - pairwise.linear_kernel(X, Z)), 8 * np.finfo(float).eps * scale
    )
    for sigma, degree, coef0 in [(1.0, 3, 1.0), (0.7, 2, 0.0), (2.5, 4, -0.3), (1.3, 1, 2.0)]:
        # (x.z / sigma^2 + coef0)^degree: the base's rounding is a few ulps of its terms' size t, the power's
        # error at most degree * t^degree times that (bases here come within 0.01 of 0 with terms up to 11)
        t = np.abs(X) @ np.abs(Z).T / sigma**2 + abs(coef0)
        got = polynomial_kernel(X, Z, sigma=sigma, degree=degree, coef0=coef0)
        want = pairwise.polynomial_kernel(X, Z, degree=degree, gamma=1 / sigma**2, coef0=coef0)
        np.testing.assert_array_less(np.abs(got - want), 16 * np.finfo(float).eps * degree * t**degree)


def test_kernel_matrix_dispatch_and_alias():
    rng = np.random.default_rng(4)
    X = rng.normal(size=(6, 2))
    np.testing.assert_array_equal(kernel_matrix(X, kernel="rbf", sigma=0.8), rbf_kernel(X, sigma=0.8))
    np.testing.assert_array_equal(kernel_matrix(X, kernel="linear", sigma=5.0), linear_kernel(X))
    np.testing.assert_array_equal(
        kernel_matrix(X, kernel="polynomial", sigma=0.8, degree=2, coef0=0.5),
        kernel_matrix(X, kernel="poly", sigma=0.8, degree=2, coef0=0.5),
    )
    assert check_kernel("polynomial") == "poly"


@pytest.mark.parametrize("value", [0, 0.0, -1.0, float("nan"), float("inf"), "1.0", None, True])
def test_sigma_must_be_a_positive_finite_number(value):
    with pytest.raises(ValueError, match=re.escape(f"sigma must be a finite number > 0, got {value!r}") + "$"):
        kernel_matrix(np.zeros((2, 1)), sigma=value)


def test_check_positive_returns_float():
    assert check_positive("gamma", 3) == 3.0 and isinstance(check_positive("gamma", 3), float)


def test_unknown_kernel_and_bad_polynomial_parameters():
    X = np.zeros((2, 1))
    with pytest.raises(ValueError, match=r"unknown kernel 'sigmoid'; expected one of 'rbf', 'linear', 'poly'"):
        kernel_matrix(X, kernel="sigmoid")
    with pytest.raises(ValueError, match="unknown kernel None"):
        kernel_matrix(X, kernel=None)
    with pytest.raises(ValueError, match="degree must be an integer >= 1, got 2.5"):
        kernel_matrix(X, kernel="poly", degree=2.5)
    with pytest.raises(ValueError, match="degree must be an integer >= 1, got 0"):
        kernel_matrix(X, kernel="poly", degree=0)
    with pytest.raises(ValueError, match="coef0 must be a finite real number, got nan"):
        kernel_matrix(X, kernel="poly", coef0=float("nan"))
    # An integral float degree (e.g. from a parameter grid) is accepted.
    np.testing.assert_array_equal(polynomial_kernel(X + 1, degree=2.0), polynomial_kernel(X + 1, degree=2))
