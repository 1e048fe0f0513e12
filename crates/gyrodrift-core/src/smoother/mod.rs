//! The full-information estimator of the axial drift: a forward Kalman filter and a Rauch-Tung-Striebel smoother
//! over a whole static-base log (coarse alignment, then every sample to the end of the span, 16 h by default),
//! with zero velocity AND the known position as measurements throughout, the turntable running. Its covariance
//! under the linear-Gaussian model is the Cramer-Rao line of any drift identification from the same data.
//! The same error model serves the covariance analyses of the label (`label`) and the planner (`plan`).
//!
//! States (this order, `state_names`): the 12 of `kalman` (phi E N U \[rad\], dv E N U [m/s], gyro bias x y z
//! [rad/s], accelerometer bias x y z [m/s^2]), then the position error north, east \[m\] (computed minus true:
//! dN = (R_M + h) dL, dE = (R_N + h) cos L dlon), then optionally a first-order Gauss-Markov gyro bias (x y z)
//! and a rate random walk gyro bias (x y z) [rad/s], then optionally (`thermal`) the thermal coefficient k_z
//! [rad/s/degC] of the z gyro. The gyro's total residual bias is eps + b_gm + b_rrw (+ k_z (T - T_ref) on z, T the
//! log's temperature, T_ref that of the last coarse-alignment sample unless given); the gyro bias states `eps` and
//! k_z are random constants.
//!
//! Thermal model: the z drift eps_z + k_z (T(t) - T_ref) enters the attitude error as -C_b^n[:, z] (T - T_ref) k_z,
//! with T - T_ref averaged over each update interval (a known input, like C_b^n). k_z is not fed back (as the
//! Gauss-Markov states). Reported: the drift at the end of the span eps_z + k_z (T_end - T_ref) with its 1-sigma
//! from the joint covariance (`drift_end`), k_z, and eps_z. The constant-drift estimate `drift` is the thermal
//! state conditioned on k_z = 0: for a random constant with an independent prior that is exactly the posterior of
//! the model without the state (mean a'x - (a'P e_k / P_kk) x_k, variance a'Pa - (a'P e_k)^2 / P_kk). When the
//! temperature spanned less than `thermal_min_range` after the coarse alignment every reported estimate is
//! conditioned so (the constant model is reported, `thermal` false).
//!
//! Continuous model (static base, v = 0; `kalman::ErrorModel` plus the position couplings):
//!   phi_dot = kalman's - C_b^n (b_gm + b_rrw) + (0, -w_U dN / R_M, w_N dN / R_M)   (the Earth rate at the
//!             computed latitude, w_N = w_ie cos L, w_U = w_ie sin L),
//!   dN_dot = dv_N, dE_dot = dv_E,
//!   b_gm_dot = -b_gm / tau + w_gm (density sqrt(2 sigma^2 / tau)), b_rrw_dot = w_rrw (density rrw).
//! C_b^n is the navigator's attitude as the table turns, averaged over each update interval (exact for the axial
//! column: the table turns about body z). Discretisation over the update interval T: Phi = exp(F T) (Taylor
//! series to order 8; |F T| is small but for the g and 1/R couplings, whose products stay below 1e-3),
//! Q = (Phi Q_c Phi' + Q_c) T / 2.
//! Measurements every `update_s`: the navigator's velocity (truth zero; sigma `zupt_sigma`) and its position minus
//! the known site in metres north and east (sigma `position_sigma_m`); Joseph-form update.
//!
//! Feedback and linearisation: as the alignment, closed loop. After each update the attitude, velocity, gyro- and
//! accelerometer-bias estimates are fed back into the navigator (`Navigator::correct`, bias estimates += eps,
//! nabla); the position and the Gauss-Markov and random-walk states are not (the navigator's position is never
//! reset; those bias states keep their estimates). So the navigator's errors stay those of a fine alignment all
//! along (arcseconds, mm/s, metres: the first-order model holds to 1e-7 relative), and the smoother works on the
//! filter's error state with the applied correction u_k as a known input:
//!   x_{k+1} = Phi_k (x_k - u_k) + w_k,   x_{k+1|k} = Phi_k (x_{k|k} - u_k),
//!   C_k = P_{k|k} Phi_k' P_{k+1|k}^-1,  x_{k|N} = x_{k|k} + C_k (x_{k+1|N} - x_{k+1|k}),
//!   P_{k|N} = P_{k|k} + C_k (P_{k+1|N} - P_{k+1|k}) C_k'
//! (the usual RTS recursion; the known input shifts the prediction and the smoothed mean alike). The total z
//! drift at update k is the navigator's z bias before that update plus the smoothed eps_z (+ b_gm,z + b_rrw,z;
//! plus k_z (T_k - T_ref) under the thermal model): the history. The drift carried into navigation (`drift_end`)
//! is the same at the last update without b_gm,z: a Gauss-Markov bias forgets its value within its correlation
//! time, so its mean over a mission of many correlation times is near zero.
//! P_{k+1|k}^-1 is applied through a Cholesky factor of its correlation matrix (states span 1e-24 to 1e-6 in
//! their SI variances).
//!
//! Here the driver ([`Smoother`]: coarse alignment, then the forward filter per sample); in `config` the settings,
//! in `model` the error model, in `forward` the forward filter, in `rts` the backward pass and the result.

