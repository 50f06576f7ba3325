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
/// [`SCALE_MIN`] samples are in. Fixes whose own noise shows their σ optimistic lift it
/// further ([`NoiseScale::set_own`]).
#[derive(Debug, Clone)]
pub struct NoiseScale {
    /// The fixes used as measured.
    used: Windows,
    /// Every tested fix (used or not), for [`NoiseScale::set_own`].
    tested: Windows,
    /// The fixes' own noise over their recorded σ ([`super::own_noise::OwnNoise::ratio`]).
    own: f64,
    /// Fixed scale (no estimation) when set.
    fixed: Option<f64>,
    lo: f64,
    hi: f64,
    /// Per solution quality of the receiver (RTKLIB's codes), a scale of its own over every
    /// tested fix of that quality ([`NoiseScale::scale_for`]).
    classes: Vec<(u8, NoiseScale)>,
    /// The best quality seen (rank of [`quality_rank`]).
    best: Option<u8>,
    /// The quality of the last fix observed, and when an RTK float fix was last used as
    /// measured and last observed (s).
    last_q: u8,
    float_used: f64,
    float_seen: f64,
}

/// Seconds after the filter last used a float fix during which a fixed one is a return from
/// it ([`NoiseScale::resolved`]).
pub const RESOLVE_MEMORY: f64 = 10.0;

/// The largest offset (m, INS − fix) a return from float fixes explains: an RTK float
/// solution is off by decimetres, rarely a metre; a larger jump at the return is a fault's.
pub const FLOAT_RETURN: f64 = 1.0;

