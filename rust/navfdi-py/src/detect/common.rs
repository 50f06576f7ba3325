//! What every detector binding shares: the per-epoch `Decision`, the whole-sequence
//! `DetectionRun`, reading residual sequences, and argument checks.

use crate::convert::{matrix, read, to_numpy, vector};
use crate::errors::IntoPyResult;
use nalgebra::{DMatrix, DVector};
use navfdi_core::detect::{Decision, SprtVariance};
use navfdi_core::run::at_epoch;
use numpy::{IxDyn, PyArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// What any detector reports for one epoch.
#[derive(Clone)]
pub(crate) struct Report {
    pub(crate) decision: Decision,
    pub(crate) components: Option<Vec<f64>>,
    pub(crate) chi2: Option<Decision>,
    pub(crate) reset: bool,
}

/// One epoch's decision of a detector.
#[pyclass(name = "Decision", module = "navfdi._core", frozen)]
pub struct PyDecision {
    report: Report,
}

impl PyDecision {
    /// A plain decision (no SPRT components, no chi-square part).
    pub fn from_decision(d: Decision) -> Self {
        PyDecision {
            report: Report {
                decision: d,
                components: None,
                chi2: None,
                reset: false,
            },
        }
    }
}

#[pymethods]
impl PyDecision {
    /// Test statistic (NaN when no residual component was available).
    #[getter]
    fn statistic(&self) -> f64 {
        self.report.decision.statistic
    }
    /// Threshold compared with the statistic.
    #[getter]
    fn threshold(&self) -> f64 {
        self.report.decision.threshold
    }
    /// Fault declared this epoch.
    #[getter]
    fn alarm(&self) -> bool {
        self.report.decision.alarm
    }
    /// Number of residual components used.
    #[getter]
    fn dof(&self) -> usize {
        self.report.decision.dof
    }
    /// statistic / threshold; ≥ 1 means alarm.
    #[getter]
    fn ratio(&self) -> f64 {
        self.report.decision.ratio()
    }
    /// SPRT per-component statistics λ_j, shape (m,); None for the chi-square test.
    #[getter]
    fn components<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, PyArray<f64, IxDyn>>>> {
        match &self.report.components {
            Some(c) => Ok(Some(to_numpy(py, c.clone(), &[c.len()])?)),
            None => Ok(None),
        }
    }
    /// The joint detector's chi-square decision; None for the other detectors.
    #[getter]
    fn chi2(&self) -> Option<PyDecision> {
        self.report.chi2.clone().map(|d| PyDecision {
            report: Report {
                decision: d,
                components: None,
                chi2: None,
                reset: false,
            },
        })
    }
    /// True when the joint detector's chi-square end-of-fault reset the SPRT this epoch.
    #[getter]
    fn reset(&self) -> bool {
        self.report.reset
    }
    fn __repr__(&self) -> String {
        let d = &self.report.decision;
        format!(
            "Decision(alarm={}, statistic={}, threshold={}, ratio={}, dof={})",
            crate::convert::py_bool(d.alarm),
            crate::convert::py_float(d.statistic),
            crate::convert::py_float(d.threshold),
            crate::convert::py_float(d.ratio()),
            d.dof
        )
    }
}

/// Per-epoch decisions of a whole sequence.
#[pyclass(name = "DetectionRun", module = "navfdi._core", frozen)]
pub struct PyDetectionRun {
    reports: Vec<Report>,
    m: usize,
}

impl PyDetectionRun {
    fn col<T: numpy::Element, F: Fn(&Report) -> T>(&self, f: F) -> Vec<T> {
        self.reports.iter().map(f).collect()
    }
}

#[pymethods]
impl PyDetectionRun {
    /// Statistic per epoch, shape (T,).
    #[getter]
    fn statistic<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        to_numpy(
            py,
            self.col(|r| r.decision.statistic),
            &[self.reports.len()],
        )
    }
    /// Threshold per epoch, shape (T,).
    #[getter]
    fn threshold<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        to_numpy(
            py,
            self.col(|r| r.decision.threshold),
            &[self.reports.len()],
        )
    }
    /// Alarm per epoch, shape (T,).
    #[getter]
    fn alarm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<bool, IxDyn>>> {
        to_numpy(py, self.col(|r| r.decision.alarm), &[self.reports.len()])
    }
    /// Components used per epoch, shape (T,).
    #[getter]
    fn dof<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<i64, IxDyn>>> {
        to_numpy(
            py,
            self.col(|r| r.decision.dof as i64),
            &[self.reports.len()],
        )
    }
    /// SPRT per-component statistics, shape (T, m); None for the chi-square test.
    #[getter]
    fn components<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, PyArray<f64, IxDyn>>>> {
        if self.reports.first().is_none_or(|r| r.components.is_none()) {
            return Ok(None);
        }
        let mut data = Vec::with_capacity(self.reports.len() * self.m);
        for r in &self.reports {
            match &r.components {
                Some(c) if c.len() == self.m => data.extend_from_slice(c),
                _ => data.extend(std::iter::repeat_n(f64::NAN, self.m)),
            }
        }
        Ok(Some(to_numpy(py, data, &[self.reports.len(), self.m])?))
    }
    /// Joint detector: chi-square statistic per epoch, shape (T,); None otherwise.
    #[getter]
    fn chi2_statistic<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, PyArray<f64, IxDyn>>>> {
        self.chi2_col(py, |d| d.statistic)
    }
    /// Joint detector: chi-square threshold per epoch, shape (T,); None otherwise.
    #[getter]
    fn chi2_threshold<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, PyArray<f64, IxDyn>>>> {
        self.chi2_col(py, |d| d.threshold)
    }
    /// Joint detector: chi-square alarm per epoch, shape (T,); None otherwise.
    #[getter]
    fn chi2_alarm<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, PyArray<bool, IxDyn>>>> {
        self.chi2_col(py, |d| d.alarm)
    }
    /// Joint detector: epochs at which the SPRT was reset, shape (T,); None otherwise.
    #[getter]
    fn reset<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray<bool, IxDyn>>>> {
        if self.reports.first().is_none_or(|r| r.chi2.is_none()) {
            return Ok(None);
        }
        Ok(Some(to_numpy(
            py,
            self.col(|r| r.reset),
            &[self.reports.len()],
        )?))
    }
    fn __len__(&self) -> usize {
        self.reports.len()
    }
}

