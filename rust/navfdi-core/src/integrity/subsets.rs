//! Weighted least squares of the satellite subsets of ARAIM's fault modes ([`super::araim`]):
//! the all-in-view normal matrix downdated per subset ([`Subsets`]) and rank-r downdates of the
//! all-in-view covariance by the Woodbury identity ([`Downdate`]).

use nalgebra::DMatrix;

/// Weighted least squares of satellite subsets by downdating the all-in-view normal matrix:
/// `N_k = GᵀWG − Σ_{i removed} wᵢ gᵢ gᵢᵀ`, the clock column of a constellation with no
/// satellite left decoupled (`N[c, c] = 1`), then `cov_k = N_k⁻¹` and the three position rows
/// of `S_k = N_k⁻¹ GᵀW` (zero for removed satellites): the cost of a mode is
/// O(|removed| m² + m³ + 3 m n) instead of forming each subset's normal matrix.
pub(crate) struct Subsets<'a> {
    g: &'a DMatrix<f64>,
    w: &'a [f64],
    n0: DMatrix<f64>,
}

impl<'a> Subsets<'a> {
    pub(crate) fn new(g: &'a DMatrix<f64>, w: &'a [f64]) -> Self {
        let (n, m) = g.shape();
        let mut n0 = DMatrix::zeros(m, m);
        for i in 0..n {
            for a in 0..m {
                let ga = g[(i, a)] * w[i];
                if ga == 0.0 {
                    continue;
                }
                for b in 0..m {
                    n0[(a, b)] += ga * g[(i, b)];
                }
            }
        }
        Subsets { g, w, n0 }
    }

    /// `cov` (m × m; decoupled clock entries for absent constellations) and the position rows
    /// of `S` (3 × n) of the subset without `removed`; None when it cannot be solved.
    pub(crate) fn solve(&self, removed: &[usize]) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let (n, m) = self.g.shape();
        let mut nk = self.n0.clone();
        for &i in removed {
            for a in 0..m {
                let ga = self.g[(i, a)] * self.w[i];
                if ga == 0.0 {
                    continue;
                }
                for b in 0..m {
                    nk[(a, b)] -= ga * self.g[(i, b)];
                }
            }
        }
        // Clock columns with no satellite left; at least as many satellites as unknowns.
        let mut kept = vec![true; n];
        for &i in removed {
            kept[i] = false;
        }
        let mut unknowns = 3;
        for c in 3..m {
            let used = (0..n).any(|i| self.g[(i, c)] != 0.0 && kept[i]);
            if used {
                unknowns += 1;
            } else {
                for j in 0..m {
                    nk[(c, j)] = 0.0;
                    nk[(j, c)] = 0.0;
                }
                nk[(c, c)] = 1.0;
            }
        }
        if n - removed.len() < unknowns {
            return None;
        }
        let cov = nalgebra::Cholesky::new(nk)?.inverse();
        if !cov.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut s = DMatrix::zeros(3, n);
        for i in (0..n).filter(|&i| kept[i]) {
            for q in 0..3 {
                let mut v = 0.0;
                for a in 0..m {
                    v += cov[(q, a)] * self.g[(i, a)];
                }
                s[(q, i)] = v * self.w[i];
            }
        }
        Some((cov, s))
    }
}

/// The all-in-view solution prepared for rank-r downdates (Woodbury): with `A = cov₀Gᵀ`
/// (m × n) and `P = G cov₀ Gᵀ` (n × n), removing the rows R gives
/// `cov_k = cov₀ + A_R M⁻¹ A_Rᵀ`, `M = W_R⁻¹ − P_RR` (r × r), and the subset's gain column
/// `S_k[:, i] = S₀[:, i] + A_R M⁻¹ P_R,i wᵢ` (i ∉ R; zero for i ∈ R). A mode then costs
/// O(r³ + 3 r n) instead of a Cholesky factor, an inverse and an m-wide product per satellite.
/// Used when every clock column keeps a satellite; otherwise (and when M is ill-conditioned)
/// [`Subsets::solve`] decides.
pub(crate) struct Downdate<'a> {
    subsets: &'a Subsets<'a>,
    cov0: DMatrix<f64>,
    /// `A = cov₀Gᵀ`, m × n.
    a: DMatrix<f64>,
    /// `P = G cov₀ Gᵀ`, n × n.
    p: DMatrix<f64>,
    /// Satellites per clock column.
    per_clock: Vec<usize>,
    /// The position rows of A per satellite, `a_t[i][q] = A[q, i]`.
    a_t: Vec<[f64; 3]>,
}

/// What takes a subset's gain rows from [`Downdate::rows_each`], one satellite at a time (a
/// trait rather than a closure, so that its `#[inline(always)]` body joins the rows' loop).
pub(crate) trait EachRow {
    /// Satellite `i`'s position rows `S_k[q, i]`, east, north, up.
    fn row(&mut self, i: usize, s: [f64; 3]);
}

