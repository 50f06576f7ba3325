//! Detector bindings: `ResidualChi2`, `ImprovedSprt`, `JointChi2Sprt`, their per-epoch
//! `Decision` and the whole-sequence `DetectionRun`.

use crate::convert::{matrix, read, to_numpy, vector};
use crate::errors::IntoPyResult;
use nalgebra::{DMatrix, DVector};
use navfdi_core::detect::{
    Aime, Decision, ImprovedSprt, JointChi2Sprt, ResidualChi2, SprtVariance, TwoStageAime,
};
use navfdi_core::run::at_epoch;
use numpy::{IxDyn, PyArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// What any detector reports for one epoch.
#[derive(Clone)]
struct Report {
    decision: Decision,
    components: Option<Vec<f64>>,
    chi2: Option<Decision>,
    reset: bool,
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
            "Decision(alarm={}, statistic={:.6}, threshold={:.6}, ratio={:.4}, dof={})",
            if d.alarm { "True" } else { "False" },
            d.statistic,
            d.threshold,
            d.ratio(),
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
type Sequence = (Vec<DVector<f64>>, Vec<DMatrix<f64>>);

/// Read residuals (T, m) and covariances (T, m, m).
fn read_sequence(
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
fn run_sequence<D: Clone + Send, F>(
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

fn read_pair(
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
fn test_one<D>(
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

fn parse_variance(v: &str) -> PyResult<SprtVariance> {
    match v {
        "known" => Ok(SprtVariance::Known),
        "sample" => Ok(SprtVariance::Sample),
        other => Err(PyValueError::new_err(format!(
            "variance = {other:?}: must be \"known\" (normalise by sqrt(A_jj)) or \"sample\" (running sample variance)"
        ))),
    }
}

fn variance_name(v: SprtVariance) -> &'static str {
    match v {
        SprtVariance::Known => "known",
        SprtVariance::Sample => "sample",
    }
}

fn chi2_step(
    d: &mut ResidualChi2,
    r: &DVector<f64>,
    a: &DMatrix<f64>,
) -> navfdi_core::Result<Report> {
    Ok(Report {
        decision: d.test(r, a)?,
        components: None,
        chi2: None,
        reset: false,
    })
}

fn sprt_step(
    d: &mut ImprovedSprt,
    r: &DVector<f64>,
    a: &DMatrix<f64>,
) -> navfdi_core::Result<Report> {
    let decision = d.test(r, a)?;
    Ok(Report {
        decision,
        components: Some(d.component_statistics()),
        chi2: None,
        reset: false,
    })
}

fn joint_step(
    d: &mut JointChi2Sprt,
    r: &DVector<f64>,
    a: &DMatrix<f64>,
) -> navfdi_core::Result<Report> {
    let j = d.test(r, a)?;
    Ok(Report {
        decision: j.decision,
        components: Some(d.sprt().component_statistics()),
        chi2: Some(j.chi2),
        reset: j.reset,
    })
}

fn aime_step(d: &mut Aime, r: &DVector<f64>, a: &DMatrix<f64>) -> navfdi_core::Result<Report> {
    Ok(Report {
        decision: d.test(r, a)?,
        components: None,
        chi2: None,
        reset: false,
    })
}

/// AIME detector (paper 004): chi-square test of the information-weighted mean innovation
/// over a sliding window.
#[pyclass(name = "Aime", module = "navfdi._core")]
pub struct PyAime {
    inner: Aime,
}

impl PyAime {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: Aime) -> Self {
        PyAime { inner }
    }
}

#[pymethods]
impl PyAime {
    #[new]
    #[pyo3(signature = (pf, window))]
    fn new(pf: f64, window: i64) -> PyResult<Self> {
        if window < 1 {
            return Err(PyValueError::new_err(format!(
                "window = {window}: the AIME window must be at least 1 epoch"
            )));
        }
        Ok(PyAime {
            inner: Aime::new(pf, window as usize).py()?,
        })
    }
    /// Test one epoch.
    fn test(
        &mut self,
        residual: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
    ) -> PyResult<PyDecision> {
        test_one(&mut self.inner, residual, covariance, aime_step)
    }
    /// Test a whole sequence in Rust.
    fn test_sequence(
        &mut self,
        py: Python<'_>,
        residuals: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
    ) -> PyResult<PyDetectionRun> {
        run_sequence(py, &mut self.inner, residuals, covariances, aime_step)
    }
    /// Empty the window.
    fn reset(&mut self) {
        self.inner.reset()
    }
    /// Threshold for `dof` components.
    #[pyo3(signature = (dof = None))]
    fn threshold(&mut self, dof: Option<i64>) -> PyResult<f64> {
        let dof = dof.ok_or_else(|| {
            PyValueError::new_err(
                "dof: the AIME threshold depends on the number of residual components; give dof",
            )
        })?;
        let dof = positive_dof(dof)?;
        self.inner.threshold(dof).py()
    }
    /// False-alarm probability per epoch.
    #[getter]
    fn pf(&self) -> f64 {
        self.inner.pf()
    }
    /// Window length N (epochs).
    #[getter]
    fn window(&self) -> usize {
        self.inner.window()
    }
    /// Epochs currently in the window.
    #[getter]
    fn filled(&self) -> usize {
        self.inner.len()
    }
    /// Last alarm state.
    #[getter]
    fn alarm(&self) -> bool {
        self.inner.alarm()
    }
    /// Pickle support: ``(navfdi._core._restore, ("Aime", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(py, "Aime", crate::pickling::state("Aime", &self.inner)?)
    }
    fn __repr__(&self) -> String {
        format!(
            "Aime(pf={}, window={})",
            self.inner.pf(),
            self.inner.window()
        )
    }
}

fn two_stage_step(
    d: &mut TwoStageAime,
    r: &DVector<f64>,
    a: &DMatrix<f64>,
) -> navfdi_core::Result<Report> {
    Ok(Report {
        decision: d.test(r, a)?,
        components: None,
        chi2: None,
        reset: false,
    })
}

/// Two-stage AIME detector (paper 004).
#[pyclass(name = "TwoStageAime", module = "navfdi._core")]
pub struct PyTwoStageAime {
    inner: TwoStageAime,
}

impl PyTwoStageAime {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: TwoStageAime) -> Self {
        PyTwoStageAime { inner }
    }
}

#[pymethods]
impl PyTwoStageAime {
    #[new]
    #[pyo3(signature = (pf, window1, window2, q = 10.0, b = 0.99, every = 1, r0 = 1.0))]
    fn new(
        pf: f64,
        window1: i64,
        window2: i64,
        q: f64,
        b: f64,
        every: i64,
        r0: f64,
    ) -> PyResult<Self> {
        for (name, w) in [("window1", window1), ("window2", window2), ("every", every)] {
            if w < 1 {
                return Err(PyValueError::new_err(format!(
                    "{name} = {w}: must be at least 1 (epochs)"
                )));
            }
        }
        Ok(PyTwoStageAime {
            inner: TwoStageAime::new(pf, window1 as usize, window2 as usize, q, b)
                .and_then(|d| d.with_decimation(every as usize, r0))
                .py()?,
        })
    }
    /// Test one epoch.
    fn test(
        &mut self,
        residual: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
    ) -> PyResult<PyDecision> {
        test_one(&mut self.inner, residual, covariance, two_stage_step)
    }
    /// Test a whole sequence in Rust.
    fn test_sequence(
        &mut self,
        py: Python<'_>,
        residuals: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
    ) -> PyResult<PyDetectionRun> {
        run_sequence(py, &mut self.inner, residuals, covariances, two_stage_step)
    }
    /// Start over.
    fn reset(&mut self) {
        self.inner.reset()
    }
    /// Stage-2 threshold (χ²(1)); `dof`, if given, must be 1.
    #[pyo3(signature = (dof = None))]
    fn threshold(&mut self, dof: Option<i64>) -> PyResult<f64> {
        if let Some(d) = dof {
            if d != 1 {
                return Err(PyValueError::new_err(format!(
                    "dof = {d}: the two-stage AIME tests a scalar (dof 1)"
                )));
            }
        }
        self.inner.threshold().py()
    }
    /// False-alarm probability of the stage-2 test.
    #[getter]
    fn pf(&self) -> f64 {
        self.inner.pf()
    }
    /// Windows (stage 1, stage 2) in epochs.
    #[getter]
    fn windows(&self) -> (usize, usize) {
        self.inner.windows()
    }
    /// The last stage-1 statistic.
    #[getter]
    fn stage1_statistic(&self) -> f64 {
        self.inner.last_stage1()
    }
    /// The adapted measurement noise R of the statistic filter.
    #[getter]
    fn measurement_noise(&self) -> f64 {
        self.inner.measurement_noise()
    }
    /// Last alarm state.
    #[getter]
    fn alarm(&self) -> bool {
        self.inner.alarm()
    }
    /// Pickle support: ``(navfdi._core._restore, ("TwoStageAime", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "TwoStageAime",
            crate::pickling::state("TwoStageAime", &self.inner)?,
        )
    }
    fn __repr__(&self) -> String {
        let (a, b) = self.inner.windows();
        format!(
            "TwoStageAime(pf={}, window1={a}, window2={b})",
            self.inner.pf()
        )
    }
}

