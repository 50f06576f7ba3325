//! The row-by-row measurement update (test before update, diagonal `R`): [`Sequential`] and
//! [`KalmanFilter::sequential_pending`] / [`KalmanFilter::commit_sequential`], with the AVX2 +
//! FMA build of its row loop chosen at run time.

use super::{all_finite, KalmanFilter};
use crate::error::{Error, Result};
use crate::validate::symmetrize;
use nalgebra::{DMatrix, DVector};

/// A measurement update computed row by row (see [`KalmanFilter::sequential_pending`]),
/// held apart from the filter until [`KalmanFilter::commit_sequential`]. Its buffers are
/// reused from one epoch to the next.
#[derive(Debug, Clone)]
pub struct Sequential {
    pub(super) x: DVector<f64>,
    pub(super) p: DMatrix<f64>,
    u: Vec<f64>,
    k: Vec<f64>,
    nz: Vec<(usize, f64)>,
    /// `λ = rᵀA⁻¹r` of the used rows, accumulated as `Σ νᵢ²/sᵢ`.
    pub statistic: f64,
    /// Number of rows used (not NaN): the degrees of freedom of `statistic`.
    pub dof: usize,
    ready: bool,
}

impl Sequential {
    /// Empty buffers for a filter of n states.
    pub fn new(n: usize) -> Self {
        Sequential {
            x: DVector::zeros(n),
            p: DMatrix::zeros(n, n),
            u: vec![0.0; n],
            k: vec![0.0; n],
            nz: Vec::with_capacity(n),
            statistic: f64::NAN,
            dof: 0,
            ready: false,
        }
    }
}

impl KalmanFilter {
    /// Test-before-update for a measurement with **diagonal** `R` (`r_diag`, m variances):
    /// the update computed one row at a time (scalar updates, each in Joseph form
    /// `P ← P − k uᵀ − u kᵀ + s k kᵀ` with `u = P hᵢ`, `s = hᵢᵀu + rᵢ`, `k = u/s`), skipping
    /// NaN components and the zero entries of each row of `H`, into `seq` — the filter is not
    /// changed. With uncorrelated measurement noise the scalar innovations `νᵢ` are the
    /// batch innovation decorrelated, so `Σ νᵢ²/sᵢ = rᵀA⁻¹r` (the batch statistic) and the
    /// result equals the batch update ([`KalmanFilter::innovation_pending`]) up to rounding,
    /// at O(n²) per row without a factorisation. Commit with
    /// [`KalmanFilter::commit_sequential`] (no predict or update in between).
    ///
    /// Fails with [`Error::NotPositiveDefinite`] when a row's innovation variance is not
    /// positive.
    pub fn sequential_pending(
        &self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
        seq: &mut Sequential,
    ) -> Result<()> {
        let n = self.dim();
        if seq.x.len() != n {
            *seq = Sequential::new(n);
        }
        seq.ready = false;
        seq.x.copy_from(&self.x);
        seq.p.copy_from(&self.p);
        let (stat, dof) =
            scalar_rows(z, h, r_diag, seq).map_err(|(i, s)| Error::NotPositiveDefinite {
                name: "innovation covariance A = H P Hᵀ + R".into(),
                detail: format!("row {i}: innovation variance {s} is not positive"),
            })?;
        if dof > 0 {
            symmetrize(&mut seq.p);
        }
        if !stat.is_finite() || !all_finite(seq.x.as_slice()) || !all_finite(seq.p.as_slice()) {
            return Err(Error::Numerical {
                context: "update".into(),
                detail: "the updated state, covariance or statistic is not finite".into(),
            });
        }
        seq.statistic = if dof > 0 { stat } else { f64::NAN };
        seq.dof = dof;
        seq.ready = true;
        Ok(())
    }

    /// Commit the update prepared by [`KalmanFilter::sequential_pending`] (the buffers are
    /// exchanged, not copied). Fails when nothing is prepared.
    pub fn commit_sequential(&mut self, seq: &mut Sequential) -> Result<()> {
        if !seq.ready || seq.x.len() != self.dim() {
            return Err(Error::Numerical {
                context: "update".into(),
                detail: "no sequential update prepared for this filter".into(),
            });
        }
        std::mem::swap(&mut self.x, &mut seq.x);
        std::mem::swap(&mut self.p, &mut seq.p);
        seq.ready = false;
        Ok(())
    }
}

