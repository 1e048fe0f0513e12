//! Covariance analysis for planning a static identification (`gyrodrift plan`), with no IMU samples.
//!
//! [`drift_std_curve`]: how well the full-information smoother of [`crate::smoother`] knows the axial drift after a
//! span from the first sample. The same error model, priors, measurements (zero velocity and the known position
//! every `update_s`) and coarse-alignment start as the smoother, run as a Riccati recursion alone: the covariance of
//! a Kalman filter does not depend on the data, and the smoother's reported end drift (`drift_end_std`, what it
//! carries into navigation: eps_z + b_gm,z + b_rrw,z) is its filter's at the last update. So one forward pass
//! gives the smoother's 1-sigma at every span at once (each span taken at the first update at or after it: the
//! update grid is `coarse_s + k update_s`). The attitude is the simulator's C_b^n(t) = C_b0^n Rz(alpha(t)),
//! alpha the table angle of the rotation scheme (the navigator's attitude error is arcseconds: first order),
//! averaged over each update interval at the sample rate as the smoother averages its navigator's. The thermal
//! state is not part of it (the planner adds the thermal term apart; `thermal` must be off).
//!
//! The same pass carries the covariance of the drift error with the mission's noise floor. The mission navigates
//! freely from the end of the alignment (`mission_start_s`) while the span may still run: over the hours both
//! cover, the same gyro noise drives the smoother's estimation error x~ (true minus estimate) and the mission's
//! error y. With y started at zero and the same model (its bias states stay zero, so the table does not matter),
//! E[x~ y'] is propagated as Phi C Phi' + Q once the mission runs and (I - K H) C at each update, then carried
//! freely to the mission's end: `cross` = E[(d - d_hat) p_end] (north, east).
//!
//! [`mission_covariance`]: the north/east position error after a free navigation of `span_s` (72 h) from the
//! smoother's error model with no measurements: its covariance from the angle and velocity random walks and the
//! initial attitude and velocity errors, and the deterministic response g to a unit z drift (the level body: the
//! axial column of C_b^n is Up whatever the table does; the horizontal sensor biases are modulated away by the
//! table and left out). With an identified drift of 1-sigma s, the error after compensation is the Gaussian with
//! covariance `pos_cov + s^2 g g' + g c' + c g'`, c the `cross` of [`drift_std_curve`].

use crate::attitude::{euler_to_dcm, mat_mul, rot_z, Euler, Mat3};
use crate::error::{check, CoreError};
use crate::kalman::EPS;
use crate::label::FreeNavigation;
use crate::smoother::model::{initial_sigma, measurement_model, symmetrise, Model};
use crate::smoother::{SmootherConfig, POS};
use crate::turntable::{RotationScheme, Turntable};
use nalgebra::{DMatrix, DVector};

/// Settings of [`drift_std_curve`] (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanConfig {
    /// The smoother's settings (site, sample rate, coarse span, update interval, priors, noise); its `span_s` is
    /// the longest span asked for (the smoother's limits apply to it); `thermal` must be false.
    pub smoother: SmootherConfig,
    /// The table's rotation scheme and the IMU's attitude at table angle zero.
    pub scheme: RotationScheme,
    pub attitude: Euler,
    /// Spans from the first sample \[s\], ascending, each after the first update and at most `smoother.span_s`.
    pub spans_s: Vec<f64>,
    /// Start of the mission's free navigation from the first sample \[s\] (the end of the alignment, 4 h) and its
    /// length \[s\] (72 h); the mission must end after the longest span.
    pub mission_start_s: f64,
    pub mission_s: f64,
}

/// What [`drift_std_curve`] gives at each span.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftCurve {
    /// 1-sigma of the z drift carried into navigation [rad/s].
    pub drift_std: Vec<f64>,
    /// E[(d - d_hat) p], p the north, east position error at the mission's end from the noise alone (the
    /// mission's noise floor) [rad/s m]: the drift error and the floor share the noise of the hours the span and the
    /// mission overlap.
    pub cross: Vec<[f64; 2]>,
}

