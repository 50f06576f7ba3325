//! Weighted least squares and its tests (METHODS §10), below the exclusion loop of
//! [`super::snapshot`]: observation covariances ([`ObsCov`], with the scaled form used when σ
//! would over- or underflow), the test settings ([`FdeConfig`]), the linear test of `l = B x +
//! ε` ([`ls_test`]: residuals, their covariance, the global statistic and the general w-test),
//! Gauss-Newton for nonlinear models and the [`FdeModel`] trait the exclusion loop solves.

use crate::error::{Error, Result};
use crate::stats::chi2_threshold;
use nalgebra::{Cholesky, DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, Normal};

/// Observation covariance: independent observations with standard deviations σ_i, or a full
/// symmetric positive-definite matrix.
#[derive(Debug, Clone, PartialEq)]
pub enum ObsCov {
    /// σ per observation (same unit as the observations).
    Sigma(Vec<f64>),
    /// Full covariance (n × n).
    Full(DMatrix<f64>),
}

impl ObsCov {
    /// Number of observations it describes.
    pub fn len(&self) -> usize {
        match self {
            ObsCov::Sigma(s) => s.len(),
            ObsCov::Full(m) => m.nrows(),
        }
    }

    /// True when it describes no observation.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Check values: positive finite σ, or a symmetric positive-definite matrix.
    pub fn validate(&self, name: &str, n: usize) -> Result<()> {
        match self {
            ObsCov::Sigma(s) => {
                if s.len() != n {
                    return Err(Error::Shape {
                        name: name.into(),
                        expected: format!("({n},) or ({n}, {n})"),
                        got: format!("({},)", s.len()),
                    });
                }
                if let Some((i, v)) = s
                    .iter()
                    .enumerate()
                    .find(|(_, v)| !(**v > 0.0 && v.is_finite()))
                {
                    return Err(Error::InvalidParameter {
                        name: format!("{name}[{i}]"),
                        value: *v,
                        requirement: "a standard deviation must be positive and finite".into(),
                    });
                }
                Ok(())
            }
            ObsCov::Full(m) => {
                crate::validate::check_shape(name, m, n, n)?;
                crate::validate::check_finite_matrix(name, m)?;
                crate::validate::check_symmetric(name, m)?;
                if Cholesky::new(m.clone()).is_none() {
                    return Err(Error::NotPositiveDefinite {
                        name: name.into(),
                        detail: "an observation covariance must be positive definite".into(),
                    });
                }
                Ok(())
            }
        }
    }

    /// The covariance divided by `c²` and `c`, where `c` (a standard deviation) brings the
    /// σ into the range where their squares and inverses are finite (σ beyond 1e±100, e.g.
    /// every σ = 1e-200 or 1e200); `c = 1` (and the covariance as it is) otherwise. The
    /// solution does not depend on `c`; statistics scale by `1/c²` and w by `1/c`.
    pub fn normalised(&self) -> (std::borrow::Cow<'_, ObsCov>, f64) {
        let diag: Vec<f64> = match self {
            ObsCov::Sigma(s) => s.clone(),
            ObsCov::Full(m) => m.diagonal().iter().map(|v| v.sqrt()).collect(),
        };
        let lo = diag.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = diag.iter().copied().fold(0.0, f64::max);
        if diag.is_empty() || (lo >= 1e-100 && hi <= 1e100) {
            return (std::borrow::Cow::Borrowed(self), 1.0);
        }
        let c = lo.sqrt() * hi.sqrt();
        let out = match self {
            ObsCov::Sigma(s) => ObsCov::Sigma(s.iter().map(|v| v / c).collect()),
            ObsCov::Full(m) => ObsCov::Full(m.map(|v| v / c / c)),
        };
        (std::borrow::Cow::Owned(out), c)
    }

