//! Binding of `gyrodrift_core::alignment::Aligner` as `_core.Aligner` (docs/alignment-contract.md).
//! It converts types and releases the GIL, nothing else.

use super::config::AlignerConfig;
use super::{core_err, flat, increments};
use gyrodrift_core::alignment::Aligner as CoreAligner;
use gyrodrift_core::kalman::{N_STATES, STATE_NAMES};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Static-base alignment with the turntable running (see gyrodrift-core `alignment`):
/// inertial-frame coarse alignment, then a 12-state zero-velocity Kalman fine alignment (closed loop).
/// `Aligner(config: AlignerConfig)`; `process` streams the IMU log; `result()` once `done`.
#[pyclass(module = "gyrodrift._core")]
pub struct Aligner {
    inner: CoreAligner,
}

#[pymethods]
impl Aligner {
    #[new]
    fn new(config: &AlignerConfig) -> PyResult<Self> {
        Ok(Aligner {
            inner: CoreAligner::new(config.inner.clone()).map_err(core_err)?,
        })
    }

    /// State order of `hist_std`: phi E N U [rad], dv E N U [m/s], gyro bias x y z [rad/s],
    /// accelerometer bias x y z [m/s^2].
    #[classattr]
    #[allow(non_snake_case)]
    fn STATE_NAMES() -> Vec<&'static str> {
        STATE_NAMES.to_vec()
    }

    /// True when the alignment span (coarse_s + fine_s) is complete.
    #[getter]
    fn done(&self) -> bool {
        self.inner.done()
    }

    /// Samples consumed so far.
    #[getter]
    fn samples_done(&self) -> u64 {
        self.inner.samples_done()
    }

    /// Samples of the whole alignment span.
    #[getter]
    fn n_samples(&self) -> u64 {
        self.inner.n_samples()
    }

    /// Consume raw increments (dtheta [rad], dv [m/s], (n, 3), body frame); returns how many samples were used
    /// (fewer than n once the alignment span is complete: the caller passes the rest to the Navigator).
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        dtheta_rad: &Bound<'py, PyAny>,
        dv_m_s: &Bound<'py, PyAny>,
    ) -> PyResult<usize> {
        let (a, b) = increments(dtheta_rad, dv_m_s)?;
        let (dth, dv) = (flat(&a, "dtheta_rad")?, flat(&b, "dv_m_s")?);
        let inner = &mut self.inner;
        py.detach(|| inner.process(dth, dv)).map_err(core_err)
    }

    /// The alignment result (SI; keys in docs/alignment-contract.md). `CoreError` before `done` or after a refused log.
    fn result<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = self.inner.result().map_err(core_err)?;
        let d = PyDict::new(py);
        d.set_item("t_s", r.t_s)?;
        d.set_item("pitch_rad", r.attitude.pitch)?;
        d.set_item("roll_rad", r.attitude.roll)?;
        d.set_item("yaw_rad", r.attitude.yaw)?;
        d.set_item("vel_enu_m_s", PyArray1::from_slice(py, &r.vel))?;
        d.set_item("gyro_bias_rad_s", PyArray1::from_slice(py, &r.gyro_bias))?;
        d.set_item("accel_bias_m_s2", PyArray1::from_slice(py, &r.accel_bias))?;
        d.set_item("gyro_bias_std_rad_s", PyArray1::from_slice(py, &r.gyro_bias_std))?;
        d.set_item("accel_bias_std_m_s2", PyArray1::from_slice(py, &r.accel_bias_std))?;
        d.set_item("att_std_rad", PyArray1::from_slice(py, &r.att_std))?;
        d.set_item("coarse_pitch_rad", r.coarse_attitude.pitch)?;
        d.set_item("coarse_roll_rad", r.coarse_attitude.roll)?;
        d.set_item("coarse_yaw_rad", r.coarse_attitude.yaw)?;
        let m = r.hist_t.len();
        d.set_item("hist_t_s", PyArray1::from_vec(py, r.hist_t))?;
        let flat: Vec<f64> = r.hist_std.iter().flatten().copied().collect();
        d.set_item("hist_std", PyArray1::from_vec(py, flat).reshape([m, N_STATES])?)?;
        Ok(d)
    }
}
