//! Turntable: the single-axis rotation schemes of the IMU about body Up.
//!
//! The table angle alpha(t) \[rad\] is positive counter-clockwise about body Up, and alpha(0) = 0 for every
//! scheme, so with the body attitude C_b0^n at table angle zero the true attitude is
//! C_b^n(t) = C_b0^n Rz(alpha(t)); with zero pitch and roll, yaw(t) = yaw0 + alpha(t).
//!
//! Every start, stop and reversal follows a cycloidal rate ramp (continuous acceleration, bounded jerk):
//! over a ramp of duration T_r from rate 0 to rate w,
//!     u = tau / T_r,  rate(tau) = w (u - sin(2 pi u) / (2 pi)),
//!     accel(tau) = (w / T_r)(1 - cos(2 pi u)),   peak accel 2 w / T_r = `accel`  =>  T_r = 2 w / accel,
//!     angle(tau) = w T_r (u^2 / 2 + (cos(2 pi u) - 1) / (4 pi^2)),  ramp angle w T_r / 2.
//! Acceleration is zero at both ends of every ramp, so rate and acceleration are continuous everywhere.
//! A move of signed angle D at cruise rate w: ramp up, cruise, ramp down; if |D| < w T_r the peak rate is
//! lowered to sqrt(accel |D| / 2) (no cruise). Angle, rate and acceleration are closed-form functions of t.
//!
//! Schemes:
//! - `None`: alpha = 0.
//! - `Continuous`: ramp up to the cruise rate (its sign is the direction), then rotate for ever.
//! - `Reciprocating`: move +span, dwell, move -span, dwell, repeat (span signed by the rate's sign). The angle
//!   is periodic and stays in [0, span]; `dwell` may be zero (direct reversal).
//! - `Indexing`: from 0 move to positions\[0\], dwell, move to positions\[1\], dwell, ..., move from the last
//!   position back to positions\[0\] and repeat. Moves go by the numeric difference of the (unwrapped)
//!   positions, so the table never accumulates net turns: e.g. [0, 90, 180, 270] deg slews +90, +90, +90 and
//!   then -270 back. The cruise rate's magnitude is used for every slew.

use crate::error::{check, check_with, CoreError, Unit};
use crate::units::DEG;
use std::f64::consts::TAU;

/// A rotation scheme about body Up (SI: rad, rad/s, rad/s^2, s).
#[derive(Clone, Debug, PartialEq)]
pub enum RotationScheme {
    None,
    Continuous {
        rate: f64,
        accel: f64,
    },
    Reciprocating {
        rate: f64,
        accel: f64,
        span: f64,
        dwell: f64,
    },
    Indexing {
        rate: f64,
        accel: f64,
        positions: Vec<f64>,
        dwell: f64,
    },
}

/// Table state at one time: angle \[rad\], rate [rad/s], acceleration [rad/s^2], all about body Up (CCW +).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct TableState {
    pub angle: f64,
    pub rate: f64,
    pub accel: f64,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    /// Cycloidal ramp from 0 to `peak` (signed) in `duration`.
    RampUp { peak: f64 },
    /// Cycloidal ramp from `peak` (signed) to 0 in `duration`.
    RampDown { peak: f64 },
    /// Constant rate.
    Cruise { rate: f64 },
    /// At rest.
    Dwell,
}

#[derive(Clone, Copy, Debug)]
struct Segment {
    t0: f64,
    duration: f64,
    angle0: f64,
    kind: Kind,
}

/// Cycloidal ramp from rate 0 to rate `w` over `tr`, evaluated at `tau` in [0, tr].
#[inline]
fn ramp_up(w: f64, tr: f64, tau: f64) -> TableState {
    let u = tau / tr;
    let (s, c) = (TAU * u).sin_cos();
    TableState {
        angle: w * tr * (0.5 * u * u + (c - 1.0) / (TAU * TAU)),
        rate: w * (u - s / TAU),
        accel: w / tr * (1.0 - c),
    }
}

