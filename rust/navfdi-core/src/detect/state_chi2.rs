//! State chi-square test with two propagators (METHODS §8, paper 003).
//!
//! A propagator follows the filter's model without measurements: `X_s(k) = Φ_k X_s(k−1)`,
//! `P_s(k) = Φ_k P_s Φ_kᵀ + Q_k`. Against the filter's updated estimate `X̂(k)`, `P(k)`:
//! `β = X̂ − X_s`, `V = P_s − P` and `λ = βᵀV⁻¹β ~ χ²(d)` under no fault, `d` the number of
//! tested states (all, or a chosen subset). A fault the filter slowly follows pulls `X̂` away
//! from the propagator, which measurements do not touch; the residual test may not see it.
//!
//! **Resolution** (METHODS §8): two propagators are reset alternately from the filter's output
//! every `reset_every` epochs (A at 0, 2Δ, 4Δ, …; B at Δ, 3Δ, …); the test uses the one reset
//! longer ago, only once its age is at least `min_age` epochs (before that the decision says
//! `ready = false`, statistic NaN, no alarm). `V` is factored with a Cholesky decomposition of
//! its correlation form; when that fails or its condition exceeds `1e12` the decision says
//! `ill_conditioned = true` with a NaN statistic and no alarm, instead of dividing by it.
//! Order within an epoch: propagate, test, then reset the propagator due at this epoch.

use crate::error::{Error, Result};
use crate::stats::chi2_threshold;
use crate::validate::check_probability;
use nalgebra::{Cholesky, DMatrix, DVector};

/// Condition number of the correlation form of V above which the test is not made.
pub const MAX_CONDITION: f64 = 1e12;

/// One propagator.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct Propagator {
    x: DVector<f64>,
    p: DMatrix<f64>,
    /// Epochs since its last reset; None before its first reset.
    age: Option<u64>,
}

/// One epoch's decision of the state chi-square test.
#[derive(Debug, Clone, PartialEq)]
pub struct StateDecision {
    /// `λ = βᵀV⁻¹β` (NaN when not tested).
    pub statistic: f64,
    /// Threshold `F⁻¹_{χ²(d)}(1 − pf)`.
    pub threshold: f64,
    /// Fault declared this epoch.
    pub alarm: bool,
    /// Number of tested states d.
    pub dof: usize,
    /// Propagator tested (0 or 1), None when not tested.
    pub propagator: Option<usize>,
    /// Its age in epochs (0 when not tested).
    pub age: u64,
    /// A propagator old enough existed (the age rule is met).
    pub ready: bool,
    /// V could not be factored safely; nothing was tested.
    pub ill_conditioned: bool,
}

impl From<StateDecision> for super::Decision {
    /// The decision as any detector's (statistic, threshold, alarm, dof).
    fn from(d: StateDecision) -> Self {
        super::Decision {
            statistic: d.statistic,
            threshold: d.threshold,
            alarm: d.alarm,
            dof: d.dof,
        }
    }
}

/// Dual-propagator state chi-square detector.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StateChi2 {
    pf: f64,
    threshold: f64,
    reset_every: u64,
    min_age: u64,
    states: Vec<usize>,
    n: usize,
    epoch: u64,
    props: [Propagator; 2],
    /// Propagators already advanced to the current epoch ([`StateChi2::advance`]).
    #[serde(default)]
    advanced: bool,
}

