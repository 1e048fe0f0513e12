//! Temperature of the IMU [deg C] as a function of time \[s\]: the input of the temperature-dependent
//! axial drift (see `imu_error`).

use crate::error::{check, check_with, CoreError};
use std::f64::consts::TAU;

/// A daily swing added to a warm-up: A sin(2 pi t / P + phase) [deg C], with A the amplitude [deg C], P the
/// period \[s\] and the phase \[rad\] at t = 0; its rate is A (2 pi / P) cos(2 pi t / P + phase) [deg C/s].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DailySwing {
    pub amplitude_c: f64,
    pub period_s: f64,
    pub phase_rad: f64,
}

/// Default period of a daily swing \[s\] (24 h).
pub const DEFAULT_SWING_PERIOD_S: f64 = 86400.0;

impl DailySwing {
    /// No swing (amplitude 0).
    pub const NONE: DailySwing = DailySwing {
        amplitude_c: 0.0,
        period_s: DEFAULT_SWING_PERIOD_S,
        phase_rad: 0.0,
    };

    /// Angular frequency 2 pi / P [rad/s].
    #[inline]
    pub fn omega(&self) -> f64 {
        TAU / self.period_s
    }

    /// The swing's temperature [deg C] and rate [deg C/s] from the sine and cosine of its angle.
    #[inline]
    pub fn from_sin_cos(&self, sin: f64, cos: f64) -> (f64, f64) {
        (self.amplitude_c * sin, self.amplitude_c * self.omega() * cos)
    }

    /// The swing's temperature [deg C] and rate [deg C/s] at time t \[s\].
    #[inline]
    pub fn at(&self, t: f64) -> (f64, f64) {
        let (s, c) = (self.omega() * t + self.phase_rad).sin_cos();
        self.from_sin_cos(s, c)
    }
}

/// A temperature profile T(t) [deg C], t in s from the start of the run.
#[derive(Clone, Debug, PartialEq)]
pub enum TemperatureProfile {
    /// Warm-up with a daily swing: T(t) = end + (start - end) exp(-t / tau) + A sin(2 pi t / P + phase);
    /// dT/dt = -(start - end) / tau exp(-t / tau) + A (2 pi / P) cos(2 pi t / P + phase).
    WarmUp {
        start_c: f64,
        end_c: f64,
        tau_s: f64,
        swing: DailySwing,
    },
    /// Measured series, linearly interpolated; held constant (dT/dt = 0) outside [t_0, t_last].
    /// Times strictly increasing.
    Series { t_s: Vec<f64>, temp_c: Vec<f64> },
}

/// Default temperature of a warm-up's start [deg C] and its time constant \[s\].
pub const DEFAULT_TEMP_C: f64 = 20.0;
pub const DEFAULT_TAU_S: f64 = 3600.0;

impl TemperatureProfile {
    /// A profile from its named settings (the keywords of the binding's `SimulatorConfig`): a series when both
    /// `series_t_s` and `series_c` are given (a swing amplitude other than 0 is then refused), else a warm-up
    /// with `start_c` (default `DEFAULT_TEMP_C`), `end_c` (default `start_c`: constant) and `tau_s` (default
    /// `DEFAULT_TAU_S`) plus the daily swing `swing` = (amplitude [deg C], period \[s\], phase \[rad\]), each
    /// defaulting to `DailySwing::NONE`'s (0, `DEFAULT_SWING_PERIOD_S`, 0).
    pub fn from_settings(
        start_c: Option<f64>,
        end_c: Option<f64>,
        tau_s: Option<f64>,
        swing: (Option<f64>, Option<f64>, Option<f64>),
        series_t_s: Option<Vec<f64>>,
        series_c: Option<Vec<f64>>,
    ) -> Result<Self, CoreError> {
        let (amplitude_c, period_s, phase_rad) = swing;
        match (series_t_s, series_c) {
            (Some(t_s), Some(temp_c)) => {
                check(
                    amplitude_c.unwrap_or(0.0) == 0.0,
                    "temp_swing_amplitude_c",
                    "must be 0 with a temperature series (a measured series carries its own swings)",
                )?;
                Ok(TemperatureProfile::Series { t_s, temp_c })
            }
            (None, None) => {
                let start_c = start_c.unwrap_or(DEFAULT_TEMP_C);
                let none = DailySwing::NONE;
                Ok(TemperatureProfile::WarmUp {
                    start_c,
                    end_c: end_c.unwrap_or(start_c),
                    tau_s: tau_s.unwrap_or(DEFAULT_TAU_S),
                    swing: DailySwing {
                        amplitude_c: amplitude_c.unwrap_or(none.amplitude_c),
                        period_s: period_s.unwrap_or(none.period_s),
                        phase_rad: phase_rad.unwrap_or(none.phase_rad),
                    },
                })
            }
            (Some(_), None) => Err(CoreError::Setting {
                key: "temp_series_c",
                message: "required with temp_series_t_s".to_string(),
            }),
            (None, Some(_)) => Err(CoreError::Setting {
                key: "temp_series_t_s",
                message: "required with temp_series_c".to_string(),
            }),
        }
    }