    /// `D⁻¹` restricted to the observations `idx` (the inverse of the sub-matrix).
    pub(crate) fn inverse_sub(&self, idx: &[usize]) -> Option<DMatrix<f64>> {
        match self {
            ObsCov::Sigma(s) => Some(DMatrix::from_diagonal(&DVector::from_iterator(
                idx.len(),
                idx.iter().map(|&i| 1.0 / (s[i] * s[i])),
            ))),
            ObsCov::Full(m) => {
                let sub = m.select_rows(idx).select_columns(idx);
                Cholesky::new(sub).map(|c| c.inverse())
            }
        }
    }

    pub(crate) fn sub(&self, idx: &[usize]) -> DMatrix<f64> {
        match self {
            ObsCov::Sigma(s) => DMatrix::from_diagonal(&DVector::from_iterator(
                idx.len(),
                idx.iter().map(|&i| s[i] * s[i]),
            )),
            ObsCov::Full(m) => m.select_rows(idx).select_columns(idx),
        }
    }
}

/// The two-sided standard-normal quantile `N⁻¹(1 − α/2)` (the default w-test critical value).
pub fn two_sided_quantile(alpha: f64) -> Result<f64> {
    crate::validate::check_probability("alpha", alpha)?;
    let n = Normal::new(0.0, 1.0).map_err(|e| Error::Numerical {
        context: "normal quantile".into(),
        detail: e.to_string(),
    })?;
    Ok(n.inverse_cdf(1.0 - alpha / 2.0))
}

/// What opens the exclusion loop's door (METHODS §10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Detection {
    /// The global χ² test at α; the largest |w| above K identifies (the default).
    #[default]
    Global,
    /// Data snooping: the largest |w| of the n tested observations above `k0 =
    /// z(1 − α0/2)`, with `α0 = 1 − (1 − α)^(1/n)` (Šidák: the epoch's false-alarm probability
    /// is α for independent w, below it for correlated ones); it also identifies. More
    /// powerful than the global test for one faulty observation among many (large
    /// redundancy), less with few.
    WTest,
    /// Either, each at α/2 (so that the union holds α): the largest |w| above its `k0`, or the
    /// global test (then identified as by [`Detection::Global`]).
    Both,
    /// Per tested set, the one of [`Detection::Global`] and [`Detection::WTest`] (each at α)
    /// with the smaller minimal detectable bias for one faulty observation: the w-test when
    /// its non-centrality at the power β0 is below the global test's (many observations),
    /// else the global test. One test at α per set, so α holds.
    Auto,
}

impl Detection {
    /// Parse `global`, `wtest` or `both`.
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "global" => Ok(Detection::Global),
            "wtest" => Ok(Detection::WTest),
            "both" => Ok(Detection::Both),
            "auto" => Ok(Detection::Auto),
            _ => Err(Error::Invalid(format!(
                "test = {s:?}: one of \"global\" (the χ² test), \"wtest\" (data snooping), \"both\" or \"auto\" (the more powerful of the two per epoch)"
            ))),
        }
    }

    /// The name [`Detection::parse`] reads.
    pub fn as_str(self) -> &'static str {
        match self {
            Detection::Global => "global",
            Detection::WTest => "wtest",
            Detection::Both => "both",
            Detection::Auto => "auto",
        }
    }
}

/// The default power β0 at which minimal detectable biases are reported.
pub const DEFAULT_POWER: f64 = 0.8;

/// Non-centrality `λ` at which the two-sided w-test with critical value `k0` detects with
/// probability `power`: `P(|N(√λ, 1)| > k0) = power`. Memoised per thread like
/// [`crate::stats::chi2_threshold`].
pub fn w_noncentrality(k0: f64, power: f64) -> Result<f64> {
    crate::stats::memo(2, [k0.to_bits(), power.to_bits(), 0], || {
        w_noncentrality_uncached(k0, power)
    })
}

