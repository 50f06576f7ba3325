//! Filter protection levels by solution separation (Brenner 1996, "Integrated GPS/inertial
//! fault detection availability"; the ARAIM ADD's protection-level equation).
//!
//! Beside the tight filter (state `x₀`, covariance `P₀`) runs a bank of sub-filters, one per
//! satellite `s` in view, each updated with every observation the filter uses but those of
//! `s`. A sub-filter is born as a copy of the filter (after its prediction) at the first epoch
//! its satellite is in view, so it is the optimal estimate on a subset of the filter's data
//! and the separation `Δ_s = x_s − x₀` has covariance `P_s − P₀` exactly (Brenner's
//! result for Kalman filters on nested data). Per axis q (east, north, up of the position
//! error states):
//!
//! * `σ_ss,s,q² = P_s,qq − P₀,qq`, threshold `T_s,q = K_fa,q σ_ss,s,q` with the ADD's
//!   `K_fa` for N modes (`Q⁻¹(P_FA,H/4N)` horizontal, `Q⁻¹(P_FA,V/2N)` vertical);
//! * test: alarm when some `|Δ_s,q| > T_s,q` (statistic `max |Δ_s,q| / T_s,q`, threshold
//!   1); modes with `σ_ss < 0.1 mm` (a sub-filter that has not yet separated) are not tested;
//! * protection levels: the ADD's equation with the fault-free term `2Q(L/σ₀)` and one term
//!   `P_sat Q((L − T_s)/σ_s)` per sub-filter, no nominal bias (the simulated errors have
//!   none), the budgets scaled by the probability of two or more simultaneous satellite
//!   faults, which the bank does not monitor (`super::araim::protection_levels`).
//!
//! Exclusion (placement `separation`): on an alarm the satellite whose whole-state separation
//! is least likely under its covariance ([`SeparationBank::identify`]) is excluded, provided
//! the runner-up is at least [`AMBIGUITY`] times more likely (otherwise the alarm stands and
//! nothing is excluded: excluding a good satellite whose geometry resembles the faulty one's
//! restarts the bank from a contaminated state, which a slow ramp then walks past the levels).
//! The filter takes that sub-filter's state, the other sub-filters restart as copies of it
//! (they then protect against faults from that epoch on), and the satellite updates nothing
//! until its own innovation (both rows, against the filter) has stayed within
//! `Q⁻¹(P_FA,V/2)` σ for [`READMIT_EPOCHS`] epochs in a row;
//! it then rejoins with a new sub-filter. A sub-filter is dropped when its satellite leaves
//! view (its past contribution is no longer monitored: stated, not modelled).

use super::araim::{k_fa, protection_levels, Allocation, ModeTerm};
use crate::error::Result;
use crate::ins::{earth, POS};
use crate::kalman::{KalmanFilter, Sequential};
use nalgebra::{DMatrix, DVector};

/// Consecutive consistent epochs after which an excluded satellite rejoins.
pub const READMIT_EPOCHS: u32 = 10;

/// How much less likely (ratio of the χ² tails) the best exclusion candidate's separation
/// must be than the runner-up's for [`SeparationBank::identify`] to name it.
pub const AMBIGUITY: f64 = 100.0;

/// Smallest separation σ (m) a mode needs to be tested.
const MIN_SIGMA_SS: f64 = 1e-4;

/// One epoch's filter integrity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsEpoch {
    /// Vertical protection level (m).
    pub vpl: f64,
    /// Horizontal protection level (m).
    pub hpl: f64,
    /// `max |Δ_s,q| / T_s,q` over the tested modes (NaN when none is tested).
    pub statistic: f64,
    /// Some separation exceeds its threshold.
    pub alarm: bool,
    /// Satellite (index into the stream's names) of the largest normalised separation.
    pub worst: Option<usize>,
    /// Sub-filters (monitored fault modes).
    pub modes: usize,
    /// Probability of two or more simultaneous satellite faults (not monitored).
    pub p_unmonitored: f64,
}

/// One sub-filter's position statistics for [`separation_levels`], east, north, up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsMode {
    /// The satellite it leaves out (index into the stream's names).
    pub satellite: usize,
    /// Its position error variances (m²).
    pub var: [f64; 3],
    /// Its separation from the filter, `x_s − x₀` (m).
    pub separation: [f64; 3],
}

