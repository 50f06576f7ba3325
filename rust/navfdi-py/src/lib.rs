//! Python bindings of navfdi (`navfdi._core`). This crate only converts types and errors; all
//! computation lives in `navfdi-core`. Whole-sequence calls release the GIL.

#![deny(clippy::unwrap_used, clippy::expect_used)]

mod convert;
mod detect;
mod errors;
mod federated;
mod filter;
mod montecarlo;
mod scenario;

use crate::errors::IntoPyResult;
use convert::{matrix, to_numpy};
use numpy::{IxDyn, PyArray};
use pyo3::prelude::*;

/// Chi-square threshold T_D for false-alarm probability `pf` and `dof` degrees of freedom.
#[pyfunction]
fn chi2_threshold(pf: f64, dof: i64) -> PyResult<f64> {
    navfdi_core::stats::chi2_threshold(pf, detect::positive_dof(dof)?).py()
}

/// Improved-SPRT threshold ln((1 − pm)/pf).
#[pyfunction]
fn sprt_threshold(pf: f64, pm: f64) -> PyResult<f64> {
    navfdi_core::stats::sprt_threshold(pf, pm).py()
}

/// Non-centrality λ0 with F_{χ²(dof, λ0)}(T_D) = pm.
#[pyfunction]
fn noncentrality(pf: f64, pm: f64, dof: i64) -> PyResult<f64> {
    navfdi_core::stats::noncentrality(pf, pm, detect::positive_dof(dof)?).py()
}

/// Minimal detectable bias per component of a residual with covariance A.
#[pyfunction]
#[pyo3(signature = (A, pf, pm))]
#[allow(non_snake_case)]
fn mdb<'py>(
    py: Python<'py>,
    A: &Bound<'py, PyAny>,
    pf: f64,
    pm: f64,
) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
    let a = matrix("A", A)?;
    let v = navfdi_core::stats::mdb(&a, pf, pm).py()?;
    let len = v.len();
    to_numpy(py, v, &[len])
}

/// CDF of the non-central chi-square distribution.
#[pyfunction]
fn ncx2_cdf(x: f64, dof: i64, noncentrality: f64) -> PyResult<f64> {
    navfdi_core::stats::ncx2_cdf(x, detect::positive_dof(dof)?, noncentrality).py()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("LinAlgError", m.py().get_type::<errors::LinAlgError>())?;
    m.add_class::<filter::PyKalmanFilter>()?;
    m.add_class::<filter::PyInnovation>()?;
    m.add_function(wrap_pyfunction!(filter::run_filter, m)?)?;
    m.add_class::<detect::PyDecision>()?;
    m.add_class::<detect::PyDetectionRun>()?;
    m.add_class::<detect::PyResidualChi2>()?;
    m.add_class::<detect::PyImprovedSprt>()?;
    m.add_class::<detect::PyJointChi2Sprt>()?;
    m.add_function(wrap_pyfunction!(chi2_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(sprt_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(noncentrality, m)?)?;
    m.add_function(wrap_pyfunction!(ncx2_cdf, m)?)?;
    m.add_function(wrap_pyfunction!(mdb, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::validate_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::scenario_trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::run_scenario, m)?)?;
    m.add_class::<federated::PyFederatedFilter>()?;
    m.add_class::<federated::PyFederatedStep>()?;
    m.add_class::<montecarlo::PyPreparedScenario>()?;
    Ok(())
}
