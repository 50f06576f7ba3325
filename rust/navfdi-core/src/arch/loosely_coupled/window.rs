//! A slow drift of a receiver's position against its own velocity, tested over windows whose
//! noise is measured on the receiver's own record.
//!
//! The receiver consistency `e` (its displacement between fixes minus its velocity times the
//! interval, per component, m) sums over a window to the drift of its position error against
//! the integrated velocity. A Page CUSUM on `e / σ_e` treats that sum as a random walk whose
//! variance grows with the window; a receiver's position error is not one: meter-level fixes
//! carry a time-correlated (Gauss-Markov) error whose window sums saturate at twice its
//! variance, so a slow ramp (0.3–1 m/s on σ 2 m fixes) that the random-walk model hides for a
//! minute stands out of the real window noise much sooner.
//!
//! [`DriftWindow`] keeps the cumulative sum `P` of `e` (each `e` clipped at 4 σ_e, so one
//! jump — a step, which is the step test's — moves it by 4 σ_e at most) and measures its
//! structure function `σ_L² = E (P(t) − P(t − L))²` robustly: the median of `|P(t) − P(t −
//! L)|` over the last [`POOL`] windows of each length (one a second, pooled across stops and
//! gaps, so a drive that stops every minute is measured too), `/0.6745`, non-decreasing in
//! `L`, at the lags [`LAGS`] (seconds, so one set fits 1–10 Hz receivers). A drift is flagged
//! at the first fix where `|P(t) − P(t − L)| > WINDOW_Z σ_L` for a lag `L`; the lag with the
//! largest ratio is its estimated onset. A lag speaks once [`SPAN_PER_LAG`] × `L` seconds of
//! its windows are pooled (a structure function from fewer windows is too unsure to test at
//! [`WINDOW_Z`]); after a stop, windows reaching back to it are tested against the lag's σ_L
//! (shorter than `L`: conservatively).

use std::collections::VecDeque;

/// Window lengths (s) the drift is tested over.
pub const LAGS: [f64; 4] = [15.0, 30.0, 45.0, 60.0];
/// Threshold of the window test (σ_L): two-sided 5.7e-7 per lag and fix for Gaussian sums;
/// set for heavy-tailed real errors and a structure function measured from few windows.
pub const WINDOW_Z: f64 = 5.0;
/// Window sums kept per lag for the structure function: one a second at most, the last
/// [`POOL`] of them (600 s of driving at 1 Hz), across stops and gaps.
pub const POOL: usize = 600;
/// A lag `L` is tested once its pool holds `SPAN_PER_LAG · L` seconds' worth of sums (a
/// structure function from fewer windows is too unsure to test at [`WINDOW_Z`]).
pub const SPAN_PER_LAG: f64 = 6.0;
/// Seconds between two measurements of the structure function.
pub const REMEASURE: f64 = 10.0;

/// The window drift test of one position component; see the module's description.
#[derive(Debug, Clone)]
pub struct DriftWindow {
    /// Per fix since the last stop or gap, the last [`LAGS`]' longest at least: time (s) and
    /// the cumulative sums of clipped `e` and raw `e` (m), oldest first; the first sums are 0.
    cum: VecDeque<(f64, f64, f64)>,
    /// The test's windows start at this time or later (after a flag; s).
    start: f64,
    /// Per lag: `|ΣE|` of clipped `e` over past windows of that length (m), and the time of
    /// the newest (s).
    pool: [(VecDeque<f64>, f64); LAGS.len()],
    /// Seconds a pooled sum stands for: the fix interval, one second at least.
    spacing: f64,
    /// σ_L per lag of [`LAGS`] (m; NaN until measured).
    sigma: [f64; LAGS.len()],
    /// Time of the last measurement of the structure function (s).
    measured: f64,
}

impl Default for DriftWindow {
    fn default() -> Self {
        DriftWindow {
            cum: VecDeque::new(),
            start: f64::NEG_INFINITY,
            pool: std::array::from_fn(|_| (VecDeque::new(), f64::NEG_INFINITY)),
            spacing: 1.0,
            sigma: [f64::NAN; LAGS.len()],
            measured: f64::NEG_INFINITY,
        }
    }
}

/// The variance (m²) of a receiver's drift over `lag` s from its structure function
/// ([`DriftWindow::structure`]): σ_L² of the shortest measured lag at least as long, or beyond
/// the longest, its σ_L² grown in proportion to the lag (as a random walk's: the conservative
/// side); None where no lag that long is measured.
pub fn drift_var(structure: &[f64; LAGS.len()], lag: f64) -> Option<f64> {
    let last = LAGS.len() - 1;
    match LAGS.iter().position(|&l| l >= lag) {
        Some(l) => structure[l..].iter().copied().find(|v| v.is_finite()),
        None => structure[last]
            .is_finite()
            .then(|| structure[last] * lag / LAGS[last]),
    }
}

