//! Snapshot least squares with fault detection and exclusion (METHODS §10, paper 001).
//!
//! Observations `l = B x + ε`, `ε ~ N(0, D)` (linearised at the solution), `u` unknowns:
//!
//! * estimate `x̂ = (BᵀD⁻¹B)⁻¹BᵀD⁻¹l`, residuals `V = B x̂ − l`, their covariance
//!   `D_V = D − B(BᵀD⁻¹B)⁻¹Bᵀ`;
//! * global test `T = VᵀD⁻¹V ~ χ²(n − u)` against `F⁻¹(1 − α)`;
//! * when it fails, Baarda's w-test in its general (correlated) form
//!   `w_i = e_iᵀD⁻¹V / sqrt(e_iᵀD⁻¹D_VD⁻¹e_i)`, which for a diagonal `D` is `v_i / σ_{v_i}`;
//!   the observation with the largest `|w_i|` above `K` is excluded and everything is
//!   recomputed, until the global test passes. Two faults of one sign can make a healthy
//!   observation's `|w|` the largest (swamping): when a second exclusion is needed, the pair
//!   whose removal from the whole set leaves the smallest passing test ratio is taken instead
//!   of the first exclusion and the next, if it is another pair (every pair tested on a
//!   downdate of the whole set's linearised solution; the pair taken is solved in full).
//!
//! What opens the loop is [`FdeConfig::test`] ([`Detection`]): the global test (above, the
//! default), data snooping (the largest `|w_i|` of the n tested observations above `k0 =
//! z(1 − α0/2)`, `α0 = 1 − (1 − α)^(1/n)`, which also identifies; repeated until no `|w|`
//! exceeds `k0`), both (each at α/2) or, per set, the one of the two whose non-centrality at
//! the power β0 is the smaller. Each observation's minimal detectable bias
//! `√(λ0 / e_iᵀD⁻¹D_VD⁻¹e_i)` at the deciding test's `λ0` is reported ([`FdeOutcome::mdb`]).
//!
//! Outcomes ([`FdeStatus`]): `passed` (nothing excluded), `excluded` (passed after excluding
//! one or more), `unidentified` (the global test fails but no `|w_i|` exceeds `K`: the
//! solution is kept and flagged), `no_solution` (fewer than `u + 1` observations left, a
//! singular geometry or no convergence: no position is given, never a NaN one). An
//! observation with no redundancy (`e_iᵀD⁻¹D_VD⁻¹e_i ≈ 0`) cannot be tested: its `w` is NaN and
//! it is never excluded.
//!
//! Two models: [`PositionModel`] (pseudoranges → ECEF position and clock bias, iterative
//! Gauss-Newton) and [`RateModel`] (pseudorange rates → ECEF velocity and clock drift, linear).
//! The exclusion loop [`fde`] is shared.
//!
//! The least-squares machinery (covariances, the linear test, Gauss-Newton) is in
//! [`super::lsq`], re-exported here.

pub use super::lsq::{
    check_size, gauss_newton, ls_test, ls_test_cov, two_sided_quantile, Detection, FdeConfig,
    FdeModel, FdeStatus, LsTest, ObsCov, Snooping,
};
use crate::error::{Error, Result};
use nalgebra::{Cholesky, DMatrix, DVector, Vector3};

mod pairs;
use pairs::{best_pair, PairScreen};

/// Result of [`fde`].
#[derive(Debug, Clone, PartialEq)]
pub struct FdeOutcome {
    /// Solution (u), None when there is none.
    pub solution: Option<DVector<f64>>,
    /// Global-test statistic of the final set (NaN without a solution).
    pub statistic: f64,
    /// Its threshold (NaN without a solution).
    pub threshold: f64,
    /// Its degrees of freedom n − u (0 without a solution).
    pub dof: usize,
    /// Statistic, threshold and dof of the first global test (all observations); NaN / 0 when
    /// there were too few observations to test.
    pub first: (f64, f64, usize),
    /// w per input observation from the final test (NaN for excluded ones and without a
    /// solution).
    pub w: Vec<f64>,
    /// Excluded observations (indices into the inputs), in exclusion order.
    pub excluded: Vec<usize>,
    /// |w| of each excluded observation when it was excluded.
    pub excluded_w: Vec<f64>,
    /// Minimal detectable bias per input observation at the final test (m; the bias that
    /// gives the final set's non-centrality `λ0` at α and β0: `√(λ0 / q_i)`; NaN for excluded
    /// or untestable observations and without a solution).
    pub mdb: Vec<f64>,
    /// The final set's allocation (`λ0`, `k0`, `α0`, the deciding test; None without a solution).
    pub snooping: Option<super::lsq::Snooping>,
    /// How the loop ended.
    pub status: FdeStatus,
    /// Why, in words.
    pub reason: String,
}

