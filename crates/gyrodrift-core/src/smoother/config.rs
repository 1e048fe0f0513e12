//! The smoother's settings ([`SmootherConfig`]), their range checks and the state layout they give.

use super::{DEFAULT_THERMAL_MIN_RANGE_C, DEFAULT_THERMAL_SIGMA_DEG_H_PER_C, MAX_UPDATES, POS};
use crate::error::{check, check_with, CoreError};
use crate::filter_prior::FilterSettings;
use crate::kalman::{N_STATES as N_BASE, STATE_NAMES as BASE_NAMES};
use crate::limits::{check_site, check_slow_bias};
use crate::units::DEG_PER_H;

/// Settings of the smoother (SI). Keys of the binding in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct SmootherConfig {
    /// Known static site \[rad, rad, m\] (`lat_rad`, `lon_rad`, `height_m`) and sample rate \[Hz\] (`rate_hz`).
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    pub rate_hz: f64,
    /// Coarse alignment at the start \[s\] (`coarse_s`, default 300).
    pub coarse_s: f64,
    /// The whole span from the first sample \[s\] (`span_s`, default 57600: 4 h alignment + 12 h).
    pub span_s: f64,
    /// Measurement interval \[s\] (`update_s`, default 10).
    pub update_s: f64,
    /// Initial attitude 1-sigma E N U \[rad\] (`att_sigma_rad`); None: the aligner's `coarse_attitude_sigma`.
    pub att_sigma: Option<[f64; 3]>,
    /// Prior 1-sigma of the constant gyro biases [rad/s] (`gyro_bias_sigma_rad_s`, default 0.1 deg/h: wide, so the
    /// prior pulls a 0.05 deg/h drift by less than 1e-7 deg/h; the defaults of this and every setting the aligner
    /// shares are [`FilterSettings::smoother`], whose module says why they differ from the aligner's).
    pub gyro_bias_sigma: [f64; 3],
    /// Prior 1-sigma of the accelerometer biases [m/s^2] (`accel_bias_sigma_m_s2`, default 100 ug).
    pub accel_bias_sigma: [f64; 3],
    /// Angle random walk [rad/sqrt(s)] (`gyro_arw_rad_rts`, default 0.0005 deg/sqrt(h)).
    pub gyro_arw: f64,
    /// Velocity random walk [m/s/sqrt(s)] (`accel_vrw_m_s_rts`, default 5 ug/sqrt(Hz)).
    pub accel_vrw: f64,
    /// Gauss-Markov bias instability (stationary sigma) [rad/s] (`gyro_bias_instability_rad_s`, 0 = no states).
    pub gyro_bias_instability: f64,
    /// Its correlation time \[s\] (`gyro_correlation_s`, default 3600).
    pub gyro_correlation: f64,
    /// Rate random walk [rad/s/sqrt(s)] (`gyro_rrw_rad_s_rts`, 0 = no states).
    pub gyro_rrw: f64,
    /// Zero-velocity measurement 1-sigma [m/s] (`zupt_sigma_m_s`, default 1e-4).
    pub zupt_sigma: f64,
    /// Known-position measurement 1-sigma \[m\] (`position_sigma_m`, default 0.01).
    pub position_sigma: f64,
    /// Interval of the reported history \[s\] (`history_s`, default 600).
    pub history_s: f64,
    /// Thermal model of the z drift (`thermal`, default false): one more random-constant state k_z
    /// [rad/s/degC], the z drift being eps_z + k_z (T - T_ref); `process` then needs every sample's temperature.
    pub thermal: bool,
    /// Prior 1-sigma of k_z [rad/s/degC] (`thermal_sigma_rad_s_per_c`, default 0.01 deg/h/degC: wide).
    pub thermal_sigma: f64,
    /// T_ref \[deg C\] (`temp_ref_c`); None: the temperature of the last sample of the coarse alignment.
    pub temp_ref: Option<f64>,
    /// Least temperature range over the span after the coarse alignment \[deg C\] for which the thermal model is
    /// the reported one (`thermal_min_range_c`, default 0.5); below it the constant model's estimates (the thermal
    /// state conditioned on k_z = 0) are reported.
    pub thermal_min_range: f64,
}

impl SmootherConfig {
    /// The defaults at a site.
    pub fn new(lat: f64, lon: f64, height: f64, rate_hz: f64) -> Self {
        Self::with_filter(lat, lon, height, rate_hz, FilterSettings::smoother())
    }

    /// The given filter settings at a site, every other setting at its default.
    pub fn with_filter(lat: f64, lon: f64, height: f64, rate_hz: f64, filter: FilterSettings) -> Self {
        SmootherConfig {
            lat,
            lon,
            height,
            rate_hz,
            coarse_s: filter.coarse_s,
            span_s: 57_600.0,
            update_s: filter.update_s,
            att_sigma: filter.att_sigma,
            gyro_bias_sigma: filter.gyro_bias_sigma,
            accel_bias_sigma: filter.accel_bias_sigma,
            gyro_arw: filter.gyro_arw,
            accel_vrw: filter.accel_vrw,
            gyro_bias_instability: 0.0,
            gyro_correlation: 3600.0,
            gyro_rrw: 0.0,
            zupt_sigma: filter.zupt_sigma,
            position_sigma: 0.01,
            history_s: filter.history_s,
            thermal: false,
            thermal_sigma: DEFAULT_THERMAL_SIGMA_DEG_H_PER_C * DEG_PER_H,
            temp_ref: None,
            thermal_min_range: DEFAULT_THERMAL_MIN_RANGE_C,
        }
    }

