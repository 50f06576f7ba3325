//! Weighted fusion of one quantity over several sensors with a fault matrix (METHODS §9,
//! paper 003): `y = Σ w_i M_i x_i / Σ w_i M_i`, `w_i = 1/σ_i²`, `M_i ∈ {0, 1}` from the
//! sensors' detectors.
//!
//! `σ_i²` is estimated over the last `window` samples of sensor i's deviation from the
//! filter's predicted value, `d = x_i − ŷ⁻`, either as their **variance** about their mean
//! (paper 003's eq. 35, [`Estimate::Variance`]) or as their **mean square** (navfdi's
//! default, [`Estimate::MeanSquare`]: a biased sensor — a radio altimeter over uneven terrain
//! — then loses weight, where the variance keeps a slowly varying bias at full weight); until
//! a sensor has 2 samples its `prior_sigma` (the sensor's stated noise σ) is used, and the
//! estimate is never below `prior_sigma²` (**resolution**: the deviation contains the sensor's
//! own noise; a smaller estimate is sampling error that would give the sensor all the weight).
//! A sensor without a value this epoch (NaN) or with `M_i = 0` does not contribute; when none
//! contributes the output says so (`value = None`) and the caller predicts only. The
//! fused variance `1 / Σ w_i M_i` assumes independent sensors.

use crate::error::{Error, Result};
use std::collections::VecDeque;

/// One epoch's fused output.
#[derive(Debug, Clone, PartialEq)]
pub struct Fused {
    /// Fused value, None when no sensor contributed.
    pub value: Option<f64>,
    /// Its variance `1 / Σ w_i M_i` (NaN when none contributed).
    pub variance: f64,
    /// Normalised weights `w_i M_i / Σ w_j M_j` (0 for sensors that did not contribute).
    pub weights: Vec<f64>,
    /// Estimated `σ_i²` per sensor used for the weights.
    pub sigma2: Vec<f64>,
}

/// How `σ_i²` is estimated from the window of deviations `d`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimate {
    /// `Σ d² / N`: a bias counts as error.
    #[default]
    MeanSquare,
    /// `Σ (d − d̄)² / (N − 1)` (paper 003, eq. 35): only the scatter counts.
    Variance,
}

impl Estimate {
    /// Its name in scenarios and the Python API: `mean_square` or `variance`.
    pub fn name(self) -> &'static str {
        match self {
            Estimate::MeanSquare => "mean_square",
            Estimate::Variance => "variance",
        }
    }

    /// The estimate of a [`Estimate::name`], None for anything else.
    pub fn from_name(name: &str) -> Option<Self> {
        [Estimate::MeanSquare, Estimate::Variance]
            .into_iter()
            .find(|e| e.name() == name)
    }
}

/// Inverse-variance fusion with a fault matrix and windowed variance estimates.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct WeightedFusion {
    window: usize,
    prior: Vec<f64>,
    devs: Vec<VecDeque<f64>>,
    #[serde(default)]
    estimate: Estimate,
}

impl WeightedFusion {
    /// `prior_sigma` per sensor (> 0, finite; its length is the number of sensors), `window`
    /// N ≥ 2 samples.
    pub fn new(prior_sigma: &[f64], window: usize) -> Result<Self> {
        if prior_sigma.is_empty() {
            return Err(Error::Invalid(
                "prior_sigma: at least one sensor is required".into(),
            ));
        }
        if let Some((i, v)) = prior_sigma
            .iter()
            .enumerate()
            .find(|(_, v)| !(**v >= 1e-150 && **v <= 1e150))
        {
            return Err(Error::InvalidParameter {
                name: format!("prior_sigma[{i}]"),
                value: *v,
                requirement: "a standard deviation must be positive, finite and within 1e-150 … 1e150 (its square and inverse weight must be representable)".into(),
            });
        }
        if !(2..=1_000_000).contains(&window) {
            return Err(Error::InvalidParameter {
                name: "window".into(),
                value: window as f64,
                requirement: "the variance window must hold 2 to 1 000 000 samples".into(),
            });
        }
        Ok(WeightedFusion {
            window,
            prior: prior_sigma.to_vec(),
            // Grown as samples arrive (a large window costs memory only once filled).
            devs: vec![VecDeque::new(); prior_sigma.len()],
            estimate: Estimate::MeanSquare,
        })
    }

    /// The same fusion with `estimate` for `σ_i²`.
    pub fn with_estimate(mut self, estimate: Estimate) -> Self {
        self.estimate = estimate;
        self
    }

    /// How `σ_i²` is estimated.
    pub fn estimate(&self) -> Estimate {
        self.estimate
    }

