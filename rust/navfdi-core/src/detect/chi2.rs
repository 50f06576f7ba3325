//! Residual chi-square test (METHODS §2): `λ = rᵀA⁻¹r ~ χ²(m)` under no fault; alarm when
//! `λ ≥ T_D = F⁻¹_{χ²(m)}(1 − Pf)`.

use super::{check_residual, Decision};
use crate::error::{Error, Result};
use crate::validate::check_probability;
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// Residual chi-square detector with false-alarm probability `pf` per epoch.
///
/// The threshold follows the number of available residual components (NaN components are
/// skipped); thresholds are computed once per degree of freedom and cached.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ResidualChi2 {
    pf: f64,
    thresholds: Vec<f64>,
    alarm: bool,
}

impl ResidualChi2 {
    /// New detector; `pf` in (0, 1).
    pub fn new(pf: f64) -> Result<Self> {
        check_probability("pf", pf)?;
        Ok(ResidualChi2 {
            pf,
            thresholds: Vec::new(),
            alarm: false,
        })
    }

    /// False-alarm probability per epoch.
    pub fn pf(&self) -> f64 {
        self.pf
    }

    /// Threshold `T_D` for `dof` components.
    pub fn threshold(&mut self, dof: usize) -> Result<f64> {
        super::cached_chi2_threshold(&mut self.thresholds, self.pf, dof)
    }

    /// Last alarm state.
    pub fn alarm(&self) -> bool {
        self.alarm
    }

    /// Test one epoch: residual `r` (m, NaN = unavailable) and covariance `A` (m × m, positive
    /// definite on the available components).
    pub fn test(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Result<Decision> {
        let (statistic, dof) = Self::statistic(r, a)?;
        self.test_statistic(statistic, dof)
    }

    /// Validate a residual and compute `λ = rᵀA⁻¹r` over its non-NaN components, without
    /// changing any detector: returns `(λ, dof)` (λ is NaN when `dof = 0`).
    pub fn statistic(r: &DVector<f64>, a: &DMatrix<f64>) -> Result<(f64, usize)> {
        let checked = check_residual(r, a)?;
        let dof = checked.idx.len();
        let Some(chol) = checked.chol else {
            return Ok((f64::NAN, dof));
        };
        let rr = if dof == r.len() {
            r.clone()
        } else {
            r.select_rows(&checked.idx)
        };
        Ok((whitened_norm2(&chol, &rr)?, dof))
    }

    /// Decide on a statistic computed elsewhere (e.g. [`crate::kalman::Innovation::statistic`],
    /// which is `rᵀA⁻¹r` over `dof` components): no validation, no factorisation.
    pub fn test_statistic(&mut self, statistic: f64, dof: usize) -> Result<Decision> {
        if dof == 0 {
            return Ok(Decision {
                statistic: f64::NAN,
                threshold: f64::NAN,
                alarm: self.alarm,
                dof,
            });
        }
        let threshold = self.threshold(dof)?;
        self.alarm = statistic >= threshold;
        Ok(Decision {
            statistic,
            threshold,
            alarm: self.alarm,
            dof,
        })
    }

    /// Forget the last alarm state.
    pub fn reset(&mut self) {
        self.alarm = false;
    }
}

/// `rᵀA⁻¹r` as ‖L⁻¹r‖² with `A = LLᵀ`.
pub(crate) fn whitened_norm2(chol: &Cholesky<f64, Dyn>, r: &DVector<f64>) -> Result<f64> {
    let solve = |r: &DVector<f64>| {
        chol.l_dirty()
            .solve_lower_triangular(r)
            .ok_or_else(|| Error::Numerical {
                context: "chi-square statistic".into(),
                detail: "triangular solve failed".into(),
            })
    };
    let stat = solve(r)?.norm_squared();
    if stat.is_finite() {
        return Ok(stat);
    }
    // Overflow inside the solve (a residual near the largest float over a tiny variance can
    // give inf − inf = NaN): the same with r scaled by its largest magnitude, so the
    // statistic is +inf, never NaN.
    let c = r.amax();
    if !(c > 0.0 && c.is_finite()) {
        return Ok(f64::INFINITY);
    }
    Ok(c * c * solve(&(r / c))?.norm_squared())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::chi2_threshold;

    #[test]
    fn decides_against_threshold() {
        let mut d = ResidualChi2::new(0.1).unwrap();
        let a = DMatrix::identity(3, 3);
        let quiet = d.test(&DVector::from_vec(vec![0.1, 0.2, 0.3]), &a).unwrap();
        assert!(!quiet.alarm);
        assert!((quiet.statistic - 0.14).abs() < 1e-12);
        let loud = d.test(&DVector::from_vec(vec![2.0, 2.0, 1.0]), &a).unwrap();
        assert!(loud.alarm);
        assert!((loud.threshold - 6.251388631170325).abs() < 1e-9);
        // Missing component: threshold for 2 dof.
        let part = d
            .test(&DVector::from_vec(vec![f64::NAN, 1.0, 1.0]), &a)
            .unwrap();
        assert_eq!(part.dof, 2);
        assert!((part.threshold - chi2_threshold(0.1, 2).unwrap()).abs() < 1e-12);
    }
}
