//! The true increments of a static base with the table turning: two-point Gauss-Legendre quadrature of the
//! rotated Earth rate and gravity over each sample (module docs of [`super`]), with a closed form for the samples
//! during which the table turns at a constant rate ([`Uniform`]).

use super::series::rotate;
use super::{ImuSimulator, SINCOS_RESYNC};
use crate::attitude::Vec3;

/// Two-point Gauss-Legendre nodes on [0, 1]: 1/2 -+ 1/(2 sqrt 3).
pub(super) const GL2_LO: f64 = 0.5 - 0.288_675_134_594_812_9;
pub(super) const GL2_HI: f64 = 0.5 + 0.288_675_134_594_812_9;

/// Constants of a sample during which the table turns at a constant rate w (cruise or dwell): with
/// d_lo, d_hi = w dt x (Gauss-Legendre nodes) and D = w dt,
///     Ic = a cos(alpha0) - b sin(alpha0),  Is = a sin(alpha0) + b cos(alpha0),
///     a = dt/2 (cos d_lo + cos d_hi),  b = dt/2 (sin d_lo + sin d_hi),
/// and (sin, cos)(alpha0 + D) by the addition theorem: no per-sample table evaluation at the nodes and no
/// series. Same quadrature as the general path, so the same increments to rounding (1e-16 relative).
#[derive(Clone, Copy, Debug)]
pub(super) struct Uniform {
    pub(super) rate: f64,
    /// The current uniform segment: absolute start and end times [s] (end -inf: none cached), angle at
    /// the start [rad].
    pub(super) start: f64,
    pub(super) end: f64,
    pub(super) angle0: f64,
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) sin_d: f64,
    pub(super) cos_d: f64,
}

impl Uniform {
    pub(super) fn new(rate: f64, dt: f64) -> Self {
        let (s_lo, c_lo) = (rate * GL2_LO * dt).sin_cos();
        let (s_hi, c_hi) = (rate * GL2_HI * dt).sin_cos();
        let (sin_d, cos_d) = (rate * dt).sin_cos();
        let (start, end, angle0) = (0.0, f64::NEG_INFINITY, 0.0);
        Uniform {
            rate,
            start,
            end,
            angle0,
            a: 0.5 * dt * (c_lo + c_hi),
            b: 0.5 * dt * (s_lo + s_hi),
            sin_d,
            cos_d,
        }
    }
}

impl ImuSimulator {
    /// True increments (dtheta [rad], dv [m/s]) of sample k (1-based, ending at t_k = k dt); advances the
    /// table state (angle and its sine/cosine at t_k).
    #[inline]
    pub(super) fn true_increments(&mut self, k: u64, t0: f64, t1: f64) -> (Vec3, Vec3) {
        let dt = self.dt;
        let (u, a) = (self.u_w, self.u_f);
        if self.table.is_static() {
            return ([u[0] * dt, u[1] * dt, u[2] * dt], [a[0] * dt, a[1] * dt, a[2] * dt]);
        }
        let alpha0 = self.alpha;
        let (s0, c0) = (self.sin_alpha, self.cos_alpha);
        if t1 <= self.uniform.end || self.enter_uniform(t0, t1) {
            // Constant table rate over the whole sample: the node and end angles are alpha0 plus fixed
            // offsets, so their sines and cosines follow from (s0, c0) by fixed rotations (see `Uniform`).
            let w = &self.uniform;
            // The segment's closed form (what `Turntable::state_at` evaluates, without the segment search).
            let alpha1 = w.angle0 + w.rate * (t1 - w.start);
            let ic = w.a * c0 - w.b * s0;
            let is = w.a * s0 + w.b * c0;
            let (s1, c1) = if k % SINCOS_RESYNC == 0 {
                alpha1.sin_cos()
            } else {
                (s0 * w.cos_d + c0 * w.sin_d, c0 * w.cos_d - s0 * w.sin_d)
            };
            self.alpha = alpha1;
            self.sin_alpha = s1;
            self.cos_alpha = c1;
            return (
                [
                    ic * u[0] + is * u[1],
                    -is * u[0] + ic * u[1],
                    u[2] * dt + (alpha1 - alpha0),
                ],
                [ic * a[0] + is * a[1], -is * a[0] + ic * a[1], a[2] * dt],
            );
        }
        let a_lo = self.table.state_at(&mut self.cursor, t0 + GL2_LO * dt).angle;
        let a_hi = self.table.state_at(&mut self.cursor, t0 + GL2_HI * dt).angle;
        let alpha1 = self.table.state_at(&mut self.cursor, t1).angle;
        // sin/cos at the nodes by the addition theorem from the start of the sample (small angles by series).
        let (s_lo, c_lo) = rotate(s0, c0, a_lo - alpha0);
        let (s_hi, c_hi) = rotate(s0, c0, a_hi - alpha0);
        let ic = 0.5 * dt * (c_lo + c_hi);
        let is = 0.5 * dt * (s_lo + s_hi);
        // Exact re-synchronisation every SINCOS_RESYNC samples bounds the rounding random walk (< 1e-14).
        let (s1, c1) = if k % SINCOS_RESYNC == 0 {
            alpha1.sin_cos()
        } else {
            rotate(s0, c0, alpha1 - alpha0)
        };
        self.alpha = alpha1;
        self.sin_alpha = s1;
        self.cos_alpha = c1;
        (
            [
                ic * u[0] + is * u[1],
                -is * u[0] + ic * u[1],
                u[2] * dt + (alpha1 - alpha0),
            ],
            [ic * a[0] + is * a[1], -is * a[0] + ic * a[1], a[2] * dt],
        )
    }

    /// Look up the table segment holding t0; if it turns at a constant rate, cache the rotation constants of
    /// that rate (recomputed only when the rate changes) and the segment's end. Returns true if the sample
    /// [t0, t1] lies within it.
    #[cold]
    pub(super) fn enter_uniform(&mut self, t0: f64, t1: f64) -> bool {
        match self.table.uniform_at(&mut self.cursor, t0) {
            Some(seg) => {
                if seg.rate != self.uniform.rate {
                    self.uniform = Uniform::new(seg.rate, self.dt);
                }
                self.uniform.end = seg.end;
                self.uniform.start = seg.start;
                self.uniform.angle0 = seg.angle0;
                t1 <= seg.end
            }
            None => false,
        }
    }
}
