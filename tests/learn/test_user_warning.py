"""Issue 22: a warning raised inside a fit names the user's line, not scikit-learn's or gyrodrift's."""

import warnings

import pytest

from gyrodrift.runs.datasets import load_paper


def _caught(fit):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit()
    return caught


def test_search_bound_warning_through_the_pipeline_names_this_file():
    from gyrodrift.learn.drift_model import make_drift_model
    from gyrodrift.learn.tuning import SearchBoundWarning

    model = make_drift_model(method="grid", grid_size=5, bounds=((1.0, 2.0), (0.5, 0.6)))
    caught = [w for w in _caught(lambda: model.fit(load_paper().train)) if w.category is SearchBoundWarning]
    assert caught, "the search box edge was not warned"
    assert {w.filename for w in caught} == {__file__}


def test_ill_conditioned_warning_names_this_file():
    import numpy as np

    from gyrodrift.learn.lssvm_system import IllConditionedWarning, lssvr_solve

    caught = _caught(lambda: lssvr_solve(np.diag([1.0, 0.0, 0.0]), np.array([1.0, 2.0, 4.0]), 1e14))
    assert [w.category for w in caught] == [IllConditionedWarning]
    assert caught[0].filename == __file__


def test_warn_user_from_a_user_function_names_its_line():
    from gyrodrift.learn.user_warning import warn_user

    with pytest.warns(UserWarning, match="here") as record:
        line = _line_of_next_call()
        warn_user("here", UserWarning)
    assert (record[0].filename, record[0].lineno) == (__file__, line)


def _line_of_next_call():
    import sys

    return sys._getframe(1).f_lineno + 1
