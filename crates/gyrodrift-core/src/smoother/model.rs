//! The smoother's linear error model (module docs of [`super`]): the continuous system matrix, its discretisation
//! over an update interval, the prior and the measurements. Shared with the covariance analyses (`plan`, `label`).

use super::{SmootherConfig, POS};
use crate::alignment::coarse_attitude_sigma;
use crate::attitude::Mat3;
use crate::earth;
use crate::kalman::{ErrorModel, DV, EPS, NABLA, N_STATES as N_BASE, PHI};
use nalgebra::{DMatrix, DVector};

/// The error model of the smoother at a site (module docs).
#[derive(Clone, Debug)]
pub(crate) struct Model {
    base: ErrorModel,
    pub(crate) n: usize,
    w_n: f64,
    w_u: f64,
    inv_rm_h: f64,
    pub(crate) gm: Option<usize>,
    pub(crate) rrw: Option<usize>,
    pub(crate) thermal: Option<usize>,
    tau: f64,
    /// Continuous noise densities squared on the diagonal.
    pub(crate) qc: DVector<f64>,
}

impl Model {
    pub(crate) fn new(cfg: &SmootherConfig) -> Self {
        let n = cfg.n_states();
        let w = earth::earth_rate_enu(cfg.lat);
        let mut qc = DVector::zeros(n);
        for i in 0..3 {
            qc[PHI + i] = cfg.gyro_arw * cfg.gyro_arw;
        }
        for i in 0..2 {
            qc[DV + i] = cfg.accel_vrw * cfg.accel_vrw;
        }
        if let Some(g) = cfg.gm_index() {
            for i in 0..3 {
                qc[g + i] = 2.0 * cfg.gyro_bias_instability.powi(2) / cfg.gyro_correlation;
            }
        }
        if let Some(r) = cfg.rrw_index() {
            for i in 0..3 {
                qc[r + i] = cfg.gyro_rrw * cfg.gyro_rrw;
            }
        }
        Model {
            base: ErrorModel::new(cfg.lat, cfg.height),
            n,
            w_n: w[1],
            w_u: w[2],
            inv_rm_h: 1.0 / (earth::meridian_radius(cfg.lat) + cfg.height),
            gm: cfg.gm_index(),
            rrw: cfg.rrw_index(),
            thermal: cfg.thermal_index(),
            tau: cfg.gyro_correlation,
            qc,
        }
    }

    /// Continuous system matrix for the mean body-to-nav DCM `c` and the mean T - T_ref `dtemp` \[deg C\] of the
    /// interval.
    fn system_matrix(&self, c: &Mat3, dtemp: f64) -> DMatrix<f64> {
        let mut f = DMatrix::zeros(self.n, self.n);
        let b = self.base.system_matrix(c);
        for i in 0..N_BASE {
            for j in 0..N_BASE {
                f[(i, j)] = b[(i, j)];
            }
        }
        f[(PHI + 1, POS)] = -self.w_u * self.inv_rm_h;
        f[(PHI + 2, POS)] = self.w_n * self.inv_rm_h;
        f[(POS, DV + 1)] = 1.0;
        f[(POS + 1, DV)] = 1.0;
        for first in [self.gm, self.rrw].into_iter().flatten() {
            for i in 0..3 {
                for j in 0..3 {
                    f[(PHI + i, first + j)] = -c[i][j];
                }
            }
        }
        if let Some(g) = self.gm {
            for i in 0..3 {
                f[(g + i, g + i)] = -1.0 / self.tau;
            }
        }
        if let Some(k) = self.thermal {
            // The z drift's thermal part k_z (T - T_ref) on the body z axis.
            for i in 0..3 {
                f[(PHI + i, k)] = -c[i][2] * dtemp;
            }
        }
        f
    }

