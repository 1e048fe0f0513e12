//! Sines, cosines, arctangents and arcsines of the small angles of one sample by short series (the table and the
//! vehicle move by milliradians per sample), and a division-free wrap to (-pi, pi].

/// (sin, cos) of (alpha + d) from (sin alpha, cos alpha); series for |d| < 0.05 (truncation < 1e-19).
#[inline(always)]
pub(super) fn rotate(s: f64, c: f64, d: f64) -> (f64, f64) {
    let (sd, cd) = if d.abs() < 2e-3 {
        // Table travel within a sample is usually below 2e-3 rad: shorter series, truncation < 1e-21.
        let d2 = d * d;
        (
            d * (1.0 - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0))),
            1.0 - d2 * 0.5 * (1.0 - d2 * (1.0 / 12.0) * (1.0 - d2 * (1.0 / 30.0))),
        )
    } else if d.abs() < 0.05 {
        let d2 = d * d;
        // Multiplications by constant reciprocals (a division costs ~10x a multiplication).
        let sd = d
            * (1.0
                - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0) * (1.0 - d2 * (1.0 / 42.0) * (1.0 - d2 * (1.0 / 72.0)))));
        let cd = 1.0
            - d2 * 0.5
                * (1.0
                    - d2 * (1.0 / 12.0)
                        * (1.0 - d2 * (1.0 / 30.0) * (1.0 - d2 * (1.0 / 56.0) * (1.0 - d2 * (1.0 / 90.0)))));
        (sd, cd)
    } else {
        d.sin_cos()
    };
    (s * cd + c * sd, c * cd - s * sd)
}

/// atan(x) for |x| < 0.1 by its Taylor series to x^15 (truncation < 1e-18); libm otherwise.
#[inline(always)]
pub(super) fn atan_small(x: f64) -> f64 {
    if x.abs() >= 0.1 {
        return x.atan();
    }
    let x2 = x * x;
    if x2 < 1e-6 {
        // |x| < 1e-3 (the yaw correction, second order in the tilt): to x^7, truncation x^8 / 9 < 1.2e-25.
        return x * (1.0 - x2 * ((1.0 / 3.0) - x2 * ((1.0 / 5.0) - x2 * (1.0 / 7.0))));
    }
    if x2 < 4e-4 {
        // |x| < 0.02 (the usual tilt, and the yaw correction, which is second order in the tilt): to x^11,
        // truncation x^12 / 13 < 3.2e-22 relative.
        return x
            * (1.0
                - x2 * ((1.0 / 3.0)
                    - x2 * ((1.0 / 5.0) - x2 * ((1.0 / 7.0) - x2 * ((1.0 / 9.0) - x2 * (1.0 / 11.0))))));
    }
    x * (1.0
        - x2 * ((1.0 / 3.0)
            - x2 * ((1.0 / 5.0)
                - x2 * ((1.0 / 7.0)
                    - x2 * ((1.0 / 9.0) - x2 * ((1.0 / 11.0) - x2 * ((1.0 / 13.0) - x2 * (1.0 / 15.0))))))))
}

/// asin(x) for |x| < 0.1 by its Taylor series to x^15 (truncation < 1e-19); libm otherwise.
#[inline(always)]
pub(super) fn asin_small(x: f64) -> f64 {
    if x.abs() >= 0.1 {
        return x.asin();
    }
    let x2 = x * x;
    if x2 < 4e-4 {
        // |x| < 0.02: to x^11, truncation below 231/13312 x^12 < 3e-23 relative.
        return x
            * (1.0
                + x2 * ((1.0 / 6.0)
                    + x2 * ((3.0 / 40.0) + x2 * ((5.0 / 112.0) + x2 * ((35.0 / 1152.0) + x2 * (63.0 / 2816.0))))));
    }
    x * (1.0
        + x2 * ((1.0 / 6.0)
            + x2 * ((3.0 / 40.0)
                + x2 * ((5.0 / 112.0)
                    + x2 * ((35.0 / 1152.0)
                        + x2 * ((63.0 / 2816.0) + x2 * ((231.0 / 13312.0) + x2 * (143.0 / 10240.0))))))))
}

/// Wrap to (-pi, pi] without a division in the common case.
#[inline(always)]
pub(super) fn wrap_pi_fast(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if a > -PI && a <= PI {
        return a;
    }
    // Round to nearest by the 1.5 * 2^52 trick (exact for |x| < 2^51; avoids a libm call).
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let n = (a * (1.0 / TAU) + MAGIC) - MAGIC;
    let w = a - TAU * n;
    if w <= -PI {
        w + TAU
    } else if w > PI {
        w - TAU
    } else {
        w
    }
}
