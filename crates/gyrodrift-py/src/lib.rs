//! Thin PyO3 binding of `gyrodrift-core`: it converts types and releases the GIL, nothing else.
//! The user-facing API lives in the Python package `gyrodrift`. The boundary is fixed by
//! `docs/ins-binding-contract.md`.

mod alignment;
mod config;
mod errors;
mod label;
mod plan;
mod rows;
mod smoother;

use config::{AlignerConfig, NavigatorConfig, SimulatorConfig};
use errors::{arg_err, core_err};

use gyrodrift_core::earth;
use gyrodrift_core::simulator::{ImuChunk, ImuChunkSlices, ImuSimulator as CoreSimulator, TruthSlices};
use gyrodrift_core::strapdown::{NavState, Navigator as CoreNavigator, SampleInputs};
use gyrodrift_core::turntable::{balanced_reciprocating_span, RotationScheme};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray1,
    PyReadwriteArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `f(lat, h)` over equal-length float64 arrays of latitude [rad] and height [m], GIL released.
fn earth_map<'py>(
    py: Python<'py>,
    lat_rad: &PyReadonlyArray1<'py, f64>,
    height_m: &PyReadonlyArray1<'py, f64>,
    f: fn(f64, f64) -> f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let lat = lat_rad
        .as_slice()
        .map_err(|_| arg_err("lat_rad", "expected a contiguous array"))?;
    let h = height_m
        .as_slice()
        .map_err(|_| arg_err("height_m", "expected a contiguous array"))?;
    if lat.len() != h.len() {
        return Err(arg_err(
            "height_m",
            format!("lat_rad has {} values but height_m has {}", lat.len(), h.len()),
        ));
    }
    let out: Vec<f64> = py.detach(|| lat.iter().zip(h).map(|(&l, &z)| f(l, z)).collect());
    Ok(PyArray1::from_vec(py, out))
}

/// Normal gravity [m/s^2] for arrays of latitude [rad] and height [m] (WGS-84 Somigliana).
#[pyfunction]
fn normal_gravity<'py>(
    py: Python<'py>,
    lat_rad: PyReadonlyArray1<'py, f64>,
    height_m: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    earth_map(py, &lat_rad, &height_m, earth::normal_gravity)
}

/// `f(lat)` over a float64 array of latitude [rad], GIL released.
fn lat_map<'py>(
    py: Python<'py>,
    lat_rad: &PyReadonlyArray1<'py, f64>,
    f: fn(f64) -> f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let lat = lat_rad
        .as_slice()
        .map_err(|_| arg_err("lat_rad", "expected a contiguous array"))?;
    let out: Vec<f64> = py.detach(|| lat.iter().map(|&l| f(l)).collect());
    Ok(PyArray1::from_vec(py, out))
}

/// WGS-84 meridian radius of curvature R_M [m] for an array of geodetic latitude [rad].
#[pyfunction]
fn meridian_radius<'py>(py: Python<'py>, lat_rad: PyReadonlyArray1<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
    lat_map(py, &lat_rad, earth::meridian_radius)
}

/// WGS-84 prime-vertical (transverse) radius of curvature R_N [m] for an array of geodetic latitude [rad].
#[pyfunction]
fn transverse_radius<'py>(py: Python<'py>, lat_rad: PyReadonlyArray1<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
    lat_map(py, &lat_rad, earth::transverse_radius)
}

/// Static-base IMU simulator with a single-axis turntable (see gyrodrift-core `simulator`).
/// `ImuSimulator(config: SimulatorConfig)`; `next_chunk(n)` or `fill_into(out)` streams the run.
#[pyclass(module = "gyrodrift._core")]
struct ImuSimulator {
    inner: CoreSimulator,
}

#[pymethods]
impl ImuSimulator {
    #[new]
    fn new(config: &SimulatorConfig) -> PyResult<Self> {
        Ok(ImuSimulator {
            inner: CoreSimulator::new(config.inner.clone()).map_err(core_err)?,
        })
    }

