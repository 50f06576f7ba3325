//! The update's products where the measurement matrix `H` selects states: every row one
//! entry equal to 1 and zeros elsewhere (position and velocity fixes of an error-state
//! filter). `HP` is then rows of `P`, `HPHᵀ` elements of them, `Hx` elements of `x` and `THᵀ`
//! columns of `T` — copies instead of products. A product whose only non-zero term is `1·v`
//! equals `v` to the bit (every other term is an exact zero), so both paths give the same
//! numbers for finite inputs.

use nalgebra::{DMatrix, DVector};

#[cfg(test)]
thread_local! {
    /// Tests switch the selection path off to compare it with the general products.
    pub(super) static GENERAL_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// When every row of `h` (k × n) has exactly one entry 1 and zeros elsewhere, write the
/// selected state of each row to `columns` and return true; otherwise false (`columns` then
/// holds no meaning).
pub(super) fn rows_of(h: &DMatrix<f64>, columns: &mut Vec<usize>) -> bool {
    #[cfg(test)]
    if GENERAL_ONLY.with(|g| g.get()) {
        return false;
    }
    let (k, n) = h.shape();
    columns.clear();
    columns.resize(k, usize::MAX);
    let s = h.as_slice(); // column-major: h[(i, j)] = s[i + j·k]
    for j in 0..n {
        for (i, &v) in s[j * k..(j + 1) * k].iter().enumerate() {
            if v == 0.0 {
                continue;
            }
            if v != 1.0 || columns[i] != usize::MAX {
                return false;
            }
            columns[i] = j;
        }
    }
    columns.iter().all(|&c| c != usize::MAX)
}

/// `HP` (k × n) into `hp`, `A += HPHᵀ` (k × k, `a` holding R) and `res −= Hx` (`res` holding
/// z), for the selection `columns`.
pub(super) fn innovate(
    p: &DMatrix<f64>,
    x: &DVector<f64>,
    columns: &[usize],
    hp: &mut DMatrix<f64>,
    a: &mut DMatrix<f64>,
    res: &mut DVector<f64>,
) {
    let n = p.nrows();
    let k = columns.len();
    // Column-major slices: hp[(i, j)] = hs[i + j·k], p[(c, j)] = ps[c + j·n].
    let (hs, ps) = (hp.as_mut_slice(), p.as_slice());
    for (hcol, pcol) in hs.chunks_exact_mut(k).zip(ps.chunks_exact(n)) {
        for (h, &c) in hcol.iter_mut().zip(columns) {
            *h = pcol[c];
        }
    }
    for (r, &c) in res.iter_mut().zip(columns) {
        *r -= x[c];
    }
    let a_s = a.as_mut_slice();
    for (acol, &c) in a_s.chunks_exact_mut(k).zip(columns) {
        for (av, hv) in acol.iter_mut().zip(&hs[c * k..(c + 1) * k]) {
            *av += hv;
        }
    }
}

/// `U = THᵀ` (n × k): the selected columns of `t`.
pub(super) fn columns(t: &DMatrix<f64>, columns: &[usize], u: &mut DMatrix<f64>) {
    for (l, &c) in columns.iter().enumerate() {
        u.column_mut(l).copy_from(&t.column(c));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::KalmanFilter;

    #[test]
    fn selections_are_recognised() {
        let mut c = Vec::new();
        let mut h = DMatrix::zeros(2, 4);
        h[(0, 3)] = 1.0;
        h[(1, 1)] = 1.0;
        assert!(rows_of(&h, &mut c) && c == [3, 1]);
        h[(1, 2)] = 1.0; // two ones in a row
        assert!(!rows_of(&h, &mut c));
        h[(1, 2)] = 0.0;
        h[(1, 1)] = 2.0; // a scaled state
        assert!(!rows_of(&h, &mut c));
        h[(1, 1)] = 0.0; // an empty row
        assert!(!rows_of(&h, &mut c));
        let mut two = DMatrix::zeros(2, 4);
        two[(0, 2)] = 1.0;
        two[(1, 2)] = 1.0; // one state twice: still a selection
        assert!(rows_of(&two, &mut c) && c == [2, 2]);
    }

    /// The selection path gives the bits the general products give, piece by piece and for
    /// a whole update.
    #[test]
    fn the_selection_path_equals_the_products_to_the_bit() {
        use crate::linalg::gemm;
        let n = 5;
        let p = DMatrix::from_fn(n, n, |i, j| {
            1.0 / (1.0 + i as f64 + j as f64) + if i == j { 1.0 } else { 0.0 }
        });
        let x = DVector::from_fn(n, |i, _| 0.3 * i as f64 - 0.7);
        let mut h = DMatrix::zeros(3, n);
        h[(0, 4)] = 1.0;
        h[(1, 0)] = 1.0;
        h[(2, 2)] = 1.0;
        let r = DMatrix::from_diagonal(&DVector::from_vec(vec![0.5, 0.25, 2.0]));
        let z = DVector::from_vec(vec![0.1, -0.2, 0.3]);
        let mut cols = Vec::new();
        assert!(rows_of(&h, &mut cols));
        let (mut hp, mut a, mut res) = (DMatrix::zeros(3, n), r.clone(), z.clone());
        innovate(&p, &x, &cols, &mut hp, &mut a, &mut res);
        let mut hp2 = DMatrix::zeros(3, n);
        gemm(&mut hp2, 1.0, &h, &p, 0.0);
        let mut a2 = r.clone();
        gemm(&mut a2, 1.0, &hp2, &h.transpose(), 1.0);
        let mut res2 = z.clone();
        res2.gemv(-1.0, &h, &x, 1.0);
        assert_eq!(hp, hp2);
        assert_eq!(a, a2);
        assert_eq!(res, res2);
        let mut u = DMatrix::zeros(n, 3);
        columns(&p, &cols, &mut u);
        let mut u2 = DMatrix::zeros(n, 3);
        gemm(&mut u2, 1.0, &p, &h.transpose(), 0.0);
        assert_eq!(u, u2);
        // A whole update, then the same with the selection path switched off.
        let mut sel = KalmanFilter::new(x.clone(), p.clone()).unwrap();
        let mut gen = KalmanFilter::new(x, p).unwrap();
        let a_sel = sel.update_trusted(&z, &h, &r).unwrap();
        GENERAL_ONLY.with(|g| g.set(true));
        let a_gen = gen.update_trusted(&z, &h, &r).unwrap();
        GENERAL_ONLY.with(|g| g.set(false));
        assert_eq!(a_sel.statistic.to_bits(), a_gen.statistic.to_bits());
        assert_eq!(sel.x(), gen.x());
        assert_eq!(sel.p(), gen.p());
    }
}
