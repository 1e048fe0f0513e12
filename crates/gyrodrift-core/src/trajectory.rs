//! Land-vehicle trajectory: the true motion of the vehicle carrying the turntable, in closed form per segment.
//!
//! The vehicle stands still at the site until `start_s` (the static alignment/identification period), then
//! drives a route of segments. Each segment lasts `duration` \[s\] with a constant longitudinal acceleration
//! `accel` [m/s^2] and a constant yaw rate `yaw_rate` [rad/s] (straight: both 0; turn: yaw rate at constant
//! speed; accelerate/brake: accel; stop: both 0 at speed 0). Within a segment starting at t0 with speed v0
//! and vehicle yaw psi0:
//!     v(t) = v0 + accel (t - t0),   psi(t) = psi0 + yaw_rate (t - t0),
//! and the velocity in ENU is v^n = v (-sin psi, cos psi, 0) (body forward is y, yaw CCW about Up, so the
//! heading clockwise from North is -psi), its derivative
//!     dv^n/dt = accel (-sin psi, cos psi, 0) + v yaw_rate (-cos psi, -sin psi, 0).
//! Height: a segment may change the height by `climb` \[m\] along a smooth profile that starts and ends
//! with zero vertical speed, h(t) = h0 + climb (1 - cos(pi tau / T)) / 2 (tau = t - t0, T the duration), so
//!     v_U = climb pi / (2 T) sin(pi tau / T),   dv_U/dt = climb pi^2 / (2 T^2) cos(pi tau / T),
//! the vertical velocity is continuous across segments and the ENU velocity is (.., .., v_U). The vehicle body
//! stays level while it climbs (its attitude is its yaw alone). Without climbs the route is level at the
//! site's height. After the last segment the vehicle goes on straight at its last speed and height (usually 0
//! after a stop); with `repeat` the segments are driven again and again.
//!
//! Position is the one quantity without a closed form on the ellipsoid: lat' = v_N / (R_M(lat) + h),
//! lon' = v_E / ((R_N(lat) + h) cos lat). The simulator integrates it per sample by classical Runge-Kutta
//! (4th order) between segment boundaries, whose local error (dt^5 times the fifth derivative of the
//! latitude, ~1e-21 rad at 100 Hz and road dynamics) is far below rounding. The same integration on a 1 s grid
//! checks, when the trajectory is built, that the route keeps within the latitude limit.
//!
//! Frames: navigation ENU, vehicle frame Right-Forward-Up with the vehicle level. SI units throughout.

use crate::earth;
use crate::error::{check_with, sig, CoreError};
use crate::limits::{MAX_HEIGHT_M, MAX_LAT_DEG, MIN_HEIGHT_M};
use std::f64::consts::PI;

/// Highest vehicle speed [m/s] (360 km/h: above every road vehicle).
pub const MAX_SPEED_M_S: f64 = 100.0;
/// Largest |longitudinal acceleration| [m/s^2] (about 1 g: above any road vehicle's braking).
pub const MAX_ACCEL_M_S2: f64 = 10.0;
/// Largest |yaw rate| [rad/s] (1 rad/s = 57.3 deg/s: a sharp turn at walking pace).
pub const MAX_YAW_RATE_RAD_S: f64 = 1.0;
/// Largest vertical speed [m/s] of a climb (a 10 % grade at 100 m/s).
pub const MAX_CLIMB_RATE_M_S: f64 = 10.0;
/// Most segments after expanding a repeated route over the run.
pub const MAX_PIECES: usize = 1_000_000;

/// One segment of the route (SI): constant acceleration and yaw rate for `duration`, and a height change
/// `climb` \[m\] along the smooth profile of the module docs (0: level).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Segment {
    pub duration: f64,
    pub accel: f64,
    pub yaw_rate: f64,
    pub climb: f64,
}

/// A route: standing still until `start_s`, then the segments (cycled with `repeat`).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TrajectoryConfig {
    pub start_s: f64,
    pub segments: Vec<Segment>,
    pub repeat: bool,
}

/// A segment placed on the time line: start/end time [s], speed [m/s], yaw [rad] and height [m] at the start;
/// `omega` = pi / duration [rad/s] of the climb profile.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Piece {
    t0: f64,
    t1: f64,
    v0: f64,
    psi0: f64,
    accel: f64,
    yaw_rate: f64,
    h0: f64,
    climb: f64,
    omega: f64,
}