mod config;
mod forward;
pub(crate) mod model;
mod rts;

pub use config::{state_names, SmootherConfig};
pub use rts::SmootherResult;

use crate::alignment::navigator_at_rest;
use crate::attitude::quat_to_dcm;
use crate::coarse_alignment::InertialCoarseAlignment;
use crate::error::{check, CoreError};
use crate::kalman::N_STATES as N_BASE;
use crate::limits::check_increments;
use forward::{Forward, Step};
use model::{initial_sigma, Model};
use nalgebra::{DMatrix, DVector};

/// Index of the north and east position-error states \[m\].
pub const POS: usize = N_BASE;
/// Default prior 1-sigma of the thermal coefficient k_z [deg/h/degC] and least temperature range \[deg C\] for
/// which the thermal model is reported (`SmootherConfig`).
pub const DEFAULT_THERMAL_SIGMA_DEG_H_PER_C: f64 = 0.01;
pub const DEFAULT_THERMAL_MIN_RANGE_C: f64 = 0.5;
/// Largest number of updates a smoother keeps for its backward pass (memory: about 3 n^2 + 2 n floats each,
/// under 200 MB with all 20 states).
pub const MAX_UPDATES: u64 = 20_000;

/// The smoother (module docs). Streaming: `process` takes chunks of any size; `result` after `done`.
#[derive(Clone, Debug)]
pub struct Smoother {
    cfg: SmootherConfig,
    n_coarse: u64,
    n_total: u64,
    n_update: u64,
    k: u64,
    coarse: InertialCoarseAlignment,
    fwd: Option<Forward>,
    failed: Option<CoreError>,
    /// The last temperature seen \[deg C\] (the default T_ref once the coarse alignment ends).
    temp_last: f64,
}

