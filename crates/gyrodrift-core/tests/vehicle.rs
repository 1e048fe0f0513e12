//! Moving-base simulation (`trajectory` composed with the turntable in `simulator`) against closed forms and
//! independent integrations, and an error-free IMU navigated along a road route.

use gyrodrift_core::attitude::{
    add, cross, dcm_to_quat, euler_to_dcm, mat_mul, mat_t_vec, norm, quat_conj, quat_mul, quat_to_rotvec, rot_z,
    rotvec_to_quat, scale, sub, Euler, Mat3,
};
use gyrodrift_core::earth::{self, NMI};
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::strapdown::{Navigator, NavigatorConfig, SampleInputs, Vertical};
use gyrodrift_core::trajectory::{Segment, TrajectoryConfig};
use gyrodrift_core::turntable::RotationScheme;
use gyrodrift_core::units::{DEG, HOUR};
use std::f64::consts::PI;

fn seg(duration: f64, accel: f64, yaw_rate: f64) -> Segment {
    Segment {
        duration,
        accel,
        yaw_rate,
        climb: 0.0,
    }
}

fn collect(cfg: ImuSimulatorConfig) -> ImuChunk {
    let mut sim = ImuSimulator::new(cfg).unwrap();
    let mut ch = ImuChunk::default();
    let n = sim.n_samples() as usize;
    assert_eq!(sim.next_chunk(n, &mut ch), n);
    ch
}

/// Meridian arc length [m] between two latitudes (Simpson, 2000 intervals: exact to ~1e-9 m here).
fn meridian_arc(l0: f64, l1: f64, h: f64) -> f64 {
    let m = 2000;
    let d = (l1 - l0) / m as f64;
    (0..=m)
        .map(|j| {
            let w = if j == 0 || j == m {
                1.0
            } else if j % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * (earth::meridian_radius(l0 + d * j as f64) + h)
        })
        .sum::<f64>()
        * d
        / 3.0
}

#[test]
fn straight_drive_along_a_meridian_matches_the_closed_form() {
    // Stand 10 s, accelerate at 2 m/s^2 for 10 s, then 20 m/s due north (yaw 0) for 200 s; level, no table.
    let (lat0, h, v) = (28.222 * DEG, 50.0, 20.0);
    let cfg = ImuSimulatorConfig {
        lat: lat0,
        lon: 1.0,
        height: h,
        rate_hz: 100.0,
        duration_s: 220.0,
        trajectory: Some(TrajectoryConfig {
            start_s: 10.0,
            segments: vec![seg(10.0, 2.0, 0.0), seg(200.0, 0.0, 0.0)],
            repeat: false,
        }),
        ..Default::default()
    };
    let ch = collect(cfg);
    let dt = 0.01;
    // Position: the distance driven along the meridian (100 m accelerating, then v t) is the arc length.
    for k in [999usize, 1999, 5000, 21_999] {
        let t = (k + 1) as f64 * dt;
        let s = if t <= 10.0 {
            0.0
        } else if t <= 20.0 {
            (t - 10.0) * (t - 10.0)
        } else {
            100.0 + v * (t - 20.0)
        };
        let arc = meridian_arc(lat0, ch.lat[k], h);
        assert!((arc - s).abs() < 1e-6, "t = {t}: arc {arc} m vs {s} m");
        assert!((ch.lon[k] - 1.0).abs() < 1e-15);
        assert!((ch.vel[3 * k + 1] - if t >= 20.0 { v } else { 2.0 * (t - 10.0).max(0.0) }).abs() < 1e-9);
    }
    // Cruise: w_ib^b = (-v / (R_M + h), w cos L, w sin L), f^b = (-2 w sin L v, 0, g - v^2 / (R_M + h)),
    // with L(t) linear within the sample (its curvature changes the integral by ~1e-20).
    for k in (2_100..22_000).step_by(997) {
        let (l0, l1) = (ch.lat[k - 1], ch.lat[k]);
        let m = 200;
        let (mut w, mut f) = ([0.0; 3], [0.0; 3]);
        for j in 0..=m {
            let x = j as f64 / m as f64;
            let l = l0 + x * (l1 - l0);
            let rm = earth::meridian_radius(l) + h;
            let wt = if j == 0 || j == m {
                1.0
            } else if j % 2 == 1 {
                4.0
            } else {
                2.0
            } * dt
                / (3.0 * m as f64);
            let wi = [-v / rm, earth::OMEGA_IE * l.cos(), earth::OMEGA_IE * l.sin()];
            let fi = [
                -2.0 * earth::OMEGA_IE * l.sin() * v,
                0.0,
                earth::normal_gravity(l, h) - v * v / rm,
            ];
            for i in 0..3 {
                w[i] += wt * wi[i];
                f[i] += wt * fi[i];
            }
        }
        for i in 0..3 {
            assert!((ch.dtheta[3 * k + i] - w[i]).abs() < 1e-17, "dtheta {k} {i}");
            assert!(
                (ch.dv[3 * k + i] - f[i]).abs() < 1e-14,
                "dv {k} {i}: {} vs {}",
                ch.dv[3 * k + i],
                f[i]
            );
        }
        assert!(ch.yaw[k].abs() < 1e-15 && ch.pitch[k] == 0.0);
    }
}