/// The separation test and the protection levels of a filter with position error variances
/// `var0` (m², east, north, up) and sub-filters `modes`, each the optimal estimate on a subset
/// of the filter's data (so `σ_ss² = var_s − var0`), for a satellite prior `p_sat` and the
/// allocation `alloc` (see the module docs).
pub fn separation_levels(
    var0: [f64; 3],
    modes: &[SsMode],
    p_sat: f64,
    alloc: &Allocation,
) -> SsEpoch {
    let n_modes = modes.len();
    let kfa = k_fa(n_modes, alloc);
    let mut terms = Vec::with_capacity(n_modes);
    let (mut stat, mut worst) = (f64::NAN, None);
    for m in modes {
        let mut shift = [0.0; 3];
        let mut sigma = [0.0; 3];
        for q in 0..3 {
            sigma[q] = m.var[q].max(0.0).sqrt();
            let ss = (m.var[q] - var0[q]).max(0.0).sqrt();
            shift[q] = kfa[q] * ss;
            if ss > MIN_SIGMA_SS {
                let ratio = m.separation[q].abs() / shift[q];
                if !(ratio <= stat) {
                    stat = ratio;
                    worst = Some(m.satellite);
                }
            }
        }
        terms.push(ModeTerm {
            prior: p_sat,
            shift,
            sigma,
        });
    }
    let nf = n_modes as f64;
    // P(two or more of N independent faults), from the complement.
    let p_unmonitored = if n_modes < 2 {
        0.0
    } else {
        let none = (nf * (-p_sat).ln_1p()).exp();
        let one = nf * p_sat * ((nf - 1.0) * (-p_sat).ln_1p()).exp();
        (1.0 - none - one).max(0.0)
    };
    let sigma0 = var0.map(|v| v.max(0.0).sqrt());
    let (vpl, hpl) = protection_levels(sigma0, [0.0; 3], &terms, p_unmonitored, alloc);
    SsEpoch {
        vpl,
        hpl,
        statistic: stat,
        alarm: stat > 1.0,
        worst,
        modes: n_modes,
        p_unmonitored,
    }
}

/// The bank of sub-filters of one run (see the module docs).
#[derive(Debug, Clone)]
pub struct SeparationBank {
    subs: Vec<Option<KalmanFilter>>,
    excluded: Vec<bool>,
    consistent: Vec<u32>,
    p_sat: f64,
    alloc: Allocation,
    seq: Sequential,
    zbuf: DVector<f64>,
}

impl SeparationBank {
    /// A bank for `satellites` satellites (the stream's names), filters of `n` states, the
    /// prior `p_sat` of a fault of each satellite per epoch and the allocation `alloc`.
    pub fn new(satellites: usize, n: usize, p_sat: f64, alloc: Allocation) -> Self {
        SeparationBank {
            subs: vec![None; satellites],
            excluded: vec![false; satellites],
            consistent: vec![0; satellites],
            p_sat,
            alloc,
            seq: Sequential::new(n),
            zbuf: DVector::zeros(0),
        }
    }

    /// The satellite prior and the allocation the bank uses.
    pub fn allocation_spec(&self) -> (f64, Allocation) {
        (self.p_sat, self.alloc)
    }

    /// Whether satellite `s` is excluded (placement `separation`).
    pub fn is_excluded(&self, s: usize) -> bool {
        self.excluded[s]
    }

