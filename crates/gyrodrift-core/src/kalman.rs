//! The 12-state error-state Kalman filter of the zero-velocity fine alignment (static base, ENU).
//!
//! State x (this order everywhere, `STATE_NAMES`):
//!   0..3   phi = (phi_E, phi_N, phi_U) \[rad\], the attitude error (phi angle) of the computed n frame;
//!   3..6   dv = (dv_E, dv_N, dv_U) [m/s], velocity error, computed minus true;
//!   6..9   eps = (eps_x, eps_y, eps_z) [rad/s], residual gyro bias in the BODY frame (measured minus
//!          true rate after the current estimate is subtracted);
//!   9..12  nabla = (nabla_x, nabla_y, nabla_z) [m/s^2], residual accelerometer bias, body frame.
//!
//! Signs (as PSINS `qdelphi`): the computed C_b^n' = (I - [phi x]) C_b^n, so the correction of a
//! computed attitude is q <- q(phi) o q; v <- v - dv; the bias estimates grow by eps and nabla.
//!
//! Continuous model on a static base, v = 0: the phi-angle error equations of the local-level mechanisation
//! (Yan Gongmin 2016, the PSINS book, chapter on SINS error equations; PSINS `etm`; KF-GINS writes the same in NED):
//!   phi_dot = -w_ie^n x phi + M_av dv - C_b^n eps,
//!   dv_dot  =  f^n x phi - 2 w_ie^n x dv + C_b^n nabla,
//! with M_av dv = (-dv_N / (R_M + h), dv_E / (R_N + h), dv_E tan(lat) / (R_N + h)) and f^n = (0, 0, g).
//! The biases are random constants (eps_dot = 0, nabla_dot = 0). The navigator holds its vertical channel
//! fixed (v_U = 0, height held), so dv_U is identically zero: its row of F is zero and it takes no noise.
//! Hence nabla_z is seen only through the tilt of the body z axis and stays essentially at its prior.
//! C_b^n changes as the table turns; F uses its mean over the update interval.
//!
//! Discretisation over T (the update interval): Phi = I + F T + (F T)^2 / 2, and
//! Q_k = (Phi Q_c Phi' + Q_c) T / 2 (trapezoidal), Q_c = diag(ARW^2 I_3, VRW^2 (1, 1, 0), 0_6): the gyro white
//! noise enters phi through C_b^n, and C_b^n diag(s^2) C_n^b = s^2 I for equal densities.
//! Measurement: the computed velocity, whose truth is zero: z = v = H x + r, H = [0 I_3 0], r ~ N(0, R I_3).
//! Covariance update in Joseph form, P = (I - K H) P (I - K H)' + K R K', symmetrised after each step.

use crate::attitude::{Mat3, Vec3};
use crate::earth;
use nalgebra::{SMatrix, SVector};

/// Number of states.
pub const N_STATES: usize = 12;
/// State vector type.
pub type StateVector = SVector<f64, N_STATES>;
/// State covariance type.
pub type StateMatrix = SMatrix<f64, N_STATES, N_STATES>;

/// Names of the states, in order (units: rad, m/s, rad/s, m/s^2; see the module docs).
pub const STATE_NAMES: [&str; N_STATES] = [
    "phi_e",
    "phi_n",
    "phi_u",
    "dv_e",
    "dv_n",
    "dv_u",
    "gyro_bias_x",
    "gyro_bias_y",
    "gyro_bias_z",
    "accel_bias_x",
    "accel_bias_y",
    "accel_bias_z",
];

/// Index of the first attitude, velocity, gyro-bias and accelerometer-bias state.
pub const PHI: usize = 0;
pub const DV: usize = 3;
pub const EPS: usize = 6;
pub const NABLA: usize = 9;

/// Site constants of the static-base error model.
#[derive(Clone, Copy, Debug)]
pub struct ErrorModel {
    /// Earth rate in ENU [rad/s].
    w_ie: Vec3,
    /// Specific force in ENU, (0, 0, g) [m/s^2].
    f_n: Vec3,
    /// 1 / (R_M + h), 1 / (R_N + h) [1/m], tan(lat).
    inv_rm_h: f64,
    inv_rn_h: f64,
    tan_lat: f64,
}

