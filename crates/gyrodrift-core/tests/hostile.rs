//! Data that no static-base IMU delivers gives a `CoreError`, never a panic: one test per converted path.

use gyrodrift_core::alignment::{Aligner, AlignerConfig};
use gyrodrift_core::coarse_alignment::InertialCoarseAlignment;
use gyrodrift_core::error::CoreError;
use gyrodrift_core::filter_prior::FilterSettings;
use gyrodrift_core::kalman::{ErrorStateFilter, N_STATES};
use gyrodrift_core::simulator::{ImuChunkSlices, ImuSimulator, ImuSimulatorConfig, MAX_CHUNK_SAMPLES};
use gyrodrift_core::strapdown::{Navigator, NavigatorConfig};
use gyrodrift_core::turntable::RotationScheme;
use gyrodrift_core::units::STANDARD_GRAVITY;

const RATE_HZ: f64 = 10.0;

/// Increments of a constant specific force `f` [m/s^2] (body frame) and zero rate, `n` samples.
fn constant_force(f: [f64; 3], n: usize) -> (Vec<f64>, Vec<f64>) {
    let dt = 1.0 / RATE_HZ;
    (vec![0.0; 3 * n], f.iter().map(|x| x * dt).cycle().take(3 * n).collect())
}

fn short_aligner() -> Aligner {
    Aligner::new(AlignerConfig {
        fine_s: 320.0,
        ..AlignerConfig::new(0.5, 0.0, 0.0, RATE_HZ)
    })
    .unwrap()
}

#[test]
fn five_g_horizontal_is_a_divergence_not_a_panic() {
    // The case of issue 8: 5 g horizontal for 620 s at 10 Hz panicked on the accelerometer bias estimate.
    let mut al = short_aligner();
    let (dth, dv) = constant_force([5.0 * STANDARD_GRAVITY, 0.0, STANDARD_GRAVITY], 6200);
    let e = al.process(&dth, &dv).unwrap_err();
    assert!(matches!(e, CoreError::Diverged { .. }), "{e}");
    assert!(e.to_string().contains("static base"), "{e}");
    // The aligner stays stopped: the same error again, and no result.
    assert_eq!(al.process(&dth[..3], &dv[..3]).unwrap_err(), e);
    assert_eq!(al.result().unwrap_err(), e);
}

#[test]
fn no_gravity_stops_the_coarse_alignment() {
    let mut al = short_aligner();
    let (dth, dv) = constant_force([0.0; 3], 6200);
    let e = al.process(&dth, &dv).unwrap_err();
    assert!(matches!(e, CoreError::Diverged { .. }), "{e}");
}

