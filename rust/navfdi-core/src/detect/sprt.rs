//! Improved SPRT (METHODS §3), per scalar residual component.
//!
//! `λ_j(k) = k·x̄_k² / (2σ²)` with the running mean `x̄_k` of component j since the last reset
//! (no-fault mean 0). With [`SprtVariance::Known`] each component is normalised by
//! `sqrt(A_jj)` so `σ = 1`; with [`SprtVariance::Sample`] `σ²` is the running sample variance
//! from Welford's recursion `M2_k = M2_{k−1} + ((k−1)/k)(x_k − x̄_{k−1})²`, `σ_k² = M2_k / k`
//! (the paper's recursion (14) is a typo; see METHODS §3). The alarm is raised when any
//! component reaches `T(H1) = ln((1 − Pm)/Pf)`.
//!
//! Minimum sample count: with the sample variance, the statistic after k samples is
//! `(k/(k−1))·t²/2` with `t` Student-distributed with k − 1 degrees of freedom, so right after a
//! reset it is huge by chance (at k = 2, `P(λ ≥ 6.9) ≈ 0.23` per component: most fault-free
//! runs alarmed at their second epoch). A component may therefore alarm only once it has
//! [`ImprovedSprt::min_samples`] samples since the last reset: by default
//! [`DEFAULT_MIN_SAMPLES_SAMPLE`] with the sample variance and 1 (no restriction) with the
//! known variance. The statistic itself is always reported.

use super::{check_residual, Decision};
use crate::error::{Error, Result};
use crate::stats::sprt_threshold;
use nalgebra::{DMatrix, DVector};

/// Which variance normalises the SPRT statistic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SprtVariance {
    /// Use the residual covariance diagonal `A_jj` (σ = 1 after normalisation).
    Known,
    /// Use the running sample variance of the raw residual component (Welford).
    Sample,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
struct Accumulator {
    count: u64,
    mean: f64,
    m2: f64,
    lambda: f64,
}

/// Default minimum sample count before a sample-variance component may alarm.
pub const DEFAULT_MIN_SAMPLES_SAMPLE: u64 = 20;

/// Improved SPRT detector over the components of a residual vector.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ImprovedSprt {
    pf: f64,
    pm: f64,
    threshold: f64,
    variance: SprtVariance,
    min_samples: u64,
    acc: Vec<Accumulator>,
    alarm: bool,
}

impl ImprovedSprt {
    /// New detector. `pf`, `pm` in (0, 1) with `pf + pm < 1`.
    pub fn new(pf: f64, pm: f64, variance: SprtVariance) -> Result<Self> {
        let threshold = sprt_threshold(pf, pm)?;
        Ok(ImprovedSprt {
            pf,
            pm,
            threshold,
            variance,
            min_samples: match variance {
                SprtVariance::Known => 1,
                SprtVariance::Sample => DEFAULT_MIN_SAMPLES_SAMPLE,
            },
            acc: Vec::new(),
            alarm: false,
        })
    }

    /// Set the minimum number of samples (since the last reset) a component needs before it
    /// may raise the alarm (≥ 1; see the module documentation).
    pub fn with_min_samples(mut self, min_samples: u64) -> Result<Self> {
        if min_samples < 1 {
            return Err(Error::InvalidParameter {
                name: "min_samples".into(),
                value: min_samples as f64,
                requirement: "must be at least 1".into(),
            });
        }
        self.min_samples = min_samples;
        Ok(self)
    }

    /// Minimum samples per component before it may alarm.
    pub fn min_samples(&self) -> u64 {
        self.min_samples
    }

    /// False-alarm probability parameter.
    pub fn pf(&self) -> f64 {
        self.pf
    }

    /// Missed-detection probability parameter.
    pub fn pm(&self) -> f64 {
        self.pm
    }

    /// Threshold `T(H1)`.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Variance mode.
    pub fn variance(&self) -> SprtVariance {
        self.variance
    }

    /// Per-component statistics `λ_j` after the last test (empty before the first).
    pub fn component_statistics(&self) -> Vec<f64> {
        self.acc.iter().map(|a| a.lambda).collect()
    }

    /// Per-component sample counts since the last reset.
    pub fn component_counts(&self) -> Vec<u64> {
        self.acc.iter().map(|a| a.count).collect()
    }

    /// Last alarm state.
    pub fn alarm(&self) -> bool {
        self.alarm
    }

