//! Dense products of the small matrices that filters multiply every epoch.
//!
//! nalgebra sends dynamic-size products to `matrixmultiply`, whose packing costs 0.2–0.35 µs
//! per call at the sizes of a navigation filter (n ≈ 15, m ≤ 6). `nano-gemm` (from the faer
//! project) has kernels for small sizes, with run-time CPU dispatch (AVX-512, AVX2, scalar), and
//! measured 1.4–3.3× faster on these shapes (benches/README.md). Both functions check the
//! shapes and fall back to nalgebra's product when a dimension is zero or the shapes do not
//! match (where nalgebra reports the mismatch), so the unsafe call only ever sees valid,
//! contiguous column-major buffers.
//!
//! Large products (m·n·k ≥ [`BLOCKED_MIN`], e.g. the covariance propagation of a state with
//! hundreds of components) go to the `gemm` crate instead: cache-blocked, packed, SIMD kernels
//! run in parallel on rayon's threads, where the small-matrix kernels were 5–10× slower than
//! numpy's OpenBLAS (benches/README.md, "Large states").

use nalgebra::{DMatrix, SMatrix};

/// Products with at least this many multiply-adds (m·n·k) use the blocked kernel.
pub const BLOCKED_MIN: usize = 48 * 48 * 48;

/// Covariance propagations `(ΦP)Φᵀ` with n³ at least this compute only one triangle
/// ([`gemm_nt_symmetric`]); below it the small-matrix kernel's full product is faster.
pub const SYMMETRIC_MIN: usize = 96 * 96 * 96;

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
    if m * n * k >= BLOCKED_MIN {
        // SAFETY: as below (same buffers, shapes and strides). The gemm crate computes
        // dst := α_g·dst + β_g·lhs·rhs, so α_g = β and β_g = α; with β = 0 dst is not read.
        unsafe {
            gemm::gemm(
                m,
                n,
                k,
                c.as_mut_ptr(),
                m as isize,
                1,
                beta != 0.0,
                a.as_ptr(),
                m as isize,
                1,
                b.as_ptr(),
                rhs.1 as isize,
                rhs.0 as isize,
                beta,
                alpha,
                false,
                false,
                false,
                gemm::Parallelism::Rayon(0),
            );
        }
        return true;
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

/// Tile edge of the blocked element-wise loops below (keeps both tiles in L1).
const TILE: usize = 32;

/// A matrix from row-major data (numpy's C order): a tiled transpose into nalgebra's
/// column-major storage, several times faster than an element-wise one for large matrices.
pub fn from_row_major(rows: usize, cols: usize, data: &[f64]) -> DMatrix<f64> {
    if rows * cols < 64 * 64 {
        return DMatrix::from_row_slice(rows, cols, data);
    }
    let mut out = vec![0.0; rows * cols];
    for i0 in (0..rows).step_by(TILE) {
        for j0 in (0..cols).step_by(TILE) {
            for i in i0..(i0 + TILE).min(rows) {
                for j in j0..(j0 + TILE).min(cols) {
                    out[i + j * rows] = data[i * cols + j];
                }
            }
        }
    }
    DMatrix::from_vec(rows, cols, out)
}

/// `c_lower ← c_lower + α·a·bᵀ` on the lower triangle (diagonal included) of the square
/// n × n `c`, then the upper triangle is set to the mirror of the lower one, so `c` is exactly
/// symmetric. For `a·bᵀ` known to be symmetric (e.g. `(ΦP)Φᵀ`) this computes half the
/// products of a full `gemm` (faer's triangular matmul, parallel on rayon's threads).
pub fn gemm_nt_symmetric(c: &mut DMatrix<f64>, alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>) {
    use faer::linalg::matmul::triangular::{matmul, BlockStructure};
    let n = c.nrows();
    if c.ncols() != n || a.nrows() != n || b.nrows() != n || a.ncols() != b.ncols() {
        // Shapes that cannot be a symmetric product: the general product reports the mismatch.
        gemm_nt(c, alpha, a, b, 1.0);
        symmetrize_tiled(c);
        return;
    }
    let k = a.ncols();
    {
        let dst = faer::MatMut::from_column_major_slice_mut(c.as_mut_slice(), n, n);
        let lhs = faer::MatRef::from_column_major_slice(a.as_slice(), n, k);
        let rhs = faer::MatRef::from_column_major_slice(b.as_slice(), n, k).transpose();
        matmul(
            dst,
            BlockStructure::TriangularLower,
            faer::Accum::Add,
            lhs,
            BlockStructure::Rectangular,
            rhs,
            BlockStructure::Rectangular,
            alpha,
            faer::Par::rayon(0),
        );
    }
    mirror_lower(c);
}

/// Call `f(lower, upper)` with the buffer offsets of every pair `(i, j)`, `(j, i)` with
/// i > j of a square n × n column-major matrix, tile by tile (both tiles stay in L1).
fn for_each_symmetric_pair(n: usize, mut f: impl FnMut(usize, usize)) {
    for j0 in (0..n).step_by(TILE) {
        for i0 in (j0..n).step_by(TILE) {
            for j in j0..(j0 + TILE).min(n) {
                let start = if i0 == j0 { j + 1 } else { i0 };
                for i in start..(i0 + TILE).min(n) {
                    f(i + j * n, j + i * n);
                }
            }
        }
    }
}

/// Copy the lower triangle of a square matrix onto its upper triangle, tile by tile.
pub fn mirror_lower(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    let s = m.as_mut_slice();
    for_each_symmetric_pair(n, |lo, up| s[up] = s[lo]);
}

/// `M ← (M + Mᵀ)/2` in place for a square matrix, tile by tile.
pub fn symmetrize_tiled(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    let s = m.as_mut_slice();
    for_each_symmetric_pair(n, |lo, up| {
        let v = 0.5 * (s[lo] + s[up]);
        s[lo] = v;
        s[up] = v;
    });
}

/// Largest `|M[i, j] − M[j, i]|` and where (i > j), tile by tile.
pub fn max_asymmetry(m: &DMatrix<f64>) -> (f64, (usize, usize)) {
    let n = m.nrows();
    let s = m.as_slice();
    let (mut worst, mut at) = (0.0, (0, 0));
    for_each_symmetric_pair(n, |lo, up| {
        let d = (s[lo] - s[up]).abs();
        if d > worst {
            worst = d;
            at = (lo % n, lo / n);
        }
    });
    (worst, at)
}

/// Which 3 × 3 blocks of `phi` (NS × NS, NS a multiple of 3, at most 24) hold a non-zero
/// entry: per block row, the block columns, in order. None when NS is not such a size.
fn nonzero_blocks<const NS: usize>(phi: &SMatrix<f64, NS, NS>) -> Option<[([usize; 8], usize); 8]> {
    if !NS.is_multiple_of(3) || NS > 24 {
        return None;
    }
    let nb = NS / 3;
    let mut out = [([0usize; 8], 0usize); 8];
    for (bi, row) in out.iter_mut().enumerate().take(nb) {
        for bj in 0..nb {
            let any = (0..3).any(|r| (0..3).any(|c| phi[(3 * bi + r, 3 * bj + c)] != 0.0));
            if any {
                row.0[row.1] = bj;
                row.1 += 1;
            }
        }
    }
    Some(out)
}

/// `out = x · phiᵀ` with `phi`'s non-zero 3 × 3 blocks `nz` ([`nonzero_blocks`]): column
/// `c` of `out` is `Σ_k phi[c, k] · x[:, k]` over the columns k of the blocks of `phi`'s row `c`.
fn times_transpose_blocks<const NS: usize>(
    x: &SMatrix<f64, NS, NS>,
    phi: &SMatrix<f64, NS, NS>,
    nz: &[([usize; 8], usize); 8],
) -> SMatrix<f64, NS, NS> {
    let mut out = SMatrix::<f64, NS, NS>::zeros();
    times_transpose_blocks_into(x, phi, nz, &mut out);
    out
}

/// [`times_transpose_blocks`] written into `out` (overwritten; the same sums in the same order).
/// On x86-64 CPUs with AVX2 the same code is compiled for 4-wide vectors instead of the
/// baseline's 2-wide SSE2, chosen at run time: element-wise products and sums, no fused
/// multiply-add (Rust never contracts `a·b + c`), so the bits are the baseline's.
fn times_transpose_blocks_into<const NS: usize>(
    x: &SMatrix<f64, NS, NS>,
    phi: &SMatrix<f64, NS, NS>,
    nz: &[([usize; 8], usize); 8],
    out: &mut SMatrix<f64, NS, NS>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked on the line above).
        unsafe { times_transpose_blocks_avx2(x, phi, nz, out) };
        return;
    }
    times_transpose_blocks_body(x, phi, nz, out);
}

