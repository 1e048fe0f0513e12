//! Unit checks of the navigator (they need its private state).

use super::*;
use crate::attitude::{norm, quat_conj, quat_to_rotvec};

/// Increments of a tumbling body: a 1 rad/s rate whose axis turns by 0.3 rad per sample (strong coning,
/// so the previous-sample terms matter at 1e-5 rad per sample) and a wobbling specific force near 1 g.
fn tumbling(n: usize) -> (Vec<f64>, Vec<f64>) {
    let row = |k: usize| {
        let a = 0.3 * k as f64;
        (
            [0.01 * a.sin(), 0.01 * a.cos(), 0.002],
            [1e-3 * a.cos(), -1e-3 * (0.7 * a).sin(), 0.0981],
        )
    };
    let rows: Vec<_> = (0..n).map(row).collect();
    (
        rows.iter().flat_map(|r| r.0).collect(),
        rows.iter().flat_map(|r| r.1).collect(),
    )
}

/// Rotation angle between two attitude quaternions [rad].
fn angle_between(p: Quat, q: Quat) -> f64 {
    norm(quat_to_rotvec(quat_mul(p, quat_conj(q))))
}

#[test]
fn correct_removes_a_known_error_and_keeps_the_coning_memory() {
    let cfg = NavigatorConfig {
        attitude: Euler {
            pitch: 0.01,
            roll: 0.02,
            yaw: 1.0,
        },
        vel: [1.0, -2.0, 0.0],
        ..Default::default()
    };
    let (dth, dv) = tumbling(600);
    let (head, tail) = (3 * 300, 3 * 300..);
    let mut truth = Navigator::new(cfg.clone()).unwrap();
    truth.process(&dth[..head], &dv[..head], 1000, |_| {}).unwrap();

    // The same navigator with a known error: computed C_b^n' = (I - [phi x]) C_b^n, i.e. q' = q(-phi) o q,
    // and v' = v + dv (computed minus true).
    let phi = [3e-4, -2e-4, 1e-3];
    let dv_err = [0.05, -0.02, 0.0];
    let mut corrected = truth.clone();
    corrected.q = quat_mul(rotvec_to_quat(scale(phi, -1.0)), truth.q);
    corrected.vel = add(truth.vel, dv_err);
    // The sign convention: phi is the rotation from the computed to the true attitude, resolved in n.
    let seen = quat_to_rotvec(quat_mul(truth.q, quat_conj(corrected.q)));
    assert!(norm(sub(seen, phi)) < 1e-15, "{seen:?}");
    corrected.correct(phi, dv_err).unwrap();
    assert!(angle_between(corrected.q, truth.q) < 1e-15);
    assert!(norm(sub(corrected.vel, truth.vel)) < 1e-15);
    assert_eq!(corrected.samples_done(), truth.samples_done());

    // A restart from the same state (what the alignment did before `correct`) forgets the previous increments.
    let s = truth.state();
    let mut restarted = Navigator::new(NavigatorConfig {
        lat: s.lat,
        lon: s.lon,
        height: s.height,
        vel: s.vel,
        attitude: s.attitude,
        ..cfg
    })
    .unwrap();
    let (mut out_t, mut out_c) = (Vec::new(), Vec::new());
    truth
        .process(&dth[tail.clone()], &dv[tail.clone()], 1, |s| out_t.push(*s))
        .unwrap();
    corrected
        .process(&dth[tail.clone()], &dv[tail.clone()], 1, |s| out_c.push(*s))
        .unwrap();
    restarted.process(&dth[tail.clone()], &dv[tail], 1, |_| {}).unwrap();

    // The corrected run is the uninterrupted one to rounding, sample after sample.
    for (a, b) in out_t.iter().zip(&out_c) {
        assert_eq!(a.t, b.t);
        assert!(
            (a.lat - b.lat).abs() < 1e-15 && (a.lon - b.lon).abs() < 1e-15,
            "{a:?} {b:?}"
        );
        assert!(norm(sub(a.vel, b.vel)) < 1e-12, "{a:?} {b:?}");
    }
    let gap_corrected = angle_between(corrected.q, truth.q);
    let gap_restarted = angle_between(restarted.q, truth.q);
    println!("after 300 more samples: corrected run {gap_corrected:.1e} rad from the uninterrupted one, restarted run {gap_restarted:.1e} rad");
    assert!(gap_corrected < 1e-13, "{gap_corrected}");
    assert!(gap_restarted > 1e-7, "{gap_restarted}");
}

