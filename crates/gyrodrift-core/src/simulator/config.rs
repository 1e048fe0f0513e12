//! The settings of a simulated run ([`ImuSimulatorConfig`]) and their range checks.

use crate::attitude::Euler;
use crate::error::{check_with, CoreError};
use crate::imu_error::ImuErrorParams;
use crate::limits::{check_attitude, check_duration, check_site};
use crate::temperature::{DailySwing, TemperatureProfile};
use crate::trajectory::{check_route_latitude, Trajectory, TrajectoryConfig};
use crate::turntable::{RotationScheme, Turntable};

/// Everything that defines a simulated static run (SI units).
#[derive(Clone, Debug, PartialEq)]
pub struct ImuSimulatorConfig {
    /// Geodetic latitude \[rad\], longitude \[rad\], height above the ellipsoid \[m\].
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    /// Sample rate \[Hz\].
    pub rate_hz: f64,
    /// Length of the run \[s\]; the run has round(duration_s * rate_hz) samples.
    pub duration_s: f64,
    /// Seed of the single random generator.
    pub seed: u64,
    /// Body attitude at table angle zero.
    pub attitude: Euler,
    pub scheme: RotationScheme,
    pub errors: ImuErrorParams,
    pub temperature: TemperatureProfile,
    /// Moving base: the vehicle's route (`trajectory`); None for a static base. With a route, `attitude` is
    /// the IMU's attitude relative to the vehicle's level heading frame at table angle 0 (pitch, roll: the
    /// mounting tilt) and `attitude.yaw` the vehicle's initial yaw.
    pub trajectory: Option<TrajectoryConfig>,
}

impl Default for ImuSimulatorConfig {
    fn default() -> Self {
        ImuSimulatorConfig {
            lat: 28.222f64.to_radians(),
            lon: 0.0,
            height: 0.0,
            rate_hz: 100.0,
            duration_s: 3600.0,
            seed: 0,
            attitude: Euler::default(),
            scheme: RotationScheme::None,
            errors: ImuErrorParams::default(),
            temperature: TemperatureProfile::WarmUp {
                start_c: 20.0,
                end_c: 20.0,
                tau_s: 3600.0,
                swing: DailySwing::NONE,
            },
            trajectory: None,
        }
    }
}

impl ImuSimulatorConfig {
    /// Range checks; errors name the contract key.
    pub fn validate(&self) -> Result<(), CoreError> {
        check_site(self.lat, self.lon, self.height, self.rate_hz)?;
        check_duration(self.duration_s, self.rate_hz)?;
        check_attitude(self.attitude)?;
        self.errors.validate()?;
        self.temperature.validate()?;
        check_period(&Turntable::new(self.scheme.clone())?, 1.0 / self.rate_hz)?;
        if let Some(route) = &self.trajectory {
            let traj = Trajectory::new(route, self.attitude.yaw, self.height, self.duration_s)?;
            check_route_latitude(&traj, self.lat, self.attitude.yaw, self.duration_s)?;
        }
        Ok(())
    }
}

/// Fewest samples per period of a periodic table profile.
pub const MIN_SAMPLES_PER_PERIOD: f64 = 10.0;

/// A periodic table profile must last at least `MIN_SAMPLES_PER_PERIOD` samples: a table that reverses
/// faster than the IMU samples is no turntable (and its profile would be walked segment by segment for
/// every sample, e.g. a 1e-300 deg span would run for hours).
pub(super) fn check_period(table: &Turntable, dt: f64) -> Result<(), CoreError> {
    let period = table.period();
    if period == 0.0 || period >= MIN_SAMPLES_PER_PERIOD * dt {
        return Ok(());
    }
    let (key, what) = match table.scheme() {
        RotationScheme::Indexing { .. } => ("positions_rad", "indexing cycle"),
        _ => ("reciprocating_span_rad", "reciprocating period"),
    };
    check_with(false, key, || {
        format!(
            "the {what} of {} s is shorter than {MIN_SAMPLES_PER_PERIOD} samples ({} s at {} Hz): \
             the moves are too small",
            crate::error::sig(period),
            crate::error::sig(MIN_SAMPLES_PER_PERIOD * dt),
            crate::error::sig(1.0 / dt)
        )
    })
}
