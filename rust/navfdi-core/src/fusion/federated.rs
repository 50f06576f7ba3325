//! Federated Kalman filter with fault detection, isolation and reinstatement (METHODS §5).
//!
//! Each sub-filter `i` estimates the common state (e.g. the 15 INS errors) from its own sensor
//! (`H_i`, `R_i`) and runs its detectors on its residuals. Every epoch:
//!
//! 1. each sub-filter predicts with `Φ` and `Q/β_i` (reset mode; `Q` in no-reset mode) and
//!    forms its innovation `r = z − Hx⁻`, `A` (NaN components skipped);
//! 2. its detectors test the innovation; the alarm of the detector named for isolation isolates
//!    the sub-filter (when isolation is enabled), its clearing reinstates it; a sub-filter that
//!    is not isolated then updates with the measurement. A measurement found faulty is thus
//!    never absorbed.
//! 3. the master fuses the healthy sub-filters (and, with `β_m > 0`, its own prediction):
//!    `P_g = (Σ P_i⁻¹)⁻¹`, `x_g = P_g Σ P_i⁻¹ x_i`, computed by sequential pairwise fusion
//!    (`K = P(P + P_i)⁻¹`, `x ← x + K(x_i − x)`, `P ← P − KP`), which needs no inverse of
//!    any `P_i`;
//! 4. reset mode: every healthy sub-filter is reset to `x_g`, `P_g/β_i`, and the master to
//!    `x_g`, `P_g/β_m`, with the shares renormalised over the healthy sources so that they sum
//!    to one (isolation then loses no information share). A reinstated sub-filter is reset from
//!    the global solution (in both modes) and rejoins the fusion at the next epoch.
//!
//! An isolated sub-filter never feeds the master. **Resolution** (a measured departure from
//! METHODS §5's "nor is reset from it", see docs/yang2013.md): by default
//! ([`IsolatedMode::Track`]) it takes the global solution after each fusion without
//! contributing to it, so its detectors test its sensor against the fault-free navigation
//! solution and see the fault's end at once. The literal alternatives are selectable:
//! [`IsolatedMode::Update`] keeps updating with the faulty sensor (it absorbs the fault, and
//! its alarm outlasts the fault by minutes); [`IsolatedMode::Predict`] only predicts (no
//! absorption, but a sub-filter isolated before it has converged, or for long, carries a
//! stale state whose persistent residual keeps the SPRT in alarm: it may never be reinstated). With no healthy source the
//! global solution is the previous one propagated (`Φ x_g`, `ΦP_gΦᵀ + Q`), so it is always
//! available. In reset mode with `Q_i = Q/β_i`, `P_i = P_g/β_i` and fusion at every epoch the
//! federated filter reproduces the centralised Kalman filter exactly for linear systems
//! (Carlson 1990); in no-reset mode the fusion ignores the correlation of the sub-filters'
//! common process noise and is optimistic.

use crate::detect::{Decision, Detector};
use crate::error::{Error, Result};
use crate::kalman::KalmanFilter;
use crate::validate::{
    check_covariance, check_finite_matrix, check_len, check_no_inf, check_shape,
};
use nalgebra::{Cholesky, DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Configuration of one sub-filter.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SubFilterConfig {
    /// Name (e.g. the sensor's).
    pub name: String,
    /// Measurement matrix `H_i` (m_i × n).
    pub h: DMatrix<f64>,
    /// Measurement-noise covariance `R_i` (m_i × m_i).
    pub r: DMatrix<f64>,
    /// Information share `β_i` (> 0).
    pub share: f64,
    /// Named detectors.
    pub detectors: Vec<(String, Detector)>,
    /// Index into `detectors` of the detector whose alarm isolates the sub-filter.
    pub isolation: Option<usize>,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct SubFilter {
    cfg: SubFilterConfig,
    kf: KalmanFilter,
    isolated: bool,
}

/// What one sub-filter did in one epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct SubReport {
    /// `λ = rᵀA⁻¹r` of the update (NaN without measurement).
    pub statistic: f64,
    /// Components used.
    pub dof: usize,
    /// Each detector's decision, in configuration order.
    pub decisions: Vec<Decision>,
    /// Isolated after this epoch's decision.
    pub isolated: bool,
    /// Reinstated (reset from the global solution) this epoch.
    pub reinstated: bool,
    /// Contributed to this epoch's fusion.
    pub fused: bool,
}

/// One epoch of the federated filter.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    /// Per sub-filter.
    pub subs: Vec<SubReport>,
    /// Number of sources fused (sub-filters and master); 0 means the global solution was
    /// propagated without measurements.
    pub sources: usize,
}

