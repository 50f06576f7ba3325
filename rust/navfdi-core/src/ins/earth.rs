//! WGS-84 Earth model.

/// Semi-major axis a (m).
pub const A: f64 = 6_378_137.0;
/// Flattening f.
pub const F: f64 = 1.0 / 298.257_223_563;
/// First eccentricity squared e² = f(2 − f).
pub const E2: f64 = F * (2.0 - F);
/// Earth rotation rate ω_ie (rad/s).
pub const OMEGA_IE: f64 = 7.292_115e-5;
/// Normal gravity at the equator (m/s²) (Somigliana).
pub const G_EQUATOR: f64 = 9.780_325_335_9;

/// Meridian radius of curvature R_M at latitude `lat` (rad), in m.
pub fn r_meridian(lat: f64) -> f64 {
    let s = lat.sin();
    A * (1.0 - E2) / (1.0 - E2 * s * s).powf(1.5)
}

/// Prime-vertical (transverse) radius of curvature R_N at latitude `lat` (rad), in m.
pub fn r_normal(lat: f64) -> f64 {
    let s = lat.sin();
    A / (1.0 - E2 * s * s).sqrt()
}

/// Free-air gradient of normal gravity (m/s² per m of height; ≈ 2g/R).
pub const FREE_AIR_GRADIENT: f64 = 3.086e-6;

/// Magnitude of normal gravity at latitude `lat` (rad) and height `h` (m), in m/s²
/// (Somigliana with a free-air correction).
pub fn gravity(lat: f64, h: f64) -> f64 {
    let s2 = lat.sin().powi(2);
    let g0 = G_EQUATOR * (1.0 + 0.001_931_852_652_41 * s2) / (1.0 - E2 * s2).sqrt();
    g0 - FREE_AIR_GRADIENT * h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radii_and_gravity() {
        assert!((r_normal(0.0) - A).abs() < 1e-6);
        assert!((r_meridian(0.0) - 6_335_439.327).abs() < 1e-2);
        assert!((gravity(0.0, 0.0) - 9.7803253359).abs() < 1e-9);
        assert!((gravity(std::f64::consts::FRAC_PI_2, 0.0) - 9.8321849378).abs() < 1e-6);
    }
}