#[test]
fn correct_holds_the_fixed_vertical_channel_and_checks_its_input() {
    let mut nav = Navigator::new(NavigatorConfig::default()).unwrap();
    nav.correct([0.0; 3], [0.1, 0.2, 0.3]).unwrap();
    assert_eq!(nav.state().vel, [-0.1, -0.2, 0.0]);
    assert_eq!(nav.correct([f64::NAN, 0.0, 0.0], [0.0; 3]).unwrap_err().key(), "phi");
    assert_eq!(nav.correct([0.0; 3], [0.0, 2000.0, 0.0]).unwrap_err().key(), "dv");
    let mut damped = Navigator::new(NavigatorConfig {
        vertical: Vertical::Damped,
        ..Default::default()
    })
    .unwrap();
    damped.correct([0.0; 3], [0.0, 0.0, 0.3]).unwrap();
    assert_eq!(damped.state().vel, [0.0, 0.0, -0.3]);
}

#[test]
fn coning_correction_on_classic_coning_motion() {
    // Classic coning (Savage 2000, sec. 7.1.1.1): the exact attitude C(t) = Rz(W t) Rx(a) Rz(-W t) has a
    // body rate whose rotation vector sum misses the coning drift; the closed-form error rate of summing the
    // per-sample increments is W (1 - cos a) (1 - sin(W dt)/(W dt)) ~ (W a^2 / 2) (W dt)^2 / 6.
    let a: f64 = 0.01;
    let big_w: f64 = 2.0 * std::f64::consts::PI * 2.0; // 2 Hz coning
    let rate = 200.0;
    let dt = 1.0 / rate;
    let q_of = |t: f64| -> Quat {
        // q(t) = qz(W t) o qx(a) o qz(-W t)
        let qz = |ang: f64| [(0.5 * ang).cos(), 0.0, 0.0, (0.5 * ang).sin()];
        quat_mul(
            qz(big_w * t),
            quat_mul([(0.5 * a).cos(), (0.5 * a).sin(), 0.0, 0.0], qz(-big_w * t)),
        )
    };
    // Body rate from q' = 1/2 q o [0, w]: w = 2 q* o q'.
    let w_of = |t: f64| -> Vec3 {
        let h = 1e-6;
        let (qa, qb) = (q_of(t - h), q_of(t + h));
        let qd = [
            (qb[0] - qa[0]) / (2.0 * h),
            (qb[1] - qa[1]) / (2.0 * h),
            (qb[2] - qa[2]) / (2.0 * h),
            (qb[3] - qa[3]) / (2.0 * h),
        ];
        let w = quat_mul(quat_conj(q_of(t)), qd);
        [2.0 * w[1], 2.0 * w[2], 2.0 * w[3]]
    };
    let n = (10.0 * rate) as usize; // 10 s
    let run = |coning: bool| -> f64 {
        let mut q = q_of(0.0);
        let mut prev = [0.0; 3];
        for k in 0..n {
            let t0 = k as f64 * dt;
            // Gauss-Legendre 3 points per sample for the increment.
            let nodes = [
                (-0.774_596_669_241_483_4, 5.0 / 9.0),
                (0.0, 8.0 / 9.0),
                (0.774_596_669_241_483_4, 5.0 / 9.0),
            ];
            let mut d = [0.0; 3];
            for (x, wgt) in nodes {
                let w = w_of(t0 + 0.5 * dt * (1.0 + x));
                d = add(d, scale(w, 0.5 * dt * wgt));
            }
            let phi = if coning {
                coning_sculling(d, [0.0; 3], prev, [0.0; 3]).0
            } else {
                d
            };
            q = quat_mul(q, rotvec_to_quat(phi));
            prev = d;
        }
        let err = quat_to_rotvec(quat_mul(quat_conj(q_of(n as f64 * dt)), q));
        norm(err)
    };
    let drift_rate = big_w * (1.0 - a.cos());
    let wdt = big_w * dt;
    let uncorrected = run(false);
    let corrected = run(true);
    let expected = drift_rate * (1.0 - wdt.sin() / wdt) * 10.0;
    assert!(
        (uncorrected / expected - 1.0).abs() < 0.02,
        "{uncorrected} vs {expected}"
    );
    // The one-plus-previous algorithm leaves an error of order (W dt)^4.
    assert!(
        corrected < 0.01 * uncorrected,
        "corrected {corrected}, uncorrected {uncorrected}"
    );
}

