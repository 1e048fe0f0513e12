//! gyrodrift-core: everything that runs per IMU sample, with no Python in it.
//!
//! One module per concept of navigation:
//! - [`earth`]: WGS-84 constants, radii of curvature, normal gravity, Earth rate in ENU.
//! - [`attitude`]: quaternions, DCM, rotation vectors, Euler angles (PSINS conventions).
//! - [`turntable`]: single-axis rotation schemes about body Up (closed-form angle/rate/acceleration).
//! - [`temperature`]: temperature profiles (warm-up, interpolated series).
//! - [`imu_error`]: the body-frame IMU error model (biases, random walks, Gauss-Markov, scale, misalignment,
//!   temperature-dependent axial drift).
//! - [`simulator`]: exact IMU increments of a static base with a turntable, plus the error model.
//! - [`trajectory`]: the land-vehicle route of a moving base (closed-form kinematics per segment).
//! - [`strapdown`]: the strapdown navigator (coning/sculling, velocity, position, attitude).
//! - [`coarse_alignment`], [`kalman`], [`alignment`]: the static-base alignment (coarse, 12-state filter, driver).
//! - [`smoother`]: forward filter + RTS smoother over a whole static log (the axial drift with its 1-sigma).
//! - [`aligner_covariance`]: the fine aligner as a filter by covariance alone (its true error covariance under a
//!   given noise), shared by [`label`] and [`plan`].
//! - [`label`]: covariance analysis of the true-drift label (a free navigation with the smoother's error model).
//! - [`plan`]: covariance analysis for planning an identification (the smoother's drift 1-sigma against the span,
//!   the position error of a mission), with no IMU samples.
//! - [`filter_prior`]: the default prior and noise of the aligner and the smoother, and why they differ.
//! - [`limits`]: the ranges of the shared quantities (site, rate, attitude, samples), checked in one place.
//! - [`units`]: the unit constants (deg, deg/h, deg/sqrt(h), ug, arcsec, ...), the only conversion factors.
//! - [`error`]: [`error::CoreError`], the one error type; library code does not panic on data.
//!
//! Frames: navigation frame local-level East-North-Up (ENU); body frame Right-Forward-Up.
//! Units: SI everywhere inside the crate (rad, rad/s, m, m/s, s).

pub mod aligner_covariance;
pub mod alignment;
pub mod attitude;
pub mod coarse_alignment;
pub mod earth;
pub mod error;
pub mod filter_prior;
pub mod imu_error;
pub mod imu_rows;
pub mod kalman;
pub mod label;
pub mod limits;
pub mod plan;
pub mod simulator;
pub mod smoother;
pub mod strapdown;
pub mod temperature;
pub mod trajectory;
pub mod turntable;
pub mod units;
