//! Thin PyO3 binding of `gyrodrift-core`: it converts types and releases the GIL, nothing else.
//! The user-facing API lives in the Python package `gyrodrift`. The boundary is fixed by
//! `docs/ins-binding-contract.md`.

mod alignment;

use gyrodrift_core::attitude::Euler;
use gyrodrift_core::earth;
use gyrodrift_core::error::CoreError as CoreFailure;
use gyrodrift_core::imu_error::ImuErrorParams;
use gyrodrift_core::simulator::{ImuChunk, ImuChunkSlices, ImuSimulator as CoreSimulator, ImuSimulatorConfig};
use gyrodrift_core::strapdown::{NavState, Navigator as CoreNavigator, NavigatorConfig, Vertical};
use gyrodrift_core::temperature::TemperatureProfile;
use gyrodrift_core::turntable::{balanced_reciprocating_span, RotationScheme};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray1,
    PyReadwriteArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::f64::consts::PI;

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
        return Err(value_err(format!(
            "lat_rad has {} values but height_m has {}",
            lat.len(),
            h.len()
        )));
    }
    let out: Vec<f64> = py.detach(|| lat.iter().zip(h).map(|(&l, &z)| earth::normal_gravity(l, z)).collect());
    Ok(PyArray1::from_vec(py, out))
}

pyo3::import_exception!(gyrodrift.errors, CoreError);

/// The one mapping of the core's error to Python: `gyrodrift.errors.CoreError` with the message, and the
/// offending setting or input in its `key` attribute (e.g. "lat_rad", "dtheta_rad").
fn core_err(e: CoreFailure) -> PyErr {
    let key = e.key();
    let err = CoreError::new_err(e.to_string());
    Python::attach(|py| {
        // Setting an attribute on a fresh exception instance cannot fail short of memory exhaustion; the
        // message alone is still a complete error then.
        let _ = err.value(py).setattr("key", key);
    });
    err
}

/// A binding-side refusal (wrong argument type or shape) as a `gyrodrift.errors.CoreError` naming `key`.
fn arg_err(key: &'static str, message: impl std::fmt::Display) -> PyErr {
    core_err(CoreFailure::Shape {
        key,
        message: message.to_string(),
    })
}

/// A refused config value as a `gyrodrift.errors.CoreError`.
fn value_err(message: impl Into<String>) -> PyErr {
    CoreError::new_err(message.into())
}

/// The config dict, checked against the allowed keys; values taken out by typed getters.
struct Config<'py> {
    map: HashMap<String, Bound<'py, PyAny>>,
}

impl<'py> Config<'py> {
    fn new(d: &Bound<'py, PyDict>, allowed: &[&str], what: &str) -> PyResult<Self> {
        let mut map = HashMap::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| value_err(format!("{what} config keys must be strings, got {k}")))?;
            if !allowed.contains(&key.as_str()) {
                return Err(value_err(format!(
                    "{key}: unknown key in the {what} config (allowed: {})",
                    allowed.join(", ")
                )));
            }
            map.insert(key, v);
        }
        Ok(Config { map })
    }

    fn f64_opt(&self, key: &str) -> PyResult<Option<f64>> {
        match self.map.get(key) {
            None => Ok(None),
            Some(v) => v
                .extract::<f64>()
                .map(Some)
                .map_err(|_| value_err(format!("{key}: must be a float, got {v}"))),
        }
    }

    fn f64_or(&self, key: &str, default: f64) -> PyResult<f64> {
        Ok(self.f64_opt(key)?.unwrap_or(default))
    }

    fn f64_req(&self, key: &str) -> PyResult<f64> {
        self.f64_opt(key)?
            .ok_or_else(|| value_err(format!("{key}: required key is missing")))
    }

    fn list_opt(&self, key: &str) -> PyResult<Option<Vec<f64>>> {
        match self.map.get(key) {
            None => Ok(None),
            Some(v) => v
                .extract::<Vec<f64>>()
                .map(Some)
                .map_err(|_| value_err(format!("{key}: must be a sequence of floats, got {v}"))),
        }
    }

    fn array_or<const N: usize>(&self, key: &str, default: [f64; N]) -> PyResult<[f64; N]> {
        match self.list_opt(key)? {
            None => Ok(default),
            Some(v) => v
                .try_into()
                .map_err(|v: Vec<f64>| value_err(format!("{key}: must hold {N} values, got {}", v.len()))),
        }
    }

    fn bool_or(&self, key: &str, default: bool) -> PyResult<bool> {
        match self.map.get(key) {
            None => Ok(default),
            Some(v) => v
                .cast::<pyo3::types::PyBool>()
                .map(|b| b.is_true())
                .map_err(|_| value_err(format!("{key}: must be a bool, got {v}"))),
        }
    }

    fn str_or(&self, key: &str, default: &str) -> PyResult<String> {
        match self.map.get(key) {
            None => Ok(default.to_string()),
            Some(v) => v
                .extract::<String>()
                .map_err(|_| value_err(format!("{key}: must be a string, got {v}"))),
        }
    }
}

