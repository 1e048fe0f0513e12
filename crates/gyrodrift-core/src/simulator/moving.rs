//! The true increments of a moving base (a land vehicle on its route, `trajectory`), with the table turning in
//! the vehicle: per sample the rotated Earth rate, transport rate and specific force integrated by three-point
//! Gauss-Legendre quadrature, the position by RK4 ([`ImuSimulator::moving_increments`]).

use super::chunk::ImuChunkSlices;
use super::series::{rotate, wrap_pi_fast};
use super::{ImuSimulator, ImuSimulatorConfig, ATTITUDE_BLOCK, SINCOS_RESYNC};
use crate::attitude::{euler_to_dcm, mat_t_vec, Euler, Mat3, Vec3};
use crate::earth;
use crate::error::CoreError;
use crate::trajectory::{position_rate, Motion, Trajectory, TrajectoryConfig};

/// State of the moving-base path: the route, its cursor, the true position and its rate at the end of the
/// last sample, and the mounting C_0 = Rx(pitch0) Ry(roll0) (IMU at table angle 0 in the vehicle frame).
#[derive(Clone, Debug)]
pub(super) struct Moving {
    pub(super) traj: Trajectory,
    pub(super) cursor: usize,
    pub(super) pos: [f64; 2],
    pub(super) pos_rate: [f64; 2],
    /// sin and cos of the latitude `pos[0]`.
    pub(super) sin_lat: f64,
    pub(super) cos_lat: f64,
    /// The vehicle's yaw \[rad\] at the end of the last part, its sine and cosine.
    pub(super) yaw_sc: (f64, f64, f64),
    pub(super) c0: Mat3,
}

impl Moving {
    /// The moving-base state at the start of the run: the route `route` driven from the site and attitude of
    /// `cfg`.
    pub(super) fn new(route: &TrajectoryConfig, cfg: &ImuSimulatorConfig) -> Result<Self, CoreError> {
        let traj = Trajectory::new(route, cfg.attitude.yaw, cfg.height, cfg.duration_s)?;
        let mut cursor = 0;
        let v = traj.at(&mut cursor, 0.0, cfg.attitude.yaw).vel_enu();
        Ok(Moving {
            pos: [cfg.lat, cfg.lon],
            sin_lat: cfg.lat.sin(),
            cos_lat: cfg.lat.cos(),
            yaw_sc: (cfg.attitude.yaw, cfg.attitude.yaw.sin(), cfg.attitude.yaw.cos()),
            pos_rate: position_rate(cfg.lat, cfg.height, v),
            traj,
            cursor,
            c0: euler_to_dcm(Euler {
                yaw: 0.0,
                ..cfg.attitude
            }),
        })
    }
}

/// One moving-base sample: the true increments and, at its end, the vehicle's yaw \[rad\], height \[m\] and
/// ENU velocity [m/s].
#[derive(Clone, Copy, Debug)]
pub(super) struct MovingSample {
    pub(super) dtheta: Vec3,
    pub(super) dv: Vec3,
    pub(super) yaw: f64,
    pub(super) height: f64,
    pub(super) vel: Vec3,
}

/// The vehicle's motion at one time, with the sine and cosine of its yaw.
#[derive(Clone, Copy, Debug)]
struct MotionState {
    yaw: f64,
    sin_yaw: f64,
    cos_yaw: f64,
    height: f64,
    /// ENU velocity [m/s] and its time derivative [m/s^2].
    vel: Vec3,
    accel: Vec3,
}

/// The state of motion `m` at `t` \[s\], the sine and cosine of the yaw from `yaw_ref` = (yaw, sin, cos) at a
/// nearby time by the addition theorem (`rotate`).
#[inline(always)]
fn motion_state(m: &Motion, t: f64, yaw_ref: (f64, f64, f64)) -> MotionState {
    let yaw = m.yaw(t);
    let (sp, cp) = rotate(yaw_ref.1, yaw_ref.2, yaw - yaw_ref.0);
    let speed = m.speed(t);
    let (height, vu, au) = m.vertical(t);
    let vr = speed * m.yaw_rate;
    MotionState {
        yaw,
        sin_yaw: sp,
        cos_yaw: cp,
        height,
        vel: [-speed * sp, speed * cp, vu],
        accel: [-m.accel * sp - vr * cp, m.accel * cp - vr * sp, au],
    }
}