/// The exclusion loop over `n` observations with covariance `cov` (validated by the caller).
/// `usable[i] = false` leaves an observation out from the start (it is not reported as
/// excluded). `groups[i]` (optional) names the satellite of observation i: excluding an
/// observation then excludes every observation of its group (its pseudorange and its rate);
/// `excluded` lists the observation chosen by the w-test.
pub fn fde<M: FdeModel>(
    model: &mut M,
    cov: &ObsCov,
    usable: &[bool],
    groups: Option<&[usize]>,
    cfg: &FdeConfig,
) -> Result<FdeOutcome> {
    let n = usable.len();
    let u = model.unknowns();
    // Solve in a scaled form when the σ would over- or underflow when squared; statistics
    // and w are scaled back, so they are those of the σ given.
    let (cov, c) = cov.normalised();
    let cov = cov.as_ref();
    let mut active: Vec<usize> = (0..n).filter(|&i| usable[i]).collect();
    let all = active.clone();
    let mut out = FdeOutcome::empty(n);
    // The all-observation solution, kept in case exclusion runs out of observations.
    let mut first_solution: Option<(DVector<f64>, Vec<f64>)> = None;
    // The whole set's residuals, their covariance and D⁻¹ (v, D_V, D⁻¹), for the pair check
    // (see `best_pair`).
    #[allow(clippy::type_complexity)]
    let mut full: Option<(DVector<f64>, DMatrix<f64>, DMatrix<f64>)> = None;
    loop {
        if active.len() < u + 1 {
            out.reason = format!(
                "{} observation(s) left; at least u + 1 = {} are needed to solve and test",
                active.len(),
                u + 1
            );
            return Ok(out.no_solution(n));
        }
        let Some(dinv) = cov.inverse_sub(&active) else {
            out.reason = "the covariance of the remaining observations is singular".into();
            return Ok(out.no_solution(n));
        };
        let Some((b, l)) = model.solve(&active, &dinv, cfg) else {
            // A gross observation (a pseudorange of 1e12 m or below zero, a satellite at the
            // receiver) can stop the iteration: find the one observation whose removal lets
            // the rest converge with the smallest test ratio, exclude it and go on.
            if active.len() >= u + 2 {
                if let Some(j) = leave_one_out(model, cov, &active, groups, cfg)? {
                    if out.excluded.is_empty() {
                        // The set with every observation failed to converge: its global test
                        // counts as failed (statistic +inf).
                        let dof = active.len() - u;
                        out.first = (f64::INFINITY, cfg.threshold(dof)?, dof);
                    }
                    let i = active[j];
                    out.excluded.push(i);
                    out.excluded_w.push(f64::INFINITY);
                    match groups {
                        Some(g) => active.retain(|&a| g[a] != g[i]),
                        None => {
                            active.remove(j);
                        }
                    }
                    continue;
                }
            }
            out.reason = "singular geometry or no convergence".into();
            return Ok(out.no_solution(n));
        };
        let d = cov.sub(&active);
        let Some(mut test) = ls_test(&b, &l, &d, &dinv) else {
            out.reason = "singular geometry".into();
            return Ok(out.no_solution(n));
        };
        if c != 1.0 {
            test.statistic = test.statistic / c / c;
            test.w.iter_mut().for_each(|w| *w /= c);
        }
        let dof = active.len() - u;
        let threshold = cfg.threshold(dof)?;
        if out.excluded.is_empty() {
            out.first = (test.statistic, threshold, dof);
        }
        let snoop = cfg.snooping(active.len(), dof)?;
        out.statistic = test.statistic;
        out.threshold = snoop.threshold;
        out.dof = dof;
        out.snooping = Some(snoop);
        out.w = vec![f64::NAN; n];
        out.mdb = vec![f64::NAN; n];
        for (j, &i) in active.iter().enumerate() {
            out.w[i] = test.w[j];
            // q is in the normalised units: ∇ (σ given) = √(λ0 / q) · c.
            out.mdb[i] = (snoop.lambda0 / test.q[j]).sqrt() * c;
        }
        out.solution = Some(model.solution());
        if first_solution.is_none() {
            first_solution = Some((model.solution(), out.w.clone()));
        }
        // Largest |w| among the testable observations.
        let worst = active
            .iter()
            .enumerate()
            .filter(|(j, _)| test.w[*j].is_finite())
            .max_by(|a, b| test.w[a.0].abs().total_cmp(&test.w[b.0].abs()));
        let global_fails = test.statistic >= snoop.threshold;
        let w_fails = snoop.test != Detection::Global
            && worst.is_some_and(|(j, _)| test.w[j].abs() > snoop.k0);
        let fails = match snoop.test {
            Detection::Global => global_fails,
            Detection::WTest => w_fails,
            _ => global_fails || w_fails,
        };
        if fails && out.excluded.is_empty() && active.len() == all.len() {
            // The whole set's linearisation, kept for the pair check of a second exclusion
            // (only epochs that fail need it; the downdate's M is formed only if one comes).
            full = Some((test.v.clone(), test.dv.clone(), dinv.clone()));
        }
        if !fails {
            let what = match snoop.test {
                Detection::Global => "global test passed".to_string(),
                t => format!(
                    "{}no |w| above k0 = {:.3}",
                    if t == Detection::Both {
                        "global test passed and "
                    } else {
                        ""
                    },
                    snoop.k0
                ),
            };
            out.status = if out.excluded.is_empty() {
                out.reason = what;
                FdeStatus::Passed
            } else {
                out.reason = format!(
                    "{what} after excluding {} observation(s)",
                    out.excluded.len()
                );
                FdeStatus::Excluded
            };
            return Ok(out);
        }
        // Identified by the largest |w|: above k0 when the w-test fired, else above K.
        let k_id = if w_fails { snoop.k0 } else { cfg.k };
        match worst {
            Some((j, &i)) if test.w[j].abs() > k_id => {
                let left = match groups {
                    Some(g) => active.iter().filter(|&&a| g[a] != g[i]).count(),
                    None => active.len() - 1,
                };
                if left < u + 1 {
                    // Excluding would leave too few to solve and test: the fault is detected
                    // but cannot be identified. Report the solution of every observation
                    // (what scaling every σ by one factor cannot change) as unidentified.
                    if let Some((x, w)) = first_solution.take() {
                        out.solution = Some(x);
                        out.w = w;
                        out.statistic = out.first.0;
                        out.threshold = out.first.1;
                        out.dof = out.first.2;
                    }
                    out.status = FdeStatus::Unidentified;
                    let why = if w_fails {
                        format!("|w| = {:.4} > k0 = {:.4}", test.w[j].abs(), snoop.k0)
                    } else {
                        format!(
                            "global test fails ({:.4} ≥ {:.4})",
                            test.statistic, threshold
                        )
                    };
                    out.reason = format!(
                        "{why} and no subset passes before too few observations would remain ({} excluded); the solution of every observation is kept",
                        out.excluded.len()
                    );
                    out.excluded.clear();
                    out.excluded_w.clear();
                    return Ok(out);
                }
                // A second exclusion: the first may have been a healthy observation that two
                // faults together made look worst (swamping). The pair of observations (of
                // groups) whose removal from the whole set leaves the smallest test ratio,
                // when it passes and is not the pair the loop is about to make, replaces it.
                let pair = match (
                    &full,
                    out.excluded.len() == 1 && out.excluded_w[0].is_finite(),
                ) {
                    (Some((v0, dv0, d0)), true) => {
                        best_pair(&PairScreen::new(v0, dv0, d0), c, u, &all, groups, cfg)?
                    }
                    _ => None,
                };
                {
                    if let Some((a, b, rest)) = pair {
                        let same = |x, y| same_group(groups, x, y);
                        let e = out.excluded[0];
                        if !((same(a, e) && same(b, i)) || (same(a, i) && same(b, e))) {
                            let w_of = |x: usize| {
                                first_solution
                                    .as_ref()
                                    .map_or(f64::NAN, |(_, w)| w[x].abs())
                            };
                            out.excluded_w = vec![w_of(a), w_of(b)];
                            out.excluded = vec![a, b];
                            active = rest;
                            continue;
                        }
                    }
                }
                out.excluded.push(i);
                out.excluded_w.push(test.w[j].abs());
                match groups {
                    Some(g) => active.retain(|&a| g[a] != g[i]),
                    None => {
                        active.remove(j);
                    }
                }
            }
            _ => {
                out.status = FdeStatus::Unidentified;
                out.reason = format!(
                    "global test fails ({:.4} ≥ {:.4}) but no |w| exceeds K = {}",
                    test.statistic, threshold, cfg.k
                );
                return Ok(out);
            }
        }
    }
}