fn w_noncentrality_uncached(k0: f64, power: f64) -> Result<f64> {
    let n = Normal::new(0.0, 1.0).map_err(|e| Error::Numerical {
        context: "normal".into(),
        detail: e.to_string(),
    })?;
    let p = |d: f64| n.cdf(d - k0) + n.cdf(-d - k0) - power; // increasing in d ≥ 0
    let (mut lo, mut hi) = (0.0, k0 + 40.0);
    if p(lo) >= 0.0 {
        return Err(Error::Invalid(format!(
            "power {power}: reached with no bias at k0 = {k0}; the power must exceed the false-alarm probability"
        )));
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if p(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let d = 0.5 * (lo + hi);
    Ok(d * d)
}

/// The allocation of one tested set (n observations, redundancy dof): the w-test's critical
/// value and per-observation false-alarm probability, the global test's threshold, and the
/// non-centrality behind the reported minimal detectable biases.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snooping {
    /// Non-centrality of the deciding test at power β0: the global test's for
    /// [`Detection::Global`], the w-test's for [`Detection::WTest`], the smaller of the two
    /// (each at α/2) for [`Detection::Both`]. MDB_i = √(λ0 / q_i).
    pub lambda0: f64,
    /// The w-test's critical value.
    pub k0: f64,
    /// Its per-observation false-alarm probability.
    pub alpha0: f64,
    /// The global test's threshold as used (at α/2 for [`Detection::Both`]).
    pub threshold: f64,
    /// The test that decides for this set ([`Detection::Auto`] resolved to `Global` or
    /// `WTest`; the configured one otherwise).
    pub test: Detection,
}

/// Settings of the exclusion loop.
#[derive(Debug, Clone)]
pub struct FdeConfig {
    /// False-alarm probability of the global test.
    pub alpha: f64,
    /// Critical value of the w-test.
    pub k: f64,
    /// What opens the loop (the global test by default).
    pub test: Detection,
    /// Power β0 at which the minimal detectable biases are reported.
    pub power: f64,
    /// Allocations computed so far, by (observations, dof); shared by clones.
    snooping: SnoopCache,
    /// Gauss-Newton iterations allowed per solution.
    pub max_iterations: usize,
    /// Convergence: step norm below this (m).
    pub tolerance: f64,
    thresholds: Vec<std::sync::OnceLock<f64>>,
}

/// Degrees of freedom whose thresholds are computed once (on first use) and kept.
const CACHED_DOF: usize = 64;

impl FdeConfig {
    /// `alpha` ∈ (0, 1); `k` > 0 (default: [`two_sided_quantile`] of `alpha`).
    pub fn new(alpha: f64, k: Option<f64>) -> Result<Self> {
        crate::validate::check_probability("alpha", alpha)?;
        let k = match k {
            Some(k) => {
                if !(k > 0.0 && k.is_finite()) {
                    return Err(Error::InvalidParameter {
                        name: "k".into(),
                        value: k,
                        requirement: "the w-test critical value must be positive and finite".into(),
                    });
                }
                k
            }
            None => two_sided_quantile(alpha)?,
        };
        let thresholds = (0..CACHED_DOF)
            .map(|_| std::sync::OnceLock::new())
            .collect();
        Ok(FdeConfig {
            alpha,
            k,
            test: Detection::Global,
            power: DEFAULT_POWER,
            snooping: SnoopCache::default(),
            max_iterations: 20,
            tolerance: 1e-7,
            thresholds,
        })
    }

    /// The same settings with detection `test` and the power `power` (β0, in (α, 1)) at
    /// which minimal detectable biases are reported.
    pub fn with_test(mut self, test: Detection, power: f64) -> Result<Self> {
        crate::validate::check_probability("power", power)?;
        if power <= self.alpha {
            return Err(Error::InvalidParameter {
                name: "power".into(),
                value: power,
                requirement: format!("must exceed alpha = {}", self.alpha),
            });
        }
        self.test = test;
        self.power = power;
        self.snooping = SnoopCache::default();
        Ok(self)
    }

    /// The allocation of a set of `n` observations with redundancy `dof` (cached).
    pub fn snooping(&self, n: usize, dof: usize) -> Result<Snooping> {
        if let Some(s) = self.snooping.get(n, dof) {
            return Ok(s);
        }
        let a = if self.test == Detection::Both {
            self.alpha / 2.0
        } else {
            self.alpha
        };
        let alpha0 = -(-a).ln_1p() / n.max(1) as f64; // ln(1 − a) / n, then 1 − e^that
        let alpha0 = -(-alpha0).exp_m1();
        let k0 = two_sided_quantile(alpha0)?;
        let lw = w_noncentrality(k0, self.power)?;
        let lg = crate::stats::noncentrality(a, 1.0 - self.power, dof)?;
        let test = match self.test {
            Detection::Auto if lw < lg => Detection::WTest,
            Detection::Auto => Detection::Global,
            t => t,
        };
        let s = Snooping {
            lambda0: match test {
                Detection::Global => lg,
                Detection::WTest => lw,
                _ => lg.min(lw),
            },
            k0,
            alpha0,
            test,
            threshold: if self.test == Detection::Both {
                chi2_threshold(a, dof)?
            } else {
                self.threshold(dof)?
            },
        };
        self.snooping.put(n, dof, s);
        Ok(s)
    }

    /// Global-test threshold `F⁻¹_{χ²(dof)}(1 − α)`.
    pub fn threshold(&self, dof: usize) -> Result<f64> {
        match self.thresholds.get(dof.wrapping_sub(1)) {
            Some(cell) => match cell.get() {
                Some(t) => Ok(*t),
                None => {
                    let t = chi2_threshold(self.alpha, dof)?;
                    Ok(*cell.get_or_init(|| t))
                }
            },
            None => chi2_threshold(self.alpha, dof),
        }
    }
}

/// [`FdeConfig`]'s allocations by (observations, dof), shared by its clones (a campaign's
/// threads); the values depend only on α, the power and the test, fixed per configuration.
#[derive(Debug, Clone, Default)]
struct SnoopCache(
    std::sync::Arc<std::sync::Mutex<std::collections::HashMap<(usize, usize), Snooping>>>,
);

impl SnoopCache {
    fn get(&self, n: usize, dof: usize) -> Option<Snooping> {
        self.0.lock().ok().and_then(|m| m.get(&(n, dof)).copied())
    }

    fn put(&self, n: usize, dof: usize, s: Snooping) {
        if let Ok(mut m) = self.0.lock() {
            m.insert((n, dof), s);
        }
    }
}

/// How the exclusion loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FdeStatus {
    /// The global test passed with every observation.
    Passed,
    /// The global test passed after excluding one or more observations.
    Excluded,
    /// The global test fails but no |w| exceeds K; the solution is kept.
    Unidentified,
    /// Fewer than u + 1 observations, a singular geometry or no convergence: no solution.
    NoSolution,
}

