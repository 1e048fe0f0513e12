//! IMU simulator of a static base with a single-axis turntable: exact true increments plus the error model.
//!
//! Truth (ENU navigation frame n fixed to the Earth at the site, body b Right-Forward-Up):
//! - attitude C_b^n(t) = C_b0^n Rz(alpha(t)), C_b0^n = Rz(yaw0) Rx(pitch0) Ry(roll0), alpha = table angle
//!   (see `turntable`);
//! - angular rate w_ib^b = C_n^b w_ie^n + alpha'(t) e_z  (the base does not move: w_en^n = 0);
//! - specific force f^b = C_n^b (0, 0, g)   (static: f^n = -g^n, g = normal gravity of `earth`).
//!
//! Increments over sample k, [t_{k-1}, t_k], t_k = k / rate_hz:
//!     dtheta = int w_ib^b dt = [ Ic u_x + Is u_y,  -Is u_x + Ic u_y,  u_z dt + alpha(t_k) - alpha(t_{k-1}) ],
//!     dv     = int f^b dt    = [ Ic a_x + Is a_y,  -Is a_x + Ic a_y,  a_z dt ],
//! with u = C_n^b0 w_ie^n, a = C_n^b0 (0, 0, g) and Ic = int cos(alpha) dt, Is = int sin(alpha) dt (because
//! C_n^b = Rz(alpha)' C_n^b0). The table term is exact; Ic, Is use two-point Gauss-Legendre quadrature, whose
//! error (alpha' dt)^4 / 4320 relative is below 1e-16 at any realistic table rate and sample rate.
//! These are the integrals a real gyro and accelerometer deliver, so the navigator's coning, sculling and
//! rotation compensations reproduce zero velocity: nothing is sampled at a single instant.
//!
//! The error model (`imu_error`) is then applied (its deterministic terms per sample, its random terms in a
//! second pass over blocks of samples, in the same draw order); the temperature drift uses the temperature and its rate
//! at the middle of the sample. Output times are the end times t_k. Streaming: `next_chunk` produces the next
//! samples into reusable buffers and keeps all state, so a run of any length uses constant memory.
//!
//! Here the driver ([`ImuSimulator`]: per sample the true increments, the temperature and the error model); in
//! `config` the settings, in `chunk` the output buffers, in `table` the static base's increments, in `moving`
//! the moving base's, in `truth_attitude` the true attitude, in `series` the small-angle series they share.

mod chunk;
mod config;
mod moving;
mod series;
mod table;
#[cfg(test)]
mod tests;
mod truth_attitude;

pub use chunk::{ImuChunk, ImuChunkSlices, TruthSlices, MAX_CHUNK_SAMPLES};
pub use config::{ImuSimulatorConfig, MIN_SAMPLES_PER_PERIOD};

use crate::attitude::{euler_to_dcm, mat_t_vec, Mat3, Vec3};
use crate::earth;
use crate::error::{check_with, CoreError};
use crate::imu_error::ImuErrorModel;
use crate::temperature::TemperatureProfile;
use crate::turntable::{TableCursor, Turntable};
use moving::Moving;
use table::Uniform;

/// exp(-dt / tau) of a warm-up profile over `dt` \[s\] (1 for a series: no recurrence).
fn tau_decay(p: &TemperatureProfile, dt: f64) -> f64 {
    match p {
        TemperatureProfile::WarmUp { tau_s, .. } => (-dt / tau_s).exp(),
        TemperatureProfile::Series { .. } => 1.0,
    }
}

/// (sin, cos) of the angle of a warm-up's daily swing at time `t` \[s\] (`from_start`: with its phase, else
/// the angle it advances over `t`); (0, 1) for a series.
fn swing_sin_cos(p: &TemperatureProfile, t: f64, from_start: bool) -> (f64, f64) {
    match p {
        TemperatureProfile::WarmUp { swing, .. } => {
            (swing.omega() * t + if from_start { swing.phase_rad } else { 0.0 }).sin_cos()
        }
        TemperatureProfile::Series { .. } => (0.0, 1.0),
    }
}

/// The angle whose (sin, cos) is `a` advanced by the angle whose (sin, cos) is `b`.
#[inline(always)]
fn rotate(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 * b.1 + a.1 * b.0, a.1 * b.1 - a.0 * b.0)
}

