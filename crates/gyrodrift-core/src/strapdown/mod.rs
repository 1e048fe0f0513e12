//! Strapdown navigator: quaternion attitude, velocity and position in ENU, one IMU sample per update.
//!
//! Equations follow PSINS `cnscl`/`insupdate` (Yan Gongmin 2016, ch. 6-7) and KF-GINS `insmech.cpp`
//! (Niu et al.), with the one-plus-previous-sample coning and sculling algorithm (Savage 1998,
//! Ignagni 1996), so every sample is a complete update and the navigator can output after any sample.
//!
//! Frames and signs: navigation ENU, body Right-Forward-Up, `q` = q_b^n (Hamilton, scalar first).
//! Latitude/longitude in rad, height in m, velocity (v_E, v_N, v_U) in m/s. Estimated sensor biases are
//! subtracted from every sample: dtheta_used = dtheta_meas - b_g dt, dv_used = dv_meas - b_a dt.
//! A navigation error is computed minus true.
//!
//! Per sample k with increments (dtheta_k, dv_k) over dt:
//! 1. coning/sculling (`coning_sculling`):
//!    phi     = dtheta_k + 1/12 dtheta_{k-1} x dtheta_k                                   (coning)
//!    dv_b    = dv_k + 1/2 dtheta_k x dv_k + 1/12 (dtheta_{k-1} x dv_k + dv_{k-1} x dtheta_k)
//!    (rotation compensation + sculling);
//! 2. velocity (`update_velocity`), zeta = (w_ie^n + w_en^n) dt:
//!    v_k = v_{k-1} + (I - 1/2 [zeta x]) C_b^n(k-1) dv_b + (g^n - (2 w_ie^n + w_en^n) x v_{k-1}) dt;
//! 3. position (`update_position`), trapezoidal in velocity:
//!    lat += v_N dt / (R_M + h),  lon += v_E dt / ((R_N + h) cos lat),  h += v_U dt;
//! 4. attitude (`update_attitude`): q_k = q(-zeta) o q_{k-1} o q(phi), q(.) = rotation vector -> quaternion;
//!    q is normalised every `EARTH_REFRESH` samples (|q| stays within 1e-15 of 1 in between).
//!
//! Earth terms (sin/cos/tan lat, R_M, R_N, gravity, w_ie^n) are recomputed every `EARTH_REFRESH` samples
//! from the current position (they change by < 1e-12 relative over that time even at aircraft speed);
//! the transport rate w_en^n is recomputed every sample from the current velocity.
//!
//! Per-sample axial bias: `process_with` can take the z gyro bias estimate of every sample [rad/s] (a drift law
//! evaluated on the measured temperature); it replaces `gyro_bias[2]` for that sample (dtheta_z - b_z,k dt) and the
//! last one stays the estimate. A constant per-sample bias gives the bits of `set_gyro_bias` with that bias.
//!
//! Feedback of an error-state filter: `Navigator::correct(phi, dv)` (q <- q(phi) o q, v <- v - dv; the phi-angle
//! sign of `kalman`), which keeps the coning/sculling memory, so the alignment never restarts the navigator.
//!
//! Vertical channel: `Fixed` holds h at its initial value and v_U = 0 (static base). `Damped` is a
//! second-order loop towards a reference height h_ref: the initial height unless the caller gives one
//! (`set_reference_height`, or one per sample with `process_with`: a barometric or known height, the
//! route's height):
//!    v_U += (a_U - k2 (h - h_ref)) dt,   h += (v_U - k1 (h - h_ref)) dt,
//! with k1 = 2 zeta_v w_v, k2 = w_v^2 + 2 g / R (cancelling the free-inertial instability 2 g / R),
//! w_v = 0.01 rad/s (period 628 s), zeta_v = 0.707. A constant vertical accelerometer error b settles at
//! h - h_ref = b / w_v^2 with the reported v_U = k1 (h - h_ref) (e.g. 50 ug: 4.9 m and 0.069 m/s).

use crate::attitude::{
    add, cross, dcm_to_euler, dot, euler_to_quat, quat_mul, quat_normalize, quat_rotate, quat_to_dcm, rotvec_to_quat,
    scale, sub, Euler, Quat, Vec3,
};
use crate::earth;
use crate::error::{all_in_range, show_all, Unit};
use crate::error::{check, check_with, CoreError};
use crate::imu_error::{MAX_ACCEL_BIAS_M_S2, MAX_GYRO_BIAS_RAD_S};
use crate::limits::{
    check_attitude, check_increments, check_lengths, check_site, increment_bounds, MAX_HEIGHT_M, MIN_HEIGHT_M,
};