/// Residual chi-square detector.
#[pyclass(name = "ResidualChi2", module = "navfdi._core")]
pub struct PyResidualChi2 {
    inner: ResidualChi2,
}

impl PyResidualChi2 {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: ResidualChi2) -> Self {
        PyResidualChi2 { inner }
    }
}

#[pymethods]
impl PyResidualChi2 {
    #[new]
    #[pyo3(signature = (pf))]
    fn new(pf: f64) -> PyResult<Self> {
        Ok(PyResidualChi2 {
            inner: ResidualChi2::new(pf).py()?,
        })
    }
    /// Test one epoch.
    fn test(
        &mut self,
        residual: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
    ) -> PyResult<PyDecision> {
        test_one(&mut self.inner, residual, covariance, chi2_step)
    }
    /// Test a whole sequence in Rust.
    fn test_sequence(
        &mut self,
        py: Python<'_>,
        residuals: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
    ) -> PyResult<PyDetectionRun> {
        run_sequence(py, &mut self.inner, residuals, covariances, chi2_step)
    }
    /// Forget the last alarm state.
    fn reset(&mut self) {
        self.inner.reset()
    }
    /// Threshold T_D for `dof` residual components.
    #[pyo3(signature = (dof = None))]
    fn threshold(&mut self, dof: Option<i64>) -> PyResult<f64> {
        let dof = dof.ok_or_else(|| {
            PyValueError::new_err(
                "dof: the chi-square threshold depends on the number of residual components; give dof",
            )
        })?;
        let dof = positive_dof(dof)?;
        self.inner.threshold(dof).py()
    }
    /// False-alarm probability per epoch.
    #[getter]
    fn pf(&self) -> f64 {
        self.inner.pf()
    }
    /// Last alarm state.
    #[getter]
    fn alarm(&self) -> bool {
        self.inner.alarm()
    }
    /// Pickle support: ``(navfdi._core._restore, ("ResidualChi2", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "ResidualChi2",
            crate::pickling::state("ResidualChi2", &self.inner)?,
        )
    }
    fn __repr__(&self) -> String {
        format!("ResidualChi2(pf={})", self.inner.pf())
    }
}

