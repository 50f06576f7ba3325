//! A whole filter run over a measurement sequence in one call (the loop stays in Rust).
//!
//! Convention: `x0, P0` describe the state before the first epoch; at each epoch `k` the filter
//! predicts with `Φ_k, Q_k` and then updates with `z_k, H_k, R_k`. Outputs are the posterior
//! estimates after each epoch's update.

use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::kalman::{check_fading, KalmanFilter};
use crate::validate::{check_covariance, check_finite_matrix, check_shape};
use nalgebra::{DMatrix, DVector};

/// A matrix that is either constant over the run or given per epoch.
#[derive(Debug, Clone)]
pub enum MatrixSeq {
    /// The same matrix at every epoch.
    Const(DMatrix<f64>),
    /// One matrix per epoch.
    PerEpoch(Vec<DMatrix<f64>>),
}

impl MatrixSeq {
    /// The matrix for epoch `k`.
    pub fn at(&self, k: usize) -> &DMatrix<f64> {
        match self {
            MatrixSeq::Const(m) => m,
            MatrixSeq::PerEpoch(v) => &v[k],
        }
    }

    fn validate(
        &self,
        name: &str,
        t: usize,
        rows: usize,
        cols: usize,
        covariance: bool,
    ) -> Result<()> {
        let check = |label: &str, m: &DMatrix<f64>| -> Result<()> {
            check_shape(label, m, rows, cols)?;
            if covariance {
                check_covariance(label, m)
            } else {
                check_finite_matrix(label, m)
            }
        };
        match self {
            MatrixSeq::Const(m) => check(name, m),
            MatrixSeq::PerEpoch(v) => {
                if v.len() != t {
                    return Err(Error::Invalid(format!(
                        "{name}: a stack of {} matrices was given for {t} epochs; give one matrix or exactly one per epoch",
                        v.len()
                    )));
                }
                for (k, m) in v.iter().enumerate() {
                    check(&format!("{name}[{k}]"), m)?;
                }
                Ok(())
            }
        }
    }
}

/// Per-epoch outputs of [`run_filter`], flattened row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutput {
    /// Epochs T.
    pub epochs: usize,
    /// State dimension n.
    pub n: usize,
    /// Measurement dimension m.
    pub m: usize,
    /// Posterior states, T × n.
    pub x: Vec<f64>,
    /// Posterior covariances, T × n × n.
    pub p: Vec<f64>,
    /// Residuals, T × m (NaN for unused components).
    pub residual: Vec<f64>,
    /// Residual covariances, T × m × m (NaN rows/columns for unused components).
    pub covariance: Vec<f64>,
    /// `λ = rᵀA⁻¹r`, T (NaN where no component was used).
    pub statistic: Vec<f64>,
    /// Used-component mask, T × m.
    pub used: Vec<bool>,
}

/// Prefix an error with the epoch at which it happened.
pub fn at_epoch(k: usize, e: Error) -> Error {
    match e {
        Error::NotPositiveDefinite { name, detail } => Error::NotPositiveDefinite {
            name: format!("epoch {k}: {name}"),
            detail,
        },
        Error::Numerical { context, detail } => Error::Numerical {
            context: format!("epoch {k}: {context}"),
            detail,
        },
        Error::Cancelled => Error::Cancelled,
        Error::TooLarge(m) => Error::TooLarge(m),
        other => Error::Invalid(format!("epoch {k}: {other}")),
    }
}

/// [`at_epoch`] for a run on recorded logs: the error names the run time `t` (s from the
/// first GNSS epoch) beside the epoch index, so the record can be found in the log.
pub fn at_time(k: usize, t: f64, e: Error) -> Error {
    match e {
        Error::NotPositiveDefinite { name, detail } => Error::NotPositiveDefinite {
            name: format!("t = {t} s (epoch {k}): {name}"),
            detail: format!(
                "{detail}; a measurement or its σ there is far outside what the filter can hold (check the log at that time)"
            ),
        },
        Error::Numerical { context, detail } => Error::Numerical {
            context: format!("t = {t} s (epoch {k}): {context}"),
            detail,
        },
        Error::Cancelled => Error::Cancelled,
        Error::TooLarge(m) => Error::TooLarge(m),
        other => Error::Invalid(format!("t = {t} s (epoch {k}): {other}")),
    }
}

