//! Python bindings of navfdi (`navfdi._core`). This crate only converts types and errors; all
//! computation lives in `navfdi-core`. Whole-sequence calls release the GIL.

#![deny(clippy::unwrap_used, clippy::expect_used)]

mod convert;
mod detect;
mod errors;
mod federated;
mod filter;
mod gnss;
mod integrity;
mod interrupt;
mod logged;
mod montecarlo;
mod pickling;
mod prefilter;
mod restore;
mod rinex;
mod scenario;
mod weighted;

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

/// Load numpy's C API (see `_core`). rust-numpy loads it on first use and panics if that fails,
/// which it does when a Ctrl-C arrives while it runs `numpy.lib.NumpyVersion` (Python code).
/// Here the same Python steps run first with errors propagated, and the remaining load is
/// guarded: a panic becomes `KeyboardInterrupt` (if the failure was one) or `ImportError`.
/// Upstream: rust-numpy's `PyArrayAPI::get` uses `expect` on a fallible initialisation.
fn load_numpy_api(py: Python<'_>) -> PyResult<()> {
    let np = py.import("numpy")?;
    let version = np.getattr("__version__")?;
    let major: u8 = py
        .import("numpy.lib")?
        .getattr("NumpyVersion")?
        .call1((version,))?
        .getattr("major")?
        .extract()?;
    py.import(if major >= 2 {
        "numpy._core.multiarray"
    } else {
        "numpy.core.multiarray"
    })?;
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let loaded = std::panic::catch_unwind(|| {
        drop(numpy::PyArray1::<f64>::zeros(py, 0, false));
    });
    std::panic::set_hook(hook);
    match loaded {
        Ok(()) => Ok(()),
        Err(payload) => {
            let msg = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            if msg.contains("KeyboardInterrupt") {
                Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(
                    "interrupted while loading numpy's C API",
                ))
            } else {
                Err(pyo3::exceptions::PyImportError::new_err(format!(
                    "navfdi: cannot load numpy's C API: {msg}"
                )))
            }
        }
    }
}

/// Bytes of memory available to this process (MemAvailable, cgroup limit, NAVFDI_MEMORY_LIMIT).
#[pyfunction]
fn memory_available() -> f64 {
    navfdi_core::memory::available()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Load numpy's C API now, where an interrupt or import failure is an ordinary exception:
    // loaded lazily at the first array conversion, a Ctrl-C during numpy's import would make
    // rust-numpy panic ("Failed to access NumPy array API capsule").
    load_numpy_api(m.py())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("LinAlgError", m.py().get_type::<errors::LinAlgError>())?;
    m.add(
        "FileFormatError",
        m.py().get_type::<errors::FileFormatError>(),
    )?;
    m.add_class::<filter::PyKalmanFilter>()?;
    m.add_class::<filter::PyInnovation>()?;
    m.add_function(wrap_pyfunction!(filter::run_filter, m)?)?;
    m.add_class::<detect::PyDecision>()?;
    m.add_class::<detect::PyDetectionRun>()?;
    m.add_class::<detect::PyResidualChi2>()?;
    m.add_class::<detect::PyAime>()?;
    m.add_class::<detect::PyTwoStageAime>()?;
    m.add_class::<detect::PyImprovedSprt>()?;
    m.add_class::<detect::PyJointChi2Sprt>()?;
    m.add_class::<detect::PyStateChi2>()?;
    m.add_class::<detect::PyStateDecision>()?;
    m.add_class::<weighted::PyWeightedFusion>()?;
    m.add_class::<weighted::PyFused>()?;
    m.add_function(wrap_pyfunction!(chi2_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(sprt_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(noncentrality, m)?)?;
    m.add_function(wrap_pyfunction!(ncx2_cdf, m)?)?;
    m.add_function(wrap_pyfunction!(mdb, m)?)?;
    m.add_function(wrap_pyfunction!(memory_available, m)?)?;
    m.add_function(wrap_pyfunction!(restore::_restore, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::validate_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::scenario_trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::run_variants, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::match_alarms, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::window_alarm, m)?)?;
    m.add("DETECTION_GRACE", navfdi_core::metrics::GRACE)?;
    m.add("CN0_SLOPE_MAX", navfdi_core::gnss::spp::CN0_SLOPE_MAX)?;
    m.add("IMU_GAP_FACTOR", navfdi_core::arch::inertial::GAP_FACTOR)?;
    {
        use navfdi_core::logs::imu_csv as limits;
        m.add("IMU_MAX_RATE", limits::MAX_RATE)?;
        m.add("IMU_MAX_SPECIFIC_FORCE", limits::MAX_SPECIFIC_FORCE)?;
        m.add("IMU_MAX_MEDIAN_RATE", limits::MAX_MEDIAN_RATE)?;
        m.add("IMU_MEDIAN_SPECIFIC_FORCE", limits::MEDIAN_SPECIFIC_FORCE)?;
    }
    m.add_class::<federated::PyFederatedFilter>()?;
    m.add_class::<federated::PyFederatedStep>()?;
    m.add_class::<montecarlo::PyPreparedScenario>()?;
    m.add_class::<gnss::PySnapshotFde>()?;
    m.add_function(wrap_pyfunction!(gnss::snapshot_fde, m)?)?;
    m.add_function(wrap_pyfunction!(gnss::py_ls_test, m)?)?;
    m.add_function(wrap_pyfunction!(integrity::araim_epoch, m)?)?;
    m.add_function(wrap_pyfunction!(integrity::araim_los, m)?)?;
    m.add_function(wrap_pyfunction!(integrity::araim_variances, m)?)?;
    m.add_function(wrap_pyfunction!(integrity::snapshot_pl, m)?)?;
    m.add_function(wrap_pyfunction!(rinex::read_rinex_obs, m)?)?;
    m.add_function(wrap_pyfunction!(logged::read_imu_csv, m)?)?;
    m.add_function(wrap_pyfunction!(logged::imu_clipped, m)?)?;
    m.add_function(wrap_pyfunction!(logged::pos_rows, m)?)?;
    m.add_function(wrap_pyfunction!(logged::read_ubx, m)?)?;
    m.add_function(wrap_pyfunction!(logged::simulate_logs, m)?)?;
    m.add_function(wrap_pyfunction!(rinex::read_rinex_nav, m)?)?;
    m.add_class::<rinex::PyGnssRun>()?;
    m.add_function(wrap_pyfunction!(montecarlo::check_campaign_memory, m)?)?;
    m.add_class::<logged::PyLoggedSource>()?;
    m.add_class::<prefilter::PyPrefilter>()?;
    m.add_class::<prefilter::PyPrefilterStep>()?;
    m.add_function(wrap_pyfunction!(prefilter::py_dll_variance, m)?)?;
    m.add_function(wrap_pyfunction!(prefilter::py_fll_variance, m)?)?;
    Ok(())
}
