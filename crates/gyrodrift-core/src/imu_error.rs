//! IMU error model in the body frame (Right-Forward-Up), applied to true increments over one sample.
//!
//! Gyro (rates in rad/s, increments in rad), for one sample of length dt from t_k to t_k + dt:
//!     dtheta_meas = (I + diag(s_g) + M_g) dtheta_true
//!                   + (b_g + b_gm(t_k) + b_rrw(t_k) + b_T e_z) dt + n_arw,
//!     n_arw ~ N(0, (arw^2 dt) I)         (white rate noise of density arw [rad/sqrt(s)] integrated over dt),
//!     b_gm:  first-order Gauss-Markov, exact discretisation over the slow step h = N dt (below):
//!            b(t + h) = phi b(t) + w, phi = exp(-h / tau), w ~ N(0, sigma^2 (1 - phi^2)); b(0) ~ N(0, sigma^2)
//!            (stationary from the start), so its statistics at the grid times do not depend on the sample rate;
//!     b_rrw: random walk over the same slow step, b(t + h) = b(t) + N(0, rrw^2 h), b(0) = 0;
//!     b_T:   temperature-dependent axial drift on gyro z only,
//!            b_T = k1 (T - T0) + k2 (T - T0)^2 + k3 dT/dt, evaluated at the middle of the sample.
//! M_g holds the misalignments: m_xy = M\[0\]\[1\], m_xz = M\[0\]\[2\], m_yx = M\[1\]\[0\], m_yz = M\[1\]\[2\],
//! m_zx = M\[2\]\[0\], m_zy = M\[2\]\[1\] (contract order xy, xz, yx, yz, zx, zy).
//! Accelerometer (m/s^2, increments m/s): dv_meas = (I + diag(s_a)) dv_true + b_a dt + n_vrw,
//! n_vrw ~ N(0, (vrw^2 dt) I).
//! The slowly varying biases b_gm and b_rrw live on a coarser exact grid of N samples (the slow step
//! h = N dt): they take their exact discrete values at t = 0, h, 2h, ... and are held in between, as every
//! bias is held within a sample. N = floor(H / dt) clamped to [1, 100] with H = min(1 s, tau / 1000) when
//! the Gauss-Markov term is on, else H = 1 s. Holding for h << tau changes the statistics of the integrated
//! bias by O(h / tau) <= 0.1 % (and the rate random walk's by O(h / t), 1 s against hours), and saves 6 of
//! the 12 normal draws per sample. At 100 Hz with tau >= 1000 s the slow step is 1 s.
//!
//! All noise comes from one generator, `rand_pcg::Pcg64Mcg` seeded with `seed` (portable: the same seed gives
//! the same bits on every platform). Normals are drawn in the order: at every sample, gyro white noise
//! (x, y, z) then accelerometer white noise (x, y, z); after every N-th sample, Gauss-Markov driving noise
//! (x, y, z) then rate random walk (x, y, z). A term whose magnitude is zero draws nothing.

use crate::attitude::Vec3;
use crate::error::{check_with, CoreError, Unit};
use crate::limits::{check_arw, check_vrw};
use rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64Mcg;

/// Largest constant, Gauss-Markov and estimated gyro bias [rad/s] (about 20600 deg/h).
pub const MAX_GYRO_BIAS_RAD_S: f64 = 0.1;
/// Largest constant and estimated accelerometer bias [m/s^2] (about 1 g).
pub const MAX_ACCEL_BIAS_M_S2: f64 = 10.0;

/// Parameters of the error model (SI units; see the module docs for the equations).
#[derive(Clone, Debug, PartialEq)]
pub struct ImuErrorParams {
    /// Constant gyro biases [rad/s], body x y z.
    pub gyro_bias: Vec3,
    /// Angle random walk [rad/sqrt(s)].
    pub gyro_arw: f64,
    /// Gauss-Markov bias instability, stationary sigma [rad/s].
    pub gyro_bias_instability: f64,
    /// Gauss-Markov correlation time \[s\].
    pub gyro_correlation: f64,
    /// Rate random walk [rad/s/sqrt(s)].
    pub gyro_rrw: f64,
    /// Gyro scale-factor errors [-].
    pub gyro_scale: Vec3,
    /// Gyro misalignments \[rad\], order xy, xz, yx, yz, zx, zy.
    pub gyro_misalignment: [f64; 6],
    /// Constant accelerometer biases [m/s^2].
    pub accel_bias: Vec3,
    /// Velocity random walk [m/s/sqrt(s)].
    pub accel_vrw: f64,
    /// Accelerometer scale-factor errors [-].
    pub accel_scale: Vec3,
    /// Reference temperature T0 of the axial drift [deg C].
    pub drift_t0_c: f64,
    /// k1 [rad/s/degC].
    pub drift_k1: f64,
    /// k2 [rad/s/degC^2].
    pub drift_k2: f64,
    /// k3 [rad/s per degC/s].
    pub drift_k3: f64,
}