/// Whether observations `x` and `y` are one satellite's (the same observation without
/// `groups`).
fn same_group(groups: Option<&[usize]>, x: usize, y: usize) -> bool {
    groups.map_or(x == y, |g| g[x] == g[y])
}

/// The global-test ratio (statistic / threshold; `c` the scale of the normalised covariance
/// `cov`) of the observations `rest` solved alone; None when they are too few, singular or do
/// not converge.
fn test_ratio<M: FdeModel>(
    model: &mut M,
    cov: &ObsCov,
    c: f64,
    rest: &[usize],
    cfg: &FdeConfig,
) -> Result<Option<f64>> {
    let u = model.unknowns();
    if rest.len() < u + 1 {
        return Ok(None);
    }
    let Some(dinv) = cov.inverse_sub(rest) else {
        return Ok(None);
    };
    let Some((b, l)) = model.solve(rest, &dinv, cfg) else {
        return Ok(None);
    };
    let Some(test) = ls_test(&b, &l, &cov.sub(rest), &dinv) else {
        return Ok(None);
    };
    let ratio = test.statistic / c / c / cfg.threshold(rest.len() - u)?;
    Ok(ratio.is_finite().then_some(ratio))
}

/// The position in `active` of the observation (with its group) whose removal lets the rest
/// solve with the smallest global-test ratio (statistic / threshold); None when no single
/// removal does. Used when the whole set does not converge.
fn leave_one_out<M: FdeModel>(
    model: &mut M,
    cov: &ObsCov,
    active: &[usize],
    groups: Option<&[usize]>,
    cfg: &FdeConfig,
) -> Result<Option<usize>> {
    let mut best: Option<(usize, f64)> = None;
    for (j, &i) in active.iter().enumerate() {
        let rest: Vec<usize> = match groups {
            Some(g) => active.iter().copied().filter(|&a| g[a] != g[i]).collect(),
            None => active.iter().copied().filter(|&a| a != i).collect(),
        };
        if let Some(ratio) = test_ratio(model, cov, 1.0, &rest, cfg)? {
            if best.is_none_or(|(_, r)| ratio < r) {
                best = Some((j, ratio));
            }
        }
    }
    Ok(best.map(|(j, _)| j))
}

