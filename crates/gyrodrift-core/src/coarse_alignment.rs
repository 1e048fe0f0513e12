//! Coarse alignment on a static base in the inertial frame (indirect analytic alignment, PSINS `aligni0`).
//!
//! Frames (the inertial-frame alignment of Qin Yongyuan and of Yan Gongmin 2016, PSINS `aligni0`):
//! - n: ENU at the site; i0: the n frame frozen in inertial space at the start t0 of the span;
//! - b: the body (it may rotate on the turntable); ib0: the b frame frozen in inertial space at t0.
//!
//! The attitude factors as C_b^n(t) = C_i0^n(t) C_ib0^i0 C_b^ib0(t), where
//! - C_b^ib0(t) is integrated from the gyros alone (the body rotation, table included, is measured), with
//!   q_k = q_{k-1} o q(phi_k) and the coning-corrected rotation vector phi_k of `strapdown::coning_sculling`;
//! - C_n^i0(t) = Rot(u, w_ie t), u = w_ie^n / w_ie, is known in closed form (the Earth turns the n frame);
//! - C_ib0^i0 = C_b^n(t0) is constant because both frames are inertial: it is the unknown.
//!
//! On a static base the specific force is f^n = -g^n = (0, 0, g). Its integrals in the two inertial frames,
//!     v^ib0(t) = int_0^t C_b^ib0 f^b dt     (summed from the velocity increments, sculling-corrected),
//!     v^i0(t)  = int_0^t C_n^i0 f^n dt      (closed form, `earth_frame_velocity`),
//! satisfy v^i0(t) = C_ib0^i0 v^ib0(t) for every t. Two epochs (the middle and the end of the span) give two
//! non-collinear vector pairs (the gravity direction turns with the Earth by w_ie cos(lat) t / 4 between them),
//! and the double-vector method (`triad`) gives C_ib0^i0. Body rotation cancels exactly: it is in C_b^ib0.
//!
//! The horizontal accelerometer bias b = (b_x, b_y) (body frame) adds M(t) b to v^ib0(t), with
//! M(t) = int_0^t C_b^ib0 dt known from the gyros. With the table turning this term is a bounded oscillation of
//! amplitude ~ |b| / w_table whose mean is not zero (it depends on the phase at the start and flips at every
//! reversal): at 6 deg/s, 64 ug turns the two-epoch heading by ~330 arcsec. So b is estimated jointly, by
//! alternating (`ALTERNATIONS` rounds at most, until the attitude moves by less than `CONVERGED_RAD`)
//! - the two-epoch solution C_ib0^i0 = `triad` on the corrected vectors v^ib0 - M b at the two epochs, and
//! - the least-squares fit of b to the residuals y_j = v^ib0_j - C_i0^ib0 v^i0_j = M_j b + trend_j over every
//!   sample j, where trend_j, a cubic polynomial in time per axis, absorbs the smooth residuals that the
//!   attitude error of the current round and the sensor noise leave (tilt ~ t, heading ~ t^2 and t^3, random
//!   walks): b is then fixed by the oscillation only. Without the trend the fit trades b against the heading
//!   and multiplies the ARW error several times under continuous rotation. The normal equations do not
//!   depend on C and are summed while streaming (`BiasFitSums`, constant memory).
//!
//! Without rotation M_j b = b t_j looks like a tilt and b is not observable: the fit runs only if the table
//! turned enough to modulate it, i.e. if the mean of C_b^ib0 e_x and of C_b^ib0 e_y over the span
//! (M(T)[:, x] / T, M(T)[:, y] / T) are shorter than `MODULATION_THRESHOLD` (1 for a still table, about 0 for
//! whole turns); otherwise the classical solution stays. (A joint Gauss-Newton fit of C and b over
//! all samples was tried: it is 10-30 times noisier in heading with ARW, and needs a prior without rotation.)
//!
//! Error budget (closed forms, static base): without rotation, levelling error ~ accelerometer bias / g and
//! heading error ~ eps_E / (w_ie cos lat) (east gyro bias). With the table turning, the horizontal gyro biases
//! are modulated and drop out, the horizontal accelerometer biases are estimated, and what is left is the noise
//! (ARW: heading ~ ARW / (w_ie cos lat sqrt(T)) times a small factor) and the axial gyro bias, which turns the
//! heading by eps_z T / 2 at most.

