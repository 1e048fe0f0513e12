//! The full-information estimator of the axial drift: a forward Kalman filter and a Rauch-Tung-Striebel smoother
//! over a whole static-base log (coarse alignment, then every sample to the end of the span, 16 h by default),
//! with zero velocity AND the known position as measurements throughout, the turntable running. Its covariance
//! under the linear-Gaussian model is the Cramer-Rao line of any drift identification from the same data.
//! A covariance analysis with the same error model gives the 1-sigma of the 72 h "true drift" label
//! ([`label_sigma`]).
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
//! plus k_z (T_k - T_ref) under the thermal model).
//! P_{k+1|k}^-1 is applied through a Cholesky factor of its correlation matrix (states span 1e-24 to 1e-6 in
//! their SI variances).

use crate::alignment::{coarse_attitude_sigma, AlignerConfig, DEG_PER_HOUR, MICRO_G};
use crate::attitude::{dcm_to_euler, quat_to_dcm, Mat3};
use crate::coarse_alignment::InertialCoarseAlignment;
use crate::earth;
use crate::error::{check, CoreError};
use crate::kalman::{ErrorModel, DV, EPS, NABLA, N_STATES as N_BASE, PHI, STATE_NAMES as BASE_NAMES};
use crate::limits::{check_increments, check_site};
use crate::strapdown::{Navigator, NavigatorConfig, Vertical};
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

/// Settings of the smoother (SI). Keys of the binding in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct SmootherConfig {
    /// Known static site \[rad, rad, m\] (`lat_rad`, `lon_rad`, `height_m`) and sample rate \[Hz\] (`rate_hz`).
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    pub rate_hz: f64,
    /// Coarse alignment at the start \[s\] (`coarse_s`, default 300).
    pub coarse_s: f64,
    /// The whole span from the first sample \[s\] (`span_s`, default 57600: 4 h alignment + 12 h).
    pub span_s: f64,
    /// Measurement interval \[s\] (`update_s`, default 10).
    pub update_s: f64,
    /// Initial attitude 1-sigma E N U \[rad\] (`att_sigma_rad`); None: the aligner's `coarse_attitude_sigma`.
    pub att_sigma: Option<[f64; 3]>,
    /// Prior 1-sigma of the constant gyro biases [rad/s] (`gyro_bias_sigma_rad_s`, default 0.1 deg/h: wide, so the
    /// prior pulls a 0.05 deg/h drift by less than 1e-7 deg/h).
    pub gyro_bias_sigma: [f64; 3],
    /// Prior 1-sigma of the accelerometer biases [m/s^2] (`accel_bias_sigma_m_s2`, default 100 ug).
    pub accel_bias_sigma: [f64; 3],
    /// Angle random walk [rad/sqrt(s)] (`gyro_arw_rad_rts`, default 0.0005 deg/sqrt(h)).
    pub gyro_arw: f64,
    /// Velocity random walk [m/s/sqrt(s)] (`accel_vrw_m_s_rts`, default 5 ug/sqrt(Hz)).
    pub accel_vrw: f64,
    /// Gauss-Markov bias instability (stationary sigma) [rad/s] (`gyro_bias_instability_rad_s`, 0 = no states).
    pub gyro_bias_instability: f64,
    /// Its correlation time \[s\] (`gyro_correlation_s`, default 3600).
    pub gyro_correlation: f64,
    /// Rate random walk [rad/s/sqrt(s)] (`gyro_rrw_rad_s_rts`, 0 = no states).
    pub gyro_rrw: f64,
    /// Zero-velocity measurement 1-sigma [m/s] (`zupt_sigma_m_s`, default 1e-4).
    pub zupt_sigma: f64,
    /// Known-position measurement 1-sigma \[m\] (`position_sigma_m`, default 0.01).
    pub position_sigma: f64,
    /// Interval of the reported history \[s\] (`history_s`, default 600).
    pub history_s: f64,
    /// Thermal model of the z drift (`thermal`, default false): one more random-constant state k_z
    /// [rad/s/degC], the z drift being eps_z + k_z (T - T_ref); `process` then needs every sample's temperature.
    pub thermal: bool,
    /// Prior 1-sigma of k_z [rad/s/degC] (`thermal_sigma_rad_s_per_c`, default 0.01 deg/h/degC: wide).
    pub thermal_sigma: f64,
    /// T_ref \[deg C\] (`temp_ref_c`); None: the temperature of the last sample of the coarse alignment.
    pub temp_ref: Option<f64>,
    /// Least temperature range over the span after the coarse alignment \[deg C\] for which the thermal model is
    /// the reported one (`thermal_min_range_c`, default 0.5); below it the constant model's estimates (the thermal
    /// state conditioned on k_z = 0) are reported.
    pub thermal_min_range: f64,
}