/// The scalar row updates of [`KalmanFilter::sequential_pending`] on a state `x` and covariance
/// `p` kept outside a [`KalmanFilter`] (the tight filter's augmented range-error states,
/// [`crate::ins::range_states`]), with no validation of `p` beyond each row's innovation
/// variance: the updated `(x, P)` (P symmetrised) and `Σ νᵢ²/sᵢ` over the rows (NaN
/// components skipped). Fails with [`Error::NotPositiveDefinite`] naming `what` when a row's
/// innovation variance is not positive.
pub(crate) fn sequential_rows(
    x: DVector<f64>,
    p: DMatrix<f64>,
    z: &DVector<f64>,
    h: &DMatrix<f64>,
    r_diag: &[f64],
    what: &str,
) -> Result<(DVector<f64>, DMatrix<f64>, f64)> {
    let mut seq = Sequential::new(x.len());
    seq.x = x;
    seq.p = p;
    let (stat, dof) =
        scalar_rows(z, h, r_diag, &mut seq).map_err(|(i, s)| Error::NotPositiveDefinite {
            name: "innovation variance".into(),
            detail: format!("row {i} of {what}: {s}"),
        })?;
    if dof > 0 {
        symmetrize(&mut seq.p);
    }
    Ok((seq.x, seq.p, stat))
}

/// The row loop of [`KalmanFilter::sequential_pending`] on `seq`'s copies of x and P:
/// `(Σ νᵢ²/sᵢ, rows used)`, or the row and variance of a non-positive `sᵢ`. Runs the AVX2 +
/// FMA build of the loop where the CPU has them (detected at run time), the baseline one
/// otherwise.
fn scalar_rows(
    z: &DVector<f64>,
    h: &DMatrix<f64>,
    r_diag: &[f64],
    seq: &mut Sequential,
) -> std::result::Result<(f64, usize), (usize, f64)> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return unsafe { scalar_rows_avx2(z, h, r_diag, seq) };
        }
    }
    scalar_rows_kernel::<false>(z, h, r_diag, seq)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn scalar_rows_avx2(
    z: &DVector<f64>,
    h: &DMatrix<f64>,
    r_diag: &[f64],
    seq: &mut Sequential,
) -> std::result::Result<(f64, usize), (usize, f64)> {
    scalar_rows_kernel::<true>(z, h, r_diag, seq)
}

/// `a·b + c`, fused where `FMA` (only inside a build with the `fma` feature).
#[inline(always)]
fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

#[inline(always)]
pub(super) fn scalar_rows_kernel<const FMA: bool>(
    z: &DVector<f64>,
    h: &DMatrix<f64>,
    r_diag: &[f64],
    seq: &mut Sequential,
) -> std::result::Result<(f64, usize), (usize, f64)> {
    let n = seq.x.len();
    let mut stat = 0.0;
    let mut dof = 0;
    let Sequential { x, p, u, k, nz, .. } = seq;
    let (x, p) = (x.as_mut_slice(), p.as_mut_slice());
    let (u, k) = (&mut u[..n], &mut k[..n]);
    for (i, &zi) in z.iter().enumerate() {
        if zi.is_nan() {
            continue;
        }
        nz.clear();
        nz.extend((0..n).map(|j| (j, h[(i, j)])).filter(|(_, v)| *v != 0.0));
        u.iter_mut().for_each(|v| *v = 0.0);
        let mut pred = 0.0;
        for &(j, hj) in nz.iter() {
            for (uv, pv) in u.iter_mut().zip(&p[j * n..(j + 1) * n]) {
                *uv = madd::<FMA>(*pv, hj, *uv);
            }
            pred += hj * x[j];
        }
        let s = nz.iter().map(|&(j, hj)| hj * u[j]).sum::<f64>() + r_diag[i];
        if !(s > 0.0) || !s.is_finite() {
            return Err((i, s));
        }
        let nu = zi - pred;
        stat += nu * nu / s;
        dof += 1;
        let inv = 1.0 / s;
        for (kv, uv) in k.iter_mut().zip(u.iter()) {
            *kv = uv * inv;
        }
        for (xv, kv) in x.iter_mut().zip(k.iter()) {
            *xv = madd::<FMA>(*kv, nu, *xv);
        }
        // Joseph form of a scalar update, column by column:
        // P[:, b] += k·(s·k_b − u_b) − u·k_b.
        for (b, col) in p.chunks_exact_mut(n).enumerate() {
            let c1 = s * k[b] - u[b];
            let c2 = -k[b];
            for ((pv, kv), uv) in col.iter_mut().zip(k.iter()).zip(u.iter()) {
                *pv = madd::<FMA>(*uv, c2, madd::<FMA>(*kv, c1, *pv));
            }
        }
    }
    Ok((stat, dof))
}