#[test]
fn quaternion_norm_stays_unit_between_normalisations() {
    let mut nav = Navigator::new(NavigatorConfig {
        attitude: Euler {
            pitch: 0.01,
            roll: 0.02,
            yaw: 1.0,
        },
        ..Default::default()
    })
    .unwrap();
    let (dth, dv) = tumbling(20_000);
    let mut worst: f64 = 0.0;
    for (x, y) in dth.chunks_exact(3).zip(dv.chunks_exact(3)) {
        nav.step([x[0], x[1], x[2]], [y[0], y[1], y[2]]);
        let q = nav.quaternion();
        worst = worst.max(((q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt() - 1.0).abs());
    }
    println!("quaternion norm: max | |q| - 1 | over 20000 tumbling samples = {worst:.1e}");
    assert!(worst < 4e-15, "{worst}");
}

#[test]
fn process_equals_step_by_step_bit_for_bit() {
    // `process` runs the samples between outputs in a separate loop on a copy of the state; it must be the
    // per-sample `step` exactly, with bias compensation and across Earth-term refreshes.
    let cfg = NavigatorConfig {
        attitude: Euler {
            pitch: 0.01,
            roll: 0.02,
            yaw: 1.0,
        },
        vel: [1.0, -2.0, 0.5],
        vertical: Vertical::Damped,
        ..Default::default()
    };
    let (dth, dv) = tumbling(1000);
    let mut a = Navigator::new(cfg.clone()).unwrap();
    let mut b = Navigator::new(cfg).unwrap();
    for nav in [&mut a, &mut b] {
        nav.set_gyro_bias([1e-6, -2e-6, 3e-6]).unwrap();
        nav.set_accel_bias([1e-3, 2e-3, -3e-3]).unwrap();
    }
    let mut out_a = Vec::new();
    a.process(&dth, &dv, 37, |s| out_a.push(*s)).unwrap();
    let mut out_b = Vec::new();
    for (k, (x, y)) in dth.chunks_exact(3).zip(dv.chunks_exact(3)).enumerate() {
        b.step([x[0], x[1], x[2]], [y[0], y[1], y[2]]);
        if (k + 1) % 37 == 0 {
            out_b.push(b.state());
        }
    }
    assert_eq!(out_a, out_b);
    assert_eq!(a.quaternion(), b.quaternion());
    assert_eq!(a.state(), b.state());
}

/// Per-sample reference heights only.
fn heights(h: &[f64]) -> SampleInputs<'_> {
    SampleInputs {
        reference_height_m: Some(h),
        ..Default::default()
    }
}

/// Per-sample axial biases only.
fn axial(b: &[f64]) -> SampleInputs<'_> {
    SampleInputs {
        axial_bias_rad_s: Some(b),
        ..Default::default()
    }
}

