//! The two-fault pair check of the exclusion loop ([`super::fde`]): every pair of satellites
//! tested on a downdate of the whole set's linearised solution.

use super::super::lsq::FdeConfig;
use super::same_group;
use crate::error::Result;
use nalgebra::{Cholesky, DMatrix, DVector};

/// The whole set's least-squares test in the form the pair check downdates: `g = D⁻¹v` and
/// its cofactor `M = D⁻¹ D_V D⁻¹ = D⁻¹ − D⁻¹B N⁻¹ BᵀD⁻¹` (normalised units), and `T = vᵀD⁻¹v`.
pub(super) struct PairScreen {
    g: DVector<f64>,
    m: DMatrix<f64>,
    statistic: f64,
    dinv_diag: DVector<f64>,
}

impl PairScreen {
    /// From the whole set's residuals `v`, their covariance `dv` (`D_V`, as [`ls_test`]
    /// gives them) and `dinv` (`D⁻¹`), all in the normalised units of the loop.
    ///
    /// [`ls_test`]: super::super::lsq::ls_test
    pub(super) fn new(v: &DVector<f64>, dv: &DMatrix<f64>, dinv: &DMatrix<f64>) -> Self {
        let g = dinv * v;
        PairScreen {
            statistic: v.dot(&g),
            g,
            m: dinv * dv * dinv,
            dinv_diag: dinv.diagonal(),
        }
    }

    /// The statistic of the set without the observations at positions `s` (of the whole
    /// set): `T − g_Sᵀ M_SS⁻¹ g_S` — exact for the linearised model, with a correlated `D` too
    /// (a free bias per removed observation leaves the others' marginal quadratic form).
    /// None when `M_SS` is singular: without them the unknowns are not determined (a
    /// system's last satellites).
    pub(super) fn without(&self, s: &[usize]) -> Option<f64> {
        let k = s.len();
        let mss = DMatrix::from_fn(k, k, |i, j| self.m[(s[i], s[j])]);
        let chol = Cholesky::new(mss)?;
        let lo = chol.l_dirty();
        if (0..k).any(|i| !(lo[(i, i)] * lo[(i, i)] > 1e-10 * self.dinv_diag[s[i]])) {
            return None;
        }
        let gs = DVector::from_fn(k, |i, _| self.g[s[i]]);
        let t = self.statistic - gs.dot(&chol.solve(&gs));
        t.is_finite().then_some(t.max(0.0))
    }
}

/// The two observations (one per group, each standing for its group) of `all` whose removal
/// leaves the smallest global-test ratio (statistic / threshold; `c` the scale of the
/// normalised covariance), when that ratio is below 1, with the observations left; None
/// otherwise. Every pair of groups is tested on the whole set's linearisation (`full`, a
/// downdate per pair: no geometry recomputed — 378 re-solves per epoch with 28 satellites
/// had cost 44 ms); the pair chosen is then solved in full by the loop.
pub(super) fn best_pair(
    full: &PairScreen,
    c: f64,
    u: usize,
    all: &[usize],
    groups: Option<&[usize]>,
    cfg: &FdeConfig,
) -> Result<Option<(usize, usize, Vec<usize>)>> {
    // One representative observation per group, in order.
    let mut reps: Vec<usize> = Vec::new();
    for &i in all {
        if !reps.iter().any(|&r| same_group(groups, r, i)) {
            reps.push(i);
        }
    }
    let mut best: Option<(usize, usize, f64)> = None;
    let mut s: Vec<usize> = Vec::new();
    for (ai, &a) in reps.iter().enumerate() {
        for &b in &reps[ai + 1..] {
            // Positions in `all` of the pair's observations.
            s.clear();
            s.extend(
                all.iter()
                    .enumerate()
                    .filter(|(_, &o)| same_group(groups, o, a) || same_group(groups, o, b))
                    .map(|(p, _)| p),
            );
            let left = all.len() - s.len();
            if left < u + 1 {
                continue;
            }
            if let Some(t) = full.without(&s) {
                let ratio = t / c / c / cfg.threshold(left - u)?;
                if ratio.is_finite() && best.is_none_or(|x| ratio < x.2) {
                    best = Some((a, b, ratio));
                }
            }
        }
    }
    Ok(best.filter(|x| x.2 < 1.0).map(|(a, b, _)| {
        let rest = all
            .iter()
            .copied()
            .filter(|&o| !same_group(groups, o, a) && !same_group(groups, o, b))
            .collect();
        (a, b, rest)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gnss::lsq::ls_test;

    /// The pair check's downdate equals solving the set without the pair, with a correlated
    /// covariance; removing a "system's" last two observations (the only rows of an unknown)
    /// is singular there and refused here.
    #[test]
    fn pair_downdate_equals_the_solve_without_the_pair() {
        let (n, u) = (9, 4);
        let mut seed = 0x9e37_79b9_u64;
        let mut r = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        // Unknown 3 is a clock seen only by observations 7 and 8.
        let b = DMatrix::from_fn(n, u, |i, j| match j {
            3 => f64::from(u8::from(i >= 7)),
            _ => r(),
        });
        let a = DMatrix::from_fn(n, n, |_, _| 0.3 * r());
        let d = &a * a.transpose() + DMatrix::identity(n, n);
        let l = DVector::from_fn(n, |_, _| 3.0 * r());
        let inv = |m: &DMatrix<f64>| Cholesky::new(m.clone()).unwrap().inverse();
        let dinv = inv(&d);
        let full = ls_test(&b, &l, &d, &dinv).unwrap();
        let screen = PairScreen::new(&full.v, &full.dv, &dinv);
        let mut checked = 0;
        for i in 0..n {
            for j in i + 1..n {
                let rest: Vec<usize> = (0..n).filter(|&k| k != i && k != j).collect();
                let got = screen.without(&[i, j]);
                if (i, j) == (7, 8) {
                    assert!(got.is_none(), "the clock's last rows removed: {got:?}");
                    continue;
                }
                let bs = b.select_rows(&rest);
                let ds = d.select_rows(&rest).select_columns(&rest);
                let want = ls_test(&bs, &l.select_rows(&rest), &ds, &inv(&ds))
                    .unwrap()
                    .statistic;
                let got = got.unwrap();
                assert!(
                    (got - want).abs() <= 1e-9 * want.max(1.0),
                    "pair ({i}, {j}): {got} against {want}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 35);
    }
}
