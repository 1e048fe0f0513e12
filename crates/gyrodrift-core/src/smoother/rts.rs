//! The backward pass: the Rauch-Tung-Striebel recursion over the stored updates (module docs of [`super`]) and
//! the result it gives.

use super::forward::{Forward, Step};
use super::model::{symmetrise, Sandwich};
use super::SmootherConfig;
use crate::error::CoreError;
use crate::kalman::{EPS, NABLA};
use nalgebra::{DMatrix, DVector};

/// Everything the smoother reports (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct SmootherResult {
    /// End of the span \[s\] from the first sample.
    pub t_s: f64,
    /// The constant part of the z-gyro bias [rad/s] (smoothed; measured - estimate is the corrected output) and its
    /// 1-sigma, under the constant-drift model: with the thermal state, conditioned on k_z = 0 (exactly the
    /// posterior of the model without that state).
    pub drift: f64,
    pub drift_std: f64,
    /// The z-gyro bias at the end of the span carried into navigation under the reported model (constant + random
    /// walk, + k_z (T_end - T_ref) when `thermal`) and its 1-sigma. The Gauss-Markov state is left out: it forgets
    /// its value within its correlation time, so over a mission of many correlation times its mean is near zero
    /// and a constant compensation that carried its end value would be wrong by that value all mission long (the
    /// history below is the total, Gauss-Markov included).
    pub drift_end: f64,
    pub drift_end_std: f64,
    /// True when the thermal model is the reported one (`drift_end`, the history, the biases): the thermal state
    /// is there and the temperature spanned at least `thermal_min_range`.
    pub thermal: bool,
    /// Thermal model (NaN without the state): eps_z, the z drift at T_ref [rad/s], and k_z [rad/s/degC], each with
    /// its 1-sigma; T_ref, the temperature at the end of the span and the range (max - min) after the coarse
    /// alignment \[deg C\].
    pub drift_ref: f64,
    pub drift_ref_std: f64,
    pub thermal_coeff: f64,
    pub thermal_coeff_std: f64,
    /// Covariance of the thermal model's end drift eps_z + k_z (T_end - T_ref) (+ b_rrw,z) with k_z
    /// [rad^2/s^2/degC] (NaN without the state): with `drift_end_std` under the thermal model and
    /// `thermal_coeff_std`, the joint covariance of the two, e.g. to condition the end drift on another prior of
    /// k_z.
    pub end_coeff_cov: f64,
    pub temp_ref: f64,
    pub temp_end: f64,
    pub temp_range: f64,
    /// The constant gyro and accelerometer biases, body x y z (smoothed), and their 1-sigma.
    pub gyro_bias: [f64; 3],
    pub gyro_bias_std: [f64; 3],
    pub accel_bias: [f64; 3],
    pub accel_bias_std: [f64; 3],
    /// Smoothed total z drift history: times \[s\], drift and 1-sigma [rad/s]; the forward filter's 1-sigma beside it.
    pub hist_t: Vec<f64>,
    pub hist_drift: Vec<f64>,
    pub hist_drift_std: Vec<f64>,
    pub hist_filter_std: Vec<f64>,
    /// Linearity diagnostics after the first hour of the fine span: the largest attitude correction \[rad\], velocity
    /// correction [m/s] and position error estimate \[m\] fed back or carried.
    pub max_attitude_correction: f64,
    pub max_velocity_correction: f64,
    pub max_position_error: f64,
    /// Number of updates.
    pub updates: usize,
}