impl PyDetectionRun {
    fn chi2_col<'py, T: numpy::Element, F: Fn(&Decision) -> T>(
        &self,
        py: Python<'py>,
        f: F,
    ) -> PyResult<Option<Bound<'py, PyArray<T, IxDyn>>>> {
        if self.reports.first().is_none_or(|r| r.chi2.is_none()) {
            return Ok(None);
        }
        let v: Vec<T> = self
            .reports
            .iter()
            .filter_map(|r| r.chi2.as_ref().map(&f))
            .collect();
        Ok(Some(to_numpy(py, v, &[self.reports.len()])?))
    }
}

/// Residuals and covariances, one per epoch.
pub(crate) type Sequence = (Vec<DVector<f64>>, Vec<DMatrix<f64>>);

/// Read residuals (T, m) and covariances (T, m, m).
pub(crate) fn read_sequence(
    residuals: &Bound<'_, PyAny>,
    covariances: &Bound<'_, PyAny>,
) -> PyResult<Sequence> {
    let r = read("residuals", residuals)?;
    let a = read("covariances", covariances)?;
    if r.shape.len() != 2 {
        return Err(PyValueError::new_err(format!(
            "residuals: expected a 2-D array (T, m), got {} dimension(s)",
            r.shape.len()
        )));
    }
    let (t, m) = (r.shape[0], r.shape[1]);
    if a.shape != [t, m, m] {
        return Err(PyValueError::new_err(format!(
            "covariances: expected shape ({t}, {m}, {m}) to match residuals, got {:?}",
            a.shape
        )));
    }
    let rs = (0..t)
        .map(|k| DVector::from_row_slice(&r.data[k * m..(k + 1) * m]))
        .collect();
    let as_ = (0..t)
        .map(|k| DMatrix::from_row_slice(m, m, &a.data[k * m * m..(k + 1) * m * m]))
        .collect();
    Ok((rs, as_))
}

