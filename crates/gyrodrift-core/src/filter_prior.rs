//! The default prior and process noise of the two static-base filters, declared side by side: the fine
//! alignment's ([`FilterPrior::ALIGNER`], `alignment::AlignerConfig::new`) and the smoother's
//! ([`FilterPrior::SMOOTHER`], `smoother::SmootherConfig::new`; the planner and the label's sigma share its model).
//! They differ on purpose, because the two filters do different jobs with the same error model:
//!
//! - Gyro bias prior, 0.01 against 0.1 deg/h. The aligner's result is the attitude; its bias prior is the
//!   navigation-grade RLG bias the package is about, which the default coarse-attitude sigma also takes as known
//!   (`alignment::coarse_attitude_sigma`: about 220 arcsec of heading). Its z-gyro estimate is weakly observable in
//!   4 h and is never applied (docs/alignment-contract.md). The smoother's result is the z drift itself, so its prior
//!   is wide: it pulls a 0.05 deg/h drift by less than 1e-7 deg/h, and the drift comes from the data.
//! - Angle and velocity random walk, 0.001 deg/sqrt(h) and 10 ug/sqrt(Hz) against 0.0005 and 5. The smoother is
//!   given the log's noise (`gyrodrift.procedure.smoother` passes the measured or given `SensorNoise`, whose default
//!   is this one: the RLG grade of the study); the procedure's aligner always runs on its defaults, twice that
//!   grade, so that a 4 h filter which is not told the log's noise over-bounds it rather than trusting it.
//! - Accelerometer bias prior: 100 ug in both.
//!
//! The values are stored in the units they are quoted in; the SI accessors convert with `units`.

use crate::units::{DEG, DEG_PER_H, MICRO_G, SQRT_HOUR};

/// A filter's default prior 1-sigma of the constant sensor biases (all three axes) and its process noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterPrior {
    /// Gyro bias prior 1-sigma \[deg/h\].
    pub gyro_bias_sigma_deg_h: f64,
    /// Accelerometer bias prior 1-sigma \[ug\].
    pub accel_bias_sigma_ug: f64,
    /// Gyro angle random walk \[deg/sqrt(h)\].
    pub gyro_arw_deg_rth: f64,
    /// Accelerometer velocity random walk \[ug/sqrt(Hz)\].
    pub accel_vrw_ug_rthz: f64,
}

impl FilterPrior {
    /// The fine alignment's defaults (module docs).
    pub const ALIGNER: FilterPrior = FilterPrior {
        gyro_bias_sigma_deg_h: 0.01,
        accel_bias_sigma_ug: 100.0,
        gyro_arw_deg_rth: 0.001,
        accel_vrw_ug_rthz: 10.0,
    };

    /// The smoother's defaults (module docs); `SensorNoise`'s default ARW and VRW in Python are these.
    pub const SMOOTHER: FilterPrior = FilterPrior {
        gyro_bias_sigma_deg_h: 0.1,
        accel_bias_sigma_ug: 100.0,
        gyro_arw_deg_rth: 0.0005,
        accel_vrw_ug_rthz: 5.0,
    };

    /// Gyro bias prior 1-sigma \[rad/s\], body x y z.
    pub fn gyro_bias_sigma(&self) -> [f64; 3] {
        [self.gyro_bias_sigma_deg_h * DEG_PER_H; 3]
    }

    /// Accelerometer bias prior 1-sigma \[m/s^2\], body x y z.
    pub fn accel_bias_sigma(&self) -> [f64; 3] {
        [self.accel_bias_sigma_ug * MICRO_G; 3]
    }

    /// Gyro angle random walk \[rad/sqrt(s)\].
    pub fn gyro_arw(&self) -> f64 {
        self.gyro_arw_deg_rth * DEG / SQRT_HOUR
    }

    /// Accelerometer velocity random walk \[m/s/sqrt(s)\].
    pub fn accel_vrw(&self) -> f64 {
        self.accel_vrw_ug_rthz * MICRO_G
    }
}
