//! Bindings of the weighted fusion with a fault matrix (METHODS §9).

use crate::convert::to_numpy;
use crate::errors::IntoPyResult;
use navfdi_core::fusion::{Estimate, Fused, WeightedFusion};
use pyo3::prelude::*;

/// One epoch's output of :class:`WeightedFusion`.
#[pyclass(name = "FusedValue", module = "navfdi._core", frozen)]
pub struct PyFused {
    inner: Fused,
}

#[pymethods]
impl PyFused {
    /// Fused value (the sensors' unit), or None when no sensor contributed (every M_i = 0 or
    /// no value): the caller then predicts only.
    #[getter]
    fn value(&self) -> Option<f64> {
        self.inner.value
    }
    /// Its variance 1 / Σ w_i M_i (NaN when none contributed).
    #[getter]
    fn variance(&self) -> f64 {
        self.inner.variance
    }
    /// Normalised weights per sensor, shape (n,) (0 for sensors that did not contribute).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(to_numpy(py, self.inner.weights.clone(), &[self.inner.weights.len()])?.into_any())
    }
    /// Estimated σ_i² per sensor, shape (n,) (mean square or variance of the deviations over
    /// the window, or the prior before two samples).
    #[getter]
    fn sigma2<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(to_numpy(py, self.inner.sigma2.clone(), &[self.inner.sigma2.len()])?.into_any())
    }
    fn __repr__(&self) -> String {
        format!(
            "FusedValue(value={}, variance={}, weights={})",
            crate::convert::py_opt(self.inner.value.map(crate::convert::py_float)),
            crate::convert::py_float(self.inner.variance),
            crate::convert::py_floats(&self.inner.weights)
        )
    }
}

/// Inverse-variance fusion of one quantity over several sensors with a fault matrix.
#[pyclass(name = "WeightedFusion", module = "navfdi._core")]
pub struct PyWeightedFusion {
    inner: WeightedFusion,
}

impl PyWeightedFusion {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: WeightedFusion) -> Self {
        PyWeightedFusion { inner }
    }
}

#[pymethods]
impl PyWeightedFusion {
    #[new]
    #[pyo3(signature = (prior_sigma, window = 20, estimate = "mean_square"))]
    fn new(prior_sigma: Vec<f64>, window: i64, estimate: &str) -> PyResult<Self> {
        let window = usize::try_from(window).map_err(|_| {
            pyo3::exceptions::PyValueError::new_err(format!("window = {window}: must be >= 2"))
        })?;
        let estimate = Estimate::from_name(estimate).ok_or_else(|| {
            pyo3::exceptions::PyValueError::new_err(format!(
                "estimate = {estimate:?}: use \"mean_square\" or \"variance\""
            ))
        })?;
        Ok(PyWeightedFusion {
            inner: WeightedFusion::new(&prior_sigma, window)
                .py()?
                .with_estimate(estimate),
        })
    }
    /// How σ_i² is estimated: ``"mean_square"`` or ``"variance"``.
    #[getter]
    fn estimate(&self) -> &'static str {
        self.inner.estimate().name()
    }
    /// One epoch: ``values`` (n,) per sensor (NaN: not available), the filter's ``predicted``
    /// value, ``healthy`` (n,) booleans, the fault matrix M_i.
    fn step(
        &mut self,
        values: &Bound<'_, PyAny>,
        predicted: f64,
        healthy: Vec<bool>,
    ) -> PyResult<PyFused> {
        let v = crate::convert::vector("values", values, Some(self.inner.sensors()))?;
        Ok(PyFused {
            inner: self.inner.step(v.as_slice(), predicted, &healthy).py()?,
        })
    }
    /// Number of sensors.
    #[getter]
    fn sensors(&self) -> usize {
        self.inner.sensors()
    }
    /// Pickle support: ``(navfdi._core._restore, ("WeightedFusion", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "WeightedFusion",
            crate::pickling::state("WeightedFusion", &self.inner)?,
        )
    }
}