/// Improved SPRT detector.
#[pyclass(name = "ImprovedSprt", module = "navfdi._core")]
pub struct PyImprovedSprt {
    inner: ImprovedSprt,
}

impl PyImprovedSprt {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: ImprovedSprt) -> Self {
        PyImprovedSprt { inner }
    }
}

#[pymethods]
impl PyImprovedSprt {
    #[new]
    #[pyo3(signature = (pf, pm, variance = "known", min_samples = None))]
    fn new(pf: f64, pm: f64, variance: &str, min_samples: Option<i64>) -> PyResult<Self> {
        let d = ImprovedSprt::new(pf, pm, parse_variance(variance)?).py()?;
        Ok(PyImprovedSprt {
            inner: with_min_samples(d, min_samples, ImprovedSprt::with_min_samples)?,
        })
    }
    /// Test one epoch.
    fn test(
        &mut self,
        residual: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
    ) -> PyResult<PyDecision> {
        test_one(&mut self.inner, residual, covariance, sprt_step)
    }
    /// Test a whole sequence in Rust.
    fn test_sequence(
        &mut self,
        py: Python<'_>,
        residuals: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
    ) -> PyResult<PyDetectionRun> {
        run_sequence(py, &mut self.inner, residuals, covariances, sprt_step)
    }
    /// Reset all accumulators to zero.
    fn reset(&mut self) {
        self.inner.reset()
    }
    /// Reset and forget the residual dimension, so the next test may use another length.
    fn reset_dimension(&mut self) {
        self.inner.reset_dimension()
    }
    /// Threshold T(H1) = ln((1 − pm)/pf) (the same for any `dof`).
    #[pyo3(signature = (dof = None))]
    fn threshold(&self, dof: Option<i64>) -> PyResult<f64> {
        if let Some(d) = dof {
            positive_dof(d)?;
        }
        Ok(self.inner.threshold())
    }
    /// Minimum samples per component since the last reset before it may alarm.
    #[getter]
    fn min_samples(&self) -> u64 {
        self.inner.min_samples()
    }
    /// False-alarm probability parameter.
    #[getter]
    fn pf(&self) -> f64 {
        self.inner.pf()
    }
    /// Missed-detection probability parameter.
    #[getter]
    fn pm(&self) -> f64 {
        self.inner.pm()
    }
    /// "known" or "sample".
    #[getter]
    fn variance(&self) -> &'static str {
        variance_name(self.inner.variance())
    }
    /// Last alarm state.
    #[getter]
    fn alarm(&self) -> bool {
        self.inner.alarm()
    }
    /// Pickle support: ``(navfdi._core._restore, ("ImprovedSprt", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "ImprovedSprt",
            crate::pickling::state("ImprovedSprt", &self.inner)?,
        )
    }
    fn __repr__(&self) -> String {
        format!(
            "ImprovedSprt(pf={}, pm={}, variance={:?})",
            self.inner.pf(),
            self.inner.pm(),
            variance_name(self.inner.variance())
        )
    }
}

