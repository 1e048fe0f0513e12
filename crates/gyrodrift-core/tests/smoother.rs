//! The full-information smoother against the simulator: the drift of noise-free logs, the consistency of its
//! 1-sigma over seeds, and the label covariance analysis against its closed-form latitude law.

use gyrodrift_core::attitude::Euler;
use gyrodrift_core::error::CoreError;
use gyrodrift_core::imu_error::ImuErrorParams;
use gyrodrift_core::label::{label_sigma, LabelConfig, SlowBias};
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::smoother::{state_names, Smoother, SmootherConfig, SmootherResult};
use gyrodrift_core::temperature::TemperatureProfile;
use gyrodrift_core::turntable::RotationScheme;
use gyrodrift_core::units::{DEG, DEG_PER_H, DEG_PER_H_PER_SQRT_H, HOUR, MICRO_G, SQRT_HOUR};
use std::f64::consts::PI;

const RATE_HZ: f64 = 5.0;
const SPAN_S: f64 = 8.0 * HOUR;
const ARW: f64 = 0.0005 * DEG / SQRT_HOUR;
const VRW: f64 = 5.0 * MICRO_G;

fn sim(lat_deg: f64, drift_deg_h: f64, scheme: RotationScheme, seed: u64, noise: bool) -> ImuSimulatorConfig {
    ImuSimulatorConfig {
        lat: lat_deg * DEG,
        rate_hz: RATE_HZ,
        duration_s: SPAN_S,
        seed,
        attitude: Euler {
            pitch: 0.2 * DEG,
            roll: -0.1 * DEG,
            yaw: 30.0 * DEG,
        },
        scheme,
        errors: ImuErrorParams {
            gyro_bias: [0.004 * DEG_PER_H, -0.003 * DEG_PER_H, drift_deg_h * DEG_PER_H],
            accel_bias: [20.0 * MICRO_G, -10.0 * MICRO_G, 5.0 * MICRO_G],
            gyro_arw: if noise { ARW } else { 0.0 },
            accel_vrw: if noise { VRW } else { 0.0 },
            ..Default::default()
        },
        ..Default::default()
    }
}

fn smooth(sim_cfg: ImuSimulatorConfig) -> SmootherResult {
    let mut cfg = SmootherConfig::new(sim_cfg.lat, sim_cfg.lon, sim_cfg.height, sim_cfg.rate_hz);
    cfg.span_s = SPAN_S;
    let mut s = ImuSimulator::new(sim_cfg).unwrap();
    let mut sm = Smoother::new(cfg).unwrap();
    let mut ch = ImuChunk::default();
    while !sm.done() && s.next_chunk(50_000, &mut ch) > 0 {
        sm.process(&ch.dtheta, &ch.dv, None).unwrap();
    }
    sm.result().unwrap()
}

fn reciprocating() -> RotationScheme {
    RotationScheme::Reciprocating {
        rate: 6.0 * DEG,
        accel: 10.0 * DEG,
        span: 2.0 * PI,
        dwell: 0.0,
    }
}

#[test]
fn noise_free_logs_give_the_simulated_drift() {
    let schemes = [
        reciprocating(),
        RotationScheme::Continuous {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
        },
    ];
    for scheme in schemes {
        for lat in [20.0, 40.0, 60.0] {
            for drift in [0.003, 0.05] {
                let r = smooth(sim(lat, drift, scheme.clone(), 1, false));
                let err = r.drift / DEG_PER_H - drift;
                println!(
                    "{scheme:?} {lat} deg, {drift} deg/h: error {err:.1e} deg/h, 1-sigma {:.1e}, largest attitude \
                     correction after 1 h {:.1e} rad, velocity {:.1e} m/s, position {:.3} m",
                    r.drift_std / DEG_PER_H,
                    r.max_attitude_correction,
                    r.max_velocity_correction,
                    r.max_position_error
                );
                assert!(err.abs() < 1e-5, "{err}");
                // The linear regime: arcsecond-free corrections, mm/s, centimetres.
                assert!(r.max_attitude_correction < 1e-6 && r.max_position_error < 1.0);
                assert!((r.drift_end - r.drift).abs() < 1e-12 * DEG_PER_H + 1e-3 * r.drift_std);
                // The smoothed history of a constant is that constant.
                for (d, s) in r.hist_drift.iter().zip(&r.hist_drift_std) {
                    assert!((d - r.drift).abs() < 0.01 * r.drift_std, "{d} {}", r.drift);
                    assert!((s / r.drift_std - 1.0).abs() < 1e-3);
                }
            }
        }
    }
}