use crate::attitude::{
    add, cross, dcm_to_rotvec, mat_mul, norm, quat_mul, quat_normalize, quat_rotate, quat_to_dcm, rotvec_to_quat,
    scale, sub, transpose, Mat3, Quat, Vec3, QUAT_IDENTITY,
};
use crate::earth;
use crate::error::{check_with, CoreError};
use crate::strapdown::coning_sculling;

/// What the coarse alignment finds at the end of its span.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoarseSolution {
    /// C_b^n at the end of the span.
    pub c_bn: Mat3,
    /// Horizontal accelerometer bias (body x, y) [m/s^2] fitted jointly (about zero without rotation).
    pub accel_bias_xy: [f64; 2],
}

/// The inertial-frame coarse alignment of a span of `n_samples` samples (streaming).
#[derive(Clone, Debug)]
pub struct InertialCoarseAlignment {
    lat: f64,
    /// Normal gravity at the site [m/s^2].
    g: f64,
    dt: f64,
    n_samples: u64,
    /// Samples processed.
    k: u64,
    /// q_b^ib0: body attitude relative to the frozen initial body frame.
    q_b_ib0: Quat,
    /// Integrated specific force in ib0 [m/s].
    v_ib0: Vec3,
    /// M = int C_b^ib0 dt [s]: the map of a body-frame accelerometer bias into v^ib0.
    m_ib0: Mat3,
    /// v^ib0 at the middle epoch (sample n_samples / 2) [m/s].
    v_ib0_mid: Vec3,
    /// M at the middle epoch [s].
    m_ib0_mid: Mat3,
    /// Normal-equation sums of the bias fit (see `BiasFitSums`).
    sums: BiasFitSums,
    dtheta_prev: Vec3,
    dv_prev: Vec3,
}

/// The bias fit runs only below this length of the mean horizontal body axes in ib0 (module docs) [-].
pub const MODULATION_THRESHOLD: f64 = 0.5;
/// Largest number of rounds of the two-epoch / bias-fit alternation.
pub const ALTERNATIONS: usize = 50;
/// The alternation stops when the attitude changes by less than this \[rad\] in one round.
pub const CONVERGED_RAD: f64 = 1e-9;

/// Polynomial terms of the trend per axis (1, tau, tau^2, tau^3 with tau = t / span).
const TREND_TERMS: usize = 4;
/// Unknowns of the bias fit: (b_x, b_y) and the trend coefficients of the three axes.
const FIT_UNKNOWNS: usize = 2 + 3 * TREND_TERMS;
type FitMatrix = nalgebra::SMatrix<f64, FIT_UNKNOWNS, FIT_UNKNOWNS>;
type FitVector = nalgebra::SVector<f64, FIT_UNKNOWNS>;

/// Sums over the samples j of the fit y_j = R_j theta, R_j = [M_j[:, 0..2], I_3 (x) (1, tau, tau^2, tau^3)]
/// (3 x `FIT_UNKNOWNS`): `rr` = sum R_j' R_j, `rw` = sum R_j' v^ib0_j, `rv[l]` = sum R_j' v^i0_j[l] e_k for
/// each k (stored as `rv[k][l]`), so that sum R_j' y_j = rw - sum_kl C[l][k] rv[k][l] for any C = C_ib0^i0.
#[derive(Clone, Debug)]
struct BiasFitSums {
    rr: FitMatrix,
    rw: FitVector,
    rv: [[FitVector; 3]; 3],
}

impl Default for BiasFitSums {
    fn default() -> Self {
        BiasFitSums {
            rr: FitMatrix::zeros(),
            rw: FitVector::zeros(),
            rv: [[FitVector::zeros(); 3]; 3],
        }
    }
}

