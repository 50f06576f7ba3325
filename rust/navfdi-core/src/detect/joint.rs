//! Joint chi-square / improved-SPRT detector of paper 000 (METHODS §4).
//!
//! Both tests run on the same residuals. The alarm is the SPRT's (sensitive to small ramps);
//! when the chi-square test declares the fault over (its alarm falls from fault to no-fault),
//! the SPRT accumulators are reset before the SPRT processes the current epoch, so that the
//! SPRT clears and a later fault is detected as a new one.

use super::{Decision, ImprovedSprt, ResidualChi2, SprtVariance};
use crate::error::Result;
use nalgebra::{DMatrix, DVector};

/// The joint detector's decision with both component tests.
#[derive(Debug, Clone, PartialEq)]
pub struct JointDecision {
    /// The joint decision (the SPRT's statistic, threshold and alarm).
    pub decision: Decision,
    /// The chi-square test's decision this epoch.
    pub chi2: Decision,
    /// True when the chi-square test's end-of-fault reset the SPRT this epoch.
    pub reset: bool,
}

/// Joint chi-square / SPRT detector with reset.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct JointChi2Sprt {
    chi2: ResidualChi2,
    sprt: ImprovedSprt,
    chi2_alarm: bool,
}

impl JointChi2Sprt {
    /// New detector; `pf`, `pm` in (0, 1), `pf + pm < 1`. Both tests use the same `pf`; the SPRT
    /// also uses `pm`.
    pub fn new(pf: f64, pm: f64, variance: SprtVariance) -> Result<Self> {
        Ok(JointChi2Sprt {
            chi2: ResidualChi2::new(pf)?,
            sprt: ImprovedSprt::new(pf, pm, variance)?,
            chi2_alarm: false,
        })
    }

    /// The chi-square part.
    pub fn chi2(&self) -> &ResidualChi2 {
        &self.chi2
    }

    /// The SPRT part.
    pub fn sprt(&self) -> &ImprovedSprt {
        &self.sprt
    }

    /// Test one epoch.
    pub fn test(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Result<JointDecision> {
        // Validate everything (and compute λ) before changing either test; a residual whose
        // covariance is positive definite on its components also has the positive diagonal
        // the known-variance SPRT divides by.
        let (statistic, dof) = ResidualChi2::statistic(r, a)?;
        self.sprt.check_dimension(r.len())?;
        self.test_trusted(r, a, statistic, dof)
    }

    /// [`JointChi2Sprt::test`] without validation, with the chi-square statistic computed
    /// elsewhere (`rᵀA⁻¹r` over the `dof` non-NaN components).
    pub fn test_trusted(
        &mut self,
        r: &DVector<f64>,
        a: &DMatrix<f64>,
        statistic: f64,
        dof: usize,
    ) -> Result<JointDecision> {
        let c = self.chi2.test_statistic(statistic, dof)?;
        let fell = c.dof > 0 && self.chi2_alarm && !c.alarm;
        if fell {
            self.sprt.reset();
        }
        let s = self.sprt.test_trusted(r, a);
        if c.dof > 0 {
            self.chi2_alarm = c.alarm;
        }
        Ok(JointDecision {
            decision: s,
            chi2: c,
            reset: fell,
        })
    }

    /// Reset both tests.
    pub fn reset(&mut self) {
        self.chi2.reset();
        self.sprt.reset();
        self.chi2_alarm = false;
    }

    /// Set the SPRT's minimum sample count ([`ImprovedSprt::with_min_samples`]).
    pub fn with_min_samples(mut self, min_samples: u64) -> Result<Self> {
        self.sprt = self.sprt.with_min_samples(min_samples)?;
        Ok(self)
    }

    /// Reset both tests and forget the residual dimension (the next test may use another
    /// length).
    pub fn reset_dimension(&mut self) {
        self.reset();
        self.sprt.reset_dimension();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_end_of_fault_resets_sprt() {
        let mut j = JointChi2Sprt::new(0.1, 0.1, SprtVariance::Known).unwrap();
        let a = DMatrix::identity(1, 1);
        // Large residuals: both alarm.
        for _ in 0..5 {
            let d = j.test(&DVector::from_vec(vec![5.0]), &a).unwrap();
            assert!(d.decision.alarm && d.chi2.alarm);
        }
        // Back to zero: chi-square falls, SPRT is reset and clears.
        let d = j.test(&DVector::from_vec(vec![0.0]), &a).unwrap();
        assert!(d.reset);
        assert!(!d.chi2.alarm);
        assert!(!d.decision.alarm);
        assert_eq!(j.sprt().component_counts(), vec![1]);
    }
}
