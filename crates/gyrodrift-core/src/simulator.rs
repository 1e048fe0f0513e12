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

use crate::attitude::{dcm_to_euler, euler_to_dcm, mat_mul, mat_t_vec, Euler, Mat3, Vec3};
use crate::earth;
use crate::error::{check, CoreError};
use crate::imu_error::{ImuErrorModel, ImuErrorParams};
use crate::limits::{check_attitude, check_duration, check_site};
use crate::temperature::TemperatureProfile;
use crate::trajectory::{check_route_latitude, position_rate, Motion, Trajectory, TrajectoryConfig};
use crate::turntable::{RotationScheme, TableCursor, Turntable};

/// Everything that defines a simulated static run (SI units).
#[derive(Clone, Debug, PartialEq)]
pub struct ImuSimulatorConfig {
    /// Geodetic latitude \[rad\], longitude \[rad\], height above the ellipsoid \[m\].
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    /// Sample rate \[Hz\].
    pub rate_hz: f64,
    /// Length of the run \[s\]; the run has round(duration_s * rate_hz) samples.
    pub duration_s: f64,
    /// Seed of the single random generator.
    pub seed: u64,
    /// Body attitude at table angle zero.
    pub attitude: Euler,
    pub scheme: RotationScheme,
    pub errors: ImuErrorParams,
    pub temperature: TemperatureProfile,
    /// Moving base: the vehicle's route (`trajectory`); None for a static base. With a route, `attitude` is
    /// the IMU's attitude relative to the vehicle's level heading frame at table angle 0 (pitch, roll: the
    /// mounting tilt) and `attitude.yaw` the vehicle's initial yaw.
    pub trajectory: Option<TrajectoryConfig>,
}

impl Default for ImuSimulatorConfig {
    fn default() -> Self {
        ImuSimulatorConfig {
            lat: 28.222f64.to_radians(),
            lon: 0.0,
            height: 0.0,
            rate_hz: 100.0,
            duration_s: 3600.0,
            seed: 0,
            attitude: Euler::default(),
            scheme: RotationScheme::None,
            errors: ImuErrorParams::default(),
            temperature: TemperatureProfile::WarmUp {
                start_c: 20.0,
                end_c: 20.0,
                tau_s: 3600.0,
            },
            trajectory: None,
        }
    }
}

impl ImuSimulatorConfig {
    /// Range checks; errors name the contract key.
    pub fn validate(&self) -> Result<(), CoreError> {
        check_site(self.lat, self.lon, self.height, self.rate_hz)?;
        check_duration(self.duration_s, self.rate_hz)?;
        check_attitude(self.attitude)?;
        self.errors.validate()?;
        self.temperature.validate()?;
        check_period(&Turntable::new(self.scheme.clone())?, 1.0 / self.rate_hz)?;
        if let Some(route) = &self.trajectory {
            let traj = Trajectory::new(route, self.attitude.yaw, self.height, self.duration_s)?;
            check_route_latitude(&traj, self.lat, self.attitude.yaw, self.duration_s)?;
        }
        Ok(())
    }
}

/// Most samples of one chunk handed to a caller (2^24: 1.5 GiB of output arrays).
pub const MAX_CHUNK_SAMPLES: u64 = 1 << 24;

/// Fewest samples per period of a periodic table profile.
pub const MIN_SAMPLES_PER_PERIOD: f64 = 10.0;

/// A periodic table profile must last at least `MIN_SAMPLES_PER_PERIOD` samples: a table that reverses
/// faster than the IMU samples is no turntable (and its profile would be walked segment by segment for
/// every sample, e.g. a 1e-300 deg span would run for hours).
fn check_period(table: &Turntable, dt: f64) -> Result<(), CoreError> {
    let period = table.period();
    if period == 0.0 || period >= MIN_SAMPLES_PER_PERIOD * dt {
        return Ok(());
    }
    let (key, what) = match table.scheme() {
        RotationScheme::Indexing { .. } => ("positions_rad", "indexing cycle"),
        _ => ("reciprocating_span_rad", "reciprocating period"),
    };
    check(
        false,
        key,
        format!(
            "the {what} of {} s is shorter than {MIN_SAMPLES_PER_PERIOD} samples ({} s at {} Hz): \
             the moves are too small",
            crate::error::sig(period),
            crate::error::sig(MIN_SAMPLES_PER_PERIOD * dt),
            crate::error::sig(1.0 / dt)
        ),
    )
}

/// A chunk of simulated samples (flat buffers, reused between calls).
#[derive(Clone, Debug, Default)]
pub struct ImuChunk {
    /// End time of each sample \[s\].
    pub t_s: Vec<f64>,
    /// Angle increments \[rad\], body x y z, flattened row-major (n x 3).
    pub dtheta: Vec<f64>,
    /// Velocity increments [m/s], body x y z, flattened row-major (n x 3).
    pub dv: Vec<f64>,
    /// Temperature at the end of each sample [deg C].
    pub temp_c: Vec<f64>,
    /// Table angle at the end of each sample \[rad\] (unwrapped, CCW about body Up).
    pub table_angle: Vec<f64>,
    /// True attitude at the end of each sample \[rad\].
    pub pitch: Vec<f64>,
    pub roll: Vec<f64>,
    pub yaw: Vec<f64>,
    /// Moving base only (empty for a static base): true position at the end of each sample (lat, lon \[rad\],
    /// height \[m\]) and true velocity [m/s], ENU, flattened row-major (n x 3).
    pub lat: Vec<f64>,
    pub lon: Vec<f64>,
    pub height: Vec<f64>,
    pub vel: Vec<f64>,
}

impl ImuChunk {
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Set every buffer to n samples (contents are overwritten by the simulator).
    fn resize(&mut self, n: usize) {
        for v in [
            &mut self.t_s,
            &mut self.temp_c,
            &mut self.table_angle,
            &mut self.pitch,
            &mut self.roll,
            &mut self.yaw,
        ] {
            v.resize(n, 0.0);
        }
        self.dtheta.resize(3 * n, 0.0);
        self.dv.resize(3 * n, 0.0);
    }

