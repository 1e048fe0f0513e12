//! WGS-84 Earth model: the one place that owns the Earth's numbers.
//!
//! Frames: navigation frame is local-level East-North-Up (ENU). Latitude `lat` in rad, height `h` in m
//! above the ellipsoid.

/// Semi-major axis a \[m\].
pub const A: f64 = 6_378_137.0;
/// Flattening f [-].
pub const F: f64 = 1.0 / 298.257_223_563;
/// First eccentricity squared e^2 = f (2 - f) [-].
pub const E2: f64 = F * (2.0 - F);
/// Semi-minor axis b = a (1 - f) \[m\].
pub const B: f64 = A * (1.0 - F);
/// Earth rotation rate w_ie [rad/s].
pub const OMEGA_IE: f64 = 7.292_115_146_7e-5;
/// Geocentric gravitational constant GM [m^3/s^2].
pub const GM: f64 = 3.986_004_418e14;
/// Normal gravity at the equator gamma_e [m/s^2].
pub const GAMMA_E: f64 = 9.780_325_335_9;
/// Normal gravity at the pole gamma_p [m/s^2].
pub const GAMMA_P: f64 = 9.832_184_937_8;
/// Somigliana constant k = (b gamma_p) / (a gamma_e) - 1 [-].
pub const SOMIGLIANA_K: f64 = (B * GAMMA_P) / (A * GAMMA_E) - 1.0;
/// m = w_ie^2 a^2 b / GM, used in the height correction [-].
pub const M_RATIO: f64 = OMEGA_IE * OMEGA_IE * A * A * B / GM;
/// One nautical mile \[m\] (1852 m exactly; never 1853).
pub const NMI: f64 = 1852.0;

/// Meridian radius of curvature R_M(lat) \[m\].
pub fn meridian_radius(lat: f64) -> f64 {
    let s = lat.sin();
    let d = 1.0 - E2 * s * s;
    A * (1.0 - E2) / (d * d.sqrt())
}

/// Prime-vertical (transverse) radius of curvature R_N(lat) \[m\].
pub fn transverse_radius(lat: f64) -> f64 {
    let s = lat.sin();
    A / (1.0 - E2 * s * s).sqrt()
}

/// Normal gravity magnitude [m/s^2] at geodetic latitude `lat` \[rad\] and height `h` \[m\].
///
/// Somigliana's closed formula on the ellipsoid, with the usual second-order height correction
/// (NIMA TR8350.2 eq. 4-3):
/// g(h) = g0 [1 - 2/a (1 + f + m - 2 f sin^2 lat) h + 3 h^2 / a^2].
/// Gravity points down: in ENU the vector is (0, 0, -g).
pub fn normal_gravity(lat: f64, h: f64) -> f64 {
    let s2 = lat.sin().powi(2);
    let g0 = GAMMA_E * (1.0 + SOMIGLIANA_K * s2) / (1.0 - E2 * s2).sqrt();
    g0 * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h + 3.0 * h * h / (A * A))
}

/// Earth rotation rate resolved in ENU at latitude `lat` \[rad\]: (0, w cos lat, w sin lat) [rad/s].
pub fn earth_rate_enu(lat: f64) -> [f64; 3] {
    [0.0, OMEGA_IE * lat.cos(), OMEGA_IE * lat.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gravity_matches_published_values_at_equator_and_pole() {
        // On the ellipsoid Somigliana's formula returns the defining constants exactly.
        assert!((normal_gravity(0.0, 0.0) - GAMMA_E).abs() < 1e-12);
        assert!((normal_gravity(std::f64::consts::FRAC_PI_2, 0.0) - GAMMA_P).abs() < 1e-9);
    }

    #[test]
    fn gravity_at_45_deg_and_free_air_gradient() {
        // Independent check: the truncated series form of WGS-84 normal gravity,
        // g = g_e (1 + 0.00530244 sin^2 L - 0.00000582 sin^2 2L), good to a few 1e-7 m/s^2.
        for deg in [0.0f64, 28.222, 45.0, 60.0, 89.0] {
            let lat = deg.to_radians();
            let series = GAMMA_E * (1.0 + 0.005_302_44 * lat.sin().powi(2) - 0.000_005_82 * (2.0 * lat).sin().powi(2));
            let g = normal_gravity(lat, 0.0);
            assert!((g - series).abs() < 1e-6, "{deg} deg: {g} vs {series}");
        }
        let g45 = normal_gravity(45f64.to_radians(), 0.0);
        // Free-air gradient is about -3.086e-6 (m/s^2)/m near the surface.
        let grad = (normal_gravity(45f64.to_radians(), 100.0) - g45) / 100.0;
        assert!((grad + 3.086e-6).abs() < 0.01e-6, "{grad}");
    }

    #[test]
    fn radii_of_curvature_closed_forms() {
        assert!((meridian_radius(0.0) - A * (1.0 - E2)).abs() < 1e-6);
        assert!((transverse_radius(0.0) - A).abs() < 1e-9);
        // At the pole both radii equal a^2 / b.
        let rp = A * A / B;
        let pole = std::f64::consts::FRAC_PI_2;
        assert!((meridian_radius(pole) - rp).abs() < 1e-6);
        assert!((transverse_radius(pole) - rp).abs() < 1e-6);
    }

    #[test]
    fn earth_rate_has_the_earth_rate_magnitude() {
        let w = earth_rate_enu(0.49);
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        assert!((n - OMEGA_IE).abs() < 1e-18);
        assert_eq!(w[0], 0.0);
    }
}