/// The simulator (see the module docs).
#[derive(Clone, Debug)]
pub struct ImuSimulator {
    cfg: ImuSimulatorConfig,
    dt: f64,
    n_samples: u64,
    /// Samples produced so far.
    k: u64,
    c_b0n: Mat3,
    /// C_n^b0 w_ie^n [rad/s].
    u_w: Vec3,
    /// C_n^b0 (0, 0, g) [m/s^2].
    u_f: Vec3,
    level: bool,
    table: Turntable,
    errors: ImuErrorModel,
    cursor: TableCursor,
    /// Table angle at the end of the previous sample [rad], its sine and cosine.
    alpha: f64,
    sin_alpha: f64,
    cos_alpha: f64,
    /// Rotation constants of the current constant-rate table segment.
    uniform: Uniform,
    /// 1 / C_b^n[2][2] (= 1 / (cos pitch0 cos roll0), unchanged by the table rotation).
    inv_c22: f64,
    /// (sin, cos) of the initial yaw.
    sincos_yaw0: (f64, f64),
    /// Warm-up recurrence: exp(-t_k / tau) at the last sample, exp(-dt / tau), exp(-dt / (2 tau)).
    decay: f64,
    decay_step: f64,
    decay_half: f64,
    /// Daily swing recurrence: (sin, cos) of its angle at the last sample, over dt and over dt / 2.
    swing_sc: (f64, f64),
    swing_step: (f64, f64),
    swing_half: (f64, f64),
    /// Moving base (None: static base).
    moving: Option<Moving>,
}
impl ImuSimulator {
    pub fn new(cfg: ImuSimulatorConfig) -> Result<Self, CoreError> {
        cfg.validate()?;
        let table = Turntable::new(cfg.scheme.clone())?;
        let dt = 1.0 / cfg.rate_hz;
        let errors = ImuErrorModel::new(cfg.errors.clone(), dt, cfg.seed)?;
        let c_b0n = euler_to_dcm(cfg.attitude);
        let g = earth::normal_gravity(cfg.lat, cfg.height);
        let u_w = mat_t_vec(&c_b0n, earth::earth_rate_enu(cfg.lat));
        let u_f = mat_t_vec(&c_b0n, [0.0, 0.0, g]);
        let moving = match &cfg.trajectory {
            None => None,
            Some(route) => Some(Moving::new(route, &cfg)?),
        };
        Ok(ImuSimulator {
            moving,
            n_samples: (cfg.duration_s * cfg.rate_hz).round() as u64,
            level: cfg.attitude.pitch == 0.0 && cfg.attitude.roll == 0.0,
            dt,
            k: 0,
            c_b0n,
            u_w,
            u_f,
            table,
            errors,
            cursor: TableCursor::default(),
            sincos_yaw0: cfg.attitude.yaw.sin_cos(),
            alpha: 0.0,
            sin_alpha: 0.0,
            cos_alpha: 1.0,
            uniform: Uniform::new(f64::NAN, dt),
            inv_c22: 1.0 / c_b0n[2][2],
            decay: 1.0,
            decay_step: tau_decay(&cfg.temperature, dt),
            decay_half: tau_decay(&cfg.temperature, 0.5 * dt),
            swing_sc: swing_sin_cos(&cfg.temperature, 0.0, true),
            swing_step: swing_sin_cos(&cfg.temperature, dt, false),
            swing_half: swing_sin_cos(&cfg.temperature, 0.5 * dt, false),
            cfg,
        })
    }

    /// Total number of samples of the run.
    pub fn n_samples(&self) -> u64 {
        self.n_samples
    }

    /// Samples produced so far.
    pub fn samples_done(&self) -> u64 {
        self.k
    }

    pub fn config(&self) -> &ImuSimulatorConfig {
        &self.cfg
    }

    /// The turntable profile.
    pub fn turntable(&self) -> &Turntable {
        &self.table
    }

