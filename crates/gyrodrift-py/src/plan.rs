//! Binding of `gyrodrift_core::plan` as `_core.drift_std_curve` and `_core.mission_covariance` (the planner's
//! covariance analysis, `gyrodrift.procedure.plan`). It converts types and releases the GIL, nothing else.

use super::config::SimulatorConfig;
use super::core_err;
use super::label::FreeNavigationConfig;
use super::smoother::SmootherConfig;
use gyrodrift_core::filter_prior::FilterSettings;
use gyrodrift_core::label::SlowBias;
use gyrodrift_core::plan::{drift_std_curve as core_curve, mission_covariance as core_mission, PlanConfig};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The smoother's 1-sigma of the z drift carried into navigation at each span [s] from the first sample, and its
/// covariance with the mission's floor (gyrodrift-core `plan::drift_std_curve`): the smoother's settings
/// (`span_s` the longest span, `thermal` off), the rotation scheme and attitude at table angle zero of
/// `simulator_config` (its other settings are not used), the mission's start and length [s]; the fine alignment
/// before the mission is the procedure's (`FilterSettings::aligner` after the smoother's coarse span). Returns a
/// dict with `drift_std_rad_s` (per span), `cross_rad_s_m` (per span: north, east), `alignment_cov_m2` (2 x 2:
/// the floor's part from the aligner's leftover attitude and velocity errors) and `walk_cov_m2` (per span, 2 x 2:
/// the floor's part from the z rate random walk's value at the span's end).
#[pyfunction]
#[pyo3(signature = (smoother_config, simulator_config, spans_s, *, mission_start_s, mission_s))]
pub fn drift_std_curve<'py>(
    py: Python<'py>,
    smoother_config: &SmootherConfig,
    simulator_config: &SimulatorConfig,
    spans_s: Vec<f64>,
    mission_start_s: f64,
    mission_s: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = PlanConfig {
        smoother: smoother_config.inner.clone(),
        aligner: FilterSettings {
            coarse_s: smoother_config.inner.coarse_s,
            ..FilterSettings::aligner()
        },
        scheme: simulator_config.inner.scheme.clone(),
        attitude: simulator_config.inner.attitude,
        spans_s,
        mission_start_s,
        mission_s,
    };
    let out = py.detach(|| core_curve(&cfg)).map_err(core_err)?;
    let d = PyDict::new(py);
    d.set_item("drift_std_rad_s", PyArray1::from_vec(py, out.drift_std))?;
    let cross: Vec<Vec<f64>> = out.cross.iter().map(|c| c.to_vec()).collect();
    d.set_item("cross_rad_s_m", PyArray2::from_vec2(py, &cross)?)?;
    let floor = vec![out.alignment_cov[0].to_vec(), out.alignment_cov[1].to_vec()];
    d.set_item("alignment_cov_m2", PyArray2::from_vec2(py, &floor)?)?;
    let walk: Vec<Vec<f64>> = out
        .walk_cov
        .iter()
        .map(|w| w.iter().flatten().copied().collect())
        .collect();
    d.set_item("walk_cov_m2", PyArray2::from_vec2(py, &walk)?)?;
    Ok(d)
}

/// Position error after the free `navigation` (gyrodrift-core `plan::mission_covariance`) with the z gyro's
/// Gauss-Markov bias (stationary) and rate random walk (from zero at the start), both none by default: a dict with
/// `pos_cov_m2` (2 x 2, north, east) and `response_m_per_rad_s` (north, east per unit z drift).
#[pyfunction]
#[pyo3(signature = (navigation, *, gyro_bias_instability_rad_s=0.0, gyro_correlation_s=3600.0,
                    gyro_rrw_rad_s_rts=0.0))]
pub fn mission_covariance<'py>(
    py: Python<'py>,
    navigation: &FreeNavigationConfig,
    gyro_bias_instability_rad_s: f64,
    gyro_correlation_s: f64,
    gyro_rrw_rad_s_rts: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = &navigation.inner;
    let slow = SlowBias {
        bias_instability: gyro_bias_instability_rad_s,
        correlation: gyro_correlation_s,
        rrw: gyro_rrw_rad_s_rts,
    };
    let r = py.detach(|| core_mission(cfg, &slow)).map_err(core_err)?;
    let d = PyDict::new(py);
    let cov = vec![r.pos_cov[0].to_vec(), r.pos_cov[1].to_vec()];
    d.set_item("pos_cov_m2", PyArray2::from_vec2(py, &cov)?)?;
    d.set_item("response_m_per_rad_s", PyArray1::from_slice(py, &r.response))?;
    Ok(d)
}
