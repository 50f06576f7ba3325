//! Linear Kalman filter (METHODS §1).
//!
//! * Predict: `x⁻ = Φx`, `P⁻ = S·ΦPΦᵀ + Q` with `Q = ΓQΓᵀ` already mapped and a fading factor
//!   `S ≥ 1` (paper 002; `S = 1` is the ordinary filter).
//! * Update: residual `r = z − Hx⁻`, its covariance `A = HP⁻Hᵀ + R`, gain `K = P⁻HᵀA⁻¹` from a
//!   Cholesky factor of `A` (no explicit inverse), `x = x⁻ + Kr`, Joseph form
//!   `P = (I − KH)P⁻(I − KH)ᵀ + KRKᵀ`, made exactly symmetric. The statistic `λ = rᵀA⁻¹r` is the
//!   squared norm of the whitened residual `L⁻¹r`.
//! * Missing data: a NaN component of `z` is skipped and the update runs on the remaining rows
//!   (reduced-dimension update). [`Innovation::used`] says which components were used; the
//!   residual and covariance of unused components are NaN.
//!
//! Every public method validates its inputs before touching the state, and commits the new
//! state only when it is finite, so a failed call leaves the filter exactly as it was.

use crate::error::{Error, Result};
use crate::linalg::{gemm, gemm_nt};
use crate::validate::{
    check_covariance, check_finite_matrix, check_finite_vector, check_len, check_no_inf,
    check_shape, symmetrize,
};
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

mod model;
mod selection;
mod sequential;
pub use model::FixedModel;
pub(crate) use sequential::sequential_rows;
pub use sequential::Sequential;

/// Result of one measurement update.
#[derive(Debug, Clone, PartialEq)]
pub struct Innovation {
    /// Residual (innovation) `r = z − Hx⁻`, length m; NaN where the component was not used.
    pub residual: DVector<f64>,
    /// Residual covariance `A = HP⁻Hᵀ + R`, m × m; NaN rows/columns for unused components.
    pub covariance: DMatrix<f64>,
    /// `λ = rᵀA⁻¹r` over the used components (χ²(dof) under no fault); NaN when none was used.
    pub statistic: f64,
    /// Which components of `z` were used (not NaN).
    pub used: Vec<bool>,
}

impl Innovation {
    /// Number of components used (the degrees of freedom of [`Innovation::statistic`]).
    pub fn dof(&self) -> usize {
        self.used.iter().filter(|u| **u).count()
    }

    fn empty(m: usize) -> Self {
        Innovation {
            residual: DVector::from_element(m, f64::NAN),
            covariance: DMatrix::from_element(m, m, f64::NAN),
            statistic: f64::NAN,
            used: vec![false; m],
        }
    }
}

/// Scratch buffers reused across steps so the hot loop does not allocate for fixed sizes.
#[derive(Debug, Clone)]
struct Workspace {
    nn_a: DMatrix<f64>,
    nn_c: DMatrix<f64>,
    x: DVector<f64>,
}

impl Workspace {
    fn new(n: usize) -> Self {
        Workspace {
            nn_a: DMatrix::zeros(n, n),
            nn_c: DMatrix::zeros(n, n),
            x: DVector::zeros(n),
        }
    }
}

/// A linear Kalman filter with state `x` (n) and covariance `P` (n × n).
///
/// Serialises as its state `{x, p}` only (the scratch buffers are rebuilt), for pickling.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(into = "KalmanState", try_from = "KalmanState")]
pub struct KalmanFilter {
    x: DVector<f64>,
    p: DMatrix<f64>,
    ws: Workspace,
    mws: Option<MWork>,
    /// The last `Q` that passed [`KalmanFilter::predict`]'s covariance check: an identical `Q`
    /// (element by element) is not checked again (the symmetric-PSD check dominates the cost
    /// of a checked predict for large n). Never serialised.
    validated_q: Option<DMatrix<f64>>,
    /// The model [`KalmanFilter::step`] runs ([`KalmanFilter::set_model`]).
    model: Option<Box<FixedModel>>,
    /// `x` and `P` before a [`KalmanFilter::step`], kept to restore them if it fails.
    saved: (DVector<f64>, DMatrix<f64>),
}

/// The serialised form of a [`KalmanFilter`]: its state and its fixed model, if any.
#[derive(serde::Serialize, serde::Deserialize)]
struct KalmanState {
    x: DVector<f64>,
    p: DMatrix<f64>,
    #[serde(default)]
    model: Option<FixedModel>,
}