/// Joint chi-square / SPRT detector.
#[pyclass(name = "JointChi2Sprt", module = "navfdi._core")]
pub struct PyJointChi2Sprt {
    inner: JointChi2Sprt,
}

impl PyJointChi2Sprt {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: JointChi2Sprt) -> Self {
        PyJointChi2Sprt { inner }
    }
}

#[pymethods]
impl PyJointChi2Sprt {
    #[new]
    #[pyo3(signature = (pf, pm, variance = "known", min_samples = None))]
    fn new(pf: f64, pm: f64, variance: &str, min_samples: Option<i64>) -> PyResult<Self> {
        let d = JointChi2Sprt::new(pf, pm, parse_variance(variance)?).py()?;
        Ok(PyJointChi2Sprt {
            inner: with_min_samples(d, min_samples, JointChi2Sprt::with_min_samples)?,
        })
    }
    /// Test one epoch.
    fn test(
        &mut self,
        residual: &Bound<'_, PyAny>,
        covariance: &Bound<'_, PyAny>,
    ) -> PyResult<PyDecision> {
        test_one(&mut self.inner, residual, covariance, joint_step)
    }
    /// Test a whole sequence in Rust.
    fn test_sequence(
        &mut self,
        py: Python<'_>,
        residuals: &Bound<'_, PyAny>,
        covariances: &Bound<'_, PyAny>,
    ) -> PyResult<PyDetectionRun> {
        run_sequence(py, &mut self.inner, residuals, covariances, joint_step)
    }
    /// Reset both tests.
    fn reset(&mut self) {
        self.inner.reset()
    }
    /// Reset and forget the residual dimension, so the next test may use another length.
    fn reset_dimension(&mut self) {
        self.inner.reset_dimension()
    }
    /// SPRT threshold T(H1) (the same for any `dof`; the alarm is the SPRT's).
    #[pyo3(signature = (dof = None))]
    fn threshold(&self, dof: Option<i64>) -> PyResult<f64> {
        if let Some(d) = dof {
            positive_dof(d)?;
        }
        Ok(self.inner.sprt().threshold())
    }
    /// Minimum samples per component since the last reset before the SPRT may alarm.
    #[getter]
    fn min_samples(&self) -> u64 {
        self.inner.sprt().min_samples()
    }
    /// False-alarm probability parameter.
    #[getter]
    fn pf(&self) -> f64 {
        self.inner.sprt().pf()
    }
    /// Missed-detection probability parameter.
    #[getter]
    fn pm(&self) -> f64 {
        self.inner.sprt().pm()
    }
    /// "known" or "sample".
    #[getter]
    fn variance(&self) -> &'static str {
        variance_name(self.inner.sprt().variance())
    }
    /// Last alarm state (the SPRT's).
    #[getter]
    fn alarm(&self) -> bool {
        self.inner.sprt().alarm()
    }
    /// Pickle support: ``(navfdi._core._restore, ("JointChi2Sprt", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "JointChi2Sprt",
            crate::pickling::state("JointChi2Sprt", &self.inner)?,
        )
    }
    fn __repr__(&self) -> String {
        format!(
            "JointChi2Sprt(pf={}, pm={}, variance={:?})",
            self.inner.sprt().pf(),
            self.inner.sprt().pm(),
            variance_name(self.inner.sprt().variance())
        )
    }
}

