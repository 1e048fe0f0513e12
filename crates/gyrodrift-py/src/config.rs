//! Typed, validated configurations of the core objects: `SimulatorConfig`, `NavigatorConfig`, `AlignerConfig` and
//! the `FilterConfig` it shares with `SmootherConfig`.
//! Keyword-only constructors (SI names); an omitted keyword (or None) takes the core's default, which lives only
//! in gyrodrift-core. Each class validates at construction (a `gyrodrift.errors.CoreError` naming the key) and
//! exposes every resolved value as a read-only attribute.

use super::core_err;
use gyrodrift_core::alignment::AlignerConfig as CoreAlignerConfig;
use gyrodrift_core::attitude::Euler;
use gyrodrift_core::filter_prior::FilterSettings;
use gyrodrift_core::imu_error::ImuErrorParams;
use gyrodrift_core::simulator::ImuSimulatorConfig;
use gyrodrift_core::strapdown::{NavigatorConfig as CoreNavigatorConfig, Vertical};
use gyrodrift_core::temperature::{DailySwing, TemperatureProfile, DEFAULT_TAU_S, DEFAULT_TEMP_C};
use gyrodrift_core::trajectory::{Segment, TrajectoryConfig};
use gyrodrift_core::turntable::{
    default_indexing_positions, scheme_from_settings, RotationScheme, DEFAULT_RECIPROCATING_SPAN_RAD,
    DEFAULT_TABLE_ACCEL_RAD_S2, DEFAULT_TABLE_RATE_RAD_S,
};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Everything that defines a simulated static run (SI; docs/ins-binding-contract.md).
#[pyclass(module = "gyrodrift._core", frozen)]
pub struct SimulatorConfig {
    pub(crate) inner: ImuSimulatorConfig,
    #[pyo3(get)]
    lat_rad: f64,
    #[pyo3(get)]
    lon_rad: f64,
    #[pyo3(get)]
    height_m: f64,
    #[pyo3(get)]
    rate_hz: f64,
    #[pyo3(get)]
    duration_s: f64,
    #[pyo3(get)]
    seed: u64,
    #[pyo3(get)]
    pitch_rad: f64,
    #[pyo3(get)]
    roll_rad: f64,
    #[pyo3(get)]
    yaw_rad: f64,
    #[pyo3(get)]
    rotation_scheme: String,
    #[pyo3(get)]
    rotation_rate_rad_s: f64,
    #[pyo3(get)]
    rotation_accel_rad_s2: f64,
    #[pyo3(get)]
    reciprocating_span_rad: f64,
    #[pyo3(get)]
    reciprocating_balanced: bool,
    #[pyo3(get)]
    positions_rad: Vec<f64>,
    #[pyo3(get)]
    dwell_s: f64,
    #[pyo3(get)]
    gyro_bias_rad_s: [f64; 3],
    #[pyo3(get)]
    gyro_arw_rad_rts: f64,
    #[pyo3(get)]
    gyro_bias_instability_rad_s: f64,
    #[pyo3(get)]
    gyro_correlation_s: f64,
    #[pyo3(get)]
    gyro_rrw_rad_s_rts: f64,
    #[pyo3(get)]
    gyro_scale: [f64; 3],
    #[pyo3(get)]
    gyro_misalignment_rad: [f64; 6],
    #[pyo3(get)]
    accel_bias_m_s2: [f64; 3],
    #[pyo3(get)]
    accel_vrw_m_s_rts: f64,
    #[pyo3(get)]
    accel_scale: [f64; 3],
    #[pyo3(get)]
    temp_start_c: f64,
    #[pyo3(get)]
    temp_end_c: f64,
    #[pyo3(get)]
    temp_tau_s: f64,
    #[pyo3(get)]
    temp_swing_amplitude_c: f64,
    #[pyo3(get)]
    temp_swing_period_s: f64,
    #[pyo3(get)]
    temp_swing_phase_rad: f64,
    #[pyo3(get)]
    temp_series_t_s: Option<Vec<f64>>,
    #[pyo3(get)]
    temp_series_c: Option<Vec<f64>>,
    #[pyo3(get)]
    drift_t0_c: f64,
    #[pyo3(get)]
    drift_k1_rad_s_per_c: f64,
    #[pyo3(get)]
    drift_k2_rad_s_per_c2: f64,
    #[pyo3(get)]
    drift_k3_rad_s_per_c_per_s: f64,
    /// Moving base (None: static): the static period before the drive [s].
    #[pyo3(get)]
    trajectory_start_s: Option<f64>,
    /// Moving base: the route's segments (duration [s], acceleration [m/s^2], yaw rate [rad/s], climb [m]).
    #[pyo3(get)]
    trajectory_segments: Option<Vec<(f64, f64, f64, f64)>>,
    /// Moving base: the segments are cycled until the end of the run.
    #[pyo3(get)]
    trajectory_repeat: bool,
}

