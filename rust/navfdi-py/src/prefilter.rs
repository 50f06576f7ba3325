//! Bindings of the channel prefilter and the discriminator noise (paper 004, METHODS §11).

use crate::convert::{matrix_to_numpy, vector_to_numpy};
use crate::errors::IntoPyResult;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use navfdi_core::gnss::prefilter::{
    dll_variance, fll_variance, Prefilter, PrefilterConfig, PrefilterStep, F_CARRIER_L1,
    F_CODE_L1CA,
};
use pyo3::prelude::*;

/// Variance (chips²) of one delay-discriminator output (Kaplan & Hegarty eq. 5.71, B = 1/(2T)).
#[pyfunction]
#[pyo3(name = "dll_variance", signature = (cn0_dbhz, t = 0.02, spacing = 1.0))]
pub fn py_dll_variance(cn0_dbhz: f64, t: f64, spacing: f64) -> PyResult<f64> {
    dll_variance(cn0_dbhz, t, spacing).py()
}

/// Variance (Hz²) of one frequency-discriminator output (Kaplan & Hegarty eq. 5.64, B = 1/(2T)).
#[pyfunction]
#[pyo3(name = "fll_variance", signature = (cn0_dbhz, t = 0.02, high_noise = false))]
pub fn py_fll_variance(cn0_dbhz: f64, t: f64, high_noise: bool) -> PyResult<f64> {
    fll_variance(cn0_dbhz, t, high_noise).py()
}

/// One step's innovation of :class:`Prefilter`.
#[pyclass(name = "PrefilterStep", module = "navfdi._core", frozen)]
pub struct PyPrefilterStep {
    inner: PrefilterStep,
}

#[pymethods]
impl PyPrefilterStep {
    /// Innovation (2,): code (chips), frequency (Hz); NaN where absent.
    #[getter]
    fn residual<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = DVector::from_column_slice(self.inner.residual.as_slice());
        Ok(vector_to_numpy(py, &v)?.into_any())
    }
    /// Its covariance (2, 2) (NaN rows/columns where absent).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let m = DMatrix::from_column_slice(2, 2, self.inner.covariance.as_slice());
        Ok(matrix_to_numpy(py, &m)?.into_any())
    }
    /// λ = rᵀA⁻¹r over the used components (NaN when none).
    #[getter]
    fn statistic(&self) -> f64 {
        self.inner.statistic
    }
    /// Components used.
    #[getter]
    fn dof(&self) -> usize {
        self.inner.dof
    }
    fn __repr__(&self) -> String {
        format!(
            "PrefilterStep(residual={}, statistic={}, dof={})",
            crate::convert::py_floats(&[self.inner.residual[0], self.inner.residual[1]]),
            crate::convert::py_float(self.inner.statistic),
            self.inner.dof
        )
    }
}

/// A channel prefilter of an ultra-tight receiver.
#[pyclass(name = "Prefilter", module = "navfdi._core")]
pub struct PyPrefilter {
    inner: Prefilter,
}

impl PyPrefilter {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: Prefilter) -> Self {
        PyPrefilter { inner }
    }
}

fn vec3(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vector3<f64>> {
    match obj {
        None => Ok(Vector3::zeros()),
        Some(o) => {
            let v = crate::convert::vector(name, o, Some(3))?;
            Ok(Vector3::new(v[0], v[1], v[2]))
        }
    }
}

#[pymethods]
impl PyPrefilter {
    #[new]
    #[pyo3(signature = (t = 0.02, beta = F_CODE_L1CA / F_CARRIER_L1, jerk_psd = 1.0, code_psd = 0.0, spacing = 1.0, x0 = None, P0 = None))]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    fn new(
        t: f64,
        beta: f64,
        jerk_psd: f64,
        code_psd: f64,
        spacing: f64,
        x0: Option<&Bound<'_, PyAny>>,
        P0: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let cfg = PrefilterConfig {
            t,
            beta,
            jerk_psd,
            code_psd,
            spacing,
        };
        let x = vec3("x0", x0)?;
        let p = match P0 {
            None => Matrix3::from_diagonal(&Vector3::new(0.01, 1.0, 1.0)),
            Some(o) => {
                let m = crate::convert::matrix("P0", o)?;
                if m.shape() != (3, 3) {
                    return Err(pyo3::exceptions::PyValueError::new_err(format!(
                        "P0: expected shape (3, 3), got ({}, {})",
                        m.nrows(),
                        m.ncols()
                    )));
                }
                Matrix3::from_iterator(m.iter().copied())
            }
        };
        Ok(PyPrefilter {
            inner: Prefilter::new(cfg, x, p).py()?,
        })
    }
    /// One coherent integration: predict over T, update with the code (chips) and frequency
    /// (Hz) discriminator outputs (NaN: absent) whose noise follows ``cn0_dbhz``.
    fn step(&mut self, z_code: f64, z_freq: f64, cn0_dbhz: f64) -> PyResult<PyPrefilterStep> {
        Ok(PyPrefilterStep {
            inner: self.inner.step(z_code, z_freq, cn0_dbhz).py()?,
        })
    }
    /// Shift the state by ``dx`` (3,) (a replica correction).
    fn shift(&mut self, dx: &Bound<'_, PyAny>) -> PyResult<()> {
        let d = vec3("dx", Some(dx))?;
        self.inner.shift(&d).py()
    }
    /// State (3,): code-phase error (chips), frequency error (Hz), its rate (Hz/s).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = DVector::from_column_slice(self.inner.x().as_slice());
        Ok(vector_to_numpy(py, &v)?.into_any())
    }
    /// Covariance (3, 3).
    #[getter]
    #[allow(non_snake_case)]
    fn P<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let m = DMatrix::from_column_slice(3, 3, self.inner.p().as_slice());
        Ok(matrix_to_numpy(py, &m)?.into_any())
    }
    /// Transition matrix Φ (3, 3) of one step.
    #[getter]
    fn phi<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let p = self.inner.config().phi();
        let m = DMatrix::from_column_slice(3, 3, p.as_slice());
        Ok(matrix_to_numpy(py, &m)?.into_any())
    }
    /// Process noise Q (3, 3) of one step.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let q = self.inner.config().q();
        let m = DMatrix::from_column_slice(3, 3, q.as_slice());
        Ok(matrix_to_numpy(py, &m)?.into_any())
    }
    /// Pickle support: ``(navfdi._core._restore, ("Prefilter", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "Prefilter",
            crate::pickling::state("Prefilter", &self.inner)?,
        )
    }
}
