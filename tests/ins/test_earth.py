"""The Rust core through the whole chain: built, imported, and checked against closed forms."""

import numpy as np
import pytest

from gyrodrift import earth


def test_constants_are_wgs84():
    assert earth.WGS84_A_M == 6378137.0
    assert earth.WGS84_F == pytest.approx(1 / 298.257223563, rel=1e-15)
    assert earth.OMEGA_IE_RAD_S == 7.2921151467e-5
    assert earth.NMI_M == 1852.0


def test_normal_gravity_equator_pole_and_broadcast():
    g = earth.normal_gravity(np.deg2rad([0.0, 90.0]), 0.0)
    np.testing.assert_allclose(g, [9.7803253359, 9.8321849378], rtol=0, atol=1e-9)
    grid = earth.normal_gravity(np.zeros((2, 3)), np.array([0.0, 100.0, 1000.0]))
    assert grid.shape == (2, 3)
    # Free-air gradient ~ -3.086e-6 (m/s^2)/m near the surface.
    assert (grid[0, 1] - grid[0, 0]) / 100.0 == pytest.approx(-3.086e-6, rel=2e-3)


def test_normal_gravity_rejects_mismatched_lengths():
    from gyrodrift import _core

    with pytest.raises(ValueError, match="lat_rad has 2 values but height_m has 1"):
        _core.normal_gravity(np.zeros(2), np.zeros(1))


def test_radii_of_curvature_come_from_the_core():
    lat = np.deg2rad(np.array([[0.0, 28.222], [60.0, 89.0]]))
    r_m, r_n = earth.radii_of_curvature(lat)
    assert r_m.shape == r_n.shape == (2, 2)
    a, f = earth.WGS84_A_M, earth.WGS84_F
    e2 = f * (2 - f)
    # Closed forms: at the equator R_M = a (1 - e^2), R_N = a; the formulas everywhere, to rounding.
    assert r_m[0, 0] == pytest.approx(a * (1 - e2), rel=1e-15) and r_n[0, 0] == pytest.approx(a, rel=1e-15)
    d = 1 - e2 * np.sin(lat) ** 2
    np.testing.assert_allclose(r_m, a * (1 - e2) / d**1.5, rtol=1e-14)
    np.testing.assert_allclose(r_n, a / np.sqrt(d), rtol=1e-14)
    assert earth.radii_of_curvature(0.5)[0].shape == ()