/// ENU -> ECEF rotation C_n^e at (lat, lon).
fn c_ne(lat: f64, lon: f64) -> Mat3 {
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    [[-so, -sl * co, cl * co], [co, -sl * so, cl * so], [0.0, cl, sl]]
}

#[test]
fn circle_with_a_rotating_table_matches_the_inertial_attitude_and_velocity() {
    // 15 m/s on a circle at 3 deg/s (radius 286 m), IMU tilted on the vehicle, reciprocating table.
    let (lat0, lon0, h) = (40.0 * DEG, 0.3, 100.0);
    let att = Euler {
        pitch: 0.4 * DEG,
        roll: -0.7 * DEG,
        yaw: 20.0 * DEG,
    };
    let cfg = ImuSimulatorConfig {
        lat: lat0,
        lon: lon0,
        height: h,
        rate_hz: 100.0,
        duration_s: 300.0,
        attitude: att,
        scheme: RotationScheme::Reciprocating {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
            span: 2.0 * PI,
            dwell: 0.0,
        },
        trajectory: Some(TrajectoryConfig {
            start_s: 5.0,
            segments: vec![seg(5.0, 3.0, 0.0), seg(1000.0, 0.0, 3.0 * DEG)],
            repeat: false,
        }),
        ..Default::default()
    };
    let ch = collect(cfg.clone());
    // Attitude: compose the angle increments (with the one-plus-previous coning term) and compare with the
    // truth C_b^i(t) = Rz_e(w_ie t) C_n^e(lat, lon) C_b^n(t), built from the true position and attitude only.
    let c_bn = |k: usize| {
        euler_to_dcm(Euler {
            pitch: ch.pitch[k],
            roll: ch.roll[k],
            yaw: ch.yaw[k],
        })
    };
    let c_bi =
        |t: f64, lat: f64, lon: f64, cbn: &Mat3| mat_mul(&rot_z(earth::OMEGA_IE * t), &mat_mul(&c_ne(lat, lon), cbn));
    let c0 = c_bi(0.0, lat0, lon0, &euler_to_dcm(att));
    let mut q = [1.0, 0.0, 0.0, 0.0];
    let mut prev = [0.0; 3];
    // Velocity in the inertial frame (ECEF axes at t = 0): v_i = C_e^i (v_e + w_ie x r_e); its change is
    // sum C_b^i dv + int (g_grav) dt, with the gravitation G = g^n-vector + w x (w x r) (normal gravity is
    // gravitation plus centrifugal).
    let n = ch.t_s.len();
    for k in 0..n {
        let d = [ch.dtheta[3 * k], ch.dtheta[3 * k + 1], ch.dtheta[3 * k + 2]];
        let phi = add(d, scale(cross(prev, d), 1.0 / 12.0));
        q = quat_mul(q, rotvec_to_quat(phi));
        prev = d;
        if (k + 1) % 1000 == 0 {
            let t = ch.t_s[k];
            let ct = c_bi(t, ch.lat[k], ch.lon[k], &c_bn(k));
            // q_b(t)^b(0) = C_b(0)^i' C_b(t)^i.
            let truth = dcm_to_quat(&mat_mul(&gyrodrift_core::attitude::transpose(&c0), &ct));
            let err = quat_to_rotvec(quat_mul(quat_conj(truth), q));
            // 1e-14 rad while standing; once the drive has started a bounded ~6e-10 rad (it does not grow over
            // the 290 s turn; 1e-4 arcsec, far below any navigation effect) from the steps of the route's
            // acceleration and turn rate, which the one-plus-previous-sample coning term models as smooth.
            assert!(norm(err) < 1e-9, "t = {t}: attitude error {err:?}");
        }
    }
    // Velocity: the true ENU velocity against the accelerometer increments resolved with the true attitude
    // (rotation compensation by the mid-sample attitude), Coriolis and gravity, over the whole turn.
    let mut v = [0.0; 3];
    for k in 1..n {
        let (la, lo) = (ch.lat[k - 1], ch.lon[k - 1]);
        let _ = lo;
        let vn = [ch.vel[3 * (k - 1)], ch.vel[3 * (k - 1) + 1], ch.vel[3 * (k - 1) + 2]];
        if k == 1 {
            v = vn;
        }
        let dvb = [ch.dv[3 * k], ch.dv[3 * k + 1], ch.dv[3 * k + 2]];
        let dth = [ch.dtheta[3 * k], ch.dtheta[3 * k + 1], ch.dtheta[3 * k + 2]];
        let dvb = add(dvb, scale(cross(dth, dvb), 0.5));
        let wie = earth::earth_rate_enu(la);
        let rm = earth::meridian_radius(la) + h;
        let rn = earth::transverse_radius(la) + h;
        let wen = [-v[1] / rm, v[0] / rn, v[0] * la.tan() / rn];
        let zeta = scale(add(wie, wen), 0.01);
        let dvn = mat_t_vec(&gyrodrift_core::attitude::transpose(&c_bn(k - 1)), dvb);
        let dvn = sub(dvn, scale(cross(zeta, dvn), 0.5));
        let cor = cross(add(scale(wie, 2.0), wen), v);
        let g = earth::normal_gravity(la, h);
        v = add(v, add(dvn, scale(sub([0.0, 0.0, -g], cor), 0.01)));
    }
    let last = [ch.vel[3 * (n - 1)], ch.vel[3 * (n - 1) + 1], ch.vel[3 * (n - 1) + 2]];
    // A second-order velocity update over 30 000 samples at 0.26 m/s^2 centripetal: within 1 mm/s.
    assert!(norm(sub(v, last)) < 1e-3, "{v:?} vs {last:?}");
    // The turn closes on itself: speed 15 m/s, yaw 20 + 3 (t - 10) deg.
    let speed = (last[0] * last[0] + last[1] * last[1]).sqrt();
    assert!((speed - 15.0).abs() < 1e-9);
}