impl FdeOutcome {
    /// No solution yet for `n` observations (NaN statistics and w, nothing excluded).
    pub fn empty(n: usize) -> Self {
        FdeOutcome {
            solution: None,
            statistic: f64::NAN,
            threshold: f64::NAN,
            dof: 0,
            first: (f64::NAN, f64::NAN, 0),
            w: vec![f64::NAN; n],
            excluded: Vec::new(),
            excluded_w: Vec::new(),
            mdb: vec![f64::NAN; n],
            snooping: None,
            status: FdeStatus::NoSolution,
            reason: String::new(),
        }
    }

    /// `w` with each excluded observation's |w| at its exclusion in place of NaN (what a
    /// per-satellite record shows).
    pub fn w_with_excluded(&self) -> Vec<f64> {
        let mut w = self.w.clone();
        for (&i, &wi) in self.excluded.iter().zip(&self.excluded_w) {
            w[i] = wi;
        }
        w
    }

    fn no_solution(mut self, n: usize) -> Self {
        self.solution = None;
        self.statistic = f64::NAN;
        self.threshold = f64::NAN;
        self.dof = 0;
        self.w = vec![f64::NAN; n];
        self.mdb = vec![f64::NAN; n];
        self.snooping = None;
        self.status = FdeStatus::NoSolution;
        self
    }
}