/// Samples per block of `Navigator::process`: a refused block is searched again for the message while in
/// cache (96 kB of increments).
const CHECK_BLOCK: usize = 4096;

/// Samples between refreshes of the position-dependent Earth terms.
pub const EARTH_REFRESH: u64 = 8;
/// Natural frequency of the damped vertical loop [rad/s].
pub const VERTICAL_OMEGA: f64 = 0.01;
/// Damping ratio of the damped vertical loop [-].
pub const VERTICAL_ZETA: f64 = 0.707;

/// Vertical-channel mechanisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Vertical {
    Fixed,
    Damped,
}

impl Vertical {
    /// The mechanisation named `name` ("fixed" or "damped").
    pub fn from_name(name: &str) -> Result<Self, CoreError> {
        match name {
            "fixed" => Ok(Vertical::Fixed),
            "damped" => Ok(Vertical::Damped),
            other => Err(CoreError::Setting {
                key: "vertical",
                message: format!("expected \"fixed\" or \"damped\", got {other:?}"),
            }),
        }
    }

    /// Its name ("fixed" or "damped").
    pub fn name(self) -> &'static str {
        match self {
            Vertical::Fixed => "fixed",
            Vertical::Damped => "damped",
        }
    }
}

/// Initial state and settings of a navigator (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct NavigatorConfig {
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    /// Initial velocity (E, N, U) [m/s].
    pub vel: Vec3,
    pub attitude: Euler,
    pub rate_hz: f64,
    pub vertical: Vertical,
}

impl Default for NavigatorConfig {
    fn default() -> Self {
        NavigatorConfig {
            lat: 28.222f64.to_radians(),
            lon: 0.0,
            height: 0.0,
            vel: [0.0; 3],
            attitude: Euler::default(),
            rate_hz: 100.0,
            vertical: Vertical::Fixed,
        }
    }
}

impl NavigatorConfig {
    pub fn validate(&self) -> Result<(), CoreError> {
        check_site(self.lat, self.lon, self.height, self.rate_hz)?;
        check_with(
            self.vel.iter().all(|v| v.is_finite() && v.abs() <= 1000.0),
            "vel_enu_m_s",
            || {
                format!(
                    "velocity {} must be finite and within +-1000 m/s",
                    show_all(&self.vel, Unit::Si("m/s"))
                )
            },
        )?;
        check_attitude(self.attitude)
    }
}

/// Navigation state at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NavState {
    /// Time since the start of the run \[s\] (samples processed / rate).
    pub t: f64,
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    pub vel: Vec3,
    pub attitude: Euler,
}

/// Position-dependent Earth quantities, refreshed every `EARTH_REFRESH` samples.
#[derive(Clone, Copy, Debug)]
struct EarthTerms {
    tan_lat: f64,
    /// 1 / (R_M + h), 1 / (R_N + h), 1 / ((R_N + h) cos lat) [1/m].
    inv_rm_h: f64,
    inv_rn_h: f64,
    inv_rn_h_cos: f64,
    /// Gravity vector in ENU (0, 0, -g) [m/s^2].
    g_n: Vec3,
    /// Earth rate in ENU [rad/s], and twice it (Coriolis).
    w_ie: Vec3,
    two_w_ie: Vec3,
    /// 2 g / R (free-inertial vertical instability) [1/s^2].
    two_g_over_r: f64,
}

impl EarthTerms {
    fn at(lat: f64, h: f64) -> Self {
        let (s, c) = lat.sin_cos();
        let g = earth::normal_gravity(lat, h);
        let rm_h = earth::meridian_radius(lat) + h;
        let rn_h = earth::transverse_radius(lat) + h;
        EarthTerms {
            tan_lat: s / c,
            inv_rm_h: 1.0 / rm_h,
            inv_rn_h: 1.0 / rn_h,
            inv_rn_h_cos: 1.0 / (rn_h * c),
            g_n: [0.0, 0.0, -g],
            w_ie: earth::earth_rate_enu(lat),
            two_w_ie: scale(earth::earth_rate_enu(lat), 2.0),
            two_g_over_r: 2.0 * g / (rm_h * rn_h).sqrt(),
        }
    }

