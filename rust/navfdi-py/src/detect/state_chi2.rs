//! `StateChi2` binding (paper 003's dual-propagator state chi-square test).

use super::common::positive_count;
use crate::errors::IntoPyResult;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

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
            "StateDecision(statistic={}, threshold={}, alarm={}, propagator={}, age={}, ready={}, ill_conditioned={})",
            crate::convert::py_float(self.inner.statistic),
            crate::convert::py_float(self.inner.threshold),
            crate::convert::py_bool(self.inner.alarm),
            crate::convert::py_opt(self.inner.propagator),
            self.inner.age,
            crate::convert::py_bool(self.inner.ready),
            crate::convert::py_bool(self.inner.ill_conditioned)
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
        pf: &Bound<'_, PyAny>,
        n: i64,
        reset_every: i64,
        min_age: Option<i64>,
        states: Option<Vec<i64>>,
    ) -> PyResult<Self> {
        let pf = crate::convert::float_arg("pf", pf)?;
        // Counts of at least 1, the same requirement (and message) whatever the sign.
        let n = positive_count("n", n)? as usize;
        let reset_every = positive_count("reset_every", reset_every)?;
        let min_age = match min_age {
            Some(a) => positive_count("min_age", a)?,
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
