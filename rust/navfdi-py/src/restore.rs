//! `_restore`: rebuild a pickled object from `(class name, state)` (see [`crate::pickling`]).
//! Above every class it restores, which import only the serialising helpers below them.

use crate::pickling::load;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Rebuild a pickled object (used by `__reduce__`; not for direct use).
#[pyfunction]
pub fn _restore(py: Python<'_>, kind: &str, state: &str) -> PyResult<Py<PyAny>> {
    use crate::detect::{PyImprovedSprt, PyJointChi2Sprt, PyResidualChi2};
    use crate::federated::PyFederatedFilter;
    use crate::filter::PyKalmanFilter;
    Ok(match kind {
        "KalmanFilter" => Py::new(py, PyKalmanFilter::from_inner(load(kind, state)?))?.into_any(),
        "ResidualChi2" => Py::new(py, PyResidualChi2::from_inner(load(kind, state)?))?.into_any(),
        "ImprovedSprt" => Py::new(py, PyImprovedSprt::from_inner(load(kind, state)?))?.into_any(),
        "JointChi2Sprt" => Py::new(py, PyJointChi2Sprt::from_inner(load(kind, state)?))?.into_any(),
        "WeightedFusion" => {
            let inner: navfdi_core::fusion::WeightedFusion = load(kind, state)?;
            inner.check_consistent().map_err(|e| {
                PyValueError::new_err(format!("cannot restore a WeightedFusion: {e}"))
            })?;
            Py::new(py, crate::weighted::PyWeightedFusion::from_inner(inner))?.into_any()
        }
        "Aime" => {
            let inner: navfdi_core::detect::Aime = load(kind, state)?;
            inner
                .check_consistent()
                .map_err(|e| PyValueError::new_err(format!("cannot restore an Aime: {e}")))?;
            Py::new(py, crate::detect::PyAime::from_inner(inner))?.into_any()
        }
        "TwoStageAime" => {
            let inner: navfdi_core::detect::TwoStageAime = load(kind, state)?;
            inner.check_consistent().map_err(|e| {
                PyValueError::new_err(format!("cannot restore a TwoStageAime: {e}"))
            })?;
            Py::new(py, crate::detect::PyTwoStageAime::from_inner(inner))?.into_any()
        }
        "StateChi2" => {
            let inner: navfdi_core::detect::StateChi2 = load(kind, state)?;
            inner
                .check_consistent()
                .map_err(|e| PyValueError::new_err(format!("cannot restore a StateChi2: {e}")))?;
            Py::new(py, crate::detect::PyStateChi2::from_inner(inner))?.into_any()
        }
        "Prefilter" => {
            let inner: navfdi_core::gnss::prefilter::Prefilter = load(kind, state)?;
            inner
                .check_consistent()
                .map_err(|e| PyValueError::new_err(format!("cannot restore a Prefilter: {e}")))?;
            Py::new(py, crate::prefilter::PyPrefilter::from_inner(inner))?.into_any()
        }
        "FederatedFilter" => {
            Py::new(py, PyFederatedFilter::from_inner(load(kind, state)?))?.into_any()
        }
        other => {
            return Err(PyValueError::new_err(format!(
                "_restore: unknown class {other:?}"
            )))
        }
    })
}