impl FdeStatus {
    /// Lower-case name (`passed`, `excluded`, `unidentified`, `no_solution`).
    pub fn as_str(self) -> &'static str {
        match self {
            FdeStatus::Passed => "passed",
            FdeStatus::Excluded => "excluded",
            FdeStatus::Unidentified => "unidentified",
            FdeStatus::NoSolution => "no_solution",
        }
    }

    /// Small integer code (0–3 in the order above), as recorded per epoch.
    pub fn code(self) -> u8 {
        self as u8
    }
}

/// One linear(ised) test: estimate, residuals and statistics (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LsTest {
    /// Estimated correction x̂ (u).
    pub x: DVector<f64>,
    /// Residuals V = B x̂ − l (n).
    pub v: DVector<f64>,
    /// Residual covariance D_V (n × n).
    pub dv: DMatrix<f64>,
    /// VᵀD⁻¹V.
    pub statistic: f64,
    /// w per observation (NaN where the observation has no redundancy).
    pub w: DVector<f64>,
    /// `e_iᵀ D⁻¹ D_V D⁻¹ e_i` per observation (1/m², the w-test's variance factor; NaN where
    /// the observation has no redundancy): a bias ∇ moves `w_i` by `∇ √q_i`.
    pub q: DVector<f64>,
}

