//! The uncertainty of the 72 h "true drift" label ([`label_sigma`]): a covariance analysis of the free navigation
//! with the smoother's error model and no IMU samples (from the fine aligner's noise-driven leftovers when its run
//! is given, `aligner_covariance`), and the settings of a free navigation (`FreeNavigation`) it shares with the
//! planner's mission (`plan::mission_covariance`).

use crate::aligner_covariance::{navigation_start_selector, AlignerPass, FineAlignment, TableAttitude};
use crate::attitude::Mat3;
use crate::error::{check, check_with, CoreError};
use crate::kalman::{DV, EPS, PHI};
use crate::limits::{check_arw, check_rate, check_site, check_slow_bias, check_vrw};
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

    /// The smoother's settings and error model this navigation propagates with the z gyro's `slow` bias: its site,
    /// white noise and slow-bias states (a 1 Hz placeholder rate, which the model does not use). The x and y
    /// slow-bias states keep zero process noise (and, started at zero, stay zero): the table modulates them away,
    /// as it does the constant horizontal biases.
    pub(crate) fn model(&self, slow: &SlowBias) -> (SmootherConfig, Model) {
        let mut sc = SmootherConfig::new(self.lat, 0.0, self.height, 1.0);
        sc.gyro_arw = self.gyro_arw;
        sc.accel_vrw = self.accel_vrw;
        sc.gyro_bias_instability = slow.bias_instability;
        sc.gyro_correlation = slow.correlation;
        sc.gyro_rrw = slow.rrw;
        let mut model = Model::new(&sc);
        for first in [model.gm, model.rrw].into_iter().flatten() {
            model.qc[first] = 0.0;
            model.qc[first + 1] = 0.0;
        }
        (sc, model)
    }
}

/// The z gyro's slowly varying bias beside its white noise (SI): a first-order Gauss-Markov bias instability
/// (stationary 1-sigma) [rad/s] with its correlation time \[s\], and a rate random walk [rad/s/sqrt(s)] (0: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlowBias {
    pub bias_instability: f64,
    pub correlation: f64,
    pub rrw: f64,
}

impl SlowBias {
    /// No slow bias (white noise only).
    pub const NONE: SlowBias = SlowBias {
        bias_instability: 0.0,
        correlation: 3600.0,
        rrw: 0.0,
    };

    /// Range checks; errors name the key.
    pub(crate) fn validate(&self) -> Result<(), CoreError> {
        check_slow_bias(self.bias_instability, self.correlation, self.rrw)
    }
}

/// Settings of the label covariance analysis ([`label_sigma`]), SI.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelConfig {
    /// The navigation after the alignment (its `step_s` is the interval of the error curves).
    pub navigation: FreeNavigation,
    /// `true`: the criterion is the root mean square of the position error over the curve; `false`: its last value.
    pub rms: bool,
    /// The z gyro's slowly varying bias, which the label's constant absorbs and the run's noise-free twin lacks,
    /// its rate random walk having walked `rrw_start_s` \[s\] (the alignment) before the navigation starts. The x
    /// and y ones are modulated by the table and left out, like the constant biases.
    pub slow: SlowBias,
    pub rrw_start_s: f64,
    /// The fine alignment the navigation starts from (None: its errors left out but `att_sigma`, `vel_sigma`).
    /// Given, the navigation starts from the covariance of the aligner's noise-driven leftovers (attitude and
    /// velocity; the part the run's noise-free twin lacks: the aligner's true error started from zero at the end of
    /// the coarse span, its prior and gain its own) and their covariance with the z gyro's slow bias.
    pub alignment: Option<FineAlignment>,
}

