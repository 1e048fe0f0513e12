//! Unit checks of the rotation schemes (they need its private state).

use super::*;
use std::f64::consts::{FRAC_PI_2, PI};

const RATE: f64 = DEFAULT_TABLE_RATE_RAD_S;
const ACC: f64 = 2.0 * DEG;

fn schemes() -> Vec<RotationScheme> {
    vec![
        RotationScheme::Continuous { rate: RATE, accel: ACC },
        RotationScheme::Continuous {
            rate: -RATE,
            accel: ACC,
        },
        RotationScheme::Reciprocating {
            rate: RATE,
            accel: ACC,
            span: 2.0 * PI,
            dwell: 0.0,
        },
        RotationScheme::Reciprocating {
            rate: RATE,
            accel: ACC,
            span: PI,
            dwell: 30.0,
        },
        RotationScheme::Reciprocating {
            rate: RATE,
            accel: ACC,
            span: 0.01,
            dwell: 1.0,
        },
        RotationScheme::Indexing {
            rate: RATE,
            accel: ACC,
            positions: vec![0.0, FRAC_PI_2, PI, 1.5 * PI],
            dwell: 300.0,
        },
        RotationScheme::Indexing {
            rate: RATE,
            accel: ACC,
            positions: vec![0.5, -2.0],
            dwell: 10.0,
        },
    ]
}

