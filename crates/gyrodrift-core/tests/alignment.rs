//! Alignment with the simulator and reciprocating rotation against closed forms and the filter's own stds.

use gyrodrift_core::alignment::{attitude_error, Aligner, AlignerConfig, AlignmentResult};
use gyrodrift_core::attitude::{euler_to_dcm, mat_vec, Euler};
use gyrodrift_core::earth;
use gyrodrift_core::filter_prior::FilterSettings;
use gyrodrift_core::imu_error::ImuErrorParams;
use gyrodrift_core::kalman::N_STATES;
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::turntable::RotationScheme;
use gyrodrift_core::units::{ARCMIN, ARCSEC, DEG, DEG_PER_H, MICRO_G, SQRT_HOUR};
use std::f64::consts::PI;
const RATE_HZ: f64 = 20.0;

fn lat0() -> f64 {
    28.222 * DEG
}

fn reciprocating() -> RotationScheme {
    RotationScheme::Reciprocating {
        rate: 6.0 * DEG,
        accel: 10.0 * DEG,
        span: 2.0 * PI,
        dwell: 0.0,
    }
}

fn biased(seed: u64, noise: bool) -> ImuSimulatorConfig {
    let errors = ImuErrorParams {
        gyro_bias: [0.01 * DEG_PER_H, -0.008 * DEG_PER_H, 0.003 * DEG_PER_H],
        accel_bias: [50.0 * MICRO_G, -40.0 * MICRO_G, 30.0 * MICRO_G],
        gyro_arw: if noise { 0.001 * DEG / SQRT_HOUR } else { 0.0 },
        accel_vrw: if noise { 10.0 * MICRO_G } else { 0.0 },
        ..Default::default()
    };
    ImuSimulatorConfig {
        lat: lat0(),
        rate_hz: RATE_HZ,
        duration_s: 14_400.0,
        seed,
        attitude: Euler {
            pitch: 0.3 * DEG,
            roll: -0.2 * DEG,
            yaw: 40.0 * DEG,
        },
        scheme: reciprocating(),
        errors,
        ..Default::default()
    }
}

/// What a run gives: the result, and the true attitude at the end of the coarse and of the whole span.
struct Run {
    res: AlignmentResult,
    true_coarse: Euler,
    true_end: Euler,
    aligner: Aligner,
}

fn run(sim_cfg: ImuSimulatorConfig, cfg: AlignerConfig) -> Run {
    let n_coarse = (cfg.filter.coarse_s * cfg.rate_hz).round() as usize;
    let mut sim = ImuSimulator::new(sim_cfg).unwrap();
    let mut al = Aligner::new(cfg).unwrap();
    let mut ch = ImuChunk::default();
    let (mut true_coarse, mut true_end) = (None, None);
    let mut seen = 0usize;
    while !al.done() && sim.next_chunk(7_777, &mut ch) > 0 {
        let used = al.process(&ch.dtheta, &ch.dv).unwrap();
        let at = |i: usize| Euler {
            pitch: ch.pitch[i],
            roll: ch.roll[i],
            yaw: ch.yaw[i],
        };
        if seen < n_coarse && n_coarse <= seen + used {
            true_coarse = Some(at(n_coarse - seen - 1));
        }
        if al.done() {
            true_end = Some(at(used - 1));
        }
        seen += used;
    }
    Run {
        res: al.result().unwrap(),
        true_coarse: true_coarse.unwrap(),
        true_end: true_end.unwrap(),
        aligner: al,
    }
}

fn cfg_4h() -> AlignerConfig {
    AlignerConfig::new(lat0(), 0.0, 0.0, RATE_HZ)
}

/// `cfg_4h` with its filter settings changed by `change`.
fn cfg_with(change: impl FnOnce(&mut FilterSettings)) -> AlignerConfig {
    let mut cfg = cfg_4h();
    change(&mut cfg.filter);
    cfg
}

