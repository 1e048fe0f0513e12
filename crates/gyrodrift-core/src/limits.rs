//! The ranges of the quantities the simulator, the navigator and the aligner share (site, sample rate,
//! duration, attitude, IMU samples), defined once and checked here by all three. The binding exposes the
//! constants to Python (`gyrodrift._core.MAX_LAT_DEG`, ...) so the scenario files and the log reader refuse
//! the same values with their own file and key.
//!
//! Why these limits (static base, ENU local-level mechanisation):
//! - latitude |lat| <= 89 deg: the north-pointing local-level mechanisation divides by cos(lat) (longitude
//!   rate, transport rate tan(lat)), and gyrocompassing sees only the horizontal Earth rate w_ie cos(lat):
//!   at 89 deg it is 0.26 deg/h and the heading error of a given gyro bias is 57 times the equator's; nearer
//!   the pole the heading is not observable at the accuracy this package is about.
//! - height in [-1000, 20000] m above the ellipsoid: every static site on land (the lowest, the Dead Sea
//!   shore, is about -430 m, the geoid is within +-110 m of the ellipsoid) up to a stratospheric balloon;
//!   the second-order free-air term of the normal gravity is accurate to 1e-6 relative there.
//! - longitude within +-360 deg (either convention, east-positive).
//! - sample rate in [1, 100000] Hz: below 1 Hz the coning/sculling and table-angle quadratures of one sample
//!   are no longer small-angle; 100 kHz is above any navigation-grade IMU output.
//! - duration (0, 1e7] s: 116 days, longer than any run of an inertial system.
//! - attitude: pitch in (-90, 90) deg (Euler singularity at +-90), roll within +-180 deg, yaw within +-360 deg.
//! - samples: an angular rate above 1000 deg/s or a specific force above 100 g is outside every
//!   navigation-grade sensor's range (these are also the log reader's limits); non-finite samples are refused.
//! - the z gyro's slow bias terms of the filters' models (`check_slow_bias`): Gauss-Markov 1-sigma and rate random
//!   walk up to 0.1 deg/h and 0.1 deg/h/sqrt(h), correlation time (0, 1e9] s.

use crate::attitude::Euler;
use crate::error::{
    all_positive_at_most, check_with, in_range, CoreError, Unit, DEG_H_PER_RTH, DEG_PER_RTH, MICRO_G_PER_RTHZ,
};
use crate::units::STANDARD_GRAVITY;

/// Largest |latitude| \[deg\] (module docs).
pub const MAX_LAT_DEG: f64 = 89.0;
/// Largest |longitude| \[deg\].
pub const MAX_LON_DEG: f64 = 360.0;
/// Lowest and highest height above the ellipsoid \[m\].
pub const MIN_HEIGHT_M: f64 = -1000.0;
pub const MAX_HEIGHT_M: f64 = 20_000.0;
/// Lowest and highest IMU sample rate \[Hz\].
pub const MIN_RATE_HZ: f64 = 1.0;
pub const MAX_RATE_HZ: f64 = 100_000.0;
/// Longest simulated run \[s\].
pub const MAX_DURATION_S: f64 = 1e7;
/// Largest |pitch| (exclusive), |roll|, |yaw| \[deg\].
pub const MAX_PITCH_DEG: f64 = 90.0;
pub const MAX_ROLL_DEG: f64 = 180.0;
pub const MAX_YAW_DEG: f64 = 360.0;
/// Largest angular rate [deg/s] and specific force \[g\] of a sample (per-axis magnitude of the mean over the
/// sample: increment / dt).
pub const MAX_ANGULAR_RATE_DEG_S: f64 = 1000.0;
pub const MAX_SPECIFIC_FORCE_G: f64 = 100.0;

/// Checks of the site and the sample rate.
pub fn check_site(lat: f64, lon: f64, height: f64, rate_hz: f64) -> Result<(), CoreError> {
    let lat_max = MAX_LAT_DEG.to_radians();
    in_range("lat_rad", "latitude", lat, -lat_max, lat_max, Unit::Deg)?;
    let lon_max = MAX_LON_DEG.to_radians();
    in_range("lon_rad", "longitude", lon, -lon_max, lon_max, Unit::Deg)?;
    in_range("height_m", "height", height, MIN_HEIGHT_M, MAX_HEIGHT_M, Unit::Si("m"))?;
    check_rate(rate_hz)
}