    /// Transport rate w_en^n = (-v_N / (R_M + h), v_E / (R_N + h), v_E tan(lat) / (R_N + h)) [rad/s].
    #[inline(always)]
    fn transport_rate(&self, v: Vec3) -> Vec3 {
        let e = v[0] * self.inv_rn_h;
        [-v[1] * self.inv_rm_h, e, e * self.tan_lat]
    }
}

/// Coning and sculling, one-plus-previous-sample algorithm (PSINS `cnscl` with one sample).
/// Returns (phi \[rad\], dv_b [m/s]): the body rotation vector and the rotation- and sculling-compensated
/// velocity increment, both in the body frame at the start of the sample.
#[inline(always)]
pub fn coning_sculling(dtheta: Vec3, dv: Vec3, dtheta_prev: Vec3, dv_prev: Vec3) -> (Vec3, Vec3) {
    let c = scale(dtheta_prev, 1.0 / 12.0);
    let phi = add(dtheta, cross(c, dtheta));
    let rot = scale(cross(dtheta, dv), 0.5);
    let scul = add(cross(c, dv), cross(scale(dv_prev, 1.0 / 12.0), dtheta));
    (phi, add(dv, add(rot, scul)))
}

/// Check per-sample values: each finite and within `[lo, hi]` (the first bad one is named by its 0-based sample
/// index and `key`).
fn check_per_sample(key: &'static str, what: &str, x: &[f64], lo: f64, hi: f64, unit: Unit) -> Result<(), CoreError> {
    match x.iter().position(|v| !(lo..=hi).contains(v)) {
        None => Ok(()),
        Some(index) => Err(CoreError::Sample {
            key,
            index,
            message: format!(
                "{what} {} must be finite and within [{}, {}]",
                unit.show(x[index]),
                unit.show(lo),
                unit.show(hi)
            ),
        }),
    }
}

/// Check reference heights \[m\]: finite and within the height limits of `limits`.
fn check_reference_heights(h: &[f64]) -> Result<(), CoreError> {
    check_per_sample(
        "reference_height_m",
        "reference height",
        h,
        MIN_HEIGHT_M,
        MAX_HEIGHT_M,
        Unit::Si("m"),
    )
}

/// The per-sample values `x[first..first + n]` of a block of samples when `given`, else none.
fn block_of(x: &[f64], given: bool, first: usize, n: usize) -> &[f64] {
    if given {
        &x[first..first + n]
    } else {
        &x[..0]
    }
}

/// Per-sample inputs of `Navigator::process_with`, one value per sample when given.
#[derive(Clone, Copy, Debug, Default)]
pub struct SampleInputs<'a> {
    /// Reference height of the damped vertical channel at the end of each sample \[m\].
    pub reference_height_m: Option<&'a [f64]>,
    /// Axial (z) gyro bias estimate subtracted from each sample [rad/s] (replaces `gyro_bias[2]`).
    pub axial_bias_rad_s: Option<&'a [f64]>,
}

/// The strapdown navigator (see the module docs).
#[derive(Clone, Debug)]
pub struct Navigator {
    cfg: NavigatorConfig,
    dt: f64,
    /// Samples processed since the start of the run.
    k: u64,
    q: Quat,
    vel: Vec3,
    lat: f64,
    lon: f64,
    height: f64,
    earth: EarthTerms,
    dtheta_prev: Vec3,
    dv_prev: Vec3,
    gyro_bias: Vec3,
    accel_bias: Vec3,
    /// The bias estimates times dt: what is subtracted from every sample's increments [rad], [m/s].
    gyro_bias_dt: Vec3,
    accel_bias_dt: Vec3,
    k1: f64,
    k2: f64,
    /// Reference height of the damped vertical channel \[m\].
    h_ref: f64,
    /// Largest |dtheta| [rad] and |dv| [m/s] of one sample (`limits` rate and specific-force limits times dt).
    max_dtheta: f64,
    max_dv: f64,
}