/// Run `step` over the sequence on a copy of the detector; commit the copy only on success.
pub(crate) fn run_sequence<D: Clone + Send, F>(
    py: Python<'_>,
    det: &mut D,
    residuals: &Bound<'_, PyAny>,
    covariances: &Bound<'_, PyAny>,
    step: F,
) -> PyResult<PyDetectionRun>
where
    F: Fn(&mut D, &DVector<f64>, &DMatrix<f64>) -> navfdi_core::Result<Report> + Send + Sync,
{
    let (rs, as_) = read_sequence(residuals, covariances)?;
    let m = rs.first().map_or(0, |r| r.len());
    let mut work = det.clone();
    let work_ref = &mut work;
    let reports = crate::interrupt::run(py, move |cancel| {
        rs.iter()
            .zip(&as_)
            .enumerate()
            .map(|(k, (r, a))| {
                cancel.check()?;
                step(work_ref, r, a).map_err(|e| at_epoch(k, e))
            })
            .collect::<navfdi_core::Result<Vec<Report>>>()
    })?;
    *det = work;
    Ok(PyDetectionRun { reports, m })
}

pub(crate) fn read_pair(
    residual: &Bound<'_, PyAny>,
    covariance: &Bound<'_, PyAny>,
) -> PyResult<(DVector<f64>, DMatrix<f64>)> {
    Ok((
        vector("residual", residual, None)?,
        matrix("covariance", covariance)?,
    ))
}

/// Test one epoch. The core detectors validate before changing any state, so a rejected call
/// leaves the detector as it was without a copy here.
pub(crate) fn test_one<D>(
    det: &mut D,
    residual: &Bound<'_, PyAny>,
    covariance: &Bound<'_, PyAny>,
    step: fn(&mut D, &DVector<f64>, &DMatrix<f64>) -> navfdi_core::Result<Report>,
) -> PyResult<PyDecision> {
    let (r, a) = read_pair(residual, covariance)?;
    Ok(PyDecision {
        report: step(det, &r, &a).py()?,
    })
}

pub(crate) fn parse_variance(v: &str) -> PyResult<SprtVariance> {
    match v {
        "known" => Ok(SprtVariance::Known),
        "sample" => Ok(SprtVariance::Sample),
        other => Err(PyValueError::new_err(format!(
            "variance = {other:?}: must be \"known\" (normalise by sqrt(A_jj)) or \"sample\" (running sample variance)"
        ))),
    }
}

pub(crate) fn variance_name(v: SprtVariance) -> &'static str {
    match v {
        SprtVariance::Known => "known",
        SprtVariance::Sample => "sample",
    }
}

/// Apply an optional `min_samples` (validated) with the detector's own setter.
pub(crate) fn with_min_samples<D>(
    d: D,
    min_samples: Option<i64>,
    set: fn(D, u64) -> navfdi_core::Result<D>,
) -> PyResult<D> {
    match min_samples {
        None => Ok(d),
        Some(n) => set(d, positive_count("min_samples", n)?).py(),
    }
}

/// Validate a Python integer as a count of at least 1 named `name`.
pub fn positive_count(name: &str, n: i64) -> PyResult<u64> {
    u64::try_from(n)
        .ok()
        .filter(|v| *v >= 1)
        .ok_or_else(|| PyValueError::new_err(format!("{name} = {n}: must be at least 1")))
}

/// Validate a Python integer as degrees of freedom.
pub fn positive_dof(dof: i64) -> PyResult<usize> {
    if dof < 1 {
        return Err(PyValueError::new_err(format!(
            "dof = {dof}: degrees of freedom must be at least 1"
        )));
    }
    usize::try_from(dof).map_err(|_| PyValueError::new_err(format!("dof = {dof}: too large")))
}