/// A road route: stand, then accelerate, drive, turn, brake, stop, cycled.
pub fn road_loop() -> Vec<Segment> {
    vec![
        seg(10.0, 2.0, 0.0),       // to 20 m/s
        seg(600.0, 0.0, 0.0),      // 12 km straight
        seg(30.0, 0.0, 3.0 * DEG), // 90 deg left
        seg(300.0, 0.0, 0.0),
        seg(60.0, 0.0, -3.0 * DEG), // 180 deg right
        seg(10.0, -2.0, 0.0),       // brake to a stop
        seg(120.0, 0.0, 0.0),       // stop
        seg(5.0, 3.0, 0.0),         // to 15 m/s
        seg(45.0, 0.0, 2.0 * DEG),  // 90 deg left
        seg(900.0, 0.0, 0.0),
        seg(7.5, -2.0, 0.0), // stop
        seg(60.0, 0.0, 0.0),
    ]
}

/// Error-free IMU along the road loop: largest horizontal position error [m] and the final one.
fn navigate_route(hours: f64, static_s: f64) -> (f64, f64) {
    let cfg = ImuSimulatorConfig {
        lat: 28.222 * DEG,
        lon: 112.99 * DEG,
        height: 50.0,
        rate_hz: 100.0,
        duration_s: hours * HOUR,
        attitude: Euler {
            pitch: 0.0,
            roll: 0.0,
            yaw: 10.0 * DEG,
        },
        scheme: RotationScheme::Reciprocating {
            rate: 6.0 * DEG,
            accel: 100.0 * DEG,
            span: 2.0 * PI,
            dwell: 0.0,
        },
        trajectory: Some(TrajectoryConfig {
            start_s: static_s,
            segments: road_loop(),
            repeat: true,
        }),
        ..Default::default()
    };
    let mut nav = Navigator::new(NavigatorConfig {
        lat: cfg.lat,
        lon: cfg.lon,
        height: cfg.height,
        vel: [0.0; 3],
        attitude: cfg.attitude,
        rate_hz: cfg.rate_hz,
        vertical: Vertical::Fixed,
    })
    .unwrap();
    let mut sim = ImuSimulator::new(cfg).unwrap();
    let mut ch = ImuChunk::default();
    let (mut worst, mut last) = (0.0f64, 0.0);
    while sim.next_chunk(100_000, &mut ch) > 0 {
        let mut states = Vec::new();
        nav.process(&ch.dtheta, &ch.dv, 100, |s| states.push(*s)).unwrap();
        for s in &states {
            let k = ((s.t * 100.0).round() as i64 + ch.len() as i64 - 1 - sim.samples_done() as i64) as usize;
            let (lat, lon) = (ch.lat[k], ch.lon[k]);
            let dn = (s.lat - lat) * earth::meridian_radius(lat);
            let de = (s.lon - lon) * earth::transverse_radius(lat) * lat.cos();
            last = dn.hypot(de);
            worst = worst.max(last);
        }
    }
    (worst, last)
}