impl ErrorModel {
    /// The model at latitude `lat` \[rad\] and height `height` \[m\].
    pub fn new(lat: f64, height: f64) -> Self {
        ErrorModel {
            w_ie: earth::earth_rate_enu(lat),
            f_n: [0.0, 0.0, earth::normal_gravity(lat, height)],
            inv_rm_h: 1.0 / (earth::meridian_radius(lat) + height),
            inv_rn_h: 1.0 / (earth::transverse_radius(lat) + height),
            tan_lat: lat.tan(),
        }
    }

    /// Continuous system matrix F (module docs) for the body-to-nav DCM `c_bn` (C_b^n).
    pub fn system_matrix(&self, c_bn: &Mat3) -> StateMatrix {
        let mut f = StateMatrix::zeros();
        // phi row: -[w_ie x] phi + M_av dv - C_b^n eps.
        set_block(&mut f, PHI, PHI, &neg(&skew(self.w_ie)));
        f[(PHI, DV + 1)] = -self.inv_rm_h;
        f[(PHI + 1, DV)] = self.inv_rn_h;
        f[(PHI + 2, DV)] = self.inv_rn_h * self.tan_lat;
        set_block(&mut f, PHI, EPS, &neg(c_bn));
        // dv row (horizontal only: the vertical channel is held): [f^n x] phi - 2 [w_ie x] dv + C_b^n nabla.
        let fx = skew(self.f_n);
        let wx2 = skew([2.0 * self.w_ie[0], 2.0 * self.w_ie[1], 2.0 * self.w_ie[2]]);
        for i in 0..2 {
            for j in 0..3 {
                f[(DV + i, PHI + j)] = fx[i][j];
                f[(DV + i, DV + j)] = -wx2[i][j];
                f[(DV + i, NABLA + j)] = c_bn[i][j];
            }
        }
        f
    }

    /// Transition matrix over `t` \[s\]: Phi = I + F t + (F t)^2 / 2.
    pub fn transition(&self, c_bn: &Mat3, t: f64) -> StateMatrix {
        let ft = self.system_matrix(c_bn) * t;
        StateMatrix::identity() + ft + ft * ft * 0.5
    }
}

/// Discrete process noise over `t` \[s\] (module docs): gyro white noise `arw` [rad/sqrt(s)] into phi,
/// accelerometer white noise `vrw` [m/s/sqrt(s)] into the horizontal velocity.
pub fn process_noise(phi: &StateMatrix, arw: f64, vrw: f64, t: f64) -> StateMatrix {
    let mut qc = StateMatrix::zeros();
    for i in 0..3 {
        qc[(PHI + i, PHI + i)] = arw * arw;
    }
    for i in 0..2 {
        qc[(DV + i, DV + i)] = vrw * vrw;
    }
    let q = (phi * qc * phi.transpose() + qc) * (0.5 * t);
    symmetrise(q)
}

/// The error-state filter: state estimate and covariance.
#[derive(Clone, Debug)]
pub struct ErrorStateFilter {
    x: StateVector,
    p: StateMatrix,
}

impl ErrorStateFilter {
    /// Zero initial state with diagonal covariance diag(`sigma`^2).
    pub fn new(sigma: &[f64; N_STATES]) -> Self {
        let mut p = StateMatrix::zeros();
        for (i, s) in sigma.iter().enumerate() {
            p[(i, i)] = s * s;
        }
        ErrorStateFilter {
            x: StateVector::zeros(),
            p,
        }
    }

    /// The current error-state estimate.
    pub fn state(&self) -> &StateVector {
        &self.x
    }

    /// The current covariance.
    pub fn covariance(&self) -> &StateMatrix {
        &self.p
    }

    /// 1-sigma of every state (square roots of the diagonal of P).
    pub fn std(&self) -> [f64; N_STATES] {
        std::array::from_fn(|i| self.p[(i, i)].max(0.0).sqrt())
    }

    /// Time update: x <- Phi x, P <- Phi P Phi' + Q.
    pub fn predict(&mut self, phi: &StateMatrix, q: &StateMatrix) {
        self.x = phi * self.x;
        self.p = symmetrise(phi * self.p * phi.transpose() + q);
    }