    /// Check that a deserialised object is self-consistent (used when unpickling).
    pub fn check_consistent(&self) -> Result<()> {
        let ok = !self.prior.is_empty()
            && self.devs.len() == self.prior.len()
            && (2..=1_000_000).contains(&self.window)
            && self.devs.iter().all(|d| d.len() <= self.window)
            && self.prior.iter().all(|v| *v > 0.0 && v.is_finite());
        if ok {
            Ok(())
        } else {
            Err(Error::Invalid("inconsistent weighted-fusion state".into()))
        }
    }

    /// Number of sensors.
    pub fn sensors(&self) -> usize {
        self.prior.len()
    }

    /// One epoch: `values` per sensor (NaN: not available), the filter's `predicted` value,
    /// `healthy` = the fault matrix `M_i`. Inputs are validated; on error nothing changes.
    pub fn step(&mut self, values: &[f64], predicted: f64, healthy: &[bool]) -> Result<Fused> {
        let n = self.prior.len();
        for (name, len) in [("values", values.len()), ("healthy", healthy.len())] {
            if len != n {
                return Err(Error::Shape {
                    name: name.into(),
                    expected: format!("({n},), one per sensor"),
                    got: format!("({len},)"),
                });
            }
        }
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| v.is_infinite()) {
            return Err(Error::NonFinite {
                name: "values".into(),
                index: format!("[{i}]"),
                value: *v,
            });
        }
        if !predicted.is_finite() {
            return Err(Error::NonFinite {
                name: "predicted".into(),
                index: "".into(),
                value: predicted,
            });
        }
        let mut sigma2 = Vec::with_capacity(n);
        for ((v, d), prior) in values.iter().zip(self.devs.iter_mut()).zip(&self.prior) {
            if v.is_finite() {
                if d.len() == self.window {
                    d.pop_front();
                }
                d.push_back(v - predicted);
            }
            sigma2.push(if d.len() >= 2 {
                let n = d.len() as f64;
                let s2 = match self.estimate {
                    Estimate::MeanSquare => d.iter().map(|x| x * x).sum::<f64>() / n,
                    Estimate::Variance => {
                        let mean = d.iter().sum::<f64>() / n;
                        d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)
                    }
                };
                // Floor: the deviation contains the sensor's own noise, so an estimate below
                // it is sampling error (from 2–3 samples it can be near zero and would take
                // all the weight, and the fused variance 1/Σw would collapse).
                s2.max(prior * prior)
            } else {
                prior * prior
            });
        }
        let mut weights = vec![0.0; n];
        let (mut sw, mut swx) = (0.0, 0.0);
        for i in 0..n {
            if healthy[i] && values[i].is_finite() {
                let w = 1.0 / sigma2[i];
                weights[i] = w;
                sw += w;
                swx += w * values[i];
            }
        }
        if sw > 0.0 {
            for w in weights.iter_mut() {
                *w /= sw;
            }
            Ok(Fused {
                value: Some(swx / sw),
                variance: 1.0 / sw,
                weights,
                sigma2,
            })
        } else {
            Ok(Fused {
                value: None,
                variance: f64::NAN,
                weights,
                sigma2,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fuses_by_inverse_variance_and_reports_none() {
        let mut f = WeightedFusion::new(&[1.0, 2.0], 3).unwrap();
        let out = f.step(&[10.0, 13.0], 10.0, &[true, true]).unwrap();
        // One sample each: priors 1 and 4 → weights 0.8 / 0.2.
        assert!((out.value.unwrap() - (0.8 * 10.0 + 0.2 * 13.0)).abs() < 1e-12);
        let out = f.step(&[f64::NAN, 12.0], 10.0, &[true, false]).unwrap();
        assert_eq!(out.value, None);
        assert!(f
            .step(&[1.0], 0.0, &[true, true])
            .unwrap_err()
            .to_string()
            .contains("values"));
        // A constant offset: its mean square counts, its variance does not.
        let mut ms = WeightedFusion::new(&[0.01, 1.0], 3).unwrap();
        let mut var = ms.clone().with_estimate(Estimate::Variance);
        for k in 0..3 {
            let v = [1.0 + 0.1 * (k % 2) as f64, 3.0];
            let a = ms.step(&v, 1.0, &[true, true]).unwrap();
            let b = var.step(&v, 1.0, &[true, true]).unwrap();
            if k == 2 {
                assert!((a.sigma2[1] - 4.0).abs() < 1e-12);
                assert!((b.sigma2[1] - 1.0).abs() < 1e-15);
                let m: f64 = 0.1 / 3.0;
                let want = (2.0 * m * m + (0.1 - m).powi(2)) / 2.0;
                assert!((b.sigma2[0] - want).abs() < 1e-15);
            }
        }
        assert!(WeightedFusion::new(&[1.0, 0.0], 3)
            .unwrap_err()
            .to_string()
            .contains("prior_sigma[1]"));
    }
}