impl Navigator {
    pub fn new(cfg: NavigatorConfig) -> Result<Self, CoreError> {
        cfg.validate()?;
        let earth = EarthTerms::at(cfg.lat, cfg.height);
        let mut vel = cfg.vel;
        if cfg.vertical == Vertical::Fixed {
            vel[2] = 0.0;
        }
        Ok(Navigator {
            dt: 1.0 / cfg.rate_hz,
            k: 0,
            q: euler_to_quat(cfg.attitude),
            vel,
            lat: cfg.lat,
            lon: cfg.lon,
            height: cfg.height,
            earth,
            dtheta_prev: [0.0; 3],
            dv_prev: [0.0; 3],
            gyro_bias: [0.0; 3],
            accel_bias: [0.0; 3],
            gyro_bias_dt: [0.0; 3],
            accel_bias_dt: [0.0; 3],
            k1: 2.0 * VERTICAL_ZETA * VERTICAL_OMEGA,
            k2: VERTICAL_OMEGA * VERTICAL_OMEGA + earth.two_g_over_r,
            h_ref: cfg.height,
            max_dtheta: increment_bounds(1.0 / cfg.rate_hz).0,
            max_dv: increment_bounds(1.0 / cfg.rate_hz).1,
            cfg,
        })
    }

    /// Set the estimated gyro bias [rad/s], subtracted from every following sample (measured - estimate).
    pub fn set_gyro_bias(&mut self, b: Vec3) -> Result<(), CoreError> {
        let m = MAX_GYRO_BIAS_RAD_S;
        all_in_range("gyro_bias_rad_s", "gyro bias", &b, -m, m, Unit::DegPerH)?;
        self.gyro_bias = b;
        self.gyro_bias_dt = scale(b, self.dt);
        Ok(())
    }

    /// Set the estimated accelerometer bias [m/s^2], subtracted from every following sample.
    pub fn set_accel_bias(&mut self, b: Vec3) -> Result<(), CoreError> {
        let m = MAX_ACCEL_BIAS_M_S2;
        all_in_range(
            "accel_bias_m_s2",
            "accelerometer bias",
            &b,
            -m,
            m,
            crate::error::MICRO_G,
        )?;
        self.accel_bias = b;
        self.accel_bias_dt = scale(b, self.dt);
        Ok(())
    }

    /// Set the reference height \[m\] of the damped vertical channel for the following samples (the initial
    /// height until then; no effect on the `Fixed` channel). Errors name `reference_height_m`.
    pub fn set_reference_height(&mut self, h: f64) -> Result<(), CoreError> {
        check_reference_heights(&[h])?;
        self.h_ref = h;
        Ok(())
    }

    /// The reference height of the damped vertical channel \[m\].
    pub fn reference_height(&self) -> f64 {
        self.h_ref
    }

    pub fn gyro_bias(&self) -> Vec3 {
        self.gyro_bias
    }

    pub fn accel_bias(&self) -> Vec3 {
        self.accel_bias
    }

    /// Samples processed so far.
    pub fn samples_done(&self) -> u64 {
        self.k
    }

    /// Attitude quaternion q_b^n.
    pub fn quaternion(&self) -> Quat {
        self.q
    }

    /// Closed-loop correction by an estimated navigation error (feedback of an error-state filter).
    ///
    /// `phi` (E, N, U) \[rad\] is the phi angle of the computed navigation frame, the sign of PSINS `qdelphi` and
    /// of `kalman`: the computed C_b^n' = (I - [phi x]) C_b^n, so the true attitude is
    /// C_b^n = (I + [phi x]) C_b^n' to first order, and the correction is q <- q(phi) o q with q(phi) the exact
    /// rotation-vector quaternion. `dv` (E, N, U) [m/s] is the velocity error, computed minus true: v <- v - dv
    /// (with the `Fixed` vertical channel v_U stays zero). Position, time, the previous sample's increments
    /// (the coning/sculling memory), the Earth terms and the bias estimates are kept, so a corrected run goes on
    /// exactly as a run started from the corrected state with the same history.
    pub fn correct(&mut self, phi: Vec3, dv: Vec3) -> Result<(), CoreError> {
        check_with(phi.iter().all(|x| x.is_finite() && x.abs() <= 0.5), "phi", || {
            format!(
                "attitude correction {} must be finite and within +-{}",
                show_all(&phi, Unit::Deg),
                Unit::Deg.show(0.5)
            )
        })?;
        check_with(dv.iter().all(|x| x.is_finite() && x.abs() <= 1000.0), "dv", || {
            format!(
                "velocity correction {} must be finite and within +-1000 m/s",
                show_all(&dv, Unit::Si("m/s"))
            )
        })?;
        self.q = quat_normalize(quat_mul(rotvec_to_quat(phi), self.q));
        self.vel = sub(self.vel, dv);
        if self.cfg.vertical == Vertical::Fixed {
            self.vel[2] = 0.0;
        }
        Ok(())
    }