    /// Phi = exp(F t) (Taylor to order 8) and Q (trapezoidal).
    ///
    /// F is sparse (about one entry in six), so each term `term F t / k` is summed over F's non-zero entries:
    /// n nnz operations instead of n^3 (the smoother, the aligner's pass and the covariance analyses discretise at
    /// every update).
    pub(crate) fn discretise(&self, c: &Mat3, dtemp: f64, t: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = self.n;
        let f = self.system_matrix(c, dtemp);
        let mut nonzeros = Vec::with_capacity(4 * n);
        for j in 0..n {
            for i in 0..n {
                if f[(i, j)] != 0.0 {
                    nonzeros.push((i, j, f[(i, j)] * t));
                }
            }
        }
        let mut phi = DMatrix::identity(n, n);
        let mut term = DMatrix::identity(n, n);
        let mut next = DMatrix::zeros(n, n);
        for k in 1..=8 {
            next.fill(0.0);
            let inv_k = 1.0 / k as f64;
            // Column j of term F t / k gathers column i of term times (F t)_ij / k (column-major storage).
            let (from, to) = (term.as_slice(), next.as_mut_slice());
            for &(i, j, v) in &nonzeros {
                let scale = v * inv_k;
                for (out, x) in to[j * n..(j + 1) * n].iter_mut().zip(&from[i * n..(i + 1) * n]) {
                    *out += x * scale;
                }
            }
            std::mem::swap(&mut term, &mut next);
            phi += &term;
        }
        let q = self.process_noise(&phi, t);
        (phi, q)
    }

    /// Q over `t` \[s\] with the transition `phi` over it (trapezoidal): (Phi Qc Phi' + Qc) t / 2. F does not
    /// depend on the noise, so a model with other noise densities on the same site and states shares its Phi.
    pub(crate) fn process_noise(&self, phi: &DMatrix<f64>, t: f64) -> DMatrix<f64> {
        // Qc is diagonal and driven on a few states (attitude, velocity, the slow biases): Phi Qc Phi' is the sum
        // of qc_j phi_j phi_j' over the columns j with qc_j != 0, rank-one updates instead of n^3 work.
        let mut q = DMatrix::from_diagonal(&self.qc);
        for (j, &qc) in self.qc.iter().enumerate() {
            if qc != 0.0 {
                let column = phi.column(j);
                q.ger(qc, &column, &column, 1.0);
            }
        }
        symmetrise(q * (0.5 * t))
    }
}

/// (M + M') / 2, in place: each off-diagonal pair becomes its mean (the diagonal is its own mean).
pub(crate) fn symmetrise(mut m: DMatrix<f64>) -> DMatrix<f64> {
    for j in 0..m.ncols() {
        for i in 0..j {
            let mean = (m[(i, j)] + m[(j, i)]) * 0.5;
            m[(i, j)] = mean;
            m[(j, i)] = mean;
        }
    }
    m
}

/// (I - K H) M (I - K H)' + K R K' for H selecting the states `measured` (`gain` K is n x `measured.len()`): with
/// H a selection, (I - K H) M = M - K M\[measured, :\] and M (I - K H)' = M - M\[:, measured\] K', rank-m
/// updates instead of n^3 products (the smoother's update and the aligner's pass).
pub(crate) fn joseph(m: &DMatrix<f64>, gain: &DMatrix<f64>, r: &DMatrix<f64>, measured: &[usize]) -> DMatrix<f64> {
    let left = m - gain * m.select_rows(measured);
    &left - left.select_columns(measured) * gain.transpose() + gain * r * gain.transpose()
}

/// Phi P Phi' over the non-zero entries of Phi (a discretised error model: its bias rows are those of the
/// identity or a decay, so about half its entries are zero).
pub(crate) struct Sandwich {
    n: usize,
    /// (row, column, value) of Phi's non-zero entries.
    entries: Vec<(usize, usize, f64)>,
}

impl Sandwich {
    pub(crate) fn new(phi: &DMatrix<f64>) -> Self {
        let n = phi.nrows();
        let mut entries = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                if phi[(i, j)] != 0.0 {
                    entries.push((i, j, phi[(i, j)]));
                }
            }
        }
        Sandwich { n, entries }
    }

    /// M Phi': column i gathers Phi_ij times column j of M (column-major storage).
    pub(crate) fn right(&self, m: &DMatrix<f64>) -> DMatrix<f64> {
        let n = self.n;
        let mut out = DMatrix::zeros(m.nrows(), n);
        let rows = m.nrows();
        let (from, to) = (m.as_slice(), out.as_mut_slice());
        for &(i, j, v) in &self.entries {
            for (o, x) in to[i * rows..(i + 1) * rows]
                .iter_mut()
                .zip(&from[j * rows..(j + 1) * rows])
            {
                *o += v * x;
            }
        }
        out
    }

    /// Phi P Phi' = ((P Phi')' Phi')'.
    pub(crate) fn apply(&self, p: &DMatrix<f64>) -> DMatrix<f64> {
        self.right(&self.right(p).transpose()).transpose()
    }
}