    /// Validate; errors name the contract key.
    pub fn validate(&self) -> Result<(), CoreError> {
        match self {
            TemperatureProfile::WarmUp {
                start_c,
                end_c,
                tau_s,
                swing,
            } => {
                check_with(
                    start_c.is_finite() && (-100.0..=200.0).contains(start_c),
                    "temp_start_c",
                    || format!("must be in [-100, 200] deg C, got {start_c}"),
                )?;
                check_with(
                    end_c.is_finite() && (-100.0..=200.0).contains(end_c),
                    "temp_end_c",
                    || format!("must be in [-100, 200] deg C, got {end_c}"),
                )?;
                check_with(tau_s.is_finite() && *tau_s > 0.0, "temp_tau_s", || {
                    format!("must be positive and finite, got {tau_s}")
                })?;
                let a = swing.amplitude_c;
                check_with(
                    a.is_finite() && a >= 0.0 && start_c.min(*end_c) - a >= -100.0 && start_c.max(*end_c) + a <= 200.0,
                    "temp_swing_amplitude_c",
                    || format!("must be >= 0 deg C and keep the warm-up within [-100, 200] deg C, got {a}"),
                )?;
                check_with(
                    swing.period_s.is_finite() && swing.period_s > 0.0,
                    "temp_swing_period_s",
                    || format!("must be positive and finite, got {}", swing.period_s),
                )?;
                check_with(swing.phase_rad.is_finite(), "temp_swing_phase_rad", || {
                    format!("must be finite, got {}", swing.phase_rad)
                })
            }
            TemperatureProfile::Series { t_s, temp_c } => {
                check(!t_s.is_empty(), "temp_series_t_s", "must not be empty")?;
                check_with(t_s.len() == temp_c.len(), "temp_series_c", || {
                    format!("has {} values but temp_series_t_s has {}", temp_c.len(), t_s.len())
                })?;
                check(t_s.iter().all(|t| t.is_finite()), "temp_series_t_s", "must be finite")?;
                check(
                    t_s.windows(2).all(|w| w[1] > w[0]),
                    "temp_series_t_s",
                    "must be strictly increasing",
                )?;
                check(
                    temp_c.iter().all(|c| c.is_finite() && (-100.0..=200.0).contains(c)),
                    "temp_series_c",
                    "must be finite and in [-100, 200] deg C",
                )
            }
        }
    }

    /// Temperature [deg C] and its rate dT/dt [deg C/s] at time t \[s\].
    #[inline]
    pub fn at(&self, t: f64) -> (f64, f64) {
        match self {
            TemperatureProfile::WarmUp {
                start_c,
                end_c,
                tau_s,
                swing,
            } => {
                let e = (-t / tau_s).exp();
                let (s, r) = swing.at(t);
                (end_c + (start_c - end_c) * e + s, -(start_c - end_c) / tau_s * e + r)
            }
            TemperatureProfile::Series { t_s, temp_c } => {
                let n = t_s.len();
                if n == 1 || t <= t_s[0] {
                    return (temp_c[0], 0.0);
                }
                if t >= t_s[n - 1] {
                    return (temp_c[n - 1], 0.0);
                }
                let i = t_s.partition_point(|&x| x <= t) - 1;
                let slope = (temp_c[i + 1] - temp_c[i]) / (t_s[i + 1] - t_s[i]);
                (temp_c[i] + slope * (t - t_s[i]), slope)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warm_up_closed_form() {
        let p = TemperatureProfile::WarmUp {
            start_c: 20.0,
            end_c: 40.0,
            tau_s: 3600.0,
            swing: DailySwing::NONE,
        };
        let (t0, r0) = p.at(0.0);
        assert_eq!(t0, 20.0);
        assert!((r0 - 20.0 / crate::units::HOUR).abs() < 1e-15);
        let (t1, _) = p.at(3600.0);
        assert!((t1 - (40.0 - 20.0 / std::f64::consts::E)).abs() < 1e-12);
        assert!((p.at(1e7).0 - 40.0).abs() < 1e-9);
    }

    #[test]
    fn swing_closed_form() {
        let swing = DailySwing {
            amplitude_c: 3.0,
            period_s: 86400.0,
            phase_rad: 0.5,
        };
        let p = TemperatureProfile::WarmUp {
            start_c: 15.0,
            end_c: 25.0,
            tau_s: 7200.0,
            swing,
        };
        p.validate().unwrap();
        let t = 30000.0;
        let w = TAU / 86400.0;
        let e = (-t / 7200.0f64).exp();
        let (temp, rate) = p.at(t);
        assert!((temp - (25.0 - 10.0 * e + 3.0 * (w * t + 0.5).sin())).abs() < 1e-12);
        assert!((rate - (10.0 / 7200.0 * e + 3.0 * w * (w * t + 0.5).cos())).abs() < 1e-15);
        let too_big = TemperatureProfile::WarmUp {
            start_c: 190.0,
            end_c: 198.0,
            tau_s: 1.0,
            swing,
        };
        assert_eq!(too_big.validate().unwrap_err().key(), "temp_swing_amplitude_c");
        let series = TemperatureProfile::from_settings(
            None,
            None,
            None,
            (Some(2.0), None, None),
            Some(vec![0.0, 1.0]),
            Some(vec![20.0, 21.0]),
        );
        assert_eq!(series.unwrap_err().key(), "temp_swing_amplitude_c");
    }

    #[test]
    fn series_interpolates_and_holds() {
        let p = TemperatureProfile::Series {
            t_s: vec![0.0, 10.0, 30.0],
            temp_c: vec![20.0, 21.0, 20.0],
        };
        p.validate().unwrap();
        assert_eq!(p.at(5.0), (20.5, 0.1));
        assert_eq!(p.at(20.0), (20.5, -0.05));
        assert_eq!(p.at(40.0), (20.0, 0.0));
        assert_eq!(p.at(-1.0), (20.0, 0.0));
        let bad = TemperatureProfile::Series {
            t_s: vec![0.0, 0.0],
            temp_c: vec![1.0, 2.0],
        };
        assert_eq!(bad.validate().unwrap_err().key(), "temp_series_t_s");
    }
}
