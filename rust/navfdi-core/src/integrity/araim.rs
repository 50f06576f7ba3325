//! Advanced RAIM by multiple-hypothesis solution separation, after the EU–US ARAIM Technical
//! Subgroup's Reference Airborne Algorithm Description Document v3.0 (the "ADD"; Blanch et
//! al.). Snapshot, one epoch; inputs are the geometry rows and the integrity support message.
//!
//! * **Geometry.** Row i of `G` is `[−u_e, −u_n, −u_u, 1 on the clock of i's constellation]`
//!   with `u` the unit line of sight from the receiver to satellite i (east, north, up).
//! * **Fault modes.** Independent fault events are each satellite (prior `P_sat,i`) and each
//!   constellation (`P_const,j`, all its satellites wrong at once). `N_max` is the smallest
//!   number of simultaneous events whose excess probability `P(more than N_max events)`
//!   (Poisson-binomial over the events) is below `P_THRES`; every combination of up to
//!   `N_max` events is a fault mode (a constellation event with satellites of the same
//!   constellation is that constellation's mode), its prior the product of its events'. A mode
//!   whose subset cannot be solved (too few satellites) is not monitored. `P_unmonitored` =
//!   `P(more than N_max events)` + the priors of the unsolvable modes.
//! * **Per mode k** (and the all-in-view solution 0): `S⁽ᵏ⁾ = (GᵀW⁽ᵏ⁾G)⁻¹GᵀW⁽ᵏ⁾` with
//!   `W = C_int⁻¹` and the mode's satellites removed (a constellation with no satellite left
//!   loses its clock column); `σ_q⁽ᵏ⁾² = (GᵀW⁽ᵏ⁾G)⁻¹_qq`; `σ_ss,q⁽ᵏ⁾² = e_qᵀ(S⁽ᵏ⁾ − S⁽⁰⁾) C_acc
//!   (S⁽ᵏ⁾ − S⁽⁰⁾)ᵀe_q`; `b_q⁽ᵏ⁾ = Σ_i |S⁽ᵏ⁾_qi| b_nom,i`; threshold `T_k,q = K_fa,q σ_ss,q⁽ᵏ⁾`
//!   with `K_fa,1 = K_fa,2 = Q⁻¹(P_FA,HOR / (4 N_modes))`, `K_fa,3 = Q⁻¹(P_FA,VERT / (2 N_modes))`.
//! * **Protection levels.** VPL solves `2Q((VPL − b₃⁽⁰⁾)/σ₃⁽⁰⁾) + Σ_k p_k Q((VPL − T_k,3 −
//!   b₃⁽ᵏ⁾)/σ₃⁽ᵏ⁾) = P_HMI,VERT (1 − P_unmonitored / (P_HMI,VERT + P_HMI,HOR))`; HPL_q (q = 1, 2)
//!   the same with `P_HMI,HOR / 2` on the right, and `HPL = sqrt(HPL₁² + HPL₂²)`. Solved by
//!   safeguarded Newton on the logarithm of the left side (which falls monotonically in the
//!   level) from the fault-free level, to 1 µm.
//! * **Detection and exclusion** ([`araim_fde`](super::araim_fde::araim_fde)): the solution separation tests on residuals,
//!   candidate subsets recomputed, the levels after exclusion.
//! * **Accuracy and EMT.** `σ_acc,q = sqrt((GᵀW_acc G)⁻¹_qq)` with `W_acc = C_acc⁻¹`; the effective
//!   monitor threshold `EMT = max T_k,3` over the modes with `p_k ≥ P_EMT`.
//!
//! Availability: `P_unmonitored ≤ P_THRES` and every PL finite.

use super::subsets::{Downdate, EachRow, Subsets};
use crate::error::{Error, Result};
use nalgebra::DMatrix;
use statrs::distribution::{ContinuousCDF, Normal};

/// Integrity support message and nominal errors, per satellite (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct Ism {
    /// Integrity variance `C_int,i` per satellite (m²): σ_URA² + troposphere + user terms.
    pub c_int: Vec<f64>,
    /// Accuracy variance `C_acc,i` per satellite (m²): σ_URE² + troposphere + user terms.
    pub c_acc: Vec<f64>,
    /// Nominal bias bound `b_nom,i` per satellite (m).
    pub b_nom: Vec<f64>,
    /// Prior probability of a fault of each satellite.
    pub p_sat: Vec<f64>,
    /// Prior probability of a fault of each constellation (index into the constellations).
    pub p_const: Vec<f64>,
}

