//! The fine aligner as the filter it is, by covariance alone (no IMU samples): its own Riccati pass (its prior,
//! noise model and zero-velocity updates on the smoother's error model) and the true covariance of its errors
//! under another noise, with the table turning. Shared by the planner (`plan::drift_std_curve`, which carries it
//! beside the smoother) and the label's sigma (`label::label_sigma`, the noise-driven leftovers the navigation
//! starts from).
//!
//! Every aligner step of `dt` with the mean attitude of its samples (x~ the errors, true minus estimate, K the
//! aligner's gain from its own pass, Phi and Q the truth's):
//!
//! - its own covariance P <- (I - K H)(Phi P Phi' + Q_own)(I - K H)' + K R_own K';
//! - its true error covariance A <- (I - K H)(Phi A Phi' + Q)(I - K H)' + K R K' (R the truth's zero-velocity
//!   noise);
//! - J = E[x_o x~'] <- (Phi J Phi' + Q)(I - K H)', x_o another error driven by the same noise with the same
//!   transition (the smoother's, which applies its own updates to J; or the true state itself, no updates);
//! - vectors u = E[x~ v] carried with the aligner's error (no new shared noise): u <- (I - K H) Phi u.

use crate::attitude::{euler_to_dcm, mat_mul, Euler, Mat3};
use crate::error::{check, CoreError};
use crate::filter_prior::FilterSettings;
use crate::kalman::{DV, PHI};
use crate::smoother::model::{initial_sigma, joseph, measurement_noise, symmetrise, Model, Sandwich};
use crate::smoother::SmootherConfig;
use crate::turntable::{RotationScheme, Turntable};
use nalgebra::{DMatrix, DVector};

/// The fine alignment a navigation starts from (SI): the log's sample rate, the table's rotation scheme and the
/// IMU's attitude at table angle zero, the aligner's filter settings (coarse span, update interval, prior, noise
/// model, zero-velocity sigma: the procedure's are [`FilterSettings::aligner`]) and its end from the first
/// sample \[s\] (coarse plus fine span, 4 h).
#[derive(Clone, Debug, PartialEq)]
pub struct FineAlignment {
    pub rate_hz: f64,
    pub scheme: RotationScheme,
    pub attitude: Euler,
    pub filter: FilterSettings,
    pub end_s: f64,
}

/// The body-to-nav attitude of the simulator's geometry, C_b^n(t) = C_b0^n Rz(alpha(t)), alpha the table angle.
pub(crate) struct TableAttitude {
    c0: Mat3,
    table: Turntable,
    rate: f64,
}

impl TableAttitude {
    pub(crate) fn new(scheme: &RotationScheme, attitude: Euler, rate_hz: f64) -> Result<Self, CoreError> {
        Ok(TableAttitude {
            c0: euler_to_dcm(attitude),
            table: Turntable::new(scheme.clone())?,
            rate: rate_hz,
        })
    }