    /// Size the moving-base truth buffers to n samples (0 for a static base).
    fn resize_truth(&mut self, n: usize) {
        for v in [&mut self.lat, &mut self.lon, &mut self.height] {
            v.resize(n, 0.0);
        }
        self.vel.resize(3 * n, 0.0);
    }
}

/// Caller-provided moving-base truth buffers (same meaning as the fields of [`ImuChunk`]).
#[derive(Debug)]
pub struct TruthSlices<'a> {
    pub lat: &'a mut [f64],
    pub lon: &'a mut [f64],
    pub height: &'a mut [f64],
    pub vel: &'a mut [f64],
}

/// Caller-provided output buffers for [`ImuSimulator::fill`] (same meaning as the fields of [`ImuChunk`]).
#[derive(Debug)]
pub struct ImuChunkSlices<'a> {
    pub t_s: &'a mut [f64],
    pub dtheta: &'a mut [f64],
    pub dv: &'a mut [f64],
    pub temp_c: &'a mut [f64],
    pub table_angle: &'a mut [f64],
    pub pitch: &'a mut [f64],
    pub roll: &'a mut [f64],
    pub yaw: &'a mut [f64],
    /// Moving base: where to write the true position and velocity (None: not wanted).
    pub truth: Option<TruthSlices<'a>>,
}

/// Two-point Gauss-Legendre nodes on [0, 1]: 1/2 -+ 1/(2 sqrt 3).
const GL2_LO: f64 = 0.5 - 0.288_675_134_594_812_9;
const GL2_HI: f64 = 0.5 + 0.288_675_134_594_812_9;

fn tau_decay(p: &TemperatureProfile, dt: f64) -> f64 {
    match p {
        TemperatureProfile::WarmUp { tau_s, .. } => (-dt / tau_s).exp(),
        TemperatureProfile::Series { .. } => 1.0,
    }
}

/// Constants of a sample during which the table turns at a constant rate w (cruise or dwell): with
/// d_lo, d_hi = w dt x (Gauss-Legendre nodes) and D = w dt,
///     Ic = a cos(alpha0) - b sin(alpha0),  Is = a sin(alpha0) + b cos(alpha0),
///     a = dt/2 (cos d_lo + cos d_hi),  b = dt/2 (sin d_lo + sin d_hi),
/// and (sin, cos)(alpha0 + D) by the addition theorem: no per-sample table evaluation at the nodes and no
/// series. Same quadrature as the general path, so the same increments to rounding (1e-16 relative).
#[derive(Clone, Copy, Debug)]
struct Uniform {
    rate: f64,
    /// The current uniform segment: absolute start and end times [s] (end -inf: none cached), angle at
    /// the start [rad].
    start: f64,
    end: f64,
    angle0: f64,
    a: f64,
    b: f64,
    sin_d: f64,
    cos_d: f64,
}

impl Uniform {
    fn new(rate: f64, dt: f64) -> Self {
        let (s_lo, c_lo) = (rate * GL2_LO * dt).sin_cos();
        let (s_hi, c_hi) = (rate * GL2_HI * dt).sin_cos();
        let (sin_d, cos_d) = (rate * dt).sin_cos();
        let (start, end, angle0) = (0.0, f64::NEG_INFINITY, 0.0);
        Uniform {
            rate,
            start,
            end,
            angle0,
            a: 0.5 * dt * (c_lo + c_hi),
            b: 0.5 * dt * (s_lo + s_hi),
            sin_d,
            cos_d,
        }
    }
}

/// State of the moving-base path: the route, its cursor, the true position and its rate at the end of the
/// last sample, and the mounting C_0 = Rx(pitch0) Ry(roll0) (IMU at table angle 0 in the vehicle frame).
#[derive(Clone, Debug)]
struct Moving {
    traj: Trajectory,
    cursor: usize,
    pos: [f64; 2],
    pos_rate: [f64; 2],
    /// sin and cos of the latitude `pos[0]`.
    sin_lat: f64,
    cos_lat: f64,
    /// The vehicle's yaw \[rad\] at the end of the last part, its sine and cosine.
    yaw_sc: (f64, f64, f64),
    c0: Mat3,
}

/// One moving-base sample: the true increments and, at its end, the vehicle's yaw \[rad\], height \[m\] and
/// ENU velocity [m/s].
#[derive(Clone, Copy, Debug)]
struct MovingSample {
    dtheta: Vec3,
    dv: Vec3,
    yaw: f64,
    height: f64,
    vel: Vec3,
}

/// The vehicle's motion at one time, with the sine and cosine of its yaw.
#[derive(Clone, Copy, Debug)]
struct MotionState {
    yaw: f64,
    sin_yaw: f64,
    cos_yaw: f64,
    height: f64,
    /// ENU velocity [m/s] and its time derivative [m/s^2].
    vel: Vec3,
    accel: Vec3,
}

/// The state of motion `m` at `t` \[s\], the sine and cosine of the yaw from `yaw_ref` = (yaw, sin, cos) at a
/// nearby time by the addition theorem (`rotate`).
#[inline(always)]
fn motion_state(m: &Motion, t: f64, yaw_ref: (f64, f64, f64)) -> MotionState {
    let yaw = m.yaw(t);
    let (sp, cp) = rotate(yaw_ref.1, yaw_ref.2, yaw - yaw_ref.0);
    let speed = m.speed(t);
    let (height, vu, au) = m.vertical(t);
    let vr = speed * m.yaw_rate;
    MotionState {
        yaw,
        sin_yaw: sp,
        cos_yaw: cp,
        height,
        vel: [-speed * sp, speed * cp, vu],
        accel: [-m.accel * sp - vr * cp, m.accel * cp - vr * sp, au],
    }
}