impl StateChi2 {
    /// `pf` in (0, 1); `n` filter states; `reset_every` Δ ≥ 1 epochs; `min_age` ≤ `reset_every`
    /// epochs (≥ 1); `states` the tested state indices (None: all n).
    pub fn new(
        pf: f64,
        n: usize,
        reset_every: u64,
        min_age: u64,
        states: Option<Vec<usize>>,
    ) -> Result<Self> {
        check_probability("pf", pf)?;
        if n == 0 {
            return Err(Error::InvalidParameter {
                name: "n".into(),
                value: 0.0,
                requirement: "the filter must have at least one state".into(),
            });
        }
        if reset_every == 0 {
            return Err(Error::InvalidParameter {
                name: "reset_every".into(),
                value: 0.0,
                requirement: "propagators are reset every reset_every >= 1 epochs".into(),
            });
        }
        if min_age == 0 || min_age > reset_every {
            return Err(Error::InvalidParameter {
                name: "min_age".into(),
                value: min_age as f64,
                requirement: format!(
                    "must be in 1 ..= reset_every ({reset_every}): the older propagator's age is at least reset_every once both run"
                ),
            });
        }
        crate::memory::check(
            "StateChi2",
            6.0 * (n as f64).powi(2) * 8.0,
            &format!("two propagators of {n} states with their n × n covariances"),
            "use fewer states",
        )?;
        let states = states.unwrap_or_else(|| (0..n).collect());
        if states.is_empty() {
            return Err(Error::Invalid(
                "states: at least one state must be tested".into(),
            ));
        }
        for (i, &s) in states.iter().enumerate() {
            if s >= n {
                return Err(Error::Invalid(format!(
                    "states[{i}]: index {s} out of range for {n} states"
                )));
            }
            if states[..i].contains(&s) {
                return Err(Error::Invalid(format!(
                    "states[{i}]: state {s} is listed twice"
                )));
            }
        }
        let threshold = chi2_threshold(pf, states.len())?;
        let empty = Propagator {
            x: DVector::zeros(n),
            p: DMatrix::zeros(n, n),
            age: None,
        };
        Ok(StateChi2 {
            pf,
            threshold,
            reset_every,
            min_age,
            states,
            n,
            epoch: 0,
            props: [empty.clone(), empty],
            advanced: false,
        })
    }

    /// False-alarm probability per epoch.
    pub fn pf(&self) -> f64 {
        self.pf
    }

    /// Threshold `F⁻¹_{χ²(d)}(1 − pf)`.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Tested state indices.
    pub fn states(&self) -> &[usize] {
        &self.states
    }

    /// Number of filter states.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Check that a deserialised detector is self-consistent (sizes and indices), so that a
    /// tampered pickle cannot make a later step index out of range.
    pub fn check_consistent(&self) -> Result<()> {
        let n = self.n;
        let ok = n > 0
            && self.reset_every > 0
            && (1..=self.reset_every).contains(&self.min_age)
            && !self.states.is_empty()
            && self.states.iter().all(|&s| s < n)
            && self
                .props
                .iter()
                .all(|p| p.x.len() == n && p.p.shape() == (n, n));
        if ok {
            Ok(())
        } else {
            Err(Error::Invalid(
                "inconsistent state chi-square detector state".into(),
            ))
        }
    }

    /// Check one epoch's inputs (shapes and finiteness) without changing anything.
    pub fn check(
        &self,
        x: &DVector<f64>,
        p: &DMatrix<f64>,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
    ) -> Result<()> {
        let n = self.n;
        crate::validate::check_len("x", x, n)?;
        crate::validate::check_finite_vector("x", x)?;
        crate::validate::check_shape("P", p, n, n)?;
        crate::validate::check_covariance("P", p)?;
        crate::validate::check_shape("Phi", phi, n, n)?;
        crate::validate::check_finite_matrix("Phi", phi)?;
        crate::validate::check_shape("Q", q, n, n)?;
        crate::validate::check_covariance("Q", q)
    }

    /// One epoch: `phi`, `q` the transition and process noise from the previous epoch to this
    /// one (ignored at the first epoch), `x`, `p` the filter's updated estimate. Inputs are
    /// validated; on error nothing changes.
    pub fn step(
        &mut self,
        x: &DVector<f64>,
        p: &DMatrix<f64>,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
    ) -> Result<StateDecision> {
        self.check(x, p, phi, q)?;
        Ok(self.step_trusted(x, p, phi, q))
    }