#[pymethods]
impl SimulatorConfig {
    #[new]
    #[pyo3(signature = (
        *, lat_rad, rate_hz, duration_s, lon_rad = None, height_m = None, seed = None, pitch_rad = None,
        roll_rad = None, yaw_rad = None, rotation_scheme = None, rotation_rate_rad_s = None,
        rotation_accel_rad_s2 = None, reciprocating_span_rad = None, reciprocating_balanced = false,
        positions_rad = None, dwell_s = None, gyro_bias_rad_s = None, gyro_arw_rad_rts = None,
        gyro_bias_instability_rad_s = None, gyro_correlation_s = None, gyro_rrw_rad_s_rts = None,
        gyro_scale = None, gyro_misalignment_rad = None, accel_bias_m_s2 = None, accel_vrw_m_s_rts = None,
        accel_scale = None, temp_start_c = None, temp_end_c = None, temp_tau_s = None, temp_swing_amplitude_c = None,
        temp_swing_period_s = None, temp_swing_phase_rad = None, temp_series_t_s = None, temp_series_c = None, drift_t0_c = None, drift_k1_rad_s_per_c = None, drift_k2_rad_s_per_c2 = None,
        drift_k3_rad_s_per_c_per_s = None, trajectory_start_s = None, trajectory_segments = None,
        trajectory_repeat = false
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        lat_rad: f64,
        rate_hz: f64,
        duration_s: f64,
        lon_rad: Option<f64>,
        height_m: Option<f64>,
        seed: Option<u64>,
        pitch_rad: Option<f64>,
        roll_rad: Option<f64>,
        yaw_rad: Option<f64>,
        rotation_scheme: Option<String>,
        rotation_rate_rad_s: Option<f64>,
        rotation_accel_rad_s2: Option<f64>,
        reciprocating_span_rad: Option<f64>,
        reciprocating_balanced: bool,
        positions_rad: Option<Vec<f64>>,
        dwell_s: Option<f64>,
        gyro_bias_rad_s: Option<[f64; 3]>,
        gyro_arw_rad_rts: Option<f64>,
        gyro_bias_instability_rad_s: Option<f64>,
        gyro_correlation_s: Option<f64>,
        gyro_rrw_rad_s_rts: Option<f64>,
        gyro_scale: Option<[f64; 3]>,
        gyro_misalignment_rad: Option<[f64; 6]>,
        accel_bias_m_s2: Option<[f64; 3]>,
        accel_vrw_m_s_rts: Option<f64>,
        accel_scale: Option<[f64; 3]>,
        temp_start_c: Option<f64>,
        temp_end_c: Option<f64>,
        temp_tau_s: Option<f64>,
        temp_swing_amplitude_c: Option<f64>,
        temp_swing_period_s: Option<f64>,
        temp_swing_phase_rad: Option<f64>,
        temp_series_t_s: Option<Vec<f64>>,
        temp_series_c: Option<Vec<f64>>,
        drift_t0_c: Option<f64>,
        drift_k1_rad_s_per_c: Option<f64>,
        drift_k2_rad_s_per_c2: Option<f64>,
        drift_k3_rad_s_per_c_per_s: Option<f64>,
        trajectory_start_s: Option<f64>,
        trajectory_segments: Option<Vec<(f64, f64, f64, f64)>>,
        trajectory_repeat: bool,
    ) -> PyResult<Self> {
        let d = ImuSimulatorConfig::default();
        let d0 = ImuErrorParams::default();
        let scheme_name = rotation_scheme.unwrap_or_else(|| "none".to_string());
        let scheme = scheme_from_settings(
            &scheme_name,
            rotation_rate_rad_s,
            rotation_accel_rad_s2,
            reciprocating_span_rad,
            reciprocating_balanced,
            positions_rad.clone(),
            dwell_s,
        )
        .map_err(core_err)?;
        let temperature = TemperatureProfile::from_settings(
            temp_start_c,
            temp_end_c,
            temp_tau_s,
            (temp_swing_amplitude_c, temp_swing_period_s, temp_swing_phase_rad),
            temp_series_t_s.clone(),
            temp_series_c.clone(),
        )
        .map_err(core_err)?;
        let errors = ImuErrorParams {
            gyro_bias: gyro_bias_rad_s.unwrap_or(d0.gyro_bias),
            gyro_arw: gyro_arw_rad_rts.unwrap_or(d0.gyro_arw),
            gyro_bias_instability: gyro_bias_instability_rad_s.unwrap_or(d0.gyro_bias_instability),
            gyro_correlation: gyro_correlation_s.unwrap_or(d0.gyro_correlation),
            gyro_rrw: gyro_rrw_rad_s_rts.unwrap_or(d0.gyro_rrw),
            gyro_scale: gyro_scale.unwrap_or(d0.gyro_scale),
            gyro_misalignment: gyro_misalignment_rad.unwrap_or(d0.gyro_misalignment),
            accel_bias: accel_bias_m_s2.unwrap_or(d0.accel_bias),
            accel_vrw: accel_vrw_m_s_rts.unwrap_or(d0.accel_vrw),
            accel_scale: accel_scale.unwrap_or(d0.accel_scale),
            drift_t0_c: drift_t0_c.unwrap_or(d0.drift_t0_c),
            drift_k1: drift_k1_rad_s_per_c.unwrap_or(d0.drift_k1),
            drift_k2: drift_k2_rad_s_per_c2.unwrap_or(d0.drift_k2),
            drift_k3: drift_k3_rad_s_per_c_per_s.unwrap_or(d0.drift_k3),
        };
        let inner = ImuSimulatorConfig {
            lat: lat_rad,
            lon: lon_rad.unwrap_or(d.lon),
            height: height_m.unwrap_or(d.height),
            rate_hz,
            duration_s,
            seed: seed.unwrap_or(d.seed),
            attitude: Euler {
                pitch: pitch_rad.unwrap_or(d.attitude.pitch),
                roll: roll_rad.unwrap_or(d.attitude.roll),
                yaw: yaw_rad.unwrap_or(d.attitude.yaw),
            },
            scheme,
            errors,
            temperature,
            trajectory: if trajectory_start_s.is_some() || trajectory_segments.is_some() {
                Some(TrajectoryConfig {
                    start_s: trajectory_start_s.unwrap_or(0.0),
                    segments: trajectory_segments
                        .unwrap_or_default()
                        .into_iter()
                        .map(|(duration, accel, yaw_rate, climb)| Segment {
                            duration,
                            accel,
                            yaw_rate,
                            climb,
                        })
                        .collect(),
                    repeat: trajectory_repeat,
                })
            } else {
                None
            },
        };
        inner.validate().map_err(core_err)?;
        Ok(Self::resolved(inner, scheme_name, reciprocating_balanced))
    }

    fn __repr__(&self) -> String {
        format!("SimulatorConfig({:?})", self.inner)
    }
}

