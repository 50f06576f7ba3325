//! The ADD's error models for ARAIM from the lines of sight ([`super::araim`]): the
//! troposphere and the airborne dual-frequency user terms per elevation, and the integrity
//! and accuracy variances `C_int = σ_URA² + σ_tropo² + σ_user²`, `C_acc = σ_URE² + …` with the
//! ADD's geometry rows, from unit lines of sight (east, north, up).

use crate::error::{num, Error, Result};

/// GPS L1 and L5 carrier frequencies (MHz), for the dual-frequency user-error model.
pub const F_L1: f64 = 1575.42;
/// See [`F_L1`].
pub const F_L5: f64 = 1176.45;

/// `(σ_tropo², σ_user²)` (m²) at elevation `el` (rad) by the ADD's models: the troposphere
/// `0.12 · 1.001 / sqrt(0.002001 + sin² el)` and the dual-frequency (L1/L5) user term
/// `(f1⁴ + f5⁴)/(f1² − f5²)² · (σ_MP² + σ_noise²)` with `σ_MP = 0.13 + 0.53 e^(−el/10°)` and
/// `σ_noise = 0.15 + 0.43 e^(−el/6.9°)` (the airborne GPS model, used for every system).
pub fn elevation_variances(el: f64) -> (f64, f64) {
    let el_deg = el.to_degrees();
    let s = el.sin();
    let t = 0.12 * 1.001 / (0.002001 + s * s).sqrt();
    let mp = 0.13 + 0.53 * (-el_deg / 10.0).exp();
    let noise = 0.15 + 0.43 * (-el_deg / 6.9).exp();
    let d = F_L1.powf(2.0) - F_L5.powf(2.0);
    let k = (F_L1.powf(4.0) + F_L5.powf(4.0)) / (d * d);
    (t * t, k * (mp * mp + noise * noise))
}

/// `v` for each of `n` satellites: one value for all (length 1) or one each (length n);
/// a shape error naming `name` otherwise.
pub fn per_satellite(name: &str, v: Vec<f64>, n: usize) -> Result<Vec<f64>> {
    match v.len() {
        len if len == n => Ok(v),
        1 => Ok(vec![v[0]; n]),
        len => Err(Error::Invalid(format!(
            "{name}: expected a scalar or ({n},) values, got {len}"
        ))),
    }
}

/// Geometry rows and variances from lines of sight ([`los_rows_and_variances`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LosModel {
    /// Geometry rows `−u` (east, north, up).
    pub rows: Vec<[f64; 3]>,
    /// `C_int,i` (m²).
    pub c_int: Vec<f64>,
    /// `C_acc,i` (m²).
    pub c_acc: Vec<f64>,
}

/// The ADD's geometry rows (minus the lines of sight) and the default variances from unit
/// lines of sight `los_enu` (n; east, north, up): `C_int,i = σ_URA,i² + σ_tropo² + σ_user²`
/// and `C_acc,i = σ_URE,i² + …` at each satellite's elevation `asin(u)`. `sigma_ura`,
/// `sigma_ure` (m) have n values. Errors: a non-finite component, a norm off 1 by more than
/// 1e-3 (naming the satellite).
pub fn los_rows_and_variances(
    los_enu: &[[f64; 3]],
    sigma_ura: &[f64],
    sigma_ure: &[f64],
) -> Result<LosModel> {
    check_los(los_enu)?;
    let n = los_enu.len();
    let (mut c_int, mut c_acc) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (i, u) in los_enu.iter().enumerate() {
        let (tropo, user) = elevation_variances(u[2].clamp(-1.0, 1.0).asin());
        c_int.push(sigma_ura[i] * sigma_ura[i] + tropo + user);
        c_acc.push(sigma_ure[i] * sigma_ure[i] + tropo + user);
    }
    Ok(LosModel {
        rows: rows(los_enu),
        c_int,
        c_acc,
    })
}

/// Geometry rows `−u` from lines of sight `u`.
pub fn rows(los_enu: &[[f64; 3]]) -> Vec<[f64; 3]> {
    los_enu.iter().map(|u| u.map(|v| -v)).collect()
}

/// Every line of sight finite and of unit norm (within 1e-3), naming the first one that is not.
pub fn check_los(los_enu: &[[f64; 3]]) -> Result<()> {
    for (i, u) in los_enu.iter().enumerate() {
        if let Some(j) = u.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                name: "los_enu".into(),
                index: format!("[{i}, {j}]"),
                value: u[j],
            });
        }
        let norm = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        if (norm - 1.0).abs() > 1e-3 {
            return Err(Error::Invalid(format!(
                "los_enu[{i}]: norm {}; give unit vectors",
                num(norm)
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_models_at_known_elevations() {
        // Troposphere at zenith 0.12·1.001/sqrt(1.002001) m; at 90° the user terms are
        // 0.13 + 0.53 e^-9 and 0.15 + 0.43 e^-13.04 m, times the dual-frequency factor.
        let (t, u) = elevation_variances(std::f64::consts::FRAC_PI_2);
        let t_ref = 0.12 * 1.001 / 1.002_001_f64.sqrt();
        assert!((t - t_ref * t_ref).abs() < 1e-15);
        let k = (1575.42_f64.powi(4) + 1176.45_f64.powi(4))
            / (1575.42_f64.powi(2) - 1176.45_f64.powi(2)).powi(2);
        let mp = 0.13 + 0.53 * (-9.0_f64).exp();
        let nz = 0.15 + 0.43 * (-90.0_f64 / 6.9).exp();
        assert!((u - k * (mp * mp + nz * nz)).abs() < 1e-12 * u);
        // Lower elevations cost more, both terms.
        let (t10, u10) = elevation_variances(10f64.to_radians());
        assert!(t10 > 10.0 * t && u10 > u);
    }

    #[test]
    fn lines_of_sight_are_checked_and_scalars_broadcast() {
        let ok = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]];
        let m = los_rows_and_variances(&ok, &[0.75; 2], &[0.5; 2]).unwrap();
        let (ci, ca) = (&m.c_int, &m.c_acc);
        assert_eq!(m.rows[1], [-0.6, -0.0, -0.8]);
        assert!(ci[1] > ci[0] && (ci[0] - ca[0] - (0.75 * 0.75 - 0.25)).abs() < 1e-12);
        let e = check_los(&[[0.0, 0.0, 1.0], [0.0, f64::NAN, 1.0]]).unwrap_err();
        assert!(
            e.to_string().contains("los_enu: element [1, 1] is NaN"),
            "{e}"
        );
        let e = check_los(&[[0.0, 0.0, 2.0]]).unwrap_err();
        assert_eq!(e.to_string(), "los_enu[0]: norm 2; give unit vectors");
        assert_eq!(per_satellite("b", vec![0.5], 3).unwrap(), vec![0.5; 3]);
        let e = per_satellite("ism.b_nom", vec![0.5, 0.4], 3).unwrap_err();
        assert_eq!(
            e.to_string(),
            "ism.b_nom: expected a scalar or (3,) values, got 2"
        );
    }
}