impl From<KalmanFilter> for KalmanState {
    fn from(kf: KalmanFilter) -> Self {
        KalmanState {
            x: kf.x,
            p: kf.p,
            model: kf.model.map(|m| *m),
        }
    }
}

impl TryFrom<KalmanState> for KalmanFilter {
    type Error = Error;
    fn try_from(s: KalmanState) -> Result<Self> {
        let mut kf = KalmanFilter::new(s.x, s.p)?;
        if let Some(m) = s.model {
            kf.set_model(m.phi, m.q, m.h, m.r)?;
        }
        Ok(kf)
    }
}

impl KalmanFilter {
    /// Create a filter from an initial state `x0` (n) and covariance `P0` (n × n, symmetric
    /// positive semi-definite, finite).
    pub fn new(x0: DVector<f64>, p0: DMatrix<f64>) -> Result<Self> {
        let n = x0.len();
        if n == 0 {
            return Err(Error::Shape {
                name: "x0".into(),
                expected: "a non-empty state vector".into(),
                got: "(0,)".into(),
            });
        }
        check_finite_vector("x0", &x0)?;
        check_shape("P0", &p0, n, n)?;
        check_covariance("P0", &p0)?;
        let mut p = p0;
        symmetrize(&mut p);
        Ok(KalmanFilter {
            x: x0,
            p,
            ws: Workspace::new(n),
            mws: None,
            validated_q: None,
            model: None,
            saved: (DVector::zeros(0), DMatrix::zeros(0, 0)),
        })
    }

    /// State dimension n.
    pub fn dim(&self) -> usize {
        self.x.len()
    }

    /// Current state estimate.
    pub fn x(&self) -> &DVector<f64> {
        &self.x
    }

    /// Current covariance.
    pub fn p(&self) -> &DMatrix<f64> {
        &self.p
    }

    /// Replace state and covariance (e.g. a federated reset), validated like [`KalmanFilter::new`].
    pub fn set_state(&mut self, x: DVector<f64>, p: DMatrix<f64>) -> Result<()> {
        let n = self.dim();
        check_len("x", &x, n)?;
        check_finite_vector("x", &x)?;
        check_shape("P", &p, n, n)?;
        check_covariance("P", &p)?;
        self.x = x;
        self.p = p;
        symmetrize(&mut self.p);
        Ok(())
    }

    /// Set `x` and `p_scale·P` by copying into the existing buffers (no validation: same
    /// shapes, finite, `p_scale > 0`).
    pub fn set_state_scaled(&mut self, x: &DVector<f64>, p: &DMatrix<f64>, p_scale: f64) {
        self.x.copy_from(x);
        self.p.copy_from(p);
        self.p *= p_scale;
    }

    /// Validate the arguments of [`KalmanFilter::predict`] without changing anything.
    pub fn check_predict(&self, phi: &DMatrix<f64>, q: &DMatrix<f64>, fading: f64) -> Result<()> {
        self.check_predict_with(phi, q, fading, false)
    }

    /// [`KalmanFilter::check_predict`], skipping the covariance check of `Q` when `q_known`.
    fn check_predict_with(
        &self,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
        fading: f64,
        q_known: bool,
    ) -> Result<()> {
        let n = self.dim();
        check_shape("Phi", phi, n, n)?;
        check_finite_matrix("Phi", phi)?;
        check_shape("Q", q, n, n)?;
        if !q_known {
            check_covariance("Q", q)?;
        }
        check_fading(fading)
    }

    /// Time update `x⁻ = Φx`, `P⁻ = S·ΦPΦᵀ + Q`.
    ///
    /// `phi`: n × n transition matrix; `q`: n × n process-noise covariance already mapped to the
    /// state (ΓQΓᵀ), symmetric PSD; `fading`: factor `S ≥ 1` (1 for the ordinary filter).
    ///
    /// `Q` is checked (symmetric, PSD) unless it equals, element by element, the last `Q` that
    /// passed the check.
    pub fn predict(&mut self, phi: &DMatrix<f64>, q: &DMatrix<f64>, fading: f64) -> Result<()> {
        let known = self
            .validated_q
            .as_ref()
            .is_some_and(|v| v.shape() == q.shape() && v.as_slice() == q.as_slice());
        self.check_predict_with(phi, q, fading, known)?;
        self.predict_trusted(phi, q, fading)?;
        if !known {
            match self.validated_q.as_mut() {
                Some(v) if v.shape() == q.shape() => v.copy_from(q),
                _ => self.validated_q = Some(q.clone()),
            }
        }
        Ok(())
    }

