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
//! The route is level: the height stays at the site's. After the last segment the vehicle goes on straight
//! at its last speed (usually 0 after a stop); with `repeat` the segments are driven again and again.
//!
//! Position is the one quantity without a closed form on the ellipsoid: lat' = v_N / (R_M(lat) + h),
//! lon' = v_E / ((R_N(lat) + h) cos lat). The simulator integrates it per sample by classical Runge-Kutta
//! (4th order) between segment boundaries, whose local error (dt^5 times the fifth derivative of the
//! latitude, ~1e-21 rad at 100 Hz and road dynamics) is far below rounding. The same integration on a 1 s grid
//! checks, when the trajectory is built, that the route keeps within the latitude limit.
//!
//! Frames: navigation ENU, vehicle frame Right-Forward-Up with the vehicle level. SI units throughout.

use crate::earth;
use crate::error::{check, sig, CoreError};
use crate::limits::MAX_LAT_DEG;

/// Highest vehicle speed [m/s] (360 km/h: above every road vehicle).
pub const MAX_SPEED_M_S: f64 = 100.0;
/// Largest |longitudinal acceleration| [m/s^2] (about 1 g: above any road vehicle's braking).
pub const MAX_ACCEL_M_S2: f64 = 10.0;
/// Largest |yaw rate| [rad/s] (1 rad/s = 57.3 deg/s: a sharp turn at walking pace).
pub const MAX_YAW_RATE_RAD_S: f64 = 1.0;
/// Most segments after expanding a repeated route over the run.
pub const MAX_PIECES: usize = 1_000_000;

/// One segment of the route (SI): constant acceleration and yaw rate for `duration`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub duration: f64,
    pub accel: f64,
    pub yaw_rate: f64,
}

/// A route: standing still until `start_s`, then the segments (cycled with `repeat`).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TrajectoryConfig {
    pub start_s: f64,
    pub segments: Vec<Segment>,
    pub repeat: bool,
}

/// A segment placed on the time line: start/end time [s], speed [m/s] and yaw [rad] at the start.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Piece {
    t0: f64,
    t1: f64,
    v0: f64,
    psi0: f64,
    accel: f64,
    yaw_rate: f64,
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
}

impl Kinematics {
    /// Velocity in ENU [m/s].
    pub fn vel_enu(&self) -> [f64; 3] {
        let (s, c) = self.yaw.sin_cos();
        [-self.speed * s, self.speed * c, 0.0]
    }

    /// Time derivative of the ENU velocity components [m/s^2].
    pub fn accel_enu(&self) -> [f64; 3] {
        let (s, c) = self.yaw.sin_cos();
        let vr = self.speed * self.yaw_rate;
        [-self.accel * s - vr * c, self.accel * c - vr * s, 0.0]
    }
}

