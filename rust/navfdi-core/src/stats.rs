//! Detection thresholds and detectability (METHODS §2, §3, §6).
//!
//! * [`chi2_threshold`]: `T_D = F⁻¹_{χ²(dof)}(1 − Pf)` (residual chi-square test).
//! * [`sprt_threshold`]: `T(H1) = ln((1 − Pm)/Pf)` (improved SPRT).
//! * [`noncentrality`]: `λ0` with `F_{χ²(dof, λ0)}(T_D) = Pm` (non-central chi-square).
//! * [`mdb`]: minimal detectable bias per measurement component, `sqrt(λ0 / (A⁻¹)_ii)`.
//! * [`median_of`]: the median the robust scales (MAD) use.
//!
//! The central chi-square distribution comes from `statrs`; the non-central CDF is the
//! Poisson mixture `Σ_j e^{−λ/2}(λ/2)^j/j! · P(χ²(dof + 2j) ≤ x)` with the central terms from
//! `statrs`' regularised incomplete gamma function.

use crate::error::{Error, Result};
use crate::validate::{check_probability, check_symmetric};
use nalgebra::DMatrix;
use statrs::distribution::{ChiSquared, Continuous, ContinuousCDF};
use statrs::function::gamma::{checked_gamma_lr, ln_gamma};

fn check_dof(dof: usize) -> Result<()> {
    if dof == 0 {
        return Err(Error::InvalidParameter {
            name: "dof".into(),
            value: 0.0,
            requirement: "degrees of freedom must be at least 1".into(),
        });
    }
    Ok(())
}

/// The median size of a two-dimensional standard Gaussian (√(2 ln 2), to four decimals): a
/// per-component σ is the median size of 2D errors over it.
pub const RAYLEIGH_MEDIAN: f64 = 1.1774;