impl SimulatorConfig {
    /// The attributes of a validated core config (every default filled in; the table settings a scheme does
    /// not use, and the warm-up settings of a series, show the core's defaults).
    fn resolved(inner: ImuSimulatorConfig, scheme_name: String, balanced: bool) -> Self {
        let (rate, accel, span, positions, dwell) = match &inner.scheme {
            RotationScheme::None => (None, None, None, None, None),
            RotationScheme::Continuous { rate, accel } => (Some(*rate), Some(*accel), None, None, None),
            RotationScheme::Reciprocating {
                rate,
                accel,
                span,
                dwell,
            } => (Some(*rate), Some(*accel), Some(*span), None, Some(*dwell)),
            RotationScheme::Indexing {
                rate,
                accel,
                positions,
                dwell,
            } => (Some(*rate), Some(*accel), None, Some(positions.clone()), Some(*dwell)),
        };
        let (start, end, tau, swing, series_t, series_c) = match &inner.temperature {
            TemperatureProfile::WarmUp {
                start_c,
                end_c,
                tau_s,
                swing,
            } => (*start_c, *end_c, *tau_s, *swing, None, None),
            TemperatureProfile::Series { t_s, temp_c } => (
                temp_c.first().copied().unwrap_or(DEFAULT_TEMP_C),
                temp_c.last().copied().unwrap_or(DEFAULT_TEMP_C),
                DEFAULT_TAU_S,
                DailySwing::NONE,
                Some(t_s.clone()),
                Some(temp_c.clone()),
            ),
        };
        let e = &inner.errors;
        SimulatorConfig {
            lat_rad: inner.lat,
            lon_rad: inner.lon,
            height_m: inner.height,
            rate_hz: inner.rate_hz,
            duration_s: inner.duration_s,
            seed: inner.seed,
            pitch_rad: inner.attitude.pitch,
            roll_rad: inner.attitude.roll,
            yaw_rad: inner.attitude.yaw,
            rotation_scheme: scheme_name,
            rotation_rate_rad_s: rate.unwrap_or(DEFAULT_TABLE_RATE_RAD_S),
            rotation_accel_rad_s2: accel.unwrap_or(DEFAULT_TABLE_ACCEL_RAD_S2),
            reciprocating_span_rad: span.unwrap_or(DEFAULT_RECIPROCATING_SPAN_RAD),
            reciprocating_balanced: balanced,
            positions_rad: positions.unwrap_or_else(default_indexing_positions),
            dwell_s: dwell.unwrap_or(0.0),
            gyro_bias_rad_s: e.gyro_bias,
            gyro_arw_rad_rts: e.gyro_arw,
            gyro_bias_instability_rad_s: e.gyro_bias_instability,
            gyro_correlation_s: e.gyro_correlation,
            gyro_rrw_rad_s_rts: e.gyro_rrw,
            gyro_scale: e.gyro_scale,
            gyro_misalignment_rad: e.gyro_misalignment,
            accel_bias_m_s2: e.accel_bias,
            accel_vrw_m_s_rts: e.accel_vrw,
            accel_scale: e.accel_scale,
            temp_start_c: start,
            temp_end_c: end,
            temp_tau_s: tau,
            temp_swing_amplitude_c: swing.amplitude_c,
            temp_swing_period_s: swing.period_s,
            temp_swing_phase_rad: swing.phase_rad,
            temp_series_t_s: series_t,
            temp_series_c: series_c,
            drift_t0_c: e.drift_t0_c,
            drift_k1_rad_s_per_c: e.drift_k1,
            drift_k2_rad_s_per_c2: e.drift_k2,
            drift_k3_rad_s_per_c_per_s: e.drift_k3,
            trajectory_start_s: inner.trajectory.as_ref().map(|t| t.start_s),
            trajectory_segments: inner.trajectory.as_ref().map(|t| {
                t.segments
                    .iter()
                    .map(|s| (s.duration, s.accel, s.yaw_rate, s.climb))
                    .collect()
            }),
            trajectory_repeat: inner.trajectory.as_ref().is_some_and(|t| t.repeat),
            inner,
        }
    }
}

