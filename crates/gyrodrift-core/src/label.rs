//! The uncertainty of the 72 h "true drift" label ([`label_sigma`]): a covariance analysis of the free navigation
//! with the smoother's error model and no IMU samples, and the settings of a free navigation (`FreeNavigation`)
//! it shares with the planner's mission (`plan::mission_covariance`).

use crate::attitude::Mat3;
use crate::error::{check, CoreError};
use crate::kalman::{DV, EPS, PHI};
use crate::limits::{check_arw, check_site, check_slow_bias, check_vrw};
use crate::smoother::model::{symmetrise, Model};
use crate::smoother::{SmootherConfig, POS};
use nalgebra::{DMatrix, DVector};

/// A free navigation propagated by covariance alone, with no measurements (SI): the settings of the label's sigma
/// ([`LabelConfig`]) and of the planner's mission (`plan::mission_covariance`), checked with one set of limits.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeNavigation {
    /// Site latitude \[rad\] and height \[m\].
    pub lat: f64,
    pub height: f64,
    /// Navigation after the alignment \[s\] (72 h).
    pub span_s: f64,
    /// Propagation step \[s\] (60; for the label, the interval of the error curves the criterion is taken over).
    pub step_s: f64,
    /// Angle random walk [rad/sqrt(s)] and velocity random walk [m/s/sqrt(s)].
    pub gyro_arw: f64,
    pub accel_vrw: f64,
    /// Attitude error 1-sigma E N U at the start of the navigation \[rad\] (the alignment's), and velocity [m/s].
    pub att_sigma: [f64; 3],
    pub vel_sigma: f64,
}

impl FreeNavigation {
    /// White noise only at the site (height 0), the alignment's errors left out.
    pub fn white(lat: f64, span_s: f64, step_s: f64, gyro_arw: f64, accel_vrw: f64) -> Self {
        FreeNavigation {
            lat,
            height: 0.0,
            span_s,
            step_s,
            gyro_arw,
            accel_vrw,
            att_sigma: [0.0; 3],
            vel_sigma: 0.0,
        }
    }

    /// Range checks; errors name the key (`step_what` names the step in the message).
    pub(crate) fn validate(&self, step_what: &str) -> Result<(), CoreError> {
        use crate::error::{all_in_range, in_range, Unit};
        check_site(self.lat, 0.0, self.height, 1.0)?;
        let s = Unit::Si("s");
        in_range("span_s", "span", self.span_s, 60.0, 1e7, s)?;
        in_range("step_s", step_what, self.step_s, 1.0, self.span_s, s)?;
        check_arw(self.gyro_arw)?;
        check_vrw(self.accel_vrw)?;
        all_in_range("att_sigma_rad", "attitude sigma", &self.att_sigma, 0.0, 0.2, Unit::Deg)?;
        in_range(
            "vel_sigma_m_s",
            "velocity sigma",
            self.vel_sigma,
            0.0,
            10.0,
            Unit::Si("m/s"),
        )
    }

    /// The smoother's settings whose error model this navigation propagates (its site and noise; a 1 Hz placeholder
    /// rate, which the model does not use).
    pub(crate) fn smoother_config(&self) -> SmootherConfig {
        let mut sc = SmootherConfig::new(self.lat, 0.0, self.height, 1.0);
        sc.gyro_arw = self.gyro_arw;
        sc.accel_vrw = self.accel_vrw;
        sc
    }
}

/// Settings of the label covariance analysis ([`label_sigma`]), SI.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelConfig {
    /// The navigation after the alignment (its `step_s` is the interval of the error curves).
    pub navigation: FreeNavigation,
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
            navigation: FreeNavigation::white(lat, span_s, step_s, gyro_arw, accel_vrw),
            rms,
            gyro_bias_instability: 0.0,
            gyro_correlation: 3600.0,
            gyro_rrw: 0.0,
            rrw_start_s: 0.0,
        }
    }
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
    let nav = &cfg.navigation;
    nav.validate("curve interval")?;
    let s = Unit::Si("s");
    check_slow_bias(cfg.gyro_bias_instability, cfg.gyro_correlation, cfg.gyro_rrw)?;
    in_range("rrw_start_s", "random-walk start", cfg.rrw_start_s, 0.0, 1e7, s)?;
    let mut sc = nav.smoother_config();
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
    let (phi, q) = model.discretise(&identity, 0.0, nav.step_s);
    // Augmented covariance: the error state and the accumulator s (last).
    let na = n + 1;
    let mut p = DMatrix::zeros(na, na);
    for i in 0..3 {
        p[(PHI + i, PHI + i)] = nav.att_sigma[i] * nav.att_sigma[i];
    }
    for i in 0..2 {
        p[(DV + i, DV + i)] = nav.vel_sigma * nav.vel_sigma;
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
    let steps = (nav.span_s / nav.step_s).round().max(1.0) as usize;
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
