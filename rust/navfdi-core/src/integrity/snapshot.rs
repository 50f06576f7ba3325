//! Snapshot RAIM protection levels of the weighted least-squares global test (slope method:
//! Brown 1992; Walter & Enge 1995, "Weighted RAIM for precision approach").
//!
//! For geometry rows `G` (n × (3 + c): the negated east/north/up line of sight and one clock
//! column per system), weights `W = diag(1/σᵢ²)`, `K = (GᵀWG)⁻¹GᵀW` and the residual projector
//! `S = I − G K`, a bias `b` on satellite i raises the test statistic `rᵀWr` by
//! `b² Sᵢᵢ / σᵢ²` and the position error by `K·ᵢ b`. The bias that brings the statistic to the
//! threshold `T` (the χ² quantile the test uses) moves the position by `slopeᵢ √T` with
//! `Vslopeᵢ = |K_uᵢ| σᵢ / √Sᵢᵢ` and `Hslopeᵢ = √(K_eᵢ² + K_nᵢ²) σᵢ / √Sᵢᵢ`. The protection
//! levels add the noise at the missed-detection probability:
//! `VPL = maxᵢ Vslopeᵢ √T + k_md σ_v`, `HPL = maxᵢ Hslopeᵢ √T + k_md σ_h` (σ_h: the semi-major
//! axis of the horizontal covariance). They bound the error against a single-satellite fault
//! the test misses with probability `P_md`, not against several faults at once (ARAIM's
//! fault modes, [`super::araim`], do that).

use crate::error::{Error, Result};
use nalgebra::{DMatrix, Vector3};

/// Protection levels of one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SnapshotPl {
    /// Horizontal protection level (m).
    pub hpl: f64,
    /// Vertical protection level (m).
    pub vpl: f64,
    /// Largest horizontal slope (dimensionless: m of error per m of √statistic).
    pub hslope: f64,
    /// Largest vertical slope.
    pub vslope: f64,
    /// Satellite with the largest vertical slope (index into the inputs).
    pub critical: usize,
    /// 1σ of the vertical position (m) and semi-major axis of the horizontal one (m).
    pub sigma_v: f64,
    /// See [`SnapshotPl::sigma_v`].
    pub sigma_h: f64,
}

/// Slope-based protection levels of satellites with unit line-of-sight vectors `los_enu`
/// (receiver to satellite, east/north/up), clock group `clock[i]` (0-based, one clock per
/// group), variances `sigma2[i]` (m²), the test's threshold `threshold` on `rᵀWr` and the
/// missed-detection quantile `k_md`. Infinite levels when a satellite has no redundancy
/// (`Sᵢᵢ ≈ 0`); an error when the geometry is singular or an input is invalid.
pub fn snapshot_pl(
    los_enu: &[Vector3<f64>],
    clock: &[usize],
    sigma2: &[f64],
    threshold: f64,
    k_md: f64,
) -> Result<SnapshotPl> {
    snapshot_pl_overbound(los_enu, clock, sigma2, threshold, k_md, None)
}

