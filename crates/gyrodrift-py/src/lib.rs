//! Thin PyO3 binding of `gyrodrift-core`: it converts types and releases the GIL, nothing else.
//! The user-facing API lives in the Python package `gyrodrift`.

use gyrodrift_core::earth;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;

/// Normal gravity [m/s^2] for arrays of latitude [rad] and height [m] (WGS-84 Somigliana).
#[pyfunction]
fn normal_gravity<'py>(
    py: Python<'py>,
    lat_rad: PyReadonlyArray1<'py, f64>,
    height_m: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let lat = lat_rad.as_slice()?;
    let h = height_m.as_slice()?;
    if lat.len() != h.len() {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "lat_rad has {} values but height_m has {}",
            lat.len(),
            h.len()
        )));
    }
    let out: Vec<f64> = py.detach(|| {
        lat.iter().zip(h).map(|(&l, &z)| earth::normal_gravity(l, z)).collect()
    });
    Ok(PyArray1::from_vec(py, out))
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("WGS84_A_M", earth::A)?;
    m.add("WGS84_F", earth::F)?;
    m.add("OMEGA_IE_RAD_S", earth::OMEGA_IE)?;
    m.add("NMI_M", earth::NMI)?;
    m.add_function(wrap_pyfunction!(normal_gravity, m)?)?;
    Ok(())
}
