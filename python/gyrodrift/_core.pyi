"""Type stubs of the Rust extension `gyrodrift._core` (crates/gyrodrift-py; docs/ins-binding-contract.md and
docs/alignment-contract.md). SI units everywhere. Every refusal is a `gyrodrift.errors.CoreError`, the subclass of
the core's error kind (`CoreSettingError`, `CoreShapeError`, `CoreSampleError`, `CoreDivergedError`,
`CoreIncompleteError`; its `key` attribute names the setting or input). Keyword defaults of None take the core's
default (documented in the contracts; each config shows it resolved as an attribute)."""

from collections.abc import Sequence
from typing import Any, ClassVar, Final, TypedDict, Unpack

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]

# WGS-84 (gyrodrift-core `earth`)
WGS84_A_M: Final[float]
WGS84_F: Final[float]
OMEGA_IE_RAD_S: Final[float]
NMI_M: Final[float]
STANDARD_GRAVITY_M_S2: Final[float]

# The smoother's default noise (gyrodrift-core `filter_prior`): `procedure.noise.SensorNoise`'s defaults.
SMOOTHER_GYRO_ARW_DEG_RTH: Final[float]
SMOOTHER_ACCEL_VRW_UG_RTHZ: Final[float]

# Limits of the shared quantities, in the units their names carry (gyrodrift-core `limits`, `turntable`,
# `simulator`); scenario files and the core refuse the same values.
MAX_LAT_DEG: Final[float]
MAX_LON_DEG: Final[float]
MIN_HEIGHT_M: Final[float]
MAX_HEIGHT_M: Final[float]
MIN_RATE_HZ: Final[float]
MAX_RATE_HZ: Final[float]
MAX_DURATION_S: Final[float]
MAX_PITCH_DEG: Final[float]
MAX_ROLL_DEG: Final[float]
MAX_YAW_DEG: Final[float]
MAX_ANGULAR_RATE_DEG_S: Final[float]
MAX_SPECIFIC_FORCE_G: Final[float]
MAX_TABLE_RATE_DEG_S: Final[float]
MAX_TABLE_ACCEL_DEG_S2: Final[float]
MAX_SPAN_DEG: Final[float]
MIN_SAMPLES_PER_PERIOD: Final[float]
MAX_CHUNK_SAMPLES: Final[int]
MAX_INDEX_POSITIONS: Final[int]
MAX_VEHICLE_SPEED_M_S: Final[float]
MAX_VEHICLE_ACCEL_M_S2: Final[float]
MAX_VEHICLE_CLIMB_RATE_M_S: Final[float]
MAX_VEHICLE_YAW_RATE_DEG_S: Final[float]

def normal_gravity(lat_rad: FloatArray, height_m: FloatArray) -> FloatArray: ...
def meridian_radius(lat_rad: FloatArray) -> FloatArray: ...
def transverse_radius(lat_rad: FloatArray) -> FloatArray: ...
def balanced_reciprocating_span_rad(
    rotation_rate_rad_s: float, rotation_accel_rad_s2: float, dwell_s: float = 0.0, turns: int = 1
) -> float: ...