impl Default for ImuErrorParams {
    /// An error-free IMU (correlation time 3600 s and T0 = 20 deg C, which matter only once their terms are set).
    fn default() -> Self {
        ImuErrorParams {
            gyro_bias: [0.0; 3],
            gyro_arw: 0.0,
            gyro_bias_instability: 0.0,
            gyro_correlation: 3600.0,
            gyro_rrw: 0.0,
            gyro_scale: [0.0; 3],
            gyro_misalignment: [0.0; 6],
            accel_bias: [0.0; 3],
            accel_vrw: 0.0,
            accel_scale: [0.0; 3],
            drift_t0_c: 20.0,
            drift_k1: 0.0,
            drift_k2: 0.0,
            drift_k3: 0.0,
        }
    }
}

impl ImuErrorParams {
    /// Range checks; errors name the contract key. Limits reject nonsense, not unusual sensors.
    pub fn validate(&self) -> Result<(), CoreError> {
        use crate::error::{all_in_range, in_range, ARCSEC, DEG_H_PER_C, DEG_H_PER_RTH, MICRO_G, PPM};
        use crate::units::{DEG, HOUR};
        let (gb, g) = (MAX_GYRO_BIAS_RAD_S, Unit::DegPerH);
        all_in_range("gyro_bias_rad_s", "gyro bias", &self.gyro_bias, -gb, gb, g)?;
        check_arw(self.gyro_arw)?;
        in_range(
            "gyro_bias_instability_rad_s",
            "bias instability",
            self.gyro_bias_instability,
            0.0,
            gb,
            g,
        )?;
        check_with(
            self.gyro_correlation.is_finite() && self.gyro_correlation > 0.0,
            "gyro_correlation_s",
            || {
                format!(
                    "correlation time {} s must be positive and finite",
                    crate::error::sig(self.gyro_correlation)
                )
            },
        )?;
        in_range(
            "gyro_rrw_rad_s_rts",
            "rate random walk",
            self.gyro_rrw,
            0.0,
            0.1,
            DEG_H_PER_RTH,
        )?;
        all_in_range("gyro_scale", "gyro scale factor", &self.gyro_scale, -0.1, 0.1, PPM)?;
        all_in_range(
            "gyro_misalignment_rad",
            "gyro misalignment",
            &self.gyro_misalignment,
            -0.1,
            0.1,
            ARCSEC,
        )?;
        let ab = MAX_ACCEL_BIAS_M_S2;
        all_in_range(
            "accel_bias_m_s2",
            "accelerometer bias",
            &self.accel_bias,
            -ab,
            ab,
            MICRO_G,
        )?;
        check_vrw(self.accel_vrw)?;
        all_in_range(
            "accel_scale",
            "accelerometer scale factor",
            &self.accel_scale,
            -0.1,
            0.1,
            PPM,
        )?;
        in_range(
            "drift_t0_c",
            "drift reference temperature",
            self.drift_t0_c,
            -100.0,
            200.0,
            Unit::Si("deg C"),
        )?;
        in_range(
            "drift_k1_rad_s_per_c",
            "drift k1",
            self.drift_k1,
            -1e-3,
            1e-3,
            DEG_H_PER_C,
        )?;
        let per_c2 = Unit::Scaled(HOUR / DEG, "deg/h/degC^2");
        in_range("drift_k2_rad_s_per_c2", "drift k2", self.drift_k2, -1e-3, 1e-3, per_c2)?;
        // k3 [rad/s per degC/s] in [deg/h per degC/h]: the hours cancel.
        let per_c_per_h = Unit::Scaled(1.0 / DEG, "deg/h per degC/h");
        in_range(
            "drift_k3_rad_s_per_c_per_s",
            "drift k3",
            self.drift_k3,
            -1.0,
            1.0,
            per_c_per_h,
        )
    }