impl Segment {
    #[inline]
    fn eval(&self, t: f64) -> TableState {
        let tau = t - self.t0;
        match self.kind {
            Kind::Dwell => TableState {
                angle: self.angle0,
                rate: 0.0,
                accel: 0.0,
            },
            Kind::Cruise { rate } => TableState {
                angle: self.angle0 + rate * tau,
                rate,
                accel: 0.0,
            },
            Kind::RampUp { peak } => {
                let s = ramp_up(peak, self.duration, tau);
                TableState {
                    angle: self.angle0 + s.angle,
                    ..s
                }
            }
            Kind::RampDown { peak } => {
                let s = ramp_up(peak, self.duration, tau);
                TableState {
                    angle: self.angle0 + peak * tau - s.angle,
                    rate: peak - s.rate,
                    accel: -s.accel,
                }
            }
        }
    }

    #[cfg(test)]
    fn end(&self) -> TableState {
        let t = self.t0 + self.duration;
        match self.kind {
            // Closed-form end values avoid rounding of sin/cos at u = 1.
            Kind::RampUp { peak } => TableState {
                angle: self.angle0 + 0.5 * peak * self.duration,
                rate: peak,
                accel: 0.0,
            },
            Kind::RampDown { peak } => TableState {
                angle: self.angle0 + 0.5 * peak * self.duration,
                rate: 0.0,
                accel: 0.0,
            },
            _ => self.eval(t),
        }
    }
}

/// The reciprocating span near `turns` full turns whose finite-acceleration reversals leave no first-harmonic
/// residual ([`Turntable::modulation_residual`] = 0): the extra time spent near the reversal headings is
/// balanced by shortening the span below 2 pi `turns`. Bisection on the residual's component along the
/// symmetry direction e^{i S / 2} (the residual of a symmetric move is parallel to it).
pub fn balanced_reciprocating_span(rate: f64, accel: f64, dwell: f64, turns: u32) -> Result<f64, CoreError> {
    check(turns >= 1, "turns", "must be at least 1")?;
    let component = |span: f64| -> Result<f64, CoreError> {
        let t = Turntable::new(RotationScheme::Reciprocating {
            rate,
            accel,
            span,
            dwell,
        })?;
        let (c, s) = t.modulation_residual();
        Ok(c * (0.5 * span).cos() + s * (0.5 * span).sin())
    };
    let full = TAU * turns as f64;
    let (mut lo, mut hi) = (full - std::f64::consts::PI, full);
    let (f_lo, f_hi) = (component(lo)?, component(hi)?);
    check(
        f_lo * f_hi <= 0.0,
        "rotation_accel_rad_s2",
        "too slow for a balanced span within half a turn",
    )?;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if component(mid)? * f_lo > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Default cruise rate of the table [rad/s] (6 deg/s; written (6 pi) / 180, one bit above `6.0 * DEG`, as every
/// simulated run so far has had it).
pub const DEFAULT_TABLE_RATE_RAD_S: f64 = 6.0 * std::f64::consts::PI / 180.0;
/// Default peak acceleration of starts, stops and reversals [rad/s^2] (100 deg/s^2: a ramp to 6 deg/s takes
/// 0.12 s and a 360 deg reciprocating span leaves 0.2 % of a horizontal error un-modulated).
pub const DEFAULT_TABLE_ACCEL_RAD_S2: f64 = 100.0 * DEG;
/// Default reciprocating span \[rad\] (one turn).
pub const DEFAULT_RECIPROCATING_SPAN_RAD: f64 = TAU;
/// Names of the schemes, as the binding and the scenario files spell them.
pub const SCHEME_NAMES: [&str; 4] = ["none", "continuous", "reciprocating", "indexing"];

/// Default indexing positions \[rad\]: 0, 90, 180, 270, 360, 270, 180, 90 deg, an order whose slews mirror each
/// other, so the modulation residual cancels exactly.
pub fn default_indexing_positions() -> Vec<f64> {
    use std::f64::consts::PI;
    vec![0.0, 0.5 * PI, PI, 1.5 * PI, 2.0 * PI, 1.5 * PI, PI, 0.5 * PI]
}

/// A scheme from its named settings (the keywords of the binding's `SimulatorConfig`); `None` takes the
/// defaults above. With `balanced` the reciprocating span becomes [`balanced_reciprocating_span`] near
/// round(span / 2 pi) turns (at least one).
pub fn scheme_from_settings(
    name: &str,
    rate: Option<f64>,
    accel: Option<f64>,
    span: Option<f64>,
    balanced: bool,
    positions: Option<Vec<f64>>,
    dwell: Option<f64>,
) -> Result<RotationScheme, CoreError> {
    let rate = rate.unwrap_or(DEFAULT_TABLE_RATE_RAD_S);
    let accel = accel.unwrap_or(DEFAULT_TABLE_ACCEL_RAD_S2);
    let dwell = dwell.unwrap_or(0.0);
    Ok(match name {
        "none" => RotationScheme::None,
        "continuous" => RotationScheme::Continuous { rate, accel },
        "reciprocating" => {
            let span = span.unwrap_or(DEFAULT_RECIPROCATING_SPAN_RAD);
            let span = if balanced {
                check_span(span)?;
                let turns = (span / TAU).round().max(1.0) as u32;
                balanced_reciprocating_span(rate, accel, dwell, turns)?
            } else {
                span
            };
            RotationScheme::Reciprocating {
                rate,
                accel,
                span,
                dwell,
            }
        }
        "indexing" => RotationScheme::Indexing {
            rate,
            accel,
            positions: positions.unwrap_or_else(default_indexing_positions),
            dwell,
        },
        other => {
            return Err(CoreError::Setting {
                key: "rotation_scheme",
                message: format!("expected one of {}, got {other:?}", SCHEME_NAMES.join(", ")),
            })
        }
    })
}

/// Most positions of an indexing cycle (real tables index through a handful; the profile and its modulation
/// residual cost grows with the number).
pub const MAX_INDEX_POSITIONS: usize = 1000;

/// Largest reciprocating span \[rad\] (about 159 turns).
pub const MAX_SPAN_RAD: f64 = 1000.0;

fn check_span(span: f64) -> Result<(), CoreError> {
    check_with(
        span.is_finite() && span > 0.0 && span <= MAX_SPAN_RAD,
        "reciprocating_span_rad",
        || {
            format!(
                "span {} is outside (0, {}]",
                Unit::Deg.show(span),
                Unit::Deg.show(MAX_SPAN_RAD)
            )
        },
    )
}

/// A stretch of constant table rate (see [`Turntable::uniform_at`]): angle(t) = angle0 + rate (t - start)
/// for start <= t <= end (absolute times \[s\], angle \[rad\], rate [rad/s]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformSegment {
    pub rate: f64,
    pub start: f64,
    pub end: f64,
    pub angle0: f64,
}

/// Position of a monotone time stream in a [`Turntable`] profile (see [`Turntable::state_at`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct TableCursor {
    seg: usize,
    n_period: u64,
    /// Time offset of the current repetition of the period [s].
    base: f64,
}