/// Check of the IMU sample rate.
pub fn check_rate(rate_hz: f64) -> Result<(), CoreError> {
    in_range(
        "rate_hz",
        "sample rate",
        rate_hz,
        MIN_RATE_HZ,
        MAX_RATE_HZ,
        Unit::Si("Hz"),
    )
}

/// Check of a run length \[s\] at `rate_hz` (at least one sample).
pub fn check_duration(duration_s: f64, rate_hz: f64) -> Result<(), CoreError> {
    check_with(
        duration_s.is_finite() && duration_s > 0.0 && duration_s <= MAX_DURATION_S,
        "duration_s",
        || {
            format!(
                "duration {} s is outside (0, {}] s",
                crate::error::sig(duration_s),
                MAX_DURATION_S
            )
        },
    )?;
    check_with((duration_s * rate_hz).round() >= 1.0, "duration_s", || {
        format!(
            "duration {} s gives no sample at {} Hz",
            crate::error::sig(duration_s),
            crate::error::sig(rate_hz)
        )
    })
}

/// Checks of an attitude.
pub fn check_attitude(e: Euler) -> Result<(), CoreError> {
    let p = MAX_PITCH_DEG.to_radians();
    check_with(e.pitch.is_finite() && e.pitch.abs() < p, "pitch_rad", || {
        format!(
            "pitch {} is outside (-{MAX_PITCH_DEG}, {MAX_PITCH_DEG}) deg",
            Unit::Deg.show(e.pitch)
        )
    })?;
    let r = MAX_ROLL_DEG.to_radians();
    in_range("roll_rad", "roll", e.roll, -r, r, Unit::Deg)?;
    let y = MAX_YAW_DEG.to_radians();
    in_range("yaw_rad", "yaw", e.yaw, -y, y, Unit::Deg)
}

/// A gyro's angle random walk [rad/sqrt(s)]: finite, in [0, 0.1] (344 deg/sqrt(h)); one limit for the simulated
/// IMU and the filters' models.
pub(crate) fn check_arw(arw: f64) -> Result<(), CoreError> {
    in_range("gyro_arw_rad_rts", "angle random walk", arw, 0.0, 0.1, DEG_PER_RTH)
}

/// An accelerometer's velocity random walk [m/s/sqrt(s)]: finite, in [0, 1] (102 000 ug/sqrt(Hz)); one limit for
/// the simulated IMU and the filters' models.
pub(crate) fn check_vrw(vrw: f64) -> Result<(), CoreError> {
    in_range(
        "accel_vrw_m_s_rts",
        "velocity random walk",
        vrw,
        0.0,
        1.0,
        MICRO_G_PER_RTHZ,
    )
}

/// The z gyro's slow bias terms (Gauss-Markov 1-sigma [rad/s] and correlation time \[s\], rate random walk
/// [rad/s/sqrt(s)]): one set of limits for the smoother, the label's sigma and the planner.
pub(crate) fn check_slow_bias(instability: f64, correlation: f64, rrw: f64) -> Result<(), CoreError> {
    in_range(
        "gyro_bias_instability_rad_s",
        "bias instability",
        instability,
        0.0,
        0.1,
        Unit::DegPerH,
    )?;
    all_positive_at_most(
        "gyro_correlation_s",
        "correlation time",
        &[correlation],
        1e9,
        Unit::Si("s"),
    )?;
    in_range("gyro_rrw_rad_s_rts", "rate random walk", rrw, 0.0, 0.1, DEG_H_PER_RTH)
}

/// Checks of streamed increments given as flat row-major (n x 3) slices (dtheta \[rad\], dv [m/s]) at sample
/// interval `dt` \[s\]: equal whole lengths, every value finite, rate and specific force within the limits.
/// Returns n.
pub fn check_increments(dtheta: &[f64], dv: &[f64], dt: f64) -> Result<usize, CoreError> {
    check_lengths(dtheta, dv)?;
    // Bounds on the increments: |x| <= limit is false for NaN, so one comparison per value checks both.
    let (max_dth, max_dv) = increment_bounds(dt);
    let ok = |v: &[f64], lim: f64| v.iter().fold(true, |acc, x| acc & (x.abs() <= lim));
    if ok(dtheta, max_dth) && ok(dv, max_dv) {
        return Ok(dtheta.len() / 3);
    }
    // Rare path: find the first offending value for the message.
    for (i, (a, b)) in dtheta.chunks_exact(3).zip(dv.chunks_exact(3)).enumerate() {
        if let Some(x) = a.iter().find(|x| x.is_nan() || x.abs() > max_dth) {
            return Err(sample_error(
                "dtheta_rad",
                i,
                *x / dt,
                Unit::DegPerS,
                MAX_ANGULAR_RATE_DEG_S,
            ));
        }
        if let Some(x) = b.iter().find(|x| x.is_nan() || x.abs() > max_dv) {
            return Err(sample_error("dv_m_s", i, *x / dt, Unit::G, MAX_SPECIFIC_FORCE_G));
        }
    }
    // Invariant: the fold above found a value failing the same bound, so the loop has returned.
    unreachable!("some value failed the bound above")
}

