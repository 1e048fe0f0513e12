//! Covariance analysis for planning a static identification (`gyrodrift plan`), with no IMU samples.
//!
//! [`drift_std_curve`]: how well the full-information smoother of [`crate::smoother`] knows the axial drift after a
//! span from the first sample. The same error model, priors, measurements (zero velocity and the known position
//! every `update_s`) and coarse-alignment start as the smoother, run as a Riccati recursion alone: the covariance of
//! a Kalman filter does not depend on the data, and the smoother's reported end drift (`drift_end_std`, what it
//! carries into navigation: eps_z + b_rrw,z, the Gauss-Markov state b_gm,z left out) is its filter's at the last
//! update. So one forward pass gives the smoother's 1-sigma at every span at once (each span taken at the first
//! update at or after it: the update grid is `coarse_s + k update_s`). The attitude is the simulator's
//! C_b^n(t) = C_b0^n Rz(alpha(t)), alpha the table angle of the rotation scheme (the navigator's attitude error is
//! arcseconds: first order),
//! averaged over each update interval at the sample rate as the smoother averages its navigator's. The thermal
//! state is not part of it (the planner adds the thermal term apart; `thermal` must be off).
//!
//! The same pass gives the covariance of the drift error with the mission's floor, the 72 h error the mission would
//! have with the exact drift. The mission navigates freely from the end of the fine alignment (`mission_start_s`),
//! starting from the aligner's attitude and velocity: its error y starts as the aligner's leftover errors (attitude
//! and velocity; the horizontal sensor biases it leaves are modulated away by the table and left out) and then
//! grows with the noise. Both the aligner's leftovers and the smoother's drift error come from the same data: the
//! same initial errors after the one coarse alignment, the same gyro and accelerometer noise over the hours both
//! filters run, and after the alignment the same noise drives the smoother's error and the mission's. The aligner
//! is taken as the filter it is (`aligner`: its prior, noise model, 1 s zero-velocity updates, from the end of the
//! coarse span to the mission's start) on the smoother's error model, and the truth as the smoother's model with
//! the given noise and the aligner's prior (the navigation-grade biases, which the smoother's wide prior bounds);
//! the aligner's pass is [`crate::aligner_covariance`]'s, which the label's sigma shares. Carried jointly, every
//! aligner step (x~ the errors, true minus estimate, K the filters' own gains):
//!
//! - the aligner's true error covariance A <- (I - K_a H_a)(Phi A Phi' + Q)(I - K_a H_a)' + K_a R K_a' (R the
//!   truth's zero-velocity noise, the smoother's; the aligner's gain is from its own Riccati pass);
//! - J = E[x~_s x~_a'] <- (Phi J Phi' + Q)(I - K_a H_a)', and (I - K_s H_s) J at each smoother update (the two
//!   filters' zero-velocity noise taken independent);
//!
//! then at the mission's start y0 = E x~_a (attitude and velocity), E[x~_s y'] = J E' is carried as Phi C Phi' + Q
//! (the mission and the smoother's error share the noise) and (I - K_s H_s) C at each update, and E[y y'] freely to
//! the mission's end (`alignment_cov`: the part of the floor from y0). A span that ends before the mission starts
//! carries E[x~_a (a'x~_s)] on through the aligner's steps (no new shared noise) to the start. Each span's `cross`
//! = E[(d - d_hat) p_end] (north, east), p_end the floor's position error at the mission's end (the noise's part,
//! [`mission_covariance`], and the alignment's).
//!
//! [`mission_covariance`]: the north/east position error after a free navigation of `span_s` (72 h) from the
//! smoother's error model with no measurements: its covariance from the angle and velocity random walks and the
//! initial attitude and velocity errors, and the deterministic response g to a unit z drift (the level body: the
//! axial column of C_b^n is Up whatever the table does; the horizontal sensor biases are modulated away by the
//! table and left out). With an identified drift of 1-sigma s, the error after compensation is the Gaussian with
//! covariance `pos_cov + alignment_cov + s^2 g g' + g c' + c g'`, c the `cross` of [`drift_std_curve`].

use crate::aligner_covariance::{aligner_on_smoother_model, navigation_start_selector, AlignerPass, TableAttitude};
use crate::attitude::{Euler, Mat3};
use crate::error::{check, CoreError};
use crate::filter_prior::FilterSettings;
use crate::kalman::EPS;
use crate::label::FreeNavigation;
use crate::smoother::model::{initial_sigma, measurement_model, symmetrise, Model};
use crate::smoother::{SmootherConfig, POS};
use crate::turntable::RotationScheme;
use nalgebra::{DMatrix, DVector};

