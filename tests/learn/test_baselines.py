"""The physics inversion against the closed-form latitude error it inverts."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gyrodrift.learn.baselines import latitude_error_at, physics_inversion
from gyrodrift.runs.table import RunTable
from gyrodrift.units import HOUR


def test_reference_number_of_method_md():
    # 0.003 deg/h at 28.222 deg: latitude error at 12 h is 72.5 arcsec (method.md).
    assert abs(latitude_error_at(12 * HOUR, 0.003, 28.222) - 72.5) < 0.05


@settings(max_examples=50, deadline=None)
@given(drift=st.floats(-0.01, 0.01), lat0=st.floats(-70, 70))
def test_inversion_recovers_the_drift_of_the_closed_form(drift, lat0):
    err_arcsec = latitude_error_at(12 * HOUR, drift, lat0)
    runs = RunTable(
        run=np.array(["a"], dtype=object),
        lat_deg=np.array([lat0 + err_arcsec / 3600.0]),
        lat0_deg=np.array([lat0]),
        temp_min_c=np.array([20.0]),
        temp_max_c=np.array([21.0]),
        drift_deg_h=np.array([np.nan]),
    )
    np.testing.assert_allclose(physics_inversion(runs), [drift], rtol=1e-9, atol=1e-12)