#[test]
fn coarse_alignment_without_sensor_errors_is_exact() {
    let mut sim = biased(1, false);
    sim.errors = ImuErrorParams::default();
    let cfg = AlignerConfig {
        fine_s: 0.0,
        ..cfg_4h()
    };
    let r = run(sim, cfg);
    let e = attitude_error(r.res.coarse_attitude, r.true_coarse);
    println!("coarse, no errors: phi = {:.3?} arcsec", e.map(|x| x / ARCSEC));
    assert!(e.iter().all(|x| x.abs() < 0.5 * ARCSEC), "{e:?}");
}

#[test]
fn coarse_alignment_without_rotation_has_the_closed_form_bias_errors() {
    // Still table, no noise: the classical static-alignment errors (phi = correction, C_true = (I + [phi x]) C):
    // phi_E = -nabla_N / g, phi_N = nabla_E / g, phi_U = nabla_E tan(lat) / g - eps_E / (w_ie cos lat),
    // with the biases resolved in ENU through the true attitude. (No z gyro bias here: it would add its
    // drift over the span, eps_z T / 2 = 0.45 arcsec for 0.003 deg/h.)
    let mut sim = biased(2, false);
    sim.scheme = RotationScheme::None;
    sim.errors.gyro_bias[2] = 0.0;
    let c_bn = euler_to_dcm(sim.attitude);
    let eps_n = mat_vec(&c_bn, sim.errors.gyro_bias);
    let nabla_n = mat_vec(&c_bn, sim.errors.accel_bias);
    let r = run(
        sim,
        AlignerConfig {
            fine_s: 0.0,
            ..cfg_4h()
        },
    );
    let e = attitude_error(r.res.coarse_attitude, r.true_coarse);
    let g = earth::normal_gravity(lat0(), 0.0);
    let expected = [
        -nabla_n[1] / g,
        nabla_n[0] / g,
        nabla_n[0] * lat0().tan() / g - eps_n[0] / (earth::OMEGA_IE * lat0().cos()),
    ];
    println!(
        "coarse, still table: phi = {:.3?}, closed form {:.3?} arcsec",
        e.map(|x| x / ARCSEC),
        expected.map(|x| x / ARCSEC)
    );
    for i in 0..3 {
        assert!((e[i] - expected[i]).abs() < 0.2 * ARCSEC, "{i}: {e:?} vs {expected:?}");
    }
}

#[test]
fn coarse_alignment_on_the_turning_table_removes_the_horizontal_biases() {
    // Reciprocating rotation modulates the horizontal gyro biases away and lets the fit find the accelerometer
    // ones; what is left of 0.003 deg/h on z over 300 s is below eps_z T / 2 = 0.45 arcsec.
    let r = run(
        biased(2, false),
        AlignerConfig {
            fine_s: 0.0,
            ..cfg_4h()
        },
    );
    let e = attitude_error(r.res.coarse_attitude, r.true_coarse);
    println!(
        "coarse, turning table, biases: phi = {:.3?} arcsec",
        e.map(|x| x / ARCSEC)
    );
    assert!(e.iter().all(|x| x.abs() < 3.0 * ARCSEC), "{e:?}");
}

#[test]
fn coarse_alignment_with_noise_is_within_a_few_arcmin() {
    // With ARW 0.001 deg/sqrt(h) the heading is noise-limited: ARW / (w_ie cos lat sqrt(300 s)) = 54 arcsec.
    for seed in [21, 22, 23] {
        let r = run(
            biased(seed, true),
            AlignerConfig {
                fine_s: 0.0,
                ..cfg_4h()
            },
        );
        let e = attitude_error(r.res.coarse_attitude, r.true_coarse);
        println!(
            "coarse, seed {seed}, biases + noise: phi = {:.2?} arcsec",
            e.map(|x| x / ARCSEC)
        );
        assert!(e[0].hypot(e[1]) < 3.0 * ARCSEC, "{e:?}");
        assert!(e[2].abs() < 3.0 * ARCMIN, "{e:?}");
    }
}