impl BiasFitSums {
    /// Row k (axis) of R_j at normalised time `tau`.
    fn row(m: &Mat3, tau: f64, k: usize) -> FitVector {
        let mut r = FitVector::zeros();
        r[0] = m[k][0];
        r[1] = m[k][1];
        let mut p = 1.0;
        for i in 0..TREND_TERMS {
            r[2 + k * TREND_TERMS + i] = p;
            p *= tau;
        }
        r
    }

    fn add(&mut self, m: &Mat3, tau: f64, w: Vec3, v: Vec3) {
        for (k, (rv_k, w_k)) in self.rv.iter_mut().zip(w).enumerate() {
            let r = Self::row(m, tau, k);
            self.rr.ger(1.0, &r, &r, 1.0);
            self.rw.axpy(w_k, &r, 1.0);
            for (rv_kl, v_l) in rv_k.iter_mut().zip(v) {
                rv_kl.axpy(v_l, &r, 1.0);
            }
        }
    }

    /// Least-squares (b_x, b_y) [m/s^2] given C_ib0^i0 (`c`), residuals y_j = v^ib0_j - C' v^i0_j.
    /// None if the normal matrix is singular.
    fn solve(&self, c: &Mat3) -> Option<[f64; 2]> {
        let mut rhs = self.rw;
        for (k, rv_k) in self.rv.iter().enumerate() {
            for (c_l, rv_kl) in c.iter().zip(rv_k) {
                // (C' v)_k = sum_l C[l][k] v_l.
                rhs.axpy(-c_l[k], rv_kl, 1.0);
            }
        }
        let theta = self.rr.cholesky()?.solve(&rhs);
        Some([theta[0], theta[1]])
    }
}

impl InertialCoarseAlignment {
    /// A span of `n_samples` (at least 2) samples at `rate_hz` \[Hz\] at latitude `lat` \[rad\], height `height` \[m\].
    pub fn new(lat: f64, height: f64, rate_hz: f64, n_samples: u64) -> Result<Self, CoreError> {
        check_with(n_samples >= 2, "coarse_s", || {
            format!("the coarse span holds {n_samples} samples, at least 2 are needed")
        })?;
        Ok(InertialCoarseAlignment {
            lat,
            g: earth::normal_gravity(lat, height),
            dt: 1.0 / rate_hz,
            n_samples,
            k: 0,
            q_b_ib0: QUAT_IDENTITY,
            v_ib0: [0.0; 3],
            m_ib0: [[0.0; 3]; 3],
            v_ib0_mid: [0.0; 3],
            m_ib0_mid: [[0.0; 3]; 3],
            sums: BiasFitSums::default(),
            dtheta_prev: [0.0; 3],
            dv_prev: [0.0; 3],
        })
    }

    /// True when all samples of the span have been processed.
    pub fn is_complete(&self) -> bool {
        self.k >= self.n_samples
    }

    /// Samples processed so far.
    pub fn samples_done(&self) -> u64 {
        self.k
    }

    /// One sample of raw increments (dtheta \[rad\], dv [m/s], body frame). Ignored once the span is complete.
    pub fn step(&mut self, dtheta: Vec3, dv: Vec3) {
        if self.is_complete() {
            return;
        }
        let (phi, dv_b) = coning_sculling(dtheta, dv, self.dtheta_prev, self.dv_prev);
        // dv_b is resolved in the body frame at the start of the sample: rotate with the old attitude.
        self.v_ib0 = add(self.v_ib0, quat_rotate(self.q_b_ib0, dv_b));
        let c_old = quat_to_dcm(self.q_b_ib0);
        self.q_b_ib0 = quat_normalize(quat_mul(self.q_b_ib0, rotvec_to_quat(phi)));
        let c_new = quat_to_dcm(self.q_b_ib0);
        // A constant body-frame bias integrates through the mean attitude of the sample (trapezoid).
        for i in 0..3 {
            for j in 0..3 {
                self.m_ib0[i][j] += 0.5 * (c_old[i][j] + c_new[i][j]) * self.dt;
            }
        }
        self.dtheta_prev = dtheta;
        self.dv_prev = dv;
        self.k += 1;
        let v_i0 = earth_frame_velocity(self.lat, self.g, self.k as f64 * self.dt);
        let tau = self.k as f64 / self.n_samples as f64;
        self.sums.add(&self.m_ib0, tau, self.v_ib0, v_i0);
        if self.k == self.n_samples / 2 {
            self.v_ib0_mid = self.v_ib0;
            self.m_ib0_mid = self.m_ib0;
        }
    }

