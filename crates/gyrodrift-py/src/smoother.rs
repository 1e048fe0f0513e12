//! Binding of `gyrodrift_core::smoother` as `_core.SmootherConfig` and `_core.Smoother` (docs/identification.md,
//! "The 16 h smoother"). It converts types and releases the GIL, nothing else.

use super::{arg_err, core_err, flat, increments};
use gyrodrift_core::smoother::{state_names, Smoother as CoreSmoother, SmootherConfig as CoreSmootherConfig};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Validated settings of the full-information smoother (SI; keyword-only; None takes the core's default).
#[pyclass(module = "gyrodrift._core", frozen)]
pub struct SmootherConfig {
    pub(crate) inner: CoreSmootherConfig,
    #[pyo3(get)]
    lat_rad: f64,
    #[pyo3(get)]
    lon_rad: f64,
    #[pyo3(get)]
    height_m: f64,
    #[pyo3(get)]
    rate_hz: f64,
    #[pyo3(get)]
    coarse_s: f64,
    #[pyo3(get)]
    span_s: f64,
    #[pyo3(get)]
    update_s: f64,
    #[pyo3(get)]
    att_sigma_rad: Option<[f64; 3]>,
    #[pyo3(get)]
    gyro_bias_sigma_rad_s: [f64; 3],
    #[pyo3(get)]
    accel_bias_sigma_m_s2: [f64; 3],
    #[pyo3(get)]
    gyro_arw_rad_rts: f64,
    #[pyo3(get)]
    accel_vrw_m_s_rts: f64,
    #[pyo3(get)]
    gyro_bias_instability_rad_s: f64,
    #[pyo3(get)]
    gyro_correlation_s: f64,
    #[pyo3(get)]
    gyro_rrw_rad_s_rts: f64,
    #[pyo3(get)]
    zupt_sigma_m_s: f64,
    #[pyo3(get)]
    position_sigma_m: f64,
    #[pyo3(get)]
    history_s: f64,
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
        *, lat_rad, lon_rad, height_m, rate_hz, coarse_s = None, span_s = None, update_s = None,
        att_sigma_rad = None, gyro_bias_sigma_rad_s = None, accel_bias_sigma_m_s2 = None, gyro_arw_rad_rts = None,
        accel_vrw_m_s_rts = None, gyro_bias_instability_rad_s = None, gyro_correlation_s = None,
        gyro_rrw_rad_s_rts = None, zupt_sigma_m_s = None, position_sigma_m = None, history_s = None,
        thermal = None, thermal_sigma_rad_s_per_c = None, temp_ref_c = None, thermal_min_range_c = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        lat_rad: f64,
        lon_rad: f64,
        height_m: f64,
        rate_hz: f64,
        coarse_s: Option<f64>,
        span_s: Option<f64>,
        update_s: Option<f64>,
        att_sigma_rad: Option<[f64; 3]>,
        gyro_bias_sigma_rad_s: Option<[f64; 3]>,
        accel_bias_sigma_m_s2: Option<[f64; 3]>,
        gyro_arw_rad_rts: Option<f64>,
        accel_vrw_m_s_rts: Option<f64>,
        gyro_bias_instability_rad_s: Option<f64>,
        gyro_correlation_s: Option<f64>,
        gyro_rrw_rad_s_rts: Option<f64>,
        zupt_sigma_m_s: Option<f64>,
        position_sigma_m: Option<f64>,
        history_s: Option<f64>,
        thermal: Option<bool>,
        thermal_sigma_rad_s_per_c: Option<f64>,
        temp_ref_c: Option<f64>,
        thermal_min_range_c: Option<f64>,
    ) -> PyResult<Self> {
        let base = CoreSmootherConfig::new(lat_rad, lon_rad, height_m, rate_hz);
        let inner = CoreSmootherConfig {
            coarse_s: coarse_s.unwrap_or(base.coarse_s),
            span_s: span_s.unwrap_or(base.span_s),
            update_s: update_s.unwrap_or(base.update_s),
            att_sigma: att_sigma_rad,
            gyro_bias_sigma: gyro_bias_sigma_rad_s.unwrap_or(base.gyro_bias_sigma),
            accel_bias_sigma: accel_bias_sigma_m_s2.unwrap_or(base.accel_bias_sigma),
            gyro_arw: gyro_arw_rad_rts.unwrap_or(base.gyro_arw),
            accel_vrw: accel_vrw_m_s_rts.unwrap_or(base.accel_vrw),
            gyro_bias_instability: gyro_bias_instability_rad_s.unwrap_or(base.gyro_bias_instability),
            gyro_correlation: gyro_correlation_s.unwrap_or(base.gyro_correlation),
            gyro_rrw: gyro_rrw_rad_s_rts.unwrap_or(base.gyro_rrw),
            zupt_sigma: zupt_sigma_m_s.unwrap_or(base.zupt_sigma),
            position_sigma: position_sigma_m.unwrap_or(base.position_sigma),
            history_s: history_s.unwrap_or(base.history_s),
            thermal: thermal.unwrap_or(base.thermal),
            thermal_sigma: thermal_sigma_rad_s_per_c.unwrap_or(base.thermal_sigma),
            temp_ref: temp_ref_c,
            thermal_min_range: thermal_min_range_c.unwrap_or(base.thermal_min_range),
            ..base
        };
        inner.validate().map_err(core_err)?;
        Ok(SmootherConfig {
            lat_rad,
            lon_rad,
            height_m,
            rate_hz,
            coarse_s: inner.coarse_s,
            span_s: inner.span_s,
            update_s: inner.update_s,
            att_sigma_rad: inner.att_sigma,
            gyro_bias_sigma_rad_s: inner.gyro_bias_sigma,
            accel_bias_sigma_m_s2: inner.accel_bias_sigma,
            gyro_arw_rad_rts: inner.gyro_arw,
            accel_vrw_m_s_rts: inner.accel_vrw,
            gyro_bias_instability_rad_s: inner.gyro_bias_instability,
            gyro_correlation_s: inner.gyro_correlation,
            gyro_rrw_rad_s_rts: inner.gyro_rrw,
            zupt_sigma_m_s: inner.zupt_sigma,
            position_sigma_m: inner.position_sigma,
            history_s: inner.history_s,
            thermal: inner.thermal,
            thermal_sigma_rad_s_per_c: inner.thermal_sigma,
            temp_ref_c: inner.temp_ref,
            thermal_min_range_c: inner.thermal_min_range,
            inner,
        })
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