/// Position rows of a subset's gain: `σ_q²` (east, north, up) and `S_k[q, i]` for every
/// satellite (zero for the removed ones), stored as `s[i][q]`.
pub(crate) struct SubsetRows {
    var: [f64; 3],
    s: Vec<[f64; 3]>,
}

impl<'a> Downdate<'a> {
    pub(crate) fn new(subsets: &'a Subsets<'a>, cov0: DMatrix<f64>) -> Self {
        let g = subsets.g;
        let (n, m) = g.shape();
        let a = &cov0 * g.transpose();
        let p = g * &a;
        let per_clock = (0..m)
            .map(|c| (0..n).filter(|&i| c >= 3 && g[(i, c)] != 0.0).count())
            .collect();
        let a_t = (0..n).map(|i| [a[(0, i)], a[(1, i)], a[(2, i)]]).collect();
        Downdate {
            subsets,
            cov0,
            a,
            p,
            per_clock,
            a_t,
        }
    }

    /// The subset without `removed` (sorted, distinct); None when it cannot be solved.
    #[cfg(test)]
    fn rows(&self, removed: &[usize]) -> Option<SubsetRows> {
        let s = vec![[0.0; 3]; self.a_t.len()];
        struct Keep(Vec<[f64; 3]>);
        impl EachRow for Keep {
            fn row(&mut self, i: usize, s: [f64; 3]) {
                self.0[i] = s;
            }
        }
        let mut keep = Keep(s);
        let var = self.rows_each(removed, &mut keep)?;
        Some(SubsetRows { var, s: keep.0 })
    }

    /// [`Downdate::rows`] handed to `each.row(i, S_k[:, i])` for every satellite i in order
    /// (zero rows for the removed ones), without a buffer: the caller's statistics run in the
    /// same pass. Returns `σ_q²`; None (and no call) when the subset cannot be solved.
    pub(crate) fn rows_each(&self, removed: &[usize], each: &mut impl EachRow) -> Option<[f64; 3]> {
        let g = self.subsets.g;
        let w = self.subsets.w;
        let (n, m) = g.shape();
        let mut unknowns = 3;
        let mut clock_lost = false;
        for c in 3..m {
            if self.per_clock[c] == 0 {
                continue;
            }
            let gone = removed.iter().filter(|&&i| g[(i, c)] != 0.0).count();
            if gone == self.per_clock[c] {
                clock_lost = true;
            } else {
                unknowns += 1;
            }
        }
        if clock_lost {
            return self.direct_each(removed, each);
        }
        if n - removed.len() < unknowns {
            return None;
        }
        let r = removed.len();
        // u_q = M⁻¹ A[q, R] for the three position rows (M = W_R⁻¹ − P_RR, r × r).
        let mut var = [0.0; 3];
        let mut u = [[0.0f64; 2]; 3]; // r ≤ 2 in closed form; larger removals in `big`
        let big: Vec<nalgebra::DVector<f64>>;
        let m_entry = |x: usize, y: usize| {
            let (i, j) = (removed[x], removed[y]);
            let v = -self.p[(i, j)];
            if x == y {
                v + 1.0 / w[i]
            } else {
                v
            }
        };
        // A removal that leaves the subset (nearly) singular, seen as a pivot of M small
        // against its diagonal, is left to the direct solution, which decides it as before.
        let pivot_ok = |pivot: f64, diag: f64| pivot > 1e-9 * diag;
        match r {
            1 => {
                let m00 = m_entry(0, 0);
                if !pivot_ok(m00, 1.0 / w[removed[0]]) {
                    return self.direct_each(removed, each);
                }
                for (q, v) in var.iter_mut().enumerate() {
                    let a0 = self.a[(q, removed[0])];
                    u[q][0] = a0 / m00;
                    *v = self.cov0[(q, q)] + a0 * u[q][0];
                }
                big = Vec::new();
            }
            2 => {
                let (m00, m01, m11) = (m_entry(0, 0), m_entry(0, 1), m_entry(1, 1));
                let det = m00 * m11 - m01 * m01;
                if !pivot_ok(m00, 1.0 / w[removed[0]]) || !pivot_ok(det / m00, 1.0 / w[removed[1]])
                {
                    return self.direct_each(removed, each);
                }
                for (q, v) in var.iter_mut().enumerate() {
                    let (a0, a1) = (self.a[(q, removed[0])], self.a[(q, removed[1])]);
                    u[q][0] = (m11 * a0 - m01 * a1) / det;
                    u[q][1] = (m00 * a1 - m01 * a0) / det;
                    *v = self.cov0[(q, q)] + a0 * u[q][0] + a1 * u[q][1];
                }
                big = Vec::new();
            }
            _ => {
                let mm = DMatrix::from_fn(r, r, m_entry);
                let diag: Vec<f64> = (0..r).map(|x| mm[(x, x)]).collect();
                let chol = match nalgebra::Cholesky::new(mm) {
                    Some(c) if (0..r).all(|x| pivot_ok(c.l_dirty()[(x, x)].powi(2), diag[x])) => c,
                    _ => return self.direct_each(removed, each),
                };
                let mut sols = Vec::with_capacity(3);
                for (q, v) in var.iter_mut().enumerate() {
                    let aq = nalgebra::DVector::from_iterator(
                        r,
                        removed.iter().map(|&i| self.a[(q, i)]),
                    );
                    let sol = chol.solve(&aq);
                    *v = self.cov0[(q, q)] + aq.dot(&sol);
                    sols.push(sol);
                }
                big = sols;
            }
        }
        // P is symmetric: P[j, i] is column j of P, contiguous.
        let ps = self.p.as_slice();
        let col = |x: usize| &ps[removed[x] * n..(removed[x] + 1) * n];
        // The first two removed satellites' columns (none removed: unused, empty).
        let (c0, c1) = match r {
            0 => (&ps[..0], &ps[..0]),
            _ => (col(0), col(r.min(2) - 1)),
        };
        let mut next = 0;
        for (i, (&a, &wi)) in self.a_t.iter().zip(w).enumerate() {
            let row = if next < r && removed[next] == i {
                next += 1;
                [0.0; 3]
            } else {
                match r {
                    1 => {
                        let p0 = c0[i];
                        [0, 1, 2].map(|q| (a[q] + u[q][0] * p0) * wi)
                    }
                    2 => {
                        let (p0, p1) = (c0[i], c1[i]);
                        [0, 1, 2].map(|q| (a[q] + u[q][0] * p0 + u[q][1] * p1) * wi)
                    }
                    _ => [0, 1, 2].map(|q| {
                        let d: f64 = (0..r).map(|x| big[q][x] * col(x)[i]).sum();
                        (a[q] + d) * wi
                    }),
                }
            };
            each.row(i, row);
        }
        Some(var)
    }