/// Settings of [`drift_std_curve`] (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanConfig {
    /// The smoother's settings (site, sample rate, coarse span, update interval, priors, noise); its `span_s` is
    /// the longest span asked for (the smoother's limits apply to it); `thermal` must be false.
    pub smoother: SmootherConfig,
    /// The fine alignment's filter settings (its prior, noise model and update interval; the procedure's aligner
    /// runs on [`FilterSettings::aligner`]); its coarse span must be the smoother's (one coarse alignment).
    pub aligner: FilterSettings,
    /// The table's rotation scheme and the IMU's attitude at table angle zero.
    pub scheme: RotationScheme,
    pub attitude: Euler,
    /// Spans from the first sample \[s\], ascending, each after the first update and at most `smoother.span_s`.
    pub spans_s: Vec<f64>,
    /// Start of the mission's free navigation from the first sample \[s\] (the end of the fine alignment, 4 h;
    /// taken at the smoother's update nearest to it) and its length \[s\] (72 h); the mission must end after the
    /// longest span.
    pub mission_start_s: f64,
    pub mission_s: f64,
}

/// What [`drift_std_curve`] gives.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftCurve {
    /// 1-sigma of the z drift carried into navigation at each span [rad/s].
    pub drift_std: Vec<f64>,
    /// At each span, E[(d - d_hat) p] [rad/s m], p the north, east position error at the mission's end with the
    /// exact drift (the mission's floor: the noise's part and the aligner's leftovers').
    pub cross: Vec<[f64; 2]>,
    /// Covariance of the floor's part from the aligner's leftover attitude and velocity errors at the mission's
    /// end \[m^2\] (north, east); the noise's part is [`mission_covariance`]'s.
    pub alignment_cov: [[f64; 2]; 2],
}

/// The north and east rows of the free (no measurement) transition of the mission's error (level body) over any
/// span: E' Phi(60 s)^m tabulated as far as asked, times Phi of the rest of the span (Phi = exp(F t): the same
/// transition as `ceil(t / 60)` equal steps, to rounding).
struct FreeRows<'a> {
    model: &'a Model,
    step: DMatrix<f64>,
    /// E' Phi(60 s)^m for m = 0, 1, ... (2 x n each).
    table: Vec<DMatrix<f64>>,
}

impl<'a> FreeRows<'a> {
    const LEVEL: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    fn new(model: &'a Model) -> Self {
        let (step, _) = model.discretise(&Self::LEVEL, 0.0, MISSION_STEP_S);
        let rows = DMatrix::identity(model.n, model.n).rows(POS, 2).into_owned();
        FreeRows {
            model,
            step,
            table: vec![rows],
        }
    }

    /// The rows (north, east; 2 x n) of the free transition over `t` \[s\] (0 for t <= 0).
    fn over(&mut self, t: f64) -> DMatrix<f64> {
        let t = t.max(0.0);
        let whole = (t / MISSION_STEP_S).floor() as usize;
        while self.table.len() <= whole {
            let next = self.table.last().expect("the table starts with E'") * &self.step;
            self.table.push(next);
        }
        let rest = t - whole as f64 * MISSION_STEP_S;
        if rest > 0.0 {
            &self.table[whole] * self.model.discretise(&Self::LEVEL, 0.0, rest).0
        } else {
            self.table[whole].clone()
        }
    }
}