/// The federated filter.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct FederatedFilter {
    subs: Vec<SubFilter>,
    mode: FusionMode,
    master_share: f64,
    master: Option<KalmanFilter>,
    x: DVector<f64>,
    p: DMatrix<f64>,
    isolation_enabled: bool,
    isolated_mode: IsolatedMode,
}

impl FederatedFilter {
    /// Build a federated filter; every sub-filter and the master start from `x0`, `P0/β`.
    ///
    /// Shares must be positive and sum, with `master_share ≥ 0`, to 1. In no-reset mode the
    /// sub-filters start from `P0` and the shares only matter for reinstatement.
    pub fn new(
        x0: DVector<f64>,
        p0: DMatrix<f64>,
        subs: Vec<SubFilterConfig>,
        mode: FusionMode,
        master_share: f64,
        isolation_enabled: bool,
    ) -> Result<Self> {
        let global = KalmanFilter::new(x0.clone(), p0.clone())?;
        let n = global.dim();
        if subs.is_empty() {
            return Err(Error::Invalid(
                "subfilters: at least one sub-filter is required".into(),
            ));
        }
        if !(master_share >= 0.0 && master_share.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "master_share".into(),
                value: master_share,
                requirement: "must be finite and >= 0".into(),
            });
        }
        let total: f64 = subs.iter().map(|s| s.share).sum::<f64>() + master_share;
        if (total - 1.0).abs() > 1e-6 {
            return Err(Error::Invalid(format!(
                "shares must sum to 1 (Σβ_i + master_share = {total})"
            )));
        }
        let mut built = Vec::with_capacity(subs.len());
        for (i, cfg) in subs.into_iter().enumerate() {
            let label = format!("subfilters[{i}] ({})", cfg.name);
            if !(cfg.share > 0.0 && cfg.share.is_finite()) {
                return Err(Error::InvalidParameter {
                    name: format!("{label}.share"),
                    value: cfg.share,
                    requirement: "must be > 0".into(),
                });
            }
            let m = cfg.h.nrows();
            check_shape(&format!("{label}.H"), &cfg.h, m, n)?;
            check_finite_matrix(&format!("{label}.H"), &cfg.h)?;
            check_shape(&format!("{label}.R"), &cfg.r, m, m)?;
            check_covariance(&format!("{label}.R"), &cfg.r)?;
            if let Some(k) = cfg.isolation {
                if k >= cfg.detectors.len() {
                    return Err(Error::Invalid(format!(
                        "{label}.isolation: detector index {k} out of range"
                    )));
                }
            }
            let p = match mode {
                FusionMode::Reset => &p0 / cfg.share,
                FusionMode::NoReset => p0.clone(),
            };
            built.push(SubFilter {
                kf: KalmanFilter::new(x0.clone(), p)?,
                cfg,
                isolated: false,
            });
        }
        let master = if master_share > 0.0 && mode == FusionMode::Reset {
            Some(KalmanFilter::new(x0.clone(), &p0 / master_share)?)
        } else {
            None
        };
        Ok(FederatedFilter {
            subs: built,
            mode,
            master_share,
            master,
            x: x0,
            p: p0,
            isolation_enabled,
            isolated_mode: IsolatedMode::Track,
        })
    }

    /// What an isolated sub-filter does (default [`IsolatedMode::Track`]).
    pub fn set_isolated_mode(&mut self, mode: IsolatedMode) {
        self.isolated_mode = mode;
    }

    /// Global estimate `x_g` (n).
    pub fn x(&self) -> &DVector<f64> {
        &self.x
    }

    /// Global covariance `P_g` (n × n).
    pub fn p(&self) -> &DMatrix<f64> {
        &self.p
    }

    /// Number of sub-filters.
    pub fn len(&self) -> usize {
        self.subs.len()
    }

    /// True when there are no sub-filters (never, after construction).
    pub fn is_empty(&self) -> bool {
        self.subs.is_empty()
    }

    /// Sub-filter names.
    pub fn names(&self) -> Vec<String> {
        self.subs.iter().map(|s| s.cfg.name.clone()).collect()
    }

    /// Detector names of sub-filter `i`.
    pub fn detector_names(&self, i: usize) -> Vec<String> {
        self.subs
            .get(i)
            .map(|s| s.cfg.detectors.iter().map(|d| d.0.clone()).collect())
            .unwrap_or_default()
    }

    /// State estimate of sub-filter `i`.
    pub fn sub_x(&self, i: usize) -> Option<&DVector<f64>> {
        self.subs.get(i).map(|s| s.kf.x())
    }

    /// Isolation flags.
    pub fn isolated(&self) -> Vec<bool> {
        self.subs.iter().map(|s| s.isolated).collect()
    }

    /// Replace the measurement model of sub-filter `i` (validated).
    pub fn set_model(&mut self, i: usize, h: DMatrix<f64>, r: DMatrix<f64>) -> Result<()> {
        let n = self.x.len();
        let sub = self
            .subs
            .get_mut(i)
            .ok_or_else(|| Error::Invalid(format!("sub-filter index {i} out of range")))?;
        let m = sub.cfg.h.nrows();
        check_shape("H", &h, m, n)?;
        check_finite_matrix("H", &h)?;
        check_shape("R", &r, m, m)?;
        check_covariance("R", &r)?;
        sub.cfg.h = h;
        sub.cfg.r = r;
        Ok(())
    }

    /// Replace `H_i` without validation (the caller guarantees shape and finiteness).
    pub fn set_h_trusted(&mut self, i: usize, h: &DMatrix<f64>) {
        if let Some(sub) = self.subs.get_mut(i) {
            sub.cfg.h.copy_from(h);
        }
    }

    /// Replace `R_i` without validation (the caller guarantees shape and a valid covariance).
    pub fn set_r_trusted(&mut self, i: usize, r: &DMatrix<f64>) {
        if let Some(sub) = self.subs.get_mut(i) {
            sub.cfg.r.copy_from(r);
        }
    }

    /// Validate one epoch's inputs: `Φ`, `Q` (n × n) and one measurement per sub-filter.
    pub fn check_step(
        &self,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
        zs: &[DVector<f64>],
    ) -> Result<()> {
        let n = self.x.len();
        check_shape("Phi", phi, n, n)?;
        check_finite_matrix("Phi", phi)?;
        check_shape("Q", q, n, n)?;
        check_covariance("Q", q)?;
        if zs.len() != self.subs.len() {
            return Err(Error::Invalid(format!(
                "measurements: {} given for {} sub-filters",
                zs.len(),
                self.subs.len()
            )));
        }
        for (z, s) in zs.iter().zip(&self.subs) {
            let name = format!("measurements[{}]", s.cfg.name);
            check_len(&name, z, s.cfg.h.nrows())?;
            check_no_inf(&name, z)?;
        }
        Ok(())
    }

    /// One validated epoch; on error the filter is unchanged.
    pub fn step(
        &mut self,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
        zs: &[DVector<f64>],
    ) -> Result<StepReport> {
        self.check_step(phi, q, zs)?;
        let mut work = self.clone();
        let report = work.step_trusted(phi, q, zs)?;
        *self = work;
        Ok(report)
    }

    /// One epoch without input validation (for whole-run loops that validated up front).
    /// On error the filter may be partly updated.
    pub fn step_trusted(
        &mut self,
        phi: &DMatrix<f64>,
        q: &DMatrix<f64>,
        zs: &[DVector<f64>],
    ) -> Result<StepReport> {
        let reset = self.mode == FusionMode::Reset;
        let mut reports = Vec::with_capacity(self.subs.len());
        for (sub, z) in self.subs.iter_mut().zip(zs) {
            // 1. filter
            let q_scale = if reset { 1.0 / sub.cfg.share } else { 1.0 };
            sub.kf
                .predict_scaled(phi, q, q_scale, 1.0)
                .map_err(|e| ctx(&sub.cfg.name, e))?;
            let (inn, pending) = sub
                .kf
                .innovation_pending(z, &sub.cfg.h, &sub.cfg.r)
                .map_err(|e| ctx(&sub.cfg.name, e))?;
            // 2. detect
            let mut decisions = Vec::with_capacity(sub.cfg.detectors.len());
            for (_, det) in sub.cfg.detectors.iter_mut() {
                decisions.push(
                    det.test_innovation(&inn.residual, &inn.covariance, inn.statistic, inn.dof())
                        .map_err(|e| ctx(&sub.cfg.name, e))?,
                );
            }
            let was = sub.isolated;
            if self.isolation_enabled {
                if let Some(k) = sub.cfg.isolation {
                    sub.isolated = decisions[k].alarm;
                }
            }
            if !sub.isolated || self.isolated_mode == IsolatedMode::Update {
                if let Some(pending) = pending {
                    sub.kf
                        .apply_pending(pending, &sub.cfg.r)
                        .map_err(|e| ctx(&sub.cfg.name, e))?;
                }
            }
            reports.push(SubReport {
                statistic: inn.statistic,
                dof: inn.dof(),
                decisions,
                isolated: sub.isolated,
                reinstated: was && !sub.isolated,
                fused: false,
            });
        }
        // 3. fuse
        if let Some(m) = self.master.as_mut() {
            m.predict_scaled(phi, q, 1.0 / self.master_share, 1.0)?;
        }
        let healthy: Vec<usize> = (0..self.subs.len())
            .filter(|&i| !reports[i].isolated && !reports[i].reinstated)
            .collect();
        let use_master = self.master.is_some() && reset;
        let sources = healthy.len() + usize::from(use_master);
        if sources == 0 {
            // Keep the global solution available: propagate it.
            let mut g = KalmanFilter::new(self.x.clone(), self.p.clone())?;
            g.predict_trusted(phi, q, 1.0)?;
            self.x = g.x().clone();
            self.p = g.p().clone();
        } else if sources == 1 && !use_master {
            let s = &self.subs[healthy[0]].kf;
            self.x = s.x().clone();
            self.p = s.p().clone();
        } else {
            // Sequential pairwise fusion, algebraically the information form
            // P_g = (Σ P_i⁻¹)⁻¹, x_g = P_g Σ P_i⁻¹ x_i, without inverting any P_i:
            // K = P (P + P_i)⁻¹, x ← x + K(x_i − x), P ← P − K P.
            let mut sources_iter = healthy
                .iter()
                .map(|&i| {
                    (
                        self.subs[i].cfg.name.as_str(),
                        self.subs[i].kf.x(),
                        self.subs[i].kf.p(),
                    )
                })
                .chain(
                    self.master
                        .as_ref()
                        .filter(|_| use_master)
                        .map(|m| ("master", m.x(), m.p())),
                );
            let (_, x0, p0) = sources_iter
                .next()
                .ok_or_else(|| Error::Invalid("fusion: no source".into()))?;
            let mut x = x0.clone();
            let mut p = p0.clone();
            let mut k = DMatrix::<f64>::zeros(x.len(), x.len());
            let mut inv_diag = vec![0.0; x.len()];
            let mut kp = DMatrix::<f64>::zeros(x.len(), x.len());
            for (name, xi, pi) in sources_iter {
                let chol = Cholesky::new(&p + pi).ok_or_else(|| Error::NotPositiveDefinite {
                    name: format!("sum of the fused covariance and that of {name}"),
                    detail: "fusion needs P + P_i positive definite".into(),
                })?;
                k.copy_from(&p);
                crate::kalman::gain_from_cholesky(chol.l_dirty(), &mut k, &mut inv_diag);
                let dx = xi - &x;
                x.gemv(1.0, &k, &dx, 1.0);
                // P ← P − K P (K P computed into the spare buffer, then subtracted)
                kp.copy_from(&p);
                crate::linalg::gemm(&mut p, -1.0, &k, &kp, 1.0);
                crate::validate::symmetrize(&mut p);
            }
            if !x.iter().chain(p.iter()).all(|v| v.is_finite()) {
                return Err(Error::Numerical {
                    context: "fusion".into(),
                    detail: "the fused estimate is not finite".into(),
                });
            }
            self.x = x;
            self.p = p;
        }
        for &i in &healthy {
            reports[i].fused = true;
        }
        // 4. reset and reinstatement
        let share_sum: f64 = healthy.iter().map(|&i| self.subs[i].cfg.share).sum::<f64>()
            + if use_master { self.master_share } else { 0.0 };
        let scale = if share_sum > 0.0 {
            1.0 / share_sum
        } else {
            1.0
        };
        for (i, sub) in self.subs.iter_mut().enumerate() {
            let r = &reports[i];
            let track = r.isolated && self.isolated_mode == IsolatedMode::Track;
            let do_reset = (reset && r.fused) || r.reinstated || track;
            if do_reset {
                let beta = match self.mode {
                    FusionMode::Reset => sub.cfg.share * scale,
                    FusionMode::NoReset => 1.0,
                };
                sub.kf.set_state_scaled(&self.x, &self.p, 1.0 / beta);
            }
        }
        if use_master {
            let beta = self.master_share * scale;
            if let Some(m) = self.master.as_mut() {
                m.set_state_scaled(&self.x, &self.p, 1.0 / beta);
            }
        }
        Ok(StepReport {
            subs: reports,
            sources,
        })
    }
}

fn ctx(name: &str, e: Error) -> Error {
    match e {
        Error::NotPositiveDefinite { name: n, detail } => Error::NotPositiveDefinite {
            name: format!("sub-filter {name}: {n}"),
            detail,
        },
        Error::Numerical { context, detail } => Error::Numerical {
            context: format!("sub-filter {name}: {context}"),
            detail,
        },
        other => Error::Invalid(format!("sub-filter {name}: {other}")),
    }
}

/// Federated fusion mode (METHODS §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FusionMode {
    /// After fusion each healthy sub-filter is reset to `x_g`, `P_g/β_i` (Carlson).
    Reset,
    /// Sub-filters run independently; the master only fuses.
    NoReset,
}

/// Behaviour of an isolated sub-filter (it never feeds the master in any mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IsolatedMode {
    /// After each fusion take the global solution (`x_g`, `P_g/β_i`); its detectors then test
    /// the sensor against the fault-free navigation solution.
    #[default]
    Track,
    /// Predict only (no update, no reset) until reinstated.
    Predict,
    /// Keep updating with its own sensor (absorbs the fault).
    Update,
}
