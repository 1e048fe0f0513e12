//! Checks of the simulator against numerical integration and the DCM route.

use super::table::{GL2_HI, GL2_LO};
use super::*;
use crate::attitude::{
    add, dcm_to_euler, euler_to_quat, mat_mul, norm, quat_conj, quat_mul, quat_to_rotvec, rot_z, rotvec_to_quat, sub,
    Euler,
};
use crate::turntable::RotationScheme;

fn rotating(level: bool) -> ImuSimulatorConfig {
    ImuSimulatorConfig {
        rate_hz: 50.0,
        duration_s: 200.0,
        attitude: if level {
            Euler {
                pitch: 0.0,
                roll: 0.0,
                yaw: 0.3,
            }
        } else {
            Euler {
                pitch: 0.02,
                roll: -0.03,
                yaw: 0.3,
            }
        },
        scheme: RotationScheme::Reciprocating {
            rate: 0.3,
            accel: 0.2,
            span: 3.0,
            dwell: 2.0,
        },
        ..Default::default()
    }
}

#[test]
fn increments_match_a_fine_numerical_integration() {
    for level in [true, false] {
        let cfg = rotating(level);
        let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
        let mut ch = ImuChunk::default();
        let n = sim.next_chunk(2000, &mut ch);
        assert_eq!(n, 2000);
        let c_b0n = euler_to_dcm(cfg.attitude);
        let wie = earth::earth_rate_enu(cfg.lat);
        let g = earth::normal_gravity(cfg.lat, cfg.height);
        let table = Turntable::new(cfg.scheme.clone()).unwrap();
        for k in (0..2000).step_by(37) {
            // Simpson with 200 sub-intervals per sample.
            let (t0, dt) = (k as f64 * 0.02, 0.02);
            let m = 200;
            let mut sw = [0.0; 3];
            let mut sf = [0.0; 3];
            for j in 0..=m {
                let t = t0 + dt * j as f64 / m as f64;
                let st = table.state(t);
                let cbn = mat_mul(&c_b0n, &rot_z(st.angle));
                let w = add(mat_t_vec(&cbn, wie), [0.0, 0.0, st.rate]);
                let f = mat_t_vec(&cbn, [0.0, 0.0, g]);
                let wt = if j == 0 || j == m {
                    1.0
                } else if j % 2 == 1 {
                    4.0
                } else {
                    2.0
                } * dt
                    / (3.0 * m as f64);
                for i in 0..3 {
                    sw[i] += wt * w[i];
                    sf[i] += wt * f[i];
                }
            }
            let dth = [ch.dtheta[3 * k], ch.dtheta[3 * k + 1], ch.dtheta[3 * k + 2]];
            let dv = [ch.dv[3 * k], ch.dv[3 * k + 1], ch.dv[3 * k + 2]];
            assert!(norm(sub(dth, sw)) < 1e-14, "{k}: {dth:?} vs {sw:?}");
            // Two-point Gauss-Legendre is exact for cubics; at a ramp start alpha ~ t^4 and the quadrature
            // error reaches ~1e-13 m/s on 6e-3 m/s (3e-12 m/s^2 while the ramp starts: negligible).
            assert!(norm(sub(dv, sf)) < 1e-12, "{k}: {dv:?} vs {sf:?}");
            // True attitude = C_b0^n Rz(alpha).
            let e = dcm_to_euler(&mat_mul(&c_b0n, &rot_z(table.angle(t0 + dt))));
            assert!((ch.yaw[k] - e.yaw).abs() < 1e-12 && (ch.pitch[k] - e.pitch).abs() < 1e-12);
        }
    }
}

#[test]
fn summed_increments_give_the_true_attitude_change() {
    // Integrating dtheta with exact rotation-vector composition (tiny steps) must track the body relative
    // to inertial space; compare against C_b^i(t) = C_n^i(t) C_b^n(t) with C_n^i = Rz_polar(w_ie t).
    let cfg = rotating(false);
    let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
    let mut ch = ImuChunk::default();
    sim.next_chunk(5000, &mut ch);
    let mut q = QUAT0;
    let mut prev = [0.0; 3];
    for k in 0..5000 {
        let d = [ch.dtheta[3 * k], ch.dtheta[3 * k + 1], ch.dtheta[3 * k + 2]];
        // One-plus-previous-sample coning correction.
        let phi = add(d, crate::attitude::scale(crate::attitude::cross(prev, d), 1.0 / 12.0));
        q = quat_mul(q, rotvec_to_quat(phi));
        prev = d;
    }
    // Truth: q_{b(t)}^{b(0)} = q_n^b(0) o q_{n(t)}^{n(0)} o q_b^n(t); n rotates about the polar axis,
    // which in ENU is w_ie^n / w_ie, by w_ie t.
    let t = 100.0;
    let pol = earth::earth_rate_enu(cfg.lat);
    let qn = rotvec_to_quat([pol[0] * t, pol[1] * t, pol[2] * t]);
    let qb0 = euler_to_quat(cfg.attitude);
    let table = Turntable::new(cfg.scheme.clone()).unwrap();
    let qbt = quat_mul(qb0, rotvec_to_quat([0.0, 0.0, table.angle(t)]));
    let truth = quat_mul(quat_conj(qb0), quat_mul(qn, qbt));
    let err = quat_to_rotvec(quat_mul(quat_conj(truth), q));
    // With the coning correction the composition reproduces the true rotation to rounding level.
    assert!(norm(err) < 1e-11, "{err:?}");
}