    /// Total number of samples of the run (round(duration_s * rate_hz)).
    #[getter]
    fn n_samples(&self) -> u64 {
        self.inner.n_samples()
    }

    /// Samples produced so far.
    #[getter]
    fn samples_done(&self) -> u64 {
        self.inner.samples_done()
    }

    /// Fraction of a body-fixed horizontal sensor error that the rotation scheme leaves un-modulated:
    /// the magnitude of the time average of (cos, sin) of the table angle over one period (1 without
    /// rotation, 0 for continuous rotation). The navigation error of a horizontal bias scales with it.
    #[getter]
    fn modulation_residual(&self) -> f64 {
        let (c, s) = self.inner.turntable().modulation_residual();
        c.hypot(s)
    }

    /// Reciprocating span actually used [rad] (the balanced span when `reciprocating_span_rad` is
    /// "balanced"); None for the other schemes.
    #[getter]
    fn reciprocating_span_rad(&self) -> Option<f64> {
        match self.inner.config().scheme {
            RotationScheme::Reciprocating { span, .. } => Some(span),
            _ => None,
        }
    }

    /// The next at most `n` samples as a dict of numpy arrays, or None when the run is over.
    fn next_chunk<'py>(&mut self, py: Python<'py>, n: i64) -> PyResult<Option<Bound<'py, PyDict>>> {
        let m = self.inner.chunk_len(n.max(0) as u64).map_err(core_err)?;
        if m == 0 {
            return Ok(None);
        }
        // The core fills owned buffers with the GIL released; numpy then takes them over without a copy.
        let mut chunk = ImuChunk::default();
        let inner = &mut self.inner;
        let written = py.detach(|| inner.next_chunk(m, &mut chunk));
        debug_assert_eq!(written, m);
        let d = PyDict::new(py);
        let n3 = |v: Vec<f64>| -> PyResult<Bound<'py, PyArray2<f64>>> {
            // Invariant: the core gives 3 m values for the (m, 3) arrays.
            let a = numpy::ndarray::Array2::from_shape_vec((m, 3), v).expect("3 values per sample");
            Ok(a.into_pyarray(py))
        };
        d.set_item("t_s", chunk.t_s.into_pyarray(py))?;
        d.set_item("dtheta_rad", n3(chunk.dtheta)?)?;
        d.set_item("dv_m_s", n3(chunk.dv)?)?;
        d.set_item("temp_c", chunk.temp_c.into_pyarray(py))?;
        d.set_item("table_angle_rad", chunk.table_angle.into_pyarray(py))?;
        d.set_item("pitch_rad", chunk.pitch.into_pyarray(py))?;
        d.set_item("roll_rad", chunk.roll.into_pyarray(py))?;
        d.set_item("yaw_rad", chunk.yaw.into_pyarray(py))?;
        if !chunk.lat.is_empty() {
            // Moving base: the true position and velocity.
            d.set_item("lat_rad", chunk.lat.into_pyarray(py))?;
            d.set_item("lon_rad", chunk.lon.into_pyarray(py))?;
            d.set_item("height_m", chunk.height.into_pyarray(py))?;
            d.set_item("vel_enu_m_s", n3(chunk.vel)?)?;
        }
        Ok(Some(d))
    }

    /// Fill caller-provided arrays with the next samples instead of allocating a chunk (reuse the same
    /// buffers in a streaming loop: a fresh chunk costs page faults and zeroing). `out` holds the keys of
    /// `next_chunk`, each a writeable C-contiguous float64 array: (n,) or (n, 3). Fills the first
    /// min(n, remaining) samples of every array and returns that count (0 when the run is over); the rest
    /// of the arrays is left as it was. The caller owns the buffers: a kept chunk is overwritten by the next
    /// call. Buffers too short, of another dtype or not contiguous are a `CoreError` naming the key.
    fn fill_into(&mut self, py: Python<'_>, out: &Bound<'_, PyDict>) -> PyResult<usize> {
        let mut t = writeable1(out, "t_s")?;
        let mut dth = writeable2(out, "dtheta_rad")?;
        let mut dv = writeable2(out, "dv_m_s")?;
        let mut temp = writeable1(out, "temp_c")?;
        let mut table = writeable1(out, "table_angle_rad")?;
        let mut pitch = writeable1(out, "pitch_rad")?;
        let mut roll = writeable1(out, "roll_rad")?;
        let mut yaw = writeable1(out, "yaw_rad")?;
        // Moving base: the truth keys are optional, all four or none.
        let want_truth = out.contains("lat_rad")?;
        let mut truth_arrays = if want_truth {
            Some((
                writeable1(out, "lat_rad")?,
                writeable1(out, "lon_rad")?,
                writeable1(out, "height_m")?,
                writeable2(out, "vel_enu_m_s")?,
            ))
        } else {
            None
        };
        let contiguous = |key: &'static str| arg_err(key, "expected a C-contiguous array");
        let slices = ImuChunkSlices {
            t_s: t.as_slice_mut().map_err(|_| contiguous("t_s"))?,
            dtheta: dth.as_slice_mut().map_err(|_| contiguous("dtheta_rad"))?,
            dv: dv.as_slice_mut().map_err(|_| contiguous("dv_m_s"))?,
            temp_c: temp.as_slice_mut().map_err(|_| contiguous("temp_c"))?,
            table_angle: table.as_slice_mut().map_err(|_| contiguous("table_angle_rad"))?,
            pitch: pitch.as_slice_mut().map_err(|_| contiguous("pitch_rad"))?,
            roll: roll.as_slice_mut().map_err(|_| contiguous("roll_rad"))?,
            yaw: yaw.as_slice_mut().map_err(|_| contiguous("yaw_rad"))?,
            truth: match truth_arrays.as_mut() {
                None => None,
                Some((lat, lon, h, vel)) => Some(TruthSlices {
                    lat: lat.as_slice_mut().map_err(|_| contiguous("lat_rad"))?,
                    lon: lon.as_slice_mut().map_err(|_| contiguous("lon_rad"))?,
                    height: h.as_slice_mut().map_err(|_| contiguous("height_m"))?,
                    vel: vel.as_slice_mut().map_err(|_| contiguous("vel_enu_m_s"))?,
                }),
            },
        };
        let inner = &mut self.inner;
        py.detach(|| inner.fill(slices)).map_err(core_err)
    }
}