    /// Current state (Euler angles from q_b^n).
    pub fn state(&self) -> NavState {
        NavState {
            t: self.k as f64 / self.cfg.rate_hz,
            lat: self.lat,
            lon: self.lon,
            height: self.height,
            vel: self.vel,
            attitude: dcm_to_euler(&quat_to_dcm(self.q)),
        }
    }

    /// Velocity update (module docs, step 2): returns the new velocity.
    #[inline(always)]
    fn update_velocity(&self, dv_b: Vec3, zeta: Vec3, w_en: Vec3) -> Vec3 {
        let e = &self.earth;
        let dv_n = quat_rotate(self.q, dv_b);
        let dv_sf = sub(dv_n, scale(cross(zeta, dv_n), 0.5));
        let coriolis = cross(add(e.two_w_ie, w_en), self.vel);
        let dv_gc = scale(sub(e.g_n, coriolis), self.dt);
        let mut v = add(self.vel, add(dv_sf, dv_gc));
        match self.cfg.vertical {
            Vertical::Fixed => v[2] = 0.0,
            Vertical::Damped => v[2] -= self.k2 * (self.height - self.h_ref) * self.dt,
        }
        v
    }

    /// Position update (module docs, step 3) with the mean of the old and new velocity.
    #[inline(always)]
    fn update_position(&mut self, v_old: Vec3, v_new: Vec3) {
        let e = &self.earth;
        let half_dt = 0.5 * self.dt;
        self.lat += (v_old[1] + v_new[1]) * half_dt * e.inv_rm_h;
        self.lon += (v_old[0] + v_new[0]) * half_dt * e.inv_rn_h_cos;
        if self.cfg.vertical == Vertical::Damped {
            self.height += ((v_old[2] + v_new[2]) * half_dt) - self.k1 * (self.height - self.h_ref) * self.dt;
        }
    }

    /// Attitude update (module docs, step 4): q_k = q(-zeta) o q_{k-1} o q(phi).
    #[inline(always)]
    fn update_attitude(&mut self, phi: Vec3, zeta: Vec3) {
        // |zeta| < 1e-6 rad: q(-zeta) = [1 - |zeta|^2 / 8, -zeta / 2] is exact to 1e-26.
        let q_nn = [
            1.0 - 0.125 * dot(zeta, zeta),
            -0.5 * zeta[0],
            -0.5 * zeta[1],
            -0.5 * zeta[2],
        ];
        // Normalised with the Earth terms (`step`), not here: products of unit quaternions keep |q| within a few
        // 1e-16 of 1 over `EARTH_REFRESH` samples (tested), and a norm error e scales the velocity increments by
        // only 1 + 2 e, while normalising every sample lengthens the sample-to-sample dependency chain (8 %).
        self.q = quat_mul(q_nn, quat_mul(self.q, rotvec_to_quat(phi)));
    }

    /// One complete update with one sample's increments (before bias compensation).
    pub fn step(&mut self, dtheta_meas: Vec3, dv_meas: Vec3) {
        self.step_inline(dtheta_meas, dv_meas);
    }

    /// `step`, always inlined: the loop of `run` keeps the state in registers only if it sees the whole update.
    #[inline(always)]
    fn step_inline(&mut self, dtheta_meas: Vec3, dv_meas: Vec3) {
        let dt = self.dt;
        let dtheta = sub(dtheta_meas, self.gyro_bias_dt);
        let dv = sub(dv_meas, self.accel_bias_dt);
        let (phi, dv_b) = coning_sculling(dtheta, dv, self.dtheta_prev, self.dv_prev);
        let w_en = self.earth.transport_rate(self.vel);
        let zeta = scale(add(self.earth.w_ie, w_en), dt);
        let v_new = self.update_velocity(dv_b, zeta, w_en);
        let v_old = self.vel;
        self.update_position(v_old, v_new);
        self.vel = v_new;
        self.update_attitude(phi, zeta);
        self.dtheta_prev = dtheta;
        self.dv_prev = dv;
        self.k += 1;
        if self.k % EARTH_REFRESH == 0 {
            self.earth = EarthTerms::at(self.lat, self.height);
            self.q = quat_normalize(self.q);
        }
    }