    /// [`KalmanFilter::predict`] without input validation, for loops whose inputs were validated
    /// once up front. Still refuses to commit a non-finite result.
    pub fn predict_trusted(
        &mut self,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
        fading: f64,
    ) -> Result<()> {
        self.predict_scaled(phi, q, 1.0, fading)
    }

    /// `P⁻ = S·ΦPΦᵀ + c·Q` without validation (`c > 0`, e.g. `1/β_i` in a federated filter).
    pub fn predict_scaled(
        &mut self,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
        q_scale: f64,
        fading: f64,
    ) -> Result<()> {
        let ws = &mut self.ws;
        // x⁻ = Φx
        ws.x.gemv(1.0, phi, &self.x, 0.0);
        // P⁻ = S·(ΦP)Φᵀ + Q
        gemm(&mut ws.nn_a, 1.0, phi, &self.p, 0.0);
        ws.nn_c.copy_from(q);
        if q_scale != 1.0 {
            ws.nn_c *= q_scale;
        }
        let n = phi.nrows();
        if n * n * n >= crate::linalg::SYMMETRIC_MIN {
            // Large states: only the lower triangle of (ΦP)Φᵀ (symmetric), mirrored.
            crate::linalg::gemm_nt_symmetric(&mut ws.nn_c, fading, &ws.nn_a, phi);
        } else {
            gemm_nt(&mut ws.nn_c, fading, &ws.nn_a, phi, 1.0);
            symmetrize_with(&mut ws.nn_c, &mut ws.nn_a);
        }
        if !all_finite(ws.x.as_slice()) || !all_finite(ws.nn_c.as_slice()) {
            return Err(Error::Numerical {
                context: "predict".into(),
                detail: "the predicted state or covariance is not finite (overflow)".into(),
            });
        }
        // The previous state stays in `ws.x` and `ws.nn_c` (`step` keeps it from there).
        std::mem::swap(&mut self.x, &mut ws.x);
        std::mem::swap(&mut self.p, &mut ws.nn_c);
        Ok(())
    }