#[test]
fn white_noise_z_scores_have_unit_rms() {
    // 12 seeds (the 30-seed runs are in benchmarks/bench_smoother.py and docs/studies/2026-11-23-smoother.md).
    let mut z2 = 0.0;
    let n = 12;
    for seed in 0..n {
        let r = smooth(sim(40.0, 0.003, reciprocating(), 100 + seed, true));
        let z = (r.drift / DEG_PER_H - 0.003) / (r.drift_std / DEG_PER_H);
        z2 += z * z;
    }
    let rms = (z2 / n as f64).sqrt();
    println!("z-score rms over {n} seeds: {rms:.2}");
    assert!((0.6..1.5).contains(&rms), "{rms}");
}

#[test]
fn label_sigma_follows_one_over_sin_cos_latitude() {
    let at =
        |lat_deg: f64| label_sigma(&LabelConfig::white(lat_deg * DEG, 72.0 * HOUR, 60.0, ARW, VRW, false)).unwrap();
    let s45 = at(45.0).drift_std;
    for lat in [10.0, 80.0] {
        let law = s45 * (0.5 / ((lat * DEG).sin() * (lat * DEG).cos()));
        let ratio = at(lat).drift_std / law;
        println!(
            "{lat} deg: {:.2e} deg/h, {ratio:.3} of the 1/(sin L cos L) law",
            at(lat).drift_std / DEG_PER_H
        );
        assert!((0.8..1.25).contains(&ratio), "{ratio}");
    }
    // method.md: 1.5-1.7e-4 deg/h at 40 deg for this grade (ARW 0.0005 deg/sqrt(h), 72 h).
    let s40 = at(40.0).drift_std / DEG_PER_H;
    assert!((1.0e-4..2.5e-4).contains(&s40), "{s40}");
    assert!(label_sigma(&LabelConfig::white(0.5, 3600.0, 60.0, f64::NAN, 0.0, true)).is_err());
}

