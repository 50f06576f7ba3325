//! The scale of a GNSS channel's measurement σ, estimated from its own innovations
//! ([`NoiseScale`], `[loosely_coupled] noise_scale = "auto"`), and the window lengths the
//! receiver's consistency ([`super::receiver::ReceiverConsistency`]) shares with it.

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
    d2: Rolling<SCALE_WINDOW>,
    hph: Rolling<SCALE_WINDOW>,
    r: Rolling<SCALE_WINDOW>,
    /// Fixed scale (no estimation) when set.
    fixed: Option<f64>,
    lo: f64,
    hi: f64,
}

/// A window of the last `CAP` values that keeps a sorted copy beside them, so that its median
/// costs a look-up instead of a selection over a copy at every fix (the same value: the
/// element of rank `len / 2` in `f64::total_cmp`'s order, as [`super::window::median_of`]
/// selects it).
#[derive(Debug, Clone, Default)]
pub(super) struct Rolling<const CAP: usize> {
    fifo: VecDeque<f64>,
    sorted: Vec<f64>,
}

impl<const CAP: usize> Rolling<CAP> {
    /// Add `x`, dropping the oldest value when full.
    pub fn push(&mut self, x: f64) {
        if self.fifo.len() == CAP {
            if let Some(old) = self.fifo.pop_front() {
                let i = self.sorted.partition_point(|v| v.total_cmp(&old).is_lt());
                self.sorted.remove(i);
            }
        }
        self.fifo.push_back(x);
        let i = self.sorted.partition_point(|v| v.total_cmp(&x).is_le());
        self.sorted.insert(i, x);
    }

    /// Values in the window.
    pub fn len(&self) -> usize {
        self.fifo.len()
    }

    /// The (upper) median; NaN when empty.
    pub fn median(&self) -> f64 {
        self.sorted
            .get(self.sorted.len() / 2)
            .copied()
            .unwrap_or(f64::NAN)
    }
}

/// Components (3 per fix) the scale is estimated over.
pub const SCALE_WINDOW: usize = 180;
/// Components needed before the scale departs from 1.
pub const SCALE_MIN: usize = 30;

impl NoiseScale {
    /// An estimated scale clamped to `[lo, hi]`, or a `fixed` one.
    pub fn new(fixed: Option<f64>, lo: f64, hi: f64) -> Self {
        NoiseScale {
            d2: Rolling::default(),
            hph: Rolling::default(),
            r: Rolling::default(),
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
            self.d2.push(d2[j]);
            self.hph.push(hph[j].max(0.0));
            self.r.push(r[j]);
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
        let c2 = (self.d2.median() / 0.454_936_4 - self.hph.median()) / self.r.median();
        c2.max(self.lo * self.lo).sqrt().clamp(self.lo, self.hi)
    }
}

#[cfg(test)]
mod scale_tests {
    use super::super::window::median_of;
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

    /// The rolling window's median is the selection's over the same values, to the bit,
    /// through ties, signed zeros and the window's turnover.
    #[test]
    fn the_rolling_median_is_the_selected_one() {
        let mut w = Rolling::<7>::default();
        let mut plain = VecDeque::new();
        for k in 0..60u32 {
            let x = match k % 5 {
                0 => 0.0,
                1 => -0.0,
                _ => f64::from((k * 37) % 11) * 0.25 - 1.0,
            };
            w.push(x);
            if plain.len() == 7 {
                plain.pop_front();
            }
            plain.push_back(x);
            let mut v: Vec<f64> = plain.iter().copied().collect();
            assert_eq!(w.median().to_bits(), median_of(&mut v).to_bits(), "{k}");
            assert_eq!(w.len(), plain.len());
        }
        assert!(Rolling::<3>::default().median().is_nan());
    }
}