    /// Test one epoch. The residual dimension is fixed by the first call.
    pub fn test(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Result<Decision> {
        let idx = check_residual(r, a)?.idx;
        self.check_dimension(r.len())?;
        if self.variance == SprtVariance::Known {
            for &j in &idx {
                if !(a[(j, j)] > 0.0) {
                    return Err(Error::NotPositiveDefinite {
                        name: "covariance".into(),
                        detail: format!(
                            "diagonal element [{j}, {j}] = {} must be positive",
                            a[(j, j)]
                        ),
                    });
                }
            }
        }
        Ok(self.test_trusted(r, a))
    }

    /// Check a residual length against the dimension fixed by the first test.
    pub fn check_dimension(&self, m: usize) -> Result<()> {
        if !self.acc.is_empty() && self.acc.len() != m {
            return Err(Error::Shape {
                name: "residual".into(),
                expected: format!(
                    "({},) as in earlier epochs (call reset_dimension() to change it)",
                    self.acc.len()
                ),
                got: format!("({m},)"),
            });
        }
        Ok(())
    }

    /// [`ImprovedSprt::test`] without validation, for residuals from a filter (`A` positive
    /// definite on the non-NaN components, constant dimension).
    pub fn test_trusted(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Decision {
        let m = r.len();
        if self.acc.len() != m {
            self.acc = vec![Accumulator::default(); m];
        }
        let mut dof = 0;
        let mut overflow = false;
        for (j, acc) in self.acc.iter_mut().enumerate() {
            let raw = r[j];
            if raw.is_nan() {
                continue;
            }
            dof += 1;
            let x = match self.variance {
                SprtVariance::Known => raw / a[(j, j)].sqrt(),
                SprtVariance::Sample => raw,
            };
            let mut next = *acc;
            next.count += 1;
            let k = next.count as f64;
            let d = x - next.mean;
            next.m2 += (k - 1.0) / k * d * d;
            next.mean += d / k;
            let s2 = match self.variance {
                SprtVariance::Known => 1.0,
                SprtVariance::Sample => next.m2 / k,
            };
            next.lambda = if s2 > 0.0 {
                k * next.mean * next.mean / (2.0 * s2)
            } else if k >= 2.0 && next.mean != 0.0 {
                // Two or more identical non-zero samples: a mean with no spread at all.
                f64::INFINITY
            } else {
                0.0
            };
            if next.m2.is_finite() && next.mean.is_finite() && !next.lambda.is_nan() {
                *acc = next;
            } else {
                // The sample overflows the accumulator (a residual near the largest float or
                // a variance near the smallest): the largest possible evidence of a fault.
                // The accumulator is left as it was, so it is not poisoned for later epochs.
                overflow = true;
            }
        }
        if dof == 0 {
            return Decision {
                statistic: f64::NAN,
                threshold: self.threshold,
                alarm: self.alarm,
                dof: 0,
            };
        }
        let statistic = if overflow {
            f64::INFINITY
        } else {
            self.acc.iter().map(|a| a.lambda).fold(0.0, f64::max)
        };
        let min = self.min_samples;
        self.alarm = overflow
            || self
                .acc
                .iter()
                .any(|a| a.count >= min && a.lambda >= self.threshold);
        Decision {
            statistic,
            threshold: self.threshold,
            alarm: self.alarm,
            dof,
        }
    }

    /// Reset every accumulator to zero (keeps the residual dimension).
    pub fn reset(&mut self) {
        for a in &mut self.acc {
            *a = Accumulator::default();
        }
        self.alarm = false;
    }

    /// Restart component `j`'s accumulator (its "pseudo-normal" state, paper 002); the alarm
    /// is re-evaluated at the next test. Out-of-range `j` does nothing.
    pub fn reset_component(&mut self, j: usize) {
        if let Some(a) = self.acc.get_mut(j) {
            *a = Accumulator::default();
        }
    }

    /// Reset and forget the residual dimension, so the next test may use another length.
    pub fn reset_dimension(&mut self) {
        self.acc.clear();
        self.alarm = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_variance_statistic() {
        let mut s = ImprovedSprt::new(0.1, 0.1, SprtVariance::Known).unwrap();
        let a = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0]));
        // x = r/2: 1, 1, 1 → mean 1 → λ = k/2.
        for k in 1..=3 {
            let d = s.test(&DVector::from_vec(vec![2.0]), &a).unwrap();
            assert!((d.statistic - k as f64 / 2.0).abs() < 1e-12);
            assert_eq!(d.alarm, k as f64 / 2.0 >= 2.1972245773362196);
        }
        s.reset();
        assert_eq!(s.component_counts(), vec![0]);
    }

    #[test]
    fn welford_sample_variance() {
        let mut s = ImprovedSprt::new(0.1, 0.1, SprtVariance::Sample).unwrap();
        let a = DMatrix::identity(1, 1);
        let data = [1.0, 3.0, 2.0, 6.0];
        let mut d = None;
        for x in data {
            d = Some(s.test(&DVector::from_vec(vec![x]), &a).unwrap());
        }
        let mean = 3.0;
        let var = data.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / 4.0;
        let expected = 4.0 * mean * mean / (2.0 * var);
        assert!((d.unwrap().statistic - expected).abs() < 1e-12);
    }

    #[test]
    fn reset_component_restarts_only_that_component() {
        let mut s = ImprovedSprt::new(0.1, 0.1, SprtVariance::Known).unwrap();
        let a = DMatrix::identity(2, 2);
        for _ in 0..3 {
            s.test(&DVector::from_vec(vec![2.0, 1.0]), &a).unwrap();
        }
        s.reset_component(0);
        s.reset_component(9); // out of range: nothing
        assert_eq!(s.component_counts(), vec![0, 3]);
        let d = s.test(&DVector::from_vec(vec![2.0, 1.0]), &a).unwrap();
        assert_eq!(s.component_statistics()[0], 2.0); // 1·2²/2 after the restart
        assert!((d.statistic - 2.0).abs() < 1e-12);
    }

    #[test]
    fn min_samples_gates_the_alarm() {
        let mut s = ImprovedSprt::new(0.1, 0.1, SprtVariance::Known)
            .unwrap()
            .with_min_samples(3)
            .unwrap();
        let a = DMatrix::identity(1, 1);
        let big = DVector::from_vec(vec![10.0]);
        assert!(!s.test(&big, &a).unwrap().alarm);
        assert!(!s.test(&big, &a).unwrap().alarm);
        assert!(s.test(&big, &a).unwrap().alarm);
        assert!(ImprovedSprt::new(0.1, 0.1, SprtVariance::Known)
            .unwrap()
            .with_min_samples(0)
            .is_err());
    }

    #[test]
    fn dimension_is_fixed() {
        let mut s = ImprovedSprt::new(0.1, 0.1, SprtVariance::Known).unwrap();
        s.test(&DVector::zeros(2), &DMatrix::identity(2, 2))
            .unwrap();
        assert!(s
            .test(&DVector::zeros(3), &DMatrix::identity(3, 3))
            .is_err());
        assert_eq!(s.component_counts(), vec![1, 1]);
    }
}