#[test]
fn label_sigma_adds_the_z_gyro_bias_instability_and_rate_random_walk() {
    // 72 h at 40 deg, final criterion.
    let white = LabelConfig::white(40.0 * DEG, 72.0 * HOUR, 60.0, ARW, VRW, false);
    let s_white = label_sigma(&white).unwrap().drift_std;
    // A Gauss-Markov z bias (1-sigma bi, correlation time tau): independent of the white noise, so the label's
    // variances add.
    let (bi, tau) = (0.001 * DEG_PER_H, 600.0);
    let slow = SlowBias {
        bias_instability: bi,
        correlation: tau,
        rrw: 0.0,
    };
    let gm = LabelConfig { slow, ..white.clone() };
    let s_gm = label_sigma(&gm).unwrap().drift_std;
    let gm_only = LabelConfig::white(40.0 * DEG, 72.0 * HOUR, 60.0, 0.0, 0.0, false);
    let s_gm_only = label_sigma(&LabelConfig {
        slow,
        ..gm_only.clone()
    })
    .unwrap()
    .drift_std;
    assert!((s_gm * s_gm - s_white * s_white - s_gm_only * s_gm_only).abs() < 1e-6 * s_gm * s_gm);
    // Short memory (tau << 24 h): white z rate noise of density q = sigma sqrt(2 tau). It reaches the position
    // through the Earth-rate coupling only (psi' = -Omega x psi + eps): a unit drift impulse tau' before the end
    // moves (east, north) by G(tau') = R (sin L cos L (1 - cos W tau'), cos L sin W tau'), whose integral is the
    // drift response g (method.md's dlon and dL); var(d*) = q^2 int (g . G)^2 / |g|^4 (R cancels).
    let (t, w, lat) = (72.0 * HOUR, 7.2921151467e-5, 40.0 * DEG);
    let (sl, cl) = (lat.sin(), lat.cos());
    let steps = 200_000;
    let h = t / steps as f64;
    let (mut gn, mut ge) = (0.0, 0.0);
    let resp: Vec<(f64, f64)> = (0..steps)
        .map(|k| {
            let u = (k as f64 + 0.5) * h;
            let r = (sl * cl * (1.0 - (w * u).cos()), cl * (w * u).sin());
            gn += r.0 * h;
            ge += r.1 * h;
            r
        })
        .collect();
    let num: f64 = resp.iter().map(|r| (gn * r.0 + ge * r.1).powi(2) * h).sum();
    let g2 = gn * gn + ge * ge;
    let closed = (2.0 * bi * bi * tau * num / (g2 * g2)).sqrt();
    let ratio = s_gm_only / closed;
    println!(
        "GM only (tau {tau} s): {:.3e} deg/h, {ratio:.4} of the closed form",
        s_gm_only / DEG_PER_H
    );
    assert!((0.97..1.03).contains(&ratio), "{ratio}");
    // Long memory (tau >> 72 h): a random constant, which the label absorbs in full: sigma(d*) = sigma.
    let s_const = label_sigma(&LabelConfig {
        slow: SlowBias {
            correlation: 1e9,
            ..slow
        },
        ..gm_only.clone()
    })
    .unwrap()
    .drift_std;
    assert!((s_const / bi - 1.0).abs() < 0.01, "{}", s_const / bi);
    // A rate random walk that has walked `start` before the navigation: its value then is a constant the label
    // absorbs in full (variance rrw^2 start), independent of its walk during the span: the variances add.
    let rrw = 0.0005 * DEG_PER_H_PER_SQRT_H;
    let start = 4.0 * HOUR;
    let walk = SlowBias { rrw, ..SlowBias::NONE };
    let only_start = label_sigma(&LabelConfig {
        slow: walk,
        rrw_start_s: start,
        ..gm_only.clone()
    })
    .unwrap()
    .drift_std;
    assert!(only_start > rrw * start.sqrt());
    let walking = label_sigma(&LabelConfig {
        slow: walk,
        rrw_start_s: 0.0,
        ..gm_only.clone()
    })
    .unwrap()
    .drift_std;
    let both = (rrw * rrw * start + walking * walking).sqrt();
    assert!((only_start - both).abs() < 1e-6 * both, "{only_start} {both}");
    // Refused settings name their key.
    let bad = label_sigma(&LabelConfig {
        slow: SlowBias {
            correlation: 0.0,
            ..slow
        },
        ..gm
    })
    .unwrap_err();
    assert_eq!(bad.key(), "gyro_correlation_s");
}

#[test]
fn settings_are_checked_and_results_wait_for_the_span() {
    let mut cfg = SmootherConfig::new(0.7, 0.0, 0.0, 10.0);
    cfg.update_s = 0.5;
    assert_eq!(Smoother::new(cfg.clone()).unwrap_err().key(), "update_s");
    cfg.update_s = 10.0;
    cfg.gyro_arw = 0.0;
    assert_eq!(Smoother::new(cfg.clone()).unwrap_err().key(), "gyro_arw_rad_rts");
    cfg.gyro_arw = ARW;
    cfg.span_s = 100.0;
    assert_eq!(Smoother::new(cfg.clone()).unwrap_err().key(), "span_s");
    cfg.span_s = 3600.0;
    let mut sm = Smoother::new(cfg).unwrap();
    assert!(sm.result().is_err());
    assert!(sm.process(&[f64::NAN, 0.0, 0.0], &[0.0, 0.0, 9.8], None).is_err());
    assert_eq!(sm.samples_done(), 0);
}

/// A warm-up log: drift = `drift_deg_h` + `k1_deg_h_per_c` (T - 28 degC), T from 18 to 38 degC with time constant
/// `tau_h`.
fn thermal_sim(drift_deg_h: f64, k1_deg_h_per_c: f64, tau_h: f64, seed: u64, noise: bool) -> ImuSimulatorConfig {
    let mut s = sim(40.0, drift_deg_h, reciprocating(), seed, noise);
    s.errors.drift_t0_c = 28.0;
    s.errors.drift_k1 = k1_deg_h_per_c * DEG_PER_H;
    s.temperature = TemperatureProfile::WarmUp {
        start_c: 18.0,
        end_c: 38.0,
        tau_s: tau_h * HOUR,
        swing: gyrodrift_core::temperature::DailySwing::NONE,
    };
    s
}

