//! Binding of `gyrodrift_core::imu_rows` as `_core.check_rows`: the log reader's fast pass over a block of rows.
//! It converts types and releases the GIL, nothing else.

use super::{array_1, array_n3, core_err, flat};
use gyrodrift_core::imu_rows::{Axes, RowBlock, RowLimits};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// One sensor's axes as passed: an (n, 3) array, or a sequence of three (n,) arrays.
enum SensorArg<'py> {
    Rows(PyReadonlyArray2<'py, f64>),
    Columns([PyReadonlyArray1<'py, f64>; 3]),
}

impl<'py> SensorArg<'py> {
    fn extract(obj: &Bound<'py, PyAny>, key: &'static str) -> PyResult<Self> {
        if let Ok(seq) = obj.cast::<PyTuple>() {
            if seq.len() == 3 {
                return Ok(SensorArg::Columns([
                    array_1(&seq.get_item(0)?, key)?,
                    array_1(&seq.get_item(1)?, key)?,
                    array_1(&seq.get_item(2)?, key)?,
                ]));
            }
        }
        Ok(SensorArg::Rows(array_n3(obj, key)?))
    }

    fn axes(&self, key: &'static str) -> PyResult<Axes<'_>> {
        Ok(match self {
            SensorArg::Rows(a) => Axes::Rows(flat(a, key)?),
            SensorArg::Columns([x, y, z]) => Axes::Columns([slice(x, key)?, slice(y, key)?, slice(z, key)?]),
        })
    }
}

fn slice<'a>(a: &'a PyReadonlyArray1<'_, f64>, key: &'static str) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| super::arg_err(key, "expected a contiguous array"))
}

/// `(clean, gyro, accel)` of one block of IMU log rows (gyrodrift-core `imu_rows`): `clean` whether every row
/// passes the reader's checks, and when it does the gyro and accelerometer values times `scale` as C-contiguous
/// (n, 3) float64 arrays (None for an (n, 3) array passed with `scale` 1: it is already that). `gyro` and `accel`
/// are (n, 3) arrays or tuples of three (n,) arrays; `previous_t` the last time stamp of the block before \[s\].
#[pyfunction]
#[pyo3(signature = (t, gyro, accel, *, temperature, truth, ref_height, previous_t, step_s, step_tolerance_s,
                    max_gyro, max_accel, temperature_c, height_m, scale))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(crate) fn check_rows<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    accel: &Bound<'py, PyAny>,
    temperature: Option<&Bound<'py, PyAny>>,
    truth: Vec<Bound<'py, PyAny>>,
    ref_height: Option<&Bound<'py, PyAny>>,
    previous_t: Option<f64>,
    step_s: f64,
    step_tolerance_s: f64,
    max_gyro: f64,
    max_accel: f64,
    temperature_c: (f64, f64),
    height_m: (f64, f64),
    scale: f64,
) -> PyResult<(bool, Option<Bound<'py, PyAny>>, Option<Bound<'py, PyAny>>)> {
    let t = array_1(t, "t_s")?;
    let (gyro, accel) = (SensorArg::extract(gyro, "gyro")?, SensorArg::extract(accel, "accel")?);
    let temperature = temperature.map(|a| array_1(a, "temperature")).transpose()?;
    let truth = truth
        .iter()
        .map(|a| array_1(a, "truth"))
        .collect::<PyResult<Vec<_>>>()?;
    let ref_height = ref_height.map(|a| array_1(a, "ref_height")).transpose()?;
    let block = RowBlock {
        t: slice(&t, "t_s")?,
        gyro: gyro.axes("gyro")?,
        accel: accel.axes("accel")?,
        temperature: temperature.as_ref().map(|a| slice(a, "temperature")).transpose()?,
        truth: truth.iter().map(|a| slice(a, "truth")).collect::<PyResult<Vec<_>>>()?,
        ref_height: ref_height.as_ref().map(|a| slice(a, "ref_height")).transpose()?,
    };
    block.check_lengths().map_err(core_err)?;
    let limits = RowLimits {
        step_s,
        step_tolerance_s,
        max_gyro,
        max_accel,
        temperature_c,
        height_m,
    };
    let rows_as_they_are = |a: &Axes| matches!(a, Axes::Rows(_)) && scale == 1.0;
    let (keep_gyro, keep_accel) = (rows_as_they_are(&block.gyro), rows_as_they_are(&block.accel));
    let (clean, outputs) = py.detach(|| {
        if !block.is_clean(previous_t, &limits) {
            return (false, (None, None));
        }
        let out = |a: &Axes, keep: bool| (!keep).then(|| a.rows_scaled(scale));
        (true, (out(&block.gyro, keep_gyro), out(&block.accel, keep_accel)))
    });
    let n3 = |values: Option<Vec<f64>>| -> PyResult<Option<Bound<'py, PyAny>>> {
        values
            .map(|v| {
                let n = v.len() / 3;
                Ok(PyArray1::from_vec(py, v).reshape([n, 3])?.into_any())
            })
            .transpose()
    };
    Ok((clean, n3(outputs.0)?, n3(outputs.1)?))
}