    /// Temperature-dependent axial drift [rad/s]: k1 (T - T0) + k2 (T - T0)^2 + k3 dT/dt.
    #[inline]
    pub fn axial_drift(&self, temp_c: f64, dtemp_c_s: f64) -> f64 {
        let d = temp_c - self.drift_t0_c;
        self.drift_k1 * d + self.drift_k2 * d * d + self.drift_k3 * dtemp_c_s
    }

    /// True if the temperature drift terms are all zero.
    pub fn has_temperature_drift(&self) -> bool {
        self.drift_k1 != 0.0 || self.drift_k2 != 0.0 || self.drift_k3 != 0.0
    }
}

/// The error model with its random state, for a fixed sample interval.
#[derive(Clone, Debug)]
pub struct ImuErrorModel {
    p: ImuErrorParams,
    dt: f64,
    rng: Pcg64Mcg,
    /// I + diag(s_g) + M_g.
    gyro_matrix: [[f64; 3]; 3],
    /// Gauss-Markov state [rad/s].
    gm: Vec3,
    /// Rate random walk state [rad/s].
    rrw: Vec3,
    /// Samples per slow step (see the module docs) and samples since the last slow update.
    slow_n: u32,
    slow_count: u32,
    /// Gauss-Markov transition and driving-noise sd over one slow step.
    gm_phi: f64,
    gm_q_sd: f64,
    arw_sd: f64,
    vrw_sd: f64,
    /// Rate-random-walk increment sd over one slow step.
    rrw_sd: f64,
}

/// Samples per slow step for sample interval `dt` (see the module docs).
pub fn slow_step_samples(p: &ImuErrorParams, dt: f64) -> u32 {
    let horizon = if p.gyro_bias_instability > 0.0 {
        (1e-3 * p.gyro_correlation).min(1.0)
    } else {
        1.0
    };
    // The 1e-9 guards an exact ratio (1 s at 100 Hz) against rounding down.
    ((horizon / dt * (1.0 + 1e-9)).floor() as u32).clamp(1, 100)
}