/// Three-point Gauss-Legendre nodes on [0, 1] and weights (exact for polynomials of degree 5).
const GL3: [(f64, f64); 3] = [
    (0.5 - 0.387_298_334_620_741_7, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.5 + 0.387_298_334_620_741_7, 5.0 / 18.0),
];

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
            Some(route) => {
                let traj = Trajectory::new(route, cfg.attitude.yaw, cfg.height, cfg.duration_s)?;
                let mut cursor = 0;
                let v = traj.at(&mut cursor, 0.0, cfg.attitude.yaw).vel_enu();
                Some(Moving {
                    pos: [cfg.lat, cfg.lon],
                    sin_lat: cfg.lat.sin(),
                    cos_lat: cfg.lat.cos(),
                    yaw_sc: (cfg.attitude.yaw, cfg.attitude.yaw.sin(), cfg.attitude.yaw.cos()),
                    pos_rate: position_rate(cfg.lat, cfg.height, v),
                    traj,
                    cursor,
                    c0: euler_to_dcm(Euler {
                        yaw: 0.0,
                        ..cfg.attitude
                    }),
                })
            }
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

    /// True increments (dtheta [rad], dv [m/s]) of sample k (1-based, ending at t_k = k dt); advances the
    /// table state (angle and its sine/cosine at t_k).
    #[inline]
    fn true_increments(&mut self, k: u64, t0: f64, t1: f64) -> (Vec3, Vec3) {
        let dt = self.dt;
        let (u, a) = (self.u_w, self.u_f);
        if self.table.is_static() {
            return ([u[0] * dt, u[1] * dt, u[2] * dt], [a[0] * dt, a[1] * dt, a[2] * dt]);
        }
        let alpha0 = self.alpha;
        let (s0, c0) = (self.sin_alpha, self.cos_alpha);
        if t1 <= self.uniform.end || self.enter_uniform(t0, t1) {
            // Constant table rate over the whole sample: the node and end angles are alpha0 plus fixed
            // offsets, so their sines and cosines follow from (s0, c0) by fixed rotations (see `Uniform`).
            let w = &self.uniform;
            // The segment's closed form (what `Turntable::state_at` evaluates, without the segment search).
            let alpha1 = w.angle0 + w.rate * (t1 - w.start);
            let ic = w.a * c0 - w.b * s0;
            let is = w.a * s0 + w.b * c0;
            let (s1, c1) = if k % SINCOS_RESYNC == 0 {
                alpha1.sin_cos()
            } else {
                (s0 * w.cos_d + c0 * w.sin_d, c0 * w.cos_d - s0 * w.sin_d)
            };
            self.alpha = alpha1;
            self.sin_alpha = s1;
            self.cos_alpha = c1;
            return (
                [
                    ic * u[0] + is * u[1],
                    -is * u[0] + ic * u[1],
                    u[2] * dt + (alpha1 - alpha0),
                ],
                [ic * a[0] + is * a[1], -is * a[0] + ic * a[1], a[2] * dt],
            );
        }
        let a_lo = self.table.state_at(&mut self.cursor, t0 + GL2_LO * dt).angle;
        let a_hi = self.table.state_at(&mut self.cursor, t0 + GL2_HI * dt).angle;
        let alpha1 = self.table.state_at(&mut self.cursor, t1).angle;
        // sin/cos at the nodes by the addition theorem from the start of the sample (small angles by series).
        let (s_lo, c_lo) = rotate(s0, c0, a_lo - alpha0);
        let (s_hi, c_hi) = rotate(s0, c0, a_hi - alpha0);
        let ic = 0.5 * dt * (c_lo + c_hi);
        let is = 0.5 * dt * (s_lo + s_hi);
        // Exact re-synchronisation every SINCOS_RESYNC samples bounds the rounding random walk (< 1e-14).
        let (s1, c1) = if k % SINCOS_RESYNC == 0 {
            alpha1.sin_cos()
        } else {
            rotate(s0, c0, alpha1 - alpha0)
        };
        self.alpha = alpha1;
        self.sin_alpha = s1;
        self.cos_alpha = c1;
        (
            [
                ic * u[0] + is * u[1],
                -is * u[0] + ic * u[1],
                u[2] * dt + (alpha1 - alpha0),
            ],
            [ic * a[0] + is * a[1], -is * a[0] + ic * a[1], a[2] * dt],
        )
    }

    /// Look up the table segment holding t0; if it turns at a constant rate, cache the rotation constants of
    /// that rate (recomputed only when the rate changes) and the segment's end. Returns true if the sample
    /// [t0, t1] lies within it.
    #[cold]
    fn enter_uniform(&mut self, t0: f64, t1: f64) -> bool {
        match self.table.uniform_at(&mut self.cursor, t0) {
            Some(seg) => {
                if seg.rate != self.uniform.rate {
                    self.uniform = Uniform::new(seg.rate, self.dt);
                }
                self.uniform.end = seg.end;
                self.uniform.start = seg.start;
                self.uniform.angle0 = seg.angle0;
                t1 <= seg.end
            }
            None => false,
        }
    }

    /// Temperature [deg C] at t_k and, if needed, temperature and rate at the middle of the sample.
    #[inline]
    fn temperature(&mut self, k: u64, t1: f64, need_mid: bool) -> (f64, (f64, f64)) {
        match self.cfg.temperature {
            TemperatureProfile::WarmUp { start_c, end_c, tau_s } => {
                if start_c == end_c {
                    return (end_c, (end_c, 0.0));
                }
                // e_k = exp(-t_k / tau) by recurrence, exact every SINCOS_RESYNC samples.
                let e_prev = self.decay;
                let e1 = if k % SINCOS_RESYNC == 0 {
                    (-t1 / tau_s).exp()
                } else {
                    e_prev * self.decay_step
                };
                self.decay = e1;
                let d = start_c - end_c;
                let mid = if need_mid {
                    let em = e_prev * self.decay_half;
                    (end_c + d * em, -d / tau_s * em)
                } else {
                    (0.0, 0.0)
                };
                (end_c + d * e1, mid)
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

    /// Euler angles of C_b^n = C_b0^n Rz(alpha) from the sine `s` and cosine `c` of alpha already known.
    /// Same values as `dcm_to_euler` (to ~1e-16 rad); for tilts below ~5.7 deg the small angles (pitch, roll,
    /// and yaw relative to yaw0 + alpha) come from short series instead of libm asin/atan2.
    #[inline]
    fn true_attitude_tilted(&self, alpha: f64, s: f64, c: f64) -> Euler {
        let b = &self.c_b0n;
        let c20 = b[2][0] * c + b[2][1] * s;
        let c21 = -b[2][0] * s + b[2][1] * c;
        let c22 = b[2][2];
        let c01 = -b[0][0] * s + b[0][1] * c;
        let c11 = -b[1][0] * s + b[1][1] * c;
        if c21.abs() >= 0.1 || c22 <= 0.0 || c20.abs() >= 0.1 * c22 {
            let rz = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
            return dcm_to_euler(&mat_mul(b, &rz));
        }
        let pitch = asin_small(c21);
        let roll = atan_small(-c20 * self.inv_c22);
        // yaw = yaw_hat + atan2(x, y) with yaw_hat = yaw0 + alpha and (x, y) = cos(pitch) (sin, cos)(yaw - yaw_hat).
        let (sy0, cy0) = self.sincos_yaw0;
        let (sh, ch) = (sy0 * c + cy0 * s, cy0 * c - sy0 * s);
        let x = -c01 * ch - c11 * sh;
        let y = -c01 * sh + c11 * ch;
        let yaw = if y > 0.0 && x.abs() < 0.1 * y {
            wrap_pi_fast(self.cfg.attitude.yaw + alpha + atan_small(x / y))
        } else {
            (-c01).atan2(c11)
        };
        Euler { pitch, roll, yaw }
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
        check(
            (1..=MAX_CHUNK_SAMPLES).contains(&n),
            "n",
            format!("a chunk of {n} samples is outside [1, {MAX_CHUNK_SAMPLES}] samples (12 float64 values each)"),
        )?;
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
    pub fn fill(&mut self, out: ImuChunkSlices<'_>) -> Result<usize, CoreError> {
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
                let (mut dth, mut dv) = self.true_increments(k, t0, t1);
                let (temp, (temp_mid, rate_mid)) = self.temperature(k, t1, temp_drift);
                let drift = if temp_drift {
                    self.errors.params().axial_drift(temp_mid, rate_mid)
                } else {
                    0.0
                };
                self.errors.apply_deterministic(drift, &mut dth, &mut dv);
                out.t_s[i] = t1;
                t0 = t1;
                out.dtheta[3 * i..3 * i + 3].copy_from_slice(&dth);
                out.dv[3 * i..3 * i + 3].copy_from_slice(&dv);
                out.temp_c[i] = temp;
                out.table_angle[i] = self.alpha;
                out.pitch[i] = self.sin_alpha;
                out.roll[i] = self.cos_alpha;
                self.k = k;
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

    /// `fill` on a moving base (buffers already checked for `m` samples): per sample the true increments by
    /// `moving_increments`, the temperature and the deterministic errors, then the random terms per block and
    /// the attitudes (`moving_attitudes`) from the table's sine and cosine and the vehicle's yaw change parked
    /// in the pitch, roll and yaw outputs. Samples ending before the vehicle starts (the static period) are the
    /// static base's (`true_increments`: the same motion, without the per-sample Earth terms).
    fn fill_moving(&mut self, mut out: ImuChunkSlices<'_>, m: usize) -> usize {
        let temp_drift = self.errors.params().has_temperature_drift();
        let rate = self.cfg.rate_hz;
        let yaw0 = self.cfg.attitude.yaw;
        let standing_until = self.moving.as_ref().expect("moving base").traj.start();
        for start in (0..m).step_by(ATTITUDE_BLOCK) {
            let end = (start + ATTITUDE_BLOCK).min(m);
            for i in start..end {
                let k = self.k + 1;
                let (t0, t1) = (self.k as f64 / rate, k as f64 / rate);
                let sample = if t1 <= standing_until {
                    let (dtheta, dv) = self.true_increments(k, t0, t1);
                    MovingSample {
                        dtheta,
                        dv,
                        yaw: yaw0,
                        height: self.cfg.height,
                        vel: [0.0; 3],
                    }
                } else {
                    self.moving_increments(k, t0, t1, self.dt)
                };
                let (mut dth, mut dv) = (sample.dtheta, sample.dv);
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
                out.yaw[i] = sample.yaw - yaw0;
                if let Some(tr) = out.truth.as_mut() {
                    let mv = self.moving.as_ref().expect("moving base");
                    tr.lat[i] = mv.pos[0];
                    tr.lon[i] = mv.pos[1];
                    tr.height[i] = sample.height;
                    tr.vel[3 * i..3 * i + 3].copy_from_slice(&sample.vel);
                }
                self.k = k;
            }
            self.errors
                .add_noise(&mut out.dtheta[3 * start..3 * end], &mut out.dv[3 * start..3 * end]);
            self.moving_attitudes(
                &out.table_angle[start..end],
                &mut out.pitch[start..end],
                &mut out.roll[start..end],
                &mut out.yaw[start..end],
            );
        }
        m
    }

    /// Attitudes of a block on a moving base: on entry `pitch`, `roll` hold sin and cos of the table angle and
    /// `yaw` the vehicle's yaw change psi - psi0; on exit the IMU's true attitude. C_b^n = Rz(psi) C_0 Rz(alpha)
    /// = Rz(psi - psi0) C_b0^n Rz(alpha), and a turn about Up on the left adds to the yaw only: the static
    /// base's attitude of the table angle, its yaw plus psi - psi0.
    #[inline]
    fn moving_attitudes(&self, alpha: &[f64], pitch: &mut [f64], roll: &mut [f64], yaw: &mut [f64]) {
        let yaw0 = self.cfg.attitude.yaw;
        for i in 0..alpha.len() {
            let turned = yaw[i];
            if self.level {
                pitch[i] = 0.0;
                roll[i] = 0.0;
                yaw[i] = wrap_pi_fast(yaw0 + alpha[i] + turned);
            } else {
                let e = self.true_attitude_tilted(alpha[i], pitch[i], roll[i]);
                pitch[i] = e.pitch;
                roll[i] = e.roll;
                yaw[i] = wrap_pi_fast(e.yaw + turned);
            }
        }
    }

    /// True increments of the sample [t0, t1] on a moving base (sample `k`), and the vehicle's yaw, height and
    /// velocity at t1; advances the position and the table angle. With psi the vehicle yaw, C_0 the mounting and
    /// alpha the table angle, C_b^n = Rz(psi) C_0 Rz(alpha), so
    ///     w_ib^b = Rz(-alpha) C_0' (Rz(-psi) (w_ie^n + w_en^n) + psi' e_z) + alpha' e_z,
    ///     f^b    = Rz(-alpha) C_0' Rz(-psi) (dv^n/dt + (2 w_ie^n + w_en^n) x v^n + g e_z).
    /// The sample is split at the route's segment boundaries; on each part the position advances by one RK4
    /// step, the latitude inside it is the cubic Hermite interpolant of the step's ends (error ~1e-20 rad), and
    /// the rate and specific force are integrated by three-point Gauss-Legendre quadrature (their derivatives
    /// are continuous within a part; the table turns by at most a few milliradians per sample, so the error is
    /// below 1e-16 relative). The table's own term alpha(t1) - alpha(t0) is added exactly.
    ///
    /// Cost: the sines and cosines of the latitude, the vehicle yaw and the table angle at the quadrature nodes
    /// and RK4 stages follow from their values at the start of the part by the addition theorem with short
    /// series (`rotate`: the angles move by < 2e-3 rad within a sample, truncation < 1e-21), and the radii,
    /// their reciprocals and gravity from their exact values at the start of the part by Taylor expansion in the
    /// latitude and height steps (`earth::EarthNear`, relative error < 5e-17); the yaw and latitude at the start
    /// of the next part follow the same way, with exact libm values every `SINCOS_RESYNC` samples (the rounding
    /// walk stays below 1e-14): one square root and a few divisions per part instead of about thirty libm
    /// sine/cosine pairs and twenty square roots and divisions.
    ///
    /// The parts are measured from t0 and add up to exactly `dt` (t1 - t0 differs from dt by the rounding of
    /// t1, 3e-11 s at 72 h: 3e-9 relative, which the increments must not carry).
    fn moving_increments(&mut self, k: u64, t0: f64, t1: f64, dt: f64) -> MovingSample {
        let yaw0 = self.cfg.attitude.yaw;
        let (alpha0, sa0, ca0) = (self.alpha, self.sin_alpha, self.cos_alpha);
        // A table turning at a constant rate over the whole sample (cruise, dwell): its closed form, no search.
        let uniform = (t1 <= self.uniform.end || self.enter_uniform(t0, t1)).then_some(self.uniform);
        let (table, table_cursor) = (&self.table, &mut self.cursor);
        let mut table_angle = |t: f64| match &uniform {
            Some(w) => w.angle0 + w.rate * (t - w.start),
            None => table.state_at(table_cursor, t).angle,
        };
        let mv = self.moving.as_mut().expect("moving base");
        let c0 = mv.c0;
        let (mut w, mut f) = ([0.0f64; 3], [0.0f64; 3]);
        // The yaw and its sine and cosine at the start of the last part.
        let mut yaw_ref = mv.yaw_sc;
        // Exact sines and cosines every SINCOS_RESYNC samples bound the rounding random walk of the recurrences.
        let resync = k % SINCOS_RESYNC == 0;
        let mut u = 0.0;
        while u < dt {
            let a = t0 + u;
            let m = mv.traj.motion(&mut mv.cursor, a, yaw0);
            let end = m.end - t0;
            let ub = if end > u && end < dt { end } else { dt };
            let span = ub - u;
            let psi_a = m.yaw(a);
            let (sp_a, cp_a) = if resync {
                psi_a.sin_cos()
            } else {
                rotate(yaw_ref.1, yaw_ref.2, psi_a - yaw_ref.0)
            };
            yaw_ref = (psi_a, sp_a, cp_a);
            let (p0, r0, sl0, cl0) = (mv.pos, mv.pos_rate, mv.sin_lat, mv.cos_lat);
            let h_a = m.vertical(a).0;
            let near = earth::EarthNear::at_position(sl0, cl0, h_a);
            let earth_at = |dlat: f64, h: f64| {
                let (s, c) = rotate(sl0, cl0, dlat);
                near.near(dlat, s, c, h)
            };
            // Classical RK4 of the position over the part (as `trajectory::rk4_position`).
            let (sm, se) = (
                motion_state(&m, a + 0.5 * span, yaw_ref),
                motion_state(&m, a + span, yaw_ref),
            );
            let rate_at = |dlat: f64, st: &MotionState| {
                let e = earth_at(dlat, st.height);
                [st.vel[1] * e.inv_rmh, st.vel[0] * e.inv_rnh * e.inv_cos]
            };
            let k1 = r0;
            let k2 = rate_at(0.5 * span * k1[0], &sm);
            let k3 = rate_at(0.5 * span * k2[0], &sm);
            let k4 = rate_at(span * k3[0], &se);
            let p1 = [
                p0[0] + span / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
                p0[1] + span / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
            ];
            let (sl1, cl1) = if resync {
                p1[0].sin_cos()
            } else {
                rotate(sl0, cl0, p1[0] - p0[0])
            };
            let r1 = {
                let e = near.near(p1[0] - p0[0], sl1, cl1, se.height);
                [se.vel[1] * e.inv_rmh, se.vel[0] * e.inv_rnh * e.inv_cos]
            };
            for (x, wgt) in GL3 {
                let t = a + x * span;
                // Cubic Hermite basis on [0, 1].
                let (x2, x3) = (x * x, x * x * x);
                let dlat = (x3 - 2.0 * x2 + x) * span * r0[0]
                    + (-2.0 * x3 + 3.0 * x2) * (p1[0] - p0[0])
                    + (x3 - x2) * span * r1[0];
                let st = motion_state(&m, t, yaw_ref);
                let ep = earth_at(dlat, st.height);
                let (sl, cl, g) = (ep.sin_lat, ep.cos_lat, ep.g);
                let alpha = table_angle(t);
                let (sa, ca) = rotate(sa0, ca0, alpha - alpha0);
                let v = st.vel;
                let wie = [0.0, earth::OMEGA_IE * cl, earth::OMEGA_IE * sl];
                let e = v[0] * ep.inv_rnh;
                let wen = [-v[1] * ep.inv_rmh, e, e * sl * ep.inv_cos];
                let win = crate::attitude::add(wie, wen);
                let cor = crate::attitude::cross(crate::attitude::add(crate::attitude::scale(wie, 2.0), wen), v);
                let dvdt = st.accel;
                let fnav = [dvdt[0] + cor[0], dvdt[1] + cor[1], dvdt[2] + cor[2] + g];
                let (sp, cp) = (st.sin_yaw, st.cos_yaw);
                // Rz(-psi) x = (c x0 + s x1, -s x0 + c x1, x2).
                let rot = |x: Vec3| [cp * x[0] + sp * x[1], -sp * x[0] + cp * x[1], x[2]];
                let mut wv = rot(win);
                wv[2] += m.yaw_rate;
                let (wb, fb) = (mat_t_vec(&c0, wv), mat_t_vec(&c0, rot(fnav)));
                let s = wgt * span;
                w[0] += s * (ca * wb[0] + sa * wb[1]);
                w[1] += s * (-sa * wb[0] + ca * wb[1]);
                w[2] += s * wb[2];
                f[0] += s * (ca * fb[0] + sa * fb[1]);
                f[1] += s * (-sa * fb[0] + ca * fb[1]);
                f[2] += s * fb[2];
            }
            mv.pos = p1;
            mv.pos_rate = r1;
            mv.sin_lat = sl1;
            mv.cos_lat = cl1;
            u = ub;
        }
        let alpha1 = table_angle(t1);
        w[2] += alpha1 - alpha0;
        let end = motion_state(&mv.traj.motion(&mut mv.cursor, t1, yaw0), t1, yaw_ref);
        mv.yaw_sc = (end.yaw, end.sin_yaw, end.cos_yaw);
        // Exact re-synchronisation every SINCOS_RESYNC samples bounds the rounding random walk (< 1e-14).
        let (s1, c1) = if resync {
            alpha1.sin_cos()
        } else {
            rotate(sa0, ca0, alpha1 - alpha0)
        };
        self.alpha = alpha1;
        self.sin_alpha = s1;
        self.cos_alpha = c1;
        MovingSample {
            dtheta: w,
            dv: f,
            yaw: end.yaw,
            height: end.height,
            vel: end.vel,
        }
    }

    /// Second pass of `fill`: on entry `pitch`, `roll` hold sin and cos of the table angle; on exit the
    /// true attitude [rad].
    #[inline]
    fn attitudes(&self, alpha: &[f64], pitch: &mut [f64], roll: &mut [f64], yaw: &mut [f64]) {
        let yaw0 = self.cfg.attitude.yaw;
        if self.level {
            for i in 0..alpha.len() {
                pitch[i] = 0.0;
                roll[i] = 0.0;
                yaw[i] = wrap_pi_fast(yaw0 + alpha[i]);
            }
        } else {
            for i in 0..alpha.len() {
                let e = self.true_attitude_tilted(alpha[i], pitch[i], roll[i]);
                pitch[i] = e.pitch;
                roll[i] = e.roll;
                yaw[i] = e.yaw;
            }
        }
    }
}

/// Samples per block of the two passes of `fill`.
const ATTITUDE_BLOCK: usize = 512;

/// Samples between exact evaluations of recurrences (table sine/cosine, warm-up exponential).
const SINCOS_RESYNC: u64 = 256;

/// (sin, cos) of (alpha + d) from (sin alpha, cos alpha); series for |d| < 0.05 (truncation < 1e-19).
#[inline(always)]
fn rotate(s: f64, c: f64, d: f64) -> (f64, f64) {
    let (sd, cd) = if d.abs() < 2e-3 {
        // Table travel within a sample is usually below 2e-3 rad: shorter series, truncation < 1e-21.
        let d2 = d * d;
        (
            d * (1.0 - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0))),
            1.0 - d2 * 0.5 * (1.0 - d2 * (1.0 / 12.0) * (1.0 - d2 * (1.0 / 30.0))),
        )
    } else if d.abs() < 0.05 {
        let d2 = d * d;
        // Multiplications by constant reciprocals (a division costs ~10x a multiplication).
        let sd = d
            * (1.0
                - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0) * (1.0 - d2 * (1.0 / 42.0) * (1.0 - d2 * (1.0 / 72.0)))));
        let cd = 1.0
            - d2 * 0.5
                * (1.0
                    - d2 * (1.0 / 12.0)
                        * (1.0 - d2 * (1.0 / 30.0) * (1.0 - d2 * (1.0 / 56.0) * (1.0 - d2 * (1.0 / 90.0)))));
        (sd, cd)
    } else {
        d.sin_cos()
    };
    (s * cd + c * sd, c * cd - s * sd)
}