    /// [`StateChi2::step`] without validation (inside whole runs): [`StateChi2::advance`],
    /// [`StateChi2::test`] of `x`, `p`, then [`StateChi2::finish`] with them.
    pub fn step_trusted(
        &mut self,
        x: &DVector<f64>,
        p: &DMatrix<f64>,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
    ) -> StateDecision {
        self.advance(phi, q);
        let out = self.test(x, p, self.threshold);
        self.finish(x, p);
        out
    }

    /// Propagate the running propagators to this epoch with `phi`, `q` (no-op at the first
    /// epoch, and when already advanced this epoch). Unvalidated: n × n finite inputs.
    pub fn advance(&mut self, phi: &DMatrix<f64>, q: &DMatrix<f64>) {
        if self.epoch == 0 || self.advanced {
            return;
        }
        for pr in self.props.iter_mut() {
            if let Some(age) = pr.age.as_mut() {
                pr.x = phi * &pr.x;
                pr.p = phi * &pr.p * phi.transpose() + q;
                crate::validate::symmetrize(&mut pr.p);
                *age += 1;
            }
        }
        self.advanced = true;
    }

    /// The propagator reset longer ago and its age, once that age is at least `min_age`
    /// (None: the age rule is not met yet).
    pub fn older(&self) -> Option<(usize, u64)> {
        (0..2)
            .filter_map(|i| self.props[i].age.map(|a| (i, a)))
            .max_by_key(|&(_, a)| a)
            .filter(|&(_, a)| a >= self.min_age)
    }

    /// The propagator [`StateChi2::finish`] resets at this epoch, if any.
    pub fn reset_due(&self) -> Option<usize> {
        self.epoch
            .is_multiple_of(self.reset_every)
            .then(|| ((self.epoch / self.reset_every) % 2) as usize)
    }

    /// Test the filter's estimate `x`, `p` of this epoch (after [`StateChi2::advance`]) against
    /// the propagator reset longer ago, with `threshold`: `β = x − X_s`, `V = P_s − p` on the
    /// tested states. Unvalidated: n-vector, n × n.
    pub fn test(&self, x: &DVector<f64>, p: &DMatrix<f64>, threshold: f64) -> StateDecision {
        self.test_with(|_| Some((x, p)), threshold)
    }

    /// [`StateChi2::test`] of the estimate `estimate(i)` paired with propagator `i` (None: not
    /// tested). Paper 003's per-sensor test pairs each propagator with a sub-filter reset from
    /// the same filter output at the same epoch and updated since by one sensor alone: both
    /// start from the same state, so `V = P_s − P_i` is the covariance of `β` under no fault
    /// (its eq. 25).
    pub fn test_with<'a>(
        &self,
        estimate: impl Fn(usize) -> Option<(&'a DVector<f64>, &'a DMatrix<f64>)>,
        threshold: f64,
    ) -> StateDecision {
        let d = self.states.len();
        let mut out = StateDecision {
            statistic: f64::NAN,
            threshold,
            alarm: false,
            dof: d,
            propagator: None,
            age: 0,
            ready: false,
            ill_conditioned: false,
        };
        let Some((i, age)) = self.older() else {
            return out;
        };
        let Some((x, p)) = estimate(i) else {
            return out;
        };
        out.ready = true;
        out.propagator = Some(i);
        out.age = age;
        let pr = &self.props[i];
        let beta = DVector::from_iterator(d, self.states.iter().map(|&s| x[s] - pr.x[s]));
        let v = DMatrix::from_fn(d, d, |a, b| {
            let (sa, sb) = (self.states[a], self.states[b]);
            pr.p[(sa, sb)] - p[(sa, sb)]
        });
        match whitened_statistic(&beta, &v) {
            Some(l) => {
                out.statistic = l;
                out.alarm = l >= threshold;
            }
            None => out.ill_conditioned = true,
        }
        out
    }

    /// End the epoch: reset the propagator due at it from the filter's `x`, `p`.
    pub fn finish(&mut self, x: &DVector<f64>, p: &DMatrix<f64>) {
        if let Some(i) = self.reset_due() {
            let pr = &mut self.props[i];
            pr.x.copy_from(x);
            pr.p.copy_from(p);
            pr.age = Some(0);
        }
        self.epoch += 1;
        self.advanced = false;
    }
}