/// Vehicle kinematics at one time (closed form).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// Speed [m/s] and its rate [m/s^2].
    pub speed: f64,
    pub accel: f64,
    /// Vehicle yaw \[rad\] (CCW about Up, unwrapped) and its rate [rad/s].
    pub yaw: f64,
    pub yaw_rate: f64,
    /// Height \[m\], vertical speed (Up) [m/s] and its rate [m/s^2].
    pub height: f64,
    pub climb_rate: f64,
    pub climb_accel: f64,
}

impl Kinematics {
    /// Velocity in ENU [m/s].
    pub fn vel_enu(&self) -> [f64; 3] {
        let (s, c) = self.yaw.sin_cos();
        [-self.speed * s, self.speed * c, self.climb_rate]
    }

    /// Time derivative of the ENU velocity components [m/s^2].
    pub fn accel_enu(&self) -> [f64; 3] {
        let (s, c) = self.yaw.sin_cos();
        let vr = self.speed * self.yaw_rate;
        [-self.accel * s - vr * c, self.accel * c - vr * s, self.climb_accel]
    }
}

/// The route laid out over a run (see the module docs).
#[derive(Clone, Debug)]
pub struct Trajectory {
    pieces: Vec<Piece>,
    /// Time, speed, yaw and height after the last piece.
    tail: (f64, f64, f64, f64),
    /// Height of the standing vehicle before the route starts \[m\].
    h0: f64,
}

/// Position (lat \[rad\], lon \[rad\]) derivative at height `h` for ENU velocity `v`.
#[inline]
pub fn position_rate(lat: f64, h: f64, v: [f64; 3]) -> [f64; 2] {
    [
        v[1] / (earth::meridian_radius(lat) + h),
        v[0] / ((earth::transverse_radius(lat) + h) * lat.cos()),
    ]
}