const QUAT0: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

#[test]
fn fast_true_attitude_equals_the_dcm_route() {
    for (p, r, y) in [
        (0.02, -0.03, 0.3),
        (0.0, 0.09, -3.1),
        (-0.3, 0.5, 2.0),
        (0.001, 0.0, 3.1),
    ] {
        let cfg = ImuSimulatorConfig {
            attitude: Euler {
                pitch: p,
                roll: r,
                yaw: y,
            },
            scheme: RotationScheme::Continuous { rate: 1.0, accel: 1.0 },
            duration_s: 20.0,
            ..Default::default()
        };
        let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
        let mut ch = ImuChunk::default();
        sim.next_chunk(2000, &mut ch);
        let c_b0n = euler_to_dcm(cfg.attitude);
        for k in (0..2000).step_by(7) {
            let e = dcm_to_euler(&mat_mul(&c_b0n, &rot_z(ch.table_angle[k])));
            assert!((ch.pitch[k] - e.pitch).abs() < 1e-13, "pitch {k}");
            assert!((ch.roll[k] - e.roll).abs() < 1e-13, "roll {k}");
            let dy = (ch.yaw[k] - e.yaw).abs();
            assert!(
                dy.min((dy - 2.0 * std::f64::consts::PI).abs()) < 1e-13,
                "yaw {k}: {} {}",
                ch.yaw[k],
                e.yaw
            );
        }
    }
}

#[test]
fn constant_rate_shortcut_matches_direct_quadrature_late_in_a_long_run() {
    // Cruise and dwell samples take the constant-rate path (fixed rotations of sin/cos, resynchronised
    // every SINCOS_RESYNC samples); compare with the two-point quadrature from libm sin/cos at the nodes.
    for scheme in [
        RotationScheme::Continuous { rate: 1.0, accel: 2.0 },
        RotationScheme::Indexing {
            rate: 0.5,
            accel: 1.0,
            positions: vec![0.0, 1.0, 2.5],
            dwell: 3.0,
        },
    ] {
        let cfg = ImuSimulatorConfig {
            rate_hz: 100.0,
            duration_s: 2000.0,
            attitude: Euler {
                pitch: 0.01,
                roll: 0.02,
                yaw: 1.0,
            },
            scheme,
            ..Default::default()
        };
        let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
        let mut ch = ImuChunk::default();
        let mut first = 0usize;
        while sim.next_chunk(30_000, &mut ch) == 30_000 && sim.samples_done() < 180_000 {
            first += 30_000;
        }
        let c_b0n = euler_to_dcm(cfg.attitude);
        let u = mat_t_vec(&c_b0n, earth::earth_rate_enu(cfg.lat));
        let table = Turntable::new(cfg.scheme.clone()).unwrap();
        let dt = 0.01;
        for i in (0..ch.len()).step_by(97) {
            let t0 = (first + i) as f64 * dt;
            let (a_lo, a_hi) = (table.angle(t0 + GL2_LO * dt), table.angle(t0 + GL2_HI * dt));
            let ic = 0.5 * dt * (a_lo.cos() + a_hi.cos());
            let is = 0.5 * dt * (a_lo.sin() + a_hi.sin());
            let ex = [ic * u[0] + is * u[1], -is * u[0] + ic * u[1]];
            for (j, want) in ex.iter().enumerate() {
                let got = ch.dtheta[3 * i + j];
                assert!((got - want).abs() < 1e-18, "{i} {j}: {got} vs {want}");
            }
            assert!((ch.table_angle[i] - table.angle(t0 + dt)).abs() < 1e-9);
        }
    }
}

#[test]
fn chunking_does_not_change_the_output() {
    let mut cfg = rotating(false);
    cfg.errors.gyro_arw = 1e-6;
    cfg.errors.accel_vrw = 1e-5;
    cfg.errors.gyro_bias_instability = 1e-7;
    let mut a = ImuSimulator::new(cfg.clone()).unwrap();
    let mut b = ImuSimulator::new(cfg).unwrap();
    let mut ca = ImuChunk::default();
    a.next_chunk(10_000, &mut ca);
    let mut all = Vec::new();
    let mut cb = ImuChunk::default();
    while b.next_chunk(333, &mut cb) > 0 {
        all.extend_from_slice(&cb.dtheta);
    }
    assert_eq!(ca.dtheta, all);
    assert_eq!(a.next_chunk(5, &mut ca), 0);
}