/// The writeable (n,) float64 array `out[key]` of `fill_into`.
fn writeable1<'py>(out: &Bound<'py, PyDict>, key: &'static str) -> PyResult<PyReadwriteArray1<'py, f64>> {
    out.get_item(key)?
        .ok_or_else(|| arg_err(key, "missing from the output arrays"))?
        .extract()
        .map_err(|_| arg_err(key, "expected a writeable (n,) float64 array, distinct from the others"))
}

/// The writeable (n, 3) float64 array `out[key]` of `fill_into`.
fn writeable2<'py>(out: &Bound<'py, PyDict>, key: &'static str) -> PyResult<PyReadwriteArray2<'py, f64>> {
    let a: PyReadwriteArray2<'py, f64> = out
        .get_item(key)?
        .ok_or_else(|| arg_err(key, "missing from the output arrays"))?
        .extract()
        .map_err(|_| {
            arg_err(
                key,
                "expected a writeable (n, 3) float64 array, distinct from the others",
            )
        })?;
    if a.shape()[1] != 3 {
        return Err(arg_err(key, format!("expected shape (n, 3), got {:?}", a.shape())));
    }
    Ok(a)
}

/// Output columns of `Navigator.process`.
#[derive(Default)]
struct NavColumns {
    t: Vec<f64>,
    lat: Vec<f64>,
    lon: Vec<f64>,
    h: Vec<f64>,
    vel: Vec<f64>,
    pitch: Vec<f64>,
    roll: Vec<f64>,
    yaw: Vec<f64>,
}

impl NavColumns {
    fn with_capacity(n: usize) -> Self {
        NavColumns {
            t: Vec::with_capacity(n),
            lat: Vec::with_capacity(n),
            lon: Vec::with_capacity(n),
            h: Vec::with_capacity(n),
            vel: Vec::with_capacity(3 * n),
            pitch: Vec::with_capacity(n),
            roll: Vec::with_capacity(n),
            yaw: Vec::with_capacity(n),
        }
    }