/// Rank of a solution quality in RTKLIB's codes, best first: fixed, float, PPP, DGPS, SBAS,
/// single, then any other code; None for 0 (unknown).
pub fn quality_rank(q: u8) -> Option<u8> {
    match q {
        0 => None,
        1 => Some(0),
        2 => Some(1),
        6 => Some(2),
        4 => Some(3),
        3 => Some(4),
        5 => Some(5),
        _ => Some(6),
    }
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
/// The fixes' own noise over their recorded σ beyond which the recorded σ are taken as
/// optimistic ([`NoiseScale::set_own`]): well beyond the ratio's own scatter (a median over
/// [`super::own_noise::OWN_WINDOW`] third differences is good to about 10 %).
pub const OWN_SCALE: f64 = 1.5;

impl NoiseScale {
    /// An estimated scale clamped to `[lo, hi]`, or a `fixed` one.
    pub fn new(fixed: Option<f64>, lo: f64, hi: f64) -> Self {
        NoiseScale {
            used: Windows::default(),
            tested: Windows::default(),
            own: 1.0,
            fixed,
            lo,
            hi,
            classes: Vec::new(),
            best: None,
            last_q: 0,
            float_used: f64::NEG_INFINITY,
            float_seen: f64::NEG_INFINITY,
        }
    }

    /// The fixes' own noise over their recorded σ, `ratio`
    /// ([`super::own_noise::OwnNoise::ratio`]). Beyond [`OWN_SCALE`] the recorded σ are
    /// optimistic by the fixes' own account, and the scale is at least what every tested fix's
    /// innovations say, up to that ratio (the ratio itself until [`SCALE_MIN`] components are
    /// tested): fixes tested at a third of their noise fail, and a
    /// scale learned only from fixes used would stay at 1 while the INS runs on without them.
    /// A wrong mounting, which also makes the innovations large, leaves the ratio near 1 (its
    /// misfit is the INS's, not the fixes').
    pub fn set_own(&mut self, ratio: f64) {
        self.own = if ratio.is_finite() { ratio } else { 1.0 };
    }

    /// Whether the last fix observed, at `t` (s) and `offset` (m, |INS − fix|) from the INS,
    /// is an RTK fixed solution within [`FLOAT_RETURN`] of it, at most [`RESOLVE_MEMORY`] s
    /// after a float one at `since` (s). Only RTK: a meter-level receiver that alternates DGPS
    /// and single fixes jumps by as much as a fault would.
    fn after_float(&self, t: f64, offset: f64, since: f64) -> bool {
        self.last_q == 1 && offset <= FLOAT_RETURN && t - since <= RESOLVE_MEMORY
    }

    /// [`NoiseScale::after_float`] a float fix observed (used or not): a ramp held through a
    /// float stretch ends there.
    pub fn float_ended(&self, t: f64, offset: f64) -> bool {
        self.after_float(t, offset, self.float_seen)
    }

    /// [`NoiseScale::after_float`] a float fix used as measured: the receiver's return to its
    /// fixed solution after the filter followed float ones (a jump of it is that return, not
    /// a fault's onset: [`super::diverge::Outlast`]).
    pub fn resolved(&self, t: f64, offset: f64) -> bool {
        self.after_float(t, offset, self.float_used)
    }

    /// A fix used as measured at `t` (s), the last one observed: its innovation `r` (m), the
    /// innovation covariance `s` of its test and its measurement covariance `r_meas` at
    /// `scale` (m²; `inn` = (r, s)), learned by this scale.
    pub fn used(
        &mut self,
        t: f64,
        inn: &(nalgebra::DVector<f64>, nalgebra::DMatrix<f64>),
        r_meas: &nalgebra::DMatrix<f64>,
        scale: f64,
    ) {
        self.add_innovation(inn, r_meas, scale);
        if self.last_q == 2 && self.best == quality_rank(1) {
            self.float_used = t;
        }
    }

    /// [`NoiseScale::add`] from an innovation `r` (m) with the covariance `s` of its test and
    /// the measurement covariance `r_meas` at `scale` (m²; `inn` = (r, s)).
    fn add_innovation(
        &mut self,
        inn: &(nalgebra::DVector<f64>, nalgebra::DMatrix<f64>),
        r_meas: &nalgebra::DMatrix<f64>,
        scale: f64,
    ) {
        if self.fixed.is_none() {
            self.used.add_innovation(inn, r_meas, scale);
        }
    }

    /// The scale for a fix of solution quality `q` (RTKLIB's codes; 0 unknown): this scale for
    /// the best quality the receiver has given (and where unknown, or fixed by the user); for a
    /// worse one, that quality's own once it has [`SCALE_MIN`] components. A receiver's σ are
    /// not equally honest across its solution types — RTKLIB's float σ are often a tenth of
    /// the float solution's error while its fixed σ fit — and one scale over a window of
    /// mostly fixed solutions leaves the float ones' σ as optimistic as stated.
    pub fn scale_for(&self, q: u8) -> f64 {
        let rank = quality_rank(q);
        if self.fixed.is_some() || rank.is_none() || rank <= self.best {
            return self.scale();
        }
        match self.classes.iter().find(|c| c.0 == q) {
            Some((_, c)) if c.used.d2.len() >= SCALE_MIN => c.scale(),
            _ => self.scale(),
        }
    }

    /// A tested fix of quality `q` at `t` (s; `fix` = (q, t); used or not): its innovation `r`
    /// (m) and the innovation covariance `s` of its test (m²; `inn` = (r, s), None: not
    /// tested) and its measurement covariance `r_meas` at `scale` (m²), for that quality's own
    /// scale; the best quality seen is updated.
    pub fn observe(
        &mut self,
        fix: (u8, f64),
        inn: Option<&(nalgebra::DVector<f64>, nalgebra::DMatrix<f64>)>,
        r_meas: &nalgebra::DMatrix<f64>,
        scale: f64,
    ) {
        let q = fix.0;
        self.last_q = q;
        if q == 2 {
            self.float_seen = fix.1;
        }
        let Some(inn) = inn else {
            return;
        };
        if self.fixed.is_none() {
            self.tested.add_innovation(inn, r_meas, scale);
        }
        let Some(rank) = quality_rank(q) else {
            return;
        };
        self.best = Some(self.best.map_or(rank, |b| b.min(rank)));
        let i = match self.classes.iter().position(|c| c.0 == q) {
            Some(i) => i,
            None => {
                self.classes
                    .push((q, NoiseScale::new(self.fixed, self.lo, self.hi)));
                self.classes.len() - 1
            }
        };
        self.classes[i].1.add_innovation(inn, r_meas, scale);
    }

    /// Add a fix used as measured: its components' squared innovations `d²`, predicted
    /// variances `HPHᵀ` and measurement variances `R` (unscaled).
    #[cfg(test)]
    pub fn add(&mut self, d2: &[f64], hph: &[f64], r: &[f64]) {
        if self.fixed.is_none() {
            self.used.add(d2, hph, r);
        }
    }

    /// The current scale `c` (of σ).
    pub fn scale(&self) -> f64 {
        if let Some(f) = self.fixed {
            return f;
        }
        let used = self.used.scale(self.lo, self.hi);
        if self.own <= OWN_SCALE {
            used
        } else if self.tested.d2.len() < SCALE_MIN {
            used.max(self.own.clamp(self.lo, self.hi))
        } else {
            used.max(self.tested.scale(self.lo, self.hi).min(self.own))
        }
    }
}

/// Windows of the last [`SCALE_WINDOW`] components' squared innovations, predicted variances
/// `HPHᵀ` and measurement variances `R` (unscaled).
#[derive(Debug, Clone, Default)]
struct Windows {
    d2: Rolling<SCALE_WINDOW>,
    hph: Rolling<SCALE_WINDOW>,
    r: Rolling<SCALE_WINDOW>,
}

impl Windows {
    /// Add components (finite, R > 0).
    fn add(&mut self, d2: &[f64], hph: &[f64], r: &[f64]) {
        for j in 0..d2.len().min(hph.len()).min(r.len()) {
            if !(d2[j].is_finite() && hph[j].is_finite() && r[j] > 0.0) {
                continue;
            }
            self.d2.push(d2[j]);
            self.hph.push(hph[j].max(0.0));
            self.r.push(r[j]);
        }
    }

    /// Add an innovation `r` (m) with the covariance `s` of its test and the measurement
    /// covariance `r_meas` at `scale` (m²; `inn` = (r, s)).
    fn add_innovation(
        &mut self,
        inn: &(nalgebra::DVector<f64>, nalgebra::DMatrix<f64>),
        r_meas: &nalgebra::DMatrix<f64>,
        scale: f64,
    ) {
        let (r, s) = inn;
        let c2 = scale * scale;
        let n = r.len();
        let d2: Vec<f64> = (0..n).map(|i| r[i] * r[i]).collect();
        let hph: Vec<f64> = (0..n).map(|i| s[(i, i)] - r_meas[(i, i)]).collect();
        let rr: Vec<f64> = (0..n).map(|i| r_meas[(i, i)] / c2).collect();
        self.add(&d2, &hph, &rr);
    }

    /// `c = √((med(d²)/0.4549 − med(HPHᵀ)) / med(R))` clamped to `[lo, hi]`; 1 below
    /// [`SCALE_MIN`] components.
    fn scale(&self, lo: f64, hi: f64) -> f64 {
        if self.d2.len() < SCALE_MIN {
            return 1.0;
        }
        let c2 = (self.d2.median() / 0.454_936_4 - self.hph.median()) / self.r.median();
        c2.max(lo * lo).sqrt().clamp(lo, hi)
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

    /// A worse solution quality gets its own scale once it has enough components; the best
    /// quality seen, an unknown one and a fixed scale keep the channel's.
    #[test]
    fn a_worse_solution_quality_learns_its_own_scale() {
        use nalgebra::{DMatrix, DVector};
        let mut s = NoiseScale::new(None, 1.0, 10.0);
        // Fixed solutions (1) that fit their σ (1 cm; innovations 1 cm at HPHᵀ ≈ 0).
        let r_meas = DMatrix::from_diagonal_element(3, 3, 1e-4);
        let fixed = (DVector::from_element(3, 0.01), &r_meas * 1.0001);
        for _ in 0..40 {
            s.observe((1, 0.0), Some(&fixed), &r_meas, 1.0);
            s.add(&[1e-4; 3], &[1e-8; 3], &[1e-4; 3]);
        }
        let channel = s.scale();
        // Float solutions (2) 0.3 m off at the same stated σ.
        let float = (DVector::from_element(3, 0.3), &r_meas * 1.0001);
        for k in 0..SCALE_MIN / 3 {
            // Below SCALE_MIN components the channel's scale.
            assert_eq!(s.scale_for(2), channel, "after {k} float fixes");
            s.observe((2, 0.0), Some(&float), &r_meas, 1.0);
        }
        assert_eq!(s.scale_for(2), 10.0); // 30 σ, clamped at hi
        assert_eq!(s.scale_for(1), channel);
        assert_eq!(s.scale_for(0), channel);
        // A fixed scale is the user's for every quality.
        let mut f = NoiseScale::new(Some(2.0), 1.0, 10.0);
        for _ in 0..20 {
            f.observe((2, 0.0), Some(&float), &r_meas, 2.0);
        }
        assert_eq!(f.scale_for(2), 2.0);
        // Float first, fixed later: once fixed solutions are seen, float is the worse one.
        let mut g = NoiseScale::new(None, 1.0, 10.0);
        for _ in 0..12 {
            g.observe((2, 0.0), Some(&float), &r_meas, 1.0);
        }
        assert_eq!(g.scale_for(2), g.scale());
        g.observe((1, 0.0), Some(&fixed), &r_meas, 1.0);
        assert_eq!(g.scale_for(2), 10.0);
        // A fixed fix within RESOLVE_MEMORY s of a float fix used, within FLOAT_RETURN of the
        // INS, is the return from it.
        g.observe((2, 0.0), Some(&float), &r_meas, 1.0);
        g.used(100.0, &float, &r_meas, 1.0);
        g.observe((1, 0.0), Some(&fixed), &r_meas, 1.0);
        assert!(g.resolved(105.0, 0.5) && !g.resolved(100.0 + RESOLVE_MEMORY + 0.5, 0.5));
        assert!(
            !g.resolved(105.0, FLOAT_RETURN + 0.1),
            "a jump beyond a float error"
        );
        g.observe((2, 0.0), Some(&float), &r_meas, 1.0);
        assert!(!g.resolved(101.0, 0.5), "a float fix is no return");
        // A float fix seen but not used does not count.
        let mut h = NoiseScale::new(None, 1.0, 10.0);
        h.observe((1, 0.0), Some(&fixed), &r_meas, 1.0);
        h.observe((2, 0.0), Some(&float), &r_meas, 1.0);
        h.observe((1, 0.0), Some(&fixed), &r_meas, 1.0);
        assert!(!h.resolved(1.0, 0.5));
        // Meter-level qualities (single after DGPS) are no RTK return.
        let mut m = NoiseScale::new(None, 1.0, 10.0);
        m.observe((4, 0.0), Some(&fixed), &r_meas, 1.0);
        m.observe((5, 0.0), Some(&float), &r_meas, 1.0);
        m.used(10.0, &float, &r_meas, 1.0);
        m.observe((4, 0.0), Some(&fixed), &r_meas, 1.0);
        assert!(!m.resolved(11.0, 0.5));
        assert_eq!(
            [1, 2, 6, 4, 3, 5, 9].map(quality_rank),
            [0, 1, 2, 3, 4, 5, 6].map(Some)
        );
        assert_eq!(quality_rank(0), None);
        // A fixed fix within RESOLVE_MEMORY s of a float one seen (used or not) ends a float
        // stretch, within FLOAT_RETURN.
        let mut e = NoiseScale::new(None, 1.0, 10.0);
        e.observe((1, 0.0), Some(&fixed), &r_meas, 1.0);
        e.observe((2, 50.0), Some(&float), &r_meas, 1.0);
        e.observe((1, 51.0), Some(&fixed), &r_meas, 1.0);
        assert!(e.float_ended(51.0, 0.8) && !e.float_ended(51.0, 1.2));
        assert!(!e.float_ended(50.0 + RESOLVE_MEMORY + 1.0, 0.8));
    }

    /// The fixes' own noise beyond [`OWN_SCALE`] times their σ lifts the scale to what every
    /// tested fix says, up to that ratio (the ratio alone before enough are tested); within
    /// it, the scale is the used fixes' alone.
    #[test]
    fn optimistic_fixes_by_their_own_account_lift_the_scale() {
        use nalgebra::{DMatrix, DVector};
        // Innovations of 3 σ at a stated R of 1 m² and HPHᵀ ≈ 0: the tested fixes say 3.
        let r_meas = DMatrix::from_diagonal_element(3, 3, 1.0);
        let inn = (
            DVector::from_element(3, 3.0 * 0.454_936_4f64.sqrt()),
            &r_meas * 1.0,
        );
        let mut s = NoiseScale::new(None, 1.0, 10.0);
        s.set_own(2.5);
        assert_eq!(s.scale(), 2.5, "the ratio alone before any fix is tested");
        for _ in 0..SCALE_MIN / 3 {
            s.observe((5, 0.0), Some(&inn), &r_meas, 1.0);
        }
        assert_eq!(s.scale(), 2.5, "capped at the ratio");
        s.set_own(4.0);
        assert!((s.scale() - 3.0).abs() < 1e-9, "{}", s.scale());
        s.set_own(OWN_SCALE);
        assert_eq!(s.scale(), 1.0, "within OWN_SCALE: the used fixes' scale");
        s.set_own(f64::NAN);
        assert_eq!(s.scale(), 1.0);
        // A user's fixed scale stays.
        let mut f = NoiseScale::new(Some(1.5), 1.0, 10.0);
        f.set_own(4.0);
        f.observe((5, 0.0), Some(&inn), &r_meas, 1.0);
        assert_eq!(f.scale(), 1.5);
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
