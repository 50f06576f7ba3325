//! `Aime` and `TwoStageAime` bindings (paper 004).

use super::common::*;
use crate::errors::IntoPyResult;
use nalgebra::{DMatrix, DVector};
use navfdi_core::detect::{Aime, TwoStageAime};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

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
    fn new(pf: &Bound<'_, PyAny>, window: i64) -> PyResult<Self> {
        let pf = crate::convert::float_arg("pf", pf)?;
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
        pf: &Bound<'_, PyAny>,
        window1: i64,
        window2: i64,
        q: f64,
        b: f64,
        every: i64,
        r0: f64,
    ) -> PyResult<Self> {
        let pf = crate::convert::float_arg("pf", pf)?;
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
