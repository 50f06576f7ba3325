//! Sequential detectors on per-satellite residual streams of a single-point solution.
//!
//! The snapshot test judges each epoch alone. A slowly growing fault shows earlier in a
//! satellite's residual *history*. Every satellite with a residual at an epoch (used or
//! excluded) feeds two detectors; a satellite without one (not tracked, below the mask, no
//! solution) restarts both.
//!
//! * **Improved SPRT** ([`crate::detect::sprt::ImprovedSprt`], known variance) on the
//!   normalised residual `v/σ`: `λ = k·x̄²/2` over the k samples since the satellite's last
//!   restart, alarm at `ln((1 − P_m)/P_f)`. It assumes zero-mean white residuals; real
//!   residuals carry slowly varying satellite biases (multipath, broadcast orbit and clock), so
//!   on real data it alarms on biased satellites without any fault (measured, see
//!   docs/gnss_real.md).
//! * **AIME** ([`crate::detect::Aime`]) on the same normalised residual, window N epochs:
//!   the χ²(1) test of the window mean; like the SPRT it reads a steady bias as a fault.
//! * **Rate CUSUM**: Page's two-sided CUSUM on the residual's epoch-to-epoch change
//!   `d_k = v_k − v_{k−1}` normalised by its own running RMS:
//!   `g⁺ = max(0, g⁺ + d/ŝ − ν)`, `g⁻ = max(0, g⁻ − d/ŝ − ν)`, alarm when either exceeds `h`.
//!   `ŝ² ` is an exponentially weighted mean of `d²` (time constant `tau` epochs, floor `floor`
//!   m), updated only while both sums are zero so that a fault does not inflate it; no alarm
//!   during the first `warmup` epochs after a restart. Differencing removes the slowly varying
//!   biases that trouble the SPRT; a ramp of rate ρ shifts `d` by about `r_i ρ` per epoch (r_i
//!   the redundancy of the satellite). ν = 1 and h = 5 are the textbook CUSUM choices for a
//!   shift of 2ŝ; its false-alarm rate on real data is measured, not derived (the changes are
//!   not Gaussian white noise).

use crate::detect::sprt::{ImprovedSprt, SprtVariance};
use crate::detect::Aime;
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// Settings of the rate CUSUM.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CusumConfig {
    /// Drift ν (in units of ŝ).
    pub drift: f64,
    /// Threshold h (in units of ŝ).
    pub threshold: f64,
    /// Time constant of ŝ² (epochs).
    pub tau: f64,
    /// Epochs after a restart without alarms.
    pub warmup: usize,
    /// Floor of ŝ (m).
    pub floor: f64,
}

impl Default for CusumConfig {
    fn default() -> Self {
        CusumConfig {
            drift: 1.0,
            threshold: 5.0,
            tau: 60.0,
            warmup: 20,
            floor: 0.02,
        }
    }
}

impl CusumConfig {
    /// Check the numbers.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("cusum drift", self.drift),
            ("cusum threshold", self.threshold),
            ("cusum tau", self.tau),
            ("cusum floor", self.floor),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::InvalidParameter {
                    name: name.into(),
                    value: v,
                    requirement: "must be positive and finite".into(),
                });
            }
        }
        if self.tau < 1.0 {
            return Err(Error::InvalidParameter {
                name: "cusum tau".into(),
                value: self.tau,
                requirement: "the time constant must be at least 1 epoch".into(),
            });
        }
        Ok(())
    }
}

/// The rate CUSUM of one satellite.
#[derive(Debug, Clone, Default)]
pub struct RateCusum {
    prev: Option<f64>,
    var: Option<f64>,
    pos: f64,
    neg: f64,
    count: usize,
}

impl RateCusum {
    /// Feed residual `v` (m); returns (statistic max(g⁺, g⁻), alarm).
    pub fn step(&mut self, v: f64, cfg: &CusumConfig) -> (f64, bool) {
        let Some(prev) = self.prev.replace(v) else {
            self.count = 1;
            return (0.0, false);
        };
        self.count += 1;
        let d = v - prev;
        if let Some(var) = self.var {
            let s = var.sqrt().max(cfg.floor);
            if self.count > cfg.warmup {
                self.pos = (self.pos + d / s - cfg.drift).max(0.0);
                self.neg = (self.neg - d / s - cfg.drift).max(0.0);
            }
        }
        if self.pos == 0.0 && self.neg == 0.0 {
            let a = 1.0 / cfg.tau;
            self.var = Some(match self.var {
                None => d * d,
                Some(var) => (1.0 - a) * var + a * d * d,
            });
        }
        let g = self.pos.max(self.neg);
        (g, g > cfg.threshold)
    }
}

