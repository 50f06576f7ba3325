//! `KalmanFilter`, `Innovation` and `run_filter` bindings.

use crate::convert::{
    matrix, matrix_seq, matrix_to_numpy, read, to_numpy, vector, vector_to_numpy,
};
use crate::errors::IntoPyResult;
use navfdi_core::kalman::{Innovation, KalmanFilter};
use navfdi_core::run::run_filter as core_run_filter;
use numpy::{IxDyn, PyArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Result of one measurement update: ``residual`` (m,) ``z − Hx⁻`` (NaN for unused
/// components), ``covariance`` (m, m) ``A = HP⁻Hᵀ + R``, ``statistic`` ``rᵀA⁻¹r``, ``used``
/// (m,) bool, ``dof`` (components used).
#[pyclass(name = "Innovation", module = "navfdi._core", frozen)]
pub struct PyInnovation {
    pub inner: Innovation,
}

#[pymethods]
impl PyInnovation {
    /// Residual r = z − Hx⁻, shape (m,); NaN where the component was not used.
    #[getter]
    fn residual<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        vector_to_numpy(py, &self.inner.residual)
    }

    /// Residual covariance A = HP⁻Hᵀ + R, shape (m, m); NaN rows/columns for unused components.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        matrix_to_numpy(py, &self.inner.covariance)
    }

    /// λ = rᵀA⁻¹r over the used components; NaN when no component was used.
    #[getter]
    fn statistic(&self) -> f64 {
        self.inner.statistic
    }

    /// Boolean mask of the components of z that were used, shape (m,).
    #[getter]
    fn used<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<bool, IxDyn>>> {
        to_numpy(py, self.inner.used.clone(), &[self.inner.used.len()])
    }

    /// Number of components used (degrees of freedom of `statistic`).
    #[getter]
    fn dof(&self) -> usize {
        self.inner.dof()
    }

    fn __repr__(&self) -> String {
        format!(
            "Innovation(statistic={}, dof={}, m={})",
            crate::convert::py_float(self.inner.statistic),
            self.inner.dof(),
            self.inner.used.len()
        )
    }
}

/// Linear Kalman filter with state ``x`` (n,) and covariance ``P`` (n, n).
///
/// ``KalmanFilter(x0, P0)``: initial state and covariance (symmetric positive definite).
/// ``predict(Phi, Q, fading=1.0)``: ``x = Φx``, ``P = S·ΦPΦᵀ + Q``. ``update(z, H, R)``: the
/// Cholesky/Joseph-form update; NaN components of ``z`` are left out (reduced-dimension
/// update); returns an :class:`Innovation` (residual, covariance ``A = HPHᵀ + R``, statistic
/// ``rᵀA⁻¹r``, components used). ``set_model(Phi, Q, H, R)`` fixes a model once and
/// ``step(z)`` runs an epoch of it (the same arithmetic as ``predict`` then ``update``; only
/// ``z`` is converted and checked). A rejected call leaves the filter as it was. Properties
/// ``x``, ``P``, ``n``; picklable. Shapes and units in ``navfdi._core.pyi`` / ``help()``.
#[pyclass(name = "KalmanFilter", module = "navfdi._core")]
pub struct PyKalmanFilter {
    inner: KalmanFilter,
}

impl PyKalmanFilter {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: KalmanFilter) -> Self {
        PyKalmanFilter { inner }
    }
}

#[pymethods]
impl PyKalmanFilter {
    #[new]
    #[pyo3(signature = (x0, P0))]
    #[allow(non_snake_case)]
    fn new(x0: &Bound<'_, PyAny>, P0: &Bound<'_, PyAny>) -> PyResult<Self> {
        let x0 = vector("x0", x0, None)?;
        let p0 = matrix("P0", P0)?;
        Ok(PyKalmanFilter {
            inner: KalmanFilter::new(x0, p0).py()?,
        })
    }

    /// Time update x⁻ = Φx, P⁻ = S·ΦPΦᵀ + Q.
    #[pyo3(signature = (Phi, Q, fading = 1.0))]
    #[allow(non_snake_case)]
    fn predict(
        &mut self,
        Phi: &Bound<'_, PyAny>,
        Q: &Bound<'_, PyAny>,
        fading: f64,
    ) -> PyResult<()> {
        let phi = matrix("Phi", Phi)?;
        let q = matrix("Q", Q)?;
        self.inner.predict(&phi, &q, fading).py()
    }