/// The test of `l = B x + ε`, `D⁻¹` given (`d` is `D`). None when `BᵀD⁻¹B` is singular.
pub fn ls_test(
    b: &DMatrix<f64>,
    l: &DVector<f64>,
    d: &DMatrix<f64>,
    dinv: &DMatrix<f64>,
) -> Option<LsTest> {
    let f = dinv * b; // D⁻¹B (n × u)
    let n_mat = b.transpose() * &f;
    let n_inv = Cholesky::new(n_mat)?.inverse();
    let x = &n_inv * (f.transpose() * l);
    let v = b * &x - l;
    let bn = b * &n_inv; // B N⁻¹ (n × u)
    let dv = d - &bn * b.transpose();
    let g = dinv * &v;
    let statistic = v.dot(&g);
    let fn_ = &f * &n_inv; // D⁻¹B N⁻¹
    let n = v.len();
    let q = DVector::from_fn(n, |i, _| {
        // e_iᵀ D⁻¹ D_V D⁻¹ e_i = (D⁻¹)_ii − (D⁻¹B N⁻¹ BᵀD⁻¹)_ii
        let q = dinv[(i, i)] - fn_.row(i).dot(&f.row(i));
        if q > 1e-12 * dinv[(i, i)] {
            q
        } else {
            f64::NAN
        }
    });
    let w = DVector::from_fn(n, |i, _| g[i] / q[i].sqrt());
    Some(LsTest {
        x,
        v,
        dv,
        statistic,
        w,
        q,
    })
}

/// [`ls_test`] on a user's `B` (n × u), `l` (n) and covariance (all validated by the caller),
/// computed in a scaled form when the σ would over- or underflow when squared (results as
/// for the σ given). An error when `BᵀD⁻¹B` is singular or numerically so: a condition number
/// beyond 1e14 (e.g. two proportional columns) leaves the unknowns undetermined.
pub fn ls_test_cov(b: &DMatrix<f64>, l: &DVector<f64>, cov: &ObsCov) -> Result<LsTest> {
    let n = l.len();
    let (scaled, c) = cov.normalised();
    let all: Vec<usize> = (0..n).collect();
    let d = scaled.sub(&all);
    // The inverse through a Cholesky factor of D in both forms (σ or full), so the two agree
    // to the last bits.
    let dinv = Cholesky::new(d.clone())
        .map(|c| c.inverse())
        .ok_or_else(|| Error::NotPositiveDefinite {
            name: "D".into(),
            detail: "the observation covariance cannot be factored".into(),
        })?;
    let n_mat = b.transpose() * (&dinv * b);
    let singular = || Error::Numerical {
        context: "B".into(),
        detail: "BᵀD⁻¹B is singular (the unknowns are not determined by the observations)".into(),
    };
    let chol = Cholesky::new(n_mat.clone()).ok_or_else(singular)?;
    let diag = chol.l_dirty().diagonal();
    let (lo, hi) = diag.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v.abs()), hi.max(v.abs()))
    });
    // cond(N) ≥ (max L_ii / min L_ii)²; beyond 1e14 the solution is rounding noise.
    if !(lo > 0.0) || (hi / lo).powi(2) > 1e14 {
        return Err(Error::Numerical {
            context: "B".into(),
            detail: format!(
                "BᵀD⁻¹B is numerically singular (condition number ≥ {:.1e}: some unknowns are not determined by the observations, e.g. proportional columns)",
                (hi / lo).powi(2)
            ),
        });
    }
    let mut t = ls_test(b, l, &d, &dinv).ok_or_else(singular)?;
    if c != 1.0 {
        t.statistic = t.statistic / c / c;
        t.w.iter_mut().for_each(|w| *w /= c);
        t.dv = t.dv.map(|v| v * c * c);
    }
    Ok(t)
}

