"""Hostile arrays and configs into the Rust core give `gyrodrift.errors.CoreError`, never a PanicException or a hang.

Each case asserts the exact package class of the core's error kind (`CoreSettingError`, `CoreShapeError`,
`CoreSampleError`, `CoreDivergedError`, `CoreIncompleteError`; a PanicException derives from BaseException, not
Exception, so ``pytest.raises(CoreError)`` would let it through as a failure) and that the message names the input.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gyrodrift import _core
from gyrodrift.errors import (
    CoreDivergedError,
    CoreError,
    CoreIncompleteError,
    CoreSampleError,
    CoreSettingError,
    CoreShapeError,
    InputError,
    OptionError,
)

G = 9.80665
RATE_HZ = 10.0
DT = 1.0 / RATE_HZ


def _aligner():
    return _core.Aligner(_core.AlignerConfig(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ, fine_s=320.0))


def _navigator():
    return _core.Navigator(
        _core.NavigatorConfig(
            lat_rad=0.5, lon_rad=0.0, height_m=0.0, pitch_rad=0.0, roll_rad=0.0, yaw_rad=0.0, rate_hz=RATE_HZ
        )
    )


def _static(n: int, force=(0.0, 0.0, G)) -> tuple[np.ndarray, np.ndarray]:
    dth = np.zeros((n, 3))
    dv = np.tile(np.asarray(force) * DT, (n, 1))
    return dth, dv


def test_five_g_horizontal_alignment_is_a_core_error():
    # Issue 8: _core.Aligner panicked on a 5 g horizontal specific force for 620 s at 10 Hz.
    al = _aligner()
    dth, dv = _static(6200, (5 * G, 0.0, G))
    with pytest.raises(CoreError, match="static base") as info:
        al.process(dth, dv)
    assert type(info.value) is CoreDivergedError
    assert info.value.key == "accel_bias_m_s2"
    assert f"at t = {info.value.t_s:g} s" in str(info.value) and 300.0 < info.value.t_s <= 620.0
    with pytest.raises(CoreDivergedError, match="static base"):
        al.result()


def _bad_arrays():
    """(label, dtheta, dv, expected key, expected class): arrays the core must refuse."""
    dth, dv = _static(50)
    nan = dth.copy()
    nan[7, 1] = np.nan
    inf = dv.copy()
    inf[3, 0] = np.inf
    huge = dv.copy()
    huge[0, 2] = 1e300
    return [
        ("nan", nan, dv, "dtheta_rad", CoreSampleError),
        ("inf", dth, inf, "dv_m_s", CoreSampleError),
        ("1e300", dth, huge, "dv_m_s", CoreSampleError),
        ("wrong columns", np.zeros((50, 4)), dv, "dtheta_rad", CoreShapeError),
        ("one-dimensional", np.zeros(150), dv, "dtheta_rad", CoreShapeError),
        ("three-dimensional", np.zeros((50, 3, 1)), dv, "dtheta_rad", CoreShapeError),
        ("rows differ", dth, dv[:-1], "dv_m_s", CoreShapeError),
        ("complex", dth.astype(complex), dv, "dtheta_rad", CoreShapeError),
        ("strings", np.full((50, 3), "x"), dv, "dtheta_rad", CoreShapeError),
        ("boolean", np.zeros((50, 3), dtype=bool), dv, "dtheta_rad", CoreShapeError),
        ("not an array", "abc", dv, "dtheta_rad", CoreShapeError),
        ("None", None, dv, "dtheta_rad", CoreShapeError),
        ("ragged list", [[0.0, 0.0], [0.0]], dv, "dtheta_rad", CoreShapeError),
    ]


@pytest.mark.parametrize("label,dth,dv,key,kind", _bad_arrays(), ids=[c[0] for c in _bad_arrays()])
@pytest.mark.parametrize("make", [_aligner, _navigator], ids=["aligner", "navigator"])
def test_bad_arrays_are_core_errors(make, label, dth, dv, key, kind):
    obj = make()
    with pytest.raises(CoreError) as info:
        obj.process(dth, dv)
    assert type(info.value) is kind
    assert info.value.key == key, str(info.value)
    if kind is CoreSampleError:
        assert info.value.index == {"nan": 7, "inf": 3, "1e300": 0}[label]
        assert f"sample {info.value.index}:" in str(info.value)
    assert key in str(info.value)
    assert obj.samples_done == 0


@pytest.mark.parametrize("make", [_aligner, _navigator], ids=["aligner", "navigator"])
def test_convertible_arrays_give_the_same_answer(make):
    # float32, integers (as float), non-contiguous and Fortran-ordered arrays are converted, not refused.
    dth, dv = _static(40)
    ref = make()
    ref.process(dth, dv)
    variants = [
        (dth.astype(np.float32), dv.astype(np.float32)),
        (np.zeros((40, 3), dtype=np.int64), dv),
        (np.zeros((40, 6))[:, ::2], np.repeat(dv, 2, axis=0)[::2]),
        (np.asfortranarray(dth), np.asfortranarray(dv)),
        (dth.tolist(), dv.tolist()),
    ]
    for a, b in variants:
        obj = make()
        obj.process(a, b)
        assert obj.samples_done == ref.samples_done == 40
    nav_a, nav_b = _navigator(), _navigator()
    out_a = nav_a.process(dth[:, :], dv, 10)
    out_b = nav_b.process(np.zeros((40, 6))[:, 1::2], dv.astype(np.float32).astype(np.float64), 10)
    np.testing.assert_array_equal(out_a["lat_rad"], out_b["lat_rad"])


def test_zero_rows_are_no_samples():
    # A zero-length chunk is legal when streaming: nothing happens, nothing is returned.
    nav = _navigator()
    out = nav.process(np.zeros((0, 3)), np.zeros((0, 3)), 1)
    assert len(out["t_s"]) == 0 and nav.samples_done == 0
    al = _aligner()
    assert al.process(np.zeros((0, 3)), np.zeros((0, 3))) == 0


def test_navigator_divergence_and_arguments():
    nav = _navigator()
    dth, dv = _static(36_000, (0.0, 90 * G, G))
    with pytest.raises(CoreDivergedError, match="left the Earth"):
        nav.process(dth, dv, 1000)
    nav = _navigator()
    for bad in (0, -3):
        with pytest.raises(CoreShapeError, match="decimation"):
            nav.process(*_static(3), bad)
    with pytest.raises(CoreShapeError, match="b_rad_s"):
        nav.set_gyro_bias([0.0, 0.0])
    with pytest.raises(CoreSettingError, match="gyro bias"):
        nav.set_gyro_bias([np.nan, 0.0, 0.0])
    with pytest.raises(CoreShapeError, match="b_m_s2"):
        nav.set_accel_bias("abc")


def _sim_config(**kw) -> _core.SimulatorConfig:
    base = dict(lat_rad=0.5, rate_hz=100.0, duration_s=10.0)
    base.update(kw)
    return _core.SimulatorConfig(**base)


@pytest.mark.parametrize(
    "kw,key",
    [
        (dict(lat_rad=float("nan")), "lat_rad"),
        (dict(lat_rad=1e300), "lat_rad"),
        (dict(height_m=float("inf")), "height_m"),
        (dict(rate_hz=1e308), "rate_hz"),
        (dict(duration_s=1e306), "duration_s"),
        (dict(duration_s=0.0), "duration_s"),
        (dict(gyro_bias_rad_s=[1e300, 0.0, 0.0]), "gyro_bias_rad_s"),
        (dict(rotation_scheme="reciprocating", reciprocating_span_rad=1e-300), "reciprocating_span_rad"),
        (dict(rotation_scheme="indexing", positions_rad=[0.0, 1e-300], dwell_s=0.0), "positions_rad"),
        (dict(rotation_scheme="continuous", rotation_rate_rad_s=1e300), "rotation_rate_rad_s"),
        (dict(temp_series_t_s=[0.0, 1.0], temp_series_c=[20.0]), "temp_series_c"),
        (dict(temp_series_t_s=[1.0, 0.0], temp_series_c=[20.0, 21.0]), "temp_series_t_s"),
    ],
)
def test_hostile_simulator_configs(kw, key):
    with pytest.raises(CoreError) as info:
        _core.ImuSimulator(_sim_config(**kw))
    assert type(info.value) is CoreSettingError
    assert info.value.key == key, str(info.value)


def test_simulator_chunk_sizes():
    sim = _core.ImuSimulator(_sim_config())
    for bad in (0, -1, 2**40):
        with pytest.raises(CoreSettingError, match="chunk"):
            sim.next_chunk(bad)
    assert len(sim.next_chunk(10**9 // 100)["t_s"]) == 1000
    assert sim.next_chunk(5) is None


def test_huge_aligner_and_navigator_configs():
    with pytest.raises(CoreSettingError, match="coarse_s"):
        _core.AlignerConfig(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ, coarse_s=1e300)
    with pytest.raises(CoreSettingError, match="latitude"):
        _core.NavigatorConfig(
            lat_rad=1.6, lon_rad=0.0, height_m=0.0, pitch_rad=0.0, roll_rad=0.0, yaw_rad=0.0, rate_hz=RATE_HZ
        )
    with pytest.raises(CoreSettingError, match="rate_hz"):
        _core.NavigatorConfig(
            lat_rad=0.5, lon_rad=0.0, height_m=0.0, pitch_rad=0.0, roll_rad=0.0, yaw_rad=0.0, rate_hz=1e308
        )
    with pytest.raises(CoreSettingError, match="vertical"):
        _core.NavigatorConfig(
            lat_rad=0.5, lon_rad=0.0, height_m=0.0, pitch_rad=0.0, roll_rad=0.0, yaw_rad=0.0, rate_hz=10, vertical="x"
        )
    with pytest.raises(CoreSettingError, match="rotation_scheme"):
        _sim_config(rotation_scheme="wobble")


def test_each_core_error_kind_is_its_own_class():
    # gyrodrift_core::error::CoreError's five kinds, each mapped once in the binding to its class; all stay a
    # CoreError (an InputError, a ValueError), and a bad setting is also an OptionError.
    for kind in (CoreSettingError, CoreShapeError, CoreSampleError, CoreDivergedError, CoreIncompleteError):
        assert issubclass(kind, CoreError) and issubclass(kind, InputError) and issubclass(kind, ValueError)
    assert issubclass(CoreSettingError, OptionError)
    assert not issubclass(CoreShapeError, OptionError)
    with pytest.raises(CoreSettingError) as setting:
        _core.SmootherConfig(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ, update_s=-1.0)
    assert setting.value.key == "update_s" and str(setting.value).startswith("update_s: ")
    al = _aligner()
    al.process(*_static(40))
    with pytest.raises(CoreIncompleteError) as incomplete:
        al.result()
    assert (incomplete.value.key, incomplete.value.done, incomplete.value.needed) == ("samples", 40, al.n_samples)
    assert str(incomplete.value) == f"alignment not complete: 40 of {al.n_samples} samples processed"
    sm = _core.Smoother(
        _core.SmootherConfig(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ, span_s=900.0, thermal=True)
    )
    with pytest.raises(CoreShapeError, match="temp_c"):
        sm.process(*_static(5), np.zeros(4))
    with pytest.raises(CoreIncompleteError):
        sm.result()


def test_the_filters_noise_priors_are_declared_once():
    # gyrodrift-core filter_prior: SensorNoise's default is the smoother's prior (read from the core); the aligner's
    # is twice that grade, with a 10 times tighter gyro bias prior (the reasons are in filter_prior's docs).
    from gyrodrift.procedure.noise import SensorNoise
    from gyrodrift.units import DEG_PER_H, MICRO_G

    noise = SensorNoise()
    site = dict(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ)
    smoother, aligner = _core.SmootherConfig(**site), _core.AlignerConfig(**site)
    assert smoother.gyro_arw_rad_rts == pytest.approx(noise.arw_rad_rts, rel=1e-15)
    assert smoother.accel_vrw_m_s_rts == pytest.approx(noise.vrw_m_s_rts, rel=1e-15)
    assert aligner.gyro_arw_rad_rts == pytest.approx(2 * noise.arw_rad_rts, rel=1e-15)
    assert aligner.accel_vrw_m_s_rts == pytest.approx(2 * noise.vrw_m_s_rts, rel=1e-15)
    assert smoother.gyro_bias_sigma_rad_s == pytest.approx([0.1 * DEG_PER_H] * 3, rel=1e-15)
    assert aligner.gyro_bias_sigma_rad_s == pytest.approx([0.01 * DEG_PER_H] * 3, rel=1e-15)
    assert smoother.accel_bias_sigma_m_s2 == aligner.accel_bias_sigma_m_s2 == pytest.approx([100 * MICRO_G] * 3)


def test_the_aligner_and_the_smoother_read_their_shared_filter_keywords_alike():
    # One FilterConfig (gyrodrift-core FilterSettings) under both configs: the same keywords, read by one helper.
    site = dict(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ)
    given = dict(
        coarse_s=120.0,
        update_s=5.0,
        att_sigma_rad=[1e-4, 2e-4, 3e-3],
        gyro_bias_sigma_rad_s=[1e-8, 2e-8, 3e-8],
        accel_bias_sigma_m_s2=[1e-4, 2e-4, 3e-4],
        gyro_arw_rad_rts=1e-6,
        accel_vrw_m_s_rts=1e-5,
        zupt_sigma_m_s=2e-3,
        history_s=100.0,
    )
    assert sorted(k for k in dir(_core.FilterConfig) if not k.startswith("_")) == sorted([*site, *given])
    for cls in (_core.AlignerConfig, _core.SmootherConfig):
        config, default = cls(**site, **given), cls(**site)
        assert isinstance(config, _core.FilterConfig)
        assert {k: getattr(config, k) for k in given} == given
        for key in given:  # None takes the config's own default
            assert getattr(cls(**site, **{key: None}), key) == getattr(default, key), key
        with pytest.raises(TypeError, match=rf"^{cls.__name__}\(\) got an unexpected keyword argument 'fine'$"):
            cls(**site, fine=1.0)
        with pytest.raises(TypeError, match="^argument 'update_s': "):
            cls(**site, update_s="1")
        with pytest.raises(CoreSettingError, match="^zupt_sigma_m_s: "):
            cls(**site, zupt_sigma_m_s=0.0)
    assert _core.AlignerConfig(**site).update_s == 1.0 and _core.SmootherConfig(**site).update_s == 10.0


def test_configs_resolve_the_core_defaults():
    # The defaults live in the core only; the typed configs show them resolved.
    c = _sim_config(rotation_scheme="reciprocating")
    assert c.rotation_rate_rad_s == pytest.approx(np.deg2rad(6.0), rel=1e-15)
    assert c.rotation_accel_rad_s2 == pytest.approx(np.deg2rad(100.0), rel=1e-15)
    assert c.reciprocating_span_rad == pytest.approx(2 * np.pi, rel=1e-15)
    assert (c.temp_start_c, c.temp_end_c, c.temp_tau_s, c.seed) == (20.0, 20.0, 3600.0, 0)
    a = _core.AlignerConfig(lat_rad=0.5, lon_rad=0.0, height_m=0.0, rate_hz=RATE_HZ, coarse_s=600.0)
    assert (a.coarse_s, a.fine_s, a.update_s, a.att_sigma_rad) == (600.0, 13800.0, 1.0, None)
    n = _core.NavigatorConfig(
        lat_rad=0.5, lon_rad=0.0, height_m=0.0, pitch_rad=0.0, roll_rad=0.0, yaw_rad=0.0, rate_hz=RATE_HZ
    )
    assert (n.vertical, n.vel_enu_m_s) == ("fixed", [0.0, 0.0, 0.0])


def test_fill_into_matches_next_chunk_and_refuses_bad_buffers():
    cfg = _sim_config(rotation_scheme="reciprocating", gyro_arw_rad_rts=1e-5, duration_s=25.0)
    ref = _core.ImuSimulator(cfg).next_chunk(10**6)
    keys = list(ref)
    out = {k: np.zeros((700, 3) if ref[k].ndim == 2 else 700) for k in keys}
    sim = _core.ImuSimulator(cfg)
    got = {k: [] for k in keys}
    while (m := sim.fill_into(out)) > 0:
        for k in keys:
            got[k].append(out[k][:m].copy())
    for k in keys:
        np.testing.assert_array_equal(np.concatenate(got[k]), ref[k])
    sim = _core.ImuSimulator(cfg)
    bad = [
        ("dv_m_s", dict(out, dv_m_s=np.zeros((10, 3)))),
        ("temp_c", dict(out, temp_c=np.zeros(700, dtype=np.float32))),
        ("yaw_rad", dict(out, yaw_rad=np.zeros(1400)[::2])),
        ("dtheta_rad", dict(out, dtheta_rad=np.zeros((700, 4)))),
        ("pitch_rad", {k: v for k, v in out.items() if k != "pitch_rad"}),
        ("roll_rad", dict(out, roll_rad=out["t_s"])),
    ]
    for key, arrays in bad:
        with pytest.raises(CoreError) as info:
            sim.fill_into(arrays)
        assert type(info.value) is CoreShapeError and info.value.key == key, str(info.value)
    assert sim.samples_done == 0


def test_the_type_stub_names_what_the_extension_has():
    import re
    from pathlib import Path

    stub = (Path(_core.__file__).parent / "_core.pyi").read_text()
    names = re.findall(r"^(?:class |def )?([A-Za-z_][A-Za-z_0-9]*)(?:: Final|\(|:)", stub, re.M)
    names = [n for n in names if n not in ("ArrayLike", "FloatArray", "FilterKeywords")]  # typing only
    assert len(names) > 25
    assert [n for n in names if not hasattr(_core, n)] == []
    classes = ("SimulatorConfig", "NavigatorConfig", "FilterConfig", "AlignerConfig", "SmootherConfig", "ImuSimulator")
    for cls in (*classes, "Navigator", "Aligner", "Smoother"):
        block = re.split(rf"^class {cls}\b.*:$", stub, flags=re.M)[1].split("\nclass ")[0]
        for attr in re.findall(r"def ([a-z_0-9]+)\(", block):
            assert hasattr(getattr(_core, cls), attr), f"{cls}.{attr}"


_DTYPES = [np.float64, np.float32, np.int64, np.int8, np.uint16, np.complex128, np.bool_]


@st.composite
def _hostile_arrays(draw):
    rows = draw(st.integers(0, 12))
    cols = draw(st.sampled_from([3, 3, 3, 1, 4]))
    dtype = draw(st.sampled_from(_DTYPES))
    values = draw(
        st.lists(
            st.sampled_from([0.0, 1e-3, -2e-3, 0.0981, 1e300, -1e300, np.nan, np.inf, 5.0]),
            min_size=rows * cols,
            max_size=rows * cols,
        )
    )
    with np.errstate(invalid="ignore", over="ignore"):
        a = np.asarray(values, dtype=float).reshape(rows, cols).astype(dtype)
    if draw(st.booleans()) and rows > 1:
        a = a[::2]
    if draw(st.booleans()):
        a = np.asfortranarray(a)
    return a


@settings(max_examples=60, deadline=None)
@given(dth=_hostile_arrays(), dv=_hostile_arrays(), which=st.sampled_from(["aligner", "navigator"]))
def test_any_array_gives_a_result_or_a_core_error(dth, dv, which):
    obj = _aligner() if which == "aligner" else _navigator()
    try:
        obj.process(dth, dv)
    except CoreError:
        assert obj.samples_done == 0
        return
    # Accepted: real numbers of shape (n, 3), equal rows, finite and within the sensor limits.
    assert dth.shape == dv.shape and dth.ndim == 2 and dth.shape[1] == 3
    assert dth.dtype.kind in "fiu" and dv.dtype.kind in "fiu"
    assert obj.samples_done == len(dth)