/// [`times_transpose_blocks_body`] compiled with AVX2 enabled.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn times_transpose_blocks_avx2<const NS: usize>(
    x: &SMatrix<f64, NS, NS>,
    phi: &SMatrix<f64, NS, NS>,
    nz: &[([usize; 8], usize); 8],
    out: &mut SMatrix<f64, NS, NS>,
) {
    times_transpose_blocks_body(x, phi, nz, out);
}

/// The loops of [`times_transpose_blocks_into`], inlined into each of its two builds.
#[inline(always)]
fn times_transpose_blocks_body<const NS: usize>(
    x: &SMatrix<f64, NS, NS>,
    phi: &SMatrix<f64, NS, NS>,
    nz: &[([usize; 8], usize); 8],
    out: &mut SMatrix<f64, NS, NS>,
) {
    // A slice's fill (a memset): nalgebra's `fill` on a static matrix compiled to a strided
    // loop that cost as much as the products (perf, the walk's protection-level bank).
    out.as_mut_slice().fill(0.0);
    let xs = x.as_slice();
    for (bi, (blocks, count)) in nz.iter().enumerate().take(NS / 3) {
        for r in 0..3 {
            let col = 3 * bi + r;
            let oc = &mut out.as_mut_slice()[col * NS..(col + 1) * NS];
            for &bj in &blocks[..*count] {
                for cc in 0..3 {
                    let k = 3 * bj + cc;
                    let f = phi[(col, k)];
                    if f != 0.0 {
                        for (o, v) in oc.iter_mut().zip(&xs[k * NS..(k + 1) * NS]) {
                            *o += f * v;
                        }
                    }
                }
            }
        }
    }
}