pub(super) use crate::stats::median_of;

impl DriftWindow {
    /// Forget the record (a gap, a stop: sums across it mean nothing); the pooled sums and
    /// the measured σ_L are the receiver's and are kept.
    pub fn restart(&mut self) {
        self.cum.clear();
        self.start = f64::NEG_INFINITY;
    }

    /// Start the test's windows at the newest fix (another test flagged it).
    pub fn hold_off(&mut self) {
        if let Some(&(t, _, _)) = self.cum.back() {
            self.start = t;
        }
    }

    /// The measured σ_L per lag of [`LAGS`] (m; NaN where not yet measured).
    #[cfg(test)]
    pub fn sigma(&self) -> [f64; LAGS.len()] {
        self.sigma
    }

    /// The index of the last fix at or before `t` (s), if any.
    fn at_or_before(&self, t: f64) -> Option<usize> {
        self.cum.partition_point(|x| x.0 <= t + 1e-6).checked_sub(1)
    }

    /// Add the consistency `e` (m) of the fix at `t` (s, increasing) with its robust σ_e (m);
    /// returns the drift since its estimated onset (raw `e` summed over the flagging window,
    /// m) and that window's variance σ_L² (m²) when the test flags one. A flag starts the
    /// test's windows afresh.
    pub fn add(&mut self, t: f64, e: f64, sigma_e: f64) -> Option<(f64, f64)> {
        if !(t.is_finite() && e.is_finite() && sigma_e.is_finite() && sigma_e > 0.0) {
            return None;
        }
        if self.cum.back().is_some_and(|b| t <= b.0) {
            return None;
        }
        if self.cum.is_empty() {
            // The record's origin: the previous fix (the one `e` is measured from).
            self.cum.push_back((f64::NEG_INFINITY, 0.0, 0.0));
        }
        let &(prev, c, r) = self.cum.back()?;
        if prev.is_finite() {
            self.spacing = (t - prev).max(1.0);
        }
        let clip = 4.0 * sigma_e;
        self.cum.push_back((t, c + e.clamp(-clip, clip), r + e));
        // Keep one fix at or before the longest lag.
        let longest = LAGS[LAGS.len() - 1];
        while self.cum.len() > 2 && self.cum[1].0 <= t - longest {
            self.cum.pop_front();
        }
        self.pool_windows(t);
        if t - self.measured >= REMEASURE {
            self.measured = t;
            self.measure();
        }
        self.test()
    }

    /// The structure function: σ_L² (m²) per lag of [`LAGS`], NaN where not measured.
    pub fn structure(&self) -> [f64; LAGS.len()] {
        self.sigma.map(|s| s * s)
    }

    /// The receiver's drift up to its latest fix over each window of [`LAGS`] (from a stop or
    /// gap on: shorter, against the lag's σ_L): the raw drift (m) and its size in σ_L of
    /// clipped `e`; zeros where the lag is not measured or the record is empty.
    pub fn excursions(&self) -> [(f64, f64); LAGS.len()] {
        self.drifts(f64::NEG_INFINITY)
            .map(|d| d.unwrap_or((0.0, 0.0)))
    }

    /// Per lag of [`LAGS`] whose σ_L is measured, the window up to the newest fix that begins
    /// at `since` (s) or later: the raw drift over it (m) and its size
    /// in σ_L of clipped `e` (the record's origin has no time: a window from it is shorter
    /// than the lag, sized conservatively).
    fn drifts(&self, since: f64) -> [Option<(f64, f64)>; LAGS.len()] {
        let mut out = [None; LAGS.len()];
        let Some(&(t, last_c, last_r)) = self.cum.back() else {
            return out;
        };
        for (l, &lag) in LAGS.iter().enumerate() {
            let s = self.sigma[l];
            if let Some(j) = self.at_or_before(t - lag) {
                if s.is_finite() && self.cum[j].0 >= since {
                    out[l] = Some((last_r - self.cum[j].2, (last_c - self.cum[j].1).abs() / s));
                }
            }
        }
        out
    }