/// Pseudoranges `ρ_i = |r_s,i − r| + b + ε_i` → ECEF position r (m) and clock bias b (m).
#[derive(Debug, Clone)]
pub struct PositionModel<'a> {
    /// Satellite ECEF positions (m).
    pub sat: &'a [Vector3<f64>],
    /// Pseudoranges (m).
    pub rho: &'a [f64],
    /// Current estimate `[x, y, z, b]` (start value on entry).
    pub x: [f64; 4],
    x0: [f64; 4],
}

impl<'a> PositionModel<'a> {
    /// A model starting from `x0 = [x, y, z, b]` (m).
    pub fn new(sat: &'a [Vector3<f64>], rho: &'a [f64], x0: [f64; 4]) -> Self {
        PositionModel {
            sat,
            rho,
            x: x0,
            x0,
        }
    }
}

/// `(B, l)` of [`PositionModel`] at `x = [x, y, z, b]` for the observations `idx`.
fn position_linearise(
    sat: &[Vector3<f64>],
    rho: &[f64],
    x: &[f64],
    idx: &[usize],
) -> (DMatrix<f64>, DVector<f64>) {
    let m = idx.len();
    let r = Vector3::new(x[0], x[1], x[2]);
    let mut b = DMatrix::zeros(m, 4);
    let mut l = DVector::zeros(m);
    for (j, &i) in idx.iter().enumerate() {
        let d = sat[i] - r;
        let range = d.norm();
        for c in 0..3 {
            b[(j, c)] = -d[c] / range;
        }
        b[(j, 3)] = 1.0;
        l[j] = rho[i] - (range + x[3]);
    }
    (b, l)
}

impl FdeModel for PositionModel<'_> {
    fn unknowns(&self) -> usize {
        4
    }

    fn solve(
        &mut self,
        idx: &[usize],
        dinv: &DMatrix<f64>,
        cfg: &FdeConfig,
    ) -> Option<(DMatrix<f64>, DVector<f64>)> {
        // Each subset starts from the caller's start value, so an exclusion does not inherit a
        // solution pulled by the excluded observation.
        self.x = self.x0;
        let (sat, rho) = (self.sat, self.rho);
        gauss_newton(
            &mut self.x,
            |x| position_linearise(sat, rho, x, idx),
            dinv,
            cfg.max_iterations,
            cfg.tolerance,
        )
    }

    fn solution(&self) -> DVector<f64> {
        DVector::from_row_slice(&self.x)
    }
}

/// Pseudorange rates `ρ̇_i = u_iᵀ(v_s,i − v) + d + ε_i` → ECEF velocity v (m/s) and clock drift
/// d (m/s), with `u_i` the unit line of sight from the receiver to satellite i.
#[derive(Debug, Clone)]
pub struct RateModel<'a> {
    /// Unit lines of sight (ECEF).
    pub los: &'a [Vector3<f64>],
    /// Satellite ECEF velocities (m/s).
    pub sat_vel: &'a [Vector3<f64>],
    /// Pseudorange rates (m/s).
    pub rate: &'a [f64],
    x: DVector<f64>,
}