impl Smoother {
    /// A validated smoother.
    pub fn new(cfg: SmootherConfig) -> Result<Self, CoreError> {
        cfg.validate()?;
        let n = |s: f64| (s * cfg.rate_hz).round() as u64;
        let (n_coarse, n_total, n_update) = (n(cfg.coarse_s), n(cfg.span_s), n(cfg.update_s));
        check(n_coarse >= 2, "coarse_s", "gives fewer than 2 samples at this rate")?;
        Ok(Smoother {
            coarse: InertialCoarseAlignment::new(cfg.lat, cfg.height, cfg.rate_hz, n_coarse)?,
            cfg,
            n_coarse,
            n_total,
            n_update,
            k: 0,
            fwd: None,
            failed: None,
            temp_last: f64::NAN,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SmootherConfig {
        &self.cfg
    }

    /// Samples consumed so far.
    pub fn samples_done(&self) -> u64 {
        self.k
    }

    /// Samples of the whole span.
    pub fn n_samples(&self) -> u64 {
        self.n_total
    }

    /// True when the span is complete.
    pub fn done(&self) -> bool {
        self.k >= self.n_total
    }

    /// Consume raw increments (flat row-major (n x 3) slices, dtheta \[rad\], dv [m/s], body frame) and, with the
    /// thermal state, the temperature of each sample \[deg C\] (`temp_c`, one per sample; ignored without it);
    /// stops at the end of the span. Returns how many samples were used. A refused chunk changes nothing; an
    /// estimate leaving its range ([`CoreError::Diverged`]) stops the smoother.
    pub fn process(&mut self, dtheta: &[f64], dv: &[f64], temp_c: Option<&[f64]>) -> Result<usize, CoreError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        let rows = check_increments(dtheta, dv, 1.0 / self.cfg.rate_hz)?;
        let temp = if self.cfg.thermal {
            let t = temp_c.ok_or_else(|| CoreError::Shape {
                key: "temp_c",
                message: "the thermal model needs the temperature of every sample".to_string(),
            })?;
            check_temperatures(t, rows)?;
            Some(t)
        } else {
            None
        };
        let n = rows.min(usize::try_from(self.n_total - self.k).unwrap_or(usize::MAX));
        for (i, (a, b)) in dtheta.chunks_exact(3).zip(dv.chunks_exact(3)).take(n).enumerate() {
            let t = temp.map_or(f64::NAN, |t| t[i]);
            if let Err(e) = self.step([a[0], a[1], a[2]], [b[0], b[1], b[2]], t) {
                self.failed = Some(e.clone());
                return Err(e);
            }
        }
        Ok(n)
    }

    fn step(&mut self, dtheta: [f64; 3], dv: [f64; 3], temp_c: f64) -> Result<(), CoreError> {
        self.k += 1;
        self.temp_last = temp_c;
        if self.k <= self.n_coarse {
            self.coarse.step(dtheta, dv);
            if self.k == self.n_coarse {
                self.start()?;
            }
            return Ok(());
        }
        let last = self.k == self.n_total;
        let fwd = self
            .fwd
            .as_mut()
            .expect("the forward filter starts after the coarse span");
        fwd.nav.step(dtheta, dv);
        let c = quat_to_dcm(fwd.nav.quaternion());
        for (sum_row, c_row) in fwd.c_sum.iter_mut().zip(c) {
            for (sum, x) in sum_row.iter_mut().zip(c_row) {
                *sum += x;
            }
        }
        if self.cfg.thermal {
            fwd.temp_sum += temp_c - fwd.temp_ref;
            fwd.temp_min = fwd.temp_min.min(temp_c);
            fwd.temp_max = fwd.temp_max.max(temp_c);
            fwd.temp_last = temp_c;
        }
        fwd.n_interval += 1;
        if fwd.n_interval == self.n_update || last {
            let t_s = self.k as f64 / self.cfg.rate_hz;
            let fine_t = t_s - self.cfg.coarse_s;
            fwd.update(&self.cfg, t_s, fine_t)?;
        }
        Ok(())
    }

    fn start(&mut self) -> Result<(), CoreError> {
        let t_s = self.k as f64 / self.cfg.rate_hz;
        let c_bn = self.coarse.attitude().expect("coarse span complete");
        let cfg = &self.cfg;
        let (_, nav) = navigator_at_rest(&c_bn, cfg.lat, cfg.lon, cfg.height, cfg.rate_hz, t_s)?;
        let model = Model::new(cfg);
        let n = model.n;
        let sigma = initial_sigma(cfg, t_s);
        let temp_ref = if cfg.thermal {
            cfg.temp_ref.unwrap_or(self.temp_last)
        } else {
            0.0
        };
        let p = DMatrix::from_diagonal(&DVector::from_iterator(n, sigma.iter().map(|s| s * s)));
        let x = DVector::zeros(n);
        let steps = vec![Step {
            t: t_s,
            x: x.clone(),
            p: p.clone(),
            phi_next: None,
            gyro_bias: [0.0; 3],
            accel_bias: [0.0; 3],
            dtemp: if cfg.thermal { self.temp_last - temp_ref } else { 0.0 },
        }];
        self.fwd = Some(Forward {
            nav,
            model,
            x,
            p,
            gyro_bias: [0.0; 3],
            accel_bias: [0.0; 3],
            c_sum: [[0.0; 3]; 3],
            temp_sum: 0.0,
            temp_ref,
            temp_min: self.temp_last,
            temp_max: self.temp_last,
            temp_last: self.temp_last,
            n_interval: 0,
            steps,
            p_pred: Vec::new(),
            x_pred: Vec::new(),
            max_att: 0.0,
            max_vel: 0.0,
            max_pos: 0.0,
        });
        Ok(())
    }

    /// The smoothed result: [`CoreError::Incomplete`] until the span is complete.
    pub fn result(&self) -> Result<SmootherResult, CoreError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        if !self.done() {
            return Err(CoreError::Incomplete {
                done: self.k,
                needed: self.n_total,
            });
        }
        let fwd = self.fwd.as_ref().expect("done implies the forward filter ran");
        let t_s = self.k as f64 / self.cfg.rate_hz;
        fwd.smooth(&self.cfg, t_s)
    }
}

/// Check one chunk's temperatures \[deg C\]: one per sample, finite, within the simulator's [-100, 200].
fn check_temperatures(temp_c: &[f64], rows: usize) -> Result<(), CoreError> {
    if temp_c.len() != rows {
        return Err(CoreError::Shape {
            key: "temp_c",
            message: format!("has {} values for {rows} samples", temp_c.len()),
        });
    }
    match temp_c.iter().position(|t| !(-100.0..=200.0).contains(t)) {
        None => Ok(()),
        Some(index) => Err(CoreError::Sample {
            key: "temp_c",
            index,
            message: format!("temperature {} deg C is outside [-100, 200] deg C", temp_c[index]),
        }),
    }
}