impl Ism {
    /// Check every value: variances positive and finite, nominal biases finite and ≥ 0,
    /// satellite priors in (0, 1), constellation priors in [0, 1). The error names the field and satellite (NaN never
    /// passes: a NaN bias or prior would make the levels vanish).
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("c_int", &self.c_int), ("c_acc", &self.c_acc)] {
            if let Some((i, x)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !(**x > 0.0 && x.is_finite()))
            {
                return Err(Error::InvalidParameter {
                    name: format!("{name}[{i}]"),
                    value: *x,
                    requirement: "a variance must be positive and finite".into(),
                });
            }
        }
        if let Some((i, x)) = self
            .b_nom
            .iter()
            .enumerate()
            .find(|(_, x)| !(**x >= 0.0 && x.is_finite()))
        {
            return Err(Error::InvalidParameter {
                name: format!("b_nom[{i}]"),
                value: *x,
                requirement: "a nominal bias bound must be finite and non-negative (m)".into(),
            });
        }
        // A constellation prior may be 0 (no constellation fault monitored); a satellite's may
        // not (every satellite can fail).
        for (name, v, zero) in [
            ("p_sat", &self.p_sat, false),
            ("p_const", &self.p_const, true),
        ] {
            if let Some((i, x)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !((**x > 0.0 || (zero && **x == 0.0)) && **x < 1.0))
            {
                return Err(Error::InvalidParameter {
                    name: format!("{name}[{i}]"),
                    value: *x,
                    requirement: if zero {
                        "a constellation prior must be in [0, 1) (0: none monitored)".into()
                    } else {
                        "a satellite prior must be a probability in (0, 1)".into()
                    },
                });
            }
        }
        Ok(())
    }
}

/// Integrity allocation (LPV-200 in [`Allocation::lpv200`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Allocation {
    /// Integrity budget of the vertical.
    pub p_hmi_vert: f64,
    /// Integrity budget of the horizontal.
    pub p_hmi_hor: f64,
    /// Continuity (false-alert) budget of the vertical tests.
    pub p_fa_vert: f64,
    /// Continuity budget of the horizontal tests.
    pub p_fa_hor: f64,
    /// Largest probability of the unmonitored fault modes.
    pub p_thres: f64,
    /// Smallest prior of a mode counted in the EMT.
    pub p_emt: f64,
    /// The ADD's protection-level tolerance TOL_PL (m): the levels are the upper end of the
    /// ADD's half-interval search once its bracket is this narrow (so at most this much above
    /// the root of the PL equation); 0 solves the equation to 1 µm instead.
    pub tol_pl: f64,
}

impl Allocation {
    /// The LPV-200 allocation of the ADD (P_HMI 1e-7 split 9.8e-8 / 2e-9; P_FA 3.9e-6 / 9e-8;
    /// P_THRES 8e-8; P_EMT 1e-5; TOL_PL 5 cm).
    pub fn lpv200() -> Self {
        Allocation {
            p_hmi_vert: 9.8e-8,
            p_hmi_hor: 2e-9,
            p_fa_vert: 3.9e-6,
            p_fa_hor: 9e-8,
            p_thres: 8e-8,
            p_emt: 1e-5,
            tol_pl: 0.05,
        }
    }

    /// Check the allocation: every probability finite in (0, 1), P_HMI,V + P_HMI,H below 1,
    /// TOL_PL finite in [0, 10] m.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("p_hmi_vert", self.p_hmi_vert),
            ("p_hmi_hor", self.p_hmi_hor),
            ("p_fa_vert", self.p_fa_vert),
            ("p_fa_hor", self.p_fa_hor),
            ("p_thres", self.p_thres),
            ("p_emt", self.p_emt),
        ] {
            if !(v > 0.0 && v < 1.0) {
                return Err(Error::InvalidParameter {
                    name: format!("allocation.{name}"),
                    value: v,
                    requirement: "must be a probability in (0, 1)".into(),
                });
            }
        }
        if self.p_hmi_vert + self.p_hmi_hor >= 1.0 {
            return Err(Error::InvalidParameter {
                name: "allocation.p_hmi_vert + p_hmi_hor".into(),
                value: self.p_hmi_vert + self.p_hmi_hor,
                requirement: "the integrity budget must be below 1".into(),
            });
        }
        if !(0.0..=10.0).contains(&self.tol_pl) {
            return Err(Error::InvalidParameter {
                name: "allocation.tol_pl".into(),
                value: self.tol_pl,
                requirement: "must be in [0, 10] m".into(),
            });
        }
        Ok(())
    }
}

