//! The forward pass: the Kalman filter after the coarse alignment, with the navigator it corrects (closed loop),
//! and the store of every update the backward pass needs.

use super::model::{joseph, measurement_noise, symmetrise, Model, Sandwich, MEASURED};
use super::{SmootherConfig, POS};
use crate::attitude::Mat3;
use crate::earth;
use crate::error::CoreError;
use crate::kalman::{DV, EPS, NABLA, PHI};
use crate::strapdown::Navigator;
use nalgebra::{DMatrix, DVector};

/// What the forward pass keeps of one update for the backward pass.
#[derive(Clone, Debug)]
pub(super) struct Step {
    /// Time of the update \[s\] from the first sample.
    pub(super) t: f64,
    /// x_{k|k} (before the feedback) and P_{k|k}.
    pub(super) x: DVector<f64>,
    pub(super) p: DMatrix<f64>,
    /// Transition to the next update (set when the next update comes).
    pub(super) phi_next: Option<DMatrix<f64>>,
    /// The navigator's z gyro bias [rad/s] and all three gyro biases before this update's feedback.
    pub(super) gyro_bias: [f64; 3],
    pub(super) accel_bias: [f64; 3],
    /// T - T_ref at the update \[deg C\] (0 without the thermal state).
    pub(super) dtemp: f64,
}

/// The forward filter and its store (after the coarse alignment).
#[derive(Clone, Debug)]
pub(super) struct Forward {
    pub(super) nav: Navigator,
    pub(super) model: Model,
    pub(super) x: DVector<f64>,
    pub(super) p: DMatrix<f64>,
    pub(super) gyro_bias: [f64; 3],
    pub(super) accel_bias: [f64; 3],
    pub(super) c_sum: Mat3,
    /// Sum of T - T_ref over the interval \[deg C\], T_ref, and the temperature range and last value after the
    /// coarse alignment (thermal state only).
    pub(super) temp_sum: f64,
    pub(super) temp_ref: f64,
    pub(super) temp_min: f64,
    pub(super) temp_max: f64,
    pub(super) temp_last: f64,
    pub(super) n_interval: u64,
    pub(super) steps: Vec<Step>,
    /// P_{k+1|k} of each step's successor (parallel to `steps`, one fewer at the end).
    pub(super) p_pred: Vec<DMatrix<f64>>,
    pub(super) x_pred: Vec<DVector<f64>>,
    pub(super) max_att: f64,
    pub(super) max_vel: f64,
    pub(super) max_pos: f64,
}

impl Forward {
    /// Predict over the interval just ended, update with zero velocity and the known position, feed back.
    pub(super) fn update(&mut self, cfg: &SmootherConfig, t_s: f64, fine_t: f64) -> Result<(), CoreError> {
        let n_int = self.n_interval as f64;
        let t = n_int / cfg.rate_hz;
        let c_mean: Mat3 = std::array::from_fn(|i| std::array::from_fn(|j| self.c_sum[i][j] / n_int));
        let (phi, q) = self.model.discretise(&c_mean, self.temp_sum / n_int, t);
        let x_pred = &phi * &self.x;
        let p_pred = symmetrise(Sandwich::new(&phi).apply(&self.p) + q);
        if let Some(prev) = self.steps.last_mut() {
            prev.phi_next = Some(phi);
        }
        // Measurements: velocity (3) and position north, east (2) [m].
        let s = self.nav.state();
        let rm = earth::meridian_radius(cfg.lat) + cfg.height;
        let rn = earth::transverse_radius(cfg.lat) + cfg.height;
        let z = DVector::from_vec(vec![
            s.vel[0],
            s.vel[1],
            s.vel[2],
            (s.lat - cfg.lat) * rm,
            (s.lon - cfg.lon) * rn * cfg.lat.cos(),
        ]);
        let n = self.model.n;
        let r = measurement_noise(cfg);
        let diverged = |message: String| CoreError::Diverged {
            key: "dv_m_s",
            t_s,
            message,
        };
        // H selects the MEASURED states: H P H' and P H' are P's rows and columns (model::joseph).
        let innovation_cov = p_pred.select_rows(&MEASURED).select_columns(&MEASURED) + &r;
        let s_inv = innovation_cov
            .try_inverse()
            .filter(|m| m.iter().all(|x| x.is_finite()) && z.iter().all(|x| x.is_finite()))
            .ok_or_else(|| diverged("the smoother's update has no finite solution".to_string()))?;
        let k_gain = p_pred.select_columns(&MEASURED) * s_inv;
        let x_upd = &x_pred + &k_gain * (&z - x_pred.select_rows(&MEASURED));
        let p_upd = symmetrise(joseph(&p_pred, &k_gain, &r, &MEASURED));
        // Feedback of attitude, velocity and the constant biases; position, GM and RRW stay in the state.
        let mut u = DVector::zeros(n);
        for i in PHI..NABLA + 3 {
            u[i] = x_upd[i];
        }
        let before = (self.gyro_bias, self.accel_bias);
        let phi_c = [u[PHI], u[PHI + 1], u[PHI + 2]];
        let dv_c = [u[DV], u[DV + 1], u[DV + 2]];
        for i in 0..3 {
            self.gyro_bias[i] += u[EPS + i];
            self.accel_bias[i] += u[NABLA + i];
        }
        if fine_t > 3600.0 {
            self.max_att = phi_c.iter().fold(self.max_att, |m, x| m.max(x.abs()));
            self.max_vel = dv_c.iter().fold(self.max_vel, |m, x| m.max(x.abs()));
            self.max_pos = self.max_pos.max(x_upd[POS].abs()).max(x_upd[POS + 1].abs());
        }
        let wrap = |what: &str, e: CoreError| {
            diverged(format!(
                "the smoother's {what} left its range ({e}): the log does not look like a static base at the \
                 given site and sample rate"
            ))
        };
        self.nav.correct(phi_c, dv_c).map_err(|e| wrap("correction", e))?;
        self.nav
            .set_gyro_bias(self.gyro_bias)
            .map_err(|e| wrap("gyro bias", e))?;
        self.nav
            .set_accel_bias(self.accel_bias)
            .map_err(|e| wrap("accelerometer bias", e))?;
        self.x_pred.push(x_pred);
        self.p_pred.push(p_pred);
        self.x = &x_upd - &u;
        self.p = p_upd.clone();
        self.steps.push(Step {
            t: t_s,
            x: x_upd,
            p: p_upd,
            phi_next: None,
            gyro_bias: before.0,
            accel_bias: before.1,
            dtemp: if self.model.thermal.is_some() {
                self.temp_last - self.temp_ref
            } else {
                0.0
            },
        });
        self.c_sum = [[0.0; 3]; 3];
        self.temp_sum = 0.0;
        self.n_interval = 0;
        Ok(())
    }
}