/// Initial state and settings of a navigator (SI; docs/ins-binding-contract.md).
#[pyclass(module = "gyrodrift._core", frozen)]
pub struct NavigatorConfig {
    pub(crate) inner: CoreNavigatorConfig,
    #[pyo3(get)]
    lat_rad: f64,
    #[pyo3(get)]
    lon_rad: f64,
    #[pyo3(get)]
    height_m: f64,
    #[pyo3(get)]
    vel_enu_m_s: [f64; 3],
    #[pyo3(get)]
    pitch_rad: f64,
    #[pyo3(get)]
    roll_rad: f64,
    #[pyo3(get)]
    yaw_rad: f64,
    #[pyo3(get)]
    rate_hz: f64,
    #[pyo3(get)]
    vertical: &'static str,
}

#[pymethods]
impl NavigatorConfig {
    #[new]
    #[pyo3(signature = (*, lat_rad, lon_rad, height_m, pitch_rad, roll_rad, yaw_rad, rate_hz, vel_enu_m_s = None, vertical = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        lat_rad: f64,
        lon_rad: f64,
        height_m: f64,
        pitch_rad: f64,
        roll_rad: f64,
        yaw_rad: f64,
        rate_hz: f64,
        vel_enu_m_s: Option<[f64; 3]>,
        vertical: Option<&str>,
    ) -> PyResult<Self> {
        let d = CoreNavigatorConfig::default();
        let vertical = match vertical {
            Some(name) => Vertical::from_name(name).map_err(core_err)?,
            None => d.vertical,
        };
        let inner = CoreNavigatorConfig {
            lat: lat_rad,
            lon: lon_rad,
            height: height_m,
            vel: vel_enu_m_s.unwrap_or(d.vel),
            attitude: Euler {
                pitch: pitch_rad,
                roll: roll_rad,
                yaw: yaw_rad,
            },
            rate_hz,
            vertical,
        };
        inner.validate().map_err(core_err)?;
        Ok(NavigatorConfig {
            lat_rad,
            lon_rad,
            height_m,
            vel_enu_m_s: inner.vel,
            pitch_rad,
            roll_rad,
            yaw_rad,
            rate_hz,
            vertical: vertical.name(),
            inner,
        })
    }

    fn __repr__(&self) -> String {
        format!("NavigatorConfig({:?})", self.inner)
    }
}

