//! The true attitude of every sample from the table angle: C_b^n = C_b0^n Rz(alpha), its Euler angles by short
//! series for the usual small tilts ([`ImuSimulator::true_attitude_tilted`]).

use super::series::{asin_small, atan_small, wrap_pi_fast};
use super::ImuSimulator;
use crate::attitude::{dcm_to_euler, mat_mul, Euler};

impl ImuSimulator {
    /// Euler angles of C_b^n = C_b0^n Rz(alpha) from the sine `s` and cosine `c` of alpha already known.
    /// Same values as `dcm_to_euler` (to ~1e-16 rad); for tilts below ~5.7 deg the small angles (pitch, roll,
    /// and yaw relative to yaw0 + alpha) come from short series instead of libm asin/atan2.
    #[inline]
    pub(super) fn true_attitude_tilted(&self, alpha: f64, s: f64, c: f64) -> Euler {
        let b = &self.c_b0n;
        let c20 = b[2][0] * c + b[2][1] * s;
        let c21 = -b[2][0] * s + b[2][1] * c;
        let c22 = b[2][2];
        let c01 = -b[0][0] * s + b[0][1] * c;
        let c11 = -b[1][0] * s + b[1][1] * c;
        if c21.abs() >= 0.1 || c22 <= 0.0 || c20.abs() >= 0.1 * c22 {
            let rz = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
            return dcm_to_euler(&mat_mul(b, &rz));
        }
        let pitch = asin_small(c21);
        let roll = atan_small(-c20 * self.inv_c22);
        // yaw = yaw_hat + atan2(x, y) with yaw_hat = yaw0 + alpha and (x, y) = cos(pitch) (sin, cos)(yaw - yaw_hat).
        let (sy0, cy0) = self.sincos_yaw0;
        let (sh, ch) = (sy0 * c + cy0 * s, cy0 * c - sy0 * s);
        let x = -c01 * ch - c11 * sh;
        let y = -c01 * sh + c11 * ch;
        let yaw = if y > 0.0 && x.abs() < 0.1 * y {
            wrap_pi_fast(self.cfg.attitude.yaw + alpha + atan_small(x / y))
        } else {
            (-c01).atan2(c11)
        };
        Euler { pitch, roll, yaw }
    }

    /// Second pass of `fill`: on entry `pitch`, `roll` hold sin and cos of the table angle; on exit the
    /// true attitude [rad].
    #[inline]
    pub(super) fn attitudes(&self, alpha: &[f64], pitch: &mut [f64], roll: &mut [f64], yaw: &mut [f64]) {
        let yaw0 = self.cfg.attitude.yaw;
        if self.level {
            for i in 0..alpha.len() {
                pitch[i] = 0.0;
                roll[i] = 0.0;
                yaw[i] = wrap_pi_fast(yaw0 + alpha[i]);
            }
        } else {
            for i in 0..alpha.len() {
                let e = self.true_attitude_tilted(alpha[i], pitch[i], roll[i]);
                pitch[i] = e.pitch;
                roll[i] = e.roll;
                yaw[i] = e.yaw;
            }
        }
    }
}