    /// Pool the sums of the windows of each lag that end at the newest fix (one a second at
    /// most), when the record holds their start.
    fn pool_windows(&mut self, t: f64) {
        let Some(&(_, last, _)) = self.cum.back() else {
            return;
        };
        for (l, &lag) in LAGS.iter().enumerate() {
            if t - self.pool[l].1 < 1.0 {
                continue;
            }
            let Some(j) = self.at_or_before(t - lag) else {
                continue;
            };
            if !self.cum[j].0.is_finite() {
                continue;
            }
            let (pool, newest) = &mut self.pool[l];
            if pool.len() == POOL {
                pool.pop_front();
            }
            pool.push_back((last - self.cum[j].1).abs());
            *newest = t;
        }
    }

    /// Measure σ_L at every lag whose pool is full enough; keep the previous value elsewhere.
    fn measure(&mut self) {
        let mut diffs = Vec::with_capacity(POOL);
        let mut floor = 0.0_f64;
        for (l, &lag) in LAGS.iter().enumerate() {
            let pool = &self.pool[l].0;
            if pool.len() as f64 * self.spacing >= SPAN_PER_LAG * lag {
                diffs.clear();
                diffs.extend(pool.iter().copied());
                let s = median_of(&mut diffs) / 0.674_489_75;
                if s.is_finite() && s > 0.0 {
                    self.sigma[l] = s;
                }
            }
            // Longer windows are no quieter than shorter ones.
            if self.sigma[l].is_finite() {
                self.sigma[l] = self.sigma[l].max(floor);
                floor = self.sigma[l];
            }
        }
    }

