//! The settings the two static-base filters share ([`FilterSettings`]: the coarse span, the update interval, the
//! prior, the process noise, the zero-velocity sigma and the history interval) and their defaults, declared side by
//! side: the fine alignment's ([`FilterSettings::aligner`], used by `alignment::AlignerConfig::new`) and the
//! smoother's ([`FilterSettings::smoother`], `smoother::SmootherConfig::new`; the planner and the label's sigma
//! share its model). The prior and the noise ([`FilterPrior`]) differ on purpose, because the two filters do
//! different jobs with the same error model:
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
//! The measurement settings differ too: the aligner updates every 1 s with a 0.001 m/s zero-velocity sigma and
//! records its covariance every 60 s; the smoother updates every 10 s (it keeps every update for the backward pass,
//! at most `smoother::MAX_UPDATES`) with 1e-4 m/s and records every 600 s. Both start with a 300 s coarse alignment.
//!
//! The prior's values are stored in the units they are quoted in; the SI accessors convert with `units`.

use crate::attitude::Vec3;
use crate::error::{self, all_positive_at_most, check_with, in_range, sig, CoreError, Unit};
use crate::limits::{check_arw, check_vrw};
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

/// The settings of a static-base error-state filter that the aligner (`alignment::AlignerConfig`) and the smoother
/// (`smoother::SmootherConfig`) share (SI). Keys of the binding in brackets; the defaults are the two constructors'.
#[derive(Clone, Debug, PartialEq)]
pub struct FilterSettings {
    /// Coarse alignment span at the start \[s\] (`coarse_s`).
    pub coarse_s: f64,
    /// Zero-velocity measurement interval \[s\] (`update_s`).
    pub update_s: f64,
    /// Initial attitude error 1-sigma E, N, U \[rad\] (`att_sigma_rad`); None: `alignment::coarse_attitude_sigma`.
    pub att_sigma: Option<Vec3>,
    /// Prior 1-sigma of the constant gyro biases, body x y z \[rad/s\] (`gyro_bias_sigma_rad_s`).
    pub gyro_bias_sigma: Vec3,
    /// Prior 1-sigma of the accelerometer biases, body x y z \[m/s^2\] (`accel_bias_sigma_m_s2`).
    pub accel_bias_sigma: Vec3,
    /// Gyro angle random walk \[rad/sqrt(s)\] (`gyro_arw_rad_rts`).
    pub gyro_arw: f64,
    /// Accelerometer velocity random walk \[m/s/sqrt(s)\] (`accel_vrw_m_s_rts`).
    pub accel_vrw: f64,
    /// Zero-velocity measurement noise 1-sigma \[m/s\] (`zupt_sigma_m_s`).
    pub zupt_sigma: f64,
    /// Interval of the reported covariance history \[s\] (`history_s`).
    pub history_s: f64,
}

impl FilterSettings {
    /// The fine alignment's defaults (module docs): 300 s coarse, 1 s updates, 0.001 m/s, history every 60 s.
    pub fn aligner() -> Self {
        Self::with_prior(&FilterPrior::ALIGNER, 1.0, 1e-3, 60.0)
    }

    /// The smoother's defaults (module docs): 300 s coarse, 10 s updates, 1e-4 m/s, history every 600 s.
    pub fn smoother() -> Self {
        Self::with_prior(&FilterPrior::SMOOTHER, 10.0, 1e-4, 600.0)
    }

    fn with_prior(prior: &FilterPrior, update_s: f64, zupt_sigma: f64, history_s: f64) -> Self {
        FilterSettings {
            coarse_s: 300.0,
            update_s,
            att_sigma: None,
            gyro_bias_sigma: prior.gyro_bias_sigma(),
            accel_bias_sigma: prior.accel_bias_sigma(),
            gyro_arw: prior.gyro_arw(),
            accel_vrw: prior.accel_vrw(),
            zupt_sigma,
            history_s,
        }
    }

    /// Range checks at a sample rate `rate_hz` \[Hz\] (one set of limits for both filters); errors name the key.
    pub fn validate(&self, rate_hz: f64) -> Result<(), CoreError> {
        let s = Unit::Si("s");
        in_range("coarse_s", "coarse span", self.coarse_s, 10.0, 86_400.0, s)?;
        all_positive_at_most("update_s", "update interval", &[self.update_s], 60.0, s)?;
        check_with((self.update_s * rate_hz).round() >= 1.0, "update_s", || {
            format!(
                "update interval {} s holds no sample at {} Hz",
                sig(self.update_s),
                sig(rate_hz)
            )
        })?;
        if let Some(a) = self.att_sigma {
            all_positive_at_most("att_sigma_rad", "initial attitude sigma", &a, 0.2, error::ARCSEC)?;
        }
        let gyro = &self.gyro_bias_sigma;
        all_positive_at_most("gyro_bias_sigma_rad_s", "gyro bias sigma", gyro, 0.1, Unit::DegPerH)?;
        let acc = &self.accel_bias_sigma;
        all_positive_at_most(
            "accel_bias_sigma_m_s2",
            "accelerometer bias sigma",
            acc,
            10.0,
            error::MICRO_G,
        )?;
        check_arw(self.gyro_arw)?;
        check_vrw(self.accel_vrw)?;
        let zupt = [self.zupt_sigma];
        all_positive_at_most("zupt_sigma_m_s", "zero-velocity sigma", &zupt, 10.0, Unit::Si("m/s"))?;
        all_positive_at_most("history_s", "history interval", &[self.history_s], 1e6, s)
    }
}