/// The smoother's 1-sigma of the z drift carried into navigation at each of `cfg.spans_s`, and its covariance with
/// the mission's floor (module docs).
pub fn drift_std_curve(cfg: &PlanConfig) -> Result<DriftCurve, CoreError> {
    let sc = &cfg.smoother;
    sc.validate()?;
    cfg.aligner.validate(sc.rate_hz)?;
    check(
        !sc.thermal,
        "thermal",
        "the planner has no thermal state (the thermal term is added apart)",
    )?;
    check(
        cfg.aligner.coarse_s == sc.coarse_s,
        "aligner",
        format!(
            "the aligner's coarse span ({} s) must be the smoother's ({} s): one coarse alignment",
            cfg.aligner.coarse_s, sc.coarse_s
        ),
    )?;
    let attitude = TableAttitude::new(&cfg.scheme, cfg.attitude, sc.rate_hz)?;
    let rate = sc.rate_hz;
    let n_coarse = (sc.coarse_s * rate).round() as u64;
    let n_update = ((sc.update_s * rate).round() as u64).max(1);
    let n_align_update = ((cfg.aligner.update_s * rate).round() as u64).max(1);
    let t_first = (n_coarse + n_update) as f64 / rate;
    check(!cfg.spans_s.is_empty(), "spans_s", "no span given")?;
    let mut last = f64::NEG_INFINITY;
    for &s in &cfg.spans_s {
        check(
            s.is_finite() && s >= t_first && s <= sc.span_s * (1.0 + 1e-12) && s > last,
            "spans_s",
            format!(
                "spans must ascend within [{t_first} s, {} s] (the first update to the smoother's span), got {s}",
                sc.span_s
            ),
        )?;
        last = s;
    }
    check(
        cfg.mission_start_s.is_finite() && cfg.mission_start_s >= t_first,
        "mission_start_s",
        format!("must be a finite time >= the first update ({t_first} s): the alignment ends there at the earliest"),
    )?;
    check(
        cfg.mission_s.is_finite() && cfg.mission_s >= 60.0 && cfg.mission_start_s + cfg.mission_s >= last,
        "mission_s",
        format!("the mission must last >= 60 s and end after the longest span ({last} s)"),
    )?;
    let model = Model::new(sc);
    let n = model.n;
    let (h, r) = measurement_model(sc, n);
    let mut p = DMatrix::from_diagonal(&DVector::from_iterator(
        n,
        initial_sigma(sc, n_coarse as f64 / rate).iter().map(|s| s * s),
    ));
    // The aligner on the smoother's model (its prior, noise and update interval; the same slow-bias states), the
    // truth from its prior.
    let coarse_end_s = n_coarse as f64 / rate;
    let acfg = aligner_on_smoother_model(sc, &cfg.aligner);
    let prior = DMatrix::from_diagonal(&DVector::from_iterator(
        n,
        initial_sigma(&acfg, coarse_end_s).iter().map(|s| s * s),
    ));
    let mut aligner = AlignerPass::new(sc, &cfg.aligner, coarse_end_s, prior)?;
    // The mission starts at the smoother's update nearest to `mission_start_s` (the update grid's k).
    let k_start =
        n_coarse + ((cfg.mission_start_s * rate - n_coarse as f64) / n_update as f64).round() as u64 * n_update;
    let mission_end = cfg.mission_start_s + cfg.mission_s;
    // Selector of the z drift carried into navigation: eps_z + rrw_z, the Gauss-Markov state left out as the
    // smoother leaves it out of `drift_end` (its value at the span's end is forgotten within a few correlation times).
    let mut a = DVector::zeros(n);
    a[EPS + 2] = 1.0;
    if let Some(r) = model.rrw {
        a[r + 2] = 1.0;
    }
    let identity = DMatrix::<f64>::identity(n, n);
    let select = navigation_start_selector(n);
    // E[x~_s y'] once the mission runs (module docs).
    let mut cross: Option<DMatrix<f64>> = None;
    let mut free_rows = FreeRows::new(&model);
    let mut out = DriftCurve {
        drift_std: Vec::with_capacity(cfg.spans_s.len()),
        cross: vec![[0.0; 2]; cfg.spans_s.len()],
        alignment_cov: [[0.0; 2]; 2],
    };
    let mut k = n_coarse;
    let mut next_span = 0;
    while next_span < cfg.spans_s.len() || k < k_start {
        // The aligner's steps over this interval while the alignment runs.
        if k < k_start {
            aligner.advance(&attitude, k, k + n_update, n_align_update, &model)?;
        }
        // One smoother update interval: the mean attitude over its samples (each at the end of its sample).
        let (phi, q) = model.discretise(&attitude.mean(k, k + n_update), 0.0, n_update as f64 / rate);
        k += n_update;
        p = symmetrise(&phi * &p * phi.transpose() + &q);
        if let Some(c) = cross.as_mut() {
            *c = &phi * &*c * phi.transpose() + &q;
        }
        let s_inv = (&h * &p * h.transpose() + &r).try_inverse().ok_or(CoreError::Setting {
            key: "update_s",
            message: "the planner's innovation covariance is singular".to_string(),
        })?;
        let gain = &p * h.transpose() * s_inv;
        let i_kh = &identity - &gain * &h;
        p = symmetrise(&i_kh * &p * i_kh.transpose() + &gain * &r * gain.transpose());
        if k <= k_start {
            aligner.joint = &i_kh * &aligner.joint;
        }
        if let Some(c) = cross.as_mut() {
            *c = &i_kh * &*c;
        }
        if k == k_start {
            // The mission starts from the aligner's leftovers y0 = E x~_a.
            cross = Some(&aligner.joint * &select);
            let to_end = free_rows.over(cfg.mission_s) * &select;
            let floor = &to_end * &aligner.truth * to_end.transpose();
            out.alignment_cov = [[floor[(0, 0)], floor[(0, 1)]], [floor[(1, 0)], floor[(1, 1)]]];
            for (i, u) in aligner.pending.drain(..) {
                let v = &to_end * u;
                out.cross[i] = [v[0], v[1]];
            }
        }
        let t = k as f64 / rate;
        while next_span < cfg.spans_s.len() && t >= cfg.spans_s[next_span] - 1e-9 {
            out.drift_std.push(a.dot(&(&p * &a)).max(0.0).sqrt());
            match cross.as_ref() {
                // E[y a'x~] carried freely to the mission's end.
                Some(c) => {
                    let u = free_rows.over(mission_end - t) * (c.transpose() * &a);
                    out.cross[next_span] = [u[0], u[1]];
                }
                None => aligner.pending.push((next_span, aligner.joint.transpose() * &a)),
            }
            next_span += 1;
        }
    }
    Ok(out)
}