/// Apply an optional `min_samples` (validated) with the detector's own setter.
fn with_min_samples<D>(
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

/// One epoch's decision of :class:`StateChi2`.
#[pyclass(name = "StateDecision", module = "navfdi._core", frozen)]
pub struct PyStateDecision {
    inner: navfdi_core::detect::StateDecision,
}

#[pymethods]
impl PyStateDecision {
    /// λ = βᵀV⁻¹β (NaN when not tested: propagator too young or V ill-conditioned).
    #[getter]
    fn statistic(&self) -> f64 {
        self.inner.statistic
    }
    /// Threshold F⁻¹_{χ²(dof)}(1 − pf).
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.threshold
    }
    /// Fault declared this epoch.
    #[getter]
    fn alarm(&self) -> bool {
        self.inner.alarm
    }
    /// Number of tested states.
    #[getter]
    fn dof(&self) -> usize {
        self.inner.dof
    }
    /// Index (0 or 1) of the propagator tested, None when not tested.
    #[getter]
    fn propagator(&self) -> Option<usize> {
        self.inner.propagator
    }
    /// Age of the tested propagator in epochs (0 when not tested).
    #[getter]
    fn age(&self) -> u64 {
        self.inner.age
    }
    /// The age rule is met (a propagator at least ``min_age`` epochs old exists).
    #[getter]
    fn ready(&self) -> bool {
        self.inner.ready
    }
    /// V = P_s − P could not be factored safely; nothing was tested.
    #[getter]
    fn ill_conditioned(&self) -> bool {
        self.inner.ill_conditioned
    }
    /// Statistic over threshold (≥ 1 means alarm; NaN when not tested).
    #[getter]
    fn ratio(&self) -> f64 {
        self.inner.statistic / self.inner.threshold
    }
    fn __repr__(&self) -> String {
        format!(
            "StateDecision(statistic={:.4}, threshold={:.4}, alarm={}, propagator={:?}, age={}, ready={}, ill_conditioned={})",
            self.inner.statistic,
            self.inner.threshold,
            self.inner.alarm,
            self.inner.propagator,
            self.inner.age,
            self.inner.ready,
            self.inner.ill_conditioned
        )
    }
}