impl SmootherConfig {
    /// The defaults at a site.
    pub fn new(lat: f64, lon: f64, height: f64, rate_hz: f64) -> Self {
        SmootherConfig {
            lat,
            lon,
            height,
            rate_hz,
            coarse_s: 300.0,
            span_s: 57_600.0,
            update_s: 10.0,
            att_sigma: None,
            gyro_bias_sigma: [0.1 * DEG_PER_HOUR; 3],
            accel_bias_sigma: [100.0 * MICRO_G; 3],
            gyro_arw: 0.0005 * std::f64::consts::PI / 180.0 / 60.0,
            accel_vrw: 5.0 * MICRO_G,
            gyro_bias_instability: 0.0,
            gyro_correlation: 3600.0,
            gyro_rrw: 0.0,
            zupt_sigma: 1e-4,
            position_sigma: 0.01,
            history_s: 600.0,
            thermal: false,
            thermal_sigma: DEFAULT_THERMAL_SIGMA_DEG_H_PER_C * DEG_PER_HOUR,
            temp_ref: None,
            thermal_min_range: DEFAULT_THERMAL_MIN_RANGE_C,
        }
    }

    /// Range checks; errors name the key.
    pub fn validate(&self) -> Result<(), CoreError> {
        use crate::error::{all_positive_at_most, in_range, sig, Unit};
        check_site(self.lat, self.lon, self.height, self.rate_hz)?;
        // The aligner's checks of the shared settings (one set of limits).
        self.aligner_config().validate()?;
        let s = Unit::Si("s");
        // Without process noise the covariance of the long span collapses and the filter stops listening.
        check(
            self.gyro_arw > 0.0 && self.accel_vrw > 0.0,
            if self.gyro_arw > 0.0 {
                "accel_vrw_m_s_rts"
            } else {
                "gyro_arw_rad_rts"
            },
            "the smoother needs positive noise densities (model a noise-free log with small ones)",
        )?;
        in_range("span_s", "span", self.span_s, self.coarse_s + self.update_s, 1e6, s)?;
        check_slow_bias(self.gyro_bias_instability, self.gyro_correlation, self.gyro_rrw)?;
        all_positive_at_most(
            "position_sigma_m",
            "position sigma",
            &[self.position_sigma],
            1e4,
            Unit::Si("m"),
        )?;
        let per_c = Unit::Scaled(180.0 / std::f64::consts::PI * 3600.0, "deg/h/degC");
        all_positive_at_most(
            "thermal_sigma_rad_s_per_c",
            "thermal coefficient prior sigma",
            &[self.thermal_sigma],
            DEG_PER_HOUR,
            per_c,
        )?;
        if let Some(t) = self.temp_ref {
            in_range(
                "temp_ref_c",
                "reference temperature",
                t,
                -100.0,
                200.0,
                Unit::Si("deg C"),
            )?;
        }
        in_range(
            "thermal_min_range_c",
            "least temperature range",
            self.thermal_min_range,
            0.0,
            300.0,
            Unit::Si("deg C"),
        )?;
        let updates = ((self.span_s - self.coarse_s) / self.update_s).ceil();
        check(
            updates <= MAX_UPDATES as f64,
            "update_s",
            format!(
                "update interval {} s gives {} updates over the span; at most {MAX_UPDATES} are kept for the \
                 backward pass (use a longer interval)",
                sig(self.update_s),
                sig(updates)
            ),
        )
    }

