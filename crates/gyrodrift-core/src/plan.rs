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
//! The z gyro's slow bias (the smoother's Gauss-Markov state b and rate random walk r, when its settings have them)
//! drives the mission too: the drift carried, d = eps_z + r_z at the span's end, leaves b out, and r walks on. The
//! mission's error y has b_z as the truth's own (stationary, and the same noise), and r_z as W, the walk since the
//! mission's start; the x and y slow biases are modulated away by the table and left out (the noise the mission
//! shares is Q M, M zeroing their columns). So y0 = S x~_a + b_z e_b: E[x~_s y0'] gains E[x~_s b_z] in b's
//! column (carried from the common start, E[x~_s b] <- phi_b Phi E[x~_s b] + Q e_b, (I - K_s H_s) at the
//! updates), the floor gains the covariance of the aligner's leftovers with b_z (r g_b' + g_b r', r the leftovers'
//! part E[y0 b_z] = S E[x~_a b_z] carried to the end, from a second aligner pass whose J is E[x x~_a'], no
//! smoother updates), and a span before the mission's start adds E[a'x~_s b_z] decayed to the start. The mission
//! compensates d, not eps_z + r_z at its start: the floor relative to d is F = F_0 - g W(S), F_0 the floor from
//! the start ([`mission_covariance`]'s, with W), so `cross` takes away g E[a'x~_s W(S)] and `walk_cov` =
//! g g' E[W^2] - g b' - b g' (b = E[F_0 W(S)], from E[y W] <- Phi E[y W] + M Q e_W since the start) joins the
//! floor. With a random walk every span must end after the mission's start (the walk between a span's end and
//! the start would be shared with the aligner's leftovers: not carried).
//!
//! [`mission_covariance`]: the north/east position error after a free navigation of `span_s` (72 h) from the
//! smoother's error model with no measurements: its covariance from the angle and velocity random walks, the z
//! gyro's slow bias (the Gauss-Markov state stationary at the start, independent of the initial errors; the rate
//! random walk from zero: the drift taken at the start) and the initial attitude and velocity errors, and the
//! deterministic response g to a unit z drift (the level body: the axial column of C_b^n is Up whatever the table
//! does; the horizontal sensor biases, slow ones included, are modulated away by the table and left out). With an
//! identified drift of 1-sigma s, the error after compensation is the Gaussian with covariance
//! `pos_cov + alignment_cov + walk_cov + s^2 g g' + g c' + c g'`, c the `cross` of [`drift_std_curve`].

