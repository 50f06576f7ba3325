//! `ResidualChi2`, `ImprovedSprt` and `JointChi2Sprt` bindings.

use super::common::*;
use crate::errors::IntoPyResult;
use nalgebra::{DMatrix, DVector};
use navfdi_core::detect::{ImprovedSprt, JointChi2Sprt, ResidualChi2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

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
    fn new(pf: &Bound<'_, PyAny>) -> PyResult<Self> {
        let pf = crate::convert::float_arg("pf", pf)?;
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
    fn new(
        pf: &Bound<'_, PyAny>,
        pm: &Bound<'_, PyAny>,
        variance: &str,
        min_samples: Option<i64>,
    ) -> PyResult<Self> {
        let pf = crate::convert::float_arg("pf", pf)?;
        let pm = crate::convert::float_arg("pm", pm)?;
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
            "ImprovedSprt(pf={}, pm={}, variance='{}')",
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
    fn new(
        pf: &Bound<'_, PyAny>,
        pm: &Bound<'_, PyAny>,
        variance: &str,
        min_samples: Option<i64>,
    ) -> PyResult<Self> {
        let pf = crate::convert::float_arg("pf", pf)?;
        let pm = crate::convert::float_arg("pm", pm)?;
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
            "JointChi2Sprt(pf={}, pm={}, variance='{}')",
            self.inner.sprt().pf(),
            self.inner.sprt().pm(),
            variance_name(self.inner.sprt().variance())
        )
    }
}