/// Three-point Gauss-Legendre nodes on [0, 1] and weights (exact for polynomials of degree 5).
const GL3: [(f64, f64); 3] = [
    (0.5 - 0.387_298_334_620_741_7, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.5 + 0.387_298_334_620_741_7, 5.0 / 18.0),
];

impl ImuSimulator {
    /// `fill` on a moving base (buffers already checked for `m` samples): per sample the true increments by
    /// `moving_increments`, the temperature and the deterministic errors, then the random terms per block and
    /// the attitudes (`moving_attitudes`) from the table's sine and cosine and the vehicle's yaw change parked
    /// in the pitch, roll and yaw outputs. Samples ending before the vehicle starts (the static period) are the
    /// static base's (`true_increments`: the same motion, without the per-sample Earth terms).
    pub(super) fn fill_moving(&mut self, mut out: ImuChunkSlices<'_>, m: usize) -> usize {
        let temp_drift = self.errors.params().has_temperature_drift();
        let rate = self.cfg.rate_hz;
        let yaw0 = self.cfg.attitude.yaw;
        let standing_until = self.moving.as_ref().expect("moving base").traj.start();
        for start in (0..m).step_by(ATTITUDE_BLOCK) {
            let end = (start + ATTITUDE_BLOCK).min(m);
            for i in start..end {
                let k = self.k + 1;
                let (t0, t1) = (self.k as f64 / rate, k as f64 / rate);
                let sample = if t1 <= standing_until {
                    let (dtheta, dv) = self.true_increments(k, t0, t1);
                    MovingSample {
                        dtheta,
                        dv,
                        yaw: yaw0,
                        height: self.cfg.height,
                        vel: [0.0; 3],
                    }
                } else {
                    self.moving_increments(k, t0, t1, self.dt)
                };
                self.write_sample(&mut out, i, k, t1, temp_drift, (sample.dtheta, sample.dv));
                out.yaw[i] = sample.yaw - yaw0;
                if let Some(tr) = out.truth.as_mut() {
                    let mv = self.moving.as_ref().expect("moving base");
                    tr.lat[i] = mv.pos[0];
                    tr.lon[i] = mv.pos[1];
                    tr.height[i] = sample.height;
                    tr.vel[3 * i..3 * i + 3].copy_from_slice(&sample.vel);
                }
            }
            self.errors
                .add_noise(&mut out.dtheta[3 * start..3 * end], &mut out.dv[3 * start..3 * end]);
            self.moving_attitudes(
                &out.table_angle[start..end],
                &mut out.pitch[start..end],
                &mut out.roll[start..end],
                &mut out.yaw[start..end],
            );
        }
        m
    }

    /// Attitudes of a block on a moving base: on entry `pitch`, `roll` hold sin and cos of the table angle and
    /// `yaw` the vehicle's yaw change psi - psi0; on exit the IMU's true attitude. C_b^n = Rz(psi) C_0 Rz(alpha)
    /// = Rz(psi - psi0) C_b0^n Rz(alpha), and a turn about Up on the left adds to the yaw only: the static
    /// base's attitude of the table angle, its yaw plus psi - psi0.
    #[inline]
    fn moving_attitudes(&self, alpha: &[f64], pitch: &mut [f64], roll: &mut [f64], yaw: &mut [f64]) {
        let yaw0 = self.cfg.attitude.yaw;
        for i in 0..alpha.len() {
            let turned = yaw[i];
            if self.level {
                pitch[i] = 0.0;
                roll[i] = 0.0;
                yaw[i] = wrap_pi_fast(yaw0 + alpha[i] + turned);
            } else {
                let e = self.true_attitude_tilted(alpha[i], pitch[i], roll[i]);
                pitch[i] = e.pitch;
                roll[i] = e.roll;
                yaw[i] = wrap_pi_fast(e.yaw + turned);
            }
        }
    }

