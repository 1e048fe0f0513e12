//! Binding of `gyrodrift_core::smoother` as `_core.SmootherConfig` and `_core.Smoother` (docs/identification.md,
//! "The 16 h smoother"). It converts types and releases the GIL, nothing else.

use super::config::FilterConfig;
use super::{arg_err, core_err, flat, increments};
use gyrodrift_core::filter_prior::FilterSettings;
use gyrodrift_core::smoother::{state_names, Smoother as CoreSmoother, SmootherConfig as CoreSmootherConfig};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Validated settings of the full-information smoother (SI; keyword-only; None takes the core's default): a
/// `FilterConfig` (its `**filter` keywords; defaults gyrodrift-core `FilterSettings::smoother`) and the smoother's own.
#[pyclass(module = "gyrodrift._core", frozen, extends = FilterConfig)]
pub struct SmootherConfig {
    pub(crate) inner: CoreSmootherConfig,
    #[pyo3(get)]
    span_s: f64,
    #[pyo3(get)]
    gyro_bias_instability_rad_s: f64,
    #[pyo3(get)]
    gyro_correlation_s: f64,
    #[pyo3(get)]
    gyro_rrw_rad_s_rts: f64,
    #[pyo3(get)]
    position_sigma_m: f64,
    #[pyo3(get)]
    thermal: bool,
    #[pyo3(get)]
    thermal_sigma_rad_s_per_c: f64,
    #[pyo3(get)]
    temp_ref_c: Option<f64>,
    #[pyo3(get)]
    thermal_min_range_c: f64,
}

#[pymethods]
impl SmootherConfig {
    #[new]
    #[pyo3(signature = (
        *, lat_rad, lon_rad, height_m, rate_hz, span_s = None, gyro_bias_instability_rad_s = None,
        gyro_correlation_s = None, gyro_rrw_rad_s_rts = None, position_sigma_m = None, thermal = None,
        thermal_sigma_rad_s_per_c = None, temp_ref_c = None, thermal_min_range_c = None, **filter
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        lat_rad: f64,
        lon_rad: f64,
        height_m: f64,
        rate_hz: f64,
        span_s: Option<f64>,
        gyro_bias_instability_rad_s: Option<f64>,
        gyro_correlation_s: Option<f64>,
        gyro_rrw_rad_s_rts: Option<f64>,
        position_sigma_m: Option<f64>,
        thermal: Option<bool>,
        thermal_sigma_rad_s_per_c: Option<f64>,
        temp_ref_c: Option<f64>,
        thermal_min_range_c: Option<f64>,
        filter: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let settings = FilterConfig::settings("SmootherConfig", filter, FilterSettings::smoother())?;
        let base = CoreSmootherConfig::with_filter(lat_rad, lon_rad, height_m, rate_hz, settings);
        let inner = CoreSmootherConfig {
            span_s: span_s.unwrap_or(base.span_s),
            gyro_bias_instability: gyro_bias_instability_rad_s.unwrap_or(base.gyro_bias_instability),
            gyro_correlation: gyro_correlation_s.unwrap_or(base.gyro_correlation),
            gyro_rrw: gyro_rrw_rad_s_rts.unwrap_or(base.gyro_rrw),
            position_sigma: position_sigma_m.unwrap_or(base.position_sigma),
            thermal: thermal.unwrap_or(base.thermal),
            thermal_sigma: thermal_sigma_rad_s_per_c.unwrap_or(base.thermal_sigma),
            temp_ref: temp_ref_c,
            thermal_min_range: thermal_min_range_c.unwrap_or(base.thermal_min_range),
            ..base
        };
        inner.validate().map_err(core_err)?;
        let shared = FilterConfig::resolved([lat_rad, lon_rad, height_m, rate_hz], &inner.filter());
        Ok(PyClassInitializer::from(shared).add_subclass(SmootherConfig {
            span_s: inner.span_s,
            gyro_bias_instability_rad_s: inner.gyro_bias_instability,
            gyro_correlation_s: inner.gyro_correlation,
            gyro_rrw_rad_s_rts: inner.gyro_rrw,
            position_sigma_m: inner.position_sigma,
            thermal: inner.thermal,
            thermal_sigma_rad_s_per_c: inner.thermal_sigma,
            temp_ref_c: inner.temp_ref,
            thermal_min_range_c: inner.thermal_min_range,
            inner,
        }))
    }

    /// Names of the states, in order (14; 17 with the Gauss-Markov states; 20 with the rate random walk too; one
    /// more, `gyro_temp_z`, with the thermal state).
    #[getter]
    fn state_names(&self) -> Vec<&'static str> {
        state_names(&self.inner)
    }

    fn __repr__(&self) -> String {
        format!("SmootherConfig({:?})", self.inner)
    }
}

