//! AIME: the autonomous integrity monitored extrapolation test (METHODS §11, paper 004).
//!
//! Over the last N epochs, with innovations `r_j` (m) and covariances `A_j`:
//! `r̄ = (Σ A_j⁻¹)⁻¹ Σ A_j⁻¹ r_j`, `Ā = (Σ A_j⁻¹)⁻¹`, statistic
//! `r̄ᵀĀ⁻¹r̄ = sᵀ S⁻¹ s` with the information sums `S = Σ A_j⁻¹`, `s = Σ A_j⁻¹ r_j`; under no
//! fault (independent zero-mean innovations) it is χ²(m); alarm when it reaches
//! `F⁻¹_{χ²(m)}(1 − P_f)`.
//!
//! The window sums are updated in O(m²) per epoch (add the new epoch's `A⁻¹`, `A⁻¹r`, subtract
//! the one leaving the window). Rounding would accumulate over millions of epochs, so the sums
//! are recomputed exactly from the stored window every N epochs (O(N m²) once per N epochs:
//! O(m²) per epoch on average); the drift test runs 10⁶ epochs.
//!
//! An epoch without any component leaves the window unchanged (as the other detectors do).
//! Missing components (NaN) contribute no information: the epoch's `A⁻¹` is the inverse of
//! the available sub-block, zero elsewhere. Components with no information in the whole window
//! are left out of the statistic, whose degrees of freedom are the components kept.

use super::{check_residual, Decision};
use crate::error::{Error, Result};
use crate::validate::check_probability;
use nalgebra::{Cholesky, DMatrix, DVector};
use std::collections::VecDeque;

/// Largest window accepted (epochs).
pub const MAX_WINDOW: usize = 1_000_000;

/// AIME detector with window `N` epochs and false-alarm probability `pf` per epoch.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Aime {
    pf: f64,
    window: usize,
    thresholds: Vec<f64>,
    /// Per epoch in the window: (A⁻¹ as a column-major m × m, A⁻¹ r).
    entries: VecDeque<(Vec<f64>, Vec<f64>)>,
    info: Vec<f64>,
    info_r: Vec<f64>,
    m: usize,
    since_resum: usize,
    alarm: bool,
    /// Scratch (not part of the state): A⁻¹, A⁻¹r of the epoch being added, the Cholesky
    /// factor of the decision, the kept components.
    #[serde(skip)]
    scratch: Scratch,
}

#[derive(Debug, Clone, Default)]
struct Scratch {
    ainv: Vec<f64>,
    ainv_r: Vec<f64>,
    l: Vec<f64>,
    v: Vec<f64>,
    keep: Vec<usize>,
}

/// Lower Cholesky factor of the k × k symmetric matrix in `a` (column-major, only the lower
/// triangle read), in place; false when it is not positive definite.
fn cholesky_in_place(a: &mut [f64], k: usize) -> bool {
    for j in 0..k {
        let mut d = a[j + j * k];
        for p in 0..j {
            d -= a[j + p * k] * a[j + p * k];
        }
        if !(d > 0.0) || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j + j * k] = d;
        for i in j + 1..k {
            let mut v = a[i + j * k];
            for p in 0..j {
                v -= a[i + p * k] * a[j + p * k];
            }
            a[i + j * k] = v / d;
        }
    }
    true
}

/// `‖L⁻¹v‖²` for the lower factor `l` (k × k) — `vᵀA⁻¹v` — overwriting `v`.
fn whitened_norm2(l: &[f64], k: usize, v: &mut [f64]) -> f64 {
    let mut s = 0.0;
    for i in 0..k {
        let mut x = v[i];
        for p in 0..i {
            x -= l[i + p * k] * v[p];
        }
        x /= l[i + i * k];
        v[i] = x;
        s += x * x;
    }
    s
}