/// The largest |dtheta| \[rad\] and |dv| [m/s] of one sample of `dt` \[s\]: the rate and specific-force limits
/// times dt (one computation for every check of increments).
pub fn increment_bounds(dt: f64) -> (f64, f64) {
    (
        MAX_ANGULAR_RATE_DEG_S.to_radians() * dt,
        MAX_SPECIFIC_FORCE_G * STANDARD_GRAVITY * dt,
    )
}

/// The length checks of `check_increments` alone: whole rows of 3, as many in `dv` as in `dtheta`.
pub fn check_lengths(dtheta: &[f64], dv: &[f64]) -> Result<(), CoreError> {
    check_shape(dtheta.len() % 3 == 0, "dtheta_rad", dtheta.len())?;
    check_shape(dv.len() % 3 == 0, "dv_m_s", dv.len())?;
    if dtheta.len() != dv.len() {
        return Err(CoreError::Shape {
            key: "dv_m_s",
            message: format!("has {} rows but dtheta_rad has {}", dv.len() / 3, dtheta.len() / 3),
        });
    }
    Ok(())
}

fn check_shape(ok: bool, key: &'static str, len: usize) -> Result<(), CoreError> {
    if ok {
        Ok(())
    } else {
        Err(CoreError::Shape {
            key,
            message: format!("{len} values do not form rows of 3 (x, y, z)"),
        })
    }
}

fn sample_error(key: &'static str, index: usize, mean: f64, unit: Unit, limit: f64) -> CoreError {
    let what = if key == "dtheta_rad" {
        "angular rate"
    } else {
        "specific force"
    };
    let message = if mean.is_finite() {
        format!(
            "{what} {} exceeds {}",
            unit.show(mean.abs()),
            unit.show(unit.to_si(limit))
        )
    } else {
        format!("{what} is not finite ({mean})")
    };
    CoreError::Sample { key, index, message }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn site_messages_in_degrees_name_the_key() {
        let e = check_site(89.5f64.to_radians(), 0.0, 0.0, 100.0).unwrap_err();
        assert_eq!(e.key(), "lat_rad");
        assert!(e.to_string().contains("89.5 deg is outside [-89, 89] deg"), "{e}");
        assert_eq!(check_site(0.5, 0.0, 3e4, 100.0).unwrap_err().key(), "height_m");
        assert_eq!(check_site(0.5, 7.0, 0.0, 100.0).unwrap_err().key(), "lon_rad");
        assert_eq!(check_site(0.5, 0.0, 0.0, 1e308).unwrap_err().key(), "rate_hz");
        check_site(0.5, 0.0, 0.0, 100.0).unwrap();
    }

    #[test]
    fn increments_refuse_nan_huge_and_ragged() {
        let dt = 0.01;
        let good = [0.0, 0.0, 1e-6];
        let g = [0.0, 0.0, 0.0981];
        assert_eq!(check_increments(&good, &g, dt).unwrap(), 1);
        assert_eq!(check_increments(&[], &[], dt).unwrap(), 0);
        let e = check_increments(&[0.0, f64::NAN, 0.0], &g, dt).unwrap_err();
        assert!(
            matches!(
                e,
                CoreError::Sample {
                    key: "dtheta_rad",
                    index: 0,
                    ..
                }
            ),
            "{e}"
        );
        let e = check_increments(&[good, good].concat(), &[g, [1e300, 0.0, 0.0]].concat(), dt).unwrap_err();
        assert!(
            matches!(
                e,
                CoreError::Sample {
                    key: "dv_m_s",
                    index: 1,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("exceeds 100 g"), "{e}");
        let e = check_increments(&good, &[0.0; 6], dt).unwrap_err();
        assert_eq!(e.key(), "dv_m_s");
        let e = check_increments(&[0.0; 4], &[0.0; 4], dt).unwrap_err();
        assert_eq!(e.key(), "dtheta_rad");
    }
}