/// Step of the free propagations \[s\].
const MISSION_STEP_S: f64 = 60.0;

/// The position error at the end of a free navigation ([`mission_covariance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MissionCovariance {
    /// Covariance of the north and east position errors from the noise and the initial errors \[m^2\]
    /// (row/column order north, east).
    pub pos_cov: [[f64; 2]; 2],
    /// Position error north, east per unit of uncompensated z drift [m per rad/s] (computed minus true; a drift
    /// error d moves the position by d times this).
    pub response: [f64; 2],
}

/// The north/east position error after `span_s` of free navigation (module docs).
pub fn mission_covariance(cfg: &FreeNavigation) -> Result<MissionCovariance, CoreError> {
    cfg.validate("propagation step")?;
    let sc = cfg.smoother_config();
    let model = Model::new(&sc);
    let n = model.n;
    let level: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let (phi, q) = model.discretise(&level, 0.0, cfg.step_s);
    let mut p = DMatrix::zeros(n, n);
    for i in 0..3 {
        p[(i, i)] = cfg.att_sigma[i] * cfg.att_sigma[i];
    }
    for i in 3..5 {
        p[(i, i)] = cfg.vel_sigma * cfg.vel_sigma;
    }
    let mut g = DVector::zeros(n);
    g[EPS + 2] = 1.0;
    let steps = (cfg.span_s / cfg.step_s).round().max(1.0) as usize;
    for _ in 0..steps {
        g = &phi * g;
        p = symmetrise(&phi * &p * phi.transpose() + &q);
    }
    let pos_cov = [
        [p[(POS, POS)], p[(POS, POS + 1)]],
        [p[(POS + 1, POS)], p[(POS + 1, POS + 1)]],
    ];
    check(
        pos_cov.iter().flatten().all(|x| x.is_finite()) && g[POS].is_finite() && g[POS + 1].is_finite(),
        "lat_rad",
        "the mission covariance is not finite",
    )?;
    Ok(MissionCovariance {
        pos_cov,
        response: [g[POS], g[POS + 1]],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{euler_to_dcm, mat_mul, rot_z};
    use crate::earth::OMEGA_IE;
    use crate::smoother::Smoother;
    use crate::turntable::scheme_from_settings;
    use crate::turntable::Turntable;
    use crate::units::{DEG_PER_H, HOUR};

    fn plan_config(lat_deg: f64, spans_h: &[f64]) -> PlanConfig {
        let mut sc = SmootherConfig::new(lat_deg.to_radians(), 0.0, 0.0, 10.0);
        sc.span_s = 86_400.0;
        PlanConfig {
            smoother: sc,
            aligner: FilterSettings::aligner(),
            scheme: scheme_from_settings("reciprocating", None, None, None, false, None, None).unwrap(),
            attitude: Euler {
                pitch: 0.0,
                roll: 0.0,
                yaw: 0.0,
            },
            spans_s: spans_h.iter().map(|h| h * HOUR).collect(),
            mission_start_s: 4.0 * HOUR,
            mission_s: 72.0 * HOUR,
        }
    }

    #[test]
    fn the_drift_sigma_falls_with_the_span() {
        let s = drift_std_curve(&plan_config(40.0, &[6.0, 10.0, 16.0, 24.0]))
            .unwrap()
            .drift_std;
        assert!(s.windows(2).all(|w| w[1] < w[0]), "{s:?}");
        // Between the alignment-only 2e-3 deg/h of method.md and zero; 16 h near the 1.9e-4 deg/h.
        let s16 = s[2] / DEG_PER_H;
        assert!((1.2e-4..3.0e-4).contains(&s16), "{s16}");
    }

    #[test]
    fn the_planner_matches_the_smoother_on_a_noise_free_log() {
        // The smoother's reported sigma does not depend on the data (a Kalman covariance): a noise-free log of the
        // simulator with the same scheme and attitude gives the same 1-sigma as the planner's Riccati pass.
        use crate::simulator::{ImuSimulator, ImuSimulatorConfig};
        let mut cfg = plan_config(40.0, &[2.0]);
        cfg.smoother.rate_hz = 5.0;
        cfg.smoother.span_s = 7200.0;
        let planned = drift_std_curve(&cfg).unwrap().drift_std[0];
        let sim_cfg = ImuSimulatorConfig {
            lat: cfg.smoother.lat,
            rate_hz: 5.0,
            duration_s: 7200.0,
            scheme: cfg.scheme.clone(),
            attitude: cfg.attitude,
            ..ImuSimulatorConfig::default()
        };
        let mut sim = ImuSimulator::new(sim_cfg).unwrap();
        let mut chunk = crate::simulator::ImuChunk::default();
        assert_eq!(sim.next_chunk(36_000, &mut chunk), 36_000);
        let mut sm = Smoother::new(cfg.smoother.clone()).unwrap();
        sm.process(&chunk.dtheta, &chunk.dv, None).unwrap();
        let got = sm.result().unwrap().drift_end_std;
        assert!((planned / got - 1.0).abs() < 0.01, "planned {planned}, smoother {got}");
    }

    /// Brute force for `the_cross_terms_match_a_monte_carlo_of_the_linear_model`: `runs` draws of the linear error
    /// model at 1 Hz (the truth from the aligner's prior, its noise the smoother's Q sampled as
    /// sqrt(t/2) (Phi Lc z1 + Lc z2)), the aligner and the smoother run as Kalman filters on simulated
    /// measurements, the mission navigated from the aligner's leftovers (attitude, velocity) with the truth's noise;
    /// returns the drift errors a'(x - x_hat_s) at each span and the mission's north, east error at its end.
    fn monte_carlo(cfg: &PlanConfig, runs: usize, seed: u64) -> (Vec<DMatrix<f64>>, DMatrix<f64>) {
        use rand_core::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let sc = &cfg.smoother;
        assert_eq!(sc.rate_hz, 1.0);
        let model = Model::new(sc);
        let acfg = aligner_on_smoother_model(sc, &cfg.aligner);
        let amodel = Model::new(&acfg);
        let n = model.n;
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let mut normal = |r: usize| DMatrix::<f64>::from_fn(r, runs, |_, _| StandardNormal.sample(&mut rng));
        let lc = DMatrix::from_diagonal(&model.qc.map(f64::sqrt));
        let table = Turntable::new(cfg.scheme.clone()).unwrap();
        let c0 = euler_to_dcm(cfg.attitude);
        let at = |k: u64| mat_mul(&c0, &rot_z(table.angle(k as f64)));
        let (h, r) = measurement_model(sc, n);
        let hv = h.rows(0, 3).into_owned();
        let coarse = sc.coarse_s as u64;
        let prior = |c: &SmootherConfig| DVector::from_vec(initial_sigma(c, sc.coarse_s));
        let mut x = DMatrix::from_diagonal(&prior(&acfg)) * normal(n);
        let (mut xa, mut xs) = (DMatrix::zeros(n, runs), DMatrix::zeros(n, runs));
        let mut pa = DMatrix::from_diagonal(&prior(&acfg).map(|s| s * s));
        let mut ps = DMatrix::from_diagonal(&prior(sc).map(|s| s * s));
        let start = cfg.mission_start_s as u64;
        let last = *cfg.spans_s.last().unwrap() as u64;
        let mut y: Option<DMatrix<f64>> = None;
        let mut deltas = Vec::new();
        let mut a = DVector::zeros(n);
        a[EPS + 2] = 1.0;
        let kalman =
            |p: &mut DMatrix<f64>, est: &mut DMatrix<f64>, z: DMatrix<f64>, h: &DMatrix<f64>, r: &DMatrix<f64>| {
                let gain = &*p * h.transpose() * (h * &*p * h.transpose() + r).try_inverse().unwrap();
                *est += &gain * (z - h * &*est);
                let i_kh = DMatrix::identity(n, n) - &gain * h;
                *p = &i_kh * &*p * i_kh.transpose() + &gain * r * gain.transpose();
            };
        for k in coarse + 1..=last.max(start) {
            let (phi, _) = model.discretise(&at(k), 0.0, 1.0);
            let w = (&phi * &lc * normal(n) + &lc * normal(n)) * 0.5f64.sqrt();
            x = &phi * &x + &w;
            if let Some(y) = y.as_mut() {
                *y = &phi * &*y + &w;
            }
            if k <= start {
                let (_, qa) = amodel.discretise(&at(k), 0.0, 1.0);
                xa = &phi * &xa;
                pa = &phi * &pa * phi.transpose() + qa;
                let z = &hv * &x + normal(3) * sc.zupt_sigma;
                let ra = DMatrix::from_diagonal_element(3, 3, cfg.aligner.zupt_sigma.powi(2));
                kalman(&mut pa, &mut xa, z, &hv, &ra);
            }
            if k == start {
                y = Some(navigation_start_selector(n) * (&x - &xa));
            }
            if (k - coarse) % 10 == 0 {
                let mut cm: Mat3 = [[0.0; 3]; 3];
                for j in k - 9..=k {
                    let c = at(j);
                    for (i, row) in cm.iter_mut().enumerate() {
                        for (jj, v) in row.iter_mut().enumerate() {
                            *v += c[i][jj] / 10.0;
                        }
                    }
                }
                let (phi10, q10) = model.discretise(&cm, 0.0, 10.0);
                xs = &phi10 * &xs;
                ps = &phi10 * &ps * phi10.transpose() + q10;
                let noise = DMatrix::from_diagonal(&r.diagonal().map(f64::sqrt)) * normal(5);
                kalman(&mut ps, &mut xs, &h * &x + noise, &h, &r);
                if cfg.spans_s.iter().any(|&s| s as u64 == k) {
                    let d = a.transpose() * (&x - &xs);
                    deltas.push(DMatrix::from_iterator(1, runs, d.iter().copied()));
                }
            }
        }
        // The rest of the mission, free (level body; its bias states are zero).
        let level: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let (phi, _) = model.discretise(&level, 0.0, 60.0);
        let mut y = y.unwrap();
        let steps = ((cfg.mission_start_s + cfg.mission_s - last.max(start) as f64) / 60.0).round() as usize;
        for _ in 0..steps {
            y = &phi * &y + (&phi * &lc * normal(n) + &lc * normal(n)) * 30f64.sqrt();
        }
        (deltas, y.rows(POS, 2).into_owned())
    }

    #[test]
    fn the_cross_terms_match_a_monte_carlo_of_the_linear_model() {
        // One span before the mission starts (the aligner's leftovers only), one after (and the shared noise).
        let mut cfg = plan_config(40.0, &[1.0, 2.0]);
        cfg.smoother.rate_hz = 1.0;
        cfg.smoother.span_s = 2.0 * HOUR;
        cfg.mission_start_s = 1.5 * HOUR;
        cfg.mission_s = 6.0 * HOUR;
        let curve = drift_std_curve(&cfg).unwrap();
        let m = mission_covariance(&FreeNavigation::white(
            cfg.smoother.lat,
            cfg.mission_s,
            60.0,
            cfg.smoother.gyro_arw,
            cfg.smoother.accel_vrw,
        ))
        .unwrap();
        let runs = 400;
        let (deltas, p) = monte_carlo(&cfg, runs, 11);
        let mean = |v: &DMatrix<f64>| v.sum() / runs as f64;
        let cov = |u: &DMatrix<f64>, v: &DMatrix<f64>| {
            (u.add_scalar(-mean(u))).component_mul(&v.add_scalar(-mean(v))).sum() / (runs - 1) as f64
        };
        for axis in 0..2 {
            let pa = p.rows(axis, 1).into_owned();
            let floor = m.pos_cov[axis][axis] + curve.alignment_cov[axis][axis];
            let var_p = cov(&pa, &pa);
            // The floor's variance within 4 standard errors (sqrt(2 / N) relative), and the alignment's part
            // more than that (so the check can fail without it).
            let se = floor * (2.0 / runs as f64).sqrt();
            assert!((var_p - floor).abs() < 4.0 * se, "axis {axis}: {var_p} vs {floor}");
            for (i, d) in deltas.iter().enumerate() {
                let (c_mc, c_plan) = (cov(d, &pa), curve.cross[i][axis]);
                let se = ((cov(d, d) * var_p + c_mc * c_mc) / runs as f64).sqrt();
                assert!(
                    (c_mc - c_plan).abs() < 4.0 * se,
                    "span {i} axis {axis}: {c_mc} vs {c_plan} (se {se})"
                );
            }
        }
        // The alignment's leftovers matter here: the span before the mission has a cross term of its own.
        let c = curve.cross[0][1];
        let s = curve.drift_std[0];
        let floor = (m.pos_cov[1][1] + curve.alignment_cov[1][1]).sqrt();
        assert!(c.abs() > 0.05 * s * floor && c.abs() < s * floor, "{c} {s} {floor}");
    }

    #[test]
    fn the_tabulated_free_rows_match_the_dense_transition() {
        // The definition: the whole transition in ceil(t / 60 s) equal steps, its north and east rows.
        let model = Model::new(&plan_config(40.0, &[6.0]).smoother);
        let level: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let dense = |t: f64| {
            let steps = (t / MISSION_STEP_S).ceil() as usize;
            let mut out = DMatrix::identity(model.n, model.n);
            if steps > 0 {
                let (phi, _) = model.discretise(&level, 0.0, t / steps as f64);
                for _ in 0..steps {
                    out = &phi * out;
                }
            }
            out.rows(POS, 2).into_owned()
        };
        let mut rows = FreeRows::new(&model);
        for t in [0.0, 37.0, 60.0, 3_605.0, 250_000.0, 76.0 * HOUR + 5.0, 1_000.0] {
            let (fast, slow) = (rows.over(t), dense(t));
            // Column by column (each state's own unit), relative to the column's size.
            for (f, d) in fast.column_iter().zip(slow.column_iter()) {
                let gap = (f - d).abs().max();
                assert!(gap <= 1e-10 * d.abs().max(), "t = {t} s: {f} vs {d}");
            }
        }
    }

    #[test]
    fn bad_spans_are_refused_by_key() {
        for spans in [vec![], vec![10.0, 6.0], vec![30.0], vec![0.01]] {
            let e = drift_std_curve(&plan_config(40.0, &spans)).unwrap_err();
            assert!(e.to_string().contains("spans_s"), "{e}");
        }
    }

    #[test]
    fn the_mission_response_follows_the_closed_forms() {
        // dL(t) = (eps cos L / w)(1 - cos w t), dlon(t) = eps sin L (t - sin(w t) / w), Schuler terms aside.
        let lat = 40f64.to_radians();
        let cfg = FreeNavigation::white(lat, 72.0 * HOUR, 60.0, 0.0, 0.0);
        let m = mission_covariance(&cfg).unwrap();
        let t = cfg.span_s;
        let w = OMEGA_IE;
        let rm = crate::earth::meridian_radius(lat);
        let rn = crate::earth::transverse_radius(lat);
        let north = rm * lat.cos() / w * (1.0 - (w * t).cos());
        let east = rn * lat.cos() * lat.sin() * (t - (w * t).sin() / w);
        let scale = north.hypot(east);
        // Computed minus true for a drift in the gyro output: the errors of the closed forms with their sign.
        assert!(
            (m.response[0] - north).abs() < 0.01 * scale,
            "{} {north}",
            m.response[0]
        );
        assert!((m.response[1] - east).abs() < 0.01 * scale, "{} {east}", m.response[1]);
        assert_eq!(m.pos_cov, [[0.0; 2]; 2]);
    }
}