#[test]
fn error_free_imu_navigates_a_road_route() {
    let (worst, last) = navigate_route(3.0, 1800.0);
    eprintln!("error-free road route, 3 h: max {worst:.4} m, final {last:.4} m");
    assert!(worst < 0.01 * NMI / 24.0, "{worst} m");
}

/// The whole 72 h drive after a 16 h stand (run with `cargo test --release -- --ignored`).
#[test]
#[ignore]
fn error_free_imu_navigates_a_road_route_for_72_h() {
    let (worst, last) = navigate_route(88.0, 16.0 * HOUR);
    eprintln!(
        "error-free road route, 16 h + 72 h: max {:.3e} nmi, final {:.3e} nmi",
        worst / NMI,
        last / NMI
    );
    assert!(worst < 0.01 * NMI, "{worst} m");
}

/// A hilly road: 20 m/s with climbs and descents of 40-60 m over the straights (peak grade 0.5 %).
fn hilly_loop() -> Vec<Segment> {
    let climb = |duration: f64, climb: f64| Segment {
        duration,
        climb,
        ..Default::default()
    };
    vec![
        seg(10.0, 2.0, 0.0),
        climb(600.0, 60.0),
        seg(30.0, 0.0, 3.0 * DEG),
        climb(300.0, -40.0),
        seg(60.0, 0.0, -3.0 * DEG),
        climb(400.0, -20.0),
        seg(10.0, -2.0, 0.0),
        seg(60.0, 0.0, 0.0),
    ]
}