class SimulatorConfig:
    """A validated simulated run (the keywords of docs/ins-binding-contract.md)."""

    def __init__(
        self,
        *,
        lat_rad: float,
        rate_hz: float,
        duration_s: float,
        lon_rad: float | None = None,
        height_m: float | None = None,
        seed: int | None = None,
        pitch_rad: float | None = None,
        roll_rad: float | None = None,
        yaw_rad: float | None = None,
        rotation_scheme: str | None = None,
        rotation_rate_rad_s: float | None = None,
        rotation_accel_rad_s2: float | None = None,
        reciprocating_span_rad: float | None = None,
        reciprocating_balanced: bool = False,
        positions_rad: list[float] | None = None,
        dwell_s: float | None = None,
        gyro_bias_rad_s: list[float] | None = None,
        gyro_arw_rad_rts: float | None = None,
        gyro_bias_instability_rad_s: float | None = None,
        gyro_correlation_s: float | None = None,
        gyro_rrw_rad_s_rts: float | None = None,
        gyro_scale: list[float] | None = None,
        gyro_misalignment_rad: list[float] | None = None,
        accel_bias_m_s2: list[float] | None = None,
        accel_vrw_m_s_rts: float | None = None,
        accel_scale: list[float] | None = None,
        temp_start_c: float | None = None,
        temp_end_c: float | None = None,
        temp_tau_s: float | None = None,
        temp_swing_amplitude_c: float | None = None,
        temp_swing_period_s: float | None = None,
        temp_swing_phase_rad: float | None = None,
        temp_series_t_s: list[float] | None = None,
        temp_series_c: list[float] | None = None,
        drift_t0_c: float | None = None,
        drift_k1_rad_s_per_c: float | None = None,
        drift_k2_rad_s_per_c2: float | None = None,
        drift_k3_rad_s_per_c_per_s: float | None = None,
        trajectory_start_s: float | None = None,
        trajectory_segments: Sequence[tuple[float, float, float, float]] | None = None,
        trajectory_repeat: bool = False,
    ) -> None: ...
    @property
    def lat_rad(self) -> float: ...
    @property
    def lon_rad(self) -> float: ...
    @property
    def height_m(self) -> float: ...
    @property
    def rate_hz(self) -> float: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def pitch_rad(self) -> float: ...
    @property
    def roll_rad(self) -> float: ...
    @property
    def yaw_rad(self) -> float: ...
    @property
    def rotation_scheme(self) -> str: ...
    @property
    def rotation_rate_rad_s(self) -> float: ...
    @property
    def rotation_accel_rad_s2(self) -> float: ...
    @property
    def reciprocating_span_rad(self) -> float: ...
    @property
    def reciprocating_balanced(self) -> bool: ...
    @property
    def positions_rad(self) -> list[float]: ...
    @property
    def dwell_s(self) -> float: ...
    @property
    def gyro_bias_rad_s(self) -> list[float]: ...
    @property
    def gyro_arw_rad_rts(self) -> float: ...
    @property
    def gyro_bias_instability_rad_s(self) -> float: ...
    @property
    def gyro_correlation_s(self) -> float: ...
    @property
    def gyro_rrw_rad_s_rts(self) -> float: ...
    @property
    def gyro_scale(self) -> list[float]: ...
    @property
    def gyro_misalignment_rad(self) -> list[float]: ...
    @property
    def accel_bias_m_s2(self) -> list[float]: ...
    @property
    def accel_vrw_m_s_rts(self) -> float: ...
    @property
    def accel_scale(self) -> list[float]: ...
    @property
    def temp_start_c(self) -> float: ...
    @property
    def temp_end_c(self) -> float: ...
    @property
    def temp_tau_s(self) -> float: ...
    @property
    def temp_swing_amplitude_c(self) -> float: ...
    @property
    def temp_swing_period_s(self) -> float: ...
    @property
    def temp_swing_phase_rad(self) -> float: ...
    @property
    def temp_series_t_s(self) -> list[float] | None: ...
    @property
    def temp_series_c(self) -> list[float] | None: ...
    @property
    def drift_t0_c(self) -> float: ...
    @property
    def drift_k1_rad_s_per_c(self) -> float: ...
    @property
    def drift_k2_rad_s_per_c2(self) -> float: ...
    @property
    def drift_k3_rad_s_per_c_per_s(self) -> float: ...
    @property
    def trajectory_start_s(self) -> float | None: ...
    @property
    def trajectory_segments(self) -> list[tuple[float, float, float, float]] | None: ...
    @property
    def trajectory_repeat(self) -> bool: ...