    /// The aligner settings these share (the coarse alignment, the priors and the noise).
    pub(crate) fn aligner_config(&self) -> AlignerConfig {
        AlignerConfig {
            coarse_s: self.coarse_s,
            fine_s: 0.0,
            update_s: self.update_s,
            att_sigma: self.att_sigma,
            gyro_bias_sigma: self.gyro_bias_sigma,
            accel_bias_sigma: self.accel_bias_sigma,
            gyro_arw: self.gyro_arw,
            accel_vrw: self.accel_vrw,
            zupt_sigma: self.zupt_sigma,
            history_s: self.history_s,
            ..AlignerConfig::new(self.lat, self.lon, self.height, self.rate_hz)
        }
    }

    fn has_gm(&self) -> bool {
        self.gyro_bias_instability > 0.0
    }

    fn has_rrw(&self) -> bool {
        self.gyro_rrw > 0.0
    }

    /// Number of states (14, 17 or 20; one more with the thermal state).
    pub fn n_states(&self) -> usize {
        N_BASE + 2 + 3 * usize::from(self.has_gm()) + 3 * usize::from(self.has_rrw()) + usize::from(self.thermal)
    }

    /// Index of the thermal coefficient k_z (the last state; None when absent).
    fn thermal_index(&self) -> Option<usize> {
        self.thermal.then(|| self.n_states() - 1)
    }

    /// First Gauss-Markov state and first random-walk state (None when absent).
    fn gm_index(&self) -> Option<usize> {
        self.has_gm().then_some(POS + 2)
    }

    fn rrw_index(&self) -> Option<usize> {
        self.has_rrw().then_some(POS + 2 + 3 * usize::from(self.has_gm()))
    }
}

/// Names of the states of a configuration, in order.
pub fn state_names(cfg: &SmootherConfig) -> Vec<&'static str> {
    let mut names: Vec<&'static str> = BASE_NAMES.to_vec();
    names.extend(["pos_n", "pos_e"]);
    if cfg.has_gm() {
        names.extend(["gyro_gm_x", "gyro_gm_y", "gyro_gm_z"]);
    }
    if cfg.has_rrw() {
        names.extend(["gyro_rrw_x", "gyro_rrw_y", "gyro_rrw_z"]);
    }
    if cfg.thermal {
        names.push("gyro_temp_z");
    }
    names
}

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
    thermal: Option<usize>,
    tau: f64,
    /// Continuous noise densities squared on the diagonal.
    qc: DVector<f64>,
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
    pub(crate) fn discretise(&self, c: &Mat3, dtemp: f64, t: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        let ft = self.system_matrix(c, dtemp) * t;
        let mut phi = DMatrix::identity(self.n, self.n);
        let mut term = DMatrix::identity(self.n, self.n);
        for k in 1..=8 {
            term = &term * &ft / k as f64;
            phi += &term;
        }
        let qc = DMatrix::from_diagonal(&self.qc);
        let q = (&phi * &qc * phi.transpose() + &qc) * (0.5 * t);
        (phi, symmetrise(q))
    }
}

pub(crate) fn symmetrise(m: DMatrix<f64>) -> DMatrix<f64> {
    (&m + m.transpose()) * 0.5
}