/// The smoother's 1-sigma of the z drift carried into navigation at each of `cfg.spans_s`, and its covariance with
/// the mission's noise floor (module docs).
pub fn drift_std_curve(cfg: &PlanConfig) -> Result<DriftCurve, CoreError> {
    let sc = &cfg.smoother;
    sc.validate()?;
    check(
        !sc.thermal,
        "thermal",
        "the planner has no thermal state (the thermal term is added apart)",
    )?;
    let table = Turntable::new(cfg.scheme.clone())?;
    let rate = sc.rate_hz;
    let n_coarse = (sc.coarse_s * rate).round() as u64;
    let n_update = ((sc.update_s * rate).round() as u64).max(1);
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
        cfg.mission_start_s.is_finite() && cfg.mission_start_s >= 0.0,
        "mission_start_s",
        "must be a finite time >= 0 s",
    )?;
    check(
        cfg.mission_s.is_finite() && cfg.mission_s >= 60.0 && cfg.mission_start_s + cfg.mission_s >= last,
        "mission_s",
        format!("the mission must last >= 60 s and end after the longest span ({last} s)"),
    )?;
    let model = Model::new(sc);
    let n = model.n;
    let c0 = euler_to_dcm(cfg.attitude);
    let (h, r) = measurement_model(sc, n);
    let mut p = DMatrix::from_diagonal(&DVector::from_iterator(
        n,
        initial_sigma(sc, n_coarse as f64 / rate).iter().map(|s| s * s),
    ));
    // Selector of the total z drift carried into navigation.
    let mut a = DVector::zeros(n);
    a[EPS + 2] = 1.0;
    for first in [model.gm, model.rrw].into_iter().flatten() {
        a[first + 2] = 1.0;
    }
    let identity = DMatrix::<f64>::identity(n, n);
    // E[x~ y'], x~ the filter's estimation error (true minus estimate) and y the free mission navigation's error
    // from the noise alone, started at zero at `mission_start_s`: the same model, the same noise w_k in both
    // (predict: Phi C Phi' + Q once the mission runs), the measurements only on x~ (update: (I - K H) C).
    let mut cross = DMatrix::<f64>::zeros(n, n);
    // The free mission's transition (level body: the bias states of y stay zero, so the table does not matter).
    let level: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mission_end = cfg.mission_start_s + cfg.mission_s;
    let mut out = DriftCurve {
        drift_std: Vec::with_capacity(cfg.spans_s.len()),
        cross: Vec::with_capacity(cfg.spans_s.len()),
    };
    let mut k = n_coarse;
    let mut want = cfg.spans_s.iter().peekable();
    while want.peek().is_some() {
        // One update interval: the mean attitude over its samples (each at the end of its sample).
        let t_start = k as f64 / rate;
        let mut c_sum: Mat3 = [[0.0; 3]; 3];
        for j in 1..=n_update {
            let c = mat_mul(&c0, &rot_z(table.angle((k + j) as f64 / rate)));
            for (s_row, c_row) in c_sum.iter_mut().zip(c) {
                for (s, x) in s_row.iter_mut().zip(c_row) {
                    *s += x;
                }
            }
        }
        k += n_update;
        let c_mean: Mat3 = std::array::from_fn(|i| std::array::from_fn(|j| c_sum[i][j] / n_update as f64));
        let (phi, q) = model.discretise(&c_mean, 0.0, n_update as f64 / rate);
        p = symmetrise(&phi * &p * phi.transpose() + &q);
        if t_start >= cfg.mission_start_s - 1e-9 {
            cross = &phi * &cross * phi.transpose() + &q;
        }
        let s_inv = (&h * &p * h.transpose() + &r).try_inverse().ok_or(CoreError::Setting {
            key: "update_s",
            message: "the planner's innovation covariance is singular".to_string(),
        })?;
        let gain = &p * h.transpose() * s_inv;
        let i_kh = &identity - &gain * &h;
        p = symmetrise(&i_kh * &p * i_kh.transpose() + &gain * &r * gain.transpose());
        cross = &i_kh * &cross;
        let t = k as f64 / rate;
        while want.peek().is_some_and(|&&s| t >= s - 1e-9) {
            want.next();
            out.drift_std.push(a.dot(&(&p * &a)).max(0.0).sqrt());
            // E[y a'x~] carried freely to the mission's end (after t if the mission started, else from its start).
            let mut u: DVector<f64> = cross.transpose() * &a;
            let from = t.max(cfg.mission_start_s);
            let rest = (mission_end - from).max(0.0);
            let steps = (rest / MISSION_STEP_S).ceil() as usize;
            if steps > 0 {
                let (phi_free, _) = model.discretise(&level, 0.0, rest / steps as f64);
                for _ in 0..steps {
                    u = &phi_free * u;
                }
            }
            out.cross.push([u[POS], u[POS + 1]]);
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
    use crate::earth::OMEGA_IE;
    use crate::smoother::Smoother;
    use crate::turntable::scheme_from_settings;
    use crate::units::{DEG_PER_H, HOUR};

    fn plan_config(lat_deg: f64, spans_h: &[f64]) -> PlanConfig {
        let mut sc = SmootherConfig::new(lat_deg.to_radians(), 0.0, 0.0, 10.0);
        sc.span_s = 86_400.0;
        PlanConfig {
            smoother: sc,
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

    #[test]
    fn the_drift_error_shares_the_mission_noise_only_where_they_overlap() {
        let mut cfg = plan_config(40.0, &[3.0, 16.0]);
        let curve = drift_std_curve(&cfg).unwrap();
        assert_eq!(curve.cross[0], [0.0, 0.0]); // the span ends before the mission starts
        let m = mission_covariance(&FreeNavigation::white(
            cfg.smoother.lat,
            cfg.mission_s,
            60.0,
            cfg.smoother.gyro_arw,
            cfg.smoother.accel_vrw,
        ))
        .unwrap();
        // Cauchy-Schwarz on the east axis, and a correlation that is there after 12 h of overlap (about -0.05).
        let (c, s, floor) = (curve.cross[1][1], curve.drift_std[1], m.pos_cov[1][1].sqrt());
        assert!(c.abs() < s * floor && c.abs() > 0.01 * s * floor, "{c} {s} {floor}");
        cfg.mission_start_s = 20.0 * HOUR;
        assert_eq!(drift_std_curve(&cfg).unwrap().cross[1], [0.0, 0.0]);
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