/// Error-free IMU along the hilly loop for 1 h with the damped vertical channel: (largest horizontal error [m],
/// largest |height error| [m], largest |v_U error| [m/s], largest true height change [m]). `reference`: the true
/// height per sample as the channel's reference (else the initial height).
fn navigate_hills(reference: bool) -> (f64, f64, f64, f64) {
    let cfg = ImuSimulatorConfig {
        lat: 28.222 * DEG,
        lon: 112.99 * DEG,
        height: 50.0,
        rate_hz: 100.0,
        duration_s: 3600.0,
        attitude: Euler {
            pitch: 0.3 * DEG,
            roll: -0.2 * DEG,
            yaw: 10.0 * DEG,
        },
        scheme: RotationScheme::Reciprocating {
            rate: 6.0 * DEG,
            accel: 100.0 * DEG,
            span: 2.0 * PI,
            dwell: 0.0,
        },
        trajectory: Some(TrajectoryConfig {
            start_s: 60.0,
            segments: hilly_loop(),
            repeat: true,
        }),
        ..Default::default()
    };
    let mut nav = Navigator::new(NavigatorConfig {
        lat: cfg.lat,
        lon: cfg.lon,
        height: cfg.height,
        vel: [0.0; 3],
        attitude: cfg.attitude,
        rate_hz: cfg.rate_hz,
        vertical: Vertical::Damped,
    })
    .unwrap();
    let mut sim = ImuSimulator::new(cfg.clone()).unwrap();
    let mut ch = ImuChunk::default();
    let (mut worst, mut worst_h, mut worst_vu, mut span_h) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    while sim.next_chunk(50_000, &mut ch) > 0 {
        let mut states = Vec::new();
        if reference {
            let heights = SampleInputs {
                reference_height_m: Some(&ch.height),
                ..Default::default()
            };
            nav.process_with(&ch.dtheta, &ch.dv, heights, 10, |s| states.push(*s))
                .unwrap();
        } else {
            nav.process(&ch.dtheta, &ch.dv, 10, |s| states.push(*s)).unwrap();
        }
        for s in &states {
            let k = ((s.t * 100.0).round() as i64 + ch.len() as i64 - 1 - sim.samples_done() as i64) as usize;
            let (lat, lon) = (ch.lat[k], ch.lon[k]);
            let dn = (s.lat - lat) * earth::meridian_radius(lat);
            let de = (s.lon - lon) * earth::transverse_radius(lat) * lat.cos();
            worst = worst.max(dn.hypot(de));
            worst_h = worst_h.max((s.height - ch.height[k]).abs());
            worst_vu = worst_vu.max((s.vel[2] - ch.vel[3 * k + 2]).abs());
            span_h = span_h.max((ch.height[k] - cfg.height).abs());
        }
    }
    (worst, worst_h, worst_vu, span_h)
}

#[test]
fn climbing_route_navigates_with_the_route_height_as_vertical_reference() {
    // The climbs are in the increments (vertical speed and acceleration, gravity and transport rate at the
    // height): with the true height as the damped channel's reference the navigated height and vertical speed
    // follow the truth (any vertical specific-force error a would settle at a / w_v^2 = 1e4 a metres); with the
    // initial height as reference the channel is pulled away from the true height by the climbs themselves.
    let (horiz, dh, dvu, span) = navigate_hills(true);
    eprintln!("hilly route, route height reference: horizontal {horiz:.4} m, height {dh:.2e} m, v_U {dvu:.2e} m/s (climbs up to {span:.0} m)");
    assert!(span > 50.0, "{span}");
    assert!(dh < 1e-2 && dvu < 1e-4, "{dh} m, {dvu} m/s");
    assert!(horiz < 0.5, "{horiz} m");
    let (horiz0, dh0, _, _) = navigate_hills(false);
    eprintln!("hilly route, initial height reference: horizontal {horiz0:.4} m, height {dh0:.1} m");
    assert!(dh0 > 10.0, "{dh0}");
}

#[test]
fn climbs_beyond_the_vehicle_limits_are_refused() {
    let base = ImuSimulatorConfig {
        duration_s: 100.0,
        trajectory: Some(TrajectoryConfig {
            start_s: 1.0,
            segments: vec![
                seg(5.0, 2.0, 0.0),
                Segment {
                    duration: 10.0,
                    climb: 200.0,
                    ..Default::default()
                },
            ],
            repeat: false,
        }),
        ..Default::default()
    };
    let err = ImuSimulator::new(base.clone()).unwrap_err().to_string();
    assert!(err.contains("segment 2: a climb of 200 m in 10 s"), "{err}");
    let mut low = base;
    low.trajectory.as_mut().unwrap().segments[1] = Segment {
        duration: 1000.0,
        climb: -2000.0,
        ..Default::default()
    };
    let err = ImuSimulator::new(low).unwrap_err().to_string();
    assert!(err.contains("ends at height -2000 m"), "{err}");
}