/// Both detectors of one satellite.
#[derive(Debug, Clone)]
pub struct SatDetectors {
    sprt: ImprovedSprt,
    aime: Aime,
    cusum: RateCusum,
}

/// Per-satellite statistics and alarms of one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeqOutput {
    /// SPRT statistic λ.
    pub sprt: f64,
    /// SPRT alarm.
    pub sprt_alarm: bool,
    /// AIME statistic.
    pub aime: f64,
    /// AIME alarm.
    pub aime_alarm: bool,
    /// CUSUM statistic max(g⁺, g⁻).
    pub cusum: f64,
    /// CUSUM alarm.
    pub cusum_alarm: bool,
}

impl SeqOutput {
    /// No residual at this epoch.
    pub const NONE: SeqOutput = SeqOutput {
        sprt: f64::NAN,
        sprt_alarm: false,
        aime: f64::NAN,
        aime_alarm: false,
        cusum: f64::NAN,
        cusum_alarm: false,
    };
}

/// Settings of both detectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeqConfig {
    /// SPRT false-alarm and missed-detection probabilities.
    pub sprt: (f64, f64),
    /// AIME false-alarm probability and window (epochs).
    pub aime: (f64, usize),
    /// Rate CUSUM.
    pub cusum: CusumConfig,
}

impl Default for SeqConfig {
    fn default() -> Self {
        SeqConfig {
            sprt: (1e-3, 1e-3),
            aime: (1e-3, 10),
            cusum: CusumConfig::default(),
        }
    }
}

impl SeqConfig {
    /// Check the numbers.
    pub fn validate(&self) -> Result<()> {
        ImprovedSprt::new(self.sprt.0, self.sprt.1, SprtVariance::Known)?;
        Aime::new(self.aime.0, self.aime.1)?;
        self.cusum.validate()
    }
}

impl SatDetectors {
    /// Fresh detectors.
    pub fn new(cfg: &SeqConfig) -> Result<Self> {
        Ok(SatDetectors {
            sprt: ImprovedSprt::new(cfg.sprt.0, cfg.sprt.1, SprtVariance::Known)?,
            aime: Aime::new(cfg.aime.0, cfg.aime.1)?,
            cusum: RateCusum::default(),
        })
    }

    /// Feed residual `v` (m) with its σ (m).
    pub fn step(&mut self, v: f64, sigma: f64, cfg: &SeqConfig) -> SeqOutput {
        let x = DVector::from_element(1, v / sigma);
        let one = DMatrix::from_element(1, 1, 1.0);
        let d = self.sprt.test_trusted(&x, &one);
        let a = self.aime.test(&x, &one).unwrap_or(crate::detect::Decision {
            statistic: f64::NAN,
            threshold: f64::NAN,
            alarm: false,
            dof: 0,
        });
        let (cusum, cusum_alarm) = self.cusum.step(v, &cfg.cusum);
        SeqOutput {
            sprt: d.statistic,
            sprt_alarm: d.alarm,
            aime: a.statistic,
            aime_alarm: a.alarm,
            cusum,
            cusum_alarm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cusum_ignores_a_constant_bias_and_catches_a_ramp() {
        let cfg = CusumConfig::default();
        let mut c = RateCusum::default();
        // Bias 3 m plus small alternating noise: no alarm.
        for k in 0..200 {
            let v = 3.0 + if k % 2 == 0 { 0.03 } else { -0.03 };
            assert!(!c.step(v, &cfg).1, "epoch {k}");
        }
        // Ramp of 0.3 m/epoch: alarm within a few epochs.
        let mut first = None;
        for j in 1..20 {
            let v = 3.0 + 0.3 * j as f64 + if j % 2 == 0 { 0.03 } else { -0.03 };
            if c.step(v, &cfg).1 && first.is_none() {
                first = Some(j);
            }
        }
        assert!(matches!(first, Some(j) if j <= 3), "{first:?}");
    }

    #[test]
    fn bad_settings_are_named() {
        let cfg = CusumConfig {
            drift: -1.0,
            ..CusumConfig::default()
        };
        assert!(cfg
            .validate()
            .unwrap_err()
            .to_string()
            .contains("cusum drift"));
        let s = SeqConfig {
            sprt: (0.6, 0.6),
            ..SeqConfig::default()
        };
        assert!(s.validate().is_err());
    }
}