/// What `AlignerConfig` and `SmootherConfig` share, resolved (SI): the known static site, the sample rate and
/// gyrodrift-core's `filter_prior::FilterSettings` (the coarse span, the update interval, the prior, the process
/// noise, the zero-velocity sigma, the history interval). The base class of both; not built on its own.
#[pyclass(module = "gyrodrift._core", frozen, subclass, get_all)]
pub struct FilterConfig {
    lat_rad: f64,
    lon_rad: f64,
    height_m: f64,
    rate_hz: f64,
    coarse_s: f64,
    update_s: f64,
    att_sigma_rad: Option<[f64; 3]>,
    gyro_bias_sigma_rad_s: [f64; 3],
    accel_bias_sigma_m_s2: [f64; 3],
    gyro_arw_rad_rts: f64,
    accel_vrw_m_s_rts: f64,
    zupt_sigma_m_s: f64,
    history_s: f64,
}

impl FilterConfig {
    /// The filter settings of a config's `**filter` keywords (`owner` names the config in the messages): each
    /// keyword of a `FilterConfig` attribute but the site's, None or left out for the value in `defaults`; any other
    /// keyword is refused as Python refuses an unexpected one.
    pub(crate) fn settings(
        owner: &str,
        keywords: Option<&Bound<'_, PyDict>>,
        defaults: FilterSettings,
    ) -> PyResult<FilterSettings> {
        let mut f = defaults;
        for (key, value) in keywords.into_iter().flat_map(|d| d.iter()) {
            let key: String = key.extract()?;
            let v = &value;
            match key.as_str() {
                "coarse_s" => f.coarse_s = keyword(&key, v, f.coarse_s)?,
                "update_s" => f.update_s = keyword(&key, v, f.update_s)?,
                "att_sigma_rad" => f.att_sigma = keyword(&key, v, None)?,
                "gyro_bias_sigma_rad_s" => f.gyro_bias_sigma = keyword(&key, v, f.gyro_bias_sigma)?,
                "accel_bias_sigma_m_s2" => f.accel_bias_sigma = keyword(&key, v, f.accel_bias_sigma)?,
                "gyro_arw_rad_rts" => f.gyro_arw = keyword(&key, v, f.gyro_arw)?,
                "accel_vrw_m_s_rts" => f.accel_vrw = keyword(&key, v, f.accel_vrw)?,
                "zupt_sigma_m_s" => f.zupt_sigma = keyword(&key, v, f.zupt_sigma)?,
                "history_s" => f.history_s = keyword(&key, v, f.history_s)?,
                _ => {
                    return Err(PyTypeError::new_err(format!(
                        "{owner}() got an unexpected keyword argument '{key}'"
                    )))
                }
            }
        }
        Ok(f)
    }