    /// The mean C_b^n over samples `from + 1 ..= to` (each at the end of its sample): C_b0^n times the mean
    /// Rz(alpha), whose cos and sin sums are closed-form geometric sums over each constant-rate stretch of the
    /// table (dwells and cruises; [`Turntable::uniform_at`]) and per-sample sums over its ramps.
    pub(crate) fn mean(&self, from: u64, to: u64) -> Mat3 {
        let (mut cos_sum, mut sin_sum) = (0.0, 0.0);
        let mut cursor = self.table.cursor_at((from + 1) as f64 / self.rate);
        let mut j = from + 1;
        while j <= to {
            let t = j as f64 / self.rate;
            match self.table.uniform_at(&mut cursor, t) {
                Some(seg) => {
                    // The samples j ..= last of this stretch (t < seg.end, as the cursor assigns them).
                    let mut last = ((seg.end * self.rate).ceil() as u64).clamp(j, to);
                    while last > j && last as f64 / self.rate >= seg.end {
                        last -= 1;
                    }
                    let (c, s) = uniform_sum(
                        seg.angle0 + seg.rate * (t - seg.start),
                        seg.rate / self.rate,
                        last - j + 1,
                    );
                    cos_sum += c;
                    sin_sum += s;
                    j = last + 1;
                }
                None => {
                    let (s, c) = self.table.state_at(&mut cursor, t).angle.sin_cos();
                    cos_sum += c;
                    sin_sum += s;
                    j += 1;
                }
            }
        }
        let m = (to - from) as f64;
        let (c, s) = (cos_sum / m, sin_sum / m);
        mat_mul(&self.c0, &[[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    }
}

/// (sum cos, sum sin) of the `count` angles `first + i step`, i = 0 .. count - 1 \[rad\]: the geometric sum
/// e^(i (first + (count - 1) step / 2)) sin(count step / 2) / sin(step / 2).
fn uniform_sum(first: f64, step: f64, count: u64) -> (f64, f64) {
    let m = count as f64;
    let half = 0.5 * step;
    let gain = if half.sin().abs() < 1e-300 {
        m
    } else {
        (m * half).sin() / half.sin()
    };
    let (s, c) = (first + (m - 1.0) * half).sin_cos();
    (gain * c, gain * s)
}

/// The aligner's settings on the smoother's model (the same site, rate and slow-bias states).
pub(crate) fn aligner_on_smoother_model(sc: &SmootherConfig, al: &FilterSettings) -> SmootherConfig {
    SmootherConfig {
        coarse_s: al.coarse_s,
        update_s: al.update_s,
        att_sigma: al.att_sigma,
        gyro_bias_sigma: al.gyro_bias_sigma,
        accel_bias_sigma: al.accel_bias_sigma,
        gyro_arw: al.gyro_arw,
        accel_vrw: al.accel_vrw,
        zupt_sigma: al.zupt_sigma,
        ..sc.clone()
    }
}

/// The selector of the aligner's leftovers a navigation starts from (attitude and velocity; the horizontal sensor
/// biases it leaves are modulated away by the table).
pub(crate) fn navigation_start_selector(n: usize) -> DMatrix<f64> {
    let mut e = DMatrix::zeros(n, n);
    for i in (PHI..PHI + 3).chain(DV..DV + 3) {
        e[(i, i)] = 1.0;
    }
    e
}

/// The states the aligner's zero-velocity update measures.
const VELOCITY: [usize; 3] = [DV, DV + 1, DV + 2];

/// The aligner's own Riccati pass and the true covariances it carries (module docs).
pub(crate) struct AlignerPass {
    /// Its own covariance (for its gain), its true error covariance A, and J = E[x_o x~'].
    own: DMatrix<f64>,
    pub(crate) truth: DMatrix<f64>,
    pub(crate) joint: DMatrix<f64>,
    /// Its zero-velocity noise and the truth's (the measurement: the velocity states `DV..DV + 3`).
    r_own: DMatrix<f64>,
    r_true: DMatrix<f64>,
    model: Model,
    /// Vectors E[x~ v] carried with the aligner's error (the caller's index, vector).
    pub(crate) pending: Vec<(usize, DVector<f64>)>,
}

impl AlignerPass {
    /// The aligner of `al` on the model of `sc` (the truth's: site, slow-bias states, zero-velocity noise), from
    /// its prior at the end of the coarse span `coarse_end_s` \[s\]; A and J start at `start`.
    pub(crate) fn new(
        sc: &SmootherConfig,
        al: &FilterSettings,
        coarse_end_s: f64,
        start: DMatrix<f64>,
    ) -> Result<Self, CoreError> {
        let acfg = aligner_on_smoother_model(sc, al);
        let model = Model::new(&acfg);
        let n = model.n;
        check(
            start.nrows() == n && start.ncols() == n,
            "aligner",
            "the aligner's starting covariance does not fit the error model",
        )?;
        let own = DMatrix::from_diagonal(&DVector::from_iterator(
            n,
            initial_sigma(&acfg, coarse_end_s).iter().map(|s| s * s),
        ));
        let r = measurement_noise(sc);
        Ok(AlignerPass {
            own,
            truth: start.clone(),
            joint: start,
            r_own: DMatrix::from_diagonal_element(3, 3, al.zupt_sigma * al.zupt_sigma),
            r_true: r.view((0, 0), (3, 3)).into_owned(),
            model,
            pending: Vec::new(),
        })
    }

    /// One aligner step of `dt` \[s\] with the mean attitude `c` (`truth`: the true model's Phi and Q).
    ///
    /// H selects the three velocity states, so (I - K H) M = M - K M\[v, :\] and M (I - K H)' = M - M\[:, v\] K':
    /// rank-3 updates instead of n^3 products; Phi P Phi' runs over Phi's non-zero entries ([`Sandwich`]).
    fn step(&mut self, c: &Mat3, dt: f64, truth: &Model) -> Result<(), CoreError> {
        let (phi, q) = truth.discretise(c, 0.0, dt);
        let q_own = self.model.process_noise(&phi, dt); // the same site and states: the same Phi
        let phi_nz = Sandwich::new(&phi);
        let own = symmetrise(phi_nz.apply(&self.own) + q_own);
        let s_inv = (own.view((DV, DV), (3, 3)) + &self.r_own)
            .try_inverse()
            .ok_or_else(|| CoreError::Setting {
                key: "aligner",
                message: "the aligner's innovation covariance is singular".to_string(),
            })?;
        let gain = own.columns(DV, 3) * s_inv;
        self.own = symmetrise(joseph(&own, &gain, &self.r_own, &VELOCITY));
        self.truth = symmetrise(joseph(
            &(phi_nz.apply(&self.truth) + &q),
            &gain,
            &self.r_true,
            &VELOCITY,
        ));
        let joint = phi_nz.apply(&self.joint) + &q;
        self.joint = &joint - joint.columns(DV, 3) * gain.transpose();
        for (_, u) in self.pending.iter_mut() {
            let w = &phi * &*u;
            *u = &w - &gain * w.rows(DV, 3);
        }
        Ok(())
    }

    /// The aligner's steps over samples `from + 1 ..= to`, one per `per_update` samples (the last may be shorter),
    /// each with the mean attitude of its samples.
    pub(crate) fn advance(
        &mut self,
        attitude: &TableAttitude,
        from: u64,
        to: u64,
        per_update: u64,
        truth: &Model,
    ) -> Result<(), CoreError> {
        let mut j = from;
        while j < to {
            let end = (j + per_update).min(to);
            self.step(&attitude.mean(j, end), (end - j) as f64 / attitude.rate, truth)?;
            j = end;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::rot_z;
    use crate::units::DEG;

    /// The mean C_b^n sample by sample, each angle from [`Turntable::angle`] (the definition).
    fn mean_by_sample(table: &TableAttitude, from: u64, to: u64) -> Mat3 {
        let mut sum: Mat3 = [[0.0; 3]; 3];
        for j in from + 1..=to {
            let c = mat_mul(&table.c0, &rot_z(table.table.angle(j as f64 / table.rate)));
            for (row, c_row) in sum.iter_mut().zip(c) {
                for (s, x) in row.iter_mut().zip(c_row) {
                    *s += x;
                }
            }
        }
        sum.map(|row| row.map(|x| x / (to - from) as f64))
    }

    #[test]
    fn the_closed_form_mean_matches_the_sample_sums() {
        let schemes = [
            RotationScheme::None,
            RotationScheme::Continuous {
                rate: 6.0 * DEG,
                accel: 2.0 * DEG,
            },
            RotationScheme::Reciprocating {
                rate: 6.0 * DEG,
                accel: 2.0 * DEG,
                span: 360.0 * DEG,
                dwell: 0.0,
            },
            RotationScheme::Reciprocating {
                rate: 10.0 * DEG,
                accel: 50.0 * DEG,
                span: 180.0 * DEG,
                dwell: 7.3,
            },
            RotationScheme::Indexing {
                rate: 9.0 * DEG,
                accel: 30.0 * DEG,
                positions: vec![90.0 * DEG, 180.0 * DEG, 270.0 * DEG],
                dwell: 13.0,
            },
        ];
        let attitude = Euler {
            pitch: 0.01,
            roll: -0.02,
            yaw: 0.7,
        };
        let mut worst: f64 = 0.0;
        for scheme in &schemes {
            for rate in [1.0, 10.0, 100.0, 333.0] {
                let table = TableAttitude::new(scheme, attitude, rate).unwrap();
                // Short and long intervals from the start, across ramps and periods, and tens of hours in.
                for (start_s, span_s) in [
                    (0.0, 0.1),
                    (0.0, 1.0),
                    (3.0, 10.0),
                    (95.7, 60.0),
                    (3600.0, 10.0),
                    (180_000.3, 600.0),
                ] {
                    let from = (start_s * rate) as u64;
                    let to = from + ((span_s * rate) as u64).max(1);
                    let (fast, slow) = (table.mean(from, to), mean_by_sample(&table, from, to));
                    for (a, b) in fast.iter().flatten().zip(slow.iter().flatten()) {
                        worst = worst.max((a - b).abs());
                    }
                }
            }
        }
        // Both are means of unit-size terms: they differ by the rounding of the angles (the period offset of
        // tens of hours, ~1e-11 rad) and of the sums.
        assert!(worst < 1e-10, "closed-form and sample means differ by {worst:e}");
    }
}