/// Smooth a simulated log feeding its temperature column; `configure` edits the settings.
fn smooth_thermal(sim_cfg: ImuSimulatorConfig, configure: impl Fn(&mut SmootherConfig)) -> SmootherResult {
    let mut cfg = SmootherConfig::new(sim_cfg.lat, sim_cfg.lon, sim_cfg.height, sim_cfg.rate_hz);
    cfg.span_s = SPAN_S;
    cfg.thermal = true;
    configure(&mut cfg);
    let mut s = ImuSimulator::new(sim_cfg).unwrap();
    let mut sm = Smoother::new(cfg).unwrap();
    let mut ch = ImuChunk::default();
    while !sm.done() && s.next_chunk(50_000, &mut ch) > 0 {
        sm.process(&ch.dtheta, &ch.dv, Some(&ch.temp_c)).unwrap();
    }
    sm.result().unwrap()
}

/// The simulated z drift [deg/h] at time t [s] of `thermal_sim`.
fn thermal_drift_at(drift_deg_h: f64, k1_deg_h_per_c: f64, tau_h: f64, t_s: f64) -> f64 {
    let temp = 38.0 + (18.0 - 38.0) * (-t_s / (tau_h * HOUR)).exp();
    drift_deg_h + k1_deg_h_per_c * (temp - 28.0)
}

#[test]
fn noise_free_thermal_logs_give_the_end_drift_and_the_coefficient() {
    for (tau_h, k1) in [(1.5, 0.0002), (3.0, -0.0005)] {
        let r = smooth_thermal(thermal_sim(0.003, k1, tau_h, 1, false), |_| {});
        assert!(r.thermal);
        let end = thermal_drift_at(0.003, k1, tau_h, SPAN_S);
        let err_end = r.drift_end / DEG_PER_H - end;
        let err_k = r.thermal_coeff / DEG_PER_H - k1;
        println!(
            "tau {tau_h} h, k1 {k1}: end drift error {err_end:.1e} deg/h (1-sigma {:.1e}), k error {err_k:.1e} \
             deg/h/degC (1-sigma {:.1e}), T_ref {:.2}, T_end {:.2}, range {:.2} degC",
            r.drift_end_std / DEG_PER_H,
            r.thermal_coeff_std / DEG_PER_H,
            r.temp_ref,
            r.temp_end,
            r.temp_range
        );
        assert!(err_end.abs() < 1e-5, "{err_end}");
        assert!(err_k.abs() < 1e-6, "{err_k}");
        // eps_z is the drift at T_ref; the history follows the law.
        let at_ref = 0.003 + k1 * (r.temp_ref - 28.0);
        assert!((r.drift_ref / DEG_PER_H - at_ref).abs() < 1e-5);
        for (t, d) in r.hist_t.iter().zip(&r.hist_drift) {
            assert!(
                (d / DEG_PER_H - thermal_drift_at(0.003, k1, tau_h, *t)).abs() < 2e-5,
                "{t} {d}"
            );
        }
        // The constant model (conditioned on k_z = 0) sees a mean of the warm-up, not the end.
        assert!((r.drift / DEG_PER_H - end).abs() > 1e-4);
    }
}