impl Trajectory {
    /// Lay the route out from `yaw0` and height `h0` \[m\] over [0, `duration_s`] and check it (errors name
    /// `trajectory`).
    pub fn new(cfg: &TrajectoryConfig, yaw0: f64, h0: f64, duration_s: f64) -> Result<Self, CoreError> {
        check_with(cfg.start_s.is_finite() && cfg.start_s >= 0.0, "trajectory", || {
            format!("the static period of {} s must be >= 0", sig(cfg.start_s))
        })?;
        for (i, s) in cfg.segments.iter().enumerate() {
            check_with(s.duration.is_finite() && s.duration > 0.0, "trajectory", || {
                format!("segment {}: duration {} s must be > 0", i + 1, sig(s.duration))
            })?;
            check_with(
                s.accel.is_finite() && s.accel.abs() <= MAX_ACCEL_M_S2,
                "trajectory",
                || {
                    format!(
                        "segment {}: acceleration {} m/s^2 is outside [-{MAX_ACCEL_M_S2}, {MAX_ACCEL_M_S2}] m/s^2",
                        i + 1,
                        sig(s.accel)
                    )
                },
            )?;
            check_with(
                s.yaw_rate.is_finite() && s.yaw_rate.abs() <= MAX_YAW_RATE_RAD_S,
                "trajectory",
                || {
                    format!(
                        "segment {}: turn rate {} deg/s is outside +-{} deg/s",
                        i + 1,
                        sig(s.yaw_rate.to_degrees()),
                        sig(MAX_YAW_RATE_RAD_S.to_degrees())
                    )
                },
            )?;
            // Peak vertical speed and acceleration of the climb profile.
            let (w, a) = (
                s.climb.abs() * PI / (2.0 * s.duration),
                s.climb.abs() * PI * PI / (2.0 * s.duration * s.duration),
            );
            check_with(
                s.climb.is_finite() && w <= MAX_CLIMB_RATE_M_S && a <= MAX_ACCEL_M_S2,
                "trajectory",
                || {
                    format!(
                    "segment {}: a climb of {} m in {} s needs a vertical speed of {} m/s and acceleration {} m/s^2 \
                     (at most {MAX_CLIMB_RATE_M_S} m/s and {MAX_ACCEL_M_S2} m/s^2)",
                    i + 1,
                    sig(s.climb),
                    sig(s.duration),
                    sig(w),
                    sig(a)
                )
                },
            )?;
        }
        let mut pieces = Vec::new();
        let (mut t, mut v, mut psi, mut h) = (cfg.start_s, 0.0f64, yaw0, h0);
        let cycle: f64 = cfg.segments.iter().map(|s| s.duration).sum();
        'outer: while t < duration_s && !cfg.segments.is_empty() {
            for (i, s) in cfg.segments.iter().enumerate() {
                if t >= duration_s {
                    break 'outer;
                }
                check_with(pieces.len() < MAX_PIECES, "trajectory", || {
                    format!("the route repeats more than {MAX_PIECES} segments over the run")
                })?;
                let mut v1 = v + s.accel * s.duration;
                // An exact stop (v0 = accel x duration) may round to -1e-16 m/s: that is zero.
                if v1.abs() <= 1e-9 * (1.0 + v.abs()) {
                    v1 = 0.0;
                }
                check_with((0.0..=MAX_SPEED_M_S).contains(&v1), "trajectory", || {
                    format!(
                        "segment {} ends at speed {} m/s (t = {} s), outside [0, {MAX_SPEED_M_S}] m/s",
                        i + 1,
                        sig(v1),
                        sig(t + s.duration)
                    )
                })?;
                let h1 = h + s.climb;
                check_with((MIN_HEIGHT_M..=MAX_HEIGHT_M).contains(&h1), "trajectory", || {
                    format!(
                        "segment {} ends at height {} m (t = {} s), outside [{MIN_HEIGHT_M}, {MAX_HEIGHT_M}] m",
                        i + 1,
                        sig(h1),
                        sig(t + s.duration)
                    )
                })?;
                pieces.push(Piece {
                    t0: t,
                    t1: t + s.duration,
                    v0: v,
                    psi0: psi,
                    accel: s.accel,
                    yaw_rate: s.yaw_rate,
                    h0: h,
                    climb: s.climb,
                    omega: PI / s.duration,
                });
                t += s.duration;
                v = v1;
                psi += s.yaw_rate * s.duration;
                h = h1;
            }
            if !cfg.repeat || cycle <= 0.0 {
                break;
            }
        }
        Ok(Trajectory {
            pieces,
            tail: (t, v, psi, h),
            h0,
        })
    }

    /// When the vehicle starts moving \[s\] (the first segment's start; infinite without segments).
    pub fn start(&self) -> f64 {
        self.pieces.first().map_or(f64::INFINITY, |p| p.t0)
    }

    /// Times \[s\] where the kinematics change form (segment starts and ends), increasing.
    pub fn boundaries(&self) -> impl Iterator<Item = f64> + '_ {
        self.pieces.iter().map(|p| p.t0).chain(self.pieces.last().map(|p| p.t1))
    }

    /// Index of the piece holding `t` (the last one starting at or before t), using and moving `cursor`.
    #[inline]
    fn find(&self, cursor: &mut usize, t: f64) -> Option<usize> {
        if self.pieces.is_empty() || t < self.pieces[0].t0 {
            return None;
        }
        let mut i = (*cursor).min(self.pieces.len() - 1);
        if self.pieces[i].t0 > t {
            i = self.pieces.partition_point(|p| p.t0 <= t).saturating_sub(1);
        }
        while i + 1 < self.pieces.len() && self.pieces[i + 1].t0 <= t {
            i += 1;
        }
        *cursor = i;
        Some(i)
    }

    /// End time \[s\] of the piece holding `t` (infinite if none follows).
    #[inline]
    pub fn piece_end(&self, cursor: &mut usize, t: f64) -> f64 {
        match self.find(cursor, t) {
            None => self.pieces.first().map_or(f64::INFINITY, |p| p.t0),
            Some(i) if t < self.pieces[i].t1 => self.pieces[i].t1,
            Some(_) => f64::INFINITY,
        }
    }

    /// Kinematics at `t` \[s\] (closed form; `cursor` speeds up monotone queries), with `yaw0` the heading of
    /// the standing vehicle.
    #[inline]
    pub fn at(&self, cursor: &mut usize, t: f64, yaw0: f64) -> Kinematics {
        self.motion(cursor, t, yaw0).at(t)
    }

    /// The closed-form motion holding at `t` \[s\]: the piece's, or the standing vehicle's before the route, or
    /// the straight run at the last speed after it (`cursor` speeds up monotone queries).
    #[inline]
    pub fn motion(&self, cursor: &mut usize, t: f64, yaw0: f64) -> Motion {
        let still = |t0: f64, end: f64, v0: f64, psi0: f64, h0: f64| Motion {
            t0,
            end,
            v0,
            accel: 0.0,
            psi0,
            yaw_rate: 0.0,
            h0,
            climb: 0.0,
            omega: 0.0,
        };
        match self.find(cursor, t) {
            None => {
                let end = self.pieces.first().map_or(f64::INFINITY, |p| p.t0);
                still(0.0, end, 0.0, yaw0, self.h0)
            }
            Some(i) if t < self.pieces[i].t1 => {
                let p = &self.pieces[i];
                Motion {
                    t0: p.t0,
                    end: p.t1,
                    v0: p.v0,
                    accel: p.accel,
                    psi0: p.psi0,
                    yaw_rate: p.yaw_rate,
                    h0: p.h0,
                    climb: p.climb,
                    omega: p.omega,
                }
            }
            Some(_) => {
                let (t_end, v, psi, h) = self.tail;
                still(t_end, f64::INFINITY, v, psi, h)
            }
        }
    }
}