/// `βᵀV⁻¹β` through the correlation form of V (scaled to unit diagonal, Cholesky, condition
/// from the factor's diagonal); None when V is not safely positive definite.
fn whitened_statistic(beta: &DVector<f64>, v: &DMatrix<f64>) -> Option<f64> {
    let d = beta.len();
    let s: Vec<f64> = (0..d).map(|i| v[(i, i)]).collect();
    if s.iter().any(|x| !(*x > 0.0 && x.is_finite())) {
        return None;
    }
    let s: Vec<f64> = s.iter().map(|x| x.sqrt()).collect();
    let c = DMatrix::from_fn(d, d, |a, b| v[(a, b)] / (s[a] * s[b]));
    let chol = Cholesky::new(c)?;
    let l = chol.l_dirty();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for i in 0..d {
        lo = lo.min(l[(i, i)].abs());
        hi = hi.max(l[(i, i)].abs());
    }
    // cond(C) ≥ (max/min diagonal of L)²; refuse near-singular forms.
    if !(lo > 0.0) || (hi / lo).powi(2) > MAX_CONDITION {
        return None;
    }
    let b = DVector::from_fn(d, |i, _| beta[i] / s[i]);
    let w = l.solve_lower_triangular(&b)?;
    let stat = w.norm_squared();
    if stat.is_finite() {
        return Some(stat);
    }
    // Overflow (a state difference near the largest float): the same with β scaled by its
    // largest magnitude; the statistic is then +inf, the largest evidence of a fault.
    let c = b.amax();
    if !(c > 0.0 && c.is_finite()) {
        return Some(f64::INFINITY);
    }
    let w = l.solve_lower_triangular(&(b / c))?;
    Some(c * c * w.norm_squared())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_age_rule_and_ill_conditioning() {
        let n = 2;
        let mut d = StateChi2::new(0.01, n, 5, 3, None).unwrap();
        let phi = DMatrix::identity(n, n);
        let q = DMatrix::identity(n, n) * 0.1;
        let p = DMatrix::identity(n, n) * 0.05;
        let x = DVector::zeros(n);
        let mut ages = Vec::new();
        for _ in 0..15 {
            let r = d.step(&x, &p, &phi, &q).unwrap();
            ages.push((r.ready, r.propagator, r.age));
        }
        // Propagator 0 reset at 0, 10; propagator 1 at 5: the older is ≥ 5 once both run.
        assert_eq!(ages[2], (false, None, 0));
        assert_eq!(ages[3], (true, Some(0), 3));
        assert_eq!(ages[7], (true, Some(0), 7));
        assert_eq!(ages[10], (true, Some(0), 10)); // tested before its reset at epoch 10
        assert_eq!(ages[11], (true, Some(1), 6));
        // V = P_s − P = 0 (no process noise, P unchanged): reported, not divided by.
        let mut z = StateChi2::new(0.01, n, 5, 1, None).unwrap();
        let q0 = DMatrix::zeros(n, n);
        z.step(&x, &p, &phi, &q0).unwrap();
        let r = z.step(&x, &p, &phi, &q0).unwrap();
        assert!(r.ready && r.ill_conditioned && r.statistic.is_nan() && !r.alarm);
        // Bad parameters are named.
        assert!(StateChi2::new(0.01, 2, 5, 6, None)
            .unwrap_err()
            .to_string()
            .contains("min_age"));
        assert!(StateChi2::new(0.01, 2, 0, 1, None)
            .unwrap_err()
            .to_string()
            .contains("reset_every"));
        assert!(StateChi2::new(0.01, 2, 5, 1, Some(vec![2]))
            .unwrap_err()
            .to_string()
            .contains("states[0]"));
        assert!(z
            .step(&DVector::zeros(3), &p, &phi, &q)
            .unwrap_err()
            .to_string()
            .contains('x'));
    }
}
