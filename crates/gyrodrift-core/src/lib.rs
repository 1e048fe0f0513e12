//! gyrodrift-core: everything that runs per IMU sample, with no Python in it.
//!
//! One module per concept of navigation:
//! - [`earth`]: WGS-84 constants, radii of curvature, normal gravity, Earth rate in ENU.
//!
//! Frames: navigation frame local-level East-North-Up (ENU); body frame Right-Forward-Up.
//! Units: SI everywhere inside the crate (rad, rad/s, m, m/s, s).

pub mod earth;