/// A turntable profile: exact closed-form angle, rate and acceleration as functions of time.
#[derive(Clone, Debug)]
pub struct Turntable {
    scheme: RotationScheme,
    /// One period of the profile (or the whole of it for `Continuous`).
    segments: Vec<Segment>,
    /// Period [s] for periodic schemes (angle returns to its value at `period_start`); 0 if not periodic.
    period: f64,
    /// Time at which periodic repetition starts (after an initial move for indexing) [s].
    period_start: f64,
    /// Segments before `period_start` that are not repeated.
    n_prefix: usize,
}

/// Build a move of signed angle `d` into `segs`, starting at (`t`, `angle`); returns the end time.
fn push_move(segs: &mut Vec<Segment>, t: f64, angle: f64, d: f64, rate: f64, accel: f64) -> f64 {
    if d == 0.0 {
        return t;
    }
    let sign = d.signum();
    let dist = d.abs();
    let mut w = rate.abs();
    let mut tr = 2.0 * w / accel;
    if dist < w * tr {
        w = (accel * dist / 2.0).sqrt();
        tr = 2.0 * w / accel;
    }
    let peak = sign * w;
    let cruise_t = (dist - w * tr) / w;
    let mut t = t;
    let mut a = angle;
    segs.push(Segment {
        t0: t,
        duration: tr,
        angle0: a,
        kind: Kind::RampUp { peak },
    });
    t += tr;
    a += 0.5 * peak * tr;
    if cruise_t > 0.0 {
        segs.push(Segment {
            t0: t,
            duration: cruise_t,
            angle0: a,
            kind: Kind::Cruise { rate: peak },
        });
        t += cruise_t;
        a += peak * cruise_t;
    }
    segs.push(Segment {
        t0: t,
        duration: tr,
        angle0: a,
        kind: Kind::RampDown { peak },
    });
    t + tr
}