#[test]
fn reference_heights_per_sample_or_set_once_and_refused_values() {
    let cfg = NavigatorConfig {
        vertical: Vertical::Damped,
        height: 10.0,
        ..Default::default()
    };
    let (dth, dv) = tumbling(500);
    let mut a = Navigator::new(cfg.clone()).unwrap();
    let mut b = Navigator::new(cfg).unwrap();
    a.process_with(&dth, &dv, heights(&[25.0; 500]), 50, |_| {}).unwrap();
    b.set_reference_height(25.0).unwrap();
    b.process(&dth, &dv, 50, |_| {}).unwrap();
    assert_eq!(a.state(), b.state());
    assert_eq!(a.reference_height(), 25.0);
    // A bad value anywhere leaves the navigator as it was, naming the sample.
    let before = a.state();
    let mut h = vec![25.0; 500];
    h[321] = f64::NAN;
    let err = a.process_with(&dth, &dv, heights(&h), 50, |_| {}).unwrap_err();
    assert_eq!(
        (err.key(), err.to_string().contains("sample 321")),
        ("reference_height_m", true)
    );
    h[321] = 30_000.0;
    assert!(a.process_with(&dth, &dv, heights(&h), 50, |_| {}).is_err());
    let err = a.process_with(&dth, &dv, heights(&h[..10]), 50, |_| {}).unwrap_err();
    assert_eq!(err.key(), "reference_height_m");
    assert_eq!(a.state(), before);
    assert!(a.set_reference_height(f64::INFINITY).is_err());
}

#[test]
fn chunking_and_decimation() {
    let cfg = NavigatorConfig {
        attitude: Euler {
            pitch: 0.01,
            roll: 0.02,
            yaw: 1.0,
        },
        ..Default::default()
    };
    let mut a = Navigator::new(cfg.clone()).unwrap();
    let mut b = Navigator::new(cfg).unwrap();
    let n = 1000;
    let dth: Vec<f64> = (0..3 * n).map(|i| 1e-5 * ((i as f64) * 0.37).sin()).collect();
    let dv: Vec<f64> = (0..3 * n)
        .map(|i| {
            if i % 3 == 2 {
                0.098
            } else {
                1e-3 * ((i as f64) * 0.11).cos()
            }
        })
        .collect();
    let mut out_a = Vec::new();
    a.process(&dth, &dv, 7, |s| out_a.push(*s)).unwrap();
    let mut out_b = Vec::new();
    for (x, y) in dth.chunks(3 * 13).zip(dv.chunks(3 * 13)) {
        b.process(x, y, 7, |s| out_b.push(*s)).unwrap();
    }
    assert_eq!(out_a, out_b);
    assert_eq!(out_a.len(), 1000 / 7);
    assert!((out_a[0].t - 0.07).abs() < 1e-15);
}

/// 0.004 deg/h in rad/s: an RLG's axial drift.
const DRIFT: f64 = 0.004 * std::f64::consts::PI / 180.0 / 3600.0;

#[test]
fn a_constant_axial_bias_per_sample_gives_the_bits_of_the_constant_bias() {
    let cfg = NavigatorConfig {
        attitude: Euler {
            pitch: 0.01,
            roll: 0.02,
            yaw: 1.0,
        },
        ..Default::default()
    };
    // 10 000 samples: more than two check blocks, with a decimation that does not divide them.
    let (dth, dv) = tumbling(10_000);
    let mut a = Navigator::new(cfg.clone()).unwrap();
    let mut b = Navigator::new(cfg).unwrap();
    a.set_gyro_bias([1e-6, -2e-6, DRIFT]).unwrap();
    b.set_gyro_bias([1e-6, -2e-6, 0.0]).unwrap();
    let (mut out_a, mut out_b) = (Vec::new(), Vec::new());
    a.process(&dth, &dv, 37, |s| out_a.push(*s)).unwrap();
    b.process_with(&dth, &dv, axial(&[DRIFT; 10_000]), 37, |s| out_b.push(*s))
        .unwrap();
    assert_eq!(out_a, out_b);
    assert_eq!(a.quaternion(), b.quaternion());
    assert_eq!(a.state(), b.state());
    // The last per-sample bias stays the estimate: both go on alike.
    assert_eq!(b.gyro_bias(), [1e-6, -2e-6, DRIFT]);
    a.process(&dth[..300], &dv[..300], 1, |_| {}).unwrap();
    b.process(&dth[..300], &dv[..300], 1, |_| {}).unwrap();
    assert_eq!(a.state(), b.state());
}