/// `A⁻¹` (k × k, column-major) of a symmetric positive definite `a` into `out`, using `l`
/// as scratch; false when `a` is not positive definite.
fn spd_inverse(a: &[f64], k: usize, l: &mut Vec<f64>, out: &mut [f64]) -> bool {
    if k == 2 {
        // Closed form (a prefilter's or a satellite's two components: the hot case).
        let (a00, a10, a11) = (a[0], a[1], a[3]);
        let det = a00 * a11 - a10 * a10;
        if !(a00 > 0.0 && det > 0.0 && det.is_finite()) {
            return false;
        }
        let inv = 1.0 / det;
        out[0] = a11 * inv;
        out[1] = -a10 * inv;
        out[2] = -a10 * inv;
        out[3] = a00 * inv;
        return true;
    }
    l.clear();
    l.extend_from_slice(&a[..k * k]);
    if !cholesky_in_place(l, k) {
        return false;
    }
    // Columns of A⁻¹: solve L y = e_j, then Lᵀ x = y.
    for j in 0..k {
        let col = &mut out[j * k..(j + 1) * k];
        col.iter_mut().for_each(|v| *v = 0.0);
        col[j] = 1.0;
        for i in 0..k {
            let mut x = col[i];
            for p in 0..i {
                x -= l[i + p * k] * col[p];
            }
            col[i] = x / l[i + i * k];
        }
        for i in (0..k).rev() {
            let mut x = col[i];
            for p in i + 1..k {
                x -= l[p + i * k] * col[p];
            }
            col[i] = x / l[i + i * k];
        }
    }
    true
}

impl Aime {
    /// New detector: `pf` in (0, 1), `window` ≥ 1 epochs.
    pub fn new(pf: f64, window: usize) -> Result<Self> {
        check_probability("pf", pf)?;
        if window == 0 || window > MAX_WINDOW {
            return Err(Error::InvalidParameter {
                name: "window".into(),
                value: window as f64,
                requirement: format!("the AIME window must be 1 … {MAX_WINDOW} epochs"),
            });
        }
        Ok(Aime {
            pf,
            window,
            thresholds: Vec::new(),
            entries: VecDeque::new(),
            info: Vec::new(),
            info_r: Vec::new(),
            m: 0,
            since_resum: 0,
            alarm: false,
            scratch: Scratch::default(),
        })
    }

    /// False-alarm probability per epoch.
    pub fn pf(&self) -> f64 {
        self.pf
    }

    /// Window length N (epochs).
    pub fn window(&self) -> usize {
        self.window
    }

    /// Epochs currently in the window.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// No epoch in the window yet.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Last alarm state.
    pub fn alarm(&self) -> bool {
        self.alarm
    }

    /// Threshold for `dof` components (NaN for 0).
    pub fn threshold(&mut self, dof: usize) -> Result<f64> {
        super::cached_chi2_threshold(&mut self.thresholds, self.pf, dof)
    }

    /// Empty the window (keeps the dimension).
    pub fn reset(&mut self) {
        self.entries.clear();
        self.info.iter_mut().for_each(|v| *v = 0.0);
        self.info_r.iter_mut().for_each(|v| *v = 0.0);
        self.since_resum = 0;
        self.alarm = false;
    }