/// atan(x) for |x| < 0.1 by its Taylor series to x^15 (truncation < 1e-18); libm otherwise.
#[inline(always)]
fn atan_small(x: f64) -> f64 {
    if x.abs() >= 0.1 {
        return x.atan();
    }
    let x2 = x * x;
    if x2 < 1e-6 {
        // |x| < 1e-3 (the yaw correction, second order in the tilt): to x^7, truncation x^8 / 9 < 1.2e-25.
        return x * (1.0 - x2 * ((1.0 / 3.0) - x2 * ((1.0 / 5.0) - x2 * (1.0 / 7.0))));
    }
    if x2 < 4e-4 {
        // |x| < 0.02 (the usual tilt, and the yaw correction, which is second order in the tilt): to x^11,
        // truncation x^12 / 13 < 3.2e-22 relative.
        return x
            * (1.0
                - x2 * ((1.0 / 3.0)
                    - x2 * ((1.0 / 5.0) - x2 * ((1.0 / 7.0) - x2 * ((1.0 / 9.0) - x2 * (1.0 / 11.0))))));
    }
    x * (1.0
        - x2 * ((1.0 / 3.0)
            - x2 * ((1.0 / 5.0)
                - x2 * ((1.0 / 7.0)
                    - x2 * ((1.0 / 9.0) - x2 * ((1.0 / 11.0) - x2 * ((1.0 / 13.0) - x2 * (1.0 / 15.0))))))))
}

