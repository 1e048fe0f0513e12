//! IMU error model in the body frame (Right-Forward-Up), applied to true increments over one sample.
//!
//! Gyro (rates in rad/s, increments in rad), for one sample of length dt from t_k to t_k + dt:
//!     dtheta_meas = (I + diag(s_g) + M_g) dtheta_true
//!                   + (b_g + b_gm(t_k) + b_rrw(t_k) + b_T e_z) dt + n_arw,
//!     n_arw ~ N(0, (arw^2 dt) I)         (white rate noise of density arw [rad/sqrt(s)] integrated over dt),
//!     b_gm:  first-order Gauss-Markov, exact discretisation b_{k+1} = phi b_k + w_k, phi = exp(-dt / tau),
//!            w_k ~ N(0, sigma^2 (1 - phi^2)); b_0 ~ N(0, sigma^2) (stationary from the start), so its statistics
//!            at any time do not depend on the sample rate;
//!     b_rrw: random walk b_{k+1} = b_k + N(0, rrw^2 dt), b_0 = 0;
//!     b_T:   temperature-dependent axial drift on gyro z only,
//!            b_T = k1 (T - T0) + k2 (T - T0)^2 + k3 dT/dt, evaluated at the middle of the sample.
//! M_g holds the misalignments: m_xy = M[0][1], m_xz = M[0][2], m_yx = M[1][0], m_yz = M[1][2],
//! m_zx = M[2][0], m_zy = M[2][1] (contract order xy, xz, yx, yz, zx, zy).
//! Accelerometer (m/s^2, increments m/s): dv_meas = (I + diag(s_a)) dv_true + b_a dt + n_vrw,
//! n_vrw ~ N(0, (vrw^2 dt) I).
//! The biases inside a sample are held at their value at the start of the sample.
//!
//! All noise comes from one generator, `rand_pcg::Pcg64Mcg` seeded with `seed` (portable: the same seed gives
//! the same bits on every platform). Normals are drawn per sample in the order gyro white noise (x, y, z),
//! accelerometer white noise (x, y, z), Gauss-Markov driving noise (x, y, z), rate random walk (x, y, z);
//! a term whose magnitude is zero draws nothing.

use crate::attitude::Vec3;
use crate::turntable::{check, ParamError};
use rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64Mcg;