/// [`snapshot_pl`] with the fault-free error taken from an overbounding error model instead
/// of the test's σ: `overbound = (variances, nominal biases)` per satellite (m², m). The
/// estimator and the test keep their weights (`sigma2`), so the slopes are unchanged; the
/// position's fault-free σ is that of the estimator under the overbound, `K C_ob Kᵀ`, and the
/// nominal biases add in the worst sign, `Σᵢ |K_uᵢ| bᵢ` (vertical) and the norm of the east
/// and north sums (horizontal):
/// `VPL = Vslope √T + k_md σ_v,ob + b_v`, `HPL = Hslope √T + k_md σ_h,ob + b_h`.
pub fn snapshot_pl_overbound(
    los_enu: &[Vector3<f64>],
    clock: &[usize],
    sigma2: &[f64],
    threshold: f64,
    k_md: f64,
    overbound: Option<(&[f64], &[f64])>,
) -> Result<SnapshotPl> {
    let n = los_enu.len();
    if let Some((c, b)) = overbound {
        if c.len() != n || b.len() != n {
            return Err(Error::Invalid(format!(
                "snapshot PL: {n} satellites, {} overbound variances and {} nominal biases",
                c.len(),
                b.len()
            )));
        }
        if c.iter().any(|v| !(*v > 0.0 && v.is_finite()))
            || b.iter().any(|v| !(*v >= 0.0 && v.is_finite()))
        {
            return Err(Error::Invalid(
                "snapshot PL: overbound variances must be positive and nominal biases non-negative, all finite".into(),
            ));
        }
    }
    if clock.len() != n || sigma2.len() != n {
        return Err(Error::Invalid(format!(
            "snapshot PL: {n} lines of sight, {} clock groups and {} variances",
            clock.len(),
            sigma2.len()
        )));
    }
    if sigma2.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(Error::Invalid(
            "snapshot PL: variances must be positive and finite".into(),
        ));
    }
    if !(threshold > 0.0 && threshold.is_finite() && k_md >= 0.0 && k_md.is_finite()) {
        return Err(Error::Invalid(
            "snapshot PL: the threshold must be positive and k_md non-negative".into(),
        ));
    }
    let groups = clock.iter().copied().max().map_or(0, |m| m + 1);
    let m = 3 + groups;
    if n <= m {
        return Err(Error::Invalid(format!(
            "snapshot PL: {n} satellites for {m} unknowns: no redundancy to test"
        )));
    }
    let mut g = DMatrix::zeros(n, m);
    let mut gw = DMatrix::zeros(m, n);
    for i in 0..n {
        for j in 0..3 {
            g[(i, j)] = -los_enu[i][j];
        }
        g[(i, 3 + clock[i])] = 1.0;
        for j in 0..m {
            gw[(j, i)] = g[(i, j)] / sigma2[i];
        }
    }
    let cov = (&gw * &g)
        .try_inverse()
        .ok_or_else(|| Error::Invalid("snapshot PL: singular geometry".into()))?;
    let k = &cov * &gw;
    let s = DMatrix::<f64>::identity(n, n) - &g * &k;
    let (mut vs, mut hs, mut crit) = (0.0f64, 0.0f64, 0usize);
    for i in 0..n {
        let sii = s[(i, i)];
        let (v, h) = if sii <= 1e-12 {
            (f64::INFINITY, f64::INFINITY)
        } else {
            let f = sigma2[i].sqrt() / sii.sqrt();
            (k[(2, i)].abs() * f, k[(0, i)].hypot(k[(1, i)]) * f)
        };
        if v > vs {
            vs = v;
            crit = i;
        }
        hs = hs.max(h);
    }
    // Fault-free position covariance: the estimator's own, or under the overbound.
    let (pcov, bias) = match overbound {
        None => (cov.clone(), [0.0; 3]),
        Some((c_ob, b_nom)) => {
            let kc = DMatrix::from_fn(m, n, |r, i| k[(r, i)] * c_ob[i]);
            let mut bias = [0.0; 3];
            for (r, b) in bias.iter_mut().enumerate() {
                *b = (0..n).map(|i| k[(r, i)].abs() * b_nom[i]).sum();
            }
            (&kc * k.transpose(), bias)
        }
    };
    let cov = pcov;
    let sigma_v = cov[(2, 2)].max(0.0).sqrt();
    let (a, b, c) = (cov[(0, 0)], cov[(1, 1)], cov[(0, 1)]);
    let sigma_h = (0.5 * (a + b) + (0.25 * (a - b).powi(2) + c * c).sqrt())
        .max(0.0)
        .sqrt();
    let t = threshold.sqrt();
    Ok(SnapshotPl {
        hpl: hs * t + k_md * sigma_h + bias[0].hypot(bias[1]),
        vpl: vs * t + k_md * sigma_v + bias[2],
        hslope: hs,
        vslope: vs,
        critical: crit,
        sigma_v,
        sigma_h,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry() -> Vec<Vector3<f64>> {
        [
            (90.0f64, 0.0f64),
            (30.0, 0.0),
            (30.0, 90.0),
            (30.0, 180.0),
            (30.0, 270.0),
            (60.0, 45.0),
        ]
        .iter()
        .map(|&(el, az)| {
            let (el, az) = (el.to_radians(), az.to_radians());
            Vector3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin())
        })
        .collect()
    }

    #[test]
    fn slope_matches_the_bias_that_reaches_the_threshold() {
        let los = geometry();
        let n = los.len();
        let sig2 = vec![1.0; n];
        let thr = 10.0;
        let pl = snapshot_pl(&los, &vec![0; n], &sig2, thr, 0.0).unwrap();
        // Put the critical satellite's threshold bias into a least-squares solve: the vertical
        // error equals VPL and the statistic equals the threshold.
        let i = pl.critical;
        let mut g = DMatrix::zeros(n, 4);
        for (r, l) in los.iter().enumerate() {
            for j in 0..3 {
                g[(r, j)] = -l[j];
            }
            g[(r, 3)] = 1.0;
        }
        let k = (g.transpose() * &g).try_inverse().unwrap() * g.transpose();
        let s = DMatrix::<f64>::identity(n, n) - &g * &k;
        let b = (thr / s[(i, i)]).sqrt();
        let mut y = nalgebra::DVector::zeros(n);
        y[i] = b;
        let x = &k * &y;
        let r = &s * &y;
        assert!((r.dot(&r) - thr).abs() < 1e-9);
        assert!((x[2].abs() - pl.vpl).abs() < 1e-9, "{} vs {}", x[2], pl.vpl);
    }

    #[test]
    fn no_redundancy_is_refused_and_noise_adds() {
        let los = geometry();
        assert!(snapshot_pl(&los[..4], &[0; 4], &[1.0; 4], 10.0, 3.0).is_err());
        let a = snapshot_pl(&los, &[0; 6], &[1.0; 6], 10.0, 0.0).unwrap();
        let b = snapshot_pl(&los, &[0; 6], &[1.0; 6], 10.0, 3.0).unwrap();
        assert!((b.vpl - a.vpl - 3.0 * a.sigma_v).abs() < 1e-12);
        assert!(b.hpl > a.hpl && a.hpl.is_finite());
        assert!(snapshot_pl(&los, &[0; 6], &[0.0; 6], 10.0, 3.0).is_err());
        // The overbound equal to the test's σ and no bias: the same levels.
        let same = snapshot_pl_overbound(
            &los,
            &[0; 6],
            &[1.0; 6],
            10.0,
            3.0,
            Some((&[1.0; 6], &[0.0; 6])),
        )
        .unwrap();
        assert!((same.hpl - b.hpl).abs() < 1e-12 && (same.vpl - b.vpl).abs() < 1e-12);
        // Four times the variance doubles the noise term; a bias adds Σ|K_u| b.
        let ob = snapshot_pl_overbound(
            &los,
            &[0; 6],
            &[1.0; 6],
            10.0,
            3.0,
            Some((&[4.0; 6], &[0.5; 6])),
        )
        .unwrap();
        assert!((ob.sigma_v - 2.0 * b.sigma_v).abs() < 1e-12);
        assert!(ob.vpl > b.vpl + 3.0 * b.sigma_v && ob.vslope == b.vslope);
        assert!(snapshot_pl_overbound(
            &los,
            &[0; 6],
            &[1.0; 6],
            10.0,
            3.0,
            Some((&[1.0; 5], &[0.0; 6]))
        )
        .is_err());
    }
}
