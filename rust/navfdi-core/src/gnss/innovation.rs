//! Satellite FDE on Kalman-filter innovations (paper 001's method 2): the innovation
//! chi-square test followed by the general w-test `w_i = (A⁻¹r)_i / sqrt((A⁻¹)_ii)` per
//! observation (Teunissen 1990, the paper's ref. 9) with iterative exclusion of the satellite
//! of the largest |w| above K (both its rows: pseudorange `j` and, with rates, `m + j`).

use super::snapshot::{fde, FdeConfig, FdeStatus, ObsCov, PositionModel, RateModel, StackedModel};
use crate::error::{Error, Result};
use crate::kalman::{KalmanFilter, Pending};
use nalgebra::{Cholesky, DMatrix, DVector};

/// Update `kf` with the satellites not in `excluded` (local indices of m satellites; rows `j`
/// and, when `z` has 2m rows, `m + j`): the prepared update when nothing is excluded, a
/// reduced update otherwise, none when every satellite is excluded. Returns the number of
/// satellites used.
pub fn update_without(
    kf: &mut KalmanFilter,
    z: &DVector<f64>,
    h: &DMatrix<f64>,
    r: &DMatrix<f64>,
    m: usize,
    excluded: &[usize],
    pending: Option<Pending>,
) -> Result<usize> {
    if excluded.is_empty() {
        match pending {
            Some(p) => kf.apply_pending(p, r)?,
            None => {
                kf.update_trusted(z, h, r)?;
            }
        }
        return Ok(m);
    }
    let used = m - excluded.len();
    if used > 0 {
        let mut zu = z.clone();
        for &j in excluded {
            zu[j] = f64::NAN;
            if zu.len() > m {
                zu[m + j] = f64::NAN;
            }
        }
        kf.update_trusted(&zu, h, r)?;
    }
    Ok(used)
}

/// Outcome of one epoch's satellite FDE.
#[derive(Debug, Clone, PartialEq)]
pub struct SatFde {
    /// Excluded satellites (local indices), in exclusion order.
    pub excluded: Vec<usize>,
    /// How the loop ended.
    pub status: FdeStatus,
    /// Statistic, threshold and dof of the first global test.
    pub first: (f64, f64, usize),
    /// w per local satellite (its pseudorange row; for an excluded one its |w| when
    /// excluded).
    pub w: Vec<f64>,
}

/// Method 2 (`exclude = true`) or the recorded global test only: the innovation test on the
/// residual `res` and covariance `a` of m satellites (rows `j` and, with rates, `m + j`).
/// `statistic`: `rᵀA⁻¹r` of all rows if already known (the filter computes it); then an
/// epoch whose test passes needs no factorisation unless `want_w` (w per satellite, for
/// records; NaN otherwise).
pub fn innovation_fde(
    res: &DVector<f64>,
    a: &DMatrix<f64>,
    m: usize,
    exclude: bool,
    statistic: Option<f64>,
    want_w: bool,
    cfg: &FdeConfig,
) -> Result<SatFde> {
    let rows = res.len();
    let mut active: Vec<usize> = (0..rows).collect();
    let mut out = SatFde {
        excluded: Vec::new(),
        status: FdeStatus::Passed,
        first: (f64::NAN, f64::NAN, 0),
        w: vec![f64::NAN; m],
    };
    let mut w_at_exclusion = vec![f64::NAN; m];
    if let (Some(stat), false) = (statistic, want_w) {
        let thr = cfg.threshold(rows)?;
        if stat < thr || !exclude {
            out.first = (stat, thr, rows);
            return Ok(out);
        }
    }
    loop {
        if active.is_empty() {
            out.status = FdeStatus::NoSolution;
            break;
        }
        let ra = res.select_rows(&active);
        let aa = a.select_rows(&active).select_columns(&active);
        let chol = Cholesky::new(aa).ok_or_else(|| Error::NotPositiveDefinite {
            name: "innovation covariance A".into(),
            detail: "cannot factor the innovation covariance of the satellites in view".into(),
        })?;
        let g = chol.solve(&ra);
        let stat = ra.dot(&g);
        let thr = cfg.threshold(active.len())?;
        if out.excluded.is_empty() {
            out.first = (stat, thr, active.len());
        }
        let ainv = chol.inverse();
        let wrow: Vec<f64> = (0..active.len())
            .map(|i| g[i] / ainv[(i, i)].sqrt())
            .collect();
        out.w = vec![f64::NAN; m];
        for (i, &row) in active.iter().enumerate() {
            if row < m {
                out.w[row] = wrow[i];
            }
        }
        if stat < thr || !exclude {
            out.status = if out.excluded.is_empty() {
                FdeStatus::Passed
            } else {
                FdeStatus::Excluded
            };
            break;
        }
        let (wi, wmax) = wrow
            .iter()
            .enumerate()
            .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))
            .map(|(i, v)| (i, v.abs()))
            .unwrap_or((0, 0.0));
        if !(wmax > cfg.k) {
            out.status = FdeStatus::Unidentified;
            break;
        }
        let satj = active[wi] % m;
        out.excluded.push(satj);
        w_at_exclusion[satj] = wmax;
        active.retain(|&row| row % m != satj);
    }
    for &j in &out.excluded {
        out.w[j] = w_at_exclusion[j];
    }
    Ok(out)
}

/// Method 1 of a tight filter (`ls_precheck`): the snapshot test and exclusion loop on the
/// pseudoranges of `position` (m satellites) and, with `rate`, their rates stacked (rows `j`
/// and `m + j` of satellite j, excluded together), σ per row `sigma`; as [`SatFde`] with the w
/// of each satellite's pseudorange (for an excluded one the |w| that excluded it).
pub fn snapshot_sat_fde(
    position: PositionModel<'_>,
    rate: Option<RateModel<'_>>,
    sigma: Vec<f64>,
    cfg: &FdeConfig,
) -> Result<SatFde> {
    let m = position.rho.len();
    let out = match rate {
        Some(rate) => {
            let mut stacked = StackedModel { position, rate };
            let groups: Vec<usize> = (0..2 * m).map(|i| i % m).collect();
            fde(
                &mut stacked,
                &ObsCov::Sigma(sigma),
                &vec![true; 2 * m],
                Some(&groups),
                cfg,
            )?
        }
        None => {
            let mut model = position;
            fde(&mut model, &ObsCov::Sigma(sigma), &vec![true; m], None, cfg)?
        }
    };
    let mut w: Vec<f64> = out.w[..m].to_vec();
    for (&i, &wi) in out.excluded.iter().zip(&out.excluded_w) {
        w[i % m] = wi;
    }
    Ok(SatFde {
        excluded: out.excluded.iter().map(|i| i % m).collect(),
        status: out.status,
        first: out.first,
        w,
    })
}