class NavigatorConfig:
    """A validated initial state of the navigator."""

    def __init__(
        self,
        *,
        lat_rad: float,
        lon_rad: float,
        height_m: float,
        pitch_rad: float,
        roll_rad: float,
        yaw_rad: float,
        rate_hz: float,
        vel_enu_m_s: list[float] | None = None,
        vertical: str | None = None,
    ) -> None: ...
    @property
    def lat_rad(self) -> float: ...
    @property
    def lon_rad(self) -> float: ...
    @property
    def height_m(self) -> float: ...
    @property
    def vel_enu_m_s(self) -> list[float]: ...
    @property
    def pitch_rad(self) -> float: ...
    @property
    def roll_rad(self) -> float: ...
    @property
    def yaw_rad(self) -> float: ...
    @property
    def rate_hz(self) -> float: ...
    @property
    def vertical(self) -> str: ...

class FilterKeywords(TypedDict, total=False):
    """The ``**filter`` keywords of `AlignerConfig` and `SmootherConfig` (SI; None or left out: the config's default,
    gyrodrift-core `FilterSettings::aligner` or `FilterSettings::smoother`, whose module `filter_prior` says why they
    differ). Typing only: not in the extension."""

    coarse_s: float | None
    update_s: float | None
    att_sigma_rad: Sequence[float] | None
    gyro_bias_sigma_rad_s: Sequence[float] | None
    accel_bias_sigma_m_s2: Sequence[float] | None
    gyro_arw_rad_rts: float | None
    accel_vrw_m_s_rts: float | None
    zupt_sigma_m_s: float | None
    history_s: float | None

class FilterConfig:
    """What `AlignerConfig` and `SmootherConfig` share, resolved: the static site, the sample rate and the filter
    settings (`FilterKeywords`). The base class of both; not built on its own."""

    @property
    def lat_rad(self) -> float: ...
    @property
    def lon_rad(self) -> float: ...
    @property
    def height_m(self) -> float: ...
    @property
    def rate_hz(self) -> float: ...
    @property
    def coarse_s(self) -> float: ...
    @property
    def update_s(self) -> float: ...
    @property
    def att_sigma_rad(self) -> list[float] | None: ...
    @property
    def gyro_bias_sigma_rad_s(self) -> list[float]: ...
    @property
    def accel_bias_sigma_m_s2(self) -> list[float]: ...
    @property
    def gyro_arw_rad_rts(self) -> float: ...
    @property
    def accel_vrw_m_s_rts(self) -> float: ...
    @property
    def zupt_sigma_m_s(self) -> float: ...
    @property
    def history_s(self) -> float: ...

class AlignerConfig(FilterConfig):
    """Validated settings of a static-base alignment (docs/alignment-contract.md)."""

    def __init__(
        self,
        *,
        lat_rad: float,
        lon_rad: float,
        height_m: float,
        rate_hz: float,
        fine_s: float | None = None,
        **filter: Unpack[FilterKeywords],
    ) -> None: ...
    @property
    def fine_s(self) -> float: ...

class ImuSimulator:
    def __init__(self, config: SimulatorConfig) -> None: ...
    @property
    def n_samples(self) -> int: ...
    @property
    def samples_done(self) -> int: ...
    @property
    def modulation_residual(self) -> float: ...
    @property
    def reciprocating_span_rad(self) -> float | None: ...
    def next_chunk(self, n: int) -> dict[str, FloatArray] | None: ...
    def fill_into(self, out: dict[str, FloatArray]) -> int: ...

class Navigator:
    def __init__(self, config: NavigatorConfig) -> None: ...
    @property
    def samples_done(self) -> int: ...
    def set_gyro_bias(self, b_rad_s: ArrayLike) -> None: ...
    def set_accel_bias(self, b_m_s2: ArrayLike) -> None: ...
    def set_reference_height(self, height_m: float) -> None: ...
    @property
    def reference_height_m(self) -> float: ...
    def process(
        self,
        dtheta_rad: ArrayLike,
        dv_m_s: ArrayLike,
        decimation: int = 1,
        reference_height_m: ArrayLike | None = None,
        axial_bias_rad_s: ArrayLike | None = None,
    ) -> dict[str, FloatArray]: ...
    def state(self) -> dict[str, Any]: ...

