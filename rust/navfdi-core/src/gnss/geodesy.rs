//! WGS-84 geodesy: geodetic ⇄ ECEF, the local east-north-up frame, elevation and azimuth.

use crate::ins::earth::{r_normal, E2};
use nalgebra::{Matrix3, Vector3};

/// ECEF position (m) of geodetic latitude `lat`, longitude `lon` (rad) and height `h` (m).
pub fn lla_to_ecef(lat: f64, lon: f64, h: f64) -> Vector3<f64> {
    let rn = r_normal(lat);
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    Vector3::new(
        (rn + h) * cl * co,
        (rn + h) * cl * so,
        (rn * (1.0 - E2) + h) * sl,
    )
}

/// Geodetic latitude, longitude (rad) and height (m) of an ECEF position (m), by fixed-point
/// iteration on the latitude (converges to < 1e-12 rad in a few steps away from the centre).
pub fn ecef_to_lla(r: &Vector3<f64>) -> (f64, f64, f64) {
    let p = (r.x * r.x + r.y * r.y).sqrt();
    let lon = r.y.atan2(r.x);
    let mut lat = r.z.atan2(p * (1.0 - E2));
    let mut h = 0.0;
    for _ in 0..10 {
        let rn = r_normal(lat);
        h = if lat.cos().abs() > 1e-9 {
            p / lat.cos() - rn
        } else {
            r.z.abs() - rn * (1.0 - E2)
        };
        let next = r.z.atan2(p * (1.0 - E2 * rn / (rn + h)));
        if (next - lat).abs() < 1e-14 {
            lat = next;
            break;
        }
        lat = next;
    }
    (lat, lon, h)
}

/// Rotation from ECEF to the local ENU frame at `lat`, `lon` (rad): rows are the east, north
/// and up unit vectors in ECEF.
pub fn ecef_to_enu(lat: f64, lon: f64) -> Matrix3<f64> {
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    Matrix3::new(-so, co, 0.0, -sl * co, -sl * so, cl, cl * co, cl * so, sl)
}

/// Elevation and azimuth (rad; azimuth clockwise from north) of ECEF point `sat` seen from
/// ECEF point `rx` at geodetic `lat`, `lon`.
pub fn elevation_azimuth(rx: &Vector3<f64>, lat: f64, lon: f64, sat: &Vector3<f64>) -> (f64, f64) {
    let d = ecef_to_enu(lat, lon) * (sat - rx);
    let horiz = (d.x * d.x + d.y * d.y).sqrt();
    (d.z.atan2(horiz), d.x.atan2(d.y))
}

/// Earth rotation rate (rad/s, WGS-84).
pub const OMEGA_E: f64 = 7.292_115_146_7e-5;

/// Satellite ECEF position `sat` (m, at transmission) rotated by the Earth's rotation over the
/// signal's travel from it to the receiver at `r` (the Sagnac correction as a position, to
/// first order in the angle).
pub fn sagnac(sat: &Vector3<f64>, r: &Vector3<f64>) -> Vector3<f64> {
    let a = OMEGA_E * (sat - r).norm() / super::C;
    Vector3::new(sat.x + a * sat.y, sat.y - a * sat.x, sat.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ins::earth::A;

    #[test]
    fn round_trip_and_frames() {
        for &(lat, lon, h) in &[
            (0.0, 0.0, 0.0),
            (0.6, 1.9, 120.0),
            (-1.2, -2.5, 8000.0),
            (1.5, 0.3, -400.0),
        ] {
            let r = lla_to_ecef(lat, lon, h);
            let (la, lo, hh) = ecef_to_lla(&r);
            assert!((la - lat).abs() < 1e-12 && (lo - lon).abs() < 1e-12);
            assert!((hh - h).abs() < 1e-6, "{hh} vs {h}");
            let m = ecef_to_enu(lat, lon);
            assert!((m * m.transpose() - Matrix3::identity()).norm() < 1e-14);
            // Up is the ellipsoid normal: a point 1 km straight up.
            let up = lla_to_ecef(lat, lon, h + 1000.0);
            let (el, _) = elevation_azimuth(&r, lat, lon, &up);
            assert!((el - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        }
        assert!((lla_to_ecef(0.0, 0.0, 0.0).x - A).abs() < 1e-9);
        // A point due north on the surface has azimuth 0, due east π/2.
        let r = lla_to_ecef(0.5, 0.5, 0.0);
        let (_, az) = elevation_azimuth(&r, 0.5, 0.5, &lla_to_ecef(0.5001, 0.5, 0.0));
        assert!(az.abs() < 1e-3);
        let (_, az) = elevation_azimuth(&r, 0.5, 0.5, &lla_to_ecef(0.5, 0.5001, 0.0));
        assert!((az - std::f64::consts::FRAC_PI_2).abs() < 1e-3);
    }
}