fn push_dwell(segs: &mut Vec<Segment>, t: f64, angle: f64, dwell: f64) -> f64 {
    if dwell > 0.0 {
        segs.push(Segment {
            t0: t,
            duration: dwell,
            angle0: angle,
            kind: Kind::Dwell,
        });
    }
    t + dwell
}

/// Largest table rate [rad/s] (about 573 deg/s) and acceleration [rad/s^2] (about 5730 deg/s^2).
pub const MAX_TABLE_RATE_RAD_S: f64 = 10.0;
pub const MAX_TABLE_ACCEL_RAD_S2: f64 = 100.0;

fn check_rate_accel(rate: f64, accel: f64) -> Result<(), CoreError> {
    check_with(
        rate.is_finite() && rate != 0.0 && rate.abs() <= MAX_TABLE_RATE_RAD_S,
        "rotation_rate_rad_s",
        || {
            format!(
                "table rate {} must be non-zero and within +-{}",
                Unit::DegPerS.show(rate),
                Unit::DegPerS.show(MAX_TABLE_RATE_RAD_S)
            )
        },
    )?;
    check_with(
        accel.is_finite() && accel > 0.0 && accel <= MAX_TABLE_ACCEL_RAD_S2,
        "rotation_accel_rad_s2",
        || {
            format!(
                "table acceleration {} is outside (0, {}]",
                Unit::DegPerS2.show(accel),
                Unit::DegPerS2.show(MAX_TABLE_ACCEL_RAD_S2)
            )
        },
    )
}

impl Turntable {
    /// Build and validate a profile.
    pub fn new(scheme: RotationScheme) -> Result<Self, CoreError> {
        let mut segs = Vec::new();
        let (period, period_start, n_prefix);
        match &scheme {
            RotationScheme::None => {
                period = 0.0;
                period_start = 0.0;
                n_prefix = 0;
            }
            RotationScheme::Continuous { rate, accel } => {
                check_rate_accel(*rate, *accel)?;
                let tr = 2.0 * rate.abs() / accel;
                segs.push(Segment {
                    t0: 0.0,
                    duration: tr,
                    angle0: 0.0,
                    kind: Kind::RampUp { peak: *rate },
                });
                segs.push(Segment {
                    t0: tr,
                    duration: f64::INFINITY,
                    angle0: 0.5 * rate * tr,
                    kind: Kind::Cruise { rate: *rate },
                });
                period = 0.0;
                period_start = 0.0;
                n_prefix = 0;
            }
            RotationScheme::Reciprocating {
                rate,
                accel,
                span,
                dwell,
            } => {
                check_rate_accel(*rate, *accel)?;
                check_span(*span)?;
                check_with(dwell.is_finite() && *dwell >= 0.0, "dwell_s", || {
                    format!("dwell {} s must be >= 0 and finite", crate::error::sig(*dwell))
                })?;
                let d = span * rate.signum();
                let mut t = push_move(&mut segs, 0.0, 0.0, d, *rate, *accel);
                t = push_dwell(&mut segs, t, d, *dwell);
                t = push_move(&mut segs, t, d, -d, *rate, *accel);
                t = push_dwell(&mut segs, t, 0.0, *dwell);
                period = t;
                period_start = 0.0;
                n_prefix = 0;
            }
            RotationScheme::Indexing {
                rate,
                accel,
                positions,
                dwell,
            } => {
                check_rate_accel(*rate, *accel)?;
                check_with(
                    !positions.is_empty() && positions.len() <= MAX_INDEX_POSITIONS,
                    "positions_rad",
                    || {
                        format!(
                        "{} positions, expected 1 to {MAX_INDEX_POSITIONS} (the cycle's profile and its modulation \
                         residual grow with their number)",
                        positions.len()
                    )
                    },
                )?;
                check_with(
                    positions.iter().all(|p| p.is_finite() && p.abs() <= 1000.0),
                    "positions_rad",
                    || format!("positions must be finite and within +-{}", Unit::Deg.show(1000.0)),
                )?;
                check_with(dwell.is_finite() && *dwell >= 0.0, "dwell_s", || {
                    format!("dwell {} s must be >= 0 and finite", crate::error::sig(*dwell))
                })?;
                // Prefix: move from 0 to positions[0].
                let mut t = push_move(&mut segs, 0.0, 0.0, positions[0], *rate, *accel);
                n_prefix = segs.len();
                period_start = t;
                let n = positions.len();
                for i in 0..n {
                    t = push_dwell(&mut segs, t, positions[i], *dwell);
                    let next = positions[(i + 1) % n];
                    t = push_move(&mut segs, t, positions[i], next - positions[i], *rate, *accel);
                }
                period = t - period_start;
                check(
                    period > 0.0,
                    "positions_rad",
                    "with dwell_s = 0 the positions must not all be equal",
                )?;
            }
        }
        Ok(Turntable {
            scheme,
            segments: segs,
            period,
            period_start,
            n_prefix,
        })
    }