    /// Sample interval \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Temperature [deg C] at t_k and, if needed, temperature and rate at the middle of the sample.
    #[inline]
    fn temperature(&mut self, k: u64, t1: f64, need_mid: bool) -> (f64, (f64, f64)) {
        match self.cfg.temperature {
            TemperatureProfile::WarmUp {
                start_c,
                end_c,
                tau_s,
                swing,
            } => {
                if start_c == end_c && swing.amplitude_c == 0.0 {
                    return (end_c, (end_c, 0.0));
                }
                // e_k = exp(-t_k / tau) and the swing's (sin, cos) by recurrence, exact every SINCOS_RESYNC
                // samples.
                let resync = k % SINCOS_RESYNC == 0;
                let e_prev = self.decay;
                let e1 = if resync {
                    (-t1 / tau_s).exp()
                } else {
                    e_prev * self.decay_step
                };
                self.decay = e1;
                let d = start_c - end_c;
                let (mut temp, mut mid) = (end_c + d * e1, (0.0, 0.0));
                if need_mid {
                    let em = e_prev * self.decay_half;
                    mid = (end_c + d * em, -d / tau_s * em);
                }
                if swing.amplitude_c != 0.0 {
                    let sc_prev = self.swing_sc;
                    self.swing_sc = if resync {
                        (swing.omega() * t1 + swing.phase_rad).sin_cos()
                    } else {
                        rotate(sc_prev, self.swing_step)
                    };
                    temp += swing.from_sin_cos(self.swing_sc.0, self.swing_sc.1).0;
                    if need_mid {
                        let (sm, cm) = rotate(sc_prev, self.swing_half);
                        let (ts, rs) = swing.from_sin_cos(sm, cm);
                        mid = (mid.0 + ts, mid.1 + rs);
                    }
                }
                (temp, mid)
            }
            TemperatureProfile::Series { .. } => {
                let mid = if need_mid {
                    self.cfg.temperature.at(t1 - 0.5 * self.dt)
                } else {
                    (0.0, 0.0)
                };
                (self.cfg.temperature.at(t1).0, mid)
            }
        }
    }

    /// Produce the next at most `n` samples into `out` (cleared first). Returns the number produced;
    /// 0 means the run is over.
    pub fn next_chunk(&mut self, n: usize, out: &mut ImuChunk) -> usize {
        let m = self.remaining().min(n as u64) as usize;
        out.resize(m);
        out.resize_truth(if self.moving.is_some() { m } else { 0 });
        let truth = self.moving.is_some().then_some(TruthSlices {
            lat: &mut out.lat,
            lon: &mut out.lon,
            height: &mut out.height,
            vel: &mut out.vel,
        });
        let slices = ImuChunkSlices {
            t_s: &mut out.t_s,
            dtheta: &mut out.dtheta,
            dv: &mut out.dv,
            temp_c: &mut out.temp_c,
            table_angle: &mut out.table_angle,
            pitch: &mut out.pitch,
            roll: &mut out.roll,
            yaw: &mut out.yaw,
            truth,
        };
        // Invariant: `resize` gave every buffer m samples (3 m values for dtheta and dv).
        self.fill(slices).expect("buffers sized by resize")
    }

    /// The number of samples the next chunk of at most `n` samples holds (the samples remaining, if fewer),
    /// after checking `n` against [`MAX_CHUNK_SAMPLES`] so that a caller never allocates more than that.
    pub fn chunk_len(&self, n: u64) -> Result<usize, CoreError> {
        check_with((1..=MAX_CHUNK_SAMPLES).contains(&n), "n", || {
            format!("a chunk of {n} samples is outside [1, {MAX_CHUNK_SAMPLES}] samples (12 float64 values each)")
        })?;
        // Bounded by MAX_CHUNK_SAMPLES, which fits usize on every supported platform (>= 32 bits).
        Ok(self.remaining().min(n) as usize)
    }

    /// Samples not produced yet.
    pub fn remaining(&self) -> u64 {
        self.n_samples - self.k
    }