/// The median of `v` (reordered; the upper one of an even count); NaN when empty.
pub fn median_of(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Chi-square detection threshold `T_D` with false-alarm probability `pf` and `dof` degrees of
/// freedom: the `1 − pf` quantile of `χ²(dof)`.
///
/// The quantile from `statrs` is polished with Newton steps on the survival function, so small
/// `pf` keep full relative accuracy; below about 1e-16 (where `1 − pf` rounds to 1) the
/// iteration starts from the tail asymptote, so thresholds exist down to `pf` ≈ 1e-300.
///
/// Reference values: `(0.1, 3) → 6.2514`, `(0.005, 6) → 18.548`, `(0.05, 5) → 11.0705`.
///
/// Results are memoised per thread (keyed by the bits of `pf` and `dof`; at most
/// [`THRESHOLD_CACHE`] entries), so callers that build a new configuration per call (the
/// Python API's `snapshot_fde`, say) do not pay for the quantile (≈ 20 µs) every time.
pub fn chi2_threshold(pf: f64, dof: usize) -> Result<f64> {
    check_probability("pf", pf)?;
    check_dof(dof)?;
    memo(0, [pf.to_bits(), dof as u64, 0], || {
        chi2_threshold_uncached(pf, dof)
    })
}

/// Entries kept by the per-thread memo of [`chi2_threshold`], [`noncentrality`] and
/// [`crate::gnss::lsq::w_noncentrality`] before it is cleared.
pub const THRESHOLD_CACHE: usize = 4096;

thread_local! {
    static CACHE: std::cell::RefCell<std::collections::HashMap<(u8, [u64; 3]), f64>> =
        std::cell::RefCell::new(std::collections::HashMap::new());
}

/// `f()` memoised per thread under `(kind, key)` (the bits of the arguments; `kind` tells the
/// functions apart); errors are not kept. At most [`THRESHOLD_CACHE`] entries, then cleared.
pub(crate) fn memo(kind: u8, key: [u64; 3], f: impl FnOnce() -> Result<f64>) -> Result<f64> {
    let key = (kind, key);
    if let Some(t) = CACHE.with(|c| c.borrow().get(&key).copied()) {
        return Ok(t);
    }
    let t = f()?;
    CACHE.with(|c| {
        let mut c = c.borrow_mut();
        if c.len() >= THRESHOLD_CACHE {
            c.clear();
        }
        c.insert(key, t);
    });
    Ok(t)
}

fn chi2_threshold_uncached(pf: f64, dof: usize) -> Result<f64> {
    let dist = ChiSquared::new(dof as f64).map_err(|e| Error::Numerical {
        context: "chi2_threshold".into(),
        detail: e.to_string(),
    })?;
    let mut x = dist.inverse_cdf(1.0 - pf);
    if !(x.is_finite() && x > 0.0) {
        // 1 − pf rounds to 1 for pf below about 1e-16: start from the tail asymptote
        // sf(x) ≈ exp(−x/2)·(x/2)^(dof/2 − 1)/Γ(dof/2), to leading order x ≈ dof − 2 ln pf.
        x = dof as f64 - 2.0 * pf.ln();
    }
    // Newton on ln sf(x) = ln pf (well scaled down to pf ~ 1e-300), safeguarded: keep x
    // positive and stop when converged.
    let target = pf.ln();
    for _ in 0..60 {
        let s = dist.sf(x);
        let d = dist.pdf(x);
        if !(s > 0.0 && d > 0.0) {
            break;
        }
        let step = (s.ln() - target) * s / d;
        let next = x + step;
        let next = if next <= 0.0 { 0.5 * x } else { next };
        let converged = (next - x).abs() <= 1e-15 * x.abs();
        x = next;
        if converged {
            break;
        }
    }
    if !x.is_finite() || x <= 0.0 {
        return Err(Error::Numerical {
            context: "chi2_threshold".into(),
            detail: format!("quantile for pf = {pf:e}, dof = {dof} did not converge"),
        });
    }
    Ok(x)
}

/// The regularised lower incomplete gamma function `P(a, x)` for `a > 0`, total on `x`: 0 at
/// `x ≤ 0` (and where `x` is so small that statrs's scaling makes it 0), 1 at `+∞`, NaN at
/// NaN. statrs 0.19's `gamma_lr` panics for `x = 0` (`XInvalid`), which its own
/// `Gamma::cdf` reaches for any positive `x` below about 1e-308 (the rate scaling
/// underflows): every chi-square probability of navfdi goes through here or
/// [`chi2_sf`] instead.
pub fn lower_gamma(a: f64, x: f64) -> f64 {
    if x.is_nan() || a.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    if x.is_infinite() {
        return 1.0;
    }
    checked_gamma_lr(a, x).unwrap_or(f64::NAN)
}

/// Upper tail `P(χ²(dof) ≥ x)` of the central chi-square, total on `x` (1 at `x ≤ 0` or
/// below the smallest normal float, 0 at `+∞`, NaN at NaN; see [`lower_gamma`] for the
/// statrs bug it avoids). `dof ≥ 1`.
pub fn chi2_sf(dof: usize, x: f64) -> f64 {
    if x.is_nan() || dof == 0 {
        return f64::NAN;
    }
    if !(0.5 * x > 0.0) {
        return 1.0;
    }
    if x.is_infinite() {
        return 0.0;
    }
    statrs::function::gamma::checked_gamma_ur(0.5 * dof as f64, 0.5 * x).unwrap_or(f64::NAN)
}

/// Improved-SPRT threshold `T(H1) = ln((1 − pm)/pf)`.
///
/// Requires `pf + pm < 1` so that the threshold is positive. Reference values:
/// `(0.1, 0.1) → 2.197`, `(0.005, 0.005) → 5.293`.
pub fn sprt_threshold(pf: f64, pm: f64) -> Result<f64> {
    check_probability("pf", pf)?;
    check_probability("pm", pm)?;
    if pf + pm >= 1.0 {
        return Err(Error::InvalidParameter {
            name: "pf + pm".into(),
            value: pf + pm,
            requirement: "must be below 1 for a positive SPRT threshold ln((1 - pm)/pf)".into(),
        });
    }
    Ok(((1.0 - pm) / pf).ln())
}

/// CDF of the non-central chi-square distribution `χ²(dof, λ)` at `x`.
///
/// Poisson mixture of central chi-square CDFs, summed outward from the Poisson mode until the
/// remaining Poisson mass is below 1e-17.
pub fn ncx2_cdf(x: f64, dof: usize, lambda: f64) -> Result<f64> {
    check_dof(dof)?;
    if !(lambda >= 0.0) || !lambda.is_finite() {
        return Err(Error::InvalidParameter {
            name: "lambda".into(),
            value: lambda,
            requirement: "non-centrality must be finite and non-negative".into(),
        });
    }
    if x.is_nan() {
        return Err(Error::InvalidParameter {
            name: "x".into(),
            value: x,
            requirement: "must not be NaN".into(),
        });
    }
    if x <= 0.0 {
        return Ok(0.0);
    }
    if x.is_infinite() {
        return Ok(1.0);
    }
    let k = dof as f64;
    let half = 0.5 * lambda;
    if half == 0.0 {
        return Ok(lower_gamma(0.5 * k, 0.5 * x));
    }
    if half > 1e6 {
        // The Poisson mixture would need millions of terms (and `j + 1` stops changing beyond
        // 2⁵³): the normal limit of χ²(k, λ), mean k + λ, variance 2(k + 2λ), is exact to
        // O(λ^-1/2) there.
        let z = (x - (k + lambda)) / (2.0 * (k + 2.0 * lambda)).sqrt();
        return Ok(0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2));
    }
    let log_w = |j: f64| -half + j * half.ln() - ln_gamma(j + 1.0);
    let term = |j: f64| lower_gamma(0.5 * k + j, 0.5 * x);
    let mode = half.floor();
    let mut sum = 0.0;
    let mut mass = 0.0;
    // Upward from the mode.
    let mut j = mode;
    loop {
        let w = log_w(j).exp();
        sum += w * term(j);
        mass += w;
        if (w < 1e-17 && j > mode + 1.0) || j > mode + 10_000.0 {
            break;
        }
        j += 1.0;
    }
    // Downward from the mode.
    let mut j = mode - 1.0;
    while j >= 0.0 {
        let w = log_w(j).exp();
        sum += w * term(j);
        mass += w;
        if w < 1e-17 {
            break;
        }
        j -= 1.0;
    }
    let _ = mass;
    Ok(sum.clamp(0.0, 1.0))
}