    /// The scheme this profile was built from.
    pub fn scheme(&self) -> &RotationScheme {
        &self.scheme
    }

    /// Period of the profile \[s\] (0 for `None` and `Continuous`).
    pub fn period(&self) -> f64 {
        self.period
    }

    /// True if the table never moves.
    pub fn is_static(&self) -> bool {
        self.segments.is_empty()
    }

    /// Angle \[rad\], rate [rad/s] and acceleration [rad/s^2] at time t >= 0 \[s\].
    #[inline]
    pub fn state(&self, t: f64) -> TableState {
        if self.segments.is_empty() {
            return TableState::default();
        }
        let (segs, tt) = if self.period > 0.0 && t >= self.period_start {
            let tau = (t - self.period_start) % self.period;
            (&self.segments[self.n_prefix..], self.period_start + tau)
        } else {
            (&self.segments[..], t)
        };
        // Last segment starting at or before tt.
        let i = segs.partition_point(|s| s.t0 <= tt).saturating_sub(1);
        segs[i].eval(tt)
    }

    /// State at time t \[s\] using `cursor` to find the segment: O(1) for non-decreasing times, identical in
    /// value to [`Turntable::state`] up to rounding of the period offset. Use one cursor per time stream.
    #[inline]
    pub fn state_at(&self, cursor: &mut TableCursor, t: f64) -> TableState {
        if self.segments.is_empty() {
            return TableState::default();
        }
        if t < cursor.base + self.segments[cursor.seg].t0 {
            *cursor = TableCursor::default();
        }
        loop {
            let s = &self.segments[cursor.seg];
            if t < cursor.base + s.t0 + s.duration {
                return s.eval(t - cursor.base);
            }
            cursor.seg += 1;
            if cursor.seg == self.segments.len() {
                if self.period > 0.0 {
                    cursor.n_period += 1;
                    cursor.seg = self.n_prefix;
                    cursor.base = cursor.n_period as f64 * self.period;
                } else {
                    // Only `Continuous` ends in an infinite cruise; keep it (guards against t = inf).
                    cursor.seg -= 1;
                    return self.segments[cursor.seg].eval(t - cursor.base);
                }
            }
        }
    }

    /// A cursor at time t >= 0 \[s\] for [`Turntable::state_at`] and [`Turntable::uniform_at`] from t on, found
    /// as [`Turntable::state`] finds its segment (no walk through the earlier periods).
    pub fn cursor_at(&self, t: f64) -> TableCursor {
        if self.segments.is_empty() || !(self.period > 0.0 && t >= self.period_start) {
            let seg = self.segments.partition_point(|s| s.t0 <= t).saturating_sub(1);
            return TableCursor {
                seg,
                ..TableCursor::default()
            };
        }
        let mut n_period = ((t - self.period_start) / self.period).floor() as u64;
        let mut base = n_period as f64 * self.period;
        if n_period > 0 && t < base + self.period_start {
            n_period -= 1; // rounding put t just before this period's start
            base = n_period as f64 * self.period;
        }
        let segs = &self.segments[self.n_prefix..];
        let seg = self.n_prefix + segs.partition_point(|s| s.t0 <= t - base).saturating_sub(1);
        TableCursor { seg, n_period, base }
    }

