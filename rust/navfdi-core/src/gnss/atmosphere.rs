//! Broadcast ionosphere (Klobuchar) and standard-atmosphere troposphere (Saastamoinen)
//! delays for single-frequency pseudoranges, in the forms RTKLIB's `ionmodel` and `tropmodel`
//! use (so that single-point solutions compare).

use std::f64::consts::PI;

/// Klobuchar coefficients `[α₀..α₃, β₀..β₃]` (s, s/semicircle, …) as broadcast by GPS.
pub type Klobuchar = [f64; 8];

/// RTKLIB's default coefficients, used when a navigation file carries none (all zero).
pub const KLOBUCHAR_DEFAULT: Klobuchar = [
    0.1118e-07,
    -0.7451e-08,
    -0.5961e-07,
    0.1192e-06,
    0.1167e+06,
    -0.2294e+06,
    -0.1311e+06,
    0.1049e+07,
];

/// Klobuchar L1 ionospheric delay (m) at GPS seconds of week `sow`, receiver geodetic `lat`,
/// `lon` (rad), height `h` (m), satellite azimuth `az` and elevation `el` (rad) (IS-GPS-200
/// §20.3.3.5.2.5). Zero below the horizon or for heights below −1 km. Other frequencies scale
/// by `(f_L1/f)²`.
pub fn klobuchar(coef: &Klobuchar, sow: f64, lat: f64, lon: f64, h: f64, az: f64, el: f64) -> f64 {
    if h < -1e3 || el <= 0.0 {
        return 0.0;
    }
    let ion = if coef.iter().all(|c| *c == 0.0) {
        &KLOBUCHAR_DEFAULT
    } else {
        coef
    };
    let (phi, lam) = pierce_point(lat, lon, az, el);
    let mut tt = 43_200.0 * lam + sow;
    tt -= (tt / 86_400.0).floor() * 86_400.0;
    let f = 1.0 + 16.0 * (0.53 - el / PI).powi(3);
    let amp = (ion[0] + phi * (ion[1] + phi * (ion[2] + phi * ion[3]))).max(0.0);
    let per = (ion[4] + phi * (ion[5] + phi * (ion[6] + phi * ion[7]))).max(72_000.0);
    let x = 2.0 * PI * (tt - 50_400.0) / per;
    let delay = if x.abs() < 1.57 {
        5e-9 + amp * (1.0 + x * x * (-0.5 + x * x / 24.0))
    } else {
        5e-9
    };
    super::C * f * delay
}

/// Klobuchar's ionospheric pierce point (IS-GPS-200): its geomagnetic latitude and its
/// geodetic longitude, both in semicircles, for a receiver at `lat`, `lon` (rad) and a
/// satellite at azimuth `az`, elevation `el` (rad).
fn pierce_point(lat: f64, lon: f64, az: f64, el: f64) -> (f64, f64) {
    let psi = 0.0137 / (el / PI + 0.11) - 0.022;
    let phi = (lat / PI + psi * az.cos()).clamp(-0.416, 0.416);
    let lam = lon / PI + psi * az.sin() / (phi * PI).cos();
    (phi + 0.064 * ((lam - 1.617) * PI).cos(), lam)
}

/// Vertical ionospheric delay left after the Klobuchar correction, 1σ (m), by |geomagnetic
/// latitude| of the pierce point (RTCA DO-229, appendix J): within 20°, to 55°, beyond.
pub const IONO_TAU_VERT: [(f64, f64); 3] = [(20.0, 9.0), (55.0, 4.5), (90.0, 6.0)];

/// σ (m) of the L1 ionospheric delay left after the Klobuchar correction: DO-229's
/// single-frequency model `F_pp τ_vert`, `F_pp = [1 − (R_e cos el / (R_e + 350 km))²]^(−1/2)`,
/// `τ_vert` ([`IONO_TAU_VERT`]) at the geomagnetic latitude of Klobuchar's pierce point;
/// receiver `lat`, `lon`, satellite `az`, `el` in rad. Other frequencies scale by `(f_L1/f)²`.
pub fn klobuchar_residual_sigma(lat: f64, lon: f64, az: f64, el: f64) -> f64 {
    let phi_m = pierce_point(lat, lon, az, el).0.abs() * 180.0;
    let tau = IONO_TAU_VERT
        .iter()
        .find(|(edge, _)| phi_m <= *edge)
        .map_or(IONO_TAU_VERT[2].1, |b| b.1);
    let (re, hi) = (6_378.136_3, 350.0);
    tau / (1.0 - (re * el.cos() / (re + hi)).powi(2)).sqrt()
}