#[test]
fn a_step_in_the_axial_bias_is_two_runs_spliced_and_reaches_the_update() {
    let cfg = NavigatorConfig::default();
    let (dth, dv) = tumbling(6000);
    let split = 2500;
    let mut bias = vec![DRIFT; 6000];
    bias[split..].iter_mut().for_each(|b| *b = -3.0 * DRIFT);
    let mut stepped = Navigator::new(cfg.clone()).unwrap();
    let mut out_stepped = Vec::new();
    stepped
        .process_with(&dth, &dv, axial(&bias), 100, |s| out_stepped.push(*s))
        .unwrap();
    // The same with the bias set before each part (the state carried from the first part to the second).
    let mut spliced = Navigator::new(cfg.clone()).unwrap();
    let mut out_spliced = Vec::new();
    spliced.set_gyro_bias([0.0, 0.0, DRIFT]).unwrap();
    spliced
        .process(&dth[..3 * split], &dv[..3 * split], 100, |s| out_spliced.push(*s))
        .unwrap();
    spliced.set_gyro_bias([0.0, 0.0, -3.0 * DRIFT]).unwrap();
    spliced
        .process(&dth[3 * split..], &dv[3 * split..], 100, |s| out_spliced.push(*s))
        .unwrap();
    assert_eq!(out_stepped, out_spliced);
    assert_eq!(stepped.state(), spliced.state());
    // And it reaches the attitude: on a body at rest (no body rotation to turn the error), the attitude differs
    // from the constant bias's by the bias step times the time after it, about the z axis.
    let (still_a, still_b) = ([0.0; 3 * 6000], [0.0, 0.0, 0.0981].repeat(6000));
    let mut with_step = Navigator::new(cfg.clone()).unwrap();
    with_step
        .process_with(&still_a, &still_b, axial(&bias), 100, |_| {})
        .unwrap();
    let mut constant = Navigator::new(cfg).unwrap();
    constant.set_gyro_bias([0.0, 0.0, DRIFT]).unwrap();
    constant.process(&still_a, &still_b, 100, |_| {}).unwrap();
    let expected = 4.0 * DRIFT * (6000 - split) as f64 / 100.0;
    let seen = angle_between(with_step.quaternion(), constant.quaternion());
    assert!((seen - expected).abs() < 1e-6 * expected, "{seen} vs {expected}");
}

#[test]
fn axial_biases_refused_by_length_or_value_leave_the_navigator_as_it_was() {
    let (dth, dv) = tumbling(500);
    let mut a = Navigator::new(NavigatorConfig::default()).unwrap();
    a.set_gyro_bias([0.0, 0.0, DRIFT]).unwrap();
    a.process(&dth, &dv, 50, |_| {}).unwrap();
    let before = a.state();
    let err = a.process_with(&dth, &dv, axial(&[DRIFT; 499]), 50, |_| {}).unwrap_err();
    assert_eq!(err.key(), "axial_bias_rad_s");
    assert!(err.to_string().contains("499 values for 500 samples"), "{err}");
    let mut b = vec![DRIFT; 500];
    for bad in [f64::NAN, f64::INFINITY, 0.2] {
        b[123] = bad;
        let err = a.process_with(&dth, &dv, axial(&b), 50, |_| {}).unwrap_err();
        assert_eq!(err.key(), "axial_bias_rad_s");
        assert!(err.to_string().contains("sample 123"), "{err}");
    }
    // Both inputs at once: each checked.
    let h = [0.0; 500];
    let both = SampleInputs {
        reference_height_m: Some(&h),
        axial_bias_rad_s: Some(&b),
    };
    assert_eq!(
        a.process_with(&dth, &dv, both, 50, |_| {}).unwrap_err().key(),
        "axial_bias_rad_s"
    );
    assert_eq!(a.state(), before);
    assert_eq!(a.gyro_bias(), [0.0, 0.0, DRIFT]);
}