    /// Predict every sub-filter with the filter's Φ and Q.
    pub fn predict(&mut self, phi: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<()> {
        for f in self.subs.iter_mut().flatten() {
            f.predict_trusted(phi, q, 1.0)?;
        }
        Ok(())
    }

    /// Match the bank to the satellites in view `sats`, with `main` the filter after its
    /// prediction and before its update: a sub-filter (a copy of `main`) for each satellite
    /// in view without one and not excluded; none for satellites out of view.
    pub fn sync_view(&mut self, main: &KalmanFilter, sats: &[usize]) {
        for s in 0..self.subs.len() {
            let in_view = sats.contains(&s);
            if !in_view {
                self.subs[s] = None;
                self.consistent[s] = 0;
            } else if self.subs[s].is_none() && !self.excluded[s] {
                self.subs[s] = Some(main.clone());
            }
        }
    }

    /// Update each sub-filter with the rows of `z`/`h` (m pseudoranges, then m rates when
    /// `z` has 2m rows; `r_diag` their variances) of the satellites `used[j]` the filter
    /// used, but those of its own satellite; `sats[j]` maps local to stream satellites.
    pub fn update(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
        sats: &[usize],
        used: &[bool],
    ) -> Result<()> {
        let m = sats.len();
        let rows = z.len();
        for (j, &s) in sats.iter().enumerate() {
            let Some(f) = self.subs[s].as_mut() else {
                continue;
            };
            self.zbuf.clone_from(z);
            for (i, &u) in used.iter().enumerate() {
                if !u || i == j {
                    self.zbuf[i] = f64::NAN;
                    if rows > m {
                        self.zbuf[m + i] = f64::NAN;
                    }
                }
            }
            f.sequential_pending(&self.zbuf, h, r_diag, &mut self.seq)?;
            f.commit_sequential(&mut self.seq)?;
        }
        Ok(())
    }

    /// Protection levels and separation test of the filter `main` (after its update) at
    /// latitude `lat` (rad) and height `height` (m).
    pub fn levels(&self, main: &KalmanFilter, lat: f64, height: f64) -> SsEpoch {
        let scale = enu_scale(lat, height);
        let p0 = main.p();
        let x0 = main.x();
        let var0: [f64; 3] = [0, 1, 2].map(|q| p0[(idx(q), idx(q))].max(0.0) * scale[q] * scale[q]);
        let modes: Vec<SsMode> = self
            .subs
            .iter()
            .enumerate()
            .filter_map(|(s, f)| {
                let f = f.as_ref()?;
                let (ps, xs) = (f.p(), f.x());
                Some(SsMode {
                    satellite: s,
                    var: [0, 1, 2].map(|q| ps[(idx(q), idx(q))].max(0.0) * scale[q] * scale[q]),
                    separation: [0, 1, 2].map(|q| (xs[idx(q)] - x0[idx(q)]) * scale[q]),
                })
            })
            .collect();
        separation_levels(var0, &modes, self.p_sat, &self.alloc)
    }

    /// The satellite to exclude on an alarm: the sub-filter whose whole-state separation
    /// `Δ_s = x_s − x₀` is least likely under its covariance `P_s − P₀` (the χ² tail of
    /// `Δ_sᵀ (P_s − P₀)⁺ Δ_s` with the pseudo-inverse's rank as degrees of freedom). The
    /// position axes alone (the test's statistic) mistake a satellite whose geometry resembles
    /// the faulty one's for it under slow ramps; the whole state (velocity, attitude, clock)
    /// separates them. None when no sub-filter has separated, or when the runner-up's
    /// separation is within [`AMBIGUITY`] of the best (likelihood ratio of the two tails):
    /// then two satellites explain the alarm about equally, an exclusion would as likely
    /// remove a good one (and the restarted bank would no longer see the fault), and the
    /// alarm stands without an exclusion (the ADD's answer to an exclusion it cannot
    /// validate).
    pub fn identify(&self, main: &KalmanFilter) -> Option<usize> {
        let (x0, p0) = (main.x(), main.p());
        let scores = self.subs.iter().enumerate().filter_map(|(s, f)| {
            let f = f.as_ref()?;
            separation_score(&(f.x() - x0), &(f.p() - p0)).map(|v| (v, s))
        });
        most_separated(scores.collect())
    }

    /// Exclude satellite `s`: `main` takes its sub-filter's state, the other sub-filters
    /// restart as copies of it. False (nothing changed) when `s` has no sub-filter.
    pub fn exclude(&mut self, main: &mut KalmanFilter, s: usize) -> Result<bool> {
        let Some(f) = self.subs[s].take() else {
            return Ok(false);
        };
        main.set_state(f.x().clone(), f.p().clone())?;
        self.excluded[s] = true;
        self.consistent[s] = 0;
        for g in self.subs.iter_mut().flatten() {
            *g = main.clone();
        }
        Ok(true)
    }

    /// After the filter's update: count the epochs in a row that each excluded satellite in
    /// view (`sats[j]`, rows of `z`/`h`, variances `r_diag`) stays consistent with the filter
    /// `main` (every row's innovation within `Q⁻¹(P_FA,V/2)` σ), and readmit it (a new
    /// sub-filter, a copy of `main`) after [`READMIT_EPOCHS`]. Returns the readmitted ones.
    pub fn readmit(
        &mut self,
        main: &KalmanFilter,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
        sats: &[usize],
    ) -> Vec<usize> {
        let m = sats.len();
        let rows = z.len();
        let gate = k_fa(1, &self.alloc)[2].max(3.0);
        let (x, p) = (main.x(), main.p());
        let mut back = Vec::new();
        for (j, &s) in sats.iter().enumerate() {
            if !self.excluded[s] {
                continue;
            }
            let ok = (0..rows / m.max(1)).all(|b| {
                let i = b * m + j;
                let hr = h.row(i);
                let nu = z[i] - (hr * x)[0];
                let var = (hr * p * hr.transpose())[0] + r_diag[i];
                var > 0.0 && nu.abs() <= gate * var.sqrt()
            });
            self.consistent[s] = if ok { self.consistent[s] + 1 } else { 0 };
            if self.consistent[s] >= READMIT_EPOCHS {
                self.excluded[s] = false;
                self.consistent[s] = 0;
                self.subs[s] = Some(main.clone());
                back.push(s);
            }
        }
        back
    }
}

/// How far a sub-filter has separated: the log of the χ² tail of the separation `d` normalised
/// by its covariance `c` (`P_s − P₀`, symmetrised; its rank the eigenvalues above 1e-9 of the
/// largest) — comparable across ranks and finite far in the tail (`d' c⁻¹ d` where the tail
/// underflows). None when `c` has no positive eigenvalue.
pub fn separation_score(d: &DVector<f64>, c: &DMatrix<f64>) -> Option<f64> {
    let c = (c + c.transpose()) * 0.5;
    let eig = c.symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    if !(top > 0.0) {
        return None;
    }
    let (mut m2, mut rank) = (0.0, 0usize);
    for (j, &l) in eig.eigenvalues.iter().enumerate() {
        if l > 1e-9 * top {
            let proj = eig.eigenvectors.column(j).dot(d);
            m2 += proj * proj / l;
            rank += 1;
        }
    }
    if rank == 0 {
        return None;
    }
    let tail = crate::stats::chi2_sf(rank, m2);
    Some(if tail > 0.0 { -tail.ln() } else { m2 })
}

/// The satellite of the highest [`separation_score`] among `(score, satellite)`, if the
/// runner-up is at least [`AMBIGUITY`] times less likely; None otherwise.
pub fn most_separated(mut scores: Vec<(f64, usize)>) -> Option<usize> {
    scores.sort_by(|a, b| b.0.total_cmp(&a.0));
    match scores.as_slice() {
        [] => None,
        [(_, s)] => Some(*s),
        [(a, s), (b, _), ..] => (a - b >= AMBIGUITY.ln()).then_some(*s),
    }
}

/// State index of position axis q (east: longitude, north: latitude, up: height).
fn idx(q: usize) -> usize {
    [POS + 1, POS, POS + 2][q]
}

/// Metres per unit of the position error states east (longitude), north (latitude), up.
fn enu_scale(lat: f64, h: f64) -> [f64; 3] {
    let rm = earth::r_meridian(lat) + h;
    let rn = earth::r_normal(lat) + h;
    [rn * lat.cos(), rm, 1.0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// A 3-state filter whose "position" is the only state: east, north, up of a static
    /// point measured directly by `m` sensors (each observes one axis, or all of them mixed).
    fn bank_setup() -> (KalmanFilter, SeparationBank, DMatrix<f64>) {
        // 15 states as the INS error model has them; only the position ones matter here.
        let n = crate::ins::N_STATES;
        let mut p0 = DMatrix::identity(n, n);
        let s = enu_scale(0.0, 0.0);
        for q in 0..3 {
            p0[(idx(q), idx(q))] = 100.0 / (s[q] * s[q]);
        }
        let kf = KalmanFilter::new(DVector::zeros(n), p0).unwrap();
        let bank = SeparationBank::new(6, n, 1e-5, Allocation::lpv200());
        // Six "satellites": rows of mixed position sensitivities (m per state unit).
        let dirs = [
            [0.3, 0.2, 0.93],
            [-0.5, 0.4, 0.77],
            [0.6, -0.6, 0.53],
            [-0.2, -0.7, 0.68],
            [0.8, 0.1, 0.59],
            [-0.7, -0.1, 0.71],
        ];
        let mut h = DMatrix::zeros(6, n);
        for (j, d) in dirs.iter().enumerate() {
            for q in 0..3 {
                h[(j, idx(q))] = d[q] * s[q];
            }
        }
        (kf, bank, h)
    }

    #[test]
    fn separation_covariance_is_the_difference_and_a_fault_is_isolated() {
        let (mut kf, mut bank, h) = bank_setup();
        let sats: Vec<usize> = (0..6).collect();
        let r_diag = vec![1.0; 6];
        let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
        let phi = DMatrix::identity(kf.dim(), kf.dim());
        let q = DMatrix::zeros(kf.dim(), kf.dim());
        let used = vec![true; 6];
        // Fault-free epochs: measurements with small deterministic errors.
        for k in 0..5 {
            kf.predict_trusted(&phi, &q, 1.0).unwrap();
            bank.predict(&phi, &q).unwrap();
            bank.sync_view(&kf, &sats);
            let z = DVector::from_fn(6, |j, _| 0.3 * (((j + k) % 3) as f64 - 1.0));
            kf.update_trusted(&z, &h, &r).unwrap();
            bank.update(&z, &h, &r_diag, &sats, &used).unwrap();
            let lv = bank.levels(&kf, 0.0, 0.0);
            assert!(
                !lv.alarm,
                "fault-free epoch {k}: statistic {}",
                lv.statistic
            );
            assert_eq!(lv.modes, 6);
            assert!(lv.vpl.is_finite() && lv.hpl.is_finite() && lv.vpl > 0.0);
        }
        // The PL bounds the fault-free σ from above and is not absurd.
        let lv = bank.levels(&kf, 0.0, 0.0);
        let sigma_u = kf.p()[(idx(2), idx(2))].sqrt();
        assert!(
            lv.vpl > 5.0 * sigma_u && lv.vpl < 200.0 * sigma_u,
            "{} vs σ {sigma_u}",
            lv.vpl
        );
        // A 40 m bias on satellite 2: the test alarms and names it; excluding it returns the
        // filter to the sub-filter that never saw it.
        kf.predict_trusted(&phi, &q, 1.0).unwrap();
        bank.predict(&phi, &q).unwrap();
        bank.sync_view(&kf, &sats);
        let mut z = DVector::zeros(6);
        z[2] = 40.0;
        kf.update_trusted(&z, &h, &r).unwrap();
        bank.update(&z, &h, &r_diag, &sats, &used).unwrap();
        let lv = bank.levels(&kf, 0.0, 0.0);
        assert!(lv.alarm && lv.worst == Some(2), "{lv:?}");
        assert_eq!(bank.identify(&kf), Some(2));
        let before = kf.x().clone();
        assert!(bank.exclude(&mut kf, 2).unwrap());
        assert!(bank.is_excluded(2));
        assert!((kf.x() - before).norm() > 0.0);
        let after = bank.levels(&kf, 0.0, 0.0);
        assert_eq!(after.modes, 5);
        assert!(!after.alarm);
        // Satellite 2 consistent again: readmitted after READMIT_EPOCHS epochs.
        let used2: Vec<bool> = (0..6).map(|j| j != 2).collect();
        let z0 = DVector::zeros(6);
        let mut back = Vec::new();
        for _ in 0..READMIT_EPOCHS {
            assert!(back.is_empty());
            kf.predict_trusted(&phi, &q, 1.0).unwrap();
            bank.predict(&phi, &q).unwrap();
            bank.sync_view(&kf, &sats);
            crate::gnss::innovation::update_without(&mut kf, &z0, &h, &r, 6, &[2], None).unwrap();
            bank.update(&z0, &h, &r_diag, &sats, &used2).unwrap();
            back = bank.readmit(&kf, &z0, &h, &r_diag, &sats);
        }
        assert_eq!(back, vec![2]);
        assert!(!bank.is_excluded(2));
    }

    #[test]
    fn two_satellites_that_explain_an_alarm_equally_are_not_excluded() {
        // Only satellites 0 and 1 see the height (the others east and north only): a bias on
        // either moves the solution the same way, so the alarm names neither; a third
        // satellite seeing the height names the biased one.
        let n = crate::ins::N_STATES;
        let sc = enu_scale(0.0, 0.0);
        let mut p0 = DMatrix::identity(n, n);
        for q in 0..3 {
            p0[(idx(q), idx(q))] = 1e4 / (sc[q] * sc[q]);
        }
        let dirs = [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.7, 0.7, 0.0],
            [-0.7, 0.7, 0.0],
        ];
        let run = |third: bool| {
            let mut h = DMatrix::zeros(6, n);
            for (j, d) in dirs.iter().enumerate() {
                for q in 0..3 {
                    h[(j, idx(q))] = d[q] * sc[q];
                }
            }
            if third {
                h[(5, idx(2))] = 0.7 * sc[2];
            }
            let mut kf = KalmanFilter::new(DVector::zeros(n), p0.clone()).unwrap();
            let mut bank = SeparationBank::new(6, n, 1e-5, Allocation::lpv200());
            let sats: Vec<usize> = (0..6).collect();
            let r_diag = vec![1.0; 6];
            let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
            bank.sync_view(&kf, &sats);
            let mut z = DVector::zeros(6);
            z[0] = 12.0;
            kf.update_trusted(&z, &h, &r).unwrap();
            bank.update(&z, &h, &r_diag, &sats, &[true; 6]).unwrap();
            let lv = bank.levels(&kf, 0.0, 0.0);
            assert!(lv.alarm, "{lv:?}");
            bank.identify(&kf)
        };
        assert_eq!(run(false), None);
        assert_eq!(run(true), Some(0));
    }

    #[test]
    fn the_sub_filter_separation_variance_is_exact_on_nested_data() {
        // Brenner's identity cov(x_s − x₀) = P_s − P₀, checked by the sample covariance of
        // the separation over random measurement draws (deterministic generator).
        let (kf0, mut bank0, h) = bank_setup();
        let sats: Vec<usize> = (0..6).collect();
        let r_diag = vec![4.0; 6];
        let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
        let used = vec![true; 6];
        let mut rng = 12345u64;
        let mut gauss = move || {
            // Box–Muller on a 64-bit LCG: enough for a sample-covariance check.
            let mut u = || {
                rng = rng
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((rng >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        let trials = 4000;
        let mut sum2 = 0.0;
        let mut predicted = 0.0;
        for _ in 0..trials {
            let mut kf = kf0.clone();
            let mut bank = bank0.clone();
            bank.sync_view(&kf, &sats);
            // Truth: a random position drawn from P0; measurements with noise R.
            let truth = DVector::from_fn(kf.dim(), |i, _| kf0.p()[(i, i)].sqrt() * gauss());
            let z = &h * &truth + DVector::from_fn(6, |_, _| 2.0 * gauss());
            kf.update_trusted(&z, &h, &r).unwrap();
            bank.update(&z, &h, &r_diag, &sats, &used).unwrap();
            let sub = bank.subs[3].as_ref().unwrap();
            let i = idx(2);
            let d = sub.x()[i] - kf.x()[i];
            sum2 += d * d;
            predicted = sub.p()[(i, i)] - kf.p()[(i, i)];
        }
        bank0.sync_view(&kf0, &sats);
        let var = sum2 / trials as f64;
        // 4000 draws: the sample variance is within ±10 % of the true one at > 99.9 %.
        assert!(
            (var / predicted - 1.0).abs() < 0.1,
            "sample {var}, P_s − P₀ {predicted}"
        );
    }
}