/// Non-centrality `λ0` at which the chi-square test with threshold `T_D = chi2_threshold(pf,
/// dof)` misses a fault with probability `pm`: `F_{χ²(dof, λ0)}(T_D) = pm`.
///
/// Requires `pf + pm < 1` (otherwise `λ0 = 0` already misses more often than `pm`).
/// Example: `pf = 0.1, pm = 0.05, dof = 6 → 17.87`; `pf = pm = 0.005, dof = 6 → 41.04`.
/// Memoised per thread like [`chi2_threshold`] (the root costs ≈ 200 µs: a configuration built
/// per call, as `snapshot_fde` from Python does, paid it at every call).
pub fn noncentrality(pf: f64, pm: f64, dof: usize) -> Result<f64> {
    memo(1, [pf.to_bits(), pm.to_bits(), dof as u64], || {
        noncentrality_uncached(pf, pm, dof)
    })
}

fn noncentrality_uncached(pf: f64, pm: f64, dof: usize) -> Result<f64> {
    check_probability("pm", pm)?;
    let td = chi2_threshold(pf, dof)?;
    if pf + pm >= 1.0 {
        return Err(Error::InvalidParameter {
            name: "pf + pm".into(),
            value: pf + pm,
            requirement:
                "must be below 1: a fault with zero bias is already missed with probability 1 - pf"
                    .into(),
        });
    }
    // g(λ) = F(T_D; λ) − pm is decreasing in λ, g(0) = 1 − pf − pm > 0.
    let g = |l: f64| ncx2_cdf(td, dof, l).map(|c| c - pm);
    let mut lo = 0.0;
    let mut hi = td.max(1.0);
    while g(hi)? > 0.0 {
        lo = hi;
        hi *= 2.0;
        if hi > 1e7 {
            return Err(Error::Numerical {
                context: "noncentrality".into(),
                detail: format!("no root below 1e7 for pf = {pf:e}, pm = {pm:e}, dof = {dof}"),
            });
        }
    }
    // Bisection to machine precision (the function is smooth and monotone; ~60 steps).
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid)? > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-13 * hi {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Minimal detectable bias per measurement component (METHODS §6).
///
/// `a`: innovation covariance `A` (m × m, symmetric positive definite). Returns
/// `MDB_i = sqrt(λ0 / (A⁻¹)_ii)` for `i = 0..m`, in the measurement's units, with
/// `λ0 = noncentrality(pf, pm, m)`.
pub fn mdb(a: &DMatrix<f64>, pf: f64, pm: f64) -> Result<Vec<f64>> {
    check_symmetric("A", a)?;
    let m = a.nrows();
    if m == 0 {
        return Err(Error::Shape {
            name: "A".into(),
            expected: "a non-empty square matrix".into(),
            got: "(0, 0)".into(),
        });
    }
    mdb_with(a, noncentrality(pf, pm, m)?)
}

/// [`mdb`] for a given non-centrality `λ0` (for per-epoch use with a cached `λ0`); `a` must
/// be symmetric positive definite (not checked for symmetry here).
pub fn mdb_with(a: &DMatrix<f64>, lambda0: f64) -> Result<Vec<f64>> {
    let m = a.nrows();
    let chol = nalgebra::Cholesky::new(a.clone()).ok_or_else(|| Error::NotPositiveDefinite {
        name: "A".into(),
        detail: "Cholesky factorisation failed".into(),
    })?;
    let inv = chol.inverse();
    (0..m)
        .map(|i| {
            let d = inv[(i, i)];
            if d > 0.0 && d.is_finite() {
                Ok((lambda0 / d).sqrt())
            } else {
                Err(Error::Numerical {
                    context: "mdb".into(),
                    detail: format!("(A^-1)[{i}, {i}] = {d} is not positive"),
                })
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn chi_square_probabilities_are_total_where_statrs_panics() {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        // statrs 0.19: Gamma::cdf of a positive x below ~1e-308 scales it to 0 and panics in
        // gamma_lr; navfdi's own functions answer.
        let tiny = 5e-324;
        assert!(std::panic::catch_unwind(|| ChiSquared::new(3.0).unwrap().cdf(tiny)).is_err());
        assert_eq!(lower_gamma(1.5, 0.5 * tiny), 0.0);
        assert_eq!(chi2_sf(3, tiny), 1.0);
        assert_eq!(ncx2_cdf(tiny, 3, 0.0).unwrap(), 0.0);
        assert!(ncx2_cdf(tiny, 3, 2.0).unwrap() < 1e-300);
        assert_eq!(chi2_sf(3, f64::INFINITY), 0.0);
        assert!(chi2_sf(3, f64::NAN).is_nan() && lower_gamma(1.0, f64::NAN).is_nan());
        assert_eq!(lower_gamma(2.0, f64::INFINITY), 1.0);
        assert_eq!(chi2_sf(3, -1.0), 1.0);
        let exact = ChiSquared::new(3.0).unwrap().sf(7.8);
        assert!((chi2_sf(3, 7.8) - exact).abs() < 1e-15);
    }

    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn paper_thresholds() {
        assert_relative_eq!(
            chi2_threshold(0.1, 3).unwrap(),
            6.251388631170325,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            chi2_threshold(0.005, 6).unwrap(),
            18.547584178511087,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            chi2_threshold(0.05, 5).unwrap(),
            11.070497693516351,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            sprt_threshold(0.1, 0.1).unwrap(),
            2.1972245773362196,
            max_relative = 1e-14
        );
        assert_relative_eq!(
            sprt_threshold(0.005, 0.005).unwrap(),
            5.293304824724492,
            max_relative = 1e-14
        );
    }

    #[test]
    fn memoised_threshold_equals_the_computed_one() {
        for dof in 1..40 {
            for pf in [0.05, 1e-3, 1e-20] {
                let a = chi2_threshold(pf, dof).unwrap();
                let b = chi2_threshold(pf, dof).unwrap(); // from the memo
                assert_eq!(a.to_bits(), b.to_bits());
                assert_eq!(
                    a.to_bits(),
                    chi2_threshold_uncached(pf, dof).unwrap().to_bits()
                );
            }
        }
        // Bad input is refused before the memo is consulted.
        assert!(chi2_threshold(0.0, 3).is_err());
        assert!(chi2_threshold(0.05, 0).is_err());
    }

    #[test]
    fn noncentral_reduces_to_central() {
        let c = ncx2_cdf(5.0, 3, 0.0).unwrap();
        assert_relative_eq!(
            c,
            ChiSquared::new(3.0).unwrap().cdf(5.0),
            max_relative = 1e-14
        );
    }

    #[test]
    fn noncentrality_solves_its_equation() {
        for &(pf, pm, m) in &[
            (0.1, 0.05, 6usize),
            (0.005, 0.005, 6),
            (0.005, 0.005, 1),
            (0.01, 0.2, 3),
        ] {
            let l = noncentrality(pf, pm, m).unwrap();
            let td = chi2_threshold(pf, m).unwrap();
            assert_relative_eq!(ncx2_cdf(td, m, l).unwrap(), pm, max_relative = 1e-9);
        }
    }

    #[test]
    fn memo_returns_each_function_its_own_value_and_keeps_no_error() {
        // Same argument bits under the three kinds: each gets its own value, equal to the
        // uncached computation, also on the second (memoised) call.
        for _ in 0..2 {
            assert_eq!(
                noncentrality(0.1, 0.05, 6).unwrap(),
                noncentrality_uncached(0.1, 0.05, 6).unwrap()
            );
            assert_eq!(
                chi2_threshold(0.1, 6).unwrap(),
                chi2_threshold_uncached(0.1, 6).unwrap()
            );
            let k = crate::gnss::lsq::two_sided_quantile(0.01).unwrap();
            let w = crate::gnss::lsq::w_noncentrality(k, 0.8).unwrap();
            assert!((w.sqrt() - 3.4172).abs() < 1e-3, "{w}"); // k0 2.5758 + z(0.8) 0.8416
        }
        // An error is returned every time, not kept as a value.
        for _ in 0..2 {
            assert!(noncentrality(0.5, 0.6, 3).is_err());
            assert!(crate::gnss::lsq::w_noncentrality(1.0, 0.1).is_err());
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(chi2_threshold(0.0, 3).is_err());
        assert!(chi2_threshold(0.1, 0).is_err());
        assert!(sprt_threshold(0.6, 0.5).is_err());
        assert!(noncentrality(0.5, 0.6, 3).is_err());
        let not_pd = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(matches!(
            mdb(&not_pd, 0.01, 0.01),
            Err(Error::NotPositiveDefinite { .. })
        ));
    }

    #[test]
    fn mdb_scalar_closed_form() {
        // Scalar A = σ²: MDB = σ·sqrt(λ0).
        let a = DMatrix::from_element(1, 1, 100.0);
        let l0 = noncentrality(0.005, 0.005, 1).unwrap();
        assert_relative_eq!(
            mdb(&a, 0.005, 0.005).unwrap()[0],
            10.0 * l0.sqrt(),
            max_relative = 1e-12
        );
    }
}
