"""The core's fast pass over a block of log rows (`_core.check_rows`) against numpy's reading of the same checks
(the reader's former vectorised pass): the same verdict on clean blocks and on blocks with one fault of each
kind, either sensor layout, and the increments it gives are the values times the scale, to the last bit."""

from __future__ import annotations

import numpy as np
import pytest

from gyrodrift import _core
from gyrodrift.errors import CoreShapeError

STEP, TOL = 0.1, 0.001
LIMITS = {"max_gyro": 0.02, "max_accel": 3.0, "temperature_c": (-60.0, 150.0), "height_m": (-1000.0, 20000.0)}


def numpy_clean(t, gyro, acc, temp, truth, href, prev_t) -> bool:
    full = t if prev_t is None else np.concatenate([[prev_t], t])
    low, high = LIMITS["temperature_c"]
    return bool(
        np.isfinite(t).all()
        and (np.abs(np.diff(full) - STEP) <= TOL).all()
        and (np.abs(gyro) <= LIMITS["max_gyro"]).all()
        and (np.abs(acc) <= LIMITS["max_accel"]).all()
        and (temp is None or ((temp >= low) & (temp <= high)).all())
        and all(np.isfinite(c).all() for c in truth)
        and (href is None or ((href >= LIMITS["height_m"][0]) & (href <= LIMITS["height_m"][1])).all())
    )


def block(rng: np.random.Generator, n: int):
    t = 100.0 + STEP * np.arange(n) + rng.uniform(-0.25, 0.25, n) * TOL  # steps within TOL / 2: clean by a margin
    gyro = rng.uniform(-1, 1, (n, 3)) * LIMITS["max_gyro"] * 0.99
    acc = rng.uniform(-1, 1, (n, 3)) * LIMITS["max_accel"] * 0.99
    return t, gyro, acc, rng.uniform(-50, 140, n), [rng.normal(size=n) for _ in range(3)], rng.uniform(0, 500, n)


FAULTS = {
    "none": lambda b, i, rng: None,
    "time NaN": lambda b, i, rng: b[0].__setitem__(i, np.nan),
    "gap": lambda b, i, rng: b[0].__setitem__(slice(i, None), b[0][i:] + 3 * TOL),
    "duplicate": lambda b, i, rng: b[0].__setitem__(i, b[0][i - 1] if i else b[0][0]),
    "gyro over": lambda b, i, rng: b[1].__setitem__((i, rng.integers(3)), 1.5 * LIMITS["max_gyro"]),
    "gyro NaN": lambda b, i, rng: b[1].__setitem__((i, rng.integers(3)), np.nan),
    "accel inf": lambda b, i, rng: b[2].__setitem__((i, rng.integers(3)), -np.inf),
    "temperature kelvin": lambda b, i, rng: b[3].__setitem__(i, 298.15),
    "temperature NaN": lambda b, i, rng: b[3].__setitem__(i, np.nan),
    "truth NaN": lambda b, i, rng: b[4][rng.integers(3)].__setitem__(i, np.nan),
    "height low": lambda b, i, rng: b[5].__setitem__(i, -1500.0),
}


@pytest.mark.parametrize("fault", list(FAULTS))
@pytest.mark.parametrize("layout", ["columns", "rows"])
def test_the_core_and_numpy_agree_on_every_kind_of_fault(fault, layout):
    rng = np.random.default_rng([list(FAULTS).index(fault), layout == "rows"])
    for trial in range(20):
        n = int(rng.integers(1, 300))
        b = block(rng, n)
        FAULTS[fault](b, int(rng.integers(n)), rng)
        t, gyro, acc, temp, truth, href = b
        prev_t = None if trial % 3 == 0 else float(t[0] - STEP)
        with_optional = trial % 2 == 0
        args = (tuple(gyro.T), tuple(acc.T)) if layout == "columns" else (gyro, acc)
        scale = 1.0 if trial % 4 < 2 else 0.01
        clean, g, a = _core.check_rows(
            t,
            *args,
            temperature=temp if with_optional else None,
            truth=truth if with_optional else (),
            ref_height=href if with_optional else None,
            previous_t=prev_t,
            step_s=STEP,
            step_tolerance_s=TOL,
            scale=scale,
            **LIMITS,
        )
        expected = numpy_clean(t, gyro, acc, *((temp, truth, href) if with_optional else (None, [], None)), prev_t)
        assert clean == expected, (fault, layout, trial)
        if clean and not (layout == "rows" and scale == 1.0):
            assert g is not None and a is not None and g.flags.c_contiguous and g.shape == (n, 3)
            np.testing.assert_array_equal(g, gyro * scale)  # one product per value: exact
            np.testing.assert_array_equal(a, acc * scale)
        elif clean:
            assert g is None and a is None  # the (n, 3) arrays as they are


def test_a_column_of_another_length_is_a_shape_error():
    rng = np.random.default_rng(1)
    t, gyro, acc, temp, truth, href = block(rng, 10)
    with pytest.raises(CoreShapeError, match="temperature"):
        _core.check_rows(
            t, gyro, acc, temperature=temp[:9], truth=(), ref_height=None, previous_t=None, step_s=STEP,
            step_tolerance_s=TOL, scale=1.0, **LIMITS,
        )  # fmt: skip