impl<'a> RateModel<'a> {
    /// A rate model.
    pub fn new(los: &'a [Vector3<f64>], sat_vel: &'a [Vector3<f64>], rate: &'a [f64]) -> Self {
        RateModel {
            los,
            sat_vel,
            rate,
            x: DVector::zeros(4),
        }
    }
}

impl FdeModel for RateModel<'_> {
    fn unknowns(&self) -> usize {
        4
    }

    fn solve(
        &mut self,
        idx: &[usize],
        dinv: &DMatrix<f64>,
        _cfg: &FdeConfig,
    ) -> Option<(DMatrix<f64>, DVector<f64>)> {
        let m = idx.len();
        let mut b = DMatrix::zeros(m, 4);
        let mut l = DVector::zeros(m);
        for (j, &i) in idx.iter().enumerate() {
            let u = &self.los[i];
            for c in 0..3 {
                b[(j, c)] = -u[c];
            }
            b[(j, 3)] = 1.0;
            l[j] = self.rate[i] - u.dot(&self.sat_vel[i]);
        }
        let f = dinv * &b;
        self.x = Cholesky::new(b.transpose() * &f)?.solve(&(f.transpose() * &l));
        if !self.x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let l0 = &l - &b * &self.x;
        Some((b, l0))
    }

    fn solution(&self) -> DVector<f64> {
        self.x.clone()
    }
}

/// Pseudoranges and rates of the same m satellites together (observations `0..m`
/// pseudoranges, `m..2m` rates; u = 8: position, clock bias, velocity, clock drift), so one
/// global test covers both observables, as the filter's innovation test does. The two blocks
/// are independent (`D` block-diagonal); each is solved by its own model.
#[derive(Debug, Clone)]
pub struct StackedModel<'a> {
    /// Pseudorange part.
    pub position: PositionModel<'a>,
    /// Rate part (lines of sight from the true geometry).
    pub rate: RateModel<'a>,
}

impl FdeModel for StackedModel<'_> {
    fn unknowns(&self) -> usize {
        8
    }

    fn solve(
        &mut self,
        idx: &[usize],
        dinv: &DMatrix<f64>,
        cfg: &FdeConfig,
    ) -> Option<(DMatrix<f64>, DVector<f64>)> {
        let m = self.position.rho.len();
        let split = idx.iter().position(|&i| i >= m).unwrap_or(idx.len());
        let (ip, ir): (Vec<usize>, Vec<usize>) = (
            idx[..split].to_vec(),
            idx[split..].iter().map(|i| i - m).collect(),
        );
        if ip.len() < 4 || ir.len() < 4 {
            return None;
        }
        let dp = dinv.view((0, 0), (split, split)).into_owned();
        let dr = dinv.view((split, split), (ir.len(), ir.len())).into_owned();
        let (bp, lp) = self.position.solve(&ip, &dp, cfg)?;
        let (br, lr) = self.rate.solve(&ir, &dr, cfg)?;
        let mut b = DMatrix::zeros(idx.len(), 8);
        b.view_mut((0, 0), (split, 4)).copy_from(&bp);
        b.view_mut((split, 4), (ir.len(), 4)).copy_from(&br);
        let mut l = DVector::zeros(idx.len());
        l.rows_mut(0, split).copy_from(&lp);
        l.rows_mut(split, ir.len()).copy_from(&lr);
        Some((b, l))
    }

    fn solution(&self) -> DVector<f64> {
        let mut x = DVector::zeros(8);
        x.rows_mut(0, 4).copy_from(&self.position.solution());
        x.rows_mut(4, 4).copy_from(&self.rate.solution());
        x
    }
}

/// Result of [`snapshot_fde`].
#[derive(Debug, Clone, PartialEq)]
pub struct SnapshotResult {
    /// ECEF position (m), None when there is no solution.
    pub position: Option<Vector3<f64>>,
    /// Receiver clock bias c·δt (m), None when there is no solution.
    pub clock: Option<f64>,
    /// The exclusion loop's outcome (statistic, threshold, dof, w, excluded, status, reason).
    pub fde: FdeOutcome,
}