    fn push(&mut self, s: &NavState) {
        self.t.push(s.t);
        self.lat.push(s.lat);
        self.lon.push(s.lon);
        self.h.push(s.height);
        self.vel.extend_from_slice(&s.vel);
        self.pitch.push(s.attitude.pitch);
        self.roll.push(s.attitude.roll);
        self.yaw.push(s.attitude.yaw);
    }
}

/// Three floats from a sequence or array (a bias vector, body x y z).
fn vec3(v: &Bound<'_, PyAny>, key: &'static str) -> PyResult<[f64; 3]> {
    let v: Vec<f64> = v
        .extract()
        .map_err(|_| arg_err(key, format!("expected 3 numbers, got {}", type_name(v))))?;
    v.try_into()
        .map_err(|v: Vec<f64>| arg_err(key, format!("expected 3 numbers, got {}", v.len())))
}

/// The Python type name of `obj` for messages.
fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "object".to_string())
}

/// An (n, 3) float64 C-contiguous array from any array-like of real numbers: a float64 C-contiguous array is
/// borrowed as it is; other real dtypes (float32, integers) and non-contiguous arrays are converted (copied by
/// numpy); anything else (complex, bool, strings, objects, another shape) is a `CoreError` naming `key` and
/// what was expected (docs/ins-binding-contract.md).
fn array_n3<'py>(obj: &Bound<'py, PyAny>, key: &'static str) -> PyResult<PyReadonlyArray2<'py, f64>> {
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'py, f64>>() {
        if a.shape()[1] == 3 && a.is_c_contiguous() {
            return Ok(a);
        }
    }
    let expected = "expected an (n, 3) array of real numbers (float64; float32 and integers are converted)";
    real_f64_array(obj, key, expected, |shape| shape.len() == 2 && shape[1] == 3)?
        .extract::<PyReadonlyArray2<'py, f64>>()
        .map_err(|_| arg_err(key, format!("{expected}, got {}", type_name(obj))))
}

/// An (n,) float64 C-contiguous array from any 1-D array-like of real numbers (converted as in `array_n3`).
fn array_1<'py>(obj: &Bound<'py, PyAny>, key: &'static str) -> PyResult<PyReadonlyArray1<'py, f64>> {
    if let Ok(a) = obj.extract::<PyReadonlyArray1<'py, f64>>() {
        if a.is_c_contiguous() {
            return Ok(a);
        }
    }
    let expected = "expected an (n,) array of real numbers (float64; float32 and integers are converted)";
    real_f64_array(obj, key, expected, |shape| shape.len() == 1)?
        .extract::<PyReadonlyArray1<'py, f64>>()
        .map_err(|_| arg_err(key, format!("{expected}, got {}", type_name(obj))))
}

/// `obj` as a float64 C-contiguous numpy array (numpy converts real dtypes and copies when needed), or a
/// `CoreError` naming `key`, what was `expected` and what came: not an array, a dtype that is not real (complex,
/// bool, strings, objects), or a shape `shape_ok` refuses.
fn real_f64_array<'py>(
    obj: &Bound<'py, PyAny>,
    key: &'static str,
    expected: &str,
    shape_ok: impl Fn(&[usize]) -> bool,
) -> PyResult<Bound<'py, PyAny>> {
    let np = obj.py().import("numpy")?;
    let arr = np
        .call_method1("asarray", (obj,))
        .map_err(|_| arg_err(key, format!("{expected}, got {}", type_name(obj))))?;
    let dtype = arr.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(arg_err(key, format!("{expected}, got dtype {}", dtype.str()?)));
    }
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    if !shape_ok(&shape) {
        return Err(arg_err(key, format!("{expected}, got shape {shape:?}")));
    }
    let kwargs = pyo3::types::PyDict::new(obj.py());
    kwargs.set_item("dtype", "float64")?;
    np.call_method("ascontiguousarray", (arr,), Some(&kwargs))
}