use crate::aligner_covariance::{aligner_on_smoother_model, navigation_start_selector, AlignerPass, TableAttitude};
use crate::attitude::{Euler, Mat3};
use crate::error::{check, check_with, CoreError};
use crate::filter_prior::FilterSettings;
use crate::kalman::EPS;
use crate::label::{FreeNavigation, SlowBias};
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
    /// end \[m^2\] (north, east), with their covariance with the Gauss-Markov z bias at the mission's start; the
    /// noise's part is [`mission_covariance`]'s.
    pub alignment_cov: [[f64; 2]; 2],
    /// At each span, the floor's part from the z rate random walk's value at the span's end \[m^2\] (north,
    /// east; zero without one): [`mission_covariance`] takes the drift at the mission's start, the smoother
    /// carries it at the span's end (module docs).
    pub walk_cov: Vec<[[f64; 2]; 2]>,
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
    check_with(cfg.aligner.coarse_s == sc.coarse_s, "aligner", || {
        format!(
            "the aligner's coarse span ({} s) must be the smoother's ({} s): one coarse alignment",
            cfg.aligner.coarse_s, sc.coarse_s
        )
    })?;
    let attitude = TableAttitude::new(&cfg.scheme, cfg.attitude, sc.rate_hz)?;
    let rate = sc.rate_hz;
    let n_coarse = (sc.coarse_s * rate).round() as u64;
    let n_update = ((sc.update_s * rate).round() as u64).max(1);
    let n_align_update = ((cfg.aligner.update_s * rate).round() as u64).max(1);
    let t_first = (n_coarse + n_update) as f64 / rate;
    check(!cfg.spans_s.is_empty(), "spans_s", "no span given")?;
    let mut last = f64::NEG_INFINITY;
    for &s in &cfg.spans_s {
        check_with(
            s.is_finite() && s >= t_first && s <= sc.span_s * (1.0 + 1e-12) && s > last,
            "spans_s",
            || {
                format!(
                    "spans must ascend within [{t_first} s, {} s] (the first update to the smoother's span), got {s}",
                    sc.span_s
                )
            },
        )?;
        last = s;
    }
    check_with(
        cfg.mission_start_s.is_finite() && cfg.mission_start_s >= t_first,
        "mission_start_s",
        || format!("must be a finite time >= the first update ({t_first} s): the alignment ends there at the earliest"),
    )?;
    check_with(
        cfg.mission_s.is_finite() && cfg.mission_s >= 60.0 && cfg.mission_start_s + cfg.mission_s >= last,
        "mission_s",
        || format!("the mission must last >= 60 s and end after the longest span ({last} s)"),
    )?;
    let model = Model::new(sc);
    let n = model.n;
    // The z gyro's Gauss-Markov and random-walk states, and the x and y ones the mission leaves out (module docs).
    let gz = model.gm.map(|g| g + 2);
    let rz = model.rrw.map(|r| r + 2);
    let horizontal: Vec<usize> = [model.gm, model.rrw]
        .into_iter()
        .flatten()
        .flat_map(|f| [f, f + 1])
        .collect();
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
    // With a Gauss-Markov bias: E[x~_s b] (b its z state, the truth's; from the common start, E[x0 x0'] = prior)
    // and a second aligner pass whose J is E[x x~_a'] (the truth itself: no smoother updates).
    let mut gm_smoother = gz.map(|g| prior.column(g).into_owned());
    let mut gm_aligner = match gz {
        Some(_) => Some(AlignerPass::new(sc, &cfg.aligner, coarse_end_s, prior.clone())?),
        None => None,
    };
    let mut aligner = AlignerPass::new(sc, &cfg.aligner, coarse_end_s, prior)?;
    // The mission starts at the smoother's update nearest to `mission_start_s` (the update grid's k).
    let k_start =
        n_coarse + ((cfg.mission_start_s * rate - n_coarse as f64) / n_update as f64).round() as u64 * n_update;
    check_with(
        rz.is_none() || cfg.spans_s[0] >= k_start as f64 / rate - 1e-9,
        "spans_s",
        || {
            format!(
                "with a rate random walk every span must end after the mission starts ({} s), got {} s",
                k_start as f64 / rate,
                cfg.spans_s[0]
            )
        },
    )?;
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
    // E[x~_s y'] once the mission runs, and E[y W] (W the z random walk since the mission's start; module docs).
    let mut cross: Option<DMatrix<f64>> = None;
    let mut walk: Option<DVector<f64>> = None;
    // E[(a'x~_s at a span before the mission's start) b] (the span's index, carried to the start).
    let mut gm_pending: Vec<(usize, f64)> = Vec::new();
    // The north, east response at the mission's end to a unit z drift over the whole mission.
    let mut response = DVector::zeros(2);
    let mut free_rows = FreeRows::new(&model);
    let mut out = DriftCurve {
        drift_std: Vec::with_capacity(cfg.spans_s.len()),
        cross: vec![[0.0; 2]; cfg.spans_s.len()],
        alignment_cov: [[0.0; 2]; 2],
        walk_cov: vec![[[0.0; 2]; 2]; cfg.spans_s.len()],
    };
    let mut k = n_coarse;
    let mut next_span = 0;
    while next_span < cfg.spans_s.len() || k < k_start {
        // The aligner's steps over this interval while the alignment runs.
        if k < k_start {
            aligner.advance(&attitude, k, k + n_update, n_align_update, &model)?;
            if let Some(pass) = gm_aligner.as_mut() {
                pass.advance(&attitude, k, k + n_update, n_align_update, &model)?;
            }
        }
        // One smoother update interval: the mean attitude over its samples (each at the end of its sample).
        let (phi, q) = model.discretise(&attitude.mean(k, k + n_update), 0.0, n_update as f64 / rate);
        k += n_update;
        p = symmetrise(&phi * &p * phi.transpose() + &q);
        // The noise the mission shares, E[w (M w)'] = Q M: the x and y slow biases' columns left out.
        let q_masked = (!horizontal.is_empty()).then(|| {
            let mut m = q.clone();
            for &j in &horizontal {
                m.column_mut(j).fill(0.0);
            }
            m
        });
        let q_mission = q_masked.as_ref().unwrap_or(&q);
        if let Some(c) = cross.as_mut() {
            *c = &phi * &*c * phi.transpose() + q_mission;
        }
        if let (Some(w), Some(r)) = (walk.as_mut(), rz) {
            *w = &phi * &*w + q_mission.row(r).transpose();
        }
        if let (Some(g), None) = (gz, cross.as_ref()) {
            let decay = phi[(g, g)];
            if let Some(u) = gm_smoother.as_mut() {
                *u = &phi * &*u * decay + q.column(g);
            }
            for (_, v) in gm_pending.iter_mut() {
                *v *= decay;
            }
        }
        let s_inv = (&h * &p * h.transpose() + &r)
            .try_inverse()
            .ok_or_else(|| CoreError::Setting {
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
        } else if let Some(u) = gm_smoother.as_mut() {
            *u = &i_kh * &*u;
        }
        if k == k_start {
            // The mission starts from the aligner's leftovers y0 = E x~_a (and the true Gauss-Markov z bias).
            let mut start = &aligner.joint * &select;
            let rows = free_rows.over(cfg.mission_s);
            let to_end = &rows * &select;
            let mut floor = &to_end * &aligner.truth * to_end.transpose();
            for (i, u) in aligner.pending.drain(..) {
                let v = &to_end * u;
                out.cross[i] = [v[0], v[1]];
            }
            if let (Some(g), Some(pass), Some(u)) = (gz, gm_aligner.as_ref(), gm_smoother.as_ref()) {
                // E[x~_s b] joins E[x~_s y0'] in b's column; E[y0 b] = S E[x~_a b] moves the floor by
                // r g_b' + g_b r' (g_b the response to b at the start, r = rows S E[x~_a b]).
                start.column_mut(g).copy_from(u);
                let r = &to_end * pass.joint.row(g).transpose();
                let g_b = rows.column(g);
                floor += &r * g_b.transpose() + g_b * r.transpose();
                for (i, v) in gm_pending.drain(..) {
                    out.cross[i][0] += g_b[0] * v;
                    out.cross[i][1] += g_b[1] * v;
                }
            }
            out.alignment_cov = [[floor[(0, 0)], floor[(0, 1)]], [floor[(1, 0)], floor[(1, 1)]]];
            response = rows.column(EPS + 2).into_owned();
            cross = Some(start);
            walk = rz.map(|_| DVector::zeros(n));
        }
        let t = k as f64 / rate;
        while next_span < cfg.spans_s.len() && t >= cfg.spans_s[next_span] - 1e-9 {
            out.drift_std.push(a.dot(&(&p * &a)).max(0.0).sqrt());
            match cross.as_ref() {
                // E[y a'x~] carried freely to the mission's end.
                Some(c) => {
                    let ca = c.transpose() * &a;
                    let rows = free_rows.over(mission_end - t);
                    let u = &rows * &ca;
                    out.cross[next_span] = [u[0], u[1]];
                    if let (Some(r), Some(w)) = (rz, walk.as_ref()) {
                        // The floor relative to the drift carried (b_rrw,z at the span's end) is the floor from
                        // the mission's start less g W: E[a'x~ F] less g E[a'x~ W], and its covariance moves by
                        // g g' E[W^2] - g b' - b g', b = E[F W].
                        let b = &rows * w;
                        out.cross[next_span][0] -= response[0] * ca[r];
                        out.cross[next_span][1] -= response[1] * ca[r];
                        let extra = &response * response.transpose() * w[r]
                            - &response * b.transpose()
                            - &b * response.transpose();
                        out.walk_cov[next_span] = [[extra[(0, 0)], extra[(0, 1)]], [extra[(1, 0)], extra[(1, 1)]]];
                    }
                }
                None => {
                    aligner.pending.push((next_span, aligner.joint.transpose() * &a));
                    if let Some(u) = gm_smoother.as_ref() {
                        gm_pending.push((next_span, u.dot(&a)));
                    }
                }
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

/// The north/east position error after `span_s` of free navigation with the z gyro's `slow` bias (module docs).
pub fn mission_covariance(cfg: &FreeNavigation, slow: &SlowBias) -> Result<MissionCovariance, CoreError> {
    cfg.validate("propagation step")?;
    slow.validate()?;
    let (_, model) = cfg.model(slow);
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
    // The Gauss-Markov z bias stationary; the random walk from zero (the drift is taken at the mission's start).
    if let Some(g) = model.gm {
        p[(g + 2, g + 2)] = slow.bias_instability * slow.bias_instability;
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

    /// What [`monte_carlo`] draws: per span the drift error a'(x - x_hat_s) and the z random walk since the
    /// mission's start W (1 x runs each), and the mission's north, east error at its end (2 x runs).
    struct Draws {
        deltas: Vec<DMatrix<f64>>,
        walks: Vec<DMatrix<f64>>,
        end: DMatrix<f64>,
    }

    /// Brute force for `the_cross_terms_match_a_monte_carlo_of_the_linear_model`: `runs` draws of the linear error
    /// model at 1 Hz (the truth from the aligner's prior, its noise the smoother's Q sampled as
    /// sqrt(t/2) (Phi Lc z1 + Lc z2)), the aligner and the smoother run as Kalman filters on simulated
    /// measurements, the mission navigated from the aligner's leftovers (attitude, velocity) and the true
    /// Gauss-Markov z bias with the truth's noise (the x and y slow biases' left out), its z random walk from zero.
    fn monte_carlo(cfg: &PlanConfig, runs: usize, seed: u64) -> Draws {
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
        let (mut deltas, mut walks) = (Vec::new(), Vec::new());
        // The mission's share of the noise: the x and y slow biases' rows left out.
        let mask = |mut w: DMatrix<f64>| {
            for f in [model.gm, model.rrw].into_iter().flatten() {
                w.row_mut(f).fill(0.0);
                w.row_mut(f + 1).fill(0.0);
            }
            w
        };
        let mut a = DVector::zeros(n);
        a[EPS + 2] = 1.0;
        if let Some(r) = model.rrw {
            a[r + 2] = 1.0;
        }
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
                *y = &phi * &*y + mask(w.clone());
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
                let mut y0 = navigation_start_selector(n) * (&x - &xa);
                if let Some(g) = model.gm {
                    y0.set_row(g + 2, &x.row(g + 2));
                }
                y = Some(y0);
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
                    walks.push(match (model.rrw, y.as_ref()) {
                        (Some(r), Some(y)) => y.rows(r + 2, 1).into_owned(),
                        _ => DMatrix::zeros(1, runs),
                    });
                }
            }
        }
        // The rest of the mission, free (level body).
        let level: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let (phi, _) = model.discretise(&level, 0.0, 60.0);
        let mut y = y.unwrap();
        let steps = ((cfg.mission_start_s + cfg.mission_s - last.max(start) as f64) / 60.0).round() as usize;
        for _ in 0..steps {
            y = &phi * &y + mask((&phi * &lc * normal(n) + &lc * normal(n)) * 30f64.sqrt());
        }
        Draws {
            deltas,
            walks,
            end: y.rows(POS, 2).into_owned(),
        }
    }

    /// The planner's floor and cross terms against [`monte_carlo`]'s draws (400 runs, 4 standard errors) for the
    /// slow bias `slow` and `spans_h` (a 6 h mission from 1.5 h, 1 Hz); returns the planner's curve and the
    /// mission's covariance.
    fn check_against_monte_carlo(slow: SlowBias, spans_h: &[f64], seed: u64) -> (DriftCurve, MissionCovariance) {
        let mut cfg = plan_config(40.0, spans_h);
        cfg.smoother.rate_hz = 1.0;
        cfg.smoother.span_s = 2.0 * HOUR;
        cfg.smoother.gyro_bias_instability = slow.bias_instability;
        cfg.smoother.gyro_correlation = slow.correlation;
        cfg.smoother.gyro_rrw = slow.rrw;
        cfg.mission_start_s = 1.5 * HOUR;
        cfg.mission_s = 6.0 * HOUR;
        let curve = drift_std_curve(&cfg).unwrap();
        let nav = FreeNavigation::white(
            cfg.smoother.lat,
            cfg.mission_s,
            60.0,
            cfg.smoother.gyro_arw,
            cfg.smoother.accel_vrw,
        );
        let m = mission_covariance(&nav, &slow).unwrap();
        let runs = 400;
        let draws = monte_carlo(&cfg, runs, seed);
        let mean = |v: &DMatrix<f64>| v.sum() / runs as f64;
        let cov = |u: &DMatrix<f64>, v: &DMatrix<f64>| {
            (u.add_scalar(-mean(u))).component_mul(&v.add_scalar(-mean(v))).sum() / (runs - 1) as f64
        };
        for (axis, g) in m.response.iter().enumerate() {
            for (i, (d, w)) in draws.deltas.iter().zip(&draws.walks).enumerate() {
                // The floor relative to the drift carried at this span: the end error less g W.
                let f = draws.end.rows(axis, 1) - w * *g;
                let floor = m.pos_cov[axis][axis] + curve.alignment_cov[axis][axis] + curve.walk_cov[i][axis][axis];
                let var_f = cov(&f, &f);
                // The floor's variance within 4 standard errors (sqrt(2 / N) relative).
                let se = floor * (2.0 / runs as f64).sqrt();
                assert!(
                    (var_f - floor).abs() < 4.0 * se,
                    "span {i} axis {axis}: {var_f} vs {floor}"
                );
                let (c_mc, c_plan) = (cov(d, &f), curve.cross[i][axis]);
                let se = ((cov(d, d) * var_f + c_mc * c_mc) / runs as f64).sqrt();
                assert!(
                    (c_mc - c_plan).abs() < 4.0 * se,
                    "span {i} axis {axis}: {c_mc} vs {c_plan} (se {se})"
                );
            }
        }
        (curve, m)
    }

    #[test]
    fn the_cross_terms_match_a_monte_carlo_of_the_linear_model() {
        // One span before the mission starts (the aligner's leftovers only), one after (and the shared noise).
        let (curve, m) = check_against_monte_carlo(SlowBias::NONE, &[1.0, 2.0], 11);
        // The alignment's leftovers matter here: the span before the mission has a cross term of its own.
        let (c, s) = (curve.cross[0][1], curve.drift_std[0]);
        let floor = (m.pos_cov[1][1] + curve.alignment_cov[1][1]).sqrt();
        assert!(c.abs() > 0.05 * s * floor && c.abs() < s * floor, "{c} {s} {floor}");
        assert_eq!(curve.walk_cov, vec![[[0.0; 2]; 2]; 2]);
    }

    #[test]
    fn the_slow_bias_terms_match_a_monte_carlo_of_the_linear_model() {
        // A Gauss-Markov z bias large beside the white noise (its stationary start, its covariance with the
        // aligner's leftovers and the smoother's drift error; a span before the mission's start too), then with a
        // rate random walk (spans after the start: the floor relative to the walk's value at the span's end).
        let gm = SlowBias {
            bias_instability: 0.01 * DEG_PER_H,
            correlation: 1800.0,
            rrw: 0.0,
        };
        let (_, m) = check_against_monte_carlo(gm, &[1.0, 2.0], 12);
        let walk = SlowBias {
            rrw: 0.01 * DEG_PER_H / HOUR.sqrt(),
            ..gm
        };
        let (curve, m_walk) = check_against_monte_carlo(walk, &[1.75, 2.0], 13);
        // The slow terms move the floor by more than the check's 4 standard errors (sqrt(2 / 400) relative), so
        // it fails without them: the Gauss-Markov bias's part of the floor, the random walk's over the mission
        // (the drift taken at its start) and its part from the walk's value at the span's end.
        let nav = FreeNavigation::white(40f64.to_radians(), 6.0 * HOUR, 60.0, 0.0, 0.0);
        let four_se = 4.0 * (2.0f64 / 400.0).sqrt();
        for axis in 0..2 {
            let white = mission_covariance(&nav, &SlowBias::NONE).unwrap().pos_cov[axis][axis];
            let gm_only = mission_covariance(&nav, &gm).unwrap().pos_cov[axis][axis];
            assert!(
                gm_only - white > four_se * m.pos_cov[axis][axis],
                "axis {axis}: {gm_only} {white}"
            );
            let rrw_part = m_walk.pos_cov[axis][axis] - m.pos_cov[axis][axis];
            assert!(
                rrw_part > four_se * m_walk.pos_cov[axis][axis],
                "axis {axis}: {rrw_part}"
            );
            let floor = m_walk.pos_cov[axis][axis] + curve.alignment_cov[axis][axis] + curve.walk_cov[1][axis][axis];
            assert!(
                -curve.walk_cov[1][axis][axis] > four_se * floor,
                "axis {axis}: {:?}",
                curve.walk_cov[1]
            );
        }
        // A span before the mission's start with a random walk is refused by key.
        let mut cfg = plan_config(40.0, &[1.0, 2.0]);
        cfg.smoother.gyro_rrw = walk.rrw;
        cfg.mission_start_s = 1.5 * HOUR;
        cfg.mission_s = 6.0 * HOUR;
        cfg.smoother.span_s = 2.0 * HOUR;
        assert_eq!(drift_std_curve(&cfg).unwrap_err().key(), "spans_s");
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
        let m = mission_covariance(&cfg, &SlowBias::NONE).unwrap();
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