impl ImuErrorModel {
    /// A model for sample interval `dt` \[s\], noise seeded by `seed`.
    pub fn new(p: ImuErrorParams, dt: f64, seed: u64) -> Result<Self, CoreError> {
        p.validate()?;
        let m = p.gyro_misalignment;
        let s = p.gyro_scale;
        let gyro_matrix = [
            [1.0 + s[0], m[0], m[1]],
            [m[2], 1.0 + s[1], m[3]],
            [m[4], m[5], 1.0 + s[2]],
        ];
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let sigma = p.gyro_bias_instability;
        let slow_n = slow_step_samples(&p, dt);
        let h = slow_n as f64 * dt;
        let phi = (-h / p.gyro_correlation).exp();
        let mut gm = [0.0; 3];
        if sigma > 0.0 {
            for g in gm.iter_mut() {
                let n: f64 = StandardNormal.sample(&mut rng);
                *g = sigma * n;
            }
        }
        Ok(ImuErrorModel {
            gyro_matrix,
            gm,
            rrw: [0.0; 3],
            gm_phi: phi,
            // sigma^2 (1 - phi^2) written with exp_m1 to keep precision when dt << tau.
            gm_q_sd: sigma * (-(-2.0 * h / p.gyro_correlation).exp_m1()).sqrt(),
            arw_sd: p.gyro_arw * dt.sqrt(),
            vrw_sd: p.accel_vrw * dt.sqrt(),
            rrw_sd: p.gyro_rrw * h.sqrt(),
            slow_n,
            slow_count: 0,
            dt,
            rng,
            p,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &ImuErrorParams {
        &self.p
    }

    /// Current Gauss-Markov bias state [rad/s] (for tests and diagnostics).
    pub fn gauss_markov_state(&self) -> Vec3 {
        self.gm
    }

    #[inline(always)]
    fn normal3(&mut self, sd: f64) -> Vec3 {
        let a: f64 = StandardNormal.sample(&mut self.rng);
        let b: f64 = StandardNormal.sample(&mut self.rng);
        let c: f64 = StandardNormal.sample(&mut self.rng);
        [a * sd, b * sd, c * sd]
    }

    /// Turn true increments into measured ones in place and advance the random states by one sample.
    /// `axial_drift` [rad/s] is the temperature term b_T (see `ImuErrorParams::axial_drift`).
    /// Equivalent to [`ImuErrorModel::apply_deterministic`] followed by [`ImuErrorModel::add_noise`].
    #[inline]
    pub fn apply(&mut self, axial_drift: f64, dtheta: &mut Vec3, dv: &mut Vec3) {
        self.apply_deterministic(axial_drift, dtheta, dv);
        self.add_noise(dtheta, dv);
    }

    /// The deterministic terms of one sample, in place: scale factors, misalignments, constant biases and
    /// the axial drift `axial_drift` [rad/s]. Touches no random state.
    #[inline]
    pub fn apply_deterministic(&self, axial_drift: f64, dtheta: &mut Vec3, dv: &mut Vec3) {
        let dt = self.dt;
        let g = &self.gyro_matrix;
        let w = *dtheta;
        let b = self.p.gyro_bias;
        *dtheta = [
            g[0][0] * w[0] + g[0][1] * w[1] + g[0][2] * w[2] + b[0] * dt,
            g[1][0] * w[0] + g[1][1] * w[1] + g[1][2] * w[2] + b[1] * dt,
            g[2][0] * w[0] + g[2][1] * w[1] + g[2][2] * w[2] + (b[2] + axial_drift) * dt,
        ];
        let (sa, ba) = (self.p.accel_scale, self.p.accel_bias);
        *dv = [
            dv[0] * (1.0 + sa[0]) + ba[0] * dt,
            dv[1] * (1.0 + sa[1]) + ba[1] * dt,
            dv[2] * (1.0 + sa[2]) + ba[2] * dt,
        ];
    }

    /// True if [`ImuErrorModel::add_noise`] changes anything (some random term is on).
    pub fn is_noisy(&self) -> bool {
        self.arw_sd > 0.0 || self.vrw_sd > 0.0 || self.gm_q_sd > 0.0 || self.rrw_sd > 0.0
    }

    /// The random terms of consecutive samples, in place, advancing the random states: `dtheta` and `dv`
    /// hold n samples each (flattened n x 3, after [`ImuErrorModel::apply_deterministic`]). Adds the held
    /// slow biases (b_gm + b_rrw) dt and the white noises, drawing in the documented order.
    #[inline]
    pub fn add_noise(&mut self, dtheta: &mut [f64], dv: &mut [f64]) {
        if !self.is_noisy() {
            return;
        }
        let n = dtheta.len() / 3;
        debug_assert_eq!(dv.len(), 3 * n);
        let slow = self.gm_q_sd > 0.0 || self.rrw_sd > 0.0;
        let mut held = self.held_bias_increment();
        for (o, v) in dtheta.chunks_exact_mut(3).zip(dv.chunks_exact_mut(3)) {
            if slow {
                for i in 0..3 {
                    o[i] += held[i];
                }
            }
            if self.arw_sd > 0.0 {
                let x = self.normal3(self.arw_sd);
                for i in 0..3 {
                    o[i] += x[i];
                }
            }
            if self.vrw_sd > 0.0 {
                let x = self.normal3(self.vrw_sd);
                for i in 0..3 {
                    v[i] += x[i];
                }
            }
            if slow {
                self.slow_count += 1;
                if self.slow_count == self.slow_n {
                    self.slow_count = 0;
                    self.slow_update();
                    held = self.held_bias_increment();
                }
            }
        }
    }

    /// (b_gm + b_rrw) dt of the current slow step [rad].
    #[inline]
    fn held_bias_increment(&self) -> Vec3 {
        let dt = self.dt;
        [
            (self.gm[0] + self.rrw[0]) * dt,
            (self.gm[1] + self.rrw[1]) * dt,
            (self.gm[2] + self.rrw[2]) * dt,
        ]
    }

    /// Advance the Gauss-Markov and rate-random-walk states by one slow step.
    #[inline]
    fn slow_update(&mut self) {
        if self.gm_q_sd > 0.0 {
            let n = self.normal3(self.gm_q_sd);
            let phi = self.gm_phi;
            for (g, x) in self.gm.iter_mut().zip(n) {
                *g = phi * *g + x;
            }
        }
        if self.rrw_sd > 0.0 {
            let n = self.normal3(self.rrw_sd);
            for (r, x) in self.rrw.iter_mut().zip(n) {
                *r += x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gm_params(sigma: f64, tau: f64) -> ImuErrorParams {
        ImuErrorParams {
            gyro_bias_instability: sigma,
            gyro_correlation: tau,
            ..Default::default()
        }
    }

    #[test]
    fn gauss_markov_variance_and_correlation_do_not_depend_on_the_rate() {
        let sigma = 1e-6;
        let tau = 10.0;
        for rate in [10.0, 100.0, 1000.0] {
            let dt = 1.0 / rate;
            // Across many independent seeds: variance at t = 0 and at t = 30 s, and the covariance between them.
            let n_seeds = 4000;
            let steps = (30.0 * rate) as usize;
            let (mut s00, mut s11, mut s01) = (0.0, 0.0, 0.0);
            for seed in 0..n_seeds {
                let mut m = ImuErrorModel::new(gm_params(sigma, tau), dt, seed).unwrap();
                let x0 = m.gauss_markov_state()[0];
                let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
                for _ in 0..steps {
                    m.apply(0.0, &mut a, &mut b);
                }
                let x1 = m.gauss_markov_state()[0];
                s00 += x0 * x0;
                s11 += x1 * x1;
                s01 += x0 * x1;
            }
            let n = n_seeds as f64;
            let (v0, v1, c) = (s00 / n, s11 / n, s01 / n);
            // Sampling error of a variance estimate with 4000 samples: ~2.2 %; allow 4 sigma.
            assert!((v0 / (sigma * sigma) - 1.0).abs() < 0.09, "rate {rate}: var0 {v0}");
            assert!((v1 / (sigma * sigma) - 1.0).abs() < 0.09, "rate {rate}: var1 {v1}");
            // Correlation after 30 s = exp(-3) = 0.0498.
            assert!(
                (c / (sigma * sigma) - (-3.0f64).exp()).abs() < 0.07,
                "rate {rate}: corr {c}"
            );
        }
    }

    #[test]
    fn rate_random_walk_variance_grows_as_t_at_any_rate() {
        let rrw = 1e-7;
        let t = 50.0;
        for rate in [20.0, 200.0] {
            let p = ImuErrorParams {
                gyro_rrw: rrw,
                ..Default::default()
            };
            let n_seeds = 2000;
            let mut s2 = 0.0;
            for seed in 0..n_seeds {
                let mut m = ImuErrorModel::new(p.clone(), 1.0 / rate, seed).unwrap();
                let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
                for _ in 0..(t * rate) as usize {
                    m.apply(0.0, &mut a, &mut b);
                }
                s2 += m.rrw[1] * m.rrw[1];
            }
            let var = s2 / n_seeds as f64;
            // 2000 samples: variance estimate good to ~3 %; allow 4 sigma.
            assert!((var / (rrw * rrw * t) - 1.0).abs() < 0.13, "rate {rate}: {var}");
        }
    }

    #[test]
    fn slow_step_follows_the_correlation_time_and_the_rate() {
        let gm = |tau| ImuErrorParams {
            gyro_bias_instability: 1e-7,
            gyro_correlation: tau,
            ..Default::default()
        };
        assert_eq!(slow_step_samples(&gm(3600.0), 0.01), 100); // 1 s at 100 Hz
        assert_eq!(slow_step_samples(&gm(3600.0), 0.1), 10);
        assert_eq!(slow_step_samples(&gm(10.0), 0.01), 1); // tau / 1000 = one sample
        assert_eq!(slow_step_samples(&gm(10.0), 0.001), 10);
        assert_eq!(slow_step_samples(&gm(3600.0), 1e-4), 100); // capped at 100 samples
        assert_eq!(
            slow_step_samples(
                &ImuErrorParams {
                    gyro_rrw: 1e-8,
                    ..Default::default()
                },
                0.05
            ),
            20
        );
        assert_eq!(slow_step_samples(&gm(0.5), 0.01), 1);
    }

    #[test]
    fn block_noise_equals_per_sample_application() {
        let p = ImuErrorParams {
            gyro_arw: 1e-5,
            accel_vrw: 1e-4,
            gyro_correlation: 100.0,
            gyro_bias_instability: 1e-7,
            gyro_rrw: 1e-8,
            gyro_bias: [1e-6, 0.0, 2e-6],
            ..Default::default()
        };
        let mut a = ImuErrorModel::new(p.clone(), 0.01, 5).unwrap();
        let mut b = ImuErrorModel::new(p, 0.01, 5).unwrap();
        let n = 1000;
        let (mut th, mut v) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        for i in 0..n {
            let (mut w, mut f) = ([0.001 * i as f64, 0.0, 1e-3], [0.0, 0.1, 0.098]);
            a.apply(1e-7, &mut w, &mut f);
            th[3 * i..3 * i + 3].copy_from_slice(&w);
            v[3 * i..3 * i + 3].copy_from_slice(&f);
        }
        let (mut th2, mut v2) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        for i in 0..n {
            let (mut w, mut f) = ([0.001 * i as f64, 0.0, 1e-3], [0.0, 0.1, 0.098]);
            b.apply_deterministic(1e-7, &mut w, &mut f);
            th2[3 * i..3 * i + 3].copy_from_slice(&w);
            v2[3 * i..3 * i + 3].copy_from_slice(&f);
        }
        b.add_noise(&mut th2[..1500], &mut v2[..1500]);
        b.add_noise(&mut th2[1500..], &mut v2[1500..]);
        assert_eq!(th, th2);
        assert_eq!(v, v2);
    }

    #[test]
    fn deterministic_for_a_seed() {
        let p = ImuErrorParams {
            gyro_arw: 1e-5,
            accel_vrw: 1e-4,
            gyro_correlation: 100.0,
            gyro_bias_instability: 1e-7,
            ..Default::default()
        };
        let run = |seed| {
            let mut m = ImuErrorModel::new(p.clone(), 0.01, seed).unwrap();
            let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
            for _ in 0..100 {
                m.apply(0.0, &mut a, &mut b);
            }
            (a, b)
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
    }

    #[test]
    fn deterministic_terms_follow_the_measurement_model() {
        let p = ImuErrorParams {
            gyro_bias: [1e-6, 2e-6, 3e-6],
            gyro_scale: [1e-5, 2e-5, 3e-5],
            gyro_misalignment: [1e-4, 2e-4, 3e-4, 4e-4, 5e-4, 6e-4],
            accel_bias: [1e-3, -1e-3, 2e-3],
            accel_scale: [1e-4, 0.0, -1e-4],
            gyro_correlation: 1.0,
            ..Default::default()
        };
        let dt = 0.01;
        let mut m = ImuErrorModel::new(p, dt, 0).unwrap();
        let (mut w, mut v) = ([0.1, 0.2, 0.3], [1.0, 2.0, 3.0]);
        m.apply(1e-7, &mut w, &mut v);
        let ex = [
            0.1 * (1.0 + 1e-5) + 1e-4 * 0.2 + 2e-4 * 0.3 + 1e-6 * dt,
            3e-4 * 0.1 + 0.2 * (1.0 + 2e-5) + 4e-4 * 0.3 + 2e-6 * dt,
            5e-4 * 0.1 + 6e-4 * 0.2 + 0.3 * (1.0 + 3e-5) + (3e-6 + 1e-7) * dt,
        ];
        for i in 0..3 {
            assert!((w[i] - ex[i]).abs() < 1e-17, "{i}");
        }
        assert!((v[0] - (1.0001 + 1e-5)).abs() < 1e-15);
        assert!((v[2] - (3.0 * (1.0 - 1e-4) + 2e-5)).abs() < 1e-15);
        let p = ImuErrorParams {
            drift_t0_c: 20.0,
            drift_k1: 1.0,
            drift_k2: 0.5,
            drift_k3: 10.0,
            ..Default::default()
        };
        assert_eq!(p.axial_drift(22.0, 0.1), 2.0 + 2.0 + 1.0);
    }

    #[test]
    fn validation_names_the_key() {
        let p = ImuErrorParams {
            gyro_arw: -1.0,
            gyro_correlation: 1.0,
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().key(), "gyro_arw_rad_rts");
        let p = ImuErrorParams {
            gyro_correlation: 0.0,
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().key(), "gyro_correlation_s");
        ImuErrorParams::default().validate().unwrap();
    }
}