/// Both increment arrays of a `process` call (see `array_n3`).
fn increments<'py>(
    dtheta: &Bound<'py, PyAny>,
    dv: &Bound<'py, PyAny>,
) -> PyResult<(PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, f64>)> {
    Ok((array_n3(dtheta, "dtheta_rad")?, array_n3(dv, "dv_m_s")?))
}

/// The flat row-major values of an array from `array_n3` (C-contiguous by construction).
fn flat<'a>(a: &'a PyReadonlyArray2<'_, f64>, key: &'static str) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| arg_err(key, "expected a C-contiguous array"))
}

/// An optional per-sample argument of `Navigator.process` (see `array_1`).
fn per_sample<'py>(obj: Option<&Bound<'py, PyAny>>, key: &'static str) -> PyResult<Option<PyReadonlyArray1<'py, f64>>> {
    obj.map(|x| array_1(x, key)).transpose()
}

/// The values of an optional array from `per_sample`.
fn contiguous<'a>(a: &'a Option<PyReadonlyArray1<'_, f64>>, key: &'static str) -> PyResult<Option<&'a [f64]>> {
    a.as_ref()
        .map(|x| x.as_slice().map_err(|_| arg_err(key, "expected a contiguous array")))
        .transpose()
}

/// Strapdown navigator (see gyrodrift-core `strapdown`). `Navigator(config: NavigatorConfig)`.
#[pyclass(module = "gyrodrift._core")]
struct Navigator {
    inner: CoreNavigator,
}

#[pymethods]
impl Navigator {
    #[new]
    fn new(config: &NavigatorConfig) -> PyResult<Self> {
        Ok(Navigator {
            inner: CoreNavigator::new(config.inner.clone()).map_err(core_err)?,
        })
    }

    /// Estimated gyro bias [rad/s, body x y z], subtracted from every following sample (measured - estimate).
    fn set_gyro_bias(&mut self, b_rad_s: &Bound<'_, PyAny>) -> PyResult<()> {
        self.inner.set_gyro_bias(vec3(b_rad_s, "b_rad_s")?).map_err(core_err)
    }

    /// Estimated accelerometer bias [m/s^2, body x y z], subtracted from every following sample.
    fn set_accel_bias(&mut self, b_m_s2: &Bound<'_, PyAny>) -> PyResult<()> {
        self.inner.set_accel_bias(vec3(b_m_s2, "b_m_s2")?).map_err(core_err)
    }

    /// Samples processed since the start of the run.
    #[getter]
    fn samples_done(&self) -> u64 {
        self.inner.samples_done()
    }

    /// Reference height [m] of the damped vertical channel for the following samples (initially the configured
    /// height).
    fn set_reference_height(&mut self, height_m: f64) -> PyResult<()> {
        self.inner.set_reference_height(height_m).map_err(core_err)
    }

    /// The reference height [m] of the damped vertical channel.
    #[getter]
    fn reference_height_m(&self) -> f64 {
        self.inner.reference_height()
    }