    /// Range checks; errors name the key.
    pub fn validate(&self) -> Result<(), CoreError> {
        use crate::error::{all_positive_at_most, in_range, sig, Unit, DEG_H_PER_C};
        check_site(self.lat, self.lon, self.height, self.rate_hz)?;
        // The shared settings have one set of limits, the aligner's.
        self.filter().validate(self.rate_hz)?;
        let s = Unit::Si("s");
        // Without process noise the covariance of the long span collapses and the filter stops listening.
        check(
            self.gyro_arw > 0.0 && self.accel_vrw > 0.0,
            if self.gyro_arw > 0.0 {
                "accel_vrw_m_s_rts"
            } else {
                "gyro_arw_rad_rts"
            },
            "the smoother needs positive noise densities (model a noise-free log with small ones)",
        )?;
        in_range("span_s", "span", self.span_s, self.coarse_s + self.update_s, 1e6, s)?;
        check_slow_bias(self.gyro_bias_instability, self.gyro_correlation, self.gyro_rrw)?;
        all_positive_at_most(
            "position_sigma_m",
            "position sigma",
            &[self.position_sigma],
            1e4,
            Unit::Si("m"),
        )?;
        all_positive_at_most(
            "thermal_sigma_rad_s_per_c",
            "thermal coefficient prior sigma",
            &[self.thermal_sigma],
            DEG_PER_H,
            DEG_H_PER_C,
        )?;
        if let Some(t) = self.temp_ref {
            in_range(
                "temp_ref_c",
                "reference temperature",
                t,
                -100.0,
                200.0,
                Unit::Si("deg C"),
            )?;
        }
        in_range(
            "thermal_min_range_c",
            "least temperature range",
            self.thermal_min_range,
            0.0,
            300.0,
            Unit::Si("deg C"),
        )?;
        let updates = ((self.span_s - self.coarse_s) / self.update_s).ceil();
        check_with(updates <= MAX_UPDATES as f64, "update_s", || {
            format!(
                "update interval {} s gives {} updates over the span; at most {MAX_UPDATES} are kept for the \
                 backward pass (use a longer interval)",
                sig(self.update_s),
                sig(updates)
            )
        })
    }

    /// The settings the aligner shares (flat here: `FilterSettings` names them once; `new` and `with_filter` take
    /// them from it).
    pub fn filter(&self) -> FilterSettings {
        FilterSettings {
            coarse_s: self.coarse_s,
            update_s: self.update_s,
            att_sigma: self.att_sigma,
            gyro_bias_sigma: self.gyro_bias_sigma,
            accel_bias_sigma: self.accel_bias_sigma,
            gyro_arw: self.gyro_arw,
            accel_vrw: self.accel_vrw,
            zupt_sigma: self.zupt_sigma,
            history_s: self.history_s,
        }
    }

    pub(super) fn has_gm(&self) -> bool {
        self.gyro_bias_instability > 0.0
    }

    pub(super) fn has_rrw(&self) -> bool {
        self.gyro_rrw > 0.0
    }

    /// Number of states (14, 17 or 20; one more with the thermal state).
    pub fn n_states(&self) -> usize {
        N_BASE + 2 + 3 * usize::from(self.has_gm()) + 3 * usize::from(self.has_rrw()) + usize::from(self.thermal)
    }

    /// Index of the thermal coefficient k_z (the last state; None when absent).
    pub(super) fn thermal_index(&self) -> Option<usize> {
        self.thermal.then(|| self.n_states() - 1)
    }

    /// First Gauss-Markov state and first random-walk state (None when absent).
    pub(super) fn gm_index(&self) -> Option<usize> {
        self.has_gm().then_some(POS + 2)
    }

    pub(super) fn rrw_index(&self) -> Option<usize> {
        self.has_rrw().then_some(POS + 2 + 3 * usize::from(self.has_gm()))
    }
}

/// Names of the states of a configuration, in order.
pub fn state_names(cfg: &SmootherConfig) -> Vec<&'static str> {
    let mut names: Vec<&'static str> = BASE_NAMES.to_vec();
    names.extend(["pos_n", "pos_e"]);
    if cfg.has_gm() {
        names.extend(["gyro_gm_x", "gyro_gm_y", "gyro_gm_z"]);
    }
    if cfg.has_rrw() {
        names.extend(["gyro_rrw_x", "gyro_rrw_y", "gyro_rrw_z"]);
    }
    if cfg.thermal {
        names.push("gyro_temp_z");
    }
    names
}