#[test]
fn increments_match_a_direct_fine_integration_while_turning_braking_and_climbing() {
    // The simulator evaluates the trigonometry and the Earth terms incrementally (addition theorem from the
    // start of each part, radii from the sine): compare with the defining integrals evaluated directly (libm
    // everywhere, the `earth` functions, the route's closed form through the public `Trajectory`) by Simpson's
    // rule on 200 sub-intervals per sample, on samples in a turn with a climb, in braking and across segment
    // boundaries, with a tilted IMU on a reciprocating table.
    use gyrodrift_core::trajectory::Trajectory;
    use gyrodrift_core::turntable::Turntable;
    let att = Euler {
        pitch: 0.6 * DEG,
        roll: -0.9 * DEG,
        yaw: 40.0 * DEG,
    };
    let (lat0, h0) = (35.0 * DEG, 300.0);
    let route = TrajectoryConfig {
        start_s: 2.0,
        segments: vec![
            seg(5.0, 3.0, 0.0),
            Segment {
                duration: 30.0,
                yaw_rate: 4.0 * DEG,
                climb: 12.0,
                ..Default::default()
            },
            Segment {
                duration: 7.5,
                accel: -2.0,
                climb: -3.0,
                ..Default::default()
            },
        ],
        repeat: true,
    };
    let scheme = RotationScheme::Reciprocating {
        rate: 6.0 * DEG,
        accel: 10.0 * DEG,
        span: 2.0 * PI,
        dwell: 0.5,
    };
    let cfg = ImuSimulatorConfig {
        lat: lat0,
        lon: 0.4,
        height: h0,
        rate_hz: 100.0,
        duration_s: 120.0,
        attitude: att,
        scheme: scheme.clone(),
        trajectory: Some(route.clone()),
        ..Default::default()
    };
    let ch = collect(cfg);
    let traj = Trajectory::new(&route, att.yaw, h0, 120.0).unwrap();
    let table = Turntable::new(scheme).unwrap();
    let c0 = euler_to_dcm(Euler { yaw: 0.0, ..att });
    let dt = 0.01;
    let mut cursor = 0;
    let (mut worst_w, mut worst_f) = (0.0f64, 0.0f64);
    for k in (1..12_000).step_by(61).chain([699, 700, 3_699, 3_700, 4_449, 4_450]) {
        let t0 = k as f64 * dt;
        let (l0, l1) = (ch.lat[k - 1], ch.lat[k]);
        let m = 200;
        let (mut w, mut f) = ([0.0; 3], [0.0; 3]);
        for j in 0..=m {
            let x = j as f64 / m as f64;
            let t = t0 + x * dt;
            let lat = l0 + x * (l1 - l0);
            // The segment boundaries fall on sample ends here: the closed form of the piece holding the sample.
            let kin = traj.motion(&mut cursor, t0 + 0.5 * dt, att.yaw).at(t);
            let (v, dvdt, h) = (kin.vel_enu(), kin.accel_enu(), kin.height);
            let (rm, rn) = (earth::meridian_radius(lat) + h, earth::transverse_radius(lat) + h);
            let wie = earth::earth_rate_enu(lat);
            let wen = [-v[1] / rm, v[0] / rn, v[0] * lat.tan() / rn];
            let cbn = mat_mul(&mat_mul(&rot_z(kin.yaw), &c0), &rot_z(table.angle(t)));
            let mut wi = mat_t_vec(&cbn, add(wie, wen));
            // Body rate of C_b^n = Rz(psi) C_0 Rz(alpha): psi' about n-Up and alpha' about b-Up.
            wi = add(wi, mat_t_vec(&cbn, [0.0, 0.0, kin.yaw_rate]));
            wi[2] += table.state(t).rate;
            let cor = cross(add(scale(wie, 2.0), wen), v);
            let g = earth::normal_gravity(lat, h);
            let fi = mat_t_vec(&cbn, [dvdt[0] + cor[0], dvdt[1] + cor[1], dvdt[2] + cor[2] + g]);
            let wt = if j == 0 || j == m {
                1.0
            } else if j % 2 == 1 {
                4.0
            } else {
                2.0
            } * dt
                / (3.0 * m as f64);
            for i in 0..3 {
                w[i] += wt * wi[i];
                f[i] += wt * fi[i];
            }
        }
        for i in 0..3 {
            worst_w = worst_w.max((ch.dtheta[3 * k + i] - w[i]).abs());
            worst_f = worst_f.max((ch.dv[3 * k + i] - f[i]).abs());
        }
    }
    eprintln!("moving base against direct integration: dtheta {worst_w:.1e} rad, dv {worst_f:.1e} m/s");
    // The z angle increment holds alpha(t1) - alpha(t0) of table angles up to 2 pi: 1e-15 rad of rounding; the
    // 1e-14 m/s of dv is the reference's own (the previous, all-libm simulator gave the same 9.9e-15 m/s).
    assert!(worst_w < 2e-15 && worst_f < 3e-14, "{worst_w} {worst_f}");
}