#[test]
fn the_constant_model_is_the_thermal_state_conditioned_on_zero() {
    // One noisy warm-up log: the thermal filter told to report the constant model (range threshold above the
    // warm-up) against the filter without the thermal state.
    let sim_cfg = thermal_sim(0.003, 0.0002, 2.0, 7, true);
    let plain = smooth(sim_cfg.clone());
    let cond = smooth_thermal(sim_cfg.clone(), |c| c.thermal_min_range = 100.0);
    assert!(!cond.thermal && cond.temp_range > 15.0);
    for (a, b, what) in [
        (plain.drift, cond.drift, "drift"),
        (plain.drift_std, cond.drift_std, "drift sigma"),
        (plain.drift_end, cond.drift_end, "end drift"),
        (plain.drift_end_std, cond.drift_end_std, "end sigma"),
        (plain.gyro_bias_std[0], cond.gyro_bias_std[0], "x sigma"),
    ] {
        assert!((a - b).abs() < 1e-3 * plain.drift_std, "{what}: {a} vs {b}");
    }
    // The thermal report of the same log: a wider end-drift sigma, and `drift` is still the constant model's.
    let th = smooth_thermal(sim_cfg, |_| {});
    assert!(th.thermal && th.drift_end_std > plain.drift_std);
    assert!((th.drift - plain.drift).abs() < 1e-3 * plain.drift_std);
    // A constant temperature: the thermal state is decoupled, the constant model reported, the same numbers.
    let mut flat = thermal_sim(0.003, 0.0002, 2.0, 7, true);
    flat.temperature = TemperatureProfile::WarmUp {
        start_c: 30.0,
        end_c: 30.0,
        tau_s: 3600.0,
        swing: gyrodrift_core::temperature::DailySwing::NONE,
    };
    let plain = smooth(flat.clone());
    let th = smooth_thermal(flat, |_| {});
    assert!(!th.thermal && th.temp_range == 0.0);
    assert!((th.drift_end - plain.drift_end).abs() < 1e-6 * plain.drift_std);
}

#[test]
fn thermal_z_scores_of_the_end_drift_have_unit_rms() {
    // 8 seeds, 8 h at 5 Hz (the 30-seed runs are in tests/procedure/test_smoother.py's benchmark and the docs).
    let n = 8;
    let mut z2 = 0.0;
    for seed in 0..n {
        let r = smooth_thermal(thermal_sim(0.003, 0.0002, 3.0, 200 + seed, true), |_| {});
        let z =
            (r.drift_end / DEG_PER_H - thermal_drift_at(0.003, 0.0002, 3.0, SPAN_S)) / (r.drift_end_std / DEG_PER_H);
        z2 += z * z;
    }
    let rms = (z2 / n as f64).sqrt();
    println!("thermal end-drift z-score rms over {n} seeds: {rms:.2}");
    assert!((0.5..1.6).contains(&rms), "{rms}");
}

#[test]
fn thermal_settings_and_temperatures_are_checked() {
    let mut cfg = SmootherConfig::new(0.7, 0.0, 0.0, 10.0);
    cfg.span_s = 3600.0;
    cfg.thermal = true;
    cfg.thermal_sigma = 0.0;
    assert_eq!(
        Smoother::new(cfg.clone()).unwrap_err().key(),
        "thermal_sigma_rad_s_per_c"
    );
    cfg.thermal_sigma = 0.01 * DEG_PER_H;
    cfg.temp_ref = Some(500.0);
    assert_eq!(Smoother::new(cfg.clone()).unwrap_err().key(), "temp_ref_c");
    cfg.temp_ref = None;
    cfg.thermal_min_range = -1.0;
    assert_eq!(Smoother::new(cfg.clone()).unwrap_err().key(), "thermal_min_range_c");
    cfg.thermal_min_range = 0.5;
    let mut sm = Smoother::new(cfg).unwrap();
    let (dth, dv) = ([0.0; 6], [0.0, 0.0, 0.98, 0.0, 0.0, 0.98]);
    assert_eq!(sm.process(&dth, &dv, None).unwrap_err().key(), "temp_c");
    assert_eq!(sm.process(&dth, &dv, Some(&[20.0])).unwrap_err().key(), "temp_c");
    let e = sm.process(&dth, &dv, Some(&[20.0, f64::NAN])).unwrap_err();
    assert!(
        matches!(
            e,
            CoreError::Sample {
                key: "temp_c",
                index: 1,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(sm.samples_done(), 0);
    assert_eq!(sm.process(&dth, &dv, Some(&[20.0, 20.1])), Ok(2));
    assert_eq!(sm.config().n_states(), 15);
    assert_eq!(state_names(sm.config()).last(), Some(&"gyro_temp_z"));
}