/// Dual-propagator state chi-square detector (METHODS §8, paper 003).
#[pyclass(name = "StateChi2", module = "navfdi._core")]
pub struct PyStateChi2 {
    inner: navfdi_core::detect::StateChi2,
}

impl PyStateChi2 {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: navfdi_core::detect::StateChi2) -> Self {
        PyStateChi2 { inner }
    }
}

#[pymethods]
impl PyStateChi2 {
    #[new]
    #[pyo3(signature = (pf, n, reset_every, min_age = None, states = None))]
    fn new(
        pf: f64,
        n: i64,
        reset_every: i64,
        min_age: Option<i64>,
        states: Option<Vec<i64>>,
    ) -> PyResult<Self> {
        let nonneg = |name: &str, v: i64| -> PyResult<u64> {
            u64::try_from(v)
                .map_err(|_| PyValueError::new_err(format!("{name} = {v}: must be >= 0")))
        };
        let n = nonneg("n", n)? as usize;
        let reset_every = nonneg("reset_every", reset_every)?;
        let min_age = match min_age {
            Some(a) => nonneg("min_age", a)?,
            None => reset_every,
        };
        let states = states
            .map(|v| {
                v.into_iter()
                    .enumerate()
                    .map(|(i, s)| {
                        usize::try_from(s).map_err(|_| {
                            PyValueError::new_err(format!("states[{i}] = {s}: must be >= 0"))
                        })
                    })
                    .collect::<PyResult<Vec<usize>>>()
            })
            .transpose()?;
        Ok(PyStateChi2 {
            inner: navfdi_core::detect::StateChi2::new(pf, n, reset_every, min_age, states).py()?,
        })
    }
    /// One epoch: the filter's updated estimate ``x`` (n,) and ``P`` (n, n), and the
    /// transition ``Phi`` (n, n) and process noise ``Q`` (n, n) from the previous epoch.
    #[allow(non_snake_case)]
    fn step(
        &mut self,
        x: &Bound<'_, PyAny>,
        P: &Bound<'_, PyAny>,
        Phi: &Bound<'_, PyAny>,
        Q: &Bound<'_, PyAny>,
    ) -> PyResult<PyStateDecision> {
        let n = self.inner.n();
        let x = crate::convert::vector("x", x, Some(n))?;
        let p = crate::convert::matrix("P", P)?;
        let phi = crate::convert::matrix("Phi", Phi)?;
        let q = crate::convert::matrix("Q", Q)?;
        Ok(PyStateDecision {
            inner: self.inner.step(&x, &p, &phi, &q).py()?,
        })
    }
    /// Threshold F⁻¹_{χ²(len(states))}(1 − pf).
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.threshold()
    }
    /// False-alarm probability per epoch.
    #[getter]
    fn pf(&self) -> f64 {
        self.inner.pf()
    }
    /// Tested state indices.
    #[getter]
    fn states(&self) -> Vec<usize> {
        self.inner.states().to_vec()
    }
    /// Pickle support: ``(navfdi._core._restore, ("StateChi2", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "StateChi2",
            crate::pickling::state("StateChi2", &self.inner)?,
        )
    }
    fn __repr__(&self) -> String {
        format!(
            "StateChi2(pf={}, n={}, states={:?})",
            self.inner.pf(),
            self.inner.n(),
            self.inner.states()
        )
    }
}
