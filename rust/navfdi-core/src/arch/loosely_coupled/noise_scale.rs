//! The scale of a GNSS channel's measurement σ, estimated from its own innovations
//! ([`NoiseScale`], `[loosely_coupled] noise_scale = "auto"`), and the window lengths the
//! receiver's consistency ([`super::receiver::ReceiverConsistency`]) shares with it.

use super::window::median_of;
use std::collections::VecDeque;

/// The scale `c` of a GNSS channel's measurement σ, estimated from its own innovations: over
/// the last [`SCALE_WINDOW`] components of fixes used as measured, `c² = (med(d²)/0.4549 −
/// med(HPHᵀ)) / med(R)` (0.4549: the median of χ²₁), so that the innovations' median matches
/// a consistent filter's — robust to the faults it must find (held fixes are not counted, and
/// a median ignores the rest). Optimistic σ give `c > 1` (tests that hold their pf); the
/// loosely coupled filter clamps it to `[1, 10]`. Clamped to `[lo, hi]`; 1 until
/// [`SCALE_MIN`] samples are in.
#[derive(Debug, Clone)]
pub struct NoiseScale {
    d2: VecDeque<f64>,
    hph: VecDeque<f64>,
    r: VecDeque<f64>,
    /// Fixed scale (no estimation) when set.
    fixed: Option<f64>,
    lo: f64,
    hi: f64,
}

/// The (upper) median of a window; NaN when empty.
pub(super) fn median(v: &VecDeque<f64>) -> f64 {
    median_of(&mut v.iter().copied().collect::<Vec<_>>())
}

/// Components (3 per fix) the scale is estimated over.
pub const SCALE_WINDOW: usize = 180;
/// Components needed before the scale departs from 1.
pub const SCALE_MIN: usize = 30;

impl NoiseScale {
    /// An estimated scale clamped to `[lo, hi]`, or a `fixed` one.
    pub fn new(fixed: Option<f64>, lo: f64, hi: f64) -> Self {
        NoiseScale {
            d2: Default::default(),
            hph: Default::default(),
            r: Default::default(),
            fixed,
            lo,
            hi,
        }
    }

    /// Add a fix used as measured: its components' squared innovations `d²`, predicted
    /// variances `HPHᵀ` and measurement variances `R` (unscaled).
    pub fn add(&mut self, d2: &[f64], hph: &[f64], r: &[f64]) {
        if self.fixed.is_some() {
            return;
        }
        for j in 0..d2.len().min(hph.len()).min(r.len()) {
            if !(d2[j].is_finite() && hph[j].is_finite() && r[j] > 0.0) {
                continue;
            }
            if self.d2.len() == SCALE_WINDOW {
                self.d2.pop_front();
                self.hph.pop_front();
                self.r.pop_front();
            }
            self.d2.push_back(d2[j]);
            self.hph.push_back(hph[j].max(0.0));
            self.r.push_back(r[j]);
        }
    }

    /// The current scale `c` (of σ).
    pub fn scale(&self) -> f64 {
        if let Some(f) = self.fixed {
            return f;
        }
        if self.d2.len() < SCALE_MIN {
            return 1.0;
        }
        let med = |v: &VecDeque<f64>| median(v);
        let c2 = (med(&self.d2) / 0.454_936_4 - med(&self.hph)) / med(&self.r);
        c2.max(self.lo * self.lo).sqrt().clamp(self.lo, self.hi)
    }
}

#[cfg(test)]
mod scale_tests {
    use super::*;

    #[test]
    fn the_scale_matches_the_innovations_and_ignores_outliers() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut s = NoiseScale::new(None, 0.1, 10.0);
        assert_eq!(s.scale(), 1.0);
        // Innovations of σ 0.6 m against a reported R of 4 m² and HPHᵀ 0.04 m²: c ≈ 0.29.
        for k in 0..200 {
            let n: f64 = StandardNormal.sample(&mut rng);
            let d = 0.6 * n;
            let d = if k % 10 == 0 { 30.0 } else { d }; // 10 % gross outliers
            s.add(&[d * d], &[0.04], &[4.0]);
        }
        let c = s.scale();
        assert!((c - (0.36f64 - 0.04).sqrt() / 2.0).abs() < 0.06, "{c}");
        assert_eq!(NoiseScale::new(Some(2.0), 0.1, 10.0).scale(), 2.0);
    }
}
