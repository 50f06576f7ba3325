//! Input validation shared by the filters, detectors and statistics.
//!
//! All checks are read-only and run before any state changes, so a rejected call leaves its
//! object exactly as it was.

use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// Relative tolerance for symmetry: `|M_ij − M_ji| ≤ SYM_RTOL · max(1, max|M|)`.
pub const SYM_RTOL: f64 = 1e-9;
/// Relative jitter added to the diagonal when testing positive semi-definiteness by Cholesky.
pub const PSD_RTOL: f64 = 1e-10;

/// Format a shape as `(a, b)`.
pub fn shape_str(dims: &[usize]) -> String {
    let inner: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
    if dims.len() == 1 {
        format!("({},)", inner[0])
    } else {
        format!("({})", inner.join(", "))
    }
}

/// Check a matrix has shape `(rows, cols)`.
pub fn check_shape(name: &str, m: &DMatrix<f64>, rows: usize, cols: usize) -> Result<()> {
    if m.nrows() != rows || m.ncols() != cols {
        return Err(Error::Shape {
            name: name.to_string(),
            expected: shape_str(&[rows, cols]),
            got: shape_str(&[m.nrows(), m.ncols()]),
        });
    }
    Ok(())
}

/// Check a vector has length `len`.
pub fn check_len(name: &str, v: &DVector<f64>, len: usize) -> Result<()> {
    if v.len() != len {
        return Err(Error::Shape {
            name: name.to_string(),
            expected: shape_str(&[len]),
            got: shape_str(&[v.len()]),
        });
    }
    Ok(())
}

/// Check every element of a matrix is finite.
pub fn check_finite_matrix(name: &str, m: &DMatrix<f64>) -> Result<()> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            let v = m[(i, j)];
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    name: name.to_string(),
                    index: format!("[{i}, {j}]"),
                    value: v,
                });
            }
        }
    }
    Ok(())
}

/// Check every element of a vector is finite.
pub fn check_finite_vector(name: &str, v: &DVector<f64>) -> Result<()> {
    for (i, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(Error::NonFinite {
                name: name.to_string(),
                index: format!("[{i}]"),
                value: *x,
            });
        }
    }
    Ok(())
}

/// Check a vector holds no infinity (NaN allowed: it marks a missing component).
pub fn check_no_inf(name: &str, v: &DVector<f64>) -> Result<()> {
    for (i, x) in v.iter().enumerate() {
        if x.is_infinite() {
            return Err(Error::NonFinite {
                name: name.to_string(),
                index: format!("[{i}]"),
                value: *x,
            });
        }
    }
    Ok(())
}

/// Check a square matrix is finite and symmetric within [`SYM_RTOL`].
pub fn check_symmetric(name: &str, m: &DMatrix<f64>) -> Result<()> {
    if m.nrows() != m.ncols() {
        return Err(Error::Shape {
            name: name.to_string(),
            expected: "a square matrix".to_string(),
            got: shape_str(&[m.nrows(), m.ncols()]),
        });
    }
    check_finite_matrix(name, m)?;
    let scale = m.amax().max(1.0);
    let tol = SYM_RTOL * scale;
    let (worst, at) = crate::linalg::max_asymmetry(m);
    if worst > tol {
        return Err(Error::NotSymmetric {
            name: name.to_string(),
            asymmetry: worst,
            index: format!("[{}, {}]", at.0, at.1),
            tolerance: tol,
        });
    }
    Ok(())
}

/// Check a matrix is a valid covariance: square, finite, symmetric and positive semi-definite.
///
/// Semi-definiteness is tested by a Cholesky factorisation of `M + δI` with
/// `δ = PSD_RTOL · max(max diag, tiny)`: a matrix whose most negative eigenvalue is below
/// `−δ` is rejected. Zero rows and columns (unexcited states) are accepted.
pub fn check_covariance(name: &str, m: &DMatrix<f64>) -> Result<()> {
    check_symmetric(name, m)?;
    let n = m.nrows();
    let mut max_diag: f64 = 0.0;
    for i in 0..n {
        let d = m[(i, i)];
        if d < 0.0 {
            return Err(Error::NotPositiveSemiDefinite {
                name: name.to_string(),
                detail: format!("diagonal element [{i}, {i}] = {d} is negative"),
            });
        }
        max_diag = max_diag.max(d);
    }
    if max_diag == 0.0 {
        // All-zero diagonal: PSD only if the whole matrix is zero.
        if m.amax() > 0.0 {
            return Err(Error::NotPositiveSemiDefinite {
                name: name.to_string(),
                detail: "zero diagonal with non-zero off-diagonal elements".to_string(),
            });
        }
        return Ok(());
    }
    let delta = PSD_RTOL * max_diag;
    let mut shifted = m.clone();
    for i in 0..n {
        shifted[(i, i)] += delta;
    }
    if !cholesky_succeeds(shifted) {
        return Err(Error::NotPositiveSemiDefinite {
            name: name.to_string(),
            detail: "it has a negative eigenvalue (Cholesky factorisation failed)".to_string(),
        });
    }
    Ok(())
}

/// Whether a symmetric matrix has a Cholesky factor. Large matrices use faer's blocked,
/// parallel factorisation (nalgebra's unblocked one took ~100 ms at n = 1000, which made
/// validating `Q` the dominant cost of a large `predict`).
fn cholesky_succeeds(m: DMatrix<f64>) -> bool {
    let n = m.nrows();
    if n < 64 {
        return nalgebra::Cholesky::new(m).is_some();
    }
    let view = faer::MatRef::from_column_major_slice(m.as_slice(), n, n);
    view.llt(faer::Side::Lower).is_ok()
}

/// Check a probability lies in the open interval (0, 1).
pub fn check_probability(name: &str, p: f64) -> Result<()> {
    if !(p > 0.0 && p < 1.0) {
        return Err(Error::InvalidParameter {
            name: name.to_string(),
            value: p,
            requirement: "must be a probability in the open interval (0, 1)".to_string(),
        });
    }
    Ok(())
}

/// Make a square matrix exactly symmetric in place: `M ← (M + Mᵀ)/2`.
pub fn symmetrize(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covariance_checks() {
        let ok = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        assert!(check_covariance("M", &ok).is_ok());
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        assert!(check_covariance("M", &singular).is_ok());
        let zero = DMatrix::<f64>::zeros(3, 3);
        assert!(check_covariance("M", &zero).is_ok());
        let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(matches!(
            check_covariance("M", &indefinite),
            Err(Error::NotPositiveSemiDefinite { .. })
        ));
        let asym = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 1.0]);
        assert!(matches!(
            check_covariance("M", &asym),
            Err(Error::NotSymmetric { .. })
        ));
        let nan = DMatrix::from_row_slice(2, 2, &[1.0, f64::NAN, f64::NAN, 1.0]);
        assert!(matches!(
            check_covariance("M", &nan),
            Err(Error::NonFinite { .. })
        ));
        let neg = DMatrix::from_row_slice(1, 1, &[-1.0]);
        assert!(matches!(
            check_covariance("M", &neg),
            Err(Error::NotPositiveSemiDefinite { .. })
        ));
    }

    #[test]
    fn probabilities() {
        assert!(check_probability("pf", 0.5).is_ok());
        for p in [0.0, 1.0, -0.1, 1.5, f64::NAN] {
            assert!(check_probability("pf", p).is_err());
        }
    }
}