    /// True if the table turned enough over the span for the horizontal accelerometer bias to be fitted.
    fn bias_is_modulated(&self, t_end: f64) -> bool {
        let m = &self.m_ib0;
        (0..2).all(|a| (m[0][a].powi(2) + m[1][a].powi(2) + m[2][a].powi(2)).sqrt() < MODULATION_THRESHOLD * t_end)
    }

    /// C_b^n at the end of the span (None before it is complete).
    pub fn attitude(&self) -> Option<Mat3> {
        self.solve().map(|s| s.c_bn)
    }

    /// The solution at the end of the span (None before it is complete).
    pub fn solve(&self) -> Option<CoarseSolution> {
        if !self.is_complete() {
            return None;
        }
        let t_mid = (self.n_samples / 2) as f64 * self.dt;
        let t_end = self.n_samples as f64 * self.dt;
        let v_i0_mid = earth_frame_velocity(self.lat, self.g, t_mid);
        let v_i0_end = earth_frame_velocity(self.lat, self.g, t_end);
        // C_ib0^i0 maps the bias-corrected v^ib0 onto v^i0 at both epochs; alternate with the bias fit.
        let mut bias = [0.0; 2];
        let mut c_ib0_i0 = triad(self.v_ib0_mid, self.v_ib0, v_i0_mid, v_i0_end);
        let rounds = if self.bias_is_modulated(t_end) { ALTERNATIONS } else { 0 };
        for _ in 0..rounds {
            let Some(b) = self.sums.solve(&c_ib0_i0) else { break };
            bias = b;
            let a1 = sub(self.v_ib0_mid, bias_velocity(&self.m_ib0_mid, bias));
            let a2 = sub(self.v_ib0, bias_velocity(&self.m_ib0, bias));
            let c_new = triad(a1, a2, v_i0_mid, v_i0_end);
            let change = norm(dcm_to_rotvec(&mat_mul(&c_new, &transpose(&c_ib0_i0))));
            c_ib0_i0 = c_new;
            if change < CONVERGED_RAD {
                break;
            }
        }
        let c_i0_n = transpose(&earth_rotation(self.lat, t_end));
        let c_bn = mat_mul(&c_i0_n, &mat_mul(&c_ib0_i0, &quat_to_dcm(self.q_b_ib0)));
        Some(CoarseSolution {
            c_bn,
            accel_bias_xy: bias,
        })
    }
}

/// M[:, 0..2] b: the velocity [m/s] that a horizontal body-frame bias b = (b_x, b_y) adds to v^ib0.
fn bias_velocity(m: &Mat3, b: [f64; 2]) -> Vec3 {
    std::array::from_fn(|i| m[i][0] * b[0] + m[i][1] * b[1])
}

/// C_n^i0(t): the rotation of the n frame in inertial space after `t` \[s\] on a static base, the rotation by
/// w_ie t about the Earth axis u = (0, cos lat, sin lat) (ENU coordinates at t0), by Rodrigues' formula
/// R = cos a I + (1 - cos a) u u' + sin a [u x].
pub fn earth_rotation(lat: f64, t: f64) -> Mat3 {
    let u = scale(earth::earth_rate_enu(lat), 1.0 / earth::OMEGA_IE);
    let (s, c) = (earth::OMEGA_IE * t).sin_cos();
    rodrigues_combination(u, c, 1.0 - c, s)
}