/// A measurement model the exclusion loop can solve on any subset of its observations.
pub trait FdeModel {
    /// Number of unknowns u.
    fn unknowns(&self) -> usize;
    /// Solve on the observations `idx` (with `D⁻¹` of that subset) and return `(B, l)`
    /// linearised at the solution (so that `x̂ ≈ 0`); None when the geometry is singular or
    /// the iteration does not converge. The solution is kept in the model.
    fn solve(
        &mut self,
        idx: &[usize],
        dinv: &DMatrix<f64>,
        cfg: &FdeConfig,
    ) -> Option<(DMatrix<f64>, DVector<f64>)>;
    /// The current solution (u).
    fn solution(&self) -> DVector<f64>;
}

/// Gauss-Newton for a nonlinear [`FdeModel`]: from `x` (updated in place), `lin(x)` gives
/// `(B, l)` with `l` = observed − predicted; step `(BᵀD⁻¹B)⁻¹BᵀD⁻¹l` until its norm is below
/// `tolerance`, at most `iterations` times. Returns `(B, l)` at the solution; None when the
/// normal matrix is singular, a step is not finite or the iteration does not converge.
pub fn gauss_newton<F>(
    x: &mut [f64],
    mut lin: F,
    dinv: &DMatrix<f64>,
    iterations: usize,
    tolerance: f64,
) -> Option<(DMatrix<f64>, DVector<f64>)>
where
    F: FnMut(&[f64]) -> (DMatrix<f64>, DVector<f64>),
{
    for _ in 0..iterations {
        let (b, l) = lin(x);
        let f = dinv * &b;
        let dx = Cholesky::new(b.transpose() * &f)?.solve(&(f.transpose() * &l));
        if !dx.iter().all(|v| v.is_finite()) {
            return None;
        }
        for (xi, d) in x.iter_mut().zip(dx.iter()) {
            *xi += d;
        }
        if dx.norm() < tolerance {
            return Some(lin(x));
        }
    }
    None
}

/// Refuse (`MemoryError` in Python) a least-squares problem of `n` observations whose n × n
/// work matrices (about six: D, D⁻¹, D_V and temporaries) would not fit in memory.
pub fn check_size(what: &str, n: usize) -> Result<()> {
    let n = n as f64;
    crate::memory::check(
        what,
        6.0 * n * n * 8.0,
        &format!("{n} observations need n × n work matrices"),
        "give fewer observations per epoch",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snooping_allocation_is_sidak_and_its_power_is_the_one_asked() {
        let cfg = FdeConfig::new(0.01, None)
            .and_then(|c| c.with_test(Detection::WTest, 0.8))
            .unwrap();
        let s = cfg.snooping(10, 5).unwrap();
        // 1 − (1 − α0)^n = α.
        assert!((1.0 - (1.0 - s.alpha0).powi(10) - 0.01).abs() < 1e-12);
        assert!((two_sided_quantile(s.alpha0).unwrap() - s.k0).abs() < 1e-12);
        // P(|N(√λ0, 1)| > k0) = 0.8.
        let n = Normal::new(0.0, 1.0).unwrap();
        let d = s.lambda0.sqrt();
        assert!((n.cdf(d - s.k0) + n.cdf(-d - s.k0) - 0.8).abs() < 1e-9);
        // Both: each at α/2; the global threshold is the χ² quantile at α/2.
        let both = FdeConfig::new(0.01, None)
            .and_then(|c| c.with_test(Detection::Both, 0.8))
            .unwrap();
        let b = both.snooping(10, 5).unwrap();
        assert!(b.k0 > s.k0 && b.threshold > cfg.threshold(5).unwrap());
        // Auto: the w-test with many observations, the global test with few.
        let auto = FdeConfig::new(0.01, None)
            .and_then(|c| c.with_test(Detection::Auto, 0.8))
            .unwrap();
        assert_eq!(auto.snooping(16, 11).unwrap().test, Detection::WTest);
        assert_eq!(auto.snooping(6, 2).unwrap().test, Detection::Global);
        assert!(FdeConfig::new(0.05, None)
            .and_then(|c| c.with_test(Detection::WTest, 0.01))
            .is_err());
        assert!(Detection::parse("chi2").is_err());
    }
}