#[test]
fn fine_alignment_4h_estimates_the_horizontal_biases() {
    let r = run(biased(3, false), cfg_4h());
    let res = &r.res;
    let gb = [0.01, -0.008, 0.003];
    let ab = [50.0, -40.0, 30.0];
    let gerr: Vec<f64> = (0..3).map(|i| res.gyro_bias[i] / DEG_PER_H - gb[i]).collect();
    let aerr: Vec<f64> = (0..3).map(|i| res.accel_bias[i] / MICRO_G - ab[i]).collect();
    let phi = attitude_error(res.attitude, r.true_end);
    println!(
        "fine 4 h, no noise: gyro err {gerr:.5?} deg/h, std {:.5?}",
        res.gyro_bias_std.map(|x| x / DEG_PER_H)
    );
    println!(
        "  accel err {aerr:.3?} ug, std {:.3?}",
        res.accel_bias_std.map(|x| x / MICRO_G)
    );
    println!(
        "  att err {:.3?} arcsec, std {:.3?}",
        phi.map(|x| x / ARCSEC),
        res.att_std.map(|x| x / ARCSEC)
    );
    println!(
        "  coarse err {:.3?} arcsec",
        attitude_error(res.coarse_attitude, r.true_coarse).map(|x| x / ARCSEC)
    );
    assert!((res.t_s - 14_400.0).abs() < 1e-9);
    assert!(gerr[0].abs() < 0.001 && gerr[1].abs() < 0.001, "{gerr:?}");
    assert!(aerr[0].abs() < 5.0 && aerr[1].abs() < 5.0, "{aerr:?}");
    assert!(phi[0].abs() < 3.0 * ARCSEC && phi[1].abs() < 3.0 * ARCSEC, "{phi:?}");
    for i in 0..3 {
        assert!(gerr[i].abs() < 3.0 * res.gyro_bias_std[i] / DEG_PER_H, "gyro {i}");
        assert!(phi[i].abs() < 3.0 * res.att_std[i], "att {i}");
    }
    // The axial drift stays weakly observable: its std is of the order of method.md's 0.002 deg/h.
    let z_std = res.gyro_bias_std[2] / DEG_PER_H;
    assert!(z_std > 0.001 && z_std < 0.004, "{z_std}");
    assert!(res.gyro_bias_std[0] < res.gyro_bias_std[2] && res.gyro_bias_std[1] < res.gyro_bias_std[2]);
}

#[test]
fn covariance_stays_symmetric_and_positive_definite() {
    let r = run(
        biased(4, true),
        AlignerConfig {
            fine_s: 3600.0,
            ..cfg_4h()
        },
    );
    let p = r.aligner.covariance().unwrap();
    let asym = (p - p.transpose()).abs().max();
    assert!(asym == 0.0, "{asym}");
    let eig = p.symmetric_eigenvalues();
    assert!(eig.iter().all(|&x| x > 0.0), "{eig:?}");
    assert!(p.cholesky().is_some());
    // History: start of the fine span, every 60 s, the end; stds of the horizontal gyro biases decrease.
    let h = &r.res;
    assert_eq!(h.hist_t.len(), 61);
    assert!((h.hist_t[0] - 300.0).abs() < 1e-9 && (h.hist_t[60] - 3900.0).abs() < 1e-9);
    assert!(h
        .hist_std
        .iter()
        .all(|s| s.len() == N_STATES && s.iter().all(|x| x.is_finite() && *x > 0.0)));
    assert!(h.hist_std.windows(2).all(|w| w[1][6] <= w[0][6] * (1.0 + 1e-12)));
}