    /// The attributes of validated settings at a site: latitude, longitude [rad], height [m], rate [Hz].
    pub(crate) fn resolved(site: [f64; 4], f: &FilterSettings) -> Self {
        let [lat_rad, lon_rad, height_m, rate_hz] = site;
        FilterConfig {
            lat_rad,
            lon_rad,
            height_m,
            rate_hz,
            coarse_s: f.coarse_s,
            update_s: f.update_s,
            att_sigma_rad: f.att_sigma,
            gyro_bias_sigma_rad_s: f.gyro_bias_sigma,
            accel_bias_sigma_m_s2: f.accel_bias_sigma,
            gyro_arw_rad_rts: f.gyro_arw,
            accel_vrw_m_s_rts: f.accel_vrw,
            zupt_sigma_m_s: f.zupt_sigma,
            history_s: f.history_s,
        }
    }
}

/// A keyword's `value` as a `T`, None for `default`; a value of another type is a `TypeError` naming `key`, as
/// for a declared argument.
fn keyword<'a, 'py, T: FromPyObject<'a, 'py>>(key: &str, value: &'a Bound<'py, PyAny>, default: T) -> PyResult<T> {
    if value.is_none() {
        return Ok(default);
    }
    value.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        PyTypeError::new_err(format!("argument '{key}': {}", e.value(value.py())))
    })
}

/// Settings of a static-base alignment (SI; docs/alignment-contract.md): a `FilterConfig` (its `**filter`
/// keywords; defaults gyrodrift-core `FilterSettings::aligner`) and the fine span.
#[pyclass(module = "gyrodrift._core", frozen, extends = FilterConfig)]
pub struct AlignerConfig {
    pub(crate) inner: CoreAlignerConfig,
    #[pyo3(get)]
    fine_s: f64,
}

#[pymethods]
impl AlignerConfig {
    #[new]
    #[pyo3(signature = (*, lat_rad, lon_rad, height_m, rate_hz, fine_s = None, **filter))]
    fn new(
        lat_rad: f64,
        lon_rad: f64,
        height_m: f64,
        rate_hz: f64,
        fine_s: Option<f64>,
        filter: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let settings = FilterConfig::settings("AlignerConfig", filter, FilterSettings::aligner())?;
        let base = CoreAlignerConfig::with_filter(lat_rad, lon_rad, height_m, rate_hz, settings);
        let inner = CoreAlignerConfig {
            fine_s: fine_s.unwrap_or(base.fine_s),
            ..base
        };
        inner.validate().map_err(core_err)?;
        let shared = FilterConfig::resolved([lat_rad, lon_rad, height_m, rate_hz], &inner.filter);
        Ok(PyClassInitializer::from(shared).add_subclass(AlignerConfig {
            fine_s: inner.fine_s,
            inner,
        }))
    }

    fn __repr__(&self) -> String {
        format!("AlignerConfig({:?})", self.inner)
    }
}