    fn direct_each(&self, removed: &[usize], each: &mut impl EachRow) -> Option<[f64; 3]> {
        let d = self.direct(removed)?;
        for (i, &row) in d.s.iter().enumerate() {
            each.row(i, row);
        }
        Some(d.var)
    }

    fn direct(&self, removed: &[usize]) -> Option<SubsetRows> {
        let (cov, sk) = self.subsets.solve(removed)?;
        let n = sk.ncols();
        Some(SubsetRows {
            var: [cov[(0, 0)], cov[(1, 1)], cov[(2, 2)]],
            s: (0..n)
                .map(|i| [sk[(0, i)], sk[(1, i)], sk[(2, i)]])
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downdated_subsets_equal_the_direct_solutions() {
        // Every single and pair removal of a 12-satellite two-constellation geometry with
        // unequal weights, and removals that take a constellation's last satellites (those go
        // to the direct path): σ² and the gain rows agree with the subset's own normal matrix.
        let mut rows = Vec::new();
        let mut cons = Vec::new();
        for i in 0..12 {
            let az = (i as f64) * 2.399_963;
            let el = (8.0 + 80.0 * ((i * 5 % 12) as f64) / 11.0).to_radians();
            rows.push([-el.cos() * az.sin(), -el.cos() * az.cos(), -el.sin()]);
            cons.push(usize::from(i >= 8));
        }
        let mut g = DMatrix::zeros(12, 5);
        for (i, r) in rows.iter().enumerate() {
            for c in 0..3 {
                g[(i, c)] = r[c];
            }
            g[(i, 3 + cons[i])] = 1.0;
        }
        let w: Vec<f64> = (0..12)
            .map(|i| 1.0 / (0.5 + 0.3 * (i % 4) as f64))
            .collect();
        let sub = Subsets::new(&g, &w);
        let (cov0, _) = sub.solve(&[]).unwrap();
        let down = Downdate::new(&sub, cov0);
        let mut removals: Vec<Vec<usize>> = (0..12).map(|i| vec![i]).collect();
        for i in 0..12 {
            for j in i + 1..12 {
                removals.push(vec![i, j]);
            }
        }
        removals.push(vec![8, 9, 10, 11]);
        removals.push(vec![0, 8, 9, 10, 11]);
        // Nothing removed: the all-in-view rows.
        removals.push(vec![]);
        // Three removed: the Cholesky path.
        removals.push(vec![1, 4, 9]);
        let mut compared = 0;
        for removed in &removals {
            let fast = down.rows(removed);
            let slow = down.direct(removed);
            assert_eq!(fast.is_some(), slow.is_some(), "{removed:?}");
            if let (Some(f), Some(d)) = (fast, slow) {
                for q in 0..3 {
                    assert!(
                        (f.var[q] - d.var[q]).abs() < 1e-10 * d.var[q],
                        "{removed:?}"
                    );
                    for i in 0..12 {
                        assert!((f.s[i][q] - d.s[i][q]).abs() < 1e-10, "{removed:?} {i}");
                    }
                }
                compared += 1;
            }
        }
        assert!(compared > 70, "{compared}");
    }
}