/// Prior 1-sigma of every state when the forward filter starts at `t_s` [s] (the end of the coarse alignment),
/// in the order of `state_names` (SI).
pub(crate) fn initial_sigma(cfg: &SmootherConfig, t_s: f64) -> Vec<f64> {
    let n = cfg.n_states();
    let att = cfg
        .att_sigma
        .unwrap_or_else(|| coarse_attitude_sigma(&cfg.aligner_config()));
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

/// The measurement matrix and noise covariance of one update (velocity E N U [m/s], position north, east [m]).
pub(crate) fn measurement_model(cfg: &SmootherConfig, n: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut h = DMatrix::zeros(5, n);
    for i in 0..3 {
        h[(i, DV + i)] = 1.0;
    }
    h[(3, POS)] = 1.0;
    h[(4, POS + 1)] = 1.0;
    let mut r = DMatrix::zeros(5, 5);
    for i in 0..3 {
        r[(i, i)] = cfg.zupt_sigma * cfg.zupt_sigma;
    }
    for i in 3..5 {
        r[(i, i)] = cfg.position_sigma * cfg.position_sigma;
    }
    (h, r)
}

/// What the forward pass keeps of one update for the backward pass.
#[derive(Clone, Debug)]
struct Step {
    /// Time of the update \[s\] from the first sample.
    t: f64,
    /// x_{k|k} (before the feedback) and P_{k|k}.
    x: DVector<f64>,
    p: DMatrix<f64>,
    /// Transition to the next update (set when the next update comes).
    phi_next: Option<DMatrix<f64>>,
    /// The navigator's z gyro bias [rad/s] and all three gyro biases before this update's feedback.
    gyro_bias: [f64; 3],
    accel_bias: [f64; 3],
    /// T - T_ref at the update \[deg C\] (0 without the thermal state).
    dtemp: f64,
}

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
    /// The total z-gyro bias at the end of the span under the reported model (constant + Gauss-Markov + random
    /// walk, + k_z (T_end - T_ref) when `thermal`) and its 1-sigma: the drift carried into navigation.
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
    /// Covariance of the thermal model's end drift eps_z + k_z (T_end - T_ref) (+ b_gm,z + b_rrw,z) with k_z
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

/// The forward filter and its store (after the coarse alignment).
#[derive(Clone, Debug)]
struct Forward {
    nav: Navigator,
    model: Model,
    x: DVector<f64>,
    p: DMatrix<f64>,
    gyro_bias: [f64; 3],
    accel_bias: [f64; 3],
    c_sum: Mat3,
    /// Sum of T - T_ref over the interval \[deg C\], T_ref, and the temperature range and last value after the
    /// coarse alignment (thermal state only).
    temp_sum: f64,
    temp_ref: f64,
    temp_min: f64,
    temp_max: f64,
    temp_last: f64,
    n_interval: u64,
    steps: Vec<Step>,
    /// P_{k+1|k} of each step's successor (parallel to `steps`, one fewer at the end).
    p_pred: Vec<DMatrix<f64>>,
    x_pred: Vec<DVector<f64>>,
    max_att: f64,
    max_vel: f64,
    max_pos: f64,
}

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
        let diverged = |message: String| CoreError::Diverged {
            key: "dv_m_s",
            t_s,
            message,
        };
        if !c_bn.iter().flatten().all(|x| x.is_finite()) {
            return Err(diverged(
                "the coarse alignment found no attitude (no gravity in the log?)".to_string(),
            ));
        }
        let cfg = &self.cfg;
        let nav = Navigator::new(NavigatorConfig {
            lat: cfg.lat,
            lon: cfg.lon,
            height: cfg.height,
            vel: [0.0; 3],
            attitude: dcm_to_euler(&c_bn),
            rate_hz: cfg.rate_hz,
            vertical: Vertical::Fixed,
        })
        .map_err(|e| diverged(format!("the coarse attitude is outside the navigator's range: {e}")))?;
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

impl Forward {
    /// Predict over the interval just ended, update with zero velocity and the known position, feed back.
    fn update(&mut self, cfg: &SmootherConfig, t_s: f64, fine_t: f64) -> Result<(), CoreError> {
        let n_int = self.n_interval as f64;
        let t = n_int / cfg.rate_hz;
        let c_mean: Mat3 = std::array::from_fn(|i| std::array::from_fn(|j| self.c_sum[i][j] / n_int));
        let (phi, q) = self.model.discretise(&c_mean, self.temp_sum / n_int, t);
        let x_pred = &phi * &self.x;
        let p_pred = symmetrise(&phi * &self.p * phi.transpose() + q);
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
        let (h, r) = measurement_model(cfg, n);
        let diverged = |message: String| CoreError::Diverged {
            key: "dv_m_s",
            t_s,
            message,
        };
        let innovation_cov = &h * &p_pred * h.transpose() + &r;
        let s_inv = innovation_cov
            .try_inverse()
            .filter(|m| m.iter().all(|x| x.is_finite()) && z.iter().all(|x| x.is_finite()))
            .ok_or_else(|| diverged("the smoother's update has no finite solution".to_string()))?;
        let k_gain = &p_pred * h.transpose() * s_inv;
        let x_upd = &x_pred + &k_gain * (&z - &h * &x_pred);
        let i_kh = DMatrix::identity(n, n) - &k_gain * &h;
        let p_upd = symmetrise(&i_kh * &p_pred * i_kh.transpose() + &k_gain * r * k_gain.transpose());
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

    /// The backward (RTS) pass and the result.
    fn smooth(&self, cfg: &SmootherConfig, t_end: f64) -> Result<SmootherResult, CoreError> {
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
        // Selector of the total z drift: eps_z + gm_z + rrw_z (+ k_z (T - T_ref) under the thermal model).
        let mut e_total = unit(EPS + 2);
        if let Some(g) = self.model.gm {
            e_total[g + 2] = 1.0;
        }
        if let Some(r) = self.model.rrw {
            e_total[r + 2] = 1.0;
        }
        let total = |step: &Step, x: &DVector<f64>, p: &DMatrix<f64>| {
            let mut a = e_total.clone();
            if let (Some(k), true) = (k_th, thermal) {
                a[k] = step.dtemp;
            }
            let (d, s) = linear(&a, x, p, !thermal);
            (step.gyro_bias[2] + d, s)
        };
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
        let (drift_end, drift_end_std) = total(last, &xs, &ps);
        // Covariance of the thermal model's end drift with k_z (unconditioned; the last step's smoothed = filtered P).
        let end_coeff_cov = k_th.map_or(f64::NAN, |k| {
            let mut a = e_total.clone();
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
            let d: DVector<f64> = p_pred.diagonal().map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 });
            let dm = DMatrix::from_diagonal(&d);
            let corr = symmetrise(&dm * p_pred * &dm);
            let chol = corr
                .cholesky()
                .ok_or_else(|| diverged("the smoother's predicted covariance is not positive definite"))?;
            let a = &step.p * phi.transpose() * &dm; // P_k Phi' D
            let c = chol.solve(&a.transpose()).transpose() * &dm; // (P_k Phi' D) corr^-1 D
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

/// Settings of the label covariance analysis ([`label_sigma`]), SI.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelConfig {
    /// Site latitude \[rad\] and height \[m\].
    pub lat: f64,
    pub height: f64,
    /// Navigation after the alignment \[s\] (72 h).
    pub span_s: f64,
    /// Interval of the error curves the criterion is taken over \[s\] (60).
    pub step_s: f64,
    /// Angle random walk [rad/sqrt(s)] and velocity random walk [m/s/sqrt(s)] of the log.
    pub gyro_arw: f64,
    pub accel_vrw: f64,
    /// Attitude error 1-sigma E N U at the start of the navigation \[rad\] (the alignment's), and velocity [m/s].
    pub att_sigma: [f64; 3],
    pub vel_sigma: f64,
    /// `true`: the criterion is the root mean square of the position error over the curve; `false`: its last value.
    pub rms: bool,
    /// The z gyro's slowly varying bias, which the label's constant absorbs and the run's noise-free twin lacks:
    /// first-order Gauss-Markov bias instability (stationary 1-sigma) [rad/s] with correlation time \[s\], and
    /// rate random walk [rad/s/sqrt(s)] that has walked `rrw_start_s` \[s\] (the alignment) before the navigation
    /// starts (0: none). The x and y ones are modulated by the table and left out, like the constant biases.
    pub gyro_bias_instability: f64,
    pub gyro_correlation: f64,
    pub gyro_rrw: f64,
    pub rrw_start_s: f64,
}

impl LabelConfig {
    /// White noise only (no bias instability, no rate random walk), the alignment's errors left out.
    pub fn white(lat: f64, span_s: f64, step_s: f64, gyro_arw: f64, accel_vrw: f64, rms: bool) -> Self {
        LabelConfig {
            lat,
            height: 0.0,
            span_s,
            step_s,
            gyro_arw,
            accel_vrw,
            att_sigma: [0.0; 3],
            vel_sigma: 0.0,
            rms,
            gyro_bias_instability: 0.0,
            gyro_correlation: 3600.0,
            gyro_rrw: 0.0,
            rrw_start_s: 0.0,
        }
    }
}

/// The z gyro's slow bias terms (Gauss-Markov 1-sigma [rad/s] and correlation time \[s\], rate random walk
/// [rad/s/sqrt(s)]): one set of limits for the smoother, the label's sigma and the planner.
pub(crate) fn check_slow_bias(instability: f64, correlation: f64, rrw: f64) -> Result<(), CoreError> {
    use crate::error::{all_positive_at_most, in_range, Unit, DEG_H_PER_RTH};
    in_range(
        "gyro_bias_instability_rad_s",
        "bias instability",
        instability,
        0.0,
        0.1,
        Unit::DegPerH,
    )?;
    all_positive_at_most(
        "gyro_correlation_s",
        "correlation time",
        &[correlation],
        1e9,
        Unit::Si("s"),
    )?;
    in_range("gyro_rrw_rad_s_rts", "rate random walk", rrw, 0.0, 0.1, DEG_H_PER_RTH)
}

/// A free navigation propagated by covariance alone ([`label_sigma`], the planner's mission): the settings both
/// check with one set of limits (SI; `step_what` names the step in the message).
pub(crate) struct FreeNavigation<'a> {
    pub lat: f64,
    pub height: f64,
    pub span_s: f64,
    pub step_s: f64,
    pub step_what: &'a str,
    pub gyro_arw: f64,
    pub accel_vrw: f64,
    pub att_sigma: [f64; 3],
    pub vel_sigma: f64,
}

/// Range checks of a [`FreeNavigation`]; errors name the key.
pub(crate) fn check_free_navigation(f: &FreeNavigation) -> Result<(), CoreError> {
    use crate::error::{all_in_range, in_range, Unit, DEG_PER_RTH, MICRO_G_PER_RTHZ};
    check_site(f.lat, 0.0, f.height, 1.0)?;
    let s = Unit::Si("s");
    in_range("span_s", "span", f.span_s, 60.0, 1e7, s)?;
    in_range("step_s", f.step_what, f.step_s, 1.0, f.span_s, s)?;
    in_range(
        "gyro_arw_rad_rts",
        "angle random walk",
        f.gyro_arw,
        0.0,
        0.1,
        DEG_PER_RTH,
    )?;
    in_range(
        "accel_vrw_m_s_rts",
        "velocity random walk",
        f.accel_vrw,
        0.0,
        1.0,
        MICRO_G_PER_RTHZ,
    )?;
    all_in_range("att_sigma_rad", "attitude sigma", &f.att_sigma, 0.0, 0.2, Unit::Deg)?;
    in_range(
        "vel_sigma_m_s",
        "velocity sigma",
        f.vel_sigma,
        0.0,
        10.0,
        Unit::Si("m/s"),
    )
}

/// The label's uncertainty ([`label_sigma`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelSigma {
    /// 1-sigma of the best constant drift [rad/s].
    pub drift_std: f64,
    /// Sensitivity of the position error at the end of the span to the drift: hypot of the north and east
    /// responses [m per rad/s].
    pub sensitivity: f64,
    /// 1-sigma of the north and east position errors at the end from the noise and the initial errors \[m\].
    pub pos_std: [f64; 2],
}

/// 1-sigma of the "true drift" label of a log: the z drift d* minimising the position-error criterion over the
/// navigation (`final`: the last point; `rms`) moves with the part of the position error the drift does not
/// explain. With e(t) that part (north, east) and g(t) the position response to a unit z drift, both from the
/// smoother's error model (free navigation, no measurements; the horizontal sensor biases modulated away by the
/// table, so left out; the body level, so C_b^n = I for the z column):
///   final: d* - d = -g(T)' e(T) / |g(T)|^2,  var = g(T)' Cov(e(T)) g(T) / |g(T)|^4;
///   rms:   d* - d = -sum_k g_k' e_k / sum_k |g_k|^2, whose variance comes from an accumulator state s,
///          s <- s + g_k' e_k at every curve point, propagated with the error state.
/// e is driven by the angle and velocity random walks over the span, by the z gyro's Gauss-Markov bias and rate
/// random walk when given (states of the same model; the Gauss-Markov one stationary, the random walk with the
/// spread it has at the start: variance rrw^2 `rrw_start_s`), and by the attitude and velocity errors left by
/// the alignment (`att_sigma`, `vel_sigma`, independent of the drift: an approximation, since the alignment's
/// heading error and its z-bias estimate are correlated). With white noise only, `final`, and T >> the Schuler
/// period this is close to sqrt(1.5 T) N / |g(T)| (N the ARW; tests/procedure/test_label_flags_and_noise.py derives it).
pub fn label_sigma(cfg: &LabelConfig) -> Result<LabelSigma, CoreError> {
    use crate::error::{in_range, Unit};
    check_free_navigation(&FreeNavigation {
        lat: cfg.lat,
        height: cfg.height,
        span_s: cfg.span_s,
        step_s: cfg.step_s,
        step_what: "curve interval",
        gyro_arw: cfg.gyro_arw,
        accel_vrw: cfg.accel_vrw,
        att_sigma: cfg.att_sigma,
        vel_sigma: cfg.vel_sigma,
    })?;
    let s = Unit::Si("s");
    check_slow_bias(cfg.gyro_bias_instability, cfg.gyro_correlation, cfg.gyro_rrw)?;
    in_range("rrw_start_s", "random-walk start", cfg.rrw_start_s, 0.0, 1e7, s)?;
    let mut sc = SmootherConfig::new(cfg.lat, 0.0, cfg.height, 1.0);
    sc.gyro_arw = cfg.gyro_arw;
    sc.accel_vrw = cfg.accel_vrw;
    sc.gyro_bias_instability = cfg.gyro_bias_instability;
    sc.gyro_correlation = cfg.gyro_correlation;
    sc.gyro_rrw = cfg.gyro_rrw;
    let mut model = Model::new(&sc);
    let n = model.n;
    // The z gyro's slow bias only: the x and y states keep zero variance and no process noise.
    for first in [model.gm, model.rrw].into_iter().flatten() {
        model.qc[first] = 0.0;
        model.qc[first + 1] = 0.0;
    }
    let identity: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let (phi, q) = model.discretise(&identity, 0.0, cfg.step_s);
    // Augmented covariance: the error state and the accumulator s (last).
    let na = n + 1;
    let mut p = DMatrix::zeros(na, na);
    for i in 0..3 {
        p[(PHI + i, PHI + i)] = cfg.att_sigma[i] * cfg.att_sigma[i];
    }
    for i in 0..2 {
        p[(DV + i, DV + i)] = cfg.vel_sigma * cfg.vel_sigma;
    }
    if let Some(g) = model.gm {
        p[(g + 2, g + 2)] = cfg.gyro_bias_instability * cfg.gyro_bias_instability;
    }
    if let Some(r) = model.rrw {
        p[(r + 2, r + 2)] = cfg.gyro_rrw * cfg.gyro_rrw * cfg.rrw_start_s;
    }
    let mut phi_a = DMatrix::identity(na, na);
    phi_a.view_mut((0, 0), (n, n)).copy_from(&phi);
    let mut q_a = DMatrix::zeros(na, na);
    q_a.view_mut((0, 0), (n, n)).copy_from(&q);
    // Response to a unit z drift: the bias state set to 1 rad/s and carried by the same transition.
    let mut g = DVector::zeros(n);
    g[EPS + 2] = 1.0;
    let steps = (cfg.span_s / cfg.step_s).round().max(1.0) as usize;
    let mut sum_g2 = 0.0;
    for _ in 0..steps {
        g = &phi * g;
        p = symmetrise(&phi_a * &p * phi_a.transpose() + &q_a);
        if cfg.rms {
            // s <- s + g_N e_N + g_E e_E.
            let mut a = DMatrix::identity(na, na);
            a[(n, POS)] = g[POS];
            a[(n, POS + 1)] = g[POS + 1];
            p = symmetrise(&a * &p * a.transpose());
            sum_g2 += g[POS] * g[POS] + g[POS + 1] * g[POS + 1];
        }
    }
    let (gn, ge) = (g[POS], g[POS + 1]);
    let g2 = gn * gn + ge * ge;
    let var = if cfg.rms {
        p[(n, n)] / (sum_g2 * sum_g2)
    } else {
        (gn * gn * p[(POS, POS)] + 2.0 * gn * ge * p[(POS, POS + 1)] + ge * ge * p[(POS + 1, POS + 1)]) / (g2 * g2)
    };
    check(
        var.is_finite() && g2 > 0.0,
        "lat_rad",
        "the position error does not depend on the z drift here (zero sensitivity)",
    )?;
    Ok(LabelSigma {
        drift_std: var.max(0.0).sqrt(),
        sensitivity: g2.sqrt(),
        pos_std: [p[(POS, POS)].max(0.0).sqrt(), p[(POS + 1, POS + 1)].max(0.0).sqrt()],
    })
}