#[test]
fn angle_rate_accel_are_continuous_consistent_and_bounded() {
    for sch in schemes() {
        let tt = Turntable::new(sch.clone()).unwrap();
        let horizon = if tt.period() > 0.0 {
            3.0 * tt.period() + 100.0
        } else {
            600.0
        };
        let dt = 1e-3;
        let w_min = tt
            .segments
            .iter()
            .filter_map(|g| match g.kind {
                Kind::RampUp { peak } => Some(peak.abs()),
                _ => None,
            })
            .fold(f64::INFINITY, f64::min);
        let mut prev = tt.state(0.0);
        assert_eq!(prev.angle, 0.0);
        assert_eq!(prev.rate, 0.0);
        let mut t = dt;
        let mut max_rate: f64 = 0.0;
        while t < horizon {
            let s = tt.state(t);
            // Continuity: no jumps larger than what the bounds allow over dt.
            assert!(
                (s.angle - prev.angle).abs() <= RATE * dt * (1.0 + 1e-9) + 1e-12,
                "{sch:?} angle jump at {t}"
            );
            assert!(
                (s.rate - prev.rate).abs() <= ACC * dt * (1.0 + 1e-9) + 1e-12,
                "{sch:?} rate jump at {t}"
            );
            // Jerk of a cycloidal ramp peaks at pi accel^2 / (2 w_peak).
            assert!(
                (s.accel - prev.accel).abs() <= PI * ACC * ACC / (2.0 * w_min) * dt * 1.01 + 1e-12,
                "{sch:?} accel jump at {t}"
            );
            // Consistency: finite differences of angle and rate match rate and accel (central, O(dt^2)).
            let (a, b) = (tt.state(t - 1e-4), tt.state(t + 1e-4));
            assert!(
                ((b.angle - a.angle) / 2e-4 - s.rate).abs() < 1e-7,
                "{sch:?} rate at {t}"
            );
            assert!(
                ((b.rate - a.rate) / 2e-4 - s.accel).abs() < 1e-6,
                "{sch:?} accel at {t}"
            );
            assert!(s.accel.abs() <= ACC * (1.0 + 1e-12));
            max_rate = max_rate.max(s.rate.abs());
            prev = s;
            t += dt;
        }
        assert!(max_rate <= RATE * (1.0 + 1e-12));
        // The cursor evaluation agrees with the direct one.
        let mut cur = TableCursor::default();
        let mut t = 0.0;
        while t < horizon {
            let (a, b) = (tt.state(t), tt.state_at(&mut cur, t));
            assert!(
                (a.angle - b.angle).abs() < 1e-9 && (a.rate - b.rate).abs() < 1e-12,
                "{sch:?} cursor at {t}"
            );
            t += 0.0137;
        }
        // A cursor placed by cursor_at (no walk from the start) agrees too, at the time and from it on.
        for t0 in [0.0, 0.5 * horizon, 1000.0 * horizon + 0.3] {
            let mut cur = tt.cursor_at(t0);
            if !tt.segments.is_empty() {
                let g = &tt.segments[cur.seg];
                let (start, end) = (cur.base + g.t0, cur.base + g.t0 + g.duration);
                assert!(start <= t0 && t0 < end, "{sch:?} cursor_at({t0}) on [{start}, {end})");
            }
            for t in [t0, t0 + 0.07, t0 + 0.5 * horizon, t0 + 2.0 * horizon] {
                let (a, b) = (tt.state(t), tt.state_at(&mut cur, t));
                assert!((a.angle - b.angle).abs() < 1e-9, "{sch:?} cursor_at({t0}) at {t}");
            }
        }
        // Segment ends in closed form agree with evaluation.
        for (te, s) in tt.segment_ends() {
            if te.is_finite() {
                let e = tt.segments.iter().find(|g| g.t0 + g.duration == te).unwrap().eval(te);
                assert!((e.angle - s.angle).abs() < 1e-12 && (e.rate - s.rate).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn continuous_reaches_cruise_rate_and_the_angle_is_linear() {
    let tt = Turntable::new(RotationScheme::Continuous { rate: RATE, accel: ACC }).unwrap();
    let tr = 2.0 * RATE / ACC; // 6 s
    let s = tt.state(1000.0);
    assert!((s.rate - RATE).abs() < 1e-15);
    assert!((s.angle - (0.5 * RATE * tr + RATE * (1000.0 - tr))).abs() < 1e-10);
    // Half-way through the ramp the rate is half the cruise rate and the acceleration peaks.
    let h = tt.state(0.5 * tr);
    assert!((h.rate - 0.5 * RATE).abs() < 1e-15 && (h.accel - ACC).abs() < 1e-15);
}

#[test]
fn reciprocating_turns_span_and_back() {
    let span = 2.0 * PI;
    let tt = Turntable::new(RotationScheme::Reciprocating {
        rate: RATE,
        accel: ACC,
        span,
        dwell: 20.0,
    })
    .unwrap();
    let tr = 2.0 * RATE / ACC;
    let move_t = (span - RATE * tr) / RATE + 2.0 * tr;
    assert!((tt.period() - 2.0 * (move_t + 20.0)).abs() < 1e-9);
    let top = tt.state(move_t + 10.0);
    assert!((top.angle - span).abs() < 1e-12 && top.rate == 0.0);
    for k in 0..5 {
        let s = tt.state(k as f64 * tt.period() + 5.0);
        assert!((s.angle - tt.state(5.0).angle).abs() < 1e-9, "periodic");
        let b = tt.state((k + 1) as f64 * tt.period() - 10.0);
        assert!(b.angle.abs() < 1e-12 && b.rate == 0.0, "dwell at zero");
    }
}

#[test]
fn indexing_dwells_at_each_position() {
    let pos = vec![0.0, FRAC_PI_2, PI, 1.5 * PI];
    let dwell = 300.0;
    let tt = Turntable::new(RotationScheme::Indexing {
        rate: RATE,
        accel: ACC,
        positions: pos.clone(),
        dwell,
    })
    .unwrap();
    // Walk through two periods and check the middle of each dwell.
    let mut t = 0.0;
    let slew = |d: f64| {
        let tr = 2.0 * RATE / ACC;
        let d = d.abs();
        if d >= RATE * tr {
            (d - RATE * tr) / RATE + 2.0 * tr
        } else {
            2.0 * (2.0 * (ACC * d / 2.0).sqrt() / ACC)
        }
    };
    for _ in 0..2 {
        for i in 0..4 {
            let s = tt.state(t + 0.5 * dwell);
            assert!((s.angle - pos[i]).abs() < 1e-9, "position {i}: {s:?}");
            assert_eq!(s.rate, 0.0);
            t += dwell + slew(pos[(i + 1) % 4] - pos[i]);
        }
    }
    assert!((tt.period() - t / 2.0).abs() < 1e-9);
}

#[test]
fn modulation_residual_of_the_schemes() {
    let r = Turntable::new(RotationScheme::None).unwrap().modulation_residual();
    assert_eq!(r, (1.0, 0.0));
    // Reciprocating 2 pi reversing at heading 0: about 2 T_r / period left along heading 0.
    let tt = Turntable::new(RotationScheme::Reciprocating {
        rate: RATE,
        accel: ACC,
        span: 2.0 * PI,
        dwell: 0.0,
    })
    .unwrap();
    let (c, s) = tt.modulation_residual();
    let tr = 2.0 * RATE / ACC;
    assert!(s.abs() < 1e-9);
    assert!(
        c > 0.5 * 2.0 * tr / tt.period() && c < 1.5 * 2.0 * tr / tt.period(),
        "{c}"
    );
    // The balanced span removes it.
    let span = balanced_reciprocating_span(RATE, ACC, 0.0, 1).unwrap();
    assert!(span < 2.0 * PI && span > PI);
    let tb = Turntable::new(RotationScheme::Reciprocating {
        rate: RATE,
        accel: ACC,
        span,
        dwell: 0.0,
    })
    .unwrap();
    let (c, s) = tb.modulation_residual();
    assert!(c.hypot(s) < 1e-9, "{c} {s}");
    // 8-step indexing through four positions and back is balanced; [0, 90, 180, 270] with a -270 return is not.
    let d = PI / 2.0;
    let eight = Turntable::new(RotationScheme::Indexing {
        rate: RATE,
        accel: ACC,
        positions: vec![0.0, d, 2.0 * d, 3.0 * d, 4.0 * d, 3.0 * d, 2.0 * d, d],
        dwell: 300.0,
    })
    .unwrap();
    let (c, s) = eight.modulation_residual();
    assert!(c.hypot(s) < 1e-9, "{c} {s}");
    let four = Turntable::new(RotationScheme::Indexing {
        rate: RATE,
        accel: ACC,
        positions: vec![0.0, d, 2.0 * d, 3.0 * d],
        dwell: 300.0,
    })
    .unwrap();
    let (c, s) = four.modulation_residual();
    assert!(c.hypot(s) > 1e-3);
}

#[test]
fn bad_parameters_name_the_key() {
    let e = Turntable::new(RotationScheme::Continuous { rate: 0.0, accel: ACC }).unwrap_err();
    assert_eq!(e.key(), "rotation_rate_rad_s");
    let e = Turntable::new(RotationScheme::Continuous {
        rate: RATE,
        accel: -1.0,
    })
    .unwrap_err();
    assert_eq!(e.key(), "rotation_accel_rad_s2");
    let e = Turntable::new(RotationScheme::Indexing {
        rate: RATE,
        accel: ACC,
        positions: vec![],
        dwell: 1.0,
    })
    .unwrap_err();
    assert_eq!(e.key(), "positions_rad");
    let e = Turntable::new(RotationScheme::Reciprocating {
        rate: RATE,
        accel: ACC,
        span: f64::NAN,
        dwell: 0.0,
    })
    .unwrap_err();
    assert_eq!(e.key(), "reciprocating_span_rad");
}