#[test]
fn filter_stds_are_consistent_with_the_errors_over_seeds() {
    let gb = [0.01, -0.008, 0.003];
    let ab = [50.0, -40.0, 30.0];
    for seed in [11, 12, 13] {
        let r = run(biased(seed, true), cfg_4h());
        let res = &r.res;
        let phi = attitude_error(res.attitude, r.true_end);
        let gz: Vec<f64> = (0..3)
            .map(|i| (res.gyro_bias[i] / DEG_PER_H - gb[i]) / (res.gyro_bias_std[i] / DEG_PER_H))
            .collect();
        let az: Vec<f64> = (0..2)
            .map(|i| (res.accel_bias[i] / MICRO_G - ab[i]) / (res.accel_bias_std[i] / MICRO_G))
            .collect();
        let pz: Vec<f64> = (0..3).map(|i| phi[i] / res.att_std[i]).collect();
        println!("seed {seed}: gyro z-scores {gz:.2?}, accel {az:.2?}, attitude {pz:.2?}");
        println!(
            "  gyro err {:.5?} deg/h, accel err {:.2?} ug, att err {:.2?} arcsec",
            (0..3).map(|i| res.gyro_bias[i] / DEG_PER_H - gb[i]).collect::<Vec<_>>(),
            (0..3).map(|i| res.accel_bias[i] / MICRO_G - ab[i]).collect::<Vec<_>>(),
            phi.map(|x| x / ARCSEC)
        );
        assert!(gz.iter().chain(&az).chain(&pz).all(|z| z.abs() < 3.0), "seed {seed}");
    }
}

#[test]
fn streaming_in_any_chunks_gives_the_same_result_and_stops_at_the_span() {
    let cfg = AlignerConfig {
        fine_s: 120.0,
        ..cfg_with(|f| f.coarse_s = 60.0)
    };
    let mut sim = ImuSimulator::new(ImuSimulatorConfig {
        duration_s: 200.0,
        ..biased(5, true)
    })
    .unwrap();
    let mut ch = ImuChunk::default();
    sim.next_chunk(4000, &mut ch);
    let mut a = Aligner::new(cfg.clone()).unwrap();
    assert_eq!(a.process(&ch.dtheta, &ch.dv), Ok(3600));
    assert!(a.done());
    let mut b = Aligner::new(cfg).unwrap();
    let mut used = 0;
    for (x, y) in ch.dtheta.chunks(3 * 997).zip(ch.dv.chunks(3 * 997)) {
        used += b.process(x, y).unwrap();
    }
    assert_eq!(used, 3600);
    assert_eq!(a.result(), b.result());
    assert!(Aligner::new(cfg_with(|f| f.coarse_s = 60.0)).unwrap().result().is_err());
}

#[test]
fn bad_settings_name_their_key() {
    let bad = |c: AlignerConfig| Aligner::new(c).unwrap_err().key();
    assert_eq!(bad(cfg_with(|f| f.coarse_s = 1.0)), "coarse_s");
    assert_eq!(
        bad(AlignerConfig {
            fine_s: -1.0,
            ..cfg_4h()
        }),
        "fine_s"
    );
    assert_eq!(bad(cfg_with(|f| f.update_s = 0.0)), "update_s");
    assert_eq!(
        bad(cfg_with(|f| f.att_sigma = Some([0.0, 1e-4, 1e-3]))),
        "att_sigma_rad"
    );
    assert_eq!(
        bad(cfg_with(|f| f.gyro_bias_sigma = [f64::NAN; 3])),
        "gyro_bias_sigma_rad_s"
    );
    assert_eq!(
        bad(cfg_with(|f| f.accel_bias_sigma = [0.0; 3])),
        "accel_bias_sigma_m_s2"
    );
    assert_eq!(bad(cfg_with(|f| f.gyro_arw = -1.0)), "gyro_arw_rad_rts");
    assert_eq!(bad(cfg_with(|f| f.accel_vrw = 2.0)), "accel_vrw_m_s_rts");
    assert_eq!(bad(cfg_with(|f| f.zupt_sigma = 0.0)), "zupt_sigma_m_s");
    assert_eq!(bad(cfg_with(|f| f.history_s = 0.0)), "history_s");
    assert_eq!(
        bad(AlignerConfig {
            rate_hz: 0.0,
            ..cfg_4h()
        }),
        "rate_hz"
    );
    assert_eq!(bad(AlignerConfig { lat: 2.0, ..cfg_4h() }), "lat_rad");
}

