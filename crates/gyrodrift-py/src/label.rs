//! Binding of `gyrodrift_core::label` as `_core.FreeNavigationConfig` (the settings `_core.label_sigma` and
//! `_core.mission_covariance` share, converted once) and `_core.label_sigma`. It converts types and releases the
//! GIL, nothing else.

use super::config::SimulatorConfig;
use super::core_err;
use gyrodrift_core::aligner_covariance::FineAlignment;
use gyrodrift_core::filter_prior::FilterSettings;
use gyrodrift_core::label::{label_sigma as core_label_sigma, FreeNavigation, LabelConfig, SlowBias};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A free navigation propagated by covariance alone (SI; keyword-only): site, span, propagation step, noise and
/// the attitude and velocity errors at its start. Checked by the function that takes it, whose message names
/// the step as that function uses it.
#[pyclass(module = "gyrodrift._core", frozen)]
pub struct FreeNavigationConfig {
    pub(crate) inner: FreeNavigation,
}

#[pymethods]
impl FreeNavigationConfig {
    #[new]
    #[pyo3(signature = (*, lat_rad, height_m, span_s, step_s, gyro_arw_rad_rts, accel_vrw_m_s_rts, att_sigma_rad,
                        vel_sigma_m_s))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        lat_rad: f64,
        height_m: f64,
        span_s: f64,
        step_s: f64,
        gyro_arw_rad_rts: f64,
        accel_vrw_m_s_rts: f64,
        att_sigma_rad: [f64; 3],
        vel_sigma_m_s: f64,
    ) -> Self {
        FreeNavigationConfig {
            inner: FreeNavigation {
                lat: lat_rad,
                height: height_m,
                span_s,
                step_s,
                gyro_arw: gyro_arw_rad_rts,
                accel_vrw: accel_vrw_m_s_rts,
                att_sigma: att_sigma_rad,
                vel_sigma: vel_sigma_m_s,
            },
        }
    }

    fn __repr__(&self) -> String {
        format!("FreeNavigationConfig({:?})", self.inner)
    }
}

/// 1-sigma of the true-drift label (gyrodrift-core `label::label_sigma`) after the free `navigation` (its
/// `step_s` the interval of the error curves): returns a dict with `drift_std_rad_s`, `sensitivity_m_per_rad_s`
/// and `pos_std_m` (north, east at the end). The z gyro's Gauss-Markov bias and rate random walk (`rrw_start_s`:
/// how long it has walked when the navigation starts) default to none. `alignment` (the run's sample rate, table
/// scheme and attitude at table angle zero) with `alignment_end_s` and `coarse_s`: the navigation starts from the
/// procedure's fine aligner's noise-driven leftovers (`FilterSettings::aligner` after that coarse span); None:
/// they are left out.
#[pyfunction]
#[pyo3(signature = (navigation, *, rms, gyro_bias_instability_rad_s=0.0, gyro_correlation_s=3600.0,
                    gyro_rrw_rad_s_rts=0.0, rrw_start_s=0.0, alignment=None, alignment_end_s=14_400.0,
                    coarse_s=300.0))]
#[allow(clippy::too_many_arguments)]
pub fn label_sigma<'py>(
    py: Python<'py>,
    navigation: &FreeNavigationConfig,
    rms: bool,
    gyro_bias_instability_rad_s: f64,
    gyro_correlation_s: f64,
    gyro_rrw_rad_s_rts: f64,
    rrw_start_s: f64,
    alignment: Option<&SimulatorConfig>,
    alignment_end_s: f64,
    coarse_s: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = LabelConfig {
        navigation: navigation.inner.clone(),
        rms,
        slow: SlowBias {
            bias_instability: gyro_bias_instability_rad_s,
            correlation: gyro_correlation_s,
            rrw: gyro_rrw_rad_s_rts,
        },
        rrw_start_s,
        alignment: alignment.map(|sim| FineAlignment {
            rate_hz: sim.inner.rate_hz,
            scheme: sim.inner.scheme.clone(),
            attitude: sim.inner.attitude,
            filter: FilterSettings {
                coarse_s,
                ..FilterSettings::aligner()
            },
            end_s: alignment_end_s,
        }),
    };
    let r = py.detach(|| core_label_sigma(&cfg)).map_err(core_err)?;
    let d = PyDict::new(py);
    d.set_item("drift_std_rad_s", r.drift_std)?;
    d.set_item("sensitivity_m_per_rad_s", r.sensitivity)?;
    d.set_item("pos_std_m", PyArray1::from_slice(py, &r.pos_std))?;
    Ok(d)
}