/// One closed-form piece of motion (module docs) from `t0` until `end` \[s\]: speed v0 + accel tau, yaw
/// psi0 + yaw_rate tau, height h0 + climb (1 - cos(omega tau)) / 2, tau = t - t0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    pub t0: f64,
    pub end: f64,
    pub v0: f64,
    pub accel: f64,
    pub psi0: f64,
    pub yaw_rate: f64,
    pub h0: f64,
    pub climb: f64,
    pub omega: f64,
}

impl Motion {
    /// Yaw \[rad\] at `t` \[s\].
    #[inline(always)]
    pub fn yaw(&self, t: f64) -> f64 {
        self.psi0 + self.yaw_rate * (t - self.t0)
    }

    /// Speed [m/s] at `t` \[s\].
    #[inline(always)]
    pub fn speed(&self, t: f64) -> f64 {
        self.v0 + self.accel * (t - self.t0)
    }

    /// (height \[m\], vertical speed [m/s], vertical acceleration [m/s^2]) at `t` \[s\].
    #[inline(always)]
    pub fn vertical(&self, t: f64) -> (f64, f64, f64) {
        if self.climb == 0.0 {
            return (self.h0, 0.0, 0.0);
        }
        let (s, c) = (self.omega * (t - self.t0)).sin_cos();
        let half = 0.5 * self.climb;
        (
            self.h0 + half * (1.0 - c),
            half * self.omega * s,
            half * self.omega * self.omega * c,
        )
    }

    /// Kinematics at `t` \[s\].
    #[inline]
    pub fn at(&self, t: f64) -> Kinematics {
        let (height, climb_rate, climb_accel) = self.vertical(t);
        Kinematics {
            speed: self.speed(t),
            accel: self.accel,
            yaw: self.yaw(t),
            yaw_rate: self.yaw_rate,
            height,
            climb_rate,
            climb_accel,
        }
    }
}

/// One classical Runge-Kutta step of the position from `t0` over `dt` within one piece (no boundary inside):
/// returns (lat, lon) at t0 + dt and their rate there (the height is the route's closed form).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn rk4_position(
    traj: &Trajectory,
    cursor: &mut usize,
    yaw0: f64,
    t0: f64,
    dt: f64,
    p0: [f64; 2],
    rate0: [f64; 2],
) -> ([f64; 2], [f64; 2]) {
    let t1 = t0 + dt;
    let tm = t0 + 0.5 * dt;
    let km = traj.at(cursor, tm, yaw0);
    let k_1 = traj.at(cursor, t1, yaw0);
    let (vm, hm, v1, h1) = (km.vel_enu(), km.height, k_1.vel_enu(), k_1.height);
    let k1 = rate0;
    let k2 = position_rate(p0[0] + 0.5 * dt * k1[0], hm, vm);
    let k3 = position_rate(p0[0] + 0.5 * dt * k2[0], hm, vm);
    let k4 = position_rate(p0[0] + dt * k3[0], h1, v1);
    let p1 = [
        p0[0] + dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        p0[1] + dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
    ];
    (p1, position_rate(p1[0], h1, v1))
}

/// Check that a route starting at latitude `lat0` stays within the latitude limit (RK4 on a 1 s grid split
/// at the segment boundaries).
pub fn check_route_latitude(traj: &Trajectory, lat0: f64, yaw0: f64, duration_s: f64) -> Result<(), CoreError> {
    let lat_max = (MAX_LAT_DEG - 0.01).to_radians();
    let mut cursor = 0usize;
    let mut p = [lat0, 0.0];
    let k0 = traj.at(&mut cursor, 0.0, yaw0);
    let mut rate = position_rate(lat0, k0.height, k0.vel_enu());
    let mut t = 0.0;
    while t < duration_s {
        let t1 = (t + 1.0).min(duration_s).min(traj.piece_end(&mut cursor, t));
        let (p1, r1) = rk4_position(traj, &mut cursor, yaw0, t, t1 - t, p, rate);
        p = p1;
        rate = r1;
        t = t1;
        // Once per second of route (0.3 M times for 88 h): the message is formatted only on failure.
        check_with(p[0].abs() <= lat_max, "trajectory", || {
            format!(
                "the route reaches latitude {} deg at t = {} h, beyond +-{} deg",
                sig(p[0].to_degrees()),
                sig(t / crate::units::HOUR),
                sig(lat_max.to_degrees())
            )
        })?;
    }
    Ok(())
}