/// One monitored fault mode.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultMode {
    /// Satellites removed (indices into the inputs).
    pub satellites: Vec<usize>,
    /// Constellations whose fault the mode covers (indices).
    pub constellations: Vec<usize>,
    /// Prior probability.
    pub prior: f64,
    /// σ_q of the subset solution, east, north, up (m).
    pub sigma: [f64; 3],
    /// σ_ss,q of the solution separation (m).
    pub sigma_ss: [f64; 3],
    /// b_q of the subset solution (m).
    pub bias: [f64; 3],
    /// Test thresholds T_k,q (m).
    pub threshold: [f64; 3],
    /// Solution separation `x̂⁽ᵏ⁾ − x̂⁽⁰⁾` east, north, up (m), from the residuals given to
    /// [`araim_fde`](super::araim_fde::araim_fde); NaN from [`araim`].
    pub separation: [f64; 3],
}

/// Result of [`araim`].
#[derive(Debug, Clone, PartialEq)]
pub struct AraimResult {
    /// Vertical protection level (m; inf when unavailable).
    pub vpl: f64,
    /// Horizontal protection level (m).
    pub hpl: f64,
    /// Effective monitor threshold (m).
    pub emt: f64,
    /// σ_acc of the vertical and of each horizontal axis (east, north), m.
    pub sigma_acc: [f64; 3],
    /// All-in-view σ_q (integrity), east, north, up (m).
    pub sigma0: [f64; 3],
    /// All-in-view b_q (m).
    pub bias0: [f64; 3],
    /// K_fa for east, north, up.
    pub k_fa: [f64; 3],
    /// Probability of the faults not monitored.
    pub p_unmonitored: f64,
    /// Most simultaneous fault events monitored.
    pub n_max: usize,
    /// The all-in-view least-squares correction `S⁽⁰⁾ y` east, north, up (m) from the
    /// residuals given to [`araim_fde`](super::araim_fde::araim_fde) (the position is the linearisation point plus it);
    /// NaN from [`araim`].
    pub correction: [f64; 3],
    /// The monitored fault modes (fault-free excluded).
    pub modes: Vec<FaultMode>,
    /// `P_unmonitored ≤ P_THRES` and finite protection levels.
    pub available: bool,
}

/// Upper tail of the standard normal.
fn q(x: f64) -> f64 {
    let n = Normal::standard();
    n.sf(x)
}

/// Standard normal density.
fn phi(x: f64) -> f64 {
    (-0.5 * x * x).exp() * 0.398_942_280_401_432_7
}

/// Inverse of [`q`], as `−Φ⁻¹(p)`: evaluating `Φ⁻¹(1 − p)` loses the tail's precision for
/// p ~ 1e-9 (the horizontal false-alert allocation per mode).
fn q_inv(p: f64) -> f64 {
    // statrs panics outside [0, 1]; the inputs are validated, but no value may panic.
    if !(p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    -Normal::standard().inverse_cdf(p)
}

/// Probabilities of exactly 0, 1, … independent events with probabilities `p`.
fn count_distribution(p: &[f64]) -> Vec<f64> {
    let mut d = vec![1.0];
    for &pi in p {
        let mut next = vec![0.0; d.len() + 1];
        for (k, &v) in d.iter().enumerate() {
            next[k] += v * (1.0 - pi);
            next[k + 1] += v * pi;
        }
        d = next;
    }
    d
}

/// Calls `f` with every index set of size 1..=r over `m` items (increasing indices, sets
/// in lexicographic order).
fn for_each_combination(m: usize, r: usize, f: &mut dyn FnMut(&[usize])) {
    fn rec(start: usize, m: usize, r: usize, cur: &mut Vec<usize>, f: &mut dyn FnMut(&[usize])) {
        if !cur.is_empty() {
            f(cur);
        }
        if cur.len() == r {
            return;
        }
        for i in start..m {
            cur.push(i);
            rec(i + 1, m, r, cur, f);
            cur.pop();
        }
    }
    rec(0, m, r, &mut Vec::with_capacity(r), f);
}

/// A mode's sums over the satellites of its gain rows `S⁽ᵏ⁾[:, i]`, against the all-in-view
/// rows `S⁽⁰⁾[:, i]` (`s0_t[i]`): `σ_ss²` (with `C_acc`), the bias bound (with `b_nom`) and,
/// given residuals `y`, the solution separation; east, north, up.
struct ModeSums<'a> {
    s0_t: &'a [[f64; 3]],
    c_acc: &'a [f64],
    b_nom: &'a [f64],
    y: Option<&'a [f64]>,
    ss2: [f64; 3],
    bias: [f64; 3],
    separation: [f64; 3],
}