impl Forward {
    /// The backward (RTS) pass and the result.
    pub(super) fn smooth(&self, cfg: &SmootherConfig, t_end: f64) -> Result<SmootherResult, CoreError> {
        let n = self.model.n;
        let m = self.steps.len();
        let last = &self.steps[m - 1];
        let mut xs = last.x.clone();
        let mut ps = last.p.clone();
        // The thermal model is reported when its state is there and the temperature moved enough; otherwise every
        // estimate is conditioned on k_z = 0, which is exactly the posterior of the constant-drift model.
        let k_th = self.model.thermal;
        let temp_range = self.temp_max - self.temp_min;
        let thermal = k_th.is_some() && temp_range >= cfg.thermal_min_range;
        // Mean and 1-sigma of a'x, conditioned on k_z = 0 when `cond`.
        let linear = |a: &DVector<f64>, x: &DVector<f64>, p: &DMatrix<f64>, cond: bool| {
            let pa = p * a;
            let (mut mean, mut var) = (a.dot(x), a.dot(&pa));
            if let (Some(k), true) = (k_th, cond) {
                if p[(k, k)] > 0.0 {
                    mean -= pa[k] / p[(k, k)] * x[k];
                    var -= pa[k] * pa[k] / p[(k, k)];
                }
            }
            (mean, var.max(0.0).sqrt())
        };
        let unit = |i: usize| {
            let mut a = DVector::zeros(n);
            a[i] = 1.0;
            a
        };
        // Selectors of the carried z drift, eps_z + rrw_z, and of the total, + gm_z (each + k_z (T - T_ref) under
        // the thermal model).
        let mut e_carried = unit(EPS + 2);
        if let Some(r) = self.model.rrw {
            e_carried[r + 2] = 1.0;
        }
        let mut e_total = e_carried.clone();
        if let Some(g) = self.model.gm {
            e_total[g + 2] = 1.0;
        }
        let drift_of = |e: &DVector<f64>, step: &Step, x: &DVector<f64>, p: &DMatrix<f64>| {
            let mut a = e.clone();
            if let (Some(k), true) = (k_th, thermal) {
                a[k] = step.dtemp;
            }
            let (d, s) = linear(&a, x, p, !thermal);
            (step.gyro_bias[2] + d, s)
        };
        let total = |step: &Step, x: &DVector<f64>, p: &DMatrix<f64>| drift_of(&e_total, step, x, p);
        let every = ((cfg.history_s / cfg.update_s).round() as usize).max(1);
        let mut hist = Vec::new();
        let record =
            |k: usize, step: &Step, x: &DVector<f64>, p: &DMatrix<f64>, hist: &mut Vec<(f64, f64, f64, f64)>| {
                if k % every == 0 || k + 1 == m {
                    let (d, s) = total(step, x, p);
                    let (_, sf) = total(step, &step.x, &step.p);
                    hist.push((step.t, d, s, sf));
                }
            };
        record(m - 1, last, &xs, &ps, &mut hist);
        let (drift_end, drift_end_std) = drift_of(&e_carried, last, &xs, &ps);
        // Covariance of the thermal model's end drift with k_z (unconditioned; the last step's smoothed = filtered P).
        let end_coeff_cov = k_th.map_or(f64::NAN, |k| {
            let mut a = e_carried.clone();
            a[k] = last.dtemp;
            (&ps * a)[k]
        });
        let diverged = |message: &str| CoreError::Diverged {
            key: "dv_m_s",
            t_s: t_end,
            message: message.to_string(),
        };
        for k in (0..m - 1).rev() {
            let step = &self.steps[k];
            let phi = step.phi_next.as_ref().expect("every step but the last has a successor");
            let p_pred = &self.p_pred[k];
            // C = P_k Phi' P_pred^-1 through the correlation matrix of P_pred.
            // D scales rows and columns (diagonal): no n^3 products with it.
            let d: DVector<f64> = p_pred.diagonal().map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 });
            let corr = symmetrise(DMatrix::from_fn(n, n, |i, j| d[i] * p_pred[(i, j)] * d[j]));
            let chol = corr
                .cholesky()
                .ok_or_else(|| diverged("the smoother's predicted covariance is not positive definite"))?;
            let mut a = Sandwich::new(phi).right(&step.p); // P_k Phi' D
            for (mut column, dj) in a.column_iter_mut().zip(d.iter()) {
                column *= *dj;
            }
            let mut c = chol.solve(&a.transpose()).transpose(); // (P_k Phi' D) corr^-1 D
            for (mut column, dj) in c.column_iter_mut().zip(d.iter()) {
                column *= *dj;
            }
            xs = &step.x + &c * (&xs - &self.x_pred[k]);
            ps = symmetrise(&step.p + &c * (&ps - p_pred) * c.transpose());
            record(k, step, &xs, &ps, &mut hist);
        }
        hist.reverse();
        // xs, ps are now at the first step (the start of the fine span, zero navigator biases).
        let first = &self.steps[0];
        let est = |i: usize, cond: bool| linear(&unit(i), &xs, &ps, cond);
        let gyro_bias: [f64; 3] = std::array::from_fn(|i| first.gyro_bias[i] + est(EPS + i, !thermal).0);
        let accel_bias: [f64; 3] = std::array::from_fn(|i| first.accel_bias[i] + est(NABLA + i, !thermal).0);
        let (drift, drift_std) = est(EPS + 2, true);
        let (drift_ref, drift_ref_std, thermal_coeff, thermal_coeff_std) = match k_th {
            Some(k) => {
                let (e, es) = est(EPS + 2, false);
                let (c, cs) = est(k, false);
                (first.gyro_bias[2] + e, es, c, cs)
            }
            None => (f64::NAN, f64::NAN, f64::NAN, f64::NAN),
        };
        let some = |x: f64| if k_th.is_some() { x } else { f64::NAN };
        Ok(SmootherResult {
            t_s: t_end,
            drift: first.gyro_bias[2] + drift,
            drift_std,
            drift_end,
            drift_end_std,
            thermal,
            drift_ref,
            drift_ref_std,
            thermal_coeff,
            thermal_coeff_std,
            end_coeff_cov,
            temp_ref: some(self.temp_ref),
            temp_end: some(self.temp_last),
            temp_range: some(temp_range),
            gyro_bias,
            gyro_bias_std: std::array::from_fn(|i| est(EPS + i, !thermal).1),
            accel_bias,
            accel_bias_std: std::array::from_fn(|i| est(NABLA + i, !thermal).1),
            hist_t: hist.iter().map(|h| h.0).collect(),
            hist_drift: hist.iter().map(|h| h.1).collect(),
            hist_drift_std: hist.iter().map(|h| h.2).collect(),
            hist_filter_std: hist.iter().map(|h| h.3).collect(),
            max_attitude_correction: self.max_att,
            max_velocity_correction: self.max_vel,
            max_position_error: self.max_pos,
            updates: m - 1,
        })
    }
}