    /// Navigate `n` samples given as flat row-major (n x 3) slices; after every sample whose 1-based index
    /// from the start of the run is a multiple of `decimation`, `sink` receives the state.
    ///
    /// Every sample is checked (`limits::check_increments`: equal lengths, finite, within the sensor limits);
    /// a refused chunk leaves the navigator as it was before the call (states already given to `sink` for that
    /// call are to be dropped). If the navigated state is no longer finite
    /// or the latitude reaches a pole, the error is [`CoreError::Diverged`] and the navigator is unusable.
    pub fn process<F: FnMut(&NavState)>(
        &mut self,
        dtheta: &[f64],
        dv: &[f64],
        decimation: u64,
        sink: F,
    ) -> Result<(), CoreError> {
        self.process_impl::<false, false, F>(dtheta, dv, &[], &[], decimation, sink)
    }

    /// `process` with per-sample inputs (`SampleInputs`, one value per sample each):
    /// - `reference_height_m` \[m\]: the damped vertical channel's reference height at the end of every sample,
    ///   finite and within the height limits of `limits`; the last one stays the reference for later calls;
    /// - `axial_bias_rad_s` [rad/s]: the z gyro bias estimate subtracted from every sample (replacing
    ///   `gyro_bias[2]`), finite and within the gyro bias limit; the last one stays the estimate.
    ///
    /// A wrong length or a bad value is an error naming the key (and the sample), and leaves the navigator as it
    /// was. A constant `axial_bias_rad_s` gives the same bits as `set_gyro_bias` with that z bias and `process`.
    pub fn process_with<F: FnMut(&NavState)>(
        &mut self,
        dtheta: &[f64],
        dv: &[f64],
        inputs: SampleInputs<'_>,
        decimation: u64,
        sink: F,
    ) -> Result<(), CoreError> {
        let given = |key: &'static str, x: Option<&[f64]>| match x {
            Some(x) => check_with(3 * x.len() == dtheta.len(), key, || {
                format!("{} values for {} samples", x.len(), dtheta.len() / 3)
            }),
            None => Ok(()),
        };
        given("reference_height_m", inputs.reference_height_m)?;
        given("axial_bias_rad_s", inputs.axial_bias_rad_s)?;
        if let Some(h) = inputs.reference_height_m {
            check_reference_heights(h)?;
        }
        if let Some(b) = inputs.axial_bias_rad_s {
            let m = MAX_GYRO_BIAS_RAD_S;
            check_per_sample("axial_bias_rad_s", "axial gyro bias", b, -m, m, Unit::DegPerH)?;
        }
        let (h, b) = (inputs.reference_height_m, inputs.axial_bias_rad_s);
        let (hs, bs) = (h.unwrap_or(&[]), b.unwrap_or(&[]));
        match (h.is_some(), b.is_some()) {
            (false, false) => self.process_impl::<false, false, F>(dtheta, dv, hs, bs, decimation, sink),
            (true, false) => self.process_impl::<true, false, F>(dtheta, dv, hs, bs, decimation, sink),
            (false, true) => self.process_impl::<false, true, F>(dtheta, dv, hs, bs, decimation, sink),
            (true, true) => self.process_impl::<true, true, F>(dtheta, dv, hs, bs, decimation, sink),
        }
    }

    fn process_impl<const REF: bool, const BIAS: bool, F: FnMut(&NavState)>(
        &mut self,
        dtheta: &[f64],
        dv: &[f64],
        reference_m: &[f64],
        axial_bias: &[f64],
        decimation: u64,
        mut sink: F,
    ) -> Result<(), CoreError> {
        check(decimation >= 1, "decimation", "must be a positive number of samples")?;
        check_lengths(dtheta, dv)?;
        // A refused sample restores the state from before the call (the samples are checked in `run`, block by
        // block, and the block holding a bad value is searched again for the message).
        let saved = self.clone();
        // Samples left until the next output; the samples in between run in `run`, whose code does not depend
        // on the caller's sink.
        let mut left = decimation - self.k % decimation;
        for (i, (block_a, block_b)) in dtheta
            .chunks(3 * CHECK_BLOCK)
            .zip(dv.chunks(3 * CHECK_BLOCK))
            .enumerate()
        {
            let mut bad = false;
            let (first, n) = (i * CHECK_BLOCK, block_a.len() / 3);
            let mut rest = (
                block_a,
                block_b,
                block_of(reference_m, REF, first, n),
                block_of(axial_bias, BIAS, first, n),
            );
            while !rest.0.is_empty() {
                let m = (rest.0.len() / 3).min(usize::try_from(left).unwrap_or(usize::MAX));
                let (a, a_rest) = rest.0.split_at(3 * m);
                let (b, b_rest) = rest.1.split_at(3 * m);
                let (h, h_rest) = rest.2.split_at(if REF { m } else { 0 });
                let (z, z_rest) = rest.3.split_at(if BIAS { m } else { 0 });
                bad |= self.run::<REF, BIAS>(a, b, h, z);
                rest = (a_rest, b_rest, h_rest, z_rest);
                left -= m as u64;
                if left == 0 {
                    sink(&self.state());
                    left = decimation;
                }
            }
            if bad {
                *self = saved;
                // `run` flagged this block with the same bounds, so the full check finds the value.
                check_increments(block_a, block_b, self.dt).map_err(|e| e.offset(i * CHECK_BLOCK))?;
                return Err(CoreError::Sample {
                    key: "dtheta_rad",
                    index: i * CHECK_BLOCK,
                    message: "a value in this block of samples is not finite or beyond the sensor limits".into(),
                });
            }
        }
        if BIAS {
            if let Some(&last) = axial_bias.last() {
                self.gyro_bias[2] = last;
            }
        }
        self.check_state()
    }

    /// The navigated state is finite and off the poles.
    fn check_state(&self) -> Result<(), CoreError> {
        let finite = self.lat.is_finite()
            && self.lon.is_finite()
            && self.height.is_finite()
            && self.vel.iter().all(|v| v.is_finite())
            && self.q.iter().all(|v| v.is_finite());
        if finite && self.lat.abs() < std::f64::consts::FRAC_PI_2 {
            return Ok(());
        }
        Err(CoreError::Diverged {
            key: "dtheta_rad",
            t_s: self.k as f64 / self.cfg.rate_hz,
            message: format!(
                "the navigated state left the Earth (latitude {}, velocity {}): \
                 the increments do not describe a navigable motion",
                Unit::Deg.show(self.lat),
                show_all(&self.vel, Unit::Si("m/s"))
            ),
        })
    }

    /// Navigate all samples of the slices (no output). Returns true if some value is not finite or beyond
    /// the sensor limits (`limits::check_increments`, checked here while the values are in registers: the
    /// comparisons run beside the update at no measurable cost, where a separate pass cost 6 %); the caller
    /// then restores its saved state.
    /// With `REF`, `reference_m` holds the reference height of each sample (already checked), set before its
    /// update; with `BIAS`, `axial_bias` holds the z gyro bias of each sample [rad/s] (already checked).
    #[inline(never)]
    fn run<const REF: bool, const BIAS: bool>(
        &mut self,
        dtheta: &[f64],
        dv: &[f64],
        reference_m: &[f64],
        axial_bias: &[f64],
    ) -> bool {
        // A local copy lets the state stay in registers for the whole loop.
        let mut nav = self.clone();
        let (lim_a, lim_b) = (self.max_dtheta, self.max_dv);
        let mut bad = false;
        let mut sample = |nav: &mut Navigator, k: usize, a: &[f64], b: &[f64]| {
            // |x| <= limit is false for NaN: one comparison per value checks both.
            bad |= !((a[0].abs() <= lim_a) & (a[1].abs() <= lim_a) & (a[2].abs() <= lim_a))
                | !((b[0].abs() <= lim_b) & (b[1].abs() <= lim_b) & (b[2].abs() <= lim_b));
            if REF {
                nav.h_ref = reference_m[k];
            }
            nav.step_inline([a[0], a[1], a[2]], [b[0], b[1], b[2]]);
        };
        let samples = dtheta.chunks_exact(3).zip(dv.chunks_exact(3)).enumerate();
        if BIAS {
            // Zipped with the samples (no index to check); the product `set_gyro_bias` forms (`scale`), so a
            // constant bias gives the same bits.
            for ((k, (a, b)), z) in samples.zip(axial_bias) {
                nav.gyro_bias_dt[2] = z * nav.dt;
                sample(&mut nav, k, a, b);
            }
        } else {
            for (k, (a, b)) in samples {
                sample(&mut nav, k, a, b);
            }
        }
        *self = nav;
        bad
    }
}

#[cfg(test)]
mod tests;