impl EachRow for ModeSums<'_> {
    /// Satellite i's row, inlined into the rows' loop (a closure body this size is not).
    #[inline(always)]
    fn row(&mut self, i: usize, sk: [f64; 3]) {
        let s0i = self.s0_t[i];
        let (c, b) = (self.c_acc[i], self.b_nom[i]);
        for q in 0..3 {
            let d = sk[q] - s0i[q];
            self.ss2[q] += d * d * c;
            self.bias[q] += sk[q].abs() * b;
        }
        if let Some(y) = self.y {
            for q in 0..3 {
                self.separation[q] += (sk[q] - s0i[q]) * y[i];
            }
        }
    }
}

/// The indices of the bits set in `mask`, increasing.
fn set_bits(mut mask: u128) -> Vec<usize> {
    let mut out = Vec::with_capacity(mask.count_ones() as usize);
    while mask != 0 {
        out.push(mask.trailing_zeros() as usize);
        mask &= mask - 1;
    }
    out
}

/// A fault mode's removed satellites: a bit mask up to 128 satellites, else the list.
#[derive(PartialEq, Eq, Hash)]
enum ModeKey {
    Mask(u128),
    List(Vec<usize>),
}

/// Solve `f(L) = target` for the decreasing `f` from `lo` (`f(lo) ≥ target`) below a level
/// `hi` where `f(hi) ≤ target` (checked only if the search reaches it, then widened by
/// doubling; inf when even a huge level leaves `f` above the target). `fd(L)` returns
/// `(f, f')`. Safeguarded Newton on `ln f − ln target`, nearly linear in the level (three or
/// four evaluations), bisection when a step leaves the bracket; stops on the safe side
/// (`f ≤ target`) once the next Newton step is under 1 µm, or when the bracket is 0.1 mm
/// wide (its upper end is returned).
fn solve_level(fd: impl Fn(f64) -> (f64, f64), target: f64, mut lo: f64, mut hi: f64) -> f64 {
    let lt = target.ln();
    let g = |l: f64| {
        let (f, d) = fd(l);
        let f = f.max(1e-300);
        (f.ln() - lt, d / f)
    };
    if !(hi > lo) {
        hi = lo + 1.0;
    }
    let (mut gx, mut dx) = g(lo);
    if gx <= 0.0 {
        return lo;
    }
    let mut x = lo;
    loop {
        while hi - lo > 1e-4 {
            let mut next = if dx < 0.0 { x - gx / dx } else { f64::NAN };
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let (gn, dn) = g(next);
            if gn > 0.0 {
                lo = next;
            } else {
                hi = next;
                if dn < 0.0 && gn / dn < 1e-6 {
                    return next;
                }
            }
            (x, gx, dx) = (next, gn, dn);
        }
        // The bracket closed on `hi`: confirm it, or widen.
        let (gh, dh) = g(hi);
        if gh <= 0.0 {
            return hi;
        }
        lo = hi;
        hi *= 2.0;
        if hi > 1e7 {
            return f64::INFINITY;
        }
        (x, gx, dx) = (lo, gh, dh);
    }
}

/// The left side of the protection-level equation and its derivative at a level `L` (m):
/// `(2Q((L − b₀)/σ₀) + Σ p Q((L − shift)/σ), its derivative)`, `terms` (prior, shift, 1/σ).
fn level_fd(bias0: f64, sigma0: f64, terms: &[(f64, f64, f64)]) -> impl Fn(f64) -> (f64, f64) + '_ {
    let inv0 = 1.0 / sigma0;
    move |l: f64| {
        let x0 = (l - bias0) * inv0;
        let (mut f, mut d) = (2.0 * q(x0), -2.0 * phi(x0) * inv0);
        for &(p, shift, inv) in terms {
            let x = (l - shift) * inv;
            f += p * q(x);
            d -= p * phi(x) * inv;
        }
        (f, d)
    }
}