impl LabelConfig {
    /// White noise only (no bias instability, no rate random walk), the alignment's errors left out.
    pub fn white(lat: f64, span_s: f64, step_s: f64, gyro_arw: f64, accel_vrw: f64, rms: bool) -> Self {
        LabelConfig {
            navigation: FreeNavigation::white(lat, span_s, step_s, gyro_arw, accel_vrw),
            rms,
            slow: SlowBias::NONE,
            rrw_start_s: 0.0,
            alignment: None,
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
/// spread it has at the start: variance rrw^2 `rrw_start_s`), by the fine aligner's noise-driven leftover
/// attitude and velocity errors when its run is given (`alignment`: the aligner's true error covariance under
/// this noise, started from zero after the coarse span, `aligner_covariance`; with the covariance of the z gyro's
/// slow bias with them, which the same noise drives; the noise after the alignment is independent of them), and
/// by independent initial attitude and velocity errors `att_sigma`, `vel_sigma`. The aligner's leftovers move the
/// position by an Earth-rate oscillation that nearly returns to zero after whole sidereal days (72 h) but not
/// after 8 h. With white noise only, `final`, no initial errors and T >> the Schuler period this is close to
/// sqrt(1.5 T) N / |g(T)| (N the ARW; tests/procedure/test_label_flags_and_noise.py derives it).
pub fn label_sigma(cfg: &LabelConfig) -> Result<LabelSigma, CoreError> {
    use crate::error::{in_range, Unit};
    let nav = &cfg.navigation;
    nav.validate("curve interval")?;
    let s = Unit::Si("s");
    cfg.slow.validate()?;
    in_range("rrw_start_s", "random-walk start", cfg.rrw_start_s, 0.0, 1e7, s)?;
    let (sc, model) = nav.model(&cfg.slow);
    let n = model.n;
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
        p[(g + 2, g + 2)] = cfg.slow.bias_instability * cfg.slow.bias_instability;
    }
    if let Some(r) = model.rrw {
        p[(r + 2, r + 2)] = cfg.slow.rrw * cfg.slow.rrw * cfg.rrw_start_s;
    }
    if let Some(al) = &cfg.alignment {
        let leftovers = alignment_leftovers(cfg, &sc, &model, al)?;
        let mut block = p.view_mut((0, 0), (n, n));
        block += leftovers;
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

/// Covariance of the navigation's error state at its start from the fine aligner's noise-driven leftovers
/// ([`LabelConfig::alignment`]): E[y0 y0'] = S A S' (S the attitude and velocity, A the aligner's true error
/// covariance started from zero at the end of the coarse span, but for the z gyro's slow bias, which the twin
/// lacks, with exact zero-velocity measurements), and E[b y0'] for the z gyro's slow-bias states b (the truth's,
/// from the aligner pass's E[x x~']).
/// `model` is the truth's (its x and y slow biases without noise); `sc` its settings.
fn alignment_leftovers(
    cfg: &LabelConfig,
    sc: &crate::smoother::SmootherConfig,
    model: &Model,
    al: &FineAlignment,
) -> Result<DMatrix<f64>, CoreError> {
    use crate::error::{in_range, Unit};
    check_rate(al.rate_hz)?;
    al.filter.validate(al.rate_hz)?;
    let first_update = al.filter.coarse_s + al.filter.update_s;
    in_range(
        "alignment_end_s",
        "alignment end",
        al.end_s,
        first_update,
        1e7,
        Unit::Si("s"),
    )?;
    check_with(
        cfg.slow.rrw == 0.0 || (cfg.rrw_start_s - al.end_s).abs() <= 1e-9 * al.end_s,
        "rrw_start_s",
        || {
            format!(
                "the rate random walk starts the navigation at the alignment's end ({} s), got {} s",
                al.end_s, cfg.rrw_start_s
            )
        },
    )?;
    let rate = al.rate_hz;
    let n_coarse = (al.filter.coarse_s * rate).round() as u64;
    let n_end = (al.end_s * rate).round() as u64;
    let per_update = ((al.filter.update_s * rate).round() as u64).max(1);
    let coarse_end_s = n_coarse as f64 / rate;
    let n = model.n;
    let mut start = DMatrix::zeros(n, n);
    if let Some(g) = model.gm {
        start[(g + 2, g + 2)] = cfg.slow.bias_instability * cfg.slow.bias_instability;
    }
    if let Some(r) = model.rrw {
        start[(r + 2, r + 2)] = cfg.slow.rrw * cfg.slow.rrw * coarse_end_s;
    }
    // The run's zero-velocity measurement is exact (the navigator's velocity error is the state, the sensor noise
    // the model's Q): a noise-free run leaves the aligner nothing of its own.
    let exact = crate::smoother::SmootherConfig {
        zupt_sigma: 0.0,
        ..sc.clone()
    };
    let mut pass = AlignerPass::new(&exact, &al.filter, coarse_end_s, start)?;
    let attitude = TableAttitude::new(&al.scheme, al.attitude, rate)?;
    pass.advance(&attitude, n_coarse, n_end, per_update, model)?;
    let select = navigation_start_selector(n);
    let mut out = &select * &pass.truth * &select;
    for first in [model.gm, model.rrw].into_iter().flatten() {
        let b = first + 2;
        let cross = pass.joint.row(b) * &select;
        for j in 0..n {
            out[(b, j)] += cross[j];
            out[(j, b)] += cross[j];
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aligner_covariance::aligner_on_smoother_model;
    use crate::attitude::Euler;
    use crate::filter_prior::FilterSettings;
    use crate::smoother::model::{initial_sigma, measurement_model};
    use crate::turntable::scheme_from_settings;
    use crate::units::{DEG, DEG_PER_H, DEG_PER_H_PER_SQRT_H, DEG_PER_SQRT_H, HOUR, MICRO_G};

    /// 1 Hz, 1 h of alignment (reciprocating table, heading 30 deg) and 6 h of navigation at 40 deg, RLG noise;
    /// `slow`: with the z gyro's Gauss-Markov bias and rate random walk.
    fn config(slow: bool) -> LabelConfig {
        let arw = 0.0005 * DEG_PER_SQRT_H;
        let mut cfg = LabelConfig::white(40.0 * DEG, 6.0 * HOUR, 60.0, arw, 5.0 * MICRO_G, false);
        if slow {
            cfg.slow.bias_instability = 0.002 * DEG_PER_H;
            cfg.slow.rrw = 0.0005 * DEG_PER_H_PER_SQRT_H;
            cfg.rrw_start_s = HOUR;
        }
        cfg.alignment = Some(FineAlignment {
            rate_hz: 1.0,
            scheme: scheme_from_settings("reciprocating", None, None, None, false, None, None).unwrap(),
            attitude: Euler {
                pitch: 0.0,
                roll: 0.0,
                yaw: 30.0 * DEG,
            },
            filter: FilterSettings::aligner(),
            end_s: HOUR,
        });
        cfg
    }

    /// Brute force: `runs` draws of the linear error model's noise part (the truth from zero but for the z gyro's
    /// slow bias, its noise the model's Q sampled as sqrt(t/2) (Phi Lc z1 + Lc z2)), the aligner run as a Kalman
    /// filter on the (exact) zero-velocity measurements every second, the navigation from its leftover attitude and
    /// velocity and the true slow bias; returns d* - d = -g'e(T) / |g|^2 of each draw (criterion `final`).
    fn monte_carlo(cfg: &LabelConfig, runs: usize, seed: u64) -> Vec<f64> {
        use rand_core::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let al = cfg.alignment.as_ref().unwrap();
        assert_eq!(al.rate_hz, 1.0);
        let (sc, model) = cfg.navigation.model(&cfg.slow);
        let acfg = aligner_on_smoother_model(&sc, &al.filter);
        let own = Model::new(&acfg);
        let n = model.n;
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let mut normal = |r: usize| DMatrix::<f64>::from_fn(r, runs, |_, _| StandardNormal.sample(&mut rng));
        let lc = DMatrix::from_diagonal(&model.qc.map(f64::sqrt));
        let (coarse, end) = (al.filter.coarse_s as u64, al.end_s as u64);
        let mut x = DMatrix::zeros(n, runs);
        if let Some(g) = model.gm {
            x.set_row(g + 2, &(normal(1) * cfg.slow.bias_instability).row(0));
        }
        if let Some(r) = model.rrw {
            x.set_row(r + 2, &(normal(1) * (cfg.slow.rrw * (coarse as f64).sqrt())).row(0));
        }
        let mut xa = DMatrix::zeros(n, runs);
        let mut pa = DMatrix::from_diagonal(&DVector::from_vec(initial_sigma(&acfg, coarse as f64)).map(|s| s * s));
        let (h, _) = measurement_model(&sc, n);
        let h = h.rows(0, 3).into_owned();
        let r_own = DMatrix::from_diagonal_element(3, 3, al.filter.zupt_sigma.powi(2));
        let table = TableAttitude::new(&al.scheme, al.attitude, 1.0).unwrap();
        for k in coarse + 1..=end {
            let c = table.mean(k - 1, k);
            let (phi, _) = model.discretise(&c, 0.0, 1.0);
            let (_, q_own) = own.discretise(&c, 0.0, 1.0);
            x = &phi * &x + (&phi * &lc * normal(n) + &lc * normal(n)) * 0.5f64.sqrt();
            xa = &phi * &xa;
            pa = &phi * &pa * phi.transpose() + q_own;
            let gain = &pa * h.transpose() * (&h * &pa * h.transpose() + &r_own).try_inverse().unwrap();
            let z = &h * &x;
            xa += &gain * (z - &h * &xa);
            pa = (DMatrix::identity(n, n) - &gain * &h) * &pa;
        }
        let mut y = navigation_start_selector(n) * (&x - &xa);
        for first in [model.gm, model.rrw].into_iter().flatten() {
            y.set_row(first + 2, &x.row(first + 2));
        }
        let level: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let step = cfg.navigation.step_s;
        let (phi, _) = model.discretise(&level, 0.0, step);
        let mut g = DVector::zeros(n);
        g[EPS + 2] = 1.0;
        for _ in 0..(cfg.navigation.span_s / step).round() as usize {
            y = &phi * &y + (&phi * &lc * normal(n) + &lc * normal(n)) * (0.5 * step).sqrt();
            g = &phi * g;
        }
        let g2 = g[POS] * g[POS] + g[POS + 1] * g[POS + 1];
        (0..runs)
            .map(|j| -(g[POS] * y[(POS, j)] + g[POS + 1] * y[(POS + 1, j)]) / g2)
            .collect()
    }

    #[test]
    fn the_alignment_term_matches_a_monte_carlo_of_the_linear_model() {
        let runs = 1000;
        for (slow, seed) in [(false, 5), (true, 6)] {
            let cfg = config(slow);
            let d = monte_carlo(&cfg, runs, seed);
            let var_mc = d.iter().map(|v| v * v).sum::<f64>() / runs as f64;
            let var = label_sigma(&cfg).unwrap().drift_std.powi(2);
            let without = label_sigma(&LabelConfig {
                alignment: None,
                ..cfg.clone()
            })
            .unwrap()
            .drift_std
            .powi(2);
            // Within 4 standard errors of a variance of 1000 zero-mean Gaussian draws (sqrt(2 / N) relative),
            // and the alignment's part more than that (the check fails without it).
            let se = var * (2.0 / runs as f64).sqrt();
            assert!((var_mc - var).abs() < 4.0 * se, "slow {slow}: {var_mc} vs {var}");
            assert!(var - without > 4.0 * se, "slow {slow}: {var} vs {without}");
        }
    }

    #[test]
    fn a_noise_free_run_has_no_label_error() {
        let cfg = LabelConfig {
            navigation: FreeNavigation::white(40.0 * DEG, 8.0 * HOUR, 60.0, 0.0, 0.0),
            ..config(false)
        };
        assert_eq!(label_sigma(&cfg).unwrap().drift_std, 0.0);
    }

    #[test]
    fn an_alignment_that_ends_before_its_first_update_is_refused_by_key() {
        let mut cfg = config(false);
        cfg.alignment.as_mut().unwrap().end_s = 300.5;
        assert_eq!(label_sigma(&cfg).unwrap_err().key(), "alignment_end_s");
        let mut cfg = config(true);
        cfg.rrw_start_s = 2.0 * HOUR;
        assert_eq!(label_sigma(&cfg).unwrap_err().key(), "rrw_start_s");
    }
}