/// v^i0(t) = int_0^t C_n^i0(tau) dtau f^n [m/s] with f^n = (0, 0, g) (static base), in closed form:
/// int_0^t R dtau = (sin(w t) / w) I + (t - sin(w t) / w) u u' + ((1 - cos(w t)) / w) [u x], w = w_ie.
pub fn earth_frame_velocity(lat: f64, g: f64, t: f64) -> Vec3 {
    let w = earth::OMEGA_IE;
    let u = scale(earth::earth_rate_enu(lat), 1.0 / w);
    let (s, c) = (w * t).sin_cos();
    let m = rodrigues_combination(u, s / w, t - s / w, (1.0 - c) / w);
    [m[0][2] * g, m[1][2] * g, m[2][2] * g]
}

/// a I + b u u' + c [u x] for a unit vector u.
fn rodrigues_combination(u: Vec3, a: f64, b: f64, c: f64) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = b * u[i] * u[j] + if i == j { a } else { 0.0 };
        }
    }
    m[0][1] -= c * u[2];
    m[0][2] += c * u[1];
    m[1][0] += c * u[2];
    m[1][2] -= c * u[0];
    m[2][0] -= c * u[1];
    m[2][1] += c * u[0];
    m
}

/// Double-vector attitude determination (TRIAD; PSINS `dv2atti`): the rotation C with b1 = C a1 exactly in
/// direction and b2 = C a2 as closely as possible (a1 is the reference direction).
pub fn triad(a1: Vec3, a2: Vec3, b1: Vec3, b2: Vec3) -> Mat3 {
    let ta = orthonormal_triad(a1, a2);
    let tb = orthonormal_triad(b1, b2);
    // C = Tb Ta' with the triad vectors as columns; here they are rows, so C = Tb' Ta.
    mat_mul(&transpose(&tb), &ta)
}

/// Rows: v1 / |v1|, (v1 x v2) / |v1 x v2|, and their cross product.
fn orthonormal_triad(v1: Vec3, v2: Vec3) -> Mat3 {
    let e1 = scale(v1, 1.0 / norm(v1));
    let w = cross(v1, v2);
    let e2 = scale(w, 1.0 / norm(w));
    [e1, e2, cross(e1, e2)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{mat_vec, rot_x, rot_z, transpose};

    fn close(a: &Mat3, b: &Mat3, tol: f64) -> bool {
        (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() < tol))
    }

    #[test]
    fn triad_recovers_a_rotation() {
        let c = mat_mul(&rot_z(0.7), &rot_x(-0.2));
        let (a1, a2) = ([1.0, 2.0, 3.0], [-0.5, 0.1, 2.0]);
        let got = triad(a1, a2, mat_vec(&c, a1), mat_vec(&c, a2));
        assert!(close(&got, &c, 1e-14));
    }

    #[test]
    fn earth_frame_velocity_is_the_integral_of_the_rotation() {
        let (lat, g, t) = (0.49, 9.79, 300.0);
        let n = 30_000;
        let h = t / n as f64;
        let mut v = [0.0; 3];
        for k in 0..n {
            let r = earth_rotation(lat, (k as f64 + 0.5) * h);
            v = add(v, scale([r[0][2], r[1][2], r[2][2]], g * h));
        }
        let v_cf = earth_frame_velocity(lat, g, t);
        assert!(
            norm(crate::attitude::sub(v, v_cf)) < 1e-9 * norm(v_cf),
            "{v:?} vs {v_cf:?}"
        );
        // The Earth rotation is a proper rotation that keeps the Earth axis.
        let r = earth_rotation(lat, 5000.0);
        let u = [0.0, lat.cos(), lat.sin()];
        assert!(norm(crate::attitude::sub(mat_vec(&r, u), u)) < 1e-15);
        assert!(close(
            &mat_mul(&r, &transpose(&r)),
            &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            1e-15
        ));
    }
}