/// The bracket of [`add_level`]'s search: below, the largest `shift + σ Q⁻¹(min(1, target/p))`
/// over the terms and the fault-free one (p = 2); above, the largest `shift + σ max(0,
/// Q⁻¹(target/(N p)))` over the N terms.
fn add_bracket(bias0: f64, sigma0: f64, terms: &[(f64, f64, f64)], target: f64) -> (f64, f64) {
    let all = std::iter::once((2.0, bias0, 1.0 / sigma0)).chain(terms.iter().copied());
    let n = (terms.len() + 1) as f64;
    let (mut lo, mut hi) = (0.0_f64, 0.0_f64);
    // The modes' priors take a few values (a satellite, a pair, a constellation and a
    // satellite, …): each quantile is computed once per prior (the same bits).
    let mut memo: Vec<(u64, [f64; 2])> = Vec::with_capacity(8);
    for (p, shift, inv) in all {
        let [q_lo, q_hi] = match memo.iter().find(|m| m.0 == p.to_bits()) {
            Some(m) => m.1,
            None => {
                let (r_lo, r_hi) = (target / p, target / (n * p));
                let v = [
                    if r_lo < 1.0 { q_inv(r_lo) } else { f64::NAN },
                    if r_hi < 0.5 { q_inv(r_hi) } else { 0.0 },
                ];
                memo.push((p.to_bits(), v));
                v
            }
        };
        if !q_lo.is_nan() {
            lo = lo.max(shift + q_lo / inv);
        }
        hi = hi.max(shift + q_hi / inv);
    }
    (lo, hi)
}

/// The terms the root search of [`add_level`] evaluates: those that may exceed `1e-16 target`
/// somewhere at or above `lo` (m). A term `p Q((L − shift)/σ)` falls with `L`, and by the Chernoff
/// bound `Q(x) ≤ exp(−x²/2)/2` (x ≥ 0) it stays below that once `x ≥ √(2 ln(p / (2·1e-16
/// target)))`; the terms left out sum to at most `N·1e-16` of the target, so the root moves by
/// far less than the micrometre it is found to. At 40 satellites most pair modes are so far out
/// (about 800 of 862 terms per axis).
fn root_terms(terms: &[(f64, f64, f64)], target: f64, lo: f64) -> Vec<(f64, f64, f64)> {
    let floor = 1e-16 * target;
    let mut memo: Vec<(u64, f64)> = Vec::with_capacity(8);
    let mut kept = Vec::with_capacity(terms.len());
    for &(p, shift, inv) in terms {
        let x_min = match memo.iter().find(|m| m.0 == p.to_bits()) {
            Some(m) => m.1,
            None => {
                let x = (2.0 * (0.5 * p / floor).ln()).max(0.0).sqrt();
                memo.push((p.to_bits(), x));
                x
            }
        };
        // NaN (and a term at or below its floor only beyond the bracket) is kept.
        if !((lo - shift) * inv >= x_min) {
            kept.push((p, shift, inv));
        }
    }
    kept
}

/// The ADD's protection-level search (Appendix A): half-interval search on
/// `f(L) = 2Q((L − b_0)/σ_0) + Σ_k p_k Q((L − shift_k)/σ_k)` between the ADD's bounds — below,
/// the largest `shift + σ Q⁻¹(min(1, target/p))` over the terms (the fault-free one with
/// p = 2), where one term alone reaches the target; above, the largest
/// `shift + σ max(0, Q⁻¹(target/(N p)))` over the N terms, where each holds at most target/N —
/// until the bracket is at most `tol` (m) wide; its upper end is returned, a level within
/// `tol` above the root. `terms`: (prior, shift, 1/σ).
///
/// The search is replayed rather than evaluated: the root is found first by [`solve_level`]
/// (a few evaluations), and each midpoint goes to the side the root is on; `f` itself is
/// evaluated only for a midpoint within 10 µm of the root, where that is not certain. The
/// returned level is the ADD search's, bit for bit (`f` falls by ≈ 10⁻⁵ of itself over 10 µm,
/// far beyond its rounding), at a third of its evaluations.
fn add_level(bias0: f64, sigma0: f64, terms: &[(f64, f64, f64)], target: f64, tol: f64) -> f64 {
    let (mut lo, mut hi) = add_bracket(bias0, sigma0, terms, target);
    if !(lo.is_finite() && hi.is_finite()) {
        return f64::INFINITY;
    }
    let kept = root_terms(terms, target, lo);
    let fd = level_fd(bias0, sigma0, &kept);
    let all = || std::iter::once((2.0, bias0, 1.0 / sigma0)).chain(terms.iter().copied());
    let f = |l: f64| -> f64 { all().map(|(p, shift, inv)| p * q((l - shift) * inv)).sum() };
    let root = solve_level(fd, target, lo, hi);
    let above = |l: f64| -> bool {
        if (l - root).abs() > 1e-5 {
            l < root
        } else {
            f(l) > target
        }
    };
    let mut count = 0;
    while hi - lo > tol && count < 200 {
        let half = 0.5 * (lo + hi);
        if above(half) {
            lo = half;
        } else {
            hi = half;
        }
        count += 1;
    }
    hi
}

