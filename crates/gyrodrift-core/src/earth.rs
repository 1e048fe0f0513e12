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

/// The Earth terms a moving-base simulation needs near one position, for latitudes and heights a small step
/// away: sin and cos of the latitude, 1 / (R_M + h), 1 / (R_N + h), 1 / cos(lat) and normal gravity.
///
/// Exact at the position (`at_position`); `near` expands the radii and the latitude part of gravity to first
/// order and the reciprocals to second order in the step, so for latitude steps |dlat| <= 1e-7 rad (a sample at
/// up to 600 m/s) and height steps |dh| <= 1 m the relative error is below 5e-17 (the second-order terms of the
/// radii and of gravity, f'' dlat^2 / 2; the reciprocals' third-order terms are < 1e-21), below the rounding of
/// the exact formulas; the caller supplies sin and cos of the latitude.
#[derive(Clone, Copy, Debug)]
pub struct EarthNear {
    pub sin_lat: f64,
    pub cos_lat: f64,
    h: f64,
    d_rm: f64,
    d_rn: f64,
    inv_rmh: f64,
    inv_rnh: f64,
    inv_cos: f64,
    g_lat: f64,
    d_g_lat: f64,
}

/// Earth terms at one point (see [`EarthNear`]).
#[derive(Clone, Copy, Debug)]
pub struct EarthPoint {
    pub sin_lat: f64,
    pub cos_lat: f64,
    /// 1 / (R_M + h), 1 / (R_N + h) [1/m], 1 / cos(lat) [-].
    pub inv_rmh: f64,
    pub inv_rnh: f64,
    pub inv_cos: f64,
    /// Normal gravity [m/s^2].
    pub g: f64,
}

impl EarthNear {
    /// The terms at latitude `lat` \[rad\] (given by its sine and cosine) and height `h` \[m\].
    pub fn at_position(sin_lat: f64, cos_lat: f64, h: f64) -> Self {
        let s2 = sin_lat * sin_lat;
        let d = 1.0 - E2 * s2;
        let (inv_sqrt, inv_d) = (1.0 / d.sqrt(), 1.0 / d);
        let rn = A * inv_sqrt;
        let rm = A * (1.0 - E2) * inv_sqrt * inv_d;
        let sc = sin_lat * cos_lat;
        // d/dlat of R_N = a d^(-1/2), R_M = a (1 - e^2) d^(-3/2) and g_lat = g_e (1 + k s^2) d^(-1/2), with
        // d d / dlat = -2 e^2 s c.
        let d_rn = rn * E2 * sc * inv_d;
        let d_rm = 3.0 * rm * E2 * sc * inv_d;
        let g_lat = GAMMA_E * (1.0 + SOMIGLIANA_K * s2) * inv_sqrt;
        let d_g_lat =
            GAMMA_E * 2.0 * sc * (SOMIGLIANA_K * inv_sqrt + 0.5 * (1.0 + SOMIGLIANA_K * s2) * E2 * inv_sqrt * inv_d);
        EarthNear {
            sin_lat,
            cos_lat,
            h,
            d_rm,
            d_rn,
            inv_rmh: 1.0 / (rm + h),
            inv_rnh: 1.0 / (rn + h),
            inv_cos: 1.0 / cos_lat,
            g_lat,
            d_g_lat,
        }
    }

    /// The terms at latitude lat + `dlat` (its sine and cosine `sin_lat`, `cos_lat`, known by the caller) and
    /// height `h` (see the type's docs for the accuracy).
    #[inline(always)]
    pub fn near(&self, dlat: f64, sin_lat: f64, cos_lat: f64, h: f64) -> EarthPoint {
        // 1 / (X0 + dX) = (1 / X0) (1 - e + e^2), e = dX / X0.
        let recip = |inv0: f64, dx: f64| {
            let e = dx * inv0;
            inv0 * (1.0 - e + e * e)
        };
        let dh = h - self.h;
        let s2 = sin_lat * sin_lat;
        let g_lat = self.g_lat + self.d_g_lat * dlat;
        EarthPoint {
            sin_lat,
            cos_lat,
            inv_rmh: recip(self.inv_rmh, self.d_rm * dlat + dh),
            inv_rnh: recip(self.inv_rnh, self.d_rn * dlat + dh),
            inv_cos: recip(self.inv_cos, cos_lat - self.cos_lat),
            g: g_lat * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h + 3.0 * h * h / (A * A)),
        }
    }
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
    fn earth_terms_near_a_position_match_the_exact_ones() {
        for deg in [-88.0f64, -30.0, 0.0, 28.222, 61.5, 88.5] {
            let lat = deg.to_radians();
            for (h0, dh) in [(0.0, 0.5), (1234.5, -1.0), (-800.0, 0.0)] {
                let near = EarthNear::at_position(lat.sin(), lat.cos(), h0);
                for dlat in [-1e-7, -3e-8, 0.0, 2e-8, 1e-7] {
                    let (l, h) = (lat + dlat, h0 + dh);
                    let p = near.near(dlat, l.sin(), l.cos(), h);
                    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
                    // Rounding of the two evaluations (a few 1e-16), far above the truncation (< 1e-20).
                    assert!(rel(p.inv_rmh, 1.0 / (meridian_radius(l) + h)) < 6e-16, "{deg} {dlat}");
                    assert!(rel(p.inv_rnh, 1.0 / (transverse_radius(l) + h)) < 6e-16, "{deg} {dlat}");
                    assert!(rel(p.inv_cos, 1.0 / l.cos()) < 6e-16, "{deg} {dlat}");
                    assert!(rel(p.g, normal_gravity(l, h)) < 6e-16, "{deg} {dlat}");
                }
            }
        }
    }

    #[test]
    fn earth_rate_has_the_earth_rate_magnitude() {
        let w = earth_rate_enu(0.49);
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        assert!((n - OMEGA_IE).abs() < 1e-18);
        assert_eq!(w[0], 0.0);
    }
}