/// `Φ P Φᵀ` for a symmetric `p` and a transition `phi` most of whose 3 × 3 blocks are zero
/// (an INS error filter's: ten of 25 at 15 states), with the zero blocks skipped: `C = P Φᵀ`,
/// then `Cᵀ Φᵀ` (= Φ P Φᵀ since `Cᵀ = Φ P`), each a column-by-column sum over the non-zero
/// blocks of a row of Φ — 9·NS multiply-adds per non-zero block and product instead of NS³.
/// Equal to the dense product to rounding (a different order of the sums; not symmetrised).
/// Sizes that are not a multiple of 3 (or above 24) take the dense product.
pub fn sandwich_block_sparse<const NS: usize>(
    phi: &SMatrix<f64, NS, NS>,
    p: &SMatrix<f64, NS, NS>,
) -> SMatrix<f64, NS, NS> {
    let mut out = *p;
    sandwich_block_sparse_in_place(phi, &mut out);
    out
}

/// [`sandwich_block_sparse`] written over `p` itself, without the copies of `p` that returning
/// the product costs (the strapdown filters propagate their covariance at every IMU sample).
pub fn sandwich_block_sparse_in_place<const NS: usize>(
    phi: &SMatrix<f64, NS, NS>,
    p: &mut SMatrix<f64, NS, NS>,
) {
    match nonzero_blocks(phi) {
        Some(nz) => {
            let c = times_transpose_blocks(p, phi, &nz).transpose();
            times_transpose_blocks_into(&c, phi, &nz, p);
        }
        None => *p = phi * *p * phi.transpose(),
    }
}