    /// Validate the arguments of [`KalmanFilter::update`] without changing anything.
    pub fn check_update(&self, z: &DVector<f64>, h: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<()> {
        let n = self.dim();
        let m = z.len();
        if m == 0 {
            return Err(Error::Shape {
                name: "z".into(),
                expected: "a non-empty measurement vector".into(),
                got: "(0,)".into(),
            });
        }
        check_no_inf("z", z)?;
        if h.ncols() == n && h.nrows() != m {
            // H fits the state: the measurement vector is the one of the wrong length.
            return Err(Error::Shape {
                name: "z".into(),
                expected: format!("({},) to match H ({} × {n})", h.nrows(), h.nrows()),
                got: format!("({m},)"),
            });
        }
        check_shape("H", h, m, n)?;
        check_finite_matrix("H", h)?;
        check_shape("R", r, m, m)?;
        check_covariance("R", r)
    }

    /// Measurement update with `z` (m; NaN marks a missing component), `H` (m × n) and `R`
    /// (m × m, symmetric PSD). Returns the residual, its covariance and `λ = rᵀA⁻¹r`.
    ///
    /// Fails with [`Error::NotPositiveDefinite`] when the innovation covariance of the used
    /// components cannot be factored; the filter is then unchanged.
    pub fn update(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<Innovation> {
        self.check_update(z, h, r)?;
        self.update_trusted(z, h, r)
    }

    /// [`KalmanFilter::update`] without input validation (shapes must already be right).
    pub fn update_trusted(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<Innovation> {
        let (inn, pending) = self.innovation_pending(z, h, r)?;
        if let Some(p) = pending {
            self.apply_pending(p, r)?;
        }
        Ok(inn)
    }

    /// Innovation on fully used inputs: `r = z − Hx⁻`, `A = HP⁻Hᵀ + R`, its Cholesky factor and
    /// `λ`. Leaves `HP⁻` and `Hᵀ` in the workspace for [`KalmanFilter::apply_core`].
    fn innovate_core(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<Innovated> {
        let n = self.dim();
        let k = z.len();
        let mw = self.mws.get_or_insert_with(|| MWork::new(n, k));
        if mw.hp.nrows() != k {
            *mw = MWork::new(n, k);
        }
        let mut a = r.clone();
        let mut res = z.clone();
        mw.selection = selection::rows_of(h, &mut mw.columns);
        if mw.selection {
            // H selects states (one 1 per row, zeros elsewhere): the products below are copies
            // and single subtractions, the same numbers as the general path's.
            selection::innovate(&self.p, &self.x, &mw.columns, &mut mw.hp, &mut a, &mut res);
        } else {
            // HP⁻ (k × n); PHᵀ = (HP)ᵀ since P is symmetric.
            gemm(&mut mw.hp, 1.0, h, &self.p, 0.0);
            h.transpose_to(&mut mw.ht);
            // A = (HP)Hᵀ + R  (k × k)
            gemm(&mut a, 1.0, &mw.hp, &mw.ht, 1.0);
            // residual r = z − Hx⁻
            res.gemv(-1.0, h, &self.x, 1.0);
        }
        symmetrize(&mut a);
        // Factored in the buffer the last applied update handed back (no allocation per epoch).
        let mut buf = std::mem::replace(&mut mw.chol_buf, DMatrix::zeros(0, 0));
        if buf.shape() == a.shape() {
            buf.copy_from(&a);
        } else {
            buf = a.clone();
        }
        let chol: Cholesky<f64, Dyn> =
            Cholesky::new(buf).ok_or_else(|| Error::NotPositiveDefinite {
                name: "innovation covariance A = H P Hᵀ + R".into(),
                detail: "Cholesky factorisation failed; check R and P".into(),
            })?;
        // Whitened residual w = L⁻¹r, λ = ‖w‖² (solved in a kept buffer).
        mw.w.copy_from(&res);
        if !chol.l_dirty().solve_lower_triangular_mut(&mut mw.w) {
            return Err(Error::Numerical {
                context: "update".into(),
                detail: "triangular solve of the innovation covariance failed".into(),
            });
        }
        let stat = mw.w.norm_squared();
        if !stat.is_finite() {
            return Err(Error::Numerical {
                context: "update".into(),
                detail: "the innovation statistic is not finite".into(),
            });
        }
        Ok((res, a, chol, stat))
    }

    /// Apply the update prepared by [`KalmanFilter::innovate_core`] (same `h`, `r`, and `P`
    /// unchanged since).
    ///
    /// The Joseph form `P = (I − KH)P⁻(I − KH)ᵀ + KRKᵀ` is evaluated without forming the n × n
    /// matrix `I − KH`: `T = (I − KH)P⁻ = P⁻ − K(HP⁻)`, then `T(I − KH)ᵀ = T − (THᵀ)Kᵀ`, so
    /// `P = T − (THᵀ − KR)Kᵀ`. The identity factors are applied exactly; every product has an
    /// inner dimension of m, which keeps the update O(n²m).
    fn apply_core(
        &mut self,
        r: &DMatrix<f64>,
        res: &DVector<f64>,
        chol: &Cholesky<f64, Dyn>,
    ) -> Result<()> {
        let Some(mw) = self.mws.as_mut() else {
            return Err(Error::Numerical {
                context: "update".into(),
                detail: "no innovation prepared".into(),
            });
        };
        // K = PHᵀA⁻¹ (n × k) by substitution with the Cholesky factor, then Kᵀ.
        mw.hp.transpose_to(&mut mw.k);
        gain_from_cholesky(chol.l_dirty(), &mut mw.k, &mut mw.inv_diag);
        let ws = &mut self.ws;
        // x = x⁻ + K r
        ws.x.copy_from(&self.x);
        ws.x.gemv(1.0, &mw.k, res, 1.0);
        // T = P⁻ − K(HP⁻)
        ws.nn_a.copy_from(&self.p);
        gemm(&mut ws.nn_a, -1.0, &mw.k, &mw.hp, 1.0);
        // U = THᵀ − KR  (n × k); a diagonal R (the usual case) scales K's columns.
        if mw.selection {
            selection::columns(&ws.nn_a, &mw.columns, &mut mw.u);
        } else {
            gemm(&mut mw.u, 1.0, &ws.nn_a, &mw.ht, 0.0);
        }
        if is_diagonal(r) {
            let n = mw.u.nrows();
            let ks = mw.k.as_slice();
            let us = mw.u.as_mut_slice();
            for j in 0..r.nrows() {
                let rj = r[(j, j)];
                for (u, k) in us[j * n..(j + 1) * n]
                    .iter_mut()
                    .zip(&ks[j * n..(j + 1) * n])
                {
                    *u -= k * rj;
                }
            }
        } else {
            gemm(&mut mw.u, -1.0, &mw.k, r, 1.0);
        }
        // P = T − U Kᵀ
        gemm_nt(&mut ws.nn_a, -1.0, &mw.u, &mw.k, 1.0);
        symmetrize_with(&mut ws.nn_a, &mut ws.nn_c);
        if !all_finite(ws.x.as_slice()) || !all_finite(ws.nn_a.as_slice()) {
            return Err(Error::Numerical {
                context: "update".into(),
                detail: "the updated state or covariance is not finite".into(),
            });
        }
        std::mem::swap(&mut self.x, &mut ws.x);
        std::mem::swap(&mut self.p, &mut ws.nn_a);
        Ok(())
    }

    /// Test-before-update, step 1: the innovation of `z` (NaN components skipped) without
    /// changing the state, plus what [`KalmanFilter::apply_pending`] needs to update with the
    /// same measurement afterwards (None when no component is available). Inputs must be valid
    /// as for [`KalmanFilter::update_trusted`].
    pub fn innovation_pending(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<(Innovation, Option<Pending>)> {
        let m = z.len();
        let used: Vec<bool> = z.iter().map(|v| !v.is_nan()).collect();
        let n_used = used.iter().filter(|u| **u).count();
        if n_used == 0 {
            return Ok((Innovation::empty(m), None));
        }
        if n_used == m {
            let (res, a, chol, stat) = self.innovate_core(z, h, r)?;
            let inn = Innovation {
                residual: res.clone(),
                covariance: a,
                statistic: stat,
                used,
            };
            return Ok((
                inn,
                Some(Pending {
                    idx: None,
                    res,
                    chol,
                }),
            ));
        }
        let idx: Vec<usize> = (0..m).filter(|i| used[*i]).collect();
        let (zr, hr, rr) = (
            z.select_rows(&idx),
            h.select_rows(&idx),
            r.select_rows(&idx).select_columns(&idx),
        );
        let (res_r, a_r, chol, stat) = self.innovate_core(&zr, &hr, &rr)?;
        let mut residual = DVector::from_element(m, f64::NAN);
        let mut covariance = DMatrix::from_element(m, m, f64::NAN);
        for (ai, &i) in idx.iter().enumerate() {
            residual[i] = res_r[ai];
            for (bi, &j) in idx.iter().enumerate() {
                covariance[(i, j)] = a_r[(ai, bi)];
            }
        }
        Ok((
            Innovation {
                residual,
                covariance,
                statistic: stat,
                used,
            },
            Some(Pending {
                idx: Some(idx),
                res: res_r,
                chol,
            }),
        ))
    }

    /// Test-before-update, step 2: update with the measurement whose innovation
    /// [`KalmanFilter::innovation_pending`] just computed (same `R`; no predict or update in
    /// between; `H` and `HP⁻` were kept from step 1).
    pub fn apply_pending(&mut self, pending: Pending, r: &DMatrix<f64>) -> Result<()> {
        let out = match &pending.idx {
            None => self.apply_core(r, &pending.res, &pending.chol),
            Some(idx) => {
                let rr = r.select_rows(idx).select_columns(idx);
                self.apply_core(&rr, &pending.res, &pending.chol)
            }
        };
        // The factor's storage goes back to the workspace for the next innovation.
        if let Some(mw) = self.mws.as_mut() {
            mw.chol_buf = pending.chol.unpack_dirty();
        }
        out
    }
}

/// `(r, A, Cholesky factor of A, λ)` of a fully used measurement.
type Innovated = (DVector<f64>, DMatrix<f64>, Cholesky<f64, Dyn>, f64);

/// A prepared measurement update (see [`KalmanFilter::innovation_pending`]).
#[derive(Debug, Clone)]
pub struct Pending {
    idx: Option<Vec<usize>>,
    res: DVector<f64>,
    chol: Cholesky<f64, Dyn>,
}

/// True when every off-diagonal element of the square matrix `m` is zero.
fn is_diagonal(m: &DMatrix<f64>) -> bool {
    let k = m.nrows();
    m.as_slice()
        .iter()
        .enumerate()
        .all(|(idx, v)| *v == 0.0 || idx % (k + 1) == 0)
}

/// Scratch buffers of the update for one measurement dimension k.
#[derive(Debug, Clone)]
struct MWork {
    hp: DMatrix<f64>,
    ht: DMatrix<f64>,
    k: DMatrix<f64>,
    u: DMatrix<f64>,
    inv_diag: Vec<f64>,
    /// Whether the last innovation's H was a selection, and the state each row selects.
    selection: bool,
    columns: Vec<usize>,
    /// The whitened residual `L⁻¹r` (k).
    w: DVector<f64>,
    /// Storage for the next Cholesky factor of `A` (k × k; empty until an update hands one back).
    chol_buf: DMatrix<f64>,
}

impl MWork {
    fn new(n: usize, k: usize) -> Self {
        MWork {
            hp: DMatrix::zeros(k, n),
            ht: DMatrix::zeros(n, k),
            k: DMatrix::zeros(n, k),
            u: DMatrix::zeros(n, k),
            inv_diag: vec![0.0; k],
            selection: false,
            columns: Vec::with_capacity(k),
            w: DVector::zeros(k),
            chol_buf: DMatrix::zeros(0, 0),
        }
    }
}

/// Overwrite `y = PHᵀ` (n × k) with `K = y A⁻¹`, where `A = LLᵀ` and `l` holds `L` in its lower
/// triangle (the upper triangle is ignored).
///
/// Two substitutions on the columns of `y`, which are contiguous in nalgebra's column-major
/// storage: `Z Lᵀ = Y` forward, then `K L = Z` backward. Each pivot is divided once (its
/// reciprocal is kept), so the inner loops are vectorisable multiply-adds.
pub(crate) fn gain_from_cholesky(l: &DMatrix<f64>, y: &mut DMatrix<f64>, inv_diag: &mut [f64]) {
    let n = y.nrows();
    let k = y.ncols();
    let lk = l.nrows();
    let ls = l.as_slice(); // column-major: L[(i, j)] = ls[i + j·lk]
    for i in 0..k {
        inv_diag[i] = 1.0 / ls[i + i * lk];
    }
    let data = y.as_mut_slice();
    // Forward: Z[:, i] = (Y[:, i] − Σ_{j<i} L[i, j] Z[:, j]) / L[i, i]
    for i in 0..k {
        let (done, rest) = data.split_at_mut(i * n);
        let col = &mut rest[..n];
        for (j, zj) in done.chunks_exact(n).enumerate() {
            let c = ls[i + j * lk];
            for (a, b) in col.iter_mut().zip(zj) {
                *a -= c * b;
            }
        }
        let d = inv_diag[i];
        col.iter_mut().for_each(|a| *a *= d);
    }
    // Backward: K[:, i] = (Z[:, i] − Σ_{j>i} L[j, i] K[:, j]) / L[i, i]
    for i in (0..k).rev() {
        let (head, done) = data.split_at_mut((i + 1) * n);
        let col = &mut head[i * n..];
        let lcol = &ls[i * lk + i + 1..i * lk + k];
        for (c, kj) in lcol.iter().zip(done.chunks_exact(n)) {
            for (a, b) in col.iter_mut().zip(kj) {
                *a -= c * b;
            }
        }
        let d = inv_diag[i];
        col.iter_mut().for_each(|a| *a *= d);
    }
}

/// Check a fading factor: finite and `≥ 1`.
pub fn check_fading(fading: f64) -> Result<()> {
    if !(fading >= 1.0) || !fading.is_finite() {
        return Err(Error::InvalidParameter {
            name: "fading".into(),
            value: fading,
            requirement: "fading factor S must be finite and >= 1".into(),
        });
    }
    Ok(())
}

/// `M ← (M + Mᵀ)/2` through a scratch buffer of the same shape: one transpose and one
/// vectorisable pass; exactly symmetric because floating-point addition commutes.
fn symmetrize_with(m: &mut DMatrix<f64>, scratch: &mut DMatrix<f64>) {
    if m.nrows() >= 64 {
        crate::linalg::symmetrize_tiled(m);
        return;
    }
    m.transpose_to(scratch);
    for (a, b) in m.as_mut_slice().iter_mut().zip(scratch.as_slice()) {
        *a = 0.5 * (*a + *b);
    }
}

/// True when every element is finite: `v·0` is 0 for finite `v` and NaN otherwise; four
/// independent accumulators let the loop vectorise (no early exit needed on the hot path).
fn all_finite(s: &[f64]) -> bool {
    let mut acc = [0.0f64; 4];
    let mut chunks = s.chunks_exact(4);
    for c in &mut chunks {
        for (a, v) in acc.iter_mut().zip(c) {
            *a += v * 0.0;
        }
    }
    let mut r = acc[0] + acc[1] + acc[2] + acc[3];
    for v in chunks.remainder() {
        r += v * 0.0;
    }
    r == 0.0
}

#[cfg(test)]
mod tests {
    use super::sequential::scalar_rows_kernel;
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn scalar_closed_form() {
        // x0 = 0, P0 = 4, Φ = 1, Q = 1 → P⁻ = 5; z = 2, H = 1, R = 5 → K = 0.5, x = 1, P = 2.5.
        let mut kf = KalmanFilter::new(
            DVector::from_element(1, 0.0),
            DMatrix::from_element(1, 1, 4.0),
        )
        .unwrap();
        kf.predict(
            &DMatrix::from_element(1, 1, 1.0),
            &DMatrix::from_element(1, 1, 1.0),
            1.0,
        )
        .unwrap();
        let inn = kf
            .update(
                &DVector::from_element(1, 2.0),
                &DMatrix::from_element(1, 1, 1.0),
                &DMatrix::from_element(1, 1, 5.0),
            )
            .unwrap();
        assert_relative_eq!(kf.x()[0], 1.0, max_relative = 1e-14);
        assert_relative_eq!(kf.p()[(0, 0)], 2.5, max_relative = 1e-14);
        assert_relative_eq!(inn.statistic, 4.0 / 10.0, max_relative = 1e-14);
        assert_relative_eq!(inn.covariance[(0, 0)], 10.0, max_relative = 1e-14);
    }

    #[test]
    fn fading_scales_propagated_covariance() {
        let mut kf = KalmanFilter::new(
            DVector::from_element(1, 0.0),
            DMatrix::from_element(1, 1, 4.0),
        )
        .unwrap();
        kf.predict(
            &DMatrix::from_element(1, 1, 2.0),
            &DMatrix::from_element(1, 1, 1.0),
            1.5,
        )
        .unwrap();
        assert_relative_eq!(kf.p()[(0, 0)], 1.5 * 16.0 + 1.0, max_relative = 1e-14);
        assert!(kf
            .predict(
                &DMatrix::from_element(1, 1, 1.0),
                &DMatrix::from_element(1, 1, 1.0),
                0.5
            )
            .is_err());
    }

    #[test]
    fn failed_update_leaves_state() {
        let mut kf =
            KalmanFilter::new(DVector::from_element(2, 1.0), DMatrix::zeros(2, 2)).unwrap();
        let before = (kf.x().clone(), kf.p().clone());
        // P = 0 and R = 0 → A = 0, not positive definite.
        let err = kf.update(
            &DVector::from_element(1, 0.0),
            &DMatrix::from_element(1, 2, 1.0),
            &DMatrix::zeros(1, 1),
        );
        assert!(matches!(err, Err(Error::NotPositiveDefinite { .. })));
        assert_eq!((kf.x().clone(), kf.p().clone()), before);
        // Wrong shapes and non-finite values are refused too.
        assert!(matches!(
            kf.update(
                &DVector::from_element(2, 0.0),
                &DMatrix::from_element(1, 2, 1.0),
                &DMatrix::identity(1, 1)
            ),
            Err(Error::Shape { .. })
        ));
        assert!(matches!(
            kf.update(
                &DVector::from_element(1, f64::INFINITY),
                &DMatrix::from_element(1, 2, 1.0),
                &DMatrix::identity(1, 1)
            ),
            Err(Error::NonFinite { .. })
        ));
        assert_eq!((kf.x().clone(), kf.p().clone()), before);
    }

    #[test]
    fn all_missing_is_a_no_op() {
        let mut kf =
            KalmanFilter::new(DVector::from_element(2, 1.0), DMatrix::identity(2, 2)).unwrap();
        let inn = kf
            .update(
                &DVector::from_element(2, f64::NAN),
                &DMatrix::identity(2, 2),
                &DMatrix::identity(2, 2),
            )
            .unwrap();
        assert_eq!(inn.dof(), 0);
        assert!(inn.statistic.is_nan());
        assert_eq!(kf.x(), &DVector::from_element(2, 1.0));
    }

    #[test]
    fn sequential_equals_batch_update() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for trial in 0..20 {
            let n = 17;
            let m = 3 + trial;
            let b = DMatrix::from_fn(n, n, |_, _| rng.random::<f64>() - 0.5);
            let p0 = &b * b.transpose() + DMatrix::identity(n, n) * 0.1;
            let x0 = DVector::from_fn(n, |_, _| rng.random::<f64>());
            // Sparse rows like a tight filter's (a few states each), some dense ones.
            let h = DMatrix::from_fn(m, n, |i, j| {
                if i % 3 == 0 || (j + i) % 5 == 0 {
                    rng.random::<f64>() - 0.5
                } else {
                    0.0
                }
            });
            let r_diag: Vec<f64> = (0..m).map(|_| 0.05 + rng.random::<f64>()).collect();
            let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
            let mut z = DVector::from_fn(m, |_, _| 3.0 * (rng.random::<f64>() - 0.5));
            if trial % 4 == 1 {
                z[1] = f64::NAN;
            }
            let mut batch = KalmanFilter::new(x0.clone(), p0.clone()).unwrap();
            let inn = batch.update_trusted(&z, &h, &r).unwrap();
            let mut kf = KalmanFilter::new(x0, p0).unwrap();
            let before = (kf.x().clone(), kf.p().clone());
            let mut seq = Sequential::new(1);
            kf.sequential_pending(&z, &h, &r_diag, &mut seq).unwrap();
            assert_eq!(
                (kf.x().clone(), kf.p().clone()),
                before,
                "not committed yet"
            );
            assert_eq!(seq.dof, inn.dof());
            assert_relative_eq!(seq.statistic, inn.statistic, max_relative = 1e-9);
            kf.commit_sequential(&mut seq).unwrap();
            assert!((kf.x() - batch.x()).amax() < 1e-9);
            assert!((kf.p() - batch.p()).amax() < 1e-9 * batch.p().amax());
            assert_eq!(kf.p(), &kf.p().transpose());
            // Committed once: a second commit is refused.
            assert!(kf.commit_sequential(&mut seq).is_err());
        }
    }

    #[test]
    fn sequential_refuses_a_non_positive_variance() {
        let kf = KalmanFilter::new(DVector::zeros(2), DMatrix::zeros(2, 2)).unwrap();
        let mut seq = Sequential::new(2);
        let err = kf.sequential_pending(
            &DVector::from_element(1, 1.0),
            &DMatrix::from_element(1, 2, 1.0),
            &[0.0],
            &mut seq,
        );
        assert!(matches!(err, Err(Error::NotPositiveDefinite { .. })));
        let mut kf = kf;
        assert!(kf.commit_sequential(&mut seq).is_err());
    }

    #[test]
    fn sequential_kernels_agree() {
        // The baseline build of the row loop (what a CPU without AVX2/FMA runs) against the
        // dispatched one.
        let n = 17;
        let p0 = DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                2.0
            } else {
                0.3 / (1.0 + (i + j) as f64)
            }
        });
        let kf = KalmanFilter::new(DVector::from_fn(n, |i, _| i as f64 * 0.1), p0).unwrap();
        let h = DMatrix::from_fn(12, n, |i, j| {
            if j % 4 == i % 4 {
                0.5 + j as f64 * 0.01
            } else {
                0.0
            }
        });
        let z = DVector::from_fn(12, |i, _| (i as f64).sin());
        let r = vec![0.7; 12];
        let mut a = Sequential::new(n);
        kf.sequential_pending(&z, &h, &r, &mut a).unwrap();
        let mut b = Sequential::new(n);
        b.x.copy_from(kf.x());
        b.p.copy_from(kf.p());
        let (stat, dof) = scalar_rows_kernel::<false>(&z, &h, &r, &mut b).unwrap();
        symmetrize(&mut b.p);
        assert_eq!(dof, a.dof);
        assert_relative_eq!(stat, a.statistic, max_relative = 1e-12);
        assert!((&a.x - &b.x).amax() < 1e-12);
        assert!((&a.p - &b.p).amax() < 1e-12);
    }
}