/// The route laid out over a run (see the module docs).
#[derive(Clone, Debug)]
pub struct Trajectory {
    pieces: Vec<Piece>,
    /// Speed and yaw after the last piece.
    tail: (f64, f64, f64),
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
    /// Lay the route out from `yaw0` over [0, `duration_s`] and check it (errors name `trajectory`).
    pub fn new(cfg: &TrajectoryConfig, yaw0: f64, duration_s: f64) -> Result<Self, CoreError> {
        check(
            cfg.start_s.is_finite() && cfg.start_s >= 0.0,
            "trajectory",
            format!("the static period of {} s must be >= 0", sig(cfg.start_s)),
        )?;
        for (i, s) in cfg.segments.iter().enumerate() {
            check(
                s.duration.is_finite() && s.duration > 0.0,
                "trajectory",
                format!("segment {}: duration {} s must be > 0", i + 1, sig(s.duration)),
            )?;
            check(
                s.accel.is_finite() && s.accel.abs() <= MAX_ACCEL_M_S2,
                "trajectory",
                format!(
                    "segment {}: acceleration {} m/s^2 is outside [-{MAX_ACCEL_M_S2}, {MAX_ACCEL_M_S2}] m/s^2",
                    i + 1,
                    sig(s.accel)
                ),
            )?;
            check(
                s.yaw_rate.is_finite() && s.yaw_rate.abs() <= MAX_YAW_RATE_RAD_S,
                "trajectory",
                format!(
                    "segment {}: turn rate {} deg/s is outside +-{} deg/s",
                    i + 1,
                    sig(s.yaw_rate.to_degrees()),
                    sig(MAX_YAW_RATE_RAD_S.to_degrees())
                ),
            )?;
        }
        let mut pieces = Vec::new();
        let (mut t, mut v, mut psi) = (cfg.start_s, 0.0f64, yaw0);
        let cycle: f64 = cfg.segments.iter().map(|s| s.duration).sum();
        'outer: while t < duration_s && !cfg.segments.is_empty() {
            for (i, s) in cfg.segments.iter().enumerate() {
                if t >= duration_s {
                    break 'outer;
                }
                check(
                    pieces.len() < MAX_PIECES,
                    "trajectory",
                    format!("the route repeats more than {MAX_PIECES} segments over the run"),
                )?;
                let mut v1 = v + s.accel * s.duration;
                // An exact stop (v0 = accel x duration) may round to -1e-16 m/s: that is zero.
                if v1.abs() <= 1e-9 * (1.0 + v.abs()) {
                    v1 = 0.0;
                }
                check(
                    (0.0..=MAX_SPEED_M_S).contains(&v1),
                    "trajectory",
                    format!(
                        "segment {} ends at speed {} m/s (t = {} s), outside [0, {MAX_SPEED_M_S}] m/s",
                        i + 1,
                        sig(v1),
                        sig(t + s.duration)
                    ),
                )?;
                pieces.push(Piece {
                    t0: t,
                    t1: t + s.duration,
                    v0: v,
                    psi0: psi,
                    accel: s.accel,
                    yaw_rate: s.yaw_rate,
                });
                t += s.duration;
                v = v1;
                psi += s.yaw_rate * s.duration;
            }
            if !cfg.repeat || cycle <= 0.0 {
                break;
            }
        }
        Ok(Trajectory {
            pieces,
            tail: (t, v, psi),
        })
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
        match self.find(cursor, t) {
            None => Kinematics {
                speed: 0.0,
                accel: 0.0,
                yaw: yaw0,
                yaw_rate: 0.0,
            },
            Some(i) if t < self.pieces[i].t1 => {
                let p = &self.pieces[i];
                let tau = t - p.t0;
                Kinematics {
                    speed: p.v0 + p.accel * tau,
                    accel: p.accel,
                    yaw: p.psi0 + p.yaw_rate * tau,
                    yaw_rate: p.yaw_rate,
                }
            }
            Some(_) => {
                let (_, v, psi) = self.tail;
                Kinematics {
                    speed: v,
                    accel: 0.0,
                    yaw: psi,
                    yaw_rate: 0.0,
                }
            }
        }
    }
}

/// One classical Runge-Kutta step of the position from `t0` over `dt` within one piece (no boundary inside):
/// returns (lat, lon) at t0 + dt and their rate there.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn rk4_position(
    traj: &Trajectory,
    cursor: &mut usize,
    yaw0: f64,
    h: f64,
    t0: f64,
    dt: f64,
    p0: [f64; 2],
    rate0: [f64; 2],
) -> ([f64; 2], [f64; 2]) {
    let t1 = t0 + dt;
    let tm = t0 + 0.5 * dt;
    let vm = traj.at(cursor, tm, yaw0).vel_enu();
    let v1 = traj.at(cursor, t1, yaw0).vel_enu();
    let k1 = rate0;
    let k2 = position_rate(p0[0] + 0.5 * dt * k1[0], h, vm);
    let k3 = position_rate(p0[0] + 0.5 * dt * k2[0], h, vm);
    let k4 = position_rate(p0[0] + dt * k3[0], h, v1);
    let p1 = [
        p0[0] + dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        p0[1] + dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
    ];
    (p1, position_rate(p1[0], h, v1))
}

/// Check that a route starting at latitude `lat0` stays within the latitude limit (RK4 on a 1 s grid split
/// at the segment boundaries).
pub fn check_route_latitude(traj: &Trajectory, lat0: f64, h: f64, yaw0: f64, duration_s: f64) -> Result<(), CoreError> {
    let lat_max = (MAX_LAT_DEG - 0.01).to_radians();
    let mut cursor = 0usize;
    let mut p = [lat0, 0.0];
    let mut rate = position_rate(lat0, h, traj.at(&mut cursor, 0.0, yaw0).vel_enu());
    let mut t = 0.0;
    while t < duration_s {
        let t1 = (t + 1.0).min(duration_s).min(traj.piece_end(&mut cursor, t));
        let (p1, r1) = rk4_position(traj, &mut cursor, yaw0, h, t, t1 - t, p, rate);
        p = p1;
        rate = r1;
        t = t1;
        check(
            p[0].abs() <= lat_max,
            "trajectory",
            format!(
                "the route reaches latitude {} deg at t = {} h, beyond +-{} deg",
                sig(p[0].to_degrees()),
                sig(t / 3600.0),
                sig(lat_max.to_degrees())
            ),
        )?;
    }
    Ok(())
}
