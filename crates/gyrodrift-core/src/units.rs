//! One of each user unit in SI, so that `x * DEG_PER_H` is x deg/h in rad/s and `y / DEG_PER_H` is y rad/s in
//! deg/h. The crate computes in SI (rad, rad/s, m, m/s, s); these are the only conversion factors it writes.
//!
//! Rounding: `x * DEG / SQRT_HOUR` (x deg/sqrt(h)) and `x * DEG_PER_SQRT_H` can differ in the last bit; the
//! filters' default noise densities are written the first way, which keeps their values as they always were.

/// One degree \[rad\] (the factor of `f64::to_radians`).
pub const DEG: f64 = std::f64::consts::PI / 180.0;
/// One arcminute \[rad\].
pub const ARCMIN: f64 = DEG / 60.0;
/// One arcsecond \[rad\].
pub const ARCSEC: f64 = DEG / 3600.0;
/// One hour \[s\].
pub const HOUR: f64 = 3600.0;
/// The square root of one hour \[sqrt(s)\]: a density per sqrt(h) is 1/60 of the same per sqrt(s).
pub const SQRT_HOUR: f64 = 60.0;
/// One deg/h \[rad/s\] (a gyro drift).
pub const DEG_PER_H: f64 = DEG / HOUR;
/// One deg/sqrt(h) \[rad/sqrt(s)\] (an angle random walk).
pub const DEG_PER_SQRT_H: f64 = DEG / SQRT_HOUR;
/// One deg/h/sqrt(h) \[rad/s/sqrt(s)\] (a rate random walk).
pub const DEG_PER_H_PER_SQRT_H: f64 = DEG_PER_H / SQRT_HOUR;
/// One standard gravity g \[m/s^2\].
pub const STANDARD_GRAVITY: f64 = 9.806_65;
/// One micro-g \[m/s^2\] (an accelerometer bias); one ug/sqrt(Hz) is the same number in m/s/sqrt(s) (a velocity
/// random walk).
pub const MICRO_G: f64 = 9.806_65e-6;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_units_are_the_conversions_they_replace() {
        // Bit for bit: the crate's numbers did not move when the inline conversions became these constants.
        let pi = std::f64::consts::PI;
        assert_eq!(DEG, 1.0f64.to_radians());
        assert_eq!(DEG_PER_H, pi / 180.0 / 3600.0);
        assert_eq!(ARCSEC, pi / 180.0 / 3600.0);
        for x in [0.0005, 0.001] {
            assert_eq!(x * DEG / SQRT_HOUR, x * pi / 180.0 / 60.0);
        }
        assert_eq!(100.0 * DEG, 100.0 * pi / 180.0);
        // The factors of messages (`error::Unit`): rad/sqrt(s) in deg/sqrt(h), rad in arcsec, rad/s/sqrt(s) in
        // deg/h/sqrt(h), rad in deg.
        assert_eq!(SQRT_HOUR / DEG, 180.0 / pi * 60.0);
        assert_eq!(HOUR / DEG, 180.0 / pi * 3600.0);
        assert_eq!(HOUR * SQRT_HOUR / DEG, 180.0 / pi * 3600.0 * 60.0);
        assert_eq!(1.0 / DEG, 180.0 / pi);
        assert!((DEG_PER_SQRT_H * (SQRT_HOUR / DEG) - 1.0).abs() < 1e-15);
        assert!((DEG_PER_H_PER_SQRT_H * (HOUR * SQRT_HOUR / DEG) - 1.0).abs() < 1e-15);
        assert!((MICRO_G / (STANDARD_GRAVITY * 1e-6) - 1.0).abs() < 1e-15);
    }
}