/// Parameters of the error model (SI units; see the module docs for the equations).
#[derive(Clone, Debug, PartialEq)]
pub struct ImuErrorParams {
    /// Constant gyro biases [rad/s], body x y z.
    pub gyro_bias: Vec3,
    /// Angle random walk [rad/sqrt(s)].
    pub gyro_arw: f64,
    /// Gauss-Markov bias instability, stationary sigma [rad/s].
    pub gyro_bias_instability: f64,
    /// Gauss-Markov correlation time [s].
    pub gyro_correlation: f64,
    /// Rate random walk [rad/s/sqrt(s)].
    pub gyro_rrw: f64,
    /// Gyro scale-factor errors [-].
    pub gyro_scale: Vec3,
    /// Gyro misalignments [rad], order xy, xz, yx, yz, zx, zy.
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
    pub fn validate(&self) -> Result<(), ParamError> {
        let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
        check(fin(&self.gyro_bias) && self.gyro_bias.iter().all(|b| b.abs() <= 0.1), "gyro_bias_rad_s", "must be finite with |b| <= 0.1 rad/s")?;
        check(self.gyro_arw.is_finite() && self.gyro_arw >= 0.0 && self.gyro_arw <= 0.1, "gyro_arw_rad_rts", "must be in [0, 0.1] rad/sqrt(s)")?;
        check(self.gyro_bias_instability.is_finite() && self.gyro_bias_instability >= 0.0 && self.gyro_bias_instability <= 0.1, "gyro_bias_instability_rad_s", "must be in [0, 0.1] rad/s")?;
        check(self.gyro_correlation.is_finite() && self.gyro_correlation > 0.0, "gyro_correlation_s", "must be positive and finite")?;
        check(self.gyro_rrw.is_finite() && self.gyro_rrw >= 0.0 && self.gyro_rrw <= 0.1, "gyro_rrw_rad_s_rts", "must be in [0, 0.1] rad/s/sqrt(s)")?;
        check(fin(&self.gyro_scale) && self.gyro_scale.iter().all(|s| s.abs() <= 0.1), "gyro_scale", "must be finite with |s| <= 0.1")?;
        check(fin(&self.gyro_misalignment) && self.gyro_misalignment.iter().all(|s| s.abs() <= 0.1), "gyro_misalignment_rad", "must be finite with |m| <= 0.1 rad")?;
        check(fin(&self.accel_bias) && self.accel_bias.iter().all(|b| b.abs() <= 10.0), "accel_bias_m_s2", "must be finite with |b| <= 10 m/s^2")?;
        check(self.accel_vrw.is_finite() && self.accel_vrw >= 0.0 && self.accel_vrw <= 1.0, "accel_vrw_m_s_rts", "must be in [0, 1] m/s/sqrt(s)")?;
        check(fin(&self.accel_scale) && self.accel_scale.iter().all(|s| s.abs() <= 0.1), "accel_scale", "must be finite with |s| <= 0.1")?;
        check(self.drift_t0_c.is_finite() && (-100.0..=200.0).contains(&self.drift_t0_c), "drift_t0_c", "must be in [-100, 200] deg C")?;
        check(self.drift_k1.is_finite() && self.drift_k1.abs() <= 1e-3, "drift_k1_rad_s_per_c", "must be finite with |k1| <= 1e-3 rad/s/degC")?;
        check(self.drift_k2.is_finite() && self.drift_k2.abs() <= 1e-3, "drift_k2_rad_s_per_c2", "must be finite with |k2| <= 1e-3 rad/s/degC^2")?;
        check(self.drift_k3.is_finite() && self.drift_k3.abs() <= 1.0, "drift_k3_rad_s_per_c_per_s", "must be finite with |k3| <= 1 rad/s per degC/s")
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
    gm_phi: f64,
    gm_q_sd: f64,
    arw_sd: f64,
    vrw_sd: f64,
    rrw_sd: f64,
}

impl ImuErrorModel {
    /// A model for sample interval `dt` [s], noise seeded by `seed`.
    pub fn new(p: ImuErrorParams, dt: f64, seed: u64) -> Result<Self, ParamError> {
        p.validate()?;
        let m = p.gyro_misalignment;
        let s = p.gyro_scale;
        let gyro_matrix = [[1.0 + s[0], m[0], m[1]], [m[2], 1.0 + s[1], m[3]], [m[4], m[5], 1.0 + s[2]]];
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let sigma = p.gyro_bias_instability;
        let phi = (-dt / p.gyro_correlation).exp();
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
            gm_q_sd: sigma * (-(-2.0 * dt / p.gyro_correlation).exp_m1()).sqrt(),
            arw_sd: p.gyro_arw * dt.sqrt(),
            vrw_sd: p.accel_vrw * dt.sqrt(),
            rrw_sd: p.gyro_rrw * dt.sqrt(),
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
    #[inline]
    pub fn apply(&mut self, axial_drift: f64, dtheta: &mut Vec3, dv: &mut Vec3) {
        let dt = self.dt;
        let g = &self.gyro_matrix;
        let w = *dtheta;
        let mut out = [
            g[0][0] * w[0] + g[0][1] * w[1] + g[0][2] * w[2],
            g[1][0] * w[0] + g[1][1] * w[1] + g[1][2] * w[2],
            g[2][0] * w[0] + g[2][1] * w[1] + g[2][2] * w[2],
        ];
        for (i, o) in out.iter_mut().enumerate() {
            *o += (self.p.gyro_bias[i] + self.gm[i] + self.rrw[i]) * dt;
        }
        out[2] += axial_drift * dt;
        let sa = self.p.accel_scale;
        let mut v = [dv[0] * (1.0 + sa[0]), dv[1] * (1.0 + sa[1]), dv[2] * (1.0 + sa[2])];
        for (x, b) in v.iter_mut().zip(self.p.accel_bias) {
            *x += b * dt;
        }
        if self.arw_sd > 0.0 {
            let n = self.normal3(self.arw_sd);
            for (o, x) in out.iter_mut().zip(n) {
                *o += x;
            }
        }
        if self.vrw_sd > 0.0 {
            let n = self.normal3(self.vrw_sd);
            for (o, x) in v.iter_mut().zip(n) {
                *o += x;
            }
        }
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
        *dtheta = out;
        *dv = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gm_params(sigma: f64, tau: f64) -> ImuErrorParams {
        ImuErrorParams { gyro_bias_instability: sigma, gyro_correlation: tau, ..Default::default() }
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
            assert!((c / (sigma * sigma) - (-3.0f64).exp()).abs() < 0.07, "rate {rate}: corr {c}");
        }
    }

    #[test]
    fn rate_random_walk_variance_grows_as_t_at_any_rate() {
        let rrw = 1e-7;
        let t = 50.0;
        for rate in [20.0, 200.0] {
            let p = ImuErrorParams { gyro_rrw: rrw, ..Default::default() };
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
    fn deterministic_for_a_seed() {
        let p = ImuErrorParams { gyro_arw: 1e-5, accel_vrw: 1e-4, gyro_correlation: 100.0, gyro_bias_instability: 1e-7, ..Default::default() };
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
        let p = ImuErrorParams { drift_t0_c: 20.0, drift_k1: 1.0, drift_k2: 0.5, drift_k3: 10.0, ..Default::default() };
        assert_eq!(p.axial_drift(22.0, 0.1), 2.0 + 2.0 + 1.0);
    }

    #[test]
    fn validation_names_the_key() {
        let p = ImuErrorParams { gyro_arw: -1.0, gyro_correlation: 1.0, ..Default::default() };
        assert_eq!(p.validate().unwrap_err().key, "gyro_arw_rad_rts");
        let p = ImuErrorParams { gyro_correlation: 0.0, ..Default::default() };
        assert_eq!(p.validate().unwrap_err().key, "gyro_correlation_s");
        ImuErrorParams::default().validate().unwrap();
    }
}