/// The ADD's false-alert multipliers `K_fa` east, north, up for `n_modes` monitored modes:
/// `Q⁻¹(P_FA,H / 4N)` twice and `Q⁻¹(P_FA,V / 2N)`.
pub(crate) fn k_fa(n_modes: usize, alloc: &Allocation) -> [f64; 3] {
    let nm = n_modes.max(1) as f64;
    [
        q_inv(alloc.p_fa_hor / (4.0 * nm)),
        q_inv(alloc.p_fa_hor / (4.0 * nm)),
        q_inv(alloc.p_fa_vert / (2.0 * nm)),
    ]
}

/// One fault mode's terms in the protection-level equation, east, north, up (m): prior,
/// `T_k,q + b_k,q` and `σ_k,q`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ModeTerm {
    pub prior: f64,
    pub shift: [f64; 3],
    pub sigma: [f64; 3],
}

/// VPL and HPL (m) by the ADD's equations (Appendix, PL root finding) from the fault-free
/// `σ_0,q` and `b_0,q` (east, north, up) and the modes' terms: the level `L` where
/// `2Q((L − b_0)/σ_0) + Σ_k p_k Q((L − T_k − b_k)/σ_k)` equals the budget (P_HMI,V for the
/// vertical; half P_HMI,H for each horizontal axis, HPL the root sum square), the budgets
/// scaled by `1 − P_unmonitored / (P_HMI,V + P_HMI,H)`. Infinite when that scale is not
/// positive.
pub(crate) fn protection_levels(
    sigma0: [f64; 3],
    bias0: [f64; 3],
    modes: &[ModeTerm],
    p_unmonitored: f64,
    alloc: &Allocation,
) -> (f64, f64) {
    let scale = 1.0 - p_unmonitored / (alloc.p_hmi_vert + alloc.p_hmi_hor);
    let level = |qd: usize, target: f64| -> f64 {
        // (prior, T + b, 1/σ) per mode; the bracket [lo, hi] from the fault-free term alone
        // (every term is ≥ 0) and from each term held to target/(N+1) by the Chernoff bound
        // Q(x) ≤ exp(−x²/2)/2, so the root search needs no doubling.
        let terms: Vec<(f64, f64, f64)> = modes
            .iter()
            .map(|m| (m.prior, m.shift[qd], 1.0 / m.sigma[qd]))
            .collect();
        let fd = level_fd(bias0[qd], sigma0[qd], &terms);
        if alloc.tol_pl > 0.0 {
            return add_level(bias0[qd], sigma0[qd], &terms, target, alloc.tol_pl);
        }
        let share = target / (terms.len() + 1) as f64;
        let lo = bias0[qd] + sigma0[qd] * q_inv(0.5 * target);
        let mut hi = bias0[qd] + sigma0[qd] * (2.0 * (1.0 / share).ln()).sqrt();
        for &(p, shift, inv) in &terms {
            let x = (2.0 * (0.5 * p / share).ln()).max(0.0).sqrt();
            hi = hi.max(shift + x / inv);
        }
        solve_level(fd, target, lo.max(0.0), hi)
    };
    if scale > 0.0 {
        let v = level(2, alloc.p_hmi_vert * scale);
        let h1 = level(0, 0.5 * alloc.p_hmi_hor * scale);
        let h2 = level(1, 0.5 * alloc.p_hmi_hor * scale);
        (v, h1.hypot(h2))
    } else {
        (f64::INFINITY, f64::INFINITY)
    }
}

/// ARAIM protection levels of one epoch. `rows` (n): ENU geometry rows (minus the unit lines of
/// sight); `constellation` (n): index of each satellite's constellation (0..C); `ism`, `alloc`.
pub fn araim(
    rows: &[[f64; 3]],
    constellation: &[usize],
    ism: &Ism,
    alloc: &Allocation,
) -> Result<AraimResult> {
    araim_inner(rows, constellation, ism, alloc, None)
}