/// Snapshot position + clock with FDE from pseudoranges. `sat` (n) ECEF positions (m), `rho`
/// (n) pseudoranges (m), `cov` σ (m) or a full covariance (m²), `x0` start `[x, y, z, b]`
/// (default: the Earth's centre and zero clock). Inputs are validated.
pub fn snapshot_fde(
    sat: &[Vector3<f64>],
    rho: &[f64],
    cov: &ObsCov,
    cfg: &FdeConfig,
    x0: Option<[f64; 4]>,
) -> Result<SnapshotResult> {
    let n = rho.len();
    if sat.len() != n {
        return Err(Error::Shape {
            name: "sat_pos".into(),
            expected: format!("({n}, 3) to match pseudoranges ({n},)"),
            got: format!("({}, 3)", sat.len()),
        });
    }
    if let Some((i, s)) = sat
        .iter()
        .enumerate()
        .find(|(_, s)| !s.iter().all(|v| v.is_finite()))
    {
        return Err(Error::NonFinite {
            name: "sat_pos".into(),
            index: format!("[{i}]"),
            value: s
                .iter()
                .copied()
                .find(|v| !v.is_finite())
                .unwrap_or(f64::NAN),
        });
    }
    if let Some((i, v)) = rho.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(Error::NonFinite {
            name: "pseudoranges".into(),
            index: format!("[{i}]"),
            value: *v,
        });
    }
    check_size("snapshot_fde", n)?;
    cov.validate("sigma", n)?;
    let x0 = x0.unwrap_or([0.0; 4]);
    if let Some(v) = x0.iter().find(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            name: "x0".into(),
            index: "[..]".into(),
            value: *v,
        });
    }
    let mut model = PositionModel::new(sat, rho, x0);
    let out = fde(&mut model, cov, &vec![true; n], None, cfg)?;
    let (position, clock) = match &out.solution {
        Some(s) => (Some(Vector3::new(s[0], s[1], s[2])), Some(s[3])),
        None => (None, None),
    };
    Ok(SnapshotResult {
        position,
        clock,
        fde: out,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gnss::constellation::gps;
    use crate::gnss::geodesy::{elevation_azimuth, lla_to_ecef};

    fn scene(t: f64) -> (Vector3<f64>, Vec<Vector3<f64>>) {
        let (lat, lon) = (0.6, 1.9);
        let rx = lla_to_ecef(lat, lon, 50.0);
        let sats: Vec<_> = gps()
            .iter()
            .map(|o| o.ecef(t).0)
            .filter(|s| elevation_azimuth(&rx, lat, lon, s).0 > 10f64.to_radians())
            .collect();
        (rx, sats)
    }

    /// Two equal biases at once: every pair of satellites of a scene biased by 40 σ. Where the
    /// largest |w| of the all-satellite solution is a healthy satellite (the two faults swamp
    /// it), the loop's first exclusion is wrong; the pair check then finds the two.
    #[test]
    fn two_faults_are_excluded_together_even_when_they_swamp_a_healthy_satellite() {
        let (rx, sats) = scene(3000.0);
        let n = sats.len();
        let cfg = FdeConfig::new(0.01, None).unwrap();
        let blind = FdeConfig::new(0.01, Some(1e9)).unwrap();
        let (mut swamped, mut exact, mut pairs) = (0, 0, 0);
        for a in 0..n {
            for b in a + 1..n {
                let mut rho: Vec<f64> = sats.iter().map(|s| (s - rx).norm()).collect();
                rho[a] += 40.0;
                rho[b] += 40.0;
                let cov = ObsCov::Sigma(vec![1.0; n]);
                // K = 1e9: nothing is identified, w is the all-satellite solution's.
                let all = snapshot_fde(&sats, &rho, &cov, &blind, None).unwrap();
                let worst = (0..n)
                    .max_by(|&i, &j| all.fde.w[i].abs().total_cmp(&all.fde.w[j].abs()))
                    .unwrap();
                let r = snapshot_fde(&sats, &rho, &cov, &cfg, None).unwrap();
                let mut got = r.fde.excluded.clone();
                got.sort_unstable();
                pairs += 1;
                exact += usize::from(got == vec![a, b]);
                if worst != a && worst != b {
                    swamped += 1;
                    assert_eq!(got, vec![a, b], "pair {a}, {b} (largest |w| at {worst})");
                }
            }
        }
        assert!(
            swamped > 0,
            "no pair of this scene swamps a healthy satellite"
        );
        assert_eq!(exact, pairs, "{exact} of {pairs} pairs excluded exactly");
    }

    #[test]
    fn exact_ranges_give_the_position_and_pass() {
        let (rx, sats) = scene(0.0);
        assert!(sats.len() >= 6, "{}", sats.len());
        let rho: Vec<f64> = sats.iter().map(|s| (s - rx).norm() + 1234.5).collect();
        let cfg = FdeConfig::new(0.05, None).unwrap();
        let r = snapshot_fde(
            &sats,
            &rho,
            &ObsCov::Sigma(vec![3.0; sats.len()]),
            &cfg,
            None,
        )
        .unwrap();
        assert_eq!(r.fde.status, FdeStatus::Passed);
        assert!((r.position.unwrap() - rx).norm() < 1e-3);
        assert!((r.clock.unwrap() - 1234.5).abs() < 1e-3);
        assert!(r.fde.statistic < 1e-6);
        assert_eq!(r.fde.dof, sats.len() - 4);
    }

    #[test]
    fn a_large_fault_is_excluded_and_too_few_is_no_solution() {
        let (rx, sats) = scene(3000.0);
        let n = sats.len();
        let mut rho: Vec<f64> = sats.iter().map(|s| (s - rx).norm()).collect();
        rho[2] += 100.0;
        let cfg = FdeConfig::new(0.05, None).unwrap();
        let r = snapshot_fde(&sats, &rho, &ObsCov::Sigma(vec![1.0; n]), &cfg, None).unwrap();
        assert_eq!(r.fde.excluded, vec![2]);
        assert_eq!(r.fde.status, FdeStatus::Excluded);
        assert!(r.fde.w[2].is_nan());
        let r = snapshot_fde(
            &sats[..4],
            &rho[..4],
            &ObsCov::Sigma(vec![1.0; 4]),
            &cfg,
            None,
        )
        .unwrap();
        assert_eq!(r.fde.status, FdeStatus::NoSolution);
        assert!(r.position.is_none());
        // Five satellites: the fault is detected (one degree of freedom) but excluding one
        // would leave four, too few to test: unidentified, with the all-satellite solution.
        let r = snapshot_fde(
            &sats[..5],
            &rho[..5],
            &ObsCov::Sigma(vec![1.0; 5]),
            &cfg,
            None,
        )
        .unwrap();
        assert_eq!(r.fde.status, FdeStatus::Unidentified);
        assert!(r.position.is_some() && r.fde.excluded.is_empty());
    }

    #[test]
    fn bad_inputs_are_named() {
        let cfg = FdeConfig::new(0.05, None).unwrap();
        let sats = vec![Vector3::new(2e7, 0.0, 0.0); 3];
        let e =
            snapshot_fde(&sats, &[1.0, 2.0], &ObsCov::Sigma(vec![1.0; 2]), &cfg, None).unwrap_err();
        assert!(e.to_string().contains("sat_pos"), "{e}");
        let e = snapshot_fde(
            &sats,
            &[1.0, 2.0, f64::NAN],
            &ObsCov::Sigma(vec![1.0; 3]),
            &cfg,
            None,
        )
        .unwrap_err();
        assert!(e.to_string().contains("pseudoranges"), "{e}");
        let e = snapshot_fde(
            &sats,
            &[1.0; 3],
            &ObsCov::Sigma(vec![1.0, -1.0, 1.0]),
            &cfg,
            None,
        )
        .unwrap_err();
        assert!(e.to_string().contains("sigma[1]"), "{e}");
        assert!(FdeConfig::new(1.5, None).is_err());
        assert!(FdeConfig::new(0.05, Some(-1.0)).is_err());
        assert!((two_sided_quantile(0.1).unwrap() - 1.6449).abs() < 1e-4);
    }
}