    /// Navigate the samples; returns the state after every `decimation`-th sample counted from the run start.
    /// Optional, one value per sample: `reference_height_m` (n,) [m], the damped vertical channel's reference height
    /// at the end of every sample; `axial_bias_rad_s` (n,) [rad/s], the z gyro bias estimate subtracted from every
    /// sample instead of `set_gyro_bias`'s z (a drift law on the measured temperature). The last value of each stays
    /// in force afterwards.
    #[pyo3(signature = (dtheta_rad, dv_m_s, decimation = 1, reference_height_m = None, axial_bias_rad_s = None))]
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        dtheta_rad: &Bound<'py, PyAny>,
        dv_m_s: &Bound<'py, PyAny>,
        decimation: i64,
        reference_height_m: Option<&Bound<'py, PyAny>>,
        axial_bias_rad_s: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        if decimation < 1 {
            return Err(arg_err(
                "decimation",
                format!("expected a positive number of samples, got {decimation}"),
            ));
        }
        let decimation = decimation as u64;
        let (a, b) = increments(dtheta_rad, dv_m_s)?;
        let (dth, dv) = (flat(&a, "dtheta_rad")?, flat(&b, "dv_m_s")?);
        let n = dth.len() / 3;
        let href = per_sample(reference_height_m, "reference_height_m")?;
        let bias = per_sample(axial_bias_rad_s, "axial_bias_rad_s")?;
        let inputs = SampleInputs {
            reference_height_m: contiguous(&href, "reference_height_m")?,
            axial_bias_rad_s: contiguous(&bias, "axial_bias_rad_s")?,
        };
        let inner = &mut self.inner;
        let cols = py
            .detach(|| {
                let done = inner.samples_done();
                let n_out = ((done + n as u64) / decimation - done / decimation) as usize;
                let mut cols = NavColumns::with_capacity(n_out);
                inner
                    .process_with(dth, dv, inputs, decimation, |s| cols.push(s))
                    .map(|()| cols)
            })
            .map_err(core_err)?;
        let m = cols.t.len();
        let d = PyDict::new(py);
        d.set_item("t_s", PyArray1::from_vec(py, cols.t))?;
        d.set_item("lat_rad", PyArray1::from_vec(py, cols.lat))?;
        d.set_item("lon_rad", PyArray1::from_vec(py, cols.lon))?;
        d.set_item("height_m", PyArray1::from_vec(py, cols.h))?;
        d.set_item("vel_enu_m_s", PyArray1::from_vec(py, cols.vel).reshape([m, 3])?)?;
        d.set_item("pitch_rad", PyArray1::from_vec(py, cols.pitch))?;
        d.set_item("roll_rad", PyArray1::from_vec(py, cols.roll))?;
        d.set_item("yaw_rad", PyArray1::from_vec(py, cols.yaw))?;
        Ok(d)
    }

    /// The current state: scalars, and `vel_enu_m_s` as a (3,) array.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.inner.state();
        let d = PyDict::new(py);
        d.set_item("t_s", s.t)?;
        d.set_item("lat_rad", s.lat)?;
        d.set_item("lon_rad", s.lon)?;
        d.set_item("height_m", s.height)?;
        d.set_item("vel_enu_m_s", PyArray1::from_slice(py, &s.vel))?;
        d.set_item("pitch_rad", s.attitude.pitch)?;
        d.set_item("roll_rad", s.attitude.roll)?;
        d.set_item("yaw_rad", s.attitude.yaw)?;
        Ok(d)
    }
}