    /// True increments of the sample [t0, t1] on a moving base (sample `k`), and the vehicle's yaw, height and
    /// velocity at t1; advances the position and the table angle. With psi the vehicle yaw, C_0 the mounting and
    /// alpha the table angle, C_b^n = Rz(psi) C_0 Rz(alpha), so
    ///     w_ib^b = Rz(-alpha) C_0' (Rz(-psi) (w_ie^n + w_en^n) + psi' e_z) + alpha' e_z,
    ///     f^b    = Rz(-alpha) C_0' Rz(-psi) (dv^n/dt + (2 w_ie^n + w_en^n) x v^n + g e_z).
    /// The sample is split at the route's segment boundaries; on each part the position advances by one RK4
    /// step, the latitude inside it is the cubic Hermite interpolant of the step's ends (error ~1e-20 rad), and
    /// the rate and specific force are integrated by three-point Gauss-Legendre quadrature (their derivatives
    /// are continuous within a part; the table turns by at most a few milliradians per sample, so the error is
    /// below 1e-16 relative). The table's own term alpha(t1) - alpha(t0) is added exactly.
    ///
    /// Cost: the sines and cosines of the latitude, the vehicle yaw and the table angle at the quadrature nodes
    /// and RK4 stages follow from their values at the start of the part by the addition theorem with short
    /// series (`rotate`: the angles move by < 2e-3 rad within a sample, truncation < 1e-21), and the radii,
    /// their reciprocals and gravity from their exact values at the start of the part by Taylor expansion in the
    /// latitude and height steps (`earth::EarthNear`, relative error < 5e-17); the yaw and latitude at the start
    /// of the next part follow the same way, with exact libm values every `SINCOS_RESYNC` samples (the rounding
    /// walk stays below 1e-14): one square root and a few divisions per part instead of about thirty libm
    /// sine/cosine pairs and twenty square roots and divisions.
    ///
    /// The parts are measured from t0 and add up to exactly `dt` (t1 - t0 differs from dt by the rounding of
    /// t1, 3e-11 s at 72 h: 3e-9 relative, which the increments must not carry).
    fn moving_increments(&mut self, k: u64, t0: f64, t1: f64, dt: f64) -> MovingSample {
        let yaw0 = self.cfg.attitude.yaw;
        let (alpha0, sa0, ca0) = (self.alpha, self.sin_alpha, self.cos_alpha);
        // A table turning at a constant rate over the whole sample (cruise, dwell): its closed form, no search.
        let uniform = (t1 <= self.uniform.end || self.enter_uniform(t0, t1)).then_some(self.uniform);
        let (table, table_cursor) = (&self.table, &mut self.cursor);
        let mut table_angle = |t: f64| match &uniform {
            Some(w) => w.angle0 + w.rate * (t - w.start),
            None => table.state_at(table_cursor, t).angle,
        };
        let mv = self.moving.as_mut().expect("moving base");
        let c0 = mv.c0;
        let (mut w, mut f) = ([0.0f64; 3], [0.0f64; 3]);
        // The yaw and its sine and cosine at the start of the last part.
        let mut yaw_ref = mv.yaw_sc;
        // Exact sines and cosines every SINCOS_RESYNC samples bound the rounding random walk of the recurrences.
        let resync = k % SINCOS_RESYNC == 0;
        let mut u = 0.0;
        while u < dt {
            let a = t0 + u;
            let m = mv.traj.motion(&mut mv.cursor, a, yaw0);
            let end = m.end - t0;
            let ub = if end > u && end < dt { end } else { dt };
            let span = ub - u;
            let psi_a = m.yaw(a);
            let (sp_a, cp_a) = if resync {
                psi_a.sin_cos()
            } else {
                rotate(yaw_ref.1, yaw_ref.2, psi_a - yaw_ref.0)
            };
            yaw_ref = (psi_a, sp_a, cp_a);
            let (p0, r0, sl0, cl0) = (mv.pos, mv.pos_rate, mv.sin_lat, mv.cos_lat);
            let h_a = m.vertical(a).0;
            let near = earth::EarthNear::at_position(sl0, cl0, h_a);
            let earth_at = |dlat: f64, h: f64| {
                let (s, c) = rotate(sl0, cl0, dlat);
                near.near(dlat, s, c, h)
            };
            // Classical RK4 of the position over the part (as `trajectory::rk4_position`).
            let (sm, se) = (
                motion_state(&m, a + 0.5 * span, yaw_ref),
                motion_state(&m, a + span, yaw_ref),
            );
            let rate_at = |dlat: f64, st: &MotionState| {
                let e = earth_at(dlat, st.height);
                [st.vel[1] * e.inv_rmh, st.vel[0] * e.inv_rnh * e.inv_cos]
            };
            let k1 = r0;
            let k2 = rate_at(0.5 * span * k1[0], &sm);
            let k3 = rate_at(0.5 * span * k2[0], &sm);
            let k4 = rate_at(span * k3[0], &se);
            let p1 = [
                p0[0] + span / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
                p0[1] + span / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
            ];
            let (sl1, cl1) = if resync {
                p1[0].sin_cos()
            } else {
                rotate(sl0, cl0, p1[0] - p0[0])
            };
            let r1 = {
                let e = near.near(p1[0] - p0[0], sl1, cl1, se.height);
                [se.vel[1] * e.inv_rmh, se.vel[0] * e.inv_rnh * e.inv_cos]
            };
            for (x, wgt) in GL3 {
                let t = a + x * span;
                // Cubic Hermite basis on [0, 1].
                let (x2, x3) = (x * x, x * x * x);
                let dlat = (x3 - 2.0 * x2 + x) * span * r0[0]
                    + (-2.0 * x3 + 3.0 * x2) * (p1[0] - p0[0])
                    + (x3 - x2) * span * r1[0];
                let st = motion_state(&m, t, yaw_ref);
                let ep = earth_at(dlat, st.height);
                let (sl, cl, g) = (ep.sin_lat, ep.cos_lat, ep.g);
                let alpha = table_angle(t);
                let (sa, ca) = rotate(sa0, ca0, alpha - alpha0);
                let v = st.vel;
                let wie = [0.0, earth::OMEGA_IE * cl, earth::OMEGA_IE * sl];
                let e = v[0] * ep.inv_rnh;
                let wen = [-v[1] * ep.inv_rmh, e, e * sl * ep.inv_cos];
                let win = crate::attitude::add(wie, wen);
                let cor = crate::attitude::cross(crate::attitude::add(crate::attitude::scale(wie, 2.0), wen), v);
                let dvdt = st.accel;
                let fnav = [dvdt[0] + cor[0], dvdt[1] + cor[1], dvdt[2] + cor[2] + g];
                let (sp, cp) = (st.sin_yaw, st.cos_yaw);
                // Rz(-psi) x = (c x0 + s x1, -s x0 + c x1, x2).
                let rot = |x: Vec3| [cp * x[0] + sp * x[1], -sp * x[0] + cp * x[1], x[2]];
                let mut wv = rot(win);
                wv[2] += m.yaw_rate;
                let (wb, fb) = (mat_t_vec(&c0, wv), mat_t_vec(&c0, rot(fnav)));
                let s = wgt * span;
                w[0] += s * (ca * wb[0] + sa * wb[1]);
                w[1] += s * (-sa * wb[0] + ca * wb[1]);
                w[2] += s * wb[2];
                f[0] += s * (ca * fb[0] + sa * fb[1]);
                f[1] += s * (-sa * fb[0] + ca * fb[1]);
                f[2] += s * fb[2];
            }
            mv.pos = p1;
            mv.pos_rate = r1;
            mv.sin_lat = sl1;
            mv.cos_lat = cl1;
            u = ub;
        }
        let alpha1 = table_angle(t1);
        w[2] += alpha1 - alpha0;
        let end = motion_state(&mv.traj.motion(&mut mv.cursor, t1, yaw0), t1, yaw_ref);
        mv.yaw_sc = (end.yaw, end.sin_yaw, end.cos_yaw);
        // Exact re-synchronisation every SINCOS_RESYNC samples bounds the rounding random walk (< 1e-14).
        let (s1, c1) = if resync {
            alpha1.sin_cos()
        } else {
            rotate(sa0, ca0, alpha1 - alpha0)
        };
        self.alpha = alpha1;
        self.sin_alpha = s1;
        self.cos_alpha = c1;
        MovingSample {
            dtheta: w,
            dv: f,
            yaw: end.yaw,
            height: end.height,
            vel: end.vel,
        }
    }
}