#[test]
fn bad_samples_are_refused_before_anything_changes() {
    let mut al = short_aligner();
    let (mut dth, dv) = constant_force([0.0, 0.0, STANDARD_GRAVITY], 100);
    dth[3 * 57 + 1] = f64::NAN;
    let e = al.process(&dth, &dv).unwrap_err();
    assert!(
        matches!(
            e,
            CoreError::Sample {
                key: "dtheta_rad",
                index: 57,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(al.samples_done(), 0);
    assert!(matches!(al.result(), Err(CoreError::Incomplete { done: 0, .. })));
    // Ragged input.
    assert!(matches!(al.process(&dth[..4], &dv[..4]), Err(CoreError::Shape { .. })));
    assert!(matches!(al.process(&dth[..3], &dv[..6]), Err(CoreError::Shape { .. })));
    // A refused chunk does not stop the aligner: good data still go in.
    let (dth, dv) = constant_force([0.0, 0.0, STANDARD_GRAVITY], 10);
    assert_eq!(al.process(&dth, &dv), Ok(10));
}

#[test]
fn navigator_refuses_nan_huge_and_ragged_samples_unchanged() {
    let mut nav = Navigator::new(NavigatorConfig {
        rate_hz: RATE_HZ,
        ..Default::default()
    })
    .unwrap();
    let before = nav.state();
    for bad in [f64::NAN, f64::INFINITY, 1e300] {
        let (dth, mut dv) = constant_force([0.0, 0.0, STANDARD_GRAVITY], 20);
        dv[3 * 5] = bad;
        let e = nav.process(&dth, &dv, 1, |_| {}).unwrap_err();
        assert!(
            matches!(
                e,
                CoreError::Sample {
                    key: "dv_m_s",
                    index: 5,
                    ..
                }
            ),
            "{e}"
        );
    }
    assert!(matches!(
        nav.process(&[0.0; 3], &[], 1, |_| {}),
        Err(CoreError::Shape { .. })
    ));
    assert_eq!(
        nav.process(&[0.0; 3], &[0.0; 3], 0, |_| {}).unwrap_err().key(),
        "decimation"
    );
    assert_eq!(nav.state(), before);
    assert_eq!(nav.samples_done(), 0);
    // Zero samples are no samples.
    nav.process(&[], &[], 1, |_| panic!("no output")).unwrap();
}

#[test]
fn navigator_reports_a_state_that_leaves_the_earth() {
    let mut nav = Navigator::new(NavigatorConfig {
        rate_hz: RATE_HZ,
        ..Default::default()
    })
    .unwrap();
    // 90 g north for an hour (within the sensor limits): the position runs over the pole.
    let (dth, dv) = constant_force([0.0, 90.0 * STANDARD_GRAVITY, STANDARD_GRAVITY], 36_000);
    let e = nav.process(&dth, &dv, 1000, |_| {}).unwrap_err();
    assert!(matches!(e, CoreError::Diverged { .. }), "{e}");
}

#[test]
fn simulator_refuses_short_buffers_tiny_spans_and_huge_chunks() {
    let mut sim = ImuSimulator::new(ImuSimulatorConfig {
        duration_s: 10.0,
        ..Default::default()
    })
    .unwrap();
    let (mut a, mut b, mut c) = ([0.0; 4], [0.0; 12], [0.0; 11]);
    let (mut d, mut e, mut f, mut g, mut h) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
    let out = ImuChunkSlices {
        t_s: &mut a,
        dtheta: &mut b,
        dv: &mut c,
        temp_c: &mut d,
        table_angle: &mut e,
        pitch: &mut f,
        roll: &mut g,
        yaw: &mut h,
        truth: None,
    };
    assert_eq!(sim.fill(out).unwrap_err().key(), "dv_m_s");
    assert_eq!(sim.samples_done(), 0);
    assert_eq!(sim.chunk_len(0).unwrap_err().key(), "n");
    assert!(sim.chunk_len(MAX_CHUNK_SAMPLES + 1).is_err());
    assert_eq!(sim.chunk_len(MAX_CHUNK_SAMPLES).unwrap(), 1000);

    // A 1e-300 rad reciprocating span would walk its profile for hours.
    let tiny = ImuSimulatorConfig {
        scheme: RotationScheme::Reciprocating {
            rate: 0.1,
            accel: 1.0,
            span: 1e-300,
            dwell: 0.0,
        },
        ..Default::default()
    };
    let e = ImuSimulator::new(tiny).unwrap_err();
    assert_eq!(e.key(), "reciprocating_span_rad");
    assert!(e.to_string().contains("shorter than 10 samples"), "{e}");
}

#[test]
fn filter_and_coarse_alignment_refuse_instead_of_panicking() {
    let mut kf = ErrorStateFilter::new(&[f64::NAN; N_STATES]);
    assert!(kf.update_zero_velocity([0.0; 3], 0.001).is_err());
    let mut kf = ErrorStateFilter::new(&[1.0; N_STATES]);
    assert!(kf.update_zero_velocity([f64::NAN, 0.0, 0.0], 0.001).is_err());
    assert_eq!(
        InertialCoarseAlignment::new(0.5, 0.0, 100.0, 1).unwrap_err().key(),
        "coarse_s"
    );
}

#[test]
fn aligner_settings_are_refused_in_user_units() {
    let base = AlignerConfig::new(0.5, 0.0, 0.0, RATE_HZ);
    let e = Aligner::new(AlignerConfig {
        filter: FilterSettings {
            gyro_bias_sigma: [1.0; 3],
            ..base.filter.clone()
        },
        ..base.clone()
    })
    .unwrap_err();
    assert_eq!(e.key(), "gyro_bias_sigma_rad_s");
    assert!(e.to_string().contains("deg/h"), "{e}");
    let e = Aligner::new(AlignerConfig {
        filter: FilterSettings {
            accel_bias_sigma: [f64::NAN, 1e-4, 1e-4],
            ..base.filter.clone()
        },
        ..base.clone()
    })
    .unwrap_err();
    assert!(e.to_string().contains("ug"), "{e}");
    let e = Aligner::new(AlignerConfig {
        filter: FilterSettings {
            update_s: 0.01,
            ..base.filter
        },
        ..base
    })
    .unwrap_err();
    assert!(e.to_string().contains("holds no sample at 10 Hz"), "{e}");
}

#[test]
fn navigator_refusal_in_a_later_block_restores_the_state() {
    let mut nav = Navigator::new(NavigatorConfig {
        rate_hz: RATE_HZ,
        ..Default::default()
    })
    .unwrap();
    let (dth, mut dv) = constant_force([0.0, 0.0, STANDARD_GRAVITY], 10_000);
    nav.process(&dth[..300], &dv[..300], 7, |_| {}).unwrap();
    let before = nav.clone();
    dv[3 * 9_001] = f64::NAN;
    let mut outputs = 0;
    let e = nav.process(&dth, &dv, 7, |_| outputs += 1).unwrap_err();
    assert!(matches!(e, CoreError::Sample { index: 9_001, .. }), "{e}");
    assert!(outputs > 0, "the blocks before the bad one were navigated");
    assert_eq!(nav.state(), before.state());
    assert_eq!(nav.samples_done(), 100);
    // And it goes on exactly as if the refused call had not happened.
    let (mut a, mut b) = (Vec::new(), Vec::new());
    nav.process(&dth[..600], &dv[..600], 7, |s| a.push(*s)).unwrap();
    let mut twin = before;
    twin.process(&dth[..600], &dv[..600], 7, |s| b.push(*s)).unwrap();
    assert_eq!(a, b);
}
