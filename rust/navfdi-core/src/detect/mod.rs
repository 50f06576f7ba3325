//! Fault detectors (METHODS §2–§4, AIME §11). Each steps once per epoch on a residual `r` (m) and its
//! covariance `A` (m × m) and reports a [`Decision`]: statistic, threshold, alarm.
//!
//! NaN components of `r` mark measurements that were not used this epoch (see
//! [`crate::kalman::Innovation`]); a detector skips them. With no component at all a detector
//! leaves its state unchanged and repeats its previous alarm, with a NaN statistic.

pub mod aime;
pub mod chi2;
pub mod joint;
pub mod sprt;
pub mod state_chi2;

pub use aime::{Aime, TwoStageAime};
pub use chi2::ResidualChi2;
pub use joint::{JointChi2Sprt, JointDecision};
pub use sprt::{ImprovedSprt, SprtVariance};
pub use state_chi2::{StateChi2, StateDecision};

use crate::error::{Error, Result};
use crate::validate::{check_symmetric, shape_str};
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// `F⁻¹_{χ²(dof)}(1 − pf)` kept in `cache` (entry `dof − 1`, computed on first use); NaN for
/// `dof = 0`.
pub(crate) fn cached_chi2_threshold(cache: &mut Vec<f64>, pf: f64, dof: usize) -> Result<f64> {
    if dof == 0 {
        return Ok(f64::NAN);
    }
    while cache.len() < dof {
        let d = cache.len() + 1;
        cache.push(crate::stats::chi2_threshold(pf, d)?);
    }
    Ok(cache[dof - 1])
}

/// Serde for an `f64` that may be NaN (JSON has no NaN: it is written as `null` and read
/// back as NaN), for detector states that are pickled through JSON.
pub mod nan_f64 {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Write NaN as `null`.
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
        if v.is_nan() {
            s.serialize_none()
        } else {
            s.serialize_f64(*v)
        }
    }

    /// Read `null` as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// One epoch's decision of a detector.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Decision {
    /// Test statistic (chi-square: `λ = rᵀA⁻¹r`; SPRT: the largest per-component `λ_j`).
    /// NaN when no component was available.
    #[serde(with = "nan_f64")]
    pub statistic: f64,
    /// Threshold the statistic is compared with (NaN when no component was available to the
    /// chi-square test, whose threshold depends on the number of components).
    #[serde(with = "nan_f64")]
    pub threshold: f64,
    /// Fault declared this epoch.
    pub alarm: bool,
    /// Number of residual components used.
    pub dof: usize,
}

impl Decision {
    /// Statistic over threshold (PX4's "test ratio"): ≥ 1 means alarm.
    pub fn ratio(&self) -> f64 {
        self.statistic / self.threshold
    }
}

/// A validated residual: the indices of the available components and the Cholesky factor of
/// the covariance restricted to them (None when no component is available).
pub(crate) struct CheckedResidual {
    pub idx: Vec<usize>,
    pub chol: Option<Cholesky<f64, Dyn>>,
}

/// Check a residual / covariance pair: `r` length m (NaN allowed, no infinity), `A` m × m,
/// finite, symmetric and positive definite on the rows and columns of the available components.
pub(crate) fn check_residual(r: &DVector<f64>, a: &DMatrix<f64>) -> Result<CheckedResidual> {
    let m = r.len();
    if m == 0 {
        return Err(Error::Shape {
            name: "residual".into(),
            expected: "a non-empty vector".into(),
            got: "(0,)".into(),
        });
    }
    if a.nrows() != m || a.ncols() != m {
        return Err(Error::Shape {
            name: "covariance".into(),
            expected: shape_str(&[m, m]),
            got: shape_str(&[a.nrows(), a.ncols()]),
        });
    }
    let mut idx = Vec::with_capacity(m);
    for (i, v) in r.iter().enumerate() {
        if v.is_infinite() {
            return Err(Error::NonFinite {
                name: "residual".into(),
                index: format!("[{i}]"),
                value: *v,
            });
        }
        if !v.is_nan() {
            idx.push(i);
        }
    }
    for &i in &idx {
        for &j in &idx {
            let v = a[(i, j)];
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    name: "covariance".into(),
                    index: format!("[{i}, {j}]"),
                    value: v,
                });
            }
        }
    }
    if idx.is_empty() {
        return Ok(CheckedResidual { idx, chol: None });
    }
    let sub = if idx.len() == m {
        a.clone()
    } else {
        a.select_rows(&idx).select_columns(&idx)
    };
    check_symmetric("covariance", &sub)?;
    let chol = Cholesky::new(sub).ok_or_else(|| Error::NotPositiveDefinite {
        name: "covariance".into(),
        detail: "Cholesky factorisation of the residual covariance (available components) failed"
            .into(),
    })?;
    Ok(CheckedResidual {
        idx,
        chol: Some(chol),
    })
}

/// Any of the detectors, for code that configures detectors at run time.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub enum Detector {
    /// Residual chi-square test.
    Chi2(ResidualChi2),
    /// Improved SPRT per residual component.
    Sprt(ImprovedSprt),
    /// Joint chi-square / SPRT detector with reset.
    Joint(JointChi2Sprt),
}

impl Detector {
    /// Test one epoch.
    pub fn test(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Result<Decision> {
        match self {
            Detector::Chi2(d) => d.test(r, a),
            Detector::Sprt(d) => d.test(r, a),
            Detector::Joint(d) => d.test(r, a).map(|j| j.decision),
        }
    }

    /// Test an innovation produced by a filter: no validation, and the chi-square statistic is
    /// taken from `λ = rᵀA⁻¹r` (`statistic`, over `dof` components) instead of re-factoring `A`.
    pub fn test_innovation(
        &mut self,
        r: &DVector<f64>,
        a: &DMatrix<f64>,
        statistic: f64,
        dof: usize,
    ) -> Result<Decision> {
        match self {
            Detector::Chi2(d) => d.test_statistic(statistic, dof),
            Detector::Sprt(d) => Ok(d.test_trusted(r, a)),
            Detector::Joint(d) => d.test_trusted(r, a, statistic, dof).map(|j| j.decision),
        }
    }

    /// Clear all accumulated state.
    pub fn reset(&mut self) {
        match self {
            Detector::Chi2(d) => d.reset(),
            Detector::Sprt(d) => d.reset(),
            Detector::Joint(d) => d.reset(),
        }
    }
}