/// asin(x) for |x| < 0.1 by its Taylor series to x^15 (truncation < 1e-19); libm otherwise.
#[inline(always)]
fn asin_small(x: f64) -> f64 {
    if x.abs() >= 0.1 {
        return x.asin();
    }
    let x2 = x * x;
    if x2 < 4e-4 {
        // |x| < 0.02: to x^11, truncation below 231/13312 x^12 < 3e-23 relative.
        return x
            * (1.0
                + x2 * ((1.0 / 6.0)
                    + x2 * ((3.0 / 40.0) + x2 * ((5.0 / 112.0) + x2 * ((35.0 / 1152.0) + x2 * (63.0 / 2816.0))))));
    }
    x * (1.0
        + x2 * ((1.0 / 6.0)
            + x2 * ((3.0 / 40.0)
                + x2 * ((5.0 / 112.0)
                    + x2 * ((35.0 / 1152.0)
                        + x2 * ((63.0 / 2816.0) + x2 * ((231.0 / 13312.0) + x2 * (143.0 / 10240.0))))))))
}

/// Wrap to (-pi, pi] without a division in the common case.
#[inline(always)]
fn wrap_pi_fast(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if a > -PI && a <= PI {
        return a;
    }
    // Round to nearest by the 1.5 * 2^52 trick (exact for |x| < 2^51; avoids a libm call).
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let n = (a * (1.0 / TAU) + MAGIC) - MAGIC;
    let w = a - TAU * n;
    if w <= -PI {
        w + TAU
    } else if w > PI {
        w - TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{add, euler_to_quat, norm, quat_conj, quat_mul, quat_to_rotvec, rot_z, rotvec_to_quat, sub};

    fn rotating(level: bool) -> ImuSimulatorConfig {
        ImuSimulatorConfig {
            rate_hz: 50.0,
            duration_s: 200.0,
            attitude: if level {
                Euler {
                    pitch: 0.0,
                    roll: 0.0,
                    yaw: 0.3,
                }
            } else {
                Euler {
                    pitch: 0.02,
                    roll: -0.03,
                    yaw: 0.3,
                }
            },
            scheme: RotationScheme::Reciprocating {
                rate: 0.3,
                accel: 0.2,
                span: 3.0,
                dwell: 2.0,
            },
            ..Default::default()
        }
    }

    #[test]
    fn increments_match_a_fine_numerical_integration() {
        for level in [true, false] {
            let cfg = rotating(level);
            let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
            let mut ch = ImuChunk::default();
            let n = sim.next_chunk(2000, &mut ch);
            assert_eq!(n, 2000);
            let c_b0n = euler_to_dcm(cfg.attitude);
            let wie = earth::earth_rate_enu(cfg.lat);
            let g = earth::normal_gravity(cfg.lat, cfg.height);
            let table = Turntable::new(cfg.scheme.clone()).unwrap();
            for k in (0..2000).step_by(37) {
                // Simpson with 200 sub-intervals per sample.
                let (t0, dt) = (k as f64 * 0.02, 0.02);
                let m = 200;
                let mut sw = [0.0; 3];
                let mut sf = [0.0; 3];
                for j in 0..=m {
                    let t = t0 + dt * j as f64 / m as f64;
                    let st = table.state(t);
                    let cbn = mat_mul(&c_b0n, &rot_z(st.angle));
                    let w = add(mat_t_vec(&cbn, wie), [0.0, 0.0, st.rate]);
                    let f = mat_t_vec(&cbn, [0.0, 0.0, g]);
                    let wt = if j == 0 || j == m {
                        1.0
                    } else if j % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    } * dt
                        / (3.0 * m as f64);
                    for i in 0..3 {
                        sw[i] += wt * w[i];
                        sf[i] += wt * f[i];
                    }
                }
                let dth = [ch.dtheta[3 * k], ch.dtheta[3 * k + 1], ch.dtheta[3 * k + 2]];
                let dv = [ch.dv[3 * k], ch.dv[3 * k + 1], ch.dv[3 * k + 2]];
                assert!(norm(sub(dth, sw)) < 1e-14, "{k}: {dth:?} vs {sw:?}");
                // Two-point Gauss-Legendre is exact for cubics; at a ramp start alpha ~ t^4 and the quadrature
                // error reaches ~1e-13 m/s on 6e-3 m/s (3e-12 m/s^2 while the ramp starts: negligible).
                assert!(norm(sub(dv, sf)) < 1e-12, "{k}: {dv:?} vs {sf:?}");
                // True attitude = C_b0^n Rz(alpha).
                let e = dcm_to_euler(&mat_mul(&c_b0n, &rot_z(table.angle(t0 + dt))));
                assert!((ch.yaw[k] - e.yaw).abs() < 1e-12 && (ch.pitch[k] - e.pitch).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn summed_increments_give_the_true_attitude_change() {
        // Integrating dtheta with exact rotation-vector composition (tiny steps) must track the body relative
        // to inertial space; compare against C_b^i(t) = C_n^i(t) C_b^n(t) with C_n^i = Rz_polar(w_ie t).
        let cfg = rotating(false);
        let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
        let mut ch = ImuChunk::default();
        sim.next_chunk(5000, &mut ch);
        let mut q = QUAT0;
        let mut prev = [0.0; 3];
        for k in 0..5000 {
            let d = [ch.dtheta[3 * k], ch.dtheta[3 * k + 1], ch.dtheta[3 * k + 2]];
            // One-plus-previous-sample coning correction.
            let phi = add(d, crate::attitude::scale(crate::attitude::cross(prev, d), 1.0 / 12.0));
            q = quat_mul(q, rotvec_to_quat(phi));
            prev = d;
        }
        // Truth: q_{b(t)}^{b(0)} = q_n^b(0) o q_{n(t)}^{n(0)} o q_b^n(t); n rotates about the polar axis,
        // which in ENU is w_ie^n / w_ie, by w_ie t.
        let t = 100.0;
        let pol = earth::earth_rate_enu(cfg.lat);
        let qn = rotvec_to_quat([pol[0] * t, pol[1] * t, pol[2] * t]);
        let qb0 = euler_to_quat(cfg.attitude);
        let table = Turntable::new(cfg.scheme.clone()).unwrap();
        let qbt = quat_mul(qb0, rotvec_to_quat([0.0, 0.0, table.angle(t)]));
        let truth = quat_mul(quat_conj(qb0), quat_mul(qn, qbt));
        let err = quat_to_rotvec(quat_mul(quat_conj(truth), q));
        // With the coning correction the composition reproduces the true rotation to rounding level.
        assert!(norm(err) < 1e-11, "{err:?}");
    }

    const QUAT0: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

    #[test]
    fn fast_true_attitude_equals_the_dcm_route() {
        for (p, r, y) in [
            (0.02, -0.03, 0.3),
            (0.0, 0.09, -3.1),
            (-0.3, 0.5, 2.0),
            (0.001, 0.0, 3.1),
        ] {
            let cfg = ImuSimulatorConfig {
                attitude: Euler {
                    pitch: p,
                    roll: r,
                    yaw: y,
                },
                scheme: RotationScheme::Continuous { rate: 1.0, accel: 1.0 },
                duration_s: 20.0,
                ..Default::default()
            };
            let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
            let mut ch = ImuChunk::default();
            sim.next_chunk(2000, &mut ch);
            let c_b0n = euler_to_dcm(cfg.attitude);
            for k in (0..2000).step_by(7) {
                let e = dcm_to_euler(&mat_mul(&c_b0n, &rot_z(ch.table_angle[k])));
                assert!((ch.pitch[k] - e.pitch).abs() < 1e-13, "pitch {k}");
                assert!((ch.roll[k] - e.roll).abs() < 1e-13, "roll {k}");
                let dy = (ch.yaw[k] - e.yaw).abs();
                assert!(
                    dy.min((dy - 2.0 * std::f64::consts::PI).abs()) < 1e-13,
                    "yaw {k}: {} {}",
                    ch.yaw[k],
                    e.yaw
                );
            }
        }
    }

    #[test]
    fn constant_rate_shortcut_matches_direct_quadrature_late_in_a_long_run() {
        // Cruise and dwell samples take the constant-rate path (fixed rotations of sin/cos, resynchronised
        // every SINCOS_RESYNC samples); compare with the two-point quadrature from libm sin/cos at the nodes.
        for scheme in [
            RotationScheme::Continuous { rate: 1.0, accel: 2.0 },
            RotationScheme::Indexing {
                rate: 0.5,
                accel: 1.0,
                positions: vec![0.0, 1.0, 2.5],
                dwell: 3.0,
            },
        ] {
            let cfg = ImuSimulatorConfig {
                rate_hz: 100.0,
                duration_s: 2000.0,
                attitude: Euler {
                    pitch: 0.01,
                    roll: 0.02,
                    yaw: 1.0,
                },
                scheme,
                ..Default::default()
            };
            let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
            let mut ch = ImuChunk::default();
            let mut first = 0usize;
            while sim.next_chunk(30_000, &mut ch) == 30_000 && sim.samples_done() < 180_000 {
                first += 30_000;
            }
            let c_b0n = euler_to_dcm(cfg.attitude);
            let u = mat_t_vec(&c_b0n, earth::earth_rate_enu(cfg.lat));
            let table = Turntable::new(cfg.scheme.clone()).unwrap();
            let dt = 0.01;
            for i in (0..ch.len()).step_by(97) {
                let t0 = (first + i) as f64 * dt;
                let (a_lo, a_hi) = (table.angle(t0 + GL2_LO * dt), table.angle(t0 + GL2_HI * dt));
                let ic = 0.5 * dt * (a_lo.cos() + a_hi.cos());
                let is = 0.5 * dt * (a_lo.sin() + a_hi.sin());
                let ex = [ic * u[0] + is * u[1], -is * u[0] + ic * u[1]];
                for (j, want) in ex.iter().enumerate() {
                    let got = ch.dtheta[3 * i + j];
                    assert!((got - want).abs() < 1e-18, "{i} {j}: {got} vs {want}");
                }
                assert!((ch.table_angle[i] - table.angle(t0 + dt)).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn chunking_does_not_change_the_output() {
        let mut cfg = rotating(false);
        cfg.errors.gyro_arw = 1e-6;
        cfg.errors.accel_vrw = 1e-5;
        cfg.errors.gyro_bias_instability = 1e-7;
        let mut a = ImuSimulator::new(cfg.clone()).unwrap();
        let mut b = ImuSimulator::new(cfg).unwrap();
        let mut ca = ImuChunk::default();
        a.next_chunk(10_000, &mut ca);
        let mut all = Vec::new();
        let mut cb = ImuChunk::default();
        while b.next_chunk(333, &mut cb) > 0 {
            all.extend_from_slice(&cb.dtheta);
        }
        assert_eq!(ca.dtheta, all);
        assert_eq!(a.next_chunk(5, &mut ca), 0);
    }
}