#[test]
fn a_partial_last_update_interval_still_ends_the_alignment() {
    // 100 s of fine alignment with 7 s updates: 14 whole intervals and a last one of 2 s; history every 21 s.
    let cfg = AlignerConfig {
        fine_s: 100.0,
        ..cfg_with(|f| {
            f.coarse_s = 60.0;
            f.update_s = 7.0;
            f.history_s = 21.0;
        })
    };
    let r = run(
        ImuSimulatorConfig {
            duration_s: 200.0,
            ..biased(6, true)
        },
        cfg,
    );
    let t: Vec<f64> = r.res.hist_t.clone();
    assert_eq!(t, vec![60.0, 81.0, 102.0, 123.0, 144.0, 160.0]);
    assert!((r.res.t_s - 160.0).abs() < 1e-12);
    assert!(r.res.vel.iter().all(|v| v.abs() < 0.01), "{:?}", r.res.vel);
}

/// Sensor biases and noise, 4 h, on another rotation scheme.
fn run_scheme(scheme: RotationScheme, seed: u64) -> Run {
    run(
        ImuSimulatorConfig {
            scheme,
            ..biased(seed, true)
        },
        cfg_4h(),
    )
}

#[test]
fn continuous_rotation_cannot_tell_horizontal_gyro_from_accelerometer_biases() {
    // Unidirectional rotation at w: a horizontal gyro bias tilts the platform by a vector of length eps / w turning
    // with the table, whose g x phi is exactly what a rotated accelerometer bias of g eps / w does: the filter
    // keeps the horizontal gyro std at its prior (0.01 deg/h) and the accelerometer std near g 0.01 deg/h / w.
    let r = run_scheme(
        RotationScheme::Continuous {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
        },
        7,
    );
    let prior = 0.01;
    for i in 0..2 {
        let std = r.res.gyro_bias_std[i] / DEG_PER_H;
        assert!((std / prior - 1.0).abs() < 0.01, "{i}: {std}");
    }
    let confounded = earth::normal_gravity(lat0(), 0.0) * prior * DEG_PER_H / (6.0 * DEG) / MICRO_G;
    println!(
        "continuous: accel std {:.3?} ug, g eps / w = {confounded:.3} ug",
        r.res.accel_bias_std.map(|x| x / MICRO_G)
    );
    assert!(r.res.accel_bias_std[0] / MICRO_G < 1.5 * confounded);
}

#[test]
fn four_position_indexing_observes_the_horizontal_gyro_biases() {
    let scheme = RotationScheme::Indexing {
        rate: 6.0 * DEG,
        accel: 10.0 * DEG,
        positions: vec![0.0, 0.5 * PI, PI, 1.5 * PI],
        dwell: 300.0,
    };
    let r = run_scheme(scheme, 8);
    let res = &r.res;
    let gb = [0.01, -0.008, 0.003];
    let phi = attitude_error(res.attitude, r.true_end);
    for i in 0..3 {
        let err = res.gyro_bias[i] / DEG_PER_H - gb[i];
        let std = res.gyro_bias_std[i] / DEG_PER_H;
        println!(
            "indexing: gyro {i} err {err:.5} std {std:.5} deg/h; phi {:.2} std {:.2} arcsec",
            phi[i] / ARCSEC,
            res.att_std[i] / ARCSEC
        );
        assert!(err.abs() < 3.0 * std && phi[i].abs() < 3.0 * res.att_std[i]);
    }
    assert!(res.gyro_bias_std[0] / DEG_PER_H < 0.001 && res.gyro_bias_std[1] / DEG_PER_H < 0.001);
}
