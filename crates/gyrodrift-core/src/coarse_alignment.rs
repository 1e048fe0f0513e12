//! Coarse alignment on a static base in the inertial frame (indirect analytic alignment, PSINS `aligni0`).
//!
//! Frames (Qin Yongyuan; Yan Gongmin 2016, sec. 7.1.3 "inertial-frame alignment"):
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
//! Error budget (closed forms, static base, no rotation): levelling error ~ accelerometer bias / g, heading
//! error ~ eps_E / (w_ie cos lat) (east gyro bias). With the table turning, the horizontal biases are
//! modulated in the inertial frames and the errors are smaller; the axial (z) gyro bias is not modulated.

use crate::attitude::{
    add, cross, mat_mul, norm, quat_mul, quat_normalize, quat_rotate, quat_to_dcm, rotvec_to_quat, scale,
    transpose, Mat3, Quat, Vec3, QUAT_IDENTITY,
};
use crate::earth;
use crate::strapdown::coning_sculling;

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
    /// v^ib0 at the middle epoch (sample n_samples / 2) [m/s].
    v_ib0_mid: Vec3,
    dtheta_prev: Vec3,
    dv_prev: Vec3,
}

impl InertialCoarseAlignment {
    /// A span of `n_samples` (at least 2) samples at `rate_hz` [Hz] at latitude `lat` [rad], height `height` [m].
    pub fn new(lat: f64, height: f64, rate_hz: f64, n_samples: u64) -> Self {
        assert!(n_samples >= 2, "the coarse span needs at least 2 samples");
        InertialCoarseAlignment {
            lat,
            g: earth::normal_gravity(lat, height),
            dt: 1.0 / rate_hz,
            n_samples,
            k: 0,
            q_b_ib0: QUAT_IDENTITY,
            v_ib0: [0.0; 3],
            v_ib0_mid: [0.0; 3],
            dtheta_prev: [0.0; 3],
            dv_prev: [0.0; 3],
        }
    }

    /// True when all samples of the span have been processed.
    pub fn is_complete(&self) -> bool {
        self.k >= self.n_samples
    }

    /// Samples processed so far.
    pub fn samples_done(&self) -> u64 {
        self.k
    }

    /// One sample of raw increments (dtheta [rad], dv [m/s], body frame). Ignored once the span is complete.
    pub fn step(&mut self, dtheta: Vec3, dv: Vec3) {
        if self.is_complete() {
            return;
        }
        let (phi, dv_b) = coning_sculling(dtheta, dv, self.dtheta_prev, self.dv_prev);
        // dv_b is resolved in the body frame at the start of the sample: rotate with the old attitude.
        self.v_ib0 = add(self.v_ib0, quat_rotate(self.q_b_ib0, dv_b));
        self.q_b_ib0 = quat_normalize(quat_mul(self.q_b_ib0, rotvec_to_quat(phi)));
        self.dtheta_prev = dtheta;
        self.dv_prev = dv;
        self.k += 1;
        if self.k == self.n_samples / 2 {
            self.v_ib0_mid = self.v_ib0;
        }
    }

    /// C_b^n at the end of the span (None before it is complete).
    pub fn attitude(&self) -> Option<Mat3> {
        if !self.is_complete() {
            return None;
        }
        let t_mid = (self.n_samples / 2) as f64 * self.dt;
        let t_end = self.n_samples as f64 * self.dt;
        let v_i0_mid = earth_frame_velocity(self.lat, self.g, t_mid);
        let v_i0_end = earth_frame_velocity(self.lat, self.g, t_end);
        // C_ib0^i0 maps v^ib0 onto v^i0 at both epochs.
        let c_ib0_i0 = triad(self.v_ib0_mid, self.v_ib0, v_i0_mid, v_i0_end);
        let c_i0_n = transpose(&earth_rotation(self.lat, t_end));
        Some(mat_mul(&c_i0_n, &mat_mul(&c_ib0_i0, &quat_to_dcm(self.q_b_ib0))))
    }
}

/// C_n^i0(t): the rotation of the n frame in inertial space after `t` [s] on a static base, the rotation by
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
        assert!(norm(crate::attitude::sub(v, v_cf)) < 1e-9 * norm(v_cf), "{v:?} vs {v_cf:?}");
        // The Earth rotation is a proper rotation that keeps the Earth axis.
        let r = earth_rotation(lat, 5000.0);
        let u = [0.0, lat.cos(), lat.sin()];
        assert!(norm(crate::attitude::sub(mat_vec(&r, u), u)) < 1e-15);
        assert!(close(&mat_mul(&r, &transpose(&r)), &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 1e-15));
    }
}