const SIM_KEYS: &[&str] = &[
    "lat_rad",
    "lon_rad",
    "height_m",
    "rate_hz",
    "duration_s",
    "seed",
    "pitch_rad",
    "roll_rad",
    "yaw_rad",
    "rotation_scheme",
    "rotation_rate_rad_s",
    "rotation_accel_rad_s2",
    "reciprocating_span_rad",
    "reciprocating_balanced",
    "positions_rad",
    "dwell_s",
    "gyro_bias_rad_s",
    "gyro_arw_rad_rts",
    "gyro_bias_instability_rad_s",
    "gyro_correlation_s",
    "gyro_rrw_rad_s_rts",
    "gyro_scale",
    "gyro_misalignment_rad",
    "accel_bias_m_s2",
    "accel_vrw_m_s_rts",
    "accel_scale",
    "temp_start_c",
    "temp_end_c",
    "temp_tau_s",
    "temp_series_t_s",
    "temp_series_c",
    "drift_t0_c",
    "drift_k1_rad_s_per_c",
    "drift_k2_rad_s_per_c2",
    "drift_k3_rad_s_per_c_per_s",
];

/// Defaults of optional keys (SI). Documented in docs/ins-binding-contract.md.
const DEFAULT_RATE: f64 = 6.0 * PI / 180.0;
/// Same default as the scenario files (python/gyrodrift/ins/scenario.py): fast reversals leave little residual.
const DEFAULT_ACCEL: f64 = 100.0 * PI / 180.0;