    /// Produce the next samples into caller-provided buffers (e.g. numpy arrays): as many as `out.t_s.len()`
    /// or the samples remaining, whichever is smaller. Returns the number produced. Every slice must hold at
    /// least that many samples (x 3 for `dtheta` and `dv`).
    pub fn fill(&mut self, mut out: ImuChunkSlices<'_>) -> Result<usize, CoreError> {
        let m = self.remaining().min(out.t_s.len() as u64) as usize;
        let short = [
            ("dtheta_rad", out.dtheta.len(), 3 * m),
            ("dv_m_s", out.dv.len(), 3 * m),
            ("temp_c", out.temp_c.len(), m),
            ("table_angle_rad", out.table_angle.len(), m),
            ("pitch_rad", out.pitch.len(), m),
            ("roll_rad", out.roll.len(), m),
            ("yaw_rad", out.yaw.len(), m),
        ]
        .into_iter()
        .find(|(_, len, need)| len < need);
        let short_truth = out.truth.as_ref().and_then(|tr| {
            [
                ("lat_rad", tr.lat.len(), m),
                ("lon_rad", tr.lon.len(), m),
                ("height_m", tr.height.len(), m),
                ("vel_enu_m_s", tr.vel.len(), 3 * m),
            ]
            .into_iter()
            .find(|(_, len, need)| len < need)
        });
        if let Some((key, len, need)) = short.or(short_truth) {
            return Err(CoreError::Shape {
                key,
                message: format!("output buffer holds {len} values, {need} needed for {m} samples"),
            });
        }
        if self.moving.is_some() {
            return Ok(self.fill_moving(out, m));
        }
        let temp_drift = self.errors.params().has_temperature_drift();
        let rate = self.cfg.rate_hz;
        let mut t0 = self.k as f64 / rate;
        // Blocks that stay in cache: the first pass produces the increments and parks sin/cos of the table
        // angle in the pitch/roll outputs; the second turns them into the attitude. The second pass has no
        // dependence between samples, so the processor overlaps its long polynomial chains.
        for start in (0..m).step_by(ATTITUDE_BLOCK) {
            let end = (start + ATTITUDE_BLOCK).min(m);
            for i in start..end {
                let k = self.k + 1;
                let t1 = k as f64 / rate;
                let increments = self.true_increments(k, t0, t1);
                self.write_sample(&mut out, i, k, t1, temp_drift, increments);
                t0 = t1;
            }
            // Third pass: the random terms, a tight loop around the generator.
            self.errors
                .add_noise(&mut out.dtheta[3 * start..3 * end], &mut out.dv[3 * start..3 * end]);
            self.attitudes(
                &out.table_angle[start..end],
                &mut out.pitch[start..end],
                &mut out.roll[start..end],
                &mut out.yaw[start..end],
            );
        }
        Ok(m)
    }
}

impl ImuSimulator {
    /// The first pass of `fill` for sample `i` (sample `k` of the run, ending at `t1` \[s\]) from its true
    /// `increments`: the temperature (and the axial drift it drives when `temp_drift`), the deterministic errors,
    /// then the time, the increments, the temperature and the table angle written out, the angle's sine and
    /// cosine parked in the pitch and roll outputs for the attitude pass; the run advances to sample `k`.
    #[inline(always)]
    pub(super) fn write_sample(
        &mut self,
        out: &mut ImuChunkSlices<'_>,
        i: usize,
        k: u64,
        t1: f64,
        temp_drift: bool,
        increments: (Vec3, Vec3),
    ) {
        let (mut dth, mut dv) = increments;
        let (temp, (temp_mid, rate_mid)) = self.temperature(k, t1, temp_drift);
        let drift = if temp_drift {
            self.errors.params().axial_drift(temp_mid, rate_mid)
        } else {
            0.0
        };
        self.errors.apply_deterministic(drift, &mut dth, &mut dv);
        out.t_s[i] = t1;
        out.dtheta[3 * i..3 * i + 3].copy_from_slice(&dth);
        out.dv[3 * i..3 * i + 3].copy_from_slice(&dv);
        out.temp_c[i] = temp;
        out.table_angle[i] = self.alpha;
        out.pitch[i] = self.sin_alpha;
        out.roll[i] = self.cos_alpha;
        self.k = k;
    }
}

/// Samples per block of the two passes of `fill`.
pub(super) const ATTITUDE_BLOCK: usize = 512;

/// Samples between exact evaluations of recurrences (table sine/cosine, warm-up exponential).
pub(super) const SINCOS_RESYNC: u64 = 256;