/// Forward Kalman filter + RTS smoother over a whole static log (see gyrodrift-core `smoother`).
/// `Smoother(config)`; `process` streams the log from its first sample; `result()` once `done`.
#[pyclass(module = "gyrodrift._core")]
pub struct Smoother {
    inner: CoreSmoother,
}

#[pymethods]
impl Smoother {
    #[new]
    fn new(config: &SmootherConfig) -> PyResult<Self> {
        Ok(Smoother {
            inner: CoreSmoother::new(config.inner.clone()).map_err(core_err)?,
        })
    }

    /// True when the span is complete.
    #[getter]
    fn done(&self) -> bool {
        self.inner.done()
    }

    /// Samples consumed so far.
    #[getter]
    fn samples_done(&self) -> u64 {
        self.inner.samples_done()
    }

    /// Samples of the span.
    #[getter]
    fn n_samples(&self) -> u64 {
        self.inner.n_samples()
    }

    /// Consume raw increments (dtheta [rad], dv [m/s], (n, 3), body frame) and, with the thermal state, the
    /// temperature of each sample (`temp_c` [deg C], (n,)); returns how many samples were used.
    #[pyo3(signature = (dtheta_rad, dv_m_s, temp_c = None))]
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        dtheta_rad: &Bound<'py, PyAny>,
        dv_m_s: &Bound<'py, PyAny>,
        temp_c: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<usize> {
        let (a, b) = increments(dtheta_rad, dv_m_s)?;
        let (dth, dv) = (flat(&a, "dtheta_rad")?, flat(&b, "dv_m_s")?);
        let temp = temp_c
            .as_ref()
            .map(|t| {
                t.as_slice()
                    .map_err(|_| arg_err("temp_c", "expected a contiguous array"))
            })
            .transpose()?;
        let inner = &mut self.inner;
        py.detach(|| inner.process(dth, dv, temp)).map_err(core_err)
    }

    /// The smoothed result (SI): runs the backward pass (GIL released). `CoreError` before `done`.
    fn result<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let inner = &self.inner;
        let r = py.detach(|| inner.result()).map_err(core_err)?;
        let d = PyDict::new(py);
        d.set_item("t_s", r.t_s)?;
        d.set_item("drift_rad_s", r.drift)?;
        d.set_item("drift_std_rad_s", r.drift_std)?;
        d.set_item("drift_end_rad_s", r.drift_end)?;
        d.set_item("drift_end_std_rad_s", r.drift_end_std)?;
        d.set_item("thermal", r.thermal)?;
        d.set_item("drift_ref_rad_s", r.drift_ref)?;
        d.set_item("drift_ref_std_rad_s", r.drift_ref_std)?;
        d.set_item("thermal_coeff_rad_s_per_c", r.thermal_coeff)?;
        d.set_item("thermal_coeff_std_rad_s_per_c", r.thermal_coeff_std)?;
        d.set_item("end_coeff_cov_rad2_s2_per_c", r.end_coeff_cov)?;
        d.set_item("temp_ref_c", r.temp_ref)?;
        d.set_item("temp_end_c", r.temp_end)?;
        d.set_item("temp_range_c", r.temp_range)?;
        d.set_item("gyro_bias_rad_s", PyArray1::from_slice(py, &r.gyro_bias))?;
        d.set_item("gyro_bias_std_rad_s", PyArray1::from_slice(py, &r.gyro_bias_std))?;
        d.set_item("accel_bias_m_s2", PyArray1::from_slice(py, &r.accel_bias))?;
        d.set_item("accel_bias_std_m_s2", PyArray1::from_slice(py, &r.accel_bias_std))?;
        d.set_item("hist_t_s", PyArray1::from_vec(py, r.hist_t))?;
        d.set_item("hist_drift_rad_s", PyArray1::from_vec(py, r.hist_drift))?;
        d.set_item("hist_drift_std_rad_s", PyArray1::from_vec(py, r.hist_drift_std))?;
        d.set_item("hist_filter_std_rad_s", PyArray1::from_vec(py, r.hist_filter_std))?;
        d.set_item("max_attitude_correction_rad", r.max_attitude_correction)?;
        d.set_item("max_velocity_correction_m_s", r.max_velocity_correction)?;
        d.set_item("max_position_error_m", r.max_position_error)?;
        d.set_item("updates", r.updates)?;
        Ok(d)
    }
}