    /// Zero-velocity measurement update with the computed velocity `v` [m/s] (true velocity zero) and
    /// measurement noise 1-sigma `sigma` [m/s] per axis; Joseph-form covariance update. With sigma > 0 the
    /// innovation covariance H P H' + R is positive definite as long as P is finite; an error (the message)
    /// if P or v is no longer finite, and then the filter is left unchanged.
    pub fn update_zero_velocity(&mut self, v: Vec3, sigma: f64) -> Result<(), String> {
        let mut h = SMatrix::<f64, 3, N_STATES>::zeros();
        for i in 0..3 {
            h[(i, DV + i)] = 1.0;
        }
        let r = SMatrix::<f64, 3, 3>::identity() * (sigma * sigma);
        let z = SVector::<f64, 3>::from_column_slice(&v);
        let s = h * self.p * h.transpose() + r;
        let s_inv = match s.try_inverse() {
            Some(m) if m.iter().all(|x| x.is_finite()) && v.iter().all(|x| x.is_finite()) => m,
            _ => {
                return Err(format!(
                    "the zero-velocity update has no finite solution (velocity {:?} m/s, innovation \
                     covariance not invertible or not finite)",
                    v
                ))
            }
        };
        let k = self.p * h.transpose() * s_inv;
        self.x += k * (z - h * self.x);
        let i_kh = StateMatrix::identity() - k * h;
        self.p = symmetrise(i_kh * self.p * i_kh.transpose() + k * r * k.transpose());
        Ok(())
    }

    /// Hand over the estimate for feedback correction and reset the error state to zero (closed loop).
    pub fn take_correction(&mut self) -> StateVector {
        std::mem::replace(&mut self.x, StateVector::zeros())
    }
}

/// (M + M') / 2.
fn symmetrise(m: StateMatrix) -> StateMatrix {
    (m + m.transpose()) * 0.5
}

/// Cross-product matrix [v x] (row-major).
fn skew(v: Vec3) -> Mat3 {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

fn neg(m: &Mat3) -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| -m[i][j]))
}

/// Write the 3x3 block `m` at (`row`, `col`).
fn set_block(f: &mut StateMatrix, row: usize, col: usize, m: &Mat3) {
    for (i, r) in m.iter().enumerate() {
        for (j, x) in r.iter().enumerate() {
            f[(row + i, col + j)] = *x;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_body_model_has_the_textbook_couplings() {
        let m = ErrorModel::new(0.5, 0.0);
        let c = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let f = m.system_matrix(&c);
        let g = earth::normal_gravity(0.5, 0.0);
        // dv_E_dot = -g phi_N + nabla_x; dv_N_dot = g phi_E + nabla_y; phi_E_dot = -eps_x + ...
        assert_eq!(f[(DV, PHI + 1)], -g);
        assert_eq!(f[(DV + 1, PHI)], g);
        assert_eq!(f[(DV, NABLA)], 1.0);
        assert_eq!(f[(PHI, EPS)], -1.0);
        // phi_E_dot = w_U phi_N - w_N phi_U.
        let w = earth::earth_rate_enu(0.5);
        assert_eq!(f[(PHI, PHI + 1)], w[2]);
        assert_eq!(f[(PHI, PHI + 2)], -w[1]);
        // The held vertical channel has no dynamics.
        assert!((0..N_STATES).all(|j| f[(DV + 2, j)] == 0.0));
    }

    #[test]
    fn joseph_update_shrinks_the_measured_states() {
        let mut kf = ErrorStateFilter::new(&[1.0; N_STATES]);
        kf.update_zero_velocity([0.5, 0.0, 0.0], 1.0).unwrap();
        assert!((kf.state()[DV] - 0.25).abs() < 1e-15);
        assert!((kf.covariance()[(DV, DV)] - 0.5).abs() < 1e-15);
        assert_eq!(kf.covariance()[(PHI, PHI)], 1.0);
        let x = kf.take_correction();
        assert!((x[DV] - 0.25).abs() < 1e-15);
        assert_eq!(kf.state().norm(), 0.0);
    }
}