fn sim_config(d: &Bound<'_, PyDict>) -> PyResult<ImuSimulatorConfig> {
    let c = Config::new(d, SIM_KEYS, "ImuSimulator")?;
    let seed = match c.map.get("seed") {
        None => 0,
        Some(v) => v
            .extract::<u64>()
            .map_err(|_| value_err(format!("seed: must be an integer in [0, 2**64), got {v}")))?,
    };
    let rate = c.f64_or("rotation_rate_rad_s", DEFAULT_RATE)?;
    let accel = c.f64_or("rotation_accel_rad_s2", DEFAULT_ACCEL)?;
    let dwell = c.f64_or("dwell_s", 0.0)?;
    let scheme_name = c.str_or("rotation_scheme", "none")?;
    let scheme = match scheme_name.as_str() {
        "none" => RotationScheme::None,
        "continuous" => RotationScheme::Continuous { rate, accel },
        "reciprocating" => {
            let span = c.f64_or("reciprocating_span_rad", 2.0 * PI)?;
            let span = if c.bool_or("reciprocating_balanced", false)? {
                if !(span.is_finite() && span > 0.0 && span <= 1000.0) {
                    return Err(value_err(format!(
                        "reciprocating_span_rad: must be positive and finite, got {span}"
                    )));
                }
                let turns = (span / (2.0 * PI)).round().max(1.0) as u32;
                balanced_reciprocating_span(rate, accel, dwell, turns).map_err(core_err)?
            } else {
                span
            };
            RotationScheme::Reciprocating {
                rate,
                accel,
                span,
                dwell,
            }
        }
        "indexing" => RotationScheme::Indexing {
            rate,
            accel,
            // The 8-step order cancels exactly (see the contract's modulation residual).
            positions: c
                .list_opt("positions_rad")?
                .unwrap_or_else(|| vec![0.0, 0.5 * PI, PI, 1.5 * PI, 2.0 * PI, 1.5 * PI, PI, 0.5 * PI]),
            dwell,
        },
        other => {
            return Err(value_err(format!(
            "rotation_scheme: must be one of \"none\", \"continuous\", \"reciprocating\", \"indexing\", got {other:?}"
        )))
        }
    };
    let d0 = ImuErrorParams::default();
    let errors = ImuErrorParams {
        gyro_bias: c.array_or("gyro_bias_rad_s", d0.gyro_bias)?,
        gyro_arw: c.f64_or("gyro_arw_rad_rts", d0.gyro_arw)?,
        gyro_bias_instability: c.f64_or("gyro_bias_instability_rad_s", d0.gyro_bias_instability)?,
        gyro_correlation: c.f64_or("gyro_correlation_s", d0.gyro_correlation)?,
        gyro_rrw: c.f64_or("gyro_rrw_rad_s_rts", d0.gyro_rrw)?,
        gyro_scale: c.array_or("gyro_scale", d0.gyro_scale)?,
        gyro_misalignment: c.array_or("gyro_misalignment_rad", d0.gyro_misalignment)?,
        accel_bias: c.array_or("accel_bias_m_s2", d0.accel_bias)?,
        accel_vrw: c.f64_or("accel_vrw_m_s_rts", d0.accel_vrw)?,
        accel_scale: c.array_or("accel_scale", d0.accel_scale)?,
        drift_t0_c: c.f64_or("drift_t0_c", d0.drift_t0_c)?,
        drift_k1: c.f64_or("drift_k1_rad_s_per_c", 0.0)?,
        drift_k2: c.f64_or("drift_k2_rad_s_per_c2", 0.0)?,
        drift_k3: c.f64_or("drift_k3_rad_s_per_c_per_s", 0.0)?,
    };
    let series_t = c.list_opt("temp_series_t_s")?;
    let series_c = c.list_opt("temp_series_c")?;
    let temperature = match (series_t, series_c) {
        (Some(t_s), Some(temp_c)) => TemperatureProfile::Series { t_s, temp_c },
        (None, None) => {
            let start_c = c.f64_or("temp_start_c", 20.0)?;
            TemperatureProfile::WarmUp {
                start_c,
                end_c: c.f64_or("temp_end_c", start_c)?,
                tau_s: c.f64_or("temp_tau_s", 3600.0)?,
            }
        }
        (Some(_), None) => return Err(value_err("temp_series_c: required with temp_series_t_s")),
        (None, Some(_)) => return Err(value_err("temp_series_t_s: required with temp_series_c")),
    };
    Ok(ImuSimulatorConfig {
        lat: c.f64_req("lat_rad")?,
        lon: c.f64_or("lon_rad", 0.0)?,
        height: c.f64_or("height_m", 0.0)?,
        rate_hz: c.f64_req("rate_hz")?,
        duration_s: c.f64_req("duration_s")?,
        seed,
        attitude: Euler {
            pitch: c.f64_or("pitch_rad", 0.0)?,
            roll: c.f64_or("roll_rad", 0.0)?,
            yaw: c.f64_or("yaw_rad", 0.0)?,
        },
        scheme,
        errors,
        temperature,
    })
}