/// Prior 1-sigma of every state when the forward filter starts at `t_s` [s] (the end of the coarse alignment),
/// in the order of `state_names` (SI).
pub(crate) fn initial_sigma(cfg: &SmootherConfig, t_s: f64) -> Vec<f64> {
    let n = cfg.n_states();
    let att = cfg
        .att_sigma
        .unwrap_or_else(|| coarse_attitude_sigma(cfg.lat, cfg.height, &cfg.filter()));
    let mut sigma = vec![0.0; n];
    sigma[PHI..PHI + 3].copy_from_slice(&att);
    sigma[DV..DV + 3].copy_from_slice(&[cfg.zupt_sigma; 3]);
    sigma[EPS..EPS + 3].copy_from_slice(&cfg.gyro_bias_sigma);
    sigma[NABLA..NABLA + 3].copy_from_slice(&cfg.accel_bias_sigma);
    sigma[POS] = cfg.position_sigma;
    sigma[POS + 1] = cfg.position_sigma;
    if let Some(g) = cfg.gm_index() {
        sigma[g..g + 3].copy_from_slice(&[cfg.gyro_bias_instability; 3]);
    }
    if let Some(r) = cfg.rrw_index() {
        // The random walk starts at zero with the log; by the end of the coarse span it has spread.
        sigma[r..r + 3].copy_from_slice(&[cfg.gyro_rrw * t_s.sqrt(); 3]);
    }
    if let Some(k) = cfg.thermal_index() {
        sigma[k] = cfg.thermal_sigma;
    }
    sigma
}

/// The states one update measures, in the order of the measurement (velocity E N U, position north, east).
pub(crate) const MEASURED: [usize; 5] = [DV, DV + 1, DV + 2, POS, POS + 1];

/// The measurement matrix (selecting [`MEASURED`]) and noise covariance of one update (velocity E N U [m/s],
/// position north, east [m]).
pub(crate) fn measurement_model(cfg: &SmootherConfig, n: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut h = DMatrix::zeros(5, n);
    for (row, &state) in MEASURED.iter().enumerate() {
        h[(row, state)] = 1.0;
    }
    (h, measurement_noise(cfg))
}

/// The noise covariance of one update's measurements ([`MEASURED`]): zero-velocity, then position.
pub(crate) fn measurement_noise(cfg: &SmootherConfig) -> DMatrix<f64> {
    let mut r = DMatrix::zeros(5, 5);
    for i in 0..3 {
        r[(i, i)] = cfg.zupt_sigma * cfg.zupt_sigma;
    }
    for i in 3..5 {
        r[(i, i)] = cfg.position_sigma * cfg.position_sigma;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pseudo-random matrix with about a third of its entries zero (a fixed LCG: reproducible).
    fn matrix(rows: usize, cols: usize, seed: u64) -> DMatrix<f64> {
        let mut state = seed;
        DMatrix::from_fn(rows, cols, |_, _| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            if u < 0.33 {
                0.0
            } else {
                2.0 * u - 1.0
            }
        })
    }

    #[test]
    fn the_sparse_sandwich_and_the_selected_joseph_form_match_the_dense_products() {
        let velocity = [DV, DV + 1, DV + 2];
        for n in [17, 21] {
            let phi = matrix(n, n, 1 + n as u64);
            let m = matrix(n, n, 2 + n as u64);
            let dense = &phi * &m * phi.transpose();
            let worst = (Sandwich::new(&phi).apply(&m) - &dense).amax();
            assert!(worst < 1e-12 * dense.amax(), "n {n}: sandwich off by {worst:e}");
            for measured in [&velocity[..], &MEASURED[..]] {
                let k = measured.len();
                let gain = matrix(n, k, 3 + n as u64);
                let r = DMatrix::from_diagonal_element(k, k, 0.3);
                let mut h = DMatrix::zeros(k, n);
                for (row, &state) in measured.iter().enumerate() {
                    h[(row, state)] = 1.0;
                }
                let i_kh = DMatrix::<f64>::identity(n, n) - &gain * &h;
                let dense = &i_kh * &m * i_kh.transpose() + &gain * &r * gain.transpose();
                let worst = (joseph(&m, &gain, &r, measured) - &dense).amax();
                assert!(
                    worst < 1e-12 * dense.amax(),
                    "n {n}, {k} measured: Joseph form off by {worst:e}"
                );
            }
        }
    }
}