class Aligner:
    STATE_NAMES: ClassVar[list[str]]
    def __init__(self, config: AlignerConfig) -> None: ...
    @property
    def done(self) -> bool: ...
    @property
    def samples_done(self) -> int: ...
    @property
    def n_samples(self) -> int: ...
    def process(self, dtheta_rad: ArrayLike, dv_m_s: ArrayLike) -> int: ...
    def result(self) -> dict[str, Any]: ...

class SmootherConfig(FilterConfig):
    """Validated settings of the full-information smoother (gyrodrift-core `smoother`; docs/identification.md)."""

    def __init__(
        self,
        *,
        lat_rad: float,
        lon_rad: float,
        height_m: float,
        rate_hz: float,
        span_s: float | None = None,
        gyro_bias_instability_rad_s: float | None = None,
        gyro_correlation_s: float | None = None,
        gyro_rrw_rad_s_rts: float | None = None,
        position_sigma_m: float | None = None,
        thermal: bool | None = None,
        thermal_sigma_rad_s_per_c: float | None = None,
        temp_ref_c: float | None = None,
        thermal_min_range_c: float | None = None,
        **filter: Unpack[FilterKeywords],
    ) -> None: ...
    @property
    def span_s(self) -> float: ...
    @property
    def gyro_bias_instability_rad_s(self) -> float: ...
    @property
    def gyro_correlation_s(self) -> float: ...
    @property
    def gyro_rrw_rad_s_rts(self) -> float: ...
    @property
    def position_sigma_m(self) -> float: ...
    @property
    def thermal(self) -> bool: ...
    @property
    def thermal_sigma_rad_s_per_c(self) -> float: ...
    @property
    def temp_ref_c(self) -> float | None: ...
    @property
    def thermal_min_range_c(self) -> float: ...
    @property
    def state_names(self) -> list[str]: ...

class Smoother:
    def __init__(self, config: SmootherConfig) -> None: ...
    @property
    def done(self) -> bool: ...
    @property
    def samples_done(self) -> int: ...
    @property
    def n_samples(self) -> int: ...
    def process(self, dtheta_rad: ArrayLike, dv_m_s: ArrayLike, temp_c: ArrayLike | None = None) -> int: ...
    def result(self) -> dict[str, Any]: ...

class FreeNavigationConfig:
    """A free navigation propagated by covariance alone (the settings `label_sigma` and `mission_covariance` take;
    checked by the function that takes it)."""

    def __init__(
        self,
        *,
        lat_rad: float,
        height_m: float,
        span_s: float,
        step_s: float,
        gyro_arw_rad_rts: float,
        accel_vrw_m_s_rts: float,
        att_sigma_rad: Sequence[float],
        vel_sigma_m_s: float,
    ) -> None: ...

def label_sigma(
    navigation: FreeNavigationConfig,
    *,
    rms: bool,
    gyro_bias_instability_rad_s: float = ...,
    gyro_correlation_s: float = ...,
    gyro_rrw_rad_s_rts: float = ...,
    rrw_start_s: float = ...,
    alignment: SimulatorConfig | None = ...,
    alignment_end_s: float = ...,
    coarse_s: float = ...,
) -> dict[str, Any]: ...
def check_rows(
    t: npt.ArrayLike,
    gyro: npt.ArrayLike | tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike],
    accel: npt.ArrayLike | tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike],
    *,
    temperature: npt.ArrayLike | None,
    truth: Sequence[npt.ArrayLike],
    ref_height: npt.ArrayLike | None,
    previous_t: float | None,
    step_s: float,
    step_tolerance_s: float,
    max_gyro: float,
    max_accel: float,
    temperature_c: tuple[float, float],
    height_m: tuple[float, float],
    scale: float,
) -> tuple[bool, FloatArray | None, FloatArray | None]: ...
def drift_std_curve(
    smoother_config: SmootherConfig,
    simulator_config: SimulatorConfig,
    spans_s: list[float],
    *,
    mission_start_s: float,
    mission_s: float,
) -> dict[str, Any]: ...
def mission_covariance(navigation: FreeNavigationConfig) -> dict[str, Any]: ...