/// Static-base IMU simulator with a single-axis turntable (see gyrodrift-core `simulator`).
/// `ImuSimulator(config: dict)` with SI floats; `next_chunk(n)` streams the run.
#[pyclass(module = "gyrodrift._core")]
struct ImuSimulator {
    inner: CoreSimulator,
}

#[pymethods]
impl ImuSimulator {
    #[new]
    fn new(config: &Bound<'_, PyDict>) -> PyResult<Self> {
        let cfg = sim_config(config)?;
        Ok(ImuSimulator {
            inner: CoreSimulator::new(cfg).map_err(core_err)?,
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

const NAV_KEYS: &[&str] = &[
    "lat_rad",
    "lon_rad",
    "height_m",
    "vel_enu_m_s",
    "pitch_rad",
    "roll_rad",
    "yaw_rad",
    "rate_hz",
    "vertical",
];

fn nav_config(d: &Bound<'_, PyDict>) -> PyResult<NavigatorConfig> {
    let c = Config::new(d, NAV_KEYS, "Navigator")?;
    let vertical = match c.str_or("vertical", "fixed")?.as_str() {
        "fixed" => Vertical::Fixed,
        "damped" => Vertical::Damped,
        other => {
            return Err(value_err(format!(
                "vertical: must be \"fixed\" or \"damped\", got {other:?}"
            )))
        }
    };
    Ok(NavigatorConfig {
        lat: c.f64_req("lat_rad")?,
        lon: c.f64_req("lon_rad")?,
        height: c.f64_req("height_m")?,
        vel: c.array_or("vel_enu_m_s", [0.0; 3])?,
        attitude: Euler {
            pitch: c.f64_req("pitch_rad")?,
            roll: c.f64_req("roll_rad")?,
            yaw: c.f64_req("yaw_rad")?,
        },
        rate_hz: c.f64_req("rate_hz")?,
        vertical,
    })
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
    if shape.len() != 2 || shape[1] != 3 {
        return Err(arg_err(key, format!("{expected}, got shape {shape:?}")));
    }
    let kwargs = pyo3::types::PyDict::new(obj.py());
    kwargs.set_item("dtype", "float64")?;
    np.call_method("ascontiguousarray", (arr,), Some(&kwargs))?
        .extract::<PyReadonlyArray2<'py, f64>>()
        .map_err(|_| arg_err(key, format!("{expected}, got {}", type_name(obj))))
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

/// Strapdown navigator (see gyrodrift-core `strapdown`). `Navigator(config: dict)` with SI floats.
#[pyclass(module = "gyrodrift._core")]
struct Navigator {
    inner: CoreNavigator,
}

#[pymethods]
impl Navigator {
    #[new]
    fn new(config: &Bound<'_, PyDict>) -> PyResult<Self> {
        Ok(Navigator {
            inner: CoreNavigator::new(nav_config(config)?).map_err(core_err)?,
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

    /// Navigate the samples; returns the state after every `decimation`-th sample counted from the run start.
    #[pyo3(signature = (dtheta_rad, dv_m_s, decimation = 1))]
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        dtheta_rad: &Bound<'py, PyAny>,
        dv_m_s: &Bound<'py, PyAny>,
        decimation: i64,
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
        let inner = &mut self.inner;
        let cols = py
            .detach(|| {
                let done = inner.samples_done();
                let n_out = ((done + n as u64) / decimation - done / decimation) as usize;
                let mut cols = NavColumns::with_capacity(n_out);
                inner.process(dth, dv, decimation, |s| cols.push(s)).map(|()| cols)
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
    m.add_function(wrap_pyfunction!(normal_gravity, m)?)?;
    m.add_function(wrap_pyfunction!(balanced_reciprocating_span_rad, m)?)?;
    m.add_class::<ImuSimulator>()?;
    m.add_class::<Navigator>()?;
    m.add_class::<alignment::Aligner>()?;
    Ok(())
}