/// The reciprocating span [rad] near `turns` full turns whose reversal ramps leave no un-modulated
/// residual (see gyrodrift-core `turntable::balanced_reciprocating_span`): rate [rad/s], accel [rad/s^2],
/// dwell [s]. ValueError naming the key when no such span lies within half a turn below.
#[pyfunction]
#[pyo3(signature = (rotation_rate_rad_s, rotation_accel_rad_s2, dwell_s = 0.0, turns = 1))]
fn balanced_reciprocating_span_rad(
    rotation_rate_rad_s: f64,
    rotation_accel_rad_s2: f64,
    dwell_s: f64,
    turns: u32,
) -> PyResult<f64> {
    balanced_reciprocating_span(rotation_rate_rad_s, rotation_accel_rad_s2, dwell_s, turns).map_err(core_err)
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("WGS84_A_M", earth::A)?;
    m.add("WGS84_F", earth::F)?;
    m.add("OMEGA_IE_RAD_S", earth::OMEGA_IE)?;
    m.add("NMI_M", earth::NMI)?;
    m.add("STANDARD_GRAVITY_M_S2", gyrodrift_core::units::STANDARD_GRAVITY)?;
    // The smoother's default noise (gyrodrift-core `filter_prior`), in the units of `SensorNoise`'s keys.
    let prior = gyrodrift_core::filter_prior::FilterPrior::SMOOTHER;
    m.add("SMOOTHER_GYRO_ARW_DEG_RTH", prior.gyro_arw_deg_rth)?;
    m.add("SMOOTHER_ACCEL_VRW_UG_RTHZ", prior.accel_vrw_ug_rthz)?;
    // The limits of gyrodrift-core (`limits`, `turntable`, `simulator`), in the units their names carry.
    {
        use gyrodrift_core::limits as l;
        use gyrodrift_core::turntable as t;
        for (name, value) in [
            ("MAX_LAT_DEG", l::MAX_LAT_DEG),
            ("MAX_LON_DEG", l::MAX_LON_DEG),
            ("MIN_HEIGHT_M", l::MIN_HEIGHT_M),
            ("MAX_HEIGHT_M", l::MAX_HEIGHT_M),
            ("MIN_RATE_HZ", l::MIN_RATE_HZ),
            ("MAX_RATE_HZ", l::MAX_RATE_HZ),
            ("MAX_DURATION_S", l::MAX_DURATION_S),
            ("MAX_PITCH_DEG", l::MAX_PITCH_DEG),
            ("MAX_ROLL_DEG", l::MAX_ROLL_DEG),
            ("MAX_YAW_DEG", l::MAX_YAW_DEG),
            ("MAX_ANGULAR_RATE_DEG_S", l::MAX_ANGULAR_RATE_DEG_S),
            ("MAX_SPECIFIC_FORCE_G", l::MAX_SPECIFIC_FORCE_G),
            ("MAX_TABLE_RATE_DEG_S", t::MAX_TABLE_RATE_RAD_S.to_degrees()),
            ("MAX_TABLE_ACCEL_DEG_S2", t::MAX_TABLE_ACCEL_RAD_S2.to_degrees()),
            ("MAX_SPAN_DEG", t::MAX_SPAN_RAD.to_degrees()),
            (
                "MIN_SAMPLES_PER_PERIOD",
                gyrodrift_core::simulator::MIN_SAMPLES_PER_PERIOD,
            ),
        ] {
            m.add(name, value)?;
        }
        m.add("MAX_CHUNK_SAMPLES", gyrodrift_core::simulator::MAX_CHUNK_SAMPLES)?;
        m.add("MAX_INDEX_POSITIONS", t::MAX_INDEX_POSITIONS)?;
        m.add("MAX_VEHICLE_SPEED_M_S", gyrodrift_core::trajectory::MAX_SPEED_M_S)?;
        m.add("MAX_VEHICLE_ACCEL_M_S2", gyrodrift_core::trajectory::MAX_ACCEL_M_S2)?;
        m.add(
            "MAX_VEHICLE_CLIMB_RATE_M_S",
            gyrodrift_core::trajectory::MAX_CLIMB_RATE_M_S,
        )?;
        m.add(
            "MAX_VEHICLE_YAW_RATE_DEG_S",
            gyrodrift_core::trajectory::MAX_YAW_RATE_RAD_S.to_degrees(),
        )?;
    }
    m.add_function(wrap_pyfunction!(normal_gravity, m)?)?;
    m.add_function(wrap_pyfunction!(meridian_radius, m)?)?;
    m.add_function(wrap_pyfunction!(transverse_radius, m)?)?;
    m.add_function(wrap_pyfunction!(balanced_reciprocating_span_rad, m)?)?;
    m.add_class::<SimulatorConfig>()?;
    m.add_class::<NavigatorConfig>()?;
    m.add_class::<config::FilterConfig>()?;
    m.add_class::<AlignerConfig>()?;
    m.add_class::<ImuSimulator>()?;
    m.add_class::<Navigator>()?;
    m.add_class::<alignment::Aligner>()?;
    m.add_class::<smoother::SmootherConfig>()?;
    m.add_class::<smoother::Smoother>()?;
    m.add_class::<label::FreeNavigationConfig>()?;
    m.add_function(wrap_pyfunction!(label::label_sigma, m)?)?;
    m.add_function(wrap_pyfunction!(rows::check_rows, m)?)?;
    m.add_function(wrap_pyfunction!(plan::drift_std_curve, m)?)?;
    m.add_function(wrap_pyfunction!(plan::mission_covariance, m)?)?;
    Ok(())
}