/// `p ← (p + pᵀ)/2` in place: each pair set to `0.5·(p_ij + p_ji)` — the same values as
/// `0.5 * (p + p.transpose())`, without its two temporaries.
pub fn symmetrise<const NS: usize>(p: &mut SMatrix<f64, NS, NS>) {
    for j in 0..NS {
        // `0.5·(x + x)` is `x` but where `x + x` overflows: kept as the expression is.
        p[(j, j)] = 0.5 * (p[(j, j)] + p[(j, j)]);
        for i in j + 1..NS {
            let m = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = m;
            p[(j, i)] = m;
        }
    }
}

/// `Φ T` for a `phi` most of whose 3 × 3 blocks are zero (see [`sandwich_block_sparse`]);
/// equal to the dense product to rounding.
pub fn left_block_sparse<const NS: usize>(
    phi: &SMatrix<f64, NS, NS>,
    t: &SMatrix<f64, NS, NS>,
) -> SMatrix<f64, NS, NS> {
    match nonzero_blocks(phi) {
        // Φ T = (Tᵀ Φᵀ)ᵀ.
        Some(nz) => times_transpose_blocks(&t.transpose(), phi, &nz).transpose(),
        None => phi * t,
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::SMatrix;

    /// A transition with an INS error filter's block pattern (and a stray entry inside one
    /// block), and a symmetric positive matrix.
    fn structured<const NS: usize>(seed: u64) -> (SMatrix<f64, NS, NS>, SMatrix<f64, NS, NS>) {
        let mut state = seed;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut phi = SMatrix::<f64, NS, NS>::identity();
        for (bi, bj) in [
            (0, 0),
            (0, 1),
            (1, 0),
            (1, 1),
            (1, 2),
            (1, 4),
            (2, 2),
            (2, 3),
        ] {
            for r in 0..3 {
                for c in 0..3 {
                    phi[(3 * bi + r, 3 * bj + c)] += 0.01 * rnd();
                }
            }
        }
        if NS > 15 {
            phi[(15, 17)] = 0.25;
        }
        let a = SMatrix::<f64, NS, NS>::from_fn(|_, _| rnd());
        (phi, a * a.transpose() + SMatrix::<f64, NS, NS>::identity())
    }

    fn check<const NS: usize>() {
        for seed in 1..20 {
            let (phi, p) = structured::<NS>(seed);
            let dense = phi * p * phi.transpose();
            let sparse = super::sandwich_block_sparse(&phi, &p);
            let rel = (sparse - dense).abs().max() / dense.abs().max();
            assert!(rel < 1e-14, "NS {NS}: {rel:e}");
            let left = super::left_block_sparse(&phi, &p);
            let rel = (left - phi * p).abs().max() / (phi * p).abs().max();
            assert!(rel < 1e-14, "NS {NS}: {rel:e}");
            // In place: the same bits as the returned product, and the in-place symmetrisation
            // the same bits as `0.5 (P + Pᵀ)` (the product alone is not exactly symmetric).
            let mut inplace = p;
            super::sandwich_block_sparse_in_place(&phi, &mut inplace);
            assert_eq!(inplace, sparse, "NS {NS}");
            assert_ne!(sparse, sparse.transpose(), "NS {NS}: nothing to symmetrise");
            super::symmetrise(&mut inplace);
            assert_eq!(inplace, 0.5 * (sparse + sparse.transpose()), "NS {NS}");
            // The run-time dispatched kernel (AVX2 where the CPU has it) gives the baseline
            // build's bits.
            let nz = super::nonzero_blocks(&phi).expect("a multiple of 3");
            let mut baseline = SMatrix::<f64, NS, NS>::zeros();
            super::times_transpose_blocks_body(&p, &phi, &nz, &mut baseline);
            assert_eq!(
                super::times_transpose_blocks(&p, &phi, &nz),
                baseline,
                "NS {NS}"
            );
        }
    }

    #[test]
    fn block_sparse_products_equal_the_dense_ones() {
        check::<15>();
        check::<18>();
        check::<21>();
        // Not a multiple of 3: the dense product.
        let p = SMatrix::<f64, 4, 4>::identity() * 2.0;
        let phi = SMatrix::<f64, 4, 4>::identity();
        assert_eq!(super::sandwich_block_sparse(&phi, &p), p);
    }

    use super::*;

    #[test]
    fn symmetric_product_equals_the_full_one() {
        for &n in &[1usize, 7, 100, 131] {
            let phi = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 13) % 11) as f64 / 11.0 - 0.4);
            let l = DMatrix::from_fn(n, n, |i, j| ((i * 3 + j * 5) % 7) as f64 / 7.0);
            let p = &l * l.transpose() + DMatrix::identity(n, n);
            let ap = &phi * &p;
            let q = DMatrix::identity(n, n) * 0.01;
            let want = &q + 0.9 * &ap * phi.transpose();
            let mut got = q.clone();
            gemm_nt_symmetric(&mut got, 0.9, &ap, &phi);
            assert_eq!(got, got.transpose(), "exactly symmetric, n = {n}");
            let scale = want.amax();
            assert!((&got - &want).amax() <= 1e-12 * scale, "n = {n}");
        }
    }

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

    #[test]
    fn tiled_loops_match_plain_ones() {
        for (r, c) in [(3, 5), (64, 64), (100, 37), (130, 130)] {
            let data: Vec<f64> = (0..r * c).map(|v| v as f64 * 0.5 - 7.0).collect();
            assert_eq!(
                from_row_major(r, c, &data),
                DMatrix::from_row_slice(r, c, &data)
            );
        }
        for n in [1, 5, 33, 100] {
            let a = DMatrix::from_fn(n, n, |i, j| ((i * 31 + j * 17) % 23) as f64 - 11.0);
            let mut m = a.clone();
            symmetrize_tiled(&mut m);
            let expect = (&a + a.transpose()) * 0.5;
            assert_eq!(m, expect);
            let (w, at) = max_asymmetry(&a);
            let d = &a - a.transpose();
            assert_eq!(w, d.amax());
            assert_eq!((a[at] - a[(at.1, at.0)]).abs(), w);
        }
    }

    #[test]
    fn blocked_kernel_matches_nalgebra() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for (m, k, n) in [(48, 48, 48), (100, 60, 70), (130, 130, 130), (61, 200, 50)] {
            assert!(m * n * k >= BLOCKED_MIN);
            let a = DMatrix::from_fn(m, k, |_, _| next());
            let b = DMatrix::from_fn(k, n, |_, _| next());
            let c0 = DMatrix::from_fn(m, n, |_, _| next());
            let reference = &a * &b * 1.5 + &c0 * -0.5;
            let mut c1 = c0.clone();
            gemm(&mut c1, 1.5, &a, &b, -0.5);
            assert!((&c1 - &reference).amax() < 1e-11, "{m}x{k}x{n}");
            let mut c2 = c0.clone();
            gemm_nt(&mut c2, 1.5, &a, &b.transpose(), -0.5);
            assert!((&c2 - &reference).amax() < 1e-11, "nt {m}x{k}x{n}");
            let mut c3 = DMatrix::from_element(m, n, f64::NAN);
            gemm(&mut c3, 1.0, &a, &b, 0.0);
            assert!((&c3 - &a * &b).amax() < 1e-11);
        }
    }
}