    /// Measurement update; NaN components of z are skipped.
    #[pyo3(signature = (z, H, R))]
    #[allow(non_snake_case)]
    fn update(
        &mut self,
        z: &Bound<'_, PyAny>,
        H: &Bound<'_, PyAny>,
        R: &Bound<'_, PyAny>,
    ) -> PyResult<PyInnovation> {
        let z = vector("z", z, None)?;
        let h = matrix("H", H)?;
        let r = matrix("R", R)?;
        Ok(PyInnovation {
            inner: self.inner.update(&z, &h, &r).py()?,
        })
    }

    /// Fix the model ``step`` runs: ``Phi``, ``Q`` (n, n), ``H`` (m, n), ``R`` (m, m), validated
    /// once as ``predict`` and ``update`` validate theirs.
    #[pyo3(signature = (Phi, Q, H, R))]
    #[allow(non_snake_case)]
    fn set_model(
        &mut self,
        Phi: &Bound<'_, PyAny>,
        Q: &Bound<'_, PyAny>,
        H: &Bound<'_, PyAny>,
        R: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (phi, q) = (matrix("Phi", Phi)?, matrix("Q", Q)?);
        let (h, r) = (matrix("H", H)?, matrix("R", R)?);
        self.inner.set_model(phi, q, h, r).py()
    }

    /// One epoch of the fixed model: ``predict`` then ``update`` with ``z`` (m,).
    #[pyo3(signature = (z))]
    fn step(&mut self, z: &Bound<'_, PyAny>) -> PyResult<PyInnovation> {
        let z = vector("z", z, None)?;
        Ok(PyInnovation {
            inner: self.inner.step(&z).py()?,
        })
    }

    /// Replace the state and covariance.
    #[pyo3(signature = (x, P))]
    #[allow(non_snake_case)]
    fn set_state(&mut self, x: &Bound<'_, PyAny>, P: &Bound<'_, PyAny>) -> PyResult<()> {
        let n = self.inner.dim();
        let x = vector("x", x, Some(n))?;
        let p = matrix("P", P)?;
        self.inner.set_state(x, p).py()
    }

    /// State estimate, shape (n,) (a copy).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        vector_to_numpy(py, self.inner.x())
    }

    /// Covariance, shape (n, n) (a copy).
    #[getter(P)]
    fn p<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        matrix_to_numpy(py, self.inner.p())
    }

    /// State dimension n.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// Pickle support: ``(navfdi._core._restore, ("KalmanFilter", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "KalmanFilter",
            crate::pickling::state("KalmanFilter", &self.inner)?,
        )
    }
    fn __repr__(&self) -> String {
        format!("KalmanFilter(n={})", self.inner.dim())
    }
}

type RunArrays<'py> = (
    Bound<'py, PyArray<f64, IxDyn>>,
    Bound<'py, PyArray<f64, IxDyn>>,
    Bound<'py, PyArray<f64, IxDyn>>,
    Bound<'py, PyArray<f64, IxDyn>>,
    Bound<'py, PyArray<f64, IxDyn>>,
    Bound<'py, PyArray<bool, IxDyn>>,
);

/// Whole run; returns (x, P, residual, covariance, statistic, used).
#[pyfunction]
#[pyo3(signature = (x0, P0, Phi, Q, zs, H, R, fading = 1.0))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn run_filter<'py>(
    py: Python<'py>,
    x0: &Bound<'py, PyAny>,
    P0: &Bound<'py, PyAny>,
    Phi: &Bound<'py, PyAny>,
    Q: &Bound<'py, PyAny>,
    zs: &Bound<'py, PyAny>,
    H: &Bound<'py, PyAny>,
    R: &Bound<'py, PyAny>,
    fading: f64,
) -> PyResult<RunArrays<'py>> {
    let x0 = vector("x0", x0, None)?;
    let p0 = matrix("P0", P0)?;
    let phi = matrix_seq("Phi", Phi)?;
    let q = matrix_seq("Q", Q)?;
    let h = matrix_seq("H", H)?;
    let r = matrix_seq("R", R)?;
    let z = read("zs", zs)?;
    if z.shape.len() != 2 {
        return Err(PyValueError::new_err(format!(
            "zs: expected a 2-D array (T, m) with one measurement row per epoch, got {} dimension(s)",
            z.shape.len()
        )));
    }
    let epochs = z.shape[0];
    let out = crate::interrupt::run(py, move |cancel| {
        core_run_filter(x0, p0, &phi, &q, &z.data, epochs, &h, &r, fading, cancel)
    })?;
    let (t, n, m) = (out.epochs, out.n, out.m);
    Ok((
        to_numpy(py, out.x, &[t, n])?,
        to_numpy(py, out.p, &[t, n, n])?,
        to_numpy(py, out.residual, &[t, m])?,
        to_numpy(py, out.covariance, &[t, m, m])?,
        to_numpy(py, out.statistic, &[t])?,
        to_numpy(py, out.used, &[t, m])?,
    ))
}