    /// The test at the newest fix: the windows since the last flag, the largest beyond
    /// [`WINDOW_Z`].
    fn test(&mut self) -> Option<(f64, f64)> {
        let t = self.cum.back()?.0;
        let (l, x) = self
            .drifts(self.start)
            .iter()
            .enumerate()
            .filter_map(|(l, d)| d.map(|(x, z)| (l, x, z)))
            .filter(|&(_, _, z)| z > WINDOW_Z)
            .max_by(|a, b| a.2.total_cmp(&b.2))
            .map(|(l, x, _)| (l, x))?;
        self.start = t;
        Some((x, self.sigma[l] * self.sigma[l]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn the_drift_variance_reads_the_next_measured_lag_and_grows_beyond_the_longest() {
        let nan = f64::NAN;
        assert_eq!(drift_var(&[1.0, 2.0, 3.0, 4.0], 10.0), Some(1.0));
        assert_eq!(drift_var(&[1.0, 2.0, 3.0, 4.0], 15.0), Some(1.0));
        assert_eq!(drift_var(&[1.0, 2.0, 3.0, 4.0], 20.0), Some(2.0));
        assert_eq!(drift_var(&[1.0, 2.0, 3.0, 4.0], 90.0), Some(6.0));
        assert_eq!(drift_var(&[nan, 2.0, nan, 4.0], 10.0), Some(2.0));
        assert_eq!(drift_var(&[nan, 2.0, nan, 4.0], 40.0), Some(4.0));
        assert_eq!(drift_var(&[1.0, 2.0, 3.0, nan], 90.0), None);
        assert_eq!(drift_var(&[nan; 4], 10.0), None);
    }

    /// `e` of a receiver whose position error is Gauss-Markov (σ `sg`, τ `tau` s) plus
    /// white `sw`, at 1 Hz, with a ramp of `rate` m/s from `from` s.
    fn receiver_e(
        seed: u64,
        fixes: usize,
        sg: f64,
        tau: f64,
        sw: f64,
        rate: f64,
        from: usize,
    ) -> Vec<f64> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let phi = (-1.0 / tau).exp();
        let mut g = 0.0;
        let mut prev = 0.0;
        let mut out = Vec::with_capacity(fixes);
        for k in 0..fixes {
            let a: f64 = StandardNormal.sample(&mut rng);
            let b: f64 = StandardNormal.sample(&mut rng);
            g = phi * g + sg * (1.0 - phi * phi).sqrt() * a;
            let ramp = if k >= from {
                rate * (k - from) as f64
            } else {
                0.0
            };
            let p = g + sw * b + ramp;
            if k > 0 {
                out.push(p - prev);
            }
            prev = p;
        }
        out
    }

    fn sigma_e(e: &[f64]) -> f64 {
        let mut a: Vec<f64> = e.iter().map(|x| x.abs()).collect();
        median_of(&mut a) / 0.674_489_75
    }

    #[test]
    fn gauss_markov_errors_are_quiet_and_their_structure_saturates() {
        // σ 2 m, τ 30 s, 0.3 m white: 20 records of 600 s at 1 Hz, no flag; σ_45 near
        // √(2·4·(1 − e^{−1.5}) + 2·0.09) = 2.60 m, below the random walk's √45 σ_e (0.58 of it).
        let mut flags = 0;
        let mut s45 = Vec::new();
        for seed in 0..20 {
            let e = receiver_e(seed, 600, 2.0, 30.0, 0.3, 0.0, usize::MAX);
            let se = sigma_e(&e);
            let mut w = DriftWindow::default();
            flags += e
                .iter()
                .enumerate()
                .filter(|&(k, &x)| w.add(k as f64, x, se).is_some())
                .count();
            s45.push(w.sigma()[2]);
            assert!(
                w.sigma()[2] < 0.75 * 45f64.sqrt() * se,
                "{:?} {se}",
                w.sigma()
            );
        }
        assert_eq!(flags, 0);
        let m = median_of(&mut s45);
        assert!((m / 2.60 - 1.0).abs() < 0.25, "{m}");
    }

    #[test]
    fn a_slow_ramp_is_flagged_with_its_size() {
        // 0.5 m/s on σ 2 m Gauss-Markov fixes from 400 s: flagged within 40 s, the
        // drift's size within 3σ_L of the ramp's over the flagging window — and a CUSUM at
        // k 0.5 σ_e sees a drift of about 0.7 σ_e per fix for about a minute first.
        let (mut delays, mut cusum_delays) = (Vec::new(), Vec::new());
        for seed in 100..120 {
            let e = receiver_e(seed, 560, 2.0, 30.0, 0.3, 0.5, 400);
            let se = sigma_e(&e[..390]);
            let mut w = DriftWindow::default();
            let mut hit = None;
            let (mut up, mut cusum_hit) = (0.0_f64, None);
            for (k, &x) in e.iter().enumerate() {
                if let Some((d, var)) = w.add(k as f64, x, se) {
                    assert!(k + 1 >= 400, "seed {seed}: flag at {k} before the ramp");
                    hit.get_or_insert((k + 1 - 400, d, var));
                }
                // The receiver consistency's CUSUM on the same e (one side).
                up = (up + (x / se).clamp(-4.0, 4.0) - super::super::receiver::CUSUM_K).max(0.0);
                if up > super::super::receiver::CUSUM_H && k + 1 >= 400 {
                    cusum_hit.get_or_insert((k + 1 - 400) as f64);
                }
            }
            let (delay, d, var) = hit.expect("flagged");
            assert!(d > 0.0 && d.abs() > 3.0 * var.sqrt() - 1e-9, "{d} {var}");
            delays.push(delay as f64);
            cusum_delays.push(cusum_hit.unwrap_or(f64::INFINITY));
        }
        let med = median_of(&mut delays);
        let cusum = median_of(&mut cusum_delays);
        assert!(
            med <= 40.0 && cusum >= med + 10.0,
            "{delays:?} {cusum_delays:?}"
        );
    }

    #[test]
    fn one_jump_is_not_a_drift_and_restart_forgets_the_record() {
        let mut e = receiver_e(7, 500, 2.0, 30.0, 0.3, 0.0, usize::MAX);
        let se = sigma_e(&e);
        e[450] += 20.0;
        let mut w = DriftWindow::default();
        assert!(e
            .iter()
            .enumerate()
            .all(|(k, &x)| w.add(k as f64, x, se).is_none()));
        let s = w.sigma();
        w.restart();
        assert_eq!(w.sigma(), s);
        assert!(
            w.add(600.0, 1e3, se).is_none(),
            "one jump after a restart, clipped"
        );
        assert!(w.add(601.0, f64::NAN, se).is_none() && w.add(602.0, 1.0, f64::NAN).is_none());
        assert!(w.add(599.5, 1.0, se).is_none(), "time goes forward");
    }

    #[test]
    fn a_drive_that_stops_every_minute_is_measured_and_tested() {
        // The record restarts every 50 s (a stop): the pools span the stops, σ_15 and σ_30
        // are measured, and a 1 m/s ramp within one 50 s stretch is flagged.
        let e = receiver_e(11, 900, 2.0, 30.0, 0.3, 1.0, 810);
        let se = sigma_e(&e[..800]);
        let mut w = DriftWindow::default();
        let mut hit = None;
        for (k, &x) in e.iter().enumerate() {
            if k % 50 == 0 {
                w.restart();
            }
            if w.add(k as f64, x, se).is_some() {
                assert!(k + 1 >= 810, "flag at {k} before the ramp");
                hit.get_or_insert(k + 1 - 810);
            }
        }
        assert!(
            w.sigma()[0].is_finite() && w.sigma()[1].is_finite(),
            "{:?}",
            w.sigma()
        );
        assert!(hit.is_some_and(|d| d <= 30), "{hit:?}");
    }
}