/// Saastamoinen tropospheric delay (m) with the standard atmosphere (15 °C and 1013.25 hPa at
/// sea level, relative humidity `humidity` ∈ [0, 1]) at geodetic `lat` (rad), height `h` (m)
/// and elevation `el` (rad). Zero below the horizon or outside −100 m … 10 km.
pub fn saastamoinen(lat: f64, h: f64, el: f64, humidity: f64) -> f64 {
    if !(-100.0..=1e4).contains(&h) || el <= 0.0 {
        return 0.0;
    }
    let hgt = h.max(0.0);
    let pres = 1013.25 * (1.0 - 2.2557e-5 * hgt).powf(5.2568);
    let temp = 15.0 - 6.5e-3 * hgt + 273.16;
    let e = 6.108 * humidity * ((17.15 * temp - 4684.0) / (temp - 38.45)).exp();
    let z = PI / 2.0 - el;
    let trph =
        0.002_276_8 * pres / (1.0 - 0.002_66 * (2.0 * lat).cos() - 0.000_28 * hgt / 1e3) / z.cos();
    let trpw = 0.002_277 * (1255.0 / temp + 0.05) * e / z.cos();
    trph + trpw
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn klobuchar_residual_sigma_follows_do229() {
        let up = PI / 2.0;
        let d = |x: f64| x.to_radians();
        // Zenith: F_pp = 1, σ = τ_vert of the pierce point's geomagnetic band.
        assert!((klobuchar_residual_sigma(d(35.0), d(137.0), 0.0, up) - 4.5).abs() < 1e-9); // Nagoya
        assert!((klobuchar_residual_sigma(d(-5.0), d(-80.0), 0.0, up) - 9.0).abs() < 1e-9);
        assert!((klobuchar_residual_sigma(d(70.0), 0.0, 0.0, up) - 6.0).abs() < 1e-9);
        // Lower satellites: the obliquity factor, up to ≈ 3 at the horizon.
        let low = klobuchar_residual_sigma(d(35.0), d(137.0), 0.0, d(5.0));
        let mid = klobuchar_residual_sigma(d(35.0), d(137.0), 0.0, d(30.0));
        assert!(2.5 * 4.5 < low && low < 3.1 * 4.5 && 4.5 < mid && mid < low);
    }

    #[test]
    fn magnitudes_are_physical() {
        // Zenith troposphere at sea level ≈ 2.3 m dry + a few dm wet; grows ~1/sin(el).
        let z = saastamoinen(0.6, 0.0, PI / 2.0, 0.7);
        assert!((2.3..2.7).contains(&z), "{z}");
        let low = saastamoinen(0.6, 0.0, 10f64.to_radians(), 0.7);
        assert!(low > 5.0 * z && low < 6.5 * z);
        assert_eq!(saastamoinen(0.6, 2e4, 1.0, 0.7), 0.0);
        // Klobuchar night-time floor is 5 ns × obliquity; daytime larger; zero below horizon.
        let night = klobuchar(&KLOBUCHAR_DEFAULT, 0.0, 0.0, 0.0, 0.0, 0.0, PI / 2.0);
        assert!((night - 5e-9 * super::super::C * (1.0 + 16.0 * 0.03f64.powi(3))).abs() < 1e-6);
        let day = klobuchar(&KLOBUCHAR_DEFAULT, 50_400.0, 0.0, 0.0, 0.0, 0.0, PI / 2.0);
        assert!(day > night && day < 30.0);
        assert_eq!(
            klobuchar(&KLOBUCHAR_DEFAULT, 0.0, 0.0, 0.0, 0.0, 0.0, -0.1),
            0.0
        );
    }
}
