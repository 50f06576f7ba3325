//! Dense products of the small matrices that filters multiply every epoch.
//!
//! nalgebra sends dynamic-size products to `matrixmultiply`, whose packing costs 0.2–0.35 µs
//! per call at the sizes of a navigation filter (n ≈ 15, m ≤ 6). `nano-gemm` (from the faer
//! project) has kernels for small sizes, with run-time CPU dispatch (AVX-512, AVX2, scalar), and
//! measured 1.4–3.3× faster on these shapes (benches/README.md). Both functions check the
//! shapes and fall back to nalgebra's product when a dimension is zero or the shapes do not
//! match (where nalgebra reports the mismatch), so the unsafe call only ever sees valid,
//! contiguous column-major buffers.

use nalgebra::DMatrix;

/// `c ← α·a·b + β·c` (nalgebra's `gemm` convention).
pub fn gemm(c: &mut DMatrix<f64>, alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64) {
    if b.nrows() != a.ncols() || !product(c, alpha, a, b, b.ncols(), (1, b.nrows()), beta) {
        c.gemm(alpha, a, b, beta);
    }
}

/// `c ← α·a·bᵀ + β·c` without forming `bᵀ`.
pub fn gemm_nt(c: &mut DMatrix<f64>, alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64) {
    // Element (i, j) of bᵀ is b[(j, i)] at offset j + i·n: row stride n, column stride 1.
    if b.ncols() != a.ncols() || !product(c, alpha, a, b, b.nrows(), (b.nrows(), 1), beta) {
        c.gemm(alpha, a, &b.transpose(), beta);
    }
}

/// `c ← α·a·B + β·c` where `B` (k × n, k = `a.ncols()`) is read from `b`'s buffer with
/// `(row, column)` strides `rhs`. Returns false, touching nothing, when a dimension is zero or
/// `c` is not m × n; the callers have checked that `b`'s buffer holds exactly k·n elements laid
/// out by those strides.
fn product(
    c: &mut DMatrix<f64>,
    alpha: f64,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    n: usize,
    rhs: (usize, usize),
    beta: f64,
) -> bool {
    let (m, k) = (a.nrows(), a.ncols());
    if m == 0 || n == 0 || k == 0 || c.nrows() != m || c.ncols() != n || b.len() != k * n {
        return false;
    }
    let plan = nano_gemm::Plan::new_colmajor_lhs_and_dst_f64(m, n, k);
    // SAFETY: c is m × n and a is m × k, contiguous column-major (nalgebra's DMatrix storage);
    // b's buffer holds k·n elements and the callers' strides address B[(i, j)] at
    // i·rhs.0 + j·rhs.1 < k·n, all checked above.
    unsafe {
        plan.execute_unchecked(
            m,
            n,
            k,
            c.as_mut_ptr(),
            1,
            m as isize,
            a.as_ptr(),
            1,
            m as isize,
            b.as_ptr(),
            rhs.0 as isize,
            rhs.1 as isize,
            beta,
            alpha,
            false,
            false,
        );
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_nalgebra_for_many_shapes() {
        let mut seed = 1u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for m in 1..18 {
            for k in 1..9 {
                for n in [1usize, 3, 6, 15, 17] {
                    let a = DMatrix::from_fn(m, k, |_, _| next());
                    let b = DMatrix::from_fn(k, n, |_, _| next());
                    let c0 = DMatrix::from_fn(m, n, |_, _| next());
                    let mut c1 = c0.clone();
                    gemm(&mut c1, 1.5, &a, &b, -0.5);
                    let reference = &a * &b * 1.5 + &c0 * -0.5;
                    assert!((&c1 - &reference).amax() < 1e-12, "{m}x{k}x{n}");
                    let bt = b.transpose();
                    let mut c2 = c0.clone();
                    gemm_nt(&mut c2, 1.5, &a, &bt, -0.5);
                    assert!((&c2 - &reference).amax() < 1e-12, "nt {m}x{k}x{n}");
                    // β = 0 ignores whatever c held (even NaN).
                    let mut c3 = DMatrix::from_element(m, n, f64::NAN);
                    gemm(&mut c3, 1.0, &a, &b, 0.0);
                    assert!((&c3 - &a * &b).amax() < 1e-12);
                }
            }
        }
    }
}