/// Run predict + update over `epochs` epochs.
///
/// * `x0` (n), `p0` (n × n): prior before epoch 0.
/// * `phi`, `q` (n × n), `h` (m × n), `r` (m × m): constant or per epoch.
/// * `zs`: measurements, row-major `epochs × m`; NaN marks a missing component.
/// * `fading`: factor `S ≥ 1` applied at every prediction.
///
/// All inputs are validated, and the memory of the outputs checked against what is available,
/// before the first epoch. A numerical failure at epoch k is reported with `k` in the message;
/// `cancel` is checked every epoch ([`Error::Cancelled`]).
#[allow(clippy::too_many_arguments)]
pub fn run_filter(
    x0: DVector<f64>,
    p0: DMatrix<f64>,
    phi: &MatrixSeq,
    q: &MatrixSeq,
    zs: &[f64],
    epochs: usize,
    h: &MatrixSeq,
    r: &MatrixSeq,
    fading: f64,
    cancel: &Cancel,
) -> Result<RunOutput> {
    let mut kf = KalmanFilter::new(x0, p0)?;
    let n = kf.dim();
    if epochs == 0 || !zs.len().is_multiple_of(epochs) {
        return Err(Error::Invalid(format!(
            "zs: {} values cannot form {epochs} epochs of equal length (need at least one epoch)",
            zs.len()
        )));
    }
    let m = zs.len() / epochs;
    if m == 0 {
        return Err(Error::Shape {
            name: "zs".into(),
            expected: "(T, m) with m >= 1".into(),
            got: format!("({epochs}, 0)"),
        });
    }
    check_fading(fading)?;
    phi.validate("Phi", epochs, n, n, false)?;
    q.validate("Q", epochs, n, n, true)?;
    h.validate("H", epochs, m, n, false)?;
    r.validate("R", epochs, m, m, true)?;
    if let Some((i, v)) = zs.iter().enumerate().find(|(_, v)| v.is_infinite()) {
        return Err(Error::NonFinite {
            name: "zs".into(),
            index: format!("[{}, {}]", i / m, i % m),
            value: *v,
        });
    }

    let per_epoch = (n + n * n + m + m * m + 1) as f64 * 8.0 + m as f64;
    crate::memory::check(
        "run_filter",
        per_epoch * epochs as f64,
        &format!("{epochs} epochs with n = {n} states and m = {m} measurements (the outputs hold P, shape (T, n, n), and A, shape (T, m, m))"),
        "run fewer epochs per call (split zs) or reduce the state dimension",
    )?;
    let mut out = RunOutput {
        epochs,
        n,
        m,
        x: Vec::with_capacity(epochs * n),
        p: Vec::with_capacity(epochs * n * n),
        residual: Vec::with_capacity(epochs * m),
        covariance: Vec::with_capacity(epochs * m * m),
        statistic: Vec::with_capacity(epochs),
        used: Vec::with_capacity(epochs * m),
    };
    for k in 0..epochs {
        cancel.check()?;
        kf.predict_trusted(phi.at(k), q.at(k), fading)
            .map_err(|e| at_epoch(k, e))?;
        let z = DVector::from_column_slice(&zs[k * m..(k + 1) * m]);
        let inn = kf
            .update_trusted(&z, h.at(k), r.at(k))
            .map_err(|e| at_epoch(k, e))?;
        out.x.extend_from_slice(kf.x().as_slice());
        // P and A are symmetric, so column-major storage equals row-major.
        out.p.extend_from_slice(kf.p().as_slice());
        out.residual.extend_from_slice(inn.residual.as_slice());
        out.covariance.extend_from_slice(inn.covariance.as_slice());
        out.statistic.push(inn.statistic);
        out.used.extend_from_slice(&inn.used);
    }
    Ok(out)
}