/// [`araim`], and with `residuals` (n, m: any pseudorange residuals of the linear model, e.g.
/// the all-in-view least-squares residuals) each mode's solution separation
/// `Δ_k = (S⁽ᵏ⁾ − S⁽⁰⁾) y` in [`FaultMode::separation`].
pub(crate) fn araim_inner(
    rows: &[[f64; 3]],
    constellation: &[usize],
    ism: &Ism,
    alloc: &Allocation,
    residuals: Option<&[f64]>,
) -> Result<AraimResult> {
    alloc.validate()?;
    let n = rows.len();
    let nc = constellation.iter().copied().max().map_or(0, |m| m + 1);
    for (name, len) in [
        ("constellation", constellation.len()),
        ("c_int", ism.c_int.len()),
        ("c_acc", ism.c_acc.len()),
        ("b_nom", ism.b_nom.len()),
        ("p_sat", ism.p_sat.len()),
    ] {
        if len != n {
            return Err(Error::Shape {
                name: name.into(),
                expected: format!("({n},), one per satellite"),
                got: format!("({len},)"),
            });
        }
    }
    if ism.p_const.len() < nc {
        return Err(Error::Shape {
            name: "p_const".into(),
            expected: format!("at least {nc} (one per constellation)"),
            got: format!("({},)", ism.p_const.len()),
        });
    }
    ism.validate()?;
    let mut g = DMatrix::zeros(n, 3 + nc);
    for (i, r) in rows.iter().enumerate() {
        for c in 0..3 {
            g[(i, c)] = r[c];
        }
        g[(i, 3 + constellation[i])] = 1.0;
    }
    let w_int: Vec<f64> = ism.c_int.iter().map(|c| 1.0 / c).collect();
    let w_acc: Vec<f64> = ism.c_acc.iter().map(|c| 1.0 / c).collect();
    let int = Subsets::new(&g, &w_int);
    let (cov0, s0) = int.solve(&[]).ok_or_else(|| Error::Numerical {
        context: "ARAIM".into(),
        detail: "the all-in-view geometry is singular".into(),
    })?;
    let (cov_acc, _) = Subsets::new(&g, &w_acc)
        .solve(&[])
        .ok_or_else(|| Error::Numerical {
            context: "ARAIM".into(),
            detail: "the all-in-view geometry is singular".into(),
        })?;
    // Fault events: satellites, then constellations.
    let mut events: Vec<f64> = ism.p_sat.clone();
    events.extend(ism.p_const[..nc].iter().copied());
    let dist = count_distribution(&events);
    let tail = |r: usize| -> f64 { dist.iter().skip(r + 1).sum::<f64>().max(0.0) };
    let mut n_max = 0;
    while n_max < events.len() && tail(n_max) >= alloc.p_thres {
        n_max += 1;
    }
    let mut p_unmonitored = tail(n_max);
    // Candidate modes: combinations of up to n_max events, normalised (a constellation event
    // absorbs its own satellites), deduplicated.
    // Sized for every combination at once (growing them costs copies and page faults).
    let combos = (1..=n_max).fold((0usize, 1usize), |(sum, c), k| {
        let c = c.saturating_mul(events.len() + 1 - k) / k;
        (sum.saturating_add(c), c)
    });
    let capacity = combos.0.min(1 << 16);
    let mut seen: rustc_hash::FxHashMap<ModeKey, usize> =
        rustc_hash::FxHashMap::with_capacity_and_hasher(capacity, Default::default());
    let mut modes_raw: Vec<(Vec<usize>, Vec<usize>, f64)> = Vec::with_capacity(capacity);
    let small = n <= 128;
    let const_mask: Vec<u128> = (0..nc)
        .map(|c| {
            (0..n)
                .filter(|&i| small && constellation[i] == c)
                .fold(0u128, |m, i| m | 1u128 << i)
        })
        .collect();
    for_each_combination(events.len(), n_max, &mut |combo: &[usize]| {
        let prior: f64 = combo.iter().map(|&e| events[e]).product();
        let in_const = |i: usize| combo.iter().any(|&e| e >= n && e - n == constellation[i]);
        let key = if small {
            let mask = combo.iter().fold(0u128, |m, &e| {
                if e < n {
                    m | 1u128 << e
                } else {
                    m | const_mask[e - n]
                }
            });
            if mask == 0 {
                return;
            }
            ModeKey::Mask(mask)
        } else {
            let removed: Vec<usize> = (0..n)
                .filter(|&i| combo.contains(&i) || in_const(i))
                .collect();
            if removed.is_empty() {
                return;
            }
            ModeKey::List(removed)
        };
        match seen.entry(key) {
            std::collections::hash_map::Entry::Occupied(e) => modes_raw[*e.get()].2 += prior,
            std::collections::hash_map::Entry::Vacant(e) => {
                let removed: Vec<usize> = match e.key() {
                    ModeKey::Mask(mask) => set_bits(*mask),
                    ModeKey::List(list) => list.clone(),
                };
                let consts: Vec<usize> =
                    combo.iter().filter(|&&e| e >= n).map(|&e| e - n).collect();
                modes_raw.push((removed, consts, prior));
                e.insert(modes_raw.len() - 1);
            }
        }
    });
    let down = Downdate::new(&int, cov0.clone());
    // Every mode's statistics in the same pass as its gain rows; the thresholds once the
    // number of monitored modes is known.
    let s0_t: Vec<[f64; 3]> = (0..n)
        .map(|i| [s0[(0, i)], s0[(1, i)], s0[(2, i)]])
        .collect();
    let mut modes: Vec<FaultMode> = Vec::with_capacity(modes_raw.len());
    for (removed, consts, prior) in modes_raw {
        let mut sums = ModeSums {
            s0_t: &s0_t,
            c_acc: &ism.c_acc,
            b_nom: &ism.b_nom,
            y: residuals,
            ss2: [0.0; 3],
            bias: [0.0; 3],
            separation: [0.0; 3],
        };
        let Some(var) = down.rows_each(&removed, &mut sums) else {
            p_unmonitored += prior;
            continue;
        };
        let ModeSums {
            ss2,
            bias,
            mut separation,
            ..
        } = sums;
        if residuals.is_none() {
            separation = [f64::NAN; 3];
        }
        modes.push(FaultMode {
            satellites: removed,
            constellations: consts,
            prior,
            sigma: var.map(|v| v.max(0.0).sqrt()),
            sigma_ss: ss2.map(|v| v.max(0.0).sqrt()),
            bias,
            threshold: [0.0; 3],
            separation,
        });
    }
    let k_fa = k_fa(modes.len(), alloc);
    for m in &mut modes {
        m.threshold = [0, 1, 2].map(|q| k_fa[q] * m.sigma_ss[q]);
    }
    let bias_of = |s: &DMatrix<f64>, qd: usize| -> f64 {
        (0..n).map(|i| s[(qd, i)].abs() * ism.b_nom[i]).sum()
    };
    let sigma0 = [
        cov0[(0, 0)].sqrt(),
        cov0[(1, 1)].sqrt(),
        cov0[(2, 2)].sqrt(),
    ];
    let bias0 = [bias_of(&s0, 0), bias_of(&s0, 1), bias_of(&s0, 2)];
    let terms: Vec<ModeTerm> = modes
        .iter()
        .map(|m| ModeTerm {
            prior: m.prior,
            shift: [0, 1, 2].map(|q| m.threshold[q] + m.bias[q]),
            sigma: m.sigma,
        })
        .collect();
    let (vpl, hpl) = protection_levels(sigma0, bias0, &terms, p_unmonitored, alloc);
    let emt = modes
        .iter()
        .filter(|m| m.prior >= alloc.p_emt)
        .map(|m| m.threshold[2])
        .fold(0.0, f64::max);
    let sigma_acc = [
        cov_acc[(0, 0)].sqrt(),
        cov_acc[(1, 1)].sqrt(),
        cov_acc[(2, 2)].sqrt(),
    ];
    let available = p_unmonitored <= alloc.p_thres && vpl.is_finite() && hpl.is_finite();
    let correction = match residuals {
        Some(y) => [0, 1, 2].map(|q| (0..n).map(|i| s0[(q, i)] * y[i]).sum()),
        None => [f64::NAN; 3],
    };
    Ok(AraimResult {
        vpl,
        hpl,
        emt,
        correction,
        sigma_acc,
        sigma0,
        bias0,
        k_fa,
        p_unmonitored,
        n_max,
        modes,
        available,
    })
}

#[cfg(test)]
#[path = "araim_tests.rs"]
pub(crate) mod tests;