    /// If the segment holding time t (found through `cursor`, as in [`Turntable::state_at`]) turns at a
    /// constant rate (a cruise, a dwell, or the whole of `None`), that segment; `None` during ramps. Lets a
    /// caller reuse per-sample trigonometry and evaluate the angle without a segment search.
    #[inline]
    pub fn uniform_at(&self, cursor: &mut TableCursor, t: f64) -> Option<UniformSegment> {
        if self.segments.is_empty() {
            return Some(UniformSegment {
                rate: 0.0,
                start: 0.0,
                end: f64::INFINITY,
                angle0: 0.0,
            });
        }
        self.state_at(cursor, t);
        let s = &self.segments[cursor.seg];
        let (start, end) = (cursor.base + s.t0, cursor.base + s.t0 + s.duration);
        match s.kind {
            Kind::Cruise { rate } => Some(UniformSegment {
                rate,
                start,
                end,
                angle0: s.angle0,
            }),
            Kind::Dwell => Some(UniformSegment {
                rate: 0.0,
                start,
                end,
                angle0: s.angle0,
            }),
            _ => None,
        }
    }

    /// Angle \[rad\] at time t \[s\].
    #[inline]
    pub fn angle(&self, t: f64) -> f64 {
        self.state(t).angle
    }

    /// Time average over one period of (cos alpha, sin alpha): the fraction of a body-fixed horizontal sensor
    /// error that the scheme leaves un-modulated in the navigation frame (relative to the table-zero heading).
    /// (1, 0) for `None`; for `Continuous` the average over one revolution of the cruise, i.e. (0, 0).
    /// Slow starts, stops and dwells weight their headings more, so a reciprocating scheme that reverses at
    /// the same heading (span 2 pi) leaves about 2 T_r / period, T_r = 2 rate / accel; see
    /// [`balanced_reciprocating_span`].
    pub fn modulation_residual(&self) -> (f64, f64) {
        match self.scheme {
            RotationScheme::None => return (1.0, 0.0),
            RotationScheme::Continuous { .. } => return (0.0, 0.0),
            _ => {}
        }
        let segs = &self.segments[self.n_prefix..];
        let (mut c, mut s) = (0.0, 0.0);
        // Gauss-Legendre 4 points on pieces of at most 0.05 rad of table travel (error < 1e-12).
        const X: [f64; 4] = [
            -0.861_136_311_594_052_6,
            -0.339_981_043_584_856_3,
            0.339_981_043_584_856_3,
            0.861_136_311_594_052_6,
        ];
        const W: [f64; 4] = [
            0.347_854_845_137_453_9,
            0.652_145_154_862_546_1,
            0.652_145_154_862_546_1,
            0.347_854_845_137_453_9,
        ];
        for g in segs {
            let travel = match g.kind {
                Kind::Dwell => 0.0,
                Kind::Cruise { rate } => rate.abs() * g.duration,
                Kind::RampUp { peak } | Kind::RampDown { peak } => 0.5 * peak.abs() * g.duration,
            };
            let n = ((travel / 0.05).ceil() as usize).max(1);
            let h = g.duration / n as f64;
            for i in 0..n {
                let mid = g.t0 + (i as f64 + 0.5) * h;
                for j in 0..4 {
                    let a = g.eval(mid + 0.5 * h * X[j]).angle;
                    c += 0.5 * h * W[j] * a.cos();
                    s += 0.5 * h * W[j] * a.sin();
                }
            }
        }
        (c / self.period, s / self.period)
    }

    /// Largest rate magnitude any segment reaches [rad/s].
    pub fn max_rate(&self) -> f64 {
        self.segments
            .iter()
            .map(|s| match s.kind {
                Kind::RampUp { peak } | Kind::RampDown { peak } => peak.abs(),
                Kind::Cruise { rate } => rate.abs(),
                Kind::Dwell => 0.0,
            })
            .fold(0.0, f64::max)
    }

    #[cfg(test)]
    fn segment_ends(&self) -> Vec<(f64, TableState)> {
        self.segments.iter().map(|s| (s.t0 + s.duration, s.end())).collect()
    }
}

#[cfg(test)]
mod tests;