    /// Test one epoch: residual `r` (NaN = unavailable) and covariance `A`, validated
    /// (shape, finiteness, symmetric positive definite on the available components). A
    /// rejected epoch changes nothing. The residual dimension must stay the same between
    /// resets.
    pub fn test(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Result<Decision> {
        let checked = check_residual(r, a)?;
        let m = r.len();
        if !self.entries.is_empty() && m != self.m {
            return Err(Error::Invalid(format!(
                "residual: {m} components, but the AIME window holds {}-component residuals; reset() first to change the dimension",
                self.m
            )));
        }
        let Some(chol) = &checked.chol else {
            // No component this epoch: state unchanged, previous alarm repeated.
            return Ok(Decision {
                statistic: f64::NAN,
                threshold: f64::NAN,
                alarm: self.alarm,
                dof: 0,
            });
        };
        let mut ainv = std::mem::take(&mut self.scratch.ainv);
        let mut ainv_r = std::mem::take(&mut self.scratch.ainv_r);
        ainv.clear();
        ainv.resize(m * m, 0.0);
        ainv_r.clear();
        ainv_r.resize(m, 0.0);
        {
            let idx = &checked.idx;
            let inv = chol.inverse();
            for (p, &i) in idx.iter().enumerate() {
                for (q, &j) in idx.iter().enumerate() {
                    ainv[i + j * m] = inv[(p, q)];
                }
            }
            for &i in idx {
                ainv_r[i] = idx.iter().map(|&j| ainv[i + j * m] * r[j]).sum();
            }
        }
        let d = self.push(m, &ainv, &ainv_r);
        self.scratch.ainv = ainv;
        self.scratch.ainv_r = ainv_r;
        Ok(d)
    }

    /// [`Aime::test`] for callers that validated their inputs (inside whole runs): every
    /// component of `r` (m) present and finite, `a` (m × m, column-major) symmetric. An `a`
    /// that is not positive definite counts as an epoch without any component (state
    /// unchanged, previous alarm repeated); a change of dimension empties the window. No
    /// allocation once the window is full.
    pub fn test_trusted(&mut self, r: &[f64], a: &[f64]) -> Decision {
        let m = r.len();
        if !self.entries.is_empty() && m != self.m {
            self.reset();
        }
        let mut ainv = std::mem::take(&mut self.scratch.ainv);
        let mut ainv_r = std::mem::take(&mut self.scratch.ainv_r);
        ainv.resize(m * m, 0.0);
        ainv_r.resize(m, 0.0);
        let ok = spd_inverse(a, m, &mut self.scratch.l, &mut ainv[..m * m]);
        let d = if ok {
            for i in 0..m {
                ainv_r[i] = (0..m).map(|j| ainv[i + j * m] * r[j]).sum();
            }
            self.push(m, &ainv[..m * m], &ainv_r[..m])
        } else {
            Decision {
                statistic: f64::NAN,
                threshold: f64::NAN,
                alarm: self.alarm,
                dof: 0,
            }
        };
        self.scratch.ainv = ainv;
        self.scratch.ainv_r = ainv_r;
        d
    }

    /// Add one epoch's `A⁻¹` and `A⁻¹r` to the window (reusing the buffers of the epoch that
    /// leaves it) and decide.
    fn push(&mut self, m: usize, ainv: &[f64], ainv_r: &[f64]) -> Decision {
        if self.m != m || self.info.len() != m * m {
            self.m = m;
            self.info = vec![0.0; m * m];
            self.info_r = vec![0.0; m];
        }
        let (mut a_buf, mut r_buf) = if self.entries.len() >= self.window {
            match self.entries.pop_front() {
                Some((old, old_r)) => {
                    for (s, v) in self.info.iter_mut().zip(&old) {
                        *s -= v;
                    }
                    for (s, v) in self.info_r.iter_mut().zip(&old_r) {
                        *s -= v;
                    }
                    (old, old_r)
                }
                None => (Vec::new(), Vec::new()),
            }
        } else {
            (Vec::with_capacity(m * m), Vec::with_capacity(m))
        };
        a_buf.clear();
        a_buf.extend_from_slice(ainv);
        r_buf.clear();
        r_buf.extend_from_slice(ainv_r);
        for (s, v) in self.info.iter_mut().zip(&a_buf) {
            *s += v;
        }
        for (s, v) in self.info_r.iter_mut().zip(&r_buf) {
            *s += v;
        }
        self.entries.push_back((a_buf, r_buf));
        self.since_resum += 1;
        // A non-finite sum (an overflowing epoch entered, or left and inf − inf remained) is
        // recomputed from the stored window at once, so it lasts exactly as long as the
        // overflowing epoch stays in the window.
        if self.since_resum >= self.window
            || self.info.iter().chain(&self.info_r).any(|v| !v.is_finite())
        {
            self.resum();
        }
        self.decide()
    }

    /// Check a deserialised state (window, sizes) before use.
    pub fn check_consistent(&self) -> Result<()> {
        check_probability("pf", self.pf)?;
        let m = self.m;
        let ok = self.window >= 1
            && self.window <= MAX_WINDOW
            && self.entries.len() <= self.window
            && (self.entries.is_empty() || (self.info.len() == m * m && self.info_r.len() == m))
            && self
                .entries
                .iter()
                .all(|(a, r)| a.len() == m * m && r.len() == m);
        if ok {
            Ok(())
        } else {
            Err(Error::Invalid(
                "AIME state: window and stored sums are inconsistent".into(),
            ))
        }
    }

    /// Recompute the sums exactly from the stored window.
    fn resum(&mut self) {
        self.info.iter_mut().for_each(|v| *v = 0.0);
        self.info_r.iter_mut().for_each(|v| *v = 0.0);
        for (a, ar) in &self.entries {
            for (s, v) in self.info.iter_mut().zip(a) {
                *s += v;
            }
            for (s, v) in self.info_r.iter_mut().zip(ar) {
                *s += v;
            }
        }
        self.since_resum = 0;
    }

    fn decide(&mut self) -> Decision {
        let m = self.m;
        // Components with information in the window.
        let max_diag = (0..m).map(|i| self.info[i + i * m]).fold(0.0, f64::max);
        let mut keep = std::mem::take(&mut self.scratch.keep);
        keep.clear();
        keep.extend(
            (0..m)
                .filter(|&i| self.info[i + i * m] > 1e-12 * max_diag && self.info[i + i * m] > 0.0),
        );
        let k = keep.len();
        // The window's sums overflowed (a residual near the largest float, or a covariance so
        // small that its inverse summed over the window exceeds it): the largest possible
        // evidence of a fault, never a silent pass.
        let overflow = keep.iter().any(|&i| {
            !self.info_r[i].is_finite() || keep.iter().any(|&j| !self.info[i + j * m].is_finite())
        });
        let statistic = if overflow {
            f64::INFINITY
        } else {
            let s = self.statistic(&keep, 1.0);
            if s.is_finite() || k == 0 || max_diag <= 0.0 {
                s
            } else {
                // Intermediate products overflowed (e.g. A = 1e-160 I): the same statistic with
                // S scaled by 1/c and s by 1/√c, c = the largest diagonal of S.
                self.statistic(&keep, max_diag)
            }
        };
        self.scratch.keep = keep;
        self.decision(statistic, k)
    }

    /// `sᵀS⁻¹s` over the `keep` components with `S = Σ A⁻¹ / c` and `s = Σ A⁻¹r / √c` (the
    /// same value for any `c > 0`; `c = 1` leaves the arithmetic as it always was). NaN when
    /// S is not numerically positive definite.
    fn statistic(&mut self, keep: &[usize], c: f64) -> f64 {
        let m = self.m;
        let k = keep.len();
        let sq = c.sqrt();
        let sc = &mut self.scratch;
        if k == 2 && m == 2 {
            // Closed form of sᵀS⁻¹s for two components.
            let (s00, s10, s11) = (self.info[0] / c, self.info[1] / c, self.info[3] / c);
            let (v0, v1) = (self.info_r[0] / sq, self.info_r[1] / sq);
            let det = s00 * s11 - s10 * s10;
            return if s00 > 0.0 && det > 0.0 {
                (s11 * v0 * v0 - 2.0 * s10 * v0 * v1 + s00 * v1 * v1) / det
            } else {
                f64::NAN
            };
        }
        sc.l.clear();
        for q in 0..k {
            for p in 0..k {
                sc.l.push(self.info[keep[p] + keep[q] * m] / c);
            }
        }
        sc.v.clear();
        sc.v.extend(keep.iter().map(|&i| self.info_r[i] / sq));
        // r̄ᵀĀ⁻¹r̄ = sᵀS⁻¹s with S = Σ A⁻¹, s = Σ A⁻¹r.
        if k > 0 && cholesky_in_place(&mut sc.l, k) {
            whitened_norm2(&sc.l, k, &mut sc.v)
        } else {
            f64::NAN
        }
    }

    /// The decision for `statistic` on `k` components (sets the alarm state). A statistic
    /// that overflowed to +inf alarms; NaN (S numerically singular) is no test.
    fn decision(&mut self, statistic: f64, k: usize) -> Decision {
        let threshold = self.threshold(k).unwrap_or(f64::NAN);
        let tested = k > 0 && !statistic.is_nan();
        self.alarm = tested && statistic >= threshold;
        Decision {
            statistic,
            threshold,
            alarm: self.alarm,
            dof: if tested { k } else { 0 },
        }
    }

    /// The window's weighted mean innovation `r̄` (NaN for components without information).
    pub fn mean(&self) -> DVector<f64> {
        let m = self.m;
        let keep: Vec<usize> = (0..m).filter(|&i| self.info[i + i * m] > 0.0).collect();
        let mut out = DVector::from_element(m, f64::NAN);
        let k = keep.len();
        let s = DMatrix::from_fn(k, k, |p, q| self.info[keep[p] + keep[q] * m]);
        let v = DVector::from_fn(k, |p, _| self.info_r[keep[p]]);
        if let Some(c) = Cholesky::new(s) {
            let x = c.solve(&v);
            for (p, &i) in keep.iter().enumerate() {
                out[i] = x[p];
            }
        }
        out
    }
}

/// Two-stage AIME (paper 004, METHODS §11): stage 1 is [`Aime`] on the innovations (short
/// window); its statistic `s_k` is the measurement of a scalar random-walk Kalman filter
/// (`x_k = x_{k−1} + w`, `Var w = q`; the paper sets q = 10) whose measurement noise follows an
/// Allan-variance estimate with fading factor b: `R_k = b R_{k−1} + (1 − b)·½(s_k − s_{k−1})²`,
/// `R_0 = 1` (METHODS §11 resolution; the paper's formulas (23)–(24) are lost). Stage 2 is
/// [`Aime`] (longer window) on that filter's innovations `ν_k = s_k − x̂_{k−1}` with variance
/// `S_k = P_{k−1} + q + R_k` (paper eq. 26); only the stage-2 statistic is compared with the
/// threshold. A steadily growing stage-1 statistic (a slowly growing fault) gives innovations
/// of one sign, which stage 2 accumulates.
///
/// The first stage-1 statistic initialises the filter (`x̂ = s₁`, `P = q`); stage 2 starts at
/// the second. Under no fault the stage-2 statistic is not exactly χ²(1) (`s_k` is χ²(m)
/// correlated over the stage-1 window, and R adapts): its false-alarm rate is measured, not
/// guaranteed.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct TwoStageAime {
    stage1: Aime,
    stage2: Aime,
    q: f64,
    b: f64,
    x: f64,
    p: f64,
    r: f64,
    prev: Option<f64>,
    #[serde(with = "super::nan_f64")]
    last_stage1: f64,
    /// The statistic filter and stage 2 take every `every`-th stage-1 statistic (1: each).
    #[serde(default = "one")]
    every: usize,
    /// Stage-1 statistics since the last one taken.
    #[serde(default)]
    count: usize,
    /// The last stage-2 decision (repeated between the statistics taken).
    #[serde(default)]
    last: Option<Decision>,
    /// Starting R (1 unless [`TwoStageAime::with_decimation`] sets it).
    #[serde(default = "one_f")]
    r0: f64,
}

