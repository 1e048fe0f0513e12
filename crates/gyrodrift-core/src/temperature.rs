//! Temperature of the IMU [deg C] as a function of time \[s\]: the input of the temperature-dependent
//! axial drift (see `imu_error`).

use crate::error::{check, CoreError};

/// A temperature profile T(t) [deg C], t in s from the start of the run.
#[derive(Clone, Debug, PartialEq)]
pub enum TemperatureProfile {
    /// Warm-up: T(t) = end + (start - end) exp(-t / tau); dT/dt = -(start - end) / tau exp(-t / tau).
    WarmUp { start_c: f64, end_c: f64, tau_s: f64 },
    /// Measured series, linearly interpolated; held constant (dT/dt = 0) outside [t_0, t_last].
    /// Times strictly increasing.
    Series { t_s: Vec<f64>, temp_c: Vec<f64> },
}

/// Default temperature of a warm-up's start [deg C] and its time constant \[s\].
pub const DEFAULT_TEMP_C: f64 = 20.0;
pub const DEFAULT_TAU_S: f64 = 3600.0;

impl TemperatureProfile {
    /// A profile from its named settings (the keywords of the binding's `SimulatorConfig`): a series when both
    /// `series_t_s` and `series_c` are given, else a warm-up with `start_c` (default `DEFAULT_TEMP_C`), `end_c`
    /// (default `start_c`: constant) and `tau_s` (default `DEFAULT_TAU_S`).
    pub fn from_settings(
        start_c: Option<f64>,
        end_c: Option<f64>,
        tau_s: Option<f64>,
        series_t_s: Option<Vec<f64>>,
        series_c: Option<Vec<f64>>,
    ) -> Result<Self, CoreError> {
        match (series_t_s, series_c) {
            (Some(t_s), Some(temp_c)) => Ok(TemperatureProfile::Series { t_s, temp_c }),
            (None, None) => {
                let start_c = start_c.unwrap_or(DEFAULT_TEMP_C);
                Ok(TemperatureProfile::WarmUp {
                    start_c,
                    end_c: end_c.unwrap_or(start_c),
                    tau_s: tau_s.unwrap_or(DEFAULT_TAU_S),
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
            TemperatureProfile::WarmUp { start_c, end_c, tau_s } => {
                check(
                    start_c.is_finite() && (-100.0..=200.0).contains(start_c),
                    "temp_start_c",
                    format!("must be in [-100, 200] deg C, got {start_c}"),
                )?;
                check(
                    end_c.is_finite() && (-100.0..=200.0).contains(end_c),
                    "temp_end_c",
                    format!("must be in [-100, 200] deg C, got {end_c}"),
                )?;
                check(
                    tau_s.is_finite() && *tau_s > 0.0,
                    "temp_tau_s",
                    format!("must be positive and finite, got {tau_s}"),
                )
            }
            TemperatureProfile::Series { t_s, temp_c } => {
                check(!t_s.is_empty(), "temp_series_t_s", "must not be empty")?;
                check(
                    t_s.len() == temp_c.len(),
                    "temp_series_c",
                    format!("has {} values but temp_series_t_s has {}", temp_c.len(), t_s.len()),
                )?;
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
            TemperatureProfile::WarmUp { start_c, end_c, tau_s } => {
                let e = (-t / tau_s).exp();
                (end_c + (start_c - end_c) * e, -(start_c - end_c) / tau_s * e)
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
        };
        let (t0, r0) = p.at(0.0);
        assert_eq!(t0, 20.0);
        assert!((r0 - 20.0 / crate::units::HOUR).abs() < 1e-15);
        let (t1, _) = p.at(3600.0);
        assert!((t1 - (40.0 - 20.0 / std::f64::consts::E)).abs() < 1e-12);
        assert!((p.at(1e7).0 - 40.0).abs() < 1e-9);
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