fn one_f() -> f64 {
    1.0
}

fn one() -> usize {
    1
}

impl TwoStageAime {
    /// `pf` of the stage-2 test, windows of the two stages (epochs), process noise `q` > 0
    /// and fading factor `b` in (0, 1).
    pub fn new(pf: f64, window1: usize, window2: usize, q: f64, b: f64) -> Result<Self> {
        if !(q > 0.0 && q.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "q".into(),
                value: q,
                requirement: "the random-walk variance must be positive and finite".into(),
            });
        }
        if !(b > 0.0 && b < 1.0) {
            return Err(Error::InvalidParameter {
                name: "b".into(),
                value: b,
                requirement: "the fading factor must be in (0, 1) (the paper uses 0.9–0.999)"
                    .into(),
            });
        }
        Ok(TwoStageAime {
            stage1: Aime::new(pf, window1)?,
            stage2: Aime::new(pf, window2)?,
            q,
            b,
            x: 0.0,
            p: q,
            r: 1.0,
            prev: None,
            last_stage1: f64::NAN,
            every: 1,
            count: 0,
            last: None,
            r0: 1.0,
        })
    }

    /// Feed the statistic filter and stage 2 with every `every`-th stage-1 statistic only
    /// (`every` = the stage-1 window makes the samples non-overlapping, hence independent
    /// under no fault, which is what the Allan-variance estimate of R assumes); stage-2's
    /// window then counts those samples. Between them [`TwoStageAime::test`] repeats the last
    /// decision.
    ///
    /// `r0` (> 0) is the starting R of the Allan-variance estimate (METHODS §11: 1).
    pub fn with_decimation(mut self, every: usize, r0: f64) -> Result<Self> {
        if !(r0 > 0.0 && r0.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "r0".into(),
                value: r0,
                requirement: "the starting measurement noise must be positive and finite".into(),
            });
        }
        self.r0 = r0;
        self.r = r0;
        if every == 0 || every > MAX_WINDOW {
            return Err(Error::InvalidParameter {
                name: "every".into(),
                value: every as f64,
                requirement: format!("take every 1 … {MAX_WINDOW}-th stage-1 statistic"),
            });
        }
        self.every = every;
        self.count = 0;
        Ok(self)
    }

    /// False-alarm probability of the stage-2 test.
    pub fn pf(&self) -> f64 {
        self.stage2.pf()
    }

    /// Windows (stage 1, stage 2) in epochs.
    pub fn windows(&self) -> (usize, usize) {
        (self.stage1.window(), self.stage2.window())
    }

    /// The last stage-1 statistic (NaN before the first epoch).
    pub fn last_stage1(&self) -> f64 {
        self.last_stage1
    }

    /// The adapted measurement noise R of the statistic filter.
    pub fn measurement_noise(&self) -> f64 {
        self.r
    }

    /// Last alarm state.
    pub fn alarm(&self) -> bool {
        self.stage2.alarm()
    }

    /// Stage-2 threshold (χ²(1)).
    pub fn threshold(&mut self) -> Result<f64> {
        self.stage2.threshold(1)
    }

    /// Start over.
    pub fn reset(&mut self) {
        self.stage1.reset();
        self.stage2.reset();
        self.x = 0.0;
        self.p = self.q;
        self.r = self.r0;
        self.prev = None;
        self.last_stage1 = f64::NAN;
        self.count = 0;
        self.last = None;
    }

    /// Check a deserialised state.
    pub fn check_consistent(&self) -> Result<()> {
        self.stage1.check_consistent()?;
        self.stage2.check_consistent()?;
        if !(self.q > 0.0
            && self.b > 0.0
            && self.b < 1.0
            && self.p >= 0.0
            && self.r >= 0.0
            && self.every >= 1
            && self.every <= MAX_WINDOW)
        {
            return Err(Error::Invalid(
                "two-stage AIME state: q, b, P or R out of range".into(),
            ));
        }
        Ok(())
    }

    /// Test one epoch (validated like [`Aime::test`]; a rejected epoch changes nothing).
    pub fn test(&mut self, r: &DVector<f64>, a: &DMatrix<f64>) -> Result<Decision> {
        let d1 = self.stage1.test(r, a)?;
        self.after_stage1(d1.statistic)
    }

    /// Decimation, statistic filter and stage 2 after a stage-1 statistic `s`.
    fn after_stage1(&mut self, s: f64) -> Result<Decision> {
        let threshold = self.stage2.threshold(1)?;
        if s == f64::INFINITY {
            // Stage 1 overflowed: the largest possible evidence of a fault. The statistic
            // filter is left as it was (an infinite sample would poison its R for good).
            let d = Decision {
                statistic: f64::INFINITY,
                threshold,
                alarm: true,
                dof: 1,
            };
            self.last = Some(d.clone());
            return Ok(d);
        }
        if !s.is_finite() {
            return Ok(Decision {
                statistic: f64::NAN,
                threshold,
                alarm: self.stage2.alarm(),
                dof: 0,
            });
        }
        self.last_stage1 = s;
        self.count += 1;
        if self.count < self.every {
            return Ok(self.last.clone().unwrap_or(Decision {
                statistic: f64::NAN,
                threshold,
                alarm: false,
                dof: 0,
            }));
        }
        self.count = 0;
        let d = self.filter_and_test(s, threshold)?;
        self.last = Some(d.clone());
        Ok(d)
    }

    /// [`TwoStageAime::test`] on validated inputs ([`Aime::test_trusted`]'s contract).
    pub fn test_trusted(&mut self, r: &[f64], a: &[f64]) -> Result<Decision> {
        let d1 = self.stage1.test_trusted(r, a);
        self.after_stage1(d1.statistic)
    }

    /// The statistic filter and stage 2 on one taken stage-1 statistic `s`.
    fn filter_and_test(&mut self, s: f64, threshold: f64) -> Result<Decision> {
        let Some(prev) = self.prev.replace(s) else {
            self.x = s;
            self.p = self.q;
            return Ok(Decision {
                statistic: f64::NAN,
                threshold,
                alarm: false,
                dof: 0,
            });
        };
        let r = self.b * self.r + (1.0 - self.b) * 0.5 * (s - prev) * (s - prev);
        let p_pred = self.p + self.q;
        let nu = s - self.x;
        let var = p_pred + r;
        if !(var.is_finite() && nu.is_finite()) {
            // A stage-1 statistic so large that its squared jump overflows: alarm, and keep
            // the filter's R, x and P as they were.
            return Ok(Decision {
                statistic: f64::INFINITY,
                threshold,
                alarm: true,
                dof: 1,
            });
        }
        self.r = r;
        let d2 = self.stage2.test(
            &DVector::from_element(1, nu),
            &DMatrix::from_element(1, 1, var),
        )?;
        let k = p_pred / var;
        self.x += k * nu;
        self.p = (1.0 - k) * p_pred;
        Ok(d2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    fn reference(rs: &[DVector<f64>], as_: &[DMatrix<f64>]) -> f64 {
        let m = rs[0].len();
        let mut s = DMatrix::zeros(m, m);
        let mut v = DVector::zeros(m);
        for (r, a) in rs.iter().zip(as_) {
            let inv = a.clone().try_inverse().unwrap();
            v += &inv * r;
            s += inv;
        }
        let rbar = s.clone().try_inverse().unwrap() * &v;
        (rbar.transpose() * s * rbar)[(0, 0)]
    }

    #[test]
    fn matches_the_definition_and_does_not_drift() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = 7;
        let mut d = Aime::new(0.01, n).unwrap();
        let mut rs = Vec::new();
        let mut as_ = Vec::new();
        for k in 0..1_000_000usize {
            let r = DVector::from_fn(2, |_, _| {
                Distribution::<f64>::sample(&StandardNormal, &mut rng)
            });
            let l = DMatrix::from_fn(2, 2, |i, j| {
                if i >= j {
                    0.5 + 0.1 * Distribution::<f64>::sample(&StandardNormal, &mut rng)
                } else {
                    0.0
                }
            });
            let a = &l * l.transpose() + DMatrix::identity(2, 2) * 0.1;
            let dec = d.test(&r, &a).unwrap();
            rs.push(r);
            as_.push(a);
            if rs.len() > n {
                rs.remove(0);
                as_.remove(0);
            }
            if k % 99_991 == 0 || k > 999_990 {
                let want = reference(&rs, &as_);
                assert!(
                    (dec.statistic - want).abs() <= 1e-9 * want.max(1.0),
                    "{k}: {} vs {want}",
                    dec.statistic
                );
            }
        }
    }

    #[test]
    fn two_stage_follows_its_definition() {
        let mut t = TwoStageAime::new(0.01, 2, 3, 10.0, 0.9).unwrap();
        let one = DMatrix::from_element(1, 1, 1.0);
        let rs = [0.5, -1.0, 2.0, 0.3, 3.0];
        let mut s1 = Aime::new(0.01, 2).unwrap();
        let mut s2 = Aime::new(0.01, 3).unwrap();
        let (mut x, mut p, mut r, mut prev) = (0.0, 10.0, 1.0, f64::NAN);
        for (k, &v) in rs.iter().enumerate() {
            let vec = DVector::from_element(1, v);
            let d = t.test(&vec, &one).unwrap();
            let s = s1.test(&vec, &one).unwrap().statistic;
            if k == 0 {
                x = s;
                assert!(d.statistic.is_nan());
            } else {
                r = 0.9 * r + 0.1 * 0.5 * (s - prev).powi(2);
                let pp = p + 10.0;
                let nu = s - x;
                let want = s2
                    .test(
                        &DVector::from_element(1, nu),
                        &DMatrix::from_element(1, 1, pp + r),
                    )
                    .unwrap();
                assert!((d.statistic - want.statistic).abs() < 1e-12);
                let g = pp / (pp + r);
                x += g * nu;
                p = (1.0 - g) * pp;
            }
            prev = s;
        }
        assert!(TwoStageAime::new(0.01, 2, 3, 0.0, 0.9).is_err());
        assert!(TwoStageAime::new(0.01, 2, 3, 10.0, 1.0).is_err());
    }

    #[test]
    fn missing_components_and_bad_input() {
        let mut d = Aime::new(0.01, 3).unwrap();
        let a = DMatrix::identity(2, 2);
        let dec = d.test(&DVector::from_vec(vec![1.0, f64::NAN]), &a).unwrap();
        assert_eq!(dec.dof, 1);
        assert!((dec.statistic - 1.0).abs() < 1e-12);
        let dec = d.test(&DVector::from_vec(vec![1.0, 2.0]), &a).unwrap();
        assert_eq!(dec.dof, 2);
        // (1+1)²/2 + 2²/1 = 2 + 4
        assert!((dec.statistic - 6.0).abs() < 1e-12);
        assert!(d
            .test(&DVector::from_vec(vec![1.0]), &DMatrix::identity(1, 1))
            .is_err());
        assert_eq!(d.len(), 2);
        assert!(Aime::new(0.01, 0).is_err());
        assert!(Aime::new(1.5, 3).is_err());
    }

    #[test]
    fn decimated_two_stage_takes_every_nth_statistic() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let a = DMatrix::identity(2, 2);
        let every = 5;
        let mut d = TwoStageAime::new(1e-3, every, 4, 1e-3, 0.99)
            .unwrap()
            .with_decimation(every, 4.0)
            .unwrap();
        assert_eq!(d.measurement_noise(), 4.0);
        let mut last = None;
        for i in 0..200 {
            let r = DVector::from_fn(2, |_, _| StandardNormal.sample(&mut rng));
            let dec = d.test(&r, &a).unwrap();
            if (i + 1) % every != 0 {
                // Between taken statistics the last decision is repeated.
                if let Some(l) = &last {
                    let l: &Decision = l;
                    assert_eq!(dec.statistic.to_bits(), l.statistic.to_bits());
                    assert_eq!((dec.alarm, dec.dof), (l.alarm, l.dof));
                }
            } else {
                last = Some(dec);
            }
        }
        // The Allan estimate of R moves towards the variance of χ²(2) samples (4).
        assert!(d.measurement_noise() > 1.0 && d.measurement_noise() < 12.0);
        assert!(TwoStageAime::new(1e-3, 5, 4, 1e-3, 0.99)
            .unwrap()
            .with_decimation(0, 4.0)
            .is_err());
        assert!(TwoStageAime::new(1e-3, 5, 4, 1e-3, 0.99)
            .unwrap()
            .with_decimation(5, f64::NAN)
            .is_err());
    }
}
